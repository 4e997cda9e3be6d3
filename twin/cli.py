"""The ``twin`` command line.

Subcommands live in modules listed in :data:`COMMANDS`; each exposes
``register(subparsers)`` which adds its parser and sets ``func`` to a handler taking the
parsed arguments and returning an exit status. Shared configuration options (``--config``,
``--test``, clearances, orientation, speed, ...) come from :func:`add_config_args` and are
turned into a :class:`~twin.config.BenchConfig` by :func:`config_from_args`.

Every :class:`~twin.errors.TwinError` (bad config, bad recording, bad argument) is printed
as one line ``twin: error: ...`` with exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import signal
import sys
import threading
import tomllib
from typing import Any, Sequence

from twin.config import (CHANNEL_GROUPS, ENGINES, ORIENTATIONS, BenchConfig, load_config,
                         preset, with_overrides)
from twin.errors import ConfigError, TwinError

#: modules providing subcommands (``register(subparsers)``), in help order
COMMANDS: list[str] = [
    "twin.commands.simulate",
    "twin.commands.export_mjcf",
    "twin.commands.view",
    "twin.commands.study",
    "twin.commands.calibrate",
    "twin.commands.import_recording",
    "twin.commands.replay",
    "twin.commands.analyze",
]


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line (no usage dump), exit status 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message}\n")


def add_config_args(p: argparse.ArgumentParser) -> None:
    """Options that select and override a bench configuration."""
    g = p.add_argument_group("bench configuration")
    g.add_argument("--config", metavar="FILE", help="TOML configuration (partial files override the defaults)")
    g.add_argument("--test", type=int, metavar="ID", help="Table 4 test preset, 1..12")
    g.add_argument("--clearance-b", type=float, metavar="MM", help="diametral clearance at B [mm], 0 = ball bearing")
    g.add_argument("--clearance-c", type=float, metavar="MM", help="diametral clearance at C [mm], 0 = ball bearing")
    g.add_argument("--orientation", choices=ORIENTATIONS, help="bench axis that points up")
    sp = g.add_mutually_exclusive_group()
    sp.add_argument("--speed", type=float, metavar="MOTOR_RPM", help="constant motor speed [rpm]")
    sp.add_argument("--protocol", action="store_true", help="the 38 s three-speed protocol of S003 §4.3")
    sp.add_argument("--trace", metavar="FILE", help="drive by an encoder trace (.npz/.csv with t, angle)")
    g.add_argument("--duration", type=float, metavar="S", help="simulated time [s] (0 = program length)")
    g.add_argument("--timestep", type=float, metavar="S", help="integration step [s]")
    g.add_argument("--engine", choices=ENGINES, help="mujoco (the twin) or reference (R-matrix)")
    g.add_argument("--channels", metavar="G,G", help=f"channel groups to compute: {','.join(CHANNEL_GROUPS)}")
    g.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override any field by dotted path, TOML value (e.g. drive.ramp_s=0.2)")


def _parse_value(key: str, text: str) -> Any:
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text  # bare strings: --set mechanism.orientation=x


def config_from_args(args: argparse.Namespace) -> BenchConfig:
    """Configuration from ``--config``/``--test`` plus the override options."""
    if args.config and args.test is not None:
        raise ConfigError("--test", "cannot be combined with --config (put 'test = N' in the file)")
    cfg = load_config(args.config) if args.config else (preset(args.test) if args.test is not None else BenchConfig())
    ov: dict[str, Any] = {}
    if args.clearance_b is not None:
        ov["joints.clearance_b_mm"] = args.clearance_b
    if args.clearance_c is not None:
        ov["joints.clearance_c_mm"] = args.clearance_c
    if args.orientation:
        ov["mechanism.orientation"] = args.orientation
    if args.speed is not None:
        ov["drive.program"], ov["drive.motor_rpm"] = "constant", args.speed
    if args.protocol:
        ov["drive.program"] = "protocol"
        if args.duration is None:
            ov["simulation.duration_s"] = 0.0
    if args.trace:
        ov["drive.program"], ov["drive.trace_file"] = "trace", args.trace
        if args.duration is None:
            ov["simulation.duration_s"] = 0.0
    if args.duration is not None:
        ov["simulation.duration_s"] = args.duration
    if args.timestep is not None:
        ov["simulation.timestep_s"] = args.timestep
    if args.engine:
        ov["simulation.engine"] = args.engine
    if args.channels:
        ov["sensors.channels"] = [c.strip() for c in args.channels.split(",") if c.strip()]
    for item in args.set:
        if "=" not in item:
            raise ConfigError("--set", f"expects KEY=VALUE, got {item!r}")
        key, text = item.split("=", 1)
        ov[key.strip()] = _parse_value(key, text.strip())
    return with_overrides(cfg, ov) if ov else cfg


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="twin", description="Digital twin of the slider-crank clearance test bench.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for mod in COMMANDS:
        importlib.import_module(mod).register(sub)
    return parser


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread like Ctrl-C so that every writer's clean-up runs
    (temporary files removed, nothing half-written left under the final name)."""


def _raise_terminated(signum, frame):  # noqa: ARG001 - signal handler signature
    raise Terminated()


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    previous = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        return int(args.func(args) or 0)
    except TwinError as err:
        print(f"twin: error: {err}", file=sys.stderr)
        return 2
    except Terminated:
        print("twin: terminated", file=sys.stderr)
        return 128 + signal.SIGTERM
    except KeyboardInterrupt:
        print("twin: interrupted", file=sys.stderr)
        return 130
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
