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
#: "slider_accel" (the slider's acceleration along its guide; spatial mechanism only).
OPTIONAL_CHANNEL_GROUPS: tuple[str, ...] = ("energy", "motor", "drive_energy", "slider_accel")
#: Every channel group, in canonical order (the defaults, then the optional ones).
ALL_CHANNEL_GROUPS: tuple[str, ...] = CHANNEL_GROUPS + OPTIONAL_CHANNEL_GROUPS
#: Optional channel groups that only some engines produce: group -> engines.
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
