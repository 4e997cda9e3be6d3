"""Reading configurations: TOML files (:func:`load_config`, which may start from a preset) and the
copies stored in run files (:func:`config_from_toml`, which migrates the layouts of earlier versions)."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any, Mapping

from twin.config.bench import BenchConfig
from twin.config.convert import _deep_merge, from_dict
from twin.config.presets import named_preset, preset
from twin.errors import ConfigError, TwinError
from twin.util import toml_loads


def load_config(path: str | Path) -> BenchConfig:
    """Read a TOML configuration file (partial files override the defaults).

    A file with ``drive.program = "trace"`` and no duration (or 0) keeps ``simulation.duration_s = 0``,
    "the trace's length": the run fills it in when it reads the trace
    (:func:`twin.tracefile.with_trace_duration`); loading a configuration opens no data file.
    """
    import os

    if isinstance(path, bool) or not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path: must be a path (str or os.PathLike), got {type(path).__name__}")
    if not str(path):
        raise ConfigError("path", "is empty; give a TOML configuration file")
    from twin.util import read_input_bytes, show

    p = Path(path)
    try:
        raw = read_input_bytes(p, "path")  # a regular file of bounded size: a FIFO or /dev/zero never hangs
    except ConfigError:
        raise
    except TwinError as err:
        raise ConfigError("path", err.message or str(err)) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ConfigError("path", f"{show(p)} is not a UTF-8 text (TOML) file: byte {err.start} "
                                  f"is {raw[err.start:err.start + 1]!r}") from None
    try:
        data = toml_loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ConfigError("path", f"{show(p)} is not valid TOML: {err}") from None
    base: dict[str, Any] = {}
    if "test" in data and "preset" in data:
        raise ConfigError("preset", "cannot be combined with test = N: give one starting point")
    if "test" in data:  # a config may start from a Table 4 preset: test = 6
        test = data.pop("test")
        base = preset(test).to_dict()
    if "preset" in data:  # or from a paper's mechanism: preset = "s001"
        base = named_preset(data.pop("preset"), "preset").to_dict()
    merged = _deep_merge(base or BenchConfig().to_dict(), data)
    drive, sim = merged.get("drive"), merged.get("simulation")
    own_sim = data.get("simulation") if isinstance(data.get("simulation"), Mapping) else {}
    if (isinstance(drive, Mapping) and isinstance(sim, Mapping) and drive.get("program") == "trace"
            and "duration_s" not in own_sim):
        merged["simulation"] = {**sim, "duration_s": 0.0}  # the trace's length (a preset's duration does not apply)
    return from_dict(BenchConfig, merged)


def config_from_toml(text: str) -> BenchConfig:
    """Parse a configuration from TOML text (e.g. the copy stored in a run file).

    Files written by earlier versions are migrated: ``mujoco.impact_speed_floor_mps`` is now
    ``contact.impact_speed_floor_mps`` (one floor for both engines); ``mujoco.contact_source =
    "calibration"`` (the retired calibration table) reads as "law" and the retired
    ``mujoco.contact_damping`` is dropped (the native law carries its own damping).
    """
    if not isinstance(text, str):
        raise TypeError(f"text: must be the TOML text (str), got {type(text).__name__}")
    try:
        data = toml_loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ConfigError("config", f"stored configuration is not valid TOML: {err}") from None
    mj = data.get("mujoco")
    if isinstance(mj, dict) and "impact_speed_floor_mps" in mj:
        data.setdefault("contact", {}).setdefault("impact_speed_floor_mps", mj.pop("impact_speed_floor_mps"))
    if isinstance(mj, dict):
        mj.pop("contact_damping", None)
        if mj.get("contact_source") == "calibration":
            mj["contact_source"] = "law"
    return from_dict(BenchConfig, data)
