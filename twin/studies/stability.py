"""Numerical-stability stress test of the MuJoCo twin (``twin study stability``).

Method
------
``N`` randomized scenes are drawn; scene ``i`` of seed ``S`` depends on ``(S, i)`` only
(``numpy.random.default_rng([S, i])``), so a campaign can be extended or one scene re-run alone.
Each scene draws (:func:`sample_scene`):

* clearances: which joints have one ("B", "C" or "both", equally likely) and, for each, a
  catalogue diametral value (S003 §2.2.1, uniformly); the other joint is ideal;
* orientation: the vertical bench axis, x, y or z (equally likely);
* drive program (equally likely): ``constant`` (a motor speed uniform in [100, 800] rpm with a
  random cosine ``ramp_s``), ``startstop`` (the ``trace`` program on a generated crank-angle
  trace: rest, accelerate, hold, brake to rest, stop, restart to a second speed, hold) and
  ``protocol`` (the paper's three-speed program, shortened through ``protocol_hold_s`` and
  ``protocol_stop_s`` to the scene's duration, three random speeds); a random initial crank
  angle;
* timestep: 1e-5 s (half the scenes), 5e-6 s or 2e-5 s (a quarter each); the output rate is
  100 kHz, or one sample per step (50 kHz) for 2e-5 s, set explicitly;
* contact parameters within the calibrated uncertainty: ``mujoco.contact_stiffness_scale``
  uniform in [0.8, 1.2], ``mujoco.contact_damping_scale`` uniform in [0.7, 1.3];
* duration uniform in [0.3, 1.0] s (``--quick``) or [0.5, 3.0] s (full campaign).

Metrics per scene (:func:`scene_metrics`):

* ``diverged``: the engine raised (NaN/Inf in the state or sensors, time not reached), or a
  channel holds NaN/Inf, or MuJoCo raised a warning (``mjData.warning``, exposed by the engine
  as ``run.meta["warnings"]``), or the run is shorter than asked;
* ``pen_over_c``: max penetration / radial clearance c = diametral/2 per clearance joint;
* tracking: max and RMS of |crank_angle − theta_ref| from ``settle_s`` (the end of the first
  speed ramp) to the end [rad];
* energy balance. With W_in(t) = ∫ τ ω dt (the PID's work on the crank, trapezoidal rule on
  the output samples), D_guide(t) = ∫ F_guide |v_slider| dt (the guide's dry friction at its
  nominal force) and E = kinetic + gravitational potential energy (MuJoCo's energy sensors,
  the optional channel group ``energy``), the *residual* is

      R(t) = W_in(t) − D_guide(t) − (E(t) − E(0)).

  R lumps together everything the balance does not model explicitly: the energy dissipated
  by the clearance contacts' damping and by the joints' regularized Coulomb friction (both
  ≥ 0), the elastic energy held in the soft contacts at time t (≥ 0), the guide friction's
  shortfall at velocity reversals (its soft frictionloss acts below the nominal force at very
  low speed; ≥ 0 up to the overestimate of D_guide), the soft loop-closure constraint of an
  ideal joint C, and the integrator's and the quadrature's energy error (either sign).
  Physically R ≥ 0 up to the numerical error. It is reported relative to the positive work
  input W+ = ∫ max(τ ω, 0) dt: ``residual_rel`` = R(end)/W+ and ``residual_min_rel`` =
  min_t R(t)/W+. ``energy_created`` flags a scene where min_t R(t) < −ENERGY_TOL · W+, i.e.
  the model generated more than ENERGY_TOL of the work input. On an ideal scene (no contact)
  R is the integration error alone (tests: |R|/W+ < 1e-3).

A scene *passes* when it did not diverge and pen/c ≤ PEN_LIMIT at each clearance joint; the
study's exit status is 0 when all pass. ``energy_created`` is reported, not a failure. A scene
over PEN_LIMIT is re-run by the reference engine (R-matrix, the same contact law) at its converged
step (REFERENCE_TIMESTEP_S = 1e-6 s) under the twin's perturbed law: the twin's stiffness factor
becomes the reference's ``contact.stiffness_scale``, and its damping factor s becomes the
restitution e' with χ(e') = s χ(e) (hysteresis laws: LN, Hunt–Crossley, Flores; the other
laws, and a factor no restitution reaches — LN's χ is at most 3/4 —, keep the configured
damping: ``damping_carried`` false). ``metrics["reference"]``: the converged pen/c per
joint, ``agrees`` (the twin's pen/c within REFERENCE_AGREEMENT = 1.25 times the reference's at each
exceeding joint) and ``cause``: ``"physical"`` where the converged reference exceeds PEN_LIMIT
too at each exceeding joint (the law's own deflection: at the 0.02 mm catalogue clearance,
c = 10 µm, a 1.5 kN impact already deflects 2.5 µm; no integrator can pass such a scene), else
``"numerical"`` (the twin's step overshoots the converged penetration past the limit). Either way
the scene still fails.

Outputs (``--out DIR``): ``stability.json`` (per scene: parameters and metrics; summary),
``stability.md`` (table and summary), ``stability.png`` (histograms of pen/c and of the
residual), all written atomically.
"""

from __future__ import annotations

import io
import math
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np

from twin.config import CATALOGUE_DIAMETRAL_MM, ORIENTATIONS, BenchConfig, preset
from twin.errors import ConfigError, TwinError
from twin.studies.stability_summary import StabilitySummary, Stats  # noqa: F401 (public here too)
from twin.studies.stability_bench import ENGINES, bench_draws, bench_overrides, guide_penetration, label, rotor_energy
from twin.tracefile import DriveInputs
from twin.provenance import figure_metadata
from twin.util import atomic_write_bytes, atomic_write_json, atomic_write_text

