"""Contact force element of a clearance joint: normal-force laws and regularized friction.

Small compiled (numba) functions, one per law, all with the same arguments so a new law is
one more function and one more code in :data:`LAW_CODES`:

``f = law(delta, delta_dot, v_impact, K, n, e, c_lin)``

* ``delta`` penetration δ = |e| − c [m] (> 0 in contact), ``delta_dot`` its rate [m/s];
* ``v_impact`` δ̇⁻, the penetration rate stored at the start of the contact event [m/s]
  (kept ≥ the engine's ``min_impact_speed_mps``, see :class:`~twin.reference.engine.ReferenceOptions`);
* ``K`` stiffness [N/m^n] (linear law: [N/m]), ``n`` exponent, ``e`` restitution coefficient;
* ``c_lin`` damping of the linear law [N s/m] (unused by the others).

Laws (S003 Eq. 17 and the forms of :mod:`twin.impact`):

* Lankarani–Nikravesh: f = K δ^n [1 + 3(1 − e²)/4 · δ̇/δ̇⁻]
* Hunt–Crossley:        f = K δ^n [1 + 3(1 − e)/2 · δ̇/δ̇⁻]
* Flores et al.:        f = K δ^n [1 + 8(1 − e)/(5e) · δ̇/δ̇⁻]
* linear:               f = K δ + c_lin δ̇
* ADAMS IMPACT (S001, S004): f = K δ^n + STEP(δ, 0, 0, d_max, c_max) δ̇ (c_max in ``c_lin``)
* Johnson's cylindrical law: f = F_J(δ) [1 + 3(1 − e²)/4 · δ̇/δ̇⁻], F_J the elastic force of a pin
  in its bore of length L (:func:`twin.contact_params.johnson_elastic_force`; K = π L E*, the
  radial clearance ΔR in ``c_lin``)

In the hysteresis laws the ratio δ̇/δ̇⁻ is kept above −1 during separation (S003 §3: no
artificial sticking). Every law returns max(f, 0): a contact pushes, never pulls.

Friction (S003 Eq. 19–20): f_T = μ(v) f_N with μ = 0 for v ≤ v0, a linear ramp to μ0 between
v0 and v1 and μ0 above v1, v the magnitude of the tangential relative velocity of the contact
points; the force opposes that velocity. :func:`ramp` is the ramp alone (μ/μ0); the slider
guide friction uses the same ramp (see :mod:`twin.reference.model`).

Adams/COSMOS friction (S001 Table II; MSC Adams "Contact Friction Force Calculation",
``contact.friction_law = "adams"``): with s = |v| the slip speed, μ(s) = STEP(s, −v_s, −μ_s, v_s,
μ_s) for s < v_s (an odd cubic through μ(0) = 0), STEP(s, v_s, μ_s, v_d, μ_d) for v_s ≤ s < v_d and
μ_d above v_d, STEP(x, x0, h0, x1, h1) = h0 + (h1 − h0) Δ²(3 − 2Δ), Δ = (x − x0)/(x1 − x0)
(:func:`adams_mu`, :func:`adams_friction_force`).
"""

from __future__ import annotations

import math

from twin.jit import njit

from twin.contact_params import johnson_elastic_force as _johnson_elastic_force

#: law name (``cfg.contact.law``) -> code used inside the compiled loop
LAW_CODES: dict[str, int] = {
    "lankarani-nikravesh": 0,
    "hunt-crossley": 1,
    "flores": 2,
    "linear": 3,
    "adams-impact": 4,
    "johnson-cylindrical": 5,
}

#: the Johnson cylindrical elastic force, compiled from its plain-Python definition
johnson_elastic = njit(cache=True)(_johnson_elastic_force)


@njit(cache=True)
def _hysteresis(delta, delta_dot, v_impact, K, n, chi):
    ratio = delta_dot / v_impact
    if ratio < -1.0:
        ratio = -1.0
    dn = delta * math.sqrt(delta) if n == 1.5 else delta ** n
    f = K * dn * (1.0 + chi * ratio)
    return f if f > 0.0 else 0.0


@njit(cache=True)
def lankarani_nikravesh(delta, delta_dot, v_impact, K, n, e, c_lin):
    """Lankarani–Nikravesh (S003 Eq. 17) normal force [N]; 0 if δ ≤ 0."""
    if delta <= 0.0:
        return 0.0
    return _hysteresis(delta, delta_dot, v_impact, K, n, 0.75 * (1.0 - e * e))


@njit(cache=True)
def hunt_crossley(delta, delta_dot, v_impact, K, n, e, c_lin):
    """Hunt–Crossley normal force [N], damping factor 3(1 − e)/2; 0 if δ ≤ 0."""
    if delta <= 0.0:
        return 0.0
    return _hysteresis(delta, delta_dot, v_impact, K, n, 1.5 * (1.0 - e))


@njit(cache=True)
def flores(delta, delta_dot, v_impact, K, n, e, c_lin):
    """Flores et al. normal force [N], damping factor 8(1 − e)/(5e); 0 if δ ≤ 0."""
    if delta <= 0.0:
        return 0.0
    return _hysteresis(delta, delta_dot, v_impact, K, n, 8.0 * (1.0 - e) / (5.0 * e))


