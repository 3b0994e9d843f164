"""The bench-side bindings (calibrate, parts) against the CLI's --json documents and the files it
writes for the same design and measurement file, with properties of the fit checked on their own
(sigmas from the covariance, the patched design holding the fitted values)."""
import os
import re
import subprocess

import numpy as np
import pytest

import fivebar
from conftest import ROOT, SHOWCASE, cli_path, run_cli

MEASUREMENTS = ROOT / "designs" / "bench" / "calibration.csv"


def same_but_sources(returned, cli_file, data):
    """The design returned equals the file the CLI wrote but for its provenance sources: the CLI names
    the data file relative to the folder it wrote the design into, Python (which writes nothing) by
    its absolute path; both lead to the data file."""
    cli_text = open(cli_file).read()
    source = re.compile(r'source: "([^"]*)"')
    assert source.findall(returned) and source.findall(cli_text)
    for s in source.findall(returned):
        assert os.path.isabs(s) and os.path.realpath(s) == os.path.realpath(data)
    for s in source.findall(cli_text):
        assert not os.path.isabs(s)
        assert os.path.realpath(os.path.join(os.path.dirname(cli_file), s)) == os.path.realpath(data)
    assert source.sub("source: X", returned) == source.sub("source: X", cli_text)


def test_calibrate_equals_cli_json_and_its_patched_file(showcase, tmp_path):
    out = tmp_path / "cal"
    doc = run_cli("calibrate", SHOWCASE, MEASUREMENTS, "--out", out, "--json")
    assert doc["files"]
    doc.pop("files")
    c = fivebar.calibrate(showcase, MEASUREMENTS)
    assert c.to_dict() == doc
    assert bool(c) and c.gate_passed
    records = doc["calibration"]["parameters"]
    assert c.keys == [r["parameter"] for r in records]
    assert list(c.value) == [r["value"] for r in records]
    assert list(c.sigma) == [r["sigma"] for r in records]
    assert list(c.identified) == [r["identified"] for r in records]
    # The patched design is the file the CLI wrote, and holds the fitted values at their keys.
    same_but_sources(c.design.to_yaml(), out / "iros2022-calibrated.yaml", MEASUREMENTS)
    for key, value, ok in zip(c.keys, c.value, c.identified):
        if ok and key.startswith("stations."):
            assert c.design.number(key) == pytest.approx(value, rel=1e-12, abs=1e-12)
    assert fivebar.load(SHOWCASE).to_yaml() == showcase.to_yaml()  # the input design is untouched


def test_calibrate_sigmas_are_the_covariance_diagonal(showcase):
    c = fivebar.calibrate(showcase, MEASUREMENTS)
    cov = c.covariance
    assert cov.shape == (len(c.covariance_names),) * 2
    assert np.allclose(cov, cov.T, rtol=0, atol=1e-15 * np.max(np.abs(cov)))
    assert np.all(np.linalg.eigvalsh(cov) > 0)  # identified parameters: positive definite
    kcov = c.key_covariance
    assert kcov.shape == (len(c.key_covariance_keys),) * 2
    for i, key in enumerate(c.key_covariance_keys):
        k = c.keys.index(key)
        assert c.identified[k]
        assert np.sqrt(kcov[i, i]) == pytest.approx(c.sigma[k], rel=1e-9)


