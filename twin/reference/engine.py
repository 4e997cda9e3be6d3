"""The reference engine: R-matrix natural-coordinate model of S003 with contact and friction.

``twin simulate --engine reference`` runs this instead of MuJoCo, with the same
configuration, drive, channels, chunking and metadata (:class:`twin.simulation.Engine`), so
the two engines compare channel by channel. The formulation is in
:mod:`twin.natural_coordinates` (coordinates, constraints, mass matrix) and
:mod:`twin.reference.model` (forces, equations of motion, integration), the contact laws in
:mod:`twin.physics.contact` with their constants from :mod:`twin.contact_params`.

Clearance joints: any of A (the crank journal in the frame's bore; its eccentricity channels in
the bench frame), B and C (rod frame), each with its own pin and bushing radii.

Each chunk of ``simulation.chunk_s`` is one call of the compiled loop
(:func:`twin.reference.model.run_steps`); the state (coordinates, velocities, PID integral,
contact events with their stored impact speeds) carries over between chunks, so chunking does
not change the result. Sample k of a run is the state at t_k = k h before step k, with the
accelerations of that step (as MuJoCo's sensordata).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from twin import __version__ as twin_version
from twin.channels import GUIDE_CHANNELS
from twin.config import ACCELEROMETERS, BenchConfig
from twin.errors import ConfigError, SimulationError
from twin.natural_coordinates import initial_state
from twin.reference import model as ref_model
from twin.tracefile import DriveInputs

ENGINE_VERSION = "1"
#: the flexible rod's formulations (:attr:`ReferenceOptions.rod_model`)
ROD_MODELS = ("chain", "modal")


@dataclass(frozen=True)
class ReferenceOptions:
    """Numerical settings of the reference engine (not part of the bench configuration).

    The floor of the stored impact speed is part of the contact law and lives in the bench
    configuration (``contact.impact_speed_floor_mps``), shared with the MuJoCo twin.

    Attributes:
        newton_tol_m: the position projection stops when max |Δq| ≤ this [m]; Newton's quadratic
            convergence then leaves ‖Φ‖ ≈ |Δq|², below round-off.
        newton_max_iter: iterations before the step is declared failed.
        integrator: "euler" (symplectic Euler, S003 Eq. 21: the default) or "midpoint" (explicit
            midpoint, second order for smooth motion, two evaluations per step; opt-in, chosen by
            the work–precision comparison of ``twin study formulations``). Scenes with a clearance
            joint refuse "midpoint": through hard impacts at h = 1e-5 s it is not stable (a 12.5 ms
            spin-up of test 12: AC1 RMS 9242 m/s² against 113 m/s² converged, Euler 234).
        rod_model: the flexible rod (``structure.mode = "flexible"``): "chain" (the MuJoCo engine's chain of
            rigid segments, :mod:`twin.reference.flexible`) or "modal" (its chord and three sine shapes with a
            constant mass matrix, :mod:`twin.reference.flexible_modal`: the same modes, far fewer coordinates and
            rows; the housings' rotary inertia must be 0). Unused with a rigid structure.
    """

    newton_tol_m: float = 1e-10
    newton_max_iter: int = 20
    integrator: str = "euler"
    rod_model: str = "chain"

    def __post_init__(self) -> None:
        t = self.newton_tol_m
        if not (isinstance(t, (int, float)) and math.isfinite(t) and 0 < t <= 1e-6):
            raise ConfigError("reference.newton_tol_m", f"must lie in (0, 1e-6] m, got {t!r}")
        n = self.newton_max_iter
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= 100:
            raise ConfigError("reference.newton_max_iter", f"must be an integer in [1, 100], got {n!r}")
        if self.integrator not in ref_model.INTEGRATORS:
            raise ConfigError("reference.integrator", f"must be one of {', '.join(ref_model.INTEGRATORS)}, "
                                                      f"got {self.integrator!r}")
        if self.rod_model not in ROD_MODELS:
            raise ConfigError("reference.rod_model", f"must be one of {', '.join(ROD_MODELS)}, got {self.rod_model!r}")


def engine_params(cfg: BenchConfig, options: ReferenceOptions = ReferenceOptions(), **switches: bool
                  ) -> np.ndarray:
    """Parameter vector of a configuration (contact stiffness still unresolved: see
    :func:`twin.reference.model.contact_parameters`); ``switches`` are the ``drive``,
    ``guide_friction``, ``joint_friction`` flags of :func:`twin.reference.model.build_params`."""
    return ref_model.build_params(cfg, min_impact_speed_mps=cfg.contact.impact_speed_floor_mps,
                          newton_tol_m=options.newton_tol_m, newton_max_iter=options.newton_max_iter,
                          integrator=options.integrator, **switches)


class ReferenceEngine:
    """R-matrix reference engine (see module docstring); the chunk loop is
    :func:`twin.simulation.run_chunks`."""

    name = "reference"

    def __init__(self, cfg: BenchConfig, options: ReferenceOptions | None = None, *, inputs: DriveInputs | None = None):
        self.cfg = cfg
        self.inputs = inputs
        self.options = options or ReferenceOptions()
        if self.options.integrator == "midpoint" and cfg.drive.mode == "prescribed":
            raise ConfigError("reference.integrator",
                              "the explicit midpoint integrator is not available with drive.mode = \"prescribed\" "
                              "(use \"euler\")")
        if self.options.integrator == "midpoint" and cfg.drive.mode in ("motor", "torque"):
            raise ConfigError("reference.integrator",
                              f"the explicit midpoint integrator is not available with drive.mode = {cfg.drive.mode!r} "
                              "(use \"euler\")")
        if self.options.integrator == "midpoint" and (cfg.joints.clearance_joints or cfg.joints.guide_play):
            raise ConfigError("reference.integrator",
                              "the explicit midpoint integrator is for scenes without clearance joints or guide "
                              "clearance: it is not stable through hard impacts at the bench's steps (use \"euler\")")
        t0 = time.perf_counter()
        self.P = engine_params(cfg, self.options)
        self._flex = None
        if cfg.structure.flexible:
            self._flex = _flexible_run(cfg, self.P, self.options)
        self.build_s = time.perf_counter() - t0
        self.load_s = warm_up() + (warm_up_prescribed() if cfg.drive.mode == "prescribed" else 0.0)
        self.meta: dict[str, Any] = {
            "engine": self.name,
            "engine_version": f"twin-reference {ENGINE_VERSION} (twin {twin_version}, numba {_numba_version()})",
            "formulation": "natural coordinates, R-matrix (S003 Eq. 11-16)",
            "integrator": ("symplectic Euler (S003 Eq. 21)" if self.options.integrator == "euler" else
                           "explicit midpoint (second order)") + " with position/velocity projection",
            "timestep_s": cfg.simulation.timestep_s,
            "steps": 0,
            "wall_s": 0.0,
            "build_s": self.build_s,
            "compile_s": self.load_s,
            "options": {k: v for k, v in asdict(self.options).items()   # the rod's model only where there is one
                        if k != "rod_model" or cfg.structure.flexible},
        }
        self.state0: np.ndarray | None = None
        self.contacts: dict[str, Any] = {}
        self._st: np.ndarray | None = None
        self._buf = np.empty((0, ref_model.N_OUT))
        self._k = 0
        self._drive = None
        self._train = None
        if cfg.drive.mode in ("motor", "torque"):
            from twin.reference.drivetrain_run import ReferenceTrain

            self._train = ReferenceTrain(cfg, inputs)
            self.load_s += self._train.warm_up()
            self.meta["drive"] = self._train.describe()
        if cfg.drive.mode == "prescribed":
            from twin.drive import DriveReference

            self._drive = DriveReference(cfg, inputs)
            self.meta["drive"] = "prescribed: the crank angle is a driving constraint theta = theta_ref(t)"

    def reset(self, theta0: float | None = None) -> None:
        """Mechanism at crank bench angle ``theta0`` [rad] (None: the drive program's initial
        angle), eccentricities as configured, at rest (or, with a prescribed drive, turning at the
        program's start rate, :meth:`twin.drive.DriveReference.start_rate`); resolves the contact
        parameters (the linear law's damping uses the effective mass at this pose)."""
        if theta0 is None:
            from twin.drive import DriveReference

            theta0 = float(DriveReference(self.cfg, self.inputs)(np.array([0.0]))[0][0])
        omega0 = self._drive.start_rate() if self._drive is not None else 0.0
        try:
            self.state0 = initial_state(self.cfg, theta0, omega0, self.P)
        except ValueError as err:
            raise ConfigError("bodies", str(err)) from None
        self.contacts = ref_model.contact_parameters(self.cfg, self.P, self.state0)
        self.meta["contact"] = {j: {"law": self.cfg.contact.law, **asdict(c)} for j, c in self.contacts.items()}
        self._st = self.state0.copy()
        self._k = 0
        if self._flex is not None:
            self._flex.reset(self.state0)
        if self._train is not None:
            self._train.reset()

    def snapshot(self) -> tuple[int, dict[str, np.ndarray]]:
        """The run's whole state: (integration steps since reset, arrays): the state vector ``st``
        (coordinates, velocities, PID integral, contact events with their stored impact speeds,
        guide state), the parameter vector ``P`` as resolved at reset (a check on restore) and,
        with a drive train, its state ``train_ds`` and parameters ``train_D``."""
        if self._st is None:
            self.reset()
        arrays = {"st": self._st.copy(), "P": self.P.copy()}
        if self._train is not None:
            arrays["train_ds"] = self._train.ds.copy()
            arrays["train_D"] = self._train.D.copy()
        return self._k, arrays

    def restore(self, snap: tuple[int, dict[str, np.ndarray]]) -> None:
        """Continue from :meth:`snapshot` of an engine of the same configuration (this one or
        another): reset (which resolves the contact parameters as the snapshot's engine did), then
        the state; a snapshot of another configuration (other parameters or layout) is refused."""
        k, arrays = snap
        self.reset()
        want = {"st": self._st, "P": self.P}
        if self._train is not None:
            want.update(train_ds=self._train.ds, train_D=self._train.D)
        if set(arrays) != set(want):
            raise ValueError(f"{self.cfg.name}: the snapshot holds {sorted(arrays)}, this engine needs {sorted(want)}")
        for name, mine in want.items():
            a = np.asarray(arrays[name], dtype=np.float64)
            if a.shape != mine.shape:
                raise ValueError(f"{self.cfg.name}: the snapshot's {name} has shape {a.shape}, expected {mine.shape}")
            if name in ("P", "train_D") and a.tobytes() != mine.tobytes():
                raise ValueError(f"{self.cfg.name}: the snapshot is of another configuration (its {name} differs)")
        self._st[:] = arrays["st"]
        if self._train is not None:
            self._train.ds[:] = arrays["train_ds"]
        self._k = int(k)

    def advance(self, theta_ref: np.ndarray, omega_ref: np.ndarray, stride: int) -> dict[str, np.ndarray]:
        """One call of the compiled loop over ``len(theta_ref)`` steps (see
        :meth:`twin.simulation.Engine.advance`)."""
        if self._st is None:
            self.reset()
        h = self.cfg.simulation.timestep_s
        nstep = len(theta_ref)
        n_out = -(-nstep // stride)
        if self._buf.shape[0] < n_out:
            self._buf = np.empty((n_out, ref_model.N_OUT))
        if self._flex is not None:
            from twin.reference.flexible import N_OUT_FLEX

            if self._buf.shape[0] < n_out or self._buf.shape[1] != N_OUT_FLEX:
                self._buf = np.empty((n_out, N_OUT_FLEX))
            if self._drive is not None:   # the prescribed crank: the program at t_k .. t_{k+n} and its acceleration
                t = (self._k + np.arange(nstep + 1)) * h
                th, om = self._drive(t)
                status, steps = self._flex.run(self._st, np.ascontiguousarray(th), np.ascontiguousarray(om), stride,
                                               self._buf[:n_out], None, self._k,
                                               np.ascontiguousarray(self._drive.acceleration(t[:-1])))
            else:
                status, steps = self._flex.run(self._st, np.ascontiguousarray(theta_ref, dtype=np.float64),
                                               np.ascontiguousarray(omega_ref, dtype=np.float64), stride,
                                               self._buf[:n_out], self._train, self._k)
        elif self._train is not None:
            status, steps = self._train.run(self.P, self._st, self._k, omega_ref, stride, self._buf, n_out)
        elif self._drive is not None:
            # the program at t_k .. t_{k+n} (the driving constraint's next value) and its acceleration
            t = (self._k + np.arange(nstep + 1)) * h
            th, om = self._drive(t)
            al = self._drive.acceleration(t[:-1])
            status, steps = ref_model.run_prescribed(self.P, self._st, np.ascontiguousarray(th), np.ascontiguousarray(om),
                                             np.ascontiguousarray(al), stride, self._buf, True)
        else:
            status, steps = ref_model.run_steps(self.P, self._st, np.ascontiguousarray(theta_ref, dtype=np.float64),
                                        np.ascontiguousarray(omega_ref, dtype=np.float64), stride, self._buf, True)
        if status != ref_model.OK:
            why = "the position projection did not converge" if status == ref_model.NEWTON_FAILED \
                else "NaN or Inf in the state"
            c = self.cfg
            raise SimulationError(f"{c.name}: reference run failed at t = {(self._k + steps) * h:.6f} s ({why}); "
                                  f"likely responsible: simulation.timestep_s ({h:g} s), contact.stiffness, "
                                  f"joints.clearance_*_mm (B {c.joints.clearance_b_mm:g}, C {c.joints.clearance_c_mm:g} "
                                  "mm), bodies.*.mass_kg and inertia_kgm2; try a smaller timestep")
        self._k += nstep
        return self._channels(self._buf[:n_out])

    def _channels(self, out: np.ndarray) -> dict[str, np.ndarray]:
        cfg = self.cfg
        cols: dict[str, np.ndarray] = {}
        groups = cfg.sensors.channels
        if "accel" in groups:
            for i, a in enumerate(ACCELEROMETERS):
                cols[a] = out[:, ref_model.O_ACC + i]
        if "encoder" in groups or "crank" in groups:
            cols["crank_angle"] = out[:, ref_model.O_THETA]
        if "crank" in groups:
            cols["crank_speed"] = out[:, ref_model.O_OMEGA]
        if "slider" in groups:
            cols["slider_position"] = out[:, ref_model.O_SLIDER]
        if "joints" in groups:
            for jt in cfg.joints.clearance_joints:
                base = {"A": ref_model.O_JOINT_A, "B": ref_model.O_JOINT_B, "C": ref_model.O_JOINT_C}[jt]  # A: bench frame
                for k, name in enumerate((f"ecc_{jt}_x", f"ecc_{jt}_y", f"pen_{jt}", f"fn_{jt}", f"ft_{jt}")):
                    cols[name] = out[:, base + k]
            if cfg.joints.guide_play:
                for k, (name, *_) in enumerate(GUIDE_CHANNELS):
                    cols[name] = out[:, ref_model.O_GUIDE + k]
        if "energy" in groups:
            cols["energy_kinetic"] = out[:, ref_model.O_EKIN]
            cols["energy_potential"] = out[:, ref_model.O_EPOT]
            cols["slider_speed"] = out[:, ref_model.O_VSLIDER]
        if "drive" in groups:
            cols["crank_torque"] = out[:, ref_model.O_TORQUE]
        if self._train is not None:
            cols.update(self._train.channels(out.shape[0]))
        if self._flex is not None and "structure" in groups:
            from twin.reference.flexible import O_STRUCT, STRUCTURE_CHANNELS

            for k, name in enumerate(STRUCTURE_CHANNELS):
                cols[name] = out[:, O_STRUCT + k]
        if self._flex is not None and "accel" in groups:   # the sensors on their mounts (one-way, exact)
            acc = self._flex.mounts.process(np.stack([cols[a] for a in ACCELEROMETERS], axis=1))
            for i, a in enumerate(ACCELEROMETERS):
                cols[a] = acc[:, i]
        # copies: the output buffer is reused by the next chunk
        return {k: np.array(v) for k, v in cols.items()}


def _flexible_run(cfg: BenchConfig, P: np.ndarray, options: ReferenceOptions):
    """The flexible structure's runner (:mod:`twin.reference.flexible`), or a ConfigError naming what its scope
    leaves out."""
    from twin.reference.flexible import FlexibleRun

    if options.integrator != "euler":
        raise ConfigError("reference.integrator", "the flexible structure integrates with \"euler\"")
    if "drive_energy" in cfg.sensors.channels:
        raise ConfigError("sensors.channels", "the optional group 'drive_energy' does not count the flexible "
                          "structure's dampers in the reference engine yet (its balance would not close); remove it "
                          "with structure.mode = \"flexible\"")
    if cfg.joints.diametral_mm("A") > 0 or cfg.joints.guide_play:
        field, value = (("clearance_a_mm", cfg.joints.clearance_a_mm) if cfg.joints.diametral_mm("A") > 0
                        else ("clearance_guide_mm", cfg.joints.clearance_guide_mm))
        raise ConfigError(f"joints.{field}", "is not available with structure.mode = \"flexible\" (it carries the "
                          "frame and the guide on their supports: the reference engine has it with A and the guide "
                          f"ideal); use 0, got {value!r}")
    if options.rod_model == "modal":
        from twin.reference.flexible_modal_run import ModalRun

        return ModalRun(cfg, P, lambda c: engine_params(c, options))
    return FlexibleRun(cfg, P, lambda c: engine_params(c, options))


def warm_up() -> float:
    """Compile (first use) or load from numba's cache the stepping loop; returns seconds spent.

    Done once per process at engine construction so that ``wall_s`` measures stepping only."""
    global _WARM
    if _WARM:
        return 0.0
    t0 = time.perf_counter()
    cfg = BenchConfig()
    P = ref_model.build_params(cfg)
    st = initial_state(cfg, 0.0)
    z = np.zeros(0)
    ref_model.run_steps(P, st, z, z, 1, np.empty((1, ref_model.N_OUT)), True)
    _WARM = True
    return time.perf_counter() - t0


def warm_up_prescribed() -> float:
    """The same for the prescribed drive's loop (:func:`twin.reference.model.run_prescribed`)."""
    global _WARM_PRESCRIBED
    if _WARM_PRESCRIBED:
        return 0.0
    t0 = time.perf_counter()
    P = ref_model.build_params(BenchConfig())
    st = initial_state(BenchConfig(), 0.0)
    z1 = np.zeros(1)
    ref_model.run_prescribed(P, st, z1, z1, np.zeros(0), 1, np.empty((1, ref_model.N_OUT)), True)
    _WARM_PRESCRIBED = True
    return time.perf_counter() - t0


_WARM_PRESCRIBED = False


_WARM = False


def _numba_version() -> str:
    import numba

    return numba.__version__
