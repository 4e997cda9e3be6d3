r"""The reference engine's flexible structure (``structure.mode = "flexible"``): the connecting rod as the chain of
:mod:`twin.structure.rod` in natural coordinates, the crank's and the slider's supports as lumped oscillators and
structural damping, on the R-matrix formulation of :mod:`twin.natural_coordinates` (which it extends, unchanged).

Coordinates: the twelve of the rigid model, then two per chain point::

    q = [q_0 … q_11 | P_1 … P_{N+M}]      (n = 12 + 2 (N + M))

B' (q_2, q_3) is the housing at B (``end_B``, a point mass m_B) and C (q_4, q_5) the housing at C (``end_C``, m_C):
the rod's bores, where the joints B and C act as in the rigid model. Between them the N rigid segments: segment j
is a natural-coordinate bar between two chain points a_j, b_j with |b_j − a_j| = l (mass matrix m_s/6 [[2I, I],
[I, 2I]], constant: a rigid uniform bar). Nodes 1 … N−1 are shared points (the hinges); where the chain has a
slide the node has two points, P⁻ (end of the parent) and P⁺ (start of the child), with P⁺ − P⁻ along the
child's axis; at node 0 P⁻ is B', at node N P⁺ is C.

Rows: the rigid model's twelve, with row 2 (the rod's length) turned from a constraint into an independent
coordinate (|C − B'|² − L², the rod's total stretch), then the chain's: N segment lengths |b − a|² − l²,
M + 1 slide rows (P⁺ − P⁻) × (b − a)_child = 0, and N + M − 1 independent rows: the y of each interior node (its
parent-side point) and x(P⁺) − x(P⁻) of the slide at B and of each interior slide. The chain's rows do not enter
the rigid twelve, so A is block lower-triangular: the rigid block is solved in closed form
(:func:`twin.natural_coordinates.solve_aug`, row 2 taking its value from the right-hand side), the chain block
(2 (N + M) square) by a block-tridiagonal LU, one 2 × 2 block per chain point (the projection's Newton
iterations and its velocity projection; :func:`twin.reference.flexible_kernels.chain_order`). The
rod stays within ±12° of the guide, where the y rows and the length rows are independent. The accelerations are
the R-matrix formulation's, computed without R: by the constraint forces on the constant block-diagonal mass
matrix (:mod:`twin.reference.flexible_kkt`; the R-matrix kernels of :mod:`twin.reference.flexible_kernels`
remain as its check).

Elastic joints as forces: a hinge's moment −k Δ − c Δ̇ (Δ the angle from the parent's axis to the child's) on
the two bars (a moment M on a bar a→b: forces ±M R₉₀u/|u|² on b and a); a slide's force −k δ − c δ̇ along the
child's axis on P⁺ and the opposite on P⁻ (δ = (P⁺ − P⁻)·û). Supports: the frame's bore, with A ideal, moves with
the crank journal A' (rows 8–9 become independent: A' is the frame's displacement, with the frame's mass, its weight and
an isotropic spring and damper to ground); the guide rails with the slider move normal to the guide (row 10, y_g,
independent, with the guide's mass, spring and damper; the slider's weight is carried by the spring). The
accelerometers on the rod read their segment (rigid): p̈ = ä + ξ ü + η R₉₀ ü along the segment's axes; the
mount filter (:class:`twin.structure.MountFilter`) is applied to the sampled channels.

Clearance joints: the contact force on the rod acts on the eye's centre (B' or C), its friction moment −R_b f_T on
the end segment (the rigid model spreads a force on the rod over B' and C, which on a flexible rod would add a
spurious axial pair R_b f_N / L). Where it differs from the rigid model's conventions: the friction's sliding speed
takes the eye's spin from the end segment (the housing turns with it), not the chord C − B' (as the MuJoCo engine's
native module, from the housing body); the contact stiffnesses are resolved with the rigid rod's effective mass; the
law's explicit damping is bounded at the dead-beat value m̂/(2h), m̂ the flexible model's effective mass along the
normal (:func:`_bound_damping`, as the MuJoCo engine's force path: unbounded, against the light housing it rang at
the step's Nyquist rate), and after the explicit solve the law's damping is integrated by the θ-method as the MuJoCo
engine's contact rows do (:func:`twin.reference.flexible_kkt.kkt_theta_damping`): the explicit damping had been the largest step error against
MuJoCo (test 12, 12 dB at 10 kHz). The friction then follows the θ-method's normal force
(:func:`twin.reference.flexible_kkt.kkt_friction_follow`): f_T = μ(v_t) f_N with the f_N the step applies, as in the
rigid model and the MuJoCo engine (it had taken the explicit f_N: |f_T|/f_N up to 2 % off μ in sliding contact, and
the engines 1.6 dB apart on test 12 at the default step).
Scope: every drive (crank PID, prescribed crank, motor and torque through the drive train), symplectic Euler,
clearances at B and C (A and the guide ideal).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from twin.jit import njit
from twin.natural_coordinates import (N_Q, P_CLR_B, P_CLR_C, P_FGUIDE, P_GX, P_GY, P_H, P_IMAX, P_KI, P_KP,
                                      P_KV, P_L, P_M1, P_M2, P_M3, P_OUT_ENERGY, P_R, P_RBUSH_B, P_RBUSH_C, P_RPIN_B,
                                      P_V0, P_V1, P_XG1, P_XG2, S_I, S_IN_A, S_IN_B, S_IN_C, S_Q, S_QD, S_VIMP_A,
                                      S_VIMP_B, S_VIMP_C)
from twin.reference.model import N_OUT, NEWTON_FAILED, NOT_FINITE, O_EKIN, O_EPOT, OK, _outputs, generalized_forces
from twin.reference import drivetrain as DT
from twin.reference.guide import N_GUIDE_OUT
from twin.reference.flexible_kernels import (G_MID_SEG, G_MID_XI, N_G, support_table, G_CF, G_CG, G_FLEX_A, G_FLEX_G, G_KF, G_KG, G_MF, G_MG, factor,
                                             _eye_contact, _bound_damping, _seg_angle_rate, chain_forces, law_terms,
                                             flex_energy, flex_project,
                                             _rod_sensors, _slider_sensors)
from twin.reference.flexible_kkt import (KKTLayout, kkt_accelerations, kkt_factor, kkt_friction_follow, kkt_rows,
                                          pair_response, theta_from_responses)
from twin.reference.flexible_modal import (_modal_eye_contact, _modal_rod_sensors, _modal_structure_outputs,
                                           _tangent, modal_energy, modal_forces, modal_project)



@dataclasses.dataclass
class FlexLayout:
    """Index tables of the flexible rod (built from :func:`twin.structure.rod_chain`)."""

    n: int                      #: number of coordinates
    n_pts: int                  #: chain points
    segs: np.ndarray            #: (N, 2) coordinate index (x) of each segment's points a, b
    seg_f: np.ndarray           #: (N, 2) mass, length
    hinges: np.ndarray          #: (N−1, 2) parent and child segment
    hinge_f: np.ndarray         #: (N−1, 2) stiffness, damping
    slides: np.ndarray          #: (M+1, 3) P⁻ index, P⁺ index, child segment
    slide_f: np.ndarray         #: (M+1, 2) stiffness, damping
    indep: np.ndarray           #: (N+M−1, 3) kind (0: y of point i; 1: x(i) − x(j)), i, j
    sensors: np.ndarray         #: (6, 4) segment (−1: not on the rod), ξ [m from a], η [m], axis code
    G: np.ndarray               #: supports (layout G_*)
    x0: np.ndarray              #: (n_pts,) abscissa of each chain point along the straight rod [m]


def build(cfg, chain) -> FlexLayout:
    """The index tables of ``chain`` (:class:`twin.structure.RodChain`) for configuration ``cfg``."""
    N = len(chain.bodies) - 2
    L = chain.length_m
    # the nodes' abscissae: each segment's start, then L (segments of equal or, tuned, unequal length)
    xn = [b.x0_m for b in chain.bodies[1:-1]] + [L]

    def node_of(x: float) -> int:
        return int(np.argmin(np.abs(np.asarray(xn) - x)))

    slide_nodes = sorted({node_of(j.x_m) for j in chain.joints if j.kind == "slide"})
    # points: for each node, P⁻ then (if a slide sits there) P⁺; node 0's P⁻ is B' (index 2), node N's P⁺ is C (4)
    minus, plus, x0 = {}, {}, []
    idx = N_Q
    for node in range(N + 1):
        if node == 0:
            minus[0] = 2
        else:
            minus[node] = idx
            x0.append(xn[node])
            idx += 2
        if node in slide_nodes:
            if node == N:
                plus[N] = 4
            else:
                plus[node] = idx
                x0.append(xn[node])
                idx += 2
        else:
            plus[node] = minus[node]
    n = idx
    segs = np.array([[plus[j], minus[j + 1]] for j in range(N)], dtype=np.int64)
    seg_bodies = chain.bodies[1:-1]
    seg_f = np.array([[b.mass_kg, xn[j + 1] - xn[j]] for j, b in enumerate(seg_bodies)])
    hinges, hinge_f, slides, slide_f = [], [], [], []
    for jt in chain.joints:
        node = node_of(jt.x_m)
        if jt.kind == "hinge":
            hinges.append([node - 1, node])
            hinge_f.append([jt.stiffness, jt.damping])
        else:
            slides.append([minus[node], plus[node], min(node, N - 1)])
            slide_f.append([jt.stiffness, jt.damping])
    indep = [[0, minus[j], 0] for j in range(1, N)]
    indep += [[1, plus[j], minus[j]] for j in slide_nodes if j < N]
    assert len(indep) == (n - N_Q) - (N + len(slide_nodes)), "the chain's rows must be square"
    sens = np.full((6, 4), -1.0)
    from twin.config import ACCELEROMETERS
    from twin.structure.rod import _body_at

    axes = {"+x": 0, "-x": 1, "+y": 2, "-y": 3}
    for i, name in enumerate(ACCELEROMETERS):
        mnt = cfg.sensors.accelerometers[name]
        if mnt.body != "rod":
            continue
        sx, sy = mnt.position_m
        seg = _body_at(chain, sx) - 1 if 0.0 < sx < L else (0 if sx <= 0.0 else N - 1)
        sens[i] = [seg, sx - xn[seg], sy, axes[mnt.axis]]
    st = cfg.structure
    # the mid-span point: the chain body holding L/2 (the MuJoCo engine's rule, twin.structure.rod._body_at), at the
    # same distance from that segment's start
    mid = _body_at(chain, L / 2) - 1
    G = support_table(st, mid, L / 2 - chain.bodies[mid + 1].x0_m)
    return FlexLayout(n, (n - N_Q) // 2, segs, seg_f, np.array(hinges, dtype=np.int64), np.array(hinge_f),
                      np.array(slides, dtype=np.int64), np.array(slide_f), np.array(indep, dtype=np.int64), sens, G,
                      np.array(x0))


# --------------------------------------------------------------------------------------------- kernels
@njit(cache=True)
def _structure_outputs(P, G, q, segs, row):
    """The "structure" channels into ``row`` from column ``N_OUT + 1`` (:data:`STRUCTURE_CHANNELS`), as the MuJoCo
    engine defines them (:func:`twin.mujoco_engine.flexible.structure_channels`): the rod's stretch |C − B'| − L, the
    mid-span material point's distance from the chord B'–C (+ to the left of B'→C), the frame's displacement at A
    (A' = (q_8, q_9)) and the guide's normal to the guide (y_g = q_10) [m]."""
    bx, by, cx, cy = q[2], q[3], q[4], q[5]
    dx, dy = cx - bx, cy - by
    d = math.sqrt(dx * dx + dy * dy)
    seg = int(G[G_MID_SEG])
    a, b = segs[seg, 0], segs[seg, 1]
    ux, uy = q[b] - q[a], q[b + 1] - q[a + 1]
    f = G[G_MID_XI] / math.sqrt(ux * ux + uy * uy)
    mx, my = q[a] + f * ux, q[a + 1] + f * uy
    o = N_OUT + 1
    row[o] = d - P[P_L]
    row[o + 1] = (dx * (my - by) - dy * (mx - bx)) / d
    row[o + 2] = q[8] if G[G_FLEX_A] > 0.5 else 0.0
    row[o + 3] = q[9] if G[G_FLEX_A] > 0.5 else 0.0
    row[o + 4] = q[10] if G[G_FLEX_G] > 0.5 else 0.0


@njit(cache=True, nogil=True)
def run_flexible(P, G, segs, seg_f, hinges, hinge_f, slides, slide_f, indep, sens, st, x, theta_ref, omega_ref,
                 stride, out, want_out, D, ds, setpoint, dout, alpha_ref, crow, pat, pn, Minv, cols, cn, Mcrank,
                 kaug, H, MD, F, msens, sphi, sdphi, wlo):
    """Integrate ``len(theta_ref)`` steps of the flexible bench from the rigid state ``st`` (PID integral,
    contact events; its q, q̇ unused) and the full coordinates ``x`` = [q (n), q̇ (n), dissipated energy]
    (updated in place). Crank PID drive, or with ``D`` non-empty the drive train (:mod:`twin.reference.drivetrain`,
    state ``ds``, ``setpoint[k]`` the step's speed set point or motor torque, ``dout`` its sample rows) as
    :func:`twin.reference.model.run_motor`; symplectic Euler with projection, the same sampling as
    :func:`twin.reference.model.run_steps`. With ``alpha_ref`` non-empty the crank angle is prescribed as
    :func:`twin.reference.model.run_prescribed` does (``theta_ref``, ``omega_ref`` hold the program at t_0 … t_n,
    ``alpha_ref`` its acceleration at t_0 … t_{n−1}; the drive torque goes to the torque column). Returns
    (status, steps done). The accelerations by the sparse constraint-force solve of
    :mod:`twin.reference.flexible_kkt` (``crow`` to ``kaug`` and ``wlo``: its
    :class:`~twin.reference.flexible_kkt.KKTLayout`,
    with θ's row among the constraints when the crank is prescribed). ``H`` non-empty: the rod is the modal rod of
    :mod:`twin.reference.flexible_modal` (``H`` … ``sdphi`` its tables; the chain's tables empty): its forces,
    projection, sensors, energy, eye contact and the pairs' responses (one solve per pair for the damping bound and
    the θ-method) are that module's, the rest of the step is the same."""
    n = (x.shape[0] - 1) // 2
    nc = n - N_Q
    h = P[P_H]
    kp, kv, ki, imax = P[P_KP], P[P_KV], P[P_KI], P[P_IMAX]
    q = x[:n].copy()
    qd = x[n:2 * n].copy()
    diss_total = x[2 * n]
    integ = st[S_I]
    cst_a = np.empty(2)
    cst_b = np.empty(2)
    cst_c = np.empty(6)
    cst_a[0], cst_a[1] = st[S_IN_A], st[S_VIMP_A]
    cst_b[0], cst_b[1] = st[S_IN_B], st[S_VIMP_B]
    cst_c[0], cst_c[1] = st[S_IN_C], st[S_VIMP_C]
    for i in range(4):
        cst_c[2 + i] = 0.0
    Q = np.empty(n)
    qs = np.empty(N_Q)
    qds = np.empty(N_Q)
    ja = np.zeros(5)
    jb = np.zeros(5)
    jc = np.zeros(5 + N_GUIDE_OUT)
    mk = crow.shape[0]
    PhiV = np.zeros((mk, pat.shape[1]))
    gam = np.empty(mk)
    Yk = np.empty((mk, n))
    Wk = np.empty((mk, mk))
    lam = np.empty(mk)
    sck = np.empty((3, 5, 5))
    qs2 = np.empty(N_Q)
    qdd = np.empty(n)
    res = np.empty(n)
    dq = np.empty(n)
    b = np.empty(n)
    tmp = np.empty(n)
    A = np.empty((nc, n))
    LU = np.empty((nc, nc))
    piv = np.empty(nc, dtype=np.int64)
    lawB = np.zeros(6)
    lawC = np.zeros(6)
    fcb = np.zeros(3)   # the laws' (F_e, c) from the damping bound, for the θ-method's terms
    fcc = np.zeros(3)
    zth = np.empty((2, n))
    gfr = np.empty(n)
    gfi = np.empty(n, dtype=np.int64)
    vth = np.empty((2, mk))
    modal = H.shape[0] > 0
    act = np.zeros(2, dtype=np.bool_)
    Wm = np.zeros((2, 2))
    an = np.zeros(2)
    f0 = np.zeros(2)
    dl = np.zeros(2)
    motor = D.shape[0] > 0
    prescribed = alpha_ref.shape[0] > 0
    nsteps = setpoint.shape[0] if motor else (alpha_ref.shape[0] if prescribed else theta_ref.shape[0])
    dtmp = np.empty(3)
    Qb = np.empty(N_Q)
    qd0 = np.empty(N_Q)
    Qg = np.zeros(N_Q)
    if motor:
        DT.gravity_forces(P[P_GX], P[P_GY], P[P_M1], P[P_XG1], P[P_R], P[P_M2], P[P_XG2], P[P_L], P[P_M3], Qg)
    status = OK
    k = 0
    while k < nsteps:
        if motor:   # drive-train hook: the belt's torque on the crank
            err = 0.0
            tau = DT.begin_step(D, ds, qd[7], setpoint[k], dtmp)
        elif prescribed:
            err = 0.0
            tau = 0.0
        else:
            err = theta_ref[k] - q[7]
            tau = kp * err + kv * (omega_ref[k] - qd[7]) + ki * integ
        for i in range(n):
            Q[i] = 0.0
        for i in range(N_Q):
            qs[i] = q[i]
            qds[i] = qd[i]
        shift = G[G_FLEX_G] > 0.5 and P[P_CLR_C] > 0.5
        if shift:   # the joint C's pin C' rides on the guide: its eccentricity is measured from d_off + y_g
            qs[5] -= q[10]
            qds[5] -= qd[10]
        if not modal and k == 0 and not factor(q, segs, slides, indep, A, LU, piv):   # later steps: the projection's
            status = NOT_FINITE
            break
        # the constraint rows and the mobility W = Φ_c M̃⁻¹ Φ_cᵀ at (q, q̇) (flexible_kkt: the R matrix's q̈ to
        # round-off)
        kkt_rows(P, q, qd, segs, slides, crow, pat, pn, alpha_ref[k] if prescribed else 0.0, PhiV, gam, qs2)
        if not kkt_factor(P, q, crow, pat, pn, PhiV, Minv, cols, cn, Mcrank, kaug, Yk, Wk, sck, wlo):
            status = NOT_FINITE
            break
        generalized_forces(P, qs, qds, tau, cst_a, cst_b, cst_c, Q[:N_Q], ja, jb, jc)
        # the contact forces on the rod act on its eyes (end_B, end_C), not spread as on a rigid rod, with the
        # law's damping bounded by the pair's effective mass (_bound_damping)
        if P[P_CLR_B] > 0.5 and jb[2] > 0.0:
            # the pair's constrained response, solved once: its mobility bounds the damping here, the θ-method
            # below reads the response itself
            mob = pair_response(Minv, Yk, Wk, mk, 0, 0, 1, 2, 3, jb, zth, vth)
            if modal:
                w_eye = _tangent(q, qd, MD, 0)[2]
            else:
                w_eye = _seg_angle_rate(q, qd, segs[0, 0], segs[0, 1])[2]
            fn0, ft0 = _bound_damping(P, qs, qds, True, cst_b, jb, mob, h, w_eye, Q, fcb)
            if fn0 > 0.0 or jb[3] > 0.0:
                if modal:
                    _modal_eye_contact(P, qs, q, MD, jb, fn0, ft0, 2, P[P_RBUSH_B], Q)
                else:
                    _eye_contact(P, qs, q, jb, fn0, ft0, 2, P[P_RBUSH_B], segs[0, 0], segs[0, 1], Q)
        if P[P_CLR_C] > 0.5 and jc[2] > 0.0:
            last = segs.shape[0] - 1
            mob = pair_response(Minv, Yk, Wk, mk, 1, 6, 10 if shift else -1, 4, 5, jc, zth, vth)
            if modal:
                w_eye = _tangent(q, qd, MD, 1)[2]
            else:
                w_eye = _seg_angle_rate(q, qd, segs[last, 0], segs[last, 1])[2]
            fn0, ft0 = _bound_damping(P, qs, qds, False, cst_c, jc, mob, h, w_eye, Q, fcc)
            if fn0 > 0.0 or jc[3] > 0.0:
                if modal:
                    _modal_eye_contact(P, qs, q, MD, jc, fn0, ft0, 4, P[P_RBUSH_C], Q)
                else:
                    _eye_contact(P, qs, q, jc, fn0, ft0, 4, P[P_RBUSH_C], segs[last, 0], segs[last, 1], Q)
        if shift and jc[3] > 0.0:   # the contact's normal component on the pin, which the ideal guide took, moves it
            ex, ey = jc[0], jc[1]
            d = math.sqrt(ex * ex + ey * ey)
            nx, ny = (ex / d, ey / d) if d > 0.0 else (1.0, 0.0)
            Q[10] += -jc[3] * ny + jc[4] * nx
        for i in range(N_Q):   # the mechanism's own forces (the drive train's accounts read them)
            Qb[i] = Q[i]
        if modal:
            diss = modal_forces(P, q, qd, H, MD, G, Q)
        else:
            diss = chain_forces(P, q, qd, segs, seg_f, hinges, hinge_f, slides, slide_f, G, Q)
        # the laws' damping by the θ-method (theta_from_responses, as kkt_theta_damping) after the explicit solve: the
        # laws' terms now
        fB = fC = 0.0
        if P[P_CLR_B] > 0.5 and jb[2] > 0.0:
            law_terms(P, qs, qds, True, cst_b, jb, lawB, fcb)
            fB = jb[3]
        if P[P_CLR_C] > 0.5 and jc[2] > 0.0:
            law_terms(P, qs, qds, False, cst_c, jc, lawC, fcc)
            fC = jc[3]
        mu = kkt_accelerations(q, Q, crow, pat, pn, PhiV, gam, Minv, cols, cn, Yk, Wk, qdd, lam)
        if prescribed:   # the drive torque: minus the multiplier of the driving constraint
            tau = -mu
        if fB > 0.0 or fC > 0.0:   # the pairs' responses of this step, solved above
            tau += theta_from_responses(h, qdd, mk, crow, lawB, lawC, fB, fC, shift, jb, jc, zth, vth, act, Wm, an,
                                        f0, dl)
            if not modal:   # the friction with the normal force the step applies (Coulomb's f_T = μ f_N, as the
                # rigid model's); the modal rod's friction keeps the explicit normal force (not carried over to it)
                tau += kkt_friction_follow(q, qdd, Minv, Yk, Wk, mk, crow, segs, P[P_RPIN_B], P[P_RBUSH_B],
                                           P[P_RBUSH_C], fB, fC, shift, jb, jc, gfr, zth[0], vth[0], gfi)
        if want_out and k % stride == 0:
            row = out[k // stride]
            _outputs(P, q[:N_Q], qd[:N_Q], qdd[:N_Q], tau, ja, jb, jc, row)
            if modal:
                _modal_rod_sensors(P, q, qdd, msens, sphi, sdphi, row)
            else:
                _rod_sensors(P, q, qdd, segs, sens, row)
            if G[G_FLEX_G] > 0.5:
                _slider_sensors(P, qdd, sens, row)
            if P[P_OUT_ENERGY] > 0.5:
                T, V = modal_energy(P, q, qd, H, MD, G, F) if modal else \
                    flex_energy(P, q, qd, segs, seg_f, hinges, hinge_f, slides, slide_f, G)
                row[O_EKIN] = T
                row[O_EPOT] = V
            row[N_OUT] = diss_total
            if modal:
                _modal_structure_outputs(P, G, q, MD, row)
            else:
                _structure_outputs(P, G, q, segs, row)
            if motor:
                DT.outputs(D, ds, dout[k // stride])
                if D[DT.D_ACCOUNT] != 0.0:
                    T, V = modal_energy(P, q, qd, H, MD, G, F) if modal else \
                        flex_energy(P, q, qd, segs, seg_f, hinges, hinge_f, slides, slide_f, G)
                    dout[k // stride, DT.DO_EMECH] = T + V + dout[k // stride, DT.DO_ROTOR_KE]
        diss_total += h * diss
        integ += h * err
        if imax > 0.0:
            if integ > imax:
                integ = imax
            elif integ < -imax:
                integ = -imax
        for i in range(N_Q):
            qd0[i] = qd[i]
        for i in range(n):
            qd[i] += h * qdd[i]
            q[i] += h * qd[i]
        if prescribed:   # the driving constraint: θ and θ̇ are the program's at t_{k+1}
            q[7] = theta_ref[k + 1]
            qd[7] = omega_ref[k + 1]
        if (modal_project(P, G, q, qd, res, dq, b, indep) if modal else
                flex_project(P, G, q, qd, segs, seg_f, slides, indep, A, LU, piv, res, dq, b, tmp, True)) < 0:
            status = NEWTON_FAILED
            k += 1
            break
        fin = True
        for i in range(n):
            if not (math.isfinite(q[i]) and math.isfinite(qd[i])):
                fin = False
        if not fin:
            status = NOT_FINITE
            k += 1
            break
        if motor:   # drive-train hook: rotor, belt stretch, accounts
            fgd = DT.guide_force(P[P_FGUIDE], qd0[6], P[P_V0], P[P_V1]) if D[DT.D_ACCOUNT] != 0.0 else 0.0
            DT.end_step(D, ds, Qb, Qg, tau, fgd, qd0, qd[:N_Q])
        k += 1
    x[:n] = q
    x[n:2 * n] = qd
    x[2 * n] = diss_total
    st[S_Q:S_Q + N_Q] = q[:N_Q]
    st[S_QD:S_QD + N_Q] = qd[:N_Q]
    st[S_I] = integ
    st[S_IN_A], st[S_VIMP_A] = cst_a[0], cst_a[1]
    st[S_IN_B], st[S_VIMP_B] = cst_b[0], cst_b[1]
    st[S_IN_C], st[S_VIMP_C] = cst_c[0], cst_c[1]
    return status, k


# ------------------------------------------------------------------------------------------ Python side
#: the modal rod's tables of :func:`run_flexible`, empty: the chain
NO_MODAL = (np.empty(0), np.empty((0, 8)), np.empty((0, 0)), np.empty((0, 4)), np.empty((0, 0)), np.empty((0, 0)))
#: output columns of :func:`run_flexible`: the rigid model's, then the dissipated energy, then the "structure"
#: channels (:data:`STRUCTURE_CHANNELS` order, :func:`_structure_outputs`)
O_DISS = N_OUT
O_STRUCT = N_OUT + 1
#: the "structure" channel group (:mod:`twin.channels`; the MuJoCo engine's, same names, meaning and units [m])
STRUCTURE_CHANNELS = ("rod_stretch", "rod_deflection", "frame_x", "frame_y", "guide_y")
N_OUT_FLEX = O_STRUCT + len(STRUCTURE_CHANNELS)


def rigid_rod_body(split):
    """The rod's two housings as the rigid model's rod body (point masses m_B at B', m_C at C)."""
    from twin.config.mechanism import BodyParams

    m = split.end_b_kg + split.end_c_kg
    L = split.length_m
    return BodyParams(m, L, L * split.end_c_kg / m, split.end_b_kg * split.end_c_kg * L * L / m)


def initial_coordinates(P, G, lay: FlexLayout, q_rigid, qd_rigid) -> np.ndarray:
    """Full coordinates [q, q̇, 0] of the straight, unstretched rod on the rigid pose, velocities projected."""
    n = lay.n
    x = np.zeros(2 * n + 1)
    q, qd = x[:n], np.zeros(n)
    q[:N_Q] = q_rigid
    qd[:N_Q] = qd_rigid
    bx, by, cx, cy = q_rigid[2], q_rigid[3], q_rigid[4], q_rigid[5]
    bvx, bvy, cvx, cvy = qd_rigid[2], qd_rigid[3], qd_rigid[4], qd_rigid[5]
    L = math.hypot(cx - bx, cy - by)
    for p in range(lay.n_pts):
        f = lay.x0[p] / L
        i = N_Q + 2 * p
        q[i], q[i + 1] = bx + f * (cx - bx), by + f * (cy - by)
        qd[i], qd[i + 1] = bvx + f * (cvx - bvx), bvy + f * (cvy - bvy)
    nc = n - N_Q
    A, LU, piv = np.empty((nc, n)), np.empty((nc, nc)), np.empty(nc, dtype=np.int64)
    qc = q.copy()
    it = flex_project(P, G, qc, qd, lay.segs, lay.seg_f, lay.slides, lay.indep, A, LU, piv, np.empty(n),
                      np.empty(n), np.empty(n), np.empty(n), False)
    if it < 0:
        raise ValueError("the flexible rod's initial pose does not satisfy its constraints")
    x[:n], x[n:2 * n] = qc, qd
    return x


class RodRun:
    """What the two reference rods' runners share (:class:`FlexibleRun`, the chain;
    :class:`twin.reference.flexible_modal.ModalRun`): Table 1's rod split, the rigid model's parameters with the rod as
    its two housings (``P``), the accelerometer mounts, the state ``x``."""

    def __init__(self, cfg, P_rigid: np.ndarray, params) -> None:
        from twin.config.structure import StructureConfig
        from twin.structure import MountFilter, rod_split

        st = cfg.structure
        self.cfg = cfg
        self.split = rod_split(cfg.bodies.rod.mass_kg, cfg.bodies.rod.length_m, cfg.bodies.rod.x_g_m,
                               cfg.bodies.rod.inertia_kgm2, st.rod_end_inertia_kgm2)
        # (the rigid model's parameters of the rod's two housings; its "structure" channels are this runner's)
        sensors = dataclasses.replace(cfg.sensors, channels=tuple(g for g in cfg.sensors.channels if g != "structure"))
        ends = dataclasses.replace(cfg, bodies=dataclasses.replace(cfg.bodies, rod=rigid_rod_body(self.split)),
                                   structure=StructureConfig(), sensors=sensors)
        self.P = params(ends)
        self.P_rigid = P_rigid
        self.mounts = MountFilter(st.mount_frequency_hz, st.mount_damping_ratio, cfg.sensors.output_rate_hz)
        self.x: np.ndarray | None = None
        self._kkt: dict[bool, KKTLayout] = {}

    def take_contact_parameters(self) -> None:
        """The contact stiffnesses of the rigid model's parameters (resolved at its reset)."""
        from twin.natural_coordinates import P_CLIN_A, P_CLIN_B, P_CLIN_C, P_K_A, P_K_B, P_K_C
        for i in (P_K_A, P_K_B, P_K_C, P_CLIN_A, P_CLIN_B, P_CLIN_C):
            self.P[i] = self.P_rigid[i]


class FlexibleRun(RodRun):
    """The flexible bench of one configuration for :class:`twin.reference.engine.ReferenceEngine`: parameters,
    layout, state and the accelerometer mounts."""

    def __init__(self, cfg, P_rigid: np.ndarray, params) -> None:
        from twin.structure import rod_chain

        super().__init__(cfg, P_rigid, params)
        self.chain = rod_chain(cfg.structure, cfg.bodies.rod, cfg.bodies.slider.mass_kg)
        self.layout = build(cfg, self.chain)
        self.kkt(cfg.drive.mode == "prescribed")   # built here, not in the first chunk's stepping time

    def reset(self, st_rigid: np.ndarray) -> None:
        """Start from the rigid model's state (the straight, unstretched rod on its pose), the contact stiffnesses
        of the rigid model's parameters."""
        self.take_contact_parameters()
        lay = self.layout
        self.x = initial_coordinates(self.P, lay.G, lay, st_rigid[S_Q:S_Q + N_Q], st_rigid[S_QD:S_QD + N_Q])
        self.mounts.reset()

    def run(self, st: np.ndarray, theta_ref: np.ndarray, omega_ref: np.ndarray, stride: int, buf: np.ndarray,
            train=None, k0: int = 0, alpha_ref: np.ndarray | None = None):
        """One chunk; ``train`` the run's :class:`twin.reference.drivetrain_run.ReferenceTrain` (motor or torque
        drive; ``k0`` the chunk's first step) or None (crank PID, or the prescribed crank with ``alpha_ref``: then
        ``theta_ref`` and ``omega_ref`` hold one more value, the program at the chunk's end)."""
        lay = self.layout
        if train is not None:
            n_out = buf.shape[0]
            sp, dbuf = train.chunk_inputs(k0, omega_ref, stride, n_out)
            D, ds = train.D, train.ds
        else:
            sp = dbuf = D = ds = np.empty(0)
            dbuf = np.empty((0, 1))
        kk = self.kkt(alpha_ref is not None)
        return run_flexible(self.P, lay.G, lay.segs, lay.seg_f, lay.hinges, lay.hinge_f, lay.slides, lay.slide_f,
                            lay.indep, lay.sensors, st, self.x, theta_ref, omega_ref, stride, buf, True, D, ds, sp,
                            dbuf, np.empty(0) if alpha_ref is None else alpha_ref, kk.crow, kk.pat, kk.pn, kk.Minv,
                            kk.cols, kk.cn, kk.Mcrank, kk.kaug, *NO_MODAL, kk.wlo)

    def kkt(self, prescribed: bool) -> KKTLayout:
        """The sparse acceleration solve's tables (:class:`twin.reference.flexible_kkt.KKTLayout`), built once per
        drive kind (with the crank prescribed θ's row is a constraint)."""
        kk = self._kkt.get(prescribed)
        if kk is None:
            lay = self.layout
            kk = self._kkt[prescribed] = KKTLayout(self.P, lay.G, lay.segs, lay.seg_f, lay.slides, lay.n, prescribed)
        return kk


def tap_kick(q: np.ndarray, qd: np.ndarray, node: int, speed_mps: float, axial: bool) -> None:
    """The tap's velocity change on a flexible rod's coordinates, in place: the point whose x coordinate is
    ``q[node]`` given ``speed_mps`` [m/s] normal to the chord B'–C, or (``axial``) the bore C along it. Either rod's
    (the chain's middle node; the modal rod's first shape)."""
    ux, uy = q[4] - q[2], q[5] - q[3]
    L = math.hypot(ux, uy)
    if axial:
        qd[4] += speed_mps * ux / L
        qd[5] += speed_mps * uy / L
    else:
        qd[node] += -speed_mps * uy / L
        qd[node + 1] += speed_mps * ux / L


def chain_tap_response(cfg, speed_mps: float = 0.01, duration_s: float = 0.2, every: int = 5, theta0: float = 0.3,
                       drive: bool = False, axial: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """A tap on the flexible rod in the reference engine: the mechanism at rest at crank angle ``theta0`` [rad]
    (no drive unless ``drive``, no guide friction), the rod's middle node given ``speed_mps`` normal to the
    chord; returns (t [s], the node's distance from the chord B'–C [m]) every ``every`` steps for
    ``duration_s``. The rod's bending relative to its ends: its ringing gives the in-situ bending mode and
    its damping (``tests/test_structure_reference.py``; the MuJoCo twin's agreement checks can tap the same).
    ``axial``: the tap is on the bore C along the chord instead, and the response the stretch |C − B'| − L.
    The chain rod's; :func:`twin.reference.flexible_tap.tap_response` takes either rod."""
    from twin.natural_coordinates import initial_state
    from twin.reference.model import build_params

    prm = lambda c: build_params(c, drive=drive, guide_friction=False)  # noqa: E731
    run = FlexibleRun(cfg, prm(cfg), prm)
    st = initial_state(cfg, theta0, 0.0, run.P)
    run.reset(st)
    lay = run.layout
    n = lay.n
    mid = int(lay.segs[cfg.structure.rod_segments // 2 - 1, 1])   # the middle node (end of the middle segment)
    x = run.x
    q, qd = x[:n].copy(), x[n:2 * n].copy()
    tap_kick(q, qd, mid, speed_mps, axial)
    nc = n - N_Q
    A, LU, piv = np.empty((nc, n)), np.empty((nc, nc)), np.empty(nc, dtype=np.int64)
    if flex_project(run.P, lay.G, q, qd, lay.segs, lay.seg_f, lay.slides, lay.indep, A, LU, piv,
                    np.empty(n), np.empty(n), np.empty(n), np.empty(n), False) < 0:
        raise ValueError("the tapped state does not satisfy the constraints")
    x[:n], x[n:2 * n] = q, qd
    h = cfg.simulation.timestep_s
    steps = int(round(duration_s / (every * h)))
    buf = np.empty((1, N_OUT_FLEX))
    ref = np.full(every, theta0)
    zero = np.zeros(every)
    w = np.empty(steps)
    for i in range(steps):
        status, _ = run.run(st, ref, zero, every, buf)
        if status != OK:
            raise ValueError(f"the tap response failed at step {i * every} (status {status})")
        qq = x[:n]
        ux, uy = qq[4] - qq[2], qq[5] - qq[3]
        if axial:
            w[i] = math.hypot(ux, uy) - cfg.bodies.rod.length_m
        else:
            w[i] = ((qq[mid] - qq[2]) * (-uy) + (qq[mid + 1] - qq[3]) * ux) / math.hypot(ux, uy)
    return (np.arange(steps) + 1) * every * h, w
