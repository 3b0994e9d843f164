"""The device-side bindings (collision, pattern, replay, fivebar.runtime.Controller) against the
CLI's --json documents of the same design and files, closed forms (tactor-plane clearance, the
stretch path, the potentiometer chain, the PID's first steps) and second formulations (FK of the
commanded angles, the runtime driven row by row against the log the CLI's software-in-the-loop run
wrote)."""
import json
import math

import numpy as np
import pytest

import fivebar
from conftest import SHOWCASE, run_cli


def mm(point):
    return np.asarray(point, dtype=float)


# --- collision --------------------------------------------------------------------------------------


@pytest.mark.parametrize("upper, lower", [((6.25, 15.5), (6.25, 15.5)),   # both at the centre: moved
                                          ((6.25, 19.5), (6.25, 11.5)),   # 8 mm apart: clear
                                          ((3.0, 17.0), (8.0, 14.0))])
def test_collision_equals_cli_json(showcase, upper, lower):
    doc = run_cli("collision", SHOWCASE, "--station", "index", "--upper", "%g,%g" % upper,
                  "--lower", "%g,%g" % lower, "--json")
    c = fivebar.collision(showcase, upper, lower, station="index")
    assert c.to_dict() == doc
    assert c.collides == doc["collides"]
    assert c.status == doc["status"]
    assert c.moved_mm == doc["moved_mm"]
    assert list(c.lower_point) == doc["lower_point_mm"]
    if doc["before"] is not None:
        assert c.clearance_mm == doc["before"]["min_clearance_mm"]
    assert bool(c) == (not doc["collides"])


def test_collision_clearances_are_the_closed_forms(showcase):
    # Upper tactor straight above the lower one, 8 mm apart: the tactor disks (diameter d_t) are
    # 8 - d_t apart, and in the distal-link plane the closest parts are the two bosses at P
    # (diameter d_b): 8 - d_b. The smallest of the planes is the clearance.
    c = fivebar.collision(showcase, (6.25, 19.5), (6.25, 11.5), station="index")
    d_t = showcase.number("geometry.tactor_diameter")
    d_b = showcase.number("geometry.boss_diameter")
    planes = {p["plane"]: p for p in c.to_dict()["before"]["planes"]}
    tactor = [p for p in planes.values() if p["tactor_plane"]]
    assert len(tactor) == 1 and tactor[0]["min_clearance_mm"] == pytest.approx(8.0 - d_t, abs=1e-12)
    assert planes[1]["min_clearance_mm"] == pytest.approx(8.0 - d_b, abs=1e-12)
    assert c.clearance_mm == pytest.approx(min(p["min_clearance_mm"] for p in planes.values()), abs=0)
    assert c.status == "clear" and not c.collides and c.moved_mm == 0.0
    assert np.array_equal(c.lower_point, c.lower_target)


def test_collision_moved_point_is_free_and_closer_points_on_its_ray_are_not(showcase):
    c = fivebar.collision(showcase, (6.25, 15.5), (6.25, 15.5), station="index")
    assert c.collides and c.status == "moved"
    step = c.lower_point - c.lower_target
    assert np.hypot(*step) == pytest.approx(c.moved_mm, rel=1e-12)
    # A second evaluation at the commanded pair: no collision, nothing to move.
    again = fivebar.collision(showcase, c.upper_target, c.lower_point, station="index")
    assert not again.collides and again.status == "clear"
    assert again.clearance_mm >= showcase.number("geometry.min_clearance")
    # 2 % closer along the same ray still collides (the rule returned the ray's first free point).
    closer = fivebar.collision(showcase, c.upper_target, c.lower_target + 0.98 * step, station="index")
    assert closer.collides


