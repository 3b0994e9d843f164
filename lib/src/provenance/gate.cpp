// The quality gate between a fit and the design (fivebar/provenance/gate.hpp).
#include "fivebar/provenance/gate.hpp"

#include <algorithm>
#include <cmath>

#include "fivebar/format.hpp"

namespace fivebar::gate {

namespace {

/// P(a, x) by its series, for x < a + 1 (Numerical Recipes, 2nd ed., gser).
double gamma_p_series(double a, double x) {
  double sum = 1.0 / a, term = sum, ap = a;
  for (int n = 0; n < 100000; ++n) {
    ap += 1.0;
    term *= x / ap;
    sum += term;
    if (std::abs(term) < std::abs(sum) * 1e-16) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

/// Q(a, x) by its continued fraction (modified Lentz), for x >= a + 1 (Numerical Recipes, gcf).
double gamma_q_fraction(double a, double x) {
  constexpr double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::abs(del - 1.0) < 1e-16) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

std::string ratio_text(double r) { return format::shortest(std::round(r * 100.0) / 100.0) + "x"; }

}  // namespace

double chi_square_sf(double x, double dof) {
  if (!(dof > 0.0) || std::isnan(x)) return std::numeric_limits<double>::quiet_NaN();
  if (x <= 0.0) return 1.0;
  if (std::isinf(x)) return 0.0;
  const double a = dof / 2.0, y = x / 2.0;
  return y < a + 1.0 ? 1.0 - gamma_p_series(a, y) : gamma_q_fraction(a, y);
}

ResidualTest chi_square_test(double sum_squares, int dof, double alpha) {
  ResidualTest t;
  t.name = "chi-square";
  t.statistic = sum_squares;
  if (dof <= 0) {
    t.applicable = false;
    t.statement = "chi-square: not performed (no degrees of freedom: as many unknowns as equations)";
    return t;
  }
  t.p_value = chi_square_sf(sum_squares, dof);
  t.passed = !(t.p_value < alpha);
  const std::string head = "chi-square: sum (r/sigma)^2 = " + format::fixed(sum_squares, 1) + " on " + std::to_string(dof) + " dof, p = ";
  t.statement = head + format::general(t.p_value, 3) + (t.passed ? " >= " : " < ") + format::general(alpha, 3) +
                (t.passed ? "" : ": the residuals are larger than the stated measurement sigma explains");
  if (t.passed && sum_squares < 0.5 * dof) t.statement += " (residuals well below the stated sigma: the sigmas are conservative)";
  return t;
}

ResidualTest largest_residual_test(const std::vector<double>& standardized, double alpha) {
  ResidualTest t;
  t.name = "largest residual";
  if (standardized.empty()) {
    t.applicable = false;
    t.statement = "largest residual: not performed (no residuals)";
    return t;
  }
  double largest = 0.0;
  for (double z : standardized) largest = std::max(largest, std::abs(z));
  const auto n = static_cast<double>(standardized.size());
  t.statistic = largest;
  t.p_value = std::min(1.0, n * std::erfc(largest / std::sqrt(2.0)));  // Bonferroni over n normal residuals
  t.passed = !(t.p_value < alpha);
  t.statement = "largest residual: max |r|/s = " + format::fixed(largest, 2) + " of " + std::to_string(standardized.size()) +
                " (sigma from the residuals), Bonferroni p = " + format::general(t.p_value, 3) + (t.passed ? " >= " : " < ") +
                format::general(alpha, 3) + (t.passed ? "" : ": a residual that the noise of the other residuals does not explain");
  return t;
}

GateResult evaluate(const GateInput& in) {
  GateResult g;
  g.fit = in.fit;
  g.solver = in.solver;
  g.tests = in.tests;
  g.max_sigma_to_prior = in.max_sigma_to_prior;
  if (!in.solver.converged) {
    g.reasons.push_back("the solver did not converge (" + (in.solver.termination.empty() ? std::string("no verdict") : in.solver.termination) +
                        ")");
  }
  for (const ResidualTest& t : in.tests) {
    if (t.applicable && !t.passed) g.reasons.push_back(t.statement);
  }
  g.passed = g.reasons.empty();
  for (const ParameterCheck& p : in.parameters) {
    ParameterVerdict v;
    v.key = p.key;
    v.label = p.label;
    v.unit = p.unit;
    v.value = p.value;
    v.sigma = p.sigma;
    v.prior_sigma = p.prior_sigma;
    if (!p.identifiable) v.reasons.push_back("not identifiable" + (p.identifiability.empty() ? std::string() : ": " + p.identifiability));
    if (!std::isfinite(p.value) || !std::isfinite(p.sigma)) v.reasons.push_back("no finite estimate or sigma");
    if (std::isfinite(p.prior_sigma) && p.prior_sigma > 0.0 && std::isfinite(p.sigma)) {
      v.sigma_ratio = p.sigma / p.prior_sigma;
      if (v.sigma_ratio > in.max_sigma_to_prior) {
        v.reasons.push_back("sigma " + format::general(p.sigma, 3) + " " + p.unit + " is " + ratio_text(v.sigma_ratio) + " its prior " +
                            format::general(p.prior_sigma, 3) + " " + p.unit + " (bound " + ratio_text(in.max_sigma_to_prior) + ")");
      }
    }
    if (std::isfinite(p.max_relative_sigma) && std::isfinite(p.sigma) && std::isfinite(p.value) &&
        p.sigma > p.max_relative_sigma * std::abs(p.value)) {
      v.reasons.push_back("sigma " + format::general(p.sigma, 3) + " " + p.unit + " is " +
                          (p.value == 0.0 ? std::string("larger than the value 0")
                                          : format::fixed(100.0 * p.sigma / std::abs(p.value), 0) + " % of the value") +
                          " (bound " + format::fixed(100.0 * p.max_relative_sigma, 0) + " %): the data do not determine it");
    }
    v.passed = g.reasons.empty() && v.reasons.empty();
    g.passed = g.passed && v.passed;
    g.parameters.push_back(std::move(v));
  }
  return g;
}

std::vector<std::string> GateResult::refusal_lines() const {
  std::vector<std::string> out;
  for (const ParameterVerdict& v : parameters) {
    if (v.passed) continue;
    std::vector<std::string> why = reasons;
    why.insert(why.end(), v.reasons.begin(), v.reasons.end());
    out.push_back(v.label + " (" + v.key + ") = " + format::general(v.value, 6) + " +- " + format::general(v.sigma, 3) + " " + v.unit + ": " +
                  format::join(why, "; "));
  }
  if (out.empty() && !passed) out.push_back(fit + ": " + format::join(reasons, "; "));
  return out;
}

GateRecord GateResult::record(std::string_view key) const {
  GateRecord r;
  r.solver = solver.termination.empty() ? std::string(solver.converged ? "converged" : "no verdict") : solver.termination;
  std::vector<std::string> statements;
  for (const ResidualTest& t : tests) {
    statements.push_back(t.statement);
    if (t.applicable && std::isfinite(t.p_value)) r.p_value = r.p_value ? std::min(*r.p_value, t.p_value) : t.p_value;
  }
  r.tests = format::join(statements, "; ");
  r.passed = passed;
  for (const ParameterVerdict& v : parameters) {
    if (v.key != key) continue;
    r.passed = reasons.empty() && v.passed;  // this value's own verdict (the fit-wide conditions included)
    if (std::isfinite(v.sigma_ratio)) r.sigma_ratio = v.sigma_ratio;
    if (std::isfinite(v.prior_sigma) && v.prior_sigma > 0.0) r.prior_sigma = v.prior_sigma;
  }
  return r;
}

std::vector<GateRecord> GateResult::records(const std::vector<std::string>& keys) const {
  std::vector<GateRecord> out;
  for (const std::string& k : keys) out.push_back(record(k));
  return out;
}

std::string to_text(const GateResult& g) {
  if (g.parameters.empty() && g.passed) return {};
  std::string out = "quality gate: " + std::string(g.passed ? "passed" : "refused") + " (solver " + g.solver.termination + ", " +
                    std::to_string(g.solver.iterations) + " iterations)\n";
  for (const ResidualTest& t : g.tests) out += "  " + t.statement + "\n";
  for (const std::string& line : g.refusal_lines()) out += "  not measured: " + line + "\n";
  return out;
}

Json to_json(const GateResult& g) {
  const auto num = [](double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); };
  Json tests = Json::array();
  for (const ResidualTest& t : g.tests) {
    tests.push_back({{"name", t.name}, {"statement", t.statement}, {"statistic", num(t.statistic)}, {"p_value", num(t.p_value)},
                     {"applicable", t.applicable}, {"passed", t.passed}});
  }
  Json params = Json::array();
  for (const ParameterVerdict& v : g.parameters) {
    params.push_back({{"parameter", v.key}, {"label", v.label}, {"unit", v.unit}, {"value", num(v.value)}, {"sigma", num(v.sigma)},
                      {"prior_sigma", num(v.prior_sigma)}, {"sigma_ratio", num(v.sigma_ratio)}, {"passed", v.passed},
                      {"reasons", v.reasons}});
  }
  return {{"passed", g.passed},
          {"fit", g.fit},
          {"solver", {{"converged", g.solver.converged}, {"termination", g.solver.termination}, {"iterations", g.solver.iterations}}},
          {"tests", tests},
          {"reasons", g.reasons},
          {"parameters", params},
          {"max_sigma_to_prior", g.max_sigma_to_prior},
          {"alpha", kAlpha}};
}

}  // namespace fivebar::gate
