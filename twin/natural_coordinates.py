r"""Natural-coordinate model of the slider-crank: coordinates, constraints, velocity transformation
(R-matrix) and mass matrix (S003 §3, Eq. 11–16).

Neutral ground of the two engines: the reference engine (:mod:`twin.reference.model`: forces,
equations of motion, integration) steps it, and the contact parameters
(:mod:`twin.contact_params`) take from it the effective mass a clearance joint sees, which the
linear contact law of both engines needs.

Coordinates (S003 Eq. 14, extended by the crank journal), bench frame of :mod:`twin.config`
(the frame's bore centre A at the origin)::

    q = [x_B, y_B, x'_B, y'_B, x_C, y_C, x'_C, θ, x_A, y_A, y_g, φ]    indices 0..11   (N_Q = 12)

* A' = (x_A, y_A): centre of the crank's journal at the ground pivot A (crank body 1; the
  bushing at A is the frame's bore, fixed, centred at the origin);
* B = (x_B, y_B): centre of the crank pin (crank body 1);
* B' = (x'_B, y'_B): centre of the rod's eye at B (rod body 2, origin of the rod frame);
* C = (x_C, y_C): centre of the rod's eye at C (rod body 2);
* C' = (x'_C, d_off + y_g): centre of the slider pin (slider body 3 translates on the guide
  y = 0 through A; C' is ``d_off`` above it);
* θ: crank bench angle from +x (direction A' → B);
* y_g, φ: the slider's transverse position and tilt in a guide with clearance
  (``joints.clearance_guide_mm``, :mod:`twin.reference.guide`); 0 with the ideal guide.

Pins sit on the crank (the journal A', the pin B) and on the slider (C'); bushings are the
frame's bore (A) and the rod eyes (B', C). A' and θ sit at the end of q so that the indices of
the S003 coordinates are those of the eight-coordinate model that had A fixed.

Equations. Twelve rows, always the same (the "augmented" set)::

    0  (x_B − x_A)² + (y_B − y_A)² − r²      crank length      constraint
    1  (x_B − x_A) sin θ − (y_B − y_A) cos θ crank angle       constraint
    2  (x_C − x'_B)² + (y_C − y'_B)² − l²    rod length        constraint
    3  x_B − x'_B        = e_Bx          pair B (Eq. 15)  constraint (= 0) or independent
    4  y_B − y'_B        = e_By          pair B (Eq. 15)  constraint (= 0) or independent
    5  x'_C − x_C        = e_Cx          pair C (Eq. 16)  constraint (= 0) or independent
    6  d_off + y_g − y_C = e_Cy          pair C (Eq. 16)  constraint (= 0) or independent
    7  θ                                 crank angle              independent
    8  x_A               = e_Ax          pair A           constraint (= 0) or independent
    9  y_A               = e_Ay          pair A           constraint (= 0) or independent
    10 y_g                               guide            constraint (= 0) or independent
    11 φ                                 guide            constraint (= 0) or independent

An ideal joint keeps its two pair rows as constraints (nine constraints, one degree of
freedom, S003 §3: A' is then held at the origin and the model is S003's). A clearance joint
drops them from the constraint set and uses the same two expressions — the eccentricity
e = pin − bushing in the bench frame, the "relative journal position" — as independent
coordinates, next to θ; its contact is a force element. q itself never changes. Independent
coordinates z, in this order: θ, then e_A, e_B, e_C of the joints that have a clearance, then
y_g, φ with a guide clearance (r = 1 … 9). With the ideal guide rows 10–11 hold y_g = φ = 0 and
every product skips or adds exact zeros: runs are bit-identical to the ten-coordinate model.

Crank angle equation. S003 writes θ "as a function of x_B or y_B": x_B = r cos θ is
singular with the crank length row where y_B = 0, y_B = r sin θ where x_B = 0, so a code
must switch between them during a turn. Row 1 uses both at once: with d = B − A',
d_x sin θ − d_y cos θ = 0 (d parallel to (cos θ, sin θ)). Together with row 0 the crank block
[[2d_x, 2d_y], [sin θ, −cos θ]] (in the unknowns Ḃ − Ȧ') has determinant
−2(d_x cos θ + d_y sin θ) = −2r: never singular over a turn, and smooth (no switching). The rod
block is singular only with the rod perpendicular to the guide, which the bench's geometry
(l > r + |d_off| + the clearances) excludes.

Velocity transformation (S003 Eq. 11–13). With A(q) the 12×12 Jacobian of the twelve rows
(constant rows 3–11), A q̇ = [0, 0, 0, ė_B or 0, ė_C or 0, θ̇, ė_A or 0, ẏ_g, φ̇ or 0]: the columns of
R = A⁻¹[0; I] belonging to the independent rows give q̇ = R ż with Φ_q R = 0, and
differentiating once more, q̈ = R z̈ + Ṙż with Ṙż = A⁻¹[−Φ̇_q q̇; 0]. The reduced equations
Rᵀ M R z̈ = Rᵀ (Q − M Ṙż) have r ≤ 9 unknowns. A is solved in closed form (:func:`solve_aug`:
Ȧ' from rows 8–9, a 2×2 block for Ḃ − Ȧ', one row for the rod, substitutions for the rest:
about 35 flops), never inverted. With A ideal, Ȧ' = 0 exactly and every operation of the
eight-coordinate model is repeated on the same numbers (the new terms add exact zeros), so
runs with A ideal are bit-identical to it.

Mass matrix (derivation). A planar rigid body described by two of its points i and j at
distance L, a material point at body coordinates (ξ along i→j, η normal to it) is
p = r_i + (ξ/L) d + (η/L) R₉₀ d, d = r_j − r_i, R₉₀ the +90° rotation. With u = ṙ_i:
ṗ = u + (ξ/L) ḋ + (η/L) R₉₀ ḋ, and since ḋ·R₉₀ḋ = 0, integrating ρ|ṗ|² over the body gives

    T = ½ [ m|u|² + 2 (m ξ_G / L) u·ḋ + (I_i / L²) |ḋ|² ],   I_i = I_G + m ξ_G²   (η_G = 0)

which, with ḋ = ṙ_j − ṙ_i, is T = ½ [ṙ_iᵀ ṙ_jᵀ] M [ṙ_i; ṙ_j] with 2×2 identity blocks

    M_ii = m − 2 m ξ_G/L + I_i/L²,   M_ij = m ξ_G/L − I_i/L²,   M_jj = I_i/L².

Exact as long as |d| = L, which the length constraints keep. For the rod (Table 1: m₂, ξ_G
from B, I_G) i = B', j = C, L = l. For the crank (m₁, ξ_G from A, I_G) i = A', j = B, L = r:
M_jj = I_A / r² on (x_B, y_B) with I_A = I_G + m₁ ξ_G², M_ii on (x_A, y_A) and M_ij coupling
them (with A' fixed, Ȧ' = 0, only M_jj acts: the crank turning about A). The slider translates:
m₃ on x'_C (its y and rotation are taken by the ideal guide; with a guide clearance m₃ on y_g,
I_G + m₃ x_G² on φ and the coupling m₃ x_G of y_g and φ at φ = 0, :mod:`twin.reference.guide`). θ carries no mass (it is tied to A' and B
by rows 0–1).

Everything here is compiled with numba (``cache=True``); the parameter vector layout is given by
the ``P_*`` indices (the reference engine's :func:`twin.reference.model.build_params` fills all
of it, :func:`mechanism_params` the geometry and masses this module reads).
"""

