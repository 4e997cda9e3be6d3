r"""S004's continuous-contact model: the clearance at B as a virtual massless rod.

S004 (Xiao, Song & Zhang 2019, §2.1) assumes that the journal of the
clearance joint B never leaves the bushing wall: the pin centre B and the bushing (rod eye)
centre B' are then a fixed distance c apart, a massless rigid "virtual rod" of length c at an
angle ψ. With the crank prescribed (θ₁(t), S004: 30 rad/s) the mechanism has one degree of
freedom, ψ, whose equation follows from Lagrange's equations. This module derives and integrates
it, and compares it with the contact model (either engine of the twin, ``--preset s004``).

Geometry (bench frame of :mod:`twin.config`: A at the origin, x along the guide, y up; the guide
line y = d_off through A)::

    B  = r (cos θ₁, sin θ₁)                       crank pin centre (prescribed)
    B' = B + c u,   u = (cos ψ, sin ψ)            rod eye (bushing) centre: the virtual rod
    sin θ₂ = (d_off − B'_y)/l,  cos θ₂ > 0        rod angle (rod B'–C of length l)
    G₂ = B' + x_G (cos θ₂, sin θ₂)                rod centre of mass
    x₃ = B'_x + l cos θ₂                          slider (pin C on the guide)

Velocities are linear in (θ̇₁, ψ̇): with Ḃ'_y = r θ̇₁ cos θ₁ + c ψ̇ cos ψ,
θ̇₂ = −Ḃ'_y/(l cos θ₂) and ẋ₃ = Ḃ'_x − l θ̇₂ sin θ₂; accelerations follow by differentiating once
more (l cos θ₂ θ̈₂ = −B̈'_y + l θ̇₂² sin θ₂).

Lagrange's equation for ψ. Kinetic energy T = ½ I_A θ̇₁² + ½ m₂ |Ġ₂|² + ½ I₂ θ̇₂² + ½ m₃ ẋ₃²
(crank about A, rod about its centre of mass, slider translating; the virtual rod is massless and
carries no energy), potential V = m₁ g y_G1 + m₂ g y_G2 (the slider moves along the horizontal
guide; y_G1 does not depend on ψ). Friction is absent (S004 names none) and the contact force acts
along the virtual rod, so it does no virtual work on δψ: the generalized force is zero and

    d/dt ∂T/∂ψ̇ − ∂T/∂ψ + ∂V/∂ψ = 0.

For a holonomic system with position vectors p_i(θ₁, ψ) (scleronomic in ψ), the identity
d/dt ∂(½ m |ṗ|²)/∂ψ̇ − ∂(½ m |ṗ|²)/∂ψ = m p̈·∂p/∂ψ (with ∂ṗ/∂ψ̇ = ∂p/∂ψ) turns this into

    m₂ G̈₂·∂G₂/∂ψ + I₂ θ̈₂ ∂θ₂/∂ψ + m₃ ẍ₃ ∂x₃/∂ψ + m₂ g ∂y_G2/∂ψ = 0,

and since every acceleration is affine in ψ̈ (a = a⁰ + (∂p/∂ψ) ψ̈, a⁰ the acceleration with ψ̈ = 0,
which holds θ̈₁, ψ̇² and θ̇₁² terms), the equation of motion is

    ψ̈ = −[m₂ G̈₂⁰·∂G₂/∂ψ + I₂ θ̈₂⁰ ∂θ₂/∂ψ + m₃ ẍ₃⁰ ∂x₃/∂ψ + m₂ g ∂y_G2/∂ψ]
         / [m₂ |∂G₂/∂ψ|² + I₂ (∂θ₂/∂ψ)² + m₃ (∂x₃/∂ψ)²].

(S004's printed Eq. 3–6 are this equation for slender bars, I_A = m₁ l₁²/3 and I₂ = m₂ l₂²/12 about
the centre of mass, which it writes as m₂ l₂²/3 with the translational term m₂ ẋ₃²; here the bars'
inertias of the configuration are used.) The partial derivatives ∂p/∂ψ are the coefficients of ψ̇
in the velocities, computed exactly by evaluating the velocity functions with (θ̇₁, ψ̇) = (0, 1).

The contact force. Newton–Euler on rod and slider gives the force F of the pin on the rod eye at
B' (x: m₂ G̈₂ₓ + m₃ ẍ₃ = F_x; moment about C of the rod: (B' − C) × F + (G₂ − C) × m₂(g − G̈₂) −
I₂ θ̈₂ = 0). The pin pushes the bore wall away from itself, along −u, so f_N = −F·u is the contact
force the model needs; F·(ẑ × u) must vanish (frictionless contact, a check of the equation of
motion: :func:`ContinuousContact.forces`). Where f_N would have to be negative the journal would
in reality leave the wall: the model's own indicator of separation.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from twin.config import BenchConfig
from twin.errors import ConfigError
from twin.util import json_default


@dataclass(frozen=True)
class Mechanism:
    """The data the continuous-contact model needs (SI units).

    Attributes:
        r: crank length A–B [m]. l: rod length B'–C [m]. c: virtual rod length (radial clearance) [m].
        x_g: rod centre of mass from B' [m]. m2, i2: rod mass [kg] and inertia about G₂ [kg m²].
        m3: slider mass [kg]. g: gravity along −y [m/s²]. d_off: guide line height [m].
    """

    r: float
    l: float
    c: float
    x_g: float
    m2: float
    i2: float
    m3: float
    g: float
    d_off: float = 0.0

    @classmethod
    def from_config(cls, cfg: BenchConfig, radial_clearance_m: float | None = None) -> "Mechanism":
        """The mechanism of a configuration (y vertical), clearance at B (its radial value unless given)."""
        b = cfg.bodies
        g = -cfg.mechanism.gravity_vector[1]
        c = cfg.joints.radial_m("B") if radial_clearance_m is None else radial_clearance_m
        return cls(b.crank.length_m, b.rod.length_m, c, b.rod.x_g_m, b.rod.mass_kg, b.rod.inertia_kgm2,
                   b.slider.mass_kg, g, cfg.mechanism.d_off_m)


class ContinuousContact:
    """S004's one-degree-of-freedom model (module docstring) with a prescribed crank θ₁(t)."""

    def __init__(self, mech: Mechanism):
        self.m = mech

    # -- kinematics: positions, velocities and accelerations for given (θ₁, ψ) and their rates
    def kinematics(self, th1, w1, a1, psi, wpsi, apsi) -> dict[str, np.ndarray]:
        """Everything the model uses, vectorized: B', θ₂ and its rates, G₂ and x₃ with rates."""
        m = self.m
        th1, w1, a1, psi, wpsi, apsi = (np.asarray(v, dtype=float) for v in (th1, w1, a1, psi, wpsi, apsi))
        s1, c1, sp, cp = np.sin(th1), np.cos(th1), np.sin(psi), np.cos(psi)
        bx, by = m.r * c1 + m.c * cp, m.r * s1 + m.c * sp
        bxd = -m.r * s1 * w1 - m.c * sp * wpsi
        byd = m.r * c1 * w1 + m.c * cp * wpsi
        bxdd = -m.r * (c1 * w1 ** 2 + s1 * a1) - m.c * (cp * wpsi ** 2 + sp * apsi)
        bydd = m.r * (c1 * a1 - s1 * w1 ** 2) + m.c * (cp * apsi - sp * wpsi ** 2)
        s2 = (m.d_off - by) / m.l
        c2 = np.sqrt(1.0 - s2 * s2)
        w2 = -byd / (m.l * c2)
        a2 = (-bydd + m.l * s2 * w2 ** 2) / (m.l * c2)
        gx, gy = bx + m.x_g * c2, by + m.x_g * s2
        gxd, gyd = bxd - m.x_g * s2 * w2, byd + m.x_g * c2 * w2
        gxdd = bxdd - m.x_g * (c2 * w2 ** 2 + s2 * a2)
        gydd = bydd + m.x_g * (c2 * a2 - s2 * w2 ** 2)
        x3 = bx + m.l * c2
        x3d = bxd - m.l * s2 * w2
        x3dd = bxdd - m.l * (c2 * w2 ** 2 + s2 * a2)
        return dict(bx=bx, by=by, s2=s2, c2=c2, w2=w2, a2=a2, gx=gx, gy=gy, gxd=gxd, gyd=gyd, gxdd=gxdd,
                    gydd=gydd, x3=x3, x3d=x3d, x3dd=x3dd)

    def psi_acceleration(self, th1, w1, a1, psi, wpsi):
        """ψ̈ from Lagrange's equation (module docstring)."""
        m = self.m
        k0 = self.kinematics(th1, w1, a1, psi, wpsi, 0.0)       # accelerations with ψ̈ = 0
        p = self.kinematics(th1, 0.0, 0.0, psi, 1.0, 0.0)       # partial velocities ∂/∂ψ̇ = ∂/∂ψ
        num = (m.m2 * (k0["gxdd"] * p["gxd"] + k0["gydd"] * p["gyd"]) + m.i2 * k0["a2"] * p["w2"]
               + m.m3 * k0["x3dd"] * p["x3d"] + m.m2 * m.g * p["gyd"])
        den = m.m2 * (p["gxd"] ** 2 + p["gyd"] ** 2) + m.i2 * p["w2"] ** 2 + m.m3 * p["x3d"] ** 2
        return -num / den

    def energy(self, th1, w1, psi, wpsi):
        """T + V of rod and slider [J] (the crank's are prescribed; for the crank held still, w1 = 0,
        this is the conserved energy of the free model)."""
        m = self.m
        k = self.kinematics(th1, w1, 0.0, psi, wpsi, 0.0)
        return (0.5 * m.m2 * (k["gxd"] ** 2 + k["gyd"] ** 2) + 0.5 * m.i2 * k["w2"] ** 2 + 0.5 * m.m3 * k["x3d"] ** 2
                + m.m2 * m.g * k["gy"])

    def forces(self, th1, w1, a1, psi, wpsi, apsi) -> tuple[np.ndarray, np.ndarray]:
        """(f_N, f_T): the force of the pin on the rod eye along −u (contact, > 0 pushing) and
        across it (must be 0: frictionless), from Newton–Euler on rod and slider [N]."""
        m = self.m
        k = self.kinematics(th1, w1, a1, psi, wpsi, apsi)
        fx = m.m2 * k["gxdd"] + m.m3 * k["x3dd"]
        cx, cy = k["x3"], np.full_like(k["x3"], m.d_off)
        # moment about C: (B' − C) × F + (G − C) × m2 (g − a_G) − I θ̈₂ = 0, g = (0, −g)
        rbx, rby = k["bx"] - cx, k["by"] - cy
        rgx, rgy = k["gx"] - cx, k["gy"] - cy
        wx, wy = -m.m2 * k["gxdd"], m.m2 * (-m.g - k["gydd"])
        mom = rgx * wy - rgy * wx - m.i2 * k["a2"]
        # rbx F_y − rby F_x + mom = 0
        fy = (rby * fx - mom) / rbx
        u = np.stack([np.cos(psi), np.sin(psi)])
        return -(fx * u[0] + fy * u[1]), (-fx * u[1] + fy * u[0])

    def simulate(self, t: np.ndarray, theta1, omega1, alpha1, psi0: float, wpsi0: float,
                 rtol: float = 1e-10, atol: float = 1e-12) -> dict[str, np.ndarray]:
        """Integrate ψ over the times ``t`` (scipy's DOP853) with the prescribed crank given as
        functions θ₁(t), ω₁(t), α₁(t); returns ψ, ψ̇, ψ̈, the slider's x, ẋ, ẍ and the contact forces."""
        from scipy.integrate import solve_ivp

        def rhs(tt, y):
            return [y[1], float(self.psi_acceleration(theta1(tt), omega1(tt), alpha1(tt), y[0], y[1]))]

        sol = solve_ivp(rhs, (float(t[0]), float(t[-1])), [psi0, wpsi0], method="DOP853", t_eval=t,
                        rtol=rtol, atol=atol)
        if not sol.success:
            raise RuntimeError(f"continuous-contact model: {sol.message}")
        psi, wpsi = sol.y
        th, w, a = theta1(t), omega1(t), alpha1(t)
        apsi = self.psi_acceleration(th, w, a, psi, wpsi)
        k = self.kinematics(th, w, a, psi, wpsi, apsi)
        fn, ft = self.forces(th, w, a, psi, wpsi, apsi)
        return dict(t=t, psi=psi, wpsi=wpsi, apsi=apsi, x=k["x3"], v=k["x3d"], a=k["x3dd"], fn=fn, ft=ft)

    def quasi_static_start(self, th1: float, w1: float, a1: float = 0.0) -> tuple[float, float]:
        """ψ and ψ̇ that put the virtual rod along the ideal joint's load at θ₁: the journal on the
        side the ideal mechanism's pin force pushes it to (u = −F/|F|, F of the pin on the rod eye),
        its rate by a central difference over ±1 µs of the crank's motion. A start for the model
        without an impact."""
        ideal = ContinuousContact(Mechanism(**{**self.m.__dict__, "c": 0.0}))

        def direction(th):
            # with c = 0 the eye is at B whatever ψ: F from Newton–Euler, ψ irrelevant (take 0)
            k = ideal.kinematics(th, w1, a1, 0.0, 0.0, 0.0)
            m = self.m
            fx = m.m2 * k["gxdd"] + m.m3 * k["x3dd"]
            rbx, rby = k["bx"] - k["x3"], k["by"] - m.d_off
            rgx, rgy = k["gx"] - k["x3"], k["gy"] - m.d_off
            wx, wy = -m.m2 * k["gxdd"], m.m2 * (-m.g - k["gydd"])
            fy = (rby * fx - (rgx * wy - rgy * wx - m.i2 * k["a2"])) / rbx
            return math.atan2(-float(fy), -float(fx))

        dt = 1e-6
        p0 = direction(th1)
        dp = (direction(th1 + w1 * dt) - direction(th1 - w1 * dt))
        dp = (dp + math.pi) % (2 * math.pi) - math.pi
        return p0, dp / (2 * dt)


