"""What a recording is, measured, against what the identification model was trained on.

An answer is only calibrated for recordings like the training runs. These are the quantities a recording
shows by itself, measured the same way on every training run (``twin identify train`` stores their ranges
in the model file) and on every recording answered:

* **crank rate** [Hz]: the steady rate of :func:`twin.identification.features.steady_windows`;
* **within-turn speed ripple** [% of the mean speed], harmonics 1 to :data:`RIPPLE_HARMONICS` of the crank
  rate, from the encoder alone (:func:`measure_ripple`);
* **noise level** [µg/√Hz]: the accelerometers' noise floor above the sensors' resonance
  (:func:`measure_noise`);
* **orientation**: the bench axis that points up (the recording's configuration);
* **direction of rotation**: forward or reverse, from the encoder (:mod:`twin.identification.rotation`);
* **speed swing** [%]: the 50 ms crank rate's swing in steady running (:attr:`twin.identification.features.
  Windows.swing`): it widens the steady part's tolerance without a cap below a stop, so a recording that turns
  through whole turns is answered however it swings;
* **distance in feature space**: how many of the recording's features lie beyond Tukey's far-out fences
  (quartiles ± 3 interquartile ranges) of the training windows' (:func:`feature_outliers`), where the model
  stores those quartiles.

**Rules** (:func:`out_of_range`). A quantity is outside when it lies beyond the training range widened by a
margin for its measurement, stated here and never tuned on an answer:

* crank rate: ±:data:`SPEED_MARGIN` (3 %, the allowance the model has always given the measured rate);
* ripple: above the trained maximum of that harmonic by more than :data:`RIPPLE_MARGIN_PCT` (0.25 percentage
  points: the estimator reads a known imposed ripple to within 0.05 points, test; the rest allows for the PID
  tracking a rippled reference a little above or below it);
* noise: beyond the trained range by more than a factor :data:`NOISE_MARGIN` (1.15: the level, a median over
  short segments of six sensors, reads the noise density put in to within ±2.5 % whatever the clearance,
  speed and engine: measured level / noise scale 29.7-30.9 µg/√Hz over 1594 MuJoCo training runs and 427
  reference-engine development runs, noise ×0.7-4; the margin is six times that spread);
* orientation: not among the training runs';
* direction of rotation: not among the training runs' (a model that does not store them: forward only,
  :mod:`twin.identification.rotation`);
* features: more features beyond the training windows' far-out fences than 99 % of the training runs have
  (``max_outliers``, stored by :func:`feature_reference`); a model without that count: at least
  :data:`FEATURE_OUTLIER_SHARE` (5 %) of the features; and, whatever the training runs reach, a third of the
  features or more (:data:`FEATURE_FAR_SHARE`: judged on the recording itself, a confident answer resting on
  so many features the trees never saw there is not);
* rigid rod (:data:`RIGID_ROD_FEATURE`): the rod's two longitudinal accelerometers, AC1 at B and AC4 at C, read the
  same acceleration above :data:`twin.identification.features.RATIO_BAND_HZ`'s 800 Hz on a rigid rod (a rigid body's
  points on one line along it share their acceleration along that line, but for the centripetal term, which lies
  far below the band); the log10 ratio of their band energies beyond :data:`RIGID_ROD_RATIO_MAX` says the rod does
  not move as one body there (a flexible structure: the rod's axial modes; or a sensor loose on its mount);
* speed swing (the 50 ms crank rate's swing in steady running, :attr:`twin.identification.features.Windows.swing`):
  beyond :data:`BENCH_SWING_PCT` (85 %, the most the bench's motor drive gives, measured), or, where the model
  stores the training runs' range, beyond its top by :data:`SWING_MARGIN_PCT` (5 points).

**What an answer says of sizes.** Every size and interval lies within the clearances the model was trained on at
that joint (:func:`clip_to_hull`: never below the smallest trained size, never above the largest).

**What an answer outside says.** One warning per reason, and, at each joint, the interval replaced by every
clearance the model was trained on at that joint, the same for every recording (:func:`widen`): outside the training data the conformal
guarantee (exchangeability with the training runs) no longer holds, and nothing the model stores tells how far
its answer may stray, save that a tree ensemble answers within the values it was trained on. The widened
interval is honest and says little; the fault location is still given, with the warnings.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from twin.identification.rotation import rotation, rotation_warning, training_rotations

#: harmonics of the crank rate whose ripple is measured
RIPPLE_HARMONICS = 4
#: relative allowance on the crank rate's training range [-]
SPEED_MARGIN = 0.03
#: allowance above a harmonic's trained ripple [percentage points]
RIPPLE_MARGIN_PCT = 0.25
#: factor of allowance on the noise level's training range [-]
NOISE_MARGIN = 1.15
#: share of features beyond the training windows' far-out fences that makes a recording outside, for a model
#: that stores no ``max_outliers`` [-]
FEATURE_OUTLIER_SHARE = 0.05
#: share of features beyond the training windows' far-out fences that makes a recording outside whatever the
#: training runs' own counts (a third: the answer then rests on features the trees never split on there) [-]
FEATURE_FAR_SHARE = 1.0 / 3.0
#: the largest crank-rate swing of steady running the bench's motor drive gives [%]: the 95th percentile of the
#: 50 ms rate's deviation from its median over the last half of a recording (:attr:`twin.identification.features.
#: Windows.swing`), measured on 60 motor-drive runs that turn (of 72; 3 s, MuJoCo) with the drive train's
#: placeholders drawn over their documented ranges, x/y/z vertical, 250-800 rpm: median 28 %, 90th percentile
#: 46 %, largest 75.7 % (x vertical, a soft speed loop); the threshold is that largest plus the steady part's
#: allowance RIPPLE_ALLOWANCE (5 points), rounded up to 5 % (``analysis/identify/speed_swing.py``, result
#: ``analysis/results/identify/speed_swing.json``). A recording that swings more is answered with a warning
BENCH_SWING_PCT = 85.0
#: allowance above the training runs' largest swing [percentage points]: the allowance the steady part's
#: tolerance gives a recording's own spread (:data:`twin.identification.features.RIPPLE_ALLOWANCE`)
SWING_MARGIN_PCT = 5.0
#: the feature of the rigid-rod check: log10 of the 0.8-6 kHz band energy of AC1 (rod, at B, along it) over AC4's
#: (rod, at C, along it) (:mod:`twin.identification.features`)
RIGID_ROD_FEATURE = "ratio_band_AC1_AC4"
#: the largest |RIGID_ROD_FEATURE| (a recording's median over its windows) of a rod moving as one body [log10]:
#: 1812 whole-bench training runs (both engines, rigid structure, sensor mount offsets, noise and contact
#: parameters drawn) reach 0.069 and the 97 development runs 0.023; the threshold is the training runs' largest rounded
#: up to 0.1 (a 26 % band-energy difference between the rod's two ends). Recordings of the flexible structure
#: (``structure.mode = "flexible"``, ``twin record``) read 0.17-0.46 in 7 of 8 (x/y/z vertical, 300-700 rpm, both
#: engines), 0.026 in the eighth (z vertical, 300 rpm, 0.5 mm at B: the impacts' energy dominates both ends);
#: ``analysis/identify/rigid_rod_check.py``
RIGID_ROD_RATIO_MAX = 0.1
#: Tukey's far-out fences: quartiles ± this many interquartile ranges
FENCE_IQR = 3.0
#: noise band [Hz]: above the accelerometers' 21 kHz resonance, below the 50 kHz Nyquist rate of the DAQ
NOISE_BAND_HZ = (30_000.0, 48_000.0)
#: samples per segment of the noise floor's median
NOISE_SEGMENT = 1024
STANDARD_G = 9.80665


def measure_ripple(counts: np.ndarray, rate_hz: float, counts_per_rev: float, start: int, stop: int,
                   harmonics: int = RIPPLE_HARMONICS) -> list[float]:
    """Within-turn speed ripple of samples [start, stop) (whole revolutions) from the encoder [% of the mean
    speed], harmonics 1..``harmonics`` of the crank rate.

    A speed ω(t) = Ω (1 + Σ a_k sin(kΩt + p_k)) turns the crank by
    φ(t) = φ0 + Ω t − Σ (a_k/k) cos(kΩt + p_k):
    least squares fit φ (counts → rad) to a quadratic in t (the mean speed and a slow drift) and the cosine and
    sine at kΩ, Ω the mean rate over the span; a_k = k · (harmonic amplitude [rad]). Ripple tied to the crank
    angle instead of time (``crank_trace``, the drive's ``ripple_pct``) reads the same to first order in a_k."""
    phi = np.asarray(counts[start:stop], dtype=np.float64) * (2.0 * math.pi / counts_per_rev)
    n = phi.size
    if n < 8:
        return [0.0] * harmonics
    t = np.arange(n) / rate_hz
    T = t[-1]
    omega = (phi[-1] - phi[0]) / T
    tc = (t - T / 2.0) / T  # in [-1/2, 1/2]: the normal equations stay well conditioned
    cols = [np.ones(n), tc, tc * tc]
    for k in range(1, harmonics + 1):
        cols += [np.cos(k * omega * t), np.sin(k * omega * t)]
    A = np.stack(cols, axis=1)
    coef = np.linalg.solve(A.T @ A, A.T @ (phi - phi[0]))
    out = []
    for k in range(1, harmonics + 1):
        c, s = coef[3 + 2 * (k - 1)], coef[4 + 2 * (k - 1)]
        out.append(float(100.0 * k * math.hypot(c, s)))
    return out


def measure_noise(acc: dict[str, np.ndarray], rate_hz: float, start: int, stop: int) -> float:
    """Noise floor of the calibrated accelerations over samples [start, stop) [µg/√Hz]: per sensor, the
    median over segments of :data:`NOISE_SEGMENT` samples of the root mean one-sided power density in
    :data:`NOISE_BAND_HZ` (Hann window), the median over the sensors. Above the sensors' resonance the
    mechanism's content is attenuated; the median over segments leaves the impacts' bursts out."""
    hi = min(NOISE_BAND_HZ[1], 0.48 * rate_hz)
    lo = min(NOISE_BAND_HZ[0], 0.6 * hi)
    win = np.hanning(NOISE_SEGMENT)
    f = np.fft.rfftfreq(NOISE_SEGMENT, 1.0 / rate_hz)
    sel = (f >= lo) & (f < hi)
    levels = []
    for x in acc.values():
        x = np.asarray(x[start:stop], dtype=np.float64)
        m = x.size // NOISE_SEGMENT
        if m < 1 or not sel.any():
            continue
        seg = x[:m * NOISE_SEGMENT].reshape(m, NOISE_SEGMENT)
        seg = (seg - seg.mean(axis=1, keepdims=True)) * win
        p = np.abs(np.fft.rfft(seg, axis=1)) ** 2 * (2.0 / (rate_hz * np.sum(win * win)))
        levels.append(math.sqrt(float(np.median(p[:, sel].mean(axis=1)))))
    if not levels:
        return float("nan")
    return float(np.median(levels)) / STANDARD_G * 1e6


#: windows whose mean rate differs from the last window's by more than this share are left out of the
#: ripple's span (the tail of a spin-up is a slow speed change, not a ripple) [-]
RIPPLE_SPAN_TOL = 0.005


def ripple_span(counts: np.ndarray, windows: Any) -> tuple[int, int]:
    """Samples [start, stop) over which the ripple is measured: the steady windows, from the last one back
    while each window's mean rate stays within :data:`RIPPLE_SPAN_TOL` of the last one's."""
    ws = windows.windows
    rate = [abs(float(counts[b - 1]) - float(counts[a])) / max(b - 1 - a, 1) for a, b in ws]
    first = len(ws) - 1
    while first > 0 and abs(rate[first - 1] / rate[-1] - 1.0) <= RIPPLE_SPAN_TOL:
        first -= 1
    return ws[first][0], ws[-1][1]


def recording_measures(acc: dict[str, np.ndarray], counts: np.ndarray, rate_hz: float, counts_per_rev: float,
                       windows: Any) -> dict[str, Any]:
    """The measured quantities of a recording's steady windows (module docstring): crank rate [Hz], ripple
    per harmonic [%], noise level [µg/√Hz], speed swing [%] and the direction of rotation
    (:mod:`twin.identification.rotation`)."""
    a, b = ripple_span(counts, windows)
    return {"crank_hz": float(windows.crank_hz),
            "ripple_pct": [round(v, 4) for v in measure_ripple(counts, rate_hz, counts_per_rev, a, b)],
            "noise_ug_rthz": round(measure_noise(acc, rate_hz, a, b), 3),
            "speed_swing_pct": round(100.0 * float(getattr(windows, "swing", 0.0)), 3),
            "rotation": rotation(counts, a, b)}


def training_ranges(measures: list[dict[str, Any]], orientations: list[str], source: str) -> dict[str, Any]:
    """Ranges of the training runs' measures (``ranges`` of a model's ``trained_on``)."""
    r = np.array([m["ripple_pct"] for m in measures], float)
    nz = np.array([m["noise_ug_rthz"] for m in measures], float)
    hz = np.array([m["crank_hz"] for m in measures], float)
    sw = np.array([m.get("speed_swing_pct", np.nan) for m in measures], float)
    swing = {"speed_swing_pct": [float(np.nanmin(sw)), float(np.nanmax(sw))]} if np.isfinite(sw).any() else {}
    return {"source": source, "runs": len(measures),
            "crank_hz": [float(hz.min()), float(hz.max())], **swing,
            "ripple_pct": [[float(r[:, k].min()), float(r[:, k].max())] for k in range(r.shape[1])],
            "noise_ug_rthz": [float(np.nanmin(nz)), float(np.nanmax(nz))],
            "orientations": sorted(set(orientations)), **training_rotations(measures)}


#: share of the training runs a feature-distance threshold leaves inside [-]
FEATURE_RUN_QUANTILE = 0.99


def feature_reference(X: np.ndarray, owner: np.ndarray | None = None) -> dict[str, Any]:
    """Quartiles of every feature over the training windows (the far-out fences' basis) and, given each
    window's run (``owner``), ``max_outliers``: the count of features beyond the fences that the training runs'
    own median feature vectors stay within, at the conformal rank ⌈(n + 1)·0.99⌉ of their n counts (a recording
    like the training runs exceeds it with probability at most 1 %). The training data span orientations,
    speeds and sizes, so a training run itself has many features beyond fences set by all windows' quartiles
    (development: median 1, 90th percentile 30, 99th 83 of 178); a fixed share would flag them."""
    X = np.asarray(X, float)
    q1, q3 = np.quantile(X, [0.25, 0.75], axis=0)
    ref: dict[str, Any] = {"q25": [float(v) for v in q1], "q75": [float(v) for v in q3]}
    if owner is not None:
        owner = np.asarray(owner)
        counts = np.sort([feature_outliers(np.median(X[owner == r], axis=0), ref)[0] for r in np.unique(owner)])
        k = min(int(math.ceil((counts.size + 1) * FEATURE_RUN_QUANTILE)), counts.size) - 1
        ref["max_outliers"] = int(counts[k])
        ref["rule"] = (f"more features beyond the far-out fences than {FEATURE_RUN_QUANTILE:.0%} of the training runs "
                       "have (conformal rank of their counts)")
    return ref


def feature_outliers(x: np.ndarray, ref: dict[str, list[float]]) -> tuple[int, list[int]]:
    """Number of features of ``x`` (a recording's median feature vector) beyond the far-out fences of
    ``ref``, and their indices."""
    q1, q3 = np.asarray(ref["q25"], float), np.asarray(ref["q75"], float)
    iqr = q3 - q1
    out = (x < q1 - FENCE_IQR * iqr) | (x > q3 + FENCE_IQR * iqr)
    # a feature constant over the training windows (iqr 0) is outside only where it differs
    idx = [int(i) for i in np.flatnonzero(out)]
    return len(idx), idx


def out_of_range(measures: dict[str, Any], orientation: str, ranges: dict[str, Any] | None,
                 x_median: np.ndarray | None = None, features_ref: dict[str, list[float]] | None = None,
                 feature_names: list[str] | None = None) -> tuple[list[str], dict[str, Any]]:
    """Warnings (one per reason) and the check's evidence for a recording's ``measures`` against the
    model's training ``ranges`` (module docstring's rules). ``ranges`` None: only the crank rate and the
    orientation can be checked (by the caller); nothing else is claimed."""
    warnings: list[str] = []
    ev: dict[str, Any] = {"measured": measures}
    turned = rotation_warning(measures.get("rotation"), ranges)  # a model without ranges: read as trained forward
    if turned:
        warnings.append(turned)
    if ranges is None:
        ev["ranges"] = "unavailable (the model stores no training ranges)"
        return warnings, ev
    lo, hi = ranges["crank_hz"]
    hz = measures["crank_hz"]
    if not (lo * (1 - SPEED_MARGIN) <= hz <= hi * (1 + SPEED_MARGIN)):
        warnings.append(f"crank rate {hz:.3f} Hz is outside the training range {lo:.3f}-{hi:.3f} Hz: "
                        "the answer is an extrapolation")
    tr = ranges["ripple_pct"]
    for k, v in enumerate(measures["ripple_pct"], start=1):
        top = tr[k - 1][1] if k <= len(tr) else 0.0
        if v > top + RIPPLE_MARGIN_PCT:
            warnings.append(f"within-turn speed ripple {v:.2f} % at {k}x the crank rate (measured from the encoder) "
                            f"is outside the training range 0-{top:.2f} % of that harmonic: the answer is an "
                            "extrapolation")
    nlo, nhi = ranges["noise_ug_rthz"]
    nz = measures["noise_ug_rthz"]
    if math.isfinite(nz) and not (nlo / NOISE_MARGIN <= nz <= nhi * NOISE_MARGIN):
        warnings.append(f"sensor noise level {nz:.1f} ug/rtHz is outside the training range {nlo:.1f}-{nhi:.1f} "
                        "ug/rtHz: the answer is an extrapolation")
    sw = measures.get("speed_swing_pct")
    if sw is not None and sw > BENCH_SWING_PCT:
        warnings.append(f"the crank rate swings {sw:.0f} % within 50 ms, more than the bench's motor drive gives in "
                        f"steady running (up to {BENCH_SWING_PCT:.0f} %, measured): a spin-up, a stall or a drive "
                        "unlike the bench's; the answer is an extrapolation")
    elif sw is not None and "speed_swing_pct" in ranges and sw > ranges["speed_swing_pct"][1] + SWING_MARGIN_PCT:
        warnings.append(f"the crank rate swings {sw:.0f} % within 50 ms, outside the training range 0-"
                        f"{ranges['speed_swing_pct'][1]:.0f} %: the answer is an extrapolation")
    if orientation not in ranges["orientations"]:
        warnings.append(f"orientation {orientation} was not in the training data: the answer is an extrapolation")
    if x_median is not None and feature_names and RIGID_ROD_FEATURE in feature_names:
        r = float(x_median[feature_names.index(RIGID_ROD_FEATURE)])
        ev["rigid_rod_ratio_log10"] = {"measured": round(r, 4), "limit": RIGID_ROD_RATIO_MAX}
        if math.isfinite(r) and abs(r) > RIGID_ROD_RATIO_MAX:
            warnings.append(f"the rod's two longitudinal accelerometers (AC1 at B, AC4 at C) differ by {abs(r):.2f} "
                            f"in log10 of their 0.8-6 kHz band energy, more than a rigid rod gives (up to "
                            f"{RIGID_ROD_RATIO_MAX:g}, measured): a flexible structure or a loose sensor mount, unlike "
                            "the training data; the answer is an extrapolation")
    if features_ref is None:
        ev["feature_distance"] = "unavailable (the model stores no reference of its training features)"
    elif x_median is not None:
        n, idx = feature_outliers(x_median, features_ref)
        limit = features_ref.get("max_outliers")
        ev["feature_distance"] = {"beyond_far_out_fences": n, "of": int(x_median.size),
                                  "training_runs_max": limit}
        far = n >= FEATURE_FAR_SHARE * x_median.size
        if far or ((n > limit) if limit is not None else (n >= FEATURE_OUTLIER_SHARE * x_median.size)):
            names = [feature_names[i] for i in idx[:3]] if feature_names else []
            warnings.append(f"{n} of {x_median.size} features lie beyond the training windows' far-out fences "
                            f"(e.g. {', '.join(names)}): the recording is unlike the training data")
    return warnings, ev


def trained_hull(seen: Any) -> tuple[float, float] | None:
    """The smallest and largest clearance the model was trained on at a joint [mm] (``seen``:
    ``trained_on["clearances_mm"][joint]``, a list of values or {min, max, ...}; 0, a ball bearing, is not a
    size); None where nothing was trained there."""
    if isinstance(seen, dict):
        vals = [float(seen["min"]), float(seen["max"])]
    else:
        vals = [float(v) for v in seen if float(v) > 0]
    return (min(vals), max(vals)) if vals else None


def clip_to_hull(interval: list[float] | tuple[float, float], seen: Any) -> list[float]:
    """The interval [mm] held within the clearances the model was trained on at that joint (:func:`trained_hull`):
    a tree ensemble answers within the values it was trained on, so no end of an interval lies below the
    smallest trained size or above the largest."""
    hull = trained_hull(seen)
    if hull is None:
        return list(interval)
    lo, hi = hull
    return [min(max(float(interval[0]), lo), hi), min(max(float(interval[1]), lo), hi)]


#: the guide's play answered within this factor of the largest play trained (0.25-0.4 mm of a model trained up to
#: 0.4 mm) warns that it may lie beyond the trained range: a play beyond it gives features inside the training data's
#: and is answered at the top of the hull (whole-bench fresh look: 0.6-1.0 mm answered 0.28-0.40 mm, 10 of 15
#: without a warning). Chosen on the development sets: docs/identification.md, "The whole bench"
HULL_TOP_FACTOR = {"G": 1.6}


def at_hull_top(joint: str, size_mm: float, seen: Any) -> float | None:
    """The size [mm] from which an answer at ``joint`` reads at the top of the clearances trained there
    (:data:`HULL_TOP_FACTOR`) where ``size_mm`` [mm] reaches it, else None (also at a joint without the rule)."""
    hull = trained_hull(seen) if joint in HULL_TOP_FACTOR else None
    if hull is None:
        return None
    top = hull[1] / HULL_TOP_FACTOR[joint]
    return top if size_mm >= top else None


def widen(interval: list[float], seen: Any) -> list[float]:
    """The interval outside the training data: every clearance the model was trained on at that joint
    (:func:`trained_hull`) [mm], the same for every recording (``seen``: ``trained_on["clearances_mm"][joint]``);
    see the module docstring. ``interval`` where nothing was trained at that joint."""
    hull = trained_hull(seen)
    return list(hull) if hull is not None else list(interval)
