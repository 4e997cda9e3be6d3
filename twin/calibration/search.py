"""The search: evaluations (parallel, logged, resumable) and the global-then-local stages.

Stages, in normalized coordinates u ∈ [0, 1]^d (:class:`twin.calibration.params.Parameter`):

1. ``short``: the base point, then a scrambled Sobol sample (``n_global`` points,
   :class:`scipy.stats.qmc.Sobol`, seeded) on short windows (the first ``short_fraction`` of each
   recording), then Nelder–Mead (bounded, scipy) from the best point, ``local_short`` evaluations;
2. ``full``: Nelder–Mead from the short stage's best on the whole recordings, ``local_full``
   evaluations, then the profile points (each parameter moved by ± ``profile_steps`` from the best
   point, the others held), evaluated in parallel.

Why these: a handful of parameters, a noisy-but-deterministic objective (common random numbers) that
costs about a second per evaluation; a space-filling sample finds the basin without gradients, and
Nelder–Mead needs no derivatives and few evaluations in 1-5 dimensions. A Bayesian optimizer would
save evaluations at 5+ parameters but adds a dependency; not needed for a first version.

Every evaluation is appended to ``evaluations.jsonl`` (JSON lines: one header, then one line per
evaluation, flushed as it is written). A calibration started again with the same recordings,
parameters, bounds and options reads the log back (checked line by line; a truncated last line,
left by an interruption, is dropped) and takes the logged evaluations instead of simulating them
again: the searches are deterministic, so they retrace their steps through the log.
"""

from __future__ import annotations

import json
import math
import os
import time
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np

from twin.calibration.objective import combine
from twin.errors import TwinError

LOG_FORMAT = "twin-calibration-log"
LOG_VERSION = 2  # 2: full-length evaluations log their residual vectors ("resid")
#: objective value given to a point whose simulation failed (unstable parameters): worse than any real one
#: (the terms are scaled by the repeats' scatter, so a real objective can reach 1e6 and more)
FAILED_J = 1e300


def _key(stage: str, u: np.ndarray) -> tuple:
    return (stage, *(round(float(x), 10) for x in u))


class LogError(TwinError):
    """The evaluation log cannot be resumed (another calibration's, or damaged)."""


def read_log(path: Path, header: dict[str, Any], d: int) -> tuple[list[dict[str, Any]], list[str]]:
    """The evaluations of the log at ``path`` whose header equals ``header``; notes on what was dropped.
    LogError naming ``log`` when the header differs or a line other than the last is damaged."""
    notes: list[str] = []
    lines = path.read_text(encoding="utf-8").split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    if not lines:
        return [], notes
    try:
        first = json.loads(lines[0])
    except json.JSONDecodeError:
        raise LogError(f"{path}: line 1 is not JSON; not an evaluation log (delete it or choose another output "
                       "folder)", field="log") from None
    if not isinstance(first, dict) or first.get("format") != LOG_FORMAT:
        raise LogError(f"{path}: not a {LOG_FORMAT} file", field="log")
    if first.get("version") != header.get("version"):
        raise LogError(f"{path}: an evaluation log of version {first.get('version', 1)!r} (another twin's; this twin "
                       f"resumes version {header.get('version')!r} only); delete it to start over or use another "
                       "output folder", field="log")
    diff = sorted(k for k in set(first) | set(header) if k != "created" and first.get(k) != header.get(k))
    if diff:
        raise LogError(f"{path} was written by another calibration ({', '.join(diff)} differ); use another output "
                       "folder or delete the log to start over", field="log")
    out = []
    for i, line in enumerate(lines[1:], start=2):
        try:
            e = json.loads(line)
            ok = (isinstance(e, dict) and e.get("stage") in ("short", "full") and isinstance(e.get("u"), list)
                  and len(e["u"]) == d and all(isinstance(x, (int, float)) and 0 <= x <= 1 for x in e["u"])
                  and e.get("status") in ("ok", "failed") and isinstance(e.get("terms"), list)
                  and all(isinstance(t, dict) and all(isinstance(v, (int, float)) for v in t.values())
                          for t in e["terms"])
                  and all(isinstance(r, list) and all(isinstance(t, dict) for t in r)
                          for r in e.get("terms_rep", [])))
        except json.JSONDecodeError:
            ok = False
        if not ok:
            if i == len(lines):
                notes.append(f"{path.name}: dropped a damaged last line (an interrupted write)")
                break
            raise LogError(f"{path}: line {i} is not a valid evaluation; delete the log to start over", field="log")
        out.append(e)
    return out, notes


