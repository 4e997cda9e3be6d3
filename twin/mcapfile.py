"""Runs as MCAP files: batched array messages per channel group, uncompressed CRC-checked chunks.

Layout (documented for other tools in ``recordings/FORMAT.md``):

* one topic per channel group, ``/twin/<group>`` (``/twin/accel``, ``/twin/joint_C``...),
  message encoding ``cdr``, schema encoding ``ros2msg``, schema ``twin_msgs/msg/<Group>Block``;
* each message is a block of up to ``block`` consecutive samples (5000 = 50 ms at 100 kHz):
  ``builtin_interfaces/Time stamp`` (time of the block's first sample), ``uint64 first_index``,
  ``float64 rate_hz``, then one ``float32[]``/``float64[]`` array per channel;
* ``log_time = publish_time = stamp`` in nanoseconds of simulation time (epoch: the run's
  start, t = 0), never the wall clock, so files are reproducible;
* channel metadata ``names``/``units``/``dtypes`` (comma separated) give the exact channel
  names and units (ros2msg field names are lower-cased);
* metadata records ``twin.config`` (``toml``: the full configuration), ``twin.run``
  (``format``, ``t0``, ``rate_hz``, ``n``, ``meta`` as JSON) and optionally ``twin.summary``.

Preview (optional, ``preview_rate_hz`` > 0; ``twin simulate`` writes one at 1 kHz by default):
a topic ``/preview`` with one message per preview sample, every channel of the run a scalar
field (schema ``twin_msgs/msg/Preview``: ``std_msgs/Header header`` then one
``float32``/``float64`` per channel), so that Foxglove's plot panel draws each channel as a time
series (it cannot plot the arrays of the block messages). The preview is the block mean of
``M = round(rate_hz / preview_rate_hz)`` consecutive full-rate samples (a boxcar anti-alias
filter: no overshoot or ringing at impacts, streamed with no state but the incomplete block),
stamped at the block's centre ``t0 + (k M + (M - 1) / 2) / rate_hz``; the trailing ``n mod M``
samples have none. :func:`read_run` ignores it (it reads only ``/twin/`` topics, as readers of
files without a preview do); :func:`read_preview` reads it back.

Writes go to a temporary file that is renamed into place on success, so an existing file is
never left half-written.

Chunks: uncompressed, their CRCs written and checked on read (files written earlier with LZ4 or
zstd chunks read as before: the reader decompresses every MCAP codec). Measured side by side on
4 s of test 12 with the reference engine (23 channels at 100 kHz, 52 MB; ``python
analysis/bench_output.py --mcap-variants --repeats 7``): writing on the run's writer thread adds
12.5 % to the wall time with LZ4 chunks and 1000-sample blocks (0.3.0), 9.9 % with LZ4 and
5000-sample blocks, 7.0 % uncompressed with 5000-sample blocks (8.2 % in the loop; the MuJoCo
engine 2.6 %): LZ4 makes sampled float signals 7 % smaller (zstd 11 %, at 2.2x LZ4's write time),
and the per-message encoding in Python scales with the number of blocks.
"""

from __future__ import annotations

import json
import os
import re
import struct
from pathlib import Path
from typing import Any, Iterable

import numpy as np
from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from zstandard import ZstdError

from twin import __version__
from twin.config import BenchConfig, config_from_toml
from twin.errors import RecordingError, TwinError
from twin.run import Channel, Run
from twin.util import check_not_link, json_text, open_new, remove_stale_temps, temp_path

#: what a damaged file raises while it is read (LZ4's frame decoder raises RuntimeError)
_UNREADABLE = (McapError, ZstdError, RuntimeError, EOFError, struct.error, ValueError, KeyError)


FORMAT = "twin-run/1"
TOPIC_PREFIX = "/twin/"
DEFAULT_BLOCK = 5000
#: the preview topic (outside TOPIC_PREFIX: readers of the full-rate channels never see it)
PREVIEW_TOPIC = "/preview"
PREVIEW_SCHEMA = "twin_msgs/msg/Preview"
#: preview rate of ``twin simulate`` [Hz] (the library's writers write none unless asked)
DEFAULT_PREVIEW_HZ = 1000.0
#: chunk codecs a writer may use (the default "none": see the module docstring)
_COMPRESSION = {"none": CompressionType.NONE, "lz4": CompressionType.LZ4, "zstd": CompressionType.ZSTD}
_CDR_LE = b"\x00\x01\x00\x00"
_DTYPES = {"float32": ("float32", 4), "float64": ("float64", 8)}

