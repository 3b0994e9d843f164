#pragma once
/// The quality gate between a fit and the design (docs/calibrate.md "The quality gate"): one rule
/// for every fit that writes values into a design as measured (`fivebar calibrate`, its hard stops,
/// `fivebar identify`). A fitted value is written as measured only when
///   1. the solver converged (Ceres' termination type CONVERGENCE, or a closed form);
///   2. every residual test of the fit passed: the residuals are consistent with the noise
///      (chi_square_test() when the measurement sigma is known, largest_residual_test() when it is
///      estimated from the residuals; identification adds its own, e.g. a whiteness test, as a
///      ResidualTest with its statement and p-value);
///   3. the parameter is identifiable from the data;
///   4. its posterior sigma is at most max_sigma_to_prior (kMaxSigmaToPrior) times its prior
///      sigma (the a-priori uncertainty the fit was meant to reduce), and, where a fit states one,
///      at most max_relative_sigma of its own value (a value without a stated prior sigma, such
///      as a motor datasheet value or an assumption: the data must at least fix its size).
/// Otherwise the fit is refused as a whole: nothing is patched and the command exits 1 with the
/// reasons per parameter (refusal_lines()). A passed gate's figures go into each provenance entry
/// it writes (GateRecord, fivebar/sections/provenance.hpp), and the export's
/// `controller.require_measured` trusts only entries whose gate passed (fivebar/provenance.hpp
/// untrusted_values()).

#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/json.hpp"
#include "fivebar/sections/provenance.hpp"

namespace fivebar::gate {

/// Significance level of the residual tests: a fit is refused when its residuals are this unlikely
/// (or less) under the stated noise model.
inline constexpr double kAlpha = 1e-3;
/// A value is measured only when its posterior sigma is at most this many times its prior sigma:
/// a "measurement" that knows a value no better than before the fit has not measured it.
inline constexpr double kMaxSigmaToPrior = 1.0;

/// What the solver said.
struct SolverVerdict {
  bool converged = false;    ///< Ceres CONVERGENCE (Solver::Summary::termination_type), or a closed form
  std::string termination;   ///< "CONVERGENCE", "NO_CONVERGENCE", "FAILURE", "closed form", ...
  int iterations = 0;
};

/// One test of the residuals against the noise model.
struct ResidualTest {
  std::string name;       ///< "chi-square", "largest residual", "whiteness", "validation fit"
  std::string statement;  ///< the test with its figures, e.g. "sum (r/sigma)^2 = 130.2 on 108 dof: p = 0.071 >= 0.001"
  double statistic = std::numeric_limits<double>::quiet_NaN();
  double p_value = std::numeric_limits<double>::quiet_NaN();  ///< NaN for a test without one (a floor)
  bool applicable = true;  ///< false: could not be performed (the statement says why); never fails
  bool passed = true;
};

/// One fitted value that would be written into the design.
struct ParameterCheck {
  std::string key;     ///< design key path it patches
  std::string label;   ///< short name for messages ("lower.L3")
  std::string unit;    ///< file unit of value and sigmas
  double value = 0.0;
  double sigma = 0.0;  ///< posterior standard deviation
  /// A-priori standard deviation (the uncertainty before the fit), in `unit`; NaN or <= 0: no bound
  /// (the ratio is not checked and the record says so).
  double prior_sigma = std::numeric_limits<double>::quiet_NaN();
  bool identifiable = true;
  std::string identifiability;  ///< why not identifiable (when it is not)
  /// Largest sigma / |value| accepted (0.5: the value is at least two sigmas from zero); NaN: no
  /// relative bound.
  double max_relative_sigma = std::numeric_limits<double>::quiet_NaN();
};

struct GateInput {
  std::string fit;  ///< "fivebar calibrate", "fivebar identify", for messages
  SolverVerdict solver;
  std::vector<ResidualTest> tests;
  std::vector<ParameterCheck> parameters;
  double max_sigma_to_prior = kMaxSigmaToPrior;
};

struct ParameterVerdict {
  std::string key, label, unit;
  double value = 0.0, sigma = 0.0, prior_sigma = 0.0;
  double sigma_ratio = std::numeric_limits<double>::quiet_NaN();  ///< sigma / prior_sigma (NaN: no prior)
  bool passed = false;
  std::vector<std::string> reasons;  ///< why not (empty when passed)
};

struct GateResult {
  std::string fit;
  bool passed = false;
  SolverVerdict solver;
  std::vector<ResidualTest> tests;
  std::vector<std::string> reasons;  ///< fit-wide: the solver, the failed tests (every parameter inherits them)
  std::vector<ParameterVerdict> parameters;
  double max_sigma_to_prior = kMaxSigmaToPrior;

  /// One line per refused parameter: "lower.L3 (stations.index.mechanisms.lower.links[2]) = 12.38 +- 90.1 mm:
  /// the solver did not converge (NO_CONVERGENCE); sigma 90.1 mm is 901x its prior 0.1 mm (bound 1x)".
  std::vector<std::string> refusal_lines() const;
  /// The record of the gate a provenance entry keeps for `key` (one of the parameters): passed when
  /// the fit-wide conditions and this value's own held (a fit is written only when all passed).
  GateRecord record(std::string_view key) const;
  /// record() of each key, in order (fivebar/provenance.hpp with_measured_values()'s `gates`).
  std::vector<GateRecord> records(const std::vector<std::string>& keys) const;
};

/// Applies the four conditions above.
GateResult evaluate(const GateInput& input);

/// Chi-square test of weighted residuals with a known measurement sigma: sum_squares = sum (r_i /
/// sigma_i)^2 over `dof` degrees of freedom (rows minus fitted parameters) is chi-square(dof) under
/// the noise model; refused when its upper tail P(X >= sum_squares) < alpha (residuals too large for
/// the noise: a blunder, a model error or an understated sigma). Residuals smaller than the noise
/// are stated but not refused (the sigmas are then conservative).
ResidualTest chi_square_test(double sum_squares, int dof, double alpha = kAlpha);
/// When the sigma is estimated from the residuals themselves (the chi-square statistic is then
/// dof by construction): the largest standardized residual |r_i| / s of n against the Bonferroni
/// bound of normal noise, refused when n P(|Z| >= max) < alpha (a residual no Gaussian noise of the
/// fit's own scale explains: a blunder or a model error).
ResidualTest largest_residual_test(const std::vector<double>& standardized, double alpha = kAlpha);
/// Upper tail of the chi-square distribution, P(X >= x) for X ~ chi-square(dof) (the regularised
/// upper incomplete gamma Q(dof/2, x/2); Numerical Recipes' series and continued fraction).
double chi_square_sf(double x, double dof);

/// The gate as text, one line per test and per refused value ("quality gate: passed (solver ...)",
/// "  not measured: ..."); empty for a fit without values that passed.
std::string to_text(const GateResult& gate);

/// The gate as JSON: {passed, fit, solver: {converged, termination, iterations}, tests: [{name,
/// statement, statistic, p_value, applicable, passed}], reasons, parameters: [{parameter, value,
/// sigma, prior_sigma, sigma_ratio, passed, reasons}], max_sigma_to_prior}.
Json to_json(const GateResult& gate);

}  // namespace fivebar::gate
