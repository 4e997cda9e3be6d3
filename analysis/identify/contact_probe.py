"""Can the identification features see the contact's parameters? A probe for an out-of-range check.

Question. The fresh tests' "parameters out" parts (contact stiffness ×0.25-0.4, restitution 0.65-0.85, contact
friction 0.005-0.015: all outside the training ranges ×0.5-2, 0.3-0.6, 0.02-0.10) are answered without a warning:
the measured quantities (speed, ripple, noise, orientation) are in range, and the feature-space distance sees
nothing. A warning would need an estimate of the contact parameters from the recording.

Method. Per run, the median over its windows of the 178 features (``twin-identify-features/6``, the development
study's cache ``WORK/features/NAME.npz``). On the faulty runs of the seven training sets of the third round, two
regressors of each parameter (log stiffness scale, restitution, log contact friction): gradient-boosted trees
(400 iterations, 31 leaves) and ridge regression on standardized features (regularization by cross-validation; a
linear model extrapolates where trees cannot). Printed, for the in-range development sets and the parameters-out
sets: the correlation of each estimate with the truth, and the 10/50/90 % quantiles of the truth and of each
estimate.

Result (development data only; 2026-11-27): correlations 0.20-0.33 (stiffness), below 0.13 (restitution),
0.04-0.48 (friction) on the in-range sets, and on the third fresh test's parameters-out runs the estimates'
quantiles lie in the middle of the training range (stiffness estimate median ×1.0 for a truth of ×0.32). The
features were built to be independent of the contact law (``twin.identification.features``), and they are: no
warning can rest on them. A contact-parameter check would need features of the impacts' shape (duration,
spectral content above the sensors' resonance), which the engines and a bench do not share.

Run: ``python analysis/identify/contact_probe.py [--work DIR]`` (needs scikit-learn, the ``train`` extra, and the
feature cache of ``analysis/identify/nuisance_study.py``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from nuisance_study import ROOT, VARIANTS  # noqa: E402

TRAIN = VARIANTS["small-b-mean-engine"][0]  # the seven training sets of the third round
PROBED = ("clearance_id_nuisance_dev", "clearance_id_fresh3_in", "clearance_id_fresh3_out_params",
          "clearance_id_nuisance_ref_soft")
#: parameter (a dataset factor) and the transform it is regressed in
PARAMETERS = {"stiffness_scale": np.log, "restitution": lambda x: x, "mu0": np.log}


def run_medians(work: Path, name: str) -> tuple[np.ndarray, list[dict]]:
    """Per-run median feature vectors of a cached dataset and its rows."""
    z = np.load(work / "features" / f"{name}.npz", allow_pickle=False)
    rows = json.loads((work / "features" / f"{name}.json").read_text())["rows"]
    X, owner = z["X"], z["owner"]
    return np.array([np.median(X[owner == i], axis=0) for i in range(len(rows))]), rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", default=str(ROOT.parent / "identify_work"))
    args = ap.parse_args()
    from sklearn.ensemble import HistGradientBoostingRegressor
    from sklearn.linear_model import RidgeCV
    from sklearn.preprocessing import StandardScaler

    work = Path(args.work)
    data = {n: run_medians(work, n) for n in TRAIN + PROBED if (work / "features" / f"{n}.npz").is_file()}
    missing = [n for n in TRAIN if n not in data]
    if missing:
        raise SystemExit(f"--work: no feature cache for {', '.join(missing)} (run nuisance_study.py first)")
    Xtr = np.vstack([data[n][0] for n in TRAIN])
    rows = [r for n in TRAIN for r in data[n][1]]
    faulty = np.array([r["fault"] != "none" for r in rows])
    for k, tf in PARAMETERS.items():
        y = tf(np.array([r.get(f"factor_{k}", np.nan) for r in rows], float))
        ok = np.isfinite(y) & faulty
        trees = HistGradientBoostingRegressor(max_iter=400, learning_rate=0.05, max_leaf_nodes=31,
                                              random_state=0).fit(Xtr[ok], y[ok])
        scale = StandardScaler().fit(Xtr[ok])
        ridge = RidgeCV(alphas=np.logspace(-2, 3, 12)).fit(scale.transform(Xtr[ok]), y[ok])
        print(f"{k} (training runs {ok.sum()}, truth {np.min(y[ok]):.2f} to {np.max(y[ok]):.2f} after transform)")
        for n in PROBED:
            if n not in data:
                continue
            X, R = data[n]
            yy = tf(np.array([r.get(f"factor_{k}", np.nan) for r in R], float))
            m = np.isfinite(yy) & np.array([r["fault"] != "none" for r in R])
            pt, pr = trees.predict(X[m]), ridge.predict(scale.transform(X[m]))
            q = lambda v: np.round(np.percentile(v, [10, 50, 90]), 2)  # noqa: E731
            print(f"  {n:34s} runs {m.sum():4d}  corr trees {np.corrcoef(pt, yy[m])[0, 1]:5.2f} ridge "
                  f"{np.corrcoef(pr, yy[m])[0, 1]:5.2f}  truth {q(yy[m])} trees {q(pt)} ridge {q(pr)}")


if __name__ == "__main__":
    main()
