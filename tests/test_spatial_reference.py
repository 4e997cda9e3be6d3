"""The spatial slider–crank of S002 in the reference engine (twin.spatial): checks against closed-form
kinematics, energy conservation and the planar reference model."""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.config import ConfigError, named_preset
from twin.simulation import Collector, simulate, simulate_run
from twin.spatial import model as SM
from twin.spatial.engine import SpatialOptions, SpatialReferenceEngine, run_raw
from twin.spatial.geometry import slider_closed_form

IDEAL = {"joints.clearance_a_mm": 0.0, "joints.clearance_b_mm": 0.0, "joints.clearance_c_mm": 0.0}


def _s002(**overrides):
    return named_preset("s002").replace(**{"simulation.engine": "reference", **overrides})


@pytest.mark.parametrize("axis,offset", [("x", 0.019554), ("x", 0.15), ("y", 0.02)])
def test_ideal_slider_matches_closed_form_kinematics(axis, offset):
    """Independent basis: the slider's position and acceleration in closed form (twin.spatial.geometry,
    from |C − B| = L differentiated twice by hand), at the run's crank angles, ≤ 1e-6 relative."""
    cfg = _s002(**IDEAL, **{"simulation.duration_s": 0.08, "spatial.guide_axis": axis,
                            "spatial.guide_offset_z_m": offset})
    run = simulate_run(cfg)
    theta, omega = run["crank_angle"], run["crank_speed"]
    assert np.max(np.abs(theta - run["theta_ref"])) < 1e-9
    x, _, a = slider_closed_form(cfg, theta, omega)
    assert np.max(np.abs(run["slider_position"] - x)) <= 1e-6 * np.max(np.abs(x))
    assert np.max(np.abs(run["slider_acceleration"] - a)) <= 1e-6 * np.max(np.abs(a))
    assert np.ptp(run["slider_position"]) > 0.005  # the slider does move (a stroke of millimetres at least)


