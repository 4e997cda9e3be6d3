"""One entry point for both engines: a configuration in, a stream of chunks out, sinks consume it.

The chunk loop lives here and only here (:func:`run_chunks`). An engine supplies its stepping
and how its state maps to channels (:class:`Engine`); it never imports this module. For each
chunk of ``simulation.chunk_s`` the loop evaluates the drive reference at every integration
step, lets the engine advance, adds the channels every engine shares (drive reference, encoder
angle), converts each channel to its storage type (:func:`twin.channels.channel_specs`) and
keeps the run's metadata (steps, wall time, real-time factor).

:func:`simulate` owns the life of a run: it builds the engine, streams every chunk to the sinks
(:class:`Sink`: the MCAP file, the rerun recording, a collector for callers that want the whole
run in memory, ...), keeps the summary incrementally (:class:`twin.summary.SummaryAccumulator`)
and closes the sinks with the metadata and summary at the end. On any error or signal
(KeyboardInterrupt; SIGTERM is turned into one while it runs) every sink is aborted: no sink
leaves a partial file. Nothing here keeps a chunk after the sinks have seen it, so memory does
not grow with the duration.
"""

from __future__ import annotations

import contextlib
import importlib
import signal
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Iterable, Iterator, Protocol, runtime_checkable

import numpy as np

from twin.channels import channel_specs, encoder_from_bench
from twin.config import ENGINE_CLASSES, BenchConfig
from twin.errors import SimulationError, raise_terminated
from twin.run import Channel, Run
from twin.tracefile import DriveInputs, with_trace_duration

#: channels the loop computes itself (from the drive reference and the crank angle)
LOOP_CHANNELS = ("theta_ref", "omega_ref", "encoder_angle")


class Engine(Protocol):
    """What an engine supplies to the chunk loop.

    ``meta`` holds the engine's metadata (name, version, build and compile times, contact
    settings, warnings...); the loop adds ``steps``, ``wall_s`` and ``real_time_factor``.
    """

    name: str
    meta: dict[str, Any]

    def reset(self, theta0: float | None = None) -> None:
        """Put the mechanism at rest at crank bench angle ``theta0`` [rad] (None: the drive
        program's initial angle), eccentricities as configured."""

    def advance(self, theta_ref: np.ndarray, omega_ref: np.ndarray, stride: int) -> dict[str, np.ndarray]:
        """Integrate ``len(theta_ref)`` steps, step k tracking ``theta_ref[k]`` [rad] and
        ``omega_ref[k]`` [rad/s]; return the engine's channels at steps 0, stride, 2·stride, ...
        (the state at the start of those steps): every channel of :func:`channel_specs` except
        :data:`LOOP_CHANNELS`, plus ``crank_angle`` whenever the encoder group is asked for.
        Raise :class:`~twin.errors.SimulationError` on divergence."""


@runtime_checkable
class Sink(Protocol):
    """Consumer of a run's chunks: ``write`` for consecutive chunks, then exactly one of
    ``close`` (success: finalize, e.g. rename the temporary file into place) or ``abort``
    (failure or interruption: drop everything, leave nothing behind)."""

    def write(self, chunk: Run) -> None: ...

    def close(self, meta: dict[str, Any], summary: dict[str, Any]) -> Any: ...

    def abort(self) -> None: ...


class Collector:
    """Sink that keeps every chunk, for callers that want the whole run in memory
    (:func:`simulate_run`; tests, studies of short windows). Its memory grows with the run."""

    def __init__(self) -> None:
        self._chunks: list[Run] = []
        self.run: Run | None = None

    def write(self, chunk: Run) -> None:
        self._chunks.append(chunk)

    def close(self, meta: dict[str, Any], summary: dict[str, Any]) -> Run:
        self.run = Run.concat(self._chunks)
        self.run.meta = dict(meta)
        self._chunks = []
        return self.run

    def abort(self) -> None:
        self._chunks = []