class Evaluator:
    """Evaluations of the objective with a cache and an append-only log.

    ``tasks_of(stage, u_list)`` builds the worker tasks; ``scales[stage]`` the term scales;
    ``run(tasks)`` runs tasks (in this process or a pool) and yields results as they finish.
    """

    def __init__(self, log_path: Path, header: dict[str, Any], params, make_task: Callable[[str, np.ndarray, int], dict],
                 scales: dict[str, dict[str, float]], run: Callable[[list[dict]], Iterator[dict]],
                 progress: bool = False, run_single: Callable[[list[dict]], Iterator[dict]] | None = None):
        # run_single: the executor of a lone point (Nelder-Mead's steps): in this process, no pool start-up
        self.params, self.make_task, self.scales, self.run = params, make_task, scales, run
        self.run_single = run_single or run
        self.progress = progress
        self.cache: dict[tuple, dict[str, Any]] = {}
        self.history: list[dict[str, Any]] = []  # in the order evaluated (or read back)
        self.resumed = 0
        self.notes: list[str] = []
        self.simulated = 0
        log_path.parent.mkdir(parents=True, exist_ok=True)
        if log_path.exists():
            old, self.notes = read_log(log_path, header, len(params))
            for e in old:
                self.cache[_key(e["stage"], np.asarray(e["u"]))] = e
            self.resumed = len(old)
            # rewrite without a damaged tail (write then rename: the old log is never half-replaced)
            tmp = log_path.with_suffix(".jsonl.tmp")
            tmp.write_text("\n".join([json.dumps(header)] + [json.dumps(e) for e in old]) + "\n", encoding="utf-8")
            os.replace(tmp, log_path)
        else:
            log_path.write_text(json.dumps(header) + "\n", encoding="utf-8")
        self.log = open(log_path, "a", encoding="utf-8")

    def close(self) -> None:
        self.log.close()

    def value(self, e: dict[str, Any]) -> float:
        if e["status"] != "ok":
            return FAILED_J
        return float(sum(combine(t, self.scales[e["stage"]]) for t in e["terms"]))

    def replicate_values(self, e: dict[str, Any], k: int) -> list[float]:
        """The objective at ``e`` under each of its ``k`` noise replicates (empty if it has none)."""
        if e["status"] != "ok":
            return [FAILED_J] * k
        return [float(sum(combine(t, self.scales[e["stage"]]) for t in rep)) for rep in e.get("terms_rep", [])]

    def many(self, stage: str, us: list[np.ndarray], desc: str = "") -> list[float]:
        """Objective values at the points ``us`` of ``stage``; new points simulated (in parallel)."""
        us = [np.clip(np.asarray(u, dtype=np.float64), 0.0, 1.0) for u in us]
        keys = [_key(stage, u) for u in us]
        todo, seen = [], set()
        for k, u in zip(keys, us):
            if k not in self.cache and k not in seen:
                seen.add(k)
                todo.append((k, u))
        if todo:
            bar = None
            if self.progress:
                from tqdm import tqdm

                bar = tqdm(total=len(todo), desc=desc or f"{stage} evaluations", unit="eval", leave=False)
            tasks = [self.make_task(stage, u, i) for i, (_k, u) in enumerate(todo)]
            try:
                for r in (self.run_single if len(tasks) == 1 else self.run)(tasks):
                    k, u = todo[r["id"] if "id" in r else r["index"]]  # a crashed worker's report has no id
                    e = {"stage": stage, "u": [float(x) for x in u],
                         "x": [p.from_unit(x) for p, x in zip(self.params, u)],
                         "status": r["status"], "terms": r.get("terms", []),
                         "terms_rep": r.get("terms_rep", []), "resid": r.get("resid", []),
                         "error": r.get("error") or r.get("reason"),
                         "wall_s": r.get("wall_s", 0.0), "sim_wall_s": r.get("sim_wall_s", 0.0)}
                    if e["status"] != "ok":
                        e["terms"], e["terms_rep"], e["resid"] = [], [], []
                    self.cache[k] = e
                    self.log.write(json.dumps(e) + "\n")
                    self.log.flush()
                    self.simulated += 1
                    if bar is not None:
                        bar.update(1)
            finally:
                if bar is not None:
                    bar.close()
        out = []
        for k in keys:
            e = self.cache[k]
            self.history.append(e)
            out.append(self.value(e))
        return out

    def one(self, stage: str, u: np.ndarray) -> float:
        return self.many(stage, [u])[0]


def in_process(fn: Callable[[dict], dict]) -> Callable[[list[dict]], Iterator[dict]]:
    """Executor running the tasks one after the other in this process (one worker: no spawn cost)."""
    def run(tasks: list[dict]) -> Iterator[dict]:
        for t in tasks:
            yield fn(t)
    return run


