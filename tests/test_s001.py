"""S001's rig (issue 18): the preset, the Adams/COSMOS friction and the linear ramp in both
engines, and the ideal run's slider-acceleration peaks against the closed form rω²(1 ± r/L)."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from twin import names
from twin.cli import build_parser, config_from_args
from twin.config import BenchConfig, config_from_toml, ln_stiffness, load_config, named_preset
from twin.drive import DriveReference
from twin.errors import ConfigError
from twin.simulation import simulate_run

from conftest import bore_bias_acceleration


def _adams_mu(v, mus, mud, vs, vd):
    """MSC Adams' contact friction coefficient, written from its documentation (independent
    of twin.physics.contact): step(v, −vs, μs, vs, −μs) of the force direction inside ±vs,
    −step(|v|, vs, μs, vd, μd) sign(v) beyond; returned as a magnitude."""
    def step(x, x0, h0, x1, h1):
        d = np.clip((x - x0) / (x1 - x0), 0.0, 1.0)
        return h0 + (h1 - h0) * d * d * (3 - 2 * d)
    v = np.abs(np.asarray(v, dtype=float))
    return np.where(v < vs, -step(v, -vs, mus, vs, -mus), step(v, vs, mus, vd, mud))


# ---------------------------------------------------------------------------- preset
def test_s001_preset_holds_the_papers_numbers():
    c = named_preset("s001")
    assert (c.bodies.crank.length_m, c.bodies.crank.mass_kg, c.bodies.crank.inertia_kgm2) == (0.08, 2.37, 0.01201)
    assert (c.bodies.rod.length_m, c.bodies.rod.mass_kg, c.bodies.rod.inertia_kgm2) == (0.32, 0.72, 0.0006926)
    assert c.bodies.slider.mass_kg == 2.28
    assert c.joints.radial_m("C") == pytest.approx(0.5e-3) and c.joints.clearance_b_mm == 0
    assert 2 * c.joints.bushing_radius_m("C") == pytest.approx(0.015)          # bearing diameter 15 mm
    assert (c.materials.pin.youngs_modulus_pa, c.materials.bushing.youngs_modulus_pa) == (207e9, 97e9)
    con = c.contact
    assert (con.friction_law, con.mu_static, con.mu0, con.v_static_mps, con.v_kinetic_mps) == \
        ("adams", 0.08, 0.05, 1e-4, 0.01016)
    assert con.restitution == 0.55 and con.law == "lankarani-nikravesh"
    # K of S001 Eq. 4-5 = the twin's Eq. 18 with h = (1 - nu^2)/E, written out here
    h = (1 - 0.3**2) / 207e9 + (1 - 0.3**2) / 97e9
    assert ln_stiffness(c.joints, c.materials, "C") == pytest.approx(4 / (3 * h) * math.sqrt(7.5e-3 * 7e-3 / 0.5e-3))
    assert c.drive.crank_rad_s == pytest.approx(300 * 2 * math.pi / 60)
    assert (c.drive.ramp_s, c.drive.ramp_shape, c.mechanism.orientation) == (0.2, "linear", "y")
    assert c.output_rate_hz == 5000 and c.instrumentation.daq_rate_hz == 5000
    assert config_from_toml(c.to_toml()) == c


def test_s001_preset_from_cli_and_toml(tmp_path):
    p = build_parser()
    cfg = config_from_args(p.parse_args(["simulate", "--preset", "s001", "--engine", "reference"]))
    assert cfg.name == "s001" and cfg.simulation.engine == "reference" and cfg.bodies.crank.length_m == 0.08
    with pytest.raises(ConfigError, match="--preset"):
        config_from_args(p.parse_args(["simulate", "--preset", "s001", "--test", "3"]))
    with pytest.raises(ConfigError, match="s001"):
        config_from_args(p.parse_args(["simulate", "--preset", "s999"]))
    f = tmp_path / "c.toml"
    f.write_text('preset = "s001"\n[contact]\nrestitution = 0.4\n')
    c = load_config(f)
    assert c.contact.restitution == 0.4 and c.contact.friction_law == "adams" and c.bodies.rod.length_m == 0.32
    # the bench's defaults are untouched by the new fields
    b = BenchConfig()
    assert b.contact.friction_law == "regularized-coulomb" and b.drive.ramp_shape == "cosine"


def test_linear_ramp_reference():
    cfg = named_preset("s001")
    w = cfg.drive.crank_rad_s
    ref = DriveReference(cfg)
    t = np.array([0.0, 0.05, 0.1, 0.2, 0.3])
    th, om = ref(t)
    np.testing.assert_allclose(om, [0, w / 4, w / 2, w, w], rtol=1e-12)
    np.testing.assert_allclose(th - th[0], [0, w * 0.05**2 / 0.4, w * 0.1**2 / 0.4, w * 0.1, w * 0.2], rtol=1e-12)
    assert th[0] == pytest.approx(0.0, abs=1e-12)             # slider fully extended: θ = 0


# ------------------------------------------------------------------------- friction
def test_adams_friction_law_of_the_reference():
    from twin.physics.contact import adams_friction_force, adams_mu

    mus, mud, vs, vd = 0.08, 0.05, 1e-4, 0.01016
    v = np.concatenate([np.linspace(0, 2e-4, 201), np.geomspace(2e-4, 0.1, 200)])
    mu = np.array([adams_mu(x, mus, mud, vs, vd) for x in v])
    np.testing.assert_allclose(mu, _adams_mu(v, mus, mud, vs, vd), atol=1e-15)
    assert adams_mu(0.0, mus, mud, vs, vd) == 0 and adams_mu(vs, mus, mud, vs, vd) == pytest.approx(mus)
    assert adams_mu(vd, mus, mud, vs, vd) == pytest.approx(mud) and adams_mu(1.0, mus, mud, vs, vd) == mud
    assert adams_friction_force(0.01, 100.0, mus, mud, vs, vd) == pytest.approx(-100 * _adams_mu(0.01, mus, mud, vs, vd))
    assert adams_friction_force(-1.0, 100.0, mus, mud, vs, vd) == pytest.approx(5.0)


def test_adams_friction_of_the_native_module():
    """The MuJoCo twin's native friction on the S001 journal is μ(v_t) f_N of the Adams law, with v_t
    the contact points' slip measured here from MuJoCo's Jacobians."""
    from twin.mujoco_engine.engine import MujocoEngine

    cfg = named_preset("s001").replace(**{"simulation.duration_s": 0.4, "sensors.output_rate_hz": 100000.0})
    eng = MujocoEngine(cfg)
    m, d = eng.model, eng.data
    eng.reset()
    ref = DriveReference(cfg)
    con_cfg = cfg.contact
    K = ln_stiffness(cfg.joints, cfg.materials, "C")
    sens = eng._sensor_slices
    got, want = [], []
    for _ in range(40000):
        th, om = ref(np.array([d.time]))
        d.ctrl[:] = [th[0], om[0]]
        mujoco.mj_step(m, d)
        mujoco.mj_forward(m, d)  # the sensor and the contact at the same state
        for ci in range(d.ncon):
            con = d.contact[ci]
            a = con.efc_address
            if a < 0 or d.efc_force[a] < 1.0:
                continue
            g0 = m.geom(con.geom[0]).name
            pin_first = g0 == names.pin("C")
            gp, gb = (con.geom[0], con.geom[1]) if pin_first else (con.geom[1], con.geom[0])
            jp, jb = np.zeros((3, m.nv)), np.zeros((3, m.nv))
            mujoco.mj_jac(m, d, jp, None, con.pos, m.geom_bodyid[gp])
            mujoco.mj_jac(m, d, jb, None, con.pos, m.geom_bodyid[gb])
            n_bp = (1.0 if pin_first else -1.0) * con.frame[:3]  # bore centre -> pin side
            vt = ((jp - jb) @ d.qvel) @ np.cross([0, 0, 1], n_bp)
            ft = d.sensordata[sens[names.sensor_friction("C")].start]
            # the law's normal force at this state (Lankarani-Nikravesh with the stored impact
            # speed) at the step's secant rate: the rate less h b/2, b = -J'q' of the row
            delta, ddelta = -(d.efc_pos[a] - d.efc_margin[a]), -d.efc_vel[a]
            chi = 0.75 * (1 - con_cfg.restitution**2)
            ratio = max(ddelta / d.userdata[0], -1.0)
            fn = K * delta**1.5 * (1 + chi * ratio)
            if ratio > -1.0:
                h = m.opt.timestep
                fn -= chi * K * delta**1.5 / d.userdata[0] * h * bore_bias_acceleration(m, d, gp, gb, d.qvel) / 2
            if fn > 1.0:
                got.append(ft / fn)
                want.append(-np.sign(vt) * _adams_mu(vt, con_cfg.mu_static, con_cfg.mu0,
                                                     con_cfg.v_static_mps, con_cfg.v_kinetic_mps))
    got, want = np.array(got), np.array(want)
    assert got.size > 500
    np.testing.assert_allclose(got, want, atol=1e-4)
    mid = (np.abs(want) > 0.051) & (np.abs(want) < 0.079)      # on the STEP between μ_s and μ_k
    assert mid.sum() >= 5


# --------------------------------------------------------------------- closed form
@pytest.mark.parametrize("engine", ["mujoco", "reference"])
def test_ideal_slider_acceleration_peaks_equal_the_closed_form(engine):
    """Issue 18: the ideal S001 run's slider-acceleration peaks at 300 rpm are rω²(1 ± r/L)
    (98.7 and 59.2 m/s²) within 0.5 %. The accelerometer along the guide (AC6, 5 kHz) after the
    0.2 s ramp; a constant ω makes θ = 0 and π (sampled at 1000 points a turn) the extremes."""
    cfg = named_preset("s001").replace(**{"joints.clearance_c_mm": 0.0, "simulation.engine": engine})
    run = simulate_run(cfg)
    r, L = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    w = 300 * 2 * math.pi / 60
    steady = run.time >= 0.3
    a = run["AC6"][steady].astype(float)
    lo, hi = -r * w * w * (1 + r / L), r * w * w * (1 - r / L)
    assert lo == pytest.approx(-98.70, abs=0.01) and hi == pytest.approx(59.22, abs=0.01)
    assert a.min() == pytest.approx(lo, rel=5e-3)
    assert a.max() == pytest.approx(hi, rel=5e-3)


def test_adams_friction_of_the_reference_run():
    """The reference engine's journal friction on S001: |f_T| ≤ μ_s f_N, μ_k while sliding fast and
    values on the STEP between (which the regularized Coulomb law, capped at μ0 = μ_k, never gives)."""
    cfg = named_preset("s001").replace(**{"simulation.engine": "reference", "simulation.duration_s": 0.4,
                                          "sensors.output_rate_hz": 100000.0})
    run = simulate_run(cfg)
    fn, ft = run["fn_C"].astype(float), run["ft_C"].astype(float)
    on = fn > 1.0
    mu = np.abs(ft[on]) / fn[on]
    assert on.sum() > 500 and mu.max() <= 0.08 * (1 + 1e-5)
    assert np.mean(np.isclose(mu, 0.05, rtol=1e-4)) > 0.3
    assert np.sum((mu > 0.0505) & (mu < 0.0795)) >= 5


# ------------------------------------------------------------- restitution from a recording
#: coarse grid 0.17, 0.22, ..., 0.97: the known values 0.55, 0.4, 0.7 are not on it
_OFF_GRID = tuple(round(0.17 + 0.05 * k, 2) for k in range(17))


def _recover(tmp_path, e_true: float, engine: str = "mujoco") -> float:
    from twin.identification.restitution import SweepOptions, sweep_restitution, write_synthetic_recording

    cfg = named_preset("s001").replace(**{"simulation.engine": engine})
    rec = write_synthetic_recording(cfg, tmp_path / f"s001_e{e_true}.mcap", e_true, noise_mps2=5.0, seed=7)
    res = sweep_restitution(rec, SweepOptions(coarse=_OFF_GRID))
    assert res.engine == engine and res.window_s == (0.0, 0.6) and res.rate_hz == 5000
    return res.restitution


@pytest.mark.long  # a few seconds: run by CI and with -m long
def test_restitution_recovered_from_a_synthetic_noisy_recording(tmp_path):
    """Issue 18: twin identify restitution recovers a known e = 0.55 within ±0.03 from a synthetic
    recording (the twin at e = 0.55, 5 m/s² RMS white noise on the slider accelerometer, the sensor
    chain, 5 kHz) by sweeping e and comparing the calibrated slider acceleration. The reference
    engine here (a third of the MuJoCo twin's time on this short run); the twin in the slow test."""
    assert _recover(tmp_path, 0.55, "reference") == pytest.approx(0.55, abs=0.03)


def test_sweep_starts_must_be_a_whole_number_of_at_least_one():
    from twin.errors import ConfigError
    from twin.identification.restitution import SweepOptions

    for bad in (0, -1, 1.5):
        with pytest.raises(ConfigError, match="^starts: must be a whole number"):
            SweepOptions(starts=bad)


#: S001's run at e = 0.7 is chaotic in the twin since the secant-rate friction (f819579): a run at
#: e = 0.705 differs from e = 0.7's as much as one at 0.75 does (AC6 low-passed at 200 Hz 1.9 m/s²,
#: full band 19 m/s²; reference engine 1.25 / 12, the twin before 1.0 / 16), so no stage of the sweep
#: sees a basin around the answer and it returns 0.316; only a grid point exactly at 0.7 would
#: match. A known gap of trajectory matching on a chaotic recording (README, S001).
_CHAOTIC = {(0.7, "mujoco")}


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["mujoco", "reference"])
@pytest.mark.parametrize("e_true", [0.55, 0.4, 0.7, 0.437, 0.712])
def test_restitution_recovered_at_other_values(tmp_path, e_true, engine, request):
    if (e_true, engine) in _CHAOTIC:
        request.applymarker(pytest.mark.xfail(strict=True, reason="chaotic at e = 0.7 in the twin (see _CHAOTIC)"))
    assert _recover(tmp_path, e_true, engine) == pytest.approx(e_true, abs=0.03)


