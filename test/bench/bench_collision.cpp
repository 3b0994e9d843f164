// Speed of the collision checks on the paper's index station (designs/iros2022.yaml): one segment
// distance, one interference of a pose pair (outlines and every shared-plane pair), the priority
// rule when it has to search, one pattern checked at 100 Hz, and the whole collision map.
//   ./build/fivebar_bench --benchmark_filter='collision|priority|pattern|segment'
#include <benchmark/benchmark.h>

#include <filesystem>
#include <random>
#include <vector>

#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/collision.hpp"
#include "fivebar/pattern.hpp"

namespace {

using namespace fivebar;

const Design& design() {
  static const Design d = load_design(std::filesystem::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml");
  return d;
}

void BM_segment_distance(benchmark::State& state) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> c(-20.0, 20.0);
  std::vector<Vec2> p(4096);
  for (auto& v : p) v = {c(rng), c(rng)};
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(segment_distance(p[i], p[i + 1], p[i + 2], p[i + 3]).distance);
    i = (i + 4) & 4095;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_segment_distance);

void BM_interference_pose_pair(benchmark::State& state) {
  const Station& s = *design().station("index");
  const Pose up = ik(*s.upper, {6.25, 19.5});
  const Pose low = ik(*s.lower, {6.25, 11.5});
  for (auto _ : state) benchmark::DoNotOptimize(interference(*s.upper, up, *s.lower, low, *design().get<Geometry>()).min_clearance_mm);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_interference_pose_pair);

void BM_priority_rule_search(benchmark::State& state) {
  // Both targets at the centre: the search moves the lower 5.3 mm.
  const Station& s = *design().station("index");
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        apply_priority(*s.upper, *s.lower, *design().get<Geometry>(), s.target.center, s.target.center).moved_mm);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_priority_rule_search)->Unit(benchmark::kMillisecond);

void BM_pattern_twist_1s_100hz(benchmark::State& state) {
  const Station& s = *design().station("index");
  const PatternSpec spec = design().get<PatternSettings>()->for_station("index")[2];
  for (auto _ : state) {
    benchmark::DoNotOptimize(check_pattern(s, *design().get<Geometry>(), spec, design().get<PatternSettings>()->max_joint_speed).passed);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(spec.samples()));
}
BENCHMARK(BM_pattern_twist_1s_100hz)->Unit(benchmark::kMillisecond);

void BM_collision_map_index(benchmark::State& state) {
  const Station& s = *design().station("index");
  for (auto _ : state) benchmark::DoNotOptimize(collision_map(s, *design().get<Geometry>()).colliding);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_collision_map_index)->Unit(benchmark::kMillisecond);

/// The per-design collision fraction of a sweep (2 mm grid: 35 points, 1225 pairs on the index).
void BM_collision_fraction_index(benchmark::State& state) {
  const Station& s = *design().station("index");
  for (auto _ : state) benchmark::DoNotOptimize(collision_fraction(s, *design().get<Geometry>(), 2.0).colliding);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_collision_fraction_index)->Unit(benchmark::kMicrosecond);

}  // namespace
