"""A clearance at the ground pivot A in the reference engine (the crank journal A' in the frame's
bore, q[8:10]) and per-joint pin radii, each checked on an independent basis: the static load of
:mod:`twin.kinematics` and Eq. 18 (closed forms), the exact kinematics of the slider–crank with a
displaced crank centre, the power of the contact forces against finite differences of the
contact points' material velocities, the ideal limit c → 0, and the bit-identity of scenes whose
joint A is ideal."""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.config import ACCELEROMETERS, BenchConfig, preset
from twin.drive import DriveReference
from twin.kinematics import static_pin_forces
from twin import natural_coordinates as natural
from twin.reference import model as ref_model
from twin.reference.engine import ReferenceEngine
from twin.simulation import simulate_run

from conftest import short

STEEL_BORE = {"youngs_modulus_pa": 200e9, "poisson": 0.29, "density_kgm3": 7800.0}


def _eq18(pin_radius: float, clearance: float, pin, bushing) -> float:
    """S003 Eq. 18 written out: K = 4 / (3 (h_i + h_j)) sqrt(R_i R_j / (R_i − R_j)), h = (1 − ν²)/E."""
    h = sum((1 - m.poisson ** 2) / m.youngs_modulus_pa for m in (pin, bushing))
    ri = pin_radius + clearance
    return 4 / (3 * h) * math.sqrt(ri * pin_radius / (ri - pin_radius))


# ------------------------------------------------------------------------ statics
@pytest.mark.parametrize("orientation, clearances", [
    ("y", {"joints.clearance_a_mm": 0.1, "joints.clearance_c_mm": 0.0}),
    ("x", {"joints.clearance_a_mm": 0.1, "joints.clearance_b_mm": 0.1, "joints.clearance_c_mm": 0.5}),
])
def test_journal_rests_in_the_bore_under_its_static_load(orientation, clearances):
    """Crank held by the PID at a fixed angle, guide friction off: the frame's bore carries the
    crank's weight and pin B's static load (twin.kinematics.static_pin_forces), F_A = m₁ g + F_B;
    the journal sinks δ = (|F|/K)^(2/3) towards F, with K = Eq. 18 of A's own pin and bore (here a
    steel bore and a 30 mm journal), and the normal force equals |F|."""
    cfg = BenchConfig().replace(**{
        **clearances, "simulation.engine": "reference", "drive.motor_rpm": 0.0,
        "mechanism.orientation": orientation, "mechanism.guide_friction_n": 0.0,
        "joints.pin_diameters_m": {"A": 0.03}, "materials.bushings": {"A": STEEL_BORE},
        "drive.initial_encoder_angle_rad": 2.2, "sensors.channels": ["crank", "joints"], "simulation.duration_s": 0.1})
    run = simulate_run(cfg)
    theta = float(run["crank_angle"][-1])
    f_b, f_c = static_pin_forces(cfg, theta)
    f_a = cfg.bodies.crank.mass_kg * np.asarray(cfg.mechanism.gravity_vector[:2]) + f_b
    mat = cfg.materials
    for j, f in (("A", f_a), ("B", f_b), ("C", f_c)):
        if j not in cfg.joints.clearance_joints:
            assert f"pen_{j}" not in run.channels
            continue
        K = _eq18(cfg.joints.pin_radius(j), cfg.joints.radial_m(j), mat.pin_of(j), mat.bushing_of(j))
        assert run.meta["contact"][j]["stiffness"] == pytest.approx(K, rel=1e-12)
        closed = (np.linalg.norm(f) / K) ** (2 / 3)
        pen = run[f"pen_{j}"][-100:]                           # the last millisecond
        fn = run[f"fn_{j}"][-100:].astype(float)
        # 1e-3: what is left of the settling after 0.1 s (A: 2.8e-4 (y), 4.4e-5 (x) measured; the
        # tangential rocking of a journal at the bottom of a bore is undamped below the friction
        # law's v0), not a model error
        assert pen.mean() / closed - 1 == pytest.approx(0, abs=1e-3), (j, pen.mean() / closed - 1)
        assert fn.mean() / np.linalg.norm(f) - 1 == pytest.approx(0, abs=1e-3), j
        if j == "A":  # bench frame: the journal sits on the side its load pushes it to
            e = np.array([run["ecc_A_x"][-1], run["ecc_A_y"][-1]])
            assert np.linalg.norm(e) == pytest.approx(cfg.joints.radial_m("A") + pen[-1], rel=1e-9)
            assert e @ f / (np.linalg.norm(e) * np.linalg.norm(f)) > 0.999


