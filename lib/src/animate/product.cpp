// The `animate` product: one animation per station and pattern (fivebar/animation.hpp): both
// linkages moving through the pattern at true speed over the reachable regions and the target,
// with the simulated tactor beside the reference when the `simulate` product ran in the scene.
// index.html places these SVGs inline (their script runs there); summary.md links them.

#include <filesystem>
#include <fstream>
#include <string>

#include "fivebar/animation.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/pattern.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

namespace {

constexpr const char* kPreamble =
    "Each pattern of the `pattern` product as an animation of the station: both linkages (motors O1, O2, elbows, "
    "tactor) moving through the samples at true speed, the tactor paths drawn as they go, the reachable regions and "
    "the fingertip target behind them. Open `index.html` to play them (play/pause, a time slider, `#t=SECONDS` in "
    "the address seeks); each file `animations/<station>-<pattern>.svg` also plays on its own in a browser. When the "
    "scene builds `simulate`, the simulated tactor (the dynamics under the exported controller) is drawn beside the "
    "reference.\n\n";

/// The simulated time series of (station, pattern) written by the `simulate` product, if any.
std::vector<SimulatedTrack> simulated_tracks(const Context& ctx, const std::string& station, const std::string& pattern) {
  const Json* sim = ctx.result_of("simulate");
  if (sim == nullptr || !sim->contains("runs")) return {};
  for (const Json& run : (*sim)["runs"]) {
    if (run.value("station", "") != station || run.value("reference", "") != pattern || !run.contains("csv")) continue;
    const std::string rel = run["csv"].get<std::string>();
    std::ifstream in(ctx.dir / rel);
    if (!in) return {};
    return read_simulated_tracks(in, rel);
  }
  return {};
}

}  // namespace

Product animate_product() {
  Product p;
  p.name = "animate";
  p.title = "Animated patterns";
  p.prerequisites = {"pattern"};
  p.after = {"simulate"};  // its simulated tracks, when the scene simulates
  p.unavailable = [](const Design& d) -> std::optional<std::string> {
    if (!d.get<PatternSettings>()) return "the design has no `patterns:` section";
    return without_pairs(d, "the patterns are checked with the link outlines");
  };
  p.build = [](Context& ctx) {
    const Design& d = ctx.design;
    const Geometry& g = *d.get<Geometry>();
    const PatternSettings& settings = *d.get<PatternSettings>();
    md::Table table({"station", "pattern", "frames", "duration (s)", "simulated tactor", "file"}, "llrrll");
    std::string images;
    Json files = Json::array();
    std::size_t with_sim = 0;
    for (const Station& s : d.stations) {
      if (!has_pair(s)) continue;
      for (const PatternSpec& spec : settings.for_station(s.name)) {
        const std::string kind(to_string(spec.kind));
        ctx.say("animate: station " + s.name + ", " + kind);
        const PatternResult r = check_pattern(s, g, spec, pattern_joint_speed_limit(d, s));
        AnimationOptions options;
        options.tactor_diameter_mm = g.tactor_diameter;
        options.simulated = simulated_tracks(ctx, s.name, kind);
        const std::string rel = "animations/" + s.name + "-" + kind + ".svg";
        ctx.write_file(rel, animate_pattern_svg(s, r, options));
        const std::size_t frames = animation_frames(s, r, options.max_frames).size();
        const bool sim = !options.simulated.empty();
        with_sim += sim ? 1 : 0;
        files.push_back({{"station", s.name}, {"pattern", kind}, {"file", rel}, {"frames", frames},
                         {"duration_s", r.samples.empty() ? 0.0 : r.samples.back().time_s}, {"simulated", sim}});
        table.row({md::code(s.name), kind, std::to_string(frames),
                   md::fixed(r.samples.empty() ? 0.0 : r.samples.back().time_s, 2),
                   sim ? "shown" : "— (`simulate` not in the scene)", "[svg](" + rel + ")"});
        images += "![" + kind + " on station " + s.name + "](" + rel + ")\n\n";
      }
    }
    Built b;
    b.result = {{"animations", files}};
    b.markdown = std::string(kPreamble) + table.str() + "\n" + images;
    b.check = std::to_string(files.size()) + " animations written, " + std::to_string(with_sim) +
              " with the simulated tactor";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
