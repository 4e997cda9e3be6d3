"""Dataset specifications: what to vary, how to sample it, what to store, how to split it.

A spec is a TOML file (examples in ``analysis/datasets/``; every key is documented in
``twin/dataset/FORMAT.md``)::

    [dataset]
    name = "tiny"            # names the runs ("tiny-<run id>")
    seed = 7                 # root of every random draw (numpy SeedSequence)

    [base]
    test = 6                 # a Table 4 preset, or: config = "bench.toml" (relative to the spec),
                             # or: preset = "s000" (a paper's mechanism, twin.config.NAMED_PRESETS)
    engine = "mujoco"        # mujoco | reference
    duration_s = 0.5         # simulated time of every run (0 = the protocol's length)
    program = "constant"     # constant | protocol | random-profile (the default speed program)
    set = { "drive.ramp_s" = 0.1 }   # further configuration overrides (dotted paths)

    [base.profile]           # random speed profiles (program = "random-profile")
    rpm = [250.0, 750.0]     # motor speed range of each step [rpm] (within the motor's ±1000)
    hold_s = [0.2, 1.0]      # time between steps [s]
    stop_probability = 0.2   # chance that a step stops the motor

    [design]
    kind = "grid"            # grid | lhs | sobol | random | list
    runs = 8                 # design points of lhs, sobol, random
    repeats = 1              # every point is run this many times with different seeds

    [factors]                # factor = list of values | { range = [lo, hi], scale, levels, exclude }
    fault = ["none", "B", "C", "BC"]
    clearance_c_mm = [0.1]
    motor_rpm = { range = [250, 750], levels = 3 }
    # exclude = [a, b]: a band inside the range that is never drawn (the range is mapped onto the
    # two parts, so a design keeps its stratification): e.g. a value held out for a test set

    [outputs]
    truth = ["accel", "encoder", "joints"]   # engine channel groups stored
    instrumented = true                       # raw volts, encoder counts, motor command, meas_AC
    rate_hz = 100000.0
    dtype = "auto"           # auto (float32 where lossless or the channel is float32) | float32
    recordings = false       # true: also a bench recording per run, recordings/<run_id>.mcap (as twin record)

    [splits]
    train = 0.7
    val = 0.15
    test = 0.15
    holdout = { orientation = ["z"] }         # values seen only in test

Every problem is a :class:`SpecError` naming the key (``factors.motor_rpm.range``) and what is
allowed. The spec is only data: designs, factors and splits are in their own modules.
"""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Mapping

from twin.errors import TwinError, did_you_mean, unknown

#: designs a spec may ask for
DESIGNS = ("grid", "lhs", "sobol", "random", "list")
#: speed programs a dataset run can have
DATASET_PROGRAMS = ("constant", "protocol", "random-profile")
#: instrumented channel sets (the bench's sensor chain)
INSTRUMENTED = ("volts", "counts", "command", "calibrated")
#: storage types of the signals
DTYPES = ("auto", "float32")
#: split names, in order
SPLITS = ("train", "val", "test")


class SpecError(TwinError):
    """A dataset spec is malformed: names the key and what is allowed."""

    def __init__(self, key: str, message: str):
        self.key = key
        self.message = message
        super().__init__(f"{key}: {message}")

    def __reduce__(self):  # picklable with its two arguments (see ConfigError.__reduce__)
        return (type(self), (self.key, self.message))


def _num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


@dataclass(frozen=True)
class Profile:
    """Random speed profiles: steps at random times to random motor speeds (twin.config "steps")."""

    rpm: tuple[float, float] = (250.0, 750.0)
    hold_s: tuple[float, float] = (0.2, 1.0)
    stop_probability: float = 0.2

    def __post_init__(self) -> None:
        for key, lim in (("rpm", 1000.0), ("hold_s", 3600.0)):
            v = getattr(self, key)
            if not (len(v) == 2 and all(_num(x) for x in v) and v[0] <= v[1] and abs(v[0]) <= lim and abs(v[1]) <= lim):
                raise SpecError(f"base.profile.{key}", f"must be [low, high] with low <= high within ±{lim:g}, got {v!r}")
        if self.hold_s[0] < 0.01:
            raise SpecError("base.profile.hold_s", f"must be >= 0.01 s (a step every 10 ms at most), "
                                                   f"got {list(self.hold_s)!r}")
        if not (_num(self.stop_probability) and 0 <= self.stop_probability <= 1):
            raise SpecError("base.profile.stop_probability", f"must lie in [0, 1], got {self.stop_probability!r}")


