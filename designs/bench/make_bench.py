#!/usr/bin/env python3
"""Writes the showcase's synthetic bench files (designs/iros2022.yaml `bench:`), from the repository root:

    python3 designs/bench/make_bench.py [--fivebar build/fivebar]

(needs a built fivebar and PyYAML, Debian python3-yaml; no test runs it: the files are in the
repository, and running it again rewrites them byte for byte)

Nobody measured these: they stand in for a bench until a lab measures its own device, and they
are made from a stated truth so that what `fivebar calibrate` and `fivebar identify` find can be
checked against it (docs/calibrate.md, docs/identify.md).

calibration.csv: the 12 poses `fivebar calibrate designs/iros2022.yaml --plan 12 -s index -m lower`
plans, read on a "true" device that differs from the design: L3 = 15.2 mm (design 15), the second
base joint at x = 12.4 mm (12.5) and theta1's potentiometer reading 0.27 V at zero (0.25). Its
tactor at each pose is `fivebar fk` of a copy of the design with that geometry at the true joint
angles theta_j = k_j (V_j - V0_j), plus N(0, 0.02 mm) of measurement noise per axis (seed 1).

identification.csv: a motor on the bench (no load), driven by a current (the `motor:` defaults as
priors: eta N k_t = 0.7 N m/A at the output) of 0.3 ... 6 Hz random-phase multisine, 10 mA rms,
with true output inertia 2.4e-3 kg m^2, viscous friction 2e-4 N m s/rad, Coulomb friction
8e-4 N m and no offset; simulated by RK4 at 10 kHz (the drive held over each 2 ms sample),
logged at 500 Hz for 4 s with 0.5 mA of noise on the logged current and the angle quantised to
2^16 counts per turn (seed 2).

replay.csv: a device log in the format of `fivebar replay LOG` (docs/runtime.md "Replay"): the
index station following its stretch pattern, the device being `fivebar replay --sil` (the runtime
of this design's export closed around the simulator: its motors, driver, ADC and skin, no noise
beyond the ADC's quantisation), which logs per 10 ms cycle the ADC codes, the reference points and
the duties. Replayed through the runtime of the same export it must give every duty again; after
a change of the controller's gains or calibration in the design it does not (that is what the
`bench_replay` product checks), and this script writes it again.
"""
import argparse
import math
import os
import random
import subprocess
import sys
import tempfile

import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
DESIGN = os.path.join(HERE, "..", "iros2022.yaml")


def calibration(fivebar):
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([fivebar, "calibrate", DESIGN, "--plan", "12", "-s", "index", "-m", "lower", "--out", tmp],
                       check=True, stdout=subprocess.DEVNULL)
        with open(os.path.join(tmp, "calibration-plan.csv")) as f:
            head, *rows = [line.strip().split(",") for line in f if line.strip()]
        plan = [dict(zip(head, r)) for r in rows]
        with open(DESIGN) as f:
            design = yaml.safe_load(f)
        lower = design["stations"]["index"]["mechanisms"]["lower"]
        lower["links"][2] = 15.2
        lower["bases"][1][0] = 12.4
        true_file = os.path.join(tmp, "true.yaml")
        with open(true_file, "w") as f:
            yaml.safe_dump(design, f)
        k = 1.0 / design["controller"]["potentiometer"]["volts_per_rad"]
        v0_true = (0.27, 1.75)
        angles = "theta1_deg,theta2_deg\n"
        for p in plan:
            th1 = k * (float(p["volts1"]) - v0_true[0])
            th2 = k * (float(p["volts2"]) - v0_true[1])
            angles += f"{math.degrees(th1)!r},{math.degrees(th2)!r}\n"
        out = subprocess.run([fivebar, "fk", true_file, "-s", "index", "-m", "lower", "--theta-file", "-"],
                             input=angles, text=True, check=True, capture_output=True).stdout
    fk_head, *fk_rows = [line.split(",") for line in out.strip().splitlines()]
    rng = random.Random(1)
    text = "# Synthetic: made by designs/bench/make_bench.py (its docstring states the truth and the noise)\n"
    text += "station,mechanism,volts1,volts2,x_mm,y_mm\n"
    for p, r in zip(plan, fk_rows):
        row = dict(zip(fk_head, r))
        assert row["status"] == "ok", row
        x = float(row["x_mm"]) + rng.gauss(0.0, 0.02)
        y = float(row["y_mm"]) + rng.gauss(0.0, 0.02)
        text += f"index,lower,{p['volts1']},{p['volts2']},{x:.4f},{y:.4f}\n"
    with open(os.path.join(HERE, "calibration.csv"), "w") as f:
        f.write(text)


def identification():
    rng = random.Random(2)
    J, b, c, alpha = 2.4e-3, 2e-4, 8e-4, 0.7
    harmonics = 20
    phase = [rng.uniform(0.0, 2.0 * math.pi) for _ in range(harmonics)]

    def command(t):
        s = sum(math.sin(2.0 * math.pi * 0.3 * k * t + phase[k - 1]) for k in range(1, harmonics + 1))
        return 0.01 * s / math.sqrt(0.5 * harmonics)

    def accel(u, w):
        return (alpha * u - b * w - c * math.tanh(w / 1e-3)) / J

    rate, sub, duration = 500, 20, 4.0
    h = 1.0 / (rate * sub)
    q, w = 0.0, 0.0
    count = 2.0 * math.pi / 65536.0
    text = "# Synthetic: made by designs/bench/make_bench.py (its docstring states the truth and the noise)\n"
    text += "time_s,current_A,theta_rad\n"
    for n in range(int(duration * rate)):
        t = n / rate
        u = command(t)
        logged = u + rng.gauss(0.0, 5e-4)
        text += f"{t:.3f},{logged:.6f},{round(q / count) * count:.7f}\n"
        for _ in range(sub):  # RK4 with the command held over the sample
            k1q, k1w = w, accel(u, w)
            k2q, k2w = w + 0.5 * h * k1w, accel(u, w + 0.5 * h * k1w)
            k3q, k3w = w + 0.5 * h * k2w, accel(u, w + 0.5 * h * k2w)
            k4q, k4w = w + h * k3w, accel(u, w + h * k3w)
            q += h / 6.0 * (k1q + 2 * k2q + 2 * k3q + k4q)
            w += h / 6.0 * (k1w + 2 * k2w + 2 * k3w + k4w)
    with open(os.path.join(HERE, "identification.csv"), "w") as f:
        f.write(text)


def replay(fivebar):
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([fivebar, "replay", DESIGN, "--sil", "-s", "index", "--pattern", "stretch", "--out", tmp],
                       check=True, stdout=subprocess.DEVNULL)
        with open(os.path.join(tmp, "index-stretch-sil.csv")) as f:
            log = f.read()
    text = "# Synthetic: made by designs/bench/make_bench.py (its docstring states how)\n" + log
    with open(os.path.join(HERE, "replay.csv"), "w") as f:
        f.write(text)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fivebar", default=os.path.join("build", "fivebar"), help="the fivebar binary")
    args = parser.parse_args()
    calibration(args.fivebar)
    identification()
    replay(args.fivebar)
    return 0


if __name__ == "__main__":
    sys.exit(main())
