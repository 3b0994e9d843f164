#!/usr/bin/env bash
# Quick start 2/2: install what is missing, build (Release) and run the whole test suite.
# Packages (.ci/setup.sh): ./run.sh's FIVEBAR_PACKAGES plus the test tools FIVEBAR_TEST_PACKAGES
# (GoogleTest, Google Benchmark, Chromium, jsonschema, urdfdom tools, MuJoCo, PrusaSlicer, pytest);
# --fuzz and --all add FIVEBAR_HARDENING_PACKAGES (clang, its sanitizer runtimes and libFuzzer).
#
#   ./test.sh              the test suite through ctest (build/, Release)
#   ./test.sh --sanitize   the suite again under AddressSanitizer + UndefinedBehaviorSanitizer
#                          (build-sanitize/, Debug at -O1, gcc; the long property tests run fewer
#                          cases there: FIVEBAR_SANITIZE; the whole-scene tests of
#                          test/sanitizer/release-only.txt run in the Release suite only)
#   ./test.sh --core       fivebar::core alone, configured with only its dependencies (Eigen, yaml-cpp,
#                          CGAL, GoogleTest), and its suites and layering test (build-core/)
#   ./test.sh --fuzz       each libFuzzer target for FIVEBAR_FUZZ_SECONDS seconds (default 60)
#                          (build-fuzz/, clang; test/fuzz/run_fuzzers.sh)
#   ./test.sh --all        the four in that order; what `./test.sh` does when CI=true (.ci/run)
#
# Every build directory shares the machine's compiler cache (.ci/setup.sh). Each stage logs its
# wall time ("stage NAME: N s"); test/build_cost.py tabulates them.
#
# Other arguments go to ctest (e.g. ./test.sh -R hostile). Tests labelled `long` (many minutes of
# CPU: the priority rule on 10^4 random pairs per station) are left out: `ctest -L long` runs them.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
source .ci/setup.sh

normal=0 core=0 sanitize=0 fuzz=0
ctest_args=()
for arg in "$@"; do
  case "$arg" in
    --sanitize) sanitize=1 ;;
    --core) core=1 ;;
    --fuzz) fuzz=1 ;;
    --all) normal=1 core=1 sanitize=1 fuzz=1 ;;
    *) ctest_args+=("$arg") ;;
  esac
done
if ((normal + core + sanitize + fuzz == 0)); then
  normal=1
  if [[ "${CI:-}" == "true" ]]; then core=1 sanitize=1 fuzz=1; fi
fi

# The main job's packages and the test tools; the fuzzing toolchain only for --fuzz (and --all).
packages=("${FIVEBAR_PACKAGES[@]}" "${FIVEBAR_TEST_PACKAGES[@]}")
if ((fuzz)); then packages+=("${FIVEBAR_HARDENING_PACKAGES[@]}"); fi
fivebar_stage packages fivebar_install_packages "${packages[@]}"

if ((normal)); then
  fivebar_stage build fivebar_build_in build "Release" -DFIVEBAR_BUILD_TESTS=ON --
  fivebar_log "test suite (build/)"
  # Label `long`: runs of many minutes that a change rarely needs (ctest -L long runs them).
  fivebar_stage test ctest --test-dir build --output-on-failure -j2 -LE long "${ctest_args[@]}"
fi

if ((core)); then
  # The layers hold (docs/architecture.md "Layers"): the core configures with its own dependencies
  # only, builds and passes its suites and the layering test without anything above it.
  fivebar_stage core-build fivebar_build_in build-core "fivebar::core alone" -DFIVEBAR_CORE_ONLY=ON --
  fivebar_log "core suites (build-core/)"
  fivebar_stage core-test ctest --test-dir build-core --output-on-failure -j2 "${ctest_args[@]}"
fi

if ((sanitize)); then
  # Without MPI: OpenMPI's own allocations at MPI_Init read as leaks to LeakSanitizer (the MPI
  # sweep test skips itself there; the normal suite runs it). Without the benchmarks: their smoke run
  # takes several minutes under ASan, and what it checks (each benchmark runs) the normal suite checks.
  fivebar_stage sanitize-build fivebar_build_in build-sanitize "ASan + UBSan, Debug -O1" -DCMAKE_BUILD_TYPE=Debug \
    -DFIVEBAR_SANITIZE=ON -DFIVEBAR_WITH_MPI=OFF -DFIVEBAR_BUILD_BENCH=OFF --
  # Any sanitizer report fails the test that triggered it, also in a child `fivebar` process: the
  # distinctive exit code 86 never matches an expected one. Leaks are reported too.
  export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:check_initialization_order=1:strict_init_order=1:detect_stack_use_after_return=0:exitcode=86}"
  export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1:exitcode=86}"
  # Caches of fontconfig, cairo and OpenMPI that live until exit (test/sanitizer/lsan.supp).
  export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$PWD/test/sanitizer/lsan.supp:print_suppressions=0}"
  # A whole `fivebar run` of the showcase takes about 55 s under ASan on this 2-core machine.
  export FIVEBAR_TEST_CHILD_TIMEOUT_S="${FIVEBAR_TEST_CHILD_TIMEOUT_S:-240}"
  # Whole-scene and whole-pipeline tests run in the Release suite only (test/sanitizer/release-only.txt
  # says which and what each costs here); every other test runs under the sanitizers.
  release_only="$(sed -e 's/#.*//' -e 's/[[:space:]]//g' -e '/^$/d' -e 's/\./\\./g' test/sanitizer/release-only.txt | paste -sd'|')"
  # A name there that no longer exists would leave nothing out silently: each must match one test.
  listed="$(grep -c '^[^#[:space:]]' test/sanitizer/release-only.txt)"
  all_tests="$(ctest --test-dir build-sanitize -N -LE long | sed -n 's/^Total Tests: //p')"
  kept_tests="$(ctest --test-dir build-sanitize -N -LE long -E "^(${release_only})\$" | sed -n 's/^Total Tests: //p')"
  if ((all_tests - kept_tests != listed)); then
    fivebar_log "test/sanitizer/release-only.txt lists $listed tests but $((all_tests - kept_tests)) match: a name there is no test"
    exit 1
  fi
  fivebar_log "test suite under ASan + UBSan (build-sanitize/), without the $listed tests of test/sanitizer/release-only.txt"
  fivebar_stage sanitize-test ctest --test-dir build-sanitize --output-on-failure -j2 --timeout 1500 -LE long -E "^(${release_only})\$" "${ctest_args[@]}"
fi

if ((fuzz)); then
  # The fuzzers alone (clang's libFuzzer), without the suites.
  fivebar_stage fuzz-build fivebar_build_in build-fuzz "libFuzzer, clang, ASan + UBSan" -DCMAKE_BUILD_TYPE=Debug \
    -DFIVEBAR_FUZZ=ON -DFIVEBAR_WITH_MPI=OFF -DFIVEBAR_BUILD_TESTS=OFF -DCMAKE_CXX_COMPILER=clang++ \
    -DCMAKE_C_COMPILER=clang -- fuzz_design_loader fuzz_cli fuzz_bench_csv fuzz_runtime_json
  fivebar_stage fuzz test/fuzz/run_fuzzers.sh build-fuzz
fi
