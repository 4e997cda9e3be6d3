"""The reference engine's flexible structure: a tap on the rod decays with the configured damping, the energy balance
holds with the structural dampers' dissipation counted, a stiffer structure tends to the rigid model, and a
flexible run of a Table 4 test goes through the engine with the sensor mounts."""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.config import preset
from twin.natural_coordinates import initial_state
from twin.reference import model as RM
from twin.reference.flexible import N_OUT_FLEX, O_DISS, FlexibleRun
from twin.reference.flexible_tap import tap_response


def _run(cfg, theta0, *, drive=False, guide_friction=False, rod_model="chain"):
    prm = lambda c: RM.build_params(c, drive=drive, guide_friction=guide_friction)  # noqa: E731
    if rod_model == "modal":
        from twin.reference.flexible_modal_run import ModalRun

        run = ModalRun(cfg, prm(cfg), prm)
    else:
        run = FlexibleRun(cfg, prm(cfg), prm)
    run.P[RM.P_OUT_ENERGY] = 1.0   # the energy columns
    st = initial_state(cfg, theta0, 0.0, run.P)
    run.reset(st)
    return run, st


@pytest.mark.parametrize("rod_model", ["chain", "modal"])
def test_tap_decays_with_the_configured_damping_ratio(rod_model):
    """Rod between a crank of large inertia and the guide on heavy, undamped supports, no gravity, no drive: a tap
    (transverse velocity of the middle node) rings in the first bending mode, whose logarithmic decrement over
    ~30 periods gives the damping ratio set for it (independent basis: ζ = δ / √(4π² + δ²) of a linear mode).
    Both reference rods (the chain and the modal rod, ``reference.rod_model``)."""
    zeta_set = 0.01
    cfg = preset(3).replace(**{
        "structure.mode": "flexible", "mechanism.gravity_mps2": 0.0, "bodies.crank.inertia_kgm2": 10.0,
        "structure.bending_damping_ratio": zeta_set, "structure.frame_damping_ratio": 0.0,
        "structure.guide_damping_ratio": 0.0, "structure.frame_mass_kg": 1000.0, "structure.guide_mass_kg": 1000.0})
    t, w = tap_response(cfg, 0.01, 0.2, 5, 0.3, rod_model=rod_model)
    stride, h = 5, cfg.simulation.timestep_s
    peaks, times = [], []
    for i in range(1, w.size - 1):
        if w[i] > 0 and w[i] > w[i - 1] and w[i] >= w[i + 1]:   # parabolic interpolation of each crest
            a, b, c = w[i - 1], w[i], w[i + 1]
            d = 0.5 * (a - c) / (a - 2 * b + c)
            peaks.append(b - 0.25 * (a - c) * d)
            times.append(t[i] + d * stride * h)
    peaks, times = np.array(peaks), np.array(times)
    keep = times > 0.02      # after the third mode (ζ ≈ 9 %) has died out
    v = peaks[keep]
    delta = math.log(v[0] / v[-1]) / (v.size - 1)
    zeta = delta / math.sqrt(4 * math.pi ** 2 + delta ** 2)
    assert v.size > 25
    assert zeta == pytest.approx(zeta_set, rel=0.05)
    # and it rings at the first bending mode (pinned-pinned closed form 192.4 Hz, within 1 %)
    assert 1.0 / np.mean(np.diff(times[keep])) == pytest.approx(192.4, rel=0.01)


def _crests(t, w, sign):
    """Times and values of the crests (sign +1) or troughs (−1) of w, each refined by a parabola."""
    tt, vv = [], []
    for i in range(1, w.size - 1):
        if sign * w[i] > sign * w[i - 1] and sign * w[i] >= sign * w[i + 1]:
            a, b, c = w[i - 1], w[i], w[i + 1]
            d = 0.5 * (a - c) / (a - 2 * b + c)
            vv.append(b - 0.25 * (a - c) * d)
            tt.append(t[i] + d * (t[1] - t[0]))
    return np.array(tt), np.array(vv)


