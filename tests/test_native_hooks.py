"""The native hooks hold no state of their own (twin/native/collider.py, "One hook for every model").

MuJoCo's callbacks and collision table are process-wide; the twin's hooks must read everything from the
model and data they are given. Independent basis: each model run alone in a fresh process (a hook that
cached anything from the first model it saw would pass a comparison made in one process). The two models
differ in their contact parameters (the planar B+C scene of Table 4 test 12, the spatial S002 preset with
its ball-in-socket colliders), so a parameter or a state leaking from one to the other changes bytes.
"""

from __future__ import annotations

import ctypes
import hashlib
import json
import shutil
import subprocess
import sys
import sysconfig
import threading
from pathlib import Path

import mujoco
import numpy as np
import pytest

import twin
from twin import names
from twin.config import preset
from twin.errors import ModelError
from twin.native.collider import check_model, ensure_installed, mujoco_library
from twin.simulation import make_engine

from conftest import short

SOURCES = ("law", "force")
DURATION_S = 0.05


def _planar(source: str):
    return short(preset(12), DURATION_S, **{"mujoco.contact_source": source})


def _spatial():
    return short(twin.preset("s002"), DURATION_S)


def _bytes(run) -> dict[str, str]:
    """SHA-256 of each channel's bytes."""
    return {name: hashlib.sha256(np.ascontiguousarray(run[name]).tobytes()).hexdigest() for name in run.channels}


def _config(which: str):
    return _spatial() if which == "s002" else _planar(which)


NSTEP = 1500  # steps of the one-thread interleaving (15 ms: both models' contacts active)


def _engine(which: str):
    e = make_engine(_config(which))
    e.reset()
    return e


def _state(e) -> str:
    d = e.data
    return hashlib.sha256(b"".join(np.ascontiguousarray(x).tobytes()
                                   for x in (d.qpos, d.qvel, d.sensordata, d.userdata))).hexdigest()


def solo(which: str) -> dict:
    """What one model gives alone (run by the fixture :func:`fresh` in a process of its own): the run's channel
    digests and the state digest after NSTEP plain steps."""
    e = _engine(which)
    for _ in range(NSTEP):
        mujoco.mj_step(e.model, e.data)
    return {"run": _bytes(twin.simulate(_config(which))), "steps": _state(e)}


@pytest.fixture(scope="module")
def fresh() -> dict[str, dict]:
    """:func:`solo` of each model, each in a fresh Python process."""
    here = Path(__file__).resolve().parent
    out = {}
    for which in ("law", "force", "s002"):
        code = f"import sys, json; sys.path.insert(0, {str(here)!r}); import test_native_hooks as t; " \
               f"print(json.dumps(t.solo({which!r})))"
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=here)
        assert r.returncode == 0, r.stderr[-2000:]
        out[which] = json.loads(r.stdout.strip().splitlines()[-1])
    return out


def _law_rows(model: mujoco.MjModel) -> set[tuple[float, ...]]:
    """(law, stiffness, exponent, damping) of every bore of a model."""
    f = names.BORE_USERDATA_FIELDS
    cols = [f.index(k) for k in ("law", "stiffness", "exponent", "damping")]
    rows = model.geom_user[model.geom_user[:, f.index("marker")] == names.BORE_MAGIC]
    return {tuple(float(r[c]) for c in cols) for r in rows}


