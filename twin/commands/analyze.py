"""``twin analyze``: analyses over several runs or recordings.

``twin analyze repeatability RUN...``: pairwise normalized DTW distances and mean time shifts
between runs of the same test (S003 §5); the analysis is :mod:`twin.studies.repeatability`,
this module parses the arguments and prints its table.
"""

from __future__ import annotations

import argparse



def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("analyze", help="analyses over several runs or recordings (repeatability)",
                       description="Analyses over several runs or recordings.")
    asub = p.add_subparsers(dest="analysis", metavar="ANALYSIS", parser_class=type(p))
    asub.required = True
    r = asub.add_parser(
        "repeatability", help="pairwise normalized DTW distances between runs of one test (S003 §5)",
        description="Pairwise normalized DTW distance [%] (RMS difference along the warping path / acceleration "
                    "range of the first run) and mean time shift [s] between runs or recordings of the same test. "
                    "Recordings are calibrated with their stored calibration (S003 Eq. 1-4); simulated runs use "
                    "the calibrated channel meas_ACi if present, else the simulated ACi.")
    r.add_argument("runs", nargs="+", metavar="RUN",
                   help="run files or bench recordings (.mcap; sample:NAME for a sample that ships with twin, e.g. "
                        "sample:test6_repeat1), at least 2")
    r.add_argument("--channel", default="AC4", help="accelerometer (AC1..AC6) or an exact channel name (default AC4)")
    r.add_argument("--start", type=float, metavar="S", help="window start, run time [s] (default: start)")
    r.add_argument("--stop", type=float, metavar="S", help="window stop, run time [s] (default: end)")
    r.add_argument("--dtw-window", type=float, default=0.05, metavar="S",
                   help="Sakoe-Chiba half-width [s] (default 0.05; the paper's shifts are ~0.015 s)")
    r.add_argument("--align-angle", type=float, metavar="DEG",
                   help="start each run's window at its first pass through this encoder angle after --start "
                        "(runs whose start position differs, S003 §5); the window keeps the length stop - start")
    r.add_argument("--decimate", type=int, default=1, metavar="K",
                   help="use every K-th sample after a zero-phase anti-alias filter (faster DTW)")
    r.add_argument("--json", metavar="FILE", help="write the table as JSON")
    r.add_argument("--no-progress", action="store_true", help="no progress bar")
    r.set_defaults(func=run_repeatability, _field_flags={"runs": "RUN..."})  # the positional arguments


def run_repeatability(args: argparse.Namespace) -> int:
    import sys

    from twin.commands.inputs import recording
    from twin.studies.repeatability import repeatability
    from twin.util import atomic_write_json

    from twin.util import check_output_file

    runs = [recording(r) for r in args.runs]  # repeatability() checks the arguments before it reads them
    if args.json is not None:  # checked before the work, not after
        check_output_file(args.json, "--json", ".json", inputs=runs)
    rep = repeatability(runs, args.channel, args.start, args.stop, args.dtw_window, args.align_angle,
                        args.decimate, progress=not args.no_progress and sys.stderr.isatty())
    result, lengths = rep.result, rep.window_samples
    if max(lengths) - min(lengths) > 1:
        print(f"  note: windows hold {min(lengths)}..{max(lengths)} samples (a run ends inside the window); "
              f"all are cut to {min(lengths)} samples")
    rows, worst, norm = result["pairs"], result["worst"], result["normalizer"]
    print(f"repeatability of {args.channel} over {len(result['runs'])} runs ({rep.samples} samples at "
          f"{result['rate_hz']:g} Hz, range of run 1 = {norm:.3g}):")
    for n, (p, u) in enumerate(zip(result["runs"], result["channels_used"]), 1):
        print(f"  run {n}: {p} [{u}] from t = {result['window_starts_s'][n - 1]:.5f} s")
    print("  pair   DTW %    mean shift [s]")
    for r in rows:
        print(f"  {r['run_a']}-{r['run_b']}  {r['distance_pct']:7.4f}  {r['mean_shift_s']:.5f}")
    print(f"  worst: runs {worst['run_a']} and {worst['run_b']}, {worst['distance_pct']:.4f} %, "
          f"mean shift {worst['mean_shift_s']:.5f} s (S003: 0.296 % ideal, 0.6953 % with 0.1 mm at C)")
    if args.json:
        atomic_write_json(args.json, result)
    return 0
