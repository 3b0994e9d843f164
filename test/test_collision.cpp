// Tests of fivebar/collision.hpp: the segment and capsule distances against hand-worked cases and
// a brute-force reference, their symmetry and rigid-motion invariance; link outlines plane by plane;
// interference of hand-built poses; the priority rule (moved target collision-free, nothing closer
// by dense sampling, clear targets untouched); the collision map on the paper's stations.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <numbers>
#include <random>
#include <string>

#include <Eigen/Geometry>

#include "fivebar/sections/geometry.hpp"
#include "fivebar/collision.hpp"
#include "fivebar/design.hpp"
#include "fivebar/kinematics.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

const fs::path kDesign = fs::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml";

/// Seed of the random tests: FIVEBAR_TEST_SEED overrides the fixed default.
std::uint64_t seed() {
  const char* env = std::getenv("FIVEBAR_TEST_SEED");
  return env ? std::strtoull(env, nullptr, 10) : 20220523u;
}

// ---------------------------------------------------------------------------------------------
// Segment distance: hand-worked cases.

TEST(SegmentDistance, ParallelOverlappingInProjection) {
  // Horizontal segments 2 mm apart, overlapping in x: the gap is the vertical distance.
  EXPECT_DOUBLE_EQ(segment_distance({0, 0}, {4, 0}, {1, 2}, {3, 2}).distance, 2.0);
  EXPECT_DOUBLE_EQ(segment_distance({0, 0}, {4, 0}, {3, -2}, {1, -2}).distance, 2.0);  // reversed, below
}

TEST(SegmentDistance, ParallelOffsetEndToEnd) {
  // (1, 0) to (3, 1): sqrt(2^2 + 1^2).
  const auto d = segment_distance({0, 0}, {1, 0}, {3, 1}, {5, 1});
  EXPECT_DOUBLE_EQ(d.distance, std::sqrt(5.0));
  EXPECT_EQ(d.on_first, Vec2(1, 0));
  EXPECT_EQ(d.on_second, Vec2(3, 1));
}

TEST(SegmentDistance, CollinearDisjointAndOverlapping) {
  EXPECT_DOUBLE_EQ(segment_distance({0, 0}, {1, 0}, {3, 0}, {5, 0}).distance, 2.0);
  EXPECT_DOUBLE_EQ(segment_distance({0, 0}, {3, 0}, {2, 0}, {5, 0}).distance, 0.0);
  EXPECT_DOUBLE_EQ(segment_distance({0, 0}, {5, 0}, {1, 0}, {2, 0}).distance, 0.0);  // one inside the other
}

TEST(SegmentDistance, CrossingIsZeroAtTheIntersection) {
  const auto d = segment_distance({0, 0}, {2, 2}, {0, 2}, {2, 0});
  EXPECT_EQ(d.distance, 0.0);
  EXPECT_NEAR(d.on_first.x(), 1.0, 1e-15);
  EXPECT_NEAR(d.on_first.y(), 1.0, 1e-15);
  // A steep crossing far from the endpoints, where every endpoint distance is large.
  const auto steep = segment_distance({-100, 0}, {100, 0}, {0.5, -100}, {0.5, 100});
  EXPECT_EQ(steep.distance, 0.0);
  EXPECT_NEAR(steep.on_first.x(), 0.5, 1e-13);
}

TEST(SegmentDistance, TouchingAtAnEndpoint) {
  // T: the end of the second lies on the first.
  EXPECT_DOUBLE_EQ(segment_distance({0, 0}, {4, 0}, {2, 0}, {2, 3}).distance, 0.0);
  // Endpoints shared.
  EXPECT_DOUBLE_EQ(segment_distance({0, 0}, {1, 1}, {1, 1}, {2, 0}).distance, 0.0);
}

TEST(SegmentDistance, EndpointToInterior) {
  // (2, 1) is 1 above the middle of [(0,0), (4,0)]; the second segment points away.
  const auto d = segment_distance({0, 0}, {4, 0}, {2, 1}, {3, 5});
  EXPECT_DOUBLE_EQ(d.distance, 1.0);
  EXPECT_EQ(d.on_first, Vec2(2, 0));
  // Skew, nearest at two endpoints: (1, 0) to (2, 1).
  EXPECT_DOUBLE_EQ(segment_distance({0, 0}, {1, 0}, {2, 1}, {3, 5}).distance, std::sqrt(2.0));
}

TEST(SegmentDistance, DegenerateSegmentsArePoints) {
  EXPECT_DOUBLE_EQ(segment_distance({1, 1}, {1, 1}, {4, 5}, {4, 5}).distance, 5.0);  // 3-4-5
  EXPECT_DOUBLE_EQ(segment_distance({1, 1}, {1, 1}, {-2, 0}, {2, 0}).distance, 1.0);
  EXPECT_DOUBLE_EQ(segment_distance({5, 0}, {5, 0}, {-2, 0}, {2, 0}).distance, 3.0);  // beyond the end
}

// ---------------------------------------------------------------------------------------------
// Capsules: touching, overlapping by 1e-9, parallel, crossing.

TEST(CapsuleClearance, TouchingIsZero) {
  // Centre lines 1 apart (the point (0.5, 1) above the middle of the first), radii 0.5 + 0.5.
  const Capsule a{{0, 0}, {1, 0}, 0.5};
  const Capsule b{{0.5, 1}, {0.5, 2}, 0.5};
  EXPECT_EQ(capsule_clearance(a, b), 0.0);
}

