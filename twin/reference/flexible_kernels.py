"""Compiled kernels of the reference engine's flexible structure (:mod:`twin.reference.flexible`): the chain's
Jacobian, residuals and quadratic velocity terms, the chain block's block-tridiagonal LU (2 × 2 blocks, one per
chain point, O(N)), the elastic joints' and supports' forces and energy, the clearance contact on the rod's eyes
with its damping bound and the laws' terms, and the accelerometers on the segments. The step's accelerations come
from :mod:`twin.reference.flexible_kkt`; the R-matrix form they are checked against is
:mod:`twin.reference.flexible_rmatrix`. The model, the
coordinates and the rows are described in :mod:`twin.reference.flexible`; the stepping loop lives there.
"""

from __future__ import annotations

import math

import numpy as np

from twin.jit import njit
from twin.natural_coordinates import (N_Q, P_CLIN_B, P_CLIN_C, P_CLR_G, P_DMAX, P_E, P_FRIC_LAW, P_K_B, P_K_C,
                                      P_LAW, P_MU0, P_MUS, P_N, P_RPIN_B, P_VD, P_VS, P_CLR_B, P_CLR_C, P_DOFF,
                                      P_GX, P_GY, P_M3, P_NEWTON_MAXIT, P_NEWTON_TOL, P_RBUSH_B, P_RBUSH_C, P_SENS,
                                      P_V0, P_V1, energy, kinetic_energy, mass_times, residual, solve_aug)
from twin.physics.contact import adams_friction_force, friction_force, normal_force
from twin.reference.model import O_ACC, _rod_force

# ----------------------------------------------------------------- the supports' parameters ``G`` (build())
G_KF, G_CF, G_MF, G_KG, G_CG, G_MG, G_FLEX_A, G_FLEX_G = 0, 1, 2, 3, 4, 5, 6, 7
# then the rod's mid-span material point for the "structure" channels (``flexible._structure_outputs``): its segment
# and its distance from the segment's start [m]; :func:`support_table` fills them
G_MID_SEG, G_MID_XI = 8, 9
N_G = 10


@njit(cache=True)
def _cross(ax, ay, bx, by):
    return ax * by - ay * bx


@njit(cache=True)
def chain_jacobian(q, segs, slides, indep, A):
    """Rows of the chain (n − 12 of them) over all n coordinates into ``A`` (zeroed here)."""
    A[:, :] = 0.0
    r = 0
    for j in range(segs.shape[0]):
        a, b = segs[j, 0], segs[j, 1]
        ux, uy = q[b] - q[a], q[b + 1] - q[a + 1]
        A[r, a] -= 2.0 * ux
        A[r, a + 1] -= 2.0 * uy
        A[r, b] += 2.0 * ux
        A[r, b + 1] += 2.0 * uy
        r += 1
    for k in range(slides.shape[0]):
        p, c, s = slides[k, 0], slides[k, 1], slides[k, 2]
        a, b = segs[s, 0], segs[s, 1]
        dx, dy = q[c] - q[p], q[c + 1] - q[p + 1]
        wx, wy = q[b] - q[a], q[b + 1] - q[a + 1]
        # f = d × w: ∂/∂c = (w_y, −w_x), ∂/∂p = −that, ∂/∂b = (−d_y, d_x), ∂/∂a = −that
        A[r, c] += wy
        A[r, c + 1] -= wx
        A[r, p] -= wy
        A[r, p + 1] += wx
        A[r, b] -= dy
        A[r, b + 1] += dx
        A[r, a] += dy
        A[r, a + 1] -= dx
        r += 1
    for k in range(indep.shape[0]):
        if indep[k, 0] == 0:
            A[r, indep[k, 1] + 1] = 1.0
        else:
            A[r, indep[k, 1]] = 1.0
            A[r, indep[k, 2]] = -1.0
        r += 1


@njit(cache=True)
def chain_residual(q, segs, seg_f, slides, out):
    """Constraint residuals of the chain's rows (independent rows 0)."""
    out[:] = 0.0
    r = 0
    for j in range(segs.shape[0]):
        a, b = segs[j, 0], segs[j, 1]
        ux, uy = q[b] - q[a], q[b + 1] - q[a + 1]
        out[r] = ux * ux + uy * uy - seg_f[j, 1] * seg_f[j, 1]
        r += 1
    for k in range(slides.shape[0]):
        p, c, s = slides[k, 0], slides[k, 1], slides[k, 2]
        a, b = segs[s, 0], segs[s, 1]
        out[r] = _cross(q[c] - q[p], q[c + 1] - q[p + 1], q[b] - q[a], q[b + 1] - q[a + 1])
        r += 1


