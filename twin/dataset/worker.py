"""One dataset run, in a worker process: simulate, instrument, write, return a small summary.

:func:`run_one` is what the executors (a local process pool, Dask distributed) call. It takes a
task of plain data (the run's configuration as TOML text, its id, the output settings) and
returns a dict of numbers and strings, never arrays: status, wall time, file size and SHA-256,
the run summary, and per-channel statistics. A failed run (an engine error, a MuJoCo warning,
an exception) returns its reason instead and leaves no file. The signals go to
``data/<run_id>.parquet`` through :class:`twin.dataset.storage.ParquetRunWriter` (temporary
file, renamed when complete), chunk by chunk: a worker's memory does not grow with the run.

Instrumented outputs (``outputs.instrumented``) put every chunk through the bench's sensor chain
(:class:`twin.instrument.ChainStream`, noise stream 0, seeded by the run's
``instrumentation.seed``) and, for calibrated accelerations, the static calibration of a
simulated static recording (stream 1), as a bench recording is made.
"""

from __future__ import annotations

import resource
import time
import traceback
from pathlib import Path
from typing import Any

import numpy as np

from twin.run import Channel, Run

#: instrumented channel sets -> channel names (prefix-free)
INSTRUMENTED_CHANNELS = {
    "volts": [f"volt_AC{i}" for i in range(1, 7)],
    "counts": ["encoder_counts"],
    "command": ["motor_command"],
    "calibrated": [f"meas_AC{i}" for i in range(1, 7)],
}


def column_specs(cfg, truth_groups: tuple[str, ...], instrumented: tuple[str, ...], dtype: str):
    """The stored columns of a run of ``cfg`` (names, units, groups, storage types), in order."""
    from twin.channels import channel_specs
    from twin.dataset.storage import ColumnSpec, storage_dtype
    from twin.instrument.chain import daq_specs, meas_specs

    quantized = cfg.instrumentation.quantization
    out = []
    for s in channel_specs(cfg):
        # channel groups of the configuration: "joints" covers the run file's joint_B, joint_C
        if ("joints" if s.group.startswith("joint_") else s.group) in truth_groups:
            out.append(ColumnSpec(s.name, s.unit, s.group, *storage_dtype(s.name, s.dtype, dtype, False)))
    wanted = {n for k in instrumented for n in INSTRUMENTED_CHANNELS[k]}
    for s in daq_specs(cfg) + meas_specs():
        if s.name in wanted:
            run_dtype = "float32" if s.name.startswith("meas_") else s.dtype
            out.append(ColumnSpec(s.name, s.unit, s.group, *storage_dtype(s.name, run_dtype, dtype, quantized)))
    return out


class InstrumentSink:
    """Sink adapter: truth chunk -> stored channels (truth groups kept, DAQ and calibrated added)."""

    def __init__(self, cfg, columns, inner, instrumented: tuple[str, ...]):
        from twin.instrument.chain import ChainStream

        self.cfg, self.inner = cfg, inner
        self.columns = columns
        self.chain = ChainStream(cfg, cfg.output_rate_hz, stream=0, command="command" in instrumented) \
            if instrumented else None
        self.cal = None
        if "calibrated" in instrumented:
            from twin.instrument.chain import simulated_calibration

            self.cal = simulated_calibration(cfg, 1.0, stream=1)

    def write(self, chunk: Run) -> None:
        chans = dict(chunk.channels)
        if self.chain is not None:
            daq = self.chain.process(chunk)
            if daq.n != chunk.n:
                from twin.errors import TwinError

                raise TwinError("dataset outputs: the DAQ rate must equal the output rate")
            chans.update(daq.channels)
            if self.cal is not None:
                from twin.instrument.calibration import measured_accel

                chans.update(measured_accel(daq, self.cal).channels)
        out = {}
        for c in self.columns:
            # a channel this run lacks (the eccentricities of a joint without clearance): NaN
            out[c.name] = chans[c.name] if c.name in chans else \
                Channel(c.name, c.unit, c.group, np.full(chunk.n, np.nan))
        self.inner.write(Run(chunk.t0, chunk.rate_hz, out, chunk.config))

    def close(self, meta, summary):
        return self.inner.close(meta, summary)

    def abort(self):
        self.inner.abort()


