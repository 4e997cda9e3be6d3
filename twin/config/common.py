"""Names and checks shared by the configuration's modules: the allowed values (joints, programs,
channel groups, accelerometers...), the base model's defaults and the validation helpers that
raise :class:`~twin.errors.ConfigError` naming the field."""

from __future__ import annotations

import math
import re
from typing import Any

from twin import model_xml
from twin.errors import ConfigError, did_you_mean

#: defaults held by the base model mjcf/bench.xml (parsed once; ModelError if unreadable)
XML_DEFAULTS = model_xml.defaults()

#: Diametral clearances of the bushing catalogue [mm] (S003 §2.2.1).
CATALOGUE_DIAMETRAL_MM: tuple[float, ...] = (0.02, 0.05, 0.07, 0.10, 0.50, 1.00)
#: Bench axes that can be vertical (S003 §2.2.3).
ORIENTATIONS: tuple[str, ...] = ("x", "y", "z")
#: Joints that can take a clearance, in order: the ground–crank pivot A (a ball bearing on the S003
#: bench; a clearance there for the general mechanism of the seeds), crank–rod B, rod–slider C.
JOINTS: tuple[str, ...] = ("A", "B", "C")
#: Drive programs.
PROGRAMS: tuple[str, ...] = ("constant", "protocol", "trace", "steps")
#: Output channel groups a run can carry (see :mod:`twin.channels`).
CHANNEL_GROUPS: tuple[str, ...] = ("accel", "encoder", "crank", "slider", "joints", "drive")
#: Channel groups a scene may ask for but that are not in the default list (they cost time):
#: "energy" (mechanical energy and slider speed, for energy balances; both engines);
#: "motor" (motor, belt and command channels; drive.mode "motor" or "torque" only);
#: "drive_energy" (the drive train's work, dissipation and energy accumulators; "motor"/"torque");
#: "slider_accel" (the slider's acceleration along its guide; spatial mechanism only);
#: "structure" (the flexible rod's deflection and stretch, the supports' displacements; structure.mode
#: "flexible" only).
OPTIONAL_CHANNEL_GROUPS: tuple[str, ...] = ("energy", "motor", "drive_energy", "slider_accel", "structure")
#: Every channel group, in canonical order (the defaults, then the optional ones).
ALL_CHANNEL_GROUPS: tuple[str, ...] = CHANNEL_GROUPS + OPTIONAL_CHANNEL_GROUPS
#: Optional channel groups that only some engines produce: group -> engines (none at present: "structure" is
#: produced by both engines with the flexible structure).
ENGINE_ONLY_GROUPS: dict[str, tuple[str, ...]] = {}
#: Configuration names (they name default output files).
_NAME_RE = re.compile(r"[A-Za-z0-9_+=@,-][A-Za-z0-9._+=@,-]*")
#: Accelerometers of the bench (S003 Table 3).
ACCELEROMETERS: tuple[str, ...] = ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6")


def _check(cond: bool, name: str, message: str) -> None:
    if not cond:
        raise ConfigError(name, message)


def _positive(value: float, name: str, unit: str) -> None:
    _check(isinstance(value, (int, float)) and math.isfinite(value) and value > 0,
           name, f"must be a finite number > 0 [{unit}], got {value!r}")


def _finite(value: float, name: str, unit: str) -> None:
    _check(isinstance(value, (int, float)) and math.isfinite(value),
           name, f"must be a finite number [{unit}], got {value!r}")


def _choice(value: str, name: str, allowed: tuple[str, ...]) -> None:
    _check(value in allowed, name, f"must be one of {', '.join(allowed)}; got {value!r}{did_you_mean(value, allowed)}")


def _joint_table(obj: Any, name: str) -> list[tuple[str, Any]]:
    """Items of the per-joint table ``obj.<name>`` (keys checked to be joints, ConfigError
    ``<name>.<key>`` otherwise), for the caller to check the values."""
    items = list(getattr(obj, name).items())
    for key, _ in items:
        _choice(key, f"{name}.{key}", JOINTS)
    return items


def _bounded(value: Any, name: str, lo: float, hi: float, unit: str, reason: str,
             lo_open: bool = False, hi_open: bool = False) -> None:
    """A finite number in [lo, hi] (ends open as asked), else ConfigError naming ``name``, the range and
    ``reason`` (why the range is what it is: the schema states its bounds where the field is declared)."""
    ok = (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
          and (value > lo if lo_open else value >= lo) and (value < hi if hi_open else value <= hi))
    _check(ok, name, f"must lie in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
                     f"{' ' + unit if unit else ''} ({reason}), got {value!r}")


_HINTS: dict[type, dict[str, Any]] = {}


def _type_ok(value: Any, tp: Any) -> str | None:
    """None if ``value`` fits the annotation ``tp`` of a configuration field, else what it must be."""
    import collections.abc
    import dataclasses
    import numbers
    import typing

    origin = typing.get_origin(tp)
    if tp is float:
        return None if isinstance(value, numbers.Real) and not isinstance(value, bool) else "a number"
    if tp is int:
        return None if isinstance(value, numbers.Integral) and not isinstance(value, bool) else "an integer"
    if tp is bool:
        return None if isinstance(value, bool) else "true or false"
    if tp is str:
        return None if isinstance(value, str) else "a string"
    if origin is tuple:
        # a string is a sequence of characters: refused, never read as its characters
        if isinstance(value, (str, bytes, collections.abc.Mapping)) or not isinstance(value, collections.abc.Iterable):
            return "a list (array)"
        et = typing.get_args(tp)[0]
        for v in value:
            what = _type_ok(v, et)
            if what is not None:
                return f"a list of {what.removeprefix('a ').removeprefix('an ')}s"
        return None
    if origin in (collections.abc.Mapping, dict):
        if not isinstance(value, collections.abc.Mapping):
            return "a table (mapping)"
        _, vt = typing.get_args(tp)
        for v in value.values():
            what = _type_ok(v, vt)
            if what is not None:
                return f"a table of {what.removeprefix('a ').removeprefix('an ')} values"
        return None
    if dataclasses.is_dataclass(tp):
        return None if isinstance(value, tp) else f"a {tp.__name__} (table of its fields)"
    return None


def check_types(obj: Any) -> None:
    """ConfigError naming the field of the first field of the frozen dataclass ``obj`` whose value is not of
    its declared type (a number, an integer, a string, a list, a table or a section): the configuration
    built by the Python API gets the same one-line refusal as a TOML file, and a list field given as a
    string is refused instead of being read as its characters."""
    import dataclasses
    import typing

    cls = type(obj)
    hints = _HINTS.get(cls)
    if hints is None:
        hints = _HINTS[cls] = typing.get_type_hints(cls)
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        what = _type_ok(value, hints[f.name])
        if what is not None:
            raise ConfigError(f.name, f"must be {what}, got {value!r}")
