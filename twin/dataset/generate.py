"""The dataset driver: plan, resume, execute on a process pool or Dask, write the manifest.

Layout of ``DIR`` (``twin/dataset/FORMAT.md``): ``info.json``, ``runs.parquet``, ``stats.json``,
``data/<run_id>.parquet`` (workers), ``results/<run_id>.json`` (the driver's record of each
finished run, so that a killed generation resumes). Only the driver writes ``info.json``,
``results/``, ``runs.parquet`` and ``stats.json``; every file is written under a temporary name
and renamed.

Resuming: a run is done when its result record exists and says ``failed``, or says ``ok`` and
its data file exists with the recorded size (the checksum is checked by ``twin dataset
verify``). Everything else is run again; temporary files of killed processes are removed. A
``DIR`` whose ``info.json`` holds a different spec is refused before anything is written.

Executors: ``--workers N`` local processes (``--scheduler processes``:
``concurrent.futures.ProcessPoolExecutor``, spawn start method: every worker imports MuJoCo
itself), N threads of the driver process (``--scheduler threads``: one engine per run, stepping
without the GIL; the same bytes), or Dask distributed (``--scheduler local`` starts a
``LocalCluster`` of N single-threaded worker processes; ``--scheduler tcp://HOST:PORT`` submits to
a running cluster whose workers see ``DIR`` on a shared file system). Without ``--scheduler``
(:func:`default_scheduler`): threads up to :data:`THREADS_UP_TO` workers, processes beyond
(``analysis/bench_threads.py``, 2 cores: threads save the worker processes' start-up and step as
fast as processes; beyond that the Python of a run outside the engine, which holds the GIL, bounds
how far threads scale). Processes keep a crashing run (a segmentation fault) to its own worker;
on threads it ends the driver, and the same command resumes. Workers call
:func:`twin.dataset.worker.run_one` and return small dicts, never arrays.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator

from twin import __version__
from twin.dataset.design import RunPlan, base_config, plan
from twin.dataset.spec import SPLITS, DatasetSpec
from twin.dataset.worker import column_specs
from twin.errors import MissingExtraError, TwinError
from twin.util import (_TMP_RE, FolderLock, atomic_write_json, atomic_write_bytes, check_output_dir,
                       remove_stale_temps_in)

FORMAT = "twin-dataset/2"
#: folder of a dataset's bench recordings (``outputs.recordings``), one ``<run_id>.mcap`` per run
RECORDINGS_DIR = "recordings"
#: formats this version reads: twin-dataset/1 (data files hold the channels only, no ``run_id``,
#: ``t`` and label columns) is read as it is, never added to
READABLE = ("twin-dataset/1", FORMAT)


class DatasetError(TwinError):
    """A dataset folder cannot be used (another dataset, a missing or corrupt file)."""


@dataclass
class Prepared:
    """A planned dataset and what is already done in its folder."""

    spec: DatasetSpec
    out: Path
    runs: list[RunPlan]
    columns: list[Any]
    done: dict[str, dict[str, Any]]
    identity: dict[str, Any]
    label_types: dict[str, str] = field(default_factory=dict)

    @property
    def pending(self) -> list[RunPlan]:
        return [r for r in self.runs if r.run_id not in self.done]


def identity(spec: DatasetSpec) -> dict[str, Any]:
    """What makes two datasets the same: the spec (its base configuration by content, not path)."""
    c = spec.canonical()
    c["base_config"] = base_config(spec).to_toml() if spec.base_config else None
    return c


def dataset_columns(runs: list[RunPlan], spec: DatasetSpec) -> list[Any]:
    """Stored columns of the dataset: the union over its runs, in canonical order (channels a run
    lacks, e.g. the eccentricities of a joint without clearance, are stored as NaN there)."""
    if not runs:
        return []
    probe = runs[0].config.replace(**{"joints.clearance_a_mm": 0.1, "joints.clearance_b_mm": 0.1,
                                       "joints.clearance_c_mm": 0.1, "joints.allow_noncatalogue": True,
                                       "joints.clearance_guide_mm": 0.1})
    every = column_specs(probe, spec.outputs.truth, spec.outputs.instrumented, spec.outputs.dtype)
    present: set[str] = set()
    for r in runs:
        present.update(c.name for c in column_specs(r.config, spec.outputs.truth, spec.outputs.instrumented,
                                                    spec.outputs.dtype))
    return [c for c in every if c.name in present]


def prepare(spec: DatasetSpec, out_dir: str | Path) -> Prepared:
    """Plan the spec and read what ``out_dir`` already holds (refusing another dataset)."""
    runs = plan(spec)
    ident = identity(spec)
    out = check_output_dir(out_dir, "out_dir", need_parent=False)
    if out.exists():
        check_writable(out)
    info_path = out / "info.json"
    if out.exists() and any(e.name != FolderLock.NAME and not _TMP_RE.match(e.name) for e in out.iterdir()):
        if not info_path.is_file():
            raise DatasetError(f"{out} is not empty and holds no dataset (no info.json); choose an empty "
                               "or new folder", field="out_dir")
        try:
            info = json.loads(info_path.read_text())
        except (OSError, ValueError) as err:
            raise DatasetError(f"{info_path}: unreadable ({err})") from None
        if not isinstance(info, dict):
            raise DatasetError(f"{info_path}: must hold a JSON object, got {type(info).__name__}")
        if info.get("format") != FORMAT:
            older = info.get("format") in READABLE
            raise DatasetError(f"{out} holds a dataset of format {info.get('format')!r}"
                               + (f" (an older twin's; this one reads it but writes {FORMAT} only): generate into a "
                                  "new folder" if older else f", expected {FORMAT}: use another folder"), field="out_dir")
        if not isinstance(info.get("identity"), dict):
            raise DatasetError(f"{info_path}: field 'identity' must be an object, got {info.get('identity', 'missing')!r}"[:400])
        if info.get("identity") != json.loads(json.dumps(ident)):
            diff = sorted(k for k in set(ident) | set(info.get("identity", {}))
                          if info.get("identity", {}).get(k) != json.loads(json.dumps(ident)).get(k))
            raise DatasetError(f"{out} holds a different dataset ({info.get('identity', {}).get('name')!r}; "
                               f"differs in {', '.join(diff)}); use another folder", field="out_dir")
    columns = dataset_columns(runs, spec)
    done = _read_done(out, {r.run_id for r in runs}) if out.exists() else {}
    if len(done) < len(runs) and (out / "results").is_dir():
        ids = {r.run_id for r in runs}
        stale = [q.stem for q in (out / "results").glob("*.json") if q.stem not in ids]
        if done or stale:
            _check_same_code(info_path)
        if stale:
            # same spec, other run ids: each run's configuration changed (new fields or defaults of a
            # newer twin); adding the new runs beside the old ones would leave files no manifest names
            raise DatasetError(f"{out} holds {len(stale)} runs that this spec no longer plans (their "
                               "configurations differ, e.g. made by another twin version); use another folder", field="out_dir")
    return Prepared(spec, out, runs, columns, done, ident, label_types(runs))


def _check_same_code(info_path: Path) -> None:
    """Refuse to add runs to a dataset whose finished runs another twin or MuJoCo made: the same
    spec simulated by other physics (e.g. before a contact-law change) must not be mixed in one
    dataset. A complete dataset is only read, so it is never refused."""
    import mujoco

    try:
        versions = json.loads(info_path.read_text()).get("versions", {})
    except (OSError, ValueError):
        return  # info.json is rewritten by this generation; its runs' files were checked already
    ours = {"twin": __version__, "mujoco": mujoco.__version__}
    differ = [f"{k} {versions.get(k)!r} (now {v!r})" for k, v in ours.items() if versions.get(k) != v]
    if differ:
        raise DatasetError(f"{info_path.parent} was started by {', '.join(differ)}; its runs would mix two "
                           "versions of the physics: use another folder", field="out_dir")


def _read_done(out: Path, ids: set[str]) -> dict[str, dict[str, Any]]:
    done = {}
    res = out / "results"
    if not res.is_dir():
        return done
    for p in res.glob("*.json"):
        rid = p.stem
        if rid not in ids:
            continue
        try:
            r = json.loads(p.read_text())
        except (OSError, ValueError):
            continue  # a record that cannot be read is as good as none: run again
        if r.get("status") == "failed":
            done[rid] = r
        elif r.get("status") == "ok":
            f = out / "data" / f"{rid}.parquet"
            rec = r.get("recording")  # outputs.recordings: the run's bench recording too
            if f.is_file() and f.stat().st_size == r.get("bytes") and \
                    (not rec or (out / rec["file"]).is_file() and (out / rec["file"]).stat().st_size == rec["bytes"]):
                done[rid] = r
    return done


def run_labels(r: RunPlan) -> dict[str, Any]:
    """The labels of a run, as in its row of ``runs.parquet`` and as constant columns of its data
    file: split, design point and repeat, every varied factor (``factor_<name>``), fault and
    clearances, orientation, drive program and constant motor speed (NaN otherwise)."""
    out: dict[str, Any] = {"point": r.point, "repeat": r.repeat, "split": r.split}
    for k, v in r.factors.items():
        out[f"factor_{k}"] = v
    out.update(r.labels)
    out.update(orientation=r.config.mechanism.orientation, program=r.config.drive.program,
               motor_rpm=r.config.drive.motor_rpm if r.config.drive.program == "constant" else math.nan)
    return out


def label_types(runs: list[RunPlan]) -> dict[str, str]:
    """Arrow type of each label column, the same in every data file of the dataset (a factor that
    is a number in every run is float64, a string otherwise, as in ``runs.parquet``)."""
    values: dict[str, list[Any]] = {}
    for r in runs:
        for k, v in run_labels(r).items():
            values.setdefault(k, []).append(v)
    out = {}
    for k, vals in values.items():
        kinds = {type(v) for v in vals if v is not None}
        if k in ("point", "repeat"):
            out[k] = "int64"
        elif kinds and kinds <= {int, float}:
            out[k] = "float64"
        else:
            out[k] = "string"
    return out


def label_value(v: Any, dtype: str) -> Any:
    """A label value as stored in a column of type ``dtype`` (None: NaN for numbers, null for strings)."""
    if dtype == "float64":
        return math.nan if v is None else float(v)
    if dtype == "int64":
        return int(v)
    return None if v is None else str(v)


def task_of(p: Prepared, r: RunPlan) -> dict[str, Any]:
    labels = run_labels(r)
    return {"run_id": r.run_id, "index": r.index, "config_toml": r.config.to_toml(),
            "data_dir": str(p.out / "data"), "columns": [tuple(vars(c).values()) for c in p.columns],
            "instrumented": list(p.spec.outputs.instrumented),
            "recordings_dir": str(p.out / RECORDINGS_DIR) if p.spec.outputs.recordings else "",
            "labels": [(k, t, label_value(labels.get(k), t)) for k, t in p.label_types.items()]}


def group_tasks(p: Prepared, runs: list[RunPlan], warm_start: bool = True,
                approx_warm_start: bool = False) -> list[dict[str, Any]]:
    """The tasks of ``runs``: with ``warm_start``, runs of one :func:`twin.warm.mechanical_key` (the
    repeats of a design point: they differ in their noise seed only) are one task whose members share
    one engine run (each file the bytes of its run alone); groups in the order of their first run.
    Without, one task per run. ``approx_warm_start`` (opt-in, an approximation): runs of one
    :func:`twin.warm_approx.approx_key` are one task (``"approx": True``) whose members share one
    spin-up (:func:`twin.warm_approx.simulate_approx`)."""
    if approx_warm_start:
        from twin.warm_approx import approx_groups

        tasks = []
        for g in approx_groups([r.config for r in runs]):
            members = [task_of(p, runs[i]) for i in g]
            tasks.append(members[0] if len(members) == 1 else
                         {"run_id": members[0]["run_id"], "index": members[0]["index"], "members": members,
                          "approx": True})
        return tasks
    if not warm_start:
        return [task_of(p, r) for r in runs]
    from twin.warm import share_groups

    tasks = []
    for g in share_groups([r.config for r in runs]):
        members = [task_of(p, runs[i]) for i in g]
        tasks.append(members[0] if len(members) == 1 else
                     {"run_id": members[0]["run_id"], "index": members[0]["index"], "members": members})
    return tasks


def _results(res: dict[str, Any]) -> list[dict[str, Any]]:
    """The run results of one task's result (a group's, or a run's)."""
    return list(res["group"]) if "group" in res else [res]