def local_pool(workers: int, fn: Callable[[dict], dict]) -> Callable[[list[dict]], Iterator[dict]]:
    """The dataset machinery's local process pool (spawned workers; a crashed worker fails only its task).
    A new pool per call: see :class:`PersistentPool` for one kept across the stages."""
    from twin.dataset.generate import _local

    return _local(workers, fn)


class PersistentPool:
    """A local process pool kept across calls (the calibration's stages): the workers are spawned
    once and keep their prepared recordings (:func:`twin.calibration.objective.get_target` caches per
    process), so a batch costs its simulations only. A worker that dies fails the tasks in flight (each
    is reported ``failed``, as the dataset pool reports a crashed run) and the pool is started again.
    Call :meth:`close` at the end (or use it as a context manager)."""

    def __init__(self, workers: int, fn: Callable[[dict], dict]):
        self.workers, self.fn = int(workers), fn
        self.ex = None

    def _pool(self):
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        from twin.dataset.worker import watch_parent

        if self.ex is None:
            self.ex = ProcessPoolExecutor(max_workers=self.workers, mp_context=mp.get_context("spawn"),
                                          initializer=watch_parent)
        return self.ex

    def __call__(self, tasks: list[dict]) -> Iterator[dict]:
        from concurrent.futures import FIRST_COMPLETED, wait
        from concurrent.futures.process import BrokenProcessPool

        queue = list(tasks)[::-1]
        pending: dict = {}
        while queue or pending:
            ex = self._pool()
            while queue and len(pending) < 2 * self.workers:
                t = queue.pop()
                pending[ex.submit(self.fn, t)] = t
            finished, _ = wait(set(pending), return_when=FIRST_COMPLETED)
            broken = False
            for f in finished:
                t = pending.pop(f)
                try:
                    yield f.result()
                except BrokenProcessPool as err:
                    broken = True
                    yield {"id": t["id"], "status": "failed", "error": f"worker process died: {err}"}
            if broken:  # every task in flight died with the pool
                for t in pending.values():
                    yield {"id": t["id"], "status": "failed", "error": "worker process died"}
                pending = {}
                self.close()

    def close(self) -> None:
        if self.ex is not None:
            self.ex.shutdown(wait=True, cancel_futures=True)
            self.ex = None

    def __enter__(self) -> "PersistentPool":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def nelder_mead(ev: Evaluator, stage: str, u0: np.ndarray, maxfev: int, step: float) -> np.ndarray:
    """Bounded Nelder–Mead in normalized coordinates from ``u0``, at most ``maxfev`` evaluations;
    returns the best point evaluated."""
    from scipy.optimize import minimize

    d = len(u0)
    simplex = [np.asarray(u0, dtype=np.float64)]
    for i in range(d):
        v = simplex[0].copy()
        v[i] = v[i] + step if v[i] + step <= 1.0 else v[i] - step
        simplex.append(v)
    best = {"u": simplex[0], "J": math.inf}

    def f(u: np.ndarray) -> float:
        j = ev.one(stage, u)
        if j < best["J"]:
            best["u"], best["J"] = np.clip(u, 0, 1), j
        return j

    if maxfev > 0:
        minimize(f, simplex[0], method="Nelder-Mead", bounds=[(0.0, 1.0)] * d,
                 options={"maxfev": maxfev, "initial_simplex": np.asarray(simplex), "xatol": 1e-3, "fatol": 1e-6})
    return best["u"]


def sobol_points(d: int, n: int, seed: int) -> list[np.ndarray]:
    """``n`` scrambled Sobol points in [0, 1]^d (seeded: the same points every time)."""
    from scipy.stats import qmc

    if n <= 0:
        return []
    m = max(0, math.ceil(math.log2(n)))
    pts = qmc.Sobol(d, scramble=True, seed=seed).random_base2(m)[:n]
    return [np.asarray(p) for p in pts]


def estimate_wall_s(t_short: float, t_full: float, n_short: int, n_full: int, workers: int,
                    n_sobol: int, n_profile: int) -> float:
    """Wall-time estimate [s] from one timed evaluation per stage: the Sobol and profile points run
    ``workers`` at a time, Nelder–Mead one at a time."""
    w = max(1, workers)
    return (t_short * (math.ceil(n_sobol / w) + n_short) + t_full * (n_full + math.ceil(n_profile / w)))


def timing(e: dict[str, Any]) -> float:
    return float(e.get("wall_s", 0.0))


def now() -> float:
    return time.perf_counter()
