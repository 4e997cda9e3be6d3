"""The whole configuration of one run, :class:`BenchConfig`, and what needs all of it."""

from __future__ import annotations

import dataclasses
import hashlib
from dataclasses import dataclass, field
from typing import Any

import tomli_w

from twin.config.common import ENGINE_ONLY_GROUPS, _NAME_RE, _check, check_types
from twin.config.convert import _to_plain, with_overrides
from twin.config.drive import PID, Drive
from twin.config.drivetrain import Drivetrain
from twin.config.engines import MujocoSettings, Simulation
from twin.config.mechanism import Bodies, Contact, Joints, Materials, Mechanism, ln_stiffness
from twin.config.sensors import Instrumentation, Sensors
from twin.config.spatial import Spatial, check_spatial
from twin.config.structure import StructureConfig
from twin.errors import ConfigError


@dataclass(frozen=True)
class BenchConfig:
    """Everything that defines one run of the bench, for either engine."""

    name: str = "test6"
    bodies: Bodies = Bodies()
    materials: Materials = Materials()
    joints: Joints = Joints(clearance_c_mm=0.1)
    mechanism: Mechanism = Mechanism()
    contact: Contact = Contact()
    mujoco: MujocoSettings = MujocoSettings()
    drive: Drive = Drive()
    pid: PID = PID()
    sensors: Sensors = field(default_factory=Sensors)
    simulation: Simulation = Simulation()
    instrumentation: Instrumentation = field(default_factory=Instrumentation)
    drivetrain: Drivetrain = Drivetrain()
    spatial: Spatial = Spatial()
    structure: StructureConfig = StructureConfig()

    def __post_init__(self) -> None:

        check_types(self)
        _check(isinstance(self.name, str) and 0 < len(self.name) <= 80 and _NAME_RE.fullmatch(self.name) is not None,
               "name", "must be 1-80 characters of letters, digits and . _ - + = @ , (it names the default output "
               f"file), not starting with '.'; got {self.name!r}")
        # cross-field rules: a configuration that exists can be run
        crank, rod = self.bodies.crank.length_m, self.bodies.rod.length_m
        if rod <= crank + abs(self.mechanism.d_off_m):
            raise ConfigError("bodies.rod.length_m",
                              f"{rod:g} m must exceed the crank's length ({crank:g} m, bodies.crank.length_m) plus the "
                              f"guide offset (|mechanism.d_off_m| = {abs(self.mechanism.d_off_m):g} m): a shorter rod "
                              "cannot follow the crank round a full turn")
        _check_bores_fit(self)
        _check_options_used(self)
        sim, sen = self.simulation, self.sensors
        if sim.duration_s == 0 and self.drive.program not in ("protocol", "trace"):
            raise ConfigError("simulation.duration_s",
                              f"must be > 0 for the {self.drive.program} program (0 = the protocol's or the "
                              "trace's length); got 0")
        k = 1.0 / (sim.timestep_s * sen.output_rate_hz)
        stride = int(round(k))
        if stride < 1 or abs(stride - k) > 1e-6 * k:
            every = 1.0 / sim.timestep_s
            raise ConfigError("simulation.timestep_s",
                              f"{sim.timestep_s:g} s does not divide the output period 1/{sen.output_rate_hz:g} Hz; "
                              f"use a timestep of (1/output_rate)/k for an integer k, or set the output rate "
                              f"explicitly (`sensors.output_rate_hz`), e.g. {every:.10g} Hz for a "
                              "sample every step")
        if not self.trace_length_pending and round(self.duration_s * sen.output_rate_hz) < 1:
            raise ConfigError("simulation.duration_s",
                              f"must hold at least one output sample (>= {1.0 / sen.output_rate_hz:g} s at "
                              f"{sen.output_rate_hz:g} Hz), got {sim.duration_s!r}")
        if self.drive.mode == "prescribed" and sim.engine == "mujoco":
            if self.mujoco.integrator != "Euler":
                raise ConfigError("mujoco.integrator",
                                  "must be \"Euler\" for drive.mode = \"prescribed\" (the dead-beat drive lands each "
                                  f"step on the program with Euler's update), got {self.mujoco.integrator!r}")
            if "energy" in sen.channels:
                raise ConfigError("sensors.channels",
                                  "the optional group 'energy' is not available with drive.mode = \"prescribed\" in "
                                  "the MuJoCo engine (its kinetic energy would hold the drive's infinite flywheel)")
        if self.drive.mode in ("motor", "torque"):
            self.drivetrain.controller_stride(sim.timestep_s)
            if sim.engine == "mujoco" and self.mujoco.integrator not in ("Euler", "implicitfast", "implicit"):
                raise ConfigError("mujoco.integrator",
                                  f"must be \"Euler\", \"implicitfast\" or \"implicit\" for drive.mode = "
                                  f"{self.drive.mode!r} (the drive train's native states advance once a step), "
                                  f"got {self.mujoco.integrator!r}")
        else:
            for group in ("motor", "drive_energy"):
                if group in sen.channels:
                    raise ConfigError("sensors.channels", f"the optional group {group!r} needs drive.mode = "
                                      f"\"motor\" or \"torque\", got {self.drive.mode!r}")
        if self.spatial.enabled:
            check_spatial(self)
        elif "slider_accel" in sen.channels:
            raise ConfigError("sensors.channels", "the optional group 'slider_accel' is produced by the spatial "
                              "mechanism only (spatial.enabled = true); remove it")
        for group, engines in ENGINE_ONLY_GROUPS.items():
            if group in sen.channels and sim.engine not in engines:
                raise ConfigError("sensors.channels",
                                  f"the optional group {group!r} is produced by the {' and '.join(engines)} engine "
                                  f"only; remove it for simulation.engine = {sim.engine!r}")
        if "structure" in sen.channels and not self.structure.flexible:
            raise ConfigError("sensors.channels", "the optional group 'structure' is produced by the flexible structure "
                              "only (structure.mode = \"flexible\"); remove it")
        if self.structure.flexible:
            from twin.structure.checks import check_structure

            check_structure(self)

    # -- derived
    @property
    def duration_s(self) -> float:
        """Simulated time of the run [s] (resolves ``simulation.duration_s = 0`` of the protocol).

        A trace program's 0 (the trace's length) is known once the trace is read: the run fills it
        in (:func:`twin.tracefile.with_trace_duration`); asked before, this raises a one-line
        :class:`~twin.errors.ConfigError`."""
        if self.simulation.duration_s > 0:
            return float(self.simulation.duration_s)
        if self.trace_length_pending:
            raise ConfigError("simulation.duration_s", "is 0, the trace's length, known once the trace is read: "
                                                       "pass the configuration through twin.tracefile."
                                                       "with_trace_duration, or give the duration")
        return self.drive.protocol_duration_s

    @property
    def trace_length_pending(self) -> bool:
        """True for a trace program with ``simulation.duration_s = 0`` (the trace's length, not yet read)."""
        return self.drive.program == "trace" and self.simulation.duration_s == 0

    @property
    def output_rate_hz(self) -> float:
        """Sample rate of the run's channels [Hz] (``sensors.output_rate_hz``)."""
        return float(self.sensors.output_rate_hz)

    @property
    def output_stride(self) -> int:
        """Integration steps per output sample (an integer by construction)."""
        return int(round(1.0 / (self.simulation.timestep_s * self.sensors.output_rate_hz)))

    @property
    def n_samples(self) -> int:
        """Number of output samples of a run of this configuration."""
        return int(round(self.duration_s * self.sensors.output_rate_hz))

    # -- serialization
    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (tuples as lists), the TOML layout. The ``[drivetrain]`` table is left
        out while it holds the defaults and the drive does not use it (crank PID, prescribed), and the
        ``[spatial]`` table while it holds the defaults (the planar bench), the ``[structure]`` table
        while it holds the defaults (the rigid bench) and ``mujoco.flexible_solver`` at its default, so that the text and
        digest of such configurations are what they were before these tables existed."""
        out = _to_plain(self)
        joints = out.get("joints", {})
        if all(joints.get(k) == v for k, v in Joints.GUIDE_DEFAULTS.items()):
            for k in Joints.GUIDE_DEFAULTS:
                joints.pop(k, None)
        if self.drive.mode in ("pid", "prescribed") and self.drivetrain == Drivetrain():
            out.pop("drivetrain", None)
        if self.spatial == Spatial():  # the planar bench: no [spatial] table (same text and digest as before it)
            out.pop("spatial", None)
        if self.structure == StructureConfig():  # rigid defaults: no [structure] table (same text and digest)
            out.pop("structure", None)
        if self.mujoco.flexible_solver == MujocoSettings().flexible_solver:  # the default: left out (same digest)
            out.get("mujoco", {}).pop("flexible_solver", None)
        return out

    def to_toml(self) -> str:
        """Canonical TOML text of this configuration."""
        return tomli_w.dumps(self.to_dict())

    def digest(self) -> str:
        """Short SHA-256 of the canonical TOML: a deterministic id of this configuration."""
        return hashlib.sha256(self.to_toml().encode()).hexdigest()[:16]

    def replace(self, **overrides: Any) -> "BenchConfig":
        """Copy with dotted-path overrides, e.g. ``replace(**{"drive.motor_rpm": 500})``."""
        return with_overrides(self, overrides)


def _check_bores_fit(cfg: BenchConfig) -> None:
    """The two bores of the crank (joints A and B) and of the rod (B and C) fit side by side in the body:
    their radii (pin radius + radial clearance) add up to less than its length."""
    j = cfg.joints
    for body, (a, b) in (("crank", ("A", "B")), ("rod", ("B", "C"))):
        length = getattr(cfg.bodies, body).length_m
        reach = j.bushing_radius_m(a) + j.bushing_radius_m(b)
        if reach >= length:
            raise ConfigError(f"bodies.{body}.length_m",
                              f"{length:g} m cannot hold the bores of joints {a} and {b} (radii {j.bushing_radius_m(a):g} "
                              f"+ {j.bushing_radius_m(b):g} m, joints.pin_diameter_m and the clearances): the link must be "
                              "longer than the two bore radii together")


#: the fields each drive mode leaves unused, as (section, fields, modes that use them): a value other than the
#: default in another mode is refused (it would be accepted and silently ignored)
_MODE_FIELDS: tuple[tuple[str, tuple[str, ...], tuple[str, ...]], ...] = (
    # (the motor speed of a Table 4 test switched to the torque drive is the test's, not the user's: the command
    # line refuses --speed with the torque drive; crank_rpm is set only on purpose)
    ("drive", ("crank_rpm",), ("pid", "prescribed", "motor")),
    ("pid", ("kp", "kv", "ki", "imax"), ("pid",)),
    ("drivetrain", tuple(f.name for f in dataclasses.fields(Drivetrain)
                         if f.name not in ("torque_s", "torque_nm", "torque_ramp_s", "release_s", "command_file",
                                           "controller_rate_hz", "encoder_counts", "speed_filter_hz", "speed_kp_nms",
                                           "speed_ki_nm")), ("motor", "torque")),
    ("drivetrain", ("controller_rate_hz", "encoder_counts", "speed_filter_hz", "speed_kp_nms", "speed_ki_nm",
                    "command_file"), ("motor",)),
    ("drivetrain", ("torque_s", "torque_nm", "torque_ramp_s", "release_s"), ("torque",)),
)
#: the fields each drive program leaves unused, as (fields of [drive], programs that use them)
_PROGRAM_FIELDS: tuple[tuple[tuple[str, ...], tuple[str, ...]], ...] = (
    (("trace_file", "trace_filter_hz"), ("trace",)),
    (("protocol_rpm", "protocol_hold_s", "protocol_stop_s"), ("protocol",)),
    (("steps_s", "steps_rpm"), ("steps",)),
)


def _check_options_used(cfg: BenchConfig) -> None:
    """Every option is used or refused: a field set away from its default in a mode, program or mechanism that
    does not read it is refused in one line naming the field and the mode (instead of being ignored)."""
    mode, program = cfg.drive.mode, cfg.drive.program
    for section, names, modes in _MODE_FIELDS:
        if mode in modes:
            continue
        own, default = getattr(cfg, section), type(getattr(cfg, section))()
        for name in names:
            if getattr(own, name) != getattr(default, name):
                raise ConfigError(f"{section}.{name}", f"is not used with drive.mode = {mode!r} (only with "
                                  f"{' or '.join(repr(m) for m in modes)}); leave it out (default "
                                  f"{getattr(default, name)!r}), got {getattr(own, name)!r}")
    default = Drive()
    if mode == "torque" and program != default.program:
        raise ConfigError("drive.program", f"is not used with drive.mode = 'torque' (the motor follows the torque "
                          "program drivetrain.torque_s/torque_nm, then coasts: no speed program); leave it out "
                          f"(default {default.program!r}), got {program!r}")
    for names, programs in _PROGRAM_FIELDS:
        if program in programs:
            continue
        for name in names:
            if getattr(cfg.drive, name) != getattr(default, name):
                raise ConfigError(f"drive.{name}", f"is not used by drive.program = {program!r} (only by "
                                  f"{' or '.join(repr(p) for p in programs)}); leave it out, got "
                                  f"{getattr(cfg.drive, name)!r}")
    j, sp = cfg.joints, cfg.spatial
    if sp.enabled and j.clearance_guide_mm != 0:
        raise ConfigError("joints.clearance_guide_mm", "is not used by the spatial mechanism (spatial.enabled = true: "
                          f"its slider runs on an ideal guide); use 0, got {j.clearance_guide_mm!r}")
    if j.clearance_guide_mm == 0:
        for name in ("guide_span_m", "guide_edge_radius_m"):
            if getattr(j, name) != Joints.GUIDE_DEFAULTS[name]:
                raise ConfigError(f"joints.{name}", "is used only with a guide clearance (joints.clearance_guide_mm "
                                  f"> 0); leave it out (default {Joints.GUIDE_DEFAULTS[name]!r}), got {getattr(j, name)!r}")
    st = cfg.structure
    if not st.flexible:
        for f in dataclasses.fields(StructureConfig):
            if f.name != "mode" and getattr(st, f.name) != f.default:
                raise ConfigError(f"structure.{f.name}", "is used only by the flexible structure (structure.mode = "
                                  f"\"flexible\"); leave it out (default {f.default!r}), got {getattr(st, f.name)!r}")
    if not sp.enabled:
        for f in dataclasses.fields(Spatial):
            if f.name != "enabled" and getattr(sp, f.name) != f.default:
                raise ConfigError(f"spatial.{f.name}", "is used only by the spatial mechanism (spatial.enabled = "
                                  f"true); leave it out (default {f.default!r}), got {getattr(sp, f.name)!r}")


def joint_stiffness(cfg: BenchConfig, joint: str) -> float:
    """K of ``joint``'s hysteresis law before ``stiffness_scale`` [N/m^n]: the configured one
    (:meth:`Contact.stiffness_of`) or S003 Eq. 18 from the joint's own pin, bushing and
    materials (:func:`ln_stiffness`). Both engines resolve K here."""
    return cfg.contact.stiffness_of(joint) or ln_stiffness(cfg.joints, cfg.materials, joint)
