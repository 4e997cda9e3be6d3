"""One source for the model: ``mjcf/bench.xml`` (shipped as package data of ``twin.mjcf``) is the
authority for every number it shares with the configuration.

* the shipped file compiles and runs in plain MuJoCo without a warning;
* it equals the builder's model of the default configuration in every physical number, with
  ideal joints (the base model is ideal);
* the configuration's defaults are the values :mod:`twin.model_xml` parses from it, and MuJoCo's
  own reading of the file agrees (this guards the parser); a changed value reaches the model;
* the bushing user data have one layout (``twin.names.BORE_USERDATA_FIELDS``) that the native
  module, the builder and the base file agree on.

What the builder changes in the default configuration's model on top of the base file:

* every scene: drops the sensors the configuration's channel groups do not need (and the
  eccentricity/contact/friction sensors of ideal joints, and the accelerometer sensors with
  ``mujoco.accelerometers = "posthoc"``, the default; their sites stay), names the model after the
  configuration; a scene without a clearance joint switches contact detection off
  (``mjDSBL_CONTACT``; the base model's geoms never collide anyway);
* a clearance variant (``joints.clearance_b_mm``/``clearance_c_mm`` > 0; the default is test 6,
  C at 0.1 mm): the bushing's bore radius R_j + c (and its visual ring), one contact pair
  pin/bushing (its solref/solimp the placeholder of the native law), the bushing's contact-law
  fields (``law``, ``stiffness``, ``exponent``, ``damping``, ``speed_floor``, ``slot``) and
  ``nuserdata`` slots; at C it
  deletes the ``joint_C`` connect, at B it adds the planar slides ``ecc_B_x``/``ecc_B_y``, at A
  (``joints.clearance_a_mm``) ``ecc_A_x``/``ecc_A_y`` before the crank hinge;
* every scene with the default ``mujoco.guide_friction = "native"``: the slider guide's dry
  friction moves from the slide joint's ``frictionloss`` (MuJoCo's friction constraint, what a
  plain MuJoCo simulates from the file) into its user data (``nuser_jnt``,
  ``twin.names.GUIDE_USERDATA_FIELDS``), the reference's regularized law applied by the native
  module; the force itself is the file's;
* the optional "energy" channel group: energy sensors and ``mjENBL_ENERGY``; the "ring" and
  "tendon" bushing representations: their boxes/tendon instead of the bore pair.
"""

from __future__ import annotations

import dataclasses
import math
from importlib import resources
from pathlib import Path

import mujoco
import numpy as np
import pytest

from twin import model_xml
from twin import names as mjcf_names
from twin.config import BenchConfig
from twin.errors import EngineUnavailableError, ModelError
from twin.native import collider
from twin.mujoco_engine.builder import build

IDEAL = BenchConfig().replace(**{"joints.clearance_c_mm": 0.0})
#: visual geoms the builder re-derives from the lengths (crank arm centre r/2 - 0.01 differs
#: from the file's 0.05 by one rounding, 7e-18 m)
VISUAL_POS_ATOL = 1e-15


def _shipped_xml() -> Path:
    return Path(str(resources.files("twin.mjcf").joinpath("bench.xml")))


@pytest.fixture(scope="module")
def base() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(_shipped_xml()))


@pytest.fixture(scope="module")
def ideal() -> mujoco.MjModel:
    return build(IDEAL)[1]


def test_the_base_model_is_package_data():
    path = _shipped_xml()
    assert path.is_file() and mjcf_names.BASE_XML == path
    assert model_xml.defaults().path == str(path)


def test_the_shipped_xml_compiles_and_steps_without_warnings(base):
    data = mujoco.MjData(base)
    mujoco.mj_forward(base, data)
    for _ in range(400):
        mujoco.mj_step(base, data)
    assert [data.warning[i].number for i in range(len(data.warning))] == [0] * len(data.warning)
    assert np.isfinite(data.qpos).all() and np.isfinite(data.sensordata).all()
    # the loop closure holds: the slider pin stays on the rod eye
    gap = data.site_xpos[base.site(mjcf_names.pin("C")).id] - data.site_xpos[base.site(mjcf_names.bushing("C")).id]
    assert np.linalg.norm(gap) < 1e-8


