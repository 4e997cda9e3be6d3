"""Signals of a dataset run as a Parquet file: written chunk by chunk, read with pyarrow alone.

One file per run, ``data/<run_id>.parquet``: first the key columns, ``run_id`` and ``t`` (sample
time [s], ``t0 + k / rate_hz``), then the run's labels (the same values as its row of
``runs.parquet``: split, fault, clearances, factors, orientation, speed...), constant over the
file, then one column per channel; one row group per chunk of the run (0.5 s by default), zstd.
Every row is a labelled sample, so ``datasets.load_dataset("parquet", ...)`` or
``polars.scan_parquet`` need no join with the manifest. Key-value metadata ``twin.dataset``: JSON
with ``run_id``, ``rate_hz``, ``t0``, ``units`` and ``groups`` per channel column, ``labels`` (the
label column names), the run's configuration ``config_toml``. Encodings: BYTE_STREAM_SPLIT for
floats (``t`` too), DELTA_BINARY_PACKED for counts, dictionaries only for ``run_id`` and the
labels (one value per row group: a dictionary of one entry and a run-length of indices, a few
bytes each), zstd level 3 (chosen by ``analysis/bench_storage.py`` against Arrow's defaults,
Zarr v3, NPZ, HDF5 and MCAP). Storage types (``outputs.dtype``):

* ``auto``: float32 where the channel is float32 in the run (accelerometers, forces, torque,
  calibrated accelerations) or float32 holds it exactly (quantized DAQ volts: 18-bit codes over
  ±10 V are integer multiples of 2**-16 V below 2**20 of them, within float32's 24-bit mantissa;
  checked on every block, an inexact value is an error, not a silent loss); encoder counts as
  int32 (whole counts; an overflow is an error); float64 elsewhere (angles unwrapped over many
  turns, eccentricities of a few µm, positions);
* ``float32``: every float channel float32 (lossy for the float64 ones: documented, for users
  who want the smallest files), counts int32.

The writer is a :class:`twin.simulation.Sink`: a temporary file beside the target, renamed by
``close``, deleted by ``abort``. Per-channel statistics (count, mean, M2, min, max; Chan's parallel
update) are kept while writing, for the training split's normalization statistics.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable

import numpy as np

from twin.errors import RecordingError, TwinError
from twin.run import Channel, Run
from twin.util import check_not_link, json_text, open_new, remove_stale_temps, temp_path

META_KEY = b"twin.dataset"
#: the key columns of every data file (format twin-dataset/2), before the labels and channels
KEY_COLUMNS = ("run_id", "t")
#: Arrow types a label column may have (``LabelColumn.dtype``)
LABEL_TYPES = ("string", "float64", "int64")


class WriteError(TwinError):
    """The file system refused a write (full disk, quota, read-only, permissions): not the run's
    fault, so a dataset stops instead of recording every following run as failed."""

#: channels quantized by the DAQ (float32 holds them exactly when quantization is on)
QUANTIZED = ("volt_AC1", "volt_AC2", "volt_AC3", "volt_AC4", "volt_AC5", "volt_AC6", "motor_command")
COUNTS = ("encoder_counts",)


@dataclass(frozen=True)
class ColumnSpec:
    """A stored column: channel name, unit, group, storage type, and whether a float32 cast must be
    exact (checked)."""

    name: str
    unit: str
    group: str
    dtype: str  # float32 | float64 | int32
    exact: bool = False


@dataclass(frozen=True)
class LabelColumn:
    """A label stored as a constant column of a run file: name, Arrow type (``LABEL_TYPES``) and
    the run's value (None: null)."""

    name: str
    dtype: str
    value: Any

    def __post_init__(self) -> None:
        if self.dtype not in LABEL_TYPES:
            raise TwinError(f"label column {self.name}: dtype must be one of {', '.join(LABEL_TYPES)}, got {self.dtype!r}")


