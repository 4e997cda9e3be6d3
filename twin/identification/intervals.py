"""Conformal 90 % intervals of the clearance size: calibration from out-of-fold answers, and the half width an
answer takes.

Method (split-conformal at the level of recordings). The training runs with a clearance at a joint are split into
:data:`CONFORMAL_FOLDS` groups (``interval_folds="runs"``) or one group per motor speed (``"speed"``: every score
an answer at a speed its regressor never saw, as a bench recording's may be; :func:`_conformal_folds`). Each
group's runs are answered by a regressor fitted on the other groups; a run's score is
|log10(answer) − log10(truth)| [log10]; the ⌈(n + 1)·0.9⌉-th smallest score w (:func:`conformal_half_width`)
gives every answer the interval [size·10^−w, size·10^w], which holds the truth in at least 90 % of recordings
like the training runs (exchangeability).

The scores are split (Mondrian, :func:`_interval_parts`) where each side holds :data:`MONDRIAN_MIN_RUNS` runs, in
this order, each split adding a suffix to the key of the half width (``"B"``, ``"C"``):

* by the joint's size-resolution map (:func:`size_resolved`, :data:`SIZE_RESOLVED_FROM_RPM`): ``_unresolved``;
* by the recording's measured within-turn speed ripple (:data:`RIPPLE_BAND_PCT`): ``_rippled``;
* at the joints of ``fault_split`` (:data:`FAULT_SPLIT_JOINTS`), by whether both joints are located faulty:
  ``_both`` (the other joint's impacts reach this joint's sensors and scatter its size);
* by the answer's size at the boundaries of ``size_band_mm`` (default :data:`CATALOGUE_BANDS_MM`, one band per
  group of catalogue values): ``_small``, ``_small2``, ... below each boundary used (:func:`band_half_width`).

Variants recorded in the model file's ``trained_on.interval``: ``by_engine`` (each half width the largest of the
pooled runs' and each engine's runs', :func:`half_widths`), ``half_width_log10_by_windows`` (the same parts
calibrated on the out-of-fold runs' answers from their first n windows, for recordings answered from n windows,
:func:`half_widths_by_windows`) and ``normalized`` (normalized conformal scales q·(spread + beta),
:func:`normalized_scale`; not the default: a recording of one or two windows has no measurable spread).

The held-out size accuracy (:func:`held_out_accuracy`, :func:`held_out_at`) comes from the same out-of-fold
answers: per joint, orientation and training speed, the share within a factor :data:`HELD_OUT_FACTOR` of the truth.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from twin.config import CATALOGUE_DIAMETRAL_MM, Drive
from twin.identification.trees import ModelError

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
# At the slider guide G (its two-sided play, a model of format 5) no speed map was measured: on the whole-bench
# development sets (analysis/identify/train_bench.py) its size held within x1.5 in 2 of 16 runs with y vertical, where
# gravity holds the slider on its lower rail (and 6 of those 16 runs were not located G at all), against 7 of 16 with
# x and 16 of 19 with z vertical: G is resolved with x or z vertical over the trained speeds, never with y.
SIZE_RESOLVED_FROM_RPM = {
    "B": {"x": 375.0, "y": 300.0, "z": 250.0},
    "C": {"x": 425.0, "y": 475.0, "z": 300.0},
    "G": {"x": 250.0, "z": 250.0},
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
#: ``TrainOptions(size_band_mm=CATALOGUE_BANDS_MM)`` calibrates a half width for the answers of each group, where the
#: training runs allow, so that the coverage holds value by value and not only over all answers together
CATALOGUE_BANDS_MM = catalogue_bands(BAND_MIN_RATIO)
#: recordings whose largest within-turn speed ripple (harmonics 1-4 of the crank rate, measured from the encoder)
#: exceeds this [% of the speed] get their own conformal half widths (``"B_rippled"``, ...), where the training
#: runs allow: a motor driving through the V-belt ripples by 10-20 % at twice the crank rate (docs/drivetrain.md),
#: and the sizes of such runs scatter more than those of a crank PID's 0-4 % (development: 90 % intervals
#: calibrated on all runs together held 29-67 % of the drive train's B sizes). 4.5 % lies above the PID-driven
#: training runs' imposed 0-4 %
RIPPLE_BAND_PCT = 4.5
#: floor of the normalized intervals' difficulty offset beta [log10] (runs of one window have no spread)
SPREAD_FLOOR_LOG10 = 0.01


def size_resolved(joint: str, orientation: str, crank_hz: float) -> bool:
    """Whether the bench's sensors resolve the size of a clearance at ``joint`` ("B" or "C") at this
    crank rate [Hz] with ``orientation`` vertical (:data:`SIZE_RESOLVED_FROM_RPM`; 2 % allowance for
    the measured rate)."""
    rpm = SIZE_RESOLVED_FROM_RPM[joint].get(orientation)
    return rpm is not None and abs(crank_hz) * 60.0 * BELT_RATIO >= 0.98 * rpm


def resolution(orientation: str, crank_hz: float) -> dict[str, bool]:
    """:func:`size_resolved` at every location with a map: {"B": bool, "C": bool, "G": bool}."""
    return {j: size_resolved(j, orientation, crank_hz) for j in SIZE_RESOLVED_FROM_RPM}


#: the joints whose interval half widths are split by the located fault by default (the shipped model's)
FAULT_SPLIT_JOINTS = ("C",)


def fault_split_joints(value: Any) -> tuple[str, ...]:
    """The joints whose half widths are split by the fault, from ``TrainOptions.fault_split`` or a model file's
    ``trained_on.interval.fault_split``: True (both joints),
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
    # a location without a size-resolution map (the guide G): one part, no split by it
    on = np.array([j not in SIZE_RESOLVED_FROM_RPM or size_resolved(j, row["orientation"], row["crank_hz"])
                   for row in held_runs], bool)
    split = _mondrian([(j, everything)], ~on, "_unresolved")
    if ripple_split:
        split = _mondrian(split, np.array([rippled(row.get("measures", {}).get("ripple_pct")) for row in held_runs],
                                          bool), "_rippled")
    if fault_split:
        split = _mondrian(split, np.array([{"B", "C"} <= set(row.get("fault") or "") for row in held_runs], bool),
                          "_both")
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