TEST(CapsuleClearance, OverlappingByOneNanometreScale) {
  // Same as touching with the second radius 1e-9 larger: overlap 1e-9 mm.
  const Capsule a{{0, 0}, {1, 0}, 0.5};
  const Capsule b{{0.5, 1}, {0.5, 2}, 0.5 + 1e-9};
  const double c = capsule_clearance(a, b);
  EXPECT_LT(c, 0.0);
  EXPECT_NEAR(c, -1e-9, 1e-15);
}

TEST(CapsuleClearance, ParallelLinks) {
  // Two 4 mm wide links (radius 2) whose centre lines are 5 mm apart: 1 mm of clearance.
  const Capsule a{{0, 0}, {15, 0}, 2.0};
  const Capsule b{{3, 5}, {18, 5}, 2.0};
  Vec2 pa, pb;
  EXPECT_DOUBLE_EQ(capsule_clearance(a, b, &pa, &pb), 1.0);
  EXPECT_DOUBLE_EQ((pa - pb).norm(), 5.0);
}

TEST(CapsuleClearance, CrossingLinksOverlapByBothRadii) {
  const Capsule a{{0, 0}, {10, 10}, 2.0};
  const Capsule b{{0, 10}, {10, 0}, 1.5};
  EXPECT_DOUBLE_EQ(capsule_clearance(a, b), -3.5);
}

TEST(CapsuleClearance, DisksAreZeroLengthCapsules) {
  const Capsule a{{0, 0}, {0, 0}, 2.5};
  const Capsule b{{3, 4}, {3, 4}, 2.5};
  EXPECT_DOUBLE_EQ(capsule_clearance(a, b), 0.0);  // |(3,4)| = 5 = 2.5 + 2.5
}

// ---------------------------------------------------------------------------------------------
// Properties on random segments: symmetry, rigid motion, brute force.

struct RandomSegments {
  std::mt19937_64 rng{seed()};
  std::uniform_real_distribution<double> coord{-20.0, 20.0};
  std::uniform_int_distribution<int> kind{0, 9};
  Vec2 point() { return {coord(rng), coord(rng)}; }
  /// Mostly general segments, some degenerate, parallel or sharing a line.
  std::array<Vec2, 4> next() {
    Vec2 p0 = point(), p1 = point(), q0 = point(), q1 = point();
    switch (kind(rng)) {
      case 0: p1 = p0; break;                    // a point
      case 1: q1 = q0 + 0.7 * (p1 - p0); break;  // parallel
      case 2: q0 = p0 + 1.5 * (p1 - p0), q1 = p0 + 2.5 * (p1 - p0); break;  // collinear
      default: break;
    }
    return {p0, p1, q0, q1};
  }
};

TEST(SegmentDistanceProperties, SymmetricInItsArguments) {
  RandomSegments r;
  for (int i = 0; i < 2000; ++i) {
    const auto s = r.next();
    SCOPED_TRACE("seed " + std::to_string(seed()) + " case " + std::to_string(i));
    const double d = segment_distance(s[0], s[1], s[2], s[3]).distance;
    EXPECT_EQ(d, segment_distance(s[2], s[3], s[0], s[1]).distance);
    // Reversing a segment's direction changes only rounding.
    EXPECT_NEAR(d, segment_distance(s[1], s[0], s[3], s[2]).distance, 1e-13 * 40.0);
  }
}

TEST(SegmentDistanceProperties, InvariantUnderRigidMotionOfBoth) {
  RandomSegments r;
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  for (int i = 0; i < 2000; ++i) {
    const auto s = r.next();
    const double a = angle(r.rng);
    const Eigen::Matrix2d R = Eigen::Rotation2Dd(a).toRotationMatrix();
    const Vec2 t = r.point();
    const auto move = [&](const Vec2& p) -> Vec2 { return R * p + t; };
    SCOPED_TRACE("seed " + std::to_string(seed()) + " case " + std::to_string(i));
    const double d = segment_distance(s[0], s[1], s[2], s[3]).distance;
    const double moved = segment_distance(move(s[0]), move(s[1]), move(s[2]), move(s[3])).distance;
    EXPECT_NEAR(d, moved, 1e-12 * 60.0);  // coordinates up to ~60 mm after the motion
  }
}

TEST(SegmentDistanceProperties, AgreesWithDenseSamplingOfBothSegments) {
  // Sampling can only overestimate the distance, by at most half the sample spacing of each segment.
  RandomSegments r;
  constexpr int kSamples = 400;
  for (int i = 0; i < 200; ++i) {
    const auto s = r.next();
    double brute = std::numeric_limits<double>::infinity();
    for (int a = 0; a <= kSamples; ++a) {
      const Vec2 p = s[0] + (s[1] - s[0]) * (double(a) / kSamples);
      for (int b = 0; b <= kSamples; ++b) {
        const Vec2 q = s[2] + (s[3] - s[2]) * (double(b) / kSamples);
        brute = std::min(brute, (p - q).norm());
      }
    }
    const double slack = 0.5 * ((s[1] - s[0]).norm() + (s[3] - s[2]).norm()) / kSamples;
    const double d = segment_distance(s[0], s[1], s[2], s[3]).distance;
    SCOPED_TRACE("seed " + std::to_string(seed()) + " case " + std::to_string(i));
    EXPECT_LE(d, brute + 1e-12);
    EXPECT_GE(d, brute - slack - 1e-12);
  }
}

