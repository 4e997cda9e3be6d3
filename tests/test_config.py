"""Configuration: defaults, TOML round trip, presets and clear errors for bad values."""

from __future__ import annotations

import math
import re

import pytest

from twin.config import (CATALOGUE_DIAMETRAL_MM, TABLE4, BenchConfig, config_from_toml, ln_stiffness,
                         load_config, preset, with_overrides)
from twin.errors import ConfigError


def test_defaults_are_bench_numbers():
    c = BenchConfig()
    assert (c.bodies.crank.mass_kg, c.bodies.rod.length_m, c.bodies.slider.inertia_kgm2) == (5.72, 0.60, 0.0025)
    assert c.drive.belt_ratio == 3.97 and c.contact.mu0 == 0.05 and c.mechanism.guide_friction_n == 2.5
    assert c.mechanism.gravity_vector == (0.0, -9.81, 0.0)
    # 750 motor rpm through the 1:3.97 belt: 188.9 crank rpm (BENCH.md)
    assert math.isclose(c.drive.crank_rad_s * 60 / (2 * math.pi), 188.9, abs_tol=0.05)
    assert c.drive.protocol_duration_s == 38.0


def test_ln_stiffness_matches_bench_md():
    # BENCH.md: 10 mm pin radius, 0.1 mm diametral clearance -> K ≈ 1.3e11 N/m^1.5
    k = ln_stiffness(preset(12).joints, BenchConfig().materials, "B")
    assert 1.30e11 < k < 1.36e11


def test_toml_round_trip_and_digest():
    c = preset(11).replace(**{"mechanism.orientation": "x", "drive.ramp_s": 0.25})
    back = config_from_toml(c.to_toml())
    assert back == c and back.digest() == c.digest()
    assert preset(10).digest() != preset(11).digest()


def test_partial_toml_file_merges_over_defaults(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text('test = 9\nname = "mine"\n[drive]\nmotor_rpm = 300\n[bodies.rod]\nmass_kg = 4.0\n')
    c = load_config(p)
    assert c.name == "mine" and c.joints.clearance_b_mm == 0.1 and c.joints.clearance_c_mm == 0.0
    assert c.drive.motor_rpm == 300.0 and c.bodies.rod.mass_kg == 4.0 and c.bodies.rod.length_m == 0.6


@pytest.mark.parametrize("test_id", sorted(TABLE4))
def test_presets_follow_table4(test_id):
    b, cc, rpm = TABLE4[test_id]
    c = preset(test_id)
    assert (c.joints.clearance_b_mm, c.joints.clearance_c_mm, c.drive.motor_rpm) == (b, cc, rpm)
    assert c.mechanism.orientation == "y"
    assert set(c.joints.clearance_joints) == {j for j, v in (("B", b), ("C", cc)) if v > 0}


@pytest.mark.parametrize("overrides, field, fragment", [
    ({"joints.clearance_b_mm": 0.3}, "joints.clearance_b_mm", "catalogue"),
    ({"joints.clearance_c_mm": -0.1}, "joints.clearance_c_mm", "ball bearing"),
    ({"mechanism.orientation": "w"}, "mechanism.orientation", "x, y, z"),
    ({"bodies.crank.mass_kg": 0.0}, "bodies.crank.mass_kg", "[0.0001, 1000] kg"),
    ({"drive.motor_rpm": 1500.0}, "drive.motor_rpm", "±10 V"),
    ({"drive.program": "sine"}, "drive.program", "constant, protocol, trace"),
    ({"drive.program": "trace"}, "drive.trace_file", "trace file"),
    ({"simulation.timestep_s": 0.1}, "simulation.timestep_s", "[1e-7, 1e-3]"),
    ({"simulation.engine": "ode"}, "simulation.engine", "mujoco, reference"),
    ({"contact.restitution": 1.5}, "contact.restitution", "(0, 1]"),
    ({"contact.v1_mps": 1e-4}, "contact.v1_mps", "v0_mps"),
    ({"mujoco.contact_solref": [0.1]}, "mujoco.contact_solref", "2 numbers"),
    ({"mujoco.contact_source": "calibration"}, "mujoco.contact_source", "law, force, first-guess"),
    ({"mujoco.impact_damping_gain": 0.0}, "mujoco.impact_damping_gain", "[0.1, 10]"),
    ({"contact.impact_speed_floor_mps": 5.0}, "contact.impact_speed_floor_mps", "[1e-6, 1] m/s"),
    ({"sensors.channels": ["accel", "gps"]}, "sensors.channels", "accel"),
    ({"materials.pin.poisson": 0.7}, "materials.pin.poisson", "(-1, 0.5)"),
    ({"drive.nope": 1}, "drive.nope", "unknown field"),
    ({"joints.clearance_b_mm": "big"}, "joints.clearance_b_mm", "number"),
])
def test_bad_values_name_the_field(overrides, field, fragment):
    with pytest.raises(ConfigError) as err:
        with_overrides(BenchConfig(), overrides)
    assert err.value.field == field
    assert fragment in str(err.value)
    assert "\n" not in str(err.value)


def test_noncatalogue_clearance_needs_opt_in():
    c = with_overrides(BenchConfig(), {"joints.allow_noncatalogue": True, "joints.clearance_b_mm": 0.3})
    assert c.joints.radial_m("B") == pytest.approx(0.15e-3)
    assert all(with_overrides(BenchConfig(), {"joints.clearance_c_mm": v}).joints.clearance_c_mm == v
               for v in CATALOGUE_DIAMETRAL_MM)


def test_bad_preset_and_bad_file(tmp_path):
    with pytest.raises(ConfigError, match="1..12"):
        preset(13)
    p = tmp_path / "bad.toml"
    p.write_text("[drive\nmotor_rpm = 1")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_config(p)
    with pytest.raises(ConfigError, match="cannot read"):
        load_config(tmp_path / "missing.toml")


@pytest.mark.parametrize("overrides, fragment", [
    ({"drive.program": "steps"}, "drive.steps_s: must hold at least one step"),
    ({"drive.steps_s": [0.0, 1.0], "drive.steps_rpm": [500.0]}, "drive.steps_rpm: must hold one speed"),
    ({"drive.program": "steps", "drive.steps_s": [1.0, 0.5], "drive.steps_rpm": [1.0, 2.0]}, "increasing order"),
    ({"drive.program": "steps", "drive.steps_s": [0.0], "drive.steps_rpm": [1500.0]}, "±1000 rpm"),
    ({"contact.stiffness_scale": 0.0}, "contact.stiffness_scale"),
])
def test_steps_program_and_stiffness_scale_are_validated(overrides, fragment):
    with pytest.raises(ConfigError, match=re.escape(fragment)):
        preset(6).replace(**overrides)
