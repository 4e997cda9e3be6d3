r"""The flexible reference engine's accelerations by the constraint forces (a sparse KKT solve) instead of the
R matrix: the same q̈ to round-off, at a fraction of the cost.

:func:`twin.reference.flexible_rmatrix.flex_mass` builds the R matrix column by column (one solve of the
augmented Jacobian per independent coordinate) and the dense Rᵀ M R (r²n): with the chain's 28 coordinates and
16 independent ones that was most of a step. The accelerations do not depend on the basis of the motions the
constraints allow: q̈ is the unique minimizer of ½ q̈ᵀ M q̈ − Qᵀ q̈ on {Φ_c q̈ = γ_c} (Gauss's principle), Φ_c the
constraint rows (the rows of the augmented set that are not independent coordinates) and γ_c = −Φ̇_c q̇ their
quadratic terms. Rᵀ M R z̈ = Rᵀ (Q − M Ṙż) and the Lagrange form

    M q̈ + Φ_cᵀ λ = Q,   Φ_c q̈ = γ_c

give the same q̈ (exactly; here to round-off). The natural-coordinate mass matrix is constant, except that θ
carries no mass (rows 0–1 tie it to the crank): the crank's rows are added to it as a penalty,
M̃ = M + Σ k_r Φ_rᵀ Φ_r (r = 0, 1), so that M̃ is positive definite. The solution's q̈ does not change: the rows
stay constraints, Φ_r q̈ = γ_r, so the added force Φ_rᵀ k_r Φ_r q̈ = Φ_rᵀ k_r γ_r only shifts the rows' own
multipliers by k_r γ_r (neither q̈ nor θ's multiplier reads them). M̃ is block diagonal: the crank's five
coordinates (θ, A', B; its block changes with θ and is inverted each step, 5 × 5) and constant blocks (the rod's
housings, the slider, the supports, the chain's groups of segments) inverted once. Then, with Y = M̃⁻¹ Φ_cᵀ and
W = Φ_c Y (the constraints' mobility, 12 × 12 for a uniform chain of 6 segments):

    W λ = Φ_c M̃⁻¹ Q − γ_c,   q̈ = M̃⁻¹ Q − Y λ.

Sparse: each constraint row touches at most eight coordinates, each coordinate's column of M̃⁻¹ only its block
(x or y of the points of one axial group of segments: 4 for a chain of 6 segments in 2 groups).
With the crank angle prescribed (a driving constraint) θ's row e₇ joins Φ_c with γ = α and the drive torque is
−λ₇ (:func:`twin.reference.flexible_rmatrix.flex_solve_acc` gives R₀ᵀ (M q̈ − Q), the same number).
The normal mobility of a clearance joint (:func:`twin.reference.flexible_rmatrix.normal_mobility`,
J R (Rᵀ M R)⁻¹ Rᵀ Jᵀ) is J N Jᵀ with N = M̃⁻¹ − Y W⁻¹ Yᵀ the constrained inverse mass matrix.
``tests/test_structure_reference.py`` checks the three against the R-matrix kernels on random states.
"""

from __future__ import annotations

import math

import numpy as np

from twin.jit import njit
from twin.natural_coordinates import N_Q, P_CLR_A, P_CLR_B, P_CLR_C, P_CLR_G, P_MC, P_R, quadratic_terms
from twin.reference.flexible_kernels import G_FLEX_A, G_FLEX_G, flex_mass_times, theta_forces
from twin.reference.model import cholesky_factor, cholesky_solve_factored

#: the crank's coordinates (x_B, y_B, θ, x_A, y_A): the block of M̃ that changes with θ
CRANK = np.array([0, 1, 7, 8, 9], dtype=np.int64)
_MAXNZ = 8


