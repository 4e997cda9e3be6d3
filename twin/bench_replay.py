"""Replay a bench recording through the twin and compare measured with simulated accelerations.

S003 §4.3 and Fig. 16: the crank angle measured by the encoder drives the simulation through the
PID; the virtual accelerometers go through the same sensor chain and the same calibration as the
real ones; the two are compared. Steps of :func:`replay`:

1. read and validate the recording (:func:`twin.recording.read_recording`), repairs reported;
2. encoder counts → encoder angle (count centres), handed to the drive in memory
   (:class:`twin.tracefile.DriveInputs`) and written to ``encoder_trace.npz`` in the output folder
   as an output; the drive's ``trace`` program turns it into the reference angle and rate with its zero-phase
   filter (``drive.trace_filter_hz``, :meth:`twin.drive.DriveReference._prepare_trace`);
3. simulate with the recording's bench configuration, or an overridden one (e.g. ideal joints
   on a clearance recording, as in Fig. 16), at the recording's sample rate
   (:func:`twin.simulation.simulate`);
4. virtual sensor chain on the simulated run (:func:`twin.instrument.apply_chain`), its zero-g
   offsets set to the recording's calibration so that raw volts are comparable, calibrated
   with a simulated static recording exactly as the bench calibrates (Eq. 1–4);
5. comparison over an analysis window: time alignment (:func:`twin.signals.estimate_lag`: the
   lag that best explains the recorded sensors by the simulated ones, each sensor weighted by its
   evidence, with a 95 % confidence interval; no shift is kept when the data cannot tell), per-sensor errors (RMS, peak, NRMSE vs the recorded range,
   correlation), the paper's normalized DTW distance and time shift (:mod:`twin.signals`),
   Hann-windowed spectra with the crank rate and its harmonics and the 1 kHz / 3 kHz band
   energies, crank tracking error in encoder counts;
6. output folder: ``replay.mcap`` (recorded and simulated channels side by side, names in
   ``recordings/FORMAT.md``), ``report.json``, ``report.md``, PNG plots, ``encoder_trace.npz``.
   The folder is written under a temporary name beside it and renamed into place at the end, so
   an existing folder is replaced whole or left as it was (bad input found late, an error,
   Ctrl-C, SIGTERM); every input (recording, configuration, window) is checked before anything
   is written.

The simulation starts at rest at the first recorded angle: recordings should start with the
crank at rest (the bench protocol does); otherwise exclude the catch-up from the window.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from twin.channels import encoder_from_bench
from twin.config import ACCELEROMETERS, CHANNEL_GROUPS, BenchConfig
from twin.config.drivetrain import Drivetrain
from twin.errors import ConfigError, RecordingError, TwinError
from twin.instrument import (apply_chain, counts_to_angle, measured_accel, simulated_calibration)
from twin.instrument.encoder import count_step_rad
from twin.recording import read_recording
from twin.replay_result import ReplayResult
from twin.run import Channel, Run
from twin.signals import band_energy_db, dtw_compare, hann_spectrum
from twin.tracefile import DriveInputs
from twin.util import json_default, json_text

#: Frequency bands of S003 Fig. 15 where clearance raises spectral activity [Hz]. The paper
#: shades them without giving edges; ±200 Hz around 1 kHz and ±300 Hz around 3 kHz is our
#: reading of the figure (PLACEHOLDER).
DEFAULT_BANDS_HZ: tuple[tuple[float, float], ...] = ((800.0, 1200.0), (2700.0, 3300.0))


@dataclass(frozen=True)
class ReplayOptions:
    """Analysis settings of a replay.

    Attributes:
        window_s: analysis window (start, stop) in recording time from its first sample [s];
            None = the second half of the recording, at most 1 s, ending 2/``drive.trace_filter_hz``
            before the end (edge of the trace filter).
        max_lag_s: largest time lag searched when aligning simulated to recorded signals [s].
        dtw_window_s: Sakoe–Chiba half-width of the DTW comparison [s] (the replay is aligned by
            construction, so a narrow band suffices).
        dtw_max_s: DTW is computed on at most this much of the window, from its start [s] (cost).
        bands_hz: frequency bands whose energy is compared [Hz].
        harmonics: number of crank-rate multiples marked and tabulated (rate and harmonics).
        static_s: length of the simulated static calibration recording [s].
        nan: NaN policy of the recording reader ("error" or "interpolate").
        plots: write PNG plots.
        progress: show a progress bar while simulating.
        drive: "pid" (the crank PID on the encoder trace, S003 §4.3) or "motor": in addition, the
            motor model (``drive.mode = "motor"``, ``[drivetrain]``) driven by the recording's motor
            command channel (``motor_command_trace.npz``) is simulated and compared with the recording
            the same way; the report puts the two drives side by side (``motor_drive``). The MCAP
            file, plots and the main tables stay the PID replay's.
    """

    window_s: tuple[float, float] | None = None
    max_lag_s: float = 0.005
    dtw_window_s: float = 0.002
    dtw_max_s: float = 0.5
    bands_hz: tuple[tuple[float, float], ...] = DEFAULT_BANDS_HZ
    harmonics: int = 7
    static_s: float = 1.0
    nan: str = "error"
    plots: bool = True
    progress: bool = False
    drive: str = "pid"

    def __post_init__(self) -> None:
        for name in ("max_lag_s", "dtw_window_s", "dtw_max_s"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and 0 <= v <= 10):
                raise ConfigError(name, f"must lie in [0, 10] s, got {v!r}")
        if self.dtw_window_s == 0:  # the library's "no band": a full DTW of up to dtw_max_s, O(n²) (minutes)
            raise ConfigError("dtw_window_s", "must lie in (0, 10] s: 0 is a DTW without a band, whose cost grows "
                                              "with the square of the samples compared (minutes on 0.5 s at 100 kHz)")
        if self.dtw_max_s < 0.001:  # DTW on a few samples says nothing
            raise ConfigError("dtw_max_s", f"must be at least 0.001 s, got {self.dtw_max_s!r}")
        if self.drive not in ("pid", "motor"):
            raise ConfigError("drive", f"must be pid or motor, got {self.drive!r}")


def check_replayable(rec: Run, info: Any, base: BenchConfig, where: str, command: str | None = None) -> None:
    """What a recording must hold before the twin replays it under ``base`` (``twin replay``, ``twin calibrate``):
    whole crank turns (:func:`check_motion`), calibration data, the DAQ rate of ``base``'s instrumentation, and
    the motor command where ``command`` (what needs it, for the message) is given. One-line
    :class:`RecordingError` starting with ``where`` otherwise."""
    check_motion(rec, where)
    if info.calibration is None:
        raise RecordingError(f"{where}: no calibration data; import it again with a static recording in the "
                             "calibration pose or the six sensors' known zero-g offsets")
    inst = base.instrumentation
    if abs(inst.daq_rate_hz - rec.rate_hz) > 1e-6 * rec.rate_hz:
        raise RecordingError(f"{where}: instrumentation.daq_rate_hz ({inst.daq_rate_hz:g} Hz) differs from the "
                             f"recording's rate ({rec.rate_hz:g} Hz)")
    if command is not None and "motor_command" not in rec:
        raise RecordingError(f"{where}: {command} needs the recording's motor_command channel; it has none")


def torque_as_pid(cfg: BenchConfig) -> dict[str, Any]:
    """Overrides that replay a torque-driven configuration by the crank PID on a trace: the torque mode has no
    speed program to follow a trace, and a coast-down passes the motor drive's speed range; the PID reads no
    drive-train field, so they go back to their defaults (the PID mode refuses them). Empty for other modes."""
    if cfg.drive.mode != "torque":
        return {}
    return {"drive.mode": "pid", **{f"drivetrain.{f.name}": f.default for f in dataclasses.fields(Drivetrain)}}


#: the drive modes that follow a trace; a replay drives the crank by the recording's encoder trace in one of them
TRACE_MODES = ("pid", "prescribed")
#: [drive] fields of the programs a trace replaces (the steps and the protocol) and of the ripple imposed on a
#: program: a replay's trace holds what the crank did, ripple included
_PROGRAM_ONLY = ("steps_s", "steps_rpm", "protocol_rpm", "protocol_hold_s", "protocol_stop_s", "ripple_pct",
                 "ripple_phase_rad")
#: the [drivetrain] fields of the torque program alone (the motor mode refuses them)
_TORQUE_ONLY = ("torque_s", "torque_nm", "torque_ramp_s", "release_s")


def trace_drive(cfg: BenchConfig) -> dict[str, Any]:
    """Overrides that make ``cfg``'s drive follow the recording's encoder trace, whatever drove the recorded run: a
    motor or torque drive becomes the crank PID (the motor's speed loop and belt only follow a reference through
    their own dynamics: a motor recording replayed by them lagged its trace by a tenth of a turn), its drive-train
    fields back to their defaults (:func:`torque_as_pid`); the fields of the program the trace replaces and any
    imposed ripple (the trace holds the recorded ripple; imposed again it doubles) back to theirs. Empty where
    ``cfg`` already follows a trace as it is."""
    from twin.config.drive import Drive

    over = {"drive.mode": "pid", **{f"drivetrain.{f.name}": f.default for f in dataclasses.fields(Drivetrain)}} \
        if cfg.drive.mode not in TRACE_MODES else {}
    default = Drive()
    over |= {f"drive.{n}": getattr(default, n) for n in _PROGRAM_ONLY if getattr(cfg.drive, n) != getattr(default, n)}
    return over


def replay_config(rec_cfg: BenchConfig, trace_file: Path, rec: Run, zero_g_v: dict[str, float]) -> BenchConfig:
    """Simulation configuration of a replay: ``rec_cfg`` driven by the trace at the recording's rate
    (:func:`trace_drive`: a motor- or torque-driven recording is replayed by the crank PID on the trace)."""
    return rec_cfg.replace(**trace_drive(rec_cfg), **{
        "drive.program": "trace", "drive.trace_file": str(trace_file),
        "drive.crank_rpm": 0.0,  # the constant program's speed: the trace replaces it (nonzero is refused with it)
        "simulation.duration_s": rec.n / rec.rate_hz,
        "sensors.output_rate_hz": rec.rate_hz, "sensors.channels": list(CHANNEL_GROUPS),
        "instrumentation.zero_g_v": dict(zero_g_v),
    })


def _window_indices(n: int, rate: float, window_s: tuple[float, float] | None,
                    edge_s: float = 0.0) -> tuple[int, int]:
    T = n / rate
    if window_s is None:
        t1 = T - min(edge_s, T / 10.0)
        t0 = max(T / 2.0, t1 - 1.0)
    else:
        t0, t1 = window_s
        if not (0 <= t0 < t1 <= T + 1e-12):
            raise TwinError(f"need 0 <= start < stop <= {T:g} s (recording length), got {t0:g} {t1:g}",
                            field="window_s")
    i0, i1 = int(round(t0 * rate)), min(n, int(round(t1 * rate)))
    if i1 - i0 < 16:
        raise TwinError(f"{t0:g}..{t1:g} s holds fewer than 16 samples", field="window_s")
    return i0, i1


def _harmonic_amplitudes(f: np.ndarray, amp: np.ndarray, freqs: np.ndarray) -> list[float]:
    df = f[1] - f[0]
    out = []
    for fh in freqs:
        k = int(round(fh / df))
        lo, hi = max(0, k - 1), min(len(f), k + 2)
        out.append(float(np.max(amp[lo:hi])) if lo < hi else float("nan"))
    return out


#: a recorded channel whose standard deviation in the window is below this share of its mean...
NEAR_CONSTANT_OF_MEAN = 0.01
#: ...or below this multiple of its sensor's noise is nearly constant (see :func:`near_constant`)
NEAR_CONSTANT_OF_NOISE = 3.0


def sensor_noise_rms(cfg: BenchConfig, sensor: str, rate_hz: float) -> float:
    """RMS noise of an accelerometer over the recording's band [m/s²]: the datasheet density
    (twin.instrument.accel) over 0 … rate/2, whatever the configuration's noise switch (the
    bench's sensors have it)."""
    from twin.instrument.accel import STANDARD_G, model_of

    return model_of(cfg.instrumentation, sensor).noise_g_rthz * STANDARD_G * math.sqrt(rate_hz / 2.0)


