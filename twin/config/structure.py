"""The bench's structure: a flexible connecting rod, compliant supports and the accelerometers' mounts.

``mode = "rigid"`` (the default) is the twin as it always was: every body rigid, the frame and the
guide fixed, the accelerometers read the body at their site. ``mode = "flexible"`` (both engines,
the same discrete model, :mod:`twin.structure`):

* the connecting rod bends in the mechanism's plane and stretches along its axis: a chain of
  ``rod_segments`` rigid segments joined by elastic hinges (bending) and of ``rod_axial_groups``
  groups of segments joined by elastic slides (axial), between two end bodies (the bushing
  housings at B and C). Table 1's rod (mass, centre of mass, inertia about it) is kept exactly:
  its mass is split into a uniform bar and the two end masses by the three equations of mass,
  first and second moment (:func:`twin.structure.rod_split`); the section and the modulus set
  the stiffness;
* the crank's support (the frame at A) and the slider's support (the guide rails, normal to the
  guide) are lumped oscillators: a participating mass on a spring and a damper to the ground;
* structural damping: stiffness-proportional (Rayleigh β) on the rod's hinges and slides, set by
  the damping ratio of the first bending and the first axial mode;
* each accelerometer sits on a mount, a base-excited second-order oscillator (the sensor weighs
  grams: one-way coupled), discretized exactly at the output rate.

Every number the papers do not give is a PLACEHOLDER with a physical default and the range a
user should explore (:data:`EXPLORE_RANGES`). What the papers give (S003 Table 1, 3): the rod's
3.55 kg, 0.60 m, x_G 0.30 m and I_G 0.197 kg m² — more than a uniform bar's m L²/12 = 0.1065, so
mass sits at the ends: 2.04 kg of uniform bar and 0.754 kg at each end reproduce all three.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from twin.config.common import _bounded, _check, _choice, check_types

#: structure modes
STRUCTURE_MODES: tuple[str, ...] = ("rigid", "flexible")
#: the rod chain's shapes (:func:`twin.structure.undamped_chain`)
ROD_CHAINS: tuple[str, ...] = ("tuned", "uniform")


@dataclass(frozen=True)
class StructureConfig:
    """Structure of the bench (see the module docstring for the model; SI units).

    Attributes:
        mode: "rigid" (every body rigid, supports fixed, sensors read the body directly: the
            twin as it was) or "flexible" (the flexible rod, compliant supports, damped
            structure and sensor mounts below). The other fields are used by "flexible" only.
        rod_section_height_m: depth of the rod's section in the mechanism's plane [m] (sets the
            in-plane bending stiffness E b h³/12). PLACEHOLDER: 0.030; with the width 0.014 and
            the 2.04 kg of bar that Table 1 implies the bar's density is 8100 kg/m³ (steel), and
            it bends at ≈ 0.19/0.77/1.73/3.1 kHz pinned–pinned. Explore 0.015 – 0.045.
        rod_section_width_m: thickness of the rod's section normal to the plane [m] (axial
            stiffness E b h). PLACEHOLDER: 0.014, explore 0.008 – 0.030.
        rod_youngs_modulus_pa: Young's modulus of the rod [Pa]. PLACEHOLDER: 210e9 (steel; the
            pins are F125 steel, S003 Table 2); aluminium 70e9 has nearly the same E/ρ, so the
            section, not the material, sets the modes. Explore 70e9 – 215e9.
        rod_end_inertia_kgm2: rotary inertia of each end housing about its own centre (the
            bore) [kg m²]; it reduces the inertia left to the bar and the end masses, and lowers
            the bending modes (the housing turns with the rod's slope at its end). PLACEHOLDER: 0
            (Table 1 is met by point end masses; a 0.75 kg housing of ≈ 35 mm outer radius
            would hold ≈ 5e-4, which lowers the third mode by 12 %). The chain turns each housing
            with its end segment's chord, which underestimates the housings' effect: the uniform
            chain with N = 6 and 5e-4 has the second mode 1 % high, the third 6 % (convergence with
            N in docs/structure.md); the tuned chain (the default) is solved against the closed form
            with this inertia and meets its first three modes. Explore 0 – 2e-3.
        rod_segments: number N of rigid segments of the rod's bending chain [-] (hinges at the
            N − 1 interior nodes). Numerical: the tuned chain (``rod_chain``) reproduces the first
            three bending modes exactly from 4 segments (the default); the uniform chain needs 6 for
            them within 0.8 % (error ≈ (nπ/N)⁴/1440), 8 for four. The highest mode must stay below
            the explicit stability limit of the step. Range 2 – 24 (4 – 24 tuned).
        rod_axial_groups: number M of axially rigid groups of segments [-] (must divide N): an
            elastic slide at each end and between groups, each holding the bar's compliance between
            two neighbouring mass centres. Numerical: 2 (the default) gives the first axial mode with
            B fixed and the slider at C exactly (tuned) or within ≈ 0.4 % (uniform), and the free
            rod's within 1 % (tuned; uniform 1.35 %); 1 misses the free rod's by 20 %. Range 1 – N.
        rod_chain: "tuned" (the default) or "uniform". Uniform: equal segments, hinges E I / l,
            axial springs E A over the distance between neighbouring mass centres. Tuned: the two
            outer segments' length and the hinges' stiffness (outermost two, the others) solved at
            the model's build so that the chain's first three bending modes (B pinned, C held normal
            to the rod) equal Euler–Bernoulli's with the housings' inertia, and the axial springs
            scaled so that its first axial mode (B fixed, the end mass and the slider at C) equals
            the continuum's (:func:`twin.structure.tuned_parameters`). Numerical, no placeholder.
        bending_damping_ratio: damping ratio ζ of the rod's first bending mode (pinned–pinned)
            [-]; stiffness-proportional on the hinges (c = β k, β = 2 ζ / ω₁), so mode n has
            ζ (ω_n/ω₁). PLACEHOLDER: 0.01 (a bolted steel link), explore 0.002 – 0.05.
        axial_damping_ratio: damping ratio ζ of the rod's first axial mode (B fixed, the end
            mass and the slider at C) [-], stiffness-proportional on the slides.
            PLACEHOLDER: 0.01, explore 0.002 – 0.05.
        frame_mass_kg: participating mass of the crank's support (the frame at A) [kg]: the crank
            pivot sits on it, it moves in the plane on an isotropic spring and damper to ground.
            PLACEHOLDER: 8, explore 2 – 40.
        frame_frequency_hz: natural frequency of that mass on its spring alone [Hz].
            PLACEHOLDER: 600, explore 150 – 3000.
        frame_damping_ratio: its damping ratio [-]. PLACEHOLDER: 0.05, explore 0.01 – 0.2.
        guide_mass_kg: participating mass of the slider's support (guide rails and carriage)
            [kg]: it moves normal to the guide on a spring and damper; the slider rides on it.
            PLACEHOLDER: 3, explore 0.5 – 20.
        guide_frequency_hz: natural frequency of that mass on its spring alone [Hz].
            PLACEHOLDER: 1500 (a preloaded profile rail, ≈ 3e8 N/m), explore 300 – 5000.
        guide_damping_ratio: its damping ratio [-]. PLACEHOLDER: 0.05, explore 0.01 – 0.2.
        mount_frequency_hz: natural frequency of each accelerometer on its mount [Hz] (the
            ADXL1001/1002 boards screwed or glued to the bodies; the sensor's own ~21 kHz
            resonance is the sensor chain's, not this). PLACEHOLDER: 12000, explore 4000 – 30000;
            below half the output rate.
        mount_damping_ratio: damping ratio of the mount [-]. PLACEHOLDER: 0.05, explore
            0.01 – 0.3.
    """

    mode: str = "rigid"
    rod_section_height_m: float = 0.030
    rod_section_width_m: float = 0.014
    rod_youngs_modulus_pa: float = 210e9
    rod_end_inertia_kgm2: float = 0.0
    rod_segments: int = 4
    rod_axial_groups: int = 2
    rod_chain: str = "tuned"
    bending_damping_ratio: float = 0.01
    axial_damping_ratio: float = 0.01
    frame_mass_kg: float = 8.0
    frame_frequency_hz: float = 600.0
    frame_damping_ratio: float = 0.05
    guide_mass_kg: float = 3.0
    guide_frequency_hz: float = 1500.0
    guide_damping_ratio: float = 0.05
    mount_frequency_hz: float = 12000.0
    mount_damping_ratio: float = 0.05

    def __post_init__(self) -> None:

        check_types(self)
        _choice(self.mode, "mode", STRUCTURE_MODES)
        _bounded(self.rod_section_height_m, "rod_section_height_m", 0.003, 0.2, "m", "the rod's in-plane depth")
        _bounded(self.rod_section_width_m, "rod_section_width_m", 0.002, 0.2, "m", "the rod's thickness")
        _bounded(self.rod_youngs_modulus_pa, "rod_youngs_modulus_pa", 1e9, 1e12, "Pa",
                 "a structural metal or composite")
        _bounded(self.rod_end_inertia_kgm2, "rod_end_inertia_kgm2", 0.0, 0.05, "kg m^2",
                 "the housings' own inertia; Table 1's rod must keep a bar of positive mass")
        _check(isinstance(self.rod_segments, int) and not isinstance(self.rod_segments, bool)
               and 2 <= self.rod_segments <= 24, "rod_segments",
               f"must be an integer in [2, 24] (4 tuned or 6 uniform resolve three bending modes to 1 %), "
               f"got {self.rod_segments!r}")
        _choice(self.rod_chain, "rod_chain", ROD_CHAINS)
        _check(self.rod_chain == "uniform" or self.rod_segments >= 4, "rod_segments",
               f"must be at least 4 with rod_chain = \"tuned\" (three bending modes need three elastic hinges; "
               f"rod_chain = \"uniform\" takes 2 - 3), got {self.rod_segments!r}")
        n, m = self.rod_segments, self.rod_axial_groups
        _check(isinstance(m, int) and not isinstance(m, bool) and 1 <= m <= n and n % m == 0, "rod_axial_groups",
               f"must be an integer in [1, {n}] dividing rod_segments ({n}), got {m!r}")
        for name in ("bending_damping_ratio", "axial_damping_ratio"):
            _bounded(getattr(self, name), name, 0.0, 0.2, "", "structural damping of a metal link")
        for part, mass_hi in (("frame", 1000.0), ("guide", 1000.0)):
            _bounded(getattr(self, f"{part}_mass_kg"), f"{part}_mass_kg", 0.0, mass_hi, "kg",
                     "a participating mass", lo_open=True)
            _bounded(getattr(self, f"{part}_frequency_hz"), f"{part}_frequency_hz", 10.0, 20000.0, "Hz",
                     "a support's natural frequency below the step's stability limit")
            _bounded(getattr(self, f"{part}_damping_ratio"), f"{part}_damping_ratio", 0.0, 1.0, "",
                     "at most critical", hi_open=True)
        _bounded(self.mount_frequency_hz, "mount_frequency_hz", 500.0, 100000.0, "Hz",
                 "a sensor mount's resonance; below half the output rate, checked with it")
        _bounded(self.mount_damping_ratio, "mount_damping_ratio", 0.0, 1.0, "", "at most critical", lo_open=True)

    # -- derived (SI)
    @property
    def flexible(self) -> bool:
        """True in ``mode = "flexible"``."""
        return self.mode == "flexible"

    @property
    def rod_area_m2(self) -> float:
        """Cross-section area A = b h of the rod's bar [m²]."""
        return self.rod_section_width_m * self.rod_section_height_m

    @property
    def rod_second_moment_m4(self) -> float:
        """Second moment of area for in-plane bending I = b h³ / 12 [m⁴]."""
        return self.rod_section_width_m * self.rod_section_height_m ** 3 / 12.0

    @property
    def rod_ea_n(self) -> float:
        """Axial stiffness E A [N]."""
        return self.rod_youngs_modulus_pa * self.rod_area_m2

    @property
    def rod_ei_nm2(self) -> float:
        """In-plane bending stiffness E I [N m²]."""
        return self.rod_youngs_modulus_pa * self.rod_second_moment_m4

    @staticmethod
    def support_stiffness(mass_kg: float, frequency_hz: float) -> float:
        """Spring of a lumped support k = m (2π f)² [N/m]."""
        return mass_kg * (2.0 * math.pi * frequency_hz) ** 2

    @staticmethod
    def support_damping(mass_kg: float, frequency_hz: float, ratio: float) -> float:
        """Damper of a lumped support c = 2 ζ m (2π f) [N s/m]."""
        return 2.0 * ratio * mass_kg * 2.0 * math.pi * frequency_hz


#: the placeholders' ranges a user should explore (their documentation above), as (factor name, field,
#: description, (low, high)): for the dataset factors and the stability campaign
EXPLORE_RANGES: tuple[tuple[str, str, str, tuple[float, float]], ...] = (
    ("rod_section_height_m", "rod_section_height_m", "rod section depth in the plane [m]", (0.015, 0.045)),
    ("rod_section_width_m", "rod_section_width_m", "rod section thickness [m]", (0.008, 0.030)),
    ("rod_youngs_modulus_pa", "rod_youngs_modulus_pa", "rod Young's modulus [Pa]", (70e9, 215e9)),
    ("rod_end_inertia_kgm2", "rod_end_inertia_kgm2", "rod end housing inertia [kg m^2]", (0.0, 2e-3)),
    ("bending_damping_ratio", "bending_damping_ratio", "first bending mode damping ratio [-]", (0.002, 0.05)),
    ("axial_damping_ratio", "axial_damping_ratio", "first axial mode damping ratio [-]", (0.002, 0.05)),
    ("frame_mass_kg", "frame_mass_kg", "crank support participating mass [kg]", (2.0, 40.0)),
    ("frame_frequency_hz", "frame_frequency_hz", "crank support natural frequency [Hz]", (150.0, 3000.0)),
    ("frame_damping_ratio", "frame_damping_ratio", "crank support damping ratio [-]", (0.01, 0.2)),
    ("guide_mass_kg", "guide_mass_kg", "guide support participating mass [kg]", (0.5, 20.0)),
    ("guide_frequency_hz", "guide_frequency_hz", "guide support natural frequency [Hz]", (300.0, 5000.0)),
    ("guide_damping_ratio", "guide_damping_ratio", "guide support damping ratio [-]", (0.01, 0.2)),
    ("mount_frequency_hz", "mount_frequency_hz", "accelerometer mount natural frequency [Hz]", (4000.0, 30000.0)),
    ("mount_damping_ratio", "mount_damping_ratio", "accelerometer mount damping ratio [-]", (0.01, 0.3)),
)