// ---------------------------------------------------------------------------------------------
// Outlines.

Mechanism mechanism(const char* name, Vec2 O1, Vec2 O2, std::array<double, 4> L, const char* mode, AssemblyMode asm_mode) {
  Mechanism m;
  m.name = name;
  m.O1 = O1;
  m.O2 = O2;
  m.L = L;
  m.working_mode = *parse_working_mode(mode);
  m.assembly_mode = asm_mode;
  return m;
}

/// A pose with the joints given by hand (only the positions matter to outlines).
Pose pose_at(Vec2 A1, Vec2 A2, Vec2 P) {
  Pose p;
  p.status = Status::ok;
  p.A1 = A1;
  p.A2 = A2;
  p.P = P;
  return p;
}

TEST(Outline, PartsPlanesAndRadiiForThePaperLayers) {
  const Mechanism m = mechanism("lower", {0, 0}, {12.5, 0}, {9, 9, 15, 15}, "-+", AssemblyMode::Plus);
  Geometry g;  // width 4 (radius 2), bosses 5 (radius 2.5), layers [0, 0, 1, 1], tactor 4
  const Pose pose = ik(m, {6.25, 15.5});
  const auto parts = link_outline(m, pose, g);
  // Adjacent planes: no pin crosses a plane; the motors sit under plane 0; P is in the top plane.
  ASSERT_EQ(parts.size(), 5u);
  const std::array<std::array<Vec2, 2>, 4> ends{{{m.O1, pose.A1}, {m.O2, pose.A2}, {pose.A1, pose.P}, {pose.A2, pose.P}}};
  for (std::size_t i = 0; i < 4; ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(parts[i].name, "L" + std::to_string(i + 1));
    EXPECT_EQ(parts[i].plane, g.layers[i]);
    ASSERT_EQ(parts[i].count, 3);  // the bosses are wider than the link
    EXPECT_EQ(parts[i].shapes[0].a, ends[i][0]);
    EXPECT_EQ(parts[i].shapes[0].b, ends[i][1]);
    EXPECT_EQ(parts[i].shapes[0].radius, 2.0);
    EXPECT_EQ(parts[i].shapes[1].radius, 2.5);
    EXPECT_EQ(parts[i].shapes[1].a, ends[i][0]);
    EXPECT_EQ(parts[i].shapes[2].a, ends[i][1]);
  }
  EXPECT_EQ(parts[4].name, "tactor");
  EXPECT_EQ(parts[4].plane, 2);
  EXPECT_EQ(tactor_plane(g), 2);
  EXPECT_EQ(parts[4].shapes[0].radius, 2.0);
  EXPECT_EQ(parts[4].shapes[0].a, pose.P);

  g.boss_diameter = 3.0;  // narrower than the 4 mm links: no separate boss disks
  for (const auto& part : link_outline(m, pose, g)) EXPECT_EQ(part.count, 1) << part.name;
}

TEST(Outline, PinsShaftsAndPostCrossTheirPlanes) {
  const Mechanism m = mechanism("lower", {0, 0}, {12.5, 0}, {9, 9, 15, 15}, "-+", AssemblyMode::Plus);
  Geometry g;
  // L1 in plane 1, L2 in 2, L3 in 0, L4 in 3: pin P spans planes 1 and 2 (between L3 and L4),
  // shaft O1 crosses plane 0, shaft O2 planes 0 and 1; nothing above P's top plane 3 but the tactor.
  g.layers = {1, 2, 0, 3};
  const Pose pose = ik(m, {6.25, 15.5});
  const auto parts = link_outline(m, pose, g);
  std::map<std::string, std::vector<int>> planes;
  for (const auto& p : parts) planes[std::string(p.name)].push_back(p.plane);
  EXPECT_EQ(planes["pin P"], (std::vector<int>{1, 2}));
  EXPECT_EQ(planes["shaft O1"], (std::vector<int>{0}));
  EXPECT_EQ(planes["shaft O2"], (std::vector<int>{0, 1}));
  EXPECT_EQ(planes.count("pin A1"), 0u);  // L1 (1) and L3 (0) are adjacent
  EXPECT_EQ(planes.count("pin A2"), 0u);  // L2 (2) and L4 (3) are adjacent
  EXPECT_EQ(planes.count("post P"), 0u);
  EXPECT_EQ(planes["tactor"], (std::vector<int>{4}));
  EXPECT_EQ(parts.size(), 10u);

  // Distal links below the proximal ones: the tactor post rises through planes 2 and 3.
  g.layers = {2, 3, 0, 1};
  std::map<std::string, std::vector<int>> below;
  for (const auto& p : link_outline(m, pose, g)) below[std::string(p.name)].push_back(p.plane);
  EXPECT_EQ(below["post P"], (std::vector<int>{2, 3}));
  EXPECT_EQ(below["pin A1"], (std::vector<int>{1}));  // between L1 (2) and L3 (0)
  EXPECT_EQ(below["pin A2"], (std::vector<int>{2}));  // between L2 (3) and L4 (1)
  for (const auto& p : link_outline(m, pose, g)) {
    if (p.name == "post P" || p.name.starts_with("pin")) EXPECT_EQ(p.shapes[0].radius, 0.5 * g.pin_diameter);
    if (p.name.starts_with("shaft")) EXPECT_EQ(p.shapes[0].radius, 0.5 * g.motor_shaft_diameter);
  }
}