def _by_name(model: mujoco.MjModel, kind: str, names: list[str], attr: str) -> dict[str, np.ndarray]:
    return {n: np.array(getattr(getattr(model, kind)(n), attr)) for n in names}


def _names(model: mujoco.MjModel, kind: str, count: int) -> list[str]:
    return [getattr(model, kind)(i).name for i in range(count)]


def _assert_same(a: dict, b: dict, what: str, atol: float = 0.0) -> None:
    assert a.keys() == b.keys(), what
    for k in a:
        assert a[k].shape == b[k].shape and np.allclose(a[k], b[k], rtol=0, atol=atol), (what, k, a[k], b[k])


def _dry_friction(model: mujoco.MjModel, joint: str) -> float:
    """A joint's dry friction force: MuJoCo's frictionloss, or the native guide friction's force
    (``mujoco.guide_friction = "native"``: joint user data, twin.names.GUIDE_USERDATA_FIELDS)."""
    j = model.joint(joint)
    native = model.nuser_jnt and j.user[0] == mjcf_names.GUIDE_MAGIC
    return float(model.dof_frictionloss[j.dofadr[0]] + (j.user[1] if native else 0.0))


def _compare(base: mujoco.MjModel, m: mujoco.MjModel, skip_geoms: tuple[str, ...] = (),
             equality: bool = True) -> None:
    """Every physical number of ``base`` and ``m``, matched by name (order-independent)."""
    bodies = _names(base, "body", base.nbody)
    assert bodies == _names(m, "body", m.nbody)
    for attr in ("mass", "ipos", "iquat", "inertia", "pos", "quat"):
        _assert_same(_by_name(base, "body", bodies, attr), _by_name(m, "body", bodies, attr), f"body {attr}")
    joints = _names(base, "joint", base.njnt)
    assert set(joints) <= set(_names(m, "joint", m.njnt))
    for attr in ("type", "axis", "pos", "solref", "solimp", "range", "limited"):
        _assert_same(_by_name(base, "joint", joints, attr), _by_name(m, "joint", joints, attr), f"joint {attr}")
    # per dof (one per joint here); a joint's solreffriction/solimpfriction are its dof's solref/solimp
    for attr in ("damping", "armature", "solref", "solimp"):
        _assert_same({n: np.array(getattr(base, f"dof_{attr}")[base.joint(n).dofadr[0]]) for n in joints},
                     {n: np.array(getattr(m, f"dof_{attr}")[m.joint(n).dofadr[0]]) for n in joints}, f"dof {attr}")
    # dry friction: the file's frictionloss, which the builder moves into the native guide friction
    _assert_same({n: np.array(_dry_friction(base, n)) for n in joints}, {n: np.array(_dry_friction(m, n)) for n in joints},
                 "dof dry friction (frictionloss or native guide friction)")
    if m.nuser_jnt:
        assert m.nuser_jnt == len(mjcf_names.GUIDE_USERDATA_FIELDS)
        guide = m.joint(mjcf_names.SLIDER_SLIDE)
        assert m.dof_frictionloss[guide.dofadr[0]] == 0 and guide.user[0] == mjcf_names.GUIDE_MAGIC
    geoms = [g for g in _names(base, "geom", base.ngeom) if g not in skip_geoms]
    physical = [mjcf_names.pin("B"), mjcf_names.pin("C"), mjcf_names.bushing("B"), mjcf_names.bushing("C")]
    for attr in ("size", "pos", "quat", "user", "type", "contype", "conaffinity", "group"):
        exact = {g: v for g, v in _by_name(base, "geom", geoms, attr).items() if g in physical}
        _assert_same(exact, {g: v for g, v in _by_name(m, "geom", geoms, attr).items() if g in physical},
                     f"pin/bushing geom {attr}")
        _assert_same(_by_name(base, "geom", geoms, attr), _by_name(m, "geom", geoms, attr), f"geom {attr}",
                     atol=VISUAL_POS_ATOL)
    sites = _names(base, "site", base.nsite)
    for attr in ("pos", "quat", "bodyid", "size", "type"):
        _assert_same(_by_name(base, "site", sites, attr), _by_name(m, "site", sites, attr), f"site {attr}")
    acts = _names(base, "actuator", base.nactuator)
    assert acts == _names(m, "actuator", m.nactuator)
    for attr in (a for a in dir(base) if a.startswith("actuator_")):  # gainprm, biasprm, dynprm, ... all
        _assert_same({n: np.array(getattr(base, attr)[base.actuator(n).id]) for n in acts},
                     {n: np.array(getattr(m, attr)[m.actuator(n).id]) for n in acts}, attr)
    for attr in ("timestep", "gravity", "integrator", "solver", "iterations", "tolerance", "cone", "enableflags",
                 "ls_iterations", "ls_tolerance", "noslip_iterations", "impratio"):
        assert np.array_equal(getattr(base.opt, attr), getattr(m.opt, attr)), attr
    # the builder switches contact off in scenes without a clearance joint; nothing else differs
    contact = int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    assert base.opt.disableflags & ~contact == m.opt.disableflags & ~contact
    assert base.nuser_geom == m.nuser_geom == len(mjcf_names.BORE_USERDATA_FIELDS)
    if equality:
        eqs = _names(base, "equality", base.neq)
        assert eqs == _names(m, "equality", m.neq)
        for attr in ("solref", "solimp", "data", "type", "obj1id", "obj2id", "active0"):
            _assert_same(_by_name(base, "equality", eqs, attr), _by_name(m, "equality", eqs, attr), f"equality {attr}")


