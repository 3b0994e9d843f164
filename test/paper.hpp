#pragma once
// The paper's device (IROS 2022, Table 1), typed here from the paper and independent of the design
// loader, and the seed of the random tests. Shared by the unit tests and the benchmarks.

#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "fivebar/kinematics.hpp"

namespace fivebar::testing {

/// Seed of a file's random tests: FIVEBAR_TEST_SEED overrides `fallback` (never the clock), so a
/// failure found with one seed can be replayed.
inline std::uint64_t test_seed(std::uint64_t fallback = 20221023) {
  if (const char* s = std::getenv("FIVEBAR_TEST_SEED")) return std::strtoull(s, nullptr, 10);
  return fallback;
}

/// One mechanism of Table 1: `station` "index" (distal links 15 mm, upper bases at y = 31 mm) or
/// "thumb" (17.5 mm, y = 35 mm), `which` "lower" or "upper". Bases 12.5 mm apart, proximal links
/// 9 mm, both elbows outward: working mode -+ below and +- above, the tactor on the side away from
/// the base line (assembly + below, - above).
inline Mechanism paper_mechanism(std::string_view station, std::string_view which) {
  const bool lower = which == "lower";
  const bool index = station == "index";
  const double distal = index ? 15.0 : 17.5;
  const double y = lower ? 0.0 : (index ? 31.0 : 35.0);
  Mechanism m;
  m.name = std::string(which);
  m.O1 = {0.0, y};
  m.O2 = {12.5, y};
  m.L = {9.0, 9.0, distal, distal};
  m.working_mode = lower ? WorkingMode{-1, +1} : WorkingMode{+1, -1};
  m.assembly_mode = lower ? AssemblyMode::Plus : AssemblyMode::Minus;
  return m;
}

}  // namespace fivebar::testing
