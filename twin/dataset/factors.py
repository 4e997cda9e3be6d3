"""Factors a dataset can vary, and how a value becomes configuration.

Named factors (below) cover what the bench's users vary; any other configuration field can be
varied by its dotted path (``pid.kp``, ``drive.ramp_s``, ``mujoco.contact_damping_scale``): its
values are checked by building the configuration. Factors drawn per run (sensor offsets, mounting
errors, random speed profiles) take their randomness from the run's own seed, so a run is
reproducible from its configuration alone (the configuration records what was drawn).

Labels: ``fault`` ∈ {none, B, C, BC, G, BG, CG, BCG} and ``clearance_b_mm``/``clearance_c_mm`` (diametral, 0 for
a ball bearing) are read back from the resolved configuration, whatever factors produced it; a run whose slider
guide has play (``joints.clearance_guide_mm`` > 0) has G in its fault and the label ``clearance_guide_mm`` (the
guide's two-sided play [mm]; a dataset without guide play anywhere has no such column, as before the guide was a
fault location, and a run without it in a dataset with it holds NaN there: read it as 0).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from twin.config import ACCELEROMETERS, CATALOGUE_DIAMETRAL_MM, BenchConfig
from twin.config.drivetrain import EXPLORE_RANGES
from twin.config.structure import EXPLORE_RANGES as STRUCTURE_RANGES
from twin.config.structure import STRUCTURE_MODES
from twin.dataset.spec import SpecError
from twin.errors import did_you_mean

#: fault classes: which locations have a clearance (B, C: the revolute joints; G: the slider guide)
FAULTS = ("none", "B", "C", "BC", "G", "BG", "CG", "BCG")
#: clearance of a faulty joint whose size is not varied [mm] (Table 4's 0.1 mm)
DEFAULT_FAULT_CLEARANCE_MM = 0.1


@dataclass(frozen=True)
class Factor:
    """A named factor.

    Attributes:
        name: the spec's key.
        doc: what it sets, with units.
        choices: allowed values of a categorical factor (None: numeric).
        bounds: allowed numeric range [lo, hi] (None: categorical).
        apply: ``apply(value, ov, rng, base)`` adds dotted-path overrides to ``ov``; ``rng`` is the
            run's generator (for per-run draws), ``base`` the base configuration.
        engines: engines that support it.
    """

    name: str
    doc: str
    choices: tuple[Any, ...] | None
    bounds: tuple[float, float] | None
    apply: Callable[[Any, dict[str, Any], np.random.Generator, BenchConfig], None]
    engines: tuple[str, ...] = ("mujoco", "reference")


def _set(path: str) -> Callable[[Any, dict[str, Any], np.random.Generator, BenchConfig], None]:
    def apply(v, ov, rng, base):  # noqa: ARG001
        ov[path] = v
    return apply


def _clearance(joint: str):
    def apply(v, ov, rng, base):  # noqa: ARG001
        ov[f"joints.clearance_{joint.lower()}_mm"] = float(v)
        if v != 0 and not any(abs(v - c) < 1e-9 for c in CATALOGUE_DIAMETRAL_MM):
            ov["joints.allow_noncatalogue"] = True
    return apply


def _radial_clearance(joint: str):
    def apply(v, ov, rng, base):  # noqa: ARG001
        ov[f"joints.clearance_{joint.lower()}_mm"] = 2.0 * float(v)  # the configuration holds diametral sizes
        ov["joints.allow_noncatalogue"] = True
    return apply


def _crank_rpm(v, ov, rng, base):  # noqa: ARG001
    ov["drive.crank_rpm"] = float(v)


def _fault(v, ov, rng, base):  # noqa: ARG001
    # applied after every other factor (twin.dataset.design.resolve_config): a faulty joint keeps the
    # size a clearance factor gave it, else 0.1 mm; a healthy joint gets 0 whatever it was given (the guide, G,
    # likewise: its play as clearance_guide_mm gave it, else 0.1 mm)
    for j in "BCG":
        key = "joints.clearance_guide_mm" if j == "G" else f"joints.clearance_{j.lower()}_mm"
        now = base.joints.clearance_guide_mm if j == "G" else base.joints.diametral_mm(j)
        if j in v:
            if ov.get(key, now) == 0:
                ov[key] = DEFAULT_FAULT_CLEARANCE_MM
        else:
            ov[key] = 0.0


def _program(v, ov, rng, base):  # noqa: ARG001
    ov["@program"] = v  # resolved by the design once every factor is known (needs the duration)


def _pid_scale(v, ov, rng, base):  # noqa: ARG001
    for k in ("kp", "kv", "ki"):
        ov[f"pid.{k}"] = getattr(base.pid, k) * float(v)


def _zero_g_spread(v, ov, rng, base):  # noqa: ARG001
    supply = base.instrumentation.supply_v
    offs = supply / 2 + float(v) * rng.standard_normal(len(ACCELEROMETERS))
    ov["instrumentation.zero_g_v"] = {a: float(np.clip(o, 0.05 * supply, 0.95 * supply))
                                      for a, o in zip(ACCELEROMETERS, offs)}


def _mount_offset(v, ov, rng, base):  # noqa: ARG001
    mounts = {}
    for a in ACCELEROMETERS:
        m = base.sensors.accelerometers[a]
        dx, dy = float(v) * (2 * rng.random(2) - 1)
        mounts[a] = {"body": m.body, "position_m": [m.position_m[0] + dx, m.position_m[1] + dy], "axis": m.axis}
    ov["sensors.accelerometers"] = mounts


def _ripple(k: int):
    """Harmonic ``k`` of the within-turn speed ripple (drive.ripple_pct, drive.ripple_phase_rad): its
    amplitude is the value [%], its phase drawn uniformly over a turn from the run's generator."""
    def apply(v, ov, rng, base):  # noqa: ARG001
        n = max(k, len(ov.get("drive.ripple_pct", ())), len(base.drive.ripple_pct))
        pct = list(ov.get("drive.ripple_pct", base.drive.ripple_pct)) + [0.0] * n
        ph = list(ov.get("drive.ripple_phase_rad", base.drive.ripple_phase_rad or (0.0,) * len(base.drive.ripple_pct)))
        ph += [0.0] * n
        pct[k - 1] = float(v)
        ph[k - 1] = float(rng.uniform(0.0, 2.0 * np.pi))
        ov["drive.ripple_pct"] = pct[:n]
        ov["drive.ripple_phase_rad"] = ph[:n]
    return apply