class ThreadedSink:
    """Runs another sink's ``write`` calls on a background thread, so that its encoding,
    compression and file writes overlap the engine's stepping (both engines release the GIL while
    they step: ``mujoco.rollout`` and the reference engine's compiled loop).

    The inner sink sees exactly the calls it would see without the thread, in the same order, so
    what it writes is the same bytes. ``write`` hands the chunk over and returns (a bounded queue:
    at most ``depth`` chunks wait, so memory stays bounded; the chunk loop never reuses a chunk's
    arrays). An error raised by the inner ``write`` is raised again in the caller's thread by the
    next ``write`` or by ``close``. ``close`` waits for the queued writes, then calls the inner
    ``close`` in the caller's thread; ``abort`` drops the chunks still waiting, waits for the write
    in progress and aborts the inner sink (so an interrupted run leaves nothing behind, as without
    the thread).
    """

    _END = object()

    def __init__(self, inner: Sink, depth: int = 2) -> None:
        import queue

        self.inner = inner
        self._queue: queue.Queue = queue.Queue(maxsize=max(1, int(depth)))
        self._error: BaseException | None = None
        self._stop = False
        self._thread: threading.Thread | None = None

    def _work(self) -> None:
        while True:
            chunk = self._queue.get()
            if chunk is self._END:
                return
            if self._error is None and not self._stop:  # after an error: drain, so put() never blocks
                try:
                    self.inner.write(chunk)
                except BaseException as err:  # noqa: BLE001 - handed to the caller's thread
                    self._error = err
            del chunk

    def _join(self) -> None:
        if self._thread is not None:
            self._queue.put(self._END)
            self._thread.join()
            self._thread = None

    def write(self, chunk: Run) -> None:
        if self._error is not None:
            raise self._error
        if self._thread is None:
            self._thread = threading.Thread(target=self._work, name="twin-sink-writer", daemon=True)
            self._thread.start()
        self._queue.put(chunk)

    def close(self, meta: dict[str, Any], summary: dict[str, Any]) -> Any:
        self._join()
        if self._error is not None:
            raise self._error
        return self.inner.close(meta, summary)

    def abort(self) -> None:
        import queue

        self._stop = True
        while True:  # drop what waits (never block here: abort runs on errors and interrupts)
            try:
                self._queue.get_nowait()
            except queue.Empty:
                break
        if self._thread is not None:
            self._queue.put(self._END)  # there is room now; the write in progress ends first
            self._thread.join()
            self._thread = None
        self.inner.abort()


@dataclass
class Outcome:
    """What :func:`simulate` returns: the run's metadata and summary (the data went to the sinks)."""

    meta: dict[str, Any] = field(default_factory=dict)
    summary: dict[str, Any] = field(default_factory=dict)


def make_engine(cfg: BenchConfig, inputs: DriveInputs | None = None) -> Engine:
    """Instantiate the engine named by ``cfg.simulation.engine``; ``inputs``: recorded drive inputs in
    memory (encoder trace, motor command), used instead of the files the configuration names. The files
    a configuration names are read and checked here, before an engine is built (a bad file is refused
    before the reference engine compiles), and reach the engine as arrays."""
    inputs = _read_drive_files(cfg, inputs)
    cfg = with_trace_duration(cfg, inputs)
    if cfg.spatial.enabled:  # the spatial mechanism has its own pair of engines
        from twin.spatial import SPATIAL_ENGINE_CLASSES

        mod, cls = SPATIAL_ENGINE_CLASSES[cfg.simulation.engine].split(":")
        return getattr(importlib.import_module(mod), cls)(cfg, inputs=inputs)
    mod, cls = ENGINE_CLASSES[cfg.simulation.engine].split(":")  # imported on demand
    return getattr(importlib.import_module(mod), cls)(cfg, inputs=inputs)


def _read_drive_files(cfg: BenchConfig, inputs: DriveInputs | None) -> DriveInputs | None:
    """``inputs`` completed with the encoder trace (``drive.trace_file`` of the "trace" program) and the
    motor command (``drivetrain.command_file`` of the motor drive) the configuration names, read and
    checked; None where the run reads neither."""
    from twin.motor_drive import command_trace
    from twin.tracefile import load_trace

    trace = inputs.trace if inputs is not None else None
    command = inputs.command if inputs is not None else None
    if trace is None and cfg.drive.program == "trace" and cfg.drive.trace_file:
        trace = load_trace(cfg.drive.trace_file)
    if command is None and cfg.drive.mode == "motor" and cfg.drivetrain.command_file:
        command = command_trace(cfg)
    if trace is None and command is None:
        return inputs
    return DriveInputs(trace=trace, command=command)


