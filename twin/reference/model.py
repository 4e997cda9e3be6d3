r"""Natural-coordinate model of the bench and its R-matrix dynamics (S003 §3, Eq. 11–16).

Coordinates (S003 Eq. 14, extended by the crank journal), bench frame of :mod:`twin.config`
(the frame's bore centre A at the origin)::

    q = [x_B, y_B, x'_B, y'_B, x_C, y_C, x'_C, θ, x_A, y_A]      indices 0..9   (N_Q = 10)

* A' = (x_A, y_A): centre of the crank's journal at the ground pivot A (crank body 1; the
  bushing at A is the frame's bore, fixed, centred at the origin);
* B = (x_B, y_B): centre of the crank pin (crank body 1);
* B' = (x'_B, y'_B): centre of the rod's eye at B (rod body 2, origin of the rod frame);
* C = (x_C, y_C): centre of the rod's eye at C (rod body 2);
* C' = (x'_C, d_off): centre of the slider pin (slider body 3 translates on the guide
  y = 0 through A; C' is ``d_off`` above it, so only x'_C is a coordinate);
* θ: crank bench angle from +x (direction A' → B).

Pins sit on the crank (the journal A', the pin B) and on the slider (C'); bushings are the
frame's bore (A) and the rod eyes (B', C). A' and θ sit at the end of q so that the indices of
the S003 coordinates are those of the eight-coordinate model that had A fixed.

Equations. Ten rows, always the same (the "augmented" set)::

    0  (x_B − x_A)² + (y_B − y_A)² − r²      crank length      constraint
    1  (x_B − x_A) sin θ − (y_B − y_A) cos θ crank angle       constraint
    2  (x_C − x'_B)² + (y_C − y'_B)² − l²    rod length        constraint
    3  x_B − x'_B        = e_Bx          pair B (Eq. 15)  constraint (= 0) or independent
    4  y_B − y'_B        = e_By          pair B (Eq. 15)  constraint (= 0) or independent
    5  x'_C − x_C        = e_Cx          pair C (Eq. 16)  constraint (= 0) or independent
    6  d_off − y_C       = e_Cy          pair C (Eq. 16)  constraint (= 0) or independent
    7  θ                                 crank angle              independent
    8  x_A               = e_Ax          pair A           constraint (= 0) or independent
    9  y_A               = e_Ay          pair A           constraint (= 0) or independent

An ideal joint keeps its two pair rows as constraints (nine constraints, one degree of
freedom, S003 §3: A' is then held at the origin and the model is S003's). A clearance joint
drops them from the constraint set and uses the same two expressions — the eccentricity
e = pin − bushing in the bench frame, the "relative journal position" — as independent
coordinates, next to θ; its contact is a force element. q itself never changes. Independent
coordinates z, in this order: θ, then e_A, e_B, e_C of the joints that have a clearance
(r = 1, 3, 5 or 7).

Crank angle equation. S003 writes θ "as a function of x_B or y_B": x_B = r cos θ is
singular with the crank length row where y_B = 0, y_B = r sin θ where x_B = 0, so a code
must switch between them during a turn. Row 1 uses both at once: with d = B − A',
d_x sin θ − d_y cos θ = 0 (d parallel to (cos θ, sin θ)). Together with row 0 the crank block
[[2d_x, 2d_y], [sin θ, −cos θ]] (in the unknowns Ḃ − Ȧ') has determinant
−2(d_x cos θ + d_y sin θ) = −2r: never singular over a turn, and smooth (no switching). The rod
block is singular only with the rod perpendicular to the guide, which the bench's geometry
(l > r + |d_off| + the clearances) excludes.

Velocity transformation (S003 Eq. 11–13). With A(q) the 10×10 Jacobian of the ten rows
(constant rows 3–9), A q̇ = [0, 0, 0, ė_B or 0, ė_C or 0, θ̇, ė_A or 0]: the columns of
R = A⁻¹[0; I] belonging to the independent rows give q̇ = R ż with Φ_q R = 0, and
differentiating once more, q̈ = R z̈ + Ṙż with Ṙż = A⁻¹[−Φ̇_q q̇; 0]. The reduced equations
Rᵀ M R z̈ = Rᵀ (Q − M Ṙż) have r ≤ 7 unknowns. A is solved in closed form (:func:`solve_aug`:
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
m₃ on x'_C (its y and rotation are taken by the guide). θ carries no mass (it is tied to A' and B
by rows 0–1).

Generalized forces Q (virtual work over δq):

* gravity g = (g_x, g_y) (in-plane components of ``mechanism.gravity_vector``; the normal
  component does no work): centre of mass of the crank (1 − ξ_G/r) A' + (ξ_G/r) B, of the rod
  (1 − ξ_G/l) B' + (ξ_G/l) C, slider m₃ g_x on x'_C (the guide takes m₃ g_y);
* drive torque τ about +z on θ (virtual work τ δθ: a couple on the crank);
* a force F at a crank point P (δP = δA' + δθ ẑ × (P − A')): F on (x_A, y_A) and the torque
  ((P − A') × F)_z on θ; at a rod point P = B' + α u + β R₉₀ u (u = C − B'):
  (1 − α) F − β R₉₀ᵀF on B', α F + β R₉₀ᵀF on C; on the slider pin: F_x on x'_C;
* contact at a clearance joint (:mod:`twin.reference.contact`): penetration δ = |e| − c,
  n = e/|e|, t = ẑ × n; force on the pin −f_N n + f_T t at the pin's surface point
  (pin centre + R_pin n), the opposite on the bushing's body at the bushing's surface point
  (bushing centre + R_bushing n). f_T acts on the true tangential relative velocity of those two
  material points: v_t = ė·t + ω₁ R_pin,B − ω₂ R_bushing,B at B (crank ω₁ = θ̇, rod ω₂),
  v_t = ė·t − ω₂ R_bushing,C at C (the slider does not rotate) and v_t = ė·t + ω₁ R_pin,A at A
  (the frame does not rotate; its reaction is not modelled). Pin and bushing radii are the
  joint's own (``joints.pin_radius(j)``, ``joints.bushing_radius_m(j)``);
* slider guide friction (S003 §3: 2.5 N whenever the slider moves): −F_g ρ(|ẋ'_C|) sign(ẋ'_C)
  on x'_C, with ρ the same regularization ramp as the joint friction (0 below v0, linear to 1
  at v1; :func:`twin.reference.contact.ramp`). A discontinuous sign() would chatter at the
  slider's dead centres; the ramp makes the guide force exactly F_g once |ẋ| ≥ v1 = 1 mm/s.

Integration (S003 Eq. 21, symplectic Euler on the independent coordinates): ż ← ż + h z̈,
z ← z + h ż (velocity first: the printed Eq. 21 shows ẏ_k in the position update, which would
be explicit Euler; the symplectic variant, as in MuJoCo's Euler, uses the new velocity). The
dependent coordinates follow q̈ = R z̈ + Ṙż the same way, then are projected with z held:
Newton–Raphson on A(q) Δq = −[Φ(q); 0] (z rows of the right-hand side zero), then
q̇ ← R(q) ż. ‖Φ‖ and ‖Φ̇‖ therefore stay at round-off. Opt-in alternative
(``P[P_INTEGRATOR]``, :data:`INTEGRATORS`): the explicit midpoint rule, second order: the state
at t + h/2 by an Euler half step, projected the same way, the accelerations there, then
q ← q + h q̇_mid, q̇ ← q̇ + h q̈_mid and the projection (two force and acceleration evaluations per
step). The drive reference at the midpoint is θ_ref + h/2 ω_ref (ω_ref averaged over the step),
the PID integral is that of the step start and contact events advance at step starts only, so it
is second order for smooth motion (``twin study formulations`` measures it). Through hard
impacts explicit midpoint is not stable at the bench's steps: the engine refuses it for scenes
with a clearance joint (:class:`twin.reference.engine.ReferenceOptions`).

Drive: MuJoCo's native ``<pid>`` law: τ_k = kp (θ_ref − θ) + kv (ω_ref − ω) + ki I_k, then
I_{k+1} = clamp(I_k + h (θ_ref − θ_k), ±imax) (imax = 0: no clamp).

Everything here is compiled with numba (``cache=True``); the parameter vector layout is
given by the ``P_*`` indices and built by :func:`build_params`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from twin.config import ACCELEROMETERS, BenchConfig, joint_stiffness
from twin.kinematics import initial_pose
from twin.reference import drivetrain as DT
from twin.reference.contact import FRICTION_CODES, LAW_CODES, adams_friction_force, friction_force, normal_force, ramp

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
# clearance-joint friction law (twin.reference.contact.FRICTION_CODES: 0 regularized Coulomb with
# P_MU0, P_V0, P_V1; 1 Adams/COSMOS with μ_d = P_MU0, μ_s, v_s, v_d)
P_FRIC_LAW, P_MUS, P_VS, P_VD = P_SENS + 24, P_SENS + 25, P_SENS + 26, P_SENS + 27
P_DMAX = P_VD + 1       # penetration of full damping of the ADAMS IMPACT law (its c_max in P_CLIN_B/C)
P_PRESCRIBED = P_DMAX + 1  # 1: prescribed crank (drive.mode = "prescribed", driving constraint θ = θ_ref(t))
# the ground pivot A (flag, radial clearance, bore and journal radii, law constants) and the pin radius
# at C (per-joint pins: P_RPIN_B is B's)
P_CLR_A, P_C_A, P_RBUSH_A, P_RPIN_A, P_K_A, P_CLIN_A, P_RPIN_C = (P_PRESCRIBED + 1 + i for i in range(7))
P_MA, P_MAB = P_RPIN_C + 1, P_RPIN_C + 2  # crank mass matrix blocks M_ii (on A') and M_ij (A'–B) [kg]
P_INTEGRATOR = P_MAB + 1  # 0 symplectic Euler (default), 1 explicit midpoint (INTEGRATORS); the last entry
N_PARAMS = P_INTEGRATOR + 1

#: integrators of :func:`run_steps` by name -> code in ``P[P_INTEGRATOR]``
INTEGRATORS = {"euler": 0, "midpoint": 1}

#: number of coordinates q (module docstring)
N_Q = 10
#: most independent coordinates: θ and the eccentricities at A, B and C
N_Z = 7
#: joint codes of :func:`_joint`
J_A, J_B, J_C = 0, 1, 2

# --------------------------------------------------------------------- state layout
S_Q, S_QD = 0, N_Q     # q[0:10], q̇[10:20]
S_I = 2 * N_Q          # PID integral state [rad s]
S_IN_B, S_VIMP_B = S_I + 1, S_I + 2  # contact event flag and stored impact speed at B
S_IN_C, S_VIMP_C = S_I + 3, S_I + 4  # same at C
S_IN_A, S_VIMP_A = S_I + 5, S_I + 6  # same at A
N_STATE = S_I + 7

# ------------------------------------------------------------------- output columns
O_THETA, O_OMEGA, O_SLIDER = 0, 1, 2
O_ACC = 3              # AC1..AC6: 3..8
O_TORQUE = 9
O_JOINT_B, O_JOINT_C = 10, 15  # ecc_x, ecc_y (rod frame), pen, fn, ft
O_JOINT_A = 20                 # the same at A, ecc in the bench frame
N_OUT = 25

#: integration status codes of :func:`run_steps`
OK, NEWTON_FAILED, NOT_FINITE = 0, 1, 2

_AXES = {"+x": 0, "-x": 1, "+y": 2, "-y": 3}
#: impact speed at which the linear law's default stiffness matches the LN contact duration [m/s]
#: (the MuJoCo twin's first-guess speed, ``twin.mujoco_engine.builder.FIRST_GUESS_SPEED``)
LINEAR_MATCH_SPEED = 0.1


@dataclass(frozen=True)
class JointContact:
    """Resolved contact parameters of one clearance joint (for run metadata).

    Attributes:
        radial_clearance_m: c [m].
        stiffness: K of the law [N/m^n] (linear law: [N/m]).
        exponent: n [-].
        damping_ns_per_m: damping of the linear law, c_max of the ADAMS IMPACT law [N s/m] (None for the
            hysteresis laws).
        effective_mass_kg: mass seen along the initial contact normal (reduced mass matrix) [kg].
    """

    radial_clearance_m: float
    stiffness: float
    exponent: float
    damping_ns_per_m: float | None
    effective_mass_kg: float


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
        out[6] = P[P_DOFF] - q[5]
    out[7] = 0.0
    if P[P_CLR_A] > 0.5:
        out[8] = 0.0
        out[9] = 0.0
    else:                      # the journal centre on the bore centre, the origin
        out[8] = q[8]
        out[9] = q[9]


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
        acc += (qd[6] - qd[4]) ** 2 + qd[5] ** 2
    if P[P_CLR_A] < 0.5:
        acc += qd[8] ** 2 + qd[9] ** 2
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
    out[7] = 0.0
    out[8] = ma * v[8] + mab * v[0]
    out[9] = ma * v[9] + mab * v[1]


@njit(cache=True)
def _rod_force(P, q, Fx, Fy, px, py, Q):
    """Add a force (Fx, Fy) acting on the rod at bench point (px, py) to Q."""
    ux, uy = q[4] - q[2], q[5] - q[3]
    uu = ux * ux + uy * uy
    rx, ry = px - q[2], py - q[3]
    alpha = (rx * ux + ry * uy) / uu
    beta = (-rx * uy + ry * ux) / uu
    # R90ᵀ F = (F_y, −F_x)
    Q[2] += (1.0 - alpha) * Fx - beta * Fy
    Q[3] += (1.0 - alpha) * Fy + beta * Fx
    Q[4] += alpha * Fx + beta * Fy
    Q[5] += alpha * Fy - beta * Fx


@njit(cache=True)
def _joint(P, q, qd, joint, cst, Q, jout):
    """Contact force element of clearance joint ``J_A``, ``J_B`` or ``J_C``: adds to Q, updates
    the contact event state cst = [in_contact, v_impact], writes jout = [ecc_x, ecc_y (bench),
    pen, fn, ft]."""
    if joint == J_B:
        ex, ey = q[0] - q[2], q[1] - q[3]
        edx, edy = qd[0] - qd[2], qd[1] - qd[3]
        c, Rb, Rp, K, clin = P[P_C_B], P[P_RBUSH_B], P[P_RPIN_B], P[P_K_B], P[P_CLIN_B]
    elif joint == J_C:
        ex, ey = q[6] - q[4], P[P_DOFF] - q[5]
        edx, edy = qd[6] - qd[4], -qd[5]
        c, Rb, Rp, K, clin = P[P_C_C], P[P_RBUSH_C], P[P_RPIN_C], P[P_K_C], P[P_CLIN_C]
    else:  # A: the crank journal A' in the frame's bore (centred at the origin)
        ex, ey = q[8], q[9]
        edx, edy = qd[8], qd[9]
        c, Rb, Rp, K, clin = P[P_C_A], P[P_RBUSH_A], P[P_RPIN_A], P[P_K_A], P[P_CLIN_A]
    d = math.sqrt(ex * ex + ey * ey)
    if d > 0.0:
        nx, ny = ex / d, ey / d
    else:
        nx, ny = 1.0, 0.0
    delta = d - c
    ddelta = nx * edx + ny * edy
    jout[0] = ex
    jout[1] = ey
    if delta > 0.0:
        if cst[0] < 0.5:  # start of a contact event: store the impact speed
            cst[0] = 1.0
            cst[1] = ddelta if ddelta > P[P_VMIN] else P[P_VMIN]
        fn = normal_force(int(P[P_LAW]), delta, ddelta, cst[1], K, P[P_N], P[P_E], clin, P[P_DMAX])
        jout[2] = delta
    else:
        cst[0] = 0.0
        fn = 0.0
        jout[2] = 0.0
    tx, ty = -ny, nx
    if joint == J_A:  # the frame does not rotate; the crank turns at θ̇
        vt = edx * tx + edy * ty + qd[7] * Rp
    else:
        # rod angular velocity
        ux, uy = q[4] - q[2], q[5] - q[3]
        udx, udy = qd[4] - qd[2], qd[5] - qd[3]
        w2 = (ux * udy - uy * udx) / (ux * ux + uy * uy)
        vt = edx * tx + edy * ty - w2 * Rb
        if joint == J_B:
            vt += qd[7] * Rp
    if fn <= 0.0:
        ft = 0.0
    elif P[P_FRIC_LAW] > 0.5:
        ft = adams_friction_force(vt, fn, P[P_MUS], P[P_MU0], P[P_VS], P[P_VD])
    else:
        ft = friction_force(vt, fn, P[P_MU0], P[P_V0], P[P_V1])
    jout[3] = fn
    jout[4] = ft
    if fn == 0.0:
        return
    Fx = -fn * nx + ft * tx  # on the pin
    Fy = -fn * ny + ft * ty
    if joint == J_B:
        # crank material point P = B + R_pin n: F on A', torque ((P − A') × F)_z on θ
        pcx, pcy = q[0] - q[8] + Rp * nx, q[1] - q[9] + Rp * ny
        Q[7] += pcx * Fy - pcy * Fx
        Q[8] += Fx
        Q[9] += Fy
        _rod_force(P, q, -Fx, -Fy, q[2] + Rb * nx, q[3] + Rb * ny, Q)
    elif joint == J_C:
        Q[6] += Fx                                 # slider pin: the guide takes F_y
        _rod_force(P, q, -Fx, -Fy, q[4] + Rb * nx, q[5] + Rb * ny, Q)
    else:
        # crank journal point P = A' + R_pin n: F on A', torque (R_pin n × F)_z on θ; the opposite
        # acts on the frame (not modelled)
        Q[7] += Rp * (nx * Fy - ny * Fx)
        Q[8] += Fx
        Q[9] += Fy


@njit(cache=True)
def generalized_forces(P, q, qd, tau, cst_a, cst_b, cst_c, Q, ja, jb, jc):
    """Q(q, q̇, τ): gravity, drive torque, guide friction and contact elements (joint J's
    event state ``cst_j``, its output ``jj``)."""
    gx, gy = P[P_GX], P[P_GY]
    w1 = P[P_M1] * P[P_XG1] / P[P_R]
    wa = P[P_M1] - w1          # the crank's weight share on A': m₁ (1 − ξ_G/r)
    a2 = P[P_XG2] / P[P_L]
    m2 = P[P_M2]
    Q[0] = w1 * gx
    Q[1] = w1 * gy
    Q[2] = m2 * (1.0 - a2) * gx
    Q[3] = m2 * (1.0 - a2) * gy
    Q[4] = m2 * a2 * gx
    Q[5] = m2 * a2 * gy
    Q[6] = P[P_M3] * gx
    Q[7] = tau
    Q[8] = wa * gx
    Q[9] = wa * gy
    fg = P[P_FGUIDE]
    if fg > 0.0:
        v = qd[6]
        f = fg * ramp(v, P[P_V0], P[P_V1])
        if v > 0.0:
            Q[6] -= f
        elif v < 0.0:
            Q[6] += f
    if P[P_CLR_A] > 0.5:
        _joint(P, q, qd, J_A, cst_a, Q, ja)
    if P[P_CLR_B] > 0.5:
        _joint(P, q, qd, J_B, cst_b, Q, jb)
    if P[P_CLR_C] > 0.5:
        _joint(P, q, qd, J_C, cst_c, Q, jc)


@njit(cache=True)
def _cholesky_solve(A, b, n):
    """Solve the SPD system A x = b (n × n, in place: A -> L, b -> x)."""
    for j in range(n):
        sacc = A[j, j]
        for k in range(j):
            sacc -= A[j, k] * A[j, k]
        if not sacc > 0.0:
            return False
        ljj = math.sqrt(sacc)
        A[j, j] = ljj
        for i in range(j + 1, n):
            t = A[i, j]
            for k in range(j):
                t -= A[i, k] * A[j, k]
            A[i, j] = t / ljj
    for i in range(n):
        t = b[i]
        for k in range(i):
            t -= A[i, k] * b[k]
        b[i] = t / A[i, i]
    for i in range(n - 1, -1, -1):
        t = b[i]
        for k in range(i + 1, n):
            t -= A[k, i] * b[k]
        b[i] = t / A[i, i]
    return True


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
def _assemble(P, q, qd, s, c, Q, rows, nz, Rt, S, Mb, rhs, tmp):
    """Rᵀ (r × N_Q) into ``Rt``, Ṙż into ``S``, Rᵀ M R into ``Mb`` and Rᵀ (Q − M Ṙż) into ``rhs``
    (``tmp``: (r + 2) × N_Q scratch, its first r rows left holding M R)."""
    b = tmp[nz]
    mr = tmp[nz + 1]
    for j in range(nz):
        for i in range(N_Q):
            b[i] = 0.0
        b[rows[j]] = 1.0
        solve_aug(q, s, c, b, Rt[j])
        mass_times(P, Rt[j], tmp[j])
    quadratic_terms(q, qd, s, c, b)
    solve_aug(q, s, c, b, S)
    mass_times(P, S, mr)
    for i in range(N_Q):
        b[i] = Q[i] - mr[i]
    # with A ideal, R's rows 8–9 are exact zeros: the products skip them (the same sums)
    nq = N_Q if P[P_CLR_A] > 0.5 else 8
    for j in range(nz):
        acc = 0.0
        for k in range(nq):
            acc += Rt[j, k] * b[k]
        rhs[j] = acc
    for j in range(nz):
        for i in range(j, nz):
            acc = 0.0
            for k in range(nq):
                acc += Rt[i, k] * tmp[j, k]
            Mb[i, j] = acc
            Mb[j, i] = acc


@njit(cache=True)
def _dependent_accelerations(S, Rt, zdd, nz, qdd):
    """q̈ = Ṙż + R z̈ (``S`` = Ṙż, ``Rt`` = Rᵀ), the last step of both acceleration solves."""
    for i in range(N_Q):
        acc = S[i]
        for j in range(nz):
            acc += Rt[j, i] * zdd[j]
        qdd[i] = acc


@njit(cache=True)
def accelerations(P, q, qd, s, c, Q, rows, nz, Rt, S, Mb, rhs, tmp, qdd):
    """q̈ = R z̈ + Ṙż from Rᵀ M R z̈ = Rᵀ (Q − M Ṙż); returns False if Rᵀ M R is not SPD.

    ``Rt`` holds Rᵀ (r × N_Q, rows contiguous); ``tmp`` is (r + 2) × N_Q scratch (M R rows, b)."""
    _assemble(P, q, qd, s, c, Q, rows, nz, Rt, S, Mb, rhs, tmp)
    if not _cholesky_solve(Mb, rhs, nz):
        return False
    _dependent_accelerations(S, Rt, rhs, nz, qdd)
    return True


@njit(cache=True)
def accelerations_prescribed(P, q, qd, s, c, Q, rows, nz, Rt, S, Mb, rhs, tmp, qdd, alpha, tau):
    """The same with the crank angle a driving constraint (θ̈ = ``alpha`` given, Q[7] = 0):
    the rows of the other independent coordinates w (the eccentricities) give
    (RᵀMR)_ww ẅ = [Rᵀ(Q − MṘż)]_w − (RᵀMR)_wθ α, and the θ row the drive torque
    τ = (RᵀMR)_θθ α + (RᵀMR)_θw ẅ − [Rᵀ(Q − MṘż)]_θ (the Lagrange multiplier of θ − θ_ref(t) = 0),
    written to ``tau[0]``. Returns False if (RᵀMR)_ww is not SPD."""
    # the assembly of ``accelerations``, then a singular-proof solve of the w block only
    _assemble(P, q, qd, s, c, Q, rows, nz, Rt, S, Mb, rhs, tmp)
    m = nz - 1
    zdd = np.empty(N_Z)
    zdd[0] = alpha
    if m > 0:
        W = np.empty((m, m))
        rw = np.empty(m)
        for i in range(m):
            rw[i] = rhs[i + 1] - Mb[i + 1, 0] * alpha
            for j in range(m):
                W[i, j] = Mb[i + 1, j + 1]
        if not _cholesky_solve(W, rw, m):
            return False
        for i in range(m):
            zdd[i + 1] = rw[i]
    t = -rhs[0]
    for j in range(nz):
        t += Mb[0, j] * zdd[j]
    tau[0] = t
    _dependent_accelerations(S, Rt, zdd, nz, qdd)
    return True


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
        b[6] = -qd[5]
    solve_aug(q, s, c, b, dq)
    for i in range(N_Q):
        qd[i] = dq[i]
    return it


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
    return T + V


@njit(cache=True)
def _outputs(P, q, qd, qdd, tau, ja, jb, jc, row):
    """One output sample (layout ``O_*``) from the state, its accelerations and forces."""
    row[O_THETA] = q[7]
    row[O_OMEGA] = qd[7]
    row[O_SLIDER] = q[6]
    row[O_TORQUE] = tau
    ux, uy = q[4] - q[2], q[5] - q[3]
    L = math.sqrt(ux * ux + uy * uy)
    hx, hy = ux / L, uy / L          # rod x axis (B' -> C)
    px_, py_ = -hy, hx               # rod y axis
    uddx, uddy = qdd[4] - qdd[2], qdd[5] - qdd[3]
    gx, gy = P[P_GX], P[P_GY]
    for i in range(6):
        base = P_SENS + 4 * i
        body = P[base]
        sx, sy = P[base + 1], P[base + 2]
        axis = int(P[base + 3])
        if body < 0.5:   # rod: P = B' + sx x̂ + sy ŷ, rigid with |u| = L
            ax = qdd[2] + (sx * uddx - sy * uddy) / L - gx
            ay = qdd[3] + (sx * uddy + sy * uddx) / L - gy
            if axis < 2:
                v = ax * hx + ay * hy
            else:
                v = ax * px_ + ay * py_
        else:            # slider: translates along x, frame = bench frame
            ax = qdd[6] - gx
            ay = -gy
            v = ax if axis < 2 else ay
        if axis == 1 or axis == 3:
            v = -v
        row[O_ACC + i] = v
    for j in range(2):
        jo = jb if j == 0 else jc
        base = O_JOINT_B if j == 0 else O_JOINT_C
        if (j == 0 and P[P_CLR_B] > 0.5) or (j == 1 and P[P_CLR_C] > 0.5):
            row[base] = jo[0] * hx + jo[1] * hy       # eccentricity in the rod frame
            row[base + 1] = jo[0] * px_ + jo[1] * py_
            row[base + 2] = jo[2]
            row[base + 3] = jo[3]
            row[base + 4] = jo[4]
        else:
            for k in range(5):
                row[base + k] = 0.0
    for k in range(5):         # A: eccentricity in the bench frame (the bushing is the frame's bore)
        row[O_JOINT_A + k] = ja[k] if P[P_CLR_A] > 0.5 else 0.0


@njit(cache=True, nogil=True)  # no GIL while stepping: a sink's writer thread runs meanwhile
def run_steps(P, st, theta_ref, omega_ref, stride, out, want_out):
    """Integrate ``len(theta_ref)`` steps from state ``st`` (updated in place).

    Step k uses the references theta_ref[k], omega_ref[k]; every ``stride``-th step writes
    the sample of its starting state (and of the accelerations of that step) to ``out``
    (if ``want_out``). Returns (status, steps done); status ``OK``, ``NEWTON_FAILED`` or
    ``NOT_FINITE``.
    """
    return _integrate(P, st, theta_ref, omega_ref, np.empty(0), False, stride, out, want_out,
                      np.empty(0), np.empty(0), np.empty(0), out)


@njit(cache=True, nogil=True)
def run_prescribed(P, st, theta_ref, omega_ref, alpha_ref, stride, out, want_out):
    """Integrate ``len(alpha_ref)`` steps with the crank angle prescribed (``drive.mode =
    "prescribed"``): the driving constraint θ − θ_ref(t) = 0. ``theta_ref``, ``omega_ref`` hold
    the program at t_0 … t_n (n + 1 values), ``alpha_ref`` its acceleration at t_0 … t_{n−1}.
    Step k solves the reduced equations with θ̈ = alpha_ref[k] (:func:`accelerations_prescribed`;
    the drive torque is written to the torque column), advances the other independent
    coordinates by symplectic Euler, sets θ, θ̇ to theta_ref[k + 1], omega_ref[k + 1] and projects
    (Newton on the constraints with z held, q̇ = R ż): the crank angle equals the program at every
    step to round-off, whatever the loads. Same returns as :func:`run_steps`."""
    return _integrate(P, st, theta_ref, omega_ref, alpha_ref, True, stride, out, want_out,
                      np.empty(0), np.empty(0), np.empty(0), out)


@njit(cache=True, nogil=True)
def run_motor(P, D, st, ds, setpoint, stride, out, dout, want_out):
    """Integrate ``len(setpoint)`` steps driven by the drive train (``drive.mode`` "motor" or
    "torque", :mod:`twin.reference.drivetrain`: parameters ``D``, state ``ds`` updated in place):
    the crank receives the belt's torque; ``setpoint[k]`` is step k's motor speed set point
    [rad/s] or motor torque [N m]. ``dout`` gets the drive train's sample rows. Same returns as
    :func:`run_steps`."""
    z = np.empty(0)
    return _integrate(P, st, z, z, z, False, stride, out, want_out, D, ds, setpoint, dout)


@njit(cache=True, nogil=True)
def _integrate(P, st, theta_ref, omega_ref, alpha_ref, prescribed, stride, out, want_out, D, ds, setpoint, dout):
    """The stepping loop of :func:`run_steps` (PID drive), :func:`run_prescribed` and
    :func:`run_motor` (drive train: ``D`` non-empty)."""
    h = P[P_H]
    kp, kv, ki, imax = P[P_KP], P[P_KV], P[P_KI], P[P_IMAX]
    q = st[S_Q:S_Q + N_Q].copy()
    qd = st[S_QD:S_QD + N_Q].copy()
    integ = st[S_I]
    cst_a = np.empty(2)
    cst_b = np.empty(2)
    cst_c = np.empty(2)
    cst_a[0], cst_a[1] = st[S_IN_A], st[S_VIMP_A]
    cst_b[0], cst_b[1] = st[S_IN_B], st[S_VIMP_B]
    cst_c[0], cst_c[1] = st[S_IN_C], st[S_VIMP_C]
    Q = np.empty(N_Q)
    ja = np.zeros(5)
    jb = np.zeros(5)
    jc = np.zeros(5)
    rows = np.empty(N_Z, dtype=np.int64)
    nz = independent_rows(P, rows)
    Rt = np.empty((N_Z, N_Q))
    S = np.empty(N_Q)
    Mb = np.empty((N_Z, N_Z))
    rhs = np.empty(N_Z)
    tmp = np.empty((N_Z + 2, N_Q))
    qdd = np.empty(N_Q)
    res = np.empty(N_Q)
    dq = np.empty(N_Q)
    bb = np.empty(N_Q)
    s, c = math.sin(q[7]), math.cos(q[7])
    motor = D.shape[0] > 0
    n = alpha_ref.shape[0] if prescribed else (setpoint.shape[0] if motor else theta_ref.shape[0])
    dtmp = np.empty(3)
    qd0 = np.empty(N_Q)
    Qg = np.zeros(N_Q)
    if motor:
        DT.gravity_forces(P[P_GX], P[P_GY], P[P_M1], P[P_XG1], P[P_R], P[P_M2], P[P_XG2], P[P_L], P[P_M3], Qg)
    tau_p = np.zeros(1)
    midpoint = P[P_INTEGRATOR] == 1.0 and not prescribed
    qm = np.empty(N_Q)        # midpoint stage (explicit midpoint only)
    qdm = np.empty(N_Q)
    cm_a = np.empty(2)
    cm_b = np.empty(2)
    cm_c = np.empty(2)
    jm_a = np.zeros(5)
    jm_b = np.zeros(5)
    jm_c = np.zeros(5)
    status = OK
    k = 0
    while k < n:
        err = 0.0 if motor else theta_ref[k] - q[7]
        if prescribed:
            generalized_forces(P, q, qd, 0.0, cst_a, cst_b, cst_c, Q, ja, jb, jc)
            if not accelerations_prescribed(P, q, qd, s, c, Q, rows, nz, Rt, S, Mb, rhs, tmp, qdd,
                                            alpha_ref[k], tau_p):
                status = NOT_FINITE
                break
            tau = tau_p[0]
        else:
            if motor:  # drive-train hook: the belt's torque on the crank
                tau = DT.begin_step(D, ds, qd[7], setpoint[k], dtmp)
            else:
                tau = kp * err + kv * (omega_ref[k] - qd[7]) + ki * integ
            generalized_forces(P, q, qd, tau, cst_a, cst_b, cst_c, Q, ja, jb, jc)
            if not accelerations(P, q, qd, s, c, Q, rows, nz, Rt, S, Mb, rhs, tmp, qdd):
                status = NOT_FINITE
                break
        if want_out and k % stride == 0:
            _outputs(P, q, qd, qdd, tau, ja, jb, jc, out[k // stride])
            if motor:
                DT.outputs(D, ds, dout[k // stride])
                if D[DT.D_ACCOUNT] != 0.0:
                    dout[k // stride, DT.DO_EMECH] = energy(P, q, qd) + dout[k // stride, DT.DO_ROTOR_KE]
        if midpoint:
            # explicit midpoint (second order): the state at t + h/2 (projected), the accelerations
            # there (PID integral of the step start, contact events advanced at step starts only),
            # then the whole step with the midpoint's rates
            for i in range(N_Q):
                qm[i] = q[i] + 0.5 * h * qd[i]
                qdm[i] = qd[i] + 0.5 * h * qdd[i]
            sm, cm = math.sin(qm[7]), math.cos(qm[7])
            if project(P, qm, qdm, sm, cm, res, dq, bb) < 0:
                status = NEWTON_FAILED
                k += 1
                break
            # drive reference at t + h/2 (second order: θ_ref + h/2 ω_ref, ω_ref averaged)
            om_ref = 0.5 * (omega_ref[k] + omega_ref[k + 1]) if k + 1 < n else omega_ref[k]
            taum = kp * (theta_ref[k] + 0.5 * h * omega_ref[k] - qm[7]) + kv * (om_ref - qdm[7]) + ki * integ
            cm_a[0], cm_a[1] = cst_a[0], cst_a[1]
            cm_b[0], cm_b[1] = cst_b[0], cst_b[1]
            cm_c[0], cm_c[1] = cst_c[0], cst_c[1]
            generalized_forces(P, qm, qdm, taum, cm_a, cm_b, cm_c, Q, jm_a, jm_b, jm_c)
            if not accelerations(P, qm, qdm, sm, cm, Q, rows, nz, Rt, S, Mb, rhs, tmp, qdd):
                status = NOT_FINITE
                break
        integ += h * err
        if imax > 0.0:
            if integ > imax:
                integ = imax
            elif integ < -imax:
                integ = -imax
        if midpoint:
            for i in range(N_Q):
                q[i] += h * qdm[i]
                qd[i] += h * qdd[i]
        else:
            if motor and D[DT.D_ACCOUNT] != 0.0:  # step-start velocities for the accounts
                for i in range(N_Q):
                    qd0[i] = qd[i]
            for i in range(N_Q):
                qd[i] += h * qdd[i]
                q[i] += h * qd[i]
        if prescribed:  # the driving constraint: θ and θ̇ are the program's at t_{k+1}
            q[7] = theta_ref[k + 1]
            qd[7] = omega_ref[k + 1]
        s, c = math.sin(q[7]), math.cos(q[7])
        if project(P, q, qd, s, c, res, dq, bb) < 0:
            status = NEWTON_FAILED
            k += 1
            break
        fin = True
        for i in range(N_Q):
            if not (math.isfinite(q[i]) and math.isfinite(qd[i])):
                fin = False
        if not fin:
            status = NOT_FINITE
            k += 1
            break
        if motor:  # drive-train hook: rotor, belt stretch, accounts
            fgd = DT.guide_force(P[P_FGUIDE], qd0[6], P[P_V0], P[P_V1]) if D[DT.D_ACCOUNT] != 0.0 else 0.0
            DT.end_step(D, ds, Q, Qg, tau, fgd, qd0, qd)
        k += 1
    st[S_Q:S_Q + N_Q] = q
    st[S_QD:S_QD + N_Q] = qd
    st[S_I] = integ
    st[S_IN_A], st[S_VIMP_A] = cst_a[0], cst_a[1]
    st[S_IN_B], st[S_VIMP_B] = cst_b[0], cst_b[1]
    st[S_IN_C], st[S_VIMP_C] = cst_c[0], cst_c[1]
    return status, k


@njit(cache=True)
def free_motion(P, st, nsteps, every, th_d, en, phi, phid):
    """Unforced run (τ = 0) recording θ̇, energy, ‖Φ‖, ‖Φ̇‖ before step 0 and after every
    ``every`` steps. Returns (status, steps done, samples written)."""
    zero = np.zeros(every)
    out = np.empty((1, N_OUT))
    m = 0
    k = 0
    status = OK
    while True:
        q = st[S_Q:S_Q + N_Q]
        qd = st[S_QD:S_QD + N_Q]
        th_d[m] = qd[7]
        en[m] = energy(P, q, qd)
        phi[m] = constraint_norm(P, q)
        phid[m] = velocity_constraint_norm(P, q, qd)
        m += 1
        if k + every > nsteps or status != OK:
            break
        status, done = run_steps(P, st, zero, zero, every, out, False)
        k += done
    return status, k, m


# ----------------------------------------------------------------- Python helpers
def build_params(cfg: BenchConfig, *, min_impact_speed_mps: float = 1e-3, newton_tol_m: float = 1e-10,
                 newton_max_iter: int = 20, drive: bool = True, guide_friction: bool = True,
                 joint_friction: bool = True, integrator: str = "euler") -> np.ndarray:
    """Parameter vector of a configuration (layout ``P_*``).

    ``drive=False`` zeroes the PID gains (free motion), ``guide_friction``/``joint_friction``
    False switch those forces off (§4.1 study). The linear law's stiffness and damping are
    resolved here (see :func:`contact_parameters`). ``integrator``: "euler" (symplectic Euler,
    S003 Eq. 21, the default) or "midpoint" (explicit midpoint, second order; see :func:`run_steps`).
    """
    b, j, mech, con = cfg.bodies, cfg.joints, cfg.mechanism, cfg.contact
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
    P[P_LAW] = LAW_CODES[con.law]
    P[P_N], P[P_E] = con.exponent, con.restitution
    P[P_VMIN] = min_impact_speed_mps
    P[P_MU0] = con.mu0 if joint_friction else 0.0
    P[P_V0], P[P_V1] = con.v0_mps, con.v1_mps
    P[P_DMAX] = con.impact_d_max_m
    P[P_FRIC_LAW] = FRICTION_CODES[con.friction_law]
    P[P_MUS] = con.mu_static if joint_friction else 0.0
    P[P_VS], P[P_VD] = con.v_static_mps, con.v_kinetic_mps
    P[P_FGUIDE] = mech.guide_friction_n if guide_friction else 0.0
    if drive:
        P[P_KP], P[P_KV], P[P_KI], P[P_IMAX] = cfg.pid.kp, cfg.pid.kv, cfg.pid.ki, cfg.pid.imax
    P[P_H] = cfg.simulation.timestep_s
    P[P_NEWTON_TOL], P[P_NEWTON_MAXIT] = newton_tol_m, newton_max_iter
    P[P_INTEGRATOR] = INTEGRATORS[integrator]
    P[P_PRESCRIBED] = 1.0 if cfg.drive.mode == "prescribed" else 0.0
    for i, name in enumerate(ACCELEROMETERS):
        mnt = cfg.sensors.accelerometers[name]
        base = P_SENS + 4 * i
        P[base] = 0.0 if mnt.body == "rod" else 1.0
        P[base + 1], P[base + 2] = mnt.position_m
        P[base + 3] = _AXES[mnt.axis]
    return P


def contact_parameters(cfg: BenchConfig, P: np.ndarray, st: np.ndarray) -> dict[str, JointContact]:
    """Resolve K (and the linear law's k, c) of each clearance joint into ``P`` (in place).

    Joints A, B, C, each with its own pin, bushing and materials. Hysteresis laws: K = the joint's
    ``contact.stiffness_of(j)`` if set, else S003 Eq. 18 (:func:`twin.config.joint_stiffness`),
    exponent ``contact.exponent``. Linear law f = k δ + c δ̇: k = ``contact.stiffness_of(j)`` [N/m]
    if set, else the linear contact with the Lankarani–Nikravesh law's contact duration for an impact
    at 0.1 m/s (the MuJoCo twin's first guess, :func:`twin.impact.linear_equivalent`); c gives that
    linear contact the restitution ``contact.restitution``: c = 2 ζ(e) sqrt(k m_eff), with m_eff
    the effective mass along the initial contact normal from the reduced mass matrix (at A the
    crank's, whose journal moves in the frame's bore). K (or k) is multiplied by ``contact.stiffness_scale``.
    """
    from twin.impact import linear_damping_ratio, linear_equivalent

    out: dict[str, JointContact] = {}
    con = cfg.contact
    q = st[S_Q:S_Q + N_Q]
    Mb = reduced_mass(P, q)
    W = np.linalg.inv(Mb)
    off = 1                    # z = θ, then e_A, e_B, e_C of the clearance joints
    for jt, kidx, cidx in (("A", P_K_A, P_CLIN_A), ("B", P_K_B, P_CLIN_B), ("C", P_K_C, P_CLIN_C)):
        if cfg.joints.diametral_mm(jt) <= 0:
            continue
        e = {"A": np.array([q[8], q[9]]), "B": np.array([q[0] - q[2], q[1] - q[3]]),
             "C": np.array([q[6] - q[4], P[P_DOFF] - q[5]])}[jt]
        n = e / np.linalg.norm(e) if np.linalg.norm(e) > 0 else np.array([0.0, 1.0])
        w = W[off:off + 2, off:off + 2]
        m_eff = float(1.0 / (n @ w @ n))
        off += 2
        K_ln = joint_stiffness(cfg, jt)
        if con.law == "linear":
            k = con.stiffness_of(jt) if con.stiffness_of(jt) > 0 else \
                linear_equivalent(K_ln, con.exponent, con.restitution, m_eff, LINEAR_MATCH_SPEED)[0]
            k *= con.stiffness_scale
            c = 2.0 * linear_damping_ratio(con.restitution) * math.sqrt(k * m_eff)
            P[kidx], P[cidx] = k, c
            out[jt] = JointContact(cfg.joints.radial_m(jt), float(k), 1.0, float(c), m_eff)
        elif con.law == "adams-impact":  # K δⁿ + STEP(δ; d_max) c_max δ̇: c_max in the linear law's slot
            K_ln *= con.stiffness_scale
            P[kidx], P[cidx] = K_ln, con.impact_c_max_nspm
            out[jt] = JointContact(cfg.joints.radial_m(jt), float(K_ln), con.exponent, con.impact_c_max_nspm, m_eff)
        else:
            K_ln *= con.stiffness_scale
            P[kidx] = K_ln
            out[jt] = JointContact(cfg.joints.radial_m(jt), float(K_ln), con.exponent, None, m_eff)
    return out


def initial_state(cfg: BenchConfig, theta: float, omega: float = 0.0, P: np.ndarray | None = None) -> np.ndarray:
    """State vector (layout ``S_*``) at crank angle θ with the configured initial
    eccentricities (:func:`twin.kinematics.initial_pose`), PID integral 0, no contact event;
    at rest, or turning at crank rate ``omega`` [rad/s] (needs ``P``) with the eccentricities
    fixed in the bench frame (ė = 0) and every other velocity from the constraints (q̇ = R ż)."""
    pose = initial_pose(cfg, theta)
    st = np.zeros(N_STATE)
    st[S_Q:S_Q + N_Q] = [pose.b_pin[0], pose.b_pin[1], pose.b_bush[0], pose.b_bush[1],
                         pose.c_bush[0], pose.c_bush[1], pose.c_pin[0], pose.theta, pose.e_a[0], pose.e_a[1]]
    if omega != 0.0:
        if P is None:
            raise ValueError("initial_state: a turning start needs the parameter vector P")
        q, qd = st[S_Q:S_Q + N_Q].copy(), np.zeros(N_Q)
        qd[7] = omega
        if project(P, q, qd, math.sin(q[7]), math.cos(q[7]), np.empty(N_Q), np.empty(N_Q), np.empty(N_Q)) < 0:
            raise ValueError("the initial pose does not satisfy the constraints")
        st[S_Q:S_Q + N_Q], st[S_QD:S_QD + N_Q] = q, qd
    return st
