"""Cost of ``structure.mode = "flexible"`` against ``"rigid"`` per simulated second, test 12 (B+C clearances,
750 motor rpm), measured side by side in one run, for each engine that runs the flexible structure.

For each engine and mode: the best of ``--repeats`` runs of ``--duration`` s of stepping (``meta["wall_s"]``:
compiled code loaded before the clock starts), µs per step, and the ratio flexible / rigid. The issue's target
is a ratio of at most 1.5 in each engine. Engines that refuse the flexible structure are reported as such.

Run: ``python analysis/structure_cost.py [--duration 0.3] [--repeats 3] [--engines reference,mujoco]``.
Timings on a shared machine are noisy: compare the numbers of one run.
"""

from __future__ import annotations

import argparse

from twin.config import preset
from twin.errors import TwinError


def measure(engine: str, mode: str, duration: float, repeats: int) -> float | None:
    """Best stepping time [s] of ``repeats`` runs, None if the engine refuses the scene."""
    from twin.simulation import make_engine, run_chunks

    cfg = preset(12).replace(**{"simulation.duration_s": duration, "simulation.engine": engine,
                                "structure.mode": mode})
    best = None
    for _ in range(repeats):
        try:
            eng = make_engine(cfg)
            for _ in run_chunks(cfg, eng):
                pass
        except TwinError as err:
            print(f"  {engine} {mode}: refused ({err})")
            return None
        w = float(eng.meta["wall_s"])
        best = w if best is None else min(best, w)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.3)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--engines", default="reference,mujoco")
    a = ap.parse_args()
    steps = a.duration / preset(12).simulation.timestep_s
    print(f"test 12, {a.duration:g} s simulated, best of {a.repeats}; stepping time (meta wall_s)")
    print(f"{'engine':10s} {'rigid µs/step':>14s} {'flexible µs/step':>17s} {'ratio':>7s}")
    for engine in a.engines.split(","):
        rigid = measure(engine, "rigid", a.duration, a.repeats)
        flex = measure(engine, "flexible", a.duration, a.repeats)
        if rigid is None or flex is None:
            continue
        print(f"{engine:10s} {rigid / steps * 1e6:14.2f} {flex / steps * 1e6:17.2f} {flex / rigid:7.2f}")


if __name__ == "__main__":
    main()
