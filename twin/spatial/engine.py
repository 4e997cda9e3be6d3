"""The spatial reference engine (``twin simulate --preset s002 --engine reference``): the model of
:mod:`twin.spatial.model` behind the chunk loop of :func:`twin.simulation.run_chunks`, with the bench's
configuration, channels and summary.

Channels (see :mod:`twin.channels`): ``crank_angle`` (θ from +y about +x, unwrapped) and
``crank_speed``; ``slider_position`` (along the guide from its point nearest the crank plane's origin)
and ``slider_acceleration`` (group ``slider_accel``); per clearance joint J ``ecc_J_x/y/z`` (pin minus
bushing centre in the spatial frame), ``pen_J``, ``fn_J`` and ``ft_J`` (magnitude of the friction
force); ``crank_torque`` (the drive's torque about +x).
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from twin import __version__ as twin_version
from twin.errors import ConfigError, SimulationError
from twin.tracefile import DriveInputs
from twin.spatial import geometry as spatial_geometry
from twin.spatial import model as SM

ENGINE_VERSION = "1"
JOINT_INDEX = {"A": 0, "B": 1, "C": 2}


@dataclass(frozen=True)
class SpatialOptions:
    """Numerical settings of the spatial reference (not part of the bench configuration).

    Attributes:
        newton_tol_m: the position projection stops when max |Δq| ≤ this [m].
        newton_max_iter: iterations before the step is declared failed.
        drive: False releases the crank (no driving constraint: the free motion of the energy check).
        projection: "mass" (mass-weighted, the default: the centres of mass stay where the step put
            them, as a free body's) or "partitioned" (the independent coordinates held, as the planar
            reference engine does: with it the spatial model laid in a plane is that engine's run to
            round-off). See :func:`twin.spatial.model._project`.
    """

    newton_tol_m: float = 1e-10
    newton_max_iter: int = 20
    drive: bool = True
    projection: str = "mass"

    def __post_init__(self) -> None:
        if self.projection not in ("mass", "partitioned"):
            raise ConfigError("reference.projection", f"must be mass or partitioned, got {self.projection!r}")
        if not (isinstance(self.newton_tol_m, (int, float)) and 0 < self.newton_tol_m <= 1e-6):
            raise ConfigError("reference.newton_tol_m", f"must lie in (0, 1e-6] m, got {self.newton_tol_m!r}")
        if isinstance(self.newton_max_iter, bool) or not isinstance(self.newton_max_iter, int) \
                or not 1 <= self.newton_max_iter <= 100:
            raise ConfigError("reference.newton_max_iter", f"must be an integer in [1, 100], got "
                                                           f"{self.newton_max_iter!r}")


def build(cfg: Any, options: SpatialOptions = SpatialOptions()) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """(P, jon, contacts): the model's parameter vector, the clearance flags (A, B, C) and the resolved
    contact constants per clearance joint."""
    from twin.contact_params import law_stiffness
    from twin.physics.contact import LAW_CODES

    con = cfg.contact
    if con.law == "linear":
        raise ConfigError("contact.law", "the linear law is not available for the spatial mechanism (its damping "
                                         "needs the planar model's effective mass); use a hysteresis law or "
                                         "adams-impact")
    if con.friction_law != "regularized-coulomb":
        raise ConfigError("contact.friction_law", "must be \"regularized-coulomb\" for the spatial mechanism, "
                                                  f"got {con.friction_law!r}")
    P = np.zeros(SM.N_P)
    P[SM.P_R], P[SM.P_L] = cfg.bodies.crank.length_m, cfg.bodies.rod.length_m
    p0, g = spatial_geometry.guide(cfg)
    e1 = np.array([0.0, 1.0, 0.0]) if cfg.spatial.guide_axis == "x" else np.array([0.0, 0.0, 1.0])
    e2 = np.cross(g, e1)
    P[SM.P_G:SM.P_G + 3], P[SM.P_P0:SM.P_P0 + 3] = g, p0
    P[SM.P_E1:SM.P_E1 + 3], P[SM.P_E2:SM.P_E2 + 3] = e1, e2
    P[SM.P_DRIVE] = 1.0 if options.drive else 0.0
    P[SM.P_GUIDE_F] = cfg.mechanism.guide_friction_n
    P[SM.P_V0], P[SM.P_V1] = con.v0_mps, con.v1_mps
    P[SM.P_TOL], P[SM.P_MAXIT] = options.newton_tol_m, options.newton_max_iter
    P[SM.P_H] = cfg.simulation.timestep_s
    P[SM.P_PROJ] = 1.0 if options.projection == "mass" else 0.0
    jon = np.zeros(3, dtype=np.int64)
    contacts: dict[str, Any] = {}
    for jt in cfg.joints.clearance_joints:
        i = JOINT_INDEX[jt]
        jon[i] = 1
        b = SM.P_JOINT + i * SM.J_SIZE
        K = law_stiffness(cfg, jt)
        P[b + SM.J_ON] = 1.0
        P[b + SM.J_C] = cfg.joints.radial_m(jt)
        P[b + SM.J_K] = K
        P[b + SM.J_N] = con.exponent
        P[b + SM.J_E] = con.restitution
        P[b + SM.J_LAW] = LAW_CODES[con.law]
        P[b + SM.J_CLIN] = con.impact_c_max_nspm
        P[b + SM.J_DMAX] = con.impact_d_max_m
        P[b + SM.J_R] = cfg.joints.pin_radius(jt)
        P[b + SM.J_MU] = con.mu0
        P[b + SM.J_FLOOR] = con.impact_speed_floor_mps
        contacts[jt] = {"law": con.law, "kind": "journal in bearing" if jt == "A" else "ball in socket",
                        "radial_clearance_m": cfg.joints.radial_m(jt), "stiffness": K, "exponent": con.exponent,
                        "pin_radius_m": cfg.joints.pin_radius(jt)}
    return P, jon, contacts


def initial_state(cfg: Any, theta0: float, omega0: float) -> np.ndarray:
    """State at crank angle θ0 [rad] turning at ω0 [rad/s], every clearance joint centred (S002 §2.1:
    "the journal's and bearing's initial centers were concentric, and the ball's and socket's")."""
    st = np.zeros(SM.N_STATE)
    st[SM.S_Q:SM.S_Q + spatial_geometry.NQ] = spatial_geometry.ideal_coordinates(cfg, theta0)
    st[SM.S_V:SM.S_V + spatial_geometry.NQ] = spatial_geometry.ideal_velocities(cfg, theta0, omega0)
    st[SM.S_THETA] = theta0
    return st


class SpatialReferenceEngine:
    """Spatial reference engine (module docstring); the chunk loop is :func:`twin.simulation.run_chunks`."""

    name = "reference"

    def __init__(self, cfg: Any, options: SpatialOptions | None = None, *, inputs: DriveInputs | None = None):
        self.cfg = cfg
        self.options = options or SpatialOptions()
        t0 = time.perf_counter()
        self.P, self.jon, contacts = build(cfg, self.options)
        self.M = spatial_geometry.mass_matrix(cfg)
        self.Minv = np.linalg.inv(self.M)
        self.Qg = spatial_geometry.gravity_forces(cfg)
        self.build_s = time.perf_counter() - t0
        self.load_s = warm_up()
        from twin.drive import DriveReference

        self._drive = DriveReference(cfg, inputs)
        self.meta: dict[str, Any] = {
            "engine": self.name,
            "engine_version": f"twin-spatial-reference {ENGINE_VERSION} (twin {twin_version})",
            "mechanism": "spatial slider-crank (S002)",
            "formulation": "3D natural coordinates (points), R-matrix from the null space of the constraint "
                           "Jacobian",
            "integrator": "symplectic Euler (S003 Eq. 21) with position/velocity projection",
            "timestep_s": cfg.simulation.timestep_s,
            "steps": 0, "wall_s": 0.0, "build_s": self.build_s, "compile_s": self.load_s,
            "options": asdict(self.options), "contact": contacts,
            "drive": "prescribed: (B - A) . n(theta_ref(t)) = 0" if self.options.drive else "free",
        }
        self._st: np.ndarray | None = None
        self._k = 0
        self._buf = np.empty((0, SM.N_OUT))

    def reset(self, theta0: float | None = None) -> None:
        """Mechanism at crank angle θ0 (None: the drive's initial angle) turning at the program's start
        rate (0 without the drive), every joint centred."""
        if theta0 is None:
            theta0 = float(self._drive(np.array([0.0]))[0][0])
        omega0 = self._drive.start_rate() if self.options.drive else 0.0
        self._st = initial_state(self.cfg, theta0, omega0)
        self._k = 0

    def advance(self, theta_ref: np.ndarray, omega_ref: np.ndarray, stride: int) -> dict[str, np.ndarray]:
        """Integrate ``len(theta_ref)`` steps on the drive's program (see
        :meth:`twin.simulation.Engine.advance`)."""
        if self._st is None:
            self.reset()
        h = self.cfg.simulation.timestep_s
        nstep = len(theta_ref)
        n_out = -(-nstep // stride)
        if self._buf.shape[0] < n_out:
            self._buf = np.empty((n_out, SM.N_OUT))
        t = (self._k + np.arange(nstep + 1)) * h
        th, om = self._drive(t)
        al = self._drive.acceleration(t[:-1])
        if self._k == 0 and self.options.drive:
            om = np.array(om, dtype=float)
            om[0] = self._drive.start_rate()  # the right-hand limit of a speed jump at t = 0
        status, steps = SM.run(self.P, self.jon, self.M, self.Minv, self.Qg, self._st,
                               np.ascontiguousarray(th, dtype=float),
                               np.ascontiguousarray(om, dtype=float), np.ascontiguousarray(al, dtype=float),
                               stride, self._buf)
        if status != SM.OK:
            why = "the position projection did not converge" if status == SM.NEWTON_FAILED \
                else "NaN or Inf in the state"
            raise SimulationError(f"{self.cfg.name}: spatial reference run failed at t = {(self._k + steps) * h:.6f} s "
                                  f"({why}); try a smaller timestep")
        self._k += nstep
        return self.channels(self._buf[:n_out])

    def channels(self, out: np.ndarray) -> dict[str, np.ndarray]:
        """The configured channel groups from the model's output rows."""
        groups = self.cfg.sensors.channels
        cols: dict[str, np.ndarray] = {}
        if "encoder" in groups or "crank" in groups:
            cols["crank_angle"] = out[:, SM.O_THETA]
        if "crank" in groups:
            cols["crank_speed"] = out[:, SM.O_OMEGA]
        if "slider" in groups:
            cols["slider_position"] = out[:, SM.O_SLIDER]
        if "slider_accel" in groups:
            cols["slider_acceleration"] = out[:, SM.O_SLIDER_ACC]
        if "joints" in groups:
            for jt in self.cfg.joints.clearance_joints:
                base = SM.O_JOINT + 6 * JOINT_INDEX[jt]
                for k, nm in enumerate((f"ecc_{jt}_x", f"ecc_{jt}_y", f"ecc_{jt}_z", f"pen_{jt}", f"fn_{jt}",
                                        f"ft_{jt}")):
                    cols[nm] = out[:, base + k]
        if "drive" in groups:
            cols["crank_torque"] = out[:, SM.O_TORQUE]
        return {k: np.array(v) for k, v in cols.items()}

    def raw(self) -> np.ndarray:
        """The model's output rows of the last chunk (energies included), for checks."""
        return self._buf


