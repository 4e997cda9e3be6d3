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
import re
import signal
import sys
import threading
import tomllib
from typing import TYPE_CHECKING, Any, Sequence

from twin.errors import ConfigError, Terminated, TwinError, raise_terminated

if TYPE_CHECKING:
    from twin.config import BenchConfig
# twin.config is imported where it is used: it reads the packaged base model, and a broken
# installation must still give one line (main catches its ModelError), not an import traceback

#: modules providing subcommands (``register(subparsers)``), in help order
COMMANDS: list[str] = [
    "twin.commands.simulate",
    "twin.commands.record",
    "twin.commands.export_mjcf",
    "twin.commands.view",
    "twin.commands.plot",
    "twin.commands.study",
    "twin.commands.check",
    "twin.commands.calibrate",
    "twin.commands.import_recording",
    "twin.commands.replay",
    "twin.commands.analyze",
    "twin.commands.dataset",
    "twin.commands.identify",
]


#: options whose value is a path (their ``dest``): an empty value is refused for every command
PATH_OPTIONS = ("out", "save", "json", "summary_json", "rerun", "screenshot", "model", "calibration", "config",
                "trace")


#: arguments whose value is something the command reads (their ``dest``): registered with
#: :func:`twin.util.reading` while the command runs, so that no output of any command can be one of
#: them or lie inside one read as a folder (:data:`FOLDER_INPUTS`: a dataset)
INPUT_OPTIONS = ("config", "trace", "calibration", "model", "dataset", "dir", "recording", "spec", "export", "runs",
                 "input", "responses_csv", "responses")
FOLDER_INPUTS = ("dataset", "dir", "input")


def inputs_of(args: argparse.Namespace, dests: Sequence[str] = INPUT_OPTIONS) -> list[str]:
    """The input paths named on a parsed command line (those of ``dests``)."""
    out: list[str] = []
    for dest in dests:
        v = getattr(args, dest, None)
        for x in (v if isinstance(v, (list, tuple)) else [v]):
            if isinstance(x, str) and x.strip() and x != "-":
                out.append(x)
    return out


