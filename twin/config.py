"""Bench configuration: one frozen dataclass per component, loadable from TOML.

Every number of the physical bench is a field here with its source (``S003`` is the bench
paper, ``../shared/seeds/003_...``; tables refer to it). Values the papers leave open are
marked PLACEHOLDER in the docstrings: they are configuration, documented, never hidden
in code.

Numbers the base MuJoCo model ``mjcf/bench.xml`` also holds (Table 1 bodies, pin and bushing
sizes, the bushing friction law, guide friction, gravity, d_off, PID gains, accelerometer
mounts, timestep and solver numerics) are written once, in that file with their sources: the
fields' defaults are read from it by :mod:`twin.model_xml` ("default: mjcf/bench.xml" in
their docstrings). The other defaults are written here.

Bench frame (used by both engines): origin at the crank pivot A, ``x`` along the slider
guide towards the slider, ``y`` perpendicular in the plane of the mechanism (up in the
paper's tests), ``z = x × y`` along the crank axis. The bench angle ``θ`` of the crank is
measured from ``+x`` counter-clockwise about ``+z``; the encoder angle is ``θ + π/2`` so
that it reads zero with the crank along ``−y`` (S003 §2.3.3).

Validation happens in ``__post_init__``; errors are :class:`~twin.errors.ConfigError`
naming the dotted TOML path of the field and what is allowed.
"""

from __future__ import annotations

import collections.abc
import dataclasses
import hashlib
import math
import re
import tomllib
import types
import typing
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, Mapping

import tomli_w

from twin import model_xml
from twin.drivetrain_params import Drivetrain
from twin.errors import ConfigError

#: defaults held by the base model mjcf/bench.xml (parsed once; ModelError if unreadable)
_XML = model_xml.defaults()

#: Diametral clearances of the bushing catalogue [mm] (S003 §2.2.1).
CATALOGUE_DIAMETRAL_MM: tuple[float, ...] = (0.02, 0.05, 0.07, 0.10, 0.50, 1.00)
#: Bench axes that can be vertical (S003 §2.2.3).
ORIENTATIONS: tuple[str, ...] = ("x", "y", "z")
#: Joints that can take a clearance, in order: the ground–crank pivot A (a ball bearing on the S003
#: bench; a clearance there for the general mechanism of the seeds), crank–rod B, rod–slider C.
JOINTS: tuple[str, ...] = ("A", "B", "C")
#: Engines that speak this configuration.
ENGINES: tuple[str, ...] = ("mujoco", "reference")
#: Drive programs.
PROGRAMS: tuple[str, ...] = ("constant", "protocol", "trace", "steps")
#: Output channel groups a run can carry (see :mod:`twin.channels`).
CHANNEL_GROUPS: tuple[str, ...] = ("accel", "encoder", "crank", "slider", "joints", "drive")
#: Channel groups a scene may ask for but that are not in the default list (they cost time):
#: "energy" (mechanical energy and slider speed, for energy balances; MuJoCo engine only);
#: "motor" (motor, belt and command channels; drive.mode "motor" or "torque" only);
#: "drive_energy" (the drive train's work, dissipation and energy accumulators; "motor"/"torque").
OPTIONAL_CHANNEL_GROUPS: tuple[str, ...] = ("energy", "motor", "drive_energy")
#: Every channel group, in canonical order (the defaults, then the optional ones).
ALL_CHANNEL_GROUPS: tuple[str, ...] = CHANNEL_GROUPS + OPTIONAL_CHANNEL_GROUPS
#: Optional channel groups that only some engines produce: group -> engines.
ENGINE_ONLY_GROUPS: dict[str, tuple[str, ...]] = {"energy": ("mujoco",)}
#: Configuration names (they name default output files).
_NAME_RE = re.compile(r"[A-Za-z0-9_+=@,-][A-Za-z0-9._+=@,-]*")
#: Accelerometers of the bench (S003 Table 3).
ACCELEROMETERS: tuple[str, ...] = ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6")


def _check(cond: bool, name: str, message: str) -> None:
    if not cond:
        raise ConfigError(name, message)


def _positive(value: float, name: str, unit: str) -> None:
    _check(isinstance(value, (int, float)) and math.isfinite(value) and value > 0,
           name, f"must be a finite number > 0 [{unit}], got {value!r}")


def _finite(value: float, name: str, unit: str) -> None:
    _check(isinstance(value, (int, float)) and math.isfinite(value),
           name, f"must be a finite number [{unit}], got {value!r}")


def _choice(value: str, name: str, allowed: tuple[str, ...]) -> None:
    _check(value in allowed, name, f"must be one of {', '.join(allowed)}; got {value!r}")


def _joint_table(obj: Any, name: str) -> list[tuple[str, Any]]:
    """Items of the per-joint table ``obj.<name>`` (keys checked to be joints, ConfigError
    ``<name>.<key>`` otherwise), for the caller to check the values."""
    items = list(getattr(obj, name).items())
    for key, _ in items:
        _choice(key, f"{name}.{key}", JOINTS)
    return items


# --------------------------------------------------------------------------- bodies
@dataclass(frozen=True)
class BodyParams:
    """Rigid body of the mechanism (S003 Table 1). Defaults: mjcf/bench.xml (S003 Table 1).

    Attributes:
        mass_kg: mass [kg].
        length_m: distance between the body's two joints (slider: its length) [m].
        x_g_m: centre of mass along the body's longitudinal axis from its origin (A, B, C) [m].
        inertia_kgm2: moment of inertia about the centre of mass, about the crank axis [kg m²]
            (Table 1 prints "kg/m²", a typo).
    """

    mass_kg: float
    length_m: float
    x_g_m: float
    inertia_kgm2: float

    def __post_init__(self) -> None:
        _positive(self.mass_kg, "mass_kg", "kg")
        _positive(self.length_m, "length_m", "m")
        _finite(self.x_g_m, "x_g_m", "m")
        _positive(self.inertia_kgm2, "inertia_kgm2", "kg m^2")


@dataclass(frozen=True)
class Bodies:
    """The three moving bodies (S003 Table 1; crank includes shaft and pulley).

    Default: mjcf/bench.xml (source S003 Table 1: each body's ``<inertial>`` mass, pos x and
    diaginertia z; lengths from pin B's x, bushing C's x and the slider block's length).
    """

    crank: BodyParams = BodyParams(**dataclasses.asdict(_XML.crank))
    rod: BodyParams = BodyParams(**dataclasses.asdict(_XML.rod))
    slider: BodyParams = BodyParams(**dataclasses.asdict(_XML.slider))


# ------------------------------------------------------------------------ materials
@dataclass(frozen=True)
class Material:
    """Isotropic elastic material.

    Attributes:
        youngs_modulus_pa: Young's modulus E [Pa].
        poisson: Poisson's ratio ν [-].
        density_kgm3: mass density [kg/m³] (visual sizes only; body masses come from Table 1).
    """

    youngs_modulus_pa: float
    poisson: float
    density_kgm3: float

    def __post_init__(self) -> None:
        _positive(self.youngs_modulus_pa, "youngs_modulus_pa", "Pa")
        _check(isinstance(self.poisson, (int, float)) and -1.0 < self.poisson < 0.5,
               "poisson", f"must lie in (-1, 0.5), got {self.poisson!r}")
        _positive(self.density_kgm3, "density_kgm3", "kg/m^3")

    @property
    def compliance_h(self) -> float:
        """h = (1 − ν²)/E of the Lankarani–Nikravesh stiffness (S003 Eq. 18) [1/Pa]."""
        return (1.0 - self.poisson**2) / self.youngs_modulus_pa


@dataclass(frozen=True)
class Materials:
    """Pin and bushing materials (S003 Table 2): F125 steel pins, RG10 bronze bushings.

    Attributes:
        pin: material of every pin (journal) [-].
        bushing: material of every bushing [-].
        pins: per-joint pin material where a joint differs from ``pin``, keyed by joint
            ("A", "B", "C"), e.g. ``[materials.pins.B]`` in TOML (S004: steel pins throughout;
            a general mechanism may fit different pins). Empty: every joint takes ``pin``.
        bushings: per-joint bushing material where a joint differs from ``bushing``.
    """

    pin: Material = Material(210e9, 0.30, 7850.0)
    bushing: Material = Material(90e9, 0.34, 8700.0)
    pins: Mapping[str, Material] = field(default_factory=dict)
    bushings: Mapping[str, Material] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("pins", "bushings"):
            for key, value in _joint_table(self, name):
                _check(isinstance(value, Material), f"{name}.{key}", f"must be a Material table, got {value!r}")

    def pin_of(self, joint: str) -> Material:
        """Pin material of ``joint`` ("A", "B" or "C")."""
        _choice(joint, "joint", JOINTS)
        return self.pins.get(joint, self.pin)

    def bushing_of(self, joint: str) -> Material:
        """Bushing material of ``joint`` ("A", "B" or "C")."""
        _choice(joint, "joint", JOINTS)
        return self.bushings.get(joint, self.bushing)


