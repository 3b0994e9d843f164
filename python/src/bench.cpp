// The bench-side commands from Python (docs/python.md): kinematic calibration from a measurement
// file (`fivebar calibrate DESIGN MEAS.csv`) and the printable parts' OpenSCAD sources
// (`fivebar parts --no-render`). Plain dicts and NumPy arrays; nothing is written: the patched
// design is returned as a Design, the .scad texts as strings.

#include <filesystem>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>

#include "bindings.hpp"
#include "fivebar/calibrate.hpp"
#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/identify.hpp"
#include "fivebar/parts.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/provenance/gate.hpp"
#include "fivebar/sections/bench.hpp"
#include "fivebar/sha256.hpp"

namespace fivebar::python {

namespace {

// --- Calibrate ------------------------------------------------------------------------------------

struct CalibrateArgs {
  std::string station, mechanism, frame = "fixed", loss = "none";
  std::vector<std::string> fit;
  double loss_scale = 2.0;
  std::optional<double> sigma_mm;
  int holdout = 0;
};

/// The options of `fivebar calibrate`, checked as the CLI checks its flags (cli/calibrate.cpp).
calibrate::CalibrateOptions calibrate_options(const CalibrateArgs& a) {
  if (a.frame != "fixed" && a.frame != "fit") throw InputError("frame = '" + a.frame + "': must be fixed or fit");
  if (a.loss != "none" && a.loss != "huber" && a.loss != "cauchy") {
    throw InputError("loss = '" + a.loss + "': must be none, huber or cauchy");
  }
  const auto positive = [](const char* name, double v, const char* unit) {
    if (!(v > 0.0) || !std::isfinite(v) || v > csv::kMaxBenchValue) {
      throw InputError(std::string(name) + " = " + std::to_string(v) + ": must be a finite number > 0 and at most 1e9 (" +
                       unit + ")");
    }
  };
  positive("loss_scale", a.loss_scale, "measurement sigmas");
  if (a.sigma_mm) positive("sigma_mm", *a.sigma_mm, "mm");
  if (a.holdout < 0) throw InputError("holdout = " + std::to_string(a.holdout) + ": must be >= 0");
  calibrate::CalibrateOptions co;
  co.station = a.station;
  if (!a.mechanism.empty()) co.mechanisms = {a.mechanism};
  co.fit_frame = a.frame == "fit";
  co.fit = a.fit;
  co.fit_given = !a.fit.empty();
  co.loss = a.loss == "huber" ? calibrate::Loss::huber : a.loss == "cauchy" ? calibrate::Loss::cauchy : calibrate::Loss::none;
  co.loss_scale = a.loss_scale;
  co.sigma_mm = a.sigma_mm;
  co.holdout = a.holdout;
  return co;
}

/// The data file as a provenance entry of a design returned in memory names it: absolute (free of
/// links and dots), so that untrusted_values() finds it wherever the design is saved. The CLI, which
/// knows where it writes the design, names it relative to that folder (recorded_source()).
std::string absolute_source(const std::string& path) {
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::weakly_canonical(std::filesystem::absolute(path, ec), ec);
  return ec ? path : p.generic_string();
}

py::array_t<double> matrix(const Eigen::VectorXd& v) {
  py::array_t<double> a(py::ssize_t(v.size()));
  for (Eigen::Index i = 0; i < v.size(); ++i) a.mutable_at(py::ssize_t(i)) = v(i);
  return a;
}

py::array_t<double> matrix(const Eigen::MatrixXd& m) {
  py::array_t<double> a({py::ssize_t(m.rows()), py::ssize_t(m.cols())});
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    for (Eigen::Index j = 0; j < m.cols(); ++j) a.mutable_at(py::ssize_t(i), py::ssize_t(j)) = m(i, j);
  }
  return a;
}

/// A calibration's result as the Python dict (`doc_key`: where the CLI's --json puts it, "calibration"
/// or "hard_stops"); the patched design `fivebar calibrate --out` would write, when the result passed.
py::dict calibration_dict(const Design& design, const calibrate::CalibrationResult& r, const std::string& path,
                          const std::string& text, const char* doc_key) {
  const py::ssize_t n = py::ssize_t(r.parameters.size());
  py::array_t<double> value(n), sigma(n), prior(n);
  py::array_t<bool> identified(n);
  py::list keys, names, units;
  for (py::ssize_t k = 0; k < n; ++k) {
    const calibrate::Parameter& p = r.parameters[std::size_t(k)];
    value.mutable_at(k) = p.value;
    sigma.mutable_at(k) = p.sigma;
    prior.mutable_at(k) = p.design;
    identified.mutable_at(k) = p.identified;
    keys.append(p.key);
    names.append(p.mechanism.empty() ? "frame." + p.name : p.mechanism + "." + p.name);
    units.append(p.unit);
  }
  py::dict d;
  d["station"] = r.station;
  d["mechanisms"] = py::cast(r.mechanisms);
  d["poses"] = r.poses;
  d["keys"] = keys;
  d["names"] = names;
  d["units"] = units;
  d["value"] = value;
  d["sigma"] = sigma;
  d["design_value"] = prior;
  d["identified"] = identified;
  d["covariance"] = matrix(r.covariance);
  d["covariance_names"] = py::cast(r.covariance_names);
  d["key_covariance"] = matrix(r.key_covariance);
  d["key_covariance_keys"] = py::cast(r.key_covariance_keys);
  py::list unidentifiable;
  for (const calibrate::Unidentifiable& u : r.unidentifiable) unidentifiable.append(py::make_tuple(u.parameter, u.combination));
  d["unidentifiable"] = unidentifiable;
  d["requested_unidentifiable"] = r.requested_unidentifiable;
  d["condition_number"] = r.condition_number;
  d["observability_index"] = r.observability_index;
  d["sigma_mm"] = r.sigma_mm;
  d["gate_passed"] = r.gate.passed;
  d["gate_reasons"] = py::cast(r.gate.refusal_lines());
  // The patched design `fivebar calibrate --out` would write, in memory, when the fit passed.
  if (!r.requested_unidentifiable && r.gate.passed) {
    calibrate::Source source{absolute_source(path), sha256_hex(text), today_utc()};
    auto patched = std::make_shared<Design>(calibrate::with_provenance(calibrate::patched_design(design, r), r, source));
    patched->reset<BenchSettings>();  // as the CLI's file: its bench: files would not resolve elsewhere
    d["design"] = patched;
  } else {
    d["design"] = py::none();
  }
  Json doc = {{"command", "calibrate"}, {"design", design.name}};
  doc[doc_key] = calibrate::to_json(r);
  d["summary"] = to_python(doc);
  return d;
}

py::dict calibrate_fit(const Design& design, const std::string& path, const CalibrateArgs& args) {
  const calibrate::CalibrateOptions co = calibrate_options(args);
  const std::string text = csv::read_bounded(path, calibrate::kMeasurementLimits.max_bytes, "measurement file");
  const auto rows = calibrate::parse_measurements(text, path, design);
  calibrate::CalibrationResult r;
  Interruptible run;
  run.run([&] { r = calibrate::calibrate(design, rows, co, path); });
  return calibration_dict(design, r, path, text, "calibration");
}

/// `fivebar calibrate DESIGN --hard-stops LOG`: the potentiometers from readings at the hard stops.
py::dict calibrate_hard_stops(const Design& design, const std::string& path) {
  const std::string text = csv::read_bounded(path, calibrate::kMeasurementLimits.max_bytes, "hard-stop readings");
  return calibration_dict(design, calibrate::hard_stop_calibration(design, text, path), path, text, "hard_stops");
}

/// `fivebar calibrate DESIGN --plan N`: the poses to measure per mechanism (nothing written).
py::dict calibration_plan(const Design& design, int poses, const std::string& station_given, const std::string& mechanism,
                          double sigma_mm, const std::string& criterion, std::uint64_t seed) {
  if (!(sigma_mm > 0.0) || !std::isfinite(sigma_mm) || sigma_mm > csv::kMaxBenchValue) {
    throw InputError("sigma_mm = " + std::to_string(sigma_mm) + ": must be a finite number > 0 and at most 1e9 (mm)");
  }
  if (criterion != "i" && criterion != "d") throw InputError("criterion = '" + criterion + "': must be i or d");
  calibrate::PlanOptions po;
  po.poses = poses;
  po.sigma_mm = sigma_mm;
  po.criterion = criterion == "d" ? calibrate::PlanCriterion::d_optimal : calibrate::PlanCriterion::i_optimal;
  po.seed = seed;
  std::string station = station_given;
  if (station.empty()) {
    const auto st = design.select_stations("");
    if (st.size() != 1) throw InputError("plan: choose a station with station= (the design has several)");
    station = st.front()->name;
  }
  std::vector<calibrate::MechanismPlan> plans;
  Interruptible run;
  run.run([&] { plans = calibrate::plan_poses(design, station, mechanism, po); });
  py::list out;
  for (const calibrate::MechanismPlan& p : plans) {
    const py::ssize_t n = py::ssize_t(p.poses.size());
    py::array_t<double> theta({n, py::ssize_t(2)}), volts({n, py::ssize_t(2)}), point({n, py::ssize_t(2)});
    for (py::ssize_t k = 0; k < n; ++k) {
      const calibrate::PlannedPose& x = p.poses[std::size_t(k)];
      theta.mutable_at(k, 0) = x.theta1;
      theta.mutable_at(k, 1) = x.theta2;
      volts.mutable_at(k, 0) = x.volts1;
      volts.mutable_at(k, 1) = x.volts2;
      point.mutable_at(k, 0) = x.point.x();
      point.mutable_at(k, 1) = x.point.y();
    }
    py::dict d;
    d["station"] = p.station;
    d["mechanism"] = p.mechanism;
    d["theta"] = theta;
    d["volts"] = volts;
    d["point_mm"] = point;
    d["candidates"] = p.candidates;
    d["observability_index"] = p.observability_index;
    d["random_observability_index"] = p.random_observability_index;
    d["names"] = py::cast(p.names);
    d["expected_sigma"] = py::array_t<double>(py::ssize_t(p.expected_sigma.size()), p.expected_sigma.data());
    d["random_sigma"] = py::array_t<double>(py::ssize_t(p.random_sigma.size()), p.random_sigma.data());
    d["predicted_target_error_mm"] = p.predicted_target_error_mm;
    d["random_target_error_mm"] = p.random_target_error_mm;
    d["problem"] = p.problem;
    out.append(d);
  }
  py::dict d;
  d["plans"] = out;
  d["csv"] = calibrate::plan_csv(plans);
  Json doc = {{"command", "calibrate"}, {"design", design.name}};
  doc["plan"] = calibrate::to_json(plans, po);
  d["summary"] = to_python(doc);
  return d;
}

// --- Identify -------------------------------------------------------------------------------------

namespace id = fivebar::identify;

struct IdentifyArgs {
  std::vector<std::string> logs;
  std::string rig_station, rig_mechanism;  ///< --rig mechanism STATION/MECHANISM; empty: the motor rig
  std::string validation, joint, method = "idim";
  bool closed_loop = false, output_error = true, per_direction = false, instant_drive = false;
  std::optional<double> cutoff_hz;
  std::optional<int> decimation;
  int filter_order = 4;
  double load_inertia = 0.0;
  std::vector<std::string> fit;
};

id::IdentifyOptions identify_options(const IdentifyArgs& a) {
  if (a.logs.empty()) throw InputError("logs: an identification log is required");
  if (a.cutoff_hz && (!(*a.cutoff_hz > 0.0) || !std::isfinite(*a.cutoff_hz))) {
    throw InputError("cutoff_hz = " + std::to_string(*a.cutoff_hz) + ": must be a finite number > 0 Hz (None for a tenth of the sample rate)");
  }
  if (a.decimation && *a.decimation < 1) {
    throw InputError("decimation = " + std::to_string(*a.decimation) + ": must be a whole number >= 1 (None for 10)");
  }
  if (!(a.load_inertia >= 0.0) || !std::isfinite(a.load_inertia)) throw InputError("load_inertia: must be >= 0 kg m^2");
  if (a.method != "idim" && a.method != "oe") throw InputError("method = '" + a.method + "': idim or oe");
  if (a.closed_loop && a.method == "oe") {
    throw InputError("method 'oe': not with closed_loop (an open-loop simulation of a log taken under feedback drifts)");
  }
  if (!a.rig_station.empty()) {  // the rules of `fivebar identify --rig mechanism` (cli/identify.cpp)
    if (!a.validation.empty()) throw InputError("validation: not with rig mechanism yet");
    if (a.method == "oe") throw InputError("method 'oe': not with rig mechanism (a joint of a closed chain is not simulated alone)");
    if (a.closed_loop) throw InputError("closed_loop: with the motor rig only");
    if (a.logs.size() > 1) throw InputError("logs: rig mechanism takes one log");
  }
  id::IdentifyOptions o;
  o.cutoff_hz = a.cutoff_hz.value_or(0.0);
  o.filter_order = a.filter_order;
  o.decimation = a.decimation.value_or(0);
  o.per_direction = a.per_direction;
  o.zero_order_hold = !a.instant_drive;
  o.output_error = a.output_error;
  o.use_output_error = a.method == "oe";
  if (o.use_output_error && !o.output_error) throw InputError("method 'oe': needs the output-error refinement (output_error=True)");
  o.require = a.fit;
  return o;
}

/// Each joint of the logs (or `joint`), its logs fitted together, open or closed loop: the motor
/// rig of `fivebar identify` (identify::identify_motor_rig(), as the CLI).
std::vector<id::JointIdentification> identify_motor_joints(const Design& design, const IdentifyArgs& a,
                                                           const std::vector<id::IdentifyLog>& logs,
                                                           const std::optional<id::IdentifyLog>& val,
                                                           const id::IdentifyOptions& o) {
  return id::identify_motor_rig(design, {&logs, a.logs, val ? &*val : nullptr, a.validation, a.joint, a.load_inertia, a.closed_loop}, o);
}

py::dict joint_dict(const id::JointIdentification& r) {
  const py::ssize_t n = py::ssize_t(r.parameters.size());
  py::array_t<double> value(n), sigma(n);
  py::array_t<bool> identified(n);
  py::list keys;
  for (py::ssize_t k = 0; k < n; ++k) {
    const id::Parameter& p = r.parameters[std::size_t(k)];
    value.mutable_at(k) = p.value;
    sigma.mutable_at(k) = p.sigma;
    identified.mutable_at(k) = p.identified;
    keys.append(p.key);
  }
  const id::Estimate& est = r.iv ? *r.iv : r.idim;
  py::dict d;
  d["joint"] = r.joint;
  d["method"] = r.method;
  d["keys"] = keys;
  d["value"] = value;
  d["sigma"] = sigma;
  d["identified"] = identified;
  d["unidentifiable"] = py::cast(r.unidentifiable);
  d["estimate_names"] = py::cast(est.names);
  d["estimate_value"] = matrix(est.value);
  d["estimate_sigma"] = matrix(est.sigma);
  d["covariance"] = matrix(est.covariance);
  d["correlation"] = matrix(est.correlation);
  d["residual_sigma"] = est.residual_sigma;
  d["drive_fit_percent"] = r.estimation_idim.drive_fit_percent;
  return d;
}

py::dict identify_fit(const Design& design, const IdentifyArgs& a) {
  const id::IdentifyOptions o = identify_options(a);
  std::vector<id::IdentifyLog> logs;
  for (const std::string& f : a.logs) logs.push_back(id::read_identify_log(std::filesystem::path(f)));
  std::optional<id::IdentifyLog> val;
  if (!a.validation.empty()) val = id::read_identify_log(std::filesystem::path(a.validation));
  for (const id::IdentifyLog& l : logs) id::require_log_joints_in(design, l);
  if (val) id::require_log_joints_in(design, *val);
  std::vector<id::JointIdentification> results;
  Interruptible run;
  const bool mechanism_rig = !a.rig_station.empty();
  run.run([&] {
    results = mechanism_rig ? id::identify_mechanism(design, logs.front(), a.rig_station, a.rig_mechanism, o)
                            : identify_motor_joints(design, a, logs, val, o);
  });
  if (results.empty()) throw InputError("joint = '" + a.joint + "': the log has no such joint");
  const std::vector<std::string> refused = id::refused_fits(results, o, "fit");
  Json doc = {{"command", "identify"}, {"design", design.name}, {"rig", mechanism_rig ? "mechanism" : "motor"}, {"log", a.logs.front()},
              {"logs", a.logs}, {"closed_loop", a.closed_loop}};
  if (val) doc["validation"] = a.validation;
  doc["method"] = a.method == "oe" ? "output error" : a.closed_loop ? "IDIM-IV" : "IDIM-LS";
  doc["joints"] = Json::array();
  for (const auto& r : results) doc["joints"].push_back(id::to_json(r));
  doc["refused"] = refused;
  py::dict d;
  py::list joints;
  for (const auto& r : results) joints.append(joint_dict(r));
  d["joints"] = joints;
  d["refused"] = py::cast(refused);
  d["design"] = py::none();
  d["gate_passed"] = false;
  d["gate_reasons"] = py::list();
  d["patched"] = py::list();
  d["not_patched"] = py::list();
  if (refused.empty()) {
    MeasurementSource source;
    source.file = absolute_source(a.logs.front());
    source.sha256 = sha256_file(a.logs.front());
    source.date = today_utc();
    source.method = std::string(mechanism_rig ? "fivebar identify --rig mechanism: " : "fivebar identify --rig motor: ") +
                    (a.method == "oe"   ? "output-error refinement (Ceres)"
                     : a.closed_loop    ? "inverse dynamic model by instrumental variables under the design's PID (IDIM-IV)"
                                        : "inverse dynamic model by least squares (IDIM-LS)") +
                    ", standard deviation";
    for (std::size_t i = 1; i < a.logs.size(); ++i) source.method += "; with " + absolute_source(a.logs[i]) + " (sha256 " + sha256_file(a.logs[i]) + ")";
    id::Patch patch = id::patch_design(design, results, source, a.method == "oe");
    if (patch.design) patch.design->reset<BenchSettings>();
    doc["gate"] = gate::to_json(patch.gate);
    doc["patched"] = patch.patched;
    doc["not_patched"] = patch.not_patched;
    d["gate_passed"] = patch.gate.passed;
    d["gate_reasons"] = py::cast(patch.gate.refusal_lines());
    d["patched"] = py::cast(patch.patched);
    d["not_patched"] = py::cast(patch.not_patched);
    if (patch.design) d["design"] = std::make_shared<Design>(std::move(*patch.design));
  }
  d["summary"] = to_python(doc);
  return d;
}

// --- Parts ----------------------------------------------------------------------------------------

py::list parts(const Design& design, const std::optional<std::string>& station, const std::optional<int>& fn) {
  PartsOptions options;
  options.station = station;
  options.fn = fn;
  options.render = false;
  py::list out;
  for (const PartSpec& p : plan_parts(design, options)) {
    py::dict d;
    d["station"] = p.station;
    d["name"] = p.name;
    d["kind"] = std::string(to_string(p.kind));
    d["uses"] = py::cast(p.uses);
    py::list mechanisms;  // "lower+upper" as the CLI's JSON lists it; "-" (none) as []
    std::string rest = p.mechanisms == "-" ? std::string() : p.mechanisms;
    while (!rest.empty()) {
      const std::size_t plus = rest.find('+');
      mechanisms.append(rest.substr(0, plus));
      rest = plus == std::string::npos ? std::string() : rest.substr(plus + 1);
    }
    d["mechanisms"] = mechanisms;
    d["count"] = p.count;
    const bool link = p.kind == PartKind::proximal_link || p.kind == PartKind::distal_link;
    d["length_mm"] = link ? py::object(py::float_(p.length_mm)) : py::object(py::none());
    d["height_mm"] = p.height_mm ? py::object(py::float_(*p.height_mm)) : py::object(py::none());
    d["scad"] = p.scad;
    out.append(d);
  }
  return out;
}

}  // namespace

