"""Run time versus error of the MuJoCo twin and the reference engine (``twin study accuracy``).

Method
------
For each Table 4 test with a clearance (4–12), every *variant* (an engine plus a few dotted
configuration overrides) simulates the same scene: the constant-speed program with its
``ramp_s`` spin-up, then a window of ``window_s`` that is analysed. The *truth* is the reference
engine (R-matrix, Lankarani–Nikravesh, symplectic Euler) at the converged step
``TRUTH_TIMESTEP_S`` = 1e-6 s (10 steps per 100 kHz output sample). Every variant's window is
compared with the truth's window of the same test:

* ``impacts``: |n − n_ref| / max(n_ref, 1) per clearance joint (impact = contact onset after
  ≥ 0.1 ms of separation, :func:`twin.summary.count_impacts`);
* ``peak_fn`` / ``mean_fn``: relative error of max and mean normal contact force per joint;
* ``rms_slider`` / ``peak_slider``: relative error of AC6's RMS / max |a| (proper acceleration);
* ``rms_rod`` / ``peak_rod``: the largest relative error of AC1–AC4's RMS / max |a|;
* ``band_db``: the largest |ΔE| over AC1–AC6 of the mean-square content in 0.5–5 kHz
  (Hann-windowed PSD over the window, :func:`twin.signals.band_energy_db`) [dB];
* ``dtw_slider``: the paper's normalized DTW distance of AC6 (:func:`twin.signals.dtw_compare`),
  computed on both signals resampled to ``DTW_RATE_HZ`` = 10 kHz (polyphase anti-alias filter;
  a 2 s window at 100 kHz would cost minutes per pair) with a 5 ms Sakoe–Chiba band [%].

Per variant each metric is averaged over the tests (and joints); the table also gives the worst
test. The *score* is the largest ratio of a targeted metric's mean to its target (impact
count and peak force 10 %, RMS 3 %, band energy 1.5 dB): score ≤ 1 meets every target on
average. Cost is the engine's own stepping wall time per simulated second (``run.meta["wall_s"]``,
model build excluded), measured in this process one run after another, so ratios between
variants are meaningful on one machine; absolute numbers depend on the machine's load.
A MuJoCo variant is on the Pareto front when no other MuJoCo variant is at most as costly and
at most as wrong in every error of ``FRONT_METRICS`` (the targeted metrics and the AC6 DTW
distance), strictly better in one (:func:`pareto_front`); the table also flags the front in the
two-dimensional (cost, score) sense. The front is what the twin's settings can trade; the
reference at its default step is shown beside them for context, not as a twin setting.

Outputs (``--out DIR``): ``accuracy.json`` (every variant × test metric and timing),
``accuracy.md`` (the table, default marked), one work–precision PNG per metric plus
``work_precision_score.png``.
"""

from __future__ import annotations

import dataclasses
import io
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from twin.config import ACCELEROMETERS, BenchConfig, preset
from twin.errors import ConfigError, TwinError
from twin.run import Run
from twin.signals import band_energy_db, dtw_compare
from twin.summary import count_impacts
from twin.provenance import figure_metadata, stamped, with_stamp_line
from twin.util import atomic_write_bytes, atomic_write_json, atomic_write_text

#: Step of the converged reference ("truth") [s].
TRUTH_TIMESTEP_S = 1e-6
#: Rate both AC6 signals are resampled to for the DTW distance [Hz], and its band [s].
DTW_RATE_HZ = 10_000.0
DTW_WINDOW_S = 0.005
#: Spectral band of ``band_db`` [Hz].
BAND_HZ = (500.0, 5000.0)
#: Targeted metrics and their targets.
TARGETS: dict[str, float] = {"impacts": 0.10, "peak_fn": 0.10, "rms_slider": 0.03, "rms_rod": 0.03,
                             "band_db": 1.5}
#: Every metric, in table order, with its unit ("" = relative, shown in %).
METRICS: dict[str, str] = {"impacts": "", "peak_fn": "", "mean_fn": "", "rms_slider": "", "rms_rod": "",
                           "peak_slider": "", "peak_rod": "", "band_db": "dB", "dtw_slider": "%"}
