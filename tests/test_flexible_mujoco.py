"""The MuJoCo twin's flexible structure (structure.mode = "flexible") against the shared discrete model.

Independent bases: the modes of the linearized chain computed by :mod:`twin.structure.rod` from its own
kinetic energy (no MuJoCo), and a support's k/m closed form. MuJoCo's side is measured from the compiled
model itself: its mass matrix (``mj_fullM``), its passive forces' finite differences (stiffness) and its
loop-closure constraint's Jacobian at the straight rod, and in the time domain a tap integrated by
MuJoCo's own step (frequency and logarithmic decrement)."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from scipy.linalg import eigh, null_space
from scipy.signal import find_peaks

from twin import names
from twin.config import preset
from twin.errors import ConfigError
from twin.mujoco_engine.engine import MujocoEngine
from twin.mujoco_engine.flexible import chain_of, joint_names
from twin.structure import modes


def _flexible(test: int = 3, **over):
    return preset(test).replace(**{"structure.mode": "flexible", "simulation.duration_s": 0.01, **over})


def _engine_at_dead_centre(cfg) -> MujocoEngine:
    eng = MujocoEngine(cfg)
    eng.reset(0.0)  # crank along +x: B, C and the guide on one line, the rod straight along x
    return eng


def _linear_modes(eng: MujocoEngine) -> np.ndarray:
    """Undamped frequencies [Hz] of MuJoCo's model linearized at rest, with B pinned (crank, frame and guide
    locked) and C held by the loop closure (joint C's connect, the slider free along the guide)."""
    m, d = eng.model, eng.data
    chain = chain_of(eng.cfg)
    free = [names.ROD_HINGE, *joint_names(chain), names.SLIDER_SLIDE]
    dofs = [int(m.jnt_dofadr[m.joint(j).id]) for j in free]
    qadr = [int(m.jnt_qposadr[m.joint(j).id]) for j in free]
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    # stiffness: central differences of MuJoCo's passive forces
    K = np.zeros((len(free), len(free)))
    q0 = d.qpos.copy()
    eps = 1e-7
    for i, a in enumerate(qadr):
        f = []
        for s in (+1, -1):
            d.qpos[:] = q0
            d.qpos[a] += s * eps
            mujoco.mj_forward(m, d)
            f.append(d.qfrc_passive[dofs].copy())
        K[:, i] = -(f[0] - f[1]) / (2 * eps)
    d.qpos[:] = q0
    mujoco.mj_forward(m, d)
    # the connect's rows (x and y of C in the world)
    eq = m.equality(names.JOINT_C_CONNECT).id
    rows = [r for r in range(d.nefc) if d.efc_type[r] == mujoco.mjtConstraint.mjCNSTR_EQUALITY and d.efc_id[r] == eq]
    J = d.efc_J.reshape(d.nefc, m.nv)[rows][:, dofs]
    J = J[np.linalg.norm(J, axis=1) > 1e-12]
    T = null_space(J)
    w2 = eigh(T.T @ K @ T, T.T @ M[np.ix_(dofs, dofs)] @ T, eigvals_only=True)
    return np.sqrt(np.maximum(w2, 0.0)) / (2 * math.pi)


@pytest.mark.parametrize("segments,groups", [(6, 2), (8, 2), (4, 1)])
def test_mujoco_modes_equal_the_shared_discrete_model(segments, groups):
    cfg = _flexible(**{"structure.rod_segments": segments, "structure.rod_axial_groups": groups})
    f_mj = _linear_modes(_engine_at_dead_centre(cfg))
    ref = modes(chain_of(cfg), "mechanism", cfg.bodies.slider.mass_kg).frequencies_hz
    assert len(f_mj) == len(ref)
    err = np.abs(f_mj / ref - 1.0)
    assert err.max() < 0.01, (f_mj, ref)
    # the same discretization: far tighter than the 1 % asked (a regression guard on the builder)
    assert err.max() < 1e-6, (f_mj, ref)


def test_rod_keeps_table1_mass_centre_and_inertia():
    cfg = _flexible()
    eng = _engine_at_dead_centre(cfg)
    m, d = eng.model, eng.data
    rod = m.body(names.ROD).id
    bodies = [b for b in range(m.nbody) if b == rod or _is_descendant(m, b, rod)]
    mass = sum(m.body_mass[b] for b in bodies)
    # centre of mass and inertia about it in the rod frame (rod straight along x at θ = 0)
    x0 = d.xpos[rod]
    com = sum(m.body_mass[b] * (d.xipos[b] - x0) for b in bodies) / mass
    izz = sum(m.body_inertia[b][2] + m.body_mass[b] * np.sum((d.xipos[b] - x0 - com)[:2] ** 2) for b in bodies)
    r = cfg.bodies.rod
    assert mass == pytest.approx(r.mass_kg, rel=1e-12)
    assert com[0] == pytest.approx(r.x_g_m, rel=1e-9) and abs(com[1]) < 1e-12
    assert izz == pytest.approx(r.inertia_kgm2, rel=1e-6)  # point-mass housings carry 1e-12 kg m² each


def _is_descendant(m, b, root):
    while b > 0:
        b = m.body_parentid[b]
        if b == root:
            return True
    return False


def test_supports_are_their_configured_oscillators():
    cfg = _flexible(**{"structure.frame_mass_kg": 10.0, "structure.frame_frequency_hz": 700.0,
                       "structure.guide_mass_kg": 2.5, "structure.guide_frequency_hz": 1800.0})
    m = _engine_at_dead_centre(cfg).model
    for joint, body, f in ((names.FRAME_X, names.FRAME_SUPPORT, 700.0), (names.FRAME_Y, names.FRAME_SUPPORT, 700.0),
                           (names.GUIDE_Y, names.GUIDE_SUPPORT, 1800.0)):
        k = float(m.jnt_stiffness[m.joint(joint).id])
        mass = float(m.body_mass[m.body(body).id])
        assert math.sqrt(k / mass) / (2 * math.pi) == pytest.approx(f, rel=1e-12)


def test_tap_rings_at_the_first_bending_mode_and_decays_with_its_damping():
    """Tap: the straight rod at rest (prescribed crank, no gravity, supports made stiff), initial velocity
    in the shared model's first bending mode; MuJoCo's own steps. Frequency within 1 % of the shared
    model's, logarithmic decrement within 5 % of 2πζ/√(1 − ζ²) of the configured ζ."""
    zeta = 0.02
    cfg = _flexible(**{"drive.mode": "prescribed", "structure.bending_damping_ratio": zeta,
                       "structure.frame_mass_kg": 40.0, "structure.frame_frequency_hz": 12000.0,
                       "structure.guide_mass_kg": 20.0, "structure.guide_frequency_hz": 12000.0})
    eng = _engine_at_dead_centre(cfg)
    m, d = eng.model, eng.data
    m.opt.gravity[:] = 0.0
    chain = chain_of(cfg)
    md = modes(chain, "mechanism", cfg.bodies.slider.mass_kg)
    i1 = int(np.flatnonzero(np.array(md.kinds) == "bending")[0])
    shape = md.shapes[:, i1]  # [x_B, y_B, φ, joints...]
    d.qvel[m.jnt_dofadr[m.joint(names.ROD_HINGE).id]] = shape[2]
    for k, jn in enumerate(joint_names(chain)):
        d.qvel[m.jnt_dofadr[m.joint(jn).id]] = shape[3 + k]
    d.qvel[m.jnt_dofadr[m.joint(names.SLIDER_SLIDE).id]] = 0.0
    scale = 1e-3 / np.max(np.abs(d.qvel))
    d.qvel[:] *= scale
    mid = m.site(names.ROD_MID).id
    h = m.opt.timestep
    n = int(0.1 / h)
    y = np.empty(n)
    d.ctrl[:] = 0.0  # crank held at θ = 0 by the dead-beat drive
    for k in range(n):
        mujoco.mj_step(m, d)
        y[k] = d.site_xpos[mid][1]
    f1 = md.frequencies_hz[i1]
    # the positive peaks (at least 0.7 of the shared model's period apart: the higher modes' small ripple
    # makes spurious zero crossings)
    peaks, _ = find_peaks(y, distance=int(0.7 / (f1 * h)))
    peaks = peaks[1:-1]
    period = np.mean(np.diff(peaks)) * h
    assert 1.0 / period == pytest.approx(f1, rel=0.01)
    decrement = np.polyfit(np.arange(len(peaks)), np.log(y[peaks]), 1)[0]
    assert -decrement == pytest.approx(2 * math.pi * zeta / math.sqrt(1 - zeta ** 2), rel=0.05)


def test_flexible_refusals_name_the_field():
    with pytest.raises(ConfigError, match="joints.clearance_a_mm"):
        MujocoEngine(_flexible(**{"joints.clearance_a_mm": 0.1}))
    with pytest.raises(ConfigError, match="mujoco.bushing"):
        MujocoEngine(_flexible(6, **{"mujoco.bushing": "ring", "mujoco.friction": "cone"}))


@pytest.mark.parametrize("test", [6, 12])
def test_posthoc_tree_accelerometers_equal_mujocos_sensors(test):
    """The flexible tree's after-the-rollout readings (twin.mujoco_engine.accel_tree) against MuJoCo's own
    ``<accelerometer>`` sensors on the same run; every other channel bit for bit. Tolerance from the method's
    round-off (tests/test_posthoc_accel.py: eps |qvel|/h per unit lever arm, here times the mount filter's
    largest gain 1/(2ζ) = 10 at its resonance)."""
    from test_posthoc_accel import EPS, _run

    cfg = _flexible(test, **{"simulation.duration_s": 0.03})
    a, ea, qa = _run(cfg, "sensor")
    b, eb, qb = _run(cfg, "posthoc")
    assert ea._accel is None and type(eb._accel).__name__ == "TreeAccelerometers"
    bound = 4 * EPS * max(qa, qb) / cfg.simulation.timestep_s * 2 * 10
    for k in names.ACCEL_SENSORS:
        assert np.max(np.abs(a[k] - b[k])) < bound, k
    assert all(np.array_equal(a[k], b[k]) for k in a if k not in names.ACCEL_SENSORS)


def test_a_dataset_spec_varies_every_structure_field():
    """Every [structure] placeholder is a named dataset factor with its documented range; the plan's
    configurations carry the drawn values (resolved, so each is a valid flexible configuration)."""
    from twin.config.structure import EXPLORE_RANGES
    from twin.dataset.design import plan
    from twin.dataset.factors import NAMED
    from twin.dataset.spec import parse_spec

    assert NAMED["structure"].choices == ("rigid", "flexible")
    factors = {"structure": ["flexible"]}
    for name, field, _doc, bounds in EXPLORE_RANGES:
        assert NAMED[name].bounds == bounds
        factors[name] = {"range": list(bounds)}
    spec = parse_spec({"dataset": {"name": "t", "seed": 3}, "base": {"test": 6, "duration_s": 0.05},
                       "factors": factors, "design": {"kind": "lhs", "runs": 8}})
    runs = plan(spec)
    assert len(runs) == 8
    for r in runs:
        st = r.config.structure
        assert st.mode == "flexible"
        for name, field, _doc, (lo, hi) in EXPLORE_RANGES:
            assert lo <= getattr(st, field) <= hi
    assert len({r.config.structure.frame_frequency_hz for r in runs}) == 8  # one stratum each


def test_export_mjcf_of_the_flexible_bench_loads_in_plain_mujoco(tmp_path):
    from twin.cli import main

    out = tmp_path / "flex.xml"
    assert main(["export-mjcf", "--test", "12", "--structure", "flexible", "--out", str(out)]) == 0
    m = mujoco.MjModel.from_xml_path(str(out))
    cfg = _flexible(12)
    chain = chain_of(cfg)
    for j, name in zip(chain.joints, joint_names(chain)):
        assert m.jnt_stiffness[m.joint(name).id] == pytest.approx(j.stiffness, rel=1e-9)
        assert m.dof_damping[m.jnt_dofadr[m.joint(name).id]] == pytest.approx(j.damping, rel=1e-9)
    assert m.body(names.FRAME_SUPPORT).id > 0 and m.body(names.GUIDE_SUPPORT).id > 0


@pytest.mark.parametrize("engine", ["mujoco", "reference"])
def test_simulate_test6_flexible_runs_in_both_engines(engine, tmp_path, capsys):
    from twin.cli import main
    from twin.mcapfile import read_run

    out = tmp_path / "t6.mcap"
    assert main(["simulate", "--test", "6", "--structure", "flexible", "--engine", engine, "--duration", "0.05",
                 "--out", str(out), "--no-progress"]) == 0
    assert "structure: flexible, rod modes" in capsys.readouterr().out
    run = read_run(out)
    assert run.config.structure.mode == "flexible"
    assert "rod_deflection" in run.channels   # --structure flexible adds the group, in both engines
    assert np.all(np.isfinite(run["AC4"]))


def _worst_band_db(test: int, overrides: dict, duration: float = 0.6, skip: float = 0.2) -> tuple[float, dict]:
    """The largest |10 log10(E_mujoco / E_reference)| over AC1-AC6 and the third-octave bands 100 Hz - 10 kHz
    (``duration`` s from rest, bands over t >= ``skip`` s; analysis/structure_agreement.py), and the worst per
    sensor."""
    import sys
    from pathlib import Path

    saved = list(sys.path)  # restored below: analysis/datasets would shadow Hugging Face's datasets
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "analysis"))
    try:
        from structure_agreement import agreement
    finally:
        sys.path[:] = saved

    per = agreement(test, duration, skip, overrides)
    worst = {k: round(max(abs(x) for x in v), 2) for k, v in per.items()}
    return max(worst.values()), worst