def test_calibrate_gate_refusal_is_reported_and_nothing_patched(showcase):
    # A stated measurement sigma 100x below the synthetic noise: the chi-square test refuses the fit.
    proc = subprocess.run([cli_path(), "calibrate", str(SHOWCASE), str(MEASUREMENTS), "--sigma", "0.0001", "--json"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1
    c = fivebar.calibrate(showcase, MEASUREMENTS, sigma_mm=0.0001)
    import json
    doc = json.loads(proc.stdout)
    doc.pop("files")
    assert c.to_dict() == doc
    assert not c and not c.gate_passed and c.design is None
    assert c.gate_reasons and all(("  " + line) in proc.stderr for line in c.gate_reasons)


def test_hard_stops_give_the_closed_form_offset_and_equal_the_cli(showcase, tmp_path):
    # index/lower theta1's low end is a hard stop at the usable range's end (the export's
    # min_position): readings V = V0 + theta_stop / k give V0 back with the design's k.
    import json
    run_cli("export", SHOWCASE, "-s", "index", "--format", "json", "--out", tmp_path / "exp", "--json")
    p = json.loads((tmp_path / "exp" / "iros2022_controller_index.json").read_text())
    p = p["fivebar_controller"]["ros__parameters"]
    theta_stop = p["joint_limits"]["index_lower_theta1"]["min_position"]
    k = p["potentiometers"]["index_lower_theta1"]["rad_per_volt"]
    v0 = 0.3
    log = tmp_path / "stops.csv"
    log.write_text("station,mechanism,joint,stop,volts\n" + "".join(
        f"index,lower,1,lo,{v0 + theta_stop / k + dv!r}\n" for dv in (-2e-4, 2e-4)))
    out = tmp_path / "cal"
    doc = run_cli("calibrate", SHOWCASE, "--hard-stops", log, "--out", out, "--json")
    doc.pop("files")
    c = fivebar.calibrate_hard_stops(showcase, log)
    assert c.to_dict() == doc and bool(c)
    key = "controller.stations.index.lower.theta1.potentiometer.volts_at_zero"
    k_index = c.keys.index(key)
    assert c.identified[k_index] and c.value[k_index] == pytest.approx(v0, abs=1e-12)
    same_but_sources(c.design.to_yaml(), out / "iros2022-calibrated.yaml", log)
    bad = tmp_path / "bad.csv"
    bad.write_text("station,mechanism,joint,stop,volts\nindex,lower,1,sideways,1\n")
    with pytest.raises(fivebar.InputError, match="bad.csv:2: column 'stop'"):
        fivebar.calibrate_hard_stops(showcase, bad)


def test_calibration_plan_equals_cli_json_and_its_csv(showcase, tmp_path):
    out = tmp_path / "plan"
    doc = run_cli("calibrate", SHOWCASE, "--plan", "12", "-s", "index", "-m", "lower", "--out", out, "--json")
    doc.pop("files")
    plan = fivebar.calibration_plan(showcase, 12, station="index", mechanism="lower")
    assert plan.to_dict() == doc
    assert plan.csv == (out / "calibration-plan.csv").read_text()
    (p,) = plan.plans
    assert bool(plan) and p["problem"] == "" and p["theta"].shape == (12, 2)
    # Each planned tactor point is FK of its planned angles (a second evaluation).
    lower = showcase.station("index").lower
    x, y, status = fivebar.fk(lower, p["theta"][:, 0].copy(), p["theta"][:, 1].copy())
    assert np.all(status == 0)
    assert x == pytest.approx(p["point_mm"][:, 0], abs=1e-9) and y == pytest.approx(p["point_mm"][:, 1], abs=1e-9)
    assert list(p["expected_sigma"]) == [r["planned"] for r in doc["plan"][0]["expected_sigma"]]
    with pytest.raises(fivebar.InputError, match="criterion = 'a'"):
        fivebar.calibration_plan(showcase, 12, station="index", criterion="a")
    with pytest.raises(fivebar.InputError, match="choose a station"):
        fivebar.calibration_plan(showcase, 12)


def test_calibrate_errors(showcase, tmp_path):
    with pytest.raises(fivebar.InputError, match="frame = 'moving'"):
        fivebar.calibrate(showcase, MEASUREMENTS, frame="moving")
    with pytest.raises(fivebar.InputError, match="sigma_mm = "):
        fivebar.calibrate(showcase, MEASUREMENTS, sigma_mm=-1.0)
    bad = tmp_path / "bad.csv"
    bad.write_text("station,mechanism,volts1,volts2,x_mm,y_mm\nindex,lower,1.0,oops,6.0,15.0\n")
    with pytest.raises(fivebar.InputError, match=str(bad) + ":2"):
        fivebar.calibrate(showcase, bad)
    with pytest.raises((fivebar.InputError, fivebar.IoError)):
        fivebar.calibrate(showcase, tmp_path / "missing.csv")


def test_parts_equal_the_cli_files(showcase, tmp_path):
    out = tmp_path / "parts"
    doc = run_cli("parts", SHOWCASE, "--no-render", "--out", out, "--json")
    parts = fivebar.parts(showcase)
    assert [(p.station, p.name) for p in parts] == [(r["station"], r["name"]) for r in doc["parts"]]
    for p, record in zip(parts, doc["parts"]):
        assert p.scad == (out / record["scad"]).read_text()
        assert p.count == record["count"] and p.kind == record["kind"] and p.uses == record["uses"]
        assert p.length_mm == record["length_mm"] and p.mechanisms == record["mechanisms"]
    # A link part is as long as the design's link it makes (the key path of its first use).
    for p in parts:
        if p.kind.endswith("link"):
            mech, link = p.uses[0].split("/")
            key = f"stations.{p.station}.mechanisms.{mech}.links[{int(link[1:]) - 1}]"
            assert p.length_mm == showcase.number(key)
    index_only = fivebar.parts(showcase, station="index")
    assert [p.name for p in index_only] == [p.name for p in parts if p.station == "index"]


def test_parts_errors(showcase):
    with pytest.raises(fivebar.InputError, match="pinky"):
        fivebar.parts(showcase, station="pinky")


# --- identify ---------------------------------------------------------------------------------------

IDENTIFICATION = ROOT / "designs" / "bench" / "identification.csv"


def test_identify_equals_cli_json_and_its_patched_file(showcase, tmp_path):
    out = tmp_path / "id"
    doc = run_cli("identify", SHOWCASE, IDENTIFICATION, "--no-output-error", "--out", out, "--json")
    files = doc.pop("files")
    r = fivebar.identify(showcase, IDENTIFICATION, output_error=False)
    assert r.to_dict() == doc
    assert r.gate_passed == doc["gate"]["passed"] and r.patched == doc["patched"]
    assert r.not_patched == doc["not_patched"]
    (joint,) = r.joints
    record = doc["joints"][0]
    assert joint["keys"] == [p["parameter"] for p in record["parameters"]]
    assert list(joint["value"]) == [p["value"] for p in record["parameters"]]
    assert list(joint["sigma"]) == [p["sigma"] for p in record["parameters"]]
    # Some keys passed the gate: the patched design is the file the CLI wrote.
    assert r.patched and r.design is not None
    written = [f for f in files if f.endswith("-identified.yaml")]
    assert len(written) == 1
    same_but_sources(r.design.to_yaml(), written[0], IDENTIFICATION)


def test_identify_finds_the_synthetic_truth_within_its_sigmas(showcase):
    # designs/bench/make_bench.py's docstring: inertia 2.4e-3 kg m^2, viscous 2e-4 N m s/rad,
    # Coulomb 8e-4 N m, no offset.
    truth = {"inertia_kg_m2": 2.4e-3, "viscous_Nm_s_per_rad": 2e-4, "coulomb_Nm": 8e-4, "offset_Nm": 0.0}
    (joint,) = fivebar.identify(showcase, IDENTIFICATION, output_error=False).joints
    for key, true in truth.items():
        k = joint["keys"].index(key)
        assert joint["identified"][k]
        assert abs(joint["value"][k] - true) < 4.0 * joint["sigma"][k], key
    # The estimate's sigmas are the square roots of its covariance's diagonal, and the correlation
    # is the covariance scaled by them (a second formulation of the same statistics).
    cov, s = joint["covariance"], joint["estimate_sigma"]
    assert np.sqrt(np.diag(cov)) == pytest.approx(s, rel=1e-9)
    ok = s > 0
    corr = cov[np.ix_(ok, ok)] / np.outer(s[ok], s[ok])
    assert corr == pytest.approx(joint["correlation"][np.ix_(ok, ok)], abs=1e-9)


def test_identify_the_assembled_mechanism_equals_cli_json(showcase):
    log = ROOT / "designs" / "bench" / "replay.csv"
    doc = run_cli("identify", SHOWCASE, log, "--rig", "mechanism", "index/lower", "--no-files", "--no-output-error",
                  "--json")
    doc.pop("files")
    r = fivebar.identify(showcase, log, rig="index/lower", output_error=False)
    assert r.to_dict() == doc
    assert [j["joint"] for j in r.joints] == [j["joint"] for j in doc["joints"]] == ["index_lower_theta1",
                                                                                     "index_lower_theta2"]
    for joint in r.joints:
        cov, s = joint["covariance"], joint["estimate_sigma"]
        assert np.sqrt(np.diag(cov)) == pytest.approx(s, rel=1e-9)
    with pytest.raises(fivebar.InputError, match="rig = 'index'"):
        fivebar.identify(showcase, log, rig="index")
    with pytest.raises(fivebar.InputError, match="not with rig mechanism"):
        fivebar.identify(showcase, log, rig="index/lower", method="oe")


def test_identify_errors(showcase, tmp_path):
    with pytest.raises(fivebar.InputError, match="method = 'ls'"):
        fivebar.identify(showcase, IDENTIFICATION, method="ls")
    with pytest.raises(fivebar.InputError, match="not a parameter of this rig"):
        fivebar.identify(showcase, IDENTIFICATION, output_error=False, fit=["spring_rate"])
    with pytest.raises(fivebar.InputError, match="decimation = 0"):
        fivebar.identify(showcase, IDENTIFICATION, decimation=0)
    r = fivebar.identify(showcase, IDENTIFICATION, output_error=False, fit=["motor.gear_ratio"])
    assert r.refused and r.design is None and not r
