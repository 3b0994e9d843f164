// The `provenance:` section (fivebar/sections/provenance.hpp): key path -> where the value came from.
#include "fivebar/sections/provenance.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "fivebar/design.hpp"
#include "sections/rules.hpp"
#include "sections/section.hpp"

namespace fivebar {

namespace {

/// YYYY-MM-DD (digits already checked) names a day of the Gregorian calendar.
bool calendar_date(const std::string& date) {
  const int y = std::stoi(date.substr(0, 4)), m = std::stoi(date.substr(5, 2)), d = std::stoi(date.substr(8, 2));
  if (m < 1 || m > 12 || d < 1) return false;
  static constexpr int kDays[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
  return d <= kDays[m - 1] + (m == 2 && leap ? 1 : 0);
}

/// The correlations of the entries that have any, as one matrix (unit diagonal, 0 where none is
/// given), must be a correlation matrix: positive semi-definite (ρ01 = ρ02 = 0.99 with ρ12 = -0.99
/// is no covariance's), within rounding.
void check_correlations_psd(const std::map<std::string, ProvenanceEntry, std::less<>>& entries) {
  std::vector<std::string> keys;
  for (const auto& item : entries)
    if (!item.second.correlation.empty()) keys.push_back(item.first);
  for (const auto& item : entries)
    for (const auto& c : item.second.correlation)
      if (std::find(keys.begin(), keys.end(), c.first) == keys.end()) keys.push_back(c.first);
  if (keys.size() < 3) return;  // each |rho| <= 1 already makes a 2 x 2 matrix valid
  const auto n = static_cast<Eigen::Index>(keys.size());
  Eigen::MatrixXd R = Eigen::MatrixXd::Identity(n, n);
  for (Eigen::Index a = 0; a < n; ++a) {
    for (const auto& c : entries.at(keys[static_cast<std::size_t>(a)]).correlation) {
      const auto b = static_cast<Eigen::Index>(std::find(keys.begin(), keys.end(), c.first) - keys.begin());
      R(a, b) = R(b, a) = c.second;
    }
  }
  const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(R, Eigen::EigenvaluesOnly).eigenvalues().minCoeff();
  if (smallest < -1e-9) {
    throw ValidationError(keys.front() + ".correlation", "the correlations of " + std::to_string(keys.size()) +
                                                             " keys are no covariance's (the matrix has the eigenvalue " +
                                                             rules::plain_number(smallest) + " < 0: not positive semi-definite)");
  }
}

}  // namespace

void GateRecord::validate() const {
  if (solver.empty()) throw ValidationError("solver", "must not be empty");
  if (p_value && !(*p_value >= 0.0 && *p_value <= 1.0)) throw ValidationError("p_value", "= " + rules::plain_number(*p_value) + ": must be in [0, 1]");
  if (sigma_ratio && !(*sigma_ratio >= 0.0 && std::isfinite(*sigma_ratio))) {
    throw ValidationError("sigma_ratio", "= " + rules::plain_number(*sigma_ratio) + ": must be >= 0");
  }
  if (prior_sigma && !(*prior_sigma > 0.0 && std::isfinite(*prior_sigma))) {
    throw ValidationError("prior_sigma", "= " + rules::plain_number(*prior_sigma) + ": must be > 0");
  }
}

bool ProvenanceEntry::placeholder_hash() const { return sha256.find_first_not_of('0') == std::string::npos; }

void ProvenanceEntry::validate() const {
  if (source.empty()) throw ValidationError("source", "must not be empty");
  if (method.empty()) throw ValidationError("method", "must not be empty");
  bool hex = sha256.size() == 64;
  for (const char c : sha256) hex = hex && ((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'));
  if (!hex) throw ValidationError("sha256", "= " + sha256 + ": must be 64 lowercase hex digits");
  bool date_ok = date.size() == 10 && date[4] == '-' && date[7] == '-';
  for (std::size_t i = 0; i < date.size() && date_ok; ++i) date_ok = i == 4 || i == 7 || (date[i] >= '0' && date[i] <= '9');
  if (!date_ok) throw ValidationError("date", "= " + date + ": must be YYYY-MM-DD");
  if (!calendar_date(date)) throw ValidationError("date", "= " + date + ": not a date of the calendar (month 01-12, day within the month)");
  if (sigma && !(*sigma >= 0.0 && std::isfinite(*sigma))) {
    throw ValidationError("sigma", "= " + rules::plain_number(*sigma) + ": must be >= 0");
  }
  for (const auto& [key, rho] : correlation) {
    if (!(std::abs(rho) <= 1.0)) throw ValidationError("correlation." + key, "= " + rules::plain_number(rho) + ": must be in [-1, 1]");
    if (!sigma) throw ValidationError("correlation", "needs this entry's sigma");
  }
  if (gate) rules::validate_nested("gate", [this] { gate->validate(); });
}

void ProvenanceSettings::validate() const {
  // Not a structured binding: clang before 16 cannot capture one in a lambda (the fuzz build).
  for (const auto& item : entries) {
    const ProvenanceEntry& entry = item.second;
    rules::validate_nested(item.first, [&entry] { entry.validate(); });
    for (const auto& c : entry.correlation) {
      const std::string where = item.first + ".correlation." + c.first;
      const auto other = entries.find(c.first);
      if (c.first == item.first) throw ValidationError(where, "a value's correlation with itself is 1: leave it out");
      if (other == entries.end() || !other->second.sigma) {
        throw ValidationError(where, "names a key without its own provenance entry and sigma");
      }
      const auto back = other->second.correlation.find(item.first);
      if (back != other->second.correlation.end() && back->second != c.second) {
        throw ValidationError(where, "= " + rules::plain_number(c.second) + ": the entry of " + c.first + " gives " +
                                         rules::plain_number(back->second) + " for the same pair");
      }
    }
  }
  check_correlations_psd(entries);
}

namespace sections {
namespace {

void load(const Value& v, Design& design) {
  ProvenanceSettings& p = design.set(ProvenanceSettings{});
  if (v.is_null()) return;
  for (const Value& e : v.entries({}, "from key paths of the design to {source, sha256, date, method, sigma}", /*any_key=*/true)) {
    const auto all = e.entries({"source", "sha256", "date", "method", "sigma", "correlation", "gate"},
                               "(source, sha256, date, method, sigma, correlation, gate)");
    ProvenanceEntry entry;
    entry.source = require(all, "source", e).text("must be text (a file name)");
    entry.sha256 = require(all, "sha256", e).text("must be text (64 hex digits)");
    entry.date = require(all, "date", e).text("must be text (YYYY-MM-DD)");
    entry.method = require(all, "method", e).text("must be text");
    if (const Value* s = find(all, "sigma")) entry.sigma = s->number("");
    if (const Value* c = find(all, "correlation")) {
      if (!c->is_null()) {
        for (const Value& r : c->entries({}, "from key paths of measured values to correlation coefficients", /*any_key=*/true)) {
          entry.correlation[r.name()] = r.number("");
        }
      }
    }
    if (const Value* g = find(all, "gate")) {
      const auto fields = g->entries({"passed", "solver", "tests", "p_value", "sigma_ratio", "prior_sigma"},
                                     "(passed, solver, tests, p_value, sigma_ratio, prior_sigma)");
      GateRecord r;
      const Value& passed = require(fields, "passed", *g);
      const std::string word = passed.text("must be true or false");
      if (word != "true" && word != "false") passed.fail_value("must be true or false");
      r.passed = word == "true";
      r.solver = require(fields, "solver", *g).text("must be text (the solver's termination)");
      if (const Value* t = find(fields, "tests")) r.tests = t->text("must be text");
      if (const Value* x = find(fields, "p_value")) r.p_value = x->number("");
      if (const Value* x = find(fields, "sigma_ratio")) r.sigma_ratio = x->number("");
      if (const Value* x = find(fields, "prior_sigma")) r.prior_sigma = x->number("");
      entry.gate = std::move(r);
    }
    p.entries[e.name()] = std::move(entry);
  }
}

void validate(const Design& design) {
  const ProvenanceSettings* p = design.get<ProvenanceSettings>();
  if (p == nullptr) return;
  rules::validate_nested("provenance", [&] { p->validate(); });
  for (const auto& [key, entry] : p->entries) {
    if (design_number_keys(design, key).empty()) {
      throw ValidationError("provenance." + key, "is not a key path of the design that leads to a number");
    }
  }
}

void write(const Design& design, Out& top) {
  const ProvenanceSettings* p = design.get<ProvenanceSettings>();
  if (p == nullptr) return;
  Out& o = top.add("provenance", Out::map());
  for (const auto& [key, e] : p->entries) {
    Out& m = o.add(key, Out::map(/*flow=*/true));
    m.add("source", Out::quoted(e.source));
    m.add("sha256", Out::plain(e.sha256));
    m.add("date", Out::quoted(e.date));
    m.add("method", Out::quoted(e.method));
    if (e.sigma) m.add("sigma", Out::number(*e.sigma));
    if (!e.correlation.empty()) {
      Out& c = m.add("correlation", Out::map(/*flow=*/true));
      for (const auto& [other, rho] : e.correlation) c.add(other, Out::number(rho));
    }
    if (e.gate) {
      Out& g = m.add("gate", Out::map(/*flow=*/true));
      g.add("passed", Out::plain(e.gate->passed ? "true" : "false"));
      g.add("solver", Out::quoted(e.gate->solver));
      if (!e.gate->tests.empty()) g.add("tests", Out::quoted(e.gate->tests));
      if (e.gate->p_value) g.add("p_value", Out::number(*e.gate->p_value));
      if (e.gate->sigma_ratio) g.add("sigma_ratio", Out::number(*e.gate->sigma_ratio));
      if (e.gate->prior_sigma) g.add("prior_sigma", Out::number(*e.gate->prior_sigma));
    }
  }
}

}  // namespace

Section provenance_section() { return {ProvenanceSettings::kKey, &load, &validate, &write}; }

}  // namespace sections
}  // namespace fivebar