def phases(fn: np.ndarray, rate_hz: float, impact_max_s: float = 2e-3) -> dict[str, object]:
    """Separation, impact and contact phases of a joint's contact force (S004 Fig. 7).

    Separation: f_N = 0 (journal free in the bushing). A contact event (consecutive samples with
    f_N > 0) shorter than ``impact_max_s`` is an impact (the journal strikes and rebounds); a
    longer one is a contact phase (the journal follows the wall, S004's continuous-contact
    assumption). Returns the time fractions, the number of events of each kind and their peaks."""
    on = fn > 0
    edges = np.flatnonzero(np.diff(np.concatenate([[0], on.astype(np.int8), [0]])))
    starts, stops = edges[0::2], edges[1::2]
    dur = (stops - starts) / rate_hz
    impact = dur < impact_max_s
    n = len(fn)
    peaks = np.array([fn[a:b].max() for a, b in zip(starts, stops)]) if len(starts) else np.zeros(0)
    return dict(
        separation_fraction=float(1 - on.mean()),
        impact_fraction=float(dur[impact].sum() * rate_hz / n),
        contact_fraction=float(dur[~impact].sum() * rate_hz / n),
        impacts=int(impact.sum()), contacts=int((~impact).sum()),
        impact_peak_n=float(peaks[impact].max()) if impact.any() else 0.0,
        contact_peak_n=float(peaks[~impact].max()) if (~impact).any() else 0.0,
        starts=starts, stops=stops, is_impact=impact,
    )


