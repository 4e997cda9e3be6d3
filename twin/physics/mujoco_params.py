"""MuJoCo parameters of the bench that the planar and the spatial MuJoCo models share: the contact
law of a clearance joint as the native module (``_bore.c``, ``_socket.c``) applies it
(:class:`NativeLaw`), the MuJoCo pair's solref/solimp and where they came from
(:func:`contact_setting`), and the prescribed drive's flywheel (:func:`prescribed_armature`).

Engine-free: numbers from the configuration and :mod:`twin.contact_params` only (no ``mujoco``
import, no model), so that :mod:`twin.mujoco_engine` (planar) and :mod:`twin.spatial.mujoco` take
them from here rather than one from the other.

Contact of a clearance joint (:func:`contact_setting`): with the bore bushing and
``mujoco.contact_source = "law"`` (default) the native module applies the configured reference
law (:class:`NativeLaw`, its constants from :mod:`twin.contact_params`);
``mujoco.contact_solref``/``contact_solimp`` (raw MuJoCo values) or ``contact_source =
"first-guess"`` give MuJoCo's own soft contact instead (the documented linear first guess
:func:`twin.contact_params.first_guess_contact`), which the ring and tendon bushings always use.
"""

from __future__ import annotations

from dataclasses import dataclass

from twin import names as mjcf_names
from twin.config import BenchConfig
from twin.contact_params import (cylindrical_stiffness, first_guess_contact, initial_linear_law, johnson_elastic_force,
                                 law_stiffness)
from twin.impact import DAMPING_FACTOR
from twin.tracefile import DriveInputs

#: flat, tiny impedance: the contact force is then exactly k δ + c δ̇ with a direct solref
#: (−k Â, −c Â), Â the row's inverse-inertia estimate (ENGINEERING_NOTES, re-measured in tests).
#: Also the pair's impedance under the native law: its regularizer R = Â (1 − d)/d is the largest
#: the native module keeps (the residual −a/R it leaves is 1e-4 of the row's inertial force)
FLAT_SOLIMP = (1e-4, 1e-4, 1e-3, 0.5, 2.0)


@dataclass(frozen=True)
class ContactTerm:
    """One MuJoCo pair of a pin/bushing contact law.

    Attributes:
        solref: the pair's solref (2 numbers; negative = direct stiffness/damping).
        solimp: the pair's solimp (5 numbers).
        stiffness_n_per_m: physical stiffness k at full impedance, if defined that way [N/m].
        damping_ns_per_m: physical damping c at full impedance [N s/m].
    """

    solref: tuple[float, float]
    solimp: tuple[float, ...]
    stiffness_n_per_m: float | None = None
    damping_ns_per_m: float | None = None


