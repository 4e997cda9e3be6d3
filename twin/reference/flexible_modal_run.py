"""The modal rod's runner (:mod:`twin.reference.flexible_modal` holds its model and kernels; the stepping loop is the
chain's, :func:`twin.reference.flexible.run_flexible`) and its tap response."""

from __future__ import annotations

import math

import numpy as np

from twin.natural_coordinates import N_Q, S_Q, S_QD
from twin.reference.flexible import RodRun, tap_kick
from twin.reference.flexible_modal import ModalLayout, _modal_structure_outputs, modal_project
from twin.reference.model import N_OUT, OK


class ModalRun(RodRun):
    """The modal rod's runner for :class:`twin.reference.engine.ReferenceEngine` (the interface of
    :class:`twin.reference.flexible.FlexibleRun`: ``reset``, ``run``, ``mounts``, ``x``, ``layout``)."""

    def __init__(self, cfg, P_rigid: np.ndarray, params) -> None:
        from twin.errors import ConfigError

        if cfg.structure.rod_end_inertia_kgm2 != 0.0:
            raise ConfigError("reference.rod_model", "\"modal\" needs structure.rod_end_inertia_kgm2 = 0 (its sine "
                                                     "shapes leave the housings' rotary inertia out); use \"chain\"")
        super().__init__(cfg, P_rigid, params)
        self.layout = ModalLayout(cfg, self.split)
        self._z = np.empty((0, 3), dtype=np.int64)
        self.kkt(cfg.drive.mode == "prescribed")

    def kkt(self, prescribed: bool):
        """The sparse acceleration solve's tables (the rigid model's rows only), built once per drive kind."""
        from twin.reference.flexible_kkt import KKTLayout

        kk = self._kkt.get(prescribed)
        if kk is None:
            lay = self.layout
            z2 = np.empty((0, 2), dtype=np.int64)
            kk = self._kkt[prescribed] = KKTLayout(self.P, lay.G, z2, np.empty((0, 2)), self._z, lay.n, prescribed,
                                                   mass=lay.mass_matrix(self.P))
        return kk

    def reset(self, st_rigid: np.ndarray) -> None:
        """The straight, unstretched rod on the rigid model's pose (its velocities projected), the contact stiffnesses
        of the rigid model's parameters."""
        self.take_contact_parameters()
        n = self.layout.n
        x = np.zeros(2 * n + 1)
        q, qd = x[:n].copy(), np.zeros(n)
        q[:N_Q] = st_rigid[S_Q:S_Q + N_Q]
        qd[:N_Q] = st_rigid[S_QD:S_QD + N_Q]
        if modal_project(self.P, self.layout.G, q, qd, np.empty(n), np.empty(n), np.empty(n), self._z) < 0:
            raise ValueError("the modal rod's initial pose does not satisfy its constraints")
        x[:n], x[n:2 * n] = q, qd
        self.x = x
        self.mounts.reset()

    def run(self, st: np.ndarray, theta_ref: np.ndarray, omega_ref: np.ndarray, stride: int, buf: np.ndarray,
            train=None, k0: int = 0, alpha_ref: np.ndarray | None = None):
        """One chunk (arguments as :meth:`twin.reference.flexible.FlexibleRun.run`): the stepping loop is the
        chain's, :func:`twin.reference.flexible.run_flexible`, with this rod's tables."""
        from twin.reference.flexible import run_flexible

        lay = self.layout
        if train is not None:
            sp, dbuf = train.chunk_inputs(k0, omega_ref, stride, buf.shape[0])
            D, ds = train.D, train.ds
        else:
            sp = D = ds = np.empty(0)
            dbuf = np.empty((0, 1))
        kk = self.kkt(alpha_ref is not None)
        e2, ez = np.empty((0, 2)), np.empty((0, 2), dtype=np.int64)
        return run_flexible(self.P, lay.G, ez, e2, ez, e2, self._z, e2, self._z, lay.sens, st, self.x, theta_ref,
                            omega_ref, stride, buf, True, D, ds, sp, dbuf,
                            np.empty(0) if alpha_ref is None else alpha_ref, kk.crow, kk.pat, kk.pn, kk.Minv, kk.cols,
                            kk.cn, kk.Mcrank, kk.kaug, lay.H, lay.MD, lay.F, lay.sens, lay.sphi, lay.sdphi, kk.wlo)

    def tap(self, speed_mps: float, axial: bool) -> None:
        """A tap on the current state: the mid-span point given ``speed_mps`` normal to the chord (through the
        first shape, φ_1(½) = 1), or (``axial``) the bore C along the chord; velocities projected."""
        n = self.layout.n
        x = self.x
        q, qd = x[:n].copy(), x[n:2 * n].copy()
        tap_kick(q, qd, N_Q, speed_mps, axial)
        if modal_project(self.P, self.layout.G, q, qd, np.empty(n), np.empty(n), np.empty(n), self._z) < 0:
            raise ValueError("the tapped state does not satisfy the constraints")
        x[:n], x[n:2 * n] = q, qd

    def deflection(self) -> float:
        """The mid-span point's distance from the chord B'–C [m]."""
        row = np.zeros(N_OUT + 6)
        _modal_structure_outputs(self.P, self.layout.G, self.x[:self.layout.n], self.layout.MD, row)
        return float(row[N_OUT + 2])


def modal_tap_response(cfg, speed_mps: float, duration_s: float, every: int, theta0: float, drive: bool,
                       axial: bool) -> tuple[np.ndarray, np.ndarray]:
    """:func:`twin.reference.flexible.chain_tap_response` for the modal rod (the same arguments and returns; the bending
    tap is the mid-span point's velocity given through the first shape)."""
    from twin.natural_coordinates import initial_state
    from twin.reference.model import build_params

    prm = lambda c: build_params(c, drive=drive, guide_friction=False)  # noqa: E731
    run = ModalRun(cfg, prm(cfg), prm)
    st = initial_state(cfg, theta0, 0.0, run.P)
    run.reset(st)
    run.tap(speed_mps, axial)
    n = run.layout.n
    h = cfg.simulation.timestep_s
    steps = int(round(duration_s / (every * h)))
    buf = np.empty((1, N_OUT + 6))
    ref = np.full(every, theta0)
    zero = np.zeros(every)
    w = np.empty(steps)
    for i in range(steps):
        status, _ = run.run(st, ref, zero, every, buf)
        if status != OK:
            raise ValueError(f"the tap response failed at step {i * every} (status {status})")
        qq = run.x[:n]
        w[i] = math.hypot(qq[4] - qq[2], qq[5] - qq[3]) - cfg.bodies.rod.length_m if axial else run.deflection()
    return (np.arange(steps) + 1) * every * h, w