# ------------------------------------------------------------------------ twin study
def run_free(cfg: BenchConfig, duration_s: float, rate_hz: float = 1e5) -> dict:
    """The model alone for ``cfg`` (clearance at B, the crank prescribed at a constant speed, y up),
    from the quasi-static start at the program's initial angle, for ``duration_s``: its time series,
    the crank angle up to which it is valid (f_N ≥ 0 from the start) and its deviation from the ideal
    slider motion up to there."""
    from twin.drive import DriveReference
    from twin.kinematics import slider_kinematics

    check_config(cfg)
    model = ContinuousContact(Mechanism.from_config(cfg))
    ref = DriveReference(cfg)
    th0, w = float(ref(np.zeros(1))[0][0]), ref.start_rate()
    t = np.arange(int(round(duration_s * rate_hz)) + 1) / rate_hz
    psi0, dpsi0 = model.quasi_static_start(th0, w)
    sim = model.simulate(t, lambda tt: th0 + w * np.asarray(tt, float), lambda tt: w + 0 * np.asarray(tt, float),
                         lambda tt: 0 * np.asarray(tt, float), psi0, dpsi0, rtol=1e-9, atol=1e-12)
    m = model.m
    xi, vi, ai = slider_kinematics(th0 + w * t, w, 0.0, m.r, m.l, m.d_off)
    bad = np.flatnonzero(sim["fn"] < 0)
    valid = int(bad[0]) if len(bad) else len(t)
    sl = slice(0, max(valid, 1))
    summary = dict(clearance_radial_m=m.c, crank_rad_s=w, duration_s=duration_s, psi0_rad=psi0, psi_rate0_rad_s=dpsi0,
                   valid_until_s=float(t[sl][-1]), valid_until_crank_deg=float(np.degrees(w * t[sl][-1])),
                   dx_max_m=float(np.max(np.abs(sim["x"][sl] - xi[sl]))),
                   dv_max_mps=float(np.max(np.abs(sim["v"][sl] - vi[sl]))),
                   da_max_mps2=float(np.max(np.abs(sim["a"][sl] - ai[sl]))),
                   fn_max_n=float(sim["fn"].max()), fn_min_n=float(sim["fn"].min()),
                   ft_max_abs_n=float(np.max(np.abs(sim["ft"]))))
    series = dict(t=t, theta=th0 + w * t, psi=sim["psi"], x=sim["x"], v=sim["v"], a=sim["a"], fn=sim["fn"],
                  x_ideal=xi, v_ideal=vi, a_ideal=ai)
    return dict(summary=summary, series=series)


