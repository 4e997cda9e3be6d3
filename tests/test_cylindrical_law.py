"""Johnson's cylindrical contact law (``contact.law = "johnson-cylindrical"``).

Independent bases: the law's own closed form, δ = (F/k)[ln(4 ΔR k/F) − 1] (Johnson, Contact
Mechanics, 1985, §5.6), which the code inverts by Halley's iteration and which is checked here
by substituting the force back and against SciPy's Lambert W; k = π L E* from the materials by
hand; and the two engines against each other on S004's mechanism.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import lambertw

from twin.config import named_preset
from twin.contact_params import cylindrical_stiffness, johnson_elastic_force
from twin.simulation import simulate_run

#: S004's preset sets the ADAMS IMPACT law's own numbers; another law refuses them, so they go back to default
NOT_IMPACT = {"contact.impact_c_max_nspm": 27960.0, "contact.impact_d_max_m": 1e-5}

K_S004 = math.pi * 0.05 * 207e9 / (2 * (1 - 0.3 ** 2))   # π L E*, steel on steel, L = 50 mm [N/m]
DR = 0.5e-3                                             # radial clearance [m]


def test_stiffness_is_pi_L_Estar_and_grows_with_the_length():
    cfg = named_preset("s004").replace(**{"contact.law": "johnson-cylindrical", **NOT_IMPACT})
    assert cylindrical_stiffness(cfg, "B") == pytest.approx(K_S004, rel=1e-12)
    longer = cfg.replace(**{"joints.bushing_length_m": 0.10})
    assert cylindrical_stiffness(longer, "B") == pytest.approx(2 * K_S004, rel=1e-12)
    assert cylindrical_stiffness(cfg.replace(**{"contact.stiffness_scale": 2.0}), "B") == pytest.approx(2 * K_S004)


def test_force_penetration_curve_is_johnsons_closed_form():
    d_star = 4 * DR / math.e ** 2            # the relation's turning point
    for delta in np.r_[np.geomspace(1e-10, 0.999 * d_star, 40), 0.999999 * d_star]:
        F = johnson_elastic_force(float(delta), K_S004, DR)
        back = F / K_S004 * (math.log(4 * DR * K_S004 / F) - 1)
        assert back == pytest.approx(delta, rel=1e-11)
        w = lambertw(-math.e * delta / (4 * DR), -1).real
        assert F == pytest.approx(-K_S004 * delta / w, rel=1e-9)
    # monotonic, softer than linear k δ near 0 (the secant F/δ = k/(ln(4ΔRk/F) − 1) < k)
    d = np.geomspace(1e-9, 0.99 * d_star, 200)
    F = np.array([johnson_elastic_force(float(x), K_S004, DR) for x in d])
    assert np.all(np.diff(F) > 0) and np.all(F < K_S004 * d)
    # beyond the turning point: continued as k δ (continuous there)
    assert johnson_elastic_force(1.2 * d_star, K_S004, DR) == pytest.approx(1.2 * K_S004 * d_star)
    assert johnson_elastic_force(0.0, K_S004, DR) == 0.0 and johnson_elastic_force(-1e-6, K_S004, DR) == 0.0


def test_reference_and_native_law_apply_the_same_force():
    """The reference's compiled law and the native module's description (``NativeLaw``, what
    _bore.c computes) give F_J(δ) (1 + 3(1 − e²)/4 · max(δ̇/δ̇⁻, −1))."""
    from twin.mujoco_engine.builder import build
    from twin.physics.contact import LAW_CODES, normal_force

    e = 0.9
    cfg = named_preset("s004").replace(**{"contact.law": "johnson-cylindrical", **NOT_IMPACT, "contact.restitution": e})
    law = build(cfg)[2].contacts["B"].law
    assert law.law == "johnson-cylindrical" and law.d_max_m == pytest.approx(DR)
    assert law.stiffness == pytest.approx(K_S004, rel=1e-12)
    chi = 0.75 * (1 - e * e)
    for delta in (1e-7, 1e-5, 2e-4):
        for rate, vimp in ((0.05, 0.1), (-0.05, 0.1), (-0.3, 0.1), (0.0, 0.1)):
            want = johnson_elastic_force(delta, K_S004, DR) * (1 + chi * max(rate / vimp, -1.0))
            got = normal_force(LAW_CODES["johnson-cylindrical"], delta, rate, vimp, K_S004, 1.5, e, DR, 1e-5)
            assert got == pytest.approx(want, rel=1e-12)
            assert law.force(delta, rate, vimp) == pytest.approx(want, rel=1e-12)


def test_cylindrical_law_run_agrees_between_engines():
    """S004 (0.5 mm at B, MN loads) with the cylindrical law, 0.3 s: the largest penetration and
    contact force of the two engines within 2 % (measured: 0.4068 / 0.4069 mm and 7.42 / 7.39 MN
    over 1 s)."""
    out = {}
    for eng in ("reference", "mujoco"):
        run = simulate_run(named_preset("s004").replace(**{
            "simulation.engine": eng, "contact.law": "johnson-cylindrical", **NOT_IMPACT, "contact.restitution": 0.9,
            "simulation.duration_s": 0.3}))
        out[eng] = (float(np.nanmax(run["pen_B"])), float(np.nanmax(run["fn_B"])))
    (pr, fr), (pm, fm) = out["reference"], out["mujoco"]
    assert pm == pytest.approx(pr, rel=0.02) and fm == pytest.approx(fr, rel=0.02)
    assert pr < DR   # the length-dependent law keeps the journal inside its clearance here


def test_native_module_applies_the_cylindrical_law():
    """The solver's force on the probe's bore contact (``_bore.c``, law 4) is F_J(δ)(1 + χ δ̇/v_imp)
    plus the native module's θ-damping term (c = χ F_J / v_imp, the same rule as the hysteresis
    laws, tests/test_mujoco_physics.py), F_J from Johnson's relation, below and near the turning
    point and in the clamped branch (δ̇/v_imp < −1)."""
    import mujoco

    from twin.studies.contact_check import probe_model

    e = 0.9
    cfg = named_preset("s004").replace(**{"contact.law": "johnson-cylindrical", **NOT_IMPACT, "contact.restitution": e})
    model = probe_model(cfg, "B", 50.0)
    chi = 0.75 * (1 - e * e)
    h = model.opt.timestep
    for delta in (1e-6, 5e-5, 2.5e-4):
        for rate, v_imp in ((0.05, 0.1), (-0.05, 0.1), (-0.3, 0.1)):
            d = mujoco.MjData(model)
            d.qpos[0], d.qvel[0] = DR + delta, rate
            d.userdata[0] = v_imp
            mujoco.mj_forward(model, d)
            fe = johnson_elastic_force(delta, K_S004, DR)
            F = fe * (1 + chi * max(rate / v_imp, -1.0))
            cd = 0.0 if rate < -v_imp else chi * fe / v_imp
            a_diag = d.efc_diagA[0]
            theta = 1 - 1 / (a_diag * cd * h) if cd * h * a_diag > 2 else 0.5
            gamma = theta * cd * h
            r0 = a_diag * (1 - 1e-4) / 1e-4
            r = 1 / gamma if gamma * r0 > 1 else r0
            assert d.efc_force[0] == pytest.approx(F + float(d.qacc[0]) / r, rel=1e-9)
