"""Drive train of the reference engine: motor rotor, speed controller and V-belt (numba).

The model and its parameters are :mod:`twin.config.drivetrain` (the MuJoCo twin's native
callback implements the same equations). Here they are kernels the stepping loop of
:mod:`twin.reference.model` calls from three hooks when ``drive.mode`` is "motor" or "torque":

* :func:`begin_step` at the start of step k: the controller sample (every ``stride_ctrl``
  steps: encoder count, speed estimate, PI with the torque clamp) or the torque program's
  value, then the belt pull F from the belt stretch x and the pulley speeds (closed form, see
  :func:`belt_pull`); returns the torque r_c F the crank receives.
* :func:`end_step` after the mechanism's step: the rotor by symplectic Euler,
  J_m ω̇_m = τ_m − r_m F, φ_m ← φ_m + h ω_m, the belt stretch by explicit Euler x ← x + h ẋ,
  and (if asked) the work and dissipation accumulators with the step's mean velocities
  (½ (v_k + v_{k+1}): the quadrature under which symplectic Euler's kinetic energy change is
  exactly the work of the forces held over the step).
* :func:`outputs` writes one sample of the drive train's channels (layout ``DO_*``).

Parameter vector ``D`` (layout ``D_*``, :func:`build`) and state vector ``ds`` (layout
``DS_*``, :func:`initial_state`) travel with the mechanism's state between chunks.
"""

from __future__ import annotations

import math

import numpy as np
from twin.jit import njit

from twin.physics.contact import ramp

# ---------------------------------------------------------------- parameter layout
(D_MODE, D_JM, D_RM, D_RC, D_K, D_C, D_EA, D_FMAX, D_CS, D_STRIDE, D_COUNTS, D_ALPHA, D_KP, D_KI,
 D_TCTRL, D_PEAK, D_H, D_ACCOUNT) = range(18)
N_D = 18
#: D[D_MODE]: 1 speed loop on the analog command, 2 torque program
MODE_SPEED, MODE_TORQUE = 1.0, 2.0

# -------------------------------------------------------------------- state layout
(DS_PHI, DS_OMEGA, DS_X, DS_INT, DS_U, DS_COUNT, DS_WF, DS_STARTED, DS_K, DS_F, DS_W, DS_XDOT,
 DS_WORK, DS_DDAMP, DS_DSLIP, DS_DGUIDE, DS_DCONTACT) = range(17)
N_DS = 17

# ------------------------------------------------------------------- output columns
(DO_PHI, DO_OMEGA, DO_TORQUE, DO_BELT_TORQUE, DO_SLIP, DO_WORK, DO_EBELT, DO_DDAMP, DO_DSLIP,
 DO_DGUIDE, DO_DCONTACT, DO_ROTOR_KE, DO_EMECH) = range(13)
#: DO_EMECH: the mechanism's T + V plus the rotor's kinetic energy, written by the model's hook
N_DO = 13


def build(cfg) -> np.ndarray:
    """Parameter vector of a configuration's drive train (``drive.mode`` "motor" or "torque")."""
    dt = cfg.drivetrain
    h = cfg.simulation.timestep_s
    D = np.zeros(N_D)
    D[D_MODE] = MODE_SPEED if cfg.drive.mode == "motor" else MODE_TORQUE
    D[D_JM] = dt.rotor_inertia_kgm2
    D[D_RM] = dt.motor_pulley_radius_m
    D[D_RC] = dt.crank_pulley_radius_m(cfg.drive.belt_ratio)
    D[D_K] = dt.stiffness_npm
    D[D_C] = dt.belt_damping_nspm
    D[D_EA] = dt.belt_ea_n
    D[D_FMAX] = dt.max_pull_n
    D[D_CS] = dt.slip_damping_nspm
    D[D_STRIDE] = dt.controller_stride(h)
    D[D_COUNTS] = dt.encoder_counts
    T = D[D_STRIDE] * h
    D[D_TCTRL] = T
    D[D_ALPHA] = 1.0 - math.exp(-2.0 * math.pi * dt.speed_filter_hz * T)
    D[D_KP], D[D_KI] = dt.speed_kp_nms, dt.speed_ki_nm
    D[D_PEAK] = dt.peak_torque_nm
    D[D_H] = h
    D[D_ACCOUNT] = 1.0 if "drive_energy" in cfg.sensors.channels else 0.0
    return D


def initial_state() -> np.ndarray:
    """Motor at rest at angle 0, belt unstretched, controller reset, accumulators zero."""
    return np.zeros(N_DS)


@njit(cache=True)
def belt_pull(D, x, v_rel, v_m, out):
    """Belt pull F [N], slip speed w [m/s] and stretch rate ẋ [m/s] (``out[0:3]``) from the
    stretch x [m], the relative belt speed v_rel = v_m − v_c and the motor pulley's belt speed v_m.

    F = k x + c (v_rel − w(F)), w = λ F below the friction limit (creep, λ = |v_m|/EA) and
    sign(F) [λ F_max + (|F| − F_max)/c_slip] beyond: w is piecewise linear and increasing in F,
    so F + c w(F) = k x + c v_rel has one solution, in closed form."""
    k, c, Fmax, cs = D[D_K], D[D_C], D[D_FMAX], D[D_CS]
    lam = abs(v_m) / D[D_EA]
    A = k * x + c * v_rel
    F = A / (1.0 + c * lam)
    if abs(F) <= Fmax:
        w = lam * F
    else:
        sg = 1.0 if A > 0.0 else -1.0
        aF = (abs(A) - c * lam * Fmax + c * Fmax / cs) / (1.0 + c / cs)
        F = sg * aF
        w = sg * (lam * Fmax + (aF - Fmax) / cs)
    out[0] = F
    out[1] = w
    out[2] = v_rel - w