@dataclass(frozen=True)
class FactorSpec:
    """One varied factor: explicit ``values``, or a ``range`` [lo, hi] (``scale`` linear or log;
    ``levels`` points for a grid; ``exclude`` an open band (a, b) inside it that is never drawn)."""

    name: str
    values: tuple[Any, ...] | None = None
    range: tuple[float, float] | None = None
    scale: str = "linear"
    levels: int | None = None
    exclude: tuple[float, float] | None = None

    @property
    def discrete(self) -> bool:
        return self.values is not None or self.levels is not None


@dataclass(frozen=True)
class Outputs:
    truth: tuple[str, ...] = ("accel", "encoder", "joints")
    instrumented: tuple[str, ...] = INSTRUMENTED
    rate_hz: float = 100_000.0
    dtype: str = "auto"
    recordings: bool = False


@dataclass(frozen=True)
class Splits:
    fractions: tuple[float, float, float] = (0.7, 0.15, 0.15)
    holdout: Mapping[str, tuple[Any, ...]] = field(default_factory=dict)


@dataclass(frozen=True)
class DatasetSpec:
    """A parsed, validated spec (see module docstring)."""

    name: str
    seed: int
    base_test: int | None
    base_config: str | None
    engine: str
    duration_s: float
    program: str
    base_set: Mapping[str, Any]
    profile: Profile
    design: str
    runs: int | None
    repeats: int
    factors: tuple[FactorSpec, ...]
    points: tuple[Mapping[str, Any], ...]
    outputs: Outputs
    splits: Splits
    source: str = ""  # the file it came from (not part of its identity)
    base_preset: str | None = None  # a named preset (base.preset = "s000"); part of the identity when set

    def canonical(self) -> dict[str, Any]:
        """The spec as plain data, the identity of a dataset (stored in info.json; a DIR holding
        a different one is refused)."""
        d = asdict(self)
        d.pop("source")
        if d["base_preset"] is None:  # specs without one keep the identity they had before the key existed
            d.pop("base_preset")
        if not d["outputs"]["recordings"]:  # likewise specs without bench recordings
            d["outputs"].pop("recordings")
        for f in d["factors"]:  # likewise factors without an excluded band
            if f.get("exclude") is None:
                f.pop("exclude", None)
        return json.loads(json.dumps(d, sort_keys=True, default=list))


# ------------------------------------------------------------------------- parsing
_TOP = ("dataset", "base", "design", "factors", "outputs", "splits")


def _table(data: Mapping[str, Any], key: str, allowed: tuple[str, ...]) -> dict[str, Any]:
    t = data.get(key, {})
    if not isinstance(t, Mapping):
        raise SpecError(key, f"must be a table, got {t!r}")
    for k in t:
        if k not in allowed:
            raise SpecError(f"{key}.{k}", unknown("key", k, allowed))
    return dict(t)


def _factor(name: str, raw: Any) -> FactorSpec:
    key = f"factors.{name}"
    if isinstance(raw, list):
        if not raw:
            raise SpecError(key, "needs at least one value")
        for v in raw:
            if not (isinstance(v, (str, bool)) or _num(v)):
                raise SpecError(key, f"values must be numbers, strings or booleans, got {v!r}")
        return FactorSpec(name, values=tuple(raw))
    if isinstance(raw, (str, bool)) or _num(raw):
        return FactorSpec(name, values=(raw,))
    if not isinstance(raw, Mapping):
        raise SpecError(key, f"must be a list of values or a table {{ range = [lo, hi] }}, got {raw!r}")
    for k in raw:
        if k not in ("values", "range", "scale", "levels", "exclude"):
            raise SpecError(f"{key}.{k}", unknown("key", k, ("values", "range", "scale", "levels", "exclude")))
    if "values" in raw:
        if set(raw) - {"values"}:
            raise SpecError(key, "give either values or range (with scale, levels, exclude), not both")
        return _factor(name, raw["values"])
    rng = raw.get("range")
    if not (isinstance(rng, list) and len(rng) == 2 and all(_num(x) for x in rng)):
        raise SpecError(f"{key}.range", f"must be [low, high] (two finite numbers), got {rng!r}")
    lo, hi = float(rng[0]), float(rng[1])
    if not lo < hi:
        raise SpecError(f"{key}.range", f"is empty or inverted: [{lo:g}, {hi:g}] (need low < high)")
    scale = raw.get("scale", "linear")
    if scale not in ("linear", "log"):
        raise SpecError(f"{key}.scale", f"must be one of linear, log; got {scale!r}")
    if scale == "log" and lo <= 0:
        raise SpecError(f"{key}.range", f"a log scale needs low > 0, got {lo:g}")
    levels = raw.get("levels")
    if levels is not None and (isinstance(levels, bool) or not isinstance(levels, int) or not 2 <= levels <= 1000):
        raise SpecError(f"{key}.levels", f"must be an integer in [2, 1000], got {levels!r}")
    exclude = raw.get("exclude")
    if exclude is not None:
        if not (isinstance(exclude, list) and len(exclude) == 2 and all(_num(x) for x in exclude)
                and lo < float(exclude[0]) < float(exclude[1]) < hi):
            raise SpecError(f"{key}.exclude", f"must be [a, b] with {lo:g} < a < b < {hi:g}, got {exclude!r}")
        exclude = (float(exclude[0]), float(exclude[1]))
    return FactorSpec(name, range=(lo, hi), scale=scale, levels=levels, exclude=exclude)


