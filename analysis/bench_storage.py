"""Signal layout of ``twin dataset``: Parquet against Zarr v3, NPZ, the project's MCAP and HDF5, measured.

Method
------
1. **Data, made once.** A real run of the project: Table 4 test 12 (clearance 0.1 mm at B and C,
   750 motor rpm) on the MuJoCo engine for ``--duration`` s at 100 kHz (``--program constant``,
   default; ``protocol`` stretches the three-speed protocol to the duration through its hold
   time, duration >= 9 s), all 23 truth channels in their storage dtype (float32 accelerations,
   forces and torque; float64 angles, rates, positions, eccentricities, penetrations), plus the
   instrumented channels of a synthetic bench recording: the sensor chain on the run
   (``twin.instrument.apply_chain``: ``volt_AC1..6`` and ``motor_command`` [V], 18-bit
   quantized float64; ``encoder_counts``, whole-number float64) and the calibrated
   accelerations ``meas_AC1..6`` [m/s^2] (``simulated_calibration`` + ``measured_accel``, float64),
   as ``twin/bench_replay.py`` builds them. 37 channels, 252 bytes of raw data per sample.
2. **Writes stream.** Every layout except NPZ is written the way the generator will write it:
   chunks of ``--chunk-s`` (0.5 s, the simulator's chunk) handed to the writer one after the
   other; a writer keeps at most one row group / chunk of its own. NPZ cannot stream
   (``np.savez_compressed`` takes whole arrays): it is given the whole run. Layouts:

   * Parquet (``pyarrow.parquet.ParquetWriter``), one column per channel, zstd (Arrow's default
     level 1), no time column (uniform rate, stored in the schema metadata with units and groups
     per field), row groups of 0.1 / 0.5 / 1 s (chunks are buffered up to a row group, so a
     1 s row group holds two 0.5 s chunks); encodings: ``dict`` = Arrow's default (dictionary
     with fallback to plain), ``bss`` = BYTE_STREAM_SPLIT (byte-plane transposition, no
     dictionary), ``dict+bss`` = dictionary for the 18-bit quantized volt channels, BYTE_STREAM_SPLIT
     elsewhere; zstd level 1 (Arrow's default) or 3 (``L3``); dtypes ``native`` (float32 where
     the channel is float32, float64 elsewhere), ``sensor-f32`` (also float32 for the instrumented
     channels: volts, motor command, encoder counts, calibrated accelerations) or ``all-f32``
     (everything float32); the last two are lossy where float32 cannot hold the value, their
     errors are reported instead of an identity check;
   * Zarr v3 (``zarr`` 3), one array per channel in a group, chunked along time (0.5 s unless
     named), ``zstd`` codec (level 0 = zstd's default 3) or ``blosc`` (zstd inside blosc with
     byte shuffle);
   * NPZ, ``np.savez_compressed`` (zip deflate), whole run;
   * MCAP, the project's own run file (``twin.mcapfile.RunWriter``: one topic per channel group,
     5000-sample CDR blocks, uncompressed chunks of 4 MiB; its results in the README were measured
     with 1000-sample blocks and zstd chunks);
   * HDF5 (``h5py``), one chunked dataset per channel (0.1 s chunks), gzip level 4 + shuffle or lzf
     + shuffle.

   A layout whose package is missing is skipped with a printed note.
3. **Measurements**, each layout in turn within every repeat (interleaved), best of ``--repeats``:
   (the order of the layouts is shuffled from the second repeat on); bytes on disk (file or folder total) and per simulated second; write throughput (raw MB of
   the source in its native dtypes per wall second, and simulated s per wall s; files are
   closed, not fsync'ed: the page cache absorbs the write); full read (every channel, whole run,
   into numpy arrays, the better of two reads; warm page cache, the file was just written); random access: ``--windows``
   windows of 0.1 s of 6 channels at the same random offsets for every layout (file opened once,
   as a data loader keeps its handle; each window is read and decoded into numpy), median
   latency per repeat (at most ``--window-budget`` s of windows per layout and repeat: NPZ must
   inflate the 6 whole members for every window); "open + window": open the file, read one window,
   close (median of 5), for a loader that opens a run per sample. Peak memory of the write: a fresh child
   process loads the source into memory, resets its peak-RSS counter (``/proc/self/clear_refs``
   = 5) and writes the layout once; reported is ``VmHWM`` after the write minus ``VmRSS``
   before it, i.e. the resident memory the writer adds (pyarrow's and zstd's native buffers
   included, which tracemalloc would not see); the chunks are handed over as fresh arrays, as the
   simulator makes them, so the chunk in flight and any chunk a writer keeps are counted. Where
   clear_refs is refused, a 1 ms RSS sampler is used instead (the table says which).
4. **Round trip**: after the first write of each layout, the full read is compared with the
   source, channel by channel: same dtype and bit-identical bytes. The float32 variants are
   compared in value on the channels they cast: max |error| in units and in the channel's
   resolution (ADC steps for volts and calibrated accelerations, counts for the encoder, encoder
   counts for angles), and whether the ADC codes and encoder counts are still recovered exactly
   by rounding; their other channels must be bit-identical.
5. **Portability of the Parquet files**: a child process imports only pyarrow and numpy, reads
   every Parquet file and compares it with the source (``twin`` must not be imported); if
   Hugging Face ``datasets`` is installed, another child times
   ``datasets.load_dataset("parquet", data_files=..., split="train")`` (offline, fresh cache,
   which converts the file into Arrow cache files) and compares every column.

Run: ``python analysis/bench_storage.py [--duration S] [--repeats N]`` (defaults 10 s, 3; about
four and a half minutes on two cores). Benchmark-only packages: ``pip install pyarrow zarr h5py datasets``.
The table is printed as markdown on stdout (``--markdown FILE`` also writes it, ``--json FILE``
the raw numbers); files go to a temporary folder that is deleted (``--keep DIR`` keeps them).
"""

from __future__ import annotations

import argparse
import bisect
import gc
import importlib
import importlib.metadata
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np