TEST(Outline, UnreachablePoseHasNone) {
  const Mechanism m = mechanism("lower", {0, 0}, {12.5, 0}, {9, 9, 15, 15}, "-+", AssemblyMode::Plus);
  EXPECT_THAT([&] { link_outline(m, ik(m, {100, 100}), Geometry{}); },
              ThrowsMessage<InputError>(HasSubstr("unreachable")));
}

// ---------------------------------------------------------------------------------------------
// Interference of hand-built poses.

/// Geometry with thin links and small bosses, so that chosen pairs decide the clearance.
Geometry thin() {
  Geometry g;
  g.link_width = {1.0, 1.0, 1.0, 1.0};
  g.pin_diameter = 0.5;
  g.boss_diameter = 1.2;
  g.tactor_diameter = 4.0;
  g.min_clearance = 0.0;
  return g;
}

const Mechanism kUpper = mechanism("upper", {0, 31}, {12.5, 31}, {9, 9, 15, 15}, "+-", AssemblyMode::Minus);
const Mechanism kLower = mechanism("lower", {0, 0}, {12.5, 0}, {9, 9, 15, 15}, "-+", AssemblyMode::Plus);

TEST(Interference, TactorsTouchingAndOverlappingByOneNanometreScale) {
  // Tactors one above the other, everything else far apart: only the tactor disks (radius 2) meet.
  const Pose up = pose_at({-5, 25}, {17.5, 25}, {6.25, 17.5});
  const Pose touching = pose_at({-5, 6}, {17.5, 6}, {6.25, 13.5});  // |P - P'| = 4 = 2 + 2
  const Interference t = interference(kUpper, up, kLower, touching, thin());
  EXPECT_FALSE(t.collides);  // clearance 0 is not below min_clearance 0
  EXPECT_EQ(t.min_clearance_mm, 0.0);
  EXPECT_EQ(t.closest.name(), "upper.tactor vs lower.tactor");
  EXPECT_EQ(t.closest.plane, 2);

  const Pose overlapping = pose_at({-5, 6}, {17.5, 6}, {6.25, 13.5 + 1e-9});
  const Interference o = interference(kUpper, up, kLower, overlapping, thin());
  EXPECT_TRUE(o.collides);
  EXPECT_NEAR(o.min_clearance_mm, -1e-9, 1e-14);
  ASSERT_EQ(o.colliding.size(), 1u);
  EXPECT_EQ(o.colliding[0].name(), "upper.tactor vs lower.tactor");
}

TEST(Interference, CrossingDistalLinksInTheSamePlaneCollide) {
  // Lower tactor above the upper one: upper.L3 runs from A1 (-5, 25) through X = (6, 15) to
  // P (11.5, 10) and lower.L4 from A2 (17.5, 6) through X to P (0.25, 19.5): the centre lines cross
  // at X, mid-link, in plane 1, so the capsules overlap by both radii (0.5 + 0.5).
  const Pose up = pose_at({-5, 25}, {17.5, 25}, {11.5, 10});
  const Pose low = pose_at({-5, 6}, {17.5, 6}, {0.25, 19.5});
  const Interference in = interference(kUpper, up, kLower, low, thin());
  EXPECT_TRUE(in.collides);
  EXPECT_DOUBLE_EQ(in.min_clearance_mm, -1.0);
  std::map<std::string, double> colliding;
  for (const auto& p : in.colliding) colliding[p.name()] = p.clearance_mm;
  ASSERT_EQ(colliding.count("upper.L3 vs lower.L4"), 1u);
  EXPECT_DOUBLE_EQ(colliding["upper.L3 vs lower.L4"], -1.0);
  for (const auto& p : in.colliding) EXPECT_LT(p.clearance_mm, 0.0);
  EXPECT_TRUE(std::is_sorted(in.colliding.begin(), in.colliding.end(),
                             [](const PairClearance& a, const PairClearance& b) { return a.clearance_mm < b.clearance_mm; }));
  ASSERT_EQ(in.planes.size(), 3u);
  EXPECT_EQ(in.planes[0].plane, 0);
  EXPECT_EQ(in.planes[1].plane, 1);
  EXPECT_TRUE(in.planes[2].tactor);

  // L4 in a plane of its own: upper.L3 (plane 1) and lower.L4 (plane 2) pass over each other.
  Geometry split = thin();
  split.layers = {0, 0, 1, 2};
  const Interference apart = interference(kUpper, up, kLower, low, split);
  for (const auto& p : apart.colliding) {
    EXPECT_NE(p.name(), "upper.L3 vs lower.L4");
    EXPECT_NE(p.name(), "upper.L4 vs lower.L3");
  }
  EXPECT_EQ(apart.planes.size(), 4u);  // planes 0, 1, 2 and the tactor plane 3
}

