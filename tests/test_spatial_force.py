"""S002's spatial scene with ``mujoco.contact_source = "force"`` (the law and friction of the bore at A and the
sockets at B and C as passive forces, no contact row) against the spatial reference engine and ``"law"``."""

from __future__ import annotations

import numpy as np
import pytest

from twin.config import named_preset
from twin.simulation import simulate_run


def _s002(engine: str, **overrides):
    return named_preset("s002").replace(**{"simulation.engine": engine, **overrides})


def test_force_builds_without_pairs_and_fills_the_contact_sensors():
    from twin.spatial.mujoco import build

    cfg = _s002("mujoco", **{"mujoco.contact_source": "force"})
    _, model, _ = build(cfg, 0.0)
    assert model.npair == 0 and model.nuserdata == 2 * len(cfg.joints.clearance_joints)
    run = simulate_run(cfg.replace(**{"simulation.duration_s": 0.002}))
    for j in "ABC":
        assert np.all(np.isfinite(run[f"fn_{j}"]))
    assert float(np.max(run["fn_A"])) > 0  # the journal at A meets its bore within 2 ms


@pytest.mark.long
def test_force_first_impacts_match_reference():
    """As tests/test_spatial_engines.py's check of "law" (independent basis: the spatial reference engine): the
    joints' first contacts begin within a step of the reference's, and their peak force in the first 3 ms within
    5 % (measured: A −3.7 %, B −1.2 %, C −0.3 % at 0.1 mm radial; "law" −3.4 %, +0.4 %, −0.5 %)."""
    out = {}
    for engine, src in (("reference", "law"), ("mujoco", "force")):
        out[engine] = simulate_run(_s002(engine, **{"simulation.duration_s": 0.003, "mujoco.contact_source": src}))
    for j in "ABC":
        ka = int(np.argmax(out["reference"][f"fn_{j}"] > 0))
        kb = int(np.argmax(out["mujoco"][f"fn_{j}"] > 0))
        assert ka > 0 and abs(ka - kb) <= 1, (j, ka, kb)
        pa, pb = float(np.max(out["reference"][f"fn_{j}"])), float(np.max(out["mujoco"][f"fn_{j}"]))
        assert abs(pb / pa - 1) <= 0.05, (j, pa, pb)
