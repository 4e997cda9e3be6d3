"""``twin study accuracy``: metrics, Pareto front, the quick study end to end, argument errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from twin.cli import main
from twin.studies import accuracy as accuracy_study


def test_pareto_front_by_hand():
    # (cost, error): (1, 5) and (2, 2) and (4, 1) trade; (3, 3) is dominated by (2, 2);
    # (2, 2.5) is dominated by (2, 2) (same cost, worse)
    pts = [(1, 5), (2, 2), (3, 3), (4, 1), (2, 2.5)]
    assert accuracy_study.pareto_front(pts) == [True, True, False, True, False]
    # more than one error: a point better in one error survives
    assert accuracy_study.pareto_front([(1, 1, 5), (1, 2, 1), (2, 2, 5)]) == [True, True, False]


def test_score_is_the_worst_ratio_to_target():
    m = {k: 0.0 for k in accuracy_study.METRICS}
    assert accuracy_study.score(m) == 0.0
    m["band_db"] = 3.0  # twice the 1.5 dB target
    m["rms_rod"] = 0.015  # half the 3 % target
    assert accuracy_study.score(m) == pytest.approx(2.0)


def test_settings_reject_tests_without_clearance():
    with pytest.raises(Exception, match="^tests: "):
        accuracy_study.StudySettings(tests=(1,))
    with pytest.raises(Exception, match="window_s"):
        accuracy_study.StudySettings(window_s=0.01)


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("acc")
    assert main(["study", "accuracy", "--quick", "--out", str(out), "--no-progress"]) == 0
    return out, json.loads((out / "accuracy.json").read_text())


def test_quick_study_writes_table_json_and_plots(quick):
    out, data = quick
    md = (out / "accuracy.md").read_text()
    assert "**mujoco default**" in md
    for name in data["figures"]:
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert {f"work_precision_{k}.png" for k in [*accuracy_study.METRICS, "score"]} == set(data["figures"])
    assert data["settings"]["tests"] == [6, 12]


def test_the_reference_at_ten_times_the_truths_step_meets_every_target(quick):
    """First-order symplectic Euler at h = 1e-5 against the truth at 1e-6: every metric of every
    window within its stated target (``TARGETS``: impacts and peak force 10 %, RMS 3 %, band 1.5 dB)."""
    _, data = quick
    ref = next(r for r in data["summary"] if r["key"] == "reference h=1e-5")
    for k, target in accuracy_study.TARGETS.items():
        assert ref["worst"][k] <= target, k


def test_twin_default_meets_every_target_against_the_converged_reference(quick):
    """The twin's default against the converged reference (h = 1e-6), worst window of tests 6 and
    12: impact count and peak contact force within 10 %, accelerometer RMS within 3 %, band energy
    0.5-5 kHz within 1.5 dB (the study's stated targets, ``accuracy_study.TARGETS``), so its score is <= 1."""
    _, data = quick
    d = next(r for r in data["summary"] if r["key"] == data["default"])
    for k, target in accuracy_study.TARGETS.items():
        assert d["worst"][k] <= target, k
    assert accuracy_study.score(d["worst"]) <= 1.0
    # timing is measured: per simulated second, positive and finite
    assert 0 < d["wall_per_sim_s"] < 60


def test_pareto_flags_are_consistent(quick):
    _, data = quick
    tw = [r for r in data["summary"] if r["engine"] == "mujoco"]
    pts = np.array([(r["wall_per_sim_s"], *(r["mean"][k] for k in accuracy_study.FRONT_METRICS)) for r in tw])
    for i, r in enumerate(tw):
        others = np.delete(pts, i, axis=0)
        dominated = np.any(np.all(others <= pts[i], axis=1) & np.any(others < pts[i], axis=1))
        assert r["pareto"] == (not dominated)
    assert data["default_on_pareto_front"] == next(r for r in tw if r["key"] == data["default"])["pareto"]


@pytest.mark.parametrize("argv, field", [
    (["--tests", "1"], "--tests"),
    (["--tests", "six"], "--tests"),
    (["--window", "0.01"], "--window"),
])
def test_bad_arguments_give_one_line_errors(tmp_path, capsys, argv, field):
    assert main(["study", "accuracy", "--out", str(tmp_path / "o"), *argv]) != 0
    err = capsys.readouterr().err.strip()
    assert field in err and "Traceback" not in err and len(err.splitlines()) == 1
    assert not (tmp_path / "o").exists()
