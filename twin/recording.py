"""Bench recordings: layout, validation, and import from the DAQ's plain exports.

A bench recording is a twin run file (``twin.mcapfile``, format ``twin-run/1``, read with
:func:`~twin.mcapfile.read_run`) holding the raw DAQ channels in group ``daq``:

==================  =======  ==========================================================
channel             unit     content
==================  =======  ==========================================================
``volt_AC1..6``     V        accelerometer output voltages (required)
``encoder_counts``  count    crank encoder, 4× quadrature counts, whole counts as float64,
                             continuous over turns (required; zero count = crank along −y)
``motor_command``   V        motor speed command, ±10 V ↔ ±1000 rpm (optional)
==================  =======  ==========================================================

plus the ``twin.config`` record (the bench configuration of the test: clearances, orientation,
drive, instrumentation) and a ``twin.recording`` metadata record with keys ``format``
(``twin-recording/1``) and ``json``: sample rate, calibration data (:class:`~twin.instrument.
calibration.Calibration`), free-text notes, source file and its SHA-256, whether it is synthetic
(and how it was made), and the repairs applied on import. One file holds everything.

Validation (:func:`validate_daq`, run on import and on every read for replay) gives a one-line
:class:`~twin.errors.RecordingError` for: a missing channel, an unknown unit, NaN/infinite
samples (or, with ``nan="interpolate"``, a reported repair of gaps up to
:data:`MAX_NAN_GAP` samples), a sample rate different from ``instrumentation.daq_rate_hz``,
non-integer encoder counts, and encoder jumps the crank cannot make (short glitches are
repaired and reported, steps are errors). Table imports also check that the time column is
strictly increasing and regular, in seconds, and that it agrees with ``rate_hz``; that NPZ columns
are 1-D arrays of real numbers (int, uint, float: no bool, complex, object/pickle, string or date
types) of one length and CSV files UTF-8 text with one number per header column on every line
(the error names the line and column); that imported volts lie in the DAQ's input range
(``instrumentation.daq_range``, the motor command in ±10 V) and counts within ±2**53; and that
``mapping``, ``rate_hz``, ``zero_g_v`` (inside the sensor's output range) and ``encoder_modulus``
make sense. Every such error is one :class:`RecordingError` line naming the file or argument.
"""

from __future__ import annotations

import json
import math
import re
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from twin.config import ACCELEROMETERS, BenchConfig
from twin.errors import RecordingError
from twin.instrument.calibration import Calibration, calibrate_static, calibration_pose_g, nominal_sensitivities
from twin.instrument.chain import DAQ_GROUP
from twin.instrument.encoder import check_counts, max_counts_per_sample, unwrap_counts
from twin.run import Channel, Run
from twin.util import json_text

RECORDING_FORMAT = "twin-recording/1"
RECORDING_RECORD = "twin.recording"
VOLT_CHANNELS: tuple[str, ...] = tuple(f"volt_{a}" for a in ACCELEROMETERS)
REQUIRED_CHANNELS: tuple[str, ...] = VOLT_CHANNELS + ("encoder_counts",)
OPTIONAL_CHANNELS: tuple[str, ...] = ("motor_command",)
#: Unit each DAQ channel is stored in.
CHANNEL_UNITS: dict[str, str] = {**{c: "V" for c in VOLT_CHANNELS}, "encoder_counts": "count", "motor_command": "V"}
#: Units accepted on import: spelling -> (stored unit, factor to it).
UNIT_ALIASES: dict[str, tuple[str, float]] = {
    "V": ("V", 1.0), "v": ("V", 1.0), "volt": ("V", 1.0), "volts": ("V", 1.0),
    "mV": ("V", 1e-3), "mv": ("V", 1e-3),
    "count": ("count", 1.0), "counts": ("count", 1.0), "cnt": ("count", 1.0), "cts": ("count", 1.0),
}
#: Longest NaN gap repaired by interpolation with ``nan="interpolate"`` [samples].
MAX_NAN_GAP = 16
#: Relative tolerance of the sample rate against the configuration and of time regularity.
RATE_TOL = 1e-4
#: how closely a stored recording's rate must match the configured DAQ rate (and ``rate_hz`` the
#: time column) [-]: replay and identify compare the two to this precision
STORED_RATE_TOL = 1e-6


@dataclass
class RecordingInfo:
    """The ``twin.recording`` metadata record of a bench recording.

    Attributes:
        rate_hz: DAQ sample rate [Hz].
        source_file: file the recording was imported from (or made by).
        source_sha256: SHA-256 of that file ("" if none).
        notes: free text (operator, date, test id, run number, ...).
        calibration: static calibration (zero-g offsets, sensitivities), or None.
        synthetic: True for recordings made by the twin (sensor chain on a simulated run).
        created_by: the program that wrote the file.
        repairs: one line per repair applied on import (NaN gaps, encoder glitches, unit scaling).
        extra: anything else (e.g. engine and seed of a synthetic recording).
    """

    rate_hz: float
    source_file: str = ""
    source_sha256: str = ""
    notes: str = ""
    calibration: Calibration | None = None
    synthetic: bool = False
    created_by: str = ""
    repairs: list[str] = field(default_factory=list)
    extra: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {"rate_hz": self.rate_hz, "source_file": self.source_file, "source_sha256": self.source_sha256,
                "notes": self.notes, "calibration": self.calibration.to_dict() if self.calibration else None,
                "synthetic": self.synthetic, "created_by": self.created_by, "repairs": list(self.repairs),
                "extra": self.extra}

    def to_record(self) -> dict[str, str]:
        return {"format": RECORDING_FORMAT, "json": json_text(self.to_dict(), indent=None, sort_keys=True)}

    @classmethod
    def from_record(cls, record: Mapping[str, str], where: str = "") -> "RecordingInfo":
        if record.get("format") != RECORDING_FORMAT:
            raise RecordingError(f"{where}: unsupported recording format {record.get('format')!r}, "
                                 f"expected {RECORDING_FORMAT}")
        try:
            d = json.loads(record["json"])
            cal = Calibration.from_dict(d["calibration"]) if d.get("calibration") else None
            return cls(float(d["rate_hz"]), str(d.get("source_file", "")), str(d.get("source_sha256", "")),
                       str(d.get("notes", "")), cal, bool(d.get("synthetic", False)), str(d.get("created_by", "")),
                       [str(r) for r in d.get("repairs", [])], dict(d.get("extra", {})))
        except (KeyError, ValueError, TypeError) as err:
            raise RecordingError(f"{where}: malformed '{RECORDING_RECORD}' record ({type(err).__name__}: {err})") from None


