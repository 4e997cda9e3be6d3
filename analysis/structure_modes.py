"""The flexible rod's discrete modes against the closed forms, and their convergence with the number of segments.

Prints, for the default ``[structure]`` (S003 Table 1 rod split into a 2.04 kg bar and 0.754 kg ends, 30 × 14 mm
steel section): the first four bending modes (B and C pinned; Euler–Bernoulli with the ends' rotary inertia) and the
first axial mode (B fixed, the end mass and the 1.97 kg slider at C) of the chain for N = 4 … 24 segments and
M axial groups, with their relative errors, the highest mode of the chain (the explicit step's limit) and the same
with housings of 5e-4 kg m² each: the uniform chain (``rod_chain = "uniform"``) and the tuned one (the default: outer
segments' length and hinge stiffnesses solved for the first three bending modes, axial springs for the first axial
mode, :func:`twin.structure.tuned_parameters`), the latter also with the free rod's first axial mode (end masses). Closed forms: :mod:`twin.structure.closed_forms`; chain: :mod:`twin.structure.rod`.

Run: ``python analysis/structure_modes.py``.
"""

from __future__ import annotations

from twin.config import BenchConfig, StructureConfig
from twin.structure import (axial_fixed_mass_hz, axial_free_masses_hz, bending_pinned_end_inertia_hz, modes,
                            rod_split, tuned_parameters, undamped_chain)


def table(end_inertia: float) -> None:
    cfg = BenchConfig()
    rod, slider = cfg.bodies.rod, cfg.bodies.slider.mass_kg
    st = StructureConfig()
    sp = rod_split(rod.mass_kg, rod.length_m, rod.x_g_m, rod.inertia_kgm2, end_inertia)
    mu = sp.bar_mass_kg / sp.length_m
    ref_b = bending_pinned_end_inertia_hz(st.rod_ei_nm2, mu, sp.length_m, end_inertia, 4)
    ref_a = axial_fixed_mass_hz(st.rod_ea_n, mu, sp.length_m, sp.end_c_kg + slider, 1)[0]
    print(f"\nend housings' inertia {end_inertia:g} kg m^2: bar {sp.bar_mass_kg:.4f} kg, ends {sp.end_b_kg:.4f} kg")
    print("closed forms: bending " + ", ".join(f"{f:.1f}" for f in ref_b) + f" Hz; axial {ref_a:.1f} Hz")
    ref_f = axial_free_masses_hz(st.rod_ea_n, mu, sp.length_m, sp.end_b_kg, sp.end_c_kg, 1)[0]
    print(f"free rod's first axial mode with its end masses: {ref_f:.1f} Hz")
    print(f"{'chain':>7s} {'N':>3s} {'M':>2s} | {'bending errors [%] (modes 1-4)':>34s} | {'axial [%]':>9s} | "
          f"{'free ax [%]':>11s} | {'highest [Hz]':>12s}")
    rows = [("uniform", n, m) for n, m in ((4, 2), (6, 2), (6, 3), (8, 2), (8, 4), (12, 2), (12, 3), (24, 2), (24, 6))]
    rows += [("tuned", n, m) for n, m in ((4, 1), (4, 2), (6, 2), (8, 2))]
    for kind, n, m in rows:
        ch = undamped_chain(sp, st.rod_ea_n, st.rod_ei_nm2, n, m, tuned=kind == "tuned", tip_mass_kg=slider)
        md = modes(ch, "mechanism", slider)
        b = md.of_kind("bending")
        eb = [100 * (b[i] / ref_b[i] - 1) if i < len(b) else float("nan") for i in range(4)]
        ea = 100 * (md.of_kind("axial")[0] / ref_a - 1)
        ef = 100 * (modes(ch, "free").of_kind("axial")[0] / ref_f - 1)
        print(f"{kind:>7s} {n:3d} {m:2d} | " + " ".join(f"{e:+8.3f}" for e in eb) + f" | {ea:+9.3f} | {ef:+11.3f} | "
              f"{md.frequencies_hz[-1]:12.0f}")
        if kind == "tuned":
            tu = tuned_parameters(sp, st.rod_ea_n, st.rod_ei_nm2, n, m, slider)
            print(f"{'':>14s}   outer segments {tu.outer_fraction:.4f} L, hinges x {tu.k_outer:.4f} (outer) "
                  f"x {tu.k_inner:.4f} (inner), axial springs x {tu.k_axial:.4f}")


if __name__ == "__main__":
    table(0.0)
    table(5e-4)
