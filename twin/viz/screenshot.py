"""Headless screenshot of a recording's default view (for documentation and checks).

Starts rerun's viewer in headless mode (``--headless``: an offscreen window driven by the
viewer itself, no X server needed) with the Vulkan renderer, which on a machine without a GPU
is Mesa's software rasterizer (Debian: ``apt-get install mesa-vulkan-drivers``). twin starts
the viewer process itself (:class:`HeadlessViewer`: the flags ``ViewerClient.spawn`` would pass,
plus the window size, which ``spawn`` cannot set), so the exit status it reads is the viewer's
own; it connects ``rerun.experimental.ViewerClient`` once the port listens, opens the recording,
sets the time cursor, waits until nothing is loading and two screenshots in a row are identical
(at most ``wait_s``), and writes the PNG.

What the machine needs is checked before any work (:func:`check_vulkan`, called by ``twin view``
before it converts): on Linux a Vulkan installable client driver (ICD) must be registered where
the Vulkan loader looks for one: the ``.json`` manifests listed in ``$VK_DRIVER_FILES`` (or the
older ``$VK_ICD_FILENAMES``; files or folders, ``:``-separated), which replace the search, plus
``$VK_ADD_DRIVER_FILES``; otherwise ``vulkan/icd.d`` under ``$XDG_CONFIG_HOME`` (~/.config),
``$XDG_CONFIG_DIRS`` (/etc/xdg), /usr/local/etc, /etc, ``$XDG_DATA_HOME`` (~/.local/share),
``$XDG_DATA_DIRS`` (/usr/local/share, /usr/share). No manifest = no driver: a one-line
:class:`TwinError`, where rerun would panic. A driver that is registered but cannot render (no
adapter, a broken library) makes the viewer exit: its output goes to a log and the error line
quotes the viewer's own message (the panic or "Error:" line). Other systems are not checked.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator

from twin.errors import TwinError
from twin.util import check_size_px, temp_path

#: System folders the Vulkan loader searches for ICD manifests on Linux (besides the XDG ones).
SYSTEM_ICD_DIRS: tuple[str, ...] = ("/usr/local/etc/vulkan/icd.d", "/etc/vulkan/icd.d",
                                    "/usr/local/share/vulkan/icd.d", "/usr/share/vulkan/icd.d")
#: Seconds between checks that the headless viewer still runs while it loads.
POLL_S = 0.25
#: Seconds the headless viewer may take to listen on its port.
START_TIMEOUT_S = 30.0
_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")


def icd_search_dirs() -> list[Path]:
    """Folders the Vulkan loader searches for ICD manifests (Linux), without override variables."""
    home = Path(os.environ.get("HOME") or "~").expanduser()
    config_home = os.environ.get("XDG_CONFIG_HOME") or str(home / ".config")
    config_dirs = (os.environ.get("XDG_CONFIG_DIRS") or "/etc/xdg").split(os.pathsep)
    data_home = os.environ.get("XDG_DATA_HOME") or str(home / ".local" / "share")
    data_dirs = (os.environ.get("XDG_DATA_DIRS") or "/usr/local/share:/usr/share").split(os.pathsep)
    dirs = [Path(d) / "vulkan" / "icd.d" for d in [config_home, *config_dirs] if d]
    dirs += [Path(d) for d in SYSTEM_ICD_DIRS]
    dirs += [Path(d) / "vulkan" / "icd.d" for d in [data_home, *data_dirs] if d]
    out: list[Path] = []
    for d in dirs:
        if d not in out:
            out.append(d)
    return out


def _manifests(entries: list[str] | list[Path]) -> list[Path]:
    found: list[Path] = []
    for e in entries:
        p = Path(e)
        if not str(e):
            continue
        if p.is_file():
            found.append(p)
        elif p.is_dir():
            found.extend(sorted(q for q in p.glob("*.json") if q.is_file()))
    return found


def vulkan_drivers() -> list[Path]:
    """The Vulkan ICD manifests the loader would find (see the module docstring)."""
    override = os.environ.get("VK_DRIVER_FILES") or os.environ.get("VK_ICD_FILENAMES")
    entries = override.split(os.pathsep) if override else icd_search_dirs()
    extra = os.environ.get("VK_ADD_DRIVER_FILES", "")
    return _manifests(list(entries) + (extra.split(os.pathsep) if extra else []))


def check_vulkan(flag: str = "png") -> None:
    """Raise a one-line :class:`TwinError` if no Vulkan driver is registered (Linux only)."""
    if not sys.platform.startswith("linux") or vulkan_drivers():
        return
    if os.environ.get("VK_DRIVER_FILES") or os.environ.get("VK_ICD_FILENAMES"):
        where = "in $VK_DRIVER_FILES / $VK_ICD_FILENAMES"
    else:
        where = "in " + ", ".join(str(d) for d in SYSTEM_ICD_DIRS) + " or the XDG folders"
    raise TwinError(f"no Vulkan driver found (no ICD manifest {where}); the headless viewer renders "
                    "with Vulkan: install one (Debian: apt-get install mesa-vulkan-drivers) or leave out "
                    f"{flag}", field=flag)


def viewer_message(text: str | bytes) -> str:
    """One line from a rerun viewer's output saying why it stopped: its panic message, else its
    last ``Error:`` line, else its last line."""
    if isinstance(text, bytes):
        text = text.decode("utf-8", "replace")
    lines = [ln.strip() for ln in _ANSI.sub("", text).splitlines() if ln.strip()]
    msg = ""
    for i, ln in enumerate(lines):
        if "panicked at" in ln:
            m = re.search(r"panicked at '(.*)'", ln)
            if m:
                msg = m.group(1)
            elif i + 1 < len(lines):
                msg = lines[i + 1]
            break
    if not msg:
        errors = [ln for ln in lines if ln.startswith("Error:")]
        msg = errors[-1] if errors else (lines[-1] if lines else "no message")
    msg = re.sub(r" at \S+\.rs:\d+(?::\d+)?:", ":", " ".join(msg.split()))  # drop Rust source locations
    return msg if len(msg) <= 300 else msg[:297] + "..."


@contextlib.contextmanager
def _stderr_to(path: Path) -> Iterator[None]:
    """Send file descriptor 2 to ``path`` meanwhile: the rerun SDK's Rust logger writes there
    directly (e.g. a warning when a spawned viewer dies before it binds its port)."""
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(path, "ab") as fh:
            os.dup2(fh.fileno(), 2)
            try:
                yield
            finally:
                sys.stderr.flush()
                os.dup2(saved, 2)
    finally:
        os.close(saved)


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def check_screenshot_args(wait_s: float, at_s: float | None, window: tuple[int, int]) -> None:
    """The one check of :func:`screenshot`'s settings (a front end calls it before its long work):
    a one-line :class:`TwinError` naming the argument otherwise."""
    if not (isinstance(wait_s, (int, float)) and math.isfinite(wait_s) and wait_s >= 0):
        raise TwinError(f"must be a finite number of seconds >= 0, got {wait_s!r}", field="wait_s")
    if at_s is not None and not (isinstance(at_s, (int, float)) and math.isfinite(at_s)):
        raise TwinError(f"must be a finite time [s], got {at_s!r}", field="at_s")
    check_size_px(window, "window")


def rerun_executable() -> Path:
    """The ``rerun`` viewer of this environment (from rerun-sdk), or a one-line TwinError."""
    exe = Path(sys.executable).with_name("rerun")
    if not exe.is_file():
        raise TwinError(f"the rerun viewer ({exe}, from rerun-sdk) is not installed", field="png")
    return exe


def viewer_command(exe: str | Path, port: int, window: tuple[int, int]) -> list[str]:
    """Command line of the headless viewer: the flags ``rerun.experimental.ViewerClient.spawn``
    passes (rerun 0.41), plus the window size and the Vulkan renderer."""
    return [str(exe), f"--port={port}", "--memory-limit=75%", "--server-memory-limit=1GiB", "--hide-welcome-screen",
            "--headless", "--window-size", f"{window[0]}x{window[1]}", "--renderer", "vulkan"]


class HeadlessViewer:
    """A headless rerun viewer process this process started and owns: its exit status is
    ``Popen.poll()`` (no launcher script, no status file), its output goes to ``log``, and
    :meth:`stop` ends its process group. ``client`` is a ViewerClient once :meth:`connect` has
    seen the port listening."""

    def __init__(self, command: list[str], log: Path, runtime_dir: Path):
        env = dict(os.environ, RUST_LOG="error", RUST_BACKTRACE="0", RERUN_APP_ONLY="true",
                   XDG_RUNTIME_DIR=str(runtime_dir))
        self.log = log
        self.port = int(next(a for a in command if a.startswith("--port="))[len("--port="):])
        with open(log, "wb") as out:
            self.proc = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=out, stderr=out, env=env,
                                         start_new_session=True)
        self.client = None

    def status(self) -> int | None:
        """The viewer's exit status, or None while it runs."""
        return self.proc.poll()

    def error(self, what: str) -> TwinError:
        """One-line error: the viewer's exit status and message if it ended, else ``what``."""
        code = self.status()
        if code is None:  # a failing call may come just before the exit: give it a moment
            try:
                code = self.proc.wait(timeout=POLL_S)
            except subprocess.TimeoutExpired:
                code = None
        out = self.log.read_bytes() if self.log.is_file() else b""
        if code is None:
            return TwinError(f"the headless viewer {what}", field="png")
        return TwinError(f"the headless viewer exited (status {code}): "
                         f"{viewer_message(out) if out.strip() else what}", field="png")

    def connect(self, timeout_s: float = START_TIMEOUT_S):
        """Wait until the viewer listens on its port (or exits: error), then connect a client."""
        import rerun as rr

        deadline = time.monotonic() + timeout_s
        while True:
            if self.status() is not None:
                raise self.error("stopped while starting")
            try:
                socket.create_connection(("127.0.0.1", self.port), timeout=POLL_S).close()
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise self.error(f"did not listen on port {self.port} within {timeout_s:g} s") from None
                time.sleep(min(POLL_S, max(deadline - time.monotonic(), 0.0)) or 0.01)
        try:
            self.client = rr.experimental.ViewerClient(f"rerun+http://127.0.0.1:{self.port}/proxy")
        except Exception as err:  # noqa: BLE001 - the viewer went away between the port check and the connection
            # (rerun raises its own transport errors, not OSError): the viewer's state and log say why
            raise self.error(f"did not answer ({type(err).__name__}: "
                             f"{' '.join(str(err).split()) or 'no message'})") from None
        return self.client

    def stop(self) -> None:
        """End the viewer's process group (SIGTERM, SIGKILL after 5 s)."""
        for sig, wait in ((signal.SIGTERM, 5.0), (signal.SIGKILL, 5.0)):
            if self.status() is not None:
                break
            with contextlib.suppress(OSError):
                os.killpg(self.proc.pid, sig)
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.proc.wait(timeout=wait)


