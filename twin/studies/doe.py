"""Design of experiments with a Kriging surrogate (``twin study doe SPEC --out DIR``; S000's method).

S000 (Zhang, Xu, Flores & Lankarani) samples a few design points of a
slider–crank with a clearance joint by Latin hypercube, simulates each, builds a Kriging model of
each response (the absolute maxima of slider acceleration, contact force and power), checks it at
a point it was not built on, and searches its optimum with a genetic algorithm. This module does
the same with the twin:

* **SPEC** is a dataset spec (``twin/dataset/spec.py``) with one more table, ``[doe]``; the design
  (``lhs``, or ``list`` for given points) runs through the dataset generator (:mod:`twin.dataset`)
  into ``DIR/dataset``: no second runner.
* **Responses** (:data:`RESPONSES`) are computed per run from its stored channels over the steady
  part of the run, ``t >= doe.settle_s``: ``max_slider_accel`` max |AC6| (the slider accelerometer
  along the guide) [m/s²], ``max_contact_force`` max normal force over the clearance joints [N],
  ``max_power`` max |crank torque × crank speed| [W], ``max_crank_torque`` max |crank torque| [N m].
* **Kriging** (:class:`Kriging`): scikit-learn's ``GaussianProcessRegressor``, a constant times an
  anisotropic Matérn 5/2 kernel (one length scale per factor) on the factors mapped to the unit cube
  (a factor with ``scale = "log"`` in log space), responses normalised (``doe.transform = "log"``:
  their logarithm), no noise term: the model
  interpolates its training points (a jitter of 1e-10 on the normalised diagonal). Hyperparameters
  by maximum likelihood (10 restarts, seeded). **Leave-one-out**: each point is predicted by the
  model built on the other n − 1 with the same hyperparameters (refit, :meth:`Kriging.loo`); the RMS
  error, its ratio to the responses' standard deviation and the largest error are reported.
* **Optimum**: ``scipy.optimize.differential_evolution`` minimises (``doe.goal = "min"``) or
  maximises the surrogate's mean over the factor box (:func:`optimize`); the optimum is then
  simulated (a check the surrogate cannot give itself).
* **Hold-out points** (``[[doe.holdout]]``, e.g. S000's 11th point) are simulated through the same
  generator (a ``list`` design in ``DIR/holdout``) and predicted by the surrogate.
* **Sensitivity**: first-order and total Sobol indices of the surrogate's mean with the factors
  uniform over the unit cube (``scipy.stats.sobol_indices``, 2**12 base samples, seeded), and the
  main effect of each factor (the surrogate along that factor, the others at their centre).
* **Plots**: one PNG per response, the surrogate over two factors (``doe.plot.x``/``y``; further
  factors at ``doe.plot.slices`` values, one panel each, else at their centre), with the training,
  hold-out and optimum points.

Outputs: ``doe.json`` (everything), ``doe.md`` (tables), ``<response>.png``, ``dataset/`` and
``holdout/`` (the generated datasets; a second call resumes them).
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from twin.dataset.spec import DatasetSpec, FactorSpec, SpecError, parse_spec, read_spec_toml
from twin.errors import unknown
from twin.provenance import figure_metadata

#: response name -> (unit, description)
RESPONSES: dict[str, tuple[str, str]] = {
    "max_slider_accel": ("m/s^2", "max |AC6|, slider acceleration along the guide"),
    "max_contact_force": ("N", "max normal contact force over the clearance joints"),
    "max_power": ("W", "max |crank torque x crank speed|"),
    "max_crank_torque": ("N m", "max |crank torque|"),
}
#: channel groups the responses need
NEEDED_GROUPS = ("accel", "crank", "joints", "drive")
_DOE_KEYS = ("responses", "settle_s", "goal", "transform", "holdout", "plot", "verify_optimum", "seed")


@dataclass(frozen=True)
class DoeSpec:
    """A parsed ``[doe]`` table and the dataset spec it goes with."""

    dataset: DatasetSpec
    responses: tuple[str, ...]
    settle_s: float
    goal: str = "min"
    holdout: tuple[Mapping[str, float], ...] = ()
    plot_x: str = ""
    plot_y: str = ""
    plot_slices: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    verify_optimum: bool = True
    seed: int = 0
    transform: str = "none"

    @property
    def factors(self) -> tuple[FactorSpec, ...]:
        return self.dataset.factors


def _num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def parse_doe(data: Mapping[str, Any], source: str = "") -> DoeSpec:
    """Validate a DOE spec given as nested dicts: a dataset spec plus ``[doe]``."""
    data = dict(data)
    raw = data.pop("doe", None)
    if not isinstance(raw, Mapping):
        raise SpecError("doe", "a DOE spec needs a [doe] table (responses, settle_s, ...)")
    for k in raw:
        if k not in _DOE_KEYS:
            raise SpecError(f"doe.{k}", unknown("key", k, _DOE_KEYS))
    out = data.get("outputs")
    if out is None:  # the responses' channels only, at the spec's default rate
        data["outputs"] = {"truth": list(NEEDED_GROUPS), "instrumented": False}
    spec = parse_spec(data, source)
    missing = [g for g in NEEDED_GROUPS if g not in spec.outputs.truth]
    if missing:
        raise SpecError("outputs.truth", f"must hold {', '.join(NEEDED_GROUPS)} for the responses; missing "
                                         f"{', '.join(missing)} (or leave [outputs] out)")
    if spec.design not in ("lhs", "list"):
        raise SpecError("design.kind", f"must be lhs or list for a DOE (a Kriging surrogate of a few "
                                       f"simulations), got {spec.design!r}")
    if spec.repeats != 1:
        raise SpecError("design.repeats", f"must be 1 for a DOE (the simulations are deterministic), got {spec.repeats}")
    if not spec.factors:
        raise SpecError("factors", "a DOE needs at least one factor with a range")
    for f in spec.factors:
        if f.range is None or f.levels is not None or f.exclude is not None:
            raise SpecError(f"factors.{f.name}", "must be a continuous range { range = [lo, hi] } (scale linear or "
                                                 "log, no levels, no exclude) for the surrogate")
    if spec.design == "list":
        names = {f.name for f in spec.factors}
        for i, p in enumerate(spec.points):
            if set(p) != names:
                raise SpecError(f"design.points[{i}]", f"must set exactly the factors {', '.join(sorted(names))}, "
                                                       f"got {', '.join(sorted(p))}")
            _check_point(spec.factors, p, f"design.points[{i}]")
    n = spec.runs if spec.design == "lhs" else len(spec.points)
    if n < len(spec.factors) + 2:
        raise SpecError("design", f"has {n} points; a surrogate of {len(spec.factors)} factors needs at least "
                                  f"{len(spec.factors) + 2}")
    responses = raw.get("responses", list(RESPONSES)[:3])
    if not (isinstance(responses, list) and responses and all(r in RESPONSES for r in responses)):
        raise SpecError("doe.responses", f"must be a non-empty list of {', '.join(RESPONSES)}; got {responses!r}")
    settle = raw.get("settle_s", 0.0)
    if not (_num(settle) and 0 <= settle < spec.duration_s):
        raise SpecError("doe.settle_s", f"must lie in [0, base.duration_s = {spec.duration_s:g}) s, got {settle!r}")
    goal = raw.get("goal", "min")
    if goal not in ("min", "max"):
        raise SpecError("doe.goal", f"must be one of min, max; got {goal!r}")
    transform = raw.get("transform", "none")
    if transform not in ("none", "log"):
        raise SpecError("doe.transform", f"must be one of none, log; got {transform!r}")
    hold = raw.get("holdout", [])
    if not (isinstance(hold, list) and all(isinstance(p, Mapping) for p in hold)):
        raise SpecError("doe.holdout", "must be [[doe.holdout]] tables, one value per factor")
    for i, p in enumerate(hold):
        if set(p) != {f.name for f in spec.factors}:
            raise SpecError(f"doe.holdout[{i}]", f"must set exactly the factors "
                                                 f"{', '.join(f.name for f in spec.factors)}, got {', '.join(p)}")
        _check_point(spec.factors, p, f"doe.holdout[{i}]")
    plot = raw.get("plot", {})
    if not isinstance(plot, Mapping):
        raise SpecError("doe.plot", f"must be a table {{ x, y, slices }}, got {plot!r}")
    for k in plot:
        if k not in ("x", "y", "slices"):
            raise SpecError(f"doe.plot.{k}", unknown("key", k, ("x", "y", "slices")))
    names = [f.name for f in spec.factors]
    px = plot.get("x", names[0])
    py = plot.get("y", names[1] if len(names) > 1 else "")
    for key, v in (("x", px), ("y", py)):
        if v and v not in names or (key == "x" and not v):
            raise SpecError(f"doe.plot.{key}", f"must name a factor ({', '.join(names)}), got {v!r}")
    if px == py:
        raise SpecError("doe.plot.y", f"must differ from doe.plot.x ({px!r})")
    slices = plot.get("slices", {})
    if not isinstance(slices, Mapping):
        raise SpecError("doe.plot.slices", f"must be a table factor = [values], got {slices!r}")
    sl = {}
    for k, v in slices.items():
        if k not in names or k in (px, py):
            raise SpecError(f"doe.plot.slices.{k}", f"must name a factor other than x and y ({', '.join(names)})")
        if not (isinstance(v, list) and v and all(_num(x) for x in v) and len(v) <= 6):
            raise SpecError(f"doe.plot.slices.{k}", f"must be a list of 1-6 numbers, got {v!r}")
        sl[k] = tuple(float(x) for x in v)
    verify = raw.get("verify_optimum", True)
    if not isinstance(verify, bool):
        raise SpecError("doe.verify_optimum", f"must be true or false, got {verify!r}")
    seed = raw.get("seed", spec.seed)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**32:
        raise SpecError("doe.seed", f"must be an integer in [0, 2**32), got {seed!r}")
    return DoeSpec(spec, tuple(responses), float(settle), goal, tuple(dict(p) for p in hold), px, py or "", sl,
                   verify, seed, transform)


def _check_point(factors: Sequence[FactorSpec], p: Mapping[str, Any], key: str) -> None:
    for f in factors:
        v = p[f.name]
        lo, hi = f.range
        if not (_num(v) and lo <= v <= hi):
            raise SpecError(f"{key}.{f.name}", f"must be a number within the factor's range [{lo:g}, {hi:g}], got {v!r}")


def load_doe(path: str | Path) -> DoeSpec:
    """Read a DOE spec file (one-line :class:`SpecError` naming the file or key)."""
    p = Path(path)
    doe = parse_doe(read_spec_toml(p, "a DOE spec"), str(p))
    if doe.dataset.base_config is not None and not Path(doe.dataset.base_config).is_absolute():
        doe = dataclasses.replace(doe, dataset=dataclasses.replace(
            doe.dataset, base_config=str(p.parent / doe.dataset.base_config)))
    return doe


# ------------------------------------------------------------------ factor space
def to_unit(factors: Sequence[FactorSpec], x: np.ndarray) -> np.ndarray:
    """Factor values (n, d) -> unit cube (log factors in log space)."""
    x = np.atleast_2d(np.asarray(x, float))
    u = np.empty_like(x)
    for k, f in enumerate(factors):
        lo, hi = f.range
        if f.scale == "log":
            u[:, k] = (np.log(x[:, k]) - math.log(lo)) / (math.log(hi) - math.log(lo))
        else:
            u[:, k] = (x[:, k] - lo) / (hi - lo)
    return u


def from_unit(factors: Sequence[FactorSpec], u: np.ndarray) -> np.ndarray:
    """Unit cube (n, d) -> factor values."""
    u = np.atleast_2d(np.asarray(u, float))
    x = np.empty_like(u)
    for k, f in enumerate(factors):
        lo, hi = f.range
        x[:, k] = np.exp(math.log(lo) + u[:, k] * (math.log(hi) - math.log(lo))) if f.scale == "log" \
            else lo + u[:, k] * (hi - lo)
    return x


# ---------------------------------------------------------------------- Kriging
class Kriging:
    """Kriging surrogate on the unit cube: ``GaussianProcessRegressor`` with a constant × anisotropic
    Matérn 5/2 kernel, normalised responses, interpolating (see the module docstring).

    ``fit(u, y)``; ``predict(u)`` -> mean; ``predict(u, return_std=True)``; ``loo()`` -> the
    leave-one-out predictions at the training points. ``log=True`` models log(y) (responses > 0 that
    span decades, e.g. over crank speeds 50-5000 rpm): predictions are exp of the model's mean (the
    median), standard deviations exp(mean)·σ (first order)."""

    def __init__(self, seed: int = 0, restarts: int = 10, nu: float = 2.5, jitter: float = 1e-10, log: bool = False):
        self.seed, self.restarts, self.nu, self.jitter, self.log = seed, restarts, nu, jitter, log
        self.gp = None

    def _gp(self, kernel, optimize: bool):
        from sklearn.gaussian_process import GaussianProcessRegressor

        return GaussianProcessRegressor(kernel=kernel, alpha=self.jitter, normalize_y=True,
                                        optimizer="fmin_l_bfgs_b" if optimize else None,
                                        n_restarts_optimizer=self.restarts if optimize else 0,
                                        random_state=self.seed)

    def fit(self, u: np.ndarray, y: np.ndarray) -> "Kriging":
        from sklearn.gaussian_process.kernels import ConstantKernel, Matern

        u = np.atleast_2d(np.asarray(u, float))
        y = np.asarray(y, float)
        if self.log and np.any(y <= 0):
            from twin.errors import TwinError

            raise TwinError("doe.transform: log needs responses > 0")
        self.u, self.y = u, (np.log(y) if self.log else y)
        d = u.shape[1]
        kernel = ConstantKernel(1.0, (1e-3, 1e3)) * Matern(length_scale=np.full(d, 0.5), length_scale_bounds=(1e-2, 1e2),
                                                           nu=self.nu)
        import warnings

        from sklearn.exceptions import ConvergenceWarning

        with warnings.catch_warnings():  # a length scale at its bound is reported in the kernel, not warned
            warnings.simplefilter("ignore", ConvergenceWarning)
            self.gp = self._gp(kernel, True).fit(u, self.y)
        return self

    @property
    def kernel(self):
        return self.gp.kernel_

    @property
    def length_scales(self) -> np.ndarray:
        return np.atleast_1d(self.gp.kernel_.k2.length_scale)

    def predict(self, u: np.ndarray, return_std: bool = False):
        res = self.gp.predict(np.atleast_2d(np.asarray(u, float)), return_std=return_std)
        if not self.log:
            return res
        if return_std:
            m = np.exp(res[0])
            return m, m * res[1]
        return np.exp(res)

    def loo(self) -> np.ndarray:
        """Leave-one-out predictions: point i predicted by the model built on the other points with
        this model's hyperparameters (kernel fixed, response normalisation recomputed)."""
        n = len(self.y)
        out = np.empty(n)
        for i in range(n):
            keep = np.arange(n) != i
            gp = self._gp(self.gp.kernel_, False).fit(self.u[keep], self.y[keep])
            out[i] = gp.predict(self.u[i:i + 1])[0]
        return np.exp(out) if self.log else out


