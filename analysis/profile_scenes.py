"""What each default scene skips, and what that saves: µs/step before/after.

The twin builds every scene with only what it needs (``twin/mujoco_engine/builder.py``):
no collision detection at all in an ideal scene, one explicit pair (per contact-law term)
per clearance joint and no other collidable geom, only the sensors of the requested channel
groups, island discovery and Euler damping off (``mjcf/bench.xml``: a 3–5 DOF chain has one
island and no joint damping). This script measures, for Table 4 tests 3 (ideal), 6 (C only)
and 12 (B+C) at h = 1e-5 s, interleaved best-of-``--repeats`` rollouts of ``--steps``:

* ``default``: the scene as built (default channel groups);
* ``before``: the same scene with every skipped item put back — contact detection on, every
  geom collidable (contype/conaffinity 1, parent filtering keeps the touching links apart,
  the extra contacts this creates are excluded so the physics is unchanged), every sensor of
  the base model, island discovery and Euler damping on;
* ``lean``: only the channels a dataset of accelerations needs (accel + encoder);
* ``floor``: constraints off (no contact, loop closure or guide friction): the bound below
  which no constraint setting can go.

Run: ``python analysis/profile_scenes.py [--steps N] [--repeats R]``.
"""

from __future__ import annotations

import argparse
import copy
import math
import sys
from pathlib import Path

import mujoco

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_mujoco import prepare, step_time  # noqa: E402

from twin import names  # noqa: E402
from twin.config import CHANNEL_GROUPS, preset  # noqa: E402
from twin.mujoco_engine.builder import build  # noqa: E402

SCENES = {"ideal (test 3)": 3, "C only (test 6)": 6, "B+C (test 12)": 12}
D = mujoco.mjtDisableBit


def before_model(test_id: int) -> mujoco.MjModel:
    """The scene with everything the builder skips put back (same physics)."""
    cfg = preset(test_id).replace(**{"sensors.channels": list(CHANNEL_GROUPS)})
    spec, _, _ = build(cfg)
    spec.option.disableflags &= ~(D.mjDSBL_CONTACT | D.mjDSBL_ISLAND | D.mjDSBL_EULERDAMP)
    bodies = [b.name for b in spec.bodies if b.name != "world"]
    for g in spec.geoms:
        g.contype, g.conaffinity = 1, 1
    # keep the physics: exclude every body pair (the explicit pin/bushing pairs still act)
    for i, a in enumerate(["world"] + bodies):
        for b in bodies[i:]:
            if a != b:
                spec.add_exclude(bodyname1=a, bodyname2=b)
    return spec.compile()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20_000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    variants = {}
    for label, tid in SCENES.items():
        m, s, c = prepare(tid, args.steps)
        ml, sl, cl = prepare(tid, args.steps, channels=["accel", "encoder"])
        full = prepare(tid, args.steps, channels=list(CHANNEL_GROUPS))
        mb = before_model(tid)
        if mb.nq != m.nq:
            raise RuntimeError("before-model differs in state size")
        floor = copy.copy(m)
        floor.opt.disableflags |= D.mjDSBL_CONSTRAINT
        variants[label] = {"before": (mb, full[1], full[2]), "default": (m, s, c), "lean": (ml, sl, cl),
                           "floor": (floor, s, c)}
    best = {(lab, k): math.inf for lab, v in variants.items() for k in v}
    for _ in range(args.repeats):
        for lab, v in variants.items():
            for k, (mm, ss, cc) in v.items():
                best[(lab, k)] = min(best[(lab, k)], step_time(mm, ss, cc, args.steps))
    print(f"MuJoCo {mujoco.__version__}, h = 1e-5 s, {args.steps} steps, best of {args.repeats} (interleaved)")
    print("| scene | before us/step | default us/step | saved | lean us/step | floor us/step | default/floor |")
    print("|---|---|---|---|---|---|---|")
    for lab in SCENES:
        b, d, ln, f = (best[(lab, k)] for k in ("before", "default", "lean", "floor"))
        print(f"| {lab} | {b:.2f} | {d:.2f} | {1 - d / b:.0%} | {ln:.2f} | {f:.2f} | {d / f:.2f} |")
    print(f"(sensors in the default B+C scene: {variants['B+C (test 12)']['default'][0].nsensor}; "
          f"before: {variants['B+C (test 12)']['before'][0].nsensor}; pair names e.g. {names.pair('C', 1)})")


if __name__ == "__main__":
    main()