class Progress:
    """Progress bar on stderr (tqdm), in simulated seconds."""

    def __init__(self, total_s: float, enabled: bool = True, desc: str = "simulating"):
        self.bar = None
        if enabled:
            from tqdm import tqdm

            self.bar = tqdm(total=round(total_s, 6), unit="sim s", desc=desc, leave=False,
                            bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.2f}/{total:.2f} sim s "
                                       "[{elapsed}<{remaining}]")

    def update(self, chunk: Run) -> None:
        if self.bar is not None:
            self.bar.update(round(chunk.duration_s, 6))

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def run_chunks(cfg: BenchConfig, engine: Engine | None = None, progress: bool = False, *,
               inputs: DriveInputs | None = None, start: Any = None, until: int | None = None) -> Iterator[Run]:
    """The chunk loop (see the module docstring): yields consecutive chunks of the run of ``cfg``
    on ``engine`` (default: a new engine of ``cfg.simulation.engine``). ``engine.meta`` holds the
    run's metadata as it goes. ``inputs``: recorded drive inputs in memory (:func:`make_engine`).

    ``start``: a saved state (:class:`twin.warm.WarmState`) to continue from instead of the rest
    state: the engine is restored into it (``start.restore_engine``, which returns the output
    samples already done) and the chunks run on from that sample. ``until``: stop after this many
    output samples of the run (default: the run's end)."""
    from twin.drive import DriveReference

    if cfg.trace_length_pending:  # the run lasts as long as its trace
        inputs = _read_drive_files(cfg, inputs)
        cfg = with_trace_duration(cfg, inputs)
    engine = engine if engine is not None else make_engine(cfg, inputs)
    ref = DriveReference(cfg, inputs)
    h, stride, rate, n_out = cfg.simulation.timestep_s, cfg.output_stride, cfg.output_rate_hz, cfg.n_samples
    specs = channel_specs(cfg)
    encoder = "encoder" in cfg.sensors.channels
    direction = cfg.mechanism.crank_direction
    per_chunk = max(1, int(round(cfg.simulation.chunk_s * rate)))
    done = 0
    if start is None:
        engine.reset(float(ref(np.zeros(1))[0][0]))
    else:
        done = int(start.restore_engine(engine, cfg))
    if until is not None:
        n_out = min(n_out, int(until))
    engine.meta.update(steps=done * stride, wall_s=0.0, real_time_factor=None)
    bar = Progress((n_out - done) / rate, progress, desc=f"{cfg.simulation.engine} {cfg.name}")
    wall, done0 = 0.0, done
    try:
        while done < n_out:
            n = min(per_chunk, n_out - done)
            nstep = n * stride
            t_start = time.perf_counter()
            k0 = done * stride
            theta_ref, omega_ref = ref((k0 + np.arange(nstep)) * h)
            cols = engine.advance(theta_ref, omega_ref, stride)
            short_cols = [k for k, v in cols.items() if len(v) != n]
            if short_cols:
                raise SimulationError(f"internal: the {engine.name} engine returned {len(cols[short_cols[0]])} samples "
                                      f"of {short_cols[0]}, expected {n}")
            cols["theta_ref"], cols["omega_ref"] = theta_ref[::stride], omega_ref[::stride]
            if encoder:
                cols["encoder_angle"] = encoder_from_bench(cols["crank_angle"], direction)
            try:
                chans = {s.name: Channel(s.name, s.unit, s.group, np.ascontiguousarray(cols[s.name], dtype=s.dtype))
                         for s in specs}
            except KeyError as err:
                raise SimulationError(f"internal: the {engine.name} engine did not produce channel {err}") from None
            chunk = Run(done / rate, rate, chans, cfg, {})
            wall += time.perf_counter() - t_start
            done += n
            engine.meta.update(steps=done * stride, wall_s=wall,
                               real_time_factor=((done - done0) * stride * h) / wall if wall > 0 else None)
            bar.update(chunk)
            yield chunk
    finally:
        bar.close()


