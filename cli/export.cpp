// fivebar export: the validated controller configuration (ROS 2 parameters YAML, JSON, C++17
// header), written only when the design passes the export gate; --check re-reads an exported file
// and compares it with the design.

#include <algorithm>
#include <iostream>
#include <memory>

#include "common.hpp"
#include "fivebar/error.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/format.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/io.hpp"

namespace fivebar::cli {

namespace {

struct ExportCliOptions {
  std::string design;
  std::string station;
  std::string format = "all";
  std::string out;
  std::string check;
  std::string ros2_package;
  bool json = false;
};

std::vector<ExportFormat> formats_of(const std::string& text) {
  if (text == "all") return all_export_formats();
  if (text == "urdf" || text == "mjcf") return {};
  if (const auto f = parse_export_format(text)) return {*f};
  throw InputError("--format '" + text + "': expected ros2, json, header, urdf, mjcf or all");
}

void print_gate(const ExportGate& gate) {
  std::size_t kind_w = 5, subject_w = 7;
  for (const GateCheck& c : gate.checks) {
    kind_w = std::max(kind_w, c.kind.size());
    subject_w = std::max(subject_w, c.subject.size());
  }
  const auto pad = [](std::string s, std::size_t w) {
    s.resize(std::max(s.size(), w), ' ');
    return s;
  };
  std::cout << "  " << pad("check", kind_w) << "  " << pad("subject", subject_w) << "  verdict  detail\n";
  for (const GateCheck& c : gate.checks) {
    std::cout << "  " << pad(c.kind, kind_w) << "  " << pad(c.subject, subject_w) << "  "
              << (c.passed ? "ok     " : "FAILED ") << "  " << c.detail << "\n";
  }
}

int run_check(const ExportCliOptions& opt) {
  if (!opt.station.empty() || opt.format != "all" || !opt.out.empty()) {
    throw InputError("--check FILE DESIGN compares a file with a design: --station, --format and --out do not apply");
  }
  const Design design = load(opt.design);
  const ExportCheck c = check_export_file(opt.check, design);
  if (opt.json) {
    Json diffs = Json::array();
    for (const auto& d : c.differences) diffs.push_back({{"path", d.path}, {"expected", d.expected}, {"found", d.found}});
    print_json({{"command", "export"},
                {"check", opt.check},
                {"design", design.name},
                {"format", c.format},
                {"not_compared", c.not_compared},
                {"matches", c.matches()},
                {"hash_matches", c.hash_matches()},
                {"file_design", c.file_design},
                {"file_hash", c.file_hash},
                {"design_hash", c.design_hash},
                {"file_tool_version", c.file_tool_version},
                {"stations", c.stations},
                {"differences", diffs}});
  } else {
    std::cout << opt.check << " (" << c.format << ") against design " << design.name << "\n";
    std::cout << "  design in file    " << c.file_design << "\n";
    std::cout << "  stations          ";
    for (std::size_t i = 0; i < c.stations.size(); ++i) std::cout << (i ? ", " : "") << c.stations[i];
    std::cout << "\n  hash in file      " << c.file_hash << "\n";
    std::cout << "  hash of design    " << c.design_hash << (c.hash_matches() ? "  (same)" : "  (STALE: differs)") << "\n";
    std::cout << "  written by        fivebar " << c.file_tool_version << "\n";
    for (const std::string& n : c.not_compared) std::cout << "  not compared      " << n << "\n";
    if (c.matches()) {
      std::cout << "the file matches the design\n";
    } else {
      std::cout << c.differences.size() << " difference(s):\n";
      for (const auto& d : c.differences) {
        std::cout << "  " << d.path << ": design " << d.expected << ", file " << d.found << "\n";
      }
    }
  }
  if (!c.matches()) {
    std::cerr << "fivebar export --check: " << opt.check << " does not match design " << design.name << " ("
              << c.differences.size() << " difference(s)" << (c.hash_matches() ? "" : ", stale hash") << ")\n";
    return kCheckFailed;
  }
  return kOk;
}

int run_export(const ExportCliOptions& opt) {
  if (!opt.check.empty()) return run_check(opt);
  const bool package = !opt.ros2_package.empty();
  if (package && (opt.format != "all" || !opt.out.empty())) {
    throw InputError("--ros2-package DIR writes the package alone into DIR: --format and --out do not apply");
  }
  const std::vector<ExportFormat> formats = package ? std::vector<ExportFormat>{} : formats_of(opt.format);
  const Design design = load(opt.design);
  if (package && !design.has<Geometry>()) {
    throw InputError("--ros2-package: design " + design.name + " has no geometry: section (the URDF's links)");
  }
  ExportOptions options;
  options.urdf = !package && (opt.format == "all" || opt.format == "urdf");  // fivebar/export/urdf.hpp: closed-form masses here
  options.mjcf = !package && (opt.format == "all" || opt.format == "mjcf");  // fivebar/export/mjcf.hpp: the MuJoCo bundles
  options.ros2_package = package;                                            // fivebar/export/ros2_package.hpp
  if (!opt.station.empty()) options.stations = {opt.station};
  options.progress = terminal_progress("export");
  // The directory is created only once the gate has passed.
  const std::filesystem::path dir =
      package ? std::filesystem::path(opt.ros2_package) : command_output_dir(opt.out, design.name, "export");
  const WriteFence fence(dir);  // nothing of this command lands outside it (fivebar/io.hpp)
  const ExportResult r = export_controller(design, formats, dir, options);

  if (opt.json) {
    Json files = Json::array();
    for (const auto& f : r.files) files.push_back(f.generic_string());
    print_json({{"command", "export"},
                {"design", design.name},
                {"node", design.get<ControllerSettings>()->node},
                {"design_hash", r.hash},
                {"exported", r.gate.passed()},
                {"files", files},
                {"gate", to_json(r.gate)}});
  } else {
    std::cout << "export of design " << design.name << " for node " << design.get<ControllerSettings>()->node << ", stations ";
    for (std::size_t i = 0; i < r.gate.stations.size(); ++i) std::cout << (i ? ", " : "") << r.gate.stations[i];
    std::cout << "\n";
    print_gate(r.gate);
    // What each validated figure rests on (fivebar/provenance.hpp figure_bases()).
    for (const auto& [station, mechanisms] : r.gate.validation.items()) {
      for (const auto& [mechanism, figures] : mechanisms.items()) {
        // Figures that rest on the same groups share a line.
        std::vector<std::pair<std::string, std::vector<std::string>>> by_basis;
        for (const FigureBasis& f : figure_bases()) {
          if (!figures.contains(f.key) || !figures.at(f.key).is_number()) continue;
          const std::string text = rests_on_text(design, f.key, station, mechanism);
          const std::string figure = figure_text(f.key, figures.at(f.key).get<double>());
          auto it = std::find_if(by_basis.begin(), by_basis.end(), [&](const auto& x) { return x.first == text; });
          if (it == by_basis.end()) by_basis.push_back({text, {figure}});
          else it->second.push_back(figure);
        }
        for (const auto& [text, list] : by_basis) {
          std::cout << "  validated " << station << "/" << mechanism << ": " << format::join(list) << ": " << text << "\n";
        }
      }
    }
    if (r.gate.passed()) {
      std::cout << "design hash " << r.hash << "\n";
      for (const auto& f : r.files) std::cout << "  wrote " << f.generic_string() << "\n";
    }
  }
  if (!r.gate.passed()) {
    std::cerr << "fivebar export: refused, nothing written:\n";
    for (const std::string& reason : r.gate.reasons()) std::cerr << "  " << reason << "\n";
    return kCheckFailed;
  }
  return kOk;
}

}  // namespace

void setup_export(CLI::App& app) {
  auto [sub, opt] = add_command<ExportCliOptions>(
      app, "export",
      "Validated controller configuration: ROS 2 parameters YAML, JSON and a C++17 header, written only when the "
      "design passes the export gate (coverage, singularities, joint limits, calibration, patterns)",
      run_export);
  add_design_argument(*sub, opt->design);
  add_station_option(*sub, opt->station, "every station");
  sub->add_option("--format", opt->format,
                  "ros2, json, header, urdf, mjcf or all (default: all; urdf: one URDF with ros2_control per station; "
                  "mjcf: one MuJoCo MJCF per station, loops closed, motors as actuators)")->type_name("FORMAT");
  add_out_option(*sub, opt->out, "the files", "export");
  sub->add_option("--check", opt->check,
                  "Re-read an exported FILE (any format) and confirm it matches DESIGN: hash and every value")
      ->type_name("FILE");
  sub->add_option("--ros2-package", opt->ros2_package,
                  "Write a ROS 2 description package (package.xml, CMakeLists.txt, urdf/, config/, launch/) into DIR "
                  "instead of the files above")
      ->type_name("DIR");
  add_json_flag(*sub, opt->json);
  sub->footer(
      "Files: <design>_controller[_<station>].yaml|.json|.hpp, <design>_<station>.urdf and the MuJoCo bundle\n"
      "<design>_<station>/ (MJCF, scene.xml, README.md; both with geometry:), SI "
      "units; joints <station>_<mechanism>_theta<1|2>, their limits the usable range of each joint (potentiometer\n"
      "travel, hard stops, joint_limits).\n" +
      exit_status({.ok = "exported (or --check: the file matches)",
                   .failed = "export refused by the gate (nothing written) or --check found differences",
                   .bad_input = "bad input (design without controller: section, unknown station, ...)",
                   .writes = true}));
}

}  // namespace fivebar::cli
