"""Honest answers: what a recording shows by itself (crank rate, within-turn speed ripple, noise level,
orientation, distance in feature space) measured against the model's training ranges, the warnings and the
widened interval outside them, the imposed ripple of the drive program, the ranges in the model file.

Independent bases: encoder traces and noise of known closed form (a 2 % first harmonic must read 2 %, white
noise of a known density must read that density); the drive's rippled reference against finite differences
of itself and against its defining speed law; short simulations through the sensor chain on either side of a
small model's training ranges (a model trained at 500-600 motor rpm with y vertical, without ripple, with
the datasheet's noise).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.identification import ranges as id_ranges

RATE = 100_000.0
CPR = 32768.0


# ------------------------------------------------------------------ measures, closed form
@pytest.mark.parametrize("k, pct, phase", [(1, 2.0, 0.7), (2, 2.0, 2.1), (3, 1.0, -1.0)])
def test_a_known_ripple_reads_back_from_quantized_encoder_counts(k, pct, phase):
    """ω = Ω (1 + a sin(kΩt + p)) gives φ = Ωt − (a/k) cos(kΩt + p): counts of a 32768-count encoder over two
    turns at 3 Hz must read a to within 0.05 percentage points, the other harmonics below 0.05 points."""
    W = 2 * math.pi * 3.0
    n = int(round(2 / 3.0 * RATE))
    t = np.arange(n + 1) / RATE
    phi = W * t - (pct / 100.0 / k) * np.cos(k * W * t + phase) + 0.3
    counts = np.floor(phi / (2 * math.pi) * CPR)
    got = id_ranges.measure_ripple(counts, RATE, CPR, 0, n)
    assert got[k - 1] == pytest.approx(pct, abs=0.05)
    assert all(v < 0.05 for i, v in enumerate(got) if i != k - 1)


def test_a_ripple_tied_to_the_crank_angle_reads_its_amplitudes_after_a_spin_up():
    """The sample recordings' motion (``crank_trace``: 1.5 % at 1x, 2.5 % at 2x, tied to the crank angle,
    after a spin-up): the windows left of the spin-up's tail read both amplitudes to first order (within 0.05
    points; the second-order terms of 1.5 % x 2.5 % are below that)."""
    from twin.identification.features import steady_windows
    from twin.recording import crank_trace

    t, phi = crank_trace(750, 3.97, 1.5, RATE, ramp_s=0.3, rest_s=0.0, ripple=(0.015, 0.025), ripple_phase=(0.4, 1.3))
    counts = np.floor(phi / (2 * math.pi) * CPR)
    w = steady_windows(counts, RATE, CPR)
    got = id_ranges.measure_ripple(counts, RATE, CPR, *id_ranges.ripple_span(counts, w))
    assert got[0] == pytest.approx(1.5, abs=0.05) and got[1] == pytest.approx(2.5, abs=0.05)
    assert got[2] < 0.1 and got[3] < 0.1


def test_white_noise_of_a_known_density_reads_that_density():
    """One-sided density D [g/√Hz] of white noise sampled at fs has variance D² fs/2: 30 µg/√Hz must read
    30 µg/√Hz within 5 % (median of 1024-sample periodograms: its bias for the mean of ~190 χ² bins is
    under 1 %)."""
    rng = np.random.default_rng(3)
    D = 30e-6
    sigma = D * math.sqrt(RATE / 2) * id_ranges.STANDARD_G
    acc = {f"AC{i}": sigma * rng.standard_normal(100_000) for i in range(1, 7)}
    assert id_ranges.measure_noise(acc, RATE, 0, 100_000) == pytest.approx(30.0, rel=0.05)


# ------------------------------------------------------------------ rules
RANGES = {"source": "test", "runs": 3, "crank_hz": [2.0, 2.5], "ripple_pct": [[0.0, 0.01]] * 4,
          "noise_ug_rthz": [29.0, 31.0], "orientations": ["y"]}


@pytest.mark.parametrize("change, reason", [
    ({}, None),
    ({"crank_hz": 2.57}, None),  # within the 3 % allowance
    ({"crank_hz": 2.7}, "crank rate"), ({"crank_hz": 1.9}, "crank rate"),
    ({"ripple_pct": [0.2, 0.0, 0.0, 0.0]}, None),  # within the 0.25-point allowance
    ({"ripple_pct": [0.0, 0.3, 0.0, 0.0]}, "ripple 0.30 % at 2x"),
    # the 1.15 allowance on the 29-31 range: 35.6 and 25.2 inside, 36 and 25 outside
    ({"noise_ug_rthz": 35.6}, None), ({"noise_ug_rthz": 25.3}, None),
    ({"noise_ug_rthz": 36.0}, "noise"), ({"noise_ug_rthz": 25.0}, "noise"),
    ({"orientation": "x"}, "orientation x"),
])
def test_each_rule_warns_outside_its_range_and_not_inside(change, reason):
    m = {"crank_hz": 2.2, "ripple_pct": [0.0, 0.0, 0.0, 0.0], "noise_ug_rthz": 30.0}
    orient = change.pop("orientation", "y") if "orientation" in change else "y"
    m.update(change)
    warnings, ev = id_ranges.out_of_range(m, orient, RANGES)
    if reason is None:
        assert warnings == []
    else:
        assert len(warnings) == 1 and reason in warnings[0] and "extrapolation" in warnings[0]
    assert ev["feature_distance"].startswith("unavailable")


def test_the_feature_distance_counts_features_beyond_the_far_out_fences():
    X = np.random.default_rng(0).normal(size=(400, 40))
    ref = id_ranges.feature_reference(X)
    x = np.median(X[:20], axis=0)
    m = {"crank_hz": 2.2, "ripple_pct": [0.0] * 4, "noise_ug_rthz": 30.0}
    assert id_ranges.out_of_range(m, "y", RANGES, x, ref)[0] == []
    x[:2] += 100.0  # 2 of 40 features far out: 5 %
    w, ev = id_ranges.out_of_range(m, "y", RANGES, x, ref, [f"f{i}" for i in range(40)])
    assert ev["feature_distance"] == {"beyond_far_out_fences": 2, "of": 40, "training_runs_max": None}
    assert len(w) == 1 and "f0, f1" in w[0]


def test_the_feature_distance_limit_is_what_the_training_runs_themselves_reach():
    """With the windows' runs given, the limit is the conformal 99 % rank of the training runs' own counts:
    here 200 runs whose first 5 features sit in one of two far-apart groups (a multimodal training set, as
    orientations make it), so a run has none or 5 far-out features; the limit holds the runs' own worst."""
    rng = np.random.default_rng(1)
    X = rng.normal(size=(800, 40))
    owner = np.repeat(np.arange(200), 4)
    X[owner < 30, :5] += 50.0  # 30 runs of another group
    ref = id_ranges.feature_reference(X, owner)
    own = [id_ranges.feature_outliers(np.median(X[owner == r], axis=0), ref)[0] for r in range(200)]
    assert max(own) == 5 and ref["max_outliers"] == 5
    m = {"crank_hz": 2.2, "ripple_pct": [0.0] * 4, "noise_ug_rthz": 30.0}
    assert id_ranges.out_of_range(m, "y", RANGES, np.median(X[owner == 0], axis=0), ref)[0] == []
    x = np.median(X[owner == 100], axis=0)
    x[5:11] += 100.0  # 6 features far out, more than any training run has
    assert len(id_ranges.out_of_range(m, "y", RANGES, x, ref)[0]) == 1


