"""The one time-series structure of the twin: a :class:`Run`.

Engines produce runs (whole, or chunk by chunk), recordings are read back into runs, and
every sink (MCAP, rerun, datasets, reports) consumes them. A run is a uniform time base,
named channels with units, the full bench configuration and engine metadata.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping

import numpy as np

from twin.channels import spec_by_name
from twin.config import BenchConfig
from twin.errors import MissingExtraError, RecordingError


@dataclass
class Channel:
    """One uniformly sampled signal.

    Attributes:
        name: channel name (see :mod:`twin.channels`).
        unit: SI unit string, e.g. ``"m/s^2"``.
        group: channel group (MCAP topic), e.g. ``"accel"``.
        data: 1-D array of samples (float32 or float64).
    """

    name: str
    unit: str
    group: str
    data: np.ndarray

    def __post_init__(self) -> None:
        self.data = np.asarray(self.data)
        if self.data.ndim != 1:
            raise RecordingError(f"channel {self.name}: data must be 1-D, got shape {self.data.shape}")


@dataclass
class Run:
    """A uniformly sampled multi-channel time series of one bench run.

    Attributes:
        t0: time of sample 0 [s] (simulation time; recordings: time since start).
        rate_hz: sample rate [Hz].
        channels: channels by name, in canonical order; all of equal length.
        config: bench configuration that produced (or describes) the run.
        meta: engine and provenance metadata (engine, versions, timestep, wall time...).
    """

    t0: float
    rate_hz: float
    channels: dict[str, Channel]
    config: BenchConfig | None = None
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not (self.rate_hz > 0 and np.isfinite(self.rate_hz)):
            raise RecordingError(f"rate_hz must be > 0, got {self.rate_hz!r}")
        lengths = {len(c.data) for c in self.channels.values()}
        if len(lengths) > 1:
            raise RecordingError(f"channels have different lengths: {sorted(lengths)}")

    # -- construction
    @classmethod
    def from_arrays(cls, t0: float, rate_hz: float, arrays: Mapping[str, np.ndarray],
                    config: BenchConfig | None = None, meta: Mapping[str, Any] | None = None,
                    units: Mapping[str, str] | None = None, groups: Mapping[str, str] | None = None) -> "Run":
        """Build a run from ``{name: samples}``; units and groups default to the known specs."""
        chans: dict[str, Channel] = {}
        for name, arr in arrays.items():
            spec = spec_by_name(name)
            unit = (units or {}).get(name) or (spec.unit if spec else "")
            group = (groups or {}).get(name) or (spec.group if spec else "extra")
            dtype = spec.dtype if spec else np.asarray(arr).dtype
            chans[name] = Channel(name, unit, group, np.ascontiguousarray(arr, dtype=dtype))
        return cls(float(t0), float(rate_hz), chans, config, dict(meta or {}))

    # -- access
    @property
    def n(self) -> int:
        """Number of samples."""
        return len(next(iter(self.channels.values())).data) if self.channels else 0

    @property
    def dt(self) -> float:
        """Sample period [s]."""
        return 1.0 / self.rate_hz

    @property
    def time(self) -> np.ndarray:
        """Sample times [s] (float64)."""
        return self.t0 + np.arange(self.n) / self.rate_hz

    @property
    def duration_s(self) -> float:
        """n / rate [s]."""
        return self.n / self.rate_hz

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.channels[name].data
        except KeyError:
            raise RecordingError(f"run has no channel {name!r}; channels: {', '.join(self.channels)}") from None

    def __contains__(self, name: str) -> bool:
        return name in self.channels

    @property
    def groups(self) -> dict[str, list[str]]:
        """Channel names per group, in order."""
        out: dict[str, list[str]] = {}
        for c in self.channels.values():
            out.setdefault(c.group, []).append(c.name)
        return out

    def to_pandas(self):
        """The run as a pandas DataFrame: a column per channel (its dtype kept), indexed by the
        sample times ``t`` [s]; ``df.attrs["units"]`` holds each channel's unit. Needs pandas,
        which the twin does not depend on (``pip install pandas``)."""
        try:
            import pandas as pd
        except ImportError:
            raise MissingExtraError("Run.to_pandas needs pandas, which is not installed: pip install pandas") from None
        df = pd.DataFrame({k: c.data for k, c in self.channels.items()}, index=pd.Index(self.time, name="t"))
        df.attrs["units"] = {k: c.unit for k, c in self.channels.items()}
        return df

    # -- transforms
    def slice(self, start: int, stop: int) -> "Run":
        """Samples [start, stop) as a new run (views, not copies)."""
        start, stop, _ = slice(start, stop).indices(self.n)
        chans = {k: dataclasses.replace(c, data=c.data[start:stop]) for k, c in self.channels.items()}
        return Run(self.t0 + start / self.rate_hz, self.rate_hz, chans, self.config, dict(self.meta))

    def window(self, t_start: float, t_stop: float) -> "Run":
        """Samples with t_start <= t < t_stop [s]."""
        i0 = int(np.ceil((t_start - self.t0) * self.rate_hz - 1e-9))
        i1 = int(np.ceil((t_stop - self.t0) * self.rate_hz - 1e-9))
        return self.slice(max(i0, 0), max(i1, 0))

    def select(self, names: Iterable[str]) -> "Run":
        """Run restricted to the named channels (in the given order)."""
        names = list(names)
        for n in names:
            self[n]  # raises a clear error for unknown names
        return Run(self.t0, self.rate_hz, {n: self.channels[n] for n in names}, self.config, dict(self.meta))

    def with_channels(self, channels: Iterable[Channel]) -> "Run":
        """Copy with channels added or replaced."""
        chans = dict(self.channels)
        for c in channels:
            chans[c.name] = c
        return Run(self.t0, self.rate_hz, chans, self.config, dict(self.meta))

    @staticmethod
    def concat(chunks: Iterable["Run"]) -> "Run":
        """Join consecutive chunks of one run (same channels and rate) into one run."""
        chunks = list(chunks)
        if not chunks:
            raise RecordingError("no chunks to concatenate")
        first = chunks[0]
        for c in chunks[1:]:
            if list(c.channels) != list(first.channels) or c.rate_hz != first.rate_hz:
                raise RecordingError("chunks differ in channels or rate")
        chans = {k: dataclasses.replace(ch, data=np.concatenate([c.channels[k].data for c in chunks]))
                 for k, ch in first.channels.items()}
        meta = dict(chunks[-1].meta)
        return Run(first.t0, first.rate_hz, chans, first.config, meta)
