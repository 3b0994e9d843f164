// Validated controller export (fivebar/export/export.hpp): the gate, the parameter tree, the design hash,
// writing the files and checking an exported file against a design. The three formats' text is
// in export_formats.cpp (and yaml/export_yaml_reader.cpp for reading ROS YAML back).

#include "fivebar/format.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/design/angles.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/export/mjcf.hpp"
#include "fivebar/export/ros2_package.hpp"
#include "fivebar/sections/tolerance.hpp"
#include "fivebar/sections/bench.hpp"
#include "fivebar/sections/optimize.hpp"
#include "fivebar/sections/sweep.hpp"
#include "fivebar/sha256.hpp"
#include "fivebar/tolerance.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>

#include "fivebar/coverage/coverage.hpp"
#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/device/config.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/pattern.hpp"
#include "fivebar/version.hpp"
#include "export/export_control_gate.hpp"
#include "export/export_detail.hpp"

namespace fivebar {

namespace {

using angles::kPi;
using angles::kTwoPi;
using format::kDegPerRad;
/// Lengths leave in metres (REP 103). Divided, not multiplied by 1e-3: the quotient is the double
/// nearest the true value, so 9 mm is written 0.009 rather than 0.009000000000000001.
constexpr double kMmPerMetre = 1000.0;
/// Version of the exported layout; a controller may refuse a layout it does not know.
constexpr int kFormatVersion = 1;

using format::fixed;

std::string point_text(const Vec2& p) { return "(" + fixed(p.x(), 3) + ", " + fixed(p.y(), 3) + ") mm"; }


/// Words a name cannot take in the header: C++ keywords and alternative tokens, and the macros GNU
/// mode predefines (`linux`, `unix`).
const std::set<std::string_view>& reserved_words() {
  static const std::set<std::string_view> words{
      "alignas", "alignof", "and", "and_eq", "asm", "auto", "bitand", "bitor", "bool", "break", "case", "catch",
      "char", "char8_t", "char16_t", "char32_t", "class", "compl", "concept", "const", "consteval", "constexpr",
      "constinit", "const_cast", "continue", "co_await", "co_return", "co_yield", "decltype", "default", "delete",
      "do", "double", "dynamic_cast", "else", "enum", "explicit", "export", "extern", "false", "float", "for",
      "friend", "goto", "if", "inline", "int", "long", "mutable", "namespace", "new", "noexcept", "not", "not_eq",
      "nullptr", "operator", "or", "or_eq", "private", "protected", "public", "register", "reinterpret_cast",
      "requires", "return", "short", "signed", "sizeof", "static", "static_assert", "static_cast", "struct",
      "switch", "template", "this", "thread_local", "throw", "true", "try", "typedef", "typeid", "typename",
      "union", "unsigned", "using", "virtual", "void", "volatile", "wchar_t", "while", "xor", "xor_eq", "linux",
      "unix"};
  return words;
}

/// Why `name` cannot serve as a ROS parameter name component and a C++ identifier, if it cannot.
std::optional<std::string> identifier_problem(std::string_view name) {
  const auto letter = [](char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); };
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  if (name.empty() || !letter(name.front())) return "must start with a letter";
  if (!std::all_of(name.begin(), name.end(), [&](char c) { return letter(c) || digit(c) || c == '_'; })) {
    return "may hold only letters, digits and _ (it names ROS parameters and C++ namespaces)";
  }
  if (name.find("__") != std::string_view::npos) return "must not contain \"__\" (reserved in C++)";
  if (reserved_words().count(name) > 0) return "is a C++ keyword or predefined macro";
  return std::nullopt;
}

/// Joint angles over the filled ellipse: boundary samples for the ranges, and rings for the limits.
struct JointSamples {
  std::array<double, 2> lo{0.0, 0.0}, hi{0.0, 0.0};
  bool any = false;
  std::size_t samples = 0, unreachable = 0, outside = 0;
  double worst_excess = 0.0;  ///< rad beyond the limits
  int worst_joint = 0;
  double worst_theta = 0.0;   ///< on the branch
  Vec2 worst_point{0.0, 0.0};
  std::array<JointBranch, 2> branch;
};

JointSamples sample_joints(const Mechanism& m, const Ellipse& e, const ExportOptions& options) {
  JointSamples out;
  std::array<JointBranch, 2> branch = joint_branches(m, e);
  bool reference_set = ik(m, e.center).status != Status::unreachable;
  const auto visit = [&](const Vec2& p) {
    ++out.samples;
    const Pose pose = ik(m, p);
    if (pose.status == Status::unreachable) {
      ++out.unreachable;
      return;
    }
    if (!reference_set) {
      branch[0].reference = angles::wrap_pi(pose.theta1), branch[1].reference = angles::wrap_pi(pose.theta2);
      reference_set = true;
    }
    const std::array<double, 2> theta{branch[0].represent(pose.theta1), branch[1].represent(pose.theta2)};
    for (int j = 0; j < 2; ++j) {
      out.lo[j] = out.any ? std::min(out.lo[j], theta[j]) : theta[j];
      out.hi[j] = out.any ? std::max(out.hi[j], theta[j]) : theta[j];
      if (branch[j].limits) {
        const double excess = std::max(branch[j].lo() - theta[j], theta[j] - branch[j].hi());
        if (excess > out.worst_excess) {
          out.worst_excess = excess, out.worst_joint = j, out.worst_theta = theta[j], out.worst_point = p;
        }
      }
    }
    out.any = true;
    if (!pose.within_joint_limits) ++out.outside;
  };
  out.branch = branch;
  visit(e.center);
  const int n = std::max(8, options.boundary_samples);
  for (int k = 0; k < n; ++k) visit(e.boundary_point(kTwoPi * k / n));
  const int rings = std::max(1, options.coverage.rings);
  const int angles = std::max(8, options.coverage.angles);
  for (int i = 1; i < rings; ++i) {
    const double s = double(i) / rings;
    for (int k = 0; k < angles; ++k) visit(e.center + s * (e.boundary_point(kTwoPi * k / angles) - e.center));
  }
  return out;
}

std::string deg_range(double lo, double hi) { return "[" + fixed(lo * kDegPerRad, 2) + ", " + fixed(hi * kDegPerRad, 2) + "] deg"; }

void say(const ExportOptions& o, const std::string& line) {
  if (o.progress) o.progress(line);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Formats and names

std::string_view to_string(ExportFormat format) {
  switch (format) {
    case ExportFormat::ros2: return "ros2";
    case ExportFormat::json: return "json";
    case ExportFormat::header: return "header";
  }
  return "ros2";
}

std::optional<ExportFormat> parse_export_format(std::string_view text) {
  for (ExportFormat f : all_export_formats()) {
    if (text == to_string(f)) return f;
  }
  return std::nullopt;
}

std::string_view file_extension(ExportFormat format) {
  switch (format) {
    case ExportFormat::ros2: return ".yaml";
    case ExportFormat::json: return ".json";
    case ExportFormat::header: return ".hpp";
  }
  return ".yaml";
}

std::vector<ExportFormat> all_export_formats() { return {ExportFormat::ros2, ExportFormat::json, ExportFormat::header}; }

// ---------------------------------------------------------------------------------------------
// Gate

bool ExportGate::passed() const {
  return std::all_of(checks.begin(), checks.end(), [](const GateCheck& c) { return c.passed; });
}

std::vector<std::string> ExportGate::reasons() const {
  std::vector<std::string> out;
  for (const GateCheck& c : checks) {
    if (!c.passed) out.push_back(c.subject + " " + c.kind + ": " + c.detail);
  }
  return out;
}

namespace {

/// The export gate's checks of a station's hardware limits (fivebar/device/joint_limits.hpp):
///   hardware_limits  per mechanism: both joints have a usable range (describe() of each);
///   joint_margin     per mechanism and per pattern: check_joint_margins() with the gate's sampling.
std::vector<GateCheck> hardware_limit_checks(const Design& design, const Station& station, const ExportOptions& options) {
  std::vector<GateCheck> out;
  for (const Mechanism* m : station.mechanisms()) {
    const std::array<UsableRange, 2> r = usable_ranges(design, station, *m);
    out.push_back(GateCheck{"hardware_limits", station.name + "/" + m->name, r[0].usable && r[1].usable,
                            "theta1 " + describe(r[0]) + "; theta2 " + describe(r[1])});
  }
  JointMarginOptions sampling;
  sampling.boundary_samples = options.boundary_samples;
  sampling.rings = options.coverage.rings;
  sampling.angles = options.coverage.angles;
  for (const JointMarginCheck& c : check_joint_margins(design, station, sampling)) {
    out.push_back(GateCheck{"joint_margin", c.subject, c.passed, c.detail});
  }
  return out;
}

}  // namespace

ExportGate export_gate(const Design& d, const ExportOptions& options) {
  const ControllerSettings& c = require_controller(d);
  ExportGate gate;
  gate.stations = chosen_stations(d, options.stations);
  auto add = [&gate](std::string kind, std::string subject, bool passed, std::string detail) {
    gate.checks.push_back(GateCheck{std::move(kind), std::move(subject), passed, std::move(detail)});
  };

  // Names: ROS parameter components and C++ namespaces in all three formats.
  {
    std::vector<std::string> problems;
    if (auto p = identifier_problem(c.node)) problems.push_back("controller.node '" + c.node + "' " + *p);
    for (const std::string& s : gate.stations) {
      if (auto p = identifier_problem(s)) problems.push_back("station '" + s + "' " + *p);
    }
    std::string detail;
    for (const auto& p : problems) detail += (detail.empty() ? "" : "; ") + p;
    add("names", "design", problems.empty(), problems.empty() ? "node and station names are identifiers" : detail);
  }

  // Collision geometry for every station whose two tactors share the workspace.
  bool pairs = false;
  for (const std::string& name : gate.stations) {
    const Station& s = *d.station(name);
    pairs = pairs || (s.lower && s.upper);
  }
  if (pairs) {
    add("geometry", "design", d.has<Geometry>(),
        d.get<Geometry>() ? "link outlines for the controller's collision check: geometry: section"
                   : "no geometry: section: the controller's collision check (FK of the measured joints, "
                     "upper priority) needs the link widths, pins and planes");
  }

  for (const std::string& name : gate.stations) {
    const Station s = with_usable_limits(d, *d.station(name));  // hardware limits (fivebar/device/joint_limits.hpp)
    say(options, "export gate: coverage of station " + name);
    const StationCoverage sc = station_coverage(s, std::nullopt, options.coverage);
    for (const Mechanism* m : s.mechanisms()) {
      const std::string subject = name + "/" + m->name;
      const CoverageResult& r = m->name == "lower" ? *sc.lower : *sc.upper;
      add("coverage", subject, r.covered,
          r.covered ? "covers the target, margin " + fixed(r.margin_mm, 3) + " mm (" + r.method + ")"
                    : "does not cover the target: " + r.reason + " (margin " + fixed(r.margin_mm, 3) + " mm)");

      const double threshold = std::max(c.min_lci, m->min_lci);
      const bool lci_ok = r.min_lci >= threshold && r.min_lci > 0.0;
      add("singularity", subject, lci_ok,
          "min LCI over the ellipse " + fixed(r.min_lci, 4) + " at " + point_text(r.min_lci_point) +
              (lci_ok ? " >= " : " below ") + fixed(threshold, 4) +
              " (the larger of controller.min_lci and the mechanism's min_lci" +
              (threshold > 0.0 ? ")" : "; a singular point has LCI 0)"));

      const JointSamples js = sample_joints(*m, s.target, options);
      for (int j = 0; j < 2; ++j) {
        if (js.any) gate.joints.push_back(JointSweep{joint_name(name, m->name, j + 1), js.lo[j], js.hi[j]});
      }
      if (!m->joint_limits) {
        add("joint_limits", subject, true, "no joint limits in the design (has_position_limits: false)");
      } else {
        std::string detail;
        if (js.outside == 0) {
          for (int j = 0; j < 2; ++j) {
            detail += std::string(j ? "; " : "") + "theta" + std::to_string(j + 1) + " " +
                      (js.any ? deg_range(js.lo[j], js.hi[j]) : std::string("-")) + " within " +
                      deg_range(js.branch[j].lo(), js.branch[j].hi());
          }
          detail += " (" + std::to_string(js.samples - js.unreachable) + " samples)";
        } else {
          const int j = js.worst_joint;
          detail = std::to_string(js.outside) + " of " + std::to_string(js.samples) +
                   " samples outside the limits; worst: theta" + std::to_string(j + 1) + " = " +
                   fixed(js.worst_theta * kDegPerRad, 2) + " deg at " + point_text(js.worst_point) + ", outside " +
                   deg_range(js.branch[j].lo(), js.branch[j].hi());
        }
        add("joint_limits", subject, js.outside == 0, detail);
      }

      // Calibration: the joint's whole range reads within the ADC's input range.
      {
        bool ok = js.any || m->joint_limits.has_value();
        std::string detail;
        for (int j = 0; j < 2; ++j) {
          const JointControl jc = c.joint(name, m->name, j + 1);
          double lo = 0.0, hi = 0.0;
          if (m->joint_limits) {
            lo = js.branch[j].lo(), hi = js.branch[j].hi();
          } else if (js.any) {
            lo = js.lo[j], hi = js.hi[j];
          } else {
            continue;
          }
          const double v1 = jc.potentiometer.volts_at_zero + lo / jc.potentiometer.rad_per_volt;
          const double v2 = jc.potentiometer.volts_at_zero + hi / jc.potentiometer.rad_per_volt;
          const double vlo = std::min(v1, v2), vhi = std::max(v1, v2);
          const bool in = vlo >= c.adc_range_v[0] && vhi <= c.adc_range_v[1];
          ok = ok && in;
          const double deg_per_count =
              std::abs(jc.potentiometer.rad_per_volt) * (c.adc_range_v[1] - c.adc_range_v[0]) /
              std::ldexp(1.0, c.adc_bits) * kDegPerRad;
          detail += std::string(j ? "; " : "") + "theta" + std::to_string(j + 1) + " " + deg_range(lo, hi) +
                    (m->joint_limits ? " (limits)" : " (over the ellipse)") + " reads [" + fixed(vlo, 3) + ", " +
                    fixed(vhi, 3) + "] V" + (in ? "" : " OUTSIDE") + ", " + fixed(deg_per_count, 4) + " deg/count";
        }
        if (detail.empty()) detail = "no reachable point to calibrate for";
        add("calibration", subject, ok,
            detail + "; ADC range [" + fixed(c.adc_range_v[0], 3) + ", " + fixed(c.adc_range_v[1], 3) + "] V");
      }
    }
    if (sc.shared) {
      const CoverageResult& r = *sc.shared;
      add("coverage", name + "/shared", r.covered,
          r.covered ? "both tactors reach the whole target, margin " + fixed(r.margin_mm, 3) + " mm"
                    : "the shared region does not cover the target: " + r.reason);
    }
    for (GateCheck& check : hardware_limit_checks(d, *d.station(name), options)) gate.checks.push_back(std::move(check));
    // Robust coverage (fivebar/tolerance.hpp) when tolerance.export_gate asks for it: the target
    // covered by tolerance.robust_fraction of printed devices (first order, at every boundary point).
    if (const ToleranceSettings* t = d.get<ToleranceSettings>(); t != nullptr && t->export_gate) {
      for (const Mechanism* m : s.mechanisms()) {
        say(options, "export gate: robust coverage of " + name + "/" + m->name);
        const ToleranceSources src = tolerance_sources(d, s, *m);
        const RobustCoverage r = robust_coverage(*m, s.target, src.spread(), src.robust_fraction, 0, src.seed);
        // Every link and base calibrated: the margin rests on those measurements, not on tolerance:.
        const bool geometry_calibrated =
            src.calibrated && std::all_of(src.calibrated->measured.begin(), src.calibrated->measured.begin() + 8, [](bool b) { return b; });
        add("robust_coverage", name + "/" + m->name, r.covered,
            fixed(100.0 * r.fraction, 1) + " % of printed devices keep a margin of " + fixed(r.robust_margin_mm, 3) +
                " mm (design " + fixed(r.margin_mm, 3) + " mm, sigma " + fixed(r.sigma_mm, 3) + " mm at " +
                point_text(r.robust_point) + ")" + (r.covered ? "" : ": printed devices lose the target") +
                (r.calibrated ? "; sigmas: the calibration's posterior covariance" : "") + "; rests on: " +
                (geometry_calibrated ? std::string("measured (kinematics, its posterior covariance in place of the tolerance: sigmas)")
                                     : rests_on_text(d, "robust_margin_mm", name, m->name)));
      }
    }
  }

  // Patterns declared for the exported stations.
  if (!d.get<PatternSettings>()) {
    add("pattern", "design", true, "no patterns: section: nothing to check");
  } else {
    for (const std::string& name : gate.stations) {
      const Station s = with_usable_limits(d, *d.station(name));  // hardware limits (fivebar/device/joint_limits.hpp)
      const std::vector<PatternSpec> specs = d.get<PatternSettings>()->for_station(name);
      if (specs.empty() || !(s.lower && s.upper)) continue;  // patterns move both tactors
      for (const PatternSpec& spec : specs) {
        const std::string subject = name + " " + std::string(to_string(spec.kind));
        if (!d.get<Geometry>()) {
          add("pattern", subject, false, "not checked: the collision checks need a geometry: section");
          continue;
        }
        say(options, "export gate: pattern " + subject);
        const PatternResult r = check_pattern(s, *d.get<Geometry>(), spec, pattern_joint_speed_limit(d, s));
        if (r.passed) {
          add("pattern", subject, true,
              "renderable: " + std::to_string(r.samples.size()) + " samples, peak motor speed " +
                  fixed(r.peak_joint_speed * kDegPerRad, 1) + " deg/s (limit " +
                  fixed(r.max_joint_speed * kDegPerRad, 1) + "), min clearance " +
                  (std::isfinite(r.min_clearance_mm) ? fixed(r.min_clearance_mm, 3) + " mm" : std::string("-")));
        } else {
          add("pattern", subject, false,
              "not renderable: at t = " + fixed(r.first_failure->time_s, 3) + " s, " + r.first_failure->reason);
        }
      }
    }
  }

  // The loop: stability over the targets, tracking and saturation in the simulated patterns.
  detail::ControlGate loop = detail::control_gate(d, gate.stations, options.progress);
  for (GateCheck& check : loop.checks) gate.checks.push_back(std::move(check));
  gate.validation = std::move(loop.figures);
  // What each validated figure rests on (fivebar/provenance.hpp figure_bases()), beside the figures.
  for (auto& [station, mechanisms] : gate.validation.items()) {
    for (auto& [mechanism, figures] : mechanisms.items()) {
      Json rests = Json::object();
      for (const FigureBasis& f : figure_bases()) {
        if (figures.contains(f.key)) rests[f.key] = rests_on_text(d, f.key, station, mechanism);
      }
      figures["rests_on"] = rests;
    }
  }

  // Measured or assumed (fivebar/provenance.hpp): what the validated figures rest on, and the
  // groups controller.require_measured wants measured.
  // Both follow the exported stations: a value of a station not exported is not what they rest on.
  gate.assumed = assumed_groups(d, gate.stations);
  for (const std::string& group : c.require_measured) {
    const std::vector<UntrustedValue> untrusted = untrusted_values(d, group, gate.stations);
    add("provenance", group, untrusted.empty(),
        untrusted.empty() ? "every value measured, each through a fit that passed its quality gate (provenance:)"
                          : std::to_string(untrusted.size()) + " value(s) not trusted as measured, e.g. " + untrusted.front().key + ": " +
                                untrusted.front().reason + " (controller.require_measured)");
  }
  return gate;
}

Json to_json(const ExportGate& gate) {
  Json checks = Json::array();
  for (const GateCheck& c : gate.checks) {
    checks.push_back({{"kind", c.kind}, {"subject", c.subject}, {"passed", c.passed}, {"detail", c.detail}});
  }
  Json joints = Json::array();
  for (const JointSweep& j : gate.joints) {
    joints.push_back({{"name", j.name}, {"range_over_ellipse_deg", {j.lo * kDegPerRad, j.hi * kDegPerRad}}});
  }
  return {{"passed", gate.passed()},
          {"stations", gate.stations},
          {"reasons", gate.reasons()},
          {"checks", checks},
          {"joints", joints},
          {"assumed", gate.assumed}};
}

// ---------------------------------------------------------------------------------------------
// Parameter tree

Json controller_parameters(const Design& d, const std::vector<std::string>& stations) {
  return configuration_document(device_config(d, stations));
}

// ---------------------------------------------------------------------------------------------
// Writing

std::string export_stem(const Design& d, const std::vector<std::string>& stations) {
  std::string stem = d.name + "_controller";
  if (stations.size() == 1 && d.stations.size() > 1) stem += "_" + stations.front();
  return stem;
}

ExportResult export_controller(const Design& d, const std::vector<ExportFormat>& formats,
                               const std::filesystem::path& dir, const ExportOptions& options) {
  ExportResult result;
  result.gate = export_gate(d, options);
  result.hash = design_hash(d, result.gate.stations);
  if (!result.gate.passed()) return result;  // nothing created, nothing written

  result.parameters = controller_parameters(d, result.gate.stations);
  if (!result.gate.validation.empty()) {
    result.parameters.begin().value()["ros__parameters"]["fivebar"]["validation"] = result.gate.validation;
  }
  // Every document in memory first: a rendering failure writes nothing.
  std::vector<std::pair<std::filesystem::path, std::string>> documents;
  const std::string stem = export_stem(d, result.gate.stations);
  for (ExportFormat f : formats) {
    documents.emplace_back(dir / (stem + std::string(file_extension(f))), render(f, result.parameters));
  }
  if (options.urdf && d.has<Geometry>()) {  // the links' outlines and masses (fivebar/export/urdf.hpp)
    for (const std::string& name : result.gate.stations) {
      const Station& s = *d.station(name);
      documents.emplace_back(dir / urdf_file_name(d, s), render_urdf(d, s, options.urdf_options));
    }
  }
  if (options.mjcf && d.has<Geometry>()) {  // the MuJoCo bundle per station (fivebar/export/mjcf.hpp)
    for (const std::string& name : result.gate.stations) {
      const Station& s = *d.station(name);
      for (BundleFile& f : mujoco_bundle(d, s, options.urdf_options)) {
        documents.emplace_back(dir / mujoco_bundle_name(d, s) / f.path, std::move(f.bytes));
      }
    }
  }
  if (options.ros2_package && d.has<Geometry>()) {  // fivebar/export/ros2_package.hpp
    for (BundleFile& f : ros2_package(d, result.gate.stations, result.parameters, options.urdf_options)) {
      documents.emplace_back(dir / options.ros2_package_subdir / f.path, std::move(f.bytes));
    }
  }
  // A target that cannot be replaced (a directory of that name) fails before anything is written.
  for (const auto& [path, text] : documents) {
    std::error_code ec;
    const auto status = std::filesystem::symlink_status(path, ec);
    if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) {
      throw IoError(path.string() + ": exists and is not a regular file; nothing written");
    }
  }
  make_directories(dir);
  for (const auto& [path, text] : documents) {
    if (path.parent_path() != dir) make_directories(path.parent_path());  // a bundle's folders
  }
  std::vector<AtomicFile> files;
  for (const auto& [path, text] : documents) {
    files.emplace_back(path);
    files.back().stream() << text;
  }
  for (AtomicFile& f : files) {
    f.commit();
    result.files.push_back(f.path());
  }
  return result;
}

// ---------------------------------------------------------------------------------------------
// Checking an exported file

namespace {

std::string kind_of(const Json& v) {
  if (v.is_number_float()) return "double";
  if (v.is_number_integer()) return "integer";
  if (v.is_string()) return "string";
  if (v.is_boolean()) return "bool";
  if (v.is_array()) return "list";
  if (v.is_object()) return "map";
  return "null";
}

std::string shown(const Json& v) {
  std::string s;
  if (v.is_number_float()) {
    s = format_double(v.get<double>());
  } else if (v.is_array()) {
    s = "[";
    for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + shown(v[i]);
    s += "]";
  } else if (v.is_object()) {
    s = "{...}";
  } else {
    s = v.dump();
  }
  if (s.size() > 120) s = s.substr(0, 117) + "...";
  return s;
}

bool same(const Json& a, const Json& b) {
  if (kind_of(a) != kind_of(b)) return false;
  if (a.is_number_float()) {
    const double x = a.get<double>(), y = b.get<double>();
    return (x == y && std::signbit(x) == std::signbit(y)) || (std::isnan(x) && std::isnan(y));
  }
  if (a.is_number_integer()) return a.get<std::int64_t>() == b.get<std::int64_t>();
  return a == b;
}

void diff(const Json& expected, const Json& found, const std::string& path, std::vector<ExportDifference>& out) {
  const auto child = [&](const std::string& key) { return path.empty() ? key : path + "." + key; };
  if (expected.is_object() && found.is_object()) {
    for (const auto& [key, value] : expected.items()) {
      if (!found.contains(key)) {
        out.push_back({child(key), shown(value), "(absent)"});
      } else {
        diff(value, found.at(key), child(key), out);
      }
    }
    for (const auto& [key, value] : found.items()) {
      if (!expected.contains(key)) out.push_back({child(key), "(absent)", shown(value)});
    }
    return;
  }
  if (expected.is_array() && found.is_array() && expected.size() == found.size()) {
    for (std::size_t i = 0; i < expected.size(); ++i) {
      diff(expected[i], found[i], path + "[" + std::to_string(i) + "]", out);
    }
    return;
  }
  if (!same(expected, found)) {
    std::string e = shown(expected), f = shown(found);
    if (kind_of(expected) != kind_of(found)) e += " (" + kind_of(expected) + ")", f += " (" + kind_of(found) + ")";
    out.push_back({path, e, f});
  }
}

[[noreturn]] void not_export(const std::string& origin, const std::string& why) {
  throw InputError(origin + ": not a fivebar controller export: " + why);
}

}  // namespace

ExportCheck check_export(const std::string& text, ExportFormat format, const Design& d, const std::string& origin) {
  const Json tree = parse_export(format, text, origin);
  if (!tree.is_object() || tree.size() != 1) not_export(origin, "expected one top-level key, the node name");
  const Json& node = tree.begin().value();
  if (!node.is_object() || !node.contains("ros__parameters") || !node.at("ros__parameters").is_object()) {
    not_export(origin, "no ros__parameters under the node '" + tree.begin().key() + "'");
  }
  const Json& params = node.at("ros__parameters");
  const auto info_string = [&](const char* key) -> std::string {
    if (!params.contains("fivebar") || !params.at("fivebar").is_object()) not_export(origin, "no fivebar: block");
    const Json& info = params.at("fivebar");
    if (!info.contains(key) || !info.at(key).is_string()) not_export(origin, std::string("no fivebar.") + key);
    return info.at(key).get<std::string>();
  };

  ExportCheck check;
  check.format = std::string(to_string(format));
  check.file_design = info_string("design");
  check.file_hash = info_string("design_hash");
  check.file_tool_version = info_string("tool_version");
  if (!params.contains("station_names") || !params.at("station_names").is_array()) not_export(origin, "no station_names");
  std::vector<std::string> known;
  for (const Json& s : params.at("station_names")) {
    if (!s.is_string()) not_export(origin, "station_names must be strings");
    check.stations.push_back(s.get<std::string>());
    if (d.station(check.stations.back()) != nullptr) known.push_back(check.stations.back());
  }
  // None of the file's stations in the design: compare with every station (the differences say so).
  const Json expected = controller_parameters(d, known);
  check.design_hash = expected.begin().value().at("ros__parameters").at("fivebar").at("design_hash").get<std::string>();
  // fivebar.validation holds what the gate measured, not values of the design: not compared.
  Json found = tree;
  found.begin().value()["ros__parameters"]["fivebar"].erase("validation");
  diff(expected, found, "", check.differences);
  if (format == ExportFormat::header) {
    // The header's second copy, the one the runtime reads (fivebar/runtime/header_config.hpp).
    Json embedded = detail::header_runtime_json(text, origin);
    if (embedded.is_object() && embedded.size() == 1 && embedded.begin().value().contains("ros__parameters")) {
      embedded.begin().value()["ros__parameters"]["fivebar"].erase("validation");
    }
    diff(expected, embedded, "runtime_json", check.differences);
  }
  return check;
}

ExportCheck check_export_file(const std::filesystem::path& file, const Design& d) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) throw InputError(file.string() + ": no such exported file");
  // An exported file is a few kilobytes (a URDF with meshes inline some megabytes): one past
  // kMaxExportedFileBytes is refused while reading, not read whole (docs/reliability.md).
  const std::string content = csv::read_bounded(file, kMaxExportedFileBytes, "exported file");
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return char(std::tolower(ch)); });
  const auto first = content.find_first_not_of(" \t\r\n");
  if (ext == ".urdf" || ext == ".xml" || (first != std::string::npos && content[first] == '<')) {
    return check_robot_export(content, d, file.string());
  }
  return check_export(content, detect_export_format(file, content), d, file.string());
}

}  // namespace fivebar
