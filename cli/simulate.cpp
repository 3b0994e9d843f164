// fivebar simulate: the dynamics of a station's two tactors under the exported PID (motors,
// driver limits, ADC, skin contact), integrated by CVODE or ARKODE's explicit RK, with the averaged
// or the switched PWM (fivebar/dynamics.hpp); per pattern (or step, or chirp) and mechanism the
// tracking error, currents, saturation and shear force, a CSV time series and its picture, the
// dense output on request, and for the chirp the Bode magnitude and bandwidth.

#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "common.hpp"
#include "fivebar/resources/estimates.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/parts.hpp"
#include "tactors.hpp"

namespace fivebar::cli {

namespace {

struct SimulateOptions {
  std::string design;
  std::string station;
  std::string pattern;
  bool step = false;
  bool chirp = false;
  bool no_render = false;
  std::optional<double> rtol;
  std::string integrator = "bdf";
  std::string pwm = "averaged";
  std::optional<double> dense_dt_s;
  bool yes = false;  ///< run beyond the resource bounds (docs/reliability.md)
  double max_wall_s = 120.0;
  std::string out;
  bool json = false;
};

void print_run(const SimulationInput& in, const SimulationResult& r, const std::string& file) {
  std::cout << in.station << "  " << in.reference_name << ": " << to_string(r.status) << ", " << fixed(r.t_end, 3)
            << " s simulated in " << fixed(r.wall_s, 3) << " s (" << r.steps << " steps, " << r.restarts
            << " restarts)\n";
  if (!r.ok()) std::cout << "  " << r.reason << "\n";
  for (const MechanismSummary& s : r.summary) {
    std::cout << "  " << s.name << ": tracking error max " << fixed(s.max_error_mm, 3) << " mm, rms "
              << fixed(s.rms_error_mm, 3) << " mm (joint " << fixed(s.max_joint_error_deg, 2) << " deg); current peak "
              << fixed(s.peak_current_A, 3) << " A, rms " << fixed(s.rms_current_A, 3) << " A; peak duty "
              << fixed(s.peak_duty, 3) << ", saturated " << fixed(s.saturation_s, 3) << " s; peak shear "
              << fixed(s.peak_shear_N, 3) << " N, " << (s.slipped ? "slipped (" + std::to_string(s.slips) + "x)" : "no slip")
              << "\n";
  }
  std::cout << "  time series: " << file << " (picture: .svg, .png beside it)\n";
}

int run_simulate(const SimulateOptions& opt) {
  std::optional<PatternKind> kind;
  if (!opt.pattern.empty()) {
    kind = parse_pattern_kind(opt.pattern);
    if (!kind) throw InputError("--pattern '" + opt.pattern + "': expected stretch, slip, twist or pivot");
  }
  if (opt.rtol && (!(*opt.rtol >= 1e-14) || !(*opt.rtol <= 1e-2))) {
    throw InputError("--rtol must be within [1e-14, 1e-2]");
  }
  if (!(opt.max_wall_s > 0.0) || !(opt.max_wall_s <= 1e6)) throw InputError("--max-wall must be > 0 and <= 1e6 s");
  const std::optional<Integrator> integrator = parse_integrator(opt.integrator);
  if (!integrator) throw InputError("--integrator '" + opt.integrator + "': expected bdf or erk");
  const std::optional<PwmModel> pwm = parse_pwm_model(opt.pwm);
  if (!pwm) throw InputError("--pwm '" + opt.pwm + "': expected averaged or switched");
  if (opt.dense_dt_s && (!(*opt.dense_dt_s >= 1e-5) || !(*opt.dense_dt_s <= 1.0))) {
    throw InputError("--dense must be within [1e-5, 1] s");
  }
  const Design design = load(opt.design);
  std::vector<const Station*> stations;
  if (!opt.station.empty()) {
    stations.push_back(&select_pair_station(design, opt.station));
  } else {
    for (const Station& s : design.stations)
      if (s.lower && s.upper) stations.push_back(&s);
    if (stations.empty()) throw InputError("design '" + design.name + "' has no station with both mechanisms");
  }
  require_geometry(design);
  // Missing sections are bad input before anything is written.
  std::vector<SimulationInput> planned;
  for (const Station* s : stations) {
    SimulationRequest probe;
    probe.station = s->name;
    probe.pattern = kind;
    probe.step = opt.step;
    probe.chirp = opt.chirp;
    std::map<std::string, MechanismInertia> none;
    for (const Mechanism* m : s->mechanisms()) none[m->name] = MechanismInertia{};
    for (SimulationInput& in : simulation_inputs(design, probe, none)) planned.push_back(std::move(in));
  }
  // The dense output's size, estimated from the request before anything is written (the one
  // resource rule, fivebar/resources/budget.hpp).
  if (opt.dense_dt_s) {
    check_budget(dense_output_estimate(planned, *opt.dense_dt_s), opt.yes, "confirm with --yes, or give a coarser --dense");
  }

  const std::filesystem::path dir = output_dir(design, opt.out, "simulate");
  const WriteFence fence(dir);  // nothing of this command lands outside it (fivebar/io.hpp)
  std::optional<Json> parts;
  std::filesystem::path parts_dir = dir / "parts";
  if (!opt.no_render) {
    PartsOptions po;
    po.out_dir = parts_dir;
    if (opt.station.size()) po.station = opt.station;
    po.progress = terminal_progress("simulate");
    const PartsReport report = build_parts(design, po);
    if (!report.passed()) {
      std::cerr << "fivebar simulate: the parts' renders failed their checks (see " << parts_dir.generic_string()
                << "); no mass properties\n";
      return kCheckFailed;
    }
    parts = to_json(report);
  }
  SimulationOptions so;
  if (opt.rtol) so.rtol = *opt.rtol;
  so.max_wall_s = opt.max_wall_s;
  so.integrator = *integrator;
  so.pwm = *pwm;
  if (opt.dense_dt_s) so.dense_dt_s = *opt.dense_dt_s;
  Json runs = Json::array();
  Json mass = Json::array();  // one record per station and mechanism (docs/conventions.md "JSON documents")
  std::vector<std::string> files;
  bool all_ok = true;
  for (const Station* s : stations) {
    const auto inertia = station_inertia(design, *s, parts ? &*parts : nullptr, parts_dir);
    for (const auto& [name, in] : inertia) {
      double moving = in.tip_mass_kg;
      for (const LinkInertia& l : in.links) moving += l.mass_kg;
      mass.push_back({{"station", s->name},
                      {"mechanism", name},
                      {"source", std::string(to_string(in.source))},
                      {"note", in.note},
                      {"moving_mass_g", moving * 1e3}});
    }
    SimulationRequest request;
    request.station = s->name;
    request.pattern = kind;
    request.step = opt.step;
    request.chirp = opt.chirp;
    for (const SimulationInput& in : simulation_inputs(design, request, inertia)) {
      if (!in.unusable.empty()) {
        all_ok = false;
        // Every field a run record has (docs/schemas/simulate.schema.json), null for what does not exist.
        runs.push_back({{"station", s->name}, {"reference", in.reference_name}, {"status", "not_simulated"},
                        {"reason", in.unusable}, {"t_end_s", nullptr}, {"steps", 0}, {"rhs_evaluations", 0},
                        {"restarts", 0}, {"wall_s", 0.0}, {"samples", 0}, {"mechanisms", Json::array()},
                        {"csv", nullptr}});
        if (!opt.json) std::cout << s->name << "  " << in.reference_name << ": not simulated, " << in.unusable << "\n";
        continue;
      }
      const SimulationResult r = simulate(in, so);
      const std::filesystem::path csv = dir / (s->name + "-" + in.reference_name + ".csv");
      AtomicFile file(csv);
      write_time_series_csv(file.stream(), r);
      file.commit();
      files.push_back(csv.generic_string());
      const RenderedPlot picture = plot_simulation(*s, in, r);
      const std::filesystem::path svg = dir / (s->name + "-" + in.reference_name + ".svg");
      write_file_atomic(svg, picture.svg);
      write_file_atomic(dir / (s->name + "-" + in.reference_name + ".png"), picture.png);
      files.push_back(svg.generic_string());
      files.push_back((dir / (s->name + "-" + in.reference_name + ".png")).generic_string());
      Json j = to_json(in, r);
      j["csv"] = csv.generic_string();
      j["picture"] = svg.generic_string();
      if (opt.dense_dt_s) {
        SimulationResult dense_only;
        dense_only.samples = r.dense;
        dense_only.summary = r.summary;  // the mechanisms' names
        const std::filesystem::path dense_csv = dir / (s->name + "-" + in.reference_name + "-dense.csv");
        AtomicFile dense_file(dense_csv);
        write_time_series_csv(dense_file.stream(), dense_only);
        dense_file.commit();
        files.push_back(dense_csv.generic_string());
        j["dense_csv"] = dense_csv.generic_string();
      }
      runs.push_back(j);
      all_ok = all_ok && r.ok();
      if (!opt.json) print_run(in, r, csv.generic_string());
      if (opt.chirp) {
        const BodeResult bode = chirp_bode(in, r, request);
        const std::string stem = s->name + "-chirp-bode";
        AtomicFile bode_csv(dir / (stem + ".csv"));
        write_bode_csv(bode_csv.stream(), bode);
        bode_csv.commit();
        const std::string title = "Frequency response at the target centre, station " + s->name;
        write_file_atomic(dir / (stem + ".svg"), bode_svg(bode, title));
        write_file_atomic(dir / (stem + ".png"), bode_png(bode, title));
        Json bw = Json::array();  // records, not an object keyed by the mechanisms' names
        for (std::size_t m = 0; m < bode.mechanisms.size(); ++m) {
          bw.push_back({{"mechanism", bode.mechanisms[m]},
                        {"bandwidth_hz", bode.bandwidth_hz[m] ? Json(*bode.bandwidth_hz[m]) : Json(nullptr)}});
          if (!opt.json) {
            std::cout << "  " << bode.mechanisms[m] << ": -3 dB bandwidth "
                      << (bode.bandwidth_hz[m] ? fixed(*bode.bandwidth_hz[m], 2) + " Hz"
                                               : std::string("beyond the chirp's band"))
                      << " (magnitude " << fixed(bode.magnitude[m].front(), 3) << " at " << fixed(bode.f_hz.front(), 2)
                      << " Hz, " << fixed(bode.magnitude[m].back(), 3) << " at " << fixed(bode.f_hz.back(), 2)
                      << " Hz)\n";
          }
        }
        for (const char* ext : {".csv", ".svg", ".png"}) files.push_back((dir / (stem + ext)).generic_string());
        runs.back()["bandwidth"] = bw;
        runs.back()["bode_csv"] = (dir / (stem + ".csv")).generic_string();
        if (!opt.json) std::cout << "  Bode magnitude: " << (dir / (stem + ".csv")).generic_string() << ", .svg, .png\n";
      }
    }
  }
  if (opt.json) {
    print_json({{"command", "simulate"},
                {"design", design.name},
                {"integrator", so.integrator == Integrator::erk ? "ARKODE ERK, Dormand-Prince 5(4)"
                                                                : "CVODE BDF, Newton, dense"},
                {"pwm", std::string(to_string(so.pwm))},
                {"rtol", so.rtol},
                {"mass", mass},
                {"runs", runs},
                {"files", files}});
  } else {
    for (const Json& m : mass) {
      std::cout << "mass properties " << m["station"].get<std::string>() << "/" << m["mechanism"].get<std::string>()
                << ": " << m["note"].get<std::string>() << "\n";
    }
  }
  if (!all_ok) {
    std::cerr << "fivebar simulate: a simulation did not finish or could not start (its status and reason are above)\n";
    return kCheckFailed;
  }
  return kOk;
}

}  // namespace

void setup_simulate(CLI::App& app) {
  auto [sub, opt] = add_command<SimulateOptions>(
      app, "simulate",
      "Dynamics of a station's two tactors under the exported PID: motors, driver limits, ADC, skin stick/slip, "
      "integrated by CVODE; tracking error, currents, saturation, shear force, CSV time series",
      run_simulate);
  add_design_argument(*sub, opt->design);
  add_station_option(*sub, opt->station, "every station with both tactors");
  auto* pattern = sub->add_option("--pattern", opt->pattern, "Only this pattern: stretch, slip, twist or pivot")
                      ->type_name("KIND");
  auto* step = sub->add_flag("--step", opt->step,
                             "A 1 mm step of both tactors along +x from the stretch pattern's start, 0.5 s")
                   ->excludes(pattern);
  sub->add_flag("--chirp", opt->chirp,
                "A 0.2 mm chirp of both tactors along x, 0.5 -> 25 Hz (a quarter of the loop rate) over 6 s: Bode "
                "magnitude and -3 dB bandwidth (<station>-chirp-bode.csv, .svg, .png)")
      ->excludes(pattern)
      ->excludes(step);
  sub->add_flag("--no-render", opt->no_render,
                "Links' masses from the closed form (slab with bosses) instead of the parts' STL renders (openscad)");
  sub->add_option("--rtol", opt->rtol, "The integrator's relative tolerance (default 1e-6)")->type_name("R");
  sub->add_option("--integrator", opt->integrator,
                  "bdf (CVODE BDF, Newton; the default) or erk (ARKODE explicit Runge-Kutta, Dormand-Prince 5(4), "
                  "the comparison)")
      ->type_name("KIND");
  sub->add_option("--pwm", opt->pwm,
                  "averaged (V = duty x supply; the default) or switched (the 1 kHz sign-magnitude waveform, every "
                  "edge a stop time)")
      ->type_name("MODEL");
  sub->add_flag("--yes", opt->yes, "Write a dense output estimated at over a gigabyte or an hour (refused otherwise)");
  sub->add_option("--dense", opt->dense_dt_s,
                  "Also write <station>-<reference>-dense.csv: the integrator's dense output every S seconds")
      ->type_name("S");
  sub->add_option("--max-wall", opt->max_wall_s, "Wall-time bound of each simulation (s, default 120): beyond it the run "
                  "stops with status wall_time_limit")
      ->type_name("S");
  add_out_option(*sub, opt->out, "the CSV files", "simulate");
  add_json_flag(*sub, opt->json);
  sub->footer(
      "Needs the design's geometry:, motor: and controller: sections (contact: and print: take their defaults).\n"
      "Without --pattern, --step or --chirp, every pattern of the station's patterns: section (or all four defaults).\n" +
      exit_status({.ok = "every simulation finished",
                   .failed = "one did not (singular pose, step or time limit) or a part failed to render",
                   .writes = true}));
}

}  // namespace fivebar::cli
