"""Intervals from a block bootstrap over crank turns, and the roughness of the objective.

**Residual vector.** The objective's terms are norms of feature differences (simulated − recorded):
band energies per sensor and band [dB], the three impact-peak statistics per sensor [log10], the
crank-speed harmonics [rad/s], the low-passed crank speed over the run (the command term, decimated
to :data:`COMMAND_RESID_HZ`) [rad/s]; the DTW distance stays a scalar. Scaled as the objective scales
them, the vector ``r`` has ``Σ r² = J`` for one recording (the command part up to its decimation;
:func:`residual_vector`, :func:`residual_weights`).

**Bootstrap** (:func:`block_bootstrap`): the analysis window of a recording and of the simulation at
the fitted point is cut into blocks — whole crank turns (from the recorded crank angle) when the
window holds at least :data:`MIN_TURNS` of them, else blocks of two consecutive Welch segments (about
40 ms at 100 kHz; the report says which) — and the blocks are resampled with replacement, the same
blocks on both sides (paired: the simulated side varies turn to turn as the recording does, and the
pairing keeps the crank phase common to both). The command term's series (the low-passed crank
speed's difference, decimated to :data:`COMMAND_RESID_HZ`) is a residual series of its own: its
residual at the fitted point is resampled in moving blocks of :data:`COMMAND_BLOCK_S`. Each replicate's features: the mean of the chosen
segments' periodograms (the band energies; the Welch average of the whole window is the mean of all
segments), the impact-peak statistics of the peaks that fall in the chosen blocks. Its residual
vector minus the full window's is one draw ``δ_b`` of the scatter of the objective's terms — sensor
noise, the impacts' turn-to-turn variation on both sides and the model's error at that point
included. DTW and the ripple harmonics are whole-window quantities that blocks cannot resample: their
``δ`` is drawn from a normal law whose size is the term's scaled value at the fitted point, at least 1
(one repeat-to-repeat scatter; a misfit larger than that is taken as the term's unexplained variation).

**Interval** (:func:`surrogate_intervals`): the Jacobian ``G`` of the residual vector in normalized
coordinates from the profile points (per parameter, a quadratic least-squares fit of each component
over the slice within :data:`JAC_RADIUS`; the slope at the centre). For each replicate the quadratic
surrogate ``‖r̂ + δ_b + G Δu‖²`` is minimized again (Gauss–Newton: ``Δu_b = −(GᵀG)⁻¹ Gᵀ (r̂ + δ_b)``);
the percentiles 5 and 95 of ``Δu_b − Δu_0`` (widened by :func:`small_sample_factor` for the few
blocks) placed both around the fitted value and around the surrogate's own minimum ``Δu_0`` — their
hull, with the fitted value, is the interval (where the surrogate's minimum is not the fitted point,
the objective is not the surrogate: the disagreement is part of the uncertainty).
:func:`tests.test_calibrate_bootstrap` checks it on a synthetic linear model with known covariance.

**Roughness** (:func:`roughness`): where the impacts are chaotic, neighbouring parameter values give
another impact sequence: the objective jumps deterministically between profile points. A smooth
objective rises monotonically away from its minimum; moving outward from the slice's minimum, the
largest fall below the running maximum onto a point within :data:`ROUGH_LEVEL` ΔJ of it is the jitter
(the running maximum takes every point passed: a peak above the level between two points within it
counts). ROUGH (not identifiable, like FLAT) when it
exceeds the rise ΔJ that bounds an interval: the located minimum is then set by the jumps, not by the
recordings' information. A ROUGH parameter's interval is widened to where the objective stays within
ΔJ + the jitter of its minimum along the profile (the fitted number means nothing; the report says so).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from twin.calibration.terms import band_levels_from_psd, stats_of_events

#: crank turns the analysis window must hold for whole-turn blocks
MIN_TURNS = 4
#: bootstrap replicates
N_BOOT = 400
#: two-sided level of the bootstrap interval
BOOT_ALPHA = 0.10
#: slice points within this normalized distance of the centre enter the Jacobian
JAC_RADIUS = 0.105
#: the roughness looks only at slice points whose objective is within this many ΔJ of the minimum (added
#: after the second validation: far from the minimum a second basin thousands of ΔJ up is no jump that
#: moves the located minimum, and counting it called seven told fields ROUGH)
ROUGH_LEVEL = 10.0


# --------------------------------------------------------------------------- features per segment / event
def segment_psd(x: np.ndarray, rate_hz: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Welch's segments as :func:`twin.calibration.objective.band_levels_db` takes them: frequencies
    [Hz], the periodogram of each segment (n_seg, n_f) [(m/s²)²/Hz] and each segment's centre sample."""
    from scipy.signal import spectrogram

    nper = int(min(len(x), 2 ** int(math.log2(max(16, rate_hz / 25.0)))))
    f, t, s = spectrogram(np.asarray(x, dtype=np.float64) - np.mean(x), fs=rate_hz, window="hann", nperseg=nper,
                          noverlap=nper // 2, detrend="constant", scaling="density", mode="psd")
    return f, s.T, np.round(t * rate_hz).astype(int)


# --------------------------------------------------------------------------- residual vectors
#: sampling rate of the command term's residual series (the crank speed low-passed at 50 Hz) [Hz]
COMMAND_RESID_HZ = 500.0
#: length of the blocks of the command residual's block bootstrap [s]
COMMAND_BLOCK_S = 0.05


def command_series(sim, rec, rate_hz: float) -> np.ndarray:
    """The ``command`` term's difference series (simulated − recorded low-passed crank speed [rad/s]),
    decimated to :data:`COMMAND_RESID_HZ`; empty when the term is absent."""
    if sim.speed is None or rec.speed is None:
        return np.zeros(0)
    n = min(len(sim.speed), len(rec.speed))
    k = max(1, int(round(rate_hz / COMMAND_RESID_HZ)))
    return (np.asarray(sim.speed[:n], dtype=np.float64) - np.asarray(rec.speed[:n], dtype=np.float64))[::k]


def residual_vector(terms: dict[str, float], sim, rec, ripple: bool, rate_hz: float = 100_000.0) -> np.ndarray:
    """Unscaled differences simulated − recorded (module docstring): bands per sensor, peak statistics
    per sensor (NaN where either side has none), ripple harmonics (if ``ripple``), the DTW term as it
    is (NaN if absent), then the command term's difference series (:func:`command_series`)."""
    sensors = list(rec.bands)
    parts = [sim.bands[a] - rec.bands[a] for a in sensors]
    for a in sensors:
        parts.append(sim.peaks[a] - rec.peaks[a] if sim.peaks[a] is not None and rec.peaks[a] is not None
                     else np.full(3, np.nan))
    if ripple:
        parts.append(sim.ripple - rec.ripple)
    parts.append(np.array([terms.get("dtw", np.nan)]))
    parts.append(command_series(sim, rec, rate_hz))
    return np.concatenate(parts).astype(np.float64)


def layout(n_sensors: int, n_bands: int, ripple: bool, m: int) -> dict[str, slice]:
    """Where each term's components sit in a residual vector of length ``m``."""
    nb, npk = n_sensors * n_bands, 3 * n_sensors
    out = {"bands": slice(0, nb), "peaks": slice(nb, nb + npk)}
    k = nb + npk
    if ripple:
        out["ripple"] = slice(k, k + 4)
        k += 4
    out["dtw"] = slice(k, k + 1)
    out["command"] = slice(k + 1, m)
    return out


def residual_weights(r: np.ndarray, lay: dict[str, slice], scales: dict[str, float]) -> np.ndarray:
    """Weights w with Σ (w r)² = Σ (term/scale)² at the point ``r`` (NaN components weigh 0)."""
    w = np.zeros_like(r)
    for k, sl in lay.items():
        present = np.isfinite(r[sl])
        n = int(np.count_nonzero(present))
        if not n:
            continue
        if k == "dtw":
            w[sl] = 1.0 / scales[k]
        else:
            w[sl] = np.where(present, 1.0 / (scales[k] * math.sqrt(n)), 0.0)
    return w


# --------------------------------------------------------------------------- the block bootstrap
def blocks_of(n: int, seg_centres: np.ndarray, angle: np.ndarray | None) -> tuple[np.ndarray, str, float]:
    """Block id of each Welch segment: whole crank turns when the window (``n`` samples, crank angle
    ``angle``) holds :data:`MIN_TURNS` or more, else pairs of consecutive segments; a note; the turns held."""
    turns = abs(float(angle[-1] - angle[0])) / (2 * math.pi) if angle is not None and len(angle) > 1 else 0.0
    if turns >= MIN_TURNS:
        a = np.abs(np.asarray(angle, dtype=np.float64) - angle[0])
        turn = np.floor(a / (2 * math.pi)).astype(int)
        ids = turn[np.clip(seg_centres, 0, n - 1)]
        full = int(math.floor(turns))
        ids = np.minimum(ids, full - 1)  # the last, partial turn joins the one before
        return ids, f"whole crank turns ({full} in the window)", turns
    ids = np.arange(len(seg_centres)) // 2
    return ids, (f"pairs of Welch segments ({int(ids.max()) + 1} blocks; the window holds {turns:.2f} crank "
                 f"turns, fewer than {MIN_TURNS})"), turns


def _event_arrays(x: np.ndarray, rate_hz: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from twin.calibration.terms import peak_events

    ev = peak_events(x, rate_hz)
    if ev is None:
        return np.zeros(0, int), np.zeros(0), np.zeros(0)
    return ev


def block_bootstrap(sim_acc: dict[str, np.ndarray], rec_acc: dict[str, np.ndarray], angle: np.ndarray,
                    rate_hz: float, n_boot: int, seed: int) -> dict[str, Any]:
    """Paired block-bootstrap replicates of the band and peak differences (simulated − recorded):
    (n_boot, m) in the layout of :func:`residual_vector` (bands, then peaks; the rest is not
    resampled), the full window's vector from the same segments, and the blocks' description."""
    sensors = list(rec_acc)
    n = len(next(iter(rec_acc.values())))
    psd = {}
    for side, acc in (("sim", sim_acc), ("rec", rec_acc)):
        for a in sensors:
            f, s, centres = segment_psd(acc[a], rate_hz)
            psd[side, a] = s
    ids, note, turns = blocks_of(n, centres, angle)
    n_blocks = int(ids.max()) + 1
    seg_of = [np.flatnonzero(ids == b) for b in range(n_blocks)]
    # each segment's span: an impact event belongs to the block of the segment whose centre is nearest
    events = {}
    for side, acc in (("sim", sim_acc), ("rec", rec_acc)):
        for a in sensors:
            idx, pk, dc = _event_arrays(acc[a], rate_hz)
            blk = ids[np.argmin(np.abs(idx[:, None] - centres[None, :]), axis=1)] if len(idx) else np.zeros(0, int)
            events[side, a] = (blk, pk, dc)

    def vector(chosen_segs: np.ndarray, chosen_blocks: np.ndarray) -> np.ndarray:
        bands, peaks = [], []
        counts = np.bincount(chosen_blocks, minlength=n_blocks)
        for a in sensors:
            lv = {side: band_levels_from_psd(f, psd[side, a][chosen_segs].mean(axis=0), rate_hz)
                  for side in ("sim", "rec")}
            bands.append(lv["sim"] - lv["rec"])
        for a in sensors:
            st = {}
            for side in ("sim", "rec"):
                blk, pk, dc = events[side, a]
                rep = counts[blk] if len(blk) else np.zeros(0, int)
                st[side] = stats_of_events(np.repeat(pk, rep), np.repeat(dc, rep))
            peaks.append(st["sim"] - st["rec"] if st["sim"] is not None and st["rec"] is not None
                         else np.full(3, np.nan))
        return np.concatenate(bands + peaks)

    all_blocks = np.arange(n_blocks)
    full = vector(np.arange(len(ids)), all_blocks)
    psd_bands = (full.size - 3 * len(sensors)) // len(sensors)
    rng = np.random.default_rng(seed)
    reps = np.empty((n_boot, full.size))
    for b in range(n_boot):
        chosen = rng.integers(0, n_blocks, n_blocks)
        segs = np.concatenate([seg_of[k] for k in chosen])
        reps[b] = vector(segs, chosen)
    return {"full": full, "replicates": reps, "blocks": note, "n_blocks": n_blocks, "turns": turns,
            "n_sensors": len(sensors), "n_bands": int(psd_bands)}


# --------------------------------------------------------------------------- intervals
def slice_jacobian(du: np.ndarray, R: np.ndarray, radius: float = JAC_RADIUS) -> np.ndarray:
    """Slope at du = 0 of each column of ``R`` (n_points, m) along a slice (offsets ``du``): quadratic
    least squares over the points within ``radius`` (linear with fewer than four distinct offsets)."""
    sel = np.abs(du) <= radius
    x, Y = du[sel], R[sel]
    deg = 2 if len(np.unique(np.round(x, 12))) >= 4 else 1
    if len(np.unique(np.round(x, 12))) < 2:
        return np.full(R.shape[1], np.nan)
    A = np.vander(x, deg + 1, increasing=True)
    out = np.full(R.shape[1], np.nan)
    ok = np.all(np.isfinite(Y), axis=0)
    if np.any(ok):
        out[ok] = np.linalg.lstsq(A, Y[:, ok], rcond=None)[0][1]
    return out


def small_sample_factor(n_blocks: int, alpha: float = BOOT_ALPHA) -> float:
    """Widening of a bootstrap interval from ``n_blocks`` blocks: the resampled mean's variance is
    (n − 1)/n of the mean's, and its scatter is estimated from n blocks (Student's t with n − 1 degrees
    of freedom instead of the normal quantile): sqrt(n/(n − 1)) t_{n−1, 1−α/2} / z_{1−α/2}."""
    from scipy.stats import norm, t

    n = int(n_blocks)
    if n < 2:
        return math.inf
    return math.sqrt(n / (n - 1)) * float(t.ppf(1 - alpha / 2, n - 1)) / float(norm.ppf(1 - alpha / 2))


def surrogate_intervals(r0: np.ndarray, G: np.ndarray, deltas: np.ndarray,
                        alpha: float = BOOT_ALPHA, n_blocks: int | None = None) -> dict[str, Any]:
    """Re-minimize ‖r0 + δ_b + G Δu‖² (Gauss–Newton) for each replicate δ_b (rows of ``deltas``):
    ``r0`` (m,) scaled residuals at the fitted point, ``G`` (m, d) their Jacobian, components with
    NaN dropped. Returns the shifts ``Δu_b − Δu_0`` (n_boot, d), their percentiles (α/2, 1 − α/2) and
    standard deviations, and Δu_0 (the surrogate's own minimizer: not 0 where the fitted point is not
    the surrogate's minimum)."""
    ok = np.isfinite(r0) & np.all(np.isfinite(G), axis=1) & np.all(np.isfinite(deltas), axis=0)
    r, g, D = r0[ok], G[ok], deltas[:, ok]
    d = G.shape[1]
    if not r.size:
        nan = np.full(d, np.nan)
        return {"shifts": np.zeros((0, d)), "lo": nan, "hi": nan, "sd": nan, "du0": nan, "components": 0}
    A = g.T @ g
    pinv = np.linalg.pinv(A)
    du0 = -pinv @ (g.T @ r)
    shifts = -(D @ g) @ pinv.T  # (n_boot, d): Δu_b − Δu_0 = -(A^-1 g^T δ_b)
    if n_blocks is not None:  # widened for the few blocks (small_sample_factor)
        shifts = shifts * small_sample_factor(n_blocks, alpha)
    lo = np.percentile(shifts, 100 * alpha / 2, axis=0)
    hi = np.percentile(shifts, 100 * (1 - alpha / 2), axis=0)
    return {"shifts": shifts, "lo": lo, "hi": hi, "sd": shifts.std(axis=0, ddof=1) if len(shifts) > 1 else
            np.full(d, np.nan), "du0": du0, "components": int(r.size),
            "jtj": A}


@dataclass(frozen=True)
class Roughness:
    """The objective's deterministic jumps along one parameter's slice."""

    max_drop: float  # largest fall of J below its running maximum, moving outward from the slice's minimum
    points: int
    rough: bool  # max_drop > ΔJ: the objective jumps by more than the rise that bounds an interval
    lo_u: float  # where J stays within ΔJ + max_drop of its minimum along the slice [normalized]
    hi_u: float

    def to_dict(self) -> dict[str, Any]:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in self.__dict__.items()}


def roughness(u0: float, du: np.ndarray, j: np.ndarray, delta_j: float) -> Roughness:
    """Roughness along a slice (offsets ``du`` from ``u0``, objective ``j``): a smooth objective rises
    monotonically away from its minimum; moving outward from the slice's minimum on each side, the
    largest fall below the running maximum onto a point within :data:`ROUGH_LEVEL` ``delta_j`` of the
    minimum is the jitter (the running maximum takes every point passed, those above the level included:
    a peak between two low points splits the low set). ROUGH when it exceeds ``delta_j``. The jitter
    interval: where J stays within ``delta_j`` + that fall of the minimum (linear interpolation; a side
    that never rises so far reaches the range's end)."""
    from twin.calibration.uncertainty import slice_interval

    du, j = np.asarray(du, dtype=np.float64), np.asarray(j, dtype=np.float64)
    ok = np.isfinite(j) & (j < 1e299)
    du, j = du[ok], j[ok]
    if du.size < 3:
        return Roughness(math.nan, int(du.size), False, 0.0, 1.0)
    order = np.argsort(du)
    du, j = du[order], j[order]
    k0 = int(np.argmin(j))
    near = j <= j[k0] + ROUGH_LEVEL * delta_j  # only falls *to* where the objective is within ROUGH_LEVEL ΔJ of its minimum
    drop = 0.0
    for idx in (range(k0, du.size), range(k0, -1, -1)):
        run = -math.inf
        for k in idx:
            # the running maximum takes every point on the way out (a peak above the level between two
            # points within it is a jump: the sub-level set is split), the falls only count where they land
            # within the level (a second basin far up the slope is not roughness)
            run = max(run, j[k])
            if near[k]:
                drop = max(drop, run - j[k])
    lo, hi, _flat = slice_interval(u0 + du[k0], du - du[k0], j, delta_j + drop)
    return Roughness(float(drop), int(du.size), bool(drop > delta_j), lo, hi)


def residual_block_bootstrap(r: np.ndarray, block: int, n_boot: int, seed: int) -> np.ndarray:
    """Moving-block bootstrap of a residual series ``r``: (n_boot, len(r)) draws r*_b − r, each r*_b the
    concatenation of randomly started blocks of ``block`` samples (NaN samples count as 0)."""
    r = np.nan_to_num(np.asarray(r, dtype=np.float64))
    n = len(r)
    if n == 0:
        return np.zeros((n_boot, 0))
    block = min(block, n)
    n_blk = -(-n // block)
    rng = np.random.default_rng(seed)
    starts = rng.integers(0, n - block + 1, (n_boot, n_blk))
    idx = (starts[:, :, None] + np.arange(block)[None, None, :]).reshape(n_boot, -1)[:, :n]
    return r[idx] - r[None, :]


def _num(x) -> float | None:
    return float(x) if x is not None and math.isfinite(float(x)) else None


def analyse_bootstrap(params, u_best: np.ndarray, centre: np.ndarray, entries: list[dict[str, Any]], values: list[float],
                      boot: list[dict[str, Any]], scales: dict[str, float], ripple: bool, delta_j: float,
                      alpha: float = BOOT_ALPHA, seed: int = 0) -> dict[str, Any]:
    """The bootstrap intervals and roughness verdicts of every parameter (module docstring).

    ``entries``: the full-length evaluations (each with ``u`` and ``resid``: one raw residual vector per
    recording), ``values``: their objective values; ``boot``: :func:`block_bootstrap`'s result per
    recording at the fitted point; ``scales``: the full stage's term scales."""
    U = np.asarray([e["u"] for e in entries], dtype=np.float64)
    Jv = np.asarray(values, dtype=np.float64)
    ok = np.asarray([e.get("status") == "ok" and bool(e.get("resid")) for e in entries]) & (Jv < 1e299)
    U, Jv = U[ok], Jv[ok]
    ents = [e for e, k in zip(entries, ok) if k]
    d = len(params)
    c_idx = int(np.argmin(np.max(np.abs(U - centre), axis=1))) if len(U) else -1
    if c_idx < 0 or np.max(np.abs(U[c_idx] - centre)) > 1e-9:
        return {"available": False, "why": "no full-length evaluation with residuals at the profile centre"}
    n_rec = len(ents[c_idx]["resid"])
    R_parts, r0_parts, D_parts = [], [], []
    for k in range(n_rec):
        Rk = np.asarray([[np.nan if v is None else v for v in e["resid"][k]] for e in ents], dtype=np.float64)
        n_s = boot[k]["full"].size  # bands + peaks components of this recording
        m = Rk.shape[1]
        if m < n_s + (4 if ripple else 0) + 1:
            return {"available": False, "why": "residual layout does not match the bootstrap's"}
        lay = layout(boot[k]["n_sensors"], boot[k]["n_bands"], ripple, m)
        w = residual_weights(Rk[c_idx], lay, scales)
        Rs = Rk * w
        R_parts.append(Rs)
        r0_parts.append(Rs[c_idx])
        n_b = boot[k]["replicates"].shape[0]
        delta = np.zeros((n_b, m))
        delta[:, :n_s] = (boot[k]["replicates"] - boot[k]["full"]) * w[:n_s]
        rng = np.random.default_rng(seed + 101 + k)
        for key in ("ripple", "dtw"):  # whole-window terms, not resampled: a parametric draw (docstring)
            sl = lay.get(key)
            if sl is None or sl.stop <= sl.start:
                continue
            comp = Rs[c_idx, sl]
            present = np.isfinite(comp)
            if not np.any(present):
                continue
            size = max(1.0, float(np.sqrt(np.nansum(comp ** 2))))  # the term's scatter (1) or its misfit
            delta[:, sl] = np.where(present, rng.normal(0.0, size / math.sqrt(np.count_nonzero(present)),
                                                        (n_b, sl.stop - sl.start)), 0.0)
        cs = lay["command"]
        if cs.stop > cs.start:  # the command series: a moving-block bootstrap of its residual at the centre
            delta[:, cs] = residual_block_bootstrap(Rs[c_idx, cs], max(1, int(round(COMMAND_BLOCK_S * COMMAND_RESID_HZ))),
                                                    n_b, seed + 1 + k)
        D_parts.append(delta)
    R = np.hstack(R_parts)
    r0 = np.concatenate(r0_parts)
    D = np.hstack(D_parts)
    G = np.full((R.shape[1], d), np.nan)
    rough = []
    for i in range(d):
        others = [q for q in range(d) if q != i]
        on = np.all(np.abs(U[:, others] - centre[others]) < 1e-9, axis=1) if others else np.ones(len(U), bool)
        du = U[on, i] - centre[i]
        G[:, i] = slice_jacobian(du, R[on])
        rough.append(roughness(float(centre[i]), du, Jv[on], delta_j))
    sur = surrogate_intervals(r0, G, D, alpha, n_blocks=min(b["n_blocks"] for b in boot))
    out = []
    for i, p in enumerate(params):
        rg = rough[i]
        blo, bhi = float(sur["lo"][i]), float(sur["hi"][i])
        s0 = float(sur["du0"][i]) if math.isfinite(float(sur["du0"][i])) else 0.0
        # the hull of the scatter around the fitted value and around the surrogate's own minimum (the
        # literal re-minimization): where they disagree, the surrogate's error is part of the interval
        b_lo_u, b_hi_u = u_best[i] + min(0.0, blo, s0 + blo), u_best[i] + max(0.0, bhi, s0 + bhi)
        if not (math.isfinite(b_lo_u) and math.isfinite(b_hi_u)):
            b_lo_u, b_hi_u = 0.0, 1.0
        b_lo_u, b_hi_u = float(np.clip(b_lo_u, 0, 1)), float(np.clip(b_hi_u, 0, 1))
        # the reported interval: the bootstrap's, widened to the jitter interval where the objective is rough
        lo_u, hi_u = (min(b_lo_u, rg.lo_u), max(b_hi_u, rg.hi_u)) if rg.rough else (b_lo_u, b_hi_u)
        out.append({"field": p.field,
                    "boot_lo": p.from_unit(b_lo_u), "boot_hi": p.from_unit(b_hi_u),
                    "lo": p.from_unit(lo_u), "hi": p.from_unit(hi_u), "lo_u": lo_u, "hi_u": hi_u,
                    "jitter_lo": p.from_unit(rg.lo_u), "jitter_hi": p.from_unit(rg.hi_u),
                    "boot_sd_u": _num(sur["sd"][i]), "surrogate_shift_u": _num(sur["du0"][i]),
                    "roughness": rg.to_dict(), "rough": rg.rough})
    corr = None
    if len(sur["shifts"]) > 2 and d > 1:
        c = np.corrcoef(sur["shifts"].T)
        corr = c.tolist() if np.all(np.isfinite(c)) else None
    return {"available": True, "parameters": out, "replicates": int(D.shape[0]), "alpha": alpha,
            "blocks": [b["blocks"] for b in boot], "turns_in_window": [b["turns"] for b in boot],
            "components": sur["components"], "correlation": corr,
            "method": (f"paired block bootstrap ({D.shape[0]} replicates) of the band and impact-peak differences, "
                       "re-minimized on the Gauss-Newton surrogate; widened to the jitter interval where the objective is ROUGH")}