@pytest.mark.long
@pytest.mark.parametrize("test, timestep_s", [(6, None), (12, None), (12, 2.5e-6)])
def test_engines_agree_on_third_octave_band_energies(test, timestep_s):
    """The issue's engine agreement, where it holds: AC1-AC6 third-octave band energies, 100 Hz - 10 kHz, within
    1 dB between MuJoCo and the reference. Test 6 at the default step (measured 0.43 dB); test 12 at the default step
    (0.85 dB; 1.58 before the reference's friction followed the θ-method's normal force) and at 2.5e-6 s (0.21 dB
    before that change). Independent basis: the other engine. (Test 3 measures 0.74 dB at 2.5e-6 s but 1.33 at
    1.25e-6 s, MuJoCo's closure's round-off floor growing as the step is refined: not held as a test, see the xfail
    below.)"""
    worst, per = _worst_band_db(test, {} if timestep_s is None else {"simulation.timestep_s": timestep_s})
    assert worst <= 1.0, per


@pytest.mark.long
@pytest.mark.xfail(strict=True, reason=(
    "known gap (analysis/results/structure/agreement.md, docs/structure-mujoco.md): test 3's AC5 1.79 dB "
    "(1.87 with Newton) at 10 kHz (2.69 with the channels in float64), a band of ~1e-7 m/s^2 rms where MuJoCo's loop "
    "closure at the ideal C adds a numerical floor (round-off of its positions through the connect's stabilization, "
    "analysis/structure_closure_floor.py; the reference converges to 0.02 dB) and MuJoCo's step error on the guide "
    "friction's reversals"))
