"""Quick development-set comparison of whole-bench location and size variants on kept features (no intervals).

Reads the window features ``analysis/identify/train_bench.py`` keeps beside each training set
(``features_cache.npz`` + ``.json``) and computes the development sets' once (kept in ``--cache``); fits each
variant's estimators with scikit-learn and answers the development runs as the model does (class: the most probable
after the mean of the windows' probabilities; size: the median of the windows' log10 answers), without intervals or
training-data checks. The location of a size variant is the shipped ``bench`` model's classifier, the sizes of a
location variant its regressors, so each line changes one thing. Prints, per variant: location hits, sizes within
x1.5 where resolved (B, C: the size-resolution map; G: x or z vertical) and the recall per class; and a table of the
shipped model's size errors by factor (``--factors``).

    python analysis/identify/bench_variants.py --work DIR [--cache DIR] [--variants S0 SW SWc C0 D0 ...] [--factors]

Variants. Sizes (squared error on log10, 1000 trees of 31 leaves at 0.05, leaves of 20 windows, as trained):
``S0`` every window alike; ``SW`` each run alike (windows weighted 1/windows of their run); ``SWc`` SW with the
other locations' play as two more columns (true classes in training, the located class in answering); ``S0c``
S0 with them; ``S2`` 600 trees of 15 leaves, leaves of 60, half the features per split; ``SWl`` SW with leaves of
10; ``SR`` one row per run (its windows' median features). Location: ``C0`` one classifier over the eight classes as
trained (400 trees of 15 leaves at 0.08, balanced, early stopping); ``D0`` a presence detector per location with
the same settings, combined as their product; ``DW``/``CW`` D0/C0 with each run alike.
Run with ``OMP_NUM_THREADS=1`` on a shared machine (scikit-learn's threads wait on each other under load).
"""

from __future__ import annotations

import argparse
import collections
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "analysis" / "identify"))
from train_bench import DEV, TRAIN  # noqa: E402

CLS = ("none", "B", "C", "BC", "G", "BG", "CG", "BCG")
REG = dict(loss="squared_error", max_iter=1000, learning_rate=0.05, max_leaf_nodes=31, l2_regularization=1.0,
           min_samples_leaf=20)
CLF = dict(max_iter=400, learning_rate=0.08, max_leaf_nodes=15, l2_regularization=1.0, min_samples_leaf=20,
           class_weight="balanced", early_stopping=True, validation_fraction=0.15, random_state=0)


def load(work: Path, names: tuple[str, ...], cache: Path) -> tuple[np.ndarray, list[dict], np.ndarray]:
    """Pooled window features, run rows and window -> row of the datasets ``names`` (kept features where present,
    else computed and kept in ``cache``)."""
    from twin.dataset import open as open_dataset
    from twin.identification.inputs import dataset_features

    Xs, rows, owner = [], [], []
    for n in names:
        npz, js = work / n / "features_cache.npz", work / n / "features_cache.json"
        if not npz.is_file():
            npz, js = cache / f"{n}.npz", cache / f"{n}.json"
            if not npz.is_file():
                X, r, o, _ = dataset_features(open_dataset(work / n), ("train", "val", "test"), 2)
                cache.mkdir(parents=True, exist_ok=True)
                np.savez(npz, X=X, owner=np.asarray(o))
                js.write_text(json.dumps({"rows": r}, default=float))
        z, meta = np.load(npz, allow_pickle=False), json.loads(js.read_text())
        owner += [len(rows) + int(i) for i in z["owner"]]
        rows += meta["rows"]
        Xs.append(z["X"])
    return np.concatenate(Xs), rows, np.array(owner)


def context(j: str, faults: list[str]) -> np.ndarray:
    from twin.identification.model import size_context

    return size_context(j, list(faults))


def evaluate(Xd, rows, owner, loc, size, label: str) -> None:
    from twin.identification.intervals import resolution
    from twin.identification.model import label_mm

    P, classes = loc(Xd)
    hits, per, tot, res = 0, collections.Counter(), collections.Counter(), {j: [] for j in "BCG"}
    n = 0
    for r in range(len(rows)):
        m = owner == r
        if not m.any():
            continue
        n += 1
        fault, t = classes[int(np.argmax(P[m].mean(axis=0)))], rows[r]["fault"]
        hits += fault == t
        tot[t] += 1
        per[t] += fault == t
        rz = resolution(rows[r]["orientation"], rows[r]["crank_hz"])
        for j in "BCG":
            truth = label_mm(rows[r], j)
            if truth > 0 and rz.get(j, True):
                a = 10 ** float(np.median(size(j, Xd[m], fault)))
                res[j].append(abs(math.log(a / truth)) <= math.log(1.5))
    print(f"{label:16s} location {hits}/{n} | x1.5 " + " ".join(f"{j}:{sum(v)}/{len(v)}" for j, v in res.items())
          + " | recall " + " ".join(f"{c}:{per[c]}/{tot[c]}" for c in CLS if tot[c]), flush=True)


