"""The typed summary of a stability campaign (``stability.json``'s ``summary``): :class:`StabilitySummary`, its
statistics :class:`Stats` (:func:`twin.studies.stability.summarize` computes them)."""

from __future__ import annotations

from dataclasses import dataclass

from twin.typed import Record

__all__ = ["StabilitySummary", "Stats"]


@dataclass(frozen=True)
class Stats(Record):
    """Statistics of a metric over the scenes that have it (finite values); only ``n`` (0) where none has.

    Attributes:
        n: scenes counted; min, median, mean, p95, max: the statistics [the metric's unit].
    """

    _OMIT_NONE = ("min", "median", "mean", "p95", "max")

    n: int
    min: float | None = None
    median: float | None = None
    mean: float | None = None
    p95: float | None = None
    max: float | None = None


@dataclass(frozen=True)
class StabilitySummary(Record):
    """The counts and statistics of a campaign.

    Attributes:
        scenes, passed, diverged: scenes run, passed and diverged.
        diverged_scenes, failed_scenes: their indices.
        pen_exceeded_scenes: scenes whose largest penetration exceeded the limit (not diverged);
            pen_exceeded_reference_agrees, pen_exceeded_physical, pen_exceeded_numerical: those the reference engine
            reproduced, and the cause it found.
        max_pen_over_c, max_pen_over_c_scene: the largest penetration / clearance [-] and its scene (NaN, None
            where no scene has one).
        pen_over_c: its statistics; guide_pen_over_c: the slider guide's (None: a campaign summarized before the
            guide was counted).
        energy_created, energy_created_scenes: scenes that created energy, their indices.
        residual_rel, residual_min_rel: the energy residual / positive work at the end and its least over the run [-].
        most_negative_residual_rel, most_negative_residual_scene: the least residual and its scene.
        tracking_max_rad, tracking_rms_rad: the crank's tracking error, largest and RMS [rad].
        wall_s: the campaign's wall time [s]; engine_wall_s: the engines' share summed over the scenes [s].
    """

    _OMIT_NONE = ("guide_pen_over_c",)
    _NESTED = {"pen_over_c": Stats, "guide_pen_over_c": Stats, "residual_rel": Stats, "residual_min_rel": Stats,
               "tracking_max_rad": Stats, "tracking_rms_rad": Stats}

    scenes: int
    passed: int
    diverged: int
    diverged_scenes: tuple[int, ...]
    failed_scenes: tuple[int, ...]
    pen_exceeded_scenes: tuple[int, ...]
    pen_exceeded_reference_agrees: tuple[int, ...]
    pen_exceeded_physical: tuple[int, ...]
    pen_exceeded_numerical: tuple[int, ...]
    max_pen_over_c: float | None
    max_pen_over_c_scene: int | None
    pen_over_c: Stats
    guide_pen_over_c: Stats | None = None
    energy_created: int = 0
    energy_created_scenes: tuple[int, ...] = ()
    residual_rel: Stats = Stats(0)
    residual_min_rel: Stats = Stats(0)
    most_negative_residual_rel: float | None = None
    most_negative_residual_scene: int | None = None
    tracking_max_rad: Stats = Stats(0)
    tracking_rms_rad: Stats = Stats(0)
    wall_s: float = 0.0
    engine_wall_s: float = 0.0
