# shellcheck shell=bash
# Set-up shared by ./run.sh and ./test.sh (README "Quick start"); source it, then call
# fivebar_setup [TARGET...]. It installs the Debian packages that are missing (apt-get, via sudo
# when not root), configures a Release build in build/ (Ninja when available) and builds.

FIVEBAR_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# What each quick-start command installs (README "Quick start"), in three lists:
#   FIVEBAR_PACKAGES           ./run.sh: the build, the libraries and the programs `fivebar run` calls
#   FIVEBAR_TEST_PACKAGES      ./test.sh adds the test tools (what the suites read results with)
#   FIVEBAR_HARDENING_PACKAGES ./test.sh --fuzz / --all add the fuzzing toolchain (clang, libFuzzer)
# (--sanitize builds with gcc, whose ASan and UBSan runtimes come with build-essential.)
FIVEBAR_PACKAGES=(
  build-essential cmake git pkg-config ccache ninja-build
  libeigen3-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  libvtk9-dev libcairo2-dev
  # The MPI sweep and optimiser (FIVEBAR_WITH_MPI, on by default).
  libopenmpi-dev openmpi-bin
  libsundials-dev
  # Optimisation: pagmo2 (multi-objective evolutionary search) and NLopt (derivative-free polish, tuning).
  libpagmo-dev libnlopt-cxx-dev
  # Kinematic calibration (fivebar calibrate) and identification (fivebar identify): Ceres Solver's
  # nonlinear least squares.
  libceres-dev
  # index.html: GitHub's CommonMark parser with its tables (lib/src/products/html.cpp).
  libcmark-gfm-dev libcmark-gfm-extensions-dev
  # The parts product renders its OpenSCAD sources to STL (fivebar parts, fivebar run).
  openscad
  # The Python module fivebar (python/), built by ./run.sh: pybind11 bindings for the system python3
  # with NumPy.
  pybind11-dev python3-dev python3-numpy
  # fivebar studio's local web server (cli/studio.cpp): cpp-httplib, a header-only HTTP library.
  libcpp-httplib-dev
)
FIVEBAR_TEST_PACKAGES=(
  libgtest-dev libgmock-dev libbenchmark-dev
  # Tests of what users open: urdfdom's check_urdf reads the exported URDF, python3-jsonschema
  # validates every command's --json against docs/schemas/, headless Chromium loads the HTML report.
  liburdfdom-tools python3-jsonschema chromium
  # MuJoCo's library and headers: test_mujoco loads the exported URDF and MJCF and runs them against
  # fivebar simulate.
  libmujoco-dev
  # Gazebo's SDFormat reader (ign sdf -p; the URDF importer of Gazebo): test_urdf checks that it keeps
  # every link and joint of the exported URDF and of the ROS 2 description package.
  libsdformat-dev ignition-tools
  # catkin_pkg, the reader of ROS package manifests: test_urdf parses the ROS 2 package's package.xml.
  python3-catkin-pkg
  # PyYAML, a YAML 1.1 reader as ROS 2's parameter parser is: test_export reads the parameters file with it.
  python3-yaml
  # The Python module's tests (pytest, run by ctest).
  python3-pytest
  # Tests of what users open: PrusaSlicer slices the parts (with unzip to read its .sl1 archive).
  prusa-slicer unzip
  # The runtime for a Raspberry Pi (ctest runtime_aarch64, test/runtime_package/aarch64.sh): Debian's
  # aarch64 cross compiler builds the runtime package alone, qemu-user runs its C test and compares
  # its duties with the x86-64 build's bit for bit, and cpack makes its arm64 .deb packages (checked
  # with dpkg-deb and file).
  g++-aarch64-linux-gnu
  qemu-user
  # The studio's browser test (test/studio_browser.py) drives Chromium over the DevTools protocol.
  python3-websocket
  # `pip install .` into a fresh venv (ctest python_pip_install): venv, pip and the setuptools build.
  python3-venv python3-pip python3-setuptools python3-wheel
)
FIVEBAR_HARDENING_PACKAGES=(
  # Hardening (./test.sh --fuzz): clang with libFuzzer and the sanitizer runtimes, clang's OpenMP.
  clang libclang-rt-14-dev libomp-dev
)

fivebar_log() { printf '[fivebar] %s\n' "$*" >&2; }

