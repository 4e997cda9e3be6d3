"""Presets: configurations of the papers' tests and mechanisms, as TOML data files shipped with the
package beside this module (each value's source in the file's comments).

* ``table4.toml``: the twelve tests of S003 Table 4 (``[test.N]`` tables), :func:`preset`;
* ``s001.toml``, ``s000.toml``, ``s004.toml``, ``s002.toml`` (spatial): the mechanisms of the other seed papers,
  :func:`named_preset`;
* ``torque_release.toml``, ``torque_release_protocol.toml``: the bench's planned torque-driven
  release test and its three-speed protocol variant (drive train, ``drive.mode = "torque"``),
  :func:`named_preset`.

A file is a partial configuration: the fields it gives, over the bench's defaults (as
:func:`twin.config.load_config` reads a file of the user's).
"""

from __future__ import annotations

import copy
import functools
import tomllib
import typing
from importlib import resources
from typing import Any

from twin.config.bench import BenchConfig
from twin.config.convert import from_dict
from twin.errors import ConfigError, did_you_mean


@functools.lru_cache(maxsize=None)
def _read(name: str) -> dict[str, Any]:
    """Parsed preset file ``name`` (``table4``, ``s001``...) of this folder."""
    return tomllib.loads(resources.files(__name__).joinpath(f"{name}.toml").read_text(encoding="utf-8"))


def _table4() -> dict[int, dict[str, Any]]:
    return {int(k): v for k, v in _read("table4")["test"].items()}


#: S003 Table 4: test id -> (diametral clearance B [mm], C [mm], motor speed [rpm]) (read from table4.toml).
TABLE4: dict[int, tuple[float, float, float]] = {
    i: (t["joints"]["clearance_b_mm"], t["joints"]["clearance_c_mm"], t["drive"]["motor_rpm"])
    for i, t in _table4().items()
}


def preset(test_id: int) -> BenchConfig:
    """Configuration of S003 Table 4 test ``test_id`` (1–12): clearances and a constant
    motor speed, y vertical. The 38 s protocol with the same clearances is
    ``preset(i).replace(**{"drive.program": "protocol"})``."""
    if isinstance(test_id, bool) or not isinstance(test_id, int) or test_id not in TABLE4:
        raise ConfigError("--test", f"must be a Table 4 test id 1..12, got {test_id!r}")
    return _test(test_id)


# built once: the configurations are frozen (as BenchConfig()'s default sections are shared)
@functools.lru_cache(maxsize=None)
def _test(test_id: int) -> BenchConfig:
    return from_dict(BenchConfig, copy.deepcopy(_table4()[test_id]))


@functools.lru_cache(maxsize=None)
def _named(name: str) -> BenchConfig:
    return from_dict(BenchConfig, copy.deepcopy(_read(name)))


#: Named presets of the other mechanisms of the seed papers and of the bench's torque-release test:
#: name -> builder (reads ``NAME.toml``).
NAMED_PRESETS: dict[str, typing.Callable[[], BenchConfig]] = {
    name: functools.partial(_named, name)
    for name in ("s001", "s000", "s004", "s002", "torque_release", "torque_release_protocol")
}


def named_preset(name: str, field_name: str = "--preset") -> BenchConfig:
    """Configuration of a paper's mechanism (``--preset NAME``, ``preset = "NAME"`` in TOML):
    ``s001`` (S001's rig), ``s000`` (S000's Flores slider–crank), ``s004`` (S004's large
    mechanism), ``s002`` (S002's spatial slider–crank), ``torque_release`` (the bench's torque-driven release test),
    ``torque_release_protocol`` (three spin-ups and coast-downs); the sources of their numbers are in the files ``NAME.toml`` of this folder."""
    if not isinstance(name, str) or name.lower() not in NAMED_PRESETS:
        raise ConfigError(field_name, f"must be one of {', '.join(NAMED_PRESETS)}, got {name!r}"
                                      f"{did_you_mean(name, NAMED_PRESETS)}")
    return NAMED_PRESETS[name.lower()]()
