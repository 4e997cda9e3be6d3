"""Approximate warm starts: one spin-up shared by runs whose physical parameters differ (opt-in).

The exact warm starts (:mod:`twin.warm`) share an engine run only between configurations the engine
cannot tell apart. A nuisance identification spec draws its own mechanism for every run (clearance
sizes, contact and guide parameters, speed ripple, start angle, sensor mounts), so no two runs share
anything exactly. What a run's spin-up leaves behind, though, is decided by far fewer things: the
speed, the orientation, the drive, which joints have a clearance. This module shares the spin-up
between the runs that agree on those (:func:`approx_key`), as a stated approximation:

1. **Group**: runs whose configurations agree on everything except :data:`SWITCHED_FIELDS` (and the
   sensor chain's fields, :data:`twin.warm.CHAIN_ONLY_FIELDS`) form a group; the set of joints with a
   clearance is part of the key (their presence changes the model's coordinates). Only MuJoCo runs of
   the "pid" drive with the "constant" program, no clearance at A, no guide play and the rigid
   structure take part (:func:`eligible`); any other run runs fresh.
2. **Spin up once**: the group's first configuration (design order) is simulated from rest to the
   switch time ``switch_s`` (past the drive's ramp); that run goes on to its end unchanged, so the
   first member's file is bit for bit its fresh run's.
3. **Switch**: every other member starts at ``switch_s`` in its own engine (its own clearances,
   contact, guide, ripple, mounts) from the spin-up's mechanism state carried over: the crank angle
   and rate shifted by the difference of the two drive references at that time (start angle and
   ripple), the PID's integral, and the eccentricities at B and C in the spin-up's direction and
   rate of turning, their sizes mapped to the member's clearance (a joint in contact keeps its
   penetration, a pin in flight keeps its place relative to its clearance). Rod and slider follow
   from the loop's kinematics. Before ``switch_s`` the member's file holds the spin-up's motion seen
   through the member's own sensor chain (noise, offsets, DAQ): those samples are not the member's
   physics.
4. **Settle**: the transient of the switch (pins finding their own contact, the PID's integral its
   own load) dies out within ``settle_s``; the member's physics holds from ``valid_from_s`` =
   ``switch_s + settle_s`` on, which its file's metadata records (``warm_start.valid_from_s``) and
   the identification's features skip (:func:`valid_from_s`).

What makes it acceptable, measured (``analysis/warm_approx_check.py``, docs/datasets.md): the
features the identification reads differ between a member started this way and its fresh run by
less than they differ between two fresh runs of the same configuration with another noise seed and
start angle (the repeat-to-repeat scatter). ``tests/test_warm_approx.py`` checks that on a few cases.
It is never on by default: ``twin dataset generate --approx-warm-start`` and the dataset's info say so.
"""

from __future__ import annotations

import hashlib
import json
import math
import time
import tomllib
from dataclasses import dataclass
from typing import Any, Iterable, Sequence

import numpy as np

from twin.config import BenchConfig
from twin.dataset.storage import valid_from_s  # noqa: F401 - where the run files' metadata is read
from twin.errors import TwinError

#: configuration fields a group's members may differ in ("section.field"; the sensor chain's fields
#: too, as for the exact warm starts). The clearance sizes are here, the set of clearance joints is in
#: the key.
SWITCHED_FIELDS = ("joints.clearance_b_mm", "joints.clearance_c_mm", "contact.restitution", "contact.mu0",
                   "contact.stiffness_scale", "mechanism.guide_friction_n", "mujoco.contact_damping_scale",
                   "mujoco.impact_damping_gain", "drive.ripple_pct", "drive.ripple_phase_rad",
                   "drive.initial_encoder_angle_rad", "sensors.accelerometers",
                   "joints.allow_noncatalogue")
#: default switch time after the end of the drive's ramp [s]
SWITCH_AFTER_RAMP_S = 0.05
#: default settling time after the switch [s] (measured: docs/datasets.md)
SETTLE_S = 0.1


class ApproxWarmError(TwinError):
    """An approximate warm start cannot be made (a run not eligible, times out of range)."""


