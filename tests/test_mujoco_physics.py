"""Physics of the MuJoCo twin: closed-form kinematics, the calibration pose, the clearance
bound, the exact bore geometry and the contact and friction laws."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from twin import names
from twin.config import BenchConfig, preset
from twin.drive import DriveReference
from twin.kinematics import slider_position
from twin.mujoco_engine.builder import build
from twin.mujoco_engine.engine import MujocoEngine
from twin.simulation import simulate_run

from conftest import bore_bias_acceleration, short

G = 9.81


@pytest.mark.parametrize("d_off", [0.0, 0.02])
def test_ideal_slider_follows_closed_form_over_a_turn(d_off):
    cfg = short(preset(3), 0.7, **{"drive.ramp_s": 0.2, "mechanism.d_off_m": d_off})
    run = simulate_run(cfg)
    th = run["crank_angle"]
    assert th.max() - th.min() > 2 * math.pi  # more than a full turn
    closed = slider_position(th, 0.12, 0.60, d_off)
    # the loop closure at C is a stiff soft constraint: sub-micrometre agreement
    assert np.max(np.abs(run["slider_position"] - closed)) < 1e-7


# rod horizontal at rest (crank along +x): BENCH.md calibration pose, for each vertical axis
@pytest.mark.parametrize("orientation, expected_g", [
    ("y", {"AC1": 0, "AC2": 1, "AC3": 1, "AC4": 0, "AC5": 1, "AC6": 0}),
    ("x", {"AC1": 1, "AC2": 0, "AC3": 0, "AC4": 1, "AC5": 0, "AC6": 1}),
    ("z", {"AC1": 0, "AC2": 0, "AC3": 0, "AC4": 0, "AC5": 0, "AC6": 0}),
])
def test_calibration_pose_readings(orientation, expected_g):
    cfg = BenchConfig().replace(**{
        "joints.clearance_c_mm": 0.0, "drive.motor_rpm": 0.0, "mechanism.orientation": orientation,
        "drive.initial_encoder_angle_rad": math.pi / 2,  # encoder zero is -y: +π/2 puts the crank on +x
        "simulation.duration_s": 0.05})
    run = simulate_run(cfg)
    for a, g in expected_g.items():
        assert run[a][-500:].mean() / G == pytest.approx(g, abs=1e-4), a


def test_clearance_eccentricity_bounded_by_radial_clearance():
    cfg = short(preset(12), 0.4)
    run = simulate_run(cfg)
    for j in ("B", "C"):
        c = cfg.joints.radial_m(j)
        ecc = np.hypot(run[f"ecc_{j}_x"], run[f"ecc_{j}_y"])
        assert ecc.max() > 0.99 * c          # the journal does reach the bushing
        # and penetrates it by a few percent of c: the reference's Hertzian law, which the twin
        # applies, lets the pin sink ~2.6 um into the 50 um clearance at C under ~650 N
        assert ecc.max() < 1.08 * c
        assert np.max(run[f"pen_{j}"]) == pytest.approx(max(ecc.max() - c, 0), abs=1e-12)
        assert run[f"fn_{j}"].max() > 0


def test_bore_collider_is_an_exact_circle():
    cfg = preset(6)
    _, model, _ = build(cfg)
    model.pair_margin[:] = 1e-3
    d = mujoco.MjData(model)
    c = cfg.joints.radial_m("C")
    pin = model.geom(names.pin("C")).id
    model.geom_sameframe[pin] = 0  # geom_pos is edited below: do not reuse the body frame
    slide = model.jnt_qposadr[model.joint(names.SLIDER_SLIDE).id]
    x_bush = cfg.bodies.crank.length_m + cfg.bodies.rod.length_m   # all joint angles 0
    rng = np.random.default_rng(1)
    for alpha, rho in zip(rng.uniform(0, 2 * np.pi, 200), rng.uniform(0.2, 1.3, 200)):
        mujoco.mj_resetData(model, d)
        d.qpos[slide] = x_bush + rho * c * math.cos(alpha)
        model.geom_pos[pin, 1] = rho * c * math.sin(alpha)
        mujoco.mj_forward(model, d)
        con = [d.contact[i] for i in range(d.ncon)]
        assert len(con) == 1
        assert con[0].dist == pytest.approx(c * (1 - rho), abs=1e-15)
        # MuJoCo's convention: the normal points from contact geom[0] to geom[1]; from the
        # pin towards the bushing material it is along e, outwards
        sign = 1.0 if con[0].geom[0] == pin else -1.0
        assert np.allclose(con[0].frame[:3], sign * np.array([math.cos(alpha), math.sin(alpha), 0]), atol=1e-9)


def test_soft_first_guess_is_the_linear_law_and_friction_is_regularized_coulomb():
    # MuJoCo's own soft contact, the first guess: one linear term with a flat impedance,
    # f = k δ + c δ̇ exactly (the native law is tested below)
    cfg = short(preset(12), 0.2, **{"drive.ramp_s": 0.02, "mujoco.contact_source": "first-guess"})
    eng = MujocoEngine(cfg)
    m, d = eng.model, eng.data
    eng.reset()
    ref = DriveReference(cfg)
    law = eng.info.contacts
    sens = eng._sensor_slices
    ratio, mu, sign = [], [], []
    for _ in range(8000):
        th, om = ref(np.array([d.time]))
        d.ctrl[:] = [th[0], om[0]]
        mujoco.mj_step(m, d)
        for ci in range(d.ncon):
            con = d.contact[ci]
            j = m.geom(con.geom[0]).name[-1]
            a = con.efc_address
            lin = law[j].stiffness_n_per_m * -d.efc_pos[a] + law[j].damping_ns_per_m * -d.efc_vel[a]
            if lin < 5:
                continue
            ratio.append(d.efc_force[a] / lin)
            jp, jb = np.zeros((3, m.nv)), np.zeros((3, m.nv))
            mujoco.mj_jac(m, d, jp, None, con.pos, m.geom_bodyid[con.geom[0]])
            mujoco.mj_jac(m, d, jb, None, con.pos, m.geom_bodyid[con.geom[1]])
            vt = ((jp - jb) @ d.qvel) @ np.cross([0, 0, 1], con.frame[:3])
            ft = d.sensordata[sens[names.sensor_friction(j)].start]
            if abs(vt) > 2 * cfg.contact.v1_mps:
                mu.append(abs(ft) / d.efc_force[a])
                sign.append(np.sign(ft * vt))
    assert len(ratio) > 1000 and len(mu) > 1000
    assert np.median(ratio) == pytest.approx(1.0, abs=2e-3)
    assert np.max(np.abs(np.array(ratio) - 1)) < 0.02
    assert np.median(mu) == pytest.approx(cfg.contact.mu0, rel=2e-3)
    assert np.all(np.array(sign) == -1)  # friction on the pin opposes its slip


def test_first_guess_contact_reproduces_reference_restitution():
    from twin.impact import hysteresis_restitution, impact_linear

    cfg = preset(12).replace(**{"mujoco.contact_source": "first-guess"})
    eng = MujocoEngine(cfg)
    for j, s in eng.info.contacts.items():
        assert s.source == "first-guess"
        r = impact_linear(s.stiffness_n_per_m, s.damping_ns_per_m, 1 / eng.info.a_hat[j], 0.1)
        assert r.restitution == pytest.approx(hysteresis_restitution("lankarani-nikravesh", 0.4), abs=0.02)


@pytest.mark.parametrize("orientation", ["x", "y"])
def test_static_pin_forces_balance_rod_and_slider(orientation):
    from twin.kinematics import rod_angle, static_pin_forces
    cfg = BenchConfig().replace(**{"mechanism.orientation": orientation, "mechanism.d_off_m": 0.02})
    b = cfg.bodies
    g = np.asarray(cfg.mechanism.gravity_vector[:2])
    r, l, xg = b.crank.length_m, b.rod.length_m, b.rod.x_g_m
    for theta in np.linspace(0, 2 * math.pi, 7):
        f_b, f_c = static_pin_forces(cfg, theta)     # forces of the rod eyes on the pins
        phi = float(rod_angle(theta, r, l, cfg.mechanism.d_off_m))
        u = np.array([math.cos(phi), math.sin(phi)])
        cross = lambda a, f: a[0] * f[1] - a[1] * f[0]  # noqa: E731
        # rod: its weight and the pins' reactions (−F_B, −F_C) balance in force and moment about B
        assert np.allclose(b.rod.mass_kg * g - f_b - f_c, 0, atol=1e-9)
        assert cross(xg * u, b.rod.mass_kg * g) + cross(l * u, -f_c) == pytest.approx(0, abs=1e-9)
        # slider: the guide reacts across it only, so the rod carries the weight along the guide
        assert (b.slider.mass_kg * g + f_c)[0] == pytest.approx(0, abs=1e-9)


@pytest.mark.parametrize("engine", ["mujoco", "reference"])
@pytest.mark.parametrize("orientation", ["x", "y"])
def test_loaded_start_is_at_rest(engine, orientation):
    """The "loaded" start puts each pin where its static load holds it: a crank held still
    leaves both journals where they started (a wrong side would drop the pin across 2c)."""
    cfg = BenchConfig().replace(**{
        "joints.clearance_b_mm": 0.5, "joints.clearance_c_mm": 0.5, "drive.motor_rpm": 0.0,
        "mechanism.orientation": orientation, "drive.initial_encoder_angle_rad": 2.2,
        "simulation.engine": engine, "sensors.channels": ["crank", "joints"],
        "simulation.duration_s": 0.03})
    run = simulate_run(cfg)
    for j in ("B", "C"):
        c = cfg.joints.radial_m(j)
        e = np.stack([run[f"ecc_{j}_x"], run[f"ecc_{j}_y"]], axis=1)
        assert np.linalg.norm(e[0]) > 0.99 * c, j   # starts touching
        assert np.max(np.linalg.norm(e - e[0], axis=1)) < 0.05 * c, (j, np.max(np.linalg.norm(e - e[0], axis=1)) / c)


def _law_force(cfg, law, delta, rate, v_imp):
    """The law's force before the contact's max(·, 0) (the native module applies max(·, 0) to the
    whole θ-blended force, decided by the solver); where positive, the reference engine's own law
    function (twin.physics.contact) gives the same value."""
    from twin.impact import DAMPING_FACTOR
    from twin.physics.contact import LAW_CODES, normal_force

    if cfg.contact.law == "linear":
        raw = law.stiffness * delta + law.damping * rate
    else:
        chi = DAMPING_FACTOR[cfg.contact.law](cfg.contact.restitution)
        raw = law.stiffness * delta ** cfg.contact.exponent * (1 + chi * max(rate / v_imp, -1.0))
    ref = normal_force(LAW_CODES[cfg.contact.law], delta, rate, v_imp, law.stiffness, law.exponent,
                       cfg.contact.restitution, law.damping)
    assert ref == pytest.approx(max(raw, 0.0), rel=1e-12, abs=1e-12)
    return raw


def _theta(c, h, a_diag):
    """The native module's θ of the damping (trapezoidal up to c h = 2 m̂)."""
    ch = c * h
    return 1 - 1 / (a_diag * ch) if ch * a_diag > 2 else 0.5