#: Largest admissible penetration / radial clearance [-].
PEN_LIMIT = 0.25
#: Tolerance of the energy-created flag, relative to the positive work input [-].
ENERGY_TOL = 0.01
#: Programs the sampler draws.
PROGRAMS: tuple[str, ...] = ("constant", "startstop", "protocol")
#: Timesteps [s] and their probabilities.
TIMESTEPS: tuple[float, ...] = (1e-5, 5e-6, 2e-5)
TIMESTEP_P: tuple[float, ...] = (0.5, 0.25, 0.25)
#: Motor speed range [rpm].
RPM_RANGE = (100.0, 800.0)
#: Contact-parameter ranges (calibrated uncertainty) [-].
STIFFNESS_SCALE = (0.8, 1.2)
DAMPING_SCALE = (0.7, 1.3)
#: Sample rate of generated start/stop traces [Hz].
TRACE_RATE_HZ = 10_000.0
#: Step of the reference engine that re-runs a scene exceeding PEN_LIMIT [s]: its converged step
#: (the issue-15 table's: penetration within 0.3 % of h = 1e-6 s's at h = 1e-5 s)
REFERENCE_TIMESTEP_S = 1e-6
#: A twin pen/c within this factor of the reference's counts as agreeing with it [-].
REFERENCE_AGREEMENT = 1.25
#: Channel groups a scene computes.
CHANNELS = ("crank", "slider", "joints", "drive", "energy")