void register_bench(py::module_& m) {
  m.def("_calibrate",
        [](const Design& d, const std::string& path, const std::string& station, const std::string& mechanism,
           const std::string& frame, const std::vector<std::string>& fit, const std::string& loss, double loss_scale,
           std::optional<double> sigma_mm, int holdout) {
          CalibrateArgs a{station, mechanism, frame, loss, fit, loss_scale, sigma_mm, holdout};
          return calibrate_fit(d, path, a);
        });
  m.def("_calibrate_hard_stops", &calibrate_hard_stops, py::arg("design"), py::arg("log"));
  m.def("_calibration_plan", &calibration_plan, py::arg("design"), py::arg("poses"), py::arg("station"),
        py::arg("mechanism"), py::arg("sigma_mm"), py::arg("criterion"), py::arg("seed"));
  m.def("_identify",
        [](const Design& d, const std::vector<std::string>& logs, const std::string& rig, const std::string& validation,
           const std::string& joint,
           const std::string& method, bool closed_loop, bool output_error, bool per_direction, bool instant_drive,
           std::optional<double> cutoff_hz, std::optional<int> decimation, int filter_order, double load_inertia,
           const std::vector<std::string>& fit) {
          std::string rig_station, rig_mechanism;
          if (!rig.empty() && rig != "motor") {
            const std::size_t slash = rig.find('/');
            if (slash == std::string::npos || slash == 0 || slash + 1 == rig.size() || rig.find('/', slash + 1) != std::string::npos) {
              throw InputError("rig = '" + rig + "': \"motor\" or STATION/MECHANISM (e.g. \"index/lower\")");
            }
            rig_station = rig.substr(0, slash);
            rig_mechanism = rig.substr(slash + 1);
          }
          IdentifyArgs a{logs, rig_station, rig_mechanism, validation, joint, method, closed_loop, output_error,
                         per_direction, instant_drive, cutoff_hz, decimation, filter_order, load_inertia, fit};
          return identify_fit(d, a);
        });
  m.def("_parts", &parts, py::arg("design"), py::arg("station"), py::arg("fn"));
}

}  // namespace fivebar::python