def loo_closed_form(kernel_matrix: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Leave-one-out predictions of a zero-mean Gaussian-process interpolator with a fixed kernel from
    one inverse (Dubrule 1983): y_i − [K⁻¹ y]_i / [K⁻¹]_ii. The check of :meth:`Kriging.loo`."""
    kinv = np.linalg.inv(kernel_matrix)
    return y - (kinv @ y) / np.diag(kinv)


def loo_stats(y: np.ndarray, pred: np.ndarray) -> dict[str, float]:
    err = pred - y
    rmse = float(np.sqrt(np.mean(err**2)))
    return {"rmse": rmse, "rmse_over_std": rmse / float(np.std(y)) if np.std(y) > 0 else math.nan,
            "max_abs": float(np.max(np.abs(err))), "max_rel": float(np.max(np.abs(err) / np.abs(y)))}


# -------------------------------------------------------------------- optimizer
def optimize(fun: Callable[[np.ndarray], float], d: int, goal: str = "min", seed: int = 0) -> dict[str, Any]:
    """Global optimum of ``fun`` (a function of a point of the unit cube [0, 1]^d) by
    ``scipy.optimize.differential_evolution`` (seeded, polished by L-BFGS-B)."""
    from scipy.optimize import differential_evolution

    sign = 1.0 if goal == "min" else -1.0
    res = differential_evolution(lambda u: sign * float(fun(u)), [(0.0, 1.0)] * d, seed=seed, tol=1e-10,
                                 maxiter=2000, polish=True)
    return {"u": np.clip(res.x, 0, 1), "value": sign * float(res.fun), "nfev": int(res.nfev),
            "success": bool(res.success)}


def sobol(fun: Callable[[np.ndarray], np.ndarray], d: int, seed: int = 0, m: int = 12) -> dict[str, list[float]]:
    """First-order and total Sobol indices of ``fun`` (vectorised over points of [0, 1]^d) with
    uniform factors (``scipy.stats.sobol_indices``, 2**m base samples)."""
    from scipy.stats import sobol_indices, uniform

    if d == 1:
        return {"first_order": [1.0], "total": [1.0]}
    res = sobol_indices(func=lambda x: fun(x.T), n=2**m, dists=[uniform(0, 1)] * d,
                        rng=np.random.default_rng(seed)) if _has_rng_kw() else \
        sobol_indices(func=lambda x: fun(x.T), n=2**m, dists=[uniform(0, 1)] * d, random_state=seed)
    return {"first_order": [float(v) for v in np.atleast_1d(res.first_order)],
            "total": [float(v) for v in np.atleast_1d(res.total_order)]}


def _has_rng_kw() -> bool:
    import inspect

    from scipy.stats import sobol_indices

    return "rng" in inspect.signature(sobol_indices).parameters


# -------------------------------------------------------------------- responses
def run_responses(path: Path, rate_hz: float, settle_s: float, names: Sequence[str]) -> dict[str, float]:
    """The responses of one stored run (``data/<run_id>.parquet``) over t >= settle_s."""
    import pyarrow.parquet as pq

    cols = pq.read_schema(path).names
    want = ["AC6", "crank_torque", "crank_speed"] + [c for c in cols if c.startswith("fn_")]
    tab = pq.read_table(path, columns=[c for c in want if c in cols])
    i0 = int(math.ceil(settle_s * rate_hz - 1e-9))
    col = {c: np.asarray(tab.column(c).to_numpy(zero_copy_only=False), float)[i0:] for c in tab.column_names}
    out = {}
    for r in names:
        if r == "max_slider_accel":
            out[r] = float(np.max(np.abs(col["AC6"])))
        elif r == "max_contact_force":
            fn = [np.nanmax(v) for k, v in col.items() if k.startswith("fn_") and np.isfinite(v).any()]
            out[r] = float(max(fn)) if fn else 0.0
        elif r == "max_power":
            out[r] = float(np.max(np.abs(col["crank_torque"] * col["crank_speed"])))
        elif r == "max_crank_torque":
            out[r] = float(np.max(np.abs(col["crank_torque"])))
    return out


def _simulate(spec: DatasetSpec, out: Path, doe: DoeSpec, workers: int | None, progress: bool) -> list[dict]:
    """Generate ``spec`` into ``out`` (resumes) and return per run: factors and responses."""
    from twin.dataset.design import plan
    from twin.dataset.generate import generate

    generate(spec, out, workers=workers, progress=progress)
    rows = []
    for r in plan(spec):
        res = json.loads((out / "results" / f"{r.run_id}.json").read_text())
        if res["status"] != "ok":
            from twin.errors import TwinError

            raise TwinError(f"DOE run {r.run_id} ({r.factors}) failed: {res['reason']}")
        resp = run_responses(out / "data" / f"{r.run_id}.parquet", spec.outputs.rate_hz, doe.settle_s, doe.responses)
        rows.append({"run_id": r.run_id, "factors": dict(r.factors), "responses": resp,
                     "wall_s": res.get("wall_s")})
    return rows


def _list_spec(doe: DoeSpec, points: Sequence[Mapping[str, float]], name: str) -> DatasetSpec:
    return dataclasses.replace(doe.dataset, name=name, design="list", runs=None,
                               points=tuple(dict(p) for p in points))


# ------------------------------------------------------------------------ study
@dataclass(frozen=True)
class DoeOptions:
    """What the study runs.

    Attributes:
        spec: the DOE spec (:func:`load_doe`); every configuration of its design and hold-out points
            is checked here, before anything is simulated or written.
        out: output folder (created; a second call resumes its datasets).
        workers: simulations at a time (None = the machine's cores; else 1..1024).
        progress: a progress bar on stderr.
    """

    spec: DoeSpec
    out: str | Path
    workers: int | None = None
    progress: bool = False

    def __post_init__(self) -> None:
        from twin.dataset.design import plan
        from twin.util import resolve_workers

        if self.workers is not None:
            resolve_workers(self.workers)
        plan(self.spec.dataset)  # every configuration is valid before anything is written
        for p in self.spec.holdout:
            plan(_list_spec(self.spec, [p], self.spec.dataset.name + "-check"))


@dataclass(frozen=True)
class DoePoint:
    """One simulated point of the design (or a check point, :class:`DoeCheck`).

    Attributes:
        run_id: the run's id in the generated dataset.
        factors: factor name -> its value at the point (the factor's unit).
        responses: response name -> its value from the run (:data:`RESPONSES` gives the units).
        wall_s: wall time of the run [s] (None where the dataset does not record it).
    """

    run_id: str
    factors: Mapping[str, float]
    responses: Mapping[str, float]
    wall_s: float | None

    def to_dict(self) -> dict[str, Any]:
        return {"run_id": self.run_id, "factors": dict(self.factors), "responses": dict(self.responses),
                "wall_s": self.wall_s}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "DoePoint":
        return cls(d["run_id"], dict(d["factors"]), dict(d["responses"]), d["wall_s"])


@dataclass(frozen=True)
class DoeCheck(DoePoint):
    """A hold-out point or a surrogate's optimum, simulated, with what the surrogates predicted there.

    Attributes:
        predicted: response name -> {"mean", "std"} of its Kriging prediction.
        kind: "holdout" or "optimum".
    """

    predicted: Mapping[str, Mapping[str, float]] = dataclasses.field(default_factory=dict)
    kind: str = "holdout"

    def to_dict(self) -> dict[str, Any]:
        return {**super().to_dict(), "predicted": {r: dict(v) for r, v in self.predicted.items()}, "kind": self.kind}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "DoeCheck":
        return cls(d["run_id"], dict(d["factors"]), dict(d["responses"]), d["wall_s"],
                   {r: dict(v) for r, v in d["predicted"].items()}, d["kind"])


@dataclass(frozen=True)
class DoeResponse:
    """One response's Kriging surrogate over the design.

    Attributes:
        unit: the response's unit.
        kernel: the fitted kernel (text).
        length_scales: its length scales, one per factor, in the unit cube [-].
        train_fit_max_rel: largest relative error of the surrogate at the design points [-].
        loo: the leave-one-out predictions at the design points (response unit).
        loo_stats: their error statistics (``rmse``, ``rmse_over_std``, ...).
        optimum: the surrogate's optimum: ``factors``, ``predicted`` value, ``nfev``.
        sobol: Sobol indices, ``first_order`` and ``total``, factor name -> index [-].
        main_effects: factor name -> {"x", "y"}: the surrogate along the factor, the others at mid-range.
    """

    unit: str
    kernel: str
    length_scales: tuple[float, ...]
    train_fit_max_rel: float
    loo: tuple[float, ...]
    loo_stats: Mapping[str, float]
    optimum: Mapping[str, Any]
    sobol: Mapping[str, Mapping[str, float]]
    main_effects: Mapping[str, Mapping[str, list[float]]]

    def to_dict(self) -> dict[str, Any]:
        return {"unit": self.unit, "kernel": self.kernel, "length_scales": list(self.length_scales),
                "train_fit_max_rel": self.train_fit_max_rel, "loo": list(self.loo), "loo_stats": dict(self.loo_stats),
                "optimum": {**self.optimum, "factors": dict(self.optimum["factors"])},
                "sobol": {k: dict(v) for k, v in self.sobol.items()},
                "main_effects": {n: {"x": list(v["x"]), "y": list(v["y"])} for n, v in self.main_effects.items()}}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "DoeResponse":
        return cls(d["unit"], d["kernel"], tuple(d["length_scales"]), d["train_fit_max_rel"], tuple(d["loo"]),
                   dict(d["loo_stats"]), {**d["optimum"], "factors": dict(d["optimum"]["factors"])},
                   {k: dict(v) for k, v in d["sobol"].items()},
                   {n: {"x": list(v["x"]), "y": list(v["y"])} for n, v in d["main_effects"].items()})


@dataclass(frozen=True)
class DoeResult:
    """What the study found (``doe.json``): the simulated design ``points``, per response its
    Kriging surrogate's leave-one-out error, optimum, Sobol indices and main effects
    (``responses``), the hold-out and optimum ``checks`` simulated with their predictions."""

    factors: list[dict[str, Any]]
    responses: dict[str, DoeResponse]
    design: str
    points: tuple[DoePoint, ...]
    settle_s: float
    goal: str
    spec: str
    checks: tuple[DoeCheck, ...]
    figures: tuple[str, ...]
    lhs_strata_ok: bool | None = None  # a Latin hypercube design only

    def to_dict(self) -> dict[str, Any]:
        """The JSON data of ``doe.json``."""
        d: dict[str, Any] = {"factors": self.factors, "responses": {r: v.to_dict() for r, v in self.responses.items()},
                             "design": self.design, "points": [p.to_dict() for p in self.points],
                             "settle_s": self.settle_s, "goal": self.goal, "spec": self.spec}
        if self.lhs_strata_ok is not None:
            d["lhs_strata_ok"] = self.lhs_strata_ok
        return d | {"checks": [c.to_dict() for c in self.checks], "figures": list(self.figures)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "DoeResult":
        """The result of a dict as :meth:`to_dict` (or ``doe.json``) holds it."""
        return cls(factors=[dict(f) for f in d["factors"]],
                   responses={r: DoeResponse.from_dict(v) for r, v in d["responses"].items()}, design=d["design"],
                   points=tuple(DoePoint.from_dict(p) for p in d["points"]), settle_s=d["settle_s"], goal=d["goal"],
                   spec=d["spec"], checks=tuple(DoeCheck.from_dict(c) for c in d["checks"]),
                   figures=tuple(d["figures"]), lhs_strata_ok=d.get("lhs_strata_ok"))


def run_study(options: DoeOptions, *, log: Callable[[str], None] = lambda m: None) -> DoeResult:
    """The whole study (module docstring); writes ``doe.json``, ``doe.md`` and the PNGs in
    ``options.out``; ``log`` receives a line per stage."""
    from twin.provenance import stamped, with_stamp_line
    from twin.util import atomic_write_json, atomic_write_bytes

    doe, workers, progress = options.spec, options.workers, options.progress
    out = Path(options.out)
    out.mkdir(parents=True, exist_ok=True)
    names = [f.name for f in doe.factors]
    d = len(names)
    log(f"design: {doe.dataset.design}, {d} factors, simulating into {out / 'dataset'}")
    train = _simulate(doe.dataset, out / "dataset", doe, workers, progress)
    X = np.array([[r["factors"][n] for n in names] for r in train], float)
    U = to_unit(doe.factors, X)
    models: dict[str, Kriging] = {}
    result: dict[str, Any] = {"factors": [dataclasses.asdict(f) for f in doe.factors], "responses": {},
                              "design": doe.dataset.design, "points": train, "settle_s": doe.settle_s,
                              "goal": doe.goal, "spec": doe.dataset.source}
    if doe.dataset.design == "lhs":
        result["lhs_strata_ok"] = bool(is_latin_hypercube(U))
    for rname in doe.responses:
        y = np.array([r["responses"][rname] for r in train])
        k = Kriging(seed=doe.seed, log=doe.transform == "log").fit(U, y)
        models[rname] = k
        loo = k.loo()
        opt = optimize(lambda u, k=k: k.predict(u)[0], d, doe.goal, doe.seed)
        sens = sobol(lambda uu, k=k: k.predict(uu), d, doe.seed)
        grid = np.linspace(0, 1, 21)
        main = {}
        for j, n in enumerate(names):
            uu = np.full((len(grid), d), 0.5)
            uu[:, j] = grid
            main[n] = {"x": from_unit(doe.factors, uu)[:, j].tolist(), "y": k.predict(uu).tolist()}
        result["responses"][rname] = {
            "unit": RESPONSES[rname][0], "kernel": str(k.kernel), "length_scales": k.length_scales.tolist(),
            "train_fit_max_rel": float(np.max(np.abs(k.predict(U) - y) / np.abs(y))),
            "loo": loo.tolist(), "loo_stats": loo_stats(y, loo),
            "optimum": {"factors": dict(zip(names, from_unit(doe.factors, opt["u"])[0].tolist())),
                        "predicted": opt["value"], "nfev": opt["nfev"]},
            "sobol": dict(zip(("first_order", "total"), (dict(zip(names, sens["first_order"])),
                                                          dict(zip(names, sens["total"]))))),
            "main_effects": main,
        }
        log(f"{rname}: LOO RMSE/std {result['responses'][rname]['loo_stats']['rmse_over_std']:.3f}, optimum "
            f"{result['responses'][rname]['optimum']}")
    # hold-out points and the optima, simulated through the same generator
    extra = [dict(p) for p in doe.holdout]
    opt_points = []
    if doe.verify_optimum:
        for rname in doe.responses:
            p = result["responses"][rname]["optimum"]["factors"]
            p = {n: float(min(max(p[n], f.range[0]), f.range[1])) for n, f in zip(names, doe.factors)}
            if p not in extra + opt_points:
                opt_points.append(p)
    checks = extra + opt_points
    if checks:
        log(f"simulating {len(checks)} check points (hold-out and optima) into {out / 'holdout'}")
        rows = _simulate(_list_spec(doe, checks, doe.dataset.name + "-check"), out / "holdout", doe, workers, progress)
        Uc = to_unit(doe.factors, np.array([[r["factors"][n] for n in names] for r in rows]))
        for r, u in zip(rows, Uc):
            r["predicted"] = {}
            for rname, k in models.items():
                m, s = k.predict(u[None, :], return_std=True)
                r["predicted"][rname] = {"mean": float(m[0]), "std": float(s[0])}
            r["kind"] = "holdout" if r["factors"] in extra else "optimum"
        result["checks"] = rows
    else:
        result["checks"] = []
    figures = []
    for rname, k in models.items():
        png = out / f"{rname}.png"
        atomic_write_bytes(png, _plot(doe, k, rname, X, result))
        figures.append(png.name)
    result["figures"] = figures
    atomic_write_json(out / "doe.json", stamped(result))
    atomic_write_bytes(out / "doe.md", with_stamp_line(report_md(doe, result)).encode())
    return DoeResult.from_dict(result)


def is_latin_hypercube(u: np.ndarray) -> bool:
    """Whether n points of the unit cube put exactly one point in each of the n equal strata of
    every factor."""
    u = np.atleast_2d(u)
    n = len(u)
    strata = np.minimum(np.floor(u * n).astype(int), n - 1)
    return all(sorted(strata[:, j]) == list(range(n)) for j in range(u.shape[1]))


# ------------------------------------------------------------------------ output
def _fmt(v: float) -> str:
    return f"{v:.3g}"


def report_md(doe: DoeSpec, res: dict[str, Any]) -> str:
    names = [f.name for f in doe.factors]
    L = [f"# DOE and Kriging study: {doe.dataset.name}", "",
         f"Spec `{doe.dataset.source}`; {doe.dataset.design} design of {len(res['points'])} points over "
         + ", ".join(f"`{f.name}` [{f.range[0]:g}, {f.range[1]:g}]{' (log)' if f.scale == 'log' else ''}"
                     for f in doe.factors)
         + f"; engine {doe.dataset.engine}, {doe.dataset.duration_s:g} s per run, responses over t >= "
         f"{doe.settle_s:g} s; surrogate of {'log(response)' if doe.transform == 'log' else 'the response'}.", ""]
    if "lhs_strata_ok" in res:
        L += [f"Latin hypercube (one point per stratum of every factor): {res['lhs_strata_ok']}.", ""]
    L += ["## Points", "", "| # | " + " | ".join(names) + " | " + " | ".join(
        f"{r} [{RESPONSES[r][0]}]" for r in doe.responses) + " |", "|" + "---|" * (1 + len(names) + len(doe.responses))]
    for i, p in enumerate(res["points"], 1):
        L.append(f"| {i} | " + " | ".join(_fmt(p["factors"][n]) for n in names) + " | "
                 + " | ".join(_fmt(p["responses"][r]) for r in doe.responses) + " |")
    L += ["", "## Surrogates", "", "| response | LOO RMSE | LOO RMSE / std | LOO max rel. error | length scales ("
          + ", ".join(names) + ") | optimum (" + doe.goal + ") | predicted | Sobol first order | Sobol total |",
          "|---|---|---|---|---|---|---|---|---|"]
    for r in doe.responses:
        s = res["responses"][r]
        o = s["optimum"]
        L.append(f"| {r} | {_fmt(s['loo_stats']['rmse'])} | {s['loo_stats']['rmse_over_std']:.3f} | "
                 f"{100 * s['loo_stats']['max_rel']:.1f} % | " + ", ".join(f"{v:.3g}" for v in s["length_scales"])
                 + " | " + ", ".join(f"{n} {_fmt(o['factors'][n])}" for n in names) + f" | {_fmt(o['predicted'])} | "
                 + ", ".join(f"{n} {s['sobol']['first_order'][n]:.2f}" for n in names) + " | "
                 + ", ".join(f"{n} {s['sobol']['total'][n]:.2f}" for n in names) + " |")
    if res["checks"]:
        L += ["", "## Check points (simulated, and predicted by the surrogate)", "",
              "| kind | " + " | ".join(names) + " | " + " | ".join(f"{r} simulated | predicted (±1σ) | error"
                                                                  for r in doe.responses) + " |",
              "|" + "---|" * (1 + len(names) + 3 * len(doe.responses))]
        for c in res["checks"]:
            cells = []
            for r in doe.responses:
                sim, pr = c["responses"][r], c["predicted"][r]
                cells += [_fmt(sim), f"{_fmt(pr['mean'])} ± {_fmt(pr['std'])}",
                          f"{100 * (pr['mean'] - sim) / sim:+.1f} %"]
            L.append(f"| {c['kind']} | " + " | ".join(_fmt(c["factors"][n]) for n in names) + " | "
                     + " | ".join(cells) + " |")
    L += ["", "Figures: " + ", ".join(f"`{f}`" for f in res["figures"]), ""]
    return "\n".join(L)


def _plot(doe: DoeSpec, k: Kriging, rname: str, X: np.ndarray, res: dict[str, Any]) -> bytes:
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [f.name for f in doe.factors]
    d = len(names)
    ix = names.index(doe.plot_x)
    unit, desc = RESPONSES[rname]
    if d == 1:
        fig, ax = plt.subplots(figsize=(6, 4))
        g = np.linspace(0, 1, 200)[:, None]
        m, s = k.predict(g, return_std=True)
        xg = from_unit(doe.factors, g)[:, 0]
        ax.plot(xg, m, label="Kriging mean")
        ax.fill_between(xg, m - 2 * s, m + 2 * s, alpha=0.2, label="±2σ")
        ax.plot(X[:, 0], [p["responses"][rname] for p in res["points"]], "ko", label="simulated")
        ax.set_xlabel(names[0])
        ax.set_ylabel(f"{rname} [{unit}]")
        ax.legend()
    else:
        iy = names.index(doe.plot_y)
        others = [j for j in range(d) if j not in (ix, iy)]
        slices: list[dict[int, float]] = [{}]
        for j in others:
            vals = doe.plot_slices.get(names[j])
            if vals is None:
                vals = (float(from_unit(doe.factors, np.full((1, d), 0.5))[0, j]),)
            slices = [{**s, j: v} for s in slices for v in vals]
        n = len(slices)
        fig, axes = plt.subplots(1, n, figsize=(max(5.2 * n, 6.4), 4.6), squeeze=False)
        g = np.linspace(0, 1, 81)
        gx, gy = np.meshgrid(g, g)
        ys = [p["responses"][rname] for p in res["points"]]
        vmin, vmax = min(ys), max(ys)
        for ax, s in zip(axes[0], slices):
            uu = np.full((gx.size, d), 0.5)
            uu[:, ix], uu[:, iy] = gx.ravel(), gy.ravel()
            for j, v in s.items():
                uu[:, j] = to_unit(doe.factors, _one(doe, j, v))[0, j]
            m = k.predict(uu).reshape(gx.shape)
            xx = from_unit(doe.factors, uu)
            cs = ax.contourf(xx[:, ix].reshape(gx.shape), xx[:, iy].reshape(gx.shape), m, levels=20,
                             cmap="viridis", vmin=min(vmin, m.min()), vmax=max(vmax, m.max()))
            fig.colorbar(cs, ax=ax, label=f"{rname} [{unit}]")
            ax.scatter(X[:, ix], X[:, iy], c="w", edgecolors="k", s=30,
                       label="design points" + (" (all " + ", ".join(names[j] for j in others) + ")" if others else ""))
            for c in res["checks"]:
                mk = "s" if c["kind"] == "holdout" else "*"
                ax.scatter([c["factors"][names[ix]]], [c["factors"][names[iy]]], marker=mk, c="r", s=80,
                           edgecolors="k", label=c["kind"], clip_on=False, zorder=5)
            for f, axis in ((doe.factors[ix], "x"), (doe.factors[iy], "y")):
                if f.scale == "log":
                    getattr(ax, f"set_{axis}scale")("log")
            ax.set_xlabel(names[ix])
            ax.set_ylabel(names[iy])
            title = ", ".join(f"{names[j]} = {v:g}" for j, v in s.items())
            ax.set_title(title or desc, fontsize=9)
            h, lab = ax.get_legend_handles_labels()
            uniq = dict(zip(lab, h))
            ax.legend(uniq.values(), uniq.keys(), fontsize=7, loc="best")
        fig.suptitle(f"Kriging surrogate of {rname}", fontsize=10)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, metadata=figure_metadata())
    plt.close(fig)
    return buf.getvalue()


def _one(doe: DoeSpec, j: int, v: float) -> np.ndarray:
    x = from_unit(doe.factors, np.full((1, len(doe.factors)), 0.5))
    x[0, j] = v
    return x
