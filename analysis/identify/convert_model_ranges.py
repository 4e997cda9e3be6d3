"""Convert a clearance-identification model of format 3 to format 4: add the training ranges.

Format 4 stores, with what the model was trained on, the ranges of what a recording shows by itself
(``twin.identification.ranges``): crank rate, within-turn speed ripple per harmonic of the crank rate
(measured from the encoder), sensor noise level, orientations; and the training windows' feature
quartiles. ``twin identify train`` measures them on every training run. A model of format 3 was trained
before they were measured and its training datasets are not kept (``analysis/identify/train_default.py``:
about 17 GB, generated for the training and deleted), so this script fills them in from what is known:

* **crank rate and orientations**: the model's own ``crank_hz_range`` and ``orientations`` (measured on the
  training runs when it was trained);
* **ripple and noise**: measured, with the same functions, on runs made the way the training runs were: the
  training specs' base configuration (``analysis/datasets/clearance_id*.toml``: MuJoCo, Table 4 test 1 with
  the fault factor, constant program through the PID, ``drive.ramp_s`` 0.3, 3 s, sensor chain with noise,
  sensor offsets of 30 mV spread, 2 mm mounting error; no imposed ripple), at the ends and the middle of the
  training speeds (250, 525, 800 motor rpm) with each orientation and a fault class each (none, B+C 0.5 mm,
  C 0.1 mm). The ripple range is [0, the largest measured] per harmonic (a constant program through the PID
  has no ripple but the PID's tracking residual), the noise range [smallest, largest measured]. These are
  runs LIKE the training runs, not the training runs: the ``source`` field of the ranges says so;
* **feature quartiles**: unknown (null): the feature-space distance is reported as unavailable for this model.

The estimators' arrays, the intervals and every other field are copied unchanged, so the model's location,
sizes and conformal intervals are bit for bit those of the format-3 file (checked on the sample recordings
before writing); only the checks against the training data are new.

Run: ``python analysis/identify/convert_model_ranges.py twin/data/identify_default.npz`` (about 3 minutes on
two cores; writes the file in place, atomically, and ``analysis/results/identify/ranges_shipped.json``).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from twin.provenance import stamped

ROOT = Path(__file__).resolve().parents[2]
OLD_FORMAT = "twin-identify-model/3"
SPEEDS_RPM = (250.0, 525.0, 800.0)
ORIENTATIONS = ("x", "y", "z")
FAULTS = ({}, {"joints.clearance_b_mm": 0.5, "joints.clearance_c_mm": 0.5, "joints.allow_noncatalogue": True},
          {"joints.clearance_c_mm": 0.1})


def measured_like_training() -> list[dict]:
    from twin.config import preset
    from twin.identification.features import steady_windows
    from twin.identification.inputs import simulated_inputs
    from twin.identification.ranges import recording_measures
    from twin.simulation import simulate_run

    rows = []
    for i, rpm in enumerate(SPEEDS_RPM):
        for j, orient in enumerate(ORIENTATIONS):
            fault = FAULTS[(i + j) % len(FAULTS)]
            cfg = preset(1).replace(**{
                "simulation.engine": "mujoco", "simulation.duration_s": 3.0, "drive.ramp_s": 0.3,
                "drive.motor_rpm": rpm, "mechanism.orientation": orient, "instrumentation.seed": 100 + 3 * i + j,
                "instrumentation.zero_g_v": {f"AC{k}": 2.5 + 0.03 * s for k, s in
                                             zip(range(1, 7), (0.4, -1.1, 0.9, -0.3, 1.6, -0.7))},
                "sensors.channels": ("accel", "encoder"), "joints.clearance_b_mm": 0.0, "joints.clearance_c_mm": 0.0,
                **fault})
            run = simulate_run(cfg)
            acc, counts, rate, cpr = simulated_inputs(run, cfg)
            w = steady_windows(counts, rate, cpr)
            m = recording_measures(acc, counts, rate, cpr, w)
            rows.append({"motor_rpm": rpm, "orientation": orient, "clearances_mm": [cfg.joints.clearance_b_mm,
                                                                                    cfg.joints.clearance_c_mm], **m})
            print(rows[-1], flush=True)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("model", help="model file of format 3 (.npz); rewritten in place as format 4")
    ap.add_argument("--out", default=str(ROOT / "analysis" / "results" / "identify" / "ranges_shipped.json"))
    args = ap.parse_args()
    from twin.identification.features import features
    from twin.identification.inputs import recording_inputs
    from twin.identification.intervals import resolution
    from twin.identification.model import ESTIMATORS, ClearanceModel
    from twin.identification.model import MODEL_FORMAT_4 as MODEL_FORMAT  # this script makes format 4 (B, C)
    from twin.identification.modelfile import read_model, write_model

    path = Path(args.model)
    meta, est = read_model(path, OLD_FORMAT, ESTIMATORS)
    rows = measured_like_training()
    tr = meta["trained_on"]
    rip = np.array([r["ripple_pct"] for r in rows])
    nz = np.array([r["noise_ug_rthz"] for r in rows])
    tr["ranges"] = {
        "source": ("crank rate and orientations: the training runs'; ripple and noise: measured by "
                   f"analysis/identify/convert_model_ranges.py on {len(rows)} MuJoCo runs made like the training runs "
                   "(constant program through the PID, no imposed ripple, 250/525/800 motor rpm, x/y/z vertical), "
                   "not on the training runs themselves (not kept)"),
        "runs": len(rows),
        "crank_hz": [float(v) for v in tr["crank_hz_range"]],
        "ripple_pct": [[0.0, float(v)] for v in rip.max(axis=0)],
        "noise_ug_rthz": [float(nz.min()), float(nz.max())],
        "orientations": list(tr["orientations"])}
    tr["feature_reference"] = None
    new_meta = dict(meta, format=MODEL_FORMAT, trained_on=tr)
    tmp = path.with_suffix(".v4.npz")
    write_model(tmp, new_meta, est)
    # the answers before the checks: bit for bit those of the format-3 model
    old = ClearanceModel(est["classifier"], {"B": est["size_B"], "C": est["size_C"]},
                         {k: float(v) for k, v in meta["interval_log10"].items()}, trained_on=meta["trained_on"])
    new = ClearanceModel.load(tmp)
    for rec in sorted((ROOT / "recordings").glob("test*_synthetic.mcap")):
        acc, counts, rate, cpr, cfg = recording_inputs(rec)
        X, w = features(acc, counts, rate, cpr, orientation=cfg.mechanism.orientation)
        res = resolution(cfg.mechanism.orientation, w.crank_hz)
        a, b = old.identify(X, res).to_dict(), new.identify(X, res).to_dict()
        if json.dumps(a, sort_keys=True) != json.dumps(b, sort_keys=True):
            tmp.unlink()
            raise SystemExit(f"{rec.name}: the converted model answers differently: {a} vs {b}")
        print(f"{rec.name}: same answer ({a['fault']}, C {a['clearance_c_if_faulty_mm']})")
    tmp.replace(path)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped({"runs": rows, "ranges": tr["ranges"]}), indent=1) + "\n")
    print(f"wrote {path} ({MODEL_FORMAT}) and {out}")


if __name__ == "__main__":
    main()
