"""Bushing representations side by side: cost per step and geometric error.

MuJoCo has no concave primitive, so the bore of a bushing must be represented somehow. This
script builds Table 4 test 12 (0.1 mm diametral clearance at B and C, 750 motor rpm) with each
representation, rolls every variant out from the same state at speed with the same drive
input (h = 1e-5 s, all sensors), and prints side by side:

* ``us/step``: best of ``REPEATS`` rollouts of ``STEPS`` steps (``mujoco.rollout``, repeats
  interleaved over the variants), and the ratio to the constraint-free floor of the same model
  measured in the same run;
* ``geom err / c``: the geometric error of the bore, measured, not computed: the pin is placed
  at eccentricity |e| = c in 3600 directions, MuJoCo's collision runs, and the largest
  |signed distance| it reports (for the tendon: |tendon length − c|), divided by the radial
  clearance c (0 = exact circle);
* ``pairs per joint``: contact pairs (or tendon limits) that represent one bushing;
* ``friction``: how Coulomb friction is obtained.

Representations (each built by the twin's builder from ``mujoco.bushing`` and
``mujoco.friction``, i.e. exactly what a scene with that setting runs; the bore carries the
reference's contact law applied by the native module, one pair per joint, the others MuJoCo's
soft first-guess contact):

1. ``bore``: the native pin-in-bore collider (exact circle), one frictionless contact whose
   force is the reference's law (native module), and the native regularized Coulomb friction
   (the twin's choice);
2. ``bore+cone``: the same collider with MuJoCo's elliptic friction cone (condim 3, μ = 0.05)
   instead of the native friction;
3. ``ring N``: N boxes whose inner faces form a regular N-gon tangent to the bore, one explicit
   pair per box, condim 3 (N = 24, 48, 96);
4. ``tendon``: a spatial tendon between pin and bushing centres limited to [0, c] (exact circle,
   but a limit constraint has no friction).

Run: ``python analysis/bushing_representations.py`` (about two minutes on 2 cores).
"""

from __future__ import annotations

import copy
import math
import time

import mujoco
import numpy as np
from mujoco import rollout

from twin import names
from twin.config import preset
from twin.mujoco_engine.builder import build
from twin.drive import DriveReference
from twin.mujoco_engine.engine import MujocoEngine
from twin.simulation import run_chunks

STEPS = 20_000
REPEATS = 5
RING_SIZES = (24, 48, 96)
_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS


def base_config():
    return preset(12).replace(**{"simulation.duration_s": 0.3, "drive.ramp_s": 0.1})


def variant(kind: str, n_ring: int = 0):
    """(model, description of friction) of a representation, built by the twin's own builder
    (``mujoco.bushing`` / ``mujoco.friction``), so what is timed is what a scene would run."""
    over = {
        "bore": {},
        "bore+cone": {"mujoco.friction": "cone"},
        "ring": {"mujoco.bushing": "ring", "mujoco.ring_boxes": n_ring, "mujoco.friction": "cone"},
        "tendon": {"mujoco.bushing": "tendon"},
    }[kind]
    _spec, model, _info = build(base_config().replace(**over))
    friction = {"bore": "native regularized Coulomb", "tendon": "none (limit constraints are frictionless)"}
    return model, friction.get(kind, "MuJoCo elliptic cone, condim 3")


def n_constraints(model: mujoco.MjModel, joint: str) -> int:
    """Pairs (or tendon limits) that represent the bushing of ``joint``."""
    pairs = sum(1 for i in range(model.npair) if model.pair(i).name.startswith(names.pair(joint)))
    return pairs or sum(1 for i in range(model.ntendon) if model.tendon(i).name == names.pair(joint))


