"""Train the whole-bench clearance identification (B, C and the slider guide G) and choose it on the development sets.

Steps (plain ``twin`` commands and :func:`twin.identification.training.train`):

1. the training sets ``clearance_id_bench_motor.toml`` (reference engine, motor speed loop and V-belt with its
   placeholders drawn), ``clearance_id_bench_pid.toml`` (reference, crank PID with ripple) and
   ``clearance_id_bench_mujoco.toml`` (MuJoCo, motor + V-belt), their second sets (``_motor2``, ``_pid2``) and the
   third (``_motor3``: y or z vertical only, ``_pid3``, ``_mujoco2``: added where the development misses gathered),
   and the development sets
   ``clearance_id_bench_dev_{motor,pid,mujoco}.toml``: ``twin dataset generate SPEC --out WORK/NAME --workers N``
   (skipped where the folder is complete);
2. the window features of the training runs, computed once; each variant (``--variants``) trained on them
   (:class:`twin.identification.training.TrainOptions`), saved to ``WORK/bench_VARIANT.npz``, its wall time printed;
3. each variant, and the previous default model (``--baseline``), answered on the development sets through the
   recording answer path (``analysis/identify/bench_eval.py``), the figures printed and written to
   ``WORK/dev_VARIANT.json``;
   (variant ``det``: a presence detector per location, ``TrainOptions(location="detectors")``; the development set
   of guide play beyond the trained range, ``clearance_id_bench_dev_out_guide.toml``, is answered apart with
   ``bench_eval.py``: its runs are out of range and count for the warned share only);
4. ``--save VARIANT:PATH`` copies that variant's model file to PATH (the choice, made on step 3's figures only).

Run: ``python analysis/identify/train_bench.py --work DIR [--workers 2] [--variants base runs] [--save base:PATH]``.
The whole-bench fresh look (``analysis/identify/FRESH_TEST_WHOLE_BENCH.md``) is not run here.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TRAIN = ("clearance_id_bench_motor", "clearance_id_bench_pid", "clearance_id_bench_mujoco", "clearance_id_bench_motor2",
         "clearance_id_bench_pid2", "clearance_id_bench_motor3", "clearance_id_bench_pid3", "clearance_id_bench_mujoco2")
DEV = ("clearance_id_bench_dev_motor", "clearance_id_bench_dev_pid", "clearance_id_bench_dev_mujoco")
#: the variants tried on the development sets (TrainOptions fields)
VARIANTS = {
    "base": dict(interval_folds="runs"),
    "speed": dict(interval_folds="speed"),
    "median": dict(interval_folds="runs", size_regressor="median"),
    "nosplit": dict(interval_folds="runs", fault_split=False, size_band_mm=None),
    "det": dict(interval_folds="runs", location="detectors"),
    "detw": dict(interval_folds="runs", location="detectors", size_weights="runs"),
    "detwf": dict(interval_folds="runs", location="detectors", size_weights="runs", hull_floor=True),
    "detwc": dict(interval_folds="runs", location="detectors", size_weights="runs", size_context=True),
}


def generate(work: Path, name: str, workers: str) -> Path:
    d = work / name
    subprocess.run([str(Path(sys.executable).parent / "twin"), "dataset", "generate", f"analysis/datasets/{name}.toml", "--out",
                    str(d), "--workers", workers, "--no-progress"], cwd=ROOT, check=True)
    return d


def dev_eval(model: Path, work: Path, out: Path, workers: str) -> dict:
    dev = [str(work / d) for d in DEV if (work / d / "runs.parquet").is_file()]
    subprocess.run([sys.executable, str(ROOT / "analysis" / "identify" / "bench_eval.py"), str(model),
                    *dev, "--out", str(out), "--workers", workers], check=True,
                   stdout=subprocess.DEVNULL)
    return json.loads(out.read_text())


def cached_features(d: Path, workers: int) -> tuple:
    """:func:`twin.identification.inputs.dataset_features` of one dataset's train and val runs, kept beside it
    (``features_cache.npz`` + ``.json``, plain arrays and JSON; keyed by its manifest's digest) and read back."""
    import hashlib

    import numpy as np

    from twin.dataset import open as open_dataset
    from twin.identification.inputs import dataset_features
    from twin.provenance import stamped

    ds = open_dataset(d)
    key = hashlib.sha256((d / "runs.parquet").read_bytes()).hexdigest()
    npz, js = d / "features_cache.npz", d / "features_cache.json"
    if npz.is_file() and js.is_file():
        meta = json.loads(js.read_text())
        if meta["key"] == key:
            z = np.load(npz, allow_pickle=False)
            return z["X"], meta["rows"], z["owner"].tolist(), meta["skipped"], [ds]
    X, rows, owner, skipped = dataset_features(ds, ("train", "val"), workers)
    rows = [dict(r, dataset=ds.info["name"]) for r in rows]
    np.savez(npz, X=X, owner=np.asarray(owner))
    js.write_text(json.dumps(stamped({"key": key, "rows": rows, "skipped": skipped}), default=float))
    return X, json.loads(json.dumps(rows, default=float)), list(owner), skipped, [ds]


def summary(rep: dict) -> str:
    f = rep["all"]
    s = lambda d: "-" if d["share"] is None else f"{100 * d['share']:.0f}% ({d['hits']}/{d['n']})"  # noqa: E731
    parts = [f"location {s(f['location'])}", f"refused {s(f['refused_of_turning'])}",
             "recall " + " ".join(f"{c}:{s(v)}" for c, v in f["recall"].items()),
             "presence " + " ".join(f"{j}:{s(v)}" for j, v in f["presence_recall"].items()),
             "x1.5 " + " ".join(f"{j}:{s(v)}" for j, v in f["within_1_5"].items()),
             "cover " + " ".join(f"{j}:{s(v)}" for j, v in f["coverage"].items()), f"warned {s(f['warned'])}"]
    return "\n    ".join(parts)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", required=True, help="folder of the datasets and the variants' models")
    ap.add_argument("--workers", default="2")
    ap.add_argument("--variants", nargs="+", default=["base"], choices=sorted(VARIANTS))
    ap.add_argument("--baseline", default=str(ROOT / "twin" / "data" / "identify_default.npz"),
                    help="the model to compare with on the development sets ('' for none)")
    ap.add_argument("--save", metavar="VARIANT:PATH", help="copy the chosen variant's model file to PATH")
    ap.add_argument("--no-generate", action="store_true", help="use the dataset folders as they are")
    ap.add_argument("--cache-only", action="store_true", help="only compute and keep the complete training sets' features")
    args = ap.parse_args()
    from twin.identification.inputs import pool_features
    from twin.identification.training import TrainOptions, train

    work = Path(args.work)
    dirs = [work / n for n in TRAIN] if args.no_generate else [generate(work, n, args.workers) for n in TRAIN]
    if not args.no_generate:
        for n in DEV:
            generate(work, n, args.workers)
    dirs = [d for d in dirs if (d / "runs.parquet").is_file()]  # complete datasets only
    t0 = time.perf_counter()
    feats = pool_features([cached_features(d, int(args.workers)) for d in dirs])
    if args.cache_only:
        print(f"features of {', '.join(d.name for d in dirs)} kept: {time.perf_counter() - t0:.0f} s")
        return
    t_feat = time.perf_counter() - t0
    print(f"features of {len(feats[1])} runs ({len(feats[0])} windows, {len(feats[3])} runs without windows) from "
          f"{', '.join(d.name for d in dirs)}: {t_feat:.0f} s on {args.workers} workers", flush=True)
    for v in args.variants:
        t1 = time.perf_counter()
        model, tr = train(dirs, TrainOptions(workers=int(args.workers), **VARIANTS[v]), features=feats)
        fit = time.perf_counter() - t1
        path = work / f"bench_{v}.npz"
        model.save(path)
        print(f"variant {v}: fit {fit:.0f} s (+ features {t_feat:.0f} s), joints {model.joints}, classes "
              f"{tr['classes']}", flush=True)
        rep = dev_eval(path, work, work / f"dev_{v}.json", args.workers)
        print(f"  dev {v}:\n    {summary(rep)}", flush=True)
    if args.baseline:
        rep = dev_eval(Path(args.baseline), work, work / "dev_baseline.json", args.workers)
        print(f"  dev baseline ({args.baseline}):\n    {summary(rep)}", flush=True)
    if args.save:
        v, dest = args.save.split(":", 1)
        shutil.copyfile(work / f"bench_{v}.npz", dest)
        print(f"saved {v} to {dest}")


if __name__ == "__main__":
    main()
