"""The MuJoCo engine: steps the compiled bench inside the engine with ``mujoco.rollout``.

Each chunk of ``simulation.chunk_s`` is one rollout call (no per-step Python): the control
sequence holds the drive reference [θ_ref, ω_ref] for every step, sensor data come back for
every step (computed at the state before the step, i.e. at t_k = k h) and are decimated to
the output rate. The data object carries the state (and the solver warmstart) from one chunk
to the next, so chunking does not change the result.

Per-scene state. A scene's state is more than ``mujoco.rollout`` takes (``mjSTATE_FULLPHYSICS``):
the solver warmstart (passed to it separately) and the native contact law's stored impact speed
of each clearance joint (``mjData.userdata``, one slot per joint, see ``_bore.c``), which the
rollout neither sets nor resets. Each engine has its own model and data object, so scenes on
separate engines (on threads: :func:`twin.simulation.simulate_many`) share nothing; :meth:`reset`
clears the impact speeds with the rest of the data, and :meth:`snapshot` / :meth:`restore` move
the whole state (``mjSTATE_INTEGRATION``: physics, controls, warmstart, user data) and the step
count, so a run continued from a snapshot, in this engine or another of the same
configuration, gives the same bits as the uninterrupted run.
"""

from __future__ import annotations

import math
import time
from typing import Any

import mujoco
import numpy as np
from mujoco import rollout

from twin import names
from twin.config import BenchConfig
from twin.errors import SimulationError

from twin.mujoco_log import MUJOCO_WARNINGS  # noqa: E402 - MuJoCo's warnings: kept, never printed

#: largest speed of any degree of freedom [m/s or rad/s] before a run counts as exploding: 100 times
#: the fastest crank of any preset (6000 rpm = 628 rad/s) and far beyond any body speed of the bench
MAX_DOF_SPEED = 1.0e5
from twin.kinematics import initial_pose, rot2
from twin.mujoco_engine.accel import PosthocAccelerometers, posthoc_applies
from twin.mujoco_engine.builder import build, solver_name
from twin.tracefile import DriveInputs

_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
#: everything a step reads besides the model: physics, controls, warmstart and user data (v_imp)
_SCENE_STATE = mujoco.mjtState.mjSTATE_INTEGRATION
_clock: tuple[Any, int] | None = None  # (the mjcb_time global, MuJoCo's own clock as first seen here)


def stage_timers_off() -> None:
    """Switch MuJoCo's stage timers off for this process (the twin never reads ``mjData.timer``).

    MuJoCo 4.0 starts with the global ``mjcb_time`` set to a clock of its own, read about 25
    times a step: 0.6-0.7 µs of a 3-5 µs step on this machine (``analysis/profile_stages.py``).
    Timers never change a result. Only MuJoCo's own clock is cleared (the value first seen here);
    one installed since, e.g. through ``mujoco.set_mjcb_time`` or a profiler, is kept.
    """
    global _clock
    if _clock is None:
        import ctypes

        from twin.native.collider import mujoco_library

        slot = ctypes.c_void_p.in_dll(mujoco_library(), "mjcb_time")
        _clock = (slot, slot.value or 0)
    slot, default = _clock
    if slot.value and slot.value == default and mujoco.get_mjcb_time() is None:
        slot.value = None


