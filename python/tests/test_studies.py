"""The studies from Python against the CLI's JSON and files for the showcase (coverage, workspace,
sweep, tolerance, export gate), their arrays checked against independent evaluations, progress
callbacks and Ctrl-C (KeyboardInterrupt, no thread left behind)."""
import _thread
import csv
import math
import threading

import numpy as np
import pytest

import fivebar
from conftest import SHOWCASE, run_cli


def close(a, b, tol=1e-9):
    return a == pytest.approx(b, rel=tol, abs=tol)


def test_coverage_equals_cli_json(showcase):
    doc = run_cli("coverage", SHOWCASE, "--json")
    for station_doc in doc["stations"]:
        c = fivebar.coverage(showcase, station_doc["station"])
        assert c.to_dict() == station_doc  # the CLI's station record, key for key
        expected = all(m["covered"] for m in station_doc["mechanisms"]) and (
            station_doc["shared"] is None or station_doc["shared"]["covered"])
        assert c.covered == expected
        for record in station_doc["mechanisms"]:
            r = getattr(c, record["mechanism"])
            assert r.covered == record["covered"]
            assert close(r.margin_mm, record["margin_mm"])
            assert close(r.min_lci, record["min_lci"])
            assert close(r.covered_fraction, record["covered_fraction"])
            assert r.worst_point == pytest.approx(tuple(record["worst_point_mm"]), abs=1e-9)
        if station_doc["shared"] is not None:
            assert close(c.shared.margin_mm, station_doc["shared"]["margin_mm"])


def test_coverage_of_a_mechanism_and_a_target(index_lower):
    inside = fivebar.coverage(index_lower, target=fivebar.Ellipse((6.25, 15.5), (4.0, 3.0)))
    assert inside.covered and inside.margin_mm > 0
    outside = fivebar.coverage(index_lower, target=fivebar.Ellipse((6.25, 40.0), (4.0, 3.0)))
    assert not outside.covered and outside.margin_mm < 0 and outside.reason


def test_workspace_equals_cli_json_and_its_fields_are_views(showcase, tmp_path):
    doc = run_cli("workspace", SHOWCASE, "--station", "index", "--spacing", "0.5", "--out", tmp_path, "--json")
    ws = fivebar.workspace(showcase, "index", spacing_mm=0.5)
    cli = doc["stations"][0] if "stations" in doc else doc
    mechs = cli["mechanisms"]
    for name, mw in ws.mechanisms.items():
        rec = mechs[name] if isinstance(mechs, dict) else next(m for m in mechs if m["mechanism"] == name)
        assert close(mw.area_mm2, rec["area_mm2"])
        assert close(mw.lci_area_mm2, rec["lci_area_mm2"])
        # The boundary polylines enclose the exact area (shoelace, holes negative): 1 degree arcs.
        shoelace = sum(0.5 * np.sum(b[:, 0] * np.roll(b[:, 1], -1) - np.roll(b[:, 0], -1) * b[:, 1])
                       for b in mw.boundary)
        assert shoelace == pytest.approx(mw.area_mm2, rel=2e-3)
        # Fields: read-only views of the result (no copy), on the grid.
        lci = mw.fields["lci"]
        assert lci.shape == (ws.grid["ny"], ws.grid["nx"])
        assert not lci.flags.writeable and not lci.flags.owndata
        # Independent: the LCI kernel at the reachable grid points.
        X, Y = np.meshgrid(ws.grid["x"], ws.grid["y"])
        reach = mw.fields["reach"].astype(bool)
        value, status = fivebar.lci(mw.mechanism, X[reach], Y[reach])
        assert (status == int(fivebar.Status.ok)).mean() > 0.99
        ok = status == int(fivebar.Status.ok)
        assert np.abs(value[ok] - lci[reach][ok]).max() < 1e-9
    assert ws.shared is not None and close(ws.shared.area_mm2, cli["shared"]["area_mm2"])


def small_sweep(tmp_path):
    text = SHOWCASE.read_text()
    for old, new in (("L34: [12, 19, 29]", "L34: [12, 19, 4]"), ("L12: [6, 12, 25]", "L12: [6, 12, 5]")):
        assert old in text
        text = text.replace(old, new, 1)
    path = tmp_path / "small-sweep.yaml"
    path.write_text(text)
    return path