@dataclass(frozen=True)
class StudySettings:
    """What a campaign runs.

    Attributes:
        scenes: number of scenes N (≥ 1).
        seed: seed S (≥ 0); scene i draws from ``default_rng([S, i])``.
        duration_range_s: range of the scenes' simulated durations [s].
        bench: also draw the guide clearance and the drive train and run every scene in both
            engines (:mod:`twin.studies.stability_bench`).
        family: "bench" (the planar twin's scenes, this module) or "spatial" (S002's mechanism in both
            engines, :mod:`twin.studies.spatial_stability`).
        structure: every scene with the flexible structure (``structure.mode = "flexible"``), its placeholders
            drawn uniformly over their documented ranges (:data:`twin.config.structure.EXPLORE_RANGES`) from the
            scene's own generator ``default_rng([seed, index, 43])`` (the other draws stay those of the rigid
            campaign), and run in both engines (one row each).
        first: index of the first scene (≥ 0): the campaign runs scenes ``first`` … ``first + scenes − 1`` of its
            seed, so a long campaign can run in parts (:func:`merge_results` joins them).
    """

    scenes: int = 500
    seed: int = 1
    duration_range_s: tuple[float, float] = (0.5, 3.0)
    bench: bool = False
    family: str = "bench"
    structure: bool = False
    first: int = 0

    def __post_init__(self) -> None:
        if isinstance(self.scenes, bool) or not isinstance(self.scenes, int) or not 1 <= self.scenes <= MAX_SCENES:
            raise ConfigError("scenes", f"must be an integer in [1, {MAX_SCENES}], got {self.scenes!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigError("seed", f"must be an integer >= 0, got {self.seed!r}")
        if self.family not in ("bench", "spatial"):
            raise ConfigError("family", f"must be bench or spatial, got {self.family!r}")
        if isinstance(self.first, bool) or not isinstance(self.first, int) or self.first < 0:
            raise ConfigError("first", f"must be an integer >= 0, got {self.first!r}")
        lo, hi = (tuple(self.duration_range_s) + (None, None))[:2]
        if (len(self.duration_range_s) != 2 or not all(isinstance(x, (int, float)) and math.isfinite(x)
                                                       for x in (lo, hi)) or not 0 < lo <= hi <= MAX_DURATION_S):
            raise ConfigError("durations", f"must be two numbers LO HI with 0 < LO <= HI <= {MAX_DURATION_S:g} [s] (a "
                              "scene's speed ramp, up to 0.4 of its duration, stays within the drive's 10 s), got "
                              f"{list(self.duration_range_s)!r}")
        if self.structure and (self.bench or self.family != "bench"):
            raise ConfigError("structure", "draws the flexible structure on the planar twin's plain scenes; it "
                              "cannot be combined with bench (guide clearance and motor drive are not available "
                              "with the flexible structure) or the spatial family")


#: the most scenes a campaign draws (the documented campaign has 500; more only fills the memory with scenes to run)
MAX_SCENES = 100_000
#: the longest scene [s]: the constant program's ramp is drawn up to 0.4 of the duration, and drive.ramp_s <= 10 s
MAX_DURATION_S = 20.0


def quick(scenes: int = 20, seed: int = 1, bench: bool = False) -> StudySettings:
    """The CI version: short scenes (0.3–1.0 s)."""
    return StudySettings(scenes=scenes, seed=seed, duration_range_s=(0.3, 1.0), bench=bench)


# ----------------------------------------------------------------------- sampler
def sample_scene(seed: int, index: int, duration_range_s: tuple[float, float] = (0.5, 3.0),
                 bench: bool = False, structure: bool = False) -> dict[str, Any]:
    """Parameters of scene ``index`` of seed ``seed`` (JSON-ready; see module docstring); with
    ``bench`` the whole-bench draws follow (:func:`twin.studies.stability_bench.bench_draws`).

    Durations and program times are rounded to 0.1 ms so they fall on the output grid.
    """
    rng = np.random.default_rng([seed, index])
    r4 = lambda x: round(float(x), 4)  # noqa: E731
    which = ("B", "C", "both")[rng.integers(3)]
    cb = float(rng.choice(CATALOGUE_DIAMETRAL_MM)) if which in ("B", "both") else 0.0
    cc = float(rng.choice(CATALOGUE_DIAMETRAL_MM)) if which in ("C", "both") else 0.0
    orientation = ORIENTATIONS[rng.integers(len(ORIENTATIONS))]
    program = PROGRAMS[rng.integers(len(PROGRAMS))]
    timestep = float(TIMESTEPS[rng.choice(len(TIMESTEPS), p=TIMESTEP_P)])
    ks = r4(rng.uniform(*STIFFNESS_SCALE))
    cs = r4(rng.uniform(*DAMPING_SCALE))
    duration = r4(rng.uniform(*duration_range_s))
    phi0 = r4(rng.uniform(0.0, 2.0 * math.pi))
    drive: dict[str, Any] = {"program": program}
    if program == "constant":
        drive["motor_rpm"] = r4(rng.uniform(*RPM_RANGE))
        drive["ramp_s"] = r4(rng.uniform(0.05, 0.4) * duration)
        settle = drive["ramp_s"]
    elif program == "protocol":
        stop = r4(rng.uniform(0.04, 0.08) * duration)
        hold = r4((duration - 4 * stop) / 3)
        drive["protocol_rpm"] = [r4(rng.uniform(*RPM_RANGE)) for _ in range(3)]
        drive["protocol_stop_s"] = stop
        drive["protocol_hold_s"] = hold
        drive["ramp_s"] = r4(rng.uniform(0.2, 0.5) * hold)
        duration = r4(4 * stop + 3 * hold)
        settle = r4(stop + drive["ramp_s"])
    else:  # start/stop: fractions of the duration for rest, ramps, holds, stop
        f = rng.uniform(0.08, 0.14, size=4)  # ramp up, brake, restart ramp; stop
        rest = r4(0.03 * duration)
        up, down, up2, stop = (r4(x * duration) for x in f)
        free = duration - rest - up - down - stop - up2
        hold1 = r4(free * rng.uniform(0.3, 0.6))
        drive["segments"] = {"rest_s": rest, "ramp_up_s": up, "hold_s": hold1, "brake_s": down, "stop_s": stop,
                             "ramp_up2_s": up2}
        drive["motor_rpm"] = [r4(rng.uniform(*RPM_RANGE)) for _ in range(2)]
        settle = r4(rest + up)
    scene = {"index": index, "seed": seed, "clearance_b_mm": cb, "clearance_c_mm": cc, "orientation": orientation,
             "drive": drive, "initial_encoder_angle_rad": phi0, "timestep_s": timestep,
             "contact_stiffness_scale": ks, "contact_damping_scale": cs, "duration_s": duration, "settle_s": settle}
    if bench:
        scene.update(bench_draws(rng))
    if structure:
        scene["structure"] = structure_draws(seed, index, timestep, cb, cc)
    return scene


def structure_draws(seed: int, index: int, timestep_s: float, clearance_b_mm: float = 0.0,
                    clearance_c_mm: float = 0.0) -> dict[str, float]:
    """The flexible structure's placeholders of a scene, uniform over their documented ranges, from the scene's own
    generator; a draw the configuration refuses at this timestep and with the scene's clearances at B and C (a mount
    at or above half the output rate, a mode beyond the explicit step's stability margin — with a clearance, the
    free rod's too) is drawn again (at most 100 times), so every scene is one a user could run."""
    from twin.config.structure import EXPLORE_RANGES

    srng = np.random.default_rng([seed, index, 43])
    rate = min(100_000.0, 1.0 / timestep_s)
    for _ in range(100):
        draw = {field: float(f"{srng.uniform(lo, hi):.6g}") for _, field, _, (lo, hi) in EXPLORE_RANGES}
        try:
            preset(1).replace(**{"structure.mode": "flexible", "simulation.timestep_s": timestep_s,
                                 "sensors.output_rate_hz": rate, "joints.clearance_b_mm": clearance_b_mm,
                                 "joints.clearance_c_mm": clearance_c_mm,
                                 **{f"structure.{k}": v for k, v in draw.items()}})
        except ConfigError:
            continue
        return draw
    raise TwinError(f"stability scene {index} (seed {seed}): no runnable structure in 100 draws at h = {timestep_s:g} s")


def startstop_trace(scene: dict[str, Any], belt_ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """Encoder trace (t [s], angle [rad]) of a start/stop scene: rest, cosine ramp to the first
    speed, hold, cosine brake to rest, stop, cosine ramp to the second speed, hold to the end
    (the trace runs 10 ms past the scene so the reference never extrapolates)."""
    seg = scene["drive"]["segments"]
    w1, w2 = (r / belt_ratio * 2.0 * math.pi / 60.0 for r in scene["drive"]["motor_rpm"])
    t = np.arange(int(round((scene["duration_s"] + 0.01) * TRACE_RATE_HZ)) + 1) / TRACE_RATE_HZ

    def ramp(tau: np.ndarray, T: float) -> np.ndarray:
        return 0.5 * (1.0 - np.cos(np.pi * np.clip(tau / T, 0.0, 1.0)))

    t1 = seg["rest_s"]
    t2 = t1 + seg["ramp_up_s"] + seg["hold_s"]
    t3 = t2 + seg["brake_s"] + seg["stop_s"]
    omega = (w1 * ramp(t - t1, seg["ramp_up_s"]) - w1 * ramp(t - t2, seg["brake_s"])
             + w2 * ramp(t - t3, seg["ramp_up2_s"]))
    angle = scene["initial_encoder_angle_rad"] + np.concatenate(
        [[0.0], np.cumsum(0.5 * (omega[1:] + omega[:-1]) / TRACE_RATE_HZ)])
    return t, angle


def scene_inputs(scene: dict[str, Any]) -> DriveInputs | None:
    """The recorded drive input of a scene, in memory: a start/stop scene's encoder trace
    (:func:`startstop_trace`), None for the other programs."""
    if scene["drive"]["program"] in ("constant", "protocol"):
        return None
    return DriveInputs(trace=startstop_trace(scene, preset(1).drive.belt_ratio))


def scene_config(scene: dict[str, Any], trace_dir: Path | None = None) -> BenchConfig:
    """Bench configuration of a scene (MuJoCo engine). A start/stop scene's trace travels in memory
    (:func:`scene_inputs`); with ``trace_dir`` it is also written there, as the file the configuration
    names (to run the scene again outside the study), else the configuration names it only."""
    base = preset(1)
    d = scene["drive"]
    ov: dict[str, Any] = {
        "name": f"stability_s{scene['seed']}_{scene['index']:05d}",
        "joints.clearance_b_mm": scene["clearance_b_mm"], "joints.clearance_c_mm": scene["clearance_c_mm"],
        "mechanism.orientation": scene["orientation"],
        "drive.initial_encoder_angle_rad": scene["initial_encoder_angle_rad"],
        "simulation.engine": "mujoco", "simulation.timestep_s": scene["timestep_s"],
        "sensors.output_rate_hz": min(100_000.0, 1.0 / scene["timestep_s"]),
        "simulation.duration_s": scene["duration_s"],
        "mujoco.contact_stiffness_scale": scene["contact_stiffness_scale"],
        "mujoco.contact_damping_scale": scene["contact_damping_scale"],
        "sensors.channels": list(CHANNELS),
    }
    if d["program"] == "constant":
        ov.update({"drive.program": "constant", "drive.motor_rpm": d["motor_rpm"], "drive.ramp_s": d["ramp_s"]})
    elif d["program"] == "protocol":
        ov.update({"drive.program": "protocol", "drive.protocol_rpm": d["protocol_rpm"],
                   "drive.protocol_hold_s": d["protocol_hold_s"], "drive.protocol_stop_s": d["protocol_stop_s"],
                   "drive.ramp_s": d["ramp_s"]})
    else:
        path = Path(trace_dir or ".") / f"trace_s{scene['seed']}_{scene['index']:05d}.npz"
        if trace_dir is not None:
            t, angle = startstop_trace(scene, base.drive.belt_ratio)
            np.savez(path, t=t, angle=angle)
        ov.update({"drive.program": "trace", "drive.trace_file": str(path)})
    if "structure" in scene:  # the flexible structure (StudySettings.structure), in the scene's engine
        ov.update({"structure.mode": "flexible", "simulation.engine": scene.get("engine", "mujoco"),
                   **{f"structure.{k}": v for k, v in scene["structure"].items()}})
    if "drive_mode" in scene:
        ov.update(bench_overrides(scene))
        if scene["drive_mode"] == "motor":
            ov["sensors.channels"] = list(CHANNELS) + ["motor"]
    return base.replace(**ov)


# ----------------------------------------------------------------------- metrics
def _cumtrapz(y: np.ndarray, dt: float) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(0.5 * (y[1:] + y[:-1]) * dt)])