@njit(cache=True)
def chain_quadratic(qd, segs, slides, out):
    """−Φ̇_q q̇ of the chain's rows (zero for the independent rows)."""
    out[:] = 0.0
    r = 0
    for j in range(segs.shape[0]):
        a, b = segs[j, 0], segs[j, 1]
        vx, vy = qd[b] - qd[a], qd[b + 1] - qd[a + 1]
        out[r] = -2.0 * (vx * vx + vy * vy)
        r += 1
    for k in range(slides.shape[0]):
        p, c, s = slides[k, 0], slides[k, 1], slides[k, 2]
        a, b = segs[s, 0], segs[s, 1]
        out[r] = -2.0 * _cross(qd[c] - qd[p], qd[c + 1] - qd[p + 1], qd[b] - qd[a], qd[b + 1] - qd[a + 1])
        r += 1


@njit(cache=True)
def chain_order(segs, slides, indep, piv):
    """The chain block as block tridiagonal: the two rows of A (indices into the chain's rows) of each chain point
    k into ``piv[2k]``, ``piv[2k + 1]``, in chain order (the point's columns are 12 + 2k, 12 + 2k + 1). A point
    owns the length row of the segment it ends and its y row, or, as a slide's P⁺, that slide's row and its
    x(P⁺) − x(P⁻) row; the last point (P⁻ at C) owns the last segment's length row and the slide at C. Every row
    then reaches only its point and the two next to it (its segment's start, a slide's P⁻ and its child's end;
    checked for every chain the configuration allows by ``tests/test_structure_reference.py``). False if a
    point does not own exactly two rows."""
    nseg, nsl = segs.shape[0], slides.shape[0]
    nc = piv.shape[0]
    for i in range(nc):
        piv[i] = -1
    for r in range(nc):
        if r < nseg:
            owner = segs[r, 1]
        elif r < nseg + nsl:
            k = r - nseg
            owner = slides[k, 1] if slides[k, 1] >= N_Q else slides[k, 0]
        else:
            owner = indep[r - nseg - nsl, 1]
        b = owner - N_Q
        if b < 0 or b >= nc or b % 2 != 0:
            return False
        if piv[b] < 0:
            piv[b] = r
        elif piv[b + 1] < 0:
            piv[b + 1] = r
        else:
            return False
    for i in range(nc):
        if piv[i] < 0:
            return False
    return True


@njit(cache=True)
def bt_factor(A, piv, LU):
    """Block LU (2 × 2 blocks, no pivoting between blocks) of the chain block of A in the order of
    :func:`chain_order` (``piv``): per point k, E_k⁻¹ into ``LU[2k:2k+2, 0:2]``, G_k = L_k E_{k−1}⁻¹ into
    ``[2k:2k+2, 2:4]``, the upper block U_k into ``[2k:2k+2, 4:6]`` (E_k = D_k − G_k U_{k−1}, D, L, U the
    diagonal, lower and upper blocks). The diagonal blocks dominate (a length row's 2l along the rod and a y row,
    or a slide's l across it and an x row); the upper blocks are a slide's stretch, ~0. False if a block is
    singular."""
    nc = A.shape[0]
    nb = nc // 2
    for k in range(nb):
        r0, r1 = piv[2 * k], piv[2 * k + 1]
        c = N_Q + 2 * k
        d00, d01, d10, d11 = A[r0, c], A[r0, c + 1], A[r1, c], A[r1, c + 1]
        i0 = 2 * k
        if k > 0:
            l00, l01, l10, l11 = A[r0, c - 2], A[r0, c - 1], A[r1, c - 2], A[r1, c - 1]
            e00, e01, e10, e11 = LU[i0 - 2, 0], LU[i0 - 2, 1], LU[i0 - 1, 0], LU[i0 - 1, 1]
            g00, g01 = l00 * e00 + l01 * e10, l00 * e01 + l01 * e11
            g10, g11 = l10 * e00 + l11 * e10, l10 * e01 + l11 * e11
            LU[i0, 2], LU[i0, 3], LU[i0 + 1, 2], LU[i0 + 1, 3] = g00, g01, g10, g11
            u00, u01, u10, u11 = LU[i0 - 2, 4], LU[i0 - 2, 5], LU[i0 - 1, 4], LU[i0 - 1, 5]
            d00 -= g00 * u00 + g01 * u10
            d01 -= g00 * u01 + g01 * u11
            d10 -= g10 * u00 + g11 * u10
            d11 -= g10 * u01 + g11 * u11
        if k < nb - 1:
            LU[i0, 4], LU[i0, 5] = A[r0, c + 2], A[r0, c + 3]
            LU[i0 + 1, 4], LU[i0 + 1, 5] = A[r1, c + 2], A[r1, c + 3]
        else:
            LU[i0, 4] = LU[i0, 5] = LU[i0 + 1, 4] = LU[i0 + 1, 5] = 0.0
        det = d00 * d11 - d01 * d10
        if not (det != 0.0 and math.isfinite(det)):
            return False
        LU[i0, 0], LU[i0, 1], LU[i0 + 1, 0], LU[i0 + 1, 1] = d11 / det, -d01 / det, -d10 / det, d00 / det
    return True


