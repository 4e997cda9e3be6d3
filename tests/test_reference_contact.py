"""Contact element of the reference engine: the normal-force laws, a single impact inside the
multibody model against the 1-DOF impact analysis of twin.impact, the clearance bound and the
regularized Coulomb friction of a running clearance scene."""

from __future__ import annotations

import numpy as np
import pytest

from twin.config import BenchConfig, ln_stiffness, preset
from twin.impact import hysteresis_restitution, impact_hysteresis
from twin.physics import contact as ref_contact
from twin import natural_coordinates as natural
from twin.reference import model as ref_model
from twin.simulation import simulate_run

from conftest import short


# ------------------------------------------------------------------------ laws
def test_laws_follow_their_formulas():
    K, n, e, v = 1e10, 1.5, 0.4, 0.2
    d, dd = 2e-6, 0.05
    base = K * d**1.5
    assert ref_contact.lankarani_nikravesh(d, dd, v, K, n, e, 0.0) == pytest.approx(base * (1 + 0.75 * (1 - e * e) * dd / v))
    assert ref_contact.hunt_crossley(d, dd, v, K, n, e, 0.0) == pytest.approx(base * (1 + 1.5 * (1 - e) * dd / v))
    assert ref_contact.flores(d, dd, v, K, n, e, 0.0) == pytest.approx(base * (1 + 8 * (1 - e) / (5 * e) * dd / v))
    assert ref_contact.linear(d, dd, v, 3e7, n, e, 100.0) == pytest.approx(3e7 * d + 100.0 * dd)
    assert ref_contact.lankarani_nikravesh(d, dd, v, K, 1.3, e, 0.0) == pytest.approx(K * d**1.3 * (1 + 0.63 * dd / v))
    for code in ref_contact.LAW_CODES.values():  # no force without penetration
        assert ref_contact.normal_force(code, -1e-9, -0.1, v, K, n, e, 100.0) == 0.0


def test_separation_ratio_is_kept_above_minus_one():
    K, n, e, v = 1e10, 1.5, 0.4, 0.2
    d = 1e-6
    chi = 0.75 * (1 - e * e)
    # fast separation (δ̇/δ̇⁻ = −5): the ratio is clamped at −1, the force stays positive
    f = ref_contact.lankarani_nikravesh(d, -5 * v, v, K, n, e, 0.0)
    assert f == pytest.approx(K * d**1.5 * (1 - chi)) and f > 0
    # laws whose damping factor exceeds 1 never pull
    assert ref_contact.flores(d, -5 * v, v, K, n, 0.2, 0.0) == 0.0
    assert ref_contact.linear(d, -1.0, v, 1e6, n, e, 1e5) == 0.0


def test_friction_ramp_and_direction():
    mu0, v0, v1, fn = 0.05, 5e-4, 1e-3, 100.0
    assert ref_contact.friction_force(4e-4, fn, mu0, v0, v1) == 0.0
    assert ref_contact.friction_force(7.5e-4, fn, mu0, v0, v1) == pytest.approx(-0.5 * mu0 * fn)
    assert ref_contact.friction_force(0.3, fn, mu0, v0, v1) == pytest.approx(-mu0 * fn)
    assert ref_contact.friction_force(-0.3, fn, mu0, v0, v1) == pytest.approx(mu0 * fn)
    assert ref_contact.ramp(-2e-3, v0, v1) == 1.0


# ---------------------------------------------------------------- single impact
def _impact(law: str, h: float, v: float = 0.1):
    """The slider pin hits its bushing at C along +x at speed v, no gravity, no friction, crank at
    the dead centre θ = 0 (the rod cannot move along its axis there, so the impact is 1-DOF with
    the slider's mass). Returns (restitution, peak force, contact duration)."""
    cfg = BenchConfig().replace(**{
        "joints.clearance_c_mm": 0.1, "joints.initial_eccentricity": "centred", "mechanism.gravity_mps2": 0.0,
        "mechanism.guide_friction_n": 0.0, "contact.mu0": 0.0, "contact.law": law})
    P = ref_model.build_params(cfg, drive=False)
    P[ref_model.P_H] = h
    st = natural.initial_state(cfg, 0.0)
    st[6] += 1e-9                      # contact normal along +x
    ref_model.contact_parameters(cfg, P, st)
    R, S = np.zeros((ref_model.N_Q, ref_model.N_Z)), np.zeros(ref_model.N_Q)
    nz = natural.r_matrix(P, st[:ref_model.N_Q], np.zeros(ref_model.N_Q), R, S)
    st[ref_model.S_QD:ref_model.S_QD + ref_model.N_Q] = R[:, :nz] @ np.array([0.0, v, 0.0])   # ż = (θ̇, ė_Cx, ė_Cy)
    c = cfg.joints.radial_m("C")
    n = int(round(2.5 * c / v / h))
    out = np.zeros((n, ref_model.N_OUT))
    z = np.zeros(n)
    assert ref_model.run_steps(P, st, z, z, 1, out, True)[0] == ref_model.OK
    e = np.hypot(out[:, ref_model.O_JOINT_C], out[:, ref_model.O_JOINT_C + 1])
    pen = out[:, ref_model.O_JOINT_C + 2]
    inside = np.flatnonzero(pen > 0)
    first, last = inside[0], inside[-1]
    assert np.all(pen[first:last + 1] > 0)   # one contact event, no chatter
    m = 5
    v_in = (e[first - 1] - e[first - 1 - m]) / (m * h)
    v_out = (e[last + 1 + m] - e[last + 1]) / (m * h)
    assert v_in == pytest.approx(v, rel=1e-6)
    return -v_out / v_in, out[:, ref_model.O_JOINT_C + 3].max(), (last + 1 - first) * h, cfg


