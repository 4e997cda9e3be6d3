"""Repeatability of runs of one test: pairwise normalized DTW distances and mean time shifts.

S003 §5: AC4, five runs, around t = 30 s; worst pair 0.296 % without clearance, 0.6953 % with
0.1 mm at C. The distance of every pair is normalized by the acceleration range (max − min) of
the first run given, "the first maneuver" of the paper. Runs are simulated runs or bench
recordings (.mcap); recordings are calibrated with their stored calibration (S003 Eq. 1-4),
simulated runs use the calibrated channel ``meas_ACi`` if present, else the simulated ``ACi``.
``twin analyze repeatability`` prints :func:`repeatability`'s table.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from twin.errors import RecordingError, TwinError


@dataclass(frozen=True)
class Repeatability:
    """Outcome of :func:`repeatability`.

    Attributes:
        result: the table (JSON-ready): channel, runs, channels used, window, pairs (DTW distance
            [%], mean and signed time shift [s]), worst pair, mean distance [%].
        window_samples: samples of each run's window before they are cut to the shortest.
        samples: samples per run that were compared (after the cut and the decimation).
    """

    result: dict
    window_samples: list[int]
    samples: int


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
        raise TwinError(f"the crank never passes {np.degrees(angle_rad):g} deg after the window start",
                        field="align_angle")
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
                raise RecordingError(f"{p}: recording has no calibration data; import it again with a static "
                                     "recording in the calibration pose or known zero-g offsets")
            meas = measured_accel(rec.select([f"volt_{channel}"]), info.calibration)
            return meas[f"meas_{channel}"].astype(np.float64), rec.t0, rec.rate_hz, f"meas_{channel}"
        return rec[channel].astype(np.float64), rec.t0, rec.rate_hz, channel
    run = read_run(p)
    for name in ((f"meas_{channel}", channel) if channel in ACCELEROMETERS else (channel,)):
        if name in run:
            return run[name].astype(np.float64), run.t0, run.rate_hz, name
    raise RecordingError(f"{p}: no channel {channel!r} (channels: {', '.join(run.channels)})")


def check_arguments(runs: Sequence[str | Path], start: float | None, stop: float | None, dtw_window: float,
                    align_angle: float | None, decimate: int) -> None:
    """The rules of :func:`repeatability`'s arguments (a one-line :class:`TwinError` naming the
    argument), checked before any run is read."""
    if len(runs) < 2:
        raise TwinError(f"give at least 2 runs, got {len(runs)}", field="runs")
    if isinstance(decimate, bool) or not isinstance(decimate, int) or decimate < 1:
        raise TwinError(f"must be an integer >= 1, got {decimate!r}", field="decimate")
    for name, v in (("start", start), ("stop", stop), ("align_angle", align_angle)):
        if v is not None and not math.isfinite(v):
            raise TwinError(f"must be a finite number, got {v!r}", field=name)
    if start is not None and start < 0:
        raise TwinError(f"must be a time >= 0 s, got {start!r}", field="start")
    if stop is not None and stop <= (start or 0.0):
        raise TwinError(f"must be a time > `start`, got {stop!r}", field="stop")
    if not (math.isfinite(dtw_window) and 0 <= dtw_window <= 10):
        raise TwinError(f"must lie in [0, 10] s, got {dtw_window!r}", field="dtw_window")
    if align_angle is not None and not -360 <= align_angle <= 360:
        raise TwinError(f"must lie in [-360, 360] degrees, got {align_angle!r}", field="align_angle")


def repeatability(runs: Sequence[str | Path], channel: str = "AC4", start: float | None = None,
                  stop: float | None = None, dtw_window: float = 0.05, align_angle: float | None = None,
                  decimate: int = 1, progress: bool = False) -> Repeatability:
    """Pairwise normalized DTW distance [%] (RMS difference along the warping path / acceleration
    range of the first run) and mean time shift [s] between ``runs`` of the same test.

    ``channel``: accelerometer (AC1..AC6) or an exact channel name; ``start``/``stop``: window in
    run time [s] (None: the run's start/end); ``dtw_window``: Sakoe-Chiba half-width [s];
    ``align_angle`` [deg]: start each run's window at its first pass through this encoder angle
    after ``start`` (the window keeps the length stop - start); ``decimate``: use every k-th
    sample after a zero-phase anti-alias filter. Windows of different length are cut to the
    shortest.
    """
    from twin.signals import dtw_compare

    check_arguments(runs, start, stop, dtw_window, align_angle, decimate)
    sigs = []
    starts: list[float] = []
    rate = None
    for path in runs:
        x, t0, r, used = load_signal(path, channel)
        if rate is not None and abs(r - rate) > 1e-9 * rate:
            raise RecordingError(f"{path}: sampled at {r:g} Hz, the first run at {rate:g} Hz")
        rate = r
        t = t0 + np.arange(x.size) / r
        lo = start if start is not None else t[0]
        hi = stop if stop is not None else t[-1] + 1 / r
        if align_angle is not None:
            i_from = int(np.searchsorted(t, lo))
            k = first_pass(load_encoder_angle(path), i_from, np.radians(align_angle))
            lo, hi = t[k], t[k] + (hi - lo)
        sel = (t >= lo) & (t < hi)
        if sel.sum() < 16:
            raise TwinError(f"{path}: the window {lo:g}..{hi:g} s holds {int(sel.sum())} samples "
                            f"(run covers {t[0]:g}..{t[-1]:g} s)")
        sigs.append((str(path), x[sel], used))
        starts.append(float(lo))
    lengths = [x.size for _, x, _ in sigs]
    n_common = min(lengths)
    sigs = [(p, x[:n_common], u) for p, x, u in sigs]
    k = decimate
    if k > 1:
        from scipy.signal import decimate as fir_decimate

        sigs = [(p, fir_decimate(x, k, ftype="fir", zero_phase=True), u) for p, x, u in sigs]
    rate_used = rate / k
    first = sigs[0][1]
    norm = float(first.max() - first.min())
    pairs = list(itertools.combinations(range(len(sigs)), 2))
    rows = []
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(pairs), desc="DTW pairs", leave=False)
    for i, j in pairs:
        d = dtw_compare(sigs[i][1], sigs[j][1], rate_used, dtw_window, norm_range=norm)
        rows.append({"run_a": i + 1, "run_b": j + 1, "distance_pct": d.distance_pct,
                     "mean_shift_s": d.mean_shift_s, "signed_shift_s": d.signed_shift_s})
        if bar is not None:
            bar.update(1)
    if bar is not None:
        bar.close()
    worst = max(rows, key=lambda r: r["distance_pct"])
    result = {"channel": channel, "runs": [p for p, _, _ in sigs], "channels_used": [u for _, _, u in sigs],
              "window_s": [start, stop], "window_starts_s": starts, "align_angle_deg": align_angle,
              "rate_hz": rate_used, "dtw_window_s": dtw_window,
              "normalizer": norm, "normalizer_note": "max - min of the first run in the window",
              "pairs": rows, "worst": worst,
              "mean_distance_pct": float(np.mean([r["distance_pct"] for r in rows]))}
    return Repeatability(result, lengths, int(sigs[0][1].size))