@njit(cache=True)
def bt_solve(LU, piv, nc, b, x):
    """Solve the chain block with :func:`bt_factor`'s factors: ``b`` indexed by the chain's rows, the solution
    into ``x`` indexed by its columns (b is not changed)."""
    nb = nc // 2
    for k in range(nb):   # forward: y_k = b_k − G_k y_{k−1} (into x)
        i0 = 2 * k
        y0, y1 = b[piv[i0]], b[piv[i0 + 1]]
        if k > 0:
            y0 -= LU[i0, 2] * x[i0 - 2] + LU[i0, 3] * x[i0 - 1]
            y1 -= LU[i0 + 1, 2] * x[i0 - 2] + LU[i0 + 1, 3] * x[i0 - 1]
        x[i0], x[i0 + 1] = y0, y1
    for k in range(nb - 1, -1, -1):   # backward: x_k = E_k⁻¹ (y_k − U_k x_{k+1})
        i0 = 2 * k
        y0, y1 = x[i0], x[i0 + 1]
        if k < nb - 1:
            y0 -= LU[i0, 4] * x[i0 + 2] + LU[i0, 5] * x[i0 + 3]
            y1 -= LU[i0 + 1, 4] * x[i0 + 2] + LU[i0 + 1, 5] * x[i0 + 3]
        x[i0] = LU[i0, 0] * y0 + LU[i0, 1] * y1
        x[i0 + 1] = LU[i0 + 1, 0] * y0 + LU[i0 + 1, 1] * y1


@njit(cache=True)
def flex_solve(q, s, c, A, LU, piv, b, out, tmp):
    """Solve the whole augmented system for v: the rigid twelve in closed form, then the chain block (A holds
    the chain's rows over all coordinates, LU/piv the block factors of its chain columns, :func:`factor`)."""
    nc = A.shape[0]
    rigid = False
    for k in range(N_Q):
        if b[k] != 0.0:
            rigid = True
            break
    if rigid:
        solve_aug(q, s, c, b, out)
        for r in range(nc):   # the chain's rows reach the rigid coordinates through B' and C only (q_2 … q_5)
            tmp[r] = b[N_Q + r] - A[r, 2] * out[2] - A[r, 3] * out[3] - A[r, 4] * out[4] - A[r, 5] * out[5]
    else:   # a chain-only right-hand side (the chain's independent columns of R): the rigid block's answer is 0
        for k in range(N_Q):
            out[k] = 0.0
        for r in range(nc):
            tmp[r] = b[N_Q + r]
    bt_solve(LU, piv, nc, tmp, out[N_Q:])


@njit(cache=True)
def factor(q, segs, slides, indep, A, LU, piv):
    """Chain rows at q into A and the block-tridiagonal LU of their chain columns into LU (:func:`bt_factor`, the
    rows' order in ``piv``, :func:`chain_order`); False if singular."""
    chain_jacobian(q, segs, slides, indep, A)
    if not chain_order(segs, slides, indep, piv):
        return False
    return bt_factor(A, piv, LU)


@njit(cache=True)
def flex_mass_times(P, segs, seg_f, G, v, out):
    """out = M v: the rigid model's blocks (the rod as its two end masses), the segments' bars, the supports."""
    mass_times(P, v[:N_Q], out[:N_Q])
    for i in range(N_Q, v.shape[0]):
        out[i] = 0.0
    if G[G_FLEX_A] > 0.5:
        out[8] += G[G_MF] * v[8]
        out[9] += G[G_MF] * v[9]
    if G[G_FLEX_G] > 0.5:
        out[10] += G[G_MG] * v[10]
    for j in range(segs.shape[0]):
        a, b = segs[j, 0], segs[j, 1]
        m3, m6 = seg_f[j, 0] / 3.0, seg_f[j, 0] / 6.0
        for d in range(2):
            out[a + d] += m3 * v[a + d] + m6 * v[b + d]
            out[b + d] += m6 * v[a + d] + m3 * v[b + d]


@njit(cache=True)
def _seg_angle_rate(q, qd, a, b):
    ux, uy = q[b] - q[a], q[b + 1] - q[a + 1]
    vx, vy = qd[b] - qd[a], qd[b + 1] - qd[a + 1]
    return ux, uy, _cross(ux, uy, vx, vy) / (ux * ux + uy * uy)


@njit(cache=True)
def _moment(q, a, b, m, Q):
    """A moment m about z on the bar a→b as the force pair ±m R₉₀u/|u|² on b and a."""
    ux, uy = q[b] - q[a], q[b + 1] - q[a + 1]
    f = m / (ux * ux + uy * uy)
    Q[b] += -uy * f
    Q[b + 1] += ux * f
    Q[a] -= -uy * f
    Q[a + 1] -= ux * f