class KKTLayout:
    """The constant tables of the sparse solve for one flexible layout (:class:`twin.reference.flexible.FlexLayout`)
    and parameter vector ``P``; ``prescribed``: θ's row is a constraint too.

    Attributes (all numpy arrays for the compiled kernels): ``crow`` the constraint rows (0–11 the rigid set's,
    12 + j segment j's length, 12 + N + k slide k's), ``pat``/``pn`` each row's structural columns, ``Minv`` the
    inverse of M̃'s constant blocks (n × n, zero on the crank's rows and columns), ``cols``/``cn`` for each
    coordinate the coordinates of its block, ``kaug`` the penalty weights of rows 0 and 1, ``wlo`` the envelope of
    W = Φ_c M̃⁻¹ Φ_cᵀ (each row's first structurally nonzero column). ``mass``: the constant
    mass matrix (n × n) where it is not the chain's (the modal rod, no segments or slides)."""

    def __init__(self, P: np.ndarray, G: np.ndarray, segs: np.ndarray, seg_f: np.ndarray, slides: np.ndarray,
                 n: int, prescribed: bool, mass: np.ndarray | None = None) -> None:
        indep = {7, 2}
        if P[P_CLR_A] > 0.5 or G[G_FLEX_A] > 0.5:
            indep |= {8, 9}
        if P[P_CLR_B] > 0.5:
            indep |= {3, 4}
        if P[P_CLR_C] > 0.5:
            indep |= {5, 6}
        if P[P_CLR_G] > 0.5:
            indep |= {10, 11}
        elif G[G_FLEX_G] > 0.5:
            indep |= {10}
        if {8, 9} - indep:
            raise ValueError("the sparse flexible solve needs the crank journal A' free (frame support or clearance)")
        rows = [r for r in range(N_Q) if r not in indep]
        if prescribed:
            rows.append(7)
        nseg, nsl = segs.shape[0], slides.shape[0]
        rows += [N_Q + j for j in range(nseg + nsl)]
        self.crow = np.array(sorted(rows), dtype=np.int64)
        # structural columns of each row
        pats = []
        for r in self.crow:
            if r == 0:
                p = [0, 1, 8, 9]
            elif r == 1:
                p = [0, 1, 7, 8, 9]
            elif r == 2:
                p = [2, 3, 4, 5]
            elif r == 3:
                p = [0, 2]
            elif r == 4:
                p = [1, 3]
            elif r == 5:
                p = [4, 6]
            elif r == 6:
                p = [5, 10]
            elif r < N_Q:
                p = [int(r)]
            elif r < N_Q + nseg:
                a, b = segs[r - N_Q]
                p = [a, a + 1, b, b + 1]
            else:
                pp, c, s = slides[r - N_Q - nseg]
                a, b = segs[s]
                p = sorted({pp, pp + 1, c, c + 1, a, a + 1, b, b + 1})
            pats.append(sorted(int(v) for v in p))
        self.pn = np.array([len(p) for p in pats], dtype=np.int64)
        self.pat = np.zeros((len(pats), _MAXNZ), dtype=np.int64)
        for i, p in enumerate(pats):
            self.pat[i, :len(p)] = p
        # the constant mass matrix, probed (or given: the modal rod's, twin.reference.flexible_modal)
        if mass is not None:
            M = np.array(mass, dtype=np.float64)
        else:
            M = np.empty((n, n))
            e = np.zeros(n)
            for k in range(n):
                e[:] = 0.0
                e[k] = 1.0
                flex_mass_times(P, segs, seg_f, G, e, M[:, k])
        crank = set(CRANK.tolist())
        rest = [k for k in range(n) if k not in crank]
        if np.any(M[np.ix_(CRANK, rest)] != 0.0):
            raise ValueError("the crank's block of the mass matrix is coupled to other coordinates")
        Mr = M[np.ix_(rest, rest)]
        # blocks: connected components of M's pattern
        nr = len(rest)
        comp = list(range(nr))

        def root(i):
            while comp[i] != i:
                comp[i] = comp[comp[i]]
                i = comp[i]
            return i

        for i in range(nr):
            for j in range(nr):
                if Mr[i, j] != 0.0:
                    comp[root(i)] = root(j)
        groups: dict[int, list[int]] = {}
        for i in range(nr):
            groups.setdefault(root(i), []).append(i)
        self.Minv = np.zeros((n, n))
        self.cols = np.zeros((n, max([5] + [len(g) for g in groups.values()])), dtype=np.int64)
        self.cn = np.zeros(n, dtype=np.int64)
        for members in groups.values():
            idx = [rest[i] for i in members]
            blk = M[np.ix_(idx, idx)].copy()
            if len(idx) == 1 and blk[0, 0] == 0.0 and idx[0] in (10, 11) and idx[0] in self.crow:
                # a massless coordinate held by its own unit row (φ = 0 with the ideal guide): the penalty
                # Φᵀ k Φ = k e e ᵀ with γ = 0 gives it a unit mass without changing Q̃
                blk[0, 0] = 1.0
            if np.any(np.linalg.eigvalsh(blk) <= 0.0):
                raise ValueError(f"the mass matrix is not positive definite on coordinates {idx}")
            L = np.linalg.cholesky(blk)
            Li = np.linalg.solve(L, np.eye(len(idx)))
            self.Minv[np.ix_(idx, idx)] = Li.T @ Li
            for k in idx:
                self.cn[k] = len(idx)
                self.cols[k, :len(idx)] = idx
        for k in CRANK:
            self.cn[k] = 5
            self.cols[k, :5] = CRANK
        # W's envelope: W_rs = Φ_r M̃⁻¹ Φ_sᵀ is structurally zero unless rows r and s reach a common block of M̃;
        # wlo[r] the first row s ≤ r it can be nonzero in. Cholesky keeps the envelope (no fill before wlo[r]),
        # so W and its factor are computed on it only (the same numbers: the entries left out are exact zeros)
        blocks = [{int(self.cols[k, 0]) for k in p} for p in pats]
        self.wlo = np.array([min(s for s in range(r + 1) if blocks[r] & blocks[s]) for r in range(len(pats))],
                            dtype=np.int64)
        self.Mcrank = M[np.ix_(CRANK, CRANK)].copy()
        mc, r = P[P_MC], P[P_R]
        # penalty weights: row 0 (gradient 2(B − A'), |2r|) adds ≈ m_c/2 on B, row 1 (|(s, −c)| = 1, r on θ)
        # m_c on B and m_c r² on θ: the crank's own scale, for a well-conditioned M̃
        self.kaug = np.array([mc / (8.0 * r * r), mc])
        self.prescribed = prescribed