def energy_balance(run: Any, cfg: BenchConfig) -> dict[str, float]:
    """Energy balance of a run with the ``drive``, ``crank`` and ``energy`` groups (module
    docstring): work in, guide dissipation, ΔE [J], residual [J] and relative to W+ [-]."""
    dt = run.dt
    power = np.asarray(run["crank_torque"], dtype=np.float64) * run["crank_speed"]
    w_in = _cumtrapz(power, dt)
    w_pos = float(_cumtrapz(np.maximum(power, 0.0), dt)[-1])
    d_guide = _cumtrapz(cfg.mechanism.guide_friction_n * np.abs(run["slider_speed"]), dt)
    energy = run["energy_kinetic"] + run["energy_potential"] - rotor_energy(run, cfg)
    res = w_in - d_guide - (energy - energy[0])
    scale = max(w_pos, 1e-12)
    return {"work_in_J": float(w_in[-1]), "work_pos_J": w_pos, "guide_dissipation_J": float(d_guide[-1]),
            "delta_energy_J": float(energy[-1] - energy[0]), "residual_J": float(res[-1]),
            "residual_rel": float(res[-1] / scale), "residual_min_rel": float(res.min() / scale),
            "energy_created": bool(res.min() < -ENERGY_TOL * w_pos)}


def scene_metrics(run: Any, cfg: BenchConfig, scene: dict[str, Any]) -> dict[str, Any]:
    """Metrics of one finished run (see module docstring)."""
    nonfinite = [k for k, c in run.channels.items() if not np.all(np.isfinite(c.data))]
    warnings = dict(run.meta.get("warnings", {}))
    expected = int(round(cfg.duration_s * run.rate_hz))
    short = run.n < expected
    out: dict[str, Any] = {"diverged": bool(nonfinite or warnings or short), "error": None,
                           "nonfinite_channels": nonfinite, "warnings": warnings,
                           "samples": run.n, "samples_expected": expected}
    pen = {}
    for j in cfg.joints.clearance_joints:
        c = cfg.joints.radial_m(j)
        p = run[f"pen_{j}"]
        pen[j] = {"max_pen_m": float(np.nanmax(p)), "c_m": c, "pen_over_c": float(np.nanmax(p) / c)}
    out["joints"] = pen
    out["max_pen_over_c"] = max((v["pen_over_c"] for v in pen.values()), default=0.0)
    if cfg.joints.guide_play:  # reported, not a criterion (stability_bench.guide_penetration)
        out["guide_pen_over_c"] = guide_penetration(run, cfg) / cfg.joints.guide_radial_m
    i0 = min(int(math.ceil(scene["settle_s"] * run.rate_hz)), run.n - 1)
    err = np.abs(run["crank_angle"][i0:] - run["theta_ref"][i0:])
    out["tracking_max_rad"] = float(np.max(err))
    out["tracking_rms_rad"] = float(np.sqrt(np.mean(err ** 2)))
    out.update(energy_balance(run, cfg) if not nonfinite else {})
    out["wall_s"] = float(run.meta.get("wall_s", 0.0))
    out["passed"] = bool(not out["diverged"] and out["max_pen_over_c"] <= PEN_LIMIT)
    return out


