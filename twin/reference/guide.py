r"""The slider guide's two-sided clearance in the reference engine (numba kernels).

With ``joints.clearance_guide_mm`` > 0 the slider gains two coordinates of the natural-coordinate
model (:mod:`twin.natural_coordinates`): its transverse position y_g (q[10], the pin C' at
(x'_C, d_off + y_g)) and its tilt φ (q[11], about +z). Its front and rear contact points, the
ends of its shoe on the guide line (half span a = ``guide_span_m`` / 2), sit at

    p± = C' + R(φ) (±a, −d_off),   p±_y = y_g ± a sin φ + d_off (1 − cos φ)   (guide line y = 0)

between an upper rail at y = +c_g and a lower one at y = −c_g (c_g half the play). Each end
touches at most one rail: penetration δ = p_y − c_g (upper, force −f_N ŷ on the slider) or
−c_g − p_y (lower, +f_N ŷ), δ̇ its rate. f_N is the joints' hysteresis law (Lankarani–Nikravesh,
Hunt–Crossley or Flores as configured; with the linear or the ADAMS IMPACT law the guide uses
Lankarani–Nikravesh) with the guide's stiffness K_g (:func:`twin.config.mechanism.guide_stiffness`)
and its own contact events (impact speed stored per end). Friction: the joints' friction law
on the end's sliding speed ṗ_x (the rails are fixed): f_T along x. The guide's own friction
(``mechanism.guide_friction_n``, 2.5 N) acts on x'_C as with the ideal guide, contact or not.

Generalized forces of F = (F_x, F_y) at p±: F_x on x'_C, F_y on y_g, and
F_x ∂p_x/∂φ + F_y ∂p_y/∂φ on φ, ∂p/∂φ = (∓a sin φ + d_off cos φ, ±a cos φ + d_off sin φ).

The slider's mass matrix on (x'_C, y_g, φ) (centre of mass at C' + R(φ)(x_G, −d_off)) is taken at
φ = 0: m₃ on x'_C and y_g, I_C' = I_G + m₃ (x_G² + d_off²) on φ, couplings m₃ d_off (x'_C, φ) and
m₃ x_G (y_g, φ). The tilt stays below c_g / a (2e-3 rad for 0.1 mm over 50 mm), so the neglected
terms are O(φ) of the couplings. Gravity acts exactly (its moment m₃ g · ∂G/∂φ on φ).
"""

from __future__ import annotations

import math

from twin.jit import njit

from twin.natural_coordinates import (P_C_G, P_DOFF, P_E, P_FRIC_LAW, P_GA, P_GX, P_GY, P_K_G, P_LAW, P_M3, P_MU0,
                                      P_MUS, P_N, P_S3D, P_S3X, P_V0, P_V1, P_VD, P_VMIN, P_VS)
from twin.physics.contact import adams_friction_force, friction_force, normal_force

#: outputs of :func:`guide_forces` (``jout``): y_g, φ, then per end (front, rear) the normal
#: force along +y on the slider (positive: from the lower rail), the friction force along +x
N_GUIDE_OUT = 6


@njit(cache=True)
def guide_law_code(law):
    """The guide's normal law: the configured hysteresis law, else Lankarani–Nikravesh."""
    return law if law <= 2 else 0


@njit(cache=True)
def guide_forces(P, q, qd, cst, jout, Q):
    """Add the guide's gravity on y_g and φ and its two end contacts to Q; ``cst`` = [in, v_imp]
    of the front end then the rear end (updated), ``jout`` the outputs (:data:`N_GUIDE_OUT`)."""
    c, a, d = P[P_C_G], P[P_GA], P[P_DOFF]
    cf, sf = math.cos(q[11]), math.sin(q[11])
    gx, gy = P[P_GX], P[P_GY]
    Q[10] += P[P_M3] * gy
    Q[11] += gx * (-P[P_S3X] * sf + P[P_S3D] * cf) + gy * (P[P_S3X] * cf + P[P_S3D] * sf)
    jout[0] = q[10]
    jout[1] = q[11]
    law = guide_law_code(int(P[P_LAW]))
    for e in range(2):
        s = a if e == 0 else -a
        dpx = -s * sf + d * cf
        dpy = s * cf + d * sf
        py = q[10] + s * sf + d * (1.0 - cf)
        vx = qd[6] + qd[11] * dpx
        vy = qd[10] + qd[11] * dpy
        if py > c:
            delta, ddelta, sgn = py - c, vy, -1.0
        elif py < -c:
            delta, ddelta, sgn = -c - py, -vy, 1.0
        else:
            delta, ddelta, sgn = 0.0, 0.0, 0.0
        i = 2 * e
        if delta > 0.0:
            if cst[i] < 0.5:
                cst[i] = 1.0
                cst[i + 1] = ddelta if ddelta > P[P_VMIN] else P[P_VMIN]
            fn = normal_force(law, delta, ddelta, cst[i + 1], P[P_K_G], P[P_N], P[P_E], 0.0, 1e-5)
        else:
            cst[i] = 0.0
            fn = 0.0
        if fn <= 0.0:
            fn = 0.0
            ft = 0.0
        elif P[P_FRIC_LAW] > 0.5:
            ft = adams_friction_force(vx, fn, P[P_MUS], P[P_MU0], P[P_VS], P[P_VD])
        else:
            ft = friction_force(vx, fn, P[P_MU0], P[P_V0], P[P_V1])
        Fx, Fy = ft, sgn * fn
        jout[2 + e] = Fy
        jout[4 + e] = Fx
        Q[6] += Fx
        Q[10] += Fy
        Q[11] += Fx * dpx + Fy * dpy