# --------------------------------------------------------------------------- joints
@dataclass(frozen=True)
class Joints:
    """Revolute joints A (ground–crank pivot), B (crank–rod) and C (rod–slider).

    Attributes:
        clearance_b_mm: diametral clearance at B [mm]; 0 = deep-groove ball bearing (ideal
            joint, S003 §2.2.1 case A), otherwise a catalogue value.
        clearance_c_mm: diametral clearance at C [mm], same rules.
        clearance_a_mm: diametral clearance at the ground–crank pivot A [mm], same rules. The
            S003 bench carries its crank shaft in ball bearings (0, the default); the general
            mechanism of the seeds may have a clearance there too (issue 18). At A the pin is
            the crank's journal and the bushing the frame's bore, so e_A = crank journal −
            frame bore centre.
        allow_noncatalogue: accept clearances outside the catalogue (0.02–1.00 mm values).
        pin_diameter_m: journal (pin) diameter of every joint [m]. PLACEHOLDER: not given by
            S003. Default: mjcf/bench.xml (pin class size, BENCH.md's documented placeholder,
            consistent with its K ≈ 1.3e11).
        bushing_length_m: axial length of every bushing [m]. PLACEHOLDER: not given.
            Default: mjcf/bench.xml (pin/bushing class half length × 2).
        pin_diameters_m: per-joint pin diameter where a joint differs from ``pin_diameter_m``
            [m], keyed by joint ("A", "B", "C"), e.g. ``[joints.pin_diameters_m] B = 0.015``.
        bushing_lengths_m: per-joint bushing length where a joint differs from
            ``bushing_length_m`` [m], keyed by joint.
        initial_eccentricity: ``"loaded"`` starts each journal touching the bushing on the side
            its static load pushes it to (no artificial drop at t = 0); ``"centred"`` starts
            it at the bushing centre.
    """

    clearance_b_mm: float = 0.0
    clearance_c_mm: float = 0.0
    clearance_a_mm: float = 0.0
    allow_noncatalogue: bool = False
    pin_diameter_m: float = _XML.pin_diameter_m
    bushing_length_m: float = _XML.bushing_length_m
    pin_diameters_m: Mapping[str, float] = field(default_factory=dict)
    bushing_lengths_m: Mapping[str, float] = field(default_factory=dict)
    initial_eccentricity: str = "loaded"

    def __post_init__(self) -> None:
        for name in ("clearance_a_mm", "clearance_b_mm", "clearance_c_mm"):
            value = getattr(self, name)
            _check(isinstance(value, (int, float)) and math.isfinite(value) and value >= 0,
                   name, f"must be 0 (ball bearing) or a diametral clearance > 0 [mm], got {value!r}")
            if value != 0 and not self.allow_noncatalogue:
                ok = any(abs(value - c) < 1e-9 for c in CATALOGUE_DIAMETRAL_MM)
                _check(ok, name, "must be 0 (ball bearing) or a catalogue diametral clearance "
                       f"{', '.join(f'{c:g}' for c in CATALOGUE_DIAMETRAL_MM)} mm; got {value!r} "
                       "(set joints.allow_noncatalogue = true for other values)")
            if value != 0:
                _check(value < 5.0, name, f"must be < 5 mm even off-catalogue, got {value!r}")
        _positive(self.pin_diameter_m, "pin_diameter_m", "m")
        _positive(self.bushing_length_m, "bushing_length_m", "m")
        for name in ("pin_diameters_m", "bushing_lengths_m"):
            for key, value in _joint_table(self, name):
                _positive(value, f"{name}.{key}", "m")
        for jt in JOINTS:
            _check(self.pin_diameter(jt) < 0.5, "pin_diameters_m" if jt in self.pin_diameters_m else "pin_diameter_m",
                   f"must be < 0.5 m, got {self.pin_diameter(jt)!r} at joint {jt}")
        _choice(self.initial_eccentricity, "initial_eccentricity", ("loaded", "centred"))

    def diametral_mm(self, joint: str) -> float:
        """Diametral clearance of ``joint`` ("A", "B" or "C") [mm]."""
        _choice(joint, "joint", JOINTS)
        return {"A": self.clearance_a_mm, "B": self.clearance_b_mm, "C": self.clearance_c_mm}[joint]

    def radial_m(self, joint: str) -> float:
        """Radial clearance c = (bushing radius − pin radius) of ``joint`` [m]."""
        return self.diametral_mm(joint) * 1e-3 / 2.0

    def pin_diameter(self, joint: str) -> float:
        """Pin diameter of ``joint`` [m] (``pin_diameters_m`` or the shared ``pin_diameter_m``)."""
        _choice(joint, "joint", JOINTS)
        return float(self.pin_diameters_m.get(joint, self.pin_diameter_m))

    def pin_radius(self, joint: str) -> float:
        """Pin radius R_j of ``joint`` [m]."""
        return self.pin_diameter(joint) / 2.0

    def bushing_length(self, joint: str) -> float:
        """Axial bushing length of ``joint`` [m] (``bushing_lengths_m`` or ``bushing_length_m``)."""
        _choice(joint, "joint", JOINTS)
        return float(self.bushing_lengths_m.get(joint, self.bushing_length_m))

    @property
    def pin_radius_m(self) -> float:
        """Shared pin radius [m] (``pin_diameter_m`` / 2; a joint's own: :meth:`pin_radius`)."""
        return self.pin_diameter_m / 2.0

    def bushing_radius_m(self, joint: str) -> float:
        """Bushing bore radius R_i = R_j + c of ``joint`` [m]."""
        return self.pin_radius(joint) + self.radial_m(joint)

    @property
    def clearance_joints(self) -> tuple[str, ...]:
        """Joints fitted with a bushing, in order ("A", "B", "C")."""
        return tuple(j for j in JOINTS if self.diametral_mm(j) > 0)


# ------------------------------------------------------------------------ mechanism
@dataclass(frozen=True)
class Mechanism:
    """Frame, orientation and slider guide.

    Attributes:
        orientation: bench axis that points up ("x", "y" or "z"); gravity acts along its
            negative direction. S003 tested only "y" (§2.2.3, §4.3). Default: mjcf/bench.xml
            (the axis of ``<option gravity>``).
        gravity_mps2: magnitude of gravity [m/s²]. Default: mjcf/bench.xml (source S003 §4.1).
        d_off_m: offset of C' above the slider guide centre line [m] (S003 Fig. 7).
            PLACEHOLDER: not given. Default: mjcf/bench.xml (y of pin C on the slider). The
            guide line through A is also an assumption.
        guide_friction_n: slider guide friction force whenever the slider moves [N].
            Default: mjcf/bench.xml (source S003 §3: frictionloss of the slide joint).
        crank_direction: +1 if a positive motor speed turns the crank counter-clockwise about
            +z (bench angle increasing), −1 otherwise. PLACEHOLDER: not given; +1.
    """

    orientation: str = _XML.orientation
    gravity_mps2: float = _XML.gravity_mps2
    d_off_m: float = _XML.d_off_m
    guide_friction_n: float = _XML.guide_friction_n
    crank_direction: int = 1

    def __post_init__(self) -> None:
        _choice(self.orientation, "orientation", ORIENTATIONS)
        _check(isinstance(self.gravity_mps2, (int, float)) and 0 <= self.gravity_mps2 < 100,
               "gravity_mps2", f"must lie in [0, 100) m/s^2, got {self.gravity_mps2!r}")
        _finite(self.d_off_m, "d_off_m", "m")
        _check(abs(self.d_off_m) < 0.1, "d_off_m", f"must lie in (-0.1, 0.1) m, got {self.d_off_m!r}")
        _check(isinstance(self.guide_friction_n, (int, float)) and 0 <= self.guide_friction_n < 1e3,
               "guide_friction_n", f"must lie in [0, 1000) N, got {self.guide_friction_n!r}")
        _check(self.crank_direction in (1, -1), "crank_direction",
               f"must be 1 or -1, got {self.crank_direction!r}")

    @property
    def gravity_vector(self) -> tuple[float, float, float]:
        """Gravity in the bench frame [m/s²]: −g along the vertical axis."""
        g = [0.0, 0.0, 0.0]
        g["xyz".index(self.orientation)] = -float(self.gravity_mps2)
        return (g[0], g[1], g[2])


# -------------------------------------------------------------------------- contact
@dataclass(frozen=True)
class Contact:
    """Clearance-joint contact and friction of the reference model (S003 §3, Eq. 17–20).

    Attributes:
        law: normal force law of both engines ("lankarani-nikravesh", "hunt-crossley",
            "flores", "linear" or "adams-impact"). "adams-impact" is ADAMS' IMPACT function as
            S001 (§II, Eq. 3 and 9) and S004 use it: F = K δⁿ + STEP(δ, 0, 0, d_max, c_max) δ̇
            (STEP the cubic h0 + (h1 − h0) Δ²(3 − 2Δ)), K and n as for the other laws,
            ``impact_c_max_nspm`` and ``impact_d_max_m``; ``restitution`` is not used by it.
        restitution: coefficient of restitution e [-] (S003: 0.4, tuned against the bench).
        exponent: force exponent n [-] (S003: 1.5).
        stiffness: contact stiffness K [N/m^n]; 0 = computed from the pin/bushing geometry
            and materials with Eq. 18.
        stiffnesses: per-joint K [N/m^n] where a joint's differs from ``stiffness``, keyed by
            joint ("A", "B", "C"); 0 = that joint's Eq. 18. Empty: every joint takes ``stiffness``.
        stiffness_scale: factor on the normal law's stiffness in both engines [-] (K of the
            hysteresis laws, k of the linear law, the same law in the MuJoCo twin's native
            contact and its soft first guess): the uncertainty of Eq. 18's K for
            sensitivity studies and datasets. 1 = as computed.
        mu0: dynamic friction coefficient μ0 [-] (μ_k of the "adams" friction law). Default:
            mjcf/bench.xml (source S003
            Eq. 19–20; bushing geom user data, field ``mu0`` of twin.names.BORE_USERDATA_FIELDS).
        v0_mps: friction regularization velocity below which μ = 0 [m/s]. Default:
            mjcf/bench.xml (source S003 Eq. 19–20; user data field ``v0``).
        v1_mps: velocity above which μ = μ0 [m/s]. Default: mjcf/bench.xml (source S003
            Eq. 19–20; user data field ``v1``).
        impact_c_max_nspm: maximum damping c_max of the "adams-impact" law [N s/m] (S001 Table IV:
            27 960 N s/m, the value of its e = 0.55).
        impact_d_max_m: penetration at which the "adams-impact" damping reaches c_max [m]
            (S001 Table II: 1e-5 m, CosmosMotion's recommended value).
        friction_law: clearance-joint friction law of both engines: "regularized-coulomb"
            (S003 Eq. 19–20: μ = 0 below ``v0_mps``, a linear ramp to ``mu0`` at ``v1_mps``; the
            bench's) or "adams" (the Adams/COSMOS contact friction of S001 Table II, MSC Adams
            "Contact Friction Force Calculation": with s the slip speed, μ = STEP(s, −v_s, −μ_s,
            v_s, μ_s) below the stiction transition velocity v_s = ``v_static_mps`` (an odd cubic
            through 0), STEP(s, v_s, μ_s, v_d, μ_d) up to the friction transition velocity
            v_d = ``v_kinetic_mps`` and μ_d = ``mu0`` above; STEP is the cubic
            h0 + (h1 − h0) Δ²(3 − 2Δ)). The slider guide keeps the ramp of ``v0_mps``/``v1_mps``.
        mu_static: static coefficient μ_s of the "adams" law [-] (S001 Table II: 0.08; unused by
            the regularized Coulomb law).
        v_static_mps: stiction transition velocity v_s of the "adams" law [m/s] (S001 Table II:
            "static friction vel." 0.0001 m/s).
        v_kinetic_mps: friction transition velocity v_d of the "adams" law [m/s] (S001 Table II:
            "kinetic friction vel." 0.01016 m/s); must exceed v_static_mps.
        impact_speed_floor_mps: floor of the stored impact speed δ̇⁻ of the hysteresis laws
            [m/s], used by both engines (the reference's LN damping and the MuJoCo twin's native
            impact-speed damping). A contact event that starts with δ̇ below it (resting or
            grazing contact, e.g. the "loaded" start with δ̇ = 0) uses this value: the damping
            term K δⁿ χ δ̇/δ̇⁻ would otherwise have an unbounded coefficient and make explicit
            integration unstable. PLACEHOLDER: S003 does not say what it did. 1 mm/s is measured
            (``analysis/bench_reference.py --floor``, test 12, 2 s): the smallest decade that is
            stable at h = 1e-5 s (1e-4 m/s rings at B: 794 N peak instead of 298 N, AC1 RMS 52
            instead of 32 m/s²); at h = 2.5e-6 s, where 1e-4 m/s is stable too, the two floors give
            the same impact counts, peaks within 0.3 % (B) and 0.4 % (C) and accelerometer RMS
            within 0.6 %. Larger floors change the physics of slow impacts (1e-2 m/s: 19 instead
            of 25 impacts at C; 1e-1 m/s: 49).
    """

    law: str = "lankarani-nikravesh"
    restitution: float = 0.4
    exponent: float = 1.5
    stiffness: float = 0.0
    stiffnesses: Mapping[str, float] = field(default_factory=dict)
    stiffness_scale: float = 1.0
    mu0: float = _XML.mu0
    v0_mps: float = _XML.v0_mps
    v1_mps: float = _XML.v1_mps
    impact_speed_floor_mps: float = 1e-3
    impact_c_max_nspm: float = 27960.0
    impact_d_max_m: float = 1e-5
    friction_law: str = "regularized-coulomb"
    mu_static: float = 0.08
    v_static_mps: float = 1e-4
    v_kinetic_mps: float = 0.01016

    LAWS: typing.ClassVar[tuple[str, ...]] = ("lankarani-nikravesh", "hunt-crossley", "flores", "linear",
                                              "adams-impact")
    FRICTION_LAWS: typing.ClassVar[tuple[str, ...]] = ("regularized-coulomb", "adams")

    def __post_init__(self) -> None:
        _choice(self.law, "law", self.LAWS)
        _check(isinstance(self.restitution, (int, float)) and 0 < self.restitution <= 1,
               "restitution", f"must lie in (0, 1], got {self.restitution!r}")
        _check(isinstance(self.exponent, (int, float)) and 1 <= self.exponent <= 3,
               "exponent", f"must lie in [1, 3], got {self.exponent!r}")
        _check(isinstance(self.stiffness, (int, float)) and math.isfinite(self.stiffness)
               and self.stiffness >= 0, "stiffness", f"must be >= 0 (0 = from Eq. 18), got {self.stiffness!r}")
        for key, value in _joint_table(self, "stiffnesses"):
            _check(isinstance(value, (int, float)) and math.isfinite(value) and value >= 0, f"stiffnesses.{key}",
                   f"must be >= 0 (0 = from Eq. 18), got {value!r}")
        _check(isinstance(self.stiffness_scale, (int, float)) and 0.1 <= self.stiffness_scale <= 10,
               "stiffness_scale", f"must lie in [0.1, 10], got {self.stiffness_scale!r}")
        _check(isinstance(self.mu0, (int, float)) and 0 <= self.mu0 <= 1,
               "mu0", f"must lie in [0, 1], got {self.mu0!r}")
        _positive(self.v0_mps, "v0_mps", "m/s")
        _positive(self.v1_mps, "v1_mps", "m/s")
        _check(self.v1_mps > self.v0_mps, "v1_mps", f"must exceed v0_mps ({self.v0_mps}), got {self.v1_mps!r}")
        _check(isinstance(self.impact_speed_floor_mps, (int, float)) and 1e-6 <= self.impact_speed_floor_mps <= 1,
               "impact_speed_floor_mps", f"must lie in [1e-6, 1] m/s, got {self.impact_speed_floor_mps!r}")
        _check(isinstance(self.impact_c_max_nspm, (int, float)) and math.isfinite(self.impact_c_max_nspm)
               and self.impact_c_max_nspm >= 0, "impact_c_max_nspm",
               f"must be a finite number >= 0 [N s/m], got {self.impact_c_max_nspm!r}")
        _positive(self.impact_d_max_m, "impact_d_max_m", "m")
        _choice(self.friction_law, "friction_law", self.FRICTION_LAWS)
        _check(isinstance(self.mu_static, (int, float)) and 0 <= self.mu_static <= 1,
               "mu_static", f"must lie in [0, 1], got {self.mu_static!r}")
        _positive(self.v_static_mps, "v_static_mps", "m/s")
        _positive(self.v_kinetic_mps, "v_kinetic_mps", "m/s")
        _check(self.v_kinetic_mps > self.v_static_mps, "v_kinetic_mps",
               f"must exceed v_static_mps ({self.v_static_mps}), got {self.v_kinetic_mps!r}")


    def stiffness_of(self, joint: str) -> float:
        """K given for ``joint`` [N/m^n] (``stiffnesses`` or the shared ``stiffness``); 0 = from
        Eq. 18 (:func:`joint_stiffness` resolves it)."""
        _choice(joint, "joint", JOINTS)
        return float(self.stiffnesses.get(joint, self.stiffness))


