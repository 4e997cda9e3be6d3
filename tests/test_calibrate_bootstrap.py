"""The block bootstrap's interval machinery against independent references: a linear model with
known noise covariance (the interval covers the truth at its nominal rate), the Welch average it
resamples (scipy's own), and the roughness verdict on a smooth and on a jumping objective."""

from __future__ import annotations

import numpy as np
import pytest


def test_surrogate_bootstrap_interval_covers_at_the_nominal_rate():
    """Blocks j = 1..n observe y_j = G θ + e_j (recording) and G u + e'_j (simulation), e, e' Gaussian with
    a known covariance; the statistic is the block mean. θ̂ minimizes ‖mean(sim(u)) − mean(rec)‖². Paired
    block bootstrap of the differences, re-minimized on the surrogate: the 90 % interval holds θ in
    90 % ± 3 % of 600 cases (binomial sd 1.2 %) with 12 blocks, as few as a short window holds."""
    from twin.calibration.bootstrap import surrogate_intervals

    rng = np.random.default_rng(11)
    m, d, n, B = 12, 2, 12, 300
    G = rng.normal(size=(m, d))
    L = np.tril(rng.normal(size=(m, m))) * 0.3 + np.eye(m)  # correlated noise
    theta = np.array([0.3, 0.6])
    hits = np.zeros(d)
    cases = 600
    for _ in range(cases):
        e_rec = rng.normal(size=(n, m)) @ L.T
        e_sim = rng.normal(size=(n, m)) @ L.T
        # the fitted point: exact least squares of the means
        diff_blocks = e_sim - e_rec  # simulated − recorded at u = θ, block by block
        th_hat = theta - np.linalg.lstsq(G, diff_blocks.mean(axis=0), rcond=None)[0]
        r0 = G @ (th_hat - theta) + diff_blocks.mean(axis=0)  # residual at the fitted point
        idx = rng.integers(0, n, (B, n))
        deltas = diff_blocks[idx].mean(axis=1) - diff_blocks.mean(axis=0)
        s = surrogate_intervals(r0, G, deltas, alpha=0.10, n_blocks=n)
        lo, hi = th_hat + s["lo"], th_hat + s["hi"]
        hits += (lo <= theta) & (theta <= hi)
    cover = hits / cases
    assert np.all((cover >= 0.87) & (cover <= 0.93)), cover


def test_segments_average_to_scipys_welch():
    """The bootstrap resamples Welch's segments: their mean periodogram is scipy.signal.welch's PSD."""
    from scipy.signal import welch

    from twin.calibration.bootstrap import band_levels_from_psd, segment_psd
    from twin.calibration.objective import band_levels_db

    rng = np.random.default_rng(3)
    rate = 100_000.0
    x = rng.normal(size=23_000) + np.sin(2 * np.pi * 1500 * np.arange(23_000) / rate)
    f, s, _c = segment_psd(x, rate)
    fw, pw = welch(x - x.mean(), fs=rate, window="hann", nperseg=2048, noverlap=1024)
    np.testing.assert_allclose(f, fw)
    np.testing.assert_allclose(s.mean(axis=0), pw, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(band_levels_from_psd(f, s.mean(axis=0), rate), band_levels_db(x, rate), atol=1e-9)


def test_roughness_flags_jumps_not_a_smooth_parabola():
    from twin.calibration.bootstrap import roughness

    du = np.array([-0.25, -0.1, -0.03, -0.01, 0.0, 0.01, 0.03, 0.1, 0.25])
    smooth = 400 * du ** 2
    r = roughness(0.5, du, smooth, 1.0)
    assert not r.rough and r.max_drop == 0.0
    # the ΔJ interval of 400 du² is ±0.05; linear interpolation between the evaluated points 0.03 and 0.1
    # (the chord lies above the convex curve) gives ±0.0423
    assert abs(r.lo_u - (0.5 - 0.03 - 0.07 * 0.64 / 3.64)) < 1e-12 and abs(r.hi_u - (0.5 + 0.03 + 0.07 * 0.64 / 3.64)) < 1e-12
    jumps = smooth + np.array([0, 3, 0, 6, 0, 5, 2, 0, 0])  # deterministic jumps of up to 6 ΔJ near the centre
    r = roughness(0.5, du, jumps, 1.0)
    assert r.rough and abs(r.max_drop - (6.04 - 0.36)) < 1e-9 and r.hi_u - r.lo_u > 0.15
    # a far second basin thousands of ΔJ up is no jump near the minimum
    far = np.concatenate([[-0.45, -0.4, -0.35], du])
    r = roughness(0.5, far, np.concatenate([[4000.0, 6000.0, 2000.0], smooth]), 1.0)
    assert not r.rough and r.max_drop == 0.0
    # a peak far above the level between the minimum and a point within it splits the low set: a jump
    # (the third validation set's mu_c: J 3.1e4 at the minimum, 4.9e5 next, 6.6e4 after it, ΔJ 5.2e3)
    split = smooth.copy()
    split[6] = 500.0  # du = +0.03 raised far above the 10 ΔJ level
    r = roughness(0.5, du, split, 1.0)
    assert r.rough and abs(r.max_drop - (500.0 - 4.0)) < 1e-9  # falls to du = +0.1 (J = 4, within 10 ΔJ)


def test_residual_block_bootstrap_keeps_blocks_and_scatter():
    """Moving blocks of an AR(1) series: each draw is made of contiguous runs of the series, and the
    draws' mean has the series' long-run variance (closed form for AR(1): σ²/(1−φ)² / n), within 25 %."""
    from twin.calibration.bootstrap import residual_block_bootstrap

    rng = np.random.default_rng(5)
    n, phi = 2000, 0.5
    e = rng.normal(size=n)
    r = np.zeros(n)
    for i in range(1, n):
        r[i] = phi * r[i - 1] + e[i]
    d = residual_block_bootstrap(r, 50, 2000, 1) + r[None, :]
    # contiguity inside the first block of a draw
    k = int(np.argmin(np.abs(r - d[0, 0])))
    np.testing.assert_allclose(d[0, :50], r[k:k + 50], atol=1e-12)
    var_mean = np.var(d.mean(axis=1))
    expected = 1.0 / (1 - phi) ** 2 / n
    assert 0.75 < var_mean / expected < 1.25


@pytest.mark.parametrize("kw", [{"interval": "widest"}, {"boot_replicates": -1}, {"boot_replicates": 1.5}])
def test_bad_bootstrap_options_name_the_field(kw):
    from twin.calibration import CalibrationOptions
    from twin.errors import ConfigError

    with pytest.raises(ConfigError, match=next(iter(kw))):
        CalibrationOptions(**kw)
