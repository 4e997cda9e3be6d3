"""Shared fixtures: short runs of the standard scenes, computed once per session."""

from __future__ import annotations

import pytest

from twin.config import BenchConfig, preset


def short(cfg: BenchConfig, duration: float = 0.2, **overrides) -> BenchConfig:
    """A short copy of ``cfg`` (drive ramp shortened so the crank is turning)."""
    ov = {"simulation.duration_s": duration, "drive.ramp_s": min(cfg.drive.ramp_s, duration / 4)}
    ov.update(overrides)
    return cfg.replace(**ov)


@pytest.fixture(scope="session")
def cfg_test12() -> BenchConfig:
    return short(preset(12))
