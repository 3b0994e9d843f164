#!/usr/bin/env python3
"""Benchmarks of the Python module (docs/python.md "Speed"), figures quoted in the docs:

  fk      FK of 10^6 random angle pairs on NumPy arrays (into preallocated out= arrays and into
          new ones), to compare with the C++ batch benchmark BM_fk_batch_million
          (build/fivebar_bench --benchmark_filter=BM_fk_batch_million);
  sweep   a grid sweep of 201 x 201 = 40,401 designs of the showcase's sweep: section, in process,
          against `fivebar sweep --no-plots` on the same file;
  loop    an external optimiser's loop (one design at a time, as scipy / pymoo drive it) on
          Problem.fitness in process, against one CLI call per design on the same designs (the
          edited design written out, `fivebar coverage DESIGN --station index --json`, its JSON
          read), and against the CLI's start-up alone (`fivebar --version`).

    PYTHONPATH=build/python /usr/bin/python3 python/bench/bench_fk.py [fk|sweep|loop ...]
"""
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

import fivebar

ROOT = pathlib.Path(__file__).resolve().parents[2]
SHOWCASE = ROOT / "designs" / "iros2022.yaml"
CLI = os.environ.get("FIVEBAR_CLI", str(ROOT / "build" / "fivebar"))


def best_of(fn, repeat):
    """Smallest wall time and smallest CPU time of the calling thread (the kernel runs on it, the
    GIL released), in seconds; Google Benchmark's items_per_second is per CPU second likewise."""
    wall, cpu = [], []
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.thread_time()
        fn()
        cpu.append(time.thread_time() - c0)
        wall.append(time.perf_counter() - w0)
    return min(wall), min(cpu)


def bench_fk():
    n = 1_000_000
    rng = np.random.default_rng(1)
    t1, t2 = rng.uniform(-np.pi, np.pi, n), rng.uniform(-np.pi, np.pi, n)
    m = fivebar.load(SHOWCASE).station("index").lower
    x, y, st = np.empty(n), np.empty(n), np.empty(n, np.uint8)
    fivebar.fk(m, t1, t2, out=(x, y, st))  # warm up (pages of the outputs touched)
    w_out, c_out = best_of(lambda: m.fk_batch(t1, t2, out=(x, y, st)), 30)
    w_new, c_new = best_of(lambda: m.fk_batch(t1, t2), 30)
    print(f"fk: 1e6 pairs into out= arrays {w_out * 1e3:.2f} ms wall, {c_out * 1e3:.2f} ms CPU "
          f"({n / c_out / 1e6:.1f} M/s per CPU second); into new arrays {w_new * 1e3:.2f} ms wall, "
          f"{c_new * 1e3:.2f} ms CPU ({n / c_new / 1e6:.1f} M/s); ok {np.mean(st == 0):.3f}")


def sweep_design(tmp):
    text = SHOWCASE.read_text()
    for old, new in (("L34: [12, 19, 29]", "L34: [12, 19, 201]"), ("L12: [6, 12, 25]", "L12: [6, 12, 201]")):
        assert old in text, old
        text = text.replace(old, new, 1)
    path = pathlib.Path(tmp) / "sweep-40401.yaml"
    path.write_text(text)
    return path


def bench_sweep():
    with tempfile.TemporaryDirectory() as tmp:
        path = sweep_design(tmp)
        design = fivebar.load(path)
        t0 = time.perf_counter()
        cols = fivebar.sweep(design)
        t_py = time.perf_counter() - t0
        t0 = time.perf_counter()
        subprocess.run([CLI, "sweep", str(path), "--out", str(pathlib.Path(tmp) / "out"), "--no-plots", "--yes"],
                       check=True, capture_output=True)
        t_cli = time.perf_counter() - t0
    n = len(cols["index"])
    print(f"sweep: {n} designs from Python {t_py:.2f} s ({n / t_py:.0f}/s), CLI {t_cli:.2f} s ({n / t_cli:.0f}/s); "
          f"covered {int(cols['covered'].sum())}")


def bench_loop():
    design = fivebar.load(SHOWCASE)
    problem = fivebar.Problem(design)
    rng = np.random.default_rng(5)
    lo, hi = np.array(problem.lower), np.array(problem.upper)
    n_py, n_cli = 400, 10
    X = rng.uniform(lo, hi, size=(n_py, len(lo)))
    t0 = time.perf_counter()
    best = None
    for x in X:  # one design at a time, as an external optimiser (scipy, pymoo) asks
        f = problem.fitness(x)
        best = f if best is None or f < best else best
    t_py = (time.perf_counter() - t0) / n_py
    verdicts = [problem.evaluate(x)["verdict"] for x in X[:n_cli]]
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        for k, x in enumerate(X[:n_cli]):  # the same designs, the CLI way: a file, a process, its JSON
            try:
                edited = problem.design_at(x)
            except fivebar.InputError:
                edited = design
            path = pathlib.Path(tmp) / f"d{k}.yaml"
            path.write_text(edited.to_yaml())
            subprocess.run([CLI, "coverage", str(path), "--station", "index", "--json"], capture_output=True)
        t_cli = (time.perf_counter() - t0) / n_cli
        t0 = time.perf_counter()
        for _ in range(n_cli):  # the floor: the process doing nothing but start and print its version
            subprocess.run([CLI, "--version"], capture_output=True)
        t_floor = (time.perf_counter() - t0) / n_cli
    print(f"loop: in process {t_py * 1e3:.2f} ms per design ({len(lo)} variables, staged evaluation, "
          f"{n_py} random designs); CLI `coverage --json` per design {t_cli * 1e3:.1f} ms "
          f"(verdicts of its first {n_cli}: {', '.join(sorted(set(verdicts)))}); ratio {t_cli / t_py:.0f}x; "
          f"CLI start-up alone {t_floor * 1e3:.1f} ms, ratio {t_floor / t_py:.0f}x")


if __name__ == "__main__":
    which = sys.argv[1:] or ["fk", "sweep", "loop"]
    for name in which:
        {"fk": bench_fk, "sweep": bench_sweep, "loop": bench_loop}[name]()
