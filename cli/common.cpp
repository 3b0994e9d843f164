#include "fivebar/format.hpp"
#include "common.hpp"

#include "fivebar/ranges.hpp"

#include <csignal>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>

#include <unistd.h>

#include "fivebar/error.hpp"
#include "fivebar/scene.hpp"
#include "fivebar/json.hpp"

namespace fivebar::cli {




std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

std::vector<std::string_view> split(std::string_view line, char sep) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const auto pos = line.find(sep, start);
    out.push_back(trim(line.substr(start, pos == std::string_view::npos ? std::string_view::npos : pos - start)));
    if (pos == std::string_view::npos) break;
    start = pos + 1;
  }
  return out;
}


void finish(int code) {
  if (code != kOk) throw CLI::RuntimeError(code);
}

// --- Design and mechanism selection -----------------------------------------------------------

void add_design_argument(CLI::App& sub, std::string& design) {
  sub.add_option("DESIGN", design, "Design/scene file (YAML), e.g. designs/iros2022.yaml")
      ->required()
      ->type_name("FILE");
}

void add_target_options(CLI::App& sub, Target& target) {
  add_design_argument(sub, target.design);
  add_station_option(sub, target.station, "the only one in the design");
  sub.add_option("-m,--mechanism", target.mechanism,
                 "Mechanism of the station: lower or upper; default: the only one present")
      ->check(CLI::IsMember({"lower", "upper"}))
      ->type_name("NAME");
}

CLI::Option* add_station_option(CLI::App& sub, std::string& station, std::string_view when_absent) {
  return sub.add_option("-s,--station", station, "Finger station (e.g. index, thumb); default: " + std::string(when_absent))
      ->type_name("NAME");
}

CLI::Option* add_out_option(CLI::App& sub, std::string& out, std::string_view what, std::string_view folder) {
  return sub
      .add_option("-o,--out", out,
                  "Directory for " + std::string(what) + " (default: outputs/<design>/" + std::string(folder) + ")")
      ->type_name("DIR");
}

CLI::Option* add_json_flag(CLI::App& sub, bool& json, std::string_view what) {
  return sub.add_flag("--json", json, "Print " + std::string(what) + " on stdout and nothing else");
}

std::string exit_status(const ExitStatus& status) {
  std::string text = "Exit status: 0 " + std::string(status.ok);
  if (!status.failed.empty()) text += ", 1 " + std::string(status.failed);
  text += ", 2 " + std::string(status.bad_input) + ", 3 internal error";
  if (status.writes) text += " or output not writable";
  if (status.resumable) text += ", 130 interrupted (continue with --resume)";
  return text + ".";
}

Design load(const std::string& path) { return load_scene(path); }

std::string Selection::label() const { return station->name + "/" + mechanism->name; }

Selection select(const Design& design, const Target& target) {
  Selection sel;
  std::vector<std::string> stations;
  for (const Station& s : design.stations) stations.push_back(s.name);
  if (target.station.empty()) {
    if (design.stations.size() != 1) {
      throw InputError("design '" + design.name + "' has " +
                       (stations.empty() ? std::string("no station") : "stations " + format::join(stations)) +
                       ": choose one with --station");
    }
    sel.station = &design.stations.front();
  } else {
    sel.station = &design.require_station(target.station);
  }
  std::vector<std::string> mechanisms;
  for (const Mechanism* m : sel.station->mechanisms()) mechanisms.push_back(m->name);
  if (target.mechanism.empty()) {
    if (mechanisms.size() != 1) {
      throw InputError("station '" + sel.station->name + "' has " +
                       (mechanisms.empty() ? std::string("no mechanism") : "mechanisms " + format::join(mechanisms)) +
                       ": choose one with --mechanism");
    }
    sel.mechanism = sel.station->mechanisms().front();
  } else {
    sel.mechanism = sel.station->mechanism(target.mechanism);
    if (sel.mechanism == nullptr) {
      throw InputError("station '" + sel.station->name + "' has no " + target.mechanism + " mechanism (it has: " +
                       (mechanisms.empty() ? std::string("none") : format::join(mechanisms)) + ")");
    }
  }
  return sel;
}