_TIME_DEF = """================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"""


def field_name(channel: str) -> str:
    """ros2msg field name of a channel (lower case, [a-z0-9_])."""
    f = re.sub(r"[^a-z0-9_]", "_", channel.lower())
    return f if f[:1].isalpha() else f"c_{f}"


def schema_name(group: str) -> str:
    """ros2msg type name of a group's block message."""
    return "twin_msgs/msg/" + "".join(p.capitalize() for p in re.split(r"[_\W]+", group) if p) + "Block"


def schema_text(group: str, channels: list[Channel]) -> str:
    lines = [f"# Block of uniformly sampled channels of group '{group}' (twin run file, {FORMAT})",
             "builtin_interfaces/Time stamp  # simulation time of the first sample",
             "uint64 first_index             # index of the first sample in the run",
             "float64 rate_hz                # sample rate [Hz]"]
    for c in channels:
        lines.append(f"{c.data.dtype.name}[] {field_name(c.name)}  # {c.name} [{c.unit}]")
    return "\n".join(lines) + "\n" + _TIME_DEF


def _ns(t: float) -> int:
    return int(round(t * 1e9))


def encode_block(stamp_ns: int, first_index: int, rate_hz: float, arrays: list[np.ndarray]) -> bytes:
    """CDR (little endian) encoding of one block message."""
    sec, nsec = divmod(stamp_ns, 1_000_000_000)
    parts = [_CDR_LE, struct.pack("<iIQd", sec, nsec, first_index, rate_hz)]
    pos = 24  # offset after the encapsulation header
    for a in arrays:
        pad = (-pos) % 4
        parts.append(b"\x00" * pad + struct.pack("<I", a.size))
        pos += pad + 4
        pad = (-pos) % a.itemsize
        parts.append(b"\x00" * pad)
        pos += pad
        raw = a.astype(a.dtype.newbyteorder("<"), copy=False).tobytes()
        parts.append(raw)
        pos += len(raw)
    return b"".join(parts)


def decode_block(data: bytes, dtypes: list[str]) -> tuple[int, int, float, list[np.ndarray]]:
    """Inverse of :func:`encode_block`: (stamp_ns, first_index, rate_hz, arrays)."""
    if data[:4] != _CDR_LE or len(data) < 28:
        raise RecordingError("block message is not little-endian CDR")
    sec, nsec, first, rate = struct.unpack_from("<iIQd", data, 4)
    pos, out = 24, []
    for dt in dtypes:
        size = _DTYPES[dt][1]
        pos += (-pos) % 4
        (n,) = struct.unpack_from("<I", data, 4 + pos)
        pos += 4
        pos += (-pos) % size
        end = pos + n * size
        if 4 + end > len(data):
            raise RecordingError("block message is truncated")
        out.append(np.frombuffer(data, dtype=np.dtype(dt).newbyteorder("<"), count=n, offset=4 + pos).astype(dt))
        pos = end
    return sec * 1_000_000_000 + nsec, first, rate, out


_HEADER_DEF = """================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
"""


def check_preview_rate(preview_rate_hz: float, rate_hz: float | None = None) -> float:
    """The rule of a preview rate [Hz]: 0 (no preview) or a finite rate > 0, at most the run's
    ``rate_hz`` when known (a preview is a block mean of full-rate samples); a one-line
    :class:`TwinError` about ``preview_rate_hz`` otherwise."""
    ok = isinstance(preview_rate_hz, (int, float, np.integer, np.floating)) and not isinstance(preview_rate_hz, bool) \
        and np.isfinite(preview_rate_hz) and preview_rate_hz >= 0
    if ok and rate_hz is not None and preview_rate_hz > rate_hz:
        ok = False
    if not ok:
        raise TwinError(("must be >= 0 Hz (0 = no preview)" if rate_hz is None else
                         f"must be 0 (no preview) or a rate up to the output rate {rate_hz:g} Hz")
                        + f", got {preview_rate_hz!r}", field="preview_rate_hz")
    return float(preview_rate_hz)