@pytest.mark.parametrize("law", ["lankarani-nikravesh", "hunt-crossley", "flores", "linear"])
def test_contact_force_in_the_mechanism_is_the_reference_law(law):
    """Test 12 (B and C), stepped by MuJoCo: at every step with contact the solver's normal force
    is the reference law at the step's state plus the θ-part of its damping taken at the step's
    end, f = F(δ, δ̇) + θ c h δ̈ + c h (θ − ½) b (F from the reference engine's own law functions,
    c = ∂F/∂δ̇, δ̈ = −J q̈ the row's acceleration and b = −J̇ q̇ the rest of the penetration's, by
    MuJoCo's mj_jacDot: the law on the step's secant rate, nothing at θ = ½; where θ c h is below
    MuJoCo's own 1/R0 = 1e-4 m̂ of the pair, δ̈/R0 instead), the stored impact speed is the
    approach speed of the contact event (floored), and the friction on the pin is the regularized
    Coulomb law on F(δ, δ̇ − h b/2) = F − c h b/2, the law at the step's secant rate."""
    cfg = short(preset(12), 0.25, **{"drive.ramp_s": 0.02, "contact.law": law})
    eng = MujocoEngine(cfg)
    m, d = eng.model, eng.data
    eng.reset()
    ref = DriveReference(cfg)
    h = cfg.simulation.timestep_s
    sens = eng._sensor_slices
    slot = {j: int(names.read_bore_userdata(m.geom_user[m.geom(names.bushing(j)).id])["slot"]) for j in "BC"}
    prev_in = {"B": True, "C": True}  # the loaded start begins in contact
    checked, events, mu, errs = 0, 0, [], []
    for _ in range(20_000):
        th, om = ref(np.array([d.time]))
        d.ctrl[:] = [th[0], om[0]]
        mujoco.mj_step(m, d)  # efc_* and userdata: the state the step started from
        seen = set()
        for ci in range(d.ncon):
            con = d.contact[ci]
            j = m.geom(con.geom[1]).name[-1]
            seen.add(j)
            a = con.efc_address
            law_j = eng.info.contacts[j].law
            delta, rate = -d.efc_pos[a], -d.efc_vel[a]
            v_imp = d.userdata[slot[j]]
            if not prev_in[j]:  # a new contact event stores its approach speed
                assert v_imp == pytest.approx(max(rate, cfg.contact.impact_speed_floor_mps), rel=1e-9)
                events += 1
            F = _law_force(cfg, law_j, delta, rate, v_imp)
            if law_j.law == "linear":
                c = law_j.damping
            else:
                c = 0.0 if rate < -v_imp else law_j.damping * law_j.stiffness * delta ** law_j.exponent / v_imp
            J = d.efc_J[a * m.nv:(a + 1) * m.nv]
            acc = -float(J @ d.qacc)  # δ̈
            # the row's regularizer: 1/(θ c h), or MuJoCo's own R0 of the pair's impedance 1e-4
            r0 = d.efc_diagA[a] * (1 - 1e-4) / 1e-4
            theta = _theta(c, h, d.efc_diagA[a])
            gamma = theta * c * h
            r = 1 / gamma if gamma * r0 > 1 else r0
            assert d.efc_R[a] == pytest.approx(r, rel=1e-9)
            pin_g, bore_g = (con.geom[0], con.geom[1]) if m.geom(con.geom[1]).name == names.bushing(j) \
                else (con.geom[1], con.geom[0])
            b = bore_bias_acceleration(m, d, pin_g, bore_g, d.qvel - h * d.qacc) if c > 0 else 0.0
            expected = max(F + acc / r + c * h * (theta - 0.5) * b, 0.0)
            if expected > 1.0:
                errs.append(d.efc_force[a] / expected - 1)
                checked += 1
            # friction: regularized Coulomb on the law's force at the step's state
            jp, jb = np.zeros((3, m.nv)), np.zeros((3, m.nv))
            mujoco.mj_jac(m, d, jp, None, con.pos, m.geom_bodyid[con.geom[0]])
            mujoco.mj_jac(m, d, jb, None, con.pos, m.geom_bodyid[con.geom[1]])
            # the state moved on: d.qvel is the step's end; the friction sensor is from its start,
            # so compare magnitudes only where sliding is fast (|v_t| well above v1 either way)
            vt = ((jp - jb) @ d.qvel) @ np.cross([0, 0, 1], con.frame[:3])
            ft = d.sensordata[sens[names.sensor_friction(j)].start]
            fn = F - c * h * b / 2
            if abs(vt) > 20 * cfg.contact.v1_mps and fn > 1.0:
                mu.append(abs(ft) / fn)
        for j in "BC":
            prev_in[j] = j in seen
    assert checked > 1000 and events > 0
    errs = np.abs(errs)
    assert errs.max() < 1e-9, errs.max()
    assert len(mu) > 200 and np.median(mu) == pytest.approx(cfg.contact.mu0, rel=1e-6)


