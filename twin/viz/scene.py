"""Static 3-D geometry of the bench, at the true sizes of a configuration.

Entity layout (bench frame of :mod:`twin.config`, metres; every moving body is an entity
whose ``Transform3D`` changes in time, its geometry is logged once, statically, in the
body's own frame):

* ``/bench/frame``: crank bearing housing at A and the slider guide rail (fixed); with a
  clearance at A the frame's bore (radius R_i = R_j + c of A), its orbit inset ``orbit_A`` and
  contact arrow ``contact_A`` (A's eccentricity is in the bench frame);
* ``/bench/crank``: arm, crank journal at A and crank pin B (each of its joint's radius R_j),
  frame rotated by θ about z and, with a clearance at A, translated by e_A;
* ``/bench/rod``: frame at the rod eye centre B' with x towards C (the eccentricities'
  frame): beam, both eyes (bushing bore R_i = R_j + c drawn as circles on both faces of the
  bushing, or a ball bearing at an ideal joint), accelerometers AC1–AC4 with their sensitive
  axes, the magnified orbit insets ``orbit_J`` and the contact force arrows ``contact_J``;
* ``/bench/slider``: frame at the slider pin centre C': pin, block, AC5/AC6.

Sizes that the configuration does not define (arm and beam cross sections, block size,
bushing wall, bearing ring) are visual only and documented here: they do not pretend to be
bench data. Pins, bores, bushing length, link lengths, d_off and sensor positions are the
configuration's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import rerun as rr

from twin.config import JOINTS, BenchConfig

# colours (RGBA)
C_FRAME = (110, 112, 118, 255)
C_CRANK = (72, 112, 165, 255)
C_ROD = (175, 180, 190, 255)
C_SLIDER = (95, 95, 108, 255)
C_PIN = (55, 58, 66, 255)
C_BUSHING = (205, 140, 60, 255)
C_BEARING = (150, 150, 160, 255)
C_SENSOR = (30, 130, 230, 255)
C_ORBIT = (20, 160, 90, 255)
C_CONTACT = (225, 40, 40, 255)
C_FREE = (30, 110, 220, 255)

#: visual-only sizes [m] (not bench data)
ARM_WIDTH, ARM_THICK = 0.036, 0.012
BEAM_WIDTH, BEAM_THICK = 0.024, 0.012
BUSHING_WALL = 0.006
BEARING_OUTER = 0.021
BLOCK_H, BLOCK_T = 0.04, 0.03

_VIEW_UP = {"x": rr.ViewCoordinates.RIGHT_HAND_X_UP, "y": rr.ViewCoordinates.RIGHT_HAND_Y_UP,
            "z": rr.ViewCoordinates.RIGHT_HAND_Z_UP}


def nice_magnification(radial_m: float, target_m: float) -> int:
    """Largest 1-2-5 series number M with M·c ≤ target (at least 1)."""
    if radial_m <= 0:
        return 1
    raw = target_m / radial_m
    if raw < 1:
        return 1
    exp = 10 ** math.floor(math.log10(raw))
    for m in (5, 2, 1):
        if m * exp <= raw:
            return int(m * exp)
    return int(exp)  # pragma: no cover


def circle(radius: float, centre: tuple[float, float] = (0.0, 0.0), z: float = 0.0, n: int = 96) -> np.ndarray:
    """Closed polyline of a circle in the plane z = const, shape (n + 1, 3)."""
    a = np.linspace(0.0, 2.0 * np.pi, n + 1)
    return np.stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a), np.full_like(a, z)], axis=1)


@dataclass(frozen=True)
class SceneInfo:
    """What the static scene drew, for the time-varying parts and the labels.

    Attributes:
        joint_centres: bushing centre of each joint in its parent's frame (B, C: rod frame; A: the
            bench frame, under ``/bench/frame``) [m].
        radial: radial clearance per joint [m] (0 = ideal).
        magnification: orbit inset magnification per clearance joint [-].
        front_z: z of the front faces (insets and arrows are drawn there) [m].
    """

    joint_centres: dict[str, tuple[float, float]]
    radial: dict[str, float]
    magnification: dict[str, int]
    front_z: float


def _axis_vec(axis: str) -> tuple[float, float, float]:
    sign = 1.0 if axis[0] == "+" else -1.0
    return (sign, 0.0, 0.0) if axis[1] == "x" else (0.0, sign, 0.0)


def joint_parent(joint: str) -> str:
    """Entity under which a joint's bushing, orbit inset and contact arrow are logged: the frame
    for the ground pivot A (its bore is fixed), the rod for B and C (their bushings are the rod
    eyes)."""
    return "/bench/frame" if joint == "A" else "/bench/rod"


def log_static_scene(rec: rr.RecordingStream, cfg: BenchConfig, orbit_radius_m: float) -> SceneInfo:
    """Log the fixed frame, the bodies' geometry and the orbit insets (all static)."""
    r, l = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    d_off = cfg.mechanism.d_off_m
    jt = cfg.joints
    blen = max(jt.bushing_length(j) for j in JOINTS)  # the widest bushing sets the faces in front and behind
    half = blen / 2.0
    front = half + 0.002
    radial = {j: jt.radial_m(j) for j in JOINTS}
    centres = {"A": (0.0, 0.0), "B": (0.0, 0.0), "C": (l, 0.0)}
    mag = {j: nice_magnification(c, orbit_radius_m) for j, c in radial.items() if c > 0}

    rec.log("/bench", _VIEW_UP[cfg.mechanism.orientation], static=True)

    # fixed frame: bearing housing behind the crank, guide rail under the slider's travel
    back = -half - ARM_THICK
    x_min, x_max = l - r - 0.06, l + r + 0.06
    rec.log("/bench/frame", rr.Boxes3D(
        centers=[((x_min + x_max) / 2, -BLOCK_H / 2 - 0.006, back - BLOCK_T / 2)],
        half_sizes=[((x_max - x_min) / 2, 0.006, BLOCK_T / 2 + 0.004)],
        colors=[C_FRAME], fill_mode="solid", labels=["guide"], show_labels=False), static=True)
    rec.log("/bench/frame/bearing", rr.Cylinders3D(
        lengths=[0.03], radii=[0.03], centers=[(0.0, 0.0, back - 0.015 - ARM_THICK / 2)], colors=[C_FRAME],
        fill_mode="solid"), static=True)

    # crank: arm from A to B, pin B (true radius, 2 mm proud of the bushing on each face); with a
    # clearance at A also its journal (true radius) in the frame's bore
    rec.log("/bench/crank/arm", rr.Boxes3D(
        centers=[(r / 2, 0.0, -half - ARM_THICK / 2)], half_sizes=[(r / 2 + ARM_WIDTH / 2, ARM_WIDTH / 2, ARM_THICK / 2)],
        colors=[C_CRANK], fill_mode="solid", labels=["crank"], show_labels=False), static=True)
    rec.log("/bench/crank/pin_B", rr.Cylinders3D(
        lengths=[jt.bushing_length("B") + 0.004], radii=[jt.pin_radius("B")], centers=[(r, 0.0, 0.0)],
        colors=[C_PIN], fill_mode="solid"), static=True)
    if radial["A"] > 0:
        rec.log("/bench/crank/pin_A", rr.Cylinders3D(
            lengths=[jt.bushing_length("A") + 0.004], radii=[jt.pin_radius("A")], centers=[(0.0, 0.0, 0.0)],
            colors=[C_PIN], fill_mode="solid"), static=True)
        _log_bushing(rec, cfg, "A", centres["A"], mag["A"], front)

    # rod: beam between the eyes, eyes (bushing or bearing) at B' and C
    eye_outer = {j: (jt.bushing_radius_m(j) + BUSHING_WALL) if radial[j] > 0 else BEARING_OUTER for j in ("B", "C")}
    x0, x1 = eye_outer["B"], l - eye_outer["C"]
    rec.log("/bench/rod/beam", rr.Boxes3D(
        centers=[((x0 + x1) / 2, 0.0, 0.0)], half_sizes=[((x1 - x0) / 2, BEAM_WIDTH / 2, BEAM_THICK / 2)],
        colors=[C_ROD], fill_mode="solid", labels=["rod"], show_labels=False), static=True)
    for j in ("B", "C"):
        cx, cy = centres[j]
        if radial[j] > 0:
            _log_bushing(rec, cfg, j, centres[j], mag[j], front)
        else:
            rec.log(f"/bench/rod/eye_{j}", rr.Cylinders3D(
                lengths=[jt.bushing_length(j)], radii=[BEARING_OUTER], centers=[(cx, cy, 0.0)], colors=[C_BEARING],
                fill_mode="majorwireframe", labels=[f"{j}: ball bearing (ideal)"], show_labels=False), static=True)
    _log_sensors(rec, cfg, "rod", "/bench/rod/sensors", (0.0, 0.0), half)

    # slider: frame at C' (d_off above the guide line); block on the guide line below the pin
    rec.log("/bench/slider/pin_C", rr.Cylinders3D(
        lengths=[jt.bushing_length("C") + 0.004], radii=[jt.pin_radius("C")], centers=[(0.0, 0.0, 0.0)], colors=[C_PIN], fill_mode="solid"), static=True)
    sl = cfg.bodies.slider.length_m
    rec.log("/bench/slider/block", rr.Boxes3D(
        centers=[(0.0, -d_off, back - BLOCK_T / 2 + 0.004)], half_sizes=[(sl / 2, BLOCK_H / 2, BLOCK_T / 2)],
        colors=[C_SLIDER], fill_mode="solid", labels=["slider"], show_labels=False), static=True)
    _log_sensors(rec, cfg, "slider", "/bench/slider/sensors", (0.0, 0.0), half)
    return SceneInfo(centres, radial, mag, front)


