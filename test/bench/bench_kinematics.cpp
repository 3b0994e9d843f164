// FK/IK speed on the paper's index lower mechanism, each beside a floor that does only the work no
// FK/IK can avoid, with the same sin/cos/atan2 as the measured code (glibc for scalar, fastmath.hpp
// for batch). A circle intersection needs one square root (the chord height; detail::chord shows
// the centre distance's own root is avoidable), so the floors are: FK, sine and cosine of both
// angles and one square root; IK, two square roots (one per leg) and two atan2. The floors leave
// out the one division per intersection that every FK and IK also needs (the foot is a rational
// function of d^2). Items per second = evaluations per second. Compare ratios within one run:
//   ./build/fivebar_bench --benchmark_filter='fk|ik'
// The batch IK takes its angles with detail::fast_angle, which knows the elbow offset's length
// (the proximal link) and needs one division where the general fast_atan2 needs two. The plain
// floor has two general atan2 (ik_floor*); ik_floor16_known_length has two fast_angle instead, the
// stricter floor by the same reasoning that took the centre distance's root out: both are here so
// that the ratio can be read against either.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "fivebar/detail/fastmath.hpp"
#include "fivebar/kinematics.hpp"
#include "paper.hpp"

namespace {

using fivebar::Mechanism;
using fivebar::testing::paper_mechanism;
using fivebar::Status;
using fivebar::Vec2;

constexpr std::size_t kN = 4096;

/// Points uniformly in the index target ellipse (15 x 12 mm at (6.25, 15.5)) and their angles.
struct Data {
  std::vector<double> px, py, t1, t2, ox, oy, o1, o2;
  std::vector<Status> st;
  Data() : px(kN), py(kN), t1(kN), t2(kN), ox(kN), oy(kN), o1(kN), o2(kN), st(kN) {
    const Mechanism m = paper_mechanism("index", "lower");
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (std::size_t k = 0; k < kN;) {
      const double x = u(rng), y = u(rng);
      if (x * x + y * y > 1.0) continue;
      px[k] = 6.25 + 7.5 * x;
      py[k] = 15.5 + 6.0 * y;
      const fivebar::Pose p = fivebar::ik(m, {px[k], py[k]});
      t1[k] = p.theta1;
      t2[k] = p.theta2;
      ++k;
    }
  }
};
const Data& data() {
  static const Data d;
  return d;
}

// The batch floors: the same loops the library's batch kernels vectorise, compiled the same way
// (FIVEBAR_SIMD_CLONES: baseline, AVX2 and AVX-512 clones, picked at load time), and not inlined
// into the benchmark so that the compiler sees them as the library sees its kernels. Each comes in
// two schedules, and the faster one is the floor: as written (`floor`), GCC runs one vector of
// points per iteration; with a 16-bit output per point beside the doubles (`floor16`, as the
// kernels' status codes) it runs 16 or 32 points per iteration, whose independent chains hide
// latency. On the reference machine floor16 is the faster: with the AVX-512 clone by 17% (FK) and
// 3% (IK); in an AVX2-only build of the same work, by about 30%.

/// The unavoidable work of one FK: sin and cos of both angles, one square root.
inline void fk_floor_one(double t1, double t2, double& x, double& y) {
  double s1, c1, s2, c2;
  fivebar::detail::fast_sincos(t1, s1, c1);
  fivebar::detail::fast_sincos(t2, s2, c2);
  x = std::sqrt(c1 * c2 + 2.0);
  y = s1 * s2;
}

/// The unavoidable work of one IK: a square root per leg, and an atan2 per leg.
inline void ik_floor_one(double x, double y, double& a, double& b) {
  const double r1 = std::sqrt(x * x + y * y), r2 = std::sqrt(x * y + 400.0);
  a = fivebar::detail::fast_atan2(r1 - x, y);
  b = fivebar::detail::fast_atan2(r2 - y, x);
}

FIVEBAR_SIMD_CLONES __attribute__((noinline)) void fk_floor_loop(const double* t1, const double* t2,
                                                                   double* __restrict x, double* __restrict y,
                                                                   std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) fk_floor_one(t1[k], t2[k], x[k], y[k]);
}

FIVEBAR_SIMD_CLONES __attribute__((noinline)) void fk_floor16_loop(const double* t1, const double* t2,
                                                                     double* __restrict x, double* __restrict y,
                                                                     std::int16_t* __restrict tag, std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) {
    fk_floor_one(t1[k], t2[k], x[k], y[k]);
    tag[k] = std::int16_t(k);
  }
}

