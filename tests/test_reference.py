"""The R-matrix reference engine: formulation (R, Ṙż, projection), accuracy against an
independent minimal-coordinate solution, energy behaviour, the engine protocol and agreement
with the MuJoCo twin on an ideal scene."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from twin.channels import channel_specs
from twin.config import BenchConfig, preset
from twin.errors import ConfigError
from twin import natural_coordinates as natural
from twin.reference import model as ref_model
from twin.reference.engine import ReferenceEngine, ReferenceOptions
from twin.run import Run
from twin.drive import DriveReference
from twin.simulation import run_chunks, simulate_run
from twin.summary import summarize

from conftest import short

G = 9.81


def _ideal(**ov) -> BenchConfig:
    return BenchConfig().replace(**{"joints.clearance_c_mm": 0.0, "mechanism.guide_friction_n": 0.0, **ov})


def _free_params(cfg: BenchConfig, h: float) -> np.ndarray:
    P = ref_model.build_params(cfg, drive=False, guide_friction=False, joint_friction=False)
    P[ref_model.P_H] = h
    return P


def _free_run(cfg: BenchConfig, h: float, duration: float, theta0: float = math.pi / 3, every_s: float = 1e-3):
    P = _free_params(cfg, h)
    st = natural.initial_state(cfg, theta0)
    n = int(round(duration / h))
    every = max(1, int(round(every_s / h)))
    bufs = [np.zeros(n // every + 2) for _ in range(4)]
    status, steps, m = ref_model.free_motion(P, st, n, every, *bufs)
    assert status == ref_model.OK and steps == n
    t = np.arange(m) * every * h
    return (t, *(b[:m] for b in bufs))


# ------------------------------------------------------------- R and Ṙż vs FD
def _state(clear_b: float, clear_c: float, theta: float, e_b=(0.0, 0.0), e_c=(0.0, 0.0), d_off=0.0):
    """A consistent (q, q̇) with the given eccentricities (bench frame) and random ż."""
    cfg = BenchConfig().replace(**{"joints.clearance_b_mm": clear_b, "joints.clearance_c_mm": clear_c,
                                   "joints.initial_eccentricity": "centred", "mechanism.d_off_m": d_off})
    P = ref_model.build_params(cfg)
    q = natural.initial_state(cfg, theta)[:ref_model.N_Q].copy()
    if clear_b:
        q[2:4] = q[0:2] - np.asarray(e_b)
    if clear_c:
        q[5] = d_off - e_c[1]
    q = _project(P, q)
    if clear_c:
        q[6] = q[4] + e_c[0]
    R, S = np.zeros((ref_model.N_Q, ref_model.N_Z)), np.zeros(ref_model.N_Q)
    nz = natural.r_matrix(P, q, np.zeros(ref_model.N_Q), R, S)
    zd = np.random.default_rng(1).normal(size=nz) * np.array([10.0, 0.05, -0.03, 0.02, 0.04])[:nz]
    qd = R[:, :nz] @ zd
    return P, q, qd, zd, nz


def _project(P, q):
    q = q.copy()
    res, dq, b = np.zeros(ref_model.N_Q), np.zeros(ref_model.N_Q), np.zeros(ref_model.N_Q)
    qd = np.zeros(ref_model.N_Q)
    assert ref_model.project(P, q, qd, math.sin(q[7]), math.cos(q[7]), res, dq, b) > 0
    return q


def _phi(P, q):
    res = np.zeros(ref_model.N_Q)
    natural.residual(P, q, math.sin(q[7]), math.cos(q[7]), res)
    return res


def _z(P, q):
    """Independent coordinates of q: θ, then e_B, e_C where the joint has a clearance."""
    z = [q[7]]
    if P[ref_model.P_CLR_B] > 0.5:
        z += [q[0] - q[2], q[1] - q[3]]
    if P[ref_model.P_CLR_C] > 0.5:
        z += [q[6] - q[4], P[ref_model.P_DOFF] - q[5]]
    return np.array(z)


SCENES = [
    (0.0, 0.0, 0.3, (0, 0), (0, 0), 0.0),
    (0.0, 0.1, 2.0, (0, 0), (3e-5, -2e-5), 0.01),
    (0.1, 0.1, -1.2, (1e-5, 4e-5), (-2e-5, 1e-5), 0.0),
    (0.1, 0.0, math.pi / 2, (4e-5, 0), (0, 0), -0.02),   # x_B = 0: the form x_B = r cos θ would be singular
    (0.1, 0.1, 0.0, (0, -4e-5), (4e-5, 0), 0.0),         # y_B = 0: the form y_B = r sin θ would be singular
]


@pytest.mark.parametrize("scene", SCENES)
def test_r_matrix_against_finite_differences_of_the_constraints(scene):
    P, q, qd, zd, nz = _state(*scene)
    R, S = np.zeros((ref_model.N_Q, ref_model.N_Z)), np.zeros(ref_model.N_Q)
    assert natural.r_matrix(P, q, qd, R, S) == nz
    R = R[:, :nz]
    eps = 1e-6
    constraint_rows = [i for i in range(7) if _is_constraint(P, i)]
    for j in range(nz):
        # Φ_q R = 0, by central differences of the constraint functions
        dphi = (_phi(P, q + eps * R[:, j]) - _phi(P, q - eps * R[:, j])) / (2 * eps)
        assert np.max(np.abs(dphi[constraint_rows])) < 1e-9
        # R = ∂q/∂z: move z_j, hold the others, re-solve the dependent coordinates
        qp, qm = _move_z(P, q, j, eps), _move_z(P, q, j, -eps)
        np.testing.assert_allclose((qp - qm) / (2 * eps), R[:, j], atol=1e-7)
    # Ṙż: q(t) = q + t q̇ + ½ t² Ṙż keeps Φ at O(t³) (Φ̈ = Φ_q Ṙż + Φ̇_q q̇ = 0 with z̈ = 0)
    for dt in (1e-4,):
        qp = q + dt * qd + 0.5 * dt * dt * S
        qm = q - dt * qd + 0.5 * dt * dt * S
        phi_dd = (_phi(P, qp) + _phi(P, qm) - 2 * _phi(P, q)) / dt**2
        assert np.max(np.abs(phi_dd[constraint_rows])) < 1e-6 * max(1.0, np.abs(qd).max() ** 2)
    # and Ṙż = (dR/dt) ż, from R at q ± δ q̇
    d = 1e-6
    Rp, Rm = np.zeros((ref_model.N_Q, ref_model.N_Z)), np.zeros((ref_model.N_Q, ref_model.N_Z))
    natural.r_matrix(P, q + d * qd, qd, Rp, np.zeros(ref_model.N_Q))
    natural.r_matrix(P, q - d * qd, qd, Rm, np.zeros(ref_model.N_Q))
    np.testing.assert_allclose((Rp[:, :nz] - Rm[:, :nz]) / (2 * d) @ zd, S, atol=1e-6 * max(1, np.abs(S).max()))


def _is_constraint(P, row):
    if row in (3, 4):
        return P[ref_model.P_CLR_B] < 0.5
    if row in (5, 6):
        return P[ref_model.P_CLR_C] < 0.5
    return True


def _move_z(P, q, j, eps):
    """Configuration with independent coordinate j moved by eps (others held), projected."""
    q = q.copy()
    rows = np.zeros(ref_model.N_Z, dtype=np.int64)
    ref_model.independent_rows(P, rows)
    row = rows[j]
    if row == 7:
        q[7] += eps
    elif row == 3:
        q[2] -= eps
    elif row == 4:
        q[3] -= eps
    elif row == 5:
        q[6] += eps
    elif row == 6:
        q[5] -= eps
    z0 = _z(P, q)
    q2 = _project(P, q)
    np.testing.assert_allclose(_z(P, q2), z0, atol=1e-15)  # the projection holds z
    return q2


# --------------------------------------------------------------- §4.1 free motion
def test_constraints_stay_at_round_off_over_the_5s_study_run():
    cfg = _ideal()
    _t, w, _e, phi, phid = _free_run(cfg, 1e-4, 5.0)
    assert np.max(phi) <= 1e-12
    assert np.max(phid) <= 1e-12
    assert np.max(np.abs(w)) > 5  # the crank really swings


def test_constraints_stay_at_round_off_with_clearances():
    cfg = short(preset(12), 0.1)
    eng = ReferenceEngine(cfg)
    eng.reset()
    st = eng.state0.copy()
    h = cfg.simulation.timestep_s
    buf = np.empty((1000, ref_model.N_OUT))
    ref_t = np.arange(10000) * h
    th, om = DriveReference(cfg)(ref_t)
    for k in range(10):
        sl = slice(1000 * k, 1000 * (k + 1))
        status, _ = ref_model.run_steps(eng.P, st, th[sl].copy(), om[sl].copy(), 1, buf, True)
        assert status == ref_model.OK
        q, qd = st[ref_model.S_Q:ref_model.S_Q + ref_model.N_Q], st[ref_model.S_QD:ref_model.S_QD + ref_model.N_Q]
        assert ref_model.constraint_norm(eng.P, q) <= 1e-12
        assert ref_model.velocity_constraint_norm(eng.P, q, qd) <= 1e-12


def test_energy_drift_first_order():
    """Frictionless ideal run: the energy error of symplectic Euler shrinks about linearly with h."""
    cfg = _ideal()
    drift = []
    for h in (2e-4, 1e-4, 5e-5):
        _t, _w, e, _phi, _phid = _free_run(cfg, h, 2.0)
        drift.append(abs(e[-1] - e[0]))
    assert drift[0] > 1e-4  # measurable
    for a, b in zip(drift, drift[1:]):
        assert 1.7 < a / b < 2.3


class Minimal:
    """Independent minimal-coordinate model of the ideal mechanism (Lagrange, coordinate θ).

    Closed-form slider–crank: B = r(cos θ, sin θ), sin φ = (d − r sin θ)/l, x_s = r cos θ + l cos φ,
    G₂ = B + ξ₂ (cos φ, sin φ). With ′ = d/dθ: T = ½ J(θ) θ̇², J = I_A + m₂|G₂′|² + I₂ φ′² + m₃ x_s′²,
    V = −g·(m₁ G₁ + m₂ G₂) − m₃ g_x x_s, and J θ̈ + ½ J′ θ̇² + V′ = 0, every derivative analytic
    (a finite-difference J′ is too noisy for a 1e-12 tolerance)."""

    def __init__(self, cfg: BenchConfig):
        b = cfg.bodies
        self.r, self.l, self.d = b.crank.length_m, b.rod.length_m, cfg.mechanism.d_off_m
        self.m1, self.k1 = b.crank.mass_kg, b.crank.x_g_m / b.crank.length_m
        self.ia = b.crank.inertia_kgm2 + b.crank.mass_kg * b.crank.x_g_m**2
        self.m2, self.x2, self.i2 = b.rod.mass_kg, b.rod.x_g_m, b.rod.inertia_kgm2
        self.m3 = b.slider.mass_kg
        self.g = np.array(cfg.mechanism.gravity_vector[:2])

    def terms(self, th):
        """(J, J′, V′) at θ."""
        r, l, x2 = self.r, self.l, self.x2
        s, c = math.sin(th), math.cos(th)
        sp = (self.d - r * s) / l
        cp = math.sqrt(1 - sp * sp)
        p1 = -r * c / (l * cp)                       # φ′
        p2 = (r * s / l + sp * p1 * p1) / cp         # φ″
        B1, B2 = np.array([-r * s, r * c]), np.array([-r * c, -r * s])
        n, u = np.array([-sp, cp]), np.array([cp, sp])
        G1 = B1 + x2 * p1 * n                        # G₂′
        G2 = B2 + x2 * (p2 * n - p1 * p1 * u)        # G₂″
        xs1 = -r * s - l * sp * p1
        xs2 = -r * c - l * cp * p1 * p1 - l * sp * p2
        J = self.ia + self.m2 * G1 @ G1 + self.i2 * p1 * p1 + self.m3 * xs1 * xs1
        dJ = 2 * (self.m2 * G1 @ G2 + self.i2 * p1 * p2 + self.m3 * xs1 * xs2)
        dV = -(self.g @ (self.m1 * self.k1 * B1 + self.m2 * G1)) - self.m3 * self.g[0] * xs1
        return J, dJ, dV

    def acc(self, th, w):
        J, dJ, dV = self.terms(th)
        return -(0.5 * dJ * w * w + dV) / J


@pytest.mark.parametrize("orientation, d_off", [("y", 0.0), ("x", 0.02)])
def test_agrees_with_minimal_coordinate_solution(orientation, d_off):
    cfg = _ideal(**{"mechanism.orientation": orientation, "mechanism.d_off_m": d_off})
    mm = Minimal(cfg)
    theta0 = math.pi / 3
    T = 1.0
    t_eval = np.arange(0, T + 1e-9, 1e-3)
    sol = solve_ivp(lambda _t, y: [y[1], mm.acc(y[0], y[1])], (0, T), [theta0, 0.0], method="DOP853",
                    t_eval=t_eval, rtol=1e-12, atol=1e-12)
    errs = []
    for h in (1e-4, 1e-5):
        P = _free_params(cfg, h)
        st = natural.initial_state(cfg, theta0)
        every = int(round(1e-3 / h))
        ths, ws = [st[7]], [st[ref_model.S_QD + 7]]
        zero = np.zeros(every)
        for _ in range(len(t_eval) - 1):
            status, _ = ref_model.run_steps(P, st, zero, zero, every, np.empty((1, ref_model.N_OUT)), False)
            assert status == ref_model.OK
            ths.append(st[7])
            ws.append(st[ref_model.S_QD + 7])
        errs.append((np.max(np.abs(np.array(ths) - sol.y[0])), np.max(np.abs(np.array(ws) - sol.y[1]))))
    assert np.max(np.abs(sol.y[1])) > 3          # a real swing
    th_err, w_err = errs[1]
    assert th_err < 1e-3 and w_err < 5e-3        # h = 1e-5 s (1 s of a swing up to 20 rad/s)
    # first-order convergence to the exact solution: ten times smaller for a ten times smaller h
    assert 8 < errs[0][0] / errs[1][0] < 12
    assert 8 < errs[0][1] / errs[1][1] < 12


def test_rmatrix_equals_euler_on_minimal_ode():
    """The R-matrix step is symplectic Euler on the reduced 1-DOF equation: same numbers."""
    cfg = _ideal()
    mm = Minimal(cfg)
    h, n = 1e-4, 5000
    th, w = math.pi / 3, 0.0
    for _ in range(n):
        w += h * mm.acc(th, w)
        th += h * w
    P = _free_params(cfg, h)
    st = natural.initial_state(cfg, math.pi / 3)
    z = np.zeros(n)
    assert ref_model.run_steps(P, st, z, z, 1, np.empty((1, ref_model.N_OUT)), False)[0] == ref_model.OK
    assert st[7] == pytest.approx(th, abs=1e-7)
    assert st[ref_model.S_QD + 7] == pytest.approx(w, abs=1e-6)


# ---------------------------------------------------------------- engine protocol
def test_engine_channels_chunks_and_summary():
    cfg = short(preset(12), 0.06, **{"simulation.chunk_s": 0.025})
    eng = ReferenceEngine(cfg)
    chunks = list(run_chunks(cfg, engine=eng))
    assert len(chunks) == 3
    run = Run.concat(chunks)
    run.meta = dict(eng.meta)
    assert list(run.channels) == [s.name for s in channel_specs(cfg)]
    assert run.n == 6000 and run.rate_hz == 100_000
    whole = simulate_run(cfg.replace(**{"simulation.engine": "reference", "simulation.chunk_s": 1.0}))
    for name in run.channels:  # chunking does not change the result
        np.testing.assert_array_equal(run[name], whole[name])
    for key in ("engine", "engine_version", "timestep_s", "steps", "wall_s", "real_time_factor"):
        assert key in eng.meta
    assert eng.meta["steps"] == 6000 and eng.meta["engine"] == "reference"
    s = summarize(run)
    assert s["engine"] == "reference" and s["C"]["max_contact_force_N"] > 0
    # sample 0 is the initial state: at rest, crank at the drive's start angle
    assert run["crank_speed"][0] == 0.0
    assert run["crank_angle"][0] == pytest.approx(-math.pi / 2)


@pytest.mark.parametrize("orientation, expected_g", [
    ("y", {"AC1": 0, "AC2": 1, "AC3": 1, "AC4": 0, "AC5": 1, "AC6": 0}),
    ("x", {"AC1": 1, "AC2": 0, "AC3": 0, "AC4": 1, "AC5": 0, "AC6": 1}),
    ("z", {"AC1": 0, "AC2": 0, "AC3": 0, "AC4": 0, "AC5": 0, "AC6": 0}),
])
def test_calibration_pose_readings(orientation, expected_g):
    cfg = BenchConfig().replace(**{
        "joints.clearance_c_mm": 0.0, "drive.motor_rpm": 0.0, "mechanism.orientation": orientation,
        "drive.initial_encoder_angle_rad": math.pi / 2, "simulation.duration_s": 0.05,
        "simulation.engine": "reference"})
    run = simulate_run(cfg)
    for a, g in expected_g.items():
        assert run[a][-500:].mean() / G == pytest.approx(g, abs=1e-4), a


def test_matches_mujoco_on_ideal_test3():
    """Ideal joints (test 3 scene): the two engines agree closely (MuJoCo's loop closure at C is
    a stiff soft constraint, the reference's is exact)."""
    cfg = short(preset(3), 0.5, **{"drive.ramp_s": 0.2})
    mj = simulate_run(cfg.replace(**{"simulation.engine": "mujoco"}))
    ref = simulate_run(cfg.replace(**{"simulation.engine": "reference"}))
    assert np.max(np.abs(mj["slider_position"] - ref["slider_position"])) < 1e-6
    assert np.max(np.abs(mj["crank_angle"] - ref["crank_angle"])) < 1e-5
    for a in ("AC1", "AC2", "AC3", "AC4", "AC6"):
        rms_mj = np.sqrt(np.mean(mj[a].astype(float) ** 2))
        rms_ref = np.sqrt(np.mean(ref[a].astype(float) ** 2))
        assert rms_ref == pytest.approx(rms_mj, rel=2e-3), a
    assert np.sqrt(np.mean(ref["crank_torque"].astype(float) ** 2)) == pytest.approx(
        np.sqrt(np.mean(mj["crank_torque"].astype(float) ** 2)), rel=1e-2)


# ---------------------------------------------------------------------- bad input
def test_bad_options_give_clear_errors():
    with pytest.raises(ConfigError, match="newton_tol_m"):
        ReferenceOptions(newton_tol_m=1.0)
    with pytest.raises(ConfigError, match="newton_max_iter"):
        ReferenceOptions(newton_max_iter=0)
    with pytest.raises(ConfigError, match="impact_speed_floor_mps"):
        preset(6).replace(**{"contact.impact_speed_floor_mps": 0.0})


def test_geometry_the_rod_cannot_close_is_a_config_error():
    with pytest.raises(ConfigError, match="bodies"):  # refused by the configuration, before any engine
        ReferenceEngine(preset(3).replace(**{"bodies.rod.length_m": 0.1})).reset()  # rod shorter than the crank
