"""``twin study stability --bench``: the whole-bench draws (guide clearance, drive train) in both engines."""

from __future__ import annotations

import pytest

from twin.config.drivetrain import EXPLORE_RANGES
from twin.studies import stability as stability_study
from twin.studies import stability_bench as SB


def test_bench_draws_follow_the_plain_scene_and_cover_their_ranges():
    scenes = [stability_study.sample_scene(1, i, (0.3, 1.0), bench=True) for i in range(60)]
    for i, sc in enumerate(scenes):
        plain = stability_study.sample_scene(1, i, (0.3, 1.0))
        assert {k: sc[k] for k in plain} == plain          # the plain campaign's scene, unchanged
        g = sc["clearance_guide_mm"]
        assert g == 0.0 or SB.GUIDE_RANGE_MM[0] <= g <= SB.GUIDE_RANGE_MM[1]
        for _, field, _, (lo, hi) in EXPLORE_RANGES:
            assert lo <= sc["drivetrain"][field] <= hi
    assert {sc["drive_mode"] for sc in scenes} == {"pid", "motor"}
    assert any(sc["clearance_guide_mm"] == 0 for sc in scenes) and any(sc["clearance_guide_mm"] > 0 for sc in scenes)
    cfg = stability_study.scene_config({**next(sc for sc in scenes if sc["drive_mode"] == "motor" and sc["drive"]["program"]
                                 != "startstop"), "engine": "reference"})
    assert cfg.drive.mode == "motor" and cfg.simulation.engine == "reference" and "motor" in cfg.sensors.channels


def test_short_bench_campaign_in_both_engines():
    """Two short bench scenes (a motor scene with guide play, a PID one), each in both engines: no
    divergence, no energy created."""
    res = stability_study.run_study(stability_study.StudySettings(scenes=2, seed=1, duration_range_s=(0.1, 0.2), bench=True))
    data = res.to_dict()
    s = data["summary"]
    assert s["scenes"] == 4 and s["diverged"] == 0 and s["energy_created"] == 0, stability_study.one_line(res)
    assert [r["scene"]["engine"] for r in data["scenes"]] == list(SB.ENGINES) * 2


@pytest.mark.slow
def test_full_bench_campaign():
    """The full campaign (500 scenes of 0.5-3 s, each in both engines: about 25 min on 2 cores, estimated):
    0 divergences and no energy created."""
    res = stability_study.run_study(stability_study.StudySettings(scenes=500, seed=1, bench=True))
    s = res.summary
    assert s["diverged"] == 0 and s["energy_created"] == 0, stability_study.one_line(res)