# ------------------------------------------------------------------------ validation
#: how far beyond its supply rails a recorded accelerometer voltage may read (ADC noise, offsets) [V]
RAIL_TOL_V = 0.1
#: fastest crank of the torque drive [rpm]: no speed command bounds it, so drive.crank_rpm's range does
TORQUE_DRIVE_MAX_CRANK_RPM = 6000.0


def _max_crank_rpm(cfg: BenchConfig) -> float:
    """Fastest crank speed the drive commands (±1000 motor rpm, a faster drive.crank_rpm; torque drive: above) [rpm]."""
    if cfg.drive.mode == "torque":
        return TORQUE_DRIVE_MAX_CRANK_RPM
    return max(1000.0 / cfg.drive.belt_ratio, abs(cfg.drive.crank_rpm))


def encoder_max_step(cfg: BenchConfig, rate_hz: float) -> float:
    """Plausibility limit of the encoder count change per sample: twice the count rate of the
    fastest commandable crank speed (the belt can slip, never overdrive) [counts/sample]."""
    return 2.0 * max_counts_per_sample(cfg.instrumentation.encoder_counts_per_rev, rate_hz, _max_crank_rpm(cfg))


def _fill_nan(x: np.ndarray, name: str, rate_hz: float, repairs: list[str]) -> np.ndarray:
    bad = ~np.isfinite(x)
    if not bad.any():
        return x
    if bad[0] or bad[-1]:
        i = 0 if bad[0] else x.size - 1
        raise RecordingError(f"{name}: NaN or infinite sample at the {'start' if i == 0 else 'end'} of the "
                             "recording (cannot interpolate); trim the recording")
    idx = np.flatnonzero(bad)
    starts = idx[np.r_[True, np.diff(idx) > 1]]
    ends = idx[np.r_[np.diff(idx) > 1, True]]
    longest = int(np.max(ends - starts + 1))
    if longest > MAX_NAN_GAP:
        k = int(starts[np.argmax(ends - starts)])
        raise RecordingError(f"{name}: a gap of {longest} NaN samples at sample {k} (t = {k / rate_hz:.6f} s) "
                             f"is longer than the {MAX_NAN_GAP} samples that can be interpolated")
    good = np.flatnonzero(~bad)
    y = x.copy()
    y[idx] = np.interp(idx, good, x[good])
    repairs.append(f"{name}: interpolated {idx.size} NaN samples in {starts.size} gap(s) "
                   f"(longest {longest}, first at t = {starts[0] / rate_hz:.6f} s)")
    return y