def joint_stiffness(cfg: "BenchConfig", joint: str) -> float:
    """K of ``joint``'s hysteresis law before ``stiffness_scale`` [N/m^n]: the configured one
    (:meth:`Contact.stiffness_of`) or S003 Eq. 18 from the joint's own pin, bushing and
    materials (:func:`ln_stiffness`). Both engines resolve K here."""
    return cfg.contact.stiffness_of(joint) or ln_stiffness(cfg.joints, cfg.materials, joint)


def ln_stiffness(joints: Joints, materials: Materials, joint: str) -> float:
    """Lankarani–Nikravesh stiffness K of a clearance joint (S003 Eq. 18) [N/m^1.5].

    K = 4 / (3 (h_i + h_j)) · sqrt(R_i R_j / (R_i − R_j)), bushing radius R_i > pin radius R_j.
    """
    c = joints.radial_m(joint)
    if c <= 0:
        raise ConfigError(f"joints.clearance_{joint.lower()}_mm", "is 0: no contact at an ideal joint")
    ri, rj = joints.bushing_radius_m(joint), joints.pin_radius(joint)
    h = materials.pin_of(joint).compliance_h + materials.bushing_of(joint).compliance_h
    return 4.0 / (3.0 * h) * math.sqrt(ri * rj / (ri - rj))


# --------------------------------------------------------------------------- mujoco
@dataclass(frozen=True)
class MujocoSettings:
    """Solver and contact settings of the MuJoCo twin.

    Attributes:
        integrator: MuJoCo integrator ("Euler", "implicitfast", "implicit", "RK4").
            Default: mjcf/bench.xml (``<option>``, with the reasons there), as are solver,
            iterations and tolerance.
        solver: constraint solver ("Newton", "CG", "PGS").
        iterations: maximum solver iterations.
        tolerance: solver tolerance (0 disables the early exit).
        contact_solref: pin/bushing ``solref`` (2 numbers): raw MuJoCo values of a soft contact
            that replaces the native law when given with ``contact_solimp``; empty = the
            ``contact_source``.
        contact_solimp: pin/bushing ``solimp`` (5 numbers); empty = the ``contact_source``.
        equality_solref: ``solref`` of the loop-closure ``connect`` at an ideal joint C.
            Default: mjcf/bench.xml (the ``joint_C`` connect), as is equality_solimp.
        equality_solimp: ``solimp`` of that connect.
        guide_solreffriction: ``solreffriction`` of the guide's dry friction (frictionloss).
            Default: mjcf/bench.xml (the slide joint).
        guide_friction: the slider guide's friction (``mechanism.guide_friction_n``): "native"
            (default): the reference engine's law, F ramp(|v|) against the slider's velocity
            with the ramp of ``contact.v0_mps``/``v1_mps``, a passive force of the native module
            (issue 15: MuJoCo's frictionloss constraint holds the slider at its reversals where
            the reference's friction vanishes, and shifted the 0.5-5 kHz band energy of the
            250 rpm tests by 4-6 dB); "frictionloss": MuJoCo's dry-friction constraint
            (``frictionloss`` with ``guide_solreffriction``), the base model's.
        bushing: representation of a bushing bore: "bore" (native pin-in-bore collider, exact
            circle; the default, chosen by ``analysis/bushing_representations.py``), "ring"
            (``ring_boxes`` boxes whose faces form a regular polygon tangent to the bore) or
            "tendon" (pin-bushing distance limited to c: exact, frictionless).
        ring_boxes: number of boxes of the "ring" representation.
        friction: clearance-joint friction: "native" (the reference's regularized Coulomb law
            as a passive force, default; bore only) or "cone" (MuJoCo's elliptic friction
            cone, μ0; bore or ring). A tendon bushing is frictionless whatever this says.
        contact_source: "law" (default): the bore bushing's contact force is the reference's
            own law (``contact.law``: Lankarani–Nikravesh K δⁿ (1 + χ δ̇/v_imp) with its stored
            impact speed and floor, Hunt–Crossley, Flores or linear; same K, n, e), applied
            exactly by the native module (``_bore.c``, issue 15); ring and tendon bushings,
            which the module does not serve, take the first guess. "first-guess": MuJoCo's own
            soft contact, the linear spring-damper with the LN law's duration and restitution
            at 0.1 m/s (``builder.first_guess_contact``). ``contact_solref``/``solimp`` override
            both. (Stored configurations with the retired "calibration" read as "law", and their
            retired ``contact_damping`` is dropped.)
        contact_stiffness_scale: factor on the twin's contact stiffness (the law's K, or the
            soft contact's k) [-]; 1 = the reference's. For sensitivity and stress studies.
        contact_damping_scale: factor on the twin's contact damping (the law's χ or linear c,
            or the soft contact's c) [-].
        impact_damping_gain: factor on χ of a hysteresis law [-] (1 = the reference's law).
        accelerometers: how the AC1..AC6 channels are computed: "posthoc" (default) from the
            recorded state after each rollout (qacc_k = (qvel_{k+1} − qvel_k)/h, exact to
            round-off with the Euler integrator, and the planar kinematics of the compiled chain:
            ``twin.mujoco_engine.accel``), or "sensor": MuJoCo's ``<accelerometer>`` sensors,
            which make every step run ``mj_rnePostConstraint``. Same readings to round-off
            (``tests/test_posthoc_accel.py``). "posthoc" needs the Euler integrator: with another
            integrator the run takes the sensors (``meta["accelerometers"]`` says which).
            Measured side by side (``analysis/bench_mujoco.py --repeats 5``, all channels at
            100 kHz, µs per step sensor → posthoc, the readings' cost included): ideal (test 3)
            2.19 → 1.95, C only (test 6) 2.75 → 2.57, B+C (test 12) 3.47 → 3.25 (6-12 % less; a
            whole 4 s run of test 12 spends 1.41-1.58 s in the engine instead of 1.92-2.10 s);
            README "Where a step goes".
    """

    integrator: str = _XML.integrator
    solver: str = _XML.solver
    iterations: int = _XML.iterations
    tolerance: float = _XML.tolerance
    contact_solref: tuple[float, ...] = ()
    contact_solimp: tuple[float, ...] = ()
    equality_solref: tuple[float, ...] = _XML.equality_solref
    equality_solimp: tuple[float, ...] = _XML.equality_solimp
    guide_solreffriction: tuple[float, ...] = _XML.guide_solreffriction
    guide_friction: str = "native"
    bushing: str = "bore"
    ring_boxes: int = 48
    friction: str = "native"
    contact_source: str = "law"
    contact_stiffness_scale: float = 1.0
    contact_damping_scale: float = 1.0
    impact_damping_gain: float = 1.0
    accelerometers: str = "posthoc"

    def __post_init__(self) -> None:
        _choice(self.accelerometers, "accelerometers", ("sensor", "posthoc"))
        for name in ("contact_stiffness_scale", "contact_damping_scale"):
            v = getattr(self, name)
            _check(isinstance(v, (int, float)) and 0.01 <= v <= 100, name, f"must lie in [0.01, 100], got {v!r}")
        _choice(self.integrator, "integrator", ("Euler", "implicitfast", "implicit", "RK4"))
        _choice(self.bushing, "bushing", ("bore", "ring", "tendon"))
        _check(isinstance(self.ring_boxes, int) and 8 <= self.ring_boxes <= 512, "ring_boxes",
               f"must be an integer in [8, 512], got {self.ring_boxes!r}")
        _choice(self.friction, "friction", ("native", "cone"))
        _choice(self.contact_source, "contact_source", ("law", "first-guess"))
        _choice(self.guide_friction, "guide_friction", ("native", "frictionloss"))
        _check(isinstance(self.impact_damping_gain, (int, float)) and 0.1 <= self.impact_damping_gain <= 10,
               "impact_damping_gain", f"must lie in [0.1, 10], got {self.impact_damping_gain!r}")
        _check(self.bushing == "bore" or self.friction == "cone" or self.bushing == "tendon", "friction",
               "a ring bushing takes MuJoCo's friction cone: set friction = \"cone\" (native friction needs the bore)")
        _choice(self.solver, "solver", ("Newton", "CG", "PGS"))
        _check(isinstance(self.iterations, int) and 1 <= self.iterations <= 1000,
               "iterations", f"must be an integer in [1, 1000], got {self.iterations!r}")
        _check(isinstance(self.tolerance, (int, float)) and 0 <= self.tolerance < 1,
               "tolerance", f"must lie in [0, 1), got {self.tolerance!r}")
        for name, n in (("contact_solref", 2), ("contact_solimp", 5)):
            v = getattr(self, name)
            _check(len(v) in (0, n), name, f"must hold {n} numbers or be empty (contact_source), got {list(v)!r}")
        for name, n in (("equality_solref", 2), ("equality_solimp", 5), ("guide_solreffriction", 2)):
            v = getattr(self, name)
            _check(len(v) == n, name, f"must hold {n} numbers, got {list(v)!r}")


