#!/usr/bin/env bash
# Quick start 2/2: install what is missing, build (Release) and run the whole test suite.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
source .ci/setup.sh
fivebar_setup
exec ctest --test-dir build --output-on-failure -j2
