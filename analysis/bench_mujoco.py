"""Speed of the MuJoCo twin: µs per step and real-time factor beside the constraint-free floor.

For the ideal (Table 4 test 3), C-only (test 6) and B+C (test 12) clearance scenes at
h = 1e-5 s, this script measures in one run, interleaved so that machine load hits every
variant alike:

* ``scene``: the twin's compiled model stepping inside ``mujoco.rollout`` (all channels of the
  default channel groups, 100 kHz output), from a state at full speed (750 motor rpm), with
  the drive reference as control input, once per accelerometer setting
  (``mujoco.accelerometers``): "sensor" (MuJoCo's ``<accelerometer>`` sensors, which make each
  step run ``mj_rnePostConstraint``) and "posthoc" (no accelerometer sensor; the rollout also
  returns the state of every step and the timing includes the engine's after-the-rollout
  kinematics of the six readings, ``twin.mujoco_engine.accel``);
* ``floor``: the same model with constraints disabled (``mjDSBL_CONSTRAINT``: no collision,
  no contact, no loop closure, no guide friction): the lower bound of this model;
* ``ratio`` = scene / floor (the issue's target: clearance scenes within 2x the floor);
* ``engine RTF``: the real-time factor of the whole engine path (``twin.simulation.simulate``:
  reference generation, rollout, channel assembly) over the same simulated time;
* ``posthoc / sensor``: the step time of the posthoc setting over the sensor setting's;
* ``force``: the scene with the bushing as a passive force (``mujoco.contact_source = "force"``:
  no collision, contact row or solver), posthoc accelerometers, beside the default "law" and the
  same constraint-free floor.

Each timing is the best of ``REPEATS`` rollouts of ``STEPS`` steps, every variant interleaved.
Run: ``python analysis/bench_mujoco.py [--steps N] [--repeats R] [--lean]``.
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
from twin.simulation import run_chunks, simulate_run

_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
SCENES = {"ideal (test 3)": 3, "C only (test 6)": 6, "B+C (test 12)": 12}
SETTINGS = ("sensor", "posthoc")  # mujoco.accelerometers


def prepare(test_id: int, steps: int, channels=None, accelerometers: str = "sensor", structure: str = "rigid"):
    """Compiled model, a state at full speed and the control sequence that continues it
    (``analysis/profile_stages.py`` and ``profile_scenes.py`` take theirs from here; MuJoCo's
    accelerometer sensors unless ``accelerometers = "posthoc"``; ``structure``: ``structure.mode``)."""
    return prepare_posthoc(test_id, steps, channels, accelerometers, structure=structure)[:3]


def prepare_posthoc(test_id: int, steps: int, channels=None, accelerometers: str = "posthoc",
                    contact_source: str = "law", structure: str = "rigid"):
    """:func:`prepare` and the engine's after-the-rollout accelerometers (None with the sensors);
    ``contact_source``: ``mujoco.contact_source`` ("law", the default, or "force"); ``structure``:
    ``structure.mode`` ("rigid", the default, or "flexible")."""
    over = {"simulation.duration_s": 0.4, "drive.ramp_s": 0.2, "mujoco.accelerometers": accelerometers,
            "mujoco.contact_source": contact_source, "structure.mode": structure}
    if channels is not None:
        over["sensors.channels"] = channels
    eng = MujocoEngine(preset(test_id).replace(**over))
    for _ in run_chunks(eng.cfg, engine=eng):
        pass
    state = np.empty(mujoco.mj_stateSize(eng.model, _STATE))
    mujoco.mj_getState(eng.model, eng.data, state, _STATE)
    t = eng.data.time + np.arange(steps) * eng.cfg.simulation.timestep_s
    th, om = DriveReference(eng.cfg)(t)
    return eng.model, state, np.stack([th, om], -1)[None], eng._accel


def step_time(model, state, ctrl, steps: int, accel=None) -> float:
    """µs per step of one rollout; with ``accel`` (posthoc) the rollout also returns every
    step's state and the time includes the six readings at each (100 kHz) output sample."""
    d = mujoco.MjData(model)
    sd = np.empty((1, steps, max(model.nsensordata, 1)))
    st = np.empty((1, steps, len(state))) if accel is not None else None
    t0 = time.perf_counter()
    rollout.rollout(model, d, state[None], ctrl, nstep=steps, sensordata=sd if model.nsensordata else None,
                    state=st)
    if accel is not None:
        accel(state, st[0], 1, steps)
    wall = time.perf_counter() - t0
    if abs(d.time - (state[0] + steps * model.opt.timestep)) > 0.5 * model.opt.timestep:
        raise RuntimeError("rollout stopped early (warning)")
    return wall / steps * 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=50_000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--lean", action="store_true", help="also time a lean channel set (accel + encoder)")
    ap.add_argument("--rtf-repeats", type=int, default=1, help="1 s engine runs per scene and setting (best kept)")
    args = ap.parse_args()
    variants = {}
    for label, tid in SCENES.items():
        variants[label] = {}
        for acc in SETTINGS:
            m, s, c, post = prepare_posthoc(tid, args.steps, accelerometers=acc)
            floor = copy.copy(m)
            floor.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
            variants[label][("scene", acc)] = (m, s, c, post)
            variants[label][("floor", acc)] = (floor, s, c, post)
        if args.lean:  # the default setting
            ml, sl, cl, pl = prepare_posthoc(tid, args.steps, channels=["accel", "encoder"])
            variants[label][("lean", "posthoc")] = (ml, sl, cl, pl)
        # the bushing as a passive force (mujoco.contact_source = "force"), posthoc accelerometers
        variants[label][("force", "posthoc")] = prepare_posthoc(tid, args.steps, contact_source="force")
    best = {(lab, k): math.inf for lab, v in variants.items() for k in v}
    for _ in range(args.repeats):  # interleaved repeats
        for lab, v in variants.items():
            for k, (m, s, c, post) in v.items():
                best[(lab, k)] = min(best[(lab, k)], step_time(m, s, c, args.steps, post))
    rtf = {}
    for _ in range(args.rtf_repeats):
        for lab, tid in SCENES.items():
            for acc in SETTINGS:
                cfg = preset(tid).replace(**{"simulation.duration_s": 1.0, "drive.ramp_s": 0.2,
                                             "mujoco.accelerometers": acc})
                rtf[(lab, acc)] = max(rtf.get((lab, acc), 0.0), simulate_run(cfg).meta["real_time_factor"])
    h = 1e-5
    print(f"MuJoCo {mujoco.__version__}, h = {h:g} s, {args.steps} steps, best of {args.repeats} (interleaved); "
          f"engine RTF best of {args.rtf_repeats}")
    head = ("| scene | accelerometers | us/step | RTF | floor us/step | floor RTF | ratio scene/floor | "
            "engine RTF (1 s run) |")
    if args.lean:
        head += " lean us/step | lean ratio |"
    print(head)
    print("|" + "---|" * (head.count("|") - 1))
    for lab in SCENES:
        for acc in SETTINGS:
            sc, fl = best[(lab, ("scene", acc))], best[(lab, ("floor", acc))]
            row = (f"| {lab} | {acc} | {sc:.2f} | {h * 1e6 / sc:.2f} | {fl:.2f} | {h * 1e6 / fl:.2f} | "
                   f"{sc / fl:.2f} | {rtf[(lab, acc)]:.2f} |")
            if args.lean:
                if acc == "posthoc":
                    ln = best[(lab, ("lean", "posthoc"))]
                    row += f" {ln:.2f} | {ln / fl:.2f} |"
                else:
                    row += " | |"
            print(row)
    print()
    print("Bushing representation (posthoc accelerometers; floor = the \"law\" model's constraint-free floor, "
          "the same in both):")
    print()
    print("| scene | \"law\" us/step | \"force\" us/step | floor us/step | law / floor | force / floor | "
          "force RTF | law / force |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for lab in SCENES:
        la, fo = best[(lab, ("scene", "posthoc"))], best[(lab, ("force", "posthoc"))]
        fl = best[(lab, ("floor", "posthoc"))]
        print(f"| {lab} | {la:.2f} | {fo:.2f} | {fl:.2f} | {la / fl:.2f} | {fo / fl:.2f} | {h * 1e6 / fo:.2f} | "
              f"{la / fo:.2f} |")
    print()
    print("| scene | posthoc / sensor us/step | posthoc / sensor engine RTF |")
    print("|---|---|---|")
    for lab in SCENES:
        print(f"| {lab} | {best[(lab, ('scene', 'posthoc'))] / best[(lab, ('scene', 'sensor'))]:.3f} | "
              f"{rtf[(lab, 'posthoc')] / rtf[(lab, 'sensor')]:.3f} |")


if __name__ == "__main__":
    main()