def test_the_base_xml_is_the_builders_ideal_default_model(base, ideal):
    _compare(base, ideal)
    # what the builder changed: contact off, the clearance-joint sensors removed, the accelerometer
    # sensors too (computed after the rollout by default, mujoco.accelerometers = "posthoc")
    assert ideal.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
    assert set(_names(base, "sensor", base.nsensor)) - set(_names(ideal, "sensor", ideal.nsensor)) == {
        n for jt in ("A", "B", "C") for n in (mjcf_names.sensor_ecc(jt), mjcf_names.sensor_contact(jt), mjcf_names.sensor_friction(jt))} | \
        set(mjcf_names.ACCEL_SENSORS)
    with_sensors = build(IDEAL.replace(**{"mujoco.accelerometers": "sensor"}))[1]
    assert set(mjcf_names.ACCEL_SENSORS) <= set(_names(with_sensors, "sensor", with_sensors.nsensor))


def test_the_default_clearance_variant_changes_only_joint_c(base):
    """Test 6 (C at 0.1 mm): the same model but for the items of the module docstring."""
    cfg = BenchConfig()
    m = build(cfg)[1]
    _compare(base, m, skip_geoms=(mjcf_names.bushing("C"), mjcf_names.bushing_ring("C")), equality=False)
    assert m.neq == 0 and m.npair == len(build(cfg)[2].contacts["C"].terms)
    bush = m.geom(mjcf_names.bushing("C"))
    assert bush.size[0] == pytest.approx(cfg.joints.pin_radius_m + 0.05e-3, abs=1e-15)
    user = mjcf_names.read_bore_userdata(bush.user)
    assert {k: user[k] for k in ("marker", "mu0", "v0", "v1")} == {
        k: v for k, v in mjcf_names.read_bore_userdata(base.geom(mjcf_names.bushing("C")).user).items() if k in ("marker", "mu0", "v0", "v1")}
    assert user["law"] == mjcf_names.BORE_LAWS["hysteresis"] and user["stiffness"] > 0 and user["slot"] == 0
    assert m.nuserdata == 1