def factors(report: Path) -> None:
    """The size errors of a bench_eval.py report by factor: hits within x1.5 / runs, median log10 error, median
    absolute log10 error."""
    d = json.loads(report.read_text())
    P = [p for p in d["predictions"] if not p["refused"] and p["turns"] >= 2]
    keys = {"orientation": lambda p, j: p["orientation"], "drive": lambda p, j: p["drive"],
            "engine": lambda p, j: p["engine"],
            "motor rpm": lambda p, j: "<400" if p["motor_rpm"] < 400 else "<600" if p["motor_rpm"] < 600 else ">=600",
            "size mm": lambda p, j: "<0.1" if p["truth_mm"][j] < 0.1 else "<0.3" if p["truth_mm"][j] < 0.3 else ">=0.3",
            "class": lambda p, j: p["true_fault"]}
    for j in "BCG":
        rs = [p for p in P if p["truth_mm"][j] > 0 and j in p["joints"] and p["joints"][j]["resolved"] is not False]
        print(f"{j}: {len(rs)} resolved runs with play")
        for name, key in keys.items():
            g = collections.defaultdict(list)
            for p in rs:
                g[key(p, j)].append(math.log10(p["joints"][j]["size_mm"] / p["truth_mm"][j]))
            print(f"  {name:12s} " + " | ".join(
                f"{k}: {sum(abs(e) <= math.log10(1.5) for e in v)}/{len(v)} bias {np.median(v):+.2f} "
                f"mad {np.median(np.abs(v)):.2f}" for k, v in sorted(g.items())))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", required=True, help="folder of the datasets (train_bench.py --work)")
    ap.add_argument("--cache", default=None, help="where the development sets' features are kept (default WORK/variants_cache)")
    ap.add_argument("--variants", nargs="*", default=["S0", "SW", "SWc", "D0"])
    ap.add_argument("--factors", metavar="REPORT.json", help="a bench_eval.py report whose size errors to tabulate")
    args = ap.parse_args()
    from sklearn.ensemble import HistGradientBoostingClassifier, HistGradientBoostingRegressor

    from twin.identification.model import ClearanceModel, label_mm, shipped_model_path

    if args.factors:
        factors(Path(args.factors))
    work = Path(args.work)
    X, rows, owner = load(work, TRAIN, Path(args.cache or work / "variants_cache"))
    Xd, rd, od = load(work, DEV, Path(args.cache or work / "variants_cache"))
    y = np.array([rows[i]["fault"] for i in owner])
    w_run = 1.0 / np.bincount(owner)[owner]
    shipped = ClearanceModel.load(shipped_model_path("bench"))
    ship_loc = lambda Z: (shipped.classifier.predict_proba(Z), list(shipped.classifier.classes_))  # noqa: E731
    ship_size = lambda j, Z, f: shipped.size[j].predict(Z)  # noqa: E731
    evaluate(Xd, rd, od, ship_loc, ship_size, "shipped bench")
    for v in args.variants:
        t0 = time.perf_counter()
        if v.startswith("S"):
            ctx, weights = v.endswith("c"), v.startswith("SW")
            params = REG | ({"min_samples_leaf": 10} if v == "SWl" else {}) | (
                dict(max_iter=600, max_leaf_nodes=15, min_samples_leaf=60, max_features=0.5) if v.startswith("S2") else {})
            regs = {}
            for j in "BCG":
                truth = np.array([label_mm(rows[i], j) for i in owner])
                sel = truth > 0
                if v == "SR":
                    runs = np.unique(owner[sel])
                    Xr = np.array([np.median(X[owner == r], axis=0) for r in runs])
                    regs[j] = HistGradientBoostingRegressor(**(REG | {"min_samples_leaf": 8}), random_state=0).fit(
                        Xr, np.log10([label_mm(rows[r], j) for r in runs]))
                    continue
                Xj = np.hstack([X, context(j, y)]) if ctx else X
                regs[j] = HistGradientBoostingRegressor(**params, random_state=0).fit(
                    Xj[sel], np.log10(truth[sel]), sample_weight=w_run[sel] if weights else None)
            if v == "SR":
                size = lambda j, Z, f: regs[j].predict(np.median(Z, axis=0)[None])  # noqa: E731
            elif ctx:
                size = lambda j, Z, f: regs[j].predict(np.hstack([Z, context(j, [f] * len(Z))]))  # noqa: E731
            else:
                size = lambda j, Z, f: regs[j].predict(Z)  # noqa: E731
            evaluate(Xd, rd, od, ship_loc, size, f"{v} ({time.perf_counter() - t0:.0f} s)")
        else:
            weights = v.endswith("W")
            if v.startswith("D"):
                det = {}
                for j in "BCG":
                    lab = np.array([j in c for c in y])
                    sw = None
                    if weights:
                        sw = w_run * np.where(lab, len(lab) / (2 * lab.sum()), len(lab) / (2 * (~lab).sum()))
                    det[j] = HistGradientBoostingClassifier(**(CLF | ({"class_weight": None} if weights else {}))).fit(
                        X, lab, sample_weight=sw)

                def loc(Z, det=det):
                    p = {j: det[j].predict_proba(Z)[:, 1] for j in "BCG"}
                    return np.stack([np.prod([p[j] if j in c else 1 - p[j] for j in "BCG"], axis=0) for c in CLS],
                                    1), list(CLS)
            else:
                sw = None
                if weights:
                    share = {k: len(y) / (8 * np.sum(y == k)) for k in CLS}
                    sw = w_run * np.array([share[k] for k in y])
                clf = HistGradientBoostingClassifier(**(CLF | ({"class_weight": None} if weights else {}))).fit(
                    X, y, sample_weight=sw)
                loc = lambda Z, clf=clf: (clf.predict_proba(Z), list(clf.classes_))  # noqa: E731
            evaluate(Xd, rd, od, loc, ship_size, f"{v} ({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
