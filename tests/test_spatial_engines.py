"""The spatial slider–crank of S002 in MuJoCo (twin.spatial.mujoco) against the closed form and the
spatial reference engine."""

from __future__ import annotations

import numpy as np
import pytest

from twin.config import named_preset
from twin.simulate import simulate_run
from twin.spatial.geometry import slider_closed_form
from twin.summary import summarize


def _s002(engine: str, **overrides):
    return named_preset("s002").replace(**{"simulation.engine": engine, **overrides})


def test_mujoco_ideal_slider_follows_closed_form():
    """Ideal joints (connect equalities, soft: MuJoCo has no hard loop closure): the slider's position
    against the closed form (twin.spatial.geometry) ≤ 1e-6 relative."""
    cfg = _s002("mujoco", **{"simulation.duration_s": 0.03, "joints.clearance_a_mm": 0.0,
                             "joints.clearance_b_mm": 0.0, "joints.clearance_c_mm": 0.0})
    run = simulate_run(cfg)
    x, _, _ = slider_closed_form(cfg, run["crank_angle"], run["crank_speed"])
    assert np.max(np.abs(run["slider_position"] - x)) <= 1e-6 * np.max(np.abs(x))
    assert np.ptp(run["slider_position"]) > 0.002  # millimetres of stroke within the window


def test_mujoco_first_impacts_match_reference():
    """0.1 mm radial clearance at A, B, C (S002 level 1): both engines start at speed with every joint
    centred; the joints' first contacts begin within a step of each other."""
    out = {}
    for engine in ("reference", "mujoco"):
        out[engine] = simulate_run(_s002(engine, **{"simulation.duration_s": 0.003}))
    for j in "ABC":
        ka = int(np.argmax(out["reference"][f"fn_{j}"] > 0))
        kb = int(np.argmax(out["mujoco"][f"fn_{j}"] > 0))
        assert ka > 0 and abs(ka - kb) <= 1, (j, ka, kb)


# S002's clearance levels (radial 0.1, 0.4, 0.7 mm, Eq. 1) as diametral clearances; measured gaps
# (0.3 s, h = 5 µs, the s002 preset otherwise): peak contact force MuJoCo vs reference
#   0.8 mm: A −3.3 %, B −8.5 %, C −7.8 %;  1.4 mm: A +6.9 %, B +19.4 %, C +17.0 %;
# slider acceleration RMS within 0.7 % at every level. Each engine's own peaks move as much with the
# step (reference at 1.4 mm, 5 → 2.5 µs: A 18 807 → 15 737 N; MuJoCo B 36 072 → 29 731 N): the largest
# impact of a chaotic sequence, not a converged quantity.
_LEVELS = [
    pytest.param(0.2, id="c0.1mm"),
    pytest.param(0.8, id="c0.4mm", marks=pytest.mark.xfail(strict=True, reason=(
        "peak contact force B −8.5 %, C −7.8 % (MuJoCo vs reference, 0.3 s at 5 µs): above 5 %"))),
    pytest.param(1.4, id="c0.7mm", marks=pytest.mark.xfail(strict=True, reason=(
        "peak contact force A +6.9 %, B +19.4 %, C +17.0 % (MuJoCo vs reference, 0.3 s at 5 µs): above 5 %"))),
]


@pytest.mark.slow
@pytest.mark.parametrize("clearance_mm", _LEVELS)
def test_engines_agree_at_s002_clearance_levels(clearance_mm):
    """Independent basis: the two engines (separate formulations: natural coordinates with an R matrix,
    MuJoCo's joint coordinates with native colliders). Peak contact force per joint within 5 %, slider
    acceleration RMS within 2 %."""
    c = clearance_mm
    s = {}
    for engine in ("reference", "mujoco"):
        run = simulate_run(_s002(engine, **{"joints.clearance_a_mm": c, "joints.clearance_b_mm": c,
                                            "joints.clearance_c_mm": c}))
        s[engine] = summarize(run)
    ref, mj = s["reference"], s["mujoco"]
    rms_r, rms_m = ref["slider_acceleration"]["rms_mps2"], mj["slider_acceleration"]["rms_mps2"]
    assert abs(rms_m / rms_r - 1) <= 0.02
    for j in "ABC":
        fr, fm = ref[j]["max_contact_force_N"], mj[j]["max_contact_force_N"]
        assert abs(fm / fr - 1) <= 0.05, (j, fr, fm)
