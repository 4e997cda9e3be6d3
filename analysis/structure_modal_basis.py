"""The reference engine's modal rod (``reference.rod_model = "modal"``, :mod:`twin.reference.flexible_modal`): its
constant-mass basis against the closed forms, with more shapes and with the housings' rotary inertia.

The reference's flexible step with the chain costs ~5× its rigid step (``analysis/profile_reference_flexible.py``):
24 coordinates with 10 constraint rows in the acceleration solve and 12 chain rows in the projection. The modal rod
keeps the natural-coordinate machinery (a constant, block-diagonal mass matrix; only the rigid model's rows):

    r(ξ) = B' + ξ (C − B') + Σ_k φ_k(ξ) u_k,     ξ = x/L ∈ [0, 1],

B', C the housings' centres (as the rigid model's rod, with its chord length free: the stretch), u_k ∈ R² one global
2-vector per shape φ_k (φ_k(0) = φ_k(1) = 0). r is linear in the coordinates, so the kinetic energy of the bar (mass
per length μ) and the end masses m_B, m_C is a constant quadratic form, the same for x and y (two 5 × 5 blocks with
three shapes). The elastic energy in the rod's frame (ê = (C − B')/|C − B'|):

    V = ½ (EA/L) (|C − B'| − L)² + Σ_k [½ k_b,k |u_k|² + ½ (k_a,k − k_b,k) (u_k·ê)²],
    k_a,k = EA ∫φ_k'² dx,  k_b,k = EI ∫φ_k''² dx,

bending along n̂ = R₉₀ ê and axial along ê, no constraint rows added: the rows of the acceleration solve are the rigid
model's (3 for Table 4 test 12 against 10 for the chain) and the projection is the rigid model's closed form. With
φ_k = sin(kπξ) (the pinned–pinned beam's and the fixed–fixed bar's own shapes, ∫φ_k' φ_j' = 0 for k ≠ j and against the
chord's linear field) the stiffness is diagonal. The housings' rotary inertia J_e (0 by default) would enter as
½ J_e |ṫ|², t = r'(0)/L (constant too), which also counts the axial components' slope: measured below.

This script computes the basis's linearized frequencies (the same boundary conditions as
:func:`twin.structure.rod.modes`: "mechanism" — B pinned, C on the guide with the slider's mass — and the free rod) and
compares them with :mod:`twin.structure.closed_forms` for the default rod and the explore range's corners; and the
highest frequency against the explicit step's limit ω h < 2. Writes
``analysis/results/structure/modal_basis.md``. Run: ``python analysis/structure_modal_basis.py`` (seconds).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
from scipy.linalg import eigh

from twin.provenance import write_stamped_text


def basis_matrices(split, ea: float, ei: float, shapes: int, slope_inertia: bool = True):
    """(M, Ka, Kb) of :func:`twin.reference.flexible_modal.modal_matrices` (per direction over [B', C, u_1 … u_n]), with
    the housings' rotary inertia J_e read through the end slopes when ``slope_inertia`` (½ J_e (ẇ'(0)² + ẇ'(L)²))."""
    from twin.reference.flexible_modal import modal_matrices

    M, Ka, Kb = modal_matrices(split, ea, ei, shapes)
    if slope_inertia and split.end_inertia_kgm2 > 0.0:   # slopes d/dx = (d/dξ) / L of (1 − ξ, ξ, sin kπξ)
        L = split.length_m
        d0 = [-1.0, 1.0] + [k * math.pi for k in range(1, shapes + 1)]
        d1 = [-1.0, 1.0] + [k * math.pi * math.cos(k * math.pi) for k in range(1, shapes + 1)]
        M = M + split.end_inertia_kgm2 / (L * L) * (np.outer(d0, d0) + np.outer(d1, d1))
    return M, Ka, Kb


def frequencies(split, ea, ei, slider_kg, shapes, axial_slope_inertia):
    """bending 1–3 (pinned–pinned: B', C fixed across), axial 1 (B fixed, C with the slider), free axial 1, highest
    (free rod, either direction) [Hz]."""
    M, Ka, Kb = basis_matrices(split, ea, ei, shapes)
    Ma, _, _ = basis_matrices(split, ea, ei, shapes, slope_inertia=axial_slope_inertia)
    hz = lambda w2: np.sqrt(np.maximum(w2, 0.0)) / (2.0 * math.pi)  # noqa: E731
    bend = hz(eigh(Kb[2:, 2:], M[2:, 2:], eigvals_only=True))[:3]
    Mm = Ma.copy()
    Mm[1, 1] += slider_kg
    idx = [1] + list(range(2, Ma.shape[0]))
    ax = hz(eigh(Ka[np.ix_(idx, idx)], Mm[np.ix_(idx, idx)], eigvals_only=True))[0]
    free = hz(eigh(Ka, Ma, eigvals_only=True))
    highest = max(free[-1], hz(eigh(Kb + 1e-9 * np.eye(len(Kb)), M, eigvals_only=True))[-1])
    return bend, ax, free[1], highest


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "structure" / "modal_basis.md"))
    args = ap.parse_args()
    import dataclasses

    from twin.config import BenchConfig
    from twin.structure import closed_forms as cf
    from twin.structure.rod import rod_split

    base = BenchConfig()
    rod, slider_kg = base.bodies.rod, base.bodies.slider.mass_kg
    h = base.simulation.timestep_s
    cases = [(0.0, 0.030), (0.0, 0.015), (0.0, 0.045), (5e-4, 0.030), (2e-3, 0.045), (2e-3, 0.030)]
    lines = ["Modal rod basis [chord B'–C + u_k sin(kπξ)] against the closed forms, % error (Euler–Bernoulli "
             "pinned–pinned with the housings' rotary inertia J_e; axial: B fixed with the end mass and the slider at "
             "C, and the free rod with its end masses). Columns 'axial, slope inertia': the housings' J_e read through "
             "the end tangent, which also counts the shapes' axial slope (a spurious axial inertia).", "",
             "| J_e [kg m²] | height [m] | shapes | bending 1 | bending 2 | bending 3 | axial (B fixed) | free axial "
             "| axial, slope inertia | free axial, slope inertia | highest [Hz] | ω_max h |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for je, height in cases:
        st = dataclasses.replace(base.structure, mode="flexible", rod_end_inertia_kgm2=je,
                                 rod_section_height_m=height)
        sp = rod_split(rod.mass_kg, rod.length_m, rod.x_g_m, rod.inertia_kgm2, je)
        mu, L = sp.bar_mass_kg / sp.length_m, sp.length_m
        ref_b = cf.bending_pinned_end_inertia_hz(st.rod_ei_nm2, mu, L, je, 3) if je > 0.0 else \
            [cf.bending_pinned_hz(st.rod_ei_nm2, mu, L, k) for k in (1, 2, 3)]
        ref_a = cf.axial_fixed_mass_hz(st.rod_ea_n, mu, L, sp.end_c_kg + slider_kg, 1)[0]
        ref_f = cf.axial_free_masses_hz(st.rod_ea_n, mu, L, sp.end_b_kg, sp.end_c_kg, 1)[0]
        for shapes in (3, 4, 6):
            b, a, fa, hi = frequencies(sp, st.rod_ea_n, st.rod_ei_nm2, slider_kg, shapes, False)
            _, a2, fa2, _ = frequencies(sp, st.rod_ea_n, st.rod_ei_nm2, slider_kg, shapes, True)
            e = lambda x, r: f"{(x / r - 1.0) * 100.0:+.3f}"  # noqa: E731
            lines.append(f"| {je:g} | {height:g} | {shapes} | {e(b[0], ref_b[0])} | {e(b[1], ref_b[1])} | "
                         f"{e(b[2], ref_b[2])} | {e(a, ref_a)} | {e(fa, ref_f)} | {e(a2, ref_a)} | {e(fa2, ref_f)} | "
                         f"{hi:.0f} | {2 * math.pi * hi * h:.2f} |")
    lines += ["", f"Step h = {h:g} s (explicit limit ω h < 2). Closed forms: twin.structure.closed_forms "
              "(the chain's tests' basis)."]
    text = "\n".join(lines) + "\n"
    print(text)
    print(f"wrote {write_stamped_text(args.out, text)}")


if __name__ == "__main__":
    main()