@njit(cache=True)
def _eye_contact(P, qs, q, jo, fn0, ft0, eye, rb, a, b, Q):
    """Move a clearance joint's contact force on the rod from the rigid rod's distribution over B' and C
    (:func:`twin.reference.model._rod_force`, which the joint's element applied with the forces ``fn0``, ``ft0``) to
    the eye it acts on: the force of ``jo`` (f_N, f_T: the element's, or the damping-bounded ones of
    :func:`_bound_damping`) at the eye's centre (index ``eye``: 2 for B', 4 for C) and its moment about it,
    −R_b f_T, on the end segment a→b (the housing turns with it)."""
    ex, ey = jo[0], jo[1]
    d = math.sqrt(ex * ex + ey * ey)
    if d > 0.0:
        nx, ny = ex / d, ey / d
    else:
        nx, ny = 1.0, 0.0
    fx = -fn0 * nx - ft0 * ny      # on the pin: −f_N n + f_T t, t = (−n_y, n_x)
    fy = -fn0 * ny + ft0 * nx
    _rod_force(P, qs, fx, fy, qs[eye] + rb * nx, qs[eye + 1] + rb * ny, Q)   # undoes the element's −F
    fx = -jo[3] * nx - jo[4] * ny
    fy = -jo[3] * ny + jo[4] * nx
    Q[eye] -= fx
    Q[eye + 1] -= fy
    _moment(q, a, b, -rb * jo[4], Q)


@njit(cache=True)
def _bound_damping(P, qs, qds, pin_b, cst, jo, mob, h, w_eye, Q, fc):
    """The contact law and friction of clearance joint B (``pin_b``) or C on the flexible rod: the element of the
    rigid model (:func:`twin.reference.model._joint`) evaluated them for a rigid rod; two things differ here.

    * The eye's spin: the bore turns with its housing, which turns with the rod's end segment (no hinge at the
      rod's end nodes), at ``w_eye`` [rad/s] (:func:`_seg_angle_rate` of the end segment), not with the chord
      B'–C as the element assumes; the friction's sliding speed takes it (as the MuJoCo engine's native module,
      which reads the housing body's own velocity).
    * The law's damping is bounded at the dead-beat value m̂/(2h) (m̂ = 1/``mob``, :func:`normal_mobility`; h the
      step), as the MuJoCo engine's force source does: the law's damping c (its force at unit approach rate less
      its elastic force) beyond m̂/(2h) is scaled to it — the law evaluated at the rate δ̇ m̂/(2 h c). An explicit
      damping c acting on the mass m̂ decays the rate by 1 − c h/m̂ per step: beyond 2m̂/h it diverges, beyond
      m̂/h it alternates (the step's Nyquist ringing); at m̂/(2h) the rate halves each step.

    The friction is evaluated from the (possibly bounded) normal force and that sliding speed. The element's forces
    (``jo`` [3:5], which it applied to ``Q`` on both bodies) are replaced in ``jo`` and on the pin's side of ``Q``
    (the crank, or the slider); the rod's side is :func:`_eye_contact`'s. Returns the element's (f_N, f_T). ``fc``
    (3): the law's elastic force and damping coefficient (F_e, c) with fc[2] = 1 where evaluated here, else 0 (for
    :func:`law_terms`, the same numbers at the same state)."""
    fn0, ft0 = jo[3], jo[4]
    delta = jo[2]
    fc[2] = 0.0
    if not delta > 0.0:
        return fn0, ft0
    if pin_b:
        edx, edy = qds[0] - qds[2], qds[1] - qds[3]
        K, clin, rb = P[P_K_B], P[P_CLIN_B], P[P_RBUSH_B]
    else:
        edx = qds[6] - qds[4]
        edy = (qds[10] - qds[5]) if P[P_CLR_G] > 0.5 else -qds[5]
        K, clin, rb = P[P_K_C], P[P_CLIN_C], P[P_RBUSH_C]
    ex, ey = jo[0], jo[1]
    d = math.sqrt(ex * ex + ey * ey)
    nx, ny = (ex / d, ey / d) if d > 0.0 else (1.0, 0.0)
    fn = fn0
    if mob > 0.0:
        code = int(P[P_LAW])
        fe = normal_force(code, delta, 0.0, cst[1], K, P[P_N], P[P_E], clin, P[P_DMAX])
        c = normal_force(code, delta, 1.0, cst[1], K, P[P_N], P[P_E], clin, P[P_DMAX]) - fe
        fc[0], fc[1], fc[2] = fe, c, 1.0
        cmax = 0.5 / (h * mob)
        if c > cmax:
            rate = (nx * edx + ny * edy) * (cmax / c)
            fn = normal_force(code, delta, rate, cst[1], K, P[P_N], P[P_E], clin, P[P_DMAX])
    tx, ty = -ny, nx
    vt = edx * tx + edy * ty - w_eye * rb
    if pin_b:
        vt += qds[7] * P[P_RPIN_B]
    if fn <= 0.0:
        ft = 0.0
    elif P[P_FRIC_LAW] > 0.5:
        ft = adams_friction_force(vt, fn, P[P_MUS], P[P_MU0], P[P_VS], P[P_VD])
    else:
        ft = friction_force(vt, fn, P[P_MU0], P[P_V0], P[P_V1])
    if fn == fn0 and ft == ft0:
        return fn0, ft0
    dfx = -(fn - fn0) * nx + (ft - ft0) * tx   # the change of the force on the pin
    dfy = -(fn - fn0) * ny + (ft - ft0) * ty
    if pin_b:
        pcx, pcy = qs[0] - qs[8] + P[P_RPIN_B] * nx, qs[1] - qs[9] + P[P_RPIN_B] * ny
        Q[7] += pcx * dfy - pcy * dfx
        Q[8] += dfx
        Q[9] += dfy
    else:
        Q[6] += dfx
        if P[P_CLR_G] > 0.5:
            Q[10] += dfy
    jo[3] = fn
    jo[4] = ft
    return fn0, ft0


