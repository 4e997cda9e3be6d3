"""The signal measures the calibration objective compares (:mod:`twin.calibration.objective`) and its
bootstrap resamples (:mod:`twin.calibration.bootstrap`): third-octave band levels, impact peaks and their
decay near the acceleration reversals, crank-speed harmonics and the low-passed crank speed."""

from __future__ import annotations

import math

import numpy as np

#: cut-off of the crank-speed low-pass of the ``command`` term [Hz]
COMMAND_LOWPASS_HZ = 50.0
#: lowest and highest third-octave band centres [Hz]
BAND_F_MIN_HZ, BAND_F_MAX_HZ = 200.0, 10_000.0


def third_octave_bands(rate_hz: float) -> list[tuple[float, float, float]]:
    """(centre, low, high) of the base-2 third-octave bands from 200 Hz to 10 kHz within Nyquist [Hz]."""
    out = []
    for k in range(0, 40):
        fc = BAND_F_MIN_HZ * 2.0 ** (k / 3.0)
        if fc > BAND_F_MAX_HZ * 1.0001:
            break
        lo, hi = fc * 2 ** (-1 / 6), fc * 2 ** (1 / 6)
        if hi <= rate_hz / 2:
            out.append((fc, lo, hi))
    return out


def band_levels_db(x: np.ndarray, rate_hz: float) -> np.ndarray:
    """Third-octave band energies [dB re 1 (m/s²)²] of ``x`` (Welch PSD, integrated over each band)."""
    from scipy.signal import welch

    nper = int(min(len(x), 2 ** int(math.log2(max(16, rate_hz / 25.0)))))  # ~25 Hz resolution
    f, p = welch(x - np.mean(x), fs=rate_hz, window="hann", nperseg=nper, noverlap=nper // 2)
    return band_levels_from_psd(f, p, rate_hz)


def band_levels_from_psd(f: np.ndarray, p: np.ndarray, rate_hz: float) -> np.ndarray:
    """Third-octave band energies [dB re 1 (m/s²)²] of a PSD ``p`` [(m/s²)²/Hz] on the frequencies ``f`` [Hz]."""
    df = f[1] - f[0]
    out = []
    for _fc, lo, hi in third_octave_bands(rate_hz):
        sel = (f >= lo) & (f < hi)
        e = float(np.sum(p[sel]) * df) if np.any(sel) else 0.0
        out.append(10.0 * math.log10(max(e, 1e-30)))
    return np.asarray(out)


def peak_events(x: np.ndarray, rate_hz: float) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The impact events near the acceleration reversals (module docstring): sample index of each
    peak, its |high-passed acceleration| and its decay ratio; None when the rate is too low for them."""
    from scipy.signal import butter, sosfiltfilt

    nyq = rate_hz / 2
    if nyq <= 600:
        return None
    low = sosfiltfilt(butter(2, min(150.0, 0.4 * nyq) / nyq, output="sos"), x - np.mean(x))
    high = sosfiltfilt(butter(4, 500.0 / nyq, btype="high", output="sos"), x)
    s = np.signbit(low)
    rev = np.flatnonzero(s[1:] != s[:-1])
    w, d0, d1 = int(0.003 * rate_hz), int(0.003 * rate_hz), int(0.008 * rate_hz)
    idx, peaks, decays = [], [], []
    last = -10 * w
    for i in rev:
        if i - last < 2 * w or i - w < 0 or i + w + d1 >= len(x):
            continue
        last = i
        seg = np.abs(high[i - w:i + w])
        k = i - w + int(np.argmax(seg))
        idx.append(k)
        peaks.append(float(seg.max()))
        early = float(np.sqrt(np.mean(high[k:k + d0] ** 2)))
        late = float(np.sqrt(np.mean(high[k + d0:k + d1] ** 2)))
        decays.append(late / early if early > 0 else 1.0)
    return np.asarray(idx, dtype=int), np.asarray(peaks, dtype=np.float64), np.asarray(decays, dtype=np.float64)


def peak_stats(x: np.ndarray, rate_hz: float) -> np.ndarray | None:
    """log10 of (median peak, 90th-percentile peak, median decay ratio) of the impact peaks near the
    acceleration reversals (module docstring); None when the window holds fewer than 2 reversals."""
    ev = peak_events(x, rate_hz)
    return None if ev is None else stats_of_events(ev[1], ev[2])


def stats_of_events(peaks: np.ndarray, decays: np.ndarray) -> np.ndarray | None:
    """log10 of (median peak, 90th-percentile peak, median decay ratio) of impact events; None under two."""
    if len(peaks) < 2:
        return None
    return np.log10(np.maximum([np.median(peaks), np.percentile(peaks, 90), np.median(decays)], 1e-12))


def speed_harmonics(angle: np.ndarray, rate_hz: float, n: int = 4) -> np.ndarray:
    """Amplitudes of the crank-speed harmonics 1..n of the mean crank rate [rad/s] (Hann window)."""
    from twin.signals import hann_spectrum

    speed = np.gradient(np.asarray(angle, dtype=np.float64)) * rate_hz
    f_rot = abs(float(angle[-1] - angle[0])) / (2 * math.pi) / (len(angle) / rate_hz)
    f, a = hann_spectrum(speed, rate_hz, remove_mean=True)
    df = f[1] - f[0]
    out = []
    for k in range(1, n + 1):
        j = int(round(k * f_rot / df))
        out.append(float(np.max(a[max(0, j - 1):j + 2])) if 0 < j < len(a) - 1 else 0.0)
    return np.asarray(out)


def lowpassed_speed(angle: np.ndarray, rate_hz: float, cutoff_hz: float = COMMAND_LOWPASS_HZ) -> np.ndarray:
    """Crank speed [rad/s] from a crank angle [rad] sampled at ``rate_hz``: central differences, then a
    zero-phase 2nd-order Butterworth low-pass at ``cutoff_hz`` (none when it is at or above Nyquist),
    without its first and last 1/``cutoff_hz`` seconds (the filter's edge transients: on a
    count-quantized encoder angle they reach 15 rad/s and would dominate the term)."""
    from scipy.signal import butter, sosfiltfilt

    w = np.gradient(np.asarray(angle, dtype=np.float64)) * rate_hz
    nyq = rate_hz / 2
    if cutoff_hz >= nyq or len(w) < 16:
        return w
    w = sosfiltfilt(butter(2, cutoff_hz / nyq, output="sos"), w)
    edge = int(round(rate_hz / cutoff_hz))
    return w[edge:len(w) - edge] if len(w) > 4 * edge else w


def command_term(sim_speed: np.ndarray, rec_speed: np.ndarray) -> float:
    """RMS difference [rad/s] of two low-passed crank-speed histories (the ``command`` term)."""
    n = min(len(sim_speed), len(rec_speed))
    d = np.asarray(sim_speed[:n], dtype=np.float64) - np.asarray(rec_speed[:n], dtype=np.float64)
    return float(np.sqrt(np.mean(d * d))) if n else 0.0