def test_sweep_columns_equal_the_cli_csv(tmp_path):
    path = small_sweep(tmp_path)
    out = tmp_path / "sweep"
    run_cli("sweep", path, "--out", out, "--no-plots", "--json")
    with open(out / "sweep.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    calls = []
    columns = fivebar.sweep(fivebar.load(path), chunk=7, progress=lambda done, total, s: calls.append((done, total)))
    assert len(rows) == 20 and len(columns["index"]) == 20
    # Ready for pandas.DataFrame(columns): one-dimensional arrays of one length, named as the CSV.
    assert all(isinstance(c, np.ndarray) and c.shape == (20,) for c in columns.values())
    assert list(columns)[: len(rows[0])] == list(rows[0].keys())
    assert calls[-1] == (20, 20) and len(calls) == 3
    names = [n for n in rows[0].keys()]
    for name in names:
        col = columns[name]
        for k, row in enumerate(rows):
            if name == "status":
                assert col[k] == row[name]
            elif name == "covered":
                assert bool(col[k]) == (row[name] == "1")
            elif row[name] == "":
                assert math.isnan(col[k]), (name, k)
            else:
                assert col[k] == pytest.approx(float(row[name]), rel=1e-12, abs=1e-15), (name, k)
    with open(out / "pareto.csv", newline="") as f:
        front = {int(r["index"]) for r in csv.DictReader(f)}
    assert set(columns["index"][columns["pareto"]]) == front


def test_a_progress_callback_that_raises_stops_the_sweep(tmp_path):
    design = fivebar.load(small_sweep(tmp_path))
    threads = threading.active_count()

    def stop(done, total, seconds):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        fivebar.sweep(design, chunk=2, progress=stop)
    with pytest.raises(ZeroDivisionError):
        fivebar.sweep(design, chunk=2, progress=lambda *a: 1 / 0)
    assert threading.active_count() == threads


def test_ctrl_c_interrupts_a_long_call(tmp_path):
    """SIGINT during a sweep (simulated with _thread.interrupt_main once the sweep has reported its
    first chunk) raises KeyboardInterrupt in the caller and leaves no thread running."""
    text = SHOWCASE.read_text()
    for old, new in (("L34: [12, 19, 29]", "L34: [12, 19, 201]"), ("L12: [6, 12, 25]", "L12: [6, 12, 201]")):
        text = text.replace(old, new, 1)
    design = fivebar.Design.from_yaml(text)  # 40,401 designs: many seconds, stopped within one chunk
    threads = threading.active_count()
    seen = []
    started = threading.Event()

    def progress(done, total, seconds):
        seen.append(done)
        started.set()

    def interrupt():
        if started.wait(60):
            _thread.interrupt_main()

    interrupter = threading.Thread(target=interrupt)
    interrupter.start()
    with pytest.raises(KeyboardInterrupt):
        fivebar.sweep(design, chunk=64, progress=progress)
    interrupter.join()
    assert seen and seen[-1] < 40401
    assert threading.active_count() == threads


def test_problem_evaluates_in_process(showcase):
    p = fivebar.Problem(showcase)
    assert p.dimension == len(p.variables) == len(p.lower) == len(p.upper)
    x0 = p.reference_values()
    c = p.evaluate(x0)
    assert set(c["x"]) == set(p.variables) and c["verdict"] in {"feasible", "not_covered", "cheap_constraint",
                                                              "invalid", "loop_constraint", "simulation_constraint"}
    rng = np.random.default_rng(3)
    X = rng.uniform(p.lower, p.upper, size=(6, p.dimension))
    cols = p.evaluate_many(X)
    for k in range(6):
        one = p.evaluate(X[k])
        assert cols["verdict"][k] == one["verdict"]
        for fig, value in one["figures"].items():
            assert cols[fig][k] == pytest.approx(value, rel=1e-12)
    assert len(p.fitness(x0)) == len(p.objectives)
    with pytest.raises(ValueError, match=rf"expected shape \(n, {p.dimension}\)"):
        p.evaluate_many(np.zeros((2, p.dimension + 1)))
    with pytest.raises(ValueError, match=rf"x: expected {p.dimension} values"):
        p.evaluate([1.0])
    with pytest.raises(ValueError, match=r"x\[0\] is not finite"):
        p.evaluate([float("nan")] * p.dimension)


def test_problem_figures_name_every_objective_and_every_evaluated_figure(showcase):
    """Problem.figures is a property of the instance (it raised TypeError when bound without self):
    every objective's figure and every figure an evaluation carries is among them."""
    p = fivebar.Problem(showcase)
    figures = p.figures
    assert isinstance(figures, list) and figures and all(isinstance(f, str) for f in figures)
    assert len(set(figures)) == len(figures)
    assert {name for name, _ in p.objectives} <= set(figures)
    assert set(p.evaluate(p.reference_values())["figures"]) <= set(figures)


def test_simulated_series_agree_with_the_summary(showcase):
    runs = fivebar.simulate(showcase, station="index", pattern="stretch")
    assert len(runs) == 1
    run = runs[0]
    assert run.status == "ok", run.reason
    t = run.t
    assert np.allclose(np.diff(t), 0.01)  # controller.loop_rate_hz: 100
    summary = {m["mechanism"] if "mechanism" in m else m["name"]: m for m in run.to_dict()["mechanisms"]}
    for name, series in run.mechanisms.items():
        assert series.P_mm.shape == (len(t), 2) and series.theta.shape == (len(t), 2)
        error = np.hypot(*(series.P_mm - series.P_ref_mm).T).max()
        assert error == pytest.approx(summary[name]["max_error_mm"], rel=1e-6, abs=1e-9)


def test_tolerance_and_export_gate_equal_cli_json(showcase, tmp_path):
    doc = run_cli("tolerance", SHOWCASE, "--station", "index", "--no-files", "--json")
    maps = fivebar.tolerance(showcase, station="index")
    for m, rec in zip(maps, doc["stations"][0]["mechanisms"]):
        assert m.to_dict() == rec
        assert m.fields["three_sigma_mm"].shape == (m.grid["ny"], m.grid["nx"])
    gate = fivebar.export_gate(showcase)
    cli = run_cli("export", SHOWCASE, "--out", tmp_path / "export", "--json")["gate"]
    assert gate.passed == cli["passed"] == bool(gate)
    assert [(c.kind, c.subject, c.passed, c.detail) for c in gate.checks] == [
        (c["kind"], c["subject"], c["passed"], c["detail"]) for c in cli["checks"]]
    assert all(c.passed for c in gate.checks) == gate.passed


def test_io_errors_are_oserrors(showcase):
    with pytest.raises(fivebar.IoError, match="/proc/fivebar-test") as err:
        fivebar.optimize(showcase, evaluations=64, out_dir="/proc/fivebar-test")
    assert isinstance(err.value, OSError)
