// fivebar::runtime (fivebar/runtime/controller.hpp): against the library's own kinematics and
// collision model (an independent formulation in mm on Eigen), a hand-stepped PID, the export read
// back by the runtime's JSON reader, the simulator's recorded loop (bit for bit), its refusal of
// bad configurations and measurements, and the real-time properties (no allocation in 10^6 cycles,
// determinism).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <limits>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <initializer_list>
#include <random>
#include <string>
#include <type_traits>

#include "fivebar/collision.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/runtime.hpp"
#include "fivebar/runtime/linux_io.hpp"
#include "paper.hpp"
#include "process.hpp"

// --- Allocation counter: every global operator new of this executable --------------------------
namespace {
std::atomic<long long> g_allocations{0};
}
void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
// The nothrow forms too (std::stable_sort's temporary buffer takes one): every form allocates
// with malloc and frees with free, so none is paired with another allocator's (ASan checks it).
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  ++g_allocations;
  return std::malloc(n ? n : 1);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  ++g_allocations;
  return std::malloc(n ? n : 1);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

namespace fivebar {
namespace {

using ::testing::HasSubstr;
namespace rt = fivebar::runtime;

const Design& paper() {
  static const Design d = load_design(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  return d;
}

std::string export_text(const std::vector<std::string>& stations = {}) {
  return render_json(controller_parameters(paper(), stations));
}

rt::Config paper_config() { return rt::parse_config_json(export_text(), "iros2022.json"); }

/// Index of mechanism `name` of `station` in the runtime's order.
std::size_t index_of(const rt::Config& c, const std::string& station, const std::string& name) {
  std::size_t k = 0;
  for (const auto& s : c.stations)
    for (const auto& m : s.mechanisms) {
      if (s.name == station && m.name == name) return k;
      ++k;
    }
  ADD_FAILURE() << station << "/" << name;
  return 0;
}

/// Radians readings that put every mechanism at the IK of `points_mm` (the design's own IK).
struct Scene {
  std::vector<double> readings, targets;
};

Scene at_points(const rt::Config& c, const std::vector<Vec2>& points_mm) {
  Scene s;
  std::size_t k = 0;
  for (const auto& st : c.stations) {
    const Station& station = paper().require_station(st.name);
    for (const auto& m : st.mechanisms) {
      const Mechanism& mech = m.name == "lower" ? *station.lower : *station.upper;
      const Pose pose = ik(mech, points_mm[k]);
      s.readings.push_back(pose.theta1);
      s.readings.push_back(pose.theta2);
      s.targets.push_back(points_mm[k].x() / 1000.0);
      s.targets.push_back(points_mm[k].y() / 1000.0);
      ++k;
    }
  }
  return s;
}

std::vector<Vec2> centres(const rt::Config& c, double separation_mm = 6.0) {
  std::vector<Vec2> p;
  for (const auto& st : c.stations) {
    const Vec2 centre = paper().require_station(st.name).target.center;
    for (const auto& m : st.mechanisms) p.push_back(centre + Vec2(0.0, (m.name == "lower" ? -0.5 : 0.5) * separation_mm));
  }
  return p;
}

TEST(Runtime, ReadsTheExportAndRefusesNothingOfIt) {
  const rt::Config c = paper_config();
  EXPECT_EQ(c.design, "iros2022");
  EXPECT_EQ(c.stations.size(), paper().stations.size());
  EXPECT_EQ(c.mechanism_count(), 4u);
  EXPECT_TRUE(c.collision.checked);
  const ControllerSettings& ctl = *paper().get<ControllerSettings>();
  EXPECT_EQ(c.loop_rate_hz, ctl.loop_rate_hz);
  EXPECT_EQ(c.joint_margin, ctl.joint_margin);
  EXPECT_EQ(c.volts_per_count, (ctl.adc_range_v[1] - ctl.adc_range_v[0]) / 65536.0);
  const Mechanism& low = *paper().require_station("index").lower;
  const rt::MechanismConfig& m = c.stations[0].mechanisms[0];
  EXPECT_EQ(m.name, "lower");
  EXPECT_EQ(m.L[2], low.L[2] / 1000.0);  // bit for bit: the export's shortest round-trip text
  EXPECT_EQ(m.joints[0].name, "index_lower_theta1");
  EXPECT_EQ(m.joints[0].gains.p, ctl.joint("index", "lower", 1).pid.kp);
}

TEST(Runtime, CommandsTheDesignsInverseKinematicsAtRandomReachablePoints) {
  const rt::Config c = paper_config();
  rt::Controller ctl(c);
  std::mt19937_64 rng(testing::test_seed());
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<Vec2> pts;
    for (const auto& st : c.stations) {
      const Ellipse& e = paper().require_station(st.name).target;
      for (const auto& mech : st.mechanisms) {
        (void)mech;
        pts.push_back(e.center + Vec2(0.5 * e.axes.x() * u(rng), 0.5 * e.axes.y() * u(rng)));
      }
    }
    ctl.reset();
    const Scene s = at_points(c, centres(c));
    std::vector<double> targets(s.targets.size());
    for (std::size_t k = 0; k < pts.size(); ++k) targets[2 * k] = pts[k].x() / 1000, targets[2 * k + 1] = pts[k].y() / 1000;
    ctl.cycle(s.readings.data(), rt::Reading::radians, targets.data());
    std::size_t k = 0;
    for (const auto& st : c.stations) {
      const Station& station = paper().require_station(st.name);
      for (const auto& mc : st.mechanisms) {
        const Mechanism& mech = mc.name == "lower" ? *station.lower : *station.upper;
        const rt::MechanismState& ms = ctl.mechanism(k);
        const Pose pose = ik(mech, pts[k]);
        SCOPED_TRACE(st.name + "/" + mc.name + " at " + std::to_string(pts[k].x()) + ", " + std::to_string(pts[k].y()));
        if (ms.status == rt::Status::ok && usable(mech, pose)) {
          // Same angle modulo a turn, to the accuracy of the closed form at this scale.
          for (int j = 0; j < 2; ++j) {
            const double d = std::remainder(ms.theta_command[std::size_t(j)] - (j ? pose.theta2 : pose.theta1), 2 * M_PI);
            EXPECT_LT(std::abs(d), 1e-12);
          }
          ++checked;
        }
        for (double v : {ms.duty[0], ms.duty[1], ms.point_command[0], ms.point_command[1]}) EXPECT_TRUE(std::isfinite(v));
        ++k;
      }
    }
  }
  EXPECT_GT(checked, 400);
}

TEST(Runtime, MeasuredPointsAreTheDesignsForwardKinematics) {
  const rt::Config c = paper_config();
  rt::Controller ctl(c);
  const std::vector<Vec2> pts = centres(c, 7.0);
  const Scene s = at_points(c, pts);
  ctl.cycle(s.readings.data(), rt::Reading::radians, s.targets.data());
  for (std::size_t k = 0; k < pts.size(); ++k) {
    ASSERT_TRUE(ctl.mechanism(k).measured_pose);
    EXPECT_NEAR(ctl.mechanism(k).point_measured[0] * 1000, pts[k].x(), 1e-9);
    EXPECT_NEAR(ctl.mechanism(k).point_measured[1] * 1000, pts[k].y(), 1e-9);
    // At the reference: zero error, zero duty.
    EXPECT_NEAR(ctl.mechanism(k).duty[0], 0.0, 1e-9);
  }
  // The measured clearance is the library's (fivebar/collision.hpp interference).
  const Station& st = paper().require_station("index");
  const Interference in = interference(*st.upper, ik(*st.upper, pts[1]), *st.lower, ik(*st.lower, pts[0]), *paper().get<Geometry>());
  ASSERT_TRUE(ctl.station(0).checked);
  EXPECT_NEAR(ctl.station(0).measured_clearance * 1000, in.min_clearance_mm, 1e-9);
  EXPECT_EQ(ctl.station(0).measured_collision, in.collides);
}

TEST(Runtime, ThePriorityRuleMovesTheLowerTargetToAFreePointAsCloseAsTheLibrarysSearch) {
  const rt::Config c = paper_config();
  rt::Controller ctl(c);
  const Station& st = paper().require_station("index");
  const Geometry& g = *paper().get<Geometry>();
  const std::size_t lo = index_of(c, "index", "lower"), up = index_of(c, "index", "upper");
  int moved = 0;
  for (double sep : {0.0, 1.0, 2.0, 3.0}) {
    SCOPED_TRACE(sep);
    std::vector<Vec2> pts = centres(c, 8.0);
    pts[up] = st.target.center + Vec2(0.0, 0.5 * sep);
    pts[lo] = st.target.center - Vec2(0.0, 0.5 * sep);
    const Scene s = at_points(c, centres(c, 8.0));
    std::vector<double> targets = s.targets;
    for (std::size_t k : {lo, up}) targets[2 * k] = pts[k].x() / 1000, targets[2 * k + 1] = pts[k].y() / 1000;
    ctl.reset();
    ctl.cycle(s.readings.data(), rt::Reading::radians, targets.data());
    const PriorityResult ref = apply_priority(*st.upper, *st.lower, g, pts[up], pts[lo]);
    const rt::MechanismState& l = ctl.mechanism(lo);
    EXPECT_EQ(ctl.mechanism(up).status, rt::Status::ok);
    if (ref.status == PriorityStatus::moved) {
      ASSERT_EQ(l.status, rt::Status::moved_by_priority);
      ++moved;
      const Vec2 p(l.point_command[0] * 1000, l.point_command[1] * 1000);
      // Free by the library's exact check, and no farther than its search's point plus the ray
      // spacing's chord (32 rays: 1 - cos(pi / 32) = 0.5 %) and its tolerance.
      const Interference after = interference(*st.upper, ik(*st.upper, pts[up]), *st.lower, ik(*st.lower, p), g);
      EXPECT_FALSE(after.collides) << after.min_clearance_mm;
      EXPECT_NEAR(l.moved * 1000, (p - pts[lo]).norm(), 1e-9);
      EXPECT_LE(l.moved * 1000, ref.moved_mm * 1.01 + 1e-3);
      EXPECT_GE(l.moved * 1000, ref.moved_mm - 1e-3);
      for (double d : l.duty) EXPECT_TRUE(std::isfinite(d));
    } else {
      EXPECT_EQ(l.status, rt::Status::ok);
    }
  }
  EXPECT_GT(moved, 0);
}

/// The runtime's former priority rule, kept as the reference of its replacement: 32 rays from the
/// lower target, rings 0.025 length scales apart up to 40 rings, stopping at the first ring with a
/// free point; the free rays of that ring and the next bisected 16 times (1824 probes at most).
/// Written on the library's kinematics and outlines (mm, Eigen): the lower tactor at q is free when
/// its pose is usable and its outline clears the upper's. The distance moved, or -1 with none.
double ring_search(const Mechanism& upper, const Vec2& upper_target, const Mechanism& lower, const Vec2& origin,
                   const Geometry& g) {
  const auto up = link_outline(upper, ik(upper, upper_target), g);
  const auto free = [&](const Vec2& q) {
    const Pose p = ik(lower, q);
    return usable(lower, p) && min_clearance(up, link_outline(lower, p, g), g.min_clearance) >= g.min_clearance;
  };
  const int rays = 32, rings = 40, bisections = 16;
  const double h = 0.025 * lower.length_scale();
  const auto ray = [&](int j) { return Vec2(std::cos(2 * M_PI * j / rays), std::sin(2 * M_PI * j / rays)); };
  std::vector<int> free_k(rays, 0), free_k1(rays, 0);
  int first = -1;
  for (int k = 1; k <= rings && first < 0; ++k) {
    for (int j = 0; j < rays; ++j) free_k[j] = free(origin + k * h * ray(j));
    if (std::count(free_k.begin(), free_k.end(), 1) > 0) first = k;
  }
  if (first < 0) return -1.0;
  for (int j = 0; j < rays; ++j) free_k1[j] = !free_k[j] && free(origin + (first + 1) * h * ray(j));
  double best = 1e300;
  for (int j = 0; j < rays; ++j) {
    if (!free_k[j] && !free_k1[j]) continue;
    double lo = free_k[j] ? (first - 1) * h : first * h, hi = lo + h;
    for (int b = 0; b < bisections; ++b) (free(origin + 0.5 * (lo + hi) * ray(j)) ? hi : lo) = 0.5 * (lo + hi);
    best = std::min(best, hi);
  }
  return best;
}

/// One cycle from rest, every joint at its pose for the station centres 8 mm apart, with the
/// reference points of the mechanisms `moved` at `pts` (mm) and the others at those centres; the
/// state of the first of `moved`.
const rt::MechanismState& cycle_from_rest(rt::Controller& ctl, const rt::Config& c, const std::vector<Vec2>& pts,
                                          std::initializer_list<std::size_t> moved) {
  const Scene s = at_points(c, centres(c, 8.0));
  std::vector<double> targets = s.targets;
  for (std::size_t k : moved) targets[2 * k] = pts[k].x() / 1000, targets[2 * k + 1] = pts[k].y() / 1000;
  ctl.reset();
  ctl.cycle(s.readings.data(), rt::Reading::radians, targets.data());
  return ctl.mechanism(*moved.begin());
}

// The closed-form priority rule against the probe search it replaced (ring_search above, on the
// library's kinematics and outlines) on random colliding pairs about both stations' centres: every
// moved target is free by the library's exact check and usable, and no farther from the target
// than the reference's point plus kTol = 2.5e-4 length scales (4 um here: both rules bisect the
// last step of a ray, and the new one's conservative advance assumes the outline's speed at the
// blocked point, so where that speed grows along a step it can step over a free point that close). The library's denser search (apply_priority: 256 rays
// and a golden-section refinement of the angle) decides which pairs collide; its distances are
// quoted (the rays of both rules miss boundaries between them that only the links draw).
TEST(Runtime, ThePriorityRuleIsNoWorseThanTheProbeSearchOnRandomCollisions) {
#ifdef FIVEBAR_SANITIZE
  const int cases = 30;
#else
  const int cases = 300;
#endif
  const rt::Config c = paper_config();
  rt::Controller ctl(c);
  const Geometry& g = *paper().get<Geometry>();
  std::mt19937_64 rng(testing::test_seed());
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int moved = 0, closer = 0, compared = 0;
  double worst = -1e300, worst_dense = 0.0;
  for (int n = 0; n < cases; ++n) {
    const std::string name = n % 2 ? "thumb" : "index";
    const Station& st = paper().require_station(name);
    const std::size_t lo = index_of(c, name, "lower"), up = index_of(c, name, "upper");
    std::vector<Vec2> pts = centres(c, 8.0);
    pts[up] = st.target.center + 0.5 * Vec2(st.target.axes.x() * u(rng), st.target.axes.y() * u(rng));
    pts[lo] = pts[up] + 4.0 * Vec2(u(rng), u(rng));
    const PriorityResult dense = apply_priority(*st.upper, *st.lower, g, pts[up], pts[lo]);
    if (dense.status == PriorityStatus::upper_unusable || dense.status == PriorityStatus::lower_unusable) continue;
    const rt::MechanismState& l = cycle_from_rest(ctl, c, pts, {lo, up});
    SCOPED_TRACE(::testing::Message() << name << " upper " << pts[up].transpose() << " lower " << pts[lo].transpose());
    ++compared;
    ASSERT_EQ(ctl.mechanism(up).status, rt::Status::ok);
    if (dense.status == PriorityStatus::clear) {
      EXPECT_EQ(l.status, rt::Status::ok);
      continue;
    }
    ASSERT_EQ(dense.status, PriorityStatus::moved) << dense.reason;
    const double ref = ring_search(*st.upper, pts[up], *st.lower, pts[lo], g);
    ASSERT_GT(ref, 0.0);
    EXPECT_EQ(l.status, rt::Status::moved_by_priority);
    if (l.status != rt::Status::moved_by_priority) continue;
    ++moved;
    const Vec2 p(l.point_command[0] * 1000, l.point_command[1] * 1000);
    const Interference after = interference(*st.upper, ik(*st.upper, pts[up]), *st.lower, ik(*st.lower, p), g);
    EXPECT_FALSE(after.collides) << after.min_clearance_mm;
    EXPECT_TRUE(usable(*st.lower, ik(*st.lower, p)));
    EXPECT_NEAR(l.moved * 1000, (p - pts[lo]).norm(), 1e-9);
    const double kTol = 2.5e-4 * st.lower->length_scale();
    EXPECT_LE(l.moved * 1000, ref + kTol) << "reference " << ref << " mm, dense " << dense.moved_mm << " mm";
    worst = std::max(worst, l.moved * 1000 - ref);
    worst_dense = std::max(worst_dense, l.moved * 1000 / dense.moved_mm - 1);
    closer += l.moved * 1000 < ref - kTol;
  }
  std::printf("[priority] %d cases, %d moved, %d closer than the reference by more than its resolution, largest excess "
              "over it %.3g mm, over the dense search %.2f %%\n",
              compared, moved, closer, worst, 100 * worst_dense);
  EXPECT_GT(moved, compared / 4);
}

// Random crossings (issue 46): per station, pairs of targets drawn over the station's target area
// whose outlines collide (the library's exact check), the lower one anywhere within 8 mm of the
// upper. The library's dense search (apply_priority: 256 rays, rings 0.01 length scales apart up to
// the lower mechanism's reach, golden-section refinement of the angle) is the brute-force
// reference: wherever it finds a free point within the documented search radius
// (kPrioritySearchRadiusRel length scales) the runtime moves the lower target (never stops it),
// to a point free by the library's exact check, no farther than kPriorityDistanceFactor times the
// reference's distance plus the reference's own resolution (one ring). FIVEBAR_PRIORITY_PAIRS sets
// the pairs per station: 500 by default (about 75 s), 10^4 in ctest runtime_priority_random (label
// long, about 25 min of CPU).
// docs/runtime.md "Priority rule": the radius (lower mechanism's length scales) within which the
// rule never stops the lower mechanism while the dense search finds a free point (it searches up to
// 1 length scale; beyond 0.5 its rings are too sparse to promise it), and the factor stated for the
// distance at the 99th percentile (against the reference's distance plus one of its rings).
constexpr double kSearchRadiusRel = 0.5;
constexpr double kDistanceFactor = 1.5;

TEST(Runtime, ThePriorityRuleNeverStopsWhereTheDenseSearchFindsAFreePoint) {
#ifdef FIVEBAR_SANITIZE
  int pairs = 50;
#else
  int pairs = 500;
#endif
  if (const char* e = std::getenv("FIVEBAR_PRIORITY_PAIRS")) pairs = std::atoi(e);
  const rt::Config c = paper_config();
  rt::Controller ctl(c);
  const Geometry& g = *paper().get<Geometry>();
  std::mt19937_64 rng(testing::test_seed());
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const std::string name : {"index", "thumb"}) {
    const Station& st = paper().require_station(name);
    const std::size_t lo = index_of(c, name, "lower"), up = index_of(c, name, "upper");
    const double scale = st.lower->length_scale();
    const double radius = kSearchRadiusRel * scale, step = 0.01 * scale;
    int colliding = 0, moved = 0, stops = 0, needless = 0, stops_free_beyond = 0;
    double worst_factor = 0.0;
    std::vector<double> factors, relative;
    for (int n = 0; colliding < pairs && n < 50 * pairs; ++n) {
      std::vector<Vec2> pts = centres(c, 8.0);
      pts[up] = st.target.center + Vec2(st.target.axes.x() * u(rng), st.target.axes.y() * u(rng));
      pts[lo] = pts[up] + 8.0 * Vec2(u(rng), u(rng));
      const Pose pu = ik(*st.upper, pts[up]), pl = ik(*st.lower, pts[lo]);
      if (!usable(*st.upper, pu) || !usable(*st.lower, pl)) continue;
      if (!interference(*st.upper, pu, *st.lower, pl, g).collides) continue;
      const rt::MechanismState& l = cycle_from_rest(ctl, c, pts, {lo, up});
      // The library's usable() and the runtime's limits (less joint_margin_rad) differ within the
      // margin: a target the runtime cannot hold is not a case of the rule.
      if (ctl.mechanism(up).status != rt::Status::ok || l.status == rt::Status::limit || l.status == rt::Status::singular) continue;
      ++colliding;
      SCOPED_TRACE(::testing::Message() << name << " upper " << pts[up].transpose() << " lower " << pts[lo].transpose());
      const PriorityResult ref = apply_priority(*st.upper, *st.lower, g, pts[up], pts[lo]);
      const bool ref_found = ref.status == PriorityStatus::moved;
      if (l.status != rt::Status::moved_by_priority) {
        EXPECT_EQ(l.status, rt::Status::unreachable);
        ++stops;
        stops_free_beyond += ref_found && ref.moved_mm > radius;
        if (ref_found && ref.moved_mm <= radius) {
          ++needless;
          ADD_FAILURE() << "stopped, the dense search moves it by " << ref.moved_mm << " mm";
        }
        continue;
      }
      ++moved;
      const Vec2 p(l.point_command[0] * 1000, l.point_command[1] * 1000);
      const Pose pm = ik(*st.lower, p);
      EXPECT_TRUE(usable(*st.lower, pm));
      const Interference after = interference(*st.upper, pu, *st.lower, pm, g);
      EXPECT_FALSE(after.collides) << after.min_clearance_mm;
      EXPECT_NEAR(l.moved * 1000, (p - pts[lo]).norm(), 1e-9);
      if (!ref_found) continue;  // the runtime found a point the rings missed
      const double f = l.moved * 1000 / (ref.moved_mm + step);
      factors.push_back(l.moved * 1000 / ref.moved_mm);
      worst_factor = std::max(worst_factor, f);
      relative.push_back(f);
    }
    std::sort(factors.begin(), factors.end());
    const auto q = [&](double x) { return factors.empty() ? 0.0 : factors[std::size_t(x * double(factors.size() - 1))]; };
    std::printf("[priority %s] %d colliding pairs: %d moved, %d stopped (%d needlessly, %d with a free point beyond the "
                "radius); distance / reference: median %.4f, p99 %.4f, max %.4f; worst against reference + one ring %.4f\n",
                name.c_str(), colliding, moved, stops, needless, stops_free_beyond, q(0.5), q(0.99),
                factors.empty() ? 0.0 : factors.back(), worst_factor);
    EXPECT_EQ(colliding, pairs);
    EXPECT_EQ(needless, 0);
    // The factor holds for 99 % of the moved cases, not for all: a narrow free wedge between the
    // rule's 32 rays that the reference's 256 see can be several times closer (3000 pairs per
    // station: 10 of 6000 beyond 2, the largest 8.2).
    std::sort(relative.begin(), relative.end());
    if (!relative.empty()) EXPECT_LE(relative[std::size_t(0.99 * double(relative.size() - 1))], kDistanceFactor);
  }
}

// With no clearance required (collision.min_clearance_m 0) the links may touch but not overlap:
// bounding boxes that touch can still hold overlapping shapes, so no pair may be skipped on its box
// alone. Every moved lower command is clear by the library's exact check at clearance 0.
TEST(Runtime, ThePriorityRuleSeparatesOverlappingOutlinesAtZeroClearance) {
  rt::Config c = paper_config();
  c.collision.min_clearance = 0.0;
  rt::Controller ctl(c);
  Geometry g = *paper().get<Geometry>();
  g.min_clearance = 0.0;
  std::mt19937_64 rng(testing::test_seed());
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int moved = 0;
  for (int n = 0; n < 40; ++n) {
    const std::string name = n % 2 ? "thumb" : "index";
    const Station& st = paper().require_station(name);
    const std::size_t lo = index_of(c, name, "lower"), up = index_of(c, name, "upper");
    std::vector<Vec2> pts = centres(c, 8.0);
    pts[up] = st.target.center + 0.5 * Vec2(st.target.axes.x() * u(rng), st.target.axes.y() * u(rng));
    pts[lo] = pts[up] + 2.0 * Vec2(u(rng), u(rng));  // the tactors overlap
    const rt::MechanismState& l = cycle_from_rest(ctl, c, pts, {lo, up});
    if (l.status != rt::Status::moved_by_priority) continue;
    ++moved;
    const Vec2 p(l.point_command[0] * 1000, l.point_command[1] * 1000);
    const Interference after = interference(*st.upper, ik(*st.upper, pts[up]), *st.lower, ik(*st.lower, p), g);
    EXPECT_FALSE(after.collides) << name << ": " << after.min_clearance_mm << " mm";
    EXPECT_GE(after.min_clearance_mm, -1e-9);
    EXPECT_GT(l.moved, 0.0);
  }
  EXPECT_GT(moved, 20);
}

TEST(Runtime, ThePidFollowsTheHandComputedSequenceThroughTheWholeCycle) {
  // A one-mechanism configuration with hand-set gains; the reading is the commanded angle minus e.
  rt::Config c = paper_config();
  c.stations.resize(1);
  c.stations[0].mechanisms.resize(1);
  // No slew limit here: the readings jump by e each cycle, and the PID is what is checked (the
  // slew limit has its own test below).
  for (auto& j : c.stations[0].mechanisms[0].joints) j.gains = {0.1, 10.0, 0.02, 0.05}, j.has_velocity_limits = false;
  rt::Controller ctl(c);
  const Vec2 p = paper().require_station("index").target.center;
  const double target[2] = {p.x() / 1000, p.y() / 1000};
  double readings[2] = {0.0, 0.0};
  (void)ctl;
  // As test_dynamics' DiscretePid sequence (T = 10 ms): e -> duty.
  const double e[5] = {0.2, 0.3, 0.3, -0.4, -0.4};
  const double expected[5] = {0.04, 0.28, 0.08, -1.0, -0.07};
  rt::PidState s;
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(rt::pid_update(c.stations[0].mechanisms[0].joints[0].gains, 0.01, s, e[k]), expected[k], 1e-12);
  // Through the cycle: readings theta_command - e give exactly those duties.
  rt::Controller fresh(c);
  fresh.cycle(readings, rt::Reading::radians, target);
  const std::array<double, 2> cmd = fresh.mechanism(0).theta_command;
  fresh.reset();
  for (int k = 0; k < 5; ++k) {
    const double r[2] = {cmd[0] - e[k], cmd[1]};
    fresh.cycle(r, rt::Reading::radians, target);
    EXPECT_NEAR(fresh.duties()[0], expected[k], 1e-12) << k;
  }
}

TEST(Runtime, BadMeasurementsGiveASensorFaultAndZeroDutyNeverACrash) {
  const rt::Config c = paper_config();
  rt::Controller ctl(c);
  const Scene s = at_points(c, centres(c));
  // Counts of the same angles.
  std::vector<double> counts(s.readings.size());
  std::size_t q = 0;
  for (const auto& st : c.stations)
    for (const auto& m : st.mechanisms)
      for (const auto& j : m.joints) {
        counts[q] = rt::adc_code(j.volts_at_zero + s.readings[q] / j.rad_per_volt, c.adc_bits, c.adc_range_v, c.volts_per_count);
        ++q;
      }
  std::vector<double> targets = s.targets;
  for (std::size_t k = 0; k < targets.size(); k += 2) targets[k] += 0.5e-3;  // a 0.5 mm step: non-zero duties
  ctl.cycle(counts.data(), rt::Reading::counts, targets.data());
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(ctl.mechanism(k).status, rt::Status::ok);
    EXPECT_NE(ctl.duties()[2 * k], 0.0);
  }
  const double top = 65535.0;
  for (double bad : {0.0, top, -5.0, top + 10.0, std::nan(""), std::numeric_limits<double>::infinity(), 1.5e300}) {
    SCOPED_TRACE(bad);
    std::vector<double> r = counts;
    r[2] = bad;  // index upper theta1
    ctl.cycle(r.data(), rt::Reading::counts, targets.data());
    EXPECT_EQ(ctl.mechanism(1).status, rt::Status::sensor_fault);
    EXPECT_EQ(ctl.duties()[2], 0.0);
    EXPECT_EQ(ctl.duties()[3], 0.0);
    EXPECT_EQ(ctl.mechanism(0).status, rt::Status::ok);  // the other mechanism runs on
    for (std::size_t i = 0; i < 8; ++i) EXPECT_TRUE(std::isfinite(ctl.duties()[i]));
  }
  // Volts at or beyond the rails.
  std::vector<double> volts(counts.size());
  for (std::size_t i = 0; i < counts.size(); ++i) volts[i] = c.adc_range_v[0] + counts[i] * c.volts_per_count;
  for (double bad : {c.adc_range_v[0], c.adc_range_v[1], 11.0, -10.5}) {
    std::vector<double> r = volts;
    r[0] = bad;
    ctl.cycle(r.data(), rt::Reading::volts, targets.data());
    EXPECT_EQ(ctl.mechanism(0).status, rt::Status::sensor_fault) << bad;
    EXPECT_EQ(ctl.duties()[0], 0.0);
  }
  // Null pointers and non-finite targets.
  ctl.cycle(nullptr, rt::Reading::counts, targets.data());
  for (std::size_t k = 0; k < 4; ++k) EXPECT_EQ(ctl.mechanism(k).status, rt::Status::sensor_fault);
  ctl.reset();
  std::vector<double> nan_targets(targets.size(), std::nan(""));
  ctl.cycle(counts.data(), rt::Reading::counts, nan_targets.data());
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(ctl.mechanism(k).status, rt::Status::unreachable);
    EXPECT_EQ(ctl.duties()[2 * k], 0.0);  // no command yet: motors off
  }
  ctl.cycle(counts.data(), rt::Reading::counts, nullptr);
  for (std::size_t i = 0; i < 8; ++i) EXPECT_TRUE(std::isfinite(ctl.duties()[i]));
  // After a fault the loop recovers and holds the last valid command when the reference fails.
  ctl.cycle(counts.data(), rt::Reading::counts, targets.data());
  EXPECT_EQ(ctl.mechanism(0).status, rt::Status::ok);
  std::vector<double> far = targets;
  far[0] = 1.0;  // a metre away: unreachable
  ctl.cycle(counts.data(), rt::Reading::counts, far.data());
  EXPECT_EQ(ctl.mechanism(0).status, rt::Status::unreachable);
  EXPECT_TRUE(ctl.mechanism(0).command);
  EXPECT_NEAR(ctl.mechanism(0).point_command[0], targets[0], 1e-12);
}

