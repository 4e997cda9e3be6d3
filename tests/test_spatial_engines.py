"""The spatial slider–crank of S002 in MuJoCo (twin.spatial.mujoco) against the closed form and the
spatial reference engine."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from twin.config import named_preset
from twin.simulation import simulate_run
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


@pytest.mark.long  # a few seconds: run by CI and with -m long
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


# S002's clearance levels (radial 0.1, 0.4, 0.7 mm, Eq. 1) as diametral clearances. Measured gaps of the
# s002 preset's own 0.3 s run at its 5 µs step (MuJoCo vs reference), its largest force per joint:
#   0.2 mm: A −3.4 %, B +0.4 %, C −0.5 %, RMS −0.9 %
#   0.8 mm: A −2.4 %, B −19.8 %, C −4.6 %, RMS +1.7 %
#   1.4 mm: A −2.3 %, B −16.7 %, C −4.3 %, RMS +5.7 %
# The largest force of a 0.3 s run is one impact of a chaotic sequence (4-5 crank turns): each engine's own
# value moves by as much with the step (at 1.25 µs the gaps at B are +6.5 %, −2.0 %, −17.9 %), so it is not a
# quantity two models can agree on. What is reproducible is the distribution of the impacts: over 10 s (130 turns
# at 800 rpm) the mean of each turn's peak force agrees within 1.7 % at 1.4 mm (A −0.3 %, B −1.5 %, C −1.7 %, RMS
# 0.0 %), where 18 turns still leave 5-13 % by the draw (and the sign flips with the step). The comparison below is
# that: the mean per-turn peak contact force of each joint within 5 %, the slider acceleration's RMS within 2 %,
# over 10 s after the first turn.
AGREE_S = 10.0


@functools.lru_cache(maxsize=None)
def _turn_statistics(clearance_mm: float) -> tuple[dict, dict]:
    """Per engine: mean over whole crank turns (after the first) of each joint's peak contact force [N],
    and the slider acceleration's RMS [m/s²]."""
    c = clearance_mm
    out = []
    for engine in ("reference", "mujoco"):
        run = simulate_run(_s002(engine, **{"joints.clearance_a_mm": c, "joints.clearance_b_mm": c,
                                            "joints.clearance_c_mm": c, "simulation.duration_s": AGREE_S}))
        th = np.unwrap(np.asarray(run["crank_angle"], float))
        turn = np.floor((th - th[0]) / (2 * np.pi)).astype(int)
        # whole turns 1 .. last-1 (the crank turns one way): each one's samples [edges[k], edges[k + 1])
        edges = np.searchsorted(turn, np.arange(1, turn.max() + 1))
        stats = {j: float(np.mean(np.maximum.reduceat(np.asarray(run[f"fn_{j}"]), edges)[:-1]))
                 for j in "ABC"}
        a = np.asarray(run["slider_acceleration"], float)[turn >= 1]
        stats["rms"] = float(np.sqrt(np.mean(a * a)))
        stats["turns"] = int(turn.max()) - 1
        out.append(stats)
    return out[0], out[1]


@pytest.mark.slow
@pytest.mark.parametrize("clearance_mm", (0.2, 0.8, 1.4))
@pytest.mark.parametrize("quantity", ("A", "B", "C", "rms"))
def test_engines_agree_at_s002_clearance_levels(clearance_mm, quantity):
    """Independent basis: the two engines (separate formulations: natural coordinates with an R matrix,
    MuJoCo's joint coordinates with native colliders). Mean per-turn peak contact force of each joint within
    5 %, slider acceleration RMS within 2 % (see the note above on why not the largest force of a short run)."""
    ref, mj = _turn_statistics(clearance_mm)
    assert ref["turns"] >= 100
    tol = 0.02 if quantity == "rms" else 0.05
    assert abs(mj[quantity] / ref[quantity] - 1) <= tol, (quantity, ref[quantity], mj[quantity])


_GAPS = {(0.8, "B"): "−19.8 %", (1.4, "B"): "−16.7 %", (1.4, "rms"): "+5.7 %"}


@functools.lru_cache(maxsize=None)
def _summaries(clearance_mm: float) -> tuple[dict, dict]:
    c = clearance_mm
    out = []
    for engine in ("reference", "mujoco"):
        run = simulate_run(_s002(engine, **{"joints.clearance_a_mm": c, "joints.clearance_b_mm": c,
                                            "joints.clearance_c_mm": c}))
        out.append(summarize(run))
    return out[0], out[1]


@pytest.mark.slow
@pytest.mark.parametrize("clearance_mm,quantity", [
    pytest.param(c, q, id=f"{c}mm-{q}", marks=[pytest.mark.xfail(strict=True, reason=(
        f"measured gap {_GAPS[(c, q)]} (MuJoCo vs reference, s002 preset, 0.3 s at 5 µs): one impact of a chaotic "
        "sequence, see the note above"))] if (c, q) in _GAPS else [])
    for c in (0.2, 0.8, 1.4) for q in ("A", "B", "C", "rms")])
def test_engines_largest_force_of_the_presets_short_run(clearance_mm, quantity):
    """The s002 preset's 0.3 s run, as the Taguchi study runs it: the largest contact force of each joint within
    5 % and the slider acceleration's RMS within 2 % where the start's impacts dominate (they agree within a step,
    test above); where a later impact of the chaotic sequence sets the largest force, they do not (xfail)."""
    ref, mj = _summaries(clearance_mm)
    if quantity == "rms":
        r, m = ref["slider_acceleration"]["rms_mps2"], mj["slider_acceleration"]["rms_mps2"]
        assert abs(m / r - 1) <= 0.02, (r, m)
    else:
        r, m = ref[quantity]["max_contact_force_N"], mj[quantity]["max_contact_force_N"]
        assert abs(m / r - 1) <= 0.05, (r, m)
