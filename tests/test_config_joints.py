"""Configuration of the general mechanism's joints (issue 18): a clearance at the ground pivot A,
per-joint pins, bushings, materials and stiffness."""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.config import (JOINTS, BenchConfig, ConfigError, config_from_toml, joint_stiffness, ln_stiffness,
                         load_config)
from twin.kinematics import initial_pose, loaded_eccentricity, static_pin_forces

STEEL = {"youngs_modulus_pa": 207e9, "poisson": 0.3, "density_kgm3": 7850.0}


def _cfg(**over) -> BenchConfig:
    return BenchConfig().replace(**over)


def test_joint_a_is_ideal_by_default_and_listed_first_when_it_has_a_clearance():
    assert JOINTS == ("A", "B", "C")
    assert BenchConfig().joints.clearance_joints == ("C",)
    cfg = _cfg(**{"joints.clearance_a_mm": 0.5, "joints.clearance_b_mm": 0.1})
    assert cfg.joints.clearance_joints == ("A", "B", "C")
    assert cfg.joints.radial_m("A") == pytest.approx(0.25e-3)


def test_per_joint_pin_and_bushing_override_the_shared_ones_only_where_given():
    cfg = _cfg(**{"joints.pin_diameters_m": {"C": 0.015}, "joints.bushing_lengths_m": {"A": 0.05},
                  "joints.clearance_c_mm": 0.5})
    j = cfg.joints
    assert j.pin_radius("C") == 0.0075 and j.pin_radius("B") == j.pin_radius_m == j.pin_diameter_m / 2
    assert j.bushing_radius_m("C") == pytest.approx(0.0075 + 0.25e-3)
    assert j.bushing_length("A") == 0.05 and j.bushing_length("B") == j.bushing_length_m


def test_eq18_stiffness_uses_each_joints_own_pin_and_materials():
    """K = 4/(3(h_i + h_j)) sqrt(R_i R_j/(R_i − R_j)), h = (1 − ν²)/E, written out here."""
    cfg = _cfg(**{"joints.clearance_a_mm": 0.5, "joints.pin_diameters_m": {"A": 0.03},
                  "materials.pins": {"A": STEEL}, "materials.bushings": {"A": STEEL}})
    rj, ri = 0.015, 0.015 + 0.25e-3
    h = 2 * (1 - 0.3**2) / 207e9
    k_a = 4 / (3 * h) * math.sqrt(ri * rj / (ri - rj))
    assert ln_stiffness(cfg.joints, cfg.materials, "A") == pytest.approx(k_a, rel=1e-12)
    # joint C keeps the bench's F125 steel pin in an RG10 bronze bushing, 20 mm pin, 0.05 mm radial
    rj, ri = 0.01, 0.01 + 0.05e-3
    h = (1 - 0.3**2) / 210e9 + (1 - 0.34**2) / 90e9
    assert ln_stiffness(cfg.joints, cfg.materials, "C") == pytest.approx(4 / (3 * h) * math.sqrt(ri * rj / (ri - rj)),
                                                                          rel=1e-12)


def test_given_stiffness_per_joint_beats_the_shared_one_and_zero_means_eq18():
    cfg = _cfg(**{"joints.clearance_b_mm": 0.1, "contact.stiffness": 5e9, "contact.stiffnesses": {"C": 0.0}})
    assert joint_stiffness(cfg, "B") == 5e9
    assert joint_stiffness(cfg, "C") == ln_stiffness(cfg.joints, cfg.materials, "C")


@pytest.mark.parametrize("over, field", [
    ({"joints.clearance_a_mm": 0.3}, "joints.clearance_a_mm"),
    ({"joints.clearance_a_mm": -1.0}, "joints.clearance_a_mm"),
    ({"joints.pin_diameters_m": {"D": 0.01}}, "joints.pin_diameters_m.D"),
    ({"joints.pin_diameters_m": {"B": 0.0}}, "joints.pin_diameters_m.B"),
    ({"joints.bushing_lengths_m": {"C": -0.01}}, "joints.bushing_lengths_m.C"),
    ({"materials.pins": {"E": STEEL}}, "materials.pins.E"),
    ({"materials.bushings": {"A": {"youngs_modulus_pa": 1e11}}}, "materials.bushings.A"),
    ({"contact.stiffnesses": {"B": -1.0}}, "contact.stiffnesses.B"),
])
def test_bad_joint_fields_name_the_field(over, field):
    with pytest.raises(ConfigError) as err:
        _cfg(**over)
    assert str(err.value).startswith(field), str(err.value)


def test_per_joint_tables_round_trip_through_toml(tmp_path):
    cfg = _cfg(**{"joints.clearance_a_mm": 0.5, "joints.pin_diameters_m": {"A": 0.03},
                  "materials.pins": {"A": STEEL}, "contact.stiffnesses": {"A": 2e10}})
    assert config_from_toml(cfg.to_toml()) == cfg
    f = tmp_path / "a.toml"
    f.write_text('[joints]\nclearance_a_mm = 0.5\n[joints.pin_diameters_m]\nA = 0.03\n'
                 '[materials.pins.A]\nyoungs_modulus_pa = 207e9\npoisson = 0.3\ndensity_kgm3 = 7850.0\n')
    loaded = load_config(f)
    assert loaded.joints.pin_radius("A") == 0.015 and loaded.materials.pin_of("A").youngs_modulus_pa == 207e9
    assert loaded.materials.pin_of("B") == BenchConfig().materials.pin


@pytest.mark.parametrize("orientation", ["x", "y"])
def test_loaded_start_at_a_rests_the_journal_against_the_frames_load(orientation):
    """Statics: the frame holds the crank (weight m_c g) and pin B's load F_B, so the force of the
    bore on the journal is −(m_c g + F_B); the journal sits at e_A = −c F/|F| (touching the bore
    on the side the force comes from), and pin B moves with it."""
    cfg = _cfg(**{"joints.clearance_a_mm": 0.5, "mechanism.orientation": orientation})
    theta = 0.7
    f_b, _ = static_pin_forces(cfg, theta)
    g = np.asarray(cfg.mechanism.gravity_vector[:2])
    f_a = -(cfg.bodies.crank.mass_kg * g + f_b)
    e_a = loaded_eccentricity(cfg, "A", theta)
    assert np.linalg.norm(e_a) == pytest.approx(0.25e-3, rel=1e-12)
    assert np.dot(e_a, f_a) == pytest.approx(-0.25e-3 * np.linalg.norm(f_a), rel=1e-12)
    if orientation == "y":  # the crank and rod hang on the frame: the journal rests on the bottom
        assert e_a[1] < 0 and abs(e_a[0]) < 0.3 * abs(e_a[1])
    pose = initial_pose(cfg, theta)
    r = cfg.bodies.crank.length_m
    np.testing.assert_allclose(pose.b_pin, e_a + r * np.array([math.cos(theta), math.sin(theta)]), atol=1e-15)
    assert pose.c_pin[1] == pytest.approx(cfg.mechanism.d_off_m, abs=1e-15)  # the slider stays on its guide


def test_ideal_a_pose_is_unchanged_by_as_pin_size():
    a = initial_pose(_cfg(), 1.1)
    b = initial_pose(_cfg(**{"joints.pin_diameters_m": {"A": 0.05}}), 1.1)
    assert np.all(a.e_a == 0) and np.array_equal(a.b_pin, b.b_pin) and a.slider_x == b.slider_x