def run_scene(scene: dict[str, Any], trace_dir: Path | None = None) -> dict[str, Any]:
    """Simulate one scene and return its metrics (a raised engine error counts as a divergence);
    ``trace_dir``: where to also write a start/stop scene's trace (:func:`scene_config`)."""
    from twin.errors import SimulationError
    from twin.simulation import simulate_run

    cfg = scene_config(scene, trace_dir)
    inputs = scene_inputs(scene)
    t0 = time.perf_counter()
    try:
        run = simulate_run(cfg, inputs=inputs)
    except SimulationError as err:
        return {"diverged": True, "passed": False, "error": str(err), "warnings": {}, "nonfinite_channels": [],
                "joints": {}, "max_pen_over_c": float("nan"), "wall_s": time.perf_counter() - t0}
    met = scene_metrics(run, cfg, scene)
    if not met["diverged"] and met["max_pen_over_c"] > PEN_LIMIT:
        met["reference"] = reference_check(cfg, inputs)
        _mark_agreement(met)
    return met


def carried_restitution(cfg: BenchConfig) -> float | None:
    """Restitution e' under which the reference's law has the twin's perturbed damping:
    χ(e') = ``mujoco.contact_damping_scale`` × χ(e) for the hysteresis laws (χ of
    :data:`twin.impact.DAMPING_FACTOR`; LN: χ = 3(1 − e²)/4, so 1 − e'² = s (1 − e²)); None for the
    other laws, whose damping is not a function of e, or where no e' in (0, 1) exists."""
    from scipy.optimize import brentq

    from twin.impact import DAMPING_FACTOR

    law, e, s = cfg.contact.law, cfg.contact.restitution, cfg.mujoco.contact_damping_scale
    if law not in DAMPING_FACTOR:
        return None
    chi = DAMPING_FACTOR[law]
    target = s * chi(e)
    lo, hi = 1e-9, 1.0 - 1e-12
    if not (chi(hi) - target) * (chi(lo) - target) < 0:
        return e if s == 1.0 else None
    return float(brentq(lambda x: chi(x) - target, lo, hi, xtol=1e-14))


def reference_check(cfg: BenchConfig, inputs: DriveInputs | None = None) -> dict[str, Any]:
    """pen/c of the reference engine at its converged step (REFERENCE_TIMESTEP_S) on the same
    scene, under the twin's perturbed law (module docstring): tells a physical exceedance of
    PEN_LIMIT (the converged reference exceeds it too) from a numerical one."""
    from twin.simulation import simulate_run

    e_ref = carried_restitution(cfg)
    over = {"simulation.engine": "reference", "simulation.timestep_s": REFERENCE_TIMESTEP_S,
            "sensors.channels": ["crank", "joints", "drive"],
            "contact.stiffness_scale": cfg.contact.stiffness_scale * cfg.mujoco.contact_stiffness_scale}
    if e_ref is not None:
        over["contact.restitution"] = e_ref
    try:
        run = simulate_run(cfg.replace(**over), inputs=inputs)
    except TwinError as err:
        return {"error": str(err)}
    pen = {j: float(np.max(run[f"pen_{j}"]) / cfg.joints.radial_m(j)) for j in cfg.joints.clearance_joints}
    return {"timestep_s": REFERENCE_TIMESTEP_S, "pen_over_c": pen, "restitution": e_ref if e_ref is not None
            else cfg.contact.restitution, "damping_carried": e_ref is not None}


def _mark_agreement(met: dict[str, Any]) -> None:
    """Set ``met["reference"]["agrees"]`` (the twin's pen/c over PEN_LIMIT is at most
    REFERENCE_AGREEMENT × the reference's at each such joint) and ``cause`` ("physical" where
    the converged reference exceeds PEN_LIMIT at each such joint too, else "numerical")."""
    ref = met.get("reference", {})
    if "pen_over_c" not in ref:
        return
    over = [j for j, v in met["joints"].items() if v["pen_over_c"] > PEN_LIMIT]
    ref["agrees"] = bool(all(met["joints"][j]["pen_over_c"] <= REFERENCE_AGREEMENT * ref["pen_over_c"][j]
                             for j in over))
    ref["cause"] = "physical" if all(ref["pen_over_c"][j] > PEN_LIMIT for j in over) else "numerical"


# ------------------------------------------------------------------------- study
def _stats(x: list[float]) -> dict[str, float]:
    a = np.asarray([v for v in x if v is not None and np.isfinite(v)], dtype=float)
    if a.size == 0:
        return {"n": 0}
    return {"n": int(a.size), "min": float(a.min()), "median": float(np.median(a)), "mean": float(a.mean()),
            "p95": float(np.percentile(a, 95)), "max": float(a.max())}


