"""The clearance identification model: train on a dataset, save, load, identify.

* **Fault location**: scikit-learn's ``HistGradientBoostingClassifier`` (none, B, C, BC) on the
  window features (:mod:`twin.identification.features`), classes weighted to balance; a recording's
  class probabilities are the mean over its windows.
* **Clearance size**: per joint, a ``HistGradientBoostingRegressor`` on log10 of the diametral clearance
  (:data:`SIZE_REGRESSORS`: squared error, the mean; the first two rounds' models took the quantile loss at 50 %,
  the median), trained on the windows of the runs where that joint has a clearance; a recording's size is the
  median over its windows.
* **Training data**: one dataset or several (``train([DIR, DIR])``, ``twin identify train DS1 DS2``)
  at the same sample rate and encoder resolution (e.g. datasets generated in batches, catalogue
  clearances beside clearances drawn between them, or the same nuisances simulated by both engines);
  their runs are pooled.
* **Interval**: split-conformal (CV+-like) at the level of recordings. The training runs with a
  clearance at the joint are split into ``CONFORMAL_FOLDS`` groups; each group's runs are answered
  by a regressor fitted on the other groups; a run's score is |log10(answer) − log10(truth)|; the
  ⌈(n + 1)·0.9⌉-th smallest score w gives every answer the interval [size·10^−w, size·10^w], which
  holds the truth in at least 90 % of recordings like the training runs (exchangeability). With
  ``interval_folds="speed"`` (``--interval-folds speed``; the shipped model) each motor speed is one
  group, so every score is an answer at a speed its regressor never saw, as a bench recording's may
  be. At each joint the scores are split (Mondrian) by its size-resolution map (:func:`size_resolved`)
  where each side has ``MONDRIAN_MIN_RUNS`` runs: one half width for answers the sensors resolve,
  a wider one (``"B_unresolved"``, ``"C_unresolved"``) for those below the map. Model
  format 1 took the 5 % and 95 % quantile regressors instead: their window medians stayed at the
  catalogue's ends (0.02–0.5 mm for almost every answer), covering the truth while saying nothing.
  Each side of the map is split again by the answer's size, where the runs allow: the scatter in log differs
  from one size to another (development: small clearances scatter more than large ones, and 0.05-0.07 mm more
  than 0.02 mm). From the fourth round on the split has one band per group of catalogue values
  (:data:`CATALOGUE_BANDS_MM`, boundaries at the geometric means of neighbouring values at least
  :data:`BAND_MIN_RATIO` apart: 0.02 | 0.05-0.1 | 0.5 | 1.0 mm; ``"B"`` above the largest boundary used,
  ``"B_small"``, ``"B_small2"``, ... below each further one, :func:`band_half_width`), so that the coverage holds
  value by value; a boundary is used where both its sides have ``MONDRIAN_MIN_RUNS`` runs. The models before split
  once, at :data:`SIZE_BAND_MM` (``"B_small"``).
  Before that split, each side is split by the recording's measured within-turn speed ripple
  (:data:`RIPPLE_BAND_PCT`, ``"B_rippled"``, ``"B_unresolved_rippled_small"``, ...), where the runs allow: a
  motor driving through the V-belt ripples far more than a crank PID, and its runs' sizes scatter more.
  From the sixth round on, C's parts are split again by the located fault (``"C_both"``: both joints located faulty,
  :data:`FAULT_SPLIT_JOINTS`, ``train(fault_split=...)``), where the runs allow: B's impacts reach the slider's
  sensors, and on the development sets C's sizes scattered more with both joints loose (C 0.02 mm covered in 80 % of
  the B+C runs against 94 % of the runs with C alone); at B the split did not help there and is not made.
  From the sixth round on, the model also holds the half widths of answers from fewer windows than its training
  runs (``interval.half_width_log10_by_windows``, ``train(by_windows=True)``): for n = 1, 2, ... the same parts
  calibrated on the out-of-fold runs' answers from their first n windows; a recording answered from n windows takes
  that table (a 3 s training run holds up to four windows of two turns, a 0.8 s recording at 750 rpm one, whose
  answer scatters more), one from more windows the main table.
  Where the training runs come from several engines, each half width is the largest of the pooled runs' and each
  engine's runs' alone (``train(interval_by_engine=True)``, the default from the third round on): the bench's
  contact law is neither engine's, and a half width calibrated on the pooled runs covers the engine the regressor
  reads more easily more often than the other.
  A joint the classifier finds healthy reports 0 (ball bearing).
  ``train(normalized_intervals=True)`` also stores **normalized** conformal scales (``interval.normalized``): a
  run's score is divided by its difficulty, the spread of its per-window answers (:func:`logs_spread`) plus an
  offset beta (the median spread of the out-of-fold runs, at least :data:`SPREAD_FLOOR_LOG10`); the half width
  of an answer is then q·(spread + beta). Where a model has them they replace the fixed half widths. Not the
  default: a recording of one or two windows has no measurable spread, and on the development sets (reference
  engine, fewer windows than the training runs) they covered the truth less often than the fixed widths
  (``analysis/identify/nuisance_study.py``).
* **Held-out size accuracy** (:func:`held_out_accuracy`, ``trained_on["held_out_size_accuracy"]``): the out-of-fold
  answers the intervals are calibrated on also give, per joint, orientation and training speed, the share within a
  factor 1.5 of the truth; an answer reads its own speed's (:func:`held_out_at`: ``clearance_b_size_held_out``,
  ``clearance_c_size_held_out``), so that a size at a speed where the model's answers often miss says so.
* **Windows of an answer**: back to back, as the estimators learn from them, unless the model records another hop
  (``trained_on["answer_hop_revs"]``, :data:`ANSWER_HOP_REVS`).
* **Outside the training data** (:mod:`twin.identification.ranges`): an answer checks the recording's crank
  rate, within-turn speed ripple (from the encoder), noise level, orientation and, where the model stores the
  training features' quartiles, its distance in feature space, against the training runs' ranges; each reason
  gives a warning and the intervals are widened to every clearance trained on at that joint.
* The model is saved with its feature definition (version and names), what it was trained on
  (dataset name, identity digest, rate, speed range, clearances and orientations seen) and the
  library versions; loading checks the format and the feature version, and identifying checks the
  recording's rate and speed against the training data (a speed outside the training range is
  answered with a warning, never silently).

Model file (format ``twin-identify-model/4``, suffix ``.npz``; :meth:`ClearanceModel.save`,
:meth:`ClearanceModel.load`): a NumPy ``.npz`` archive (a zip of ``.npy`` members, each with its
CRC-32) of plain arrays and one JSON text, read with ``allow_pickle=False``: loading it runs no code
from the file, and answering needs no scikit-learn. Members:

* ``model.json``: a 0-d unicode array holding JSON: ``format`` (``twin-identify-model/4``),
  ``feature_version`` and ``feature_names`` (:mod:`twin.identification.features`), ``interval_log10`` (the
  conformal half widths [log10], see above), ``trained_on`` (the training data, with ``versions``:
  twin, scikit-learn and numpy of the training; ``ranges``: the training runs' ranges of crank rate,
  within-turn ripple per harmonic, noise level and orientations, with their ``source``; ``feature_reference``:
  the training windows' feature quartiles, or null where unknown; ``interval.normalized``: the normalized
  conformal scale per joint, where trained; ``held_out_size_accuracy`` and ``answer_hop_revs``, where recorded;
  see below), and ``estimators``: per estimator (``classifier``,
  ``size_B``, ``size_C``) its kind (link: ``softmax`` for the classifier, ``identity`` for the size
  regressors), number of features, trees per iteration, classes and source
  (:meth:`twin.identification.trees.TreeEnsemble.meta`);
* per estimator E, the arrays ``E.baseline``, ``E.tree_nodes``, ``E.feature``, ``E.threshold``,
  ``E.missing_left``, ``E.left``, ``E.right``, ``E.is_leaf``, ``E.value`` (dtypes and meaning:
  :mod:`twin.identification.trees`).

Loading refuses, in one line naming the file: anything but a zip archive (a pickle or ``.joblib``
file, as model format 2 was, is named as such and never unpickled), a damaged archive (CRC, truncation),
another format version (format 3 lacked the training ranges: ``analysis/identify/convert_model_ranges.py``
adds them), other members, an array of another dtype (object arrays included: never
unpickled), trees that a walk could not use safely, and a feature version this twin does not compute.
The scikit-learn estimators of the training are exported by :func:`twin.identification.trees.from_sklearn`,
whose answers are checked equal bit for bit on the training windows.
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from twin.config import CATALOGUE_DIAMETRAL_MM, Drive
from twin.identification.features import (FEATURE_VERSION, REVS_PER_WINDOW, IdentifyError, feature_names, features,
                                          hop_ok, MIN_HOP_REVS)
from twin.identification.ranges import feature_reference, out_of_range, recording_measures, training_ranges, widen
from twin.identification.trees import ModelError, TreeEnsemble, from_sklearn

CLASSES = ("none", "B", "C", "BC")
# Size resolution per joint: the lowest motor speed [rpm] (belt 1:3.97) per vertical axis from which the
# bench's sensor chain tells 0.05, 0.07 and 0.1 mm at that joint apart beyond the contact parameters'
# uncertainty (shrinkage LDA on this model's features, leave one run out, accuracy >= 0.95 there and at
# every faster speed measured), measured on the twin's runs over 250-750 rpm by
# ``python analysis/identify/size_observability.py --joint J --scenes x:250,...,z:750 [--start-angles]``
# (the model card's commands), once with every run started at crank angle 0 and once with the start angle
# drawn over a turn (a bench recording starts wherever the crank stood); the map is the stricter of the two
# (analysis/results/identify/size_observability_{speed,start,b,b_start}.json).
# At C below it the pin slides round the bushing (y, z) or flies chaotically (x at 300-325 rpm) and the size
# signature is under the sensor noise (noise-free accelerations separate y at 300 rpm at 1.00): 0.24-0.90
# below the map, both studies the same map. At B the free-flight band with x vertical is unresolved (0.81 and
# 0.38 at 300 and 325 rpm; 0.95 at 250 started at 0, 0.10 with the start drawn), and with y vertical at
# 250 rpm the start angle matters (1.00 started at 0, 0.81 drawn): B is resolved from 375 rpm with x
# vertical, 300 with y, over the whole measured range (from 250) with z.
SIZE_RESOLVED_FROM_RPM = {
    "B": {"x": 375.0, "y": 300.0, "z": 250.0},
    "C": {"x": 425.0, "y": 475.0, "z": 300.0},
}
BELT_RATIO = Drive.belt_ratio  # motor turns per crank turn of the bench's V-belt (S003 §2.2.2)
COVERAGE = 0.90  # nominal coverage of the reported intervals
CONFORMAL_FOLDS = 5
MONDRIAN_MIN_RUNS = 20  # out-of-fold runs each side needs before the interval at C is split by resolution
#: answers below this size [mm] get their own conformal half width (``"B_small"``, ...), where the training
#: runs allow: small clearances scatter more in log than large ones (development: 0.26 against 0.13 at B).
#: 0.2 mm lies between the catalogue's 0.1 and 0.5 mm
SIZE_BAND_MM = 0.2
#: neighbouring catalogue values at least this factor apart get a size-band boundary between them [-]: the 90 %
#: half widths are x1.3-1.6, so the answers of 0.05, 0.07 and 0.1 mm (x1.4 apart) overlap and a band each would
#: split answers by their error rather than by the size (development: bands at 0.059 and 0.084 mm too gave 0.07 mm
#: answers at C x2.4 and 0.1 mm ones x1.41, which missed 0.1 mm on a test-6 repeat)
BAND_MIN_RATIO = 2.0


def catalogue_bands(min_ratio: float) -> tuple[float, ...]:
    """Size-band boundaries [mm] at the geometric means of neighbouring catalogue values at least ``min_ratio``
    apart (1: one between every two), to 4 decimals."""
    cat = CATALOGUE_DIAMETRAL_MM
    return tuple(round(math.sqrt(lo * hi), 4) for lo, hi in zip(cat, cat[1:]) if hi / lo >= min_ratio)


#: size bands of the intervals, one per group of catalogue values: boundaries at the geometric means of neighbouring
#: catalogue values at least BAND_MIN_RATIO apart [mm] (0.032, 0.22, 0.71: 0.02 | 0.05-0.1 | 0.5 | 1.0 mm);
#: ``train(size_band_mm=CATALOGUE_BANDS_MM)`` calibrates a half width for the answers of each group, where the
#: training runs allow, so that the coverage holds value by value and not only over all answers together
CATALOGUE_BANDS_MM = catalogue_bands(BAND_MIN_RATIO)
#: recordings whose largest within-turn speed ripple (harmonics 1-4 of the crank rate, measured from the encoder)
#: exceeds this [% of the speed] get their own conformal half widths (``"B_rippled"``, ...), where the training
#: runs allow: a motor driving through the V-belt ripples by 10-20 % at twice the crank rate (docs/drivetrain.md),
#: and the sizes of such runs scatter more than those of a crank PID's 0-4 % (development: 90 % intervals
#: calibrated on all runs together held 29-67 % of the drive train's B sizes). 4.5 % lies above the PID-driven
#: training runs' imposed 0-4 %
RIPPLE_BAND_PCT = 4.5
#: an answer's windows end every this many crank turns [turns] (recorded in the model as
#: ``trained_on["answer_hop_revs"]``; models without it: back to back). The regressors learn from windows cut back to
#: back; a window starting anywhere is one of the same kind, so a model may answer from overlapping windows
#: (``train(answer_hop_revs=0.5)``: windows ending every half turn, four where a 3 s recording at 340 motor rpm
#: holds one). Tried in the fifth round and not adopted: on the fourth fresh test's in-range part B within x1.5
#: 88.7 -> 90.1 %, C 91.7 -> 92.6 %, but on ``clearance_id_nuisance_dev`` B 87.1 -> 85.7 %, C 95.2 -> 93.7 %
#: (``analysis/identify/nuisance_study.py --variants overlap``): a short recording's size error is a bias of its
#: scene (contact parameters, ripple), which more windows over the same turns do not average out
ANSWER_HOP_REVS = float(REVS_PER_WINDOW)
MODEL_FORMAT = "twin-identify-model/4"
#: floor of the normalized intervals' difficulty offset beta [log10] (runs of one window have no spread)
SPREAD_FLOOR_LOG10 = 0.01
MODEL_SUFFIX = ".npz"
ESTIMATORS = ("classifier", "size_B", "size_C")


@dataclass
class ClearanceModel:
    """A trained identification model (see module docstring)."""

    # the location classifier: a TreeEnsemble (as trained and as loaded), or anything with predict_proba
    # and classes_ (a scikit-learn estimator is exported on save)
    classifier: Any
    size: dict[str, Any]  # per joint, the size regressor of log10 clearance [log10 mm] (likewise, predict)
    # per joint, the conformal half width w [log10]; "B_unresolved" / "C_unresolved", where present, the
    # half width of answers at that joint below its size-resolution map (SIZE_RESOLVED_FROM_RPM), "B" / "C"
    # then that of the others
    interval_log10: dict[str, float]
    feature_version: str = FEATURE_VERSION
    feature_names: list[str] = field(default_factory=feature_names)
    trained_on: dict[str, Any] = field(default_factory=dict)
    format: str = MODEL_FORMAT

    # ------------------------------------------------------------------ io
    def save(self, path: str | Path) -> Path:
        """Write the model file (module docstring: format ``twin-identify-model/4``) atomically;
        scikit-learn estimators are exported first (:func:`twin.identification.trees.from_sklearn`)."""
        from twin.identification.modelfile import write_model

        est = {"classifier": self.classifier, "size_B": self.size["B"], "size_C": self.size["C"]}
        est = {k: v if isinstance(v, TreeEnsemble) else from_sklearn(v) for k, v in est.items()}
        meta = {"format": MODEL_FORMAT, "feature_version": self.feature_version,
                "feature_names": list(self.feature_names), "interval_log10": dict(self.interval_log10),
                "trained_on": self.trained_on, "estimators": {k: v.meta() for k, v in est.items()}}
        return write_model(path, meta, est)

    @staticmethod
    def load(path: str | Path) -> "ClearanceModel":
        """Read a model file, refusing in one line anything but a ``twin-identify-model/4`` file of this
        twin's features (module docstring); nothing in the file is run."""
        from twin.identification.modelfile import read_model

        p = Path(path)
        meta, est = read_model(p, MODEL_FORMAT, ESTIMATORS)
        try:
            names, version = meta["feature_names"], meta["feature_version"]
            half = {str(k): float(v) for k, v in meta["interval_log10"].items()}
            trained_on = meta["trained_on"]
            hz = [float(x) for x in trained_on["crank_hz_range"]] + [float(trained_on["rate_hz"])]
            if len(hz) != 3 or not isinstance(names, list) or not all(isinstance(n, str) for n in names) or \
                    not {"B", "C"} <= set(half) or not all(math.isfinite(v) and v >= 0 for v in half.values()):
                raise ValueError("feature_names or interval_log10 malformed")
            _check_ranges(trained_on["ranges"], trained_on.get("feature_reference"), len(names))
            sb = trained_on.get("interval", {}).get("size_band_mm")
            if sb is not None and not all(isinstance(b, (int, float)) and math.isfinite(b) and b > 0
                                          for b in ([sb] if isinstance(sb, (int, float)) else sb)):
                raise ValueError("interval.size_band_mm malformed")
            _check_held_out(trained_on.get("held_out_size_accuracy"))
            if not hop_ok(trained_on.get("answer_hop_revs", REVS_PER_WINDOW)):
                raise ValueError(f"answer_hop_revs must lie in [{MIN_HOP_REVS}, {REVS_PER_WINDOW}] turns (at most "
                                 f"{round(1 / MIN_HOP_REVS)} windows per turn)")
            try:
                fault_split_joints(trained_on.get("interval", {}).get("fault_split", False))
            except ValueError:
                raise ValueError("interval.fault_split malformed") from None
            bw = trained_on.get("interval", {}).get("half_width_log10_by_windows") or {}
            if not isinstance(bw, dict) or not all(
                    isinstance(n, str) and n.isdigit() and int(n) >= 1 and isinstance(t, dict) and {"B", "C"} & set(t)
                    and all(isinstance(v, (int, float)) and math.isfinite(v) and v >= 0 for v in t.values())
                    for n, t in bw.items()):
                raise ValueError("interval.half_width_log10_by_windows malformed")
            rb = trained_on.get("interval", {}).get("ripple_band_pct")
            if rb is not None and not (isinstance(rb, (int, float)) and math.isfinite(rb) and rb > 0):
                raise ValueError("interval.ripple_band_pct malformed")
            for v in (trained_on.get("interval", {}).get("normalized") or {}).values():
                if not (math.isfinite(float(v["q"])) and float(v["q"]) >= 0 and float(v["beta"]) > 0):
                    raise ValueError("interval.normalized malformed")
        except (KeyError, TypeError, ValueError, AttributeError) as err:
            raise ModelError(f"{p}: not a readable identification model (metadata: {type(err).__name__}: "
                             f"{err})") from None
        if version != FEATURE_VERSION or names != feature_names():
            raise ModelError(f"{p}: made for features {version!r}, this twin computes {FEATURE_VERSION!r}; "
                             "retrain it with 'twin identify train'")
        if any(e.n_features != len(names) for e in est.values()) or est["classifier"].kind == "identity" or \
                not set(est["classifier"].classes) <= set(CLASSES) or est["size_B"].kind != "identity" or \
                est["size_C"].kind != "identity":
            raise ModelError(f"{p}: not a readable identification model (estimators do not fit its "
                             f"{len(names)} features and classes {', '.join(CLASSES)})")
        return ClearanceModel(est["classifier"], {"B": est["size_B"], "C": est["size_C"]}, half,
                              feature_version=version, feature_names=names, trained_on=trained_on)

    @property
    def hop_revs(self) -> float:
        """Where an answer's windows end, every this many crank turns [turns] (:data:`ANSWER_HOP_REVS`)."""
        return float(self.trained_on.get("answer_hop_revs", REVS_PER_WINDOW))

    # ------------------------------------------------------------- predict
    def identify(self, X: np.ndarray, resolved: dict[str, bool], ripple_pct: list[float] | None = None
                 ) -> dict[str, Any]:
        """Answer for one recording from its window features [windows, features]; ``resolved``: per
        joint ("B", "C"), whether its speed and orientation are on that joint's size-resolution map
        (:func:`size_resolved`), which picks the interval's half width where the model has one for
        each side (no default: a caller that forgot it would get the narrow interval below the map);
        ``ripple_pct``: the recording's measured within-turn ripple (harmonics of the crank rate, % of
        the speed; :func:`twin.identification.ranges.recording_measures`), which picks the half widths of
        rippled recordings (:data:`RIPPLE_BAND_PCT`) where the model has them. The half widths are those of
        answers from as many windows as ``X`` holds where the model has such a table for the joint
        (``interval.half_width_log10_by_windows``), else the main ones; C's (or B's) those of recordings located
        B+C where the model split them so (``interval.fault_split``)."""
        if set(resolved) != {"B", "C"}:
            raise ModelError(f"resolved: {sorted(resolved)}; needs a flag for each of B and C")
        proba = self.classifier.predict_proba(X).mean(axis=0)
        classes = list(self.classifier.classes_)
        p = {c: float(proba[classes.index(c)]) if c in classes else 0.0 for c in CLASSES}
        fault = max(p, key=p.get)
        out: dict[str, Any] = {"fault": fault, "probabilities": p}
        interval = self.trained_on.get("interval", {})
        norm = interval.get("normalized") or {}
        band = interval.get("size_band_mm")
        wavy = rippled(ripple_pct, interval.get("ripple_band_pct") or RIPPLE_BAND_PCT)
        split_by_fault = fault_split_joints(interval.get("fault_split", False))
        few = window_table(interval, len(X))
        for j in ("B", "C"):
            logs = self.size[j].predict(X)
            mid = logs_answer(logs)
            half = few if j in few else self.interval_log10
            side = j if resolved[j] or f"{j}_unresolved" not in half else f"{j}_unresolved"
            if wavy and f"{side}_rippled" in half:
                side = f"{side}_rippled"
            if fault == "BC" and j in split_by_fault and f"{side}_both" in half:
                side = f"{side}_both"  # both joints located faulty: the other joint's impacts reach this one's sensors
            w = band_half_width(half, side, mid, band)
            if side in norm:  # normalized conformal: the half width scales with the recording's difficulty
                w = norm[side]["q"] * (logs_spread(logs) + norm[side]["beta"])
            lo, hi = (float(f"{mid * 10 ** sign:.12g}") for sign in (-w, w))
            has = j in fault
            out[f"clearance_{j.lower()}_mm"] = mid if has else 0.0
            out[f"clearance_{j.lower()}_interval_mm"] = [lo, hi] if has else [0.0, 0.0]
            out[f"clearance_{j.lower()}_if_faulty_mm"] = {"median": mid, "interval_90": [lo, hi]}
        return out