def geometric_error(model: mujoco.MjModel, kind: str) -> float:
    """Measured geometric error of the bore of joint C, divided by c: the pin is placed at
    |e| = c in 3600 directions and the largest |signed distance| MuJoCo reports (the tendon's
    length minus c for the tendon) is taken (0 = exact circle)."""
    cfg = base_config()
    d = mujoco.MjData(model)
    c = cfg.joints.radial_m("C")
    model.pair_margin[:] = 2 * c  # report distances of near, non-touching surfaces too
    slide = model.jnt_qposadr[model.joint(names.SLIDER_SLIDE).id]
    pin = model.geom(names.pin("C")).id
    tendon = model.tendon(names.pair("C")).id if kind == "tendon" else None
    site = model.site(names.pin("C")).id  # the tendon's end on the pin
    model.geom_sameframe[pin] = 0  # geom_pos is edited below: do not reuse the body frame
    model.site_sameframe[site] = 0
    worst = 0.0
    for alpha in np.linspace(0, 2 * np.pi, 3600, endpoint=False):
        mujoco.mj_resetData(model, d)
        # rod along +x (all angles 0): bushing C at (r + l, 0); put the slider pin at e
        d.qpos[slide] = cfg.bodies.crank.length_m + cfg.bodies.rod.length_m + c * math.cos(alpha)
        # y offset: move the pin geom itself (the slider cannot move in y)
        model.geom_pos[pin, 1] = model.site_pos[site, 1] = c * math.sin(alpha)
        mujoco.mj_forward(model, d)
        if tendon is not None:
            worst = max(worst, abs(d.ten_length[tendon] - c))
            continue
        dists = [d.contact[i].dist for i in range(d.ncon) if pin in (d.contact[i].geom[0], d.contact[i].geom[1])]
        worst = max(worst, abs(min(dists)) if dists else float("inf"))
    model.geom_pos[pin, 1] = model.site_pos[site, 1] = 0.0
    model.pair_margin[:] = 0.0
    return worst / c


def steady_state():
    eng = MujocoEngine(base_config())
    for _ in run_chunks(eng.cfg, engine=eng):
        pass
    st = np.empty(mujoco.mj_stateSize(eng.model, _STATE))
    mujoco.mj_getState(eng.model, eng.data, st, _STATE)
    t = eng.data.time + np.arange(STEPS) * eng.cfg.simulation.timestep_s
    th, om = DriveReference(eng.cfg)(t)
    return st, np.stack([th, om], -1)[None], eng.info


def rollout_time(model, state, ctrl) -> float:
    """Wall time of one rollout of ``STEPS`` steps [s]."""
    d = mujoco.MjData(model)
    sd = np.empty((1, STEPS, model.nsensordata))
    t0 = time.perf_counter()
    rollout.rollout(model, d, state[None], ctrl, nstep=STEPS, sensordata=sd)
    return time.perf_counter() - t0


def floor_model(model):
    """The same model with constraints disabled: the bound below which no constraint setting can go."""
    m = copy.copy(model)
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
    return m


def main() -> None:
    state, ctrl, _info = steady_state()
    kinds = [("bore", 0), ("bore+cone", 0)] + [("ring", n) for n in RING_SIZES] + [("tendon", 0)]
    models = {}
    for kind, n in kinds:
        model, friction = variant(kind, n)
        label = f"{kind} {n}" if n else kind
        models[label] = (kind, model, floor_model(model), friction)
    # interleaved repeats, so that the machine's load hits every variant alike; best of REPEATS
    best = {(label, k): math.inf for label in models for k in ("scene", "floor")}
    for r in range(REPEATS):
        for label, (_, model, floor, _) in models.items():
            best[label, "scene"] = min(best[label, "scene"], rollout_time(model, state, ctrl))
            best[label, "floor"] = min(best[label, "floor"], rollout_time(floor, state, ctrl))
        print(f"timing round {r + 1}/{REPEATS} done", flush=True)
    print()
    print("| representation | us/step | floor us/step | ratio | geom err / c | pairs per joint | friction |")
    print("|---|---|---|---|---|---|---|")
    for label, (kind, model, _, friction) in models.items():
        us, fl = best[label, "scene"] / STEPS * 1e6, best[label, "floor"] / STEPS * 1e6
        err = geometric_error(model, kind)
        print(f"| {label} | {us:.2f} | {fl:.2f} | {us / fl:.2f} | {err:.2e} | {n_constraints(model, 'C')} | {friction} |")


if __name__ == "__main__":
    main()