# ---------------------------------------------------------------------- executors
def _crashed(task: dict, why: str) -> dict:
    """The result of a run whose worker process died (a segmentation fault, the OOM killer); of each
    member of a group task (:func:`group_tasks`)."""
    if "members" in task:
        return {"group": [_crashed(m, why) for m in task["members"]]}
    return {"run_id": task["run_id"], "index": task["index"], "status": "failed",
            "reason": f"the worker process died while simulating it ({why})", "wall_s": 0.0}


def _local(workers: int, fn: Callable[[dict], dict] | None = None) -> Callable[[list[dict]], Iterator[dict]]:
    """Executor on a local process pool; ``fn`` (default :func:`twin.dataset.worker.run_one`) must
    be importable by the spawned workers."""
    def run(tasks: list[dict]) -> Iterator[dict]:
        import multiprocessing as mp
        from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
        from concurrent.futures.process import BrokenProcessPool

        from twin.dataset.worker import run_one as default_fn, watch_parent

        run_one = fn or default_fn

        def pool(n: int) -> ProcessPoolExecutor:
            return ProcessPoolExecutor(max_workers=n, mp_context=mp.get_context("spawn"), initializer=watch_parent)

        def close(ex: ProcessPoolExecutor, interrupted: bool) -> None:
            for proc in list((getattr(ex, "_processes", None) or {}).values()):
                if proc.is_alive() and interrupted:
                    proc.terminate()  # interrupted: do not wait for the running simulations
            ex.shutdown(wait=True, cancel_futures=True)

        queue = list(tasks)[::-1]  # pop() from the end: design order
        ex = pool(workers)
        try:
            pending: dict = {}
            while queue or pending:
                while queue and len(pending) < 2 * workers:  # at most 2 queued per worker
                    t = queue.pop()
                    pending[ex.submit(run_one, t)] = t
                finished, _ = wait(set(pending), return_when=FIRST_COMPLETED)
                broken = []
                for f in finished:
                    t = pending.pop(f)
                    try:
                        yield f.result()
                    except BrokenProcessPool:
                        broken.append(t)
                if broken:
                    # a worker died: every run in flight fails with it. Run each alone in a fresh
                    # process; the one that kills its process again is recorded as failed.
                    broken += list(pending.values())
                    close(ex, interrupted=True)
                    pending = {}
                    for t in broken:
                        solo = pool(1)
                        try:
                            yield solo.submit(run_one, t).result()
                        except BrokenProcessPool as err:
                            yield _crashed(t, str(err) or "BrokenProcessPool")
                        finally:
                            close(solo, interrupted=False)
                    ex = pool(workers)
        finally:
            close(ex, interrupted=sys.exc_info()[0] is not None)
    return run


