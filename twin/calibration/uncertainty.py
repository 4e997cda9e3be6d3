"""Intervals and identifiability from the evaluated points of the full-length stage.

The objective J is a sum of squared terms, each scaled by its repeat-to-repeat scatter (or a default):
a rise of ``delta_j`` (default 1) above the minimum means one term moved by about one scatter. Per
parameter:

* ``slice`` interval: along the profile points (the parameter moved from the best point, the
  others held), where the objective first rises above its minimum + ``delta_j`` on each side (linear
  interpolation; a parabola through the slice extends a side that never rises). A slice ignores the other parameters' compensation: it is narrower than the truth
  where parameters are correlated;
* ``marginal`` interval (two or more parameters, enough points): a full quadratic model fitted by
  least squares to the full-stage points near the best one, used where it fits them (R² ≥ 0.9); half-width sqrt(2 delta_j (H⁻¹)_ii), and
  the correlations of H⁻¹ name the pairs the recordings cannot tell apart (|ρ| > 0.9);
* ``flat``: the fitted curvature is not positive, or the interval covers the whole range: the
  recordings do not tell this parameter; the report says so instead of printing a value;
* ``on_bound``: the fitted value sits within 1 % of the range from a bound.

:func:`twin.calibration.calibrate` inflates ``delta_j`` by the misfit per term (J*/n, when above 1:
the Birge ratio) so that a model that cannot reach the recordings' scatter gets wider intervals.
These are heuristic intervals (the terms are not independent Gaussian residuals): their coverage is
what the validation protocol (docs/calibration.md) measures.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

#: |correlation| above which a pair is named as not told apart
CORRELATED = 0.9
#: a quadratic model fitting the points worse than this (R²) is not used for intervals
MIN_R2 = 0.9
#: distance from a bound, as a share of the range, that counts as "on the bound"
ON_BOUND = 0.01


@dataclass(frozen=True)
class Interval:
    """One parameter's fitted value and interval [the field's unit]."""

    field: str
    value: float
    lo: float
    hi: float
    method: str  # "marginal", "slice" or "none"
    flat: bool
    on_bound: str  # "", "low" or "high"
    slice_lo: float
    slice_hi: float

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


def _parabola(du: np.ndarray, dj: np.ndarray) -> tuple[float, float, float] | None:
    """Least-squares c + b du + a du² through the points; None if under-determined."""
    if len(du) < 3 or len(np.unique(np.round(du, 12))) < 3:
        return None
    A = np.stack([np.ones_like(du), du, du * du], axis=1)
    c, b, a = np.linalg.lstsq(A, dj, rcond=None)[0]
    return float(c), float(b), float(a)


def slice_interval(u_best: float, du: np.ndarray, j: np.ndarray, delta_j: float) -> tuple[float, float, bool]:
    """Interval in normalized coordinates from one parameter's slice (offsets ``du`` from ``u_best``,
    objective ``j``, the best point among them at du = 0): on each side, where the evaluated slice
    first rises above min + ``delta_j`` (linear interpolation between evaluated points); a side that
    never rises is extended by a parabola fitted to the slice, or to the range's end. Flat when
    neither side rises and the parabola has no positive curvature or covers the range."""
    order = np.argsort(du)
    du, j = np.asarray(du)[order], np.asarray(j)[order]
    if du.size == 0:
        return 0.0, 1.0, True
    k0 = int(np.argmin(np.abs(du)))
    level = float(j[k0]) + delta_j
    fit = _parabola(du, j)
    half = math.sqrt(delta_j / fit[2]) if fit is not None and fit[2] > 0 else math.inf
    centre = (-fit[1] / (2 * fit[2])) if fit is not None and fit[2] > 0 else 0.0
    bounds = []
    for side in (-1, 1):
        idx = range(k0 - 1, -1, -1) if side < 0 else range(k0 + 1, du.size)
        prev = k0
        found = None
        for k in idx:
            if j[k] > level:
                w = (level - j[prev]) / (j[k] - j[prev]) if j[k] != j[prev] else 1.0
                found = du[prev] + w * (du[k] - du[prev])
                break
            prev = k
        bounds.append(found)
    rises = [b is not None for b in bounds]
    lo = bounds[0] if rises[0] else min(du[0], centre - half)
    hi = bounds[1] if rises[1] else max(du[-1], centre + half)
    lo, hi = u_best + lo, u_best + hi
    flat = not any(rises) and (lo <= 0.0 and hi >= 1.0)
    return max(0.0, lo), min(1.0, hi), flat


def quadratic_model(U: np.ndarray, J: np.ndarray, u_best: np.ndarray) -> tuple[np.ndarray, float] | None:
    """Hessian of a full quadratic fitted to (U, J) around ``u_best`` and the fit's R²; None if
    under-determined."""
    d = U.shape[1]
    pairs = list(itertools.combinations_with_replacement(range(d), 2))
    n_coef = 1 + d + len(pairs)
    if len(U) < n_coef + 2:
        return None
    D = U - u_best
    cols = [np.ones(len(U))] + [D[:, i] for i in range(d)] + [D[:, i] * D[:, k] for i, k in pairs]
    A = np.stack(cols, axis=1)
    coef, *_ = np.linalg.lstsq(A, J, rcond=None)
    if np.linalg.matrix_rank(A) < n_coef:
        return None
    ss = float(np.sum((J - J.mean()) ** 2))
    r2 = 1.0 - float(np.sum((A @ coef - J) ** 2)) / ss if ss > 0 else 0.0
    H = np.zeros((d, d))
    for c, (i, k) in zip(coef[1 + d:], pairs):
        if i == k:
            H[i, i] = 2 * c
        else:
            H[i, k] = H[k, i] = c
    return H, r2


def analyse(params, u_best: np.ndarray, points: list[tuple[np.ndarray, float]], delta_j: float = 1.0,
            radius: float = 0.35, centre: np.ndarray | None = None) -> dict[str, Any]:
    """Intervals, correlations, flat and on-bound parameters from the full-stage ``points`` (u, J);
    ``centre``: the point the profiles were taken around (default ``u_best``; a profile point may turn
    out better than it)."""
    centre = u_best if centre is None else np.asarray(centre, dtype=np.float64)
    U = np.asarray([p[0] for p in points])
    J = np.asarray([p[1] for p in points])
    ok = J < 1e5
    U, J = U[ok], J[ok]
    d = len(params)
    near = np.max(np.abs(U - u_best), axis=1) <= radius
    model = quadratic_model(U[near], J[near], u_best) if d >= 2 else None
    H, r2 = model if model is not None else (None, float("nan"))
    cov = None
    corr = None
    if d < 2:
        why = "one parameter"
    elif H is None:
        why = "too few points for a quadratic model"
    elif r2 < MIN_R2:
        why = f"the quadratic model fits the points poorly (R² {r2:.2f} < {MIN_R2})"
    else:
        why = f"the quadratic model (R² {r2:.2f}) has no positive curvature in some direction"
    if H is not None and r2 >= MIN_R2:
        w = np.linalg.eigvalsh(H)
        if np.all(w > 0):
            cov = np.linalg.inv(H)
            s = np.sqrt(np.diag(cov))
            corr = cov / np.outer(s, s)
    intervals = []
    for i, p in enumerate(params):
        others = [k for k in range(d) if k != i]
        on = np.all(np.abs(U[:, others] - centre[others]) < 1e-9, axis=1) if others else np.ones(len(U), bool)
        du = U[on, i] - centre[i]
        slo, shi, sflat = slice_interval(float(centre[i]), du, J[on], delta_j)
        if cov is not None:
            half = math.sqrt(2 * delta_j * cov[i, i])
            lo, hi, method = max(0.0, u_best[i] - half), min(1.0, u_best[i] + half), "marginal"
            flat = u_best[i] - half <= 0 and u_best[i] + half >= 1
        else:
            lo, hi, method, flat = slo, shi, "slice", sflat
        bound = "low" if u_best[i] <= ON_BOUND else "high" if u_best[i] >= 1 - ON_BOUND else ""
        intervals.append(Interval(p.field, p.from_unit(u_best[i]), p.from_unit(lo), p.from_unit(hi), method, flat,
                                  bound, p.from_unit(slo), p.from_unit(shi)))
    pairs = []
    if corr is not None:
        for i, k in itertools.combinations(range(d), 2):
            if abs(corr[i, k]) > CORRELATED:
                pairs.append({"a": params[i].field, "b": params[k].field, "correlation": float(corr[i, k])})
    return {"intervals": intervals, "correlated_pairs": pairs,
            "correlation": corr.tolist() if corr is not None else None,
            "hessian_normalized": H.tolist() if H is not None else None,
            "points_used": int(len(U)), "delta_j": delta_j, "quadratic_r2": r2,
            "note": (f"marginal intervals from a quadratic model of the full-stage points (R² {r2:.2f})"
                     if cov is not None else f"slice intervals (profile points, other parameters held): {why}")}
