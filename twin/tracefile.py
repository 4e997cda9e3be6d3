"""Recorded drive inputs: the crank encoder trace of the "trace" drive program and the motor command
of ``drive.mode = "motor"``, in memory (:class:`DriveInputs`, what the library passes to the drive)
or in the files a user names (``drive.trace_file``: ``.npz`` or ``.csv`` with ``t`` [s] and
``angle`` [rad]; ``drivetrain.command_file``: ``.npz`` with ``t`` [s] and ``volts`` [V]). Both are
checked here, where the drive (:mod:`twin.drive`, :mod:`twin.motor_drive`) finds them. A trace
program with ``simulation.duration_s = 0`` runs for the trace's length, filled in here from the trace
in memory (:func:`with_trace_duration`): the configuration never opens a data file."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from twin.errors import ConfigError, RecordingError


def load_trace(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read an encoder trace: (t [s], encoder angle [rad]) from ``.npz`` or ``.csv``.

    ``.npz`` must hold real numeric 1-D arrays ``t`` and ``angle``; ``.csv`` a header with
    columns ``t`` and ``angle``. Time must be finite and strictly increasing. Every problem is
    a one-line error naming the file.
    """
    import zipfile

    p = Path(path)
    if p.suffix.lower() not in (".npz", ".csv"):
        raise ConfigError("drive.trace_file", f"must be a .npz or .csv file, got {str(p)!r}")
    if not p.is_file():
        raise ConfigError("drive.trace_file", f"no such file: {p}")
    try:
        if p.suffix.lower() == ".npz":
            loaded = np.load(p, allow_pickle=False)
            if not isinstance(loaded, np.lib.npyio.NpzFile):  # an .npy array renamed .npz
                raise RecordingError(f"{p}: not an .npz archive of named arrays (a single .npy array renamed?)")
            with loaded as z:
                missing = [k for k in ("t", "angle") if k not in z.files]
                if missing:
                    raise RecordingError(f"{p}: needs arrays 't' and 'angle', has {', '.join(z.files) or 'none'}")
                t, a = z["t"], z["angle"]
        else:
            import warnings

            with warnings.catch_warnings():
                warnings.simplefilter("error")  # empty or ragged files: an error, not a warning
                data = np.genfromtxt(p, delimiter=",", names=True, encoding="utf-8-sig")
            names = data.dtype.names or ()
            if "t" not in names or "angle" not in names:
                raise RecordingError(f"{p}: needs CSV columns 't' and 'angle', has {', '.join(names) or 'none'}")
            t, a = np.atleast_1d(data["t"]), np.atleast_1d(data["angle"])
    except RecordingError:
        raise
    except (OSError, ValueError, UnicodeDecodeError, zipfile.BadZipFile, EOFError, Warning) as err:
        if p.suffix.lower() == ".npz" and not zipfile.is_zipfile(p):  # numpy's own words would advise unpickling it
            raise RecordingError(f"{p}: not an .npz archive (numpy.savez of arrays 't' and 'angle'); a text export "
                                 "is read as .csv with columns t, angle") from None
        raise RecordingError(f"{p}: not a readable trace ({type(err).__name__}: {str(err).splitlines()[0] if str(err) else ''})") from None
    return check_trace(t, a, str(p))


def check_trace(t: np.ndarray, angle: np.ndarray, where: str) -> tuple[np.ndarray, np.ndarray]:
    """The encoder trace (t [s], angle [rad]) as float64 arrays, or a one-line
    :class:`~twin.errors.RecordingError` starting with ``where``: real numbers, 1-D of equal length,
    finite, time strictly increasing, at least :data:`MIN_TRACE_SAMPLES` samples spaced between
    :data:`MIN_TRACE_SPACING_S` and :data:`MAX_TRACE_GAP_S`."""
    p = where
    t, a = np.asarray(t), np.asarray(angle)
    for name, x in (("t", t), ("angle", a)):
        if x.dtype.kind not in "iuf":
            raise RecordingError(f"{p}: '{name}' must hold real numbers, got dtype {x.dtype}")
    t, a = np.asarray(t, dtype=np.float64), np.asarray(a, dtype=np.float64)
    if t.ndim != 1 or t.shape != a.shape or t.size < 2:
        raise RecordingError(f"{p}: 't' and 'angle' must be 1-D arrays of equal length >= 2")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(a))):
        raise RecordingError(f"{p}: trace holds NaN or infinite samples")
    if np.any(np.diff(t) <= 0):
        raise RecordingError(f"{p}: time must be strictly increasing")
    if t.size < MIN_TRACE_SAMPLES:
        raise RecordingError(f"{p}: holds {t.size} samples; a trace needs at least {MIN_TRACE_SAMPLES}")
    dt = np.diff(t)
    if float(np.min(dt)) < MIN_TRACE_SPACING_S:
        i = int(np.argmin(dt))
        raise RecordingError(f"{p}: samples {i} and {i + 1} lie {float(dt[i]):.3g} s apart; the spacing must be at "
                             f"least {MIN_TRACE_SPACING_S:g} s (time in seconds?)")
    if float(np.max(dt)) > MAX_TRACE_GAP_S:
        i = int(np.argmax(dt))
        raise RecordingError(f"{p}: a gap of {float(dt[i]):.3g} s after sample {i}; samples may lie at most "
                             f"{MAX_TRACE_GAP_S:g} s apart")
    return t, a




