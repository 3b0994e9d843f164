// Cost of the `report` machinery on the paper's index lower mechanism: the __float128 reference
// (what every error of the report is measured against) beside the same FK/IK in float, double and
// long double (report/precision.hpp), and one mechanism's whole stability catalogue.
//   ./build/fivebar_bench --benchmark_filter='report'
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "fivebar/report.hpp"
#include "report/precision.hpp"
#include "report/quad.hpp"
#include "paper.hpp"

namespace {

using fivebar::Mechanism;
using fivebar::testing::paper_mechanism;
/// Joint angles around the symmetric pose of the target centre (all reachable).
std::vector<std::array<double, 2>> angles() {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<std::array<double, 2>> out(1024);
  for (auto& a : out) a = {2.29 + u(rng), 0.85 + u(rng)};
  return out;
}

void report_quad_fk(benchmark::State& state) {
  const fivebar::quadref::QMechanism m(paper_mechanism("index", "lower"));
  const auto in = angles();
  std::size_t k = 0;
  for (auto _ : state) {
    const auto p = fivebar::quadref::fk(m, in[k][0], in[k][1], 1);
    benchmark::DoNotOptimize(p.P.x);
    k = (k + 1) % in.size();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(report_quad_fk);

void report_quad_ik(benchmark::State& state) {
  const Mechanism mech = paper_mechanism("index", "lower");
  const fivebar::quadref::QMechanism m(mech);
  std::vector<fivebar::quadref::QVec> pts;
  for (const auto& a : angles()) pts.push_back(fivebar::quadref::fk(m, a[0], a[1], 1).P);
  std::size_t k = 0;
  for (auto _ : state) {
    const auto p = fivebar::quadref::ik(m, pts[k], -1, 1);
    benchmark::DoNotOptimize(p.theta1);
    k = (k + 1) % pts.size();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(report_quad_ik);

template <class T>
void report_precision_fk(benchmark::State& state) {
  const fivebar::precision::MechanismT<T> m(paper_mechanism("index", "lower"));
  const auto in = angles();
  std::size_t k = 0;
  for (auto _ : state) {
    T x, y;
    benchmark::DoNotOptimize(fivebar::precision::fk(m, T(in[k][0]), T(in[k][1]), 1, x, y));
    benchmark::DoNotOptimize(x);
    k = (k + 1) % in.size();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_TEMPLATE(report_precision_fk, float);
BENCHMARK_TEMPLATE(report_precision_fk, double);
BENCHMARK_TEMPLATE(report_precision_fk, long double);

void report_stability_catalogue(benchmark::State& state) {
  const Mechanism m = paper_mechanism("index", "lower");
  fivebar::Ellipse e;
  e.center = {6.25, 15.5};
  e.axes = {15.0, 12.0};
  for (auto _ : state) {
    const auto r = fivebar::stability_catalogue(m, e, "index/lower");
    benchmark::DoNotOptimize(r.cases.size());
  }
}
BENCHMARK(report_stability_catalogue)->Unit(benchmark::kMillisecond);

}  // namespace