TEST(Interference, SymmetricInTheTwoMechanismsAndInvariantUnderRigidMotion) {
  const Design d = load_design(kDesign);
  const Station& s = *d.station("index");
  const Geometry& g = *d.get<Geometry>();
  std::mt19937_64 rng(seed());
  std::uniform_real_distribution<double> ux(-1.25, 13.75), uy(9.5, 21.5), angle(-3.0, 3.0), shift(-50.0, 50.0);
  for (int i = 0; i < 200; ++i) {
    const Pose up = ik(*s.upper, {ux(rng), uy(rng)});
    const Pose low = ik(*s.lower, {ux(rng), uy(rng)});
    if (up.status == Status::unreachable || low.status == Status::unreachable) continue;
    SCOPED_TRACE("seed " + std::to_string(seed()) + " case " + std::to_string(i));
    const Interference in = interference(*s.upper, up, *s.lower, low, g);
    // Swapping which mechanism is called upper changes the names only.
    const Interference swapped = interference(*s.lower, low, *s.upper, up, g);
    EXPECT_NEAR(in.min_clearance_mm, swapped.min_clearance_mm, 1e-12);
    EXPECT_EQ(in.colliding.size(), swapped.colliding.size());
    EXPECT_EQ(in.collides, swapped.collides);

    // Move everything rigidly: bases, elbows and tactors.
    const Eigen::Matrix2d R = Eigen::Rotation2Dd(angle(rng)).toRotationMatrix();
    const Vec2 t(shift(rng), shift(rng));
    const auto move = [&](const Vec2& p) -> Vec2 { return R * p + t; };
    Mechanism mu = *s.upper, ml = *s.lower;
    mu.O1 = move(mu.O1), mu.O2 = move(mu.O2), ml.O1 = move(ml.O1), ml.O2 = move(ml.O2);
    const Pose mup = pose_at(move(up.A1), move(up.A2), move(up.P));
    const Pose mlow = pose_at(move(low.A1), move(low.A2), move(low.P));
    const Interference moved = interference(mu, mup, ml, mlow, g);
    EXPECT_NEAR(moved.min_clearance_mm, in.min_clearance_mm, 1e-11);
    EXPECT_EQ(moved.colliding.size(), in.colliding.size());
    for (std::size_t k = 0; k < std::min(moved.planes.size(), in.planes.size()); ++k) {
      EXPECT_NEAR(moved.planes[k].closest.clearance_mm, in.planes[k].closest.clearance_mm, 1e-11);
    }
  }
}

TEST(Interference, PaperStationTactorsStackedVertically) {
  // Index station, tactors on the vertical through the centre, s apart: the closest parts are the
  // two P bosses (radius 2.5 each) as long as the links diverge, so the clearance is s - 5.
  const Design d = load_design(kDesign);
  const Station& s = *d.station("index");
  for (double sep : {5.0, 6.0, 8.0, 10.0}) {
    SCOPED_TRACE(sep);
    const Vec2 c = s.target.center;
    const Pose up = ik(*s.upper, c + Vec2(0, 0.5 * sep));
    const Pose low = ik(*s.lower, c - Vec2(0, 0.5 * sep));
    const Interference in = interference(*s.upper, up, *s.lower, low, *d.get<Geometry>());
    EXPECT_NEAR(in.min_clearance_mm, sep - 5.0, 1e-12);
    EXPECT_EQ(in.closest.plane, 1);
    EXPECT_EQ(in.collides, sep - 5.0 < d.get<Geometry>()->min_clearance);
  }
  // Both at the centre: the P bosses coincide (-5), the tactor disks too (-4).
  const Interference same =
      interference(*s.upper, ik(*s.upper, s.target.center), *s.lower, ik(*s.lower, s.target.center), *d.get<Geometry>());
  EXPECT_DOUBLE_EQ(same.min_clearance_mm, -5.0);
  const auto tactors = std::find_if(same.colliding.begin(), same.colliding.end(),
                                    [](const PairClearance& p) { return p.name() == "upper.tactor vs lower.tactor"; });
  ASSERT_NE(tactors, same.colliding.end());
  EXPECT_DOUBLE_EQ(tactors->clearance_mm, -4.0);
}

// ---------------------------------------------------------------------------------------------
// Priority rule.

/// Independent free test through the public API: the lower can hold q and does not collide.
bool lower_free(const Station& s, const Geometry& g, const Pose& upper, const Vec2& q) {
  const Pose low = ik(*s.lower, q);
  if (!usable(*s.lower, low)) return false;
  return !interference(*s.upper, upper, *s.lower, low, g).collides;
}

/// Dense grid over the disk of radius r about c (spacing h): any free point?
std::optional<Vec2> free_point_within(const Station& s, const Geometry& g, const Pose& upper, const Vec2& c, double r,
                                      double h) {
  const int n = static_cast<int>(std::ceil(r / h));
  for (int j = -n; j <= n; ++j) {
    for (int i = -n; i <= n; ++i) {
      const Vec2 q = c + h * Vec2(i, j);
      if ((q - c).norm() > r) continue;
      if (lower_free(s, g, upper, q)) return q;
    }
  }
  // And the circle of radius r itself, finely.
  for (int k = 0; k < 4000; ++k) {
    const double a = 2.0 * std::numbers::pi * k / 4000.0;
    const Vec2 q = c + r * Vec2(std::cos(a), std::sin(a));
    if (lower_free(s, g, upper, q)) return q;
  }
  return std::nullopt;
}

