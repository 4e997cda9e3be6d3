"""``twin view``: turn a run or bench recording into a rerun recording (and open it)."""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import time
from pathlib import Path

from twin.errors import TwinError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("view", help="convert a run/recording to a rerun .rrd (optionally open the viewer)",
                       description="Convert a twin run file (simulated run, bench recording or replay, MCAP) into "
                                   "a rerun recording with a default layout: the 3-D bench moving in time, journal "
                                   "orbits, contact forces, every signal, spectra and the configuration. Writes "
                                   "RUN.rrd beside the input unless --save is given; no viewer is needed.")
    p.add_argument("input", metavar="RUN_OR_RECORDING.mcap", help="twin run file to view")
    p.add_argument("--save", metavar="OUT.rrd", help="recording to write (default: beside the input, .rrd)")
    p.add_argument("--spawn", action="store_true", help="open the rerun viewer on the recording")
    p.add_argument("--fft-window", nargs=2, type=float, metavar=("T0", "T1"),
                   help="time window of the spectra [s] (default: a steady-speed second near the end)")
    p.add_argument("--pose-rate", type=float, metavar="HZ", default=1000.0,
                   help="rate of the 3-D poses and contact arrows [Hz] (signals keep their rate; default 1000)")
    p.add_argument("--plot-window", type=float, metavar="S", default=1.0,
                   help="time window around the cursor of the accelerometer and contact plots [s] "
                        "(0 = whole run; default 1)")
    p.add_argument("--screenshot", metavar="OUT.png",
                   help="also save a PNG of the default view from a headless viewer (needs Vulkan, e.g. Mesa's)")
    p.add_argument("--at", type=float, metavar="T", help="time cursor of the screenshot [s]")
    p.add_argument("--wait", type=float, metavar="S", default=60.0,
                   help="seconds the headless viewer loads before the screenshot (default 60)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from twin.viz import ViewOptions, convert_file, default_output

    src = Path(args.input)
    if src.suffix != ".mcap":
        raise TwinError(f"{src}: expected a .mcap run or recording file")
    if not src.is_file():
        raise TwinError(f"{src}: no such file")
    out = Path(args.save) if args.save else default_output(src)
    if out.suffix != ".rrd":
        raise TwinError(f"--save: must end in .rrd, got {out.name}")
    if not out.parent.is_dir():
        raise TwinError(f"--save: directory {out.parent} does not exist")
    if args.screenshot and (Path(args.screenshot).suffix != ".png" or not Path(args.screenshot).parent.is_dir()):
        raise TwinError(f"--screenshot: must be a .png in an existing directory, got {args.screenshot}")
    opts = ViewOptions(pose_rate_hz=args.pose_rate, plot_window_s=args.plot_window,
                       fft_window_s=tuple(args.fft_window) if args.fft_window else None)
    t = time.perf_counter()
    tm: dict[str, float] = {}
    path = convert_file(src, out, opts, timings=tm)
    print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB) in {time.perf_counter() - t:.2f} s "
          f"(read {tm['read']:.2f} s, id {tm['hash']:.2f} s, convert {tm['convert']:.2f} s)")
    if args.screenshot:
        from twin.viz.screenshot import screenshot

        shot = screenshot(path, args.screenshot, at_s=args.at, wait_s=args.wait)
        print(f"saved {shot}")
    if args.spawn:
        _spawn(path)
    return 0


def _spawn(path: Path) -> None:
    """Open the rerun viewer on ``path`` in the background."""
    exe = shutil.which("rerun") or str(Path(sys.executable).with_name("rerun"))
    if not Path(exe).exists() and shutil.which(exe) is None:
        raise TwinError("--spawn: the rerun viewer ('rerun' from rerun-sdk) is not on PATH")
    subprocess.Popen([exe, str(path)], start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    print(f"opened the rerun viewer on {path}")