def preview_factor(rate_hz: float, preview_rate_hz: float) -> int:
    """Full-rate samples per preview sample: round(rate / preview rate), at least 1."""
    return max(1, int(round(rate_hz / preview_rate_hz)))


def preview_layout(channels: list[Channel]) -> tuple[np.dtype, str]:
    """The CDR layout of a preview message as a numpy structured dtype (one record = one whole
    message, encapsulation header included) and its ros2msg schema text.

    CDR (XCDR1, as ROS 2 writes it): every primitive aligned to its size, counted from the end of
    the 4-byte encapsulation header; the header's empty ``frame_id`` is a length of 1 and a NUL.
    """
    names = ["encapsulation", "sec", "nanosec", "frame_id_len", "frame_id"]
    formats: list[Any] = [("u1", 4), "<i4", "<u4", "<u4", "u1"]
    offsets = [0, 4, 8, 12, 16]
    pos = 13  # after the header, counted from the end of the encapsulation
    lines = [f"# One sample of every channel of a twin run file ({FORMAT}): the block mean of the full-rate",
             "# samples around header.stamp (the block's centre), see recordings/FORMAT.md",
             "std_msgs/Header header"]
    seen = {"header": "header"}
    for c in channels:
        f = field_name(c.name)
        if f in seen:
            raise RecordingError(f"channels {seen[f]} and {c.name} have the same preview field name {f!r}")
        seen[f] = c.name
        size = _DTYPES[c.data.dtype.name][1]
        pos += (-pos) % size
        names.append(f)
        formats.append(("<f4" if size == 4 else "<f8"))
        offsets.append(4 + pos)
        pos += size
        lines.append(f"{c.data.dtype.name} {f}  # {c.name} [{c.unit}]")
    dt = np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": 4 + pos})
    return dt, "\n".join(lines) + "\n" + _HEADER_DEF + _TIME_DEF


class _Preview:
    """The preview topic of a :class:`RunWriter` (see the module docstring): block means of
    ``m`` samples, one message per block, streamed chunk by chunk."""

    def __init__(self, w: Writer, run: Run, preview_rate_hz: float):
        self.w = w
        self.rate, self.t0 = run.rate_hz, run.t0
        self.m = preview_factor(run.rate_hz, preview_rate_hz)
        self.chans = list(run.channels.values())
        self.dtype, text = preview_layout(self.chans)
        sid = w.register_schema(PREVIEW_SCHEMA, "ros2msg", text.encode())
        self.cid = w.register_channel(PREVIEW_TOPIC, "cdr", sid, metadata={
            "names": ",".join(c.name for c in self.chans), "units": ",".join(c.unit for c in self.chans),
            "dtypes": ",".join(c.data.dtype.name for c in self.chans), "groups": ",".join(c.group for c in self.chans),
            "rate_hz": repr(self.rate / self.m), "samples_per_value": str(self.m), "method": "block mean",
            "stamp": "centre of the block: t0 + (k * samples_per_value + (samples_per_value - 1) / 2) / run rate"})
        self.pending: list[np.ndarray] | None = None
        self.k = 0  # preview samples written

    def add(self, chunk: Run) -> None:
        arrays = [chunk.channels[c.name].data for c in self.chans]
        if self.pending is not None:
            arrays = [np.concatenate([p, a]) for p, a in zip(self.pending, arrays)]
        nb = len(arrays[0]) // self.m
        full = nb * self.m
        self.pending = [np.array(a[full:]) for a in arrays] if full < len(arrays[0]) else None
        if nb == 0:
            return
        rec = np.zeros(nb, dtype=self.dtype)
        rec["encapsulation"] = np.frombuffer(_CDR_LE, dtype="u1")
        idx = self.k + np.arange(nb)
        stamps = np.round((self.t0 + (idx * self.m + (self.m - 1) / 2.0) / self.rate) * 1e9).astype(np.int64)
        rec["sec"], rec["nanosec"] = np.divmod(stamps, 1_000_000_000)
        rec["frame_id_len"] = 1
        for c, a in zip(self.chans, arrays):
            rec[field_name(c.name)] = a[:full].reshape(nb, self.m).mean(axis=1, dtype=np.float64)
        buf = memoryview(rec.tobytes())
        size = self.dtype.itemsize
        add = self.w.add_message
        for i in range(nb):
            st = int(stamps[i])
            add(self.cid, log_time=st, publish_time=st, sequence=self.k + i, data=buf[i * size:(i + 1) * size])
        self.k += nb