std::function<void(std::string_view)> terminal_progress(std::string_view command) {
  if (::isatty(STDERR_FILENO) == 0) return {};
  return [name = std::string(command)](std::string_view line) { std::cerr << "fivebar " << name << ": " << line << "\n"; };
}

// --- Values -----------------------------------------------------------------------------------

std::optional<double> parse_number(std::string_view text) {
  text = trim(text);
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

std::array<double, 2> parse_pair(std::string_view text, std::string_view option, std::string_view form) {
  const auto parts = split(text, ',');
  std::array<double, 2> out{};
  bool good = parts.size() == 2;
  for (std::size_t i = 0; good && i < 2; ++i) {
    const auto v = parse_number(parts[i]);
    good = v.has_value();
    if (good) out[i] = *v;
  }
  if (!good) {
    throw InputError(std::string(option) + " '" + std::string(text) + "': expected " + std::string(form) +
                     " (two finite numbers separated by a comma)");
  }
  return out;
}

std::array<double, 2> parse_point_mm(std::string_view text, std::string_view option) {
  const auto p = parse_pair(text, option, "X,Y in mm");
  for (double v : p) {
    if (const auto rule = ranges::coordinate_rule(v)) {
      throw InputError(std::string(option) + " '" + std::string(text) + "': coordinate " + exact(v) + " mm " + *rule +
                       " (docs/reliability.md \"Numeric ranges\")");
    }
  }
  return p;
}

std::pair<std::uint64_t, std::uint64_t> parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  std::uint64_t k = 0, n = 0;
  bool ok = slash != std::string::npos;
  if (ok) {
    const auto a = std::from_chars(text.data(), text.data() + slash, k);
    const auto b = std::from_chars(text.data() + slash + 1, text.data() + text.size(), n);
    ok = a.ec == std::errc{} && a.ptr == text.data() + slash && b.ec == std::errc{} &&
         b.ptr == text.data() + text.size() && slash > 0 && n > 0 && k < n;
  }
  if (!ok) throw InputError("--shard = '" + text + "': must be K/N with 0 <= K < N (e.g. 0/4)");
  return {k, n};
}

Ellipse parse_ellipse(std::string_view text, std::string_view option) {
  const std::string form = "CX,CY,AX,AY,ANGLE: centre (mm), full axis lengths (mm), rotation (deg)";
  auto fail = [&](const std::string& why) -> Ellipse {
    throw InputError(std::string(option) + " '" + std::string(text) + "': " + why + " (expected " + form + ")");
  };
  std::vector<double> v;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    std::string_view part = text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    while (!part.empty() && (part.front() == ' ' || part.front() == '\t')) part.remove_prefix(1);
    while (!part.empty() && (part.back() == ' ' || part.back() == '\t')) part.remove_suffix(1);
    if (!part.empty() && part.front() == '+') part.remove_prefix(1);
    double x = 0.0;
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), x);
    if (part.empty() || ec != std::errc() || end != part.data() + part.size() || !std::isfinite(x)) {
      return fail("value " + std::to_string(v.size() + 1) + " '" + std::string(part) + "' is not a finite number");
    }
    v.push_back(x);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  if (v.size() != 5) return fail("got " + std::to_string(v.size()) + " numbers, need 5");
  if (!(v[2] > 0.0) || !(v[3] > 0.0)) return fail("axis lengths must be > 0");
  Ellipse e;
  e.center = {v[0], v[1]};
  e.axes = {v[2], v[3]};
  e.angle = format::rad_from_deg(v[4]);
  try {
    e.validate();
  } catch (const InputError& err) {
    return fail(err.what());
  }
  return e;
}

// --- Output -----------------------------------------------------------------------------------

std::filesystem::path command_output_dir(const std::string& out, const std::string& design_name, std::string_view sub) {
  return out.empty() ? resolve_output_dir("outputs", design_name) / std::string(sub) : std::filesystem::path(out);
}

std::string remedy_hint(Remedy remedy) {
  switch (remedy) {
    case Remedy::none: return "";
    case Remedy::confirm: return "--yes confirms it";
    case Remedy::start_afresh: return "rerun without --resume to start afresh";
    case Remedy::without_rendering: return "--no-render writes the .scad sources only";
    case Remedy::resume_shard: return "fivebar optimize --shard K/N --resume finishes the shard";
    case Remedy::longer_budget: return "--seconds (or optimize.seconds) gives it more time";
  }
  return "";
}