def check_config(cfg: BenchConfig) -> None:
    """The model's assumptions, as one-line errors naming the field: a clearance at B only, a crank
    prescribed at constant speed from t = 0, gravity along −y."""
    from twin.errors import ConfigError

    if cfg.joints.diametral_mm("B") <= 0:
        raise ConfigError("joints.clearance_b_mm", "must be > 0: the continuous-contact model is a clearance at B")
    if cfg.joints.diametral_mm("C") > 0:
        raise ConfigError("joints.clearance_c_mm", "must be 0: the continuous-contact model has its clearance at B only")
    d = cfg.drive
    if d.mode != "prescribed" or d.program != "constant" or d.ramp_s != 0:
        raise ConfigError("drive.mode", "the continuous-contact model needs the crank prescribed at constant speed from "
                                        "t = 0 (drive.mode = \"prescribed\", program = \"constant\", ramp_s = 0)")
    if cfg.mechanism.orientation != "y":
        raise ConfigError("mechanism.orientation", f"must be \"y\" for the continuous-contact model, got "
                                                   f"{cfg.mechanism.orientation!r}")


@dataclass(frozen=True)
class ContinuousContactOptions:
    """What the study runs.

    Attributes:
        out: output folder (created if needed).
        config: the mechanism (:func:`check_config`: a clearance at B, the crank prescribed).
        duration_s: simulated time [s], in (0, 10] (default one crank turn at 30 rad/s; the model
            holds only while the journal stays on the wall, well within a turn).
    """

    out: str | Path
    config: BenchConfig
    duration_s: float = 2 * math.pi / 30.0

    def __post_init__(self) -> None:
        d = self.duration_s
        if isinstance(d, bool) or not isinstance(d, (int, float)) or not (math.isfinite(d) and 0 < d <= 10):
            raise ConfigError("duration_s", f"must lie in (0, 10] s, got {d!r}")
        check_config(self.config)


