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

Time lag
--------
:func:`estimate_lag` finds the lag between recorded and simulated signals of several sensors
by maximum likelihood, with a confidence interval, and keeps no shift unless the data reject
it (method in its docstring).
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


# ------------------------------------------------------------------------ time lag
#: Confidence level of :func:`estimate_lag` (its lag interval and its test for any correlation).
LAG_CONFIDENCE = 0.95
#: Floor of the unexplained variance fraction 1 − r² in :func:`estimate_lag` (float64 resolution
#: of r near 1 for sums over ~10⁵ samples).
_MIN_UNEXPLAINED = 1e-12


@dataclass(frozen=True)
class LagEstimate:
    """Result of :func:`estimate_lag`. Lags in samples; k > 0: the recorded signals are late
    (``rec[i + k]`` pairs with ``sim[i]``).

    Attributes:
        lag: the lag to apply: the maximum-likelihood lag where the data reject "no shift",
            else 0 (rules in :func:`estimate_lag`).
        best_lag: maximum-likelihood lag (argmax of ``score``) within ±``max_lag``.
        ci: (lowest, highest) lag of the confidence set (lags whose score is within
            ``ci_threshold`` of the best).
        ci_contiguous: the confidence set is one run of lags (False: separate peaks fit as well).
        max_lag: half-width of the search [samples].
        score_best, score_at_lag, score_at_zero: combined score Σ_s N_eff,s · (−ln(1 − r_s²))
            at the best lag, the chosen lag and lag 0 (twice the log-likelihood gained over
            "no correlation"; χ² units).
        ci_threshold: χ²₁ quantile of the confidence level: a lag k is in the confidence set
            when score_best − score(k) ≤ ci_threshold.
        correlated: score_best exceeds ``null_threshold``: the signals are correlated at some lag.
        null_threshold: χ² quantile (one degree of freedom per sensor) at 1 − α/(2·max_lag + 1)
            (Bonferroni over the searched lags).
        well_defined: correlated, and the confidence set is one run of lags strictly inside
            ±``max_lag``.
        note: one line on the outcome ("peak well defined", or why 0 was kept).
        n_eff: per sensor, the effective number of independent samples of the residual (NaN:
            sensor skipped, constant signal).
        r_at_lag, r_at_zero: per-sensor correlation coefficients at ``lag`` and at 0.
        rate_hz: sample rate, when given.
        confidence: confidence level of ``ci`` and of the correlation test.
    """

    lag: int
    best_lag: int
    ci: tuple[int, int]
    ci_contiguous: bool
    max_lag: int
    score_best: float
    score_at_lag: float
    score_at_zero: float
    ci_threshold: float
    correlated: bool
    null_threshold: float
    well_defined: bool
    note: str
    n_eff: tuple[float, ...]
    r_at_lag: tuple[float, ...]
    r_at_zero: tuple[float, ...]
    rate_hz: float | None = None
    confidence: float = LAG_CONFIDENCE

    def _s(self, k: float) -> float:
        return k / self.rate_hz if self.rate_hz else float("nan")

    @property
    def lag_s(self) -> float:
        """``lag`` in seconds (NaN without ``rate_hz``)."""
        return self._s(self.lag)

    @property
    def ci_s(self) -> tuple[float, float]:
        """``ci`` in seconds (NaN without ``rate_hz``)."""
        return self._s(self.ci[0]), self._s(self.ci[1])

    def to_dict(self) -> dict:
        """JSON-ready summary (lags in samples and, with ``rate_hz``, in seconds)."""
        d = {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()}
        if self.rate_hz:
            d.update(lag_s=self.lag_s, best_lag_s=self._s(self.best_lag), ci_s=list(self.ci_s))
        return d


def effective_samples(e: np.ndarray) -> float:
    """Effective number of independent samples of a stationary signal for its variance:
    ``N / Σ_j ρ(j)²`` (ρ: autocorrelation; N for white noise, about 2·B·T for noise of
    bandwidth B over T seconds, about 2 for a sinusoid).

    Σ_j ρ(j)² is summed over |j| ≤ N/4 from the sample autocorrelation (biased estimator) and
    divided by its expected inflation ``1 + Σ_{|j|≤J} (N − |j|)/N²`` (Bartlett: far from the
    correlation length, E[ρ̂(j)²] ≈ (N − j)/N² · Σ ρ²); a correlation length beyond N/4 reads
    as N/4 (N_eff ≈ 6 to 8, where the true value may be 2 to 4).
    """
    e = np.asarray(e, dtype=np.float64)
    n = e.size
    e = e - e.mean()
    c0 = float(np.dot(e, e))
    if n < 4 or c0 <= 0:
        return float(max(n, 1))
    nfft = 1 << int(math.ceil(math.log2(2 * n)))
    f = np.fft.rfft(e, nfft)
    J = n // 4
    rho = np.fft.irfft(f.real**2 + f.imag**2, nfft)[:J + 1] / c0
    s = 1.0 + 2.0 * float(np.sum(rho[1:] ** 2))
    inflation = 1.0 + ((2 * J + 1) * n - J * (J + 1)) / n**2
    return float(min(n, max(1.0, n * inflation / s)))


