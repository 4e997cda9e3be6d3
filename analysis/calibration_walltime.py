"""Wall time of a two-recording, five-parameter calibration (the issue's target: within 15 min on 2
cores), next to a one-parameter calibration of the same recordings in the same script (both see the
machine's load, printed before and after each).

    python analysis/calibration_walltime.py --work DIR [--workers 2]

Recordings: two repeats (noise seeds 1, 2) of Table 4 test 6 with the motor drive, joint C 0.5 mm,
1000 motor rpm, 0.6 s, made with known values off the defaults; the calibration starts from the
defaults (``--config``), default budget, ``--drive program``. Prints one JSON line per calibration.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

TRUTH = {"contact.mu0": 0.1, "contact.restitution": 0.6, "contact.stiffness_scale": 2.0,
         "mechanism.guide_friction_n": 10.0, "drivetrain.speed_kp_nms": 0.3}


def config(seed: int, truth: bool):
    from twin.config import preset

    cfg = preset(6).replace(**{"simulation.engine": "reference", "simulation.duration_s": 0.6,
                               "drive.motor_rpm": 1000.0, "drive.ramp_s": 0.05, "drive.mode": "motor",
                               "joints.clearance_c_mm": 0.5, "instrumentation.seed": seed})
    return cfg.replace(**TRUTH) if truth else cfg


def main() -> None:
    import twin
    from twin.calibration import CalibrationOptions

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", required=True, type=Path)
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args()
    a.work.mkdir(parents=True, exist_ok=True)
    recs = []
    for seed in (1, 2):
        p = a.work / f"rep{seed}.mcap"
        if not p.exists():
            twin.record(config(seed, True), p)
        recs.append(p)
    base = config(0, False)
    for fields in (list(TRUTH), ["contact.mu0"]):
        out = a.work / f"cal_{len(fields)}"
        load0 = os.getloadavg()
        t0 = time.perf_counter()
        res = twin.calibrate(recs, fields, out, config=base,
                             options=CalibrationOptions(drive="program", workers=a.workers, plots=False),
                             note=lambda s: print(s, flush=True))
        wall = time.perf_counter() - t0
        print(json.dumps({"fields": fields, "wall_s": round(wall, 1), "evaluations": res.evaluations,
                          "simulated": res.simulated,
                          "seconds_per_evaluation": res.seconds_per_evaluation.to_dict(),
                          "estimate_s": res.report["evaluations"]["estimate_s"], "workers": a.workers,
                          "loadavg_before": load0, "loadavg_after": os.getloadavg(), "cpus": os.cpu_count(),
                          "values": res.values(), "truth": {f: TRUTH[f] for f in fields},
                          "intervals": {p.field: [p.lo, p.hi] for p in res.parameters},
                          "warnings": res.warnings}), flush=True)


if __name__ == "__main__":
    main()
