"""Presets as TOML files shipped with the package: the papers' numbers, the configurations they
produced when they were written in code (regression guard), and the files as configurations a user
can copy."""

from __future__ import annotations

import ast
import dataclasses
import importlib.util
import math
import re
import tomllib
from importlib import resources

import pytest

import twin.config
from twin.config import (ENGINE_CLASSES, ENGINE_ONLY_GROUPS, ENGINES, NAMED_PRESETS, TABLE4, BenchConfig, BodyParams,
                         Bodies, ConfigError, Material, Materials, load_config, named_preset, preset)

# ------------------------------------------------------------------------------ papers
#: S003 Table 4 as BENCH.md prints it: id -> (B [mm], C [mm], motor rpm), diametral clearances.
BENCH_MD_TABLE4 = {
    1: (0, 0, 250), 2: (0, 0, 500), 3: (0, 0, 750), 4: (0, 0.1, 250), 5: (0, 0.1, 500), 6: (0, 0.1, 750),
    7: (0.1, 0, 250), 8: (0.1, 0, 500), 9: (0.1, 0, 750), 10: (0.1, 0.1, 250), 11: (0.1, 0.1, 500),
    12: (0.1, 0.1, 750),
}


@pytest.mark.parametrize("test_id", sorted(BENCH_MD_TABLE4))
def test_table4_presets_hold_the_papers_numbers(test_id):
    c = preset(test_id)
    assert (c.joints.clearance_b_mm, c.joints.clearance_c_mm, c.drive.motor_rpm) == BENCH_MD_TABLE4[test_id]
    assert TABLE4[test_id] == BENCH_MD_TABLE4[test_id]
    assert c.joints.clearance_a_mm == 0  # A runs in ball bearings on the bench
    assert c.mechanism.orientation == "y" and c.mechanism.gravity_vector == (0.0, -9.81, 0.0)  # BENCH.md: y up
    # BENCH.md: 750 motor rpm through the 1:3.97 V-belt is 188.9 crank rpm
    assert c.drive.crank_rad_s * 60 / (2 * math.pi) == pytest.approx(BENCH_MD_TABLE4[test_id][2] / 3.97)
    assert c.drive.program == "constant" and c.name == f"test{test_id}"


def test_table4_has_the_twelve_tests():
    assert sorted(TABLE4) == list(range(1, 13))
    for bad in (0, 13, "6", 6.0, True):
        with pytest.raises(twin.config.ConfigError, match="^test: "):
            preset(bad)


def test_s004_preset_holds_the_papers_numbers():
    """S004 §3: steel bars 1000 and 2000 × 100 × 50 mm, a 500 mm cube, 30 rad/s, 0.5 mm at B, d = 0.01 mm."""
    c = named_preset("s004")
    assert c.drive.crank_rad_s == pytest.approx(30.0, rel=1e-12) and c.drive.mode == "prescribed"
    assert (c.bodies.crank.length_m, c.bodies.rod.length_m, c.bodies.slider.length_m) == (1.0, 2.0, 0.5)
    assert c.bodies.crank.mass_kg == pytest.approx(7850 * 1.0 * 0.1 * 0.05)  # ρ (PLACEHOLDER 7850) × volume
    assert c.bodies.slider.mass_kg == pytest.approx(7850 * 0.5 ** 3)
    assert c.bodies.rod.inertia_kgm2 == pytest.approx(78.5 * (2.0 ** 2 + 0.1 ** 2) / 12)
    assert c.joints.radial_m("B") == pytest.approx(0.5e-3) and c.joints.clearance_c_mm == 0
    assert c.contact.law == "adams-impact" and c.contact.impact_d_max_m == pytest.approx(0.01e-3)


