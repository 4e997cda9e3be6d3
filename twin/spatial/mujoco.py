"""The spatial slider–crank of S002 in MuJoCo (``twin simulate --preset s002 --engine mujoco``).

Built with ``mujoco.MjSpec`` from the configuration (no base MJCF: nothing of the planar bench's file
applies), in the spatial frame of :mod:`twin.config.spatial`:

* crank: hinge about x (with a radial clearance at A: two slides, y and z, before it), its journal a
  cylinder along x, at B a socket (a sphere marked as a socket);
* rod: a free body (its frame at the ball B, x along B → C) with a ball at each end; an ideal B or C
  is a ``<connect>`` equality (stiff soft constraint, ``mujoco.equality_solref``/``_solimp``);
* slider: a slide along the guide, a socket at C;
* the base bearing A: a cylinder of the world marked as a bore (the pin-in-bore collider of
  ``_bore.c``); the spherical joints: the ball-in-socket collider of ``_socket.c``; one frictionless
  pair per joint, the reference's contact law and regularized Coulomb friction applied natively (the
  same numbers as :mod:`twin.spatial.engine`, :func:`twin.physics.mujoco_params.native_law`);
* the prescribed drive of the bench's twin: the crank hinge a flywheel of armature
  :data:`~twin.physics.mujoco_params.PRESCRIBED_ARMATURE_FACTOR` × its inertia, driven by a dead-beat
  affine actuator onto θ_ref(t + h) (as the planar MuJoCo model's prescribed drive).

Channels as the spatial reference (:mod:`twin.spatial.engine`); ``slider_acceleration`` from an
accelerometer on the slider (its axis along the guide, gravity's component removed).
"""

from __future__ import annotations

import math
import time
from typing import Any

import mujoco

import twin.mujoco_log  # noqa: F401 - MuJoCo's warnings kept off the terminal and the folder
import numpy as np
from mujoco import rollout

from twin import __version__ as twin_version
from twin import names
from twin.errors import ConfigError, ModelError, SimulationError
from twin.physics.mujoco_params import contact_setting, prescribed_armature
from twin.tracefile import DriveInputs
from twin.spatial import geometry as spatial_geometry

_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
#: MJCF names of the spatial model
CRANK, ROD, SLIDER = "spatial_crank", "spatial_rod", "spatial_slider"
HINGE, SLIDE_Y, SLIDE_Z, SLIDER_SLIDE, ROD_FREE = ("spatial_crank_hinge", "spatial_ecc_A_y", "spatial_ecc_A_z",
                                                   "spatial_slider_slide", "spatial_rod_free")
DRIVE = "spatial_drive"
#: pin (journal / ball) and bushing (bore / socket) geoms of each joint
PIN = {"A": "spatial_journal_A", "B": "spatial_ball_B", "C": "spatial_ball_C"}
BUSH = {"A": "spatial_bore_A", "B": "spatial_socket_B", "C": "spatial_socket_C"}
#: rod spin: axial moment of inertia of a 10 mm round rod, m r²/2 (PLACEHOLDER: nothing excites the
#: spin, every force on the rod passes through the ball centres on its axis)
ROD_RADIUS_M = 0.005
_Z_TO_X = [math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0]   # a cylinder's axis (z) along world x


def _quat_x_to(u: np.ndarray) -> list[float]:
    """Unit quaternion rotating +x onto the unit vector u."""
    x = np.array([1.0, 0.0, 0.0])
    c = float(x @ u)
    axis = np.cross(x, u)
    s = float(np.linalg.norm(axis))
    if s < 1e-15:
        return [1.0, 0.0, 0.0, 0.0] if c > 0 else [0.0, 0.0, 0.0, 1.0]
    ang = math.atan2(s, c)
    axis /= s
    return [math.cos(ang / 2), *(math.sin(ang / 2) * axis)]


