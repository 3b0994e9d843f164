// The design an identification patches (fivebar/identify/patch.hpp).
#include "fivebar/identify/patch.hpp"

#include <algorithm>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/sections/motor.hpp"

namespace fivebar::identify {

namespace {

/// Splits "motor.<scope>.<field>" into the scope ("" or "stations.S.M.thetaJ") and the field.
bool split_motor_key(const std::string& key, std::string& scope, std::string& field) {
  if (key.rfind("motor.", 0) != 0) return false;
  const std::size_t dot = key.rfind('.');
  field = key.substr(dot + 1);
  scope = dot > 5 ? key.substr(6, dot - 6) : std::string();
  return true;
}

const MotorField* motor_field(const std::string& field) {
  const auto& fields = motor_fields();
  const auto f = std::find_if(fields.begin(), fields.end(), [&](const MotorField& x) { return x.key == field; });
  return f == fields.end() ? nullptr : &*f;
}

bool in_range(const MotorField& f, double v) { return (v > f.lo || (f.zero_ok && v >= f.lo)) && v <= f.hi; }

/// The drive fit the gate reads for a joint, and what it was measured on.
struct DriveFit {
  double percent = 0.0;
  std::string on;
};

DriveFit gated_fit(const JointIdentification& r, bool use_output_error) {
  if (use_output_error) {
    if (r.validation_oe) return {r.validation_oe->drive_fit_percent, "the validation log (output error)"};
    return {r.estimation_oe.drive_fit_percent, "the estimation log (output error; no validation log: an optimistic figure)"};
  }
  const std::string m = r.iv ? "IDIM-IV" : "IDIM-LS";
  if (r.validation_idim) return {r.validation_idim->drive_fit_percent, "the validation log (" + m + ")"};
  return {r.estimation_idim.drive_fit_percent, "the estimation log (" + m + "; no validation log: an optimistic figure)"};
}

}  // namespace

gate::GateResult identification_gate(const std::vector<JointIdentification>& results, bool use_output_error) {
  gate::GateInput in;
  in.fit = "fivebar identify";
  in.solver = {true, use_output_error ? "CONVERGENCE" : "closed form (IDIM-LS)", 0};
  bool closed = false;
  int iterations = 0;
  for (const JointIdentification& r : results) {
    closed = closed || r.method == "IDIM-IV";
    iterations = std::max(iterations, r.iv_iterations);
  }
  if (closed && !use_output_error) in.solver = {true, "CONVERGENCE (IDIM-IV, instrumental variables iterated)", iterations};
  for (const JointIdentification& r : results) {
    if (use_output_error && r.output_error_status != "converged") {
      in.solver = {false, "output error of joint " + r.joint + ": " + r.output_error_status, 0};
    }
    if (r.method == "IDIM-IV" && !r.iv_converged) {
      in.solver = {false, "IDIM-IV of joint " + r.joint + ": " + r.iv_status, r.iv_iterations};
    }
  }
  for (const JointIdentification& r : results) {
    const DriveFit fit = gated_fit(r, use_output_error);
    gate::ResidualTest t;
    t.name = "drive fit";
    t.statistic = fit.percent;
    t.passed = fit.percent >= kDriveFitFloorPercent;
    t.statement = "joint " + r.joint + ": drive fit " + format::fixed(fit.percent, 1) + " % on " + fit.on + (t.passed ? " >= " : " < ") +
                  "the floor " + format::fixed(kDriveFitFloorPercent, 0) + " %" +
                  (t.passed ? "" : ": the model does not describe this log (an unmodelled effect, or not the drive that moved the joint)");
    in.tests.push_back(std::move(t));
  }
  gate::ResidualTest white;
  white.name = "whiteness";
  white.applicable = false;
  white.statement = "whiteness of the residuals: not applicable (a zero-phase filtered, decimated regression's residuals are correlated by "
                    "construction; the drive fit on a second log checks the model instead)";
  in.tests.push_back(std::move(white));
  for (const JointIdentification& r : results) {
    for (const Parameter& p : r.parameters) {
      std::string scope, field;
      if (!p.identified || !split_motor_key(p.key, scope, field)) continue;
      const MotorField* f = motor_field(field);
      gate::ParameterCheck c;
      c.key = p.key;
      c.label = r.joint + " " + field;
      c.unit = f != nullptr ? std::string(f->unit) : std::string();
      c.value = p.value;
      c.sigma = p.sigma;
      c.max_relative_sigma = kMaxRelativeSigma;
      in.parameters.push_back(std::move(c));
    }
  }
  return gate::evaluate(in);
}

Patch patch_design(const Design& design, const std::vector<JointIdentification>& results, const MeasurementSource& source,
                   bool use_output_error) {
  Patch out;
  out.gate = identification_gate(results, use_output_error);
  Design d = design;
  MotorSettings* ms = d.get<MotorSettings>();
  std::vector<MeasuredValue> values;
  for (const gate::ParameterVerdict& v : out.gate.parameters) {
    std::string scope, field;
    split_motor_key(v.key, scope, field);
    if (ms == nullptr) throw InputError(design.name + ": the design has no `motor:` section to patch (" + v.key + ")");
    const MotorField* f = motor_field(field);
    if (f == nullptr) throw InputError(v.key + ": not a key of the `motor:` section");
    const std::string head =
        v.key + " = " + format::general(v.value, 5) + " " + std::string(f->unit) + " (sigma " + format::general(v.sigma, 3) + "): ";
    if (!out.gate.reasons.empty()) {
      out.not_patched.push_back(head + format::join(out.gate.reasons, "; "));
      continue;
    }
    if (!v.passed) {
      out.not_patched.push_back(head + format::join(v.reasons, "; ") + ", not written");
      continue;
    }
    // A value the `motor:` section's rules refuse (a friction estimated below zero within its
    // noise) is not written: the key stays an assumption, and the caller says why.
    if (!in_range(*f, v.value)) {
      out.not_patched.push_back(head + "outside the motor: section's range, not written");
      continue;
    }
    if (scope.empty()) {
      ms->defaults.*(f->member) = v.value;
    } else {
      // stations.<station>.<mechanism>.theta<j>: the joint's own scope, created when absent.
      const std::size_t a = scope.find('.'), b = scope.rfind('.');
      const std::size_t m = scope.rfind('.', b - 1);
      if (scope.rfind("stations.", 0) != 0 || a == b || m <= a || scope.compare(b + 1, 5, "theta") != 0) {
        throw InputError(v.key + ": expected motor.stations.<station>.<mechanism>.theta<j>.<key>");
      }
      MotorOverride key;
      key.station = scope.substr(a + 1, m - a - 1);
      key.mechanism = scope.substr(m + 1, b - m - 1);
      key.joint = scope.back() - '0';
      const Station* st = d.station(key.station);
      if (st == nullptr || st->mechanism(key.mechanism) == nullptr || (key.joint != 1 && key.joint != 2)) {
        throw InputError(v.key + ": the design has no joint " + key.station + "/" + key.mechanism + "/theta" + std::to_string(key.joint));
      }
      auto it = std::find_if(ms->overrides.begin(), ms->overrides.end(), [&](const MotorOverride& o) {
        return o.station == key.station && o.mechanism == key.mechanism && o.joint == key.joint;
      });
      if (it == ms->overrides.end()) {
        ms->overrides.push_back(key);
        it = std::prev(ms->overrides.end());
      }
      it->values[static_cast<std::size_t>(f - motor_fields().data())] = v.value;
    }
    values.push_back({v.key, v.sigma});
    out.patched.push_back(v.key);
  }
  if (values.empty()) return out;
  d.validate();
  out.design = with_measured_values(d, values, source, {}, out.gate.records(out.patched));
  return out;
}

}  // namespace fivebar::identify
