// The `control` product: the sampled PID loop of every mechanism linearised over its target ellipse
// (fivebar/control.hpp), with the links' masses from the `parts` product's STL renders: spectral
// radius map, worst pose, verdict, gain margins, damping; picture, VTK field and CSV under control/.

#include <algorithm>
#include <cmath>
#include <array>
#include <map>
#include <string>
#include <vector>

#include "fivebar/control.hpp"
#include "fivebar/error.hpp"
#include "products/markdown.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/format.hpp"
#include "products/product.hpp"

namespace fivebar::products {

namespace {

constexpr const char* kPreamble =
    "Each mechanism's loop as the device samples it: the dynamics (masses from the printed parts' STL renders, "
    "the `motor:` section, the skin of `contact:` in stick) linearised at every pose of a grid over the target "
    "ellipse, discretised exactly under zero-order hold at the loop period, closed by the exported PID with one "
    "period of computation delay (lib/include/fivebar/control.hpp). The loop is stable where the spectral radius "
    "ρ of the closed-loop matrix is below 1; the margins are the largest factors on kp (and on kd) that keep it "
    "so over the whole target. Small-signal figures: the driver's limits, Coulomb friction and the ADC "
    "quantisation are in the `simulate` product, not here.\n\n";

constexpr const char* kPerformance =
    "The worst over each target of: the −3 dB bandwidth of tactor displacement (the discrete closed loop's "
    "frequency response in the tactor's worst direction), the tactor step of one ADC count, the largest "
    "continuous shear force the motors hold in every direction (fingertip devices are compared at ≥ 1.5 N) and "
    "the Z-width, the stiffest virtual wall the loop renders passively from the device's own damping "
    "(Colgate–Schenkel, K < 2 b / T; a hard surface is 0.8–1.0 N/mm) and with the motors' Coulomb friction and "
    "the position quantum of one ADC count, both mapped to the tactor per direction (Abbott–Okamura, "
    "K ≤ min(2 b / T, 2 f_c / Δ)), and the loop rate a wall of `controller.target_stiffness_N_per_mm` needs "
    "(none when the quantisation forbids it at any rate).\n\n";

constexpr const char* kTuning =
    "`controller.tune` asks for the gains to be tuned, per mechanism (lib/include/fivebar/control/tune.hpp "
    "\"Tuning\"): from the gains the design runs (or, with `controller.tune.start`, a pole placement on the loop "
    "linearised at the target's centre, or the hand-set gains), NLopt's "
    "COBYLA searches the least worst simulated tracking error over the station's patterns, with the constraints an "
    "engineer sets over the target (the export gate's grid): spectral radius at most the limit, every oscillatory "
    "pole damped at least `controller.tune.min_damping` (ζ), kp and kd each multipliable by "
    "`controller.tune.min_gain_margin` without losing stability, the simulated 1 mm step (duty saturation and "
    "integral clamp included) overshooting no more than a second-order loop at that ζ, and no sustained "
    "saturation; masses from the closed form, as the export gate. The chirp (0.2 mm, 0.5 Hz to a quarter of the "
    "loop rate) gives the −3 dB bandwidth and the frequency at which a motor's duty first saturates; the "
    "bandwidth reported is the smaller. \"Before\" is the design's own PID, evaluated on the same objective and "
    "constraints: the tuned gains replace it only when they beat it, otherwise the design's gains are kept. "
    "`controller.tune.max_seconds` bounds the whole tuning, these figures included (a figure it cut is shown as "
    "--). `control/tuned-controller.yaml` is the patch of `controller:` that applies the tuned gains "
    "(`fivebar control --tune --merge` writes them into the design), `control/tuning.csv` the table.\n\n";

/// A figure, or "--" when the time bound left it uncomputed.
std::string figure(double v, int digits) { return std::isnan(v) ? std::string("--") : md::fixed(v, digits); }

std::string gains_cell(const PidGains& g) {
  return "kp " + md::fixed(g.kp, 3) + ", ki " + md::fixed(g.ki, 3) + ", kd " + md::fixed(g.kd, 4);
}

/// One joint's gains, or both when they differ (a per-joint tuning).
std::string gains_cell(const std::array<PidGains, 2>& g) {
  if (g[0].kp == g[1].kp && g[0].ki == g[1].ki && g[0].kd == g[1].kd) return gains_cell(g[0]);
  return "θ1 " + gains_cell(g[0]) + "; θ2 " + gains_cell(g[1]);
}

/// The tuning's tables, result and check line (the `control` product under `controller.tune`).
void add_tuning(Built& b, const TuneResult& tuned) {
  md::Table t({"station", "mechanism", "gains before (the design's)", "start", "gains after (tuned)", "max ρ before → after",
               "worst tracking error before → after (mm)", "saturated before → after", "evaluations", "stop",
               "the design runs"},
              "lllllrrrrll");
  bool feasible = true, applied = true;
  double worst_before = 0.0, worst_after = 0.0;
  for (const TunedMechanism& m : tuned.mechanisms) {
    feasible = feasible && m.feasible;
    applied = applied && m.applied();
    worst_before = std::max(worst_before, m.error_before_mm);
    worst_after = std::max(worst_after, m.error_after_mm);
    bool design_start = m.start_omega_rad_s == 0.0;
    for (std::size_t j = 0; j < 2; ++j) {
      design_start = design_start && m.start[j].kp == m.design[j].kp && m.start[j].ki == m.design[j].ki &&
                     m.start[j].kd == m.design[j].kd;
    }
    t.row({m.station, m.mechanism, gains_cell(m.before),
           (m.start_omega_rad_s > 0.0 ? "pole placement, ω " + md::fixed(m.start_omega_rad_s, 1) + " rad/s"
            : design_start           ? std::string("the design's gains")
                                     : std::string("the hand-set gains")) +
               ", max ρ " + md::fixed(m.rho_start, 4),
           m.improved ? gains_cell(m.after) : "kept (no candidate beat them)",
           md::fixed(m.rho_before, 4) + " → " + md::fixed(m.rho_after, 4),
           figure(m.error_before_mm, 3) + " → " + figure(m.error_after_mm, 3),
           figure(100 * m.saturation_before, 1) + " % → " + figure(100 * m.saturation_after, 1) + " %",
           std::to_string(m.evaluations),
           m.stop + (m.stop == "time limit" ? " (controller.tune.max_seconds)" : "") +
               (m.feasible ? "" : ", **not feasible**"),
           m.applied() ? "the tuned gains" : "other gains (" + gains_cell(m.design) + ")"});
  }
  md::Table f({"station", "mechanism", "least ζ (Hz) before → after", "kp margin before → after",
               "kd margin before → after", "1 mm step overshoot (mm) before → after",
               "chirp −3 dB / saturates at (Hz) before → after", "bandwidth (Hz) before → after",
               "tracking error (mm) before → after"},
              "llrrrrrrr");
  const auto onset = [](double hz) {
    return std::isnan(hz) ? std::string("--") : std::isfinite(hz) ? md::fixed(hz, 1) : std::string("never");
  };
  const auto chirp = [&](double bw, double sat) { return figure(bw, 1) + " / " + onset(sat); };
  for (const TunedMechanism& m : tuned.mechanisms) {
    f.row({m.station, m.mechanism,
           md::fixed(m.damping_before, 3) + " (" + md::fixed(m.damping_hz_before, 1) + ") → " +
               md::fixed(m.damping_after, 3) + " (" + md::fixed(m.damping_hz_after, 1) + ")",
           "×" + figure(m.kp_margin_before, 2) + " → ×" + figure(m.kp_margin_after, 2),
           "×" + figure(m.kd_margin_before, 2) + " → ×" + figure(m.kd_margin_after, 2),
           figure(m.overshoot_before_mm, 3) + " → " + figure(m.overshoot_after_mm, 3),
           chirp(m.chirp_bandwidth_before_hz, m.chirp_saturation_before_hz) + " → " +
               chirp(m.chirp_bandwidth_after_hz, m.chirp_saturation_after_hz),
           figure(m.bandwidth_before_hz, 1) + " → " + figure(m.bandwidth_after_hz, 1),
           figure(m.error_before_mm, 3) + " → " + figure(m.error_after_mm, 3)});
  }
  b.result["tuning"] = to_json(tuned);
  b.markdown += "### Tuning\n\n" + std::string(kTuning) + t.str() + "\nThe engineer's figures, the design's → tuned " +
                "(floors: ζ ≥ " + md::fixed(tuned.min_damping, 2) + ", margins ≥ ×" +
                md::fixed(tuned.min_gain_margin, 2) + ", step overshoot ≤ " +
                md::fixed(tuned.max_overshoot_fraction, 3) + " mm):\n\n" + f.str() + "\nTuned in " +
                md::fixed(tuned.wall_s, 1) + " s (budget " + md::fixed(tuned.budget_s, 1) + " s, these figures included), max ρ ≤ " +
                md::fixed(tuned.rho_limit, 2) + " over the target." +
                (applied ? " The design runs the tuned gains.\n"
                         : " The design does not run the tuned gains everywhere: merge "
                           "`control/tuned-controller.yaml` into its `controller:` section.\n");
  b.passed = b.passed && feasible;
  b.check += "; tuned: worst tracking error " + md::fixed(worst_before, 3) + " → " + md::fixed(worst_after, 3) +
             " mm with max ρ ≤ " + md::fixed(tuned.rho_limit, 2) +
             (feasible ? "" : " (NOT feasible for every mechanism)") +
             (applied ? ", the design runs them" : ", not applied (control/tuned-controller.yaml)");
}


}  // namespace

Product control_product() {
  Product p;
  p.name = "control";
  p.title = "Loop stability over the target";
  p.cost_s = 3.5;  // the tuning (scheduler hint only, Product::cost_s)
  p.prerequisites = {"parts"};
  p.unavailable = [](const Design& d) -> std::optional<std::string> {
    if (!d.get<MotorSettings>()) return "the design has no `motor:` section (the motors' data)";
    if (!d.get<ControllerSettings>()) return "the design has no `controller:` section (the PID to check)";
    return without_pairs(d, "the links' outlines give their masses");
  };
  p.build = [](Context& ctx) {
    const Design& d = ctx.design;
    const Json* parts = ctx.result_of("parts");
    md::Table table({"station", "mechanism", "verdict", "max ρ", "worst pose (mm)", "dominant pole ζ / Hz",
                     "least-damped oscillation ζ / Hz", "kp margin", "kd margin"},
                    "lllrlrrrr");
    md::Table performance({"station", "mechanism", "bandwidth ≥ (Hz)", "resolution ≤ (µm/count)",
                           "force in every direction ≥ (N)", "Z-width ≥ (N/mm)", "with friction and quantisation ≥ (N/mm)",
                           "loop rate for the target wall (Hz)"},
                          "llrrrrrr");
    Json studies = Json::array();
    std::map<std::string, std::map<std::string, MechanismInertia>> inertias;
    std::vector<const Station*> pairs;
    bool stable = true;
    std::size_t maps = 0;
    std::string files;
    for (const Station& s : d.stations) {
      if (!has_pair(s)) continue;
      ctx.say("stability of station " + s.name);
      const auto inertia = station_inertia(d, s, parts, ctx.dir / "parts");
      // The tuning with the closed-form masses the export gate checks with: reproducible (the STL
      // renders' masses change in their last digits between openscad runs, and the optimiser's
      // path with them).
      inertias[s.name] = station_inertia(d, s, nullptr, {});
      pairs.push_back(&s);
      const StationControl study = station_control(d, s, inertia);
      stable = stable && study.stable();
      for (const auto& [name, bytes] : control_files(study, s, "design " + d.name)) {
        ctx.write_file(std::filesystem::path("control") / name, bytes);
      }
      files += "![" + s.name + "](control/" + s.name + "-stability.svg)\n\n";
      for (const StabilityMap& m : study.maps) {
        ++maps;
        const Vec2 w = m.worst_P_mm();
        table.row({s.name, m.mechanism, m.stable ? "stable" : "**unstable**", md::fixed(m.max_rho, 4),
                   "(" + md::fixed(w.x(), 2) + ", " + md::fixed(w.y(), 2) + ")",
                   md::fixed(m.damping, 3) + " / " + md::fixed(m.frequency_hz, 2),
                   md::fixed(m.oscillatory_damping, 3) + " / " + md::fixed(m.oscillatory_frequency_hz, 2),
                   md::fixed(m.kp_margin, 2), md::fixed(m.kd_margin, 2)});
      }
      for (const PerformanceMap& m : study.performance) {
        performance.row({s.name, m.mechanism, md::fixed(m.worst_bandwidth.bandwidth_hz, 2),
                         md::fixed(m.worst_resolution.resolution_um, 3), md::fixed(m.worst_force.force_N, 2),
                         md::fixed(m.worst_zwidth.zwidth_N_per_mm, 1),
                         md::fixed(m.worst_zwidth_abbott_okamura.zwidth_abbott_okamura_N_per_mm, 2),
                         std::isfinite(m.worst_rate.rate_for_target_hz)
                             ? md::fixed(m.worst_rate.rate_for_target_hz, 2) + " for " +
                                   md::fixed(m.target_N_per_mm, 2) + " N/mm (" +
                                   (m.worst_rate.rate_for_target_hz <= m.loop_rate_hz ? "met" : "**not met**") + ")"
                             : "none: quantisation-limited"});
      }
      studies.push_back(to_json(study));
    }
    Built b;
    const std::vector<std::string> assumed = assumed_groups(d);
    b.result = {{"stations", studies}, {"stable", stable}, {"assumed", assumed}};
    b.markdown = std::string(kPreamble) + table.str() + "\n" + kPerformance + performance.str() + "\n" + files +
                 "\nRests on assumed values (no `provenance:` entry, docs/calibrate.md): " +
                 (assumed.empty() ? std::string("none") : format::join(assumed)) + ".\n";
    b.passed = stable;
    b.check = stable ? "stable over every target (" + std::to_string(maps) + " mechanisms)"
                     : "the loop is unstable somewhere on a target";
    const ControllerSettings& ctl = *d.get<ControllerSettings>();
    if (ctl.tune && !pairs.empty()) {
      TuneOptions to = tune_options(ctl);
      to.progress = [&ctx](std::string_view line) { ctx.say(line); };
      TuneResult tuned;
      try {
        tuned = tune_controller(d, pairs, inertias, to);
      } catch (const InputError& e) {
        // A pattern that cannot be followed (its reference unreachable): the `pattern` product says
        // where; no tuning without it.
        b.markdown += "### Tuning\n\n**Not tuned**: " + std::string(e.what()) + "\n";
        b.result["tuning"] = {{"error", e.what()}};
        b.passed = false;
        b.check += "; not tuned: a pattern cannot be followed";
        return b;
      }
      ctx.write_file("control/tuned-controller.yaml", tuned_patch_yaml(tuned));
      ctx.write_file("control/tuning.csv", tuning_csv(tuned));
      add_tuning(b, tuned);
    }
    return b;
  };
  return p;
}

}  // namespace fivebar::products
