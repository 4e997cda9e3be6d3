"""Small shared helpers: output paths checked before any work, temporary files, atomic writes.

Every file the twin writes goes to a temporary name beside its target, ``.NAME.PID.tmp`` (plus
the target's suffix where a library insists on it, e.g. ``.run.rrd.PID.tmp.rrd``), and is renamed
into place when complete. A process killed with SIGKILL cannot clean up; the next run on the same
target removes the leftovers of processes that no longer exist (:func:`remove_stale_temps`).
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import re
import shutil
import socket
from pathlib import Path
from typing import Any, Iterable

import numpy as np

from twin.errors import TwinError

_TMP_RE = re.compile(r"^\.(?P<name>.+)\.(?:(?P<host>[A-Za-z0-9_]+)-)?(?P<pid>\d+)\.tmp(?P<ext>\.[A-Za-z0-9]+)?$")
#: this machine, in temporary names: on a shared file system (a Dask cluster) only the host that
#: wrote a temporary file can tell whether its process still runs
_HOST = re.sub(r"[^A-Za-z0-9_]", "_", socket.gethostname())[:40] or "host"


def json_default(o: Any) -> Any:
    """``json.dumps(default=...)`` for numpy scalars and arrays and paths."""
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serializable: {type(o).__name__}")


def file_sha256(path: str | Path) -> str:
    """SHA-256 of a file's bytes, as hex (read in blocks: any size)."""
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()


def resolve_workers(n: int | None, flag: str = "--workers") -> int:
    """Worker processes: ``n``, or the machine's cores when None; one line naming ``flag`` when
    out of [1, 1024]."""
    w = n if n is not None else (os.cpu_count() or 1)
    if isinstance(w, bool) or not isinstance(w, int) or not 1 <= w <= 1024:
        raise TwinError(f"{flag}: must be an integer in [1, 1024], got {w!r}")
    return w


# ------------------------------------------------------------------ temporary files
def temp_path(target: str | Path, keep_suffix: bool = False) -> Path:
    """Temporary name of this process for ``target``: ``.NAME.PID.tmp`` beside it
    (``keep_suffix``: ``.NAME.PID.tmp.SUFFIX``, for writers that check the extension)."""
    p = Path(target)
    ext = p.suffix if keep_suffix else ""
    return p.with_name(f".{p.name}.{_HOST}-{os.getpid()}.tmp{ext}")


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    except OSError:
        return False
    return True


def remove_stale_temps(target: str | Path) -> list[Path]:
    """Remove temporary files (or folders) of ``target`` left by processes that no longer run
    (killed with SIGKILL, power loss). Returns what was removed; a temporary of a live process is
    kept (another run is writing the same target)."""
    p = Path(target)
    removed: list[Path] = []
    parent = p.parent if str(p.parent) else Path(".")
    try:
        entries = list(parent.iterdir())
    except OSError:
        return removed
    for e in entries:
        m = _TMP_RE.match(e.name)
        if not m or m["name"] != p.name or (m["host"] or _HOST) != _HOST or _alive(int(m["pid"])):
            continue  # not ours, written on another machine, or its process still runs
        try:
            if e.is_dir() and not e.is_symlink():
                shutil.rmtree(e)
            else:
                e.unlink()
            removed.append(e)
        except OSError:
            pass
    return removed


# ------------------------------------------------------------- output path checks
def _why(err: OSError) -> str:
    return err.strerror or errno.errorcode.get(err.errno or 0, str(err))


def _probe_dir_writable(directory: Path, flag: str, target: Path) -> None:
    """Create and remove a file in ``directory``: the only reliable writability test
    (``os.access`` says yes to root on read-only or virtual file systems such as /proc)."""
    probe = directory / f".{target.name}.{_HOST}-{os.getpid()}.tmp.probe"
    try:
        fd = os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError as err:
        raise TwinError(f"{flag}: cannot write in {directory} ({_why(err)})") from None
    os.close(fd)
    try:
        os.unlink(probe)
    except OSError:
        pass