TEST(Runtime, TheSlewLimitReachesAStepTargetAfterCeilStepOverVTCyclesNeverFaster) {
  // One mechanism, a proportional gain of 1 (duty = followed target - measured angle) and two
  // different speed limits; the joints are held at the IK of A (radians readings), the reference
  // steps from A to B. Closed form: joint j's target moves v_j T per cycle and reaches the command
  // at cycle n_j = ceil(|theta_B - theta_A| / (v_j T)), never before.
  rt::Config c = paper_config();
  c.stations.resize(1);
  c.stations[0].mechanisms.resize(1);
  const double v[2] = {2.0, 3.7};  // rad/s
  for (std::size_t j = 0; j < 2; ++j) {
    rt::JointConfig& jc = c.stations[0].mechanisms[0].joints[j];
    jc.gains = {1.0, 0.0, 0.0, 0.0};
    jc.max_velocity = v[j];
    ASSERT_TRUE(jc.has_velocity_limits);
  }
  const double T = 1.0 / c.loop_rate_hz;
  const Vec2 a = paper().require_station("index").target.center - Vec2(0.0, 3.0);
  const Vec2 b = a + Vec2(3.0, 2.0);
  const Scene at_a = at_points(c, {a}), at_b = at_points(c, {b});
  rt::Controller ctl(c);
  ctl.cycle(at_a.readings.data(), rt::Reading::radians, at_a.targets.data());
  ASSERT_EQ(ctl.mechanism(0).status, rt::Status::ok);
  const std::array<double, 2> theta_a = ctl.mechanism(0).theta_command;
  EXPECT_FALSE(ctl.mechanism(0).slew_limited);
  int n[2] = {0, 0};
  std::array<double, 2> theta_b{};
  for (int k = 1; k <= 200; ++k) {
    ctl.cycle(at_a.readings.data(), rt::Reading::radians, at_b.targets.data());
    const rt::MechanismState& st = ctl.mechanism(0);
    ASSERT_EQ(st.status, rt::Status::ok);
    if (k == 1) {
      theta_b = st.theta_command;
      for (std::size_t j = 0; j < 2; ++j) {
        const double ratio = std::fabs(theta_b[j] - theta_a[j]) / (v[j] * T);
        ASSERT_GT(ratio, 3.0) << "the step spans several cycles";
        ASSERT_GT(ratio - std::floor(ratio), 0.01) << "not at a cycle boundary: rounding cannot decide";
        n[j] = static_cast<int>(std::ceil(ratio));
      }
    }
    for (std::size_t j = 0; j < 2; ++j) {
      const double delta = theta_b[j] - theta_a[j];
      const double expected = k < n[j] ? theta_a[j] + std::copysign(k * v[j] * T, delta) : theta_b[j];
      EXPECT_NEAR(st.theta_follow[j], expected, 1e-12) << "joint " << j << " cycle " << k;
      if (k < n[j]) EXPECT_NE(st.theta_follow[j], theta_b[j]) << "reached before cycle " << n[j];
      if (k >= n[j]) EXPECT_EQ(st.theta_follow[j], theta_b[j]) << "cycle " << k;
      // The duty is p (target - measured): the closed form through the PID, not the state field.
      EXPECT_NEAR(ctl.duties()[j], std::clamp(expected - at_a.readings[j], -1.0, 1.0), 1e-9);
    }
    EXPECT_EQ(st.slew_limited, k < std::max(n[0], n[1]));
    if (k > std::max(n[0], n[1]) + 2) break;
  }
  // reset() starts the slew again from the measured angles (the joints at A): v T after one cycle.
  ctl.reset();
  ctl.cycle(at_a.readings.data(), rt::Reading::radians, at_b.targets.data());
  for (std::size_t j = 0; j < 2; ++j) {
    EXPECT_NEAR(ctl.mechanism(0).theta_follow[j], theta_a[j] + std::copysign(v[j] * T, theta_b[j] - theta_a[j]), 1e-9);
  }
  // So does a sensor fault (zero duty): the cycle after it starts from the measured angles.
  for (int k = 0; k < 50; ++k) ctl.cycle(at_a.readings.data(), rt::Reading::radians, at_b.targets.data());
  ASSERT_FALSE(ctl.mechanism(0).slew_limited);
  const double nan_readings[2] = {std::nan(""), at_a.readings[1]};
  ctl.cycle(nan_readings, rt::Reading::radians, at_b.targets.data());
  ASSERT_EQ(ctl.mechanism(0).status, rt::Status::sensor_fault);
  ctl.cycle(at_a.readings.data(), rt::Reading::radians, at_b.targets.data());
  EXPECT_TRUE(ctl.mechanism(0).slew_limited);
  EXPECT_NEAR(ctl.mechanism(0).theta_follow[0], theta_a[0] + std::copysign(v[0] * T, theta_b[0] - theta_a[0]), 1e-9);
  // Without velocity limits the target is the command at once.
  for (auto& jc : c.stations[0].mechanisms[0].joints) jc.has_velocity_limits = false;
  rt::Controller free_ctl(c);
  free_ctl.cycle(at_a.readings.data(), rt::Reading::radians, at_b.targets.data());
  EXPECT_EQ(free_ctl.mechanism(0).theta_follow, free_ctl.mechanism(0).theta_command);
  EXPECT_FALSE(free_ctl.mechanism(0).slew_limited);
  // A speed limit of 0 (or not finite) is refused at load, naming the key.
  c.stations[0].mechanisms[0].joints[1].has_velocity_limits = true;
  c.stations[0].mechanisms[0].joints[1].max_velocity = 0.0;
  try {
    rt::Controller bad(c);
    ADD_FAILURE() << "max_velocity 0 accepted";
  } catch (const rt::ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("joint_limits.index_lower_theta2.max_velocity"));
  }
}

