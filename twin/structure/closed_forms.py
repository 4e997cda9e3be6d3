"""Closed forms of a uniform bar's in-plane vibration, the independent basis of the discrete rod's checks.

Euler–Bernoulli bending (E I w'''' + μ ẅ = 0) and the axial bar (E A u'' = μ ü), μ = m/L the bar's mass per
length. The frequency equations below are derived from the continuum with its boundary conditions; their
roots are found by bracketing sign changes of the equation on a fine grid and refining with Brent's method
(scipy.optimize.brentq). Nothing here knows the discrete model of :mod:`twin.structure.rod`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq


def bending_pinned_hz(ei: float, mu: float, length: float, n: int) -> float:
    """n-th bending frequency of a pinned–pinned uniform bar f_n = (nπ/L)² √(EI/μ) / 2π [Hz]."""
    return (n * math.pi / length) ** 2 * math.sqrt(ei / mu) / (2.0 * math.pi)


def _roots(fun, x_max: float, count: int, samples: int = 20000) -> list[float]:
    """The first ``count`` roots of fun on (0, x_max] by sign changes on a grid, refined by brentq."""
    xs = np.linspace(1e-6, x_max, samples)
    vals = np.array([fun(x) for x in xs])
    out: list[float] = []
    for i in range(len(xs) - 1):
        a, b = vals[i], vals[i + 1]
        if a == 0.0:
            out.append(float(xs[i]))
        elif a * b < 0.0 and math.isfinite(a) and math.isfinite(b):
            root = brentq(fun, xs[i], xs[i + 1], xtol=1e-14, rtol=1e-14)
            if abs(fun(root)) < 1e-6 * (abs(a) + abs(b)):  # a sign change through a pole is no root
                out.append(float(root))
        if len(out) == count:
            return out
    raise ValueError(f"found {len(out)} of {count} roots below {x_max:g}")


def bending_pinned_end_inertia_hz(ei: float, mu: float, length: float, end_inertia: float,
                                  count: int) -> list[float]:
    """The first ``count`` bending frequencies [Hz] of a uniform bar pinned at both ends with a rotary
    inertia J at each end (the end housings turn with the bar's slope there; point masses at pinned ends
    do not move).

    w = a sin κx + b cos κx + c sinh κx + d cosh κx, ω² = κ⁴ EI/μ. Boundary conditions (from the
    Lagrangian ∫ ½μẇ² − ½EI w''² dx + ½J (ẇ'(0)² + ẇ'(L)²)): w(0) = w(L) = 0,
    EI w''(0) = −J ω² w'(0), EI w''(L) = +J ω² w'(L); the frequencies make the 4×4 determinant vanish.
    Written in λ = κL and j = J/(μL³): EI κ² w'' terms over EI κ, J ω² = j μ L³ κ⁴ EI/μ.
    """
    j = end_inertia / (mu * length ** 3)

    def det(lam: float) -> float:
        # rows in units where x = ξL, derivatives d/dξ; w'' / w' ratios: EI w''/L² = ∓ J ω² w'/L
        # → w''(ξ) = ∓ j λ⁴ w'(ξ)  (J ω² L / EI = j λ⁴)
        s, c, sh, ch = math.sin(lam), math.cos(lam), math.sinh(lam), math.cosh(lam)
        g = j * lam ** 4
        # w(ξ) = a sin λξ + b cos λξ + c sinh λξ + d cosh λξ
        # w'  = λ(a cos − b sin + c cosh + d sinh), w'' = λ²(−a sin − b cos + c sinh + d cosh)
        m = np.array([
            [0.0, 1.0, 0.0, 1.0],                                        # w(0) = 0
            [s, c, sh, ch],                                              # w(1) = 0
            [lam ** 2 * 0.0 + g * lam * 1.0, lam ** 2 * -1.0, g * lam * 1.0, lam ** 2 * 1.0],  # w''(0) + g w'(0) = 0
            [lam ** 2 * -s - g * lam * c, lam ** 2 * -c + g * lam * s,
             lam ** 2 * sh - g * lam * ch, lam ** 2 * ch - g * lam * sh],  # w''(1) − g w'(1) = 0
        ])
        return float(np.linalg.det(m)) / math.cosh(lam) ** 2
    lams = _roots(det, (count + 1.5) * math.pi, count)
    return [(lam / length) ** 2 * math.sqrt(ei / mu) / (2.0 * math.pi) for lam in lams]


def axial_fixed_mass_hz(ea: float, mu: float, length: float, tip_mass: float, count: int) -> list[float]:
    """The first ``count`` axial frequencies [Hz] of a uniform bar fixed at x = 0 carrying a mass at x = L:
    u = sin(βx/L), EA u'(L) = m ω² u(L) gives β tan β = μL/m, ω = β √(EA/μ) / L."""
    alpha = mu * length / tip_mass
    # roots of β cos β ... written without poles: α cos β − β sin β = 0
    betas = _roots(lambda b: alpha * math.cos(b) - b * math.sin(b), (count + 1) * math.pi, count)
    return [b * math.sqrt(ea / mu) / length / (2.0 * math.pi) for b in betas]


def axial_free_masses_hz(ea: float, mu: float, length: float, mass0: float, mass1: float,
                         count: int) -> list[float]:
    """The first ``count`` elastic axial frequencies [Hz] of a free uniform bar with point masses m₀, m₁ at
    its ends: u = a cos kx + b sin kx, m₀ ü(0) = EA u'(0), m₁ ü(L) = −EA u'(L); with β = kL, r_i = m_i/(μL):
    the 2×2 determinant [[r₀β, 1], [cos β − r₁β sin β, ... ]] vanishes (written out below)."""
    r0, r1 = mass0 / (mu * length), mass1 / (mu * length)

    def det(b: float) -> float:
        # −m0 ω² u(0) = EA u'(0): −r0 β² a·(1/L)... in ξ = x/L: u'(ξ) = β(−a sin βξ + b cos βξ)
        # ξ = 0: −r0 β² a = β b  → r0 β a + b = 0
        # ξ = 1: r1 β² u(1) = β u'(1)/1 → r1 β (a cos β + b sin β) − (−a sin β + b cos β) = 0
        m = np.array([[r0 * b, 1.0],
                      [r1 * b * math.cos(b) + math.sin(b), r1 * b * math.sin(b) - math.cos(b)]])
        return float(np.linalg.det(m))
    betas = _roots(det, (count + 1) * math.pi, count)
    return [b * math.sqrt(ea / mu) / length / (2.0 * math.pi) for b in betas]