# ---------------------------------------------------------------- kinematics, limit
def test_small_clearance_at_a_follows_the_exact_kinematics_and_the_ideal_limit():
    """Test 6's spin-up with a clearance at A only (B, C ideal). (1) With B and C exact the slider
    sits where the slider–crank with crank centre e_A puts it: x = e_x + r cos θ +
    sqrt(l² − (d_off − e_y − r sin θ)²), to round-off, so it differs from the ideal mechanism at
    the same θ by at most |e_A| / cos φ_max ≤ (c + δ_max)/cos φ_max. (2) As c → 0 the
    accelerations tend to the ideal run's (the journal stays loaded against the bore): the RMS
    difference of AC1–AC6 shrinks at least about linearly with c (×0.1 in c: ×0.05 measured)."""
    base = short(preset(6), 0.3, **{"drive.ramp_s": 0.1, "simulation.engine": "reference",
                                     "joints.clearance_c_mm": 0.0, "joints.allow_noncatalogue": True})
    ideal = simulate_run(base)
    r, l, d_off = base.bodies.crank.length_m, base.bodies.rod.length_m, base.mechanism.d_off_m
    rms = {}
    for cl in (0.02, 0.002):
        cfg = base.replace(**{"joints.clearance_a_mm": cl})
        run = simulate_run(cfg)
        c = cfg.joints.radial_m("A")
        th, ex, ey = run["crank_angle"], run["ecc_A_x"], run["ecc_A_y"]
        ecc = np.hypot(ex, ey)
        np.testing.assert_allclose(run["pen_A"], np.maximum(ecc - c, 0), atol=1e-15)
        assert run["fn_A"][5000:].min() > 0                     # loaded against the bore after 50 ms
        x_exact = ex + r * np.cos(th) + np.sqrt(l ** 2 - (d_off - ey - r * np.sin(th)) ** 2)
        assert np.max(np.abs(run["slider_position"] - x_exact)) < 1e-12
        cos_phi = math.sqrt(1 - ((r + abs(d_off) + c + run["pen_A"].max()) / l) ** 2)
        x_ideal = r * np.cos(th) + np.sqrt(l ** 2 - (d_off - r * np.sin(th)) ** 2)
        dev = np.abs(run["slider_position"] - x_ideal)
        assert dev.max() <= (c + run["pen_A"].max()) / cos_phi
        assert dev.max() > 0.5 * c                              # the clearance is really there
        k = slice(10000, None)                                  # after the first 0.1 s
        rms[cl] = np.array([np.sqrt(np.mean((run[a][k] - ideal[a][k]) ** 2)) for a in ACCELEROMETERS])
    ref = np.array([np.sqrt(np.mean(ideal[a][10000:] ** 2)) for a in ACCELEROMETERS])
    assert np.all(rms[0.002] <= 0.25 * rms[0.02]), rms
    assert np.all(rms[0.02] < 0.1 * ref), rms                 # regression guard: ≤ 0.06 × RMS measured


# ------------------------------------------------------------ constraints, round-off
def test_constraints_stay_at_round_off_with_a_clearance_at_every_joint():
    cfg = short(preset(12), 0.05, **{"joints.clearance_a_mm": 0.1})
    eng = ReferenceEngine(cfg)
    eng.reset()
    st = eng.state0.copy()
    h = cfg.simulation.timestep_s
    buf = np.empty((500, ref_model.N_OUT))
    th, om = DriveReference(cfg)(np.arange(5000) * h)
    moved = 0.0
    for k in range(10):
        sl = slice(500 * k, 500 * (k + 1))
        status, _ = ref_model.run_steps(eng.P, st, th[sl].copy(), om[sl].copy(), 1, buf, True)
        assert status == ref_model.OK
        q, qd = st[ref_model.S_Q:ref_model.S_Q + ref_model.N_Q], st[ref_model.S_QD:ref_model.S_QD + ref_model.N_Q]
        assert ref_model.constraint_norm(eng.P, q) <= 1e-12
        assert ref_model.velocity_constraint_norm(eng.P, q, qd) <= 1e-12
        assert math.hypot(q[8], q[9]) < 1.1 * cfg.joints.radial_m("A")
        moved = max(moved, float(np.ptp(buf[:, ref_model.O_JOINT_A])))
    assert moved > 1e-7        # the journal does move in its bore


# -------------------------------------------------------- contact forces: power
def _crank_point(q, q0, p0):
    """Bench position at q of the crank's material point that is at p0 at q0 (A' = q[8:10], θ = q[7])."""
    a = q[7] - q0[7]
    d = p0 - q0[8:10]
    return q[8:10] + np.array([math.cos(a) * d[0] - math.sin(a) * d[1], math.sin(a) * d[0] + math.cos(a) * d[1]])


