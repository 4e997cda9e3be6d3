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
        raise ConfigError("test", f"must be a Table 4 test id 1..12, got {test_id!r}")
    return _test(test_id)


# built once: the configurations are frozen (as BenchConfig()'s default sections are shared)
@functools.lru_cache(maxsize=None)
def _test(test_id: int) -> BenchConfig:
    return from_dict(BenchConfig, copy.deepcopy(_table4()[test_id]))


@functools.lru_cache(maxsize=None)
def _named(name: str) -> BenchConfig:
    return from_dict(BenchConfig, copy.deepcopy(_read(name)))


#: Named presets of the other mechanisms of the seed papers and of the bench's torque-release test:
#: name -> builder (reads ``NAME.toml``): every TOML file of this folder but table4.toml, so a new
#: file is a new preset.
NAMED_PRESETS: dict[str, typing.Callable[[], BenchConfig]] = {
    name: functools.partial(_named, name)
    for name in sorted(p.name[:-len(".toml")] for p in resources.files(__name__).iterdir()
                       if p.name.endswith(".toml") and p.name != "table4.toml")
}

#: One line per named preset, for ``--preset``'s help and the documentation (a test checks that every
#: preset file has one and that the README, docs/commands.md and ``twin.preset`` name every preset).
PRESET_SUMMARIES: dict[str, str] = {
    "s000": "S000's Flores slider-crank at 5000 rpm, a radial clearance at C",
    "s001": "S001's rig, 0.5 mm radial clearance at C, 0 -> 300 rpm in 0.2 s",
    "s002": "S002's spatial slider-crank with spherical clearance joints, run 1 of its Taguchi L27",
    "s004": "S004's steel mechanism, 0.5 mm radial clearance at B, prescribed 30 rad/s, ADAMS IMPACT contact",
    "torque_release": "the bench's torque-driven release test: test 12's clearances, 1.2 N m on the motor for "
                      "0.5 s, then coast-down through the belt, 10 s",
    "torque_release_protocol": "three spin-ups of increasing length at 1.2 N m, each released, 34 s",
}


def named_preset(name: str, field_name: str = "preset") -> BenchConfig:
    """Configuration of a named preset (``--preset NAME``, ``preset = "NAME"`` in TOML), one of
    :data:`NAMED_PRESETS` (described in :data:`PRESET_SUMMARIES`): ``s000`` (S000's Flores
    slider–crank), ``s001`` (S001's rig), ``s002`` (S002's spatial slider–crank), ``s004`` (S004's
    large mechanism), ``torque_release`` (the bench's torque-driven release test),
    ``torque_release_protocol`` (three spin-ups and coast-downs); the sources of their numbers are in
    the files ``NAME.toml`` of this folder."""
    if not isinstance(name, str) or name.lower() not in NAMED_PRESETS:
        raise ConfigError(field_name, f"must be one of {', '.join(NAMED_PRESETS)}, got {name!r}"
                                      f"{did_you_mean(name, NAMED_PRESETS)}")
    return NAMED_PRESETS[name.lower()]()
