"""The flexible structure's reduced mass matrix and accelerations on the R-matrix formulation (R ᵀ M R z̈ =
Rᵀ (Q − M Ṙ ż)), the clearance joints' normal mobility on it and the contact damping's θ-method: the dense
algebra the reference's flexible step used before :mod:`twin.reference.flexible_kkt`, kept as that solve's
independent check (``tests/test_structure_reference.py`` compares the two on random states). Not called by the
stepping loop."""

from __future__ import annotations

import math

import numpy as np

from twin.jit import njit
from twin.natural_coordinates import N_Q, independent_rows, quadratic_terms, reduced_mass_into, solve_aug
from twin.reference.flexible_kernels import (G_FLEX_A, G_FLEX_G, bt_solve, chain_quadratic, flex_mass_times,
                                             theta_forces)
from twin.reference.model import _cholesky_solve


@njit(cache=True)
def _normal_rows(Rt, nz, prescribed, pin_x, pin_y, eye_x, eye_y, nx, ny, g):
    """g[j] = n·(R_pin − R_eye) over the independent coordinates (as :func:`normal_mobility`); returns their
    number m."""
    j0 = 1 if prescribed else 0
    m = nz - j0
    for j in range(m):
        r = Rt[j + j0]
        vy = r[pin_y] if pin_y >= 0 else 0.0
        g[j] = nx * (r[pin_x] - r[eye_x]) + ny * (vy - r[eye_y])
    return m


@njit(cache=True)
def normal_mobility(Rt, Mb, nz, prescribed, pin_x, pin_y, eye_x, eye_y, nx, ny, g, W):
    """1/m̂ [1/kg]: the relative normal acceleration of a clearance joint's pin (coordinates ``pin_x``, ``pin_y``;
    ``pin_y`` −1 if the pin cannot move along y) from its eye (``eye_x``, ``eye_y``) per newton of a contact force
    pair along n = (nx, ny): J R (Rᵀ M R)⁻¹ Rᵀ Jᵀ from :func:`flex_mass`'s Rᵀ and Rᵀ M R (with ``prescribed`` the
    crank angle, a driving constraint, does not move). m̂ is the flexible model's effective mass along the
    normal (the rod's light housing, the chain behind it, the crank or the slider). ``g``, ``W`` scratch."""
    j0 = 1 if prescribed else 0
    m = _normal_rows(Rt, nz, prescribed, pin_x, pin_y, eye_x, eye_y, nx, ny, g)
    for j in range(m):
        W[j, :m] = Mb[j + j0, j0:nz]
    y = g[m:2 * m]
    y[:] = g[:m]
    if not _cholesky_solve(W, y, m):
        return 0.0
    mob = 0.0
    for j in range(m):
        mob += g[j] * y[j]
    return mob