def test_identify_restitution_command(tmp_path, capsys):
    import json

    from twin.cli import main
    from twin.identification.restitution import write_synthetic_recording

    cfg = named_preset("s001").replace(**{"simulation.duration_s": 0.4})
    rec = write_synthetic_recording(cfg, tmp_path / "rec.mcap", 0.55, noise_mps2=5.0, seed=1)
    out = tmp_path / "e.json"
    assert main(["identify", "restitution", str(rec), "--grid", "0.45,0.55,0.65", "--fine-step", "0",
                 "--json", str(out)]) == 0
    r = json.loads(out.read_text())
    assert r["restitution"] == 0.55 and len(r["candidates"]) == 3 and r["window_s"] == [0.0, 0.4]
    assert "restitution e = 0.550" in capsys.readouterr().out
    assert main(["identify", "restitution", str(rec), "--grid", "0.5,1.5"]) == 2
    assert main(["identify", "restitution", str(tmp_path / "missing.mcap")]) == 2


def test_clearance_run_agrees_between_engines():
    """The S001 clearance run (0.5 mm radial at C, e = 0.55) in the twin against the reference engine:
    the same impact bursts (onsets after >= 20 ms of calm) within 1 ms, penetrations within 10 %,
    and contact mode (journal on the circle) most of the time after the ramp."""
    def onsets(run):
        pen = np.asarray(run["pen_C"], float)
        idx = np.flatnonzero((pen[1:] > 0) & (pen[:-1] == 0)) + 1
        return run.time[idx]

    runs = {eng: simulate_run(named_preset("s001").replace(**{"simulation.engine": eng,
                                                              "sensors.output_rate_hz": 100000.0}))
            for eng in ("mujoco", "reference")}
    t = {eng: onsets(run) for eng, run in runs.items()}
    first = {eng: x[np.r_[True, np.diff(x) > 0.02]] for eng, x in t.items()}
    assert len(first["mujoco"]) == len(first["reference"]) >= 5
    np.testing.assert_allclose(first["mujoco"], first["reference"], atol=1e-3)
    pm, pr = runs["mujoco"]["pen_C"].max(), runs["reference"]["pen_C"].max()
    assert pm == pytest.approx(pr, rel=0.1)
    for run in runs.values():
        ecc = np.hypot(run["ecc_C_x"].astype(float), run["ecc_C_y"].astype(float))
        assert np.mean(ecc[run.time > 0.2] >= 0.5e-3 - 1e-6) > 0.9