def summarize(rows: list[dict[str, Any]], wall_s: float) -> dict[str, Any]:
    """Campaign summary of the per-scene rows."""
    m = [r["metrics"] for r in rows]
    pen = [(x["max_pen_over_c"], r["scene"]["index"]) for r, x in zip(rows, m) if np.isfinite(x["max_pen_over_c"])]
    worst = max(pen) if pen else (float("nan"), None)
    res = [(x["residual_min_rel"], r["scene"]["index"]) for r, x in zip(rows, m) if "residual_min_rel" in x]
    most_neg = min(res) if res else (float("nan"), None)
    return {
        "scenes": len(rows),
        "passed": sum(x["passed"] for x in m),
        "diverged": sum(x["diverged"] for x in m),
        "diverged_scenes": [r["scene"]["index"] for r, x in zip(rows, m) if x["diverged"]],
        "failed_scenes": [r["scene"]["index"] for r, x in zip(rows, m) if not x["passed"]],
        "pen_exceeded_scenes": [r["scene"]["index"] for r, x in zip(rows, m)
                                if not x["diverged"] and x["max_pen_over_c"] > PEN_LIMIT],
        "pen_exceeded_reference_agrees": [r["scene"]["index"] for r, x in zip(rows, m)
                                          if x.get("reference", {}).get("agrees")],
        "pen_exceeded_physical": [r["scene"]["index"] for r, x in zip(rows, m)
                                  if x.get("reference", {}).get("cause") == "physical"],
        "pen_exceeded_numerical": [r["scene"]["index"] for r, x in zip(rows, m)
                                   if x.get("reference", {}).get("cause") == "numerical"],
        "max_pen_over_c": worst[0], "max_pen_over_c_scene": worst[1],
        "pen_over_c": _stats([p for p, _ in pen]),
        "guide_pen_over_c": _stats([x["guide_pen_over_c"] for x in m if "guide_pen_over_c" in x]),
        "energy_created": sum(bool(x.get("energy_created")) for x in m),
        "energy_created_scenes": [r["scene"]["index"] for r, x in zip(rows, m) if x.get("energy_created")],
        "residual_rel": _stats([x.get("residual_rel") for x in m]),
        "residual_min_rel": _stats([x.get("residual_min_rel") for x in m]),
        "most_negative_residual_rel": most_neg[0], "most_negative_residual_scene": most_neg[1],
        "tracking_max_rad": _stats([x.get("tracking_max_rad") for x in m]),
        "tracking_rms_rad": _stats([x.get("tracking_rms_rad") for x in m]),
        "wall_s": wall_s,
        "engine_wall_s": float(sum(x.get("wall_s", 0.0) for x in m)),
    }


@dataclass(frozen=True)
class StabilityResult:
    """What a campaign found (``stability.json``).

    Attributes:
        settings: the campaign's :class:`StudySettings` and the pass limits (``pen_limit``, ``energy_tol``).
        summary: the counts and statistics of :func:`summarize` (``passed`` of ``scenes``, ...).
        scenes: per scene its draw (``scene``) and what it gave (``metrics``), in scene order.
        figures: the PNG files written beside the JSON (none without an output folder).
    """

    settings: dict[str, Any]
    summary: StabilitySummary
    scenes: list[dict[str, Any]]
    figures: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.summary, StabilitySummary):  # the dict of summarize() or of the JSON file
            object.__setattr__(self, "summary", StabilitySummary.from_dict(self.summary))

    @property
    def passed(self) -> bool:
        """Every scene passed."""
        return self.summary.passed == self.summary.scenes

    def to_dict(self) -> dict[str, Any]:
        """The JSON data of ``stability.json`` (non-finite floats as they are; written through
        :func:`_jsonable`)."""
        return {"study": "stability", "settings": self.settings, "summary": self.summary.to_dict(),
                "scenes": self.scenes, "figures": list(self.figures)}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "StabilityResult":
        """The result of ``stability.json``'s data (its provenance stamp ignored)."""
        return cls(d["settings"], StabilitySummary.from_dict(d["summary"]), d["scenes"], tuple(d.get("figures", ())))


def run_study(settings: StudySettings, *, out: str | Path | None = None, progress: bool = False,
              log: Callable[[str], None] | None = None) -> StabilityResult:
    """Run the campaign of ``settings``; write ``stability.json``, ``stability.md`` and
    ``stability.png`` to the folder ``out`` when given; ``progress``: a progress bar on stderr;
    ``log``: receives one line per failed scene."""
    from twin.provenance import git_commit

    git_commit()   # the stamp names the code that ran (taken now, cached), not the tree when the run ends
    run_one = run_scene
    if settings.family == "spatial":
        from twin.studies.spatial_stability import run_scene as run_one, sample_scene as sample_spatial  # noqa: F811

        scenes = [sample_spatial(settings.seed, i, settings.duration_range_s) for i in _indices(settings)]
    else:
        scenes = [sample_scene(settings.seed, i, settings.duration_range_s, settings.bench, settings.structure)
                  for i in _indices(settings)]
        if settings.bench or settings.structure:  # every bench or structure scene in both engines: one row each
            scenes = [{**sc, "engine": e} for sc in scenes for e in ENGINES]
    rows = []
    t0 = time.perf_counter()
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(scenes), desc="stability", unit="scene", mininterval=1.0)
    try:
        for sc in scenes:
            met = run_one(sc)
            rows.append({"scene": sc, "metrics": met})
            if bar is not None:
                bar.update(1)
            if log is not None and not met["passed"]:
                log(f"scene {sc['index']}: FAILED ({_failure(met)})")
    finally:
        if bar is not None:
            bar.close()
    # rigid campaigns from scene 0: the settings as before
    kept = {k: v for k, v in asdict(settings).items() if k not in ("structure", "first") or v}
    res = StabilityResult({**kept, "pen_limit": PEN_LIMIT, "energy_tol": ENERGY_TOL},
                          summarize(rows, time.perf_counter() - t0), rows)
    if out is not None:
        out = Path(out)
        out.mkdir(exist_ok=True)
        res = _write(res, out)
    return res


def _indices(settings: StudySettings) -> range:
    return range(settings.first, settings.first + settings.scenes)


