#!/usr/bin/env python3
"""One skin-deformation pattern (stretch by default) simulated under the 100 Hz PID loop and
plotted: the commanded and simulated tactor paths, the tracking error and the motor currents over
time. Needs matplotlib for the picture (Debian: python3-matplotlib); prints the figures without it.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/simulate_pattern.py [DESIGN] [PATTERN] [OUT.png]
"""
import sys

import numpy as np

import fivebar

design = fivebar.load(sys.argv[1] if len(sys.argv) > 1 else "designs/iros2022.yaml")
pattern = sys.argv[2] if len(sys.argv) > 2 else "stretch"
out = sys.argv[3] if len(sys.argv) > 3 else f"simulate_{pattern}.png"
station = next(s for s in design.stations if s.lower and s.upper)
run = fivebar.simulate(design, station=station.name, pattern=pattern)[0]
print(f"{station.name} {run.reference}: {run.status} over {run.t[-1]:.2f} s ({run.steps} integrator steps)")
for name, s in run.mechanisms.items():
    err = np.hypot(*(s.P_mm - s.P_ref_mm).T)
    print(f"  {name}: max tracking error {err.max() * 1e3:.1f} um, peak current {np.abs(s.current_A).max():.3f} A")
try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    sys.exit("no picture: this example's plot needs matplotlib (apt-get install python3-matplotlib)")
fig, (ax_path, ax_err, ax_cur) = plt.subplots(1, 3, figsize=(15, 4.5))
for name, s in run.mechanisms.items():
    ax_path.plot(s.P_ref_mm[:, 0], s.P_ref_mm[:, 1], "--", lw=1, label=f"{name} commanded")
    ax_path.plot(s.P_mm[:, 0], s.P_mm[:, 1], lw=1.5, label=f"{name} simulated")
    ax_err.plot(run.t, np.hypot(*(s.P_mm - s.P_ref_mm).T) * 1e3, label=name)
    for j in range(2):
        ax_cur.plot(run.t, s.current_A[:, j], label=f"{name} motor {j + 1}")
t = np.linspace(0, 2 * np.pi, 361)
ellipse = np.array([station.target.boundary_point(x) for x in t])
ax_path.plot(ellipse[:, 0], ellipse[:, 1], "r-", lw=1, label="target")
ax_path.set_aspect("equal")
ax_path.set(xlabel="x (mm)", ylabel="y (mm)", title=f"{station.name}: {pattern}")
ax_err.set(xlabel="t (s)", ylabel="tracking error (µm)", title="tactor error")
ax_cur.set(xlabel="t (s)", ylabel="current (A)", title="motor currents")
for ax in (ax_path, ax_err, ax_cur):
    ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(out, dpi=120)
print(f"wrote {out}")
