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
    p.add_argument("--summary-json", metavar="FILE", help="write the run summary as JSON")
    p.add_argument("--rerun", metavar="OUT.rrd", help="also stream the run into a rerun recording (as twin view)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _check_out(path: Path, suffix: str, flag: str) -> None:
    if path.suffix != suffix:
        raise TwinError(f"{flag}: must end in {suffix}, got {path.name}")
    if not path.parent.exists():
        raise TwinError(f"{flag}: directory {path.parent} does not exist")


def run(args: argparse.Namespace) -> int:
    from twin.mcapfile import RunWriter
    from twin.run import Run
    from twin.simulate import output_stride, run_chunks
    from twin.summary import summarize
    from twin.util import atomic_write_json

    cfg = config_from_args(args)
    output_stride(cfg)  # validate timestep vs output rate before any work
    out = None if args.no_out else Path(args.out or f"{cfg.name}.mcap")
    if out is not None:
        _check_out(out, ".mcap", "--out")
    if args.summary_json:
        _check_out(Path(args.summary_json), ".json", "--summary-json")
    if args.rerun:
        _check_out(Path(args.rerun), ".rrd", "--rerun")

    engine, chunks = run_chunks(cfg, progress=not args.no_progress and sys.stderr.isatty())
    writer = RunWriter(out, cfg) if out is not None else None
    rerun = _rerun_writer(Path(args.rerun), cfg) if args.rerun else None
    kept = []
    try:
        for chunk in chunks:
            if writer is not None:
                writer.write(chunk)
            if rerun is not None:
                rerun.write(chunk)
            kept.append(chunk)
        run_ = Run.concat(kept)
        run_.meta = dict(engine.meta)
        summary = summarize(run_)
        if writer is not None:
            writer.close(run_.meta, summary)
        if rerun is not None:
            rerun.close(run_.meta, summary)
    except BaseException:
        if writer is not None:
            writer.abort()
        if rerun is not None:
            rerun.abort()
        raise
    if args.summary_json:
        atomic_write_json(args.summary_json, summary)
    _print_summary(summary, out)
    if rerun is not None:
        print(f"  wrote {rerun.path}")
    return 0


def _rerun_writer(path: Path, cfg):
    """Streaming rerun sink of ``twin view``'s layout (twin/viz), id from the configuration."""
    from twin.viz import RerunWriter, simulation_recording_id

    return RerunWriter(path, cfg, recording_id=simulation_recording_id(cfg.digest()), name=cfg.name,
                       source=f"twin simulate ({cfg.simulation.engine})")


def _print_summary(s: dict, out: Path | None) -> None:
    print(f"{s['name']}: {s['engine']} {s['duration_s']:.3f} s simulated in {s['wall_s']:.2f} s "
          f"(real-time factor {s['real_time_factor']:.2f}, {s['steps']} steps of {s['timestep_s']:g} s)")
    for j in ("B", "C"):
        js = s[j]
        if "impacts" in js:
            print(f"  joint {j}: {js['clearance_mm']:g} mm, max eccentricity {js['max_eccentricity_m']*1e6:.1f} um, "
                  f"max penetration {js['max_penetration_m']*1e6:.2f} um, {js['impacts']} impacts, "
                  f"max force {js['max_contact_force_N']:.0f} N")
        else:
            print(f"  joint {j}: ideal (ball bearing)")
    acc = [f"{a} {s[a]['rms_mps2']:.1f}/{s[a]['peak_mps2']:.0f}" for a in ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6") if a in s]
    if acc:
        print("  accel rms/peak [m/s^2]: " + ", ".join(acc))
    if out is not None:
        print(f"  wrote {out}")
