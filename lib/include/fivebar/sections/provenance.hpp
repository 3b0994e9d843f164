#pragma once
/// The `provenance:` section of a design file (docs/calibrate.md
/// "Measured or assumed"): where a value came from. A map from a key path of the design
/// (`stations.index.mechanisms.lower.links[2]`, `controller.stations.index.lower.theta1.potentiometer.volts_at_zero`,
/// as design_number() takes them; a path that leads to a map or list covers every number below it)
/// to the measurement that set it. A value without an entry is an assumption. One module of the
/// design (docs/architecture.md "Design sections"); helpers in fivebar/provenance.hpp.

#include <map>
#include <optional>
#include <string>
#include <string_view>

namespace fivebar {

/// The quality gate a fitted value passed (fivebar/provenance/gate.hpp, docs/calibrate.md "The
/// quality gate"): what the fit that wrote the entry showed. Entries written by hand have none.
struct GateRecord {
  bool passed = false;     ///< every condition held (an entry whose gate did not pass is not measured)
  std::string solver;      ///< the solver's termination ("CONVERGENCE", "closed form")
  std::string tests;       ///< the residual tests' statements, "; "-separated
  std::optional<double> p_value;      ///< the smallest p-value of the residual tests
  std::optional<double> sigma_ratio;  ///< posterior sigma / prior sigma (absent: no prior)
  std::optional<double> prior_sigma;  ///< the prior sigma it was compared with, the key's file unit
  void validate() const;
};

/// One measured value's origin.
struct ProvenanceEntry {
  std::string source;          ///< the file the value was fitted from (as given on the command line)
  std::string sha256;          ///< SHA-256 of that file, 64 lowercase hex digits
  std::string date;            ///< YYYY-MM-DD (UTC)
  std::string method;          ///< "fivebar calibrate (Ceres, Levenberg-Marquardt)", "datasheet", ...
  std::optional<double> sigma; ///< standard deviation, in the key's file unit
  /// Correlation coefficients of this value's error with other measured values (their key paths,
  /// each with its own entry and sigma): the posterior covariance of a fit is sigma_a sigma_b rho_ab
  /// (fivebar/provenance.hpp provenance_covariance()). A pair is written once, under the key that
  /// sorts first; either side is read.
  std::map<std::string, double, std::less<>> correlation;
  std::optional<GateRecord> gate;  ///< the fit's quality gate (absent: written by hand)
  /// True when the sha256 is all zeros: a placeholder, not the hash of a file (not measured).
  bool placeholder_hash() const;
  void validate() const;
};

struct ProvenanceSettings {
  static constexpr std::string_view kKey = "provenance";
  std::map<std::string, ProvenanceEntry, std::less<>> entries;  ///< key path -> origin
  void validate() const;
};

}  // namespace fivebar