def _spec(cfg: Any, theta0: float) -> mujoco.MjSpec:
    b, j, h = cfg.bodies, cfg.joints, cfg.simulation.timestep_s
    spec = mujoco.MjSpec()
    spec.modelname = "spatial_slider_crank"
    o = spec.option
    o.timestep = h
    o.integrator = mujoco.mjtIntegrator.mjINT_EULER
    o.solver = mujoco.mjtSolver.mjSOL_NEWTON
    o.iterations, o.tolerance = 20, 1e-10
    o.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    o.gravity = list(cfg.mechanism.gravity_vector)
    o.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_ISLAND) | int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP)
    spec.nuser_geom = len(names.BORE_USERDATA_FIELDS)
    spec.nuser_jnt = len(names.GUIDE_USERDATA_FIELDS)
    world = spec.worldbody
    geom_kw = dict(contype=0, conaffinity=0, mass=0.0)
    q0 = spatial_geometry.ideal_coordinates(cfg, theta0)
    r, L = b.crank.length_m, b.rod.length_m

    # base bearing A
    if j.diametral_mm("A") > 0:
        world.add_geom(name=BUSH["A"], type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[j.bushing_radius_m("A"), 0.01, 0],
                       quat=_Z_TO_X, **geom_kw)
    # crank
    crank = world.add_body(name=CRANK)
    crank.explicitinertial = True
    crank.mass, crank.ipos = b.crank.mass_kg, [0.0, b.crank.x_g_m, 0.0]
    crank.inertia = [b.crank.inertia_kgm2, b.crank.inertia_kgm2 / 2, b.crank.inertia_kgm2 / 2]
    if j.diametral_mm("A") > 0:
        crank.add_joint(name=SLIDE_Y, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0])
        crank.add_joint(name=SLIDE_Z, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
    crank.add_joint(name=HINGE, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[1, 0, 0], armature=prescribed_armature(cfg))
    crank.add_geom(name=PIN["A"], type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[j.pin_radius("A"), 0.01, 0],
                   quat=_Z_TO_X, **geom_kw)
    crank.add_geom(name=BUSH["B"], type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[j.bushing_radius_m("B"), 0, 0],
                   pos=[0, r, 0], **geom_kw)
    crank.add_site(name="spatial_crank_B", pos=[0, r, 0])
    # rod: a free body at the ball B, x along B -> C
    u = (q0[spatial_geometry.ICR:spatial_geometry.ICR + 3] - q0[spatial_geometry.IBR:spatial_geometry.IBR + 3]) / L
    rod = world.add_body(name=ROD, pos=list(q0[spatial_geometry.IBR:spatial_geometry.IBR + 3]), quat=_quat_x_to(u))
    rod.add_freejoint(name=ROD_FREE)
    rod.explicitinertial = True
    rod.mass, rod.ipos = b.rod.mass_kg, [b.rod.x_g_m, 0.0, 0.0]
    rod.inertia = [b.rod.mass_kg * ROD_RADIUS_M ** 2 / 2, b.rod.inertia_kgm2, b.rod.inertia_kgm2]
    rod.add_geom(name=PIN["B"], type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[j.pin_radius("B"), 0, 0], **geom_kw)
    rod.add_geom(name=PIN["C"], type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[j.pin_radius("C"), 0, 0], pos=[L, 0, 0],
                 **geom_kw)
    rod.add_site(name="spatial_rod_B")
    rod.add_site(name="spatial_rod_C", pos=[L, 0, 0])
    # slider on the guide
    p0, g = spatial_geometry.guide(cfg)
    slider = world.add_body(name=SLIDER, pos=list(p0), quat=_quat_x_to(g))
    slider.explicitinertial = True
    slider.mass, slider.ipos = b.slider.mass_kg, [0.0, 0.0, 0.0]
    slider.inertia = [b.slider.inertia_kgm2] * 3
    sj = slider.add_joint(name=SLIDER_SLIDE, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
    if cfg.mechanism.guide_friction_n > 0:
        sj.userdata = names.guide_userdata(cfg.mechanism.guide_friction_n, cfg.contact.v0_mps, cfg.contact.v1_mps)
    slider.add_geom(name=BUSH["C"], type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[j.bushing_radius_m("C"), 0, 0],
                    **geom_kw)
    slider.add_site(name="spatial_slider_C")
    slider.add_site(name="spatial_slider_acc")
    # ideal spherical joints: connect equalities
    for jt, s1, s2 in (("B", "spatial_rod_B", "spatial_crank_B"), ("C", "spatial_rod_C", "spatial_slider_C")):
        if j.diametral_mm(jt) == 0:
            spec.add_equality(name=f"spatial_joint_{jt}", type=mujoco.mjtEq.mjEQ_CONNECT,
                              objtype=mujoco.mjtObj.mjOBJ_SITE, name1=s1, name2=s2,
                              solref=list(cfg.mujoco.equality_solref), solimp=list(cfg.mujoco.equality_solimp))
    # prescribed drive: dead-beat affine actuator onto theta_ref(t + h)
    A = prescribed_armature(cfg)
    act = spec.add_actuator(name=DRIVE, target=HINGE, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    act.gaintype, act.biastype = mujoco.mjtGain.mjGAIN_FIXED, mujoco.mjtBias.mjBIAS_AFFINE
    act.gainprm[0] = A / h ** 2
    act.biasprm[0], act.biasprm[1], act.biasprm[2] = 0.0, -A / h ** 2, -A / h
    act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
    # sensors
    S = mujoco.mjtSensor
    spec.add_sensor(name="s_theta", type=S.mjSENS_JOINTPOS, objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=HINGE)
    spec.add_sensor(name="s_omega", type=S.mjSENS_JOINTVEL, objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=HINGE)
    spec.add_sensor(name="s_slider", type=S.mjSENS_JOINTPOS, objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=SLIDER_SLIDE)
    spec.add_sensor(name="s_acc", type=S.mjSENS_ACCELEROMETER, objtype=mujoco.mjtObj.mjOBJ_SITE,
                    objname="spatial_slider_acc")
    spec.add_sensor(name="s_torque", type=S.mjSENS_ACTUATORFRC, objtype=mujoco.mjtObj.mjOBJ_ACTUATOR, objname=DRIVE)
    spec.add_sensor(name="s_angacc", type=S.mjSENS_FRAMEANGACC, objtype=mujoco.mjtObj.mjOBJ_BODY, objname=CRANK)
    for jt in j.clearance_joints:
        spec.add_sensor(name=f"s_pin_{jt}", type=S.mjSENS_FRAMEPOS, objtype=mujoco.mjtObj.mjOBJ_GEOM, objname=PIN[jt])
        spec.add_sensor(name=f"s_bush_{jt}", type=S.mjSENS_FRAMEPOS, objtype=mujoco.mjtObj.mjOBJ_GEOM,
                        objname=BUSH[jt])
        spec.add_sensor(name=f"s_contact_{jt}", type=S.mjSENS_CONTACT, objtype=mujoco.mjtObj.mjOBJ_GEOM,
                        objname=PIN[jt], reftype=mujoco.mjtObj.mjOBJ_GEOM, refname=BUSH[jt], intprm=[3, 0, 1])
        spec.add_sensor(name=f"s_friction_{jt}", type=S.mjSENS_USER, objtype=mujoco.mjtObj.mjOBJ_GEOM,
                        objname=BUSH[jt], dim=1, needstage=mujoco.mjtStage.mjSTAGE_POS,
                        datatype=mujoco.mjtDataType.mjDATATYPE_REAL)
    return spec


def _compile(spec: mujoco.MjSpec, cfg: Any) -> mujoco.MjModel:
    try:
        model = spec.compile()
    except Exception as err:
        raise ModelError(f"MuJoCo could not compile the spatial model of {cfg.name}: {err}") from None
    model.stat.meaninertia -= prescribed_armature(cfg) / model.nv  # the flywheel must not set the solver's scale
    return model


def build(cfg: Any, theta0: float) -> tuple[mujoco.MjSpec, mujoco.MjModel, dict[str, Any]]:
    """(spec, model, contacts) of the spatial mechanism at crank angle θ0 [rad]: pairs, native laws."""
    from twin.native.collider import check_model, ensure_installed

    if cfg.contact.law == "linear":
        raise ConfigError("contact.law", "the linear law is not available for the spatial mechanism; use a "
                                         "hysteresis law or adams-impact")
    if cfg.mujoco.bushing != "bore" or cfg.mujoco.contact_source not in ("law", "force"):
        raise ConfigError("mujoco.bushing", "the spatial mechanism takes the native law on its own colliders or as "
                                            "passive forces only (mujoco.bushing = \"bore\", mujoco.contact_source = "
                                            "\"law\" or \"force\")")
    ensure_installed()
    spec = _spec(cfg, theta0)
    joints = cfg.joints.clearance_joints
    # "force": the law and friction as passive forces between pin and bore/socket (_bore.c, "Force"; a
    # socket's point at the ball's centre, its friction along the slip, as the collider's contact), no pair,
    # no collision; 2 user data slots per joint (v_imp and the previous step's normal velocity)
    force = cfg.mujoco.contact_source == "force"
    per_joint = 2 if force else 1
    for jt in joints:
        spec.add_pair(name=f"spatial_pair_{jt}", geomname1=PIN[jt], geomname2=BUSH[jt], condim=1)
    model = _compile(spec, cfg)
    spec.nuserdata = per_joint * len(joints)
    if force:
        spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    contacts: dict[str, Any] = {}
    for slot, jt in enumerate(joints):
        a_hat = float(model.body_invweight0[model.geom_bodyid[model.geom(PIN[jt]).id], 0]
                      + model.body_invweight0[model.geom_bodyid[model.geom(BUSH[jt]).id], 0])
        setting = contact_setting(cfg, jt, a_hat, native=True)
        p = spec.pair(f"spatial_pair_{jt}")
        p.solref, p.solimp = list(setting.solref), list(setting.solimp)
        spec.geom(BUSH[jt]).userdata = names.bore_userdata(mu0=cfg.contact.mu0, v0=cfg.contact.v0_mps,
                                                       v1=cfg.contact.v1_mps, **setting.law.userdata(per_joint * slot))
        if force:
            from twin.native.collider import as_passive_force

            as_passive_force(spec, p, spec.geom(BUSH[jt]), int(model.geom(PIN[jt]).id), f"s_contact_{jt}")
        contacts[jt] = {"kind": "journal in bearing" if jt == "A" else "ball in socket", **setting.to_json()}
    model = _compile(spec, cfg)
    check_model(model)  # the layout the native code reads, or a one-line refusal
    return spec, model, contacts


class SpatialMujocoEngine:
    """MuJoCo engine of the spatial mechanism (module docstring); one ``mujoco.rollout`` per chunk."""

    name = "mujoco"

    def __init__(self, cfg: Any, *, inputs: DriveInputs | None = None):
        from twin.drive import DriveReference

        self.cfg = cfg
        self._drive = DriveReference(cfg, inputs)
        t0 = time.perf_counter()
        theta0 = float(self._drive(np.array([0.0]))[0][0])
        self.spec, self.model, contacts = build(cfg, theta0)
        self.theta0 = theta0
        self.data = mujoco.MjData(self.model)
        self.meta: dict[str, Any] = {
            "engine": self.name, "engine_version": f"mujoco {mujoco.__version__} (twin {twin_version})",
            "mechanism": "spatial slider-crank (S002)", "timestep_s": cfg.simulation.timestep_s,
            "integrator": "Euler", "steps": 0, "wall_s": 0.0, "build_s": time.perf_counter() - t0,
            "contact": contacts,
            "drive": f"prescribed: crank armature {prescribed_armature(cfg):.6g} kg m^2, dead-beat law",
        }
        m = self.model
        self._adr = {s: (int(m.sensor_adr[m.sensor(s).id]), int(m.sensor_dim[m.sensor(s).id]))
                     for s in (m.sensor(i).name for i in range(m.nsensor))}
        self._sens = np.empty((1, 0, m.nsensordata))
        self._k = 0

    def reset(self, theta0: float | None = None) -> None:
        """The mechanism at crank angle θ0 (None: the drive's) turning at the program's start rate,
        every clearance joint centred."""
        m, d, cfg = self.model, self.data, self.cfg
        th = self.theta0 if theta0 is None else float(theta0)
        if abs(th - self.theta0) > 1e-12:
            raise SimulationError(f"{cfg.name}: the spatial MuJoCo model is built at its drive's initial angle")
        mujoco.mj_resetData(m, d)
        d.userdata[:] = 0.0
        omega = self._drive.start_rate()
        q = spatial_geometry.ideal_coordinates(cfg, th)
        v = spatial_geometry.ideal_velocities(cfg, th, omega)
        L = cfg.bodies.rod.length_m
        d.qpos[m.jnt_qposadr[m.joint(HINGE).id]] = th
        d.qvel[m.jnt_dofadr[m.joint(HINGE).id]] = omega
        # the rod's free joint: position of its frame (ball B), orientation x along B -> C (body quat at
        # build time is the same pose: qpos quaternion = the body's world orientation)
        fa, fv = m.jnt_qposadr[m.joint(ROD_FREE).id], m.jnt_dofadr[m.joint(ROD_FREE).id]
        u = (q[spatial_geometry.ICR:spatial_geometry.ICR + 3] - q[spatial_geometry.IBR:spatial_geometry.IBR + 3]) / L
        d.qpos[fa:fa + 3] = q[spatial_geometry.IBR:spatial_geometry.IBR + 3]
        d.qpos[fa + 3:fa + 7] = _quat_x_to(u)
        vb, vc = v[spatial_geometry.IBR:spatial_geometry.IBR + 3], v[spatial_geometry.ICR:spatial_geometry.ICR + 3]
        w = np.cross(u, (vc - vb) / L)  # the rod's angular velocity (no spin)
        R = np.empty(9)
        mujoco.mju_quat2Mat(R, d.qpos[fa + 3:fa + 7])
        d.qvel[fv:fv + 3] = vb
        d.qvel[fv + 3:fv + 6] = R.reshape(3, 3).T @ w  # free joint: angular velocity in the body frame
        p0, g = spatial_geometry.guide(cfg)
        sa, sv = m.jnt_qposadr[m.joint(SLIDER_SLIDE).id], m.jnt_dofadr[m.joint(SLIDER_SLIDE).id]
        d.qpos[sa] = float((q[spatial_geometry.ICS:spatial_geometry.ICS + 3] - p0) @ g)
        d.qvel[sv] = float(v[spatial_geometry.ICS:spatial_geometry.ICS + 3] @ g)
        # the first step's control (the dead-beat drive onto theta_ref(h)), so that the forward pass's
        # accelerations, the solver's warm start of the first step, are the drive's and not a jump to 0
        d.ctrl[0] = float(self._drive(np.array([self.cfg.simulation.timestep_s]))[0][0])
        mujoco.mj_forward(m, d)
        self._k = 0

    def advance(self, theta_ref: np.ndarray, omega_ref: np.ndarray, stride: int) -> dict[str, np.ndarray]:
        """One ``mujoco.rollout`` over ``len(theta_ref)`` steps on the drive's program."""
        m, d, h = self.model, self.data, self.cfg.simulation.timestep_s
        nstep = len(theta_ref)
        if self._sens.shape[1] < nstep:
            self._sens = np.empty((1, nstep, m.nsensordata))
        sd = self._sens[:, :nstep]
        state0 = np.empty((1, mujoco.mj_stateSize(m, _STATE)))
        mujoco.mj_getState(m, d, state0[0], _STATE)
        nxt, _ = self._drive((self._k + 1 + np.arange(nstep)) * h)
        ctrl = np.ascontiguousarray(nxt[None, :, None])
        rollout.rollout(m, d, state0, ctrl, nstep=nstep, initial_warmstart=d.qacc_warmstart.copy()[None],
                        sensordata=sd)
        t_end = (self._k + nstep) * h
        if not math.isclose(d.time, t_end, rel_tol=0, abs_tol=h * 0.5) or not np.all(np.isfinite(sd)):
            raise SimulationError(f"{self.cfg.name}: the spatial MuJoCo run diverged between t = {self._k * h:.6f} s "
                                  f"and {t_end:.6f} s (MuJoCo stopped at {d.time:.6f} s); try a smaller timestep")
        self._k += nstep
        return self._channels(sd[0, ::stride])

    def _col(self, s: np.ndarray, name: str, k: int = 0) -> np.ndarray:
        return s[:, self._adr[name][0] + k]

    def _channels(self, s: np.ndarray) -> dict[str, np.ndarray]:
        cfg, groups = self.cfg, self.cfg.sensors.channels
        c = self._col
        cols: dict[str, np.ndarray] = {}
        if "encoder" in groups or "crank" in groups:
            cols["crank_angle"] = c(s, "s_theta")
        if "crank" in groups:
            cols["crank_speed"] = c(s, "s_omega")
        if "slider" in groups:
            cols["slider_position"] = c(s, "s_slider")
        if "slider_accel" in groups:
            _, g = spatial_geometry.guide(cfg)
            cols["slider_acceleration"] = c(s, "s_acc") + float(np.array(cfg.mechanism.gravity_vector) @ g)
        if "joints" in groups:
            for jt in cfg.joints.clearance_joints:
                e = np.stack([c(s, f"s_pin_{jt}", k) - c(s, f"s_bush_{jt}", k) for k in range(3)], axis=1)
                if jt == "A":
                    e[:, 0] = 0.0  # the journal's axial position is not a clearance coordinate
                for k, ax in enumerate("xyz"):
                    cols[f"ecc_{jt}_{ax}"] = e[:, k]
                cols[f"pen_{jt}"] = np.maximum(np.linalg.norm(e, axis=1) - cfg.joints.radial_m(jt), 0.0)
                cols[f"fn_{jt}"] = np.where(c(s, f"s_contact_{jt}") > 0, c(s, f"s_contact_{jt}", 1), 0.0)
                cols[f"ft_{jt}"] = np.abs(c(s, f"s_friction_{jt}"))
        if "drive" in groups:
            cols["crank_torque"] = c(s, "s_torque") - prescribed_armature(cfg) * c(s, "s_angacc")
        return {k: np.array(v) for k, v in cols.items()}