TEST(Runtime, ATargetBeyondTheJointLimitsLessTheMarginIsHeld) {
  rt::Config c = paper_config();
  rt::Controller probe(c);
  const Scene s = at_points(c, centres(c));
  probe.cycle(s.readings.data(), rt::Reading::radians, s.targets.data());
  ASSERT_EQ(probe.mechanism(0).status, rt::Status::ok);
  const double th = probe.mechanism(0).theta_command[0];
  // Limits of index_lower_theta1 so that the centre's angle sits inside the range but within the margin.
  rt::JointConfig& j = c.stations[0].mechanisms[0].joints[0];
  j.has_position_limits = true;
  j.min_position = th - 0.5 * c.joint_margin;
  j.max_position = th + 1.0;
  rt::Controller ctl(c);
  ctl.cycle(s.readings.data(), rt::Reading::radians, s.targets.data());
  EXPECT_EQ(ctl.mechanism(0).status, rt::Status::limit);
  EXPECT_FALSE(ctl.mechanism(0).command);
  EXPECT_EQ(ctl.duties()[0], 0.0);
}

TEST(Runtime, RefusesBadConfigurationsNamingTheKey) {
  const std::string good = export_text();
  const auto refuse = [](const std::string& text, const std::string& key) {
    SCOPED_TRACE(key);
    EXPECT_THAT([&] { (void)rt::parse_config_json(text, "x.json"); }, ::testing::ThrowsMessage<rt::ConfigError>(HasSubstr(key)));
  };
  const auto without = [&](const std::string& key) {
    nlohmann::json j = nlohmann::json::parse(good);
    auto& p = j.begin().value()["ros__parameters"];
    nlohmann::json* at = &p;
    std::string rest = key;
    for (std::size_t dot; (dot = rest.find('.')) != std::string::npos; rest = rest.substr(dot + 1)) at = &(*at)[rest.substr(0, dot)];
    at->erase(rest);
    return j.dump(2);
  };
  refuse(without("loop_rate_hz"), "loop_rate_hz: missing key");
  refuse(without("joint_margin_rad"), "joint_margin_rad: missing key");
  refuse(without("adc.volts_per_count"), "adc.volts_per_count: missing key");
  refuse(without("potentiometers.index_lower_theta1"), "potentiometers.index_lower_theta1: missing key");
  refuse(without("gains.thumb_upper_theta2.i_clamp"), "gains.thumb_upper_theta2.i_clamp: missing key");
  refuse(without("collision.min_clearance_m"), "collision.min_clearance_m: missing key");
  refuse(without("stations.index.lower.link_lengths_m"), "stations.index.lower.link_lengths_m: missing key");
  {
    nlohmann::json j = nlohmann::json::parse(good);
    j.begin().value()["ros__parameters"]["gains"]["index_lower_theta1"]["p"] = std::nan("");  // dumps as null
    refuse(j.dump(), "gains.index_lower_theta1.p: expected a number, found null");
  }
  {
    nlohmann::json j = nlohmann::json::parse(good);
    j.begin().value()["ros__parameters"]["potentiometers"]["index_upper_theta2"]["rad_per_volt"] = 0.0;
    refuse(j.dump(), "potentiometers.index_upper_theta2.rad_per_volt: |rad_per_volt| must be in [1e-6, 1e6] rad/V");
  }
  {
    nlohmann::json j = nlohmann::json::parse(good);
    j.begin().value()["ros__parameters"]["stations"]["index"]["lower"]["link_lengths_m"][2] = -0.015;
    refuse(j.dump(), "stations.index.lower.link_lengths_m[2]: must be > 0");
  }
  refuse("{\"a\": NaN}", "x.json:1: unexpected character 'N'");
  refuse(good.substr(0, good.size() / 2), "x.json:");
  EXPECT_THROW((void)rt::load_config_json("/nonexistent/controller.json"), rt::ConfigError);
}