@njit(cache=True)
def law_terms(P, qs, qds, pin_b, cst, jo, out, fc):
    """The contact law of clearance joint B (``pin_b``) or C at the step's state, for :func:`theta_damping`:
    ``out`` = [F_e, c, δ̇, b, n_x, n_y] with the law's force F_e + c δ̇ (F_e its elastic part, c its damping
    coefficient, both 0 out of contact; in the clamped branch of a hysteresis law c = 0), δ̇ the approach rate and
    b = |ė_⊥|²/|e| the part of δ̈ that the pin's sliding along the bore's curve adds to n·ë. ``fc``: F_e and c as
    :func:`_bound_damping` evaluated them at this state (fc[2] = 1), else evaluated here."""
    for i in range(6):
        out[i] = 0.0
    delta = jo[2]
    if not delta > 0.0:
        return
    if pin_b:
        edx, edy = qds[0] - qds[2], qds[1] - qds[3]
        K, clin = P[P_K_B], P[P_CLIN_B]
    else:
        edx = qds[6] - qds[4]
        edy = (qds[10] - qds[5]) if P[P_CLR_G] > 0.5 else -qds[5]
        K, clin = P[P_K_C], P[P_CLIN_C]
    ex, ey = jo[0], jo[1]
    d = math.sqrt(ex * ex + ey * ey)
    if not d > 0.0:
        return
    nx, ny = ex / d, ey / d
    rate = nx * edx + ny * edy
    code = int(P[P_LAW])
    if fc[2] > 0.5:   # the same law, arguments and state as _bound_damping's: the same numbers
        fe, c = fc[0], fc[1]
    else:
        fe = normal_force(code, delta, 0.0, cst[1], K, P[P_N], P[P_E], clin, P[P_DMAX])
        c = normal_force(code, delta, 1.0, cst[1], K, P[P_N], P[P_E], clin, P[P_DMAX]) - fe
    f1 = normal_force(code, delta, rate, cst[1], K, P[P_N], P[P_E], clin, P[P_DMAX])
    if c > 0.0 and abs(f1 - (fe + c * rate)) > 1e-9 * (abs(f1) + abs(fe) + 1e-300):   # clamped: no rate term
        fe, c = f1, 0.0
    vt = -ny * edx + nx * edy
    out[0], out[1], out[2], out[3], out[4], out[5] = fe, c, rate, vt * vt / d, nx, ny


@njit(cache=True)
def theta_forces(h, Wm, act, f0, lawB, lawC, an, dl):
    """The contact laws' normal forces at B and C by the θ-method, given the pairs' 2 × 2 mobility matrix ``Wm``
    [1/kg] (rows of inactive pairs unused), which pairs act (``act``), the explicit forces ``f0`` [N], the laws'
    terms (:func:`law_terms`) and the normal separation accelerations ``an`` [m/s²] the explicit forces give:
    f = F_e + c [(1 − θ) δ̇ + θ δ̇_end], θ = ½ while c h ≤ 2 m̂ and 1 − m̂/(c h) beyond (m̂ = 1/W_aa), both pairs
    solved together; a pulling force leaves its pair inactive (f = 0) and the other is solved with that known.
    Writes the forces' change into ``dl`` (2). Shared by the step's sparse form
    (:func:`twin.reference.flexible_kkt.kkt_theta_damping`) and its R-matrix check."""
    A = np.zeros((2, 2))
    r = np.zeros(2)
    for a in range(2):
        if not act[a]:
            A[a, a] = 1.0
            continue
        lw = lawB if a == 0 else lawC
        fe, c, rate, bb = lw[0], lw[1], lw[2], lw[3]
        ch = c * h
        mhat = 1.0 / Wm[a, a] if Wm[a, a] > 0.0 else 0.0
        theta = 0.5 if ch <= 2.0 * mhat else 1.0 - mhat / ch
        # f = fe + c rate + θ c h (an + bb − Σ_b W_ab (f_b − f0_b)): unknowns Δ_b = f_b − f0_b
        r[a] = fe + c * rate + theta * ch * (an[a] + bb) - f0[a]
        A[a, a] = 1.0
        for b in range(2):
            if act[b]:
                A[a, b] += theta * ch * Wm[a, b]
    det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    dl[0] = (r[0] * A[1, 1] - A[0, 1] * r[1]) / det
    dl[1] = (A[0, 0] * r[1] - A[1, 0] * r[0]) / det
    for a in range(2):
        if act[a] and f0[a] + dl[a] < 0.0:
            o = 1 - a
            dl[a] = -f0[a]
            if act[o]:
                dl[o] = (r[o] - A[o, a] * dl[a]) / A[o, o]
                if f0[o] + dl[o] < 0.0:
                    dl[o] = -f0[o]
            break


