"""Tune the crank PID gains (the defaults of ``twin.config.PID`` come from this script).

Method (pole placement on the rigid 1-DOF mechanism, then a check in the twin):

1. From the closed-form kinematics of the ideal slider–crank (``twin.kinematics``) compute,
   over one crank turn, the generalized inertia J(θ) = Σ m |∂x_G/∂θ|² + I (∂φ/∂θ)² about the
   crank axis, and the torque the drive needs to hold the fastest bench speed (750 motor rpm)
   exactly: τ(θ) = ½ J'(θ) ω² + V'(θ) + F_guide |∂x_s/∂θ| (inertial, gravity, guide friction).
2. The PID must impose the encoder trace to within ``ERROR_COUNTS`` encoder counts at that
   speed. The disturbance τ(θ) lies at the crank rate and its first harmonics (≤ 20 Hz), far
   below the loop bandwidth, so the error is ≈ τ / kp: kp = max|τ| / error.
3. With J_max the largest J over the turn, the closed loop ω_n = sqrt(kp / J_max) is critically
   damped (ζ = 1): kv = 2 ζ sqrt(kp J_max). The integral corner sits a decade below ω_n:
   ki = kp ω_n / 10, and the integral state is clamped so that its torque stays below the
   largest steady torque: imax = 2 max|τ| / ki.
4. Explicit integration at h = 1e-5 s: ω_n h and kv h / J_min must stay well below 1 (printed).
5. Check: simulate Table 4 tests 3 (ideal) and 12 (B+C clearance) with the MuJoCo twin and the
   rounded gains, and report the tracking error at steady speed in encoder counts.

Run: ``python analysis/tune_pid.py`` (about a minute). Paste the printed gains into
``twin/config/drive.py`` (class ``PID``) when they change.
"""

from __future__ import annotations

import math

import numpy as np

from twin.config import BenchConfig, preset
from twin.drive import RPM_TO_RAD_S
from twin.kinematics import rod_angle, slider_position
from twin.simulation import simulate_run

ERROR_COUNTS = 0.5          # target steady tracking error [encoder counts]
COUNTS_PER_REV = 32768      # 4x quadrature of the SICK DGS80 (S003 §2.3.3)
MAX_MOTOR_RPM = 750.0       # fastest bench speed of Table 4


def mechanism_terms(cfg: BenchConfig, theta: np.ndarray, dth: float = 1e-6):
    """J(θ) [kg m²], dJ/dθ, dV/dθ [N m] and ∂x_s/∂θ [m/rad] of the ideal mechanism."""
    b, g = cfg.bodies, np.array(cfg.mechanism.gravity_vector[:2])
    r, l, d = b.crank.length_m, b.rod.length_m, cfg.mechanism.d_off_m

    def positions(th):
        phi = rod_angle(th, r, l, d)
        bx, by = r * np.cos(th), r * np.sin(th)
        crank_g = b.crank.x_g_m * np.stack([np.cos(th), np.sin(th)])
        rod_g = np.stack([bx, by]) + b.rod.x_g_m * np.stack([np.cos(phi), np.sin(phi)])
        xs = slider_position(th, r, l, d)
        slider_g = np.stack([xs + b.slider.x_g_m, np.full_like(xs, d)])
        return phi, crank_g, rod_g, slider_g, xs

    def J_and_V(th):
        p1, p0 = positions(th + dth), positions(th - dth)
        dphi = (p1[0] - p0[0]) / (2 * dth)
        drod = (p1[2] - p0[2]) / (2 * dth)
        dsl = (p1[3] - p0[3]) / (2 * dth)
        J = (b.crank.inertia_kgm2 + b.crank.mass_kg * b.crank.x_g_m**2
             + b.rod.mass_kg * (drod**2).sum(0) + b.rod.inertia_kgm2 * dphi**2
             + b.slider.mass_kg * (dsl**2).sum(0))
        _, cg, rg, sg, _ = positions(th)
        V = -(b.crank.mass_kg * g @ cg + b.rod.mass_kg * g @ rg + b.slider.mass_kg * g @ sg)
        dxs = (p1[4] - p0[4]) / (2 * dth)
        return J, V, dxs

    J, V, dxs = J_and_V(theta)
    Jp = (J_and_V(theta + 1e-4)[0] - J_and_V(theta - 1e-4)[0]) / 2e-4
    Vp = (J_and_V(theta + 1e-4)[1] - J_and_V(theta - 1e-4)[1]) / 2e-4
    return J, Jp, Vp, dxs


def tune(cfg: BenchConfig) -> dict[str, float]:
    theta = np.linspace(0, 2 * np.pi, 3600, endpoint=False)
    J, Jp, Vp, dxs = mechanism_terms(cfg, theta)
    w = MAX_MOTOR_RPM / cfg.drive.belt_ratio * RPM_TO_RAD_S
    tau = 0.5 * Jp * w**2 + Vp + cfg.mechanism.guide_friction_n * np.abs(dxs)
    err = ERROR_COUNTS * 2 * math.pi / COUNTS_PER_REV
    kp = np.abs(tau).max() / err
    wn = math.sqrt(kp / J.max())
    kv = 2 * 1.0 * math.sqrt(kp * J.max())
    ki = kp * wn / 10
    imax = 2 * np.abs(tau).max() / ki
    h = cfg.simulation.timestep_s
    print(f"J(θ) over a turn: {J.min():.4f} .. {J.max():.4f} kg m^2")
    print(f"steady torque at {MAX_MOTOR_RPM:.0f} motor rpm (crank {w:.2f} rad/s): max |τ| = {np.abs(tau).max():.2f} N m")
    print(f"error target {ERROR_COUNTS} counts = {err:.3e} rad -> kp = {kp:.4g} N m/rad")
    print(f"ω_n = {wn:.1f} rad/s ({wn / 2 / math.pi:.1f} Hz), kv = {kv:.4g} N m s/rad, ki = {ki:.4g}, imax = {imax:.3g}")
    print(f"explicit-step checks at h = {h:g} s: ω_n h = {wn * h:.4f}, kv h / J_min = {kv * h / J.min():.4f}")
    return {"kp": kp, "kv": kv, "ki": ki, "imax": imax}


def round_sig(x: float, sig: int = 2) -> float:
    return float(f"{x:.{sig}g}")


def check(gains: dict[str, float]) -> None:
    count = 2 * math.pi / COUNTS_PER_REV
    for test in (3, 12):
        cfg = preset(test).replace(**{"simulation.duration_s": 1.5, "drive.ramp_s": 0.5,
                                      **{f"pid.{k}": v for k, v in gains.items()}})
        run = simulate_run(cfg)
        steady = run.window(1.0, 1.5)
        e = steady["theta_ref"] - steady["crank_angle"]
        print(f"test {test}: steady tracking error max {np.abs(e).max() / count:.2f} counts, "
              f"rms {np.sqrt(np.mean(e**2)) / count:.2f} counts; max PID torque "
              f"{np.abs(steady['crank_torque']).max():.1f} N m; wall {run.meta['wall_s']:.1f} s")


if __name__ == "__main__":
    raw = tune(BenchConfig())
    gains = {k: round_sig(v) for k, v in raw.items()}
    print("rounded gains for twin/config/drive.py PID:", gains)
    check(gains)
