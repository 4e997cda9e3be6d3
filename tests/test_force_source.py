"""``mujoco.contact_source = "force"``: the bore contact's law and friction as a native passive force.

Independent bases: the law's closed-form static penetration δ = (F/K)^(1/n); energy conservation
of an elastic (e = 1), frictionless single impact; the single-impact solution of the reference's
law integrated by an ODE solver at tight tolerance (:mod:`twin.impact`, through
``twin.studies.contact_check``); the reference engine on the same scene (the accuracy study's
targets: peak contact force 10 %, RMS 3 %). Structure: no pair, no contact row, and the default
``"law"`` models untouched.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from conftest import short
from twin.config import BenchConfig, preset
from twin.errors import ConfigError
from twin.mujoco_engine.builder import build
from twin.mujoco_engine.engine import MujocoEngine
from twin.names import read_bore_userdata
from twin import names
from twin.simulation import Collector, run_chunks, simulate_many, simulate_run
from twin.studies import contact_check as cc

FORCE = {"mujoco.contact_source": "force"}


def _bits_equal(a, b) -> None:
    assert list(a.channels) == list(b.channels)
    for name in a.channels:
        assert a[name].tobytes() == b[name].tobytes(), name


def test_rk4_is_refused_with_one_line_naming_the_field():
    with pytest.raises(ConfigError) as err:
        BenchConfig().replace(**FORCE, **{"mujoco.integrator": "RK4"})
    assert "integrator" in str(err.value) and "\n" not in str(err.value)


def test_force_model_has_no_pair_no_contact_and_no_constraint_row():
    _spec, model, info = build(preset(12).replace(**FORCE))
    assert model.npair == 0
    assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
    for jt in ("B", "C"):
        user = read_bore_userdata(model.geom_user[model.geom(names.bushing(jt)).id])
        assert user["force_pin"] == model.geom(names.pin(jt)).id
        assert info.contacts[jt].source == "force"
    eng = MujocoEngine(short(preset(12), 0.05, **FORCE))
    fn = []
    for chunk in run_chunks(eng.cfg, engine=eng):
        fn.append(chunk["fn_C"])
    assert eng.data.nefc == 0 and eng.data.ncon == 0
    assert np.concatenate(fn).max() > 0  # the pins touch: the force acted without a row


def test_law_models_keep_their_pair_and_row_path():
    # regression guard of the default: the pair, the contact sensor and force_pin = -1
    _spec, model, info = build(preset(12))
    assert model.npair == 2 and not model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
    for jt in ("B", "C"):
        assert read_bore_userdata(model.geom_user[model.geom(names.bushing(jt)).id])["force_pin"] == -1
        assert model.sensor(names.sensor_contact(jt)).type == mujoco.mjtSensor.mjSENS_CONTACT
        assert info.contacts[jt].source == "law"


@pytest.mark.parametrize("joint", ["B", "C"])
def test_static_penetration_is_the_closed_form(joint):
    cfg = cc.joint_case(BenchConfig().replace(**FORCE), joint, 0.1)
    for m in (0.82, 3.55):
        for load in cc.STATIC_LOADS_N:
            twin, closed = cc.static_penetration(cfg, joint, m, load)
            assert abs(twin / closed - 1) < cc.TOL_STATIC, (m, load, twin, closed)


def test_elastic_frictionless_impact_returns_its_energy():
    # e = 1: no damping; energy conservation gives the exit speed = the approach speed
    cfg = cc.joint_case(BenchConfig().replace(**FORCE, **{"contact.restitution": 1.0, "contact.mu0": 0.0}), "B", 0.1)
    for r in cc.twin_impacts(cfg, "B", 1.3, speeds=(0.003, 0.03, 0.3)):
        assert abs(r.restitution - 1) < cc.TOL_E, r


@pytest.mark.parametrize("joint, clearance", [("B", 0.02), ("C", 0.1)])
def test_single_impacts_match_the_laws_ode_solution(joint, clearance):
    cfg = cc.joint_case(BenchConfig().replace(**FORCE), joint, clearance)
    for m in (0.82, 3.55):
        err = cc.impact_errors(cc.twin_impacts(cfg, joint, m), cc.reference_impacts(cfg, joint, m))
        assert np.abs(err).max() <= 1, (m, np.abs(err).max(axis=0))


def test_scene_agrees_with_the_reference_engine():
    cfg = short(preset(12), 1.0, **FORCE)
    twin, ref = simulate_run(cfg), simulate_run(cfg.replace(**{"simulation.engine": "reference"}))
    k0 = int(0.4 * twin.rate_hz)  # after the 0.25 s ramp: three crank turns at 750 motor rpm
    for jt in ("B", "C"):
        a, b = twin[f"fn_{jt}"][k0:].max(), ref[f"fn_{jt}"][k0:].max()
        assert abs(a / b - 1) < 0.10, (jt, a, b)  # the accuracy study's peak-force target
    for ac in ("AC1", "AC6"):
        a, b = np.sqrt(np.mean(twin[ac][k0:] ** 2)), np.sqrt(np.mean(ref[ac][k0:] ** 2))
        assert abs(a / b - 1) < 0.03, (ac, a, b)  # its RMS target


def test_chunking_and_threads_do_not_change_a_bit():
    # the force path keeps v_imp and the previous step's normal velocity in mjData.userdata
    cfg = short(preset(12), 0.1, **FORCE)
    a = simulate_run(cfg)
    _bits_equal(a, simulate_run(cfg.replace(**{"simulation.chunk_s": 0.013})))
    # a "law" model and two "force" models stepping at once on threads (process-wide callbacks,
    # per-model parameters in the model, per-scene state in each data object)
    law = short(preset(12), 0.1)
    keeps = [Collector() for _ in range(3)]
    simulate_many([cfg, law, cfg], [[k] for k in keeps], threads=3)
    _bits_equal(a, keeps[0].run)
    _bits_equal(simulate_run(law), keeps[1].run)
    _bits_equal(a, keeps[2].run)
