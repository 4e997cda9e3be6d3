"""Gradient-boosted trees as plain arrays: exported from scikit-learn, evaluated with numpy.

The identification model's estimators (:mod:`twin.identification.model`) are scikit-learn's
``HistGradientBoostingClassifier`` / ``HistGradientBoostingRegressor`` while training; the model file
holds them as a :class:`TreeEnsemble`: the fitted trees' node arrays and the baseline, evaluated by
:meth:`TreeEnsemble.predict_raw` (a vectorized walk of all trees at once), so that answering needs
neither scikit-learn nor any pickled object.

What a fitted estimator computes (scikit-learn 1.9, ``_raw_predict`` and the Cython
``_predict_one_from_raw_data``), reproduced here operation for operation so that the answers are
equal bit for bit (tested, and checked on the training data by :func:`from_sklearn`):

* ``raw[:, k] = baseline[k]``, then for each boosting iteration in order and each of its
  ``trees_per_iteration`` trees k, ``raw[:, k] += leaf value`` (float64 sums in that order);
* a tree is walked from its root: at a split node, a missing feature value (NaN) goes to the left
  child if ``missing_left`` else to the right; any other value goes left if ``x <= threshold``
  (a threshold may be +inf: the "split on NaN" of scikit-learn), right otherwise; a leaf gives its
  ``value``;
* the link: ``softmax`` (multiclass log loss: ``exp(raw - max)`` over its row sum), ``sigmoid``
  (binary log loss: ``scipy.special.expit``), ``identity`` (squared error, absolute error and
  quantile losses). Categorical splits are not supported: :func:`from_sklearn` refuses a model that
  has them.

Arrays of an ensemble (``T`` trees, ``N`` nodes in all, trees one after another, iteration-major):
``baseline`` float64 [K], ``tree_nodes`` int32 [T] (nodes per tree), and per node ``feature`` int32,
``threshold`` float64, ``missing_left`` bool, ``left`` / ``right`` int32 (child indices within the
tree), ``is_leaf`` bool, ``value`` float64. A loaded ensemble is checked before use (:class:`TreeEnsemble`
``__post_init__``): every child index lies after its parent and inside its tree (so every walk ends, in at
most the tree's node count steps), every split's feature is one of the ``n_features`` columns, no
threshold is NaN, every leaf value and the baseline are finite.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from twin.errors import TwinError

KINDS = ("softmax", "sigmoid", "identity")
# the array members of an ensemble and their dtypes (exactly these; native byte order)
ARRAYS: dict[str, np.dtype] = {
    "baseline": np.dtype(np.float64), "tree_nodes": np.dtype(np.int32), "feature": np.dtype(np.int32),
    "threshold": np.dtype(np.float64), "missing_left": np.dtype(np.bool_), "left": np.dtype(np.int32),
    "right": np.dtype(np.int32), "is_leaf": np.dtype(np.bool_), "value": np.dtype(np.float64),
}
# scikit-learn's losses whose raw prediction this module turns into answers, by their link
_LOSSES = {"HalfMultinomialLoss": "softmax", "HalfBinomialLoss": "sigmoid", "HalfSquaredError": "identity",
           "AbsoluteError": "identity", "PinballLoss": "identity"}
_ROWS_PER_BLOCK = 1 << 20  # rows x trees walked at once (memory of the walk's index arrays)


class ModelError(TwinError):
    """A model file is missing, unreadable or does not fit the data."""


@dataclass(frozen=True, eq=False)
class TreeEnsemble:
    """Gradient-boosted trees as plain arrays (see module docstring). ``classes``: the class labels of
    a classifier (column order of :meth:`predict_proba`), empty for a regressor; ``source``: what it was
    exported from (estimator, loss, library versions), for the record."""

    kind: str
    n_features: int
    trees_per_iteration: int
    baseline: np.ndarray
    tree_nodes: np.ndarray
    feature: np.ndarray
    threshold: np.ndarray
    missing_left: np.ndarray
    left: np.ndarray
    right: np.ndarray
    is_leaf: np.ndarray
    value: np.ndarray
    classes: tuple[Any, ...] = ()
    source: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        _check(self)
        sizes = self.tree_nodes.astype(np.int64)
        start = np.concatenate([[0], np.cumsum(sizes)[:-1]])
        owner = np.repeat(start, sizes)  # first node of each node's tree
        idx = np.arange(sizes.sum())
        # global child indices; a leaf points at itself, so a walk that reached it stays there
        gl = np.where(self.is_leaf, idx, owner + self.left)
        gr = np.where(self.is_leaf, idx, owner + self.right)
        depth, frontier = 0, start[~self.is_leaf[start]]
        while frontier.size:  # ends: children lie after their parents (checked)
            depth += 1
            kids = np.concatenate([gl[frontier], gr[frontier]])
            frontier = kids[~self.is_leaf[kids]]
        object.__setattr__(self, "_walk", (start, np.where(self.is_leaf, 0, self.feature).astype(np.intp), gl, gr, depth))

    # ------------------------------------------------------------------ answers
    @property
    def classes_(self) -> np.ndarray:
        """The class labels (scikit-learn's name), column order of :meth:`predict_proba`."""
        return np.array(self.classes)

    @property
    def n_iter(self) -> int:
        return len(self.tree_nodes) // self.trees_per_iteration

    def predict_raw(self, X: np.ndarray) -> np.ndarray:
        """Sum of the baseline and the trees' leaf values [samples, trees_per_iteration] (scikit-learn's
        ``_raw_predict``, same operations in the same order)."""
        X = np.asarray(X, dtype=np.float64)
        if X.ndim != 2 or X.shape[1] != self.n_features:
            raise ModelError(f"features: {X.shape}; the model takes [windows, {self.n_features}]")
        start, feat, gl, gr, depth = self._walk
        K, T = self.trees_per_iteration, len(start)
        raw = np.zeros((len(X), K), dtype=np.float64, order="F")
        raw += self.baseline
        step = max(1, _ROWS_PER_BLOCK // T)
        for a in range(0, len(X), step):
            Xb = X[a:a + step]
            rows = np.arange(len(Xb))[:, None]
            node = np.repeat(start[None, :], len(Xb), axis=0)
            for _ in range(depth):
                x = Xb[rows, feat[node]]
                left = np.where(np.isnan(x), self.missing_left[node], x <= self.threshold[node])
                node = np.where(left, gl[node], gr[node])
            leaf = self.value[node].reshape(len(Xb), T // K, K)
            rb = raw[a:a + step]
            for i in range(T // K):
                rb += leaf[:, i, :]
        return raw

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Class probabilities [samples, classes] (scikit-learn's ``predict_proba``)."""
        raw = self.predict_raw(X)
        if self.kind == "softmax":  # sklearn.utils.extmath.softmax, step for step
            p = np.asarray(raw, copy=True)
            p -= np.reshape(np.max(p, axis=1), (-1, 1))
            np.exp(p, out=p)
            p /= np.reshape(np.sum(p, axis=1), (-1, 1))
            return p
        if self.kind == "sigmoid":  # HalfBinomialLoss.predict_proba
            from scipy.special import expit

            p = np.empty((len(raw), 2), dtype=raw.dtype)
            p[:, 1] = expit(raw.squeeze(1))
            p[:, 0] = 1 - p[:, 1]
            return p
        raise ModelError("predict_proba: this ensemble is a regressor")

    def predict(self, X: np.ndarray) -> np.ndarray:
        """A regressor's answers [samples]; a classifier's classes [samples] (scikit-learn's ``predict``)."""
        raw = self.predict_raw(X)
        if self.kind == "identity":
            return raw.ravel()
        k = (raw.ravel() > 0).astype(int) if raw.shape[1] == 1 else np.argmax(raw, axis=1)
        return self.classes_[k]

    # ------------------------------------------------------------------ file io
    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays of the file (:data:`ARRAYS`)."""
        return {k: getattr(self, k) for k in ARRAYS}

    def meta(self) -> dict[str, Any]:
        """The JSON part of the file."""
        return {"kind": self.kind, "n_features": self.n_features, "trees_per_iteration": self.trees_per_iteration,
                "trees": len(self.tree_nodes), "nodes": int(self.tree_nodes.sum()), "classes": list(self.classes),
                "source": self.source}

    @classmethod
    def from_file(cls, meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> "TreeEnsemble":
        """An ensemble from the JSON part and the arrays of a file; checked (:func:`_check`)."""
        for k in ("kind", "n_features", "trees_per_iteration", "classes"):
            if k not in meta:
                raise ModelError(f"no {k!r}")
        if not isinstance(meta["classes"], list) or not all(isinstance(c, str) for c in meta["classes"]):
            raise ModelError(f"classes: {meta['classes']!r}; a list of strings")
        if not all(type(meta[k]) is int for k in ("n_features", "trees_per_iteration")):
            raise ModelError("n_features and trees_per_iteration must be integers")
        return cls(kind=meta["kind"], n_features=meta["n_features"], trees_per_iteration=meta["trees_per_iteration"],
                   classes=tuple(meta["classes"]), source=dict(meta.get("source") or {}), **arrays)


def _check(e: TreeEnsemble) -> None:
    """Refuse an ensemble whose arrays a walk could not use safely (see module docstring)."""
    if e.kind not in KINDS:
        raise ModelError(f"kind: {e.kind!r}; allowed: {', '.join(KINDS)}")
    K = e.trees_per_iteration
    want_k = {"softmax": len(e.classes), "sigmoid": 1, "identity": 1}[e.kind]
    n_cls = {"softmax": len(e.classes), "sigmoid": 2, "identity": 0}[e.kind]
    if K < 1 or K != want_k or len(e.classes) != n_cls or (e.kind == "softmax" and K < 3):
        raise ModelError(f"{e.kind} ensemble with {K} trees per iteration and {len(e.classes)} classes")
    if len(set(e.classes)) != len(e.classes):
        raise ModelError(f"classes: {list(e.classes)!r} are not distinct")
    if e.n_features < 1:
        raise ModelError(f"n_features: {e.n_features}; at least 1")
    for k, dt in ARRAYS.items():
        a = getattr(e, k)
        if not isinstance(a, np.ndarray) or a.dtype != dt or a.ndim != 1:
            raise ModelError(f"{k}: {getattr(a, 'dtype', type(a).__name__)} "
                             f"{getattr(a, 'shape', '')}; expected a 1-d {dt} array")
    if e.baseline.shape != (K,) or not np.all(np.isfinite(e.baseline)):
        raise ModelError(f"baseline: {e.baseline.shape}, expected ({K},) finite values")
    sizes = e.tree_nodes.astype(np.int64)
    if sizes.size < K or sizes.size % K or np.any(sizes < 1):
        raise ModelError(f"tree_nodes: {sizes.size} trees, expected a multiple of {K}, each with a node at least")
    n = int(sizes.sum())
    for k in ("feature", "threshold", "missing_left", "left", "right", "is_leaf", "value"):
        if getattr(e, k).size != n:
            raise ModelError(f"{k}: {getattr(e, k).size} nodes, tree_nodes add up to {n}")
    local = np.arange(n) - np.repeat(np.concatenate([[0], np.cumsum(sizes)[:-1]]), sizes)
    tree_n = np.repeat(sizes, sizes)
    split = ~e.is_leaf
    for k in ("left", "right"):
        c = getattr(e, k)[split].astype(np.int64)
        if np.any(c <= local[split]) or np.any(c >= tree_n[split]):
            raise ModelError(f"{k}: a child index outside its tree or not after its parent")
    if np.any(e.feature[split] < 0) or np.any(e.feature[split] >= e.n_features):
        raise ModelError(f"feature: an index outside 0-{e.n_features - 1}")
    if np.any(np.isnan(e.threshold[split])):
        raise ModelError("threshold: NaN at a split")
    if not np.all(np.isfinite(e.value[e.is_leaf])):
        raise ModelError("value: a leaf value that is not finite")


def from_sklearn(est: Any, check: np.ndarray | None = None) -> TreeEnsemble:
    """Export a fitted scikit-learn ``HistGradientBoostingClassifier`` / ``Regressor`` (read through its
    fitted attributes ``_predictors``, ``_baseline_prediction``, ``_loss``, ``n_trees_per_iteration_``,
    ``classes_``: scikit-learn 1.9's layout); refuses categorical features and losses whose link is not
    listed in ``_LOSSES``. ``check``: features on which the export's answers must equal the estimator's
    bit for bit (``predict_proba`` or ``predict``), else :class:`ModelError`."""
    name = type(est).__name__
    if name not in ("HistGradientBoostingClassifier", "HistGradientBoostingRegressor") or \
            not hasattr(est, "_predictors"):
        raise ModelError(f"cannot export a {name}: a fitted HistGradientBoostingClassifier or Regressor only")
    if getattr(est, "is_categorical_", None) is not None or getattr(est, "_preprocessor", None) is not None:
        raise ModelError(f"cannot export this {name}: it has categorical features")
    loss = type(est._loss).__name__
    kind = _LOSSES.get(loss)
    if kind is None:
        raise ModelError(f"cannot export this {name}: loss {loss}; supported: {', '.join(_LOSSES)}")
    K = int(est.n_trees_per_iteration_)
    trees = [t for it in est._predictors for t in it]
    if any(len(it) != K for it in est._predictors):
        raise ModelError(f"cannot export this {name}: an iteration without {K} trees")
    if any(np.any(t.nodes["is_categorical"]) for t in trees):
        raise ModelError(f"cannot export this {name}: it has categorical splits")
    nodes = np.concatenate([t.nodes for t in trees])
    classes = tuple(str(c) for c in est.classes_) if kind != "identity" else ()
    if kind != "identity" and [str(c) for c in est.classes_] != [c for c in est.classes_]:
        raise ModelError(f"cannot export this {name}: class labels {list(est.classes_)!r} are not strings")
    import sklearn

    e = TreeEnsemble(
        kind=kind, n_features=int(est.n_features_in_), trees_per_iteration=K,
        baseline=np.ascontiguousarray(est._baseline_prediction, dtype=np.float64).reshape(-1),
        tree_nodes=np.array([len(t.nodes) for t in trees], dtype=np.int32),
        feature=nodes["feature_idx"].astype(np.int32), threshold=nodes["num_threshold"].astype(np.float64),
        missing_left=nodes["missing_go_to_left"].astype(bool), left=nodes["left"].astype(np.int32),
        right=nodes["right"].astype(np.int32), is_leaf=nodes["is_leaf"].astype(bool),
        value=nodes["value"].astype(np.float64), classes=classes,
        source={"estimator": name, "loss": loss, "n_iter": int(est.n_iter_), "sklearn": sklearn.__version__})
    if check is not None:
        ours, theirs = ((e.predict(check), est.predict(check)) if kind == "identity"
                        else (e.predict_proba(check), est.predict_proba(check)))
        if not np.array_equal(ours, theirs, equal_nan=True):
            raise ModelError(f"the exported {name} answers differ from scikit-learn's {sklearn.__version__} (by up "
                             f"to {np.nanmax(np.abs(ours - theirs)):.3g}): a scikit-learn outside the tested range?")
    return e
