"""The whole-bench draws of the stability campaign (``twin study stability --bench``).

On top of a scene of :func:`twin.studies.stability.sample_scene` (whose draws come first, so a
scene's other parameters are those of the plain campaign), a bench scene draws, from the same
generator ``default_rng([S, i])``:

* the slider guide's play ``joints.clearance_guide_mm``: 0 (the ideal guide) with probability
  1/3, else uniform in GUIDE_RANGE_MM;
* the drive: ``drive.mode`` "pid" (the crank PID) or "motor" (the motor's speed loop and the
  V-belt, :mod:`twin.config.drivetrain`), equally likely, and every drive-train placeholder
  uniformly over the range its documentation asks users to explore
  (:data:`twin.config.drivetrain.EXPLORE_RANGES`; drawn for every scene, used with "motor").

Each bench scene runs in both engines (MuJoCo and the reference), one row per engine. The
energy balance of a "motor" scene takes the belt's torque on the crank as the work input (the
``crank_torque`` channel of that mode) and leaves the rotor out of ΔE: the MuJoCo twin's kinetic
energy sensor covers every body, so the rotor's ½ J ω_m² (``motor_speed``) is subtracted.
The guide's deepest penetration over its half play, ``guide_pen_over_c``, is reported per row,
not judged: it is the contact law's own deflection (the rails' stiffness is a placeholder).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from twin.config.drivetrain import EXPLORE_RANGES

#: range of the guide's play drawn [mm]
GUIDE_RANGE_MM = (0.02, 1.0)
#: probability that a bench scene has a guide clearance [-]
P_GUIDE = 2.0 / 3.0
#: the engines every bench scene runs in
ENGINES: tuple[str, ...] = ("mujoco", "reference")


def _r(x: float) -> float:
    return float(f"{float(x):.6g}")


def bench_draws(rng: np.random.Generator) -> dict[str, Any]:
    """The bench parameters of a scene (JSON-ready), drawn after the plain scene's."""
    guide = round(float(rng.uniform(*GUIDE_RANGE_MM)), 4)
    if rng.random() >= P_GUIDE:
        guide = 0.0
    mode = "motor" if rng.random() < 0.5 else "pid"
    train = {field: _r(rng.uniform(lo, hi)) for _, field, _, (lo, hi) in EXPLORE_RANGES}
    return {"clearance_guide_mm": guide, "drive_mode": mode, "drivetrain": train}


def bench_overrides(scene: dict[str, Any]) -> dict[str, Any]:
    """Configuration overrides of a bench scene (its engine: ``scene["engine"]``, MuJoCo if absent)."""
    ov: dict[str, Any] = {"joints.clearance_guide_mm": scene["clearance_guide_mm"],
                          "drive.mode": scene["drive_mode"],
                          "simulation.engine": scene.get("engine", "mujoco")}
    if scene["drive_mode"] == "motor":
        ov.update({f"drivetrain.{k}": v for k, v in scene["drivetrain"].items()})
    return ov


def rotor_energy(run: Any, cfg: Any) -> np.ndarray | float:
    """The rotor's kinetic energy ½ J ω_m² [J] the MuJoCo twin's energy sensor includes (0 otherwise)."""
    if cfg.drive.mode in ("motor", "torque") and cfg.simulation.engine == "mujoco" and "motor_speed" in run:
        w = np.asarray(run["motor_speed"], dtype=np.float64)
        return 0.5 * cfg.drivetrain.rotor_inertia_kgm2 * w * w
    return 0.0


def guide_penetration(run: Any, cfg: Any) -> float:
    """Largest penetration of the slider's ends into the guide's rails over the run [m] (from
    ``slider_y``, ``slider_tilt``: p = y_g ± a sin φ + d_off (1 − cos φ), rails at ±c)."""
    y, phi = np.asarray(run["slider_y"], dtype=float), np.asarray(run["slider_tilt"], dtype=float)
    a, c, d = cfg.joints.guide_span_m / 2.0, cfg.joints.guide_radial_m, cfg.mechanism.d_off_m
    ends = [y + s * a * np.sin(phi) + d * (1.0 - np.cos(phi)) for s in (1.0, -1.0)]
    return float(max(0.0, max(np.max(np.abs(p)) for p in ends) - c))


def label(scene: dict[str, Any]) -> str:
    """What a bench scene adds to its table row."""
    if "drive_mode" not in scene:
        return ""
    g = scene["clearance_guide_mm"]
    return f"; {scene.get('engine', 'mujoco')}, {scene['drive_mode']}, guide {g:g} mm"
