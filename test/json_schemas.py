#!/usr/bin/env python3
"""Every command's --json document against its JSON Schema in docs/schemas/ (docs/conventions.md
"JSON documents"), validated by python3-jsonschema (Debian), an implementation independent of the
code that writes the documents.

    json_schemas.py FIVEBAR SOURCE_DIR WORK_DIR

Runs each subcommand on the showcase design (and on cases that change a document's shape: an
unreachable pose, a target that is not covered, both collision forms, the step of simulate),
validates stdout against docs/schemas/<command>.schema.json, validates the summary.json of a
`fivebar run`, and checks what a schema cannot say: no object anywhere is keyed by one of the
design's station names. Before that it shows that the validator rejects the shapes the rules forbid
(stations keyed by name, a mechanism record without its name), so a schema that accepted
everything would fail here.

Exit 0 all valid, 1 a document failed (each failure printed), 77 python3-jsonschema missing (ctest
reports the test as skipped; ./test.sh installs it).
"""
import copy
import json
import math
import pathlib
import shutil
import subprocess
import sys

try:
    from jsonschema import Draft202012Validator, RefResolver
except ImportError:  # pragma: no cover
    print("SKIP: python3-jsonschema is not installed (Debian package python3-jsonschema; ./test.sh installs it)")
    sys.exit(77)

FIVEBAR, SOURCE, WORK = str(pathlib.Path(sys.argv[1]).resolve()), pathlib.Path(sys.argv[2]).resolve(), pathlib.Path(sys.argv[3]).resolve()
SCHEMAS = SOURCE / "docs" / "schemas"
DESIGN = str(SOURCE / "designs" / "iros2022.yaml")
STATIONS = {"index", "thumb"}  # the showcase's station names: never keys of an object

failures = []


def validator(name):
    schema = json.loads((SCHEMAS / f"{name}.schema.json").read_text())
    Draft202012Validator.check_schema(schema)
    resolver = RefResolver(base_uri=SCHEMAS.as_uri() + "/", referrer=schema)
    return Draft202012Validator(schema, resolver=resolver)


def keyed_by_station(node, path="$"):
    """Paths of objects that hold an object under a station name (a station keyed by its name)."""
    found = []
    if isinstance(node, dict):
        for k, v in node.items():
            if k in STATIONS and isinstance(v, dict):
                found.append(f"{path}.{k}")
            found += keyed_by_station(v, f"{path}.{k}")
    elif isinstance(node, list):
        for i, v in enumerate(node):
            found += keyed_by_station(v, f"{path}[{i}]")
    return found


MECHANISMS = {"lower", "upper"}  # mechanism names: never the keys of an object either


def keyed_by_name(node, path="$"):
    """Paths of objects whose keys are all station or mechanism names (a map keyed by name, e.g.
    {"lower": 10.5, "upper": 11.2}): the conventions want a list of records instead."""
    found = []
    if isinstance(node, dict):
        if node and set(node) <= (STATIONS | MECHANISMS):
            found.append(path)
        for k, v in node.items():
            found += keyed_by_name(v, f"{path}.{k}")
    elif isinstance(node, list):
        for i, v in enumerate(node):
            found += keyed_by_name(v, f"{path}[{i}]")
    return found


def check(label, schema, doc):
    errors = sorted(validator(schema).iter_errors(doc), key=lambda e: list(e.absolute_path))
    for e in errors[:10]:
        failures.append(f"{label}: {'/'.join(map(str, e.absolute_path)) or '(root)'}: {e.message[:300]}")
    for p in keyed_by_station(doc):
        failures.append(f"{label}: {p}: an object keyed by a station name (list station records instead)")
    for p in keyed_by_name(doc):
        failures.append(f"{label}: {p}: an object keyed by station or mechanism names (list records instead)")
    if not errors:
        print(f"ok    {label}  ({schema}.schema.json)")


def run(label, schema, args, codes=(0,)):
    out = subprocess.run([FIVEBAR, *args, "--json"], cwd=WORK, capture_output=True, text=True, timeout=900)
    if out.returncode not in codes:
        failures.append(f"{label}: exit {out.returncode} (expected {codes}); stderr: {out.stderr[-500:]}")
        return None
    try:
        doc = json.loads(out.stdout)
    except json.JSONDecodeError as e:
        failures.append(f"{label}: stdout is not one JSON document ({e})")
        return None
    check(label, schema, doc)
    return doc