def near_constant(x: np.ndarray, noise_rms: float = 0.0) -> str:
    """Why a recorded channel is nearly constant over the window, or "" if it is not: its spread
    (standard deviation) is below 1 % of its mean (a sensor axis that feels gravity and almost no
    motion, e.g. AC5 at 1 g) or below 3 times its sensor's noise. Such a channel's NRMSE,
    correlation and DTW distance compare noise with noise, not motion."""
    mean, std = float(np.mean(x)), float(np.std(x))
    why = []
    if std < NEAR_CONSTANT_OF_MEAN * abs(mean):
        why.append(f"{100 * std / abs(mean):.2g} % of the mean {mean:.3g} m/s²")
    if noise_rms > 0 and std < NEAR_CONSTANT_OF_NOISE * noise_rms:
        why.append(f"{std / noise_rms:.2f} times the sensor noise {noise_rms:.2g} m/s²")
    return f"standard deviation {std:.2g} m/s² = " + ", ".join(why) if why else ""


def compare_accelerations(rec: dict[str, np.ndarray], sim: dict[str, np.ndarray], rate: float,
                          crank_rate_hz: float, opts: ReplayOptions,
                          noise_rms: dict[str, float] | None = None) -> dict[str, Any]:
    """Per-sensor comparison of aligned recorded and simulated accelerations [m/s²];
    ``noise_rms``: each sensor's noise [m/s²], for the near-constant check (:func:`near_constant`)."""
    out: dict[str, Any] = {}
    harm = crank_rate_hz * np.arange(1, opts.harmonics + 1)
    n_dtw = min(len(next(iter(rec.values()))), max(16, int(round(opts.dtw_max_s * rate))))
    for name in rec:
        x, y = rec[name].astype(np.float64), sim[name].astype(np.float64)
        e = y - x
        rng = float(np.max(x) - np.min(x))
        sx, sy = float(np.std(x)), float(np.std(y))
        corr = float(np.corrcoef(x, y)[0, 1]) if sx > 0 and sy > 0 else float("nan")
        d = dtw_compare(x[:n_dtw], y[:n_dtw], rate, opts.dtw_window_s) if rng > 0 else None
        f, ax = hann_spectrum(x, rate, remove_mean=True)
        _, ay = hann_spectrum(y, rate, remove_mean=True)
        bands = []
        for lo, hi in opts.bands_hz:
            if hi <= rate / 2 and len(x) / rate * (hi - lo) >= 1:
                er, es = band_energy_db(x, rate, lo, hi), band_energy_db(y, rate, lo, hi)
                bands.append({"f_lo_hz": lo, "f_hi_hz": hi, "recorded_db": er, "simulated_db": es,
                              "difference_db": es - er})
        flat = near_constant(x, (noise_rms or {}).get(name, 0.0))
        out[name] = {
            "recorded_mean_mps2": float(np.mean(x)), "recorded_std_mps2": sx,
            "noise_rms_mps2": (noise_rms or {}).get(name, float("nan")),
            "near_constant": bool(flat), "near_constant_note": flat,
            "rms_error_mps2": float(np.sqrt(np.mean(e * e))),
            "max_abs_error_mps2": float(np.max(np.abs(e))),
            "nrmse_pct": 100.0 * float(np.sqrt(np.mean(e * e))) / rng if rng > 0 else float("nan"),
            "correlation": corr,
            "recorded_rms_mps2": float(np.sqrt(np.mean(x * x))), "simulated_rms_mps2": float(np.sqrt(np.mean(y * y))),
            "recorded_peak_mps2": float(np.max(np.abs(x))), "simulated_peak_mps2": float(np.max(np.abs(y))),
            "dtw_distance_pct": d.distance_pct if d else float("nan"),
            "dtw_mean_shift_s": d.mean_shift_s if d else float("nan"),
            "dtw_samples": n_dtw,
            "harmonics_hz": [float(h) for h in harm],
            "recorded_harmonic_amplitudes_mps2": _harmonic_amplitudes(f, ax, harm),
            "simulated_harmonic_amplitudes_mps2": _harmonic_amplitudes(f, ay, harm),
            "bands": bands,
        }
    return out


