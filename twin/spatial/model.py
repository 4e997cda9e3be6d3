"""The spatial reference model: natural coordinates, velocity transformation (R matrix), contact
force elements at the clearance joints, projected symplectic Euler; compiled with numba.

Coordinates q (15): the points A, B_c, B_r, C_r, C_s of :mod:`twin.spatial.geometry`, with a constant
mass matrix M. Constraints Φ(q, t) = 0 (rows, in this order):

* crank in the plane x = 0: A_x = 0, B_c,x = 0; crank length |B_c − A|² = r²;
* rod length |C_r − B_r|² = L²;
* slider on the guide: (C_s − p0)·e₁ = 0, (C_s − p0)·e₂ = 0 (e₁, e₂ ⟂ g);
* ideal base joint A: A_y = A_z = 0; ideal spherical joint B: B_r − B_c = 0; ideal C: C_r − C_s = 0;
* the prescribed drive (rheonomic): (B_c − A)·n(θ(t)) = 0 with n = (0, −sin θ, cos θ).

R-matrix (S003 Eq. 11–13 in 3D): q̇ = R ż + q̇ₚ with the columns of R a basis of the null space of
Φ_q (from its singular value decomposition, so any set of clearance joints needs no hand-written R),
q̈ = R z̈ + q̈ₚ with Φ_q q̈ₚ = γ (the minimum-norm particular solution, γ = −Φ̇_q q̇ − Φ_tt) and
Rᵀ M R z̈ = Rᵀ (Q − M q̈ₚ). ż are the independent velocities: the crank's (none with the drive), and
the relative motions the clearance joints free (two at A, three at B and C each).

Integration: symplectic Euler (S003 Eq. 21), then Newton projection of q onto Φ = 0 and of q̇ onto
Φ_q q̇ + Φ_t = 0 (:func:`_project`): coordinate-partitioned, keeping the independent coordinates (θ
without the drive, the clearance joints' relative positions) at their values after the step, as the
planar R-matrix model does; or mass-weighted (each body's centre of mass where the step put it). A
minimum-norm projection is neither: it moves the crank's free journal by the crank-length correction,
r ω² h²/4 per step, half its true acceleration at S002's speeds. The partitioned projection holds the
relative position of a clearance joint, so the crank's correction at B (its centripetal curvature,
r ω² h²/2 per step) also moves the rod's ball: an O(h) error of the rod's flight that the mass-weighted
projection does not make.

Forces Q: gravity; per clearance joint the contact law of :mod:`twin.physics.contact` on the
penetration δ = |e| − c (e = pin − bushing centre; A: the journal A in the bearing at the origin, radial
in the plane x = 0; B, C: ball on the rod minus socket centre, in 3D) with the regularized Coulomb
friction of S003 Eq. 19–20 opposing the tangential sliding velocity (A: of the journal's surface at the
contact point, the crank's rotation included; B, C: of the ball's centre relative to the socket's body
at that point, the rod's own rotation not included: the natural-coordinate rod has no spin), and the
slider guide's friction.
"""

from __future__ import annotations

import math

import numpy as np
from twin.jit import njit

from twin.physics.contact import friction_force, normal_force, ramp
from twin.spatial.geometry import IA, IBC, IBR, ICR, ICS, NQ

# parameter vector P
P_R, P_L = 0, 1
P_G = 2          # guide direction (3)
P_P0 = 5         # guide point (3)
P_E1, P_E2 = 8, 11   # guide normals (3 each)
P_DRIVE = 14     # 1: prescribed drive constraint
P_GUIDE_F = 15   # guide friction force [N]
P_V0, P_V1 = 16, 17
P_TOL, P_MAXIT = 18, 19
P_H = 20         # timestep [s]
P_PROJ = 21      # projection: 0 = coordinate-partitioned, 1 = mass-weighted
P_JOINT = 22     # per joint (A, B, C): 12 values
J_ON, J_C, J_K, J_N, J_E, J_LAW, J_CLIN, J_DMAX, J_R, J_MU, J_FLOOR = range(11)
J_SIZE = 12
N_P = P_JOINT + 3 * J_SIZE

