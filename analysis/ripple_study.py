"""Crank speed ripple of the motor drive train: which placeholders matter, and which ripple to expect.

Method. Reference engine (the MuJoCo twin agrees on these harmonics within 0.7 %,
``analysis/drivetrain_checks.py``), ``drive.mode = "motor"``, constant program, y vertical, from rest
(0.5 s ramp); window 1.0–3.0 s (steady state, 2–6 whole turns). Per run:

* crank-speed harmonics 1–3 over crank angle (:func:`twin.motor_drive.speed_harmonics`), amplitude in %
  of the mean speed, and their phase against the crank angle (bench angle θ, cosine reference: the
  harmonic is A cos(kθ + phase));
* motor-to-crank lag: the phase of the 2nd harmonic (the dominant one) of the motor speed referred to
  the crank (ω_m / belt ratio) minus that of the crank speed, as a delay in ms at the mean speed;
* the fraction of samples at the motor's peak torque clamp, and the mean crank speed's loss against the
  command (creep and the loop's steady-state error).

Runs: (1) the defaults at 250/500/750 motor rpm with ideal joints and 0.1 mm at B, C, B and C (Table 4);
(2) one at a time, each placeholder at the low and high end of its documented range
(:mod:`twin.drivetrain_params`), at 250 and 750 rpm with B and C clearance.

Writes ``analysis/results/drivetrain_ripple/ripple.json`` and two PNG figures.
Run: ``python analysis/ripple_study.py [--out DIR]`` (about 2 minutes).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from twin.config import preset
from twin.motor_drive import speed_harmonics
from twin.simulation import simulate_run
from twin.provenance import figure_metadata, stamped

#: Table 4 clearance cases: name -> test id at 750 rpm (the speed is set separately)
CASES = {"ideal": 3, "C": 6, "B": 9, "BC": 12}
SPEEDS = (250.0, 500.0, 750.0)
#: the placeholders over their documented ranges (low, high)
RANGES = {
    "rotor_inertia_kgm2": (1e-4, 6e-4), "motor_pulley_radius_m": (0.015, 0.04), "belt_ea_n": (5e3, 1e5),
    "span_length_m": (0.2, 0.5), "belt_damping_nspm": (5.0, 100.0), "preload_n": (30.0, 300.0),
    "friction_mu": (0.15, 0.5), "controller_rate_hz": (1000.0, 10000.0), "speed_filter_hz": (30.0, 500.0),
    "speed_kp_nms": (0.05, 0.5), "speed_ki_nm": (0.0, 20.0),
}
T0, T1 = 1.0, 3.0


def measure(test: int, rpm: float, **drivetrain) -> dict:
    ov = {"drive.mode": "motor", "drive.motor_rpm": rpm, "simulation.engine": "reference", "simulation.duration_s": T1,
          "sensors.channels": ["crank", "motor"], "sensors.output_rate_hz": 10000.0}
    ov.update({f"drivetrain.{k}": v for k, v in drivetrain.items()})
    cfg = preset(test).replace(**ov)
    ch = {k: np.asarray(v.data, dtype=np.float64) for k, v in simulate_run(cfg).channels.items()}
    t = np.arange(ch["crank_angle"].size) / cfg.output_rate_hz
    keep = t >= T0
    th, w = ch["crank_angle"][keep], ch["crank_speed"][keep]
    amp = speed_harmonics(th, w)
    phase = _phases(th, w)
    wm = ch["motor_speed"][keep] / cfg.drive.belt_ratio
    lag_rad = _phases(th, wm)[1] - phase[1]
    lag_rad = (lag_rad + math.pi) % (2 * math.pi) - math.pi
    mean = float(np.mean(w))
    return {"harmonics_pct": [float(a) for a in amp], "phase_deg": [float(math.degrees(p)) for p in phase],
            "lag_ms": float(-lag_rad / 2 / mean * 1e3),  # > 0: the crank's 2nd harmonic lags the motor's
            "clamp_fraction": float(np.mean(np.abs(ch["motor_torque"][keep]) >= cfg.drivetrain.peak_torque_nm * (1 - 1e-6))),
            "speed_loss_pct": float(100 * (1 - mean / (rpm / cfg.drive.belt_ratio * math.pi / 30)))}


def _phases(th: np.ndarray, w: np.ndarray) -> np.ndarray:
    th = np.unwrap(th)
    start = math.ceil(th[0] / (2 * math.pi)) * 2 * math.pi  # whole turns from θ = 0 (mod 2π)
    turns = int((th[-1] - start) // (2 * math.pi))
    grid = start + np.linspace(0, 2 * math.pi * turns, 512 * turns, endpoint=False)
    spec = np.fft.rfft(np.interp(grid, th, w))
    return np.array([np.angle(spec[turns * k]) for k in (1, 2, 3)])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="analysis/results/drivetrain_ripple")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    res: dict = {"window_s": [T0, T1], "defaults": {}, "sensitivity": {}}
    for case, test in CASES.items():
        for rpm in SPEEDS:
            r = measure(test, rpm)
            res["defaults"][f"{case}@{rpm:g}"] = r
            print(f"{case:5s} {rpm:4.0f} rpm: harmonics {np.round(r['harmonics_pct'], 2)} %, phase "
                  f"{np.round(r['phase_deg'], 0)} deg, lag {r['lag_ms']:.2f} ms, clamp {100 * r['clamp_fraction']:.0f} %, "
                  f"speed loss {r['speed_loss_pct']:.3f} %", flush=True)
    for rpm in (250.0, 750.0):
        for name, (lo, hi) in RANGES.items():
            for v in (lo, hi):
                r = measure(CASES["BC"], rpm, **{name: v})
                res["sensitivity"][f"{name}={v:g}@{rpm:g}"] = r
                print(f"BC {rpm:4.0f} rpm {name}={v:g}: harmonics {np.round(r['harmonics_pct'], 2)} %", flush=True)
    (out / "ripple.json").write_text(json.dumps(stamped(res), indent=1))
    _figures(res, out)


def _figures(res: dict, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6), sharey=False)
    for k, ax in enumerate(axes):
        for case in CASES:
            ax.plot(SPEEDS, [res["defaults"][f"{case}@{s:g}"]["harmonics_pct"][k] for s in SPEEDS], "o-", label=case)
        ax.set_title(f"harmonic {k + 1}")
        ax.set_xlabel("motor speed [rpm]")
        ax.set_ylabel("% of mean crank speed")
        ax.grid(alpha=0.3)
    axes[0].legend(title="clearance")
    fig.suptitle("Crank speed ripple, motor drive train, defaults (reference engine)")
    fig.tight_layout()
    fig.savefig(out / "ripple_defaults.png", dpi=110, metadata=figure_metadata())
    plt.close(fig)

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.2))
    for ax, rpm in zip(axes, (250.0, 750.0)):
        base = res["defaults"][f"BC@{rpm:g}"]["harmonics_pct"]
        names = list(RANGES)
        y = np.arange(len(names))
        for k, color in zip(range(3), ("C0", "C1", "C2")):
            lo = [res["sensitivity"][f"{n}={RANGES[n][0]:g}@{rpm:g}"]["harmonics_pct"][k] - base[k] for n in names]
            hi = [res["sensitivity"][f"{n}={RANGES[n][1]:g}@{rpm:g}"]["harmonics_pct"][k] - base[k] for n in names]
            ax.barh(y + (k - 1) * 0.27, hi, height=0.25, color=color, label=f"h{k + 1}: high end")
            ax.barh(y + (k - 1) * 0.27, lo, height=0.25, color=color, alpha=0.4, label=f"h{k + 1}: low end")
        ax.set_yticks(y, names)
        ax.axvline(0, color="k", lw=0.8)
        ax.set_xlabel("change of the harmonic [% of mean speed] against the defaults")
        ax.set_title(f"{rpm:g} motor rpm, 0.1 mm at B and C")
        ax.grid(alpha=0.3, axis="x")
    axes[1].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(out / "ripple_sensitivity.png", dpi=110, metadata=figure_metadata())
    plt.close(fig)


if __name__ == "__main__":
    main()