@dataclass(frozen=True)
class NativeLaw:
    """The reference's contact law of one clearance joint as the native module applies it.

    Force on the pin along the normal, δ the penetration, δ̇ its rate (> 0 approaching), v_imp
    the approach speed stored when the contact event starts (floored at ``speed_floor_mps``):

    * hysteresis laws (LN, Hunt–Crossley, Flores): F = K δⁿ (1 + χ max(δ̇/v_imp, −1)),
      ``damping`` = χ(e) of the law (:data:`twin.impact.DAMPING_FACTOR`);
    * linear law: F = k δ + c δ̇, ``damping`` = c [N s/m];
    * ADAMS IMPACT (``adams-impact``, S001/S004): F = K δⁿ + STEP(δ, 0, 0, d_max, c_max) δ̇,
      ``damping`` = c_max [N s/m], ``d_max_m`` = d_max;
    * Johnson's cylindrical law (``johnson-cylindrical``): F = F_J(δ) (1 + χ max(δ̇/v_imp, −1)),
      F_J :func:`twin.contact_params.johnson_elastic_force` with ``stiffness`` = k = π L E* [N/m]
      and ``d_max_m`` = the radial clearance ΔR [m], χ the Lankarani–Nikravesh factor of e.

    The same numbers as the reference engine (:mod:`twin.physics.contact`), times the twin's
    perturbation factors ``mujoco.contact_stiffness_scale`` (K), ``contact_damping_scale``
    (χ or c) and ``impact_damping_gain`` (χ).

    Attributes:
        law: ``contact.law``.
        stiffness: K [N/mⁿ] (linear: k [N/m]).
        exponent: n [-] (linear: 1).
        damping: χ [-] (linear: c [N s/m]).
        speed_floor_mps: floor of v_imp [m/s] (``contact.impact_speed_floor_mps``).
        d_max_m: penetration of full damping of the ADAMS IMPACT law, radial clearance ΔR of the Johnson
            cylindrical law [m] (0 for the others).
    """

    law: str
    stiffness: float
    exponent: float
    damping: float
    speed_floor_mps: float
    d_max_m: float = 0.0

    @property
    def code(self) -> int:
        """The ``law`` field of the bore user data (:data:`twin.names.BORE_LAWS`)."""
        return mjcf_names.BORE_LAWS[{"linear": "linear", "adams-impact": "impact",
                            "johnson-cylindrical": "cylinder"}.get(self.law, "hysteresis")]

    def userdata(self, slot: int) -> dict[str, float]:
        """The bore user data fields of the law (``slot``: the ``mjData.userdata`` index of v_imp)."""
        return {"law": float(self.code), "stiffness": self.stiffness, "exponent": self.exponent,
                "damping": self.damping, "speed_floor": self.speed_floor_mps, "slot": float(slot),
                "dmax": self.d_max_m}

    def damping_coefficient(self, delta: float, v_imp: float = 1.0) -> float:
        """The law's damping coefficient c at penetration δ [N s/m] (hysteresis: χ K δⁿ/v_imp)."""
        if self.law == "linear":
            return self.damping
        if self.law == "adams-impact":
            x = min(max(delta / self.d_max_m, 0.0), 1.0)
            return self.damping * x * x * (3.0 - 2.0 * x)
        return self.damping * self.elastic_force(delta) / v_imp

    def elastic_force(self, delta: float) -> float:
        """The law's elastic part [N] (hysteresis and Johnson laws): K δⁿ, or F_J(δ)."""
        if self.law == "johnson-cylindrical":
            return johnson_elastic_force(delta, self.stiffness, self.d_max_m)
        return self.stiffness * max(delta, 0.0) ** self.exponent

    def force(self, delta: float, rate: float, v_imp: float) -> float:
        """The law's force [N] (what the native module applies; ≥ 0)."""
        if delta <= 0:
            return 0.0
        if self.law == "linear":
            f = self.stiffness * delta + self.damping * rate
        elif self.law == "adams-impact":
            f = self.stiffness * delta ** self.exponent + self.damping_coefficient(delta) * rate
        else:
            f = self.elastic_force(delta) * (1.0 + self.damping * max(rate / v_imp, -1.0))
        return max(f, 0.0)

    def to_json(self) -> dict:
        out = {"law": self.law, "stiffness": self.stiffness, "exponent": self.exponent, "damping": self.damping,
               "speed_floor_mps": self.speed_floor_mps}
        if self.law == "adams-impact":
            out["d_max_m"] = self.d_max_m
        if self.law == "johnson-cylindrical":
            out["radial_clearance_m"] = self.d_max_m
        return out


@dataclass(frozen=True)
class ContactSetting:
    """MuJoCo parameters of one pin/bushing contact and where they came from.

    Attributes:
        terms: the MuJoCo pair's parameters (one pair per joint; a tuple for the engine's
            contact sensor layout).
        friction: μ0 of the native regularized Coulomb friction [-].
        source: "law" (the native reference law on the contact row; the pair's solref/solimp are its
            placeholder), "force" (the same law as a passive force, no pair),
            "first-guess" (MuJoCo's soft contact, linear first guess) or "config" (the
            configuration's raw solref/solimp).
        law: the native law (source "law"), else None.
    """

    terms: tuple[ContactTerm, ...]
    friction: float
    source: str
    law: NativeLaw | None = None

    # the pair's values
    @property
    def solref(self) -> tuple[float, float]:
        return self.terms[0].solref

    @property
    def solimp(self) -> tuple[float, ...]:
        return self.terms[0].solimp

    @property
    def stiffness_n_per_m(self) -> float | None:
        return self.terms[0].stiffness_n_per_m

    @property
    def damping_ns_per_m(self) -> float | None:
        return self.terms[0].damping_ns_per_m

    def to_json(self) -> dict:
        return {"source": self.source, "friction": self.friction,
                "law": None if self.law is None else self.law.to_json(),
                "terms": [{"solref": list(t.solref), "solimp": [float(v) for v in t.solimp],
                           "stiffness_n_per_m": t.stiffness_n_per_m, "damping_ns_per_m": t.damping_ns_per_m}
                          for t in self.terms]}


# ------------------------------------------------------------------ contact parameters
def native_law_applies(cfg: BenchConfig) -> bool:
    """Whether the clearance joints take the native reference law: bore bushing,
    ``mujoco.contact_source = "law"`` or ``"force"``, no raw ``contact_solref``/``contact_solimp``, and a
    clearance joint to apply it to."""
    ms = cfg.mujoco
    return (ms.bushing == "bore" and ms.contact_source in ("law", "force") and not (ms.contact_solref and ms.contact_solimp)
            and bool(cfg.joints.clearance_joints))