def test_config_defaults_are_the_parsed_xml():
    d, cfg = model_xml.defaults(), BenchConfig()
    for body in ("crank", "rod", "slider"):
        assert dataclasses.asdict(getattr(cfg.bodies, body)) == dataclasses.asdict(getattr(d, body))
    assert (cfg.joints.pin_diameter_m, cfg.joints.bushing_length_m) == (d.pin_diameter_m, d.bushing_length_m)
    mech = cfg.mechanism
    assert (mech.orientation, mech.gravity_mps2, mech.d_off_m, mech.guide_friction_n) == (
        d.orientation, d.gravity_mps2, d.d_off_m, d.guide_friction_n)
    assert (cfg.contact.mu0, cfg.contact.v0_mps, cfg.contact.v1_mps) == (d.mu0, d.v0_mps, d.v1_mps)
    ms = cfg.mujoco
    assert (ms.integrator, ms.solver, ms.iterations, ms.tolerance) == (d.integrator, d.solver, d.iterations, d.tolerance)
    assert (ms.equality_solref, ms.equality_solimp, ms.guide_solreffriction) == (
        d.equality_solref, d.equality_solimp, d.guide_solreffriction)
    assert (cfg.pid.kp, cfg.pid.kv, cfg.pid.ki, cfg.pid.imax) == (d.kp, d.kv, d.ki, d.imax)
    assert {k: (v.body, v.position_m, v.axis) for k, v in cfg.sensors.accelerometers.items()} == {
        k: (v.body, v.position_m, v.axis) for k, v in d.accelerometers}
    assert cfg.simulation.timestep_s == d.timestep_s
    assert d.bushing_userdata == tuple(mjcf_names.bore_userdata(mu0=d.mu0, v0=d.v0_mps, v1=d.v1_mps))


def test_mujoco_reads_the_xml_as_the_parser_does(base):
    """The parser's defaults against MuJoCo's own reading of the file (default classes,
    childclass, MuJoCo's defaults): guards twin.model_xml."""
    cfg = BenchConfig()
    for name in ("crank", "rod", "slider"):
        b, p = base.body(name), getattr(cfg.bodies, name)
        assert (b.mass[0], b.ipos[0], b.inertia[2]) == (p.mass_kg, p.x_g_m, p.inertia_kgm2)
    assert base.geom(mjcf_names.pin("B")).pos[0] == cfg.bodies.crank.length_m
    assert base.geom(mjcf_names.bushing("C")).pos[0] == cfg.bodies.rod.length_m
    assert 2 * base.geom(mjcf_names.SLIDER_BLOCK).size[0] == cfg.bodies.slider.length_m
    assert 2 * base.geom(mjcf_names.pin("C")).size[0] == cfg.joints.pin_diameter_m
    assert 2 * base.geom(mjcf_names.bushing("B")).size[1] == cfg.joints.bushing_length_m
    assert tuple(base.opt.gravity) == cfg.mechanism.gravity_vector
    assert base.geom(mjcf_names.pin("C")).pos[1] == cfg.mechanism.d_off_m
    dof = base.joint(mjcf_names.SLIDER_SLIDE).dofadr[0]
    assert base.dof_frictionloss[dof] == cfg.mechanism.guide_friction_n
    assert tuple(base.dof_solref[dof]) == cfg.mujoco.guide_solreffriction
    user = mjcf_names.read_bore_userdata(base.geom(mjcf_names.bushing("B")).user)
    assert (user["mu0"], user["v0"], user["v1"]) == (cfg.contact.mu0, cfg.contact.v0_mps, cfg.contact.v1_mps)
    assert base.opt.timestep == cfg.simulation.timestep_s
    assert base.opt.integrator == getattr(mujoco.mjtIntegrator, f"mjINT_{cfg.mujoco.integrator.upper()}")
    assert base.opt.solver == getattr(mujoco.mjtSolver, f"mjSOL_{cfg.mujoco.solver.upper()}")
    assert (base.opt.iterations, base.opt.tolerance) == (cfg.mujoco.iterations, cfg.mujoco.tolerance)
    eq = base.equality(mjcf_names.JOINT_C_CONNECT)
    assert tuple(eq.solref) == cfg.mujoco.equality_solref and tuple(eq.solimp) == cfg.mujoco.equality_solimp
    act = base.actuator(mjcf_names.CRANK_PID)  # native <pid>: gainprm = ki, biasprm = [0, -kp, -kv], dynprm = imax
    assert (act.gainprm[0], -act.biasprm[1], -act.biasprm[2], act.dynprm[0]) == (
        cfg.pid.ki, cfg.pid.kp, cfg.pid.kv, cfg.pid.imax)
    axes = {"+x": (1, 0), "-x": (-1, 0), "+y": (0, 1), "-y": (0, -1)}
    for name, mount in cfg.sensors.accelerometers.items():
        s = base.site(name)
        assert base.body(s.bodyid[0]).name == mount.body
        assert tuple(s.pos[:2]) == (mount.position_m[0], mount.position_m[1] + (
            cfg.mechanism.d_off_m if mount.body == "slider" else 0.0))
        xaxis = np.zeros(3)
        mujoco.mju_rotVecQuat(xaxis, np.array([1.0, 0, 0]), s.quat)
        assert np.allclose(xaxis, [*axes[mount.axis], 0], atol=1e-12)