def run_raw(cfg: Any, options: SpatialOptions = SpatialOptions(), stride: int = 1) -> np.ndarray:
    """Whole run of ``cfg`` as the model's output rows (columns ``twin.spatial.model.O_*``), every
    ``stride``-th step: for checks and studies that need more than the channels (energies)."""
    eng = SpatialReferenceEngine(cfg, options)
    eng.reset()
    h = cfg.simulation.timestep_s
    n = int(round(cfg.duration_s / h))
    z = np.zeros(n)
    eng.advance(z, z, stride)
    return eng.raw()[: -(-n // stride)].copy()


_WARM = False


def warm_up() -> float:
    """Compile (first use) or load from numba's cache the stepping loop; returns seconds spent."""
    global _WARM
    if _WARM:
        return 0.0
    t0 = time.perf_counter()
    P = np.zeros(SM.N_P)
    P[SM.P_R], P[SM.P_L], P[SM.P_G], P[SM.P_E1 + 1], P[SM.P_E2 + 2] = 0.1, 0.35, 1.0, 1.0, 1.0
    P[SM.P_TOL], P[SM.P_MAXIT], P[SM.P_H] = 1e-10, 20, 1e-5
    st = np.zeros(SM.N_STATE)
    st[spatial_geometry.IBC + 1] = 0.1
    st[spatial_geometry.IBR + 1] = 0.1
    z = np.zeros(1)
    SM.run(P, np.zeros(3, dtype=np.int64), np.eye(spatial_geometry.NQ), np.eye(spatial_geometry.NQ), np.zeros(spatial_geometry.NQ), st, z, z, np.zeros(0), 1,
           np.empty((1, SM.N_OUT)))
    _WARM = True
    return time.perf_counter() - t0