#: the named factors, in the order they are applied (``fault`` is applied last, after the sizes)
NAMED: dict[str, Factor] = {f.name: f for f in (
    Factor("fault", "locations with a clearance: none, B, C, BC, G (the slider guide), BG, CG or BCG (size: "
           "clearance_b_mm/_c_mm/clearance_guide_mm, else 0.1 mm)",
           FAULTS, None, _fault),
    Factor("clearance_b_mm", "diametral clearance at B [mm], 0 = ball bearing; any value in [0, 1] "
           "(non-catalogue values allowed)", None, (0.0, 1.0), _clearance("B")),
    Factor("clearance_c_mm", "diametral clearance at C [mm], as clearance_b_mm", None, (0.0, 1.0), _clearance("C")),
    Factor("radial_clearance_b_mm", "radial clearance at B [mm] (half the diametral clearance_b_mm; S000's "
           "tables are radial)", None, (0.0, 2.5), _radial_clearance("B")),
    Factor("radial_clearance_c_mm", "radial clearance at C [mm], as radial_clearance_b_mm", None, (0.0, 2.5),
           _radial_clearance("C")),
    Factor("crank_rpm", "crank speed of the constant program given directly [rpm] (drive.crank_rpm; the motor "
           "and belt bypassed)", None, (-6000.0, 6000.0), _crank_rpm),
    Factor("orientation", "bench axis that points up", ("x", "y", "z"), None, _set("mechanism.orientation")),
    Factor("program", "speed program: constant (motor_rpm), protocol (S003 §4.3), random-profile (base.profile)",
           ("constant", "protocol", "random-profile"), None, _program),
    Factor("motor_rpm", "motor speed of the constant program [rpm]", None, (-1000.0, 1000.0), _set("drive.motor_rpm")),
    Factor("d_off_m", "offset of C' above the guide line [m]", None, (-0.05, 0.05), _set("mechanism.d_off_m")),
    Factor("restitution", "coefficient of restitution of the contact law [-]", None, (0.05, 1.0),
           _set("contact.restitution")),
    Factor("mu0", "clearance-joint friction coefficient [-]", None, (0.0, 1.0), _set("contact.mu0")),
    Factor("stiffness_scale", "factor on the contact stiffness, both engines [-]", None, (0.1, 10.0),
           _set("contact.stiffness_scale")),
    Factor("guide_friction_n", "slider guide friction [N]", None, (0.0, 100.0), _set("mechanism.guide_friction_n")),
    Factor("clearance_guide_mm", "two-sided clearance of the slider guide: the slider's total transverse play "
           "between its rails [mm], 0 = the preloaded ideal guide", None, (0.0, 1.0),
           _set("joints.clearance_guide_mm")),
    Factor("pid_scale", "factor on the three PID gains [-]", None, (0.1, 10.0), _pid_scale),
    Factor("zero_g_spread_v", "standard deviation of the sensors' zero-g offsets around mid-supply [V] "
           "(drawn per run)", None, (0.0, 0.5), _zero_g_spread),
    Factor("mount_offset_m", "accelerometer mounting error: uniform ±value in x and y [m] (drawn per run)",
           None, (0.0, 0.02), _mount_offset),
    Factor("noise", "sensor noise on or off", (True, False), None, _set("instrumentation.noise")),
    Factor("noise_scale", "factor on the sensors' noise density [-] (instrumentation.noise_scale; 1 = datasheet)",
           None, (0.0, 100.0), _set("instrumentation.noise_scale")),
    Factor("start_angle_rad", "crank encoder angle at t = 0 [rad] (drive.initial_encoder_angle_rad; 0 = crank "
           "along -y)", None, (0.0, 6.283185307179586), _set("drive.initial_encoder_angle_rad")),
    # within-turn speed ripple of the pid/prescribed drive (drive.ripple_pct): harmonic k of the crank rate
    *(Factor(f"ripple{k}_pct", f"within-turn speed ripple at {k}x the crank rate [% of the speed], phase drawn "
             "per run (drive.ripple_pct; pid and prescribed drives)", None, (0.0, 10.0), _ripple(k))
      for k in (1, 2, 3, 4)),
    Factor("drive_mode", "how the crank is driven: pid, prescribed, motor (motor speed loop and V-belt), torque "
           "(motor torque program, release)", ("pid", "prescribed", "motor", "torque"), None, _set("drive.mode")),
    # the drive train's placeholders (twin.config.drivetrain; with drive_mode motor/torque): bounds are the
    # ranges the parameters' documentation asks users to explore
    *(Factor(name, f"drive train: {doc} (drivetrain.{field})", None, bounds, _set(f"drivetrain.{field}"))
      for name, field, doc, bounds in EXPLORE_RANGES),
    Factor("structure", "the bench's structure: rigid, or flexible (flexible rod, sprung frame and guide, sensor "
           "mounts; structure.mode)", STRUCTURE_MODES, None, _set("structure.mode")),
    # the flexible structure's placeholders (twin.config.structure; with structure = flexible, in the factors or
    # base.set): bounds are the ranges their documentation asks users to explore
    *(Factor(name, f"flexible structure: {doc} (structure.{field}; needs structure = flexible)", None, bounds,
             _set(f"structure.{field}"))
      for name, field, doc, bounds in STRUCTURE_RANGES),
)}