from twin.provenance import stamped, with_stamp_line

MB = 1e6
WINDOW_CHANNELS = ("AC1", "AC5", "meas_AC1", "meas_AC6", "encoder_counts", "ecc_C_x")


# ----------------------------------------------------------------------------------------------
# source data


@dataclass
class Source:
    """The run to store: channels in canonical order, native dtypes, with units and groups."""

    rate_hz: float
    arrays: dict[str, np.ndarray]
    units: dict[str, str]
    groups: dict[str, str]
    chunk: int  # samples per streamed chunk
    config: Any = None  # twin BenchConfig (MCAP stores it)
    description: str = ""
    copy_chunks: bool = False  # hand out fresh arrays per chunk, as the simulator does

    @property
    def n(self) -> int:
        return len(next(iter(self.arrays.values())))

    @property
    def duration_s(self) -> float:
        return self.n / self.rate_hz

    @property
    def raw_bytes(self) -> int:
        return sum(a.nbytes for a in self.arrays.values())

    def chunks(self) -> Iterator[tuple[int, dict[str, np.ndarray]]]:
        """(first index, {name: view}) for consecutive chunks: what the generator's sink sees."""
        for i0 in range(0, self.n, self.chunk):
            if self.copy_chunks:
                yield i0, {k: a[i0:i0 + self.chunk].copy() for k, a in self.arrays.items()}
            else:
                yield i0, {k: a[i0:i0 + self.chunk] for k, a in self.arrays.items()}


def make_config(duration: float, program: str):
    from twin.config import preset

    over: dict[str, Any] = {"simulation.duration_s": duration}
    if program == "protocol":
        if duration < 9:
            raise SystemExit("--program protocol needs --duration >= 9 s (four 2 s stops and three holds)")
        over.update({"drive.program": "protocol", "drive.protocol_hold_s": (duration - 8.0) / 3.0})
    return preset(12).replace(**over)


def make_source(duration: float, program: str, chunk_s: float) -> Source:
    """Simulate the run and add the instrumented channels (twin/bench_replay.py steps 3-4)."""
    from twin.instrument import apply_chain, measured_accel, simulated_calibration
    from twin.simulation import simulate_run

    cfg = make_config(duration, program)
    t0 = time.perf_counter()
    run = simulate_run(cfg)
    sim_s = time.perf_counter() - t0
    daq = apply_chain(run, cfg)  # noise stream 0: a recording made by the twin
    meas = measured_accel(daq, simulated_calibration(cfg))
    if daq.n != run.n:
        raise SystemExit(f"instrumentation rate {daq.rate_hz} differs from the run's {run.rate_hz}")
    arrays, units, groups = {}, {}, {}
    for r in (run, daq, meas):
        for name, c in r.channels.items():
            arrays[name] = np.ascontiguousarray(c.data)
            units[name], groups[name] = c.unit, c.group
    desc = (f"Table 4 test 12, {program} drive, {duration:g} s at {run.rate_hz:g} Hz, MuJoCo "
            f"(simulated in {sim_s:.1f} s); {len(arrays)} channels: "
            f"{sum(a.dtype == np.float32 for a in arrays.values())} float32, "
            f"{sum(a.dtype == np.float64 for a in arrays.values())} float64")
    return Source(run.rate_hz, arrays, units, groups, max(1, int(round(chunk_s * run.rate_hz))), cfg, desc)


def save_source(src: Source, folder: Path) -> Path:
    """Uncompressed copy for the child processes (memory and portability checks)."""
    path = folder / "source.npz"
    np.savez(path, **src.arrays)
    (folder / "source.json").write_text(json.dumps({
        "rate_hz": src.rate_hz, "units": src.units, "groups": src.groups, "chunk": src.chunk,
        "description": src.description}))
    return path


def load_source(folder: Path, duration: float, program: str) -> Source:
    info = json.loads((folder / "source.json").read_text())
    with np.load(folder / "source.npz") as z:
        arrays = {k: np.ascontiguousarray(z[k]) for k in info["units"]}
    return Source(info["rate_hz"], arrays, info["units"], info["groups"], info["chunk"],
                  make_config(duration, program), info["description"])


# ----------------------------------------------------------------------------------------------
# layouts


class Layout:
    """A candidate layout: write (streaming or not), full read, windowed reader."""

    name = ""
    settings = ""
    streams = True
    lossy = False
    package = ""  # import name that must be present

    def suffix(self) -> str:
        return ""

    def write(self, path: Path, src: Source) -> None:
        raise NotImplementedError

    def read_all(self, path: Path) -> dict[str, np.ndarray]:
        raise NotImplementedError

    def open(self, path: Path) -> "WindowReader":
        raise NotImplementedError


class WindowReader:
    def __init__(self, fn: Callable[[int, int, tuple[str, ...]], dict[str, np.ndarray]],
                 close: Callable[[], None] = lambda: None):
        self.window, self.close = fn, close