@njit(cache=True)
def linear(delta, delta_dot, v_impact, K, n, e, c_lin):
    """Unilateral linear spring-damper K δ + c_lin δ̇ [N] (K in N/m); 0 if δ ≤ 0."""
    if delta <= 0.0:
        return 0.0
    f = K * delta + c_lin * delta_dot
    return f if f > 0.0 else 0.0


@njit(cache=True)
def adams_impact(delta, delta_dot, K, n, c_max, d_max):
    """ADAMS' IMPACT force (S001 Eq. 3 and 9, S004): K δⁿ + STEP(δ, 0, 0, d_max, c_max) δ̇ [N]; 0 if
    δ ≤ 0; never pulls."""
    if delta <= 0.0:
        return 0.0
    dn = delta * math.sqrt(delta) if n == 1.5 else delta ** n
    c = c_max
    if delta < d_max:
        x = delta / d_max
        c = c_max * x * x * (3.0 - 2.0 * x)
    f = K * dn + c * delta_dot
    return f if f > 0.0 else 0.0


@njit(cache=True)
def johnson_cylindrical(delta, delta_dot, v_impact, K, n, e, c_lin):
    """Johnson's cylindrical law with Lankarani–Nikravesh damping [N] (K = π L E* [N/m], c_lin =
    ΔR [m]); 0 if δ ≤ 0."""
    if delta <= 0.0:
        return 0.0
    ratio = delta_dot / v_impact
    if ratio < -1.0:
        ratio = -1.0
    f = johnson_elastic(delta, K, c_lin) * (1.0 + 0.75 * (1.0 - e * e) * ratio)
    return f if f > 0.0 else 0.0


@njit(cache=True)
def normal_force(code, delta, delta_dot, v_impact, K, n, e, c_lin, d_max=1e-5):
    """Normal force of the law with ``code`` (:data:`LAW_CODES`) [N]; ``c_lin`` is the linear law's c,
    the IMPACT law's c_max or the Johnson law's radial clearance ΔR [m], ``d_max`` the IMPACT law's penetration of full damping."""
    if code == 4:
        return adams_impact(delta, delta_dot, K, n, c_lin, d_max)
    if code == 5:
        return johnson_cylindrical(delta, delta_dot, v_impact, K, n, e, c_lin)
    if code == 0:
        return lankarani_nikravesh(delta, delta_dot, v_impact, K, n, e, c_lin)
    if code == 1:
        return hunt_crossley(delta, delta_dot, v_impact, K, n, e, c_lin)
    if code == 2:
        return flores(delta, delta_dot, v_impact, K, n, e, c_lin)
    return linear(delta, delta_dot, v_impact, K, n, e, c_lin)


@njit(cache=True)
def ramp(speed, v0, v1):
    """Regularization ramp of S003 Eq. 20 divided by μ0: 0 below v0, 1 above v1 [-]."""
    s = abs(speed)
    if s <= v0:
        return 0.0
    if s >= v1:
        return 1.0
    return (s - v0) / (v1 - v0)


@njit(cache=True)
def friction_force(v_t, f_n, mu0, v0, v1):
    """Regularized Coulomb force along the tangent t (S003 Eq. 19–20) [N].

    ``v_t`` is the tangential relative velocity (body whose force is returned minus the
    other body) along t; the result opposes it: −μ(|v_t|) f_N sign(v_t).
    """
    mu = mu0 * ramp(v_t, v0, v1)
    if v_t > 0.0:
        return -mu * f_n
    if v_t < 0.0:
        return mu * f_n
    return 0.0


#: friction law name (``cfg.contact.friction_law``) -> code used inside the compiled loop
FRICTION_CODES: dict[str, int] = {"regularized-coulomb": 0, "adams": 1}


@njit(cache=True)
def step3(x, x0, h0, x1, h1):
    """Adams' cubic STEP: h0 for x ≤ x0, h1 for x ≥ x1, h0 + (h1 − h0) Δ²(3 − 2Δ) between."""
    if x <= x0:
        return h0
    if x >= x1:
        return h1
    d = (x - x0) / (x1 - x0)
    return h0 + (h1 - h0) * d * d * (3.0 - 2.0 * d)


@njit(cache=True)
def adams_mu(speed, mus, mud, vs, vd):
    """Friction coefficient of the Adams/COSMOS contact friction at slip speed |speed| [-]."""
    s = abs(speed)
    if s < vs:
        return step3(s, -vs, -mus, vs, mus)
    return step3(s, vs, mus, vd, mud)


@njit(cache=True)
def adams_friction_force(v_t, f_n, mus, mud, vs, vd):
    """Adams/COSMOS friction force along the tangent t [N]: −μ(|v_t|) f_N sign(v_t)."""
    mu = adams_mu(v_t, mus, mud, vs, vd)
    if v_t > 0.0:
        return -mu * f_n
    if v_t < 0.0:
        return mu * f_n
    return 0.0