@dataclass(frozen=True)
class Shot:
    """A saved screenshot: where, after how long [s], and whether the view had settled."""

    path: Path
    seconds: float
    settled: bool


def capture(client, alive: Callable[[], bool], wait_s: float, clock: Callable[[], float] = time.monotonic,
            sleep: Callable[[float], None] = time.sleep) -> tuple[bytes, bool]:
    """PNG bytes of the viewer's window once its view has settled, and whether it did.

    Waits until nothing is loading (``get_state().loading`` empty), then takes screenshots until
    two in a row are identical (the plots' bounds and lazily fetched chunks stop changing); at
    the latest after ``wait_s`` seconds [s] it takes the picture as it is (settled = False). A
    call that times out (the client waits 15 s) is repeated until then.
    ``alive()`` False (the viewer exited) raises :class:`TwinError`; ``clock`` and ``sleep``
    (seconds) are replaceable for tests."""
    deadline = clock() + wait_s
    last: bytes | None = None
    while clock() < deadline:
        if not alive():
            raise TwinError("the headless viewer stopped while loading")
        try:
            if client.get_state().loading:
                sleep(min(POLL_S, max(deadline - clock(), 0.0)))
                continue
            img = client.take_screenshot()
        except TimeoutError:  # a busy software renderer can miss the client's 15 s deadline: ask again
            last = None
            continue
        if img == last:
            return img, True
        last = img
    if not alive():
        raise TwinError("the headless viewer stopped while loading")
    return client.take_screenshot(), False


