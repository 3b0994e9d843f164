#pragma once
/// The installed data of fivebar (docs/install.md "Where the data is found"): the OpenSCAD library
/// scad/, the JSON Schemas and the docs live in `<prefix>/share/fivebar/`, found at run time
/// relative to the binary that holds the library, so that an install prefix can be moved and no
/// checkout path is compiled in.

#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

namespace fivebar {

/// The folders of the binaries the running code came from: the shared object or executable holding
/// this library (dladdr), then the running executable (/proc/self/exe); canonical, no duplicates.
std::vector<std::filesystem::path> binary_dirs();

/// `share/fivebar/<relative>` in the nearest of `dirs` and their ancestors (up to `levels` above
/// each) where it exists: `<prefix>/bin/fivebar` finds `<prefix>/share/fivebar/`, the build tree's
/// `build/fivebar` finds `build/share/fivebar/`, a Python module in
/// `<prefix>/lib/python3.X/dist-packages/fivebar/` finds `<prefix>/share/fivebar/`. std::nullopt
/// when no candidate exists.
std::optional<std::filesystem::path> find_share_path(std::string_view relative,
                                                     const std::vector<std::filesystem::path>& dirs,
                                                     int levels = 5);

}  // namespace fivebar
