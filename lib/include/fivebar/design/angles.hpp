#pragma once
/// Joint-angle arithmetic shared by the design, the device configuration and the export: one home
/// for reducing an angle to a turn. (The runtime, a C++17 package that builds alone, does its own
/// reduction in lib/src/runtime/controller.cpp.)

#include <cmath>
#include <numbers>

namespace fivebar::angles {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// `a` reduced to [0, 2 pi).
inline double wrap_two_pi(double a) {
  double r = std::fmod(a, kTwoPi);
  if (r < 0.0) r += kTwoPi;
  if (r >= kTwoPi) r = 0.0;  // a tiny negative remainder rounds up to 2 pi
  return r;
}

/// `a` reduced to (-pi, pi].
inline double wrap_pi(double a) {
  double r = std::remainder(a, kTwoPi);
  if (r <= -kPi) r += kTwoPi;
  return r;
}

}  // namespace fivebar::angles