def parse_spec(data: Mapping[str, Any], source: str = "") -> DatasetSpec:
    """Validate a spec given as nested dicts (TOML)."""
    for k in data:
        if k not in _TOP:
            raise SpecError(k, unknown("section", k, _TOP))
    ds = _table(data, "dataset", ("name", "seed", "description"))
    name = ds.get("name")
    if not (isinstance(name, str) and 0 < len(name) <= 40 and name.replace("-", "").replace("_", "").isalnum()):
        raise SpecError("dataset.name", f"must be 1-40 letters, digits, - or _, got {name!r}")
    seed = ds.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
        raise SpecError("dataset.seed", f"must be an integer in [0, 2**63), got {seed!r}")

    base = _table(data, "base", ("test", "config", "preset", "engine", "duration_s", "program", "set", "profile"))
    test, config, base_preset = base.get("test"), base.get("config"), base.get("preset")
    if sum(v is not None for v in (test, config, base_preset)) > 1:
        raise SpecError("base", "give one of test, config or preset, not several")
    if base_preset is not None:
        from twin.config import NAMED_PRESETS

        if not (isinstance(base_preset, str) and base_preset.lower() in NAMED_PRESETS):
            raise SpecError("base.preset", f"must be one of {', '.join(NAMED_PRESETS)}, got {base_preset!r}"
                                           f"{did_you_mean(base_preset, NAMED_PRESETS)}")
        base_preset = base_preset.lower()
    if test is not None and (isinstance(test, bool) or not isinstance(test, int) or not 1 <= test <= 12):
        raise SpecError("base.test", f"must be a Table 4 test id 1..12, got {test!r}")
    if config is not None and not (isinstance(config, str) and config):
        raise SpecError("base.config", f"must name a configuration file, got {config!r}")
    engine = base.get("engine", "mujoco")
    if engine not in ("mujoco", "reference"):
        raise SpecError("base.engine", f"must be one of mujoco, reference; got {engine!r}")
    duration = base.get("duration_s", 1.0)
    if not (_num(duration) and 0 <= duration <= 3600):
        raise SpecError("base.duration_s", f"must lie in [0, 3600] s (0 = the protocol's length), got {duration!r}")
    program = base.get("program", "constant")
    if program not in DATASET_PROGRAMS:
        raise SpecError("base.program", f"must be one of {', '.join(DATASET_PROGRAMS)}; got {program!r}")
    base_set = base.get("set", {})
    if not isinstance(base_set, Mapping):
        raise SpecError("base.set", f"must be a table of dotted-path overrides, got {base_set!r}")
    prof_raw = base.get("profile", {})
    if not isinstance(prof_raw, Mapping):
        raise SpecError("base.profile", f"must be a table, got {prof_raw!r}")
    for k in prof_raw:
        if k not in ("rpm", "hold_s", "stop_probability"):
            raise SpecError(f"base.profile.{k}", unknown("key", k, ("rpm", "hold_s", "stop_probability")))
    profile = Profile(**{k: tuple(v) if isinstance(v, list) else v for k, v in prof_raw.items()})

    des = _table(data, "design", ("kind", "runs", "repeats", "points"))
    kind = des.get("kind", "grid")
    if kind not in DESIGNS:
        raise SpecError("design.kind", f"must be one of {', '.join(DESIGNS)}; got {kind!r}")
    runs = des.get("runs")
    if kind in ("lhs", "sobol", "random"):
        if isinstance(runs, bool) or not isinstance(runs, int) or not 1 <= runs <= 1_000_000:
            raise SpecError("design.runs", f"must be an integer in [1, 1000000] for a {kind} design, got {runs!r}")
    elif runs is not None:
        raise SpecError("design.runs", f"applies to lhs, sobol and random designs, not {kind}")
    repeats = des.get("repeats", 1)
    if isinstance(repeats, bool) or not isinstance(repeats, int) or not 1 <= repeats <= 10_000:
        raise SpecError("design.repeats", f"must be an integer in [1, 10000], got {repeats!r}")
    points = des.get("points", [])
    if kind == "list":
        if not (isinstance(points, list) and points and all(isinstance(p, Mapping) for p in points)):
            raise SpecError("design.points", "a list design needs [[design.points]] tables (one per run)")
    elif points:
        raise SpecError("design.points", f"apply to the list design, not {kind}")

    fac_raw = data.get("factors", {})
    if not isinstance(fac_raw, Mapping):
        raise SpecError("factors", f"must be a table, got {fac_raw!r}")
    factors = tuple(_factor(k, v) for k, v in fac_raw.items())
    if kind == "grid":
        for f in factors:
            if not f.discrete:
                raise SpecError(f"factors.{f.name}", "a grid needs values or a range with levels")

    out = _table(data, "outputs", ("truth", "instrumented", "rate_hz", "dtype", "recordings"))
    truth = out.get("truth", list(Outputs.truth))
    if not (isinstance(truth, list) and all(isinstance(g, str) for g in truth)):
        raise SpecError("outputs.truth", f"must be a list of channel groups, got {truth!r}")
    inst = out.get("instrumented", True)
    if isinstance(inst, bool):
        inst = list(INSTRUMENTED) if inst else []
    if not (isinstance(inst, list) and all(i in INSTRUMENTED for i in inst)):
        raise SpecError("outputs.instrumented", f"must be true, false or a list of {', '.join(INSTRUMENTED)}; "
                                                f"got {out.get('instrumented')!r}")
    recs = out.get("recordings", False)
    if not isinstance(recs, bool):
        raise SpecError("outputs.recordings", f"must be true or false (a bench recording per run), got {recs!r}")
    if not truth and not inst and not recs:
        raise SpecError("outputs", "stores nothing: give truth groups, instrumented channels or recordings = true")
    rate = out.get("rate_hz", 100_000.0)
    if not (_num(rate) and 0 < rate <= 1e6):
        raise SpecError("outputs.rate_hz", f"must lie in (0, 1e6] Hz, got {rate!r}")
    dtype = out.get("dtype", "auto")
    if dtype not in DTYPES:
        raise SpecError("outputs.dtype", f"must be one of {', '.join(DTYPES)}; got {dtype!r}")
    outputs = Outputs(tuple(dict.fromkeys(truth)), tuple(i for i in INSTRUMENTED if i in inst), float(rate), dtype,
                      recs)

    sp = _table(data, "splits", SPLITS + ("holdout",))
    fr = tuple(sp.get(s, d) for s, d in zip(SPLITS, Splits.fractions))
    if not all(_num(x) and 0 <= x <= 1 for x in fr) or abs(sum(fr) - 1) > 1e-9:
        raise SpecError("splits", f"train, val, test must be fractions in [0, 1] summing to 1, got {fr!r}")
    hold = sp.get("holdout", {})
    if not isinstance(hold, Mapping):
        raise SpecError("splits.holdout", f"must be a table factor = [values], got {hold!r}")
    names = {f.name for f in factors} | {k for p in points for k in p}
    if names & {"fault", "clearance_b_mm", "clearance_c_mm"}:
        names |= {"fault", "clearance_b_mm", "clearance_c_mm"}  # held out by the runs' labels
    holdout = {}
    for k, v in hold.items():
        if k not in names:
            raise SpecError(f"splits.holdout.{k}", f"is not a varied factor; varied: {', '.join(sorted(names)) or 'none'}")
        if not (isinstance(v, list) and v):
            raise SpecError(f"splits.holdout.{k}", f"must be a non-empty list of values, got {v!r}")
        holdout[k] = tuple(v)
    _check_cross_fields(factors, points, holdout)
    return DatasetSpec(name=name, seed=seed, base_test=test, base_config=config, engine=engine,
                       duration_s=float(duration), program=program, base_set=dict(base_set), profile=profile,
                       design=kind, runs=runs, repeats=repeats, factors=factors,
                       points=tuple(dict(p) for p in points), outputs=outputs,
                       splits=Splits(tuple(float(x) for x in fr), holdout), source=source, base_preset=base_preset)


