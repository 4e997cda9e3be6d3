"""Approximate warm starts (twin.warm_approx): the grouping, the state carried over, the first member's
exactness, and the stated approximation — the identification's features of a switched run differ from its
fresh run's by less than two fresh runs of one configuration differ (another noise seed and start angle)."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from twin.config import preset
from twin.simulation import Collector, make_engine, run_chunks, simulate
from twin.warm_approx import (ApproxWarmError, approx_groups, approx_key, compare_case, eligible, read_state,
                              set_state, simulate_approx, valid_from_s)


def _bench(duration: float = 0.5, **ov):
    """Table 4 test 1 as the nuisance spec's base (pid drive, constant program, ramp 0.3 s), B and C faulty."""
    base = {"simulation.duration_s": duration, "drive.ramp_s": 0.3, "drive.program": "constant",
            "drive.motor_rpm": 800.0, "joints.clearance_b_mm": 0.2, "joints.clearance_c_mm": 0.3,
            "joints.allow_noncatalogue": True, "mujoco.contact_source": "force",
            "sensors.channels": ["accel", "encoder"]}
    base.update(ov)
    return preset(1).replace(**base)


def test_groups_ignore_the_switched_fields_only():
    a = _bench()
    b = a.replace(**{"joints.clearance_b_mm": 0.05, "contact.restitution": 0.35, "contact.mu0": 0.03,
                     "mechanism.guide_friction_n": 5.0, "drive.initial_encoder_angle_rad": 2.0,
                     "drive.ripple_pct": [2.0], "drive.ripple_phase_rad": [1.0], "instrumentation.seed": 9})
    assert approx_key(a) == approx_key(b)
    # what decides the spin-up's mechanism state keeps runs apart
    for ov in ({"drive.motor_rpm": 500.0}, {"mechanism.orientation": "x"}, {"joints.clearance_c_mm": 0.0},
               {"simulation.timestep_s": 5e-6}):
        assert approx_key(a.replace(**ov)) != approx_key(a), ov
    assert approx_groups([a, a.replace(**{"drive.motor_rpm": 500.0}), b]) == [[0, 2], [1]]
    # runs the approximation does not cover run alone
    motor = a.replace(**{"drive.mode": "motor"})
    assert not eligible(motor) and not eligible(a.replace(**{"simulation.engine": "reference"}))
    assert approx_groups([motor, motor]) == [[0], [1]]
    with pytest.raises(ApproxWarmError):
        simulate_approx([motor, motor], [[], []])


def test_switch_time_must_follow_the_ramp():
    a = _bench()
    with pytest.raises(ApproxWarmError, match="switch_s"):
        simulate_approx([a, a], [[], []], switch_s=0.1)


def test_valid_from_s_reads_the_file_metadata():
    assert valid_from_s({}) == 0.0
    assert valid_from_s({"warm_start": {"valid_from_s": 0.45}}) == 0.45
    assert valid_from_s({"warm_start": '{"valid_from_s": 0.5}'}) == 0.5
    assert valid_from_s({"warm_start": {"valid_from_s": float("nan")}}) == 0.0


def test_the_state_carried_over_is_the_spin_ups_own_for_the_same_configuration():
    """Independent basis: the engine's own coordinates. Reading the mechanism state (crank, eccentricities
    at B and C in the bench frame, their rates) and setting it into a new engine of the same configuration
    gives back the spin-up's qpos and qvel (the loop's kinematics rebuild the rod and the slider)."""
    cfg = _bench(0.4)
    eng = make_engine(cfg)
    n = int(round(0.35 * cfg.output_rate_hz))
    for _ in run_chunks(cfg, eng, until=n):
        pass
    s = read_state(eng, cfg, n)
    other = make_engine(cfg)
    set_state(other, cfg, s, cfg)
    assert np.allclose(other.data.qpos, eng.data.qpos, rtol=0, atol=1e-12)
    assert np.allclose(other.data.qvel, eng.data.qvel, rtol=1e-9, atol=1e-9)
    assert np.array_equal(other.data.act, eng.data.act) and np.array_equal(other.data.userdata, eng.data.userdata)
    assert other.data.time == pytest.approx(eng.data.time, abs=1e-12)


def test_the_first_member_is_its_fresh_run_bit_for_bit():
    a = _bench(0.45)
    b = a.replace(**{"joints.clearance_b_mm": 0.1, "contact.restitution": 0.5, "drive.initial_encoder_angle_rad": 1.0})
    fresh = Collector()
    simulate(a, [fresh])
    ca, cb = Collector(), Collector()
    outs = simulate_approx([a, b], [[ca], [cb]])
    for k in fresh.run.channels:
        assert np.array_equal(ca.run[k], fresh.run[k]), k
    assert "warm_start" not in outs[0].meta
    ws = outs[1].meta["warm_start"]
    assert ws["approximate"] and ws["valid_from_s"] == pytest.approx(0.45) and ws["spin_up_of"] == a.name
    assert len(cb.run["AC1"]) == len(fresh.run["AC1"])


