"""Mechanism poses from the channels of a run (vectorized over samples).

A run carries the crank angle (``crank_angle``; bench recordings only ``encoder_angle`` or
``encoder_counts``), the slider position (``slider_position``) and, at clearance joints, the
eccentricities ``ecc_J_x/y`` = pin − bushing centre in the ROD frame (conventions in
:mod:`twin.channels` and :mod:`twin.kinematics`). This module turns them into the planar
pose of every body, consistently with :func:`twin.kinematics.initial_pose`:

* B = e_A + r (cos θ, sin θ) is the crank pin (e_A: eccentricity of the crank journal in the
  frame's bore at a clearance ground pivot A, bench frame; zero at an ideal A); the rod eye
  (bushing) centre is B' = B − R(φ) e_B;
* the other rod eye is C = B' + l (cos φ, sin φ); the slider pin is C' = C + R(φ) e_C;
* C' lies d_off above the guide line y = 0: its y equation fixes the rod angle φ.

With eccentricities expressed in the rod frame, that y equation reads
``(l + e_Cx − e_Bx) sin φ + (e_Cy − e_By) cos φ = d_off − r sin θ − e_Ay``, i.e. a sin φ + b cos φ = s,
whose root on the slider's branch (cos φ > 0) is φ = asin(s / hypot(a, b)) − atan2(b, a): exact,
no iteration. Without eccentricities it reduces to :func:`twin.kinematics.rod_angle`. The x
equation is then redundant; :attr:`Poses.slider_x` is the reconstructed x of C', which a
simulated run's own ``slider_position`` must match (a consistency check used by the tests).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from twin.channels import bench_from_encoder
from twin.config import BenchConfig
from twin.errors import RecordingError
from twin.run import Run

#: Counts per crank revolution of the bench's crank encoder (SICK DGS80 with 4× counting,
#: S003 §2.3.3 / BENCH.md) when the configuration does not say; zero count = crank along −y,
#: like ``encoder_angle``.
ENCODER_COUNTS_PER_REV = 32768


@dataclass(frozen=True)
class Poses:
    """Planar poses of the mechanism at a set of samples (bench frame, arrays of length n).

    Attributes:
        theta: crank bench angle θ [rad].
        phi: rod angle φ from +x [rad].
        e_b, e_c: eccentricities at B and C in the rod frame, shape (n, 2) [m] (zeros if ideal).
        e_a: eccentricity at A (crank journal − frame bore), bench frame, shape (n, 2) [m]
            (zeros if ideal): the translation of the crank's frame.
        b_pin: crank pin centre B, shape (n, 2) [m].
        b_bush: rod eye centre B' (rod frame origin), shape (n, 2) [m].
        c_pin: slider pin centre C', shape (n, 2) [m].
        slider_x: x of C' on the guide [m] (reconstructed from θ, φ and the eccentricities).
    """

    theta: np.ndarray
    phi: np.ndarray
    e_b: np.ndarray
    e_c: np.ndarray
    b_pin: np.ndarray
    b_bush: np.ndarray
    c_pin: np.ndarray
    slider_x: np.ndarray
    e_a: np.ndarray


def crank_angle(run: Run, idx: np.ndarray | slice = slice(None)) -> np.ndarray | None:
    """Crank bench angle θ [rad] at samples ``idx``, from the best channel the run has.

    ``crank_angle`` if present, else ``encoder_angle`` (bench convention of
    :func:`twin.channels.bench_from_encoder`, with the configured crank direction), else
    ``encoder_counts`` (``instrumentation.encoder_counts_per_rev`` of the configuration, 32768
    by default). None if the run has none of them.
    """
    direction = run.config.mechanism.crank_direction if run.config is not None else 1
    if "crank_angle" in run:
        return np.asarray(run["crank_angle"][idx], dtype=float)
    if "encoder_angle" in run:
        return bench_from_encoder(np.asarray(run["encoder_angle"][idx], dtype=float), direction)
    if "encoder_counts" in run:
        inst = getattr(run.config, "instrumentation", None)
        cpr = getattr(inst, "encoder_counts_per_rev", ENCODER_COUNTS_PER_REV)
        phi = np.asarray(run["encoder_counts"][idx], dtype=float) * (2.0 * np.pi / cpr)
        return bench_from_encoder(phi, direction)
    return None


def eccentricity(run: Run, joint: str, idx: np.ndarray | slice = slice(None)) -> np.ndarray | None:
    """Eccentricity of ``joint`` (B, C: rod frame; A: bench frame), shape (n, 2) [m], or None if
    not recorded."""
    kx, ky = f"ecc_{joint}_x", f"ecc_{joint}_y"
    if kx in run and ky in run:
        return np.stack([np.asarray(run[kx][idx], dtype=float), np.asarray(run[ky][idx], dtype=float)], axis=1)
    return None


def rod_angle(theta: np.ndarray, r: float, l: float, d_off: float,
              e_b: np.ndarray | None = None, e_c: np.ndarray | None = None,
              e_a: np.ndarray | None = None) -> np.ndarray:
    """Rod angle φ [rad] closing the loop for crank angle θ and the eccentricities (B, C in the
    rod frame, A in the bench frame).

    Solves (l + e_Cx − e_Bx) sin φ + (e_Cy − e_By) cos φ = d_off − r sin θ − e_Ay on the slider's
    branch (see the module docstring). Raises :class:`RecordingError` where the rod cannot
    reach the guide (|s| > hypot(a, b)), which only corrupt data can cause.
    """
    theta = np.asarray(theta, dtype=float)
    n = theta.shape[0]
    zb = np.zeros((n, 2)) if e_b is None else e_b
    zc = np.zeros((n, 2)) if e_c is None else e_c
    a = l + zc[:, 0] - zb[:, 0]
    b = zc[:, 1] - zb[:, 1]
    s = d_off - r * np.sin(theta) - (0.0 if e_a is None else e_a[:, 1])
    rho = np.hypot(a, b)
    q = s / rho
    if np.any(np.abs(q) > 1.0) or not np.all(np.isfinite(q)):
        raise RecordingError("pose reconstruction: crank angle and eccentricities do not close the loop "
                             "(rod cannot reach the guide); check the run's configuration")
    return np.arcsin(q) - np.arctan2(b, a)


def _rot(phi: np.ndarray, v: np.ndarray) -> np.ndarray:
    """R(φ) v for arrays φ (n,) and v (n, 2)."""
    c, s = np.cos(phi), np.sin(phi)
    return np.stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1]], axis=1)


def poses(run: Run, idx: np.ndarray | slice = slice(None), cfg: BenchConfig | None = None) -> Poses | None:
    """Poses at samples ``idx`` of ``run`` (None if the run has no crank angle channel).

    Geometry (r, l, d_off) comes from ``cfg`` or the run's configuration (defaults otherwise).
    """
    cfg = cfg or run.config or BenchConfig()
    theta = crank_angle(run, idx)
    if theta is None:
        return None
    r, l, d_off = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m, cfg.mechanism.d_off_m
    n = theta.shape[0]
    e_a, e_b, e_c = (eccentricity(run, j, idx) for j in ("A", "B", "C"))
    e_a = np.zeros((n, 2)) if e_a is None else e_a
    e_b = np.zeros((n, 2)) if e_b is None else e_b
    e_c = np.zeros((n, 2)) if e_c is None else e_c
    phi = rod_angle(theta, r, l, d_off, e_b, e_c, e_a)
    b_pin = e_a + r * np.stack([np.cos(theta), np.sin(theta)], axis=1)
    b_bush = b_pin - _rot(phi, e_b)
    c_bush = b_bush + l * np.stack([np.cos(phi), np.sin(phi)], axis=1)
    c_pin = c_bush + _rot(phi, e_c)
    return Poses(theta, phi, e_b, e_c, b_pin, b_bush, c_pin, c_pin[:, 0].copy(), e_a)
