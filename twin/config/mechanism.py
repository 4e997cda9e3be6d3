"""The mechanism's parameters: bodies (S003 Table 1), materials (Table 2), joints and their
clearances, frame and guide, and the clearance-joint contact law (S003 §3, Eq. 17–20)."""

from __future__ import annotations

import dataclasses
import math
import typing
from dataclasses import dataclass, field
from typing import Mapping

from twin.config.common import (CATALOGUE_DIAMETRAL_MM, JOINTS, ORIENTATIONS, XML_DEFAULTS, _check, _choice,
                                _bounded, _finite, _joint_table, _positive, check_types)
from twin.errors import ConfigError


# --------------------------------------------------------------------------- bodies
#: smallest clearance accepted off the catalogue [mm diametral]
MIN_CLEARANCE_MM = 1e-3
#: pin (journal) diameter [m], upper end open, and bushing length [m] of a bench-sized joint
PIN_DIAMETER_M = (1e-3, 0.5)
BUSHING_LENGTH_M = (1e-3, 0.5)
#: friction transition velocities of the contact laws [m/s]
TRANSITION_MPS = (1e-9, 10.0)


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

        check_types(self)
        # bounds of a body of a bench-sized mechanism (beyond these the model is no slider-crank, and a
        # mass of 1e300 kg overflows the contact forces)
        _bounded(self.mass_kg, "mass_kg", *MASS_KG, "kg", "a body of a bench-sized mechanism: 0.1 g to 1 t")
        _bounded(self.length_m, "length_m", *LENGTH_M, "m", "a link of a bench-sized mechanism: 1 mm to 10 m")
        _bounded(self.x_g_m, "x_g_m", -LENGTH_M[1], LENGTH_M[1], "m", "within a bench-sized mechanism")
        _bounded(self.inertia_kgm2, "inertia_kgm2", 0.0, 1e3, "kg m^2", "a bench-sized body", lo_open=True)
        # inertia consistent with the mass: the radius of gyration k = sqrt(I/m) of a rigid body of a
        # bench-sized mechanism, between 0.1 mm (a 1 mm link is no thinner) and 10 m (the longest link)
        k = math.sqrt(self.inertia_kgm2 / self.mass_kg)
        _check(GYRATION_M[0] <= k <= GYRATION_M[1], "inertia_kgm2",
               f"must give a radius of gyration sqrt(I/m) in [{GYRATION_M[0]:g}, {GYRATION_M[1]:g}] m with mass_kg = "
               f"{self.mass_kg!r} (a rigid body of a bench-sized mechanism), got {self.inertia_kgm2!r} "
               f"(sqrt(I/m) = {k:.3g} m)")


#: bounds of the bodies: mass [kg], length [m] and radius of gyration about the centre of mass [m]
MASS_KG = (1e-4, 1e3)
LENGTH_M = (1e-3, 10.0)
GYRATION_M = (1e-4, 10.0)


