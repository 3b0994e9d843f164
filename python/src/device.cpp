// The device-side commands from Python (docs/python.md): the collision check of a station's two
// tactors with the priority rule (`fivebar collision --upper --lower`), a skin-deformation pattern
// checked sample by sample (`fivebar pattern`), and the device runtime's controller
// (fivebar::runtime::Controller, the code the exported device runs). Plain dicts and NumPy arrays;
// the package (fivebar/__init__.py) wraps them into result objects. Nothing is written.

#include <pybind11/stl.h>

#include <cmath>
#include <fstream>
#include <limits>

#include "bindings.hpp"
#include "fivebar/design/pair_station.hpp"
#include "fivebar/collision.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/pattern.hpp"
#include "fivebar/replay.hpp"
#include "fivebar/replay/sil.hpp"
#include "fivebar/runtime/controller.hpp"
#include "fivebar/runtime/json_config.hpp"

namespace fivebar::python {

namespace {

using format::kDegPerRad;

/// The station (empty: the only one) with both mechanisms, as `fivebar collision` and `pattern`
/// choose it (fivebar/design/pair_station.hpp); InputError naming what is missing.
const Station& pair_station_of(const Design& design, const std::string& station) {
  if (station.empty() && design.stations.size() > 1) {
    std::string names;
    for (const Station& st : design.stations) names += (names.empty() ? "" : ", ") + st.name;
    throw InputError("design '" + design.name + "' has stations " + names + ": choose one with station=");
  }
  return fivebar::pair_station(design, station);
}

const Geometry& design_geometry(const Design& design) { return require_geometry(design); }

Vec2 finite_point(const std::array<double, 2>& p, const char* what) {
  if (!std::isfinite(p[0]) || !std::isfinite(p[1])) {
    throw InputError(std::string(what) + ": expected a finite point (x, y) in mm");
  }
  return {p[0], p[1]};
}

py::array_t<double> xy(const Vec2& p) {
  py::array_t<double> a(2);
  a.mutable_at(0) = p.x();
  a.mutable_at(1) = p.y();
  return a;
}

// --- Collision ------------------------------------------------------------------------------------

py::dict collision_pair(const Design& design, const std::string& station, const std::array<double, 2>& upper,
                        const std::array<double, 2>& lower) {
  const Station& s = pair_station_of(design, station);
  const Geometry& g = design_geometry(design);
  const PriorityResult r =
      apply_priority(*s.upper, *s.lower, g, finite_point(upper, "upper"), finite_point(lower, "lower"));
  const bool collides = r.before && r.before->collides;
  py::dict d;
  d["station"] = s.name;
  d["collides"] = collides;
  d["clearance_mm"] = r.before ? py::object(py::float_(r.before->min_clearance_mm)) : py::object(py::none());
  d["closest_pair"] = r.before ? py::object(py::str(r.before->closest.name())) : py::object(py::none());
  d["required_clearance_mm"] = g.min_clearance;
  d["status"] = std::string(to_string(r.status));
  d["reason"] = r.reason;
  d["upper_target"] = xy(r.upper_target);
  d["lower_target"] = xy(r.lower_target);
  d["lower_point"] = xy(r.lower_point);
  d["moved_mm"] = r.moved_mm;
  d["clearance_after_mm"] = r.after ? py::object(py::float_(r.after->min_clearance_mm)) : py::object(py::none());
  d["upper_pose"] = r.upper;
  d["lower_pose"] = r.lower;
  Json doc = {{"command", "collision"}, {"design", design.name}, {"station", s.name}};
  doc["collides"] = collides;
  doc.update(to_json(r));
  d["summary"] = to_python(doc);
  return d;
}

/// `fivebar collision` without points: every pair of grid points of the target ellipse (no picture).
py::dict collision_map_dict(const Design& design, const std::string& station, double spacing_mm) {
  if (!(spacing_mm > 0.0) || !std::isfinite(spacing_mm)) throw InputError("spacing_mm must be a positive number of mm");
  const Station& s = pair_station_of(design, station);
  const Geometry& g = design_geometry(design);
  CollisionMapOptions options;
  options.spacing_mm = spacing_mm;
  CollisionMap map;
  Interruptible run;
  run.run([&] { map = collision_map(s, g, options); });
  const py::ssize_t n = py::ssize_t(map.points.size());
  py::array_t<bool> upper_ok(n), lower_ok(n);
  py::array_t<double> upper_fraction(n), lower_fraction(n);
  py::array_t<std::uint8_t> centre(n);
  for (py::ssize_t k = 0; k < n; ++k) {
    const std::size_t i = std::size_t(k);
    upper_ok.mutable_at(k) = map.upper_ok[i] != 0;
    lower_ok.mutable_at(k) = map.lower_ok[i] != 0;
    upper_fraction.mutable_at(k) = map.upper_fraction[i];
    lower_fraction.mutable_at(k) = map.lower_fraction[i];
    centre.mutable_at(k) = map.centre_collides[i];
  }
  py::dict d;
  d["station"] = map.station;
  d["spacing_mm"] = map.spacing_mm;
  d["points"] = points_array(map.points);
  d["upper_ok"] = upper_ok;
  d["lower_ok"] = lower_ok;
  d["upper_fraction"] = upper_fraction;
  d["lower_fraction"] = lower_fraction;
  d["centre_collides"] = centre;
  d["pairs"] = map.pairs;
  d["colliding"] = map.colliding;
  d["colliding_fraction"] = map.colliding_fraction;
  d["any_free"] = map.any_free;
  Json doc = {{"command", "collision"}, {"design", design.name}};
  doc.update(to_json(map));
  d["summary"] = to_python(doc);
  return d;
}

// --- Pattern --------------------------------------------------------------------------------------

struct PatternArgs {
  std::optional<double> amplitude_mm, amplitude_deg, frequency_hz, duration_s, rate_hz, separation_mm;
  std::optional<std::array<double, 2>> center;
};

/// The design's entry for this station and kind, or the defaults; then the arguments (the rules of
/// `fivebar pattern`'s options, cli/pattern.cpp).
PatternSpec pattern_spec(const Design& design, const Station& s, PatternKind kind, const PatternArgs& a) {
  PatternSpec spec = fivebar::pattern_spec(design, s, kind);  // the design's entry, or the defaults
  if (a.amplitude_mm) {
    if (kind == PatternKind::pivot) throw InputError("amplitude_mm is for stretch, slip and twist; pivot takes amplitude_deg");
    spec.amplitude_mm = *a.amplitude_mm;
  }
  if (a.amplitude_deg || a.frequency_hz) {
    if (kind != PatternKind::pivot) throw InputError("amplitude_deg and frequency_hz are for pattern \"pivot\"");
    if (a.amplitude_deg) spec.pivot_amplitude = *a.amplitude_deg / kDegPerRad;
    if (a.frequency_hz) spec.pivot_frequency_hz = *a.frequency_hz;
  }
  if (a.duration_s) spec.duration_s = *a.duration_s;
  if (a.rate_hz) spec.rate_hz = *a.rate_hz;
  if (a.separation_mm) {
    spec.separation_mm = *a.separation_mm;
    spec.contact_points.reset();  // the contact points follow the separation again
  }
  if (a.center) spec.centre = finite_point(*a.center, "center");
  try {
    spec.validate();
  } catch (const ValidationError& e) {
    throw InputError("pattern " + std::string(to_string(kind)) + ": " + e.what());
  }
  // A sample count the library would allocate without bound is refused here, named.
  if (spec.samples() > 10'000'000) throw InputError("pattern: duration_s * rate_hz gives more than 10^7 samples");
  return spec;
}

py::dict tactor_series(const std::vector<PatternSample>& samples, bool upper) {
  const py::ssize_t n = py::ssize_t(samples.size());
  py::array_t<double> target({n, py::ssize_t(2)}), point({n, py::ssize_t(2)}), theta({n, py::ssize_t(2)}),
      speed({n, py::ssize_t(2)});
  py::array_t<double> lci(n);
  py::array_t<std::uint8_t> status(n);
  auto t = target.mutable_unchecked<2>();
  auto p = point.mutable_unchecked<2>();
  auto th = theta.mutable_unchecked<2>();
  auto sp = speed.mutable_unchecked<2>();
  for (py::ssize_t k = 0; k < n; ++k) {
    const TactorSample& s = upper ? samples[std::size_t(k)].upper : samples[std::size_t(k)].lower;
    t(k, 0) = s.target.x();
    t(k, 1) = s.target.y();
    p(k, 0) = s.point.x();
    p(k, 1) = s.point.y();
    for (int j = 0; j < 2; ++j) {
      th(k, j) = s.theta[std::size_t(j)];
      sp(k, j) = s.joint_speed[std::size_t(j)];
    }
    lci.mutable_at(k) = s.pose.lci;
    status.mutable_at(k) = static_cast<std::uint8_t>(s.status);
  }
  py::dict d;
  d["target_mm"] = target;
  d["point_mm"] = point;
  d["theta"] = theta;
  d["joint_speed"] = speed;
  d["lci"] = lci;
  d["status"] = status;
  return d;
}

py::dict pattern(const Design& design, const std::string& station, const std::string& kind_text,
                 const PatternArgs& args, const std::optional<double>& max_speed_deg_s) {
  const auto kind = parse_pattern_kind(kind_text);
  if (!kind) throw InputError("pattern = '" + kind_text + "': expected stretch, slip, twist or pivot");
  if (max_speed_deg_s && !(*max_speed_deg_s > 0.0 && std::isfinite(*max_speed_deg_s))) {
    throw InputError("max_joint_speed_deg_s must be a positive number of deg/s");
  }
  const Station& s = pair_station_of(design, station);
  const Geometry& g = design_geometry(design);
  const PatternSpec spec = pattern_spec(design, s, *kind, args);
  double max_speed = pattern_joint_speed_limit(design, s);
  if (max_speed_deg_s) max_speed = *max_speed_deg_s / kDegPerRad;
  PatternResult r;
  Interruptible run;
  run.run([&] { r = check_pattern(s, g, spec, max_speed); });

  const py::ssize_t n = py::ssize_t(r.samples.size());
  py::array_t<double> time(n), clearance(n), commanded(n), moved(n);
  for (py::ssize_t k = 0; k < n; ++k) {
    const PatternSample& x = r.samples[std::size_t(k)];
    time.mutable_at(k) = x.time_s;
    clearance.mutable_at(k) = x.clearance_mm.value_or(std::numeric_limits<double>::quiet_NaN());
    commanded.mutable_at(k) = x.commanded_clearance_mm.value_or(std::numeric_limits<double>::quiet_NaN());
    moved.mutable_at(k) = x.moved_mm;
  }
  py::dict d;
  d["station"] = r.station;
  d["pattern"] = std::string(to_string(r.spec.kind));
  d["passed"] = r.passed;
  d["centre"] = xy(r.centre);
  d["max_joint_speed"] = r.max_joint_speed;
  d["t"] = time;
  d["clearance_mm"] = clearance;
  d["commanded_clearance_mm"] = commanded;
  d["moved_mm"] = moved;
  py::dict mechs;
  mechs["lower"] = tactor_series(r.samples, false);
  mechs["upper"] = tactor_series(r.samples, true);
  d["mechanisms"] = mechs;
  py::list names;
  for (std::size_t i = 0; i < r.status_counts.size(); ++i) names.append(std::string(to_string(static_cast<SampleStatus>(i))));
  d["status_names"] = names;
  if (r.first_failure) {
    const PatternFailure& f = *r.first_failure;
    py::dict fd;
    fd["index"] = f.index;
    fd["time_s"] = f.time_s;
    fd["mechanism"] = f.mechanism;
    fd["status"] = std::string(to_string(f.status));
    fd["reason"] = f.reason;
    d["first_failure"] = fd;
  } else {
    d["first_failure"] = py::none();
  }
  Json doc = {{"command", "pattern"}, {"design", design.name}};
  doc.update(to_json(r, false));
  d["summary"] = to_python(doc);
  return d;
}

// --- Replay ---------------------------------------------------------------------------------------

runtime::Config read_runtime_config(const std::string& path, const char* what) {
  try {
    return runtime::load_config_json(path);
  } catch (const runtime::ConfigError& e) {
    throw InputError(std::string(what) + ": " + e.what());
  }
}

/// `fivebar replay LOG --config EXPORTED.json`: the log through a fresh runtime, its duties
/// against the logged ones; also the runtime's duties and statuses per row.
py::dict replay(const std::string& log_path, const std::string& config_path, double tolerance) {
  if (!(tolerance >= 0.0) || !(tolerance <= 2.0)) throw InputError("tolerance must be within [0, 2]");
  const runtime::Config config = read_runtime_config(config_path, "config");
  std::ifstream in(log_path, std::ios::binary);
  if (!in) throw InputError(log_path + ": cannot be read");
  const ReplayLog log = read_replay_log(in, config, log_path);
  ReplayTrace trace;
  const ReplayResult r = replay_log(config, log, tolerance, &trace);
  const py::ssize_t rows = py::ssize_t(log.time_s.size());
  const py::ssize_t joints = rows > 0 ? py::ssize_t(log.duties.front().size()) : 0;
  const py::ssize_t mechs = rows > 0 ? py::ssize_t(trace.statuses.front().size()) : 0;
  py::array_t<double> time(rows), logged({rows, joints}), computed({rows, joints});
  py::array_t<std::uint8_t> status({rows, mechs});
  for (py::ssize_t k = 0; k < rows; ++k) {
    time.mutable_at(k) = log.time_s[std::size_t(k)];
    for (py::ssize_t j = 0; j < joints; ++j) {
      logged.mutable_at(k, j) = log.duties[std::size_t(k)][std::size_t(j)];
      computed.mutable_at(k, j) = trace.duties[std::size_t(k)][std::size_t(j)];
    }
    for (py::ssize_t m = 0; m < mechs; ++m) {
      status.mutable_at(k, m) = static_cast<std::uint8_t>(trace.statuses[std::size_t(k)][std::size_t(m)]);
    }
  }
  py::dict d;
  d["passed"] = r.passed();
  d["rows"] = r.rows;
  d["max_duty_difference"] = r.max_difference;
  d["mismatches"] = r.mismatches;
  py::list joint_names;
  for (const ReplayJoint& j : r.joints) joint_names.append(j.joint);
  d["joints"] = joint_names;
  d["mechanisms"] = py::cast(r.mechanisms);
  d["t"] = time;
  d["logged_duty"] = logged;
  d["runtime_duty"] = computed;
  d["status"] = status;
  Json doc = {{"command", "replay"}, {"design", config.design}, {"mode", "log"}, {"log", log_path},
              {"config", config_path}};
  const Json body = to_json(r);
  for (const auto& [key, value] : body.items()) doc[key] = value;
  d["summary"] = to_python(doc);
  return d;
}

/// `fivebar replay DESIGN --sil`: the runtime closed around the simulator for the station's
/// patterns; each run's log written into `out_dir` (the one folder this writes in).
py::dict replay_sil(const Design& design, const std::string& out_dir, const std::string& station,
                    const std::optional<std::string>& pattern, const std::optional<std::string>& config_path) {
  std::optional<PatternKind> kind;
  if (pattern) {
    kind = parse_pattern_kind(*pattern);
    if (!kind) throw InputError("pattern = '" + *pattern + "': expected stretch, slip, twist or pivot");
  }
  SilRequest request;
  if (!station.empty()) {
    request.stations.push_back(pair_station_of(design, station).name);
  } else {
    for (const Station& s : design.stations) {
      if (s.lower && s.upper) request.stations.push_back(s.name);
    }
    if (request.stations.empty()) throw InputError("design '" + design.name + "' has no station with both mechanisms");
  }
  design_geometry(design);
  request.pattern = kind;
  if (config_path) request.config = std::make_shared<const runtime::Config>(read_runtime_config(*config_path, "config"));
  check_sil_config(design, request, "config " + config_path.value_or(""));  // before the folder exists
  const std::filesystem::path dir(out_dir);
  make_directories(dir);
  const WriteFence fence(dir);
  request.open_log = [&dir](const std::string& name) { return AtomicFile(dir / name); };
  std::vector<SilRun> runs;
  Interruptible run;
  run.run([&] { runs = run_sil(design, request); });
  py::list out;
  Json docs = Json::array();
  bool all_ok = true;
  for (const SilRun& r : runs) {
    all_ok = all_ok && r.ok();
    Json j = to_json(r);
    if (r.simulated()) {
      j["log"] = r.log.generic_string();
      j["config"] = config_path ? *config_path : std::string("the design's export, in memory");
    }
    py::dict d;
    d["station"] = r.station;
    d["reference"] = r.reference;
    d["simulated"] = r.simulated();
    d["ok"] = r.ok();
    d["log"] = r.simulated() ? py::object(py::str(r.log.generic_string())) : py::object(py::none());
    d["figures"] = to_python(j);
    out.append(d);
    docs.push_back(j);
  }
  py::dict d;
  d["ok"] = all_ok;
  d["runs"] = out;
  d["summary"] = to_python(Json{{"command", "replay"}, {"mode", "sil"}, {"design", design.name}, {"runs", docs}});
  return d;
}

// --- Runtime --------------------------------------------------------------------------------------

/// fivebar::runtime::Controller with its configuration, for Python: ConfigError becomes InputError.
class PyController {
 public:
  explicit PyController(const std::string& text_or_path) : controller_(load(text_or_path)) {
    const runtime::Config& c = controller_.config();
    for (const runtime::StationConfig& s : c.stations) {
      for (const runtime::MechanismConfig& m : s.mechanisms) {
        mechanisms_.push_back(s.name + "/" + m.name);
        for (const runtime::JointConfig& j : m.joints) joints_.push_back(j.name);
      }
    }
  }

