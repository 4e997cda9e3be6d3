"""Encoder trace files (``.npz`` or ``.csv`` with ``t`` [s] and ``angle`` [rad]) for the "trace" drive
program: read and checked here, where both the drive (:mod:`twin.drive`) and the configuration
loader (which fills in a trace program's duration) find them."""

from __future__ import annotations

from pathlib import Path

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
    if p.suffix not in (".npz", ".csv"):
        raise ConfigError("drive.trace_file", f"must be a .npz or .csv file, got {str(p)!r}")
    if not p.is_file():
        raise ConfigError("drive.trace_file", f"no such file: {p}")
    try:
        if p.suffix == ".npz":
            with np.load(p, allow_pickle=False) as z:
                missing = [k for k in ("t", "angle") if k not in z.files]
                if missing:
                    raise RecordingError(f"{p}: needs arrays 't' and 'angle', has {', '.join(z.files) or 'none'}")
                t, a = z["t"], z["angle"]
        else:
            import warnings

            with warnings.catch_warnings():
                warnings.simplefilter("error")  # empty or ragged files: an error, not a warning
                data = np.genfromtxt(p, delimiter=",", names=True, encoding="utf-8")
            names = data.dtype.names or ()
            if "t" not in names or "angle" not in names:
                raise RecordingError(f"{p}: needs CSV columns 't' and 'angle', has {', '.join(names) or 'none'}")
            t, a = np.atleast_1d(data["t"]), np.atleast_1d(data["angle"])
    except RecordingError:
        raise
    except (OSError, ValueError, UnicodeDecodeError, zipfile.BadZipFile, EOFError, Warning) as err:
        raise RecordingError(f"{p}: not a readable trace ({type(err).__name__}: {str(err).splitlines()[0] if str(err) else ''})") from None
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
    return t, a


def trace_duration(path: str | Path) -> float:
    """Length of an encoder trace [s] (last minus first time stamp); the loaders of
    configurations call it, so that a trace program's duration is known before the run."""
    t, _ = load_trace(path)
    return float(t[-1] - t[0])