// Gains and the loop rate within the physical bounds the design loader applies
// (lib/src/sections/controller.cpp): p = d = 1e308 gave a NaN duty before; numbers in the strict
// JSON grammar only (RFC 8259: no leading zero, no bare point).
TEST(Runtime, RefusesGainsOutsideTheirBoundsAndNumbersOutsideTheJsonGrammar) {
  const std::string good = export_text();
  const auto refuse = [](const std::string& text, const std::string& key) {
    SCOPED_TRACE(key);
    EXPECT_THAT([&] { (void)rt::parse_config_json(text, "x.json"); }, ::testing::ThrowsMessage<rt::ConfigError>(HasSubstr(key)));
  };
  const auto with = [&](const std::string& joint, const std::string& key, double v) {
    nlohmann::json j = nlohmann::json::parse(good);
    j.begin().value()["ros__parameters"]["gains"][joint][key] = v;
    return j.dump();
  };
  refuse(with("index_lower_theta1", "p", 1e308), "gains.index_lower_theta1.p: must be in [0, 1000000]");
  refuse(with("index_lower_theta2", "d", 1e308), "gains.index_lower_theta2.d: must be in [0, 1000000]");
  refuse(with("thumb_upper_theta1", "i", -1.0), "gains.thumb_upper_theta1.i: must be in [0, 1000000]");
  refuse(with("thumb_upper_theta1", "i_clamp", 1.5), "gains.thumb_upper_theta1.i_clamp: must be in [0, 1]");
  EXPECT_NO_THROW((void)rt::parse_config_json(with("index_lower_theta1", "p", 1e6), "x.json"));
  {
    nlohmann::json j = nlohmann::json::parse(good);
    j.begin().value()["ros__parameters"]["loop_rate_hz"] = 1e9;
    refuse(j.dump(), "loop_rate_hz: must be in (0, 100000] Hz");
    j.begin().value()["ros__parameters"]["loop_rate_hz"] = 100.0;
    j.begin().value()["ros__parameters"]["potentiometers"]["index_lower_theta1"]["volts_at_zero"] = 1e5;
    refuse(j.dump(), "potentiometers.index_lower_theta1.volts_at_zero: must be within [-1000, 1000] V");
  }
  // The loop rate written as other numbers: JSON's grammar decides, not from_chars.
  nlohmann::json j = nlohmann::json::parse(good);
  j.begin().value()["ros__parameters"]["loop_rate_hz"] = 123456789;  // a marker to replace
  const std::string marked = j.dump();
  const auto as = [&](const std::string& number) {
    std::string t = marked;
    t.replace(t.find("123456789"), 9, number);
    return t;
  };
  for (const std::string bad : {"05", "5.", ".5", "+5", "-", "1e", "1e+", "0x10", "1.e3", "--5", "00"}) {
    refuse(as(bad), "x.json:");
  }
  for (const std::string ok : {"50", "0.5e2", "5E1", "500e-1", "50.0"}) {
    SCOPED_TRACE(ok);
    EXPECT_EQ(rt::parse_config_json(as(ok), "x.json").loop_rate_hz, 50.0);
  }
}