@pytest.mark.parametrize("source", SOURCES)
def test_two_models_on_two_threads_give_the_bytes_of_each_alone(source, fresh):
    planar, spatial = _planar(source), _spatial()
    # the premise: different contact parameters in the two models
    a, b = make_engine(planar).model, make_engine(spatial).model
    assert _law_rows(a) and _law_rows(b) and not (_law_rows(a) & _law_rows(b))
    alone = [fresh[source]["run"], fresh["s002"]["run"]]
    together: list = [None, None]
    start = threading.Barrier(2)
    errors: list[BaseException] = []

    def run(i, cfg):
        try:
            start.wait()
            together[i] = _bytes(twin.simulate(cfg))
        except BaseException as err:  # noqa: BLE001 - re-raised below, in the test's thread
            errors.append(err)

    threads = [threading.Thread(target=run, args=(i, c)) for i, c in enumerate((planar, spatial))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    for solo, both in zip(alone, together):
        assert solo.keys() == both.keys()
        assert [k for k in solo if solo[k] != both[k]] == []


@pytest.mark.parametrize("source", SOURCES)
def test_two_models_stepped_in_turn_on_one_thread_give_the_bytes_of_each_alone(source, fresh):
    # the finest interleaving: one step of each model in turn, sensors on every step (a hook that kept
    # anything between calls, e.g. the "this pass computes sensors" mark, would hand it to the other model)
    turns = [_engine(source), _engine("s002")]
    touched = [False, False]
    for _ in range(NSTEP):
        for i, e in enumerate(turns):
            mujoco.mj_step(e.model, e.data)
            touched[i] |= bool(np.any(e.data.userdata != 0))
    assert touched == [True, True]  # both models' native contact state was in use
    assert [_state(e) for e in turns] == [fresh[source]["steps"], fresh["s002"]["steps"]]


def test_the_library_is_the_instance_the_mujoco_module_uses():
    # a second copy of libmujoco would have its own globals: a callback set through the mujoco module
    # must appear in the handle's slot
    lib = mujoco_library()
    slot = ctypes.c_void_p.in_dll(lib, "mjcb_control")
    assert slot.value is None
    mujoco.set_mjcb_control(lambda m, d: None)
    try:
        assert slot.value is not None
    finally:
        mujoco.set_mjcb_control(None)
    assert slot.value is None
    assert lib.mj_version() == mujoco.mj_version()


def _bore_spec(nuser: int, user: list[float], nuserdata: int = 1) -> mujoco.MjSpec:
    spec = mujoco.MjSpec()
    spec.nuser_geom = nuser
    spec.nuserdata = nuserdata
    spec.worldbody.add_geom(name="bushing_X", type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[0.01, 0.01, 0],
                            userdata=user)
    body = spec.worldbody.add_body(name="pin_body")
    body.add_joint(name="x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
    body.add_geom(name="pin_X", type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[0.009, 0.01, 0], mass=1.0)
    return spec


def _full_row(**fields) -> list[float]:
    return names.replace_bore_userdata(names.bore_userdata(mu0=0.1, v0=1e-3, v1=2e-3), **fields)


@pytest.mark.parametrize("spec, words", [
    (lambda: _bore_spec(3, [names.BORE_MAGIC, 0.1, 0.001]), ("bushing_X", "3 fields", "BORE_USERDATA_FIELDS")),
    (lambda: _bore_spec(len(names.BORE_USERDATA_FIELDS), _full_row(slot=4)), ("bushing_X", "'slot'", "nuserdata = 1")),
    (lambda: _bore_spec(len(names.BORE_USERDATA_FIELDS), _full_row(law=7)), ("bushing_X", "'law'", "0 to 4")),
    (lambda: _bore_spec(len(names.BORE_USERDATA_FIELDS), _full_row(force_pin=9)), ("bushing_X", "'force_pin'",)),
    (lambda: _bore_spec(len(names.BORE_USERDATA_FIELDS), _full_row(force_pin=1, slot=0)), ("bushing_X", "2 slot(s)")),
], ids=["short row", "slot past nuserdata", "unknown law", "no such pin", "force without two slots"])
def test_a_model_the_native_code_cannot_read_is_refused_in_one_line(spec, words):
    ensure_installed()
    model = spec().compile()
    with pytest.raises(ModelError) as err:
        check_model(model)
    msg = str(err.value)
    assert "\n" not in msg and all(w in msg for w in words), msg


def test_marked_joints_and_numerics_with_short_layouts_are_refused():
    spec = mujoco.MjSpec()
    spec.nuser_jnt = 2
    body = spec.worldbody.add_body(name="slider")
    body.add_joint(name="guide", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0],
                   userdata=[names.GUIDE_MAGIC, 3.0])
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.01, 0, 0], mass=1.0)
    with pytest.raises(ModelError, match="joint 'guide'.*GUIDE_USERDATA_FIELDS"):
        check_model(spec.compile())
    spec = mujoco.MjSpec()
    spec.add_numeric(name="drivetrain", data=[names.DRIVETRAIN_MAGIC, 0.0, 0.0])
    with pytest.raises(ModelError, match="numeric 'drivetrain'.*DRIVETRAIN_FIELDS"):
        check_model(spec.compile())


def test_the_built_models_pass_the_check():
    for cfg in (_planar("law"), _planar("force"), _spatial(), short(preset(6), 0.05, **{"drive.mode": "motor"}),
                short(preset(6), 0.05, **{"joints.clearance_guide_mm": 0.1})):
        check_model(make_engine(cfg).model)  # raises if not


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")
def test_the_native_sources_compile_without_a_warning(tmp_path):
    # the flags setup.py gives GCC and Clang; a warning fails this as it fails the build
    here = Path(__file__).resolve().parents[1] / "twin" / "native"
    include = Path(mujoco.__file__).parent / "include"
    for src in ("_bore.c", "_socket.c"):
        out = subprocess.run(["cc", "-c", "-O2", "-Wall", "-Wextra", "-Werror", "-fPIC", f"-I{include}",
                              f"-I{sysconfig.get_paths()['include']}", str(here / src), "-o", str(tmp_path / "x.o")],
                             capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
