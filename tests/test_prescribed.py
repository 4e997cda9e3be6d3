"""The prescribed (infinitely stiff) crank drive, drive.mode = "prescribed" (issue 18, item 1).

Independent basis: the closed-form slider–crank kinematics (twin.kinematics.slider_kinematics,
exact derivatives of x = r cos θ + sqrt(l² − r² sin² θ)) and, for the drive torque, the energy
balance of the ideal, frictionless mechanism at constant crank speed, τ ω = dE/dt, i.e.
τ = dE/dθ with E(θ) = T + V written from the bodies' closed-form velocities (no engine code).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.config import BenchConfig
from twin.drive import DriveReference
from twin.errors import ConfigError
from twin.kinematics import slider_kinematics
from twin.simulation import make_engine, run_chunks


def ideal(engine: str, crank_rpm: float, ramp_s: float = 0.0, duration: float = 0.05) -> BenchConfig:
    return BenchConfig().replace(**{
        "name": "prescribed", "joints.clearance_c_mm": 0.0, "joints.clearance_b_mm": 0.0,
        "drive.mode": "prescribed", "drive.crank_rpm": crank_rpm, "drive.ramp_s": ramp_s,
        "mechanism.d_off_m": 0.0, "mechanism.guide_friction_n": 0.0,
        "simulation.engine": engine, "simulation.duration_s": duration, "simulation.chunk_s": 0.005})


def run_with_velocity(cfg: BenchConfig):
    """Channels of the run and the slider velocity read from the engine's state at chunk ends."""
    eng = make_engine(cfg)
    chunks, vel = [], []
    for ch in run_chunks(cfg, eng):
        chunks.append(ch)
        t_end = ch.t0 + ch.duration_s
        if cfg.simulation.engine == "reference":
            from twin.reference import model as ref_model

            v = float(eng._st[ref_model.S_QD + 6])
        else:
            from twin import names

            v = float(eng.data.qvel[eng.model.jnt_dofadr[eng.model.joint(names.SLIDER_SLIDE).id]])
        vel.append((t_end, v))
    cols = {k: np.concatenate([np.asarray(c[k].data, dtype=float) for c in chunks]) for k in chunks[0].channels}
    return cols, vel


def energy_torque(cfg: BenchConfig, theta: np.ndarray, w: float) -> np.ndarray:
    """Drive torque of the ideal frictionless mechanism at constant ω: dE/dθ (central difference)."""
    b = cfg.bodies
    r, l, g = b.crank.length_m, b.rod.length_m, cfg.mechanism.gravity_mps2

    def E(th):
        _, v, _ = slider_kinematics(th, w, 0.0 * th, r, l, 0.0)
        phi = np.arcsin(-r * np.sin(th) / l)
        phid = -r * np.cos(th) * w / (l * np.cos(phi))
        xg = b.rod.x_g_m
        gx = -r * w * np.sin(th) - xg * phid * np.sin(phi)
        gy = r * w * np.cos(th) + xg * phid * np.cos(phi)
        ia = b.crank.inertia_kgm2 + b.crank.mass_kg * b.crank.x_g_m ** 2
        T = 0.5 * ia * w ** 2 + 0.5 * b.rod.mass_kg * (gx ** 2 + gy ** 2) + 0.5 * b.rod.inertia_kgm2 * phid ** 2 \
            + 0.5 * b.slider.mass_kg * v ** 2
        V = g * (b.crank.mass_kg * b.crank.x_g_m * np.sin(th) + b.rod.mass_kg * (r * np.sin(th) + xg * np.sin(phi)))
        return T + V

    d = 1e-6
    return (E(theta + d) - E(theta - d)) / (2 * d)


# tolerances: the reference engine is exact up to the float32 storage of the channels; MuJoCo's
# ideal joint C is a soft connect constraint (equality solref/solimp), which deflects under the
# rod force (measured 2.84 um at the dead centres at 3000 rpm, 28 kN on the slider, 7.9 um at
# 5000 rpm: 2.0e-10 m per m/s² of the slider's peak acceleration, so the position tolerance is
# x = 3e-10 s² × that peak) and needs ~1 ms to load up from the consistent start. The crank
# itself is exact.
# Velocities: the reference projects them onto the constraints at t_k (q̇ = R ż with θ̇ = ω_ref(t_k));
# MuJoCo's semi-implicit Euler keeps q_{k+1} = q_k + h q̇_{k+1}, so its velocities are those of the
# step's midpoint, t_k − h/2 (off by h a/2 at t_k: 0.07 m/s for the slider at 14 200 m/s²); they are
# compared there ("lag").
TOL = {"reference": dict(x=1e-13, v=1e-9, a=1e-6, tau=1e-5, settle=0.0, lag=0.0),
       "mujoco": dict(x=3e-10, v=1e-4, a=1e-4, tau=1e-3, settle=0.005, lag=0.5)}


