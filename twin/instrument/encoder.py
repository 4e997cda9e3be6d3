"""Crank encoder (SICK DGS80, 4× quadrature counting): angle ↔ counts, unwrap, glitches.

Counting: an ideal quadrature decoder's count is a function of position only, so for the
encoder angle φ (zero with the crank along −y, :mod:`twin.channels`) the count is
``floor(φ / Δ)`` with Δ = 2π / counts_per_rev (32768 → 0.011°), in either direction of motion.
Count 0 covers φ ∈ [0, Δ): the best angle estimate of a count c is its centre (c + ½) Δ.

Recorded counts may come from a counter that wraps (e.g. a 32-bit register, or a counter reset
every turn): :func:`unwrap_counts` makes them continuous given the modulus. Encoder glitches
(electrical noise on the A/B lines, a dropped DAQ sample) show up as jumps larger than the crank
can physically move in one sample; :func:`check_counts` repairs short spikes that return to the
track (reporting each) and refuses steps that do not return (lost counts cannot be recovered).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from twin.errors import RecordingError

#: Longest burst of bad samples that :func:`check_counts` repairs [samples].
MAX_GLITCH_SAMPLES = 8


def count_step_rad(counts_per_rev: int) -> float:
    """Angle per count Δ [rad]."""
    return 2.0 * math.pi / counts_per_rev


def angle_to_counts(phi: np.ndarray, counts_per_rev: int, quantize: bool = True) -> np.ndarray:
    """Counts of encoder angle ``phi`` [rad] (float64; whole counts when ``quantize``)."""
    c = np.asarray(phi, dtype=np.float64) / count_step_rad(counts_per_rev)
    return np.floor(c) if quantize else c


def counts_to_angle(counts: np.ndarray, counts_per_rev: int, centre: bool = True) -> np.ndarray:
    """Encoder angle [rad] of (unwrapped) counts; ``centre`` adds half a count (unbiased for whole counts)."""
    c = np.asarray(counts, dtype=np.float64)
    return (c + (0.5 if centre else 0.0)) * count_step_rad(counts_per_rev)


def unwrap_counts(counts: np.ndarray, modulus: int) -> np.ndarray:
    """Continuous counts from a counter that wraps at ``modulus`` (jumps > modulus/2 are wraps)."""
    if not (isinstance(modulus, (int, np.integer)) and modulus >= 2):
        raise ValueError(f"modulus must be an integer >= 2, got {modulus!r}")
    c = np.asarray(counts, dtype=np.float64)
    if c.size < 2:
        return c.copy()
    d = np.diff(c)
    d -= modulus * np.round(d / modulus)
    return np.concatenate([[c[0]], c[0] + np.cumsum(d)])


def max_counts_per_sample(counts_per_rev: int, rate_hz: float, max_crank_rpm: float) -> float:
    """Largest plausible count change between two samples for a crank at ``max_crank_rpm``."""
    return max_crank_rpm / 60.0 * counts_per_rev / rate_hz


@dataclass
class EncoderReport:
    """What :func:`check_counts` found and did.

    Attributes:
        repaired: list of (first sample, last sample) bursts replaced by interpolation.
        messages: one line per repair, for reports.
        max_step: the plausibility limit used [counts/sample].
    """

    repaired: list[tuple[int, int]] = field(default_factory=list)
    messages: list[str] = field(default_factory=list)
    max_step: float = 0.0


def check_counts(counts: np.ndarray, rate_hz: float, max_step: float, repair: bool = True,
                 name: str = "encoder_counts") -> tuple[np.ndarray, EncoderReport]:
    """Validate unwrapped encoder counts; repair short glitches.

    A jump |c[i+1] − c[i]| > ``max_step`` is a glitch. If the signal comes back within
    :data:`MAX_GLITCH_SAMPLES` samples to a value consistent with the track before the jump
    (at most ``max_step`` per elapsed sample), the bad samples are replaced by the rounded
    straight line between the good neighbours and the repair is reported. Otherwise (a step
    that never returns: lost counts or a counter reset) a :class:`RecordingError` is raised.
    With ``repair = False`` any glitch is an error. Returns (counts, report).
    """
    c = np.array(counts, dtype=np.float64)
    if c.ndim != 1:
        raise RecordingError(f"{name}: must be 1-D")
    if not np.all(np.isfinite(c)):
        i = int(np.flatnonzero(~np.isfinite(c))[0])
        raise RecordingError(f"{name}: NaN or infinite count at sample {i} (t = {i / rate_hz:.6f} s)")
    report = EncoderReport(max_step=float(max_step))
    limit = max_step + 1.0  # a count can flip by one on top of the motion (edge jitter)
    i = 0
    n = c.size
    while True:
        bad = np.flatnonzero(np.abs(np.diff(c[i:])) > limit)
        if bad.size == 0:
            break
        k = i + int(bad[0])  # jump between k and k+1
        t = (k + 1) / rate_hz
        jump = c[k + 1] - c[k]
        end = None
        for j in range(k + 2, min(n, k + 2 + MAX_GLITCH_SAMPLES)):
            if abs(c[j] - c[k]) <= limit * (j - k):
                end = j
                break
        if end is None or not repair:
            what = ("a step that does not return: lost counts or a counter reset; cannot repair"
                    if end is None else "a glitch (repair disabled)")
            raise RecordingError(f"{name}: jumps by {jump:+.0f} counts at sample {k + 1} (t = {t:.6f} s), more "
                                 f"than the {max_step:.2f} counts/sample the crank can move: {what}")
        seg = np.arange(k + 1, end)
        c[seg] = np.rint(c[k] + (c[end] - c[k]) * (seg - k) / (end - k))
        report.repaired.append((k + 1, end - 1))
        report.messages.append(f"{name}: repaired a {end - k - 1}-sample glitch of {jump:+.0f} counts at "
                               f"sample {k + 1} (t = {t:.6f} s) by interpolation")
        i = end
    return c, report