class ParquetLayout(Layout):
    package = "pyarrow"

    def __init__(self, rg_s: float, rate: float, encoding: str = "dict", f32: str = "native",
                 level: int | None = None):
        self.rg = max(1, int(round(rg_s * rate)))
        self.encoding, self.f32, self.level = encoding, f32, level
        self.lossy = f32 != "native"
        self.name = (f"parquet {encoding} rg {rg_s:g}s" + (f" L{level}" if level is not None else "")
                     + ("" if f32 == "native" else f" {f32}-f32"))
        self.settings = (f"zstd {'L' + str(level) if level is not None else 'L1'}, row group {self.rg} samples, "
                         + {"native": "native dtypes",
                            "all": "everything float32 (lossy)",
                            "sensor": "float32 also for the instrumented channels (volts, counts, meas_AC)"}[f32])

    def cast(self, name: str, dtype: np.dtype) -> bool:
        """Whether channel ``name`` (float64) is stored as float32."""
        if dtype == np.float32 or self.f32 == "native":
            return False
        if self.f32 == "all":
            return True
        return name.startswith(("volt_", "meas_")) or name in ("motor_command", "encoder_counts")

    def suffix(self) -> str:
        return ".parquet"

    def schema(self, src: Source):
        import pyarrow as pa

        fields = []
        for k, a in src.arrays.items():
            t = pa.float32() if (a.dtype == np.float32 or self.cast(k, a.dtype)) else pa.float64()
            fields.append(pa.field(k, t, nullable=False, metadata={"unit": src.units[k], "group": src.groups[k]}))
        meta = {"twin.rate_hz": repr(src.rate_hz), "twin.t0": "0.0", "twin.n": str(src.n)}
        return pa.schema(fields, metadata=meta)

    def writer_options(self, src: Source) -> dict[str, Any]:
        quantized = [k for k in src.arrays if k.startswith("volt_") or k == "motor_command"]
        opts: dict[str, Any] = {"compression": "zstd", "compression_level": self.level}
        if self.encoding == "dict":
            opts.update(use_dictionary=True, use_byte_stream_split=False)
        elif self.encoding == "bss":
            opts.update(use_dictionary=False, use_byte_stream_split=True)
        elif self.encoding == "dict+bss":
            opts.update(use_dictionary=quantized, use_byte_stream_split=[k for k in src.arrays if k not in quantized])
        else:
            raise ValueError(self.encoding)
        return opts

    def write(self, path: Path, src: Source) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        schema = self.schema(src)
        buf: list[pa.Table] = []
        rows = 0
        with pq.ParquetWriter(path, schema, **self.writer_options(src)) as w:
            for _, chunk in src.chunks():
                cols = [pa.array(a.astype(np.float32) if self.cast(k, a.dtype) else a) for k, a in chunk.items()]
                buf.append(pa.Table.from_arrays(cols, schema=schema))
                rows += len(chunk[next(iter(chunk))])
                while rows >= self.rg:  # write full row groups, keep the rest
                    t = pa.concat_tables(buf)
                    w.write_table(t.slice(0, self.rg), row_group_size=self.rg)
                    rest = t.slice(self.rg)
                    buf, rows = ([rest] if rest.num_rows else []), rest.num_rows
            if rows:
                w.write_table(pa.concat_tables(buf), row_group_size=self.rg)

    def read_all(self, path: Path) -> dict[str, np.ndarray]:
        import pyarrow.parquet as pq

        t = pq.read_table(path)
        return {k: t.column(k).to_numpy() for k in t.column_names}

    def open(self, path: Path) -> WindowReader:
        import pyarrow.parquet as pq

        pf = pq.ParquetFile(path)
        md = pf.metadata
        starts = [0]
        for i in range(md.num_row_groups):
            starts.append(starts[-1] + md.row_group(i).num_rows)

        def window(i0: int, i1: int, names: tuple[str, ...]) -> dict[str, np.ndarray]:
            g0 = bisect.bisect_right(starts, i0) - 1
            g1 = bisect.bisect_left(starts, i1)  # row groups g0 .. g1-1 overlap [i0, i1)
            t = pf.read_row_groups(list(range(g0, g1)), columns=list(names)).slice(i0 - starts[g0], i1 - i0)
            return {k: t.column(k).to_numpy() for k in names}

        return WindowReader(window, pf.close)


class ZarrLayout(Layout):
    package = "zarr"

    def __init__(self, chunk_s: float, rate: float, codec: str = "zstd", shard_s: float | None = None):
        self.c = max(1, int(round(chunk_s * rate)))
        self.shard = max(1, int(round(shard_s * rate))) if shard_s else None
        self.codec = codec
        self.name = f"zarr v3 {codec} chunk {chunk_s:g}s" + (f" shard {shard_s:g}s" if shard_s else "")
        self.settings = {"zstd": "zstd codec (level 0 = 3)",
                         "blosc": "blosc zstd L5 + byte shuffle"}[codec] + f", array per channel, chunk {self.c}"
        if self.shard:
            self.settings += f", shard {self.shard}"

    def suffix(self) -> str:
        return ".zarr"

    def _compressors(self, dtype: np.dtype):
        import zarr.codecs as zc

        if self.codec == "zstd":
            return zc.ZstdCodec(level=0)
        return zc.BloscCodec(cname="zstd", clevel=5, shuffle="shuffle", typesize=dtype.itemsize)

    def write(self, path: Path, src: Source) -> None:
        import zarr

        root = zarr.open_group(str(path), mode="w", zarr_format=3,
                               attributes={"rate_hz": src.rate_hz, "t0": 0.0, "n": src.n})
        arrs = {k: root.create_array(k, shape=(src.n,), chunks=(self.c,), shards=(self.shard,) if self.shard else None,
                                     dtype=a.dtype, compressors=self._compressors(a.dtype), fill_value=0.0,
                                     attributes={"unit": src.units[k], "group": src.groups[k]})
                for k, a in src.arrays.items()}
        for i0, chunk in src.chunks():
            for k, a in chunk.items():
                arrs[k][i0:i0 + len(a)] = a

    def read_all(self, path: Path) -> dict[str, np.ndarray]:
        import zarr

        g = zarr.open_group(str(path), mode="r")
        return {k: g[k][:] for k in self._names(g)}

    @staticmethod
    def _names(g) -> list[str]:
        return sorted(g.array_keys())

    def open(self, path: Path) -> WindowReader:
        import zarr

        g = zarr.open_group(str(path), mode="r")
        cache: dict[str, Any] = {}

        def window(i0: int, i1: int, names: tuple[str, ...]) -> dict[str, np.ndarray]:
            out = {}
            for k in names:
                if k not in cache:
                    cache[k] = g[k]
                out[k] = cache[k][i0:i1]
            return out

        return WindowReader(window)