def _rod_point(q, q0, p0):
    """The same for the rod (B' = q[2:4], direction C − B')."""
    ang = lambda x: math.atan2(x[5] - x[3], x[4] - x[2])  # noqa: E731
    a = ang(q) - ang(q0)
    d = p0 - q0[2:4]
    return q[2:4] + np.array([math.cos(a) * d[0] - math.sin(a) * d[1], math.sin(a) * d[0] + math.cos(a) * d[1]])


@pytest.mark.parametrize("theta", [0.4, 2.5, -1.9])
def test_contact_power_at_a_and_b_is_that_of_the_material_contact_points(theta):
    """Consistent (q, q̇ = R ż) with the journal pressed into the bore at A and the pin into the eye
    at B, with different pins (A: 30 mm, B: 15 mm): the generalized contact forces deliver the
    power F·(v_pin point − v_bushing point) summed over A and B, the velocities of the material
    points at the pins' and bushings' surfaces (centre + R n) taken by central differences of
    their positions (frame fixed, crank turning with θ, rod with its direction). A wrong radius in
    the friction's lever arm or sliding speed breaks it (friction carries ~10 % of the power)."""
    cfg = BenchConfig().replace(**{
        "joints.clearance_a_mm": 0.1, "joints.clearance_b_mm": 0.1, "joints.clearance_c_mm": 0.0,
        "joints.initial_eccentricity": "centred", "joints.pin_diameters_m": {"A": 0.03, "B": 0.015}})
    P = ref_model.build_params(cfg)
    st = natural.initial_state(cfg, theta)
    ref_model.contact_parameters(cfg, P, st)
    assert P[ref_model.P_RPIN_A] == 0.015 and P[ref_model.P_RPIN_B] == 0.0075
    q = st[:ref_model.N_Q].copy()
    nA, nB = np.array([math.cos(1.0), math.sin(1.0)]), np.array([math.cos(-2.0), math.sin(-2.0)])
    q[8:10] = (cfg.joints.radial_m("A") + 2e-6) * nA
    q[2:4] = q[0:2] - (cfg.joints.radial_m("B") + 1e-6) * nB
    assert ref_model.project(P, q, np.zeros(ref_model.N_Q), math.sin(q[7]), math.cos(q[7]),
                     np.zeros(ref_model.N_Q), np.zeros(ref_model.N_Q), np.zeros(ref_model.N_Q)) > 0
    R, S = np.zeros((ref_model.N_Q, ref_model.N_Z)), np.zeros(ref_model.N_Q)
    nz = natural.r_matrix(P, q, np.zeros(ref_model.N_Q), R, S)
    assert nz == 5
    qd = R[:, :nz] @ np.array([30.0, 0.02, -0.05, 0.03, 0.04])   # θ̇, ė_A, ė_B
    Q = np.zeros(ref_model.N_Q)
    jo = [np.zeros(5) for _ in range(3)]
    ref_model.generalized_forces(P, q, qd, 0.0, np.zeros(2), np.zeros(2), np.zeros(2), Q, *jo)
    P0 = P.copy()
    P0[ref_model.P_K_A] = P0[ref_model.P_K_B] = 0.0
    Q0 = np.zeros(ref_model.N_Q)
    ref_model.generalized_forces(P0, q, qd, 0.0, np.zeros(2), np.zeros(2), np.zeros(2), Q0, *[np.zeros(5) for _ in range(3)])
    power = (Q - Q0) @ qd
    eps = 1e-7
    expected = 0.0
    friction = 0.0
    for jout, pin_r, bush_r, on_rod in ((jo[0], 0.015, 0.015 + cfg.joints.radial_m("A"), False),
                                        (jo[1], 0.0075, 0.0075 + cfg.joints.radial_m("B"), True)):
        e = jout[:2]
        n = e / np.linalg.norm(e)
        t = np.array([-n[1], n[0]])
        fn, ft = jout[3], jout[4]
        assert fn > 10 and abs(ft) == pytest.approx(cfg.contact.mu0 * fn, rel=1e-12)   # sliding
        F = -fn * n + ft * t
        if on_rod:   # B: pin on the crank at B, bushing the rod eye at B'
            p_pin, p_bush = q[0:2] + pin_r * n, q[2:4] + bush_r * n
            v_bush = (_rod_point(q + eps * qd, q, p_bush) - _rod_point(q - eps * qd, q, p_bush)) / (2 * eps)
        else:        # A: journal on the crank at A', bushing the fixed frame's bore
            p_pin = q[8:10] + pin_r * n
            v_bush = np.zeros(2)
        v_pin = (_crank_point(q + eps * qd, q, p_pin) - _crank_point(q - eps * qd, q, p_pin)) / (2 * eps)
        expected += F @ (v_pin - v_bush)
        friction += ft * t @ (v_pin - v_bush)
    assert abs(friction) > 0.05 * abs(expected)
    assert power == pytest.approx(expected, rel=1e-7)


