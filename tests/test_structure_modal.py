"""The reference engine's modal rod (``reference.rod_model = "modal"``, :mod:`twin.reference.flexible_modal`): its
modes against the closed forms, Table 1 kept, its forces as the gradient of its energy, its sparse acceleration
solve against a dense Lagrange solve, its scope and its options' errors. Its tap, damping and energy-balance checks
run with the chain's in ``tests/test_structure_reference.py``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.config import BenchConfig, preset
from twin.errors import ConfigError
from twin.natural_coordinates import N_Q, initial_state
from twin.reference import model as RM
from twin.reference.flexible_modal import modal_energy, modal_forces, modal_frequencies, modal_matrices
from twin.reference.flexible_modal_run import ModalRun
from twin.structure import axial_fixed_mass_hz, axial_free_masses_hz, bending_pinned_hz, rod_split

BASE = BenchConfig()
ROD = BASE.bodies.rod
SLIDER_KG = BASE.bodies.slider.mass_kg


def _run(cfg, theta0=0.7):
    prm = lambda c: RM.build_params(c, drive=True, guide_friction=False)  # noqa: E731
    run = ModalRun(cfg, prm(cfg), prm)
    st = initial_state(cfg, theta0, 0.0, run.P)
    run.reset(st)
    return run, st


@pytest.mark.parametrize("height, modulus", [(0.030, 210e9), (0.015, 210e9), (0.045, 70e9), (0.020, 400e9)])
def test_modal_rod_modes_meet_the_closed_forms(height, modulus):
    """Bending 1–3 against Euler–Bernoulli pinned–pinned, the first three axial modes with B fixed and the end mass and
    the slider at C, and the free rod's first axial mode with its end masses (twin.structure.closed_forms): within
    1 % over the section's and the modulus' explore range (the sines are the pinned–pinned shapes: bending exact)."""
    cfg = BASE.replace(**{"structure.mode": "flexible", "structure.rod_section_height_m": height,
                          "structure.rod_youngs_modulus_pa": modulus})
    st = cfg.structure
    sp = rod_split(ROD.mass_kg, ROD.length_m, ROD.x_g_m, ROD.inertia_kgm2, 0.0)
    mu, L = sp.bar_mass_kg / sp.length_m, sp.length_m
    bend, ax, free = modal_frequencies(sp, st.rod_ea_n, st.rod_ei_nm2, SLIDER_KG)
    assert bend == pytest.approx([bending_pinned_hz(st.rod_ei_nm2, mu, L, k) for k in (1, 2, 3)], rel=0.01)
    assert ax[:3] == pytest.approx(axial_fixed_mass_hz(st.rod_ea_n, mu, L, sp.end_c_kg + SLIDER_KG, 3), rel=0.01)
    assert free[0] == pytest.approx(axial_free_masses_hz(st.rod_ea_n, mu, L, sp.end_b_kg, sp.end_c_kg, 1)[0],
                                    rel=0.01)


def test_modal_rod_keeps_table1_mass_centre_and_inertia():
    """The modal rod's mass matrix restricted to rigid motions (the chord's linear field, u = 0): S003 Table 1's
    3.55 kg, centre of mass 0.30 m from B and 0.197 kg m² about it."""
    sp = rod_split(ROD.mass_kg, ROD.length_m, ROD.x_g_m, ROD.inertia_kgm2, 0.0)
    M, _, _ = modal_matrices(sp, 1e8, 1e4)
    L = sp.length_m
    trans = np.array([1.0, 1.0, 0.0, 0.0, 0.0])    # B' and C moved alike
    rot_b = np.array([0.0, L, 0.0, 0.0, 0.0])      # turned about B: C moves L (across), B' stays
    m = trans @ M @ trans
    first = trans @ M @ rot_b                       # m x_G
    i_b = rot_b @ M @ rot_b
    assert m == pytest.approx(3.55)
    assert first / m == pytest.approx(0.30)
    assert i_b - m * (first / m) ** 2 == pytest.approx(0.197)


def test_modal_forces_are_the_gradient_of_the_energy_and_the_dampers_dissipate():
    """At a bent, stretched, turned rod with the supports displaced and no velocity, the forces are −∂V/∂q
    (central differences of modal_energy's V, an independent computation); with velocities, the dampers' force
    does −(the dissipated power) of work: Q_damping · q̇ = −D."""
    cfg = preset(12).replace(**{"structure.mode": "flexible"})
    run, _ = _run(cfg)
    lay, P, G = run.layout, run.P, run.layout.G
    n = lay.n
    rng = np.random.default_rng(7)
    q = run.x[:n].copy()
    q[N_Q:] = rng.normal(scale=2e-5, size=n - N_Q)
    q[4] += 3e-6
    q[8:11] += rng.normal(scale=1e-6, size=3)
    zero = np.zeros(n)
    Q = np.zeros(n)
    modal_forces(P, q, zero, lay.H, lay.MD, G, Q)
    from twin.natural_coordinates import energy, kinetic_energy

    def v_own(qq):   # the modal rod's and the supports' potential: less the rigid model's (generalized_forces')
        return (modal_energy(P, qq, zero, lay.H, lay.MD, G, lay.F)[1]
                - (energy(P, qq[:N_Q], zero[:N_Q]) - kinetic_energy(P, qq[:N_Q], zero[:N_Q])))

    for i in [2, 3, 4, 5, 8, 9, 10] + list(range(N_Q, n)):
        e = 1e-9
        qp, qm = q.copy(), q.copy()
        qp[i] += e
        qm[i] -= e
        dV = (v_own(qp) - v_own(qm)) / (2 * e)
        assert Q[i] == pytest.approx(-dV, rel=1e-5, abs=1e-6 * np.max(np.abs(Q))), i
    qd = run.x[n:2 * n].copy()
    qd[N_Q:] = rng.normal(scale=0.05, size=n - N_Q)
    Qv, Q0 = np.zeros(n), np.zeros(n)
    diss = modal_forces(P, q, qd, lay.H, lay.MD, G, Qv)
    modal_forces(P, q, zero, lay.H, lay.MD, G, Q0)
    # the elastic forces do not depend on q̇: the difference is the dampers'
    assert diss > 0.0
    assert (Qv - Q0) @ qd == pytest.approx(-diss, rel=1e-9)


@pytest.mark.parametrize("test_id", [3, 12])
def test_modal_sparse_solve_equals_a_dense_lagrange_solve(test_id):
    """The step's sparse constraint-force solve (flexible_kkt with the modal rod's constant mass matrix) against the
    dense Lagrange system [[M, Φᵀ], [Φ, 0]] [q̈, λ] = [Q, γ] built from the same rows, on random states: the same q̈."""
    from twin.reference import flexible_kkt as KK

    cfg = preset(test_id).replace(**{"structure.mode": "flexible"})
    run, _ = _run(cfg)
    lay, P = run.layout, run.P
    n = lay.n
    kk = run.kkt(False)
    m = kk.crow.shape[0]
    M = lay.mass_matrix(P)
    z = np.empty((0, 3), dtype=np.int64)
    rng = np.random.default_rng(test_id)
    for _ in range(3):
        q = run.x[:n] + rng.normal(scale=1e-3, size=n)
        qd = run.x[n:2 * n] + rng.normal(scale=0.5, size=n)
        Q = rng.normal(scale=50.0, size=n)
        PhiV, gam, Y, W = np.zeros((m, kk.pat.shape[1])), np.empty(m), np.empty((m, n)), np.empty((m, m))
        KK.kkt_rows(P, q, qd, z, z, kk.crow, kk.pat, kk.pn, 0.0, PhiV, gam, np.empty(12))
        assert KK.kkt_factor(P, q, kk.crow, kk.pat, kk.pn, PhiV, kk.Minv, kk.cols, kk.cn, kk.Mcrank, kk.kaug, Y, W,
                             np.empty((3, 5, 5)), kk.wlo)
        qdd = np.empty(n)
        KK.kkt_accelerations(q, Q, kk.crow, kk.pat, kk.pn, PhiV, gam, kk.Minv, kk.cols, kk.cn, Y, W, qdd, np.empty(m))
        Phi = np.zeros((m, n))
        for r in range(m):
            for t in range(kk.pn[r]):
                Phi[r, kk.pat[r, t]] += PhiV[r, t]
        # θ carries no mass: the dense system is still regular (rows 0-1 hold θ through the crank)
        A = np.block([[M, Phi.T], [Phi, np.zeros((m, m))]])
        sol = np.linalg.solve(A, np.concatenate([Q, gam]))
        assert np.max(np.abs(sol[:n] - qdd)) <= 1e-9 * np.max(np.abs(qdd))


def test_modal_rod_runs_test12_and_reads_the_structure_channels():
    """Table 4 test 12 with the modal rod, 10 ms from rest: finite channels, the rod's sag under gravity and its
    stretch of the chain's order (µm and sub-µm), and the option in the metadata only where the rod is flexible."""
    from twin.reference.engine import ReferenceEngine, ReferenceOptions
    from twin.simulation import Collector, simulate

    cfg = preset(12).replace(**{"simulation.engine": "reference", "simulation.duration_s": 0.01,
                                "structure.mode": "flexible",
                                "sensors.channels": ("accel", "crank", "structure")})
    keep = Collector()
    eng = ReferenceEngine(cfg, ReferenceOptions(rod_model="modal"))
    simulate(cfg, [keep], engine=eng)
    run = keep.run
    for name in ("AC1", "AC4", "rod_deflection", "rod_stretch"):
        assert np.all(np.isfinite(run[name])), name
    assert 1e-7 < np.max(np.abs(run["rod_deflection"])) < 1e-4
    assert np.max(np.abs(run["rod_stretch"])) < 1e-5
    assert eng.meta["options"]["rod_model"] == "modal"
    rigid = ReferenceEngine(preset(12).replace(**{"simulation.engine": "reference"}))
    assert "rod_model" not in rigid.meta["options"]