@dataclass(frozen=True)
class ContinuousContactSummary:
    """The figures of a run of the continuous-contact model (``continuous_contact.json``).

    Attributes:
        clearance_radial_m: radial clearance c at B [m]; crank_rad_s: the crank's rate [rad/s];
            duration_s: the run's length [s].
        psi0_rad, psi_rate0_rad_s: the quasi-static start: the virtual rod's angle [rad] and rate [rad/s].
        valid_until_s, valid_until_crank_deg: how long (time [s], crank angle [deg]) the journal stays on the
            wall (f_N >= 0), the model's assumption.
        dx_max_m, dv_max_mps, da_max_mps2: the slider's largest deviation from the ideal motion until then:
            position [m], velocity [m/s], acceleration [m/s²].
        fn_max_n, fn_min_n: largest and smallest normal force over the run [N]; ft_max_abs_n: largest |tangential
            force| [N].
    """

    clearance_radial_m: float
    crank_rad_s: float
    duration_s: float
    psi0_rad: float
    psi_rate0_rad_s: float
    valid_until_s: float
    valid_until_crank_deg: float
    dx_max_m: float
    dv_max_mps: float
    da_max_mps2: float
    fn_max_n: float
    fn_min_n: float
    ft_max_abs_n: float

    def to_dict(self) -> dict[str, Any]:
        return json.loads(json.dumps({f.name: getattr(self, f.name) for f in dataclasses.fields(self)},
                                     default=json_default))

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "ContinuousContactSummary":
        return cls(**{f.name: d[f.name] for f in dataclasses.fields(cls)})