def test_s000_preset_holds_the_papers_numbers():
    """S000: the clearance at the piston pin C, the crank at a constant 5000 rpm, slider 0.14 kg."""
    c = named_preset("s000")
    assert c.drive.crank_rad_s == pytest.approx(5000 * 2 * math.pi / 60) and c.drive.mode == "prescribed"
    assert c.joints.clearance_joints == ("C",) and c.bodies.slider.mass_kg == 0.14
    # S000 Table 4: the ideal slider's peak r ω² (1 + r/L) ≈ 2.0e4 m/s² for the crank and rod of the preset
    r, L, w = c.bodies.crank.length_m, c.bodies.rod.length_m, c.drive.crank_rad_s
    assert r * w * w * (1 + r / L) == pytest.approx(2.0e4, rel=0.05)


# --------------------------------------------------------------------- regression guard
def _former_code() -> dict[str, BenchConfig]:
    """The presets as the code built them before they became TOML files (copied from it): the files
    must give exactly these configurations. A regression guard: it pins the former values, not the
    papers (the tests above do that)."""
    out: dict[str, BenchConfig] = {}
    base = BenchConfig()
    for i, (b, c, rpm) in {1: (0.0, 0.0, 250.0), 2: (0.0, 0.0, 500.0), 3: (0.0, 0.0, 750.0),
                           4: (0.0, 0.1, 250.0), 5: (0.0, 0.1, 500.0), 6: (0.0, 0.1, 750.0),
                           7: (0.1, 0.0, 250.0), 8: (0.1, 0.0, 500.0), 9: (0.1, 0.0, 750.0),
                           10: (0.1, 0.1, 250.0), 11: (0.1, 0.1, 500.0), 12: (0.1, 0.1, 750.0)}.items():
        out[f"test{i}"] = dataclasses.replace(
            base, name=f"test{i}", joints=dataclasses.replace(base.joints, clearance_b_mm=b, clearance_c_mm=c),
            drive=dataclasses.replace(base.drive, program="constant", motor_rpm=rpm))

    mounts = dict(base.sensors.accelerometers)
    for name in ("AC3", "AC4"):
        mounts[name] = dataclasses.replace(mounts[name], position_m=(0.27, 0.0))
    out["s001"] = dataclasses.replace(
        base, name="s001",
        bodies=Bodies(crank=BodyParams(2.37, 0.08, 0.0, 0.01201), rod=BodyParams(0.72, 0.32, 0.16, 0.0006926),
                      slider=dataclasses.replace(base.bodies.slider, mass_kg=2.28, x_g_m=0.0)),
        materials=Materials(pin=Material(207e9, 0.30, 7850.0), bushing=Material(97e9, 0.30, 8500.0)),
        joints=dataclasses.replace(base.joints, clearance_b_mm=0.0, clearance_c_mm=1.0, pin_diameter_m=0.014,
                                   initial_eccentricity="centred"),
        mechanism=dataclasses.replace(base.mechanism, orientation="y", d_off_m=0.0, guide_friction_n=0.0,
                                      crank_direction=1),
        contact=dataclasses.replace(base.contact, law="lankarani-nikravesh", restitution=0.55, exponent=1.5,
                                    mu0=0.05, friction_law="adams", mu_static=0.08, v_static_mps=1e-4,
                                    v_kinetic_mps=0.01016),
        drive=dataclasses.replace(base.drive, program="constant", motor_rpm=300.0, belt_ratio=1.0, ramp_s=0.2,
                                  ramp_shape="linear", initial_encoder_angle_rad=math.pi / 2),
        sensors=dataclasses.replace(base.sensors, accelerometers=mounts, output_rate_hz=5000.0),
        simulation=dataclasses.replace(base.simulation, duration_s=0.6),
        instrumentation=dataclasses.replace(base.instrumentation, daq_rate_hz=5000.0, response="off",
                                            models={**base.instrumentation.models, "AC6": "ADXL1001"}))

    mounts = dict(base.sensors.accelerometers)
    for name in ("AC3", "AC4"):
        mounts[name] = dataclasses.replace(mounts[name], position_m=(0.10, 0.0))
    for name in ("AC1", "AC2"):
        mounts[name] = dataclasses.replace(mounts[name], position_m=(0.02, 0.0))
    steel = Material(207e9, 0.30, 7850.0)
    out["s000"] = dataclasses.replace(
        base, name="s000",
        bodies=Bodies(crank=BodyParams(0.30, 0.05, 0.025, 1.0e-4), rod=BodyParams(0.21, 0.12, 0.06, 2.5e-4),
                      slider=BodyParams(0.14, base.bodies.slider.length_m, 0.0, 1.0e-4)),
        materials=Materials(pin=steel, bushing=steel),
        joints=dataclasses.replace(base.joints, clearance_b_mm=0.0, clearance_c_mm=1.0, allow_noncatalogue=True,
                                   pin_diameter_m=0.020, bushing_length_m=0.040, initial_eccentricity="centred"),
        mechanism=dataclasses.replace(base.mechanism, orientation="y", d_off_m=0.0, guide_friction_n=0.0,
                                      crank_direction=1),
        contact=dataclasses.replace(base.contact, law="lankarani-nikravesh", restitution=0.9, exponent=1.5,
                                    stiffness=0.0, mu0=0.03),
        drive=dataclasses.replace(base.drive, program="constant", mode="prescribed", crank_rpm=5000.0,
                                  belt_ratio=1.0, motor_rpm=0.0, ramp_s=0.0, initial_encoder_angle_rad=math.pi / 2),
        mujoco=dataclasses.replace(base.mujoco, integrator="Euler"),
        sensors=dataclasses.replace(base.sensors, accelerometers=mounts),
        simulation=dataclasses.replace(base.simulation, duration_s=0.06, timestep_s=1e-6, chunk_s=0.02),
        instrumentation=dataclasses.replace(base.instrumentation, response="off"))

    def bar(length: float, width: float, thickness: float) -> BodyParams:
        m = steel.density_kgm3 * length * width * thickness
        return BodyParams(m, length, length / 2, m * (length ** 2 + width ** 2) / 12)

    m_s = steel.density_kgm3 * 0.5 ** 3
    out["s004"] = dataclasses.replace(
        base, name="s004",
        bodies=Bodies(crank=bar(1.0, 0.1, 0.05), rod=bar(2.0, 0.1, 0.05),
                      slider=BodyParams(m_s, 0.5, 0.0, m_s * (0.5 ** 2 + 0.5 ** 2) / 12)),
        materials=Materials(pin=steel, bushing=steel),
        joints=dataclasses.replace(base.joints, clearance_b_mm=1.0, clearance_c_mm=0.0, pin_diameter_m=0.05,
                                   bushing_length_m=0.05, initial_eccentricity="centred"),
        mechanism=dataclasses.replace(base.mechanism, orientation="y", d_off_m=0.0, guide_friction_n=0.0,
                                      crank_direction=1),
        contact=dataclasses.replace(base.contact, law="adams-impact", exponent=1.5, stiffness=0.0,
                                    impact_c_max_nspm=1e4, impact_d_max_m=1e-5, mu0=0.0),
        drive=dataclasses.replace(base.drive, program="constant", mode="prescribed",
                                  crank_rpm=30.0 * 60.0 / (2.0 * math.pi), ramp_s=0.0,
                                  initial_encoder_angle_rad=math.pi / 2),
        mujoco=dataclasses.replace(base.mujoco, integrator="Euler"),
        simulation=dataclasses.replace(base.simulation, duration_s=1.0))
    return out


