"""Headless screenshot of a recording's default view (for documentation and checks).

Starts rerun's viewer in headless mode (``--headless``: an offscreen window driven by the
viewer itself, no X server needed) with the Vulkan renderer, which on a machine without a GPU
is Mesa's software rasterizer (Debian: ``apt-get install mesa-vulkan-drivers``). The recording
is opened, the time cursor set, and after ``wait_s`` (the viewer loads chunks lazily and the
software renderer is slow) the whole window is saved as PNG through
``rerun.experimental.ViewerClient``.

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
import stat
import sys
import tempfile
import time
from pathlib import Path
from typing import Iterator

from twin.errors import TwinError
from twin.util import temp_path

#: System folders the Vulkan loader searches for ICD manifests on Linux (besides the XDG ones).
SYSTEM_ICD_DIRS: tuple[str, ...] = ("/usr/local/etc/vulkan/icd.d", "/etc/vulkan/icd.d",
                                    "/usr/local/share/vulkan/icd.d", "/usr/share/vulkan/icd.d")
#: Seconds between checks that the headless viewer still runs while it loads.
POLL_S = 0.25
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


def check_vulkan(flag: str = "--screenshot") -> None:
    """Raise a one-line :class:`TwinError` if no Vulkan driver is registered (Linux only)."""
    if not sys.platform.startswith("linux") or vulkan_drivers():
        return
    if os.environ.get("VK_DRIVER_FILES") or os.environ.get("VK_ICD_FILENAMES"):
        where = "in $VK_DRIVER_FILES / $VK_ICD_FILENAMES"
    else:
        where = "in " + ", ".join(str(d) for d in SYSTEM_ICD_DIRS) + " or the XDG folders"
    raise TwinError(f"{flag}: no Vulkan driver found (no ICD manifest {where}); the headless viewer renders "
                    "with Vulkan: install one (Debian: apt-get install mesa-vulkan-drivers) or leave out "
                    f"{flag}")


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


def rerun_executable() -> Path:
    """The ``rerun`` viewer of this environment (from rerun-sdk), or a one-line TwinError."""
    exe = Path(sys.executable).with_name("rerun")
    if not exe.is_file():
        raise TwinError(f"--screenshot: the rerun viewer ({exe}, from rerun-sdk) is not installed")
    return exe


def screenshot(rrd: str | Path, png: str | Path, *, at_s: float | None = None, wait_s: float = 60.0,
               window: tuple[int, int] = (1600, 900), port: int | None = None) -> Path:
    """Save a PNG of ``rrd``'s default view with the time cursor at ``at_s`` [s] (paused).

    ``port``: the viewer's gRPC port (default: a free one). Raises a one-line :class:`TwinError`
    if no Vulkan driver is registered, or if the viewer exits or fails while loading or saving
    (quoting its message); the PNG is written to a temporary name and renamed when complete."""
    import rerun as rr

    rrd, png = Path(rrd).resolve(), Path(png).resolve()
    if not rrd.is_file():
        raise TwinError(f"{rrd}: no such recording")
    if png.suffix != ".png" or not png.parent.is_dir():
        raise TwinError(f"--screenshot: {png} must be a .png in an existing directory")
    if not (isinstance(wait_s, (int, float)) and math.isfinite(wait_s) and wait_s >= 0):
        raise TwinError(f"--wait: must be a finite number of seconds >= 0, got {wait_s!r}")
    if at_s is not None and not (isinstance(at_s, (int, float)) and math.isfinite(at_s)):
        raise TwinError(f"--at: must be a finite time [s], got {at_s!r}")
    check_vulkan()
    exe = rerun_executable()
    port = port or _free_port()
    with tempfile.TemporaryDirectory() as d:
        # ViewerClient.spawn has no window-size option: a tiny launcher adds the viewer flags; the
        # viewer's output goes to a log (quoted on failure) and its exit status to a file
        log, status, pidfile = Path(d) / "viewer.log", Path(d) / "exit-status", Path(d) / "pid"
        launcher = Path(d) / "rerun-headless"
        launcher.write_text(f'#!/bin/sh\necho $$ >"{pidfile}"\n'
                            f'export RUST_LOG=error RUST_BACKTRACE=0 XDG_RUNTIME_DIR="{d}"\n'
                            f'"{exe}" --window-size {window[0]}x{window[1]} --renderer vulkan "$@" '
                            f'>"{log}" 2>&1\necho $? >"{status}"\n')
        launcher.chmod(launcher.stat().st_mode | stat.S_IXUSR)

        def failed(what: str) -> TwinError:
            out = log.read_bytes() if log.is_file() else b""
            code = status.read_text().strip() if status.is_file() else ""
            ended = f"the headless viewer exited (status {code})" if code else f"the headless viewer {what}"
            return TwinError(f"--screenshot: {ended}: {viewer_message(out) if out.strip() else what}")

        client = None
        tmp = temp_path(png, keep_suffix=True)
        with _stderr_to(Path(d) / "sdk.log"):
            try:
                client = rr.experimental.ViewerClient.spawn(headless=True, executable_path=str(launcher), port=port,
                                                            hide_welcome_screen=True)
                client.open(str(rrd))
                if at_s is not None:
                    client.set_time("time", duration=float(at_s), play_state="paused")
                deadline = time.monotonic() + wait_s
                while (left := deadline - time.monotonic()) > 0:  # let it load; stop early if it dies
                    if status.is_file():
                        raise failed("stopped while loading")
                    time.sleep(min(POLL_S, left))
                client.save_screenshot(str(tmp))
                if not tmp.is_file():
                    raise failed("wrote no image")
                os.replace(tmp, png)
            except (OSError, RuntimeError, ValueError) as err:  # ConnectionError, TimeoutError: OSError
                time.sleep(POLL_S)  # a dying viewer: let the launcher record its status
                raise failed(f"did not answer ({type(err).__name__}: {' '.join(str(err).split()) or 'no message'})") \
                    from None
            finally:
                tmp.unlink(missing_ok=True)
                if client is not None:
                    try:
                        client.quit()
                    except (OSError, RuntimeError):
                        pass
                elif pidfile.is_file() and not status.is_file():  # spawned, never connected: end its process group
                    try:
                        os.killpg(int(pidfile.read_text().strip()), signal.SIGTERM)
                    except (OSError, ValueError):
                        pass
    return png