@njit(cache=True)
def kkt_rows(P, q, qd, segs, slides, crow, pat, pn, alpha, PhiV, gam, qt):
    """The constraint rows' values on their structural columns (``PhiV``) and γ_c = −Φ̇_c q̇ (``gam``); θ's row (if
    in ``crow``) is the prescribed acceleration ``alpha``. ``qt``: scratch (≥ 12)."""
    s, c = math.sin(q[7]), math.cos(q[7])
    quadratic_terms(q[:N_Q], qd[:N_Q], s, c, qt)
    nseg = segs.shape[0]
    dxB, dyB = q[0] - q[8], q[1] - q[9]
    for i in range(crow.shape[0]):
        r = crow[i]
        for k in range(pn[i]):
            PhiV[i, k] = 0.0
        if r < N_Q:
            gam[i] = qt[r]
            if r == 0:   # pat 0, 1, 8, 9
                PhiV[i, 0] = 2.0 * dxB
                PhiV[i, 1] = 2.0 * dyB
                PhiV[i, 2] = -2.0 * dxB
                PhiV[i, 3] = -2.0 * dyB
            elif r == 1:   # pat 0, 1, 7, 8, 9
                PhiV[i, 0] = s
                PhiV[i, 1] = -c
                PhiV[i, 2] = dxB * c + dyB * s
                PhiV[i, 3] = -s
                PhiV[i, 4] = c
            elif r == 2:   # 2, 3, 4, 5
                dx, dy = q[4] - q[2], q[5] - q[3]
                PhiV[i, 0] = -2.0 * dx
                PhiV[i, 1] = -2.0 * dy
                PhiV[i, 2] = 2.0 * dx
                PhiV[i, 3] = 2.0 * dy
            elif r == 3 or r == 4:   # x_B − x'_B (0, 2) / y_B − y'_B (1, 3)
                PhiV[i, 0] = 1.0
                PhiV[i, 1] = -1.0
            elif r == 5:   # x'_C − x_C (4, 6)
                PhiV[i, 0] = -1.0
                PhiV[i, 1] = 1.0
            elif r == 6:   # d_off + y_g − y_C (5, 10)
                PhiV[i, 0] = -1.0
                PhiV[i, 1] = 1.0
            else:
                PhiV[i, 0] = 1.0
                if r == 7:
                    gam[i] = alpha
        elif r < N_Q + nseg:
            a, b = segs[r - N_Q, 0], segs[r - N_Q, 1]
            ux, uy = q[b] - q[a], q[b + 1] - q[a + 1]
            vx, vy = qd[b] - qd[a], qd[b + 1] - qd[a + 1]
            gam[i] = -2.0 * (vx * vx + vy * vy)
            _put(pat, pn, i, a, -2.0 * ux, PhiV)
            _put(pat, pn, i, a + 1, -2.0 * uy, PhiV)
            _put(pat, pn, i, b, 2.0 * ux, PhiV)
            _put(pat, pn, i, b + 1, 2.0 * uy, PhiV)
        else:
            k = r - N_Q - nseg
            p, cc, sg = slides[k, 0], slides[k, 1], slides[k, 2]
            a, b = segs[sg, 0], segs[sg, 1]
            dx, dy = q[cc] - q[p], q[cc + 1] - q[p + 1]
            wx, wy = q[b] - q[a], q[b + 1] - q[a + 1]
            ddx, ddy = qd[cc] - qd[p], qd[cc + 1] - qd[p + 1]
            dwx, dwy = qd[b] - qd[a], qd[b + 1] - qd[a + 1]
            gam[i] = -2.0 * (ddx * dwy - ddy * dwx)
            _put(pat, pn, i, cc, wy, PhiV)
            _put(pat, pn, i, cc + 1, -wx, PhiV)
            _put(pat, pn, i, p, -wy, PhiV)
            _put(pat, pn, i, p + 1, wx, PhiV)
            _put(pat, pn, i, b, -dy, PhiV)
            _put(pat, pn, i, b + 1, dx, PhiV)
            _put(pat, pn, i, a, dy, PhiV)
            _put(pat, pn, i, a + 1, -dx, PhiV)