from __future__ import annotations

import math

import numpy as np
from twin.jit import njit

from twin.config import BenchConfig
from twin.kinematics import guide_start, initial_pose

# ----------------------------------------------------------------- parameter layout
P_R, P_L, P_DOFF, P_GX, P_GY = 0, 1, 2, 3, 4
P_MC, P_RA, P_RB, P_RC, P_M3 = 5, 6, 7, 8, 9
P_M1, P_XG1, P_M2, P_XG2 = 10, 11, 12, 13
P_CLR_B, P_CLR_C = 14, 15
P_C_B, P_C_C, P_RPIN_B, P_RBUSH_B, P_RBUSH_C = 16, 17, 18, 19, 20
P_LAW, P_K_B, P_K_C, P_N, P_E, P_CLIN_B, P_CLIN_C, P_VMIN = 21, 22, 23, 24, 25, 26, 27, 28
P_MU0, P_V0, P_V1, P_FGUIDE = 29, 30, 31, 32
P_KP, P_KV, P_KI, P_IMAX, P_H = 33, 34, 35, 36, 37
P_NEWTON_TOL, P_NEWTON_MAXIT = 38, 39
P_SENS = 40            # 6 sensors × (body 0 rod / 1 slider, x, y, axis 0 +x 1 −x 2 +y 3 −y)
# clearance-joint friction law (twin.physics.contact.FRICTION_CODES: 0 regularized Coulomb with
# P_MU0, P_V0, P_V1; 1 Adams/COSMOS with μ_d = P_MU0, μ_s, v_s, v_d)
P_FRIC_LAW, P_MUS, P_VS, P_VD = P_SENS + 24, P_SENS + 25, P_SENS + 26, P_SENS + 27
P_DMAX = P_VD + 1       # penetration of full damping of the ADAMS IMPACT law (its c_max in P_CLIN_B/C)
P_PRESCRIBED = P_DMAX + 1  # 1: prescribed crank (drive.mode = "prescribed", driving constraint θ = θ_ref(t))
# the ground pivot A (flag, radial clearance, bore and journal radii, law constants) and the pin radius
# at C (per-joint pins: P_RPIN_B is B's)
P_CLR_A, P_C_A, P_RBUSH_A, P_RPIN_A, P_K_A, P_CLIN_A, P_RPIN_C = (P_PRESCRIBED + 1 + i for i in range(7))
P_MA, P_MAB = P_RPIN_C + 1, P_RPIN_C + 2  # crank mass matrix blocks M_ii (on A') and M_ij (A'–B) [kg]
# 0 symplectic Euler (default), 1 explicit midpoint (twin.reference.model.INTEGRATORS); the last entry
P_INTEGRATOR = P_MAB + 1
# the slider guide's clearance (twin.guide): flag, half play c_g [m], half span a [m], contact
# stiffness K_g [N/m^n], the slider's moment of inertia about C' [kg m²] (its tilt coordinate),
# its static moments m₃ x_G and m₃ d_off about C' [kg m] (centre of mass at C' + R(φ)(x_G, −d_off))
P_CLR_G, P_C_G, P_GA, P_K_G, P_I3, P_S3X, P_S3D = (P_INTEGRATOR + 1 + i for i in range(7))
P_OUT_ENERGY = P_S3D + 1   # 1: the reference engine's samples carry T and V (channel group "energy")
N_PARAMS = P_OUT_ENERGY + 1

