"""``twin replay``: drive the twin with a bench recording's encoder trace and compare accelerations."""

from __future__ import annotations

import argparse
import copy
import os
import sys
import tempfile
from pathlib import Path

from twin.cli import MODEL_OPTIONS, SELECT_OPTIONS, add_config_args, config_from_args
from twin.commands.inputs import RECORDING_HELP, recording
from twin.config import BenchConfig
from twin.errors import TwinError
from twin.replay_result import ReplayResult


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "replay", help="replay a bench recording through the twin and compare accelerations",
        description="Unwrap and filter the recording's encoder counts into a crank reference, simulate with the "
                    "recording's bench configuration (configuration options override it, e.g. --clearance-c 0 "
                    "for the ideal model on a clearance recording, as in S003 Fig. 16), put the virtual sensors "
                    "through the bench's sensor chain and calibration, and compare with the recorded "
                    "accelerations. Writes replay.mcap, report.json, report.md and PNG plots to --out.")
    p.add_argument("recording", metavar="RECORDING.mcap", help=RECORDING_HELP)
    # the model to replay with; the drive, duration, channels and rate come from the recording
    add_config_args(p, SELECT_OPTIONS + MODEL_OPTIONS + ("engine", "timestep"),
                    refused_set=("drive.program", "drive.trace_file", "drive.crank_rpm", "simulation.duration_s",
                                 "sensors.channels", "sensors.output_rate_hz", "instrumentation.zero_g_v",
                                 "instrumentation.daq_rate_hz", *REPLACED_BY_TRACE))
    p.add_argument("--out", metavar="DIR", help="output folder (default: replay_<recording name>)")
    p.add_argument("--window", nargs=2, type=float, metavar=("START", "STOP"),
                   help="analysis window in recording time [s] (default: second half, at most 1 s)")
    p.add_argument("--max-lag", type=float, default=0.005, metavar="S", help="largest alignment lag searched [s]")
    p.add_argument("--dtw-window", type=float, default=0.002, metavar="S", help="DTW Sakoe-Chiba half-width [s]")
    p.add_argument("--dtw-max", type=float, default=0.5, metavar="S", help="DTW on at most this much of the window [s]")
    p.add_argument("--repair-nan", action="store_true", help="interpolate short NaN gaps (reported) instead of failing")
    p.add_argument("--drive", choices=("pid", "motor"), default="pid",
                   help="pid: the crank PID on the encoder trace (default); motor: also drive the motor model "
                        "(speed loop and V-belt, [drivetrain] parameters) by the recorded motor command and compare "
                        "both drives in the report")
    p.add_argument("--no-plots", action="store_true", help="no PNG plots")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


#: [drive] fields of the program the recording's trace replaces (its speeds, ramps, steps, protocol, start angle and
#: imposed ripple): a replay follows what the crank did, so ``--set`` of them is refused (they would be ignored)
REPLACED_BY_TRACE = tuple(f"drive.{n}" for n in ("motor_rpm", "ramp_s", "ramp_shape", "protocol_rpm", "protocol_hold_s",
                                                  "protocol_stop_s", "steps_s", "steps_rpm", "initial_encoder_angle_rad",
                                                  "ripple_pct", "ripple_phase_rad"))


def set_drive_mode(args: argparse.Namespace) -> str | None:
    """The drive mode ``--set drive.mode=...`` (or ``--set drive={mode=...}``) asks for, None where none; one-line
    refusal of a mode that does not follow a trace (:data:`twin.bench_replay.TRACE_MODES`): a replay drives the
    crank by the recording's encoder trace."""
    from twin.bench_replay import TRACE_MODES
    from twin.cli import _flatten, _parse_value

    mode = None
    for item in getattr(args, "set", None) or []:
        key, _, text = (x.strip() for x in item.partition("="))
        for k, v in _flatten(key, _parse_value(key, text)):
            if k == "drive.mode":
                mode = v
    if mode is not None and mode not in TRACE_MODES:
        raise TwinError(f"--set drive.mode: a replay drives the crank by the recording's encoder trace, with "
                        f"{' or '.join(TRACE_MODES)} (the crank PID, or the angle imposed); got {mode!r} (--drive motor "
                        "adds the motor model driven by the recorded motor command)")
    return mode