class PriorityRule : public ::testing::Test {
 protected:
  void SetUp() override {
    design_ = load_design(kDesign);
    g_ = *design_.get<Geometry>();
  }
  Design design_;
  Geometry g_;
};

TEST_F(PriorityRule, TargetsThatDoNotCollideAreLeftAlone) {
  const Station& s = *design_.station("index");
  const Vec2 up(6.25, 19.5), low(6.25, 11.5);  // 8 mm apart vertically: clearance 3 mm
  const PriorityResult r = apply_priority(*s.upper, *s.lower, g_, up, low);
  EXPECT_EQ(r.status, PriorityStatus::clear);
  EXPECT_EQ(r.lower_point, low);
  EXPECT_EQ(r.moved_mm, 0.0);
  EXPECT_EQ(r.lower.theta1, ik(*s.lower, low).theta1);
  EXPECT_EQ(r.upper.theta1, ik(*s.upper, up).theta1);
  ASSERT_TRUE(r.before && r.after);
  EXPECT_FALSE(r.before->collides);
  EXPECT_NEAR(r.before->min_clearance_mm, 3.0, 1e-12);
}

TEST_F(PriorityRule, BothAtTheCentreMovesTheLowerByThePinBossDistance) {
  // The P bosses (2.5 + 2.5) plus min_clearance 0.3 need 5.3 mm between the tactors; straight
  // below the upper tactor the links diverge, so 5.3 mm (and no less) is free: the answer is 5.3.
  for (const char* name : {"index", "thumb"}) {
    SCOPED_TRACE(name);
    const Station& s = *design_.station(name);
    const Vec2 c = s.target.center;
    const PriorityResult r = apply_priority(*s.upper, *s.lower, g_, c, c);
    ASSERT_EQ(r.status, PriorityStatus::moved);
    EXPECT_TRUE(r.before->collides);
    EXPECT_FALSE(r.after->collides);
    EXPECT_GE(r.after->min_clearance_mm, g_.min_clearance);
    EXPECT_NEAR(r.moved_mm, 5.3, 1e-3);
    EXPECT_GE(r.moved_mm, 5.3 - 1e-12);
    EXPECT_DOUBLE_EQ(r.moved_mm, (r.lower_point - c).norm());
    // The upper keeps its solution.
    EXPECT_EQ(r.upper.P, ik(*s.upper, c).P);
    EXPECT_EQ(r.upper.theta2, ik(*s.upper, c).theta2);
    EXPECT_TRUE(lower_free(s, g_, r.upper, r.lower_point));
  }
}

TEST_F(PriorityRule, NoCollisionFreePointIsCloserThanTheMovedTarget) {
  // Targets chosen to collide in different ways: the lower above the upper, beside it, a little
  // below it, and the thumb station.
  struct Case {
    const char* station;
    Vec2 upper, lower;
  };
  const std::vector<Case> cases{{"index", {6.25, 15.5}, {6.25, 15.5}},
                                {"index", {6.25, 14.0}, {9.0, 16.0}},
                                {"index", {3.0, 17.0}, {8.0, 15.0}},
                                {"index", {6.25, 17.0}, {6.0, 13.0}},
                                {"thumb", {9.0, 18.0}, {4.0, 19.0}}};
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.station) + " upper (" + std::to_string(c.upper.x()) + ", " + std::to_string(c.upper.y()) +
                 ") lower (" + std::to_string(c.lower.x()) + ", " + std::to_string(c.lower.y()) + ")");
    const Station& s = *design_.station(c.station);
    const PriorityResult r = apply_priority(*s.upper, *s.lower, g_, c.upper, c.lower);
    ASSERT_EQ(r.status, PriorityStatus::moved) << r.reason;
    EXPECT_TRUE(lower_free(s, g_, r.upper, r.lower_point));
    EXPECT_DOUBLE_EQ(r.moved_mm, (r.lower_point - c.lower).norm());
    // Dense sampling of the disk 2e-3 mm smaller than the move finds no free point.
    const auto closer = free_point_within(s, g_, r.upper, c.lower, r.moved_mm - 2e-3, 0.04);
    EXPECT_FALSE(closer.has_value()) << "free point " << closer->transpose() << " at "
                                     << (*closer - c.lower).norm() << " mm, moved " << r.moved_mm;
  }
}

TEST_F(PriorityRule, UnusableTargetsAreReportedNotMoved) {
  const Station& s = *design_.station("index");
  const PriorityResult up = apply_priority(*s.upper, *s.lower, g_, {100, 100}, {6.25, 15.5});
  EXPECT_EQ(up.status, PriorityStatus::upper_unusable);
  EXPECT_THAT(up.reason, HasSubstr("unreachable"));
  EXPECT_EQ(up.lower_point, Vec2(6.25, 15.5));
  EXPECT_EQ(up.moved_mm, 0.0);
  const PriorityResult low = apply_priority(*s.upper, *s.lower, g_, {6.25, 15.5}, {100, -100});
  EXPECT_EQ(low.status, PriorityStatus::lower_unusable);
  EXPECT_EQ(low.moved_mm, 0.0);
  EXPECT_FALSE(low.before.has_value());
}