def _energy_run(clearance_mm: float, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Free fall of the released mechanism (no drive), μ = 0, e = 1 (the LN law without damping: its
    elastic energy K δ^(n+1)/(n+1) counted), 0.1 s at step ``h`` [s]: the total energy's departure from
    its initial value [J], the kinetic energy [J] and whether any joint is in contact, per step."""
    cfg = _s002(**{"simulation.duration_s": 0.1, "simulation.timestep_s": h, "sensors.output_rate_hz": 1.0 / h,
                   "joints.clearance_a_mm": clearance_mm, "joints.clearance_b_mm": clearance_mm,
                   "joints.clearance_c_mm": clearance_mm, "contact.mu0": 0.0, "contact.restitution": 1.0,
                   "drive.initial_encoder_angle_rad": math.pi / 2 + 1.0})
    out = run_raw(cfg, SpatialOptions(drive=False))
    energy = out[:, SM.O_EKIN] + out[:, SM.O_EPOT] + out[:, SM.O_EEL]
    contact = np.any(out[:, [SM.O_JOINT + 6 * j + 4 for j in range(3)]] > 0.0, axis=1)
    return energy - energy[0], out[:, SM.O_EKIN], contact


@pytest.mark.parametrize("clearance_mm", [0.0, 0.2])
def test_energy_error_is_first_order_in_h_while_the_motion_is_smooth(clearance_mm):
    """The exact motion (no drive, no friction, no damping) conserves energy. On a smooth stretch of it
    the symplectic Euler's energy error is C h + O(h²) with C fixed by the motion (S003 Eq. 21 is a first
    order method), so halving h halves the error (ratio 2; 1.5–2.6 leaves room for the O(h²) part).
    Without clearance the whole 0.1 s is smooth; with 0.2 mm only the flight before the first contact
    is: through impacts the pins' flights depend chaotically on every rounding (another CPU's BLAS
    gives another sequence of impacts), and one pair of step sizes shows no order there (see the test
    below for what does hold through impacts)."""
    de1, ekin, c1 = _energy_run(clearance_mm, 1e-5)
    de2, _, c2 = _energy_run(clearance_mm, 5e-6)
    assert ekin.max() > 0.1  # the mechanism does fall (J)
    # the smooth window: up to the first contact of either run (the whole run without clearance)
    t1 = np.argmax(c1) if c1.any() else len(c1)
    t2 = np.argmax(c2) if c2.any() else len(c2)
    n1 = min(t1, t2 // 2)  # samples of the h = 1e-5 run in the window (the other run has twice as many)
    assert n1 > 200  # a window of 2 ms at least (with clearance: the first impact comes after 4.5 ms)
    if clearance_mm == 0.0:
        assert n1 == len(c1)
    err1, err2 = np.max(np.abs(de1[:n1])), np.max(np.abs(de2[:2 * n1]))
    assert err1 < 1e-3 * ekin.max()
    assert 1.5 < err1 / err2 < 2.6


def test_energy_error_through_impacts_is_bounded_by_h_times_the_power():
    """Through impacts (0.2 mm clearance at A, B, C; elastic Hertz-type contact, e = 1, μ = 0) the energy
    error of the symplectic Euler stays bounded by h times the forces' power, at every step size.

    Basis (backward error analysis, Hairer, Lubich & Wanner, Geometric Numerical Integration, IX.3):
    the symplectic Euler v ← v + h M⁻¹F(q), q ← q + h v conserves a modified energy
    H̃ = H ± (h/2) F(q)·v + O(h²) — the error's first term is half a step of the power P = F·v, and it
    does not grow with time (a non-symplectic first-order method's error grows as h t). So
    |E_n − E_0| ≤ (h/2)(|P_n| + |P_0|) + O(h²) ≤ h max|P|. P is measured as dE_kin/dt of the run (the
    power of all forces, by central differences of the kinetic energy). The bound is the theory's leading
    term without a margin factor; the runs sit at 0.3–0.65 of it. It holds at each step size whatever the
    (chaotic) sequence of impacts. Checked to fail: explicit Euler (q ← q + h v_old: the run diverges
    through the first impacts) and a contact that is not quite conservative (e = 0.995: its loss does not
    shrink with h, 1.6× the bound at h = 2.5 µs)."""
    for h in (2e-5, 1e-5, 5e-6, 2.5e-6):
        de, ekin, contact = _energy_run(0.2, h)
        assert np.count_nonzero(np.diff(contact.astype(int)) == 1) >= 5  # impacts happen (contacts begun)
        power = np.gradient(ekin, h)  # [W]
        assert np.max(np.abs(de)) <= h * np.max(np.abs(power)), h


@pytest.mark.parametrize("clearance_mm", [0.0, 0.2])
def test_spatial_model_in_a_plane_reproduces_planar_reference(clearance_mm):
    """Guide in the crank's plane, gravity in that plane, μ = 0: the spatial model is the planar one
    (spatial x, y, z = planar z, x, y; a spherical joint moving in a plane is a revolute joint with the
    same contact law), projected as the planar engine projects. Independent basis: the planar reference engine (twin.reference), a separate
    formulation and code; the runs must agree to round-off through the impacts."""
    c = clearance_mm
    base = _s002(**{"simulation.duration_s": 0.05, "joints.clearance_a_mm": c, "joints.clearance_b_mm": c,
                    "joints.clearance_c_mm": c, "contact.mu0": 0.0, "mechanism.d_off_m": 0.02,
                    "contact.impact_speed_floor_mps": 0.1})
    cfg = base.replace(**{"spatial.guide_axis": "y", "spatial.guide_offset_z_m": 0.02,
                          "mechanism.orientation": "z"})
    keep = Collector()
    # the planar engine's projection (independent coordinates held): the same discrete motion
    simulate(cfg, [keep], engine=SpatialReferenceEngine(cfg, SpatialOptions(projection="partitioned")))
    spatial = keep.run
    planar = simulate_run(base.replace(**{"spatial.enabled": False,
                                          "sensors.channels": ["encoder", "crank", "slider", "joints", "drive"]}))
    assert np.max(np.abs(spatial["slider_position"] - planar["slider_position"])) < 1e-12
    torque = planar["crank_torque"].astype(float)
    assert np.max(np.abs(spatial["crank_torque"] - torque)) <= 1e-5 * np.max(np.abs(torque))
    for j in base.joints.clearance_joints:
        fn = planar[f"fn_{j}"].astype(float)
        assert fn.max() > 100.0  # impacts happen
        assert np.max(np.abs(spatial[f"fn_{j}"] - fn)) <= 1e-5 * fn.max()
        assert np.max(np.abs(spatial[f"pen_{j}"] - planar[f"pen_{j}"])) < 1e-12


def test_s002_preset_runs_with_the_bench_channels_and_summary():
    cfg = _s002(**{"simulation.duration_s": 0.02})
    run = simulate_run(cfg)
    for name in ("slider_position", "slider_acceleration", "crank_angle", "encoder_angle", "crank_torque",
                 "fn_A", "fn_B", "fn_C", "ecc_B_z"):
        assert name in run.channels
    assert run.channels["slider_acceleration"].unit == "m/s^2"
    from twin.summary import summarize

    s = summarize(run)
    assert set("ABC") <= set(s) and s["slider_acceleration"]["rms_mps2"] > 0


def test_spatial_configuration_errors_name_the_field():
    with pytest.raises(ConfigError) as err:
        _s002(**{"spatial.guide_axis": "z"})
    assert err.value.field == "spatial.guide_axis"
    with pytest.raises(ConfigError) as err:
        _s002(**{"drive.mode": "pid"})
    assert err.value.field == "drive.mode"
    with pytest.raises(ConfigError) as err:
        _s002(**{"spatial.guide_offset_z_m": 0.3})
    assert err.value.field == "spatial.guide_offset_z_m"
    with pytest.raises(ConfigError) as err:  # the planar bench has no slider_accel group
        named_preset("s001").replace(**{"sensors.channels": ["crank", "slider_accel"]})
    assert err.value.field == "sensors.channels"
