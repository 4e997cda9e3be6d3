"""The report of a bench-recording replay (:func:`twin.bench_replay.replay`, ``twin.replay``) as a typed, frozen
value: :class:`ReplayResult`, with the simulated configuration (:class:`ReplayConfiguration`), the crank
tracking (:class:`ReplayTracking`), one :class:`SensorComparison` per accelerometer (its band energies as
:class:`BandComparison`) and, replayed with the motor drive, the :class:`MotorDriveComparison` (one
:class:`MotorDriveSensor` per accelerometer).

``to_dict()`` gives the report as the plain dict of ``report.json`` (``recordings/FORMAT.md`` describes its
keys), in the file's key order, plus ``files["report"]`` (the report files, written after it); ``from_dict`` reads
one back; ``to_json()`` is its strict JSON text. Each typed row's ``to_dict()`` is its part of ``report.json``,
key order included. The calibrations, the time-lag estimate's details, the simulation's figures and the files stay
mappings keyed as in ``report.json``.
"""

from __future__ import annotations

import copy
import dataclasses
import json
from dataclasses import dataclass, fields
from typing import Any, Mapping

__all__ = ["BandComparison", "MotorDriveComparison", "MotorDriveSensor", "ReplayConfiguration", "ReplayResult",
           "ReplayTracking", "SensorComparison"]


def _plain(row: Any) -> dict[str, Any]:
    """A flat row's fields as a dict in field order, tuples as lists."""
    return {f.name: list(v) if isinstance(v := getattr(row, f.name), tuple) else v for f in fields(row)}


def _row(cls: type, d: Mapping[str, Any], where: str) -> Any:
    """The row ``cls`` of the dict ``d``: every field, tuples for lists; KeyError or TypeError naming ``where``."""
    names = [f.name for f in fields(cls)]
    unknown = sorted(set(d) - set(names))
    if unknown:
        raise TypeError(f"{where}: unknown key(s) {', '.join(unknown)}")
    missing = [n for n in names if n not in d]
    if missing:
        raise KeyError(f"{where}: missing key(s) {', '.join(missing)}")
    return cls(**{n: tuple(v) if isinstance(v := d[n], list) else copy.deepcopy(v) for n in names})


@dataclass(frozen=True)
class BandComparison:
    """The energy of one frequency band of a sensor's recorded and simulated signals (Hann PSD) [dB re 1 (m/s²)²].

    Attributes:
        f_lo_hz, f_hi_hz: the band [Hz].
        recorded_db, simulated_db: the band energy of each signal [dB].
        difference_db: simulated − recorded [dB].
    """

    f_lo_hz: float
    f_hi_hz: float
    recorded_db: float
    simulated_db: float
    difference_db: float

    def to_dict(self) -> dict[str, Any]:
        return _plain(self)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "BandComparison":
        return _row(cls, d, "band")


@dataclass(frozen=True)
class SensorComparison:
    """One accelerometer's recorded and simulated accelerations compared over the analysis window, after the time
    lag is removed (:func:`twin.bench_replay.compare_accelerations`) [m/s² unless named otherwise].

    Attributes:
        recorded_mean_mps2, recorded_std_mps2: the recorded signal's mean and standard deviation.
        noise_rms_mps2: the sensor's noise (NaN where unknown).
        near_constant: whether the recorded signal is nearly constant (its NRMSE, correlation and DTW then compare
            noise, not motion); near_constant_note: why ("" if not).
        rms_error_mps2, max_abs_error_mps2: RMS and largest |simulated − recorded|.
        nrmse_pct: RMS error / (max − min of the recorded signal) [%].
        correlation: Pearson correlation [-].
        recorded_rms_mps2, simulated_rms_mps2, recorded_peak_mps2, simulated_peak_mps2: RMS and peak |a| of each.
        dtw_distance_pct: RMS difference along the optimal warping path / (max − min recorded) [%];
            dtw_mean_shift_s: the path's mean time shift [s]; dtw_samples: samples compared by DTW.
        harmonics_hz: the crank-rate harmonics compared [Hz].
        recorded_harmonic_amplitudes_mps2, simulated_harmonic_amplitudes_mps2: their Hann amplitudes.
        bands: the band energies compared.
    """

    recorded_mean_mps2: float
    recorded_std_mps2: float
    noise_rms_mps2: float
    near_constant: bool
    near_constant_note: str
    rms_error_mps2: float
    max_abs_error_mps2: float
    nrmse_pct: float
    correlation: float
    recorded_rms_mps2: float
    simulated_rms_mps2: float
    recorded_peak_mps2: float
    simulated_peak_mps2: float
    dtw_distance_pct: float
    dtw_mean_shift_s: float
    dtw_samples: int
    harmonics_hz: tuple[float, ...]
    recorded_harmonic_amplitudes_mps2: tuple[float, ...]
    simulated_harmonic_amplitudes_mps2: tuple[float, ...]
    bands: tuple[BandComparison, ...]

    def to_dict(self) -> dict[str, Any]:
        return {**_plain(self), "bands": [b.to_dict() for b in self.bands]}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "SensorComparison":
        row = _row(cls, d, "sensor comparison")
        return dataclasses.replace(row, bands=tuple(BandComparison.from_dict(b) for b in d["bands"]))


