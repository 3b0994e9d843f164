// fivebar::core on its own (docs/architecture.md "Layers"): a program that needs the design,
// kinematics, workspaces and coverage links this library alone, without VTK, cairo, MPI or
// quadmath (ctest core_links_no_heavy_library checks the executable's dynamic libraries).

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "fivebar/coverage/coverage.hpp"
#include "fivebar/design.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/workspace/region.hpp"

namespace fivebar {
namespace {

const std::filesystem::path kDesign = std::filesystem::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml";

TEST(Core, LoadsTheShowcaseWithEverySectionAndRoundTripsIt) {
  const Design d = load_design(kDesign);
  ASSERT_NE(d.get<ControllerSettings>(), nullptr);
  EXPECT_EQ(d.get<ControllerSettings>()->loop_rate_hz, 100.0);  // the paper's 100 Hz loop
  const Design back = load_design_from_string(to_yaml(d), "back.yaml");
  EXPECT_EQ(to_yaml(back), to_yaml(d));
}

TEST(Core, InverseThenForwardKinematicsReturnsThePoint) {
  const Design d = load_design(kDesign);
  const Mechanism& m = *d.station("index")->lower;
  const Vec2 p(6.25, 15.5);  // the index target's centre (paper Table 1)
  const Pose inverse = ik(m, p);
  ASSERT_EQ(inverse.status, Status::ok);
  const Pose forward = fk(m, inverse.theta1, inverse.theta2);
  ASSERT_EQ(forward.status, Status::ok);
  EXPECT_NEAR((forward.P - p).norm(), 0.0, 1e-12);
}

TEST(Core, TheShowcaseTargetIsCovered) {
  const Design d = load_design(kDesign);
  const Station& s = *d.station("index");
  const CoverageResult r = coverage(*s.lower, s.target);
  EXPECT_TRUE(r.covered);
  EXPECT_GT(r.margin_mm, 0.0);
}

}  // namespace
}  // namespace fivebar