def storage_dtype(name: str, run_dtype: str, mode: str, quantized: bool) -> tuple[str, bool]:
    """(storage type, exact-cast check) of a channel (see module docstring)."""
    if name in COUNTS:
        return "int32", True
    if mode == "float32" or run_dtype == "float32":
        return "float32", False
    if name in QUANTIZED and quantized:
        return "float32", True
    return "float64", False


class Stats:
    """Per-channel count, mean, M2 (sum of squared deviations), min, max; mergeable (Chan et al.)."""

    def __init__(self) -> None:
        self.d: dict[str, list[float]] = {}

    def update(self, name: str, x: np.ndarray) -> None:
        x = np.asarray(x, dtype=np.float64)
        x = x[np.isfinite(x)]  # NaN: a channel the run lacks
        if x.size == 0:
            return
        n_b, mean_b = x.size, float(np.mean(x))
        m2_b = float(np.sum((x - mean_b) ** 2))
        self.merge(name, [n_b, mean_b, m2_b, float(np.min(x)), float(np.max(x))])

    def merge(self, name: str, b: list[float]) -> None:
        a = self.d.get(name)
        if a is None:
            self.d[name] = list(map(float, b))
            return
        n = a[0] + b[0]
        delta = b[1] - a[1]
        self.d[name] = [n, a[1] + delta * b[0] / n, a[2] + b[2] + delta * delta * a[0] * b[0] / n,
                        min(a[3], b[3]), max(a[4], b[4])]

    def as_dict(self) -> dict[str, dict[str, float]]:
        out = {}
        for k, (n, mean, m2, lo, hi) in self.d.items():
            out[k] = {"count": int(n), "mean": mean, "std": float(np.sqrt(m2 / n)) if n else 0.0, "min": lo, "max": hi}
        return out


