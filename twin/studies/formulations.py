"""The §4.1 study of S003: R-matrix versus penalty formulation on the ideal mechanism.

Setup (S003 §4.1): ideal joints, released at rest at θ = π/3, gravity 9.81 m/s² along −y,
no drive torque, no friction (joints and slider guide), 5 s, symplectic Euler at h = 1e-4 s;
the penalty formulation (Eq. 10) with several (α, ζ, ω), and both at h = 1e-3 s where the
paper reports the penalty run failing. Outputs crank angular velocity, mechanical energy and
‖Φ‖ over time (PNG), and a markdown table.

Besides the paper's quantities the study integrates the same mechanism in its one minimal
coordinate θ (Lagrange: J(θ) θ̈ + ½ J'(θ) θ̇² + V'(θ) = 0, closed-form slider–crank
kinematics, scipy DOP853 at rtol 1e-12) and reports each run's largest crank-speed error
against it: the energy alone does not show a formulation that is wrong but conservative.

Work–precision: the same free motion integrated by the R-matrix with
symplectic Euler and with the explicit midpoint rule (``ReferenceOptions.integrator``), by the
MuJoCo twin (its compiled model of the same mechanism: ideal joints, actuation disabled) with
Euler and RK4, and by Exudyn (generalized-α, its default spectral radius 0.9; three rigid 2-D
bodies, three revolute joints and the slider's guide; optional: skipped when ``exudyn`` is not
installed), each at several steps: µs per step, seconds per simulated second and the error of
θ(T) against the minimal-coordinate solution. A run is on the front when no other is at most as
costly per simulated second and at most as wrong, one of them strictly.

Entry point: :func:`run_study` (``twin study formulations --out DIR``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from twin.config import BenchConfig
from twin.errors import ConfigError
from twin.natural_coordinates import N_Q, P_H, S_Q, S_QD, initial_state
from twin.reference.model import N_OUT, OK, build_params, free_motion, run_steps
from twin.studies.penalty import PenaltyParams, penalty_run
from twin.provenance import figure_metadata, stamped, with_stamp_line
from twin.typed import Record
from twin.util import atomic_write_bytes, atomic_write_json, atomic_write_text

#: release angle of §4.1 [rad]
THETA0 = math.pi / 3
#: recording interval of the time histories [s]
SAMPLE_DT = 1e-3


@dataclass(frozen=True)
class Case:
    """One run of the study.

    Attributes:
        method: "R-matrix" or "penalty".
        timestep_s: integration step h [s].
        penalty: α, ζ, ω of a penalty run (None for the R-matrix).
    """

    method: str
    timestep_s: float
    penalty: PenaltyParams | None = None

    @property
    def label(self) -> str:
        name = "R-matrix" if self.penalty is None else self.penalty.label
        return f"{name}, h={self.timestep_s:g}"


#: the study's runs: R-matrix and penalty at the paper's step (α and ω each varied with the
#: other held), the R-matrix at the bench step 1e-5 s, then h = 1e-3 s
DEFAULT_CASES: tuple[Case, ...] = (
    Case("R-matrix", 1e-4),
    Case("penalty", 1e-4, PenaltyParams(1e9, 1.0, 10.0)),
    Case("penalty", 1e-4, PenaltyParams(1e9, 1.0, 100.0)),
    Case("penalty", 1e-4, PenaltyParams(1e9, 1.0, 1000.0)),
    Case("penalty", 1e-4, PenaltyParams(1e3, 1.0, 1000.0)),
    Case("penalty", 1e-4, PenaltyParams(1e5, 1.0, 10.0)),
    Case("penalty", 1e-4, PenaltyParams(1e11, 1.0, 1000.0)),
    Case("R-matrix", 1e-5),
    Case("R-matrix", 1e-3),
    Case("penalty", 1e-3, PenaltyParams(1e9, 1.0, 1000.0)),
    Case("penalty", 1e-3, PenaltyParams(1e9, 1.0, 100.0)),
    Case("penalty", 1e-3, PenaltyParams(1e9, 1.0, 10.0)),
)


@dataclass
class CaseResult:
    """Time histories and figures of one run (sampled every :data:`SAMPLE_DT`)."""

    case: Case
    t: np.ndarray
    omega: np.ndarray
    energy: np.ndarray
    phi: np.ndarray
    phid: np.ndarray
    diverged: bool
    steps: int
    wall_s: float
    extra: dict = field(default_factory=dict)

    @property
    def t_end(self) -> float:
        return float(self.t[-1]) if self.t.size else 0.0


def study_config(cfg: BenchConfig | None = None) -> BenchConfig:
    """The §4.1 mechanism: ``cfg``'s bodies and d_off with ideal joints, y up, g = 9.81 m/s²."""
    cfg = cfg or BenchConfig()
    return cfg.replace(**{"name": "formulations", "joints.clearance_a_mm": 0.0, "joints.clearance_b_mm": 0.0,
                          "joints.clearance_c_mm": 0.0,
                          "mechanism.orientation": "y", "mechanism.gravity_mps2": 9.81,
                          "mechanism.guide_friction_n": 0.0})