def test_collision_map_equals_cli_json_and_pair_checks(showcase, tmp_path):
    doc = run_cli("collision", SHOWCASE, "--station", "index", "--spacing", "1.5", "--json", "--out", tmp_path)
    doc.pop("files")
    m = fivebar.collision_map(showcase, station="index", spacing_mm=1.5)
    assert m.to_dict() == doc
    assert len(m.points) == doc["points"] and m.pairs == doc["pairs"] and m.colliding == doc["colliding_pairs"]
    assert m.colliding_fraction == pytest.approx(m.colliding / m.pairs, rel=1e-15)
    # Brute force by the pair check (a second path through the library): the lower tactor at every
    # point against the upper at the centre, and three upper positions' colliding shares.
    centre = int(np.argmin(np.hypot(*(m.points - np.array(showcase.station("index").target.center)).T)))
    assert np.hypot(*(m.points[centre] - np.array(showcase.station("index").target.center))) < 1e-12
    usable = m.lower_ok & m.upper_ok
    for upper_index in (centre, 0, len(m.points) - 1):
        if not m.upper_ok[upper_index]:
            continue
        hits = [fivebar.collision(showcase, m.points[upper_index], q, station="index").collides
                for q, ok in zip(m.points, m.lower_ok) if ok]
        assert m.upper_fraction[upper_index] == pytest.approx(np.mean(hits), abs=1e-15)
        if upper_index == centre:
            assert list(m.centre_collides[m.lower_ok]) == [int(h) for h in hits]
    assert usable.any() and bool(m) == (doc["min_free_pair_mm"] is not None)


def test_collision_errors(showcase):
    with pytest.raises(fivebar.InputError, match="unknown station 'pinky'"):
        fivebar.collision(showcase, (6, 15), (6, 15), station="pinky")
    with pytest.raises(fivebar.InputError, match="choose one with station="):
        fivebar.collision(showcase, (6, 15), (6, 15))
    with pytest.raises(fivebar.InputError, match="lower: expected a finite point"):
        fivebar.collision(showcase, (6, 15), (math.nan, 15), station="index")
    with pytest.raises(fivebar.InputError, match=r"upper: expected 2 numbers \(x, y\) in mm, got 3 numbers"):
        fivebar.collision(showcase, (6, 15, 1), (6, 15), station="index")
    with pytest.raises(fivebar.InputError, match="lower: expected 2 numbers"):
        fivebar.collision(showcase, (6, 15), "here", station="index")


# --- pattern ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["stretch", "slip", "twist", "pivot"])
def test_pattern_equals_cli_json(showcase, kind, tmp_path):
    doc = run_cli("pattern", SHOWCASE, "--station", "index", "--pattern", kind, "--json", "--samples",
                  "--out", tmp_path)
    samples = doc.pop("samples")
    doc.pop("files")
    p = fivebar.pattern(showcase, kind, station="index")
    assert p.to_dict() == doc
    assert p.passed == doc["passed"] and bool(p) == doc["passed"]
    assert len(p.t) == len(samples) == doc["spec"]["samples"]
    assert list(p.t) == [s["time_s"] for s in samples]
    for m, name in enumerate(["lower", "upper"]):
        series = p.mechanisms[name]
        for k, s in enumerate(samples):
            record = s["mechanisms"][m]
            assert record["mechanism"] == name
            assert p.status_names[series["status"][k]] == record["status"]
            assert list(series["target_mm"][k]) == record["target_mm"]
            assert list(series["point_mm"][k]) == record["point_mm"]
            if record.get("theta_deg") is not None:
                assert np.degrees(series["theta"][k]) == pytest.approx(record["theta_deg"], rel=1e-13, abs=1e-12)
                assert np.degrees(series["joint_speed"][k]) == pytest.approx(record["joint_speed_deg_s"],
                                                                             rel=1e-13, abs=1e-12)
    for k, s in enumerate(samples):
        if s.get("clearance_mm") is None:
            assert math.isnan(p.clearance_mm[k])
        else:
            assert p.clearance_mm[k] == s["clearance_mm"]
        assert p.moved_mm[k] == s["moved_mm"]


def test_stretch_follows_its_closed_form_and_fk_of_the_angles(showcase):
    a, s, T, rate = 2.5, 7.0, 0.8, 50.0
    p = fivebar.pattern(showcase, "stretch", station="index", amplitude_mm=a, separation_mm=s, duration_s=T,
                        rate_hz=rate)
    cx, cy = showcase.station("index").target.center
    t = np.arange(int(T * rate) + 1) / rate
    assert p.t == pytest.approx(t, abs=1e-15)
    u = (1.0 - np.cos(np.pi * t / T)) / 2.0
    up, low = p.mechanisms["upper"], p.mechanisms["lower"]
    assert up["target_mm"][:, 0] == pytest.approx(cx + a * u, abs=1e-12)
    assert up["target_mm"][:, 1] == pytest.approx(np.full_like(t, cy + s / 2), abs=1e-12)
    assert low["target_mm"][:, 0] == pytest.approx(cx - a * u, abs=1e-12)
    assert low["target_mm"][:, 1] == pytest.approx(np.full_like(t, cy - s / 2), abs=1e-12)
    # The commanded angles put each tactor on its commanded point (FK, a second formulation).
    for name, series in (("upper", up), ("lower", low)):
        mech = showcase.station("index").mechanism(name)
        ok = series["status"] == 0
        x, y, status = fivebar.fk(mech, series["theta"][ok, 0].copy(), series["theta"][ok, 1].copy())
        assert np.all(status == 0)
        assert x == pytest.approx(series["point_mm"][ok, 0], abs=1e-9)
        assert y == pytest.approx(series["point_mm"][ok, 1], abs=1e-9)


