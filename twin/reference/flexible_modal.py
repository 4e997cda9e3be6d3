r"""The reference engine's modal rod (``reference.rod_model = "modal"``): the flexible connecting rod as its chord and
a few assumed modes with a constant mass matrix, on the same R-matrix / constraint-force machinery as the chain
(:mod:`twin.reference.flexible`), at a fraction of its cost (``analysis/profile_reference_flexible.py``).

Kinematics: the material point at ξ = x/L of the rod (B' at ξ = 0, C at ξ = 1, the housings' centres as in the
rigid model and the chain) is

    r(ξ) = B' + ξ (C − B') + Σ_k φ_k(ξ) u_k,     φ_k(ξ) = sin(kπξ),  k = 1 … K (K = 3),

u_k ∈ R² a global 2-vector per shape: coordinates q = [q_0 … q_11 | u_1 … u_K] (n = 12 + 2K). r is linear in q, so
the bar's kinetic energy ½ ∫ μ |ṙ|² dx (μ its mass per length; the housings are the rigid model's point masses at
B' and C) is a constant quadratic form, the same in x and in y. Its elastic energy in the rod's frame
(ê = (C − B')/ℓ, ℓ = |C − B'|, n̂ = R₉₀ ê):

    V = ½ (EA/L) (ℓ − L)² + Σ_k [½ k_a,k s_k² + ½ k_b,k w_k²],   s_k = u_k·ê,  w_k = u_k·n̂,
    k_a,k = EA ∫φ_k'² dx = EA (kπ/L)² L/2,   k_b,k = EI ∫φ_k''² dx = EI (kπ/L)⁴ L/2:

the chord's stretch and the shapes' axial (s) and bending (w) amplitudes. The sines are the pinned–pinned beam's
and the fixed–fixed bar's own shapes: bending 1–3 are Euler–Bernoulli's exactly, the first axial mode (B fixed, the
end mass and the slider at C) within 0.003 % and the free rod's within 0.07 % (``analysis/structure_modal_basis.py``).
No constraint row is added (the rod's length row 2 is an independent coordinate, its stretch, as in the chain): the
acceleration solve has the rigid model's rows and the projection is the rigid model's closed form.

Damping: stiffness-proportional as the chain's (β_b = 2ζ_b/ω_b1, β_a = 2ζ_a/ω_a1, the model's own first pinned–pinned
bending and first axial modes), on the objective rates ṡ_k = u̇_k·ê + w_k (n̂·ḋ)/ℓ, ẇ_k = u̇_k·n̂ − s_k (n̂·ḋ)/ℓ
and ℓ̇ (d = C − B'): the dampers dissipate Σ c ṡ² + c ẇ² + c_s ℓ̇² ≥ 0 and a rigid rotation of the bent rod none.

The housings turn with the rod's end tangents t_B = r'(0), t_C = r'(1) (ξ-derivatives): a clearance joint's
friction moment acts there (the force pair of a moment M on t: M R₉₀t/|t|² through ∂t/∂q) and the friction's
sliding speed takes the tangent's spin. The accelerometers read the material point at their abscissa, offset across
along the local normal: p̈ = r̈(ξ) + η R₉₀ r̈'(ξ), η = offset/|r'(ξ)|, along the local tangent. Everything else (the
supports, the contact forces on the eyes, the laws' damping bound and θ-method, the drive train, the sampling) is
the chain's (:mod:`twin.reference.flexible`).

Scope: the housings' own rotary inertia (``structure.rod_end_inertia_kgm2``) must be 0 (the sines are not the
pinned–pinned modes with end inertia; the chain takes it).
"""

from __future__ import annotations

import math

import numpy as np

from twin.jit import njit
from twin.natural_coordinates import (N_Q, P_GX, P_GY, P_L, P_NEWTON_MAXIT, P_NEWTON_TOL, energy, kinetic_energy,
                                      mass_times, solve_aug)
from twin.reference.flexible_kernels import (G_FLEX_A, G_FLEX_G, G_MF, G_MG,
                                             _independent_values, rigid_residual, support_energy, support_forces)
from twin.reference.model import N_OUT, O_ACC, _rod_force