/// The same with angles of known length (detail::fast_angle, one division each, as the batch IK).
inline void ik_floor_known_length_one(double x, double y, double& a, double& b) {
  const double r1 = std::sqrt(x * x + y * y), r2 = std::sqrt(x * y + 400.0);
  a = fivebar::detail::fast_angle(r1 - x, y, 9.0);
  b = fivebar::detail::fast_angle(r2 - y, x, 9.0);
}

FIVEBAR_SIMD_CLONES __attribute__((noinline)) void ik_floor_loop(const double* px, const double* py,
                                                                   double* __restrict a, double* __restrict b,
                                                                   std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) ik_floor_one(px[k], py[k], a[k], b[k]);
}

FIVEBAR_SIMD_CLONES __attribute__((noinline)) void ik_floor16_loop(const double* px, const double* py,
                                                                     double* __restrict a, double* __restrict b,
                                                                     std::int16_t* __restrict tag, std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) {
    ik_floor_one(px[k], py[k], a[k], b[k]);
    tag[k] = std::int16_t(k);
  }
}

FIVEBAR_SIMD_CLONES __attribute__((noinline)) void ik_floor16_known_length_loop(const double* px, const double* py,
                                                                                  double* __restrict a,
                                                                                  double* __restrict b,
                                                                                  std::int16_t* __restrict tag,
                                                                                  std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) {
    ik_floor_known_length_one(px[k], py[k], a[k], b[k]);
    tag[k] = std::int16_t(k);
  }
}

/// Times one batch floor over kN inputs: `loop(in1, in2, out1, out2, tag)`.
template <class Loop>
void run_floor(benchmark::State& state, const std::vector<double>& in1, const std::vector<double>& in2, Loop loop) {
  std::vector<double> o1(kN), o2(kN);
  std::vector<std::int16_t> tag(kN);
  for (auto _ : state) {
    loop(in1.data(), in2.data(), o1.data(), o2.data(), tag.data());
    benchmark::DoNotOptimize(o1.data());
    benchmark::DoNotOptimize(o2.data());
    benchmark::DoNotOptimize(tag.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kN));
}

// --- FK --------------------------------------------------------------------------------------------

void BM_fk_floor_scalar(benchmark::State& state) {
  const Data& d = data();
  std::vector<double> ox(kN), oy(kN);
  for (auto _ : state) {
    for (std::size_t k = 0; k < kN; ++k) {
      const double s1 = std::sin(d.t1[k]), c1 = std::cos(d.t1[k]);
      const double s2 = std::sin(d.t2[k]), c2 = std::cos(d.t2[k]);
      ox[k] = std::sqrt(c1 * c2 + 2.0);
      oy[k] = s1 * s2;
    }
    benchmark::DoNotOptimize(ox.data());
    benchmark::DoNotOptimize(oy.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kN));
}
BENCHMARK(BM_fk_floor_scalar);

void BM_fk_scalar(benchmark::State& state) {
  const Data& d = data();
  const Mechanism m = paper_mechanism("index", "lower");
  std::vector<double> ox(kN), oy(kN);
  for (auto _ : state) {
    for (std::size_t k = 0; k < kN; ++k) {
      const fivebar::PointResult r = fivebar::fk_point(m, d.t1[k], d.t2[k]);
      ox[k] = r.P.x();
      oy[k] = r.P.y();
    }
    benchmark::DoNotOptimize(ox.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kN));
}
BENCHMARK(BM_fk_scalar);

/// The full pose: point, Jacobian, LCI, transmission angles, singularity distances.
void BM_fk_scalar_full_pose(benchmark::State& state) {
  const Data& d = data();
  const Mechanism m = paper_mechanism("index", "lower");
  double acc = 0.0;
  for (auto _ : state) {
    for (std::size_t k = 0; k < kN; ++k) acc += fivebar::fk(m, d.t1[k], d.t2[k]).lci;
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kN));
}
BENCHMARK(BM_fk_scalar_full_pose);

void BM_fk_floor_batch(benchmark::State& state) {
  run_floor(state, data().t1, data().t2, [](const double* a, const double* b, double* x, double* y, std::int16_t*) {
    fk_floor_loop(a, b, x, y, kN);
  });
}
BENCHMARK(BM_fk_floor_batch);

void BM_fk_floor16_batch(benchmark::State& state) {
  run_floor(state, data().t1, data().t2, [](const double* a, const double* b, double* x, double* y, std::int16_t* tag) {
    fk_floor16_loop(a, b, x, y, tag, kN);
  });
}
BENCHMARK(BM_fk_floor16_batch);

void BM_fk_batch(benchmark::State& state) {
  const Data& d = data();
  const Mechanism m = paper_mechanism("index", "lower");
  std::vector<double> ox(kN), oy(kN);
  std::vector<Status> st(kN);
  for (auto _ : state) {
    fivebar::fk_batch(m, d.t1, d.t2, ox, oy, st);
    benchmark::DoNotOptimize(ox.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kN));
}
BENCHMARK(BM_fk_batch);

