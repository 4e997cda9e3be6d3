"""MuJoCo's constraint solver for the flexible structure (``mujoco.flexible_solver``, PGS by default).

The choice and its evidence: docs/structure-mujoco.md ("Cost"), ``analysis/mujoco_flexible_pgs.py`` and
``analysis/structure_solver_bands.py``."""

from __future__ import annotations

import copy
import sys
from pathlib import Path

import mujoco
import pytest

from twin.config import preset
from twin.errors import ConfigError


def test_flexible_solver_reaches_the_model_and_leaves_the_rigid_model_alone():
    from twin.mujoco_engine.builder import build

    flex = preset(12).replace(**{"structure.mode": "flexible"})
    assert flex.mujoco.flexible_solver == "PGS"
    assert build(flex)[1].opt.solver == mujoco.mjtSolver.mjSOL_PGS
    assert build(flex.replace(**{"mujoco.flexible_solver": "Newton"}))[1].opt.solver == mujoco.mjtSolver.mjSOL_NEWTON
    # the rigid model takes mujoco.solver whatever flexible_solver says
    rigid = preset(12).replace(**{"mujoco.flexible_solver": "CG"})
    assert build(rigid)[1].opt.solver == getattr(mujoco.mjtSolver, f"mjSOL_{rigid.mujoco.solver.upper()}")


def test_bad_flexible_solver_names_the_field():
    with pytest.raises(ConfigError, match=r"mujoco\.flexible_solver.*PGS, Newton, CG"):
        preset(12).replace(**{"mujoco.flexible_solver": "pgs"})


@pytest.mark.parametrize("test", [3, 12])
def test_pgs_converges_below_its_iteration_cap_and_matches_newtons_constraints(test, monkeypatch):
    """At full speed (test 3: the loop closed by the connect at C; test 12: the two bore contacts' law rows), 1000
    steps: PGS stops on its tolerance on every step, never at ``opt.iterations``, with no MuJoCo warning, and its loop
    closure residual and penetrations equal Newton's (independent basis: Newton's solve of the same rows, which
    converges in one iteration, as the rows' cost is quadratic) to 1e-3 of their size."""
    # the analysis scripts on a path restored after the test (analysis/datasets would shadow Hugging Face's)
    monkeypatch.setattr(sys, "path", [str(Path(__file__).resolve().parent.parent / "analysis"), *sys.path])
    from bench_mujoco import prepare_posthoc
    from mujoco_flexible_pgs import stats

    steps = 1000
    m0, s, c, _ = prepare_posthoc(test, steps, structure="flexible")
    r = {}
    for name, sol in (("PGS", mujoco.mjtSolver.mjSOL_PGS), ("Newton", mujoco.mjtSolver.mjSOL_NEWTON)):
        m = copy.copy(m0)
        m.opt.solver = sol
        r[name] = stats(m, s, c, steps)
    pgs, newton = r["PGS"], r["Newton"]
    assert pgs["steps_with_rows"] == steps and pgs["at_cap"] == 0 and pgs["niter_max"] < m0.opt.iterations
    assert not pgs["warnings"] and not newton["warnings"]
    key = "eq_max" if test == 3 else "pen_max"
    assert newton[key] > 0
    assert abs(pgs[key] - newton[key]) <= 1e-3 * newton[key], (pgs[key], newton[key])