def test_engines_agree_on_third_octave_band_energies_at_the_default_step_test3():
    """The rest of the issue's agreement: test 3 at the default step, within 1 dB in every band."""
    worst, per = _worst_band_db(3, {})
    assert worst <= 1.0, per


@pytest.mark.long
@pytest.mark.parametrize("test, timestep_s", [(6, 2.5e-6), (12, 1.25e-6)])
def test_engines_agree_at_full_speed_where_both_steps_have_converged(test, timestep_s):
    """Full speed (1.1 s from rest, bands over t >= 0.6 s, after the drive's 0.5 s ramp): within 1 dB once both
    engines' steps have converged (measured: test 6 0.06 dB at 2.5e-6 s, 0.87 at the default step; test 12 0.03 dB at
    1.25e-6 s, 6.3-6.6 dB at 1e-5 ... 2.5e-6 s, where the first free flight at C after the ramp ends in a bounce in
    one engine and not in the other: a threshold that 0.05 % of the slider's mass moves in either engine, which
    their step errors cross; analysis/results/structure/fullspeed.md). Independent basis: the other engine."""
    worst, per = _worst_band_db(test, {"simulation.timestep_s": timestep_s}, duration=1.1, skip=0.6)
    assert worst <= 1.0, per


@pytest.mark.long
def test_structure_channels_mean_the_same_in_both_engines():
    """The "structure" group (rod_stretch, rod_deflection, frame_x, frame_y, guide_y [m]) in both engines on the same
    tap: test 12 started with the rod straight and unstretched and the supports unloaded, so gravity and the drive
    strike the structure at t = 0 and it rings (the rod's mid-span swings by ~18 µm, the frame sags by ~2.4 µm).
    Independent basis: the other engine's state (MuJoCo's site and joint sensors against the reference's natural
    coordinates). Measured: every channel within 0.5 % of its peak (rod_stretch 0.44 %, the others <= 0.2 %)."""
    import twin

    runs = {}
    for engine in ("mujoco", "reference"):
        cfg = preset(12).replace(**{"structure.mode": "flexible", "simulation.duration_s": 0.05,
                                    "simulation.engine": engine,
                                    "sensors.channels": ["accel", "crank", "slider", "joints", "structure"]})
        runs[engine] = twin.simulate(cfg)
    mj, ref = runs["mujoco"], runs["reference"]
    assert abs(ref["rod_stretch"][0]) < 1e-12 and abs(ref["rod_deflection"][0]) < 1e-12
    assert np.max(np.abs(ref["rod_deflection"])) > 5e-6 and np.max(np.abs(ref["frame_y"])) > 1e-6
    for name in ("rod_stretch", "rod_deflection", "frame_x", "frame_y", "guide_y"):
        a, b = np.asarray(mj[name]), np.asarray(ref[name])
        assert a.shape == b.shape
        assert np.max(np.abs(a - b)) <= 0.01 * np.max(np.abs(b)), name