FORMER = _former_code()


@pytest.mark.parametrize("name", sorted(FORMER))
def test_regression_guard_presets_equal_the_former_code(name):
    """Field for field, type for type (the canonical TOML, hence the digest, holds 1 and 1.0 apart)."""
    got = preset(int(name[4:])) if name.startswith("test") else named_preset(name)
    assert got == FORMER[name]
    assert got.to_toml() == FORMER[name].to_toml()


# ----------------------------------------------------------------------------- files
def _preset_text(name: str) -> str:
    return resources.files("twin.config.presets").joinpath(f"{name}.toml").read_text(encoding="utf-8")


@pytest.mark.parametrize("name", list(NAMED_PRESETS))
def test_a_copied_preset_file_is_a_configuration(name, tmp_path):
    f = tmp_path / "mine.toml"
    f.write_text(_preset_text(name), encoding="utf-8")
    assert load_config(f) == named_preset(name)
    f.write_text(_preset_text(name) + "\n[pid]\nkp = 12.0\n", encoding="utf-8")  # an edit of the copy
    if named_preset(name).drive.mode != "pid":  # a crank PID gain is refused where no crank PID runs
        with pytest.raises(ConfigError, match="pid.kp: is not used with drive.mode"):
            load_config(f)
        return
    edited = load_config(f)
    assert edited.pid.kp == 12.0 and edited == named_preset(name).replace(**{"pid.kp": 12.0})