@dataclass(frozen=True)
class MotorDriveSensor:
    """One accelerometer in the motor-driven replay beside the PID replay (same window and time lag).

    Attributes:
        nrmse_pct, correlation, dtw_distance_pct: the motor-driven run's figures (as :class:`SensorComparison`).
        simulated_rms_mps2, simulated_peak_mps2: its simulated RMS and peak [m/s²].
        pid_nrmse_pct, pid_correlation, pid_dtw_distance_pct: the PID replay's figures.
    """

    nrmse_pct: float
    correlation: float
    dtw_distance_pct: float
    simulated_rms_mps2: float
    simulated_peak_mps2: float
    pid_nrmse_pct: float
    pid_correlation: float
    pid_dtw_distance_pct: float

    def to_dict(self) -> dict[str, Any]:
        return _plain(self)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "MotorDriveSensor":
        return _row(cls, d, "motor-drive sensor")


@dataclass(frozen=True)
class MotorDriveComparison:
    """The replay driven by the recorded motor command (speed loop and V-belt) beside the PID replay.

    Attributes:
        note: what the comparison is.
        tracking: simulated vs recorded encoder angle, max and RMS, and the PID replay's max [counts].
        crank_speed_ripple_pct: the motor run's crank speed ripple in the window, (max − min) / mean [%]; None
            for an empty window.
        sensors: accelerometer -> its figures.
        simulation: wall time [s], engine, steps and real-time factor of the motor run.
    """

    note: str
    tracking: Mapping[str, float]
    crank_speed_ripple_pct: float | None
    sensors: Mapping[str, MotorDriveSensor]
    simulation: Mapping[str, Any]

    def to_dict(self) -> dict[str, Any]:
        return {"note": self.note, "tracking": dict(self.tracking), "crank_speed_ripple_pct": self.crank_speed_ripple_pct,
                "sensors": {a: m.to_dict() for a, m in self.sensors.items()}, "simulation": copy.deepcopy(dict(self.simulation))}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "MotorDriveComparison":
        row = _row(cls, d, "motor drive")
        return dataclasses.replace(row, tracking=dict(d["tracking"]),
                                   sensors={a: MotorDriveSensor.from_dict(m) for a, m in d["sensors"].items()})


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
    sensors: Mapping[str, SensorComparison]
    bands_hz: tuple[tuple[float, float], ...]
    simulation: Mapping[str, Any]
    files: Mapping[str, Any]
    plots: Mapping[str, Any] | None = None
    motor_drive: MotorDriveComparison | None = None
    wall_s: Mapping[str, float] | None = None

    def to_dict(self) -> dict[str, Any]:
        """The report as the plain dict of ``report.json`` (a copy: changing it leaves the result as it was)."""
        out: dict[str, Any] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name in ("plots", "motor_drive", "wall_s") and v is None:
                continue  # absent from the report
            if isinstance(v, (ReplayConfiguration, ReplayTracking, MotorDriveComparison)):
                v = v.to_dict()
            elif f.name == "sensors":
                v = {a: m.to_dict() for a, m in v.items()}
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
        kw["sensors"] = {a: SensorComparison.from_dict(m) for a, m in kw["sensors"].items()}
        if kw.get("motor_drive") is not None:
            kw["motor_drive"] = MotorDriveComparison.from_dict(kw["motor_drive"])
        kw["repairs"] = tuple(kw["repairs"])
        kw["window_s"] = tuple(kw["window_s"])
        kw["time_lag_ci_s"] = tuple(kw["time_lag_ci_s"])
        kw["bands_hz"] = tuple(tuple(b) for b in kw["bands_hz"])
        return cls(**kw)

    @classmethod
    def from_json(cls, text: str) -> "ReplayResult":
        """The result of a JSON text as :meth:`to_json` (or ``report.json``) holds it."""
        return cls.from_dict(json.loads(text))