def validate_daq(run: Run, cfg: BenchConfig, nan: str = "error", encoder_repair: bool = True,
                 encoder_modulus: int | None = None, where: str = "recording") -> tuple[Run, list[str]]:
    """Check a bench recording's ``daq`` channels; return the (repaired) run and the repairs made.

    Args:
        run: the recording (channels named as in the module docstring).
        cfg: its bench configuration (sample rate, encoder resolution, drive limits).
        nan: "error" (default) or "interpolate" (gaps up to :data:`MAX_NAN_GAP` samples).
        encoder_repair: repair short encoder glitches (reported) instead of failing.
        encoder_modulus: if the counter wraps (e.g. 2**32, or counts per turn), unwrap first.
        where: name used in messages (file name).
    """
    if nan not in ("error", "interpolate"):
        raise ValueError(f"nan must be 'error' or 'interpolate', got {nan!r}")
    missing = [c for c in REQUIRED_CHANNELS if c not in run]
    if missing:
        raise RecordingError(f"{where}: missing channel(s) {', '.join(missing)} "
                             f"(a bench recording needs {', '.join(REQUIRED_CHANNELS)})")
    if run.n < 2:
        raise RecordingError(f"{where}: holds {run.n} samples; a recording needs at least 2")
    rate = cfg.instrumentation.daq_rate_hz
    if abs(run.rate_hz - rate) > RATE_TOL * rate:
        raise RecordingError(f"{where}: sampled at {run.rate_hz:g} Hz but instrumentation.daq_rate_hz is "
                             f"{rate:g} Hz (wrong sample rate; if the DAQ really ran at {run.rate_hz:g} Hz, set "
                             f"instrumentation.daq_rate_hz = {run.rate_hz:g})")
    repairs: list[str] = []
    chans: dict[str, Channel] = {}
    for name in REQUIRED_CHANNELS + OPTIONAL_CHANNELS:
        if name not in run:
            continue
        ch = run.channels[name]
        if ch.unit != CHANNEL_UNITS[name]:
            raise RecordingError(f"{where}: channel {name} is in unit {ch.unit!r}; expected {CHANNEL_UNITS[name]!r} "
                                 "(unknown or wrong unit)")
        x = np.asarray(ch.data, dtype=np.float64)
        if name == "encoder_counts":
            if not np.all(np.isfinite(x)):
                i = int(np.flatnonzero(~np.isfinite(x))[0])
                raise RecordingError(f"{where}: encoder_counts has a NaN or infinite sample at sample {i} "
                                     f"(t = {run.t0 + i / run.rate_hz:.6f} s); counts cannot be interpolated")
            if cfg.instrumentation.encoder_quantization and np.any(x != np.round(x)):
                i = int(np.flatnonzero(x != np.round(x))[0])
                raise RecordingError(f"{where}: encoder_counts holds a non-integer count {x[i]!r} at sample {i}: "
                                     "not quadrature counts (unit?)")
            if encoder_modulus is not None:
                check_encoder_modulus(encoder_modulus)
                m = int(encoder_modulus)
                step = encoder_max_step(cfg, run.rate_hz)
                if m <= 2 * step:
                    raise RecordingError(f"{m} is too small: at {run.rate_hz:g} Hz the crank can move "
                                         f"{step:.3g} counts per sample, so a counter wrapping at {m} cannot be "
                                         f"unwrapped (needs more than {2 * step:.3g})", field="encoder_modulus")
                if np.max(np.abs(x)) >= m:
                    i = int(np.argmax(np.abs(x) >= m))
                    raise RecordingError(f"{where}: encoder_counts reaches {x[i]:.0f} at sample {i}, not below "
                                         f"`encoder_modulus` {m}: the counter does not wrap at {m}")
                x = unwrap_counts(x, m)
                repairs.append(f"encoder_counts: unwrapped a counter of modulus {int(encoder_modulus)}")
            try:
                x, rep = check_counts(x, run.rate_hz, encoder_max_step(cfg, run.rate_hz), repair=encoder_repair)
            except RecordingError as err:
                raise RecordingError(f"{where}: {err}") from None
            repairs.extend(rep.messages)
        elif not np.all(np.isfinite(x)):
            if nan == "error":
                i = int(np.flatnonzero(~np.isfinite(x))[0])
                raise RecordingError(f"{where}: channel {name} has a NaN or infinite sample at sample {i} "
                                     f"(t = {run.t0 + i / run.rate_hz:.6f} s); import with `nan='interpolate'` to "
                                     f"interpolate gaps of up to {MAX_NAN_GAP} samples")
            x = _fill_nan(x, name, run.rate_hz, repairs)
        if name.startswith("volt_AC") and x.size:
            # an accelerometer's output cannot leave its supply rails (ADC noise: a 0.1 V margin)
            top = cfg.instrumentation.supply_v
            lo, hi = float(np.nanmin(x)), float(np.nanmax(x))
            if lo < -RAIL_TOL_V or hi > top + RAIL_TOL_V:
                bad = lo if lo < -RAIL_TOL_V else hi
                raise RecordingError(f"{where}: channel {name} reaches {bad:.4g} V, outside the sensor's output "
                                     f"rails [0, {top:g}] V (instrumentation.supply_v; unit or gain wrong?)")
        chans[name] = Channel(name, CHANNEL_UNITS[name], DAQ_GROUP, x)
    return Run(run.t0, run.rate_hz, chans, cfg, dict(run.meta)), repairs


# -------------------------------------------------------------------------- files
def write_recording(path: str | Path, run: Run, info: RecordingInfo) -> Path:
    """Write a validated recording (``daq`` group + ``twin.config`` + ``twin.recording``)."""
    from twin.mcapfile import write_run

    if run.config is None:
        raise RecordingError("write_recording: the run carries no bench configuration")
    daq, _ = validate_daq(run, run.config, where=str(path))
    extra = {RECORDING_RECORD: info.to_record()}
    return write_run(path, daq, extra_metadata=extra)


def read_recording(path: str | Path, nan: str = "error") -> tuple[Run, RecordingInfo, list[str]]:
    """Read and validate a bench recording: (daq run with its configuration, info, repairs)."""
    from twin.mcapfile import read_metadata, read_run

    p = Path(path)
    records = read_metadata(p)
    if RECORDING_RECORD not in records:
        raise RecordingError(f"{p}: no '{RECORDING_RECORD}' record: not a bench recording "
                             "(convert DAQ exports with 'twin import')")
    info = RecordingInfo.from_record(records[RECORDING_RECORD], str(p))
    try:
        run = read_run(p, groups=[DAQ_GROUP])
    except RecordingError as err:
        msg = str(err)
        raise RecordingError(msg if msg.startswith(str(p)) else f"{p}: {msg}") from None
    if run.config is None:
        raise RecordingError(f"{p}: no 'twin.config' record: the bench configuration of the test is unknown")
    run, repairs = validate_daq(run, run.config, nan=nan, where=str(p))
    return run, info, repairs


# ------------------------------------------------------------------------ importers
_HEADER_UNIT = re.compile(r"^\s*(?P<name>[^\[\(]+?)\s*(?:[\[\(]\s*(?P<unit>[^\]\)]*)\s*[\]\)])?\s*$")


