"""``twin simulate``: run a bench configuration on an engine, write MCAP and a summary."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from twin.cli import add_config_args, config_from_args
from twin.errors import TwinError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("simulate", help="simulate the bench and write a run file",
                       description="Simulate a bench configuration (default: Table 4 test 6, 2 s) and write "
                                   "the run as MCAP plus an optional JSON summary.")
    add_config_args(p)
    p.add_argument("--out", metavar="RUN.mcap", help="run file to write (default: <name>.mcap)")
    p.add_argument("--no-out", action="store_true", help="do not write a run file")
    p.add_argument("--preview-rate", type=float, metavar="HZ",
                   help="rate of the run file's /preview topic [Hz]: one message per sample, every channel a "
                        "field, for Foxglove's plot panel; block means of the full-rate samples (default 1000, "
                        "or the output rate if lower; 0 = no preview)")
    p.add_argument("--summary-json", metavar="FILE", help="write the run summary as JSON")
    p.add_argument("--rerun", metavar="OUT.rrd", help="also stream the run into a rerun recording (as twin view)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from twin.simulation import ThreadedSink, simulate
    from twin.summary import SummaryJsonWriter
    from twin.util import check_output_file

    cfg = config_from_args(args)
    if args.no_out and args.out:
        raise TwinError("--out and --no-out: give one")
    # every output location is checked before any work starts
    out = None if args.no_out else check_output_file(args.out or f"{cfg.name}.mcap", "--out", ".mcap")
    js = check_output_file(args.summary_json, "--summary-json", ".json") if args.summary_json else None
    rrd = check_output_file(args.rerun, "--rerun", ".rrd") if args.rerun else None
    paths = [p.resolve() for p in (out, js, rrd) if p is not None]
    if len(set(paths)) < len(paths):
        raise TwinError("--out, --summary-json and --rerun must name different files")
    preview = preview_rate(args.preview_rate, cfg.output_rate_hz)
    if out is not None:
        check_free_space(cfg, out, preview)
    sinks = []
    if out is not None:
        from twin.mcapfile import RunWriter  # the MCAP library only for a run that writes one

        # encoding and file writes overlap the stepping
        sinks.append(ThreadedSink(RunWriter(out, cfg, preview_rate_hz=preview)))
    if rrd is not None:
        sinks.append(_rerun_writer(rrd, cfg))
    if js is not None:
        sinks.append(SummaryJsonWriter(js))
    outcome = simulate(cfg, sinks, progress=not args.no_progress and sys.stderr.isatty())
    _print_summary(outcome.summary, out)
    if rrd is not None:
        print(f"  wrote {rrd}")
    return 0


def preview_rate(given: float | None, output_rate_hz: float) -> float:
    """The preview rate of ``--preview-rate`` [Hz]: the default (1 kHz, at most the output rate),
    0 (none), or a given rate between 0 and the output rate."""
    from twin.mcapfile import DEFAULT_PREVIEW_HZ, check_preview_rate

    if given is None:
        return min(DEFAULT_PREVIEW_HZ, output_rate_hz)
    return check_preview_rate(given, output_rate_hz)  # the writer's rule, checked before the run


def check_free_space(cfg, out: Path, preview_hz: float = 0.0) -> None:
    """Refuse a run whose file cannot fit on the disk. Estimate: the channels' raw size plus 1 % (the
    chunks are uncompressed, twin.mcapfile: 2 s of test 12 are 28.05 MB for 28.00 MB of samples,
    the rest the messages' framing, indexes and metadata), plus the preview: per message its
    samples and 72 bytes of header, framing and index (209 bytes in all for test 12's 23 channels,
    measured by analysis/bench_preview.py)."""
    import shutil

    from twin.channels import channel_specs

    specs = channel_specs(cfg)
    raw = cfg.n_samples * sum(4 if s.dtype == "float32" else 8 for s in specs)
    need = int(raw * 1.01)
    if preview_hz > 0:
        need += int(cfg.duration_s * preview_hz * (72 + sum(4 if s.dtype == "float32" else 8 for s in specs)))
    free = shutil.disk_usage(out.parent if str(out.parent) else ".").free
    if need > free:
        raise TwinError(f"--out: the run file needs about {need / 1e9:.1f} GB and {out.parent or '.'} has "
                        f"{free / 1e9:.1f} GB free; shorten --duration, ask for fewer --channels or use --no-out")


def _rerun_writer(path: Path, cfg):
    """Streaming rerun sink of ``twin view``'s layout (twin/viz), id from the configuration."""
    from twin.viz import RerunWriter, simulation_recording_id

    return RerunWriter(path, cfg, recording_id=simulation_recording_id(cfg.digest()), name=cfg.name,
                       source=f"twin simulate ({cfg.simulation.engine})")


def _print_summary(s: dict, out: Path | None) -> None:
    print(f"{s['name']}: {s['engine']} {s['duration_s']:.3f} s simulated in {s['wall_s']:.2f} s "
          f"(real-time factor {s['real_time_factor']:.2f}, {s['steps']} steps of {s['timestep_s']:g} s)")
    for j in ("A", "B", "C"):
        if j not in s:
            continue  # the ground pivot A has an entry only with a clearance
        js = s[j]
        if "impacts" in js:
            print(f"  joint {j}: {js['clearance_mm']:g} mm, max eccentricity {js['max_eccentricity_m']*1e6:.1f} um, "
                  f"max penetration {js['max_penetration_m']*1e6:.2f} um, {js['impacts']} impacts, "
                  f"max force {js['max_contact_force_N']:.0f} N")
        else:
            print(f"  joint {j}: ideal (ball bearing)")
    if "guide" in s:
        g = s["guide"]
        print(f"  guide: {g['clearance_mm']:g} mm play, max transverse {g['max_transverse_m']*1e6:.1f} um, "
              f"max tilt {g['max_tilt_rad']*1e3:.3f} mrad, max force front/rear {g['max_force_front_N']:.0f}/"
              f"{g['max_force_rear_N']:.0f} N, {g['impacts_front']}/{g['impacts_rear']} contact onsets")
    acc = [f"{a} {s[a]['rms_mps2']:.1f}/{s[a]['peak_mps2']:.0f}" for a in ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6") if a in s]
    if acc:
        print("  accel rms/peak [m/s^2]: " + ", ".join(acc))
    if "structure" in s:
        st = s["structure"]
        line = f"  structure: flexible, rod modes {st['first_bending_hz']:.0f} Hz (bending), {st['first_axial_hz']:.0f} Hz (axial)"
        if st.get("max_rod_deflection_m") is not None:
            line += (f"; max rod deflection {st['max_rod_deflection_m'] * 1e6:.2f} um, stretch "
                     f"{st['max_rod_stretch_m'] * 1e6:.2f} um")
        print(line)
    if "drive_train" in s:
        dt = s["drive_train"]
        over = " (above the continuous rating)" if dt["rms_exceeds_continuous"] else ""
        print(f"  motor torque rms/peak {dt['motor_rms_torque_Nm']:.3f}/{dt['motor_peak_torque_Nm']:.3f} N m{over}, "
              f"{100 * dt['fraction_at_peak_clamp']:.1f} % at the clamp; belt torque peak "
              f"{dt['max_belt_torque_Nm']:.2f} N m, slip peak {dt['max_belt_slip_mps'] * 1e3:.2f} mm/s")
    if out is not None:
        print(f"  wrote {out}")