def main():
    if WORK.exists():
        shutil.rmtree(WORK)
    WORK.mkdir(parents=True)
    for f in sorted(SCHEMAS.glob("*.schema.json")):
        Draft202012Validator.check_schema(json.loads(f.read_text()))

    out = str(WORK / "out")
    coverage = run("coverage", "coverage", ["coverage", DESIGN])
    # The validator must reject the forbidden shapes (a check that cannot fail is no check).
    if coverage is not None:
        bad = copy.deepcopy(coverage)
        bad["stations"] = {s["station"]: s for s in bad["stations"]}
        if not list(validator("coverage").iter_errors(bad)):
            failures.append("self-test: stations keyed by name passed the coverage schema")
        bad = copy.deepcopy(coverage)
        del bad["stations"][0]["mechanisms"][0]["mechanism"]
        if not list(validator("coverage").iter_errors(bad)):
            failures.append("self-test: a mechanism record without \"mechanism\" passed the coverage schema")
        bad = copy.deepcopy(coverage)
        bad["stations"][0]["mechanisms"] = {m["mechanism"]: m for m in bad["stations"][0]["mechanisms"]}
        if not list(validator("coverage").iter_errors(bad)):
            failures.append("self-test: mechanisms keyed by name passed the coverage schema")
        if not keyed_by_station({"x": {"index": {"margin_mm": 1}}}) or keyed_by_station({"index": 3}):
            failures.append("self-test: the station-key walk is wrong")

    run("coverage --robust", "coverage", ["coverage", DESIGN, "-s", "thumb", "--robust"])
    run("coverage, not covered", "coverage", ["coverage", DESIGN, "-s", "index", "--ellipse", "6.25,15.5,30,30,0"], (1,))
    run("fk", "fk", ["fk", DESIGN, "-s", "index", "-m", "lower", "--theta", "100,80"])
    run("fk --all", "fk", ["fk", DESIGN, "-s", "index", "-m", "lower", "--theta", "100,80", "--all"])
    run("fk, unreachable", "fk", ["fk", DESIGN, "-s", "index", "-m", "lower", "--theta", "180,0"], (1,))
    run("ik", "ik", ["ik", DESIGN, "-s", "index", "-m", "lower", "--point", "6.25,15.5"])
    run("ik --all", "ik", ["ik", DESIGN, "-s", "index", "-m", "lower", "--point", "6.25,15.5", "--all"])
    run("ik, unreachable", "ik", ["ik", DESIGN, "-s", "index", "-m", "lower", "--point", "60,15.5"], (1,))
    run("workspace", "workspace", ["workspace", DESIGN, "--spacing", "0.5", "--out", out + "/ws"])
    run("collision map", "collision", ["collision", DESIGN, "-s", "index", "--spacing", "1.5", "--out", out + "/col"])
    run("collision pair", "collision", ["collision", DESIGN, "-s", "index", "--upper", "6,18", "--lower", "6,14"], (0, 1))
    run("pattern", "pattern", ["pattern", DESIGN, "-s", "thumb", "--pattern", "twist", "--out", out + "/pat"])
    run("sweep", "sweep", ["sweep", DESIGN, "--no-plots", "--out", out + "/sweep"])
    run("optimize", "optimize", ["optimize", DESIGN, "--evaluations", "128", "--no-plots", "--out", out + "/optimize"])
    run("parts", "parts", ["parts", DESIGN, "--no-render", "--out", out + "/parts"])
    # Rendered (openscad): the STL paths, the mesh checks and the measured holes; the thumb's
    # parts are the index's but for the base and the distal links, so one station shows every kind.
    rendered = run("parts, rendered", "parts", ["parts", DESIGN, "-s", "index", "--out", out + "/parts-rendered"])
    if rendered is not None and not all(p["mesh"] is not None for p in rendered["parts"]):
        failures.append("parts, rendered: a part without its mesh checks")
    run("export", "export", ["export", DESIGN, "--out", out + "/export"])
    run("report stability", "report-stability", ["report", "stability", DESIGN, "-s", "index", "-q"])
    run("report accuracy", "report-accuracy", ["report", "accuracy", DESIGN, "-s", "index", "--quick", "-q", "--out", out + "/report"])
    run("simulate", "simulate", ["simulate", DESIGN, "-s", "index", "--pattern", "stretch", "--no-render", "--out", out + "/sim"])
    run("simulate --step", "simulate", ["simulate", DESIGN, "-s", "index", "--step", "--no-render", "--out", out + "/sim"])
    sil = run("replay --sil", "replay", ["replay", DESIGN, "--sil", "-s", "index", "--pattern", "stretch", "--out", out + "/replay"])
    if sil is not None and sil.get("runs"):
        run("replay LOG", "replay", ["replay", sil["runs"][0]["log"], "--config", out + "/export/iros2022_controller.json"])
    run("tolerance", "tolerance", ["tolerance", DESIGN, "--out", out + "/tol"])
    # identify: a bench log of a rigid motor under a torque drive, written here (explicit Euler).
    rows, q, v = ["time_s,torque_Nm,theta_rad"], 0.0, 0.0
    for k in range(3000):
        t = k * 1e-3
        tau = 0.05 * math.sin(2 * math.pi * 1.3 * t) + 0.03 * math.sin(2 * math.pi * 3.1 * t + 1.0)
        rows.append(f"{t:.6f},{tau!r},{q!r}")
        v += (tau - 1e-3 * v - 5e-3 * math.tanh(v / 1e-2)) / 2e-3 * 1e-3
        q += v * 1e-3
    pathlib.Path(out).mkdir(parents=True, exist_ok=True)
    bench_log = pathlib.Path(out) / "bench.csv"
    bench_log.write_text("\n".join(rows) + "\n")
    run("identify", "identify", ["identify", DESIGN, str(bench_log), "--validation", str(bench_log), "--out", out + "/identify"])
    run("identify --plan", "identify", ["identify", DESIGN, "--plan", "--out", out + "/identify"])
    run("control", "control", ["control", DESIGN, "-s", "index", "--grid", "9", "--field", "9", "--out", out + "/control"])
    run("control --tune", "control", ["control", DESIGN, "-s", "index", "--grid", "9", "--field", "9", "--tune",
                                      "--tune-evaluations", "2", "--out", out + "/tune"], (0, 1))
    # calibrate: a plan, then "measurements" at the planned poses (their expected points, 0.01 mm
    # apart from the model), fitted with the instrument's pose (a shape with unidentifiable entries).
    plan = run("calibrate --plan", "calibrate", ["calibrate", DESIGN, "-s", "index", "--plan", "12", "--out", out + "/cal"])
    if plan is not None:
        rows = (pathlib.Path(out) / "cal" / "calibration-plan.csv").read_text().splitlines()[1:]
        meas = ["station,mechanism,volts1,volts2,x_mm,y_mm"]
        for i, row in enumerate(rows):
            c = row.split(",")
            meas.append(f"{c[0]},{c[1]},{c[5]},{c[6]},{float(c[7]) + 0.01 * ((i % 3) - 1)},{float(c[8]) - 0.01 * ((i % 5) - 2)}")
        (WORK / "meas.csv").write_text("\n".join(meas) + "\n")
        run("calibrate", "calibrate", ["calibrate", DESIGN, str(WORK / "meas.csv"), "--frame", "fit", "--holdout", "2",
                                       "--out", out + "/cal"])
    run("animate", "animate", ["animate", DESIGN, "-s", "index", "--pattern", "twist", "--out", out + "/anim"])
    # docs/reliability.md: the hostile and partial shapes validate too, and keep the conventions.
    if keyed_by_name({"a": {"lower": 1.0, "upper": None}}) != ["$.a"] or keyed_by_name({"lower": 1, "x": 2}):
        failures.append("self-test: the name-key walk is wrong")
    showcase = pathlib.Path(DESIGN).read_text()

    def variant(name, old, new):
        assert old in showcase, old
        path = WORK / name
        path.write_text(showcase.replace(old, new, 1))
        return str(path)

    chirp = run("simulate --chirp", "simulate", ["simulate", DESIGN, "-s", "index", "--chirp", "--no-render", "--out", out + "/chirp"],
                (0, 1))
    if chirp is not None and not any("bandwidth" in r for r in chirp["runs"]):
        failures.append("simulate --chirp: no run carries its bandwidth records")
    far = variant("far.yaml", "amplitude_mm: 3             # each tactor", "amplitude_mm: 40            # each tactor")
    sim = run("simulate, not simulated", "simulate", ["simulate", far, "-s", "index", "--pattern", "stretch", "--no-render",
                                                      "--out", out + "/far"], (0, 1, 2))
    if sim is not None and not any(r["status"] == "not_simulated" for r in sim["runs"]):
        print("note  simulate, not simulated: the pattern ran (no not_simulated record to check)")
    unreachable = variant("unreachable.yaml", "target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}",
                          "target: {center: [6.25, 95.5], axes: [15, 12], angle: 0}")
    ctl = run("control, unreachable target", "control", ["control", unreachable, "-s", "index", "--grid", "5", "--field", "5",
                                                         "--out", out + "/ctl-far"], (1,))
    if ctl is not None:
        for st in ctl["stations"]:
            for m in st["mechanisms"]:
                if m["max_rho"] is not None:
                    failures.append(f"control, unreachable target: {m['mechanism']}: max_rho {m['max_rho']} where none exists (null)")
            for m in st["performance"]:
                if m["target_renderable"]:
                    failures.append(f"control, unreachable target: {m['mechanism']}: renderable without a reachable pose")
    tol = run("tolerance, unreachable target", "tolerance", ["tolerance", unreachable, "-s", "index", "--no-files"], (0, 1))
    if tol is not None:
        for st in tol["stations"]:
            for m in st["mechanisms"]:
                if m["target_points_not_ok"] >= m["target_points"] and m["target_worst_3sigma_first_order_at_mm"] is not None:
                    failures.append(f"tolerance, unreachable target: {m['mechanism']}: a worst point where none exists (null)")
    exported = run("export for --check", "export", ["export", DESIGN, "--out", out + "/export-check"])
    if exported is not None:
        yaml = [f for f in exported["files"] if f.endswith(".yaml")]
        if yaml:
            run("export --check", "export", ["export", "--check", yaml[0], DESIGN])
        else:
            failures.append("export: no parameters file to --check")

    doc = run("run", "run", ["run", DESIGN, "-q", "--out", out + "/run", "-P",
                             "kinematics,workspace,coverage,collision,pattern,export,bench_replay"])
    if doc is not None:
        summary = json.loads(pathlib.Path(doc["summary_json"]).read_text())
        check("run: summary.json", "run", summary)

    for f in failures:
        print("FAIL  " + f)
    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
