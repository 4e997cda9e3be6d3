"""The calibration's honest parts without simulations: the noise share of an interval on smooth
objectives whose minimizers are known in closed form, its coverage under the Gaussian model it
assumes, the command term's crank speed against the analytic derivative, the structure fields in the
registry, and the persistent worker pool."""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.errors import ConfigError


def _grid(centre: float) -> np.ndarray:
    return np.array([[centre + d] for d in (-0.25, -0.1, -0.03, -0.01, 0.0, 0.01, 0.03, 0.1, 0.25)])


def test_noise_interval_of_exact_parabolas_is_the_closed_form():
    """J_k(u) = ((u - m_k)/s)²: each objective's minimizer is m_k exactly, the interval is
    mean(m) ± t_{K,0.95} · std(m) · sqrt(1 + 1/(K+1))."""
    from scipy.stats import t as student_t

    from twin.calibration.uncertainty import replicate_spread

    m = np.array([0.41, 0.395, 0.402, 0.388, 0.407])
    U = _grid(0.4)
    Js = np.array([((U[:, 0] - mk) / 0.05) ** 2 for mk in m])
    r = replicate_spread(U, Js, np.array([0.4]))
    np.testing.assert_allclose(r["minimizers"][:, 0], m, atol=1e-12)
    K = len(m) - 1
    half = student_t.ppf(0.95, K) * np.std(m, ddof=1) * math.sqrt(1 + 1 / (K + 1))
    assert r["mean"][0] == pytest.approx(m.mean(), abs=1e-12)
    assert r["half"][0] == pytest.approx(half, rel=1e-12)


def test_noise_interval_covers_the_truth_at_its_level_on_a_smooth_objective():
    """Known truth θ = 0.4; the recording carries noise e_r, each simulated realization e_k (σ = 0.01):
    objective k is ((u - θ - e_r + e_k)/s)² plus a smooth non-quadratic part. Over 2000 cases the
    90 % interval holds the truth in 90 % ± 3 % (binomial sd 0.7 %)."""
    from twin.calibration.uncertainty import replicate_spread

    rng = np.random.default_rng(7)
    theta, sigma, K = 0.4, 0.01, 4
    U = _grid(theta)
    hits = 0
    n = 2000
    for _ in range(n):
        e_r = rng.normal(0, sigma)
        ms = theta + e_r - rng.normal(0, sigma, K + 1)
        Js = np.array([((U[:, 0] - mk) / 0.05) ** 2 for mk in ms])
        r = replicate_spread(U, Js, np.array([theta]))
        hits += abs(r["mean"][0] - theta) <= r["half"][0]
    assert 0.87 <= hits / n <= 0.93


def test_analyse_interval_holds_the_noise_interval_and_the_fitted_value():
    from twin.calibration.params import Parameter
    from twin.calibration.uncertainty import analyse

    p = (Parameter("contact.mu0", 0.0, 1.0),)
    U = _grid(0.5)
    m = [0.52, 0.53, 0.51, 0.535, 0.525]  # every replicate's minimum right of the fitted point
    J0 = ((U[:, 0] - m[0]) / 0.2) ** 2
    R = np.array([((U[:, 0] - mk) / 0.2) ** 2 for mk in m[1:]])
    iv = analyse(p, np.array([0.5]), [(u, j) for u, j in zip(U, J0)], delta_j=1e-4, replicates=R)["intervals"][0]
    assert iv.method == "slice+noise"
    assert iv.lo <= 0.5 <= iv.hi and iv.lo <= iv.noise_lo < iv.noise_hi <= iv.hi
    assert iv.noise_lo < np.mean(m) < iv.noise_hi


def test_command_term_speed_is_the_derivative_of_the_angle():
    """Closed form: φ(t) = ω t + a sin(2π f t) has speed ω + 2π f a cos(2π f t); the low-passed
    central difference (f well below the 50 Hz cut-off) matches it away from the ends, and the term
    of a speed offset δ is |δ|. The filter's edge transients (1/cut-off at each end) are cut off."""
    from twin.calibration.objective import command_term, lowpassed_speed

    rate = 10_000.0
    t = np.arange(int(0.5 * rate)) / rate
    w, a, f = 60.0, 0.05, 5.0
    phi = w * t + a * np.sin(2 * np.pi * f * t)
    v = lowpassed_speed(phi, rate)
    edge = int(rate / 50.0)
    assert len(v) == len(t) - 2 * edge
    exact = (w + 2 * np.pi * f * a * np.cos(2 * np.pi * f * t))[edge:-edge]
    mid = slice(300, -300)
    assert np.max(np.abs(v[mid] - exact[mid])) < 0.01 * 2 * np.pi * f * a  # filter gain at 5/50 Hz: 1e-4
    assert command_term(v + 0.3, v) == pytest.approx(0.3, rel=1e-12)


def test_structure_fields_have_their_documented_ranges_and_need_the_flexible_structure():
    from twin.calibration.params import make_parameters
    from twin.config import BenchConfig
    from twin.config.structure import EXPLORE_RANGES

    flex = BenchConfig().replace(**{"structure.mode": "flexible"})
    fields = [f"structure.{f}" for _n, f, _d, _b in EXPLORE_RANGES]
    ps = make_parameters(fields, flex)
    for p, (_n, _f, _d, b) in zip(ps, EXPLORE_RANGES):
        assert (p.lo, p.hi) == b
    assert {p.field for p in ps if p.log} >= {"structure.frame_frequency_hz", "structure.bending_damping_ratio"}
    with pytest.raises(ConfigError) as err:
        make_parameters(["structure.frame_frequency_hz"], BenchConfig())
    assert err.value.field == "params" and "flexible" in str(err.value)


def test_persistent_pool_keeps_its_workers_across_calls():
    from twin.calibration.objective import evaluate_task
    from twin.calibration.search import PersistentPool

    task = dict(recordings=["/nonexistent.mcap"], base_toml=None, fraction=1.0, dtw_max_s=0.05, dtw_window_s=0.002,
                motor=False, ripple=False, drive="program", fields=[], values=[])
    with PersistentPool(2, evaluate_task) as pool:
        first = list(pool([dict(task, id=i) for i in range(3)]))
        ex = pool.ex
        second = list(pool([dict(task, id=i) for i in range(2)]))
        assert pool.ex is ex  # the same processes served both calls
    assert pool.ex is None
    assert sorted(r["id"] for r in first) == [0, 1, 2] and sorted(r["id"] for r in second) == [0, 1]
    assert all(r["status"] == "failed" and "nonexistent" in r["error"] for r in first + second)