def check_output_file(path: str | Path, flag: str, suffixes: str | Iterable[str],
                      inputs: Iterable[str | Path] = ()) -> Path:
    """Check an output file given on the command line before any work starts.

    It must end in one of ``suffixes``, its folder must exist and be writable, it must not be a
    folder, nor one of ``inputs``. Stale temporary files of the target are removed. Raises a
    one-line :class:`TwinError` naming ``flag`` otherwise. Nothing is created.
    """
    out = Path(path)
    allowed = (suffixes,) if isinstance(suffixes, str) else tuple(suffixes)
    if out.suffix not in allowed:
        raise TwinError(f"{flag}: must end in {' or '.join(allowed)}, got {str(out)!r}")
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.exists():
        raise TwinError(f"{flag}: directory {parent} does not exist")
    if not parent.is_dir():
        raise TwinError(f"{flag}: {parent} is not a directory")
    if out.is_dir():
        raise TwinError(f"{flag}: {out} is a directory")
    if out.exists() and not out.is_file():
        raise TwinError(f"{flag}: {out} exists and is not a regular file")
    for i in inputs:
        if Path(i).exists() and out.exists() and out.resolve() == Path(i).resolve():
            raise TwinError(f"{flag}: {out} is also an input; choose another output")
    _probe_dir_writable(parent, flag, out)
    remove_stale_temps(out)
    return out


def check_output_dir(path: str | Path, flag: str = "--out", need_parent: bool = True) -> Path:
    """An output folder given on the command line: it may exist (as a folder) or be created (in an
    existing parent unless ``need_parent`` is False, for callers that create parents). The
    folder that will hold it must be writable. Raises TwinError naming ``flag`` otherwise."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise TwinError(f"{flag}: {out} exists and is not a directory")
    parent = out.parent if str(out.parent) else Path(".")
    if need_parent and not parent.exists():
        raise TwinError(f"{flag}: parent directory {parent} does not exist")
    probe_in = parent
    while not probe_in.exists():
        probe_in = probe_in.parent
    if not probe_in.is_dir():
        raise TwinError(f"{flag}: {probe_in} is not a directory")
    _probe_dir_writable(probe_in, flag, out)
    remove_stale_temps(out)
    return out


# -------------------------------------------------------------------- atomic writes
def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to a temporary file beside ``path`` and rename it into place."""
    p = Path(path)
    if not p.parent.exists():
        raise TwinError(f"{p}: directory {p.parent} does not exist")
    tmp = temp_path(p)
    try:
        try:
            tmp.write_bytes(data)
            os.replace(tmp, p)
        except OSError as err:
            raise TwinError(f"{p}: cannot write ({_why(err)})") from None
    finally:
        tmp.unlink(missing_ok=True)
    return p


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Text version of :func:`atomic_write_bytes` (UTF-8)."""
    return atomic_write_bytes(path, text.encode())


def atomic_write_json(path: str | Path, obj: Any) -> Path:
    """Pretty JSON, written atomically."""
    return atomic_write_text(path, json.dumps(obj, indent=2, sort_keys=False, default=json_default) + "\n")


def replace_dir(tmp_dir: Path, target: Path) -> Path:
    """Move a completed temporary folder into place as ``target``: an existing ``target`` is
    first renamed aside and deleted only after the new one is in place, so at no time is
    ``target`` a mix of the old and the new contents."""
    import signal
    import threading

    old = target.with_name(f".{target.name}.{_HOST}-{os.getpid()}.tmp.old") if target.exists() else None
    if old is not None and old.exists():
        shutil.rmtree(old)
    # Ctrl-C or SIGTERM between the two renames would leave no target: hold them until both are done
    masked = threading.current_thread() is threading.main_thread() and hasattr(signal, "pthread_sigmask")
    if masked:
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        if old is not None:
            os.replace(target, old)
        try:
            os.replace(tmp_dir, target)
        except BaseException:
            if old is not None:
                os.replace(old, target)
            raise
    finally:
        if masked:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    return target
