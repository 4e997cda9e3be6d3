"""The rigid-rod check of the identification's training-data check (``twin.identification.ranges.RIGID_ROD_RATIO_MAX``).

On a rigid rod the two longitudinal accelerometers, AC1 at B and AC4 at C, read the same acceleration above 800 Hz:
the feature ``ratio_band_AC1_AC4`` (log10 of their 0.8-6 kHz band energies) stays near 0. This script measures

1. that feature (each run's median over its windows) on the whole-bench training runs and the development runs
   (dataset folders of ``analysis/identify/train_bench.py``; the training sets' kept features are read where
   present);
2. the same on bench recordings of the flexible structure (``structure.mode = "flexible"``) made with
   ``twin record`` (:data:`FLEXIBLE`: x/y/z vertical, 300-700 rpm, both engines), each answered with the shipped
   ``bench`` model through ``twin identify clearance``'s path: location, probability, warnings.

    python analysis/identify/rigid_rod_check.py --work DIR [--out analysis/results/identify/rigid_rod_check.json]

``--work``: the folder holding the datasets (``clearance_id_bench_*``); the flexible recordings are written to
``DIR/flexible/``. Writes a stamped JSON report.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "analysis" / "identify"))
from train_bench import DEV, TRAIN  # noqa: E402

#: the flexible-structure recordings: name -> twin record options (3 s each)
FLEXIBLE = {
    "flex1": ["--clearance-b", "0.1", "--orientation", "y", "--speed", "500", "--engine", "reference"],
    "flex2": ["--clearance-c", "0.5", "--orientation", "z", "--speed", "650", "--engine", "reference"],
    "flex3": ["--orientation", "x", "--speed", "400", "--engine", "reference"],
    "flex4": ["--clearance-b", "0.05", "--orientation", "y", "--speed", "550", "--engine", "mujoco"],
    "flex5": ["--clearance-b", "0.5", "--clearance-c", "0.1", "--orientation", "z", "--speed", "300",
              "--engine", "mujoco"],
    "flex6": ["--orientation", "y", "--speed", "700", "--engine", "reference"],
    "flex7": ["--clearance-c", "0.1", "--orientation", "x", "--speed", "600", "--engine", "mujoco"],
    "flex8": ["--clearance-b", "0.02", "--clearance-c", "0.05", "--orientation", "z", "--speed", "450",
              "--engine", "reference"],
}


def run_ratios(d: Path, splits: tuple[str, ...], index: int) -> list[float]:
    """Each ok run's median over its windows of feature ``index``, from the kept features
    (``features_cache.npz``) where present, else computed."""
    cache = d / "features_cache.npz"
    if cache.is_file():
        z = np.load(cache, allow_pickle=False)
        X, owner = z["X"], z["owner"]
    else:
        from twin.dataset import open as open_dataset
        from twin.identification.inputs import dataset_features

        X, _, owner, _ = dataset_features(open_dataset(d), splits, 2)
        owner = np.asarray(owner)
    return [float(np.median(X[owner == r, index])) for r in np.unique(owner)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", required=True)
    ap.add_argument("--out", default=str(ROOT / "analysis" / "results" / "identify" / "rigid_rod_check.json"))
    args = ap.parse_args()
    from twin.identification.features import feature_names
    from twin.identification.model import ClearanceModel, identify_recording, shipped_model_path
    from twin.identification.ranges import RIGID_ROD_FEATURE, RIGID_ROD_RATIO_MAX
    from twin.provenance import stamped

    work = Path(args.work)
    i = feature_names().index(RIGID_ROD_FEATURE)
    report: dict = {"feature": RIGID_ROD_FEATURE, "limit_log10": RIGID_ROD_RATIO_MAX, "sets": {}, "flexible": []}
    for names, splits in ((TRAIN, ("train", "val")), (DEV, ("train", "val", "test"))):
        for n in names:
            if (work / n / "runs.parquet").is_file():
                r = np.abs(run_ratios(work / n, splits, i))
                report["sets"][n] = {"runs": int(r.size), "largest_abs": float(r.max()),
                                     "p99_abs": float(np.quantile(r, 0.99)),
                                     "beyond_limit": int(np.sum(r > RIGID_ROD_RATIO_MAX))}
                print(f"{n}: {r.size} runs, largest |ratio| {r.max():.3f}, beyond {RIGID_ROD_RATIO_MAX}: "
                      f"{int(np.sum(r > RIGID_ROD_RATIO_MAX))}", flush=True)
    model = ClearanceModel.load(shipped_model_path("bench"))
    (work / "flexible").mkdir(parents=True, exist_ok=True)
    twin = str(Path(sys.executable).parent / "twin")
    for name, opts in FLEXIBLE.items():
        rec = work / "flexible" / f"{name}.mcap"
        if not rec.is_file():
            subprocess.run([twin, "record", "--structure", "flexible", "--duration", "3", *opts, "--out", str(rec),
                            "--no-progress"], check=True, stdout=subprocess.DEVNULL)
        a = identify_recording(model, rec)
        rr = a.evidence.training_data_check.rigid_rod_ratio_log10
        row = {"name": name, "options": " ".join(opts), "ratio_log10": rr.measured if rr else None,
               "fault": a.fault, "probability": a.probabilities[a.fault], "warnings": list(a.warnings),
               "rigid_rod_warned": any("rigid rod" in w for w in a.warnings)}
        report["flexible"].append(row)
        print(f"{name} ({row['options']}): ratio {row['ratio_log10']}, answered {a.fault} p={row['probability']:.2f}, "
              f"rigid-rod warning: {row['rigid_rod_warned']}", flush=True)
    report["flexible_warned"] = sum(r["rigid_rod_warned"] for r in report["flexible"])
    Path(args.out).write_text(json.dumps(stamped(report), indent=1))
    print(f"flexible recordings warned: {report['flexible_warned']}/{len(FLEXIBLE)}; wrote {args.out}")


if __name__ == "__main__":
    main()
