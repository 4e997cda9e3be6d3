"""Robustness of the reference engine's flexible structure over the placeholders' ranges.

Draws ``--scenes`` scenes: a Table 4 test (1–12), every ``[structure]`` placeholder uniformly within its range to
explore (:data:`twin.config.structure.EXPLORE_RANGES`), the drive "pid" or "motor"; runs each for ``--duration`` s in
the reference engine and counts refusals (ConfigError: a drawn combination beyond the step's stability margin),
divergences (SimulationError) and runs whose channels are not finite. Prints one line per failure and a summary.

Run: ``python analysis/structure_stability.py [--scenes 40] [--duration 0.05] [--seed 1]``.
"""

from __future__ import annotations

import argparse

import numpy as np

from twin.config import preset
from twin.config.structure import EXPLORE_RANGES
from twin.errors import ConfigError, SimulationError


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=40)
    ap.add_argument("--duration", type=float, default=0.05)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    from twin.simulation import simulate_run

    rng = np.random.default_rng(a.seed)
    counts = {"ok": 0, "refused": 0, "diverged": 0, "not finite": 0}
    for i in range(a.scenes):
        test = int(rng.integers(1, 13))
        drive = ("pid", "motor")[int(rng.integers(0, 2))]
        ov = {f"structure.{field}": float(rng.uniform(lo, hi)) for _, field, _, (lo, hi) in EXPLORE_RANGES}
        ov.update({"structure.mode": "flexible", "simulation.engine": "reference", "drive.mode": drive,
                   "simulation.duration_s": a.duration})
        try:
            run = simulate_run(preset(test).replace(**ov))
        except ConfigError as err:
            counts["refused"] += 1
            print(f"scene {i}: test {test} {drive}: refused: {err}")
            continue
        except SimulationError as err:
            counts["diverged"] += 1
            print(f"scene {i}: test {test} {drive}: DIVERGED: {err}")
            continue
        if not all(np.all(np.isfinite(ch.data)) for ch in run.channels.values()):
            counts["not finite"] += 1
            print(f"scene {i}: test {test} {drive}: channels not finite")
            continue
        counts["ok"] += 1
    print(f"{a.scenes} scenes of {a.duration:g} s (seed {a.seed}): {counts}")


if __name__ == "__main__":
    main()