#: Table 4 tests with a clearance.
CLEARANCE_TESTS: tuple[int, ...] = (4, 5, 6, 7, 8, 9, 10, 11, 12)
ROD_SENSORS = ("AC1", "AC2", "AC3", "AC4")
#: Errors the Pareto front is taken over (with the cost): the targeted metrics and the DTW distance.
FRONT_METRICS: tuple[str, ...] = (*TARGETS, "dtw_slider")


@dataclass(frozen=True)
class Variant:
    """One way of simulating a scene.

    Attributes:
        key: short unique name (table row, JSON key).
        engine: "mujoco" or "reference".
        family: what the variant varies ("default", "timestep", "integrator", "solver",
            "contact", "bushing", "reference", "truth").
        overrides: dotted configuration overrides applied to the test's preset.
    """

    key: str
    engine: str
    family: str
    overrides: dict[str, Any] = field(default_factory=dict)

    def config(self, base: BenchConfig) -> BenchConfig:
        return base.replace(**{"simulation.engine": self.engine, **self.overrides})


DEFAULT_KEY = "mujoco default"
TRUTH = Variant("reference h=1e-6 (truth)", "reference", "truth", {"simulation.timestep_s": TRUTH_TIMESTEP_S})


def variants(quick: bool = False) -> list[Variant]:
    """The variants of the study (the truth is separate: :data:`TRUTH`)."""
    m = "mujoco"
    if quick:
        return [
            Variant(DEFAULT_KEY, m, "default"),
            Variant("mujoco h=2e-5", m, "timestep", {"simulation.timestep_s": 2e-5, "sensors.output_rate_hz": 5e4}),
            Variant("mujoco first-guess contact", m, "contact", {"mujoco.contact_source": "first-guess"}),
            Variant("mujoco force contact", m, "contact", {"mujoco.contact_source": "force"}),
            Variant("reference h=1e-5", "reference", "reference", {"simulation.timestep_s": 1e-5}),
        ]
    return [
        Variant(DEFAULT_KEY, m, "default"),
        Variant("mujoco h=5e-6", m, "timestep", {"simulation.timestep_s": 5e-6}),
        Variant("mujoco h=2e-5", m, "timestep", {"simulation.timestep_s": 2e-5, "sensors.output_rate_hz": 5e4}),
        Variant("mujoco h=5e-5", m, "timestep", {"simulation.timestep_s": 5e-5, "sensors.output_rate_hz": 2e4}),
        Variant("mujoco implicitfast", m, "integrator", {"mujoco.integrator": "implicitfast"}),
        Variant("mujoco RK4", m, "integrator", {"mujoco.integrator": "RK4"}),
        Variant("mujoco Newton 3 it, tol 1e-6", m, "solver", {"mujoco.iterations": 3, "mujoco.tolerance": 1e-6}),
        Variant("mujoco PGS", m, "solver", {"mujoco.solver": "PGS"}),
        Variant("mujoco first-guess contact", m, "contact", {"mujoco.contact_source": "first-guess"}),
        Variant("mujoco force contact", m, "contact", {"mujoco.contact_source": "force"}),
        Variant("mujoco force contact h=2e-5", m, "contact", {"mujoco.contact_source": "force",
                                                                "simulation.timestep_s": 2e-5, "sensors.output_rate_hz": 5e4}),
        Variant("mujoco impact-speed damping x2", m, "contact", {"mujoco.impact_damping_gain": 2.0}),
        Variant("mujoco frictionloss guide", m, "contact", {"mujoco.guide_friction": "frictionloss"}),
        Variant("mujoco friction cone", m, "bushing", {"mujoco.friction": "cone"}),
        Variant("mujoco ring48 (cone)", m, "bushing", {"mujoco.bushing": "ring", "mujoco.friction": "cone"}),
        Variant("mujoco tendon (frictionless)", m, "bushing", {"mujoco.bushing": "tendon"}),
        Variant("reference h=1e-5", "reference", "reference", {"simulation.timestep_s": 1e-5}),
        Variant("reference h=5e-6", "reference", "reference", {"simulation.timestep_s": 5e-6}),
    ]


