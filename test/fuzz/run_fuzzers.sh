#!/usr/bin/env bash
# Runs each libFuzzer target of a FIVEBAR_FUZZ build for a bounded time (README "Hardening").
#
#   test/fuzz/run_fuzzers.sh BUILD_DIR [TARGET...]      (default targets: design_loader cli bench_csv runtime_json)
#
#   FIVEBAR_FUZZ_SECONDS   time per target, default 60
#   FIVEBAR_FUZZ_FLAGS     extra libFuzzer flags (e.g. "-jobs=2 -workers=2" or "-seed=1")
#
# The corpus grows in BUILD_DIR/fuzz-corpus/<target>/ (kept between runs, seeded from designs/,
# test/data/malformed/ and test/data/fuzz-regressions/). A finding stops the script with the path
# of the input libFuzzer saved under BUILD_DIR/fuzz-artifacts/<target>/: fix the bug, then keep the
# input as a regression file in test/data/fuzz-regressions/<target>/.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="$(cd "${1:?usage: run_fuzzers.sh BUILD_DIR [TARGET...]}" && pwd)"
shift
targets=("$@")
((${#targets[@]} > 0)) || targets=(design_loader cli bench_csv runtime_json)
seconds="${FIVEBAR_FUZZ_SECONDS:-60}"
read -r -a extra <<<"${FIVEBAR_FUZZ_FLAGS:-}"

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
# Caches of fontconfig and cairo that live until exit (the sanitizer suite's suppressions).
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$root/test/sanitizer/lsan.supp:print_suppressions=0}"

log() { printf '[fivebar fuzz] %s\n' "$*" >&2; }

for target in "${targets[@]}"; do
  exe="$build/fuzz_$target"
  [[ -x "$exe" ]] || { log "missing $exe (configure with -DFIVEBAR_FUZZ=ON and build it)"; exit 2; }
  corpus="$build/fuzz-corpus/$target"
  artifacts="$build/fuzz-artifacts/$target"
  mkdir -p "$corpus" "$artifacts"
  case "$target" in
    design_loader) seeds=("$root/designs" "$root/test/data/malformed") ;;
    cli) seeds=("$build/test/fuzz/seeds/cli") ;;
    bench_csv) seeds=("$root/test/data/fuzz-seeds/bench_csv") ;;
    runtime_json) seeds=("$root/test/data/fuzz-seeds/runtime_json") ;;
    *) seeds=() ;;
  esac
  seeds+=("$root/test/data/fuzz-regressions/$target")
  flags=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=16384 -print_final_stats=1
         -artifact_prefix="$artifacts/")
  [[ -f "$root/test/fuzz/$target.dict" ]] && flags+=(-dict="$root/test/fuzz/$target.dict")
  log "fuzz_$target for ${seconds} s (corpus $corpus)"
  logfile="$build/fuzz-$target.log"
  status=0
  "$exe" "${flags[@]}" "${extra[@]}" "$corpus" "${seeds[@]}" >"$logfile" 2>&1 || status=$?
  # The summary: libFuzzer's final statistics and its last status line.
  grep -E '^(stat::|Done )|INFO: seed corpus|exec/s' "$logfile" | grep -vE '^#[0-9]+\s+(NEW|REDUCE)' | tail -n 12 >&2 || true
  if ((status != 0)); then
    log "fuzz_$target FOUND A PROBLEM (exit $status); log: $logfile"
    grep -E 'ERROR|SUMMARY|fuzz_(cli|design_loader):|Test unit written|==[0-9]+==' "$logfile" | head -n 40 >&2 || true
    exit 1
  fi
  log "fuzz_$target: no finding"
done