@njit(cache=True)
def _put(pat, pn, i, col, v, PhiV):
    for k in range(pn[i]):
        if pat[i, k] == col:
            PhiV[i, k] += v
            return


@njit(cache=True)
def kkt_factor(P, q, crow, pat, pn, PhiV, Minv, cols, cn, Mcrank, kaug, Y, W, sc, wlo):
    """M̃'s crank block inverted into ``Minv`` (the rest of ``Minv`` is constant), Y = M̃⁻¹ Φ_cᵀ (n × m) and the
    Cholesky factor of W = Φ_c Y into ``W``'s lower triangle; False if W is not positive definite. ``Y`` is held
    transposed, m × n (a constraint row's M̃⁻¹ Φ_rᵀ contiguous); ``sc``: scratch, (3, 5, 5) (no allocation in the
    step); ``wlo``: W's envelope (:class:`KKTLayout`; W and its factor are computed on it, zero before it)."""
    m = crow.shape[0]
    # the crank block: M + k0 Φ0ᵀΦ0 + k1 Φ1ᵀΦ1 on (x_B, y_B, θ, x_A, y_A)
    s, c = math.sin(q[7]), math.cos(q[7])
    dxB, dyB = q[0] - q[8], q[1] - q[9]
    Mc, L, gv = sc[0], sc[1], sc[2]
    g0, g1, x5 = gv[0], gv[1], gv[2]
    g0[0], g0[1], g0[2], g0[3], g0[4] = 2.0 * dxB, 2.0 * dyB, 0.0, -2.0 * dxB, -2.0 * dyB
    g1[0], g1[1], g1[2], g1[3], g1[4] = s, -c, dxB * c + dyB * s, -s, c
    for i in range(5):
        for j in range(5):
            Mc[i, j] = Mcrank[i, j] + kaug[0] * g0[i] * g0[j] + kaug[1] * g1[i] * g1[j]
    if not _spd_inverse(Mc, 5, L, x5):
        return False
    for i in range(5):
        for j in range(5):
            Minv[CRANK_C[i], CRANK_C[j]] = Mc[i, j]
    n = q.shape[0]
    for r in range(m):
        Yr = Y[r]
        for i in range(n):
            Yr[i] = 0.0
        for t in range(pn[r]):
            k = pat[r, t]
            v = PhiV[r, t]
            for u in range(cn[k]):
                i = cols[k, u]
                Yr[i] += Minv[k, i] * v   # M̃⁻¹ symmetric: its row k
    for r in range(m):
        for s2 in range(wlo[r]):
            W[r, s2] = 0.0
        for s2 in range(wlo[r], r + 1):
            Ys = Y[s2]
            acc = 0.0
            for t in range(pn[r]):
                acc += PhiV[r, t] * Ys[pat[r, t]]
            W[r, s2] = acc
    return envelope_cholesky(W, m, wlo)