#: shapes of the modal rod (bending 1–3 need three; the first axial mode is the chord's with their axial parts)
N_SHAPES = 3
# the rod's scalars ``H``: length L [m], the chord's stiffness EA/L [N/m] and damping [N s/m], the bar's mass [kg]
H_L, H_KS, H_CS, H_MBAR = 0, 1, 2, 3
N_H = 4
# per shape ``MD[k]``: k_b, k_a, c_b, c_a, φ_k(½), φ_k'(0), φ_k'(1), ∫φ_k dξ
D_KB, D_KA, D_CB, D_CA, D_MID, D_T0, D_T1, D_INT = range(8)
N_D = 8


def shape_tables(K: int):
    """φ_k(ξ) = sin(kπξ): (at ½, slope at 0, slope at 1, integral over [0, 1]) per shape, and the bar's mass integrals
    ∫ f_i f_j dξ over f = (1 − ξ, ξ, φ_1 … φ_K) (closed forms)."""
    tab = np.zeros((K, 4))
    F = np.zeros((K + 2, K + 2))
    F[0, 0] = F[1, 1] = 1.0 / 3.0
    F[0, 1] = F[1, 0] = 1.0 / 6.0
    for k in range(1, K + 1):
        kp = k * math.pi
        tab[k - 1] = [math.sin(kp / 2.0), kp, kp * math.cos(kp), (1.0 - math.cos(kp)) / kp]
        F[0, 1 + k] = F[1 + k, 0] = 1.0 / kp                  # ∫(1 − ξ) sin kπξ
        F[1, 1 + k] = F[1 + k, 1] = -math.cos(kp) / kp        # ∫ξ sin kπξ
        F[1 + k, 1 + k] = 0.5
    return tab, F


def modal_matrices(split, ea: float, ei: float, K: int = N_SHAPES):
    """(M, Ka, Kb) per direction over [B', C, u_1 … u_K], the rod along x and straight: the bar's consistent mass
    with the housings' point masses, the axial stiffness (chord and shapes) and the bending stiffness."""
    L = split.length_m
    _, F = shape_tables(K)
    M = split.bar_mass_kg * F
    M[0, 0] += split.end_b_kg
    M[1, 1] += split.end_c_kg
    Ka, Kb = np.zeros((K + 2, K + 2)), np.zeros((K + 2, K + 2))
    Ka[:2, :2] = ea / L * np.array([[1.0, -1.0], [-1.0, 1.0]])
    for k in range(1, K + 1):
        Ka[1 + k, 1 + k] = ea * (k * math.pi / L) ** 2 * L / 2.0
        Kb[1 + k, 1 + k] = ei * (k * math.pi / L) ** 4 * L / 2.0
    return M, Ka, Kb


def modal_frequencies(split, ea: float, ei: float, slider_kg: float, K: int = N_SHAPES):
    """The modal rod's linearized frequencies [Hz]: (bending with B' and C held across — pinned–pinned, ascending;
    axial with B fixed and the slider at C, ascending; the free rod's elastic axial, ascending)."""
    from scipy.linalg import eigh

    M, Ka, Kb = modal_matrices(split, ea, ei, K)
    hz = lambda w2: np.sqrt(np.maximum(w2, 0.0)) / (2.0 * math.pi)  # noqa: E731
    bend = hz(eigh(Kb[2:, 2:], M[2:, 2:], eigvals_only=True))
    Mm = M.copy()
    Mm[1, 1] += slider_kg
    idx = [1] + list(range(2, K + 2))
    ax = hz(eigh(Ka[np.ix_(idx, idx)], Mm[np.ix_(idx, idx)], eigvals_only=True))
    free = hz(eigh(Ka, M, eigvals_only=True))[1:]
    return bend, ax, free