def _params(cfg: BenchConfig, h: float, integrator: str = "euler") -> np.ndarray:
    P = build_params(cfg, drive=False, guide_friction=False, joint_friction=False, integrator=integrator)
    P[P_H] = h
    return P


def run_case(cfg: BenchConfig, case: Case, duration_s: float = 5.0, theta0: float = THETA0) -> CaseResult:
    """Integrate one case (the compiled loops are warmed up before the clock starts)."""
    cfg = study_config(cfg)
    h = case.timestep_s
    nsteps = int(round(duration_s / h))
    every = max(1, int(round(SAMPLE_DT / h)))
    nsamp = nsteps // every + 2
    bufs = [np.zeros(nsamp) for _ in range(4)]
    P = _params(cfg, h)
    st = initial_state(cfg, theta0)
    _warm(P, st, case)
    if case.penalty is None:
        t0 = time.perf_counter()
        status, steps, m = free_motion(P, st, nsteps, every, *bufs)
        wall = time.perf_counter() - t0
        diverged = status != OK
    else:
        q, qd = st[S_Q:S_Q + N_Q].copy(), st[S_QD:S_QD + N_Q].copy()
        pp = case.penalty
        t0 = time.perf_counter()
        diverged, steps, m = penalty_run(P, q, qd, pp.alpha, pp.zeta, pp.omega, nsteps, every, *bufs)
        wall = time.perf_counter() - t0
    t = np.arange(m) * every * h
    return CaseResult(case, t, *(b[:m].copy() for b in bufs), bool(diverged), int(steps), wall)


def _warm(P: np.ndarray, st: np.ndarray, case: Case) -> None:
    z = [np.zeros(4) for _ in range(4)]
    if case.penalty is None:
        free_motion(P, st.copy(), 1, 1, *z)
    else:
        penalty_run(P, st[S_Q:S_Q + N_Q].copy(), st[S_QD:S_QD + N_Q].copy(), 1.0, 0.0, 0.0, 1, 1, *z)