def test_native_law_event_state_in_the_probe():
    """The stored impact speed: taken when the contact event starts (its approach speed, or the
    floor), kept while it lasts, forgotten when the pin leaves the wall, left in mjData.userdata
    by rollout (it is not part of mjSTATE_FULLPHYSICS: the engine's data object carries it across
    chunks); δ̇/v_imp clamped at −1 while separating."""
    from mujoco import rollout

    from twin.studies.contact_check import probe_model

    cfg = BenchConfig().replace(**{"joints.clearance_c_mm": 0.1})
    c = cfg.joints.radial_m("C")
    model = probe_model(cfg, "C", 1.3)
    law = build(cfg)[2].contacts["C"].law
    floor = cfg.contact.impact_speed_floor_mps

    def forward(delta, rate, v_imp=0.0):
        d = mujoco.MjData(model)
        d.qpos[0], d.qvel[0] = c + delta, rate   # the probe's slide axis points into the wall
        d.userdata[0] = v_imp
        mujoco.mj_forward(model, d)
        return d

    delta = 2e-6
    for rate, v_imp in [(0.01, 0.02), (-0.005, 0.02), (-0.05, 0.02)]:
        d = forward(delta, rate, v_imp)
        assert d.userdata[0] == v_imp                       # an event under way keeps its speed
        F = law.force(delta, rate, v_imp)                   # clamped at δ̇/v_imp = −1 for the last
        cdamp = 0.0 if rate < -v_imp else law.damping * law.stiffness * delta ** 1.5 / v_imp
        acc = float(d.qacc[0])                              # δ̈ (the probe's axis is +δ)
        gamma = _theta(cdamp, model.opt.timestep, d.efc_diagA[0]) * cdamp * model.opt.timestep
        r0 = d.efc_diagA[0] * (1 - 1e-4) / 1e-4                        # the pair's own R
        r = 1 / gamma if gamma * r0 > 1 else r0                         # the θ-damping's, if larger
        assert d.efc_force[0] == pytest.approx(F + acc / r, rel=1e-9)
    assert law.force(delta, -0.05, 0.02) == pytest.approx(law.stiffness * delta ** 1.5 * (1 - law.damping))
    assert forward(delta, 0.004).userdata[0] == pytest.approx(0.004)   # a new event stores its speed
    assert forward(delta, 0.0002).userdata[0] == pytest.approx(floor)  # or the floor
    assert forward(-1e-6, 0.01, 0.02).userdata[0] == 0.0               # out of contact: no event
    d = forward(delta, 0.001, 0.02)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, d, state, spec)
    rollout.rollout(model, d, state[None], nstep=3)
    assert d.userdata[0] == 0.02


