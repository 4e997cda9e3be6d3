"""Why is B's size weakest at slow speeds: a nuisance the model cannot see, or too few training runs there?

Question. After the fourth look B's size within ×1.5 was 73 % at 340 rpm against 91-93 % at 515-765 rpm, and
neither more windows per run, window weights nor longer recordings lifted it on every development set
(``docs/identification.md``, "How it was chosen"). Two explanations predict different things: a nuisance that
shifts a slow run's features like a change of size (e.g. the contact's stiffness) makes the error follow that
nuisance and does not shrink with more runs; a regressor short of data at those speeds leaves an error that follows
no nuisance, shrinks the answers toward the middle of the trained sizes and falls as runs are added.

Method. The runs of the fourth round's crank-PID training sets (the drive train's draw other factors) at the slow
speeds of the training grid (250-425 motor rpm) with y or z vertical and a clearance at B; per run the median of
its windows' 178 features (``twin-identify-features/6``, the development study's cache ``WORK/features``).

1. Out-of-fold answers (5 folds of runs; gradient-boosted trees of log10 of B's clearance, the shipped size
   regressor's settings ``SIZE_REGRESSORS["mean"]``) and the Spearman correlation of their error (log10 answer -
   log10 truth) with the true size and with each drawn nuisance factor.
2. A learning curve: a fifth of the runs held out, the regressor fitted on a quarter, half, three quarters and all of
   the rest; the held-out share within ×1.5, for two random splits.

Result (2026-11-27, before the fifth round's training set existed; ``analysis/results/identify/slow_b_probe.json``):
1334 runs, 79.2 % within ×1.5 out of fold. The error correlates with the true size (-0.41 to -0.44: the answers
shrink toward the middle of the trained sizes) and with no drawn nuisance (ripple, contact restitution, friction
and stiffness, guide friction, sensor offsets, mounting, noise, start angle, speed, the twin's damping: -0.07 to
+0.05). Held-out share within ×1.5 from 267, 534, 801 and 1068 training runs: 64, 72, 73, 77 % and 62, 70, 71,
76 % (two splits), still rising at the end. The model is short of slow-speed runs at B, not of information: the
fifth round's training set (``clearance_id_nuisance_ref_slow_b2.toml``) adds 2400.

Run: ``python analysis/identify/slow_b_probe.py [--work DIR]`` (needs scikit-learn, the ``train`` extra; about
3 min on two cores).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from nuisance_study import MOTOR, MOTOR_YZ, ROOT, VARIANTS  # noqa: E402
from twin.provenance import stamped  # noqa: E402

#: the fourth round's training sets driven by the crank PID
SETS = tuple(n for n in VARIANTS["slow-b-bands"][0] if n not in (MOTOR, MOTOR_YZ))
SLOW_RPM = 425.0
OUT = ROOT / "analysis" / "results" / "identify" / "slow_b_probe.json"
FACTOR = 1.5


def slow_runs(work: Path) -> tuple[np.ndarray, np.ndarray, list[dict]]:
    """Per-run median features, log10 of B's clearance and the rows of the slow y/z runs with a clearance at B."""
    X, y, rows = [], [], []
    for name in SETS:
        z = np.load(work / "features" / f"{name}.npz", allow_pickle=False)
        meta = json.loads((work / "features" / f"{name}.json").read_text())
        owner = z["owner"]
        for i, r in enumerate(meta["rows"]):
            if r["clearance_b_mm"] > 0 and r["motor_rpm"] <= SLOW_RPM and r["orientation"] in ("y", "z"):
                X.append(np.median(z["X"][owner == i], axis=0))
                y.append(np.log10(r["clearance_b_mm"]))
                rows.append(r)
    return np.array(X), np.array(y), rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", default=str(ROOT.parent / "identify_work"))
    args = ap.parse_args()
    from scipy.stats import spearmanr
    from sklearn.ensemble import HistGradientBoostingRegressor
    from sklearn.model_selection import KFold, cross_val_predict

    from twin.identification.training import SIZE_REGRESSORS

    X, y, rows = slow_runs(Path(args.work))
    tol = np.log10(FACTOR)

    def regressor() -> HistGradientBoostingRegressor:
        return HistGradientBoostingRegressor(random_state=0, **SIZE_REGRESSORS["mean"])

    print(f"{len(rows)} slow runs with a clearance at B, y or z vertical, from {', '.join(SETS)}", flush=True)
    err = cross_val_predict(regressor(), X, y, cv=KFold(5, shuffle=True, random_state=0)) - y
    factors = sorted({k for r in rows for k, v in r.items()
                      if k.startswith("factor_") and isinstance(v, (int, float)) and not isinstance(v, bool)})
    out: dict = {"runs": len(rows), "sets": list(SETS), "within_1_5_out_of_fold": float(np.mean(np.abs(err) <= tol)),
                 "spearman_error_with": {}, "learning_curve": []}
    truth = {"true size (log)": y} | {f: np.array([float(r.get(f, np.nan)) for r in rows]) for f in factors}
    for name, v in truth.items():
        ok = np.isfinite(v)
        if ok.sum() < 20 or np.ptp(v[ok]) == 0:
            continue
        out["spearman_error_with"][name] = float(spearmanr(v[ok], err[ok])[0])
    print(f"out of fold, within x{FACTOR}: {100 * out['within_1_5_out_of_fold']:.1f} %")
    for name, c in out["spearman_error_with"].items():
        print(f"  error vs {name:34s} {c:+.2f}")
    rng = np.random.default_rng(1)
    for split in range(2):
        perm = rng.permutation(len(rows))
        test, pool = perm[: len(rows) // 5], perm[len(rows) // 5:]
        for frac in (0.25, 0.5, 0.75, 1.0):
            tr = pool[: int(len(pool) * frac)]
            p = regressor().fit(X[tr], y[tr]).predict(X[test])
            share = float(np.mean(np.abs(p - y[test]) <= tol))
            out["learning_curve"].append({"split": split, "training_runs": int(len(tr)), "held_out_runs": int(len(test)),
                                          "within_1_5": share})
            print(f"  split {split}: {len(tr):4d} training runs -> {100 * share:.1f} % of {len(test)} held out within "
                  f"x{FACTOR}", flush=True)
    OUT.write_text(json.dumps(stamped(out), indent=1) + "\n")
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