# ------------------------------------------------------------ minimal coordinates
class MinimalModel:
    """The ideal slider–crank in its minimal coordinate θ (closed-form kinematics).

    J(θ) = I_A + m₂ |∂G₂/∂θ|² + I_G₂ (∂φ/∂θ)² + m₃ (∂x_s/∂θ)², V(θ) = −g·(m₁ G₁ + m₂ G₂) − m₃ g_x x_s.
    """

    def __init__(self, cfg: BenchConfig):
        b = cfg.bodies
        self.r, self.l, self.d = b.crank.length_m, b.rod.length_m, cfg.mechanism.d_off_m
        self.m1, self.xg1 = b.crank.mass_kg, b.crank.x_g_m
        self.ia = b.crank.inertia_kgm2 + self.m1 * self.xg1 ** 2
        self.m2, self.xg2, self.ig2 = b.rod.mass_kg, b.rod.x_g_m, b.rod.inertia_kgm2
        self.m3 = b.slider.mass_kg
        self.g = np.asarray(cfg.mechanism.gravity_vector[:2])

    def inertia(self, th: float) -> float:
        r, l, xg2 = self.r, self.l, self.xg2
        phi = math.asin((self.d - r * math.sin(th)) / l)
        dphi = -r * math.cos(th) / (l * math.cos(phi))
        dB = np.array([-r * math.sin(th), r * math.cos(th)])
        dG2 = dB + xg2 * dphi * np.array([-math.sin(phi), math.cos(phi)])
        dxs = dB[0] - l * dphi * math.sin(phi)
        return self.ia + self.m2 * dG2 @ dG2 + self.ig2 * dphi ** 2 + self.m3 * dxs ** 2

    def potential(self, th: float) -> float:
        r, l = self.r, self.l
        phi = math.asin((self.d - r * math.sin(th)) / l)
        B = np.array([r * math.cos(th), r * math.sin(th)])
        G2 = B + self.xg2 * np.array([math.cos(phi), math.sin(phi)])
        xs = B[0] + l * math.cos(phi)
        return -(self.g @ (self.m1 * self.xg1 / r * B + self.m2 * G2)) - self.m3 * self.g[0] * xs

    def rhs(self, _t: float, y: np.ndarray) -> list[float]:
        th, w = y
        e = 1e-6
        dJ = (self.inertia(th + e) - self.inertia(th - e)) / (2 * e)
        dV = (self.potential(th + e) - self.potential(th - e)) / (2 * e)
        return [w, -(0.5 * dJ * w * w + dV) / self.inertia(th)]

    def solve(self, theta0: float, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(θ, θ̇) at times ``t`` from rest at θ0 (DOP853, rtol 1e-12)."""
        from scipy.integrate import solve_ivp

        sol = solve_ivp(self.rhs, (0.0, float(t[-1])), [theta0, 0.0], method="DOP853", t_eval=t,
                        rtol=1e-12, atol=1e-12)
        return sol.y[0], sol.y[1]


# ---------------------------------------------------------------- work–precision
#: methods of the work–precision comparison and the steps each is run at [s]
WORK_PRECISION: dict[str, tuple[float, ...]] = {
    "R-matrix, symplectic Euler": (1e-3, 1e-4, 1e-5),
    "R-matrix, explicit midpoint": (2e-3, 1e-3, 5e-4, 1e-4, 1e-5),
    "MuJoCo twin, Euler": (1e-4, 1e-5),
    "MuJoCo twin, RK4": (1e-3, 5e-4, 1e-4, 1e-5),  # the configuration allows h <= 1e-3 s
    "Exudyn, generalized-α": (1e-3, 1e-4, 1e-5),
}


def _time_best(fn, repeats: int = 2) -> tuple[float, float]:
    """(θ at the end, wall seconds) of ``fn()``, best of ``repeats`` when a run takes under 1 s."""
    theta, wall = fn()
    for _ in range(repeats - 1):
        if wall >= 1.0:
            break
        theta, w = fn()
        wall = min(wall, w)
    return theta, wall


def _rmatrix_theta(cfg: BenchConfig, h: float, duration_s: float, integrator: str) -> tuple[float, float]:
    P = _params(cfg, h, integrator)
    st0 = initial_state(cfg, THETA0)
    n = int(round(duration_s / h))
    z = np.zeros(n)
    out = np.empty((1, N_OUT))
    run_steps(P, st0.copy(), z[:1], z[:1], 1, out, False)  # compiled or loaded before the clock

    def once():
        st = st0.copy()
        t0 = time.perf_counter()
        status, _ = run_steps(P, st, z, z, n, out, False)
        wall = time.perf_counter() - t0
        return (float(st[S_Q + 7]) if status == OK else float("nan")), wall

    return _time_best(once)


def _mujoco_theta(cfg: BenchConfig, h: float, duration_s: float, integrator: str) -> tuple[float, float]:
    import mujoco
    from mujoco import rollout

    from twin import names
    from twin.mujoco_engine.engine import MujocoEngine

    c = cfg.replace(**{"mujoco.integrator": integrator, "simulation.timestep_s": h,
                       "simulation.duration_s": duration_s, "sensors.channels": ["encoder"],
                       "sensors.output_rate_hz": min(1e5, 1.0 / h)})
    eng = MujocoEngine(c)
    m, d = eng.model, eng.data
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_ACTUATION  # no drive: free motion
    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty((1, mujoco.mj_stateSize(m, kind)))
    adr = m.jnt_qposadr[m.joint(names.CRANK_HINGE).id]
    n = int(round(duration_s / h))

    def once():
        eng.reset(THETA0)
        done = 0
        t0 = time.perf_counter()
        while done < n:  # no per-step output: the data object carries the state
            k = min(100_000, n - done)
            mujoco.mj_getState(m, d, state[0], kind)
            rollout.rollout(m, d, state, nstep=k)
            done += k
        wall = time.perf_counter() - t0
        th = float(d.qpos[adr])
        return (th if np.isfinite(d.qpos).all() else float("nan")), wall

    return _time_best(once)


def exudyn_available() -> bool:
    """Whether the optional Exudyn package can be imported."""
    import importlib.util

    return importlib.util.find_spec("exudyn") is not None


def _exudyn_theta(cfg: BenchConfig, h: float, duration_s: float) -> tuple[float, float]:
    """The §4.1 mechanism in Exudyn: crank and rod as rigid 2-D bodies (mass, inertia about the
    centre of mass), the slider a mass point held on the guide by a coordinate constraint,
    revolute joints at A, B and C, gravity on every body; generalized-α (Exudyn's default
    spectral radius 0.9; ρ∞ = 1 stopped on step-size reduction near the end of the run)."""
    import exudyn as exu
    from exudyn.itemInterface import (CoordinateConstraint, LoadMassProportional, MarkerBodyMass,
                                      MarkerBodyPosition, MarkerNodeCoordinate, NodePoint2D, NodePointGround,
                                      NodeRigidBody2D, ObjectGround, ObjectJointRevolute2D, ObjectMassPoint2D,
                                      ObjectRigidBody2D)

    b = cfg.bodies
    r, l, d_off = b.crank.length_m, b.rod.length_m, cfg.mechanism.d_off_m
    g = cfg.mechanism.gravity_vector
    th0 = THETA0
    phi = math.asin((d_off - r * math.sin(th0)) / l)
    B = np.array([r * math.cos(th0), r * math.sin(th0)])
    C = B + l * np.array([math.cos(phi), math.sin(phi)])
    xg1, xg2 = b.crank.x_g_m, b.rod.x_g_m
    G2 = B + xg2 * np.array([math.cos(phi), math.sin(phi)])
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground = mbs.AddObject(ObjectGround(referencePosition=[0, 0, 0]))
    nc = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[xg1 * math.cos(th0), xg1 * math.sin(th0), th0]))
    crank = mbs.AddObject(ObjectRigidBody2D(mass=b.crank.mass_kg, inertia=b.crank.inertia_kgm2, nodeNumber=nc))
    nr = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[G2[0], G2[1], phi]))
    rod = mbs.AddObject(ObjectRigidBody2D(mass=b.rod.mass_kg, inertia=b.rod.inertia_kgm2, nodeNumber=nr))
    ns = mbs.AddNode(NodePoint2D(referenceCoordinates=[C[0], d_off]))
    slider = mbs.AddObject(ObjectMassPoint2D(mass=b.slider.mass_kg, nodeNumber=ns))

    def pos(body, x):
        return mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[x, 0, 0]))

    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[pos(ground, 0.0), pos(crank, -xg1)]))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[pos(crank, r - xg1), pos(rod, -xg2)]))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[pos(rod, l - xg2), pos(slider, 0.0)]))
    ng = mbs.AddNode(NodePointGround(referenceCoordinates=[0, d_off, 0]))
    mbs.AddObject(CoordinateConstraint(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ng, coordinate=1)),
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ns, coordinate=1))]))
    for body in (crank, rod, slider):
        mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=body)),
                                         loadVector=[g[0], g[1], 0]))
    mbs.Assemble()
    st = exu.SimulationSettings()
    st.timeIntegration.numberOfSteps = int(round(duration_s / h))
    st.timeIntegration.endTime = duration_s
    st.timeIntegration.verboseMode = 0
    st.timeIntegration.generalizedAlpha.spectralRadius = 0.9
    st.solution.file.write = False
    st.linearSolver.solverType = exu.LinearSolverType.EXUdense
    t0 = time.perf_counter()
    try:
        exu.SolveDynamic(mbs, st)
    except Exception:  # noqa: BLE001 - a failed run is reported as such
        return float("nan"), time.perf_counter() - t0
    wall = time.perf_counter() - t0
    return float(np.ravel(mbs.GetNodeOutput(nc, exu.OutputVariableType.Rotation))[-1]), wall


def work_precision(cfg: BenchConfig, duration_s: float, theta_exact: float,
                   methods: dict[str, tuple[float, ...]] | None = None, progress=None) -> list[dict]:
    """Rows of the work–precision comparison (module docstring); ``progress`` is called with each
    finished row. Exudyn rows are left out when it is not installed."""
    cfg = study_config(cfg)
    methods = WORK_PRECISION if methods is None else methods
    rows = []
    for method, steps in methods.items():
        if method.startswith("Exudyn") and not exudyn_available():
            continue
        for h in steps:
            if method.startswith("R-matrix"):
                th, wall = _rmatrix_theta(cfg, h, duration_s, "euler" if "Euler" in method else "midpoint")
            elif method.startswith("MuJoCo"):
                th, wall = _mujoco_theta(cfg, h, duration_s, method.rsplit(", ", 1)[1])
            else:
                th, wall = _exudyn_theta(cfg, h, duration_s)
            n = int(round(duration_s / h))
            err = abs(th - theta_exact)
            rows.append({"method": method, "timestep_s": h, "steps": n, "wall_s": wall,
                         "us_per_step": wall / n * 1e6, "s_per_sim_s": wall / duration_s,
                         "theta_error_rad": err if math.isfinite(err) else None})
            if progress is not None:
                progress(rows[-1])
    for r in rows:
        e, c = r["theta_error_rad"], r["s_per_sim_s"]
        r["front"] = e is not None and not any(
            o is not r and o["theta_error_rad"] is not None and o["s_per_sim_s"] <= c and o["theta_error_rad"] <= e
            and (o["s_per_sim_s"] < c or o["theta_error_rad"] < e) for o in rows)
    return rows


def work_precision_markdown(rows: list[dict], duration_s: float, exudyn: bool) -> str:
    lines = [f"## Work–precision: θ({duration_s:g} s) against the exact solution", "",
             "Same release as above (no drive, no friction). Cost measured in this process, one run after another "
             "(best of 2 for runs under 1 s); it moves with the machine's load, the ratios less. Front: no other run "
             "is at most as costly per simulated second and at most as wrong.", "",
             "| method | h [s] | µs / step | s / simulated s | \\|θ − θ_exact\\| [rad] | front |",
             "|---|---:|---:|---:|---:|:-:|"]
    for r in rows:
        lines.append(f"| {r['method']} | {r['timestep_s']:g} | {r['us_per_step']:.2f} | {r['s_per_sim_s']:.4f} | "
                     f"{_fmt(r['theta_error_rad'], '.2e')} | {'P' if r['front'] else ''} |")
    if not exudyn:
        lines += ["", "Exudyn is not installed here: its rows are skipped (`pip install exudyn` adds them)."]
    return "\n".join(lines) + "\n"


def _work_precision_plot(rows: list[dict], out: Path) -> Path:
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    for method in dict.fromkeys(r["method"] for r in rows):
        sel = [r for r in rows if r["method"] == method and r["theta_error_rad"] is not None]
        if not sel:
            continue
        ax.loglog([r["s_per_sim_s"] for r in sel], [max(r["theta_error_rad"], 1e-16) for r in sel], "o-", label=method)
        for r in sel:
            ax.annotate(f"{r['timestep_s']:g}", (r["s_per_sim_s"], max(r["theta_error_rad"], 1e-16)), fontsize=7,
                        textcoords="offset points", xytext=(4, 3))
    front = sorted((r for r in rows if r["front"]), key=lambda r: r["s_per_sim_s"])
    if front:
        ax.loglog([r["s_per_sim_s"] for r in front], [r["theta_error_rad"] for r in front], "k:", lw=1, label="front")
    ax.set(xlabel="wall seconds per simulated second", ylabel="|θ(T) − θ_exact(T)| [rad]",
           title="S003 §4.1 free motion: work–precision (labels: h [s])")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, metadata=figure_metadata())
    plt.close(fig)
    return atomic_write_bytes(out / "work_precision.png", buf.getvalue())


# ------------------------------------------------------------------------- report
def _row(res: CaseResult, ref_t: np.ndarray, ref_w: np.ndarray, tmax: float) -> dict:
    de = res.energy - res.energy[0]
    n = min(res.t.size, ref_t.size)
    fin = np.isfinite(res.omega[:n])
    werr = float(np.max(np.abs(res.omega[:n][fin] - ref_w[:n][fin]))) if fin.any() else float("nan")
    return {
        "case": res.case.label,
        "method": res.case.method,
        "timestep_s": res.case.timestep_s,
        "alpha": res.case.penalty.alpha if res.case.penalty else None,
        "zeta": res.case.penalty.zeta if res.case.penalty else None,
        "omega": res.case.penalty.omega if res.case.penalty else None,
        "diverged": res.diverged,
        "t_end_s": res.t_end,
        "final_energy_error_J": float(de[-1]),
        "final_energy_error_rel": float(de[-1] / tmax),
        "max_abs_energy_error_J": float(np.nanmax(np.abs(de))),
        "max_phi": float(np.nanmax(res.phi)),
        "max_phi_dot": float(np.nanmax(res.phid)),
        "max_crank_speed_error_rad_s": werr,
        "wall_s": res.wall_s,
        "steps": res.steps,
    }


def _fmt(x: float, spec: str = ".3g") -> str:
    return "—" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, spec)


def markdown_table(rows: list[dict], duration_s: float, tmax: float) -> str:
    head = ("| run | h [s] | ΔE at end [mJ] | ΔE / T_max | max \\|ΔE\\| [mJ] | max ‖Φ‖ | max ‖Φ̇‖ "
            "| max \\|θ̇ − θ̇_exact\\| [rad/s] | diverged? | wall [s] |\n"
            "|---|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in rows:
        div = f"yes, at {r['t_end_s']:.3f} s" if r["diverged"] else "no"
        lines.append(f"| {r['case'].rsplit(', h=', 1)[0]} | {r['timestep_s']:g} | "
                     f"{_fmt(r['final_energy_error_J'] * 1e3)} | {_fmt(r['final_energy_error_rel'], '.2e')} | "
                     f"{_fmt(r['max_abs_energy_error_J'] * 1e3)} | {_fmt(r['max_phi'], '.2e')} | "
                     f"{_fmt(r['max_phi_dot'], '.2e')} | {_fmt(r['max_crank_speed_error_rad_s'])} | {div} | "
                     f"{r['wall_s']:.3f} |")
    return head + "\n".join(lines) + "\n"


def _notes(rows: list[dict]) -> str:
    by = {r["case"]: r for r in rows}
    notes = ["## Notes", ""]
    rm = by.get("R-matrix, h=0.0001")
    if rm:
        notes.append(f"- R-matrix: ‖Φ‖ stays at round-off (max {rm['max_phi']:.1e}, ‖Φ̇‖ max {rm['max_phi_dot']:.1e}) "
                     f"and the energy decreases slightly ({rm['final_energy_error_J'] * 1e3:.2f} mJ in "
                     f"{rm['t_end_s']:g} s), as S003 reports. The loss is the integrator's, not the projection's: "
                     "symplectic Euler applied to the reduced equation in (θ, θ̇) reproduces it to 8 digits "
                     "(tests/test_reference.py::test_rmatrix_equals_euler_on_minimal_ode). That equation has a "
                     "configuration-dependent inertia, so Euler in (θ, θ̇) is not a symplectic map and the energy "
                     "drifts at O(h) (it shrinks tenfold per decade of h: compare h = 1e-3, 1e-4, 1e-5 above).")
    pen = [r for r in rows if r["method"] == "penalty" and r["timestep_s"] == 1e-4 and not r["diverged"]]
    if pen:
        b = min(pen, key=lambda r: abs(r["max_crank_speed_error_rad_s"]))
        w = max(pen, key=lambda r: abs(r["max_crank_speed_error_rad_s"]))
        notes.append(f"- Penalty at h = 1e-4 s: results depend on α and ω, as in S003 Fig. 10–11: the crank-speed "
                     f"error ranges from {b['max_crank_speed_error_rad_s']:.3g} rad/s ({b['case'].split(',')[0]}) to "
                     f"{w['max_crank_speed_error_rad_s']:.3g} rad/s ({w['case'].split(',')[0]}); ω matters most, α "
                     "only once it is too small to dominate the mass matrix (α ≲ 1e5 here). ‖Φ‖ never goes below "
                     "~1e-7: the reactions need a violation.")
    p4 = by.get("P α=1e+09 ζ=1 ω=1000, h=0.0001")
    if rm and p4:
        notes.append(f"- Difference from S003's reading: with the exact minimal-coordinate solution as judge, the "
                     f"paper's best penalty setting (α = 1e9, ω = 1000) is *more* accurate at h = 1e-4 s than the "
                     f"R-matrix (max crank-speed error {p4['max_crank_speed_error_rad_s']:.2g} vs "
                     f"{rm['max_crank_speed_error_rad_s']:.2g} rad/s; energy error {p4['final_energy_error_J'] * 1e3:.2f} "
                     f"vs {rm['final_energy_error_J'] * 1e3:.2f} mJ, oscillating instead of drifting): integrating q with "
                     "the constant natural-coordinate mass matrix keeps symplectic Euler nearly symplectic when the "
                     "penalty is stiff. The R-matrix's advantages are the ones S003 names: exact constraints, no "
                     "parameters to tune (ω = 10 is worse by orders of magnitude), and stability at h = 1e-3 s.")
    p3 = by.get("P α=1e+09 ζ=1 ω=1000, h=0.001")
    if p3:
        notes.append("- h = 1e-3 s with α = 1e9, ω = 1000: " + (
            f"diverges (at t = {p3['t_end_s']:.3f} s), as S003 reports. Why: for large α the constraint error "
            "obeys Φ̈ + 2ζωΦ̇ + ω²Φ ≈ 0, and symplectic Euler is stable on that oscillator only for "
            "ω h < 2(√2 − 1) ≈ 0.83 (ζ = 1); here ω h = 1. Smaller ω runs, but with a large error."
            if p3["diverged"] else "did NOT diverge here, unlike S003."))
    notes.append("- ΔE / T_max: energy error relative to the largest kinetic energy of the exact motion "
                 "(a datum-free scale). θ̇_exact: the minimal-coordinate solution (module docstring of "
                 "twin/studies/formulations.py).")
    notes.append("- S003 plots but does not tabulate, and does not list all its (α, ω) pairs: the settings here are "
                 "our choice. Both formulations use the crank angle equation x_B sin θ − y_B cos θ = 0 (never "
                 "singular, twin/reference/model.py and twin/natural_coordinates.py); S003 does not print its exact form.")
    return "\n".join(notes) + "\n"


def _plots(results: list[CaseResult], ref_t: np.ndarray, ref_w: np.ndarray, out: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import io

    import matplotlib.pyplot as plt

    def save(fig, name: str) -> Path:
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=110, metadata=figure_metadata())
        plt.close(fig)
        return atomic_write_bytes(out / name, buf.getvalue())

    paths = []
    for h, tag in ((1e-4, "h1e-4"), (1e-3, "h1e-3")):  # h = 1e-5 appears in the table only
        sel = [r for r in results if r.case.timestep_s == h]
        if not sel:
            continue
        fig, axes = plt.subplots(2, 2, figsize=(13, 8))
        ax = axes[0, 0]
        ax.plot(ref_t, ref_w, "k-", lw=2.5, alpha=0.35, label="exact (minimal coordinates)")
        for r in sel:
            ax.plot(r.t, r.omega, lw=1, label=r.case.label + (" (diverged)" if r.diverged else ""))
        ax.set(xlabel="t [s]", ylabel="crank angular velocity [rad/s]", title=f"(a) crank speed, h = {h:g} s")
        ax.legend(fontsize=7)
        lim = max(abs(ref_w).max() * 1.3, 1.0)
        ax.set_ylim(-lim, lim)
        ax = axes[0, 1]
        t1 = ref_t[-1]
        m = ref_t >= t1 - 0.5
        ax.plot(ref_t[m], ref_w[m], "k-", lw=2.5, alpha=0.35, label="exact")
        for r in sel:
            mm = r.t >= t1 - 0.5
            ax.plot(r.t[mm], r.omega[mm], lw=1, label=r.case.label)
        ax.set(xlabel="t [s]", ylabel="crank angular velocity [rad/s]", title="(b) last 0.5 s")
        ax.set_ylim(-lim, lim)
        ax = axes[1, 0]
        for r in sel:
            ax.plot(r.t, (r.energy - r.energy[0]) * 1e3, lw=1, label=r.case.label)
        ax.set(xlabel="t [s]", ylabel="E(t) − E(0) [mJ]", title="(c) mechanical energy")
        ax.set_yscale("symlog", linthresh=1e-2)
        ax.legend(fontsize=7)
        ax = axes[1, 1]
        for r in sel:
            ax.semilogy(r.t, np.maximum(r.phi, 1e-18), lw=1, label=r.case.label)
        ax.set(xlabel="t [s]", ylabel="‖Φ‖", title="(d) constraint violation (floor 1e-18)")
        ax.legend(fontsize=7)
        fig.suptitle("S003 §4.1: ideal slider–crank released at θ = π/3 under gravity, no drive, no friction")
        fig.tight_layout()
        paths.append(save(fig, f"formulations_{tag}.png"))
    return paths


@dataclass(frozen=True)
class FormulationsOptions:
    """What the study runs.

    Attributes:
        out: output folder (created if needed).
        config: configuration of the bodies and d_off (:func:`study_config` makes the joints ideal,
            y up); None = the bench's.
        duration_s: simulated time [s], in (0, 60] (the penalty cases at h = 1e-4 s take about a
            second of wall time per simulated second).
        cases: the formulation cases compared.
        work_precision_methods: method -> timesteps of the work–precision comparison; None =
            :data:`WORK_PRECISION`, ``{}`` = none.
        progress: a progress bar on stderr.
    """

    out: str | Path
    config: BenchConfig | None = None
    duration_s: float = 5.0
    cases: tuple[Case, ...] = DEFAULT_CASES
    work_precision_methods: dict[str, tuple[float, ...]] | None = None
    progress: bool = False

    def __post_init__(self) -> None:
        d = self.duration_s
        if isinstance(d, bool) or not isinstance(d, (int, float)) or not (math.isfinite(d) and 0 < d <= 60):
            raise ConfigError("duration_s", f"must lie in (0, 60] s, got {d!r}")


@dataclass(frozen=True)
class CaseRow(Record):
    """One case of the study (a row of ``formulations.json``'s ``rows``).

    Attributes:
        case: its label; method: "R-matrix" or "penalty"; timestep_s: the step [s].
        alpha, zeta, omega: the penalty's parameters (None for the R-matrix).
        diverged: whether the run diverged; t_end_s: where it stopped [s].
        final_energy_error_J, final_energy_error_rel: the energy error at the end [J] and over T_max [-];
            max_abs_energy_error_J: its largest magnitude [J].
        max_phi, max_phi_dot: the largest constraint violation [m] and its rate [m/s].
        max_crank_speed_error_rad_s: the largest crank speed error against the exact motion [rad/s].
        wall_s: wall time [s]; steps: steps taken.
    """

    case: str
    method: str
    timestep_s: float
    alpha: float | None
    zeta: float | None
    omega: float | None
    diverged: bool
    t_end_s: float
    final_energy_error_J: float
    final_energy_error_rel: float
    max_abs_energy_error_J: float
    max_phi: float
    max_phi_dot: float
    max_crank_speed_error_rad_s: float
    wall_s: float
    steps: int


@dataclass(frozen=True)
class WorkPrecisionRow(Record):
    """One method and step of the work–precision comparison (a row of ``work_precision``).

    Attributes:
        method: the integrator; timestep_s: its step [s]; steps: steps over the run.
        wall_s: wall time [s]; us_per_step: per step [µs]; s_per_sim_s: per simulated second [s].
        theta_error_rad: |θ(T) − θ_exact(T)| [rad] (None: the run failed).
        front: on the Pareto front of cost and error.
    """

    method: str
    timestep_s: float
    steps: int
    wall_s: float
    us_per_step: float
    s_per_sim_s: float
    theta_error_rad: float | None
    front: bool


@dataclass(frozen=True)
class FormulationsResult:
    """What the study found (``formulations.json``): per case a row of energy error, constraint
    violation and wall time (:class:`CaseRow`); the exact solution's end angle; the work–precision rows
    (:class:`WorkPrecisionRow`). Rows given as dicts are read into those."""

    duration_s: float
    theta0_rad: float
    t_max_J: float
    rows: tuple[CaseRow, ...]
    theta_exact_end_rad: float
    work_precision: tuple[WorkPrecisionRow, ...]
    exudyn: bool
    figures: tuple[str, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "rows", tuple(r if isinstance(r, CaseRow) else CaseRow.from_dict(r)
                                               for r in self.rows))
        object.__setattr__(self, "work_precision", tuple(r if isinstance(r, WorkPrecisionRow) else
                                                         WorkPrecisionRow.from_dict(r) for r in self.work_precision))

    def to_dict(self) -> dict[str, Any]:
        """The JSON data of ``formulations.json``."""
        return {"duration_s": self.duration_s, "theta0_rad": self.theta0_rad, "t_max_J": self.t_max_J,
                "rows": [r.to_dict() for r in self.rows], "theta_exact_end_rad": self.theta_exact_end_rad,
                "work_precision": [r.to_dict() for r in self.work_precision], "exudyn": self.exudyn,
                "figures": list(self.figures)}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "FormulationsResult":
        """The result of ``formulations.json``'s data (its provenance stamp ignored)."""
        return cls(d["duration_s"], d["theta0_rad"], d["t_max_J"], d["rows"], d["theta_exact_end_rad"],
                   d["work_precision"], d["exudyn"], tuple(d["figures"]))


def run_study(options: FormulationsOptions) -> FormulationsResult:
    """Run every case and the work–precision comparison, write ``formulations.md``,
    ``formulations.json`` and PNG plots into ``options.out``."""
    out = Path(options.out)
    out.mkdir(parents=True, exist_ok=True)
    cfg = study_config(options.config)
    duration_s, cases, progress = options.duration_s, options.cases, options.progress
    work_precision_methods = options.work_precision_methods
    results = []
    it = cases
    if progress:
        from tqdm import tqdm

        it = tqdm(cases, desc="formulations", unit="run", leave=False)
    for case in it:
        results.append(run_case(cfg, case, duration_s))
    mm = MinimalModel(cfg)
    ref_t = np.arange(int(round(duration_s / SAMPLE_DT)) + 1) * SAMPLE_DT
    th, ref_w = mm.solve(THETA0, ref_t)
    e0 = mm.potential(THETA0)
    tmax = float(max(e0 - mm.potential(x) for x in th))
    rows = [_row(r, ref_t, ref_w, tmax) for r in results]
    table = markdown_table(rows, duration_s, tmax)
    pngs = _plots(results, ref_t, ref_w, out)
    wp = work_precision(cfg, duration_s, float(th[-1]), work_precision_methods)
    exudyn = exudyn_available()
    if wp:
        pngs.append(_work_precision_plot(wp, out))
    text = ("# S003 §4.1: R-matrix versus penalty formulation\n\n"
            f"Ideal mechanism released at rest at θ = π/3, gravity 9.81 m/s² along −y, {duration_s:g} s, symplectic "
            "Euler, no drive torque, no friction. Bodies: S003 Table 1. "
            f"T_max = {tmax * 1e3:.1f} mJ (largest kinetic energy of the exact motion).\n\n"
            + table + "\n" + _notes(rows) + "\n"
            + (work_precision_markdown(wp, duration_s, exudyn) + "\n" if wp else "")
            + "Figures: " + ", ".join(p.name for p in pngs) + "\n")
    atomic_write_text(out / "formulations.md", with_stamp_line(text))
    res = FormulationsResult(duration_s, THETA0, tmax, rows, float(th[-1]), wp, exudyn, tuple(p.name for p in pngs))
    atomic_write_json(out / "formulations.json", stamped(res.to_dict()))
    return res