@pytest.mark.parametrize("bushing, friction, native", [("bore", "native", True), ("bore", "cone", True),
                                                      ("ring", "cone", False), ("tendon", "native", False)])
def test_native_law_is_set_where_the_bore_applies_it(bushing, friction, native):
    """The default contact: the bore bushing carries the reference law (K of Eq. 18, n, χ(e), the
    floor, a userdata slot) in its user data; ring and tendon bushings, which the native module
    does not serve, keep MuJoCo's soft first-guess contact (law 0, no slot)."""
    from twin.config import ln_stiffness
    from twin.impact import DAMPING_FACTOR

    cfg = preset(6).replace(**{"mujoco.bushing": bushing, "mujoco.friction": friction})
    _, m, info = build(cfg)
    user = names.read_bore_userdata(m.geom_user[m.geom(names.bushing("C")).id])
    K = ln_stiffness(cfg.joints, cfg.materials, "C")
    if native:
        chi = DAMPING_FACTOR["lankarani-nikravesh"](cfg.contact.restitution)
        assert user["law"] == names.BORE_LAWS["hysteresis"] and user["stiffness"] == pytest.approx(K)
        assert user["exponent"] == 1.5 and user["damping"] == pytest.approx(chi)
        assert user["speed_floor"] == 1e-3 and 0 <= user["slot"] < m.nuserdata
        assert info.contacts["C"].source == "law" and m.npair == 1
        # the stress studies' factors perturb the law
        m2 = build(cfg.replace(**{"mujoco.contact_damping_scale": 1.3, "mujoco.contact_stiffness_scale": 0.8}))[1]
        u2 = names.read_bore_userdata(m2.geom_user[m2.geom(names.bushing("C")).id])
        assert u2["damping"] == pytest.approx(1.3 * chi) and u2["stiffness"] == pytest.approx(0.8 * K)
    else:
        assert user["law"] == 0 and m.nuserdata == 0
        assert info.contacts["C"].source == "first-guess" and info.contacts["C"].law is None


