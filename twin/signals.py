"""Signal analysis shared by the project: the bench paper's normalized DTW distance, Hann FFT,
spectral band energy.

Normalized DTW (S003 §5)
------------------------
The paper compares runs "using the Dynamic Time Warping (DTW) distance, normalized using the
difference between the maximum and minimum acceleration of the first maneuver", and reports
"the averaged time shift required to obtain this distance". It does not say how the raw DTW
distance is scaled with the length of the signals, so this module fixes one definition and
documents it exactly:

* The warping path P = [(i_k, j_k)], k = 1..L, is the optimal DTW path between ``a`` and ``b``
  with the squared-difference local cost (dtaidistance's C implementation, default
  ``inner_dist="squared euclidean"``), restricted to a Sakoe–Chiba band ``|i − j| ≤ w``
  (``w = round(window_s · rate_hz)`` samples).
* ``dtw_distance = sqrt( Σ_k (a[i_k] − b[j_k])² )`` (dtaidistance's DTW distance).
* ``distance_pct = 100 · sqrt( Σ_k (a[i_k] − b[j_k])² / L ) / (max(a) − min(a))``: the RMS
  difference along the warping path, divided by the range of the first signal, in percent.
  Dividing by L makes the number independent of the window length (the raw DTW distance grows
  with √n), so 0.3 % means "after the best time warping, the signals differ by 0.3 % of the
  acceleration range, RMS".
* ``mean_shift_s = Σ_k |j_k − i_k| / (L · rate_hz)``: the mean absolute time shift along the
  path [s]. (``signed_shift_s``, the mean of ``j − i``, tells which signal lags: positive when
  ``b`` is late.)

With the band, cost and memory are O(n·w) instead of O(n²). The C routine keeps the band of
the cumulative-cost matrix in memory (8 bytes per cell); above ``DTW_MEMORY_BYTES`` the
low-memory Hirschberg variant is used (same path cost, about 2–3× slower).

Spectra
-------
:func:`hann_spectrum` is a single-sided amplitude spectrum with a Hann window, scaled so that a
sinusoid of amplitude A reads A at its bin (coherent gain corrected). :func:`band_energy_db` is
the mean-square content of a band from the Hann-windowed power spectral density (scaled by the
window's energy, so broadband noise and tones both integrate to their true mean square), in dB
re 1 unit² (for accelerations in m/s²: dB re 1 (m/s²)²).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from twin.errors import TwinError

#: Default Sakoe–Chiba half-width of :func:`normalized_dtw` [s]. Larger than the mean shifts the
#: paper reports between repeated runs (0.0139 s and 0.0167 s, S003 §5).
DEFAULT_DTW_WINDOW_S = 0.05
#: Above this size of the banded cost matrix the low-memory DTW variant is used [bytes].
DTW_MEMORY_BYTES = 512 * 2**20


class SignalError(TwinError, ValueError):
    """Bad input to a signal-analysis function (empty, non-finite, wrong shape, bad band)."""


def _as_signal(x: np.ndarray, name: str) -> np.ndarray:
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim != 1 or arr.size < 2:
        raise SignalError(f"{name}: must be a 1-D signal of at least 2 samples, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise SignalError(f"{name}: holds NaN or infinite samples")
    return arr


def _check_rate(rate_hz: float) -> float:
    if not (isinstance(rate_hz, (int, float, np.floating)) and math.isfinite(rate_hz) and rate_hz > 0):
        raise SignalError(f"rate_hz: must be a finite number > 0 [Hz], got {rate_hz!r}")
    return float(rate_hz)


# ----------------------------------------------------------------------------- DTW
@dataclass(frozen=True)
class DtwResult:
    """Result of :func:`dtw_compare` (definitions in the module docstring).

    Attributes:
        distance_pct: RMS difference along the warping path / (max − min) of ``a`` [%].
        mean_shift_s: mean |j − i| along the path [s].
        signed_shift_s: mean (j − i) along the path [s]; > 0 when ``b`` lags ``a``.
        dtw_distance: sqrt of the summed squared differences along the path [signal unit].
        path_length: number of path points L.
        window_samples: Sakoe–Chiba half-width w used [samples].
        norm_range: the normalizer (max − min of ``a``, or the one given) [signal unit].
    """

    distance_pct: float
    mean_shift_s: float
    signed_shift_s: float
    dtw_distance: float
    path_length: int
    window_samples: int
    norm_range: float


def dtw_compare(a: np.ndarray, b: np.ndarray, rate_hz: float, window_s: float | None = None,
                norm_range: float | None = None) -> DtwResult:
    """Normalized DTW comparison of two uniformly sampled signals (see the module docstring).

    Args:
        a, b: signals at the same rate (lengths may differ).
        rate_hz: sample rate [Hz].
        window_s: Sakoe–Chiba half-width [s]; None = :data:`DEFAULT_DTW_WINDOW_S`, clipped to
            the signal length; 0 = no band (full O(n·m) DTW, only for short signals).
        norm_range: normalizer instead of max(a) − min(a) (e.g. the first run of a set).
    """
    from dtaidistance import dtw

    a = _as_signal(a, "a")
    b = _as_signal(b, "b")
    rate = _check_rate(rate_hz)
    if window_s is None:
        window_s = DEFAULT_DTW_WINDOW_S
    if not (math.isfinite(window_s) and window_s >= 0):
        raise SignalError(f"window_s: must be >= 0 [s] (0 = no band), got {window_s!r}")
    rng = float(np.max(a) - np.min(a)) if norm_range is None else float(norm_range)
    if not (math.isfinite(rng) and rng > 0):
        raise SignalError("normalizer: the first signal is constant (max − min = 0); "
                          "DTW distance cannot be normalized")
    n, m = a.size, b.size
    w = int(round(window_s * rate))
    if w <= 0 or w >= max(n, m):
        w = 0  # no band
    # dtaidistance: |i - j| < window + |n - m|; our half-width w means window = w + 1
    kwargs = {"window": w + 1} if w else {}
    band = (2 * w + 1 + abs(n - m)) if w else m
    cells = (n + 1) * (band + 1)
    if cells * 8 > DTW_MEMORY_BYTES:
        path = dtw.warping_path_fast(a, b, use_lowmem=True, **kwargs)
    else:
        path = dtw.warping_path_fast(a, b, **kwargs)
    p = np.asarray(path, dtype=np.int64)
    if p.ndim != 2 or p.shape[0] == 0:
        raise SignalError("DTW found no warping path (signals too different in length for the window)")
    i, j = p[:, 0], p[:, 1]
    sq = float(np.sum((a[i] - b[j]) ** 2))
    L = int(p.shape[0])
    return DtwResult(
        distance_pct=100.0 * math.sqrt(sq / L) / rng,
        mean_shift_s=float(np.mean(np.abs(j - i))) / rate,
        signed_shift_s=float(np.mean(j - i)) / rate,
        dtw_distance=math.sqrt(sq),
        path_length=L,
        window_samples=w,
        norm_range=rng,
    )


def normalized_dtw(a: np.ndarray, b: np.ndarray, rate_hz: float,
                   window_s: float | None = None) -> tuple[float, float]:
    """The paper's normalized DTW distance [%] and mean time shift [s] between ``a`` and ``b``.

    ``distance_pct = 100 · RMS(a[i] − b[j] along the optimal warping path) / (max(a) − min(a))``,
    ``mean_shift_s = mean |j − i| / rate_hz``; Sakoe–Chiba band of ``window_s`` (None: 0.05 s).
    See the module docstring and :func:`dtw_compare` for the full result.
    """
    r = dtw_compare(a, b, rate_hz, window_s)
    return r.distance_pct, r.mean_shift_s


# ------------------------------------------------------------------------- spectra
def hann_spectrum(x: np.ndarray, rate_hz: float, remove_mean: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Single-sided amplitude spectrum of ``x`` with a Hann window (S003 §5, Fig. 14–15).

    Returns ``(freq_hz, amplitude)`` for f = 0 .. rate/2 (rfft bins, spacing rate/n). The window
    is the periodic Hann window; amplitudes are ``2 |X_k| / Σ w`` (``|X_0| / Σ w`` at DC and at
    Nyquist), so a sinusoid of amplitude A centred on a bin reads A, in the unit of ``x``.
    ``remove_mean`` subtracts the mean first (keeps the DC leakage out of the lowest bins).
    """
    x = _as_signal(x, "x")
    rate = _check_rate(rate_hz)
    if remove_mean:
        x = x - x.mean()
    n = x.size
    w = np.hanning(n + 1)[:-1]  # periodic Hann
    X = np.fft.rfft(x * w)
    amp = np.abs(X) * (2.0 / w.sum())
    amp[0] *= 0.5
    if n % 2 == 0:
        amp[-1] *= 0.5
    return np.fft.rfftfreq(n, 1.0 / rate), amp