class MujocoEngine:
    """MuJoCo twin of the bench (see module docstring); the chunk loop is
    :func:`twin.simulation.run_chunks`."""

    name = "mujoco"

    def __init__(self, cfg: BenchConfig, *, inputs: DriveInputs | None = None):
        self.cfg = cfg
        self.inputs = inputs
        t0 = time.perf_counter()
        stage_timers_off()
        self.spec, self.model, self.info = build(cfg, inputs=inputs)
        self.data = mujoco.MjData(self.model)
        posthoc = posthoc_applies(cfg)
        self.meta: dict[str, Any] = {
            "engine": self.name,
            "engine_version": mujoco.__version__,
            "timestep_s": cfg.simulation.timestep_s,
            "integrator": cfg.mujoco.integrator,
            "solver": solver_name(cfg),
            "steps": 0,
            "wall_s": 0.0,
            "build_s": time.perf_counter() - t0,
            "contact": {j: s.to_json() for j, s in self.info.contacts.items()},
            "nq": int(self.model.nq), "nv": int(self.model.nv),
            "warnings": {},
            # how AC1..AC6 are computed (mujoco.accelerometers; "sensor" where "posthoc" cannot be)
            "accelerometers": ("posthoc" if posthoc else "sensor") if "accel" in cfg.sensors.channels else None,
        }
        self._sensor_slices = {self.model.sensor(i).name: slice(int(self.model.sensor_adr[i]),
                                                                 int(self.model.sensor_adr[i] + self.model.sensor_dim[i]))
                               for i in range(self.model.nsensor)}
        self._nstate = mujoco.mj_stateSize(self.model, _STATE)
        self._sens = np.empty((1, 0, self.model.nsensordata))
        # accelerometers from the recorded state (mujoco.accelerometers = "posthoc", Euler)
        self._accel = None
        if posthoc and cfg.structure.flexible:  # the flexible structure's tree: the generic planar recursion
            from twin.mujoco_engine.accel_tree import TreeAccelerometers  # numba: imported only where used

            self._accel = TreeAccelerometers(self.model)
        elif posthoc:
            self._accel = PosthocAccelerometers(self.model)
        self._states = np.empty((1, 0, self._nstate))
        self._k = 0  # integration steps taken since reset
        self._mount = None
        if cfg.structure.flexible and "accel" in cfg.sensors.channels:
            # the accelerometers' mounts (twin.structure.mount), on the sampled readings
            from twin.structure import MountFilter

            st = cfg.structure
            self._mount = MountFilter(st.mount_frequency_hz, st.mount_damping_ratio, cfg.output_rate_hz)
        self._drive = None
        if cfg.drive.mode == "prescribed":
            from twin.drive import DriveReference
            from twin.physics.mujoco_params import prescribed_armature

            self._drive = DriveReference(cfg, inputs)
            self._armature = prescribed_armature(cfg)
            self.meta["drive"] = (f"prescribed: crank armature {self._armature:.6g} kg m^2, dead-beat law "
                                  "A [(theta_ref(t + h) - theta)/h^2 - omega/h]")

    # -------------------------------------------------------------- initial state
    def reset(self, theta0: float | None = None) -> None:
        """Mechanism at rest at crank bench angle ``theta0`` [rad] (None: the drive program's
        initial angle), eccentricities as configured."""
        m, d, cfg = self.model, self.data, self.cfg
        if theta0 is None:
            from twin.drive import DriveReference

            theta0 = float(DriveReference(cfg, self.inputs)(np.array([0.0]))[0][0])
        mujoco.mj_resetData(m, d)
        d.userdata[:] = 0.0  # no contact event under way (mj_resetData clears it too; the rollout never does)
        pose = initial_pose(cfg, theta0)
        d.qpos[m.jnt_qposadr[m.joint(names.CRANK_HINGE).id]] = pose.theta
        d.qpos[m.jnt_qposadr[m.joint(names.ROD_HINGE).id]] = pose.phi - pose.theta
        if cfg.joints.diametral_mm("A") > 0:
            # slide joints: crank journal relative to the frame's bore, bench frame (ė_A = 0 at
            # start, so their velocities stay 0 below)
            d.qpos[m.jnt_qposadr[m.joint(names.ECC_A_X).id]] = pose.e_a[0]
            d.qpos[m.jnt_qposadr[m.joint(names.ECC_A_Y).id]] = pose.e_a[1]
        if cfg.joints.diametral_mm("B") > 0:
            # slide joints: bushing centre relative to the pin, in the crank frame
            rel = rot2(pose.theta).T @ (pose.b_bush - pose.b_pin)
            d.qpos[m.jnt_qposadr[m.joint(names.ECC_B_X).id]] = rel[0]
            d.qpos[m.jnt_qposadr[m.joint(names.ECC_B_Y).id]] = rel[1]
        d.qpos[m.jnt_qposadr[m.joint(names.SLIDER_SLIDE).id]] = pose.slider_x
        if cfg.joints.guide_play:  # the slider's frame Cs: y_g from the guide's start (tilt 0)
            d.qpos[m.jnt_qposadr[m.joint(names.SLIDER_Y).id]] = pose.c_pin[1] - cfg.mechanism.d_off_m
        omega = self._drive.start_rate() if self._drive is not None else 0.0
        if omega != 0.0:
            # a prescribed drive at speed from t = 0: every velocity consistent with it (ė = 0)
            from twin.kinematics import pose_rates

            phid, xd = pose_rates(cfg, pose, omega)
            d.qvel[m.jnt_dofadr[m.joint(names.CRANK_HINGE).id]] = omega
            d.qvel[m.jnt_dofadr[m.joint(names.ROD_HINGE).id]] = phid - omega
            if cfg.joints.diametral_mm("B") > 0:
                # rel = R(θ)ᵀ (B' − B) = −R(θ)ᵀ e_B with e_B fixed: d/dt = −ω (dR/dθ)ᵀ e_B
                s_, c_ = math.sin(pose.theta), math.cos(pose.theta)
                e = pose.e_b
                d.qvel[m.jnt_dofadr[m.joint(names.ECC_B_X).id]] = -omega * (-s_ * e[0] + c_ * e[1])
                d.qvel[m.jnt_dofadr[m.joint(names.ECC_B_Y).id]] = -omega * (-c_ * e[0] - s_ * e[1])
            d.qvel[m.jnt_dofadr[m.joint(names.SLIDER_SLIDE).id]] = xd
        mujoco.mj_forward(m, d)
        self._k = 0
        if self._mount is not None:
            self._mount.reset()

    def snapshot(self) -> tuple[int, np.ndarray]:
        """The scene's whole state: (integration steps since reset, ``mjSTATE_INTEGRATION`` vector
        including the warmstart and the stored impact speeds in ``mjData.userdata``)."""
        state = np.empty(mujoco.mj_stateSize(self.model, _SCENE_STATE))
        mujoco.mj_getState(self.model, self.data, state, _SCENE_STATE)
        if self._mount is not None:  # the flexible structure's sensor mounts: their filter state too
            zi = self._mount._zi  # MountFilter's lfilter state (None before the first chunk)
            return self._k, state, None if zi is None else zi.copy()
        return self._k, state

    def restore(self, snap: tuple[int, np.ndarray]) -> None:
        """Continue from :meth:`snapshot` of an engine of the same configuration (this one or another)."""
        k, state = snap[0], snap[1]
        if self._mount is not None:
            zi = snap[2] if len(snap) > 2 else None
            self._mount._zi = None if zi is None else np.array(zi, dtype=np.float64)
        if len(state) != mujoco.mj_stateSize(self.model, _SCENE_STATE):
            raise ValueError(f"{self.cfg.name}: the snapshot is of a model with another state size")
        # no mj_forward: the next rollout recomputes everything from this state (a forward pass
        # would also run the contact law's callback, which updates the stored impact speeds)
        mujoco.mj_setState(self.model, self.data, np.ascontiguousarray(state, dtype=np.float64), _SCENE_STATE)
        self._k = int(k)

    # -------------------------------------------------------------------- stepping
    def advance(self, theta_ref: np.ndarray, omega_ref: np.ndarray, stride: int) -> dict[str, np.ndarray]:
        """One ``mujoco.rollout`` call over ``len(theta_ref)`` steps (see
        :meth:`twin.simulation.Engine.advance`)."""
        m, d, h = self.model, self.data, self.cfg.simulation.timestep_s
        nstep = len(theta_ref)
        if self._sens.shape[1] < nstep:
            self._sens = np.empty((1, nstep, m.nsensordata))
        sd = self._sens[:, :nstep]
        st = None
        if self._accel is not None:
            if self._states.shape[1] < nstep:
                self._states = np.empty((1, nstep, self._nstate))
            st = self._states[:, :nstep]
        state0 = np.empty((1, self._nstate))
        mujoco.mj_getState(m, d, state0[0], _STATE)
        warm = d.qacc_warmstart.copy()[None]
        if self._drive is not None:
            # dead-beat prescribed drive: the control of step k is the program at t_{k+1} (and rate 0)
            nxt, _ = self._drive((self._k + 1 + np.arange(nstep)) * h)
            ctrl = np.stack([nxt, np.zeros(nstep)], axis=-1)[None]
        elif self.cfg.drive.mode in ("motor", "torque"):
            # the drive train's input (speed set point or torque) in the motor_command actuator's ctrl
            from twin.motor_drive import motor_input

            ctrl = motor_input(self.cfg, self._k, nstep, omega_ref, self.inputs)[None, :, None]
            self._chunk_k0 = self._k
        else:
            ctrl = np.stack([theta_ref, omega_ref], axis=-1)[None]
        # per-step state output only for the posthoc accelerometers (row k: the state after step
        # k); the data object ends holding the final state
        rollout.rollout(m, d, state0, ctrl, nstep=nstep, initial_warmstart=warm,
                        sensordata=sd if m.nsensordata else None, state=st)
        t_start, t_end = self._k * h, (self._k + nstep) * h
        if not math.isclose(d.time, t_end, rel_tol=0, abs_tol=h * 0.5) or \
                not (np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel)) and np.all(np.isfinite(sd))):
            raise SimulationError(self._divergence_message(d.time, t_start, t_end))
        top = float(np.max(np.abs(d.qvel))) if d.qvel.size else 0.0
        if top > MAX_DOF_SPEED:
            dof = int(np.argmax(np.abs(d.qvel)))
            raise SimulationError(f"{self.cfg.name}: the run explodes by t = {t_end:.6f} s: the speed of "
                                  f"{self._dof_name(dof)} reaches {top:.3g} (m/s or rad/s, limit {MAX_DOF_SPEED:g}); "
                                  f"{self._suspects()}")
        self._k += nstep
        self.meta["warnings"] = self.warnings()
        sens = sd[0, ::stride]
        if sens.shape[0] == 1 or sens.shape[1] == 1:
            # a column would be contiguous, so the chunk's channels would be views of the buffer
            # the next chunk overwrites (one sensor value per step, or a one-sample chunk)
            sens = sens.copy()
        accel = None
        if self._accel is not None:
            accel = self._accel(state0[0], st[0], stride, sens.shape[0])
        return self._channels(sens, accel)

    def warnings(self) -> dict[str, int]:
        """MuJoCo warnings raised so far in this run (``mjData.warning``): {name: count}, nonzero only."""
        return {mujoco.mjtWarning(i).name: int(self.data.warning[i].number)
                for i in range(len(self.data.warning)) if self.data.warning[i].number}

    def _dof_name(self, dof: int) -> str:
        m = self.model
        j = int(m.dof_jntid[dof])
        return f"joint {m.joint(j).name or j} (dof {dof})"

    def _suspects(self) -> str:
        cfg = self.cfg
        return (f"likely responsible: simulation.timestep_s ({cfg.simulation.timestep_s:g} s), contact.stiffness, "
                f"joints.clearance_*_mm (B {cfg.joints.clearance_b_mm:g}, C {cfg.joints.clearance_c_mm:g} mm), "
                "bodies.*.mass_kg and inertia_kgm2")

    def _divergence_message(self, t_reached: float, t_start: float, t_expected: float) -> str:
        import re

        warn = [f"{mujoco.mjtWarning(i).name}({int(self.data.warning[i].number)})"
                for i in range(len(self.data.warning)) if self.data.warning[i].number]
        what, when = "the state or sensors", f"in the chunk {t_start:.4f}-{t_expected:.4f} s"
        for text in reversed(MUJOCO_WARNINGS):  # "Nan, Inf or huge value in QACC at DOF 0 ... Time = 0.0007."
            m = re.search(r"in (\w+) at DOF (\d+).*?Time = (\d+(?:\.\d+)?(?:[eE][+-]?\d+)?)", text)
            if m:
                dof = int(m[2])
                what = f"{m[1].lower()} of {self._dof_name(dof) if dof < self.model.nv else f'dof {dof}'}"
                when = f"at t = {float(m[3]):.6f} s"  # MuJoCo's time: the run's
                break
        return (f"{self.cfg.name}: the run diverged {when}: {what} became NaN, infinite or huge (MuJoCo warnings: "
                f"{', '.join(warn) or 'none'}); {self._suspects()}")

    def _train_channels(self, sens: np.ndarray, col) -> dict[str, np.ndarray]:
        """Channels of the drive train (groups drive, motor, drive_energy)."""
        from twin.motor_drive import command_voltage

        groups, out = self.cfg.sensors.channels, {}
        f = {name: i for i, name in enumerate(names.DRIVETRAIN_SENSOR_FIELDS)}
        if "drive" in groups:
            out["crank_torque"] = col(names.SENSOR_DRIVETRAIN, f["belt_torque"])
        if "motor" in groups:
            out["motor_angle"] = col(names.SENSOR_MOTOR_ANGLE)
            out["motor_speed"] = col(names.SENSOR_MOTOR_SPEED)
            for name in ("motor_torque", "belt_torque", "belt_slip"):
                out[name] = col(names.SENSOR_DRIVETRAIN, f[name])
            n, stride = sens.shape[0], self.cfg.output_stride
            t = (self._chunk_k0 + stride * np.arange(n)) * self.cfg.simulation.timestep_s
            out["command_voltage"] = command_voltage(self.cfg, t, self.inputs)
        if "drive_energy" in groups:
            for i, name in enumerate(names.DRIVETRAIN_ENERGY_FIELDS):
                out[name] = col(names.SENSOR_DRIVETRAIN_ENERGY, i)
        return out

    def _channels(self, sens: np.ndarray, accel: np.ndarray | None = None) -> dict[str, np.ndarray]:
        cfg, sl = self.cfg, self._sensor_slices
        out: dict[str, np.ndarray] = {}

        def col(name: str, k: int = 0) -> np.ndarray:
            return sens[:, sl[name].start + k]

        groups = cfg.sensors.channels
        if "accel" in groups:
            for i, a in enumerate(names.ACCEL_SENSORS):
                # site x axis = sensitive axis; posthoc: rows of the readings computed from the state
                out[a] = col(a, 0) if accel is None else accel[i]
            if self._mount is not None:  # flexible structure: what the sensors on their mounts feel
                filtered = self._mount.process(np.stack([out[a] for a in names.ACCEL_SENSORS], axis=1))
                for i, a in enumerate(names.ACCEL_SENSORS):
                    out[a] = filtered[:, i]
        if "structure" in groups:
            from twin.mujoco_engine.flexible import structure_channels

            out.update(structure_channels(col, cfg.bodies.rod.length_m))
        if "encoder" in groups or "crank" in groups:
            out["crank_angle"] = col(names.SENSOR_CRANK_ANGLE)
        if "crank" in groups:
            out["crank_speed"] = col(names.SENSOR_CRANK_SPEED)
        if "slider" in groups:
            out["slider_position"] = col(names.SENSOR_SLIDER_POSITION)
        if "joints" in groups:
            for jt in cfg.joints.clearance_joints:
                ex, ey = col(names.sensor_ecc(jt), 0), col(names.sensor_ecc(jt), 1)
                found = col(names.sensor_contact(jt), 0) > 0 if cfg.mujoco.bushing != "tendon" else None
                out[f"ecc_{jt}_x"] = ex
                out[f"ecc_{jt}_y"] = ey
                out[f"pen_{jt}"] = np.maximum(np.hypot(ex, ey) - cfg.joints.radial_m(jt), 0.0)
                bushing, friction = cfg.mujoco.bushing, cfg.mujoco.friction
                if bushing == "bore":
                    # contact sensor: one slot per term of the law, each [found, force in the
                    # contact frame (normal, t1, axis)]; the terms act at the same point and add
                    nterm = len(self.info.contacts[jt].terms)
                    slot = [col(names.sensor_contact(jt), 4 * i) > 0 for i in range(nterm)]
                    out[f"fn_{jt}"] = sum(np.where(slot[i], col(names.sensor_contact(jt), 4 * i + 1), 0.0)
                                          for i in range(nterm))
                    if friction == "native":
                        out[f"ft_{jt}"] = col(names.sensor_friction(jt))  # native module's user sensor
                    else:
                        # force on geom2 (bushing) along t1 = axis x normal: the pin feels minus that
                        out[f"ft_{jt}"] = -sum(np.where(slot[i], col(names.sensor_contact(jt), 4 * i + 2), 0.0)
                                               for i in range(nterm))
                elif bushing == "ring":
                    # netforce of all pin/box contacts in the global frame: its in-plane magnitude
                    out[f"fn_{jt}"] = np.where(found, np.hypot(col(names.sensor_contact(jt), 1),
                                                               col(names.sensor_contact(jt), 2)), 0.0)
                else:  # tendon limit force (the sensor is the tendon's limit force)
                    out[f"fn_{jt}"] = np.abs(col(names.sensor_contact(jt), 0))
            if cfg.joints.guide_play:
                # C' from the frame Cs: y_g = y_Cs − d_off (1 − cos φ) (twin.reference.guide)
                tilt = col(names.SENSOR_SLIDER_TILT)
                out["slider_y"] = col(names.SENSOR_SLIDER_Y) - cfg.mechanism.d_off_m * (1.0 - np.cos(tilt))
                out["slider_tilt"] = tilt
                for i, name in enumerate(names.GUIDE_SENSOR_FIELDS):
                    out[name] = col(names.SENSOR_GUIDE, i)
        if "energy" in groups:
            out["energy_kinetic"] = col(names.SENSOR_ENERGY_KINETIC)
            out["energy_potential"] = col(names.SENSOR_ENERGY_POTENTIAL)
            out["slider_speed"] = col(names.SENSOR_SLIDER_SPEED)
        if self.cfg.drive.mode in ("motor", "torque"):
            out.update(self._train_channels(sens, col))
        elif "drive" in groups:
            if self._drive is not None:
                # the torque the mechanism receives: the actuator's minus the flywheel's share A θ̈
                out["crank_torque"] = col(names.SENSOR_CRANK_TORQUE) - self._armature * col(names.SENSOR_CRANK_ANGACC, 2)
            else:
                out["crank_torque"] = col(names.SENSOR_CRANK_TORQUE)
        return out