// Readings within half a code of a rail (0.4, 65534.6 and 1e-320 were ok) and angles a potentiometer
// cannot give (more than half a turn from the joint's range: the converter spans 3.3 turns of the
// showcase's calibration, so code 1 read as -10.7 rad) or an encoder more than a turn away (1e15
// rad) are sensor faults: zero duty.
TEST(Runtime, ReadingsNearARailOrOutsideOneTurnAreFaults) {
  const rt::Config c = paper_config();
  rt::Controller ctl(c);
  const Scene s = at_points(c, centres(c));
  const rt::JointConfig& j0 = c.stations[0].mechanisms[0].joints[0];
  std::vector<double> counts(s.readings.size());
  std::size_t q = 0;
  for (const auto& st : c.stations)
    for (const auto& m : st.mechanisms)
      for (const auto& j : m.joints) {
        counts[q] = rt::adc_code(j.volts_at_zero + s.readings[q] / j.rad_per_volt, c.adc_bits, c.adc_range_v, c.volts_per_count);
        ++q;
      }
  ctl.cycle(counts.data(), rt::Reading::counts, s.targets.data());
  ASSERT_EQ(ctl.mechanism(0).status, rt::Status::ok);
  const double top = std::ldexp(1.0, c.adc_bits) - 1.0;
  const double centre = j0.has_position_limits ? 0.5 * (j0.min_position + j0.max_position) : 0.0;
  // The code whose angle is half a turn and a bit beyond the centre, on either side (inside the ADC).
  const auto code_of = [&](double theta) {
    return (j0.volts_at_zero + theta / j0.rad_per_volt - c.adc_range_v[0]) / c.volts_per_count;
  };
  std::vector<double> bad = {0.4, 0.5, top - 0.4, top - 0.5, 1e-320, 1.0};
  for (double theta : {centre + M_PI + 0.05, centre - M_PI - 0.05}) {
    const double code = std::round(code_of(theta));
    if (code > 1 && code < top - 1) bad.push_back(code);
  }
  ASSERT_GE(bad.size(), 7u) << "the calibration spans more than a turn: at least one code beyond it";
  for (double b : bad) {
    SCOPED_TRACE(b);
    std::vector<double> r = counts;
    r[0] = b;
    ctl.cycle(r.data(), rt::Reading::counts, s.targets.data());
    EXPECT_EQ(ctl.mechanism(0).status, rt::Status::sensor_fault);
    EXPECT_EQ(ctl.duties()[0], 0.0);
    EXPECT_EQ(ctl.duties()[1], 0.0);
  }
  // Half a turn less a bit from the centre (a code inside the ADC): not a fault of the reading.
  const double inside = std::round(code_of(centre + M_PI - 0.05));
  if (inside > 1 && inside < top - 1) {
    std::vector<double> r = counts;
    r[0] = inside;
    ctl.cycle(r.data(), rt::Reading::counts, s.targets.data());
    EXPECT_NE(ctl.mechanism(0).status, rt::Status::sensor_fault);
  }
  for (double b : {1e15, 1e300, -1e300, centre + 2 * M_PI + 0.01, centre - 2 * M_PI - 0.01}) {
    SCOPED_TRACE(b);
    std::vector<double> r = s.readings;
    r[0] = b;
    ctl.cycle(r.data(), rt::Reading::radians, s.targets.data());
    EXPECT_EQ(ctl.mechanism(0).status, rt::Status::sensor_fault);
    EXPECT_EQ(ctl.duties()[0], 0.0);
  }
}

