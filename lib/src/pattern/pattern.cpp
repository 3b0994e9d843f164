// Skin-deformation patterns: paths, per-sample checks with the priority rule, trajectory CSV and
// JSON (fivebar/pattern.hpp). The picture is in lib/src/pattern/pattern_plot.cpp.

#include "fivebar/format.hpp"
#include "fivebar/pattern.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "fivebar/error.hpp"

namespace fivebar {

namespace {

constexpr double kPi = std::numbers::pi;
using format::kDegPerRad;
constexpr double kInf = std::numeric_limits<double>::infinity();

/// Smooth ramp from 0 to 1 over [0, T], at rest at both ends.
double ramp(double t, double T) { return 0.5 * (1.0 - std::cos(kPi * std::clamp(t / T, 0.0, 1.0))); }

Vec2 rotate(const Vec2& v, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

/// Angle difference reduced to (-pi, pi].
double wrap_pi(double d) {
  d = std::remainder(d, 2.0 * kPi);
  return d <= -kPi ? d + 2.0 * kPi : d;
}

std::string num(double v, int digits = 3) { return format::fixed(v, digits); }

std::string point_text(const Vec2& p) { return "(" + num(p.x()) + ", " + num(p.y()) + ")"; }

/// Shortest text that reads back as the same double (CSV).
std::string exact(double v) { return format::shortest(v); }

/// The pose's own problem, ignoring collisions and speed: the precedence of SampleStatus.
SampleStatus pose_status(const Mechanism& m, const Pose& pose) {
  if (pose.status == Status::unreachable) return SampleStatus::unreachable;
  if (pose.status != Status::ok) return SampleStatus::singular;
  if (m.assembly_mode != AssemblyMode::Any && pose.assembly != static_cast<std::int8_t>(m.assembly_mode)) {
    return SampleStatus::wrong_assembly;
  }
  if (!pose.within_joint_limits) return SampleStatus::outside_joint_limits;
  return SampleStatus::ok;
}

}  // namespace

std::string_view to_string(SampleStatus status) {
  switch (status) {
    case SampleStatus::ok: return "ok";
    case SampleStatus::unreachable: return "unreachable";
    case SampleStatus::singular: return "singular";
    case SampleStatus::wrong_assembly: return "wrong_assembly";
    case SampleStatus::outside_joint_limits: return "outside_joint_limits";
    case SampleStatus::no_collision_free_point: return "no_collision_free_point";
    case SampleStatus::collision_moved: return "collision_moved";
    case SampleStatus::low_lci: return "low_lci";
    case SampleStatus::too_fast: return "too_fast";
  }
  return "ok";
}

PatternPath pattern_path(const PatternSpec& spec, const Vec2& default_centre) {
  PatternPath path;
  path.kind = spec.kind;
  path.centre = spec.centre.value_or(default_centre);
  const Vec2 c = path.centre;
  const double s = spec.separation_mm;
  const double a = spec.amplitude_mm;
  const double T = spec.duration_s;
  const std::size_t n = spec.samples();
  path.time_s.reserve(n);
  path.upper.reserve(n);
  path.lower.reserve(n);
  std::array<Vec2, 2> contacts{Vec2(0.0, 0.5 * s), Vec2(0.0, -0.5 * s)};
  if (spec.contact_points) contacts = *spec.contact_points;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / spec.rate_hz;
    const double u = ramp(t, T);
    Vec2 up = c, low = c;
    switch (spec.kind) {
      case PatternKind::stretch:
        up = c + Vec2(a * u, 0.5 * s);
        low = c - Vec2(a * u, 0.5 * s);
        break;
      case PatternKind::slip:
        up = c + Vec2(0.0, 0.5 * s + 0.5 * a - a * u);
        low = c + Vec2(0.0, -0.5 * s + 0.5 * a - a * u);
        break;
      case PatternKind::twist: {
        const double angle = a * u / (0.5 * s);
        up = c + rotate(Vec2(0.0, 0.5 * s), angle);
        low = c + rotate(Vec2(0.0, -0.5 * s), angle);
        break;
      }
      case PatternKind::pivot: {
        const double phi = spec.pivot_amplitude * std::sin(2.0 * kPi * spec.pivot_frequency_hz * t);
        up = c + rotate(contacts[0], phi);
        low = c + rotate(contacts[1], phi);
        break;
      }
    }
    path.time_s.push_back(t);
    path.upper.push_back(up);
    path.lower.push_back(low);
  }
  return path;
}

PatternResult check_pattern(const Station& station, const Geometry& g, const PatternSpec& spec, double max_joint_speed,
                            const PriorityOptions& priority) {
  if (!station.lower || !station.upper) {
    throw InputError("station " + station.name + ": patterns need both a lower and an upper mechanism");
  }
  try {
    spec.validate();
  } catch (const ValidationError& e) {
    throw InputError("pattern " + std::string(to_string(spec.kind)) + ": " + e.what());
  }
  if (!(max_joint_speed > 0.0) || !std::isfinite(max_joint_speed)) {
    throw InputError("max joint speed must be a positive number");
  }
  const Mechanism& up = *station.upper;
  const Mechanism& low = *station.lower;
  const PatternPath path = pattern_path(spec, station.target.center);

  PatternResult r;
  r.station = station.name;
  r.spec = spec;
  r.centre = path.centre;
  r.max_joint_speed = max_joint_speed;
  r.min_type1_distance_mm = {kInf, kInf};
  r.min_clearance_mm = kInf;
  r.min_commanded_clearance_mm = kInf;
  r.samples.reserve(path.time_s.size());

  const auto fail_reason = [&](const std::string& name, const Mechanism& m, const TactorSample& s,
                               const PatternSample& sample) -> std::string {
    const std::string who = name + " tactor at " + point_text(s.point);
    switch (s.status) {
      case SampleStatus::ok: return "";
      case SampleStatus::unreachable:
        return who + " is unreachable in working mode " + to_string(m.working_mode);
      case SampleStatus::singular: return who + " is " + std::string(to_string(s.pose.status));
      case SampleStatus::wrong_assembly:
        return who + " is on the wrong side of its distal links (assembly mode " + to_string(m.assembly_mode) + ")";
      case SampleStatus::outside_joint_limits:
        return who + ": motor angles (" + num(angle_deg(s.pose.theta1), 2) + ", " + num(angle_deg(s.pose.theta2), 2) +
               ") deg are outside the joint limits";
      case SampleStatus::no_collision_free_point:
        return "lower tactor at " + point_text(s.target) + " collides with the upper mechanism (" +
               sample.closest_pair + ") and no collision-free point is within its reach";
      case SampleStatus::collision_moved:
        return "lower tactor at " + point_text(s.target) + " collides with the upper mechanism (" +
               sample.closest_pair + ", clearance " + num(sample.clearance_mm.value_or(0.0)) +
               " mm): the priority rule moved it by " + num(sample.moved_mm) + " mm to " + point_text(s.point);
      case SampleStatus::low_lci:
        return who + ": LCI " + num(s.pose.lci, 4) + " is below min_lci " + num(m.min_lci, 4);
      case SampleStatus::too_fast: {
        const int motor = s.joint_speed[0] >= s.joint_speed[1] ? 0 : 1;
        return name + " theta" + std::to_string(motor + 1) + " would turn at " +
               num(s.joint_speed[motor] * kDegPerRad, 1) + " deg/s (limit " + num(max_joint_speed * kDegPerRad, 1) +
               " deg/s)";
      }
    }
    return "";
  };

  for (std::size_t k = 0; k < path.time_s.size(); ++k) {
    PatternSample sample;
    sample.time_s = path.time_s[k];
    const PriorityResult pr = apply_priority(up, low, g, path.upper[k], path.lower[k], priority);
    sample.upper.target = path.upper[k];
    sample.upper.point = path.upper[k];
    sample.upper.pose = pr.upper;
    sample.lower.target = path.lower[k];
    sample.lower.point = pr.lower_point;
    sample.lower.pose = pr.lower;
    sample.moved_mm = pr.moved_mm;
    if (pr.before) {
      sample.clearance_mm = pr.before->min_clearance_mm;
      sample.closest_pair = pr.before->closest.name();
    }
    if (pr.after) sample.commanded_clearance_mm = pr.after->min_clearance_mm;

    const Mechanism* mechs[2] = {&up, &low};
    TactorSample* tactors[2] = {&sample.upper, &sample.lower};
    for (int i = 0; i < 2; ++i) {
      const Mechanism& m = *mechs[i];
      TactorSample& s = *tactors[i];
      s.status = pose_status(m, s.pose);
      if (i == 1 && s.status == SampleStatus::ok) {
        if (pr.status == PriorityStatus::no_free_point) s.status = SampleStatus::no_collision_free_point;
        if (pr.status == PriorityStatus::moved) s.status = SampleStatus::collision_moved;
      }
      if (s.status == SampleStatus::ok && s.pose.lci < m.min_lci) s.status = SampleStatus::low_lci;
      // Continuous angles and speeds against the previous sample.
      if (s.pose.status != Status::unreachable) {
        const TactorSample* prev = nullptr;
        if (k > 0) prev = i == 0 ? &r.samples.back().upper : &r.samples.back().lower;
        const std::array<double, 2> raw{s.pose.theta1, s.pose.theta2};
        for (int j = 0; j < 2; ++j) {
          if (prev != nullptr && prev->pose.status != Status::unreachable) {
            const double d = wrap_pi(raw[j] - (j == 0 ? prev->pose.theta1 : prev->pose.theta2));
            s.theta[j] = prev->theta[j] + d;
            s.joint_speed[j] = std::fabs(d) * spec.rate_hz;
          } else {
            s.theta[j] = angle_deg(raw[j]) / kDegPerRad;
          }
          if (s.joint_speed[j] > r.peak_joint_speed) {
            r.peak_joint_speed = s.joint_speed[j];
            r.peak_joint_motor = std::string(i == 0 ? "upper" : "lower") + " theta" + std::to_string(j + 1);
            r.peak_joint_time_s = sample.time_s;
          }
        }
        if (s.status == SampleStatus::ok && std::max(s.joint_speed[0], s.joint_speed[1]) > max_joint_speed) {
          s.status = SampleStatus::too_fast;
        }
        r.min_lci[i] = std::min(r.min_lci[i], s.pose.lci);
        r.min_type1_distance_mm[i] = std::min(r.min_type1_distance_mm[i], s.pose.type1_distance_mm);
      } else {
        r.min_lci[i] = 0.0;
      }
      ++r.status_counts[static_cast<std::size_t>(s.status)];
    }

    if (sample.clearance_mm) r.min_clearance_mm = std::min(r.min_clearance_mm, *sample.clearance_mm);
    if (sample.commanded_clearance_mm) {
      r.min_commanded_clearance_mm = std::min(r.min_commanded_clearance_mm, *sample.commanded_clearance_mm);
    }
    if (sample.moved_mm > 0.0) {
      ++r.moved_samples;
      r.max_moved_mm = std::max(r.max_moved_mm, sample.moved_mm);
    }
    if (!r.first_failure) {
      for (int i = 0; i < 2; ++i) {
        const TactorSample& s = *tactors[i];
        if (s.status == SampleStatus::ok) continue;
        const std::string name = i == 0 ? "upper" : "lower";
        r.first_failure = PatternFailure{k, sample.time_s, name, s.status, fail_reason(name, *mechs[i], s, sample)};
        break;
      }
    }
    r.samples.push_back(std::move(sample));
  }
  for (int i = 0; i < 2; ++i) {
    if (!std::isfinite(r.min_type1_distance_mm[i])) r.min_type1_distance_mm[i] = 0.0;
  }
  r.passed = !r.first_failure.has_value();
  return r;
}

// ---------------------------------------------------------------------------------------------
// Output

const char* const kTrajectoryHeader =
    "time_s,station,mechanism,theta1_deg,theta2_deg,x_mm,y_mm,status,target_x_mm,target_y_mm,lci";

void write_trajectory_csv(std::ostream& out, const PatternResult& result) {
  out << kTrajectoryHeader << "\n";
  for (const PatternSample& sample : result.samples) {
    const std::pair<const char*, const TactorSample*> rows[2] = {{"upper", &sample.upper}, {"lower", &sample.lower}};
    for (const auto& [name, s] : rows) {
      out << exact(sample.time_s) << "," << result.station << "," << name << ",";
      if (s->pose.status != Status::unreachable) {
        out << exact(s->theta[0] * kDegPerRad) << "," << exact(s->theta[1] * kDegPerRad) << ",";
      } else {
        out << ",,";
      }
      out << exact(s->point.x()) << "," << exact(s->point.y()) << "," << to_string(s->status) << ","
          << exact(s->target.x()) << "," << exact(s->target.y()) << ",";
      if (s->pose.status != Status::unreachable) out << exact(s->pose.lci);
      out << "\n";
    }
  }
}

namespace {

Json xy(const Vec2& p) { return Json::array({p.x(), p.y()}); }
Json finite_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json spec_json(const PatternSpec& spec, const Vec2& centre) {
  Json j;
  j["kind"] = std::string(to_string(spec.kind));
  if (spec.kind == PatternKind::pivot) {
    j["amplitude_deg"] = spec.pivot_amplitude * kDegPerRad;
    j["frequency_hz"] = spec.pivot_frequency_hz;
    std::array<Vec2, 2> contacts{Vec2(0.0, 0.5 * spec.separation_mm), Vec2(0.0, -0.5 * spec.separation_mm)};
    if (spec.contact_points) contacts = *spec.contact_points;
    j["contact_points_mm"] = Json::array({xy(contacts[0]), xy(contacts[1])});
  } else {
    j["amplitude_mm"] = spec.amplitude_mm;
  }
  j["duration_s"] = spec.duration_s;
  j["rate_hz"] = spec.rate_hz;
  j["samples"] = spec.samples();
  j["center_mm"] = xy(centre);
  j["separation_mm"] = spec.separation_mm;
  return j;
}

Json with_mechanism(const char* name, const Json& rest) {
  Json j = {{"mechanism", name}};
  j.update(rest);
  return j;
}

Json tactor_json(const TactorSample& s) {
  Json j;
  j["status"] = std::string(to_string(s.status));
  j["target_mm"] = xy(s.target);
  j["point_mm"] = xy(s.point);
  if (s.pose.status != Status::unreachable) {
    j["theta_deg"] = Json::array({s.theta[0] * kDegPerRad, s.theta[1] * kDegPerRad});
    j["joint_speed_deg_s"] = Json::array({s.joint_speed[0] * kDegPerRad, s.joint_speed[1] * kDegPerRad});
    j["lci"] = s.pose.lci;
  } else {
    j["theta_deg"] = nullptr;
    j["joint_speed_deg_s"] = nullptr;
    j["lci"] = nullptr;
  }
  return j;
}

}  // namespace

PatternSpec pattern_spec(const Design& design, const Station& station, PatternKind kind) {
  PatternSpec spec;
  spec.kind = kind;
  if (kind == PatternKind::pivot) spec.duration_s = 2.0;
  if (const PatternSettings* settings = design.get<PatternSettings>()) {
    spec.rate_hz = settings->rate_hz;
    for (const PatternSpec& p : settings->for_station(station.name)) {
      if (p.kind == kind) spec = p;
    }
  }
  return spec;
}

Json to_json(const PatternResult& r, bool samples) {
  Json j;
  j["station"] = r.station;
  j["pattern"] = std::string(to_string(r.spec.kind));
  j["passed"] = r.passed;
  j["spec"] = spec_json(r.spec, r.centre);
  j["max_joint_speed_deg_s"] = r.max_joint_speed * kDegPerRad;
  if (r.first_failure) {
    const PatternFailure& f = *r.first_failure;
    j["first_failure"] = {{"index", f.index},
                          {"time_s", f.time_s},
                          {"mechanism", f.mechanism},
                          {"status", std::string(to_string(f.status))},
                          {"reason", f.reason}};
  } else {
    j["first_failure"] = nullptr;
  }
  Json worst;
  worst["mechanisms"] = Json::array({
      {{"mechanism", "lower"}, {"min_lci", r.min_lci[1]}, {"min_type1_distance_mm", r.min_type1_distance_mm[1]}},
      {{"mechanism", "upper"}, {"min_lci", r.min_lci[0]}, {"min_type1_distance_mm", r.min_type1_distance_mm[0]}}});
  worst["min_clearance_mm"] = finite_or_null(r.min_clearance_mm);
  worst["min_commanded_clearance_mm"] = finite_or_null(r.min_commanded_clearance_mm);
  worst["max_moved_mm"] = r.max_moved_mm;
  worst["moved_samples"] = r.moved_samples;
  worst["peak_joint_speed_deg_s"] = r.peak_joint_speed * kDegPerRad;
  worst["peak_joint_motor"] = r.peak_joint_motor.empty() ? Json(nullptr) : Json(r.peak_joint_motor);
  worst["peak_joint_time_s"] = r.peak_joint_time_s;
  j["worst"] = worst;
  Json counts = Json::object();
  for (std::size_t i = 0; i < r.status_counts.size(); ++i) {
    if (r.status_counts[i] > 0) counts[std::string(to_string(static_cast<SampleStatus>(i)))] = r.status_counts[i];
  }
  j["status_counts"] = counts;
  if (samples) {
    Json list = Json::array();
    for (const PatternSample& s : r.samples) {
      list.push_back({{"time_s", s.time_s},
                      {"mechanisms", Json::array({with_mechanism("lower", tactor_json(s.lower)),
                                                  with_mechanism("upper", tactor_json(s.upper))})},
                      {"clearance_mm", s.clearance_mm ? finite_or_null(*s.clearance_mm) : Json(nullptr)},
                      {"moved_mm", s.moved_mm}});
    }
    j["samples"] = list;
  }
  return j;
}

}  // namespace fivebar
