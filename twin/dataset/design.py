"""From a spec to the list of runs: design points, repeats, seeds, configurations, ids, splits.

* **Design points**: ``grid`` (Cartesian product of every factor's values, ranges at ``levels``
  points, in the spec's order), ``lhs`` / ``sobol`` (``scipy.stats.qmc``, seeded from the spec)
  and ``random`` (uniform) draw ``runs`` points in the unit cube, mapped to each factor (a range
  linearly or logarithmically, a list of values by equal bins); ``list`` takes the spec's
  ``[[design.points]]``.
* **Repeats and seeds**: point p, repeat r is run index i = p · repeats + r. Its seed is the i-th
  child of ``numpy.random.SeedSequence(dataset.seed)`` (``spawn``), so it does not depend on the
  number of workers or the order runs finish in; it seeds the run's own draws (sensor offsets,
  mounting, random profile) and the sensor chain's noise (``instrumentation.seed``).
* **Run id**: the first 16 hex digits of SHA-256 over the resolved configuration (its canonical
  TOML, with the name left out) and the run's seed.
* **Splits** are assigned per configuration group (a design point: every repeat of a point shares
  its split, so no configuration is in two splits), stratified by fault class: within each class
  the groups are shuffled with the spec's seed and cut by the split fractions (largest
  remainders, carried from class to class so that small classes still fill every split). Groups
  holding a held-out value go to test only (for fault and the clearances, the run's labels: a
  clearance its fault class does not use is not held out).
"""

from __future__ import annotations

import hashlib
import itertools
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from twin.config import BenchConfig, load_config, named_preset, preset, with_overrides
from twin.dataset.factors import NAMED, check_value, controlled, labels, random_profile, resolve
from twin.dataset.spec import SPLITS, DatasetSpec, FactorSpec, SpecError
from twin.errors import ConfigError


#: most runs a dataset may plan
MAX_RUNS = 1_000_000
@dataclass(frozen=True)
class RunPlan:
    """One run of a dataset (everything a worker needs, and every label).

    Attributes:
        index: run index (design order).
        run_id: 16 hex digits (see module docstring).
        point: design point index (the configuration group of the splits).
        repeat: repeat number within the point.
        seed: the run's seed (an unsigned 64-bit integer).
        factors: the point's factor values, by factor name.
        labels: fault, clearance_b_mm, clearance_c_mm.
        config: the resolved configuration.
        split: train, val or test.
    """

    index: int
    run_id: str
    point: int
    repeat: int
    seed: int
    factors: dict[str, Any]
    labels: dict[str, Any]
    config: BenchConfig
    split: str = ""
    extra: dict[str, Any] = field(default_factory=dict)


#: ``mujoco.contact_source`` of a dataset's MuJoCo runs unless the spec decides it (docs/speed.md, "The bushing
#: as a force": the same accuracy targets and contact checks as "law", 1.6x faster per step)
DATASET_CONTACT_SOURCE = "force"


def dataset_force_applies(spec: DatasetSpec, cfg: BenchConfig) -> bool:
    """Whether a dataset's runs take :data:`DATASET_CONTACT_SOURCE`: MuJoCo engine, planar mechanism, bore bushing,
    not RK4, a base that is a preset (a configuration file's choice stands) with the default contact source, and no
    ``mujoco.contact_source`` in ``base.set``."""
    ms = cfg.mujoco
    return (spec.engine == "mujoco" and not spec.base_config and "mujoco.contact_source" not in spec.base_set
            and not cfg.spatial.enabled and ms.contact_source == "law" and ms.bushing == "bore"
            and ms.integrator != "RK4" and not (ms.contact_solref and ms.contact_solimp))


def base_config(spec: DatasetSpec) -> BenchConfig:
    """The spec's base configuration (Table 4 preset, named preset or file) with ``base.set``, the engine, the duration
    and the output rate applied; MuJoCo runs of a preset base take the bushing as a force
    (:func:`dataset_force_applies`)."""
    if spec.base_config:
        from twin.tracefile import with_trace_duration

        cfg = with_trace_duration(load_config(spec.base_config))  # a trace without a duration: its length
    elif spec.base_preset:
        cfg = named_preset(spec.base_preset, "base.preset")
    else:
        cfg = preset(spec.base_test) if spec.base_test else BenchConfig()
    for key in spec.base_set:
        c = controlled(key)
        if c is not None:
            raise SpecError(f"base.set.{key}", f"{c} is decided by the spec itself (base.engine, base.duration_s, "
                                               "base.program, the outputs and the run seeds); set it there")
    ov = dict(spec.base_set)
    if dataset_force_applies(spec, cfg):
        ov["mujoco.contact_source"] = DATASET_CONTACT_SOURCE
    ov["simulation.engine"] = spec.engine
    ov["sensors.output_rate_hz"] = spec.outputs.rate_hz
    ov["instrumentation.daq_rate_hz"] = spec.outputs.rate_hz
    try:
        return with_overrides(cfg, ov)
    except ConfigError as err:
        raise SpecError(f"base.set.{err.field}" if err.field in spec.base_set else f"base ({err.field})",
                        err.message) from None