def replay_overrides(args: argparse.Namespace, rec_cfg: BenchConfig) -> BenchConfig:
    """The recording's configuration with the command line's configuration options applied
    (``--config``/``--test``/``--preset`` replace it as a whole)."""
    from twin.bench_replay import TRACE_MODES, trace_drive

    if set_drive_mode(args) is not None and rec_cfg.drive.mode not in TRACE_MODES:
        # a motor or torque recording replayed with the mode asked for: the drive the replay would use anyway
        # (twin.bench_replay.trace_drive), so that its drive-train fields and channels do not refuse the mode
        rec_cfg = rec_cfg.replace(**trace_drive(rec_cfg), **{"sensors.channels": [
            g for g in rec_cfg.sensors.channels if g not in ("motor", "drive_energy")]})
    if args.config or args.test is not None or getattr(args, "preset", None) is not None:
        return config_from_args(args)
    fd, tmp = tempfile.mkstemp(suffix=".toml", prefix="twin_replay_")
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(rec_cfg.to_toml())
        ns = copy.copy(args)
        ns.config = tmp
        return config_from_args(ns)
    finally:
        os.unlink(tmp)


def run(args: argparse.Namespace) -> int:
    from twin.bench_replay import ReplayOptions, replay

    rec = recording(args.recording)
    if rec.suffix.lower() != ".mcap":
        raise TwinError(f"{rec}: a recording is an .mcap file; convert DAQ exports with 'twin import'")
    if not rec.is_file():
        raise TwinError(f"{rec}: " + ("not a regular file (a folder, pipe or device)" if rec.exists() else "no such file"))
    out = Path(args.out if args.out else f"replay_{rec.stem}")  # replay() checks it before any work
    opts = ReplayOptions(window_s=tuple(args.window) if args.window else None, max_lag_s=args.max_lag,
                         dtw_window_s=args.dtw_window, dtw_max_s=args.dtw_max,
                         nan="interpolate" if args.repair_nan else "error", plots=not args.no_plots,
                         progress=not args.no_progress and sys.stderr.isatty(), drive=args.drive)
    r = replay(rec, out, lambda c: replay_overrides(args, c), opts)
    _print(r, out)
    return 0


def _print(r: ReplayResult, out: Path) -> None:
    from twin.bench_replay import _lag_text

    c, tr = r.configuration, r.tracking
    print(f"{r.recording}: {r.duration_s:.3f} s at {r.sample_rate_hz:g} Hz; model {c.name} "
          f"({c.engine}, B {c.clearance_b_mm:g} mm, C {c.clearance_c_mm:g} mm"
          f"{'' if c.same_as_recording else ', differs from the recording'})")
    for rep in r.repairs:
        print(f"  repair: {rep}")
    print(f"  window {r.window_s[0]:.3f}-{r.window_s[1]:.3f} s, crank {r.crank_rate_hz:.3f} Hz, "
          f"lag {_lag_text(r.to_dict())}; tracking sim-recorded max {tr.sim_vs_recorded_max_counts:.2f} "
          f"counts (RMS {tr.sim_vs_recorded_rms_counts:.2f})")
    print("  sensor  NRMSE%   corr    DTW%  " + "  ".join(f"{lo / 1e3:g}-{hi / 1e3:g}kHz rec/sim dB"
                                                      for lo, hi in r.bands_hz))
    for a, m in r.sensors.items():
        bands = "  ".join(f"{b.recorded_db:8.1f}/{b.simulated_db:<8.1f}" for b in m.bands)
        if m.near_constant:  # NRMSE, correlation and DTW of noise against noise: not shown
            print(f"  {a:6s} nearly constant ({m.near_constant_note}): not compared")
            continue
        print(f"  {a:6s} {m.nrmse_pct:7.2f} {m.correlation:7.4f} {m.dtw_distance_pct:7.3f}  {bands}")
    md = r.motor_drive
    if md:
        print(f"  motor drive (recorded command): tracking max {md.tracking['sim_vs_recorded_max_counts']:.1f} counts "
              f"(PID {md.tracking['pid_sim_vs_recorded_max_counts']:.1f}); NRMSE% motor/PID "
              + ", ".join(f"{a} {m.nrmse_pct:.1f}/{m.pid_nrmse_pct:.1f}" for a, m in md.sensors.items()))
    print(f"  wrote {out}/: {', '.join([r.files['mcap'], *r.files.get('report', []), *r.files.get('plots', [])])}")