def parse_mapping(items: list[str] | None) -> dict[str, tuple[str, str | None]]:
    """``TARGET=SOURCE[:UNIT]`` items (comma-separated or repeated) → {target: (source, unit)}."""
    out: dict[str, tuple[str, str | None]] = {}
    for item in items or []:
        for part in item.split(","):
            part = part.strip()
            if not part:
                continue
            if "=" not in part:
                raise RecordingError(f"expects TARGET=SOURCE[:UNIT], got {part!r}", field="mapping")
            target, src = (s.strip() for s in part.split("=", 1))
            unit = None
            if ":" in src:
                src, unit = (s.strip() for s in src.rsplit(":", 1))
                if not unit:
                    raise RecordingError(f"empty unit after ':' in {part!r}; give TARGET=SOURCE:UNIT or "
                                         "leave out ':'", field="mapping")
            allowed = REQUIRED_CHANNELS + OPTIONAL_CHANNELS + ("t",)
            if target not in allowed:
                raise RecordingError(f"unknown target channel {target!r}; allowed: {', '.join(allowed)}", field="mapping")
            if not src:
                raise RecordingError(f"empty source column for {target!r}", field="mapping")
            if target in out:
                raise RecordingError(f"{target} is mapped twice ({out[target][0]!r} and {src!r}); give it once",
                                     field="mapping")
            out[target] = (src, unit)
    return out


#: dtype kinds accepted in a table column: signed and unsigned integers, floats (real numbers only).
_NUMERIC_KINDS = "iuf"
_KIND_NAMES = {"b": "boolean", "c": "complex", "O": "Python object", "U": "string", "S": "bytes",
               "M": "datetime", "m": "timedelta", "V": "structured/void"}
_ALLOWED_COLUMNS = "allowed: 1-D arrays of real numbers (int, uint or float)"


def _bad_line(path: Path, delim: str, names: list[str], err: Exception) -> RecordingError:
    """The first line of a CSV export that numpy could not read, located and named (error path only:
    numpy's own row numbers skip comment lines and are 0-based)."""
    n = len(names)
    try:
        with open(path, "rb") as fh:
            for lineno, raw in enumerate(fh, 1):
                try:
                    line = raw.decode("utf-8-sig" if lineno == 1 else "utf-8")
                except UnicodeDecodeError as uerr:
                    return RecordingError(f"{path}: line {lineno} is not UTF-8 text (byte 0x{raw[uerr.start]:02x}); "
                                          "export the table as UTF-8 CSV")
                if lineno == 1:
                    continue
                text = line.split("#", 1)[0].strip()
                if not text:
                    continue
                cells = text.split(delim)
                if len(cells) != n:
                    return RecordingError(f"{path}: line {lineno} has {len(cells)} fields but the header names {n} "
                                          f"columns (delimiter {delim!r}); every row needs one value per column")
                for i, cell in enumerate(cells):
                    try:
                        float(cell)
                    except ValueError:
                        return RecordingError(f"{path}: line {lineno}, column {i + 1} ({names[i]!r}): {cell.strip()[:40]!r} "
                                              "is not a number (allowed: decimal numbers with '.', nan, inf)")
    except OSError as oerr:
        return RecordingError(f"{path}: cannot read ({oerr.strerror or oerr})")
    return RecordingError(f"{path}: unreadable data ({str(err).splitlines()[0] if str(err) else type(err).__name__})")