// The Python module's FK benchmark in C++ (python/bench/bench_fk.py "fk", docs/python.md "Speed"):
// 10^6 motor-angle pairs uniform in [-pi, pi) (about half unreachable), out of cache as NumPy
// arrays of that size are, so that the two figures compare the same work.
void BM_fk_batch_million(benchmark::State& state) {
  constexpr std::size_t n = 1'000'000;
  const Mechanism m = paper_mechanism("index", "lower");
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-std::numbers::pi, std::numbers::pi);
  std::vector<double> t1(n), t2(n), ox(n), oy(n);
  std::vector<Status> st(n);
  for (std::size_t k = 0; k < n; ++k) {
    t1[k] = u(rng);
    t2[k] = u(rng);
  }
  for (auto _ : state) {
    fivebar::fk_batch(m, t1, t2, ox, oy, st);
    benchmark::DoNotOptimize(ox.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(n));
}
BENCHMARK(BM_fk_batch_million)->Unit(benchmark::kMillisecond);

// --- IK --------------------------------------------------------------------------------------------

void BM_ik_floor_scalar(benchmark::State& state) {
  const Data& d = data();
  std::vector<double> o1(kN), o2(kN);
  for (auto _ : state) {
    for (std::size_t k = 0; k < kN; ++k) {
      const double x = d.px[k], y = d.py[k];
      const double r1 = std::sqrt(x * x + y * y), r2 = std::sqrt(x * y + 400.0);
      o1[k] = std::atan2(r1 - x, y);
      o2[k] = std::atan2(r2 - y, x);
    }
    benchmark::DoNotOptimize(o1.data());
    benchmark::DoNotOptimize(o2.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kN));
}
BENCHMARK(BM_ik_floor_scalar);

void BM_ik_scalar(benchmark::State& state) {
  const Data& d = data();
  const Mechanism m = paper_mechanism("index", "lower");
  std::vector<double> o1(kN), o2(kN);
  for (auto _ : state) {
    for (std::size_t k = 0; k < kN; ++k) {
      const fivebar::AnglesResult r = fivebar::ik_angles(m, {d.px[k], d.py[k]});
      o1[k] = r.theta1;
      o2[k] = r.theta2;
    }
    benchmark::DoNotOptimize(o1.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kN));
}
BENCHMARK(BM_ik_scalar);

void BM_ik_scalar_full_pose(benchmark::State& state) {
  const Data& d = data();
  const Mechanism m = paper_mechanism("index", "lower");
  double acc = 0.0;
  for (auto _ : state) {
    for (std::size_t k = 0; k < kN; ++k) acc += fivebar::ik(m, {d.px[k], d.py[k]}).lci;
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kN));
}
BENCHMARK(BM_ik_scalar_full_pose);

void BM_ik_floor_batch(benchmark::State& state) {
  run_floor(state, data().px, data().py, [](const double* x, const double* y, double* a, double* b, std::int16_t*) {
    ik_floor_loop(x, y, a, b, kN);
  });
}
BENCHMARK(BM_ik_floor_batch);

void BM_ik_floor16_batch(benchmark::State& state) {
  run_floor(state, data().px, data().py, [](const double* x, const double* y, double* a, double* b, std::int16_t* tag) {
    ik_floor16_loop(x, y, a, b, tag, kN);
  });
}
BENCHMARK(BM_ik_floor16_batch);

void BM_ik_floor16_known_length_batch(benchmark::State& state) {
  run_floor(state, data().px, data().py, [](const double* x, const double* y, double* a, double* b, std::int16_t* tag) {
    ik_floor16_known_length_loop(x, y, a, b, tag, kN);
  });
}
BENCHMARK(BM_ik_floor16_known_length_batch);

void BM_ik_batch(benchmark::State& state) {
  const Data& d = data();
  const Mechanism m = paper_mechanism("index", "lower");
  std::vector<double> o1(kN), o2(kN);
  std::vector<Status> st(kN);
  for (auto _ : state) {
    fivebar::ik_batch(m, d.px, d.py, o1, o2, st);
    benchmark::DoNotOptimize(o1.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kN));
}
BENCHMARK(BM_ik_batch);

/// LCI from elbow positions only (square roots, no trigonometry): the workspace/coverage kernel.
void BM_lci_batch(benchmark::State& state) {
  const Data& d = data();
  const Mechanism m = paper_mechanism("index", "lower");
  std::vector<double> l(kN);
  std::vector<Status> st(kN);
  for (auto _ : state) {
    fivebar::lci_batch(m, d.px, d.py, l, st);
    benchmark::DoNotOptimize(l.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(kN));
}
BENCHMARK(BM_lci_batch);

}  // namespace
