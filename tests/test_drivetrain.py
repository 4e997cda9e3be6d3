"""Drive train (drive.mode "motor"/"torque"): configuration, independent physics checks, engines.

Independent bases: the rotor–belt–crank natural frequency against two inertias coupled by the
belt stiffness referred through the pulley radii (the crank side's inertia from the closed-form
kinematics of the slider–crank, not from either engine's mass matrix); the coast-down's energy
loss per turn against the guide's friction work over the slider's travel (closed-form
kinematics); the energy balance (motor work = Δ(kinetic + potential + belt) + dissipation, each
dissipation from its own force law); the other engine.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.config import BenchConfig, preset
from twin.config import Drivetrain
from twin.errors import ConfigError
from twin.kinematics import initial_pose
from twin.motor_drive import crank_side_inertia, speed_harmonics
from twin.simulation import simulate_run

ENGINES = ("mujoco", "reference")


def _run(cfg: BenchConfig) -> dict[str, np.ndarray]:
    return {k: np.asarray(v.data, dtype=np.float64) for k, v in simulate_run(cfg).channels.items()}


# ----------------------------------------------------------------------- configuration
def test_defaults_leave_todays_configuration_alone():
    cfg = preset(12)
    assert cfg.drive.mode == "pid"
    assert "drivetrain" not in cfg.to_dict()  # TOML text and digest of PID/prescribed runs unchanged
    motor = cfg.replace(**{"drive.mode": "motor"})
    assert "drivetrain" in motor.to_dict()
    from twin.config import config_from_toml

    assert config_from_toml(motor.replace(**{"drivetrain.preload_n": 80.0}).to_toml()).drivetrain.preload_n == 80.0


@pytest.mark.parametrize("key,value", [("drivetrain.preload_n", -1.0), ("drivetrain.friction_mu", 0.0),
                                       ("drivetrain.encoder_counts", 4096.5), ("drivetrain.torque_nm", [1.0, 2.0]),
                                       ("drivetrain.controller_rate_hz", 3000.0), ("drive.mode", "belt")])
def test_bad_values_name_the_field(key, value):
    with pytest.raises(ConfigError) as err:
        preset(12).replace(**{"drive.mode": "motor", key: value})
    text = str(err.value)
    assert key.split(".")[-1] in text and "\n" not in text


def test_cli_bad_value_one_line(tmp_path, capsys):
    from twin.cli import main

    rc = main(["simulate", "--test", "1", "--drive-mode", "motor", "--set", "drivetrain.belt_ea_n=-5",
               "--duration", "0.01", "--out", str(tmp_path / "x.mcap"), "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "drivetrain.belt_ea_n" in err and len(err.splitlines()) == 1


def test_capstan_limit_closed_form():
    d = Drivetrain(preload_n=100.0, friction_mu=0.3, groove_angle_deg=38.0, wrap_angle_rad=2.8)
    mu_w = 0.3 / math.sin(math.radians(19.0))
    tight_over_slack = math.exp(mu_w * 2.8)
    # T_t + T_s = 2 F0, T_t / T_s = e^{mu' phi}: F = T_t - T_s
    slack = 200.0 / (1 + tight_over_slack)
    assert d.max_pull_n == pytest.approx(tight_over_slack * slack - slack, rel=1e-12)


# --------------------------------------------------------------- natural frequency
@pytest.mark.parametrize("engine", ENGINES)
def test_rotor_belt_crank_natural_frequency(engine):
    """A small torque step on the free rotor rings the rotor–belt–crank mode (no belt damping,
    no gravity, no guide friction); its frequency is that of two inertias J_m r_c²/r_m² and J_c(θ0)
    (closed-form kinematics) on the belt's torsional stiffness k r_c² (crank side)."""
    theta0 = 0.3
    cfg = preset(1).replace(**{
        "name": "ring", "drive.mode": "torque", "simulation.engine": engine, "simulation.duration_s": 0.06,
        "drive.initial_encoder_angle_rad": theta0 + math.pi / 2, "mechanism.gravity_mps2": 0.0,
        "mechanism.guide_friction_n": 0.0, "drivetrain.belt_damping_nspm": 0.0,
        "drivetrain.torque_s": [0.0], "drivetrain.torque_nm": [0.02], "drivetrain.torque_ramp_s": 0.0,
        "drivetrain.release_s": 0.0, "sensors.channels": ["crank", "motor"]})
    ch = _run(cfg)
    dt, n = cfg.drivetrain, cfg.drive.belt_ratio
    r_m, r_c = dt.motor_pulley_radius_m, dt.crank_pulley_radius_m(n)
    j_c = crank_side_inertia(cfg, theta0)
    j_m = dt.rotor_inertia_kgm2 * (r_c / r_m) ** 2
    k_t = dt.stiffness_npm * r_c ** 2
    f_closed = math.sqrt(k_t * (1 / j_c + 1 / j_m)) / (2 * math.pi)
    assert abs(ch["crank_angle"][-1] - theta0) < 0.01  # linearized about the pose: it barely moves
    y = ch["belt_torque"] - np.polyval(np.polyfit(np.arange(ch["belt_torque"].size), ch["belt_torque"], 2),
                                       np.arange(ch["belt_torque"].size))
    up = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    tc = (up + -y[up] / (y[up + 1] - y[up])) / cfg.output_rate_hz  # interpolated upward zero crossings
    f_sim = (len(tc) - 1) / (tc[-1] - tc[0])
    assert len(tc) >= 4
    assert f_sim == pytest.approx(f_closed, rel=0.01), (f_sim, f_closed)