  py::dict step(const py::object& readings, const py::object& targets_m, const std::string& kind) {
    const std::size_t joints = controller_.joint_count();
    const std::vector<double> r = numbers(readings, "readings", joints, "readings (one per joint, joint order)");
    const std::vector<double> t =
        numbers(targets_m, "targets_m", 2 * controller_.mechanism_count(), "numbers (x, y in m per mechanism)");
    controller_.cycle(r.data(), reading_kind(kind), t.data());
    return state();
  }

  void reset() { controller_.reset(); }
  const std::vector<std::string>& joints() const { return joints_; }
  const std::vector<std::string>& mechanisms() const { return mechanisms_; }
  double loop_rate_hz() const { return controller_.config().loop_rate_hz; }

 private:
  static runtime::Config load(const std::string& text_or_path) {
    try {
      // JSON text starts with '{' (after blanks); anything else is a path.
      const std::size_t first = text_or_path.find_first_not_of(" \t\r\n");
      const bool text = first != std::string::npos && text_or_path[first] == '{';
      if (text) return runtime::parse_config_json(text_or_path, "<config>");
    } catch (const runtime::ConfigError& e) {
      throw InputError(e.what());
    }
    return read_runtime_config(text_or_path, "config");
  }

  static runtime::Reading reading_kind(const std::string& kind) {
    if (kind == "counts") return runtime::Reading::counts;
    if (kind == "volts") return runtime::Reading::volts;
    if (kind == "radians") return runtime::Reading::radians;
    throw InputError("kind = '" + kind + "': expected counts, volts or radians");
  }