#: number of coordinates q (module docstring)
N_Q = 12
#: most independent coordinates: θ, the eccentricities at A, B and C, the slider's y_g and φ
N_Z = 9

# --------------------------------------------------------------------- state layout
S_Q, S_QD = 0, N_Q     # q[0:10], q̇[10:20]
S_I = 2 * N_Q          # PID integral state [rad s]
S_IN_B, S_VIMP_B = S_I + 1, S_I + 2  # contact event flag and stored impact speed at B
S_IN_C, S_VIMP_C = S_I + 3, S_I + 4  # same at C
S_IN_A, S_VIMP_A = S_I + 5, S_I + 6  # same at A
S_GUIDE = S_I + 7      # guide contact events: [in, v_imp] of the slider's front, then rear end
N_STATE = S_I + 11


# ------------------------------------------------------------------------- kernels
@njit(cache=True)
def solve_aug(q, s, c, b, out):
    """Solve A(q) v = b for v (closed form, see module docstring); s, c = sin θ, cos θ.

    Ȧ' from rows 8–9, then Ḃ − Ȧ' from the crank block (rows 0–1, determinant −2r), the rod eye
    B' from rows 3–4, ẏ_C from row 6, ẋ_C from the rod length row 2, ẋ'_C from row 5."""
    vxA, vyA = b[8], b[9]
    xB, yB = q[0] - q[8], q[1] - q[9]    # B − A'
    xBp, yBp, xC, yC = q[2], q[3], q[4], q[5]
    th_d = b[7]
    rp = xB * c + yB * s
    rhs1 = b[1] - rp * th_d
    det = -2.0 * rp
    vxB = vxA + (-c * b[0] - 2.0 * yB * rhs1) / det
    vyB = vyA + (2.0 * xB * rhs1 - s * b[0]) / det
    vxBp = vxB - b[3]
    vyBp = vyB - b[4]
    vyC = -b[6]
    if b[10] != 0.0:           # the slider's transverse velocity (guide clearance; exact 0 otherwise)
        vyC += b[10]
    dx = xC - xBp
    dy = yC - yBp
    vxC = (b[2] + 2.0 * dx * vxBp + 2.0 * dy * vyBp - 2.0 * dy * vyC) / (2.0 * dx)
    out[0] = vxB
    out[1] = vyB
    out[2] = vxBp
    out[3] = vyBp
    out[4] = vxC
    out[5] = vyC
    out[6] = b[5] + vxC
    out[7] = th_d
    out[8] = vxA
    out[9] = vyA
    out[10] = b[10]
    out[11] = b[11]