class NpzLayout(Layout):
    name = "npz compressed"
    settings = "np.savez_compressed (zip deflate), whole run"
    streams = False

    def suffix(self) -> str:
        return ".npz"

    def write(self, path: Path, src: Source) -> None:
        np.savez_compressed(path, **src.arrays)  # cannot stream: needs the whole arrays

    def read_all(self, path: Path) -> dict[str, np.ndarray]:
        with np.load(path) as z:
            return {k: z[k] for k in z.files}

    def open(self, path: Path) -> WindowReader:
        z = np.load(path)

        def window(i0: int, i1: int, names: tuple[str, ...]) -> dict[str, np.ndarray]:
            return {k: z[k][i0:i1] for k in names}  # inflates each whole member

        return WindowReader(window, z.close)


class McapLayout(Layout):
    name = "mcap (twin run file)"
    settings = "twin.mcapfile.RunWriter: topic per group, 5000-sample blocks, uncompressed 4 MiB chunks"
    package = "mcap"

    def suffix(self) -> str:
        return ".mcap"

    def write(self, path: Path, src: Source) -> None:
        from twin.mcapfile import RunWriter
        from twin.run import Channel, Run

        with RunWriter(path, src.config) as w:
            for i0, chunk in src.chunks():
                chans = {k: Channel(k, src.units[k], src.groups[k], a) for k, a in chunk.items()}
                w.write(Run(i0 / src.rate_hz, src.rate_hz, chans, src.config, {}))
            w.close({}, None)

    def read_all(self, path: Path) -> dict[str, np.ndarray]:
        from twin.mcapfile import read_run

        return {k: c.data for k, c in read_run(path).channels.items()}

    def open(self, path: Path) -> WindowReader:
        from mcap.reader import make_reader

        from twin.mcapfile import DEFAULT_BLOCK, TOPIC_PREFIX, decode_block

        fh = open(path, "rb")
        reader = make_reader(fh)
        summary = reader.get_summary()
        info = {m.name: dict(m.metadata) for m in reader.iter_metadata()}["twin.run"]
        rate = float(info["rate_hz"])
        where: dict[str, tuple[str, int]] = {}  # channel -> (topic, field index)
        dtypes: dict[str, list[str]] = {}
        for ch in summary.channels.values():
            if ch.topic.startswith(TOPIC_PREFIX):
                for j, nm in enumerate(ch.metadata["names"].split(",")):
                    where[nm] = (ch.topic, j)
                dtypes[ch.topic] = ch.metadata["dtypes"].split(",")
        block = DEFAULT_BLOCK  # the writer's above

        def window(i0: int, i1: int, names: tuple[str, ...]) -> dict[str, np.ndarray]:
            topics = sorted({where[k][0] for k in names})
            b0 = (i0 // block) * block
            start = int(round(b0 / rate * 1e9))
            end = int(round((i1 - 1) / rate * 1e9)) + 1
            parts: dict[str, list[tuple[int, list[np.ndarray]]]] = {t: [] for t in topics}
            for _s, ch, msg in reader.iter_messages(topics=topics, starting_at=start, ending_before=end,
                                                    log_time_order=False):
                _, first, _, arrays = decode_block(msg.data, dtypes[ch.topic])
                parts[ch.topic].append((first, arrays))
            out = {}
            for k in names:
                topic, j = where[k]
                blocks = sorted(parts[topic], key=lambda p: p[0])
                data = np.concatenate([b[1][j] for b in blocks])
                out[k] = data[i0 - blocks[0][0]:i1 - blocks[0][0]]
            return out

        return WindowReader(window, fh.close)


class Hdf5Layout(Layout):
    package = "h5py"

    def __init__(self, chunk_s: float, rate: float, compression: str = "gzip"):
        self.c = max(1, int(round(chunk_s * rate)))
        self.compression = compression
        self.name = f"hdf5 {compression}+shuffle chunk {chunk_s:g}s"
        self.settings = (f"{'gzip L4' if compression == 'gzip' else 'lzf'} + shuffle, dataset per channel, "
                         f"chunk {self.c}")

    def suffix(self) -> str:
        return ".h5"

    def write(self, path: Path, src: Source) -> None:
        import h5py

        with h5py.File(path, "w") as f:
            f.attrs["rate_hz"] = src.rate_hz
            opts = {"compression": self.compression, "shuffle": True}
            if self.compression == "gzip":
                opts["compression_opts"] = 4
            ds = {}
            for k, a in src.arrays.items():
                ds[k] = f.create_dataset(k, shape=(src.n,), dtype=a.dtype, chunks=(min(self.c, src.n),), **opts)
                ds[k].attrs["unit"], ds[k].attrs["group"] = src.units[k], src.groups[k]
            for i0, chunk in src.chunks():
                for k, a in chunk.items():
                    ds[k][i0:i0 + len(a)] = a

    def read_all(self, path: Path) -> dict[str, np.ndarray]:
        import h5py

        with h5py.File(path, "r") as f:
            return {k: f[k][()] for k in f.keys()}

    def open(self, path: Path) -> WindowReader:
        import h5py

        # no chunk cache: a loader drawing random windows from many runs rarely hits it, and the
        # other layouts have none (with h5py's 1 MiB default, short runs are served from memory)
        f = h5py.File(path, "r", rdcc_nbytes=0)
        ds: dict[str, Any] = {}

        def window(i0: int, i1: int, names: tuple[str, ...]) -> dict[str, np.ndarray]:
            out = {}
            for k in names:
                if k not in ds:
                    ds[k] = f[k]
                out[k] = ds[k][i0:i1]
            return out

        return WindowReader(window, f.close)


def make_layouts(rate: float, which: str | None = None) -> tuple[list[Layout], list[str]]:
    """Candidate layouts (those whose package imports) and notes on the skipped ones."""
    all_layouts: list[Layout] = [
        ParquetLayout(0.5, rate, "dict"),  # Arrow's default encoding
        ParquetLayout(0.5, rate, "dict+bss"),
        ParquetLayout(0.1, rate, "bss"),
        ParquetLayout(0.5, rate, "bss"),
        ParquetLayout(1.0, rate, "bss"),
        ParquetLayout(0.1, rate, "bss", level=3),
        ParquetLayout(0.5, rate, "bss", level=3),
        ParquetLayout(1.0, rate, "bss", level=3),
        ParquetLayout(0.5, rate, "bss", f32="sensor", level=3),
        ParquetLayout(0.5, rate, "bss", f32="all", level=3),
        ZarrLayout(0.5, rate, "zstd"),
        ZarrLayout(0.5, rate, "blosc"),
        ZarrLayout(0.1, rate, "blosc", shard_s=0.5),
        NpzLayout(),
        McapLayout(),
        Hdf5Layout(0.1, rate, "gzip"),
        Hdf5Layout(0.1, rate, "lzf"),
    ]
    if which:
        keys = [w.strip() for w in which.split(",") if w.strip()]
        all_layouts = [lay for lay in all_layouts if any(k in lay.name for k in keys)]
    out, notes = [], []
    for lay in all_layouts:
        if lay.package:
            try:
                importlib.import_module(lay.package)
            except ImportError:
                notes.append(f"skipped {lay.name}: package '{lay.package}' is not installed "
                             f"(pip install {lay.package})")
                continue
        out.append(lay)
    return out, notes


# ----------------------------------------------------------------------------------------------
# measurement helpers


def disk_bytes(path: Path) -> int:
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    return path.stat().st_size


def remove(path: Path) -> None:
    if path.is_dir():
        shutil.rmtree(path)
    elif path.exists():
        path.unlink()


def identical(a: np.ndarray, b: np.ndarray) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and np.ascontiguousarray(a).tobytes() == np.ascontiguousarray(b).tobytes()


def check_exact(src: Source, got: dict[str, np.ndarray]) -> str:
    missing = [k for k in src.arrays if k not in got]
    if missing:
        return f"missing {missing[:3]}"
    bad = [k for k, a in src.arrays.items() if not identical(a, got[k])]
    return "bit-identical" if not bad else f"DIFFERS: {', '.join(bad[:4])}{' ...' if len(bad) > 4 else ''}"


def lossy_errors(src: Source, got: dict[str, np.ndarray]) -> list[dict[str, Any]]:
    """Errors of the all-float32 variant on the float64 channels."""
    from twin.instrument import STANDARD_G
    from twin.instrument.calibration import nominal_sensitivities
    from twin.instrument.daq import adc_codes, lsb_v

    inst = src.config.instrumentation
    lsb = lsb_v(inst)
    count_rad = 2 * np.pi / inst.encoder_counts_per_rev
    rows = []
    for k, a in src.arrays.items():
        if got[k].dtype == a.dtype:
            continue
        b = got[k].astype(np.float64)
        err = float(np.max(np.abs(b - a)))
        row: dict[str, Any] = {"channel": k, "unit": src.units[k], "max_abs": float(np.max(np.abs(a))), "max_err": err}
        if k.startswith("volt_") or k == "motor_command":
            row["resolution"] = f"{err / lsb:.3g} ADC steps"
            row["exact_after_rounding"] = bool(np.array_equal(adc_codes(b, inst), adc_codes(a, inst)))
        elif k == "encoder_counts":
            row["resolution"] = f"{err:.3g} counts"
            row["exact_after_rounding"] = bool(np.array_equal(np.rint(b), a))
        elif k.startswith("meas_"):  # one ADC step in m/s^2 (nominal sensitivity)
            step = lsb / nominal_sensitivities(src.config)[k[len("meas_"):]] * STANDARD_G
            row["resolution"] = f"{err / step:.3g} ADC steps"
        elif src.units[k] == "rad":
            row["resolution"] = f"{err / count_rad:.3g} encoder counts"
        rows.append(row)
    return rows


def window_offsets(n: int, w: int, count: int, seed: int = 12345) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, n - w + 1, size=count)


