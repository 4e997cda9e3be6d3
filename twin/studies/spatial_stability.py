"""The spatial scene family of the stability campaign (``twin study stability --family spatial``).

Scene ``i`` of seed ``S`` draws from ``numpy.random.default_rng([S, i, 2])`` (:func:`sample_scene`), over
the s002 preset (its 5 µs step):

* radial clearance at A, B and C, each log-uniform in [0.01, 1.0] mm (diametral 0.02–2 mm: the bench's
  catalogue range and S002's 0.1–0.7 mm radial, and beyond);
* crank length uniform in [80, 120] mm (its placeholder mass distribution with it), crank speed uniform
  in [800, 1500] rpm, friction coefficient μ0 uniform in [0, 0.2], a random initial crank angle;
* duration uniform in the campaign's range.

Each scene runs in both engines (:func:`run_scene`). Metrics per engine: ``diverged`` (an engine error,
NaN/Inf in a channel, a short run), ``pen_over_c`` per joint, the tracking error of the crank. A scene
passes when neither engine diverged and pen/c ≤ the campaign's limit in MuJoCo; the reference's pen/c
tells an exceedance the converged law makes too ("physical", as at the smallest clearances under kN
loads) from the twin's ("numerical"). The scene dict keeps the bench family's keys (``clearance_b_mm``,
``orientation``, ``drive``, ``timestep_s``...) so the campaign's tables and plots take it unchanged.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np

#: radial clearance range [mm], log-uniform
RADIAL_MM = (0.01, 1.0)
CRANK_M = (0.08, 0.12)
CRANK_RPM = (800.0, 1500.0)
MU0 = (0.0, 0.2)
#: the twin's pen/c "agrees" with the reference's within this factor (the bench family's
#: ``twin.studies.stability.REFERENCE_AGREEMENT``; not imported: that module imports this one)
REFERENCE_AGREEMENT = 1.25


def sample_scene(seed: int, index: int, duration_range_s: tuple[float, float] = (0.3, 1.0)) -> dict[str, Any]:
    """Parameters of spatial scene ``index`` of seed ``seed`` (JSON-ready; module docstring)."""
    from twin.config import named_preset

    rng = np.random.default_rng([seed, index, 2])
    r4 = lambda x: round(float(x), 4)  # noqa: E731
    radial = [r4(math.exp(rng.uniform(math.log(RADIAL_MM[0]), math.log(RADIAL_MM[1])))) for _ in range(3)]
    crank = r4(rng.uniform(*CRANK_M))
    rpm = r4(rng.uniform(*CRANK_RPM))
    mu = r4(rng.uniform(*MU0))
    phi0 = r4(rng.uniform(0.0, 2.0 * math.pi))
    duration = r4(rng.uniform(*duration_range_s))
    cfg = named_preset("s002")
    return {"family": "spatial", "index": index, "seed": seed,
            "clearance_a_mm": 2 * radial[0], "clearance_b_mm": 2 * radial[1], "clearance_c_mm": 2 * radial[2],
            "crank_length_m": crank, "mu0": mu, "orientation": cfg.mechanism.orientation,
            "drive": {"program": "constant", "motor_rpm": rpm, "ramp_s": 0.0},
            "initial_encoder_angle_rad": phi0, "timestep_s": cfg.simulation.timestep_s,
            "contact_stiffness_scale": 1.0, "contact_damping_scale": 1.0, "duration_s": duration, "settle_s": 0.0}


def scene_config(scene: dict[str, Any], engine: str) -> Any:
    """Configuration of a spatial scene for ``engine``."""
    from twin.config import named_preset

    base = named_preset("s002")
    r = scene["crank_length_m"]
    return base.replace(**{
        "name": f"stability_spatial_s{scene['seed']}_{scene['index']:05d}",
        "joints.clearance_a_mm": scene["clearance_a_mm"], "joints.clearance_b_mm": scene["clearance_b_mm"],
        "joints.clearance_c_mm": scene["clearance_c_mm"], "bodies.crank.length_m": r, "bodies.crank.x_g_m": r / 2,
        "bodies.crank.inertia_kgm2": base.bodies.crank.mass_kg * r * r / 12, "contact.mu0": scene["mu0"],
        "drive.crank_rpm": scene["drive"]["motor_rpm"],
        "drive.initial_encoder_angle_rad": scene["initial_encoder_angle_rad"],
        "simulation.engine": engine, "simulation.duration_s": scene["duration_s"],
        "sensors.channels": ["crank", "slider", "joints", "drive", "slider_accel"]})


def _engine_metrics(scene: dict[str, Any], engine: str, pen_limit: float) -> dict[str, Any]:
    from twin.errors import SimulationError
    from twin.simulation import simulate_run

    cfg = scene_config(scene, engine)
    t0 = time.perf_counter()
    try:
        run = simulate_run(cfg)
    except SimulationError as err:
        return {"diverged": True, "error": str(err), "joints": {}, "max_pen_over_c": float("nan"),
                "wall_s": time.perf_counter() - t0, "passed": False}
    nonfinite = [k for k, c in run.channels.items() if not np.all(np.isfinite(c.data))]
    expected = int(round(cfg.duration_s * run.rate_hz))
    pen = {}
    for j in cfg.joints.clearance_joints:
        p = float(np.nanmax(run[f"pen_{j}"]))
        pen[j] = {"max_pen_m": p, "c_m": cfg.joints.radial_m(j), "pen_over_c": p / cfg.joints.radial_m(j),
                  "max_fn_N": float(np.nanmax(run[f"fn_{j}"]))}
    err = np.abs(run["crank_angle"] - run["theta_ref"])
    out = {"diverged": bool(nonfinite or run.n < expected), "error": None, "nonfinite_channels": nonfinite,
           "warnings": {}, "samples": run.n, "samples_expected": expected, "joints": pen,
           "max_pen_over_c": max((v["pen_over_c"] for v in pen.values()), default=0.0),
           "tracking_max_rad": float(np.max(err)), "tracking_rms_rad": float(np.sqrt(np.mean(err ** 2))),
           "wall_s": float(run.meta.get("wall_s", 0.0))}
    out["passed"] = bool(not out["diverged"] and out["max_pen_over_c"] <= pen_limit)
    return out


def run_scene(scene: dict[str, Any], trace_dir: Path | None = None, pen_limit: float = 0.25) -> dict[str, Any]:
    """Run a spatial scene in MuJoCo and in the reference; the campaign's metrics (module docstring):
    MuJoCo's at the top level, the reference's under ``"reference_run"``."""
    mj = _engine_metrics(scene, "mujoco", pen_limit)
    ref = _engine_metrics(scene, "reference", pen_limit)
    met = dict(mj)
    met["reference_run"] = ref
    met["diverged"] = bool(mj["diverged"] or ref["diverged"])
    if not mj["diverged"] and mj["max_pen_over_c"] > pen_limit and not ref["diverged"]:
        over = [j for j, v in mj["joints"].items() if v["pen_over_c"] > pen_limit]
        pm = {j: mj["joints"][j]["pen_over_c"] for j in over}
        pr = {j: ref["joints"][j]["pen_over_c"] for j in over}
        met["reference"] = {"pen_over_c": {j: v["pen_over_c"] for j, v in ref["joints"].items()},
                            "cause": "physical" if all(pr[j] > pen_limit for j in over) else "numerical",
                            "agrees": bool(all(pm[j] <= REFERENCE_AGREEMENT * pr[j] for j in over))}
    met["passed"] = bool(not met["diverged"] and mj["max_pen_over_c"] <= pen_limit)
    met["wall_s"] = mj["wall_s"] + ref["wall_s"]
    return met