@pytest.mark.parametrize("law", ["hunt-crossley", "flores", "linear"])
def test_native_law_follows_the_configured_reference_law(law):
    """Every law of the reference: the same K, n and damping in the twin's user data (the linear
    law's k and c are the reference engine's own, resolved at the drive's initial pose)."""
    from twin.config import ln_stiffness
    from twin.impact import DAMPING_FACTOR
    from twin.reference.engine import ReferenceEngine

    cfg = preset(12).replace(**{"contact.law": law})
    m = build(cfg)[1]
    refe = ReferenceEngine(cfg)
    refe.reset()
    for j in "BC":
        user = names.read_bore_userdata(m.geom_user[m.geom(names.bushing(j)).id])
        if law == "linear":
            assert user["law"] == names.BORE_LAWS["linear"] and user["exponent"] == 1.0
            assert user["stiffness"] == pytest.approx(refe.contacts[j].stiffness, rel=1e-12)
            assert user["damping"] == pytest.approx(refe.contacts[j].damping_ns_per_m, rel=1e-12)
        else:
            assert user["law"] == names.BORE_LAWS["hysteresis"]
            assert user["stiffness"] == pytest.approx(ln_stiffness(cfg.joints, cfg.materials, j))
            assert user["damping"] == pytest.approx(DAMPING_FACTOR[law](cfg.contact.restitution))