void print_json(const Json& doc) { std::cout << doc.dump(2) << "\n"; }

std::string fixed(double value, int digits) {
  // A value that would print as 0.000 though it is not zero, or as an integer of 16 or more
  // digits, is shown in scientific form instead ("1e-06", "1e+308").
  const double magnitude = std::fabs(value);
  if (std::isfinite(value) && value != 0.0 && (magnitude < 0.5 * std::pow(10.0, -digits) || magnitude >= 1e15)) {
    return format::general(value, 4);
  }
  return format::fixed(value, digits);
}

std::string exact(double value) { return format::shortest(value); }

std::string limits_text(const Mechanism& m, const Pose& pose) {
  if (!m.joint_limits) return "none set";
  return pose.within_joint_limits ? "within" : "OUTSIDE";
}

void print_pose(std::ostream& out, const Mechanism& m, const Pose& pose) {
  constexpr double kDeg = format::kDegPerRad;
  const auto row = [&](std::string_view key, const std::string& value) {
    std::string k(key);
    k.resize(std::max<std::size_t>(k.size() + 2, 30), ' ');
    out << "  " << k << value << "\n";
  };
  row("status", std::string(to_string(pose.status)));
  if (pose.status == Status::unreachable) return;
  row("tactor P (mm)", fixed(pose.P.x()) + ", " + fixed(pose.P.y()));
  row("theta1, theta2 (deg)", fixed(angle_deg(pose.theta1)) + ", " + fixed(angle_deg(pose.theta2)));
  row("elbow A1 (mm)", fixed(pose.A1.x()) + ", " + fixed(pose.A1.y()));
  row("elbow A2 (mm)", fixed(pose.A2.x()) + ", " + fixed(pose.A2.y()));
  row("working mode (realised)", mode_string(pose.mode) + "   (design " + to_string(m.working_mode) + ")");
  row("assembly (realised)", std::string(1, sign_char(pose.assembly)) + "    (design " +
                                 to_string(m.assembly_mode) + ")");
  if (pose.jacobian_valid) {
    row("Jacobian dP/dtheta (mm/rad)", "[" + fixed(pose.J(0, 0)) + "  " + fixed(pose.J(0, 1)) + "]");
    row("", "[" + fixed(pose.J(1, 0)) + "  " + fixed(pose.J(1, 1)) + "]");
  } else {
    row("Jacobian dP/dtheta (mm/rad)", "undefined (type II singularity)");
  }
  row("LCI = 1/cond(J)", fixed(pose.lci));
  row("force capability (N/N*mm)", fixed(pose.force_capability));
  row("transmission (deg)", "elbow 1 " + fixed(pose.transmission[0] * kDeg, 2) + ", elbow 2 " +
                                fixed(pose.transmission[1] * kDeg, 2) + ", tactor " +
                                fixed(pose.transmission[2] * kDeg, 2));
  row("type I |sin| (legs 1, 2)", fixed(pose.type1_sin[0]) + ", " + fixed(pose.type1_sin[1]));
  row("type I distance (mm)", fixed(pose.type1_distance_mm));
  row("type II |sin|", fixed(pose.type2_sin));
  row("closure error (mm)", format::sci(pose.closure_error_mm, 1));
  row("joint limits", limits_text(m, pose));
}

// --- Interrupts ---------------------------------------------------------------------------------

namespace {
std::atomic<bool> g_interrupted{false};
extern "C" void on_stop_signal(int) { g_interrupted.store(true); }
}  // namespace

struct StopOnInterrupt::Saved {
  struct sigaction int_action {}, term_action {};
};

StopOnInterrupt::StopOnInterrupt() : saved_(std::make_unique<Saved>()) {
  g_interrupted.store(false);
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, &saved_->int_action);
  sigaction(SIGTERM, &sa, &saved_->term_action);
}

StopOnInterrupt::~StopOnInterrupt() {
  sigaction(SIGINT, &saved_->int_action, nullptr);
  sigaction(SIGTERM, &saved_->term_action, nullptr);
}

const std::atomic<bool>* StopOnInterrupt::stop() const { return &g_interrupted; }

}  // namespace fivebar::cli