def _write(res: StabilityResult, out: Path) -> StabilityResult:
    """Write ``stability.json`` (stamped), ``stability.md`` and ``stability.png`` of ``res`` into the folder ``out``."""
    from twin.provenance import stamped, with_stamp_line

    out.mkdir(exist_ok=True)
    res = replace(res, figures=(_figure(out, res.scenes),))
    data = res.to_dict()
    atomic_write_json(out / "stability.json", _jsonable(stamped(data)))
    atomic_write_text(out / "stability.md", with_stamp_line(markdown(data)))
    return res


def merge_results(parts: list[str | Path], out: str | Path) -> StabilityResult:
    """Join the ``stability.json`` of campaigns run in parts (the same seed, durations and draws; consecutive
    ``first`` … ranges, :attr:`StudySettings.first`) into one campaign written to ``out``. The parts' provenance must
    name one commit (the same code ran every part); a part of other settings or a gap in the scenes is refused."""
    import json

    datas = [json.loads((Path(p) / "stability.json").read_text()) for p in parts]
    datas.sort(key=lambda d: d["settings"].get("first", 0))
    commits = {d.get("provenance", {}).get("git_commit") for d in datas}
    if len(commits) != 1 or None in commits or any(str(c).endswith("-dirty") for c in commits):
        raise TwinError(f"stability parts: ran from different or unrecorded commits {sorted(map(str, commits))}")
    base = {k: v for k, v in datas[0]["settings"].items() if k not in ("scenes", "first")}
    nxt = datas[0]["settings"].get("first", 0)
    for d in datas:
        st = d["settings"]
        if {k: v for k, v in st.items() if k not in ("scenes", "first")} != base:
            raise TwinError(f"stability parts: settings differ ({st} against {base})")
        if st.get("first", 0) != nxt:
            raise TwinError(f"stability parts: scenes from {nxt} missing (a part starts at {st.get('first', 0)})")
        nxt += st["scenes"]
    rows = [r for d in datas for r in d["scenes"]]
    for r in rows:   # JSON wrote non-finite floats as null
        r["metrics"] = {k: float("nan") if v is None and k == "max_pen_over_c" else v for k, v in r["metrics"].items()}
    first = datas[0]["settings"].get("first", 0)
    settings = {**base, "scenes": nxt - first, **({"first": first} if first else {}),
                "parts": len(datas), "parts_commit": commits.pop()}
    wall = sum(d["summary"].get("wall_s", 0.0) for d in datas)
    res = StabilityResult(settings, summarize(rows, wall), rows)
    return _write(res, Path(out))


def _jsonable(o: Any) -> Any:
    """Replace non-finite floats by None (strict JSON)."""
    if isinstance(o, dict):
        return {k: _jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_jsonable(v) for v in o]
    if isinstance(o, float) and not math.isfinite(o):
        return None
    return o


def _failure(met: dict[str, Any]) -> str:
    """Why a scene failed, in a few words."""
    if met.get("error"):
        return met["error"]
    if met["diverged"]:
        return (f"diverged: warnings {met['warnings'] or 'none'}, non-finite {met['nonfinite_channels'] or 'none'}, "
                f"{met['samples']}/{met['samples_expected']} samples")
    ref = met.get("reference", {}).get("pen_over_c", {})
    return "pen/c " + ", ".join(f"{j} {v['pen_over_c']:.3f}" + (f" (reference {ref[j]:.3f})" if j in ref else "")
                                for j, v in met["joints"].items())


def one_line(result: StabilityResult) -> str:
    """The campaign in one line."""
    s = result.summary
    verdict = "PASS" if s["passed"] == s["scenes"] else "FAIL"
    return (f"stability {verdict}: {s['passed']}/{s['scenes']} scenes passed, {s['diverged']} diverged, "
            f"max pen/c {s['max_pen_over_c']:.3f} (scene {s['max_pen_over_c_scene']}), "
            f"pen/c > {PEN_LIMIT:g} in {len(s['pen_exceeded_scenes'])} "
            f"({len(s.get('pen_exceeded_physical', []))} physical: the converged reference exceeds it too), "
            f"energy created in {s['energy_created']}, residual/W+ median "
            f"{s['residual_rel'].get('median', float('nan')):.2e}, wall {s['wall_s']:.1f} s")


def _program_label(sc: dict[str, Any]) -> str:
    d = sc["drive"]
    if d["program"] == "constant":
        return f"constant {d['motor_rpm']:.0f} rpm, ramp {d['ramp_s']:.3f} s" + label(sc)
    if d["program"] == "protocol":
        return f"protocol {'/'.join(f'{r:.0f}' for r in d['protocol_rpm'])} rpm" + label(sc)
    return f"start/stop {'/'.join(f'{r:.0f}' for r in d['motor_rpm'])} rpm" + label(sc)


