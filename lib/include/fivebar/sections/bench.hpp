#pragma once
/// The `bench:` section of a design file: the bench measurements `fivebar run` fits the design to
/// (docs/calibrate.md, docs/identify.md), file names relative to the design file:
///   calibration     measurements for `calibrate` (station,mechanism,volts1,volts2,x_mm,y_mm[,sigma_mm])
///   identification  a log for `identify --rig motor` (time_s, a drive, a reading per joint)
///   replay_logs     the device's logs for `replay LOG` (fivebar/replay.hpp), each replayed through
///                   the runtime of the design's export; replay_tolerance the largest |duty
///                   difference| accepted (1e-9 by default, as `fivebar replay`'s --tolerance)
/// With a file named, the `calibrate` or `identify` product writes its report and the patched
/// design (values and provenance: entries) into the output folder; the `bench_replay` product
/// reports per log whether the device runs the exported configuration. One module of the design
/// (docs/architecture.md "Design sections"): loader and writer in lib/src/sections/bench.cpp.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"

namespace fivebar {

/// Whether the files a design names (`bench:`) may lie outside the design file's folder
/// (docs/bench-files.md "Where bench files may be"). False unless the caller allows it: the
/// command line's `--allow-outside-paths`. Process-wide; set before designs are loaded.
void allow_bench_paths_outside(bool allow);
bool bench_paths_outside_allowed();

struct BenchSettings {
  static constexpr std::string_view kKey = "bench";
  std::string calibration;     ///< as written (relative to the design file); empty: none
  std::string identification;  ///< as written; empty: none
  std::vector<std::string> replay_logs;  ///< as written; empty: none
  double replay_tolerance = 1e-9;        ///< duty, [0, 2]
  /// `file` resolved against the design file's folder (as given when absolute or without a source).
  static std::filesystem::path resolve(const Design& design, const std::string& file);
  void validate() const;
  /// ValidationError on `bench.<key>` when `file`, resolved and its links followed, lies outside
  /// the design file's folder (docs/bench-files.md); nothing when it is missing or when
  /// bench_paths_outside_allowed(). Called when the
  /// design is loaded and again by each product before it reads the file.
  static void check_inside(const Design& design, const std::string& key, const std::string& file);
  /// check_inside() for a product about to read the file: InputError "DESIGN: bench.<key> = ...".
  static void require_inside(const Design& design, const std::string& key, const std::string& file);
};

}  // namespace fivebar
