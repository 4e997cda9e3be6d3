"""The spatial slider–crank of S002 (a crank turning about x in the YOZ plane, a rod with a spherical
joint at each end, a slider along x): the geometry the bench's planar sections do not hold.

Everything else of a spatial run comes from the bench's sections, read in the spatial frame:
``bodies`` (masses, lengths, centres of mass, inertia about the centre of mass transverse to the
body), ``joints`` (``clearance_a_mm``: the base revolute joint A, a journal on the crank in a
bearing of the frame; ``clearance_b_mm`` and ``clearance_c_mm``: the crank–rod and rod–slider
spherical joints, a ball on the rod in a socket; ``pin_diameters_m``: journal and ball diameters),
``materials``, ``contact`` (law, restitution, μ0 and its regularization), ``mechanism``
(``orientation``/``gravity_mps2``: gravity in the spatial frame; ``guide_friction_n``), ``drive``
(``mode = "prescribed"``: the crank turns at the program's speed).

Spatial frame: origin at the crank pivot A, the crank axis along +x, the crank in the plane x = 0;
the crank angle θ is measured from +y about +x (B − A = r (cos θ ŷ + sin θ ẑ)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from twin.config.common import _bounded, _check, _choice, _finite, check_types
from twin.errors import ConfigError


@dataclass(frozen=True)
class Spatial:
    """Geometry of the spatial slider–crank (S002 §2.1).

    Attributes:
        enabled: run the spatial mechanism instead of the bench's planar one.
        guide_axis: direction of the slider guide: "x" (S002: the slider runs along x, normal to the
            crank's plane) or "y" (the guide in the crank's plane: the mechanism lies in the plane
            x = 0, a planar slider–crank; used to check the spatial model against the planar one).
        guide_offset_y_m: y of the guide line (the line through (0, y, z) along ``guide_axis``) [m].
            PLACEHOLDER: S002 does not give the offset between the slider line and the crank axis
            (with the guide along x through the crank axis the slider could not move: B stays at
            distance r from the x axis). Default 0: the guide in the plane XOZ, as S002 says ("the
            slider along the x axis in the XOZ plane"). Range: the guide's distance from the crank
            axis plus the crank length below the rod length (0.98 ×, checked).
        guide_offset_z_m: z of the guide line [m]. PLACEHOLDER, as ``guide_offset_y_m``: 19.554 mm,
            tuned by ``analysis/s002_guide_offset.py`` so that the ideal mechanism's peak slider
            acceleration of S002's run 1 (80 mm, 800 rpm) is the paper's 32.72 m/s² (its runs 2 and 3
            then follow to 0.04 %). Range: 0.01–0.2 m (the slider's stroke is about 2 r h / L).
    """

    enabled: bool = False
    guide_axis: str = "x"
    guide_offset_y_m: float = 0.0
    guide_offset_z_m: float = 0.019554

    def __post_init__(self) -> None:

        check_types(self)
        _check(isinstance(self.enabled, bool), "enabled", f"must be true or false, got {self.enabled!r}")
        _choice(self.guide_axis, "guide_axis", ("x", "y"))
        for name in ("guide_offset_y_m", "guide_offset_z_m"):
            value = getattr(self, name)
            _finite(value, name, "m")
            _check(abs(value) < 1.0, name, f"must lie in (-1, 1) m, got {value!r}")


# The rules of a spatial run across the bench's sections (called by BenchConfig when spatial.enabled)
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