@pytest.mark.parametrize("law", ["lankarani-nikravesh", "hunt-crossley", "flores"])
def test_single_impact_reproduces_the_law(law):
    e_eff, peak, dur, cfg = _impact(law, 1e-6)
    assert e_eff == pytest.approx(hysteresis_restitution(law, 0.4), abs=2e-4)
    if law == "lankarani-nikravesh":
        assert e_eff == pytest.approx(0.70, abs=0.005)
        K = ln_stiffness(cfg.joints, cfg.materials, "C")
        one_dof = impact_hysteresis(law, K, 1.5, 0.4, cfg.bodies.slider.mass_kg, 0.1)
        assert peak == pytest.approx(one_dof.peak_force_n, rel=5e-3)
        assert dur == pytest.approx(one_dof.duration_s, rel=1e-2)


def test_single_impact_linear_law_has_the_configured_restitution():
    e_eff, *_ = _impact("linear", 2.5e-7)
    assert e_eff == pytest.approx(0.40, abs=0.003)


# -------------------------------------------------------- running clearance scene
@pytest.fixture(scope="module")
def run12():
    cfg = short(preset(12), 0.3, **{"drive.ramp_s": 0.1, "simulation.engine": "reference"})
    return cfg, simulate_run(cfg)


def test_clearance_never_exceeded_by_more_than_a_small_penetration(run12):
    cfg, run = run12
    for j in ("B", "C"):
        c = cfg.joints.radial_m(j)
        ecc = np.hypot(run[f"ecc_{j}_x"], run[f"ecc_{j}_y"])
        pen = run[f"pen_{j}"]
        fn = run[f"fn_{j}"].astype(float)
        assert ecc.max() > 0.999 * c and fn.max() > 100      # contact happens, with real forces
        assert pen.max() < 0.1 * c                            # < 5 µm of a 50 µm radial clearance
        np.testing.assert_allclose(pen, np.maximum(ecc - c, 0), atol=1e-12)
        # Hertzian bound: at the deepest point δ̇ = 0 and f = K δ^1.5
        K = ln_stiffness(cfg.joints, cfg.materials, j)
        assert pen.max() <= 1.01 * (fn.max() / K) ** (1 / 1.5)
        assert np.all(fn[pen == 0] == 0)                      # no force without penetration


def test_joint_friction_is_regularized_coulomb(run12):
    cfg, run = run12
    mu0 = cfg.contact.mu0
    for j in ("B", "C"):
        fn, ft = run[f"fn_{j}"].astype(float), run[f"ft_{j}"].astype(float)
        assert np.all(np.abs(ft) <= mu0 * fn * (1 + 1e-6) + 1e-9)
        sliding = np.isclose(np.abs(ft), mu0 * fn, rtol=1e-5) & (fn > 1)
        assert sliding.mean() > 0.3                           # the journals mostly slide at μ0


def test_stiffness_scale_multiplies_the_law_stiffness_in_both_engines():
    """contact.stiffness_scale is a factor on Eq. 18's K (reference) and on the twin's calibrated
    pair stiffness and impact-speed damping chi K (MuJoCo), so datasets can perturb K in either."""
    from twin.config import ln_stiffness, preset
    from twin.mujoco_engine.builder import build
    from twin.physics.mujoco_params import impact_speed_coefficient
    from twin.reference.engine import ReferenceEngine

    cfg = preset(12)
    s = cfg.replace(**{"contact.stiffness_scale": 1.2})
    ref, ref_s = ReferenceEngine(cfg), ReferenceEngine(s)
    ref.reset(), ref_s.reset()
    for j in "BC":
        K = ln_stiffness(cfg.joints, cfg.materials, j)
        assert ref.contacts[j].stiffness == pytest.approx(K) and ref_s.contacts[j].stiffness == pytest.approx(1.2 * K)
        assert impact_speed_coefficient(s, j) == pytest.approx(1.2 * impact_speed_coefficient(cfg, j))
    _, _, info = build(cfg)
    _, _, info_s = build(s)
    for j in "BC":
        for t, ts in zip(info.contacts[j].terms, info_s.contacts[j].terms):
            assert ts.stiffness_n_per_m == pytest.approx(1.2 * t.stiffness_n_per_m)
            assert ts.solref[0] == pytest.approx(1.2 * t.solref[0])
