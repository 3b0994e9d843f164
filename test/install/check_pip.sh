#!/usr/bin/env bash
# `pip install .` as a user runs it (docs/install.md "Python"): usage
#   check_pip.sh BUILD_DIR SOURCE_DIR SCRATCH_DIR VERSION PYTHON
# makes a fresh venv of PYTHON (the interpreter the module is built for, Debian's /usr/bin/python3)
# with --system-site-packages (Debian's NumPy, setuptools and wheel), installs the
# source tree with no index and no build isolation (offline), building in BUILD_DIR
# (FIVEBAR_CMAKE_BUILD_DIR, setup.py), and checks from an unrelated directory that
# `import fivebar` loads the venv's copy, `fivebar.__version__` is VERSION, and that the OpenSCAD
# library shipped beside the extension is where the library looks for it.
set -euo pipefail
build=$(cd "$1" && pwd) src=$(cd "$2" && pwd) scratch=$3 version=$4 python=${5:-/usr/bin/python3}
rm -rf "$scratch"
mkdir -p "$scratch"
scratch=$(cd "$scratch" && pwd)
"$python" -m venv --system-site-packages "$scratch/venv"
FIVEBAR_CMAKE_BUILD_DIR="$build" "$scratch/venv/bin/python" -m pip install --no-build-isolation --no-index -q "$src" \
  > "$scratch/pip.log" 2>&1 || { tail -40 "$scratch/pip.log" >&2; echo "check_pip: FAIL: pip install" >&2; exit 1; }
cd "$scratch"
env -u PYTHONPATH "$scratch/venv/bin/python" - "$scratch/venv" "$version" <<'PY'
import pathlib, sys
import fivebar
venv, version = pathlib.Path(sys.argv[1]).resolve(), sys.argv[2]
where = pathlib.Path(fivebar.__file__).resolve()
assert venv in where.parents, f"fivebar imported from {where}, not from the venv {venv}"
assert fivebar.__version__ == version == fivebar.version(), (fivebar.__version__, version)
scad = where.parent / "share" / "fivebar" / "scad" / "fivebar.scad"
assert scad.is_file(), f"{scad} is missing from the wheel"
print(f"check_pip: fivebar {fivebar.__version__} from {where}")
PY
echo "check_pip: all checks passed"
