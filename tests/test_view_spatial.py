"""twin view of a run of S002's spatial slider–crank: the 3-D scene is the spatial mechanism.

A short MuJoCo run of the s002 preset (0.1 mm radial clearance at A, B and C, 800 rpm, 0.05 s)
is viewed through the command line and the logged transforms are checked against the spatial
kinematics written out here, not against the view's own code: the crank turns about +x in the
plane x = 0 with its pin on the circle of radius r (within A's clearance) at the run's crank
angle; the slider stays on its guide line (y, z of the configuration) at the closed-form
position of the ideal mechanism within the joints' clearances; the rod is rigid (its far ball
at distance L, on the slider's socket within C's clearance) and its near ball sits in the crank's
socket within B's clearance; the insets show the eccentricities magnified.
"""

from __future__ import annotations

import numpy as np
import pytest

from test_view import P, cli, read_rrd
from twin.config import named_preset
from twin.mcapfile import write_run
from twin.run import Run
from twin.simulation import simulate_run

#: rerun stores translations, quaternions and points as float32: ~1e-7 relative [-]
F32 = 1.2e-7


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors v (n, 3) by unit quaternions q (n, 4) in rerun's (x, y, z, w) order:
    v' = v + 2 w (u × v) + 2 u × (u × v)."""
    u, w = q[:, :3], q[:, 3:4]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


@pytest.fixture(scope="module")
def spatial_view(tmp_path_factory) -> tuple[Run, dict]:
    cfg = named_preset("s002").replace(**{"simulation.duration_s": 0.05, "simulation.engine": "mujoco"})
    run = simulate_run(cfg)
    d = tmp_path_factory.mktemp("spatial_view")
    write_run(d / "s002.mcap", run)
    assert cli("view", d / "s002.mcap") == 0
    return run, read_rrd(d / "s002.rrd")


def _transform(rr_: dict, entity: str) -> tuple[np.ndarray, np.ndarray]:
    ent = rr_[entity]
    return (np.array([r[0] for r in ent["Transform3D:translation"]]),
            np.array([r[0] for r in ent["Transform3D:quaternion"]]))


def test_spatial_scene_entities(spatial_view):
    run, rr_ = spatial_view
    assert {"/bench/crank/arm", "/bench/rod/beam", "/bench/rod/balls", "/bench/slider/block", "/bench/frame/eye_A",
            "/bench/crank/eye_B", "/bench/slider/eye_C", "/bench/frame/orbit_A/journal",
            "/bench/crank/orbit_B/journal", "/bench/slider/orbit_C/journal", "/orbit/A/journal"} <= set(rr_)
    assert not any(k.startswith("/bench/rod/orbit_") for k in rr_)  # no planar rod-frame insets
    # the orbit views hold the 3-D eccentricities [µm]
    pos = np.array([r[0] for r in rr_["/orbit/B/journal"]["Points3D:positions"]])
    np.testing.assert_allclose(pos[:, 2], run["ecc_B_z"][::10] * 1e6, rtol=1e-6, atol=1e-9)