class UsageError(TwinError):
    """A command line argparse refuses (unknown option, bad value type, missing argument)."""


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line (no usage dump): :func:`main` prints them and
    returns exit status 2 like every other bad input."""

    def parse_known_args(self, args=None, namespace=None):  # type: ignore[override]
        self._argv = list(sys.argv[1:] if args is None else args)  # for error(): the value argparse did not take
        return super().parse_known_args(args, namespace)

    def error(self, message: str) -> None:  # type: ignore[override]
        # `--weights -1,2`: argparse reads a value that starts with '-' (other than a plain negative number) as an
        # option and says only "expected one argument"; name the value and how to give it
        m = re.match(r"argument (-[^\s/:]+)(?:/\S+)?: expected one argument$", message)
        argv = getattr(self, "_argv", [])
        if m:
            nxt = [argv[i + 1] for i, a in enumerate(argv[:-1]) if a == m.group(1) and argv[i + 1].startswith("-")
                   and argv[i + 1].split("=")[0] not in self._option_string_actions]  # not a real option
            if nxt:
                message += f"; {nxt[0]!r} reads as an option: write {m.group(1)}={nxt[0]}"
        raise UsageError(f"{message} (see '{self.prog} --help')")


#: configuration options, by what they describe (``add_config_args(p, options=...)``)
SELECT_OPTIONS = ("config", "test")
MODEL_OPTIONS = ("clearance_b", "clearance_c", "clearance_a", "clearance_guide", "orientation", "structure", "set")
DRIVE_OPTIONS = ("speed", "protocol", "trace")
RUN_OPTIONS = ("duration", "timestep", "engine", "channels", "output_rate", "drive_mode")
ALL_CONFIG_OPTIONS = SELECT_OPTIONS + MODEL_OPTIONS + DRIVE_OPTIONS + RUN_OPTIONS


def add_config_args(p: argparse.ArgumentParser, options: Sequence[str] = ALL_CONFIG_OPTIONS,
                    refused_set: Sequence[str] = ()) -> None:
    """Options that select and override a bench configuration.

    ``options`` names those that apply to the command (the others are not offered, so argparse
    refuses them in one line); ``refused_set`` lists dotted ``--set`` keys (or prefixes ending in
    ".") that the command decides itself and refuses.
    """
    from twin.config import ALL_CHANNEL_GROUPS, ENGINES, ORIENTATIONS

    unknown = set(options) - set(ALL_CONFIG_OPTIONS)
    assert not unknown, unknown
    has = set(options)
    g = p.add_argument_group("bench configuration")
    if "config" in has:
        g.add_argument("--config", metavar="FILE", help="TOML configuration (partial files override the defaults)")
    if "test" in has:
        g.add_argument("--test", type=int, metavar="ID", help="Table 4 test preset, 1..12")
        from twin.config.presets import NAMED_PRESETS, PRESET_SUMMARIES

        g.add_argument("--preset", metavar="NAME",
                       help="another paper's mechanism or a bench test: " + ", ".join(
                           f"{n} ({PRESET_SUMMARIES.get(n, 'see twin/config/presets/' + n + '.toml')})"
                           for n in NAMED_PRESETS))
    if "clearance_b" in has:
        g.add_argument("--clearance-b", type=float, metavar="MM",
                       help="diametral clearance at B [mm], 0 = ball bearing")
    if "clearance_c" in has:
        g.add_argument("--clearance-c", type=float, metavar="MM",
                       help="diametral clearance at C [mm], 0 = ball bearing")
    if "clearance_a" in has:
        g.add_argument("--clearance-a", type=float, metavar="MM",
                       help="diametral clearance at the ground pivot A [mm], 0 = ball bearing (the bench's)")
    if "clearance_guide" in has:
        g.add_argument("--clearance-guide", type=float, metavar="MM",
                       help="two-sided clearance of the slider guide [mm]: the slider's total transverse play "
                            "between its rails (joints.clearance_guide_mm); 0 = the preloaded ideal guide")
    if "orientation" in has:
        g.add_argument("--orientation", choices=ORIENTATIONS, help="bench axis that points up")
    if "structure" in has:
        from twin.config import STRUCTURE_MODES

        g.add_argument("--structure", choices=STRUCTURE_MODES,
                       help="rigid (the default) or flexible: the connecting rod bends and stretches, the frame and "
                            "the guide are sprung supports, the accelerometers sit on mounts ([structure] fields; "
                            "the MuJoCo engine adds the channel group 'structure' unless --channels is given)")
    drive = [o for o in DRIVE_OPTIONS if o in has]
    sp = g.add_mutually_exclusive_group() if len(drive) > 1 else g
    if "speed" in has:
        sp.add_argument("--speed", type=float, metavar="MOTOR_RPM", help="constant motor speed [rpm]")
    if "protocol" in has:
        sp.add_argument("--protocol", action="store_true", help="the 38 s three-speed protocol of S003 §4.3")
    if "trace" in has:
        sp.add_argument("--trace", metavar="FILE", help="drive by an encoder trace (.npz/.csv with t, angle)")
    if "duration" in has:
        g.add_argument("--duration", type=float, metavar="S", help="simulated time [s] (0 = protocol length)")
    if "timestep" in has:
        g.add_argument("--timestep", type=float, metavar="S", help="integration step [s]")
    if "output_rate" in has:
        g.add_argument("--output-rate", type=float, metavar="HZ",
                       help="sample rate of the run's channels [Hz] (default 100000; the timestep must divide "
                            "its period)")
    if "engine" in has:
        g.add_argument("--engine", choices=ENGINES, help="mujoco (the twin) or reference (R-matrix)")
    if "drive_mode" in has:
        g.add_argument("--drive-mode", choices=("pid", "prescribed", "motor", "torque"),
                       help="how the crank is driven: pid (crank PID on the program, the default), prescribed, "
                            "motor (the bench's motor speed loop and V-belt, [drivetrain] parameters) or torque "
                            "(motor torque program, then release); motor and torque add the channel group "
                            "'motor' unless --channels is given")
    if "channels" in has:
        g.add_argument("--channels", metavar="G,G", help=f"channel groups to compute: {','.join(ALL_CHANNEL_GROUPS)}")
    if "set" in has:
        g.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                       help="override any field by dotted path, TOML value (e.g. drive.ramp_s=0.2)")
    p.set_defaults(_refused_set=tuple(refused_set))


def _parse_value(key: str, text: str) -> Any:
    from twin.util import toml_loads

    if "\n" in text or "\r" in text:
        raise ConfigError(f"--set {key}", "the value must be on one line")
    try:
        return toml_loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError as err:
        if "nested deeper" in str(err):
            raise ConfigError(f"--set {key}", str(err)) from None
        return text  # bare strings: --set mechanism.orientation=x


def _flatten(key: str, value: Any) -> list[tuple[str, Any]]:
    if isinstance(value, dict) and value:
        return [kv for k, v in value.items() for kv in _flatten(f"{key}.{k}", v)]
    return [(key, value)]


def _opt(args: argparse.Namespace, name: str) -> Any:
    return getattr(args, name, None)


def load_config_file(path: str) -> BenchConfig:
    """:func:`twin.config.load_config` for the ``--config`` option: an error about the file itself
    (the library's ``path``) names ``--config``."""
    from twin.config import load_config
    from twin.tracefile import with_trace_duration

    try:
        cfg = load_config(path)
        return with_trace_duration(cfg)  # a trace program without a duration: the trace's length
    except ConfigError as err:
        if err.field == "path":
            raise ConfigError("--config", err.message) from None
        # a bad value in the file: the message names the file as well as the field
        raise ConfigError(err.field, f"{err.message} (in --config {path})") from None


#: (flag, argparse dest, configuration field) of the options that set one field to their value
_OPTION_FIELDS = (("--clearance-b", "clearance_b", "joints.clearance_b_mm"),
                  ("--clearance-c", "clearance_c", "joints.clearance_c_mm"),
                  ("--clearance-a", "clearance_a", "joints.clearance_a_mm"),
                  ("--clearance-guide", "clearance_guide", "joints.clearance_guide_mm"),
                  ("--orientation", "orientation", "mechanism.orientation"), ("--speed", "speed", "drive.motor_rpm"),
                  ("--duration", "duration", "simulation.duration_s"), ("--timestep", "timestep", "simulation.timestep_s"),
                  ("--output-rate", "output_rate", "sensors.output_rate_hz"), ("--engine", "engine", "simulation.engine"),
                  ("--structure", "structure", "structure.mode"), ("--drive-mode", "drive_mode", "drive.mode"))


def config_from_args(args: argparse.Namespace) -> BenchConfig:
    """Configuration from ``--config``/``--test`` plus the override options the command offers."""
    from twin.config import ALL_CHANNEL_GROUPS, BenchConfig, preset, with_overrides

    if _opt(args, "config") is not None and _opt(args, "test") is not None:
        raise ConfigError("--test", "cannot be combined with --config (put 'test = N' in the file)")
    if _opt(args, "config") is not None and _opt(args, "preset") is not None:
        raise ConfigError("--preset", "cannot be combined with --config (put 'preset = \"NAME\"' in the file)")
    if _opt(args, "test") is not None and _opt(args, "preset") is not None:
        raise ConfigError("--preset", "cannot be combined with --test: give one starting point")
    if _opt(args, "config") is not None:
        cfg = load_config_file(args.config)
    elif _opt(args, "test") is not None:
        cfg = preset(args.test)
    elif _opt(args, "preset") is not None:
        from twin.config import named_preset

        cfg = named_preset(args.preset)
    else:
        cfg = BenchConfig()
    ov: dict[str, Any] = {}
    if _opt(args, "clearance_b") is not None:
        ov["joints.clearance_b_mm"] = args.clearance_b
    if _opt(args, "clearance_c") is not None:
        ov["joints.clearance_c_mm"] = args.clearance_c
    if _opt(args, "clearance_a") is not None:
        ov["joints.clearance_a_mm"] = args.clearance_a
    if _opt(args, "clearance_guide") is not None:
        ov["joints.clearance_guide_mm"] = args.clearance_guide
    if _opt(args, "orientation"):
        ov["mechanism.orientation"] = args.orientation
    if _opt(args, "speed") is not None:
        ov["drive.program"], ov["drive.motor_rpm"] = "constant", args.speed
    if _opt(args, "protocol"):
        ov["drive.program"] = "protocol"
        if _opt(args, "duration") is None:
            ov["simulation.duration_s"] = 0.0
    if _opt(args, "trace") is not None:
        from twin.drive import trace_duration

        ov["drive.program"], ov["drive.trace_file"] = "trace", args.trace
        if _opt(args, "duration") is None:
            ov["simulation.duration_s"] = trace_duration(args.trace)
    if _opt(args, "duration") is not None:
        ov["simulation.duration_s"] = args.duration
    if _opt(args, "timestep") is not None:
        ov["simulation.timestep_s"] = args.timestep
    if _opt(args, "output_rate") is not None:
        ov["sensors.output_rate_hz"] = args.output_rate
    if _opt(args, "engine"):
        ov["simulation.engine"] = args.engine
    if _opt(args, "structure") is not None:
        ov["structure.mode"] = args.structure
    if _opt(args, "drive_mode") is not None:
        ov["drive.mode"] = args.drive_mode
        if args.drive_mode in ("motor", "torque") and _opt(args, "channels") is None \
                and "motor" not in cfg.sensors.channels:
            ov["sensors.channels"] = list(cfg.sensors.channels) + ["motor"]
    if _opt(args, "channels") is not None:
        groups = [c.strip() for c in args.channels.split(",")]
        if not all(groups):
            raise ConfigError("--channels", f"expects comma-separated groups of {', '.join(ALL_CHANNEL_GROUPS)}; "
                                            f"got {args.channels!r}")
        ov["sensors.channels"] = groups
    refused = getattr(args, "_refused_set", ())
    # the fields an option sets itself, with its flag: a --set of one to another value contradicts it (before, the
    # --set won silently, or --structure flexible's channels were refused for a --set structure.mode = "rigid")
    by_option = {key: flag for flag, dest, key in _OPTION_FIELDS if _opt(args, dest) is not None}
    for item in _opt(args, "set") or []:
        if "=" not in item:
            raise ConfigError("--set", f"expects KEY=VALUE, got {item!r}")
        key, text = (x.strip() for x in item.split("=", 1))
        if not key:
            raise ConfigError("--set", f"expects KEY=VALUE with a dotted key, got {item!r}")
        value = _parse_value(key, text)
        # a table (--set simulation={engine="reference"}) sets its fields, not the whole section
        for k, v in _flatten(key, value):
            for r in refused:
                if k == r or (r.endswith(".") and k.startswith(r)):
                    raise ConfigError(f"--set {k}", f"does not apply to this command (it sets {r.rstrip('.')} "
                                                    "itself or does not use it)")
            if k in by_option and v != ov[k]:
                raise ConfigError(f"--set {k}", f"contradicts {by_option[k]} {ov[k]!r} (got {v!r}); give the field once")
            ov[k] = v
    if _opt(args, "structure") == "flexible" and _opt(args, "channels") is None:
        groups = list(ov.get("sensors.channels", cfg.sensors.channels))
        if "structure" not in groups:  # the flexible structure's channels (both engines)
            ov["sensors.channels"] = groups + ["structure"]
    if _opt(args, "structure") == "rigid" and _opt(args, "channels") is None:
        groups = list(ov.get("sensors.channels", cfg.sensors.channels))
        if "structure" in groups:  # the group --structure flexible added (e.g. a flexible recording's, replayed rigid)
            ov["sensors.channels"] = [g for g in groups if g != "structure"]
    if ov.get("drive.mode", cfg.drive.mode) == "torque":  # the torque drive follows its torque program, no speed
        # program: the configuration refuses drive.program/motor speed too; here the flag that set it is named
        for flag, given in (("--speed", _opt(args, "speed")), ("--protocol", _opt(args, "protocol") or None),
                            ("--trace", _opt(args, "trace"))):
            if given is not None:
                raise ConfigError(flag, "is not used with drive.mode = 'torque' (the motor follows the torque program "
                                        "drivetrain.torque_s/torque_nm, then coasts); leave it out or use another "
                                        "--drive-mode")
    return with_overrides(cfg, ov) if ov else cfg


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="twin", description="Digital twin of the slider-crank clearance test bench.")
    from twin import __version__

    parser.add_argument("--version", action="version", version=f"twin {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for mod in COMMANDS:
        importlib.import_module(mod).register(sub)
    for leaf in _leaf_parsers(parser):
        leaf.set_defaults(_flags={a.dest: max(a.option_strings, key=len) for a in leaf._actions
                                  if a.option_strings and a.dest not in (argparse.SUPPRESS, "help")})
    return parser


def _leaf_parsers(parser: argparse.ArgumentParser):
    """The parsers that run a command (those without subcommands of their own), each once."""
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        yield parser
    for a in subs:
        for p in dict.fromkeys(a.choices.values()):  # an alias names the same parser
            yield from _leaf_parsers(p)


#: configuration fields that :func:`config_from_args` sets from an option (its ``dest``): a message naming
#: such a field between backticks names the option too, where the command offers it
CONFIG_FLAGS = {"joints.clearance_b_mm": "clearance_b", "joints.clearance_c_mm": "clearance_c",
                "joints.clearance_a_mm": "clearance_a", "joints.clearance_guide_mm": "clearance_guide",
                "mechanism.orientation": "orientation", "drive.motor_rpm": "speed", "drive.trace_file": "trace",
                "simulation.duration_s": "duration", "simulation.timestep_s": "timestep",
                "sensors.output_rate_hz": "output_rate", "simulation.engine": "engine", "drive.mode": "drive_mode",
                "sensors.channels": "channels"}

#: configuration fields naming a file that an option gives: an error about that file names the option
_FILE_FIELDS = frozenset({"drive.trace_file"})

#: unit suffixes of the library's argument names (``max_lag_s``) that the flag leaves out (``--max-lag``)
_UNIT_SUFFIXES = ("_s", "_hz", "_mm", "_m", "_rpm", "_n", "_deg", "_px")


def error_message(err: TwinError, args: argparse.Namespace | None = None) -> str:
    """The one-line message of ``err`` as the command line shows it.

    The library names what an error is about by its own name (a Python argument, a dotted TOML
    path): as :attr:`TwinError.field`, and in the text between backticks (``give `rate_hz` ``).
    Where the running command sets that name with an option, the message names the option instead
    (``max_lag_s: ...`` -> ``--max-lag: ...``). A command maps a name whose option is spelt otherwise
    with ``set_defaults(_field_flags={name: flag})``; else a name maps to the option whose ``dest`` is
    the name (less a unit suffix: ``max_lag_s`` -> ``--max-lag``). The field of the error maps only when
    that option has a value (``test = 13`` in a ``--config`` file is not ``--test``)."""
    if args is None:
        return str(err)
    explicit = getattr(args, "_field_flags", None) or {}
    flags = getattr(args, "_flags", None) or {}

    def flag_of(name: str, given_only: bool) -> str | None:
        if name in explicit:
            return explicit[name]
        if CONFIG_FLAGS.get(name) in flags:  # a configuration field this command sets
            if not given_only:
                return f"{name} or {flags[CONFIG_FLAGS[name]]}"
            if name in _FILE_FIELDS and getattr(args, CONFIG_FLAGS[name], None) is not None:
                return flags[CONFIG_FLAGS[name]]  # a file the option named (--trace FILE): the option
        for dest in [name] + [name[:-len(u)] for u in _UNIT_SUFFIXES if name.endswith(u)]:
            if dest in flags and not (given_only and getattr(args, dest, None) is None):
                return flags[dest]
        return None

    field = getattr(err, "field", None)
    flag = flag_of(field, True) if field else None
    text = f"{flag}: {err.message}" if flag else str(err)
    return re.sub(r"`([^`\s][^`]*)`", lambda m: flag_of(m.group(1), False) or m.group(0), text)


def main(argv: Sequence[str] | None = None) -> int:
    import os

    # no twin command renders through MuJoCo: skip its OpenGL set-up at import (about 30 ms of
    # every start, analysis/bench_startup.py); a value set by the user is kept
    os.environ.setdefault("MUJOCO_GL", "disable")
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
    except TwinError as err:  # usage errors; a broken installation (ModelError, EngineUnavailableError)
        return _fail(str(err))
    for dest in PATH_OPTIONS:  # an empty path must not silently become a default name
        v = getattr(args, dest, None)
        if isinstance(v, str) and not v.strip():
            return _fail(f"--{dest.replace('_', '-')}: is empty; give a path")
    previous = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGTERM, raise_terminated)
    from twin.util import reading

    try:
        with reading(inputs_of(args, [d for d in INPUT_OPTIONS if d not in FOLDER_INPUTS]),
                     inputs_of(args, FOLDER_INPUTS)):
            rc = int(args.func(args) or 0)
        sys.stdout.flush()  # a full disk under `> /dev/full` shows here, not as a traceback at exit
        return rc
    except TwinError as err:
        return _fail(error_message(err, args))
    except Terminated:
        print("twin: terminated", file=sys.stderr)
        return 128 + signal.SIGTERM
    except KeyboardInterrupt:
        print("twin: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `twin ... | head`: the reader left; nothing to report
        _silence_stdout()
        return 1
    except OSError as err:  # the system refused (disk full, a file vanished): say which file, and why
        import errno as _errno

        where = f"{err.filename}: " if err.filename else ("standard output: " if err.errno == _errno.ENOSPC else "")
        if err.errno == _errno.ENOSPC:
            _silence_stdout()
        return _fail(f"{where}{err.strerror or err}")
    except (RecursionError, MemoryError) as err:
        return _fail(f"the input is too large or too deeply nested to process ({type(err).__name__})")
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def _one_line(text: str) -> str:
    """A message on one line: control characters (a newline in a file name) escaped."""
    text = text.strip()
    if any(ord(c) < 32 or ord(c) == 127 for c in text):
        text = text.encode("unicode_escape", "backslashreplace").decode("ascii")
    return text


def _fail(message: str) -> int:
    print(f"twin: error: {_one_line(message)}", file=sys.stderr)
    return 2


def _silence_stdout() -> None:
    """Point standard output at /dev/null: the interpreter's flush at exit must not fail again."""
    import os

    try:
        sys.stdout.flush()
    except OSError:
        pass
    try:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