class ModalLayout:
    """The modal rod's tables for one configuration: ``n`` coordinates, ``H`` (H_*), ``MD`` (K × N_D, D_*), the
    rod's accelerometers ``sens`` (6 × 4: ξ (−1: not on the rod), offset across [m], axis code, unused) with their
    shapes' values ``sphi`` and slopes ``sdphi`` (6 × K), the supports ``G`` (as the chain's), the per-direction
    bar mass ``F`` (μL ∫ f_i f_j)."""

    def __init__(self, cfg, split) -> None:
        from twin.config import ACCELEROMETERS
        from twin.config.structure import StructureConfig  # noqa: F401  (the fields read below)
        from twin.reference.flexible_kernels import support_table

        st = cfg.structure
        K = N_SHAPES
        L = split.length_m
        self.K = K
        self.n = N_Q + 2 * K
        tab, F = shape_tables(K)
        self.F = split.bar_mass_kg * F
        bend, ax, _ = modal_frequencies(split, st.rod_ea_n, st.rod_ei_nm2, cfg.bodies.slider.mass_kg, K)
        beta_b = 2.0 * st.bending_damping_ratio / (2.0 * math.pi * bend[0])
        beta_a = 2.0 * st.axial_damping_ratio / (2.0 * math.pi * ax[0])
        _, Ka, Kb = modal_matrices(split, st.rod_ea_n, st.rod_ei_nm2, K)
        self.H = np.array([L, st.rod_ea_n / L, beta_a * st.rod_ea_n / L, split.bar_mass_kg])
        self.MD = np.zeros((K, N_D))
        for k in range(K):
            kb, ka = Kb[2 + k, 2 + k], Ka[2 + k, 2 + k]
            self.MD[k] = [kb, ka, beta_b * kb, beta_a * ka, tab[k, 0], tab[k, 1], tab[k, 2], tab[k, 3]]
        axes = {"+x": 0, "-x": 1, "+y": 2, "-y": 3}
        self.sens = np.full((6, 4), -1.0)
        self.sphi = np.zeros((6, K))
        self.sdphi = np.zeros((6, K))
        for i, name in enumerate(ACCELEROMETERS):
            mnt = cfg.sensors.accelerometers[name]
            if mnt.body != "rod":
                continue
            sx, sy = mnt.position_m
            xi = min(max(sx / L, 0.0), 1.0)
            self.sens[i] = [xi, sy, axes[mnt.axis], 0.0]
            for k in range(K):
                kp = (k + 1) * math.pi
                self.sphi[i, k] = math.sin(kp * xi)
                self.sdphi[i, k] = kp * math.cos(kp * xi)
        self.G = support_table(st, -1.0, 0.5)

    def mass_matrix(self, P: np.ndarray) -> np.ndarray:
        """The full constant mass matrix (n × n; θ massless), probed from :func:`modal_mass_times`."""
        n = self.n
        M = np.empty((n, n))
        e = np.zeros(n)
        for k in range(n):
            e[:] = 0.0
            e[k] = 1.0
            modal_mass_times(P, self.G, self.F, e, M[:, k])
        return M


# --------------------------------------------------------------------------------------------- kernels
@njit(cache=True)
def modal_mass_times(P, G, F, v, out):
    """out = M v: the rigid model's blocks (the rod as its two housings), the supports, the bar's consistent mass
    over (B', C, u_k) in x and in y."""
    mass_times(P, v[:N_Q], out[:N_Q])
    for i in range(N_Q, v.shape[0]):
        out[i] = 0.0
    if G[G_FLEX_A] > 0.5:
        out[8] += G[G_MF] * v[8]
        out[9] += G[G_MF] * v[9]
    if G[G_FLEX_G] > 0.5:
        out[10] += G[G_MG] * v[10]
    m = F.shape[0]
    for d in range(2):
        for i in range(m):
            ii = 2 + 2 * i + d if i < 2 else N_Q + 2 * (i - 2) + d
            acc = 0.0
            for j in range(m):
                jj = 2 + 2 * j + d if j < 2 else N_Q + 2 * (j - 2) + d
                acc += F[i, j] * v[jj]
            out[ii] += acc


@njit(cache=True)
def _tangent(q, qd, MD, end):
    """The rod's end tangent r'(ξ) (ξ-derivative) at B (``end`` 0) or C (1) and its spin rate t × ṫ / |t|²."""
    tx, ty = q[4] - q[2], q[5] - q[3]
    vx, vy = qd[4] - qd[2], qd[5] - qd[3]
    col = 5 + end
    for k in range(MD.shape[0]):
        s = MD[k, col]
        i = N_Q + 2 * k
        tx += s * q[i]
        ty += s * q[i + 1]
        vx += s * qd[i]
        vy += s * qd[i + 1]
    return tx, ty, (tx * vy - ty * vx) / (tx * tx + ty * ty)


@njit(cache=True)
def _end_moment(q, MD, end, m, Q):
    """A moment m about z on the housing at B (``end`` 0) or C (1), which turns with the end tangent t: the
    generalized force m R₉₀t/|t|² · ∂t/∂q."""
    tx, ty, _ = _tangent(q, q, MD, end)
    f = m / (tx * tx + ty * ty)
    gx, gy = -ty * f, tx * f
    Q[4] += gx
    Q[5] += gy
    Q[2] -= gx
    Q[3] -= gy
    col = 5 + end
    for k in range(MD.shape[0]):
        s = MD[k, col]
        i = N_Q + 2 * k
        Q[i] += s * gx
        Q[i + 1] += s * gy


