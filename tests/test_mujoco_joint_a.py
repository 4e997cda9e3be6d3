"""A clearance at the ground pivot A in the MuJoCo twin, and per-joint pin and bushing sizes.

At A the pin is the crank's journal (``pin_A`` on the crank at its origin) and the bushing the
frame's bore (``bushing_A`` on the world body at the bench origin); two planar slides
(``ecc_A_x``, ``ecc_A_y``, bench frame) come before ``crank_hinge``, so the hinge angle stays the
absolute crank angle. Independent bases:

* statics: the journal resting in the bore carries the crank's weight and the rod's load on pin
  B (:func:`twin.kinematics.static_pin_forces`), F = −(m_crank g + F_B); the Lankarani–Nikravesh
  law at rest is F = K δⁿ with K written out from S003 Eq. 18 below, so δ = (F/K)^(1/n) and
  e_A = −(c + δ) F/|F|;
* kinematics: the slider–crank closure with the journal at e_A,
  x = e_x + r cos θ + sqrt(l² − (d_off − e_y − r sin θ)²), and its Lipschitz bound against the
  ideal mechanism, |Δx| ≤ (|e_A| + r |Δθ|)/cos φ_max;
* the contact law and friction step by step, written out (LN law, regularized Coulomb law on
  the law's force, against the relative velocity of the journal's surface and the still frame,
  from MuJoCo's Jacobians), and the friction's generalized forces on the crank's three dofs;
* the prescribed drive: the crank angle is the program (dead-beat law) although the journal
  moves in the bore;
* per-joint sizes: the configured radii and half lengths, K from Eq. 18 per joint.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from twin import names
from twin.config import BenchConfig, ln_stiffness, preset
from twin.drive import DriveReference
from twin.kinematics import static_pin_forces
from twin.mujoco_engine.builder import build, export_xml
from twin.mujoco_engine.engine import MujocoEngine
from twin.simulation import simulate_run

from conftest import bore_bias_acceleration, short

#: one encoder count (the bench's 32768-count quadrature encoder) [rad]
COUNT = 2 * math.pi / 32768


def a_only(clearance_a_mm: float = 0.1, **overrides) -> BenchConfig:
    """The default bench with its only clearance at A."""
    return BenchConfig().replace(**{"joints.clearance_c_mm": 0.0, "joints.clearance_b_mm": 0.0,
                                    "joints.clearance_a_mm": clearance_a_mm, **overrides})


def eq18(cfg: BenchConfig, joint: str) -> float:
    """S003 Eq. 18 written out: K = 4/(3 (h_i + h_j)) sqrt(R_i R_j/(R_i − R_j)), h = (1 − ν²)/E."""
    j, mat = cfg.joints, cfg.materials
    rj = j.pin_diameter(joint) / 2
    ri = rj + j.diametral_mm(joint) * 1e-3 / 2
    h = sum((1 - m.poisson ** 2) / m.youngs_modulus_pa for m in (mat.pin_of(joint), mat.bushing_of(joint)))
    return 4 / (3 * h) * math.sqrt(ri * rj / (ri - rj))


def _id(model: mujoco.MjModel, kind: str, name: str) -> int:
    return getattr(model, kind)(name).id


# ------------------------------------------------------------------------------------ names
def test_every_new_name_resolves_in_an_a_clearance_model():
    m = build(a_only().replace(**{"joints.clearance_b_mm": 0.1, "joints.clearance_c_mm": 0.1}))[1]
    for j in (names.ECC_A_X, names.ECC_A_Y, names.CRANK_HINGE):
        assert m.jnt_bodyid[_id(m, "joint", j)] == _id(m, "body", names.CRANK)
    # the slides come first (translate, then rotate): the hinge is the absolute crank angle
    assert _id(m, "joint", names.ECC_A_X) < _id(m, "joint", names.ECC_A_Y) < _id(m, "joint", names.CRANK_HINGE)
    assert [m.jnt_type[_id(m, "joint", j)] for j in (names.ECC_A_X, names.ECC_A_Y, names.CRANK_HINGE)] == [
        mujoco.mjtJoint.mjJNT_SLIDE, mujoco.mjtJoint.mjJNT_SLIDE, mujoco.mjtJoint.mjJNT_HINGE]
    assert m.actuator_trnid[_id(m, "actuator", names.CRANK_PID), 0] == _id(m, "joint", names.CRANK_HINGE)
    assert m.sensor_objid[_id(m, "sensor", names.SENSOR_CRANK_ANGLE)] == _id(m, "joint", names.CRANK_HINGE)
    assert m.geom_bodyid[_id(m, "geom", names.pin("A"))] == _id(m, "body", names.CRANK)
    assert m.geom_bodyid[_id(m, "geom", names.bushing("A"))] == 0  # the frame: the world body
    assert m.geom_bodyid[_id(m, "geom", names.bushing_ring("A"))] == 0
    assert m.site_bodyid[_id(m, "site", names.pin("A"))] == _id(m, "body", names.CRANK)
    assert m.site_bodyid[_id(m, "site", names.bushing("A"))] == 0
    _id(m, "pair", names.pair("A"))
    for s in (names.sensor_ecc("A"), names.sensor_contact("A"), names.sensor_friction("A")):
        _id(m, "sensor", s)
    assert m.geom_user[_id(m, "geom", names.bushing("A")), 0] == names.BORE_MAGIC
    # one impact-speed slot per clearance joint, in the order A, B, C
    assert m.nuserdata == 3
    assert [names.read_bore_userdata(m.geom_user[_id(m, "geom", names.bushing(j))])["slot"] for j in "ABC"] == [0, 1, 2]
    # an ideal A keeps the base model's crank hinge alone: no slides, pair or A sensors
    ideal = build(preset(12))[1]
    for kind, name in (("joint", names.ECC_A_X), ("joint", names.ECC_A_Y), ("pair", names.pair("A")),
                       ("sensor", names.sensor_ecc("A")), ("sensor", names.sensor_contact("A")),
                       ("sensor", names.sensor_friction("A"))):
        with pytest.raises(KeyError):
            _id(ideal, kind, name)
    for kind, name in (("geom", names.pin("A")), ("geom", names.bushing("A")), ("site", names.pin("A")), ("site", names.bushing("A"))):
        _id(ideal, kind, name)


def test_exported_a_clearance_variant_compiles_to_the_same_model():
    cfg = a_only()
    xml = export_xml(cfg)
    m = mujoco.MjModel.from_xml_string(xml)
    # the export keeps MuJoCo's accelerometer sensors (a plain MuJoCo has no posthoc path)
    ref = build(cfg.replace(**{"mujoco.accelerometers": "sensor"}))[1]
    assert (m.nq, m.nv, m.nu, m.npair, m.nsensor) == (ref.nq, ref.nv, ref.nu, ref.npair, ref.nsensor) == (5, 5, 2, 1, 13)
    np.testing.assert_allclose(m.geom_size, ref.geom_size)
    assert m.joint(names.ECC_A_X).id < m.joint(names.CRANK_HINGE).id
    # the bores' user data exactly (MuJoCo's writer alone zeroes μ0, v0, v1 and the speed floor
    # beside K ~ 1e11), and the impact-speed slots
    assert np.array_equal(m.geom_user, ref.geom_user) and m.nuserdata == ref.nuserdata == 1
    assert names.read_bore_userdata(m.geom_user[m.geom(names.bushing("A")).id])["mu0"] == cfg.contact.mu0


# ------------------------------------------------------------------------- per-joint sizes
def test_each_joint_has_its_own_pin_and_bushing():
    steel = {"youngs_modulus_pa": 200e9, "poisson": 0.29, "density_kgm3": 7800.0}
    cfg = a_only(0.1, **{"joints.clearance_b_mm": 0.05, "joints.clearance_c_mm": 0.5,
                         "joints.pin_diameters_m": {"A": 0.030, "B": 0.016},
                         "joints.bushing_lengths_m": {"A": 0.050, "C": 0.024},
                         "materials.pins": {"B": steel}, "materials.bushings": {"A": steel}})
    m = build(cfg)[1]
    sizes = {"A": (0.015, 0.025), "B": (0.008, 0.010), "C": (0.010, 0.012)}  # (R_j, L/2) as configured
    for j, (rj, half) in sizes.items():
        c = cfg.joints.diametral_mm(j) * 1e-3 / 2
        assert m.geom_size[_id(m, "geom", names.pin(j)), :2] == pytest.approx([rj, half], rel=1e-15)
        assert m.geom_size[_id(m, "geom", names.bushing(j)), :2] == pytest.approx([rj + c, half], rel=1e-15)
        user = names.read_bore_userdata(m.geom_user[_id(m, "geom", names.bushing(j))])
        assert user["stiffness"] == pytest.approx(eq18(cfg, j), rel=1e-12)
        assert user["stiffness"] == pytest.approx(ln_stiffness(cfg.joints, cfg.materials, j), rel=1e-15)
    # the three joints do differ (materials and sizes reach K)
    assert len({round(eq18(cfg, j)) for j in "ABC"}) == 3
    # an ideal joint's pin and (closed) bushing take its own size too
    m2 = build(cfg.replace(**{"joints.clearance_b_mm": 0.0}))[1]
    for g in (names.pin("B"), names.bushing("B")):
        assert m2.geom_size[_id(m2, "geom", g), :2] == pytest.approx([0.008, 0.010], rel=1e-15)


# -------------------------------------------------------------------------------- statics
@pytest.mark.parametrize("orientation, encoder", [("y", 0.3), ("x", 0.3), ("x", 2.0)])
def test_journal_rests_on_the_bore_under_its_static_load(orientation, encoder):
    """Crank held by the drive (0 rpm): the journal sinks into the bore along the static load
    F = −(m_crank g + F_B) by δ = (F/K)^(1/n). Residuals: F_B from the ideal geometry (the
    journal's offset c + δ changes the rod angle by ~c/l = 1e-4), and a swing of the journal
    along the bore wall (below v0, where the regularized friction is zero, nothing damps it;
    ≤ 2 % of c peak to peak) that the 0.2 s mean averages out."""
    cfg = a_only(0.1, **{"mechanism.orientation": orientation, "drive.motor_rpm": 0.0,
                         "drive.initial_encoder_angle_rad": encoder, "simulation.duration_s": 0.5})
    run = simulate_run(cfg)
    last = slice(-20_000, None)
    theta = float(run["crank_angle"][last].mean())
    f_b, _ = static_pin_forces(cfg, theta)
    g = np.asarray(cfg.mechanism.gravity_vector[:2])
    F = -(cfg.bodies.crank.mass_kg * g + f_b)          # force of the frame on the journal
    Fn = float(np.linalg.norm(F))
    n = cfg.contact.exponent
    delta = (Fn / eq18(cfg, "A")) ** (1 / n)
    c = cfg.joints.radial_m("A")
    assert 0.3e-6 < delta < 3e-6  # a Hertzian sink of a micrometre: the check is not vacuous
    assert run["pen_A"][last].mean() == pytest.approx(delta, rel=1e-3)
    assert run["fn_A"][last].mean() == pytest.approx(Fn, rel=1e-3)
    e = np.array([run["ecc_A_x"][last].mean(), run["ecc_A_y"][last].mean()])
    np.testing.assert_allclose(e, -(c + delta) * F / Fn, rtol=0, atol=1e-3 * c)  # bench frame
    # at rest: slower than v0 everywhere, so the regularized Coulomb friction is exactly zero
    speed = np.hypot(np.diff(run["ecc_A_x"][last]), np.diff(run["ecc_A_y"][last])) * cfg.output_rate_hz
    assert speed.max() < cfg.contact.v0_mps
    assert np.all(run["ft_A"][last] == 0.0)
    assert np.ptp(run["crank_angle"][last]) < COUNT  # the drive holds the crank


# ----------------------------------------------------------------------------- kinematics
def test_small_clearance_at_a_moves_the_slider_by_the_kinematic_bound():
    """Test 6's drive with only A at 0.02 mm (c = 10 µm): the slider obeys the closed form with the
    journal at e_A, stays within (|e_A| + r |Δθ|)/cos φ_max of the ideal run, and the crank follows
    the same program (within one encoder count of it and of the ideal run)."""
    base = short(preset(6), 0.45, **{"joints.clearance_c_mm": 0.0})
    ideal = simulate_run(base)
    cfg = base.replace(**{"joints.clearance_a_mm": 0.02})
    run = simulate_run(cfg)
    r, l, d_off = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m, cfg.mechanism.d_off_m
    c = cfg.joints.radial_m("A")
    th, ex, ey, x = run["crank_angle"], run["ecc_A_x"], run["ecc_A_y"], run["slider_position"]
    assert th[-1] - th[0] > 2 * math.pi  # more than a turn
    ecc = np.hypot(ex, ey)
    assert ecc.max() > 0.99 * c and np.all(run["pen_A"] == np.maximum(ecc - c, 0.0))
    # closure with the journal at e_A (the ideal joint C is a stiff connect: 1e-7 m, as the
    # ideal mechanism's closed-form test)
    closed = ex + r * np.cos(th) + np.sqrt(l ** 2 - (d_off - ey - r * np.sin(th)) ** 2)
    assert np.abs(x - closed).max() < 1e-7
    # against the ideal run: |∂x/∂e| = 1/cos φ, |∂x/∂θ| <= r/cos φ
    cos_phi = math.sqrt(1 - ((r + abs(d_off) + ecc.max()) / l) ** 2)
    dth = np.abs(th - ideal["crank_angle"])
    bound = (ecc.max() + r * dth.max()) / cos_phi + 2e-7
    dx = np.abs(x - ideal["slider_position"])
    assert dx.max() <= bound
    assert dx.max() > 0.5 * c  # the clearance does show
    assert dth.max() < COUNT
    assert np.abs(th - run["theta_ref"]).max() < COUNT
    assert np.array_equal(run["theta_ref"], ideal["theta_ref"])


def test_prescribed_crank_is_the_program_while_the_journal_moves():
    cfg = a_only(0.1, **{"drive.mode": "prescribed", "drive.crank_rpm": 300.0, "drive.ramp_s": 0.0,
                         "simulation.duration_s": 0.1})
    run = simulate_run(cfg)
    theta, _ = DriveReference(cfg)(run.time)
    assert np.abs(run["crank_angle"] - theta).max() < 1e-12
    assert np.ptp(run["ecc_A_x"]) > 0.5 * cfg.joints.radial_m("A")  # the journal does travel
    assert run["fn_A"].max() > 0


# -------------------------------------------------------------------- contact law, friction
def test_contact_law_and_friction_at_the_frame_bore_step_by_step():
    """Every step with a contact at A: the solver's normal force is the LN law at the step's
    state plus the θ-part of its damping and, where θ > ½, c h (θ − ½) b (as at B and C; b = −J̇q̇
    of the row, MuJoCo's mj_jacDot); the friction on the journal is the regularized Coulomb law on
    the law's force at the step's secant rate, F − c h b/2, against the slip of the journal's
    surface on the still frame (MuJoCo's Jacobians: crank spin × contact radius plus the
    journal's own motion);
    and its generalized forces are the crank's only passive forces: along the slides ft t and
    about the hinge the moment of ft t at the contact point."""
    cfg = short(preset(6), 0.2, **{"joints.clearance_c_mm": 0.0, "joints.clearance_a_mm": 0.1,
                                   "drive.ramp_s": 0.02})
    eng = MujocoEngine(cfg)
    m, d = eng.model, eng.data
    eng.reset()
    ref = DriveReference(cfg)
    h = cfg.simulation.timestep_s
    law = eng.info.contacts["A"].law
    chi = 3 * (1 - cfg.contact.restitution ** 2) / 4
    assert (law.stiffness, law.exponent, law.damping) == pytest.approx((eq18(cfg, "A"), 1.5, chi), rel=1e-12)
    mu0, v0, v1 = cfg.contact.mu0, cfg.contact.v0_mps, cfg.contact.v1_mps
    dofs = [m.jnt_dofadr[m.joint(j).id] for j in (names.ECC_A_X, names.ECC_A_Y, names.CRANK_HINGE)]
    other = [i for i in range(m.nv) if i not in dofs and i != m.jnt_dofadr[m.joint(names.SLIDER_SLIDE).id]]
    crank = m.body(names.CRANK).id
    pin, bore = m.geom(names.pin("A")).id, m.geom(names.bushing("A")).id
    fsens = eng._sensor_slices[names.sensor_friction("A")].start
    checked, sliding, errs = 0, 0, []
    for _ in range(15_000):
        th, om = ref(np.array([d.time]))
        d.ctrl[:] = [th[0], om[0]]
        mujoco.mj_step(m, d)  # efc_*, kinematics, qfrc_passive, sensors: the step's start
        assert d.ncon <= 1
        if d.ncon == 0:
            assert d.sensordata[fsens] == 0.0 and not d.qfrc_passive[dofs].any()
            continue
        con = d.contact[0]
        assert sorted(con.geom) == sorted((pin, bore))
        a = con.efc_address
        delta, rate, v_imp = -d.efc_pos[a], -d.efc_vel[a], d.userdata[0]
        if delta <= 0:
            continue
        F = max(law.stiffness * delta ** 1.5 * (1 + chi * max(rate / v_imp, -1.0)), 0.0)
        cdamp = 0.0 if rate < -v_imp else chi * law.stiffness * delta ** 1.5 / v_imp
        theta = 1 - 1 / (d.efc_diagA[a] * cdamp * h) if cdamp * h * d.efc_diagA[a] > 2 else 0.5
        gamma = theta * cdamp * h
        r0 = d.efc_diagA[a] * (1 - 1e-4) / 1e-4
        R = 1 / gamma if gamma * r0 > 1 else r0
        acc = -float(d.efc_J[a * m.nv:(a + 1) * m.nv] @ d.qacc)
        qvel0 = d.qvel - h * d.qacc  # the step's start (semi-implicit Euler)
        b = bore_bias_acceleration(m, d, pin, bore, qvel0) if cdamp > 0 else 0.0
        if F > 1.0:
            errs.append(d.efc_force[a] / max(F + acc / R + cdamp * h * (theta - 0.5) * b, 0.0) - 1)
        # friction: slip of the journal's surface on the frame at the contact point
        jp, jw = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        mujoco.mj_jac(m, d, jp, None, con.pos, crank)
        mujoco.mj_jac(m, d, jw, None, con.pos, 0)
        assert not jw.any()  # the frame does not move
        e = d.geom_xpos[pin] - d.geom_xpos[bore]
        t = np.cross([0, 0, 1], e / np.linalg.norm(e))  # ẑ × n, n from the bore centre to the journal
        vt = float(jp @ qvel0 @ t)
        s = abs(vt)
        mu = mu0 if s >= v1 else (mu0 * (s - v0) / (v1 - v0) if s > v0 else 0.0)
        fn = max(F - cdamp * h * b / 2, 0.0)  # the law on the step's secant rate
        ft = -math.copysign(mu * fn, vt) if mu else 0.0
        assert d.sensordata[fsens] == pytest.approx(ft, rel=1e-9, abs=1e-9 * (1 + F))
        arm = con.pos - d.xpos[crank]
        expected = [ft * t[0], ft * t[1], ft * (arm[0] * t[1] - arm[1] * t[0])]
        np.testing.assert_allclose(d.qfrc_passive[dofs], expected, rtol=1e-9, atol=1e-9 * (1 + F))
        assert not d.qfrc_passive[other].any()
        if F > 1.0:
            checked += 1
            sliding += mu == mu0
    assert checked > 5000 and sliding > 1000
    assert np.abs(errs).max() < 1e-9