  static std::vector<double> numbers(const py::object& given, const char* what, std::size_t n, const char* holds) {
    py::array_t<double, py::array::c_style | py::array::forcecast> a;
    try {
      a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(given);
    } catch (const py::error_already_set&) {
    }
    if (!a || a.ndim() != 1 || std::size_t(a.size()) != n) {
      throw InputError(std::string(what) + ": expected " + std::to_string(n) + " " + holds + ", got " +
                       (a ? std::to_string(a.size()) + " in " + std::to_string(a.ndim()) + " dimensions"
                          : std::string("no array of numbers")));
    }
    return std::vector<double>(a.data(), a.data() + n);
  }

  py::dict state() const {
    const std::size_t m = controller_.mechanism_count();
    const py::ssize_t nm = py::ssize_t(m);
    py::array_t<double> duties(2 * nm);
    std::copy(controller_.duties(), controller_.duties() + 2 * m, duties.mutable_data());
    py::array_t<std::uint8_t> status(nm);
    py::list names;
    py::array_t<double> theta({py::ssize_t(m), py::ssize_t(2)}), follow({py::ssize_t(m), py::ssize_t(2)}),
        command({py::ssize_t(m), py::ssize_t(2)}), point({py::ssize_t(m), py::ssize_t(2)});
    py::array_t<double> moved(nm);
    for (std::size_t k = 0; k < m; ++k) {
      const runtime::MechanismState& s = controller_.mechanism(k);
      status.mutable_at(py::ssize_t(k)) = static_cast<std::uint8_t>(s.status);
      names.append(runtime::to_string(s.status));
      for (std::size_t j = 0; j < 2; ++j) {
        theta.mutable_at(py::ssize_t(k), py::ssize_t(j)) = s.theta_measured[j];
        follow.mutable_at(py::ssize_t(k), py::ssize_t(j)) = s.theta_follow[j];
        command.mutable_at(py::ssize_t(k), py::ssize_t(j)) = s.theta_command[j];
        point.mutable_at(py::ssize_t(k), py::ssize_t(j)) = s.point_command[j];
      }
      moved.mutable_at(py::ssize_t(k)) = s.moved;
    }
    py::dict d;
    d["duties"] = duties;
    d["status"] = status;
    d["status_names"] = names;
    d["theta_measured"] = theta;
    d["theta_follow"] = follow;
    d["theta_command"] = command;
    d["point_command_m"] = point;
    d["moved_m"] = moved;
    return d;
  }

