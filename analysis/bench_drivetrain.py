"""Cost of the drive train: Table 4 test 12 per simulated second, drive.mode = "motor" against
the crank PID, both engines, side by side in one run.

For each engine (MuJoCo twin, reference engine) and each drive ("pid": the crank PID of today;
"motor": the motor's speed loop and the V-belt with the same default channel groups; "motor +
channels": the same plus the optional group ``motor``), the whole engine path
(``twin.simulation.run_chunks``: drive reference, stepping, channel assembly at 100 kHz) runs
``--duration`` simulated seconds of test 12 from rest (0.5 s spin-up ramp to 750 motor rpm,
then full speed). The figure is the process's CPU time (``time.process_time``: on a shared,
oversubscribed machine wall time mostly measures waiting) of the chunk loop per simulated second,
the engine built before (model build and compilation excluded); each variant is the best of
``--repeats`` runs, variants interleaved so that machine load hits all alike. Printed: seconds per simulated second
and the ratio motor / pid (the target: at most 1.10).

Run: ``python analysis/bench_drivetrain.py [--duration S] [--repeats R] [--test ID]`` (``--test 3``: the
ideal scene, where the two drives' contact work cannot differ).
"""

from __future__ import annotations

import argparse
import time

from twin.config import preset
from twin.simulation import make_engine, run_chunks

VARIANTS = {"pid": {}, "motor": {"drive.mode": "motor"},
            "motor + channels": {"drive.mode": "motor", "sensors.channels": None}}


def config(engine: str, variant: str, duration: float, test: int = 12):
    cfg = preset(test).replace(**{"simulation.engine": engine, "simulation.duration_s": duration})
    ov = dict(VARIANTS[variant])
    if "sensors.channels" in ov:
        ov["sensors.channels"] = list(cfg.sensors.channels) + ["motor"]
    return cfg.replace(**ov) if ov else cfg


def timed(cfg) -> float:
    """CPU seconds of this process per simulated second, stepping only (engine built first)."""
    engine = make_engine(cfg)
    it = run_chunks(cfg, engine)
    t0 = time.process_time()
    for _ in it:
        pass
    return (time.process_time() - t0) / cfg.duration_s


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=1.0, help="simulated seconds per run")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--test", type=int, default=12, help="Table 4 test (12: B+C clearance; 3: ideal joints)")
    args = ap.parse_args()
    for engine in ("mujoco", "reference"):
        timed(config(engine, "motor", 0.01))  # compile / load once
        timed(config(engine, "pid", 0.01))
    best: dict[tuple[str, str], float] = {}
    for _ in range(args.repeats):
        for engine in ("mujoco", "reference"):
            for variant in VARIANTS:
                s = timed(config(engine, variant, args.duration, args.test))
                best[engine, variant] = min(best.get((engine, variant), float("inf")), s)
    print(f"test {args.test}, {args.duration:g} s from rest, best of {args.repeats}: CPU s per simulated s")
    for engine in ("mujoco", "reference"):
        pid = best[engine, "pid"]
        line = "  ".join(f"{v} {best[engine, v]:.3f} ({best[engine, v] / pid:.3f}x)" for v in VARIANTS)
        print(f"{engine:10s} {line}")


if __name__ == "__main__":
    main()
