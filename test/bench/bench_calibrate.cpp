// Kinematic calibration (fivebar/calibrate.hpp): goals, calibrating 200 poses < 50 ms
// and planning 30 poses < 1 s.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <string>

#include "fivebar/calibrate.hpp"
#include "fivebar/design.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/sections/controller.hpp"

namespace {

using namespace fivebar;

const Design& paper() {
  static const Design d = load_design(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  return d;
}

/// 200 poses of a lower mechanism whose links are 0.1 mm off, 0.02 mm noise.
std::vector<calibrate::Measurement> poses(int n) {
  const Design& d = paper();
  const Station& st = *d.station("index");
  Mechanism truth = *st.lower;
  truth.L[2] += 0.1;
  truth.O2.x() -= 0.1;
  const auto pot1 = d.get<ControllerSettings>()->joint("index", "lower", 1).potentiometer;
  const auto pot2 = d.get<ControllerSettings>()->joint("index", "lower", 2).potentiometer;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<calibrate::Measurement> out;
  while (static_cast<int>(out.size()) < n) {
    const Vec2 p = st.target.center + Vec2(u(rng) * st.target.axes.x() / 2, u(rng) * st.target.axes.y() / 2);
    const Pose pose = ik(truth, p);
    if (pose.status != Status::ok) continue;
    calibrate::Measurement m;
    m.station = "index";
    m.mechanism = "lower";
    m.volts1 = pot1.volts_at_zero + pose.theta1 / pot1.rad_per_volt;
    m.volts2 = pot2.volts_at_zero + pose.theta2 / pot2.rad_per_volt;
    m.point = pose.P + Vec2(noise(rng), noise(rng));
    m.line = static_cast<int>(out.size()) + 2;
    out.push_back(m);
  }
  return out;
}

void BM_calibrate_200_poses(benchmark::State& state) {
  const auto rows = poses(200);
  for (auto _ : state) {
    const auto r = calibrate::calibrate(paper(), rows, {}, "bench");
    benchmark::DoNotOptimize(r.after.rms_mm);
  }
}
BENCHMARK(BM_calibrate_200_poses)->Unit(benchmark::kMillisecond);

void BM_calibrate_plan_30_poses(benchmark::State& state) {
  calibrate::PlanOptions o;
  o.poses = 30;
  for (auto _ : state) {
    const auto plans = calibrate::plan_poses(paper(), "index", "lower", o);
    benchmark::DoNotOptimize(plans.front().observability_index);
  }
}
BENCHMARK(BM_calibrate_plan_30_poses)->Unit(benchmark::kMillisecond);

}  // namespace
