"""Closed-form kinematics of the slider–crank and the initial pose both engines start from.

Bench frame as in :mod:`twin.config`: A at the origin, crank A–B of length r at bench angle
θ, rod B'–C of length l at angle φ from +x, slider pin C' at height ``d_off`` above the guide
line y = 0 that passes through A (assumption, BENCH.md). At a clearance joint the pin centre
and the bushing centre differ by the eccentricity e = pin − bushing; pins sit on the crank
(B) and on the slider (C'), bushings in the rod eyes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from twin.config import BenchConfig


def slider_position(theta: np.ndarray, r: float, l: float, d_off: float = 0.0) -> np.ndarray:
    """Slider x of the ideal mechanism (all joints exact) for crank angle θ [rad] -> [m].

    x = r cos θ + sqrt(l² − (d_off − r sin θ)²), slider on the +x side of the crank.
    """
    theta = np.asarray(theta, dtype=float)
    return r * np.cos(theta) + np.sqrt(l**2 - (d_off - r * np.sin(theta)) ** 2)


def slider_kinematics(theta: np.ndarray, omega: np.ndarray, alpha: np.ndarray, r: float, l: float,
                      d_off: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Slider position, velocity and acceleration of the ideal mechanism [m, m/s, m/s²] for crank
    angle θ, rate ω and acceleration α (closed form, exact derivatives of :func:`slider_position`).

    With u = d_off − r sin θ and S = sqrt(l² − u²): x = r cos θ + S,
    u̇ = −r ω cos θ, ü = r ω² sin θ − r α cos θ, Ṡ = −u u̇/S, S̈ = −(u̇² + u ü)/S − u² u̇²/S³,
    ẋ = −r ω sin θ + Ṡ, ẍ = −r ω² cos θ − r α sin θ + S̈. For d_off = 0 and α = 0 the
    acceleration peaks are −r ω² (1 + r/l) at θ = 0 and r ω² (1 − r/l) at θ = π (r/l < 1/4).
    """
    th = np.asarray(theta, dtype=float)
    w = np.asarray(omega, dtype=float)
    a = np.asarray(alpha, dtype=float)
    s, c = np.sin(th), np.cos(th)
    u = d_off - r * s
    ud = -r * w * c
    udd = r * w * w * s - r * a * c
    S = np.sqrt(l * l - u * u)
    Sd = -u * ud / S
    Sdd = -(ud * ud + u * udd) / S - (u * ud) ** 2 / S ** 3
    return r * c + S, -r * w * s + Sd, -r * w * w * c - r * a * s + Sdd


def rod_angle(theta: np.ndarray, r: float, l: float, d_off: float = 0.0) -> np.ndarray:
    """Rod angle φ from +x of the ideal mechanism [rad]: sin φ = (d_off − r sin θ)/l."""
    return np.arcsin((d_off - r * np.sin(np.asarray(theta, dtype=float))) / l)


def rot2(phi: float) -> np.ndarray:
    """2-D rotation matrix of angle φ."""
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, -s], [s, c]])


@dataclass(frozen=True)
class Pose:
    """Planar pose of the mechanism (bench frame).

    Attributes:
        theta: crank bench angle [rad].
        phi: rod angle from +x [rad].
        e_b: eccentricity at B, pin − bushing, bench frame [m] (zeros if ideal).
        e_c: eccentricity at C, bench frame [m] (zeros if ideal).
        b_pin: crank pin centre B [m]; ``b_bush``: rod eye centre B' = B − e_b [m].
        c_bush: rod eye centre C [m]; ``c_pin``: slider pin C' = C + e_c [m].
        slider_x: slider position along the guide (x of C') [m].
        e_a: eccentricity at the ground pivot A, crank journal − frame bore centre (the bench
            origin), bench frame [m] (zeros if ideal): the crank journal centre is at e_a and
            ``b_pin`` = e_a + r (cos θ, sin θ).
    """

    theta: float
    phi: float
    e_b: np.ndarray
    e_c: np.ndarray
    b_pin: np.ndarray
    b_bush: np.ndarray
    c_bush: np.ndarray
    c_pin: np.ndarray
    slider_x: float
    e_a: np.ndarray = field(default_factory=lambda: np.zeros(2))


def static_pin_forces(cfg: BenchConfig, theta: float) -> tuple[np.ndarray, np.ndarray]:
    """Static forces of the rod eyes on the pins B (crank) and C' (slider) at crank angle θ,
    bench frame, in-plane [N]: the mechanism at rest under gravity, ideal geometry.

    The guide carries the slider's weight across the guide (y) only; along the guide (x) the
    rod carries it (the guide's friction is left out: the reference's regularized friction is
    zero at rest). The rod (mass m_r, centre of mass x_g along B→C) is a two-pin member: its
    moment balance about B gives the force across it at C. Force of the rod eye on the slider
    pin: F_C = (−m_s g_x, tan φ F_C,x + (x_g/l) m_r (g_y − tan φ g_x)); on the crank pin:
    F_B = m_r g − F_C.
    """
    b, mech = cfg.bodies, cfg.mechanism
    g = np.asarray(mech.gravity_vector[:2], dtype=float)
    r, l = b.crank.length_m, b.rod.length_m
    phi = float(rod_angle(theta, r, l, mech.d_off_m))
    tan_phi = np.tan(phi)
    m_r, m_s = b.rod.mass_kg, b.slider.mass_kg
    fcx = -m_s * g[0]
    fcy = tan_phi * fcx + b.rod.x_g_m / l * m_r * (g[1] - tan_phi * g[0])
    f_c = np.array([fcx, fcy])
    return m_r * g - f_c, f_c


