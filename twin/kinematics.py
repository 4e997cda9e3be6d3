"""Closed-form kinematics of the slider–crank and the initial pose both engines start from.

Bench frame as in :mod:`twin.config`: A at the origin, crank A–B of length r at bench angle
θ, rod B'–C of length l at angle φ from +x, slider pin C' at height ``d_off`` above the guide
line y = 0 that passes through A (assumption, BENCH.md). At a clearance joint the pin centre
and the bushing centre differ by the eccentricity e = pin − bushing; pins sit on the crank
(B) and on the slider (C'), bushings in the rod eyes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from twin.config import BenchConfig


def slider_position(theta: np.ndarray, r: float, l: float, d_off: float = 0.0) -> np.ndarray:
    """Slider x of the ideal mechanism (all joints exact) for crank angle θ [rad] -> [m].

    x = r cos θ + sqrt(l² − (d_off − r sin θ)²), slider on the +x side of the crank.
    """
    theta = np.asarray(theta, dtype=float)
    return r * np.cos(theta) + np.sqrt(l**2 - (d_off - r * np.sin(theta)) ** 2)


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


def loaded_eccentricity(cfg: BenchConfig, joint: str) -> np.ndarray:
    """Initial eccentricity of a clearance joint, bench frame [m].

    ``joints.initial_eccentricity = "loaded"``: the rod's weight pulls both rod eyes down
    onto their pins, so the pin touches the bushing on the side opposite to gravity:
    e = c · (−ĝ in the plane of motion). Zero if gravity is normal to the plane (z vertical),
    for ``"centred"`` and for ideal joints.
    """
    c = cfg.joints.radial_m(joint)
    g = np.asarray(cfg.mechanism.gravity_vector[:2], dtype=float)
    gn = np.linalg.norm(g)
    if c == 0 or cfg.joints.initial_eccentricity == "centred" or gn == 0:
        return np.zeros(2)
    return -c * g / gn


def initial_pose(cfg: BenchConfig, theta: float) -> Pose:
    """Pose at crank angle θ with the configured initial eccentricities, at rest."""
    r, l = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    e_b, e_c = loaded_eccentricity(cfg, "B"), loaded_eccentricity(cfg, "C")
    b_pin = r * np.array([np.cos(theta), np.sin(theta)])
    b_bush = b_pin - e_b
    s = (cfg.mechanism.d_off_m - e_c[1] - b_bush[1]) / l
    if abs(s) >= 1:
        raise ValueError("rod cannot reach the guide: check lengths and d_off")
    phi = float(np.arcsin(s))
    c_bush = b_bush + l * np.array([np.cos(phi), np.sin(phi)])
    c_pin = c_bush + e_c
    return Pose(float(theta), phi, e_b, e_c, b_pin, b_bush, c_bush, c_pin, float(c_pin[0]))
