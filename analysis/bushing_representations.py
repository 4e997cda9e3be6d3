"""Bushing representations side by side: cost per step and geometric error.

MuJoCo has no concave primitive, so the bore of a bushing must be represented somehow. This
script builds Table 4 test 12 (0.1 mm diametral clearance at B and C, 750 motor rpm) with each
representation, rolls every variant out from the same state at speed with the same drive
input (h = 1e-5 s, all sensors), and prints side by side:

* ``us/step``: best of ``REPEATS`` rollouts of ``STEPS`` steps (``mujoco.rollout``), and the
  ratio to the constraint-free floor of the same model measured in the same run;
* ``geom err / c``: the geometric error of the bore, measured, not computed: the pin is placed
  at eccentricity |e| = c in 3600 directions, MuJoCo's collision runs, and the largest
  |signed distance| it reports, divided by the radial clearance c (0 = exact circle);
* ``fn/(k d + c d')``: normal-force fidelity to the intended linear law (median and max)
  during the rollout, where a representation has one;
* ``friction``: how Coulomb friction is obtained.

Representations:

1. ``bore``: the native pin-in-bore collider (exact circle) with a frictionless
   solref/solimp contact and the native regularized Coulomb friction (the twin's choice);
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

from twin import names as N
from twin.config import preset
from twin.mujoco_engine.builder import build
from twin.mujoco_engine.engine import MujocoEngine

STEPS = 20_000
REPEATS = 3
RING_SIZES = (24, 48, 96)
_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS


def base_config():
    return preset(12).replace(**{"simulation.duration_s": 0.3, "drive.ramp_s": 0.1})


def variant(kind: str, n_ring: int = 0):
    """(model, description of friction) of a representation."""
    cfg = base_config()
    spec, model, info = build(cfg)
    if kind == "bore":
        return model, "native regularized Coulomb"
    if kind == "bore+cone":
        for j in cfg.joints.clearance_joints:
            spec.pair(N.pair(j)).condim = 3
            spec.pair(N.pair(j)).friction = [cfg.contact.mu0, cfg.contact.mu0, 0, 0, 0]
            ud = list(spec.geom(N.bushing(j)).userdata)
            spec.geom(N.bushing(j)).userdata = [ud[0], 0.0, ud[2], ud[3]]  # native friction off
        return spec.compile(), "MuJoCo elliptic cone, condim 3"
    if kind == "ring":
        rod = spec.body(N.ROD)
        for j in cfg.joints.clearance_joints:
            p = spec.pair(N.pair(j))
            solref, solimp = list(p.solref), list(p.solimp)
            spec.delete(p)
            centre = np.array(spec.geom(N.bushing(j)).pos)
            ri = cfg.joints.bushing_radius_m(j)
            half_w = ri * math.tan(math.pi / n_ring)
            for k in range(n_ring):
                beta = 2 * math.pi * k / n_ring
                g = rod.add_geom(name=f"ring_{j}_{k}", type=mujoco.mjtGeom.mjGEOM_BOX,
                                 size=[0.001, half_w, cfg.joints.bushing_length_m / 2],
                                 pos=list(centre + (ri + 0.001) * np.array([math.cos(beta), math.sin(beta), 0])),
                                 quat=[math.cos(beta / 2), 0, 0, math.sin(beta / 2)],
                                 contype=0, conaffinity=0, mass=0, group=3)
                spec.add_pair(geomname1=N.pin(j), geomname2=g.name, condim=3, solref=solref, solimp=solimp,
                              friction=[cfg.contact.mu0, cfg.contact.mu0, 0, 0, 0])
        return spec.compile(), "MuJoCo elliptic cone, condim 3"
    if kind == "tendon":
        for j in cfg.joints.clearance_joints:
            spec.delete(spec.pair(N.pair(j)))
            t = spec.add_tendon(name=f"clearance_{j}", limited=True, range=[0, cfg.joints.radial_m(j)])
            t.wrap_site(N.pin(j))
            t.wrap_site(N.bushing(j))
        for s in list(spec.sensors):
            if s.name.startswith(("contact_", "friction_")):
                spec.delete(s)
        return spec.compile(), "none (limit constraints are frictionless)"
    raise ValueError(kind)


def geometric_error(model: mujoco.MjModel, kind: str) -> float:
    """max |contact distance| over 3600 directions with the pin at |e| = c, divided by c (joint C)."""
    cfg = base_config()
    if kind == "tendon":
        return 0.0  # tendon length = |e| exactly (limit on the distance of the two sites)
    d = mujoco.MjData(model)
    c = cfg.joints.radial_m("C")
    model.pair_margin[:] = 2 * c  # report distances of near, non-touching surfaces too
    slide = model.jnt_qposadr[model.joint(N.SLIDER_SLIDE).id]
    pin = model.geom(N.pin("C")).id
    model.geom_sameframe[pin] = 0  # geom_pos is edited below: do not reuse the body frame
    worst = 0.0
    for alpha in np.linspace(0, 2 * np.pi, 3600, endpoint=False):
        mujoco.mj_resetData(model, d)
        # rod along +x (all angles 0): bushing C at (r + l, 0); put the slider pin at e
        d.qpos[slide] = cfg.bodies.crank.length_m + cfg.bodies.rod.length_m + c * math.cos(alpha)
        # y offset: move the pin geom itself (the slider cannot move in y)
        model.geom_pos[pin, 1] = c * math.sin(alpha)
        mujoco.mj_forward(model, d)
        dists = [d.contact[i].dist for i in range(d.ncon) if pin in (d.contact[i].geom[0], d.contact[i].geom[1])]
        worst = max(worst, abs(min(dists)) if dists else float("inf"))
    model.geom_pos[pin, 1] = 0.0
    model.pair_margin[:] = 0.0
    return worst / c


def steady_state():
    eng = MujocoEngine(base_config())
    for _ in eng.chunks():
        pass
    st = np.empty(mujoco.mj_stateSize(eng.model, _STATE))
    mujoco.mj_getState(eng.model, eng.data, st, _STATE)
    t = eng.data.time + np.arange(STEPS) * eng.cfg.simulation.timestep_s
    th, om = eng.ref(t)
    return st, np.stack([th, om], -1)[None], eng.info


def time_rollout(model, state, ctrl, floor=False):
    m = model
    if floor:
        m = copy.copy(model)
        m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
    d = mujoco.MjData(m)
    sd = np.empty((1, STEPS, m.nsensordata))
    best = math.inf
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        rollout.rollout(m, d, state[None], ctrl, nstep=STEPS, sensordata=sd)
        best = min(best, time.perf_counter() - t0)
    return best / STEPS * 1e6, m, d


def force_fidelity(model, state, ctrl, info):
    """median, max of f_n / (k δ + c δ̇) for the bore contacts over a short stepped run."""
    if not info.contacts:
        return None
    d = mujoco.MjData(model)
    mujoco.mj_setState(model, d, state, _STATE)
    ratios = []
    for i in range(4000):
        d.ctrl[:] = ctrl[0, i]
        mujoco.mj_step(model, d)
        for ci in range(d.ncon):
            con = d.contact[ci]
            name = model.geom(con.geom[0]).name
            j = name[-1]
            if j not in info.contacts or not name.startswith("pin"):
                continue
            a = con.efc_address
            s = info.contacts[j]
            lin = s.stiffness_n_per_m * -d.efc_pos[a] + s.damping_ns_per_m * -d.efc_vel[a]
            if lin > 5:
                ratios.append(d.efc_force[a] / lin)
    return (float(np.median(ratios)), float(np.max(ratios))) if ratios else None


def main() -> None:
    state, ctrl, info = steady_state()
    rows = []
    kinds = [("bore", 0), ("bore+cone", 0)] + [("ring", n) for n in RING_SIZES] + [("tendon", 0)]
    for kind, n in kinds:
        model, friction = variant(kind, n)
        us, _, _ = time_rollout(model, state, ctrl)
        floor, _, _ = time_rollout(model, state, ctrl, floor=True)
        err = geometric_error(model, kind)
        fid = force_fidelity(model, state, ctrl, info) if kind in ("bore", "bore+cone") else None
        label = f"{kind} {n}" if n else kind
        rows.append((label, us, floor, err, fid, friction))
        print(f"measured {label}", flush=True)
    print()
    print("| representation | us/step | floor us/step | ratio | geom err / c | fn/(k d + c d') median, max | friction |")
    print("|---|---|---|---|---|---|---|")
    for label, us, floor, err, fid, friction in rows:
        f = f"{fid[0]:.3f}, {fid[1]:.2f}" if fid else "n/a"
        print(f"| {label} | {us:.2f} | {floor:.2f} | {us / floor:.2f} | {err:.2e} | {f} | {friction} |")


if __name__ == "__main__":
    main()