@njit(cache=True)
def chain_forces(P, q, qd, segs, seg_f, hinges, hinge_f, slides, slide_f, G, Q):
    """Add the chain's gravity, hinges and slides and the supports' springs, dampers and weights to Q; returns the
    power the dampers dissipate [W] (≥ 0)."""
    gx, gy = P[P_GX], P[P_GY]
    for j in range(segs.shape[0]):
        a, b = segs[j, 0], segs[j, 1]
        w = 0.5 * seg_f[j, 0]
        Q[a] += w * gx
        Q[a + 1] += w * gy
        Q[b] += w * gx
        Q[b + 1] += w * gy
    diss = 0.0
    for k in range(hinges.shape[0]):
        i0, i1 = hinges[k, 0], hinges[k, 1]
        a0, b0, a1, b1 = segs[i0, 0], segs[i0, 1], segs[i1, 0], segs[i1, 1]
        u0x, u0y, w0 = _seg_angle_rate(q, qd, a0, b0)
        u1x, u1y, w1 = _seg_angle_rate(q, qd, a1, b1)
        delta = math.atan2(_cross(u0x, u0y, u1x, u1y), u0x * u1x + u0y * u1y)
        rate = w1 - w0
        m = -hinge_f[k, 0] * delta - hinge_f[k, 1] * rate
        diss += hinge_f[k, 1] * rate * rate
        _moment(q, a1, b1, m, Q)
        _moment(q, a0, b0, -m, Q)
    for k in range(slides.shape[0]):
        p, c, s = slides[k, 0], slides[k, 1], slides[k, 2]
        a, b = segs[s, 0], segs[s, 1]
        wx, wy = q[b] - q[a], q[b + 1] - q[a + 1]
        wn = math.sqrt(wx * wx + wy * wy)
        ex, ey = wx / wn, wy / wn
        d = (q[c] - q[p]) * ex + (q[c + 1] - q[p + 1]) * ey
        dd = (qd[c] - qd[p]) * ex + (qd[c + 1] - qd[p + 1]) * ey
        f = -slide_f[k, 0] * d - slide_f[k, 1] * dd
        diss += slide_f[k, 1] * dd * dd
        Q[c] += f * ex
        Q[c + 1] += f * ey
        Q[p] -= f * ex
        Q[p + 1] -= f * ey
    return support_forces(P, q, qd, G, Q, diss)


@njit(cache=True)
def support_forces(P, q, qd, G, Q, diss):
    """Add the supports' springs, dampers and weights to Q (the frame at A' = (q_8, q_9), the guide's y_g = q_10);
    returns ``diss`` plus the power their dampers dissipate [W]. Shared by the chain and the modal rod."""
    gx, gy = P[P_GX], P[P_GY]
    if G[G_FLEX_A] > 0.5:   # the frame's spring and damper, and the frame's own weight (its mass moves with A')
        for i in (8, 9):
            Q[i] += -G[G_KF] * q[i] - G[G_CF] * qd[i]
            diss += G[G_CF] * qd[i] * qd[i]
        Q[8] += G[G_MF] * gx
        Q[9] += G[G_MF] * gy
    if G[G_FLEX_G] > 0.5:
        Q[10] += -G[G_KG] * q[10] - G[G_CG] * qd[10] + (P[P_M3] + G[G_MG]) * gy
        diss += G[G_CG] * qd[10] * qd[10]
    return diss