def test_crank_turns_about_x_with_its_pin_on_the_circle(spatial_view):
    run, rr_ = spatial_view
    cfg = run.config
    r, c_a = cfg.bodies.crank.length_m, cfg.joints.radial_m("A")
    t, q = _transform(rr_, "/bench/crank")
    k = len(t)
    assert k == -(-run.n // P) and k >= 40
    # the crank's axis is +x; the arm's end (0, r, 0) in its frame is the pin B
    np.testing.assert_allclose(rotate(q, np.tile([1.0, 0, 0], (k, 1))), np.tile([1.0, 0, 0], (k, 1)), atol=4 * F32)
    b = t + rotate(q, np.tile([0.0, r, 0.0], (k, 1)))
    np.testing.assert_allclose(b[:, 0], 0.0, atol=4 * F32 * r)  # the crank's plane x = 0 (YOZ)
    pen = run["pen_A"].max()
    assert np.all(np.abs(np.linalg.norm(b[:, 1:], axis=1) - r) <= c_a + pen + 1e-8)
    assert np.all(np.linalg.norm(t, axis=1) <= c_a + pen + 1e-8)  # journal A in its bearing
    # at the run's crank angle (from +y about +x), over most of a turn
    theta = run["crank_angle"][::P]
    ang = np.arctan2(b[:, 2] - t[:, 2], b[:, 1] - t[:, 1])
    np.testing.assert_allclose(np.angle(np.exp(1j * (ang - theta))), 0.0, atol=8 * F32)
    assert np.ptp(theta) > 3.5


def test_slider_on_its_guide_at_the_spatial_kinematics(spatial_view):
    run, rr_ = spatial_view
    cfg = run.config
    r, L = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    a, b = cfg.spatial.guide_offset_y_m, cfg.spatial.guide_offset_z_m
    t, q = _transform(rr_, "/bench/slider")
    np.testing.assert_allclose(t[:, 1], a, atol=F32 * L)  # on the guide line along x through (0, a, b)
    np.testing.assert_allclose(t[:, 2], b, atol=F32 * L)
    # ideal kinematics: |C - B| = L with B = (0, r cos θ, r sin θ), C = (x, a, b), x > 0
    theta = run["crank_angle"][::P]
    x_ideal = np.sqrt(L**2 - (a - r * np.cos(theta)) ** 2 - (b - r * np.sin(theta)) ** 2)
    slack = sum(cfg.joints.radial_m(j) + run[f"pen_{j}"].max() for j in "ABC")
    dev = np.abs(t[:, 0] - x_ideal)
    assert np.all(dev <= 1.1 * slack), (dev.max(), slack)
    assert np.ptp(t[:, 0]) > 10 * dev.max()  # the stroke is seen, not hidden in the tolerance
    np.testing.assert_allclose(q, np.tile([0.0, 0, 0, 1], (len(q), 1)))  # the slider only translates


def test_rod_is_rigid_between_its_sockets(spatial_view):
    run, rr_ = spatial_view
    cfg = run.config
    r, L = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    tr, qr = _transform(rr_, "/bench/rod")
    tc, qc = _transform(rr_, "/bench/crank")
    ts, _ = _transform(rr_, "/bench/slider")
    k = len(tr)
    ball_b = tr
    ball_c = tr + rotate(qr, np.tile([L, 0.0, 0.0], (k, 1)))
    socket_b = tc + rotate(qc, np.tile([0.0, r, 0.0], (k, 1)))
    for j, ball, socket in (("B", ball_b, socket_b), ("C", ball_c, ts)):
        gap = np.linalg.norm(ball - socket, axis=1)
        assert np.all(gap <= cfg.joints.radial_m(j) + run[f"pen_{j}"].max() + 1e-6), (j, gap.max())
        assert gap.max() > 0.5 * cfg.joints.radial_m(j)  # the balls do move in their sockets
        ecc = np.stack([run[f"ecc_{j}_{a}"][::P] for a in "xyz"], axis=1)
        np.testing.assert_allclose(ball - socket, ecc, atol=2e-6)  # the run's own eccentricities


def test_insets_magnify_the_eccentricities(spatial_view):
    run, rr_ = spatial_view
    cfg = run.config
    r = cfg.bodies.crank.length_m
    _, qc = _transform(rr_, "/bench/crank")
    for j, ent, centre in (("B", "/bench/crank/orbit_B/journal", np.array([0.0, r, 0.0])),
                           ("C", "/bench/slider/orbit_C/journal", np.zeros(3))):
        pos = np.array([row[0] for row in rr_[ent]["Points3D:positions"]])
        d = pos - centre
        if j == "B":  # the crank's frame turns with θ: back to the spatial frame
            d = rotate(qc, d)
        ecc = np.stack([run[f"ecc_{j}_{a}"][::P] for a in "xyz"], axis=1)
        big = np.linalg.norm(ecc, axis=1) > 0.2 * cfg.joints.radial_m(j)
        m = np.linalg.norm(d[big], axis=1) / np.linalg.norm(ecc[big], axis=1)
        np.testing.assert_allclose(m, m[0], rtol=1e-5)
        assert m[0] * cfg.joints.radial_m(j) >= 0.01  # a 0.1 mm clearance drawn at least 1 cm
        np.testing.assert_allclose(d, m[0] * ecc, atol=4 * F32 * r)
