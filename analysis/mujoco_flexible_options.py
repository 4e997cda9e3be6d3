"""MuJoCo stepping options for the flexible structure: cost and effect on the outputs, side by side.

For Table 4 test 12 with ``structure.mode = "flexible"`` (both contact sources) and, as the denominator,
the rigid model (its default Newton solver, and also PGS, to show whether a variant's gain is the flexible model's), this script takes the state at full speed and its control sequence
(``analysis/bench_mujoco.py``'s ``prepare_posthoc``) and rolls out ``--steps`` steps with the twin's options
and with each variant below, interleaved (best of ``--repeats``), timing the rollout plus the after-the-rollout
accelerometers (the twin's default, ``mujoco.accelerometers = "posthoc"``), in CPU time (``time.process_time``:
the wall clock of a shared machine also counts the waits for a core). For each variant it prints µs per
step, the ratio to the rigid model's step and the largest difference of the sensor outputs and the six
accelerometer readings from the twin's options, relative to each channel's largest magnitude (channels that carry
round-off only, below 1e-12 in SI units, left out), over the first 1 ms, 10 ms and the whole rollout:

* ``jacobian dense`` / ``jacobian sparse``: ``opt.jacobian`` (the twin leaves MuJoCo's auto, dense below 60
  degrees of freedom): the same equations, another order of operations;
* ``islands``: constraint islands on (the twin disables them);
* ``CG solver`` / ``Newton solver``: ``opt.solver`` conjugate gradient or Newton instead of the flexible model's
  default projected Gauss–Seidel (``mujoco.flexible_solver``), same tolerance;
* ``no warmstart``: the solver starts from the unconstrained acceleration;
* ``eulerdamp on``: the joint dampers implicit in the Euler step (the twin keeps them explicit, as the
  reference engine does): a different integrator, shown for its cost and its difference.

Run: ``python analysis/mujoco_flexible_options.py [--steps N] [--repeats R]``.
"""

from __future__ import annotations

import argparse
import copy
import sys
import time
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_mujoco import prepare_posthoc  # noqa: E402

D = mujoco.mjtDisableBit


def _variants(m: mujoco.MjModel) -> dict[str, mujoco.MjModel]:
    out = {"twin's options": m}
    for label, edit in (
            ("jacobian dense", lambda o: setattr(o, "jacobian", mujoco.mjtJacobian.mjJAC_DENSE)),
            ("jacobian sparse", lambda o: setattr(o, "jacobian", mujoco.mjtJacobian.mjJAC_SPARSE)),
            ("islands", lambda o: setattr(o, "disableflags", o.disableflags & ~int(D.mjDSBL_ISLAND))),
            ("CG solver", lambda o: setattr(o, "solver", mujoco.mjtSolver.mjSOL_CG)),
            ("Newton solver", lambda o: setattr(o, "solver", mujoco.mjtSolver.mjSOL_NEWTON)),
            ("no warmstart", lambda o: setattr(o, "disableflags", o.disableflags | int(D.mjDSBL_WARMSTART))),
            ("eulerdamp on", lambda o: setattr(o, "disableflags", o.disableflags & ~int(D.mjDSBL_EULERDAMP)))):
        v = copy.copy(m)
        edit(v.opt)
        out[label] = v
    return out


def _run(m, state, ctrl, steps, accel):
    d = mujoco.MjData(m)
    sd = np.empty((1, steps, max(m.nsensordata, 1)))
    st = np.empty((1, steps, len(state)))
    t0 = time.process_time()
    rollout.rollout(m, d, state[None], ctrl, nstep=steps, sensordata=sd if m.nsensordata else None, state=st)
    acc = accel(state, st[0], 1, steps) if accel is not None else np.empty((0, steps))
    cpu = time.process_time() - t0
    return cpu / steps * 1e6, np.concatenate([sd[0].T, acc], axis=0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    scenes = {}
    for src in ("law", "force"):
        m, s, c, acc = prepare_posthoc(12, a.steps, contact_source=src)
        pgs = copy.copy(m)
        pgs.opt.solver = mujoco.mjtSolver.mjSOL_PGS
        scenes[(src, "rigid")] = {"twin's options": m, "PGS solver": pgs}, s, c, acc
        m, s, c, acc = prepare_posthoc(12, a.steps, contact_source=src, structure="flexible")
        scenes[(src, "flexible")] = _variants(m), s, c, acc
    best: dict = {}
    outs: dict = {}
    for _ in range(a.repeats):
        for key, (models, s, c, acc) in scenes.items():
            for label, m in models.items():
                us, y = _run(m, s, c, a.steps, acc)
                k = key + (label,)
                best[k] = min(best.get(k, float("inf")), us)
                outs[k] = y
    print(f"MuJoCo {mujoco.__version__}, test 12 at full speed, {a.steps} steps (h = 1e-5 s), best of {a.repeats}, "
          "rollout + posthoc accelerometers, CPU time")
    print()
    print("| contact source | variant | µs/step | / rigid | largest output difference (relative): first 1 ms | "
          "first 10 ms | all |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for src in ("law", "force"):
        rigid = best[(src, "rigid", "twin's options")]
        print(f"| {src} | rigid model | {rigid:.2f} | 1.00 | | | |")
        print(f"| {src} | rigid model, PGS solver | {best[(src, 'rigid', 'PGS solver')]:.2f} | "
              f"{best[(src, 'rigid', 'PGS solver')] / rigid:.2f} | | | |")
        base = outs[(src, "flexible", "twin's options")]
        scale = np.max(np.abs(base), axis=1)
        # channels that carry round-off only (the out-of-plane component of a planar vector, e.g. ecc_C's z at
        # ~1e-18 m) are left out: their "relative" difference is O(1) noise; every physical channel is above 1e-12
        keep = scale > 1e-12
        base, scale = base[keep], scale[keep]
        for label in scenes[(src, "flexible")][0]:
            y = outs[(src, "flexible", label)][keep]
            diffs = [float(np.max(np.max(np.abs(y[:, :k] - base[:, :k]), axis=1) / scale))
                     for k in (100, 1000, y.shape[1])]
            print(f"| {src} | flexible, {label} | {best[(src, 'flexible', label)]:.2f} | "
                  f"{best[(src, 'flexible', label)] / rigid:.2f} | " + " | ".join(f"{d:.1e}" for d in diffs) + " |")


if __name__ == "__main__":
    main()
