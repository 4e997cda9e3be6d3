"""The spatial scene family of the stability campaign (twin.studies.spatial_stability)."""

from __future__ import annotations

import dataclasses

import pytest

from twin.config import ConfigError
from twin.studies.spatial_stability import run_scene, sample_scene
from twin.studies.stability import StudySettings


def test_spatial_scenes_are_reproducible_and_within_their_ranges():
    a = [sample_scene(3, i) for i in range(20)]
    assert a == [sample_scene(3, i) for i in range(20)]
    for s in a:
        for j in "abc":
            assert 0.02 <= s[f"clearance_{j}_mm"] <= 2.0
        assert 0.08 <= s["crank_length_m"] <= 0.12 and 800 <= s["drive"]["motor_rpm"] <= 1500
        assert 0 <= s["mu0"] <= 0.2


def test_a_short_spatial_scene_runs_in_both_engines():
    scene = dict(sample_scene(1, 1), duration_s=0.01)
    met = run_scene(scene)
    assert not met["diverged"] and not met["reference_run"]["diverged"]
    assert set(met["joints"]) == {"A", "B", "C"} == set(met["reference_run"]["joints"])


def test_family_is_checked():
    with pytest.raises(ConfigError):
        dataclasses.replace(StudySettings(scenes=1), family="planar")


def test_agreement_factor_is_the_bench_familys():
    from twin.studies import spatial_stability as spatial
    from twin.studies import stability as bench

    assert spatial.REFERENCE_AGREEMENT == bench.REFERENCE_AGREEMENT