@njit(cache=True)
def support_energy(P, q, G, V):
    """``V`` plus the supports' springs' energy and their (and the guide-borne slider's) weight's [J]."""
    gx, gy = P[P_GX], P[P_GY]
    if G[G_FLEX_A] > 0.5:
        V += 0.5 * G[G_KF] * (q[8] * q[8] + q[9] * q[9]) - G[G_MF] * (gx * q[8] + gy * q[9])
    if G[G_FLEX_G] > 0.5:
        V += 0.5 * G[G_KG] * q[10] * q[10] - (P[P_M3] + G[G_MG]) * gy * q[10]
    return V


@njit(cache=True)
def flex_energy(P, q, qd, segs, seg_f, hinges, hinge_f, slides, slide_f, G):
    """(T, V) [J]: kinetic energy (all masses) and potential (gravity as the rigid model's, the segments, the
    supports' springs with the guide's weight, the hinges and slides)."""
    n = q.shape[0]
    mv = np.empty(n)
    flex_mass_times(P, segs, seg_f, G, qd, mv)
    T = 0.0
    for i in range(n):
        T += 0.5 * qd[i] * mv[i]
    V = energy(P, q[:N_Q], qd[:N_Q]) - kinetic_energy(P, q[:N_Q], qd[:N_Q])
    gx, gy = P[P_GX], P[P_GY]
    for j in range(segs.shape[0]):
        a, b = segs[j, 0], segs[j, 1]
        w = 0.5 * seg_f[j, 0]
        V -= w * (gx * (q[a] + q[b]) + gy * (q[a + 1] + q[b + 1]))
    for k in range(hinges.shape[0]):
        i0, i1 = hinges[k, 0], hinges[k, 1]
        a0, b0, a1, b1 = segs[i0, 0], segs[i0, 1], segs[i1, 0], segs[i1, 1]
        u0x, u0y = q[b0] - q[a0], q[b0 + 1] - q[a0 + 1]
        u1x, u1y = q[b1] - q[a1], q[b1 + 1] - q[a1 + 1]
        delta = math.atan2(_cross(u0x, u0y, u1x, u1y), u0x * u1x + u0y * u1y)
        V += 0.5 * hinge_f[k, 0] * delta * delta
    for k in range(slides.shape[0]):
        p, c, s = slides[k, 0], slides[k, 1], slides[k, 2]
        a, b = segs[s, 0], segs[s, 1]
        wx, wy = q[b] - q[a], q[b + 1] - q[a + 1]
        wn = math.sqrt(wx * wx + wy * wy)
        d = ((q[c] - q[p]) * wx + (q[c + 1] - q[p + 1]) * wy) / wn
        V += 0.5 * slide_f[k, 0] * d * d
    return T, support_energy(P, q, G, V)


@njit(cache=True)
def _independent_values(P, G, q, qd, segs, slides, indep, b):
    """Right-hand side of the velocity projection: the independent coordinates' rates from q̇."""
    n = q.shape[0]
    for i in range(n):
        b[i] = 0.0
    b[7] = qd[7]
    if P[P_CLR_B] > 0.5:
        b[3] = qd[0] - qd[2]
        b[4] = qd[1] - qd[3]
    if P[P_CLR_C] > 0.5:
        b[5] = qd[6] - qd[4]
        b[6] = qd[10] - qd[5]
    b[2] = 2.0 * ((q[4] - q[2]) * (qd[4] - qd[2]) + (q[5] - q[3]) * (qd[5] - qd[3]))
    if G[G_FLEX_A] > 0.5:
        b[8] = qd[8]
        b[9] = qd[9]
    if G[G_FLEX_G] > 0.5:
        b[10] = qd[10]
    r0 = N_Q + segs.shape[0] + slides.shape[0]
    for k in range(indep.shape[0]):
        if indep[k, 0] == 0:
            b[r0 + k] = qd[indep[k, 1] + 1]
        else:
            b[r0 + k] = qd[indep[k, 1]] - qd[indep[k, 2]]


@njit(cache=True)
def rigid_residual(P, G, q, s, c, res):
    """The rigid model's constraint residuals into ``res[:12]`` with the flexible structure's independent rows 0: the
    rod's length (its stretch), the frame's A' and the guide's y_g; the ideal joint C on the moving guide: C' at
    d_off + y_g. Shared by the chain's and the modal rod's projections."""
    residual(P, q[:N_Q], s, c, res[:N_Q])
    res[2] = 0.0
    if G[G_FLEX_A] > 0.5:
        res[8] = 0.0
        res[9] = 0.0
    if G[G_FLEX_G] > 0.5:
        res[10] = 0.0
        if P[P_CLR_C] < 0.5:
            res[6] = P[P_DOFF] + q[10] - q[5]