def run_one(task: dict[str, Any], stop: Any = None) -> dict[str, Any]:
    """Simulate one run of a dataset (see module docstring). ``task`` keys: ``run_id``, ``index``,
    ``config_toml``, ``data_dir``, ``columns`` (fields of :class:`~twin.dataset.storage.ColumnSpec`),
    ``instrumented``, ``labels`` (fields of :class:`~twin.dataset.storage.LabelColumn`: the run's
    label columns). ``stop``: a :class:`threading.Event` of a driver that runs runs on threads;
    once set, the run is interrupted at its next chunk (KeyboardInterrupt: its file is removed).

    A task with ``members`` (a list of such tasks, of one :func:`twin.warm.mechanical_key`: a warm
    start) is a group: one engine run feeds every member's sensor chain and file
    (:func:`twin.warm.simulate_shared`; each file the bytes of the member's run alone), and the
    result is ``{"group": [one result per member]}``. The first member's result carries the
    engine's stepping time (``sim_wall_s``), the others 0; each member's ``wall_s`` is the group's
    divided by its size."""
    if "members" in task:
        return {"group": _run_members(task["members"], stop, approx=bool(task.get("approx")))}
    return _run_members([task], stop)[0]


def _run_members(tasks: list[dict[str, Any]], stop: Any, approx: bool = False) -> list[dict[str, Any]]:
    from twin.config import config_from_toml
    from twin.dataset.storage import ColumnSpec, LabelColumn, ParquetRunWriter, WriteError
    from twin.util import file_sha256
    from twin.bench_record import RecordingSink
    from twin.simulation import ThreadedSink, simulate

    t0 = time.perf_counter()
    paths = [Path(t["data_dir"]) / f"{t['run_id']}.parquet" for t in tasks]
    outs: list[dict[str, Any]] = [{"run_id": t["run_id"], "index": t["index"], "status": "ok", "reason": ""}
                                  for t in tasks]
    recs: list[Any] = []
    try:
        cfgs, writers, sinks = [], [], []
        approx_info = None
        for i, (task, path) in enumerate(zip(tasks, paths)):
            cfg = config_from_toml(task["config_toml"])
            columns = [ColumnSpec(*c) for c in task["columns"]]
            labels = [LabelColumn(*lab) for lab in task.get("labels", ())]
            file_meta = {"name": cfg.name, "config_toml": cfg.to_toml()}
            if approx and i > 0:
                # an approximate warm start: from when the file holds this run's own physics
                from twin.warm_approx import SETTLE_S, switch_time

                t_sw = round(switch_time(cfgs[0]) * cfg.output_rate_hz) / cfg.output_rate_hz
                approx_info = {"approximate": True, "switch_s": t_sw, "settle_s": SETTLE_S,
                               "valid_from_s": t_sw + SETTLE_S, "spin_up_of": cfgs[0].name}
                file_meta["warm_start"] = approx_info
            writer = ParquetRunWriter(path, columns, task["run_id"], file_meta, labels)
            # the sensor chain and the Parquet writer run on a thread, overlapping the stepping
            sink = ThreadedSink(InstrumentSink(cfg, columns, writer, tuple(task["instrumented"])))
            run_sinks = [_Stop(stop), sink] if stop is not None else [sink]
            if task.get("recordings_dir"):  # outputs.recordings: a bench recording as twin record writes it
                rec = RecordingSink(cfg, Path(task["recordings_dir"]) / f"{task['run_id']}.mcap",
                                    notes=f"dataset run {task['run_id']}", created_by="twin dataset generate")
                recs.append(rec)
                run_sinks.append(ThreadedSink(rec))
            cfgs.append(cfg)
            writers.append(writer)
            sinks.append(run_sinks)
        outcomes = None
        if len(tasks) == 1:
            outcome = simulate(cfgs[0], sinks[0])
        elif approx:
            from twin.warm_approx import simulate_approx

            outcomes = simulate_approx(cfgs, sinks)
            outcome = outcomes[0]
        else:
            from twin.warm import simulate_shared

            outcome = simulate_shared(cfgs, sinks)
        warnings = {k: v for o in (outcomes or [outcome]) for k, v in (o.meta.get("warnings") or {}).items()}
        if warnings:
            for path in paths + [r.path for r in recs]:
                path.unlink(missing_ok=True)
            raise _Failed("MuJoCo warnings: " + ", ".join(f"{k}({v})" for k, v in warnings.items()))
        for i, (out, cfg, writer, path) in enumerate(zip(outs, cfgs, writers, paths)):
            mine = outcomes[i] if outcomes is not None else outcome
            out.update(rows=writer.rows, bytes=path.stat().st_size, sha256=file_sha256(path),
                       summary=_small_summary(mine.summary), stats=writer.stats.d,
                       sim_wall_s=mine.meta.get("wall_s") if (i == 0 or outcomes is not None) else 0.0,
                       simulated_s=writer.rows / cfg.output_rate_hz)
            if outcomes is not None and i > 0:
                out["warm_start"] = mine.meta.get("warm_start")
            elif len(tasks) > 1:
                out["shared"] = {"runs": len(tasks), "engine_run_of": tasks[0]["run_id"]}
        for out, rec in zip(outs, recs):
            out["recording"] = {"file": f"{rec.path.parent.name}/{rec.path.name}", "bytes": rec.path.stat().st_size}
    except _Failed as err:
        for out in outs:
            out.update(status="failed", reason=str(err))
    except (WriteError, OSError) as err:  # the file system, not the run: the driver stops
        for out in outs:
            out.update(status="io-error", reason=f"{type(err).__name__}: {err}".splitlines()[0][:500])
    except Exception as err:  # noqa: BLE001 - recorded with its reason; the dataset goes on
        reason = f"{type(err).__name__}: {err}".splitlines()[0]
        if not isinstance(err, (ValueError, RuntimeError)) and "TwinError" not in [c.__name__ for c in type(err).__mro__]:
            reason += " | " + traceback.format_exc(limit=2).replace("\n", " ")[-300:]
        for out in outs:
            out.update(status="failed", reason=reason[:500])
    if any(out["status"] != "ok" for out in outs):
        for rec in recs:  # no recording of a run that failed
            rec.path.unlink(missing_ok=True)
    wall = (time.perf_counter() - t0) / len(tasks)
    # the worker process's peak so far (it runs many runs): an upper bound of this run's
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    for out in outs:
        out["wall_s"] = wall
        out["peak_rss_mb"] = peak
    return outs