# -------------------------------------------------------------------- coast-down
@pytest.mark.parametrize("engine", ENGINES)
def test_coast_down_loses_the_guide_friction_work_per_turn(engine):
    """After release the mechanism coasts through the belt; without gravity its energy at the same
    crank angle one turn later is lower by the guide's friction work F × the slider's travel per
    turn (closed-form kinematics), up to the belt's own losses."""
    cfg = preset(1).replace(**{
        "name": "coast", "drive.mode": "torque", "simulation.engine": engine, "simulation.duration_s": 2.5,
        "mechanism.gravity_mps2": 0.0, "drivetrain.torque_s": [0.0], "drivetrain.torque_nm": [1.0],
        "drivetrain.torque_ramp_s": 0.05, "drivetrain.release_s": 0.5,
        "sensors.channels": ["crank", "slider", "motor", "drive_energy"], "sensors.output_rate_hz": 10000.0})
    ch = _run(cfg)
    t = np.arange(ch["crank_angle"].size) / cfg.output_rate_hz
    th = np.unwrap(ch["crank_angle"])
    e = ch["energy_mechanical"] + ch["energy_belt"]
    after = t > 0.6
    start = th[after][0]
    marks = start + 2 * math.pi * np.arange(1, 4)
    assert th[-1] > marks[-1], "coasts at least three turns"
    e_at = np.interp(marks, th[after], e[after])
    lost = -np.diff(e_at)
    thetas = np.linspace(0, 2 * math.pi, 20001)
    xs = np.array([initial_pose(cfg, a).slider_x for a in thetas])
    travel = float(np.sum(np.abs(np.diff(xs))))
    expected = cfg.mechanism.guide_friction_n * travel
    assert np.all(np.abs(lost - expected) < 0.01 * expected), (lost, expected)
    # mean deceleration over a turn: the friction's mean torque over the turn-average inertia
    assert np.all(np.diff(np.interp(marks, th, np.gradient(th, t))) < 0)


# ----------------------------------------------------------------- energy balance
def _balance(engine: str, test: int, h: float | None = None, duration: float = 0.8) -> tuple[dict, float, float]:
    """Channels of a motor-driven run from rest, its motor work [J] and the balance's residual
    W − [Δ(mechanism + rotor energy) + belt elastic energy + every dissipation] [J]."""
    over = {"drive.mode": "motor", "simulation.engine": engine, "simulation.duration_s": duration,
            "sensors.channels": ["crank", "motor", "drive_energy"], "sensors.output_rate_hz": 1000.0}
    if h is not None:
        over["simulation.timestep_s"] = h
    ch = _run(preset(test).replace(**over))
    work = ch["motor_work"][-1]
    rest = (ch["energy_mechanical"][-1] - ch["energy_mechanical"][0] + ch["energy_belt"][-1]
            + ch["diss_belt_damping"][-1] + ch["diss_belt_slip"][-1] + ch["diss_guide"][-1] + ch["diss_contact"][-1])
    return ch, work, work - rest


@pytest.mark.parametrize("engine,test", [("mujoco", 12), ("mujoco", 9), ("reference", 1), ("reference", 6),
                                         ("reference", 9), ("reference", 12)])
