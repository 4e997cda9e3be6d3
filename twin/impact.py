"""Single-impact analysis of contact force laws (1-DOF, mass m hitting at speed v).

Used for the MuJoCo soft contact's first guess (builder), the reference's linear law, the
check of the twin's native contact law against the reference (``twin check contact``,
:mod:`twin.studies.contact_check`) and tests. The penetration δ obeys m δ̈ = −f(δ, δ̇),
δ(0) = 0, δ̇(0) = v; the contact ends when δ returns to 0 or the force would pull (a
contact cannot adhere). Results: restitution e = −δ̇_end / v, peak force, duration.

Force laws (δ ≥ 0 penetration, δ̇ its rate, v⁻ the impact speed):

* Lankarani–Nikravesh (S003 Eq. 17): f = K δ^n [1 + 3(1 − e²)/4 · δ̇/v⁻]
* Hunt–Crossley: f = K δ^n [1 + 3(1 − e)/2 · δ̇/v⁻]
* Flores et al.: f = K δ^n [1 + 8(1 − e)/(5e) · δ̇/v⁻]
* linear spring-damper: f = k δ + c δ̇ (what a direct-solref MuJoCo contact with flat,
  tiny impedance reproduces exactly)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

#: damping factor χ(e) of each hysteresis law: f = K δ^n (1 + χ δ̇/v⁻)
DAMPING_FACTOR = {
    "lankarani-nikravesh": lambda e: 0.75 * (1.0 - e * e),
    "hunt-crossley": lambda e: 1.5 * (1.0 - e),
    "flores": lambda e: 8.0 * (1.0 - e) / (5.0 * e),
}


@dataclass(frozen=True)
class ImpactResult:
    """Outcome of one impact.

    Attributes:
        restitution: −(separation speed)/(impact speed) [-].
        peak_force_n: maximum contact force [N].
        duration_s: contact duration [s].
        max_penetration_m: maximum penetration [m].
    """

    restitution: float
    peak_force_n: float
    duration_s: float
    max_penetration_m: float


def _integrate(force, m: float, v: float, t_scale: float, preload_n: float = 0.0) -> ImpactResult:
    from scipy.integrate import solve_ivp  # imported here: importing twin.impact stays light

    def rhs(_t, y):
        return [y[1], (preload_n - max(force(y[0], y[1]), 0.0)) / m if y[0] > 0 else 0.0]

    def back(_t, y):
        return y[0]

    back.terminal, back.direction = True, -1
    sol = solve_ivp(rhs, (0.0, 50 * t_scale), [0.0, v], events=back, rtol=1e-10, atol=[1e-16, 1e-12],
                    max_step=t_scale / 200, dense_output=False)
    f = np.array([max(force(d, dv), 0.0) for d, dv in zip(sol.y[0], sol.y[1])])
    if not sol.t_events[0].size:
        if preload_n > 0:  # captured: the preload keeps the bodies together
            return ImpactResult(0.0, float(f.max()), math.inf, float(sol.y[0].max()))
        raise RuntimeError("impact did not end: the law keeps the bodies in contact")
    t_end = float(sol.t_events[0][0])
    v_end = float(sol.y_events[0][0][1])
    return ImpactResult(-v_end / v, float(f.max()), t_end, float(sol.y[0].max()))


def hertz_duration(K: float, n: float, m: float, v: float) -> float:
    """Scale of the contact time of an elastic δ^n contact: δ_max / v [s]."""
    delta_max = ((n + 1) * m * v * v / (2 * K)) ** (1 / (n + 1))
    return delta_max / v


def impact_hysteresis(law: str, K: float, n: float, e: float, m: float, v: float,
                      preload_n: float = 0.0) -> ImpactResult:
    """Impact with a hysteresis-damped Hertzian law (LN, Hunt–Crossley, Flores).

    The ratio δ̇/v⁻ is kept above −1 during separation (S003 §3), so the damping term never
    makes the force pull. ``preload_n`` [N] presses the mass into the wall during contact; a
    captured mass (no separation) gives restitution 0 and an infinite duration.
    """
    chi = DAMPING_FACTOR[law](e)

    def force(d, dv):
        return K * max(d, 0.0) ** n * (1.0 + chi * max(dv / v, -1.0))

    return _integrate(force, m, v, hertz_duration(K, n, m, v), preload_n)


def impact_linear(k: float, c: float, m: float, v: float) -> ImpactResult:
    """Impact with a unilateral linear spring-damper f = max(0, k δ + c δ̇)."""
    return _integrate(lambda d, dv: k * d + c * dv, m, v, math.sqrt(m / k))


@lru_cache(maxsize=64)
def hysteresis_restitution(law: str, e: float, n: float = 1.5) -> float:
    """Effective restitution of a hysteresis law: independent of K, m and v (scale-free)."""
    return impact_hysteresis(law, 1e10, n, e, 1.0, 0.1).restitution


@lru_cache(maxsize=64)
def linear_damping_ratio(restitution: float) -> float:
    """Damping ratio ζ = c / (2 sqrt(k m)) of a unilateral linear contact with the given
    restitution (scale-free; ζ ≈ 0.358 for 0.40)."""
    from scipy.optimize import brentq

    def f(zeta):
        return impact_linear(1.0, 2 * zeta, 1.0, 1.0).restitution - restitution

    lo, hi = 1e-6, 0.99
    if f(lo) <= 0:  # (nearly) perfectly elastic, e = 1 included: no damping
        return 0.0
    if f(hi) > 0:
        from twin.errors import ConfigError

        raise ConfigError("contact.restitution", f"{restitution:g} is below {f(hi) + restitution:.3g}, the least a "
                                                 "linear spring-damper contact reaches (damping ratio 0.99)")
    return brentq(f, lo, hi, xtol=1e-10)


#: Scale-free constants of a hysteresis law's free impact and of its linear equivalent, by
#: (law, n, e): (τ, e_eff, ζ, g): the impact lasts τ δmax/v (δmax = ((n+1) m v²/(2K))^(1/(n+1)))
#: and returns e_eff; the unilateral linear contact with restitution e_eff has damping ratio ζ
#: and lasts g sqrt(m/k). The hysteresis laws are exactly scale-free (δ = δmax x, t = δmax/v s
#: removes K, m and v), so these four numbers give :func:`linear_equivalent` for every K, m, v.
#: :func:`scale_free_constants` solves them (ODE); the default law's are stored here so that the
#: twin's default build needs no ODE solver (``tests/test_calibration.py`` re-solves them).
SCALE_FREE: dict[tuple[str, float, float], tuple[float, float, float, float]] = {
    ("lankarani-nikravesh", 1.5, 0.4): (3.0846904191803572, 0.701634728074198, 0.12135586862914068,
                                       3.1625734358695716),
}


def scale_free_constants(law: str, n: float, e: float, solve: bool = False) -> tuple[float, float, float, float]:
    """(τ, e_eff, ζ, g) of :data:`SCALE_FREE` for (law, n, e), solved once per process where not
    stored (``solve``: always solve)."""
    key = (law, float(n), float(e))
    if solve or key not in SCALE_FREE:
        r = impact_hysteresis(law, 1.0, n, e, 1.0, 1.0)
        dmax = ((n + 1) / 2) ** (1 / (n + 1))
        zeta = linear_damping_ratio(r.restitution)
        consts = (r.duration_s / dmax, r.restitution, zeta, impact_linear(1.0, 2 * zeta, 1.0, 1.0).duration_s)
        if solve:
            return consts
        SCALE_FREE[key] = consts
    return SCALE_FREE[key]


def linear_equivalent(K: float, n: float, e: float, m: float, v: float,
                      law: str = "lankarani-nikravesh") -> tuple[float, float]:
    """(k [N/m], c [N s/m]) of a linear contact matching a hysteresis law's impact at speed v:
    same contact duration and the same restitution (:func:`scale_free_constants`)."""
    tau, _e_eff, zeta, g = scale_free_constants(law, n, e)
    duration = tau * hertz_duration(K, n, m, v)
    # unilateral linear contact: duration = g sqrt(m/k); match duration and restitution
    k = m * (g / duration) ** 2
    c = 2 * zeta * math.sqrt(k * m)
    return k, c