def check_motion(run: Run, where: str, min_turns: float = 1.0, min_ratio: float = 0.5) -> None:
    """Refuse a recording whose crank does not turn: at least ``min_turns`` net crank revolutions,
    and net motion at least ``min_ratio`` of the path travelled at 1 ms resolution (a random walk
    of the encoder travels far and arrives nowhere)."""
    cfg = run.config
    c = np.asarray(run.channels["encoder_counts"].data, dtype=np.float64)
    cpr = float(cfg.instrumentation.encoder_counts_per_rev) if cfg is not None else 1.0
    k = max(1, int(round(run.rate_hz * 0.001)))
    d = c[::k]
    net = abs(float(d[-1] - d[0])) / cpr if d.size else 0.0
    path = float(np.sum(np.abs(np.diff(d)))) / cpr if d.size > 1 else 0.0
    if net < min_turns or net < min_ratio * path:
        raise RecordingError(f"{where}: too little motion to replay: the crank turns {net:.2f} revolutions net "
                             f"over a path of {path:.2f} (at least {min_turns:g} net revolutions and "
                             f"{min_ratio:.0%} of the path are needed)")


#: the files a replay writes in its folder; an existing folder holding anything else is not replaced
REPLAY_FILES = frozenset({"replay.mcap", "report.json", "report.md", "encoder_trace.npz", "accelerations.png",
                          "spectra.png", "tracking.png"})