def test_a_changed_config_value_reaches_the_compiled_model():
    cfg = IDEAL.replace(**{
        "bodies.crank.mass_kg": 6.0, "bodies.rod.length_m": 0.5, "bodies.slider.inertia_kgm2": 0.003,
        "joints.pin_diameter_m": 0.024, "mechanism.guide_friction_n": 3.0, "mechanism.orientation": "x",
        "mujoco.equality_solref": [3e-5, 1.0], "mujoco.guide_solreffriction": [4e-5, 1.0], "mujoco.iterations": 30,
        "pid.kp": 2.0e5, "pid.imax": 1e-6, "simulation.timestep_s": 5e-6,
        "sensors.accelerometers.AC1.position_m": [0.1, 0.01], "sensors.accelerometers.AC1.axis": "-y",
    })
    m = build(cfg)[1]
    assert m.body(mjcf_names.CRANK).mass[0] == 6.0
    assert m.geom(mjcf_names.bushing("C")).pos[0] == 0.5 and m.site(mjcf_names.bushing("C")).pos[0] == 0.5
    assert m.body(mjcf_names.SLIDER).inertia[2] == 0.003
    assert m.geom(mjcf_names.pin("B")).size[0] == 0.012
    dof = m.joint(mjcf_names.SLIDER_SLIDE).dofadr[0]
    assert _dry_friction(m, mjcf_names.SLIDER_SLIDE) == 3.0 and tuple(m.dof_solref[dof]) == (4e-5, 1.0)
    assert tuple(m.opt.gravity) == (-cfg.mechanism.gravity_mps2, 0.0, 0.0)
    assert tuple(m.equality(mjcf_names.JOINT_C_CONNECT).solref) == (3e-5, 1.0)
    assert m.opt.iterations == 30 and m.opt.timestep == 5e-6
    act = m.actuator(mjcf_names.CRANK_PID)
    assert -act.biasprm[1] == 2.0e5 and act.dynprm[0] == 1e-6
    assert tuple(m.site("AC1").pos) == (0.1, 0.01, 0.0)
    assert np.allclose(m.site("AC1").quat, [math.sqrt(0.5), 0, 0, -math.sqrt(0.5)])
    # the friction law travels in the bushing user data
    m2 = build(BenchConfig().replace(**{"contact.mu0": 0.1, "contact.v1_mps": 2e-3}))[1]
    user = mjcf_names.read_bore_userdata(m2.geom(mjcf_names.bushing("C")).user)
    assert (user["mu0"], user["v0"], user["v1"]) == (0.1, BenchConfig().contact.v0_mps, 2e-3)


# ------------------------------------------------------------------------ the parser
def _edited(tmp_path: Path, old: str, new: str) -> Path:
    text = _shipped_xml().read_text()
    assert text.count(old) == 1, old
    p = tmp_path / "bench.xml"
    p.write_text(text.replace(old, new))
    return p


