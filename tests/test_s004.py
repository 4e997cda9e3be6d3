"""S004 (issue 18, item 3): the preset in both engines and the continuous-contact model.

Independent bases: the closed-form kinematics (twin.kinematics.slider_kinematics) for the ideal
run; for the continuous-contact model (twin.studies.continuous_contact), its energy with the crank held (the
equation of motion comes from the partial velocities, the energy from the positions' velocities:
conservation checks the derivation), Newton–Euler on rod and slider (the force across the virtual
rod must vanish for frictionless contact), and the limit c → 0 (the ideal mechanism).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.config import ln_stiffness, named_preset
from twin.kinematics import slider_kinematics
from twin.simulation import simulate_run
from twin.studies.continuous_contact import ContinuousContact, Mechanism, phases

W = 30.0


def test_preset_is_the_papers_mechanism():
    c = named_preset("s004")
    b = c.bodies
    assert b.crank.mass_kg == pytest.approx(7850 * 1.0 * 0.1 * 0.05)
    assert b.rod.mass_kg == pytest.approx(7850 * 2.0 * 0.1 * 0.05)
    assert b.slider.mass_kg == pytest.approx(7850 * 0.5 ** 3)
    assert (b.crank.length_m, b.rod.length_m) == (1.0, 2.0)
    assert b.rod.inertia_kgm2 == pytest.approx(78.5 * (4 + 0.01) / 12)
    assert c.joints.radial_m("B") == pytest.approx(0.5e-3) and c.joints.clearance_c_mm == 0
    assert c.drive.mode == "prescribed" and c.drive.crank_rad_s == pytest.approx(W)
    assert c.contact.law == "adams-impact" and c.contact.impact_d_max_m == 1e-5
    assert ln_stiffness(c.joints, c.materials, "B") == pytest.approx(1.71e11, rel=0.01)


@pytest.mark.parametrize("engine", ["reference", "mujoco"])
def test_ideal_run_equals_closed_form(engine):
    """0 mm at B: the slider of S004's mechanism at a prescribed 30 rad/s is the closed form
    (reference: exact to the channels' storage; MuJoCo: within its soft connect at C, 2e-10 m per
    m/s², tests/test_prescribed.py)."""
    cfg = named_preset("s004").replace(**{"simulation.engine": engine, "joints.clearance_b_mm": 0.0,
                                          "simulation.duration_s": 0.25})
    run = simulate_run(cfg)
    th = np.asarray(run["crank_angle"].data, dtype=float)
    t = np.arange(len(th)) / run.rate_hz
    assert np.max(np.abs(th - W * t)) < 1e-12
    x, _, a = slider_kinematics(th, W, 0.0, 1.0, 2.0, 0.0)
    peak = np.max(np.abs(a))
    assert peak == pytest.approx(1.0 * W ** 2 * 1.5)      # r ω² (1 + r/l) at θ = 0
    settle = t >= (0.005 if engine == "mujoco" else 0.0)
    tol_a = 1e-6 if engine == "reference" else 1e-4
    assert np.max(np.abs(np.asarray(run["AC6"].data)[settle] - a[settle])) < tol_a * peak
    tol_x = 1e-13 if engine == "reference" else 3e-10
    assert np.max(np.abs(np.asarray(run["slider_position"].data)[settle] - x[settle])) < tol_x * peak


def test_continuous_model_conserves_energy_with_the_crank_held():
    model = ContinuousContact(Mechanism.from_config(named_preset("s004")))
    t = np.linspace(0.0, 0.05, 501)
    hold = lambda tt: 0.7 + 0 * np.asarray(tt, float)  # noqa: E731
    zero = lambda tt: 0 * np.asarray(tt, float)  # noqa: E731
    res = model.simulate(t, hold, zero, zero, 1.0, 0.0, rtol=1e-11, atol=1e-13)
    assert np.ptp(res["psi"]) > 0.1                     # it does swing
    e = model.energy(0.7, 0.0, res["psi"], res["wpsi"])
    assert np.ptp(e) < 1e-9 * (78.5 + 981.25) * 9.81 * 1e-3  # vs the energy scale m g c
    assert np.max(np.abs(res["ft"])) < 1e-6 * np.max(np.abs(res["fn"]))


def test_continuous_model_force_is_along_the_virtual_rod_when_driven():
    model = ContinuousContact(Mechanism.from_config(named_preset("s004")))
    psi0, dpsi0 = model.quasi_static_start(0.0, W)
    t = np.linspace(0.0, 0.02, 201)
    res = model.simulate(t, lambda tt: W * np.asarray(tt, float), lambda tt: W + 0 * np.asarray(tt, float),
                         lambda tt: 0 * np.asarray(tt, float), psi0, dpsi0)
    assert np.max(np.abs(res["ft"])) < 1e-6 * np.max(np.abs(res["fn"]))
    assert np.all(res["fn"] > 0)                      # started along the load: in contact


def test_continuous_model_tends_to_the_ideal_mechanism():
    """c → 0: the virtual rod vanishes and the slider is the closed form whatever ψ does."""
    cfg = named_preset("s004")
    mech = Mechanism.from_config(cfg, radial_clearance_m=1e-9)
    model = ContinuousContact(mech)
    th = np.linspace(0.0, 2 * math.pi, 50)
    k = model.kinematics(th, W, 0.0, 0.3, 5.0, 0.0)
    x, v, a = slider_kinematics(th, W, 0.0, 1.0, 2.0, 0.0)
    assert np.max(np.abs(k["x3"] - x)) < 2e-9
    assert np.max(np.abs(k["x3d"] - v)) < 1e-7
    assert np.max(np.abs(k["x3dd"] - a)) < 1e-5
    # and the quasi-static start points the virtual rod against the ideal pin force
    psi0, _ = ContinuousContact(Mechanism.from_config(cfg)).quasi_static_start(0.0, W)
    # at θ = 0 the slider decelerates at r ω² (1 + r/l) towards A: the rod is in tension, the pin pulls
    # the rod eye towards A (F along −x), so the eye's centre sits on the C side of the pin: u = +x̂
    assert abs(math.cos(psi0) - 1.0) < 1e-3


def test_phases_classify_contact_events():
    rate = 1e5
    fn = np.zeros(10000)
    fn[100:150] = 1.0          # 0.5 ms: impact
    fn[1000:6000] = 2.0        # 50 ms: contact
    p = phases(fn, rate)
    assert (p["impacts"], p["contacts"]) == (1, 1)
    assert p["separation_fraction"] == pytest.approx(1 - 5050 / 10000)
    assert p["impact_fraction"] == pytest.approx(50 / 10000)
    assert p["contact_fraction"] == pytest.approx(5000 / 10000)


def test_s004_preset_from_cli_toml_and_rerun(tmp_path, capsys):
    """--preset s004 on the command line in both engines (run file and rerun recording written) and
    preset = "s004" in TOML."""
    from twin.cli import main
    from twin.config import load_config

    f = tmp_path / "c.toml"
    f.write_text('preset = "s004"\n[joints]\nclearance_b_mm = 0.5\n')
    cfg = load_config(f)
    assert cfg.joints.radial_m("B") == pytest.approx(0.25e-3) and cfg.bodies.slider.mass_kg == pytest.approx(981.25)
    for engine in ("reference", "mujoco"):
        out = tmp_path / f"{engine}.mcap"
        rrd = tmp_path / f"{engine}.rrd"
        assert main(["simulate", "--preset", "s004", "--engine", engine, "--duration", "0.01", "--out", str(out),
                     "--rerun", str(rrd)]) == 0
        assert out.stat().st_size > 0 and rrd.stat().st_size > 0
    capsys.readouterr()


def test_study_command_writes_its_files_and_refuses_other_mechanisms(tmp_path, capsys):
    from twin.cli import main

    out = tmp_path / "cc"
    assert main(["study", "continuous-contact", "--out", str(out), "--duration", "0.02"]) == 0
    import json

    s = json.loads((out / "continuous_contact.json").read_text())
    assert s["clearance_radial_m"] == pytest.approx(5e-4) and s["valid_until_s"] == pytest.approx(0.02)
    assert s["ft_max_abs_n"] < 1e-6 * s["fn_max_n"]
    assert {p.name for p in out.iterdir()} == {"continuous_contact.json", "continuous_contact.npz",
                                               "continuous_contact.png"}
    # S001 has its clearance at C: refused in one line, nothing written
    bad = tmp_path / "bad"
    assert main(["study", "continuous-contact", "--out", str(bad), "--preset", "s001"]) == 2
    assert "joints.clearance_b_mm" in capsys.readouterr().err and not bad.exists()