def replay(recording: str | Path, out_dir: str | Path,
           configure: Callable[[BenchConfig], BenchConfig] | None = None,
           opts: ReplayOptions = ReplayOptions()) -> ReplayResult:
    """Replay ``recording`` (see the module docstring); returns the report
    (:class:`~twin.replay_result.ReplayResult`; ``.to_dict()`` as ``report.json`` holds it).

    ``configure`` maps the recording's bench configuration to the one to simulate (CLI
    overrides); None keeps it.
    """
    from twin.util import check_output_dir, replace_dir, temp_path

    wall0 = time.perf_counter()
    # the folder is replaced whole at the end: an existing one may hold only what a replay writes
    # (never the recording, never the user's other files), and the recording must not lie inside it
    final = check_output_dir(out_dir, need_parent=False, own=lambda n: n in REPLAY_FILES, inputs=(recording,))
    rec, info, repairs = read_recording(recording, nan=opts.nan)
    rec_cfg = rec.config
    base = configure(rec_cfg) if configure is not None else rec_cfg
    check_replayable(rec, info, base, str(recording), "`drive` motor" if opts.drive == "motor" else None)
    trace = final / "encoder_trace.npz"
    # the simulated configuration (checked before anything is written) and the analysis window
    cfg = replay_config(base, trace, rec, dict(info.calibration.zero_g_v))
    if opts.drive == "motor":
        motor_config(cfg, final / "motor_command_trace.npz", base)  # checked before anything is written
    edge = 2.0 / cfg.drive.trace_filter_hz if cfg.drive.trace_filter_hz > 0 else 0.0
    window = _window_indices(rec.n, rec.rate_hz, opts.window_s, edge)
    # everything is written into a temporary folder beside the target, renamed into place at the
    # end: an existing folder is replaced whole or left as it was (error, Ctrl-C, SIGTERM)
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp = temp_path(final)
    tmp.mkdir()
    try:
        report = _replay_into(tmp, recording, rec, info, repairs, rec_cfg, base, cfg, window, opts, wall0)
        replace_dir(tmp, final)
    except BaseException:
        import shutil

        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return ReplayResult.from_dict(report)


