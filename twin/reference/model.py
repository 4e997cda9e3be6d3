r"""The reference engine's dynamics: generalized forces, equations of motion and integration
of the natural-coordinate model of the bench (S003 §3, Eq. 11–21).

The coordinates q, the ten constraint rows, the velocity transformation (R-matrix), the mass
matrix and the parameter and state layouts are :mod:`twin.natural_coordinates`; the contact laws
are :mod:`twin.physics.contact`, their constants :mod:`twin.contact_params`.


Generalized forces Q (virtual work over δq):

* gravity g = (g_x, g_y) (in-plane components of ``mechanism.gravity_vector``; the normal
  component does no work): centre of mass of the crank (1 − ξ_G/r) A' + (ξ_G/r) B, of the rod
  (1 − ξ_G/l) B' + (ξ_G/l) C, slider m₃ g_x on x'_C (the guide takes m₃ g_y);
* drive torque τ about +z on θ (virtual work τ δθ: a couple on the crank);
* a force F at a crank point P (δP = δA' + δθ ẑ × (P − A')): F on (x_A, y_A) and the torque
  ((P − A') × F)_z on θ; at a rod point P = B' + α u + β R₉₀ u (u = C − B'):
  (1 − α) F − β R₉₀ᵀF on B', α F + β R₉₀ᵀF on C; on the slider pin: F_x on x'_C;
* contact at a clearance joint (:mod:`twin.physics.contact`): penetration δ = |e| − c,
  n = e/|e|, t = ẑ × n; force on the pin −f_N n + f_T t at the pin's surface point
  (pin centre + R_pin n), the opposite on the bushing's body at the bushing's surface point
  (bushing centre + R_bushing n). f_T acts on the true tangential relative velocity of those two
  material points: v_t = ė·t + ω₁ R_pin,B − ω₂ R_bushing,B at B (crank ω₁ = θ̇, rod ω₂),
  v_t = ė·t − ω₂ R_bushing,C at C (the slider does not rotate) and v_t = ė·t + ω₁ R_pin,A at A
  (the frame does not rotate; its reaction is not modelled). Pin and bushing radii are the
  joint's own (``joints.pin_radius(j)``, ``joints.bushing_radius_m(j)``);
* slider guide friction (S003 §3: 2.5 N whenever the slider moves): −F_g ρ(|ẋ'_C|) sign(ẋ'_C)
  on x'_C, with ρ the same regularization ramp as the joint friction (0 below v0, linear to 1
  at v1; :func:`twin.physics.contact.ramp`). A discontinuous sign() would chatter at the
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

Everything here is compiled with numba (``cache=True``); the parameter vector is built by
:func:`build_params` (layout ``P_*`` of :mod:`twin.natural_coordinates`).
"""

from __future__ import annotations

import math

import numpy as np
from twin.jit import njit

from twin.config import ACCELEROMETERS, BenchConfig
from twin.config.mechanism import guide_stiffness
from twin.contact_params import JointContact, joint_contact
from twin.natural_coordinates import (
    N_Q, N_Z, P_CLIN_A, P_CLIN_B, P_CLIN_C, P_CLR_A, P_CLR_B, P_CLR_C, P_CLR_G, P_C_A, P_C_B, P_C_C, P_DMAX,
    P_DOFF, P_E, P_FGUIDE, P_FRIC_LAW, P_GX, P_GY, P_H, P_IMAX, P_INTEGRATOR, P_KI, P_KP, P_KV, P_K_A, P_K_B,
    P_K_C, P_K_G, P_L, P_LAW, P_M1, P_M2, P_M3, P_MU0, P_MUS, P_N, P_NEWTON_MAXIT, P_NEWTON_TOL, P_OUT_ENERGY,
    P_PRESCRIBED, P_R, P_RBUSH_A, P_RBUSH_B, P_RBUSH_C, P_RPIN_A, P_RPIN_B, P_RPIN_C, P_SENS, P_V0, P_V1, P_VD,
    P_VMIN, P_VS, P_XG1, P_XG2, S_GUIDE, S_I, S_IN_A, S_IN_B, S_IN_C, S_Q, S_QD, S_VIMP_A, S_VIMP_B, S_VIMP_C,
    constraint_norm, effective_masses, energy, independent_rows, kinetic_energy, mass_times, mechanism_params,
    reduced_mass_into,
    project, quadratic_terms, solve_aug, velocity_constraint_norm)
