"""Configuration -> compiled MuJoCo model, through ``mujoco.MjSpec`` edits of ``mjcf/bench.xml``.

What the builder does to the base model:

* options: timestep, integrator, solver, gravity from the orientation; contact detection is
  switched off entirely when no joint has a clearance;
* bodies: masses, centres of mass and inertias (Table 1), lengths, d_off, each joint's own pin
  radius, bore radius and bushing length (``joints.pin_radius(j)``, ``bushing_radius_m(j)``,
  ``bushing_length(j)``), accelerometer mounting sites;
* ideal joints A and B are hinges in the kinematic tree (exact); an ideal joint C is the
  loop-closure ``connect`` of the base model (stiff soft constraint);
* a clearance joint adds two slide joints (A: the crank journal relative to the frame's bore,
  bench frame, before the crank hinge, so that ``crank_hinge`` stays the absolute crank angle;
  B: rod eye relative to the crank pin, crank frame) or drops the connect (C), and adds one
  explicit frictionless ``<pair>`` pin/bushing (at A: ``pin_A`` on the crank, ``bushing_A`` on
  the world body) whose contact is computed by the native bore collider (exact circle). Its
  normal force is the reference's own contact law (``contact.law``: Lankarani–Nikravesh by default, Hunt–Crossley,
  Flores or linear, with the reference's K, n, e, impact-speed damping and floor), written
  into the bushing geom's user data and applied exactly by the native module, which sets the
  contact row's soft-constraint parameters every step (``_bore.c``: elastic term explicit as
  in the reference's symplectic Euler, damping by the θ-method, so no step limit); the pair's
  own solref/solimp are only the placeholder a plain MuJoCo would use. The reference's
  regularized Coulomb friction (μ0, v0, v1 of the ``contact`` section, also in the user data)
  is applied by the native module as a passive force. Why not MuJoCo's own friction cone: with
  soft contacts the elliptic cone adds μ × (the would-be sticking force) to the normal force
  while sliding; on test 12 that inflated the normal force by a median 23 % (up to 27×) over
  the k δ + c δ̇ law, and making the friction rows softer turned Coulomb friction into viscous
  friction (``analysis/friction_cone.py`` measures both);
* sensors: only those the configuration's channel groups need (the accelerometers not at all
  with ``mujoco.accelerometers = "posthoc"``, the default: the engine computes them from the
  recorded state, :mod:`twin.mujoco_engine.accel`; the optional "energy" group
  adds ``e_kinetic``/``e_potential`` sensors and the slider's velocity, and switches on
  MuJoCo's energy computation, ``mjENBL_ENERGY``);
* the crank PID gains.

Contact of a clearance joint: :func:`twin.physics.mujoco_params.contact_setting` (the native
reference law :class:`~twin.physics.mujoco_params.NativeLaw`, or MuJoCo's own soft contact), shared
with the spatial MuJoCo model. The former calibration table (a fitted two-pair solref/solimp law)
is retired: the law is now exact by construction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco

import twin.mujoco_log  # noqa: F401 - MuJoCo's warnings kept off the terminal and the folder
import numpy as np

from twin import names as mjcf_names
from twin.config import JOINTS, BenchConfig
from twin.errors import ModelError, TwinError
from twin.mujoco_engine.accel import posthoc_applies
from twin.mujoco_engine import drivetrain, flexible
from twin.mujoco_engine import guide as guide_clearance
from twin.native.collider import as_passive_force, check_model, ensure_installed
from twin.physics.mujoco_params import ContactSetting, contact_setting, native_law_applies, prescribed_armature
from twin.tracefile import DriveInputs

#: frictionless MuJoCo contact; friction is the native passive force (see module docstring)
_CONDIM = 1

_SENSORS_BY_GROUP = {
    "accel": list(mjcf_names.ACCEL_SENSORS),
    "encoder": [mjcf_names.SENSOR_CRANK_ANGLE],
    "crank": [mjcf_names.SENSOR_CRANK_ANGLE, mjcf_names.SENSOR_CRANK_SPEED],
    "slider": [mjcf_names.SENSOR_SLIDER_POSITION],
    "drive": [mjcf_names.SENSOR_CRANK_TORQUE],
}

_AXIS_QUAT = {  # site orientation whose x axis is the sensitive axis (rotation about z)
    "+x": (1.0, 0.0, 0.0, 0.0),
    "+y": (math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)),
    "-x": (0.0, 0.0, 0.0, 1.0),
    "-y": (math.sqrt(0.5), 0.0, 0.0, -math.sqrt(0.5)),
}


@dataclass
class BuildInfo:
    """What the builder decided, for run metadata and tests."""

    contacts: dict[str, ContactSetting] = field(default_factory=dict)
    sensors: list[str] = field(default_factory=list)
    a_hat: dict[str, float] = field(default_factory=dict)


# --------------------------------------------------------------------------- builder
def _set_inertial(body: mujoco.MjsBody, mass: float, ipos, izz: float) -> None:
    body.explicitinertial = True
    body.mass = mass
    body.ipos = list(ipos)
    body.iquat = [1.0, 0.0, 0.0, 0.0]
    # planar mechanism: only I_zz acts; the off-plane values keep the tensor valid
    body.inertia = [izz / 2, izz / 2, izz]


def solver_name(cfg: BenchConfig) -> str:
    """The constraint solver of the configuration's model: ``mujoco.flexible_solver`` with the flexible
    structure, ``mujoco.solver`` otherwise."""
    return cfg.mujoco.flexible_solver if cfg.structure.flexible else cfg.mujoco.solver


def build_spec(cfg: BenchConfig) -> mujoco.MjSpec:
    """Edited (uncompiled) spec of the configuration; contact pairs without final solref."""
    try:
        if flexible.applies(cfg):  # the flexible structure's bodies nested into the base model
            flexible.check(cfg)
            spec = mujoco.MjSpec.from_string(flexible.flexible_xml(cfg))
        else:
            spec = mujoco.MjSpec.from_file(str(mjcf_names.BASE_XML))
    except Exception as err:  # mujoco raises ValueError with the parser message
        if isinstance(err, TwinError):
            raise
        raise ModelError(f"cannot load base model {mjcf_names.BASE_XML}: {err}") from None
    spec.modelname = f"slider_crank_bench_{cfg.name}"
    b, j, mech = cfg.bodies, cfg.joints, cfg.mechanism
    r, l = b.crank.length_m, b.rod.length_m

    # options
    opt = spec.option
    opt.timestep = cfg.simulation.timestep_s
    opt.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{cfg.mujoco.integrator.upper()}")
    opt.solver = getattr(mujoco.mjtSolver, f"mjSOL_{solver_name(cfg).upper()}")
    opt.iterations = cfg.mujoco.iterations
    opt.tolerance = cfg.mujoco.tolerance
    opt.gravity = list(mech.gravity_vector)
    if not j.clearance_joints:
        opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT

    # crank
    crank = spec.body(mjcf_names.CRANK)
    _set_inertial(crank, b.crank.mass_kg, (b.crank.x_g_m, 0, 0), b.crank.inertia_kgm2)
    arm = spec.geom(mjcf_names.CRANK_ARM)
    arm.size = [r / 2 + 0.015, arm.size[1], arm.size[2]]
    arm.pos = [r / 2 - 0.01, 0, 0]
    z = spec.geom(mjcf_names.pin("B")).pos[2]
    for obj in (spec.geom(mjcf_names.pin("B")), spec.site(mjcf_names.pin("B"))):
        obj.pos = [r, 0, z]

    # rod (frame at the bushing centre B', x towards C)
    rod = spec.body(mjcf_names.ROD)
    rod.pos = [r, 0, z]
    _set_inertial(rod, b.rod.mass_kg, (b.rod.x_g_m, 0, 0), b.rod.inertia_kgm2)
    beam = spec.geom(mjcf_names.ROD_BEAM)
    beam.size = [l / 2 - 0.03, beam.size[1], beam.size[2]]
    beam.pos = [l / 2, 0, 0]
    for name in (mjcf_names.bushing("C"), mjcf_names.bushing_ring("C")):
        spec.geom(name).pos = [l, 0, 0]
    spec.site(mjcf_names.bushing("C")).pos = [l, 0, 0]

    # slider (frame at Cs on the guide line; C' is d_off above it)
    slider = spec.body(mjcf_names.SLIDER)
    _set_inertial(slider, b.slider.mass_kg, (b.slider.x_g_m, mech.d_off_m, 0), b.slider.inertia_kgm2)
    guide = spec.joint(mjcf_names.SLIDER_SLIDE)
    guide.solref_friction = list(cfg.mujoco.guide_solreffriction)
    if cfg.mujoco.guide_friction == "native":
        # the reference's regularized Coulomb guide friction, a passive force of the native module
        guide.frictionloss = 0.0
        spec.nuser_jnt = len(mjcf_names.GUIDE_USERDATA_FIELDS)
        guide.userdata = mjcf_names.guide_userdata(mech.guide_friction_n, cfg.contact.v0_mps, cfg.contact.v1_mps)
    else:
        guide.frictionloss = mech.guide_friction_n
    for obj in (spec.geom(mjcf_names.pin("C")), spec.site(mjcf_names.pin("C"))):
        obj.pos = [0, mech.d_off_m, 0]
    block = spec.geom(mjcf_names.SLIDER_BLOCK)
    block.size = [b.slider.length_m / 2, block.size[1], block.size[2]]

    # pins, bushings (user data: bore marker and friction law, layout mjcf_names.BORE_USERDATA_FIELDS)
    # and their visual rings; the contact law is MuJoCo's solref/solimp unless build() writes
    # the native law
    con = cfg.contact
    if con.friction_law == "adams":  # Adams/COSMOS: mu_d = mu0, v_s, v_d in v0, v1 (mjcf_names.BORE_USERDATA_FIELDS)
        friction_law = mjcf_names.bore_userdata(mu0=con.mu0, v0=con.v_static_mps, v1=con.v_kinetic_mps,
                                       friction=mjcf_names.BORE_FRICTION_LAWS["adams"], mus=con.mu_static)
    else:
        friction_law = mjcf_names.bore_userdata(mu0=con.mu0, v0=con.v0_mps, v1=con.v1_mps)
    for jt in JOINTS:  # each joint's own pin radius and bushing length
        half_len = j.bushing_length(jt) / 2
        spec.geom(mjcf_names.pin(jt)).size = [j.pin_radius(jt), half_len, 0]
        spec.geom(mjcf_names.bushing(jt)).size = [j.bushing_radius_m(jt), half_len, 0]
        spec.geom(mjcf_names.bushing(jt)).userdata = friction_law
        spec.geom(mjcf_names.bushing_ring(jt)).size = [j.bushing_radius_m(jt) + 0.006, half_len * 1.05, 0]

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

    # clearance joint A: crank journal free in the plane of the frame's bore. The slides come
    # before the hinge (re-added last), so the crank frame is translate(e_A) rotate(θ) and the
    # hinge angle stays the absolute crank angle the PID, the encoder and crank_angle read
    if j.diametral_mm("A") > 0:
        spec.delete(spec.joint(mjcf_names.CRANK_HINGE))
        crank.add_joint(name=mjcf_names.ECC_A_X, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
        crank.add_joint(name=mjcf_names.ECC_A_Y, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0])
        crank.add_joint(name=mjcf_names.CRANK_HINGE, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    # clearance joint B: rod eye free in the plane relative to the crank pin
    if j.diametral_mm("B") > 0:
        spec.delete(spec.joint(mjcf_names.ROD_HINGE))
        rod.add_joint(name=mjcf_names.ECC_B_X, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
        rod.add_joint(name=mjcf_names.ECC_B_Y, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0])
        rod.add_joint(name=mjcf_names.ROD_HINGE, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    # clearance joint C: no loop-closure constraint, the contact holds the rod on the pin
    eq = spec.equality(mjcf_names.JOINT_C_CONNECT)
    if j.diametral_mm("C") > 0:
        spec.delete(eq)
    else:
        eq.solref = list(cfg.mujoco.equality_solref)
        eq.solimp = list(cfg.mujoco.equality_solimp)
    for jt in j.clearance_joints:
        spec.add_pair(name=mjcf_names.pair(jt), geomname1=mjcf_names.pin(jt), geomname2=mjcf_names.bushing(jt), condim=_CONDIM)

    # sensors: keep only what the channel groups need
    keep: set[str] = set()
    for g in cfg.sensors.channels:
        keep.update(_SENSORS_BY_GROUP.get(g, []))
        if g == "joints":
            for jt in j.clearance_joints:
                keep.update((mjcf_names.sensor_ecc(jt), mjcf_names.sensor_contact(jt), mjcf_names.sensor_friction(jt)))
    if posthoc_applies(cfg):
        # accelerometers from the recorded state after the rollout (twin.mujoco_engine.accel):
        # no sensor asks for mj_rnePostConstraint every step; their sites stay
        keep.difference_update(mjcf_names.ACCEL_SENSORS)
    for s in list(spec.sensors):
        if s.name not in keep:
            spec.delete(s)
    if "energy" in cfg.sensors.channels:
        # optional energy group: MuJoCo computes energies only with the energy flag on
        opt.enableflags |= mujoco.mjtEnableBit.mjENBL_ENERGY
        spec.add_sensor(name=mjcf_names.SENSOR_ENERGY_KINETIC, type=mujoco.mjtSensor.mjSENS_E_KINETIC)
        spec.add_sensor(name=mjcf_names.SENSOR_ENERGY_POTENTIAL, type=mujoco.mjtSensor.mjSENS_E_POTENTIAL)
        spec.add_sensor(name=mjcf_names.SENSOR_SLIDER_SPEED, type=mujoco.mjtSensor.mjSENS_JOINTVEL,
                        objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=mjcf_names.SLIDER_SLIDE)

    # crank PID (native <pid>: gainprm = ki, biasprm = [0, -kp, -kv], dynprm = imax)
    act = spec.actuator(mjcf_names.CRANK_PID)
    act.gainprm[0] = cfg.pid.ki
    act.biasprm[1], act.biasprm[2] = -cfg.pid.kp, -cfg.pid.kv
    act.dynprm[0] = cfg.pid.imax
    if cfg.drive.mode == "prescribed":
        _prescribed_drive(spec, cfg)
    if guide_clearance.applies(cfg):
        guide_clearance.add_guide(spec, cfg)
    if drivetrain.applies(cfg):
        drivetrain.add_drive_train(spec, cfg)
    if flexible.applies(cfg):
        flexible.finish(spec, cfg)
    return spec


def _prescribed_drive(spec: mujoco.MjSpec, cfg: BenchConfig) -> None:
    """The prescribed (infinitely stiff) crank drive (``drive.mode = "prescribed"``).

    MuJoCo has no rheonomic constraint (its equality constraints are soft, and their data are
    not inputs of ``mujoco.rollout``), so the crank is made an infinitely heavy flywheel: armature
    A (:func:`~twin.physics.mujoco_params.prescribed_armature`), so that the mechanism's loads cannot move it and every
    constraint and contact sees it as a body of prescribed motion, driven by the native ``<pid>``
    actuator turned into a dead-beat law: kp = A/h², kv = A/h, ki = 0, with the control
    [θ_ref(t + h), 0]: τ = A [(θ_ref(t + h) − θ)/h² − θ̇/h], so that Euler's update
    θ̇ ← θ̇ + h θ̈, θ ← θ + h θ̇ lands on θ_ref(t + h) (to h² (τ_load − I θ̈)/A and round-off).
    The drive torque the mechanism receives is τ − A θ̈ (``crank_torque``; θ̈ from a
    ``frameangacc`` sensor of the crank). The solver's tolerance scale (``stat.meaninertia``, the
    mean of M's diagonal) is set back to the mechanism's own in :func:`_compile`."""
    A = prescribed_armature(cfg)
    h = cfg.simulation.timestep_s
    spec.joint(mjcf_names.CRANK_HINGE).armature = A
    act = spec.actuator(mjcf_names.CRANK_PID)
    act.gainprm[0] = 0.0
    act.biasprm[1], act.biasprm[2] = -A / h ** 2, -A / h
    act.dyntype = mujoco.mjtDyn.mjDYN_NONE  # no integral state (MuJoCo refuses a stateful pid with ki = 0)
    if "drive" in cfg.sensors.channels:
        spec.add_sensor(name=mjcf_names.SENSOR_CRANK_ANGACC, type=mujoco.mjtSensor.mjSENS_FRAMEANGACC,
                        objtype=mujoco.mjtObj.mjOBJ_BODY, objname=mjcf_names.CRANK)


def _compile(spec: mujoco.MjSpec, cfg: BenchConfig) -> mujoco.MjModel:
    try:
        model = spec.compile()
    except Exception as err:
        why = " ".join(str(err).split())  # MuJoCo's message spans lines: one line
        raise ModelError(f"MuJoCo could not compile the model of {cfg.name} (check bodies.*, joints.*, "
                         f"mechanism.*): {why}") from None
    if cfg.drive.mode == "prescribed":
        # the solver scales its tolerance by 1/meaninertia (mean of M's diagonal at qpos0): the
        # flywheel's armature would make every improvement look negligible
        model.stat.meaninertia -= prescribed_armature(cfg) / model.nv
    if model.nuser_geom != len(mjcf_names.BORE_USERDATA_FIELDS):  # _bore.c reads the user data by this layout
        raise ModelError(f"the model of {cfg.name} has nuser_geom = {model.nuser_geom}, the bore user data layout "
                         f"{len(mjcf_names.BORE_USERDATA_FIELDS)} fields {mjcf_names.BORE_USERDATA_FIELDS} (twin.names); "
                         f"fix <size nuser_geom> in {mjcf_names.BASE_XML}")
    return model


def _ring(spec: mujoco.MjSpec, cfg: BenchConfig, jt: str) -> list[str]:
    """Replace the bore of ``jt`` by ``mujoco.ring_boxes`` boxes on the bushing's body (the rod;
    the world body at A); returns the box names."""
    n = cfg.mujoco.ring_boxes
    bush = spec.geom(mjcf_names.bushing(jt))
    centre = np.array(bush.pos)
    ri = cfg.joints.bushing_radius_m(jt)
    half_w, t = ri * math.tan(math.pi / n), 1e-3
    names = []
    for k in range(n):
        beta = 2 * math.pi * k / n
        g = bush.parent.add_geom(
            name=f"{mjcf_names.bushing(jt)}_box{k}", type=mujoco.mjtGeom.mjGEOM_BOX, size=[t, half_w, cfg.joints.bushing_length(jt) / 2],
            pos=list(centre + (ri + t) * np.array([math.cos(beta), math.sin(beta), 0.0])),
            quat=[math.cos(beta / 2), 0.0, 0.0, math.sin(beta / 2)], contype=0, conaffinity=0, mass=0, group=3)
        names.append(g.name)
    return names


def build(cfg: BenchConfig, *, inputs: DriveInputs | None = None) -> tuple[mujoco.MjSpec, mujoco.MjModel, BuildInfo]:
    """Spec, compiled model and build info of a configuration (collider installed).

    The bushing representation (``mujoco.bushing``) and the friction model
    (``mujoco.friction``) are applied here: "bore" keeps the base model's pair; "ring"
    replaces it by one pair per box; "tendon" by a distance-limited tendon. The bore takes the
    native reference law (:func:`~twin.physics.mujoco_params.native_law_applies`); the others MuJoCo's soft contact with the
    first guess's (k, c, solimp), converted with each row's Â.
    """
    ensure_installed()
    ms = cfg.mujoco
    spec = build_spec(cfg)
    info = BuildInfo()
    if not cfg.joints.clearance_joints:
        info.sensors = [x.name for x in spec.sensors]
        if guide_clearance.applies(cfg):
            guide_clearance.finish(spec, cfg, _compile(spec, cfg))
        if drivetrain.applies(cfg):
            drivetrain.finish(spec, cfg, _compile(spec, cfg))
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
            spec.delete(spec.pair(mjcf_names.pair(jt)))
            rings[jt] = _ring(spec, cfg, jt)
            for k, box in enumerate(rings[jt]):
                spec.add_pair(name=f"{mjcf_names.pair(jt)}_{k}", geomname1=mjcf_names.pin(jt), geomname2=box, condim=3,
                              friction=[cfg.contact.mu0, cfg.contact.mu0, 0, 0, 0])
            if spec.sensor(mjcf_names.sensor_contact(jt)) is not None:
                sc = spec.sensor(mjcf_names.sensor_contact(jt))
                sc.reftype, sc.refname = mujoco.mjtObj.mjOBJ_BODY, spec.geom(mjcf_names.bushing(jt)).parent.name
                sc.intprm = [3, 3, 1]  # found + force, reduce = netforce (global frame), one slot
        elif ms.bushing == "tendon":
            spec.delete(spec.pair(mjcf_names.pair(jt)))
            t = spec.add_tendon(name=mjcf_names.pair(jt), limited=True, range=[0.0, cfg.joints.radial_m(jt)])
            t.wrap_site(mjcf_names.pin(jt))
            t.wrap_site(mjcf_names.bushing(jt))
            if spec.sensor(mjcf_names.sensor_contact(jt)) is not None:
                sc = spec.sensor(mjcf_names.sensor_contact(jt))
                sc.type, sc.objtype, sc.objname = mujoco.mjtSensor.mjSENS_TENDONLIMITFRC, mujoco.mjtObj.mjOBJ_TENDON, mjcf_names.pair(jt)
                sc.reftype, sc.refname, sc.intprm = mujoco.mjtObj.mjOBJ_UNKNOWN, "", [0, 0, 0]
        elif ms.friction == "cone":
            p = spec.pair(mjcf_names.pair(jt))
            p.condim = 3
            p.friction = [cfg.contact.mu0, cfg.contact.mu0, 0, 0, 0]
        if ms.bushing != "bore" or ms.friction == "cone":
            bush = spec.geom(mjcf_names.bushing(jt))
            bush.userdata = mjcf_names.replace_bore_userdata(list(bush.userdata), mu0=0.0, mus=0.0)  # native friction off
            if spec.sensor(mjcf_names.sensor_friction(jt)) is not None:
                spec.delete(spec.sensor(mjcf_names.sensor_friction(jt)))
    model = _compile(spec, cfg)
    native = native_law_applies(cfg)
    force = native and ms.contact_source == "force"
    per_joint = 2 if force else 1  # force: v_imp and the previous step's normal velocity (_bore.c, "Force")
    if native:
        spec.nuserdata = per_joint * len(cfg.joints.clearance_joints)  # v_imp of each joint's contact event
    if force:
        # the law and friction as passive forces (_bore.c, "Force"): no pair, no collision at all
        # (the guide clearance is a passive force too), the contact sensor a user sensor the
        # passive callback fills with [found, normal force, 0, 0]
        spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    for slot, jt in enumerate(cfg.joints.clearance_joints):
        if ms.bushing == "tendon":
            a_hat = float(model.tendon_invweight0[model.tendon(mjcf_names.pair(jt)).id])
        else:
            a_hat = float(model.body_invweight0[model.geom_bodyid[model.geom(mjcf_names.pin(jt)).id], 0] +
                          model.body_invweight0[model.geom_bodyid[model.geom(mjcf_names.bushing(jt)).id], 0])
        setting = contact_setting(cfg, jt, a_hat, native=native, inputs=inputs)
        if ms.bushing == "tendon":
            t = spec.tendon(mjcf_names.pair(jt))
            t.solref_limit, t.solimp_limit = list(setting.solref), list(setting.solimp)
        elif jt in rings:
            for k in range(len(rings[jt])):
                p = spec.pair(f"{mjcf_names.pair(jt)}_{k}")
                p.solref, p.solimp = list(setting.solref), list(setting.solimp)
        else:
            p = spec.pair(mjcf_names.pair(jt))
            p.solref, p.solimp = list(setting.solref), list(setting.solimp)
            if spec.sensor(mjcf_names.sensor_contact(jt)) is not None:
                spec.sensor(mjcf_names.sensor_contact(jt)).intprm = [3, 0, 1]  # [found, force], one slot
            if setting.law is not None:
                bush = spec.geom(mjcf_names.bushing(jt))
                bush.userdata = mjcf_names.replace_bore_userdata(list(bush.userdata),
                                                                 **setting.law.userdata(per_joint * slot))
            if force:
                as_passive_force(spec, p, spec.geom(mjcf_names.bushing(jt)),
                                 int(model.geom(mjcf_names.pin(jt)).id), mjcf_names.sensor_contact(jt))
        info.contacts[jt] = setting
        info.a_hat[jt] = a_hat
    info.sensors = [x.name for x in spec.sensors]
    if guide_clearance.applies(cfg):
        guide_clearance.finish(spec, cfg, model)
    if drivetrain.applies(cfg):
        drivetrain.finish(spec, cfg, model)
    model = _compile(spec, cfg)
    check_model(model)  # the layout the native code reads, or a one-line refusal
    return spec, model, info


def export_xml(cfg: BenchConfig) -> str:
    """MJCF text of the configuration's compiled variant (opens in MuJoCo's viewer). It keeps
    MuJoCo's accelerometer sensors whatever ``mujoco.accelerometers`` says: a plain MuJoCo has no
    after-the-rollout path."""
    spec, _model, info = build(cfg.replace(**{"mujoco.accelerometers": "sensor"}))
    head = (f"<!-- twin export of '{cfg.name}' (config digest {cfg.digest()}).\n"
            f"     Clearance joints: {', '.join(cfg.joints.clearance_joints) or 'none'}; contact: "
            + "; ".join(f"{jt}: {s.law.law if s.law else s.source}" for jt, s in info.contacts.items())
            + ".\n     Bushing geoms (user=\"7301 ...\") need the twin's native bore collider, contact law and "
              "friction (twin/native/_bore.c):\n     a plain MuJoCo viewer shows and simulates ideal "
              "variants faithfully; simulate clearance variants with 'twin simulate'."
            + (f"\n     Drive train ({cfg.drive.mode}): the motor rotor, its command actuator and the numeric "
               "'drivetrain' are in the model;\n     the speed controller and the V-belt's pull act only through "
               "the twin's passive callback (twin/native/_drivetrain.h)."
               if cfg.drive.mode in ("motor", "torque") else "")
            + " -->\n")
    xml = _exact_geom_user(spec.to_xml(), _model)
    if flexible.applies(cfg):
        xml = flexible.exact_structure_numbers(xml, _model)
    i = xml.find("<mujoco")
    return xml[:i] + head + xml[i:]


def _exact_geom_user(xml: str, model: mujoco.MjModel) -> str:
    """``xml`` with each named geom's ``user`` attribute written from the compiled model at full
    precision. MuJoCo's XML writer (4.0) writes a vector's entries below about 1e-12 of its largest
    as 0: a bore's friction fields (μ0 = 0.05, v0, v1) and impact-speed floor came out as 0 beside
    its K ~ 1e11."""
    import re

    if not model.nuser_geom:
        return xml
    for g in range(model.ngeom):
        name = model.geom(g).name
        if not name:
            continue
        values = " ".join(repr(float(v)).removesuffix(".0") for v in model.geom_user[g])  # shortest exact
        tag = re.compile(r'(<geom\b[^>]*?\bname="' + re.escape(name) + r'"[^>]*?\buser=")[^"]*(")')
        xml = tag.sub(lambda mt: mt.group(1) + values + mt.group(2), xml, count=1)
    return xml