def test_the_widened_interval_holds_every_clearance_trained_on():
    assert id_ranges.widen([0.3, 0.6], {"min": 0.02, "max": 1.0, "distinct": 500, "ball_bearing": True}) == [0.02, 1.0]
    assert id_ranges.widen([0.3, 0.6], [0.0, 0.1, 0.5]) == [0.1, 0.5]  # the hull, whatever the interval
    assert id_ranges.widen([0.3, 0.6], [0.0]) == [0.3, 0.6]


# ------------------------------------------------------------------ the drive's ripple program
def test_the_rippled_reference_is_its_own_derivative_and_follows_the_speed_law():
    """θ_ref, ω_ref and α_ref of ``drive.ripple_pct`` agree with finite differences of each other, and
    ω_ref = ω_b (1 + Σ a_k sin(k φ_b + p_k)) with φ_b the unrippled program's encoder angle."""
    from twin.config import preset
    from twin.drive import DriveReference

    base = preset(6).replace(**{"drive.ramp_s": 0.3, "drive.initial_encoder_angle_rad": 0.8})
    cfg = base.replace(**{"drive.ripple_pct": (2.0, 1.0, 0.5), "drive.ripple_phase_rad": (0.3, 1.0, -2.0)})
    t = np.linspace(0.0, 1.0, 100_001)
    dt = t[1] - t[0]
    th, w = DriveReference(cfg)(t)
    a = DriveReference(cfg).acceleration(t)
    thb, wb = DriveReference(base)(t)
    assert th[0] == thb[0]
    assert np.max(np.abs(np.gradient(th, dt)[1:-1] - w[1:-1])) < 1e-6 * np.max(np.abs(w))
    inner = (t > 0.01) & (t < 0.99) & (np.abs(t - 0.3) > 0.01)  # the cosine ramp's end is a jerk step
    assert np.max(np.abs(np.gradient(w, dt) - a)[inner]) < 1e-4 * np.max(np.abs(a))
    phib = (thb + math.pi / 2)  # encoder angle, direction +1
    law = wb * (1 + 0.02 * np.sin(phib + 0.3) + 0.01 * np.sin(2 * phib + 1.0) + 0.005 * np.sin(3 * phib - 2.0))
    assert np.max(np.abs(w - law)) < 1e-12 * np.max(np.abs(w))