from twin.reference import drivetrain as DT
from twin.reference.guide import N_GUIDE_OUT, guide_forces
from twin.physics.contact import FRICTION_CODES, LAW_CODES, adams_friction_force, friction_force, normal_force, ramp

#: integrators of :func:`run_steps` by name -> code in ``P[P_INTEGRATOR]``
INTEGRATORS = {"euler": 0, "midpoint": 1}
#: joint codes of :func:`_joint`
J_A, J_B, J_C = 0, 1, 2

# ------------------------------------------------------------------- output columns
O_THETA, O_OMEGA, O_SLIDER = 0, 1, 2
O_ACC = 3              # AC1..AC6: 3..8
O_TORQUE = 9
O_JOINT_B, O_JOINT_C = 10, 15  # ecc_x, ecc_y (rod frame), pen, fn, ft
O_JOINT_A = 20                 # the same at A, ecc in the bench frame
O_GUIDE = 25                   # y_g, φ, fn front, fn rear, ft front, ft rear (twin.reference.guide)
O_EKIN, O_EPOT, O_VSLIDER = O_GUIDE + N_GUIDE_OUT, O_GUIDE + N_GUIDE_OUT + 1, O_GUIDE + N_GUIDE_OUT + 2
N_OUT = O_VSLIDER + 1          # the last three with P[P_OUT_ENERGY] only (channel group "energy")

#: integration status codes of :func:`run_steps`
OK, NEWTON_FAILED, NOT_FINITE = 0, 1, 2

_AXES = {"+x": 0, "-x": 1, "+y": 2, "-y": 3}


# ------------------------------------------------------------------------- kernels
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
        if P[P_CLR_G] > 0.5:   # the slider pin C' moves with the slider's y_g
            ex, ey = q[6] - q[4], P[P_DOFF] + q[10] - q[5]
            edx, edy = qd[6] - qd[4], qd[10] - qd[5]
        else:
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
        Q[6] += Fx                                 # slider pin: the ideal guide takes F_y
        if P[P_CLR_G] > 0.5:
            Q[10] += Fy
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
    event state ``cst_j``, its output ``jj``). With a guide clearance ``cst_c`` also holds the
    guide's events (entries 2–5) and ``jc`` its outputs (entries 5–10, :mod:`twin.reference.guide`)."""
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
    Q[10] = 0.0
    Q[11] = 0.0
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
    if P[P_CLR_G] > 0.5:
        guide_forces(P, q, qd, cst_c[2:6], jc[5:5 + N_GUIDE_OUT], Q)


@njit(cache=True)
def cholesky_factor(A, n):
    """In-place Cholesky factor of the SPD matrix A (n × n, its lower triangle becomes L); False if A is not
    positive definite."""
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
    return True


@njit(cache=True)
def cholesky_solve_factored(L, n, b):
    """Solve L Lᵀ x = b in place (b -> x) with the factor of :func:`cholesky_factor`."""
    for i in range(n):
        t = b[i]
        for k in range(i):
            t -= L[i, k] * b[k]
        b[i] = t / L[i, i]
    for i in range(n - 1, -1, -1):
        t = b[i]
        for k in range(i + 1, n):
            t -= L[k, i] * b[k]
        b[i] = t / L[i, i]