def loaded_eccentricity(cfg: BenchConfig, joint: str, theta: float = 0.0) -> np.ndarray:
    """Initial eccentricity of a clearance joint at crank angle θ, bench frame [m].

    ``joints.initial_eccentricity = "loaded"``: the pin touches the bushing on the side its
    static load (:func:`static_pin_forces`) pushes it to. The contact force on the pin is
    −f_n e/|e|, so e = −c F/|F| with F the static force on the pin. With y vertical the rod's
    weight pulls both rod eyes down onto their pins (e = +c ŷ at B and C); with x vertical (the
    guide vertical) the rod carries the slider's weight, so the slider pin rests on the lower
    side of the C eye (e ≈ −c x̂) while the crank pin carries rod and slider (e ≈ +c x̂ at B).
    At the ground pivot A the frame's bore carries the crank's weight and the load of pin B: the
    force on the crank journal is −(m_crank g + F_B), so with y vertical e_A ≈ −c ŷ (the journal
    rests on the bottom of the bore).
    Zero if gravity is normal to the plane (z vertical), for ``"centred"`` and for ideal joints.
    """
    c = cfg.joints.radial_m(joint)
    if c == 0 or cfg.joints.initial_eccentricity == "centred":
        return np.zeros(2)
    f_b, f_c = static_pin_forces(cfg, theta)
    if joint == "A":  # the frame holds the crank: its weight and the rod's load on pin B
        crank_g = cfg.bodies.crank.mass_kg * np.asarray(cfg.mechanism.gravity_vector[:2], dtype=float)
        f = -(crank_g + f_b)
    else:
        f = f_b if joint == "B" else f_c
    fn = float(np.linalg.norm(f))
    if fn < 1e-12:
        return np.zeros(2)
    return -c * f / fn


def guide_start(cfg: BenchConfig) -> float:
    """The slider's transverse start y_g [m]: 0 (centred) without a guide clearance or with
    ``initial_eccentricity = "centred"``; else on the rail gravity's guide-normal component
    pushes it to (−c_g with gravity along −y; no drop at t = 0), tilt 0. The pin C' starts
    at d_off + y_g."""
    j = cfg.joints
    gy = cfg.mechanism.gravity_vector[1]
    if not j.guide_play or j.initial_eccentricity == "centred" or gy == 0:
        return 0.0
    return -j.guide_radial_m if gy < 0 else j.guide_radial_m


def initial_pose(cfg: BenchConfig, theta: float) -> Pose:
    """Pose at crank angle θ with the configured initial eccentricities, at rest."""
    r, l = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    e_b, e_c = loaded_eccentricity(cfg, "B", theta), loaded_eccentricity(cfg, "C", theta)
    e_a = loaded_eccentricity(cfg, "A", theta)
    b_pin = e_a + r * np.array([np.cos(theta), np.sin(theta)])
    b_bush = b_pin - e_b
    y_g = guide_start(cfg)
    s = ((cfg.mechanism.d_off_m + y_g if y_g else cfg.mechanism.d_off_m) - e_c[1] - b_bush[1]) / l
    if abs(s) >= 1:
        raise ValueError("rod cannot reach the guide: check lengths and d_off")
    phi = float(np.arcsin(s))
    c_bush = b_bush + l * np.array([np.cos(phi), np.sin(phi)])
    c_pin = c_bush + e_c
    return Pose(float(theta), phi, e_b, e_c, b_pin, b_bush, c_bush, c_pin, float(c_pin[0]), e_a)


def pose_rates(cfg: BenchConfig, pose: Pose, omega: float) -> tuple[float, float]:
    """Rod angular rate φ̇ [rad/s] and slider velocity ẋ [m/s] of ``pose`` with the crank turning
    at ω and the eccentricities fixed in the bench frame (ė = 0), from the relations of
    :func:`initial_pose`: sin φ = (d_off − e_Cy − B'_y)/l, with Ḃ' = Ḃ = r ω (−sin θ, cos θ):
    φ̇ = −Ḃ'_y/(l cos φ), ẋ = Ḃ'_x − l φ̇ sin φ."""
    l = cfg.bodies.rod.length_m
    bd = cfg.bodies.crank.length_m * omega * np.array([-np.sin(pose.theta), np.cos(pose.theta)])
    phid = -bd[1] / (l * np.cos(pose.phi))
    return float(phid), float(bd[0] - l * phid * np.sin(pose.phi))