# state vector
S_Q, S_V = 0, NQ
S_VIMP = 2 * NQ      # stored impact speeds (3)
S_INC = 2 * NQ + 3   # in-contact flags (3)
S_THETA = 2 * NQ + 6  # last unwrapped crank angle
N_STATE = 2 * NQ + 7

# outputs per sample
O_THETA, O_OMEGA, O_SLIDER, O_SLIDER_ACC, O_TORQUE = range(5)
O_JOINT = 5          # per joint: ex, ey, ez, pen, fn, ft
O_EKIN, O_EPOT, O_EEL = 23, 24, 25
N_OUT = 26

OK, NEWTON_FAILED, NOT_FINITE = 0, 1, 2
MAX_ROWS = 18


@njit(cache=True)
def _d3(a, i, j):
    return a[i] - a[j], a[i + 1] - a[j + 1], a[i + 2] - a[j + 2]


@njit(cache=True)
def constraints(P, jon, full, q, v, th, om, al, Phi, J, gam, phit, indep):
    """Fill Φ, Φ_q, γ = −Φ̇_q q̇ − Φ_tt and Φ_t at (q, q̇, θ, ω, α); returns the number of rows.

    ``full``: every joint's pair rows and the crank-angle row, whatever the joints and the drive (the
    square 15 × 15 system of the projection); ``indep[i]`` = 1 marks a row that is an independent
    coordinate there (a clearance joint's relative position, the crank angle without the drive)."""
    m = 0
    J[:, :] = 0.0
    indep[:] = 0
    # crank in the plane x = 0
    for idx in (IA, IBC):
        Phi[m] = q[idx]
        J[m, idx] = 1.0
        gam[m] = 0.0
        phit[m] = 0.0
        m += 1
    # lengths
    for (i, j, ell) in ((IA, IBC, P[P_R]), (IBR, ICR, P[P_L])):
        dx, dy, dz = q[j] - q[i], q[j + 1] - q[i + 1], q[j + 2] - q[i + 2]
        vx, vy, vz = v[j] - v[i], v[j + 1] - v[i + 1], v[j + 2] - v[i + 2]
        Phi[m] = dx * dx + dy * dy + dz * dz - ell * ell
        J[m, j], J[m, j + 1], J[m, j + 2] = 2 * dx, 2 * dy, 2 * dz
        J[m, i], J[m, i + 1], J[m, i + 2] = -2 * dx, -2 * dy, -2 * dz
        gam[m] = -2.0 * (vx * vx + vy * vy + vz * vz)
        phit[m] = 0.0
        m += 1
    # slider on the guide
    for e0 in (P_E1, P_E2):
        s = 0.0
        for k in range(3):
            s += (q[ICS + k] - P[P_P0 + k]) * P[e0 + k]
            J[m, ICS + k] = P[e0 + k]
        Phi[m] = s
        gam[m] = 0.0
        phit[m] = 0.0
        m += 1
    # joint pairs: rows of the ideal joints, independent coordinates of the clearance joints
    if jon[0] == 0 or full:
        for k in (1, 2):
            Phi[m] = q[IA + k]
            J[m, IA + k] = 1.0
            gam[m] = 0.0
            phit[m] = 0.0
            indep[m] = jon[0]
            m += 1
    for (jj, ip, ib) in ((1, IBR, IBC), (2, ICR, ICS)):
        if jon[jj] == 0 or full:
            for k in range(3):
                Phi[m] = q[ip + k] - q[ib + k]
                J[m, ip + k] = 1.0
                J[m, ib + k] = -1.0
                gam[m] = 0.0
                phit[m] = 0.0
                indep[m] = jon[jj]
                m += 1
    # crank angle: the prescribed drive (rheonomic), or the independent coordinate
    if P[P_DRIVE] > 0.5 or full:
        s, c = math.sin(th), math.cos(th)
        dy, dz = q[IBC + 1] - q[IA + 1], q[IBC + 2] - q[IA + 2]
        vy, vz = v[IBC + 1] - v[IA + 1], v[IBC + 2] - v[IA + 2]
        Phi[m] = -dy * s + dz * c
        J[m, IBC + 1], J[m, IBC + 2] = -s, c
        J[m, IA + 1], J[m, IA + 2] = s, -c
        dn1 = -dy * c - dz * s          # d·n'
        vn1 = -vy * c - vz * s          # ḋ·n'
        dn = -dy * s + dz * c           # d·n
        phit[m] = om * dn1
        gam[m] = -(2.0 * om * vn1 + al * dn1 - om * om * dn)
        indep[m] = 0 if P[P_DRIVE] > 0.5 else 1
        m += 1
    return m


