#!/usr/bin/env python3
"""How designs/examples/measurements.csv (docs/tour.md "calibrate") was made: a simulated bench.

The device differs from designs/iros2022.yaml: index/lower L3 = 15.2 mm, O2 at x = 12.4 mm, and its
theta1 potentiometer reads 0.27 V at zero (the design says 0.25 V). For each pose of the plan
(`fivebar calibrate designs/iros2022.yaml --plan 12 -s index -m lower --out bench`), the readings
are the plan's volts; the tactor is where `fivebar fk` puts the true device at the true angles,
plus Gaussian noise of 0.02 mm per axis (seed 2022), rounded to 0.1 um as a camera would report.

Usage: make_measurements.py FIVEBAR PLAN_CSV DESIGN_YAML > measurements.csv
"""
import csv
import io
import math
import random
import subprocess
import sys

VOLTS_PER_RAD = 0.9549296585513721  # controller.potentiometer.volts_per_rad of the design
TRUE_VOLTS_AT_ZERO = (0.27, 1.75)   # lower theta1 (design 0.25), theta2 (as designed)


def main(fivebar, plan_csv, design_yaml):
    with open(design_yaml, encoding="utf-8") as f:
        design = f.read()
    # The device as printed: index/lower L3 15.2 mm, O2 at x = 12.4 mm (the first mechanism of the file).
    device = design.replace("bases: [[0, 0], [12.5, 0]]", "bases: [[0, 0], [12.4, 0]]", 1)
    device = device.replace("links: [9, 9, 15, 15]", "links: [9, 9, 15.2, 15]", 1)
    with open("device.yaml", "w", encoding="utf-8") as f:
        f.write(device)
    with open(plan_csv, encoding="utf-8") as f:
        plan = list(csv.DictReader(f))
    angles = "theta1_deg,theta2_deg\n" + "".join(
        f"{math.degrees((float(r['volts1']) - TRUE_VOLTS_AT_ZERO[0]) / VOLTS_PER_RAD)!r},"
        f"{math.degrees((float(r['volts2']) - TRUE_VOLTS_AT_ZERO[1]) / VOLTS_PER_RAD)!r}\n" for r in plan)
    fk = subprocess.run([fivebar, "fk", "device.yaml", "-s", "index", "-m", "lower", "--theta-file", "-"],
                        input=angles, capture_output=True, text=True, check=True)
    rows = list(csv.DictReader(io.StringIO(fk.stdout)))
    rng = random.Random(2022)
    out = csv.writer(sys.stdout, lineterminator="\n")
    out.writerow(["station", "mechanism", "volts1", "volts2", "x_mm", "y_mm"])
    for r, p in zip(plan, rows):
        x = float(p["x_mm"]) + rng.gauss(0.0, 0.02)
        y = float(p["y_mm"]) + rng.gauss(0.0, 0.02)
        out.writerow([r["station"], r["mechanism"], r["volts1"], r["volts2"], f"{x:.4f}", f"{y:.4f}"])


if __name__ == "__main__":
    main(*sys.argv[1:4])
