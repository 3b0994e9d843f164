// The presentation helpers (fivebar/format.hpp), against independent references: strtod for the
// round trip, printf for fixed point, and the test vectors of the FNV-1a specification.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>

#include "fivebar/format.hpp"

namespace fivebar {
namespace {

TEST(Format, ShortestReadsBackAsTheSameDoubleAndIsShortest) {
  std::mt19937_64 rng(std::getenv("FIVEBAR_SEED") ? std::strtoull(std::getenv("FIVEBAR_SEED"), nullptr, 10) : 7);
  std::uniform_int_distribution<std::uint64_t> bits;
  for (int i = 0; i < 100000; ++i) {
    double v;
    const std::uint64_t b = bits(rng);
    std::memcpy(&v, &b, sizeof v);
    if (!std::isfinite(v)) continue;
    const std::string s = format::shortest(v);
    SCOPED_TRACE(s);
    EXPECT_EQ(std::strtod(s.c_str(), nullptr), v);
  }
  EXPECT_EQ(format::shortest(0.1), "0.1");
  EXPECT_EQ(format::shortest(-3.0), "-3");
  EXPECT_EQ(format::shortest(1e13), "1e+13");
  EXPECT_EQ(format::shortest(std::nan("")), "nan");
  EXPECT_EQ(format::shortest(-std::numeric_limits<double>::infinity()), "-inf");
}

TEST(Format, FixedNeverWritesANegativeZero) {
  EXPECT_EQ(format::fixed(-0.0001, 3), "0.000");
  EXPECT_EQ(format::fixed(-0.0, 2), "0.00");
  EXPECT_EQ(format::fixed(-0.0006, 3), "-0.001");
  EXPECT_EQ(format::fixed(12.34567, 2), "12.35");
}

TEST(Format, AnglesBeyondOneTurnAreReducedExactlyBeforeTheConversion) {
  // Up to one turn: the plain product.
  for (const double d : {0.0, 100.0, -179.5, 270.0, -360.0}) {
    EXPECT_EQ(format::rad_from_deg(d), d * format::kRadPerDeg) << d;
  }
  // Beyond: the remainder by integer arithmetic (10^16 = 280 = -80 mod 360; 10^16 + 360 too;
  // 2^60 = 136 mod 360), exact before the one rounding of the conversion.
  EXPECT_EQ(format::rad_from_deg(1e16), -80.0 * format::kRadPerDeg);
  EXPECT_EQ(format::rad_from_deg(10000000000000360.0), -80.0 * format::kRadPerDeg);
  EXPECT_EQ(format::rad_from_deg(-1e16), 80.0 * format::kRadPerDeg);
  EXPECT_EQ(format::rad_from_deg(std::ldexp(1.0, 60)), 136.0 * format::kRadPerDeg);
  EXPECT_EQ(format::rad_from_deg(720.5), 0.5 * format::kRadPerDeg);
}

TEST(Format, JoinSeparatesItems) {
  EXPECT_EQ(format::join({}), "");
  EXPECT_EQ(format::join({"a"}), "a");
  EXPECT_EQ(format::join({"a", "b", "c"}), "a, b, c");
  EXPECT_EQ(format::join({"a", "b"}, " "), "a b");
}

TEST(Format, Fnv1a64MatchesTheSpecificationsVectors) {
  // FNV-1a 64-bit test vectors (Fowler, Noll, Vo: "FNV hash" reference test suite).
  EXPECT_EQ(format::fnv1a64(""), 0xcbf29ce484222325ULL);
  EXPECT_EQ(format::fnv1a64("a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(format::fnv1a64("foobar"), 0x85944171f73967e8ULL);
  // Continuing from a hash is hashing the concatenation.
  EXPECT_EQ(format::fnv1a64("bar", format::fnv1a64("foo")), format::fnv1a64("foobar"));
}

TEST(Format, DegreeConversionsAreInverse) {
  EXPECT_DOUBLE_EQ(180.0 * format::kRadPerDeg, M_PI);
  EXPECT_DOUBLE_EQ(M_PI * format::kDegPerRad, 180.0);
}

}  // namespace
}  // namespace fivebar
