"""How much S002's placeholders move its two responses (run 1 of the L27, the MuJoCo twin).

Method: run 1 (crank 80 mm, clearance 0.1 mm radial at A, B and C, μ 0.01, 800 rpm) of
``analysis/datasets/s002_l27.toml``'s settings (0.5 s, responses over t >= 0.1 s: max |slider
acceleration|, max contact force at A), once at the preset's values and once at each end of each
placeholder's range, one placeholder at a time. Writes ``analysis/results/s002/simulated/placeholders.md``.
Run: ``python analysis/s002_placeholders.py`` (about a minute on two cores).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from twin.config import named_preset
from twin.simulation import simulate_run
from twin.provenance import with_stamp_line

OUT = Path(__file__).resolve().parent / "results/s002/simulated/placeholders.md"
SETTLE_S = 0.1
#: placeholder -> (label, low, high)
RANGES = {
    "spatial.guide_offset_z_m": ("guide offset from the crank axis [m]", 0.01, 0.05),
    "joints.pin_diameter_m": ("journal and ball diameter [m]", 0.01, 0.04),
    "contact.restitution": ("restitution e [-]", 0.2, 0.8),
    "contact.impact_speed_floor_mps": ("impact-speed floor [m/s]", 0.05, 0.2),
    "contact.stiffness_scale": ("factor on Eq. 18's K [-]", 0.5, 2.0),
}


def responses(**overrides) -> tuple[float, float]:
    cfg = named_preset("s002").replace(**{"simulation.engine": "mujoco", "simulation.duration_s": 0.5,
                                          "sensors.channels": ["crank", "slider", "joints", "slider_accel"],
                                          **overrides})
    run = simulate_run(cfg)
    i0 = int(round(SETTLE_S * run.rate_hz))
    return float(np.max(np.abs(run["slider_acceleration"][i0:]))), float(np.max(run["fn_A"][i0:]))


def main() -> None:
    a0, f0 = responses()
    lines = ["# S002 run 1: how much the placeholders move the responses", "",
             "Written by `analysis/s002_placeholders.py` (method in its docstring). MuJoCo twin, 0.5 s, responses "
             "over t >= 0.1 s; each placeholder at the ends of its range, the others at the preset's values.", "",
             f"Preset: max slider acceleration {a0:.1f} m/s², max force at A {f0:.0f} N.", "",
             "| placeholder | value | max slider acc. [m/s²] | change | max force A [N] | change |",
             "|---|---|---|---|---|---|"]
    for key, (label, lo, hi) in RANGES.items():
        for v in (lo, hi):
            a, f = responses(**{key: v})
            lines.append(f"| {label} | {v:g} | {a:.1f} | {100 * (a / a0 - 1):+.0f} % | {f:.0f} "
                         f"| {100 * (f / f0 - 1):+.0f} % |")
            print(lines[-1])
    OUT.write_text(with_stamp_line("\n".join(lines)), encoding="utf-8")
    print("wrote", OUT)


if __name__ == "__main__":
    main()
