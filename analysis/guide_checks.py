"""The slider guide clearance's check figures, both engines (docs/guide.md).

Method: (1) statics under a known side load: the crank held by its PID at rest (motor 0 rpm),
B and C ideal, 0.1 mm guide play, the slider's centre of mass 0.02 m ahead of C', gravity −y; the
mean of the last 20 samples of a 0.4 s run against the closed form of tests/test_guide.py
(closed_form: F_f + F_r = (m₃ + m₂ ξ₂/l) g, a (F_f − F_r) = m₃ g x_G, δ = (F/K)^(1/n)).
(2) A running scene: Table 4 test 12 (0.1 mm at B and C, 750 rpm) with 0.1 mm guide play, 1 s;
the peak |rail force| per end, slider |y| and |tilt| in each engine and their relative difference.

Usage: python analysis/guide_checks.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from test_guide import closed_form, static_cfg  # noqa: E402

from twin.config import preset  # noqa: E402
from twin.simulation import simulate_run  # noqa: E402

NAMES = ("fn_guide_front", "fn_guide_rear", "slider_y", "slider_tilt")


def main() -> None:
    print("statics under a known side load (last 20 samples vs closed form):")
    for engine in ("reference", "mujoco"):
        cfg = static_cfg(engine)
        run = simulate_run(cfg)
        for name, want in zip(NAMES, closed_form(cfg)):
            got = float(np.mean(run[name][-20:].astype(float)))
            print(f"  {engine:9s} {name:15s} {got: .9g}  closed form {want: .9g}  rel {(got - want) / want:+.1e}")
    print("test 12 with 0.1 mm guide play, 1 s: peaks")
    peaks = {}
    for engine in ("reference", "mujoco"):
        cfg = preset(12).replace(**{"joints.clearance_guide_mm": 0.1, "simulation.engine": engine,
                                    "simulation.duration_s": 1.0})
        run = simulate_run(cfg)
        peaks[engine] = {n: float(np.abs(run[n].astype(float)).max()) for n in NAMES}
    for n in NAMES:
        a, b = peaks["reference"][n], peaks["mujoco"][n]
        print(f"  {n:15s} reference {a:.6g}  mujoco {b:.6g}  difference {(b - a) / a:+.2%}")


if __name__ == "__main__":
    main()