def _replay_into(out: Path, recording: str | Path, rec: Run, info: Any, repairs: list[str],
                 rec_cfg: BenchConfig, base: BenchConfig, cfg: BenchConfig, window: tuple[int, int],
                 opts: ReplayOptions, wall0: float) -> dict[str, Any]:
    """Steps 2-6 of :func:`replay`, writing into the folder ``out`` (renamed into place by the
    caller); the configuration ``cfg`` names the trace at its final place (an output: the
    simulation takes the trace's arrays in memory)."""
    from twin.mcapfile import write_run
    from twin.simulation import simulate_run
    from twin.util import atomic_write_json, atomic_write_text

    # 1-2. encoder counts -> angle trace for the drive
    inst = cfg.instrumentation
    cpr = inst.encoder_counts_per_rev
    count = count_step_rad(cpr)
    phi = counts_to_angle(rec["encoder_counts"], cpr, centre=inst.encoder_quantization)
    t_rel = np.arange(rec.n) / rec.rate_hz
    inputs = DriveInputs(trace=(t_rel, phi))
    trace = out / "encoder_trace.npz"
    np.savez(trace, t=t_rel, angle=phi)  # an output (the configuration names it), never read back here
    stored_cfg = cfg

    # 3. simulate
    t_sim = time.perf_counter()
    sim = simulate_run(cfg, progress=opts.progress, inputs=inputs)
    sim_wall = time.perf_counter() - t_sim
    if sim.n != rec.n:
        raise TwinError(f"internal: simulated {sim.n} samples for a {rec.n}-sample recording")

    # 4. virtual sensor chain + the bench's calibration on both sides
    # noise streams 2 and 3: independent of a synthetic recording's own (0 and 1)
    sim_daq = apply_chain(sim, cfg, prefix="sim_", stream=2, drive_inputs=inputs)
    sim_cal = simulated_calibration(cfg, opts.static_s, stream=3)
    sim_meas = measured_accel(sim_daq, sim_cal, prefix="sim_")
    rec_meas = measured_accel(rec, info.calibration)
    sensors = [a for a in ACCELEROMETERS if f"meas_{a}" in rec_meas]

    # 5. comparison
    # default window (replay()): skip the last 2/cutoff seconds, where the trace filter's edge
    # extension (constant acceleration) departs from the true motion
    i0, i1 = window
    rate = rec.rate_hz
    max_lag = int(round(opts.max_lag_s * rate))
    from twin.signals import estimate_lag as _estimate_lag

    lag_est = _estimate_lag([rec_meas[f"meas_{a}"][i0:i1] for a in sensors],
                            [sim_meas[f"sim_meas_{a}"][i0:i1] for a in sensors], max_lag, rate)
    lag = lag_est.lag
    # aligned pairs: rec[i + lag] vs sim[i]
    j0, j1 = max(i0, -lag, 0), min(i1, rec.n - lag, rec.n)
    rec_al = {a: rec_meas[f"meas_{a}"][j0 + lag:j1 + lag] for a in sensors}
    sim_al = {a: sim_meas[f"sim_meas_{a}"][j0:j1] for a in sensors}
    turns = (phi[i1 - 1] - phi[i0]) / (2 * math.pi)
    crank_rate_hz = abs(turns) / ((i1 - 1 - i0) / rate)
    comparison = compare_accelerations(rec_al, sim_al, rate, crank_rate_hz, opts,
                                       {a: sensor_noise_rms(rec_cfg, a, rate) for a in sensors})

    sim_phi = sim["encoder_angle"].astype(np.float64)
    track = (sim_phi - phi)[i0:i1] / count
    ref_phi = encoder_from_bench(sim["theta_ref"], cfg.mechanism.crank_direction)
    pid = (sim_phi - ref_phi)[i0:i1] / count
    ref_vs_counts = (ref_phi - phi)[i0:i1] / count
    tracking = {
        "window_counts_note": "errors in encoder counts (1 count = 2*pi/counts_per_rev rad)",
        "sim_vs_recorded_max_counts": float(np.max(np.abs(track))),
        "sim_vs_recorded_rms_counts": float(np.sqrt(np.mean(track ** 2))),
        "sim_vs_reference_max_counts": float(np.max(np.abs(pid))),
        "reference_vs_recorded_max_counts": float(np.max(np.abs(ref_vs_counts))),
        "count_rad": count,
    }

    report: dict[str, Any] = {
        "recording": str(recording),
        "recording_info": {"notes": info.notes, "synthetic": info.synthetic, "source_file": info.source_file,
                           "created_by": info.created_by, "extra": info.extra},
        "repairs": list(info.repairs) + repairs,
        "configuration": {"name": cfg.name, "engine": cfg.simulation.engine,
                          "timestep_s": cfg.simulation.timestep_s,
                          "clearance_b_mm": cfg.joints.clearance_b_mm, "clearance_c_mm": cfg.joints.clearance_c_mm,
                          "orientation": cfg.mechanism.orientation, "trace_filter_hz": cfg.drive.trace_filter_hz,
                          "same_as_recording": _same_model(rec_cfg, base)},
        "sample_rate_hz": rate, "samples": rec.n, "duration_s": rec.n / rate,
        "window_s": [i0 / rate, i1 / rate],
        "crank_rate_hz": crank_rate_hz,
        "time_lag_s": lag / rate, "time_lag_note": "> 0: recorded signals lag the simulated ones",
        "time_lag_ci_s": list(lag_est.ci_s), "time_lag_well_defined": lag_est.well_defined,
        "time_lag_estimate": lag_est.to_dict(),
        "tracking": tracking,
        "calibration": {"recorded": info.calibration.to_dict(), "simulated": sim_cal.to_dict()},
        "sensors": comparison,
        "bands_hz": [list(b) for b in opts.bands_hz],
        "simulation": {k: sim.meta.get(k) for k in ("engine", "timestep_s", "steps", "wall_s", "real_time_factor")},
        "files": {},
    }

    # 6. outputs
    rec_angle = Channel("rec_encoder_angle", "rad", "rec_encoder", phi)
    chans = {**rec.channels, **rec_meas.channels, rec_angle.name: rec_angle, **sim.channels,
             **sim_daq.channels, **sim_meas.channels}
    chans = {k: dataclasses.replace(c, data=np.ascontiguousarray(c.data, dtype=np.float32 if c.data.dtype == np.float32
                                                                  else np.float64)) for k, c in chans.items()}
    both = Run(rec.t0, rate, chans, stored_cfg, {**sim.meta, "replay_of": str(recording)})
    mcap_path = out / "replay.mcap"
    write_run(mcap_path, both, extra_metadata={"twin.replay": {"json": json_text(report, indent=None)},
                                               "twin.recording": info.to_record()})
    report["files"]["mcap"] = mcap_path.name
    report["files"]["trace"] = trace.name
    if opts.plots:
        report["plots"] = _plots(out, rec_al, sim_al, rate, j0, comparison, crank_rate_hz, opts,
                                 track, pid, i0, sim, phi, cfg, rec.n / rate)
        report["files"]["plots"] = list(report["plots"])
    if opts.drive == "motor":
        report["motor_drive"] = _motor_drive(out, rec, cfg, inputs, phi, window, lag, sensors, rec_meas,
                                             crank_rate_hz, opts, comparison, tracking, base)
        report["files"]["motor_command_trace"] = "motor_command_trace.npz"
    report["wall_s"] = {"simulation": sim_wall, "total": time.perf_counter() - wall0}
    atomic_write_json(out / "report.json", json.loads(json.dumps(report, default=json_default)))
    atomic_write_text(out / "report.md", render_markdown(report))
    report["files"]["report"] = ["report.json", "report.md"]
    return report