#: configuration fields the spec's base, outputs and run seeds decide: a factor or ``base.set`` on
#: them is refused (it would be overwritten)
CONTROLLED = ("simulation.duration_s", "simulation.engine", "sensors.output_rate_hz", "sensors.channels",
              "instrumentation.daq_rate_hz", "instrumentation.seed", "drive.program", "drive.steps_s",
              "drive.steps_rpm", "name")


def controlled(key: str) -> str | None:
    """The controlled field ``key`` is or holds (a section), or None."""
    for c in CONTROLLED:
        if key == c or c.startswith(key + "."):
            return c
    return None


def resolve(name: str, engine: str) -> Factor:
    """The factor called ``name``: a named one, or a dotted configuration path."""
    if name in NAMED:
        f = NAMED[name]
    elif "." in name:
        c = controlled(name)
        if c is not None:
            raise SpecError(f"factors.{name}", f"{c} is decided by the spec itself (base.engine, base.duration_s, "
                                               "base.program or the program factor, the outputs, the run seeds)")
        section = name.split(".", 1)[0]
        engines = ("mujoco",) if section == "mujoco" else ("mujoco", "reference")
        f = Factor(name, f"configuration field {name}", None, None, _set(name), engines)
    else:
        raise SpecError(f"factors.{name}", f"unknown factor{did_you_mean(name, NAMED)}; named factors: "
                                           f"{', '.join(NAMED)}, or any "
                                           "configuration field by its dotted path (e.g. pid.kp)")
    if engine not in f.engines:
        raise SpecError(f"factors.{name}", f"is not supported by the {engine} engine (only {', '.join(f.engines)})")
    return f


