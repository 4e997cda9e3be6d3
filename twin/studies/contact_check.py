"""Check of the twin's pin/bushing contact against the reference law's closed forms.

The MuJoCo twin's contact force at a clearance joint *is* the reference's law
(:class:`twin.physics.mujoco_params.NativeLaw`, applied by ``_bore.c``): nothing is fitted any
more. The former calibration table (a two-pair solref/solimp law fitted to LN single impacts)
and its fit are retired. What remains here checks the law as MuJoCo actually integrates it, in a
probe with the real bore collider and native module, against closed forms:

1. Static penetration: a pin of mass m pressed into the bore by a constant load F settles at
   δ = (F/K)^(1/n) (hysteresis laws; F/k for the linear law). Tolerance 1 %.
2. Free single impacts of a mass m_eff at speeds v log-spaced over 1 mm/s–0.5 m/s
   (:data:`SPEEDS`; bench impacts measured on reference runs span 0.4–201 mm/s,
   ``analysis/impact_speeds.py``): restitution −δ̇(separation)/v, peak force and contact
   duration against the reference's single-impact solution (ODE at tight tolerance,
   :mod:`twin.impact`). Tolerances: restitution ±0.02, peak force 5 %, duration 10 %.
3. Preloaded impacts: the same with a constant load pressing the pin into the wall; the
   reference captures slow impacts (the mass never leaves the wall) and the twin must capture
   the same ones.

The probe is a pin of mass m_eff on a slide joint inside the joint's bore: one DOF along the
contact normal, the twin's timestep and integrator, the builder's own contact setting
(:func:`twin.physics.mujoco_params.contact_setting`). The effective masses a clearance joint sees
over a crank turn come from the twin's model (:func:`effective_masses`, equal to the reference
engine's reduced mass matrix). ``twin check contact`` runs the whole check for every joint
and catalogue clearance at the smallest, median and largest effective mass.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable

import mujoco

import twin.mujoco_log  # noqa: F401 - MuJoCo's warnings kept off the terminal and the folder
import numpy as np

from twin.config import CATALOGUE_DIAMETRAL_MM, BenchConfig, with_overrides
from twin.contact_params import initial_linear_law, law_stiffness
from twin.impact import ImpactResult, impact_hysteresis, impact_linear
from twin.native.collider import check_model, ensure_installed
from twin.names import BORE_USERDATA_FIELDS, bore_userdata, replace_bore_userdata

#: impact speeds of the check [m/s] (1 mm/s to 0.5 m/s). Measured on reference runs
#: (``analysis/impact_speeds.py``, analysis/results/impact_speeds): bench impacts span
#: 0.4-201 mm/s, 97.7 % (C) and 100 % (B) of them inside this range
SPEEDS = tuple(np.geomspace(1e-3, 0.5, 10))
#: tolerances: restitution (absolute), peak force and duration (relative), static
#: penetration (relative)
TOL_E, TOL_F, TOL_T, TOL_STATIC = 0.02, 0.05, 0.10, 0.01
#: horizon of a probe impact: no separation by then = captured [s]
T_MAX_S = 5e-3
#: static loads of the check [N] (a resting pin: the bench's static pin loads are 10-60 N)
STATIC_LOADS_N = (1.0, 10.0, 100.0, 1000.0)
#: preloads and speeds of the capture check (``analysis/preloaded_impacts.py``'s grid)
PRELOADS_N = (10.0, 30.0, 100.0)
PRELOAD_SPEEDS = (0.002, 0.005, 0.008, 0.014, 0.03, 0.1)


# ----------------------------------------------------------------------- probe model
def probe_model(cfg: BenchConfig, joint: str, m_eff: float, preload_n: float = 0.0) -> mujoco.MjModel:
    """1-DOF probe: a pin of mass ``m_eff`` on a slide joint (axis +x, into the wall at +x)
    inside ``joint``'s bore, with the twin's contact setting for ``cfg`` (native law or soft
    contact, exactly as the builder resolves it), frictionless; ``preload_n`` presses the pin
    into the wall (gravity along +x)."""
    from twin.native.collider import as_passive_force
    from twin.physics.mujoco_params import FLAT_SOLIMP, contact_setting, native_law_applies

    ensure_installed()
    rj, ri = cfg.joints.pin_radius(joint), cfg.joints.bushing_radius_m(joint)
    half = cfg.joints.bushing_length(joint) / 2
    spec = mujoco.MjSpec()
    spec.compiler.autolimits = True
    spec.nuser_geom = len(BORE_USERDATA_FIELDS)
    spec.nuserdata = 1
    spec.option.timestep = cfg.simulation.timestep_s
    spec.option.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{cfg.mujoco.integrator.upper()}")
    spec.option.gravity = [preload_n / m_eff, 0, 0]
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_EULERDAMP | mujoco.mjtDisableBit.mjDSBL_ISLAND
    bore = spec.worldbody.add_geom(name="bore", type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[ri, half, 0],
                                   contype=0, conaffinity=0, userdata=bore_userdata(mu0=0.0, v0=1.0, v1=2.0))
    body = spec.worldbody.add_body(name="pin_body")
    body.add_joint(name="x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
    body.explicitinertial = True
    body.mass = m_eff
    body.inertia = [1e-4, 1e-4, 1e-4]
    pin = body.add_geom(name="pin", type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[rj, half, 0],
                        contype=0, conaffinity=0, mass=0)
    pair = spec.add_pair(name="p", geomname1=pin.name, geomname2=bore.name, condim=1, solimp=list(FLAT_SOLIMP))
    spec.add_sensor(name="f", type=mujoco.mjtSensor.mjSENS_CONTACT, objtype=mujoco.mjtObj.mjOBJ_GEOM,
                    objname="pin", reftype=mujoco.mjtObj.mjOBJ_GEOM, refname="bore", intprm=[3, 0, 1])
    a_hat = float(spec.compile().body_invweight0[1, 0])
    native = native_law_applies(cfg) and cfg.mujoco.bushing == "bore"
    setting = contact_setting(cfg, joint, a_hat, native=native)
    pair.solref, pair.solimp = list(setting.solref), list(setting.solimp)
    if setting.law is not None:
        bore.userdata = replace_bore_userdata(list(bore.userdata), **setting.law.userdata(0))
    if setting.source == "force":  # the law as a passive force, no pair (as the builder does)
        spec.nuserdata = 2  # v_imp and the previous step's normal velocity
        pin_id = int(spec.compile().geom("pin").id)
        as_passive_force(spec, pair, bore, pin_id, "f")
        spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    model = spec.compile()
    check_model(model)
    return model


def twin_impacts(cfg: BenchConfig, joint: str, m_eff: float, speeds: Iterable[float] = SPEEDS,
                 preload_n: float = 0.0) -> list[ImpactResult]:
    """Single impacts of the twin's contact at ``speeds`` [m/s], simulated by MuJoCo.

    The pin starts half a step before touching at speed v; the impact ends when the pin is back
    at δ = 0 (duration interpolated between steps; restitution −δ̇/v there); no separation
    within :data:`T_MAX_S` = captured (restitution 0, infinite duration).
    """
    from mujoco import rollout

    model = probe_model(cfg, joint, m_eff, preload_n)
    h, c = model.opt.timestep, cfg.joints.radial_m(joint)
    nstep = int(math.ceil(T_MAX_S / h))
    out = []
    for v in speeds:
        v = float(v)
        data = mujoco.MjData(model)  # fresh data: the stored impact speed starts at 0
        nstate = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        init = np.zeros((1, nstate))
        init[0, 1], init[0, 2] = c - v * h * 0.5, v   # state layout: time, qpos, qvel
        state, sens = rollout.rollout(model, data, init, nstep=nstep)
        x, xd, f = state[0, :, 1], state[0, :, 2], sens[0, :, 1]
        delta = np.concatenate([[init[0, 1] - c], x - c])       # before step k and after it
        t = np.arange(nstep + 1) * h
        k_in = int(np.flatnonzero(delta > 0)[0])
        t_in = t[k_in - 1] + h * (0 - delta[k_in - 1]) / (delta[k_in] - delta[k_in - 1])
        out_idx = np.flatnonzero((np.arange(nstep + 1) > k_in) & (delta <= 0))
        peak = float(f.max())
        if out_idx.size == 0:
            out.append(ImpactResult(0.0, peak, math.inf, float(delta.max())))
            continue
        k = int(out_idx[0])
        t_out = t[k - 1] + h * delta[k - 1] / (delta[k - 1] - delta[k])
        out.append(ImpactResult(restitution=-float(xd[k - 1]) / v, peak_force_n=peak,
                                duration_s=float(t_out - t_in), max_penetration_m=float(delta[:k].max())))
    return out


def reference_law(cfg: BenchConfig, joint: str) -> tuple[str, float, float]:
    """(law, K or k, c of the linear law) of the reference engine for ``joint``."""
    ct = cfg.contact
    if ct.law == "linear":
        k, c = initial_linear_law(cfg)[joint]
        return ct.law, k, c
    return ct.law, law_stiffness(cfg, joint), 0.0


def reference_impacts(cfg: BenchConfig, joint: str, m_eff: float, speeds: Iterable[float] = SPEEDS,
                      preload_n: float = 0.0) -> list[ImpactResult]:
    """Single impacts of the reference law (ODE at tight tolerance, :mod:`twin.impact`)."""
    law, K, c = reference_law(cfg, joint)
    if law == "linear":
        if preload_n:
            raise ValueError("preloaded impacts are solved for the hysteresis laws only")
        return [impact_linear(K, c, m_eff, float(v)) for v in speeds]
    return [impact_hysteresis(law, K, cfg.contact.exponent, cfg.contact.restitution, m_eff, float(v), preload_n)
            for v in speeds]


def impact_errors(twin: list[ImpactResult], ref: list[ImpactResult]) -> np.ndarray:
    """Per speed: [Δe / TOL_E, (F/F_ref − 1)/TOL_F, (T/T_ref − 1)/TOL_T] (|x| ≤ 1 meets the tolerance)."""
    return np.array([[(a.restitution - b.restitution) / TOL_E,
                      (a.peak_force_n / b.peak_force_n - 1) / TOL_F,
                      (a.duration_s / b.duration_s - 1) / TOL_T] for a, b in zip(twin, ref)])


def static_penetration(cfg: BenchConfig, joint: str, m_eff: float, load_n: float,
                       settle_s: float = 0.05) -> tuple[float, float]:
    """(twin, closed form) penetration [m] of a pin pressed into the bore by ``load_n``.

    The probe starts at rest at half the closed-form penetration and settles for ``settle_s``;
    closed form: δ = (F/K)^(1/n) (linear law: F/k).
    """
    from mujoco import rollout

    law, K, _c = reference_law(cfg, joint)
    n = 1.0 if law == "linear" else cfg.contact.exponent
    closed = (load_n / K) ** (1.0 / n)
    model = probe_model(cfg, joint, m_eff, load_n)
    c = cfg.joints.radial_m(joint)
    data = mujoco.MjData(model)
    init = np.zeros((1, mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS)))
    init[0, 1] = c + 0.5 * closed
    nstep = int(round(settle_s / model.opt.timestep))
    state, _ = rollout.rollout(model, data, init, nstep=nstep)
    return float(state[0, -1, 1] - c), closed


# ------------------------------------------------------------------- effective masses
def effective_masses(cfg: BenchConfig, joint: str, n_theta: int = 24, n_dir: int = 24) -> np.ndarray:
    """1/(J M⁻¹ Jᵀ) of the relative pin/bushing motion along in-plane normals, over a turn [kg]."""
    from twin import names
    from twin.mujoco_engine.engine import MujocoEngine

    eng = MujocoEngine(cfg.replace(**{"simulation.duration_s": 0.01}))
    m, d = eng.model, eng.data
    out = []
    pin_b = m.geom_bodyid[m.geom(names.pin(joint)).id]
    bush_b = m.geom_bodyid[m.geom(names.bushing(joint)).id]
    for theta in np.linspace(0, 2 * np.pi, n_theta, endpoint=False):
        eng.reset(float(theta))
        p = d.site_xpos[m.site(names.bushing(joint)).id].copy()
        jp, jb = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        mujoco.mj_jac(m, d, jp, None, p, pin_b)
        mujoco.mj_jac(m, d, jb, None, p, bush_b)
        jrel = jp - jb
        for a in np.linspace(0, np.pi, n_dir, endpoint=False):  # ± directions give the same mass
            J = np.array([math.cos(a), math.sin(a), 0.0]) @ jrel
            x = np.zeros(m.nv)
            mujoco.mj_solveM(m, d, x.reshape(1, -1), J.reshape(1, -1))
            out.append(1.0 / float(J @ x))
    return np.array(out)


# ------------------------------------------------------------------------ the check
def joint_case(cfg: BenchConfig, joint: str, clearance_mm: float) -> BenchConfig:
    """``cfg`` with ``clearance_mm`` (diametral) at both joints (the joint's K and masses)."""
    return with_overrides(cfg, {f"joints.clearance_{joint.lower()}_mm": clearance_mm,
                                f"joints.clearance_{'c' if joint == 'B' else 'b'}_mm": clearance_mm})


@dataclass(frozen=True)
class CaseResult:
    """Check of one joint and clearance (worst over speeds and masses)."""

    key: str
    m_eff_kg: tuple[float, float, float]
    max_scaled_error: tuple[float, float, float]   # [restitution, peak force, duration] / tolerance
    static_error: float                            # worst |δ/δ_closed − 1| over STATIC_LOADS_N
    capture_agrees: bool                           # same captured impacts as the reference
    capture_worst_de: float                        # worst |Δe| of the uncaptured preloaded impacts

    @property
    def ok(self) -> bool:
        return max(self.max_scaled_error) <= 1.0 and self.static_error <= TOL_STATIC and self.capture_agrees

    def to_json(self) -> dict:
        return {"m_eff_kg": {"min": self.m_eff_kg[0], "median": self.m_eff_kg[1], "max": self.m_eff_kg[2]},
                "max_scaled_error": {"restitution": self.max_scaled_error[0], "peak_force": self.max_scaled_error[1],
                                     "duration": self.max_scaled_error[2]},
                "static_error": self.static_error, "capture_agrees": self.capture_agrees,
                "capture_worst_de": self.capture_worst_de, "ok": self.ok}


def check_case(cfg: BenchConfig, joint: str, clearance_mm: float, speeds=SPEEDS) -> CaseResult:
    """Static, free-impact and preloaded-impact checks of one joint and clearance."""
    c = joint_case(cfg, joint, clearance_mm)
    masses = effective_masses(c, joint, n_theta=12, n_dir=12)
    ms = (float(masses.min()), float(np.median(masses)), float(masses.max()))
    err = np.zeros(3)
    for m in ms:
        e = np.abs(impact_errors(twin_impacts(c, joint, m, speeds), reference_impacts(c, joint, m, speeds)))
        err = np.maximum(err, e.max(axis=0))
    static = max(abs(tw / cl - 1) for tw, cl in (static_penetration(c, joint, ms[1], f) for f in STATIC_LOADS_N))
    agrees, worst = True, 0.0
    if c.contact.law != "linear":
        for p in PRELOADS_N:
            for a, b in zip(twin_impacts(c, joint, ms[1], PRELOAD_SPEEDS, p),
                            reference_impacts(c, joint, ms[1], PRELOAD_SPEEDS, p)):
                agrees &= (a.restitution == 0) == (b.restitution == 0)
                if b.restitution > 0:
                    worst = max(worst, abs(a.restitution - b.restitution))
    return CaseResult(f"{joint}:{clearance_mm:g}", ms, tuple(float(x) for x in err), float(static), bool(agrees),
                      float(worst))


def check_joints(joints) -> tuple[str, ...]:
    """The joints a contact check may probe: one or both of B, C (a one-line ConfigError otherwise)."""
    from twin.errors import ConfigError

    joints = tuple(joints)
    if not joints or any(j not in ("B", "C") for j in joints):
        raise ConfigError("joints", f"must be one or both of B, C; got {joints!r}")
    return joints


def contact_check(cfg: BenchConfig, joints=("B", "C"), clearances=CATALOGUE_DIAMETRAL_MM, speeds=SPEEDS,
                  progress: bool = True) -> dict:
    """:func:`check_case` for every joint (some of B, C) and catalogue clearance; the JSON report."""
    from tqdm import tqdm

    joints = check_joints(joints)
    jobs = [(j, cl) for j in joints for cl in clearances if cl > 0]
    cases = [check_case(cfg, j, cl, speeds) for j, cl in tqdm(jobs, disable=not progress, desc="contact check")]
    return {
        "method": "twin/studies/contact_check.py (module docstring): the twin's native contact law in a MuJoCo probe "
                  "(real bore collider and native module) against the reference law's closed forms",
        "law": cfg.contact.law,
        "timestep_s": cfg.simulation.timestep_s,
        "integrator": cfg.mujoco.integrator,
        "speeds_mps": [float(v) for v in speeds],
        "tolerances": {"restitution": TOL_E, "peak_force": TOL_F, "duration": TOL_T, "static": TOL_STATIC},
        "cases": {r.key: r.to_json() for r in cases},
        "ok": all(r.ok for r in cases),
    }
