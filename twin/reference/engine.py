"""The reference engine: R-matrix natural-coordinate model of S003 with contact and friction.

``twin simulate --engine reference`` runs this instead of MuJoCo, with the same
configuration, drive, channels, chunking and metadata (:class:`twin.simulate.Engine`), so
the two engines compare channel by channel. The formulation is in
:mod:`twin.reference.model`, the contact laws in :mod:`twin.reference.contact`.

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
from typing import Any, Iterator

import numpy as np

from twin import __version__ as twin_version
from twin.channels import channel_specs, encoder_from_bench
from twin.config import ACCELEROMETERS, BenchConfig
from twin.drive import DriveReference
from twin.errors import ConfigError, SimulationError
from twin.reference import model as M
from twin.run import Channel, Run
from twin.simulate import n_samples, output_stride

ENGINE_VERSION = "1"


@dataclass(frozen=True)
class ReferenceOptions:
    """Numerical settings of the reference engine (not part of the bench configuration).

    Attributes:
        min_impact_speed_mps: floor of the stored impact speed δ̇⁻ of the hysteresis laws [m/s].
            A contact event that starts with δ̇ below it (resting or grazing contact, e.g. the
            "loaded" start with δ̇ = 0) uses this value: the damping term K δ^n χ δ̇/δ̇⁻ would
            otherwise have an unbounded coefficient and make the explicit integration
            unstable. S003 does not say what it did. 1 mm/s is measured (``analysis/bench_reference.py
            --floor``, test 12, 2 s): the smallest decade that is stable at h = 1e-5 s (1e-4 m/s rings at B:
            794 N peak instead of 298 N, AC1 RMS 52 instead of 32 m/s²); at h = 2.5e-6 s, where 1e-4 m/s is
            stable too, the two floors give the same impact counts, peaks within 0.3 % (B) and 0.4 % (C)
            and accelerometer RMS within 0.6 %. Larger floors change the physics of slow impacts
            (1e-2 m/s: 19 instead of 25 impacts at C; 1e-1 m/s: 49).
        newton_tol_m: the position projection stops when max |Δq| ≤ this [m]; Newton's quadratic
            convergence then leaves ‖Φ‖ ≈ |Δq|², below round-off.
        newton_max_iter: iterations before the step is declared failed.
    """

    min_impact_speed_mps: float = 1e-3
    newton_tol_m: float = 1e-10
    newton_max_iter: int = 20

    def __post_init__(self) -> None:
        v = self.min_impact_speed_mps
        if not (isinstance(v, (int, float)) and math.isfinite(v) and 0 < v <= 10):
            raise ConfigError("reference.min_impact_speed_mps", f"must lie in (0, 10] m/s, got {v!r}")
        t = self.newton_tol_m
        if not (isinstance(t, (int, float)) and math.isfinite(t) and 0 < t <= 1e-6):
            raise ConfigError("reference.newton_tol_m", f"must lie in (0, 1e-6] m, got {t!r}")
        n = self.newton_max_iter
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= 100:
            raise ConfigError("reference.newton_max_iter", f"must be an integer in [1, 100], got {n!r}")


def engine_params(cfg: BenchConfig, options: ReferenceOptions = ReferenceOptions(), **switches: bool
                  ) -> np.ndarray:
    """Parameter vector of a configuration (contact stiffness still unresolved: see
    :func:`twin.reference.model.contact_parameters`); ``switches`` are the ``drive``,
    ``guide_friction``, ``joint_friction`` flags of :func:`twin.reference.model.build_params`."""
    return M.build_params(cfg, min_impact_speed_mps=options.min_impact_speed_mps,
                          newton_tol_m=options.newton_tol_m, newton_max_iter=options.newton_max_iter, **switches)


class ReferenceEngine:
    """R-matrix reference engine (see module docstring)."""

    name = "reference"

    def __init__(self, cfg: BenchConfig, options: ReferenceOptions | None = None):
        self.cfg = cfg
        if "energy" in cfg.sensors.channels:
            raise ConfigError("sensors.channels", "the optional group 'energy' is produced by the MuJoCo engine "
                                                  "only; remove it for --engine reference")
        self.options = options or ReferenceOptions()
        self.ref = DriveReference(cfg)
        self.stride, self.rate = output_stride(cfg)
        self.n_out = n_samples(cfg)
        self.specs = channel_specs(cfg)
        t0 = time.perf_counter()
        self.P = engine_params(cfg, self.options)
        theta0 = float(self.ref(np.array([0.0]))[0][0])
        try:
            self.state0 = M.initial_state(cfg, theta0)
        except ValueError as err:
            raise ConfigError("bodies", str(err)) from None
        self.contacts = M.contact_parameters(cfg, self.P, self.state0)
        build_s = time.perf_counter() - t0
        self.load_s = warm_up()
        self.meta: dict[str, Any] = {
            "engine": self.name,
            "engine_version": f"twin-reference {ENGINE_VERSION} (twin {twin_version}, numba {_numba_version()})",
            "formulation": "natural coordinates, R-matrix (S003 Eq. 11-16)",
            "integrator": "symplectic Euler (S003 Eq. 21) with position/velocity projection",
            "timestep_s": cfg.simulation.timestep_s,
            "steps": 0,
            "wall_s": 0.0,
            "build_s": build_s,
            "compile_s": self.load_s,
            "options": asdict(self.options),
            "contact": {j: {"law": cfg.contact.law, **asdict(c)} for j, c in self.contacts.items()},
        }

    def chunks(self) -> Iterator[Run]:
        cfg = self.cfg
        h = cfg.simulation.timestep_s
        st = self.state0.copy()
        per_chunk = max(1, int(round(cfg.simulation.chunk_s * self.rate)))
        buf = np.empty((min(per_chunk, max(self.n_out, 1)), M.N_OUT))
        done = 0
        wall = 0.0
        while done < self.n_out:
            n_out = min(per_chunk, self.n_out - done)
            nstep = n_out * self.stride
            t_start = time.perf_counter()
            k0 = done * self.stride
            t_steps = (k0 + np.arange(nstep)) * h
            theta_ref, omega_ref = self.ref(t_steps)
            status, steps = M.run_steps(self.P, st, np.ascontiguousarray(theta_ref, dtype=np.float64),
                                        np.ascontiguousarray(omega_ref, dtype=np.float64), self.stride,
                                        buf, True)
            if status != M.OK:
                why = "the position projection did not converge" if status == M.NEWTON_FAILED \
                    else "NaN or Inf in the state"
                raise SimulationError(f"{cfg.name}: reference run failed at t = {(k0 + steps) * h:.6f} s ({why}); "
                                      "try a smaller timestep")
            chunk = self._channels(buf[:n_out], theta_ref[::self.stride], omega_ref[::self.stride], done)
            wall += time.perf_counter() - t_start
            done += n_out
            self.meta.update(steps=done * self.stride, wall_s=wall,
                             real_time_factor=(done * self.stride * h) / wall if wall > 0 else None)
            yield chunk

    def _channels(self, out: np.ndarray, theta_ref: np.ndarray, omega_ref: np.ndarray, first: int) -> Run:
        cfg = self.cfg
        cols: dict[str, np.ndarray] = {}
        groups = cfg.sensors.channels
        if "accel" in groups:
            for i, a in enumerate(ACCELEROMETERS):
                cols[a] = out[:, M.O_ACC + i]
        if "encoder" in groups:
            cols["encoder_angle"] = encoder_from_bench(out[:, M.O_THETA], cfg.mechanism.crank_direction)
        if "crank" in groups:
            cols["crank_angle"] = out[:, M.O_THETA]
            cols["crank_speed"] = out[:, M.O_OMEGA]
        if "slider" in groups:
            cols["slider_position"] = out[:, M.O_SLIDER]
        if "joints" in groups:
            for jt in cfg.joints.clearance_joints:
                base = M.O_JOINT_B if jt == "B" else M.O_JOINT_C
                for k, name in enumerate((f"ecc_{jt}_x", f"ecc_{jt}_y", f"pen_{jt}", f"fn_{jt}", f"ft_{jt}")):
                    cols[name] = out[:, base + k]
        if "drive" in groups:
            cols["theta_ref"] = theta_ref
            cols["omega_ref"] = omega_ref
            cols["crank_torque"] = out[:, M.O_TORQUE]
        chans = {s.name: Channel(s.name, s.unit, s.group, np.array(cols[s.name], dtype=s.dtype))
                 for s in self.specs}
        return Run(first / self.rate, self.rate, chans, cfg, {})


def warm_up() -> float:
    """Compile (first use) or load from numba's cache the stepping loop; returns seconds spent.

    Done once per process at engine construction so that ``wall_s`` measures stepping only."""
    global _WARM
    if _WARM:
        return 0.0
    t0 = time.perf_counter()
    cfg = BenchConfig()
    P = M.build_params(cfg)
    st = M.initial_state(cfg, 0.0)
    z = np.zeros(0)
    M.run_steps(P, st, z, z, 1, np.empty((1, M.N_OUT)), True)
    _WARM = True
    return time.perf_counter() - t0


_WARM = False


def _numba_version() -> str:
    import numba

    return numba.__version__