@njit(cache=True)
def residual(P, q, s, c, out):
    """Constraint residuals of the ten rows (independent rows: 0)."""
    r, l = P[P_R], P[P_L]
    dxB, dyB = q[0] - q[8], q[1] - q[9]
    out[0] = dxB * dxB + dyB * dyB - r * r
    out[1] = dxB * s - dyB * c
    dx = q[4] - q[2]
    dy = q[5] - q[3]
    out[2] = dx * dx + dy * dy - l * l
    if P[P_CLR_B] > 0.5:
        out[3] = 0.0
        out[4] = 0.0
    else:
        out[3] = q[0] - q[2]
        out[4] = q[1] - q[3]
    if P[P_CLR_C] > 0.5:
        out[5] = 0.0
        out[6] = 0.0
    else:
        out[5] = q[6] - q[4]
        out[6] = P[P_DOFF] + q[10] - q[5] if P[P_CLR_G] > 0.5 else P[P_DOFF] - q[5]
    out[7] = 0.0
    if P[P_CLR_A] > 0.5:
        out[8] = 0.0
        out[9] = 0.0
    else:                      # the journal centre on the bore centre, the origin
        out[8] = q[8]
        out[9] = q[9]
    if P[P_CLR_G] > 0.5:       # the slider's transverse position and tilt: independent
        out[10] = 0.0
        out[11] = 0.0
    else:                      # the preloaded ideal guide: y_g = φ = 0
        out[10] = q[10]
        out[11] = q[11]


@njit(cache=True)
def constraint_norm(P, q):
    """‖Φ‖₂ of the mechanism's constraints at q."""
    res = np.empty(N_Q)
    residual(P, q, math.sin(q[7]), math.cos(q[7]), res)
    acc = 0.0
    for i in range(N_Q):       # the independent rows are 0
        acc += res[i] * res[i]
    return math.sqrt(acc)