def motor_config(cfg: BenchConfig, command_trace: Path, base: BenchConfig | None = None) -> BenchConfig:
    """The PID replay's configuration ``cfg`` driven instead by the motor model from the recorded
    command (``drivetrain.command_file``), with the motor channels; the drive train's fields are those of
    ``base`` (the configuration replayed) where it drives by the motor or torque (the torque program's aside),
    else their defaults."""
    groups = list(cfg.sensors.channels) + (["motor"] if "motor" not in cfg.sensors.channels else [])
    train = {f"drivetrain.{f.name}": getattr(base.drivetrain, f.name) for f in dataclasses.fields(Drivetrain)
             if f.name not in _TORQUE_ONLY + ("command_file",)} \
        if base is not None and base.drive.mode in ("motor", "torque") else {}
    return cfg.replace(**train, **{"drive.mode": "motor", "drivetrain.command_file": str(command_trace),
                                   "sensors.channels": groups})


def _motor_drive(out: Path, rec: Run, cfg: BenchConfig, inputs: DriveInputs, phi: np.ndarray,
                 window: tuple[int, int], lag: int, sensors: list[str], rec_meas: Run, crank_rate_hz: float,
                 opts: ReplayOptions,
                 pid_comparison: dict[str, Any], pid_tracking: dict[str, Any],
                 base: BenchConfig | None = None) -> dict[str, Any]:
    """The motor-driven replay (:class:`ReplayOptions` ``drive = "motor"``): simulate, put through the
    same sensor chain and calibration, compare over the same window with the PID replay's time lag."""
    from twin.simulation import simulate_run

    t_cmd, volts = np.arange(rec.n) / rec.rate_hz, np.asarray(rec["motor_command"], dtype=np.float64)
    inputs = DriveInputs(trace=inputs.trace, command=(t_cmd, volts))
    trace = out / "motor_command_trace.npz"
    np.savez(trace, t=t_cmd, volts=volts)  # an output, never read back here
    mcfg = motor_config(cfg, trace, base)
    t0 = time.perf_counter()
    sim = simulate_run(mcfg, progress=opts.progress, inputs=inputs)
    wall = time.perf_counter() - t0
    sim_meas = measured_accel(apply_chain(sim, mcfg, prefix="sim_", stream=2, drive_inputs=inputs),
                              simulated_calibration(mcfg, opts.static_s, stream=3), prefix="sim_")
    i0, i1 = window
    j0, j1 = max(i0, -lag, 0), min(i1, rec.n - lag, rec.n)
    comparison = compare_accelerations({a: rec_meas[f"meas_{a}"][j0 + lag:j1 + lag] for a in sensors},
                                       {a: sim_meas[f"sim_meas_{a}"][j0:j1] for a in sensors}, rec.rate_hz,
                                       crank_rate_hz, opts)
    count = count_step_rad(cfg.instrumentation.encoder_counts_per_rev)
    track = (sim["encoder_angle"].astype(np.float64) - phi)[i0:i1] / count
    speed = np.gradient(np.asarray(sim["crank_angle"], dtype=np.float64)[i0:i1]) * rec.rate_hz
    return {
        "note": "motor speed loop and V-belt driven by the recorded motor command; same window and time lag "
                "as the PID replay",
        "tracking": {"sim_vs_recorded_max_counts": float(np.max(np.abs(track))),
                     "sim_vs_recorded_rms_counts": float(np.sqrt(np.mean(track ** 2))),
                     "pid_sim_vs_recorded_max_counts": pid_tracking["sim_vs_recorded_max_counts"]},
        "crank_speed_ripple_pct": float(100 * (speed.max() - speed.min()) / abs(speed.mean())) if speed.size else None,
        "sensors": {a: {k: comparison[a][k] for k in ("nrmse_pct", "correlation", "dtw_distance_pct",
                                                      "simulated_rms_mps2", "simulated_peak_mps2")}
                    | {f"pid_{k}": pid_comparison[a][k] for k in ("nrmse_pct", "correlation", "dtw_distance_pct")}
                    for a in sensors},
        "simulation": {"wall_s": wall, **{k: sim.meta.get(k) for k in ("engine", "steps", "real_time_factor")}},
    }


def _same_model(a: BenchConfig, b: BenchConfig) -> bool:
    """Whether the simulated model equals the recording's: same mechanism, contact, sensors,
    engine and step (drive program, duration and output settings aside: the channel groups are the replay's)."""
    keep = ("bodies", "materials", "joints", "mechanism", "contact", "mujoco", "pid")
    return (all(getattr(a, k) == getattr(b, k) for k in keep)
            and dataclasses.replace(a.sensors, channels=b.sensors.channels) == b.sensors
            and a.simulation.engine == b.simulation.engine and a.simulation.timestep_s == b.simulation.timestep_s)


def _fmt(v: Any, spec: str = ".3g") -> str:
    if isinstance(v, float) and not math.isfinite(v):
        return "–"
    return format(v, spec) if isinstance(v, (int, float)) else str(v)


def _lag_text(r: dict[str, Any]) -> str:
    """'+0.000 ms (95 % CI -0.010..+0.010 ms, peak well defined)' from a replay report."""
    text = f"{r['time_lag_s'] * 1e3:+.3f} ms"
    est = r.get("time_lag_estimate")
    if not est or "ci_s" not in est:
        return text
    lo, hi = (v * 1e3 for v in est["ci_s"])
    return f"{text} ({100 * est['confidence']:g} % CI {lo:+.3f}..{hi:+.3f} ms, {est['note']})"