def _factor_bounds(f: FactorSpec) -> tuple[float, float] | None:
    if f.values is not None:
        nums = [v for v in f.values if _num(v)]
        return (min(nums), max(nums)) if nums and len(nums) == len(f.values) else None
    return (float(f.range[0]), float(f.range[1])) if f.range is not None else None


def _check_cross_fields(factors: tuple[FactorSpec, ...], points: Any, holdout: dict[str, tuple[Any, ...]]) -> None:
    """Factors that contradict each other, and hold-outs that hold out nothing or everything."""
    by = {f.name: f for f in factors}
    fault = by.get("fault")
    if fault is not None and fault.values is not None and not points:
        for j in "BC":
            size = by.get(f"clearance_{j.lower()}_mm")
            bounds = _factor_bounds(size) if size is not None else None
            if bounds is None:
                continue
            with_j = [v for v in fault.values if isinstance(v, str) and j in v]
            if not with_j and bounds[1] > 0:
                raise SpecError(f"factors.clearance_{j.lower()}_mm",
                                f"varies the clearance at {j}, but no fault value has one (fault = "
                                f"{list(fault.values)!r}): the runs' label would say none; add {j} or BC to fault, "
                                "or drop the factor")
            if with_j and bounds[0] <= 0:
                raise SpecError(f"factors.clearance_{j.lower()}_mm",
                                f"holds 0 (no clearance) while fault {with_j[0]!r} puts a clearance at {j}: "
                                "sizes of a faulty joint must be > 0 mm (fault none says 'no clearance')")
    for k, held in holdout.items():
        f = by.get(k)
        if f is None or f.values is None and f.range is None:
            continue
        if f.values is not None:
            def has(h: Any, vals=f.values) -> bool:
                return any(h == v or (_num(h) and _num(v) and math.isclose(float(h), float(v), rel_tol=1e-9))
                           for v in vals)
            missing = [h for h in held if not has(h)]
            if missing:
                raise SpecError(f"splits.holdout.{k}", f"holds {missing[0]!r}, which factor {k} does not take "
                                                       f"(values {list(f.values)!r})")
            if all(any(h == v or (_num(h) and _num(v) and math.isclose(float(h), float(v), rel_tol=1e-9))
                       for h in held) for v in f.values):
                raise SpecError(f"splits.holdout.{k}", "holds out every value of the factor: the train and val "
                                                       "splits would be empty")
        else:
            lo, hi = f.range  # type: ignore[misc]
            bad = [h for h in held if not (_num(h) and lo <= h <= hi)]
            if bad:
                raise SpecError(f"splits.holdout.{k}", f"holds {bad[0]!r}, outside factor {k}'s range [{lo:g}, {hi:g}]")