def _threads(workers: int, fn: Callable[..., dict] | None = None) -> Callable[[list[dict]], Iterator[dict]]:
    """Executor on ``workers`` threads of this process (:func:`twin.simulation.simulate_many`'s way:
    one engine, model and data object per run; the engines release the GIL while they step, so the
    files are the bytes a worker process writes). A run whose thread crashes the process takes the
    driver with it (the finished runs are kept; the same command resumes). When the driver stops
    (an error, Ctrl-C), the runs in flight are aborted at their next chunk and leave no file."""
    def run(tasks: list[dict]) -> Iterator[dict]:
        import threading
        from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

        from twin.dataset.worker import run_one as default_fn

        run_one = fn or default_fn
        stop = threading.Event()
        queue = list(tasks)[::-1]  # pop() from the end: design order
        ex = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="twin-run")
        try:
            pending: dict = {}
            while queue or pending:
                while queue and len(pending) < workers:
                    t = queue.pop()
                    pending[ex.submit(run_one, t, stop)] = t
                finished, _ = wait(set(pending), return_when=FIRST_COMPLETED)
                for f in finished:
                    pending.pop(f)
                    yield f.result()
        finally:
            stop.set()
            ex.shutdown(wait=True, cancel_futures=True)
    return run


#: what a Dask scheduler address says where Dask is not installed (the local executors never import it)
NO_DASK = "{}: Dask is not installed; a Dask scheduler needs the cluster extra: pip install 'twin[cluster]'"