@njit(cache=True)
def velocity_constraint_norm(P, q, qd):
    """‖Φ̇‖₂ = ‖Φ_q q̇‖₂ of the mechanism's constraints."""
    s, c = math.sin(q[7]), math.cos(q[7])
    dxB, dyB = q[0] - q[8], q[1] - q[9]
    uxB, uyB = qd[0] - qd[8], qd[1] - qd[9]
    v0 = 2.0 * (dxB * uxB + dyB * uyB)
    v1 = s * uxB - c * uyB + (dxB * c + dyB * s) * qd[7]
    dx, dy = q[4] - q[2], q[5] - q[3]
    v2 = 2.0 * (dx * (qd[4] - qd[2]) + dy * (qd[5] - qd[3]))
    acc = v0 * v0 + v1 * v1 + v2 * v2
    if P[P_CLR_B] < 0.5:
        acc += (qd[0] - qd[2]) ** 2 + (qd[1] - qd[3]) ** 2
    if P[P_CLR_C] < 0.5:
        acc += (qd[6] - qd[4]) ** 2 + (qd[10] - qd[5]) ** 2
    if P[P_CLR_A] < 0.5:
        acc += qd[8] ** 2 + qd[9] ** 2
    if P[P_CLR_G] < 0.5:
        acc += qd[10] ** 2 + qd[11] ** 2
    return math.sqrt(acc)


@njit(cache=True)
def quadratic_terms(q, qd, s, c, out):
    """Right-hand side [−Φ̇_q q̇; 0] of Ṙż (rows 3–9 are linear: zero)."""
    th_d = qd[7]
    uxB, uyB = qd[0] - qd[8], qd[1] - qd[9]
    out[0] = -2.0 * (uxB * uxB + uyB * uyB)
    out[1] = -(2.0 * th_d * (uxB * c + uyB * s) + th_d * th_d * ((q[1] - q[9]) * c - (q[0] - q[8]) * s))
    ddx = qd[4] - qd[2]
    ddy = qd[5] - qd[3]
    out[2] = -2.0 * (ddx * ddx + ddy * ddy)
    for i in range(3, N_Q):
        out[i] = 0.0


@njit(cache=True)
def independent_rows(P, rows):
    """Rows of the augmented set that are independent coordinates (θ, then e_A, e_B, e_C of the
    clearance joints); returns their number."""
    rows[0] = 7
    nz = 1
    if P[P_CLR_A] > 0.5:
        rows[nz] = 8
        rows[nz + 1] = 9
        nz += 2
    if P[P_CLR_B] > 0.5:
        rows[nz] = 3
        rows[nz + 1] = 4
        nz += 2
    if P[P_CLR_C] > 0.5:
        rows[nz] = 5
        rows[nz + 1] = 6
        nz += 2
    if P[P_CLR_G] > 0.5:
        rows[nz] = 10
        rows[nz + 1] = 11
        nz += 2
    return nz


@njit(cache=True)
def mass_times(P, v, out):
    """out = M v (natural-coordinate mass matrix, see module docstring)."""
    mc, a, b, cc, m3 = P[P_MC], P[P_RA], P[P_RB], P[P_RC], P[P_M3]
    ma, mab = P[P_MA], P[P_MAB]
    out[0] = mc * v[0] + mab * v[8]
    out[1] = mc * v[1] + mab * v[9]
    out[2] = a * v[2] + b * v[4]
    out[3] = a * v[3] + b * v[5]
    out[4] = b * v[2] + cc * v[4]
    out[5] = b * v[3] + cc * v[5]
    out[6] = m3 * v[6]
    if P[P_CLR_G] > 0.5:       # the slider's tilt couples (linearized at φ = 0, see twin.guide)
        out[6] += P[P_S3D] * v[11]
    out[7] = 0.0
    out[8] = ma * v[8] + mab * v[0]
    out[9] = ma * v[9] + mab * v[1]
    out[10] = m3 * v[10]
    out[11] = P[P_I3] * v[11]
    if P[P_CLR_G] > 0.5:
        out[10] += P[P_S3X] * v[11]
        out[11] += P[P_S3D] * v[6] + P[P_S3X] * v[10]