# ---------------------------------------------------------------------------- drive
@dataclass(frozen=True)
class Drive:
    """Crank motion program tracked by the PID (S003 §2.2.2, §4.2–4.3).

    Attributes:
        program: "constant" (spin up from rest to ``motor_rpm`` and hold), "steps" (motor
            command steps ``steps_rpm`` at times ``steps_s``, each followed by the cosine ramp:
            any speed profile, e.g. the random profiles of ``twin dataset``), "protocol"
            (the 38 s three-speed test of §4.3) or "trace" (crank angle from a file).
        motor_rpm: motor speed of the constant program [rpm] (S003: 250, 500, 750).
        belt_ratio: motor:crank speed ratio of the V-belt [-] (S003 §2.2.2: 3.97).
        ramp_s: duration of each speed change (smooth cosine ramp of the speed) [s].
            PLACEHOLDER: the motor controller's acceleration is not given; 0.5 s.
        ramp_shape: shape of each speed change: "cosine" (smooth, the bench's placeholder) or
            "linear" (constant acceleration over ``ramp_s``: the inverter's set acceleration
            time of S001 §VI.B.1, "increase the motor speed linearly").
        protocol_rpm: the three motor speeds of the protocol [rpm].
        protocol_hold_s: time at each protocol speed [s] (10 s).
        protocol_stop_s: stops before, between and after the speeds [s] (2 s).
        initial_encoder_angle_rad: crank encoder angle at t = 0 [rad] (0 = crank along −y).
            PLACEHOLDER: S003 did not control the start position; 0.
        trace_file: encoder trace for the "trace" program (``.npz`` with ``t`` [s] and
            ``angle`` [rad], or ``.csv`` with those columns), encoder angle convention.
        trace_filter_hz: cutoff of the zero-phase low-pass that turns the (quantized) trace
            into the reference angle [Hz]: 4th-order Butterworth run forward and backward
            (``scipy.signal.sosfiltfilt``), so the cutoff is the −6 dB point of the combined
            filter and there is no lag. 100 Hz keeps ~30 harmonics of the fastest crank rate
            (3.15 Hz at 750 motor rpm) and removes the count quantization's broadband part.
            0 = no filtering (interpolating spline through the raw samples).
        steps_s: times of the motor command steps of the "steps" program [s].
        steps_rpm: motor speed commanded at each of those times [rpm] (0 = stop).
        mode: how the crank follows the program: "pid" (the bench's crank PID tracks the
            reference angle and rate: a finite drive stiffness, S003 §4.3) or "prescribed" (an
            infinitely stiff drive: the crank angle *is* the program, θ(t) = θ_ref(t), as the
            papers that impose the crank motion assume, S001's CosmosMotion motor, S004's
            constant 30 rad/s, S000's 5000 rpm), "motor" (the bench's drive train: the motor's
            speed loop follows the analog command of the program on its own encoder and drives
            the crank through the V-belt; parameters in ``[drivetrain]``,
            :mod:`twin.drivetrain_params`) or "torque" (the same motor and belt driven by the
            torque program ``drivetrain.torque_s``/``torque_nm``, released at
            ``drivetrain.release_s``: the program's speeds are not used). Reference engine: the crank angle is a driving
            constraint of the R-matrix model (θ and θ̇ set from the program every step, the
            other coordinates from the reduced equations with θ̈ = α_ref; the drive torque is
            the θ row's residual). MuJoCo twin: the crank turns as an infinitely heavy
            flywheel, armature A ≈ 1e9 × the crank-side inertia, driven by a dead-beat law
            A [(θ_ref(t + h) − θ)/h² − θ̇/h] that lands the next step on the program
            (integrator Euler only); the drive torque channel is that torque minus A θ̈.
            A program whose speed jumps after t = 0 (ramp_s = 0 with "steps"/"protocol") is
            refused; ramp_s = 0 with "constant" starts the mechanism at full speed at t = 0
            (consistent velocities of every body). The PID gains are not used.
        crank_rpm: crank speed of the constant program given directly [rpm], bypassing the
            motor and the belt (the papers give crank speeds; S000 runs 50–5000 rpm);
            0 = ``motor_rpm`` / ``belt_ratio`` (the bench). When nonzero, ``motor_rpm`` is not
            used and the motor command channel reads crank_rpm × belt_ratio. |crank_rpm| ≤ 6000.
    """

    program: str = "constant"
    motor_rpm: float = 750.0
    belt_ratio: float = 3.97
    ramp_s: float = 0.5
    ramp_shape: str = "cosine"
    protocol_rpm: tuple[float, ...] = (250.0, 500.0, 750.0)
    protocol_hold_s: float = 10.0
    protocol_stop_s: float = 2.0
    initial_encoder_angle_rad: float = 0.0
    trace_file: str = ""
    trace_filter_hz: float = 100.0
    steps_s: tuple[float, ...] = ()
    steps_rpm: tuple[float, ...] = ()
    mode: str = "pid"
    crank_rpm: float = 0.0

    MODES: typing.ClassVar[tuple[str, ...]] = ("pid", "prescribed", "motor", "torque")

    def __post_init__(self) -> None:
        _choice(self.program, "program", PROGRAMS)
        _choice(self.mode, "mode", self.MODES)
        _check(isinstance(self.crank_rpm, (int, float)) and math.isfinite(self.crank_rpm)
               and abs(self.crank_rpm) <= 6000, "crank_rpm",
               f"must lie in [-6000, 6000] rpm (0 = motor_rpm / belt_ratio), got {self.crank_rpm!r}")
        if self.crank_rpm != 0:
            _check(self.program == "constant", "crank_rpm",
                   f"sets the speed of the constant program only; got program = {self.program!r} (use 0)")
        if self.mode == "prescribed" and self.program in ("steps", "protocol"):
            _check(self.ramp_s > 0, "ramp_s",
                   "must be > 0 for a prescribed drive whose speed changes after t = 0 (a speed jump is an "
                   f"infinite crank acceleration), got {self.ramp_s!r}")
        _check(isinstance(self.motor_rpm, (int, float)) and math.isfinite(self.motor_rpm)
               and abs(self.motor_rpm) <= 1000, "motor_rpm",
               f"must lie in [-1000, 1000] rpm (±10 V command range), got {self.motor_rpm!r}")
        _positive(self.belt_ratio, "belt_ratio", "-")
        _check(isinstance(self.ramp_s, (int, float)) and 0 <= self.ramp_s <= 10,
               "ramp_s", f"must lie in [0, 10] s, got {self.ramp_s!r}")
        _choice(self.ramp_shape, "ramp_shape", ("cosine", "linear"))
        _check(len(self.protocol_rpm) >= 1 and all(abs(r) <= 1000 for r in self.protocol_rpm),
               "protocol_rpm", f"must hold 1+ speeds within ±1000 rpm, got {list(self.protocol_rpm)!r}")
        _check(self.protocol_hold_s > self.ramp_s, "protocol_hold_s",
               f"must exceed ramp_s ({self.ramp_s} s), got {self.protocol_hold_s!r}")
        _check(self.protocol_stop_s > self.ramp_s or self.protocol_stop_s >= 0, "protocol_stop_s",
               f"must be >= 0 s, got {self.protocol_stop_s!r}")
        _finite(self.initial_encoder_angle_rad, "initial_encoder_angle_rad", "rad")
        _check(isinstance(self.trace_filter_hz, (int, float)) and math.isfinite(self.trace_filter_hz)
               and self.trace_filter_hz >= 0, "trace_filter_hz",
               f"must be >= 0 Hz (0 = no filtering), got {self.trace_filter_hz!r}")
        if self.program == "trace":
            _check(bool(self.trace_file), "trace_file", "must name a trace file when program = \"trace\"")
        _check(len(self.steps_s) == len(self.steps_rpm), "steps_rpm",
               f"must hold one speed per time of steps_s ({len(self.steps_s)}), got {len(self.steps_rpm)}")
        if self.program == "steps":
            _check(len(self.steps_s) >= 1, "steps_s", "must hold at least one step time for program = \"steps\"")
        _check(all(isinstance(t, (int, float)) and math.isfinite(t) and t >= 0 for t in self.steps_s)
               and all(b > a for a, b in zip(self.steps_s, self.steps_s[1:])), "steps_s",
               f"must be times >= 0 s in increasing order, got {list(self.steps_s)!r}")
        _check(all(isinstance(r, (int, float)) and math.isfinite(r) and abs(r) <= 1000 for r in self.steps_rpm),
               "steps_rpm", f"must be motor speeds within ±1000 rpm, got {list(self.steps_rpm)!r}")

    @property
    def crank_rad_s(self) -> float:
        """Crank speed of the constant program [rad/s] (``crank_rpm``, or motor rpm / belt ratio)."""
        if self.crank_rpm != 0:
            return self.crank_rpm * 2.0 * math.pi / 60.0
        return self.motor_rpm / self.belt_ratio * 2.0 * math.pi / 60.0

    @property
    def protocol_duration_s(self) -> float:
        """Length of the protocol: stops and holds (38 s for the paper's protocol) [s]."""
        n = len(self.protocol_rpm)
        return (n + 1) * self.protocol_stop_s + n * self.protocol_hold_s


