"""Development probe of the size regressors alone: how the windows are weighted in the fit, and averaging the
regressors of several seeds, judged on the in-range development sets (after the fourth look).

Method. The shipped model's eight training sets (``nuisance_study.py``'s variant ``slow-b-bands``), read from the
study's feature cache (windows back to back), fit one size regressor per joint (``SIZE_REGRESSORS["mean"]`` of
:mod:`twin.identification.model`, the shipped settings) in each of these ways:

* ``shipped``: every window weighs one (a run at 765 motor rpm brings four windows, one at 340 rpm one);
* ``run``: each window weighs 1 / (its run's windows), so that every training run counts once, as every recording
  does in the targets;
* ``sqrt``: 1 / sqrt(its run's windows), between the two;
* ``bag3``: three regressors of seeds 0, 1, 2, their answers averaged per window.

Each development run's answer is the median over its windows (as :func:`twin.identification.model.size_answer`);
printed: per joint and way, the share of runs with a clearance at that joint, where the size-resolution map
resolves it, answered within a factor 1.5 of the truth, on each development set, and on the slowest speed of
each. No interval and no location model is fitted: this says what a change of the regressors alone would do.

Run: ``python analysis/identify/size_fit_probe.py [--work DIR]`` (the feature cache of ``nuisance_study.py``;
about 3 min on two cores).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from nuisance_study import ROOT, VARIANTS, cached_features  # noqa: E402

from twin.identification.inputs import pool_features
from twin.identification.intervals import resolution
from twin.identification.training import SIZE_REGRESSORS

DEV = ("clearance_id_fresh4_in", "clearance_id_fresh3_in", "clearance_id_fresh2_in", "clearance_id_fresh_in",
       "clearance_id_nuisance_dev")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", default=str(ROOT.parent / "identify_work"))
    args = ap.parse_args()
    from sklearn.ensemble import HistGradientBoostingRegressor

    work = Path(args.work)
    sets = VARIANTS["slow-b-bands"][0]
    X, rows, owner, _, _ = pool_features([cached_features(work, n, ("train", "val"), 2) for n in sets])
    owner = np.asarray(owner)
    nwin = np.bincount(owner)
    devs = {d: cached_features(work, d, ("train", "val", "test"), 2) for d in DEV}
    devs = {d: f for d, f in devs.items() if f is not None}
    for j in ("B", "C"):
        key = f"clearance_{j.lower()}_mm"
        truth = np.array([rows[i][key] for i in owner], float)
        sel = truth > 0
        weights = {"shipped": np.ones(len(X)), "run": 1.0 / nwin[owner], "sqrt": 1.0 / np.sqrt(nwin[owner])}
        regs = {}
        for way, w in weights.items():
            reg = HistGradientBoostingRegressor(**SIZE_REGRESSORS["mean"], min_samples_leaf=20, random_state=0)
            regs[way] = [reg.fit(X[sel], np.log10(truth[sel]), sample_weight=w[sel] / w[sel].mean())]
        regs["bag3"] = regs["shipped"] + [
            HistGradientBoostingRegressor(**SIZE_REGRESSORS["mean"], min_samples_leaf=20, random_state=s)
            .fit(X[sel], np.log10(truth[sel])) for s in (1, 2)]
        for way, rs in regs.items():
            cells = []
            for d, (Xd, rd, od, _, _) in devs.items():
                od = np.asarray(od)
                pred = np.mean([r.predict(Xd) for r in rs], axis=0)
                ok, slow = [], []
                low = min(r["motor_rpm"] for r in rd)
                for i, r in enumerate(rd):
                    if r[key] <= 0 or not resolution(r["orientation"], r["crank_hz"])[j]:
                        continue
                    good = abs(float(np.median(pred[od == i])) - math.log10(r[key])) <= math.log10(1.5)
                    ok.append(good)
                    if r["motor_rpm"] == low:
                        slow.append(good)
                at_low = f"{100 * np.mean(slow):.0f}" if slow else "none resolved"
                cells.append(f"{d.removeprefix('clearance_id_')} {100 * np.mean(ok):.1f} ({low:g} rpm {at_low})")
            print(f"{j} {way:8s} " + " | ".join(cells), flush=True)


if __name__ == "__main__":
    main()
