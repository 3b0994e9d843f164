// The `simulate` product: the dynamics of every station with both tactors under the exported PID
// (fivebar/dynamics.hpp), every pattern of the station, the links' masses from the `parts`
// product's STL renders; per pattern and mechanism the tracking error, currents, saturation and
// shear force; a CSV time series per run under simulate/.

#include <string>

#include "fivebar/dynamics.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

namespace {

constexpr const char* kPreamble =
    "Each station's two tactors simulated together through every pattern: the linkages' rigid-body dynamics "
    "(masses from the printed parts' STL renders), the DC motors and their driver's voltage and current limits, "
    "the exported PID at the controller rate with ADC quantisation, zero-order hold and one period of delay, and "
    "the skin as a shear spring with Coulomb stick/slip at each tactor; integrated by SUNDIALS CVODE (BDF, "
    "Newton, dense) restarted at every sample and every stick/slip switch (lib/include/fivebar/dynamics.hpp). "
    "The motor and skin data are the design's `motor:` and `contact:` sections: assumptions until replaced by "
    "measured values. Tracking error is |P − P_ref| at the loop rate; saturation is time at full duty or at the "
    "current limit. Time series: `simulate/<station>-<pattern>.csv`; picture (commanded and simulated tactor paths on "
    "the fingertip, motor currents and skin forces over time): `simulate/<station>-<pattern>.svg` and `.png`.\n\n";

}  // namespace

Product simulate_product() {
  Product p;
  p.name = "simulate";
  p.title = "Dynamics under the exported controller";
  p.prerequisites = {"parts"};
  p.unavailable = [](const Design& d) -> std::optional<std::string> {
    if (!d.get<MotorSettings>()) return "the design has no `motor:` section (the motors' data)";
    if (!d.get<ControllerSettings>()) return "the design has no `controller:` section (the PID to simulate)";
    return without_pairs(d, "the links' outlines give their masses");
  };
  p.build = [](Context& ctx) {
    const Design& d = ctx.design;
    const Json* parts = ctx.result_of("parts");
    md::Table table({"station", "pattern", "status", "mechanism", "max error (mm)", "rms error (mm)",
                     "peak current (A)", "rms current (A)", "saturated (s)", "peak shear (N)", "slip", "wall (s)"},
                    "llllrrrrrrlr");
    Json runs = Json::array();
    Json mass = Json::array();  // one record per station and mechanism (docs/conventions.md "JSON documents")
    std::size_t total = 0, failed = 0;
    std::string problems;
    for (const Station& s : d.stations) {
      if (!has_pair(s)) continue;
      const auto inertia = station_inertia(d, s, parts, ctx.dir / "parts");
      for (const auto& [name, in] : inertia) {
        double moving = in.tip_mass_kg;
        for (const LinkInertia& l : in.links) moving += l.mass_kg;
        mass.push_back({{"station", s.name},
                        {"mechanism", name},
                        {"source", std::string(to_string(in.source))},
                        {"note", in.note},
                        {"moving_mass_g", moving * 1e3}});
      }
      SimulationRequest request;
      request.station = s.name;
      for (const SimulationInput& in : simulation_inputs(d, request, inertia)) {
        if (!in.unusable.empty()) {
          ++total;
          ++failed;
          runs.push_back({{"station", s.name}, {"reference", in.reference_name}, {"status", "not_simulated"},
                          {"reason", in.unusable}});
          problems += "- ✗ " + s.name + " " + in.reference_name + ": not simulated, " + in.unusable + "\n";
          continue;
        }
        ctx.say("simulating " + s.name + " " + in.reference_name);
        const SimulationResult r = simulate(in);
        ++total;
        const std::filesystem::path rel = std::filesystem::path("simulate") / (s.name + "-" + in.reference_name + ".csv");
        AtomicFile file = ctx.open_file(rel);
        write_time_series_csv(file.stream(), r);
        file.commit();
        ctx.record(rel);
        const RenderedPlot picture = plot_simulation(s, in, r);
        const std::filesystem::path svg = std::filesystem::path("simulate") / (s.name + "-" + in.reference_name + ".svg");
        ctx.write_file(svg, picture.svg);
        ctx.write_file(std::filesystem::path("simulate") / (s.name + "-" + in.reference_name + ".png"), picture.png);
        Json j = to_json(in, r);
        j["csv"] = rel.generic_string();
        j["picture"] = svg.generic_string();
        runs.push_back(j);
        if (!r.ok()) {
          ++failed;
          problems += "- ✗ " + s.name + " " + in.reference_name + ": " + std::string(to_string(r.status)) + ", " + r.reason + "\n";
        }
        for (const MechanismSummary& m : r.summary) {
          table.row({s.name, in.reference_name, std::string(to_string(r.status)), m.name, md::fixed(m.max_error_mm, 3),
                     md::fixed(m.rms_error_mm, 3), md::fixed(m.peak_current_A, 3), md::fixed(m.rms_current_A, 3),
                     md::fixed(m.saturation_s, 3), md::fixed(m.peak_shear_N, 3),
                     m.slipped ? "slipped (" + std::to_string(m.slips) + "×)" : "no", md::fixed(r.wall_s, 3)});
        }
      }
    }
    Built b;
    b.result = {{"integrator", "CVODE BDF, Newton, dense"}, {"rtol", SimulationOptions{}.rtol}, {"mass", mass}, {"runs", runs}};
    std::string masses;
    for (const Json& m : mass) {
      masses += "- " + m["station"].get<std::string>() + "/" + m["mechanism"].get<std::string>() + ": moving mass " +
                md::fixed(m["moving_mass_g"].get<double>(), 3) + " g (" + m["note"].get<std::string>() + ")\n";
    }
    b.markdown = std::string(kPreamble) + table.str() + "\n" + masses + "\n" + problems;
    b.passed = failed == 0;
    // The check line is the same for the same design (the product's wall time is in its own column).
    b.check = b.passed ? std::to_string(total) + " simulations finished"
                       : std::to_string(failed) + " of " + std::to_string(total) + " simulations did not finish";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