def read_spec_toml(p: Path, what: str = "a dataset spec") -> dict[str, Any]:
    """The TOML of a spec file, or a one-line :class:`SpecError` naming the file."""
    if p.suffix.lower() != ".toml":
        raise SpecError(str(p), f"{what} is a .toml file")
    from twin.util import check_input_file, read_input_bytes, show, toml_loads

    try:
        check_input_file(p, show(p))
    except TwinError as err:  # a FIFO or /dev/zero would hang: refused before any read
        raise SpecError(show(p), str(err).split(": ", 1)[1]) from None
    try:
        text = read_input_bytes(p, show(p)).decode("utf-8")
    except UnicodeDecodeError:
        raise SpecError(str(p), "is not UTF-8 text (TOML)") from None
    try:
        data = toml_loads(text)
    except tomllib.TOMLDecodeError as err:
        raise SpecError(show(p), f"is not valid TOML: {err}") from None
    return data


def load_spec(path: str | Path) -> DatasetSpec:
    """Read and validate a spec file (one-line errors naming the file or key)."""
    p = Path(path)
    spec = parse_spec(read_spec_toml(p), source=str(p))
    if spec.base_config is not None:
        cfg_path = Path(spec.base_config)
        if not cfg_path.is_absolute():
            cfg_path = p.parent / cfg_path
        spec = _replace(spec, base_config=str(cfg_path))
    return spec


def _replace(spec: DatasetSpec, **kw: Any) -> DatasetSpec:
    import dataclasses

    return dataclasses.replace(spec, **kw)