@njit(cache=True)
def r_matrix(P, q, qd, R, S):
    """R (N_Q × r, first r columns of ``R``) and Ṙż (``S``) at (q, q̇); returns r."""
    s, c = math.sin(q[7]), math.cos(q[7])
    rows = np.empty(N_Z, dtype=np.int64)
    nz = independent_rows(P, rows)
    b = np.zeros(N_Q)
    col = np.empty(N_Q)
    for j in range(nz):
        b[:] = 0.0
        b[rows[j]] = 1.0
        solve_aug(q, s, c, b, col)
        R[:, j] = col
    quadratic_terms(q, qd, s, c, b)
    solve_aug(q, s, c, b, S)
    return nz


@njit(cache=True)
def reduced_mass(P, q):
    """Reduced mass matrix Rᵀ M R at q (r × r)."""
    R = np.zeros((N_Q, N_Z))
    S = np.zeros(N_Q)
    nz = r_matrix(P, q, np.zeros(N_Q), R, S)
    Mb = np.zeros((nz, nz))
    mr = np.empty(N_Q)
    for j in range(nz):
        mass_times(P, R[:, j], mr)
        for i in range(nz):
            acc = 0.0
            for k in range(N_Q):
                acc += R[k, i] * mr[k]
            Mb[i, j] = acc
    return Mb


@njit(cache=True)
def project(P, q, qd, s, c, res, dq, b):
    """Position then velocity projection with the independent coordinates held.

    Newton–Raphson on A(q) Δq = −[Φ(q); 0] until max|Δq| ≤ tol, then q̇ ← R(q) ż.
    Returns the number of Newton iterations, or −1 if it did not converge.
    """
    tol = P[P_NEWTON_TOL]
    maxit = int(P[P_NEWTON_MAXIT])
    it = 0
    conv = False
    while it < maxit:
        residual(P, q, s, c, res)
        for i in range(N_Q):
            res[i] = -res[i]
        solve_aug(q, s, c, res, dq)
        big = 0.0
        for i in range(N_Q):
            q[i] += dq[i]
            a = abs(dq[i])
            if a > big:
                big = a
        it += 1
        if big <= tol:
            conv = True
            break
    if not conv:
        return -1
    # velocities: ż from the integrated q̇, dependent ones re-solved
    for i in range(N_Q):
        b[i] = 0.0
    b[7] = qd[7]
    if P[P_CLR_A] > 0.5:
        b[8] = qd[8]
        b[9] = qd[9]
    if P[P_CLR_B] > 0.5:
        b[3] = qd[0] - qd[2]
        b[4] = qd[1] - qd[3]
    if P[P_CLR_C] > 0.5:
        b[5] = qd[6] - qd[4]
        b[6] = qd[10] - qd[5] if P[P_CLR_G] > 0.5 else -qd[5]
    if P[P_CLR_G] > 0.5:
        b[10] = qd[10]
        b[11] = qd[11]
    solve_aug(q, s, c, b, dq)
    for i in range(N_Q):
        qd[i] = dq[i]
    return it


@njit(cache=True)
def kinetic_energy(P, q, qd):
    """Kinetic energy T = ½ q̇ᵀ M q̇ [J]."""
    mv = np.empty(N_Q)
    mass_times(P, qd, mv)
    T = 0.0
    for i in range(N_Q):
        T += 0.5 * qd[i] * mv[i]
    return T


