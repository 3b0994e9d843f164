// fivebar identify: the motor, friction and inertia of a joint from bench logs (IDIM-LS, then an
// output-error refinement), with the fit on a validation log; or, with --plan, the excitation to log
// (fivebar/identify.hpp, docs/identify.md).

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "common.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/resources/estimates.hpp"
#include "fivebar/identify.hpp"
#include "fivebar/io.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/provenance/gate.hpp"
#include "fivebar/sha256.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/sections/bench.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/motor.hpp"

namespace fivebar::cli {

namespace {

namespace id = fivebar::identify;

/// `value` to 5 significant digits, in its shortest text.
std::string sig(double value) {
  return format::shortest(std::strtod(format::general(value, 5).c_str(), nullptr));
}

struct IdentifyCliOptions {
  std::string design;
  std::vector<std::string> logs;  ///< estimation logs, fitted together
  std::string log;                ///< the first
  std::string validation;
  bool closed_loop = false;
  std::vector<std::string> rig{"motor"};  ///< motor, or mechanism STATION/MECHANISM
  std::string joint;
  std::string out;
  std::vector<std::string> fit;
  double load_inertia = 0.0;
  std::optional<double> cutoff_hz;  ///< given: > 0 (never replaced by the default)
  int filter_order = 4;
  std::optional<int> decimation;  ///< given: >= 1
  bool per_direction = false;
  bool instant_drive = false;
  bool keep_reversals = false;
  bool no_output_error = false;
  std::string method = "idim";
  bool json = false;
  bool no_files = false;
  bool plan = false;
  double plan_duration_s = 10.0;
  std::vector<double> plan_band_hz{0.2, 5.0};
  std::vector<double> range_deg;
  double drive_noise_mNm = 1.0;
  bool yes = false;
};

/// The priors of a joint (fivebar/identify/model.hpp joint_prior()).
id::JointPrior prior_of(const Design& design, const std::string& station, const std::string& mechanism, int joint,
                        double load_inertia, bool need_motor) {
  return id::joint_prior(design, station, mechanism, joint, load_inertia, need_motor);
}

void print_estimate_table(const id::JointIdentification& r) {
  std::cout << "  parameters (" << r.method << " unless noted):\n";
  for (const id::Parameter& p : r.parameters) {
    std::cout << "    " << p.key << " = " << sig(p.value);
    if (p.identified) {
      std::cout << " +- " << sig(p.sigma);
      if (p.value != 0.0) std::cout << " (" << fixed(100.0 * p.sigma / std::abs(p.value), 2) << " %)";
    } else {
      std::cout << " HELD";
    }
    if (!p.note.empty() && !(p.identified && p.note == r.method)) std::cout << "  [" << p.note << "]";
    std::cout << "\n";
  }
}

std::string fit_text(const id::Fit& f, bool chain = false) {
  std::string s = "drive fit " + fixed(f.drive_fit_percent, 1) + " % (relative error " + fixed(f.drive_relative_error_percent, 2) + " %)";
  s += f.simulated ? ", position fit " + fixed(f.position_fit_percent, 1) + " % (relative error " +
                         fixed(f.position_relative_error_percent, 2) + " %)"
                   : chain ? ", no position fit (a joint of a closed chain is not simulated alone)"
                           : ", open-loop simulation diverged";
  return s;
}

void print_joint(const id::JointIdentification& r) {
  std::cout << "joint " << r.joint << ": drive " << r.drive_column << ", reading " << r.reading_column << ", "
            << format::shortest(1.0 / r.sample_time) << " Hz, low-pass " << format::shortest(r.cutoff_hz)
            << " Hz (Butterworth, zero phase), decimation " << r.decimation << ", " << r.idim.rows << " rows";
  if (r.reversal_samples > 0) {
    std::cout << " (" << r.reversal_rows << " within " << r.reversal_samples << " samples of a reversal left out)";
  }
  std::cout << "\n";
  print_estimate_table(r);
  if (!r.unidentifiable.empty()) {
    std::cout << "  not identifiable from this log (held at the prior): " << format::join(r.unidentifiable) << "\n";
  }
  const id::Estimate& inv = r.iv ? *r.iv : r.idim;
  std::cout << "  correlation (" << (r.iv ? "IDIM-IV" : "IDIM-LS") << "):\n";
  for (Eigen::Index a = 0; a < inv.correlation.rows(); ++a) {
    std::cout << "    " << inv.names[static_cast<std::size_t>(a)] << ":";
    for (Eigen::Index b = 0; b < inv.correlation.cols(); ++b) std::cout << " " << fixed(inv.correlation(a, b), 3);
    std::cout << "\n";
  }
  if (r.method == "IDIM-IV") {
    std::cout << "  closed loop: IDIM-IV " << r.iv_status << "; IDIM-LS (biased under feedback) gave";
    for (std::size_t i = 0; i < r.idim.names.size(); ++i) {
      const auto k = static_cast<Eigen::Index>(i);
      if (r.idim.identified[i]) std::cout << " " << r.idim.names[i] << " = " << sig(r.idim.value[k]) << " +- " << sig(r.idim.sigma[k]);
    }
    std::cout << "\n";
  }
  std::cout << "  output error: " << r.output_error_status;
  if (r.output_error) {
    std::cout << " (sigmas assume white output noise: optimistic for an open-loop drift):";
    for (std::size_t i = 0; i < r.output_error->names.size(); ++i) {
      const auto k = static_cast<Eigen::Index>(i);
      std::cout << " " << r.output_error->names[i] << " = " << sig(r.output_error->value[k]);
      if (r.output_error->identified[i]) std::cout << " +- " << sig(r.output_error->sigma[k]);
    }
  }
  std::cout << "\n";
  const bool chain = r.output_error_status.find("closed chain") != std::string::npos;
  const std::string inverse = r.method == "IDIM-IV" ? "IDIM-IV" : "IDIM-LS";
  std::cout << "  estimation log" << (r.logs > 1 ? "s (" + std::to_string(r.logs) + ")" : std::string()) << ": " << inverse << " "
            << fit_text(r.estimation_idim, chain) << "\n";
  if (r.output_error) std::cout << "                  output error " << fit_text(r.estimation_oe) << "\n";
  if (r.validation_idim) {
    std::cout << "  validation log: " << inverse << " " << fit_text(*r.validation_idim) << "\n";
    if (r.validation_oe) std::cout << "                  output error " << fit_text(*r.validation_oe) << "\n";
  }
}

int run_plan(const IdentifyCliOptions& opt, const Design& design) {
  std::string station, mechanism;
  int joint = 0;
  if (!opt.joint.empty()) {
    const std::size_t a = opt.joint.find('/'), b = opt.joint.rfind('/');
    if (a == std::string::npos || a == b || opt.joint.compare(b + 1, 5, "theta") != 0 || opt.joint.size() != b + 7 ||
        (opt.joint.back() != '1' && opt.joint.back() != '2')) {
      throw InputError("--joint '" + opt.joint + "': expected STATION/MECHANISM/theta1 or theta2");
    }
    station = opt.joint.substr(0, a);
    mechanism = opt.joint.substr(a + 1, b - a - 1);
    joint = opt.joint.back() - '0';
  }
  const id::JointPrior prior = prior_of(design, station, mechanism, joint, opt.load_inertia, true);
  id::PlanOptions po;
  po.duration_s = opt.plan_duration_s;
  if (opt.plan_band_hz.size() != 2) throw InputError("--plan-band: expected F_MIN,F_MAX in Hz");
  po.f_min_hz = opt.plan_band_hz[0];
  po.f_max_hz = opt.plan_band_hz[1];
  po.current_limit = prior.motor.current_limit_A;
  po.per_direction = opt.per_direction;
  if (!(opt.drive_noise_mNm > 0.0) || !std::isfinite(opt.drive_noise_mNm)) {
    throw InputError("--drive-noise = " + format::shortest(opt.drive_noise_mNm) + ": must be a finite number > 0 (mNm)");
  }
  po.drive_noise = opt.drive_noise_mNm * 1e-3;
  // The potentiometer read through the ADC (controller.potentiometer, adc_bits, adc_range_v).
  po.angle_quantum = std::abs(prior.rad_per_volt) * (prior.adc_hi_v - prior.adc_lo_v) / std::ldexp(1.0, prior.adc_bits);
  const ControllerSettings* cs = design.get<ControllerSettings>();
  if (cs) po.max_speed = cs->max_velocity;
  std::string range_source;
  if (!opt.range_deg.empty()) {
    if (opt.range_deg.size() != 2 || !(opt.range_deg[1] > opt.range_deg[0])) throw InputError("--range-deg: expected LO,HI with LO < HI");
    po.range_lo = opt.range_deg[0] * format::kRadPerDeg;
    po.range_hi = opt.range_deg[1] * format::kRadPerDeg;
    range_source = "--range-deg";
  } else if (!station.empty()) {
    const Station& s = design.require_station(station);
    const Mechanism* m = nullptr;
    for (const Mechanism* x : s.mechanisms()) {
      if (x->name == mechanism) m = x;
    }
    if (m == nullptr) throw InputError("--joint: station '" + station + "' has no mechanism '" + mechanism + "'");
    const UsableRange u = usable_ranges(design, s, *m)[static_cast<std::size_t>(joint - 1)];
    if (!u.usable) throw InputError("--joint " + opt.joint + ": no usable range (" + u.problem + ")");
    if (!u.limited) throw InputError("--joint " + opt.joint + ": the joint has no limit; give --range-deg");
    po.range_lo = u.lo + (cs ? cs->joint_margin : 0.0);
    po.range_hi = u.hi - (cs ? cs->joint_margin : 0.0);
    range_source = "usable range of " + u.joint + " less the controller's joint margin";
  } else {
    // A bench motor: the default potentiometer's 300 deg travel (controller.potentiometer), centred.
    po.range_lo = -150.0 * format::kRadPerDeg;
    po.range_hi = 150.0 * format::kRadPerDeg;
    range_source = "the potentiometer's 300 deg travel, centred (give --range-deg for another)";
  }
  const id::ExcitationPlan plan = id::plan_excitation(prior, po);
  Json doc = {{"command", "identify"}, {"design", design.name}, {"plan", Json::object()}};
  Json& jp = doc["plan"];
  jp["samples"] = plan.time.size();
  jp["duration_s"] = plan.time.back();
  jp["band_hz"] = {po.f_min_hz, po.f_max_hz};
  jp["range_deg"] = {po.range_lo * format::kDegPerRad, po.range_hi * format::kDegPerRad};
  jp["range_source"] = range_source;
  jp["limited_by"] = plan.limited_by;
  jp["crest_factor"] = plan.crest_factor;
  jp["drive_noise_mNm"] = opt.drive_noise_mNm;
  jp["angle_quantum_deg"] = po.angle_quantum * format::kDegPerRad;
  jp["fade_s"] = plan.fade_s;
  jp["edge_samples"] = plan.edge_samples;
  jp["expected_residual_mNm"] = plan.expected_residual * 1e3;
  jp["quantisation_share"] = plan.quantisation_share;
  jp["expected"] = Json::array();
  for (std::size_t i = 0; i < plan.names.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    jp["expected"].push_back({{"parameter", plan.names[i]}, {"prior", plan.truth[k]}, {"sigma", plan.expected_sigma[k]}});
  }
  std::vector<std::string> files;
  if (!opt.no_files) {
    const std::filesystem::path dir =
        command_output_dir(opt.out, design.name, "identify");
    make_directories(dir);
    WriteFence fence(dir);
    std::ostringstream csv;
    csv << "time_s,theta_deg,current_A,duty\n";
    for (std::size_t i = 0; i < plan.time.size(); ++i) {
      csv << exact(plan.time[i]) << "," << exact(plan.position[i] * format::kDegPerRad) << "," << exact(plan.current[i])
          << "," << exact(plan.duty[i]) << "\n";
    }
    const std::filesystem::path f = dir / "identify-plan.csv";
    write_file_atomic(f, csv.str());
    files.push_back(f.generic_string());
  }
  doc["files"] = files;
  if (opt.json) {
    print_json(doc);
    return kOk;
  }
  std::cout << "excitation: multisine, Schroeder phases, " << format::shortest(po.f_min_hz) << " ... " << format::shortest(po.f_max_hz)
            << " Hz, " << format::shortest(plan.time.back()) << " s, fading in and out over " << format::shortest(plan.fade_s)
            << " s; range " << fixed(po.range_lo * format::kDegPerRad, 1)
            << " ... " << fixed(po.range_hi * format::kDegPerRad, 1) << " deg (" << range_source << "), limited by the "
            << plan.limited_by << " (90 % of each limit)\n";
  std::cout << "expected sigmas (IDIM-LS, decimation 10, " << plan.edge_samples << " samples left out at each end; residual "
            << sig(plan.expected_residual * 1e3) << " mNm from the drive noise " << format::shortest(opt.drive_noise_mNm)
            << " mNm and the reading's quantum " << sig(po.angle_quantum * format::kDegPerRad) << " deg, "
            << fixed(100.0 * plan.quantisation_share, 0) << " % of its variance):\n";
  for (std::size_t i = 0; i < plan.names.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    std::cout << "  " << plan.names[i] << ": prior " << sig(plan.truth[k]) << ", sigma " << sig(plan.expected_sigma[k]) << "\n";
  }
  for (const std::string& f : files) std::cout << "wrote " << f << "\n";
  return kOk;
}

/// Where the identified values come from: the log, its hash, today, the method.
/// `folder`: where the patched design is written; the log is recorded relative to it.
MeasurementSource log_source(const IdentifyCliOptions& opt, bool mechanism_rig, const std::filesystem::path& folder) {
  MeasurementSource source;
  source.file = recorded_source(opt.log, folder);
  source.sha256 = sha256_file(opt.log);
  source.date = today_utc();
  source.method = std::string(mechanism_rig ? "fivebar identify --rig mechanism: " : "fivebar identify --rig motor: ") +
                  (opt.method == "oe"    ? "output-error refinement (Ceres)"
                   : opt.closed_loop    ? "inverse dynamic model by instrumental variables under the design's PID (IDIM-IV)"
                                        : "inverse dynamic model by least squares (IDIM-LS)") +
                  ", standard deviation";
  // Several logs: the entry's source is the first (its hash is checked); the others are named with theirs.
  for (std::size_t i = 1; i < opt.logs.size(); ++i) source.method += "; with " + recorded_source(opt.logs[i], folder) + " (sha256 " + sha256_file(opt.logs[i]) + ")";
  return source;
}

/// The quality gate's verdict and tests, then the values it or the motor: section refused, a line each.
void print_patch(const id::Patch& patch) {
  std::size_t passed = 0;
  for (const gate::ParameterVerdict& v : patch.gate.parameters) passed += v.passed ? 1 : 0;
  const std::string verdict = !patch.gate.reasons.empty() ? "refused, nothing patched"
                              : patch.gate.passed         ? "passed"
                                                          : "passed for " + std::to_string(passed) + " of " +
                                                                std::to_string(patch.gate.parameters.size()) + " values";
  std::cout << "quality gate: " << verdict << " (solver " << patch.gate.solver.termination << ")\n";
  for (const gate::ResidualTest& t : patch.gate.tests) std::cout << "  " << t.statement << "\n";
  for (const std::string& s : patch.not_patched) std::cout << "not patched: " << s << "\n";
}

/// Each joint of the logs (or the one --joint names), its logs fitted together, open or closed loop.
std::vector<id::JointIdentification> identify_joints(const IdentifyCliOptions& opt, const Design& design,
                                                     const std::vector<id::IdentifyLog>& logs,
                                                     const std::optional<id::IdentifyLog>& val, const id::IdentifyOptions& o) {
  return id::identify_motor_rig(design, {&logs, opt.logs, val ? &*val : nullptr, opt.validation, opt.joint, opt.load_inertia, opt.closed_loop}, o);
}

int run_identify(const IdentifyCliOptions& given) {
  IdentifyCliOptions opt = given;
  if (!opt.logs.empty()) opt.log = opt.logs.front();
  const Design design = load(opt.design);
  // --rig motor, or --rig mechanism STATION/MECHANISM (fivebar/identify/mechanism.hpp).
  std::string rig_station, rig_mechanism;
  const std::string rig = opt.rig.empty() ? "motor" : opt.rig.front();
  if (rig == "mechanism") {
    const std::string sm = opt.rig.size() == 2 ? opt.rig[1] : "";
    const std::size_t slash = sm.find('/');
    if (slash == std::string::npos || slash == 0 || slash + 1 == sm.size() || sm.find('/', slash + 1) != std::string::npos) {
      throw InputError("--rig mechanism: expected STATION/MECHANISM after it (e.g. --rig mechanism index/lower)");
    }
    rig_station = sm.substr(0, slash);
    rig_mechanism = sm.substr(slash + 1);
    if (opt.plan) throw InputError("--plan: plans one joint (--joint STATION/MECHANISM/thetaJ), not --rig mechanism");
    if (!opt.validation.empty()) throw InputError("--validation: not with --rig mechanism yet");
    if (opt.method == "oe") throw InputError("--method oe: not with --rig mechanism (a joint of a closed chain is not simulated alone)");
  } else if (rig != "motor" || opt.rig.size() != 1) {
    throw InputError("--rig: motor, or mechanism STATION/MECHANISM");
  }
  // A flag given is used or refused, never replaced by its default (docs/reliability.md).
  if (opt.cutoff_hz && (!(*opt.cutoff_hz > 0.0) || !std::isfinite(*opt.cutoff_hz))) {
    throw InputError("--cutoff = " + format::shortest(*opt.cutoff_hz) + ": must be a finite number > 0 Hz (leave it out for a tenth of the sample rate)");
  }
  if (opt.decimation && *opt.decimation < 1) {
    throw InputError("--decimation = " + std::to_string(*opt.decimation) + ": must be a whole number >= 1 (leave it out for 10)");
  }
  if (opt.plan) return run_plan(opt, design);
  if (opt.log.empty()) throw InputError("LOG: an identification log is required (or --plan)");
  std::vector<id::IdentifyLog> logs;
  for (const std::string& f : opt.logs) logs.push_back(id::read_identify_log(std::filesystem::path(f)));
  const id::IdentifyLog& est = logs.front();
  std::optional<id::IdentifyLog> val;
  if (!opt.validation.empty()) val = id::read_identify_log(std::filesystem::path(opt.validation));
  for (const id::IdentifyLog& l : logs) id::require_log_joints_in(design, l);
  if (val) id::require_log_joints_in(design, *val);
  // The study's memory and time from the logs' size, before the work (docs/reliability.md).
  std::size_t rows = val ? val->time.size() : 0;
  for (const id::IdentifyLog& l : logs) rows += l.time.size();
  check_budget(identify_estimate(rows, est.joints.size()), opt.yes, "confirm with fivebar identify --yes");
  if (!(opt.load_inertia >= 0.0) || !std::isfinite(opt.load_inertia)) throw InputError("--load-inertia: must be >= 0 kg m^2");
  if (opt.method != "idim" && opt.method != "oe") throw InputError("--method: idim or oe");
  if (opt.closed_loop && opt.method == "oe") {
    throw InputError("--method oe: not with --closed-loop (an open-loop simulation of a log taken under feedback drifts; IDIM-IV is reported)");
  }
  if (opt.closed_loop && !rig_station.empty()) throw InputError("--closed-loop: with --rig motor only");
  if (logs.size() > 1 && !rig_station.empty()) throw InputError("LOG: --rig mechanism takes one log");
  id::IdentifyOptions o;
  o.cutoff_hz = opt.cutoff_hz.value_or(0.0);  // 0: the library's default
  o.filter_order = opt.filter_order;
  o.decimation = opt.decimation.value_or(0);  // 0: the library's default
  o.per_direction = opt.per_direction;
  o.zero_order_hold = !opt.instant_drive;
  o.skip_reversals = !opt.keep_reversals;
  o.output_error = !opt.no_output_error;
  o.use_output_error = opt.method == "oe";
  if (o.use_output_error && !o.output_error) throw InputError("--method oe: needs the output-error refinement (drop --no-output-error)");
  o.require = opt.fit;

  // Identify every joint (or the one --joint names) before writing anything.
  std::vector<id::JointIdentification> results =
      rig_station.empty() ? identify_joints(opt, design, logs, val, o) : id::identify_mechanism(design, est, rig_station, rig_mechanism, o);
  if (results.empty()) throw InputError("--joint '" + opt.joint + "': the log has no such joint");
  // Requested parameters that the logs cannot give.
  const std::vector<std::string> refused = id::refused_fits(results, o, "--fit");
  Json doc = {{"command", "identify"}, {"design", design.name}, {"rig", rig}, {"log", opt.log}, {"logs", opt.logs},
              {"closed_loop", opt.closed_loop}};
  if (val) doc["validation"] = opt.validation;
  doc["method"] = opt.method == "oe" ? "output error" : opt.closed_loop ? "IDIM-IV" : "IDIM-LS";
  doc["joints"] = Json::array();
  for (const auto& r : results) doc["joints"].push_back(id::to_json(r));
  doc["refused"] = refused;
  // The patched design (docs/identify.md "The patched design"), built before anything is written,
  // with the values that passed the quality gate ("The quality gate").
  std::optional<id::Patch> patch;
  if (refused.empty()) {
    patch = id::patch_design(design, results, log_source(opt, !rig_station.empty(), command_output_dir(opt.out, design.name, "identify")),
                             opt.method == "oe");
    if (patch->design) patch->design->reset<BenchSettings>();  // written elsewhere: its bench: files would not resolve
    doc["gate"] = gate::to_json(patch->gate);
    doc["patched"] = patch->patched;
    doc["not_patched"] = patch->not_patched;
  }
  const bool gate_refused = patch && !patch->gate.reasons.empty();
  const Design* patched = patch && patch->design ? &*patch->design : nullptr;
  std::vector<std::string> files;
  if (!opt.no_files) {
    const std::filesystem::path dir =
        command_output_dir(opt.out, design.name, "identify");
    make_directories(dir);
    WriteFence fence(dir);
    if (patched) {
      const std::filesystem::path f = dir / (design.name + "-identified.yaml");
      write_file_atomic(f, to_yaml(*patched));
      files.push_back(f.generic_string());
    }
    for (const auto& r : results) {
      const id::JointIdentification& jr = r;
      for (bool v : {false, true}) {
        if (v && !jr.validation_idim) continue;
        const RenderedPlot plot = id::identify_plot(jr, v);
        const std::string stem = jr.joint + (v ? "-validation" : "-estimation");
        write_file_atomic(dir / (stem + ".svg"), plot.svg);
        write_file_atomic(dir / (stem + ".png"), plot.png);
        files.push_back((dir / (stem + ".svg")).generic_string());
        files.push_back((dir / (stem + ".png")).generic_string());
      }
    }
    doc["files"] = files;
    write_file_atomic(dir / "identify.json", doc.dump(2) + "\n");
    files.push_back((dir / "identify.json").generic_string());
  }
  doc["files"] = files;
  if (opt.json) {
    print_json(doc);
  } else {
    for (const auto& r : results) print_joint(r);
    bool referenced = false;
    for (const id::JointLog& j : est.joints) referenced = referenced || !j.reference.empty();
    if (referenced && !opt.closed_loop) {
      std::cout << "note: the log has a reference column; if it was taken while the PID ran, add --closed-loop "
                   "(IDIM-LS is biased under feedback, docs/identify.md \"Closed loop\")\n";
    }
    for (const std::string& s : refused) std::cout << "NOT IDENTIFIABLE (asked by --fit): " << s << "\n";
    if (patch) print_patch(*patch);
    if (!files.empty()) std::cout << "wrote " << files.size() << " files into " << std::filesystem::path(files.front()).parent_path().generic_string() << "\n";
  }
  if (gate_refused) {
    std::cerr << "fivebar identify: the fit did not pass the quality gate (docs/identify.md \"The quality gate\"): nothing patched\n";
    for (const std::string& r : patch->gate.reasons) std::cerr << "  " << r << "\n";
  }
  return refused.empty() && !gate_refused ? kOk : kCheckFailed;
}

}  // namespace

void setup_identify(CLI::App& app) {
  auto [sub, opt] = add_command<IdentifyCliOptions>(
      app, "identify",
      "Motor, friction and inertia of a joint from bench logs: the inverse dynamic model by least squares on zero-phase "
      "filtered data (IDIM-LS) with its standard deviations and the parameters the log cannot separate, an output-error "
      "refinement by simulation, fit percentages on the estimation and a validation log; or (--plan) the excitation to log",
      run_identify);
  add_design_argument(*sub, opt->design);
  sub->add_option("log", opt->logs, "Estimation logs, fitted together: CSV with time_s and per joint a drive (duty, voltage_V, "
                                    "current_A, torque_Nm or force_N), a reading (volts, counts, theta_rad or position_m), optionally "
                                    "current_A and (--closed-loop) the reference theta_ref_rad")
      ->type_name("LOG.csv ...");
  sub->add_flag("--closed-loop", opt->closed_loop,
                "The logs were taken while the design's PID ran at the log's rate, following the reference column: "
                "instrumental variables (IDIM-IV), unbiased under feedback");
  sub->add_option("--validation", opt->validation, "A second log of the same joints: fit figures only")->type_name("LOG.csv");
  sub->add_option("--rig", opt->rig,
                  "What the log was taken on: motor (one motor on the bench, optional known load), or mechanism "
                  "STATION/MECHANISM (the assembled five-bar: both motors, the closed chain's inertia from the design)")
      ->expected(1, 2)
      ->type_name("motor|mechanism S/M");
  sub->add_option("--joint", opt->joint,
                  "Only this joint of the log (its prefix <station>_<mechanism>_theta<j>, or motor); with --plan "
                  "STATION/MECHANISM/thetaJ: its motor and usable range")
      ->type_name("JOINT");
  sub->add_option("--load-inertia", opt->load_inertia, "Known load inertia at the output shaft (kg m^2)")->type_name("KG_M2");
  sub->add_option("--cutoff", opt->cutoff_hz, "Low-pass cutoff for position and drive (Hz; default a tenth of the sample rate)")
      ->type_name("HZ");
  sub->add_option("--filter-order", opt->filter_order, "Butterworth order (run forward and backward)")->capture_default_str();
  sub->add_option("--decimation", opt->decimation, "Decimation factor (default 10)")->type_name("R");
  sub->add_flag("--per-direction", opt->per_direction, "Viscous friction per direction of motion");
  sub->add_flag("--keep-reversals", opt->keep_reversals,
                "Voltage and duty drives: keep the rows near a reversal of the speed (by default those within the "
                "filters' main lobes of one are left out: the reading stalls in the backlash while the motor turns)");
  sub->add_flag("--instant-drive", opt->instant_drive,
                "The drive column is an instantaneous value at each sample (default: a command held over the sample, "
                "so the regression takes the mean of two consecutive commands)");
  sub->add_option("--fit", opt->fit, "Parameters that must be identified (exit 1 when the log cannot separate one)")
      ->delimiter(',')
      ->type_name("KEY,...");
  sub->add_option("--method", opt->method, "Reported values: idim (IDIM-LS) or oe (output-error refinement)")->capture_default_str();
  sub->add_flag("--no-output-error", opt->no_output_error, "IDIM-LS only");
  sub->add_flag("--plan", opt->plan, "Write an excitation (identify-plan.csv) and the sigmas it is expected to give");
  sub->add_option("--plan-duration", opt->plan_duration_s, "Length of the excitation (s)")->capture_default_str();
  sub->add_option("--plan-band", opt->plan_band_hz, "Lowest and highest harmonic (Hz)")->delimiter(',')->type_name("F_MIN,F_MAX");
  sub->add_option("--range-deg", opt->range_deg, "Joint range for the plan (deg)")->delimiter(',')->type_name("LO,HI");
  sub->add_option("--drive-noise", opt->drive_noise_mNm, "Noise of the logged drive torque the plan's sigmas assume (mNm)")
      ->capture_default_str();
  add_out_option(*sub, opt->out, "the files", "identify");
  sub->add_flag("--no-files", opt->no_files, "Print only");
  sub->add_flag("--yes", opt->yes, "Run an identification estimated at over an hour or two gigabytes of memory (refused otherwise)");
  add_json_flag(*sub, opt->json);
  sub->footer(
      "Parameters are printed with their design key path (motor.terminal_resistance_ohm, in the design's units) or a "
      "rig-only name with its unit (inertia_kg_m2, viscous_Nm_s_per_rad, coulomb_Nm, offset_Nm; a linear axis: mass_kg, "
      "viscous_N_s_per_m, coulomb_N, offset_N). docs/identify.md.\nFiles: <joint>-estimation.svg|.png, "
      "<joint>-validation.svg|.png, identify.json, <design>-identified.yaml (the identified motor keys with provenance: "
      "entries); with --plan identify-plan.csv.\n" +
      exit_status({.ok = "done", .failed = "a parameter named by --fit is not identifiable from the log, or the fit did not pass the quality gate (nothing patched)"}));
}

}  // namespace fivebar::cli
