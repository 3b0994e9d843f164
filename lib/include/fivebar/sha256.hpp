#pragma once
/// SHA-256 (FIPS 180-4) of bytes and of a file, as 64 lowercase hex digits: the hash a provenance
/// entry records of its source file (fivebar/provenance.hpp).

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace fivebar {

/// SHA-256 of `data`, lowercase hex.
std::string sha256_hex(std::string_view data);
/// Largest file sha256_file() hashes by default: the largest bench file (a device log, 1 GiB,
/// docs/bench-files.md).
inline constexpr std::uintmax_t kMaxHashedFileBytes = std::uintmax_t{1} << 30;
/// SHA-256 of the file's bytes, streamed (one 64 KiB chunk in memory); InputError when it cannot
/// be read or holds more than `max_bytes` (checked while reading: /dev/zero is refused).
std::string sha256_file(const std::filesystem::path& path, std::uintmax_t max_bytes = kMaxHashedFileBytes);

}  // namespace fivebar