@dataclass(frozen=True)
class PID:
    """Crank PID tracking the reference angle and rate (native MuJoCo ``<pid>`` law).

    torque = kp (θ_ref − θ) + kv (ω_ref − ω) + ki ∫(θ_ref − θ) dt, integral clamped to ±imax.
    Gains from ``analysis/tune_pid.py`` (pole placement on the crank's largest effective
    inertia over a turn, kp sized for 0.5 encoder count of error at 750 motor rpm; see its
    docstring), rounded to two digits. Defaults: mjcf/bench.xml (the ``crank_pid`` actuator).

    Attributes:
        kp: proportional gain [N m/rad].
        kv: rate gain [N m s/rad].
        ki: integral gain [N m/(rad s)].
        imax: anti-windup clamp of the integral state [rad s]; 0 = unclamped.
    """

    kp: float = _XML.kp
    kv: float = _XML.kv
    ki: float = _XML.ki
    imax: float = _XML.imax

    def __post_init__(self) -> None:
        _positive(self.kp, "kp", "N m/rad")
        for name in ("kv", "ki", "imax"):
            v = getattr(self, name)
            _check(isinstance(v, (int, float)) and math.isfinite(v) and v >= 0,
                   name, f"must be a finite number >= 0, got {v!r}")


# -------------------------------------------------------------------------- sensors
@dataclass(frozen=True)
class AccelMount:
    """Mounting of a uniaxial accelerometer on a body (S003 Table 3, Fig. 6/9).

    Attributes:
        body: "rod" or "slider".
        position_m: position in the body frame (x along the body from its origin B or C',
            y perpendicular in the plane) [m]. PLACEHOLDER: "near the named joint".
        axis: sensitive axis in the body frame: "+x", "-x", "+y" or "-y". PLACEHOLDER signs:
            longitudinal sensors point from B to C, perpendicular and vertical ones point up
            when the rod is horizontal (calibration pose), AC6 points along +x.
    """

    body: str
    position_m: tuple[float, float]
    axis: str

    def __post_init__(self) -> None:
        _choice(self.body, "body", ("rod", "slider"))
        _check(len(self.position_m) == 2 and all(math.isfinite(v) and abs(v) < 1 for v in self.position_m),
               "position_m", f"must be [x, y] within ±1 m, got {list(self.position_m)!r}")
        _choice(self.axis, "axis", ("+x", "-x", "+y", "-y"))


def _default_mounts() -> dict[str, AccelMount]:
    """Default: mjcf/bench.xml (the AC1..AC6 sites: parent body, position, x axis; positions
    PLACEHOLDERS of S003 Table 3, "near the joint")."""
    return {name: AccelMount(m.body, m.position_m, m.axis) for name, m in _XML.accelerometers}


@dataclass(frozen=True)
class Sensors:
    """Virtual sensors and the channel groups a run computes and keeps.

    Attributes:
        accelerometers: mounting of AC1–AC6 (keys must be AC1..AC6). Default: mjcf/bench.xml
            (the AC1..AC6 sites).
        channels: channel groups to compute (subset of accel, encoder, crank, slider,
            joints, drive, and the optional energy); a scene computes only the sensors these
            need. The default is every group except the optional ones.
        output_rate_hz: sample rate of the run's channels [Hz] (the bench logs at 100 kHz).
    """

    accelerometers: Mapping[str, AccelMount] = field(default_factory=_default_mounts)
    channels: tuple[str, ...] = CHANNEL_GROUPS
    output_rate_hz: float = 100_000.0

    def __post_init__(self) -> None:
        _check(sorted(self.accelerometers) == list(ACCELEROMETERS), "accelerometers",
               f"must define exactly {', '.join(ACCELEROMETERS)}, got {', '.join(sorted(self.accelerometers))}")
        _check(len(self.channels) >= 1, "channels",
               f"must name at least one group of {', '.join(ALL_CHANNEL_GROUPS)}, got none")
        for g in self.channels:
            _choice(g, "channels", ALL_CHANNEL_GROUPS)
        _check(len(set(self.channels)) == len(self.channels), "channels", "must not repeat a group")
        _positive(self.output_rate_hz, "output_rate_hz", "Hz")
        # hashability of the frozen config: store the mapping as a read-only proxy
        object.__setattr__(self, "accelerometers", types.MappingProxyType(dict(self.accelerometers)))

    def __hash__(self) -> int:  # MappingProxyType is not hashable
        return hash((tuple(sorted(self.accelerometers.items())), self.channels, self.output_rate_hz))


# ------------------------------------------------------------------ instrumentation
#: Accelerometer models of the bench (datasheet numbers in :mod:`twin.instrument.accel`).
ACCEL_MODEL_NAMES: tuple[str, ...] = ("ADXL1001", "ADXL1002")
#: Input ranges of the MCC USB-1808X analog inputs [V] (S003 §2.3.1).
DAQ_RANGES: dict[str, tuple[float, float]] = {"+-10": (-10.0, 10.0), "+-5": (-5.0, 5.0),
                                              "0-10": (0.0, 10.0), "0-5": (0.0, 5.0)}
#: Accelerometer frequency-response models (see :class:`Instrumentation`).
ACCEL_RESPONSES: tuple[str, ...] = ("datasheet", "lowpass", "off")


def _default_accel_models() -> dict[str, str]:
    return {"AC1": "ADXL1001", "AC2": "ADXL1001", "AC3": "ADXL1001", "AC4": "ADXL1001",
            "AC5": "ADXL1002", "AC6": "ADXL1002"}


@dataclass(frozen=True)
class Instrumentation:
    """Bench sensor chain applied to simulated runs (S003 §2.3, Table 3; ``twin.instrument``).

    Accelerometer → volts: ``V = V_0g + S · a/g`` with the model's sensitivity S, then the
    frequency response, noise, range saturation and output-rail clipping; the DAQ samples all
    channels simultaneously at ``daq_rate_hz`` and quantizes them to ``adc_bits`` over
    ``daq_range``; the crank encoder counts 4× quadrature edges; the motor command voltage is
    ``command_v_per_rpm`` × the drive's motor speed command. Every stage can be switched off;
    the noise is deterministic for a given ``seed``.

    Attributes:
        models: accelerometer model per sensor ("ADXL1001": 20 mV/g, ±100 g, 30 µg/√Hz;
            "ADXL1002": 40 mV/g, ±50 g, 25 µg/√Hz; both resonate near 21 kHz).
        supply_v: accelerometer supply [V]. PLACEHOLDER: not given by S003; 5.0 V.
        zero_g_v: zero-g output voltage per sensor [V]; sensors not listed sit at mid-supply
            (supply_v / 2, the datasheet's nominal). Real sensors differ by tens of mV: this is
            what the static calibration (Eq. 1–2) measures.
        rail_margin_v: the output swings within [rail_margin_v, supply_v − rail_margin_v] [V].
            PLACEHOLDER: datasheet-typical swing limit, 0.2 V.
        response: "datasheet": second-order mechanical resonance at the model's 21 kHz with
            quality factor ``resonance_q``; its gain crosses +3 dB near 11 kHz, which is how the
            ADXL100x datasheets state the "3 dB bandwidth" (a gain, not a loss).
            "lowpass": the same pole pair at 21 kHz damped so that the response is −3 dB at the
            model's 11 kHz bandwidth (no peaking; the "DC–11 kHz at −3 dB" reading of S003).
            "off": flat.
        resonance_q: quality factor of the sensor resonance for ``response = "datasheet"`` [-].
            PLACEHOLDER: the datasheets plot the peak but do not tabulate Q; 10.
        noise: add white sensor noise of the model's density [g/√Hz] over the DAQ band.
        saturation: clip at the model's range (±100 g / ±50 g) and at the output rails.
        daq_rate_hz: simultaneous sample rate of all DAQ channels [Hz] (S003: 100 kHz). The
            simulated run must be at this rate or an integer multiple of it (decimated).
        daq_range: analog input range ("+-10", "+-5", "0-10", "0-5") [V]. PLACEHOLDER: ±10 V.
        adc_bits: ADC resolution [bit] (USB-1808X: 18).
        quantization: quantize analog inputs to adc_bits over daq_range (and clip to it).
        anti_alias: apply a causal Butterworth low-pass before sampling (the USB-1808X has none
            documented; off by default). When the run rate is a multiple of daq_rate_hz and this
            is off, decimation aliases, as a real unfiltered sampler does.
        anti_alias_hz: its −3 dB frequency [Hz]; must be below daq_rate_hz / 2.
        anti_alias_order: its order [-].
        encoder_counts_per_rev: counts per crank turn with 4× quadrature counting (SICK DGS80:
            8192 lines × 4 = 32768).
        encoder_quantization: count whole quadrature edges (off: fractional counts).
        command_v_per_rpm: motor command voltage per motor rpm [V/rpm] (±10 V ↔ ±1000 rpm).
        seed: seed of the noise generator (each sensor gets its own stream).
    """

    models: Mapping[str, str] = field(default_factory=_default_accel_models)
    supply_v: float = 5.0
    zero_g_v: Mapping[str, float] = field(default_factory=dict)
    rail_margin_v: float = 0.2
    response: str = "datasheet"
    resonance_q: float = 10.0
    noise: bool = True
    saturation: bool = True
    daq_rate_hz: float = 100_000.0
    daq_range: str = "+-10"
    adc_bits: int = 18
    quantization: bool = True
    anti_alias: bool = False
    anti_alias_hz: float = 40_000.0
    anti_alias_order: int = 4
    encoder_counts_per_rev: int = 32768
    encoder_quantization: bool = True
    command_v_per_rpm: float = 0.01
    seed: int = 0

    def __post_init__(self) -> None:
        _check(sorted(self.models) == list(ACCELEROMETERS), "models",
               f"must give a model for each of {', '.join(ACCELEROMETERS)}, got {', '.join(sorted(self.models))}")
        for k, v in self.models.items():
            _choice(v, f"models.{k}", ACCEL_MODEL_NAMES)
        _check(isinstance(self.supply_v, (int, float)) and 2.0 <= self.supply_v <= 6.0,
               "supply_v", f"must lie in [2, 6] V (ADXL100x supply), got {self.supply_v!r}")
        for k, v in self.zero_g_v.items():
            _choice(k, "zero_g_v", ACCELEROMETERS)
            _check(isinstance(v, (int, float)) and math.isfinite(v) and 0 < v < self.supply_v,
                   f"zero_g_v.{k}", f"must lie in (0, supply_v = {self.supply_v}) V, got {v!r}")
        _check(isinstance(self.rail_margin_v, (int, float)) and 0 <= self.rail_margin_v < self.supply_v / 2,
               "rail_margin_v", f"must lie in [0, supply_v/2) V, got {self.rail_margin_v!r}")
        _choice(self.response, "response", ACCEL_RESPONSES)
        _check(isinstance(self.resonance_q, (int, float)) and 0.5 <= self.resonance_q <= 1000,
               "resonance_q", f"must lie in [0.5, 1000], got {self.resonance_q!r}")
        _positive(self.daq_rate_hz, "daq_rate_hz", "Hz")
        _choice(self.daq_range, "daq_range", tuple(DAQ_RANGES))
        _check(isinstance(self.adc_bits, int) and 8 <= self.adc_bits <= 24, "adc_bits",
               f"must be an integer in [8, 24], got {self.adc_bits!r}")
        _positive(self.anti_alias_hz, "anti_alias_hz", "Hz")
        if self.anti_alias:
            _check(self.anti_alias_hz < self.daq_rate_hz / 2, "anti_alias_hz",
                   f"must lie below daq_rate_hz/2 = {self.daq_rate_hz / 2:g} Hz when anti_alias is on, "
                   f"got {self.anti_alias_hz!r}")
        _check(isinstance(self.anti_alias_order, int) and 1 <= self.anti_alias_order <= 10,
               "anti_alias_order", f"must be an integer in [1, 10], got {self.anti_alias_order!r}")
        _check(isinstance(self.encoder_counts_per_rev, int) and self.encoder_counts_per_rev >= 4,
               "encoder_counts_per_rev", f"must be an integer >= 4, got {self.encoder_counts_per_rev!r}")
        _positive(self.command_v_per_rpm, "command_v_per_rpm", "V/rpm")
        _check(isinstance(self.seed, int) and self.seed >= 0, "seed",
               f"must be an integer >= 0, got {self.seed!r}")
        object.__setattr__(self, "models", types.MappingProxyType(dict(self.models)))
        object.__setattr__(self, "zero_g_v", types.MappingProxyType(dict(self.zero_g_v)))

    def __hash__(self) -> int:  # MappingProxyType is not hashable
        return hash(tuple((f.name, tuple(sorted(v.items())) if isinstance(v, Mapping) else v)
                          for f in fields(self) for v in [getattr(self, f.name)]))

    def zero_g(self, sensor: str) -> float:
        """Zero-g output voltage of ``sensor`` [V] (mid-supply unless configured)."""
        return float(self.zero_g_v.get(sensor, self.supply_v / 2.0))