def test_guide_friction_is_the_reference_regularized_law():
    """``mujoco.guide_friction = "native"`` (default): the slider guide's friction is the reference
    engine's, F ramp(|v|; v0, v1) against the slider's velocity, a passive force of the native
    module (test 3, ideal joints: the guide is the only passive force on the slider's dof), through
    the slider's reversals; "frictionloss" restores MuJoCo's friction constraint."""
    from twin.physics.contact import ramp

    cfg = short(preset(3), 0.4, **{"drive.ramp_s": 0.05})
    eng = MujocoEngine(cfg)
    m, d = eng.model, eng.data
    eng.reset()
    ref = DriveReference(cfg)
    dof = m.joint(names.SLIDER_SLIDE).dofadr[0]
    assert m.dof_frictionloss[dof] == 0
    F, v0, v1 = cfg.mechanism.guide_friction_n, cfg.contact.v0_mps, cfg.contact.v1_mps
    seen = {"slow": 0, "ramp": 0, "full": 0}
    for _ in range(40_000):
        th, om = ref(np.array([d.time]))
        d.ctrl[:] = [th[0], om[0]]
        v = float(d.qvel[dof])
        mujoco.mj_step(m, d)  # qfrc_passive: the state the step started from
        assert d.qfrc_passive[dof] == pytest.approx(-F * ramp(v, v0, v1) * np.sign(v), abs=1e-12)
        seen["slow" if abs(v) <= v0 else "ramp" if abs(v) < v1 else "full"] += 1
    assert min(seen.values()) > 0, seen  # reversals crossed
    m2 = build(cfg.replace(**{"mujoco.guide_friction": "frictionloss"}))[1]
    assert m2.dof_frictionloss[m2.joint(names.SLIDER_SLIDE).dofadr[0]] == F and m2.nuser_jnt == 0
