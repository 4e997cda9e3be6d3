"""Headless screenshot of a recording's default view (for documentation and checks).

Starts rerun's viewer in headless mode (``--headless``: an offscreen window driven by the
viewer itself, no X server needed) with the Vulkan renderer, which on a machine without a GPU
is Mesa's software rasterizer (Debian: ``apt-get install mesa-vulkan-drivers``). The recording
is opened, the time cursor set, and after ``wait_s`` (the viewer loads chunks lazily and the
software renderer is slow) the whole window is saved as PNG through
``rerun.experimental.ViewerClient``.
"""

from __future__ import annotations

import os
import stat
import sys
import tempfile
import time
from pathlib import Path

from twin.errors import TwinError


def screenshot(rrd: str | Path, png: str | Path, *, at_s: float | None = None, wait_s: float = 60.0,
               window: tuple[int, int] = (1600, 900), port: int = 9886) -> Path:
    """Save a PNG of ``rrd``'s default view with the time cursor at ``at_s`` [s] (paused)."""
    import rerun as rr

    rrd, png = Path(rrd).resolve(), Path(png).resolve()
    if not rrd.is_file():
        raise TwinError(f"{rrd}: no such recording")
    if png.suffix != ".png" or not png.parent.is_dir():
        raise TwinError(f"{png}: must be a .png in an existing directory")
    exe = Path(sys.executable).with_name("rerun")
    with tempfile.TemporaryDirectory() as d:
        # ViewerClient.spawn has no window-size option: a tiny launcher adds the viewer flags
        launcher = Path(d) / "rerun-headless"
        launcher.write_text(f'#!/bin/sh\nexport RUST_LOG=error XDG_RUNTIME_DIR="{d}"\n'
                            f'exec "{exe}" --window-size {window[0]}x{window[1]} --renderer vulkan "$@"\n')
        launcher.chmod(launcher.stat().st_mode | stat.S_IXUSR)
        client = rr.experimental.ViewerClient.spawn(headless=True, executable_path=str(launcher), port=port,
                                                    hide_welcome_screen=True)
        try:
            client.open(str(rrd))
            if at_s is not None:
                client.set_time("time", duration=float(at_s), play_state="paused")
            time.sleep(wait_s)
            tmp = png.with_name(f".{png.stem}.{os.getpid()}.tmp.png")
            try:
                client.save_screenshot(str(tmp))
                os.replace(tmp, png)
            finally:
                tmp.unlink(missing_ok=True)
        except TimeoutError as err:
            raise TwinError(f"screenshot: the viewer did not answer ({err})") from None
        finally:
            client.quit()
    return png
