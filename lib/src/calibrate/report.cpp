// The calibration's outputs (fivebar/calibrate/report.hpp).
#include "fivebar/calibrate/report.hpp"

#include <cmath>

#include "fivebar/format.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/sections/provenance.hpp"

#include <algorithm>
#include <stdexcept>

namespace fivebar::calibrate {

namespace {
const char* kMethod = "fivebar calibrate: nonlinear least squares (Ceres, Levenberg-Marquardt), posterior sigma";
Json finite_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
Json figures(const Figures& f) { return {{"rms_mm", finite_or_null(f.rms_mm)}, {"max_mm", finite_or_null(f.max_mm)}}; }
Json excluded(const std::vector<ExcludedPose>& poses) {
  Json out = Json::array();
  for (const ExcludedPose& e : poses) {
    out.push_back({{"line", e.line}, {"mechanism", e.mechanism}, {"reason", e.reason}, {"residual_mm", e.residual_mm},
                   {"standardized", e.standardized}});
  }
  return out;
}
}  // namespace

namespace {
std::vector<GateRecord> records(const CalibrationResult& r, const std::vector<MeasuredValue>& values) {
  std::vector<std::string> keys;
  for (const MeasuredValue& v : values) keys.push_back(v.key);
  return r.gate.records(keys);
}
}  // namespace

Json to_json(const CalibrationResult& r) {
  Json params = Json::array();
  for (const Parameter& p : r.parameters) {
    Json j = {{"parameter", p.key},  {"value", p.value},           {"sigma", p.sigma},
              {"identified", p.identified}, {"unit", p.unit},        {"design", p.design},
              {"mechanism", p.mechanism.empty() ? Json(nullptr) : Json(p.mechanism)}, {"requested", p.requested}};
    if (!p.note.empty()) j["note"] = p.note;
    params.push_back(std::move(j));
  }
  Json unid = Json::array();
  for (const Unidentifiable& u : r.unidentifiable) unid.push_back({{"parameter", u.parameter}, {"combination", u.combination}});
  Json poses = Json::array();
  for (const PoseResidual& p : r.residuals) {
    poses.push_back({{"line", p.line}, {"mechanism", p.mechanism}, {"holdout", p.holdout},
                     {"before_mm", finite_or_null(p.before_mm)}, {"after_mm", finite_or_null(p.after_mm)}});
  }
  return {{"station", r.station},
          {"mechanisms", r.mechanisms},
          {"poses", r.poses},
          {"holdout_poses", r.holdout_poses},
          {"parameters", params},
          {"identifiability",
           {{"singular_values", r.singular_values},
            // Without poses (hard-stop readings) neither exists: null, not 0 (docs/conventions.md).
            {"condition_number", r.poses > 0 ? finite_or_null(r.condition_number) : Json(nullptr)},
            {"observability_index", r.poses > 0 ? finite_or_null(r.observability_index) : Json(nullptr)},
            {"unidentifiable", unid},
            {"requested_unidentifiable", r.requested_unidentifiable}}},
          {"sigma_mm", r.sigma_mm},
          {"sigma_estimated", r.sigma_estimated},
          {"residuals", {{"before", figures(r.before)}, {"after", figures(r.after)}}},
          {"holdout", {{"before", figures(r.holdout_before)}, {"after", figures(r.holdout_after)}}},
          {"per_pose", poses},
          {"solver", {{"iterations", r.iterations}, {"converged", r.converged}, {"termination", r.termination}, {"report", r.solver_report}}},
          {"skipped", excluded(r.skipped)},
          {"outliers", excluded(r.outliers)},
          {"gate", gate::to_json(r.gate)}};
}

std::string report_markdown(const CalibrationResult& r, const Source& source) {
  using format::fixed;
  std::string md = "# Kinematic calibration of station " + r.station + "\n\n";
  md += "Measurements `" + source.file + "` (sha256 `" + source.sha256 + "`), " + std::to_string(r.poses) + " poses fitted";
  if (r.holdout_poses > 0) md += ", " + std::to_string(r.holdout_poses) + " held out";
  md += "; " + format::join(r.mechanisms) + "; " + source.date + ".\n\n";
  md += "| parameter | design | estimate | sigma | unit | |\n|---|---:|---:|---:|---|---|\n";
  for (const Parameter& p : r.parameters) {
    md += "| `" + p.key + "` | " + format::shortest(p.design) + " | " + fixed(p.value, 6) + " | " +
          (p.identified ? fixed(p.sigma, 6) : std::string("-")) + " | " + p.unit + " | " +
          (p.identified ? std::string("fitted") : p.note) + " |\n";
  }
  md += "\nResiduals (|measured - model|, mm): before RMS " + fixed(r.before.rms_mm, 4) + ", max " + fixed(r.before.max_mm, 4) +
        "; after RMS " + fixed(r.after.rms_mm, 4) + ", max " + fixed(r.after.max_mm, 4);
  if (r.holdout_poses > 0) md += "; held-out poses RMS " + fixed(r.holdout_after.rms_mm, 4) + ", max " + fixed(r.holdout_after.max_mm, 4);
  md += ".\nMeasurement sigma " + fixed(r.sigma_mm, 4) + " mm (" + (r.sigma_estimated ? "estimated from the residuals" : "given") + ").\n\n";
  md += "Identifiability: condition number " + fixed(r.condition_number, 1) + ", observability index O1 " +
        fixed(r.observability_index, 4) + " (a-priori scales, docs/calibrate.md).\n";
  for (const Unidentifiable& u : r.unidentifiable) md += "- `" + u.parameter + "` not identifiable: " + u.combination + "\n";
  for (const ExcludedPose& e : r.skipped) md += "- line " + std::to_string(e.line) + " (" + e.mechanism + ") skipped: " + e.reason + "\n";
  for (const ExcludedPose& e : r.outliers) {
    md += "- line " + std::to_string(e.line) + " (" + e.mechanism + ") " + e.reason + ": left out of the final least squares\n";
  }
  md += "\nSolver: " + r.solver_report + "\n";
  md += "\nQuality gate (docs/calibrate.md \"The quality gate\"): " + std::string(r.gate.passed ? "passed" : "refused: nothing patched") +
        "; solver " + r.gate.solver.termination + ".\n";
  for (const gate::ResidualTest& t : r.gate.tests) md += "- " + t.statement + "\n";
  for (const std::string& line : r.gate.refusal_lines()) md += "- not measured: " + line + "\n";
  return md;
}

Design with_provenance(const Design& patched, const CalibrationResult& r, const Source& source) {
  // Through the one provenance writer (fivebar/provenance.hpp), with the posterior correlations.
  if (!r.gate.passed) throw std::logic_error("with_provenance: the fit did not pass its quality gate");
  std::vector<MeasuredValue> values;
  for (const std::string& key : r.key_covariance_keys) {
    const auto it = std::find_if(r.parameters.begin(), r.parameters.end(), [&](const Parameter& q) { return q.key == key; });
    values.push_back({key, it->sigma});
  }
  if (values.empty()) {  // no joint covariance (the hard stops): the sigmas alone
    for (const Parameter& q : r.parameters) {
      if (q.identified && !q.mechanism.empty()) values.push_back({q.key, q.sigma});
    }
    return with_measured_values(patched, values, {source.file, source.sha256, source.date, kMethod}, Eigen::MatrixXd(), records(r, values));
  }
  return with_measured_values(patched, values, {source.file, source.sha256, source.date, kMethod}, r.key_covariance, records(r, values));
}

Json to_json(const std::vector<MechanismPlan>& plans, const PlanOptions& o) {
  Json out = Json::array();
  for (const MechanismPlan& p : plans) {
    Json sig = Json::array();
    for (std::size_t k = 0; k < p.names.size() && k < p.expected_sigma.size(); ++k) {
      sig.push_back({{"parameter", p.names[k]}, {"planned", finite_or_null(p.expected_sigma[k])}, {"random", finite_or_null(p.random_sigma[k])}});
    }
    out.push_back({{"station", p.station}, {"mechanism", p.mechanism}, {"poses", p.poses.size()}, {"candidates", p.candidates},
                   {"measurement_sigma_mm", o.sigma_mm}, {"observability_index", p.observability_index},
                   {"random_observability_index", p.random_observability_index}, {"expected_sigma", sig},
                   {"criterion", o.criterion == PlanCriterion::i_optimal ? "I-optimal" : "D-optimal"},
                   {"predicted_target_rms_error_mm_linearised", finite_or_null(p.predicted_target_error_mm)},
                   {"random_target_rms_error_mm_linearised", finite_or_null(p.random_target_error_mm)},
                   {"target_points", p.target_points},
                   {"margins_mm", {{"extension", o.extension_margin_mm}, {"base_line", o.base_margin_mm}}},
                   {"reach_samples", o.reach_samples},
                   {"problem", p.problem}});
  }
  return out;
}

std::string plan_csv(const std::vector<MechanismPlan>& plans) {
  std::string csv = "station,mechanism,pose,theta1_deg,theta2_deg,volts1,volts2,x_mm,y_mm\n";
  for (const MechanismPlan& p : plans) {
    for (std::size_t i = 0; i < p.poses.size(); ++i) {
      const PlannedPose& q = p.poses[i];
      csv += p.station + "," + p.mechanism + "," + std::to_string(i + 1) + "," + format::shortest(q.theta1 * format::kDegPerRad) + "," +
             format::shortest(q.theta2 * format::kDegPerRad) + "," + format::shortest(q.volts1) + "," + format::shortest(q.volts2) + "," +
             format::shortest(q.point.x()) + "," + format::shortest(q.point.y()) + "\n";
    }
  }
  return csv;
}

}  // namespace fivebar::calibrate
