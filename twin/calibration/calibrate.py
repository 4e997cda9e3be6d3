"""``twin.calibrate``: fit configuration fields to bench recordings (see docs/calibration.md).

Steps: check every input (recordings, fields, bounds, options, output folder) before any simulation;
prepare each recording for the short and the full stage (:mod:`twin.calibration.objective`); term
scales from the repeats; time the base point in both stages and state the wall-time estimate; the
search (:mod:`twin.calibration.search`); intervals (:mod:`twin.calibration.bootstrap`: a paired block
bootstrap over crank turns at the fitted point and the objective's roughness; the first version's ΔJ
and noise intervals, :mod:`twin.calibration.uncertainty`, are kept in the report); the
outputs in the folder: ``calibrated.toml``, ``report.json``, ``report.md``, ``evaluations.jsonl``
(the resumable log) and PNG figures, each written atomically.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping

import numpy as np

from twin.config import BenchConfig
from twin.errors import ConfigError
from twin.calibration.params import overlay  # noqa: F401 - part of this module's API
from twin.calibration.rows import CorrelatedPair, EvaluationTimes

#: misfit per term (J*/n) above which the report warns that the fit did not reach the recordings' scatter
MISFIT_WARN = 10.0
#: the files a calibration writes in its output folder
OUTPUT_FILES = ("calibrated.toml", "report.json", "report.md", "evaluations.jsonl", "spectra.png",
                "windows.png", "history.png", "profiles.png")


@dataclass(frozen=True)
class CalibrationOptions:
    """Settings of a calibration.

    Attributes:
        n_global: Sobol points of the global stage (short windows).
        local_short: Nelder–Mead evaluations on short windows.
        local_full: Nelder–Mead evaluations on the whole recordings.
        profile_steps: offsets of the profile points in normalized coordinates (each ± around the best point).
        short_fraction: share of each recording simulated in the short stage (0.1-1).
        drive: "trace" (the encoder trace drives the crank PID, as ``twin replay``) or "program" (the
            configuration's own drive program: synthetic recordings, or bench runs whose program is known).
        workers: local worker processes (1 = this process).
        seed: seed of the Sobol sample.
        dtw_max_s: DTW on at most this much of each window [s].
        dtw_window_s: Sakoe–Chiba half-width of the DTW [s].
        delta_j: rise of the objective that bounds an interval (1 = one term moved by one scatter).
        replicates: noise replicates per full-length evaluation (other sensor-noise realizations of
            the same simulation; their minimizers' scatter is the noise's share of each interval,
            :func:`twin.calibration.uncertainty.replicate_spread`); 0 = the ΔJ rule alone.
        boot_replicates: replicates of the block bootstrap over crank turns at the fitted point
            (:mod:`twin.calibration.bootstrap`); 0 = none (the ΔJ interval is reported).
        interval: the reported interval: "bootstrap" (the bootstrap with the objective's jitter),
            "hull" (the hull of it and the ΔJ interval) or "dj" (the ΔJ interval with the noise replicates').
        plots: write the PNG figures.
        progress: progress bars on standard error.
        restarts: when the full-length best still misses the recordings (misfit per term J*/n above
            :data:`MISFIT_WARN`), local searches again from up to this many of the global stage's next-best
            points away from the basin already searched (half the local budgets each); 0 = none.
        waveform: after the feature fit, the waveform stage (:mod:`twin.calibration.waveform`): a local
            least-squares fit of the low-passed replayed accelerations, run only where the fitted point's
            replay is predictable (not chaotic); on a real bench it may fit model error into the parameters
            (the report gives each change against its interval). Off by default (docs/calibration.md).
        waveform_budget: replays of all recordings the waveform stage may use (Jacobian columns included).
    """

    n_global: int = 16
    local_short: int = 20
    local_full: int = 12
    profile_steps: tuple[float, ...] = (0.01, 0.03, 0.1, 0.25)
    short_fraction: float = 0.5
    drive: str = "trace"
    workers: int = 1
    seed: int = 0
    dtw_max_s: float = 0.05
    dtw_window_s: float = 0.002
    delta_j: float = 1.0
    replicates: int = 4
    boot_replicates: int = 400
    interval: str = "bootstrap"
    plots: bool = True
    progress: bool = False
    restarts: int = 2
    waveform: bool = False
    waveform_budget: int = 16

    def __post_init__(self) -> None:
        for name, lo, hi in (("n_global", 0, 4096), ("local_short", 0, 10_000), ("local_full", 0, 10_000),
                             ("workers", 1, 1024), ("seed", 0, 2 ** 31 - 1), ("replicates", 0, 64),
                             ("boot_replicates", 0, 100_000), ("restarts", 0, 64),
                             ("waveform_budget", 1, 10_000)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
                raise ConfigError(name, f"must be an integer in [{lo}, {hi}], got {v!r}")
        for name, lo, hi in (("short_fraction", 0.1, 1.0), ("dtw_max_s", 0.001, 10.0), ("dtw_window_s", 0.0, 1.0),
                             ("delta_j", 1e-6, 1e6)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and lo <= v <= hi):
                raise ConfigError(name, f"must be a number in [{lo:g}, {hi:g}], got {v!r}")
        if not isinstance(self.waveform, bool):
            raise ConfigError("waveform", f"must be true or false, got {self.waveform!r}")
        if self.interval not in ("bootstrap", "hull", "dj"):
            raise ConfigError("interval", f"must be bootstrap, hull or dj, got {self.interval!r}")
        if self.drive not in ("trace", "program"):
            raise ConfigError("drive", f"must be trace or program, got {self.drive!r}")
        steps = self.profile_steps
        if not isinstance(steps, tuple) or not all(isinstance(s, (int, float)) and not isinstance(s, bool)
                                                   and 0 < s <= 0.5 for s in steps):
            raise ConfigError("profile_steps", f"must be a tuple of numbers in (0, 0.5], got {steps!r}")


@dataclass(frozen=True)
class FittedParameter:
    """A fitted field: value, interval, base value, warnings [the field's unit]."""

    field: str
    value: float
    lo: float
    hi: float
    base: float
    bounds: tuple[float, float]
    method: str
    flat: bool
    on_bound: str
    noise_lo: float = math.nan
    noise_hi: float = math.nan
    #: the ΔJ interval (slice or marginal, the hull with the noise interval): the first version's
    dj_lo: float = math.nan
    dj_hi: float = math.nan
    #: the bootstrap interval alone, and with the jitter half-width (twin.calibration.bootstrap)
    boot_lo: float = math.nan
    boot_hi: float = math.nan
    rough: bool = False
    #: the feature fit's value where the waveform stage changed it (``value`` is then the stage's); else nan
    feature_value: float = math.nan

    def to_dict(self) -> dict[str, Any]:
        d = {**self.__dict__, "bounds": list(self.bounds)}
        for k in ("noise_lo", "noise_hi", "dj_lo", "dj_hi", "boot_lo", "boot_hi", "feature_value"):
            d[k] = None if not math.isfinite(d[k]) else d[k]
        return d


@dataclass(frozen=True)
class CalibrationResult:
    """What :func:`calibrate` found and wrote.

    Attributes:
        parameters: the fitted fields with their intervals.
        objective_before, objective_after: objective at the base and the fitted values (full length).
        terms_before, terms_after: the raw terms per recording at those points.
        scales: the term scales and where they come from (``scales_note``).
        correlated_pairs: pairs of fields the recordings cannot tell apart.
        warnings: fitted values on a bound, flat profiles, failed evaluations.
        evaluations: evaluations used (simulated now + read back from the log).
        simulated: evaluations simulated by this call; resumed: read back from the log.
        seconds_per_evaluation: mean wall time of a short and a full evaluation [s].
        wall_s: wall time of the call [s].
        out_dir: the output folder.
        report: the report dict (report.json).
    """

    parameters: tuple[FittedParameter, ...]
    objective_before: float
    objective_after: float
    terms_before: list[dict[str, float]]
    terms_after: list[dict[str, float]]
    scales: dict[str, float]
    scales_note: str
    correlated_pairs: tuple[CorrelatedPair, ...]
    warnings: list[str]
    evaluations: int
    simulated: int
    resumed: int
    seconds_per_evaluation: EvaluationTimes
    wall_s: float
    out_dir: Path
    report: dict[str, Any] = field(repr=False, default_factory=dict)

    def __post_init__(self) -> None:  # the rows as the search gives them (dicts) read into their types
        object.__setattr__(self, "correlated_pairs", tuple(
            p if isinstance(p, CorrelatedPair) else CorrelatedPair.from_dict(p) for p in self.correlated_pairs))
        if not isinstance(self.seconds_per_evaluation, EvaluationTimes):
            object.__setattr__(self, "seconds_per_evaluation", EvaluationTimes.from_dict(self.seconds_per_evaluation))

    def values(self) -> dict[str, float]:
        """Fitted value by field."""
        return {p.field: p.value for p in self.parameters}

    def to_dict(self) -> dict[str, Any]:
        """A JSON-able dict."""
        return {"parameters": [p.to_dict() for p in self.parameters], "objective_before": self.objective_before,
                "objective_after": self.objective_after, "terms_before": self.terms_before,
                "terms_after": self.terms_after, "scales": self.scales, "scales_note": self.scales_note,
                "correlated_pairs": [p.to_dict() for p in self.correlated_pairs], "warnings": self.warnings,
                "evaluations": self.evaluations, "simulated": self.simulated, "resumed": self.resumed,
                "seconds_per_evaluation": self.seconds_per_evaluation.to_dict(), "wall_s": self.wall_s,
                "out_dir": str(self.out_dir)}


def _check_recordings(recordings: Iterable[str | Path]) -> list[str]:
    if isinstance(recordings, (str, Path)):
        recordings = [recordings]
    recs = [str(r) for r in recordings]
    if not recs:
        raise ConfigError("recordings", "give one or more bench recordings (.mcap)")
    for r in recs:
        if not Path(r).is_file():
            raise ConfigError("recordings", f"{r} is not a file")
    if len(set(Path(r).resolve() for r in recs)) != len(recs):
        raise ConfigError("recordings", "a recording is given twice")
    return recs


def calibrate(recordings: Iterable[str | Path] | str | Path, params: Iterable[str] | str, out: str | Path, *,
              config: BenchConfig | None = None, bounds: Mapping[str, tuple[float, float]] | None = None,
              options: CalibrationOptions = CalibrationOptions(),
              note: Callable[[str], None] | None = None) -> CalibrationResult:
    """Fit the configuration fields ``params`` (dotted paths) to ``recordings`` and write the results
    in the folder ``out`` (module docstring). ``config``: the configuration the fields are set in for
    every recording (default: each recording's own); ``bounds``: {field: (low, high)} (default: the
    documented ranges); ``note``: called with one-line messages (the wall-time estimate, resumed
    evaluations). A folder holding a previous calibration's log with the same inputs resumes it."""
    from twin.calibration import objective as obj
    from twin.calibration import search, uncertainty
    from twin.calibration.params import make_parameters
    from twin.provenance import stamp
    from twin.util import check_output_dir

    wall0 = time.perf_counter()
    say = note or (lambda s: None)
    if not isinstance(options, CalibrationOptions):
        raise TypeError(f"options: must be a CalibrationOptions, got {type(options).__name__}")
    if config is not None and not isinstance(config, BenchConfig):
        raise TypeError(f"config: must be a BenchConfig or None, got {type(config).__name__}")
    recs = _check_recordings(recordings)
    out_dir = check_output_dir(out, "out", need_parent=False)
    base_toml = config.to_toml() if config is not None else None
    motor = any(str(f).strip().startswith("drivetrain.") for f in
                (params.split(",") if isinstance(params, str) else params))
    ripple = motor or any(str(f).strip().startswith("pid.") for f in
                          (params.split(",") if isinstance(params, str) else params))
    targets = {st: [obj.get_target(r, base_toml, frac, options.dtw_max_s, motor, options.drive) for r in recs]
               for st, frac in (("short", options.short_fraction), ("full", 1.0))}
    first = targets["full"][0].base
    P = make_parameters(params, first, bounds)
    for t in targets["full"][1:]:
        make_parameters([p.field for p in P], t.base, {p.field: (p.lo, p.hi) for p in P})
    fields = [p.field for p in P]
    out_dir.mkdir(parents=True, exist_ok=True)  # every input checked: the first thing written
    scales, scales_note = {}, ""
    for st, floor in (("short", obj.SEARCH_FLOOR), ("full", obj.SCALE_FLOOR)):
        scales[st], scales_note = obj.repeat_scales(targets[st], options.dtw_window_s, ripple, floor)

    header = {"format": search.LOG_FORMAT, "version": search.LOG_VERSION,
              "recordings": [obj.recording_key(r) for r in recs],
              "parameters": [{"field": p.field, "lo": p.lo, "hi": p.hi, "log": p.log} for p in P],
              "base_config": base_toml, "options": {"short_fraction": options.short_fraction, "drive": options.drive,
                                                    "dtw_max_s": options.dtw_max_s,
                                                    "dtw_window_s": options.dtw_window_s,
                                                    "replicates": options.replicates,
                                                    "trace_filter_hz": obj.TRACE_FILTER_HZ}}

    def make_task(stage: str, u: np.ndarray, i: int) -> dict[str, Any]:
        # run_id and index: what the dataset pool's report of a crashed worker names a task by
        return {"id": i, "run_id": f"evaluation-{i}", "index": i, "recordings": recs, "base_toml": base_toml,
                "fraction": options.short_fraction if stage == "short" else 1.0,
                "dtw_max_s": options.dtw_max_s, "dtw_window_s": options.dtw_window_s, "motor": motor,
                "ripple": ripple, "drive": options.drive, "fields": fields,
                "replicates": options.replicates if stage == "full" else 0,
                "values": [p.from_unit(x) for p, x in zip(P, u)]}

    # one pool for every stage (spawned once; its workers keep their prepared recordings)
    pool = search.PersistentPool(options.workers, obj.evaluate_task) if options.workers > 1 else None
    run = pool if pool is not None else search.in_process(obj.evaluate_task)
    ev = search.Evaluator(out_dir / "evaluations.jsonl", header, P, make_task, scales, run, options.progress,
                          run_single=search.in_process(obj.evaluate_task))
    try:
        if ev.resumed:
            say(f"resuming: {ev.resumed} evaluations read back from {out_dir / 'evaluations.jsonl'}")
        for n in ev.notes:
            say(n)
        base_vals = [t.base for t in targets["full"]]
        x0 = [min(p.hi, max(p.lo, float(obj_field(first, p.field)))) for p in P]
        u0 = np.asarray([p.to_unit(x) for p, x in zip(P, x0)])
        # the base point in both stages: the "before" numbers and the timing of the estimate
        j0_short = ev.one("short", u0)
        j0_full = ev.one("full", u0)
        t_short = search.timing(ev.cache[search._key("short", u0)])
        t_full = search.timing(ev.cache[search._key("full", u0)])
        n_prof = 2 * len(options.profile_steps) * len(P)
        est = search.estimate_wall_s(t_short, t_full, options.local_short, options.local_full, options.workers,
                                     options.n_global, n_prof)
        # each restart (only when the fit misses the recordings): half the local budgets and new profiles
        est_restart = options.restarts * search.estimate_wall_s(t_short, t_full, options.local_short // 2,
                                                                options.local_full // 2, options.workers, 0, n_prof)
        say(f"one evaluation takes {t_short:.2f} s (short windows) and {t_full:.2f} s (full length) for "
            f"{len(recs)} recording(s); about {options.n_global + options.local_short + options.local_full + n_prof} "
            f"evaluations: about {est / 60:.1f} min on {options.workers} worker(s)"
            + (f", up to {(est + est_restart) / 60:.1f} min if the fit misses the recordings ({options.restarts} "
               "restart(s))" if options.restarts else "")
            + (f", and up to {options.waveform_budget * t_full / 60:.1f} min more for the waveform stage "
               f"({options.waveform_budget} replays, one process)" if options.waveform else "")
            + (" (logged ones are not simulated again)" if ev.resumed else ""))
        # 1. global stage, short windows
        pts = search.sobol_points(len(P), options.n_global, options.seed)
        js = ev.many("short", pts, "global (Sobol, short windows)")
        cand = [(j0_short, u0)] + list(zip(js, pts))
        u_g = min(cand, key=lambda c: c[0])[1]
        u_s = search.nelder_mead(ev, "short", u_g, options.local_short, 0.1)
        # 2. full length
        u_f = search.nelder_mead(ev, "full", u_s, options.local_full, 0.05)
        # this run's path only (ev.history, cached or not): a resumed run retraces the same steps
        fulls = [(np.asarray(e["u"]), ev.value(e)) for e in ev.history if e["stage"] == "full"]
        u_best = min(fulls, key=lambda c: c[1])[0] if fulls else u_f

        def profile(centre: np.ndarray) -> None:
            prof = []
            for i in range(len(P)):
                for s in options.profile_steps:
                    for sign in (-1, 1):
                        v = centre.copy()
                        v[i] = v[i] + sign * s
                        if 0 <= v[i] <= 1:
                            prof.append(v)
            ev.many("full", prof, "profiles (full length)")

        def full_points() -> dict[tuple, tuple[np.ndarray, float]]:
            out: dict[tuple, tuple[np.ndarray, float]] = {}
            for e in ev.history:
                if e["stage"] == "full":
                    out[search._key("full", np.asarray(e["u"]))] = (np.asarray(e["u"]), ev.value(e))
            return out

        u_centre = u_best.copy()
        profile(u_centre)
        seen = full_points()
        u_new = min(seen.values(), key=lambda c: c[1])[0]
        if not np.array_equal(u_new, u_centre):
            # a profile point beat the centre: the local search stopped short. Once more: Nelder-Mead
            # from it (half the full-length budget) and the profiles around the new best
            u_f = search.nelder_mead(ev, "full", u_new, max(2, options.local_full // 2), 0.02)
            seen = full_points()
            u_centre = min(seen.values(), key=lambda c: c[1])[0].copy()
            profile(u_centre)
            seen = full_points()
        restarted = []
        if options.restarts:
            u_centre, seen, restarted = _restart_on_misfit(ev, options, cand, [u_g], u_centre, seen, profile,
                                                           full_points)
        fulls = list(seen.values())
        reps = None
        if options.replicates:
            full_es = {search._key("full", np.asarray(e["u"])): e for e in ev.history if e["stage"] == "full"}
            cols = [ev.replicate_values(full_es[k], options.replicates) for k in seen]
            if cols and all(len(c) == options.replicates for c in cols):
                reps = np.asarray(cols, dtype=np.float64).T  # (K, n)
        u_best, j_best = min(fulls, key=lambda c: c[1])
        if not np.array_equal(u_best, np.clip(u_best, 0, 1)):
            u_best = np.clip(u_best, 0, 1)
        # the rise that bounds an interval: delta_j, inflated by the misfit per term where the best
        # point's terms exceed their scales (J*/n > 1: the scatter understates the model's error)
        n_terms = max(1, sum(len(t) for t in ev.cache[search._key("full", u_best)]["terms"]))
        inflation = max(1.0, float(j_best) / n_terms)
        unc = uncertainty.analyse(P, u_best, fulls, options.delta_j * inflation, centre=u_centre,
                                  replicates=reps)
        unc["inflation"] = inflation
        unc["restarts"] = restarted
        unc["profile_centre_is_best"] = bool(np.array_equal(u_centre, u_best))
        # the block bootstrap at the profile centre (one more simulation per recording; not logged)
        from twin.calibration import bootstrap as bs

        bt = make_task("full", u_centre, 0)
        bt["replicates"], bt["bootstrap"] = 0, (options.boot_replicates, options.seed)
        boot_res = next(iter(search.in_process(obj.evaluate_task)([bt]))) if options.boot_replicates else None
        full_es = {search._key("full", np.asarray(e["u"])): e for e in ev.history if e["stage"] == "full"}
        if boot_res is not None and boot_res["status"] == "ok":
            ents = list(full_es.values())
            boot = bs.analyse_bootstrap(P, u_best, u_centre, ents, [ev.value(e) for e in ents], boot_res["boot"],
                                        scales["full"], ripple, options.delta_j * inflation, seed=options.seed)
        else:
            boot = {"available": False, "why": ("boot_replicates = 0" if boot_res is None
                                                else f"the bootstrap's simulation failed: {boot_res.get('error')}")}
        e_before = ev.cache[search._key("full", u0)]
        e_after = ev.cache[search._key("full", u_best)]
    finally:
        ev.close()
        if pool is not None:
            pool.close()

    from twin.calibration.report import write_outputs

    fitted = tuple(_fitted(p, iv, x, boot["parameters"][i] if boot.get("available") else None, options.interval)
                   for i, (p, iv, x) in enumerate(zip(P, unc["intervals"], x0)))
    warnings = []
    wave = None
    if options.waveform:
        fitted, wave = _waveform(targets["full"], P, u_best, fitted, options, say, warnings)
    for f in fitted:
        if f.on_bound:
            warnings.append(f"{f.field}: the fitted value {f.value:.4g} sits on its {f.on_bound} bound "
                            f"({f.bounds[0]:g}..{f.bounds[1]:g}): the optimum may lie outside; widen the bounds")
        if f.flat:
            warnings.append(f"{f.field}: flat profile: these recordings do not tell its value (the objective "
                            f"moves by less than {options.delta_j:g} across the range)")
        if f.rough:
            warnings.append(f"{f.field}: ROUGH objective: it jumps between neighbouring values by more than the rise "
                            "that bounds an interval (chaotic impacts): these recordings do not tell its value; the "
                            "fitted number means nothing (longer recordings, more crank turns)")
    for pr in unc["correlated_pairs"]:
        warnings.append(f"{pr['a']} and {pr['b']} are correlated ({pr['correlation']:+.2f}): the recordings "
                        "cannot tell them apart")
    if not unc["profile_centre_is_best"]:
        warnings.append("a profile point was better than the point the profiles were taken around: the fitted "
                        "values are that point's, the slices are around the earlier one; more local evaluations "
                        "(local_full) would settle it")
    for r in unc.get("restarts", []):
        warnings.append(f"the search restarted from u = {', '.join(f'{x:.3g}' for x in r['start_u'])} (misfit per term "
                        f"{r['misfit_before']:.3g} above {MISFIT_WARN:g}): "
                        + ("a better point found" if r["improved"] else "no better point found"))
    if unc["inflation"] > MISFIT_WARN:
        warnings.append(f"the best point misses the recordings by {math.sqrt(unc['inflation']):.3g} scatters per term "
                        f"(J*/n = {unc['inflation']:.3g}): the search did not reach the recordings' scatter — a local "
                        "minimum, too small a budget, or a model that cannot match them; the intervals hold only if "
                        "this is the right basin (more n_global / local_full, fewer fields)")
    failed = sum(1 for e in ev.cache.values() if e["status"] != "ok")
    if failed:
        warnings.append(f"{failed} evaluation(s) failed (simulation error; counted as a very bad objective)")
    times = {st: float(np.mean([e["wall_s"] for e in ev.cache.values() if e["stage"] == st] or [math.nan]))
             for st in ("short", "full")}
    report = {
        "provenance": stamp(),
        "recordings": header["recordings"],
        "parameters": [f.to_dict() for f in fitted],
        "objective": {"before": j0_full, "after": j_best, "terms_before": e_before["terms"],
                      "terms_after": e_after["terms"], "scales": scales["full"], "scales_note": scales_note,
                      "delta_j": options.delta_j, "delta_j_used": unc["delta_j"]},
        "uncertainty": {k: v for k, v in unc.items() if k != "intervals"},
        "bootstrap": boot,
        "waveform": wave if wave is not None else {"ran": False, "reason": "not asked (waveform off)"},
        "identifiability": identifiability(P, unc["intervals"], unc["correlated_pairs"], unc["delta_j"], fitted),
        "warnings": warnings,
        "evaluations": {"total": len(ev.cache), "simulated_now": ev.simulated, "resumed": ev.resumed,
                        "failed": failed, "seconds_per_evaluation": times,
                        "estimate_s": est, "estimate_with_restarts_s": est + est_restart},
        "options": {k: (list(v) if isinstance(v, tuple) else v) for k, v in options.__dict__.items()},
        "base_config": "given (config)" if config is not None else "each recording's own",
    }
    result_wall = time.perf_counter() - wall0
    write_outputs(out_dir, report, targets["full"], P, x0, [f.value for f in fitted], config, ev, options,
                  base_vals)
    report["wall_s"] = time.perf_counter() - wall0
    from twin.util import atomic_write_json

    atomic_write_json(out_dir / "report.json", report)
    del result_wall
    return CalibrationResult(fitted, j0_full, j_best, e_before["terms"], e_after["terms"], scales["full"],
                             scales_note, unc["correlated_pairs"], warnings, len(ev.cache), ev.simulated,
                             ev.resumed, times, report["wall_s"], out_dir, report)


#: a restart's start lies at least this far (normalized, largest coordinate) from the starts already searched
RESTART_SEPARATION = 0.1


def _misfit(ev, u: np.ndarray, j: float) -> float:
    """The misfit per term J*/n of the full-length point ``u`` (objective ``j``)."""
    from twin.calibration import search

    return float(j) / max(1, sum(len(t) for t in ev.cache[search._key("full", u)]["terms"]))


def _restart_on_misfit(ev, options: CalibrationOptions, cand, starts, u_centre, seen, profile, full_points):
    """Restarts (``CalibrationOptions.restarts``): while the full-length best misses the recordings by more
    than :data:`MISFIT_WARN` per term, a short-window then a full-length Nelder–Mead (half the local
    budgets) from the next-best global point at least :data:`RESTART_SEPARATION` from every start so far;
    a better full-length point found becomes the centre of new profiles. Returns the profile centre, the
    full-length points and what each restart did (for the report)."""
    from twin.calibration import search

    done = []
    ranked = sorted(cand, key=lambda c: c[0])
    used = [np.asarray(u) for u in starts]
    for _ in range(options.restarts):
        u_best, j_best = min(seen.values(), key=lambda c: c[1])
        misfit = _misfit(ev, u_best, j_best)
        if misfit <= MISFIT_WARN:
            break
        nxt = next(((j, u) for j, u in ranked
                    if all(np.max(np.abs(np.asarray(u) - v)) >= RESTART_SEPARATION for v in used)), None)
        if nxt is None:
            break
        used.append(np.asarray(nxt[1]))
        u_s = search.nelder_mead(ev, "short", np.asarray(nxt[1]), max(2, options.local_short // 2), 0.1)
        u_f = search.nelder_mead(ev, "full", u_s, max(2, options.local_full // 2), 0.05)
        seen = full_points()
        u_new, j_new = min(seen.values(), key=lambda c: c[1])
        improved = bool(j_new < j_best)
        done.append({"start_u": [float(x) for x in nxt[1]], "misfit_before": misfit, "end_u": [float(x) for x in u_f],
                     "improved": improved, "misfit_after": _misfit(ev, u_new, j_new)})
        if improved:
            u_centre = u_new.copy()
            profile(u_centre)
            seen = full_points()
    return u_centre, seen, done


def _waveform(targets, P, u_best, fitted, options: CalibrationOptions, say, warnings: list[str]):
    """The waveform stage (:mod:`twin.calibration.waveform`) from the feature fit's point: the fitted
    parameters with the stage's values (intervals kept: the feature fit's) and the stage's report; a skip
    or a value moved outside its interval is a warning."""
    import dataclasses

    from twin.calibration.waveform import waveform_stage

    say(f"waveform stage: at most {options.waveform_budget} replays of {len(targets)} recording(s)")
    wave = waveform_stage(targets, P, u_best, [(f.lo, f.hi) for f in fitted], budget=options.waveform_budget, say=say)
    if not wave["ran"]:
        warnings.append(f"waveform stage skipped: {wave['reason']}")
        return fitted, wave
    fitted = tuple(dataclasses.replace(f, value=float(v), feature_value=f.value) for f, v in zip(fitted, wave["values"]))
    for f, c in zip(fitted, wave["changes"]):
        if not c.get("inside_interval", True):
            warnings.append(f"{f.field}: the waveform stage moved it from {f.feature_value:.6g} to {f.value:.6g}, outside "
                            f"its interval {f.lo:.4g} – {f.hi:.4g} from the features: either that interval is too narrow or the "
                            "waveform carries model error the stage fitted into the parameter (on a bench recording, "
                            "compare with --no-waveform)")
    return fitted, wave


def _fitted(p, iv, x0: float, bt: dict[str, Any] | None, how: str) -> FittedParameter:
    """The reported interval of one parameter from the ΔJ/noise interval ``iv`` and the bootstrap's ``bt``
    (``how``: "bootstrap" — the bootstrap with the jitter; "hull" — the hull of both; "dj" — the first version's)."""
    lo, hi, method = iv.lo, iv.hi, iv.method
    b_lo = b_hi = math.nan
    rough = False
    if bt is not None:
        b_lo, b_hi, rough = bt["boot_lo"], bt["boot_hi"], bool(bt["rough"])
        if how == "bootstrap":
            lo, hi, method = min(bt["lo"], iv.value), max(bt["hi"], iv.value), "bootstrap+jitter"
            if not rough and (iv.lo < lo or iv.hi > hi):
                # never narrower than where the objective rises by ΔJ (what it tells: a weakly told field,
                # e.g. restitution, gets a bootstrap far narrower than its profile allows;
                # analysis/restitution_length.py measures that rise)
                lo, hi, method = min(lo, iv.lo), max(hi, iv.hi), "bootstrap+jitter+dj"
        elif how == "hull":
            lo, hi, method = min(lo, bt["lo"]), max(hi, bt["hi"]), f"{method}+bootstrap"
    return FittedParameter(p.field, iv.value, lo, hi, x0, (p.lo, p.hi), method, iv.flat, iv.on_bound, iv.noise_lo,
                           iv.noise_hi, iv.lo, iv.hi, b_lo, b_hi, rough)


def identifiability(params, intervals, pairs, delta_j: float, fitted=None) -> list[dict[str, Any]]:
    """Per parameter, what the recordings tell: ``told`` (the interval is under a quarter of the range),
    ``weak`` (under the whole range but wider), ``flat`` (not told: the objective does not rise by ΔJ
    across the range), ``rough`` (not told: it jumps between neighbouring values, ``fitted[i].rough``), with the objective's rise along the profile, the interval's share of the range,
    the noise interval's share of it and the correlated partners."""
    out = []
    for i, (p, iv) in enumerate(zip(params, intervals)):
        f = fitted[i] if fitted is not None else iv
        share = (p.to_unit(f.hi) - p.to_unit(f.lo)) if f.hi > f.lo else 0.0
        noise = (p.to_unit(iv.noise_hi) - p.to_unit(iv.noise_lo)) if math.isfinite(iv.noise_lo) else math.nan
        verdict = ("flat" if iv.flat else "rough" if getattr(f, "rough", False) else "told" if share <= 0.25
                   else "weak")
        partners = [q["b"] if q["a"] == p.field else q["a"] for q in pairs if p.field in (q["a"], q["b"])]
        out.append({"field": p.field, "verdict": verdict, "profile_rise": iv.rise, "delta_j": delta_j,
                    "interval_share_of_range": share,
                    "noise_share_of_range": None if not math.isfinite(noise) else noise,
                    "correlated_with": partners})
    return out


def obj_field(cfg: BenchConfig, f: str) -> float:
    from twin.calibration.params import field_value

    return field_value(cfg, f)
