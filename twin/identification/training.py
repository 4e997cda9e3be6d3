"""Training of the clearance identification model on the twin's datasets (``twin identify train``).

:func:`train` fits, on the window features of the ok runs of one dataset or several pooled
(:func:`twin.identification.inputs.pooled_features`):

* the fault location: scikit-learn's ``HistGradientBoostingClassifier`` over the classes of the runs (none, B, C,
  BC and, with guide play, G, BG, CG, BCG), classes weighted to balance;
* per joint (B, C, and the slider guide G where some runs have guide play), the clearance size: a ``HistGradientBoostingRegressor`` on log10 of the diametral clearance
  (:data:`SIZE_REGRESSORS`), trained on the windows of the runs where that joint has a clearance;
* per joint, the conformal 90 % half widths from out-of-fold answers (:mod:`twin.identification.intervals`) and the
  held-out size accuracy.

Pooled datasets must agree on sample rate and encoder resolution; they may come from different engines. The
estimators are exported to plain arrays (:func:`twin.identification.trees.from_sklearn`, answers checked equal bit
for bit on the training windows); the returned :class:`~twin.identification.model.ClearanceModel` records what it
was trained on (``trained_on``, the model file's metadata).
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from twin.errors import ConfigError
from twin.identification.features import MIN_HOP_REVS, REVS_PER_WINDOW, hop_ok
from twin.identification.inputs import pooled_features
from twin.identification.intervals import (CATALOGUE_BANDS_MM, COVERAGE, FAULT_SPLIT_JOINTS, HELD_OUT_FACTOR,
                                           RIPPLE_BAND_PCT, _conformal_folds, half_widths, half_widths_by_windows,
                                           _interval_parts, fault_split_joints,
                                           held_out_accuracy, logs_answer, logs_spread, normalized_scale,
                                           recorded_size_bands)
from twin.identification.model import CLASSES, JOINTS, ClearanceModel, label_mm, size_context
from twin.identification.ranges import feature_reference, training_ranges
from twin.identification.trees import ModelError, TreeEnsemble, from_sklearn

#: how the out-of-fold scores of the intervals are grouped (:func:`twin.identification.intervals._conformal_folds`)
INTERVAL_FOLDS = ("runs", "speed")
#: settings of the per-joint size regressor (scikit-learn's ``HistGradientBoostingRegressor`` on log10 of the
#: clearance; leaves of at most 20 windows, fewer on small datasets). ``mean`` (the default): squared error, 1000
#: trees of 31 leaves at a learning rate of 0.05; ``median``: the quantile loss at 50 %, 300 trees of 15 leaves at
#: 0.08. On the development sets, trained on the same runs, ``mean`` read B's size within x1.5 in 84-92 % of the
#: resolved runs against 78-89 % (``analysis/identify/nuisance_study.py``, variants ``small-mean`` and ``small``)
SIZE_REGRESSORS = {
    "mean": dict(loss="squared_error", max_iter=1000, learning_rate=0.05, max_leaf_nodes=31, l2_regularization=1.0),
    "median": dict(loss="quantile", quantile=0.5, max_iter=300, learning_rate=0.08, max_leaf_nodes=15,
                   l2_regularization=1.0),
}

#: how the size regressors weigh the training windows (``TrainOptions.size_weights``): each window alike, or each
#: run alike (a run's windows share its weight: a 3 s run at 800 rpm has about three times the windows of one at
#: 250 rpm, and its windows are not independent observations of the size, they share the run's scene)
SIZE_WEIGHTS = ("windows", "runs")

#: how :func:`train` learns the fault location (``TrainOptions.location``): one classifier over the classes, or one
#: presence detector per location combined (:func:`detectors_as_classes`)
LOCATIONS = ("classes", "detectors")

#: an answer's windows end every this many crank turns [turns] (recorded in the model as
#: ``trained_on["answer_hop_revs"]``; models without it: back to back). The regressors learn from windows cut back to
#: back; a window starting anywhere is one of the same kind, so a model may answer from overlapping windows
#: (``TrainOptions(answer_hop_revs=0.5)``: windows ending every half turn). Back to back is the default: with windows
#: every half turn, B within x1.5 rose on one test set (88.7 -> 90.1 %) and fell on ``clearance_id_nuisance_dev``
#: (87.1 -> 85.7 %; ``analysis/identify/nuisance_study.py --variants overlap``): a short recording's size error is a
#: bias of its scene (contact parameters, ripple), which more windows over the same turns do not average out
ANSWER_HOP_REVS = float(REVS_PER_WINDOW)


class TrainOptionsError(ConfigError, ModelError):
    """A :class:`TrainOptions` field is out of its allowed values (``error.field`` names it)."""


@dataclass(frozen=True)
class TrainOptions:
    """Settings of :func:`train`; checked on construction (:class:`TrainOptionsError` naming the field).

    Attributes:
        splits: dataset splits whose ok runs are trained on ("train", "val", "test").
        workers: processes computing the features (>= 1).
        seed: random state of the estimators and of the random folds.
        interval_folds: grouping of the intervals' out-of-fold scores (:data:`INTERVAL_FOLDS`): ``"runs"``,
            :data:`~twin.identification.intervals.CONFORMAL_FOLDS` random groups of whole runs; ``"speed"``, one
            group per motor speed (each score an answer at a speed its regressor never saw).
        location_only: dataset folders pooled for the fault location only, not for the size regressors nor their
            intervals (e.g. runs of a regime the others lack, which would tilt the sizes toward it).
        size_only_at: joint ("B", "C") -> dataset folders pooled for the location and that joint's size only,
            not for the other joint's regressor nor its intervals.
        normalized_intervals: also store normalized conformal scales (``interval.normalized``,
            :func:`~twin.identification.intervals.normalized_scale`).
        size_band_mm: boundaries [mm] of the intervals' split by the answer's size (one number, several, or None
            for no split; default :data:`~twin.identification.intervals.CATALOGUE_BANDS_MM`).
        ripple_split: split the intervals by the runs' measured ripple
            (:data:`~twin.identification.intervals.RIPPLE_BAND_PCT`).
        size_regressor: a key of :data:`SIZE_REGRESSORS`.
        interval_by_engine: where the runs come from several engines, each half width is the largest of the
            pooled runs' and each engine's runs' (those with MONDRIAN_MIN_RUNS runs or more).
        answer_hop_revs: where a recording's answer windows end [crank turns] (:data:`ANSWER_HOP_REVS`); the
            estimators learn, and the out-of-fold answers are made, from windows cut back to back.
        fault_split: the joints whose intervals are split also by whether both joints are faulty (``_both``): a
            tuple of distinct joints, True for both, False for none (stored as the tuple).
        by_windows: also the half widths of answers from 1, 2, ... windows
            (``interval.half_width_log10_by_windows``; with windows back to back only). Off by default: ``train``
            has never made these tables (the option was ignored), and turning it on changes what
            ``twin identify train`` writes.
        location: how the fault location is learned (:data:`LOCATIONS`): ``"classes"``, one classifier over the
            classes; ``"detectors"``, one presence detector per location (binary, classes weighted to balance),
            stored as one classifier over the classes whose probabilities are the detectors' product
            (:func:`detectors_as_classes`).
        size_context: each joint's size regressor also reads whether the other two locations have play
            (:func:`twin.identification.model.size_context`: the training runs' true classes while training and
            for the intervals' out-of-fold answers, the located class while answering): the impacts at one joint
            reach the sensors of another, so a size read beside play elsewhere differs from one read alone.
        size_weights: how the size regressors weigh the training windows (:data:`SIZE_WEIGHTS`): ``"windows"``,
            each window alike (a fast run, with more windows in its seconds, weighs more); ``"runs"``, each run
            alike (its windows share the weight 1).
        hull_floor: an interval whose lower end lies within its half width of the smallest size trained at the
            joint reaches down to it (``interval.hull_floor``,
            :func:`twin.identification.intervals.reach_hull_floor`).
    """

    splits: tuple[str, ...] = ("train", "val")
    workers: int = 1
    seed: int = 0
    interval_folds: str = "runs"
    location_only: tuple[str | Path, ...] = ()
    size_only_at: Mapping[str, tuple[str | Path, ...]] = field(default_factory=dict)
    normalized_intervals: bool = False
    size_band_mm: float | tuple[float, ...] | None = CATALOGUE_BANDS_MM
    ripple_split: bool = True
    size_regressor: str = "mean"
    interval_by_engine: bool = True
    answer_hop_revs: float = ANSWER_HOP_REVS
    fault_split: bool | tuple[str, ...] = FAULT_SPLIT_JOINTS
    by_windows: bool = False
    location: str = "classes"
    size_context: bool = False
    size_weights: str = "windows"
    hull_floor: bool = False

    def __post_init__(self) -> None:
        def bad(name: str, message: str) -> TrainOptionsError:
            return TrainOptionsError(name, message)

        splits = (self.splits,) if isinstance(self.splits, str) else tuple(self.splits)
        if not splits or not all(s in ("train", "val", "test") for s in splits):
            raise bad("splits", f"{self.splits!r}; allowed: one or more of train, val, test")
        object.__setattr__(self, "splits", splits)
        for name in ("workers", "seed"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < (1 if name == "workers" else 0):
                raise bad(name, f"{v!r}; allowed: a whole number >= {1 if name == 'workers' else 0}")
        if self.interval_folds not in INTERVAL_FOLDS:
            raise bad("interval_folds", f"{self.interval_folds!r}; allowed: {', '.join(INTERVAL_FOLDS)}")
        if self.location not in LOCATIONS:
            raise bad("location", f"{self.location!r}; allowed: {', '.join(LOCATIONS)}")
        if not isinstance(self.hull_floor, bool):
            raise bad("hull_floor", f"{self.hull_floor!r}; allowed: true, false")
        if self.size_weights not in SIZE_WEIGHTS:
            raise bad("size_weights", f"{self.size_weights!r}; allowed: {', '.join(SIZE_WEIGHTS)}")
        if self.size_regressor not in SIZE_REGRESSORS:
            raise bad("size_regressor", f"{self.size_regressor!r}; allowed: {', '.join(SIZE_REGRESSORS)}")
        if not hop_ok(self.answer_hop_revs):
            raise bad("answer_hop_revs", f"{self.answer_hop_revs!r}; allowed: {MIN_HOP_REVS} <= answer_hop_revs <= "
                                         f"{REVS_PER_WINDOW}")
        try:
            object.__setattr__(self, "fault_split", fault_split_joints(self.fault_split))
        except ValueError:
            raise bad("fault_split", f"{self.fault_split!r}; allowed: true, false, or a list of distinct joints "
                                     "from B, C") from None
        if not isinstance(self.size_only_at, Mapping):
            raise bad("size_only_at", f"{self.size_only_at!r}; allowed: a mapping of joints B, C to dataset folders")
        wrong = [j for j in self.size_only_at if j not in ("B", "C")]
        if wrong:
            raise bad("size_only_at", f"joint {wrong[0]!r}; allowed: B, C")
        object.__setattr__(self, "size_only_at", {j: tuple(v) for j, v in self.size_only_at.items()})
        object.__setattr__(self, "location_only", tuple(self.location_only))
        bands = self.size_band_mm
        if bands is not None and not isinstance(bands, (int, float)):
            bands = tuple(bands)
            object.__setattr__(self, "size_band_mm", bands)
        if bands is not None and not all(isinstance(b, (int, float)) and not isinstance(b, bool)
                                         and math.isfinite(b) and b > 0
                                         for b in ((bands,) if isinstance(bands, (int, float)) else bands)):
            raise bad("size_band_mm", f"{self.size_band_mm!r}; allowed: None, or sizes > 0 [mm]")
        for name in ("normalized_intervals", "ripple_split", "interval_by_engine", "by_windows", "size_context"):
            if not isinstance(getattr(self, name), bool):
                raise bad(name, f"{getattr(self, name)!r}; allowed: True or False")


def _dataset_use(b: bool, c: bool) -> dict[str, str]:
    """What a training dataset taught (the model file's ``trained_on.datasets``): nothing said where it taught
    the location and both sizes."""
    if b and c:
        return {}
    return {"use": "location and the size at B" if b else "location and the size at C" if c else "location only"}



def _training_dirs(dataset_dir: str | Path | list[str | Path], o: TrainOptions
                   ) -> tuple[list[str | Path], int, int, int]:
    """Every dataset folder in the order the features are pooled (the datasets, ``size_only_at["B"]``,
    ``size_only_at["C"]``, ``location_only``), the count of the datasets, of B's size-only ones, and of all those
    teaching a size; refuses a folder given twice (its runs would be in twice)."""
    dirs = [dataset_dir] if isinstance(dataset_dir, (str, Path)) else list(dataset_dir)
    if not dirs:
        raise ModelError("no dataset to train on")
    n_both, n_b = len(dirs), len(o.size_only_at.get("B", ()))
    dirs += list(o.size_only_at.get("B", ())) + list(o.size_only_at.get("C", ()))
    n_size = len(dirs)
    dirs += list(o.location_only)
    seen: set[Path] = set()
    for d in dirs:  # a folder named twice would put its runs in twice, and what it teaches is decided by its name
        if Path(d).resolve() in seen:
            raise ModelError(f"{d}: dataset folder given twice (training sets, size-only and location-only sets): "
                             "give each once")
        seen.add(Path(d).resolve())
    return dirs, n_both, n_b, n_size


def train(dataset_dir: str | Path | list[str | Path], options: TrainOptions | None = None, *,
          features: tuple | None = None, out_of_fold: dict[str, Any] | None = None
          ) -> tuple[ClearanceModel, dict[str, Any]]:
    """Train the identification model on the ok runs of ``options.splits`` of one dataset folder or several.

    Args:
        dataset_dir: a dataset folder (``twin dataset generate``) or a list of them, pooled; with
            ``options.size_only_at`` and ``options.location_only`` the folders teaching less.
        options: the settings (:class:`TrainOptions`; default ``TrainOptions()``).
        features: what :func:`twin.identification.inputs.pooled_features` returns for these folders and splits,
            in the order of :func:`_training_dirs`, computed before (a study training several variants on the
            same runs computes them once): (X [windows, features], run rows, window -> row index [windows],
            runs left out, datasets).
        out_of_fold: a dict that receives, per joint, the out-of-fold ``scores`` [runs] [log10], ``runs`` (rows),
            ``answers`` [runs] [mm] and ``window_logs`` (per run its windows' answers [windows] [log10]) the half
            widths are calibrated on, to re-calibrate with other interval settings without fitting again.

    Returns:
        The model, and its ``trained_on`` record (also ``model.trained_on``): datasets, runs, windows, classes,
        crank rate range [Hz], clearances seen [mm], interval calibration, training ranges, versions, and the
        seconds spent on features and on fitting.
    """
    o = TrainOptions() if options is None else options
    if not isinstance(o, TrainOptions):
        raise TypeError(f"options: must be a TrainOptions, got {type(o).__name__}")
    from sklearn.ensemble import HistGradientBoostingClassifier

    dirs, n_both, n_b, n_size = _training_dirs(dataset_dir, o)
    t0 = time.perf_counter()
    X, rows, owner, skipped, dss = features if features is not None else pooled_features(dirs, o.splits, o.workers)
    y = np.array([rows[i]["fault"] for i in owner])
    names = [d.info["name"] for d in dss]
    size_names = {"B": set(names[:n_both + n_b]), "C": set(names[:n_both] + names[n_both + n_b:n_size])}
    t_feat = time.perf_counter() - t0
    # leaves of at least 20 windows (scikit-learn's default) on datasets of a thousand windows and
    # more; smaller datasets (tests, first looks) get smaller leaves, and no early stopping below 500
    leaf = int(min(20, max(3, len(X) // 48)))

    def classifier_of(labels: np.ndarray) -> Any:
        clf = HistGradientBoostingClassifier(max_iter=400, learning_rate=0.08, max_leaf_nodes=15,
                                             l2_regularization=1.0, min_samples_leaf=leaf, class_weight="balanced",
                                             early_stopping=len(X) >= 500, validation_fraction=0.15,
                                             random_state=o.seed)
        return clf.fit(X, labels)

    if o.location == "detectors":
        locations = [j for j in JOINTS if any(j in c for c in y)]
        detectors = {j: from_sklearn(classifier_of(np.array([str(j in c) for c in y])), check=X) for j in locations}
        classifier = detectors_as_classes(detectors, check=X)
    else:
        classifier = from_sklearn(classifier_of(y), check=X)  # what the file holds: answers equal bit for bit, checked
    size: dict[str, Any] = {}
    cal = _Calibration()
    # the guide G is sized where the training runs have guide play (G sizes taught by the datasets teaching both
    # joints' sizes); a model trained without guide play answers B and C only, as before the guide was a location
    size_names["G"] = set(names[:n_both])
    joints = [j for j in JOINTS if j != "G" or any(label_mm(r, "G") > 0 for r in rows)]
    for j in joints:
        for_size = np.array([rows[i]["dataset"] in size_names[j] for i in owner])
        size[j] = _fit_size(j, X, rows, np.asarray(owner), for_size, o, cal, out_of_fold, dirs)
    trained_on = _trained_on(dss, dirs, rows, X, owner, y, skipped, size_names, o, cal, tuple(size))
    trained_on |= {"feature_seconds": t_feat, "fit_seconds": time.perf_counter() - t0 - t_feat}
    return ClearanceModel(classifier, size, cal.half_width, trained_on=trained_on), trained_on


def detectors_as_classes(detectors: Mapping[str, TreeEnsemble], check: np.ndarray | None = None) -> TreeEnsemble:
    """One classifier over the fault classes (softmax ensemble, the model file's ``classifier``) from one presence
    detector per location (binary ensembles whose classes are "False", "True"; raw score f_j, P(play at j) =
    sigmoid(f_j)): class c's raw score is the sum of the f_j of its locations, so that its softmax probability is
    the product over the locations of sigmoid(f_j) where c has play at j and 1 - sigmoid(f_j) where not (the
    detectors taken as independent). Each detector iteration becomes one iteration of the combined ensemble: its tree
    for the classes with play at that location, a single leaf of value 0 for the others. ``check``: features on
    which the combined probabilities must equal the detectors' product (to 1e-9), else :class:`ModelError`."""
    locs = [j for j in JOINTS if j in detectors]
    classes = [c for c in CLASSES if c == "none" or set(c) <= set(locs)]
    for j, d in detectors.items():
        if d.kind != "sigmoid" or tuple(d.classes) != ("False", "True"):
            raise ModelError(f"detector {j}: a binary ensemble over False, True expected, got {d.kind} {d.classes}")
    K = len(classes)
    baseline = np.array([sum(float(detectors[j].baseline[0]) for j in locs if j in c) for c in classes])
    parts: dict[str, list[np.ndarray]] = {k: [] for k in ("tree_nodes", "feature", "threshold", "missing_left",
                                                          "left", "right", "is_leaf", "value")}
    leaf0 = {"tree_nodes": [1], "feature": [0], "threshold": [0.0], "missing_left": [False], "left": [0],
             "right": [0], "is_leaf": [True], "value": [0.0]}
    for j in locs:
        d = detectors[j]
        ends = np.cumsum(d.tree_nodes.astype(np.int64))
        starts = ends - d.tree_nodes
        for a, b in zip(starts, ends):
            tree = {k: getattr(d, k)[a:b] for k in parts if k != "tree_nodes"} | {"tree_nodes": [b - a]}
            for c in classes:
                for k in parts:
                    parts[k].append(np.asarray((tree if j in c else leaf0)[k]))
    dtypes = {"tree_nodes": np.int32, "feature": np.int32, "threshold": np.float64, "missing_left": np.bool_,
              "left": np.int32, "right": np.int32, "is_leaf": np.bool_, "value": np.float64}
    e = TreeEnsemble(kind="softmax", n_features=next(iter(detectors.values())).n_features, trees_per_iteration=K,
                     baseline=baseline, classes=tuple(classes),
                     source={"estimator": "presence detectors per location, combined (product of their "
                                          "probabilities)", "detectors": {j: detectors[j].source for j in locs}},
                     **{k: np.concatenate(v).astype(dtypes[k]) for k, v in parts.items()})
    if check is not None:
        p = {j: detectors[j].predict_proba(check)[:, 1] for j in locs}
        want = np.stack([np.prod([p[j] if j in c else 1 - p[j] for j in locs], axis=0) for c in classes], axis=1)
        if not np.allclose(e.predict_proba(check), want, rtol=0, atol=1e-9):
            raise ModelError("the combined detectors' probabilities differ from the product of theirs")
    return e


@dataclass
class _Calibration:
    """What :func:`_fit_size` calibrates, gathered over the joints: the conformal half widths [log10] by key, those
    of answers from 1, 2, ... windows (by str(n)), the normalized scales, the held-out size accuracy and the number
    of folds, per joint."""

    half_width: dict[str, float] = field(default_factory=dict)
    by_windows: dict[str, dict[str, float]] = field(default_factory=dict)
    normalized: dict[str, dict[str, float]] = field(default_factory=dict)
    held_out: dict[str, Any] = field(default_factory=dict)
    n_folds: dict[str, int] = field(default_factory=dict)


def _fit_size(j: str, X: np.ndarray, rows: list[dict[str, Any]], owner: np.ndarray, for_size: np.ndarray,
              o: TrainOptions, cal: _Calibration, out_of_fold: dict[str, Any] | None, dirs: list[str | Path]) -> Any:
    """Fit joint ``j``'s size regressor on the windows ``X`` [windows, features] of the runs with a clearance there
    whose dataset teaches its size (``for_size`` [windows]; ``owner`` [windows]: each window's row in ``rows``),
    and calibrate its intervals and held-out accuracy from out-of-fold answers of whole runs into ``cal``.
    Returns the regressor as plain arrays (:class:`twin.identification.trees.TreeEnsemble`)."""
    from sklearn.ensemble import HistGradientBoostingRegressor

    truth = np.array([label_mm(rows[i], j) for i in owner], float)  # the dataset's label column
    per_run = 1.0 / np.bincount(owner)[owner]  # each window's share of its run
    if o.size_context:  # the other locations' play, as the training runs have it
        X = np.hstack([X, size_context(j, [rows[i]["fault"] for i in owner])])
    sel = (truth > 0) & for_size
    if sel.sum() < 10:
        raise ModelError(f"{', '.join(map(str, dirs))}: fewer than 10 windows with a clearance at {j}: cannot "
                         "learn its size")

    def fit(use: np.ndarray) -> Any:
        reg = HistGradientBoostingRegressor(**SIZE_REGRESSORS[o.size_regressor],
                                            min_samples_leaf=int(min(20, max(3, int(use.sum()) // 48))),
                                            random_state=o.seed)
        weight = None if o.size_weights == "windows" else per_run[use]
        return reg.fit(X[use], np.log10(truth[use]), sample_weight=weight)

    regressor = from_sklearn(fit(sel), check=X[sel])
    # out-of-fold scores of whole runs (twin.identification.intervals)
    fold = _conformal_folds(rows, np.unique(owner[sel]), o.interval_folds, o.seed)
    cal.n_folds[j] = int(fold.max()) + 1
    scores, held_runs, spread, answers, window_logs = [], [], [], [], []
    for k in range(cal.n_folds[j]):
        held = sel & (fold[owner] == k)
        if not held.any() or (sel & ~held).sum() < 10:
            continue
        reg = fit(sel & ~held)
        for r in np.unique(owner[held]):
            window_logs.append(reg.predict(X[owner == r]))  # one prediction per run: its answer and spread
            answers.append(logs_answer(window_logs[-1]))
            scores.append(abs(math.log10(answers[-1]) - math.log10(label_mm(rows[int(r)], j))))
            spread.append(logs_spread(window_logs[-1]))
            held_runs.append(rows[int(r)])
    scores, spread, answers = np.array(scores), np.array(spread), np.array(answers)
    if out_of_fold is not None:
        out_of_fold[j] = {"scores": scores, "runs": held_runs, "answers": answers, "window_logs": window_logs}
    split = j in o.fault_split
    if o.normalized_intervals:
        cal.normalized[j] = normalized_scale(scores, spread)
    cal.half_width |= half_widths(j, scores, held_runs, answers, o.size_band_mm, o.ripple_split,
                                   o.interval_by_engine, split)
    if o.by_windows and float(o.answer_hop_revs) == REVS_PER_WINDOW:
        for n, half in half_widths_by_windows(j, window_logs, held_runs, o.size_band_mm, o.ripple_split,
                                               o.interval_by_engine, split).items():
            cal.by_windows.setdefault(n, {}).update(half)
    cal.held_out[j] = held_out_accuracy(scores, held_runs)
    if o.normalized_intervals:
        for part, m in _interval_parts(j, held_runs, answers, o.size_band_mm, o.ripple_split, split)[1].items():
            cal.normalized[part] = normalized_scale(scores[m], spread[m], cal.normalized[j]["beta"])
    return regressor


def _trained_on(dss: list[Any], dirs: list[str | Path], rows: list[dict[str, Any]], X: np.ndarray, owner: list[int],
                y: np.ndarray, skipped: list[dict[str, Any]], size_names: dict[str, set[str]], o: TrainOptions,
                cal: _Calibration, joints: tuple[str, ...] = ("B", "C")) -> dict[str, Any]:
    """The model file's ``trained_on`` record (module docstring of :mod:`twin.identification.model`), but the
    seconds spent."""
    import sklearn

    from twin import __version__

    infos = [ds.info for ds in dss]
    ident = infos[0]["identity"] if len(infos) == 1 else [i["identity"] for i in infos]  # one dataset: its identity
    digest = hashlib.sha256(json.dumps(ident, sort_keys=True).encode()).hexdigest()[:16]
    hz = np.array([r["crank_hz"] for r in rows])
    return {
        "dataset": "+".join(i["name"] for i in infos), "dataset_dir": ", ".join(map(str, dirs)),
        "datasets": [{"name": i["name"], "runs": sum(1 for r in rows if r["dataset"] == i["name"])}
                     | _dataset_use(i["name"] in size_names["B"], i["name"] in size_names["C"]) for i in infos],
        "identity_sha256": digest,
        "engine": "+".join(dict.fromkeys(i["identity"]["engine"] for i in infos)), "rate_hz": dss[0].rate_hz,
        "counts_per_rev": float(infos[0].get("encoder_counts_per_rev") or 32768),
        "splits": list(o.splits), "runs": len(rows), "windows": int(len(X)), "runs_left_out": skipped,
        "crank_hz_range": [float(hz.min()), float(hz.max())],
        "clearances_mm": {j: _clearances_seen([label_mm(r, j) for r in rows]) for j in joints},
        "orientations": sorted({r["orientation"] for r in rows}),
        "classes": {c: int(np.sum(y == c)) for c in CLASSES if "G" not in c or "G" in joints},
        "versions": {"twin": __version__, "sklearn": sklearn.__version__, "numpy": np.__version__},
        "size_regressor": o.size_regressor, "location": o.location,
        **({"size_context": True} if o.size_context else {}),
        **({"size_weights": o.size_weights} if o.size_weights != "windows" else {}),
        "answer_hop_revs": float(o.answer_hop_revs),
        "held_out_size_accuracy": cal.held_out | {
            "method": f"out-of-fold answers of the training runs (folds by {o.interval_folds}), per orientation and "
                      f"training speed: the share within a factor {HELD_OUT_FACTOR:g} of the truth"},
        "interval": {"method": "split-conformal, out of fold", "folds_by": o.interval_folds, "folds": cal.n_folds,
                     "coverage": COVERAGE,
                     "size_band_mm": recorded_size_bands(o.size_band_mm),
                     "ripple_band_pct": RIPPLE_BAND_PCT if o.ripple_split else None,
                     "by_engine": o.interval_by_engine,
                     "fault_split": list(o.fault_split),
                     **({"hull_floor": True} if o.hull_floor else {}),
                     "half_width_log10": cal.half_width,
                     "half_width_log10_by_windows": cal.by_windows,
                     "normalized": cal.normalized,
                     "difficulty": "spread of the per-window answers: interquartile range of the windows' log10 "
                                   "answers / 1.349 [log10]"},
        "ranges": training_ranges([r["measures"] for r in rows], [r["orientation"] for r in rows],
                                  "measured on every training run (twin identify train)"),
        "feature_reference": feature_reference(X, np.asarray(owner)),
    }


def _clearances_seen(values: list[float]) -> list[float] | dict[str, Any]:
    """The clearances of the training runs: the list of values where there are few (a catalogue),
    else their range and count (clearances drawn continuously) [mm]."""
    distinct = sorted(set(values))
    if len(distinct) <= 12:
        return distinct
    nonzero = [v for v in distinct if v > 0]
    return {"min": nonzero[0], "max": nonzero[-1], "distinct": len(nonzero), "ball_bearing": 0.0 in distinct}