def _require_dask(address: str) -> None:
    try:
        import distributed  # noqa: F401 - an optional dependency (the cluster extra)
    except ImportError:
        raise MissingExtraError(NO_DASK.format(address), field="scheduler") from None
    import re

    if address != "local" and not re.fullmatch(r"(tcp|tls|ucx)://[^\s/:]+(:\d{1,5})?/?|inproc://\S+", address):
        raise TwinError(f"{address!r} is not a Dask scheduler address like tcp://HOST:8786", field="scheduler")


def _dask_client(address: str):
    from distributed import Client

    try:
        return Client(address, timeout="20s")
    except Exception as err:  # noqa: BLE001 - distributed raises many types for an unreachable address
        why = str(err).strip().splitlines()[0][:200] if str(err).strip() else type(err).__name__
        raise TwinError(f"cannot reach a Dask scheduler at {address} ({why})", field="scheduler") from None


def _dask(address: str, workers: int) -> Callable[[list[dict]], Iterator[dict]]:
    _require_dask(address)  # before anything is written
    if address != "local":
        _dask_client(address).close()  # reachable now, before anything is written

    def run(tasks: list[dict]) -> Iterator[dict]:
        from distributed import Client, LocalCluster, as_completed

        from twin.dataset.worker import run_one

        cluster = None
        try:
            if address == "local":
                cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=40)
                client = Client(cluster)
            else:
                client = _dask_client(address)
            try:
                futures = {client.submit(run_one, t, key=f"twin-run-{t['run_id']}", pure=False): t for t in tasks}
                for f in as_completed(futures):
                    try:
                        yield f.result()
                    except Exception as err:  # noqa: BLE001 - KilledWorker and the like: the run, recorded
                        yield _crashed(futures[f], f"{type(err).__name__}: {err}".splitlines()[0][:300])
            finally:
                client.close()
        finally:
            if cluster is not None:
                cluster.close()
    return run


