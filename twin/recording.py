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
strictly increasing and regular, and that it agrees with ``--rate``.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
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
        return {"format": RECORDING_FORMAT, "json": json.dumps(self.to_dict(), sort_keys=True, default=_json_default)}

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


def _json_default(o: Any) -> Any:
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serializable: {type(o).__name__}")


def file_sha256(path: str | Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


# ------------------------------------------------------------------------ validation
def _max_crank_rpm(cfg: BenchConfig) -> float:
    """Fastest crank speed the drive can command (±1000 motor rpm through the belt) [rpm]."""
    return 1000.0 / cfg.drive.belt_ratio


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
            if encoder_modulus:
                x = unwrap_counts(x, int(encoder_modulus))
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
                                     f"(t = {run.t0 + i / run.rate_hz:.6f} s); import with --repair-nan to "
                                     f"interpolate gaps of up to {MAX_NAN_GAP} samples")
            x = _fill_nan(x, name, run.rate_hz, repairs)
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
                raise RecordingError(f"--map: expects TARGET=SOURCE[:UNIT], got {part!r}")
            target, src = (s.strip() for s in part.split("=", 1))
            unit = None
            if ":" in src:
                src, unit = (s.strip() for s in src.rsplit(":", 1))
            allowed = REQUIRED_CHANNELS + OPTIONAL_CHANNELS + ("t",)
            if target not in allowed:
                raise RecordingError(f"--map: unknown target channel {target!r}; allowed: {', '.join(allowed)}")
            if not src:
                raise RecordingError(f"--map: empty source column for {target!r}")
            out[target] = (src, unit)
    return out


