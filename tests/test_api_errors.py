"""The Python API with bad arguments: every public call raises the project's typed error (a
:class:`~twin.errors.TwinError`) or a ``TypeError`` for a wrong type, and the message names the argument or the
field; never a bare ``ValueError``, ``IndexError``, ``KeyError`` or ``AttributeError`` from numpy or the
standard library.

The walk covers ``twin.__all__`` (``preset``, ``simulate``, ``replay``, ``identify``, ``BenchConfig``), the
configuration's public constructors and readers (``twin.config``), ``twin.dataset.open`` and the decision and
Taguchi study functions, with arguments of each kind: wrong type, NaN and infinity, negative, out of range,
empty, wrong shape, unknown names and strings where a list is expected. None of these calls simulates: each
is refused before an engine starts.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import twin
from twin import config as C
from twin.errors import TwinError

ROOT = Path(__file__).resolve().parent.parent
REC = str(ROOT / "recordings" / "test6_synthetic.mcap")
NAN, INF = math.nan, math.inf


def _api_cases(tmp: Path) -> list[tuple[str, object, str]]:
    """(id, call, fragment the message must hold: the argument or field it names)."""
    from twin.studies import mcdm, taguchi

    x = np.array([[1.0, 2.0], [2.0, 1.0], [3.0, 3.0]])
    return [
        # twin.preset
        ("preset None", lambda: twin.preset(None), "which"),
        ("preset float", lambda: twin.preset(6.0), "which"),
        ("preset bool", lambda: twin.preset(True), "which"),
        ("preset list", lambda: twin.preset([6]), "which"),
        ("preset nan", lambda: twin.preset(NAN), "which"),
        ("preset 0", lambda: twin.preset(0), "test: "),
        ("preset -1", lambda: twin.preset(-1), "test: "),
        ("preset 13", lambda: twin.preset(13), "test: "),
        ("preset empty", lambda: twin.preset(""), "preset"),
        ("preset unknown", lambda: twin.preset("s999"), "preset"),
        # twin.simulate
        ("simulate cfg float", lambda: twin.simulate(1.5), "cfg"),
        ("simulate cfg list", lambda: twin.simulate([6]), "cfg"),
        ("simulate duration str", lambda: twin.simulate(6, duration="1"), "duration"),
        ("simulate duration nan", lambda: twin.simulate(6, duration=NAN), "simulation.duration_s"),
        ("simulate duration inf", lambda: twin.simulate(6, duration=INF), "simulation.duration_s"),
        ("simulate duration negative", lambda: twin.simulate(6, duration=-1.0), "simulation.duration_s"),
        ("simulate duration huge", lambda: twin.simulate(6, duration=1e9), "simulation.duration_s"),
        ("simulate engine int", lambda: twin.simulate(6, duration=0.01, engine=3), "engine"),
        ("simulate engine unknown", lambda: twin.simulate(6, duration=0.01, engine="bullet"), "simulation.engine"),
        ("simulate overrides list", lambda: twin.simulate(6, duration=0.01, overrides=[("a", 1)]), "overrides"),
        ("simulate overrides str", lambda: twin.simulate(6, duration=0.01, overrides="a=1"), "overrides"),
        ("simulate overrides int key", lambda: twin.simulate(6, duration=0.01, overrides={1: 2}), "overrides"),
        ("simulate overrides unknown", lambda: twin.simulate(6, duration=0.01, overrides={"drive.nope": 1}),
         "drive.nope"),
        ("simulate overrides section", lambda: twin.simulate(6, duration=0.01, overrides={"nope.x": 1}), "nope.x"),
        ("simulate overrides nan", lambda: twin.simulate(6, duration=0.01, overrides={"drive.motor_rpm": NAN}),
         "drive.motor_rpm"),
        ("simulate overrides list as str", lambda: twin.simulate(6, duration=0.01,
                                                                 overrides={"sensors.channels": "accel"}),
         "sensors.channels"),
        ("simulate overrides absurd mass", lambda: twin.simulate(6, duration=0.01,
                                                                 overrides={"bodies.rod.mass_kg": 1e-300}),
         "bodies.rod.mass_kg"),
        ("simulate out int", lambda: twin.simulate(6, duration=0.01, out=3), "out"),
        ("simulate out empty", lambda: twin.simulate(6, duration=0.01, out=""), "out"),
        ("simulate out wrong suffix", lambda: twin.simulate(6, duration=0.01, out=str(tmp / "x.txt")), "out"),
        ("simulate progress str", lambda: twin.simulate(6, duration=0.01, progress="yes"), "progress"),
        # twin.replay
        ("replay recording None", lambda: twin.replay(None, tmp / "r"), "recording"),
        ("replay recording int", lambda: twin.replay(3, tmp / "r"), "recording"),
        ("replay recording empty", lambda: twin.replay("", tmp / "r"), "recording"),
        ("replay recording missing", lambda: twin.replay(tmp / "missing.mcap", tmp / "r"), "missing.mcap"),
        ("replay out None", lambda: twin.replay(REC, None), "out_dir"),
        ("replay window short", lambda: twin.replay(REC, tmp / "r", window_s=(1.0,)), "window_s"),
        ("replay window str", lambda: twin.replay(REC, tmp / "r", window_s="ab"), "window_s"),
        ("replay window nan", lambda: twin.replay(REC, tmp / "r", window_s=(NAN, 1.0)), "window_s"),
        ("replay window inverted", lambda: twin.replay(REC, tmp / "r", window_s=(2.0, 1.0)), "window_s"),
        ("replay window negative", lambda: twin.replay(REC, tmp / "r", window_s=(-1.0, 1.0)), "window_s"),
        ("replay overrides list", lambda: twin.replay(REC, tmp / "r", overrides=[1]), "overrides"),
        ("replay plots str", lambda: twin.replay(REC, tmp / "r", plots="no"), "plots"),
        # twin.identify
        ("identify None", lambda: twin.identify(None), "recording"),
        ("identify int", lambda: twin.identify(3), "recording"),
        ("identify model int", lambda: twin.identify(REC, model=3), "model"),
        ("identify model empty", lambda: twin.identify(REC, model=""), "model"),
        ("identify model missing", lambda: twin.identify(REC, model=tmp / "none.npz"), "none.npz"),
        # twin.BenchConfig and the configuration's constructors
        ("BenchConfig bodies int", lambda: twin.BenchConfig(bodies=3), "bodies"),
        ("BenchConfig simulation None", lambda: twin.BenchConfig(simulation=None), "simulation"),
        ("BenchConfig name int", lambda: twin.BenchConfig(name=3), "name"),
        ("BenchConfig name empty", lambda: twin.BenchConfig(name=""), "name"),
        ("Bodies crank str", lambda: C.Bodies(crank="crank"), "crank"),
        ("BodyParams str", lambda: C.BodyParams("1", 0.1, 0.0, 1e-3), "mass_kg"),
        ("BodyParams nan", lambda: C.BodyParams(1.0, NAN, 0.0, 1e-3), "length_m"),
        ("BodyParams negative", lambda: C.BodyParams(-1.0, 0.1, 0.0, 1e-3), "mass_kg"),
        ("BodyParams tiny", lambda: C.BodyParams(1.0, 1e-300, 0.0, 1e-3), "length_m"),
        ("Material str", lambda: C.Material("steel", 0.3, 7850.0), "youngs_modulus_pa"),
        ("Material None", lambda: C.Material(2e11, None, 7850.0), "poisson"),
        ("Material inf", lambda: C.Material(INF, 0.3, 7850.0), "youngs_modulus_pa"),
        ("Materials pins list", lambda: C.Materials(pins=[1]), "pins"),
        ("Materials pins unknown joint", lambda: C.Materials(pins={"D": C.Material(2e11, 0.3, 7850.0)}), "pins.D"),
        ("Joints clearance str", lambda: C.Joints(clearance_b_mm="wide"), "clearance_b_mm"),
        ("Joints pin list", lambda: C.Joints(pin_diameters_m=[0.01]), "pin_diameters_m"),
        ("Joints pin nan", lambda: C.Joints(pin_diameter_m=NAN), "pin_diameter_m"),
        ("Joints eccentricity", lambda: C.Joints(initial_eccentricity="middle"), "initial_eccentricity"),
        ("Mechanism gravity str", lambda: C.Mechanism(gravity_mps2="g"), "gravity_mps2"),
        ("Mechanism gravity nan", lambda: C.Mechanism(gravity_mps2=NAN), "gravity_mps2"),
        ("Mechanism orientation", lambda: C.Mechanism(orientation="w"), "orientation"),
        ("Contact restitution str", lambda: C.Contact(restitution="0.4"), "restitution"),
        ("Contact v1 nan", lambda: C.Contact(v1_mps=NAN), "v1_mps"),
        ("Contact stiffness tiny", lambda: C.Contact(stiffness=1e-300), "stiffness"),
        ("Drive protocol str", lambda: C.Drive(protocol_rpm="250"), "protocol_rpm"),
        ("Drive protocol [str]", lambda: C.Drive(protocol_rpm=["a"]), "protocol_rpm"),
        ("Drive steps str", lambda: C.Drive(program="steps", steps_s="01", steps_rpm="12"), "steps_s"),
        ("Drive steps None", lambda: C.Drive(steps_s=[None], steps_rpm=[1.0]), "steps_s"),
        ("Drive ramp nan", lambda: C.Drive(ramp_s=NAN), "ramp_s"),
        ("Drive hold nan", lambda: C.Drive(protocol_hold_s=NAN), "protocol_hold_s"),
        ("Drive mode unknown", lambda: C.Drive(mode="servo"), "mode"),
        ("PID str", lambda: C.PID(kv="a"), "kv"),
        ("Simulation duration str", lambda: C.Simulation(duration_s="1"), "duration_s"),
        ("Simulation timestep nan", lambda: C.Simulation(timestep_s=NAN), "timestep_s"),
        ("MujocoSettings solref str", lambda: C.MujocoSettings(contact_solref="ab"), "contact_solref"),
        ("MujocoSettings solref nan", lambda: C.MujocoSettings(contact_solref=(NAN, 1.0)), "contact_solref"),
        ("MujocoSettings tolerance nan", lambda: C.MujocoSettings(tolerance=NAN), "tolerance"),
        ("Sensors channels str", lambda: C.Sensors(channels="accel"), "channels"),
        ("Sensors accelerometers list", lambda: C.Sensors(accelerometers=[1]), "accelerometers"),
        ("Sensors rate str", lambda: C.Sensors(output_rate_hz="fast"), "output_rate_hz"),
        ("AccelMount position str", lambda: C.AccelMount("rod", "ab", "+x"), "position_m"),
        ("AccelMount position wrong shape", lambda: C.AccelMount("rod", (0.1, 0.0, 0.0), "+x"), "position_m"),
        ("Instrumentation models list", lambda: C.Instrumentation(models=[1]), "models"),
        ("Instrumentation supply nan", lambda: C.Instrumentation(supply_v=NAN), "supply_v"),
        ("Drivetrain str", lambda: C.Drivetrain(rotor_inertia_kgm2="a"), "rotor_inertia_kgm2"),
        ("Drivetrain torque_s str", lambda: C.Drivetrain(torque_s="12", torque_nm="34"), "torque_s"),
        ("Spatial enabled int", lambda: C.Spatial(enabled=1), "enabled"),
        ("Spatial offset str", lambda: C.Spatial(guide_offset_y_m="a"), "guide_offset_y_m"),
        # readers and overrides
        ("from_dict list", lambda: C.from_dict(C.BenchConfig, [1]), "BenchConfig"),
        ("with_overrides list", lambda: C.with_overrides(twin.preset(6), [1]), "overrides"),
        ("with_overrides int key", lambda: C.with_overrides(twin.preset(6), {1: 2}), "overrides"),
        ("replace unknown", lambda: twin.preset(6).replace(**{"joints.nope": 1.0}), "joints.nope"),
        ("replace list as str", lambda: twin.preset(6).replace(**{"drive.protocol_rpm": "250"}), "drive.protocol_rpm"),
        ("load_config int", lambda: C.load_config(3), "path"),
        ("load_config None", lambda: C.load_config(None), "path"),
        ("load_config empty", lambda: C.load_config(""), "path: "),
        ("load_config missing", lambda: C.load_config(tmp / "none.toml"), "none.toml"),
        ("config_from_toml int", lambda: C.config_from_toml(3), "text"),
        ("config_from_toml bad", lambda: C.config_from_toml("[joints\n"), "config"),
        ("preset fn 0", lambda: C.preset(0), "test: "),
        ("named_preset int", lambda: C.named_preset(3, "preset"), "preset"),
        ("joint_stiffness unknown", lambda: C.joint_stiffness(twin.preset(6), "D"), "joint"),
        ("ln_stiffness ideal joint", lambda: C.ln_stiffness(twin.preset(6).joints, twin.preset(6).materials, "A"),
         "joints.clearance_a_mm"),
        # twin.dataset.open
        ("dataset.open int", lambda: twin.dataset.open(3), "path"),
        ("dataset.open missing", lambda: twin.dataset.open(tmp / "none"), "none"),
        ("dataset.open file", lambda: twin.dataset.open(ROOT / "README.md"), "README.md"),
        # decision and Taguchi studies
        ("mcdm check_matrix 1-D", lambda: mcdm.check_matrix(np.ones(3), ["a"]), "criteria: "),
        ("mcdm check_matrix nan", lambda: mcdm.check_matrix(np.array([[1.0], [NAN]]), ["a"]), "'a'"),
        ("mcdm check_matrix negative", lambda: mcdm.check_matrix(np.array([[1.0], [-2.0]]), ["a"]), "'a'"),
        ("mcdm check_matrix span", lambda: mcdm.check_matrix(np.array([[1e-200], [1e200]]), ["a"]), "'a'"),
        ("mcdm weights wrong shape", lambda: mcdm.saw(x, [False, True], [1.0]), "weights"),
        ("mcdm weights nan", lambda: mcdm.topsis(x, [False, True], [NAN, 1.0]), "weights"),
        ("mcdm weights overflow", lambda: mcdm.gra(x, [False, True], [1e308, 1e308]), "weights"),
        ("mcdm benefit wrong shape", lambda: mcdm.gra(x, [True], [0.5, 0.5]), "benefit"),
        ("mcdm lambda", lambda: mcdm.waspas(x, [False, True], [0.5, 0.5], lam=2.0), "lam: "),
        ("mcdm criteria empty", lambda: mcdm.parse_criteria(""), "criteria: "),
        ("mcdm weights text", lambda: mcdm.parse_weights("a,b", x, [False, True], ["a", "b"]), "weights: "),
        ("taguchi sn kind", lambda: taguchi.sn_ratio(np.ones(3), "middle"), "sn: "),
        ("taguchi sn zero", lambda: taguchi.sn_ratio(np.zeros(3), "larger"), "sn: "),
        ("taguchi single level", lambda: taguchi.level_index([1.0, 1.0], "A"), "'A'"),
    ]


CASES = _api_cases(Path("/nonexistent-dir-of-the-api-test"))


@pytest.mark.parametrize("case", range(len(CASES)), ids=[c[0] for c in CASES])
def test_the_public_api_refuses_bad_arguments_with_a_typed_error_naming_them(case, tmp_path):
    name, call, fragment = _api_cases(tmp_path)[case]
    with pytest.raises(Exception) as info:
        call()
    err = info.value
    assert isinstance(err, TwinError) or type(err) is TypeError, f"{name}: bare {type(err).__name__}: {err}"
    assert fragment in str(err), f"{name}: {err}"
    assert "\n" not in str(err), f"{name}: not one line: {err}"


def test_the_walk_covers_the_public_api():
    """Every name of ``twin.__all__`` that can be called, and every public constructor and reader of
    ``twin.config``, is called with bad arguments above."""
    names = " ".join(c[0] for c in CASES)
    for call in ("preset", "simulate", "replay", "identify", "BenchConfig"):
        assert call in twin.__all__ and call in names, call
    for ctor in ("Bodies", "BodyParams", "Material", "Materials", "Joints", "Mechanism", "Contact", "Drive", "PID",
                 "Simulation", "MujocoSettings", "Sensors", "AccelMount", "Instrumentation", "Drivetrain", "Spatial",
                 "from_dict", "with_overrides", "load_config", "config_from_toml", "named_preset", "joint_stiffness",
                 "ln_stiffness"):
        assert ctor in C.__all__ and ctor in names, ctor
    assert len(CASES) >= 100


def test_valid_numpy_and_integer_arguments_are_accepted():
    """Valid input the API used to refuse or mishandle: numpy scalars (from an array) for numbers and test
    ids, integers for floats, a per-joint table entry set by its dotted path."""
    cfg = twin.preset(np.int64(6)).replace(**{"drive.motor_rpm": np.int64(500), "mujoco.iterations": np.int32(30),
                                              "simulation.duration_s": 1, "joints.pin_diameters_m.B": 0.015})
    assert cfg.name == "test6" and cfg.drive.motor_rpm == 500.0 and isinstance(cfg.drive.motor_rpm, float)
    assert cfg.mujoco.iterations == 30 and type(cfg.mujoco.iterations) is int
    assert cfg.joints.pin_diameter("B") == 0.015 and cfg.joints.pin_diameter("C") == twin.preset(6).joints.pin_diameter_m
