#pragma once
/// Bench measurements for kinematic calibration (docs/calibrate.md): one row per pose, the two
/// potentiometer readings of a mechanism and the tactor point measured by an instrument.
///
/// CSV with a header row: `station,mechanism,volts1,volts2,x_mm,y_mm[,sigma_mm]`, or
/// `counts1,counts2` instead of the volts (converted through `controller.adc`: V = low + counts
/// (high - low) / 2^bits, the one ADC model of fivebar/export/export.hpp). Any column order; an unknown,
/// repeated or missing column, a cell that is not a finite number, a station or mechanism the
/// design lacks, a value out of range (docs/bench-files.md), a row that copies an earlier one:
/// InputError naming the file, the line and the column.

#include <filesystem>
#include <string>
#include <vector>

#include "fivebar/csv_reader.hpp"
#include "fivebar/design.hpp"

namespace fivebar::calibrate {

/// Bounds of a measurement or hard-stop file (docs/bench-files.md): lines of 4096 bytes, 64 MiB,
/// 1,000,000 rows (a bench session is hundreds of poses; the fit is linear in rows).
inline constexpr csv::Limits kMeasurementLimits{4096, 64ull << 20, 1'000'000};
/// |x_mm|, |y_mm| at most this many times the mechanism's largest length (Mechanism::length_scale).
inline constexpr double kMaxPointScale = 1000.0;

/// One measured pose.
struct Measurement {
  std::string station;
  std::string mechanism;  ///< "lower" or "upper"
  double volts1 = 0.0;    ///< potentiometer reading of theta1, V
  double volts2 = 0.0;
  Vec2 point{0.0, 0.0};   ///< tactor measured by the instrument, mm (instrument frame)
  double sigma_mm = 0.0;  ///< measurement standard deviation per axis, mm; 0: not given
  int line = 0;           ///< line of the file (1-based; the header is line 1)
};

/// Reads measurements from CSV text; `origin` names the source in messages. `design` gives the
/// stations and mechanisms that may appear and `controller.adc` for counts.
std::vector<Measurement> parse_measurements(const std::string& text, const std::string& origin, const Design& design);
/// Reads a measurement file (as parse_measurements()); InputError when it cannot be read.
std::vector<Measurement> read_measurements(const std::filesystem::path& path, const Design& design);

}  // namespace fivebar::calibrate