@njit(cache=True)
def _cholesky_solve(A, b, n):
    """Solve the SPD system A x = b (n × n, in place: A -> L, b -> x)."""
    if not cholesky_factor(A, n):
        return False
    cholesky_solve_factored(A, n, b)
    return True


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
    # with A and the guide ideal, R's rows 8–11 are exact zeros: the products skip them (the same sums)
    nq = N_Q if (P[P_CLR_A] > 0.5 or P[P_CLR_G] > 0.5) else 8
    for j in range(nz):
        acc = 0.0
        for k in range(nq):
            acc += Rt[j, k] * b[k]
        rhs[j] = acc
    reduced_mass_into(Rt, tmp, nz, nq, Mb)


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
        elif P[P_CLR_G] > 0.5:  # slider with guide clearance: P = Cs + R(φ)(sx, sy), Cs = C' + R(φ)(0, −d_off)
            cf, sf = math.cos(q[11]), math.sin(q[11])
            ry_ = sy - P[P_DOFF]
            rx, ry = cf * sx - sf * ry_, sf * sx + cf * ry_
            w, al = qd[11], qdd[11]
            ax = qdd[6] - al * ry - w * w * rx - gx
            ay = qdd[10] + al * rx - w * w * ry - gy
            v = (ax * cf + ay * sf) if axis < 2 else (-ax * sf + ay * cf)
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
    for k in range(N_GUIDE_OUT):
        row[O_GUIDE + k] = jc[5 + k] if P[P_CLR_G] > 0.5 else 0.0
    if P[P_OUT_ENERGY] > 0.5:  # T and V (the potential up to a constant: zero with every centre of mass at A)
        t = kinetic_energy(P, q, qd)
        row[O_EKIN] = t
        row[O_EPOT] = energy(P, q, qd) - t
        row[O_VSLIDER] = qd[6]


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
    cst_c = np.empty(6)        # C's event, then the guide's (front, rear)
    cst_a[0], cst_a[1] = st[S_IN_A], st[S_VIMP_A]
    cst_b[0], cst_b[1] = st[S_IN_B], st[S_VIMP_B]
    cst_c[0], cst_c[1] = st[S_IN_C], st[S_VIMP_C]
    for i in range(4):
        cst_c[2 + i] = st[S_GUIDE + i]
    Q = np.empty(N_Q)
    ja = np.zeros(5)
    jb = np.zeros(5)
    jc = np.zeros(5 + N_GUIDE_OUT)
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
        if P[P_CLR_G] > 0.5:   # gravity on the slider's y_g (its moment on φ is booked as guide contact)
            Qg[10] = P[P_M3] * P[P_GY]
    tau_p = np.zeros(1)
    midpoint = P[P_INTEGRATOR] == 1.0 and not prescribed
    qm = np.empty(N_Q)        # midpoint stage (explicit midpoint only)
    qdm = np.empty(N_Q)
    cm_a = np.empty(2)
    cm_b = np.empty(2)
    cm_c = np.empty(6)
    jm_a = np.zeros(5)
    jm_b = np.zeros(5)
    jm_c = np.zeros(5 + N_GUIDE_OUT)
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
            for i in range(6):
                cm_c[i] = cst_c[i]
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
    for i in range(4):
        st[S_GUIDE + i] = cst_c[2 + i]
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
    con, mech = cfg.contact, cfg.mechanism
    P = mechanism_params(cfg)
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
    P[P_OUT_ENERGY] = 1.0 if "energy" in cfg.sensors.channels else 0.0
    if cfg.joints.guide_play:
        P[P_K_G] = guide_stiffness(cfg.joints, cfg.materials)
    for i, name in enumerate(ACCELEROMETERS):
        mnt = cfg.sensors.accelerometers[name]
        base = P_SENS + 4 * i
        P[base] = 0.0 if mnt.body == "rod" else 1.0
        P[base + 1], P[base + 2] = mnt.position_m
        P[base + 3] = _AXES[mnt.axis]
    return P


def contact_parameters(cfg: BenchConfig, P: np.ndarray, st: np.ndarray) -> dict[str, JointContact]:
    """Resolve K (and the linear law's k, c) of each clearance joint into ``P`` (in place):
    :func:`twin.contact_params.joint_contact` with the effective mass along the contact normal
    at the state ``st`` (:func:`twin.natural_coordinates.effective_masses`)."""
    out: dict[str, JointContact] = {}
    q = st[S_Q:S_Q + N_Q]
    slots = {"A": (P_K_A, P_CLIN_A), "B": (P_K_B, P_CLIN_B), "C": (P_K_C, P_CLIN_C)}
    for jt, m_eff in effective_masses(cfg, P, q).items():
        jc = joint_contact(cfg, jt, m_eff)
        kidx, cidx = slots[jt]
        P[kidx] = jc.stiffness
        if jc.damping_ns_per_m is not None:  # linear law: c; ADAMS IMPACT: c_max in the linear law's slot
            P[cidx] = jc.damping_ns_per_m
        elif cfg.contact.law == "johnson-cylindrical":  # its radial clearance ΔR in the same slot
            P[cidx] = jc.radial_clearance_m
        out[jt] = jc
    return out