def test_energy_balance(engine, test):
    """Motor work = Δ(kinetic + gravitational energy of mechanism and rotor) + belt elastic energy
    + belt damping + creep/slip + guide friction + joint dissipation, to 1e-3 of the motor work over
    0.8 s from rest, at each engine's default step (tests 9 and 12: a clearance at B, the pin
    riding and hitting its bushing)."""
    ch, work, residual = _balance(engine, test)
    assert work > 1.0
    assert abs(residual) < 1e-3 * work, (work, residual)
    for k in ("diss_belt_damping", "diss_belt_slip", "diss_guide"):
        assert ch[k][-1] > 0


@pytest.mark.parametrize("test", [9, 12])
def test_the_reference_energy_residual_is_the_integrators_first_order_error(test):
    """What the reference engine's balance leaves is the first-order (symplectic Euler with
    coordinate-partitioned projection) step's error, not a leak in the accounts: halving the step
    halves it (a missing or double-booked power would not depend on h). It grows with the run's
    length (2 s of test 9 at 1e-5 s: 2.8e-3 of the motor work; docs/drivetrain.md), so long balances
    need the finer step."""
    r = [_balance("reference", test, h)[2] for h in (1e-5, 5e-6)]
    assert r[0] > 0 and 1.9 < r[0] / r[1] < 2.1, r


# ------------------------------------------------------------------ two engines
@pytest.mark.parametrize("test", [3, pytest.param(12, marks=pytest.mark.slow)])
def test_engines_agree_on_crank_ripple(test):
    h = {}
    for engine in ENGINES:
        cfg = preset(test).replace(**{"drive.mode": "motor", "simulation.engine": engine, "simulation.duration_s": 2.2,
                                      "sensors.channels": ["crank", "motor"], "sensors.output_rate_hz": 10000.0})
        ch = _run(cfg)
        keep = np.arange(ch["crank_angle"].size) / cfg.output_rate_hz >= 1.0  # after the spin-up
        h[engine] = speed_harmonics(ch["crank_angle"][keep], ch["crank_speed"][keep])
    assert h["mujoco"][0] > 1.0  # a ripple to compare
    np.testing.assert_allclose(h["mujoco"], h["reference"], rtol=0.05)


def test_engines_agree_on_peak_contact_forces_under_the_motor_drive():
    """Test 12 (0.5 mm at B and C) driven by the motor through the belt, 1.2 s after a 1 s spin-up:
    the two engines' peak joint contact forces within 5 % (measured: +1.1 % at B and C)."""
    peak = {}
    for engine in ENGINES:
        cfg = preset(12).replace(**{"drive.mode": "motor", "simulation.engine": engine, "simulation.duration_s": 2.2,
                                    "sensors.channels": ["crank", "joints"], "sensors.output_rate_hz": 100000.0})
        ch = _run(cfg)
        keep = np.arange(ch["crank_angle"].size) / cfg.output_rate_hz >= 1.0
        peak[engine] = np.array([ch[k][keep].max() for k in ("fn_B", "fn_C")])
    assert np.all(peak["reference"] > 100.0)  # the pins ride and hit: forces to compare
    np.testing.assert_allclose(peak["mujoco"], peak["reference"], rtol=0.05)


# ------------------------------------------------------------------------- replay
@pytest.mark.slow
def test_replay_compares_the_motor_drive(tmp_path):
    """``twin replay --drive motor``: the motor model from the recorded command beside the PID."""
    from pathlib import Path

    from twin.bench_replay import ReplayOptions, replay

    rec = Path(__file__).resolve().parents[1] / "recordings" / "test3_synthetic.mcap"
    r = replay(rec, tmp_path / "out", lambda c: c.replace(**{"simulation.engine": "reference"}),
               ReplayOptions(plots=False, drive="motor"))
    md = r.motor_drive
    assert set(md.sensors) == set(r.sensors)
    assert md.sensors["AC4"].pid_nrmse_pct == r.sensors["AC4"].nrmse_pct
    assert (tmp_path / "out" / "motor_command_trace.npz").is_file()
    assert "Drives compared" in (tmp_path / "out" / "report.md").read_text()


def test_dataset_factors_set_the_drive_train():
    from twin.dataset.factors import NAMED

    ov: dict = {}
    NAMED["drive_mode"].apply("motor", ov, None, preset(12))
    NAMED["belt_preload_n"].apply(80.0, ov, None, preset(12))
    cfg = preset(12).replace(**ov)
    assert cfg.drive.mode == "motor" and cfg.drivetrain.preload_n == 80.0


