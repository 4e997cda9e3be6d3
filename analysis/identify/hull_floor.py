"""Turn on the hull-floor interval rule (``trained_on.interval.hull_floor``,
:func:`twin.identification.intervals.reach_hull_floor`) in a trained model file, leaving every estimator and half
width as it is: the same as training it with ``TrainOptions(hull_floor=True)`` (variant ``detwf`` of
``train_bench.py`` is ``detw`` with it), without the fit. Checks that every array member of the new file equals the
old one's, so that the point answers (location, sizes) cannot change; only the lower ends of intervals near the
smallest size trained do.

    python analysis/identify/hull_floor.py IN.npz OUT.npz
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("model")
    ap.add_argument("out")
    args = ap.parse_args()
    from twin.identification.model import ClearanceModel

    m = ClearanceModel.load(args.model)
    m.trained_on.setdefault("interval", {})["hull_floor"] = True
    m.save(args.out)
    old, new = np.load(args.model, allow_pickle=False), np.load(args.out, allow_pickle=False)
    assert set(old.files) == set(new.files)
    for k in old.files:
        if k != "model.json":
            assert old[k].dtype == new[k].dtype and np.array_equal(old[k], new[k]), k
    a, b = json.loads(str(old["model.json"])), json.loads(str(new["model.json"]))
    b["trained_on"]["interval"].pop("hull_floor")
    assert a == b, "model.json differs beyond interval.hull_floor"
    ClearanceModel.load(args.out)
    print(f"{args.out}: {args.model} with interval.hull_floor = true (estimators and half widths equal)")


if __name__ == "__main__":
    main()