def eligible(cfg: BenchConfig) -> bool:
    """Whether ``cfg`` may take part in an approximate warm start (see the module docstring)."""
    return (cfg.simulation.engine == "mujoco" and cfg.drive.mode == "pid" and cfg.drive.program == "constant"
            and cfg.joints.diametral_mm("A") == 0 and not cfg.joints.guide_play and not cfg.structure.flexible)


def approx_key(cfg: BenchConfig) -> str:
    """Identity of a group (16 hex digits): the configuration without its name, the sensor chain's
    fields and :data:`SWITCHED_FIELDS`, with the set of joints that have a clearance."""
    from twin.warm import CHAIN_ONLY_FIELDS

    d = tomllib.loads(cfg.to_toml())
    d.pop("name", None)
    inst = d.get("instrumentation", {})
    for f in CHAIN_ONLY_FIELDS:
        inst.pop(f, None)
    for path in SWITCHED_FIELDS:
        sec, f = path.split(".")
        d.get(sec, {}).pop(f, None)
    d["clearance_joints"] = list(cfg.joints.clearance_joints)
    return hashlib.sha256(json.dumps(d, sort_keys=True, default=str).encode()).hexdigest()[:16]


def approx_groups(cfgs: Sequence[BenchConfig]) -> list[list[int]]:
    """Indices of ``cfgs`` grouped by :func:`approx_key` (ineligible runs alone), groups in the order
    of their first member, members in the given order."""
    groups: dict[str, list[int]] = {}
    for i, c in enumerate(cfgs):
        groups.setdefault(approx_key(c) if eligible(c) else f"alone-{i}", []).append(i)
    return list(groups.values())


def switch_time(cfg: BenchConfig, switch_s: float | None = None) -> float:
    """The switch time [s] (default: the drive's ramp plus :data:`SWITCH_AFTER_RAMP_S`)."""
    return cfg.drive.ramp_s + SWITCH_AFTER_RAMP_S if switch_s is None else float(switch_s)


# ------------------------------------------------------------------------------------ mechanism state
@dataclass(frozen=True)
class MechanismState:
    """What a member takes over from the spin-up (bench frame).

    Attributes:
        t_s: time [s]; samples: output samples done [-].
        theta, omega: crank angle [rad] and rate [rad/s].
        act: the actuators' states (the PID's integral).
        ecc: joint -> (e, ė): eccentricity pin − bushing [m] and its rate [m/s], for B and C.
        theta_ref, omega_ref: the spin-up's drive reference at t_s [rad], [rad/s].
        userdata: the native contact's stored speeds (per clearance joint: the impact speed of a contact
            event under way, the previous step's normal velocity), carried over as they are: a joint in
            contact keeps its penetration, so its event goes on.
    """

    t_s: float
    samples: int
    theta: float
    omega: float
    act: np.ndarray
    ecc: dict[str, tuple[np.ndarray, np.ndarray]]
    theta_ref: float
    omega_ref: float
    userdata: np.ndarray


def _rot(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


def _drot(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[-s, -c], [c, -s]])


def _q(m, joint: str) -> int:
    return int(m.jnt_qposadr[m.joint(joint).id])


def _v(m, joint: str) -> int:
    return int(m.jnt_dofadr[m.joint(joint).id])