def hann_psd(x: np.ndarray, rate_hz: float, remove_mean: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """One-sided power spectral density with a Hann window (single segment) [unit²/Hz].

    ``P_k = 2 |X_k|² / (rate · Σ w²)`` (not doubled at DC/Nyquist); Σ_k P_k · Δf equals the mean
    square of the windowed-energy-corrected signal. Used by :func:`band_energy_db`.
    """
    x = _as_signal(x, "x")
    rate = _check_rate(rate_hz)
    if remove_mean:
        x = x - x.mean()
    n = x.size
    w = np.hanning(n + 1)[:-1]
    X = np.fft.rfft(x * w)
    p = (np.abs(X) ** 2) * (2.0 / (rate * np.sum(w**2)))
    p[0] *= 0.5
    if n % 2 == 0:
        p[-1] *= 0.5
    return np.fft.rfftfreq(n, 1.0 / rate), p


def band_energy_db(x: np.ndarray, rate_hz: float, f_lo: float, f_hi: float) -> float:
    """Mean-square content of ``x`` in the band f_lo ≤ f < f_hi [Hz], in dB re 1 unit².

    Integrates the Hann-windowed PSD (:func:`hann_psd`, mean removed) over the band:
    ``10 log10( Σ_{f_lo ≤ f_k < f_hi} P_k Δf )``. A sinusoid of amplitude A well inside the
    band gives about 10 log10(A²/2); white noise of density D [unit/√Hz] gives
    10 log10(D² (f_hi − f_lo)). An empty band (no bins) is an error; zero content gives −inf.
    """
    rate = _check_rate(rate_hz)
    if not (math.isfinite(f_lo) and math.isfinite(f_hi) and 0 <= f_lo < f_hi <= rate / 2):
        raise SignalError(f"band: need 0 <= f_lo < f_hi <= rate/2 = {rate / 2:g} Hz, got [{f_lo!r}, {f_hi!r}]")
    f, p = hann_psd(x, rate)
    sel = (f >= f_lo) & (f < f_hi)
    if not np.any(sel):
        raise SignalError(f"band [{f_lo:g}, {f_hi:g}) Hz holds no frequency bin "
                          f"(resolution {f[1]:g} Hz for {len(x)} samples)")
    e = float(np.sum(p[sel]) * (f[1] - f[0]))
    return 10.0 * math.log10(e) if e > 0 else -math.inf


def crank_harmonics(crank_rate_hz: float, count: int = 6) -> np.ndarray:
    """The crank rotation frequency and its harmonics 1..count [Hz] (Fig. 14a marks six)."""
    return float(crank_rate_hz) * np.arange(1, count + 1)
