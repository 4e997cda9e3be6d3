"""Features of clearance identification, from calibrated accelerations and the crank encoder.

The same function serves dataset runs (``meas_AC1..6`` and ``encoder_counts`` of a
``twin dataset``) and bench recordings (raw volts calibrated with the recording's static
calibration, encoder counts), so a model trained on one applies to the other.

Method, per analysis window of :data:`REVS_PER_WINDOW` whole crank revolutions (the recording's
steady part is cut into such windows; an identification averages over them):

* **windows**: exactly REVS_PER_WINDOW crank turns each, cut back to back from the end of the
  recording's steady part (:func:`steady_windows`), starting at any crank angle;
* **speed**: crank rate from the encoder [Hz];
* **angle domain** (order tracking with the encoder): each revolution resampled to
  :data:`ANGLE_SAMPLES` points of crank angle; the synchronous average over the window's
  revolutions gives the amplitudes of crank orders 1–8 (the rigid-body motion, normalized by
  rω² so that speed drops out) and the residual (what is not periodic in the crank angle: impacts
  vary from one revolution to the next) as a fraction of the signal;
* **bands**: Welch power in bands around the bench's contact and structural modes, in dB re
  the band energy of a rigid-body signal of the same speed (dB of (m/s²)² minus 40 log10 ω);
* **impacts**: on the signal high-passed at 500 Hz, the count of bursts per revolution above
  6× its median absolute deviation (bursts less than 5 ms apart are one: an impact rings), its
  RMS and peak over rω²;
* **shape**: kurtosis and crest factor of the signal. Not the shape of the high-passed bursts
  (their kurtosis, crest, height over RMS): it follows the contact law's impulse shape, which the
  twin, the reference engine and the bench do not share;

* **where** (contact-law independent to first order): log ratios of the high-passed RMS and of the
  0.8–6 kHz band energy between the rod's sensor pairs (a rigid body loads its sensors in
  proportions set by where an impulse acts, whatever its shape), and the distribution of
  high-frequency energy over 12 sectors of the absolute crank angle for the sensors near B and near
  C (impacts happen where the joint force reverses);
* the bench's **orientation** (from the recording's configuration), one-hot.

:data:`FEATURE_VERSION` changes whenever a definition changes: a model refuses features of another
version.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from twin.errors import TwinError

FEATURE_VERSION = "twin-identify-features/6"
SENSORS = ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6")
#: whole crank revolutions per analysis window
REVS_PER_WINDOW = 2
#: samples per revolution of the angle-domain resampling
ANGLE_SAMPLES = 512
#: crank orders whose amplitudes are features
ORDERS = tuple(range(1, 9))
#: frequency bands [Hz]: 1 kHz contact mode, 3 kHz band of S003 Fig. 15, structural and sensor bands
BANDS_HZ = ((50.0, 400.0), (400.0, 800.0), (800.0, 1200.0), (1200.0, 2500.0), (2700.0, 3300.0),
            (3300.0, 6000.0), (6000.0, 12000.0), (12000.0, 24000.0))
HIGHPASS_HZ = 500.0
#: bursts of the high-passed signal closer than this are one impact (its ringing) [s]
IMPACT_GAP_S = 0.005
#: crank radius used to normalize by the rigid-body acceleration r ω² [m] (Table 1)
CRANK_RADIUS_M = 0.12
#: sensor groups of the rod, near B and near C (S003 Table 3). The slider's sensors are left out of
#: the high-frequency location features: at the guide, their high-frequency content follows the
#: guide friction model (it differs between the twin, the reference engine and the bench) more than
#: the clearance (measured: ``analysis/identify/README.md``)
GROUPS = {"B": ("AC1", "AC2"), "C": ("AC3", "AC4")}
#: crank-angle sectors of the high-frequency energy distribution
SECTORS = 12
#: sensor pairs whose high-frequency ratio locates an impact (rigid body: an impulse at B and one at
#: C load the rod's sensors in different proportions, whatever the contact law)
PAIRS = (("AC1", "AC4"), ("AC2", "AC3"), ("AC1", "AC3"), ("AC2", "AC4"), ("AC1", "AC2"), ("AC3", "AC4"))
ORIENTATIONS = ("x", "y", "z")
#: band of the pair ratios [Hz]
RATIO_BAND_HZ = (800.0, 6000.0)


class IdentifyError(TwinError):
    """A recording cannot be identified (no encoder, too little motion, ...)."""


def feature_names() -> list[str]:
    names = ["crank_hz"] + [f"orientation_{o}" for o in ORIENTATIONS]
    for s in SENSORS:
        names += [f"{s}_order{k}" for k in ORDERS]
        names += [f"{s}_residual", f"{s}_rms_norm"]
        names += [f"{s}_band{int(lo)}_{int(hi)}" for lo, hi in BANDS_HZ]
        names += [f"{s}_impacts_per_rev", f"{s}_kurtosis", f"{s}_crest", f"{s}_hp_rms_norm", f"{s}_hp_max_norm"]
    names += [f"ratio_hp_{a}_{b}" for a, b in PAIRS] + [f"ratio_band_{a}_{b}" for a, b in PAIRS]
    names += [f"sector_{g}_{k}" for g in GROUPS for k in range(SECTORS)]
    return names


@dataclass(frozen=True)
class Windows:
    """The steady part of a recording cut into analysis windows.

    Attributes:
        steady: (start, stop) sample indices of the steady part used.
        windows: (start, stop) sample indices of each window of exactly REVS_PER_WINDOW turns.
        revolutions: crank turns in the steady part.
        crank_hz: crank rate of the windows (their whole turns over their duration) [Hz].
        direction: +1 or -1 (encoder counting direction of the motion).
        swing: the crank rate's swing in steady running: the 95th percentile over the recording's last half of
            the 50 ms rate's deviation from its median there [-] (0.4: the rate swings ±40 %).
    """

    steady: tuple[int, int]
    windows: list[tuple[int, int]]
    revolutions: float
    crank_hz: float
    direction: int
    swing: float = 0.0


#: averaging time of the crank rate that decides what is steady [s]
RATE_WINDOW_S = 0.05


#: how far the crank rate may stray from the steady rate [-]: a motor driving through a V-belt holds
#: its speed within a few percent (the sample recordings' belt and motor model: ±3 %), a spin-up
#: leaves it by far more
SPEED_TOL = 0.10
#: allowance above a swinging recording's own rate spread [-]
RIPPLE_ALLOWANCE = 0.05
#: the largest tolerance of the 50 ms rate [-]: a rate that falls below 5 % of the steady rate is a stop, not a
#: swing (no cap on the swing itself: a recording that turns through whole turns is answered, however much its
#: speed swings within a turn; :mod:`twin.identification.ranges` warns beyond the swing the bench gives)
MAX_SPEED_TOL = 0.95
#: where the tolerance is widened for a swing, how far a whole turn's mean rate may stray from the last half's
#: mean rate before the steady part starts [-] (a spin-up's turns are left out)
TURN_TOL = SPEED_TOL


#: shortest hop between the ends of successive windows [turns]: at most 16 windows end per crank turn, so the
#: feature matrix of a recording is bounded by its turns (a model file declaring a hop of 1e-300 turn once made
#: every sample end a window: gigabytes of features for a 3 s recording, from a file of a few kilobytes)
MIN_HOP_REVS = 1.0 / 16


def hop_ok(hop_revs: object) -> bool:
    """Whether ``hop_revs`` is a hop between the ends of successive windows [turns] :func:`steady_windows` takes:
    a number in [MIN_HOP_REVS, REVS_PER_WINDOW] (REVS_PER_WINDOW: back to back)."""
    return isinstance(hop_revs, (int, float)) and not isinstance(hop_revs, bool) and \
        MIN_HOP_REVS <= hop_revs <= REVS_PER_WINDOW


def steady_windows(counts: np.ndarray, rate_hz: float, counts_per_rev: float, skip_s: float = 0.0,
                   speed_tol: float = SPEED_TOL, hop_revs: float = REVS_PER_WINDOW) -> Windows:
    """Windows of exactly REVS_PER_WINDOW crank turns in the recording's steady part.

    The crank rate is the encoder's turns over 50 ms; the steady part is the longest stretch, after
    ``skip_s``, where it stays within a tolerance of the median rate of the last half of the recording
    (a spin-up or a stop is left out): ``speed_tol``, or, where the speed swings within a turn (a motor
    speed loop through the V-belt, the slider lifted against gravity), the last half's own spread (95th
    percentile of the rate's deviation, :attr:`Windows.swing`) plus :data:`RIPPLE_ALLOWANCE`, at most
    :data:`MAX_SPEED_TOL` (a rate near 0 is a stop). Where the tolerance is so widened, the 50 ms rate no longer
    tells the end of a spin-up from the swing (and a swing's peaks may pass it once a turn), and whole turns do:
    the steady part ends at the last 50 ms rate within the tolerance and is made of the whole turns, counted
    back from there, whose mean rate lies within :data:`TURN_TOL` of the last half's mean rate
    (:func:`_first_steady_turn`). Windows are cut back to back from the end of that
    stretch (the most settled part), at any crank angle: order amplitudes do not depend on where a
    revolution starts; with ``hop_revs`` below REVS_PER_WINDOW [turns] each window ends that many turns before
    the next one ends (overlapping windows). At least REVS_PER_WINDOW steady turns are needed.
    """
    if not hop_ok(hop_revs):
        raise IdentifyError(f"hop_revs: {hop_revs!r}; allowed: {MIN_HOP_REVS} <= hop_revs <= {REVS_PER_WINDOW}")
    c = np.asarray(counts, dtype=np.float64)
    if c.size < 4 or not np.all(np.isfinite(c)):
        raise IdentifyError("the encoder counts are missing, too short or not finite")
    start = int(round(skip_s * rate_hz))
    turns = c[start:] / counts_per_rev
    moved = float(abs(turns[-1] - turns[0])) if turns.size else 0.0
    L = max(1, int(round(RATE_WINDOW_S * rate_hz)))
    if turns.size <= 2 * L and moved >= REVS_PER_WINDOW:  # turns enough, but too briefly to measure its rate
        raise IdentifyError(f"too short: {turns.size / rate_hz:.3f} s after {skip_s:g} s ({moved:.2f} crank "
                            f"revolutions); the crank rate is measured over {RATE_WINDOW_S * 1e3:g} ms windows, "
                            f"so more than {2 * L / rate_hz:g} s are needed")
    if turns.size <= 2 * L or moved < REVS_PER_WINDOW:
        raise IdentifyError(f"too little motion: {moved:.2f} crank revolutions after {skip_s:g} s "
                            f"(at least {REVS_PER_WINDOW} steady revolutions are needed)")
    hz = (turns[L:] - turns[:-L]) * rate_hz / L  # rate over [i, i + L)
    ref = float(np.median(hz[len(hz) // 2:]))
    if abs(ref) <= 1e-6:
        raise IdentifyError("too little motion: the crank is at rest over the last half of the recording")
    # a within-turn speed ripple moves the 50 ms rate by as much as the ripple's peaks: the tolerance grows
    # to hold the last half's own spread (its 95th percentile, plus RIPPLE_ALLOWANCE), up to MAX_SPEED_TOL
    # (features/6; with the fixed tolerance of features/5 a rippled recording had short steady stretches, or
    # none). A recording without ripple keeps speed_tol: its windows are those of features/5.
    spread = float(np.quantile(np.abs(hz[len(hz) // 2:] / ref - 1.0), 0.95))
    tol = max(speed_tol, min(spread + RIPPLE_ALLOWANCE, MAX_SPEED_TOL))
    ok = np.abs(hz / ref - 1.0) <= tol
    direction = 1 if ref > 0 else -1
    widened = tol > speed_tol
    if widened:
        # a swing's peaks may pass the tolerance once a turn and cut the 50 ms stretch into single turns: whole
        # turns decide, back from the last steady rate sample (a stop at the end is left out)
        last = np.flatnonzero(ok)
        b = int(last[-1]) + L if last.size else 0
        a = _first_steady_turn(direction * turns, 0, b, ok, L) if b > 0 else 0
    else:
        # longest run of steady rate samples
        edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(np.int8), [0]])))
        runs = edges.reshape(-1, 2)
        a, b = max(runs, key=lambda r: r[1] - r[0]) if len(runs) else (0, 0)
        b = b + L - 1  # the last rate sample covers L samples of position
    pos = direction * turns[a:b + 1]
    steady_turns = float(pos[-1] - pos[0])
    if steady_turns < REVS_PER_WINDOW:
        raise IdentifyError(f"too little steady motion: {steady_turns:.2f} crank revolutions "
                            + (f"whose mean rate lies within {TURN_TOL:.0%} of the steady rate" if widened else
                               f"within {tol:.0%} of {abs(ref):.2f} Hz")
                            + f" (at least {REVS_PER_WINDOW} are needed)")
    run_min = np.minimum.accumulate(pos[::-1])[::-1]  # monotone from the end backwards
    wins: list[tuple[int, int]] = []
    stop = len(pos) - 1
    while True:
        target = pos[stop] - REVS_PER_WINDOW
        # the last sample at or below the target, looking backwards from stop
        k = int(np.searchsorted(run_min[:stop + 1], target, side="right")) - 1
        if k < 0:
            break
        wins.append((start + a + k, start + a + stop))
        # the next window ends hop_revs earlier (back to back: where this one starts)
        nxt = k if hop_revs >= REVS_PER_WINDOW else \
            int(np.searchsorted(run_min[:stop + 1], pos[stop] - hop_revs, side="right")) - 1
        if not 0 <= nxt < stop:
            break
        stop = nxt
    wins.reverse()
    # the windows' mean rate: whole turns over their duration (the median of a rippled 50 ms rate is not
    # its mean; the steady part's edges may hold the end of a spin-up)
    rate = abs(ref)
    if wins:
        w0, w1 = wins[0][0], wins[-1][1]
        rate = abs(turns[w1 - start] - turns[w0 - start]) * rate_hz / max(w1 - w0, 1)
    return Windows((start + a, start + b + 1), wins, steady_turns, rate, direction, spread)


def _first_steady_turn(pos: np.ndarray, a: int, b: int, ok: np.ndarray | None = None, L: int = 1) -> int:
    """Where the steady part of [a, b] starts when judged by whole turns: whole turns of ``pos`` [turns,
    increasing with the motion] are taken back to back from ``b`` backwards while each one's mean rate lies
    within :data:`TURN_TOL` of the mean rate over the last half of [a, b]; the start of the earliest such turn
    (a turn that strays is left out with all before it; the part before the first whole turn is kept where its
    own mean rate lies within :data:`TURN_TOL` and, ``ok`` given, every ``L``-sample rate in it is ``ok``: a
    spin-up from rest is not)."""
    mid = (a + b) // 2
    if b - mid < 2 or pos[b] - pos[mid] <= 0:
        return a
    mean = (pos[b] - pos[mid]) / (b - mid)  # [turns per sample]
    run_min = np.minimum.accumulate(pos[a:b + 1][::-1])[::-1]  # monotone from the end backwards
    end = b - a
    while True:
        k = int(np.searchsorted(run_min[:end + 1], pos[a + end] - 1.0, side="right")) - 1
        if k < 0:  # less than a whole turn left: kept where it too turns at the steady rate
            rest = (pos[a + end] - pos[a]) / end / mean - 1.0 if end > 0 else 0.0
            steady_rate = ok is None or bool(np.all(ok[a:max(a + end - L + 1, a + 1)]))
            return a if abs(rest) <= TURN_TOL and steady_rate else a + end
        if abs((pos[a + end] - pos[a + k]) / (end - k) / mean - 1.0) > TURN_TOL:
            return a + end  # a turn off the steady rate: the steady part starts after it
        end = k


def _kurtosis(x: np.ndarray) -> float:
    x = x - x.mean()
    v = float(np.mean(x * x))
    return float(np.mean(x ** 4) / (v * v)) if v > 0 else 0.0


def _crest(x: np.ndarray) -> float:
    r = float(np.sqrt(np.mean(x * x)))
    return float(np.max(np.abs(x)) / r) if r > 0 else 0.0


def window_features(acc: dict[str, np.ndarray], counts: np.ndarray, rate_hz: float, counts_per_rev: float,
                    start: int, stop: int, hp_sos: np.ndarray | None = None, orientation: str = "y") -> np.ndarray:
    """Feature vector (:func:`feature_names` order) of samples [start, stop) (whole revolutions)."""
    from scipy.signal import butter, sosfiltfilt, welch

    if hp_sos is None:
        hp_sos = butter(4, HIGHPASS_HZ, btype="highpass", fs=rate_hz, output="sos")
    c = np.asarray(counts[start:stop], dtype=np.float64) / counts_per_rev
    n = stop - start
    revs = abs(c[-1] - c[0])
    crank_hz = revs * rate_hz / n
    omega = 2 * math.pi * crank_hz
    a_ref = CRANK_RADIUS_M * omega * omega  # rigid-body acceleration scale [m/s²]
    db_ref = 20.0 * math.log10(max(a_ref, 1e-6))  # 10 log10 of (r ω²)²
    out = [crank_hz] + [1.0 if orientation == o else 0.0 for o in ORIENTATIONS]
    hp_rms_of: dict[str, float] = {}
    ratio_band_of: dict[str, float] = {}
    sector_energy = {g: np.zeros(SECTORS) for g in GROUPS}
    # absolute crank angle (the encoder's zero: crank along -y) of every sample, in sectors
    sector = (np.floor(np.mod(c, 1.0) * SECTORS).astype(np.int64)) % SECTORS
    # angle grid: whole revolutions from the window's first boundary
    order = np.argsort(c, kind="stable")
    c_sorted = c[order]
    nrev = max(1, int(round(revs)))
    lo = c_sorted[0]  # windows start at any crank angle: the grid starts where the window does
    grid = lo + (np.arange(nrev * ANGLE_SAMPLES) + 0.5) / ANGLE_SAMPLES
    for s in SENSORS:
        x = np.asarray(acc[s][start:stop], dtype=np.float64)
        xa = np.interp(grid, c_sorted, x[order]).reshape(nrev, ANGLE_SAMPLES)
        avg = xa.mean(axis=0)
        spec = np.abs(np.fft.rfft(avg - avg.mean())) * 2.0 / ANGLE_SAMPLES
        out += [float(spec[k]) / a_ref for k in ORDERS]
        resid = xa - avg
        sig = float(np.sqrt(np.mean((xa - xa.mean()) ** 2)))
        out += [float(np.sqrt(np.mean(resid * resid))) / sig if sig > 0 else 0.0, sig / a_ref]
        f, p = welch(x - x.mean(), fs=rate_hz, nperseg=min(4096, n), noverlap=None)
        df = f[1] - f[0]
        for blo, bhi in BANDS_HZ:
            sel = (f >= blo) & (f < bhi)
            e = float(np.sum(p[sel]) * df) if np.any(sel) else 0.0
            out.append(10.0 * math.log10(e + 1e-12) - db_ref)  # energy over (r ω²)²
        hp = sosfiltfilt(hp_sos, x)
        hp_rms = float(np.sqrt(np.mean(hp * hp)))
        hp_rms_of[s] = hp_rms
        sel = (f >= RATIO_BAND_HZ[0]) & (f < RATIO_BAND_HZ[1])
        ratio_band_of[s] = float(np.sum(p[sel]) * df)
        for g, members in GROUPS.items():
            if s in members:
                sector_energy[g] += np.bincount(sector, weights=hp * hp, minlength=SECTORS)
        mad = float(np.median(np.abs(hp - np.median(hp)))) * 1.4826
        thr = 6.0 * mad if mad > 0 else np.inf
        events = _events(np.abs(hp), thr, int(round(IMPACT_GAP_S * rate_hz)))
        out += [len(events) / max(revs, 1e-9), _kurtosis(x), _crest(x - x.mean()), hp_rms / a_ref,
                float(np.max(np.abs(hp))) / a_ref]
    tiny = 1e-12
    out += [math.log10((hp_rms_of[a] + tiny) / (hp_rms_of[b] + tiny)) for a, b in PAIRS]
    out += [math.log10((ratio_band_of[a] + tiny) / (ratio_band_of[b] + tiny)) for a, b in PAIRS]
    for g in GROUPS:
        e = sector_energy[g]
        out += list(e / e.sum()) if e.sum() > 0 else [1.0 / SECTORS] * SECTORS
    return np.array(out, dtype=np.float64)


def _events(y: np.ndarray, threshold: float, gap: int) -> np.ndarray:
    """Peak height of each burst of ``y`` above ``threshold``; bursts less than ``gap`` samples
    apart are one (an impact rings for a few milliseconds)."""
    if not np.isfinite(threshold):
        return np.zeros(0)
    above = np.flatnonzero(y > threshold)
    if above.size == 0:
        return np.zeros(0)
    breaks = np.flatnonzero(np.diff(above) > gap)
    starts = np.concatenate([[0], breaks + 1])
    stops = np.concatenate([breaks + 1, [above.size]])
    return np.array([float(np.max(y[above[a]:above[b - 1] + 1])) for a, b in zip(starts, stops)])


def features(acc: dict[str, np.ndarray], counts: np.ndarray, rate_hz: float, counts_per_rev: float,
             skip_s: float = 0.0, orientation: str = "y", hop_revs: float = REVS_PER_WINDOW
             ) -> tuple[np.ndarray, Windows]:
    """Feature matrix [windows, features] of a recording and its windows (see module docstring; ``hop_revs``:
    :func:`steady_windows`)."""
    from scipy.signal import butter

    missing = [s for s in SENSORS if s not in acc]
    if missing:
        raise IdentifyError(f"calibrated accelerations missing for {', '.join(missing)}")
    w = steady_windows(counts, rate_hz, counts_per_rev, skip_s, hop_revs=hop_revs)
    if not w.windows:
        raise IdentifyError("too little steady motion for one window")
    sos = butter(4, HIGHPASS_HZ, btype="highpass", fs=rate_hz, output="sos")
    if orientation not in ORIENTATIONS:
        raise IdentifyError(f"orientation must be one of {', '.join(ORIENTATIONS)}, got {orientation!r}")
    X = np.stack([window_features(acc, counts, rate_hz, counts_per_rev, a, b, sos, orientation) for a, b in w.windows])
    return X, w
