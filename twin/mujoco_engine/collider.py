"""Installs the native pin-in-bore collider (``_bore.c``) into MuJoCo's collision table.

The table ``mjCOLLISIONFUNC`` is a global of the MuJoCo library; its address is taken with
ctypes from the very library the ``mujoco`` module loaded. Installation is idempotent and
process-wide; other cylinder-cylinder pairs keep MuJoCo's own collider.
"""

from __future__ import annotations

import ctypes
import glob
import os

import mujoco

from twin.errors import EngineUnavailableError
from twin.names import BORE_MAGIC

_installed = False


def _library_path() -> str:
    libs = sorted(glob.glob(os.path.join(os.path.dirname(mujoco.__file__), "libmujoco.so*")))
    if not libs:
        raise EngineUnavailableError("cannot locate libmujoco next to the mujoco module")
    return libs[0]


def ensure_installed() -> None:
    """Install the collider once per process; clear errors if the build is missing or stale."""
    global _installed
    if _installed:
        return
    try:
        from twin.mujoco_engine import _bore
    except ImportError as err:
        raise EngineUnavailableError(
            f"the native bushing collider is not built ({err}); reinstall with 'pip install -e .'") from None
    if _bore.header_version() != mujoco.mj_version():
        raise EngineUnavailableError(
            f"the bushing collider was compiled against MuJoCo {_bore.header_version()} but "
            f"{mujoco.mj_version()} is installed; reinstall twin ('pip install -e .')")
    if _bore.bore_magic() != BORE_MAGIC:
        raise EngineUnavailableError("twin.names.BORE_MAGIC and _bore.c disagree")
    lib = ctypes.CDLL(_library_path())
    table = ctypes.addressof(ctypes.c_void_p.in_dll(lib, "mjCOLLISIONFUNC"))
    _bore.install(table)
    _installed = True