@njit(cache=True)
def envelope_cholesky(A, n, lo):
    """:func:`twin.reference.model.cholesky_factor` on the envelope ``lo`` (row i is zero before column lo[i]; the
    factor keeps it): the same factor, operation for operation, without the products of the zeros before the
    envelope (which subtract exact zeros). False if A is not positive definite."""
    for j in range(n):
        sacc = A[j, j]
        for k in range(lo[j], j):
            sacc -= A[j, k] * A[j, k]
        if not sacc > 0.0:
            return False
        ljj = math.sqrt(sacc)
        A[j, j] = ljj
        for i in range(j + 1, n):
            if lo[i] > j:
                continue
            t = A[i, j]
            for k in range(max(lo[i], lo[j]), j):
                t -= A[i, k] * A[j, k]
            A[i, j] = t / ljj
    return True


CRANK_C = CRANK


@njit(cache=True)
def _spd_inverse(A, n, L, x):
    """A ← A⁻¹ for a small SPD matrix (Cholesky into ``L``, then the inverse column by column, ``x`` scratch);
    False if not SPD."""
    for i in range(n):
        for j in range(n):
            L[i, j] = A[i, j]
    if not cholesky_factor(L, n):
        return False
    for col in range(n):
        for i in range(n):
            x[i] = 1.0 if i == col else 0.0
        cholesky_solve_factored(L, n, x)
        for i in range(n):
            A[i, col] = x[i]
    return True


@njit(cache=True)
def kkt_mobility(pat, pn, PhiV, Minv, cols, cn, Y, W, m, pin_x, pin_y, eye_x, eye_y, nx, ny, u):
    """J N Jᵀ [1/kg], J = n·(pin − eye) on the coordinates (``pin_y`` −1: the pin does not move along y), N the
    constrained inverse mass (module docstring); ``u`` scratch (≥ m)."""
    # y = M̃⁻¹ Jᵀ is read through Minv's columns; J y and Φ_c y
    nj = 4 if pin_y >= 0 else 3
    jc = (pin_x, eye_x, eye_y, pin_y if pin_y >= 0 else pin_x)
    jv = (nx, -nx, -ny, ny)
    jy = 0.0
    for a in range(nj):
        for b in range(nj):
            jy += jv[a] * Minv[jc[a], jc[b]] * jv[b]
    for r in range(m):   # (Φ_c M̃⁻¹ Jᵀ)_r = Y[:, r] · Jᵀ (M̃⁻¹ symmetric)
        acc = 0.0
        for a in range(nj):
            acc += Y[r, jc[a]] * jv[a]
        u[r] = acc
    v = u[m:2 * m]
    v[:] = u[:m]
    cholesky_solve_factored(W, m, v)
    acc = 0.0
    for r in range(m):
        acc += u[r] * v[r]
    return jy - acc