def read_state(engine: Any, cfg: BenchConfig, samples: int) -> MechanismState:
    """The mechanism state of a MuJoCo ``engine`` of ``cfg`` after ``samples`` output samples."""
    from twin import names
    from twin.drive import DriveReference

    m, d = engine.model, engine.data
    th, om = float(d.qpos[_q(m, names.CRANK_HINGE)]), float(d.qvel[_v(m, names.CRANK_HINGE)])
    phi, phid = th + float(d.qpos[_q(m, names.ROD_HINGE)]), om + float(d.qvel[_v(m, names.ROD_HINGE)])
    r, l = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    b_pin = r * np.array([math.cos(th), math.sin(th)])
    b_pin_d = r * om * np.array([-math.sin(th), math.cos(th)])
    e_b, e_bd = np.zeros(2), np.zeros(2)
    if cfg.joints.diametral_mm("B") > 0:
        rel = np.array([d.qpos[_q(m, names.ECC_B_X)], d.qpos[_q(m, names.ECC_B_Y)]])
        reld = np.array([d.qvel[_v(m, names.ECC_B_X)], d.qvel[_v(m, names.ECC_B_Y)]])
        # rel = R(θ)ᵀ (B' − B) = −R(θ)ᵀ e_B  =>  e_B = −R rel, ė_B = −ω R' rel − R rel̇
        e_b = -_rot(th) @ rel
        e_bd = -om * (_drot(th) @ rel) - _rot(th) @ reld
    ecc = {"B": (e_b, e_bd)}
    b_bush, b_bush_d = b_pin - e_b, b_pin_d - e_bd
    u, ud = np.array([math.cos(phi), math.sin(phi)]), phid * np.array([-math.sin(phi), math.cos(phi)])
    c_bush, c_bush_d = b_bush + l * u, b_bush_d + l * ud
    x, xd = float(d.qpos[_q(m, names.SLIDER_SLIDE)]), float(d.qvel[_v(m, names.SLIDER_SLIDE)])
    c_pin, c_pin_d = np.array([x, cfg.mechanism.d_off_m]), np.array([xd, 0.0])
    ecc["C"] = (c_pin - c_bush, c_pin_d - c_bush_d) if cfg.joints.diametral_mm("C") > 0 else (np.zeros(2), np.zeros(2))
    t = samples / cfg.output_rate_hz
    tr, wr = DriveReference(cfg)(np.array([t]))
    return MechanismState(t, int(samples), th, om, np.array(d.act, dtype=np.float64), ecc, float(tr[0]), float(wr[0]),
                          np.array(d.userdata, dtype=np.float64))


def _map_ecc(e: np.ndarray, ed: np.ndarray, c_from: float, c_to: float) -> tuple[np.ndarray, np.ndarray]:
    """An eccentricity of a joint of radial clearance ``c_from`` mapped to one of ``c_to`` [m]: a pin
    in contact (|e| > c) keeps its penetration, one in flight its place relative to the clearance;
    the direction and its rate of turning are kept (e and ė scaled alike)."""
    n = float(np.linalg.norm(e))
    if c_to <= 0 or c_from <= 0:
        return np.zeros(2), np.zeros(2)
    if n < 1e-15:
        return np.zeros(2), ed * (c_to / c_from)
    size = c_to + (n - c_from) if n > c_from else n * (c_to / c_from)
    k = size / n
    return e * k, ed * k