class ParquetRunWriter:
    """Sink writing the chunks of one run into ``path`` (see module docstring)."""

    def __init__(self, path: str | Path, columns: list[ColumnSpec], run_id: str, extra_meta: dict | None = None,
                 labels: Iterable[LabelColumn] = ()):
        self.path = Path(path)
        self.columns = columns
        self.run_id = run_id
        self.labels = list(labels)
        clash = {lab.name for lab in self.labels} & ({c.name for c in columns} | set(KEY_COLUMNS))
        if clash:
            raise TwinError(f"label columns {', '.join(sorted(clash))} clash with a key or channel column")
        self.extra = dict(extra_meta or {})
        self.tmp = temp_path(self.path, keep_suffix=True)
        self._w = None
        self._rate: float | None = None
        self._t0: float | None = None
        self.rows = 0
        self.stats = Stats()
        self._done = False

    def _open(self, chunk: Run) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        remove_stale_temps(self.path)
        self._rate, self._t0 = chunk.rate_hz, chunk.t0
        meta = {"run_id": self.run_id, "rate_hz": chunk.rate_hz, "t0": chunk.t0,
                "units": {c.name: c.unit for c in self.columns}, "groups": {c.name: c.group for c in self.columns},
                "labels": [lab.name for lab in self.labels], **self.extra}
        fields = [pa.field("run_id", pa.string(), nullable=False), pa.field("t", pa.float64(), nullable=False)]
        fields += [pa.field(lab.name, lab.dtype) for lab in self.labels]
        fields += [pa.field(c.name, c.dtype) for c in self.columns]
        schema = pa.schema(fields, metadata={META_KEY: json_text(meta, indent=None, sort_keys=True).encode()})
        # encodings measured by analysis/bench_storage.py (10 s of test 12, truth and instrumented
        # channels): BYTE_STREAM_SPLIT without dictionaries, zstd level 3, one row group per 0.5 s
        # chunk: 42 % of the raw size against 66 % for Arrow's defaults, 2.6x faster to write.
        # run_id and the labels are constant: dictionary encoded (one entry, run-length indices)
        encoding = {c.name: ("DELTA_BINARY_PACKED" if c.dtype == "int32" else "BYTE_STREAM_SPLIT") for c in self.columns}
        encoding["t"] = "BYTE_STREAM_SPLIT"
        dictionary = ["run_id"] + [lab.name for lab in self.labels]
        self._labels = [pa.scalar(self.run_id, pa.string())] + [pa.scalar(lab.value, lab.dtype) for lab in self.labels]
        try:
            self._fh = os.fdopen(open_new(self.tmp), "wb")  # never through a link planted at the name
            self._w = pq.ParquetWriter(self._fh, schema, compression="zstd", compression_level=3,
                                       use_dictionary=dictionary, column_encoding=encoding, write_statistics=False)
        except OSError as err:
            raise WriteError(f"{self.path}: cannot write ({err})") from None
        self._schema = schema

    def write(self, chunk: Run) -> None:
        import pyarrow as pa

        if self._done:
            raise TwinError(f"{self.path}: write after close")
        if chunk.n == 0:
            return
        if self._w is None:
            self._open(chunk)
        n = chunk.n
        arrays = [pa.repeat(self._labels[0], n),
                  pa.array(self._t0 + (self.rows + np.arange(n, dtype=np.float64)) / self._rate)]
        arrays += [pa.repeat(v, n) for v in self._labels[1:]]
        for c in self.columns:
            x = chunk[c.name]
            y = x.astype(c.dtype)
            if c.exact and not np.array_equal(y.astype(np.float64), x.astype(np.float64)):
                bad = int(np.flatnonzero(y.astype(np.float64) != x.astype(np.float64))[0])
                raise RecordingError(f"{c.name}: value {x[bad]!r} does not fit {c.dtype} exactly "
                                     f"(sample {self.rows + bad} of run {self.run_id})")
            self.stats.update(c.name, y)
            arrays.append(pa.array(y))
        try:
            self._w.write_table(pa.Table.from_arrays(arrays, schema=self._schema))
        except OSError as err:
            raise WriteError(f"{self.path}: cannot write ({err})") from None
        self.rows += chunk.n

    def close(self, meta: dict[str, Any] | None = None, summary: dict[str, Any] | None = None) -> Path:  # noqa: ARG002
        if self._w is None:
            raise TwinError(f"{self.path}: the run produced no samples")
        try:
            self._w.close()
            self._fh.close()
            check_not_link(self.path)
            os.replace(self.tmp, self.path)
        except OSError as err:
            self.abort()
            raise WriteError(f"{self.path}: cannot write ({err})") from None
        self._done = True
        return self.path

    def abort(self) -> None:
        if self._done:
            return
        self._done = True
        try:
            if self._w is not None:
                self._w.close()
            if getattr(self, "_fh", None) is not None:
                self._fh.close()
        except Exception:  # noqa: BLE001 - best effort on the error path
            pass
        self.tmp.unlink(missing_ok=True)


def read_meta(path: str | Path) -> dict[str, Any]:
    """The ``twin.dataset`` metadata of a run file."""
    import pyarrow.parquet as pq

    try:
        md = pq.read_schema(path).metadata or {}
    except (OSError, ValueError) as err:
        raise RecordingError(f"{path}: not a readable Parquet file ({err})") from None
    if META_KEY not in md:
        raise RecordingError(f"{path}: no twin.dataset metadata (not a dataset run file)")
    try:
        meta = json.loads(md[META_KEY])
    except (ValueError, RecursionError) as err:
        raise RecordingError(f"{path}: twin.dataset metadata is not JSON ({' '.join(str(err).split())})") from None
    return check_meta(meta, path)


def check_meta(meta: Any, path: str | Path) -> dict[str, Any]:
    """The fields of a run file's ``twin.dataset`` metadata the readers use, or one line naming the
    file and the field."""
    import math

    def num(v: Any) -> bool:
        return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)

    if not isinstance(meta, dict):
        raise RecordingError(f"{path}: twin.dataset metadata must be a JSON object, got {type(meta).__name__}")
    for field, ok, want in (("run_id", lambda v: isinstance(v, str), "a string"),
                            ("rate_hz", lambda v: num(v) and v > 0, "a positive number"),
                            ("t0", lambda v: v is None or num(v), "a number"),
                            ("units", lambda v: isinstance(v, dict) and all(isinstance(x, str) for x in v.values()),
                             "an object of unit strings"),
                            ("groups", lambda v: v is None or isinstance(v, dict), "an object"),
                            ("config_toml", lambda v: v is None or isinstance(v, str), "a TOML text")):
        if not ok(meta.get(field)):
            raise RecordingError(f"{path}: twin.dataset metadata field {field!r} must be {want}, "
                                 f"got {meta.get(field, 'missing')!r}"[:400])
    return meta


