"""One entry point for both engines: a configuration in, a :class:`~twin.run.Run` out.

Engines implement :class:`Engine`: built from a :class:`~twin.config.BenchConfig`, they
yield consecutive chunks (runs of ``simulation.chunk_s`` each) carrying exactly the channels
of :func:`twin.channels.channel_specs`, sampled at :func:`output_stride`'s rate, and fill
``meta`` (engine, timestep_s, steps, wall_s, real_time_factor, ...) as they go. Sinks
consume the chunks; :func:`simulate` concatenates them into one run.
"""

from __future__ import annotations

import importlib
import time
from typing import Any, Callable, Iterable, Iterator, Protocol

from twin.config import BenchConfig
from twin.errors import ConfigError
from twin.run import Run

#: engine name -> "module:class"
ENGINES: dict[str, str] = {
    "mujoco": "twin.mujoco_engine.engine:MujocoEngine",
    "reference": "twin.reference.engine:ReferenceEngine",
}


class Engine(Protocol):
    """What an engine provides (see module docstring)."""

    name: str
    meta: dict[str, Any]

    def chunks(self) -> Iterator[Run]: ...


def output_stride(cfg: BenchConfig) -> tuple[int, float]:
    """(integration steps per output sample, output rate [Hz]).

    The output rate is ``sensors.output_rate_hz`` when the timestep divides its period;
    a timestep longer than that period outputs every step (rate 1/h).
    """
    h, rate = cfg.simulation.timestep_s, cfg.sensors.output_rate_hz
    k = 1.0 / (h * rate)
    if k < 1.0 - 1e-9:
        return 1, round(1.0 / h, 6)  # 1/2e-5 = 49999.99999999999 otherwise
    stride = int(round(k))
    if abs(stride - k) > 1e-6 * k:
        raise ConfigError("simulation.timestep_s",
                          f"{h:g} s does not divide the output period 1/{rate:g} Hz; "
                          "use a timestep of (1/output_rate)/k for an integer k")
    return stride, rate


def n_samples(cfg: BenchConfig) -> int:
    """Number of output samples of a run of ``cfg``."""
    _, rate = output_stride(cfg)
    return int(round(cfg.duration_s * rate))


def make_engine(cfg: BenchConfig) -> Engine:
    """Instantiate the engine named by ``cfg.simulation.engine``."""
    mod, cls = ENGINES[cfg.simulation.engine].split(":")
    return getattr(importlib.import_module(mod), cls)(cfg)


class Progress:
    """Minimal progress callback protocol: called with (simulated seconds done, total)."""

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


def run_chunks(cfg: BenchConfig, progress: bool = False) -> tuple[Engine, Iterator[Run]]:
    """Engine and its chunk iterator (progress bar on stderr if ``progress``)."""
    engine = make_engine(cfg)

    def gen() -> Iterator[Run]:
        bar = Progress(cfg.duration_s, progress, desc=f"{cfg.simulation.engine} {cfg.name}")
        try:
            for chunk in engine.chunks():
                bar.update(chunk)
                yield chunk
        finally:
            bar.close()

    return engine, gen()


def simulate(cfg: BenchConfig, progress: bool = False,
             sinks: Iterable[Callable[[Run], None]] = ()) -> Run:
    """Run ``cfg`` to the end and return the whole run (chunks also passed to ``sinks``)."""
    engine, it = run_chunks(cfg, progress)
    sinks = list(sinks)
    chunks = []
    t0 = time.perf_counter()
    for chunk in it:
        for s in sinks:
            s(chunk)
        chunks.append(chunk)
    run = Run.concat(chunks)
    run.meta = dict(engine.meta)
    run.meta.setdefault("total_wall_s", time.perf_counter() - t0)
    return run
