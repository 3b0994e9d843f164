// identify speed goals (docs/identify.md): a 10 s log at 1 kHz identified (IDIM-LS and the
// output-error refinement) in under 5 s, the IDIM-LS alone in under 50 ms. The log is synthetic
// (test/identify_synthetic.hpp): a motor with a compliance, backlash, quantisation and noise.

#include <benchmark/benchmark.h>

#include "fivebar/identify.hpp"
#include "identify_synthetic.hpp"

namespace {

namespace id = fivebar::identify;

id::JointLog bench_joint(const fivebar::testing::SyntheticLog& s) {
  id::JointLog j;
  j.drive = id::DriveKind::current;
  j.drive_column = "current_A";
  j.drive_values = s.current;
  j.reading_column = "theta_rad";
  j.reading_values = s.theta;
  return j;
}

void BM_identify_idim_ls_10s_1kHz(benchmark::State& state) {
  const auto log = fivebar::testing::synthetic_log(fivebar::testing::SyntheticTruth{}, 1);
  const id::JointLog joint = bench_joint(log);
  id::IdentifyOptions o;
  o.output_error = false;
  for (auto _ : state) {
    auto r = id::identify_joint(joint, log.time, id::JointPrior{}, nullptr, nullptr, o);
    benchmark::DoNotOptimize(r.idim.value);
  }
}
BENCHMARK(BM_identify_idim_ls_10s_1kHz)->Unit(benchmark::kMillisecond);

void BM_identify_with_output_error_10s_1kHz(benchmark::State& state) {
  const auto log = fivebar::testing::synthetic_log(fivebar::testing::SyntheticTruth{}, 1);
  const id::JointLog joint = bench_joint(log);
  id::IdentifyOptions o;
  for (auto _ : state) {
    auto r = id::identify_joint(joint, log.time, id::JointPrior{}, nullptr, nullptr, o);
    benchmark::DoNotOptimize(r.idim.value);
  }
}
BENCHMARK(BM_identify_with_output_error_10s_1kHz)->Unit(benchmark::kMillisecond);

}  // namespace