#: the default executor runs up to this many workers on threads, more on processes
THREADS_UP_TO = 2


def default_scheduler(workers: int) -> str:
    """The executor of ``--scheduler`` left out: 'threads' up to :data:`THREADS_UP_TO` workers,
    'processes' beyond (see the module docstring)."""
    return "threads" if workers <= THREADS_UP_TO else "processes"


def executor(scheduler: str | None, workers: int) -> Callable[[list[dict]], Iterator[dict]]:
    if scheduler is not None and not scheduler.strip():
        raise TwinError("is empty; give processes, threads, local or a Dask scheduler address", field="scheduler")
    scheduler = scheduler or default_scheduler(workers)
    if scheduler == "processes":
        return _local(workers)
    if scheduler == "threads":
        return _threads(workers)
    if scheduler != "local" and not scheduler.startswith(("tcp://", "tls://", "ucx://", "inproc://")):
        raise TwinError(f"must be 'processes', 'threads', 'local' or a Dask scheduler address like tcp://HOST:8786, got {scheduler!r}", field="scheduler")
    return _dask(scheduler, workers)


# ------------------------------------------------------------------------ driver
def generate(spec: DatasetSpec, out_dir: str | Path, *, workers: int | None = None, scheduler: str | None = None,
             limit: int | None = None, progress: bool = True, warm_start: bool = True,
             approx_warm_start: bool = False) -> dict[str, Any]:
    """Generate (or finish) the dataset of ``spec`` in ``out_dir``; returns the info dict.

    ``warm_start`` (default on: it changes no byte of any file): the runs to do that share their
    engine run (:func:`group_tasks`) are simulated once per group. ``approx_warm_start`` (opt-in: an
    approximation, docs/datasets.md): runs that differ in their nuisance parameters share one spin-up
    (:mod:`twin.warm_approx`); each such file's metadata says from when it holds its own physics."""
    from twin.util import resolve_workers

    workers = resolve_workers(workers)
    if limit is not None and limit < 0:
        raise TwinError(f"must be >= 0, got {limit}", field="limit")
    run_tasks = executor(scheduler, workers)  # checks the scheduler before anything is written
    p = prepare(spec, out_dir)  # every check, nothing written
    p.out.mkdir(parents=True, exist_ok=True)
    # one generator per folder: a second is refused naming the holder; the kernel frees the lock
    # of a holder that died (SIGKILL included), so a later run takes it over
    with FolderLock(p.out, "out_dir", "twin dataset generate"):
        p = prepare(spec, out_dir)  # again under the lock: runs the previous holder finished count as done
        return _generate_locked(p, workers, scheduler, run_tasks, limit, progress, warm_start, approx_warm_start)


