"""Contact parameters of the clearance joints, resolved once for both engines.

The reference engine (:func:`twin.reference.model.contact_parameters`) and the MuJoCo twin
(:mod:`twin.mujoco_engine.builder`: its native law and its soft-contact first guess) take the
constants of a joint's contact law from here, so the two engines apply the same numbers:

* hysteresis laws (Lankarani–Nikravesh, Hunt–Crossley, Flores) and ADAMS IMPACT: K of S003
  Eq. 18 (:func:`twin.config.joint_stiffness`: the joint's ``contact.stiffness_of(j)`` if set)
  times ``contact.stiffness_scale`` (:func:`law_stiffness`);
* Johnson's cylindrical law (``johnson-cylindrical``): k = π L E* [N/m] (L the bushing length,
  1/E* = h_i + h_j of Eq. 18, or ``contact.stiffness_of(j)`` if set) times
  ``contact.stiffness_scale``, and the joint's radial clearance ΔR (:func:`cylindrical_stiffness`,
  :func:`johnson_elastic_force`);
* linear law f = k δ + c δ̇: k = ``contact.stiffness_of(j)`` if set, else the linear contact with
  the Lankarani–Nikravesh law's contact duration for an impact at :data:`LINEAR_MATCH_SPEED`
  (:func:`twin.impact.linear_equivalent`), times ``contact.stiffness_scale``; c gives it the
  restitution ``contact.restitution``: c = 2 ζ(e) sqrt(k m_eff), m_eff the effective mass along
  the contact normal (:func:`twin.natural_coordinates.effective_masses`), resolved at the initial
  pose (:func:`joint_contact`, :func:`initial_linear_law`);
* the first guess of a linear soft contact for an effective mass (:func:`first_guess_contact`):
  the same linear equivalent of the LN law, with its own damping.

Importing this module stays light (no numba, no MuJoCo): the mechanism model is imported only
where an effective mass is needed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

from twin.config import BenchConfig, joint_stiffness
from twin.impact import linear_damping_ratio, linear_equivalent
from twin.tracefile import DriveInputs

#: impact speed at which a linear contact matches the Lankarani–Nikravesh contact duration [m/s]:
#: the reference's linear law and the MuJoCo twin's first guess (impact speeds on the bench:
#: 0.4-201 mm/s, ``analysis/impact_speeds.py``)
LINEAR_MATCH_SPEED = 0.1


@dataclass(frozen=True)
class JointContact:
    """Resolved contact parameters of one clearance joint (for run metadata).

    Attributes:
        radial_clearance_m: c [m].
        stiffness: K of the law [N/m^n] (linear law: [N/m]; Johnson cylindrical: k = π L E* [N/m]).
        exponent: n [-].
        damping_ns_per_m: damping of the linear law, c_max of the ADAMS IMPACT law [N s/m] (None for the
            hysteresis laws).
        effective_mass_kg: mass seen along the initial contact normal (reduced mass matrix) [kg].
    """

    radial_clearance_m: float
    stiffness: float
    exponent: float
    damping_ns_per_m: float | None
    effective_mass_kg: float


def law_stiffness(cfg: BenchConfig, joint: str) -> float:
    """K of ``joint``'s hysteresis or ADAMS IMPACT law [N/mⁿ]: S003 Eq. 18 (or the joint's own
    ``contact.stiffness_of``) times ``contact.stiffness_scale``."""
    K = joint_stiffness(cfg, joint)
    K *= cfg.contact.stiffness_scale
    return K


def joint_contact(cfg: BenchConfig, joint: str, m_eff: float) -> JointContact:
    """The contact law constants of ``joint`` for an effective mass ``m_eff`` [kg] along the
    contact normal (see module docstring; m_eff enters the linear law's k and c only)."""
    con = cfg.contact
    radial = cfg.joints.radial_m(joint)
    if con.law == "linear":
        k = con.stiffness_of(joint) if con.stiffness_of(joint) > 0 else \
            linear_equivalent(joint_stiffness(cfg, joint), con.exponent, con.restitution, m_eff,
                              LINEAR_MATCH_SPEED)[0]
        k *= con.stiffness_scale
        c = 2.0 * linear_damping_ratio(con.restitution) * math.sqrt(k * m_eff)
        return JointContact(radial, float(k), 1.0, float(c), m_eff)
    if con.law == "johnson-cylindrical":  # k = π L E*; ΔR the joint's radial clearance
        return JointContact(radial, cylindrical_stiffness(cfg, joint), 1.0, None, m_eff)
    K = law_stiffness(cfg, joint)
    if con.law == "adams-impact":  # K δⁿ + STEP(δ; d_max) c_max δ̇
        return JointContact(radial, float(K), con.exponent, con.impact_c_max_nspm, m_eff)
    return JointContact(radial, float(K), con.exponent, None, m_eff)


def cylindrical_stiffness(cfg: BenchConfig, joint: str) -> float:
    """k = π L E* of ``joint``'s Johnson cylindrical law [N/m] (L the bushing length [m],
    1/E* = (1 − ν_i²)/E_i + (1 − ν_j²)/E_j [1/Pa]), or the joint's ``contact.stiffness_of`` if
    set, times ``contact.stiffness_scale``."""
    k = cfg.contact.stiffness_of(joint)
    if not k > 0:
        m = cfg.materials
        h = m.pin_of(joint).compliance_h + m.bushing_of(joint).compliance_h
        k = math.pi * cfg.joints.bushing_length(joint) / h
    return float(k * cfg.contact.stiffness_scale)


def johnson_elastic_force(delta: float, k: float, dr: float) -> float:
    """Elastic force of a cylinder of length L in a cylindrical bore [N] (Johnson, *Contact
    Mechanics*, 1985, §5.6; the "Johnson" model of Pereira, Ramalho & Ambrósio, Nonlinear Dyn. 63
    (2011) 681–697): the F that solves

        δ = (F / k) [ln(4 ΔR k / F) − 1],   k = π L E* [N/m],  ΔR the radial clearance [m],

    δ the penetration [m]. With z = −e δ / (4 ΔR) the solution is F = −k δ / W₋₁(z), W₋₁ the
    lower branch of Lambert's W (w ≤ −1), found by Halley's iteration. The relation holds up to
    its turning point δ* = 4 ΔR / e² (≈ 0.54 ΔR, F* = k δ*), where dF/dδ is unbounded; beyond
    it the force continues as k δ (outside the model's range: say so where it is reached).
    Plain Python on floats, compiled as it is by the reference engine (numba)."""
    if delta <= 0.0:
        return 0.0
    z = -math.e * delta / (4.0 * dr)
    if z <= -1.0 / math.e:
        return k * delta
    p2 = 2.0 * (1.0 + math.e * z)
    if p2 < 0.25:  # near the branch point: w = -1 - p - p²/3 - ...
        p = math.sqrt(p2)
        w = -1.0 - p - p2 / 3.0
    else:          # asymptotic: w = L - ln(-L), L = ln(-z)
        L1 = math.log(-z)
        w = L1 - math.log(-L1)
    for _ in range(30):
        ew = math.exp(w)
        f = w * ew - z
        wp1 = w + 1.0
        if wp1 == 0.0:
            break
        dw = f / (ew * wp1 - (w + 2.0) * f / (2.0 * wp1))
        w -= dw
        if w > -1.0:
            w = -1.0
        if abs(dw) <= 1e-15 * abs(w):
            break
    return -k * delta / w


_LINEAR_LAWS: dict[str, dict[str, tuple[float, float]]] = {}


def initial_linear_law(cfg: BenchConfig, inputs: DriveInputs | None = None) -> dict[str, tuple[float, float]]:
    """{joint: (k [N/m], c [N s/m])} of the linear law for ``cfg``, resolved as the reference
    engine resolves it: at the drive's initial pose, at rest (c from the effective mass along the
    initial contact normal). The MuJoCo twin's native linear law takes these numbers. ``inputs``: the
    recorded drive trace in memory, if any (its first angle is the pose of a "trace" program)."""
    key = cfg.digest()
    if inputs is not None and inputs.trace is not None and cfg.drive.program == "trace":
        import hashlib

        key += ":" + hashlib.sha256(b"".join(a.tobytes() for a in inputs.trace)).hexdigest()
    if key not in _LINEAR_LAWS:
        import numpy as np

        from twin.drive import DriveReference
        from twin.natural_coordinates import N_Q, S_Q, effective_masses, initial_state, mechanism_params

        P = mechanism_params(cfg)
        theta0 = float(DriveReference(cfg, inputs)(np.array([0.0]))[0][0])
        q = initial_state(cfg, theta0)[S_Q:S_Q + N_Q]
        laws = {}
        for jt, m_eff in effective_masses(cfg, P, q).items():
            jc = joint_contact(cfg, jt, m_eff)
            laws[jt] = (float(jc.stiffness), float(jc.damping_ns_per_m))
        _LINEAR_LAWS[key] = laws
    return _LINEAR_LAWS[key]


@lru_cache(maxsize=64)
def _first_guess_kc(K: float, n: float, e: float, m_eff: float) -> tuple[float, float]:
    return linear_equivalent(K, n, e, m_eff, LINEAR_MATCH_SPEED, law="lankarani-nikravesh")


def first_guess_contact(cfg: BenchConfig, joint: str, m_eff: float) -> tuple[float, float]:
    """First guess (k [N/m], c [N s/m]) of a linear soft contact for ``joint``.

    Method: the Lankarani–Nikravesh law (K from S003 Eq. 18, n, e of the configuration) is
    replaced by the unilateral linear spring-damper that has the same contact duration and the
    same restitution for an impact of the effective mass ``m_eff`` [kg] at
    :data:`LINEAR_MATCH_SPEED`. The MuJoCo twin uses it for the ring and tendon bushings, for
    ``mujoco.contact_source = "first-guess"`` and as the placeholder solref of the native law's
    pair.
    """
    K = joint_stiffness(cfg, joint)
    return _first_guess_kc(float(K), float(cfg.contact.exponent), float(cfg.contact.restitution), float(m_eff))