def test_parser_reports_a_missing_file_or_an_unreadable_value(tmp_path):
    with pytest.raises(ModelError, match="missing"):
        model_xml.read_defaults(tmp_path / "nope.xml")
    with pytest.raises(ModelError, match=r"<inertial>: mass='5\.7x2'"):
        model_xml.read_defaults(_edited(tmp_path, 'mass="5.72"', 'mass="5.7x2"'))
    with pytest.raises(ModelError, match="kp"):
        model_xml.read_defaults(_edited(tmp_path, 'kp="1.7e5" ', ""))
    with pytest.raises(ModelError, match="nuser_geom=15"):
        model_xml.read_defaults(_edited(tmp_path, 'nuser_geom="14"', 'nuser_geom="15"'))
    with pytest.raises(ModelError, match="gravity"):
        model_xml.read_defaults(_edited(tmp_path, 'gravity="0 -9.81 0"', 'gravity="0 -9.81 1"'))
    with pytest.raises(ModelError, match="rod length"):  # the same number written twice must agree
        model_xml.read_defaults(_edited(tmp_path, '<site name="bushing_C" class="marker" pos="0.60 0 0"/>',
                                        '<site name="bushing_C" class="marker" pos="0.61 0 0"/>'))
    with pytest.raises(ModelError, match="not well-formed|cannot load"):
        model_xml.read_defaults(_edited(tmp_path, "</mujoco>", "</mujoc>"))


def test_parser_follows_default_classes_and_mujoco_defaults(tmp_path):
    # a value moved from the element into its default class, and one left to MuJoCo's default
    p = _edited(tmp_path, '<geom type="cylinder" size="0.010 0.010" rgba="0.3 0.3 0.35 1"/>',
                '<geom type="cylinder" size="0.012 0.010" rgba="0.3 0.3 0.35 1"/>')
    text = p.read_text().replace('size="0.010 0.010" user=', 'size="0.012 0.010" user=')
    text = text.replace(' kv="270"', "")
    p.write_text(text)
    d = model_xml.read_defaults(p)
    assert d.pin_diameter_m == 0.024 and d.kv == 0.0
    m = mujoco.MjModel.from_xml_path(str(p))
    assert 2 * m.geom(mjcf_names.pin("C")).size[0] == 0.024 and m.actuator(mjcf_names.CRANK_PID).biasprm[2] == 0.0


# ---------------------------------------------------------------- bore user data layout
def test_bore_userdata_has_one_layout():
    from twin.native import _bore

    assert tuple(_bore.userdata_fields()) == mjcf_names.BORE_USERDATA_FIELDS
    v = mjcf_names.bore_userdata(mu0=0.05, v0=5e-4, v1=1e-3, slot=1)
    assert len(v) == len(mjcf_names.BORE_USERDATA_FIELDS) and v[0] == mjcf_names.BORE_MAGIC == _bore.bore_magic()
    assert mjcf_names.read_bore_userdata(v)["slot"] == 1.0 and mjcf_names.replace_bore_userdata(v, mu0=0)[1] == 0.0
    with pytest.raises(KeyError):
        mjcf_names.bore_userdata(mu0=0.05, v0=5e-4, v1=1e-3, typo=1)
    with pytest.raises(KeyError):
        mjcf_names.bore_userdata(mu0=0.05)


def test_collider_refuses_a_different_layout(monkeypatch):
    monkeypatch.setattr(collider, "_addresses", None)
    monkeypatch.setattr(mjcf_names, "BORE_USERDATA_FIELDS", mjcf_names.BORE_USERDATA_FIELDS[:-1])
    with pytest.raises(EngineUnavailableError, match="user data"):
        collider.ensure_installed()


def test_builder_checks_nuser_geom(tmp_path, monkeypatch):
    monkeypatch.setattr(mjcf_names, "BASE_XML", _edited(tmp_path, 'nuser_geom="14"', 'nuser_geom="15"'))
    with pytest.raises(ModelError, match="nuser_geom = 15"):
        build(IDEAL)
