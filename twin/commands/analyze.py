"""``twin analyze``: analyses over several runs or recordings.

``twin analyze repeatability RUN...``: pairwise normalized DTW distances and mean time shifts
between runs of the same test (S003 §5: AC4, five runs, around t = 30 s; worst pair 0.296 %
without clearance, 0.6953 % with 0.1 mm at C). The distance of every pair is normalized by the
acceleration range (max − min) of the first run given, "the first maneuver" of the paper.
"""

from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np

from twin.errors import RecordingError, TwinError


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
    r.add_argument("runs", nargs="+", metavar="RUN", help="run files or bench recordings (.mcap), at least 2")
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
    r.set_defaults(func=run_repeatability)


def load_encoder_angle(path: str | Path) -> np.ndarray:
    """Encoder angle [rad] of a run (``encoder_angle``) or recording (count centres of ``encoder_counts``)."""
    from twin.instrument import counts_to_angle
    from twin.mcapfile import read_metadata, read_run
    from twin.recording import RECORDING_RECORD, read_recording

    p = Path(path)
    if RECORDING_RECORD in read_metadata(p):
        rec, _, _ = read_recording(p)
        inst = rec.config.instrumentation
        return counts_to_angle(rec["encoder_counts"], inst.encoder_counts_per_rev, centre=inst.encoder_quantization)
    run = read_run(p)
    if "encoder_angle" not in run:
        raise RecordingError(f"{p}: no encoder_angle channel to align on")
    return run["encoder_angle"].astype(np.float64)


def first_pass(phi: np.ndarray, i_from: int, angle_rad: float) -> int:
    """First sample >= i_from at which the encoder angle passes ``angle_rad`` (mod 2π) in either direction."""
    k = np.floor((phi[i_from:] - angle_rad) / (2 * np.pi))
    hits = np.flatnonzero(np.diff(k) != 0)
    if hits.size == 0:
        raise TwinError(f"--align-angle: the crank never passes {np.degrees(angle_rad):g} deg after the window start")
    return i_from + int(hits[0]) + 1


def load_signal(path: str | Path, channel: str) -> tuple[np.ndarray, float, float, str]:
    """(samples, t0 [s], rate [Hz], channel used) of one accelerometer signal in a run or recording."""
    from twin.config import ACCELEROMETERS
    from twin.instrument import measured_accel
    from twin.mcapfile import read_metadata, read_run
    from twin.recording import RECORDING_RECORD, read_recording

    p = Path(path)
    if RECORDING_RECORD in read_metadata(p):
        rec, info, _ = read_recording(p)
        if channel in ACCELEROMETERS:
            if info.calibration is None:
                raise RecordingError(f"{p}: recording has no calibration data; re-import it with --calibration")
            meas = measured_accel(rec.select([f"volt_{channel}"]), info.calibration)
            return meas[f"meas_{channel}"].astype(np.float64), rec.t0, rec.rate_hz, f"meas_{channel}"
        return rec[channel].astype(np.float64), rec.t0, rec.rate_hz, channel
    run = read_run(p)
    for name in ((f"meas_{channel}", channel) if channel in ACCELEROMETERS else (channel,)):
        if name in run:
            return run[name].astype(np.float64), run.t0, run.rate_hz, name
    raise RecordingError(f"{p}: no channel {channel!r} (channels: {', '.join(run.channels)})")


