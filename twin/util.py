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
import stat
from pathlib import Path
from contextlib import contextmanager
from typing import Any, Callable, Iterable, Iterator

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


def json_safe(o: Any) -> Any:
    """``o`` with every float that JSON cannot hold (NaN, +-Infinity) replaced by ``None`` (JSON's
    null), numpy scalars and arrays and paths converted: what the twin writes as JSON is strict JSON
    (RFC 8259) that every parser reads. A missing value (a label a run lacks, a metric with no data)
    is null; where a non-finite number would be a wrong answer rather than a missing one, the code
    computing it refuses instead."""
    if isinstance(o, float) or isinstance(o, np.floating):
        v = float(o)
        return v if v == v and v not in (float("inf"), float("-inf")) else None
    if isinstance(o, dict):
        return {k if isinstance(k, str) else str(k): json_safe(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [json_safe(v) for v in o]
    if isinstance(o, np.ndarray):
        return json_safe(o.tolist())
    if isinstance(o, (np.integer, np.bool_)):
        return o.item()
    if isinstance(o, Path):
        return str(o)
    return o


def json_text(obj: Any, indent: int | None = 2, sort_keys: bool = False) -> str:
    """Strict JSON text of ``obj`` (:func:`json_safe`: NaN and infinities as null, ``allow_nan`` off):
    the one serializer of every JSON the twin prints or writes."""
    return json.dumps(json_safe(obj), indent=indent, sort_keys=sort_keys, default=json_default, allow_nan=False)


def file_sha256(path: str | Path) -> str:
    """SHA-256 of a file's bytes, as hex (read in blocks: any size)."""
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()


def check_size_px(size: Any, field: str) -> tuple[int, int]:
    """An image or window size (width, height) [px]: two whole numbers in 64..8192, else a one-line
    :class:`TwinError` about ``field``."""
    if not (isinstance(size, (tuple, list)) and len(size) == 2
            and all(isinstance(v, int) and not isinstance(v, bool) and 64 <= v <= 8192 for v in size)):
        raise TwinError(f"must be two whole numbers of pixels in 64..8192, got {size!r}", field=field)
    return int(size[0]), int(size[1])


def resolve_workers(n: int | None, flag: str = "workers") -> int:
    """Worker processes: ``n``, or the machine's cores when None; one line naming ``flag`` when
    out of [1, 1024]."""
    w = n if n is not None else (os.cpu_count() or 1)
    if isinstance(w, bool) or not isinstance(w, int) or not 1 <= w <= 1024:
        raise TwinError(f"must be an integer in [1, 1024], got {w!r}", field=flag)
    return w


# ------------------------------------------------------------------ temporary files
def _name_max(directory: Path) -> int:
    """Longest file name (bytes) the file system of ``directory`` (or its nearest existing parent) allows."""
    d = directory
    for _ in range(64):
        try:
            return int(os.pathconf(d, "PC_NAME_MAX"))
        except (OSError, ValueError):
            if d == d.parent:
                break
            d = d.parent
    return 255


def temp_path(target: str | Path, keep_suffix: bool = False) -> Path:
    """Temporary name of this process for ``target``: ``.NAME.PID.tmp`` beside it
    (``keep_suffix``: ``.NAME.PID.tmp.SUFFIX``, for writers that check the extension).

    The name fits wherever the target's fits: a name too long for the file system once the
    prefix and suffix are added is shortened to its start plus a hash of the whole name."""
    p = Path(target)
    ext = p.suffix if keep_suffix else ""
    tail = f".{_HOST}-{os.getpid()}.tmp{ext}"
    name = p.name
    limit = _name_max(p.parent if str(p.parent) else Path("."))
    if len(os.fsencode(f".{name}{tail}")) > limit:
        digest = hashlib.sha1(os.fsencode(name)).hexdigest()[:10]
        keep = name.encode("utf-8", "surrogateescape")[: max(1, limit - len(os.fsencode(tail)) - 13)]
        name = keep.decode("utf-8", "ignore") + "~" + digest
    return p.with_name(f".{name}{tail}")


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
    """Remove temporary files (or folders) left in the folder of ``target`` by processes of this
    machine that no longer run (killed with SIGKILL, power loss), whatever target they were
    writing. Returns what was removed; a temporary of a live process is kept (another run is
    writing there)."""
    p = Path(target)
    removed: list[Path] = []
    parent = p.parent if str(p.parent) else Path(".")
    try:
        entries = list(parent.iterdir())
    except OSError:
        return removed
    for e in entries:
        m = _TMP_RE.match(e.name)
        if not m or (m["host"] or _HOST) != _HOST or _alive(int(m["pid"])):
            continue  # not a temporary, written on another machine, or its process still runs
        try:
            if e.is_dir() and not e.is_symlink():
                shutil.rmtree(e)
            else:
                e.unlink()
            removed.append(e)
        except OSError:
            pass
    return removed


def remove_stale_temps_in(folder: str | Path) -> list[Path]:
    """:func:`remove_stale_temps` for every temporary directly inside ``folder``."""
    return remove_stale_temps(Path(folder) / "x")


# ------------------------------------------------------------- output path checks
def _why(err: OSError) -> str:
    return err.strerror or errno.errorcode.get(err.errno or 0, str(err))


def _probe_dir_writable(directory: Path, flag: str, target: Path) -> None:
    """Create and remove a file in ``directory``: the only reliable writability test
    (``os.access`` says yes to root on read-only or virtual file systems such as /proc)."""
    probe = directory / f".twin-probe.{_HOST}-{os.getpid()}.tmp"  # fits wherever the target fits
    try:
        fd = os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError as err:
        raise TwinError(f"cannot write in {show(directory)} ({_why(err)})", field=flag) from None
    os.close(fd)
    try:
        os.unlink(probe)
    except OSError:
        pass


def show(path: str | Path) -> str:
    """A path for a one-line message: control characters (a newline in a name) escaped."""
    text = str(path)
    if any(ord(c) < 32 or ord(c) == 127 for c in text):
        return text.encode("unicode_escape", "backslashreplace").decode("ascii")
    return text


def check_path_name(path: str | Path, flag: str) -> Path:
    """A path given on the command line: not empty, each name within the file system's
    NAME_MAX and the whole within PATH_MAX, no symbolic-link loop on the way. One line naming
    ``flag`` otherwise."""
    text = os.fspath(path)
    if not text.strip():
        raise TwinError(f"is empty; give a path", field=flag)
    p = Path(text)
    limit = _name_max(p.parent if str(p.parent) else Path("."))
    for part in p.parts:
        if len(os.fsencode(part)) > limit:
            raise TwinError(f"the name {show(part[:40])}... is {len(os.fsencode(part))} bytes long; "
                            f"the file system allows {limit}", field=flag)
    if len(os.fsencode(text)) >= 4096:
        raise TwinError(f"the path is {len(os.fsencode(text))} bytes long; the system allows 4095", field=flag)
    for q in (p, *p.parents):
        try:
            os.stat(q)
        except OSError as err:
            if err.errno == errno.ELOOP:
                raise TwinError(f"{show(q)} is a symbolic-link loop", field=flag) from None
            if err.errno == errno.ENAMETOOLONG:
                raise TwinError(f"{show(q)}: name too long", field=flag) from None
    return p


#: inputs the running command reads (:func:`reading`): (path, whether it is read as a folder)
_READING: list[tuple[str, bool]] = []


@contextmanager
def reading(files: Iterable[str | Path | None], folders: Iterable[str | Path | None] = ()) -> Iterator[None]:
    """Register the files and folders a command reads while it runs: every output checked by
    :func:`check_output_file`, :func:`check_output_dir` or written by :func:`atomic_write_bytes`
    meanwhile is refused when it is one of them or lies inside one of the ``folders`` (the command
    line registers the input arguments of every command, so no command can forget one). A path
    given where a file is read is only compared, never taken as a folder: a folder given there is
    refused by its reader, naming the option."""
    added = [(os.fspath(p), folder) for ps, folder in ((files, False), (folders, True)) for p in ps
             if p is not None and os.fspath(p).strip()]
    _READING.extend(added)
    try:
        yield
    finally:
        for a in added:
            _READING.remove(a)


def _aliases(out: Path, inputs: Iterable[str | Path], holds: bool, folders: Iterable[str | Path] = ()
             ) -> tuple[str, str] | None:
    """(input, how) for the first of ``inputs`` (files), ``folders`` and of the registered :func:`reading`
    inputs that the output ``out`` would write over or into: the same file (through any link), a path
    inside an input folder (a dataset being read), or (``holds``: a folder replaced whole) a folder
    holding an input. None when the output touches no input."""
    try:
        here = out.resolve()
    except (OSError, RuntimeError):
        return None  # a loop: refused by check_path_name
    for i, folder in (*((i, False) for i in inputs), *((f, True) for f in folders), *_READING):
        if i is None or not os.fspath(i).strip():
            continue
        try:
            ip = Path(i).resolve()
        except (OSError, RuntimeError):
            continue
        if here == ip:
            return os.fspath(i), "is"
        if folder and ip in here.parents:
            return os.fspath(i), "lies inside"
        if holds and here in ip.parents:
            return os.fspath(i), "holds"
    return None


def check_not_input(out: str | Path, flag: str, inputs: Iterable[str | Path] = (), holds: bool = False,
                    folders: Iterable[str | Path] = ()) -> None:
    """Refuse (one line naming ``flag``) an output that is or lies inside one of ``inputs`` or of the
    inputs the command registered (:func:`reading`), and with ``holds`` one that holds an input: the
    one rule that keeps an input being read from being written over (``dataset info DIR --json
    DIR/info.json``, a model written into the dataset it is trained on)."""
    hit = _aliases(Path(out), inputs, holds, folders)
    if hit is not None:
        raise TwinError(f"{show(out)} {hit[1]} the input {show(hit[0])}, which this command reads; "
                        "choose an output outside every input", field=flag)


def check_output_file(path: str | Path, flag: str, suffixes: str | Iterable[str],
                      inputs: Iterable[str | Path] = (), folders: Iterable[str | Path] = ()) -> Path:
    """Check an output file given on the command line before any work starts.

    It must end in one of ``suffixes``, its folder must exist and be writable, it must not be a
    folder, nor a symbolic link, nor one of ``inputs`` (files) or a path inside one of ``folders`` or
    of what the command registered as read (:func:`reading`); its name must fit the file system
    (:func:`check_path_name`).
    Stale temporary files in its folder are removed. Raises a one-line :class:`TwinError` naming
    ``flag`` otherwise. Nothing is created.
    """
    out = check_path_name(path, flag)
    allowed = (suffixes,) if isinstance(suffixes, str) else tuple(suffixes)
    if out.suffix.lower() not in allowed or out.name.startswith(".") and out.name == out.suffix:
        raise TwinError(f"must end in {' or '.join(allowed)}, got {show(out)!r}", field=flag)
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.exists():
        raise TwinError(f"directory {show(parent)} does not exist", field=flag)
    if not parent.is_dir():
        raise TwinError(f"{show(parent)} is not a directory", field=flag)
    if out.is_dir():
        raise TwinError(f"{show(out)} is a directory", field=flag)
    if out.is_symlink() and not out.exists():
        raise TwinError(f"{show(out)} is a dangling symbolic link", field=flag)
    if out.exists() and not out.is_file():
        raise TwinError(f"{show(out)} exists and is not a regular file", field=flag)
    check_not_input(out, flag, inputs, folders=folders)
    if out.is_symlink():  # refused now, not after the work (the writers never replace a link: check_not_link)
        raise TwinError(f"{show(out)} is a symbolic link; the twin writes regular files, never through "
                        "a link: name the file itself or another one", field=flag)
    _probe_dir_writable(parent, flag, out)
    remove_stale_temps(out)
    return out


def check_output_dir(path: str | Path, flag: str = "out", need_parent: bool = True,
                     own: Callable[[str], bool] | None = None, inputs: Iterable[str | Path] = ()) -> Path:
    """An output folder given on the command line: it may exist (as a folder) or be created (in an
    existing parent unless ``need_parent`` is False, for callers that create parents). The
    folder that will hold it must be writable. Raises TwinError naming ``flag`` otherwise.

    A command that replaces the folder whole passes ``own``, which tells the names it writes:
    an existing folder holding anything else (the user's files, the input) is refused, so that
    nothing the command did not write is ever deleted. No ``inputs`` may lie inside it."""
    out = check_path_name(path, flag)
    if out.exists() and not out.is_dir():
        raise TwinError(f"{show(out)} exists and is not a directory", field=flag)
    if out.is_symlink() and not out.exists():
        raise TwinError(f"{show(out)} is a dangling symbolic link", field=flag)
    here = out.resolve()
    inputs = tuple(inputs)
    check_not_input(out, flag, inputs, holds=own is not None or bool(inputs))  # a folder replaced whole
    if own is not None and (out.name in ("", ".", "..") or here == Path.cwd().resolve() or here == here.parent):
        raise TwinError(f"{show(path)!r} names the current or a parent folder, which this command would "
                        "replace whole; give a new folder name", field=flag)
    if own is not None and out.is_dir():
        foreign = sorted(e.name for e in out.iterdir() if not own(e.name) and not _TMP_RE.match(e.name))
        if foreign:
            listed = ", ".join(show(n) for n in foreign[:3]) + (", ..." if len(foreign) > 3 else "")
            raise TwinError(f"{show(out)} holds files this command did not write ({listed}); "
                            "it would be replaced whole: give a new or empty folder", field=flag)
    parent = out.parent if str(out.parent) else Path(".")
    if need_parent and not parent.exists():
        raise TwinError(f"parent directory {show(parent)} does not exist", field=flag)
    probe_in = parent
    while not probe_in.exists():
        probe_in = probe_in.parent
    if not probe_in.is_dir():
        raise TwinError(f"{show(probe_in)} is not a directory", field=flag)
    _probe_dir_writable(probe_in, flag, out)
    remove_stale_temps(out)
    return out


# ------------------------------------------------------------------------ input files
#: largest text input (configuration, spec) read [bytes]
MAX_TEXT_BYTES = 16 * 1024 * 1024


def check_input_file(path: str | Path, flag: str, max_bytes: int | None = None) -> Path:
    """An input file given on the command line, checked before any read: it exists, is a
    regular file (a FIFO, a device such as /dev/zero or a folder would hang or never end) and
    is at most ``max_bytes`` long. One line naming ``flag`` otherwise."""
    text = os.fspath(path)
    if not text.strip():
        raise TwinError(f"is empty; give a file", field=flag)
    p = Path(text)
    try:
        st = os.stat(p)
    except OSError as err:
        raise TwinError(f"cannot read {show(p)} ({_why(err)})", field=flag) from None
    if stat.S_ISDIR(st.st_mode):
        raise TwinError(f"{show(p)} is a directory, not a file", field=flag)
    if not stat.S_ISREG(st.st_mode):
        raise TwinError(f"{show(p)} is not a regular file (a pipe or device); give a file", field=flag)
    if max_bytes is not None and st.st_size > max_bytes:
        raise TwinError(f"{show(p)} is {st.st_size} bytes; at most {max_bytes} are read", field=flag)
    return p


def read_input_bytes(path: str | Path, flag: str, max_bytes: int = MAX_TEXT_BYTES) -> bytes:
    """The bytes of an input file after :func:`check_input_file`."""
    p = check_input_file(path, flag, max_bytes)
    try:
        with open(p, "rb") as fh:
            return fh.read(max_bytes + 1)[:max_bytes]
    except OSError as err:
        raise TwinError(f"cannot read {show(p)} ({_why(err)})", field=flag) from None


#: deepest nesting of tables and arrays accepted in TOML input
MAX_TOML_DEPTH = 32


def toml_loads(text: str) -> dict[str, Any]:
    """``tomllib.loads`` that refuses deep nesting as a TOMLDecodeError (one line) instead of a
    RecursionError (nothing the twin reads is nested more than a few levels) and reads a text that starts
    with a UTF-8 byte-order mark as without it."""
    import tomllib

    try:
        data = tomllib.loads(text.removeprefix("\ufeff"))  # a byte-order mark (Windows editors write one)
    except RecursionError:
        raise tomllib.TOMLDecodeError(f"tables or arrays nested deeper than {MAX_TOML_DEPTH} levels") from None
    stack: list[tuple[Any, int]] = [(data, 1)]
    while stack:
        obj, d = stack.pop()
        if d > MAX_TOML_DEPTH:
            raise tomllib.TOMLDecodeError(f"tables or arrays nested deeper than {MAX_TOML_DEPTH} levels")
        if isinstance(obj, dict):
            stack.extend((v, d + 1) for v in obj.values())
        elif isinstance(obj, list):
            stack.extend((v, d + 1) for v in obj)
    return data


# -------------------------------------------------------------------- atomic writes
def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to a temporary file beside ``path`` and rename it into place."""
    p = Path(path)
    if not p.parent.exists():
        raise TwinError(f"{p}: directory {p.parent} does not exist")
    check_not_input(p, show(p))  # the last guard: an input being read is never written over
    tmp = temp_path(p)
    created = False
    try:
        try:
            fd = open_new(tmp)
            created = True
            with os.fdopen(fd, "wb") as fh:
                fh.write(data)
            check_not_link(p)
            os.replace(tmp, p)
        except OSError as err:
            # the file named is the one the user asked for, whichever step failed (not the temporary)
            raise TwinError(f"{show(p)}: cannot write ({_why(err)})") from None
    finally:
        if created:
            tmp.unlink(missing_ok=True)
    return p


#: flags of a file the twin creates: never through a symbolic link, never over an existing file
NEW_FILE_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)


def open_new(path: str | Path, mode: int = 0o644) -> int:
    """A descriptor of a new file at ``path`` (a temporary): created here, never an existing file
    and never the target of a symbolic link planted at that name (``O_CREAT | O_EXCL |
    O_NOFOLLOW``). A leftover of this very process (a retried write) is removed first."""
    try:
        return os.open(path, NEW_FILE_FLAGS, mode)
    except FileExistsError:
        if stat.S_ISLNK(os.lstat(path).st_mode) or not stat.S_ISREG(os.lstat(path).st_mode):
            raise
        os.unlink(path)  # our own name (host and PID): an earlier attempt of this process
        return os.open(path, NEW_FILE_FLAGS, mode)


def check_not_link(path: str | Path) -> None:
    """OSError (ELOOP) when ``path`` is a symbolic link: a file the twin owns is replaced by a rename,
    which would replace the link itself; refusing keeps a link the user made (and its target) as it is."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return
    if stat.S_ISLNK(st.st_mode):
        raise OSError(errno.ELOOP, "it is a symbolic link; the twin does not write through links", str(path))


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Text version of :func:`atomic_write_bytes` (UTF-8)."""
    return atomic_write_bytes(path, text.encode())


def atomic_write_json(path: str | Path, obj: Any) -> Path:
    """Pretty JSON, written atomically."""
    return atomic_write_text(path, json_text(obj) + "\n")


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


# ---------------------------------------------------------------------- folder lock
class FolderLock:
    """An exclusive lock on an output folder held while a command writes there (``twin dataset
    generate``): a second writer is refused in one line naming the holder's host and PID.

    The lock is ``fcntl.flock`` on the file ``.twin.lock`` in the folder; the holder writes its
    host, PID and start time into it for the message. The kernel releases a flock when its
    holder's last descriptor closes, which includes death by SIGKILL: a lock of a process that no
    longer exists is never stale, the next run simply takes it (and overwrites the holder line).
    The file itself is kept (emptied) on release: unlinking it would let a third process lock a
    new file while a second still holds the old one. On a local disk this is exact. On NFS, Linux
    maps flock to NFS byte-range locks (NLM for v3, the v4 lock state): two hosts do exclude each
    other, and a dead client's lock is released when the server's lease expires (about 90 s on
    v4) or, on v3, when the client's lock daemon recovers — until then the run is refused and
    the message names the holder so a user can check it.
    """

    NAME = ".twin.lock"

    def __init__(self, folder: str | Path, flag: str = "out", what: str = "twin"):
        self.folder = Path(folder)
        self.flag, self.what = flag, what
        self.fd: int | None = None

    def acquire(self) -> "FolderLock":
        import fcntl
        import time

        path = self.folder / self.NAME
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC | getattr(os, "O_NOFOLLOW", 0), 0o644)
        except OSError as err:
            if err.errno == errno.ELOOP:  # a link planted as the lock: never followed (its target truncated)
                raise TwinError(f"{show(path)} is a symbolic link; the lock file is the twin's own: "
                                "remove the link", field=self.flag) from None
            raise TwinError(f"cannot lock {show(self.folder)} ({_why(err)})", field=self.flag) from None
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            os.close(fd)
            raise TwinError(f"{show(path)} is not a regular file; the lock file is the twin's own: "
                            "remove it", field=self.flag)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            holder = ""
            try:
                holder = os.pread(fd, 200, 0).decode("utf-8", "replace").strip()
            except OSError:
                pass
            os.close(fd)
            if err.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise TwinError(f"{show(self.folder)} is in use by another {self.what} "
                                f"({show(holder) or 'holder unknown'}); wait for it to end", field=self.flag) from None
            raise TwinError(f"cannot lock {show(self.folder)} ({_why(err)})", field=self.flag) from None
        line = f"host {socket.gethostname()} pid {os.getpid()} since {time.strftime('%Y-%m-%d %H:%M:%S')}\n"
        os.ftruncate(fd, 0)
        os.pwrite(fd, line.encode(), 0)
        self.fd = fd
        return self

    def release(self) -> None:
        if self.fd is not None:
            try:
                os.ftruncate(self.fd, 0)
            except OSError:
                pass
            os.close(self.fd)  # releases the flock
            self.fd = None

    def __enter__(self) -> "FolderLock":
        return self.acquire()

    def __exit__(self, *exc: object) -> None:
        self.release()
