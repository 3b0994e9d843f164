#pragma once
/// SHA-256 (FIPS 180-4) of bytes and of a file, as 64 lowercase hex digits: the hash a provenance
/// entry records of its source file (fivebar/provenance.hpp).

#include <filesystem>
#include <string>
#include <string_view>

namespace fivebar {

/// SHA-256 of `data`, lowercase hex.
std::string sha256_hex(std::string_view data);
/// SHA-256 of the file's bytes; InputError when it cannot be read.
std::string sha256_file(const std::filesystem::path& path);

}  // namespace fivebar
