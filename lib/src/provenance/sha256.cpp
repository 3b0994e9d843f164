// SHA-256 after FIPS 180-4 (fivebar/sha256.hpp).
#include "fivebar/sha256.hpp"

#include <array>
#include <cstdint>
#include <fstream>

#include "fivebar/error.hpp"

namespace fivebar {

namespace {

constexpr std::array<std::uint32_t, 64> kK{
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5, 0xd807aa98, 0x12835b01,
    0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc,
    0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147,
    0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
    0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116, 0x1e376c08,
    0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3, 0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208,
    0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};

constexpr std::uint32_t rotr(std::uint32_t x, int n) { return (x >> n) | (x << (32 - n)); }

void block(std::array<std::uint32_t, 8>& h, const unsigned char* p) {
  std::array<std::uint32_t, 64> w{};
  for (int i = 0; i < 16; ++i) {
    w[static_cast<std::size_t>(i)] = (std::uint32_t{p[4 * i]} << 24) | (std::uint32_t{p[4 * i + 1]} << 16) |
                                     (std::uint32_t{p[4 * i + 2]} << 8) | std::uint32_t{p[4 * i + 3]};
  }
  for (std::size_t i = 16; i < 64; ++i) {
    const std::uint32_t s0 = rotr(w[i - 15], 7) ^ rotr(w[i - 15], 18) ^ (w[i - 15] >> 3);
    const std::uint32_t s1 = rotr(w[i - 2], 17) ^ rotr(w[i - 2], 19) ^ (w[i - 2] >> 10);
    w[i] = w[i - 16] + s0 + w[i - 7] + s1;
  }
  auto [a, b, c, d, e, f, g, hh] = h;
  for (std::size_t i = 0; i < 64; ++i) {
    const std::uint32_t t1 = hh + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) + kK[i] + w[i];
    const std::uint32_t t2 = (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
    hh = g;
    g = f;
    f = e;
    e = d + t1;
    d = c;
    c = b;
    b = a;
    a = t1 + t2;
  }
  h[0] += a, h[1] += b, h[2] += c, h[3] += d, h[4] += e, h[5] += f, h[6] += g, h[7] += hh;
}

}  // namespace

namespace {

constexpr std::array<std::uint32_t, 8> kH0{0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                                           0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};

/// The padding and length block after the last whole block, then the digest in hex.
std::string finish(std::array<std::uint32_t, 8>& h, const unsigned char* rest_bytes, std::size_t rest, std::uint64_t n) {
  std::array<unsigned char, 128> tail{};
  for (std::size_t k = 0; k < rest; ++k) tail[k] = rest_bytes[k];
  tail[rest] = 0x80;
  const std::size_t len = rest < 56 ? 64 : 128;
  const std::uint64_t bits = n * 8;
  for (int k = 0; k < 8; ++k) tail[len - 1 - static_cast<std::size_t>(k)] = static_cast<unsigned char>(bits >> (8 * k));
  block(h, tail.data());
  if (len == 128) block(h, tail.data() + 64);
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (std::uint32_t v : h) {
    for (int k = 7; k >= 0; --k) out += hex[(v >> (4 * k)) & 0xf];
  }
  return out;
}

}  // namespace

std::string sha256_hex(std::string_view data) {
  std::array<std::uint32_t, 8> h = kH0;
  const auto* bytes = reinterpret_cast<const unsigned char*>(data.data());
  const std::size_t n = data.size();
  std::size_t i = 0;
  for (; i + 64 <= n; i += 64) block(h, bytes + i);
  return finish(h, bytes + i, n - i, n);
}

std::string sha256_file(const std::filesystem::path& path, std::uintmax_t max_bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.generic_string() + ": cannot read the file to hash");
  // Streamed in chunks: the memory is one chunk whatever the file, and a file past max_bytes (or
  // /dev/zero) is refused once it passes the bound.
  std::array<std::uint32_t, 8> h = kH0;
  std::array<char, 65536> chunk{};
  std::uint64_t n = 0;
  std::size_t held = 0;  // bytes of an unfinished block at the start of chunk
  while (in.read(chunk.data() + held, static_cast<std::streamsize>(chunk.size() - held)) || in.gcount() > 0) {
    const auto got = static_cast<std::size_t>(in.gcount());
    n += got;
    if (n > max_bytes) {
      throw InputError(path.generic_string() + ": larger than " + std::to_string(max_bytes) +
                       " bytes: not hashed (docs/reliability.md \"Resource bounds\")");
    }
    const std::size_t have = held + got;
    const auto* bytes = reinterpret_cast<const unsigned char*>(chunk.data());
    std::size_t i = 0;
    for (; i + 64 <= have; i += 64) block(h, bytes + i);
    held = have - i;
    for (std::size_t k = 0; k < held; ++k) chunk[k] = chunk[i + k];
  }
  if (in.bad()) throw InputError(path.generic_string() + ": read error while hashing the file");
  return finish(h, reinterpret_cast<const unsigned char*>(chunk.data()), held, n);
}

}  // namespace fivebar
