"""How the shipped model's size answer at C (or B) depends on how many crank revolutions a recording holds.

Method. ``analysis/datasets/clearance_id_length.toml``: 72 reference-engine runs of 12 s with a
clearance at C only (0.05, 0.07, 0.1 mm), x, y and z vertical, 325 and 475 motor rpm (development
speeds), contact parameters, sensor offsets, mounting and noise drawn as in the development set,
its own seed. Each run is cut into the model's windows of two steady crank revolutions
(``twin.identification.features``; back to back from the end of the steady part). The answer from the
last ``k`` windows — what a recording of 2k steady revolutions would give — is the model's own
(:meth:`twin.identification.model.ClearanceModel.identify`: location from the windows' mean class
probabilities, size the median of the windows' answers, the model's conformal 90 % interval, the
wider one where the run is below the size-resolution map).
The datasets' 3 s runs hold one window at 300-325 rpm, two at 450-475 rpm and three to four at 650-750.

With ``--joint B``: ``analysis/datasets/clearance_id_length_b.toml``, 96 reference-engine runs of 12 s with a
clearance at B only (0.02-0.1 and 1.0 mm), y or z vertical, 325 and 400 motor rpm, every nuisance drawn over the
training ranges (speed ripple, contact, guide, sensor offsets, mounting, noise, start angle), its own seed: whether
a recording as long as the bench's (10 s per speed) reads B better where the 3 s tests read it worst.

Reported per speed, clearance value and k: runs, location answered the joint (or BC), median absolute
error of the size at the joint against the size target (half the catalogue gap), the share within a factor 1.5 of
the truth, interval coverage, and the median over runs of the windows' spread (max/min of their size answers); and
per k over all runs, the share within a factor 1.5. No model is fitted here; the sets are never used for training
or for choosing the model.

Run: ``twin dataset generate analysis/datasets/clearance_id_length.toml --out DIR`` (72 runs, about
4 min on two cores), then ``python analysis/identify/recording_length.py DIR [--joint C] [--model M]
[--json OUT]`` (about 1 min); for B ``clearance_id_length_b.toml`` (96 runs, about 6 min) and ``--joint B``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from twin.provenance import stamped

KS = (1, 2, 3, 4, 7)  # windows used, from the end of the steady part


def main(argv: list[str] | None = None) -> int:
    from twin.dataset import open as open_dataset
    from twin.identification.evaluate import half_gap_mm, within_factor
    from twin.identification.inputs import dataset_features
    from twin.identification.intervals import resolution
    from twin.identification.model import ClearanceModel

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset")
    ap.add_argument("--model", default=None, help="model file (default: the shipped one)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", default=None)
    ap.add_argument("--joint", choices=("B", "C"), default="C", help="the joint whose size is read (default C)")
    args = ap.parse_args(argv)
    if args.model is None:
        from twin.identification.model import default_model_path

        args.model = str(default_model_path())
    model = ClearanceModel.load(args.model)
    ds = open_dataset(args.dataset)
    X, rows, owner, skipped = dataset_features(ds, ("train", "val", "test"), args.workers, model.hop_revs)
    owner = np.asarray(owner)
    J, j = args.joint, args.joint.lower()
    per: dict[tuple[float, float, int], list[dict]] = {}
    for i, r in enumerate(rows):
        Xr = X[owner == i]
        c = r[f"clearance_{j}_mm"]
        if c <= 0:
            continue
        logs = model.size[J].predict(Xr)
        for k in KS:
            if k > len(Xr):
                continue
            a = model.identify(Xr[-k:], resolution(r["orientation"], r["crank_hz"]))
            est = a.joint(J).size_if_faulty_mm
            lo, hi = a.joint(J).interval_if_faulty_mm
            per.setdefault((r["motor_rpm"], c, k), []).append(
                {"located": a.joint(J).faulty, "err": abs(est - c), "within": within_factor(est, c),
                 "covered": lo <= c <= hi, "spread": float(10 ** (logs[-k:].max() - logs[-k:].min())),
                 "orientation": r["orientation"]})
    out = {"dataset": str(args.dataset), "model": str(args.model), "joint": J, "runs": len(rows),
           "runs_left_out": skipped,
           "windows_per_run": {f"{rpm:g}": sorted({int((owner == i).sum()) for i, r in enumerate(rows)
                                                   if r["motor_rpm"] == rpm})
                               for rpm in sorted({r["motor_rpm"] for r in rows})},
           "cells": []}
    print(f"{len(rows)} runs ({len(skipped)} left out), windows per run by speed: {out['windows_per_run']}")
    print()
    print(f"| motor rpm | clearance {J} mm | windows | runs | located {J} | median abs error mm | target mm | meets "
          "| within ×1.5 | interval coverage | windows' spread (max/min) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for (rpm, c, k), v in sorted(per.items()):
        e = float(np.median([x["err"] for x in v]))
        cell = {"motor_rpm": rpm, f"clearance_{j}_mm": c, "windows": k, "runs": len(v),
                "located": float(np.mean([x["located"] for x in v])), "median_abs_error_mm": e,
                "target_mm": half_gap_mm(c), "meets_target": e <= half_gap_mm(c),
                "within_factor_1_5": float(np.mean([x["within"] for x in v])),
                "interval_coverage": float(np.mean([x["covered"] for x in v])),
                "spread": float(np.median([x["spread"] for x in v]))}
        out["cells"].append(cell)
        print(f"| {rpm:g} | {c:g} | {k} | {len(v)} | {cell['located'] * 100:.0f} % | {e:.3g} | {cell['target_mm']:.3g} "
              f"| {'yes' if cell['meets_target'] else 'no'} | {cell['within_factor_1_5'] * 100:.0f} % | "
              f"{cell['interval_coverage'] * 100:.0f} % | {cell['spread']:.2f} |")
    out["within_factor_1_5_by_windows"] = {}
    for k in KS:
        v = [x["within"] for (_, _, kk), xs in per.items() if kk == k for x in xs]
        if v:
            out["within_factor_1_5_by_windows"][str(k)] = {"runs": len(v), "share": float(np.mean(v))}
    print()
    print("within ×1.5 over all runs, by windows used: " + ", ".join(
        f"{k}: {s['share'] * 100:.1f} % of {s['runs']}" for k, s in out["within_factor_1_5_by_windows"].items()))
    if args.json:
        from twin.util import atomic_write_json

        atomic_write_json(Path(args.json), stamped(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