  runtime::Controller controller_;
  std::vector<std::string> joints_;
  std::vector<std::string> mechanisms_;
};

}  // namespace

void register_device(py::module_& m) {
  m.def("_collision", &collision_pair, py::arg("design"), py::arg("station"), py::arg("upper"), py::arg("lower"));
  m.def("_collision_map", &collision_map_dict, py::arg("design"), py::arg("station"), py::arg("spacing_mm"));
  m.def("_pattern",
        [](const Design& d, const std::string& station, const std::string& kind, std::optional<double> amplitude_mm,
           std::optional<double> amplitude_deg, std::optional<double> frequency_hz, std::optional<double> duration_s,
           std::optional<double> rate_hz, std::optional<double> separation_mm,
           std::optional<std::array<double, 2>> center, std::optional<double> max_speed_deg_s) {
          PatternArgs a{amplitude_mm, amplitude_deg, frequency_hz, duration_s, rate_hz, separation_mm, center};
          return pattern(d, station, kind, a, max_speed_deg_s);
        });
  m.def("_replay_sil", &replay_sil, py::arg("design"), py::arg("out_dir"), py::arg("station"), py::arg("pattern"),
        py::arg("config"));
  m.def("_replay", &replay, py::arg("log"), py::arg("config"), py::arg("tolerance"));
  py::class_<PyController>(m, "_Controller")
      .def(py::init<const std::string&>(), py::arg("config"))
      .def("step", &PyController::step, py::arg("readings"), py::arg("targets_m"), py::arg("kind"))
      .def("reset", &PyController::reset)
      .def_property_readonly("joints", &PyController::joints)
      .def_property_readonly("mechanisms", &PyController::mechanisms)
      .def_property_readonly("loop_rate_hz", &PyController::loop_rate_hz);
}

}  // namespace fivebar::python