@njit(cache=True)
def _project(P, jon, Minv, q, v, th, om, Phi, J, gam, phit, indep):
    """Project q onto Φ = 0 and q̇ onto Φ_q q̇ + Φ_t = 0 after a step; False if Newton fails.

    ``P[P_PROJ]`` = 0, coordinate-partitioned (as S003's R-matrix with independent coordinates): Newton
    on the square system of every constraint plus the independent coordinates (the clearance joints'
    relative positions, θ without the drive) held at their values after the step, so q moves only in
    the dependent directions. 1, mass-weighted: corrections M⁻¹Φ_qᵀ(Φ_q M⁻¹Φ_qᵀ)⁻¹ r, the smallest in
    kinetic-energy norm (each body's centre of mass stays where the step put it)."""
    tol = P[P_TOL]
    mass = P[P_PROJ] > 0.5
    if P[P_DRIVE] < 0.5:
        th = math.atan2(q[IBC + 2] - q[IA + 2], q[IBC + 1] - q[IA + 1])
        om = 0.0
    m = constraints(P, jon, not mass, q, v, th, om, 0.0, Phi, J, gam, phit, indep)
    target = np.zeros(m)
    for i in range(m):
        if indep[i] == 1:
            target[i] = Phi[i]
    ok = False
    for _ in range(int(P[P_MAXIT])):
        m = constraints(P, jon, not mass, q, v, th, om, 0.0, Phi, J, gam, phit, indep)
        if mass:
            Jm = np.ascontiguousarray(J[:m])
            W = Minv @ Jm.T
            dq = W @ np.linalg.solve(Jm @ W, Phi[:m])
        else:
            dq = np.linalg.solve(J[:m], Phi[:m] - target)
        q -= dq
        if np.max(np.abs(dq)) <= tol:
            ok = True
            break
    m = constraints(P, jon, not mass, q, v, th, om, 0.0, Phi, J, gam, phit, indep)
    r = J[:m] @ v + phit[:m]
    if mass:
        Jm = np.ascontiguousarray(J[:m])
        W = Minv @ Jm.T
        v -= W @ np.linalg.solve(Jm @ W, r)
    else:
        for i in range(m):
            if indep[i] == 1:
                r[i] = 0.0
        v -= np.linalg.solve(J[:m], r)
    return ok


