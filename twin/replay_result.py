"""The report of a bench-recording replay (:func:`twin.bench_replay.replay`, ``twin.replay``) as a typed, frozen
value: :class:`ReplayResult`, with the simulated configuration (:class:`ReplayConfiguration`) and the crank
tracking (:class:`ReplayTracking`).

``to_dict()`` gives the report as the plain dict of ``report.json`` (``recordings/FORMAT.md`` describes its
keys), in the file's key order, plus ``files["report"]`` (the report files, written after it); ``from_dict`` reads
one back; ``to_json()`` is its strict JSON text. The per-sensor comparison, the calibration, the time-lag estimate
and the motor-drive comparison stay mappings keyed as in ``report.json``.
"""

from __future__ import annotations

import copy
import json
from dataclasses import dataclass, fields
from typing import Any, Mapping

__all__ = ["ReplayConfiguration", "ReplayResult", "ReplayTracking"]


@dataclass(frozen=True)
class ReplayConfiguration:
    """The bench configuration simulated by a replay.

    Attributes:
        name: the configuration's name.
        engine: the simulation engine ("mujoco", "reference").
        timestep_s: the engine's time step [s].
        clearance_b_mm: diametral clearance at joint B [mm] (0: ideal joint).
        clearance_c_mm: diametral clearance at joint C [mm].
        orientation: the vertical axis of the bench ("x", "y", "z").
        trace_filter_hz: cutoff of the drive's zero-phase filter of the encoder trace [Hz].
        same_as_recording: whether the model is the recording's own (no override changed it).
    """

    name: str
    engine: str
    timestep_s: float
    clearance_b_mm: float
    clearance_c_mm: float
    orientation: str
    trace_filter_hz: float
    same_as_recording: bool

    def to_dict(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True)
class ReplayTracking:
    """How closely the simulated crank followed the recorded one over the analysis window [encoder counts].

    Attributes:
        window_counts_note: what the figures are.
        sim_vs_recorded_max_counts: largest |simulated − recorded encoder angle|.
        sim_vs_recorded_rms_counts: its RMS.
        sim_vs_reference_max_counts: largest PID tracking error (simulated − filtered reference).
        reference_vs_recorded_max_counts: largest |filtered reference − recorded angle|.
        count_rad: one count [rad].
    """

    window_counts_note: str
    sim_vs_recorded_max_counts: float
    sim_vs_recorded_rms_counts: float
    sim_vs_reference_max_counts: float
    reference_vs_recorded_max_counts: float
    count_rad: float

    def to_dict(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True)
class ReplayResult:
    """The report of a replay (``report.json``).

    Attributes:
        recording: the recording replayed.
        recording_info: what the recording says of itself (notes, synthetic, source file, creator, extra).
        repairs: repairs made while reading it (one line each).
        configuration: the configuration simulated.
        sample_rate_hz: the recording's sample rate [Hz].
        samples: its samples.
        duration_s: its length [s].
        window_s: the analysis window (start, stop) from the first sample [s].
        crank_rate_hz: the mean crank rate over the window [Hz].
        time_lag_s: the lag kept between recorded and simulated signals [s] (> 0: the recorded lag).
        time_lag_note: what the sign means.
        time_lag_ci_s: its 95 % confidence interval (lo, hi) [s].
        time_lag_well_defined: whether the data tell the lag.
        time_lag_estimate: the estimate's details (:meth:`twin.signals.LagEstimate.to_dict`).
        tracking: the crank tracking error.
        calibration: the recorded and the simulated calibration.
        sensors: accelerometer -> its comparison (errors, NRMSE, correlation, DTW, harmonics, band energies).
        bands_hz: the frequency bands compared, (lo, hi) each [Hz].
        simulation: engine, time step, steps, wall time and real-time factor of the simulation.
        files: the files written, by kind.
        plots: PNG file -> what part of the recording it shows; None without plots.
        motor_drive: the motor drive's comparison beside the PID's; None unless replayed with ``drive="motor"``.
        wall_s: wall times [s] of the simulation and the whole replay.
    """

    recording: str
    recording_info: Mapping[str, Any]
    repairs: tuple[str, ...]
    configuration: ReplayConfiguration
    sample_rate_hz: float
    samples: int
    duration_s: float
    window_s: tuple[float, float]
    crank_rate_hz: float
    time_lag_s: float
    time_lag_note: str
    time_lag_ci_s: tuple[float, float]
    time_lag_well_defined: bool
    time_lag_estimate: Mapping[str, Any]
    tracking: ReplayTracking
    calibration: Mapping[str, Any]
    sensors: Mapping[str, Mapping[str, Any]]
    bands_hz: tuple[tuple[float, float], ...]
    simulation: Mapping[str, Any]
    files: Mapping[str, Any]
    plots: Mapping[str, Any] | None = None
    motor_drive: Mapping[str, Any] | None = None
    wall_s: Mapping[str, float] | None = None

    def to_dict(self) -> dict[str, Any]:
        """The report as the plain dict of ``report.json`` (a copy: changing it leaves the result as it was)."""
        out: dict[str, Any] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name in ("plots", "motor_drive", "wall_s") and v is None:
                continue  # absent from the report
            if isinstance(v, (ReplayConfiguration, ReplayTracking)):
                v = v.to_dict()
            elif f.name in ("repairs", "window_s", "time_lag_ci_s"):
                v = list(v)
            elif f.name == "bands_hz":
                v = [list(b) for b in v]
            else:
                v = copy.deepcopy(v)
            out[f.name] = v
        return out

    def to_json(self) -> str:
        """:meth:`to_dict` as strict, indented JSON text (numpy values as numbers, NaN as null)."""
        from twin.util import json_default, json_text

        return json_text(json.loads(json.dumps(self.to_dict(), default=json_default)))

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "ReplayResult":
        """The result of a report dict as :meth:`to_dict` (or ``report.json``) holds it; KeyError naming a
        missing key, TypeError for an unknown one."""
        kw = copy.deepcopy(dict(d))
        unknown = sorted(set(kw) - {f.name for f in fields(cls)})
        if unknown:
            raise TypeError(f"not a replay report: unknown key(s) {', '.join(unknown)}")
        kw["configuration"] = ReplayConfiguration(**kw["configuration"])
        kw["tracking"] = ReplayTracking(**kw["tracking"])
        kw["repairs"] = tuple(kw["repairs"])
        kw["window_s"] = tuple(kw["window_s"])
        kw["time_lag_ci_s"] = tuple(kw["time_lag_ci_s"])
        kw["bands_hz"] = tuple(tuple(b) for b in kw["bands_hz"])
        return cls(**kw)

    @classmethod
    def from_json(cls, text: str) -> "ReplayResult":
        """The result of a JSON text as :meth:`to_json` (or ``report.json``) holds it."""
        return cls.from_dict(json.loads(text))