def _read_csv(path: Path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    with open(path, "r", encoding="utf-8-sig") as fh:
        header = fh.readline()
        first = fh.readline()
    if not header.strip():
        raise RecordingError(f"{path}: empty file")
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
    if len(set(names)) != len(names):
        raise RecordingError(f"{path}: repeated column names in the header")
    if not first.strip():
        raise RecordingError(f"{path}: no data rows after the header")
    try:
        data = np.loadtxt(path, delimiter=delim, skiprows=1, ndmin=2, dtype=np.float64, encoding="utf-8-sig")
    except ValueError as err:
        raise RecordingError(f"{path}: unreadable data ({err})") from None
    if data.shape[1] != len(names):
        raise RecordingError(f"{path}: {data.shape[1]} data columns but {len(names)} header names")
    return {n: data[:, i] for i, n in enumerate(names)}, units


def _read_npz(path: Path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: np.asarray(z[k]) for k in z.files}
    except (OSError, ValueError, EOFError) as err:
        raise RecordingError(f"{path}: not a readable .npz file ({err})") from None
    units: dict[str, str] = {}
    if "units" in arrays:
        try:
            units = {str(k): str(v) for k, v in json.loads(str(arrays.pop("units"))).items()}
        except (ValueError, AttributeError) as err:
            raise RecordingError(f"{path}: entry 'units' must be a JSON object string ({err})") from None
    for k, v in arrays.items():
        if v.ndim != 1:
            raise RecordingError(f"{path}: array {k!r} must be 1-D, got shape {v.shape}")
    return arrays, units


def read_table(path: str | Path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """Columns and header units of a DAQ export (``.csv`` with a header row, or ``.npz``)."""
    p = Path(path)
    if not p.is_file():
        raise RecordingError(f"{p}: no such file")
    if p.suffix.lower() == ".csv":
        return _read_csv(p)
    if p.suffix.lower() == ".npz":
        return _read_npz(p)
    raise RecordingError(f"{p}: unsupported export format {p.suffix!r}; use .csv or .npz (or a .mcap recording)")


def _time_base(t: np.ndarray | None, rate_hz: float | None, n: int, where: str) -> tuple[float, float]:
    """(t0, rate) from a time column and/or --rate, with monotonicity and regularity checks."""
    if t is None:
        if rate_hz is None:
            raise RecordingError(f"{where}: no time column; give the sample rate with --rate")
        return 0.0, float(rate_hz)
    t = np.asarray(t, dtype=np.float64)
    if not np.all(np.isfinite(t)):
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise RecordingError(f"{where}: time column has a NaN or infinite value at row {i}")
    dt = np.diff(t)
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
    rate = 1.0 / h
    if rate_hz is not None and abs(rate - rate_hz) > RATE_TOL * rate_hz:
        raise RecordingError(f"{where}: wrong sample rate: the time column says {rate:.6g} Hz, --rate says {rate_hz:g} Hz")
    if rate_hz is not None:
        rate = float(rate_hz)
    else:
        # snap to the nominal rate if the time column only differs by rounding
        nominal = round(rate)
        if abs(rate - nominal) <= RATE_TOL * rate:
            rate = float(nominal)
    return float(t[0]), rate


def import_table(path: str | Path, cfg: BenchConfig, mapping: Mapping[str, tuple[str, str | None]] | None = None,
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
    cols, header_units = read_table(p)
    mapping = dict(mapping or {})
    where = str(p)
    tname = mapping.pop("t", (time_column, None))[0]
    t = cols.get(tname)
    n_rows = len(next(iter(cols.values()))) if cols else 0
    t0, rate = _time_base(t, rate_hz, n_rows, where)
    repairs: list[str] = []
    arrays: dict[str, np.ndarray] = {}
    units: dict[str, str] = {}
    for target in REQUIRED_CHANNELS + OPTIONAL_CHANNELS:
        src, unit = mapping.get(target, (target, None))
        if src not in cols:
            if target in require:
                raise RecordingError(f"{where}: missing channel {target} (no column {src!r}; columns: "
                                     f"{', '.join(cols)}); map it with --map {target}=COLUMN")
            continue
        unit = unit or header_units.get(src)
        if unit is None:
            raise RecordingError(f"{where}: unknown unit of column {src!r} ({target}); give it in the header "
                                 f"as '{src} [{CHANNEL_UNITS[target]}]' or with --map {target}={src}:{CHANNEL_UNITS[target]}")
        if unit not in UNIT_ALIASES or UNIT_ALIASES[unit][0] != CHANNEL_UNITS[target]:
            ok = [u for u, (s, _) in UNIT_ALIASES.items() if s == CHANNEL_UNITS[target]]
            raise RecordingError(f"{where}: unknown unit {unit!r} for {target} (column {src!r}); "
                                 f"allowed: {', '.join(ok)}")
        stored, factor = UNIT_ALIASES[unit]
        x = np.asarray(cols[src], dtype=np.float64)
        if factor != 1.0:
            x = x * factor
            repairs.append(f"{target}: converted {unit} to {stored}")
        arrays[target] = x
        units[target] = stored
    groups = {k: DAQ_GROUP for k in arrays}
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
    if p.suffix.lower() == ".mcap":
        from twin.mcapfile import read_run

        run = read_run(p)
        missing = [c for c in VOLT_CHANNELS if c not in run]
        if missing:
            raise RecordingError(f"{p}: static recording lacks {', '.join(missing)}")
        for c in VOLT_CHANNELS:
            if run.channels[c].unit != "V":
                raise RecordingError(f"{p}: channel {c} is in unit {run.channels[c].unit!r}; expected 'V'")
    else:
        run, _ = import_table(p, cfg, mapping, rate_hz, nan=nan, require=VOLT_CHANNELS)
    volts = {a: run[f"volt_{a}"] for a in ACCELEROMETERS}
    return calibrate_static(volts, nominal_sensitivities(cfg), calibration_pose_g(cfg), source=p.name)


def calibration_from_offsets(cfg: BenchConfig, zero_g_v: Mapping[str, float], source: str = "given offsets") -> Calibration:
    """Calibration from known zero-g offsets (e.g. a lab calibration sheet)."""
    for k, v in zero_g_v.items():
        if k not in ACCELEROMETERS:
            raise RecordingError(f"--zero-g: unknown sensor {k!r}; allowed: {', '.join(ACCELEROMETERS)}")
        if not math.isfinite(v):
            raise RecordingError(f"--zero-g: {k} must be a finite voltage, got {v!r}")
    missing = [a for a in ACCELEROMETERS if a not in zero_g_v]
    if missing:
        raise RecordingError(f"--zero-g: no offset for {', '.join(missing)}")
    sens = nominal_sensitivities(cfg)
    return Calibration({k: float(v) for k, v in zero_g_v.items()}, sens, calibration_pose_g(cfg), source=source)


# ------------------------------------------------------------------------ synthetic
def crank_trace(motor_rpm: float, belt_ratio: float, duration_s: float, rate_hz: float, ramp_s: float = 0.3,
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
    from twin.instrument import apply_chain, simulated_calibration

    daq = apply_chain(truth, cfg)
    cal = simulated_calibration(cfg, static_s)
    info = RecordingInfo(daq.rate_hz, notes=notes, calibration=cal, synthetic=True, created_by=created_by,
                         extra={"engine": truth.meta.get("engine"), "timestep_s": truth.meta.get("timestep_s"),
                                "chain_seed": cfg.instrumentation.seed, **dict(extra or {})})
    daq, repairs = validate_daq(daq, cfg, where="synthetic recording")
    info.repairs.extend(repairs)
    return daq, info
