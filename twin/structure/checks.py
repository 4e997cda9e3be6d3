"""Cross-field checks of ``structure.mode = "flexible"`` (called by :class:`~twin.config.BenchConfig`)."""

from __future__ import annotations

import math

from twin.errors import ConfigError

#: the explicit step's margin: every structural mode must keep ω h within this fraction of the symplectic
#: Euler limit 2 (√(1 + ζ²) − ζ) (ζ that mode's damping ratio); 0.65 puts the limit near 20 kHz at h = 1e-5 s
STABILITY_MARGIN = 0.65


def step_limit(omega: float, zeta: float, timestep_s: float) -> float:
    """ω h / (its stability limit 2 (√(1 + ζ²) − ζ) for symplectic Euler with explicit damping) [-]."""
    return omega * timestep_s / (2.0 * (math.sqrt(1.0 + zeta * zeta) - zeta))


def check_structure(cfg) -> None:
    """ConfigError naming the field when a flexible structure cannot run as configured: the spatial
    mechanism (the flexible rod is the planar bench's), a rod Table 1 cannot split into a bar with end
    masses, a mount resonance at or above half the output rate, a mode beyond the step's stability."""
    from twin.structure.rod import modes, rod_chain

    st, h = cfg.structure, cfg.simulation.timestep_s
    if cfg.spatial.enabled:
        raise ConfigError("structure.mode", "\"flexible\" is the planar bench's structure; use \"rigid\" with "
                          "spatial.enabled = true")
    if st.mount_frequency_hz >= 0.5 * cfg.sensors.output_rate_hz:
        raise ConfigError("structure.mount_frequency_hz",
                          f"must lie below half the output rate ({0.5 * cfg.sensors.output_rate_hz:g} Hz, "
                          f"sensors.output_rate_hz), got {st.mount_frequency_hz!r}")
    chain = rod_chain(st, cfg.bodies.rod, cfg.bodies.slider.mass_kg)
    md = modes(chain, "mechanism", cfg.bodies.slider.mass_kg)
    worst = max(step_limit(2 * math.pi * f, z, h) for f, z in zip(md.frequencies_hz, md.damping_ratios))
    if worst > STABILITY_MARGIN:
        raise ConfigError("structure.rod_segments",
                          f"the rod's highest mode ({md.frequencies_hz[-1]:.0f} Hz, damping ratio "
                          f"{md.damping_ratios[-1]:.3g}) is beyond the stability margin of the step "
                          f"{h:g} s (ω h at {worst * 100:.0f} % of the limit, "
                          f"at most {STABILITY_MARGIN * 100:.0f} %): use fewer segments or axial groups, a softer "
                          "rod (rod_section_height_m, rod_section_width_m, rod_youngs_modulus_pa), "
                          "less damping or a smaller simulation.timestep_s; got "
                          f"{st.rod_segments} segments, {st.rod_axial_groups} axial groups")
    if cfg.joints.diametral_mm("B") > 0 or cfg.joints.diametral_mm("C") > 0:
        # an end in its clearance flies free between impacts: the housing on its end slide alone, the rod's free
        # modes (light end masses, i.e. housings of much rotary inertia, put them far above the mechanism's)
        fr = modes(chain, "free")
        worst = max(step_limit(2 * math.pi * f, z, h) for f, z in zip(fr.frequencies_hz, fr.damping_ratios))
        if worst > STABILITY_MARGIN:
            raise ConfigError("structure.rod_end_inertia_kgm2" if st.rod_end_inertia_kgm2 > 0 else "structure.rod_segments",
                              f"the free rod's highest mode ({fr.frequencies_hz[-1]:.0f} Hz: a clearance at B or C "
                              f"lets the rod's ends fly free) is beyond the stability margin of the step {h:g} s "
                              f"(ω h at {worst * 100:.0f} % of the limit, at most {STABILITY_MARGIN * 100:.0f} %; "
                              f"end masses {chain.split.end_b_kg:.3g} / {chain.split.end_c_kg:.3g} kg): use less "
                              "housing inertia, fewer segments or axial groups, a softer rod or a smaller "
                              f"simulation.timestep_s; got rod_end_inertia_kgm2 = {st.rod_end_inertia_kgm2!r}, "
                              f"{st.rod_segments} segments, {st.rod_axial_groups} axial groups")
    for part in ("frame", "guide"):
        f, z = getattr(st, f"{part}_frequency_hz"), getattr(st, f"{part}_damping_ratio")
        if step_limit(2 * math.pi * f, z, h) > STABILITY_MARGIN:
            raise ConfigError(f"structure.{part}_frequency_hz",
                              f"{f:g} Hz is beyond the stability margin of the step {h:g} s (ω h at most "
                              f"{STABILITY_MARGIN * 100:.0f} % of its limit); lower it or the timestep")