# ----------------------------------------------------------------------- simulation
@dataclass(frozen=True)
class Simulation:
    """Run settings shared by both engines.

    Attributes:
        engine: "mujoco" (the twin) or "reference" (R-matrix, Lankarani–Nikravesh).
        duration_s: simulated time [s]; 0 = the protocol's length (38 s for the paper's) with
            ``drive.program = "protocol"``. The constant and trace programs need a duration > 0
            (``twin simulate --trace FILE`` and configuration files fill in the trace's length;
            the configuration itself never reads files).
        timestep_s: integration step [s]. Default: mjcf/bench.xml (source S003 §4.3, matching
            the 100 kHz logging). It must divide the output period ``1/sensors.output_rate_hz``
            (an integer number of steps per output sample): a step that does not divide
            1/100 kHz needs the output rate set explicitly.
        chunk_s: simulated time per chunk streamed to the sinks [s] (memory per chunk grows
            with it; the result does not depend on it).
    """

    engine: str = "mujoco"
    duration_s: float = 2.0
    timestep_s: float = _XML.timestep_s
    chunk_s: float = 0.5

    def __post_init__(self) -> None:
        _choice(self.engine, "engine", ENGINES)
        _check(isinstance(self.duration_s, (int, float)) and 0 <= self.duration_s <= 3600,
               "duration_s", f"must lie in [0, 3600] s (0 = the protocol's length), got {self.duration_s!r}")
        _check(isinstance(self.timestep_s, (int, float)) and 1e-7 <= self.timestep_s <= 1e-3,
               "timestep_s", f"must lie in [1e-7, 1e-3] s, got {self.timestep_s!r}")
        _check(isinstance(self.chunk_s, (int, float)) and math.isfinite(self.chunk_s) and 1e-3 <= self.chunk_s <= 10,
               "chunk_s", f"must lie in [0.001, 10] s, got {self.chunk_s!r}")


# --------------------------------------------------------------------------- config
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

    def __post_init__(self) -> None:
        _check(isinstance(self.name, str) and 0 < len(self.name) <= 80 and _NAME_RE.fullmatch(self.name) is not None,
               "name", "must be 1-80 characters of letters, digits and . _ - + = @ , (it names the default output "
               f"file), not starting with '.'; got {self.name!r}")
        # cross-field rules: a configuration that exists can be run
        sim, sen = self.simulation, self.sensors
        if sim.duration_s == 0 and self.drive.program != "protocol":
            raise ConfigError("simulation.duration_s",
                              f"must be > 0 for the {self.drive.program} program (0 = the protocol's length); "
                              + ("--trace FILE and configuration files fill in the trace's length"
                                 if self.drive.program == "trace" else "got 0"))
        k = 1.0 / (sim.timestep_s * sen.output_rate_hz)
        stride = int(round(k))
        if stride < 1 or abs(stride - k) > 1e-6 * k:
            every = 1.0 / sim.timestep_s
            raise ConfigError("simulation.timestep_s",
                              f"{sim.timestep_s:g} s does not divide the output period 1/{sen.output_rate_hz:g} Hz; "
                              f"use a timestep of (1/output_rate)/k for an integer k, or set the output rate "
                              f"explicitly (sensors.output_rate_hz, --output-rate), e.g. {every:.10g} Hz for a "
                              "sample every step")
        if round(self.duration_s * sen.output_rate_hz) < 1:
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
        for group, engines in ENGINE_ONLY_GROUPS.items():
            if group in sen.channels and sim.engine not in engines:
                raise ConfigError("sensors.channels",
                                  f"the optional group {group!r} is produced by the {' and '.join(engines)} engine "
                                  f"only; remove it for simulation.engine = {sim.engine!r}")

    # -- derived
    @property
    def duration_s(self) -> float:
        """Simulated time of the run [s] (resolves ``simulation.duration_s = 0`` of the protocol)."""
        if self.simulation.duration_s > 0:
            return float(self.simulation.duration_s)
        return self.drive.protocol_duration_s

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
        out while it holds the defaults and the drive does not use it (crank PID, prescribed), so
        that the text and digest of such configurations are what they were before it existed."""
        out = _to_plain(self)
        if self.drive.mode in ("pid", "prescribed") and self.drivetrain == Drivetrain():
            out.pop("drivetrain", None)
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


def _to_plain(obj: Any) -> Any:
    if dataclasses.is_dataclass(obj):
        return {f.name: _to_plain(getattr(obj, f.name)) for f in fields(obj)}
    if isinstance(obj, Mapping):
        return {k: _to_plain(v) for k, v in obj.items()}
    if isinstance(obj, (tuple, list)):
        return [_to_plain(v) for v in obj]
    return obj


# ----------------------------------------------------------------- dict -> dataclass
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _convert(value: Any, tp: Any, path: str) -> Any:
    origin = typing.get_origin(tp)
    if dataclasses.is_dataclass(tp):
        if not isinstance(value, Mapping):
            raise ConfigError(path, f"must be a table of {tp.__name__} fields, got {value!r}")
        return from_dict(tp, value, path)
    if origin in (collections.abc.Mapping, dict):
        _, vt = typing.get_args(tp)
        if not isinstance(value, Mapping):
            raise ConfigError(path, f"must be a table, got {value!r}")
        return {str(k): _convert(v, vt, f"{path}.{k}") for k, v in value.items()}
    if origin is tuple:
        args = typing.get_args(tp)
        if not isinstance(value, (list, tuple)):
            raise ConfigError(path, f"must be an array, got {value!r}")
        et = args[0]
        return tuple(_convert(v, et, f"{path}[{i}]") for i, v in enumerate(value))
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(path, f"must be a number, got {value!r}")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(path, f"must be an integer, got {value!r}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(path, f"must be true or false, got {value!r}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(path, f"must be a string, got {value!r}")
        return value
    raise ConfigError(path, f"unsupported type {tp!r}")  # pragma: no cover - programming error


def from_dict(cls: type, data: Mapping[str, Any], path: str = "") -> Any:
    """Build dataclass ``cls`` from a (partial) nested dict; missing fields keep defaults.

    Unknown keys, wrong types and invalid values raise :class:`ConfigError` naming the
    dotted path.
    """
    hints = _hints(cls)
    names = [f.name for f in fields(cls)]
    prefix = f"{path}." if path else ""
    for key in data:
        if key not in names:
            raise ConfigError(f"{prefix}{key}", f"unknown field; allowed: {', '.join(names)}")
    kwargs = {}
    base = cls() if all(f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING
                        for f in fields(cls)) else None
    for f in fields(cls):
        if f.name in data:
            sub = data[f.name]
            if base is not None and isinstance(sub, Mapping):
                # a partial table overrides the default sub-config field by field
                sub = _deep_merge(_to_plain(getattr(base, f.name)), sub)
            kwargs[f.name] = _convert(sub, hints[f.name], f"{prefix}{f.name}")
    try:
        return cls(**kwargs)
    except ConfigError as err:  # raised by cls.__post_init__ with a local field name
        raise ConfigError(f"{prefix}{err.field}", err.message) from None
    except TypeError as err:
        raise ConfigError(path or cls.__name__, f"missing fields: {err}") from None


def load_config(path: str | Path) -> BenchConfig:
    """Read a TOML configuration file (partial files override the defaults).

    A file with ``drive.program = "trace"`` and no duration (or 0) gets the trace's length: the
    loader reads the trace, the configuration never does.
    """
    if not str(path):
        raise ConfigError("--config", "is empty; give a TOML configuration file")
    p = Path(path)
    try:
        raw = p.read_bytes()
    except IsADirectoryError:
        raise ConfigError("--config", f"{p} is a directory, not a TOML file") from None
    except OSError as err:
        raise ConfigError("--config", f"cannot read {p}: {err.strerror}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ConfigError("--config", f"{p} is not a UTF-8 text (TOML) file: byte {err.start} "
                                      f"is {raw[err.start:err.start + 1]!r}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ConfigError("--config", f"{p} is not valid TOML: {err}") from None
    base: dict[str, Any] = {}
    if "test" in data and "preset" in data:
        raise ConfigError("preset", "cannot be combined with test = N: give one starting point")
    if "test" in data:  # a config may start from a Table 4 preset: test = 6
        test = data.pop("test")
        base = preset(test).to_dict()
    if "preset" in data:  # or from a paper's mechanism: preset = "s001"
        base = named_preset(data.pop("preset"), "preset").to_dict()
    merged = _deep_merge(base or BenchConfig().to_dict(), data)
    drive, sim = merged.get("drive"), merged.get("simulation")
    own_sim = data.get("simulation") if isinstance(data.get("simulation"), Mapping) else {}
    no_duration = own_sim.get("duration_s", 0) == 0  # the file gives none, or 0
    if (isinstance(drive, Mapping) and isinstance(sim, Mapping) and drive.get("program") == "trace"
            and no_duration and isinstance(drive.get("trace_file"), str) and drive["trace_file"]):
        from twin.drive import trace_duration  # local import: drive imports config

        merged["simulation"] = {**sim, "duration_s": trace_duration(drive["trace_file"])}
    return from_dict(BenchConfig, merged)


def _deep_merge(a: Mapping[str, Any], b: Mapping[str, Any]) -> dict[str, Any]:
    out = dict(a)
    for k, v in b.items():
        out[k] = _deep_merge(out[k], v) if isinstance(v, Mapping) and isinstance(out.get(k), Mapping) else v
    return out


def config_from_toml(text: str) -> BenchConfig:
    """Parse a configuration from TOML text (e.g. the copy stored in a run file).

    Files written by earlier versions are migrated: ``mujoco.impact_speed_floor_mps`` is now
    ``contact.impact_speed_floor_mps`` (one floor for both engines); ``mujoco.contact_source =
    "calibration"`` (the retired calibration table) reads as "law" and the retired
    ``mujoco.contact_damping`` is dropped (the native law carries its own damping, issue 15).
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ConfigError("config", f"stored configuration is not valid TOML: {err}") from None
    mj = data.get("mujoco")
    if isinstance(mj, dict) and "impact_speed_floor_mps" in mj:
        data.setdefault("contact", {}).setdefault("impact_speed_floor_mps", mj.pop("impact_speed_floor_mps"))
    if isinstance(mj, dict):
        mj.pop("contact_damping", None)
        if mj.get("contact_source") == "calibration":
            mj["contact_source"] = "law"
    return from_dict(BenchConfig, data)