def _read_csv(path: Path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    try:
        with open(path, "rb") as fh:
            head = fh.read(1 << 16)
        if b"\x00" in head:
            raise RecordingError(f"{path}: binary content (NUL bytes), not a CSV text file")
        with open(path, "r", encoding="utf-8-sig") as fh:
            header = fh.readline()
            first = ""
            for line in fh:  # first data line: blank and '#' comment lines are skipped, as numpy does
                if line.split("#", 1)[0].strip():
                    first = line
                    break
    except UnicodeDecodeError as err:
        raise RecordingError(f"{path}: not UTF-8 text (byte 0x{err.object[err.start]:02x} in the first lines); "
                             "a CSV export must be UTF-8 text with a header row") from None
    except OSError as err:
        raise RecordingError(f"{path}: cannot read ({err.strerror or err})") from None
    if not header.strip():
        raise RecordingError(f"{path}: empty file (a CSV export needs a header row and data rows)")
    delim = max((",", ";", "\t"), key=header.count)
    if header.count(delim) == 0:
        delim = ","
    names, units = [], {}
    for raw in header.rstrip("\r\n").split(delim):
        m = _HEADER_UNIT.match(raw)
        name = (m.group("name") if m else raw).strip().strip('"')
        if m and m.group("unit"):
            units[name] = m.group("unit").strip()
        names.append(name)
    for i, name in enumerate(names):
        if name in names[:i]:
            raise RecordingError(f"{path}: column name {name!r} appears twice in the header (columns "
                                 f"{names.index(name) + 1} and {i + 1}); column names must be unique")
    if not first:
        raise RecordingError(f"{path}: no data rows after the header")
    try:
        data = np.loadtxt(path, delimiter=delim, skiprows=1, ndmin=2, dtype=np.float64, encoding="utf-8-sig")
    except ValueError as err:  # includes UnicodeDecodeError
        raise _bad_line(path, delim, names, err) from None
    except OSError as err:
        raise RecordingError(f"{path}: cannot read ({err.strerror or err})") from None
    if data.shape[1] != len(names):
        raise RecordingError(f"{path}: the data rows have {data.shape[1]} fields but the header names {len(names)} "
                             f"columns (delimiter {delim!r})")
    return {n: data[:, i] for i, n in enumerate(names)}, units


def _check_column(path: Path, name: str, v: Any) -> np.ndarray:
    """An NPZ column: a 1-D array of real numbers, else a one-line error naming it."""
    if isinstance(v, bytes):  # a member that is not a .npy array (np.load returns its raw bytes)
        raise RecordingError(f"{path}: member {name!r} is not a numpy array (.npy); {_ALLOWED_COLUMNS}")
    v = np.asarray(v)
    if v.dtype.kind not in _NUMERIC_KINDS:
        what = _KIND_NAMES.get(v.dtype.kind, str(v.dtype))
        raise RecordingError(f"{path}: column {name!r} holds {what} values (dtype {v.dtype}); {_ALLOWED_COLUMNS}")
    if v.ndim != 1:
        raise RecordingError(f"{path}: column {name!r} has shape {v.shape}, not 1-D; {_ALLOWED_COLUMNS}")
    return v


def _read_npz(path: Path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    try:
        with open(path, "rb") as fh:
            magic = fh.read(6)
    except OSError as err:
        raise RecordingError(f"{path}: cannot read ({err.strerror or err})") from None
    if not magic:
        raise RecordingError(f"{path}: empty file (a .npz export is a zip archive of named 1-D arrays)")
    if magic.startswith(b"\x93NUMPY"):
        raise RecordingError(f"{path}: a single .npy array, not a .npz archive of named columns (np.savez)")
    if not magic.startswith((b"PK\x03\x04", b"PK\x05\x06")):
        raise RecordingError(f"{path}: not a .npz file (no zip archive signature); write it with np.savez")
    arrays: dict[str, Any] = {}
    unreadable = (OSError, ValueError, EOFError, KeyError, NotImplementedError, zipfile.BadZipFile, zlib.error)
    try:  # our own file object: np.load leaks its own when the zip directory is unreadable
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            for k in z.files:
                try:
                    arrays[k] = z[k]
                except ValueError as err:
                    if "allow_pickle" in str(err):
                        raise RecordingError(f"{path}: column {k!r} holds Python objects (pickled, not loaded); "
                                             f"{_ALLOWED_COLUMNS}") from None
                    raise RecordingError(f"{path}: column {k!r} is unreadable ({err})") from None
                except unreadable as err:
                    raise RecordingError(f"{path}: column {k!r} is unreadable ({type(err).__name__}: {err}); "
                                         "the file is truncated or corrupt") from None
    except unreadable as err:
        raise RecordingError(f"{path}: not a readable .npz file ({type(err).__name__}: {err})") from None
    units: dict[str, str] = {}
    if "units" in arrays:
        try:
            units = {str(k): str(v) for k, v in json.loads(str(arrays.pop("units"))).items()}
        except (ValueError, AttributeError) as err:
            raise RecordingError(f"{path}: entry 'units' must be a JSON object string ({err})") from None
    if not arrays:
        raise RecordingError(f"{path}: holds no columns")
    cols = {k: _check_column(path, k, v) for k, v in arrays.items()}
    lengths = {k: v.size for k, v in cols.items()}
    first = next(iter(lengths))
    for k, n in lengths.items():
        if n != lengths[first]:
            raise RecordingError(f"{path}: column {k!r} has {n} rows but {first!r} has {lengths[first]}; "
                                 "all columns need the same length")
    return cols, units


def read_table(path: str | Path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """Columns and header units of a DAQ export (``.csv`` with a header row, or ``.npz`` of named 1-D
    arrays of real numbers). Anything else is a one-line :class:`RecordingError` naming the file."""
    p = Path(path)
    if p.is_dir():
        raise RecordingError(f"{p}: is a directory; give a .csv or .npz export file")
    if not p.exists():
        raise RecordingError(f"{p}: no such file")
    if not p.is_file():
        raise RecordingError(f"{p}: not a regular file; give a .csv or .npz export file")
    if p.suffix.lower() == ".csv":
        return _read_csv(p)
    if p.suffix.lower() == ".npz":
        return _read_npz(p)
    raise RecordingError(f"{p}: unsupported export format {p.suffix!r}; allowed: .csv (header row) or .npz")


def _time_base(t: np.ndarray | None, rate_hz: float | None, n: int, where: str) -> tuple[float, float]:
    """(t0, rate) from a time column and/or ``rate_hz``, with monotonicity and regularity checks."""
    if t is None:
        if rate_hz is None:
            raise RecordingError(f"{where}: no time column; give the sample rate (`rate_hz`)")
        return 0.0, float(rate_hz)
    with np.errstate(over="ignore", invalid="ignore"):
        t = np.asarray(t, dtype=np.float64)
    if t.size < 2:
        raise RecordingError(f"{where}: the time column holds {t.size} sample(s); a recording needs at least 2")
    if not np.all(np.isfinite(t)):
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise RecordingError(f"{where}: time column has a NaN or infinite value at row {i}")
    with np.errstate(over="ignore", invalid="ignore"):
        dt = np.diff(t)
    if not np.all(np.isfinite(dt)):
        i = int(np.flatnonzero(~np.isfinite(dt))[0])
        raise RecordingError(f"{where}: time column values too large (step from row {i} to {i + 1} overflows); "
                             "the time column must be in seconds")
    if np.any(dt <= 0):
        i = int(np.flatnonzero(dt <= 0)[0])
        raise RecordingError(f"{where}: time is not strictly increasing at row {i + 1} "
                             f"(t = {t[i]:.9g} s, then {t[i + 1]:.9g} s)")
    h = float(np.median(dt))
    dev = np.abs(dt - h)
    # exported times are rounded: allow jitter of 1e-4 of a period plus 1 ns of printing resolution
    tol = RATE_TOL * h + 1e-9
    if np.max(dev) > tol:
        i = int(np.argmax(dev > tol))
        raise RecordingError(f"{where}: irregular time base: step {dt[i]:.9g} s at row {i + 1} (t = {t[i]:.9g} s) "
                             f"differs from the median period {h:.9g} s; the DAQ samples uniformly, so samples "
                             "were dropped or the export is not one acquisition")
    with np.errstate(over="ignore", divide="ignore"):
        rate = float(np.float64(1.0) / np.float64(h))
    if not math.isfinite(rate):
        raise RecordingError(f"{where}: time step {h:.3g} s is too small (the time column must be in seconds)")
    if rate_hz is not None and abs(rate - rate_hz) > STORED_RATE_TOL * rate_hz:
        # the rate stored is rate_hz's: it must be the time column's, to the precision replay and
        # identify compare rates with (a rate accepted here and refused there helps no one)
        raise RecordingError(f"{where}: wrong sample rate: the time column says {rate:.9g} Hz, `rate_hz` says "
                             f"{rate_hz:.9g} Hz (they must agree to {STORED_RATE_TOL:g}; leave out `rate_hz`)")
    if rate_hz is not None:
        rate = float(rate_hz)
    else:
        # snap to the nominal rate if the time column only differs by rounding
        nominal = round(rate)
        if abs(rate - nominal) <= RATE_TOL * rate:
            rate = float(nominal)
    return float(t[0]), rate


#: Units accepted for the time column.
TIME_UNITS: tuple[str, ...] = ("s", "sec", "second", "seconds")
#: Largest count magnitude a float64 holds exactly (2**53); a wrapping counter has at most 64 bits.
MAX_EXACT_COUNT = 2 ** 53
MAX_ENCODER_MODULUS = 2 ** 64
#: Full scale of the motor command [V] (±10 V ↔ ±1000 motor rpm).
MOTOR_COMMAND_RANGE_V = (-10.0, 10.0)
#: Values this fraction of the span beyond an input range are refused on import.
RANGE_MARGIN = 0.01


def check_encoder_modulus(modulus: Any) -> None:
    """``encoder_modulus``: None (no wrapping) or an integer in [2, 2**64]."""
    if modulus is None:
        return
    if isinstance(modulus, bool) or not isinstance(modulus, (int, np.integer)) \
            or not 2 <= int(modulus) <= MAX_ENCODER_MODULUS:
        raise RecordingError(f"must be an integer in [2, 2**64] (the count at which the "
                             f"counter wraps, e.g. 4294967296), got {modulus!r}", field="encoder_modulus")


def _check_range(x: np.ndarray, target: str, src: str, cfg: BenchConfig, rate: float, where: str) -> None:
    """Imported samples the instrument cannot produce: volts outside the DAQ's input range (or the
    motor command's ±10 V), counts a float64 cannot hold exactly. NaN/inf are reported elsewhere."""
    from twin.config import DAQ_RANGES

    finite = np.isfinite(x)
    if target == "encoder_counts":
        bad = finite & (np.abs(np.where(finite, x, 0.0)) > MAX_EXACT_COUNT)
        what = "beyond ±2**53, the largest count a float64 holds exactly"
    else:
        if target == "motor_command":
            lo, hi = MOTOR_COMMAND_RANGE_V
            rng = "the motor command's full scale"
        else:
            lo, hi = DAQ_RANGES[cfg.instrumentation.daq_range]
            rng = f"instrumentation.daq_range = {cfg.instrumentation.daq_range!r}"
        margin = RANGE_MARGIN * (hi - lo)
        xf = np.where(finite, x, 0.0)
        bad = finite & ((xf < lo - margin) | (xf > hi + margin))
        what = f"outside {rng} [{lo:g}, {hi:g}] V"
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise RecordingError(f"{where}: {target} (column {src!r}) is {x[i]:.6g} at sample {i} "
                             f"(t = {i / rate:.6f} s), {what}; wrong column, unit or scale?")


def import_table(path: str | Path, cfg: BenchConfig, mapping: Mapping[str, tuple[str, str | None]] | None = None, *,
                 rate_hz: float | None = None, time_column: str = "t", nan: str = "error",
                 encoder_modulus: int | None = None, require: tuple[str, ...] = REQUIRED_CHANNELS,
                 encoder_repair: bool = True) -> tuple[Run, list[str]]:
    """Convert a DAQ export (CSV/NPZ) into a validated ``daq`` run at the recording's rate.

    ``mapping``: target channel → (source column, unit or None); targets not mapped are looked
    up under their own name. Units come from the mapping, else from the header (``name [V]``),
    else from an NPZ ``units`` entry; a channel whose unit is unknown is an error. mV are
    converted to V (reported). ``require``: channels that must be present (a static calibration
    export needs only the volt channels).
    """
    p = Path(path)
    if rate_hz is not None and not (isinstance(rate_hz, (int, float)) and math.isfinite(rate_hz) and rate_hz > 0):
        raise RecordingError(f"must be a finite sample rate > 0 Hz, got {rate_hz!r}", field="rate_hz")
    check_encoder_modulus(encoder_modulus)
    cols, header_units = read_table(p)
    mapping = dict(mapping or {})
    where = str(p)
    flag = "`mapping` t=" if "t" in mapping else "`time_column`"
    explicit_t = "t" in mapping or time_column != "t"
    tname, tunit = mapping.pop("t", (time_column, None))
    t = cols.get(tname)
    if t is None and explicit_t:
        raise RecordingError(f"{where}: no time column {tname!r} ({flag}); columns: {', '.join(cols)}")
    if t is not None:
        tunit = tunit or header_units.get(tname)
        if tunit is not None and tunit not in TIME_UNITS:
            raise RecordingError(f"{where}: time column {tname!r} is in unit {tunit!r}; allowed: "
                                 f"{', '.join(TIME_UNITS)}")
    n_rows = len(next(iter(cols.values()))) if cols else 0
    if n_rows < 2:
        raise RecordingError(f"{where}: holds {n_rows} data row(s); a recording needs at least 2")
    t0, rate = _time_base(t, rate_hz, n_rows, where)
    repairs: list[str] = []
    arrays: dict[str, np.ndarray] = {}
    units: dict[str, str] = {}
    used: dict[str, str] = {tname: "the time column"} if t is not None else {}
    for target in REQUIRED_CHANNELS + OPTIONAL_CHANNELS:
        src, unit = mapping.get(target, (target, None))
        if src in used and src in cols:
            raise RecordingError(f"{where}: column {src!r} would be both {used[src]} and {target}; each channel "
                                 f"needs its own column (`mapping` {target}=COLUMN)")
        used[src] = target
        if src not in cols:
            if target in require:
                raise RecordingError(f"{where}: missing channel {target} (no column {src!r}; columns: "
                                     f"{', '.join(cols)}); map it with `mapping` {target}=COLUMN")
            continue
        unit = unit or header_units.get(src)
        if unit is None:
            raise RecordingError(f"{where}: unknown unit of column {src!r} ({target}); give it in the header "
                                 f"as '{src} [{CHANNEL_UNITS[target]}]' or with `mapping` {target}={src}:{CHANNEL_UNITS[target]}")
        if unit not in UNIT_ALIASES or UNIT_ALIASES[unit][0] != CHANNEL_UNITS[target]:
            ok = [u for u, (s, _) in UNIT_ALIASES.items() if s == CHANNEL_UNITS[target]]
            raise RecordingError(f"{where}: unknown unit {unit!r} for {target} (column {src!r}); "
                                 f"allowed: {', '.join(ok)}")
        stored, factor = UNIT_ALIASES[unit]
        with np.errstate(over="ignore", invalid="ignore"):  # out-of-range values become inf: reported below
            x = np.asarray(cols[src], dtype=np.float64)
            if factor != 1.0:
                x = x * factor
                repairs.append(f"{target}: converted {unit} to {stored}")
        _check_range(x, target, src, cfg, rate, where)
        arrays[target] = x
        units[target] = stored
    groups = {k: DAQ_GROUP for k in arrays}
    rate_cfg = cfg.instrumentation.daq_rate_hz
    if RATE_TOL * rate_cfg >= abs(rate - rate_cfg) > STORED_RATE_TOL * rate_cfg:
        raise RecordingError(f"{where}: sampled at {rate:.9g} Hz but instrumentation.daq_rate_hz is {rate_cfg:g} Hz; "
                             f"replay and identify need them equal to {STORED_RATE_TOL:g} (`rate_hz`, or set "
                             f"instrumentation.daq_rate_hz = {rate:.9g})")
    run = Run.from_arrays(t0, rate, arrays, cfg, {"imported_from": str(p)}, units=units, groups=groups)
    if set(require) == set(REQUIRED_CHANNELS):
        run, more = validate_daq(run, cfg, nan=nan, encoder_repair=encoder_repair,
                                 encoder_modulus=encoder_modulus, where=where)
        repairs.extend(more)
    else:
        rate_cfg = cfg.instrumentation.daq_rate_hz
        if abs(run.rate_hz - rate_cfg) > RATE_TOL * rate_cfg:
            raise RecordingError(f"{where}: sampled at {run.rate_hz:g} Hz but instrumentation.daq_rate_hz is "
                                 f"{rate_cfg:g} Hz (wrong sample rate)")
        for k in list(arrays):
            if not np.all(np.isfinite(arrays[k])):
                if nan == "error":
                    raise RecordingError(f"{where}: channel {k} has NaN or infinite samples")
                run.channels[k].data = _fill_nan(arrays[k], k, run.rate_hz, repairs)
    return run, repairs


def static_calibration_from(path: str | Path, cfg: BenchConfig,
                            mapping: Mapping[str, tuple[str, str | None]] | None = None,
                            rate_hz: float | None = None, nan: str = "error") -> Calibration:
    """Calibration (Eq. 1–4) from a static recording file: a bench recording (.mcap) or a DAQ
    export (.csv/.npz) with the volt channels, taken in the calibration pose of ``cfg``."""
    p = Path(path)
    if p.is_dir():
        raise RecordingError(f"{p}: is a directory; give a static recording file (.mcap, .csv or .npz)")
    if p.suffix.lower() not in (".mcap", ".csv", ".npz"):
        raise RecordingError(f"{p}: unsupported static recording format {p.suffix!r}; allowed: .mcap (bench "
                             "recording), .csv or .npz (DAQ export)")
    if p.suffix.lower() == ".mcap":
        from twin.mcapfile import read_run

        run = read_run(p)
        missing = [c for c in VOLT_CHANNELS if c not in run]
        if missing:
            raise RecordingError(f"{p}: static recording lacks {', '.join(missing)}")
        for c in VOLT_CHANNELS:
            if run.channels[c].unit != "V":
                raise RecordingError(f"{p}: channel {c} is in unit {run.channels[c].unit!r}; expected 'V'")
            if run.n < 2:
                raise RecordingError(f"{p}: holds {run.n} sample(s); a static recording needs at least 2")
            x = np.asarray(run[c], dtype=np.float64)
            if not np.all(np.isfinite(x)):
                raise RecordingError(f"{p}: channel {c} has NaN or infinite samples")
            _check_range(x, c, c, cfg, run.rate_hz, str(p))
    else:
        run, _ = import_table(p, cfg, mapping, rate_hz=rate_hz, nan=nan, require=VOLT_CHANNELS)
    volts = {a: run[f"volt_{a}"] for a in ACCELEROMETERS}
    try:
        cal = calibrate_static(volts, nominal_sensitivities(cfg), calibration_pose_g(cfg), source=p.name)
    except RecordingError as err:
        raise RecordingError(f"{p}: {err}") from None
    supply = cfg.instrumentation.supply_v
    for k, v in cal.zero_g_v.items():
        if not 0.0 < v < supply:
            raise RecordingError(f"{p}: gives a zero-g offset of {v:.4g} V for {k}, outside the sensor's output "
                                 f"range (0, supply_v = {supply:g}) V; not a static recording of the accelerometers?")
    return cal


def calibration_from_offsets(cfg: BenchConfig, zero_g_v: Mapping[str, float], source: str = "given offsets") -> Calibration:
    """Calibration from known zero-g offsets (e.g. a lab calibration sheet)."""
    for k, v in zero_g_v.items():
        if k not in ACCELEROMETERS:
            raise RecordingError(f"unknown sensor {k!r}; allowed: {', '.join(ACCELEROMETERS)}", field="zero_g_v")
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v):
            raise RecordingError(f"{k} must be a finite voltage, got {v!r}", field="zero_g_v")
        supply = cfg.instrumentation.supply_v
        if not 0.0 < v < supply:
            raise RecordingError(f"{k} = {v:g} V is outside the sensor's output range; allowed: "
                                 f"(0, supply_v = {supply:g}) V (nominal {supply / 2:g} V)", field="zero_g_v")
    missing = [a for a in ACCELEROMETERS if a not in zero_g_v]
    if missing:
        raise RecordingError(f"no offset for {', '.join(missing)}", field="zero_g_v")
    sens = nominal_sensitivities(cfg)
    return Calibration({k: float(v) for k, v in zero_g_v.items()}, sens, calibration_pose_g(cfg), source=source)


# ------------------------------------------------------------------------ synthetic
def crank_trace(motor_rpm: float, belt_ratio: float, duration_s: float, rate_hz: float, *, ramp_s: float = 0.3,
                rest_s: float = 0.0, ripple: tuple[float, ...] = (0.02, 0.01), ripple_phase: tuple[float, ...] = (0.4, 1.3),
                direction: int = 1, phi0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A realistic non-constant crank motion as an encoder trace (t [s], encoder angle [rad]).

    The crank rests for ``rest_s``, then the speed follows a cosine ramp of ``ramp_s`` to the
    nominal crank speed (motor_rpm / belt_ratio) and fluctuates within each turn:
    dφ/dt = direction · ω_nom · s(t) · (1 + Σ_k ripple[k-1] · sin(k φ + ripple_phase[k-1])), φ the
    encoder angle (starting at ``phi0``), so the fluctuation is tied to the mechanism's position. A belt-driven slider–crank's speed varies with the crank angle
    because the load torque and the effective inertia do (S003 §4.3: "speed is not constant
    within a turn"); the ripple amplitudes are illustrative (PLACEHOLDER: not measured).
    Integrated with scipy's RK45 at tight tolerance on the sample grid.
    """
    from scipy.integrate import solve_ivp

    w_nom = motor_rpm / belt_ratio * 2.0 * math.pi / 60.0
    n = int(round(duration_s * rate_hz))
    t = np.arange(n) / rate_hz

    def s(tt: float) -> float:
        tau = tt - rest_s
        if tau <= 0:
            return 0.0
        if ramp_s <= 0 or tau >= ramp_s:
            return 1.0
        return 0.5 * (1.0 - math.cos(math.pi * tau / ramp_s))

    if len(ripple) != len(ripple_phase):
        raise ValueError("crank_trace: ripple and ripple_phase need the same length")

    def rhs(tt: float, y: np.ndarray) -> list[float]:
        mod = 1.0 + sum(r * math.sin((k + 1) * y[0] + p) for k, (r, p) in enumerate(zip(ripple, ripple_phase)))
        return [direction * w_nom * s(tt) * mod]

    sol = solve_ivp(rhs, (0.0, float(t[-1]) if n > 1 else 0.0), [float(phi0)], t_eval=t, rtol=1e-10, atol=1e-12,
                    max_step=min(1e-3, ramp_s / 20 if ramp_s > 0 else 1e-3))
    if not sol.success:
        raise RecordingError(f"crank_trace: integration failed ({sol.message})")
    return t, sol.y[0]


def synthetic_recording(truth: Run, cfg: BenchConfig, notes: str = "", static_s: float = 1.0,
                        extra: Mapping[str, Any] | None = None, created_by: str = "twin.recording") -> tuple[Run, RecordingInfo]:
    """A bench recording made by the twin: the sensor chain of ``cfg.instrumentation`` on a
    simulated ``truth`` run (motor command from ``cfg``'s drive program), calibrated by a
    simulated static recording through the same chain (Eq. 1–4)."""
    from twin.instrument import apply_chain

    return synthetic_daq_recording(apply_chain(truth, cfg), cfg, truth.meta, notes, static_s, extra, created_by)


def synthetic_daq_recording(daq: Run, cfg: BenchConfig, truth_meta: Mapping[str, Any], notes: str = "",
                            static_s: float = 1.0, extra: Mapping[str, Any] | None = None,
                            created_by: str = "twin.recording") -> tuple[Run, RecordingInfo]:
    """The recording of DAQ channels ``daq`` that the sensor chain of ``cfg`` made from a simulated run
    (whose metadata is ``truth_meta``): validated as an import is, with the calibration of a simulated
    static recording of ``static_s`` [s] through the same chain (Eq. 1–4)."""
    from twin.instrument import simulated_calibration

    cal = simulated_calibration(cfg, static_s)
    info = RecordingInfo(daq.rate_hz, notes=notes, calibration=cal, synthetic=True, created_by=created_by,
                         extra={"engine": truth_meta.get("engine"), "timestep_s": truth_meta.get("timestep_s"),
                                "chain_seed": cfg.instrumentation.seed, **dict(extra or {})})
    daq, repairs = validate_daq(daq, cfg, where="synthetic recording")
    info.repairs.extend(repairs)
    return daq, info
