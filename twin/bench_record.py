"""Bench recordings made by the twin: ``twin record`` and :func:`record`.

A configuration is simulated (any engine, drive mode and program) and its truth signals go, chunk by
chunk as the engine produces them, through the sensor chain of ``[instrumentation]``
(:class:`twin.instrument.chain.ChainStream`: accelerometer response, noise, saturation, the 18-bit ±10 V
DAQ, the encoder's counts, the motor command) — the path the sample recordings took. The calibration
stored in the recording comes from a simulated static recording through the same chain (S003 Eq. 1–4),
and the file is validated as an imported bench recording is, then written atomically. Every command
that reads a bench recording (``twin replay``, ``twin identify clearance``, ``twin analyze``) reads it.

Memory: the DAQ channels of the whole run are held until the file is written (about 6.4 MB per
recorded second at 100 kHz); the truth signals are not kept.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Any

from twin.config import BenchConfig
from twin.run import Run

#: channel groups the sensor chain reads from a simulated run
CHAIN_GROUPS = ("accel", "encoder")


@dataclasses.dataclass(frozen=True)
class RecordResult:
    """What :func:`record` wrote.

    Attributes:
        path: the recording file (``.mcap``).
        duration_s: recorded time [s].
        rate_hz: DAQ sample rate [Hz].
        channels: the recording's channels (DAQ volts, encoder counts, motor command).
        engine: the engine that simulated the run.
        bytes: size of the file [B].
        seconds: wall time of the whole call [s].
        turns: crank turns through the run, last minus first angle over 2π (NaN where the run has no crank
            angle); under 1 the crank stalled or rocked (``twin record`` warns): no whole turn to analyse.
    """

    path: Path
    duration_s: float
    rate_hz: float
    channels: tuple[str, ...]
    engine: str
    bytes: int
    seconds: float
    turns: float = float("nan")

    def to_dict(self) -> dict[str, Any]:
        """A JSON-able dict (the path as text)."""
        return {**dataclasses.asdict(self), "path": str(self.path), "channels": list(self.channels)}


class RecordingSink:
    """Sink that puts each chunk of a simulated run through the sensor chain, keeps only the DAQ channels
    (the chain streams: chunks of any length give the same samples as the whole run) and, when the run
    closes, writes them as a bench recording to ``path`` (:func:`write_recorded`). :func:`record` and the
    dataset generator's ``outputs.recordings`` use it; ``cfg`` must hold the chain's channel groups
    (:func:`recording_config`).

    ``written`` is the recording's path once written, ``daq`` the DAQ run."""

    def __init__(self, cfg: BenchConfig, path: str | Path, notes: str = "", static_s: float = 1.0,
                 created_by: str = "twin record"):
        self.cfg = cfg
        self.path = Path(path)
        self.notes, self.static_s, self.created_by = notes, float(static_s), created_by
        self.stream = None
        self.parts: list[Run] = []
        self.daq: Run | None = None
        self.meta: dict[str, Any] = {}
        self.written: Path | None = None
        #: first and last crank angle of the run [rad] (unwrapped), where the run has one
        self.angle_span: list[float] = []

    def write(self, chunk: Run) -> None:
        from twin.instrument.chain import ChainStream
        from twin.names import SENSOR_CRANK_ANGLE

        if chunk.n and SENSOR_CRANK_ANGLE in chunk:
            a = chunk[SENSOR_CRANK_ANGLE]
            self.angle_span = [self.angle_span[0] if self.angle_span else float(a[0]), float(a[-1])]
        if self.stream is None:
            self.stream = ChainStream(self.cfg, chunk.rate_hz)
        out = self.stream.process(chunk)
        if out.n:
            self.parts.append(out)

    def close(self, meta: dict[str, Any], summary: dict[str, Any]) -> None:
        self.daq = Run.concat(self.parts)
        self.parts = []
        self.meta = dict(meta)
        self.daq, self.written = write_recorded(self.path, self.daq, self.cfg, self.meta, self.notes, self.static_s,
                                                self.created_by)

    def abort(self) -> None:
        self.parts = []


def write_recorded(path: Path, daq: Run, cfg: BenchConfig, meta: dict[str, Any], notes: str, static_s: float,
                   created_by: str) -> tuple[Run, Path]:
    """Write the DAQ channels ``daq`` of a simulated run of ``cfg`` (engine metadata ``meta``) as a bench
    recording with the calibration of a simulated static recording of ``static_s`` [s], validated as an import
    is, atomically. Returns the recording's run and path."""
    from twin.recording import synthetic_daq_recording, write_recording

    rec, info = synthetic_daq_recording(daq, cfg, meta, notes=notes, static_s=static_s, created_by=created_by)
    return rec, write_recording(path, rec, info)


def recording_config(cfg: BenchConfig) -> BenchConfig:
    """``cfg`` with the channel groups the sensor chain reads (:data:`CHAIN_GROUPS`) added where missing."""
    if not isinstance(cfg, BenchConfig):
        raise TypeError(f"cfg: must be a BenchConfig (twin.preset(...), twin.config.load_config(...)), "
                        f"got {type(cfg).__name__}")
    if cfg.spatial.enabled:  # refused here, not as a channel the user did not ask for
        from twin.errors import ConfigError

        raise ConfigError("spatial.enabled", "a bench recording is the planar bench's (its accelerometers and "
                          "encoder); the spatial mechanism has no accelerometer mounts: simulate it with "
                          "'twin simulate' (twin.simulate), or record with spatial.enabled = false")
    missing = [g for g in CHAIN_GROUPS if g not in cfg.sensors.channels]
    return cfg.replace(**{"sensors.channels": [*cfg.sensors.channels, *missing]}) if missing else cfg


def record(cfg: BenchConfig, out: str | Path, *, notes: str = "", static_s: float = 1.0,
           progress: bool = False) -> RecordResult:
    """Simulate ``cfg`` and write a bench recording of it to ``out`` (``.mcap``).

    ``notes``: free text stored in the recording (operator, test id, ...); ``static_s``: length of the
    simulated static calibration recording [s] whose reduction (Eq. 1–4) the recording carries
    (0.1–60 s); ``progress``: a progress bar on standard error. The output is checked before the
    simulation starts (``out`` names it in errors) and written atomically; nothing is left behind on
    failure or interruption. Returns a :class:`RecordResult`.
    """
    import math

    from twin.errors import ConfigError
    from twin.simulation import simulate
    from twin.util import check_output_file

    t0 = time.perf_counter()
    cfg = recording_config(cfg)
    if not isinstance(notes, str):
        raise TypeError(f"notes: must be a str, got {type(notes).__name__}")
    if isinstance(static_s, bool) or not isinstance(static_s, (int, float)) or not math.isfinite(static_s) \
            or not 0.1 <= static_s <= 60.0:
        raise ConfigError("static_s", f"must lie in [0.1, 60] s (the static calibration recording), got {static_s!r}")
    path = check_output_file(out, "out", ".mcap")
    sink = RecordingSink(cfg, path, notes=notes, static_s=float(static_s))
    simulate(cfg, [sink], progress=progress)
    assert sink.daq is not None and sink.written is not None
    daq, written = sink.daq, sink.written
    turns = (sink.angle_span[1] - sink.angle_span[0]) / (2 * math.pi) if sink.angle_span else float("nan")
    return RecordResult(written, daq.duration_s, daq.rate_hz, tuple(daq.channels), str(sink.meta.get("engine", "")),
                        written.stat().st_size, time.perf_counter() - t0, turns)