@njit(cache=True)
def energy(P, q, qd):
    """Mechanical energy T + V [J]: T = ½ q̇ᵀ M q̇, V = −Σ m g·r_G (zero with every centre of
    mass at A; the slider's constant guide-normal term is dropped)."""
    mv = np.empty(N_Q)
    mass_times(P, qd, mv)
    T = 0.0
    for i in range(N_Q):
        T += 0.5 * qd[i] * mv[i]
    gx, gy = P[P_GX], P[P_GY]
    w1 = P[P_M1] * P[P_XG1] / P[P_R]
    a2 = P[P_XG2] / P[P_L]
    m2 = P[P_M2]
    wa = P[P_M1] - w1
    V = -(w1 * (gx * q[0] + gy * q[1])
          + m2 * (gx * ((1.0 - a2) * q[2] + a2 * q[4]) + gy * ((1.0 - a2) * q[3] + a2 * q[5]))
          + P[P_M3] * gx * q[6]
          + wa * (gx * q[8] + gy * q[9]))
    if P[P_CLR_G] > 0.5:       # the slider's transverse position and tilt (guide clearance)
        cf, sf = math.cos(q[11]), math.sin(q[11])
        xg, dd = P[P_S3X], P[P_S3D]   # m₃ x_G, m₃ d_off: m₃ (r(φ) − r(0)), r = R(φ)(x_G, −d_off)
        V -= P[P_M3] * gy * q[10] + gx * (xg * (cf - 1.0) + dd * sf) + gy * (xg * sf - dd * (cf - 1.0))
    return T + V


# ----------------------------------------------------------------- Python helpers
def mechanism_params(cfg: BenchConfig) -> np.ndarray:
    """Parameter vector (layout ``P_*``) with the mechanism's geometry, gravity, masses, clearance
    flags, radial clearances and pin and bushing radii set, every other entry 0: what the kernels
    of this module read (the reference engine's :func:`twin.reference.model.build_params` adds
    the contact laws, friction, drive, sensors and numerical settings)."""
    b, j, mech = cfg.bodies, cfg.joints, cfg.mechanism
    P = np.zeros(N_PARAMS)
    r, l = b.crank.length_m, b.rod.length_m
    P[P_R], P[P_L], P[P_DOFF] = r, l, mech.d_off_m
    g = mech.gravity_vector
    P[P_GX], P[P_GY] = g[0], g[1]
    m1, xg1 = b.crank.mass_kg, b.crank.x_g_m
    ia = b.crank.inertia_kgm2 + m1 * xg1 ** 2
    P[P_MC] = ia / r ** 2                                   # M_jj of the crank (on B)
    P[P_MA] = m1 - 2.0 * m1 * xg1 / r + ia / r ** 2         # M_ii (on A')
    P[P_MAB] = m1 * xg1 / r - ia / r ** 2                   # M_ij
    m2, xg2 = b.rod.mass_kg, b.rod.x_g_m
    ii = b.rod.inertia_kgm2 + m2 * xg2 ** 2
    P[P_RA] = m2 - 2.0 * m2 * xg2 / l + ii / l ** 2
    P[P_RB] = m2 * xg2 / l - ii / l ** 2
    P[P_RC] = ii / l ** 2
    P[P_M3] = b.slider.mass_kg
    P[P_M1], P[P_XG1], P[P_M2], P[P_XG2] = b.crank.mass_kg, b.crank.x_g_m, m2, xg2
    P[P_CLR_A] = 1.0 if j.diametral_mm("A") > 0 else 0.0
    P[P_CLR_B] = 1.0 if j.diametral_mm("B") > 0 else 0.0
    P[P_CLR_C] = 1.0 if j.diametral_mm("C") > 0 else 0.0
    P[P_C_A], P[P_C_B], P[P_C_C] = j.radial_m("A"), j.radial_m("B"), j.radial_m("C")
    P[P_RPIN_A], P[P_RPIN_B], P[P_RPIN_C] = j.pin_radius("A"), j.pin_radius("B"), j.pin_radius("C")
    P[P_RBUSH_A] = j.bushing_radius_m("A")
    P[P_RBUSH_B], P[P_RBUSH_C] = j.bushing_radius_m("B"), j.bushing_radius_m("C")
    if j.guide_play:
        P[P_CLR_G], P[P_C_G], P[P_GA] = 1.0, j.guide_radial_m, j.guide_span_m / 2.0
        m3, xg3 = b.slider.mass_kg, b.slider.x_g_m
        # the slider's centre of mass sits x_G ahead of C' at its height (as the MuJoCo twin's
        # slider body has it): no offset normal to the slider's axis, m₃ d_off's slot holds 0
        P[P_I3] = b.slider.inertia_kgm2 + m3 * xg3 ** 2
        P[P_S3X], P[P_S3D] = m3 * xg3, 0.0
    return P