def _lag_correlation(x: np.ndarray, y: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Pearson correlation r(k) of x[j] with y[j − k] for j in the fixed window [m, N − m), and
    the unexplained variance fraction 1 − max(r, 0)², for k = −m..m."""
    n = x.size
    xw = np.zeros(n)
    xw[m:n - m] = x[m:n - m] - x[m:n - m].mean()  # the same data (rec) at every lag
    nfft = 1 << int(math.ceil(math.log2(n + m + 1)))
    c = np.fft.irfft(np.fft.rfft(xw, nfft) * np.conj(np.fft.rfft(y, nfft)), nfft)
    k = np.arange(-m, m + 1)
    cov = c[k % nfft]  # Σ_j xw[j] y[j − k]; xw has zero mean, so no mean of y is needed
    cy, cyy = np.r_[0.0, np.cumsum(y)], np.r_[0.0, np.cumsum(y * y)]
    y0, y1 = m - k, n - m - k
    sy = cy[y1] - cy[y0]
    vy = cyy[y1] - cyy[y0] - sy * sy / (n - 2 * m)
    den = float(np.dot(xw, xw)) * vy
    ok = den > 0
    safe = np.where(ok, den, 1.0)
    r = np.where(ok, cov / np.sqrt(safe), 0.0)
    u = np.where(ok & (cov > 0), (safe - cov * cov) / safe, 1.0)
    return np.clip(r, -1.0, 1.0), np.clip(u, _MIN_UNEXPLAINED, 1.0)


def estimate_lag(rec, sim, max_lag: int, rate_hz: float | None = None, lowpass_hz: float = 500.0,
                 confidence: float = LAG_CONFIDENCE) -> LagEstimate:
    """Time lag between recorded and simulated signals of several sensors, with a confidence
    interval; no shift is kept where the data cannot tell.

    ``rec`` and ``sim`` are sequences of 1-D signals, one pair per sensor, all of one length N.
    With ``rate_hz``, both are first low-passed at ``lowpass_hz`` (4th-order Butterworth,
    zero-phase): the alignment follows the mechanism's motion, not impact spikes one model has
    and the other lacks.

    Method (maximum likelihood over the lag k, |k| ≤ ``max_lag``; k > 0: ``rec`` is late):

    1. Model per sensor s: ``rec_s[i + k] = a_s · sim_s[i] + b_s + e_s[i]`` with a_s ≥ 0 and
       Gaussian noise e_s, for the recorded samples i + k in the fixed window
       [max_lag, N − max_lag): every lag explains the same data, so likelihoods compare
       (correlating over the N − |k| overlapping pairs instead biases the lag by several
       standard errors on smooth signals). Maximized over a_s, b_s and the noise variance, the
       log-likelihood is ``ℓ_s(k) = −(N_eff,s / 2) · ln(1 − r_s(k)²)`` (+ const), r_s(k) the
       Pearson correlation over that window (r < 0 counts as 0: a_s ≥ 0).
    2. The noise is not white (low-passed, model error): N_eff,s, the effective number of
       independent samples, is :func:`effective_samples` of the residual e_s at the sensor's own
       best lag (about 2 · bandwidth · duration for a noise-like residual; a few for a slow
       model error, which makes the lag correspondingly uncertain).
    3. Sensors' noises are independent: the combined score is ``score(k) = Σ_s 2 ℓ_s(k)``; the
       maximum-likelihood lag k̂ maximizes it. Each sensor weighs by its evidence: a channel
       without signal (r ≈ 0 at every lag) moves the score by O(1), a well-correlated one by
       N_eff · ln((1 − r(k)²)/(1 − r(k̂)²)), often hundreds.
    4. Confidence set (likelihood ratio, Wilks): the lags with ``score(k̂) − score(k) ≤ χ²₁(c)``
       (3.84 for c = 0.95); ``ci`` is its lowest and highest lag.
    5. Correlation test: with no relation between the signals, score(k) is about χ² with one
       degree of freedom per sensor; the signals are ``correlated`` when score(k̂) exceeds its
       quantile at 1 − (1 − c)/(2·max_lag + 1) (Bonferroni over the searched lags).
    6. Choice: ``lag = k̂`` where the signals are correlated, k̂ is inside the search range and
       lag 0 is outside the confidence set (the data reject "no shift" at level 1 − c);
       otherwise ``lag = 0``. The peak is ``well_defined`` when the signals are correlated and
       the confidence set is one run of lags strictly inside ±max_lag.

    Sensors with a constant signal are skipped. ``max_lag`` ≤ 0 searches nothing (lag 0); it is
    capped at N/4.
    """
    from scipy.stats import chi2

    if not (0.0 < confidence < 1.0):
        raise SignalError(f"confidence: must be in (0, 1), got {confidence!r}")
    if isinstance(rec, np.ndarray) and rec.ndim == 1:
        rec, sim = [rec], [sim]
    rec = [np.asarray(x, dtype=np.float64) for x in rec]
    sim = [np.asarray(y, dtype=np.float64) for y in sim]
    if len(rec) != len(sim) or not rec:
        raise SignalError(f"rec, sim: need the same number (>= 1) of signals, got {len(rec)} and {len(sim)}")
    n = rec[0].size
    for i, (x, y) in enumerate(zip(rec, sim)):
        if x.ndim != 1 or y.ndim != 1 or x.size != n or y.size != n:
            raise SignalError(f"signal {i}: rec and sim must be 1-D of one length ({n}), got {x.shape} and {y.shape}")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise SignalError(f"signal {i}: holds NaN or infinite samples")
    rate = _check_rate(rate_hz) if rate_hz is not None else None
    m = max(0, min(int(max_lag), n // 4))
    ci_thr = float(chi2.ppf(confidence, 1))
    nan = float("nan")
    k = np.arange(-m, m + 1)
    live = [bool(np.ptp(x) > 0 and np.ptp(y) > 0) for x, y in zip(rec, sim)]
    if rate is not None and lowpass_hz < rate / 2 and n > 64:
        from scipy.signal import butter, sosfiltfilt

        sos = butter(4, lowpass_hz, fs=rate, output="sos")
        rec = [sosfiltfilt(sos, x) for x in rec]
        sim = [sosfiltfilt(sos, y) for y in sim]

    score = np.zeros(k.size)
    n_eff, rs = [], []
    for x, y, ok in zip(rec, sim, live):
        xs = x[m:n - m] - x[m:n - m].mean()
        y = y - y.mean()
        if not (ok and np.dot(xs, xs) > 0):
            n_eff.append(nan)
            rs.append(np.full(k.size, nan))
            continue
        r, u = _lag_correlation(x, y, m)
        # residual at the sensor's own best lag -> its effective number of independent samples
        kb = int(k[np.argmin(u)])
        ys = y[m - kb:n - m - kb]
        ys = ys - ys.mean()
        a = max(0.0, float(np.dot(xs, ys)) / float(np.dot(ys, ys))) if np.dot(ys, ys) > 0 else 0.0
        ne = effective_samples(xs - a * ys)
        n_eff.append(ne)
        rs.append(r)
        score += ne * -np.log(u)
    used = sum(1 for v in n_eff if math.isfinite(v))
    null_thr = float(chi2.ppf(1.0 - (1.0 - confidence) / k.size, max(used, 1)))
    i0 = m  # index of lag 0
    ib = int(np.argmax(score))
    kb = int(k[ib])
    inside = np.flatnonzero(score[ib] - score <= ci_thr)
    lo, hi = int(k[inside[0]]), int(k[inside[-1]])
    contiguous = bool(inside.size == inside[-1] - inside[0] + 1)
    correlated = bool(used > 0 and m > 0 and score[ib] > null_thr)
    zero_in = bool(score[ib] - score[i0] <= ci_thr)
    at_edge = m > 0 and abs(kb) == m
    well = bool(correlated and contiguous and lo > -m and hi < m)
    if m == 0:
        lag, note = 0, "no lag searched (max_lag = 0)"
    elif not correlated:
        lag, note = 0, "no clear peak: no significant correlation at any lag; 0 kept"
    elif at_edge:
        lag, note = 0, "no clear peak: best lag at the search limit; 0 kept"
    else:
        lag = 0 if zero_in else kb
        if well:
            note = "peak well defined"
        elif not contiguous:
            note = "no clear peak: separate lags fit as well" + ("; 0 kept" if lag == 0 else "")
        else:
            note = "no clear peak: interval reaches the search limit" + ("; 0 kept" if lag == 0 else "")
    il = lag + m
    return LagEstimate(
        lag=lag, best_lag=kb, ci=(lo, hi), ci_contiguous=contiguous, max_lag=m,
        score_best=float(score[ib]), score_at_lag=float(score[il]), score_at_zero=float(score[i0]),
        ci_threshold=ci_thr, correlated=correlated, null_threshold=null_thr, well_defined=well, note=note,
        n_eff=tuple(float(v) for v in n_eff), r_at_lag=tuple(float(r[il]) for r in rs),
        r_at_zero=tuple(float(r[i0]) for r in rs), rate_hz=rate, confidence=float(confidence))