@pytest.mark.long
def test_stability_scenes_with_the_structure_drawn_pass_in_both_engines():
    """Three scenes of the campaign with the structure drawn (short: 0.05-0.1 s), both engines: none diverges, none
    creates energy (the balance with the structural dampers' dissipation counted)."""
    from twin.studies.stability import StudySettings, run_study

    res = run_study(StudySettings(scenes=3, seed=5, duration_range_s=(0.05, 0.1), structure=True))
    assert res.summary["scenes"] == 6 and res.summary["diverged"] == 0
    assert res.summary["energy_created"] == 0, res.summary


def test_stability_campaign_draws_the_structure_without_changing_the_other_draws():
    from twin.config.structure import EXPLORE_RANGES
    from twin.studies.stability import StudySettings, sample_scene, scene_config

    for i in range(5):
        plain = sample_scene(7, i, (0.3, 1.0))
        flex = sample_scene(7, i, (0.3, 1.0), structure=True)
        assert {k: v for k, v in flex.items() if k != "structure"} == plain
        for _, field, _, (lo, hi) in EXPLORE_RANGES:
            assert lo <= flex["structure"][field] <= hi
        if flex["drive"]["program"] != "startstop":
            cfg = scene_config({**flex, "engine": "reference"})
            assert cfg.structure.flexible and cfg.simulation.engine == "reference"
    with pytest.raises(ConfigError, match="structure"):
        StudySettings(scenes=2, seed=1, bench=True, structure=True)