@njit(cache=True)
def flex_project(P, G, q, qd, segs, seg_f, slides, indep, A, LU, piv, res, dq, b, tmp, held):
    """Newton on the constraints with the independent coordinates held, then q̇ ← R ż (as the rigid
    :func:`twin.natural_coordinates.project`). On return A, LU and piv hold the chain's rows and their factors at the
    final q. ``held``: the Newton iteration starts from the factors A, LU, piv already hold (:func:`factor` at the
    previous step's final q, an h q̇ away: the stepping loop's projection, which factors once per step instead of
    twice); else it factors at the given q first. Returns the iterations, −1 if no convergence."""
    n = q.shape[0]
    nc = A.shape[0]
    tol = P[P_NEWTON_TOL]
    maxit = int(P[P_NEWTON_MAXIT])
    it = 0
    conv = False
    # modified Newton: the chain block factored once, at the predicted q or (held) at the previous step's final q
    # (a step moves it by h q̇, so the iteration contracts by ~|ΔA|/|A| per pass); the velocity projection below
    # refactors at the final q
    if not held and not factor(q, segs, slides, indep, A, LU, piv):
        return -1
    lim = maxit
    while it < lim:
        s, c = math.sin(q[7]), math.cos(q[7])
        rigid_residual(P, G, q, s, c, res)
        chain_residual(q, segs, seg_f, slides, res[N_Q:])
        for i in range(n):
            res[i] = -res[i]
        flex_solve(q, s, c, A, LU, piv, res, dq, tmp)
        big = 0.0
        for i in range(n):
            q[i] += dq[i]
            if abs(dq[i]) > big:
                big = abs(dq[i])
        it += 1
        if big <= tol:
            conv = True
            break
        if held and it == maxit and lim == maxit:   # the held factors did not contract: factor here, go on
            if not factor(q, segs, slides, indep, A, LU, piv):
                return -1
            lim += maxit
    if not conv:
        return -1
    s, c = math.sin(q[7]), math.cos(q[7])
    if held:   # the rows' order (piv) is the chain's topology, set by the factor the held factors came from
        chain_jacobian(q, segs, slides, indep, A)
        if not bt_factor(A, piv, LU):
            return -1
    elif not factor(q, segs, slides, indep, A, LU, piv):
        return -1
    _independent_values(P, G, q, qd, segs, slides, indep, b)
    flex_solve(q, s, c, A, LU, piv, b, dq, tmp)
    for i in range(n):
        qd[i] = dq[i]
    return it


@njit(cache=True)
def _rod_sensors(P, q, qdd, segs, sens, row):
    """Overwrite the rod's accelerometers of the output row with their segment's reading."""
    gx, gy = P[P_GX], P[P_GY]
    for i in range(6):
        seg = int(sens[i, 0])
        if seg < 0:
            continue
        a, b = segs[seg, 0], segs[seg, 1]
        ux, uy = q[b] - q[a], q[b + 1] - q[a + 1]
        ln = math.sqrt(ux * ux + uy * uy)
        hx, hy = ux / ln, uy / ln
        xi, eta = sens[i, 1] / ln, sens[i, 2] / ln
        uax, uay = qdd[b] - qdd[a], qdd[b + 1] - qdd[a + 1]
        ax = qdd[a] + xi * uax - eta * uay - gx
        ay = qdd[a + 1] + xi * uay + eta * uax - gy
        axis = int(sens[i, 3])
        v = ax * hx + ay * hy if axis < 2 else -ax * hy + ay * hx
        if axis == 1 or axis == 3:
            v = -v
        row[O_ACC + i] = v


@njit(cache=True)
def _slider_sensors(P, qdd, sens, row):
    """The slider's accelerometers with the guide rails moving normal to the guide (y_g)."""
    gx, gy = P[P_GX], P[P_GY]
    for i in range(6):
        base = P_SENS + 4 * i
        if P[base] < 0.5:
            continue
        axis = int(P[base + 3])
        v = (qdd[6] - gx) if axis < 2 else (qdd[10] - gy)
        if axis == 1 or axis == 3:
            v = -v
        row[O_ACC + i] = v


def support_table(st, mid_seg: float, mid_xi: float) -> np.ndarray:
    """The supports' parameters ``G`` (G_* indices) of ``st`` (:class:`twin.config.structure.StructureConfig`), with
    the rod's mid-span point (its segment and the distance from its start; the modal rod: −1 and ξ = ½)."""
    G = np.zeros(N_G)
    G[G_MID_SEG] = mid_seg
    G[G_MID_XI] = mid_xi
    G[G_FLEX_A] = G[G_FLEX_G] = 1.0
    G[G_MF] = st.frame_mass_kg
    G[G_KF] = st.support_stiffness(st.frame_mass_kg, st.frame_frequency_hz)
    G[G_CF] = st.support_damping(st.frame_mass_kg, st.frame_frequency_hz, st.frame_damping_ratio)
    G[G_MG] = st.guide_mass_kg
    G[G_KG] = st.support_stiffness(st.guide_mass_kg, st.guide_frequency_hz)
    G[G_CG] = st.support_damping(st.guide_mass_kg, st.guide_frequency_hz, st.guide_damping_ratio)
    return G