@pytest.mark.parametrize("rod_model", ["chain", "modal"])
def test_axial_tap_rings_at_the_closed_form_and_decays_with_the_axial_ratio(rod_model):
    """The same heavy crank and supports; a tap on the bore C along the rod: the stretch |C − B'| − L rings at the
    first axial mode of the bar fixed at B with the end mass and the slider at C (closed form β tan β = m_bar/m_tip,
    1041.4 Hz; within 1 %) and its crest-to-trough amplitude decays with the axial damping ratio set (within 5 %)."""
    from twin.structure import axial_fixed_mass_hz, rod_split

    zeta_set = 0.01
    cfg = preset(3).replace(**{
        "structure.mode": "flexible", "mechanism.gravity_mps2": 0.0, "bodies.crank.inertia_kgm2": 10.0,
        "structure.axial_damping_ratio": zeta_set, "structure.frame_damping_ratio": 0.0,
        "structure.guide_damping_ratio": 0.0, "structure.frame_mass_kg": 1000.0, "structure.guide_mass_kg": 1000.0})
    rod = cfg.bodies.rod
    sp = rod_split(rod.mass_kg, rod.length_m, rod.x_g_m, rod.inertia_kgm2, 0.0)
    f_ref = axial_fixed_mass_hz(cfg.structure.rod_ea_n, sp.bar_mass_kg / sp.length_m, sp.length_m,
                                sp.end_c_kg + cfg.bodies.slider.mass_kg, 1)[0]
    t, w = tap_response(cfg, 0.01, 0.05, 1, 0.3, axial=True, rod_model=rod_model)
    tp, p = _crests(t, w, 1)
    _, v = _crests(t, w, -1)
    m = min(p.size, v.size)
    amp = 0.5 * (p[:m] - v[:m])     # crest to trough: blind to the slow drift of the coasting mechanism
    keep = tp[:m] > 0.002
    a = amp[keep]
    delta = math.log(a[0] / a[-1]) / (a.size - 1)
    assert a.size > 40
    assert delta / math.sqrt(4 * math.pi ** 2 + delta ** 2) == pytest.approx(zeta_set, rel=0.05)
    assert 1.0 / np.mean(np.diff(tp)) == pytest.approx(f_ref, rel=0.01)


