// fivebar animate: one pattern of one station as an animated SVG (fivebar/animation.hpp): both
// linkages moving at true speed over the reachable regions and the target, with play/pause, a time
// slider and `#t=SECONDS` seeking; optionally the simulated tactor from a `fivebar simulate` CSV.

#include <fstream>
#include <iostream>
#include <memory>

#include "common.hpp"
#include "fivebar/animation.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/io.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/pattern.hpp"
#include "tactors.hpp"

namespace fivebar::cli {

namespace {

struct AnimateOptions {
  std::string design;
  std::string station;
  std::string pattern;
  std::string out;
  std::string simulated;
  double width_px = 1100.0;
  bool json = false;
};

int run_animate(const AnimateOptions& opt) {
  const auto kind = parse_pattern_kind(opt.pattern);
  if (!kind) throw InputError("--pattern '" + opt.pattern + "': expected stretch, slip, twist or pivot");
  // --out is the directory (as for every command); the file is <station>-<pattern>.svg, as
  // `fivebar run` names it. A file name is refused with what to write instead.
  const std::filesystem::path given(opt.out);
  if (given.extension() == ".gif") {
    throw InputError("--out " + opt.out + ": fivebar writes the animation as SVG only; for a GIF, take frames with "
                     "a browser at FILE.svg#t=SECONDS (README \"fivebar animate\") and join them with a GIF tool");
  }
  if (given.extension() == ".svg" || given.extension() == ".png") {
    throw InputError("--out " + opt.out + ": --out is the directory of the file (written as <station>-<pattern>.svg), "
                     "not the file");
  }
  if (!(opt.width_px >= 360.0 && opt.width_px <= 4000.0)) {
    throw InputError("--width must be between 360 and 4000 pixels");
  }
  const Design design = load(opt.design);
  const Station& s = select_pair_station(design, opt.station);
  const Geometry& g = require_geometry(design);
  const PatternSettings* settings = design.get<PatternSettings>();
  if (settings == nullptr) {
    throw InputError("design '" + design.name + "' has no patterns: section (see designs/iros2022.yaml)");
  }
  const PatternSpec* spec = nullptr;
  const std::vector<PatternSpec> specs = settings->for_station(s.name);
  for (const PatternSpec& p : specs) {
    if (p.kind == *kind) spec = &p;
  }
  if (spec == nullptr) {
    throw InputError("station '" + s.name + "' has no " + std::string(to_string(*kind)) +
                     " pattern in the design's patterns: section");
  }
  AnimationOptions options;
  options.width_px = opt.width_px;
  options.tactor_diameter_mm = g.tactor_diameter;
  if (!opt.simulated.empty()) {
    std::ifstream in(opt.simulated);
    if (!in) throw InputError("--simulated " + opt.simulated + ": cannot open the file");
    options.simulated = read_simulated_tracks(in, opt.simulated);
  }

  const PatternResult r = check_pattern(s, g, *spec, pattern_joint_speed_limit(design, s));
  const std::string svg = animate_pattern_svg(s, r, options);
  const std::size_t frames = animation_frames(s, r, options.max_frames).size();

  const std::filesystem::path dir = command_output_dir(opt.out, design.name, "animations");
  const std::filesystem::path out = dir / (s.name + "-" + std::string(to_string(*kind)) + ".svg");
  make_directories(dir);
  const WriteFence fence(dir);  // nothing of this command lands outside it (fivebar/io.hpp)
  write_file_atomic(out, svg);

  const double duration = r.samples.back().time_s;
  if (opt.json) {
    print_json({{"command", "animate"},
                {"design", design.name},
                {"station", s.name},
                {"pattern", std::string(to_string(*kind))},
                {"renderable", r.passed},
                {"frames", frames},
                {"duration_s", duration},
                {"simulated", !options.simulated.empty()},
                {"file", out.generic_string()}});
  } else {
    std::cout << s.name << "  pattern " << to_string(*kind) << ": " << frames << " frames over " << fixed(duration, 3)
              << " s (" << (r.passed ? "renderable" : "NOT renderable") << ")"
              << (options.simulated.empty() ? "" : ", with the simulated tactor") << "\n"
              << "  wrote " << out.generic_string() << " (open it in a browser; " << out.filename().generic_string()
              << "#t=0.5 shows t = 0.5 s)\n";
  }
  if (!r.passed) {
    std::cerr << "fivebar animate: " << to_string(*kind) << " is not renderable on station " << s.name << ": "
              << r.first_failure->reason << " (the animation shows it)\n";
    return kCheckFailed;
  }
  return kOk;
}

}  // namespace

void setup_animate(CLI::App& app) {
  auto [sub, opt] = add_command<AnimateOptions>(
      app, "animate",
      "One pattern of a station as an animated SVG: both linkages moving at true speed over the reachable regions "
      "and the target, the tactor paths drawn as they go, play/pause and a time slider",
      run_animate);
  add_design_argument(*sub, opt->design);
  add_station_option(*sub, opt->station, "the only one in the design");
  sub->add_option("--pattern", opt->pattern, "stretch, slip, twist or pivot (from the design's patterns: section)")
      ->required()
      ->type_name("KIND");
  add_out_option(*sub, opt->out, "<station>-<pattern>.svg", "animations");
  sub->add_option("--simulated", opt->simulated,
                  "A time series CSV of `fivebar simulate` for this station and pattern: the simulated tactor is "
                  "drawn beside the reference")
      ->type_name("CSV");
  sub->add_option("--width", opt->width_px, "Width of the picture in pixels (default 1100)")->type_name("PX");
  add_json_flag(*sub, opt->json);
  sub->footer("The pattern's parameters come from the design's patterns: section, as in `fivebar run`.\n" +
              exit_status({.ok = "written",
                           .failed = "written but the pattern is not renderable",
                           .bad_input = "bad input (nothing written)"}));
}

}  // namespace fivebar::cli
