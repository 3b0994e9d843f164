#pragma once
/// Presentation helpers shared by every output (docs/architecture.md "Layers"): number formats,
/// lists, unit conversions and the content hash. One definition each, used by files, tables,
/// messages and pictures alike.

#include <cstdint>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

namespace fivebar::format {

/// Radians per degree and degrees per radian (files and the command line speak degrees).
inline constexpr double kRadPerDeg = std::numbers::pi / 180.0;
inline constexpr double kDegPerRad = 180.0 / std::numbers::pi;
/// Radians of an angle given in degrees (any finite value); beyond one turn it is reduced exactly
/// to [-180, 180] deg first (std::remainder is exact): 1e16 deg is the pose of its true remainder (-80 deg), not of
/// a multiple of pi rounded to a double. docs/reliability.md "Numeric ranges".
double rad_from_deg(double deg);

/// Shortest text that reads back as the same double ("0.1", "-3", "1e+13"); "nan", "inf", "-inf".
std::string shortest(double value);
/// Fixed point with `digits` decimals; a result that reads as zero never carries a sign
/// ("-0.000" is written "0.000").
std::string fixed(double value, int digits);
/// `significant` significant digits, the shorter of fixed and scientific (printf's %g): "12.5",
/// "1e-05"; never "-0".
std::string general(double value, int significant = 6);
/// Scientific with `digits` decimals (printf's %e): "1.2e-15"; never "-0.0e+00".
std::string sci(double value, int digits = 1);
/// The items separated by `separator`.
std::string join(const std::vector<std::string>& items, std::string_view separator = ", ");

/// Text for XML and HTML: & < > " ' as entities (&#39; for the quote, valid in both).
std::string xml_escape(std::string_view text);

/// FNV-1a offset basis (64 bit): the hash of no bytes.
inline constexpr std::uint64_t kFnvOffset = 14695981039346656037ull;
/// FNV-1a, 64 bit, of `bytes`, continuing from `hash`: a fingerprint of inputs (designs, render
/// inputs) to notice a change; not a security hash.
std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t hash = kFnvOffset);

}  // namespace fivebar::format