@dataclass(frozen=True)
class ContinuousContactResult:
    """What the study found: ``summary`` is ``continuous_contact.json`` (the crank angle up to which
    the journal stays on the wall and the slider's deviation from the ideal motion until then);
    ``series`` the time series of ``continuous_contact.npz``."""

    summary: ContinuousContactSummary
    series: dict[str, np.ndarray]

    def to_dict(self) -> dict[str, Any]:
        """The JSON data of ``continuous_contact.json``."""
        return self.summary.to_dict()


def run_study(options: ContinuousContactOptions) -> ContinuousContactResult:
    """Run the model from its quasi-static start and write ``continuous_contact.json``,
    ``continuous_contact.npz`` and ``continuous_contact.png`` to ``options.out``."""
    import io

    from twin.provenance import figure_metadata, stamped
    from twin.util import atomic_write_bytes, atomic_write_json

    cfg = options.config
    out = Path(options.out)
    out.mkdir(exist_ok=True)
    res = run_free(cfg, options.duration_s)
    result = ContinuousContactResult(ContinuousContactSummary.from_dict(res["summary"]), res["series"])
    atomic_write_json(out / "continuous_contact.json", stamped(result.to_dict()))
    buf = io.BytesIO()
    np.savez_compressed(buf, **res["series"])
    atomic_write_bytes(out / "continuous_contact.npz", buf.getvalue())
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = res["series"]
    fig, ax = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    deg = np.degrees(s["theta"] - s["theta"][0])
    ax[0].plot(deg, np.degrees(s["psi"]))
    ax[0].set_ylabel("virtual rod angle ψ [deg]")
    ax[1].plot(deg, s["a"], label="continuous-contact model")
    ax[1].plot(deg, s["a_ideal"], "--", label="ideal joint")
    ax[1].set_ylabel("slider acceleration [m/s²]")
    ax[1].legend()
    ax[2].plot(deg, s["fn"] / 1e3)
    ax[2].axhline(0.0, color="k", lw=0.5)
    ax[2].set_ylabel("contact force f_N [kN]")
    ax[2].set_xlabel("crank angle from the start [deg]")
    fig.suptitle(f"{cfg.name}: continuous-contact model, c = {1e3 * cfg.joints.radial_m('B'):g} mm "
                 f"(valid while f_N >= 0: up to {res['summary']['valid_until_crank_deg']:.1f} deg)")
    fig.tight_layout()
    png = io.BytesIO()
    fig.savefig(png, format="png", dpi=110, metadata=figure_metadata())
    plt.close(fig)
    atomic_write_bytes(out / "continuous_contact.png", png.getvalue())
    return result
