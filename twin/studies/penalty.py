r"""Penalty formulation of the ideal mechanism (S003 Eq. 9–10), for the §4.1 comparison.

Same natural coordinates, mass matrix and forces as :mod:`twin.reference.model`, seven
constraints of the ideal mechanism (crank length, crank angle x_B sin θ − y_B cos θ, rod
length, B = B', C = C'), but no projection and no velocity transformation: the Lagrange
multipliers are replaced by λ = α (Φ̈ + 2ζω Φ̇ + ω² Φ) (Eq. 9), which gives n = 8 ODEs
(S003's eight coordinates: the crank journal A' of the model's q[8:10] stays exactly at the
origin, A being ideal here; q and q̇ are the model's ``N_Q``-vectors)

    (M + α Φ_qᵀ Φ_q) q̈ = Q − α Φ_qᵀ (Φ̇_q q̇ + 2 ζ ω Φ̇ + ω² Φ)          (Eq. 10)

integrated with the same symplectic Euler step (q̇ ← q̇ + h q̈, q ← q + h q̇). For large α the
constraints obey Φ̈ + 2ζωΦ̇ + ω²Φ ≈ 0: a damped oscillator of frequency ω, which symplectic
Euler integrates stably only for ω h small enough (for ζ = 1 it needs ω h < 2(√2 − 1) ≈ 0.83),
so ω = 1000 rad/s fails at h = 1e-3 s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from twin.jit import njit

from twin.errors import ConfigError
from twin.natural_coordinates import N_Q, P_H, energy, mass_times, quadratic_terms, residual
from twin.reference.model import _cholesky_solve, generalized_forces


@dataclass(frozen=True)
class PenaltyParams:
    """Parameters of the penalty formulation (S003 Eq. 9–10).

    Attributes:
        alpha: penalty factor α [kg-like: mass matrix units per constraint unit²], > 0.
        zeta: damping ratio ζ of the constraint stabilization [-], ≥ 0.
        omega: natural frequency ω of the constraint stabilization [rad/s], ≥ 0.
    """

    alpha: float = 1e9
    zeta: float = 1.0
    omega: float = 1000.0

    def __post_init__(self) -> None:
        a = self.alpha
        if isinstance(a, bool) or not isinstance(a, (int, float)) or not math.isfinite(a) or not 0 < a <= 1e16:
            raise ConfigError("penalty.alpha", f"must be a number in (0, 1e16], got {a!r}")
        for name in ("zeta", "omega"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise ConfigError(f"penalty.{name}", f"must be a finite number >= 0, got {v!r}")

    @property
    def label(self) -> str:
        """Short label, e.g. ``P α=1e+09 ζ=1 ω=1000``."""
        return f"P α={self.alpha:.0e} ζ={self.zeta:g} ω={self.omega:g}"


@njit(cache=True)
def _jacobian(P, q, J):
    """Φ_q of the seven constraints of the ideal mechanism (7 × 8)."""
    s, c = math.sin(q[7]), math.cos(q[7])
    J[:, :] = 0.0
    J[0, 0] = 2.0 * q[0]
    J[0, 1] = 2.0 * q[1]
    J[1, 0] = s
    J[1, 1] = -c
    J[1, 7] = q[0] * c + q[1] * s
    dx, dy = q[4] - q[2], q[5] - q[3]
    J[2, 2] = -2.0 * dx
    J[2, 3] = -2.0 * dy
    J[2, 4] = 2.0 * dx
    J[2, 5] = 2.0 * dy
    J[3, 0] = 1.0
    J[3, 2] = -1.0
    J[4, 1] = 1.0
    J[4, 3] = -1.0
    J[5, 4] = -1.0
    J[5, 6] = 1.0
    J[6, 5] = -1.0


@njit(cache=True)
def penalty_run(P, q, qd, alpha, zeta, omega, nsteps, every, th_d, en, phi, phid):
    """Integrate Eq. 10 from (q, q̇) (``N_Q``-vectors with A' = q[8:10] = 0, held) for ``nsteps``
    steps of P[P_H] (τ = 0, ideal joints), recording θ̇, energy, ‖Φ‖, ‖Φ̇‖ before step 0 and every ``every`` steps.

    Returns (diverged, steps done, samples written). Diverged: non-finite state, failed
    factorization, ‖Φ‖ > 1 or |θ̇| > 1e4 rad/s (the run stops there)."""
    h = P[P_H]
    Mm = np.zeros((8, 8))
    e = np.zeros(N_Q)
    col = np.empty(N_Q)
    for j in range(8):
        e[:] = 0.0
        e[j] = 1.0
        mass_times(P, e, col)
        Mm[:, j] = col[:8]
    J = np.empty((7, 8))
    K = np.empty((8, 8))
    rhs = np.empty(8)
    Q = np.empty(8)
    res = np.empty(N_Q)
    quad = np.empty(N_Q)
    Qf = np.empty(N_Q)
    lam = np.empty(7)
    cst = np.zeros(2)
    jo = np.zeros(5)
    m = 0
    k = 0
    diverged = False
    while True:
        s, c = math.sin(q[7]), math.cos(q[7])
        residual(P, q, s, c, res)
        _jacobian(P, q, J)
        nphi = 0.0
        nphid = 0.0
        for i in range(7):
            v = 0.0
            for j in range(8):
                v += J[i, j] * qd[j]
            nphi += res[i] * res[i]
            nphid += v * v
            lam[i] = 2.0 * zeta * omega * v + omega * omega * res[i]
        nphi = math.sqrt(nphi)
        if k % every == 0:
            th_d[m] = qd[7]
            en[m] = energy(P, q, qd)
            phi[m] = nphi
            phid[m] = math.sqrt(nphid)
            m += 1
        if not (nphi <= 1.0 and abs(qd[7]) <= 1e4):   # also catches NaN
            diverged = True
            break
        if k == nsteps:
            break
        quadratic_terms(q, qd, s, c, quad)        # −Φ̇_q q̇ (rows 0–2)
        for i in range(3):
            lam[i] -= quad[i]
        generalized_forces(P, q, qd, 0.0, cst, cst, cst, Qf, jo, jo, jo)
        for i in range(8):
            Q[i] = Qf[i]
        for i in range(8):
            acc = Q[i]
            for r in range(7):
                acc -= alpha * J[r, i] * lam[r]
            rhs[i] = acc
            for j in range(8):
                acc2 = Mm[i, j]
                for r in range(7):
                    acc2 += alpha * J[r, i] * J[r, j]
                K[i, j] = acc2
        if not _cholesky_solve(K, rhs, 8):
            diverged = True
            break
        for i in range(8):
            qd[i] += h * rhs[i]
            q[i] += h * qd[i]
        k += 1
    return diverged, k, m