def half_widths(j: str, scores: np.ndarray, held_runs: list[dict[str, Any]], answers: np.ndarray,
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


def reach_hull_floor(lo_mm: float, half_width: float, floor_mm: float | None) -> float:
    """The lower end [mm] of an interval whose answer lies near the smallest size trained at the joint
    (``floor_mm``, the trained hull's bottom; ``interval.hull_floor`` of a model file): where the interval's lower
    end ``lo_mm`` lies within its own half width ``half_width`` [log10] of the floor (lo < floor 10^w), it reaches
    down to the floor; else ``lo_mm``. A tree ensemble answers within the sizes it was trained on, so the answers
    for plays near the hull's bottom are censored there and scatter upward only: the symmetric conformal interval of
    such an answer misses the smallest plays more often than 10 % (whole-bench development sets: 3 of the 8 misses
    at G were plays of 0.013-0.018 mm whose intervals began at 0.018-0.043 mm). The upper end is not touched."""
    if floor_mm is None or not lo_mm < floor_mm * 10 ** half_width:
        return lo_mm
    return min(lo_mm, floor_mm)


def window_table(interval: dict[str, Any], windows: int) -> dict[str, float]:
    """The half widths [log10] of answers from ``windows`` windows in a model's ``interval`` record
    (``half_width_log10_by_windows``, :func:`half_widths_by_windows`); empty where it holds none for that count
    (an answer then takes the main table)."""
    return (interval.get("half_width_log10_by_windows") or {}).get(str(windows), {})


def half_widths_by_windows(j: str, window_logs: list[np.ndarray], held_runs: list[dict[str, Any]],
                            size_band_mm: float | list[float] | None, ripple_split: bool, by_engine: bool,
                            fault_split: bool = False) -> dict[str, dict[str, float]]:
    """Half widths [log10] of answers made from fewer windows than the training runs hold: for n = 1, 2, ... up to
    one less than the most windows of a run, those of :func:`half_widths` calibrated on each out-of-fold run's
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
        out[str(n)] = half_widths(j, scores, held_runs, answers, size_band_mm, ripple_split, by_engine, fault_split)
    return out


#: the factor of the truth within which an out-of-fold answer counts in the held-out size accuracy (the targets')
HELD_OUT_FACTOR = 1.5


def held_out_accuracy(scores: np.ndarray, held_runs: list[dict[str, Any]]) -> dict[str, dict[str, list]]:
    """The held-out size accuracy of one joint from its out-of-fold scores
    (:func:`twin.identification.training.train`): per orientation, at
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


