"""Accelerometers after the rollout (``mujoco.accelerometers = "posthoc"``, issue 16 item 2).

Independent basis: MuJoCo's own ``<accelerometer>`` sensors (``"sensor"``) on the same run.
Each scene runs twice, once per setting, and the engine's float64 outputs (``advance``, before
the channels' float32 storage) are compared: the accelerometers to round-off, every other
channel bit for bit (the sensors never act on the dynamics).

Tolerance, from the round-off of the method, not from an observed difference: the posthoc path
takes qacc_k = (qvel_{k+1} − qvel_k)/h, and qvel_{k+1} = fl(qvel_k + h qacc_k) is rounded to
eps |qvel|, so qacc carries an error of about eps |qvel|/h: 2.2e-16 × 100 rad/s / 1e-5 s ≈ 2e-9
rad/s² (crank and rod about 80 rad/s at 750 motor rpm, slider below 10 m/s), about 2e-9 m/s² at
the sites (lever arms below 1 m); the sensor's own spatial-algebra round-off is eps × the largest
acceleration (1e-13 m/s² here). :data:`TOL` = 1e-7 m/s² is 50× that bound, which each run checks
against its own peak |qvel| (:func:`_bound`).
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import short
from twin import names
from twin.config import preset
from twin.errors import ConfigError
from twin.mujoco_engine.builder import build
from twin.mujoco_engine.engine import MujocoEngine
from twin.simulation import run_chunks

TOL = 1e-7  # m/s², see the module docstring
EPS = np.finfo(float).eps


def _run(cfg, setting: str):
    """The engine's float64 outputs of a run of ``cfg`` (every chunk concatenated), the engine,
    and the largest |qvel| at the chunk ends."""
    eng = MujocoEngine(cfg.replace(**{"mujoco.accelerometers": setting}))
    outs: list[dict[str, np.ndarray]] = []
    qvel = [0.0]
    advance = eng.advance

    def recording(*args):
        cols = advance(*args)
        outs.append({k: np.array(v, dtype=np.float64, copy=True) for k, v in cols.items()})
        qvel.append(float(np.abs(eng.data.qvel).max()))
        return cols

    eng.advance = recording
    for _ in run_chunks(eng.cfg, engine=eng):
        pass
    return {k: np.concatenate([o[k] for o in outs]) for k in outs[0]}, eng, max(qvel)


def _bound(qvel_max: float, h: float) -> float:
    """The round-off bound of the module docstring: eps |qvel|/h × (1 + 1 m lever arm) × 4."""
    return 4 * EPS * qvel_max / h * 2


def _compare(cfg):
    a, ea, _ = _run(cfg, "sensor")
    b, eb, qv = _run(cfg, "posthoc")
    assert ea.meta["accelerometers"] == "sensor" and eb.meta["accelerometers"] == "posthoc"
    # the posthoc model has no accelerometer sensor (no mj_rnePostConstraint for them)
    assert not set(names.ACCEL_SENSORS) & {eb.model.sensor(i).name for i in range(eb.model.nsensor)}
    assert set(names.ACCEL_SENSORS) <= {ea.model.sensor(i).name for i in range(ea.model.nsensor)}
    assert _bound(qv, cfg.simulation.timestep_s) < TOL / 10, "the tolerance no longer covers the round-off bound"
    assert list(a) == list(b)
    # live channels (a slider axis across the guide reads exactly 0 unless gravity acts along it)
    assert sum(np.max(np.abs(a[k])) > 1.0 for k in names.ACCEL_SENSORS) >= 4
    for k in a:
        if k in names.ACCEL_SENSORS:
            np.testing.assert_allclose(b[k], a[k], rtol=0, atol=TOL, err_msg=k)
        else:
            assert np.array_equal(a[k], b[k]), f"{k} changed"
    return a, b


@pytest.mark.parametrize("test_id, over", [
    (12, {}),                                        # B+C
    (6, {}),                                         # C only
    (3, {}),                                         # ideal
    (12, {"mechanism.orientation": "x"}),            # x vertical
    (12, {"mechanism.orientation": "z"}),            # z vertical (gravity off the plane)
    (12, {"joints.clearance_a_mm": 0.5}),            # clearance at A: the crank slides
    (12, {"sensors.output_rate_hz": 50_000.0}),      # stride 2
    (6, {"drive.mode": "prescribed"}),               # prescribed drive (Euler, flywheel crank)
])
def test_posthoc_equals_the_sensors(test_id, over):
    _compare(short(preset(test_id), 0.25, **over))


def test_posthoc_honours_mounts_and_moved_sites():
    """Sites moved on their body, turned, and moved between the rod and the slider."""
    over = {"sensors.accelerometers.AC1.position_m": [0.1, 0.01], "sensors.accelerometers.AC1.axis": "-y",
            "sensors.accelerometers.AC3.position_m": [0.4, -0.02], "sensors.accelerometers.AC3.axis": "-x",
            "sensors.accelerometers.AC5.body": "rod", "sensors.accelerometers.AC5.position_m": [0.3, 0.015],
            "sensors.accelerometers.AC2.body": "slider", "sensors.accelerometers.AC2.position_m": [0.01, 0.02],
            "sensors.accelerometers.AC2.axis": "-x"}
    cfg = short(preset(12), 0.25, **over)
    m = build(cfg.replace(**{"mujoco.accelerometers": "sensor"}))[1]
    assert m.site_bodyid[m.site("AC5").id] == m.body(names.ROD).id
    assert m.site_bodyid[m.site("AC2").id] == m.body(names.SLIDER).id
    _compare(cfg)


def test_posthoc_does_not_depend_on_chunking():
    cfg = short(preset(12), 0.2, **{"sensors.output_rate_hz": 50_000.0})
    a, _, _ = _run(cfg.replace(**{"simulation.chunk_s": 0.5}), "posthoc")
    b, _, _ = _run(cfg.replace(**{"simulation.chunk_s": 0.013}), "posthoc")
    for k in a:
        assert np.array_equal(a[k], b[k]), k


def test_other_integrators_keep_the_sensors():
    """qvel_{k+1} − qvel_k is not h qacc_k for RK4 or the implicit integrators: they fall back to
    MuJoCo's sensors (``meta["accelerometers"]``)."""
    cfg = short(preset(12), 0.01, **{"mujoco.integrator": "implicitfast"})
    eng = MujocoEngine(cfg)
    assert cfg.mujoco.accelerometers == "posthoc" and eng.meta["accelerometers"] == "sensor"
    assert set(names.ACCEL_SENSORS) <= {eng.model.sensor(i).name for i in range(eng.model.nsensor)}
    run = next(run_chunks(cfg, engine=eng))
    assert np.all(np.isfinite(run.channels["AC1"].data))


def test_accel_only_and_no_accel_groups():
    """Only the accel group (no sensor left in the model) and no accel group at all."""
    cfg = short(preset(12), 0.05)
    only = cfg.replace(**{"sensors.channels": ["accel"]})
    a, _, _ = _run(only, "sensor")
    b, eb, _ = _run(only, "posthoc")
    assert eb.model.nsensor == 0 and list(a) == list(b) == list(names.ACCEL_SENSORS)
    for k in a:
        np.testing.assert_allclose(b[k], a[k], rtol=0, atol=TOL, err_msg=k)
    none = cfg.replace(**{"sensors.channels": ["encoder"]})
    eng = MujocoEngine(none)
    assert eng.meta["accelerometers"] is None and eng._accel is None


def test_the_setting_is_validated():
    with pytest.raises(ConfigError, match="accelerometers"):
        preset(12).replace(**{"mujoco.accelerometers": "rne"})