def read_columns(path: str | Path, columns: Iterable[str] | None = None, start: int = 0,
                 stop: int | None = None) -> dict[str, np.ndarray]:
    """Columns of a run file as numpy arrays, rows [start, stop) (only the row groups that hold
    them are read)."""
    import pyarrow.parquet as pq

    try:
        f = pq.ParquetFile(path)
    except (OSError, ValueError) as err:
        raise RecordingError(f"{path}: not a readable Parquet file ({err})") from None
    names = list(columns) if columns is not None else f.schema_arrow.names
    missing = [c for c in names if c not in f.schema_arrow.names]
    if missing:
        raise RecordingError(f"{path}: no channels {', '.join(missing)}; it holds {', '.join(f.schema_arrow.names)}")
    n = f.metadata.num_rows
    stop = n if stop is None else min(stop, n)
    start = max(0, start)
    if stop <= start:
        return {c: np.zeros(0, dtype=f.schema_arrow.field(c).type.to_pandas_dtype()) for c in names}
    groups, first, offset = [], None, 0
    for g in range(f.num_row_groups):
        m = f.metadata.row_group(g).num_rows
        if offset + m > start and offset < stop:
            groups.append(g)
            first = offset if first is None else first
        offset += m
    try:
        table = f.read_row_groups(groups, columns=names)
    except Exception as err:  # noqa: BLE001 - a damaged page: pyarrow raises many kinds, one line here
        raise RecordingError(f"{path}: damaged ({' '.join(str(err).split())[:200]})") from None
    return {c: table.column(c).to_numpy()[start - first:stop - first] for c in names}


def channel_names(path: str | Path, meta: dict[str, Any] | None = None) -> list[str]:
    """The channel columns of a run file in file order: the columns its ``twin.dataset``
    metadata gives a unit (the key and label columns of format twin-dataset/2 left out)."""
    import pyarrow.parquet as pq

    units = (meta or read_meta(path))["units"]
    return [n for n in pq.read_schema(path).names if n in units]


def read_run(path: str | Path, columns: Iterable[str] | None = None) -> Run:
    """A run file as a :class:`~twin.run.Run` (for ``twin view``; configuration from the dataset):
    its channels (default: all of them), not its key and label columns."""
    from twin.config import config_from_toml

    meta = read_meta(path)
    cols = read_columns(path, channel_names(path, meta) if columns is None else columns)
    # channels a run lacks are stored as NaN columns (the dataset's union): left out here
    chans = {k: Channel(k, meta["units"].get(k, ""), (meta.get("groups") or {}).get(k, "extra"), v) for k, v in cols.items()
             if not (v.dtype.kind == "f" and v.size and np.isnan(v[0]) and np.all(np.isnan(v)))}
    cfg = config_from_toml(meta["config_toml"]) if meta.get("config_toml") else None
    return Run(float(meta.get("t0", 0.0)), float(meta["rate_hz"]), chans, cfg, {"run_id": meta["run_id"]})


def valid_from_s(meta: dict[str, Any]) -> float:
    """Time from which a run file's samples are its own physics [s]: ``warm_start.valid_from_s`` of
    its metadata (an approximate warm start), else 0."""
    ws = meta.get("warm_start") if isinstance(meta, dict) else None
    if isinstance(ws, str):
        try:
            ws = json.loads(ws)
        except ValueError:
            return 0.0
    v = ws.get("valid_from_s") if isinstance(ws, dict) else None
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) else 0.0