# ------------------------------------------------------------------- ADAMS IMPACT law
def _impact_force(delta, rate, K, n, c_max, d_max):
    """ADAMS' IMPACT function written from S001 Eq. 3 and 9 (independent of the engines)."""
    x = min(max(delta / d_max, 0.0), 1.0)
    return max(K * delta**n + c_max * x * x * (3 - 2 * x) * rate, 0.0) if delta > 0 else 0.0


def test_adams_impact_law_of_the_reference():
    from twin.physics.contact import LAW_CODES, adams_impact, normal_force

    K, n, cmax, dmax = 3.1e10, 1.5, 27960.0, 1e-5
    for delta in (-1e-7, 0.0, 2e-6, 5e-6, 1e-5, 2e-5):
        for rate in (-0.2, -0.01, 0.0, 0.05):
            want = _impact_force(delta, rate, K, n, cmax, dmax)
            assert adams_impact(delta, rate, K, n, cmax, dmax) == pytest.approx(want, rel=1e-12, abs=1e-12)
            assert normal_force(LAW_CODES["adams-impact"], delta, rate, 0.1, K, n, 0.5, cmax, dmax) == \
                pytest.approx(want, rel=1e-12, abs=1e-12)


def test_adams_impact_law_of_the_native_module():
    """The solver's force on the probe's bore contact is the IMPACT force plus the native module's
    θ-damping term θ c h δ̈ with c = STEP(δ; d_max) c_max (README, contact law), for penetrations
    below, at and beyond d_max."""
    from twin.studies.contact_check import probe_model
    from twin.mujoco_engine.builder import build

    cfg = named_preset("s001").replace(**{"contact.law": "adams-impact"})
    law = build(cfg)[2].contacts["C"].law
    assert law.law == "adams-impact" and law.damping == 27960.0 and law.d_max_m == 1e-5
    c = cfg.joints.radial_m("C")
    model = probe_model(cfg, "C", 1.3)
    K = ln_stiffness(cfg.joints, cfg.materials, "C")
    for delta in (2e-6, 1e-5, 1.5e-5):
        for rate in (0.05, -0.02):
            d = mujoco.MjData(model)
            d.qpos[0], d.qvel[0] = c + delta, rate
            mujoco.mj_forward(model, d)
            F = _impact_force(delta, rate, K, 1.5, 27960.0, 1e-5)
            x = min(delta / 1e-5, 1.0)
            cd = 27960.0 * x * x * (3 - 2 * x)
            h, a_diag = model.opt.timestep, d.efc_diagA[0]
            theta = 1 - 1 / (a_diag * cd * h) if cd * h * a_diag > 2 else 0.5
            gamma = theta * cd * h
            r0 = a_diag * (1 - 1e-4) / 1e-4
            r = 1 / gamma if gamma * r0 > 1 else r0
            assert d.efc_force[0] == pytest.approx(F + float(d.qacc[0]) / r, rel=1e-9)


