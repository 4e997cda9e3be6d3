"""Does where the crank starts change the size answer at C of a test-6 run? (issue 17: the sample
recordings' size miss)

Table 4 test 6 (0.1 mm at C, ball bearing at B, 750 motor rpm, y vertical), nominal contact parameters,
the datasets' constant program through the PID (0.4 s ramp), 5.5 s, through the bench's sensor chain
(noise seed fixed), started with the crank at ``--angles`` [rad] (``drive.initial_encoder_angle_rad``; the
training datasets always start at 0), on both engines. Per run and per window of two steady crank
revolutions: the model's size answer at C (the window's own, before the median over windows) and the
window's contact share at C (fn_C > 0). A start angle that moves every window of a run to another steady
answer, the same in both engines, is a second periodic motion of the mechanism, not noise or a transient.

Run: ``python analysis/identify/start_angle_check.py [--angles 0,1,2,3,4,5] [--model M] [--json OUT]``
(about 2 min on two cores).
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from twin.provenance import stamped


def one(job: tuple) -> dict:
    engine, angle, model_path = job
    from twin.config import preset
    from twin.identification.features import features
    from twin.identification.inputs import simulated_inputs
    from twin.identification.intervals import size_answer
    from twin.identification.model import ClearanceModel
    from twin.simulation import simulate_run

    cfg = preset(6).replace(**{"simulation.engine": engine, "simulation.duration_s": 5.5, "drive.ramp_s": 0.4,
                               "drive.initial_encoder_angle_rad": angle, "instrumentation.seed": 0,
                               "sensors.channels": ["accel", "encoder", "crank", "joints"]})
    run = simulate_run(cfg)
    acc, counts, rate, cpr = simulated_inputs(run, cfg)
    X, w = features(acc, counts, rate, cpr, 0.0, cfg.mechanism.orientation)
    m = ClearanceModel.load(model_path)
    est = 10 ** m.size["C"].predict(X)
    fn = np.asarray(run["fn_C"], float)
    return {"engine": engine, "start_angle_rad": angle, "answer_mm": size_answer(m.size["C"], X),
            "windows_mm": [round(float(e), 4) for e in est],
            "contact_share": [round(float(np.mean(fn[a:b] > 0)), 4) for a, b in w.windows]}


def main(argv: list[str] | None = None) -> int:
    from twin.identification.model import default_model_path

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--angles", default="0,1,2,3,4,5", help="start angles [rad], comma-separated")
    ap.add_argument("--model", default=None, help="model file (default: the shipped one)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    model = args.model or str(default_model_path())
    jobs = [(e, float(a), model) for e in ("reference", "mujoco") for a in args.angles.split(",")]
    with ProcessPoolExecutor(args.workers) as ex:
        rows = list(ex.map(one, jobs))
    print("| engine | start angle [rad] | answer at C [mm] (truth 0.1) | windows' answers [mm] | contact share at C |")
    print("|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['engine']} | {r['start_angle_rad']:g} | {r['answer_mm']:.3f} | "
              f"{', '.join(f'{x:.3f}' for x in r['windows_mm'])} | {min(r['contact_share']):.4f}-{max(r['contact_share']):.4f} |")
    if args.json:
        from twin.util import atomic_write_json

        atomic_write_json(Path(args.json), stamped({"model": model, "runs": rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
