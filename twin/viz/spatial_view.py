"""The 3-D view of a run of the spatial slider–crank (``spatial.enabled``, S002): poses from its
channels, its static geometry and the time-varying parts, beside the planar bench's
:mod:`twin.viz.pose` and :mod:`twin.viz.scene`.

Frame: the spatial frame of :mod:`twin.config.spatial` (origin at the crank pivot, crank axis +x,
crank in the plane x = 0, θ from +y about +x). From a run's ``crank_angle`` θ, the eccentricities
``ecc_J_x/y/z`` (pin − bushing centre in the spatial frame: A the crank's journal minus the frame's
bearing centre at the origin, B and C the rod's ball minus the socket's centre; zero at an ideal
joint) and ``slider_position`` s (along the guide from its point p0, :func:`twin.spatial.geometry.guide`):

* the crank's journal A = e_A and its socket B_c = A + r (0, cos θ, sin θ);
* the slider's socket C_s = p0 + s g; the balls B_r = B_c + e_B and C_r = C_s + e_C;
* without ``slider_position``, s closes the loop |C_r − B_r| = L (root on the slider's side).

Entities (metres, spatial frame):

* ``/bench/frame``: bearing housing about the crank axis, guide rail along the guide; with a
  clearance at A the bearing's bore and A's inset ``orbit_A`` (a circle in the crank's plane) and
  contact arrow ``contact_A``;
* ``/bench/crank``: rotated by θ about +x, translated by e_A: arm from A to B along its +y, the
  journal at A, the socket B (a wire sphere of the bore radius; a small solid sphere when ideal),
  B's inset ``orbit_B`` (three great circles of radius M·c) and contact arrow ``contact_B``,
  both in the crank's frame;
* ``/bench/rod``: origin at the ball B_r, +x towards C_r (shortest rotation from +x: the
  natural-coordinate rod has no spin): beam and both balls (true radius);
* ``/bench/slider``: translated to C_s: block below the socket C, the socket, C's inset and
  contact arrow (the slider only translates: its frame is the spatial frame's).

Each inset's point is the socket centre + M·e (M: :func:`twin.viz.scene.nice_magnification`, as
the planar view); a contact arrow shows the normal force on the pin (−f_n n, n = e/|e|, from the
contact point on the bore), peak of each pose window: the spatial channels hold the friction
force's magnitude only, not its direction. Visual-only sizes are those of :mod:`twin.viz.scene`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import rerun as rr

from twin.config import JOINTS, BenchConfig
from twin.errors import RecordingError
from twin.run import Run
from twin.spatial.geometry import guide, slider_closed_form
from twin.viz import scene

#: entity of each joint's socket (bushing), inset and contact arrow
JOINT_PARENT = {"A": "/bench/frame", "B": "/bench/crank", "C": "/bench/slider"}


@dataclass(frozen=True)
class SpatialPoses:
    """Points of the spatial mechanism at n samples (spatial frame, arrays (n, 3) [m]; θ (n,) [rad]).

    Attributes:
        theta: crank angle θ from +y about +x [rad].
        e_a, e_b, e_c: eccentricities (zeros at an ideal joint) [m].
        a: crank journal centre A (= e_A) [m].
        b_socket: crank's socket centre B_c [m].
        b_ball, c_ball: the rod's ball centres B_r, C_r [m].
        c_socket: slider's socket centre C_s, on the guide line [m].
    """

    theta: np.ndarray
    e_a: np.ndarray
    e_b: np.ndarray
    e_c: np.ndarray
    a: np.ndarray
    b_socket: np.ndarray
    b_ball: np.ndarray
    c_ball: np.ndarray
    c_socket: np.ndarray


def take(arr: np.ndarray, start: int, length: int, fill: float) -> np.ndarray:
    """arr[start:start+length] padded with ``fill`` where out of range."""
    out = np.full(length, fill, dtype=float)
    a, b = max(start, 0), min(start + length, len(arr))
    if b > a:
        out[a - start:b - start] = arr[a:b]
    return out


def eccentricity3(run: Run, joint: str, idx: np.ndarray | slice, n: int) -> np.ndarray:
    """Eccentricity of ``joint`` in the spatial frame, shape (n, 3) [m] (zeros if not recorded)."""
    keys = [f"ecc_{joint}_{k}" for k in "xyz"]
    if not all(k in run for k in keys):
        return np.zeros((n, 3))
    return np.stack([np.asarray(run[k][idx], dtype=float) for k in keys], axis=1)


def spatial_poses(run: Run, idx: np.ndarray | slice, cfg: BenchConfig) -> SpatialPoses | None:
    """Poses at samples ``idx`` of a spatial run (module docstring); None without ``crank_angle``."""
    if "crank_angle" not in run:
        return None
    theta = np.asarray(run["crank_angle"][idx], dtype=float)
    n = theta.shape[0]
    r, L = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    e_a, e_b, e_c = (eccentricity3(run, j, idx, n) for j in ("A", "B", "C"))
    b_socket = e_a + r * np.stack([np.zeros(n), np.cos(theta), np.sin(theta)], axis=1)
    b_ball = b_socket + e_b
    p0, g = guide(cfg)
    if "slider_position" in run:
        s = np.asarray(run["slider_position"][idx], dtype=float)
    else:
        d = p0[None, :] + e_c - b_ball
        gd = d @ g
        disc = gd * gd - np.einsum("ij,ij->i", d, d) + L * L
        if np.any(disc < 0) or not np.all(np.isfinite(disc)):
            raise RecordingError("pose reconstruction: crank angle and eccentricities do not close the loop "
                                 "(rod cannot reach the guide); check the run's configuration")
        s = -gd + np.sqrt(disc)
    c_socket = p0[None, :] + s[:, None] * g[None, :]
    return SpatialPoses(theta, e_a, e_b, e_c, e_a.copy(), b_socket, b_ball, c_socket + e_c, c_socket)


def rod_quaternion(b_ball: np.ndarray, c_ball: np.ndarray) -> np.ndarray:
    """Quaternions (x, y, z, w), shape (n, 4), of the shortest rotation taking +x to C_r − B_r."""
    u = c_ball - b_ball
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    q = np.stack([np.zeros(len(u)), -u[:, 2], u[:, 1], 1.0 + u[:, 0]], axis=1)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def crank_quaternion(theta: np.ndarray) -> np.ndarray:
    """Quaternions (x, y, z, w) of the rotation by θ about +x."""
    z = np.zeros_like(theta)
    return np.stack([np.sin(theta / 2), z, z, np.cos(theta / 2)], axis=1)


def to_crank_frame(v: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Vectors (n, 3) of the spatial frame in the crank's frame (rotated by −θ about x)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([v[:, 0], c * v[:, 1] + s * v[:, 2], -s * v[:, 1] + c * v[:, 2]], axis=1)


def great_circles(radius: float, centre: tuple[float, float, float] = (0.0, 0.0, 0.0), n: int = 96
                  ) -> list[np.ndarray]:
    """Three closed polylines: the great circles of a sphere in the planes x, y, z = const."""
    a = np.linspace(0.0, 2.0 * np.pi, n + 1)
    c, s, z = radius * np.cos(a), radius * np.sin(a), np.zeros_like(a)
    o = np.array(centre)
    return [o + np.stack(p, axis=1) for p in ((z, c, s), (c, z, s), (c, s, z))]


def yz_circle(radius: float, centre: tuple[float, float, float] = (0.0, 0.0, 0.0), n: int = 96) -> np.ndarray:
    """Closed polyline of a circle in the plane x = const (the crank's plane)."""
    return great_circles(radius, centre, n)[0]


@dataclass(frozen=True)
class SpatialSceneInfo:
    """What the static spatial scene drew (see :class:`twin.viz.scene.SceneInfo`).

    Attributes:
        joint_centres: socket (bore) centre of each joint in its parent's frame
            (:data:`JOINT_PARENT`) [m].
        radial: radial clearance per joint [m] (0 = ideal).
        magnification: inset magnification per clearance joint [-].
    """

    joint_centres: dict[str, tuple[float, float, float]]
    radial: dict[str, float]
    magnification: dict[str, int]


def inset_radius(cfg: BenchConfig, orbit_radius_m: float) -> float:
    """Target radius of the magnified insets [m]: ``orbit_radius_m``, at most 0.4 r (S002's crank is
    short: larger insets at A and B, r apart, would hide the crank)."""
    return min(orbit_radius_m, 0.4 * cfg.bodies.crank.length_m)


def magnifications(cfg: BenchConfig, orbit_radius_m: float) -> dict[str, int]:
    """Inset magnification of each clearance joint (:func:`twin.viz.scene.nice_magnification`)."""
    target = inset_radius(cfg, orbit_radius_m)
    return {j: scene.nice_magnification(cfg.joints.radial_m(j), target) for j in JOINTS
            if cfg.joints.radial_m(j) > 0}


_X_AXIS = rr.RotationAxisAngle(axis=(0.0, 1.0, 0.0), degrees=90.0)  # a cylinder's +z onto +x


def log_static_scene(rec: rr.RecordingStream, cfg: BenchConfig, orbit_radius_m: float) -> SpatialSceneInfo:
    """Log the frame, the bodies' geometry and the insets of the spatial mechanism (static)."""
    r, L = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    jt = cfg.joints
    radial = {j: jt.radial_m(j) for j in JOINTS}
    mag = magnifications(cfg, orbit_radius_m)
    half_a = jt.bushing_length("A") / 2.0
    centres = {"A": (-half_a - 0.004, 0.0, 0.0), "B": (0.0, r, 0.0), "C": (0.0, 0.0, 0.0)}
    rec.log("/bench", scene._VIEW_UP[cfg.mechanism.orientation], static=True)

    # frame: bearing housing behind the crank's plane (−x), rail under the slider's travel
    p0, g = guide(cfg)
    th = np.linspace(0.0, 2.0 * np.pi, 361)
    s = slider_closed_form(cfg, th, 0.0)[0]
    sl = cfg.bodies.slider.length_m
    s0, s1 = float(s.min()) - sl / 2 - 0.02, float(s.max()) + sl / 2 + 0.02
    sock_c = jt.bushing_radius_m("C") + scene.BUSHING_WALL
    rail_y = -sock_c - scene.BLOCK_H - 0.006
    mid, length = p0 + g * (s0 + s1) / 2, s1 - s0
    half = np.abs(g) * length / 2 + (1 - np.abs(g)) * np.array([scene.BLOCK_T / 2 + 0.004, 0.006,
                                                                scene.BLOCK_T / 2 + 0.004])
    rec.log("/bench/frame", rr.Boxes3D(
        centers=[(mid[0], mid[1] + rail_y, mid[2])], half_sizes=[tuple(half)], colors=[scene.C_FRAME],
        fill_mode="solid", labels=["guide"], show_labels=False), static=True)
    rec.log("/bench/frame/bearing", rr.Cylinders3D(
        lengths=[0.012], radii=[0.022], centers=[(-half_a - scene.ARM_THICK - 0.006, 0.0, 0.0)],
        rotation_axis_angles=[_X_AXIS], colors=[scene.C_FRAME], fill_mode="solid"), static=True)

    # crank (its frame: arm along +y, the crank's plane x = 0)
    rec.log("/bench/crank/arm", rr.Boxes3D(
        centers=[(0.0, r / 2, 0.0)], half_sizes=[(scene.ARM_THICK / 2, r / 2 + scene.ARM_WIDTH / 2, scene.ARM_WIDTH / 2)],
        colors=[scene.C_CRANK], fill_mode="solid", labels=["crank"], show_labels=False), static=True)
    rec.log("/bench/crank/pin_A", rr.Cylinders3D(
        lengths=[2 * half_a + 0.004], radii=[jt.pin_radius("A")], centers=[(-half_a, 0.0, 0.0)],
        rotation_axis_angles=[_X_AXIS], colors=[scene.C_PIN], fill_mode="solid"), static=True)
    # rod: beam between the balls, the balls at true size
    rb, rc = jt.pin_radius("B"), jt.pin_radius("C")
    rec.log("/bench/rod/beam", rr.Boxes3D(
        centers=[(L / 2, 0.0, 0.0)], half_sizes=[((L - rb - rc) / 2, scene.BEAM_WIDTH / 2, scene.BEAM_THICK / 2)],
        colors=[scene.C_ROD], fill_mode="solid", labels=["rod"], show_labels=False), static=True)
    rec.log("/bench/rod/balls", rr.Ellipsoids3D(
        centers=[(0.0, 0.0, 0.0), (L, 0.0, 0.0)], half_sizes=[(rb, rb, rb), (rc, rc, rc)],
        colors=[scene.C_PIN, scene.C_PIN], fill_mode="solid"), static=True)
    # slider: block below its socket
    rec.log("/bench/slider/block", rr.Boxes3D(
        centers=[(0.0, -sock_c - scene.BLOCK_H / 2, 0.0)],
        half_sizes=[tuple(np.abs(g) * sl / 2 + (1 - np.abs(g)) * np.array([scene.BLOCK_T / 2, scene.BLOCK_H / 2,
                                                                              scene.BLOCK_T / 2]))],
        colors=[scene.C_SLIDER], fill_mode="solid", labels=["slider"], show_labels=False), static=True)

    for j in JOINTS:
        parent, centre = JOINT_PARENT[j], centres[j]
        if j == "A":
            if radial[j] > 0:
                ri = jt.bushing_radius_m("A")
                rec.log(f"{parent}/eye_A", rr.LineStrips3D(
                    [yz_circle(ri, (x, 0.0, 0.0)) for x in (-half_a, half_a)], colors=[scene.C_BUSHING],
                    radii=[0.0006], labels=[f"A: bearing, bore {2e3 * ri:.3f} mm"], show_labels=False), static=True)
                rec.log(f"{parent}/orbit_A", rr.LineStrips3D(
                    [yz_circle(mag[j] * radial[j], centre)], colors=[scene.C_ORBIT], radii=[0.0008]), static=True)
        elif radial[j] > 0:
            ri = jt.bushing_radius_m(j)
            rec.log(f"{parent}/eye_{j}", rr.Ellipsoids3D(
                centers=[centre], half_sizes=[(ri, ri, ri)], colors=[scene.C_BUSHING], fill_mode="majorwireframe",
                labels=[f"{j}: socket, bore {2e3 * ri:.3f} mm"], show_labels=False), static=True)
            rec.log(f"{parent}/orbit_{j}", rr.LineStrips3D(
                great_circles(mag[j] * radial[j], centre), colors=[scene.C_ORBIT], radii=[0.0005]), static=True)
        else:
            rec.log(f"{parent}/eye_{j}", rr.Ellipsoids3D(
                centers=[centre], half_sizes=[(scene.BEARING_OUTER / 2,) * 3], colors=[scene.C_BEARING],
                fill_mode="majorwireframe", labels=[f"{j}: spherical joint (ideal)"], show_labels=False), static=True)
        if radial[j] > 0:
            m = mag[j]
            rec.log(f"{parent}/orbit_{j}/label", rr.Points3D(
                # A's label above its inset, B's below: apart whichever way the crank points
                [(centre[0], centre[1] + (m * radial[j] + 0.012 if j == "A" else -m * radial[j] - 0.018), centre[2])],
                radii=[0.0001], colors=[scene.C_ORBIT],
                labels=[f"{j} ×{m}"], show_labels=True), static=True)
    return SpatialSceneInfo(centres, radial, mag)


def log_orbit_clearance(rec: rr.RecordingStream, joint: str, c_um: float) -> None:
    """The clearance drawn in a joint's orbit view [µm]: a circle in the crank's plane at A, the
    sphere's great circles at B and C; axes x (red), y (green), z (blue)."""
    strips = [yz_circle(c_um)] if joint == "A" else great_circles(c_um)
    rec.log(f"/orbit/{joint}/clearance", rr.LineStrips3D(strips, colors=[scene.C_ORBIT], radii=[c_um / 150]),
            static=True)
    k = c_um * 0.25
    rec.log(f"/orbit/{joint}/axes", rr.Arrows3D(
        origins=[(0, 0, 0)] * 3, vectors=[(k, 0, 0), (0, k, 0), (0, 0, k)],
        colors=[(200, 60, 60), (60, 160, 60), (60, 90, 220)], radii=[c_um / 200] * 3), static=True)


def emit_poses(rec: rr.RecordingStream, tcol: rr.TimeColumn, p: SpatialPoses, sc: SpatialSceneInfo,
               joints: tuple[str, ...], buf: dict[str, np.ndarray], local: np.ndarray, start: int, period: int,
               cfg: BenchConfig, force_scale_m_per_n: float) -> None:
    """Send the bodies' transforms, the insets' magnified pin centres and the contact arrows of K
    poses (``local``: their indices in ``buf``; the pose windows are ``buf[start + k P : start +
    (k + 1) P]``)."""
    K = len(local)
    rec.send_columns("/bench/crank", indexes=[tcol], columns=rr.Transform3D.columns(
        translation=p.a, quaternion=crank_quaternion(p.theta)))
    rec.send_columns("/bench/rod", indexes=[tcol], columns=rr.Transform3D.columns(
        translation=p.b_ball, quaternion=rod_quaternion(p.b_ball, p.c_ball)))
    rec.send_columns("/bench/slider", indexes=[tcol], columns=rr.Transform3D.columns(
        translation=p.c_socket, quaternion=np.tile([0.0, 0.0, 0.0, 1.0], (K, 1))))
    theta_all = np.asarray(buf["crank_angle"], dtype=float)
    for j in joints:
        parent, m = JOINT_PARENT[j], sc.magnification[j]
        centre = np.array(sc.joint_centres[j])
        e = {"A": p.e_a, "B": p.e_b, "C": p.e_c}[j]
        if j == "B":
            e = to_crank_frame(e, p.theta)
        pen, fn = buf.get(f"pen_{j}"), buf.get(f"fn_{j}")
        inc = (pen[local] > 0) if pen is not None else (fn[local] > 0) if fn is not None else np.zeros(K, bool)
        colours = np.where(inc[:, None], np.array(scene.C_CONTACT), np.array(scene.C_ORBIT)).astype(np.uint8)
        rec.send_columns(f"{parent}/orbit_{j}/journal", indexes=[tcol], columns=rr.Points3D.columns(
            positions=centre + m * e, colors=colours, radii=np.full(K, 0.006, dtype=np.float32)))
        if fn is None:
            continue
        f_win = take(fn, start, K * period, -np.inf).reshape(K, period)
        j_pk = np.argmax(f_win, axis=1)
        f_pk = f_win[np.arange(K), j_pk]
        idx_pk = np.clip(start + np.arange(K) * period + j_pk, 0, len(fn) - 1)
        ev = np.stack([buf[f"ecc_{j}_{k}"][idx_pk] for k in "xyz"], axis=1)
        if j == "B":
            ev = to_crank_frame(ev, theta_all[idx_pk])
        norm = np.linalg.norm(ev, axis=1)
        on = (f_pk > 0) & (norm > 0)
        nv = np.where(on[:, None], ev / np.where(norm > 0, norm, 1.0)[:, None], 0.0)
        ri = cfg.joints.bushing_radius_m(j)
        base = centre if j != "A" else np.zeros(3)
        org = (base + ri * nv)[on]
        vec = (-force_scale_m_per_n * f_pk[:, None] * nv)[on]
        lengths = on.astype(np.int32)
        rec.send_columns(f"{parent}/contact_{j}", indexes=[tcol], columns=rr.Arrows3D.columns(
            origins=org, vectors=vec, labels=[f"{f:.0f} N" for f in f_pk[on]],
            colors=np.tile(np.array(scene.C_CONTACT, np.uint8), (int(on.sum()), 1)),
            radii=np.full(int(on.sum()), 0.002, dtype=np.float32)).partition(lengths))