def set_state(engine: Any, cfg: BenchConfig, s: MechanismState, s_cfg: BenchConfig) -> None:
    """Put a MuJoCo ``engine`` of ``cfg`` into the spin-up state ``s`` (of ``s_cfg``), mapped to
    ``cfg`` as the module docstring says."""
    from twin import names
    from twin.drive import DriveReference

    tr, wr = DriveReference(cfg)(np.array([s.t_s]))
    th = s.theta + (float(tr[0]) - s.theta_ref)
    om = s.omega + (float(wr[0]) - s.omega_ref)
    e = {}
    for j in ("B", "C"):
        e[j] = _map_ecc(*s.ecc[j], s_cfg.joints.radial_m(j), cfg.joints.radial_m(j))
    (e_b, e_bd), (e_c, e_cd) = e["B"], e["C"]
    r, l = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    b_pin = r * np.array([math.cos(th), math.sin(th)])
    b_pin_d = r * om * np.array([-math.sin(th), math.cos(th)])
    b_bush, b_bush_d = b_pin - e_b, b_pin_d - e_bd
    sphi = (cfg.mechanism.d_off_m - e_c[1] - b_bush[1]) / l
    if abs(sphi) >= 1:
        raise ApproxWarmError("the rod cannot reach the guide from the spin-up's state")
    phi = math.asin(sphi)
    phid = -(e_cd[1] + b_bush_d[1]) / (l * math.cos(phi))
    c_bush = b_bush + l * np.array([math.cos(phi), math.sin(phi)])
    c_bush_d = b_bush_d + l * phid * np.array([-math.sin(phi), math.cos(phi)])
    c_pin, c_pin_d = c_bush + e_c, c_bush_d + e_cd
    engine.reset(th)  # rest pose, zeroed user data (no contact event under way), as a fresh run
    m, d = engine.model, engine.data
    d.qpos[_q(m, names.CRANK_HINGE)] = th
    d.qvel[_v(m, names.CRANK_HINGE)] = om
    d.qpos[_q(m, names.ROD_HINGE)] = phi - th
    d.qvel[_v(m, names.ROD_HINGE)] = phid - om
    if cfg.joints.diametral_mm("B") > 0:
        rel = -_rot(th).T @ e_b
        reld = -om * (_drot(th).T @ e_b) - _rot(th).T @ e_bd
        d.qpos[_q(m, names.ECC_B_X)], d.qpos[_q(m, names.ECC_B_Y)] = rel
        d.qvel[_v(m, names.ECC_B_X)], d.qvel[_v(m, names.ECC_B_Y)] = reld
    d.qpos[_q(m, names.SLIDER_SLIDE)] = c_pin[0]
    d.qvel[_v(m, names.SLIDER_SLIDE)] = c_pin_d[0]
    if d.act.shape == s.act.shape:
        d.act[:] = s.act
    if d.userdata.shape == s.userdata.shape:
        # the contact events under way go on (a fresh v_imp at the impact-speed floor would make a resting
        # contact's damping the largest the force source allows, for as long as the contact lasts)
        d.userdata[:] = s.userdata
    k = s.samples * cfg.output_stride
    d.time = k * cfg.simulation.timestep_s
    # no forward pass: the rollout starts from this state (a forward pass would run the contact's callback,
    # which updates the stored speeds), as WarmState's restore does
    engine._k = k


class _Resume:
    """``start`` of :func:`twin.simulation.run_chunks` that leaves the engine where it is (the
    spin-up's own continuation)."""

    def __init__(self, samples: int):
        self.samples = samples

    def restore_engine(self, engine: Any, cfg: BenchConfig) -> int:  # noqa: ARG002
        return self.samples


class _Switch:
    """``start`` of :func:`twin.simulation.run_chunks`: a member's engine put into the spin-up's
    mapped state."""

    def __init__(self, state: MechanismState, s_cfg: BenchConfig, info: dict[str, Any]):
        self.state, self.s_cfg, self.info = state, s_cfg, info

    def restore_engine(self, engine: Any, cfg: BenchConfig) -> int:
        set_state(engine, cfg, self.state, self.s_cfg)
        engine.meta["warm_start"] = dict(self.info)
        return self.state.samples