def _check_ranges(ranges: Any, ref: Any, n_features: int) -> None:
    """Raise ValueError unless ``ranges`` (training ranges, :func:`twin.identification.ranges.training_ranges`)
    and ``ref`` (None, or the features' quartiles) are well formed."""
    pairs = [ranges["crank_hz"], ranges["noise_ug_rthz"], *ranges["ripple_pct"]]
    if not all(len(p) == 2 and all(math.isfinite(float(x)) for x in p) and float(p[0]) <= float(p[1]) for p in pairs):
        raise ValueError("ranges malformed")
    if not all(isinstance(o, str) for o in ranges["orientations"]) or not isinstance(ranges["source"], str):
        raise ValueError("ranges.orientations or ranges.source malformed")
    if ref is not None and not (len(ref["q25"]) == len(ref["q75"]) == n_features):
        raise ValueError("feature_reference malformed")
    if ref is not None and ref.get("max_outliers") is not None and not (
            isinstance(ref["max_outliers"], int) and 0 <= ref["max_outliers"] <= n_features):
        raise ValueError("feature_reference.max_outliers malformed")


def _check_held_out(table: Any) -> None:
    """Raise ValueError unless ``table`` (None, or :func:`train`'s ``held_out_size_accuracy``) is well formed."""
    if table is None:
        return
    if not (isinstance(table, dict) and {"B", "C"} <= set(table)):
        raise ValueError("held_out_size_accuracy malformed: needs a table for each of B and C")
    for j in ("B", "C"):
        for o, e in table[j].items():
            hz, within, runs = e["crank_hz"], e["within"], e["runs"]
            if not (isinstance(o, str) and len(hz) == len(within) == len(runs) > 0
                    and all(isinstance(h, (int, float)) and math.isfinite(h) and h > 0 for h in hz)
                    and all(a < b for a, b in zip(hz, hz[1:]))
                    and all(isinstance(x, (int, float)) and 0 <= x <= 1 for x in within)
                    and all(isinstance(n, int) and n > 0 for n in runs)):
                raise ValueError(f"held_out_size_accuracy.{j}.{o} malformed")