TEST_F(PriorityRule, NoFreePointWhenTheUpperBlocksEverything) {
  // Huge tactors (40 mm) cover every point the lower can reach near the upper: nothing is free.
  const Station& s = *design_.station("index");
  Geometry g = g_;
  g.tactor_diameter = 80.0;
  const PriorityResult r = apply_priority(*s.upper, *s.lower, g, s.target.center, s.target.center);
  EXPECT_EQ(r.status, PriorityStatus::no_free_point);
  EXPECT_EQ(r.moved_mm, 0.0);
  EXPECT_EQ(r.lower_point, s.target.center);
}

TEST_F(PriorityRule, BadSearchOptionsAreInputErrors) {
  const Station& s = *design_.station("index");
  PriorityOptions o;
  o.rays = 2;
  EXPECT_THROW(apply_priority(*s.upper, *s.lower, g_, s.target.center, s.target.center, o), InputError);
}

// ---------------------------------------------------------------------------------------------
// Collision map.

TEST(CollisionMap, PaperStations) {
  const Design d = load_design(kDesign);
  const Geometry& g = *d.get<Geometry>();
  for (const Station& s : d.stations) {
    SCOPED_TRACE(s.name);
    const CollisionMap map = collision_map(s, g);
    // Grid points: every one inside the ellipse, the centre among them.
    ASSERT_FALSE(map.points.empty());
    EXPECT_NE(std::find(map.points.begin(), map.points.end(), s.target.center), map.points.end());
    const double a = 0.5 * s.target.axes.x(), b = 0.5 * s.target.axes.y();
    for (const Vec2& p : map.points) {
      const Vec2 q = p - s.target.center;
      EXPECT_LE(q.x() * q.x() / (a * a) + q.y() * q.y() / (b * b), 1.0 + 1e-12);
    }
    const auto up_n = std::count(map.upper_ok.begin(), map.upper_ok.end(), 1);
    const auto low_n = std::count(map.lower_ok.begin(), map.lower_ok.end(), 1);
    EXPECT_EQ(map.pairs, static_cast<std::size_t>(up_n * low_n));
    EXPECT_GT(map.colliding_fraction, 0.0);
    EXPECT_LT(map.colliding_fraction, 1.0);
    // Tactors closer than 5.3 mm always collide (P bosses); the extremes are real pairs.
    ASSERT_TRUE(map.any_free && map.any_colliding);
    EXPECT_GE(map.min_free_separation_mm, 5.3);
    const Pose fu = ik(*s.upper, map.min_free_pair[0]), fl = ik(*s.lower, map.min_free_pair[1]);
    EXPECT_FALSE(interference(*s.upper, fu, *s.lower, fl, g).collides);
    EXPECT_NEAR((map.min_free_pair[0] - map.min_free_pair[1]).norm(), map.min_free_separation_mm, 1e-12);
    const Pose cu = ik(*s.upper, map.max_colliding_pair[0]), cl = ik(*s.lower, map.max_colliding_pair[1]);
    EXPECT_TRUE(interference(*s.upper, cu, *s.lower, cl, g).collides);
    std::size_t total = 0, hits = 0;
    for (const SeparationBin& bin : map.bins) {
      total += bin.pairs, hits += bin.colliding;
      if (bin.hi_mm <= 5.3 && bin.pairs > 0) EXPECT_EQ(bin.colliding, bin.pairs) << bin.lo_mm;
    }
    EXPECT_EQ(total, map.pairs);
    EXPECT_EQ(hits, map.colliding);
    EXPECT_EQ(map.centre_rule.status, PriorityStatus::moved);
  }
}

TEST(CollisionMap, NeedsBothMechanismsAndASensibleSpacing) {
  const Design d = load_design(kDesign);
  Station one = *d.station("index");
  one.upper.reset();
  EXPECT_THAT([&] { collision_map(one, *d.get<Geometry>()); }, ThrowsMessage<InputError>(HasSubstr("both")));
  CollisionMapOptions o;
  o.spacing_mm = 0.0;
  EXPECT_THROW(collision_map(*d.station("index"), *d.get<Geometry>(), o), InputError);
  o.spacing_mm = 1e-4;
  EXPECT_THROW(collision_map(*d.station("index"), *d.get<Geometry>(), o), InputError);
}

TEST(CollisionMap, PictureAndJson) {
  const Design d = load_design(kDesign);
  const Station& s = *d.station("index");
  CollisionMapOptions o;
  o.spacing_mm = 1.5;
  const CollisionMap map = collision_map(s, *d.get<Geometry>(), o);
  const RenderedPlot pic = plot_collision_map(s, *d.get<Geometry>(), map);
  ASSERT_GT(pic.png.size(), 8u);
  EXPECT_EQ(pic.png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_THAT(pic.svg, HasSubstr("<svg"));
  const Json j = to_json(map);
  EXPECT_EQ(j["points"], map.points.size());
  EXPECT_EQ(j["colliding_pairs"], map.colliding);
  EXPECT_DOUBLE_EQ(j["min_free_separation_mm"].get<double>(), map.min_free_separation_mm);
  EXPECT_EQ(j["priority_at_centre"]["status"], "moved");
}

// ---------------------------------------------------------------------------------------------
// Collision fraction (what a sweep records) and the pruned pair test behind it.

TEST(OutlinesCollide, SameVerdictAsTheUnprunedMinimumOnRandomPosePairs) {
  const Design d = load_design(kDesign);
  const Geometry& g = *d.get<Geometry>();
  const Station& s = *d.station("index");
  std::mt19937_64 rng(seed());
  std::uniform_real_distribution<double> ux(-7.5, 7.5), uy(-6.0, 6.0);
  int hits = 0, misses = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Pose pu = ik(*s.upper, s.target.center + Vec2(ux(rng), uy(rng)));
    const Pose pl = ik(*s.lower, s.target.center + Vec2(ux(rng), uy(rng)));
    if (pu.status == Status::unreachable || pl.status == Status::unreachable) continue;
    const auto up = link_outline(*s.upper, pu, g), low = link_outline(*s.lower, pl, g);
    // The reference: every same-plane capsule pair, no pruning (interference()).
    const double exact = interference(*s.upper, pu, *s.lower, pl, g).min_clearance_mm;
    for (double threshold : {-0.5, 0.0, 0.2, 1.0, 3.0, exact, std::nextafter(exact, 1e9)}) {
      const bool expected = exact < threshold;
      EXPECT_EQ(outlines_collide(up, low, threshold), expected) << "threshold " << threshold << ", clearance " << exact;
      (expected ? hits : misses) += 1;
    }
  }
  EXPECT_GT(hits, 100);
  EXPECT_GT(misses, 100);
}