@njit(cache=True)
def forces(P, jon, Qg, q, v, st, Q, jout):
    """Generalized forces Q at (q, q̇) [N]; updates the contact events in ``st``; writes per joint
    (ex, ey, ez, pen, fn, |ft|) into ``jout`` (3 × 6) and returns the contacts' elastic energy [J]."""
    for k in range(NQ):
        Q[k] = Qg[k]
    eel = 0.0
    # crank rotation about x (its plane is x = 0)
    dy, dz = q[IBC + 1] - q[IA + 1], q[IBC + 2] - q[IA + 2]
    vy, vz = v[IBC + 1] - v[IA + 1], v[IBC + 2] - v[IA + 2]
    d2 = dy * dy + dz * dz
    wx = (dy * vz - dz * vy) / d2
    # x̂ × d / |d|²: generalized direction of a torque about x on the crank
    ty, tz = -dz / d2, dy / d2
    for jj in range(3):
        for k in range(6):
            jout[jj, k] = 0.0
        if jon[jj] == 0:
            continue
        b = P_JOINT + jj * J_SIZE
        if jj == 0:
            ip, ib = IA, -1
            ex, ey, ez = 0.0, q[IA + 1], q[IA + 2]
            evx, evy, evz = 0.0, v[IA + 1], v[IA + 2]
        elif jj == 1:
            ip, ib = IBR, IBC
            ex, ey, ez = _d3(q, IBR, IBC)
            evx, evy, evz = _d3(v, IBR, IBC)
        else:
            ip, ib = ICR, ICS
            ex, ey, ez = _d3(q, ICR, ICS)
            evx, evy, evz = _d3(v, ICR, ICS)
        en = math.sqrt(ex * ex + ey * ey + ez * ez)
        jout[jj, 0], jout[jj, 1], jout[jj, 2] = ex, ey, ez
        delta = en - P[b + J_C]
        if delta <= 0.0 or en == 0.0:
            st[S_INC + jj] = 0.0
            continue
        nx, ny, nz = ex / en, ey / en, ez / en
        ddot = evx * nx + evy * ny + evz * nz
        if st[S_INC + jj] == 0.0:
            st[S_INC + jj] = 1.0
            st[S_VIMP + jj] = max(ddot, P[b + J_FLOOR])
        fn = normal_force(int(P[b + J_LAW]), delta, ddot, st[S_VIMP + jj], P[b + J_K], P[b + J_N],
                          P[b + J_E], P[b + J_CLIN], P[b + J_DMAX])
        eel += P[b + J_K] * delta ** (P[b + J_N] + 1.0) / (P[b + J_N] + 1.0)
        jout[jj, 3], jout[jj, 4] = delta, fn
        # force on the pin (journal / ball): −fn n + friction
        fx, fy, fz = -fn * nx, -fn * ny, -fn * nz
        torque = 0.0  # about x, on the crank
        if jj == 0:
            # journal surface at the contact point moves with v_A + ω x̂ × R n; tangent t = x̂ × n
            ty_, tz_ = -nz, ny  # tangent x-component 0
            vt = v[IA + 1] * ty_ + v[IA + 2] * tz_ + wx * P[b + J_R]
            ft = friction_force(vt, fn, P[b + J_MU], P[P_V0], P[P_V1])
            fy += ft * ty_
            fz += ft * tz_
            torque = P[b + J_R] * ft
            jout[jj, 5] = abs(ft)
        else:
            # sliding velocity of the ball centre relative to the socket's body at that point
            rvx, rvy, rvz = evx, evy, evz
            if jj == 1:  # the crank turns: subtract ω x̂ × e
                rvy -= -wx * ez
                rvz -= wx * ey
            rn = rvx * nx + rvy * ny + rvz * nz
            wtx, wty, wtz = rvx - rn * nx, rvy - rn * ny, rvz - rn * nz
            sv = math.sqrt(wtx * wtx + wty * wty + wtz * wtz)
            if sv > 0.0:
                mu = P[b + J_MU] * ramp(sv, P[P_V0], P[P_V1])
                gx, gy, gz = -mu * fn * wtx / sv, -mu * fn * wty / sv, -mu * fn * wtz / sv
                fx += gx
                fy += gy
                fz += gz
                jout[jj, 5] = mu * fn
                if jj == 1:  # moment about the crank's x axis of the reaction −F at B_r = B_c + e
                    torque = ey * (-gz) - ez * (-gy)
        Q[ip] += fx
        Q[ip + 1] += fy
        Q[ip + 2] += fz
        if ib >= 0:
            Q[ib] -= fx
            Q[ib + 1] -= fy
            Q[ib + 2] -= fz
        if torque != 0.0:
            Q[IBC + 1] += torque * ty
            Q[IBC + 2] += torque * tz
            Q[IA + 1] -= torque * ty
            Q[IA + 2] -= torque * tz
    # slider guide friction
    if P[P_GUIDE_F] > 0.0:
        vs = v[ICS] * P[P_G] + v[ICS + 1] * P[P_G + 1] + v[ICS + 2] * P[P_G + 2]
        f = P[P_GUIDE_F] * ramp(vs, P[P_V0], P[P_V1])
        if vs > 0.0:
            f = -f
        elif vs == 0.0:
            f = 0.0
        for k in range(3):
            Q[ICS + k] += f * P[P_G + k]
    return eel


