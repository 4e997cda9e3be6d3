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


def _energy_error(clearance_mm: float, h: float) -> tuple[float, float]:
    cfg = _s002(**{"simulation.duration_s": 0.1, "simulation.timestep_s": h, "sensors.output_rate_hz": 1.0 / h,
                   "joints.clearance_a_mm": clearance_mm, "joints.clearance_b_mm": clearance_mm,
                   "joints.clearance_c_mm": clearance_mm, "contact.mu0": 0.0, "contact.restitution": 1.0,
                   "drive.initial_encoder_angle_rad": math.pi / 2 + 1.0})
    out = run_raw(cfg, SpatialOptions(drive=False))
    energy = out[:, SM.O_EKIN] + out[:, SM.O_EPOT] + out[:, SM.O_EEL]
    return float(np.max(np.abs(energy - energy[0]))), float(np.max(out[:, SM.O_EKIN]))


@pytest.mark.parametrize("clearance_mm", [0.0, 0.2])
def test_energy_conserved_without_friction_and_damping(clearance_mm):
    """Free fall of the released mechanism (no drive), μ = 0, e = 1 (the LN law without damping: its
    elastic energy K δ^(n+1)/(n+1) counted): the exact motion conserves energy, so the symplectic
    Euler's error must be small and shrink in proportion to h (a first-order method)."""
    err1, ekin = _energy_error(clearance_mm, 1e-5)
    err2, _ = _energy_error(clearance_mm, 5e-6)
    assert ekin > 0.1  # the mechanism does fall (J)
    assert err1 < 1e-3 * ekin
    assert 1.5 < err1 / err2 < 2.6


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
