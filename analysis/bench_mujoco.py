"""Speed of the MuJoCo twin: µs per step and real-time factor beside the constraint-free floor.

For the ideal (Table 4 test 3), C-only (test 6) and B+C (test 12) clearance scenes at
h = 1e-5 s, this script measures in one run, interleaved so that machine load hits every
variant alike:

* ``scene``: the twin's compiled model stepping inside ``mujoco.rollout`` (all sensors of the
  default channel groups, 100 kHz output), from a state at full speed (750 motor rpm), with
  the drive reference as control input;
* ``floor``: the same model with constraints disabled (``mjDSBL_CONSTRAINT``: no collision,
  no contact, no loop closure, no guide friction): the lower bound of this model;
* ``ratio`` = scene / floor (the issue's target: clearance scenes within 2x the floor);
* ``engine RTF``: the real-time factor of the whole engine path (``twin.simulate.simulate``:
  reference generation, rollout, channel assembly) over the same simulated time.

Each timing is the best of ``REPEATS`` rollouts of ``STEPS`` steps. Run:
``python analysis/bench_mujoco.py [--steps N] [--repeats R]``.
"""

from __future__ import annotations

import argparse
import copy
import math
import time

import mujoco
import numpy as np
from mujoco import rollout

from twin.config import preset
from twin.mujoco_engine.engine import MujocoEngine
from twin.drive import DriveReference
from twin.simulate import run_chunks, simulate_run

_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
SCENES = {"ideal (test 3)": 3, "C only (test 6)": 6, "B+C (test 12)": 12}


def prepare(test_id: int, steps: int, channels=None):
    """Compiled model, a state at full speed and the control sequence that continues it."""
    over = {"simulation.duration_s": 0.4, "drive.ramp_s": 0.2}
    if channels is not None:
        over["sensors.channels"] = channels
    eng = MujocoEngine(preset(test_id).replace(**over))
    for _ in run_chunks(eng.cfg, engine=eng):
        pass
    state = np.empty(mujoco.mj_stateSize(eng.model, _STATE))
    mujoco.mj_getState(eng.model, eng.data, state, _STATE)
    t = eng.data.time + np.arange(steps) * eng.cfg.simulation.timestep_s
    th, om = DriveReference(eng.cfg)(t)
    return eng.model, state, np.stack([th, om], -1)[None]


def step_time(model, state, ctrl, steps: int) -> float:
    d = mujoco.MjData(model)
    sd = np.empty((1, steps, max(model.nsensordata, 1)))
    t0 = time.perf_counter()
    rollout.rollout(model, d, state[None], ctrl, nstep=steps, sensordata=sd if model.nsensordata else None)
    if abs(d.time - (state[0] + steps * model.opt.timestep)) > 0.5 * model.opt.timestep:
        raise RuntimeError("rollout stopped early (warning)")
    return (time.perf_counter() - t0) / steps * 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=50_000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--lean", action="store_true", help="also time a lean channel set (accel + encoder)")
    args = ap.parse_args()
    variants = {}
    for label, tid in SCENES.items():
        m, s, c = prepare(tid, args.steps)
        floor = copy.copy(m)
        floor.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
        variants[label] = {"scene": (m, s, c), "floor": (floor, s, c)}
        if args.lean:
            ml, sl, cl = prepare(tid, args.steps, channels=["accel", "encoder"])
            variants[label]["lean"] = (ml, sl, cl)
    best = {(lab, k): math.inf for lab, v in variants.items() for k in v}
    for _ in range(args.repeats):  # interleaved repeats
        for lab, v in variants.items():
            for k, (m, s, c) in v.items():
                best[(lab, k)] = min(best[(lab, k)], step_time(m, s, c, args.steps))
    rtf = {}
    for lab, tid in SCENES.items():
        cfg = preset(tid).replace(**{"simulation.duration_s": 1.0, "drive.ramp_s": 0.2})
        rtf[lab] = simulate_run(cfg).meta["real_time_factor"]
    h = 1e-5
    print(f"MuJoCo {mujoco.__version__}, h = {h:g} s, {args.steps} steps, best of {args.repeats} (interleaved)")
    head = "| scene | us/step | RTF | floor us/step | floor RTF | ratio scene/floor | engine RTF (1 s run) |"
    if args.lean:
        head += " lean us/step | lean ratio |"
    print(head)
    print("|" + "---|" * (head.count("|") - 1))
    for lab in SCENES:
        sc, fl = best[(lab, "scene")], best[(lab, "floor")]
        row = (f"| {lab} | {sc:.2f} | {h * 1e6 / sc:.2f} | {fl:.2f} | {h * 1e6 / fl:.2f} | {sc / fl:.2f} | "
               f"{rtf[lab]:.2f} |")
        if args.lean:
            ln = best[(lab, "lean")]
            row += f" {ln:.2f} | {ln / fl:.2f} |"
        print(row)


if __name__ == "__main__":
    main()
