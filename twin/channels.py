"""Names, units and groups of the channels a run carries, shared by both engines.

A channel is one uniformly sampled scalar signal. Groups are what a scene can ask for
(``sensors.channels`` in the configuration) and what the MCAP file stores per topic.

Conventions (bench frame of :mod:`twin.config`):

* ``AC1``..``AC6``: proper acceleration (gravity included, as a MEMS sensor reads it)
  along each sensor's sensitive axis [m/s²].
* ``encoder_angle``: crank angle in the encoder's convention, zero with the crank along
  −y, unwrapped (continuous over turns) [rad]. Quantization to counts is the sensor
  chain's job, not the engine's.
* ``crank_angle`` / ``crank_speed``: bench angle θ from +x, unwrapped [rad], and dθ/dt [rad/s].
* ``slider_position``: x of the slider reference point Cs on the guide [m].
* ``ecc_J_x``, ``ecc_J_y``: eccentricity of joint J = pin centre − bushing centre, in the
  rod frame (x from B towards C) at B and C, in the bench frame at A (its bushing is the frame's
  bore, e = crank journal − bore centre) [m]; ``pen_J``: penetration max(0, |e| − c) [m];
  ``fn_J``: normal contact force magnitude [N]; ``ft_J``: friction force on the pin
  along the in-plane tangent ẑ × n (n = e/|e|) [N].
* ``theta_ref`` / ``omega_ref``: the drive's reference bench angle [rad] and rate [rad/s];
  ``crank_torque``: torque applied by the PID to the crank about +z [N m].
* optional groups ``motor`` and ``drive_energy`` (``drive.mode`` "motor"/"torque"): see
  :mod:`twin.motor_drive` (motor angle/speed/torque, belt torque and slip, command voltage; the
  work, energy and dissipation accumulators of the energy balance).
* optional group ``structure`` (``structure.mode = "flexible"``; MuJoCo engine): ``rod_deflection``: the
  rod's mid-span point's distance from the chord B'–C' between the two bores' centres (+ to the left of
  B'→C', i.e. along ẑ × (C' − B')) [m]; ``rod_stretch``: |C' − B'| − L [m]; ``frame_x``/``frame_y``: the
  crank support's displacement, ``guide_y``: the guide support's, normal to the guide [m].
* optional group ``energy`` (MuJoCo engine only; not computed unless asked for):
  ``energy_kinetic`` / ``energy_potential``: kinetic and gravitational potential energy of the
  three bodies (MuJoCo's ``e_kinetic``/``e_potential`` sensors; the soft contacts' elastic
  energy is not included) [J]; ``slider_speed``: dx/dt of the slider on the guide [m/s].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from twin.config import ACCELEROMETERS, ALL_CHANNEL_GROUPS, JOINTS, BenchConfig

#: channels of the optional group "motor": (name, unit, dtype, description)
MOTOR_CHANNELS: tuple[tuple[str, str, str, str], ...] = (
    ("motor_angle", "rad", "float64", "motor rotor angle about +z (the crank angle's sense)"),
    ("motor_speed", "rad/s", "float64", "motor rotor angular velocity"),
    ("motor_torque", "N m", "float32", "motor electromagnetic torque (controller output, clamped)"),
    ("belt_torque", "N m", "float32", "belt torque on the crank pulley (r_c x effective pull)"),
    ("belt_slip", "m/s", "float32", "belt slip speed on the pulleys (creep and sliding)"),
    ("command_voltage", "V", "float32", "analog motor command"),
)
#: channels of the optional group "drive_energy" (accumulated from t = 0)
DRIVE_ENERGY_CHANNELS: tuple[tuple[str, str, str, str], ...] = (
    ("motor_work", "J", "float64", "work of the motor torque on the rotor"),
    ("energy_mechanical", "J", "float64", "kinetic + gravitational energy of the mechanism and the rotor"),
    ("energy_belt", "J", "float64", "elastic energy of the belt spans"),
    ("diss_belt_damping", "J", "float64", "energy dissipated by the belt's damping"),
    ("diss_belt_slip", "J", "float64", "energy dissipated by belt creep and slip"),
    ("diss_guide", "J", "float64", "energy dissipated by the slider guide's friction"),
    ("diss_contact", "J", "float64",
     "energy dissipated in the joints (contact law, joint friction; MuJoCo: every constraint force)"),
)


@dataclass(frozen=True)
class ChannelSpec:
    """Static description of one channel: name, unit, group, storage dtype."""

    name: str
    unit: str
    group: str
    dtype: str
    description: str


def _joint_specs(joint: str) -> list[ChannelSpec]:
    g = f"joint_{joint}"
    frame = "bench" if joint == "A" else "rod"
    return [
        ChannelSpec(f"ecc_{joint}_x", "m", g, "float64", f"eccentricity at {joint}, {frame} x"),
        ChannelSpec(f"ecc_{joint}_y", "m", g, "float64", f"eccentricity at {joint}, {frame} y"),
        ChannelSpec(f"pen_{joint}", "m", g, "float64", f"penetration at {joint}"),
        ChannelSpec(f"fn_{joint}", "N", g, "float32", f"normal contact force at {joint}"),
        ChannelSpec(f"ft_{joint}", "N", g, "float32", f"friction force on the pin at {joint}"),
    ]


#: the slider guide's channels (``joints.clearance_guide_mm`` > 0; in the "joints" group): the
#: slider's transverse position and tilt, and per contact point (the shoe's front and rear ends)
#: the rails' normal force along +y on the slider (positive: from the lower rail) and friction along +x
GUIDE_CHANNELS: tuple[tuple[str, str, str, str], ...] = (
    ("slider_y", "m", "float64", "slider pin C' transverse position from its centred place (+y)"),
    ("slider_tilt", "rad", "float64", "slider tilt about +z"),
    ("fn_guide_front", "N", "float32", "rail normal force on the slider's front end, along +y (+: lower rail)"),
    ("fn_guide_rear", "N", "float32", "rail normal force on the slider's rear end, along +y (+: lower rail)"),
    ("ft_guide_front", "N", "float32", "rail friction force on the slider's front end, along +x"),
    ("ft_guide_rear", "N", "float32", "rail friction force on the slider's rear end, along +x"),
)


def _guide_specs() -> list[ChannelSpec]:
    return [ChannelSpec(n, u, "joint_guide", dt, d) for n, u, dt, d in GUIDE_CHANNELS]


def _spatial_joint_specs(joint: str) -> list[ChannelSpec]:
    """A joint of the spatial mechanism: 3D eccentricity in the spatial frame, |friction force|."""
    g = f"joint_{joint}"
    return [
        ChannelSpec(f"ecc_{joint}_x", "m", g, "float64", f"eccentricity at {joint}, x"),
        ChannelSpec(f"ecc_{joint}_y", "m", g, "float64", f"eccentricity at {joint}, y"),
        ChannelSpec(f"ecc_{joint}_z", "m", g, "float64", f"eccentricity at {joint}, z"),
        ChannelSpec(f"pen_{joint}", "m", g, "float64", f"penetration at {joint}"),
        ChannelSpec(f"fn_{joint}", "N", g, "float32", f"normal contact force at {joint}"),
        ChannelSpec(f"ft_{joint}", "N", g, "float32", f"magnitude of the friction force at {joint}"),
    ]


_STATIC: dict[str, list[ChannelSpec]] = {
    "accel": [ChannelSpec(a, "m/s^2", "accel", "float32", f"{a} proper acceleration") for a in ACCELEROMETERS],
    "encoder": [ChannelSpec("encoder_angle", "rad", "encoder", "float64", "crank encoder angle, zero at -y")],
    "crank": [
        ChannelSpec("crank_angle", "rad", "crank", "float64", "crank bench angle from +x"),
        ChannelSpec("crank_speed", "rad/s", "crank", "float64", "crank angular velocity"),
    ],
    "slider": [ChannelSpec("slider_position", "m", "slider", "float64", "slider position along the guide")],
    "drive": [
        ChannelSpec("theta_ref", "rad", "drive", "float64", "reference crank bench angle"),
        ChannelSpec("omega_ref", "rad/s", "drive", "float64", "reference crank rate"),
        ChannelSpec("crank_torque", "N m", "drive", "float32", "PID torque on the crank"),
    ],
    # optional group (not in the default channel list): energy balances
    # optional groups of the drive train (drive.mode "motor"/"torque", twin.motor_drive)
    "motor": [ChannelSpec(n, u, "motor", dt, d) for n, u, dt, d in MOTOR_CHANNELS],
    "drive_energy": [ChannelSpec(n, u, "drive_energy", dt, d) for n, u, dt, d in DRIVE_ENERGY_CHANNELS],
    "energy": [
        ChannelSpec("energy_kinetic", "J", "energy", "float64", "kinetic energy of the mechanism"),
        ChannelSpec("energy_potential", "J", "energy", "float64",
                    "gravitational potential energy of the mechanism (zero at the bench origin)"),
        ChannelSpec("slider_speed", "m/s", "energy", "float64", "slider velocity along the guide"),
    ],
    # optional group of the flexible structure (structure.mode = "flexible")
    "structure": [ChannelSpec(n, "m", "structure", "float64", d) for n, d in (
        ("rod_deflection", "rod mid-span distance from the chord B'-C' (+: left of B'->C')"),
        ("rod_stretch", "rod chord length |B'C'| minus its length"),
        ("frame_x", "crank support (frame at A) displacement along x"),
        ("frame_y", "crank support (frame at A) displacement along y"),
        ("guide_y", "slider support (guide rails) displacement normal to the guide"))],
    # optional group of the spatial mechanism
    "slider_accel": [ChannelSpec("slider_acceleration", "m/s^2", "slider_accel", "float64",
                                 "slider acceleration along the guide")],
}


def channel_specs(cfg: BenchConfig) -> list[ChannelSpec]:
    """Channels a run of ``cfg`` produces, in canonical order (groups as in ALL_CHANNEL_GROUPS)."""
    out: list[ChannelSpec] = []
    for group in ALL_CHANNEL_GROUPS:
        if group not in cfg.sensors.channels:
            continue
        if group == "joints" and cfg.spatial.enabled:
            for j in cfg.joints.clearance_joints:
                out.extend(_spatial_joint_specs(j))
        elif group == "joints":
            # MuJoCo's ring and tendon bushings give no signed friction force on the pin
            no_ft = cfg.simulation.engine == "mujoco" and cfg.mujoco.bushing in ("ring", "tendon")
            for j in cfg.joints.clearance_joints:
                out.extend(s for s in _joint_specs(j) if not (no_ft and s.name.startswith("ft_")))
            if cfg.joints.guide_play:
                out.extend(_guide_specs())
        else:
            out.extend(_STATIC[group])
    return out


def spec_by_name(name: str) -> ChannelSpec | None:
    """Spec of a known channel name, or None for channels added by other tools."""
    for specs in _STATIC.values():
        for s in specs:
            if s.name == name:
                return s
    for j in JOINTS:
        for s in _joint_specs(j) + _spatial_joint_specs(j)[2:3]:
            if s.name == name:
                return s
    for s in _guide_specs():
        if s.name == name:
            return s
    return None


def encoder_from_bench(theta: np.ndarray, direction: int = 1) -> np.ndarray:
    """Encoder angle (zero along −y, counting with the drive direction) from bench angle θ [rad]."""
    return direction * (np.asarray(theta) + np.pi / 2.0)


def bench_from_encoder(phi: np.ndarray, direction: int = 1) -> np.ndarray:
    """Bench angle θ from the encoder angle [rad]; inverse of :func:`encoder_from_bench`."""
    return np.asarray(phi) * direction - np.pi / 2.0
