#!/usr/bin/env python3
"""The paper's workspace and coverage (IROS 2022, Fig. 4): each station's reachable regions, the
LCI field of the lower mechanism, the shared region and the target ellipse, with the coverage
margins in the title. Needs matplotlib (Debian: python3-matplotlib).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/workspace_coverage.py [DESIGN] [OUT.png]
"""
import sys

import numpy as np

import fivebar

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    sys.exit("this example needs matplotlib: apt-get install python3-matplotlib")

design = fivebar.load(sys.argv[1] if len(sys.argv) > 1 else "designs/iros2022.yaml")
out = sys.argv[2] if len(sys.argv) > 2 else "workspace_coverage.png"
stations = [s for s in design.stations if s.mechanisms]
fig, axes = plt.subplots(1, len(stations), figsize=(6 * len(stations), 6), squeeze=False)
for ax, station in zip(axes[0], stations):
    ws = fivebar.workspace(station, spacing_mm=0.25)
    cov = fivebar.coverage(station)
    g = ws.grid
    lower = ws.mechanisms.get("lower")
    if lower is not None:
        lci = np.where(lower.fields["reach"] == 1, lower.fields["lci"], np.nan)
        im = ax.pcolormesh(g["x"], g["y"], lci, shading="nearest", cmap="viridis", vmin=0, vmax=1)
        fig.colorbar(im, ax=ax, shrink=0.7, label="LCI (lower)")
    colours = {"lower": "tab:blue", "upper": "tab:orange"}
    for name, mw in ws.mechanisms.items():
        for k, loop in enumerate(mw.boundary):
            closed = np.vstack([loop, loop[:1]])
            ax.plot(closed[:, 0], closed[:, 1], color=colours.get(name, "k"), lw=1.2,
                    label=f"{name} reach ({mw.area_mm2:.0f} mm²)" if k == 0 else None)
        for base in (mw.mechanism.O1, mw.mechanism.O2):
            ax.plot(*base, "ks", ms=5)
    if ws.shared is not None:
        for loop in ws.shared.boundary:
            ax.fill(loop[:, 0], loop[:, 1], color="tab:green", alpha=0.15)
    t = np.linspace(0, 2 * np.pi, 361)
    ellipse = np.array([station.target.boundary_point(x) for x in t])
    ax.plot(ellipse[:, 0], ellipse[:, 1], "r-", lw=2, label="target")
    margins = ", ".join(f"{n} {getattr(cov, n).margin_mm:.2f} mm" for n in ("lower", "upper", "shared")
                        if getattr(cov, n) is not None)
    ax.set_title(f"{station.name}: {'covered' if cov.covered else 'NOT covered'} (margins {margins})", fontsize=9)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.legend(fontsize=7, loc="upper right")
fig.tight_layout()
fig.savefig(out, dpi=120)
print(f"wrote {out}")