@dataclass(frozen=True)
class StudySettings:
    """Scene timing of the study.

    Attributes:
        tests: Table 4 test ids (each must have a clearance).
        ramp_s: spin-up of the constant program [s] (``drive.ramp_s``).
        settle_s: time after the ramp before the window starts [s].
        window_s: analysed window [s] (2 s), in [0.05, 60] (spectra and impacts need 0.05 s; the
            converged reference at h = 1e-6 s runs 60 s in about an hour per test).
    """

    tests: tuple[int, ...] = CLEARANCE_TESTS
    ramp_s: float = 0.5
    settle_s: float = 0.1
    window_s: float = 2.0

    def __post_init__(self) -> None:
        for t in self.tests:
            if t not in CLEARANCE_TESTS:
                raise ConfigError("tests", f"Table 4 tests with a clearance are {list(CLEARANCE_TESTS)}, got {t!r}")
        if not self.tests:
            raise ConfigError("tests", "at least one test is needed")
        for name in ("ramp_s", "settle_s", "window_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ConfigError(name, f"must be a finite time >= 0 [s], got {v!r}")
        if not 0.05 <= self.window_s <= 60:
            raise ConfigError("window_s", f"must lie in [0.05, 60] s (spectra and impacts need 0.05 s), "
                                          f"got {self.window_s!r}")

    @property
    def t0(self) -> float:
        return self.ramp_s + self.settle_s

    @property
    def duration_s(self) -> float:
        return self.t0 + self.window_s


QUICK = StudySettings(tests=(6, 12), ramp_s=0.1, settle_s=0.05, window_s=0.3)


def scene(test_id: int, s: StudySettings) -> BenchConfig:
    """The test's preset timed for the study (all channels, 100 kHz output)."""
    return preset(test_id).replace(**{"drive.ramp_s": s.ramp_s, "simulation.duration_s": s.duration_s})


# -------------------------------------------------------------------------------- metrics
@dataclass
class WindowStats:
    """What the metrics need from one run's window (keeps memory small: no full runs kept)."""

    rate_hz: float
    joints: tuple[str, ...]
    impacts: dict[str, int]
    peak_fn: dict[str, float]
    mean_fn: dict[str, float]
    rms: dict[str, float]
    peak: dict[str, float]
    band_db: dict[str, float]
    ac6_dtw: np.ndarray  # AC6 resampled to DTW_RATE_HZ

    @classmethod
    def of(cls, run: Run, t0: float, t1: float) -> "WindowStats":
        from scipy.signal import resample_poly

        w = run.window(t0, t1)
        joints = tuple(j for j in ("B", "C") if f"fn_{j}" in w)
        up, down = _ratio(DTW_RATE_HZ, w.rate_hz)
        return cls(
            rate_hz=w.rate_hz, joints=joints,
            impacts={j: count_impacts(w[f"fn_{j}"] > 0, w.rate_hz) for j in joints},
            peak_fn={j: float(np.max(w[f"fn_{j}"])) for j in joints},
            mean_fn={j: float(np.mean(w[f"fn_{j}"])) for j in joints},
            rms={a: float(np.sqrt(np.mean(np.asarray(w[a], float) ** 2))) for a in ACCELEROMETERS},
            peak={a: float(np.max(np.abs(w[a]))) for a in ACCELEROMETERS},
            band_db={a: band_energy_db(np.asarray(w[a], float), w.rate_hz, *BAND_HZ) for a in ACCELEROMETERS},
            ac6_dtw=resample_poly(np.asarray(w["AC6"], float), up, down),
        )


def _ratio(target: float, rate: float) -> tuple[int, int]:
    from fractions import Fraction

    f = Fraction(target / rate).limit_denominator(1000)
    return f.numerator, f.denominator


def _rel(x: float, ref: float) -> float:
    return abs(x - ref) / abs(ref) if ref != 0 else (0.0 if x == 0 else math.inf)


def compare(s: WindowStats, ref: WindowStats) -> dict[str, float]:
    """Metrics of ``s`` against the truth ``ref`` (see module docstring)."""
    js = ref.joints
    n = min(s.ac6_dtw.size, ref.ac6_dtw.size)
    dtw = dtw_compare(ref.ac6_dtw[:n], s.ac6_dtw[:n], DTW_RATE_HZ, DTW_WINDOW_S)
    return {
        "impacts": float(np.mean([abs(s.impacts[j] - ref.impacts[j]) / max(ref.impacts[j], 1) for j in js])),
        "peak_fn": float(np.mean([_rel(s.peak_fn[j], ref.peak_fn[j]) for j in js])),
        "mean_fn": float(np.mean([_rel(s.mean_fn[j], ref.mean_fn[j]) for j in js])),
        "rms_slider": _rel(s.rms["AC6"], ref.rms["AC6"]),
        "rms_rod": max(_rel(s.rms[a], ref.rms[a]) for a in ROD_SENSORS),
        "peak_slider": _rel(s.peak["AC6"], ref.peak["AC6"]),
        "peak_rod": max(_rel(s.peak[a], ref.peak[a]) for a in ROD_SENSORS),
        "band_db": max(abs(s.band_db[a] - ref.band_db[a]) for a in ACCELEROMETERS),
        "dtw_slider": dtw.distance_pct,
    }


def score(metrics: dict[str, float]) -> float:
    """Largest metric/target ratio over the targeted metrics (≤ 1: every target met)."""
    return max(metrics[k] / v for k, v in TARGETS.items())


def pareto_front(points: Sequence[Sequence[float]]) -> list[bool]:
    """For each point (cost, error, ...): True when no other point is at least as good in every
    coordinate and strictly better in one (lower is better everywhere)."""
    pts = [tuple(float(x) for x in p) for p in points]
    out = []
    for i, p in enumerate(pts):
        dominated = any(all(b <= a for a, b in zip(p, q)) and any(b < a for a, b in zip(p, q))
                        for k, q in enumerate(pts) if k != i)
        out.append(not dominated)
    return out


# ---------------------------------------------------------------------------- the study
def run_variant(v: Variant, test_id: int, s: StudySettings) -> tuple[WindowStats, dict[str, Any]]:
    """Simulate one variant on one test; (window stats, timing)."""
    from twin.simulation import simulate_run

    cfg = v.config(scene(test_id, s))
    t = time.perf_counter()
    run = simulate_run(cfg)
    total = time.perf_counter() - t
    stats = WindowStats.of(run, s.t0, s.duration_s)
    wall = float(run.meta.get("wall_s") or total)
    timing = {"wall_s": wall, "total_s": total, "wall_per_sim_s": wall / cfg.duration_s,
              "timestep_s": cfg.simulation.timestep_s, "rate_hz": run.rate_hz,
              "warnings": run.meta.get("warnings")}
    return stats, timing


@dataclass(frozen=True)
class AccuracyOptions:
    """What the study runs.

    Attributes:
        out: output folder (created if needed).
        settings: the scenes' timing and tests (:data:`QUICK` for the reduced version).
        quick: the reduced variant list (:func:`variants`); recorded in the results.
        variants: the variants compared instead (must contain :data:`DEFAULT_KEY`); None = :func:`variants`.
        progress: a progress bar on stderr.
    """

    out: str | Path
    settings: StudySettings = StudySettings()
    quick: bool = False
    variants: tuple[Variant, ...] | None = None
    progress: bool = False

    def __post_init__(self) -> None:
        if self.variants is not None and not any(v.key == DEFAULT_KEY for v in self.variants):
            raise ConfigError("variants", f"must contain {DEFAULT_KEY!r}")


@dataclass(frozen=True)
class VariantSummary:
    """One variant over the study's tests (a row of ``accuracy.json``'s ``summary``).

    Attributes:
        key: the variant's name; engine: "mujoco" or "reference"; family: its group in the plots.
        overrides: the configuration fields it sets (dotted path -> value).
        wall_per_sim_s: mean wall time per simulated second [s/s]; real_time_factor: its inverse [-].
        mean, worst: metric name -> its mean and its largest value over the tests (:data:`METRICS`).
        score, worst_score: :func:`score` of ``mean`` and of ``worst`` [-].
        pareto, pareto_score: whether the variant is on the cost/metrics and on the cost/score Pareto
            fronts of the MuJoCo variants; None for the reference variants.
    """

    key: str
    engine: str
    family: str
    overrides: Mapping[str, Any]
    wall_per_sim_s: float
    real_time_factor: float
    mean: Mapping[str, float]
    worst: Mapping[str, float]
    score: float
    worst_score: float
    pareto: bool | None
    pareto_score: bool | None

    def to_dict(self) -> dict[str, Any]:
        return {f.name: dict(v) if isinstance(v := getattr(self, f.name), Mapping) else v
                for f in dataclasses.fields(self)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "VariantSummary":
        return cls(**{f.name: dict(d[f.name]) if isinstance(d[f.name], Mapping) else d[f.name]
                      for f in dataclasses.fields(cls)})


@dataclass(frozen=True)
class AccuracyResult:
    """What the study found (``accuracy.json``): per variant its mean and worst metrics over the
    tests, score and Pareto membership (``summary``), every test's rows (``per_test``)."""

    settings: dict[str, Any]
    targets: dict[str, float]
    default: str
    default_on_pareto_front: bool
    default_on_score_front: bool
    summary: tuple[VariantSummary, ...]
    per_test: dict[str, Any]
    figures: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """The JSON data of ``accuracy.json``."""
        return {"settings": self.settings, "targets": self.targets, "default": self.default,
                "default_on_pareto_front": self.default_on_pareto_front,
                "default_on_score_front": self.default_on_score_front,
                "summary": [r.to_dict() for r in self.summary], "per_test": self.per_test, "figures": list(self.figures)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "AccuracyResult":
        """The result of a dict as :meth:`to_dict` (or ``accuracy.json``) holds it."""
        return cls(settings=d["settings"], targets=d["targets"], default=d["default"],
                   default_on_pareto_front=d["default_on_pareto_front"],
                   default_on_score_front=d["default_on_score_front"],
                   summary=tuple(VariantSummary.from_dict(r) for r in d["summary"]), per_test=d["per_test"],
                   figures=tuple(d["figures"]))


def run_study(options: AccuracyOptions, *, log: Callable[[str], None] | None = None) -> AccuracyResult:
    """Run every variant on every test, compare with the truth, write ``accuracy.md``,
    ``accuracy.json`` and the PNGs to ``options.out``; ``log`` receives a line per test."""
    settings, quick, progress = options.settings, options.quick, options.progress
    variant_list = options.variants
    out = Path(options.out)
    out.mkdir(parents=True, exist_ok=True)
    vs = list(variant_list) if variant_list is not None else variants(quick)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(settings.tests) * (len(vs) + 1), desc="accuracy", unit="run", leave=False)
    per_test: dict[int, dict[str, Any]] = {}
    try:
        for test_id in settings.tests:
            truth, tt = run_variant(TRUTH, test_id, settings)
            rows: dict[str, Any] = {TRUTH.key: {"timing": tt, "metrics": compare(truth, truth),
                                                "impacts": truth.impacts, "peak_fn": truth.peak_fn}}
            if bar is not None:
                bar.update()
            for v in vs:
                if bar is not None:
                    bar.set_postfix_str(f"test {test_id}: {v.key}")
                st, tm = run_variant(v, test_id, settings)
                rows[v.key] = {"timing": tm, "metrics": compare(st, truth), "impacts": st.impacts,
                               "peak_fn": st.peak_fn}
                if bar is not None:
                    bar.update()
            per_test[test_id] = rows
            if log:
                d = rows[DEFAULT_KEY]
                log(f"test {test_id}: default score {score(d['metrics']):.2f}, "
                    f"{d['timing']['wall_per_sim_s']:.2f} s per simulated s; truth impacts {truth.impacts}")
    finally:
        if bar is not None:
            bar.close()
    data = aggregate(per_test, vs, settings, quick)
    data["figures"] = plots(out, data)
    atomic_write_json(out / "accuracy.json", stamped(data))
    atomic_write_text(out / "accuracy.md", with_stamp_line(render_markdown(data)))
    return AccuracyResult.from_dict(data)


def aggregate(per_test: dict[int, dict[str, Any]], vs: Sequence[Variant], settings: StudySettings,
              quick: bool) -> dict[str, Any]:
    """Mean and worst metric per variant over the tests, score, Pareto front."""
    summary = []
    for v in [TRUTH, *vs]:
        rows = [per_test[t][v.key] for t in settings.tests]
        mean = {k: float(np.mean([r["metrics"][k] for r in rows])) for k in METRICS}
        worst = {k: float(np.max([r["metrics"][k] for r in rows])) for k in METRICS}
        cost = float(np.mean([r["timing"]["wall_per_sim_s"] for r in rows]))
        summary.append({"key": v.key, "engine": v.engine, "family": v.family, "overrides": v.overrides,
                        "wall_per_sim_s": cost, "real_time_factor": 1.0 / cost if cost > 0 else math.inf,
                        "mean": mean, "worst": worst, "score": score(mean), "worst_score": score(worst)})
    cand = [r for r in summary if r["engine"] == "mujoco"]
    front = pareto_front([(r["wall_per_sim_s"], *(r["mean"][k] for k in FRONT_METRICS)) for r in cand])
    front_score = pareto_front([(r["wall_per_sim_s"], r["score"]) for r in cand])
    for r in summary:
        r["pareto"] = r["pareto_score"] = None
    for r, f, g in zip(cand, front, front_score):
        r["pareto"], r["pareto_score"] = f, g
    default = next(r for r in summary if r["key"] == DEFAULT_KEY)
    return {
        "settings": {"tests": list(settings.tests), "ramp_s": settings.ramp_s, "settle_s": settings.settle_s,
                     "window_s": settings.window_s, "quick": quick, "truth": TRUTH.key,
                     "truth_timestep_s": TRUTH_TIMESTEP_S, "band_hz": list(BAND_HZ), "dtw_rate_hz": DTW_RATE_HZ,
                     "dtw_window_s": DTW_WINDOW_S},
        "targets": TARGETS,
        "default": DEFAULT_KEY,
        "default_on_pareto_front": bool(default["pareto"]),
        "default_on_score_front": bool(default["pareto_score"]),
        "summary": summary,
        "per_test": {str(t): per_test[t] for t in settings.tests},
    }


def _fmt_metric(k: str, x: float) -> str:
    if not math.isfinite(x):
        return "inf"
    return f"{x:.2f}" if METRICS[k] else f"{100 * x:.1f}"


def render_markdown(data: dict[str, Any]) -> str:
    s = data["settings"]
    heads = {"impacts": "impacts %", "peak_fn": "peak Fn %", "mean_fn": "mean Fn %", "rms_slider": "AC6 RMS %",
             "rms_rod": "AC1-4 RMS %", "peak_slider": "AC6 peak %", "peak_rod": "AC1-4 peak %",
             "band_db": "band dB", "dtw_slider": "AC6 DTW %"}
    lines = [
        "# Run time versus error (twin study accuracy)",
        "",
        f"Tests {s['tests']}, window {s['window_s']} s after a {s['ramp_s']} s ramp and {s['settle_s']} s settling; "
        f"truth: {s['truth']}. Errors are means over the tests (worst test in the JSON). Relative errors in %, "
        f"band = largest |ΔdB| over AC1–AC6 in {s['band_hz'][0]:g}–{s['band_hz'][1]:g} Hz, DTW = normalized DTW "
        f"distance of AC6 at {s['dtw_rate_hz']:g} Hz. Score = largest mean error / target "
        f"({', '.join(f'{k} {v:g}' for k, v in data['targets'].items())}); cost = engine wall time per simulated "
        "second on this machine. **bold** = the default; P = on the Pareto front of the MuJoCo variants "
        "(cost vs every targeted error and the DTW distance), S = on their (cost, score) front.",
        "",
        "| variant | s / sim s | RTF | " + " | ".join(heads[k] for k in METRICS) + " | score | front |",
        "|---|---:|---:|" + "---:|" * len(METRICS) + "---:|:-:|",
    ]
    for r in data["summary"]:
        name = f"**{r['key']}**" if r["key"] == data["default"] else r["key"]
        p = ("P" if r["pareto"] else "") + ("S" if r["pareto_score"] else "")
        lines.append(f"| {name} | {r['wall_per_sim_s']:.3f} | {r['real_time_factor']:.2f} | "
                     + " | ".join(_fmt_metric(k, r["mean"][k]) for k in METRICS)
                     + f" | {r['score']:.2f} | {p} |")
    d = next(r for r in data["summary"] if r["key"] == data["default"])
    lines += ["", f"Default ({data['default']}): score {d['score']:.2f} (worst test {d['worst_score']:.2f}), "
                  f"{'on' if data['default_on_pareto_front'] else 'NOT on'} the Pareto front "
                  f"({'on' if data['default_on_score_front'] else 'not on'} the (cost, score) front), "
                  f"real-time factor {d['real_time_factor']:.2f}.", ""]
    lines += ["Default per test (truth = converged reference):", "",
              "| test | truth impacts | default impacts | peak Fn % | AC1-4 RMS % | band dB | AC6 DTW % | score |",
              "|---:|---|---|---:|---:|---:|---:|---:|"]
    for t, rows in data["per_test"].items():
        r, tr = rows[data["default"]], rows[s["truth"]]
        m = r["metrics"]
        lines.append(f"| {t} | {tr['impacts']} | {r['impacts']} | {100 * m['peak_fn']:.1f} | {100 * m['rms_rod']:.2f} | "
                     f"{m['band_db']:.2f} | {m['dtw_slider']:.2f} | {score(m):.2f} |")
    lines += [""]
    lines += ["Targets met by the default on average:", ""]
    for k, v in data["targets"].items():
        ok = d["mean"][k] <= v
        lines.append(f"- {k}: {_fmt_metric(k, d['mean'][k])} (target {_fmt_metric(k, v)}) — {'met' if ok else 'NOT met'}")
    lines.append("")
    return "\n".join(lines)


def plots(out: Path, data: dict[str, Any]) -> list[str]:
    """One work–precision PNG per metric and one of the score; returns the file names."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in data["summary"] if r["family"] != "truth"]
    colors = {"default": "k", "timestep": "tab:blue", "integrator": "tab:orange", "solver": "tab:green",
              "contact": "tab:red", "bushing": "tab:purple", "reference": "tab:brown"}
    names = []
    for k in [*METRICS, "score"]:
        fig, ax = plt.subplots(figsize=(8, 5.5))
        pts = []
        for r in rows:
            y = r["score"] if k == "score" else (r["mean"][k] if METRICS[k] else 100 * r["mean"][k])
            x = r["wall_per_sim_s"]
            pts.append((x, y))
            default = r["key"] == data["default"]
            ax.scatter(x, max(y, 1e-6), s=160 if default else 40, marker="*" if default else "o",
                       color=colors.get(r["family"], "gray"), zorder=3, edgecolor="k" if default else None)
            ax.annotate(r["key"], (x, max(y, 1e-6)), fontsize=7, xytext=(4, 3), textcoords="offset points")
        tw = [p for p, r in zip(pts, rows) if r["engine"] == "mujoco"]
        fp = sorted(p for p, f in zip(tw, pareto_front(tw)) if f)
        ax.step([p[0] for p in fp], [max(p[1], 1e-6) for p in fp], where="post", color="gray", lw=1,
                ls="--", label="Pareto front (MuJoCo variants)")
        if k in TARGETS or k == "score":
            tgt = 1.0 if k == "score" else (TARGETS[k] if METRICS[k] else 100 * TARGETS[k])
            ax.axhline(tgt, color="tab:red", lw=0.8, ls=":", label="target")
        ax.axvline(1.0, color="gray", lw=0.6, ls=":", label="real time")
        ax.set_xscale("log")
        ax.set_yscale("log")
        unit = "score (max error/target)" if k == "score" else (f"{k} [{METRICS[k]}]" if METRICS[k] else f"{k} [%]")
        ax.set_xlabel("engine wall time per simulated second [s]")
        ax.set_ylabel(f"{unit}, mean over tests")
        ax.set_title(f"work–precision: {k} (vs {data['settings']['truth']})")
        ax.legend(fontsize=8, loc="best")
        ax.grid(True, which="both", alpha=0.3)
        buf = io.BytesIO()
        fig.tight_layout()
        fig.savefig(buf, format="png", dpi=100, metadata=figure_metadata())
        plt.close(fig)
        name = f"work_precision_{k}.png"
        atomic_write_bytes(out / name, buf.getvalue())
        names.append(name)
    return names