def effective_masses(cfg: BenchConfig, P: np.ndarray, q: np.ndarray) -> dict[str, float]:
    """{joint: effective mass [kg]} of each clearance joint along its contact normal at q: the
    mass an impact there moves, 1 / (nᵀ W n) with W the joint's 2×2 block of the inverse reduced
    mass matrix (Rᵀ M R)⁻¹ and n = e/|e| (+y at zero eccentricity). At A the crank's (its journal
    moves in the frame's bore)."""
    out: dict[str, float] = {}
    Mb = reduced_mass(P, q)
    W = np.linalg.inv(Mb)
    off = 1                    # z = θ, then e_A, e_B, e_C of the clearance joints
    for jt in ("A", "B", "C"):
        if cfg.joints.diametral_mm(jt) <= 0:
            continue
        e = {"A": np.array([q[8], q[9]]), "B": np.array([q[0] - q[2], q[1] - q[3]]),
             "C": np.array([q[6] - q[4], P[P_DOFF] + q[10] - q[5]])}[jt]
        n = e / np.linalg.norm(e) if np.linalg.norm(e) > 0 else np.array([0.0, 1.0])
        w = W[off:off + 2, off:off + 2]
        out[jt] = float(1.0 / (n @ w @ n))
        off += 2
    return out


def initial_state(cfg: BenchConfig, theta: float, omega: float = 0.0, P: np.ndarray | None = None) -> np.ndarray:
    """State vector (layout ``S_*``) at crank angle θ with the configured initial
    eccentricities (:func:`twin.kinematics.initial_pose`), PID integral 0, no contact event;
    at rest, or turning at crank rate ``omega`` [rad/s] (needs ``P``) with the eccentricities
    fixed in the bench frame (ė = 0) and every other velocity from the constraints (q̇ = R ż)."""
    pose = initial_pose(cfg, theta)
    st = np.zeros(N_STATE)
    st[S_Q:S_Q + N_Q] = [pose.b_pin[0], pose.b_pin[1], pose.b_bush[0], pose.b_bush[1],
                         pose.c_bush[0], pose.c_bush[1], pose.c_pin[0], pose.theta, pose.e_a[0], pose.e_a[1],
                         0.0, 0.0]
    st[S_Q + 10] = guide_start(cfg)
    if omega != 0.0:
        if P is None:
            raise ValueError("initial_state: a turning start needs the parameter vector P")
        q, qd = st[S_Q:S_Q + N_Q].copy(), np.zeros(N_Q)
        qd[7] = omega
        if project(P, q, qd, math.sin(q[7]), math.cos(q[7]), np.empty(N_Q), np.empty(N_Q), np.empty(N_Q)) < 0:
            raise ValueError("the initial pose does not satisfy the constraints")
        st[S_Q:S_Q + N_Q], st[S_QD:S_QD + N_Q] = q, qd
    return st


@njit(cache=True)
def reduced_mass_into(Rt, MR, nz, n, Mb):
    """Rᵀ M R into ``Mb[:nz, :nz]`` from ``Rt`` = Rᵀ and ``MR`` whose row j is M R[:, j] (the first ``n``
    coordinates of each; symmetric, each entry one dot product): the reduced mass matrix of the R-matrix
    formulation (:func:`reduced_mass` computes it from q alone) in the steps of the rigid and the flexible
    reference engines."""
    for j in range(nz):
        for i in range(j, nz):
            acc = 0.0
            for k in range(n):
                acc += Rt[i, k] * MR[j, k]
            Mb[i, j] = acc
            Mb[j, i] = acc