# ----------------------------------------------------------------------------------------------
# peak memory of one write (child process)


def _status_kb(key: str) -> int:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(key + ":"):
                return int(line.split()[1])
    raise KeyError(key)


def _child_write(layout_name: str, src_dir: Path, out: Path, duration: float, program: str) -> None:
    src = load_source(src_dir, duration, program)
    layouts, _ = make_layouts(src.rate_hz)
    lay = next(x for x in layouts if x.name == layout_name)
    importlib.import_module(lay.package or "numpy")
    if isinstance(lay, McapLayout):
        importlib.import_module("twin.mcapfile")  # imports are not the write's memory
    # warm the writer's imports on a tiny file (100 samples), so that imports and one-time set-up
    # are not counted but no buffer of the real chunk size is left in the allocators' free lists
    tiny = Source(src.rate_hz, {k: a[:100] for k, a in src.arrays.items()}, src.units, src.groups, 100, src.config)
    lay.write(out.with_name("warm" + lay.suffix()), tiny)
    remove(out.with_name("warm" + lay.suffix()))
    gc.collect()
    method = "VmHWM"
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
    except OSError:
        method = "sampled"
    # chunks are fresh arrays, as the simulator hands them over: a writer that keeps a chunk
    # (row-group buffer) is charged for it; the chunk in flight (12.6 MB for 37 channels) counts
    src.copy_chunks = True
    rss0 = _status_kb("VmRSS")
    peak = [rss0]
    stop = threading.Event()
    sampler = None
    if method == "sampled":
        def sample() -> None:
            while not stop.is_set():
                peak[0] = max(peak[0], _status_kb("VmRSS"))
                time.sleep(0.001)
        sampler = threading.Thread(target=sample, daemon=True)
        sampler.start()
    lay.write(out, src)
    if sampler is not None:
        stop.set()
        sampler.join()
        hwm = peak[0]
    else:
        hwm = _status_kb("VmHWM")
    print(json.dumps({"peak_delta_mb": (hwm - rss0) * 1024 / MB, "method": method}))


