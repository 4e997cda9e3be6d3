"""Where a step of the reference engine's flexible structure goes, kernel by kernel (Table 4 test 12).

The scene is run for ``--settle`` s (B+C clearances, flexible structure, default fields) and each compiled kernel
of a step (:mod:`twin.reference.flexible_kernels`, :mod:`twin.reference.flexible_kkt`) is then called
``--calls`` times on that state from a compiled loop (best of ``--repeats``), so the figures exclude Python.
For comparison the R-matrix kernels the step used before (``flex_mass`` building R and the dense Rᵀ M R,
``normal_mobility``, ``flex_solve_acc``) are timed on the same state. The projection is timed after a step
(q ← q + h q̇ with q̇ ← q̇ + h q̈, then Newton and the velocity projection), its iterations counted.
Times are CPU time (``time.process_time``: on a shared machine the wall clock also counts the waits for a core).

Run: ``python analysis/profile_flexible.py [--calls N] [--repeats R]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from twin.jit import njit
from twin.natural_coordinates import N_Q, N_Z
from twin.reference import flexible_kernels as K
from twin.reference import flexible_kkt as KK
from twin.reference import flexible_rmatrix as FR


@njit
def _t_factor(R, q, segs, slides, indep, A, LU, piv):
    for _ in range(R):
        K.factor(q, segs, slides, indep, A, LU, piv)


@njit
def _t_mass(R, P, G, q, qd, segs, seg_f, slides, A, LU, piv, rows, nz, Rt, S, Mb, MR, b, Bm, RtT):
    for _ in range(R):
        FR.flex_mass(P, G, q, qd, segs, seg_f, slides, A, LU, piv, rows, nz, Rt, S, Mb, MR, b, Bm, RtT)


@njit
def _t_mob(R, Rt, Mb, nz, g, W):
    s = 0.0
    for _ in range(R):
        s += FR.normal_mobility(Rt, Mb, nz, False, 0, 1, 2, 3, 0.6, 0.8, g, W)
    return s


@njit
def _t_acc(R, q, Q, nz, Rt, RtT, S, Mb, Mb0, rhs, b, tmp, qdd, P, segs, seg_f, G, taup):
    for _ in range(R):
        Mb[:, :] = Mb0
        FR.flex_solve_acc(q, Q, nz, Rt, RtT, S, Mb, rhs, b, tmp, qdd, P, segs, seg_f, G, False, 0.0, taup)


@njit
def _t_forces(R, P, q, qd, segs, seg_f, hinges, hinge_f, slides, slide_f, G, Q):
    s = 0.0
    for _ in range(R):
        s += K.chain_forces(P, q, qd, segs, seg_f, hinges, hinge_f, slides, slide_f, G, Q)
    return s


@njit
def _t_proj(R, P, G, q0, qd0, qdd, h, segs, seg_f, slides, indep, A, LU, piv, res, dq, b, tmp):
    it = 0
    for _ in range(R):
        q = q0.copy()
        qd = qd0.copy()
        for i in range(q.shape[0]):
            qd[i] += h * qdd[i]
            q[i] += h * qd[i]
        it += K.flex_project(P, G, q, qd, segs, seg_f, slides, indep, A, LU, piv, res, dq, b, tmp, False)
    return it


@njit
def _t_energy(R, P, q, qd, segs, seg_f, hinges, hinge_f, slides, slide_f, G):
    s = 0.0
    for _ in range(R):
        T, V = K.flex_energy(P, q, qd, segs, seg_f, hinges, hinge_f, slides, slide_f, G)
        s += T + V
    return s


@njit
def _t_rows(R, P, q, qd, segs, slides, crow, pat, pn, PhiV, gam):
    qt = np.empty(N_Q)
    for _ in range(R):
        KK.kkt_rows(P, q, qd, segs, slides, crow, pat, pn, 0.0, PhiV, gam, qt)


@njit
def _t_kfactor(R, P, q, crow, pat, pn, PhiV, Minv, cols, cn, Mcrank, kaug, Y, W, sc, wlo):
    for _ in range(R):
        KK.kkt_factor(P, q, crow, pat, pn, PhiV, Minv, cols, cn, Mcrank, kaug, Y, W, sc, wlo)


@njit
def _t_kmob(R, pat, pn, PhiV, Minv, cols, cn, Y, W, m, u):
    s = 0.0
    for _ in range(R):
        s += KK.kkt_mobility(pat, pn, PhiV, Minv, cols, cn, Y, W, m, 0, 1, 2, 3, 0.6, 0.8, u)
    return s


@njit
def _t_kacc(R, q, Q, crow, pat, pn, PhiV, gam, Minv, cols, cn, Y, W, qdd, lam):
    for _ in range(R):
        KK.kkt_accelerations(q, Q, crow, pat, pn, PhiV, gam, Minv, cols, cn, Y, W, qdd, lam)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=20000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--settle", type=float, default=0.05, help="simulated time before the state is taken [s]")
    a = ap.parse_args()
    from twin.config import preset
    from twin.simulation import make_engine, run_chunks

    cfg = preset(12).replace(**{"simulation.engine": "reference", "simulation.duration_s": a.settle,
                                "structure.mode": "flexible"})
    eng = make_engine(cfg)
    for _ in run_chunks(cfg, eng):
        pass
    fr = eng._flex
    lay, P = fr.layout, fr.P
    G, segs, seg_f, slides, indep = lay.G, lay.segs, lay.seg_f, lay.slides, lay.indep
    n = lay.n
    nc = n - N_Q
    q, qd = fr.x[:n].copy(), fr.x[n:2 * n].copy()
    rows = np.empty(N_Z + 4 + nc, dtype=np.int64)
    nz = FR.flex_rows(P, G, indep, rows)
    for k in range(indep.shape[0]):
        rows[nz] = N_Q + segs.shape[0] + slides.shape[0] + k
        nz += 1
    A, LU, piv = np.empty((nc, n)), np.empty((nc, nc)), np.empty(nc, dtype=np.int64)
    Rt, MR, S, Mb = np.empty((nz, n)), np.empty((nz, n)), np.empty(n), np.empty((nz, nz))
    rhs, b, tmp, qdd, res, dq = (np.empty(nz),) + tuple(np.empty(n) for _ in range(5))
    Bm, RtT, gm, W2 = np.empty((nc, nz + 1)), np.empty((n, nz)), np.empty(2 * nz), np.empty((nz, nz))
    Q, taup = np.zeros(n), np.zeros(1)
    h = cfg.simulation.timestep_s
    K.factor(q, segs, slides, indep, A, LU, piv)
    FR.flex_mass(P, G, q, qd, segs, seg_f, slides, A, LU, piv, rows, nz, Rt, S, Mb, MR, b, Bm, RtT)
    Mb0 = Mb.copy()
    K.chain_forces(P, q, qd, segs, seg_f, lay.hinges, lay.hinge_f, slides, lay.slide_f, G, Q)
    FR.flex_solve_acc(q, Q, nz, Rt, RtT, S, Mb, rhs, b, tmp, qdd, P, segs, seg_f, G, False, 0.0, taup)
    kk = fr.kkt(False)
    m = kk.crow.shape[0]
    PhiV, gam, Y, W = np.zeros((m, kk.pat.shape[1])), np.empty(m), np.empty((m, n)), np.empty((m, m))
    u, Qt, lam, qdd2 = np.empty(2 * m), np.empty(n), np.empty(m), np.empty(n)
    KK.kkt_rows(P, q, qd, segs, slides, kk.crow, kk.pat, kk.pn, 0.0, PhiV, gam, np.empty(12))
    sc = np.empty((3, 5, 5))
    KK.kkt_factor(P, q, kk.crow, kk.pat, kk.pn, PhiV, kk.Minv, kk.cols, kk.cn, kk.Mcrank, kk.kaug, Y, W, sc, kk.wlo)
    tests = {
        "step now: kkt_rows (Φ_c, γ_c)": lambda R: _t_rows(R, P, q, qd, segs, slides, kk.crow, kk.pat, kk.pn, PhiV,
                                                             gam),
        "step now: kkt_factor (M̃⁻¹ crank block, Y, W, Cholesky)": lambda R: _t_kfactor(
            R, P, q, kk.crow, kk.pat, kk.pn, PhiV, kk.Minv, kk.cols, kk.cn, kk.Mcrank, kk.kaug, Y, W, sc, kk.wlo),
        "step now: kkt_mobility (per joint in contact)": lambda R: _t_kmob(R, kk.pat, kk.pn, PhiV, kk.Minv, kk.cols,
                                                                            kk.cn, Y, W, m, u),
        "step now: kkt_accelerations": lambda R: _t_kacc(R, q, Q, kk.crow, kk.pat, kk.pn, PhiV, gam, kk.Minv,
                                                          kk.cols, kk.cn, Y, W, qdd2, lam),
        "step before: flex_mass (R, M R, Rᵀ M R; chain solves now block-tridiagonal)": lambda R: _t_mass(R, P, G, q, qd, segs, seg_f, slides, A, LU, piv,
                                                                     rows, nz, Rt, S, Mb, MR, b, Bm, RtT),
        "step before: normal_mobility (per joint in contact)": lambda R: _t_mob(R, Rt, Mb0, nz, gm, W2),
        "step before: flex_solve_acc": lambda R: _t_acc(R, q, Q, nz, Rt, RtT, S, Mb, Mb0, rhs, b, tmp, qdd, P, segs,
                                                         seg_f, G, taup),
        "both: chain_forces (hinges, slides, supports)": lambda R: _t_forces(
            R, P, q, qd, segs, seg_f, lay.hinges, lay.hinge_f, slides, lay.slide_f, G, Q),
        "both: flex_project (Newton + velocity projection)": lambda R: _t_proj(
            R, P, G, q, qd, qdd, h, segs, seg_f, slides, indep, A, LU, piv, res, dq, b, tmp),
        "  of which: factor (chain Jacobian, block-tridiagonal LU)": lambda R: _t_factor(R, q, segs, slides, indep, A,
                                                                                     LU, piv),
        "both: flex_energy (per output sample, channel group energy)": lambda R: _t_energy(
            R, P, q, qd, segs, seg_f, lay.hinges, lay.hinge_f, slides, lay.slide_f, G),
    }
    for f in tests.values():
        f(10)
    print(f"reference, flexible test 12 after {a.settle:g} s: n = {n} coordinates, {nz} independent, "
          f"{m} constraint rows; Newton iterations per projection {_t_proj(100, P, G, q, qd, qdd, h, segs, seg_f, slides, indep, A, LU, piv, res, dq, b, tmp) / 100:g}")
    print()
    print("| kernel | µs per call |")
    print("|---|---:|")
    for name, f in tests.items():
        best = float("inf")
        for _ in range(a.repeats):
            t0 = time.process_time()
            f(a.calls)
            best = min(best, time.process_time() - t0)
        print(f"| {name} | {best / a.calls * 1e6:.3f} |")


if __name__ == "__main__":
    main()