class _Failed(Exception):
    pass


class _Stop:
    """First sink of a run on a driver's thread: interrupts the run once the driver stops."""

    def __init__(self, event: Any) -> None:
        self.event = event

    def write(self, chunk: Run) -> None:
        if self.event.is_set():
            raise KeyboardInterrupt("the dataset driver stopped")

    def close(self, meta: dict[str, Any], summary: dict[str, Any]) -> None:
        return None

    def abort(self) -> None:
        pass


def watch_parent(poll_s: float = 0.5, grace_s: float = 5.0) -> None:
    """Initializer of local worker processes: when the driver dies (SIGKILL, a crash), the worker
    would wait for work forever. A daemon thread notices the parent is gone (the worker was
    reparented), interrupts the running simulation (its sink deletes the temporary file) and ends
    the process."""
    import _thread
    import os
    import threading

    parent = os.getppid()

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(poll_s)
        _thread.interrupt_main()
        time.sleep(grace_s)
        os._exit(1)

    threading.Thread(target=watch, name="twin-parent-watch", daemon=True).start()


def _small_summary(s: dict[str, Any]) -> dict[str, float]:
    """The run summary flattened to numbers (``B_impacts``, ``AC4_rms_mps2``, ...)."""
    out: dict[str, float] = {}
    for k, v in s.items():
        if isinstance(v, dict):
            for kk, vv in v.items():
                if isinstance(vv, (int, float)) and not isinstance(vv, bool) and kk != "clearance_mm":
                    out[f"{k}_{kk}"] = float(vv)
    return out