def write_peak_memory(layout: Layout, src_dir: Path, work: Path, args: argparse.Namespace) -> tuple[float, str]:
    out = work / ("mem" + layout.suffix())
    cmd = [sys.executable, str(Path(__file__).resolve()), "--duration", str(args.duration), "--program", args.program,
           "--_child-write", layout.name, "--_src", str(src_dir), "--_out", str(out)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    remove(out)
    if p.returncode != 0:
        return float("nan"), f"child failed: {p.stderr.strip().splitlines()[-1] if p.stderr.strip() else p.returncode}"
    r = json.loads(p.stdout.strip().splitlines()[-1])
    return r["peak_delta_mb"], r["method"]


# ----------------------------------------------------------------------------------------------
# portability checks (child processes)

_PYARROW_ONLY = r"""
import json, sys, time
import numpy as np
import pyarrow.parquet as pq
src = np.load(sys.argv[1])
out = {}
for path in sys.argv[2:]:
    t0 = time.perf_counter()
    t = pq.read_table(path)
    cols = {k: t.column(k).to_numpy() for k in t.column_names}
    dt = time.perf_counter() - t0
    meta = {k.decode(): v.decode() for k, v in (t.schema.metadata or {}).items() if k.startswith(b"twin.")}
    unit = t.schema.field("AC1").metadata[b"unit"].decode()
    exact = all(cols[k].dtype == src[k].dtype and cols[k].tobytes() == src[k].tobytes() for k in src.files)
    out[path] = {"read_s": dt, "rows": t.num_rows, "columns": t.num_columns, "exact": exact,
                 "rate_hz": meta.get("twin.rate_hz"), "unit_AC1": unit}
out["twin_imported"] = any(m == "twin" or m.startswith("twin.") for m in sys.modules)
print(json.dumps(out))
"""

_HF_DATASETS = r"""
import json, sys, time
import numpy as np
t_imp = time.perf_counter()
import datasets
t_imp = time.perf_counter() - t_imp
src = np.load(sys.argv[1])
out = {"datasets": datasets.__version__, "import_s": t_imp}
for path in sys.argv[3:]:
    t0 = time.perf_counter()
    ds = datasets.load_dataset("parquet", data_files=path, split="train", cache_dir=sys.argv[2])
    dt = time.perf_counter() - t0
    tbl = ds.data.table
    t1 = time.perf_counter()
    ds2 = datasets.load_dataset("parquet", data_files=path, split="train", cache_dir=sys.argv[2])
    dt2 = time.perf_counter() - t1
    exact = all(tbl.column(k).to_numpy().dtype == src[k].dtype and tbl.column(k).to_numpy().tobytes() == src[k].tobytes()
                for k in src.files)
    f32 = sorted({str(ds.features[k].dtype) for k in ds.column_names})
    out[path] = {"load_s": dt, "reload_cached_s": dt2, "rows": ds.num_rows, "exact": exact, "feature_dtypes": f32}
out["twin_imported"] = any(m == "twin" or m.startswith("twin.") for m in sys.modules)
print(json.dumps(out))
"""


def run_child(code: str, argv: list[str], env: dict[str, str] | None = None) -> dict[str, Any]:
    p = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True,
                       env={**os.environ, **(env or {})}, cwd=tempfile.gettempdir())
    if p.returncode != 0:
        tail = p.stderr.strip().splitlines()[-3:] if p.stderr.strip() else [str(p.returncode)]
        return {"error": " | ".join(tail)}
    return json.loads(p.stdout.strip().splitlines()[-1])


# ----------------------------------------------------------------------------------------------
# main


@dataclass
class Result:
    layout: Layout
    size: int = 0
    write_s: list[float] = field(default_factory=list)
    read_s: list[float] = field(default_factory=list)
    window_ms: list[float] = field(default_factory=list)  # median per repeat
    open_ms: list[float] = field(default_factory=list)  # open + one window + close, median of 5 per repeat
    windows_done: int = 0
    exact: str = ""
    errors: list[dict[str, Any]] = field(default_factory=list)
    mem_mb: float = float("nan")
    mem_method: str = ""


def fmt(x: float, spec: str = ".3g") -> str:
    return "–" if not np.isfinite(x) else format(x, spec)