@njit(cache=True)
def theta_damping(h, qdd, Rt, Mb0, nz, prescribed, lawB, lawC, fB, fC, shift, jb, jc):
    """The contact laws' damping at B and C by the θ-method, as the MuJoCo engine's contact rows integrate it
    (``mujoco.contact_source = "law"``, ``_bore.c``): the normal force f = F_e + c [(1 − θ) δ̇ + θ δ̇_end], the
    elastic part explicit, δ̇_end = δ̇ + h δ̈ the rate at the step's end, θ = ½ (trapezoidal) while c h ≤ 2 m̂ and
    θ = 1 − m̂/(c h) beyond (m̂ the pair's effective mass along the normal), so the large damping of a resting
    contact needs no step limit. ``qdd`` holds the accelerations with the explicit normal forces ``fB``, ``fC``
    (0: not in contact) applied; the forces' change is solved with the pairs' mobilities (both joints together,
    the same Rᵀ M R ``Mb0``, unfactored) and its accelerations added to ``qdd``; jb[3], jc[3] take the forces.
    ``lawB``, ``lawC``: :func:`law_terms`. The friction keeps the explicit force's (MuJoCo's native friction is
    likewise a passive force evaluated before the solve). Returns the change of the drive torque with ``prescribed``
    (the driving constraint's multiplier, as :func:`flex_solve_acc` computes it), else 0."""
    j0 = 1 if prescribed else 0
    m = nz - j0
    act = np.zeros(2, dtype=np.bool_)
    act[0] = fB > 0.0 and lawB[1] > 0.0
    act[1] = fC > 0.0 and lawC[1] > 0.0
    if not (act[0] or act[1]):
        return 0.0
    g = np.zeros((2, m))
    if act[0]:
        _normal_rows(Rt, nz, prescribed, 0, 1, 2, 3, lawB[4], lawB[5], g[0])
    if act[1]:
        _normal_rows(Rt, nz, prescribed, 6, 10 if shift else -1, 4, 5, lawC[4], lawC[5], g[1])
    # Y = (Rᵀ M R)⁻¹ gᵀ, W = g Y (the 2 × 2 mobility matrix)
    W = np.empty((m, m))
    for i in range(m):
        for j in range(m):
            W[i, j] = Mb0[i + j0, j + j0]
    Y = np.zeros((2, m))
    for k in range(2):
        if act[k]:
            y = g[k].copy()
            Lk = W.copy()
            if not _cholesky_solve(Lk, y, m):
                return 0.0
            Y[k] = y
    Wm = np.zeros((2, 2))
    for a in range(2):
        for b in range(2):
            if act[a] and act[b]:
                acc = 0.0
                for j in range(m):
                    acc += g[a, j] * Y[b, j]
                Wm[a, b] = acc
    # the rows' accelerations now: a_n = n·ë (from qdd), then the forces (theta_forces)
    f0 = np.array([fB, fC])
    an = np.zeros(2)
    an[0] = lawB[4] * (qdd[0] - qdd[2]) + lawB[5] * (qdd[1] - qdd[3])
    an[1] = lawC[4] * (qdd[6] - qdd[4]) + lawC[5] * ((qdd[10] if shift else 0.0) - qdd[5])
    dl = np.zeros(2)
    theta_forces(h, Wm, act, f0, lawB, lawC, an, dl)
    n = qdd.shape[0]
    dtau = 0.0
    for a in range(2):
        if not act[a] or dl[a] == 0.0:
            continue
        for j in range(m):   # q̈ += −Δ R y: the separating pair (pin along −n, eye along +n)
            yj = Y[a, j] * dl[a]
            rj = Rt[j + j0]
            for i in range(n):
                qdd[i] -= rj[i] * yj
        if prescribed:   # τ = M_00 α − rhs_0 + Σ_j M_0j z̈_j with Δrhs = −g Δ and Δz̈ = −Y Δ
            r0 = Rt[0]
            lw = lawB if a == 0 else lawC
            if a == 0:
                g0 = lw[4] * (r0[0] - r0[2]) + lw[5] * (r0[1] - r0[3])
            else:
                g0 = lw[4] * (r0[6] - r0[4]) + lw[5] * ((r0[10] if shift else 0.0) - r0[5])
            t = g0
            for j in range(m):
                t -= Mb0[0, j + 1] * Y[a, j]
            dtau += t * dl[a]
    jb[3] = f0[0] + dl[0] if act[0] else jb[3]
    jc[3] = f0[1] + dl[1] if act[1] else jc[3]
    return dtau


@njit(cache=True)
def flex_rows(P, G, indep, rows):
    """Independent rows of the whole set: the rigid model's (θ and the clearance eccentricities), the rod's
    stretch (row 2), the supports (rows 8–9, 10) and the chain's independent rows; returns their number."""
    nz = independent_rows(P, rows)
    rows[nz] = 2
    nz += 1
    if G[G_FLEX_A] > 0.5:
        rows[nz] = 8
        rows[nz + 1] = 9
        nz += 2
    if G[G_FLEX_G] > 0.5:
        rows[nz] = 10
        nz += 1
    return nz