def run_repeatability(args: argparse.Namespace) -> int:
    from twin.signals import dtw_compare
    from twin.util import atomic_write_json

    if len(args.runs) < 2:
        raise TwinError("repeatability: give at least 2 runs")
    if args.decimate < 1:
        raise TwinError(f"--decimate: must be an integer >= 1, got {args.decimate}")
    if args.json and not Path(args.json).parent.exists():
        raise TwinError(f"--json: directory {Path(args.json).parent} does not exist")
    sigs = []
    starts: list[float] = []
    rate = None
    for path in args.runs:
        x, t0, r, used = load_signal(path, args.channel)
        if rate is not None and abs(r - rate) > 1e-9 * rate:
            raise RecordingError(f"{path}: sampled at {r:g} Hz, the first run at {rate:g} Hz")
        rate = r
        t = t0 + np.arange(x.size) / r
        lo = args.start if args.start is not None else t[0]
        hi = args.stop if args.stop is not None else t[-1] + 1 / r
        if args.align_angle is not None:
            i_from = int(np.searchsorted(t, lo))
            k = first_pass(load_encoder_angle(path), i_from, np.radians(args.align_angle))
            lo, hi = t[k], t[k] + (hi - lo)
        sel = (t >= lo) & (t < hi)
        if sel.sum() < 16:
            raise TwinError(f"{path}: the window {lo:g}..{hi:g} s holds {int(sel.sum())} samples "
                            f"(run covers {t[0]:g}..{t[-1]:g} s)")
        sigs.append((str(path), x[sel], used))
        starts.append(float(lo))
    lengths = [x.size for _, x, _ in sigs]
    if max(lengths) - min(lengths) > 1:
        print(f"  note: windows hold {min(lengths)}..{max(lengths)} samples (a run ends inside the window); "
              f"all are cut to {min(lengths)} samples")
    n_common = min(lengths)
    sigs = [(p, x[:n_common], u) for p, x, u in sigs]
    k = args.decimate
    if k > 1:
        from scipy.signal import decimate

        sigs = [(p, decimate(x, k, ftype="fir", zero_phase=True), u) for p, x, u in sigs]
    rate_used = rate / k
    first = sigs[0][1]
    norm = float(first.max() - first.min())
    pairs = list(itertools.combinations(range(len(sigs)), 2))
    rows = []
    bar = None
    if not args.no_progress and sys.stderr.isatty():
        from tqdm import tqdm

        bar = tqdm(total=len(pairs), desc="DTW pairs", leave=False)
    for i, j in pairs:
        d = dtw_compare(sigs[i][1], sigs[j][1], rate_used, args.dtw_window, norm_range=norm)
        rows.append({"run_a": i + 1, "run_b": j + 1, "distance_pct": d.distance_pct,
                     "mean_shift_s": d.mean_shift_s, "signed_shift_s": d.signed_shift_s})
        if bar is not None:
            bar.update(1)
    if bar is not None:
        bar.close()
    worst = max(rows, key=lambda r: r["distance_pct"])
    result = {"channel": args.channel, "runs": [p for p, _, _ in sigs], "channels_used": [u for _, _, u in sigs],
              "window_s": [args.start, args.stop], "window_starts_s": starts, "align_angle_deg": args.align_angle, "rate_hz": rate_used, "dtw_window_s": args.dtw_window,
              "normalizer": norm, "normalizer_note": "max - min of the first run in the window",
              "pairs": rows, "worst": worst,
              "mean_distance_pct": float(np.mean([r["distance_pct"] for r in rows]))}
    print(f"repeatability of {args.channel} over {len(sigs)} runs ({sigs[0][1].size} samples at {rate_used:g} Hz, "
          f"range of run 1 = {norm:.3g}):")
    for n, (p, _, u) in enumerate(sigs, 1):
        print(f"  run {n}: {p} [{u}] from t = {starts[n - 1]:.5f} s")
    print("  pair   DTW %    mean shift [s]")
    for r in rows:
        print(f"  {r['run_a']}-{r['run_b']}  {r['distance_pct']:7.4f}  {r['mean_shift_s']:.5f}")
    print(f"  worst: runs {worst['run_a']} and {worst['run_b']}, {worst['distance_pct']:.4f} %, "
          f"mean shift {worst['mean_shift_s']:.5f} s (S003: 0.296 % ideal, 0.6953 % with 0.1 mm at C)")
    if args.json:
        atomic_write_json(args.json, result)
    return 0
