// JSON of an identification (docs/schemas/identify.schema.json).

#include "fivebar/identify/json.hpp"

namespace fivebar::identify {

namespace {

Json estimate_json(const Estimate& e) {
  Json j = {{"rows", e.rows}, {"residual_sigma", e.residual_sigma}, {"parameters", Json::array()}};
  for (std::size_t i = 0; i < e.names.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    j["parameters"].push_back({{"name", e.names[i]},
                               {"value", e.value[k]},
                               {"sigma", e.sigma[k]},
                               {"identified", static_cast<bool>(e.identified[i])},
                               {"note", e.notes[i]}});
  }
  Json corr = Json::array(), cov = Json::array();
  for (Eigen::Index a = 0; a < e.correlation.rows(); ++a) {
    Json rc = Json::array(), rv = Json::array();
    for (Eigen::Index b = 0; b < e.correlation.cols(); ++b) {
      rc.push_back(e.correlation(a, b));
      rv.push_back(e.covariance(a, b));
    }
    corr.push_back(rc);
    cov.push_back(rv);
  }
  j["covariance"] = cov;
  j["correlation"] = corr;
  return j;
}

Json fit_json(const Fit& f) {
  Json j = {{"drive_fit_percent", f.drive_fit_percent}, {"drive_relative_error_percent", f.drive_relative_error_percent},
            {"simulated", f.simulated}};
  if (f.simulated) {
    j["position_fit_percent"] = f.position_fit_percent;
    j["position_relative_error_percent"] = f.position_relative_error_percent;
  }
  return j;
}

}  // namespace

Json to_json(const JointIdentification& r) {
  Json j = {{"joint", r.joint},
            {"drive_column", r.drive_column},
            {"reading_column", r.reading_column},
            {"linear", r.linear},
            {"sample_time_s", r.sample_time},
            {"cutoff_hz", r.cutoff_hz},
            {"decimation", r.decimation},
            {"edge_samples", r.edge_samples},
            {"reversal_samples", r.reversal_samples},
            {"reversal_rows", r.reversal_rows},
            {"method", r.method},
            {"logs", r.logs}};
  j["parameters"] = Json::array();
  for (const Parameter& p : r.parameters) {
    j["parameters"].push_back(
        {{"parameter", p.key}, {"value", p.value}, {"sigma", p.sigma}, {"identified", p.identified}, {"note", p.note}});
  }
  j["unidentifiable"] = r.unidentifiable;
  j["idim_ls"] = estimate_json(r.idim);
  if (r.electrical) j["electrical"] = estimate_json(*r.electrical);
  if (r.method == "IDIM-IV") {
    j["idim_iv"] = {{"status", r.iv_status}, {"converged", r.iv_converged}, {"iterations", r.iv_iterations}};
    if (r.iv) j["idim_iv"]["estimate"] = estimate_json(*r.iv);
  }
  const char* inverse = r.method == "IDIM-IV" ? "idim_iv" : "idim_ls";
  j["output_error"] = {{"status", r.output_error_status}};
  if (r.output_error) j["output_error"]["estimate"] = estimate_json(*r.output_error);
  j["fit"] = {{"estimation", {{inverse, fit_json(r.estimation_idim)}}}};
  if (r.output_error) j["fit"]["estimation"]["output_error"] = fit_json(r.estimation_oe);
  if (r.validation_idim) {
    j["fit"]["validation"] = {{inverse, fit_json(*r.validation_idim)}};
    if (r.validation_oe) j["fit"]["validation"]["output_error"] = fit_json(*r.validation_oe);
  }
  return j;
}

}  // namespace fivebar::identify