@njit(cache=True)
def accelerations(P, jon, M, Qg, q, v, th, om, al, st, Phi, J, gam, phit, indep, Q, jout, acc):
    """q̈ by the velocity transformation (module docstring) into ``acc``; returns (drive torque about x
    [N m], elastic energy [J])."""
    eel = forces(P, jon, Qg, q, v, st, Q, jout)
    m = constraints(P, jon, False, q, v, th, om, al, Phi, J, gam, phit, indep)
    Jm = np.ascontiguousarray(J[:m])
    U, s, Vt = np.linalg.svd(Jm)
    # particular solution q̈ₚ = V_m S⁻¹ Uᵀ γ
    w = (U.T @ gam[:m]) / s
    qp = Vt[:m].T @ w
    R = np.ascontiguousarray(Vt[m:].T)
    rhs = R.T @ (Q - M @ qp)
    zdd = np.linalg.solve(R.T @ M @ R, rhs)
    a = qp + R @ zdd
    for k in range(NQ):
        acc[k] = a[k]
    torque = 0.0
    if P[P_DRIVE] > 0.5:
        # multipliers: Φ_qᵀ λ = M q̈ − Q
        lam = U @ ((Vt[:m] @ (M @ a - Q)) / s)
        dy, dz = q[IBC + 1] - q[IA + 1], q[IBC + 2] - q[IA + 2]
        c, sn = math.cos(th), math.sin(th)
        torque = -lam[m - 1] * (-dy * c - dz * sn)
    return torque, eel


@njit(cache=True)
def run(P, jon, M, Minv, Qg, st, th, om, al, stride, out):
    """Integrate len(al) steps from state ``st`` (updated in place); step k goes from t_k to t_{k+1}
    with the drive's θ, ω at t_k, t_{k+1} (``th``, ``om``: len(al) + 1 values; ignored without the
    drive) and α at t_k. Writes the sample of every ``stride``-th step (the state before it, with its
    accelerations) into ``out``. Returns (status, steps done)."""
    nstep = len(al)
    q = st[S_Q:S_Q + NQ].copy()
    v = st[S_V:S_V + NQ].copy()
    Phi = np.zeros(MAX_ROWS)
    J = np.zeros((MAX_ROWS, NQ))
    gam = np.zeros(MAX_ROWS)
    phit = np.zeros(MAX_ROWS)
    indep = np.zeros(MAX_ROWS, dtype=np.int64)
    Q = np.zeros(NQ)
    jout = np.zeros((3, 6))
    acc = np.zeros(NQ)
    g0, g1, g2 = P[P_G], P[P_G + 1], P[P_G + 2]
    h = P[P_H]
    for k in range(nstep):
        torque, eel = accelerations(P, jon, M, Qg, q, v, th[k], om[k], al[k], st, Phi, J, gam, phit, indep, Q,
                                    jout, acc)
        if k % stride == 0:
            o = out[k // stride]
            dy, dz = q[IBC + 1] - q[IA + 1], q[IBC + 2] - q[IA + 2]
            ang = math.atan2(dz, dy)
            prev = st[S_THETA]
            ang += 2.0 * math.pi * round((prev - ang) / (2.0 * math.pi))
            st[S_THETA] = ang
            o[O_THETA] = ang
            o[O_OMEGA] = (dy * (v[IBC + 2] - v[IA + 2]) - dz * (v[IBC + 1] - v[IA + 1])) / (dy * dy + dz * dz)
            o[O_SLIDER] = (q[ICS] - P[P_P0]) * g0 + (q[ICS + 1] - P[P_P0 + 1]) * g1 + \
                (q[ICS + 2] - P[P_P0 + 2]) * g2
            o[O_SLIDER_ACC] = acc[ICS] * g0 + acc[ICS + 1] * g1 + acc[ICS + 2] * g2
            o[O_TORQUE] = torque
            for jj in range(3):
                for c in range(6):
                    o[O_JOINT + 6 * jj + c] = jout[jj, c]
            o[O_EKIN] = 0.5 * (v @ (M @ v))
            o[O_EPOT] = -(q @ Qg)
            o[O_EEL] = eel
        v += acc * h
        q += v * h
        if not _project(P, jon, Minv, q, v, th[k + 1], om[k + 1], Phi, J, gam, phit, indep):
            st[S_Q:S_Q + NQ] = q
            st[S_V:S_V + NQ] = v
            return NEWTON_FAILED, k
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            return NOT_FINITE, k
    st[S_Q:S_Q + NQ] = q
    st[S_V:S_V + NQ] = v
    return OK, nstep