// No NaN in any output: the largest gains accepted (1e6, i_clamp 1) at the fastest loop rate
// accepted (1e5 Hz), and every reading and target from a sweep of extreme finite values (the
// largest and smallest doubles, subnormals, the rails and their neighbours), in every kind.
TEST(Runtime, ExtremeFiniteInputsNeverGiveANaN) {
  rt::Config c = paper_config();
  c.loop_rate_hz = 1e5;
  for (auto& st : c.stations)
    for (auto& m : st.mechanisms)
      for (auto& j : m.joints) j.gains = {1e6, 1e6, 1e6, 1.0};
  rt::Controller ctl(c);
  const Scene s = at_points(c, centres(c));
  const double big = std::numeric_limits<double>::max(), tiny = std::numeric_limits<double>::denorm_min();
  const std::vector<double> values = {big, -big, 1e300, -1e300, 1e15, -1e15, tiny, -tiny, 1e-320, DBL_MIN, 0.0, -0.0,
                                      0.5, 1.0, 65534.0, 65534.5, 65535.0, 3.0, -3.0, 10.0, -10.0, 1e-3, -1e-3};
  std::mt19937_64 rng(testing::test_seed());
  std::uniform_int_distribution<std::size_t> pick(0, values.size() - 1);
  std::uniform_int_distribution<int> coin(0, 3);
  const auto finite_state = [&](const char* what) {
    for (std::size_t i = 0; i < ctl.joint_count(); ++i) {
      ASSERT_TRUE(std::isfinite(ctl.duties()[i]) && std::fabs(ctl.duties()[i]) <= 1.0) << what;
    }
    for (std::size_t k = 0; k < ctl.mechanism_count(); ++k) {
      const rt::MechanismState& m = ctl.mechanism(k);
      for (double v : {m.theta_measured[0], m.theta_measured[1], m.point_measured[0], m.point_measured[1], m.target[0],
                       m.target[1], m.point_command[0], m.point_command[1], m.theta_command[0], m.theta_command[1],
                       m.moved, m.duty[0], m.duty[1]}) {
        ASSERT_TRUE(std::isfinite(v)) << what << " mechanism " << k;
      }
    }
    for (std::size_t st = 0; st < c.stations.size(); ++st) ASSERT_TRUE(std::isfinite(ctl.station(st).measured_clearance));
  };
  for (int n = 0; n < 5000; ++n) {
    std::vector<double> r = s.readings, t = s.targets;
    const auto kind = static_cast<rt::Reading>(n % 3);
    for (double& x : r)
      if (coin(rng) == 0) x = values[pick(rng)];
    for (double& x : t)
      if (coin(rng) == 0) x = values[pick(rng)] * (coin(rng) ? 1.0 : 1e-3);
    ctl.cycle(r.data(), kind, t.data());
    finite_state("random");
    if (HasFatalFailure()) return;
  }
  // Every joint at every extreme value, targets at the centres: one at a time per kind.
  for (int kind = 0; kind < 3; ++kind)
    for (double v : values)
      for (std::size_t i = 0; i < s.readings.size(); ++i) {
        std::vector<double> r = s.readings;
        r[i] = v;
        ctl.cycle(r.data(), static_cast<rt::Reading>(kind), s.targets.data());
        finite_state("sweep");
        if (HasFatalFailure()) return;
      }
}

TEST(Runtime, SameInputsGiveTheSameDutiesBitForBit) {
  const rt::Config c = paper_config();
  rt::Controller a(c), b(c);
  std::mt19937_64 rng(testing::test_seed());
  std::normal_distribution<double> noise(0.0, 0.01);
  const Scene s = at_points(c, centres(c));
  for (int k = 0; k < 2000; ++k) {
    std::vector<double> r = s.readings;
    for (double& v : r) v += noise(rng);
    a.cycle(r.data(), rt::Reading::radians, s.targets.data());
    b.cycle(r.data(), rt::Reading::radians, s.targets.data());
    ASSERT_EQ(std::memcmp(a.duties(), b.duties(), 8 * sizeof(double)), 0) << k;
  }
}

TEST(Runtime, NoAllocationAndNoExceptionInAMillionCycles) {
  static_assert(noexcept(std::declval<rt::Controller&>().cycle(nullptr, rt::Reading::counts, nullptr)));
#ifdef FIVEBAR_SANITIZE
  const int cycles = 20'000;
#else
  const int cycles = 1'000'000;
#endif
  const rt::Config c = paper_config();
  rt::Controller ctl(c);
  // Every branch: moving references (a circle of 3 mm about each centre), noise, faults, a
  // collision that moves the lower target (every 50th cycle: the priority rule), nulls.
  const std::vector<Vec2> base = centres(c);
  Scene s = at_points(c, base);
  std::vector<double> readings = s.readings, targets = s.targets;
  const std::size_t lo = index_of(c, "index", "lower"), up = index_of(c, "index", "upper");
  const Vec2 centre = paper().require_station("index").target.center;
  double checksum = 0.0;
  const long long before = g_allocations.load();
  for (int k = 0; k < cycles; ++k) {
    const double phase = 2 * M_PI * (k % 400) / 400.0;
    for (std::size_t m = 0; m < base.size(); ++m) {
      targets[2 * m] = (base[m].x() + 1.5 * std::cos(phase)) / 1000;
      targets[2 * m + 1] = (base[m].y() + 1.5 * std::sin(phase)) / 1000;
    }
    for (std::size_t i = 0; i < readings.size(); ++i) readings[i] = s.readings[i] + 1e-3 * std::sin(0.37 * k + double(i));
    if (k % 50 == 17) {
      targets[2 * lo] = targets[2 * up] = centre.x() / 1000;
      targets[2 * lo + 1] = targets[2 * up + 1] = centre.y() / 1000;
    }
    if (k % 977 == 3) readings[5] = std::nan("");
    ctl.cycle(k % 10007 == 5 ? nullptr : readings.data(), rt::Reading::radians, targets.data());
    checksum += ctl.duties()[k % 8];
  }
  const long long allocations = g_allocations.load() - before;
  EXPECT_EQ(allocations, 0);
  EXPECT_TRUE(std::isfinite(checksum));
  std::printf("[runtime] %d cycles, %lld allocations\n", cycles, allocations);
}

TEST(Runtime, TheSimulatorsDutiesAreTheStandaloneRuntimesBitForBit) {
  // The simulator drives its runtime with the ADC codes of the simulated joints; a runtime built
  // from the exported JSON text alone, fed the same codes and reference points, computes the same
  // duties to the last bit, and those are the duties the simulated motors got one period later.
  const Design& d = paper();
  SimulationRequest request;
  request.station = "index";
  request.pattern = PatternKind::twist;
  const SimulationInput in = simulation_inputs(d, request, station_inertia(d, d.require_station("index"), nullptr, {})).front();
  struct Cycle {
    std::vector<double> readings, targets, duties;
  };
  std::vector<Cycle> log;
  SimulationOptions o;
  o.controller_log = [&](double, const std::vector<double>& r, rt::Reading kind, const std::vector<double>& t,
                         const rt::Controller& ctl) {
    EXPECT_EQ(kind, rt::Reading::counts);
    log.push_back({r, t, std::vector<double>(ctl.duties(), ctl.duties() + ctl.joint_count())});
  };
  const SimulationResult r = simulate(in, o);
  ASSERT_TRUE(r.ok()) << r.reason;
  ASSERT_EQ(log.size(), r.samples.size());

  rt::Controller standalone(rt::parse_config_json(export_text({"index"}), "iros2022_controller.json"));
  std::size_t nonzero = 0;
  for (std::size_t s = 0; s < log.size(); ++s) {
    standalone.cycle(log[s].readings.data(), rt::Reading::counts, log[s].targets.data());
    ASSERT_EQ(std::memcmp(standalone.duties(), log[s].duties.data(), 4 * sizeof(double)), 0) << "cycle " << s;
    if (s + 1 < r.samples.size()) {
      for (std::size_t k = 0; k < 2; ++k)
        for (std::size_t j = 0; j < 2; ++j) {
          const double applied = r.samples[s + 1].mechanisms[k].duty[j];  // one period of delay
          ASSERT_EQ(std::memcmp(&applied, &log[s].duties[2 * k + j], sizeof(double)), 0) << s;
          nonzero += applied != 0.0;
        }
    }
  }
  EXPECT_GT(nonzero, log.size());  // the pattern really drives the motors
}

}  // namespace
}  // namespace fivebar

namespace fivebar_test {
fivebar::runtime::Config runtime_config_from_header();
std::array<double, 6> header_constants();
}