# The compiler cache (ccache, found by CMakeLists.txt) is shared by every build directory and every
# checkout of this machine: paths under the checkout are hashed relative to it (base_dir) and the
# working directory is left out of the hash (hash_dir), so that a second clone, CI's fresh clone
# included, reuses what an earlier build compiled. Settings the caller made are kept.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$FIVEBAR_ROOT}"
export CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-1}"
# Four configurations of the whole tree (Release, core, ASan + libFuzzer, Debug objects carry debug
# information) hold about 6 GB: ccache's default of 5 GB would evict the first by the last.
export CCACHE_MAXSIZE="${CCACHE_MAXSIZE:-20G}"

# fivebar_stage NAME COMMAND...: runs a command and logs its wall time, for the table of CI stage
# times (test/build_cost.py reads these lines from a saved log; docs/architecture.md "Build cost").
fivebar_stage() {
  local name="$1" start end status=0
  shift
  start=$(date +%s)
  "$@" || status=$?
  end=$(date +%s)
  fivebar_log "stage ${name}: $((end - start)) s (exit ${status})"
  return "$status"
}

# fivebar_install_packages [PACKAGE...]: installs those of the packages (default: FIVEBAR_PACKAGES)
# that dpkg does not report as installed.
fivebar_install_packages() {
  if ! command -v dpkg-query >/dev/null 2>&1; then
    fivebar_log "dpkg-query not found: not a Debian system, skipping package installation"
    return 0
  fi
  local wanted=("$@")
  ((${#wanted[@]} > 0)) || wanted=("${FIVEBAR_PACKAGES[@]}")
  local missing=() pkg
  for pkg in "${wanted[@]}"; do
    if [[ "$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null || true)" != "install ok installed" ]]; then
      missing+=("$pkg")
    fi
  done
  if ((${#missing[@]} == 0)); then
    fivebar_log "all ${#wanted[@]} Debian packages present"
    return 0
  fi
  local as_root=()
  if [[ "$(id -u)" -ne 0 ]]; then
    if ! command -v sudo >/dev/null 2>&1; then
      fivebar_log "missing packages: ${missing[*]}"
      fivebar_log "run as root or install sudo, then try again"
      return 1
    fi
    as_root=(sudo)
  fi
  fivebar_log "installing: ${missing[*]}"
  "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update
  "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}"
}

# Configures build/ (Release) once and builds the given targets (default: everything). A new build/
# is configured without the test suites (./run.sh installs no GoogleTest); ./test.sh turns them on.
fivebar_build() {
  local tests=()
  [[ -f "$FIVEBAR_ROOT/build/CMakeCache.txt" ]] || tests=(-DFIVEBAR_BUILD_TESTS=OFF)
  fivebar_build_in build "Release" "${tests[@]}" -- "$@"
}

# fivebar_build_in DIR DESCRIPTION [CMAKE_ARG...] -- [TARGET...]: configures $FIVEBAR_ROOT/DIR with
# the given cmake arguments (Release unless they say otherwise) and builds the targets.
fivebar_build_in() {
  local dir="$FIVEBAR_ROOT/$1" description="$2"
  shift 2
  local cmake_args=(-DCMAKE_BUILD_TYPE=Release)
  while (($# > 0)) && [[ "$1" != "--" ]]; do
    cmake_args+=("$1")
    shift
  done
  (($# > 0)) && shift
  local generator=()
  # The generator of an existing build directory is kept; a fresh one uses Ninja when installed.
  if [[ ! -f "$dir/CMakeCache.txt" ]] && command -v ninja >/dev/null 2>&1; then
    generator=(-G Ninja)
  fi
  fivebar_log "configuring ${dir#"$FIVEBAR_ROOT"/}/ ($description)"
  # `|| return`: set -e does not hold inside a function called from `... || status=$?` (fivebar_stage).
  cmake -S "$FIVEBAR_ROOT" -B "$dir" "${cmake_args[@]}" "${generator[@]}" || return
  local targets=()
  local t
  for t in "$@"; do
    # The Python module is a target only where pybind11 and NumPy were found (FIVEBAR_PYTHON).
    if [[ "$t" == "fivebar_python" ]] && ! grep -q '^FIVEBAR_PYTHON:BOOL=ON' "$dir/CMakeCache.txt"; then
      fivebar_log "the Python module is not configured (FIVEBAR_PYTHON off): skipped"
      continue
    fi
    targets+=(--target "$t")
  done
  fivebar_log "building with $(nproc) jobs"
  cmake --build "$dir" -j"$(nproc)" "${targets[@]}" || return
}

# Packages, configure, build.
fivebar_setup() {
  fivebar_install_packages
  fivebar_build "$@"
}
