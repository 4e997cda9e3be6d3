"""PGS against Newton for the flexible structure in MuJoCo: convergence and constraint quality, side by side.

For Table 4 tests 3, 6 and 12 (``structure.mode = "flexible"``, both contact sources; the rigid model with Newton for
scale), this script takes the state at full speed (``analysis/bench_mujoco.py``'s ``prepare_posthoc``) and steps
``--steps`` steps with ``mj_step`` under each solver (the twin's iterations and tolerance), recording per step:
the iterations the solver used (and how often it reached ``opt.iterations``, i.e. stopped unconverged), its
last iteration's improvement and gradient (``mjSolverStat``: PGS stops on the improvement, Newton on the gradient,
both against ``opt.tolerance`` scaled by the mean inertia), MuJoCo's warnings, the loop closure's residual (the equality rows' ``efc_pos``:
ideal joints closed by a ``connect``) and the contact rows' penetration (``efc_pos`` < 0 of the contact rows).

Run: ``python analysis/mujoco_flexible_pgs.py [--steps N]``.
"""

from __future__ import annotations

import argparse
import copy
import sys
from pathlib import Path

import mujoco
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_mujoco import prepare_posthoc  # noqa: E402

C = mujoco.mjtConstraint
SOLVERS = {"Newton": mujoco.mjtSolver.mjSOL_NEWTON, "PGS": mujoco.mjtSolver.mjSOL_PGS}


def stats(m: mujoco.MjModel, state, ctrl, steps: int) -> dict:
    d = mujoco.MjData(m)
    mujoco.mj_setState(m, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    niter = np.zeros(steps, int)
    improv = np.zeros(steps)
    grad = np.zeros(steps)
    eq = np.zeros(steps)
    pen = np.zeros(steps)
    nefc = np.zeros(steps, int)
    for k in range(steps):
        d.ctrl[:] = ctrl[0, k]
        mujoco.mj_step(m, d)
        n = int(d.solver_niter[0])
        niter[k] = n
        nefc[k] = d.nefc
        if n:
            improv[k] = d.solver[n - 1].improvement
            grad[k] = d.solver[n - 1].gradient
        t = d.efc_type[:d.nefc]
        p = d.efc_pos[:d.nefc]
        e = p[t == C.mjCNSTR_EQUALITY]
        eq[k] = np.max(np.abs(e)) if e.size else 0.0
        c = p[(t == C.mjCNSTR_CONTACT_FRICTIONLESS) | (t == C.mjCNSTR_CONTACT_PYRAMIDAL)
              | (t == C.mjCNSTR_CONTACT_ELLIPTIC)]
        pen[k] = max(0.0, -np.min(c)) if c.size else 0.0
    warn = {mujoco.mjtWarning(i).name: int(d.warning[i].number) for i in range(len(d.warning)) if d.warning[i].number}
    active = nefc > 0
    return {"niter_mean": niter[active].mean() if active.any() else 0.0, "niter_max": int(niter.max()),
            "at_cap": int(np.sum(niter >= m.opt.iterations)), "steps_with_rows": int(active.sum()),
            "improv_max": float(improv.max()), "grad_max": float(grad.max()), "eq_max": float(eq.max()), "eq_rms": float(np.sqrt(np.mean(eq**2))),
            "pen_max": float(pen.max()), "pen_mean_in_contact": float(pen[pen > 0].mean()) if (pen > 0).any() else 0.0,
            "contact_steps": int(np.sum(pen > 0)), "warnings": warn, "final_qpos": d.qpos.copy()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--tests", default="3,6,12")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "structure" / "mujoco_flexible_pgs.md"))
    a = ap.parse_args()
    lines: list[str] = []

    def emit(text: str = "") -> None:  # the table goes to the screen and to --out
        lines.append(text)
        print(text, flush=True)

    emit(f"MuJoCo {mujoco.__version__}, tests {a.tests} at full speed, {a.steps} steps (h = 1e-5 s), mj_step")
    emit()
    emit("| test | contact source | model, solver | rows/steps | iterations mean / max | steps at the cap | "
         "largest last improvement / gradient | loop closure |efc_pos| max / rms [m] | penetration max / mean [m] (steps) | warnings |")
    emit("|---|---|---|---:|---:|---:|---:|---:|---:|---|")
    for test in (int(x) for x in a.tests.split(",")):
        for src in ("law", "force"):
            for mode in ("rigid", "flexible"):
                m0, s, c, _ = prepare_posthoc(test, a.steps, contact_source=src, structure=mode)
                for name, sol in SOLVERS.items():
                    m = copy.copy(m0)
                    m.opt.solver = sol
                    r = stats(m, s, c, a.steps)
                    emit(f"| {test} | {src} | {mode}, {name} (cap {m.opt.iterations}, tol {m.opt.tolerance:g}) | "
                         f"{r['steps_with_rows']}/{a.steps} | {r['niter_mean']:.2f} / {r['niter_max']} | "
                         f"{r['at_cap']} | {r['improv_max']:.1e} / {r['grad_max']:.1e} | "
                         f"{r['eq_max']:.2e} / {r['eq_rms']:.2e} | "
                         f"{r['pen_max']:.2e} / {r['pen_mean_in_contact']:.2e} ({r['contact_steps']}) | "
                         f"{r['warnings'] or 'none'} |")

    from twin.provenance import write_stamped_text

    out = write_stamped_text(a.out, "\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
