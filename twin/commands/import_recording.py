"""``twin import``: convert a DAQ export (CSV/NPZ) into a validated bench recording (MCAP)."""

from __future__ import annotations

import argparse

from twin.cli import MODEL_OPTIONS, SELECT_OPTIONS, add_config_args, config_from_args
from twin.errors import TwinError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "import", help="convert a DAQ export (CSV/NPZ) into a bench recording",
        description="Read a DAQ export (.csv with a header row, or .npz), map its columns to the bench channels "
                    "(volt_AC1..volt_AC6 [V], encoder_counts [count], motor_command [V]), validate it (time base, "
                    "sample rate, units, NaN, encoder glitches) and write a bench recording (.mcap, "
                    "recordings/FORMAT.md) with the bench configuration and calibration data. Use --test N (or "
                    "--config) to say which bench configuration the test ran with.")
    p.add_argument("export", metavar="EXPORT", help="DAQ export: .csv (header row; units as 'name [V]') or .npz")
    # the options that describe the bench the recording was made on (not how to simulate it)
    add_config_args(p, SELECT_OPTIONS + MODEL_OPTIONS + ("speed", "protocol"),
                    refused_set=("simulation.", "sensors.channels", "sensors.output_rate_hz", "drive.trace_file"))
    p.add_argument("--out", metavar="REC.mcap", required=True, help="recording to write")
    p.add_argument("--map", action="append", default=[], metavar="TARGET=SOURCE[:UNIT]",
                   help="column mapping, repeatable or comma-separated, e.g. volt_AC1=ai0:V,encoder_counts=ctr0:count "
                        "(TARGET t = the time column)")
    p.add_argument("--time-column", default="t", metavar="NAME", help="time column [s] (default t)")
    p.add_argument("--rate", type=float, metavar="HZ", help="sample rate; required without a time column")
    p.add_argument("--calibration", metavar="STATIC", help="static recording in the calibration pose (.csv/.npz "
                   "with the same columns, or .mcap): zero-g offsets by S003 Eq. 1-2")
    p.add_argument("--zero-g", metavar="AC1=V,...", help="known zero-g offsets of all six sensors [V] instead")
    p.add_argument("--notes", default="", metavar="TEXT", help="free-text notes stored in the recording")
    p.add_argument("--encoder-modulus", type=int, metavar="N", help="the counter wraps at N (e.g. 4294967296)")
    p.add_argument("--repair-nan", action="store_true", help="interpolate NaN gaps up to 16 samples (reported)")
    p.add_argument("--no-encoder-repair", action="store_true", help="fail on encoder glitches instead of repairing")
    # the library's names for what these options set (twin.recording.import_table's arguments)
    p.set_defaults(func=run, _field_flags={"mapping": "--map", "rate_hz": "--rate", "zero_g_v": "--zero-g",
                                           "time_column": "--time-column", "nan='interpolate'": "--repair-nan"})


def _zero_g(text: str) -> dict[str, float]:
    from twin.config import ACCELEROMETERS

    out: dict[str, float] = {}
    for part in text.split(","):
        if "=" not in part:
            raise TwinError(f"--zero-g: expects AC1=V,AC2=V,... for {', '.join(ACCELEROMETERS)}, got {part!r}")
        k, v = (s.strip() for s in part.split("=", 1))
        if k in out:
            raise TwinError(f"--zero-g: {k} is given twice")
        try:
            out[k] = float(v)
        except ValueError:
            raise TwinError(f"--zero-g: {k} must be a voltage, got {v!r}") from None
    return out


def run(args: argparse.Namespace) -> int:
    from twin.recording import (RecordingInfo, calibration_from_offsets, import_table,
                                parse_mapping, static_calibration_from, write_recording)

    from twin.commands.inputs import recording
    from twin.util import check_output_file, file_sha256

    cfg = config_from_args(args)
    if args.calibration:
        args.calibration = str(recording(args.calibration))
    inputs = [args.export] + ([args.calibration] if args.calibration else [])
    out = check_output_file(args.out, "--out", ".mcap", inputs=inputs)
    if args.calibration and args.zero_g is not None:
        raise TwinError("--calibration and --zero-g are alternatives; give one")
    mapping = parse_mapping(args.map)
    nan = "interpolate" if args.repair_nan else "error"
    run_, repairs = import_table(args.export, cfg, mapping, rate_hz=args.rate, time_column=args.time_column, nan=nan,
                                 encoder_modulus=args.encoder_modulus, encoder_repair=not args.no_encoder_repair)
    cal = None
    if args.calibration:
        static_map = {k: v for k, v in mapping.items() if k.startswith("volt_") or k == "t"}
        cal = static_calibration_from(args.calibration, cfg, static_map, args.rate, nan=nan)
    elif args.zero_g is not None:
        cal = calibration_from_offsets(cfg, _zero_g(args.zero_g))
    info = RecordingInfo(run_.rate_hz, source_file=str(args.export), source_sha256=file_sha256(args.export),
                         notes=args.notes, calibration=cal, synthetic=False, created_by="twin import",
                         repairs=repairs)
    write_recording(out, run_, info)
    print(f"{args.export}: {run_.n} samples at {run_.rate_hz:g} Hz ({run_.n / run_.rate_hz:.3f} s), "
          f"channels {', '.join(run_.channels)}; configuration {cfg.name}")
    for r in repairs:
        print(f"  repair: {r}")
    if cal is None:
        print("  no calibration data: 'twin replay' will ask for it (use --calibration or --zero-g)")
    else:
        print("  zero-g offsets [V]: " + ", ".join(f"{k} {v:.5f}" for k, v in cal.zero_g_v.items()))
    print(f"  wrote {out}")
    return 0
