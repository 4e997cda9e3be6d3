"""``twin plot``: a PNG of a run, a bench recording or a replay (matplotlib; no GPU, no display)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from twin.errors import TwinError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("plot", help="draw a run, recording or replay as a PNG (no GPU, no display)",
                       description="Draw a twin run file, a bench recording or a replay folder as a PNG: the "
                                   "channels over a time window (default: accelerometers and contact forces over "
                                   "the last 0.4 s), with --spectrum their Hann spectra with the crank harmonics "
                                   "and the bands of interest, and the journal orbits of the clearance joints when "
                                   "the file has them. A replay draws recorded and simulated accelerations "
                                   "together. Needs no GPU or display (twin view --screenshot draws the 3-D view).")
    p.add_argument("input", metavar="RUN|RECORDING|REPLAY",
                   help="run file (.mcap), bench recording (.mcap) or replay folder (or its replay.mcap)")
    p.add_argument("--out", metavar="FIG.png", required=True, help="PNG to write")
    p.add_argument("--channels", metavar="NAME,NAME",
                   help="channels to draw, comma-separated names or globs (e.g. 'AC*,fn_C'; a replay's "
                        "'meas_AC*' draws recorded and simulated together); default: accelerometers and "
                        "contact forces")
    p.add_argument("--window", metavar="START:STOP",
                   help="time window [s] (default: the last 0.4 s; with --spectrum the last second, at most "
                        "half the run)")
    p.add_argument("--spectrum", action="store_true",
                   help="add each channel's Hann amplitude spectrum with the crank harmonics and the bands")
    p.add_argument("--size", metavar="WxH", help="size of the PNG in pixels (default: from the panels)")
    p.set_defaults(func=run)


def parse_channels(text: str) -> list[str]:
    """``'AC*,fn_C'`` -> ``['AC*', 'fn_C']``; one line for an empty item."""
    items = [c.strip() for c in text.split(",")]
    if not all(items):
        raise TwinError(f"--channels: expects comma-separated channel names or globs, got {text!r}")
    return items


def parse_window(text: str) -> tuple[float, float]:
    """``'1.6:2'`` -> (1.6, 2.0) [s]; one line unless two finite numbers with START < STOP."""
    parts = text.split(":")
    try:
        t0, t1 = (float(x) for x in parts)
    except ValueError:
        raise TwinError(f"--window: expects START:STOP in seconds (e.g. 1.6:2), got {text!r}") from None
    if not (math.isfinite(t0) and math.isfinite(t1) and t0 < t1):
        raise TwinError(f"--window: expects finite seconds START < STOP, got {text!r}")
    return t0, t1


def run(args: argparse.Namespace) -> int:
    from twin.commands.view import parse_window_size
    from twin.util import check_output_file, check_size_px
    from twin.viz.plot import plot

    src = Path(args.input)
    if not src.exists():
        raise TwinError(f"{src}: no such file or folder")
    channels = parse_channels(args.channels) if args.channels is not None else None
    window = parse_window(args.window) if args.window is not None else None
    size = check_size_px(parse_window_size(args.size, "--size"), "size_px") if args.size is not None else None
    out = check_output_file(args.out, "--out", ".png", inputs=[src])
    info = plot(src, out, channels=channels, window=window, spectrum=args.spectrum, size_px=size)
    extra = []
    if info.harmonics_hz:
        extra.append(f"crank {info.crank_hz:.3f} Hz, {len(info.harmonics_hz)} harmonics marked")
    if info.orbits:
        extra.append("orbits at " + ", ".join(info.orbits))
    elif info.note:
        extra.append(info.note)
    w, h = info.size_px
    print(f"wrote {info.path} ({w}x{h} px, {info.kind}): {', '.join(info.channels)} over "
          f"{info.window_s[0]:.3f}-{info.window_s[1]:.3f} s" + "".join(f"; {e}" for e in extra)
          + f" in {info.seconds:.2f} s")
    return 0