def _energy_change(cfg, flexible, rod_model="chain"):
    """(E(end) − E(0), dissipated) of a free swing from rest at θ = π/3 (S003 §4.1), no drive, no guide friction."""
    n, stride = 10000, 100
    zero = np.zeros(n)
    if flexible:
        run, st = _run(cfg, math.pi / 3, rod_model=rod_model)
        buf = np.empty((n // stride, N_OUT_FLEX))
        assert run.run(st, zero, zero, stride, buf)[0] == RM.OK
        e = buf[:, RM.O_EKIN] + buf[:, RM.O_EPOT]
        return e[-1] - e[0], buf[-1, O_DISS]
    P = RM.build_params(cfg, drive=False, guide_friction=False)
    P[RM.P_OUT_ENERGY] = 1.0
    st = initial_state(cfg, math.pi / 3, 0.0, P)
    buf = np.empty((n // stride, RM.N_OUT))
    assert RM.run_steps(P, st, zero, zero, stride, buf, True)[0] == RM.OK
    e = buf[:, RM.O_EKIN] + buf[:, RM.O_EPOT]
    return e[-1] - e[0], 0.0


@pytest.mark.parametrize("rod_model", ["chain", "modal"])
def test_energy_balance_counts_the_structural_damping(rod_model):
    """Free swing of the ideal mechanism (test 3's joints): the flexible model's mechanical energy (kinetic, gravity,
    hinges, slides, supports; the modal rod's chord and shapes) plus what its dampers dissipated changes only by the
    rigid model's own numerical loss (the projection's, S003 §4.1) — within 2 % of the dissipated energy."""
    cfg = preset(3).replace(**{"structure.mode": "flexible", "structure.bending_damping_ratio": 0.05,
                               "structure.axial_damping_ratio": 0.05})
    d_flex, dissipated = _energy_change(cfg, True, rod_model)
    d_rigid, _ = _energy_change(preset(3), False)
    assert dissipated > 1e-5
    assert abs(d_flex + dissipated - d_rigid) < 0.02 * dissipated


@pytest.mark.parametrize("engine, solver", [("reference", None), ("mujoco", "PGS"), ("mujoco", "Newton")])
def test_stiffer_structure_tends_to_the_rigid_model(engine, solver):
    """Test 3 (ideal joints), 20 ms from rest, stiff supports: the slider's departure from the rigid model shrinks with
    the rod's compliance (quasi-static stretch and sag ∝ 1/E): each fourfold modulus at least halves it (a factor 4
    for the elastic part; what remains at the stiffest is the first-order step's difference between the two
    formulations, ~1e-3 rad/s on the crank speed), and at 840 GPa it is below 0.1 µm. In both engines, MuJoCo with
    either of its flexible solvers (``mujoco.flexible_solver``; measured 0.41, 0.17, 0.065 µm with both)."""
    base = preset(3).replace(**{"simulation.engine": engine, "simulation.duration_s": 0.02})
    from twin.simulation import simulate_run

    rigid = simulate_run(base).channels["slider_position"].data
    diffs = []
    for e in (52.5e9, 210e9, 840e9):
        cfg = base.replace(**{"structure.mode": "flexible", "structure.rod_youngs_modulus_pa": e,
                              "structure.frame_frequency_hz": 12000.0, "structure.guide_frequency_hz": 12000.0,
                              "structure.frame_mass_kg": 40.0, "structure.guide_mass_kg": 20.0,
                              **({"mujoco.flexible_solver": solver} if solver else {})})
        flex = simulate_run(cfg).channels["slider_position"].data
        diffs.append(float(np.max(np.abs(flex - rigid))))
    assert diffs[0] > 2 * diffs[1] > 4 * diffs[2], diffs
    assert diffs[2] < 1e-7, diffs


def test_flexible_test6_runs_with_mounted_sensors():
    """Test 6 (0.1 mm at C) for 20 ms, flexible: the run completes, every channel finite, the rod's sensors differ
    from the rigid run's (they read the flexible rod through their mounts) while the crank follows the same drive."""
    from twin.simulation import simulate_run

    base = preset(6).replace(**{"simulation.engine": "reference", "simulation.duration_s": 0.02})
    rigid = simulate_run(base).channels
    flex = simulate_run(base.replace(**{"structure.mode": "flexible"})).channels
    for name, ch in flex.items():
        assert np.all(np.isfinite(ch.data)), name
    assert np.max(np.abs(flex["AC3"].data - rigid["AC3"].data)) > 0.1
    assert np.max(np.abs(flex["crank_angle"].data - rigid["crank_angle"].data)) < 1e-3


def test_friction_is_mu_times_the_normal_force_the_step_applies():
    """Coulomb's law at the clearance joints B and C of the flexible rod (test 12, 0.1 s from rest): the regularized
    law gives |f_T| = μ(|v_t|) f_N with μ ≤ μ0, so |f_T| ≤ μ0 f_N in every sample.
    Independent basis: the friction law itself (S003 Eq. 19–20), with the f_N the step applies (the θ-method's,
    reported in fn_B/fn_C). The friction had taken the explicit normal force, and exceeded μ0 f_N by 0.7 %
    here (2 % at full speed). Tolerance: the channels' float32 rounding."""
    from twin.simulation import simulate_run

    cfg = preset(12).replace(**{"simulation.engine": "reference", "simulation.duration_s": 0.1,
                                "structure.mode": "flexible"})
    ch = simulate_run(cfg).channels
    mu0 = cfg.contact.mu0
    for j in ("B", "C"):
        fn = ch[f"fn_{j}"].data.astype(np.float64)
        ft = ch[f"ft_{j}"].data.astype(np.float64)
        on = fn > 1.0
        assert on.sum() > 1000, j
        ratio = np.abs(ft[on]) / fn[on]
        assert ratio.max() <= mu0 * (1.0 + 1e-5), (j, ratio.max())


def test_flexible_runs_with_the_drive_train_the_prescribed_crank_and_refuses_what_it_leaves_out():
    """Test 12 for 10 ms through the flexible loop driven by the motor and V-belt (finite channels, the motor's
    channels present) and by the prescribed crank (the crank angle is the program's at every sample, as in the
    rigid model); a clearance at A is refused in one line naming the field."""
    from twin.drive import DriveReference
    from twin.errors import ConfigError
    from twin.reference.engine import ReferenceEngine
    from twin.simulation import simulate_run

    base = preset(12).replace(**{"simulation.engine": "reference", "simulation.duration_s": 0.01,
                                 "structure.mode": "flexible"})
    run = simulate_run(base.replace(**{"drive.mode": "motor", "sensors.channels": ["accel", "crank", "motor"]}))
    assert "motor_speed" in run.channels
    assert all(np.all(np.isfinite(ch.data)) for ch in run.channels.values())
    cfg = base.replace(**{"drive.mode": "prescribed", "sensors.channels": ["accel", "crank", "drive"]})
    run = simulate_run(cfg)
    th, _ = DriveReference(cfg)(np.arange(run.channels["crank_angle"].data.size) / cfg.sensors.output_rate_hz)
    assert np.max(np.abs(run.channels["crank_angle"].data - th)) < 1e-9
    assert all(np.all(np.isfinite(ch.data)) for ch in run.channels.values())
    with pytest.raises(ConfigError, match=r"^joints\.clearance_a_mm: is not available with structure\.mode = "
                                          r"\"flexible\".*use 0, got 0\.1$"):
        ReferenceEngine(base.replace(**{"joints.clearance_a_mm": 0.1}))
    # the guide's play too, naming its own field (as the MuJoCo engine does)
    with pytest.raises(ConfigError, match=r"^joints\.clearance_guide_mm: is not available with structure\.mode"):
        ReferenceEngine(base.replace(**{"joints.clearance_guide_mm": 0.2}))
    with pytest.raises(ConfigError, match=r"^sensors\.channels: the optional group 'drive_energy'"):
        ReferenceEngine(base.replace(**{"drive.mode": "motor", "sensors.channels": ["accel", "drive_energy"]}))


def _nyquist_fraction(h):
    """Test 12 (B and C clearances, 750 rpm), flexible, reference engine at step ``h``: the share of fn_B's energy
    (Hann window, mean removed, t in [0.2, 0.6] s, sampled at 100 kHz) in the 40-50 kHz band."""
    import twin

    cfg = preset(12).replace(**{"structure.mode": "flexible", "simulation.duration_s": 0.6,
                                "simulation.engine": "reference", "simulation.timestep_s": h})
    r = twin.simulate(cfg)
    x = np.asarray(r["fn_B"], float)[int(0.2 * r.rate_hz):]
    X = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(len(x)))) ** 2
    f = np.fft.rfftfreq(len(x), 1.0 / r.rate_hz)
    return X[(f >= 40e3) & (f <= 50e3)].sum() / X[f > 0].sum()


@pytest.mark.long
def test_contact_force_at_B_does_not_ring_at_the_steps_nyquist_rate():
    """The contact law's explicit damping on the rod's light housing at B, unbounded, rang at 50 kHz, the Nyquist
    rate of h = 1e-5 s (a quarter of fn_B's energy in 40-50 kHz on test 12). Independent basis: the same run at h/2,
    whose Nyquist rate is 100 kHz, outside the band: the band's share at h is no more than 10x its share there (or
    1e-9, a floor of round-off; measured 4e-13 at h and 2e-12 at h/2 with the bound, 0.25 and 8e-16 without)."""
    at_h, at_half = _nyquist_fraction(1e-5), _nyquist_fraction(5e-6)
    assert at_h <= max(10.0 * at_half, 1e-9), (at_h, at_half)


def test_normal_mobility_is_the_relative_acceleration_per_newton():
    """normal_mobility (1/m̂ of the damping bound) against its definition: a unit force pair along n (on the crank's
    pin B, and the opposite on the rod's eye B') changes the relative normal acceleration n·(B̈ − B̈') by −1/m̂ in the
    flexible model's own accelerations; and m̂ lies between the housing's mass and the whole mechanism's."""
    from twin.natural_coordinates import N_Q, N_Z
    from twin.reference import flexible_kernels as F
    from twin.reference import flexible_rmatrix as FR

    cfg = preset(12).replace(**{"structure.mode": "flexible"})
    run, _ = _run(cfg, 0.7, drive=True)
    lay, P, G = run.layout, run.P, run.layout.G
    n, nc = lay.n, lay.n - N_Q
    q, qd = run.x[:n].copy(), run.x[n:2 * n].copy()
    rows = np.empty(N_Z + 4 + nc, dtype=np.int64)
    nz = FR.flex_rows(P, G, lay.indep, rows)
    r0 = N_Q + lay.segs.shape[0] + lay.slides.shape[0]
    for k in range(lay.indep.shape[0]):
        rows[nz] = r0 + k
        nz += 1
    A, LU, piv = np.empty((nc, n)), np.empty((nc, nc)), np.empty(nc, dtype=np.int64)
    assert F.factor(q, lay.segs, lay.slides, lay.indep, A, LU, piv)
    Rt, MR, Mb, S = np.empty((nz, n)), np.empty((nz, n)), np.empty((nz, nz)), np.empty(n)
    RtT, Bm = np.empty((n, nz)), np.empty((nc, nz + 1))
    FR.flex_mass(P, G, q, qd, lay.segs, lay.seg_f, lay.slides, A, LU, piv, rows, nz, Rt, S, Mb, MR, np.empty(n),
                Bm, RtT)
    nx, ny = 0.6, 0.8
    mob = FR.normal_mobility(Rt, Mb, nz, False, 0, 1, 2, 3, nx, ny, np.empty(2 * nz), np.empty((nz, nz)))

    def rel_acc(Q):
        qdd = np.empty(n)
        assert FR.flex_solve_acc(q, Q, nz, Rt, RtT, S, Mb.copy(), np.empty(nz), np.empty(n), np.empty(n), qdd, P,
                                lay.segs, lay.seg_f, G, False, 0.0, np.zeros(1))
        return nx * (qdd[0] - qdd[2]) + ny * (qdd[1] - qdd[3])

    Q0 = np.zeros(n)
    Q1 = Q0.copy()
    Q1[[0, 1]] -= (nx, ny)      # on the pin B (the crank's point: q_0, q_1), −n
    Q1[[2, 3]] += (nx, ny)      # on the eye B', +n
    assert rel_acc(Q1) - rel_acc(Q0) == pytest.approx(-mob, rel=1e-9)
    m_hat = 1.0 / mob
    assert 0.1 < m_hat < cfg.bodies.rod.mass_kg + cfg.bodies.slider.mass_kg + cfg.bodies.crank.mass_kg, m_hat


@pytest.mark.parametrize("test_id, chain", [(6, (6, 2)), (12, (6, 2)), (12, (16, 1)), (12, (4, 4))])
@pytest.mark.parametrize("prescribed", [False, True])
def test_sparse_constraint_force_solve_equals_the_r_matrix_solve(test_id, chain, prescribed):
    """The step's sparse solve (twin.reference.flexible_kkt: Lagrange multipliers, block-diagonal M̃) against the
    dense R-matrix one (flex_mass, flex_solve_acc, normal_mobility: Rᵀ M R z̈ = Rᵀ (Q − M Ṙż)) on random
    configurations near a running pose (coordinates moved off the constraint manifold, random velocities and
    forces): the same q̈, drive torque of the prescribed crank and contact mobilities at B and C to round-off
    (kkt_mobility and the step's pair_response), and the same change of q̈, contact forces and drive torque by the
    contact damping's θ-method (kkt_theta_damping against theta_damping); W's factor, computed on its envelope,
    against NumPy's Cholesky of the dense Φ_c M̃⁻¹ Φ_cᵀ.
    Independent basis: the two are different algebra for the same equations (Gauss's principle), the R matrix
    a basis of the allowed motions, the multipliers its complement. Chains (rod_segments, rod_axial_groups): the
    default, one axial group of 16 segments (a 17-point mass block), a slide at every node."""
    from twin.natural_coordinates import N_Q, N_Z
    from twin.reference import flexible_kernels as F
    from twin.reference import flexible_rmatrix as FR
    from twin.reference import flexible_kkt as KK

    cfg = preset(test_id).replace(**{"structure.mode": "flexible", "structure.rod_segments": chain[0],
                                     "structure.rod_axial_groups": chain[1], "simulation.timestep_s": 1e-7})
    run, _ = _run(cfg, 0.7, drive=True)
    lay, P, G = run.layout, run.P, run.layout.G
    n, nc = lay.n, lay.n - N_Q
    rng = np.random.default_rng(43 + test_id + 2 * prescribed + chain[0])
    kk = KK.KKTLayout(P, G, lay.segs, lay.seg_f, lay.slides, n, prescribed)
    m = kk.crow.shape[0]
    for _ in range(3):
        q = run.x[:n] + rng.normal(scale=1e-3, size=n)
        qd = run.x[n:2 * n] + rng.normal(scale=0.5, size=n)
        Q = rng.normal(scale=50.0, size=n)
        alpha = float(rng.normal(scale=100.0))
        rows = np.empty(N_Z + 4 + nc, dtype=np.int64)
        nz = FR.flex_rows(P, G, lay.indep, rows)
        for k in range(lay.indep.shape[0]):
            rows[nz] = N_Q + lay.segs.shape[0] + lay.slides.shape[0] + k
            nz += 1
        A, LU, piv = np.empty((nc, n)), np.empty((nc, nc)), np.empty(nc, dtype=np.int64)
        assert F.factor(q, lay.segs, lay.slides, lay.indep, A, LU, piv)
        Rt, MR, Mb, S = np.empty((nz, n)), np.empty((nz, n)), np.empty((nz, nz)), np.empty(n)
        RtT = np.empty((n, nz))
        FR.flex_mass(P, G, q, qd, lay.segs, lay.seg_f, lay.slides, A, LU, piv, rows, nz, Rt, S, Mb, MR, np.empty(n),
                    np.empty((nc, nz + 1)), RtT)
        mobs = [FR.normal_mobility(Rt, Mb, nz, prescribed, *j, 0.6, 0.8, np.empty(2 * nz), np.empty((nz, nz)))
                for j in ((0, 1, 2, 3), (6, -1, 4, 5))]
        qdd, tau = np.empty(n), np.zeros(1)
        assert FR.flex_solve_acc(q, Q, nz, Rt, RtT, S, Mb.copy(), np.empty(nz), np.empty(n), np.empty(n), qdd, P,
                                lay.segs, lay.seg_f, G, prescribed, alpha, tau)

        PhiV, gam, Y, W = np.zeros((m, kk.pat.shape[1])), np.empty(m), np.empty((m, n)), np.empty((m, m))
        KK.kkt_rows(P, q, qd, lay.segs, lay.slides, kk.crow, kk.pat, kk.pn, alpha, PhiV, gam, np.empty(12))
        assert KK.kkt_factor(P, q, kk.crow, kk.pat, kk.pn, PhiV, kk.Minv, kk.cols, kk.cn, kk.Mcrank, kk.kaug, Y, W,
                             np.empty((3, 5, 5)), kk.wlo)
        # the factor computed on W's envelope (kk.wlo) against NumPy's Cholesky of the dense Φ_c M̃⁻¹ Φ_cᵀ, which
        # is exactly zero before the envelope
        Phi = np.zeros((m, n))
        for r in range(m):
            Phi[r, kk.pat[r, :kk.pn[r]]] = PhiV[r, :kk.pn[r]]
        Wd = Phi @ kk.Minv @ Phi.T
        assert all(np.all(Wd[r, :kk.wlo[r]] == 0.0) for r in range(m))
        Ld = np.linalg.cholesky(0.5 * (Wd + Wd.T))
        assert np.max(np.abs(np.tril(W) - Ld)) <= 1e-9 * np.max(np.abs(Ld))
        mobs2 = [KK.kkt_mobility(kk.pat, kk.pn, PhiV, kk.Minv, kk.cols, kk.cn, Y, W, m, *j, 0.6, 0.8,
                                 np.empty(2 * m)) for j in ((0, 1, 2, 3), (6, -1, 4, 5))]
        qdd2 = np.empty(n)
        mu = KK.kkt_accelerations(q, Q, kk.crow, kk.pat, kk.pn, PhiV, gam, kk.Minv, kk.cols, kk.cn, Y, W, qdd2,
                                  np.empty(m))
        assert np.max(np.abs(qdd2 - qdd)) <= 1e-10 * np.max(np.abs(qdd)), np.max(np.abs(qdd2 - qdd))
        assert mobs2 == pytest.approx(mobs, rel=1e-10)
        # the step's form: one constrained response per pair, its mobility J z (the θ-method reads z)
        jo = np.array([0.6e-5, 0.8e-5, 1e-6, 0.0, 0.0])
        zr, vr = np.empty((2, n)), np.empty((2, m))
        mobs3 = [KK.pair_response(kk.Minv, Y, W, m, a, *j, jo, zr, vr)
                 for a, j in enumerate(((0, 1, 2, 3), (6, -1, 4, 5)))]
        assert mobs3 == pytest.approx(mobs, rel=1e-10)
        if prescribed:
            assert qdd2[7] == pytest.approx(alpha, rel=1e-12)
            assert -mu == pytest.approx(tau[0], rel=1e-9, abs=1e-9 * np.max(np.abs(Q)))
        # the contact damping's θ-method after the solve: the sparse form against the R-matrix one, the joints with a
        # clearance in contact, B's damping trapezoidal (c h ≤ 2 m̂) and C's beyond it (θ = 1 − m̂/(c h))
        fB = 120.0 if cfg.joints.clearance_b_mm > 0 else 0.0
        lawB = np.array([100.0, 5e3, 0.01, 0.5, 0.6, 0.8])
        lawC = np.array([80.0, 3e7, -0.02, -0.3, 0.8, -0.6])
        jb1, jc1, jb2, jc2 = np.zeros(6), np.zeros(6), np.zeros(6), np.zeros(6)
        q1, q2 = qdd.copy(), qdd2.copy()
        d1 = FR.theta_damping(1e-5, q1, Rt, Mb, nz, prescribed, lawB, lawC, fB, 90.0, False, jb1, jc1)
        d2 = KK.kkt_theta_damping(1e-5, q2, kk.Minv, Y, W, m, kk.crow, lawB, lawC, fB, 90.0, False, jb2, jc2,
                                  np.empty((2, n)), np.empty((2, m)))
        assert jc1[3] != 90.0 and (fB == 0.0 or jb1[3] != fB)   # the method changed the forces in contact
        assert (jb2[3], jc2[3]) == pytest.approx((jb1[3], jc1[3]), rel=1e-9)
        assert np.max(np.abs(q2 - q1)) <= 1e-9 * np.max(np.abs(q1)), np.max(np.abs(q2 - q1))
        assert d2 == pytest.approx(d1, rel=1e-8, abs=1e-12 * max(1.0, abs(d1)))
        if not prescribed:
            assert d1 == 0.0 and d2 == 0.0


def test_chain_block_solve_equals_a_dense_solve_for_every_chain():
    """The projection's chain block solved block-tridiagonally (flexible_kernels.chain_order, bt_factor, bt_solve)
    against numpy's dense LU with partial pivoting on the same rows, for every (rod_segments, rod_axial_groups) the
    configuration allows, at a pose moved off the straight rod at random: no row reaches beyond the points next
    to its own (the band the block LU assumes), and the solutions agree to round-off."""
    from twin.natural_coordinates import N_Q
    from twin.reference import flexible_kernels as F

    rng = np.random.default_rng(7)
    checked = 0
    for N in range(2, 25):
        for M in [m for m in range(1, N + 1) if N % m == 0]:
            cfg = preset(12).replace(**{"structure.mode": "flexible", "structure.rod_segments": N,
                                        "structure.rod_axial_groups": M, "simulation.timestep_s": 1e-7,
                                        "structure.rod_chain": "tuned" if N >= 4 else "uniform"})
            prm = lambda c: RM.build_params(c, drive=False, guide_friction=False)  # noqa: E731
            run = FlexibleRun(cfg, prm(cfg), prm)
            run.reset(initial_state(cfg, 0.7, 0.0, run.P))
            lay = run.layout
            n, nc = lay.n, lay.n - N_Q
            q = run.x[:n] + rng.normal(scale=1e-4, size=n)
            A, LU, piv = np.empty((nc, n)), np.empty((nc, nc)), np.empty(nc, dtype=np.int64)
            assert F.factor(q, lay.segs, lay.slides, lay.indep, A, LU, piv), (N, M)
            Ac = A[:, N_Q:][piv]
            band = np.zeros(Ac.shape, dtype=bool)
            for k in range(nc // 2):
                lo, hi = max(0, k - 1), min(nc // 2, k + 2)
                band[2 * k:2 * k + 2, 2 * lo:2 * hi] = True
            assert not np.any(Ac[~band]), (N, M)
            b = rng.normal(size=nc)
            x = np.empty(nc)
            F.bt_solve(LU, piv, nc, b, x)
            ref = np.linalg.solve(A[:, N_Q:], b)
            assert np.max(np.abs(x - ref)) <= 1e-12 * np.max(np.abs(ref)), (N, M)
            checked += 1
    assert checked == sum(sum(1 for m in range(1, N + 1) if N % m == 0) for N in range(2, 25))