@pytest.mark.parametrize("engine", ["reference", "mujoco"])
def test_constant_speed_from_rest_pose_equals_closed_form(engine):
    cfg = ideal(engine, 3000.0)
    cols, vel = run_with_velocity(cfg)
    tol = TOL[engine]
    w = cfg.drive.crank_rad_s
    n = len(cols["crank_angle"])
    t = np.arange(n) / cfg.output_rate_hz
    theta0 = DriveReference(cfg)(np.zeros(1))[0][0]
    # the crank angle is the program to round-off (θ up to 16 rad: 1 ulp = 3.6e-15)
    assert np.max(np.abs(cols["crank_angle"] - (theta0 + w * t))) < 1e-12
    assert np.max(np.abs(cols["crank_speed"] - w)) < 1e-6 * w
    r, l = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    x, v, a = slider_kinematics(theta0 + w * t, w, 0.0, r, l, 0.0)
    k = t >= tol["settle"]
    # AC6 is the slider's acceleration along +x (y vertical: no gravity component)
    peak = np.max(np.abs(a))
    assert np.max(np.abs(cols["slider_position"][k] - x[k])) < tol["x"] * peak
    assert peak == pytest.approx(r * w * w * (1 + r / l), rel=1e-9)
    assert np.max(np.abs(cols["AC6"][k] - a[k])) < tol["a"] * peak
    vmax = r * w * 1.1
    for t_end, vs in vel:
        if t_end < tol["settle"]:
            continue
        te = t_end - tol["lag"] * cfg.simulation.timestep_s
        ve = slider_kinematics(theta0 + w * te, w, 0.0, r, l, 0.0)[1]
        assert abs(vs - ve) < tol["v"] * vmax
    # the drive torque reported is the one the energy balance asks for
    tau = energy_torque(cfg, theta0 + w * t, w)
    assert np.max(np.abs(cols["crank_torque"][k] - tau[k])) < tol["tau"] * np.max(np.abs(tau))


@pytest.mark.parametrize("engine", ["reference", "mujoco"])
def test_ramp_to_5000_rpm_follows_the_program(engine):
    """A cosine ramp from rest to 5000 crank rpm in 20 ms: the crank is the program at every
    step, the slider the closed form with the program's ω and α."""
    cfg = ideal(engine, 5000.0, ramp_s=0.02, duration=0.03)
    cols, _ = run_with_velocity(cfg)
    ref = DriveReference(cfg)
    t = np.arange(len(cols["crank_angle"])) / cfg.output_rate_hz
    th, om = ref(t)
    al = ref.acceleration(t)
    tol = TOL[engine]
    assert np.max(np.abs(cols["crank_angle"] - th)) < 1e-12
    om_mid = ref(t[1:] - tol["lag"] * cfg.simulation.timestep_s)[1]
    assert np.max(np.abs(cols["crank_speed"][1:] - om_mid)) < 1e-6 * np.max(om)
    r, l = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    x, _, a = slider_kinematics(th, om, al, r, l, 0.0)
    assert np.max(np.abs(cols["slider_position"] - x)) < tol["x"] * np.max(np.abs(a))
    assert np.max(np.abs(cols["AC6"] - a)) < tol["a"] * np.max(np.abs(a))


def test_crank_rpm_bypasses_motor_and_belt():
    cfg = ideal("reference", 5000.0)
    assert cfg.drive.crank_rad_s == pytest.approx(5000 * 2 * math.pi / 60)
    ref = DriveReference(cfg)
    assert ref(np.array([1.0]))[1][0] == pytest.approx(5000 * 2 * math.pi / 60)
    assert ref.start_rate() == pytest.approx(5000 * 2 * math.pi / 60)
    assert ref.command_rpm(np.array([0.5]))[0] == pytest.approx(5000 * cfg.drive.belt_ratio)
    # the PID drive starts at rest whatever the ramp
    assert DriveReference(cfg.replace(**{"drive.mode": "pid"})).start_rate() == 0.0


@pytest.mark.parametrize("overrides, field", [
    ({"drive.mode": "stiff"}, "drive.mode"),
    ({"drive.crank_rpm": 7000.0}, "drive.crank_rpm"),
    ({"drive.crank_rpm": 100.0, "drive.program": "protocol"}, "drive.crank_rpm"),
    ({"drive.mode": "prescribed", "drive.program": "protocol", "drive.ramp_s": 0.0}, "drive.ramp_s"),
    ({"drive.mode": "prescribed", "mujoco.integrator": "implicitfast"}, "mujoco.integrator"),
    ({"drive.mode": "prescribed", "sensors.channels": ["accel", "energy"]}, "sensors.channels"),
])
def test_bad_drive_settings_name_the_field(overrides, field):
    with pytest.raises(ConfigError) as err:
        BenchConfig().replace(**overrides)
    assert err.value.field == field
