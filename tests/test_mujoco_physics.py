"""Physics of the MuJoCo twin: closed-form kinematics, the calibration pose, the clearance
bound, the exact bore geometry and the contact and friction laws."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from twin import names as N
from twin.config import BenchConfig, preset
from twin.drive import DriveReference
from twin.kinematics import slider_position
from twin.mujoco_engine.builder import build
from twin.mujoco_engine.engine import MujocoEngine
from twin.simulate import simulate_run

from conftest import short

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
        # and penetrates it by a few percent of c: the calibrated contact, like the reference's
        # Hertzian law, lets the pin sink 2.6 um into the 50 um clearance at C under ~650 N
        # (measured: twin 2.58 um, reference 2.65 um on this run)
        assert ecc.max() < 1.08 * c
        assert np.max(run[f"pen_{j}"]) == pytest.approx(max(ecc.max() - c, 0), abs=1e-12)
        assert run[f"fn_{j}"].max() > 0


def test_bore_collider_is_an_exact_circle():
    cfg = preset(6).replace(**{"mujoco.contact_source": "first-guess"})  # one pair: one contact
    _, model, _ = build(cfg)
    model.pair_margin[:] = 1e-3
    d = mujoco.MjData(model)
    c = cfg.joints.radial_m("C")
    pin = model.geom(N.pin("C")).id
    model.geom_sameframe[pin] = 0  # geom_pos is edited below: do not reuse the body frame
    slide = model.jnt_qposadr[model.joint(N.SLIDER_SLIDE).id]
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


def test_contact_force_is_the_linear_law_and_friction_is_regularized_coulomb():
    # the first guess is one linear term with a flat impedance: f = k δ + c δ̇ exactly (with the
    # fixed damping; the impact-speed term is tested on its own below)
    cfg = short(preset(12), 0.2, **{"drive.ramp_s": 0.02, "mujoco.contact_source": "first-guess",
                                    "mujoco.contact_damping": "fixed"})
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
            ft = d.sensordata[sens[N.sensor_friction(j)].start]
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

    cfg = preset(12).replace(**{"mujoco.contact_source": "first-guess", "mujoco.contact_damping": "fixed"})
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


def test_impact_speed_damping_adds_the_lankarani_nikravesh_term():
    """``mujoco.contact_damping = "impact-speed"``: the native module adds χK δⁿ δ̇ / v_imp to
    the contact force (v_imp stored when the event starts, floored, the ratio δ̇/v_imp clamped
    at −1 while separating) and forgets v_imp when the pin leaves the wall."""
    from twin.calibrate import ContactLaw, probe_model
    from twin.mujoco_engine.builder import CALIBRATION_FILE
    import json
    cfg = BenchConfig().replace(**{"joints.clearance_c_mm": 0.1})
    c = cfg.joints.radial_m("C")
    law = ContactLaw.from_json(json.loads(CALIBRATION_FILE.read_text())["entries"]["C:0.1"])
    coef, n, floor = 2.0e10, 1.5, 1e-3
    on = probe_model(cfg, "C", 1.3, law, (coef, n, floor))
    off = probe_model(cfg, "C", 1.3, law)

    def force(model, delta, ddelta, v_imp=0.0):
        d = mujoco.MjData(model)
        d.qpos[0], d.qvel[0] = c + delta, ddelta   # the probe's slide axis points into the wall
        if model.nuserdata:
            d.userdata[0] = v_imp
        mujoco.mj_forward(model, d)
        return float(np.sum(d.efc_force[:d.nefc])), d

    delta = 2e-6
    for ddelta, v_imp, ratio in [(0.01, 0.02, 0.5), (-0.005, 0.02, -0.25), (-0.05, 0.02, -1.0)]:
        f_on, d = force(on, delta, ddelta, v_imp)
        f_off, _ = force(off, delta, ddelta)
        assert d.userdata[0] == v_imp                       # an event under way keeps its speed
        assert f_on - f_off == pytest.approx(coef * delta ** n * ratio, rel=0.03), (ddelta, ratio)
    # a new event stores its approach speed, or the floor
    assert force(on, delta, 0.004)[1].userdata[0] == pytest.approx(0.004)
    assert force(on, delta, 0.0002)[1].userdata[0] == pytest.approx(floor)
    # out of contact: no event
    assert force(on, -1e-6, 0.01, 0.02)[1].userdata[0] == 0.0
    # the stored speed is not part of mjSTATE_FULLPHYSICS: it lives in the MjData the engine
    # keeps across its rollout chunks, and rollout must leave it there
    from mujoco import rollout
    _, d = force(on, delta, 0.001, 0.02)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(on, spec))
    mujoco.mj_getState(on, d, state, spec)
    rollout.rollout(on, d, state[None], nstep=3)
    assert d.userdata[0] == 0.02


@pytest.mark.parametrize("bushing, friction, native", [("bore", "native", True), ("bore", "cone", True),
                                                      ("ring", "cone", False), ("tendon", "native", False)])
def test_impact_speed_damping_is_set_where_the_bore_applies_it(bushing, friction, native):
    """The default "impact-speed" damping: the bore bushing carries the native term (χK, n,
    floor, a userdata slot) and its pairs keep 1 % of their damping; ring and tendon bushings,
    which the native module does not see, keep their whole fixed damping."""
    from twin.impact import DAMPING_FACTOR
    from twin.config import ln_stiffness
    from twin.mujoco_engine.builder import IMPACT_SPEED_RESIDUAL_DAMPING
    cfg = preset(6).replace(**{"mujoco.bushing": bushing, "mujoco.friction": friction})
    fixed = cfg.replace(**{"mujoco.contact_damping": "fixed"})
    _, m, info = build(cfg)
    _, _, info_fixed = build(fixed)
    user = N.read_bore_userdata(m.geom_user[m.geom(N.bushing("C")).id])
    K = ln_stiffness(cfg.joints, cfg.materials, "C")
    if native:
        chi = DAMPING_FACTOR["lankarani-nikravesh"](cfg.contact.restitution)
        assert user["damping_coef"] == pytest.approx(chi * K) and user["exponent"] == 1.5
        assert user["speed_floor"] == 1e-3 and 0 <= user["slot"] < m.nuserdata
        for t, tf in zip(info.contacts["C"].terms, info_fixed.contacts["C"].terms):
            assert t.damping_ns_per_m == pytest.approx(tf.damping_ns_per_m * IMPACT_SPEED_RESIDUAL_DAMPING)
        # the stress studies' damping factor perturbs the native term too
        m2 = build(cfg.replace(**{"mujoco.contact_damping_scale": 1.3}))[1]
        assert N.read_bore_userdata(m2.geom_user[m2.geom(N.bushing("C")).id])["damping_coef"] == \
            pytest.approx(1.3 * chi * K)
    else:
        assert user["damping_coef"] == 0 and m.nuserdata == 0
        assert info.contacts["C"].terms == info_fixed.contacts["C"].terms


def test_impact_speed_damping_follows_the_configured_hysteresis_law():
    from twin.impact import DAMPING_FACTOR
    from twin.config import ln_stiffness
    for law, native in (("hunt-crossley", True), ("linear", False)):
        cfg = preset(6).replace(**{"contact.law": law})
        m = build(cfg)[1]
        coef = N.read_bore_userdata(m.geom_user[m.geom(N.bushing("C")).id])["damping_coef"]
        if native:
            K = ln_stiffness(cfg.joints, cfg.materials, "C")
            assert coef == pytest.approx(DAMPING_FACTOR[law](cfg.contact.restitution) * K)
        else:  # a linear law has no impact-speed damping to carry over
            assert coef == 0 and m.nuserdata == 0
