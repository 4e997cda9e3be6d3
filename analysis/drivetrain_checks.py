"""Figures of the drive train's independent checks, both engines (the tests assert them; this prints them).

1. Natural frequency of the rotor–belt–crank mode: a 0.02 N m torque step on the free rotor (no
   gravity, no guide friction, no belt damping) at θ0 = 0.3 rad; frequency from the upward zero
   crossings of the belt torque (quadratic trend removed) against sqrt(k r_c² (1/J_c + 1/J_m')) / 2π,
   J_c the mechanism's inertia at the crank from closed-form kinematics, J_m' = J_m (r_c/r_m)².
2. Coast-down: 1 N m on the motor for 0.5 s, released; without gravity, the energy lost per turn
   (same crank angle one turn apart) against the guide friction × the slider's travel per turn.
3. Energy balance: motor work − [Δ(mechanism + rotor energy) + belt energy + dissipation], as a
   fraction of the motor work, 0.8 s from rest (``--long``: 2 s, and test 9 at h = 1e-5 and 5e-6 s).
4. Crank ripple harmonics (1st–3rd, % of mean speed) at 750 motor rpm after a 1 s spin-up, 1.2 s,
   ideal (test 3) and B+C clearance (test 12), both engines, and their relative difference.

Run: ``python analysis/drivetrain_checks.py [--long]``.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from twin.config import preset
from twin.kinematics import initial_pose
from twin.motor_drive import crank_side_inertia, speed_harmonics
from twin.simulation import simulate_run

ENGINES = ("mujoco", "reference")


def run(cfg):
    return {k: np.asarray(v.data, dtype=np.float64) for k, v in simulate_run(cfg).channels.items()}


def natural_frequency(engine: str) -> tuple[float, float]:
    theta0 = 0.3
    cfg = preset(1).replace(**{
        "drive.mode": "torque", "simulation.engine": engine, "simulation.duration_s": 0.06,
        "drive.initial_encoder_angle_rad": theta0 + math.pi / 2, "mechanism.gravity_mps2": 0.0,
        "mechanism.guide_friction_n": 0.0, "drivetrain.belt_damping_nspm": 0.0, "drivetrain.torque_s": [0.0],
        "drivetrain.torque_nm": [0.02], "drivetrain.torque_ramp_s": 0.0, "drivetrain.release_s": 0.0,
        "sensors.channels": ["crank", "motor"]})
    ch = run(cfg)
    dt = cfg.drivetrain
    r_m, r_c = dt.motor_pulley_radius_m, dt.crank_pulley_radius_m(cfg.drive.belt_ratio)
    f0 = math.sqrt(dt.stiffness_npm * r_c ** 2 * (1 / crank_side_inertia(cfg, theta0)
                                                  + 1 / (dt.rotor_inertia_kgm2 * (r_c / r_m) ** 2))) / (2 * math.pi)
    y = ch["belt_torque"]
    k = np.arange(y.size)
    y = y - np.polyval(np.polyfit(k, y, 2), k)
    up = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    tc = (up - y[up] / (y[up + 1] - y[up])) / cfg.output_rate_hz
    return (len(tc) - 1) / (tc[-1] - tc[0]), f0


def coast_down(engine: str) -> tuple[np.ndarray, float]:
    cfg = preset(1).replace(**{
        "drive.mode": "torque", "simulation.engine": engine, "simulation.duration_s": 2.5,
        "mechanism.gravity_mps2": 0.0, "drivetrain.torque_s": [0.0], "drivetrain.torque_nm": [1.0],
        "drivetrain.torque_ramp_s": 0.05, "drivetrain.release_s": 0.5,
        "sensors.channels": ["crank", "motor", "drive_energy"], "sensors.output_rate_hz": 10000.0})
    ch = run(cfg)
    t = np.arange(ch["crank_angle"].size) / cfg.output_rate_hz
    th = np.unwrap(ch["crank_angle"])
    e = ch["energy_mechanical"] + ch["energy_belt"]
    after = t > 0.6
    marks = th[after][0] + 2 * math.pi * np.arange(1, 4)
    lost = -np.diff(np.interp(marks, th[after], e[after]))
    xs = np.array([initial_pose(cfg, a).slider_x for a in np.linspace(0, 2 * math.pi, 20001)])
    return lost, cfg.mechanism.guide_friction_n * float(np.sum(np.abs(np.diff(xs))))


def balance(engine: str, test: int, duration: float, h: float = 1e-5) -> tuple[float, float]:
    cfg = preset(test).replace(**{"drive.mode": "motor", "simulation.engine": engine,
                                  "simulation.duration_s": duration, "simulation.timestep_s": h,
                                  "sensors.channels": ["crank", "motor", "drive_energy"],
                                  "sensors.output_rate_hz": 1000.0})
    ch = run(cfg)
    w = ch["motor_work"][-1]
    rest = (ch["energy_mechanical"][-1] - ch["energy_mechanical"][0] + ch["energy_belt"][-1]
            + sum(ch[k][-1] for k in ("diss_belt_damping", "diss_belt_slip", "diss_guide", "diss_contact")))
    return w, (w - rest) / w


def ripple(engine: str, test: int) -> np.ndarray:
    cfg = preset(test).replace(**{"drive.mode": "motor", "simulation.engine": engine, "simulation.duration_s": 2.2,
                                  "sensors.channels": ["crank", "motor"], "sensors.output_rate_hz": 10000.0})
    ch = run(cfg)
    keep = np.arange(ch["crank_angle"].size) / cfg.output_rate_hz >= 1.0
    return speed_harmonics(ch["crank_angle"][keep], ch["crank_speed"][keep])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--long", action="store_true", help="2 s balances and the timestep study of test 9")
    args = ap.parse_args()
    print("1. natural frequency [Hz]: simulated / closed form (error)")
    for e in ENGINES:
        f, f0 = natural_frequency(e)
        print(f"   {e:9s} {f:.3f} / {f0:.3f} ({100 * (f / f0 - 1):+.3f} %)")
    print("2. coast-down: energy lost per turn [J] / guide friction work per turn [J]")
    for e in ENGINES:
        lost, work = coast_down(e)
        print(f"   {e:9s} " + ", ".join(f"{x:.5f}" for x in lost) + f" / {work:.5f} "
              f"(errors {', '.join(f'{100 * (x / work - 1):+.2f} %' for x in lost)})")
    dur = 2.0 if args.long else 0.8
    print(f"3. energy balance, {dur:g} s from rest: motor work [J], residual / motor work")
    cases = [("mujoco", 12), ("mujoco", 3), ("reference", 3), ("reference", 6), ("reference", 9), ("reference", 12)]
    for e, t in cases:
        w, r = balance(e, t, dur)
        print(f"   {e:9s} test {t:2d}: {w:.4f} J, {r:+.2e}")
    if args.long:
        for h in (1e-5, 5e-6):
            w, r = balance("reference", 9, 1.0, h)
            print(f"   reference test 9, 1 s, h = {h:g} s: {w:.4f} J, {r:+.2e}")
    print("4. crank ripple harmonics 1-3 [% of mean speed], 750 motor rpm")
    for t in (3, 12):
        hm, hr = ripple("mujoco", t), ripple("reference", t)
        print(f"   test {t:2d}: mujoco {np.round(hm, 4)}, reference {np.round(hr, 4)}, "
              f"relative difference {np.round(100 * (hm / hr - 1), 2)} %")


if __name__ == "__main__":
    main()
