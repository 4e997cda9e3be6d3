"""``twin view``: turn a run or bench recording into a rerun recording (and open it).

Everything that can be checked is checked before the (possibly long) conversion, so that nothing
is written when the command cannot do what it was asked: the input, the output paths
(:func:`twin.util.check_output_file`), and what the machine needs:

* ``--spawn`` opens a window: on Linux and other X11/Wayland systems (not macOS or Windows) a
  display is there when ``DISPLAY``, ``WAYLAND_DISPLAY`` or ``WAYLAND_SOCKET`` is set (the
  variables the viewer's windowing library, winit, connects with); none set = no display, a
  one-line error. With a display, the viewer must still run :data:`SPAWN_CHECK_S` seconds after it
  started, else its own message (e.g. "Failed to open connection to X server") is the error line
  (the recording is written by then; the line says where).
* ``--screenshot`` needs a Vulkan driver (:func:`twin.viz.screenshot.check_vulkan`); a viewer that
  exits or panics while starting or loading is a one-line error quoting it.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from twin.errors import TwinError

#: Seconds the spawned viewer must keep running before ``twin view --spawn`` reports it open.
SPAWN_CHECK_S = 1.5
#: Default of --plot-window [s] (= ViewOptions.plot_window_s; kept here so the CLI loads no rerun).
DEFAULT_PLOT_WINDOW_S = 0.3
#: Window of the headless viewer [px] unless --window-size says otherwise.
DEFAULT_WINDOW = (1920, 1080)
#: Seconds the headless viewer may load and settle before a screenshot, unless --wait says otherwise.
DEFAULT_WAIT_S = 60.0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("view", help="convert a run/recording to a rerun .rrd (optionally open the viewer)",
                       description="Convert a twin run file (simulated run, bench recording or replay, MCAP) into "
                                   "a rerun recording with a default layout: the 3-D bench moving in time, journal "
                                   "orbits, contact forces, every signal, spectra and the configuration. Writes "
                                   "RUN.rrd beside the input unless --save is given; no viewer is needed.")
    p.add_argument("input", metavar="RUN_OR_RECORDING.mcap",
                   help="twin run file or bench recording to view (sample:NAME for a sample recording that ships "
                        "with twin), or a dataset folder with --run")
    p.add_argument("--run", metavar="RUN_ID", help="with a dataset folder: the run to view (twin dataset info lists them)")
    p.add_argument("--save", metavar="OUT.rrd", help="recording to write (default: beside the input, .rrd)")
    p.add_argument("--spawn", action="store_true", help="open the rerun viewer on the recording")
    p.add_argument("--fft-window", nargs=2, type=float, metavar=("T0", "T1"),
                   help="time window of the spectra [s] (default: a steady-speed second near the end)")
    p.add_argument("--pose-rate", type=float, metavar="HZ", default=1000.0,
                   help="rate of the 3-D poses and contact arrows [Hz] (signals keep their rate; default 1000)")
    p.add_argument("--plot-window", type=float, metavar="S", default=DEFAULT_PLOT_WINDOW_S,
                   help="time window around the cursor of the accelerometer and contact plots [s] "
                        f"(0 = whole run; default {DEFAULT_PLOT_WINDOW_S:g}: a time label every 100 ms)")
    p.add_argument("--screenshot", metavar="OUT.png",
                   help="also save a PNG of the default view from a headless viewer (needs Vulkan, e.g. Mesa's)")
    p.add_argument("--at", type=float, metavar="T", help="time cursor of the screenshot [s] (with --screenshot)")
    p.add_argument("--wait", type=float, metavar="S", default=None,
                   help=f"with --screenshot: the most seconds to wait for the recording to load and the view "
                        f"to settle (it is saved as soon as two frames in a row are identical; "
                        f"default {DEFAULT_WAIT_S:g})")
    p.add_argument("--window-size", metavar="WxH", default=None,
                   help="with --screenshot: size of the headless viewer's window in pixels (default 1920x1080)")
    p.set_defaults(func=run, _field_flags={"png": "--screenshot", "window": "--window-size"})  # twin.viz.screenshot's names


def run(args: argparse.Namespace) -> int:
    from twin.commands.inputs import is_sample, recording
    from twin.util import check_output_file
    from twin.viz import ViewOptions, convert_file, default_output

    src = recording(args.input)
    dataset_run = None
    if src.is_dir() and (src / "info.json").is_file():
        if not args.run:
            raise TwinError(f"{src}: a dataset folder; give --run RUN_ID (twin dataset info {src} lists the runs)")
        dataset_run = src / "data" / f"{args.run}.parquet"
        if not dataset_run.is_file():
            raise TwinError(f"--run: {args.run!r} is not a finished run of the dataset {src}")
        default = src.parent / f"{src.name}-{args.run}.rrd"
    else:
        if args.run:
            raise TwinError("--run: applies to a dataset folder, not to a run file")
        if src.suffix.lower() != ".mcap":
            raise TwinError(f"{src}: expected a .mcap run or recording file, or a dataset folder")
        if src.is_dir():
            raise TwinError(f"{src}: is a directory; expected a .mcap run or recording file, or a dataset folder")
        if not src.is_file():
            raise TwinError(f"{src}: " + ("not a regular file (a folder, pipe or device)" if src.exists()
                                          else "no such file"))
        # beside the input, but a shipped sample's in the working folder (not inside the installation)
        default = Path(default_output(src).name) if is_sample(args.input) else default_output(src)
    out = check_output_file(args.save if args.save else default, "--save", ".rrd", inputs=[src])
    wait = DEFAULT_WAIT_S if args.wait is None else args.wait
    if args.screenshot:
        check_output_file(args.screenshot, "--screenshot", ".png")
        window = parse_window_size(args.window_size) if args.window_size is not None else DEFAULT_WINDOW
        from twin.viz.screenshot import check_screenshot_args, check_vulkan, rerun_executable

        check_screenshot_args(wait, args.at, window)
        rerun_executable()
        check_vulkan()
    else:
        for flag, value in (("--at", args.at), ("--wait", args.wait), ("--window-size", args.window_size)):
            if value is not None:
                raise TwinError(f"{flag}: applies to --screenshot only; give --screenshot OUT.png or leave it out")
    if args.spawn:
        exe = _viewer_for_spawn()
    opts = ViewOptions(pose_rate_hz=args.pose_rate, plot_window_s=args.plot_window,
                       fft_window_s=tuple(args.fft_window) if args.fft_window else None)
    t = time.perf_counter()
    tm: dict[str, float] = {}
    if dataset_run is not None:
        from twin.dataset.storage import read_run
        from twin.viz import write_rrd

        run = read_run(dataset_run)
        path = write_rrd(run, out, recording_id=f"twin-dataset-{args.run}", name=run.config.name if run.config
                         else args.run, options=opts, source=f"dataset {src}, run {args.run}")
        print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB) in {time.perf_counter() - t:.2f} s")
    else:
        path = convert_file(src, out, opts, timings=tm)
        print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB) in {time.perf_counter() - t:.2f} s "
              f"(read {tm['read']:.2f} s, id {tm['hash']:.2f} s, convert {tm['convert']:.2f} s)")
    if args.screenshot:
        from twin.viz.screenshot import screenshot

        shot = screenshot(path, args.screenshot, at_s=args.at, wait_s=wait, window=window)
        how = "view settled" if shot.settled else f"view still changing at --wait {wait:g} s; a larger --wait may help"
        print(f"saved {shot.path} in {shot.seconds:.1f} s ({how})")
    if args.spawn:
        _spawn(exe, path)
    return 0


def parse_window_size(text: str, flag: str = "--window-size") -> tuple[int, int]:
    """``WxH`` (e.g. ``1600x900``) as pixels; else a one-line TwinError naming ``flag`` (the range is
    :func:`twin.viz.screenshot.check_screenshot_args`'s to check)."""
    parts = text.lower().split("x")
    if len(parts) == 2 and all(p.strip().isdigit() for p in parts):
        w, h = (int(p) for p in parts)
        return w, h
    raise TwinError(f"{flag}: must be WIDTHxHEIGHT in pixels, each 64..8192 (e.g. 1600x900), got {text!r}")


def has_display() -> bool:
    """Whether a window can be opened (see the module docstring); always True on macOS and Windows."""
    if sys.platform == "darwin" or sys.platform.startswith("win"):
        return True
    return any(os.environ.get(v) for v in ("DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"))


def _viewer_for_spawn() -> str:
    """The rerun viewer to open, after checking there is a display to open it on."""
    if not has_display():
        raise TwinError("--spawn: no display (none of DISPLAY, WAYLAND_DISPLAY, WAYLAND_SOCKET is set), so the rerun "
                        "viewer cannot open a window; leave out --spawn and open the .rrd with 'rerun FILE.rrd' "
                        "where there is a display, or use --screenshot OUT.png")
    exe = shutil.which("rerun") or str(Path(sys.executable).with_name("rerun"))
    if not Path(exe).is_file():
        raise TwinError("--spawn: the rerun viewer ('rerun' from rerun-sdk) is not on PATH")
    return exe


def _spawn(exe: str, path: Path) -> None:
    """Open the rerun viewer on ``path`` in the background; it must still run after
    :data:`SPAWN_CHECK_S` seconds (its output until then goes to a log quoted on failure)."""
    from twin.viz.screenshot import viewer_message

    from twin.viz import USER_RUST_LOG

    env = dict(os.environ, RUST_LOG=USER_RUST_LOG or "error")  # not the SDK's "off" of this process
    with tempfile.TemporaryFile() as log:
        proc = subprocess.Popen([exe, str(path)], start_new_session=True, stdin=subprocess.DEVNULL,
                                stdout=log, stderr=log, env=env)
        try:
            code = proc.wait(timeout=SPAWN_CHECK_S)
        except subprocess.TimeoutExpired:
            print(f"opened the rerun viewer on {path}")
            return
        log.seek(0)
        msg = viewer_message(log.read())
    raise TwinError(f"--spawn: the rerun viewer exited at once (status {code}: {msg}); {path} is written, "
                    f"open it with 'rerun {path}' where there is a display")