def with_overrides(cfg: BenchConfig, overrides: Mapping[str, Any]) -> BenchConfig:
    """Apply dotted-path overrides (``{"joints.clearance_b_mm": 0.1}``) and re-validate."""
    data = _to_plain(cfg)
    for dotted, value in overrides.items():
        keys = dotted.split(".")
        node = data
        for k in keys[:-1]:
            if not isinstance(node.get(k), dict):
                raise ConfigError(dotted, f"unknown section {k!r}; allowed: {', '.join(node)}")
            node = node[k]
        if keys[-1] not in node:
            raise ConfigError(dotted, f"unknown field; allowed: {', '.join(node)}")
        node[keys[-1]] = list(value) if isinstance(value, tuple) else value
    return from_dict(BenchConfig, data)


# -------------------------------------------------------------------------- presets
#: S003 Table 4: test id -> (diametral clearance B [mm], C [mm], motor speed [rpm]).
TABLE4: dict[int, tuple[float, float, float]] = {
    1: (0.0, 0.0, 250.0), 2: (0.0, 0.0, 500.0), 3: (0.0, 0.0, 750.0),
    4: (0.0, 0.1, 250.0), 5: (0.0, 0.1, 500.0), 6: (0.0, 0.1, 750.0),
    7: (0.1, 0.0, 250.0), 8: (0.1, 0.0, 500.0), 9: (0.1, 0.0, 750.0),
    10: (0.1, 0.1, 250.0), 11: (0.1, 0.1, 500.0), 12: (0.1, 0.1, 750.0),
}


def preset(test_id: int) -> BenchConfig:
    """Configuration of S003 Table 4 test ``test_id`` (1–12): clearances and a constant
    motor speed, y vertical. The 38 s protocol with the same clearances is
    ``preset(i).replace(**{"drive.program": "protocol"})``."""
    if isinstance(test_id, bool) or not isinstance(test_id, int) or test_id not in TABLE4:
        raise ConfigError("--test", f"must be a Table 4 test id 1..12, got {test_id!r}")
    b, c, rpm = TABLE4[test_id]
    base = BenchConfig()
    return dataclasses.replace(
        base,
        name=f"test{test_id}",
        joints=dataclasses.replace(base.joints, clearance_b_mm=b, clearance_c_mm=c),
        drive=dataclasses.replace(base.drive, program="constant", motor_rpm=rpm),
    )


DEFAULT_CONFIG = BenchConfig()


# ------------------------------------------------------------- other mechanisms (issue 18)
def _s001() -> BenchConfig:
    """The slider–crank rig of S001 (``../shared/seeds/001_…``, Megahed & Haroun's CAD/ADAMS
    model and experiment), 0.5 mm radial clearance at the rod–slider joint C.

    Taken from the paper:

    * Table I: crank 0.08 m, 2.37 kg, 0.01201 kg m²; rod 0.32 m, 0.72 kg, 0.0006926 kg m²;
      slider 2.28 kg. (The rod's inertia is 1/9 of a uniform bar's m l²/12 = 0.00614 kg m²;
      taken as printed.)
    * Table II: bearing (bushing bore) diameter 15.00 mm; clearance 0.5 mm, read as the
      radial clearance c (Eq. 2, δ = e − c, and Fig. 11: in contact mode the journal centre
      lies on the 0.5 mm circle), so 1.0 mm diametral here and a 14.0 mm pin; stainless
      steel E = 207 GPa, brass E = 97 GPa, ν = 0.3 (one Poisson's ratio printed, used for
      both); restitution 0.55 (found by the paper's iterations, Table IV); Adams/COSMOS
      friction μ_s = 0.08, μ_k = 0.05, static (stiction) transition velocity 1e-4 m/s,
      kinetic (friction) transition velocity 0.01016 m/s; the normal force is the
      Lankarani–Nikravesh law with n = 1.5 and K from the geometry and materials (S001
      Eq. 4–5, the twin's Eq. 18), here 3.1e10 N/m^1.5.
    * §V.A: crank 300 rpm counter-clockwise, reached from standstill in 0.2 s (§VI.B.1: the
      inverter raises the speed linearly over a set acceleration time), the slider fully
      extended along x at the start (θ = 0), journal and bearing concentric; vertical plane
      (Fig. 15/16), zero offset (§VI.A.1).
    * §VI.A.3: one slider accelerometer sampled at 5 kHz (AC6 here, along the guide).

    PLACEHOLDERs (the paper does not give them): the crank's centre of mass (a disc turning
    about its centre: x_G = 0); the rod's centre of mass (mid-length, 0.16 m); the slider's
    length, centre of mass and inertia (the bench's; the slider only translates); the bushing
    length (the bench's 20 mm); the densities (visual only: 7850 and 8500 kg/m³); the guide
    friction (a ball sleeve on "very smooth guides": 0 N); the transmission (the crank speed
    is given directly: belt ratio 1, "motor" rpm = crank rpm); the speed control (the
    inverter's vector control is modelled as the bench's crank PID tracking the ramp; the
    paper's CosmosMotion "motor" prescribes the crank motion); the rod accelerometers
    (S001 has none; AC3/AC4 moved to 0.27 m to lie on the shorter rod); the accelerometer
    (Kyowa AS-100HA, 100 g rated capacity, behind a PCD-300A interface: modelled as an
    ADXL1001 of the sensor chain, ±100 g, with the chain's 5 kHz DAQ; its frequency response is
    not given: flat, ``instrumentation.response = "off"``, which a 5 kHz run also needs, the
    ADXL's 21 kHz resonance lying above its Nyquist frequency); the run length
    (0.6 s: Fig. 15/16 span about 0.5 s).
    """
    base = BenchConfig()
    mounts = dict(base.sensors.accelerometers)
    for name in ("AC3", "AC4"):
        mounts[name] = dataclasses.replace(mounts[name], position_m=(0.27, 0.0))
    return dataclasses.replace(
        base,
        name="s001",
        bodies=Bodies(crank=BodyParams(2.37, 0.08, 0.0, 0.01201),
                      rod=BodyParams(0.72, 0.32, 0.16, 0.0006926),
                      slider=dataclasses.replace(base.bodies.slider, mass_kg=2.28, x_g_m=0.0)),
        materials=Materials(pin=Material(207e9, 0.30, 7850.0), bushing=Material(97e9, 0.30, 8500.0)),
        joints=dataclasses.replace(base.joints, clearance_b_mm=0.0, clearance_c_mm=1.0, pin_diameter_m=0.014,
                                   initial_eccentricity="centred"),
        mechanism=dataclasses.replace(base.mechanism, orientation="y", d_off_m=0.0, guide_friction_n=0.0,
                                      crank_direction=1),
        contact=dataclasses.replace(base.contact, law="lankarani-nikravesh", restitution=0.55, exponent=1.5,
                                    mu0=0.05, friction_law="adams", mu_static=0.08, v_static_mps=1e-4,
                                    v_kinetic_mps=0.01016),
        drive=dataclasses.replace(base.drive, program="constant", motor_rpm=300.0, belt_ratio=1.0, ramp_s=0.2,
                                  ramp_shape="linear", initial_encoder_angle_rad=math.pi / 2),
        sensors=dataclasses.replace(base.sensors, accelerometers=mounts, output_rate_hz=5000.0),
        simulation=dataclasses.replace(base.simulation, duration_s=0.6),
        instrumentation=dataclasses.replace(base.instrumentation, daq_rate_hz=5000.0, response="off",
                                            models={**base.instrumentation.models, "AC6": "ADXL1001"}),
    )