@njit(cache=True)
def flex_mass(P, G, q, qd, segs, seg_f, slides, A, LU, piv, rows, nz, Rt, S, Mb, MR, b, Bm, RtT):
    """The force-independent part of the accelerations q̈ = R z̈ + Ṙż (Rᵀ M R z̈ = Rᵀ (Q − M Ṙż), A already
    factored at q): Rᵀ (rows of R, the unit right-hand sides of the independent rows) into ``Rt`` and its
    transpose ``RtT``, M R into ``MR``, Ṙż into ``S`` and Rᵀ M R into ``Mb``. Each column as
    :func:`flex_solve` would give it (``Bm`` (n − 12) × (nz + 1) scratch). :func:`flex_solve_acc` completes the step with the forces."""
    n = q.shape[0]
    nc = A.shape[0]
    s, c = math.sin(q[7]), math.cos(q[7])
    for j in range(nz + 1):
        if j < nz:
            for i in range(n):
                b[i] = 0.0
            b[rows[j]] = 1.0
            out = Rt[j]
        else:
            quadratic_terms(q[:N_Q], qd[:N_Q], s, c, b[:N_Q])
            # (row 2, the stretch s = |C − B'|² − L², is an independent coordinate defined by a nonlinear
            # expression: its row keeps −Φ̇_q q̇ = −2|Ċ − Ḃ'|², as quadratic_terms writes it)
            chain_quadratic(qd, segs, slides, b[N_Q:])
            out = S
        rigid = False
        for k in range(N_Q):
            if b[k] != 0.0:
                rigid = True
                break
        if rigid:   # as flex_solve: the rigid block in closed form, its effect on the chain's rows
            solve_aug(q, s, c, b, out)
            for r in range(nc):
                Bm[r, j] = b[N_Q + r] - A[r, 2] * out[2] - A[r, 3] * out[3] - A[r, 4] * out[4] - A[r, 5] * out[5]
        else:
            for k in range(N_Q):
                out[k] = 0.0
            for r in range(nc):
                Bm[r, j] = b[N_Q + r]
    col = np.empty(nc)
    for j in range(nz + 1):
        for r in range(nc):
            col[r] = Bm[r, j]
        bt_solve(LU, piv, nc, col, Rt[j, N_Q:] if j < nz else S[N_Q:])
    for j in range(nz):
        flex_mass_times(P, segs, seg_f, G, Rt[j], MR[j])
    for k in range(n):
        for j in range(nz):
            RtT[k, j] = Rt[j, k]
    reduced_mass_into(Rt, MR, nz, n, Mb)


@njit(cache=True)
def flex_solve_acc(q, Q, nz, Rt, RtT, S, Mb, rhs, b, tmp, qdd, P, segs, seg_f, G, prescribed, alpha, tau):
    """The force-dependent part of the accelerations (after :func:`flex_mass`): z̈ from Rᵀ M R z̈ = Rᵀ (Q − M Ṙż),
    q̈ = R z̈ + Ṙż into ``qdd``; False if Rᵀ M R is not SPD. With ``prescribed`` the crank angle is a driving
    constraint (θ̈ = ``alpha``, the first independent coordinate): the other rows are solved with it known and the
    drive torque (its multiplier) written to ``tau[0]``, as :func:`twin.reference.model.accelerations_prescribed`.
    Mb is overwritten."""
    n = q.shape[0]
    flex_mass_times(P, segs, seg_f, G, S, tmp[:n])
    for i in range(n):
        b[i] = Q[i] - tmp[i]
    for j in range(nz):   # rhs[j] = Σ_k Rt[j, k] b[k], k ascending
        rhs[j] = 0.0
    for k in range(n):
        bk = b[k]
        for j in range(nz):
            rhs[j] += RtT[k, j] * bk
    if prescribed:
        m = nz - 1
        W = np.empty((m, m))
        rw = np.empty(m)
        for i in range(m):
            rw[i] = rhs[i + 1] - Mb[i + 1, 0] * alpha
            for j in range(m):
                W[i, j] = Mb[i + 1, j + 1]
        if not _cholesky_solve(W, rw, m):
            return False
        t = Mb[0, 0] * alpha - rhs[0]
        for j in range(m):
            t += Mb[0, j + 1] * rw[j]
        tau[0] = t
        rhs[0] = alpha
        for j in range(m):
            rhs[j + 1] = rw[j]
    elif not _cholesky_solve(Mb, rhs, nz):
        return False
    for i in range(n):   # qdd[i] = S[i] + Σ_j Rt[j, i] rhs[j], j ascending
        qdd[i] = S[i]
    for j in range(nz):
        rj = rhs[j]
        for i in range(n):
            qdd[i] += Rt[j, i] * rj
    return True
