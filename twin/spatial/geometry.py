"""Constants of the spatial slider–crank from a configuration, and its closed-form kinematics.

Coordinates (natural coordinates, all in the spatial frame of :mod:`twin.config.spatial`):
``q = [A, B_c, B_r, C_r, C_s]``, five points of three coordinates each:

* ``A``: centre of the crank's journal at the base joint (the bearing's centre is the origin);
* ``B_c``: centre of the socket on the crank (crank–rod joint B);
* ``B_r``, ``C_r``: centres of the balls at the rod's ends (the rod is the segment B_r–C_r);
* ``C_s``: centre of the socket on the slider (rod–slider joint C), the slider's reference point.

An ideal joint is a constraint (A = origin, B_r = B_c, C_r = C_s), a clearance joint a force element
between its two points. Crank: the points A and B_c, in the plane x = 0 (a revolute joint about x
keeps its plane even with a radial clearance). Rod: a slender body B_r–C_r (no spin about its axis,
which the spherical joints leave free and nothing drives). Slider: the point C_s on the guide line.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: index of each point's first coordinate in q
IA, IBC, IBR, ICR, ICS = 0, 3, 6, 9, 12
NQ = 15

GUIDE_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0)}


def guide(cfg: Any) -> tuple[np.ndarray, np.ndarray]:
    """(p0, g): a point of the guide line and its unit direction [m], [-]."""
    sp = cfg.spatial
    g = np.array(GUIDE_AXES[sp.guide_axis])
    p0 = np.array([0.0, sp.guide_offset_y_m, sp.guide_offset_z_m])
    p0 = p0 - g * float(p0 @ g)  # the point of the line nearest the plane's origin along g
    return p0, g


def slider_closed_form(cfg: Any, theta: np.ndarray, omega: float | np.ndarray, alpha: float | np.ndarray = 0.0
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ideal-joint slider position s = (C − p0)·g [m], velocity [m/s] and acceleration [m/s²] along the
    guide at crank angle θ [rad], rate ω [rad/s] and angular acceleration α [rad/s²], in closed form.

    Guide along x through (0, a, b): C = (s, a, b), B = (0, r cos θ, r sin θ), |C − B| = L, so
    s = √(L² − w) with w = (a − r cos θ)² + (b − r sin θ)² (the slider on the +x side).
    Guide along y through (0, ·, b): s = r cos θ + √(L² − (b − r sin θ)²).
    """
    r, L = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    p0, _ = guide(cfg)
    th = np.asarray(theta, dtype=np.float64)
    c, s_ = np.cos(th), np.sin(th)
    om, al = np.asarray(omega, dtype=np.float64), np.asarray(alpha, dtype=np.float64)
    if cfg.spatial.guide_axis == "x":
        a, b = p0[1], p0[2]
        w = (a - r * c) ** 2 + (b - r * s_) ** 2
        w1 = 2.0 * r * (a * s_ - b * c)  # dw/dθ
        w2 = 2.0 * r * (a * c + b * s_)  # d²w/dθ²
        x = np.sqrt(L * L - w)
        wd = w1 * om
        wdd = w2 * om * om + w1 * al
        v = -wd / (2.0 * x)
        acc = -wdd / (2.0 * x) - wd * wd / (4.0 * x**3)
        return x, v, acc
    b = p0[2]
    u = b - r * s_
    root = np.sqrt(L * L - u * u)
    ud = -r * c * om
    udd = r * s_ * om * om - r * c * al
    # d/dt √(L² − u²) = −u u̇ / root; second derivative
    rd = -u * ud / root
    rdd = -(ud * ud + u * udd) / root - (u * ud) ** 2 / root**3
    y = r * c + root
    v = -r * s_ * om + rd
    acc = -r * c * om * om - r * s_ * al + rdd
    return y, v, acc


def ideal_coordinates(cfg: Any, theta: float) -> np.ndarray:
    """q of the ideal mechanism at crank angle θ [rad] (every clearance joint centred)."""
    r = cfg.bodies.crank.length_m
    p0, g = guide(cfg)
    q = np.zeros(NQ)
    b = np.array([0.0, r * math.cos(theta), r * math.sin(theta)])
    s = float(slider_closed_form(cfg, np.array([theta]), 0.0)[0][0])
    c = p0 + s * g
    q[IBC:IBC + 3] = b
    q[IBR:IBR + 3] = b
    q[ICR:ICR + 3] = c
    q[ICS:ICS + 3] = c
    return q


def ideal_velocities(cfg: Any, theta: float, omega: float) -> np.ndarray:
    """q̇ of the ideal mechanism at crank angle θ [rad] turning at ω [rad/s]."""
    r = cfg.bodies.crank.length_m
    _, g = guide(cfg)
    v = np.zeros(NQ)
    bd = np.array([0.0, -r * math.sin(theta), r * math.cos(theta)]) * omega
    sd = float(slider_closed_form(cfg, np.array([theta]), omega)[1][0])
    v[IBC:IBC + 3] = bd
    v[IBR:IBR + 3] = bd
    v[ICR:ICR + 3] = sd * g
    v[ICS:ICS + 3] = sd * g
    return v


def two_point_mass(m: float, xi_g: float, j_xi: float) -> np.ndarray:
    """Constant 2 × 2 mass matrix (times I₃) of a body whose points are P = (1 − ξ) P_i + ξ P_j:
    [[m − 2 m ξ_g + J, m ξ_g − J], [m ξ_g − J, J]] with J = ∫ ξ² dm [kg]."""
    return np.array([[m - 2.0 * m * xi_g + j_xi, m * xi_g - j_xi], [m * xi_g - j_xi, j_xi]])


def mass_matrix(cfg: Any) -> np.ndarray:
    """The constant 15 × 15 mass matrix of q [kg].

    Crank (A, B_c) and rod (B_r, C_r): two-point bodies, ξ along the body from its first point,
    ∫ ξ² dm = m ξ_g² + I_G / l² (I_G the moment of inertia about the centre of mass, about the crank
    axis for the crank, transverse for the rod; exact for the crank's motion in its plane and for a
    rod without spin). Slider: its mass at C_s (it only translates)."""
    M = np.zeros((NQ, NQ))
    for body, (i, j) in (("crank", (IA, IBC)), ("rod", (IBR, ICR))):
        b = getattr(cfg.bodies, body)
        xi = b.x_g_m / b.length_m
        m2 = two_point_mass(b.mass_kg, xi, b.mass_kg * xi * xi + b.inertia_kgm2 / b.length_m**2)
        for a_, ia in enumerate((i, j)):
            for b_, ib in enumerate((i, j)):
                M[ia:ia + 3, ib:ib + 3] += m2[a_, b_] * np.eye(3)
    M[ICS:ICS + 3, ICS:ICS + 3] += cfg.bodies.slider.mass_kg * np.eye(3)
    return M


def gravity_forces(cfg: Any) -> np.ndarray:
    """Generalized gravity forces on q [N] (each body's weight shared by its points as its centre of
    mass divides them)."""
    g = np.array(cfg.mechanism.gravity_vector)
    Q = np.zeros(NQ)
    for body, (i, j) in (("crank", (IA, IBC)), ("rod", (IBR, ICR))):
        b = getattr(cfg.bodies, body)
        xi = b.x_g_m / b.length_m
        Q[i:i + 3] += b.mass_kg * (1.0 - xi) * g
        Q[j:j + 3] += b.mass_kg * xi * g
    Q[ICS:ICS + 3] += cfg.bodies.slider.mass_kg * g
    return Q
