// fivebar control: the sampled-data loop of every mechanism linearised over its target ellipse
// (ZOH plant, PID with one period of delay; fivebar/control.hpp): spectral radius map, worst pose,
// verdict, gain margins and the damping of the dominant pole; picture, VTK field, CSV, JSON.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <map>
#include <memory>
#include <optional>

#include "common.hpp"
#include "fivebar/control.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/io.hpp"
#include "fivebar/parts.hpp"
#include "fivebar/sha256.hpp"
#include "fivebar/scene.hpp"
#include "fivebar/studio.hpp"
#include "tactors.hpp"

namespace fivebar::cli {

namespace {

struct ControlCliOptions {
  std::string design;
  std::string station;
  bool render = false;
  int grid = 41;
  int field = 81;
  std::string out;
  bool json = false;
  bool tune = false;
  bool per_joint = false;
  std::optional<double> tune_seconds;   ///< default: controller.tune.max_seconds (30)
  std::optional<int> tune_evaluations;  ///< default: controller.tune.evaluations (60)
  bool merge = false;                   ///< with --tune: write the tuned gains into DESIGN
};

std::string gains_text(const PidGains& g) {
  return "kp " + fixed(g.kp, 3) + ", ki " + fixed(g.ki, 3) + ", kd " + fixed(g.kd, 4);
}

/// A figure, or "--" when the time bound left it uncomputed.
std::string figure(double v, int digits) { return std::isnan(v) ? std::string("--") : fixed(v, digits); }

/// Before and after side by side, one block per mechanism.
void print_tuning(const TuneResult& r) {
  std::cout << "tuning (max rho <= " << fixed(r.rho_limit, 2) << " over the target; worst simulated tracking error over "
            << "the patterns), from the design's gains unless controller.tune.start says otherwise; " << fixed(r.wall_s, 1)
            << " s of a " << fixed(r.budget_s, 2) << " s budget, the figures before and after included:\n";
  std::cout << "  mechanism      gains before                       gains after                        "
               "max rho before/after  error before/after (mm)  saturated before/after  evals  stop\n";
  for (const TunedMechanism& t : r.mechanisms) {
    std::string name = t.station + "/" + t.mechanism;
    name.resize(std::max<std::size_t>(name.size(), 13), ' ');
    std::string before = gains_text(t.before[0]), after = gains_text(t.after[0]);
    const bool per_joint = t.after[0].kp != t.after[1].kp || t.after[0].ki != t.after[1].ki || t.after[0].kd != t.after[1].kd;
    if (per_joint) after = "theta1 " + after;
    if (per_joint) before = "theta1 " + before;
    before.resize(std::max<std::size_t>(before.size(), 34), ' ');
    after.resize(std::max<std::size_t>(after.size(), 34), ' ');
    std::cout << "  " << name << "  " << before << " " << after << " " << fixed(t.rho_before, 4) << " / "
              << fixed(t.rho_after, 4) << "       " << figure(t.error_before_mm, 3) << " / " << figure(t.error_after_mm, 3)
              << "            " << figure(100 * t.saturation_before, 1) << " % / " << figure(100 * t.saturation_after, 1)
              << " %        " << t.evaluations << "     " << t.stop << (t.feasible ? "" : ", NOT FEASIBLE") << "\n";
    if (per_joint) {
      std::cout << "                 theta2 " << gains_text(t.before[1]) << std::string(8, ' ') << "theta2 "
                << gains_text(t.after[1]) << "\n";
    }
    std::cout << "    "
              << (t.improved ? std::string(t.objective_after_mm < t.objective_before_mm
                                               ? "tuned: objective "
                                               : "tuned: the design's gains miss a constraint, these meet them; objective ") +
                                   figure(t.objective_before_mm, 4) + " -> " + figure(t.objective_after_mm, 4) + " mm"
                  : std::isnan(t.objective_before_mm) ? std::string("kept the design's gains: the budget ended before they were measured")
                  : t.evaluations < 2 ? "kept the design's gains: the budget ended before another candidate was tried (objective " +
                                            figure(t.objective_before_mm, 4) + " mm)"
                                      : "kept the design's gains: no candidate beat them (objective " +
                                            figure(t.objective_before_mm, 4) + " mm)")
              << "\n";
    const auto onset = [](double hz) {
      return std::isnan(hz) ? std::string("--") : std::isfinite(hz) ? fixed(hz, 1) + " Hz" : std::string("never");
    };
    std::cout << "    least zeta " << fixed(t.damping_before, 3) << " -> " << fixed(t.damping_after, 3) << " (floor "
              << fixed(r.min_damping, 2) << "), kp margin x" << figure(t.kp_margin_before, 2) << " -> x"
              << figure(t.kp_margin_after, 2) << ", kd margin x" << figure(t.kd_margin_before, 2) << " -> x"
              << figure(t.kd_margin_after, 2) << " (floor x" << fixed(r.min_gain_margin, 2) << "), 1 mm step overshoot "
              << figure(t.overshoot_before_mm, 3) << " -> " << figure(t.overshoot_after_mm, 3) << " mm; chirp -3 dB "
              << figure(t.chirp_bandwidth_before_hz, 1) << " -> " << figure(t.chirp_bandwidth_after_hz, 1)
              << " Hz, motors saturate at " << onset(t.chirp_saturation_before_hz) << " -> "
              << onset(t.chirp_saturation_after_hz) << ": bandwidth " << figure(t.bandwidth_before_hz, 1) << " -> "
              << figure(t.bandwidth_after_hz, 1) << " Hz\n";
    // What the figures cover when the budget cut them: "--" above.
    for (const bool is_after : {false, true}) {
      const std::vector<std::string>& missing = is_after ? t.not_computed_after : t.not_computed_before;
      if (missing.empty()) continue;
      std::cout << "    " << (is_after ? "after" : "before") << ": not computed within the budget: " << format::join(missing)
                << " (tracking over " << fixed(is_after ? t.simulated_after_s : t.simulated_before_s, 2) << " of "
                << fixed(t.patterns_s, 2) << " s of the patterns)\n";
    }
  }
}

/// The text of the design file as read, for --merge (the loader read it, bounded, just before).
std::string design_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  if (!in && !in.eof()) throw InputError(path + ": cannot read the design file");
  return s.str();
}

/// --merge: the tuned gains written into the design file through the design-edit API
/// (fivebar/design/file_edit.hpp: only those numbers change), the diff printed first; refused
/// (exit 1, nothing written) when a tuned mechanism misses the export gate's loop checks or the
/// tuning's floors (gain_merge()), when the numbers cannot hold the gains, or when the file changed
/// on disk since it was read (as the studio's Save, Studio::save()).
int merge_tuned(const ControlCliOptions& opt, const Design& design, const std::string& text, const TuneResult& tuned,
                Json& doc) {
  GainMerge m = gain_merge(design, tuned);
  std::string after = text;
  if (!m.edits.empty()) {  // the diff is shown even when the merge is refused
    try {
      after = edit_design_text(text, opt.design, m.edits);
      (void)load_scene_from_string(after, opt.design);  // every rule of the loader holds
    } catch (const InputError& e) {
      m.refusals.push_back(e.what());
    }
  }
  const Json changes = line_diff(text, after);
  bool written = false;
  if (m.refusals.empty() && !m.edits.empty()) {
    if (sha256_hex(design_text(opt.design)) != sha256_hex(text)) {
      m.refusals.push_back(opt.design + ": the file changed on disk since it was read: nothing written (run again)");
    } else {
      write_file_atomic(opt.design, after);
      written = true;
    }
  }
  doc["merge"] = {{"file", opt.design}, {"changes", changes}, {"written", written}, {"refusals", m.refusals}};
  if (!opt.json) {
    std::cout << "merge into " << opt.design << " (" << m.edits.size() << " numbers; every other byte kept):\n";
    for (const Json& c : changes) {
      std::cout << "  line " << c["line"].get<int>() << "\n  - " << c["before"].get<std::string>() << "\n  + "
                << c["after"].get<std::string>() << "\n";
    }
    if (written) std::cout << "  wrote " << opt.design << "\n";
    else if (m.refusals.empty()) std::cout << "  nothing to change: the design already runs these gains\n";
  }
  if (!m.refusals.empty()) {
    std::cerr << "fivebar control --merge: refused, " << opt.design << " left unchanged:\n";
    for (const std::string& r : m.refusals) std::cerr << "  " << r << "\n";
    return kCheckFailed;
  }
  return kOk;
}

int run_control(const ControlCliOptions& opt) {
  if (opt.grid < 3 || opt.grid > 401) throw InputError("--grid must be within [3, 401]");
  if (opt.field < 3 || opt.field > 801) throw InputError("--field must be within [3, 801]");
  if (opt.tune_seconds && (!(*opt.tune_seconds > 0.0) || !(*opt.tune_seconds <= 3600.0))) {
    throw InputError("--tune-seconds must be > 0 and <= 3600");
  }
  if (opt.tune_evaluations && (*opt.tune_evaluations < 1 || *opt.tune_evaluations > 10000)) {
    throw InputError("--tune-evaluations must be within [1, 10000]");
  }
  if (opt.merge && !opt.tune) throw InputError("--merge writes the tuned gains into the design: give --tune with it");
  const Design design = load(opt.design);
  // --merge edits the file as read now (the loader has just read it, bounded): a regular file.
  std::string text;
  if (opt.merge) {
    if (!std::filesystem::is_regular_file(opt.design)) throw InputError("--merge: " + opt.design + " is not a regular file");
    text = design_text(opt.design);
  }
  const std::vector<const Station*> stations = design.select_stations(opt.station);
  if (stations.empty()) throw InputError("design '" + design.name + "' has no station with a mechanism");
  require_geometry(design);
  // Missing sections are bad input before anything is written.
  for (const Station* s : stations) {
    std::map<std::string, MechanismInertia> none;
    for (const Mechanism* m : s->mechanisms()) none[m->name] = MechanismInertia{};
    (void)loop_models(design, *s, none);
  }
  // --tune needs a station with both mechanisms: refused before anything is written (docs/reliability.md).
  std::vector<const Station*> pairs;
  for (const Station* s : stations)
    if (s->lower && s->upper) pairs.push_back(s);
  if (opt.tune && pairs.empty()) throw InputError("--tune: no station with both mechanisms (the patterns move both tactors)");
  const std::filesystem::path dir = output_dir(design, opt.out, "control");
  // Nothing of this command lands outside it (fivebar/io.hpp) but the design file --merge edits,
  // written once the fence is down.
  std::optional<WriteFence> fence;
  fence.emplace(dir);
  std::optional<Json> parts;
  const std::filesystem::path parts_dir = dir / "parts";
  if (opt.render) {
    PartsOptions po;
    po.out_dir = parts_dir;
    if (!opt.station.empty()) po.station = opt.station;
    po.progress = terminal_progress("control");
    const PartsReport report = build_parts(design, po);
    if (!report.passed()) {
      std::cerr << "fivebar control: the parts' renders failed their checks (see " << parts_dir.generic_string()
                << "); no mass properties\n";
      return kCheckFailed;
    }
    parts = to_json(report);
  }
  ControlOptions co;
  co.stability.grid = opt.grid;
  co.field_cells = opt.field;
  const auto progress = terminal_progress("control");
  make_directories(dir);
  Json doc = {{"command", "control"}, {"design", design.name}};
  Json studies = Json::array();
  std::vector<std::string> files;
  bool stable = true;
  std::map<std::string, std::map<std::string, MechanismInertia>> inertias;
  for (const Station* s : stations) {
    if (progress) progress("stability of station " + s->name);
    const auto inertia = station_inertia(design, *s, parts ? &*parts : nullptr, parts_dir);
    inertias[s->name] = inertia;
    const StationControl study = station_control(design, *s, inertia, co);
    stable = stable && study.stable();
    for (const auto& [name, bytes] : control_files(study, *s, "design " + design.name)) {
      const std::filesystem::path path = dir / name;
      write_file_atomic(path, bytes);
      files.push_back(path.generic_string());
    }
    Json j = to_json(study);
    std::string mass;
    for (const auto& [name, in] : inertia) mass += (mass.empty() ? "" : "; ") + name + ": " + in.note;
    j["mass_properties"] = mass;
    studies.push_back(j);
    if (!opt.json) {
      for (const std::string& line : summary_lines(study)) std::cout << line << "\n";
    }
  }
  std::optional<TuneResult> tuned;
  if (opt.tune) {
    TuneOptions to = tune_options(*design.get<ControllerSettings>());
    if (opt.tune_seconds) to.max_seconds = *opt.tune_seconds;
    if (opt.tune_evaluations) to.max_evaluations = *opt.tune_evaluations;
    if (opt.per_joint) to.per_joint = true;
    to.progress = progress;
    tuned = tune_controller(design, pairs, inertias, to);
    const std::filesystem::path patch = dir / "tuned-controller.yaml";
    write_file_atomic(patch, tuned_patch_yaml(*tuned));
    files.push_back(patch.generic_string());
    const std::filesystem::path table = dir / "tuning.csv";
    write_file_atomic(table, tuning_csv(*tuned));
    files.push_back(table.generic_string());
  }
  fence.reset();
  if (!opt.json) {
    if (tuned) print_tuning(*tuned);
    for (const std::string& f : files) std::cout << "  wrote " << f << "\n";
  }
  const int merged = opt.merge ? merge_tuned(opt, design, text, *tuned, doc) : kOk;
  if (opt.json) {
    doc["stations"] = studies;
    if (tuned) doc["tuning"] = to_json(*tuned);
    doc["files"] = files;
    print_json(doc);
  }
  if (merged != kOk) return merged;
  if (tuned) {
    bool feasible = true;
    for (const TunedMechanism& t : tuned->mechanisms) feasible = feasible && t.feasible;
    if (!feasible) {
      std::cerr << "fivebar control --tune: no gains met the constraints for every mechanism (see the table)\n";
      return kCheckFailed;
    }
    return kOk;
  }
  if (!stable) {
    bool verdict = true;  // a map without one reachable pose has no verdict: not "unstable"
    for (const Json& st : studies) {
      for (const Json& m : st.value("mechanisms", Json::array())) verdict = verdict && !m.value("max_rho", Json()).is_null();
    }
    std::cerr << (verdict ? "fivebar control: the loop is unstable (max rho >= 1) somewhere on a target (see above)\n"
                          : "fivebar control: no stability verdict: no pose of a target is reachable and regular (see above)\n");
    return kCheckFailed;
  }
  return kOk;
}

}  // namespace