def _generate_locked(p: Prepared, workers: int, scheduler: str | None, run_tasks, limit: int | None,
                     progress: bool, warm_start: bool = True, approx_warm_start: bool = False) -> dict[str, Any]:
    out = p.out
    check_writable(out)  # before anything is written: a complete dataset is never marked incomplete in vain
    todo = p.pending[:limit] if limit is not None else p.pending
    if todo or not (out / "info.json").is_file():
        _write_info(p, complete=False)  # first: a folder with info.json is this dataset's, whatever happens next
    dirs = [out, out / "data", out / "results"] + ([out / RECORDINGS_DIR] if p.spec.outputs.recordings else [])
    for d in dirs[1:]:
        d.mkdir(exist_ok=True)
    for d in dirs:
        remove_stale_temps_in(d)  # leftovers of killed processes, whatever they were writing
    t_start = time.perf_counter()
    sim_total = sum(r.config.duration_s for r in todo)
    bar = _Progress(len(todo), sim_total, progress)
    failed = 0
    tasks = group_tasks(p, todo, warm_start, approx_warm_start)
    try:
        for task_res in run_tasks(tasks):
            for res in _results(task_res):
                rid = res["run_id"]
                if res["status"] == "io-error":  # a full disk or a refused write: stop, keep what is done
                    finish(p)
                    raise DatasetError(f"run {rid}: {res['reason']}; the {len(p.done)} runs finished so far are "
                                       "kept, run the same command again once there is room")
                atomic_write_json(out / "results" / f"{rid}.json", res)
                p.done[rid] = res
                failed += res["status"] != "ok"
                bar.update(res)
    finally:
        bar.close()
    info = finish(p)
    info["generation"] = {"runs_this_call": len(todo), "failed_this_call": failed,
                          "wall_s": time.perf_counter() - t_start, "workers": workers,
                          "scheduler": scheduler or default_scheduler(workers), "warm_start": "approximate" if approx_warm_start else warm_start,
                          "engine_runs_this_call": len(tasks)}
    return info


#: the files a generation writes in the dataset folder (beside data/ and results/)
OWN_FILES = ("info.json", "runs.parquet", "stats.json")


def check_writable(out: Path) -> None:
    """Every place a generation writes in ``out`` can be written, checked before the first write: the
    folders ``out``, ``data`` and ``results`` are folders (or absent) where a file can be created, and
    ``info.json``, ``runs.parquet`` and ``stats.json`` are regular files (or absent), never links or
    folders. One line naming the place otherwise."""
    import stat as _stat

    from twin.util import show

    places = [(d, _stat.S_ISDIR, "is not a folder (a file or link where the dataset keeps its runs)")
              for d in (out, out / "data", out / "results", out / RECORDINGS_DIR)]
    places += [(out / n, _stat.S_ISREG, "is not a regular file (a link or folder where the dataset writes its own "
                                        "file)") for n in OWN_FILES]
    for path, kind_ok, what in places:
        try:
            mode = os.lstat(path).st_mode
        except FileNotFoundError:
            continue
        if not kind_ok(mode):
            raise DatasetError(f"{show(path)} {what}; move it away", field="out_dir")
        # no probe file: a folder's modification time is the dataset's own (a refused run changes nothing)
        if _stat.S_ISDIR(mode) and (not os.access(path, os.W_OK | os.X_OK) or os.statvfs(path).f_flag & os.ST_RDONLY):
            raise DatasetError(f"cannot write in {show(path)} (permission denied or a read-only file system)", field="out_dir")


class _Progress:
    def __init__(self, n: int, sim_s: float, enabled: bool):
        self.bar = None
        self.t0 = time.perf_counter()
        self.sim = 0.0
        if enabled and n:
            from tqdm import tqdm

            self.bar = tqdm(total=n, unit="run", desc="dataset", leave=False, file=sys.stderr)

    def update(self, res: dict[str, Any]) -> None:
        self.sim += res.get("simulated_s") or 0.0
        if self.bar is not None:
            rate = self.sim / max(time.perf_counter() - self.t0, 1e-9)
            self.bar.set_postfix_str(f"{rate:.2f} sim s/s", refresh=False)
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


