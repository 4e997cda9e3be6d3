"""Amplitude spectra of a time window (Hann window, as in S003 §5) for the rerun view."""

from __future__ import annotations

import numpy as np

from twin.config import BenchConfig
from twin.errors import TwinError
from twin.signals import hann_spectrum

#: reference amplitude of the dB scale [m/s^2] (1 mm/s^2, about 0.1 mg): bars start at 0 dB
DB_REF_MPS2 = 1e-3
#: most bars one spectrum shows; finer spectra keep the peak of each group of bins
MAX_BARS = 20_000
#: fewest samples a window may hold
MIN_SAMPLES = 64


def default_window(cfg: BenchConfig | None, t_start: float, t_end: float) -> tuple[float, float]:
    """Default spectrum window [s] within [t_start, t_end].

    The protocol: the second before the last second of its last speed hold (steady speed,
    the paper's highest speed for the default protocol: 34–35 s). Otherwise the last
    min(1 s, half the run) of the run.
    """
    if cfg is not None and cfg.drive.program == "protocol":
        d = cfg.drive
        n = len(d.protocol_rpm)
        end_hold = n * d.protocol_stop_s + n * d.protocol_hold_s
        t0, t1 = end_hold - 2.0, end_hold - 1.0
        if t_start <= t0 and t1 <= t_end and t0 >= end_hold - d.protocol_hold_s + d.ramp_s:
            return (t0, t1)
    length = min(1.0, 0.5 * (t_end - t_start))
    return (t_end - length, t_end)


def check_window(window: tuple[float, float], t_start: float, t_end: float, rate_hz: float,
                 flag: str = "fft_window_s") -> None:
    """Raise a one-line :class:`TwinError` naming ``flag`` unless ``window`` lies in the run and holds
    enough samples."""
    t0, t1 = window
    eps = 0.5 / rate_hz
    if t0 < t_start - eps or t1 > t_end + eps:
        raise TwinError(f"{t0:g}..{t1:g} s lies outside the run ({t_start:g}..{t_end:g} s)", field=flag)
    if (t1 - t0) * rate_hz < MIN_SAMPLES:
        raise TwinError(f"{t0:g}..{t1:g} s holds fewer than {MIN_SAMPLES} samples at {rate_hz:g} Hz", field=flag)


def peak_bins(f: np.ndarray, amp: np.ndarray, max_bins: int) -> tuple[np.ndarray, np.ndarray]:
    """At most ``max_bins`` bins: more are merged in groups of k, each keeping its first frequency
    and its peak amplitude."""
    if len(f) <= max_bins:
        return f, amp
    k = int(np.ceil(len(f) / max_bins))
    m = len(f) // k * k
    return f[:m].reshape(-1, k)[:, 0], amp[:m].reshape(-1, k).max(axis=1)


def amplitude_db(x: np.ndarray, rate_hz: float, max_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies [Hz], amplitude [dB re 1 mm/s^2, floored at 0]) of ``x``.

    The amplitude spectrum is :func:`twin.signals.hann_spectrum` (periodic Hann window, a
    sinusoid of amplitude A reads A), with the mean removed (gravity and offsets would fill
    the lowest bins). Bins above ``max_hz`` are dropped; more than :data:`MAX_BARS` bins are
    merged keeping each group's peak.
    """
    f, amp = hann_spectrum(np.asarray(x, dtype=float), rate_hz, remove_mean=True)
    keep = f <= max_hz
    f, amp = peak_bins(f[keep], amp[keep], MAX_BARS)
    db = 20.0 * np.log10(np.maximum(amp, 1e-30) / DB_REF_MPS2)
    return f, np.maximum(db, 0.0)
