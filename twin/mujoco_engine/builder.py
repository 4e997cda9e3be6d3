"""Configuration -> compiled MuJoCo model, through ``mujoco.MjSpec`` edits of ``mjcf/bench.xml``.

What the builder does to the base model:

* options: timestep, integrator, solver, gravity from the orientation; contact detection is
  switched off entirely when no joint has a clearance;
* bodies: masses, centres of mass and inertias (Table 1), lengths, d_off, pin and bushing
  radii, accelerometer mounting sites;
* an ideal joint B is a hinge in the kinematic tree (exact); an ideal joint C is the
  loop-closure ``connect`` of the base model (stiff soft constraint);
* a clearance joint replaces that by two slide joints (B: rod eye relative to the crank pin)
  or drops the connect (C), and adds an explicit frictionless ``<pair>`` pin/bushing whose
  contact is computed by the native bore collider (exact circle) and governed by
  solref/solimp; the reference's regularized Coulomb friction (μ0, v0, v1 of the ``contact``
  section, stored in the bushing geom's user data) is applied by the native module as a
  passive force. Why not MuJoCo's own friction cone: with soft contacts the elliptic cone
  adds μ × (the would-be sticking force) to the normal force while sliding; on test 12 that
  inflated the normal force by a median 23 % (up to 27×) over the k δ + c δ̇ law, and making
  the friction rows softer turned Coulomb friction into viscous friction
  (``analysis/friction_cone.py`` measures both);
* sensors: only those the configuration's channel groups need (the optional "energy" group
  adds ``e_kinetic``/``e_potential`` sensors and the slider's velocity, and switches on
  MuJoCo's energy computation, ``mjENBL_ENERGY``);
* the crank PID gains.

Contact parameters of a clearance joint, in order of precedence:
``mujoco.contact_solref``/``contact_solimp`` of the configuration (raw MuJoCo values); the
calibration table ``twin/data/contact_calibration.json`` (written by ``twin calibrate
contact``); the documented first guess :func:`first_guess_contact`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from pathlib import Path

import mujoco
import numpy as np

from twin import names as N
from twin.config import BenchConfig, ln_stiffness
from twin.errors import ConfigError, ModelError
from twin.impact import DAMPING_FACTOR
from twin.mujoco_engine.collider import ensure_installed

#: the contact calibration table, package data of twin (``twin/data``)
CALIBRATION_FILE = Path(str(resources.files("twin").joinpath("data", "contact_calibration.json")))

#: flat, tiny impedance: the contact force is then exactly k δ + c δ̇ with a direct solref
#: (−k Â, −c Â), Â the row's inverse-inertia estimate (ENGINEERING_NOTES, re-measured in tests)
FLAT_SOLIMP = (1e-4, 1e-4, 1e-3, 0.5, 2.0)
#: impact speed at which the first guess matches the reference law [m/s]. PLACEHOLDER until
#: the calibration (impact speeds on the bench: 0.4-201 mm/s, ``analysis/impact_speeds.py``).
FIRST_GUESS_SPEED = 0.1
#: with ``mujoco.contact_damping = "impact-speed"`` the pairs keep this fraction of their
#: calibrated damping (the native Lankarani–Nikravesh term replaces the rest); 1 % keeps the
#: soft constraint's own damping from vanishing. Not tuned: the value measured by ``twin study
#: accuracy`` (analysis/results/accuracy, variant "mujoco default")
IMPACT_SPEED_RESIDUAL_DAMPING = 0.01
#: frictionless MuJoCo contact; friction is the native passive force (see module docstring)
_CONDIM = 1

_SENSORS_BY_GROUP = {
    "accel": list(N.ACCEL_SENSORS),
    "encoder": [N.SENSOR_CRANK_ANGLE],
    "crank": [N.SENSOR_CRANK_ANGLE, N.SENSOR_CRANK_SPEED],
    "slider": [N.SENSOR_SLIDER_POSITION],
    "drive": [N.SENSOR_CRANK_TORQUE],
}

_AXIS_QUAT = {  # site orientation whose x axis is the sensitive axis (rotation about z)
    "+x": (1.0, 0.0, 0.0, 0.0),
    "+y": (math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)),
    "-x": (0.0, 0.0, 0.0, 1.0),
    "-y": (math.sqrt(0.5), 0.0, 0.0, -math.sqrt(0.5)),
}


@dataclass(frozen=True)
class ContactTerm:
    """One MuJoCo pair of a pin/bushing contact law.

    Attributes:
        solref: the pair's solref (2 numbers; negative = direct stiffness/damping).
        solimp: the pair's solimp (5 numbers).
        stiffness_n_per_m: physical stiffness k at full impedance, if defined that way [N/m].
        damping_ns_per_m: physical damping c at full impedance [N s/m].
    """

    solref: tuple[float, float]
    solimp: tuple[float, ...]
    stiffness_n_per_m: float | None = None
    damping_ns_per_m: float | None = None


@dataclass(frozen=True)
class ContactSetting:
    """MuJoCo parameters of one pin/bushing contact and where they came from.

    The contact force is the sum of the terms' forces, one pair each on the same two geoms
    (the calibration uses two: see :mod:`twin.calibrate`).

    Attributes:
        terms: the pairs' parameters (at least one).
        friction: μ0 of the native regularized Coulomb friction [-].
        source: "config", "calibration" or "first-guess".
    """

    terms: tuple[ContactTerm, ...]
    friction: float
    source: str

    # the first term's values (the whole law when it has one term)
    @property
    def solref(self) -> tuple[float, float]:
        return self.terms[0].solref

    @property
    def solimp(self) -> tuple[float, ...]:
        return self.terms[0].solimp

    @property
    def stiffness_n_per_m(self) -> float | None:
        return self.terms[0].stiffness_n_per_m

    @property
    def damping_ns_per_m(self) -> float | None:
        return self.terms[0].damping_ns_per_m

    def to_json(self) -> dict:
        return {"source": self.source, "friction": self.friction,
                "terms": [{"solref": list(t.solref), "solimp": [float(v) for v in t.solimp],
                           "stiffness_n_per_m": t.stiffness_n_per_m, "damping_ns_per_m": t.damping_ns_per_m}
                          for t in self.terms]}


@dataclass
class BuildInfo:
    """What the builder decided, for run metadata and tests."""

    contacts: dict[str, ContactSetting] = field(default_factory=dict)
    sensors: list[str] = field(default_factory=list)
    a_hat: dict[str, float] = field(default_factory=dict)


# ------------------------------------------------------------------ contact parameters
@lru_cache(maxsize=64)
def _first_guess_kc(K: float, n: float, e: float, m_eff: float) -> tuple[float, float]:
    from twin.impact import linear_equivalent

    return linear_equivalent(K, n, e, m_eff, FIRST_GUESS_SPEED, law="lankarani-nikravesh")


def first_guess_contact(cfg: BenchConfig, joint: str, m_eff: float) -> tuple[float, float]:
    """First guess (k [N/m], c [N s/m]) of a linear contact for ``joint``.

    Method: the reference's Lankarani–Nikravesh law (K from S003 Eq. 18, n, e of the
    configuration) is replaced by the unilateral linear spring-damper that has the same
    contact duration and the same restitution for an impact of the effective mass ``m_eff``
    at :data:`FIRST_GUESS_SPEED`. The calibration (``twin calibrate contact``) supersedes it.
    """
    K = cfg.contact.stiffness or ln_stiffness(cfg.joints, cfg.materials, joint)
    return _first_guess_kc(float(K), float(cfg.contact.exponent), float(cfg.contact.restitution), float(m_eff))


def load_calibration(path: Path = CALIBRATION_FILE) -> dict:
    """The calibration table (empty if none has been committed yet)."""
    if not path.is_file():
        return {}
    return json.loads(path.read_text())


def _calibration_entry(table: dict, cfg: BenchConfig, joint: str) -> dict | None:
    key = f"{joint}:{cfg.joints.diametral_mm(joint):g}"
    entry = table.get("entries", {}).get(key)
    if entry is None:
        return None
    # a calibration holds for the reference parameters it was fitted to
    ref = table.get("reference", {})
    same = all(math.isclose(ref.get(k, float("nan")), v, rel_tol=1e-9) for k, v in (
        ("restitution", cfg.contact.restitution), ("exponent", cfg.contact.exponent),
        ("pin_diameter_m", cfg.joints.pin_diameter_m), ("mu0", cfg.contact.mu0)))
    return entry if same and cfg.contact.stiffness == 0 else None


def contact_setting(cfg: BenchConfig, joint: str, a_hat: float, multi_term: bool = True) -> ContactSetting:
    """Resolve the pair parameters of a clearance joint (see module docstring).

    ``multi_term`` is False for representations that take one pair per contact (ring of
    boxes, tendon limit): a multi-term calibration entry then falls back to the first guess.
    ``mujoco.contact_stiffness_scale``/``contact_damping_scale`` multiply the result.
    """
    s = _resolve_contact(cfg, joint, a_hat, multi_term)
    ks, cs = cfg.mujoco.contact_stiffness_scale * cfg.contact.stiffness_scale, cfg.mujoco.contact_damping_scale
    if impact_speed_damping(cfg):
        cs *= IMPACT_SPEED_RESIDUAL_DAMPING
    if ks == 1.0 and cs == 1.0:
        return s
    terms = []
    for t in s.terms:
        if t.solref[0] >= 0:
            raise ConfigError("mujoco.contact_stiffness_scale",
                              "needs a direct (negative) contact_solref; scale only physical stiffness/damping")
        terms.append(ContactTerm((t.solref[0] * ks, t.solref[1] * cs), t.solimp,
                                 None if t.stiffness_n_per_m is None else t.stiffness_n_per_m * ks,
                                 None if t.damping_ns_per_m is None else t.damping_ns_per_m * cs))
    return ContactSetting(tuple(terms), s.friction, s.source)


def _resolve_contact(cfg: BenchConfig, joint: str, a_hat: float, multi_term: bool) -> ContactSetting:
    mu = cfg.contact.mu0
    ms = cfg.mujoco
    if ms.contact_solref and ms.contact_solimp:
        return ContactSetting((ContactTerm(tuple(ms.contact_solref), tuple(ms.contact_solimp)),), mu, "config")
    entry = _calibration_entry(load_calibration(), cfg, joint) if ms.contact_source == "calibration" else None
    if entry is not None and (multi_term or len(entry["terms"]) == 1):
        terms = tuple(ContactTerm((-t["stiffness_n_per_m"] * a_hat, -t["damping_ns_per_m"] * a_hat),
                                  tuple(t["solimp"]), t["stiffness_n_per_m"], t["damping_ns_per_m"])
                      for t in entry["terms"])
        return ContactSetting(terms, mu, "calibration")
    k, c = first_guess_contact(cfg, joint, 1.0 / a_hat)
    return ContactSetting((ContactTerm((-k * a_hat, -c * a_hat), FLAT_SOLIMP, k, c),), mu, "first-guess")


# --------------------------------------------------------------------------- builder
def _set_inertial(body: mujoco.MjsBody, mass: float, ipos, izz: float) -> None:
    body.explicitinertial = True
    body.mass = mass
    body.ipos = list(ipos)
    body.iquat = [1.0, 0.0, 0.0, 0.0]
    # planar mechanism: only I_zz acts; the off-plane values keep the tensor valid
    body.inertia = [izz / 2, izz / 2, izz]


def build_spec(cfg: BenchConfig) -> mujoco.MjSpec:
    """Edited (uncompiled) spec of the configuration; contact pairs without final solref."""
    try:
        spec = mujoco.MjSpec.from_file(str(N.BASE_XML))
    except Exception as err:  # mujoco raises ValueError with the parser message
        raise ModelError(f"cannot load base model {N.BASE_XML}: {err}") from None
    spec.modelname = f"slider_crank_bench_{cfg.name}"
    b, j, mech = cfg.bodies, cfg.joints, cfg.mechanism
    r, l = b.crank.length_m, b.rod.length_m
    rj, half_len = j.pin_radius_m, j.bushing_length_m / 2

    # options
    opt = spec.option
    opt.timestep = cfg.simulation.timestep_s
    opt.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{cfg.mujoco.integrator.upper()}")
    opt.solver = getattr(mujoco.mjtSolver, f"mjSOL_{cfg.mujoco.solver.upper()}")
    opt.iterations = cfg.mujoco.iterations
    opt.tolerance = cfg.mujoco.tolerance
    opt.gravity = list(mech.gravity_vector)
    if not j.clearance_joints:
        opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT

    # crank
    crank = spec.body(N.CRANK)
    _set_inertial(crank, b.crank.mass_kg, (b.crank.x_g_m, 0, 0), b.crank.inertia_kgm2)
    arm = spec.geom(N.CRANK_ARM)
    arm.size = [r / 2 + 0.015, arm.size[1], arm.size[2]]
    arm.pos = [r / 2 - 0.01, 0, 0]
    z = spec.geom(N.pin("B")).pos[2]
    for obj in (spec.geom(N.pin("B")), spec.site(N.pin("B"))):
        obj.pos = [r, 0, z]

    # rod (frame at the bushing centre B', x towards C)
    rod = spec.body(N.ROD)
    rod.pos = [r, 0, z]
    _set_inertial(rod, b.rod.mass_kg, (b.rod.x_g_m, 0, 0), b.rod.inertia_kgm2)
    beam = spec.geom(N.ROD_BEAM)
    beam.size = [l / 2 - 0.03, beam.size[1], beam.size[2]]
    beam.pos = [l / 2, 0, 0]
    for name in (N.bushing("C"), N.bushing_ring("C")):
        spec.geom(name).pos = [l, 0, 0]
    spec.site(N.bushing("C")).pos = [l, 0, 0]

    # slider (frame at Cs on the guide line; C' is d_off above it)
    slider = spec.body(N.SLIDER)
    _set_inertial(slider, b.slider.mass_kg, (b.slider.x_g_m, mech.d_off_m, 0), b.slider.inertia_kgm2)
    spec.joint(N.SLIDER_SLIDE).frictionloss = mech.guide_friction_n
    spec.joint(N.SLIDER_SLIDE).solref_friction = list(cfg.mujoco.guide_solreffriction)
    for obj in (spec.geom(N.pin("C")), spec.site(N.pin("C"))):
        obj.pos = [0, mech.d_off_m, 0]
    block = spec.geom(N.SLIDER_BLOCK)
    block.size = [b.slider.length_m / 2, block.size[1], block.size[2]]

    # pins, bushings (user data: bore marker and friction law, layout N.BORE_USERDATA_FIELDS)
    # and their visual rings; the impact-speed damping is off unless build() switches it on
    friction_law = N.bore_userdata(mu0=cfg.contact.mu0, v0=cfg.contact.v0_mps, v1=cfg.contact.v1_mps)
    for jt in ("B", "C"):
        spec.geom(N.pin(jt)).size = [rj, half_len, 0]
        spec.geom(N.bushing(jt)).size = [j.bushing_radius_m(jt), half_len, 0]
        spec.geom(N.bushing(jt)).userdata = friction_law
        spec.geom(N.bushing_ring(jt)).size = [j.bushing_radius_m(jt) + 0.006, half_len * 1.05, 0]

    # accelerometer sites
    for name, mount in cfg.sensors.accelerometers.items():
        site = spec.site(name)
        x, y = mount.position_m
        site.pos = [x, y, 0] if mount.body == "rod" else [x, y + mech.d_off_m, 0]
        site.quat = list(_AXIS_QUAT[mount.axis])
        if site.parent.name != mount.body:  # mounts may move between bodies only by config
            site_body = spec.body(mount.body)
            new = site_body.add_site(name=f"{name}_tmp", pos=site.pos, quat=site.quat, size=site.size,
                                     type=site.type, rgba=site.rgba, group=site.group)
            spec.delete(site)
            new.name = name

    # clearance joint B: rod eye free in the plane relative to the crank pin
    if j.diametral_mm("B") > 0:
        spec.delete(spec.joint(N.ROD_HINGE))
        rod.add_joint(name=N.ECC_B_X, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
        rod.add_joint(name=N.ECC_B_Y, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0])
        rod.add_joint(name=N.ROD_HINGE, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    # clearance joint C: no loop-closure constraint, the contact holds the rod on the pin
    eq = spec.equality(N.JOINT_C_CONNECT)
    if j.diametral_mm("C") > 0:
        spec.delete(eq)
    else:
        eq.solref = list(cfg.mujoco.equality_solref)
        eq.solimp = list(cfg.mujoco.equality_solimp)
    for jt in j.clearance_joints:
        spec.add_pair(name=N.pair(jt), geomname1=N.pin(jt), geomname2=N.bushing(jt), condim=_CONDIM)

    # sensors: keep only what the channel groups need
    keep: set[str] = set()
    for g in cfg.sensors.channels:
        keep.update(_SENSORS_BY_GROUP.get(g, []))
        if g == "joints":
            for jt in j.clearance_joints:
                keep.update((N.sensor_ecc(jt), N.sensor_contact(jt), N.sensor_friction(jt)))
    for s in list(spec.sensors):
        if s.name not in keep:
            spec.delete(s)
    if "energy" in cfg.sensors.channels:
        # optional energy group: MuJoCo computes energies only with the energy flag on
        opt.enableflags |= mujoco.mjtEnableBit.mjENBL_ENERGY
        spec.add_sensor(name=N.SENSOR_ENERGY_KINETIC, type=mujoco.mjtSensor.mjSENS_E_KINETIC)
        spec.add_sensor(name=N.SENSOR_ENERGY_POTENTIAL, type=mujoco.mjtSensor.mjSENS_E_POTENTIAL)
        spec.add_sensor(name=N.SENSOR_SLIDER_SPEED, type=mujoco.mjtSensor.mjSENS_JOINTVEL,
                        objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=N.SLIDER_SLIDE)

    # crank PID (native <pid>: gainprm = ki, biasprm = [0, -kp, -kv], dynprm = imax)
    act = spec.actuator(N.CRANK_PID)
    act.gainprm[0] = cfg.pid.ki
    act.biasprm[1], act.biasprm[2] = -cfg.pid.kp, -cfg.pid.kv
    act.dynprm[0] = cfg.pid.imax
    return spec


def _compile(spec: mujoco.MjSpec, cfg: BenchConfig) -> mujoco.MjModel:
    try:
        model = spec.compile()
    except Exception as err:
        raise ModelError(f"MuJoCo could not compile the model of {cfg.name}: {err}") from None
    if model.nuser_geom != len(N.BORE_USERDATA_FIELDS):  # _bore.c reads the user data by this layout
        raise ModelError(f"the model of {cfg.name} has nuser_geom = {model.nuser_geom}, the bore user data layout "
                         f"{len(N.BORE_USERDATA_FIELDS)} fields {N.BORE_USERDATA_FIELDS} (twin.names); "
                         f"fix <size nuser_geom> in {N.BASE_XML}")
    return model


def _ring(spec: mujoco.MjSpec, cfg: BenchConfig, jt: str) -> list[str]:
    """Replace the bore of ``jt`` by ``mujoco.ring_boxes`` boxes; returns the box names."""
    n = cfg.mujoco.ring_boxes
    bush = spec.geom(N.bushing(jt))
    centre = np.array(bush.pos)
    ri = cfg.joints.bushing_radius_m(jt)
    half_w, t = ri * math.tan(math.pi / n), 1e-3
    names = []
    for k in range(n):
        beta = 2 * math.pi * k / n
        g = spec.body(N.ROD).add_geom(
            name=f"{N.bushing(jt)}_box{k}", type=mujoco.mjtGeom.mjGEOM_BOX, size=[t, half_w, cfg.joints.bushing_length_m / 2],
            pos=list(centre + (ri + t) * np.array([math.cos(beta), math.sin(beta), 0.0])),
            quat=[math.cos(beta / 2), 0.0, 0.0, math.sin(beta / 2)], contype=0, conaffinity=0, mass=0, group=3)
        names.append(g.name)
    return names


def build(cfg: BenchConfig) -> tuple[mujoco.MjSpec, mujoco.MjModel, BuildInfo]:
    """Spec, compiled model and build info of a configuration (collider installed).

    The bushing representation (``mujoco.bushing``) and the friction model
    (``mujoco.friction``) are applied here: "bore" keeps the base model's pair; "ring"
    replaces it by one pair per box; "tendon" by a distance-limited tendon. Their contact
    parameters are the same physical law (k, c, solimp), converted with each row's Â.
    """
    ensure_installed()
    ms = cfg.mujoco
    spec = build_spec(cfg)
    info = BuildInfo()
    if not cfg.joints.clearance_joints:
        info.sensors = [x.name for x in spec.sensors]
        return spec, _compile(spec, cfg), info
    rings: dict[str, list[str]] = {}
    if ms.bushing == "ring":
        # box-cylinder contacts go through MuJoCo's convex (CCD) collider, whose default
        # tolerance (1e-6 m) is a large fraction of a 10-500 um clearance: measured chatter
        # (200+ false impacts in 0.5 s) until it is tightened
        spec.option.ccd_tolerance = 1e-10
        spec.option.ccd_iterations = 100
    for jt in cfg.joints.clearance_joints:
        if ms.bushing == "ring":
            spec.delete(spec.pair(N.pair(jt)))
            rings[jt] = _ring(spec, cfg, jt)
            for k, box in enumerate(rings[jt]):
                spec.add_pair(name=f"{N.pair(jt)}_{k}", geomname1=N.pin(jt), geomname2=box, condim=3,
                              friction=[cfg.contact.mu0, cfg.contact.mu0, 0, 0, 0])
            if spec.sensor(N.sensor_contact(jt)) is not None:
                sc = spec.sensor(N.sensor_contact(jt))
                sc.reftype, sc.refname = mujoco.mjtObj.mjOBJ_BODY, N.ROD
                sc.intprm = [3, 3, 1]  # found + force, reduce = netforce (global frame), one slot
        elif ms.bushing == "tendon":
            spec.delete(spec.pair(N.pair(jt)))
            t = spec.add_tendon(name=N.pair(jt), limited=True, range=[0.0, cfg.joints.radial_m(jt)])
            t.wrap_site(N.pin(jt))
            t.wrap_site(N.bushing(jt))
            if spec.sensor(N.sensor_contact(jt)) is not None:
                sc = spec.sensor(N.sensor_contact(jt))
                sc.type, sc.objtype, sc.objname = mujoco.mjtSensor.mjSENS_TENDONLIMITFRC, mujoco.mjtObj.mjOBJ_TENDON, N.pair(jt)
                sc.reftype, sc.refname, sc.intprm = mujoco.mjtObj.mjOBJ_UNKNOWN, "", [0, 0, 0]
        elif ms.friction == "cone":
            p = spec.pair(N.pair(jt))
            p.condim = 3
            p.friction = [cfg.contact.mu0, cfg.contact.mu0, 0, 0, 0]
        if ms.bushing != "bore" or ms.friction == "cone":
            bush = spec.geom(N.bushing(jt))
            bush.userdata = N.replace_bore_userdata(list(bush.userdata), mu0=0.0)  # native friction off
            if spec.sensor(N.sensor_friction(jt)) is not None:
                spec.delete(spec.sensor(N.sensor_friction(jt)))
    model = _compile(spec, cfg)
    for jt in cfg.joints.clearance_joints:
        if ms.bushing == "tendon":
            a_hat = float(model.tendon_invweight0[model.tendon(N.pair(jt)).id])
        else:
            a_hat = float(model.body_invweight0[model.geom_bodyid[model.geom(N.pin(jt)).id], 0] +
                          model.body_invweight0[model.geom_bodyid[model.geom(N.bushing(jt)).id], 0])
        setting = contact_setting(cfg, jt, a_hat, multi_term=ms.bushing == "bore")
        if ms.bushing == "tendon":
            t = spec.tendon(N.pair(jt))
            t.solref_limit, t.solimp_limit = list(setting.solref), list(setting.solimp)
        elif jt in rings:
            for k in range(len(rings[jt])):
                p = spec.pair(f"{N.pair(jt)}_{k}")
                p.solref, p.solimp = list(setting.solref), list(setting.solimp)
        else:
            base = spec.pair(N.pair(jt))
            for i, term in enumerate(setting.terms):
                p = base if i == 0 else spec.add_pair(name=N.pair(jt, i), geomname1=N.pin(jt),
                                                      geomname2=N.bushing(jt), condim=base.condim,
                                                      friction=list(base.friction))
                p.solref, p.solimp = list(term.solref), list(term.solimp)
            if spec.sensor(N.sensor_contact(jt)) is not None:
                # one slot per term; the engine sums their normal (and friction-cone) forces
                spec.sensor(N.sensor_contact(jt)).intprm = [3, 0, len(setting.terms)]
        info.contacts[jt] = setting
        info.a_hat[jt] = a_hat
    if impact_speed_damping(cfg):
        _set_impact_speed_damping(spec, cfg)
    info.sensors = [x.name for x in spec.sensors]
    return spec, _compile(spec, cfg), info


def impact_speed_damping(cfg: BenchConfig) -> bool:
    """Whether the scene's bushings take the native impact-speed damping (bore bushing with
    ``mujoco.contact_damping = "impact-speed"``, a hysteresis contact law of the reference, i.e.
    one whose damping is χ K δⁿ δ̇ / v_imp, and a clearance joint to apply it to)."""
    ms = cfg.mujoco
    return (ms.contact_damping == "impact-speed" and ms.bushing == "bore" and cfg.contact.law in DAMPING_FACTOR
            and bool(cfg.joints.clearance_joints))


def impact_speed_coefficient(cfg: BenchConfig, joint: str) -> float:
    """χ K of the native impact-speed damping of ``joint`` [N/mⁿ]: χ(e) of the configured
    hysteresis law (LN by default, Hunt–Crossley or Flores) and K of S003 Eq. 18 times
    ``contact.stiffness_scale``, times ``impact_damping_gain`` and ``contact_damping_scale`` (which
    perturbs all of the law's damping)."""
    ms, ct = cfg.mujoco, cfg.contact
    K = (ct.stiffness or ln_stiffness(cfg.joints, cfg.materials, joint)) * ct.stiffness_scale
    return ms.impact_damping_gain * ms.contact_damping_scale * DAMPING_FACTOR[ct.law](ct.restitution) * K


def _set_impact_speed_damping(spec: mujoco.MjSpec, cfg: BenchConfig) -> None:
    """Switch on the native impact-speed damping of each clearance bushing (``_bore.c``): the
    coefficient, exponent n, speed floor, and one ``userdata`` slot per joint for the stored
    impact speed."""
    joints = cfg.joints.clearance_joints
    spec.nuserdata = len(joints)
    for slot, jt in enumerate(joints):
        bush = spec.geom(N.bushing(jt))
        bush.userdata = N.replace_bore_userdata(
            list(bush.userdata), damping_coef=impact_speed_coefficient(cfg, jt), exponent=cfg.contact.exponent,
            speed_floor=cfg.contact.impact_speed_floor_mps, slot=slot)


def build_model(cfg: BenchConfig) -> mujoco.MjModel:
    """Compiled model of a configuration."""
    return build(cfg)[1]


def export_xml(cfg: BenchConfig) -> str:
    """MJCF text of the configuration's compiled variant (opens in MuJoCo's viewer)."""
    spec, _model, info = build(cfg)
    head = (f"<!-- twin export of '{cfg.name}' (config digest {cfg.digest()}).\n"
            f"     Clearance joints: {', '.join(cfg.joints.clearance_joints) or 'none'}; contact parameters: "
            + "; ".join(f"{jt}: {len(s.terms)} pair(s) ({s.source})" for jt, s in info.contacts.items())
            + ".\n     Bushing geoms (user=\"7301 ...\") need the twin's native bore collider and friction "
              "(twin/mujoco_engine/_bore.c):\n     a plain MuJoCo viewer shows and simulates ideal variants "
              "faithfully; simulate clearance variants with 'twin simulate'. -->\n")
    xml = spec.to_xml()
    i = xml.find("<mujoco")
    return xml[:i] + head + xml[i:]
