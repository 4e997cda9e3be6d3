"""Cost of the drive train: Table 4 test 12 per simulated second, drive.mode = "motor" against
the crank PID, both engines, side by side in one run.

For each engine (MuJoCo twin, reference engine) and each drive ("pid": the crank PID of today;
"motor": the motor's speed loop and the V-belt with the same default channel groups; "motor +
channels": the same plus the optional group ``motor``), the whole engine path
(``twin.simulate.run_chunks``: drive reference, stepping, channel assembly at 100 kHz) runs
``--duration`` simulated seconds of test 12 from rest (0.5 s spin-up ramp to 750 motor rpm,
then full speed). The figure is the engine's stepping wall time (``meta["wall_s"]``: build
and compilation excluded) per simulated second; each variant is the best of ``--repeats`` runs,
variants interleaved so that machine load hits all alike. Printed: seconds per simulated second
and the ratio motor / pid (the target: at most 1.10).

Run: ``python analysis/bench_drivetrain.py [--duration S] [--repeats R]``.
"""

from __future__ import annotations

import argparse

from twin.config import preset
from twin.simulate import make_engine, run_chunks

VARIANTS = {"pid": {}, "motor": {"drive.mode": "motor"},
            "motor + channels": {"drive.mode": "motor", "sensors.channels": None}}


def config(engine: str, variant: str, duration: float):
    cfg = preset(12).replace(**{"simulation.engine": engine, "simulation.duration_s": duration})
    ov = dict(VARIANTS[variant])
    if "sensors.channels" in ov:
        ov["sensors.channels"] = list(cfg.sensors.channels) + ["motor"]
    return cfg.replace(**ov) if ov else cfg


def timed(cfg) -> float:
    engine = make_engine(cfg)
    for _ in run_chunks(cfg, engine):
        pass
    return engine.meta["wall_s"] / cfg.duration_s


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=1.0, help="simulated seconds per run")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    for engine in ("mujoco", "reference"):
        timed(config(engine, "motor", 0.01))  # compile / load once
        timed(config(engine, "pid", 0.01))
    best: dict[tuple[str, str], float] = {}
    for _ in range(args.repeats):
        for engine in ("mujoco", "reference"):
            for variant in VARIANTS:
                s = timed(config(engine, variant, args.duration))
                best[engine, variant] = min(best.get((engine, variant), float("inf")), s)
    print(f"test 12, {args.duration:g} s from rest, best of {args.repeats}: wall s per simulated s")
    for engine in ("mujoco", "reference"):
        pid = best[engine, "pid"]
        line = "  ".join(f"{v} {best[engine, v]:.3f} ({best[engine, v] / pid:.3f}x)" for v in VARIANTS)
        print(f"{engine:10s} {line}")


if __name__ == "__main__":
    main()