# ------------------------------------------------------------------------ belt law
def test_belt_law_creep_and_slip():
    """The closed-form pull satisfies F = k x + c (v_rel − w(F)) with w = F |v_m|/EA below the
    capstan limit (creep: speed loss ∝ pull) and F_max |v_m|/EA + (|F| − F_max)/c_slip beyond."""
    from twin.reference import drivetrain as DT

    cfg = preset(1).replace(**{"drive.mode": "motor"})
    D = DT.build(cfg)
    k, c, ea, fmax, cs = (D[i] for i in (DT.D_K, DT.D_C, DT.D_EA, DT.D_FMAX, DT.D_CS))
    out = np.empty(3)
    rng = np.random.default_rng(1)
    for x, v_rel, v_m in zip(rng.normal(0, 3e-3, 200), rng.normal(0, 0.05, 200), rng.normal(0, 2.0, 200)):
        DT.belt_pull(D, x, v_rel, v_m, out)
        F, w, xd = out
        expect_w = F * abs(v_m) / ea if abs(F) <= fmax else \
            np.sign(F) * (fmax * abs(v_m) / ea + (abs(F) - fmax) / cs)
        assert w == pytest.approx(expect_w, rel=1e-9, abs=1e-15)
        assert F == pytest.approx(k * x + c * (v_rel - w), rel=1e-9, abs=1e-9)
        assert xd == pytest.approx(v_rel - w, abs=1e-15)
        assert F * w >= 0  # creep and slip dissipate
    # continuity at the limit: the pull that just reaches F_max from both sides
    v_m = 1.5
    lam = v_m / ea
    x_lim = fmax * (1 + c * lam) / k  # v_rel = 0
    DT.belt_pull(D, x_lim * (1 - 1e-9), 0.0, v_m, out)
    below = out[0]
    DT.belt_pull(D, x_lim * (1 + 1e-9), 0.0, v_m, out)
    assert below == pytest.approx(fmax, rel=1e-6) and out[0] == pytest.approx(fmax, rel=1e-6)


def test_engines_agree_while_the_belt_slips():
    """A slack belt (low preload) slips during the spin-up in both engines alike."""
    runs = {}
    for engine in ENGINES:
        cfg = preset(1).replace(**{"drive.mode": "motor", "simulation.engine": engine, "simulation.duration_s": 0.4,
                                   "drive.ramp_s": 0.1, "drivetrain.preload_n": 6.0,
                                   "sensors.channels": ["crank", "motor"], "sensors.output_rate_hz": 1000.0})
        runs[engine] = _run(cfg)
        limit = cfg.drivetrain.max_pull_n * cfg.drivetrain.crank_pulley_radius_m(cfg.drive.belt_ratio)
    for ch in runs.values():
        assert np.max(np.abs(ch["belt_torque"])) < 1.1 * limit       # held near the capstan limit
        assert np.max(np.abs(ch["belt_slip"])) > 0.05                 # and sliding [m/s], not creeping
    a, b = runs["mujoco"], runs["reference"]
    np.testing.assert_allclose(a["crank_speed"][-100:].mean(), b["crank_speed"][-100:].mean(), rtol=0.02)
    np.testing.assert_allclose(a["motor_speed"][-100:].mean(), b["motor_speed"][-100:].mean(), rtol=0.02)


@pytest.mark.parametrize("engine", ENGINES)
def test_chunking_does_not_change_the_drive_train(engine):
    """The drive train's state (rotor, belt stretch, controller, accounts) carries over between chunks."""
    base = preset(12).replace(**{"drive.mode": "motor", "simulation.engine": engine, "simulation.duration_s": 0.05,
                                 "sensors.channels": ["crank", "motor", "drive_energy"],
                                 "sensors.output_rate_hz": 10000.0})
    a = _run(base.replace(**{"simulation.chunk_s": 0.05}))
    b = _run(base.replace(**{"simulation.chunk_s": 0.0037}))
    for name in ("crank_angle", "motor_speed", "motor_torque", "belt_torque", "motor_work", "diss_contact"):
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


def test_torque_presets():
    from twin.config import named_preset

    for name in ("torque_release", "torque_release_protocol"):
        cfg = named_preset(name)
        assert cfg.drive.mode == "torque" and "motor" in cfg.sensors.channels
        tq = cfg.drivetrain.torque_program(np.arange(0.0, cfg.duration_s, 1e-3))
        assert tq.max() > 0 and tq[-1] == 0.0  # spun up, then released