@dataclass(frozen=True)
class Bodies:
    """The three moving bodies (S003 Table 1; crank includes shaft and pulley).

    Default: mjcf/bench.xml (source S003 Table 1: each body's ``<inertial>`` mass, pos x and
    diaginertia z; lengths from pin B's x, bushing C's x and the slider block's length).
    """

    crank: BodyParams = BodyParams(**dataclasses.asdict(XML_DEFAULTS.crank))
    rod: BodyParams = BodyParams(**dataclasses.asdict(XML_DEFAULTS.rod))
    slider: BodyParams = BodyParams(**dataclasses.asdict(XML_DEFAULTS.slider))

    def __post_init__(self) -> None:
        check_types(self)


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

        check_types(self)
        # real engineering materials: soft elastomers (~1 MPa) to diamond (1.05e12 Pa); the isotropic elastic
        # range of Poisson's ratio; aerogel-like foams (~10 kg/m^3) to osmium (22 590 kg/m^3)
        _bounded(self.youngs_modulus_pa, "youngs_modulus_pa", 1e6, 1.2e12, "Pa",
                 "real engineering materials: soft elastomers 1 MPa to diamond 1.05e12 Pa")
        _bounded(self.poisson, "poisson", -1.0, 0.5, "", "an isotropic elastic solid", lo_open=True, hi_open=True)
        _bounded(self.density_kgm3, "density_kgm3", 10.0, 3e4, "kg/m^3", "real solids: foams to osmium 22 590 kg/m^3")

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

        check_types(self)
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
            mechanism of the seeds may have a clearance there too. At A the pin is
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
        clearance_guide_mm: two-sided clearance of the slider guide [mm]: the total transverse
            play of the slider between its two rails (S003 §2.2.1 names it; the paper's model
            leaves it out). 0 = the preloaded ideal linear guide (pure translation, S003 §3).
            Otherwise the slider gains its transverse position and tilt, and its front and rear
            ends (``guide_span_m`` apart) each touch the upper or the lower rail through the
            joints' contact law and friction (docs/guide.md). Any value in [0, 5) mm (no catalogue).
        guide_span_m: distance between the slider's front and rear contact points along the
            guide [m]. PLACEHOLDER: S003 gives the slider's length, 0.05 m (Table 1), not its
            shoe spacing; the default takes that length.
        guide_edge_radius_m: radius of curvature of the slider's contact edges on the flat
            rails [m], for the contact stiffness (S003 Eq. 18 in the limit of a flat rail,
            R_i → ∞: K = 4/(3(h_i + h_j)) √R_j, slider and rails of the pin's steel).
            PLACEHOLDER: not given; 0.01 m (the journal's default radius).
    """

    clearance_b_mm: float = 0.0
    clearance_c_mm: float = 0.0
    clearance_a_mm: float = 0.0
    allow_noncatalogue: bool = False
    pin_diameter_m: float = XML_DEFAULTS.pin_diameter_m
    bushing_length_m: float = XML_DEFAULTS.bushing_length_m
    pin_diameters_m: Mapping[str, float] = field(default_factory=dict)
    bushing_lengths_m: Mapping[str, float] = field(default_factory=dict)
    initial_eccentricity: str = "loaded"
    clearance_guide_mm: float = 0.0
    guide_span_m: float = 0.05
    guide_edge_radius_m: float = 0.01

    #: guide fields left out of the TOML text while they hold these defaults (so that the text and
    #: digest of a configuration without a guide clearance are what they were before they existed)
    GUIDE_DEFAULTS: typing.ClassVar[dict[str, float]] = {
        "clearance_guide_mm": 0.0, "guide_span_m": 0.05, "guide_edge_radius_m": 0.01}

    def __post_init__(self) -> None:

        check_types(self)
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
                # below the surfaces' roughness and the contact's own penetration (0.1-0.5 um) a
                # clearance is no gap: the joint is a ball bearing (0)
                _check(value >= MIN_CLEARANCE_MM, name, f"must be 0 (ball bearing) or at least {MIN_CLEARANCE_MM:g} mm "
                       f"(1 um) even off-catalogue, got {value!r}")
        why = "a journal of a bench-sized joint: 1 mm to 0.5 m"
        _bounded(self.pin_diameter_m, "pin_diameter_m", *PIN_DIAMETER_M, "m", why, hi_open=True)
        _bounded(self.bushing_length_m, "bushing_length_m", *BUSHING_LENGTH_M, "m", "a bushing of a bench-sized joint")
        for name, (lo, hi) in (("pin_diameters_m", PIN_DIAMETER_M), ("bushing_lengths_m", BUSHING_LENGTH_M)):
            for key, value in _joint_table(self, name):
                _bounded(value, f"{name}.{key}", lo, hi, "m", "a bench-sized joint", hi_open=name == "pin_diameters_m")
        for jt in JOINTS:
            # the clearance a bushing can hold: its bore at most twice the pin (Eq. 18's conformal contact of a pin
            # in a bore of nearly its size; a 1 mm pin in a 5 mm bore is no journal bearing)
            d_mm = getattr(self, f"clearance_{jt.lower()}_mm")
            _check(d_mm / 1000.0 < self.pin_diameter(jt), f"clearance_{jt.lower()}_mm",
                   f"must be below the joint's pin diameter ({self.pin_diameter(jt) * 1000:g} mm: a bore at most twice "
                   f"the pin), got {d_mm!r}")
        _choice(self.initial_eccentricity, "initial_eccentricity", ("loaded", "centred"))
        g = self.clearance_guide_mm
        _check(isinstance(g, (int, float)) and not isinstance(g, bool) and math.isfinite(g) and 0 <= g < 5.0,
               "clearance_guide_mm", f"must be 0 (ideal preloaded guide) or a clearance in (0, 5) mm, got {g!r}")
        _bounded(self.guide_span_m, "guide_span_m", 1e-3, 1.0, "m", "the shoes of a bench-sized slider")
        _bounded(self.guide_edge_radius_m, "guide_edge_radius_m", 1e-4, 1.0, "m",
                 "a crowned edge: 0.1 mm to a nearly flat 1 m")

    @property
    def guide_radial_m(self) -> float:
        """Half the guide's play: the slider's free transverse travel each way from the centre [m]."""
        return self.clearance_guide_mm * 1e-3 / 2.0

    @property
    def guide_play(self) -> bool:
        """True when the guide has a clearance (the slider's transverse position and tilt are free)."""
        return self.clearance_guide_mm > 0

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

    orientation: str = XML_DEFAULTS.orientation
    gravity_mps2: float = XML_DEFAULTS.gravity_mps2
    d_off_m: float = XML_DEFAULTS.d_off_m
    guide_friction_n: float = XML_DEFAULTS.guide_friction_n
    crank_direction: int = 1

    def __post_init__(self) -> None:

        check_types(self)
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
            "flores", "linear", "adams-impact" or "johnson-cylindrical"). "adams-impact" is ADAMS' IMPACT function as
            S001 (§II, Eq. 3 and 9) and S004 use it: F = K δⁿ + STEP(δ, 0, 0, d_max, c_max) δ̇
            (STEP the cubic h0 + (h1 − h0) Δ²(3 − 2Δ)), K and n as for the other laws,
            ``impact_c_max_nspm`` and ``impact_d_max_m``; ``restitution`` is not used by it.
            "johnson-cylindrical" is the elastic force of a pin of length L in its bore (Johnson,
            Contact Mechanics, 1985, §5.6): δ = (F/k)[ln(4 ΔR k/F) − 1], k = π L E*, ΔR the radial
            clearance (:func:`twin.contact_params.johnson_elastic_force`), with the
            Lankarani–Nikravesh damping F_e (1 + 3(1 − e²)/4 · δ̇/δ̇⁻) of ``restitution``; its
            stiffness grows with the bushing length, where Eq. 18's K ignores it. ``exponent``
            is not used by it; ``stiffness``, if set, is its k [N/m].
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
    mu0: float = XML_DEFAULTS.mu0
    v0_mps: float = XML_DEFAULTS.v0_mps
    v1_mps: float = XML_DEFAULTS.v1_mps
    impact_speed_floor_mps: float = 1e-3
    impact_c_max_nspm: float = 27960.0
    impact_d_max_m: float = 1e-5
    friction_law: str = "regularized-coulomb"
    mu_static: float = 0.08
    v_static_mps: float = 1e-4
    v_kinetic_mps: float = 0.01016

    LAWS: typing.ClassVar[tuple[str, ...]] = ("lankarani-nikravesh", "hunt-crossley", "flores", "linear",
                                              "adams-impact", "johnson-cylindrical")
    FRICTION_LAWS: typing.ClassVar[tuple[str, ...]] = ("regularized-coulomb", "adams")

    def __post_init__(self) -> None:

        check_types(self)
        _choice(self.law, "law", self.LAWS)
        _check(isinstance(self.restitution, (int, float)) and 0 < self.restitution <= 1,
               "restitution", f"must lie in (0, 1], got {self.restitution!r}")
        _check(isinstance(self.exponent, (int, float)) and 1 <= self.exponent <= 3,
               "exponent", f"must lie in [1, 3], got {self.exponent!r}")
        # a given K must be a contact's: a load of 1 N penetrates between 1 pm and 1 mm (K in [1e3^n, 1e12^n]
        # N/m^n; steel and bronze joints: 1e9-1e11 at n = 1.5); 1e-300 would let a pin sink through its bushing
        n = 1.0 if self.law in ("linear", "johnson-cylindrical") else self.exponent
        lo, hi = 1e3 ** n, 1e12 ** n
        for name, value in (("stiffness", self.stiffness), *((f"stiffnesses.{k}", v)
                                                             for k, v in _joint_table(self, "stiffnesses"))):
            ok = isinstance(value, (int, float)) and math.isfinite(value) and (value == 0 or lo <= value <= hi)
            _check(ok, name, f"must be 0 (from Eq. 18) or lie in [{lo:.3g}, {hi:.3g}] N/m^{n:g} (a contact that 1 N "
                             f"presses between 1 pm and 1 mm deep), got {value!r}")
        _check(isinstance(self.stiffness_scale, (int, float)) and 0.1 <= self.stiffness_scale <= 10,
               "stiffness_scale", f"must lie in [0.1, 10], got {self.stiffness_scale!r}")
        _check(isinstance(self.mu0, (int, float)) and 0 <= self.mu0 <= 1,
               "mu0", f"must lie in [0, 1], got {self.mu0!r}")
        why = "a friction transition velocity: 1 nm/s to 10 m/s"
        _bounded(self.v0_mps, "v0_mps", *TRANSITION_MPS, "m/s", why)
        _bounded(self.v1_mps, "v1_mps", *TRANSITION_MPS, "m/s", why)
        _check(self.v1_mps > self.v0_mps, "v1_mps", f"must exceed v0_mps ({self.v0_mps}), got {self.v1_mps!r}")
        _check(isinstance(self.impact_speed_floor_mps, (int, float)) and 1e-6 <= self.impact_speed_floor_mps <= 1,
               "impact_speed_floor_mps", f"must lie in [1e-6, 1] m/s, got {self.impact_speed_floor_mps!r}")
        _bounded(self.impact_c_max_nspm, "impact_c_max_nspm", 0.0, 1e9, "N s/m",
                 "a contact's damping: S001's steel joint has 27 960 N s/m")
        _bounded(self.impact_d_max_m, "impact_d_max_m", 1e-9, 1e-2, "m", "a contact penetration: 1 nm to 10 mm")
        _choice(self.friction_law, "friction_law", self.FRICTION_LAWS)
        _check(isinstance(self.mu_static, (int, float)) and 0 <= self.mu_static <= 1,
               "mu_static", f"must lie in [0, 1], got {self.mu_static!r}")
        _bounded(self.v_static_mps, "v_static_mps", *TRANSITION_MPS, "m/s", why)
        _bounded(self.v_kinetic_mps, "v_kinetic_mps", *TRANSITION_MPS, "m/s", why)
        _check(self.v_kinetic_mps > self.v_static_mps, "v_kinetic_mps",
               f"must exceed v_static_mps ({self.v_static_mps}), got {self.v_kinetic_mps!r}")
        # a law's own fields are used by that law only: set under another law they would be ignored
        for names, field_of, law in ((("mu_static", "v_static_mps", "v_kinetic_mps"), "friction_law", "adams"),
                                     (("impact_c_max_nspm", "impact_d_max_m"), "law", "adams-impact")):
            if getattr(self, field_of) == law:
                continue
            for name in names:
                default = self.__dataclass_fields__[name].default
                _check(getattr(self, name) == default, name,
                       f"is used by {field_of} = {law!r} only, not {getattr(self, field_of)!r}; leave it out or set "
                       f"it back to its default {default!r}, got {getattr(self, name)!r}")


    def stiffness_of(self, joint: str) -> float:
        """K given for ``joint`` [N/m^n] (``stiffnesses`` or the shared ``stiffness``); 0 = from
        Eq. 18 (:func:`twin.config.joint_stiffness` resolves it)."""
        _choice(joint, "joint", JOINTS)
        return float(self.stiffnesses.get(joint, self.stiffness))


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


def guide_stiffness(joints: Joints, materials: Materials) -> float:
    """Contact stiffness K of the slider's ends on the guide rails [N/m^n] (the joints' law and
    exponent): S003 Eq. 18 in the limit of a flat rail (bushing radius R_i → ∞),
    K = 4 / (3 (h_i + h_j)) · √R_j with R_j = ``joints.guide_edge_radius_m`` and slider and rail
    of the pin's steel (h = (1 − ν²)/E each): the Hertz point contact of a crowned edge on a flat.
    PLACEHOLDER geometry (the edge radius); the papers give no guide contact data."""
    pin = materials.pin_of("C")
    return 4.0 / (3.0 * 2.0 * pin.compliance_h) * math.sqrt(joints.guide_edge_radius_m)
