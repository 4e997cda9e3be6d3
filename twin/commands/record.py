"""``twin record``: simulate a configuration and write a bench recording through the sensor chain."""

from __future__ import annotations

import argparse
import sys

from twin.cli import ALL_CONFIG_OPTIONS, add_config_args, config_from_args


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("record", help="simulate the bench and write a bench recording (DAQ volts, encoder counts)",
                       description="Simulate a bench configuration (the options of 'twin simulate') and write what "
                                   "the bench's DAQ would have recorded: the accelerometers and the encoder through "
                                   "the sensor chain of [instrumentation] (response, noise, saturation, 18-bit DAQ, "
                                   "encoder counts), the motor command, and a static calibration from a simulated "
                                   "static recording. Every command that reads a bench recording reads it.")
    # a recording holds the DAQ's channels whatever groups are computed (twin.bench_record.recording_config adds
    # those the sensor chain reads): --channels would be accepted and ignored
    add_config_args(p, tuple(o for o in ALL_CONFIG_OPTIONS if o != "channels"), refused_set=("sensors.channels",))
    p.add_argument("--out", required=True, metavar="REC.mcap", help="bench recording to write")
    p.add_argument("--notes", default="", metavar="TEXT", help="free text stored in the recording (test id, ...)")
    p.add_argument("--static", type=float, default=1.0, metavar="S", dest="static_s",
                   help="length of the simulated static calibration recording [s] (default 1, 0.1 to 60)")
    p.add_argument("--json", metavar="FILE", help="write what was recorded as JSON")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from twin.errors import ConfigError, TwinError
    from twin.bench_record import record
    from twin.util import atomic_write_json, check_output_file

    cfg = config_from_args(args)
    js = check_output_file(args.json, "--json", ".json") if args.json else None
    out = check_output_file(args.out, "--out", ".mcap")
    if js is not None and js.resolve() == out.resolve():
        raise TwinError("--out and --json must name different files")
    try:
        res = record(cfg, out, notes=args.notes, static_s=args.static_s,
                     progress=not args.no_progress and sys.stderr.isatty())
    except ConfigError as err:
        if err.field == "static_s":
            raise ConfigError("--static", err.message) from None
        raise
    if js is not None:
        atomic_write_json(js, res.to_dict())
    if abs(res.turns) < 1:  # (NaN: no crank angle, nothing said) x vertical with a weak drive stalls or rocks
        print(f"twin: warning: the crank turned {res.turns:.2f} turns in {res.duration_s:g} s, less than one whole "
              "turn (stalled, rocking, or a run too short): commands that analyse whole turns (twin identify clearance) refuse "
              "this recording", file=sys.stderr)
    print(f"  {res.engine} engine, {res.duration_s:g} s at {res.rate_hz:g} Hz: {', '.join(res.channels)}")
    print(f"  wrote {res.path} ({res.bytes / 1e6:.2f} MB) in {res.seconds:.1f} s")
    return 0