def test_the_ripple_fields_are_checked():
    from twin.config import preset
    from twin.errors import ConfigError

    with pytest.raises(ConfigError, match="ripple_pct"):
        preset(6).replace(**{"drive.ripple_pct": (12.0,)})
    with pytest.raises(ConfigError, match="ripple_phase_rad"):
        preset(6).replace(**{"drive.ripple_pct": (1.0, 2.0), "drive.ripple_phase_rad": (0.0,)})
    with pytest.raises(ConfigError, match="makes its own ripple"):
        preset(6).replace(**{"drive.ripple_pct": (1.0,), "drive.mode": "motor"})
    with pytest.raises(ConfigError, match="noise_scale"):
        preset(6).replace(**{"instrumentation.noise_scale": -1.0})


def test_the_ripple_factors_draw_a_phase_per_run_and_set_each_harmonic():
    from twin.config import preset
    from twin.dataset.factors import NAMED

    ov: dict = {}
    rng = np.random.default_rng(1)
    NAMED["ripple3_pct"].apply(1.5, ov, rng, preset(6))
    NAMED["ripple1_pct"].apply(2.5, ov, rng, preset(6))
    assert ov["drive.ripple_pct"] == [2.5, 0.0, 1.5]
    assert len(ov["drive.ripple_phase_rad"]) == 3 and ov["drive.ripple_phase_rad"][1] == 0.0
    assert all(0 <= p < 2 * math.pi for p in ov["drive.ripple_phase_rad"])
    preset(6).replace(**ov)  # a valid configuration


@pytest.mark.parametrize("ratio, warned", [(0.0, False), (0.09, False), (-0.09, False), (0.2, True), (-0.3, True)])
def test_the_rigid_rod_check_warns_where_the_rods_two_ends_disagree(ratio, warned):
    """The rod's longitudinal accelerometers at B (AC1) and C (AC4) read the same above 800 Hz on a rigid rod:
    beyond RIGID_ROD_RATIO_MAX (either sign) one warning naming both sensors, and the evidence records the
    value; the other checks are inside."""
    names = ["crank_hz", id_ranges.RIGID_ROD_FEATURE, "other"]
    x = np.array([2.2, ratio, 0.0])
    m = {"crank_hz": 2.2, "ripple_pct": [0.0] * 4, "noise_ug_rthz": 30.0}
    w, ev = id_ranges.out_of_range(m, "y", RANGES, x, None, names)
    assert ev["rigid_rod_ratio_log10"] == {"measured": ratio, "limit": id_ranges.RIGID_ROD_RATIO_MAX}
    assert len(w) == int(warned)
    if warned:
        assert "AC1" in w[0] and "AC4" in w[0] and "extrapolation" in w[0]


def test_the_rigid_rod_check_is_in_the_answers_record_and_reads_back():
    from twin.identification.results import TrainingDataCheck

    d = {"measured": {"crank_hz": 2.2, "ripple_pct": [0.0] * 4, "noise_ug_rthz": 30.0},
         "rigid_rod_ratio_log10": {"measured": 0.25, "limit": 0.1}, "outside_training_data": True,
         "interval_rule": "widened"}
    c = TrainingDataCheck.from_dict(d)
    assert c.rigid_rod_ratio_log10.measured == 0.25 and c.to_dict() == d
    with pytest.raises(ValueError, match="unknown"):
        TrainingDataCheck.from_dict(d | {"rigid_rod_ratio_log10": {"measured": 0.2, "limit": 0.1, "x": 1}})