def screenshot(rrd: str | Path, png: str | Path, *, at_s: float | None = None, wait_s: float = 60.0,
               window: tuple[int, int] = (1920, 1080), port: int | None = None) -> Shot:
    """Save a PNG of ``rrd``'s default view with the time cursor at ``at_s`` [s] (paused).

    Waits at most ``wait_s`` [s] for the recording to load and the view to settle (see
    :func:`capture`); ``window``: the window size [px]; ``port``: the viewer's gRPC port
    (default: a free one). Raises a one-line :class:`TwinError` if no Vulkan driver is
    registered, or if the viewer exits or fails while starting, loading or saving (quoting its
    message); the PNG is written to a temporary name and renamed when complete."""
    rrd, png = Path(rrd).resolve(), Path(png).resolve()
    if not rrd.is_file():
        raise TwinError(f"{rrd}: no such recording")
    if png.suffix.lower() != ".png" or not png.parent.is_dir():
        raise TwinError(f"{png} must be a .png in an existing directory", field="png")
    check_screenshot_args(wait_s, at_s, window)
    check_vulkan()
    exe = rerun_executable()
    t0 = time.monotonic()
    with tempfile.TemporaryDirectory() as d:
        viewer = HeadlessViewer(viewer_command(exe, port or _free_port(), window), Path(d) / "viewer.log", Path(d))
        tmp = temp_path(png, keep_suffix=True)
        try:
            with _stderr_to(Path(d) / "sdk.log"):  # the SDK's Rust logger writes to fd 2 directly
                client = viewer.connect()
                try:
                    client.open(str(rrd))
                    if at_s is not None:
                        client.set_time("time", duration=float(at_s), play_state="paused")
                    img, settled = capture(client, lambda: viewer.status() is None, float(wait_s))
                except TwinError:
                    raise viewer.error("stopped while loading") from None
                except Exception as err:  # noqa: BLE001 - OSError, RuntimeError, rerun's transport errors
                    raise viewer.error(f"did not answer ({type(err).__name__}: "
                                       f"{' '.join(str(err).split()) or 'no message'})") from None
            if not img.startswith(b"\x89PNG\r\n\x1a\n"):
                raise viewer.error("sent no PNG image")
            tmp.write_bytes(img)
            os.replace(tmp, png)
        finally:
            tmp.unlink(missing_ok=True)
            viewer.stop()
    return Shot(png, time.monotonic() - t0, settled)
