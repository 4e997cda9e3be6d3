"""Configurations as plain nested dicts (the TOML layout) and back: :func:`from_dict` with its
type checks, and the dotted-path overrides of ``--set`` (:func:`with_overrides`)."""

from __future__ import annotations

import collections.abc
import dataclasses
import numbers
import typing
from dataclasses import fields
from typing import Any, Mapping, TypeVar

from numpy import bool_ as np_bool

from twin.errors import ConfigError, unknown

#: a configuration dataclass (``BenchConfig``; this module does not import it)
C = TypeVar("C")


def _to_plain(obj: Any) -> Any:
    if dataclasses.is_dataclass(obj):
        return {f.name: _to_plain(getattr(obj, f.name)) for f in fields(obj)}
    if isinstance(obj, Mapping):
        return {k: _to_plain(v) for k, v in obj.items()}
    if isinstance(obj, (tuple, list)):
        return [_to_plain(v) for v in obj]
    return obj


# ----------------------------------------------------------------- dict -> dataclass
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _convert(value: Any, tp: Any, path: str) -> Any:
    origin = typing.get_origin(tp)
    if dataclasses.is_dataclass(tp):
        if not isinstance(value, Mapping):
            raise ConfigError(path, f"must be a table of {tp.__name__} fields, got {value!r}")
        return from_dict(tp, value, path)
    if origin in (collections.abc.Mapping, dict):
        _, vt = typing.get_args(tp)
        if not isinstance(value, Mapping):
            raise ConfigError(path, f"must be a table, got {value!r}")
        return {str(k): _convert(v, vt, f"{path}.{k}") for k, v in value.items()}
    if origin is tuple:
        args = typing.get_args(tp)
        if not isinstance(value, (list, tuple)):
            raise ConfigError(path, f"must be an array, got {value!r}")
        et = args[0]
        return tuple(_convert(v, et, f"{path}[{i}]") for i, v in enumerate(value))
    # numbers of any real type (numpy's float32, int64... from an array in the Python API) are numbers
    if tp is float:
        if isinstance(value, (bool, np_bool)) or not isinstance(value, numbers.Real):
            raise ConfigError(path, f"must be a number, got {value!r}")
        return float(value)
    if tp is int:
        if isinstance(value, (bool, np_bool)) or not isinstance(value, numbers.Integral):
            raise ConfigError(path, f"must be an integer, got {value!r}")
        return int(value)
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(path, f"must be true or false, got {value!r}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(path, f"must be a string, got {value!r}")
        return value
    raise ConfigError(path, f"unsupported type {tp!r}")  # pragma: no cover - programming error


def from_dict(cls: type, data: Mapping[str, Any], path: str = "") -> Any:
    """Build dataclass ``cls`` from a (partial) nested dict; missing fields keep defaults.

    Unknown keys, wrong types and invalid values raise :class:`ConfigError` naming the
    dotted path.
    """
    if not isinstance(data, Mapping):
        raise ConfigError(path or cls.__name__, f"must be a table of {cls.__name__} fields, got {data!r}")
    hints = _hints(cls)
    names = [f.name for f in fields(cls)]
    prefix = f"{path}." if path else ""
    for key in data:
        if key not in names:
            raise ConfigError(f"{prefix}{key}", unknown("field", key, names))
    kwargs = {}
    base = cls() if all(f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING
                        for f in fields(cls)) else None
    for f in fields(cls):
        if f.name in data:
            sub = data[f.name]
            cur = _to_plain(getattr(base, f.name)) if base is not None else None
            if isinstance(sub, Mapping) and isinstance(cur, Mapping):
                # a partial table overrides the default sub-config field by field (a table given for
                # a number is left to _convert, which refuses it naming the field)
                sub = _deep_merge(cur, sub)
            kwargs[f.name] = _convert(sub, hints[f.name], f"{prefix}{f.name}")
    try:
        return cls(**kwargs)
    except ConfigError as err:  # raised by cls.__post_init__ with a local field name
        raise ConfigError(f"{prefix}{err.field}", err.message) from None
    except TypeError as err:
        raise ConfigError(path or cls.__name__, f"missing fields: {err}") from None


def _deep_merge(a: Mapping[str, Any], b: Mapping[str, Any]) -> dict[str, Any]:
    out = dict(a)
    for k, v in b.items():
        out[k] = _deep_merge(out[k], v) if isinstance(v, Mapping) and isinstance(out.get(k), Mapping) else v
    return out


def with_overrides(cfg: C, overrides: Mapping[str, Any]) -> C:
    """Apply dotted-path overrides (``{"joints.clearance_b_mm": 0.1}``) to a configuration
    (a :class:`~twin.config.BenchConfig`) and re-validate."""
    if not isinstance(overrides, Mapping):
        raise TypeError(f"overrides: must be a mapping of dotted field names to values, got {type(overrides).__name__}")
    data = _to_plain(cfg)
    for dotted, value in overrides.items():
        if not isinstance(dotted, str):
            raise TypeError(f"overrides: keys must be dotted field names (str), got {dotted!r}")
        keys = dotted.split(".")
        node = data
        for k in keys[:-1]:
            if not isinstance(node.get(k), dict):
                raise ConfigError(dotted, unknown(f"section {k!r}", k, node))
            node = node[k]
        # a key the node lacks is left to from_dict: an entry of a per-joint table (joints.pin_diameters_m.B, absent
        # until set) is a field, a key unknown to a section is refused there naming it and the allowed fields
        node[keys[-1]] = list(value) if isinstance(value, tuple) else value
    return from_dict(type(cfg), data)