@njit(cache=True)
def begin_step(D, ds, omega_c, setpoint, tmp):
    """Start of a step: controller sample or torque program, belt pull; returns the crank torque
    r_c F [N m]. ``omega_c``: crank rate [rad/s]; ``setpoint``: the step's motor speed set point
    [rad/s] (speed loop) or motor torque [N m] (torque program)."""
    peak = D[D_PEAK]
    if D[D_MODE] == MODE_SPEED:
        if ds[DS_K] == 0.0:  # steps to the next controller sample (counts down)
            counts = D[D_COUNTS]
            count = math.floor(ds[DS_PHI] * counts / (2.0 * math.pi))
            if ds[DS_STARTED] == 0.0:
                ds[DS_COUNT] = count
                ds[DS_STARTED] = 1.0
            T = D[D_TCTRL]
            est = (count - ds[DS_COUNT]) * (2.0 * math.pi / counts) / T
            ds[DS_COUNT] = count
            ds[DS_WF] += D[D_ALPHA] * (est - ds[DS_WF])
            e = setpoint - ds[DS_WF]
            integ = ds[DS_INT] + D[D_KI] * T * e
            u = D[D_KP] * e + integ
            if abs(u) <= peak:
                ds[DS_INT] = integ          # anti-windup: no integration while clamped
            else:
                u = peak if u > 0.0 else -peak
            ds[DS_U] = u
            ds[DS_K] = D[D_STRIDE]
        ds[DS_K] -= 1.0
    else:
        u = setpoint
        ds[DS_U] = peak if u > peak else (-peak if u < -peak else u)
    v_m = D[D_RM] * ds[DS_OMEGA]
    belt_pull(D, ds[DS_X], v_m - D[D_RC] * omega_c, v_m, tmp)
    ds[DS_F], ds[DS_W], ds[DS_XDOT] = tmp[0], tmp[1], tmp[2]
    return D[D_RC] * tmp[0]


@njit(cache=True)
def gravity_forces(P_gx, P_gy, m1, xg1, r, m2, xg2, l, m3, Qg):
    """Generalized gravity forces of the natural coordinates (as in the reference model's
    ``generalized_forces``), for the dissipation accounts."""
    w1 = m1 * xg1 / r
    wa = m1 - w1
    a2 = xg2 / l
    Qg[0], Qg[1] = w1 * P_gx, w1 * P_gy
    Qg[2], Qg[3] = m2 * (1.0 - a2) * P_gx, m2 * (1.0 - a2) * P_gy
    Qg[4], Qg[5] = m2 * a2 * P_gx, m2 * a2 * P_gy
    Qg[6] = m3 * P_gx
    Qg[7] = 0.0
    Qg[8], Qg[9] = wa * P_gx, wa * P_gy


@njit(cache=True)
def end_step(D, ds, Q, Qg, tau, f_guide, qd0, qd1):
    """End of a step: advance the rotor and the belt stretch; accumulate the work and
    dissipation (``D[D_ACCOUNT]``) with the mean velocities ½ (qd0 + qd1) of the mechanism
    (``Q`` the step's generalized forces, ``Qg`` gravity's, ``tau`` the crank torque in Q,
    ``f_guide`` the guide friction force in Q[6])."""
    h = D[D_H]
    w0 = ds[DS_OMEGA]
    w1 = w0 + h * (ds[DS_U] - D[D_RM] * ds[DS_F]) / D[D_JM]
    ds[DS_OMEGA] = w1
    ds[DS_PHI] += h * w1
    xd = ds[DS_XDOT]
    ds[DS_X] += h * xd
    if D[D_ACCOUNT] != 0.0:
        ds[DS_WORK] += h * ds[DS_U] * 0.5 * (w0 + w1)
        ds[DS_DDAMP] += h * D[D_C] * xd * xd
        ds[DS_DSLIP] += h * ds[DS_F] * ds[DS_W]
        ds[DS_DGUIDE] -= h * f_guide * 0.5 * (qd0[6] + qd1[6])
        p = 0.0
        for i in range(Q.shape[0]):
            f = Q[i] - Qg[i]
            if i == 7:
                f -= tau
            elif i == 6:
                f -= f_guide
            p += f * 0.5 * (qd0[i] + qd1[i])
        ds[DS_DCONTACT] -= h * p


@njit(cache=True)
def guide_force(fg, v, v0, v1):
    """The slider guide's friction force (the reference model's law) [N]."""
    if fg <= 0.0:
        return 0.0
    f = fg * ramp(v, v0, v1)
    return -f if v > 0.0 else (f if v < 0.0 else 0.0)


@njit(cache=True)
def outputs(D, ds, row):
    """One sample of the drive train's channels (layout ``DO_*``)."""
    row[DO_PHI] = ds[DS_PHI]
    row[DO_OMEGA] = ds[DS_OMEGA]
    row[DO_TORQUE] = ds[DS_U]
    row[DO_BELT_TORQUE] = D[D_RC] * ds[DS_F]
    row[DO_SLIP] = ds[DS_W]
    row[DO_WORK] = ds[DS_WORK]
    row[DO_EBELT] = 0.5 * D[D_K] * ds[DS_X] * ds[DS_X]
    row[DO_DDAMP] = ds[DS_DDAMP]
    row[DO_DSLIP] = ds[DS_DSLIP]
    row[DO_DGUIDE] = ds[DS_DGUIDE]
    row[DO_DCONTACT] = ds[DS_DCONTACT]
    row[DO_ROTOR_KE] = 0.5 * D[D_JM] * ds[DS_OMEGA] * ds[DS_OMEGA]
