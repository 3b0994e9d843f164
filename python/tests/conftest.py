"""Shared fixtures of the Python module's tests (run by ctest as `python_bindings`, with PYTHONPATH
at build/python and FIVEBAR_CLI the built `fivebar`; see python/CMakeLists.txt)."""
import json
import os
import pathlib
import subprocess

import pytest

import fivebar

ROOT = pathlib.Path(os.environ.get("FIVEBAR_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
SHOWCASE = ROOT / "designs" / "iros2022.yaml"


def cli_path():
    path = os.environ.get("FIVEBAR_CLI", str(ROOT / "build" / "fivebar"))
    if not pathlib.Path(path).exists():
        pytest.skip(f"the fivebar CLI is not built ({path}): the comparisons with its JSON need it")
    return path


def run_cli(*args, check=True):
    """Runs the CLI; returns its --json document (stdout parsed)."""
    proc = subprocess.run([cli_path(), *map(str, args)], capture_output=True, text=True, timeout=300)
    if check and proc.returncode not in (0, 1):
        raise AssertionError(f"fivebar {' '.join(map(str, args))} exited {proc.returncode}: {proc.stderr}")
    return json.loads(proc.stdout)


@pytest.fixture(scope="session")
def showcase():
    return fivebar.load(SHOWCASE)


@pytest.fixture(scope="session")
def index_lower(showcase):
    return showcase.station("index").lower