def size_resolved(joint: str, orientation: str, crank_hz: float) -> bool:
    """Whether the bench's sensors resolve the size of a clearance at ``joint`` ("B" or "C") at this
    crank rate [Hz] with ``orientation`` vertical (:data:`SIZE_RESOLVED_FROM_RPM`; 2 % allowance for
    the measured rate)."""
    rpm = SIZE_RESOLVED_FROM_RPM[joint].get(orientation)
    return rpm is not None and abs(crank_hz) * 60.0 * BELT_RATIO >= 0.98 * rpm


def resolution(orientation: str, crank_hz: float) -> dict[str, bool]:
    """:func:`size_resolved` at both joints: {"B": bool, "C": bool}."""
    return {j: size_resolved(j, orientation, crank_hz) for j in ("B", "C")}


#: the joints whose interval half widths the shipped model splits by the located fault (sixth round on)
FAULT_SPLIT_JOINTS = ("C",)


def fault_split_joints(value: Any) -> tuple[str, ...]:
    """The joints whose half widths are split by the fault, from ``train(fault_split=...)`` or a model file's
    ``trained_on.interval.fault_split``: True (both joints, as the fifth round's development models recorded),
    False or None (none), or a list of distinct joints ("B", "C"). Raises ValueError on anything else."""
    if value is None or value is False:
        return ()
    if value is True:
        return ("B", "C")
    if isinstance(value, (list, tuple)) and all(isinstance(j, str) and j in ("B", "C") for j in value) \
            and len(set(value)) == len(value):
        return tuple(sorted(value))
    raise ValueError(f"fault_split: {value!r}; allowed: true, false, or a list of distinct joints from B, C")