@njit(cache=True)
def kkt_accelerations(q, Q, crow, pat, pn, PhiV, gam, Minv, cols, cn, Y, W, qdd, lam):
    """q̈ from W λ = Φ_c M̃⁻¹ Q − γ_c, q̈ = M̃⁻¹ Q − Y λ (after :func:`kkt_factor`); returns the multiplier of θ's
    row if it is a constraint (the prescribed crank: the drive torque is its negative), else 0."""
    n = q.shape[0]
    m = crow.shape[0]
    for i in range(n):   # a = M̃⁻¹ Q (block by block; the penalty needs no right-hand side, module docstring)
        acc = 0.0
        for u in range(cn[i]):
            k = cols[i, u]
            acc += Minv[i, k] * Q[k]
        qdd[i] = acc
    for r in range(m):
        acc = 0.0
        for t in range(pn[r]):
            acc += PhiV[r, t] * qdd[pat[r, t]]
        lam[r] = acc - gam[r]
    cholesky_solve_factored(W, m, lam)
    for r in range(m):
        lr = lam[r]
        Yr = Y[r]
        for i in range(n):
            qdd[i] -= Yr[i] * lr
    mu = 0.0
    for r in range(m):
        if crow[r] == 7:
            mu = lam[r]
    return mu


@njit(cache=True)
def _kkt_response(Minv, Y, W, m, pin_x, pin_y, eye_x, eye_y, nx, ny, z, v):
    """The constrained response to a unit normal force: z = N Jᵀ (n), J = n·(pin − eye) as in :func:`kkt_mobility`,
    and v = W⁻¹ Φ_c M̃⁻¹ Jᵀ (m, the constraint multipliers' change per unit force along −Jᵀ is −v)."""
    n = z.shape[0]
    nj = 4 if pin_y >= 0 else 3
    jc = (pin_x, eye_x, eye_y, pin_y if pin_y >= 0 else pin_x)
    jv = (nx, -nx, -ny, ny)
    for i in range(n):   # M̃⁻¹ Jᵀ (M̃⁻¹ symmetric: its columns jc)
        acc = 0.0
        for a in range(nj):
            acc += Minv[i, jc[a]] * jv[a]
        z[i] = acc
    for r in range(m):   # Φ_c M̃⁻¹ Jᵀ = Y[r, :] · Jᵀ, then W⁻¹ of it
        acc = 0.0
        for a in range(nj):
            acc += Y[r, jc[a]] * jv[a]
        v[r] = acc
    cholesky_solve_factored(W, m, v)
    for r in range(m):   # z = M̃⁻¹ Jᵀ − Yᵀ W⁻¹ Φ_c M̃⁻¹ Jᵀ
        vr = v[r]
        Yr = Y[r]
        for i in range(n):
            z[i] -= Yr[i] * vr


@njit(cache=True)
def pair_response(Minv, Y, W, m, a, pin_x, pin_y, eye_x, eye_y, jo, z, v):
    """The constrained response of clearance pair ``a`` (0: B, 1: C) to a unit force along its normal (``jo``'s
    eccentricity; :func:`_kkt_response` into ``z[a]``, ``v[a]``) and its normal mobility
    J N Jᵀ = J z [1/kg] (0 without a normal). One solve serves the damping bound and the θ-method (:func:`theta_from_responses`), for
    either rod."""
    d = math.sqrt(jo[0] * jo[0] + jo[1] * jo[1])
    if not d > 0.0:
        return 0.0
    nx, ny = jo[0] / d, jo[1] / d
    za = z[a]
    _kkt_response(Minv, Y, W, m, pin_x, pin_y, eye_x, eye_y, nx, ny, za, v[a])
    return nx * (za[pin_x] - za[eye_x]) + ny * ((za[pin_y] if pin_y >= 0 else 0.0) - za[eye_y])