def test_pattern_errors(showcase):
    with pytest.raises(fivebar.InputError, match="expected stretch, slip, twist or pivot"):
        fivebar.pattern(showcase, "wobble", station="index")
    with pytest.raises(fivebar.InputError, match="pivot takes amplitude_deg"):
        fivebar.pattern(showcase, "pivot", station="index", amplitude_mm=2.0)
    with pytest.raises(fivebar.InputError, match="pattern stretch: "):
        fivebar.pattern(showcase, "stretch", station="index", duration_s=-1.0)


# --- runtime and replay -----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """The showcase's index station exported (fivebar export --format json) and a log of the
    runtime closed around the simulator (fivebar replay --sil, stretch)."""
    root = tmp_path_factory.mktemp("device")
    run_cli("export", SHOWCASE, "-s", "index", "--format", "json", "--out", root / "exp", "--json")
    config = root / "exp" / "iros2022_controller_index.json"
    run_cli("replay", SHOWCASE, "--sil", "-s", "index", "--pattern", "stretch", "--out", root / "sil", "--json")
    log = root / "sil" / "index-stretch-sil.csv"
    assert config.exists() and log.exists()
    return config, log


def params(config):
    return json.loads(config.read_text())["fivebar_controller"]["ros__parameters"]


def test_replay_equals_cli_json(exported):
    config, log = exported
    doc = run_cli("replay", log, "--config", config, "--json")
    r = fivebar.replay(log, config)
    assert r.to_dict() == doc
    assert r.passed and r.rows == doc["rows"] and r.runtime_duty.shape == (doc["rows"], 4)
    assert np.max(np.abs(r.runtime_duty - r.logged_duty)) == doc["max_duty_difference"]


def test_replay_sil_equals_cli_json_and_its_log(showcase, exported, tmp_path):
    config, cli_log = exported
    doc = run_cli("replay", SHOWCASE, "--sil", "-s", "index", "--pattern", "stretch", "--out", tmp_path / "cli", "--json")
    sil = fivebar.replay_sil(showcase, tmp_path / "py", station="index", pattern="stretch")
    (run,) = sil.runs
    assert bool(sil) and run["ok"] and run["simulated"]
    doc.pop("files")
    expected = doc["runs"][0]
    assert expected.pop("log").endswith("index-stretch-sil.csv") and run["figures"].pop("log") == run["log"]
    summary = sil.to_dict()
    summary["runs"][0].pop("log")
    for d in (summary, doc):  # the simulation's wall time is the only figure that is not the run's
        assert d["runs"][0].pop("wall_s") > 0.0
    assert summary == doc
    # The log is the CLI's byte for byte, and replaying it through the exported runtime gives every
    # duty again (the runtime in the loop is the exported one).
    log = tmp_path / "py" / "index-stretch-sil.csv"
    assert run["log"] == str(log) and log.read_bytes() == (tmp_path / "cli" / "index-stretch-sil.csv").read_bytes()
    again = fivebar.replay(log, config)
    assert again.passed and again.max_duty_difference == 0.0
    with pytest.raises(fivebar.InputError, match="pattern = 'wobble'"):
        fivebar.replay_sil(showcase, tmp_path / "none", station="index", pattern="wobble")
    assert not (tmp_path / "none").exists()  # refused before anything is written


def test_controller_reproduces_the_logged_duties_row_by_row(exported):
    import csv
    config, log = exported
    ctl = fivebar.runtime.Controller(config)
    assert ctl.joints == params(config)["joint_names"]
    assert ctl.mechanisms == ["index/lower", "index/upper"]
    with open(log, newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) > 100
    worst = 0.0
    for row in rows:
        readings = [float(row[f"{j}_counts"]) for j in ctl.joints]
        targets = [float(row[f"index_{m}_{a}_ref_mm"]) / 1000.0 for m in ("lower", "upper") for a in ("x", "y")]
        out = ctl.step(readings, targets, kind="counts")
        logged = np.array([float(row[f"{j}_duty"]) for j in ctl.joints])
        worst = max(worst, float(np.max(np.abs(out["duties"] - logged))))
    assert worst <= 1e-12


def test_controller_first_steps_are_the_pid_closed_form(showcase, exported):
    config, _ = exported
    p = params(config)
    T = 1.0 / p["loop_rate_hz"]
    ctl = fivebar.runtime.Controller(config.read_text())  # the JSON text works as well as the path
    station = showcase.station("index")
    targets_mm = [(6.25, 11.5), (6.25, 19.5)]
    commanded = [fivebar.ik(station.lower, *targets_mm[0]), fivebar.ik(station.upper, *targets_mm[1])]
    delta = np.array([0.01, -0.02, -0.015, 0.005])  # rad, below the slew limit's max_velocity * T
    command = np.array([commanded[0].theta1, commanded[0].theta2, commanded[1].theta1, commanded[1].theta2])
    measured = command + delta
    targets = [c / 1000.0 for xy in targets_mm for c in xy]
    error = command - measured
    integral = np.zeros(4)
    previous = None
    for _ in range(2):
        out = ctl.step(measured, targets, kind="radians")
        assert list(out["status_names"]) == ["ok", "ok"]
        assert out["theta_measured"].ravel() == pytest.approx(measured, abs=1e-12)
        assert out["theta_command"].ravel() == pytest.approx(command, abs=1e-9)
        for k, joint in enumerate(ctl.joints):
            g = p["gains"][joint]
            integral[k] = np.clip(integral[k] + error[k] * T, -g["i_clamp"] / g["i"], g["i_clamp"] / g["i"])
            derivative = 0.0 if previous is None else (error[k] - previous[k]) / T
            expected = np.clip(g["p"] * error[k] + g["i"] * integral[k] + g["d"] * derivative, -1.0, 1.0)
            assert out["duties"][k] == pytest.approx(expected, abs=1e-9), joint
        previous = error.copy()


def test_controller_reads_counts_through_the_potentiometer_chain(exported):
    config, _ = exported
    p = params(config)
    ctl = fivebar.runtime.Controller(config)
    counts = np.array([41000.0, 40000.0, 40500.0, 41500.0])
    out = ctl.step(counts, [0.00625, 0.0115, 0.00625, 0.0195], kind="counts")
    v = p["adc"]["range_v"][0] + counts * p["adc"]["volts_per_count"]
    for k, joint in enumerate(ctl.joints):
        pot = p["potentiometers"][joint]
        theta = pot["rad_per_volt"] * (v[k] - pot["volts_at_zero"])
        assert out["theta_measured"].ravel()[k] == pytest.approx(theta, abs=1e-12)
    # A reading at the ADC's rail (code 0) is a sensor fault: zero duty for that mechanism.
    out = ctl.step([0.0, 40000.0, 40500.0, 41500.0], [0.00625, 0.0115, 0.00625, 0.0195], kind="counts")
    assert out["status_names"][0] == "sensor_fault" and out["status"][0] == fivebar.runtime.Status.sensor_fault
    assert list(out["duties"][:2]) == [0.0, 0.0]
    # A reading that is not a number is a fault too, never a NaN duty.
    out = ctl.step([41000.0, math.nan, 40500.0, 41500.0], [0.00625, 0.0115, 0.00625, 0.0195], kind="counts")
    assert out["status_names"][0] == "sensor_fault" and list(out["duties"][:2]) == [0.0, 0.0]
    assert np.all(np.isfinite(out["duties"]))


def test_controller_errors(exported):
    config, _ = exported
    with pytest.raises(fivebar.InputError):
        fivebar.runtime.Controller('{"fivebar_controller": {}}')
    with pytest.raises(fivebar.InputError, match="cannot"):
        fivebar.runtime.Controller(str(config) + ".missing")
    ctl = fivebar.runtime.Controller(config)
    with pytest.raises(fivebar.InputError, match="readings: expected 4"):
        ctl.step([1.0, 2.0, 3.0], [0.0] * 4)
    with pytest.raises(fivebar.InputError, match="targets_m: expected 4"):
        ctl.step([1.0] * 4, [0.0] * 3)
    with pytest.raises(fivebar.InputError, match="kind = 'furlongs'"):
        ctl.step([1.0] * 4, [0.0] * 4, kind="furlongs")
    with pytest.raises(fivebar.InputError, match="cannot be read"):
        fivebar.replay(str(config) + ".missing.csv", config)