def rippled(ripple_pct: list[float] | None, band_pct: float = RIPPLE_BAND_PCT) -> bool:
    """Whether a recording's measured within-turn ripple [% of the speed, per harmonic] exceeds ``band_pct``
    (:data:`RIPPLE_BAND_PCT`; a model uses the value it was trained with) at some harmonic (False where it was
    not measured)."""
    return ripple_pct is not None and len(ripple_pct) > 0 and max(float(v) for v in ripple_pct) > band_pct


def normalized_scale(scores: np.ndarray, spread: np.ndarray, beta: float | None = None) -> dict[str, float]:
    """Normalized split-conformal scale from runs' out-of-fold scores |log10 answer − log10 truth| and
    difficulties (:func:`logs_spread`) [log10]: beta (default: the median difficulty, at least
    :data:`SPREAD_FLOOR_LOG10`) and q, the conformal rank of score / (difficulty + beta); an answer's half
    width is then q (difficulty + beta)."""
    spread = np.asarray(spread, float)
    if beta is None:
        beta = max(float(np.median(spread)), SPREAD_FLOOR_LOG10)
    return {"q": conformal_half_width(np.asarray(scores, float) / (spread + beta)), "beta": float(beta)}


def logs_spread(logs: np.ndarray) -> float:
    """Difficulty of a recording for a size regressor: the spread of its per-window answers ``logs`` [log10], their
    interquartile range over 1.349 (the standard deviation of a normal sample) [log10]; 0 for one window."""
    if len(logs) < 2:
        return 0.0
    q1, q3 = np.quantile(np.asarray(logs, float), [0.25, 0.75])
    return float(q3 - q1) / 1.349


def size_answer(reg: Any, X: np.ndarray) -> float:
    """A recording's clearance [mm] from its windows' features (:func:`logs_answer` of the regressor's answers)."""
    return logs_answer(reg.predict(X))


def logs_answer(logs: np.ndarray) -> float:
    """A clearance [mm] from per-window answers ``logs`` [log10]: their median, to 12 significant digits
    (10 ** log10(0.02) is 0.020000000000000004, which would put a trained value just outside an interval that
    ends on it)."""
    return float(f"{10 ** float(np.median(logs)):.12g}")


def conformal_half_width(scores: np.ndarray, coverage: float = COVERAGE) -> float:
    """Split-conformal half width from the runs' out-of-fold scores: the ceil((n + 1) coverage)-th
    smallest (the largest where n is too small for that rank) [log10]."""
    s = np.sort(np.asarray(scores, float))
    if s.size == 0:
        raise ModelError("no out-of-fold scores to calibrate the intervals")
    return float(s[min(int(math.ceil((s.size + 1) * coverage)), s.size) - 1])