@njit(cache=True)
def kkt_theta_damping(h, qdd, Minv, Y, W, m, crow, lawB, lawC, fB, fC, shift, jb, jc, z, v):
    """The contact laws' damping at B and C by the θ-method after :func:`kkt_accelerations` (the sparse form of
    :func:`twin.reference.flexible_rmatrix.theta_damping`, which states the method and is its check): the normal
    force f = F_e + c [(1 − θ) δ̇ + θ δ̇_end], θ = ½ while c h ≤ 2 m̂ and 1 − m̂/(c h) beyond; the forces' change Δ
    solved with the pairs' mobilities W_ab = J_a N J_bᵀ (both joints together), q̈ −= Σ Δ_a N J_aᵀ; jb[3], jc[3] take
    the forces. ``lawB``, ``lawC``: :func:`twin.reference.flexible_kernels.law_terms`; ``z`` (2 × n), ``v`` (2 × m)
    scratch. Returns the change of the drive torque −λ₇ where θ's row is a constraint (the prescribed crank), else 0."""
    act = np.zeros(2, dtype=np.bool_)
    act[0] = fB > 0.0 and lawB[1] > 0.0
    act[1] = fC > 0.0 and lawC[1] > 0.0
    if not (act[0] or act[1]):
        return 0.0
    pins = ((0, 1, 2, 3), (6, 10 if shift else -1, 4, 5))
    for a in range(2):
        if act[a]:
            lw = lawB if a == 0 else lawC
            p = pins[a]
            _kkt_response(Minv, Y, W, m, p[0], p[1], p[2], p[3], lw[4], lw[5], z[a], v[a])
    return theta_from_responses(h, qdd, m, crow, lawB, lawC, fB, fC, shift, jb, jc, z, v, act, np.zeros((2, 2)),
                                np.zeros(2), np.zeros(2), np.zeros(2))


@njit(cache=True)
def theta_from_responses(h, qdd, m, crow, lawB, lawC, fB, fC, shift, jb, jc, z, v, act, Wm, an, f0, dl):
    """The θ-method of :func:`kkt_theta_damping` once the active pairs' responses ``z[a]`` = N J_aᵀ, ``v[a]`` (the
    multipliers' change per unit force, :func:`_kkt_response`) are solved (the modal rod solves them once per step for
    its damping bound too); ``act`` the active pairs (set here), ``Wm`` … ``dl`` scratch (2 × 2, 2, 2, 2)."""
    act[0] = fB > 0.0 and lawB[1] > 0.0
    act[1] = fC > 0.0 and lawC[1] > 0.0
    if not (act[0] or act[1]):
        return 0.0
    for a in range(2):
        an[a] = 0.0
        dl[a] = 0.0
        for b in range(2):
            Wm[a, b] = 0.0
    pins = ((0, 1, 2, 3), (6, 10 if shift else -1, 4, 5))
    for a in range(2):
        if not act[a]:
            continue
        lw = lawB if a == 0 else lawC
        p = pins[a]
        nx, ny = lw[4], lw[5]
        an[a] = nx * (qdd[p[0]] - qdd[p[2]]) + ny * ((qdd[p[1]] if p[1] >= 0 else 0.0) - qdd[p[3]])
        for b in range(2):
            if act[b]:   # J_a z_b
                Wm[a, b] = nx * (z[b, p[0]] - z[b, p[2]]) + ny * ((z[b, p[1]] if p[1] >= 0 else 0.0) - z[b, p[3]])
    f0[0], f0[1] = fB, fC
    theta_forces(h, Wm, act, f0, lawB, lawC, an, dl)
    n = qdd.shape[0]
    dtau = 0.0
    for a in range(2):
        if not act[a] or dl[a] == 0.0:
            continue
        for i in range(n):   # the separating pair: the force's change −Δ Jᵀ
            qdd[i] -= z[a, i] * dl[a]
        for k in range(m):   # λ changes by −Δ v; the torque −λ₇ by +Δ v₇
            if crow[k] == 7:
                dtau += v[a, k] * dl[a]
    if act[0]:
        jb[3] = f0[0] + dl[0]
    if act[1]:
        jc[3] = f0[1] + dl[1]
    return dtau


