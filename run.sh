#!/usr/bin/env bash
# Quick start 1/2: install what is missing, build (Release) and run the paper's scene,
#   fivebar run designs/iros2022.yaml [ARGS...]   -> outputs/iros2022/summary.md
# It builds only what that job runs (the `fivebar` binary and the library under it; ./test.sh builds
# the rest: the suites, the benchmarks and the Python module). It installs the main job's Debian
# packages only (FIVEBAR_PACKAGES in .ci/setup.sh): no test tools.
# Extra arguments go to `fivebar run` (e.g. ./run.sh --out /tmp/x --products kinematics).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
source .ci/setup.sh
fivebar_setup fivebar_cli
exec build/fivebar run designs/iros2022.yaml "$@"
