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

**Noise share** (:func:`replicate_spread`): the ΔJ rule above says nothing about where the minimum sits
by chance. The recording and the simulation each carry one sensor-noise realization; the minimizer
moves with both. Each full-length evaluation also computes the objective under K other noise
realizations of the simulation (:mod:`twin.calibration.objective`, no new simulation); the
minimizers m_0..m_K of the K + 1 objectives (parabola along each parameter's slice, or the
quadratic model's minimum) scatter by the noise's share σ. Under a Gaussian model (m_k = θ + e_r − e_k,
e_r the recording's noise, e_k the simulation's, all N(0, σ²)) the mean m̄ has error e_r − ē with
variance σ² (1 + 1/(K+1)), independent of the sample deviation s of the m_k, so
m̄ ± t_{K, 1−α/2} s √(1 + 1/(K+1)) holds the truth with probability 1 − α exactly (α = 0.1). The
reported interval is the hull of that and the ΔJ interval (and the fitted value). It does not cover a
model error (the replay gap of the trace drive, physics the twin lacks).
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
    noise_lo: float = math.nan
    noise_hi: float = math.nan
    noise_minimizers: tuple[float, ...] = ()
    rise: float = math.nan  # largest rise of the objective along the parameter's slice (profile) above its minimum

    def to_dict(self) -> dict[str, Any]:
        d = dict(self.__dict__)
        for k in ("noise_lo", "noise_hi"):
            d[k] = None if not math.isfinite(d[k]) else d[k]
        d["noise_minimizers"] = list(d["noise_minimizers"])
        return d


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
    flat = bool(not any(rises) and (lo <= 0.0 and hi >= 1.0))
    return float(max(0.0, lo)), float(min(1.0, hi)), flat


def _quadratic_fit(U: np.ndarray, J: np.ndarray, centre: np.ndarray):
    """A full quadratic fitted by least squares to (U, J) around ``centre``: (gradient, Hessian, R²)
    at the centre; None if under-determined."""
    d = U.shape[1]
    pairs = list(itertools.combinations_with_replacement(range(d), 2))
    n_coef = 1 + d + len(pairs)
    if len(U) < n_coef + 2:
        return None
    D = U - centre
    A = np.stack([np.ones(len(U))] + [D[:, i] for i in range(d)] + [D[:, i] * D[:, k] for i, k in pairs], axis=1)
    if np.linalg.matrix_rank(A) < n_coef:
        return None
    coef = np.linalg.lstsq(A, J, rcond=None)[0]
    ss = float(np.sum((J - J.mean()) ** 2))
    r2 = 1.0 - float(np.sum((A @ coef - J) ** 2)) / ss if ss > 0 else 0.0
    H = np.zeros((d, d))
    for c, (i, k) in zip(coef[1 + d:], pairs):
        H[i, k] = H[k, i] = (2 * c) if i == k else c
    return coef[1:1 + d], H, r2


def quadratic_model(U: np.ndarray, J: np.ndarray, u_best: np.ndarray) -> tuple[np.ndarray, float] | None:
    """Hessian of a full quadratic fitted to (U, J) around ``u_best`` and the fit's R²; None if
    under-determined."""
    fit = _quadratic_fit(U, J, u_best)
    return None if fit is None else (fit[1], fit[2])


#: objective values at or above this are failed evaluations (twin.calibration.search.FAILED_J)
FAILED = 1e299
#: two-sided level of the noise interval
NOISE_ALPHA = 0.10
#: normalized distances from the profile centre within which slice points enter a replicate's parabola:
#: the smallest holding at least four points (near points resolve the minimum, far ones are not quadratic)
SLICE_RADII = (0.035, 0.105, 0.3)


def _slice_minimum(du: np.ndarray, j: np.ndarray) -> float:
    """Minimizer (offset) of a parabola through a slice's points; the best point where the parabola
    has no positive curvature; clipped to the points' span."""
    fit = _parabola(du, j)
    if fit is None or fit[2] <= 0:
        return float(du[int(np.argmin(j))])
    return float(np.clip(-fit[1] / (2 * fit[2]), du.min(), du.max()))


def _quadratic_minimum(U: np.ndarray, J: np.ndarray, centre: np.ndarray) -> np.ndarray | None:
    """Minimizer of a full quadratic fitted to (U, J) around ``centre``; None if not positive definite."""
    fit = _quadratic_fit(U, J, centre)
    if fit is None or not np.all(np.linalg.eigvalsh(fit[1]) > 0):
        return None
    return centre - np.linalg.solve(fit[1], fit[0])


def replicate_spread(U: np.ndarray, Js: np.ndarray, centre: np.ndarray, alpha: float = NOISE_ALPHA,
                     joint: bool = False) -> dict[str, Any]:
    """The noise interval of each parameter from K + 1 objectives over the same points.

    ``U`` (n, d): the full-length points (normalized); ``Js`` (K + 1, n): the objective's values there,
    row 0 the objective's own noise, rows 1.. the replicates; ``centre``: the profile centre. Per
    objective the minimizer: with ``joint`` the quadratic model's minimum over the points, else (or
    where it has none) per parameter the parabola through its slice within :data:`SLICE_RADII`.
    Returns the minimizers (K + 1, d), their mean, deviation ``s`` (ddof 1) and the half-width
    t_{K, 1−α/2} s √(1 + 1/(K + 1)) (module docstring); half-width NaN when K < 1."""
    from scipy.stats import t as student_t

    U = np.asarray(U, dtype=np.float64)
    Js = np.atleast_2d(np.asarray(Js, dtype=np.float64))
    centre = np.asarray(centre, dtype=np.float64)
    n_obj, d = Js.shape[0], U.shape[1]
    mins = np.empty((n_obj, d))
    for k in range(n_obj):
        m = None
        if joint:
            near = np.max(np.abs(U - centre), axis=1) <= 0.35
            m = _quadratic_minimum(U[near], Js[k, near], centre)
        if m is None:
            m = np.empty(d)
            for i in range(d):
                others = [q for q in range(d) if q != i]
                on = np.all(np.abs(U[:, others] - centre[others]) < 1e-9, axis=1) if others else np.ones(len(U), bool)
                du = U[on, i] - centre[i]
                sel = np.zeros(len(du), bool)
                for r in SLICE_RADII:
                    sel = np.abs(du) <= r
                    if len(np.unique(np.round(du[sel], 12))) >= 4:
                        break
                m[i] = centre[i] + (_slice_minimum(du[sel], Js[k, on][sel]) if np.count_nonzero(sel) else 0.0)
        mins[k] = m
    K = n_obj - 1
    mean = mins.mean(axis=0)
    if K < 1:
        return {"minimizers": mins, "mean": mean, "s": np.full(d, math.nan), "half": np.full(d, math.nan)}
    s = mins.std(axis=0, ddof=1)
    half = float(student_t.ppf(1 - alpha / 2, K)) * s * math.sqrt(1 + 1 / (K + 1))
    return {"minimizers": mins, "mean": mean, "s": s, "half": half}


def analyse(params, u_best: np.ndarray, points: list[tuple[np.ndarray, float]], delta_j: float = 1.0,
            radius: float = 0.35, centre: np.ndarray | None = None,
            replicates: np.ndarray | None = None) -> dict[str, Any]:
    """Intervals, correlations, flat and on-bound parameters from the full-stage ``points`` (u, J);
    ``centre``: the point the profiles were taken around (default ``u_best``; a profile point may turn
    out better than it)."""
    centre = u_best if centre is None else np.asarray(centre, dtype=np.float64)
    U = np.asarray([p[0] for p in points])
    J = np.asarray([p[1] for p in points])
    ok = J < FAILED
    if replicates is not None:  # (K, n): the replicate objectives at the same points
        R = np.asarray(replicates, dtype=np.float64).reshape(-1, len(points))
        ok &= np.all(R < FAILED, axis=0)
        R = R[:, ok]
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
    noise = None
    if replicates is not None and R.shape[0] >= 1 and len(U):
        noise = replicate_spread(U, np.vstack([J[None, :], R]), centre, joint=cov is not None)
    intervals = []
    for i, p in enumerate(params):
        others = [k for k in range(d) if k != i]
        on = np.all(np.abs(U[:, others] - centre[others]) < 1e-9, axis=1) if others else np.ones(len(U), bool)
        du = U[on, i] - centre[i]
        slo, shi, sflat = slice_interval(float(centre[i]), du, J[on], delta_j)
        if cov is not None:
            half = math.sqrt(2 * delta_j * cov[i, i])
            lo, hi, method = max(0.0, u_best[i] - half), min(1.0, u_best[i] + half), "marginal"
            flat = bool(u_best[i] - half <= 0 and u_best[i] + half >= 1)
        else:
            lo, hi, method, flat = slo, shi, "slice", sflat
        bound = "low" if u_best[i] <= ON_BOUND else "high" if u_best[i] >= 1 - ON_BOUND else ""
        nlo = nhi = math.nan
        mins: tuple[float, ...] = ()
        if noise is not None and math.isfinite(noise["half"][i]):
            nlo_u = max(0.0, noise["mean"][i] - noise["half"][i])
            nhi_u = min(1.0, noise["mean"][i] + noise["half"][i])
            nlo, nhi = p.from_unit(nlo_u), p.from_unit(nhi_u)
            mins = tuple(p.from_unit(float(m)) for m in noise["minimizers"][:, i])
            lo, hi = min(lo, nlo_u, u_best[i]), max(hi, nhi_u, u_best[i])
            method += "+noise"
            flat = bool(flat or (lo <= 0.0 and hi >= 1.0))
        rise = float(np.max(J[on]) - np.min(J[on])) if np.any(on) else math.nan
        intervals.append(Interval(p.field, p.from_unit(u_best[i]), p.from_unit(lo), p.from_unit(hi), method, flat,
                                  bound, p.from_unit(slo), p.from_unit(shi), nlo, nhi, mins, rise))
    pairs = []
    if corr is not None:
        for i, k in itertools.combinations(range(d), 2):
            if abs(corr[i, k]) > CORRELATED:
                pairs.append({"a": params[i].field, "b": params[k].field, "correlation": float(corr[i, k])})
    return {"intervals": intervals, "correlated_pairs": pairs,
            "correlation": corr.tolist() if corr is not None else None,
            "hessian_normalized": H.tolist() if H is not None else None,
            "points_used": int(len(U)), "delta_j": delta_j, "quadratic_r2": r2,
            "noise_replicates": 0 if noise is None else int(noise["minimizers"].shape[0] - 1),
            "note": (f"marginal intervals from a quadratic model of the full-stage points (R² {r2:.2f})"
                     if cov is not None else f"slice intervals (profile points, other parameters held): {why}")}