TEST(CollisionFraction, CountsEveryUsablePairLikeAnUnprunedInterferenceCheck) {
  const Design d = load_design(kDesign);
  const Geometry& g = *d.get<Geometry>();
  for (const Station& s : d.stations) {
    SCOPED_TRACE(s.name);
    const double spacing = 2.0;
    const CollisionFraction f = collision_fraction(s, g, spacing);
    // The grid: points 2 mm apart inside the ellipse; their number is the ellipse area over
    // spacing^2 up to the boundary cells (Gauss circle problem: within the perimeter / spacing).
    const std::vector<Vec2> pts = ellipse_grid(s.target, spacing);
    ASSERT_EQ(f.points, pts.size());
    const double a = 0.5 * s.target.axes.x(), b = 0.5 * s.target.axes.y();
    const double area_pts = std::numbers::pi * a * b / (spacing * spacing);
    EXPECT_NEAR(double(pts.size()), area_pts, 2.0 * std::numbers::pi * std::max(a, b) / spacing);
    // Brute force over every pair with the full interference report.
    std::size_t pairs = 0, colliding = 0, same_point = 0;
    for (const Vec2& p : pts) {
      const Pose pu = ik(*s.upper, p);
      if (!usable(*s.upper, pu)) continue;
      same_point += usable(*s.lower, ik(*s.lower, p)) ? 1 : 0;
      for (const Vec2& q : pts) {
        const Pose pl = ik(*s.lower, q);
        if (!usable(*s.lower, pl)) continue;
        ++pairs;
        colliding += interference(*s.upper, pu, *s.lower, pl, g).collides ? 1 : 0;
      }
    }
    EXPECT_EQ(f.pairs, pairs);
    EXPECT_EQ(f.colliding, colliding);
    EXPECT_DOUBLE_EQ(f.fraction, double(colliding) / double(pairs));
    // Both tactors on the same grid point always collide (the tactor disks overlap); tactors at
    // opposite ends of the ellipse do not.
    ASSERT_GT(same_point, 0u);
    EXPECT_GE(f.colliding, same_point);
    EXPECT_LT(f.fraction, 1.0);
    // The collision map on the same grid counts the same pairs.
    CollisionMapOptions o;
    o.spacing_mm = spacing;
    const CollisionMap map = collision_map(s, g, o);
    EXPECT_EQ(map.pairs, f.pairs);
    EXPECT_EQ(map.colliding, f.colliding);
  }
}

TEST(CollisionFraction, GrowsWithTheRequiredClearance) {
  const Design d = load_design(kDesign);
  const Station& s = *d.station("thumb");
  Geometry g = *d.get<Geometry>();
  double last = -1.0;
  for (double clearance : {0.0, 0.5, 1.0, 2.0, 4.0}) {
    g.min_clearance = clearance;
    const double f = collision_fraction(s, g, 2.5).fraction;
    EXPECT_GE(f, last) << "min_clearance " << clearance;  // a pair colliding at c collides at c' > c
    last = f;
  }
  EXPECT_GT(last, 0.0);
  Station one = s;
  one.lower.reset();
  EXPECT_THAT([&] { collision_fraction(one, g, 2.0); }, ThrowsMessage<InputError>(HasSubstr("both")));
  EXPECT_THROW(collision_fraction(s, g, -1.0), InputError);
}

TEST(CollisionJson, InterferenceAndRule) {
  const Design d = load_design(kDesign);
  const Station& s = *d.station("index");
  const PriorityResult r = apply_priority(*s.upper, *s.lower, *d.get<Geometry>(), s.target.center, s.target.center);
  const Json j = to_json(r);
  EXPECT_EQ(j["status"], "moved");
  EXPECT_TRUE(j["before"]["collides"].get<bool>());
  EXPECT_FALSE(j["after"]["collides"].get<bool>());
  EXPECT_EQ(j["before"]["closest"]["pair"], r.before->closest.name());
  EXPECT_DOUBLE_EQ(j["moved_mm"].get<double>(), r.moved_mm);
  EXPECT_EQ(j["before"]["planes"].size(), 3u);
  EXPECT_EQ(j["before"]["planes"][2]["tactor_plane"], true);
}

}  // namespace
}  // namespace fivebar