def simulate_approx(cfgs: Sequence[BenchConfig], sinks: Sequence[Iterable[Any]], switch_s: float | None = None,
                    settle_s: float = SETTLE_S) -> list[Any]:
    """Simulate ``cfgs`` (one :func:`approx_key`) sharing one spin-up (module docstring): returns
    each member's :class:`~twin.simulation.Outcome`. The first member's run is its fresh run, bit
    for bit; every other member's metadata carries ``warm_start`` = {"approximate": true,
    "switch_s", "settle_s", "valid_from_s", "spin_up_of"}. On any error every sink not yet closed
    is aborted."""
    from twin.run import Run
    from twin.simulation import Outcome, make_engine, run_chunks
    from twin.summary import SummaryAccumulator

    cfgs = list(cfgs)
    sinks = [list(s) for s in sinks]
    if not cfgs or len(sinks) != len(cfgs):
        raise ValueError(f"simulate_approx: {len(cfgs)} configurations and {len(sinks)} sink lists")
    if len({approx_key(c) for c in cfgs}) != 1 or not all(eligible(c) for c in cfgs):
        raise ApproxWarmError("the configurations are not one group of approximate warm starts (approx_groups)")
    cfg0 = cfgs[0]
    t_sw = switch_time(cfg0, switch_s)
    n_sw = int(round(t_sw * cfg0.output_rate_hz))
    if not (cfg0.drive.ramp_s <= n_sw / cfg0.output_rate_hz and n_sw / cfg0.output_rate_hz + settle_s < cfg0.duration_s):
        raise ApproxWarmError(f"must lie in [{cfg0.drive.ramp_s:g}, {cfg0.duration_s - settle_s:g}) s (after the "
                              f"drive's ramp, settle_s = {settle_s:g} s before the end), got {t_sw!r}", field="switch_s")
    if not (math.isfinite(settle_s) and settle_s >= 0):
        raise ApproxWarmError(f"must be a number >= 0, got {settle_s!r}", field="settle_s")
    info = {"approximate": True, "switch_s": n_sw / cfg0.output_rate_hz, "settle_s": float(settle_s),
            "valid_from_s": n_sw / cfg0.output_rate_hz + float(settle_s), "spin_up_of": cfg0.name}
    closed = [False] * len(cfgs)
    outcomes: list[Any] = []
    try:
        t0 = time.perf_counter()
        eng0 = make_engine(cfg0)
        prefix = list(run_chunks(cfg0, eng0, until=n_sw))
        spin_wall = float(eng0.meta.get("wall_s") or 0.0)
        state = read_state(eng0, cfg0, n_sw)
        for i, (cfg, snk) in enumerate(zip(cfgs, sinks)):
            t1 = time.perf_counter()
            engine = eng0 if i == 0 else make_engine(cfg)
            start = _Resume(n_sw) if i == 0 else _Switch(state, cfg0, info)
            acc = SummaryAccumulator(cfg)
            for chunk in prefix:
                mine = chunk if i == 0 else Run(chunk.t0, chunk.rate_hz, chunk.channels, cfg, chunk.meta)
                acc.update(mine)
                for s in snk:
                    s.write(mine)
            for chunk in run_chunks(cfg, engine, start=start):
                acc.update(chunk)
                for s in snk:
                    s.write(chunk)
            meta = dict(engine.meta)
            if i == 0:
                meta["wall_s"] = float(meta.get("wall_s") or 0.0) + spin_wall
                meta["steps"] = cfg.n_samples * cfg.output_stride
            meta["total_wall_s"] = time.perf_counter() - (t0 if i == 0 else t1)
            summary = acc.result(meta)
            for s in snk:
                s.close(meta, summary)
            closed[i] = True
            outcomes.append(Outcome(meta, summary))
    except BaseException:
        for done, snk in zip(closed, sinks):
            if not done:
                for s in snk:
                    try:
                        s.abort()
                    except Exception:  # noqa: BLE001 - the original error matters
                        pass
        raise
    return outcomes


# ------------------------------------------------------------------ the approximation's measure
def run_features(run: Any, cfg: BenchConfig, skip_s: float = 0.0) -> np.ndarray:
    """Mean over its windows of the identification's features (:mod:`twin.identification.features`)
    of a simulated ``run`` of ``cfg`` seen through ``cfg``'s sensor chain and calibration, as a
    dataset run file gives them (``skip_s``: :func:`valid_from_s`)."""
    from twin.identification.features import features
    from twin.identification.inputs import simulated_inputs

    acc, counts, rate, cpr = simulated_inputs(run, cfg)
    X, _ = features(acc, counts, rate, cpr, skip_s, cfg.mechanism.orientation)
    return X.mean(axis=0)


def compare_case(ref: BenchConfig, cfg: BenchConfig, repeat: BenchConfig, switch_s: float | None = None,
                 settle_s: float = SETTLE_S) -> dict[str, np.ndarray]:
    """Features of one case (:func:`run_features`): ``fresh`` (``cfg`` from rest), ``approx`` (``cfg``
    switched from the spin-up of ``ref``, its features from :func:`valid_from_s` on) and ``repeat``
    (``repeat``: ``cfg`` with another noise seed and start angle, from rest)."""
    from twin.simulation import Collector, simulate

    out = {}
    for name, c in (("fresh", cfg), ("repeat", repeat)):
        col = Collector()
        simulate(c, [col])
        out[name] = run_features(col.run, c)
    a0, a1 = Collector(), Collector()
    outcomes = simulate_approx([ref, cfg], [[a0], [a1]], switch_s, settle_s)
    out["approx"] = run_features(a1.run, cfg, valid_from_s(outcomes[1].meta))
    return out