def _unit_points(spec: DatasetSpec, d: int) -> np.ndarray:
    n = spec.runs or 0
    if d == 0:
        return np.zeros((n, 0))
    if spec.design == "lhs":
        from scipy.stats import qmc

        return qmc.LatinHypercube(d=d, seed=np.random.default_rng(spec.seed)).random(n)
    if spec.design == "sobol":
        import warnings

        from scipy.stats import qmc

        with warnings.catch_warnings():  # balance needs 2**m points; other counts are allowed
            warnings.simplefilter("ignore", UserWarning)
            return qmc.Sobol(d=d, scramble=True, seed=np.random.default_rng(spec.seed)).random(n)
    return np.random.default_rng(spec.seed).random((n, d))


def _map(f: FactorSpec, u: float) -> Any:
    if f.values is not None:
        return f.values[min(int(u * len(f.values)), len(f.values) - 1)]
    lo, hi = f.range
    if f.exclude is not None:
        # u over the two parts [lo, a] and [b, hi] laid end to end (in log where the scale is log)
        fw, bw = (math.log, math.exp) if f.scale == "log" else (float, float)
        L, A, B, H = (fw(x) for x in (lo, f.exclude[0], f.exclude[1], hi))
        v = L + u * ((A - L) + (H - B))
        return float(bw(v if v <= A else v + (B - A)))
    if f.scale == "log":
        return float(math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo))))
    return float(lo + u * (hi - lo))


def _levels(f: FactorSpec) -> tuple[Any, ...]:
    if f.values is not None:
        return f.values
    if f.exclude is not None:
        return tuple(_map(f, float(u)) for u in np.linspace(0.0, 1.0, f.levels))
    lo, hi = f.range
    if f.scale == "log":
        return tuple(float(x) for x in np.geomspace(lo, hi, f.levels))
    return tuple(float(x) for x in np.linspace(lo, hi, f.levels))


def design_points(spec: DatasetSpec) -> list[dict[str, Any]]:
    """The design's points (factor name -> value), before repeats."""
    if spec.design == "list":
        return [dict(p) for p in spec.points]
    if spec.design == "grid":
        names = [f.name for f in spec.factors]
        levels = [_levels(f) for f in spec.factors]
        n = math.prod(len(v) for v in levels) * spec.repeats
        if n > MAX_RUNS:
            raise SpecError("design", f"has {n} runs ({' x '.join(str(len(v)) for v in levels)} levels x "
                                      f"{spec.repeats} repeats); at most {MAX_RUNS}")
        return [dict(zip(names, combo)) for combo in itertools.product(*levels)]
    u = _unit_points(spec, len(spec.factors))
    return [{f.name: _map(f, float(row[k])) for k, f in enumerate(spec.factors)} for row in u]


def run_id(cfg: BenchConfig, seed: int) -> str:
    """Identity of a run: its resolved configuration (name aside) and its seed."""
    text = cfg.replace(name="run").to_toml()
    return hashlib.sha256(f"{text}\nseed = {seed}\n".encode()).hexdigest()[:16]


def resolve_config(spec: DatasetSpec, base: BenchConfig, values: dict[str, Any], seed: int,
                   where: str = "factors") -> BenchConfig:
    """Configuration of one run: the base with the factor values applied (named factors in their
    registry order, ``fault`` last, then dotted paths), the speed program, the run's noise seed and
    the channel groups the outputs need."""
    rng = np.random.default_rng(seed)
    ov: dict[str, Any] = {}
    named = [n for n in NAMED if n in values and n != "fault"] + (["fault"] if "fault" in values else [])
    for name in named + [n for n in values if n not in NAMED]:
        f = resolve(name, spec.engine)
        v = check_value(f, values[name], f"{where}.{name}")
        f.apply(v, ov, rng, base)
    if "structure" in values or "structure.mode" in values:
        _structure_fields_where_they_apply(base, ov)
    program = ov.pop("@program", spec.program)
    duration = spec.duration_s
    if program == "protocol":
        ov["drive.program"] = "protocol"
    elif program == "random-profile":
        total = duration if duration > 0 else 1.0
        times, speeds = random_profile(rng, total, spec.profile.rpm, spec.profile.hold_s, spec.profile.stop_probability)
        ov.update({"drive.program": "steps", "drive.steps_s": times, "drive.steps_rpm": speeds})
    else:
        ov["drive.program"] = "constant"
    ov["simulation.duration_s"] = duration
    ov["instrumentation.seed"] = int(seed % (2**63))
    groups = list(spec.outputs.truth)
    if spec.outputs.instrumented or spec.outputs.recordings:  # the sensor chain reads these
        groups += ["accel", "encoder"]
    ov["sensors.channels"] = [g for g in dict.fromkeys(groups)]
    try:
        return with_overrides(base, ov)
    except ConfigError as err:
        raise SpecError(f"{where} ({err.field})", err.message) from None


