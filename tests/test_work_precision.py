"""The reference engine's opt-in explicit midpoint integrator and the work–precision comparison of
``twin study formulations`` (issue 16, item 5)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from twin.config import preset
from twin.natural_coordinates import P_INTEGRATOR
from twin.errors import ConfigError
from twin.studies import formulations as formulations_study
from twin.reference.engine import ReferenceEngine, ReferenceOptions



def _theta_error(h: float, integrator: str, duration: float = 0.5) -> float:
    cfg = formulations_study.study_config(None)
    th, _ = formulations_study._rmatrix_theta(cfg, h, duration, integrator)
    exact, _ = formulations_study.MinimalModel(cfg).solve(formulations_study.THETA0, np.array([0.0, duration]))
    return abs(th - exact[-1])


def test_midpoint_is_second_order_and_euler_first_order():
    mid = [_theta_error(h, "midpoint") for h in (1e-3, 5e-4, 2.5e-4)]
    eul = [_theta_error(h, "euler") for h in (1e-3, 5e-4, 2.5e-4)]
    for a, b in zip(mid, mid[1:]):
        assert 3.5 < a / b < 4.5
    for a, b in zip(eul, eul[1:]):
        assert 1.8 < a / b < 2.2
    assert mid[0] < eul[-1] / 10


def test_reference_engine_midpoint_option_on_an_ideal_scene():
    cfg = preset(3).replace(**{"simulation.engine": "reference", "simulation.duration_s": 0.1, "drive.ramp_s": 0.05})
    from twin.simulation import Collector, simulate

    def run(h, integrator):
        c = cfg.replace(**{"simulation.timestep_s": h})
        eng = ReferenceEngine(c, ReferenceOptions(integrator=integrator))
        keep = Collector()
        simulate(c, [keep], engine=eng)
        return eng, keep.run

    eng, mid = run(1e-5, "midpoint")
    assert "midpoint" in eng.meta["integrator"] and eng.P[P_INTEGRATOR] == 1.0
    _, eul = run(1e-5, "euler")
    _, fine = run(1e-6, "euler")
    assert eul.meta["options"]["integrator"] == "euler"
    # driven, guide friction on: more accurate than Euler at the same step
    for a in ("crank_angle", "AC1", "AC6"):
        e_mid, e_eul = (float(np.max(np.abs(x[a].astype(float) - fine[a].astype(float)))) for x in (mid, eul))
        assert e_mid < e_eul


def test_midpoint_is_refused_with_a_clearance_joint():
    with pytest.raises(ConfigError, match="reference.integrator"):
        ReferenceEngine(preset(12).replace(**{"simulation.engine": "reference"}), ReferenceOptions(integrator="midpoint"))


def test_unknown_integrator_is_refused():
    with pytest.raises(ConfigError, match="reference.integrator"):
        ReferenceOptions(integrator="rk4")


def test_work_precision_rows_and_front(tmp_path):
    methods = {"R-matrix, symplectic Euler": (1e-4,), "R-matrix, explicit midpoint": (1e-3, 1e-4),
               "MuJoCo twin, Euler": (1e-4,)}
    data = formulations_study.run_study(formulations_study.FormulationsOptions(
        tmp_path, duration_s=0.2, cases=(formulations_study.Case("R-matrix", 1e-4),), work_precision_methods=methods)).to_dict()
    rows = data["work_precision"]
    assert [r["method"] for r in rows] == ["R-matrix, symplectic Euler", "R-matrix, explicit midpoint",
                                           "R-matrix, explicit midpoint", "MuJoCo twin, Euler"]
    by = {(r["method"], r["timestep_s"]): r for r in rows}
    euler, mid = by[("R-matrix, symplectic Euler", 1e-4)], by[("R-matrix, explicit midpoint", 1e-4)]
    assert mid["theta_error_rad"] < euler["theta_error_rad"] / 100
    assert all(r["us_per_step"] > 0 and math.isfinite(r["s_per_sim_s"]) for r in rows)
    assert mid["front"] and not euler["front"]  # Euler at 1e-4 is dominated by midpoint at 1e-3
    assert json.loads((tmp_path / "formulations.json").read_text())["work_precision"] == rows
    assert "Work–precision" in (tmp_path / "formulations.md").read_text()
    assert (tmp_path / "work_precision.png").stat().st_size > 10_000


def test_exudyn_rows_are_skipped_cleanly_when_it_is_not_installed(monkeypatch):
    monkeypatch.setattr(formulations_study, "exudyn_available", lambda: False)
    rows = formulations_study.work_precision(None, 0.05, 0.0, {"Exudyn, generalized-α": (1e-3,), "R-matrix, explicit midpoint": (1e-3,)})
    assert [r["method"] for r in rows] == ["R-matrix, explicit midpoint"]
    assert "not installed" in formulations_study.work_precision_markdown(rows, 0.05, exudyn=False)