@njit(cache=True)
def _modal_eye_contact(P, qs, q, MD, jo, fn0, ft0, eye, rb, Q):
    """As :func:`twin.reference.flexible_kernels._eye_contact`: the clearance joint's force on the eye's centre
    (``eye`` 2: B', 4: C) and its friction moment −R_b f_T on the housing (the end tangent)."""
    ex, ey = jo[0], jo[1]
    d = math.sqrt(ex * ex + ey * ey)
    if d > 0.0:
        nx, ny = ex / d, ey / d
    else:
        nx, ny = 1.0, 0.0
    fx = -fn0 * nx - ft0 * ny
    fy = -fn0 * ny + ft0 * nx
    _rod_force(P, qs, fx, fy, qs[eye] + rb * nx, qs[eye + 1] + rb * ny, Q)   # undoes the element's −F
    fx = -jo[3] * nx - jo[4] * ny
    fy = -jo[3] * ny + jo[4] * nx
    Q[eye] -= fx
    Q[eye + 1] -= fy
    _end_moment(q, MD, 0 if eye == 2 else 1, -rb * jo[4], Q)


@njit(cache=True)
def modal_forces(P, q, qd, H, MD, G, Q):
    """Add the bar's weight, the chord's and the shapes' elastic and damping forces and the supports' to Q; returns
    the dampers' power [W] (≥ 0)."""
    gx, gy = P[P_GX], P[P_GY]
    mbar = H[H_MBAR]
    for i in (2, 4):   # the bar's weight: half on each end's linear field, ∫φ_k on each shape
        Q[i] += 0.5 * mbar * gx
        Q[i + 1] += 0.5 * mbar * gy
    dx, dy = q[4] - q[2], q[5] - q[3]
    vx, vy = qd[4] - qd[2], qd[5] - qd[3]
    ell = math.sqrt(dx * dx + dy * dy)
    ex, ey = dx / ell, dy / ell
    nx, ny = -ey, ex
    dn = (nx * vx + ny * vy) / ell      # the chord's spin
    rate = ex * vx + ey * vy            # ℓ̇
    fs = -H[H_KS] * (ell - H[H_L]) - H[H_CS] * rate
    diss = H[H_CS] * rate * rate
    fdx, fdy = fs * ex, fs * ey          # on C (−on B')
    for k in range(MD.shape[0]):
        i = N_Q + 2 * k
        ux, uy = q[i], q[i + 1]
        s = ux * ex + uy * ey
        w = ux * nx + uy * ny
        sd = qd[i] * ex + qd[i + 1] * ey + w * dn
        wd = qd[i] * nx + qd[i + 1] * ny - s * dn
        fa = -MD[k, D_KA] * s - MD[k, D_CA] * sd
        fb = -MD[k, D_KB] * w - MD[k, D_CB] * wd
        diss += MD[k, D_CA] * sd * sd + MD[k, D_CB] * wd * wd
        Q[i] += fa * ex + fb * nx + MD[k, D_INT] * mbar * gx
        Q[i + 1] += fa * ey + fb * ny + MD[k, D_INT] * mbar * gy
        # through ê(d), n̂(d): ∂s/∂d = w n̂/ℓ, ∂w/∂d = −s n̂/ℓ (the rates' gradients the same)
        c = (fa * w - fb * s) / ell
        fdx += c * nx
        fdy += c * ny
    Q[4] += fdx
    Q[5] += fdy
    Q[2] -= fdx
    Q[3] -= fdy
    return support_forces(P, q, qd, G, Q, diss)


@njit(cache=True)
def modal_energy(P, q, qd, H, MD, G, F):
    """(T, V) [J]: kinetic (all masses) and potential (gravity, the chord and the shapes, the supports)."""
    n = q.shape[0]
    mv = np.empty(n)
    modal_mass_times(P, G, F, qd, mv)
    T = 0.0
    for i in range(n):
        T += 0.5 * qd[i] * mv[i]
    V = energy(P, q[:N_Q], qd[:N_Q]) - kinetic_energy(P, q[:N_Q], qd[:N_Q])
    gx, gy = P[P_GX], P[P_GY]
    mbar = H[H_MBAR]
    V -= 0.5 * mbar * (gx * (q[2] + q[4]) + gy * (q[3] + q[5]))
    dx, dy = q[4] - q[2], q[5] - q[3]
    ell = math.sqrt(dx * dx + dy * dy)
    ex, ey = dx / ell, dy / ell
    V += 0.5 * H[H_KS] * (ell - H[H_L]) ** 2
    for k in range(MD.shape[0]):
        i = N_Q + 2 * k
        s = q[i] * ex + q[i + 1] * ey
        w = -q[i] * ey + q[i + 1] * ex
        V += 0.5 * MD[k, D_KA] * s * s + 0.5 * MD[k, D_KB] * w * w
        V -= MD[k, D_INT] * mbar * (gx * q[i] + gy * q[i + 1])
    return T, support_energy(P, q, G, V)