void setup_control(CLI::App& app) {
  auto [sub, opt] = add_command<ControlCliOptions>(
      app, "control",
      "Stability of each mechanism's sampled PID loop over its target ellipse: spectral radius of the ZOH plant "
      "linearised at every pose with one period of delay, worst pose, gain margins, damping; picture, VTK, CSV",
      run_control);
  add_design_argument(*sub, opt->design);
  add_station_option(*sub, opt->station, "every station with a mechanism");
  sub->add_flag("--render", opt->render,
                "Links' masses from the parts' STL renders (openscad) instead of the closed form (slab with bosses)");
  sub->add_option("--grid", opt->grid, "Grid points per axis over the target ellipse's box (default 41)")
      ->type_name("N");
  sub->add_option("--field", opt->field, "Grid points per axis over each mechanism's reach (default 81)")
      ->type_name("N");
  add_out_option(*sub, opt->out, "the files", "control");
  add_json_flag(*sub, opt->json);
  sub->add_flag("--tune", opt->tune,
                "Tune kp, ki, kd per mechanism from the design's gains (NLopt COBYLA): least worst tracking error over "
                "the patterns with max rho <= controller.tune.rho_limit (0.9), never worse than the design's gains; "
                "writes tuned-controller.yaml (a patch of controller:) and tuning.csv and prints before/after");
  sub->add_flag("--merge", opt->merge,
                "With --tune: write the tuned gains into DESIGN (only those numbers change; the diff is printed first); "
                "refused, nothing written, when a tuned loop misses the export gate's loop checks or the tuning's floors");
  sub->add_flag("--per-joint", opt->per_joint,
                "With --tune: kp, ki, kd per joint (six unknowns per mechanism; default controller.tune.per_joint)");
  sub->add_option("--tune-seconds", opt->tune_seconds,
                  "Wall-time bound of the whole tuning, its figures before and after included (s, default "
                  "controller.tune.max_seconds or 30)")
      ->type_name("S");
  sub->add_option("--tune-evaluations", opt->tune_evaluations,
                  "Objective evaluations per mechanism (default controller.tune.evaluations or 60)")
      ->type_name("N");
  sub->footer(
      "Needs the design's geometry:, motor: and controller: sections (contact: and print: take their defaults).\n"
      "Files: <station>-stability.svg|.png, <station>-<mechanism>-rho.vti, <station>-stability.csv,\n"
      "<station>-performance.csv; with --tune also tuned-controller.yaml (a patch of controller:) and tuning.csv;\n"
      "with --merge also DESIGN itself (its gains' numbers).\n" +
      exit_status({.ok = "stable everywhere on every target (with --tune: the tuned gains meet the constraints)",
                   .failed = "unstable somewhere, tuned gains infeasible, a merge refused or a part failed to render",
                   .writes = true}));
}

}  // namespace fivebar::cli
