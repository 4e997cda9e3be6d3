"""Where the reference engine's flexible step spends its time (``structure.mode = "flexible"`` against ``"rigid"``).

1. *The whole step*, in the run: Table 4 tests 3 and 12 (``--tests``), ``--duration`` s from rest, rigid and flexible
   interleaved, best of ``--rounds`` CPU times of the chunk loop (as ``analysis/bench_structure.py``), per step; the
   step h and the sampling are the configuration's in both modes (the flexible model forces no smaller step and takes
   no sub-steps: one symplectic-Euler step per h, checked here from the runs' step counts).
2. *The flexible step's kernels*, each timed alone in a compiled loop at the state reached after the run (test 12,
   B and C clearances): the constraint rows and their quadratic terms, the sparse KKT factor (Y = M̃⁻¹Φᵀ, W = Φ Y,
   its Cholesky), the mechanism's forces, the chain's elastic forces, the accelerations, one clearance pair's
   constrained response and mobility (two per step while both clearance joints touch; the θ-method reuses them), the
   position/velocity projection, the outputs. What the sum does not
   hold (the laws' damping bound and θ-method while in contact, the drive, the loop itself, the mount filter and the
   channels in Python) is the run's figure minus the sum.
3. *Sizes*: coordinates, constraint rows of the acceleration solve, projection iterations at that state.

One BLAS thread (set before NumPy loads). Writes ``analysis/results/structure/profile_reference_flexible.md``.
Run: ``nice -n 15 python analysis/profile_reference_flexible.py [--duration 0.1] [--rounds 3] [--tests 3,12]``.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from twin.provenance import write_stamped_text  # noqa: E402


def _kernel_loops():
    """Compiled loops, each calling one kernel K times (arguments as the stepping loop passes them)."""
    from twin.jit import njit
    from twin.natural_coordinates import N_Q
    from twin.reference import flexible as F, flexible_kernels as FK, model as RM
    from twin.reference.flexible_kernels import chain_forces, flex_project
    from twin.reference.flexible_kkt import kkt_accelerations, kkt_factor, kkt_rows, pair_response
    from twin.reference.model import generalized_forces

    @njit(cache=False)
    def rows(K, a):
        for _ in range(K):
            kkt_rows(a.P, a.q, a.qd, a.segs, a.slides, a.crow, a.pat, a.pn, 0.0, a.PhiV, a.gam, a.qs2)

    @njit(cache=False)
    def fac(K, a):
        ok = True
        for _ in range(K):
            ok &= kkt_factor(a.P, a.q, a.crow, a.pat, a.pn, a.PhiV, a.Minv, a.cols, a.cn, a.Mcrank, a.kaug, a.Y, a.W,
                             a.sc, a.wlo)
        return ok

    @njit(cache=False)
    def gf(K, a):
        for _ in range(K):
            generalized_forces(a.P, a.q[:N_Q], a.qd[:N_Q], 0.1, a.ca, a.cb, a.cc, a.Q[:N_Q], a.ja, a.jb, a.jc)

    @njit(cache=False)
    def chain(K, a):
        s = 0.0
        for _ in range(K):
            s += chain_forces(a.P, a.q, a.qd, a.segs, a.seg_f, a.hinges, a.hinge_f, a.slides, a.slide_f, a.G, a.Q)
        return s

    @njit(cache=False)
    def acc(K, a):
        for _ in range(K):
            kkt_accelerations(a.q, a.Q, a.crow, a.pat, a.pn, a.PhiV, a.gam, a.Minv, a.cols, a.cn, a.Y, a.W, a.qdd,
                              a.lam)

    @njit(cache=False)
    def mob(K, a):
        s = 0.0
        for _ in range(K):
            s += pair_response(a.Minv, a.Y, a.W, a.crow.shape[0], 0, 0, 1, 2, 3, a.jo, a.z, a.v)
        return s

    @njit(cache=False)
    def proj(K, a):
        it = 0
        for _ in range(K):
            for i in range(a.q.shape[0]):
                a.q2[i] = a.q[i] + a.h * a.qd[i]
                a.qd2[i] = a.qd[i]
            it += flex_project(a.P, a.G, a.q2, a.qd2, a.segs, a.seg_f, a.slides, a.indep, a.A, a.LU, a.piv, a.res,
                               a.dq, a.b, a.tmp, True)
        return it

    @njit(cache=False)
    def copy(K, a):   # the projection loop's own copy, subtracted from it
        for _ in range(K):
            for i in range(a.q.shape[0]):
                a.q2[i] = a.q[i] + a.h * a.qd[i]
                a.qd2[i] = a.qd[i]

    @njit(cache=False)
    def outs(K, a):
        for _ in range(K):
            RM._outputs(a.P, a.q[:N_Q], a.qd[:N_Q], a.qdd[:N_Q], 0.1, a.ja, a.jb, a.jc, a.row)
            FK._rod_sensors(a.P, a.q, a.qdd, a.segs, a.sens, a.row)
            F._structure_outputs(a.P, a.G, a.q, a.segs, a.row)

    return {"constraint rows + quadratic terms (kkt_rows)": rows, "KKT factor: Y, W, Cholesky (kkt_factor)": fac,
            "mechanism forces and contact laws (generalized_forces)": gf,
            "chain elastic + support forces (chain_forces)": chain,
            "accelerations: W⁻¹, q̈ (kkt_accelerations)": acc, "one pair's response and mobility (pair_response)": mob,
            "projection: Newton + velocity (flex_project)": (proj, copy), "outputs + rod sensors": outs}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.1)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--tests", default="3,12")
    ap.add_argument("--loops", type=int, default=200000, help="calls per kernel timing")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "structure"
                                         / "profile_reference_flexible.md"))
    args = ap.parse_args()
    from collections import namedtuple

    from twin.config import preset
    from twin.natural_coordinates import N_Q, S_IN_A, S_IN_B, S_IN_C, S_VIMP_A, S_VIMP_B, S_VIMP_C
    from twin.reference.guide import N_GUIDE_OUT
    from twin.simulation import make_engine, run_chunks

    tests = [int(t) for t in args.tests.split(",")]

    def run(tid, mode, dur):
        cfg = preset(tid).replace(**{"simulation.engine": "reference", "simulation.duration_s": dur,
                                     "structure.mode": mode})
        eng = make_engine(cfg)
        c0 = time.process_time()
        for _ in run_chunks(cfg, eng):
            pass
        return time.process_time() - c0, eng

    for tid in tests:   # warm-up (numba's cache)
        run(tid, "rigid", 0.002), run(tid, "flexible", 0.002)
    best: dict = {}
    engines: dict = {}
    for _ in range(args.rounds):
        for tid in tests:
            for mode in ("rigid", "flexible"):
                t, eng = run(tid, mode, args.duration)
                key = (tid, mode)
                us = t / eng.meta["steps"] * 1e6
                best[key] = min(best.get(key, float("inf")), us)
                engines[key] = eng
    lines = [f"Reference engine, flexible against rigid: Table 4 tests {', '.join(map(str, tests))} from rest, "
             f"{args.duration:g} s simulated, best of {args.rounds} interleaved rounds, CPU time of the chunk loop "
             "per step, one BLAS thread.", "",
             "| test | h rigid [s] | h flexible [s] | steps rigid | steps flexible | rigid µs/step | flexible µs/step "
             "| ratio |", "|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for tid in tests:
        er, ef = engines[(tid, "rigid")], engines[(tid, "flexible")]
        lines.append(f"| {tid} | {er.meta['timestep_s']:g} | {ef.meta['timestep_s']:g} | {er.meta['steps']} | "
                     f"{ef.meta['steps']} | {best[(tid, 'rigid')]:.2f} | {best[(tid, 'flexible')]:.2f} | "
                     f"{best[(tid, 'flexible')] / best[(tid, 'rigid')]:.2f} |")

    # kernels at test 12's final state (the last test's flexible engine)
    eng = engines[(tests[-1], "flexible")]
    fl = eng._flex
    lay = fl.layout
    kk = fl.kkt(False)
    n, nc, mk = lay.n, lay.n - N_Q, kk.crow.shape[0]
    st = eng._st
    cc = np.zeros(6)
    cc[0], cc[1] = st[S_IN_C], st[S_VIMP_C]
    fields = dict(
        P=fl.P, G=lay.G, q=fl.x[:n].copy(), qd=fl.x[n:2 * n].copy(), h=float(eng.cfg.simulation.timestep_s),
        segs=lay.segs, seg_f=lay.seg_f, hinges=lay.hinges, hinge_f=lay.hinge_f, slides=lay.slides,
        slide_f=lay.slide_f, indep=lay.indep, sens=lay.sensors, crow=kk.crow, pat=kk.pat, pn=kk.pn, Minv=kk.Minv,
        cols=kk.cols, cn=kk.cn, wlo=kk.wlo, Mcrank=kk.Mcrank, kaug=kk.kaug, PhiV=np.zeros((mk, kk.pat.shape[1])),
        gam=np.empty(mk), Y=np.empty((mk, n)), W=np.empty((mk, mk)), lam=np.empty(mk), u=np.empty(2 * mk),
        sc=np.empty((3, 5, 5)), qs2=np.empty(N_Q), qdd=np.zeros(n), A=np.empty((nc, n)), LU=np.empty((nc, nc)),
        piv=np.empty(nc, dtype=np.int64), res=np.empty(n), dq=np.empty(n), b=np.empty(n), tmp=np.empty(n),
        Q=np.zeros(n), q2=np.empty(n), qd2=np.empty(n), ca=np.array([st[S_IN_A], st[S_VIMP_A]]),
        cb=np.array([st[S_IN_B], st[S_VIMP_B]]), cc=cc, ja=np.zeros(5), jb=np.zeros(5),
        jc=np.zeros(5 + N_GUIDE_OUT), row=np.zeros(256), jo=np.array([3e-5, 4e-5, 1e-6, 0.0, 0.0]),
        z=np.empty((2, n)), v=np.empty((2, mk)))
    a = namedtuple("Args", fields)(**fields)
    from twin.reference.flexible_kernels import factor

    factor(a.q, a.segs, a.slides, a.indep, a.A, a.LU, a.piv)
    K = args.loops
    timings = {}
    for name, fn in _kernel_loops().items():
        fns = fn if isinstance(fn, tuple) else (fn,)
        per = []
        for f in fns:
            f(10, a)
            t = float("inf")
            for _ in range(3):
                c0 = time.process_time()
                f(K, a)
                t = min(t, time.process_time() - c0)
            per.append(t / K * 1e6)
        timings[name] = per[0] - (per[1] if len(per) > 1 else 0.0)
    iters = _kernel_loops()["projection: Newton + velocity (flex_project)"][0](1, a)
    total = best[(tests[-1], "flexible")]
    always = sum(v for k, v in timings.items() if "mobility" not in k)
    lines += ["", f"Kernels of the flexible step, each alone at the state after test {tests[-1]}'s run "
              f"({n} coordinates, {mk} constraint rows in the acceleration solve, {nc} chain rows in the projection; "
              f"the rigid model: {N_Q} coordinates, rows solved in closed form), µs per call:", "",
              "| kernel | µs | share of the run's flexible step |", "|---|---:|---:|"]
    for name, v in timings.items():
        lines.append(f"| {name} | {v:.3f} | {v / total:.0%} |")
    lines += [f"| sum of the kernels called every step (all but the mobility) | {always:.3f} | {always / total:.0%} |",
              f"| the rest of the run's step (contact: damping bound with the pairs' responses, θ-method; drive; loop; "
              f"mount filter, channels) | {total - always:.3f} | {(total - always) / total:.0%} |",
              f"| the run's flexible step | {total:.3f} | 100% |",
              f"| the run's rigid step (for scale) | {best[(tests[-1], 'rigid')]:.3f} | |", "",
              f"Projection iterations at that state: {iters} (Newton, tolerance {fl.P[0] if False else '1e-10'} m).",
              ""]
    text = "\n".join(lines) + "\n"
    print(text)
    print(f"wrote {write_stamped_text(args.out, text)}")


if __name__ == "__main__":
    main()
