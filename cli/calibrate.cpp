// fivebar calibrate: kinematic calibration of a station's mechanisms from bench measurements, the
// poses to measure (--plan) and the potentiometers from the hard stops (--hard-stops)
// (fivebar/calibrate.hpp, docs/calibrate.md).

#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "common.hpp"
#include "fivebar/calibrate.hpp"
#include "fivebar/csv_reader.hpp"
#include "fivebar/provenance.hpp"  // today_utc(), recorded_source()
#include "fivebar/provenance/gate.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/io.hpp"
#include "fivebar/sections/bench.hpp"
#include "fivebar/sha256.hpp"

namespace fivebar::cli {

namespace {

struct CalibrateCliOptions {
  std::string design;
  std::string measurements;
  std::string station;
  std::string mechanism;
  std::string frame = "fixed";
  int holdout = 0;
  std::string loss = "none";
  double loss_scale = 2.0;
  std::optional<double> sigma_mm;
  std::vector<std::string> fit;
  std::optional<int> plan;
  double plan_sigma_mm = 0.02;
  std::string plan_criterion = "i";
  std::uint64_t seed = 1;
  std::string hard_stops;
  bool json = false;
  std::string out;
};


std::string read_text(const std::string& path, const char* what) {
  // Bounded while reading (fivebar/csv_reader.hpp): /dev/zero is refused, not read whole.
  return csv::read_bounded(path, calibrate::kMeasurementLimits.max_bytes, what);
}

void print_result(const calibrate::CalibrationResult& r) {
  std::cout << "station " << r.station << " (" << format::join(r.mechanisms) << "): " << r.poses << " poses fitted";
  if (r.holdout_poses > 0) std::cout << ", " << r.holdout_poses << " held out";
  std::cout << "\n";
  for (const calibrate::Parameter& p : r.parameters) {
    std::cout << "  " << p.key << " = " << fixed(p.value, 6) << " " << p.unit;
    if (p.identified) std::cout << " +- " << fixed(p.sigma, 6);
    else if (!p.note.empty()) std::cout << "  (" << p.note << ")";
    std::cout << "  [design " << format::shortest(p.design) << "]\n";
  }
  if (r.poses > 0) {
    std::cout << "residuals: before RMS " << fixed(r.before.rms_mm, 4) << " mm (max " << fixed(r.before.max_mm, 4) << "), after RMS "
              << fixed(r.after.rms_mm, 4) << " mm (max " << fixed(r.after.max_mm, 4) << ")";
    if (r.holdout_poses > 0) std::cout << "; held out: RMS " << fixed(r.holdout_after.rms_mm, 4) << " mm (max " << fixed(r.holdout_after.max_mm, 4) << ")";
    std::cout << "\nmeasurement sigma " << fixed(r.sigma_mm, 4) << " mm (" << (r.sigma_estimated ? "from the residuals" : "given")
              << "); condition number " << fixed(r.condition_number, 1) << ", observability index O1 " << fixed(r.observability_index, 4)
              << "\n";
  }
  for (const calibrate::Unidentifiable& u : r.unidentifiable) {
    std::cout << "not identifiable: " << u.parameter << " " << u.combination << "\n";
  }
  for (const calibrate::ExcludedPose& e : r.skipped) std::cout << "skipped: line " << e.line << " (" << e.mechanism << "): " << e.reason << "\n";
  for (const calibrate::ExcludedPose& e : r.outliers) {
    std::cout << "outlier: line " << e.line << " (" << e.mechanism << "): " << e.reason << ": left out of the final fit\n";
  }
  std::cout << gate::to_text(r.gate);
}

int run_calibrate(const CalibrateCliOptions& opt) {
  const Design design = load(opt.design);
  if (opt.frame != "fixed" && opt.frame != "fit") throw InputError("--frame = '" + opt.frame + "': must be fixed or fit");
  if (opt.loss != "none" && opt.loss != "huber" && opt.loss != "cauchy") throw InputError("--loss = '" + opt.loss + "': must be none, huber or cauchy");
  // A sigma or scale is a positive finite number, named with its flag and value (docs/reliability.md).
  const auto positive = [](const char* flag, double v, const char* unit) {
    if (!(v > 0.0) || !std::isfinite(v) || v > csv::kMaxBenchValue) {
      throw InputError(std::string(flag) + " = " + format::shortest(v) + ": must be a finite number > 0 and at most 1e9 (" + unit + ")");
    }
  };
  positive("--loss-scale", opt.loss_scale, "measurement sigmas");
  if (opt.sigma_mm) positive("--sigma", *opt.sigma_mm, "mm");
  if (opt.plan) positive("--plan-sigma", opt.plan_sigma_mm, "mm");
  const bool fitting = !opt.measurements.empty();
  if (!fitting && !opt.plan && opt.hard_stops.empty()) {
    throw InputError("give a measurement file (MEAS.csv), --plan N or --hard-stops LOG");
  }
  if (fitting && !opt.hard_stops.empty()) throw InputError("--hard-stops replaces the measurement file: give one of them");
  Json doc = {{"command", "calibrate"}, {"design", design.name}};
  std::vector<std::pair<std::string, std::string>> files;  // name -> content, written after every check
  int code = kOk;
  std::optional<Design> patched;
  calibrate::Source source;
  source.date = today_utc();

  if (opt.plan) {
    calibrate::PlanOptions po;
    po.poses = *opt.plan;
    po.sigma_mm = opt.plan_sigma_mm;
    if (opt.plan_criterion != "i" && opt.plan_criterion != "d") throw InputError("--plan-criterion = '" + opt.plan_criterion + "': must be i or d");
    po.criterion = opt.plan_criterion == "d" ? calibrate::PlanCriterion::d_optimal : calibrate::PlanCriterion::i_optimal;
    po.seed = opt.seed;
    std::string station = opt.station;
    if (station.empty()) {
      const auto st = design.select_stations("");
      if (st.size() != 1) throw InputError("--plan: choose a station with --station (the design has several)");
      station = st.front()->name;
    }
    const auto plans = calibrate::plan_poses(design, station, opt.mechanism, po);
    doc["plan"] = calibrate::to_json(plans, po);
    files.emplace_back("calibration-plan.csv", calibrate::plan_csv(plans));
    for (const auto& p : plans) {
      if (!p.problem.empty()) code = kCheckFailed;
      if (opt.json) continue;
      std::cout << "plan " << p.station << "/" << p.mechanism << ": ";
      if (!p.problem.empty()) {
        std::cout << "none: " << p.problem << "\n";
        continue;
      }
      std::cout << p.poses.size() << " poses of " << p.candidates << " candidates, observability index " << fixed(p.observability_index, 4)
                << " (median of " << po.random_trials << " random sets of as many: " << fixed(p.random_observability_index, 4) << ")\n"
                << "  predicted RMS tactor error over the target (" << p.target_points << " points, "
                << (po.criterion == calibrate::PlanCriterion::i_optimal ? "I-optimal" : "D-optimal") << ", linearised): "
                << fixed(p.predicted_target_error_mm * 1e3, 2) << " um (random sets: " << fixed(p.random_target_error_mm * 1e3, 2) << " um)\n"
                << "  expected posterior sigma at " << fixed(po.sigma_mm, 4) << " mm per axis (planned / random median):\n";
      for (std::size_t k = 0; k < p.names.size(); ++k) {
        std::cout << "    " << p.names[k] << ": " << fixed(p.expected_sigma[k], 5) << " / " << fixed(p.random_sigma[k], 5) << "\n";
      }
    }
    if (opt.out.empty() && !opt.json) std::cout << calibrate::plan_csv(plans);
  }

  if (!opt.hard_stops.empty()) {
    const std::string text = read_text(opt.hard_stops, "hard-stop readings");
    const calibrate::CalibrationResult r = calibrate::hard_stop_calibration(design, text, opt.hard_stops);
    // Recorded relative to the folder the patched design is written in (checked from there).
    source.file = opt.out.empty() ? opt.hard_stops : recorded_source(opt.hard_stops, opt.out);
    source.sha256 = sha256_hex(text);
    doc["hard_stops"] = calibrate::to_json(r);
    if (!opt.json) print_result(r);
    if (!r.gate.passed) {
      code = kCheckFailed;
      std::cerr << "fivebar calibrate: the hard-stop calibration did not pass the quality gate (reasons above): nothing written\n";
    } else {
      patched = calibrate::with_provenance(calibrate::patched_design(design, r), r, source);
    }
  }

  if (fitting) {
    const std::string text = read_text(opt.measurements, "measurement file");
    const auto rows = calibrate::parse_measurements(text, opt.measurements, design);
    calibrate::CalibrateOptions co;
    co.station = opt.station;
    if (!opt.mechanism.empty()) co.mechanisms = {opt.mechanism};
    co.fit_frame = opt.frame == "fit";
    co.fit = opt.fit;
    co.fit_given = !opt.fit.empty();
    co.loss = opt.loss == "huber" ? calibrate::Loss::huber : opt.loss == "cauchy" ? calibrate::Loss::cauchy : calibrate::Loss::none;
    co.loss_scale = opt.loss_scale;
    co.sigma_mm = opt.sigma_mm;
    co.holdout = opt.holdout;
    const calibrate::CalibrationResult r = calibrate::calibrate(design, rows, co, opt.measurements);
    source.file = opt.out.empty() ? opt.measurements : recorded_source(opt.measurements, opt.out);
    source.sha256 = sha256_hex(text);
    doc["calibration"] = calibrate::to_json(r);
    if (!opt.json) print_result(r);
    if (r.requested_unidentifiable) {
      code = kCheckFailed;
      std::cerr << "fivebar calibrate: the poses cannot identify parameters asked for with --fit (listed above): nothing written\n";
    } else if (!r.gate.passed) {
      code = kCheckFailed;
      std::cerr << "fivebar calibrate: the fit did not pass the quality gate: nothing written\n";
      for (const std::string& line : r.gate.refusal_lines()) std::cerr << "  " << line << "\n";
    } else {
      patched = calibrate::with_provenance(calibrate::patched_design(design, r), r, source);
      files.emplace_back("calibration-summary.md", calibrate::report_markdown(r, source));
    }
  }
  if (patched) {
    patched->reset<BenchSettings>();  // written elsewhere: its bench: files would not resolve
    files.emplace_back(design.name + "-calibrated.yaml", to_yaml(*patched));
  }

  Json written = Json::array();
  if (!opt.out.empty() && code == kOk) {
    const std::filesystem::path dir(opt.out);
    make_directories(dir);
    WriteFence fence(dir);
    for (const auto& [name, content] : files) {
      write_file_atomic(dir / name, content);
      written.push_back((dir / name).generic_string());
    }
    if (!opt.json) std::cout << "wrote " << files.size() << " files into " << dir.generic_string() << "\n";
  }
  doc["files"] = written;
  if (opt.json) print_json(doc);
  return code;
}

}  // namespace

void setup_calibrate(CLI::App& app) {
  auto [sub, opt] = add_command<CalibrateCliOptions>(
      app, "calibrate",
      "Kinematic calibration from bench measurements: link lengths, base joints and potentiometer calibration of each "
      "mechanism by nonlinear least squares (Ceres), with posterior sigmas, identifiability (singular values, condition "
      "number, observability index, the parameters the poses cannot separate), residuals and a held-out check; --plan N "
      "chooses the poses to measure, --hard-stops the potentiometer offsets from readings at the hard stops",
      run_calibrate);
  add_design_argument(*sub, opt->design);
  sub->add_option("MEAS", opt->measurements,
                  "Measurements (CSV): station,mechanism,volts1,volts2,x_mm,y_mm[,sigma_mm] or counts1,counts2 instead of volts")
      ->type_name("FILE");
  add_station_option(*sub, opt->station, "the one the measurements name");
  sub->add_option("-m,--mechanism", opt->mechanism, "Only this mechanism: lower or upper")->type_name("NAME");
  sub->add_option("--frame", opt->frame, "fixed: the instrument measures in the station frame; fit: fit its planar pose too")
      ->capture_default_str();
  sub->add_option("--fit", opt->fit,
                  "Parameters to fit (default: all): L1..L4, O1x, O1y, O2x, O2y (O2 - O1), theta1.volts_at_zero, "
                  "theta1.rad_per_volt, theta2..., frame.rotation, frame.x, frame.y; naming one the poses cannot "
                  "identify exits 1")
      ->delimiter(',')
      ->type_name("LIST");
  sub->add_option("--holdout", opt->holdout, "Leave K poses (evenly spaced) out of the fit and report their error")->type_name("K");
  sub->add_option("--loss", opt->loss, "Robust loss: none, huber or cauchy")->capture_default_str();
  sub->add_option("--loss-scale", opt->loss_scale, "Scale of the robust loss, in measurement sigmas")->capture_default_str();
  sub->add_option("--sigma", opt->sigma_mm, "Measurement sigma per axis (mm) for every row; default: the sigma_mm column, "
                                             "else estimated from the residuals")
      ->type_name("MM");
  sub->add_option("--plan", opt->plan, "Choose N poses per mechanism to measure (calibration-plan.csv)")->type_name("N");
  sub->add_option("--plan-criterion", opt->plan_criterion,
                  "What the plan optimises: i (the predicted tactor error over the target, I-optimal) or d (det of the "
                  "parameters' information, D-optimal)")
      ->capture_default_str();
  sub->add_option("--plan-sigma", opt->plan_sigma_mm, "Measurement sigma the plan's expected sigmas assume (mm)")->capture_default_str();
  sub->add_option("--seed", opt->seed, "Seed of the plan's random comparison sets")->capture_default_str();
  sub->add_option("--hard-stops", opt->hard_stops, "Potentiometer calibration from readings at the hard stops (CSV "
                                                   "station,mechanism,joint,stop,volts)")
      ->type_name("LOG");
  add_json_flag(*sub, opt->json);
  // Without --out nothing is written (docs/calibrate.md): not add_out_option(), which names a default folder.
  sub->add_option("-o,--out", opt->out,
                  "Write the patched design (<design>-calibrated.yaml, with provenance: entries), calibration-summary.md and "
                  "calibration-plan.csv here; default: write nothing")
      ->type_name("DIR");
  sub->footer(
      "Model, identifiability and the bench walk-through: docs/calibrate.md.\n" +
      exit_status({.ok = "fitted",
                   .failed = "the fit did not pass the quality gate (not converged, residuals the noise does not explain, a sigma "
                             "above its prior: reasons per parameter), a parameter named with --fit is not identifiable or no "
                             "plan exists (nothing written)"}));
}

}  // namespace fivebar::cli