def _log_bushing(rec: rr.RecordingStream, cfg: BenchConfig, j: str, centre: tuple[float, float], m: int,
                 front: float) -> None:
    """Bushing of clearance joint ``j`` under its parent (:func:`joint_parent`): the bore drawn on
    both faces, the wall, and the orbit inset of radius m·c."""
    parent, (cx, cy) = joint_parent(j), centre
    c, ri = cfg.joints.radial_m(j), cfg.joints.bushing_radius_m(j)
    blen = cfg.joints.bushing_length(j)
    half = blen / 2.0
    rec.log(f"{parent}/eye_{j}", rr.Cylinders3D(
        lengths=[blen], radii=[ri + BUSHING_WALL], centers=[(cx, cy, 0.0)], colors=[C_BUSHING],
        fill_mode="majorwireframe", labels=[f"{j}: bushing, bore {2e3 * ri:.3f} mm"], show_labels=False),
        static=True)
    rec.log(f"{parent}/eye_{j}/bore", rr.LineStrips3D(
        [circle(ri, (cx, cy), half), circle(ri, (cx, cy), -half)], colors=[C_BUSHING], radii=[0.0006]),
        static=True)
    rec.log(f"{parent}/orbit_{j}", rr.LineStrips3D(
        [circle(m * c, (cx, cy), front)], colors=[C_ORBIT], radii=[0.0008]), static=True)
    rec.log(f"{parent}/orbit_{j}/label", rr.Points3D(
        [(cx, cy - m * c - 0.018, front)], radii=[0.0001], colors=[C_ORBIT],
        labels=[f"{j} ×{m}"], show_labels=True), static=True)


def _log_sensors(rec: rr.RecordingStream, cfg: BenchConfig, body: str, path: str,
                 origin: tuple[float, float], half: float) -> None:
    names, origins, vectors = [], [], []
    z = half + 0.006
    for name, mount in cfg.sensors.accelerometers.items():
        if mount.body != body:
            continue
        names.append(name)
        origins.append((origin[0] + mount.position_m[0], origin[1] + mount.position_m[1], z))
        vectors.append(tuple(0.03 * v for v in _axis_vec(mount.axis)))
    if names:
        rec.log(path, rr.Arrows3D(origins=origins, vectors=vectors, colors=[C_SENSOR] * len(names),
                                  radii=[0.0015] * len(names), labels=names, show_labels=False), static=True)
