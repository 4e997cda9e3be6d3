"""The parameters a calibration fits: configuration fields (dotted paths) with bounds.

Default bounds are the ranges the configuration's documentation asks users to explore, the same ones
the dataset factors draw from (:data:`twin.dataset.factors.NAMED`, :data:`twin.config.drivetrain.EXPLORE_RANGES`);
a field without a documented range needs explicit bounds. The search works in normalized coordinates
u ∈ [0, 1] per parameter (linear, or logarithmic for fields that span decades: stiffness scale, belt
stiffness, gains).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Iterable, Mapping

from twin.config import BenchConfig
from twin.errors import ConfigError


def documented_ranges() -> dict[str, tuple[float, float]]:
    """Dotted field -> (low, high): the ranges the configuration documents (dataset factors)."""
    from twin.config.drivetrain import EXPLORE_RANGES

    out = {
        "contact.restitution": (0.05, 1.0),
        "contact.mu0": (0.0, 1.0),
        "contact.stiffness_scale": (0.1, 10.0),
        "mechanism.guide_friction_n": (0.0, 100.0),
        "joints.clearance_guide_mm": (0.0, 1.0),
        "joints.clearance_b_mm": (0.0, 1.0),
        "joints.clearance_c_mm": (0.0, 1.0),
        "instrumentation.noise_scale": (0.0, 100.0),
    }
    for _name, field, _doc, bounds in EXPLORE_RANGES:
        out[f"drivetrain.{field}"] = (float(bounds[0]), float(bounds[1]))
    from twin.config.structure import EXPLORE_RANGES as STRUCTURE_RANGES

    for _name, field, _doc, bounds in STRUCTURE_RANGES:  # the flexible structure's placeholders
        out[f"structure.{field}"] = (float(bounds[0]), float(bounds[1]))
    # the PID gains: the dataset's pid_scale factor (0.1 - 10 times the default gains)
    from twin.config.drive import PID

    pid = PID()
    for g in ("kp", "kv", "ki"):
        v = float(getattr(pid, g))
        if v > 0:
            out[f"pid.{g}"] = (0.1 * v, 10.0 * v)
    return out


#: fields searched on a logarithmic scale (they span decades); others are linear
LOG_FIELDS = frozenset({"contact.stiffness_scale", "drivetrain.belt_ea_n", "drivetrain.rotor_inertia_kgm2",
                        "drivetrain.speed_kp_nms", "drivetrain.speed_filter_hz", "pid.kp", "pid.kv", "pid.ki",
                        "structure.rod_youngs_modulus_pa", "structure.frame_mass_kg", "structure.frame_frequency_hz",
                        "structure.guide_mass_kg", "structure.guide_frequency_hz", "structure.mount_frequency_hz",
                        "structure.bending_damping_ratio", "structure.axial_damping_ratio",
                        "structure.frame_damping_ratio", "structure.guide_damping_ratio",
                        "structure.mount_damping_ratio"})

#: fields a calibration may not fit: they describe the recording, not the bench's uncertain numbers
NOT_FITTABLE_PREFIXES = ("simulation.", "sensors.", "drive.", "name", "instrumentation.daq_rate_hz",
                         "instrumentation.seed", "instrumentation.zero_g_v")


@dataclass(frozen=True)
class Parameter:
    """One fitted configuration field.

    Attributes:
        field: dotted configuration path (``contact.restitution``).
        lo, hi: bounds [the field's unit], lo < hi.
        log: search on a logarithmic scale (needs lo > 0).
    """

    field: str
    lo: float
    hi: float
    log: bool = False

    def __post_init__(self) -> None:
        for name in ("lo", "hi"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ConfigError(self.field, f"bound {name} must be a finite number, got {v!r}")
        if not self.lo < self.hi:
            raise ConfigError(self.field, f"bounds must satisfy low < high, got {self.lo:g}:{self.hi:g}")
        if self.log and self.lo <= 0:
            raise ConfigError(self.field, f"a logarithmic scale needs low > 0, got {self.lo:g}")

    def to_unit(self, x: float) -> float:
        """Value [field unit] -> normalized coordinate (0 at lo, 1 at hi)."""
        if self.log:
            return (math.log(x) - math.log(self.lo)) / (math.log(self.hi) - math.log(self.lo))
        return (x - self.lo) / (self.hi - self.lo)

    def from_unit(self, u: float) -> float:
        """Normalized coordinate -> value, clipped to the bounds."""
        u = min(1.0, max(0.0, float(u)))
        if self.log:
            return float(math.exp(math.log(self.lo) + u * (math.log(self.hi) - math.log(self.lo))))
        return float(self.lo + u * (self.hi - self.lo))


def _field_value(cfg: BenchConfig, field: str) -> Any:
    node: Any = cfg
    for k in field.split("."):
        if isinstance(node, Mapping):
            if k not in node:
                raise KeyError(k)
            node = node[k]
        elif hasattr(node, k):
            node = getattr(node, k)
        else:
            raise KeyError(k)
    return node


def field_value(cfg: BenchConfig, field: str) -> float:
    """The numeric value of ``field`` in ``cfg``; ConfigError naming ``params`` if there is none."""
    try:
        v = _field_value(cfg, field)
    except KeyError:
        raise ConfigError("params", f"{field!r} is not a configuration field (dotted path, e.g. "
                                    "contact.restitution)") from None
    if dataclasses.is_dataclass(v) or isinstance(v, Mapping):
        raise ConfigError("params", f"{field!r} is a section, not a field; name one of its numeric fields "
                                    f"(e.g. {field}.<field>)")
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ConfigError("params", f"{field!r} is not a numeric field (value {v!r}); only numbers can be fitted")
    if _declared_int(cfg, field):
        raise ConfigError("params", f"{field!r} is an integer field (value {v!r}); only real-valued fields can be "
                                    "fitted (set it in the base configuration and fit the others)")
    return float(v)


def _declared_int(cfg: BenchConfig, field: str) -> bool:
    """True when ``field`` is declared ``int`` in its section's dataclass (a count or a choice: the search's
    real values would be refused)."""
    import typing

    parent_path, _, name = field.rpartition(".")
    parent = _field_value(cfg, parent_path) if parent_path else cfg
    if not dataclasses.is_dataclass(parent):
        return False
    return typing.get_type_hints(type(parent)).get(name) is int


def make_parameters(fields: Iterable[str], base: BenchConfig,
                    bounds: Mapping[str, tuple[float, float]] | None = None) -> tuple[Parameter, ...]:
    """Checked parameters for ``fields`` (dotted paths) of ``base``: bounds from ``bounds`` or the
    documented ranges; the base value must be a number inside the bounds' field (checked by a
    replace of the configuration at both bounds)."""
    if isinstance(fields, str):
        fields = [f for f in fields.split(",")]
    fields = [str(f).strip() for f in fields]
    if fields and not fields[-1] and len(fields) > 1:  # a trailing comma ("contact.mu0,"): nothing left out
        fields = fields[:-1]
    if not fields or not any(fields):
        raise ConfigError("params", "give one or more configuration fields, e.g. contact.restitution,contact.mu0")
    if any(not f for f in fields):
        raise ConfigError("params", f"an empty field between commas in {','.join(fields)!r}; give FIELD,FIELD "
                                    "(e.g. contact.restitution,contact.mu0)")
    if len(set(fields)) != len(fields):
        raise ConfigError("params", f"a field is given twice: {','.join(fields)}")
    bounds = dict(bounds or {})
    for k in bounds:
        if k not in fields:
            raise ConfigError("bounds", f"{k!r} is not among the fitted parameters ({','.join(fields)})")
    known = documented_ranges()
    out = []
    for f in fields:
        if any(f == p or f.startswith(p) for p in NOT_FITTABLE_PREFIXES):
            raise ConfigError("params", f"{f!r} describes the recording or its drive, not an uncertain number of "
                                        "the bench; it cannot be fitted")
        field_value(base, f)
        if f.startswith("drivetrain.") and base.drive.mode not in ("motor", "torque"):
            raise ConfigError("params", f"{f!r} acts only with drive.mode = \"motor\" or \"torque\"; the base "
                                        f"configuration's is {base.drive.mode!r} (its crank PID drives the crank: the "
                                        "drive train is not in the loop of this recording; fit it on a motor-driven one)")
        if f.startswith("structure.") and base.structure.mode != "flexible":
            raise ConfigError("params", f"{f!r} acts only with structure.mode = \"flexible\"; the base configuration "
                                        f"is {base.structure.mode!r} (start from a configuration with a flexible structure)")
        if f in bounds:
            lo, hi = bounds[f]
        elif f in known:
            lo, hi = known[f]
        else:
            raise ConfigError("bounds", f"{f!r} has no documented range; give bounds (FIELD=LO:HI); fields with "
                                        f"one: {', '.join(sorted(known))}")
        p = Parameter(f, float(lo), float(hi), log=f in LOG_FIELDS and float(lo) > 0)
        for v in (p.lo, p.hi):
            try:
                base.replace(**{f: v})
            except ConfigError as err:
                raise ConfigError("bounds", f"{f}={p.lo:g}:{p.hi:g}: the configuration refuses {v:g} ({err})") from None
        out.append(p)
    return tuple(out)


def parse_bounds(items: Iterable[str]) -> dict[str, tuple[float, float]]:
    """``["contact.mu0=0:0.5", ...]`` -> {field: (lo, hi)}; ConfigError naming ``bounds``."""
    out: dict[str, tuple[float, float]] = {}
    for item in items:
        field, sep, rng = str(item).partition("=")
        lo_s, sep2, hi_s = rng.partition(":")
        try:
            if not (sep and sep2 and field.strip()):
                raise ValueError
            lo, hi = float(lo_s), float(hi_s)
        except ValueError:
            raise ConfigError("bounds", f"expected FIELD=LO:HI (e.g. contact.restitution=0.2:0.8), got {item!r}") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ConfigError("bounds", f"{item!r}: need finite LO < HI")
        if field.strip() in out:
            raise ConfigError("bounds", f"{field.strip()!r} is given twice; give one FIELD=LO:HI per field")
        out[field.strip()] = (lo, hi)
    return out


def apply(cfg: BenchConfig, params: tuple[Parameter, ...], values: Iterable[float]) -> BenchConfig:
    """``cfg`` with the parameters set to ``values`` [field units]."""
    return cfg.replace(**{p.field: float(v) for p, v in zip(params, values)})


def overlay(base: BenchConfig | None, values: Mapping[str, float]) -> dict[str, Any]:
    """The partial configuration a calibration writes: the fields of ``base`` that differ from the
    defaults (when a base is given) and the fitted values, as nested TOML tables."""
    out: dict[str, Any] = {}
    if base is not None:
        default = BenchConfig().to_dict()

        def diff(a: dict, b: dict) -> dict:
            d = {}
            for k, v in a.items():
                if isinstance(v, dict) and isinstance(b.get(k), dict):
                    sub = diff(v, b[k])
                    if sub:
                        d[k] = sub
                elif b.get(k) != v:
                    d[k] = v
            return d

        out = diff(base.to_dict(), default)
    for f, v in values.items():
        node = out
        keys = f.split(".")
        for k in keys[:-1]:
            node = node.setdefault(k, {})
        node[keys[-1]] = float(v)
    return out
