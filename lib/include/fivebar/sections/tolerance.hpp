#pragma once
/// The `tolerance:` section of a design file: manufacturing and sensing errors of the printed
/// device (issue 17). One module of the design (see docs/architecture.md "Design sections"): the
/// struct and its validate() here, its loader and writer hooks in lib/src/sections/tolerance.cpp.
/// A Design holds it as `design.get<ToleranceSettings>()`; fivebar/tolerance.hpp turns it into
/// per-parameter standard deviations.

#include <cstdint>
#include <string_view>

namespace fivebar {

/// Manufacturing tolerances (`tolerance:`), each a standard deviation of a normal error. The
/// defaults are assumptions to replace with measurements of your printer, assembly and sensors
/// (no datasheet gives them).
struct ToleranceSettings {
  static constexpr std::string_view kKey = "tolerance";
  double link_sigma_mm = 0.05;   ///< pin-centre distance of a printed link, mm (assumption)
  double pin_sigma_mm = 0.025;   ///< each pin hole's position, per axis, mm (assumption)
  double base_sigma_mm = 0.1;    ///< each base joint's placement, per axis, mm (assumption: by hand)
  double angle_sigma_deg = 0.5;  ///< joint angle offset after calibration, deg (assumption)
  int adc_bits = 16;             ///< counts resolve one full joint turn into 2^bits (paper: 16-bit DAQ)
  std::uint64_t samples = 10000; ///< Monte Carlo devices
  std::uint64_t seed = 1;        ///< Monte Carlo seed
  void validate() const;
};

}  // namespace fivebar
