#pragma once
/// The `tolerance:` section of a design file: manufacturing and sensing errors of the printed
/// device. One module of the design (see docs/architecture.md "Design sections"): the
/// struct and its validate() here, its loader and writer hooks in lib/src/sections/tolerance.cpp.
/// A Design holds it as `design.get<ToleranceSettings>()`; fivebar/tolerance.hpp turns it into
/// per-parameter standard deviations.

#include <cstdint>
#include <optional>
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
  /// Counts per full joint turn are 2^bits (e.g. an encoder). Unset: the resolution comes from
  /// the `controller:` section's ADC range and bits and the potentiometer's scale of each joint,
  /// or 2^16 per turn without one (the paper's 16-bit DAQ).
  std::optional<int> adc_bits;
  /// Radial play of each pin joint (elbows A1, A2 and the tactor joint P): a pin of diameter d in
  /// a hole of d + 2 c lets the joint centre move anywhere within c. Unset: print.pin_clearance.
  std::optional<double> pin_play_mm;
  double shaft_play_mm = 0.02;   ///< radial play of a motor shaft in its hub, mm (assumption)
  double backlash_deg = 1.0;     ///< gear backlash at the output shaft, whole band, deg (assumption)
  /// Independent linearity of the potentiometer, +- % of its electrical travel: a sensing error
  /// left after a two-point calibration, taken as uniform over the band (assumption: a
  /// conductive-plastic part's datasheet gives 0.25 ... 2 %; replace with yours).
  double linearity_percent = 0.25;
  double pot_travel_deg = 300.0; ///< electrical travel of the potentiometer, deg (assumption)
  /// Robust coverage: the fraction of printed devices that must cover the target (0.997: 3 sigma).
  double robust_fraction = 0.997;
  /// `fivebar export` refuses a design whose target some mechanism does not cover robustly.
  bool export_gate = false;
  std::uint64_t samples = 10000; ///< Monte Carlo devices
  std::uint64_t seed = 1;        ///< Monte Carlo seed
  void validate() const;
};

}  // namespace fivebar