# three cases against the spin-up of _bench(2.0) (B 0.2, C 0.3 mm, no ripple, start angle 0): another clearance
# set, contact, guide friction, ripple and start angle. 2 s at 800 rpm (3.4 crank turns per second): the fresh run
# and the switched one (valid from 0.45 s) cut the same two 2-turn windows from the end (at 1.5 s the switched run
# keeps one window of the fresh run's two, and its features are of less data).
_CASES = (
    {"joints.clearance_b_mm": 0.6, "joints.clearance_c_mm": 0.1, "contact.restitution": 0.35,
     "contact.stiffness_scale": 1.7, "mechanism.guide_friction_n": 1.5, "drive.initial_encoder_angle_rad": 1.0,
     "instrumentation.seed": 11},
    {"joints.clearance_b_mm": 0.3, "joints.clearance_c_mm": 0.15, "contact.restitution": 0.45, "contact.mu0": 0.08,
     "mechanism.guide_friction_n": 3.0, "drive.ripple_pct": [1.0], "drive.ripple_phase_rad": [3.0],
     "drive.initial_encoder_angle_rad": 5.0, "instrumentation.seed": 12},
    # a large clearance at C (0.25 mm radial) at 800 rpm: see the xfail below
    {"joints.clearance_b_mm": 0.08, "joints.clearance_c_mm": 0.5, "contact.restitution": 0.55, "contact.mu0": 0.03,
     "mechanism.guide_friction_n": 4.0, "drive.ripple_pct": [2.0, 1.0], "drive.ripple_phase_rad": [0.5, 2.0],
     "drive.initial_encoder_angle_rad": 4.0},
)


@functools.lru_cache(maxsize=None)
def _distances() -> tuple[np.ndarray, np.ndarray]:
    """Per case: RMS over features of the standardized difference to the fresh run, of the switched run and of a
    repeat (the same configuration from rest with another noise seed and start angle), each feature standardized
    by its spread over the fresh runs and repeats of the cases."""
    ref = _bench(2.0)
    rows = []
    for k, ov in enumerate(_CASES):
        c = ref.replace(**ov)
        rep = c.replace(**{"instrumentation.seed": 1000 + k,
                           "drive.initial_encoder_angle_rad": c.drive.initial_encoder_angle_rad + 2.5})
        rows.append(compare_case(ref, c, rep))
    F = np.array([r["fresh"] for r in rows])
    R = np.array([r["repeat"] for r in rows])
    A = np.array([r["approx"] for r in rows])
    scale = np.concatenate([F, R]).std(axis=0, ddof=1)
    ok = scale > 1e-9 * (1 + np.abs(F).max(axis=0))
    return (np.sqrt(np.mean(((A - F)[:, ok] / scale[ok]) ** 2, axis=1)),
            np.sqrt(np.mean(((R - F)[:, ok] / scale[ok]) ** 2, axis=1)))


#: measured gaps (D of the switched run against D of a repeat) of the cases where the stated approximation does not
#: hold: the switched run is another draw of the joints' chaotic rattling, one that runs from rest (whatever their
#: start angle and noise seed) do not take. The figures were measured before the native contact's stored speeds were
#: carried over with the state; both cases still fail after it (measured: strict xfails)
_GAPS = {1: "D 0.90 against a repeat's 0.55 (B 0.15, C 0.075 mm radial, 1 % ripple)",
         2: "D 2.30 against a repeat's 0.64: the C pin (0.25 mm radial) rattles in another pattern than the fresh "
            "run's for the whole run, orders 4-8 of AC1/AC4 about 2x the fresh run's window after window"}


@pytest.mark.long
@pytest.mark.parametrize("case", [pytest.param(k, marks=[pytest.mark.xfail(strict=True, reason=f"measured: {_GAPS[k]}")]
                                               if k in _GAPS else []) for k in range(len(_CASES))])
def test_features_of_a_switched_run_differ_less_than_a_repeat(case):
    """The stated approximation: the identification's features (mean over windows) of the switched run, read from
    its valid_from_s, closer to its fresh run's than a repeat's are (the scatter between two recordings of one
    configuration: the independent basis). It holds for the first case and for the six nuisance-spec cases of
    analysis/warm_approx_check.py, not for the two marked (docs/datasets.md): the approximation stays opt-in."""
    d_approx, d_repeat = _distances()
    assert d_approx[case] < d_repeat[case], (d_approx, d_repeat)
