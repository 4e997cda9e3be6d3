"""Shared fixtures: short runs of the standard scenes, computed once per session."""

from __future__ import annotations

import numpy as np
import pytest

from twin.config import BenchConfig, preset


def short(cfg: BenchConfig, duration: float = 0.2, **overrides) -> BenchConfig:
    """A short copy of ``cfg`` (drive ramp shortened so the crank is turning)."""
    ov = {"simulation.duration_s": duration, "drive.ramp_s": min(cfg.drive.ramp_s, duration / 4)}
    ov.update(overrides)
    return cfg.replace(**ov)


def bore_bias_acceleration(m, d, pin: int, bore: int, qvel: np.ndarray) -> float:
    """-dJ/dt q̇ of a pin/bore contact row, by MuJoCo's own Jacobians and their time derivatives
    (mj_jacDot) at the kinematics in ``d`` and the velocity ``qvel``: the part of the
    penetration's acceleration that does not depend on q̈, n·(J̇_pin(x_p) − J̇_bore(x_b)) q̇ +
    |ė_⊥|²/|e| (e the pin centre minus the bore centre in the bore's plane, n = e/|e|), which the
    native module applies to the law's rate (twin/native/_bore.c, "Rates")."""
    import mujoco

    xp, xb = d.geom_xpos[pin].copy(), d.geom_xpos[bore].copy()
    axis = d.geom_xmat[bore].reshape(3, 3)[:, 2]
    bp, bb = m.geom_bodyid[pin], m.geom_bodyid[bore]
    jp, jb, jdp, jdb = (np.zeros((3, m.nv)) for _ in range(4))
    mujoco.mj_jac(m, d, jp, None, xp, bp)
    mujoco.mj_jac(m, d, jb, None, xb, bb)
    mujoco.mj_jacDot(m, d, jdp, None, xp, bp)
    mujoco.mj_jacDot(m, d, jdb, None, xb, bb)
    e = xp - xb
    e -= (e @ axis) * axis
    n = e / np.linalg.norm(e)
    ed = (jp - jb) @ qvel
    ed -= (ed @ axis) * axis
    return float(n @ ((jdp - jdb) @ qvel) + (ed @ ed - (ed @ n) ** 2) / np.linalg.norm(e))


@pytest.fixture(scope="session")
def cfg_test12() -> BenchConfig:
    return short(preset(12))