#: fewest samples of a trace (a spline through 2-3 samples is no drive)
MIN_TRACE_SAMPLES = 8
#: closest sample spacing [s] (10 MHz: far beyond any encoder DAQ; closer spacing is a unit error
#: and would make the uniform grid of the drive's filter billions of samples long)
MIN_TRACE_SPACING_S = 1e-7
#: widest gap between samples [s]
MAX_TRACE_GAP_S = 1.0


def check_trace_speed(t: np.ndarray, angle: np.ndarray, max_crank_rpm: float, where: str) -> None:
    """Refuse a trace whose crank turns faster than the drive can (1.5 x ``max_crank_rpm``, over 5 ms
    or 4 samples, whichever is longer, so that encoder quantization does not count): typically an
    angle in degrees, not radians."""
    if t.size < 2:
        return
    h = float(np.median(np.diff(t)))
    k = max(1, min(t.size - 1, int(np.ceil(max(0.005 / h, 4)))))
    rate = np.abs(angle[k:] - angle[:-k]) / (t[k:] - t[:-k])  # [rad/s]
    top = float(np.max(rate)) * 60.0 / (2 * np.pi)
    if top > 1.5 * max_crank_rpm:
        i = int(np.argmax(rate))
        raise ConfigError("drive.trace_file", f"{where}: the crank turns at {top:.4g} rpm at t = {t[i]:.4g} s, beyond "
                                              f"the drive's {max_crank_rpm:.4g} rpm; the angle must be in radians "
                                              "(degrees?)")


def trace_duration(path: str | Path) -> float:
    """Length of the encoder trace in the file ``path`` [s] (last minus first time stamp)."""
    t, _ = load_trace(path)
    return float(t[-1] - t[0])


def with_trace_duration(cfg: Any, inputs: DriveInputs | None = None) -> Any:
    """``cfg`` (a :class:`~twin.config.BenchConfig`) with a trace program's ``simulation.duration_s = 0``
    ("the trace's length") replaced by that length [s], last minus first time stamp of the trace:
    ``inputs.trace`` when given (in memory), else the file ``drive.trace_file`` names. Any other
    configuration is returned as it is. The run (:func:`twin.simulation.simulate`) and the command
    line's ``--config`` call it; the configuration itself reads no data file."""
    if cfg.drive.program != "trace" or cfg.simulation.duration_s != 0:
        return cfg
    if inputs is not None and inputs.trace is not None:
        t = inputs.trace[0]
    else:
        t, _ = load_trace(cfg.drive.trace_file)
    return cfg.replace(**{"simulation.duration_s": float(t[-1] - t[0])})


#: largest magnitude of a recorded motor command [V]: the DAQ's ±10 V analog output (S003 §2.3.1) with 2 % for
#: its offset and gain error
COMMAND_LIMIT_V = 10.2


def check_command(t: np.ndarray, volts: np.ndarray, where: str) -> tuple[np.ndarray, np.ndarray]:
    """The recorded motor command (t [s], volts [V]) as float64 arrays, or a one-line
    :class:`~twin.errors.ConfigError` of ``drivetrain.command_file`` starting with ``where``: 1-D of
    equal length (at least 2), time increasing, all finite, within ±:data:`COMMAND_LIMIT_V`."""
    t, v = np.asarray(t, dtype=np.float64), np.asarray(volts, dtype=np.float64)
    if t.ndim != 1 or t.shape != v.shape or t.size < 2 or np.any(np.diff(t) <= 0) \
            or not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
        raise ConfigError("drivetrain.command_file", f"{where}: 't' must increase and match 'volts', all finite")
    worst = float(np.abs(v).max())
    if worst > COMMAND_LIMIT_V:
        raise ConfigError("drivetrain.command_file",
                          f"{where}: 'volts' reaches {worst:g} V, outside the DAQ's ±10 V analog command (a command "
                          f"beyond ±{COMMAND_LIMIT_V:g} V is no recording of it: volts, not rpm or mV?)")
    return t, v


@dataclass(frozen=True)
class DriveInputs:
    """Recorded inputs of a run, in memory: what the library hands to the drive instead of a file.

    A field left None falls back to the file the configuration names (``drive.trace_file``,
    ``drivetrain.command_file``), which only a user gives. The arrays are checked (and made float64)
    on construction, with the same one-line errors as the files.

    Attributes:
        trace: (t [s], crank encoder angle [rad]) of the "trace" drive program, 1-D arrays of equal length.
        command: (t [s], motor command [V]) of ``drive.mode = "motor"``, 1-D arrays of equal length.
    """

    trace: tuple[np.ndarray, np.ndarray] | None = None
    command: tuple[np.ndarray, np.ndarray] | None = None

    def __post_init__(self) -> None:
        if self.trace is not None:
            object.__setattr__(self, "trace", check_trace(*self.trace, where="drive trace"))
        if self.command is not None:
            object.__setattr__(self, "command", check_command(*self.command, where="motor command"))