def check_value(f: Factor, value: Any, key: str) -> Any:
    """Check one value of factor ``f`` (categorical choice or numeric bounds)."""
    if f.choices is not None:
        if value not in f.choices or isinstance(value, bool) != isinstance(f.choices[0], bool):
            raise SpecError(key, f"must be one of {', '.join(map(str, f.choices))}; got {value!r}")
        return value
    if f.bounds is not None:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
            raise SpecError(key, f"must be a number, got {value!r}")
        lo, hi = f.bounds
        if not lo <= value <= hi:
            raise SpecError(key, f"must lie in [{lo:g}, {hi:g}], got {value!r}")
        return float(value)
    return value


def labels(cfg: BenchConfig) -> dict[str, Any]:
    """Labels of a resolved configuration: fault class and diametral clearances [mm] (with the guide's play
    where it has some: module docstring)."""
    b, c, g = cfg.joints.clearance_b_mm, cfg.joints.clearance_c_mm, cfg.joints.clearance_guide_mm
    fault = ("B" if b > 0 else "") + ("C" if c > 0 else "") + ("G" if g > 0 else "") or "none"
    out = {"fault": fault, "clearance_b_mm": float(b), "clearance_c_mm": float(c)}
    if g > 0:
        out["clearance_guide_mm"] = float(g)
    return out


def random_profile(rng: np.random.Generator, duration_s: float, rpm: tuple[float, float],
                   hold_s: tuple[float, float], stop_probability: float) -> tuple[list[float], list[float]]:
    """Step times [s] and motor speeds [rpm] of a random speed profile over ``duration_s``: from
    rest, a step every U(hold_s) seconds to U(rpm), or to a stop with ``stop_probability``."""
    times, speeds, t = [], [], 0.0
    while t < duration_s:
        times.append(round(t, 9))
        speeds.append(0.0 if (times[1:] and rng.random() < stop_probability) else float(rng.uniform(*rpm)))
        t += float(rng.uniform(*hold_s))
    return times, speeds