def test_rod_model_option_errors_name_the_field():
    from twin.reference.engine import ReferenceOptions

    with pytest.raises(ConfigError, match=r"^reference\.rod_model: must be one of chain, modal, got 'beam'$"):
        ReferenceOptions(rod_model="beam")
    cfg = preset(12).replace(**{"structure.mode": "flexible", "structure.rod_end_inertia_kgm2": 5e-4})
    with pytest.raises(ConfigError, match=r"^reference\.rod_model: \"modal\" needs structure\.rod_end_inertia_kgm2"):
        _run(cfg)


def test_stiffer_modal_rod_tends_to_the_rigid_model():
    """As the chain's check (tests/test_structure_reference.py): test 3, 20 ms from rest, stiff supports; the
    slider's departure from the rigid model at least halves with each fourfold modulus and is below 0.1 µm at
    840 GPa."""
    from twin.reference.engine import ReferenceEngine, ReferenceOptions
    from twin.simulation import Collector, simulate, simulate_run

    base = preset(3).replace(**{"simulation.engine": "reference", "simulation.duration_s": 0.02})
    rigid = simulate_run(base).channels["slider_position"].data
    diffs = []
    for e in (52.5e9, 210e9, 840e9):
        cfg = base.replace(**{"structure.mode": "flexible", "structure.rod_youngs_modulus_pa": e,
                              "structure.frame_frequency_hz": 12000.0, "structure.guide_frequency_hz": 12000.0,
                              "structure.frame_mass_kg": 40.0, "structure.guide_mass_kg": 20.0})
        keep = Collector()
        simulate(cfg, [keep], engine=ReferenceEngine(cfg, ReferenceOptions(rod_model="modal")))
        diffs.append(float(np.max(np.abs(keep.run.channels["slider_position"].data - rigid))))
    assert diffs[0] > 2 * diffs[1] > 4 * diffs[2], diffs
    assert diffs[2] < 1e-7, diffs
