"""The drive train in the MuJoCo twin (``drive.mode`` "motor" / "torque").

The model (:mod:`twin.config.drivetrain`) is added to the compiled bench by
:func:`add_drive_train` (spec edits) and :func:`finish` (numbers that need the compiled model):

* a motor rotor body on the world with a hinge ``motor_hinge`` about z (inertia
  ``drivetrain.rotor_inertia_kgm2`` about the axis, centre of mass on it: no gravity torque);
  it has no collision geometry;
* the crank PID actuator and its torque sensor are removed; a zero-gain actuator
  ``motor_command`` on the motor hinge carries the motor's speed set point [rad/s] ("motor") or
  its torque [N m] ("torque") as its ctrl, one value per step from the rollout's control sequence;
* the speed controller (encoder quantization, speed estimate, PI, clamp) and the V-belt's pull
  (Kelvin–Voigt spans in series with creep and slip) run in the native passive callback
  (``_drivetrain.h``, included by ``_bore.c``), parameters in the ``<numeric>`` ``drivetrain``
  (:data:`twin.names.DRIVETRAIN_FIELDS`), state in ``mjData.userdata`` after the contact slots;
* sensors: the motor hinge's angle and speed, a position-stage user sensor with the step's
  motor torque, belt torque on the crank and slip speed (:data:`twin.names.DRIVETRAIN_SENSOR_FIELDS`,
  written by the passive callback) and, with the channel group ``drive_energy``, an
  acceleration-stage one with the work/energy/dissipation accounts
  (:data:`twin.names.DRIVETRAIN_ENERGY_FIELDS`).
"""

from __future__ import annotations

import math

import mujoco

from twin import names
from twin.config import BenchConfig

#: the rotor body's mass [kg] (on the axis: it only enters the potential energy, as a constant)
ROTOR_MASS_KG = 0.5
#: where the rotor body sits in the bench frame [m] (visual only; the belt is a force law)
ROTOR_POS = (0.0, -0.25, 0.0)


def applies(cfg: BenchConfig) -> bool:
    return cfg.drive.mode in ("motor", "torque")


def add_drive_train(spec: mujoco.MjSpec, cfg: BenchConfig) -> None:
    """Spec edits of the drive train (see the module docstring)."""
    dt = cfg.drivetrain
    spec.delete(spec.actuator(names.CRANK_PID))
    if spec.sensor(names.SENSOR_CRANK_TORQUE) is not None:
        spec.delete(spec.sensor(names.SENSOR_CRANK_TORQUE))
    body = spec.worldbody.add_body(name=names.MOTOR, pos=list(ROTOR_POS))
    j = dt.rotor_inertia_kgm2
    body.mass = ROTOR_MASS_KG
    body.ipos = [0, 0, 0]
    body.inertia = [j, j, j]
    body.explicitinertial = True
    body.add_joint(name=names.MOTOR_HINGE, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    body.add_geom(name="motor_pulley", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                  size=[dt.motor_pulley_radius_m, 0.01, 0], contype=0, conaffinity=0, group=1, mass=0)
    act = spec.add_actuator(name=names.MOTOR_COMMAND, target=names.MOTOR_HINGE, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    act.gainprm[0] = 0.0
    act.biasprm[0] = 0.0
    act.ctrllimited = 0
    spec.add_numeric(name=names.DRIVETRAIN_NUMERIC, data=[0.0] * len(names.DRIVETRAIN_FIELDS))
    groups = cfg.sensors.channels
    if "motor" in groups:
        spec.add_sensor(name=names.SENSOR_MOTOR_ANGLE, type=mujoco.mjtSensor.mjSENS_JOINTPOS,
                        objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=names.MOTOR_HINGE)
        spec.add_sensor(name=names.SENSOR_MOTOR_SPEED, type=mujoco.mjtSensor.mjSENS_JOINTVEL,
                        objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=names.MOTOR_HINGE)
    if "motor" in groups or "drive" in groups:
        # position stage: the passive callback writes it, no acceleration-stage sensor pass
        spec.add_sensor(name=names.SENSOR_DRIVETRAIN, type=mujoco.mjtSensor.mjSENS_USER,
                        objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=names.MOTOR_HINGE,
                        dim=len(names.DRIVETRAIN_SENSOR_FIELDS), needstage=mujoco.mjtStage.mjSTAGE_POS)
    if "drive_energy" in groups:
        spec.add_sensor(name=names.SENSOR_DRIVETRAIN_ENERGY, type=mujoco.mjtSensor.mjSENS_USER,
                        objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=names.MOTOR_HINGE,
                        dim=len(names.DRIVETRAIN_ENERGY_FIELDS), needstage=mujoco.mjtStage.mjSTAGE_ACC)
        spec.option.enableflags |= mujoco.mjtEnableBit.mjENBL_ENERGY


def finish(spec: mujoco.MjSpec, cfg: BenchConfig, model: mujoco.MjModel) -> None:
    """Write the numeric data (dof addresses from the compiled ``model``) and the user data
    slots; the spec must be compiled again."""
    dt = cfg.drivetrain
    h = cfg.simulation.timestep_s
    stride = dt.controller_stride(h)
    T = stride * h
    slot = int(spec.nuserdata)
    guide = model.joint(names.SLIDER_SLIDE)
    guide_dof = int(model.jnt_dofadr[guide.id]) if cfg.mujoco.guide_friction == "native" else -1
    vals = dict(
        marker=names.DRIVETRAIN_MAGIC,
        motor_dof=int(model.jnt_dofadr[model.joint(names.MOTOR_HINGE).id]),
        crank_dof=int(model.jnt_dofadr[model.joint(names.CRANK_HINGE).id]),
        actuator=int(model.actuator(names.MOTOR_COMMAND).id),
        slot=slot, mode=1.0 if cfg.drive.mode == "motor" else 2.0,
        r_m=dt.motor_pulley_radius_m, r_c=dt.crank_pulley_radius_m(cfg.drive.belt_ratio),
        k=dt.stiffness_npm, c=dt.belt_damping_nspm, ea=dt.belt_ea_n, f_max=dt.max_pull_n,
        c_slip=dt.slip_damping_nspm, stride=stride, counts=dt.encoder_counts,
        alpha=1.0 - math.exp(-2.0 * math.pi * dt.speed_filter_hz * T), kp=dt.speed_kp_nms, ki=dt.speed_ki_nm,
        t_ctrl=T, peak=dt.peak_torque_nm, account=1.0 if "drive_energy" in cfg.sensors.channels else 0.0,
        guide_dof=guide_dof)
    spec.numeric(names.DRIVETRAIN_NUMERIC).data = [float(vals[f]) for f in names.DRIVETRAIN_FIELDS]
    from twin.native import _bore

    spec.nuserdata = slot + _bore.drivetrain_layout()[1] + 2 * int(model.nv)