# ------------------------------------------------------------------ per-joint pins
def test_the_pin_of_an_ideal_joint_a_changes_nothing():
    """A ideal: its journal size is not part of the model; test 12 (B and C clearance) gives the
    same bits with a 50 mm journal at A."""
    cfg = short(preset(12), 0.05, **{"simulation.engine": "reference"})
    a = simulate_run(cfg)
    b = simulate_run(cfg.replace(**{"joints.pin_diameters_m": {"A": 0.05}}))
    assert a.channels.keys() == b.channels.keys()
    assert "ecc_A_x" not in a.channels
    for name in a.channels:
        assert np.array_equal(a[name], b[name]), name


def test_per_joint_pin_radius_sets_that_joints_stiffness_and_geometry():
    """A 15 mm pin at C (20 mm elsewhere): the engine's K at C is Eq. 18 with C's radii, B's is
    unchanged, and the bushing radius at C is the pin's plus the clearance."""
    base = short(preset(12), 0.01, **{"simulation.engine": "reference"})
    cfg = base.replace(**{"joints.pin_diameters_m": {"C": 0.015}})
    eng0, eng = ReferenceEngine(base), ReferenceEngine(cfg)
    eng0.reset()
    eng.reset()
    mat = cfg.materials
    c = cfg.joints.radial_m("C")
    k_c = _eq18(0.0075, c, mat.pin, mat.bushing)
    assert eng.contacts["C"].stiffness == pytest.approx(k_c, rel=1e-12)
    assert eng0.contacts["C"].stiffness == pytest.approx(_eq18(0.01, c, mat.pin, mat.bushing), rel=1e-12)
    assert eng.contacts["C"].stiffness < 0.99 * eng0.contacts["C"].stiffness
    assert eng.contacts["B"].stiffness == eng0.contacts["B"].stiffness
    assert eng.P[ref_model.P_RPIN_C] == 0.0075 and eng.P[ref_model.P_RBUSH_C] == pytest.approx(0.0075 + c, rel=1e-15)
    assert eng.P[ref_model.P_RPIN_B] == 0.01 and eng.P[ref_model.P_RBUSH_B] == pytest.approx(0.01 + cfg.joints.radial_m("B"), rel=1e-15)


def test_r_matrix_with_a_clearance_at_a_against_finite_differences():
    """Φ_q R = 0 for every constraint row and Ṙż = (dR/dt) ż, by central differences, with A, B and
    C all clearance joints (z = θ, e_A, e_B, e_C)."""
    cfg = BenchConfig().replace(**{"joints.clearance_a_mm": 0.1, "joints.clearance_b_mm": 0.1,
                                   "joints.clearance_c_mm": 0.1, "joints.initial_eccentricity": "centred"})
    P = ref_model.build_params(cfg)
    q = natural.initial_state(cfg, 1.1)[:ref_model.N_Q].copy()
    q[8:10] = [3e-5, -2e-5]
    q[2:4] = q[0:2] - np.array([1e-5, 4e-5])
    assert ref_model.project(P, q, np.zeros(ref_model.N_Q), math.sin(q[7]), math.cos(q[7]),
                     np.zeros(ref_model.N_Q), np.zeros(ref_model.N_Q), np.zeros(ref_model.N_Q)) > 0
    R, S = np.zeros((ref_model.N_Q, ref_model.N_Z)), np.zeros(ref_model.N_Q)
    assert natural.r_matrix(P, q, np.zeros(ref_model.N_Q), R, S) == 7
    zd = np.array([10.0, 0.05, -0.03, 0.02, 0.04, -0.01, 0.03])
    qd = R[:, :7] @ zd
    natural.r_matrix(P, q, qd, R, S)

    def phi(x):
        res = np.zeros(ref_model.N_Q)
        natural.residual(P, x, math.sin(x[7]), math.cos(x[7]), res)
        return res[:3]                 # rows 0–2: the only constraints here

    eps = 1e-6
    for j in range(7):
        d = (phi(q + eps * R[:, j]) - phi(q - eps * R[:, j])) / (2 * eps)
        assert np.max(np.abs(d)) < 1e-9, j
    assert np.allclose(R[8:10, 1:3], np.eye(2)) and np.allclose(R[8:10, [0, 3, 4, 5, 6]], 0)
    Rp, Rm = np.zeros((ref_model.N_Q, ref_model.N_Z)), np.zeros((ref_model.N_Q, ref_model.N_Z))
    natural.r_matrix(P, q + eps * qd, qd, Rp, np.zeros(ref_model.N_Q))
    natural.r_matrix(P, q - eps * qd, qd, Rm, np.zeros(ref_model.N_Q))
    np.testing.assert_allclose((Rp - Rm)[:, :7] / (2 * eps) @ zd, S, atol=1e-6 * max(1, np.abs(S).max()))
