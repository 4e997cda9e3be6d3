"""Signal analysis: normalized DTW (S003 §5), Hann spectrum, band energy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.signals import (SignalError, band_energy_db, crank_harmonics, dtw_compare, hann_psd,
                          hann_spectrum, normalized_dtw)

RATE = 100_000.0


def _accel_like(n: int, rate: float = RATE, delay_s: float = 0.0) -> np.ndarray:
    """A crank-periodic acceleration-like signal (3.15 Hz fundamental and harmonics) [m/s^2]."""
    t = np.arange(n) / rate - delay_s
    f = 3.15
    return 20 * np.sin(2 * np.pi * f * t) + 8 * np.sin(2 * np.pi * 2 * f * t + 0.3) + 3 * np.cos(2 * np.pi * 5 * f * t)


def test_dtw_identical_signals_zero():
    a = _accel_like(5000)
    d, s = normalized_dtw(a, a, RATE, window_s=0.005)
    assert d == pytest.approx(0.0, abs=1e-12)
    assert s == pytest.approx(0.0, abs=1e-12)


def test_dtw_recovers_a_known_delay():
    # 0.2 s at 10 kHz, b lags a by 4 ms: the warping path shifts by the delay
    rate = 10_000.0
    n = 2000
    a = _accel_like(n, rate)
    b = _accel_like(n, rate, delay_s=0.004)
    r = dtw_compare(a, b, rate, window_s=0.02)
    # the path needs a ramp-in at the start, so the mean shift is slightly below the delay
    assert 0.0035 <= r.mean_shift_s <= 0.0041
    assert r.signed_shift_s == pytest.approx(r.mean_shift_s, rel=1e-9)  # b is late everywhere
    # after warping, the RMS difference is a small fraction of the range (edge effects only)
    assert r.distance_pct < 2.0
    # without warping (Euclidean) the difference is much larger
    eucl = 100 * np.sqrt(np.mean((a - b) ** 2)) / (a.max() - a.min())
    assert eucl > 3 * r.distance_pct
    # normalization: RMS along the path / range of the first signal
    assert r.norm_range == pytest.approx(a.max() - a.min())
    assert r.distance_pct == pytest.approx(100 * r.dtw_distance / math.sqrt(r.path_length) / r.norm_range)


def test_dtw_normalization_is_scale_invariant_and_uses_first_signal():
    rng = np.random.default_rng(1)
    a = _accel_like(3000)
    b = a + rng.normal(0, 0.2, a.size)
    d1, s1 = normalized_dtw(a, b, RATE, window_s=0.002)
    d2, s2 = normalized_dtw(10 * a, 10 * b, RATE, window_s=0.002)
    assert d2 == pytest.approx(d1, rel=1e-9)
    assert s2 == pytest.approx(s1)
    # the noise is 0.2 RMS on a ~55 m/s^2 range: DTW can only reduce the RMS difference
    direct = 100 * 0.2 / (a.max() - a.min())
    assert 0 < d1 < 1.05 * direct


def test_dtw_window_bounds_the_shift():
    rate = 10_000.0
    a = _accel_like(1500, rate)
    b = _accel_like(1500, rate, delay_s=0.01)
    narrow = dtw_compare(a, b, rate, window_s=0.002)
    wide = dtw_compare(a, b, rate, window_s=0.02)
    assert narrow.window_samples == 20
    assert narrow.mean_shift_s <= 0.002 + 1e-12  # the band limits |i - j|
    assert wide.distance_pct < narrow.distance_pct


def test_dtw_different_lengths_and_errors():
    a = _accel_like(1000)
    d, _ = normalized_dtw(a, a[:900], RATE, window_s=0.001)
    assert np.isfinite(d)
    with pytest.raises(SignalError, match="constant"):
        normalized_dtw(np.ones(100), a[:100], RATE)
    with pytest.raises(SignalError, match="NaN"):
        normalized_dtw(np.r_[a[:10], np.nan], a[:11], RATE)
    with pytest.raises(SignalError, match="rate_hz"):
        normalized_dtw(a, a, 0.0)
    with pytest.raises(SignalError, match="window_s"):
        normalized_dtw(a, a, RATE, window_s=-1.0)


def test_hann_spectrum_amplitude_and_frequency():
    rate, n = 100_000.0, 100_000  # 1 s, 1 Hz bins
    t = np.arange(n) / rate
    x = 0.5 + 3.0 * np.sin(2 * np.pi * 1000 * t) + 0.2 * np.sin(2 * np.pi * 3000 * t)
    f, amp = hann_spectrum(x, rate)
    assert f[1] == pytest.approx(1.0)
    assert f[-1] == pytest.approx(50_000.0)
    assert amp[np.argmin(abs(f - 1000))] == pytest.approx(3.0, rel=1e-6)
    assert amp[np.argmin(abs(f - 3000))] == pytest.approx(0.2, rel=1e-6)
    assert amp[0] == pytest.approx(0.5, rel=1e-6)
    _, amp0 = hann_spectrum(x, rate, remove_mean=True)
    assert amp0[0] < 1e-9


def test_band_energy_of_tone_and_noise():
    rate, n = 100_000.0, 200_000
    t = np.arange(n) / rate
    tone = 2.0 * np.sin(2 * np.pi * 1000 * t)
    assert band_energy_db(tone, rate, 800, 1200) == pytest.approx(10 * np.log10(2.0**2 / 2), abs=0.05)
    assert band_energy_db(tone, rate, 2800, 3200) < -100  # nothing there
    rng = np.random.default_rng(3)
    density = 0.01  # unit/sqrt(Hz), one-sided
    noise = rng.normal(0, density * np.sqrt(rate / 2), n)
    e = band_energy_db(noise, rate, 2000, 6000)
    assert e == pytest.approx(10 * np.log10(density**2 * 4000), abs=0.3)
    f, p = hann_psd(noise, rate)
    assert np.mean(p[(f > 1000) & (f < 40_000)]) == pytest.approx(density**2, rel=0.03)
    with pytest.raises(SignalError, match="band"):
        band_energy_db(noise, rate, 3000, 1000)
    with pytest.raises(SignalError, match="holds no frequency bin"):
        band_energy_db(noise[:100], rate, 1100, 1200)


def test_crank_harmonics():
    assert list(crank_harmonics(3.0, 3)) == [3.0, 6.0, 9.0]
