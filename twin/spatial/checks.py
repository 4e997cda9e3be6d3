"""Configuration rules of a spatial run (called by :class:`twin.config.BenchConfig` when
``spatial.enabled``); kept out of :mod:`twin.config` so that the bench's schema stays planar."""

from __future__ import annotations

import math
from typing import Any

from twin.errors import ConfigError


def check_spatial(cfg: Any) -> None:
    """Raise :class:`~twin.errors.ConfigError` naming the field if ``cfg`` (a
    :class:`~twin.config.BenchConfig` with ``spatial.enabled``) cannot be run as the spatial
    mechanism."""
    if cfg.drive.mode != "prescribed":
        raise ConfigError("drive.mode", "must be \"prescribed\" for the spatial mechanism (S002 turns its crank "
                                        f"at a constant speed; no crank PID is modelled there), got {cfg.drive.mode!r}")
    if cfg.drive.program != "constant":
        raise ConfigError("drive.program", "must be \"constant\" for the spatial mechanism, "
                                           f"got {cfg.drive.program!r}")
    for group in ("accel", "energy"):
        if group in cfg.sensors.channels:
            raise ConfigError("sensors.channels", f"the group {group!r} is not available for the spatial mechanism "
                                                  "(it has no accelerometer mounts; its slider's acceleration is "
                                                  "the group 'slider_accel'); remove it")
    if cfg.simulation.engine == "mujoco" and cfg.mujoco.integrator != "Euler":
        raise ConfigError("mujoco.integrator", "must be \"Euler\" for the spatial mechanism (the prescribed drive "
                                               f"needs it), got {cfg.mujoco.integrator!r}")
    sp, r, L = cfg.spatial, cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    # the rod must reach the guide line from every crank position, with margin for the clearances
    if sp.guide_axis == "x":
        reach = math.hypot(sp.guide_offset_y_m, sp.guide_offset_z_m) + r
    else:
        reach = abs(sp.guide_offset_z_m) + r
    if reach >= 0.98 * L:
        raise ConfigError("spatial.guide_offset_z_m",
                          f"puts the guide out of the rod's reach: crank length + guide distance {reach:.4g} m must "
                          f"stay below 0.98 × rod length ({0.98 * L:.4g} m)")