def impact_speed_coefficient(cfg: BenchConfig, joint: str) -> float:
    """χ K of the native impact-speed damping of ``joint`` [N/mⁿ] (hysteresis laws): χ(e) of
    the configured law (LN by default, Hunt–Crossley or Flores) and K of S003 Eq. 18 times
    ``contact.stiffness_scale`` and ``mujoco.contact_stiffness_scale``, times
    ``impact_damping_gain`` and ``contact_damping_scale``."""
    law = native_law(cfg, joint)
    return law.damping * law.stiffness


def native_law(cfg: BenchConfig, joint: str, inputs: DriveInputs | None = None) -> NativeLaw:
    """The reference's contact law of ``joint`` as the native module applies it (:class:`NativeLaw`);
    ``inputs``: the recorded drive trace in memory, if any (the linear law's pose)."""
    ct, ms = cfg.contact, cfg.mujoco
    if ct.law == "linear":
        k, c = initial_linear_law(cfg, inputs)[joint]
        return NativeLaw(ct.law, k * ms.contact_stiffness_scale, 1.0, c * ms.contact_damping_scale,
                         ct.impact_speed_floor_mps)
    if ct.law == "johnson-cylindrical":  # k = π L E*, ΔR in d_max_m, LN damping of e
        chi = DAMPING_FACTOR["lankarani-nikravesh"](ct.restitution)
        return NativeLaw(ct.law, cylindrical_stiffness(cfg, joint) * ms.contact_stiffness_scale, 1.0,
                         chi * ms.impact_damping_gain * ms.contact_damping_scale, ct.impact_speed_floor_mps,
                         cfg.joints.radial_m(joint))
    K = law_stiffness(cfg, joint)
    if ct.law == "adams-impact":
        return NativeLaw(ct.law, K * ms.contact_stiffness_scale, float(ct.exponent),
                         ct.impact_c_max_nspm * ms.contact_damping_scale, ct.impact_speed_floor_mps,
                         ct.impact_d_max_m)
    chi = DAMPING_FACTOR[ct.law](ct.restitution)
    return NativeLaw(ct.law, K * ms.contact_stiffness_scale, float(ct.exponent),
                     chi * ms.impact_damping_gain * ms.contact_damping_scale, ct.impact_speed_floor_mps)


def contact_setting(cfg: BenchConfig, joint: str, a_hat: float, native: bool = True,
                    inputs: DriveInputs | None = None) -> ContactSetting:
    """Resolve the contact of a clearance joint (see module docstring).

    ``native`` is False for representations the native module does not serve (ring of boxes,
    tendon limit): they take MuJoCo's soft contact. The pair's solref/solimp: the configuration's
    raw values, else the first guess (k, c) as a direct solref (−k Â, −c Â) with a flat tiny
    impedance, k and c times ``contact.stiffness_scale`` × ``mujoco.contact_stiffness_scale`` and
    ``mujoco.contact_damping_scale``. With the native law they are only its placeholder.
    """
    mu, ms = cfg.contact.mu0, cfg.mujoco
    if ms.contact_solref and ms.contact_solimp:
        return ContactSetting((ContactTerm(tuple(ms.contact_solref), tuple(ms.contact_solimp)),), mu, "config")
    k, c = first_guess_contact(cfg, joint, 1.0 / a_hat)
    k *= ms.contact_stiffness_scale * cfg.contact.stiffness_scale
    c *= ms.contact_damping_scale
    term = ContactTerm((-k * a_hat, -c * a_hat), FLAT_SOLIMP, k, c)
    if native and ms.contact_source in ("law", "force"):
        return ContactSetting((term,), mu, ms.contact_source, native_law(cfg, joint, inputs))
    return ContactSetting((term,), mu, "first-guess")


# ------------------------------------------------------------------ prescribed drive
#: the prescribed drive's flywheel: armature = this × the crank-side inertia (:func:`prescribed_armature`)
PRESCRIBED_ARMATURE_FACTOR = 1e9


def prescribed_armature(cfg: BenchConfig) -> float:
    """Armature A of the crank hinge for a prescribed drive [kg m²]: 1e9 × the inertia the crank
    drives, I_A(crank) + (m_rod + m_slider) r² (an upper bound of the crank-side inertia of the
    other bodies). The crank's own response to the mechanism's load torque τ is then τ/A; with
    the dead-beat law the angle error it leaves after one step, h² τ/A, is far below the round-off
    of θ (1e-16 rad for the bench at 750 rpm, S004 at 30 rad/s and 5000 rpm)."""
    b = cfg.bodies
    ia = b.crank.inertia_kgm2 + b.crank.mass_kg * b.crank.x_g_m ** 2
    return PRESCRIBED_ARMATURE_FACTOR * (ia + (b.rod.mass_kg + b.slider.mass_kg) * b.crank.length_m ** 2)
