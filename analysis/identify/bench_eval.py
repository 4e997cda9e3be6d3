"""Whole-bench evaluation of an identification model: every run of one or more datasets answered through the
answer path of a recording (:func:`twin.identification.model.identify_inputs`: the same refusals, warnings and
interval rules as ``twin identify clearance``), scored against the targets of the whole-bench fresh look
(analysis/identify/FRESH_TEST_WHOLE_BENCH.md):

* location accuracy over the answered in-range runs, recall per class (none, B, C, BC, G, BG, CG, BCG) and per
  location (whether a location with play is named);
* per joint (B, C, G): sizes within x1.5 of the truth where the size is resolved (G: no size-resolution map, every
  run), and the 90 % interval's coverage, over the answered runs with play at that joint;
* refusals: the share of the runs that turn (two or more whole crank turns in the recording) the answer refuses;
* out-of-range parts: the share of answered runs with at least one warning.

    python analysis/identify/bench_eval.py MODEL.npz DATASET [DATASET ...] --out REPORT.json [--out-of-range]

Writes a JSON report (every run's answer beside its labels, and the figures) and prints the figures.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

ACC = tuple(f"AC{i}" for i in range(1, 7))
TARGETS = {"location": 0.95, "recall": 0.90, "within_1_5": 0.85, "coverage": 0.85, "refused": 0.05, "warned": 0.90}


def _answer(task: tuple[str, str, str, float, dict[str, Any]]) -> dict[str, Any]:
    """One run's answer through the recording path, or its refusal, beside its labels."""
    from twin.dataset.storage import read_columns, read_meta
    from twin.errors import TwinError
    from twin.identification.model import ClearanceModel, identify_inputs, label_mm

    model_path, path, orientation, cpr, row = task
    model = _MODELS.get(model_path) or _MODELS.setdefault(model_path, ClearanceModel.load(model_path))
    meta = read_meta(path)
    cols = read_columns(path, [f"meas_{s}" for s in ACC] + ["encoder_counts"])
    counts = cols["encoder_counts"]
    turns = float((np.nanmax(counts) - np.nanmin(counts)) / cpr)
    out = {"run_id": row["run_id"], "dataset": row["dataset"], "true_fault": row["fault"],
           "orientation": orientation, "motor_rpm": row.get("motor_rpm"), "turns": turns,
           "truth_mm": {j: label_mm(row, j) for j in ("B", "C", "G")},
           "drive": row.get("factor_drive_mode") or "pid", "engine": row.get("engine")}
    try:
        a = identify_inputs(model, {s: cols[f"meas_{s}"] for s in ACC}, counts, float(meta["rate_hz"]), cpr,
                            orientation=orientation, source=row["run_id"])
    except TwinError as err:
        return out | {"refused": True, "reason": str(err)}
    return out | {"refused": False, "fault": a.fault, "probabilities": dict(a.probabilities),
                  "warnings": list(a.warnings), "seconds": a.seconds,
                  "joints": {j.joint: {"faulty": j.faulty, "size_mm": j.size_if_faulty_mm,
                                       "interval_mm": list(j.interval_if_faulty_mm),
                                       "resolved": j.size_resolved} for j in a.joints}}


_MODELS: dict[str, Any] = {}


def within(a: float, b: float, factor: float = 1.5) -> bool:
    return a > 0 and b > 0 and abs(math.log(a / b)) <= math.log(factor)


def _share(xs: list[bool]) -> dict[str, Any]:
    return {"share": float(np.mean(xs)) if xs else None, "n": len(xs), "hits": int(sum(xs))}


def figures(preds: list[dict[str, Any]], joints: tuple[str, ...]) -> dict[str, Any]:
    """The figures of the fresh look's targets over ``preds``."""
    turning = [p for p in preds if p["turns"] >= 2.0]
    answered = [p for p in preds if not p["refused"]]
    classes = sorted({p["true_fault"] for p in answered}, key=["none", "B", "C", "BC", "G", "BG", "CG", "BCG"].index)
    out: dict[str, Any] = {
        "runs": len(preds), "turning": len(turning), "answered": len(answered),
        "refused_of_turning": _share([p["refused"] for p in turning]),
        "not_turning": len(preds) - len(turning),
        "location": _share([p["fault"] == p["true_fault"] for p in answered]),
        "recall": {c: _share([p["fault"] == c for p in answered if p["true_fault"] == c]) for c in classes},
        "presence_recall": {j: _share([j in p["fault"] for p in answered if j in p["true_fault"]]) for j in "BCG"},
        "false_presence": {j: _share([j in p["fault"] for p in answered if j not in p["true_fault"]]) for j in "BCG"},
        "warned": _share([bool(p["warnings"]) for p in answered]),
        "within_1_5": {}, "coverage": {},
    }
    for j in joints:
        faulty = [p for p in answered if p["truth_mm"][j] > 0 and j in p["joints"]]
        res = [p for p in faulty if p["joints"][j]["resolved"] is not False]
        out["within_1_5"][j] = _share([within(p["joints"][j]["size_mm"], p["truth_mm"][j]) for p in res])
        out["coverage"][j] = _share([p["joints"][j]["interval_mm"][0] <= p["truth_mm"][j] <=
                                     p["joints"][j]["interval_mm"][1] for p in faulty])
    secs = [p["seconds"] for p in answered if p.get("seconds") is not None]
    out["answer_seconds_max"] = max(secs) if secs else None
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("model")
    ap.add_argument("datasets", nargs="+")
    ap.add_argument("--out", required=True)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    from twin.dataset import open as open_dataset
    from twin.identification.model import ClearanceModel

    t0 = time.perf_counter()
    model = ClearanceModel.load(args.model)
    tasks = []
    for d in args.datasets:
        ds = open_dataset(d)
        cpr = float(ds.info.get("encoder_counts_per_rev") or 32768)
        for r in ds.rows():
            if r.get("status", "ok") == "ok":
                tasks.append((args.model, str(ds.path / r["file"]), r["orientation"], cpr,
                              dict(r, dataset=ds.info["name"], engine=ds.info["identity"]["engine"])))
    with ProcessPoolExecutor(max_workers=args.workers) as ex:
        preds = list(ex.map(_answer, tasks, chunksize=2))
    report = {"model": args.model, "model_dataset": model.trained_on.get("dataset"), "datasets": args.datasets,
              "targets": TARGETS, "all": figures(preds, model.joints),
              "by_dataset": {d: figures([p for p in preds if p["dataset"] == d], model.joints)
                             for d in dict.fromkeys(p["dataset"] for p in preds)},
              "seconds": time.perf_counter() - t0, "predictions": preds}
    from twin.provenance import stamped

    Path(args.out).write_text(json.dumps(stamped(report), indent=1, default=float))
    f = report["all"]
    print(json.dumps({k: v for k, v in f.items()}, indent=1, default=float))
    print(f"wrote {args.out} ({report['seconds']:.0f} s)", file=sys.stderr)


if __name__ == "__main__":
    main()