# --------------------------------------------------------------------- manifest
def _row(p: Prepared, r: RunPlan) -> dict[str, Any]:
    res = p.done.get(r.run_id, {})
    row: dict[str, Any] = {"run_id": r.run_id, "index": r.index, "point": r.point, "repeat": r.repeat,
                           "seed": r.seed}
    row.update(run_labels(r))  # split, factors, fault, clearances, orientation, program, motor_rpm
    row.update(engine=r.config.simulation.engine, duration_s=r.config.duration_s,
               status=res.get("status", "pending"), reason=res.get("reason", ""),
               simulated_s=res.get("simulated_s") or 0.0, wall_s=res.get("wall_s") or 0.0,
               rows=int(res.get("rows") or 0), bytes=int(res.get("bytes") or 0), sha256=res.get("sha256", ""),
               file=f"data/{r.run_id}.parquet" if res.get("status") == "ok" else "")
    for k, v in (res.get("summary") or {}).items():
        row[f"summary_{k}"] = v
    return row


def manifest_table(p: Prepared):
    """``runs.parquet`` as a pyarrow table (one row per planned run)."""
    import pyarrow as pa

    rows = [_row(p, r) for r in p.runs]
    keys: list[str] = []
    for row in rows:
        keys.extend(k for k in row if k not in keys)
    cols = {}
    for k in keys:
        vals = [row.get(k) for row in rows]
        if k.startswith("summary_"):
            vals = [math.nan if v is None else float(v) for v in vals]
        elif k.startswith("factor_"):
            kinds = {type(v) for v in vals if v is not None}
            if kinds <= {int, float} and kinds:
                vals = [math.nan if v is None else float(v) for v in vals]
            else:
                vals = [None if v is None else str(v) for v in vals]
        cols[k] = pa.array(vals, type=pa.uint64()) if k == "seed" else vals
    return pa.table(cols)


def finish(p: Prepared) -> dict[str, Any]:
    """Write runs.parquet, stats.json (train split, ok runs) and the final info.json."""
    import io

    import pyarrow.parquet as pq

    from twin.dataset.storage import Stats

    buf = io.BytesIO()
    pq.write_table(manifest_table(p), buf, compression="zstd")
    atomic_write_bytes(p.out / "runs.parquet", buf.getvalue())
    st = Stats()
    for r in p.runs:
        res = p.done.get(r.run_id)
        if r.split == "train" and res and res.get("status") == "ok":
            for name, b in res.get("stats", {}).items():
                if b[0] > 0:
                    st.merge(name, b)
    atomic_write_json(p.out / "stats.json", {"split": "train", "channels": st.as_dict()})
    return _write_info(p, complete=all(r.run_id in p.done for r in p.runs))


def _write_info(p: Prepared, complete: bool) -> dict[str, Any]:
    import mujoco
    import pyarrow

    statuses = [p.done.get(r.run_id, {}).get("status", "pending") for r in p.runs]
    splits: dict[str, dict[str, Any]] = {}
    for r, s in zip(p.runs, statuses):
        d = splits.setdefault(r.split, {"runs": 0, "points": set(), "by_fault": {}, "ok": 0})
        d["runs"] += 1
        d["ok"] += s == "ok"
        d["points"].add(r.point)
        d["by_fault"][r.labels["fault"]] = d["by_fault"].get(r.labels["fault"], 0) + 1
    for d in splits.values():
        d["points"] = len(d["points"])
    rate = p.spec.outputs.rate_hz
    info = {
        "format": FORMAT,
        "name": p.spec.name,
        "complete": complete,
        "identity": p.identity,
        "runs": {"planned": len(p.runs), "ok": statuses.count("ok"), "failed": statuses.count("failed"),
                 "pending": statuses.count("pending")},
        "simulated_s_planned": sum(r.config.duration_s for r in p.runs),
        "channels": [{"name": c.name, "unit": c.unit, "group": c.group, "dtype": c.dtype, "rate_hz": rate}
                     for c in p.columns],
        "splits": {s: splits[s] for s in SPLITS if s in splits},
        "labels": ["fault", "clearance_b_mm", "clearance_c_mm"],
        "key_columns": ["run_id", "t"],
        "label_columns": list(p.label_types),
        "encoder_counts_per_rev": p.runs[0].config.instrumentation.encoder_counts_per_rev if p.runs else None,
        "versions": {"twin": __version__, "mujoco": mujoco.__version__, "pyarrow": pyarrow.__version__,
                     "python": sys.version.split()[0]},
        "files": {"runs": "runs.parquet", "stats": "stats.json", "data": "data/<run_id>.parquet",
                  "results": "results/<run_id>.json",
                  **({"recordings": f"{RECORDINGS_DIR}/<run_id>.mcap"} if p.spec.outputs.recordings else {})},
    }
    atomic_write_json(p.out / "info.json", info)
    return info