def _structure_fields_where_they_apply(base: BenchConfig, ov: dict[str, Any]) -> None:
    """A spec that crosses ``structure`` (rigid, flexible) with the flexible structure's fields: a rigid run
    keeps each of those fields at its default (the rigid bench has no such field; the configuration refuses
    one off its default), its factor value unused. A spec without a ``structure`` factor is not changed (a
    structure field on a rigid base is still refused, naming the field)."""
    import dataclasses

    from twin.config.structure import StructureConfig

    if ov.get("structure.mode", base.structure.mode) == "flexible":
        return
    for f in dataclasses.fields(StructureConfig):
        key = f"structure.{f.name}"
        if f.name != "mode" and (key in ov or getattr(base.structure, f.name) != f.default):
            ov[key] = f.default


def plan(spec: DatasetSpec) -> list[RunPlan]:
    """Every run of the spec, with its configuration, id, labels and split."""
    base = base_config(spec)
    for f in spec.factors:  # names and engines first, so a bad factor is named even with 0 points
        resolve(f.name, spec.engine)
        if f.range is not None and f.name not in NAMED:
            # both ends of a configuration field's range within the field's bounds (the schema's physical
            # plausibility): a range that reaches out of them is refused before any run, not only if a draw lands there
            for end in f.range:
                try:
                    with_overrides(base, {f.name: end})
                except ConfigError as err:
                    raise SpecError(f"factors.{f.name}.range", f"reaches {end:g}, which the configuration refuses: "
                                                               f"{err.field}: {err.message}") from None
    points = design_points(spec)
    if not points:
        raise SpecError("design", "has zero runs (a factor without values, or runs = 0)")
    n = len(points) * spec.repeats
    if n > MAX_RUNS:
        raise SpecError("design", f"has {n} runs; at most {MAX_RUNS}")
    seeds = [int(s.generate_state(1, np.uint64)[0]) for s in np.random.SeedSequence(spec.seed).spawn(n)]
    runs: list[RunPlan] = []
    for p, values in enumerate(points):
        where = f"design.points[{p}]" if spec.design == "list" else "factors"
        for r in range(spec.repeats):
            i = p * spec.repeats + r
            cfg = resolve_config(spec, base, values, seeds[i], where)
            rid = run_id(cfg, seeds[i])
            cfg = cfg.replace(name=f"{spec.name}-{rid}")
            runs.append(RunPlan(i, rid, p, r, seeds[i], dict(values), labels(cfg), cfg))
    ids = [r.run_id for r in runs]
    if len(set(ids)) != len(ids):
        raise SpecError("design", "two runs resolve to the same configuration and seed")
    return assign_splits(spec, runs)


def _holdout(spec: DatasetSpec, values: dict[str, Any]) -> bool:
    """Whether a point holds a held-out value: of its labels for fault and the clearances (a
    clearance the fault class leaves unused is not held out), of its factors otherwise."""
    for k, held in spec.splits.holdout.items():
        v = values.get(k)
        if any(v == h or (isinstance(v, float) and isinstance(h, (int, float)) and math.isclose(v, h, rel_tol=1e-9))
               for h in held):
            return True
    return False


def assign_splits(spec: DatasetSpec, runs: list[RunPlan]) -> list[RunPlan]:
    """Split per design point, stratified by fault class (module docstring)."""
    import dataclasses

    point_runs: dict[int, list[RunPlan]] = {}
    for r in runs:
        point_runs.setdefault(r.point, []).append(r)
    split_of: dict[int, str] = {}
    by_class: dict[str, list[int]] = {}
    for p, rs in point_runs.items():
        if _holdout(spec, {**rs[0].factors, **rs[0].labels}):
            split_of[p] = "test"
        else:
            by_class.setdefault(rs[0].labels["fault"], []).append(p)
    rng = np.random.default_rng([spec.seed, 1])
    cum_n, given = 0, [0] * len(SPLITS)
    for cls in sorted(by_class):
        pts = list(by_class[cls])
        rng.shuffle(pts)
        # the split sizes of the classes seen so far, taken together, by largest remainders: the
        # classes share the remainders (two groups per class still fill val and test)
        cum_n += len(pts)
        target = _largest_remainder(cum_n, spec.splits.fractions)
        counts = [t - g for t, g in zip(target, given)]
        if min(counts) < 0:
            counts = _largest_remainder(len(pts), spec.splits.fractions)
        given = [g + c for g, c in zip(given, counts)]
        k = 0
        for name, c in zip(SPLITS, counts):
            for p in pts[k:k + c]:
                split_of[p] = name
            k += c
    return [dataclasses.replace(r, split=split_of[r.point]) for r in runs]


def _largest_remainder(n: int, fractions: tuple[float, ...]) -> list[int]:
    raw = [n * f for f in fractions]
    counts = [int(math.floor(x)) for x in raw]
    for i in sorted(range(len(raw)), key=lambda i: (counts[i] - raw[i], i))[:n - sum(counts)]:
        counts[i] += 1
    return counts
