"""The clearance identification model: its file, and the answer for a recording.

A :class:`ClearanceModel` holds

* the fault location: gradient-boosted trees over the classes none, B, C, BC, G, BG, CG, BCG (:data:`CLASSES`: which
  of the revolute joints B and C and the slider guide G have play; a model of format 4 knows none, B, C, BC) on the
  window features (:mod:`twin.identification.features`); a recording's class probabilities are the mean over its windows
  and the located fault the most probable class;
* per joint (B, C and, in a format-5 model trained on runs with guide play, the guide G), the clearance size:
  gradient-boosted trees on log10 of the diametral clearance (at G: the guide's two-sided play); a recording's size is
  the median over its windows (:func:`twin.identification.intervals.logs_answer`);
* per joint, the conformal half widths of the 90 % interval (:mod:`twin.identification.intervals`), and what it was
  trained on (``trained_on``: datasets, rates, clearances, orientations, ranges, held-out size accuracy).

:func:`identify_recording` answers a recording (:func:`identify_inputs` the inputs of one,
:mod:`twin.identification.inputs`) with an :class:`~twin.identification.results.IdentifyResult`: the location,
per joint the size and its interval (0 and (0, 0) at a joint located healthy: a ball bearing), whether the bench's
sensors resolve the size at that speed and orientation, the held-out accuracy there, and the checks against the
training data (:mod:`twin.identification.ranges`): a recording outside it (crank rate, ripple, noise, orientation,
feature distance) gets one warning per reason and each interval widened to every clearance trained on at that
joint. :mod:`twin.identification.training` makes a model.

Model file (format ``twin-identify-model/5``, suffix ``.npz``; :meth:`ClearanceModel.save`,
:meth:`ClearanceModel.load`): a NumPy ``.npz`` archive (a zip of ``.npy`` members, each with its
CRC-32) of plain arrays and one JSON text, read with ``allow_pickle=False``: loading it runs no code
from the file, and answering needs no scikit-learn. Members:

* ``model.json``: a 0-d unicode array holding JSON: ``format`` (``twin-identify-model/5``), ``joints`` (the
  locations the model sizes, in the mechanism's order: ["B", "C", "G"], or ["B", "C"] for a model trained without
  guide play),
  ``feature_version`` and ``feature_names`` (:mod:`twin.identification.features`), ``interval_log10`` (the
  conformal half widths [log10], :mod:`twin.identification.intervals`), ``trained_on`` (the training data, with ``versions``:
  twin, scikit-learn and numpy of the training; ``ranges``: the training runs' ranges of crank rate,
  within-turn ripple per harmonic, noise level and orientations, with their ``source``; ``feature_reference``:
  the training windows' feature quartiles, or null where unknown; ``interval.normalized``: the normalized
  conformal scale per joint, where trained; ``held_out_size_accuracy``
  (:func:`twin.identification.intervals.held_out_accuracy`) and ``answer_hop_revs``, where recorded; ``size_context``:
  true where the size regressors also read the other locations' play, two columns after the features,
  :func:`size_context`; ``size_weights``: ``"runs"`` where they weighed each training run alike; ``interval.hull_floor``: true where an
  interval within its half width of the smallest size trained reaches down to it,
  :func:`twin.identification.intervals.reach_hull_floor`), and ``estimators``: per estimator (``classifier``,
  ``size_B``, ``size_C``, ``size_G`` where the model sizes G) its kind (link: ``softmax`` for the classifier, ``identity`` for the size
  regressors), number of features (the size regressors of a ``size_context`` model: two more), trees per iteration, classes and source
  (:meth:`twin.identification.trees.TreeEnsemble.meta`);
* per estimator E, the arrays ``E.baseline``, ``E.tree_nodes``, ``E.feature``, ``E.threshold``,
  ``E.missing_left``, ``E.left``, ``E.right``, ``E.is_leaf``, ``E.value`` (dtypes and meaning:
  :mod:`twin.identification.trees`).

Loading refuses, in one line naming the file: anything but a zip archive (a pickle or ``.joblib``
file, as model format 2 was, is named as such and never unpickled), a damaged archive (CRC, truncation),
another format version (format 3 lacked the training ranges: ``analysis/identify/convert_model_ranges.py``
adds them; format 4, the same file without ``joints`` and with B and C only, is read as such), other members, an array of another dtype (object arrays included: never
unpickled), trees that a walk could not use safely, and a feature version this twin does not compute.
The scikit-learn estimators of the training are exported by :func:`twin.identification.trees.from_sklearn`,
whose answers are checked equal bit for bit on the training windows.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from twin.identification.features import FEATURE_VERSION, MIN_HOP_REVS, REVS_PER_WINDOW, feature_names, features, hop_ok
from twin.identification.intervals import (BELT_RATIO, RIPPLE_BAND_PCT, SIZE_RESOLVED_FROM_RPM, band_half_width,
                                           fault_split_joints, held_out_at, logs_answer, logs_spread, reach_hull_floor,
                                           resolution, rippled, window_table)
from twin.identification.ranges import (at_hull_top, clip_to_hull, out_of_range, recording_measures, trained_hull,
                                        widen)
from twin.identification.results import Evidence, HeldOut, IdentifyResult, JointAnswer
from twin.identification.trees import ModelError, TreeEnsemble, from_sklearn

__all__ = ["CLASSES", "ClearanceModel", "DEFAULT_MODEL", "MODEL_FORMAT", "MODEL_SUFFIX", "ModelError",
           "default_model_path", "shipped_model_path", "resolve_model", "identify_inputs", "identify_recording", "training_check"]

CLASSES = ("none", "B", "C", "BC", "G", "BG", "CG", "BCG")
#: the clearance locations a model may answer, in the mechanism's order: the revolute joints B and C, the slider guide G
JOINTS = ("B", "C", "G")
MODEL_FORMAT = "twin-identify-model/5"
#: the format before the guide was a location (B and C only), still read
MODEL_FORMAT_4 = "twin-identify-model/4"
ESTIMATORS = ("classifier", "size_B", "size_C")  # those of a model of B and C (format 4, or 5 without G)
MODEL_SUFFIX = ".npz"
#: the model that ships with the package (analysis/identify/train_default.py makes it)
DEFAULT_MODEL = "identify_default.npz"
#: the models that ship with the package, by the name ``--model``/``model=`` accepts: "default" (B and C,
#: trained on the crank PID and the motor drive with a tight guide) and "bench" (B, C and the slider guide G,
#: trained on recordings of the whole bench; analysis/identify/train_bench.py makes it)
SHIPPED_MODELS = {"default": DEFAULT_MODEL, "bench": "identify_bench.npz"}
#: orientations where a tight guide is not told from play at the guide, with the caveat an answer that names no play
#: at G gives: with y vertical the slider's weight holds it on its lower rail, the guide's normal force keeps one sign
#: over every turn of the rigid bench at 250-800 rpm (3.6-70 N; ``analysis/identify/guide_load.py``, closed form), so
#: in steady running the slider crosses its play only where impacts at B or C lift it; on the development sets guide
#: play alone with y vertical was located in 2 of 7 runs (0.013-0.061 mm), with play at B or C as well in 7 of 8
GUIDE_HELD_DOWN = {"y": "with y vertical the slider's weight holds it on its lower rail in steady running (the "
                        "guide's load keeps one sign over the turn, model card): play at the slider guide alone is not "
                        "told from a tight guide; 'no play at G' is not established, and the interval at G is every play trained"}


def label_key(joint: str) -> str:
    """The dataset label of a location's diametral clearance [mm]: ``clearance_b_mm``, ``clearance_c_mm``,
    ``clearance_guide_mm`` (G: the guide's two-sided play)."""
    return "clearance_guide_mm" if joint == "G" else f"clearance_{joint.lower()}_mm"


def label_mm(row: dict[str, Any], joint: str) -> float:
    """A run's clearance at ``joint`` [mm] from its labels (a missing or NaN guide label: no guide play, 0)."""
    v = row.get(label_key(joint))
    return 0.0 if v is None or (isinstance(v, float) and math.isnan(v)) else float(v)


def _file_estimators(meta: dict[str, Any]) -> tuple[str, ...]:
    """The estimators a format-5 file holds: the classifier and one size regressor per joint it lists."""
    joints = meta["joints"]
    if not (isinstance(joints, list) and joints[:2] == ["B", "C"] and set(joints) <= set(JOINTS)
            and len(set(joints)) == len(joints)):
        raise ValueError(f"joints: {joints!r}; allowed: [B, C] or [B, C, G]")
    return ("classifier",) + tuple(f"size_{j}" for j in joints)


def default_model_path() -> Path:
    """The file of the model that ships with the package (it may be missing from a source checkout)."""
    return shipped_model_path("default")


def shipped_model_path(name: str) -> Path:
    """The file of a model shipped with the package, by its name in :data:`SHIPPED_MODELS`."""
    from importlib.resources import files

    if name not in SHIPPED_MODELS:
        raise ModelError(f"unknown shipped model {name!r}; allowed: {', '.join(SHIPPED_MODELS)} or a model file "
                         f"(.npz)", field="model")
    return Path(str(files("twin") / "data" / SHIPPED_MODELS[name]))


def resolve_model(model: str | Path | None) -> Path:
    """A model argument as a file: None is the default model, a shipped model's name its file, else a path."""
    if model is None:
        return default_model_path()
    if isinstance(model, str) and model in SHIPPED_MODELS:
        return shipped_model_path(model)
    return Path(model)


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

        est = {"classifier": self.classifier} | {f"size_{j}": self.size[j] for j in self.joints}
        est = {k: v if isinstance(v, TreeEnsemble) else from_sklearn(v) for k, v in est.items()}
        meta = {"format": MODEL_FORMAT, "joints": list(self.joints), "feature_version": self.feature_version,
                "feature_names": list(self.feature_names), "interval_log10": dict(self.interval_log10),
                "trained_on": self.trained_on, "estimators": {k: v.meta() for k, v in est.items()}}
        return write_model(path, meta, est)

    @staticmethod
    def load(path: str | Path) -> "ClearanceModel":
        """Read a model file, refusing in one line anything but a ``twin-identify-model/5`` (or ``/4``) file of
        this twin's features (module docstring); nothing in the file is run."""
        from twin.identification.modelfile import read_model

        p = Path(path)
        meta, est = read_model(p, {MODEL_FORMAT: _file_estimators, MODEL_FORMAT_4: ESTIMATORS})
        joints = tuple(e[5:] for e in est if e.startswith("size_"))
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
            if not isinstance(trained_on.get("interval", {}).get("hull_floor", False), bool):
                raise ValueError("interval.hull_floor malformed (true or false)")
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
        classes = CLASSES if "G" in joints else tuple(c for c in CLASSES if "G" not in c)
        n_size = len(names) + (len(JOINTS) - 1 if trained_on.get("size_context") else 0)
        if est["classifier"].n_features != len(names) or any(est[f"size_{j}"].n_features != n_size for j in joints) \
                or est["classifier"].kind == "identity" or \
                not set(est["classifier"].classes) <= set(classes) or \
                any(est[f"size_{j}"].kind != "identity" for j in joints):
            raise ModelError(f"{p}: not a readable identification model (estimators do not fit its "
                             f"{len(names)} features and classes {', '.join(classes)})")
        if "G" in joints and not ("G" in half and "G" in trained_on.get("clearances_mm", {})):
            raise ModelError(f"{p}: not a readable identification model (it sizes G without its interval or "
                             "clearances trained on)")
        return ClearanceModel(est["classifier"], {j: est[f"size_{j}"] for j in joints}, half,
                              feature_version=version, feature_names=names, trained_on=trained_on)

    @property
    def joints(self) -> tuple[str, ...]:
        """The locations this model answers, in the mechanism's order: B, C and, where trained on guide play, G."""
        return tuple(j for j in JOINTS if j in self.size)

    @property
    def classes(self) -> tuple[str, ...]:
        """The fault classes this model answers (those over its joints, :data:`CLASSES`)."""
        return tuple(c for c in CLASSES if c == "none" or set(c) <= set(self.joints))

    @property
    def hop_revs(self) -> float:
        """Where an answer's windows end, every this many crank turns [turns]
        (:data:`twin.identification.training.ANSWER_HOP_REVS`)."""
        return float(self.trained_on.get("answer_hop_revs", REVS_PER_WINDOW))

    # ------------------------------------------------------------- predict
    def identify(self, X: np.ndarray, resolved: dict[str, bool], *, ripple_pct: list[float] | None = None
                 ) -> IdentifyResult:
        """The bare answer for one recording from its window features ``X`` [windows, features]: location and,
        per joint, size [mm] and 90 % interval [mm] (no evidence, warnings or training-data checks:
        :func:`identify_inputs` adds them).

        ``resolved``: per joint ("B", "C"), whether its speed and orientation are on that joint's
        size-resolution map (:func:`twin.identification.intervals.size_resolved`), which picks the half width
        where the model has one for each side (no default: a caller that forgot it would get the narrow interval
        below the map); ``ripple_pct``: the recording's measured within-turn ripple per harmonic of the crank rate
        [% of the speed] (:func:`twin.identification.ranges.recording_measures`), which picks the half widths of
        rippled recordings where the model has them. The half widths are those of answers from as many windows as
        ``X`` holds where the model has such a table for the joint (``interval.half_width_log10_by_windows``), else
        the main ones; those of recordings located B+C where the model split them so (``interval.fault_split``)."""
        if not {"B", "C"} <= set(resolved) or not set(resolved) <= set(JOINTS):
            raise ModelError(f"resolved: {sorted(resolved)}; needs a flag for each of B and C (G: optional, no "
                             "size-resolution map)")
        proba = self.classifier.predict_proba(X).mean(axis=0)
        classes = list(self.classifier.classes_)
        p = {c: float(proba[classes.index(c)]) if c in classes else 0.0 for c in self.classes}
        fault = max(p, key=p.get)
        interval = self.trained_on.get("interval", {})
        norm = interval.get("normalized") or {}
        band = interval.get("size_band_mm")
        wavy = rippled(ripple_pct, interval.get("ripple_band_pct") or RIPPLE_BAND_PCT)
        split_by_fault = fault_split_joints(interval.get("fault_split", False))
        few = window_table(interval, len(X))
        joints = []
        for j in self.joints:
            logs = self.size[j].predict(np.hstack([X, size_context(j, [fault] * len(X))])
                                        if self.trained_on.get("size_context") else X)
            mid = logs_answer(logs)
            half = few if j in few else self.interval_log10
            side = j if resolved.get(j, True) or f"{j}_unresolved" not in half else f"{j}_unresolved"
            if wavy and f"{side}_rippled" in half:
                side = f"{side}_rippled"
            if {"B", "C"} <= set(fault) and j in split_by_fault and f"{side}_both" in half:
                side = f"{side}_both"  # both joints located faulty: the other joint's impacts reach this one's sensors
            w = band_half_width(half, side, mid, band)
            if side in norm:  # normalized conformal: the half width scales with the recording's difficulty
                w = norm[side]["q"] * (logs_spread(logs) + norm[side]["beta"])
            lo, hi = (float(f"{mid * 10 ** sign:.12g}") for sign in (-w, w))
            if interval.get("hull_floor"):  # near the smallest size trained, the interval reaches down to it
                hull = trained_hull((self.trained_on.get("clearances_mm") or {}).get(j) or [])
                lo = reach_hull_floor(lo, w, hull[0] if hull else None)
            joints.append(JointAnswer(j, j in fault, mid, (lo, hi)))
        return IdentifyResult(fault, p, tuple(joints))


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
    """Raise ValueError unless ``table`` (None, or the ``held_out_size_accuracy`` of
    :func:`twin.identification.training.train`) is well formed."""
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


def training_check(model: ClearanceModel, answer: IdentifyResult, measures: dict[str, Any], orientation: str,
                   X: np.ndarray) -> tuple[IdentifyResult, list[str], dict[str, Any]]:
    """Check a recording's ``measures`` (:func:`twin.identification.ranges.recording_measures`), orientation and
    window features ``X`` [windows, features] against the model's training data
    (:func:`twin.identification.ranges.out_of_range`). Returns the answer (each joint's size and interval held
    within the clearances trained on there, :func:`twin.identification.ranges.clip_to_hull`; outside the training
    data the interval is all of them, :func:`twin.identification.ranges.widen`), the
    warnings (one per reason) and the check's evidence."""
    tr = model.trained_on
    warnings, checks = out_of_range(measures, orientation, tr.get("ranges"), np.median(X, axis=0),
                                    tr.get("feature_reference"), model.feature_names)
    outside = bool(warnings)
    seen = tr.get("clearances_mm") or {}
    joints = []
    for a in answer.joints:
        if a.joint not in seen:
            joints.append(a)
            continue
        # never below the smallest size trained at the joint nor above the largest; outside the training data the
        # interval is that hull itself, the same for every recording
        interval = widen(list(a.interval_if_faulty_mm), seen[a.joint]) if outside else \
            clip_to_hull(a.interval_if_faulty_mm, seen[a.joint])
        size = clip_to_hull([a.size_if_faulty_mm] * 2, seen[a.joint])[0]
        top = at_hull_top(a.joint, a.size_if_faulty_mm, seen[a.joint]) if a.faulty else None
        if top is not None:
            warnings.append(f"the play at {a.joint} reads at the top of the range trained ({top:.2g}-"
                            f"{trained_hull(seen[a.joint])[1]:.2g} mm): it may lie beyond it; the size and "
                            "interval say no more than the largest play trained")
        joints.append(dataclasses.replace(a, size_if_faulty_mm=size, interval_if_faulty_mm=tuple(interval)))
    answer = dataclasses.replace(answer, joints=tuple(joints))
    checks["outside_training_data"] = outside
    few = f", calibrated on the training runs' answers from their first {len(X)} window{'s' * (len(X) > 1)} (as many " \
          "as this recording has)" if window_table(tr.get("interval", {}), len(X)) else ""
    checks["interval_rule"] = ("outside the training data: each interval widened to hold every clearance the model "
                               "was trained on at that joint (no calibrated interval exists there)" if outside else
                               f"inside the training data: the conformal 90 % interval{few}")
    return answer, warnings, checks


def size_context(joint: str, faults: list[str]) -> np.ndarray:
    """Whether the locations other than ``joint`` have play in each of ``faults`` (class names) [len(faults), 2]
    (0.0 / 1.0, in the order of :data:`JOINTS`): the columns a size regressor trained with
    ``TrainOptions(size_context=True)`` reads after the window features."""
    others = [k for k in JOINTS if k != joint]
    return np.array([[float(k in f) for k in others] for f in faults], dtype=np.float64).reshape(len(faults), len(others))


def guide_caveat(orientation: str, joints: tuple[str, ...], fault: str) -> str | None:
    """The warning of an answer that names no play at the guide where the guide's play is not told from a tight guide
    (:data:`GUIDE_HELD_DOWN`), for a model that locates the guide (``joints``); None otherwise."""
    return GUIDE_HELD_DOWN.get(orientation) if "G" in joints and "G" not in fault else None


def guide_held_down_interval(joints: list[JointAnswer], seen: dict[str, Any]) -> list[JointAnswer]:
    """``joints`` with the guide's interval (the play's size if it had play) widened to every play trained at G
    (:func:`twin.identification.ranges.widen`), for an answer with the guide caveat (:func:`guide_caveat`): where
    the slider's weight holds it on its lower rail the features say little of a play at G, and the regressor's
    size there is no better than a guess (on the development sets the two guide-only runs with y vertical that read
    no play had 0.013 and 0.020 mm, their conformal intervals began at 0.020 mm)."""
    if "G" not in seen:
        return joints
    return [dataclasses.replace(a, interval_if_faulty_mm=tuple(widen(list(a.interval_if_faulty_mm), seen["G"])))
            if a.joint == "G" else a for a in joints]


def identify_recording(model: ClearanceModel, path: str | Path) -> IdentifyResult:
    """The answer for a bench recording (any recording ``twin replay`` accepts), with the evidence used."""
    from twin.identification.inputs import recording_inputs

    t0 = time.perf_counter()
    acc, counts, rate, cpr, cfg = recording_inputs(path)
    orientation = cfg.mechanism.orientation if cfg is not None else "y"
    return identify_inputs(model, acc, counts, rate, cpr, orientation=orientation, source=str(path), t0=t0)


def identify_inputs(model: ClearanceModel, acc: dict[str, np.ndarray], counts: np.ndarray, rate: float, cpr: float, *,
                    orientation: str, source: str = "", t0: float | None = None) -> IdentifyResult:
    """The answer for calibrated accelerations (sensor -> [n] [m/s²]) and encoder counts ([n]) at ``rate`` [Hz],
    ``cpr`` counts per crank turn (:func:`twin.identification.inputs.recording_inputs`,
    :func:`twin.identification.inputs.simulated_inputs`) of a bench with ``orientation`` vertical: location, sizes,
    intervals, resolution and held-out accuracy per joint, and the checks against the training data
    (:mod:`twin.identification.ranges`): one warning per reason a recording is outside, and then each joint's
    interval widened to every clearance trained on there. ``source`` names the recording in the answer and the
    errors; ``t0``: the :func:`time.perf_counter` the answer's ``seconds`` count from (default: now)."""
    t0 = time.perf_counter() if t0 is None else t0
    tr = model.trained_on
    if abs(rate - tr["rate_hz"]) > 1e-6 * rate:
        raise ModelError(f"{source}: recorded at {rate:g} Hz, the model was trained at {tr['rate_hz']:g} Hz")
    X, w = features(acc, counts, rate, cpr, orientation=orientation, hop_revs=model.hop_revs)
    resolved = resolution(orientation, w.crank_hz)
    measures = recording_measures(acc, counts, rate, cpr, w)
    ans, warnings, checks = training_check(model, model.identify(X, resolved, ripple_pct=measures["ripple_pct"]), measures,
                                           orientation, X)
    table = tr.get("held_out_size_accuracy") or {}
    joints = []
    for a in ans.joints:
        j = a.joint
        # how often the model's answers at this joint, speed and orientation held in training runs left out
        held = HeldOut.from_dict(held_out_at(table.get(j), orientation, w.crank_hz))
        joints.append(dataclasses.replace(a, size_resolved=bool(resolved.get(j, True)), size_held_out=held))
        if a.faulty and not resolved.get(j, True) and orientation not in SIZE_RESOLVED_FROM_RPM[j]:
            warnings.append(f"the size at {j} is not resolved with {orientation} vertical at any speed (model card): "
                            "trust the location and the interval, not the size")
        elif a.faulty and not resolved.get(j, True):
            warnings.append(f"the size at {j} is not resolved at {w.crank_hz * 60 * BELT_RATIO:.0f} motor rpm with "
                            f"{orientation} vertical: the bench's sensors tell 0.05-0.1 mm at {j} apart from "
                            f"{SIZE_RESOLVED_FROM_RPM[j].get(orientation, float('nan')):g} rpm on (model card); "
                            "trust the location and the interval, not the size")
    caveat = guide_caveat(orientation, model.joints, ans.fault)
    if caveat:
        warnings.append(caveat)
        joints = guide_held_down_interval(joints, tr.get("clearances_mm") or {})
    evidence = Evidence(windows=len(w.windows), revolutions=round(w.revolutions, 2), crank_hz=w.crank_hz,
                        motor_rpm_if_belt_3_97=w.crank_hz * 60 * BELT_RATIO,
                        steady_s=(w.steady[1] - w.steady[0]) / rate, features=len(model.feature_names),
                        feature_version=model.feature_version, training_data_check=checks,
                        model={k: tr[k] for k in ("dataset", "identity_sha256", "engine", "crank_hz_range")})
    seconds = time.perf_counter() - t0
    if math.isfinite(seconds):
        seconds = round(seconds, 4)
    return dataclasses.replace(ans, joints=tuple(joints), recording=source, warnings=tuple(warnings),
                               evidence=evidence, seconds=seconds)