def _mujoco_tap(cfg, speed_mps: float, duration_s: float, every: int, theta0: float, axial: bool = False):
    """The reference's tap (twin.reference.flexible_tap.tap_response) in the MuJoCo twin: the mechanism at rest at
    ``theta0``, no drive torque (the PID's gains zeroed), the rod's middle node (axial: the bore C) struck by an
    impulse that gives it ``speed_mps`` normal to (along) the chord B'-C, the loop closure at C taking its share
    (the velocity change is M⁻¹ Jᵀ λ with J the node's and the closure's rows); returns (t, the node's distance
    from the chord) (axial: |C − B'| − L) every ``every`` steps."""
    eng = MujocoEngine(cfg)
    m, d = eng.model, eng.data
    m.actuator_gainprm[:] = 0.0
    m.actuator_biasprm[:] = 0.0
    eng.reset(theta0)
    n_seg = cfg.structure.rod_segments
    node = m.body(names.rod_segment(n_seg // 2 + 1)).id
    b_id, c_id = m.body(names.ROD).id, m.body(names.ROD_END_C).id
    u = d.xpos[c_id][:2] - d.xpos[b_id][:2]
    u /= np.linalg.norm(u)
    normal = np.array([-u[1], u[0]])
    target = c_id if axial else node
    direction = u if axial else normal
    jp = np.zeros((3, m.nv))
    mujoco.mj_jacBody(m, d, jp, None, target)
    rows = [direction @ jp[:2]]
    eq = m.equality(names.JOINT_C_CONNECT).id
    efc = d.efc_J.reshape(d.nefc, m.nv)
    rows += [efc[r] for r in range(d.nefc)
             if d.efc_type[r] == mujoco.mjtConstraint.mjCNSTR_EQUALITY and d.efc_id[r] == eq and np.any(efc[r])]
    J = np.array(rows)
    X = np.zeros((len(J), m.nv))
    mujoco.mj_solveM(m, d, X, np.ascontiguousarray(J))
    Minv_JT = X.T
    lam = np.linalg.solve(J @ Minv_JT, np.r_[speed_mps, np.zeros(len(J) - 1)])
    d.qvel[:] += Minv_JT @ lam
    steps = int(round(duration_s / (every * m.opt.timestep)))
    w = np.empty(steps)
    L = cfg.bodies.rod.length_m
    for i in range(steps):
        for _ in range(every):
            mujoco.mj_step(m, d)
        b, c, p = d.xpos[b_id][:2], d.xpos[c_id][:2], d.xpos[node][:2]
        ch = c - b
        w[i] = np.hypot(*ch) - L if axial else ((p - b) @ np.array([-ch[1], ch[0]])) / np.hypot(*ch)
    return (np.arange(steps) + 1) * every * m.opt.timestep, w


def _ringing_hz(t, w, f_lo, f_hi):
    """Frequency [Hz] of the ringing of w in [f_lo, f_hi] Hz: band-passed, mean period between the parabola-refined
    crests after the first 10 ms."""
    from scipy.signal import butter, sosfiltfilt

    fs = 1.0 / (t[1] - t[0])
    x = sosfiltfilt(butter(4, [f_lo, f_hi], "bandpass", fs=fs, output="sos"), w - w.mean())
    tc = []
    for i in range(1, x.size - 1):
        if x[i] > 0 and x[i] > x[i - 1] and x[i] >= x[i + 1]:
            a, b, c = x[i - 1], x[i], x[i + 1]
            tc.append(t[i] + 0.5 * (a - c) / (a - 2 * b + c) / fs)
    tc = np.array(tc)
    tc = tc[(tc > 0.01) & (tc < t[-1] - 0.01)]
    return 1.0 / np.mean(np.diff(tc))


@pytest.mark.parametrize("axial,band", [(False, (120.0, 300.0)), (True, (700.0, 1500.0))])
def test_engines_tap_ring_at_the_same_in_situ_mode(axial, band):
    """Modal agreement of the two engines in the mechanism as built (default supports and structure, crank free,
    no gravity): the same tap on the rod rings at the same first bending (axial: stretch) frequency within 1 %.
    Independent basis: the other engine (natural coordinates, R-matrix)."""
    from twin.reference.flexible_tap import tap_response

    cfg = _flexible(**{"mechanism.gravity_mps2": 0.0, "mechanism.guide_friction_n": 0.0})
    dur, every = (0.2, 5) if not axial else (0.05, 1)
    t_r, w_r = tap_response(cfg.replace(**{"simulation.engine": "reference"}), 0.01, dur, every, 0.3, axial=axial)
    t_m, w_m = _mujoco_tap(cfg, 0.01, dur, every, 0.3, axial=axial)
    f_r, f_m = _ringing_hz(t_r, w_r, *band), _ringing_hz(t_m, w_m, *band)
    assert f_m == pytest.approx(f_r, rel=0.01), (f_m, f_r)


def test_view_draws_the_rod_bent_by_its_deflection(tmp_path):
    """The rerun view of a flexible run: /bench/rod/bent is the centre line from B' (0, 0) to C (L + M·stretch, 0)
    with the mid-span point at M·rod_deflection of the pose's sample (M = ROD_DEFLECTION_MAGNIFICATION)."""
    from test_view import read_rrd
    from twin.viz.writer import ROD_DEFLECTION_MAGNIFICATION as M, ROD_LINE_POINTS

    from twin.mcapfile import read_run
    from twin.cli import main

    out, rrd = tmp_path / "f.mcap", tmp_path / "f.rrd"
    assert main(["simulate", "--test", "6", "--structure", "flexible", "--duration", "0.05", "--out", str(out),
                 "--rerun", str(rrd), "--no-progress"]) == 0
    run = read_run(out)
    ent = read_rrd(rrd)["/bench/rod/bent"]
    strips = ent["LineStrips3D:strips"]
    assert len(strips) > 10
    k = len(strips) // 2
    pts = np.array(strips[k][0])
    assert pts.shape == (ROD_LINE_POINTS, 3)
    i = int(round(ent["time"][k] * 1e-9 * run.rate_hz))
    L = run.config.bodies.rod.length_m
    assert pts[0, :2] == pytest.approx([0.0, 0.0], abs=1e-12)
    assert pts[-1, 0] == pytest.approx(L + M * run["rod_stretch"][i], rel=1e-6)
    assert pts[ROD_LINE_POINTS // 2, 1] == pytest.approx(M * run["rod_deflection"][i], rel=1e-5)


@pytest.mark.long
def test_prescribed_crank_torque_and_contact_forces_agree_between_engines():
    """Test 12 (B and C with clearance) with the prescribed crank, flexible, 0.3 s in both engines: the drive torque
    (the driving constraint's multiplier, with the reference's θ-method contact damping counted in it) and the
    contact forces at B and C agree (RMS of the difference over 0.1-0.3 s within 1 % of the RMS; measured 1e-4,
    0.6e-4 and 0.8e-4). Independent basis: the other engine."""
    import twin

    runs = {}
    for engine in ("mujoco", "reference"):
        cfg = preset(12).replace(**{"structure.mode": "flexible", "simulation.duration_s": 0.3,
                                    "simulation.engine": engine, "drive.mode": "prescribed",
                                    "sensors.channels": ["accel", "crank", "joints", "drive"]})
        runs[engine] = twin.simulate(cfg)
    i0 = int(0.1 * runs["reference"].rate_hz)
    for name in ("crank_torque", "fn_B", "fn_C"):
        a, b = np.asarray(runs["mujoco"][name])[i0:], np.asarray(runs["reference"][name])[i0:]
        assert np.sqrt(np.mean((a - b) ** 2)) <= 0.01 * np.sqrt(np.mean(b ** 2)), name