def test_adams_impact_run_agrees_between_engines():
    """S001 with the paper's own contact (ADAMS IMPACT, c_max 27 960 N s/m, d_max 10 µm) in both
    engines: the same impact bursts within 1 ms and penetrations of about d_max."""
    def first_onsets(run):
        pen = np.asarray(run["pen_C"], float)
        t = run.time[np.flatnonzero((pen[1:] > 0) & (pen[:-1] == 0)) + 1]
        return t[np.r_[True, np.diff(t) > 0.02]]

    runs = {eng: simulate_run(named_preset("s001").replace(**{
        "simulation.engine": eng, "contact.law": "adams-impact", "sensors.output_rate_hz": 100000.0}))
        for eng in ("mujoco", "reference")}
    fm, fr = first_onsets(runs["mujoco"]), first_onsets(runs["reference"])
    assert len(fm) == len(fr) >= 5
    np.testing.assert_allclose(fm, fr, atol=1e-3)
    for run in runs.values():
        assert 0.5e-5 < run["pen_C"].max() < 2e-5


@pytest.mark.long  # a few seconds: run by CI and with -m long
def test_impact_damping_recovered_from_a_synthetic_noisy_recording(tmp_path):
    """S001's own procedure (Table IV): sweep the IMPACT law's c_max until the slider acceleration
    matches; a noisy synthetic recording at the paper's 27 960 N s/m gives it back within 5 %
    (the coarse grid 6 100, 8 600, ... N s/m does not hold it)."""
    from twin.identification.restitution import SweepOptions, sweep_restitution, write_synthetic_recording

    cfg = named_preset("s001").replace(**{"simulation.engine": "reference", "contact.law": "adams-impact"})
    rec = write_synthetic_recording(cfg, tmp_path / "impact.mcap", 27960.0, noise_mps2=5.0, seed=7, parameter="c_max")
    res = sweep_restitution(rec, SweepOptions(parameter="c_max", coarse=tuple(6100.0 + 2500 * k for k in range(18))))
    assert res.parameter == "c_max" and res.restitution is None
    assert res.value == pytest.approx(27960.0, rel=0.05)
    with pytest.raises(ConfigError, match="adams-impact"):  # a c_max sweep needs the IMPACT law
        sweep_restitution(write_synthetic_recording(named_preset("s001").replace(**{"simulation.engine": "reference",
                                                                              "simulation.duration_s": 0.1}),
                                              tmp_path / "ln.mcap", 0.55), SweepOptions(parameter="c_max"))
