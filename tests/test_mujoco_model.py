"""The compiled MuJoCo variants: names, what each scene contains, determinism, export."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from twin import names
from twin.config import preset
from twin.errors import ConfigError
from twin.mujoco_engine.builder import build, export_xml
from twin.simulation import simulate_run

from conftest import short


def _resolve(model: mujoco.MjModel, kind: str, name: str) -> int:
    return getattr(model, kind)(name).id


def test_every_python_name_resolves_in_the_compiled_models():
    # MuJoCo's accelerometer sensors (the default "posthoc" computes them without: test_posthoc_accel.py)
    sensor = {"mujoco.accelerometers": "sensor"}
    ideal = build(preset(3).replace(**sensor))[1]
    both = build(preset(12).replace(**sensor))[1]
    for m in (ideal, both):
        for b in names.BODIES:
            _resolve(m, "body", b)
        for j in (names.CRANK_HINGE, names.ROD_HINGE, names.SLIDER_SLIDE):
            _resolve(m, "joint", j)
        for g in (names.CRANK_ARM, names.ROD_BEAM, names.SLIDER_BLOCK, names.GUIDE_RAIL):
            _resolve(m, "geom", g)
        for jt in ("B", "C"):
            _resolve(m, "geom", names.pin(jt))
            _resolve(m, "geom", names.bushing(jt))
            _resolve(m, "geom", names.bushing_ring(jt))
            _resolve(m, "site", names.pin(jt))
            _resolve(m, "site", names.bushing(jt))
        _resolve(m, "actuator", names.CRANK_PID)
        for s in (*names.ACCEL_SENSORS, names.SENSOR_CRANK_ANGLE, names.SENSOR_CRANK_SPEED, names.SENSOR_SLIDER_POSITION,
                  names.SENSOR_CRANK_TORQUE):
            _resolve(m, "sensor", s)
    _resolve(ideal, "equality", names.JOINT_C_CONNECT)
    for jt in ("B", "C"):
        _resolve(both, "pair", names.pair(jt))
        for s in (names.sensor_ecc(jt), names.sensor_contact(jt), names.sensor_friction(jt)):
            _resolve(both, "sensor", s)
    for j in (names.ECC_B_X, names.ECC_B_Y):
        _resolve(both, "joint", j)
    assert both.geom_user[both.geom(names.bushing("B")).id, 0] == names.BORE_MAGIC
    # sensors the builder adds for the optional "energy" channel group
    energy = build(preset(12).replace(**{"sensors.channels": ["energy"]}))[1]
    for s in (names.SENSOR_ENERGY_KINETIC, names.SENSOR_ENERGY_POTENTIAL, names.SENSOR_SLIDER_SPEED):
        _resolve(energy, "sensor", s)
    assert energy.opt.enableflags & mujoco.mjtEnableBit.mjENBL_ENERGY


# pairs: one per clearance joint (the native contact law)
@pytest.mark.parametrize("test_id, nv, npair, neq", [(3, 1 + 2, 0, 1), (6, 3, 1, 0), (9, 5, 1, 1), (12, 5, 2, 0)])
def test_each_scene_holds_only_what_it_needs(test_id, nv, npair, neq):
    m = build(preset(test_id))[1]
    assert (m.nv, m.npair, m.neq) == (nv, npair, neq)
    contact_off = bool(m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT)
    assert contact_off == (npair == 0)  # ideal scenes skip collision detection entirely
    # only the pin/bushing pairs may collide: every geom has contype = conaffinity = 0
    assert not m.geom_contype.any() and not m.geom_conaffinity.any()


def test_channel_groups_select_sensors():
    full = build(preset(12).replace(**{"mujoco.accelerometers": "sensor"}))[1]
    posthoc = build(preset(12))[1]  # accelerometers from the recorded state, no sensors
    lean = build(preset(12).replace(**{"sensors.channels": ["encoder"]}))[1]
    assert lean.nsensor == 1 and lean.sensor(0).name == names.SENSOR_CRANK_ANGLE
    assert full.nsensor == 6 + 4 + 2 * 3
    assert posthoc.nsensor == 4 + 2 * 3
    run = simulate_run(short(preset(12), 0.02, **{"sensors.channels": ["encoder", "accel"]}))
    assert list(run.channels) == ["AC1", "AC2", "AC3", "AC4", "AC5", "AC6", "encoder_angle"]


@pytest.mark.parametrize("source", ["law", "first-guess"])
def test_same_config_gives_identical_output_whatever_the_chunking(source):
    # the native contact law keeps each contact event's impact speed in mjData.userdata: it must
    # carry over chunk boundaries like the rest of the state
    cfg = short(preset(12), 0.1, **{"mujoco.contact_source": source})
    a = simulate_run(cfg)
    b = simulate_run(cfg)
    c = simulate_run(cfg.replace(**{"simulation.chunk_s": 0.013}))
    for name in a.channels:
        assert np.array_equal(a[name], b[name]), name
        assert np.array_equal(a[name], c[name]), name


@pytest.mark.parametrize("h, rate, n", [(1e-5, 1e5, 2000), (5e-6, 1e5, 2000), (2e-5, 5e4, 1000)])
def test_output_rate_and_length(h, rate, n):
    cfg = short(preset(6), 0.02, **{"simulation.timestep_s": h, "sensors.output_rate_hz": rate,
                                    "sensors.channels": ["crank"]})
    run = simulate_run(cfg)
    assert (run.rate_hz, run.n) == (rate, n)
    assert run.meta["steps"] == round(0.02 / h)


def test_timestep_must_divide_the_output_period():
    # a configuration that exists can be run: the rule is checked when it is made
    with pytest.raises(ConfigError, match="does not divide"):
        preset(6).replace(**{"simulation.timestep_s": 7e-6})
    with pytest.raises(ConfigError, match="output_rate_hz"):  # 2e-5 s does not divide 1/100 kHz' period
        preset(6).replace(**{"simulation.timestep_s": 3e-5})
    cfg = preset(6).replace(**{"simulation.timestep_s": 2e-5, "sensors.output_rate_hz": 50_000.0})
    assert (cfg.output_stride, cfg.n_samples) == (1, 100_000)
    assert preset(6).replace(**{"simulation.timestep_s": 2.5e-6}).output_stride == 4


def test_exported_xml_compiles_to_the_same_model(tmp_path):
    cfg = preset(12)
    xml = export_xml(cfg)
    assert "bore collider" in xml and cfg.digest() in xml
    m = mujoco.MjModel.from_xml_string(xml)
    # the export keeps MuJoCo's accelerometer sensors (a plain MuJoCo has no posthoc path)
    ref = build(cfg.replace(**{"mujoco.accelerometers": "sensor"}))[1]
    assert (m.nq, m.nv, m.nu, m.na, m.npair, m.nsensor) == (ref.nq, ref.nv, ref.nu, ref.na, ref.npair, ref.nsensor)
    np.testing.assert_allclose(m.pair_solref, ref.pair_solref, rtol=1e-5)  # XML keeps 6 digits
    np.testing.assert_allclose(m.body_mass, ref.body_mass)
    np.testing.assert_allclose(m.geom_size, ref.geom_size)


def test_exported_motor_drive_keeps_the_drive_train(tmp_path):
    """``twin export-mjcf --drive-mode motor``: the rotor, its command actuator and the drive train's
    numeric parameters (belt, controller) come out of the XML as compiled, the crank PID gone."""
    cfg = preset(12).replace(**{"drive.mode": "motor"})
    xml = export_xml(cfg)
    assert "passive callback" in xml
    m = mujoco.MjModel.from_xml_string(xml)
    ref = build(cfg.replace(**{"mujoco.accelerometers": "sensor"}))[1]
    assert (m.nq, m.nv, m.nu, m.nsensor) == (ref.nq, ref.nv, ref.nu, ref.nsensor)
    assert mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, names.CRANK_PID) == -1
    for kind, name in ((mujoco.mjtObj.mjOBJ_JOINT, names.MOTOR_HINGE), (mujoco.mjtObj.mjOBJ_ACTUATOR, names.MOTOR_COMMAND)):
        assert mujoco.mj_name2id(m, kind, name) >= 0
    b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, names.MOTOR)
    assert m.body_inertia[b][2] == pytest.approx(cfg.drivetrain.rotor_inertia_kgm2, rel=1e-6)
    i, k = (mujoco.mj_name2id(x, mujoco.mjtObj.mjOBJ_NUMERIC, "drivetrain") for x in (m, ref))
    a = m.numeric_data[m.numeric_adr[i]:m.numeric_adr[i] + m.numeric_size[i]]
    np.testing.assert_allclose(a, ref.numeric_data[ref.numeric_adr[k]:ref.numeric_adr[k] + ref.numeric_size[k]], rtol=1e-5)