@contextlib.contextmanager
def _sigterm_interrupts() -> Iterator[None]:
    """While a run streams, SIGTERM raises :class:`Terminated` (a KeyboardInterrupt) in the main
    thread, so that the sinks are aborted; a handler someone else installed is kept."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
        yield
        return
    previous = signal.signal(signal.SIGTERM, raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def simulate(cfg: BenchConfig, sinks: Iterable[Sink] = (), progress: bool = False, *,
             engine: Engine | None = None, inputs: DriveInputs | None = None, start: Any = None) -> Outcome:
    """Run ``cfg`` to the end, streaming every chunk to ``sinks``; returns metadata and summary.
    ``inputs``: recorded drive inputs in memory (the encoder trace of a "trace" program, the motor
    command of ``drive.mode = "motor"``), used instead of the files the configuration names.

    ``start``: continue from a saved state (:class:`twin.warm.WarmState`, see :func:`run_chunks`);
    the sinks and the summary then see the run from that state's time on.

    Sinks are closed in the order given, with the run's metadata and summary. If anything fails
    (engine construction, a diverging step, a sink's write or close) or the run is interrupted
    (Ctrl-C, SIGTERM), every sink not yet closed is aborted and the error propagates.
    """
    from twin.summary import SummaryAccumulator

    sinks = list(sinks)
    closed = 0
    t0 = time.perf_counter()
    if cfg.trace_length_pending:  # the run lasts as long as its trace (read once, here)
        inputs = _read_drive_files(cfg, inputs)
        cfg = with_trace_duration(cfg, inputs)
    try:
        with _sigterm_interrupts():
            engine = engine if engine is not None else make_engine(cfg, inputs)
            acc = SummaryAccumulator(cfg)
            for chunk in run_chunks(cfg, engine, progress, inputs=inputs, start=start):
                acc.update(chunk)
                for s in sinks:
                    s.write(chunk)
            meta = dict(engine.meta)
            meta["total_wall_s"] = time.perf_counter() - t0
            summary = acc.result(meta)
            for s in sinks:
                s.close(meta, summary)
                closed += 1
    except BaseException:
        for s in sinks[closed:]:
            try:
                s.abort()
            except Exception:  # noqa: BLE001 - the original error matters; abort is best effort
                pass
        raise
    return Outcome(meta, summary)


def simulate_many(cfgs: Iterable[BenchConfig], sinks: Iterable[Iterable[Sink]] | None = None,
                  threads: int | None = None) -> list[Outcome]:
    """Run several scenes in this process, on ``threads`` threads (default: one per scene), each
    with :func:`simulate`; returns their outcomes in the order given. ``sinks``: one iterable of
    sinks per scene (default none).

    Every scene has its own engine (for MuJoCo its own model and data object: the native contact
    law keeps its per-scene state, the stored impact speeds, in that data object), and the engines
    release the GIL while they step, so the scenes step in parallel and every result is bit for bit
    the serial one. The first error, in scene order, is raised once every scene has ended.
    """
    from concurrent.futures import ThreadPoolExecutor

    cfgs = list(cfgs)
    per_scene = [list(s) for s in sinks] if sinks is not None else [[] for _ in cfgs]
    if len(per_scene) != len(cfgs):
        raise ValueError(f"simulate_many: {len(cfgs)} scenes but {len(per_scene)} sink lists")
    n = max(1, min(len(cfgs), threads if threads is not None else len(cfgs)))
    with ThreadPoolExecutor(max_workers=n, thread_name_prefix="twin-scene") as ex:
        futures = [ex.submit(simulate, c, s) for c, s in zip(cfgs, per_scene)]
    return [f.result() for f in futures]


def simulate_run(cfg: BenchConfig, progress: bool = False, sinks: Iterable[Sink] = (),
                 inputs: DriveInputs | None = None) -> Run:
    """Run ``cfg`` and return the whole run in memory (plus any other ``sinks``): for short runs.
    Long runs should stream to sinks with :func:`simulate` instead. ``inputs``: as :func:`simulate`."""
    keep = Collector()
    simulate(cfg, [*sinks, keep], progress, inputs=inputs)
    assert keep.run is not None
    return keep.run
