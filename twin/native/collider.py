"""Installs the native pin-in-bore collider and its friction (``_bore.c``) into MuJoCo.

``mjCOLLISIONFUNC`` (collision table), ``mjcb_passive`` and ``mjcb_sensor`` are globals of
the MuJoCo library; their addresses, and those of ``mj_applyFT`` and ``mj_solveM`` (the effective
mass of ``mujoco.contact_source = "force"``), are taken with ctypes from the very library the
``mujoco`` module loaded (:func:`mujoco_library`). Installation is idempotent and process-wide;
other cylinder-cylinder and sphere-sphere pairs keep MuJoCo's own colliders, and callbacks
installed earlier are chained. Models without marked geoms, joints or numerics are unaffected.

One hook for every model. MuJoCo's callbacks and collision table are global, not per model (its
API reference, "Keep in mind that these are global and not model-specific"), so the hooks are
dispatchers: each reads everything it needs from the model and data it is given (parameters in
geom/joint user data and ``<numeric>`` elements, per-scene state in ``mjData.userdata``, the
"this pass computes sensors" mark in the sensors' own slots) and keeps nothing between calls.
The only process-wide values are the hook pointers and what they chain to, written once under
the GIL at installation and the same for every model. Two models with different parameters can
therefore run at the same time on two threads (MuJoCo's Python functions, ``mujoco.rollout``
included, release the GIL while they run; the hooks are C and never take it); the test
``tests/test_native_hooks.py`` checks the bytes. MuJoCo's engine plugins (``mjpPlugin``) are
model-specific, but they cannot collide geoms (a plugin adds forces, sensors, actuators or signed
distance fields), so the bore and socket colliders would stay in the global table anyway, and a
plugin's state would move from ``mjData.userdata`` into ``plugin_state`` (changing the rollout's
state vectors) while the model would no longer load without the plugin library.

A model the native code cannot read as laid out (a marked geom with a short user-data row, a
state slot past ``nuserdata``, ...) would be skipped silently by the callbacks, which cannot raise;
:func:`check_model` refuses it in one line before it runs.
"""

from __future__ import annotations

import ctypes
import os
import platform

import mujoco

import twin.mujoco_log  # noqa: F401 - MuJoCo's warnings kept off the terminal and the folder

from twin.errors import EngineUnavailableError, ModelError
from twin import names

_addresses: tuple[int, int, int, int, int] | None = None
_library: ctypes.CDLL | None = None


def mujoco_library() -> ctypes.CDLL:
    """The MuJoCo shared library the ``mujoco`` module loaded, as a ctypes handle.

    Found through mujoco's own modules, with no file-name pattern: on Linux and macOS the handle of
    mujoco's compiled extension ``mujoco._functions``, whose symbol look-ups (``dlsym`` on a handle)
    search the extension and then the libraries it links, so they resolve in the very libmujoco it
    uses (``libmujoco.so.X`` on Linux, ``libmujoco.X.dylib`` on macOS, wherever the wheel put it).
    On Windows a module's symbol look-up (``GetProcAddress``) does not search what it links; there
    the handle is the ``mujoco.dll`` that ``mujoco/__init__.py`` itself loads from its package
    folder. Checked: the handle's ``mj_version`` is the module's.
    """
    global _library
    if _library is not None:
        return _library
    try:
        if platform.system() == "Windows":
            lib = ctypes.CDLL(os.path.join(os.path.dirname(mujoco.__file__), "mujoco.dll"))
        else:
            from mujoco import _functions

            lib = ctypes.CDLL(_functions.__file__)
        lib.mj_version.restype = ctypes.c_int
        version = lib.mj_version()
    except (OSError, AttributeError, ImportError) as err:
        raise EngineUnavailableError(f"cannot reach the MuJoCo library of the mujoco module ({err})") from None
    if version != mujoco.mj_version():
        raise EngineUnavailableError(f"the MuJoCo library found reports version {version}, "
                                     f"the mujoco module {mujoco.mj_version()}")
    _library = lib
    return lib


def check_model(model: mujoco.MjModel) -> None:
    """Raise :class:`~twin.errors.ModelError` (one line) if the native code cannot run ``model`` as
    laid out: the layouts of :data:`twin.names.BORE_USERDATA_FIELDS`, ``GUIDE_USERDATA_FIELDS``,
    ``DRIVETRAIN_FIELDS`` and ``GUIDE_CLEARANCE_FIELDS`` and their state slots in ``nuserdata``.
    Only what the model marks as native (the marker values) is checked."""
    from twin.native import _bore

    problem = _bore.check_model(model._address)
    if problem is not None:
        raise ModelError(f"the model does not fit the native contact code: {problem}")


def ensure_installed() -> None:
    """Install the collider and callbacks (idempotent; re-installs a hook someone replaced).

    Clear errors if the native module is missing, was built against another MuJoCo, or reads
    the bore user data with another layout than :data:`twin.names.BORE_USERDATA_FIELDS`.
    """
    global _addresses
    if _addresses is not None:
        from twin.native import _bore

        _bore.install(*_addresses)
        return
    try:
        from twin.native import _bore
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
    lib = mujoco_library()
    table = ctypes.addressof(ctypes.c_void_p.in_dll(lib, "mjCOLLISIONFUNC"))
    passive = ctypes.addressof(ctypes.c_void_p.in_dll(lib, "mjcb_passive"))
    sensor = ctypes.addressof(ctypes.c_void_p.in_dll(lib, "mjcb_sensor"))
    apply_ft = ctypes.cast(lib.mj_applyFT, ctypes.c_void_p).value
    solve_m = ctypes.cast(lib.mj_solveM, ctypes.c_void_p).value
    _addresses = (table, passive, sensor, apply_ft, solve_m)
    _bore.install(*_addresses)


def as_passive_force(spec: mujoco.MjSpec, pair: mujoco.MjsPair, bore: mujoco.MjsGeom, pin_id: int,
                     sensor: str | None) -> None:
    """Turn a native-law pin/bore ``pair`` into ``mujoco.contact_source = "force"``: the pair is
    deleted (no collision, no contact row), the bore's ``force_pin`` user data field names the
    pin's geom id ``pin_id`` (geom ids do not change when pairs and sensors do), and the contact
    sensor ``sensor`` (if the spec has it) becomes a position-stage user sensor of dimension 4 on
    the bore that the native module fills with [found, normal force, 0, 0] (``_bore.c``, "Force")."""
    spec.delete(pair)
    bore.userdata = names.replace_bore_userdata(list(bore.userdata), force_pin=float(pin_id))
    if sensor is not None and spec.sensor(sensor) is not None:
        spec.delete(spec.sensor(sensor))
        spec.add_sensor(name=sensor, type=mujoco.mjtSensor.mjSENS_USER, objtype=mujoco.mjtObj.mjOBJ_GEOM,
                        objname=bore.name, dim=4, needstage=mujoco.mjtStage.mjSTAGE_POS,
                        datatype=mujoco.mjtDataType.mjDATATYPE_REAL)