@pytest.mark.parametrize("test_id", [1, 6, 12])
def test_a_copied_table4_entry_is_a_configuration(test_id, tmp_path):
    text = _preset_text("table4")
    block = re.search(rf"^\[test\.{test_id}\].*?\n(.*?)(?=^\[|\Z)", text, re.S | re.M).group(1)
    f = tmp_path / "mine.toml"
    f.write_text(block, encoding="utf-8")
    assert load_config(f) == preset(test_id)


def test_every_preset_file_is_read_and_cites_its_sources():
    folder = resources.files("twin.config.presets")
    names = sorted(p.name for p in folder.iterdir() if p.name.endswith(".toml"))
    assert names == sorted(["table4.toml"] + [f"{n}.toml" for n in NAMED_PRESETS])
    for n in names:
        text = folder.joinpath(n).read_text(encoding="utf-8")
        tomllib.loads(text)
        assert "PLACEHOLDER" in text or n == "table4.toml"
        assert re.search(r"S00[0-4]", text)


# --------------------------------------------------------------------- package surface
#: Every public name the single-module twin.config exported (the package keeps them).
FORMER_PUBLIC_NAMES = (
    "ACCELEROMETERS", "ACCEL_MODEL_NAMES", "ACCEL_RESPONSES", "ALL_CHANNEL_GROUPS", "CATALOGUE_DIAMETRAL_MM",
    "CHANNEL_GROUPS", "DAQ_RANGES", "ENGINES", "ENGINE_ONLY_GROUPS", "JOINTS", "NAMED_PRESETS",
    "OPTIONAL_CHANNEL_GROUPS", "ORIENTATIONS", "PROGRAMS", "TABLE4", "AccelMount", "BenchConfig", "Bodies",
    "BodyParams", "ConfigError", "Contact", "Drive", "Instrumentation", "Joints", "Material", "Materials",
    "Mechanism", "MujocoSettings", "PID", "Sensors", "Simulation", "config_from_toml", "from_dict",
    "joint_stiffness", "ln_stiffness", "load_config", "named_preset", "preset", "with_overrides",
)


def test_the_package_exports_the_former_names():
    missing = [n for n in FORMER_PUBLIC_NAMES if not hasattr(twin.config, n)]
    assert not missing
    assert set(FORMER_PUBLIC_NAMES) <= set(twin.config.__all__)
    assert not hasattr(twin.config, "DEFAULT_CONFIG")


def test_one_list_of_engines():
    """The engine names and the classes the simulator instantiates come from one mapping; each class
    is defined in its module (read with ast: importing the reference engine compiles numba code)."""
    assert ENGINES == tuple(ENGINE_CLASSES) == ("mujoco", "reference")
    for engines in ENGINE_ONLY_GROUPS.values():
        assert set(engines) <= set(ENGINES)
    for target in ENGINE_CLASSES.values():
        mod, cls = target.split(":")
        tree = ast.parse(open(importlib.util.find_spec(mod).origin, encoding="utf-8").read())
        assert cls in {n.name for n in tree.body if isinstance(n, ast.ClassDef)}, target