@njit(cache=True)
def kkt_friction_follow(q, qdd, Minv, Y, W, m, crow, segs, rpin_b, rb_b, rb_c, fB, fC, shift, jb, jc, g, z, v,
                        nzi):
    """After :func:`kkt_theta_damping`: the friction of each clearance joint follows its normal force's change, so
    that the step applies Coulomb's f_T = μ(v_t) f_N with the normal force it applies (the θ-method's), as the
    rigid model and the MuJoCo engine do; before, the friction took the explicit normal force ``fB``, ``fC``
    (:func:`twin.reference.flexible_kernels._bound_damping`), and |f_T|/f_N strayed from μ by up to 2 % in sliding
    contact, an error that does not shrink with the step (the θ-method's correction is c h δ̈ with c ~ 1/h).

    f_T is linear in f_N at the step's v_t (both friction laws), so f_T ← f_T f_N/f_N⁰ (f_N⁰ = ``fB`` or ``fC``, the
    force it was computed with; ``jb``/``jc`` [3] hold the θ-method's f_N, [4] f_T, updated here). The change ΔF_T
    acts as the friction does (:func:`twin.reference.flexible_kernels._eye_contact`): on the pin along t = R₉₀ n at
    its contact point (pin B: at B with the moment R_pin ΔF_T on the crank; pin C: x on the slider, y on the guide
    with ``shift``), opposite at the eye's centre with the moment −R_b ΔF_T on the end segment: q̈ += N g
    (N = M̃⁻¹ − Y W⁻¹ Yᵀ, g the generalized force of both joints' changes, one solve). ``g``, ``z`` (n), ``v``
    (m) and ``nzi`` (n, int64) scratch.
    Returns the change of the drive torque −λ₇ where θ's row is a constraint (the prescribed crank), else 0."""
    n = qdd.shape[0]
    for i in range(n):
        g[i] = 0.0
    any_change = False
    for a in range(2):   # g = Σ ΔF_T g_a (the response is linear: one solve for both joints)
        jo = jb if a == 0 else jc
        f0 = fB if a == 0 else fC
        if not f0 > 0.0 or jo[4] == 0.0 or jo[3] == f0:
            continue
        dft = jo[4] * (jo[3] / f0 - 1.0)
        jo[4] += dft
        any_change = True
        ex, ey = jo[0], jo[1]
        d = math.sqrt(ex * ex + ey * ey)
        nx, ny = (ex / d, ey / d) if d > 0.0 else (1.0, 0.0)
        tx, ty = -ny * dft, nx * dft
        if a == 0:
            g[0] += tx
            g[1] += ty
            g[7] += rpin_b * dft    # (R_pin n) × t = R_pin
            eye, s, rb = 2, 0, rb_b
        else:
            g[6] += tx
            if shift:
                g[10] += ty
            eye, s, rb = 4, segs.shape[0] - 1, rb_c
        g[eye] -= tx
        g[eye + 1] -= ty
        sa, sb = segs[s, 0], segs[s, 1]   # the moment −R_b ΔF_T on the end segment (flexible_kernels._moment)
        ux, uy = q[sb] - q[sa], q[sb + 1] - q[sa + 1]
        f = -rb * dft / (ux * ux + uy * uy)
        g[sb] += -uy * f
        g[sb + 1] += ux * f
        g[sa] -= -uy * f
        g[sa + 1] -= ux * f
    if not any_change:
        return 0.0
    nz = 0
    for k in range(n):   # g's nonzero coordinates (at most 18)
        if g[k] != 0.0:
            nzi[nz] = k
            nz += 1
    for i in range(n):   # M̃⁻¹ g (M̃⁻¹ symmetric)
        acc = 0.0
        for t in range(nz):
            acc += Minv[i, nzi[t]] * g[nzi[t]]
        z[i] = acc
    for r in range(m):   # W⁻¹ Φ_c M̃⁻¹ g
        acc = 0.0
        for t in range(nz):
            acc += Y[r, nzi[t]] * g[nzi[t]]
        v[r] = acc
    cholesky_solve_factored(W, m, v)
    dtau = 0.0
    for r in range(m):
        vr = v[r]
        Yr = Y[r]
        for i in range(n):
            z[i] -= Yr[i] * vr
        if crow[r] == 7:   # λ changes by +v; the torque −λ₇ by −v₇
            dtau -= vr
    for i in range(n):
        qdd[i] += z[i]
    return dtau
