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
    opts = ViewOptions(pose_rate_hz=args.pose_rate,
                       fft_window_s=tuple(args.fft_window) if args.fft_window else None)
    t = time.perf_counter()
    path = convert_file(src, out, opts)
    print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB) in {time.perf_counter() - t:.2f} s")
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
