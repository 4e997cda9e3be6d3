"""The waveform stage of ``twin.calibrate`` (:mod:`twin.calibration.waveform`).

Independent basis: synthetic bench recordings with a known friction coefficient (``twin.record``, through
the sensor chain, two noise seeds = two repeats; reference engine, 0.5 mm clearance, 0.6 s). The feature
fit's precision on such recordings is of the order of 1 % (docs/calibration.md, validation sets); the
stage starts from a value 2 % off the truth (what a feature fit leaves) and must end closer to the truth
than that, within 0.2 % — a tenth of the start's error, not a bound copied from the code's output.
"""

from __future__ import annotations

import numpy as np
import pytest

from test_calibrate_fit import TRUE_MU0, _truth, record_repeats  # the same known truth as the feature fit's tests
from twin.errors import ConfigError

START_OFFSET = 0.02  # relative: what a feature fit leaves (1-4 % on the validation sets)


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    from twin.calibration.objective import get_target
    from twin.calibration.params import make_parameters

    ws = tmp_path_factory.mktemp("wave")
    recs = record_repeats(ws)
    base = _truth().replace(**{"contact.mu0": 0.05})
    tgs = [get_target(str(r), base.to_toml(), 1.0, 0.05, False, "program") for r in recs]
    P = make_parameters(["contact.mu0"], tgs[0].base, {"contact.mu0": (0.0, 0.3)})
    return ws, recs, base, tgs, P


def test_stage_recovers_known_friction_more_precisely_than_its_start(setup):
    from twin.calibration.waveform import waveform_stage

    _ws, _recs, _base, tgs, P = setup
    start = TRUE_MU0 * (1.0 + START_OFFSET)
    u0 = np.asarray([P[0].to_unit(start)])
    st = waveform_stage(tgs, P, u0, [(0.09, 0.11)], budget=16)
    assert st["ran"], st["reason"]
    assert max(st["predictability_pct"]) <= st["chaos_pct"]  # 0.5 mm, μ 0.1: not chaotic
    (after,) = st["values"]
    err0, err1 = abs(start - TRUE_MU0) / TRUE_MU0, abs(after - TRUE_MU0) / TRUE_MU0
    assert err1 < 0.1 * err0, (start, after)
    assert st["cost_after"] < st["cost_before"] and st["replays"] <= 16
    assert max(st["nonlinearity"]) <= waveform_nonlinearity_max()
    # the replay NRMSE of every accelerometer fell (what the replay criterion measures)
    for b, a in zip(st["nrmse_before"], st["nrmse_after"]):
        assert all(a[s] < b[s] for s in b)
    (c,) = st["changes"]
    assert c["inside_interval"] and c["before"] == pytest.approx(start)


def waveform_nonlinearity_max() -> float:
    from twin.calibration.waveform import NONLINEARITY_MAX

    return NONLINEARITY_MAX


def test_stage_is_skipped_where_the_residuals_are_not_smooth(setup, monkeypatch):
    """The second gate: with a nonlinearity limit below any (a negative one), the stage stops after its
    probes at ± the Jacobian's step and says why; the values stay the feature fit's."""
    from twin.calibration import waveform

    _ws, _recs, _base, tgs, P = setup
    monkeypatch.setattr(waveform, "NONLINEARITY_MAX", -1.0)
    u0 = np.asarray([P[0].to_unit(0.102)])
    st = waveform.waveform_stage(tgs, P, u0, budget=16)
    assert not st["ran"] and "not smooth" in st["reason"] and st["replays"] == 5
    assert st["values"] == [pytest.approx(0.102)] and len(st["nonlinearity"]) == 1


def test_stage_is_skipped_where_the_replay_is_not_predictable(setup, monkeypatch):
    """The gate: with a limit below what ±1e-9 changes (every replay differs by rounding at least), the
    stage does not fit and says why; the values stay the feature fit's."""
    from twin.calibration import waveform

    _ws, _recs, _base, tgs, P = setup
    monkeypatch.setattr(waveform, "CHAOS_PCT", -1.0)
    u0 = np.asarray([P[0].to_unit(0.102)])
    st = waveform.waveform_stage(tgs, P, u0, budget=12)
    assert not st["ran"] and "not predictable" in st["reason"] and st["replays"] == 3
    assert st["values"] == [pytest.approx(0.102)]


def test_calibrate_with_waveform_reports_the_stage(setup, tmp_path):
    """``twin.calibrate(..., waveform=True)``: the fitted value is the stage's, the feature fit's is kept,
    report.json and report.md carry the stage with each change against its interval."""
    import json

    import twin
    from twin.calibration import CalibrationOptions

    _ws, recs, base, _tgs, _P = setup
    opts = CalibrationOptions(n_global=2, local_short=3, local_full=3, profile_steps=(0.03,), drive="program",
                              plots=False, replicates=0, boot_replicates=50, restarts=0, waveform=True,
                              waveform_budget=10)
    res = twin.calibrate(recs, ["contact.mu0"], tmp_path / "out", config=base, bounds={"contact.mu0": (0.0, 0.3)},
                         options=opts)
    (p,) = res.parameters
    w = res.report["waveform"]
    assert w["ran"], w["reason"]
    assert p.value == pytest.approx(w["values"][0]) and p.feature_value == pytest.approx(w["changes"][0]["before"])
    # no worse against the known truth than the feature fit (the stage keeps only points that lower its misfit)
    assert abs(p.value - TRUE_MU0) <= abs(p.feature_value - TRUE_MU0) + 1e-3 * TRUE_MU0
    md = (tmp_path / "out" / "report.md").read_text()
    assert "## Waveform stage" in md and "change / interval half-width" in md
    assert json.loads((tmp_path / "out" / "report.json").read_text())["waveform"]["ran"]


@pytest.mark.parametrize("kw", [{"waveform": 1}, {"waveform_budget": 0}])
def test_bad_waveform_options_name_the_field(kw):
    from twin.calibration import CalibrationOptions

    with pytest.raises(ConfigError) as err:
        CalibrationOptions(**kw)
    assert next(iter(kw)) in str(err.value)


def test_waveform_flags_reach_the_options_and_a_bad_budget_names_it(tmp_path, capsys):
    from twin.cli import main

    out = tmp_path / "out"
    rc = main(["calibrate", str(tmp_path / "missing.mcap"), "--params", "contact.mu0", "--waveform",
               "--waveform-budget", "0", "--out", str(out), "--no-plots", "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert rc != 0 and "--waveform-budget" in err and len(err.splitlines()) == 1, err
    assert not out.exists()
