"""Convert a clearance-identification model of format 2 (a joblib pickle of scikit-learn estimators)
into the model file twin loads (format 3: an ``.npz`` of plain arrays and JSON, no pickle).

Method:

1. Unpickle the format-2 file with joblib. Unpickling runs code from the file: give this script only a
   model you made yourself or one from this repository's history, e.g. the shipped model as committed
   before the conversion (scikit-learn 1.9, the version it was trained with, installed)::

       git show $(git rev-list -n 1 HEAD -- twin/data/identify_default.joblib)^:twin/data/identify_default.joblib \
           > /tmp/identify_default.joblib

2. Export the location classifier and the two size regressors (``HistGradientBoosting*``) as arrays:
   every fitted tree's nodes (feature index, numeric threshold, missing-go-left, children, leaf values),
   the baseline and the link (:func:`twin.identification.trees.from_sklearn`; categorical features are refused).
   The metadata are kept as they are (feature version and names, interval half widths, ``trained_on``
   with the library versions of the training); ``trained_on.converted_from`` records the source file's
   name, SHA-256 and format.
3. Check, before anything is written: the exported estimators' answers equal scikit-learn's bit for bit
   (``predict_proba`` and ``predict`` of the classifier, ``predict`` of the regressors) on the window
   features of every sample recording (``recordings/*.mcap``) and on ``--random`` random feature
   matrices: every feature drawn uniformly over the span of the thresholds the trees split it at (plus
   10 % either side; in every other row a quarter of the entries exactly at a threshold), 10 % of the
   entries NaN (missing), one row +inf and one -inf throughout.
4. Write the file (``ClearanceModel.save``, to a temporary name), load it back with
   ``ClearanceModel.load``, and check that the answers of ``identify_recording`` on every sample
   recording are the same as the format-2 model's (every field but the time taken), and the loaded
   estimators' answers on the random features the same as scikit-learn's; only then is the file moved
   into place. The checks' figures go to ``--report`` (JSON).

Run: ``python analysis/identify/convert_joblib_model.py /tmp/identify_default.joblib --out
twin/data/identify_default.npz --report analysis/results/identify/model_conversion.json`` (about 30 s on two busy cores).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
from pathlib import Path

import numpy as np
from twin.provenance import stamped

ROOT = Path(__file__).resolve().parents[2]


def recording_features() -> dict[str, np.ndarray]:
    """Window features of every sample recording that has them (the calibration-only one has none)."""
    from twin.identification.features import IdentifyError, features
    from twin.identification.inputs import recording_inputs

    out = {}
    for rec in sorted((ROOT / "recordings").glob("*.mcap")):
        try:
            acc, counts, rate, cpr, cfg = recording_inputs(rec)
            out[rec.name] = features(acc, counts, rate, cpr, orientation=cfg.mechanism.orientation if cfg else "y")[0]
        except IdentifyError:
            continue
    return out


def random_features(ensembles: list, n: int, seed: int = 0) -> np.ndarray:
    """``n`` rows: each feature uniform over its split thresholds' span (10 % either side; N(0, 1) for
    a feature no tree splits at), in every other row a quarter of the entries exactly at a threshold
    (where ``<=`` and ``<`` part), 10 % NaN, row 0 +inf, row 1 -inf."""
    rng = np.random.default_rng(seed)
    nf = ensembles[0].n_features
    X = rng.standard_normal((n, nf))
    for f in range(nf):
        t = np.concatenate([e.threshold[(~e.is_leaf) & (e.feature == f)] for e in ensembles])
        t = t[np.isfinite(t)]
        if t.size:
            lo, hi = t.min(), t.max()
            pad = 0.1 * (hi - lo) + 1e-9 * max(1.0, abs(lo))
            X[:, f] = rng.uniform(lo - pad, hi + pad, n)
            # every other row: a quarter of the entries exactly at one of the feature's thresholds
            at = (np.arange(n) % 2 == 1) & (rng.random(n) < 0.25)
            X[at, f] = rng.choice(t, int(at.sum()))
    X[rng.random(X.shape) < 0.1] = np.nan
    X[0], X[1] = np.inf, -np.inf
    return X


def compare(exported: dict, sk: dict, X: np.ndarray) -> dict[str, dict[str, float | bool]]:
    """Per estimator: whether its answers on ``X`` equal scikit-learn's bit for bit, and the largest
    difference (0 when equal)."""
    out = {}
    for name, e in exported.items():
        pairs = [("predict", e.predict(X), sk[name].predict(X))]
        if e.kind != "identity":
            pairs.append(("predict_proba", e.predict_proba(X), sk[name].predict_proba(X)))
        for what, a, b in pairs:
            same = bool(np.array_equal(a, b))
            diff = 0.0 if same or a.dtype.kind not in "f" else float(np.nanmax(np.abs(a - b)))
            out[f"{name}.{what}"] = {"bit_identical": same, "max_abs_difference": diff}
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("source", help="model of format 2 (.joblib): unpickled, so only a trusted file")
    ap.add_argument("--out", required=True, help="model file to write (.npz)")
    ap.add_argument("--report", help="JSON file of the checks' figures")
    ap.add_argument("--random", type=int, default=2000, metavar="N", help="rows of random features (default 2000)")
    args = ap.parse_args()
    import joblib

    from twin.identification.model import MODEL_SUFFIX, ClearanceModel, identify_recording
    from twin.identification.trees import from_sklearn
    from twin.util import temp_path

    src, out = Path(args.source), Path(args.out)
    if out.suffix != MODEL_SUFFIX:
        sys.exit(f"--out: must end in {MODEL_SUFFIX}")
    # the format-2 pickle names the package by its former name, twin.identify
    import twin.identification
    import twin.identification.model
    sys.modules.setdefault("twin.identify", twin.identification)
    sys.modules.setdefault("twin.identify.model", twin.identification.model)
    old = joblib.load(src)  # trusted source only (module docstring)
    if getattr(old, "format", None) != "twin-identify-model/2":
        sys.exit(f"{src}: not a model of format twin-identify-model/2 ({getattr(old, 'format', None)!r})")
    sk = {"classifier": old.classifier, "size_B": old.size["B"], "size_C": old.size["C"]}
    exported = {k: from_sklearn(v) for k, v in sk.items()}
    recs = recording_features()
    Xr = random_features(list(exported.values()), args.random)
    report = {"source": src.name, "source_sha256": hashlib.sha256(src.read_bytes()).hexdigest(),
              "sklearn_versions": {"trained": old.trained_on["versions"]["sklearn"],
                                   "converted": exported["classifier"].source["sklearn"]},
              "estimators": {k: v.meta() | {"max_depth": v._walk[-1]} for k, v in exported.items()},
              "recordings": {r: compare(exported, sk, X) for r, X in recs.items()},
              "random": {"rows": len(Xr), "nan_fraction": float(np.isnan(Xr).mean()),
                         "exported": compare(exported, sk, Xr)}}
    new = ClearanceModel(exported["classifier"], {"B": exported["size_B"], "C": exported["size_C"]},
                         dict(old.interval_log10), feature_version=old.feature_version,
                         feature_names=list(old.feature_names),
                         trained_on=old.trained_on | {"converted_from": {"file": src.name, "format": old.format,
                                                                          "sha256": report["source_sha256"]}})
    tmp = temp_path(out, keep_suffix=True)
    try:
        new.save(tmp)
        back = ClearanceModel.load(tmp)
        loaded = {"classifier": back.classifier, "size_B": back.size["B"], "size_C": back.size["C"]}
        report["random"]["loaded"] = compare(loaded, sk, Xr)
        answers = {}
        for rec in sorted((ROOT / "recordings").glob("*.mcap")):
            try:
                a, b = (identify_recording(m, rec).to_dict() for m in (old, back))
            except Exception as err:  # noqa: BLE001 - the calibration-only sample is refused by both
                answers[rec.name] = {"refused": str(err)}
                continue
            a.pop("seconds"), b.pop("seconds")
            answers[rec.name] = {"identical": json.dumps(a, default=float) == json.dumps(b, default=float),
                                 "fault": b["fault"], "clearance_c_mm": b["clearance_c_mm"]}
        report["answers"] = answers
        report["file_bytes"] = tmp.stat().st_size
        checks = [v["bit_identical"] for c in [*report["recordings"].values(), report["random"]["exported"],
                                               report["random"]["loaded"]] for v in c.values()]
        checks += [v["identical"] for v in answers.values() if "identical" in v]
        report["all_identical"] = all(checks) and len(answers) > 0
        print(json.dumps(report, indent=2))
        if args.report:
            Path(args.report).write_text(json.dumps(stamped(report), indent=2) + "\n")
        if not report["all_identical"]:
            print(f"{src}: the converted model does not answer as the original; {out} not written", file=sys.stderr)
            return 1
        os.replace(tmp, out)
        print(f"{out}: {out.stat().st_size} bytes, answers identical to {src.name}'s")
        return 0
    finally:
        tmp.unlink(missing_ok=True)


if __name__ == "__main__":
    sys.exit(main())
