// fivebar::runtime's cycle time (issue: worst case <= 20 us for all four mechanisms of the
// showcase, collision check included). One benchmark iteration runs N cycles of the showcase's
// patterns (every station, every pattern of `patterns:` at the loop rate, joints read as 16-bit ADC
// codes of the commanded angles plus a deterministic ripple of a few counts) and times each cycle
// with steady_clock (counters p50_us, p99_us, max_us) and with this thread's CPU clock
// (cpu_p50_us, cpu_p99_us, cpu_max_us: the cycle's own work, free of preemption on a shared machine). A second benchmark times the priority rule's
// bounded search alone (both tactors of a station at its centre: the lower one is moved); a third
// runs the showcase's cycles with the priority rule forced in both stations at every cycle.

#include <benchmark/benchmark.h>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "fivebar/collision.hpp"
#include "fivebar/design.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/pattern.hpp"
#include "fivebar/runtime.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/patterns.hpp"

namespace {

using namespace fivebar;
namespace rt = fivebar::runtime;

struct Samples {
  rt::Config config;
  std::vector<std::vector<double>> counts, targets;
};

const Samples& showcase() {
  static const Samples s = [] {
    Samples out;
    const Design d = load_design(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
    out.config = rt::parse_config_json(render_json(controller_parameters(d, {})), "iros2022");
    const ControllerSettings& ctl = *d.get<ControllerSettings>();
    // Per station its patterns' samples; stations run side by side (the shorter one repeats).
    std::vector<std::vector<std::pair<Vec2, Vec2>>> per_station;  // {lower, upper} commanded points
    for (const rt::StationConfig& st : out.config.stations) {
      const Station& station = d.require_station(st.name);
      std::vector<std::pair<Vec2, Vec2>> pts;
      for (PatternSpec spec : d.get<PatternSettings>()->for_station(st.name)) {
        spec.rate_hz = ctl.loop_rate_hz;
        const PatternResult pr = check_pattern(station, *d.get<Geometry>(), spec, ctl.max_velocity);
        for (const PatternSample& p : pr.samples) pts.push_back({p.lower.target, p.upper.target});
      }
      per_station.push_back(pts);
    }
    std::size_t n = 0;
    for (const auto& p : per_station) n = std::max(n, p.size());
    for (std::size_t i = 0; i < n; ++i) {
      std::vector<double> counts, targets;
      for (std::size_t s = 0; s < out.config.stations.size(); ++s) {
        const auto& [low, up] = per_station[s][i % per_station[s].size()];
        const Station& station = d.require_station(out.config.stations[s].name);
        for (const rt::MechanismConfig& m : out.config.stations[s].mechanisms) {
          const Vec2 p = m.name == "lower" ? low : up;
          const Pose pose = ik(m.name == "lower" ? *station.lower : *station.upper, p);
          for (std::size_t j = 0; j < 2; ++j) {
            const rt::JointConfig& jc = m.joints[j];
            const double theta = (j == 0 ? pose.theta1 : pose.theta2) + 2e-3 * std::sin(0.1 * double(i) + double(j));
            counts.push_back(rt::adc_code(jc.volts_at_zero + theta / jc.rad_per_volt, out.config.adc_bits,
                                          out.config.adc_range_v, out.config.volts_per_count));
          }
          targets.push_back(p.x() / 1000.0);
          targets.push_back(p.y() / 1000.0);
        }
      }
      out.counts.push_back(counts);
      out.targets.push_back(targets);
    }
    return out;
  }();
  return s;
}

/// This thread's CPU time, us: a cycle's own work, without the time the scheduler gives other
/// processes (a loaded machine preempts a wall-clock measurement for milliseconds).
double thread_cpu_us() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e6 + double(t.tv_nsec) * 1e-3;
}

void report(benchmark::State& state, std::vector<double>& us, std::vector<double>& cpu) {
  for (auto* v : {&us, &cpu}) std::sort(v->begin(), v->end());
  // How many cycles exceed the goal's 20 us (outliers of a shared or virtual machine show here).
  state.counters["over_20us"] = double(us.end() - std::upper_bound(us.begin(), us.end(), 20.0));
  state.counters["p99_99_us"] = us[std::min(us.size() - 1, static_cast<std::size_t>(0.9999 * double(us.size())))];
  const auto at = [](const std::vector<double>& v, double q) {
    return v[std::min(v.size() - 1, static_cast<std::size_t>(q * double(v.size())))];
  };
  state.counters["p50_us"] = at(us, 0.5);
  state.counters["p99_us"] = at(us, 0.99);
  state.counters["max_us"] = us.back();
  state.counters["cpu_p50_us"] = at(cpu, 0.5);
  state.counters["cpu_p99_us"] = at(cpu, 0.99);
  state.counters["cpu_max_us"] = cpu.back();
}

void BM_runtime_showcase_cycles(benchmark::State& state) {
  const Samples& s = showcase();
  const auto n = static_cast<std::size_t>(state.range(0));
  std::vector<double> us(n), cpu(n);
  // Per distinct input (each recurs n / 504 times) its fastest cycle: the input's own cost; the
  // largest of those is the worst input's cost without the machine's interruptions.
  std::vector<double> fastest(s.counts.size(), 1e300);
  std::size_t moved = 0;
  for (auto _ : state) {
    rt::Controller ctl(s.config);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = i % s.counts.size();
      const double c0 = thread_cpu_us();
      const auto t0 = std::chrono::steady_clock::now();
      ctl.cycle(s.counts[k].data(), rt::Reading::counts, s.targets[k].data());
      const auto t1 = std::chrono::steady_clock::now();
      cpu[i] = thread_cpu_us() - c0;
      benchmark::DoNotOptimize(ctl.duties());
      us[i] = std::chrono::duration<double, std::micro>(t1 - t0).count();
      fastest[k] = std::min(fastest[k], us[i]);
      for (std::size_t m = 0; m < ctl.mechanism_count(); ++m) moved += ctl.mechanism(m).status == rt::Status::moved_by_priority;
    }
  }
  report(state, us, cpu);
  state.counters["worst_input_us"] = *std::max_element(fastest.begin(), fastest.end());
  state.counters["mechanisms"] = double(s.config.mechanism_count());
  state.counters["distinct_samples"] = double(s.counts.size());
  state.counters["moved_by_priority"] = double(moved);
}
BENCHMARK(BM_runtime_showcase_cycles)->Arg(1'000'000)->Arg(10'000)->Iterations(1)->Unit(benchmark::kMillisecond);

void BM_runtime_priority_search(benchmark::State& state) {
  const Samples& s = showcase();
  const Design d = load_design(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  std::vector<double> counts = s.counts.front(), targets = s.targets.front();
  std::size_t k = 0;
  for (const rt::StationConfig& st : s.config.stations) {
    const Vec2 c = d.require_station(st.name).target.center;
    for (std::size_t m = 0; m < st.mechanisms.size(); ++m, ++k) targets[2 * k] = c.x() / 1000, targets[2 * k + 1] = c.y() / 1000;
  }
  const auto n = static_cast<std::size_t>(state.range(0));
  std::vector<double> us(n), cpu(n);
  std::size_t moved = 0;
  for (auto _ : state) {
    rt::Controller ctl(s.config);
    for (std::size_t i = 0; i < n; ++i) {
      const double c0 = thread_cpu_us();
      const auto t0 = std::chrono::steady_clock::now();
      ctl.cycle(counts.data(), rt::Reading::counts, targets.data());
      const auto t1 = std::chrono::steady_clock::now();
      cpu[i] = thread_cpu_us() - c0;
      us[i] = std::chrono::duration<double, std::micro>(t1 - t0).count();
      for (std::size_t m = 0; m < ctl.mechanism_count(); ++m) moved += ctl.mechanism(m).status == rt::Status::moved_by_priority;
    }
  }
  report(state, us, cpu);
  state.counters["moved_by_priority"] = double(moved);
  state.counters["probe_bound"] = double(rt::kPriorityMaxProbes);
}
BENCHMARK(BM_runtime_priority_search)->Arg(2000)->Iterations(1)->Unit(benchmark::kMillisecond);

/// The showcase's cycles with the priority rule forced every cycle: each station's lower target is
/// its upper target of the same sample plus an offset turning once per 97 samples (radius 0 to
/// 3 mm over 89 samples), so both stations' lower tactors collide with the upper outlines at
/// every cycle and every depth: four mechanisms, two priority rules per cycle.
void BM_runtime_showcase_priority_every_cycle(benchmark::State& state) {
  const Samples& s = showcase();
  std::vector<std::vector<double>> targets = s.targets;
  for (std::size_t i = 0; i < targets.size(); ++i) {
    std::size_t k = 0;
    for (const rt::StationConfig& st : s.config.stations) {
      std::size_t lo = k, up = k;
      for (std::size_t m = 0; m < st.mechanisms.size(); ++m) (st.mechanisms[m].name == "lower" ? lo : up) = k + m;
      const double phi = 2 * M_PI * double(i % 97) / 97.0, r = 3e-3 * double(i % 89) / 88.0;
      targets[i][2 * lo] = targets[i][2 * up] + r * std::cos(phi);
      targets[i][2 * lo + 1] = targets[i][2 * up + 1] + r * std::sin(phi);
      k += st.mechanisms.size();
    }
  }
  const auto n = static_cast<std::size_t>(state.range(0));
  std::vector<double> us(n), cpu(n);
  std::vector<double> fastest(targets.size(), 1e300);
  std::size_t moved = 0, stopped = 0;
  for (auto _ : state) {
    rt::Controller ctl(s.config);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = i % targets.size();
      const double c0 = thread_cpu_us();
      const auto t0 = std::chrono::steady_clock::now();
      ctl.cycle(s.counts[k].data(), rt::Reading::counts, targets[k].data());
      const auto t1 = std::chrono::steady_clock::now();
      cpu[i] = thread_cpu_us() - c0;
      benchmark::DoNotOptimize(ctl.duties());
      us[i] = std::chrono::duration<double, std::micro>(t1 - t0).count();
      fastest[k] = std::min(fastest[k], us[i]);
      for (std::size_t m = 0; m < ctl.mechanism_count(); ++m) {
        moved += ctl.mechanism(m).status == rt::Status::moved_by_priority;
        stopped += !ctl.mechanism(m).command;
      }
    }
  }
  report(state, us, cpu);
  state.counters["worst_input_us"] = *std::max_element(fastest.begin(), fastest.end());
  state.counters["moved_per_cycle"] = double(moved) / double(n);
  state.counters["stopped"] = double(stopped);
  state.counters["probe_bound"] = double(rt::kPriorityMaxProbes);
}
BENCHMARK(BM_runtime_showcase_priority_every_cycle)->Arg(1'000'000)->Arg(10'000)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace

namespace {

/// Random crossings (issue 46): per cycle, in both stations, an upper target uniform over the
/// station's target box (centre +- its half axes) and a lower target uniform within 8 mm of it in x
/// and y, kept only when their outlines collide by the library's exact check (both usable): every
/// cycle runs two priority rules on a new input. state.range(0) cycles; the joints' codes are the
/// first showcase sample's (the rule works on the commanded poses). Counters: the distribution of
/// the cycle's wall time and this thread's CPU time (max_us / cpu_max_us: p100), the cycles whose
/// rule stopped a lower tactor, and the probe bounds.
void BM_runtime_random_crossings(benchmark::State& state) {
  const Samples& s = showcase();
  const Design d = load_design(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  const Geometry& g = *d.get<Geometry>();
  const auto n = static_cast<std::size_t>(state.range(0));
  std::mt19937_64 rng(46);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<std::vector<double>> targets(n, s.targets.front());
  std::size_t k0 = 0;
  for (const rt::StationConfig& st : s.config.stations) {
    std::size_t lo = k0, up = k0;
    for (std::size_t m = 0; m < st.mechanisms.size(); ++m) (st.mechanisms[m].name == "lower" ? lo : up) = k0 + m;
    k0 += st.mechanisms.size();
    if (st.mechanisms.size() != 2) continue;
    const Station& station = d.require_station(st.name);
    for (std::size_t i = 0; i < n; ++i) {
      for (;;) {
        const Vec2 pu = station.target.center + Vec2(station.target.axes.x() * u(rng), station.target.axes.y() * u(rng));
        const Vec2 pl = pu + 8.0 * Vec2(u(rng), u(rng));
        const Pose a = ik(*station.upper, pu), b = ik(*station.lower, pl);
        if (!usable(*station.upper, a) || !usable(*station.lower, b)) continue;
        if (!interference(*station.upper, a, *station.lower, b, g).collides) continue;
        targets[i][2 * up] = pu.x() / 1000, targets[i][2 * up + 1] = pu.y() / 1000;
        targets[i][2 * lo] = pl.x() / 1000, targets[i][2 * lo + 1] = pl.y() / 1000;
        break;
      }
    }
  }
  std::vector<double> us(n), cpu(n);
  std::size_t moved = 0, stopped = 0;
  for (auto _ : state) {
    rt::Controller ctl(s.config);
    for (std::size_t i = 0; i < n; ++i) {
      const double c0 = thread_cpu_us();
      const auto t0 = std::chrono::steady_clock::now();
      ctl.cycle(s.counts.front().data(), rt::Reading::counts, targets[i].data());
      const auto t1 = std::chrono::steady_clock::now();
      cpu[i] = thread_cpu_us() - c0;
      benchmark::DoNotOptimize(ctl.duties());
      us[i] = std::chrono::duration<double, std::micro>(t1 - t0).count();
      for (std::size_t m = 0; m < ctl.mechanism_count(); ++m) {
        moved += ctl.mechanism(m).status == rt::Status::moved_by_priority;
        stopped += ctl.mechanism(m).status == rt::Status::unreachable;
      }
    }
  }
  report(state, us, cpu);
  std::vector<double> sorted = cpu;
  std::sort(sorted.begin(), sorted.end());
  state.counters["cpu_p99_9_us"] = sorted[std::min(n - 1, static_cast<std::size_t>(0.999 * double(n)))];
  state.counters["moved"] = double(moved);
  state.counters["stopped"] = double(stopped);
  state.counters["probe_bound"] = double(rt::kPriorityMaxProbes + 32 * rt::kPriorityRays);  // + kPriorityRings rings
}
BENCHMARK(BM_runtime_random_crossings)->Arg(100'000)->Arg(2'000)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