namespace fivebar {
namespace {

/// Every leaf and map of a tree, as paths of keys.
void paths(const Json& j, std::vector<std::string>& prefix, std::vector<std::vector<std::string>>& out) {
  if (!j.is_object()) return;
  for (const auto& [key, value] : j.items()) {
    prefix.push_back(key);
    out.push_back(prefix);
    paths(value, prefix, out);
    prefix.pop_back();
  }
}

TEST(RuntimeConfig, AConfigReadFromTheExportWritesItBackByteForByte) {
  // The reader and the writer share the one key list (fivebar/runtime/config_layout.hpp); this
  // holds that no exported value is lost or changed on the way through a runtime::Config, for
  // the whole design and for one station, in all three formats.
  for (const std::vector<std::string>& stations : {std::vector<std::string>{}, std::vector<std::string>{"thumb"}}) {
    const Json exported = controller_parameters(paper(), stations);
    const rt::Config c = rt::parse_config_json(render_json(exported), "export.json");
    const Json again = configuration_document(c);
    EXPECT_EQ(render_json(again), render_json(exported));
    EXPECT_EQ(render_ros2_yaml(again), render_ros2_yaml(exported));
    EXPECT_EQ(render_header(again), render_header(exported));
  }
}

TEST(RuntimeConfig, EveryExportedKeyIsReadNoneIgnored) {
  // Remove each key of the exported document in turn: the runtime must refuse the file and name
  // the key (a key the reader skipped would be accepted silently).
  const Json exported = controller_parameters(paper(), {"index"});
  const std::string node = exported.begin().key();
  std::vector<std::vector<std::string>> all;
  std::vector<std::string> prefix;
  paths(exported[node]["ros__parameters"], prefix, all);
  // Counted from docs/runtime.md's key list for one station of two mechanisms: fivebar 1 + 6,
  // loop_rate_hz, pwm_hz, adc 1 + 3, joint_margin_rad, station_names, joint_names (16); stations
  // 1 + index 1 + target 1 + 3 + mechanisms + 2 x (1 + 7) (23); collision 1 + 12 (13);
  // joint_limits 1 + 4 x (1 + 8) (37); gains 1 + 4 x (1 + 4) (21); potentiometers 1 + 4 x (1 + 2) (13).
  ASSERT_EQ(all.size(), 16u + 23u + 13u + 37u + 21u + 13u);
  for (const std::vector<std::string>& path : all) {
    Json j = exported;
    Json* parent = &j[node]["ros__parameters"];
    for (std::size_t i = 0; i + 1 < path.size(); ++i) parent = &(*parent)[path[i]];
    parent->erase(path.back());
    std::string dotted;
    for (const std::string& k : path) dotted += (dotted.empty() ? "" : ".") + k;
    try {
      rt::parse_config_json(j.dump(2), "cut.json");
      ADD_FAILURE() << "accepted without " << dotted;
    } catch (const rt::ConfigError& e) {
      EXPECT_THAT(e.what(), HasSubstr(path.back())) << dotted;
    }
  }
}

TEST(RuntimeConfig, SimulateRunsTheExportedConfiguration) {
  // What simulate (and so control --tune and the export gate) runs, written out, is the exported
  // JSON of the station byte for byte: not a second configuration built beside the export. (The
  // file export_controller() writes is this text with `fivebar.validation` added: the figures the
  // gate measured by simulating this very configuration, which the runtime does not read.)
  for (const std::string station : {"index", "thumb"}) {
    SimulationRequest request;
    request.station = station;
    const std::vector<SimulationInput> inputs =
        simulation_inputs(paper(), request, station_inertia(paper(), paper().require_station(station), nullptr, {}));
    ASSERT_FALSE(inputs.empty());
    const std::string exported = render_json(controller_parameters(paper(), {station}));
    for (const SimulationInput& in : inputs) {
      ASSERT_TRUE(in.runtime) << in.reference_name;
      EXPECT_EQ(render_json(configuration_document(*in.runtime)), exported) << station << " " << in.reference_name;
    }
  }
}

TEST(RuntimeConfig, TheStepInputRunsTheExportedConfigurationWithoutTheSlewLimit) {
  // docs/runtime.md "One cycle" 5: a step measures the loop, not the limiter; everything else is
  // the export's.
  SimulationRequest request;
  request.station = "index";
  request.step = true;
  const std::vector<SimulationInput> inputs =
      simulation_inputs(paper(), request, station_inertia(paper(), paper().require_station("index"), nullptr, {}));
  ASSERT_EQ(inputs.size(), 1u);
  ASSERT_TRUE(inputs[0].runtime);
  rt::Config c = rt::parse_config_json(export_text({"index"}), "index.json");
  std::size_t joints = 0;
  for (auto& s : c.stations)
    for (auto& m : s.mechanisms)
      for (auto& j : m.joints) {
        EXPECT_TRUE(j.has_velocity_limits) << j.name;
        j.has_velocity_limits = false;
        ++joints;
      }
  EXPECT_EQ(joints, 4u);
  EXPECT_EQ(render_json(configuration_document(*inputs[0].runtime)), render_json(configuration_document(c)));
}

TEST(Runtime, TheExportedHeaderConfiguresTheSameController) {
  const rt::Config json = paper_config();
  const rt::Config header = fivebar_test::runtime_config_from_header();
  ASSERT_EQ(header.mechanism_count(), json.mechanism_count());
  EXPECT_EQ(header.design_hash, json.design_hash);
  EXPECT_EQ(header.joint_margin, json.joint_margin);
  EXPECT_EQ(header.collision.link_widths, json.collision.link_widths);
  for (std::size_t s = 0; s < json.stations.size(); ++s)
    for (std::size_t m = 0; m < json.stations[s].mechanisms.size(); ++m) {
      const rt::MechanismConfig &a = json.stations[s].mechanisms[m], &b = header.stations[s].mechanisms[m];
      EXPECT_EQ(a.L, b.L);
      EXPECT_EQ(a.working_mode, b.working_mode);
      for (std::size_t j = 0; j < 2; ++j) {
        EXPECT_EQ(a.joints[j].name, b.joints[j].name);
        EXPECT_EQ(a.joints[j].rad_per_volt, b.joints[j].rad_per_volt);
        EXPECT_EQ(a.joints[j].max_position, b.joints[j].max_position);
        EXPECT_EQ(a.joints[j].gains.d, b.joints[j].gains.d);
      }
    }
  // The header's constants (compiled in) are the values the runtime read from its runtime_json.
  const std::array<double, 6> k = fivebar_test::header_constants();
  const rt::MechanismConfig& il = header.stations[0].mechanisms[0];
  const rt::MechanismConfig& iu = header.stations[0].mechanisms[1];
  const rt::MechanismConfig& tu = header.stations[1].mechanisms[1];
  ASSERT_EQ(il.joints[0].name, "index_lower_theta1");
  ASSERT_EQ(iu.joints[0].name, "index_upper_theta1");
  ASSERT_EQ(tu.joints[1].name, "thumb_upper_theta2");
  EXPECT_EQ(k[0], il.joints[0].gains.p);
  EXPECT_EQ(k[1], tu.joints[1].rad_per_volt);
  EXPECT_EQ(k[2], il.L[2]);
  EXPECT_EQ(k[3], iu.joints[0].max_velocity);
  EXPECT_EQ(k[4], iu.joints[0].min_position);
  EXPECT_EQ(k[5], header.collision.tactor_diameter);
  rt::Controller x(json), y(header);
  const Scene s = at_points(json, centres(json, 5.0));
  for (int k = 0; k < 200; ++k) {
    std::vector<double> r = s.readings;
    for (std::size_t i = 0; i < r.size(); ++i) r[i] += 0.02 * std::sin(0.3 * k + double(i));
    x.cycle(r.data(), rt::Reading::radians, s.targets.data());
    y.cycle(r.data(), rt::Reading::radians, s.targets.data());
    ASSERT_EQ(std::memcmp(x.duties(), y.duties(), 8 * sizeof(double)), 0) << k;
  }
}


// --- The Linux I/O backend (fivebar/runtime/linux_io.hpp) against a scratch folder laid out like
// the kernel's sysfs files ------------------------------------------------------------------------

namespace fs = std::filesystem;
namespace lio = fivebar::runtime::linux_io;

std::string file_text(const fs::path& p) {
  std::ifstream in(p);
  std::string t((std::istreambuf_iterator<char>(in)), {});
  while (!t.empty() && t.back() == '\n') t.pop_back();
  return t;
}
void put_text(const fs::path& p, const std::string& t) { std::ofstream(p) << t << "\n"; }

/// The tree the mainline drivers give: an IIO ADC with channels 0-7, a PWM chip with `pwm` of its
/// channels already exported, the GPIO class folder with `gpios` exported.
void kernel_tree(const fs::path& root, const std::vector<int>& pwm, const std::vector<int>& gpios) {
  const fs::path iio = root / "sys/bus/iio/devices/iio:device1", chip = root / "sys/class/pwm/pwmchip2", gpio = root / "sys/class/gpio";
  fs::create_directories(iio);
  for (int k = 0; k < 8; ++k) put_text(iio / ("in_voltage" + std::to_string(k) + "_raw"), "0");
  fs::create_directories(chip);
  put_text(chip / "export", "");
  for (int m : pwm) {
    const fs::path d = chip / ("pwm" + std::to_string(m));
    fs::create_directories(d);
    for (const char* f : {"period", "duty_cycle", "polarity", "enable"}) put_text(d / f, "");
  }
  fs::create_directories(gpio);
  put_text(gpio / "export", "");
  for (int g : gpios) {
    fs::create_directories(gpio / ("gpio" + std::to_string(g)));
    put_text(gpio / ("gpio" + std::to_string(g)) / "direction", "in");
    put_text(gpio / ("gpio" + std::to_string(g)) / "value", "0");
  }
}

// Eight joints wired to ADC channels 7..0, PWM channels in another order, GPIO lines 20..27, two
// motors reversed, offsets in codes. Over 300 cycles of moving references and noisy readings the
// files read give exactly the codes plus offsets; the duty_cycle and direction files hold, bit for
// bit, the documented conversion (round(|d| P) ns, line 1 where d < 0; P = round(1e9 / pwm_hz),
// computed here) of the duties a second runtime gives when fed the same numbers directly (what the
// CSV backend does); nothing allocates in read() and write(). A failed or out-of-range read is NaN
// (the runtime's sensor fault); a write that fails returns false naming the file, the other
// channels still written; write_zero() attempts every channel.
TEST(LinuxIo, WritesTheCsvBackendsDutiesToThePwmAndGpioFilesBitForBit) {
  // On tmpfs where there is one: on ext4 each close after O_TRUNC flushes the file to the disk
  // (auto_da_alloc), 20 s for this test; sysfs writes no disk either.
  struct Tree {
    fs::path path;
    ~Tree() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  } tree{(fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path()) /
         ("fivebar_test_linux_io_" + std::to_string(::getpid()))};
  fs::remove_all(tree.path);
  fs::create_directories(tree.path);
  const fs::path root = tree.path;
  kernel_tree(root, {0, 1, 2, 3, 4, 5, 6}, {20, 21, 22, 23, 24, 25, 26, 27});  // pwm7 not yet exported
  const rt::Config c = paper_config();
  ASSERT_EQ(c.mechanism_count(), 4u);
  const std::vector<int> pwm{3, 1, 0, 2, 7, 5, 6, 4};
  const std::vector<double> direction{1, -1, 1, 1, 1, 1, -1, 1}, offset{0, 12, -5, 3, 0, 0, 7, 0};
  lio::LinuxIoConfig cfg;
  cfg.root = root.string();
  cfg.iio_device = 1;
  cfg.pwm_chip = 2;
  cfg.pwm_hz = c.pwm_hz;
  cfg.adc_bits = c.adc_bits;
  for (int j = 0; j < 8; ++j) cfg.joints.push_back({7 - j, pwm[j], 20 + j, direction[j], offset[j]});
  // A PWM channel not exported whose folder the "kernel" does not create: refused after the export.
  try {
    lio::LinuxIo io(cfg);
    ADD_FAILURE() << "set up without pwm7";
  } catch (const lio::IoError& e) {
    EXPECT_THAT(e.what(), HasSubstr("pwmchip2/pwm7: not there after writing 7 to"));
  }
  EXPECT_EQ(file_text(root / "sys/class/pwm/pwmchip2/export"), "7");
  kernel_tree(root, {7}, {});
  lio::LinuxIo io(cfg);
  const long long period = std::llround(1e9 / c.pwm_hz);
  ASSERT_EQ(io.period_ns(), period);
  const fs::path chip = root / "sys/class/pwm/pwmchip2", iio = root / "sys/bus/iio/devices/iio:device1";
  for (int j = 0; j < 8; ++j) {
    const fs::path d = chip / ("pwm" + std::to_string(pwm[j]));
    EXPECT_EQ(file_text(d / "period"), std::to_string(period));
    EXPECT_EQ(file_text(d / "polarity"), "normal");
    EXPECT_EQ(file_text(d / "enable"), "1");
    EXPECT_EQ(file_text(d / "duty_cycle"), "0");
    EXPECT_EQ(file_text(root / ("sys/class/gpio/gpio" + std::to_string(20 + j)) / "direction"), "low");
  }
  // Readings as ADC codes: the IK of moving points through the calibration, rounded to a code.
  rt::Controller via_files(c), direct(c);
  const std::vector<Vec2> base = centres(c);
  std::vector<double> readings(8), codes(8), numbers(8);
  long long nonzero = 0, negative = 0, allocations = 0;
  for (int k = 0; k < 300; ++k) {
    std::vector<Vec2> p = base;
    for (Vec2& q : p) q += Vec2(1.5 * std::cos(0.05 * k), 1.5 * std::sin(0.05 * k));
    const Scene s = at_points(c, p);
    std::size_t j = 0;
    for (const auto& st : c.stations)
      for (const auto& m : st.mechanisms)
        for (const auto& jc : m.joints) {
          const double theta = s.readings[j] + 0.01 * std::sin(0.7 * k + double(j));  // away from the command
          const double volts = theta / jc.rad_per_volt + jc.volts_at_zero;
          codes[j] = std::round((volts - c.adc_range_v[0]) / c.volts_per_count) - offset[j];
          put_text(iio / ("in_voltage" + std::to_string(7 - j) + "_raw"), std::to_string(static_cast<long long>(codes[j])));
          numbers[j] = codes[j] + offset[j];
          ++j;
        }
    const long long before = g_allocations.load();
    const std::size_t failed = io.read(readings.data());
    via_files.cycle(readings.data(), rt::Reading::counts, s.targets.data());
    const bool written = io.write(via_files.duties());
    allocations += g_allocations.load() - before;
    ASSERT_EQ(failed, 0u);
    ASSERT_TRUE(written) << io.error();
    direct.cycle(numbers.data(), rt::Reading::counts, s.targets.data());
    for (j = 0; j < 8; ++j) {
      ASSERT_EQ(readings[j], numbers[j]) << k << " " << j;
      const double d = direct.duties()[j] * direction[j];
      const long long ns = std::llround(std::fabs(d) * static_cast<double>(period));
      ASSERT_EQ(file_text(chip / ("pwm" + std::to_string(pwm[j])) / "duty_cycle"), std::to_string(ns)) << k << " " << j;
      ASSERT_EQ(file_text(root / ("sys/class/gpio/gpio" + std::to_string(20 + j)) / "value"), d < 0 ? "1" : "0") << k << " " << j;
      nonzero += ns != 0;
      negative += d < 0;
    }
  }
  EXPECT_EQ(allocations, 0);
  EXPECT_GT(nonzero, 8 * 250);  // the motors were driven, both ways
  EXPECT_GT(negative, 300);
  // Failed readings: not a number, out of [0, 2^bits), empty, gone.
  const std::string top = std::to_string(1LL << c.adc_bits);
  put_text(iio / "in_voltage7_raw", "junk");
  put_text(iio / "in_voltage6_raw", top);
  put_text(iio / "in_voltage5_raw", "-1");
  std::ofstream(iio / "in_voltage4_raw").close();
  fs::remove(iio / "in_voltage3_raw");
  put_text(iio / "in_voltage2_raw", std::to_string((1LL << c.adc_bits) - 1));
  EXPECT_EQ(io.read(readings.data()), 5u);
  for (int j = 0; j < 5; ++j) EXPECT_TRUE(std::isnan(readings[j])) << j;
  EXPECT_EQ(readings[5], double((1LL << c.adc_bits) - 1) + offset[5]);
  via_files.cycle(readings.data(), rt::Reading::counts, base.empty() ? nullptr : at_points(c, base).targets.data());
  EXPECT_EQ(via_files.mechanism(0).status, rt::Status::sensor_fault);
  // A write that fails: pwm1's duty_cycle is a folder. The others are still written.
  fs::remove(chip / "pwm1/duty_cycle");
  fs::create_directories(chip / "pwm1/duty_cycle");
  const std::vector<double> half(8, 0.5);
  EXPECT_FALSE(io.write(half.data()));
  EXPECT_THAT(io.error(), HasSubstr("pwmchip2/pwm1/duty_cycle: Is a directory"));
  EXPECT_EQ(file_text(chip / "pwm3/duty_cycle"), std::to_string(std::llround(0.5 * static_cast<double>(period))));
  EXPECT_FALSE(io.write_zero());
  for (int m : {0, 2, 3, 4, 5, 6, 7}) EXPECT_EQ(file_text(chip / ("pwm" + std::to_string(m)) / "duty_cycle"), "0") << m;
  // The conversion's edges.
  EXPECT_EQ(lio::duty_cycle_ns(-1.0, 1000000), 1000000);
  EXPECT_EQ(lio::duty_cycle_ns(0.5e-6, 1000000), 1);  // 0.5 ns rounds away from zero
  EXPECT_EQ(lio::duty_cycle_ns(std::nan(""), 1000000), 0);
  EXPECT_EQ(lio::direction_value(-0.0), 0);
  EXPECT_THROW(lio::pwm_period_ns(0.0), lio::IoError);
}


// The E-stop input line (--estop-gpio): set up as an input; pressed when its value reads 1, and
// fail-safe when it reads anything but 0 or cannot be read; no line: never pressed.
TEST(LinuxIo, TheEStopLineIsPressedUnlessItReadsZero) {
  const fs::path root = (fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path()) /
                        ("fivebar_test_linux_estop_" + std::to_string(::getpid()));
  fs::remove_all(root);
  kernel_tree(root, {0}, {20, 30});
  lio::LinuxIoConfig cfg;
  cfg.root = root.string();
  cfg.iio_device = 1;
  cfg.pwm_chip = 2;
  cfg.pwm_hz = 1000.0;
  cfg.adc_bits = 16;
  cfg.joints.push_back({0, 0, 20, 1.0, 0.0});
  {
    lio::LinuxIo none(cfg);
    EXPECT_FALSE(none.estop());
  }
  cfg.estop_gpio = 30;
  lio::LinuxIo io(cfg);
  const fs::path line = root / "sys/class/gpio/gpio30";
  EXPECT_EQ(file_text(line / "direction"), "in");
  put_text(line / "value", "0");
  EXPECT_FALSE(io.estop());
  put_text(line / "value", "1");
  EXPECT_TRUE(io.estop());
  put_text(line / "value", "junk");
  EXPECT_TRUE(io.estop());
  put_text(line / "value", "00");
  EXPECT_TRUE(io.estop());
  fs::remove(line / "value");
  EXPECT_TRUE(io.estop());
  fs::remove_all(root);
}

}  // namespace
}  // namespace fivebar