# ------------------------------------------------------------------ training data
def run_features(path: str, skip_s: float, counts_per_rev: float, orientation: str = "y",
                 hop_revs: float = REVS_PER_WINDOW) -> tuple[np.ndarray, float, dict[str, Any]] | str:
    """Window features of one dataset run file (windows ending every ``hop_revs`` turns:
    :func:`twin.identification.features.steady_windows`), its crank rate [Hz] and its measures
    (:func:`twin.identification.ranges.recording_measures`), or the reason it has none."""
    from twin.identification.ranges import recording_measures

    from twin.dataset.storage import read_columns, read_meta

    meta = read_meta(path)
    cols = read_columns(path, [f"meas_{s}" for s in ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6")] + ["encoder_counts"])
    acc = {k[5:]: v for k, v in cols.items() if k.startswith("meas_")}
    try:
        X, w = features(acc, cols["encoder_counts"], float(meta["rate_hz"]), counts_per_rev, skip_s, orientation,
                        hop_revs=hop_revs)
    except IdentifyError as err:
        return str(err)
    return X, w.crank_hz, recording_measures(acc, cols["encoder_counts"], float(meta["rate_hz"]), counts_per_rev, w)


def dataset_features(ds, splits: tuple[str, ...], workers: int = 1, hop_revs: float = REVS_PER_WINDOW
                     ) -> tuple[np.ndarray, list[dict[str, Any]], list[int], list[dict[str, Any]]]:
    """Features of every ok run of ``splits`` (windows ending every ``hop_revs`` turns): (X [windows, features],
    run rows, window -> row index, runs left out with their reason)."""
    needed = [f"meas_AC{i}" for i in range(1, 7)] + ["encoder_counts"]
    missing = [c for c in needed if c not in ds.channels]
    if missing:
        raise ModelError(f"{ds.path}: the dataset lacks {', '.join(missing)} (a dataset for identification needs "
                         "outputs.instrumented with counts and calibrated)")
    cpr = float(ds.info.get("encoder_counts_per_rev") or 32768)
    rows = [r for r in ds.rows() if r["split"] in splits]
    if not rows:
        raise ModelError(f"{ds.path}: no finished runs in the split(s) {', '.join(splits)}")
    paths = [str(ds.path / r["file"]) for r in rows]
    results = []
    if workers > 1:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn")) as ex:
            results = list(ex.map(run_features, paths, [0.0] * len(paths), [cpr] * len(paths),
                                  [r["orientation"] for r in rows], [hop_revs] * len(paths), chunksize=4))
    else:
        results = [run_features(p, 0.0, cpr, r["orientation"], hop_revs) for p, r in zip(paths, rows)]
    X, kept, owner, skipped = [], [], [], []
    for r, res in zip(rows, results):
        if isinstance(res, str):
            skipped.append({"run_id": r["run_id"], "reason": res})
            continue
        Xr, hz, measures = res
        r = dict(r, crank_hz=hz, measures=measures)
        owner += [len(kept)] * len(Xr)
        kept.append(r)
        X.append(Xr)
    if not X:
        raise ModelError(f"{ds.path}: no run has {REVS_PER_WINDOW} steady crank revolutions to identify")
    return np.concatenate(X), kept, owner, skipped


def pooled_features(dataset_dirs: list[str | Path], splits: tuple[str, ...], workers: int,
                    hop_revs: float = REVS_PER_WINDOW
                    ) -> tuple[np.ndarray, list[dict[str, Any]], list[int], list[dict[str, Any]], list[Any]]:
    """Features of several datasets pooled (runs keep their rows, with the dataset's name; windows ending every
    ``hop_revs`` turns, :func:`twin.identification.features.steady_windows`); the
    datasets must agree on sample rate and encoder resolution (checked before any feature is computed).
    They may come from different engines: the engines' contact laws differ as a bench's differs from both,
    and a model trained on both spans that difference as one more nuisance."""
    from twin.dataset import open as open_dataset

    dss = [open_dataset(d) for d in dataset_dirs]
    _check_poolable(dss)
    parts = []
    for ds in dss:
        X, r, o, sk = dataset_features(ds, splits, workers, hop_revs)
        parts.append((X, [dict(x, dataset=ds.info["name"]) for x in r], o, sk, [ds]))
    return pool_features(parts)


def pool_features(parts: list[tuple]) -> tuple[np.ndarray, list[dict[str, Any]], list[int], list[dict[str, Any]],
                                               list[Any]]:
    """Pool what :func:`pooled_features` returns for datasets taken one by one (e.g. features computed
    before and kept): rows and windows concatenated, each window's run index shifted; the datasets must
    agree as :func:`pooled_features` requires."""
    _check_poolable([ds for part in parts for ds in part[4]])
    Xs, rows, owner, skipped, dss = [], [], [], [], []
    for X, r, o, sk, d in parts:
        owner += [len(rows) + int(i) for i in o]
        rows += r
        Xs.append(X)
        skipped += sk
        dss += d
    return np.concatenate(Xs), rows, owner, skipped, dss


def _check_poolable(dss: list[Any]) -> None:
    """Raise ModelError unless the datasets agree on sample rate and encoder resolution (not the engine:
    :func:`pooled_features`)."""
    first = None
    for ds in dss:
        key = {"rate_hz": ds.rate_hz,
               "encoder_counts_per_rev": float(ds.info.get("encoder_counts_per_rev") or 32768)}
        if first is None:
            first = (ds.path, key)
            continue
        for k, v in key.items():
            if v != first[1][k]:
                raise ModelError(f"{ds.path}: {k} is {v!r}, {first[0]} has {first[1][k]!r}: datasets pooled together "
                                 "must agree on sample rate and encoder resolution")


INTERVAL_FOLDS = ("runs", "speed")
#: settings of the per-joint size regressor (scikit-learn's ``HistGradientBoostingRegressor`` on log10 of the
#: clearance; leaves of at most 20 windows, fewer on small datasets). ``mean`` (the default from the third round on):
#: squared error, 1000 trees of 31 leaves at a learning rate of 0.05; ``median``: the quantile loss at 50 %, 300
#: trees of 15 leaves at 0.08 (the first two rounds' models). On the development sets, trained on the same runs,
#: ``mean`` read B's size within x1.5 in 84-92 % of the resolved runs against 78-89 % (``analysis/identify/
#: nuisance_study.py``, variants ``small-mean`` and ``small``)
SIZE_REGRESSORS = {
    "mean": dict(loss="squared_error", max_iter=1000, learning_rate=0.05, max_leaf_nodes=31, l2_regularization=1.0),
    "median": dict(loss="quantile", quantile=0.5, max_iter=300, learning_rate=0.08, max_leaf_nodes=15,
                   l2_regularization=1.0),
}


def _conformal_folds(rows: list[dict[str, Any]], runs: np.ndarray, how: str, seed: int) -> np.ndarray:
    """Fold of every row (−1: not in ``runs``): ``runs``, CONFORMAL_FOLDS random groups of whole runs;
    ``speed``, one fold per motor speed (the crank rate to 0.01 Hz where a run has none), so that every
    score is an answer at a speed the fitted regressor never saw, as a recording's may be."""
    fold = np.full(len(rows), -1)
    if how == "runs":
        perm = np.random.default_rng(seed).permutation(runs)
        fold[perm] = np.arange(len(perm)) % CONFORMAL_FOLDS
        return fold

    def key(r: dict[str, Any]) -> float:
        rpm = r.get("motor_rpm")
        return float(rpm) if rpm is not None and math.isfinite(float(rpm)) else round(float(r["crank_hz"]), 2)

    speeds = sorted({key(rows[int(i)]) for i in runs})
    if len(speeds) < 3:
        raise ModelError(f"interval folds by speed need runs at 3 speeds or more, the training runs have {len(speeds)}")
    for i in runs:
        fold[int(i)] = speeds.index(key(rows[int(i)]))
    return fold


def _mondrian(parts: list[tuple[str, np.ndarray]], mask: np.ndarray, suffix: str) -> list[tuple[str, np.ndarray]]:
    """Each (key, runs) of ``parts`` split by ``mask`` into (key, runs outside it) and (key + ``suffix``, runs inside
    it) where both sides hold MONDRIAN_MIN_RUNS runs; kept whole otherwise."""
    out: list[tuple[str, np.ndarray]] = []
    for key, m in parts:
        if (m & mask).sum() >= MONDRIAN_MIN_RUNS and (m & ~mask).sum() >= MONDRIAN_MIN_RUNS:
            out += [(key, m & ~mask), (f"{key}{suffix}", m & mask)]
        else:
            out.append((key, m))
    return out


def _interval_parts(j: str, held_runs: list[dict[str, Any]], answers: np.ndarray,
                    size_band_mm: float | list[float] | None, ripple_split: bool,
                    fault_split: bool = False) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The out-of-fold runs of each half width at joint ``j`` (key -> mask; see the module docstring): all runs
    (key ``j``); split (Mondrian) by the joint's size-resolution map where each side has MONDRIAN_MIN_RUNS runs
    (``j``, ``j_unresolved``), each side by the runs' measured ripple (``_rippled``) where both parts have enough,
    with ``fault_split`` each part by whether both joints are faulty (``_both``) where both parts have enough,
    and each part by the answer's size (``_small``, ``_small2``, ...: below each boundary of ``size_band_mm``,
    largest first) where both sides of a boundary have enough. Also the
    parts before the split by size (those of the normalized scales)."""
    everything = np.ones(len(held_runs), bool)
    parts = {j: everything}
    on = np.array([size_resolved(j, row["orientation"], row["crank_hz"]) for row in held_runs], bool)
    split = _mondrian([(j, everything)], ~on, "_unresolved")
    if ripple_split:
        split = _mondrian(split, np.array([rippled(row.get("measures", {}).get("ripple_pct")) for row in held_runs],
                                          bool), "_rippled")
    if fault_split:
        split = _mondrian(split, np.array([row.get("fault") == "BC" for row in held_runs], bool), "_both")
    for side, m in split:
        parts[side] = m
        rest, upper = m, side  # answers below the last boundary used, and their key
        for i, band in enumerate(size_bands(size_band_mm), start=1):
            small = rest & (answers < band)
            if small.sum() < MONDRIAN_MIN_RUNS or (rest & ~small).sum() < MONDRIAN_MIN_RUNS:
                continue  # too few runs on a side: this boundary is not used, its band stays with the one above
            parts[upper], parts[_band_key(side, i)] = rest & ~small, small
            rest, upper = small, _band_key(side, i)
    return parts, dict(split)


def size_bands(size_band_mm: float | list[float] | tuple[float, ...] | None) -> list[float]:
    """The answer-size boundaries of the intervals' Mondrian split [mm], largest first (``size_band_mm``: one
    boundary, several, or None for no split)."""
    if not size_band_mm:
        return []
    if isinstance(size_band_mm, (int, float)):
        return [float(size_band_mm)]
    return sorted((float(b) for b in size_band_mm), reverse=True)


def recorded_size_bands(size_band_mm: float | list[float] | tuple[float, ...] | None) -> float | list[float] | None:
    """``size_band_mm`` as a model file records it (``trained_on.interval.size_band_mm``): None or one number as
    given, several boundaries as a list, largest first."""
    return size_band_mm if size_band_mm is None or isinstance(size_band_mm, (int, float)) else size_bands(size_band_mm)


def _band_key(side: str, i: int) -> str:
    """Key of the half width of answers below the i-th largest size boundary on ``side`` (0: above them all), down
    to the next boundary used: ``side``, ``side_small``, ``side_small2``, ..."""
    return side if i == 0 else f"{side}_small" if i == 1 else f"{side}_small{i}"


def band_half_width(half: dict[str, float], side: str, answer_mm: float,
                    size_band_mm: float | list[float] | None) -> float:
    """Half width [log10] for an answer of ``answer_mm`` on ``side``: that of the band of the smallest boundary
    above the answer that the model used (a boundary with too few training runs on a side is not used: its
    answers belong to the band above it)."""
    depth = sum(answer_mm < b for b in size_bands(size_band_mm))
    for i in range(depth, 0, -1):
        if _band_key(side, i) in half:
            return half[_band_key(side, i)]
    return half[side]


def _half_widths(j: str, scores: np.ndarray, held_runs: list[dict[str, Any]], answers: np.ndarray,
                 size_band_mm: float | list[float] | None, ripple_split: bool, by_engine: bool,
                 fault_split: bool = False) -> dict[str, float]:
    """Conformal half width [log10] of each part of :func:`_interval_parts` from the out-of-fold scores; with
    ``by_engine``, where the runs come from several engines (the rows' ``engine``), each half width is the largest
    of the pooled runs' and of each engine's runs' alone (an engine of MONDRIAN_MIN_RUNS runs or more, split the
    same way where its runs allow): the bench's contact law is neither engine's, and an interval calibrated on
    the pooled runs holds the engine that is easier for the regressor more often than the other."""
    half = {key: conformal_half_width(scores[m])
            for key, m in _interval_parts(j, held_runs, answers, size_band_mm, ripple_split, fault_split)[0].items()}
    engine = np.array([str(row.get("engine", "")) for row in held_runs])
    for e in sorted(set(engine)) if by_engine else []:
        idx = np.flatnonzero(engine == e)
        if len(idx) < MONDRIAN_MIN_RUNS or len(idx) == len(engine):
            continue
        sub, _ = _interval_parts(j, [held_runs[i] for i in idx], answers[idx], size_band_mm, ripple_split, fault_split)
        for key, m in sub.items():
            if key in half:
                half[key] = max(half[key], conformal_half_width(scores[idx][m]))
    return half


def window_table(interval: dict[str, Any], windows: int) -> dict[str, float]:
    """The half widths [log10] of answers from ``windows`` windows in a model's ``interval`` record
    (``half_width_log10_by_windows``, :func:`_half_widths_by_windows`); empty where it holds none for that count
    (an answer then takes the main table)."""
    return (interval.get("half_width_log10_by_windows") or {}).get(str(windows), {})


def _half_widths_by_windows(j: str, window_logs: list[np.ndarray], held_runs: list[dict[str, Any]],
                            size_band_mm: float | list[float] | None, ripple_split: bool, by_engine: bool,
                            fault_split: bool = False) -> dict[str, dict[str, float]]:
    """Half widths [log10] of answers made from fewer windows than the training runs hold: for n = 1, 2, ... up to
    one less than the most windows of a run, those of :func:`_half_widths` calibrated on each out-of-fold run's
    answer from its first n windows (all of them where it has fewer; ``window_logs``: per run, the regressor's
    per-window answers [log10]), keyed by str(n). A recording answered from n windows takes the n-window table: its
    answer scatters as a training run's first n windows do, more than the run's answer from all of its windows (a
    0.8 s recording at 750 rpm has one window of two turns, a 3 s training run four)."""
    truth = np.array([math.log10(row[f"clearance_{j.lower()}_mm"]) for row in held_runs], float)
    most = max((len(w) for w in window_logs), default=0)
    out: dict[str, dict[str, float]] = {}
    for n in range(1, most):
        answers = np.array([logs_answer(w[:n]) for w in window_logs])
        scores = np.abs(np.log10(answers) - truth)
        out[str(n)] = _half_widths(j, scores, held_runs, answers, size_band_mm, ripple_split, by_engine, fault_split)
    return out


#: the factor of the truth within which an out-of-fold answer counts in the held-out size accuracy (the targets')
HELD_OUT_FACTOR = 1.5


def held_out_accuracy(scores: np.ndarray, held_runs: list[dict[str, Any]]) -> dict[str, dict[str, list]]:
    """The held-out size accuracy of one joint from its out-of-fold scores (:func:`train`): per orientation, at
    each training speed (the runs' motor speed; placed at the median of their crank rates [Hz]), the share of the
    runs whose answer lies within a factor :data:`HELD_OUT_FACTOR` of the truth and the number of runs. With
    ``interval_folds="speed"`` each answer was made by a regressor that never saw that speed, as a bench
    recording's may be."""
    lim = math.log10(HELD_OUT_FACTOR) + 1e-12
    groups: dict[tuple[str, float], list[tuple[float, bool]]] = {}
    for score, row in zip(np.asarray(scores, float), held_runs):
        hz = float(row["crank_hz"])
        rpm = row.get("motor_rpm")
        key = (str(row["orientation"]), float(rpm) if rpm is not None else round(hz, 2))
        groups.setdefault(key, []).append((hz, bool(score <= lim)))
    at: dict[str, dict[float, list[bool]]] = {}  # orientation -> crank rate of a speed -> its runs' outcomes
    for (o, _), v in groups.items():
        at.setdefault(o, {}).setdefault(round(float(np.median([h for h, _ in v])), 4), []).extend(ok for _, ok in v)
    return {o: {"crank_hz": sorted(by), "within": [round(float(np.mean(by[h])), 4) for h in sorted(by)],
                "runs": [len(by[h]) for h in sorted(by)]} for o, by in sorted(at.items())}


def held_out_at(table: dict[str, Any] | None, orientation: str, crank_hz: float) -> dict[str, Any] | None:
    """What the held-out size accuracy (:func:`held_out_accuracy`) says of a recording at ``crank_hz`` [Hz] with
    ``orientation`` vertical: the share within the factor, interpolated linearly in the crank rate between the two
    training speeds around it (the nearest one outside them), the runs behind it and the training speeds' crank
    rates used; None where the model holds no table or no run of that orientation."""
    e = (table or {}).get(orientation)
    if not e or not e["crank_hz"]:
        return None
    hz, within, runs = (np.asarray(e[k], float) for k in ("crank_hz", "within", "runs"))
    k = int(np.searchsorted(hz, crank_hz))
    if k == 0 or k == len(hz):
        i = 0 if k == 0 else len(hz) - 1
        share, n, used = within[i], runs[i], [hz[i]]
    else:
        t = (crank_hz - hz[k - 1]) / (hz[k] - hz[k - 1])
        share, n, used = (1 - t) * within[k - 1] + t * within[k], runs[k - 1] + runs[k], [hz[k - 1], hz[k]]
    return {"within_factor": HELD_OUT_FACTOR, "share": round(float(share), 3), "runs": int(n),
            "training_crank_hz": [float(h) for h in used]}


def _dataset_use(b: bool, c: bool) -> dict[str, str]:
    """What a training dataset taught (the model file's ``trained_on.datasets``): nothing said where it taught
    the location and both sizes."""
    if b and c:
        return {}
    return {"use": "location and the size at B" if b else "location and the size at C" if c else "location only"}


def train(dataset_dir: str | Path | list[str | Path], splits: tuple[str, ...] = ("train", "val"), workers: int = 1,
          seed: int = 0, interval_folds: str = "runs", location_only: list[str | Path] = (),
          size_only_at: dict[str, list[str | Path]] | None = None, features: tuple | None = None,
          normalized_intervals: bool = False,
          size_band_mm: float | list[float] | tuple[float, ...] | None = CATALOGUE_BANDS_MM, ripple_split: bool = True,
          size_regressor: str = "mean", interval_by_engine: bool = True, out_of_fold: dict[str, Any] | None = None,
          answer_hop_revs: float = ANSWER_HOP_REVS, fault_split: bool | list[str] | tuple[str, ...] = FAULT_SPLIT_JOINTS,
          by_windows: bool = True) -> tuple[ClearanceModel, dict[str, Any]]:
    """Train on the ok runs of ``splits`` of one dataset or several pooled (see module docstring);
    ``interval_folds`` groups the out-of-fold scores of the intervals (:func:`_conformal_folds`);
    the runs of the ``location_only`` datasets (pooled like the others) teach the location model
    only, not the size regressors nor their intervals (e.g. runs at one speed in a regime the others
    lack, which would tilt the size regressors toward that speed); the runs of ``size_only_at[J]`` (J: ``"B"`` or
    ``"C"``) teach the location model and the size at J only, not the other joint's regressor nor its intervals
    (e.g. runs drawn to fill slow speeds at B, whose clearances at C would tilt C's regressor toward those speeds).
    ``features``: what :func:`pooled_features` returns for these datasets and splits (in the order: the datasets,
    then ``size_only_at["B"]``, ``size_only_at["C"]``, ``location_only``), computed before (a study that trains
    several variants on the same runs computes them once). ``normalized_intervals``: also store the
    normalized conformal scales (module docstring); ``size_band_mm``: split each side of the
    size-resolution map's intervals by the answer's size at these boundaries (default: one band per group of
    catalogue values, :data:`CATALOGUE_BANDS_MM`; one number: below and above it, as the models before the fourth
    round; None: no split); ``ripple_split``: split each side
    first by the runs' measured ripple (:data:`RIPPLE_BAND_PCT`); ``size_regressor``: a key of
    :data:`SIZE_REGRESSORS`; ``interval_by_engine``: where the runs come from several engines, each half width is
    the largest of the pooled runs' and each engine's runs' (those with MONDRIAN_MIN_RUNS runs or more), so that
    it holds for each contact law alone. ``out_of_fold``: a dict that receives, per joint, the out-of-fold
    ``scores``, ``runs`` (rows), ``answers`` and per run its windows' answers ``window_logs`` [log10] the half widths
    are calibrated on (a study that compares interval options re-calibrates from them with :func:`_half_widths` and
    :func:`_half_widths_by_windows` without fitting again). ``answer_hop_revs``: where a
    recording's answer windows end (:data:`ANSWER_HOP_REVS`); the estimators learn, and the out-of-fold answers are
    made, from the training runs' windows cut back to back (``features``). ``fault_split``: the joints (a list, or
    True for both, False for none) whose intervals' parts are split also by whether both joints are faulty
    (``_both``; the training runs' true fault, a recording's located one), where both sides have MONDRIAN_MIN_RUNS
    runs: the other joint's impacts reach a joint's sensors and scatter its size (recorded as
    ``trained_on.interval.fault_split``, the list of joints; default :data:`FAULT_SPLIT_JOINTS`, C only).
    ``by_windows`` (the default from the sixth round on; with windows back to back only): also the half widths of
    answers from 1, 2, ... windows, calibrated on the out-of-fold runs' first windows
    (:func:`_half_widths_by_windows`, ``trained_on.interval.half_width_log10_by_windows``)."""
    try:
        split_by_fault = fault_split_joints(fault_split)
    except ValueError as err:
        raise ModelError(str(err)) from None
    if interval_folds not in INTERVAL_FOLDS:
        raise ModelError(f"interval_folds: {interval_folds!r}; allowed: {', '.join(INTERVAL_FOLDS)}")
    if not hop_ok(answer_hop_revs):
        raise ModelError(f"answer_hop_revs: {answer_hop_revs!r}; allowed: {MIN_HOP_REVS} <= answer_hop_revs <= {REVS_PER_WINDOW}")
    if size_regressor not in SIZE_REGRESSORS:
        raise ModelError(f"size_regressor: {size_regressor!r}; allowed: {', '.join(SIZE_REGRESSORS)}")
    from sklearn.ensemble import HistGradientBoostingClassifier, HistGradientBoostingRegressor

    dirs = [dataset_dir] if isinstance(dataset_dir, (str, Path)) else list(dataset_dir)
    if not dirs:
        raise ModelError("no dataset to train on")
    only = dict(size_only_at or {})
    bad = [j for j in only if j not in ("B", "C")]
    if bad:
        raise ModelError(f"size_only_at: joint {bad[0]!r}; allowed: B, C")
    n_both, n_b = len(dirs), len(only.get("B", ()))
    dirs += list(only.get("B", ())) + list(only.get("C", ()))
    n_size = len(dirs)
    dirs += list(location_only)
    seen: set[Path] = set()
    for d in dirs:  # a folder named twice would put its runs in twice, and what it teaches is decided by its name
        if Path(d).resolve() in seen:
            raise ModelError(f"{d}: dataset folder given twice (training sets, size-only and location-only sets): "
                             "give each once")
        seen.add(Path(d).resolve())
    t0 = time.perf_counter()
    X, rows, owner, skipped, dss = features if features is not None else pooled_features(dirs, splits, workers)
    y = np.array([rows[i]["fault"] for i in owner])
    names = [d.info["name"] for d in dss]
    size_names = {"B": set(names[:n_both + n_b]), "C": set(names[:n_both] + names[n_both + n_b:n_size])}
    for_size = {j: np.array([rows[i]["dataset"] in size_names[j] for i in owner]) for j in ("B", "C")}
    t_feat = time.perf_counter() - t0
    # leaves of at least 20 windows (scikit-learn's default) on datasets of a thousand windows and
    # more; smaller datasets (tests, first looks) get smaller leaves, and no early stopping below 500
    leaf = int(min(20, max(3, len(X) // 48)))
    clf = HistGradientBoostingClassifier(max_iter=400, learning_rate=0.08, max_leaf_nodes=15, l2_regularization=1.0,
                                         min_samples_leaf=leaf, class_weight="balanced",
                                         early_stopping=len(X) >= 500, validation_fraction=0.15, random_state=seed)
    clf.fit(X, y)
    classifier = from_sklearn(clf, check=X)  # what the file holds: answers equal bit for bit, checked
    size: dict[str, Any] = {}
    half_width: dict[str, float] = {}
    held_out: dict[str, Any] = {}
    normalized: dict[str, dict[str, float]] = {}
    by_windows: dict[str, dict[str, float]] = {}  # half widths of answers from 1, 2, ... windows
    n_folds: dict[str, int] = {}
    owner_a = np.asarray(owner)
    for j in ("B", "C"):
        key = f"clearance_{j.lower()}_mm"
        truth = np.array([rows[i][key] for i in owner], float)
        sel = (truth > 0) & for_size[j]
        if sel.sum() < 10:
            raise ModelError(f"{', '.join(map(str, dirs))}: fewer than 10 windows with a clearance at {j}: cannot "
                             "learn its size")

        def fit(use: np.ndarray) -> Any:
            reg = HistGradientBoostingRegressor(**SIZE_REGRESSORS[size_regressor],
                                                min_samples_leaf=int(min(20, max(3, int(use.sum()) // 48))),
                                                random_state=seed)
            return reg.fit(X[use], np.log10(truth[use]))

        size[j] = from_sklearn(fit(sel), check=X[sel])
        # out-of-fold scores of whole runs (see module docstring)
        fold = _conformal_folds(rows, np.unique(owner_a[sel]), interval_folds, seed)
        n_folds[j] = int(fold.max()) + 1
        scores, held_runs, spread, answers, window_logs = [], [], [], [], []
        for k in range(n_folds[j]):
            held = sel & (fold[owner_a] == k)
            if not held.any() or (sel & ~held).sum() < 10:
                continue
            reg = fit(sel & ~held)
            for r in np.unique(owner_a[held]):
                Xr = X[owner_a == r]
                window_logs.append(reg.predict(Xr))  # one prediction per run: its answer and spread
                answers.append(logs_answer(window_logs[-1]))
                scores.append(abs(math.log10(answers[-1]) - math.log10(rows[int(r)][key])))
                spread.append(logs_spread(window_logs[-1]))
                held_runs.append(rows[int(r)])
        scores, spread, answers = np.array(scores), np.array(spread), np.array(answers)
        if out_of_fold is not None:
            out_of_fold[j] = {"scores": scores, "runs": held_runs, "answers": answers, "window_logs": window_logs}
        if normalized_intervals:
            normalized[j] = normalized_scale(scores, spread)
        half_width |= _half_widths(j, scores, held_runs, answers, size_band_mm, ripple_split, interval_by_engine,
                                   j in split_by_fault)
        if by_windows and float(answer_hop_revs) == REVS_PER_WINDOW:
            for n, half in _half_widths_by_windows(j, window_logs, held_runs, size_band_mm, ripple_split,
                                                   interval_by_engine, j in split_by_fault).items():
                by_windows.setdefault(n, {}).update(half)
        held_out[j] = held_out_accuracy(scores, held_runs)
        if normalized_intervals:
            for key, m in _interval_parts(j, held_runs, answers, size_band_mm, ripple_split,
                                          j in split_by_fault)[1].items():
                normalized[key] = normalized_scale(scores[m], spread[m], normalized[j]["beta"])
    import sklearn

    from twin import __version__

    infos = [ds.info for ds in dss]
    ident = infos[0]["identity"] if len(infos) == 1 else [i["identity"] for i in infos]  # one dataset: as before
    digest = hashlib.sha256(json.dumps(ident, sort_keys=True).encode()).hexdigest()[:16]
    hz = np.array([r["crank_hz"] for r in rows])
    trained_on = {
        "dataset": "+".join(i["name"] for i in infos), "dataset_dir": ", ".join(map(str, dirs)),
        "datasets": [{"name": i["name"], "runs": sum(1 for r in rows if r["dataset"] == i["name"])}
                     | _dataset_use(i["name"] in size_names["B"], i["name"] in size_names["C"]) for i in infos],
        "identity_sha256": digest,
        "engine": "+".join(dict.fromkeys(i["identity"]["engine"] for i in infos)), "rate_hz": dss[0].rate_hz,
        "counts_per_rev": float(infos[0].get("encoder_counts_per_rev") or 32768),
        "splits": list(splits), "runs": len(rows), "windows": int(len(X)), "runs_left_out": skipped,
        "crank_hz_range": [float(hz.min()), float(hz.max())],
        "clearances_mm": {j: _clearances_seen([float(r[f"clearance_{j.lower()}_mm"]) for r in rows]) for j in ("B", "C")},
        "orientations": sorted({r["orientation"] for r in rows}),
        "classes": {c: int(np.sum(y == c)) for c in CLASSES},
        "versions": {"twin": __version__, "sklearn": sklearn.__version__, "numpy": np.__version__},
        "size_regressor": size_regressor,
        "answer_hop_revs": float(answer_hop_revs),
        "held_out_size_accuracy": held_out | {
            "method": f"out-of-fold answers of the training runs (folds by {interval_folds}), per orientation and "
                      f"training speed: the share within a factor {HELD_OUT_FACTOR:g} of the truth"},
        "interval": {"method": "split-conformal, out of fold", "folds_by": interval_folds, "folds": n_folds,
                     "coverage": COVERAGE,
                     "size_band_mm": recorded_size_bands(size_band_mm),
                     "ripple_band_pct": RIPPLE_BAND_PCT if ripple_split else None,
                     "by_engine": interval_by_engine,
                     "fault_split": list(split_by_fault),
                     "half_width_log10": half_width,
                     "half_width_log10_by_windows": by_windows,
                     "normalized": normalized,
                     "difficulty": "spread of the per-window answers: interquartile range of the windows' log10 "
                                   "answers / 1.349 [log10]"},
        "ranges": training_ranges([r["measures"] for r in rows], [r["orientation"] for r in rows],
                                  "measured on every training run (twin identify train)"),
        "feature_reference": feature_reference(X, np.asarray(owner)),
        "feature_seconds": t_feat, "fit_seconds": time.perf_counter() - t0 - t_feat,
    }
    return ClearanceModel(classifier, size, half_width, trained_on=trained_on), trained_on


def _clearances_seen(values: list[float]) -> list[float] | dict[str, Any]:
    """The clearances of the training runs: the list of values where there are few (a catalogue),
    else their range and count (clearances drawn continuously) [mm]."""
    distinct = sorted(set(values))
    if len(distinct) <= 12:
        return distinct
    nonzero = [v for v in distinct if v > 0]
    return {"min": nonzero[0], "max": nonzero[-1], "distinct": len(nonzero), "ball_bearing": 0.0 in distinct}


# ----------------------------------------------------------------- a recording
def recording_inputs(path: str | Path) -> tuple[dict[str, np.ndarray], np.ndarray, float, float, Any]:
    """Calibrated accelerations, encoder counts, rate, counts per turn and configuration of a bench
    recording (any recording ``twin replay`` accepts)."""
    from twin.instrument.calibration import measured_accel
    from twin.recording import read_recording

    rec, info, _ = read_recording(path)
    if "encoder_counts" not in rec:
        raise IdentifyError(f"{path}: the recording has no encoder_counts channel")
    if info.calibration is None:
        raise IdentifyError(f"{path}: no calibration data; re-import it with --calibration STATIC or --zero-g")
    meas = measured_accel(rec, info.calibration)
    acc = {k[5:]: np.asarray(v.data) for k, v in meas.channels.items()}
    cfg = rec.config
    cpr = float(cfg.instrumentation.encoder_counts_per_rev) if cfg else 32768.0
    return acc, np.asarray(rec["encoder_counts"]), rec.rate_hz, cpr, cfg


def simulated_inputs(run: Any, cfg: Any) -> tuple[dict[str, np.ndarray], np.ndarray, float, float]:
    """What :func:`recording_inputs` reads from a recording, made from a simulated ``run`` of ``cfg``
    (channels accel and encoder): the bench's sensor chain (``cfg.instrumentation``: sensor response,
    noise, DAQ, encoder counts) and the static calibration it would get. Returns the calibrated
    accelerations, encoder counts, rate and counts per turn."""
    from twin.instrument.calibration import measured_accel
    from twin.instrument.chain import apply_chain, simulated_calibration

    daq = apply_chain(run, cfg, command=False)
    meas = measured_accel(daq, simulated_calibration(cfg))
    acc = {k[5:]: np.asarray(v.data, float) for k, v in meas.channels.items()}
    return acc, np.asarray(daq["encoder_counts"], float), daq.rate_hz, float(cfg.instrumentation.encoder_counts_per_rev)


def training_check(model: ClearanceModel, ans: dict[str, Any], measures: dict[str, Any], orientation: str,
                   X: np.ndarray) -> tuple[list[str], dict[str, Any]]:
    """Check a recording's ``measures`` (:func:`twin.identification.ranges.recording_measures`), orientation and
    window features ``X`` against the model's training data (:func:`twin.identification.ranges.out_of_range`);
    outside, widen the intervals of the answer ``ans`` in place (:func:`twin.identification.ranges.widen`).
    Returns the warnings (one per reason) and the check's evidence."""
    tr = model.trained_on
    warnings, checks = out_of_range(measures, orientation, tr.get("ranges"), np.median(X, axis=0),
                                    tr.get("feature_reference"), model.feature_names)
    outside = bool(warnings)
    if outside:
        for j in ("B", "C"):
            key = f"clearance_{j.lower()}"
            wide = widen(ans[f"{key}_if_faulty_mm"]["interval_90"], tr["clearances_mm"][j])
            ans[f"{key}_if_faulty_mm"]["interval_90"] = wide
            if j in ans["fault"]:
                ans[f"{key}_interval_mm"] = wide
    checks["outside_training_data"] = outside
    few = f", calibrated on the training runs' answers from their first {len(X)} window{'s' * (len(X) > 1)} (as many " \
          "as this recording has)" if window_table(tr.get("interval", {}), len(X)) else ""
    checks["interval_rule"] = ("outside the training data: each interval widened to hold every clearance the model "
                               "was trained on at that joint (no calibrated interval exists there)" if outside else
                               f"inside the training data: the conformal 90 % interval{few}")
    return warnings, checks


def identify_recording(model: ClearanceModel, path: str | Path) -> dict[str, Any]:
    """The answer for a bench recording (see module docstring), with the evidence used."""
    t0 = time.perf_counter()
    acc, counts, rate, cpr, cfg = recording_inputs(path)
    orientation = cfg.mechanism.orientation if cfg is not None else "y"
    return identify_inputs(model, acc, counts, rate, cpr, orientation, str(path), t0)


def identify_inputs(model: ClearanceModel, acc: dict[str, np.ndarray], counts: np.ndarray, rate: float, cpr: float,
                    orientation: str, source: str = "", t0: float | None = None) -> dict[str, Any]:
    """The answer for calibrated accelerations and encoder counts (:func:`recording_inputs`,
    :func:`simulated_inputs`) of a bench with ``orientation`` vertical: location, sizes, intervals, and
    the checks against the training data (:mod:`twin.identification.ranges`): one warning per reason a
    recording is outside, and then each joint's interval widened to every clearance trained on there."""
    t0 = time.perf_counter() if t0 is None else t0
    tr = model.trained_on
    if abs(rate - tr["rate_hz"]) > 1e-6 * rate:
        raise ModelError(f"{source}: recorded at {rate:g} Hz, the model was trained at {tr['rate_hz']:g} Hz")
    X, w = features(acc, counts, rate, cpr, orientation=orientation, hop_revs=model.hop_revs)
    resolved = resolution(orientation, w.crank_hz)
    measures = recording_measures(acc, counts, rate, cpr, w)
    ans = model.identify(X, resolved, measures["ripple_pct"])
    warnings, checks = training_check(model, ans, measures, orientation, X)
    table = tr.get("held_out_size_accuracy") or {}
    for j in ("B", "C"):
        ans[f"clearance_{j.lower()}_size_resolved"] = resolved[j]  # which also chose the interval's width
        # how often the model's answers at this joint, speed and orientation held in training runs left out
        ans[f"clearance_{j.lower()}_size_held_out"] = held_out_at(table.get(j), orientation, w.crank_hz)
        if j in ans["fault"] and not resolved[j]:
            warnings.append(f"the size at {j} is not resolved at {w.crank_hz * 60 * BELT_RATIO:.0f} motor rpm with "
                            f"{orientation} vertical: the bench's sensors tell 0.05-0.1 mm at {j} apart from "
                            f"{SIZE_RESOLVED_FROM_RPM[j].get(orientation, float('nan')):g} rpm on (model card); "
                            "trust the location and the interval, not the size")
    ans.update({
        "recording": source,
        "warnings": warnings,
        "evidence": {"windows": len(w.windows), "revolutions": round(w.revolutions, 2),
                     "crank_hz": w.crank_hz, "motor_rpm_if_belt_3_97": w.crank_hz * 60 * BELT_RATIO,
                     "steady_s": (w.steady[1] - w.steady[0]) / rate, "features": len(model.feature_names),
                     "feature_version": model.feature_version,
                     "training_data_check": checks,
                     "model": {k: tr[k] for k in ("dataset", "identity_sha256", "engine", "crank_hz_range")}},
        "seconds": time.perf_counter() - t0,
    })
    if math.isfinite(ans["seconds"]):
        ans["seconds"] = round(ans["seconds"], 4)
    return ans
