"""``twin study doe`` (S000's method) and the S000 preset.

Independent bases: the Latin hypercube property is counted from the factor values and ranges (not
through the module's unit-cube map); the Kriging leave-one-out predictions are recomputed with
numpy's linear algebra from the fitted kernel (the Gaussian-process posterior mean of the other
n − 1 points, with the same normalisation) and against the closed form of Dubrule (1983); the
optimizer is judged on functions whose optimum is known analytically; the ideal S000 run against
the slider–crank's closed form r ω² (1 + r/L).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.cli import main
from twin.config import named_preset
from twin.dataset.design import design_points
from twin.studies import doe as doe_study

SPEC = """
[dataset]
name = "t"
seed = 3
[base]
preset = "s000"
engine = "reference"
duration_s = 0.03
[design]
kind = "lhs"
runs = 12
[factors]
radial_clearance_c_mm = { range = [0.05, 0.5] }
"contact.stiffness" = { range = [3.3e8, 3.3e11], scale = "log" }
crank_rpm = { range = [50.0, 5000.0] }
[doe]
settle_s = 0.01
"""


def _doe(text: str = SPEC) -> doe_study.DoeSpec:
    import tomllib

    return doe_study.parse_doe(tomllib.loads(text))


# ------------------------------------------------------------------------- design
def test_doe_design_is_a_latin_hypercube():
    """One point in each of the n equal strata of every factor (log strata for a log factor),
    counted from the factor values themselves."""
    doe = _doe()
    pts = design_points(doe.dataset)
    n = len(pts)
    assert n == 12
    for f in doe.factors:
        lo, hi = f.range
        x = np.array([p[f.name] for p in pts])
        assert np.all((x >= lo) & (x <= hi))
        frac = (np.log(x / lo) / math.log(hi / lo)) if f.scale == "log" else (x - lo) / (hi - lo)
        strata = np.minimum((frac * n).astype(int), n - 1)
        assert sorted(strata) == list(range(n)), f.name
    assert doe_study.is_latin_hypercube(doe_study.to_unit(doe.factors, np.array([[p[f.name] for f in doe.factors] for p in pts])))
    bad = np.random.default_rng(0).random((12, 3))
    bad[:, 0] = np.linspace(0.01, 0.49, 12)  # every point in the lower half of factor 0: not one per stratum
    assert not doe_study.is_latin_hypercube(bad)


def test_unit_map_round_trip():
    doe = _doe()
    u = np.random.default_rng(1).random((20, 3))
    assert np.allclose(doe_study.to_unit(doe.factors, doe_study.from_unit(doe.factors, u)), u, atol=1e-12)
    x = doe_study.from_unit(doe.factors, np.array([[0.5, 0.5, 0.5]]))[0]
    assert x[1] == pytest.approx(math.sqrt(3.3e8 * 3.3e11))  # log factor: the geometric mean at the centre


# ------------------------------------------------------------------------ Kriging
def _f(u):  # a smooth analytic function of two variables
    u = np.atleast_2d(u)
    return np.sin(3.0 * u[:, 0]) + 0.5 * (u[:, 1] - 0.3) ** 2 + 2.0


def _lhs(n, d, seed):
    from scipy.stats import qmc

    return qmc.LatinHypercube(d=d, seed=np.random.default_rng(seed)).random(n)


def test_kriging_interpolates_its_training_points():
    u = _lhs(15, 2, 4)
    y = _f(u)
    k = doe_study.Kriging(seed=0).fit(u, y)
    assert np.max(np.abs(k.predict(u) - y)) < 1e-6 * np.ptp(y)
    _, s = k.predict(u, return_std=True)
    assert np.max(s) < 1e-3 * np.std(y)
    # and predicts the smooth function between them
    t = np.random.default_rng(5).random((200, 2))
    assert np.sqrt(np.mean((k.predict(t) - _f(t)) ** 2)) < 0.02 * np.std(_f(t))
    assert len(k.length_scales) == 2  # anisotropic: one length scale per factor
    # the log transform (responses spanning decades) interpolates too and stays positive
    y3 = np.exp(4.0 * _f(u))
    kl = doe_study.Kriging(seed=0, log=True).fit(u, y3)
    assert np.max(np.abs(kl.predict(u) / y3 - 1)) < 1e-6
    assert np.all(kl.predict(t) > 0)


def test_leave_one_out_is_computed_correctly():
    """Kriging.loo() equals the posterior mean of the other n − 1 points computed here with numpy
    (same kernel, y normalised by the n − 1 points' mean and standard deviation, the same jitter),
    and, without normalisation, Dubrule's closed form y_i − [K⁻¹y]_i/[K⁻¹]_ii equals the refits."""
    u = _lhs(14, 2, 6)
    y = _f(u)
    k = doe_study.Kriging(seed=0).fit(u, y)
    loo = k.loo()
    ker = k.kernel
    n = len(y)
    ref = np.empty(n)
    for i in range(n):
        m = np.arange(n) != i
        mu, sd = y[m].mean(), y[m].std()
        K = ker(u[m]) + k.jitter * np.eye(n - 1)
        ref[i] = mu + sd * ker(u[i:i + 1], u[m])[0] @ np.linalg.solve(K, (y[m] - mu) / sd)
    assert np.allclose(loo, ref, rtol=1e-8, atol=1e-8 * np.ptp(y))
    # a smooth function: small LOO errors, larger than the (zero) training error
    st = doe_study.loo_stats(y, loo)
    assert 0 < st["rmse_over_std"] < 0.1
    # closed form (zero-mean GP, fixed kernel) against explicit refits
    Kf = ker(u) + 1e-10 * np.eye(n)
    z = y - y.mean()
    brute = np.array([ker(u[i:i + 1], u[np.arange(n) != i])[0]
                      @ np.linalg.solve(Kf[np.ix_(np.arange(n) != i, np.arange(n) != i)], z[np.arange(n) != i])
                      for i in range(n)])
    assert np.allclose(doe_study.loo_closed_form(Kf, z), brute, atol=1e-6 * np.ptp(z))


# ---------------------------------------------------------------------- optimizer
def test_optimizer_finds_the_known_optimum_of_a_function():
    res = doe_study.optimize(lambda u: (u[0] - 0.3) ** 2 + 2.0 * (u[1] - 0.7) ** 2 + 1.0, 2, "min", seed=0)
    assert res["u"] == pytest.approx([0.3, 0.7], abs=1e-5)
    assert res["value"] == pytest.approx(1.0, abs=1e-9)
    res = doe_study.optimize(lambda u: -((u[0] - 0.2) ** 2) + 5.0, 1, "max", seed=0)
    assert res["u"][0] == pytest.approx(0.2, abs=1e-5) and res["value"] == pytest.approx(5.0, abs=1e-9)
    # a multimodal function: the global minimum of Rastrigin on [-5.12, 5.12]² (the origin), not a local one
    ras = lambda u: float(np.sum((10.24 * u - 5.12) ** 2 - 10 * np.cos(2 * np.pi * (10.24 * u - 5.12))) + 20)  # noqa: E731
    res = doe_study.optimize(ras, 2, "min", seed=1)
    assert res["u"] == pytest.approx([0.5, 0.5], abs=1e-4) and res["value"] == pytest.approx(0.0, abs=1e-6)


def test_optimizer_finds_the_known_optimum_of_a_known_surrogate():
    """A surrogate of a quadratic bowl with its minimum at (0.3, 0.7), built on a 6 × 6 grid: the
    optimum of the surrogate is the bowl's."""
    g = np.linspace(0, 1, 6)
    u = np.array([[a, b] for a in g for b in g])
    y = (u[:, 0] - 0.3) ** 2 + 2.0 * (u[:, 1] - 0.7) ** 2 + 1.0
    k = doe_study.Kriging(seed=0).fit(u, y)
    res = doe_study.optimize(lambda v: k.predict(v)[0], 2, "min", seed=0)
    assert res["u"] == pytest.approx([0.3, 0.7], abs=0.01)
    assert res["value"] == pytest.approx(1.0, abs=1e-3)


def test_sobol_indices_of_a_known_function():
    """f = u0 + 0.1 u1: first-order indices 1/1.01 and 0.01/1.01 (variances 1/12 and 0.01/12)."""
    s = doe_study.sobol(lambda x: x[:, 0] + 0.1 * x[:, 1], 2, seed=0)
    assert s["first_order"][0] == pytest.approx(1 / 1.01, abs=0.01)
    assert s["first_order"][1] == pytest.approx(0.01 / 1.01, abs=0.01)


# -------------------------------------------------------------------------- preset
@pytest.mark.parametrize("engine", ["reference", "mujoco"])
def test_s000_ideal_slider_acceleration_equals_the_closed_form(engine):
    """The ideal S000 mechanism at 5000 rpm, crank speed prescribed: the slider's peak acceleration
    is r ω² (1 + r/L) = 1.94e4 m/s² (S000 Table 4's 0.05 mm point: 2.0e4) within 0.5 % (as S001's
    test), and the crank speed is the program's."""
    from twin.simulation import simulate_run

    cfg = named_preset("s000").replace(**{"joints.clearance_c_mm": 0.0, "simulation.engine": engine})
    run = simulate_run(cfg)
    r, L = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    w = 5000 * 2 * math.pi / 60
    steady = run.time >= 0.024
    a = run["AC6"][steady].astype(float)
    peak = r * w * w * (1 + r / L)
    assert peak == pytest.approx(1.942e4, rel=1e-3)
    assert np.abs(a).max() == pytest.approx(peak, rel=5e-3)
    speed = run["crank_speed"][steady]
    assert np.max(np.abs(speed / w - 1)) < 1e-9


# ----------------------------------------------------------------------- bad specs
BAD = [
    ("nodoe", SPEC.replace("[doe]\nsettle_s = 0.01\n", ""), "doe:"),
    ("grid", SPEC.replace('kind = "lhs"\nruns = 12', 'kind = "grid"'), "factors."),
    ("values", SPEC.replace('crank_rpm = { range = [50.0, 5000.0] }', "crank_rpm = [50.0, 5000.0]"), "factors.crank_rpm"),
    ("sobol", SPEC.replace('kind = "lhs"', 'kind = "sobol"'), "design.kind"),
    ("response", SPEC + 'responses = ["max_speed"]\n', "doe.responses"),
    ("settle", SPEC.replace("settle_s = 0.01", "settle_s = 0.5"), "doe.settle_s"),
    ("key", SPEC + "goals = \"min\"\n", "doe.goals"),
    ("goal", SPEC + "goal = \"best\"\n", "doe.goal"),
    ("holdout", SPEC + '[[doe.holdout]]\nradial_clearance_c_mm = 0.9\n"contact.stiffness" = 1e10\ncrank_rpm = 100.0\n',
     "doe.holdout[0].radial_clearance_c_mm"),
    ("holdout_missing", SPEC + "[[doe.holdout]]\nradial_clearance_c_mm = 0.1\n", "doe.holdout[0]"),
    ("few", SPEC.replace("runs = 12", "runs = 3"), "design:"),
    ("outputs", SPEC + '[outputs]\ntruth = ["accel"]\ninstrumented = false\n', "outputs.truth"),
    ("plot", SPEC + '[doe.plot]\nx = "speed"\n', "doe.plot.x"),
    ("preset", SPEC.replace('preset = "s000"', 'preset = "s999"'), "base.preset"),
    ("rpm", SPEC.replace("[50.0, 5000.0]", "[50.0, 9000.0]"), "crank_rpm"),
]


@pytest.mark.parametrize("name,text,fragment", BAD, ids=[b[0] for b in BAD])
def test_cli_refuses_bad_specs_in_one_line(tmp_path, capsys, name, text, fragment):
    spec = tmp_path / f"{name}.toml"
    spec.write_text(text)
    out = tmp_path / "out"
    assert main(["study", "doe", str(spec), "--out", str(out)]) == 2
    cap = capsys.readouterr()
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("twin: error:") and fragment in lines[0], cap.err
    assert "Traceback" not in cap.err and cap.out == ""
    assert not out.exists()


def test_cli_refuses_a_missing_spec_file(tmp_path, capsys):
    assert main(["study", "doe", str(tmp_path / "none.toml"), "--out", str(tmp_path / "o")]) == 2
    assert "none.toml" in capsys.readouterr().err


# --------------------------------------------------------------------- a whole run
def test_doe_study_end_to_end(tmp_path, capsys):
    """A small DOE through the CLI: 6 LHS points of 0.03 s (reference engine), responses, surrogate,
    a hold-out point, the optimum simulated; the contact force bounds m_slider × the slider's peak
    acceleration from above (the joint's force is the only horizontal force on the slider)."""
    spec = tmp_path / "s.toml"
    spec.write_text(SPEC.replace("runs = 12", "runs = 6").replace('crank_rpm = { range = [50.0, 5000.0] }\n', "")
                    .replace(', scale = "log"', "")
                    + 'responses = ["max_slider_accel", "max_contact_force"]\n'
                    + '[[doe.holdout]]\nradial_clearance_c_mm = 0.18\n"contact.stiffness" = 1e10\n')
    out = tmp_path / "out"
    assert main(["study", "doe", str(spec), "--out", str(out), "--workers", "1", "--no-progress"]) == 0
    import json

    res = json.loads((out / "doe.json").read_text())
    assert res.pop("provenance")["git_commit"]  # stamped (twin.provenance)
    assert (out / "doe.md").read_text().splitlines()[-1].startswith("_Written ")
    assert res["lhs_strata_ok"] is True
    assert (out / "max_slider_accel.png").stat().st_size > 10_000
    m = named_preset("s000").bodies.slider.mass_kg
    for p in res["points"] + res["checks"]:
        assert p["responses"]["max_contact_force"] >= 0.999 * m * p["responses"]["max_slider_accel"]
    kinds = [c["kind"] for c in res["checks"]]
    assert kinds[0] == "holdout" and "optimum" in kinds
    for r in ("max_slider_accel", "max_contact_force"):
        s = res["responses"][r]
        assert s["train_fit_max_rel"] < 1e-6
        assert len(s["loo"]) == 6
    assert "wrote" in capsys.readouterr().out


def test_s000_preset_from_cli_and_toml(tmp_path, capsys):
    """--preset s000 on the command line (both engines, a run file written) and preset = "s000" in TOML; the
    values S000 itself fixes: slider 0.14 kg, clearance at C only, 5000 rpm prescribed."""
    from twin.cli import build_parser, config_from_args
    from twin.config import load_config

    cfg = config_from_args(build_parser().parse_args(["simulate", "--preset", "s000", "--engine", "mujoco"]))
    assert cfg.name == "s000" and cfg.bodies.slider.mass_kg == 0.14
    assert cfg.joints.clearance_b_mm == 0 and cfg.joints.radial_m("C") == pytest.approx(0.5e-3)
    assert cfg.drive.mode == "prescribed" and cfg.drive.crank_rad_s == pytest.approx(5000 * 2 * math.pi / 60)
    f = tmp_path / "c.toml"
    f.write_text('preset = "s000"\n[contact]\nstiffness = 1e10\n')
    assert load_config(f).contact.stiffness == 1e10 and load_config(f).bodies.rod.length_m == 0.12
    for engine in ("reference", "mujoco"):
        out = tmp_path / f"{engine}.mcap"
        assert main(["simulate", "--preset", "s000", "--engine", engine, "--duration", "0.004", "--out", str(out)]) == 0
        assert out.stat().st_size > 0
    capsys.readouterr()
