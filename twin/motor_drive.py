"""What both engines share of the drive train (``drive.mode`` "motor" or "torque"): the per-step
input of the motor (speed set point or torque), the analog command voltage and the channels.

The motor's speed set point is the drive program's motor speed: ``drive.belt_ratio`` × the
program's crank rate ω_ref(t) (:class:`twin.drive.DriveReference`, with the controller's profile
ramp ``drive.ramp_s``; for a trace program the trace's filtered speed), in the crank's turning
sense. The command voltage channel is the DAQ's analog output: the program's motor speed command
× ``instrumentation.command_v_per_rpm`` (±10 V ↔ ±1000 rpm; a step, before the controller's ramp)
for "motor"; for "torque" the torque command scaled ±10 V ↔ ± ``drivetrain.peak_torque_nm``
(PLACEHOLDER: the analog scaling of a torque command is the drive's setting, not known).
"""

from __future__ import annotations

import functools

import numpy as np

from twin.config import BenchConfig
from twin.tracefile import DriveInputs, check_command


@functools.lru_cache(maxsize=4)
def _command_file(path: str, mtime_ns: int) -> tuple[np.ndarray, np.ndarray]:  # noqa: ARG001 - cache key
    from twin.errors import ConfigError

    try:
        with np.load(path, allow_pickle=False) as z:
            t, v = np.asarray(z["t"], dtype=np.float64), np.asarray(z["volts"], dtype=np.float64)
    except (OSError, KeyError, ValueError) as err:
        raise ConfigError("drivetrain.command_file", f"{path}: needs arrays 't' and 'volts' ({err})") from None
    return check_command(t, v, path)


def command_trace(cfg: BenchConfig, inputs: DriveInputs | None = None) -> tuple[np.ndarray, np.ndarray] | None:
    """(t [s], volts [V]) of the recorded motor command: ``inputs.command`` (in memory), else the
    file ``drivetrain.command_file`` a user names, else None."""
    import os

    if inputs is not None and inputs.command is not None:
        return inputs.command
    path = cfg.drivetrain.command_file
    if not path:
        return None
    if not os.path.isfile(path):
        from twin.errors import ConfigError

        raise ConfigError("drivetrain.command_file", f"no such file: {path}")
    return _command_file(path, os.stat(path).st_mtime_ns)


def motor_input(cfg: BenchConfig, k0: int, nstep: int, omega_ref: np.ndarray,
                inputs: DriveInputs | None = None) -> np.ndarray:
    """Per-step motor input of steps k0 .. k0 + nstep − 1, about +z like the crank angle: speed set
    point [rad/s] ("motor") or motor torque [N m] ("torque"); a positive command turns the crank
    in ``mechanism.crank_direction``. ``inputs``: the recorded motor command in memory, if any."""
    if cfg.drive.mode == "motor":
        rec = command_trace(cfg, inputs)
        if rec is not None:
            t = (k0 + np.arange(nstep)) * cfg.simulation.timestep_s
            rpm = np.interp(t, rec[0], rec[1]) / cfg.instrumentation.command_v_per_rpm
            return np.ascontiguousarray(cfg.mechanism.crank_direction * rpm * (2.0 * np.pi / 60.0))
        return np.ascontiguousarray(cfg.drive.belt_ratio * np.asarray(omega_ref, dtype=np.float64))
    t = (k0 + np.arange(nstep)) * cfg.simulation.timestep_s
    return np.ascontiguousarray(cfg.mechanism.crank_direction * cfg.drivetrain.torque_program(t))


def command_voltage(cfg: BenchConfig, t: np.ndarray, inputs: DriveInputs | None = None) -> np.ndarray:
    """Analog command [V] at times ``t`` (see the module docstring); ``inputs``: the recorded trace
    or motor command in memory, if any."""
    if cfg.drive.mode == "torque":
        dt = cfg.drivetrain
        return 10.0 * dt.torque_program(t) / dt.peak_torque_nm
    rec = command_trace(cfg, inputs)
    if rec is not None:
        return np.interp(t, rec[0], rec[1])
    from twin.drive import DriveReference

    return cfg.instrumentation.command_v_per_rpm * DriveReference(cfg, inputs).command_rpm(t)


def crank_side_inertia(cfg: BenchConfig, theta: float) -> float:
    """Inertia the ideal mechanism presents at the crank at bench angle ``theta`` [kg m²]: twice its
    kinetic energy at unit crank rate, from the closed-form kinematics (:mod:`twin.kinematics`),
    independent of either engine's mass matrix (for the drive train's closed-form checks)."""
    import math

    from twin.kinematics import initial_pose, pose_rates

    b = cfg.bodies
    pose = initial_pose(cfg, theta)
    phid, xd = pose_rates(cfg, pose, 1.0)
    i_a = b.crank.inertia_kgm2 + b.crank.mass_kg * b.crank.x_g_m ** 2
    vb = b.crank.length_m * np.array([-math.sin(theta), math.cos(theta)])
    vg = vb + b.rod.x_g_m * phid * np.array([-math.sin(pose.phi), math.cos(pose.phi)])
    return float(i_a + b.rod.mass_kg * float(vg @ vg) + b.rod.inertia_kgm2 * phid ** 2 + b.slider.mass_kg * xd ** 2)


def speed_harmonics(crank_angle: np.ndarray, crank_speed: np.ndarray, n: int = 3) -> np.ndarray:
    """First ``n`` harmonics of the crank speed over crank angle (whole turns of the record, speed
    resampled uniformly in angle), amplitude in % of the mean speed."""
    import math

    th = np.unwrap(np.asarray(crank_angle, dtype=np.float64))
    w = np.asarray(crank_speed, dtype=np.float64)
    if th[-1] < th[0]:
        th, w = -th, -w
    turns = int((th[-1] - th[0]) // (2 * math.pi))
    if turns < 1:
        raise ValueError("speed_harmonics needs at least one whole turn")
    grid = th[0] + np.linspace(0, 2 * math.pi * turns, 512 * turns, endpoint=False)
    spec = np.fft.rfft(np.interp(grid, th, w)) / grid.size
    return np.array([2 * abs(spec[turns * k]) / spec[0].real * 100 for k in range(1, n + 1)])
