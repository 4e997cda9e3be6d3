"""Make docs/twin.png, the README's figure: the bench's geometry and what a run of it gives.

Method: Table 4 test 12 (0.1 mm diametral clearance at B and C, 750 motor rpm, y vertical) is simulated by
the MuJoCo twin for 2 s (0.5 s ramp, then steady); the figure shows

* left: the mechanism at crank angle 60° drawn from the configuration (crank, rod, slider, guide; the
  accelerometers AC1–AC6 at their mounts; the two clearances drawn 200 times their size);
* right: what ``twin plot RUN --spectrum --channels AC6,AC3,fn_C --window 1:2`` draws
  (:func:`twin.viz.plot.draw`): over the last second, the slider's accelerometer AC6, the rod's AC3 and
  the contact force at C, their Hann spectra with the crank harmonics and the bench paper's bands, and the
  journal centres at B and C in their bushings (µm, inside the 50 µm clearance circles, red where in contact).

Run: ``python docs/make_figure.py [--out docs/twin.png] [--engine mujoco|reference]`` (a few seconds).
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import math

import matplotlib.patches as mpatches
import numpy as np
from matplotlib.figure import Figure

from twin.config import preset
from twin.simulation import simulate_run
from twin.util import atomic_write_bytes
from twin.viz.plot import DPI, draw, load

MAGNIFY = 200.0          # clearance circles in the geometry sketch
THETA_DEG = 60.0         # crank angle of the sketch
WINDOW_S = 1.0           # the signals' and spectra's window at the end of the run [s]
DURATION_S = 2.0         # simulated time [s]
CHANNELS = ["AC6", "AC3", "fn_C"]


def geometry(ax, cfg) -> None:
    r, l = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    d_off = cfg.mechanism.d_off_m
    th = math.radians(THETA_DEG)
    b = np.array([r * math.cos(th), r * math.sin(th)])
    xc = b[0] + math.sqrt(l ** 2 - (d_off - b[1]) ** 2)
    c = np.array([xc, d_off])
    u = (c - b) / l                                    # rod axis
    n = np.array([-u[1], u[0]])
    ax.plot([-0.05, xc + 0.15], [d_off - 0.03] * 2, color="0.6", lw=3, solid_capstyle="butt")   # guide
    ax.add_patch(mpatches.Rectangle((xc - 0.04, d_off - 0.03), 0.08, 0.06, fc="0.85", ec="0.3", zorder=2))
    ax.plot([0, b[0]], [0, b[1]], color="tab:blue", lw=6, solid_capstyle="round", zorder=3)
    ax.plot([b[0], c[0]], [b[1], c[1]], color="tab:gray", lw=5, solid_capstyle="round", zorder=3)
    ax.add_patch(mpatches.Circle((0, 0), 0.012, fc="k", zorder=4))
    for name, p, cl in (("B", b, cfg.joints.clearance_b_mm), ("C", c, cfg.joints.clearance_c_mm)):
        rad = cl / 2 * 1e-3 * MAGNIFY
        ax.add_patch(mpatches.Circle(p, max(rad, 0.004), fc="white", ec="tab:green", lw=1.5, zorder=5))
        below = name == "C"
        ax.annotate(f"{name}: {cl:g} mm", p, xytext=(0, -26) if below else (-12, 10), textcoords="offset points",
                    ha="center" if below else "right",
                    color="tab:green", fontsize=9)
    ax.annotate("A", (0, 0), xytext=(-14, -4), textcoords="offset points", fontsize=9)
    for name, mount in cfg.sensors.accelerometers.items():
        if mount.body == "rod":
            p = b + mount.position_m[0] * u + mount.position_m[1] * n
            d = u if mount.axis.endswith("x") else n
            off = 6 * d + (12 * n if mount.axis.endswith("x") else 0)
        elif mount.body == "slider":
            p = c + np.array(mount.position_m)
            d = np.array([1.0, 0.0]) if mount.axis.endswith("x") else np.array([0.0, 1.0])
            off = 6 * d
        else:
            continue
        ax.annotate("", p + 0.045 * d, p, arrowprops=dict(arrowstyle="->", color="tab:red", lw=1.2), zorder=6)
        ax.annotate(name, p + 0.045 * d, xytext=(off[0], off[1]), textcoords="offset points", fontsize=8,
                    color="tab:red", ha="left" if d[0] > 0.5 else "center", va="bottom" if d[1] > 0.5 else "center",
                    zorder=6)
    g = {"x": (1, 0), "y": (0, 1), "z": (0, 0)}[cfg.mechanism.orientation]
    if any(g):
        ax.annotate("g", (0.55, 0.12), xytext=(0.55 + 0.06 * g[0], 0.12 + 0.06 * g[1]),
                    arrowprops=dict(arrowstyle="<-", color="0.3"), fontsize=9, color="0.3")
    ax.set_aspect("equal")
    ax.set_xlim(-0.1, xc + 0.17)
    ax.set_ylim(-0.12, 0.22)
    ax.set_xlabel("along the guide [m]")
    ax.set_ylabel("[m]")
    ax.set_title(f"test 12 at crank angle {THETA_DEG:g}°; clearances drawn ×{MAGNIFY:g}", fontsize=10)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/twin.png")
    ap.add_argument("--engine", default="mujoco", choices=("mujoco", "reference"))
    args = ap.parse_args(argv)
    cfg = preset(12)
    cfg = dataclasses.replace(cfg, simulation=dataclasses.replace(cfg.simulation, duration_s=DURATION_S,
                                                                  engine=args.engine))
    run = simulate_run(cfg)
    fig = Figure(figsize=(16, 6.2), dpi=DPI)
    left, right = fig.subfigures(1, 2, width_ratios=[1.3, 2.4], wspace=0.0)
    ax = left.add_subplot()
    left.subplots_adjust(left=0.12, right=0.98, bottom=0.1, top=0.9)
    geometry(ax, cfg)
    # the signals, spectra and journal orbits: what `twin plot RUN --spectrum --channels AC6,AC3,fn_C` draws
    info = draw(right, load(run), channels=CHANNELS, window=(DURATION_S - WINDOW_S, DURATION_S), spectrum=True,
                title="")
    fig.suptitle(f"twin: the slider–crank bench with clearance joints (Table 4 test 12, {args.engine} engine, "
                 f"750 motor rpm; crank {info.crank_hz:.3f} Hz; the last {WINDOW_S:g} s of a {DURATION_S:g} s run)",
                 fontsize=12)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    atomic_write_bytes(args.out, buf.getvalue())
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