@njit(cache=True)
def modal_project(P, G, q, qd, res, dq, b, z):
    """Newton on the rigid model's rows (the stretch, the supports and the independent coordinates held; the shapes
    u_k free), then q̇ ← R ż on the rigid twelve (the shapes' rates kept). Returns the iterations, −1 if no
    convergence. ``z``: empty int arrays standing for the chain's tables."""
    tol = P[P_NEWTON_TOL]
    maxit = int(P[P_NEWTON_MAXIT])
    it = 0
    conv = False
    while it < maxit:
        s, c = math.sin(q[7]), math.cos(q[7])
        rigid_residual(P, G, q, s, c, res)
        for i in range(N_Q):
            res[i] = -res[i]
        solve_aug(q, s, c, res, dq)
        big = 0.0
        for i in range(N_Q):
            q[i] += dq[i]
            if abs(dq[i]) > big:
                big = abs(dq[i])
        it += 1
        if big <= tol:
            conv = True
            break
    if not conv:
        return -1
    s, c = math.sin(q[7]), math.cos(q[7])
    _independent_values(P, G, q, qd, z, z, z, b)
    solve_aug(q, s, c, b, dq)
    for i in range(N_Q):
        qd[i] = dq[i]
    return it


@njit(cache=True)
def _modal_rod_sensors(P, q, qdd, sens, sphi, sdphi, row):
    """The rod's accelerometers: the material point at ξ, offset across along the local normal, read along the local
    tangent (or normal)."""
    gx, gy = P[P_GX], P[P_GY]
    K = sphi.shape[1]
    for i in range(6):
        xi = sens[i, 0]
        if xi < 0.0:
            continue
        ax = (1.0 - xi) * qdd[2] + xi * qdd[4]
        ay = (1.0 - xi) * qdd[3] + xi * qdd[5]
        tx, ty = q[4] - q[2], q[5] - q[3]
        atx, aty = qdd[4] - qdd[2], qdd[5] - qdd[3]
        for k in range(K):
            j = N_Q + 2 * k
            ax += sphi[i, k] * qdd[j]
            ay += sphi[i, k] * qdd[j + 1]
            tx += sdphi[i, k] * q[j]
            ty += sdphi[i, k] * q[j + 1]
            atx += sdphi[i, k] * qdd[j]
            aty += sdphi[i, k] * qdd[j + 1]
        ln = math.sqrt(tx * tx + ty * ty)
        hx, hy = tx / ln, ty / ln
        eta = sens[i, 1] / ln
        ax += -eta * aty - gx
        ay += eta * atx - gy
        axis = int(sens[i, 2])
        v = ax * hx + ay * hy if axis < 2 else -ax * hy + ay * hx
        if axis == 1 or axis == 3:
            v = -v
        row[O_ACC + i] = v


@njit(cache=True)
def _modal_structure_outputs(P, G, q, MD, row):
    """The "structure" channels (as :func:`twin.reference.flexible._structure_outputs`): the stretch, the mid-span
    point's distance from the chord Σ φ_k(½) u_k·n̂, the frame's and the guide's displacements [m]."""
    dx, dy = q[4] - q[2], q[5] - q[3]
    d = math.sqrt(dx * dx + dy * dy)
    w = 0.0
    for k in range(MD.shape[0]):
        i = N_Q + 2 * k
        w += MD[k, D_MID] * (-q[i] * dy + q[i + 1] * dx) / d
    o = N_OUT + 1
    row[o] = d - P[P_L]
    row[o + 1] = w
    row[o + 2] = q[8] if G[G_FLEX_A] > 0.5 else 0.0
    row[o + 3] = q[9] if G[G_FLEX_A] > 0.5 else 0.0
    row[o + 4] = q[10] if G[G_FLEX_G] > 0.5 else 0.0