def _s000() -> BenchConfig:
    """The slider–crank of S000 (``../shared/seeds/000_…``, Zhang, Xu, Flores & Lankarani's Kriging/DOE
    study, MSC.ADAMS), a radial clearance at the rod–slider joint C (the "piston pin"), crank at 5000 rpm.

    S000's mechanism tables are not in the text available here. What S000 itself gives or implies:

    * the clearance joint is the piston pin (rod–slider joint C, abstract and Fig. 3b);
    * Example 1 runs the crank at a constant 5000 rpm (§5.1), clearances are radial (Tables 3 and 5);
    * the slider mass 0.14 kg: Tables 4 and 6 list a "contact force" equal to 0.136–0.14 × the slider
      acceleration, the slider's mass when the force on the slider is the joint's;
    * Table 4's smallest clearance (0.05 mm) gives 2.0e4 m/s², the ideal slider's peak r ω² (1 + r/L)
      = 1.94e4 m/s² for r = 0.05 m, L = 0.12 m at 5000 rpm: consistent with the crank and rod below.

    PLACEHOLDERs: everything else is the widely used slider–crank benchmark of Flores et al. (e.g.
    P. Flores, J. Ambrósio, J.C.P. Claro, H.M. Lankarani, C.S. Koshy, "A study on dynamics of
    mechanical systems including joints with clearance and lubrication", Mech. Mach. Theory 41 (2006)
    247–261, doi:10.1016/j.mechmachtheory.2005.10.002; Flores is S000's co-author), whose tables
    could not be read in this project (the public copies found hold only their first page): crank
    0.05 m, 0.30 kg, 1.0e-4 kg m²; rod 0.12 m, 0.21 kg, 2.5e-4 kg m²; slider 0.14 kg; journal
    (pin) radius 10 mm, bushing length 40 mm; steel E = 207 GPa, ν = 0.3 for pin and bushing;
    restitution 0.9 (Lankarani–Nikravesh law here; S000 used ADAMS' contact, whose damping it
    does not print); friction 0.03 (the bench's regularized Coulomb law with its transition
    velocities; S000: "a Coulomb-type friction ... kinetic coefficient ... constant"). Also
    PLACEHOLDERs: the centres of mass (mid-length of crank and rod, at C for the slider); the
    slider's length (the bench's 0.05 m) and inertia (1e-4 kg m², it only translates); a horizontal
    guide through A (d_off = 0), gravity along −y, no guide friction; the radial clearance 0.5 mm of
    the Flores benchmark (1.0 mm diametral here) and K from Eq. 18 (S000's studies set K directly,
    ``contact.stiffness``); the run: the crank at θ = 0 at t = 0, 0.06 s in all
    (the last 0.036 s, three turns at 5000 rpm, are the steady state), h = 1e-6 s (S000's ADAMS reported every
    1e-6 s) with 100 kHz output.

    The drive is S000's: a constant crank speed imposed on the crank (``drive.mode = "prescribed"``,
    ``drive.crank_rpm = 5000``; MuJoCo's integrator Euler, which the prescribed drive needs), from
    the start (``ramp_s = 0``: every body at its steady velocity at t = 0, the journal centred).
    """
    base = BenchConfig()
    mounts = dict(base.sensors.accelerometers)
    for name in ("AC3", "AC4"):  # on the 0.12 m rod
        mounts[name] = dataclasses.replace(mounts[name], position_m=(0.10, 0.0))
    for name in ("AC1", "AC2"):
        mounts[name] = dataclasses.replace(mounts[name], position_m=(0.02, 0.0))
    steel = Material(207e9, 0.30, 7850.0)
    return dataclasses.replace(
        base,
        name="s000",
        bodies=Bodies(crank=BodyParams(0.30, 0.05, 0.025, 1.0e-4),
                      rod=BodyParams(0.21, 0.12, 0.06, 2.5e-4),
                      slider=BodyParams(0.14, base.bodies.slider.length_m, 0.0, 1.0e-4)),
        materials=Materials(pin=steel, bushing=steel),
        joints=dataclasses.replace(base.joints, clearance_b_mm=0.0, clearance_c_mm=1.0, allow_noncatalogue=True,
                                   pin_diameter_m=0.020, bushing_length_m=0.040, initial_eccentricity="centred"),
        mechanism=dataclasses.replace(base.mechanism, orientation="y", d_off_m=0.0, guide_friction_n=0.0,
                                      crank_direction=1),
        contact=dataclasses.replace(base.contact, law="lankarani-nikravesh", restitution=0.9, exponent=1.5,
                                    stiffness=0.0, mu0=0.03),
        drive=dataclasses.replace(base.drive, program="constant", mode="prescribed", crank_rpm=5000.0, belt_ratio=1.0,
                                  motor_rpm=0.0, ramp_s=0.0, initial_encoder_angle_rad=math.pi / 2),
        mujoco=dataclasses.replace(base.mujoco, integrator="Euler"),
        sensors=dataclasses.replace(base.sensors, accelerometers=mounts),
        simulation=dataclasses.replace(base.simulation, duration_s=0.06, timestep_s=1e-6, chunk_s=0.02),
        instrumentation=dataclasses.replace(base.instrumentation, response="off"),
    )


#: S004's steel: E, ν, ρ (the paper says "steel"; PLACEHOLDER: 207 GPa, 0.3, 7850 kg/m³)
_S004_STEEL = Material(207e9, 0.30, 7850.0)


def _s004_bar(length: float, width: float, thickness: float) -> BodyParams:
    """A uniform steel bar of S004 with its joints at its ends: mass ρ L w t, centre of mass at
    mid-length, I_G = m (L² + w²)/12 about the crank axis (w in the plane of motion)."""
    m = _S004_STEEL.density_kgm3 * length * width * thickness
    return BodyParams(m, length, length / 2, m * (length ** 2 + width ** 2) / 12)


def _s004() -> BenchConfig:
    """The large slider–crank of S004 (``../shared/seeds/004_…``, Xiao, Song & Zhang 2019: the
    clearance at the crank–rod joint B as a virtual massless rod, and an ADAMS model with IMPACT
    contact), 0.5 mm clearance at B.

    Taken from the paper (§3): crank a steel bar 1000 × 100 × 50 mm, rod a steel bar
    2000 × 100 × 50 mm, slider a 500 mm steel cube; the crank turns at a constant 30 rad/s
    (prescribed: ``drive.mode = "prescribed"``, ``drive.crank_rpm`` = 286.48, ``ramp_s = 0``);
    clearance 0, 0.25 or 0.5 mm at B (read as the radial clearance c, the length of the
    virtual rod of §2.1 and the journal's free eccentricity: 0.5 mm here, 1.0 mm diametral);
    ADAMS IMPACT contact (Eq. 7–9) with d = 0.01 mm; gravity in the plane (Eq. 4: the
    potential energies of crank and rod, y vertical).

    PLACEHOLDERs (not in the paper): the steel (E 207 GPa, ν 0.3, ρ 7850 kg/m³: masses 39.25,
    78.5 and 981.25 kg); the joints at the bars' ends (crank length 1.0 m, rod 2.0 m) with the
    100 mm side in the plane of motion (I_G = m (L² + w²)/12: 3.30 and 26.23 kg m²; the
    paper's Eq. 3 uses the slender bar's m L²/3 about the end); the slider's centre of mass at
    C (a cube on its pin; it only translates); the pin diameter (50 mm, half the bar width) and
    the bushing length (50 mm, the bar thickness); the IMPACT stiffness k (the paper gives no
    number: K of Eq. 18 for the steel pin in its steel bore, 1.7e11 N/m^1.5 at 0.5 mm), its
    exponent (1.5, Hertz), and c_max (1e4 N s/m: ADAMS' default contact damping, 10 N s/mm);
    the friction (none: the paper names none; μ = 0 at B, no guide friction); the guide line
    through A (d_off = 0); the start (θ = 0, crank along the guide, journal centred, as ADAMS
    starts concentric parts; the mechanism at speed from t = 0); the run length (1 s, 4.8 turns:
    the paper plots one turn); MuJoCo's integrator Euler (the prescribed drive needs it); the
    accelerometers (S004 has none: the bench's mounts, AC6 the slider's acceleration along the
    guide).
    """
    base = BenchConfig()
    m_s = _S004_STEEL.density_kgm3 * 0.5 ** 3
    return dataclasses.replace(
        base,
        name="s004",
        bodies=Bodies(crank=_s004_bar(1.0, 0.1, 0.05), rod=_s004_bar(2.0, 0.1, 0.05),
                      slider=BodyParams(m_s, 0.5, 0.0, m_s * (0.5 ** 2 + 0.5 ** 2) / 12)),
        materials=Materials(pin=_S004_STEEL, bushing=_S004_STEEL),
        joints=dataclasses.replace(base.joints, clearance_b_mm=1.0, clearance_c_mm=0.0, pin_diameter_m=0.05,
                                   bushing_length_m=0.05, initial_eccentricity="centred"),
        mechanism=dataclasses.replace(base.mechanism, orientation="y", d_off_m=0.0, guide_friction_n=0.0,
                                      crank_direction=1),
        contact=dataclasses.replace(base.contact, law="adams-impact", exponent=1.5, stiffness=0.0,
                                    impact_c_max_nspm=1e4, impact_d_max_m=1e-5, mu0=0.0, mu_static=0.0),
        drive=dataclasses.replace(base.drive, program="constant", mode="prescribed",
                                  crank_rpm=30.0 * 60.0 / (2.0 * math.pi), ramp_s=0.0,
                                  initial_encoder_angle_rad=math.pi / 2),
        mujoco=dataclasses.replace(base.mujoco, integrator="Euler"),
        simulation=dataclasses.replace(base.simulation, duration_s=1.0),
    )


def _torque_release() -> BenchConfig:
    """The torque-driven release test S003 §6 plans: Table 4 test 12's clearances (0.1 mm at B and
    C), the motor driven by the torque program of :class:`twin.drivetrain_params.Drivetrain` (at rest
    for 2 s, 1.2 N m for 0.5 s, released at 2.5 s) through the V-belt, 10 s (the coast-down and the
    mechanism settling); channel group ``motor`` added."""
    base = preset(12)
    return dataclasses.replace(
        base, name="torque_release", drive=dataclasses.replace(base.drive, mode="torque"),
        simulation=dataclasses.replace(base.simulation, duration_s=10.0),
        sensors=dataclasses.replace(base.sensors, channels=tuple(base.sensors.channels) + ("motor",)))


def _torque_release_protocol() -> BenchConfig:
    """The protocol variant of the release test: like the 38 s speed protocol, three runs of
    increasing speed, each a spin-up at 1.2 N m (from 2, 12 and 22 s, for 0.22, 0.46 and 0.58 s:
    measured with the defaults, both engines: motor speeds of about 270, 500 and 960 rpm around each
    release, within a turn's ripple; the third depends on where the previous coast-down left the
    swinging mechanism) followed by a torque-free coast-down, 34 s in all (the torque program's zero
    steps are the releases)."""
    base = _torque_release()
    starts, spins = (2.0, 12.0, 22.0), (0.22, 0.46, 0.58)
    times = tuple(t for s0, d in zip(starts, spins) for t in (s0, s0 + d))
    torques = tuple(x for _ in starts for x in (1.2, 0.0))
    return dataclasses.replace(
        base, name="torque_release_protocol",
        drivetrain=dataclasses.replace(base.drivetrain, torque_s=times, torque_nm=torques, release_s=0.0),
        simulation=dataclasses.replace(base.simulation, duration_s=34.0))


#: Named presets of the other mechanisms of the seed papers (issue 18) and of the bench's planned
#: torque-release test: name -> builder.
NAMED_PRESETS: dict[str, typing.Callable[[], BenchConfig]] = {"s001": _s001, "s000": _s000, "s004": _s004,
                                                              "torque_release": _torque_release,
                                                              "torque_release_protocol": _torque_release_protocol}


def named_preset(name: str, field_name: str = "--preset") -> BenchConfig:
    """Configuration of a paper's mechanism (``--preset NAME``, ``preset = "NAME"`` in TOML):
    ``s001`` (S001's rig; see :func:`_s001`), ``s000`` (S000's Flores slider–crank; :func:`_s000`), ``s004`` (S004's large mechanism; :func:`_s004`), ``torque_release`` (the bench's torque-driven
    release test; :func:`_torque_release`), ``torque_release_protocol`` (three spin-ups and
    coast-downs; :func:`_torque_release_protocol`)."""
    if not isinstance(name, str) or name.lower() not in NAMED_PRESETS:
        raise ConfigError(field_name, f"must be one of {', '.join(NAMED_PRESETS)}, got {name!r}")
    return NAMED_PRESETS[name.lower()]()
