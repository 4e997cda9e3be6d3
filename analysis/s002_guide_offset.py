"""The guide offset of the ``s002`` preset (``spatial.guide_offset_z_m``), from the paper's responses.

S002 does not give where the slider's line lies relative to the crank axis. Method: with the guide
along x in the plane XOZ at distance h from the crank axis, the ideal mechanism's slider acceleration
is closed-form (``twin.spatial.geometry.slider_closed_form``); h is the root (Brent) of "peak |a| over
a turn of run 1 (crank 80 mm, 800 rpm) = 32.72 m/s²", S002's optimum (its run 1). The script then
prints the ideal peak at every crank length and speed of the L27 beside the paper's range of
responses (``analysis/results/s002/responses_reconstructed.csv``): the paper's maxima follow the
ideal kinematics of this h (a check, not a fit of the other runs).

Run: ``python analysis/s002_guide_offset.py``.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from twin.config import named_preset
from twin.spatial.geometry import slider_closed_form

PAPER_RUN1_MS2 = 32.72
THETA = np.linspace(0.0, 2.0 * np.pi, 20001)


def ideal_peak(h: float, crank_m: float, rpm: float) -> float:
    cfg = named_preset("s002").replace(**{"spatial.guide_offset_z_m": h, "bodies.crank.length_m": crank_m,
                                          "bodies.crank.x_g_m": crank_m / 2})
    return float(np.max(np.abs(slider_closed_form(cfg, THETA, rpm * np.pi / 30.0)[2])))


def main() -> None:
    h = brentq(lambda x: ideal_peak(x, 0.08, 800.0) - PAPER_RUN1_MS2, 1e-3, 0.1, xtol=1e-9)
    print(f"guide offset h = {h:.6f} m (ideal peak slider acceleration of run 1 = {PAPER_RUN1_MS2} m/s^2)")
    rows = list(csv.DictReader((Path(__file__).parent / "results/s002/responses_reconstructed.csv").open()))
    print("crank mm  rpm   ideal peak [m/s^2]   paper's max_slider_accel over its 3 runs at this crank/speed")
    for r_mm in (80, 100, 120):
        for rpm in (800, 1000, 1200):
            paper = [float(x["max_slider_accel_ms2"]) for x in rows
                     if int(x["crank_length_mm"]) == r_mm and int(x["speed_rpm"]) == rpm]
            print(f"{r_mm:8d} {rpm:5d} {ideal_peak(h, r_mm / 1000, rpm):12.2f}         "
                  + ", ".join(f"{p:.2f}" for p in paper))


if __name__ == "__main__":
    main()