def render_markdown(r: dict[str, Any]) -> str:
    """Markdown version of a replay report."""
    c = r["configuration"]
    tr = r["tracking"]
    lines = [
        f"# Replay of `{r['recording']}`", "",
        f"- recording: {r['duration_s']:.3f} s at {r['sample_rate_hz']:g} Hz"
        + (" (synthetic)" if r["recording_info"]["synthetic"] else "")
        + (f"; notes: {r['recording_info']['notes']}" if r["recording_info"]["notes"] else ""),
        f"- model: {c['name']}, engine {c['engine']}, h = {c['timestep_s']:g} s, clearance B {c['clearance_b_mm']:g} mm, "
        f"C {c['clearance_c_mm']:g} mm, orientation {c['orientation']} "
        f"({'same model as the recording' if c['same_as_recording'] else 'model differs from the recording'})",
        f"- analysis window: {r['window_s'][0]:.3f}–{r['window_s'][1]:.3f} s; crank rate {r['crank_rate_hz']:.3f} Hz; "
        f"time lag {_lag_text(r)}",
        f"- crank tracking (window): simulated vs recorded angle max {tr['sim_vs_recorded_max_counts']:.2f} counts, "
        f"RMS {tr['sim_vs_recorded_rms_counts']:.2f} counts; PID vs reference max {tr['sim_vs_reference_max_counts']:.2f} "
        f"counts; filtered reference vs counts max {tr['reference_vs_recorded_max_counts']:.2f} counts",
    ]
    if r["repairs"]:
        lines += ["- repairs: " + "; ".join(r["repairs"])]
    lines += ["", "## Accelerations (calibrated, m/s²)", "",
              "| sensor | RMS rec | RMS sim | RMS error | NRMSE % | peak rec | peak sim | corr | DTW % | DTW shift ms |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    flat = {a: m["near_constant_note"] for a, m in r["sensors"].items() if m.get("near_constant")}
    for a, m in r["sensors"].items():
        nc = "near-constant*"
        lines.append(f"| {a} | {_fmt(m['recorded_rms_mps2'])} | {_fmt(m['simulated_rms_mps2'])} | "
                     f"{_fmt(m['rms_error_mps2'])} | {nc if a in flat else _fmt(m['nrmse_pct'])} | "
                     f"{_fmt(m['recorded_peak_mps2'])} | {_fmt(m['simulated_peak_mps2'])} | "
                     f"{nc if a in flat else _fmt(m['correlation'], '.4f')} | "
                     f"{nc if a in flat else _fmt(m['dtw_distance_pct'])} | "
                     f"{nc if a in flat else _fmt(m['dtw_mean_shift_s'] * 1e3)} |")
    for a, why in flat.items():
        lines += ["", f"\\* {a} is nearly constant over the window ({why}): its NRMSE, correlation and DTW would "
                  "compare sensor noise, not motion, and are left out (report.json keeps them); its RMS and peaks stand."]
    if any(m["bands"] for m in r["sensors"].values()):
        lines += ["", "## Band energies (Hann PSD, dB re 1 (m/s²)²)", "",
                  "| sensor | band Hz | recorded dB | simulated dB | sim − rec dB |", "|---|---|---|---|---|"]
        for a, m in r["sensors"].items():
            for b in m["bands"]:
                lines.append(f"| {a} | {b['f_lo_hz']:g}–{b['f_hi_hz']:g} | {_fmt(b['recorded_db'], '.1f')} | "
                             f"{_fmt(b['simulated_db'], '.1f')} | {_fmt(b['difference_db'], '+.1f')} |")
    lines += ["", "## Crank-rate harmonics (Hann amplitude, m/s²)", ""]
    any_sensor = next(iter(r["sensors"].values()), None)
    if any_sensor:
        hz = any_sensor["harmonics_hz"]
        lines += ["| sensor | " + " | ".join(f"{h:.2f} Hz rec / sim" for h in hz) + " |",
                  "|---|" + "---|" * len(hz)]
        for a, m in r["sensors"].items():
            cells = [f"{_fmt(x)} / {_fmt(y)}" for x, y in zip(m["recorded_harmonic_amplitudes_mps2"],
                                                           m["simulated_harmonic_amplitudes_mps2"])]
            lines.append(f"| {a} | " + " | ".join(cells) + " |")
    lines += ["", "Definitions: NRMSE = RMS(sim − rec) / (max − min of rec); DTW % = RMS difference along the "
              "optimal warping path / (max − min of rec) (twin/signals.py); errors after removing the time lag.", ""]
    md = r.get("motor_drive")
    if md:
        lines += ["## Drives compared: crank PID on the encoder vs motor model on the recorded command", "",
                  f"Crank vs recorded encoder, max: PID {md['tracking']['pid_sim_vs_recorded_max_counts']:.1f} counts, "
                  f"motor {md['tracking']['sim_vs_recorded_max_counts']:.1f} counts (RMS "
                  f"{md['tracking']['sim_vs_recorded_rms_counts']:.1f}); motor run's crank speed ripple in the window "
                  f"{_fmt(md['crank_speed_ripple_pct'])} % (max − min over mean).", "",
                  "| sensor | NRMSE % PID / motor | corr PID / motor | DTW % PID / motor |", "|---|---|---|---|"]
        for a, m in md["sensors"].items():
            lines.append(f"| {a} | {_fmt(m['pid_nrmse_pct'])} / {_fmt(m['nrmse_pct'])} | "
                         f"{_fmt(m['pid_correlation'], '.4f')} / {_fmt(m['correlation'], '.4f')} | "
                         f"{_fmt(m['pid_dtw_distance_pct'])} / {_fmt(m['dtw_distance_pct'])} |")
        lines += [""]
    files = r.get("files", {})
    if files.get("plots"):
        shows = r.get("plots", {})
        lines += ["## Plots", ""]
        for p in files["plots"]:
            lines += ([f"{p}: {shows[p]}", ""] if p in shows else []) + [f"![{p}]({p})", ""]
    return "\n".join(lines)


def _plots(out: Path, rec: dict[str, np.ndarray], sim: dict[str, np.ndarray], rate: float, j0: int,
           comparison: dict[str, Any], crank_rate_hz: float, opts: ReplayOptions, track: np.ndarray,
           pid: np.ndarray, i0: int, simrun: Run, phi: np.ndarray, cfg: BenchConfig,
           total_s: float) -> dict[str, str]:
    """The PNG plots; returns what part of the recording each one shows, by file name."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(rec)
    files: dict[str, str] = {}
    # time histories: about 1.2 crank turns from the window start
    n = len(next(iter(rec.values())))
    m = n if crank_rate_hz <= 0 else min(n, int(round(1.2 / crank_rate_hz * rate)))
    t = (j0 + np.arange(m)) / rate
    whole = f"0–{total_s:.2f} s"
    span = f"{t[0]:.2f}–{t[-1] + 1 / rate:.2f} s of the {whole} recording"
    aligned = f"{j0 / rate:.2f}–{(j0 + n) / rate:.2f} s"
    fig, axes = plt.subplots(len(names), 1, figsize=(11, 2.0 * len(names)), sharex=True, squeeze=False)
    for ax, a in zip(axes[:, 0], names):
        ax.plot(t, rec[a][:m], lw=0.7, label="recorded", color="k")
        ax.plot(t, sim[a][:m], lw=0.7, label=f"simulated ({cfg.name})", color="tab:red", alpha=0.8)
        ax.set_ylabel(f"{a} [m/s²]")
        ax.grid(alpha=0.3)
        if comparison.get(a, {}).get("near_constant"):
            ax.text(0.01, 0.95, "nearly constant: not compared (report.md)", transform=ax.transAxes,
                    fontsize=8, va="top", bbox={"facecolor": "white", "alpha": 0.8, "lw": 0})
    axes[0, 0].legend(loc="upper right", fontsize=8)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(f"Calibrated accelerations, recorded vs simulated (clearance B {cfg.joints.clearance_b_mm:g} mm, "
                 f"C {cfg.joints.clearance_c_mm:g} mm): {span}")
    fig.tight_layout()
    fig.savefig(out / "accelerations.png", dpi=110)
    plt.close(fig)
    files["accelerations.png"] = (f"{span}" + (f" (about 1.2 crank turns from the start of the compared part "
                                               f"{aligned})" if m < n else " (the whole compared part)"))

    # spectra: low frequency with harmonics, and up to 5 kHz with the bands
    fig, axes = plt.subplots(len(names), 2, figsize=(13, 2.0 * len(names)), squeeze=False)
    harm = crank_rate_hz * np.arange(1, opts.harmonics + 1)
    for row, a in enumerate(names):
        f, ar = hann_spectrum(rec[a], rate, remove_mean=True)
        _, as_ = hann_spectrum(sim[a], rate, remove_mean=True)
        for col, (fmax, log) in enumerate(((max(harm[-1] * 1.3, 10.0), False), (5000.0, True))):
            ax = axes[row, col]
            sel = f <= fmax
            ax.plot(f[sel], ar[sel], lw=0.7, color="k", label="recorded")
            ax.plot(f[sel], as_[sel], lw=0.7, color="tab:red", alpha=0.8, label="simulated")
            if log:
                ax.set_yscale("log")
                for lo, hi in opts.bands_hz:
                    ax.axvspan(lo, hi, color="tab:orange", alpha=0.15)
            else:
                for h in harm:
                    ax.axvline(h, color="tab:blue", ls="--", lw=0.6)
            ax.set_ylabel(f"{a} [m/s²]")
            ax.grid(alpha=0.3)
    axes[0, 0].set_title(f"Hann FFT of {aligned}, crank rate and harmonics (dashed)")
    axes[0, 1].set_title(f"Hann FFT of {aligned} to 5 kHz, bands shaded")
    axes[0, 0].legend(fontsize=8)
    axes[-1, 0].set_xlabel("frequency [Hz]")
    axes[-1, 1].set_xlabel("frequency [Hz]")
    fig.tight_layout()
    fig.savefig(out / "spectra.png", dpi=110)
    plt.close(fig)
    files["spectra.png"] = f"spectra of {aligned} of the {whole} recording (the compared part of the analysis window)"

    # crank tracking
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(11, 5), sharex=True)
    ts = simrun.time
    a1.plot(ts, simrun["omega_ref"], lw=0.7, color="k", label="reference from the recorded counts (filtered)")
    a1.plot(ts, simrun["crank_speed"], lw=0.7, color="tab:red", alpha=0.8, ls="--", label="simulated")
    a1.set_ylabel("crank rate [rad/s]")
    a1.set_title(f"crank rate, the whole run ({whole})", fontsize=9)
    a1.legend(fontsize=8)
    a1.grid(alpha=0.3)
    tw = (i0 + np.arange(len(track))) / rate
    a2.plot(tw, track, lw=0.7, color="k", label="simulated − recorded")
    a2.plot(tw, pid, lw=0.7, color="tab:red", alpha=0.8, label="simulated − reference (PID error)")
    a2.axhline(1, color="gray", ls=":")
    a2.axhline(-1, color="gray", ls=":")
    a2.set_ylabel("angle error [counts]")
    a2.set_title(f"angle errors over the analysis window ({tw[0]:.2f}–{tw[-1] + 1 / rate:.2f} s)", fontsize=9)
    a2.set_xlabel("time [s]")
    a2.legend(fontsize=8)
    a2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "tracking.png", dpi=110)
    plt.close(fig)
    files["tracking.png"] = (f"crank rate over the whole run ({whole}); angle errors over the analysis window "
                             f"({tw[0]:.2f}–{tw[-1] + 1 / rate:.2f} s)")
    return files