def render(src: Source, results: list[Result], notes: list[str], checks: list[str], args: argparse.Namespace,
           env_line: str) -> str:
    raw = src.raw_bytes
    D = src.duration_s
    lines = [f"# Signal layouts for `twin dataset` ({D:g} s run, best of {args.repeats})", "",
             f"- data: {src.description}; raw {raw / MB:.1f} MB ({raw / D / 1e3:.0f} kB per simulated s); "
             f"written in {src.chunk}-sample chunks ({src.chunk / src.rate_hz:g} s)",
             f"- random access: {args.windows} windows of {args.window_s:g} s x {len(WINDOW_CHANNELS)} channels "
             f"({', '.join(WINDOW_CHANNELS)}) at random offsets, file opened once (median latency); "
             f"'open + window': open, read one window, close (median of 5); warm page cache",
             f"- write peak: resident memory added by one write in a fresh process holding the source "
             f"({', '.join(sorted({r.mem_method for r in results if r.mem_method}))}); source not counted, "
             f"the 0.5 s chunk in flight ({src.chunk * src.raw_bytes / src.n / MB:.1f} MB) counted; a layout that "
             f"cannot stream also needs the whole run in memory (+ run)",
             f"- {env_line}", "",
             "| layout | streams | size MB | kB / sim s | % of raw | write MB/s | write sim s / s | "
             "full read MB/s | window median ms | open + window ms | write peak MB | round trip |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        w, rd = min(r.write_s), min(r.read_s)
        win = min(r.window_ms) if r.window_ms else float("nan")
        opn = min(r.open_ms) if r.open_ms else float("nan")
        mem = fmt(r.mem_mb, ".0f") + ("" if r.layout.streams or not np.isfinite(r.mem_mb) else f" + run ({raw / MB:.0f})")
        lines.append(
            f"| {r.layout.name} | {'yes' if r.layout.streams else 'no'} | {r.size / MB:.1f} | {r.size / D / 1e3:.0f} | "
            f"{100 * r.size / raw:.1f} | {raw / MB / w:.0f} | {D / w:.1f} | {raw / MB / rd:.0f} | {fmt(win)} | "
            f"{fmt(opn)} | {mem} | {r.exact} |")
    lines += ["", "Settings:", ""] + [f"- {r.layout.name}: {r.layout.settings}" for r in results]
    lossy = [r for r in results if r.layout.lossy]
    for r in lossy:
        lines += ["", f"## Errors of `{r.layout.name}` (float64 channels stored as float32)", "",
                  "Resolution: ADC steps of 20 V / 2^18 (meas_AC: one step in m/s^2 at the nominal sensitivity), "
                  "encoder counts of 2 pi / 32768 rad. 'exact after rounding': the ADC codes and counts are "
                  "recovered exactly (float32 holds integers below 2^24 counts = 512 crank turns exactly).", "",
                  "| channel | unit | max abs value | max abs error | in resolution | exact after rounding |",
                  "|---|---|---|---|---|---|"]
        for e in r.errors:
            ex = e.get("exact_after_rounding")
            lines.append(f"| {e['channel']} | {e['unit']} | {e['max_abs']:.4g} | {e['max_err']:.3g} | "
                         f"{e.get('resolution', '')} | {'' if ex is None else ('yes' if ex else 'NO')} |")
    if checks:
        lines += ["", "## Checks", ""] + [f"- {c}" for c in checks]
    if notes:
        lines += ["", "## Notes", ""] + [f"- {n}" for n in notes]
    return "\n".join(lines) + "\n"


def versions() -> str:
    out = []
    for p in ("numpy", "pyarrow", "zarr", "numcodecs", "h5py", "mcap", "zstandard", "datasets"):
        try:
            out.append(f"{p} {importlib.metadata.version(p)}")
        except importlib.metadata.PackageNotFoundError:
            pass
    return (f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python "
            f"{platform.python_version()}; " + ", ".join(out))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=10.0, help="simulated duration [s] (default 10)")
    ap.add_argument("--program", choices=("constant", "protocol"), default="constant")
    ap.add_argument("--repeats", type=int, default=3, help="interleaved repeats, best kept (default 3)")
    ap.add_argument("--chunk-s", type=float, default=0.5, help="streamed chunk [s] (default 0.5)")
    ap.add_argument("--windows", type=int, default=100, help="random windows per layout and repeat (default 100)")
    ap.add_argument("--window-s", type=float, default=0.1, help="window length [s] (default 0.1)")
    ap.add_argument("--window-budget", type=float, default=2.0,
                    help="at most this many seconds of window reads per layout and repeat (default 2)")
    ap.add_argument("--layouts", default=None, help="comma-separated substrings of layout names to keep")
    ap.add_argument("--no-memory", action="store_true", help="skip the peak-memory child processes")
    ap.add_argument("--no-checks", action="store_true", help="skip the pyarrow-only and datasets checks")
    ap.add_argument("--keep", default=None, help="keep the written files in this folder")
    ap.add_argument("--markdown", default=None, help="also write the markdown table to this file")
    ap.add_argument("--json", default=None, help="write the raw numbers to this JSON file")
    ap.add_argument("--_child-write", dest="child_write", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--_src", dest="child_src", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--_out", dest="child_out", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child_write:
        _child_write(args.child_write, Path(args.child_src), Path(args.child_out), args.duration, args.program)
        return
    if args.repeats < 1 or args.windows < 1:
        raise SystemExit("--repeats and --windows must be >= 1")

    t_start = time.perf_counter()
    log = lambda msg: print(f"[{time.perf_counter() - t_start:6.1f} s] {msg}", file=sys.stderr, flush=True)  # noqa: E731
    log(f"simulating {args.duration:g} s of test 12 ({args.program}) and the sensor chain ...")
    src = make_source(args.duration, args.program, args.chunk_s)
    log(src.description)
    layouts, notes = make_layouts(src.rate_hz, args.layouts)
    for n in notes:
        print(f"note: {n}", file=sys.stderr)
    if args.keep:
        work = Path(args.keep)
        work.mkdir(parents=True, exist_ok=True)
        tmp_ctx = None
    else:
        tmp_ctx = tempfile.TemporaryDirectory(prefix="bench_storage_")
        work = Path(tmp_ctx.name)
    try:
        src_dir = work / "source"
        src_dir.mkdir(exist_ok=True)
        save_source(src, src_dir)
        w = int(round(args.window_s * src.rate_hz))
        offsets = window_offsets(src.n, w, args.windows)
        names = tuple(k for k in WINDOW_CHANNELS if k in src.arrays)
        results = [Result(lay) for lay in layouts]
        # warm-up: imports and one-time set-up of every layout on 100 samples, not timed
        tiny = Source(src.rate_hz, {k: a[:100] for k, a in src.arrays.items()}, src.units, src.groups, 100,
                      src.config)
        for lay in layouts:
            p = work / ("warm" + lay.suffix())
            lay.write(p, tiny)
            lay.read_all(p)
            rd = lay.open(p)
            rd.window(0, 50, names)
            rd.close()
            remove(p)
        for rep in range(args.repeats):
            # every repeat visits the layouts in a different order, so that what one layout leaves
            # behind (allocator state, page cache) does not always fall on the same neighbour
            order = [results[i] for i in np.random.default_rng(rep).permutation(len(results))] if rep else results
            for r in order:
                lay = r.layout
                path = work / (lay.name.replace(" ", "_").replace("(", "").replace(")", "").replace("+", "")
                               + lay.suffix())
                remove(path)
                gc.collect()
                t0 = time.perf_counter()
                lay.write(path, src)
                r.write_s.append(time.perf_counter() - t0)
                r.size = disk_bytes(path)
                reads = []
                for _ in range(2):  # the first read of a repeat may pay the allocator's page faults
                    got = None
                    gc.collect()
                    t0 = time.perf_counter()
                    got = lay.read_all(path)
                    reads.append(time.perf_counter() - t0)
                r.read_s.append(min(reads))
                if rep == 0:
                    if lay.lossy:
                        r.errors = lossy_errors(src, got)
                        cast = {e["channel"] for e in r.errors}
                        kept = Source(src.rate_hz, {k: a for k, a in src.arrays.items() if k not in cast}, src.units,
                                      src.groups, src.chunk)
                        r.exact = f"{len(cast)} channels as float32 (see errors), others {check_exact(kept, got)}"
                    else:
                        r.exact = check_exact(src, got)
                del got
                gc.collect()
                reader = lay.open(path)
                lat = []
                t_budget = time.perf_counter()
                for i, i0 in enumerate(offsets):
                    t0 = time.perf_counter()
                    win = reader.window(int(i0), int(i0) + w, names)
                    lat.append(time.perf_counter() - t0)
                    if rep == 0 and i == 0 and not lay.lossy:
                        for k in names:
                            if not identical(win[k], src.arrays[k][i0:i0 + w]):
                                r.exact += f"; window of {k} DIFFERS"
                    if time.perf_counter() - t_budget > args.window_budget and i >= 9:
                        break
                reader.close()
                opens = []
                for i0 in offsets[:5]:  # a loader that opens the file for each window
                    t0 = time.perf_counter()
                    rd = lay.open(path)
                    rd.window(int(i0), int(i0) + w, names)
                    rd.close()
                    opens.append(time.perf_counter() - t0)
                r.open_ms.append(1e3 * statistics.median(opens))
                r.windows_done = max(r.windows_done, len(lat))
                r.window_ms.append(1e3 * statistics.median(lat))
                r.layout_path = path  # type: ignore[attr-defined]
                log(f"repeat {rep + 1}/{args.repeats} {lay.name}: {r.size / MB:.1f} MB, write {r.write_s[-1]:.2f} s, "
                    f"read {r.read_s[-1]:.2f} s, window {r.window_ms[-1]:.2f} ms ({len(lat)} windows)")
        for r in results:
            if r.windows_done < args.windows:
                notes.append(f"{r.layout.name}: {r.windows_done} windows per repeat (time budget "
                             f"{args.window_budget:g} s), median of those")
        if any(isinstance(r.layout, Hdf5Layout) for r in results):
            notes.append("HDF5 write peak grows with the length of the run (about its raw size), it is not a "
                         "per-chunk buffer: the shuffle filter's buffers are kept (a separate check with h5py 3.16's "
                         "bundled HDF5: lzf without shuffle stays flat)")
        if not args.no_memory:
            for r in results:
                r.mem_mb, r.mem_method = write_peak_memory(r.layout, src_dir, work, args)
                log(f"write peak memory {r.layout.name}: {r.mem_mb:.0f} MB ({r.mem_method})")
        checks: list[str] = []
        if not args.no_checks:
            pq_files = [str(r.layout_path) for r in results  # type: ignore[attr-defined]
                        if isinstance(r.layout, ParquetLayout) and not r.layout.lossy]
            if pq_files:
                res = run_child(_PYARROW_ONLY, [str(src_dir / "source.npz"), *pq_files])
                if "error" in res:
                    checks.append(f"pyarrow-only read FAILED: {res['error']}")
                else:
                    ok = all(res[p]["exact"] for p in pq_files)
                    one = res[pq_files[0]]
                    checks.append(
                        f"pyarrow alone (child process importing only pyarrow and numpy; twin imported: "
                        f"{res['twin_imported']}): {len(pq_files)} lossless Parquet files read, "
                        f"{'all bit-identical to the source' if ok else 'SOME DIFFER'}; {one['rows']} rows x "
                        f"{one['columns']} columns, rate {one['rate_hz']} Hz and units (AC1: {one['unit_AC1']}) from "
                        f"the schema metadata; read_table + to_numpy "
                        + ", ".join(f"{Path(p).stem} {res[p]['read_s']:.2f} s" for p in pq_files))
                try:
                    importlib.metadata.version("datasets")
                    have_ds = True
                except importlib.metadata.PackageNotFoundError:
                    have_ds = False
                if have_ds:
                    cache = work / "hf_cache"
                    res = run_child(_HF_DATASETS, [str(src_dir / "source.npz"), str(cache), *pq_files],
                                    env={"HF_DATASETS_OFFLINE": "1", "HF_HUB_OFFLINE": "1",
                                         "HF_HOME": str(work / "hf_home"), "HF_DATASETS_CACHE": str(cache)})
                    if "error" in res:
                        checks.append(f"datasets.load_dataset('parquet') FAILED: {res['error']}")
                    else:
                        ok = all(res[p]["exact"] for p in pq_files)
                        checks.append(
                            f"Hugging Face datasets {res['datasets']} (child, twin imported: {res['twin_imported']}): "
                            f"load_dataset('parquet', data_files=..., split='train') on each lossless Parquet file, "
                            f"{'every column bit-identical' if ok else 'SOME DIFFER'}, features "
                            f"{res[pq_files[0]]['feature_dtypes']}; first load (converts into the Arrow cache) / "
                            f"cached reload: "
                            + ", ".join(f"{Path(p).stem} {res[p]['load_s']:.2f} s / {res[p]['reload_cached_s']:.2f} s"
                                        for p in pq_files))
                    shutil.rmtree(cache, ignore_errors=True)
                else:
                    checks.append("Hugging Face datasets not installed (pip install datasets): load_dataset check skipped")
        text = render(src, results, notes, checks, args, versions())
        print(text)
        if args.markdown:
            Path(args.markdown).write_text(with_stamp_line(text))
        if args.json:
            Path(args.json).write_text(json.dumps(stamped({
                "description": src.description, "raw_bytes": src.raw_bytes, "duration_s": src.duration_s,
                "results": [{"layout": r.layout.name, "settings": r.layout.settings, "streams": r.layout.streams,
                             "bytes": r.size, "write_s": r.write_s, "read_s": r.read_s, "window_median_ms": r.window_ms,
                             "open_window_ms": r.open_ms,
                             "windows": r.windows_done, "write_peak_mb": r.mem_mb, "memory_method": r.mem_method,
                             "round_trip": r.exact, "errors": r.errors} for r in results],
                "checks": checks, "notes": notes}), indent=1))
        log("done")
    finally:
        if tmp_ctx is not None:
            tmp_ctx.cleanup()


if __name__ == "__main__":
    main()