class RunWriter:
    """Streams a run, chunk by chunk, into an MCAP file (temporary file + rename): a
    :class:`twin.simulation.Sink`.

    The temporary file ``.NAME.PID.tmp`` is created at the first :meth:`write` (so a writer
    made before a run that then fails to start leaves nothing), :meth:`close` finalizes and
    renames it into place, :meth:`abort` deletes it. Use as a context manager to abort on error.
    """

    def __init__(self, path: str | Path, config: BenchConfig | None, block: int = DEFAULT_BLOCK,
                 compression: str = "none", preview_rate_hz: float = 0.0):
        self.path = Path(path)
        if compression not in _COMPRESSION:
            raise TwinError(f"must be one of {', '.join(_COMPRESSION)}, got {compression!r}", field="compression")
        self.preview_rate_hz = check_preview_rate(preview_rate_hz)  # the run's rate is known at its first block
        self._preview: _Preview | None = None
        self.compression = _COMPRESSION[compression]
        if self.path.suffix.lower() != ".mcap":
            raise TwinError(f"run files must end in .mcap, got {self.path.name}", field="path")
        if not self.path.parent.is_dir():
            raise TwinError(f"directory {self.path.parent} does not exist", field="path")
        self.tmp = temp_path(self.path)
        self.config = config
        self.block = int(block)
        self._fh = None
        self._w: Writer | None = None
        self._groups: dict[str, tuple[int, list[str]]] = {}
        self._pending: Run | None = None
        self._written = 0
        self.t0: float | None = None
        self.rate_hz: float | None = None
        self._channels: list[str] | None = None
        self._done = False

    def _open(self) -> None:
        remove_stale_temps(self.path)
        try:
            self._fh = os.fdopen(open_new(self.tmp), "wb")
        except OSError as err:
            raise TwinError(f"{self.path}: cannot write ({err.strerror})") from None
        self._w = Writer(self._fh, compression=self.compression, chunk_size=4 * 1024 * 1024)
        self._w.start(profile="", library=f"twin {__version__}")

    def _register(self, run: Run) -> None:
        self.t0, self.rate_hz = run.t0, run.rate_hz
        self._channels = list(run.channels)
        for group, names in run.groups.items():
            chans = [run.channels[n] for n in names]
            sid = self._w.register_schema(schema_name(group), "ros2msg", schema_text(group, chans).encode())
            cid = self._w.register_channel(
                TOPIC_PREFIX + group, "cdr", sid,
                metadata={"names": ",".join(names), "units": ",".join(c.unit for c in chans),
                          "dtypes": ",".join(c.data.dtype.name for c in chans)})
            self._groups[group] = (cid, names)
        if self.preview_rate_hz > 0:
            self._preview = _Preview(self._w, run, self.preview_rate_hz)

    def write(self, chunk: Run) -> None:
        """Append the samples of ``chunk`` (the next consecutive piece of the run)."""
        if self._done:
            raise TwinError(f"{self.path}: write after close or abort")
        if self._w is None:
            self._open()
        if self._channels is None:
            self._register(chunk)
        elif list(chunk.channels) != self._channels or chunk.rate_hz != self.rate_hz:
            raise RecordingError("chunk does not match the channels or rate of the run being written")
        for c in chunk.channels.values():
            if c.data.dtype.name not in _DTYPES:
                raise RecordingError(f"channel {c.name}: dtype {c.data.dtype} not storable (float32/float64)")
        run = chunk if self._pending is None else Run.concat([self._pending, chunk])
        full = (run.n // self.block) * self.block
        try:
            if self._preview is not None:
                self._preview.add(chunk)
            self._emit(run.slice(0, full))
        except OSError as err:
            raise TwinError(f"{self.path}: cannot write ({err.strerror})") from None
        # keep a copy of the incomplete block only, not a view that pins the whole chunk
        self._pending = Run.concat([run.slice(full, run.n)]) if full < run.n else None

    def _emit(self, run: Run) -> None:
        for i in range(0, run.n, self.block):
            idx = self._written + i
            stamp = _ns(self.t0 + idx / self.rate_hz)
            for group, (cid, names) in self._groups.items():
                arrays = [np.ascontiguousarray(run.channels[n].data[i:i + self.block]) for n in names]
                self._w.add_message(cid, log_time=stamp, publish_time=stamp, sequence=idx // self.block,
                                    data=encode_block(stamp, idx, self.rate_hz, arrays))
        self._written += run.n

    def close(self, meta: dict[str, Any] | None = None, summary: dict[str, Any] | None = None,
              extra_metadata: dict[str, dict[str, str]] | None = None) -> Path:
        """Flush, write the metadata records, finish and rename into place.

        ``extra_metadata``: further metadata records by name (string keys and values), e.g.
        ``twin.recording`` of a bench recording (``twin/recording.py``).
        """
        if self._done:
            raise TwinError(f"{self.path}: close after close or abort")
        try:
            return self._finish(meta, summary, extra_metadata)
        except OSError as err:
            self.abort()
            raise TwinError(f"{self.path}: cannot write ({err.strerror or err})") from None

    def _finish(self, meta, summary, extra_metadata) -> Path:
        if self._w is None:
            self._open()  # a run with no chunks: a valid file with metadata only
        if self._pending is not None and self._pending.n:
            self._emit(self._pending)
            self._pending = None
        for name, record in (extra_metadata or {}).items():
            self._w.add_metadata(name, {str(k): str(v) for k, v in record.items()})
        if self.config is not None:
            self._w.add_metadata("twin.config", {"toml": self.config.to_toml()})
        self._w.add_metadata("twin.run", {
            "format": FORMAT, "t0": repr(float(self.t0 or 0.0)), "rate_hz": repr(float(self.rate_hz or 0.0)),
            "n": str(self._written), "channels": ",".join(self._channels or []),
            "meta": json_text(meta or {}, indent=None, sort_keys=True)})
        if summary is not None:
            self._w.add_metadata("twin.summary", {"json": json_text(summary, indent=None, sort_keys=True)})
        self._w.finish()
        self._fh.close()
        try:
            check_not_link(self.path)
            os.replace(self.tmp, self.path)
        except OSError as err:
            raise TwinError(f"{self.path}: cannot write ({err.strerror})") from None
        self._done = True
        return self.path

    def abort(self) -> None:
        """Drop the temporary file (on error); an existing file at ``path`` is untouched."""
        if not self._done:
            self._done = True
            try:
                if self._fh is not None:
                    self._fh.close()
            except OSError:
                pass  # the buffered rest cannot be written either (a full disk): the file is dropped anyway;
                # raising here replaced the error naming the file with a bare one naming none
            finally:
                self.tmp.unlink(missing_ok=True)

    def __enter__(self) -> "RunWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None:
            self.abort()
        elif not self._done:
            self.abort()


def write_run(path: str | Path, run: Run, summary: dict[str, Any] | None = None,
              block: int = DEFAULT_BLOCK, extra_metadata: dict[str, dict[str, str]] | None = None,
              preview_rate_hz: float = 0.0) -> Path:
    """Write a whole run to ``path`` (temporary file + rename); ``extra_metadata`` as in
    :meth:`RunWriter.close`; a preview topic at ``preview_rate_hz`` (0: none)."""
    with RunWriter(path, run.config, block=block, preview_rate_hz=preview_rate_hz) as w:
        w.write(run)
        return w.close(run.meta, summary, extra_metadata)


def read_metadata(path: str | Path) -> dict[str, dict[str, str]]:
    """All metadata records of an MCAP file by name."""
    p = _check_path(path)
    try:
        with open(p, "rb") as fh:
            return {m.name: dict(m.metadata) for m in make_reader(fh).iter_metadata()}
    except _UNREADABLE as err:
        raise RecordingError(f"{p}: not a readable MCAP file ({type(err).__name__}: {err})") from None


def _check_path(path: str | Path) -> Path:
    import os
    import stat

    from twin.util import show

    p = Path(path)
    try:
        st = os.stat(p)
    except OSError:
        raise RecordingError(f"{show(p)}: no such file") from None
    if not stat.S_ISREG(st.st_mode):
        raise RecordingError(f"{show(p)}: not a regular file (a folder, pipe or device)")
    if st.st_size < 8 + 8:  # magic, header and footer: an MCAP cut to its magic bytes holds nothing
        raise RecordingError(f"{show(p)}: not a readable MCAP file ({st.st_size} bytes, truncated)")
    return p


def _field(p: Path, info: dict[str, str], key: str, kind: type, lo: float, hi: float) -> Any:
    """A number of a run file's 'twin.run' record, checked (one line naming the field otherwise)."""
    import math

    raw = info.get(key)
    try:
        v = kind(raw)
    except (TypeError, ValueError):
        raise RecordingError(f"{p}: metadata twin.run.{key} must be a number, got {raw!r}") from None
    if not (math.isfinite(v) and lo <= v <= hi):
        raise RecordingError(f"{p}: metadata twin.run.{key} = {raw!r} lies outside [{lo:g}, {hi:g}]")
    return v


def _channel_meta(p: Path, topic: str, md: dict[str, str]) -> tuple[list[str], list[str], list[str]]:
    """Names, units and dtypes of a channel's metadata: all present and of one length."""
    missing = [k for k in ("names", "units", "dtypes") if not md.get(k)]
    if missing:
        raise RecordingError(f"{p}: topic {topic} lacks its channel metadata {', '.join(missing)}")
    names, units, dtypes = md["names"].split(","), md["units"].split(","), md["dtypes"].split(",")
    if not len(names) == len(units) == len(dtypes) or len(set(names)) != len(names) or not all(names):
        raise RecordingError(f"{p}: topic {topic} metadata names {len(names)} channels, {len(units)} units and "
                             f"{len(dtypes)} types (they must agree, names unique and not empty)")
    return names, units, dtypes


def read_run(path: str | Path, groups: Iterable[str] | None = None) -> Run:
    """Read a run file back (all groups, or only ``groups``); bit-identical to what was written."""
    p = _check_path(path)
    try:
        with open(p, "rb") as fh:
            reader = make_reader(fh, validate_crcs=True)
            meta_records = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
            if "twin.run" not in meta_records:
                raise RecordingError(f"{p}: no 'twin.run' metadata record: not a twin run file "
                                     "(bench recordings are imported with 'twin import')")
            info = meta_records["twin.run"]
            if info.get("format") != FORMAT:
                raise RecordingError(f"{p}: unsupported run format {info.get('format')!r}, expected {FORMAT}")
            n = _field(p, info, "n", int, 0, 2**40)
            rate = _field(p, info, "rate_hz", float, 1e-6, 1e9)
            t0 = _field(p, info, "t0", float, -1e12, 1e12)
            wanted = None if groups is None else {TOPIC_PREFIX + g for g in groups}
            summary = reader.get_summary()
            topics = {c.topic: c for c in summary.channels.values()} if summary else {}
            if wanted is not None:
                missing = wanted - set(topics)
                if missing:
                    raise RecordingError(f"{p}: no groups {sorted(m[len(TOPIC_PREFIX):] for m in missing)}")
            elif topics:  # the full-rate topics only (not the preview)
                wanted = {t for t in topics if t.startswith(TOPIC_PREFIX)}
            blocks: dict[str, list[list[np.ndarray]]] = {}
            expected_first: dict[str, int] = {}
            chan_meta: dict[str, dict[str, str]] = {}
            for _schema, channel, message in reader.iter_messages(topics=wanted, log_time_order=False):
                topic = channel.topic
                if not topic.startswith(TOPIC_PREFIX):
                    continue
                md = chan_meta.setdefault(topic, dict(channel.metadata))
                _, _, dtypes = _channel_meta(p, topic, md)
                _, first, _, arrays = decode_block(message.data, dtypes)
                if len(arrays) != len(dtypes) or len({len(a) for a in arrays}) > 1:
                    raise RecordingError(f"{p}: topic {topic} holds {len(arrays)} arrays for {len(dtypes)} channels")
                if first != expected_first.get(topic, 0):
                    raise RecordingError(f"{p}: topic {topic} has a gap or is out of order at sample {first}")
                expected_first[topic] = first + len(arrays[0])
                blocks.setdefault(topic, []).append(arrays)
    except TwinError:
        raise
    except (*_UNREADABLE, OSError) as err:
        raise RecordingError(f"{p}: corrupt or truncated MCAP file ({type(err).__name__}: {err})") from None
    order = info.get("channels", "").split(",") if info.get("channels") else None
    chans: dict[str, Channel] = {}
    for topic, md in chan_meta.items():
        names, units, _ = _channel_meta(p, topic, md)
        if expected_first[topic] != n:
            raise RecordingError(f"{p}: topic {topic} holds {expected_first[topic]} samples, expected {n} (truncated?)")
        for k, (name, unit) in enumerate(zip(names, units)):
            data = np.concatenate([b[k] for b in blocks[topic]])
            chans[name] = Channel(name, unit, topic[len(TOPIC_PREFIX):], data)
    if order:
        chans = {k: chans[k] for k in order if k in chans}
    stored = meta_records.get("twin.config", {})
    if "twin.config" in meta_records and "toml" not in stored:
        raise RecordingError(f"{p}: metadata twin.config holds no 'toml' entry")
    try:
        config = config_from_toml(stored["toml"]) if "twin.config" in meta_records else None
    except TwinError as err:
        raise RecordingError(f"{p}: stored configuration: {err}") from None
    try:
        meta = json.loads(info.get("meta", "{}"))
    except ValueError as err:
        raise RecordingError(f"{p}: metadata twin.run.meta is not JSON ({err})") from None
    if not isinstance(meta, dict):
        raise RecordingError(f"{p}: metadata twin.run.meta must be a JSON object, got {type(meta).__name__}")
    return Run(t0, rate, chans, config, meta)


def read_preview(path: str | Path) -> tuple[np.ndarray, Run] | None:
    """The preview topic of a run file: (stamps [ns], the preview as a :class:`Run` at the preview
    rate whose ``t0`` is the first stamp), or None when the file has none."""
    p = _check_path(path)
    try:
        with open(p, "rb") as fh:
            reader = make_reader(fh, validate_crcs=True)
            summary = reader.get_summary()
            chans = [c for c in (summary.channels.values() if summary else ()) if c.topic == PREVIEW_TOPIC]
            if not chans:
                return None
            md = dict(chans[0].metadata)
            names, units, dtypes = (md[k].split(",") for k in ("names", "units", "dtypes"))
            groups = md.get("groups", "").split(",") if md.get("groups") else ["preview"] * len(names)
            cols = [Channel(n, u, g, np.zeros(0, dtype=d)) for n, u, g, d in zip(names, units, groups, dtypes)]
            dt, _ = preview_layout(cols)
            data = [m.data for _s, _c, m in reader.iter_messages(topics=[PREVIEW_TOPIC], log_time_order=True)]
    except (*_UNREADABLE, OSError) as err:
        raise RecordingError(f"{p}: corrupt or truncated MCAP file ({type(err).__name__}: {err})") from None
    if any(len(d) != dt.itemsize for d in data):
        raise RecordingError(f"{p}: preview message of an unexpected size")
    rec = np.frombuffer(b"".join(data), dtype=dt)
    stamps = rec["sec"].astype(np.int64) * 1_000_000_000 + rec["nanosec"]
    out = {c.name: Channel(c.name, c.unit, c.group, rec[field_name(c.name)].astype(c.data.dtype)) for c in cols}
    t0 = float(stamps[0]) / 1e9 if stamps.size else 0.0
    return stamps, Run(t0, float(md["rate_hz"]), out, None, {"preview": md})


def read_summary(path: str | Path) -> dict[str, Any] | None:
    """The summary stored in a run file, if any."""
    md = read_metadata(path)
    if "twin.summary" not in md:
        return None
    try:
        out = json.loads(md["twin.summary"].get("json", ""))
    except ValueError as err:
        raise RecordingError(f"{path}: metadata twin.summary is not JSON ({err})") from None
    if not isinstance(out, dict):
        raise RecordingError(f"{path}: metadata twin.summary must be a JSON object")
    return out
