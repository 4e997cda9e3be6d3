"""Make the clearance-identification model that ships with twin, and its evaluation report.

Steps (each is a plain ``twin`` command; a step whose output exists is skipped, so the script
resumes):

1. ``twin dataset generate analysis/datasets/clearance_id.toml --out WORK/clearance_id``, the same for
   ``clearance_id_dense.toml``, ``clearance_id_start.toml``, ``clearance_id_top.toml`` and
   ``clearance_id_band.toml``: the training data, MuJoCo twin, runs of 3 s (400: the catalogue at five
   speeds; 400: clearances drawn continuously at 15 speeds; 400: the same at 17 speeds to 800 rpm with the
   crank's start angle drawn; 240: y vertical at 737.5-800 rpm, start drawn; and 120 runs with x vertical
   at 312.5 rpm, the slider's free-flight speed, healthy, B or C, for the location model only);
2. ``twin identify train WORK/clearance_id WORK/clearance_id_dense WORK/clearance_id_start WORK/clearance_id_top
   --location-only WORK/clearance_id_band --interval-folds speed --out twin/data/identify_default.npz``
   (train and val splits, pooled; the intervals calibrated on answers at speeds left out);
3. ``twin dataset generate analysis/datasets/clearance_id_test.toml --out WORK/clearance_id_test``,
   ``clearance_id_test_b.toml`` and ``clearance_id_test_c.toml``: the test data (200 + 400 + 400 runs),
   reference engine, other seeds, unseen speeds and clearance value;
4. ``twin identify evaluate MODEL WORK/clearance_id_test WORK/clearance_id_test_b WORK/clearance_id_test_c
   --out analysis/results/identify``: the report of the pooled test sets (confusion matrix, recall, size
   errors by clearance and speed with bootstrap intervals, interval coverage, plots); the same for
   the first test set alone in ``analysis/results/identify/test_a`` (the set of looks 1-7) and for the
   second extension alone in ``analysis/results/identify/test_c`` (runs first evaluated at look 9); and
   the answers on the sample recordings in ``recordings/`` (``samples.json``).

Run: ``python analysis/identify/train_default.py [--work DIR] [--workers N]`` (45-55 min on two
cores, most of it the MuJoCo training data). The datasets stay in ``--work`` (default
``../identify_work`` beside the checkout; about 17 GB), not in the repository.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MODEL = ROOT / "twin" / "data" / "identify_default.joblib"
REPORT = ROOT / "analysis" / "results" / "identify"


def twin(*args: str) -> None:
    cmd = [sys.executable, "-m", "twin.cli", *args]
    print("$ twin " + " ".join(args), flush=True)
    subprocess.run(cmd, check=True, cwd=ROOT)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", default=str(ROOT.parent / "identify_work"), help="folder of the datasets")
    ap.add_argument("--workers", default=str(os.cpu_count() or 1))
    ap.add_argument("--retrain", action="store_true", help="train again even if the model exists")
    args = ap.parse_args()
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    train_ds = [work / "clearance_id", work / "clearance_id_dense", work / "clearance_id_start", work / "clearance_id_top"]
    location_ds = [work / "clearance_id_band"]
    test_ds = [work / "clearance_id_test", work / "clearance_id_test_b", work / "clearance_id_test_c"]
    t = time.perf_counter()
    for d in train_ds + location_ds:
        twin("dataset", "generate", f"analysis/datasets/{d.name}.toml", "--out", str(d), "--workers", args.workers,
             "--no-progress")
    print(f"training data: {time.perf_counter() - t:.0f} s (0 if it existed)")
    if args.retrain or not MODEL.exists():
        twin("identify", "train", *map(str, train_ds), "--location-only", *map(str, location_ds),
             "--interval-folds", "speed", "--out", str(MODEL), "--workers", args.workers)
    t = time.perf_counter()
    for d in test_ds:
        twin("dataset", "generate", f"analysis/datasets/{d.name}.toml", "--out", str(d), "--workers",
             args.workers, "--no-progress")
    print(f"test data: {time.perf_counter() - t:.0f} s (0 if it existed)")
    REPORT.mkdir(parents=True, exist_ok=True)
    twin("identify", "evaluate", str(MODEL), *map(str, test_ds), "--out", str(REPORT), "--workers", args.workers)
    for d, sub in ((test_ds[0], "test_a"), (test_ds[2], "test_c")):
        twin("identify", "evaluate", str(MODEL), str(d), "--out", str(REPORT / sub), "--workers", args.workers)
    samples = {}
    for rec in sorted((ROOT / "recordings").glob("*.mcap")):
        out = REPORT / f".{rec.stem}.json"
        r = subprocess.run([sys.executable, "-m", "twin.cli", "identify", "clearance", str(rec.relative_to(ROOT)), "--json", str(out)],
                           cwd=ROOT, capture_output=True, text=True)
        if r.returncode == 0:
            a = json.loads(out.read_text())
            out.unlink()
            samples[rec.name] = {k: a[k] for k in ("fault", "probabilities", "clearance_b_mm", "clearance_b_interval_mm",
                                                 "clearance_c_mm", "clearance_c_interval_mm", "warnings", "seconds")}
            samples[rec.name]["evidence"] = {k: a["evidence"][k] for k in ("windows", "revolutions", "crank_hz")}
        else:
            samples[rec.name] = {"refused": r.stderr.strip()}
    (REPORT / "samples.json").write_text(json.dumps(samples, indent=2) + "\n")
    print(json.dumps(samples, indent=2))


if __name__ == "__main__":
    main()
