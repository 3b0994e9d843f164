// fivebar pattern: one skin-deformation pattern (stretch, slip, twist, pivot) for both tactors of a
// station, checked sample by sample; writes the joint trajectories (CSV) and a picture of the paths.

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>

#include "fivebar/format.hpp"
#include "common.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/pattern.hpp"
#include "tactors.hpp"

namespace fivebar::cli {

namespace {

using format::kDegPerRad;

struct PatternOptions {
  std::string design;
  std::string station;
  std::string pattern;
  std::optional<double> amplitude_mm;
  std::optional<double> amplitude_deg;
  std::optional<double> frequency_hz;
  std::optional<double> duration_s;
  std::optional<double> rate_hz;
  std::optional<double> separation_mm;
  std::optional<double> max_speed_deg_s;
  std::string center;
  std::string out;
  bool json = false;
  bool samples = false;
};

/// The design's entry for this station and kind, or the defaults; then the command-line overrides.
PatternSpec spec_for(const PatternOptions& opt, const Design& design, const Station& s, PatternKind kind) {
  PatternSpec spec = pattern_spec(design, s, kind);
  if (opt.amplitude_mm) {
    if (kind == PatternKind::pivot) throw InputError("--amplitude is in mm for stretch, slip and twist; pivot takes --amplitude-deg");
    spec.amplitude_mm = *opt.amplitude_mm;
  }
  if (opt.amplitude_deg || opt.frequency_hz) {
    if (kind != PatternKind::pivot) throw InputError("--amplitude-deg and --frequency are for --pattern pivot");
    if (opt.amplitude_deg) spec.pivot_amplitude = *opt.amplitude_deg / kDegPerRad;
    if (opt.frequency_hz) spec.pivot_frequency_hz = *opt.frequency_hz;
  }
  if (opt.duration_s) spec.duration_s = *opt.duration_s;
  if (opt.rate_hz) spec.rate_hz = *opt.rate_hz;
  if (opt.separation_mm) {
    spec.separation_mm = *opt.separation_mm;
    spec.contact_points.reset();  // the contact points follow the separation again
  }
  if (!opt.center.empty()) {
    const auto c = parse_point_mm(opt.center, "--center");
    spec.centre = Vec2(c[0], c[1]);
  }
  try {
    spec.validate();
  } catch (const ValidationError& e) {
    throw InputError("pattern " + std::string(to_string(kind)) + ": " + e.what());
  }
  return spec;
}

void row(const std::string& key, const std::string& value) {
  std::string k = key;
  k.resize(std::max<std::size_t>(k.size() + 2, 26), ' ');
  std::cout << "  " << k << value << "\n";
}

void print_result(const PatternResult& r, const std::vector<std::string>& files) {
  const PatternSpec& spec = r.spec;
  std::cout << r.station << "  pattern " << to_string(spec.kind) << ": " << r.samples.size() << " samples at "
            << fixed(spec.rate_hz, 1) << " Hz over " << fixed(spec.duration_s, 3) << " s, centre ("
            << fixed(r.centre.x()) << ", " << fixed(r.centre.y()) << ") mm\n";
  if (spec.kind == PatternKind::pivot) {
    row("object angle", fixed(spec.pivot_amplitude * kDegPerRad, 2) + " deg amplitude at " +
                            fixed(spec.pivot_frequency_hz, 3) + " Hz");
  } else {
    row("amplitude", fixed(spec.amplitude_mm, 3) + " mm");
  }
  row("separation", fixed(spec.separation_mm, 3) + " mm");
  row("verdict", r.passed ? "renderable" : "NOT renderable");
  if (r.first_failure) {
    const PatternFailure& f = *r.first_failure;
    row("first failure", "sample " + std::to_string(f.index) + " (t = " + fixed(f.time_s, 3) + " s), " + f.mechanism +
                             ": " + std::string(to_string(f.status)));
    row("", f.reason);
  }
  row("min LCI upper / lower", fixed(r.min_lci[0]) + " / " + fixed(r.min_lci[1]));
  row("min type I distance", fixed(r.min_type1_distance_mm[0], 3) + " / " + fixed(r.min_type1_distance_mm[1], 3) + " mm");
  row("min clearance", std::isfinite(r.min_clearance_mm) ? fixed(r.min_clearance_mm) + " mm (requested targets)" : "-");
  row("priority rule", r.moved_samples > 0 ? "moved the lower target in " + std::to_string(r.moved_samples) +
                                                 " samples, by up to " + fixed(r.max_moved_mm) + " mm"
                                           : "never needed");
  row("peak motor speed", fixed(r.peak_joint_speed * kDegPerRad, 1) + " deg/s (" +
                              (r.peak_joint_motor.empty() ? std::string("-") : r.peak_joint_motor) + ", limit " +
                              fixed(r.max_joint_speed * kDegPerRad, 1) + " deg/s)");
  std::string counts;
  for (std::size_t i = 0; i < r.status_counts.size(); ++i) {
    if (r.status_counts[i] == 0) continue;
    counts += (counts.empty() ? "" : ", ") + std::string(to_string(static_cast<SampleStatus>(i))) + " " +
              std::to_string(r.status_counts[i]);
  }
  row("samples (both tactors)", counts);
  for (std::size_t i = 0; i < files.size(); ++i) row(i == 0 ? "files" : "", files[i]);
}

int run_pattern(const PatternOptions& opt) {
  const auto kind = parse_pattern_kind(opt.pattern);
  if (!kind) throw InputError("--pattern '" + opt.pattern + "': expected stretch, slip, twist or pivot");
  if (opt.max_speed_deg_s && !(*opt.max_speed_deg_s > 0.0)) {
    throw InputError("--max-joint-speed must be a positive number of deg/s");
  }
  const Design design = load(opt.design);
  const Station& s = select_pair_station(design, opt.station);
  const Geometry& g = require_geometry(design);
  const PatternSpec spec = spec_for(opt, design, s, *kind);
  double max_speed = pattern_joint_speed_limit(design, s);  // the one joint speed (fivebar/device/joint_limits.hpp)
  if (opt.max_speed_deg_s) max_speed = *opt.max_speed_deg_s / kDegPerRad;

  const PatternResult r = check_pattern(s, g, spec, max_speed);

  const std::filesystem::path dir = output_dir(design, opt.out, "patterns");
  const WriteFence fence(dir);  // nothing of this command lands outside it (fivebar/io.hpp)
  const std::string stem = s.name + "-" + std::string(to_string(*kind));
  const std::filesystem::path csv = dir / (stem + ".csv");
  {
    AtomicFile file(csv);
    write_trajectory_csv(file.stream(), r);
    file.commit();
  }
  const RenderedPlot pic = plot_patterns(s, g, {r});
  const std::filesystem::path svg = dir / (stem + ".svg");
  const std::filesystem::path png = dir / (stem + ".png");
  write_file_atomic(svg, pic.svg);
  write_file_atomic(png, pic.png);
  const std::vector<std::string> files{csv.generic_string(), svg.generic_string(), png.generic_string()};

  if (opt.json) {
    Json doc = {{"command", "pattern"}, {"design", design.name}};
    doc.update(to_json(r, opt.samples));
    doc["files"] = files;
    print_json(doc);
  } else {
    print_result(r, files);
  }
  if (!r.passed) {
    std::cerr << "fivebar pattern: " << to_string(*kind) << " is not renderable on station " << s.name << ": "
              << r.first_failure->reason << "\n";
    return kCheckFailed;
  }
  return kOk;
}

}  // namespace

void setup_pattern(CLI::App& app) {
  auto [sub, opt] = add_command<PatternOptions>(
      app, "pattern",
      "A skin-deformation pattern for both tactors of a station (stretch, slip, twist, pivot), checked at every "
      "sample; writes the four motors' joint trajectories (CSV) and a picture of the paths",
      run_pattern);
  add_design_argument(*sub, opt->design);
  add_station_option(*sub, opt->station, "the only one in the design");
  sub->add_option("--pattern", opt->pattern, "stretch, slip, twist or pivot")->required()->type_name("KIND");
  sub->add_option("--amplitude", opt->amplitude_mm,
                  "Travel (mm): stretch, each tactor; slip, both; twist, arc length along the circle")
      ->type_name("MM");
  sub->add_option("--amplitude-deg", opt->amplitude_deg, "Pivot: peak object angle (deg)")->type_name("DEG");
  sub->add_option("--frequency", opt->frequency_hz, "Pivot: oscillation frequency of the object angle (Hz)")
      ->type_name("HZ");
  sub->add_option("--duration", opt->duration_s, "Length of the pattern (s)")->type_name("S");
  sub->add_option("--rate", opt->rate_hz, "Samples per second (the controller rate; default 100)")->type_name("HZ");
  sub->add_option("--separation", opt->separation_mm, "Distance between the tactors at the start (mm)")
      ->type_name("MM");
  sub->add_option("--center", opt->center, "Centre of the pattern X,Y (mm; default: the target centre)")
      ->type_name("X,Y");
  sub->add_option("--max-joint-speed", opt->max_speed_deg_s,
                  "Motor speed limit (deg/s; default: patterns.max_joint_speed_deg_s, else 360)")
      ->type_name("DEG_S");
  add_out_option(*sub, opt->out, "the CSV and the picture", "patterns");
  add_json_flag(*sub, opt->json);
  sub->add_flag("--samples", opt->samples, "With --json: include every sample");
  sub->footer("Parameters not given come from the design's patterns: section for this station, else the defaults.\n" +
              exit_status({.ok = "renderable", .failed = "not renderable (a sample fails)"}));
}

}  // namespace fivebar::cli
