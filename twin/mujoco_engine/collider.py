"""Installs the native pin-in-bore collider and its friction (``_bore.c``) into MuJoCo.

``mjCOLLISIONFUNC`` (collision table), ``mjcb_passive`` and ``mjcb_sensor`` are globals of
the MuJoCo library; their addresses, and that of ``mj_applyFT``, are taken with ctypes from
the very library the ``mujoco`` module loaded (and that of ``mj_solveM``, for the effective mass
of ``mujoco.contact_source = "force"``). Installation is idempotent and process-wide;
other cylinder-cylinder pairs keep MuJoCo's own collider, and callbacks installed earlier
are chained. Models without bore geoms are unaffected.
"""

from __future__ import annotations

import ctypes
import glob
import os

import mujoco

import twin.mujoco_log  # noqa: F401 - MuJoCo's warnings kept off the terminal and the folder

from twin.errors import EngineUnavailableError
from twin import names

_addresses: tuple[int, int, int, int, int] | None = None


def _library_path() -> str:
    libs = sorted(glob.glob(os.path.join(os.path.dirname(mujoco.__file__), "libmujoco.so*")))
    if not libs:
        raise EngineUnavailableError("cannot locate libmujoco next to the mujoco module")
    return libs[0]


def ensure_installed() -> None:
    """Install the collider and callbacks (idempotent; re-installs a hook someone replaced).

    Clear errors if the native module is missing, was built against another MuJoCo, or reads
    the bore user data with another layout than :data:`twin.names.BORE_USERDATA_FIELDS`.
    """
    global _addresses
    if _addresses is not None:
        from twin.mujoco_engine import _bore

        _bore.install(*_addresses)
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
    if _bore.bore_magic() != names.BORE_MAGIC:
        raise EngineUnavailableError("twin.names.BORE_MAGIC and _bore.c disagree")
    fields = tuple(_bore.userdata_fields()) if hasattr(_bore, "userdata_fields") else None
    if fields != names.BORE_USERDATA_FIELDS:
        raise EngineUnavailableError(
            f"the bushing collider reads the bore user data as {fields} but twin.names.BORE_USERDATA_FIELDS "
            f"is {names.BORE_USERDATA_FIELDS}; rebuild the extension ('pip install -e .') after changing either")
    guide = (tuple(_bore.guide_fields()), _bore.guide_magic()) if hasattr(_bore, "guide_fields") else None
    if guide != (names.GUIDE_USERDATA_FIELDS, names.GUIDE_MAGIC):
        raise EngineUnavailableError(
            f"the native module reads the guide joint's user data as {guide} but twin.names has "
            f"{(names.GUIDE_USERDATA_FIELDS, names.GUIDE_MAGIC)}; rebuild the extension ('pip install -e .')")
    train = (tuple(_bore.drivetrain_fields()), *_bore.drivetrain_layout()[0:1], *_bore.drivetrain_layout()[2:4]) \
        if hasattr(_bore, "drivetrain_fields") else None
    if train != (names.DRIVETRAIN_FIELDS, names.DRIVETRAIN_MAGIC, len(names.DRIVETRAIN_SENSOR_FIELDS),
                 len(names.DRIVETRAIN_ENERGY_FIELDS)):
        raise EngineUnavailableError(
            "the native module's drive-train layout differs from twin.names (DRIVETRAIN_FIELDS, DRIVETRAIN_MAGIC, "
            "DRIVETRAIN_SENSOR_FIELDS, DRIVETRAIN_ENERGY_FIELDS); rebuild the extension ('pip install -e .')")
    gc = (tuple(_bore.guide_clearance_fields()), _bore.guide_clearance_layout()[0], _bore.guide_clearance_layout()[2]) \
        if hasattr(_bore, "guide_clearance_fields") else None
    if gc != (names.GUIDE_CLEARANCE_FIELDS, names.GUIDE_CLEARANCE_MAGIC, len(names.GUIDE_SENSOR_FIELDS)):
        raise EngineUnavailableError(
            "the native module's guide-clearance layout differs from twin.names (GUIDE_CLEARANCE_FIELDS, "
            "GUIDE_CLEARANCE_MAGIC, GUIDE_SENSOR_FIELDS); rebuild the extension ('pip install -e .')")
    lib = ctypes.CDLL(_library_path())
    table = ctypes.addressof(ctypes.c_void_p.in_dll(lib, "mjCOLLISIONFUNC"))
    passive = ctypes.addressof(ctypes.c_void_p.in_dll(lib, "mjcb_passive"))
    sensor = ctypes.addressof(ctypes.c_void_p.in_dll(lib, "mjcb_sensor"))
    apply_ft = ctypes.cast(lib.mj_applyFT, ctypes.c_void_p).value
    solve_m = ctypes.cast(lib.mj_solveM, ctypes.c_void_p).value
    _addresses = (table, passive, sensor, apply_ft, solve_m)
    _bore.install(*_addresses)