def markdown(data: dict[str, Any]) -> str:
    """stability.md: summary and per-scene table."""
    s, st = data["summary"], data["settings"]

    def f(stats: dict[str, float], key: str, fmt: str = ".2e") -> str:
        return format(stats[key], fmt) if key in stats else "-"

    lines = [
        "# Stability study of the MuJoCo twin",
        "",
        f"{s['scenes']} randomized scenes, seed {st['seed']}, durations {st['duration_range_s'][0]:g}-"
        f"{st['duration_range_s'][1]:g} s; method in `twin/studies/stability.py`. A scene passes with no "
        f"divergence (engine error, NaN/Inf, MuJoCo warning, short run) and pen/c <= {st['pen_limit']:g}.",
        "",
        "## Summary",
        "",
        f"* scenes passed: **{s['passed']} / {s['scenes']}**; diverged: **{s['diverged']}**"
        + (f" (scenes {', '.join(map(str, s['diverged_scenes']))})" if s["diverged_scenes"] else ""),
        f"* max pen/c: **{s['max_pen_over_c']:.4f}** (scene {s['max_pen_over_c_scene']}); median "
        f"{f(s['pen_over_c'], 'median', '.4f')}, 95th percentile {f(s['pen_over_c'], 'p95', '.4f')}",
        f"* pen/c > {st['pen_limit']:g}: {len(s['pen_exceeded_scenes'])} scenes"
        + (f" ({', '.join(map(str, s['pen_exceeded_scenes']))})" if s["pen_exceeded_scenes"] else "")
        + f"; re-run by the reference engine at its converged step (h = {REFERENCE_TIMESTEP_S:g} s) under the "
          f"twin's perturbed law: **physical** in {len(s.get('pen_exceeded_physical', []))}"
        + (f" ({', '.join(map(str, s['pen_exceeded_physical']))})" if s.get("pen_exceeded_physical") else "")
        + " (the converged reference exceeds the limit too: the law's own deflection at a small clearance, "
          f"which no integrator can bring under it), **numerical** in {len(s.get('pen_exceeded_numerical', []))}"
        + (f" ({', '.join(map(str, s['pen_exceeded_numerical']))})" if s.get("pen_exceeded_numerical") else "")
        + " (the twin's step overshoots the converged penetration past the limit); the twin's pen/c is within "
          f"{REFERENCE_AGREEMENT:g}x the reference's in {len(s['pen_exceeded_reference_agrees'])}; either way the "
          "scene fails the criterion",
        f"* energy residual R(end)/W+: median {f(s['residual_rel'], 'median')}, min {f(s['residual_rel'], 'min')}, "
        f"max {f(s['residual_rel'], 'max')}; most negative min_t R(t)/W+: {s['most_negative_residual_rel']:.2e} "
        f"(scene {s['most_negative_residual_scene']}); energy created (< -{st['energy_tol']:g} W+) in "
        f"**{s['energy_created']}** scenes"
        + (f" ({', '.join(map(str, s['energy_created_scenes']))})" if s["energy_created_scenes"] else ""),
        f"* tracking error after the first ramp: max |θ−θ_ref| median {f(s['tracking_max_rad'], 'median')} rad, "
        f"worst {f(s['tracking_max_rad'], 'max')} rad; RMS median {f(s['tracking_rms_rad'], 'median')} rad",
        f"* wall time {s['wall_s']:.1f} s (engine stepping {s['engine_wall_s']:.1f} s)",
        "",
        "R = W_in − D_guide − ΔE lumps contact damping, joint friction, soft-contact elastic energy and "
        "integration error (R ≥ 0 is physical dissipation).",
        "",
        "## Scenes",
        "",
        "| # | B [mm] | C [mm] | up | program | h [s] | k× | c× | T [s] | pen/c B | pen/c C | track max [rad] "
        "| R/W+ | min R/W+ | status |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in data["scenes"]:
        sc, m = r["scene"], r["metrics"]
        pj = {j: m["joints"].get(j, {}).get("pen_over_c") for j in ("B", "C")}
        status = "ok" if m["passed"] else ("DIVERGED" if m["diverged"] else "pen/c")
        if "pen_over_c" in m.get("reference", {}):
            status += " (ref " + ", ".join(f"{j} {v:.3f}" for j, v in m["reference"]["pen_over_c"].items()) + \
                (f"; {m['reference']['cause']}" if "cause" in m["reference"] else "") + ")"
        if m.get("energy_created"):
            status += " E+"
        lines.append(
            f"| {sc['index']} | {sc['clearance_b_mm']:g} | {sc['clearance_c_mm']:g} | {sc['orientation']} | "
            f"{_program_label(sc)} | {sc['timestep_s']:g} | {sc['contact_stiffness_scale']:.2f} | "
            f"{sc['contact_damping_scale']:.2f} | {sc['duration_s']:.3f} | "
            + " | ".join("-" if pj[j] is None else f"{pj[j]:.4f}" for j in ("B", "C"))
            + f" | {m.get('tracking_max_rad', float('nan')):.2e} | {m.get('residual_rel', float('nan')):.2e} | "
              f"{m.get('residual_min_rel', float('nan')):.2e} | {status} |")
    return "\n".join(lines) + "\n"


def _figure(out: Path, rows: list[dict[str, Any]]) -> str:
    """stability.png: histograms of pen/c per joint and of the relative energy residual."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
    for j, color in (("B", "tab:blue"), ("C", "tab:orange")):
        v = [r["metrics"]["joints"][j]["pen_over_c"] for r in rows if j in r["metrics"].get("joints", {})]
        if v:
            a1.hist(v, bins=30, alpha=0.6, color=color, label=f"joint {j} ({len(v)})")
    a1.axvline(PEN_LIMIT, color="r", ls="--", label=f"limit {PEN_LIMIT:g}")
    a1.set_xlabel("max penetration / radial clearance [-]")
    a1.set_ylabel("scenes")
    a1.legend()
    res = [r["metrics"]["residual_rel"] for r in rows if "residual_rel" in r["metrics"]]
    resmin = [r["metrics"]["residual_min_rel"] for r in rows if "residual_min_rel" in r["metrics"]]
    if res:
        a2.hist(res, bins=30, alpha=0.6, label="R(end)/W+")
        a2.hist(resmin, bins=30, alpha=0.6, label="min_t R(t)/W+")
    a2.axvline(-ENERGY_TOL, color="r", ls="--", label=f"energy created < -{ENERGY_TOL:g}")
    a2.set_xlabel("energy residual / positive work input [-]")
    a2.legend()
    fig.suptitle(f"twin study stability: {len(rows)} scenes")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, metadata=figure_metadata())
    plt.close(fig)
    atomic_write_bytes(out / "stability.png", buf.getvalue())
    return "stability.png"
