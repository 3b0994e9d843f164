#include "fivebar/share.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <system_error>

namespace fivebar {

namespace fs = std::filesystem;

namespace {
// Any object of this library: dladdr() names the binary it was loaded from.
const char kAnchor = 0;
}  // namespace

std::vector<fs::path> binary_dirs() {
  std::vector<fs::path> dirs;
  const auto add = [&dirs](const fs::path& binary) {
    std::error_code ec;
    const fs::path canonical = fs::canonical(binary, ec);
    if (ec) return;
    const fs::path dir = canonical.parent_path();
    if (std::find(dirs.begin(), dirs.end(), dir) == dirs.end()) dirs.push_back(dir);
  };
  Dl_info info{};
  if (dladdr(&kAnchor, &info) != 0 && info.dli_fname != nullptr && *info.dli_fname != '\0') add(info.dli_fname);
  add("/proc/self/exe");
  return dirs;
}

std::optional<fs::path> find_share_path(std::string_view relative, const std::vector<fs::path>& dirs, int levels) {
  for (const fs::path& start : dirs) {
    fs::path dir = start;
    for (int up = 0; up <= levels && !dir.empty(); ++up) {
      const fs::path candidate = dir / "share" / "fivebar" / relative;
      std::error_code ec;
      if (fs::exists(candidate, ec)) return candidate;
      if (dir == dir.root_path()) break;
      dir = dir.parent_path();
    }
  }
  return std::nullopt;
}

}  // namespace fivebar
