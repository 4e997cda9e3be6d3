"""Command-line use of the reference engine: ``twin simulate --engine reference`` and
``twin study formulations`` (a short version of the §4.1 study)."""

from __future__ import annotations

import json

import pytest

from twin.cli import main
from twin.errors import ConfigError
from twin.studies.penalty import PenaltyParams


def test_simulate_with_reference_engine(tmp_path, capsys):
    out, summ = tmp_path / "r.mcap", tmp_path / "s.json"
    rc = main(["simulate", "--engine", "reference", "--test", "12", "--duration", "0.1", "--out", str(out),
               "--summary-json", str(summ), "--no-progress"])
    assert rc == 0 and out.exists()
    s = json.loads(summ.read_text())
    assert s["engine"] == "reference" and s["steps"] == 10_000 and s["real_time_factor"] > 0
    for j in ("B", "C"):
        assert s[j]["max_eccentricity_m"] > 0.99 * 5e-5
    from twin.mcapfile import read_run

    run = read_run(out)
    assert run.meta["engine"] == "reference" and run.n == 10_000


def test_study_formulations_short(tmp_path, capsys):
    rc = main(["study", "formulations", "--out", str(tmp_path / "f"), "--duration", "0.5", "--no-progress"])
    assert rc == 0
    d = tmp_path / "f"
    data = json.loads((d / "formulations.json").read_text())
    assert (d / "formulations.md").read_text().count("\n| ") >= 12
    for f in data["figures"]:
        assert (d / f).stat().st_size > 10_000
    rows = {r["case"]: r for r in data["rows"]}
    rm = rows["R-matrix, h=0.0001"]
    assert rm["max_phi"] < 1e-12 and not rm["diverged"] and rm["final_energy_error_J"] < 0
    p = rows["P α=1e+09 ζ=1 ω=1000, h=0.0001"]
    assert not p["diverged"] and 1e-9 < p["max_phi"] < 1e-4   # penalty needs a violation
    assert rows["P α=1e+09 ζ=1 ω=1000, h=0.001"]["diverged"]   # S003: fails at h = 1e-3
    assert not rows["R-matrix, h=0.001"]["diverged"]
    # ω matters: the soft stabilization drifts far more
    assert abs(rows["P α=1e+09 ζ=1 ω=10, h=0.0001"]["final_energy_error_J"]) > 5 * abs(p["final_energy_error_J"])


@pytest.mark.parametrize("argv, message", [
    (["study", "formulations", "--out", "/nonexistent-dir/x"], "does not exist"),
    (["study", "formulations", "--out", "OUT", "--duration", "-1"], "--duration"),
    (["study"], "required"),
])
def test_study_bad_arguments_are_one_line_errors(argv, message, tmp_path, capsys):
    argv = [a.replace("OUT", str(tmp_path / "o")) for a in argv]
    try:
        rc = main(argv)
    except SystemExit as ex:  # argparse errors
        rc = ex.code
    assert rc == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "Traceback" not in err and len(err.splitlines()) == 1


def test_penalty_params_are_validated():
    with pytest.raises(ConfigError, match="penalty.alpha"):
        PenaltyParams(alpha=-1.0)
    with pytest.raises(ConfigError, match="penalty.omega"):
        PenaltyParams(omega=float("nan"))
    with pytest.raises(ConfigError, match="penalty.zeta"):
        PenaltyParams(zeta=-0.5)
