"""S003 Fig. 15 and §6 side by side, rigid against flexible structure, in the reference engine.

S003 §5 (Fig. 15b): with 0.1 mm at C (test 6) against ideal joints (test 3) at 750 motor rpm, AC4's Hann spectrum
rises "specially around 1000 Hz and 3000 Hz" while the crank rate and its first harmonics barely change; §6: impact
peaks "quickly reach their maximum value and subside in a few milliseconds".

Method: tests 3 and 6 (750 motor rpm) driven by the bench's motor and V-belt (``drive.mode = "motor"``; ``--drive
pid`` for the crank PID), ``--duration`` s from rest, each with ``structure.mode`` rigid and flexible (the defaults
of ``[structure]``: every number a documented placeholder); AC4 through the sensor chain
(``twin.instrument.apply_chain``: ADXL1001 response, noise, 18-bit DAQ), ``--repeats`` noise streams per run (the
simulation is deterministic: repeats differ by the sensor chain's noise only). Spectra of the last ``--window`` s
(Hann, one-sided, averaged over the repeats), summed per 250 Hz band up to 5 kHz, in dB re 1 g²; the increase is
test 6 − test 3. Impact decay: AC4 of the truth (no noise) in test 6 high-passed at 200 Hz, each impact peak
(local maxima of |a| above half the largest), the time its envelope (|a| max over 0.2 ms windows) takes to fall to 10 % of the peak.

Writes ``analysis/results/structure_fig15/<drive>/{bands.csv, summary.json, fig15.png}`` and prints the tables.
Run: ``python analysis/structure_fig15.py [--duration 2] [--window 1] [--repeats 5] [--drive motor|pid]``.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
from pathlib import Path

import numpy as np

from twin.provenance import figure_metadata, git_commit, stamped

from twin import __version__
from twin.config import preset
from twin.simulation import simulate_run

OUT = Path(__file__).resolve().parent / "results" / "structure_fig15"
BAND_HZ = 250.0
F_MAX = 5000.0
G = 9.80665


def run_case(test: int, mode: str, duration: float, drive: str):
    cfg = preset(test).replace(**{"simulation.engine": "reference", "simulation.duration_s": duration,
                                  "structure.mode": mode, "drive.mode": drive})
    return cfg, simulate_run(cfg)


def spectra(cfg, run, window: float, repeats: int) -> tuple[np.ndarray, np.ndarray]:
    """(f [Hz], mean one-sided Hann power spectrum of AC4 [g²] over ``repeats`` sensor-chain noise streams)."""
    from twin.instrument.chain import apply_chain

    sens = 0.020   # V/g, ADXL1001 (S003 Table 3)
    acc = []
    for k in range(repeats):
        daq = apply_chain(run, cfg, stream=k, command=False)
        v = np.asarray(daq["volt_AC4"], dtype=np.float64)
        n = int(round(window * daq.rate_hz))
        x = v[-n:] / sens
        x = x - x.mean()
        w = np.hanning(n)
        X = np.fft.rfft(x * w)
        acc.append(np.abs(X) ** 2 * 2.0 / (np.sum(w ** 2) * daq.rate_hz))   # PSD [g²/Hz]
        f = np.fft.rfftfreq(n, 1.0 / daq.rate_hz)
    return f, np.mean(acc, axis=0)


def bands(f: np.ndarray, psd: np.ndarray) -> np.ndarray:
    df = f[1] - f[0]
    edges = np.arange(0.0, F_MAX + BAND_HZ, BAND_HZ)
    return np.array([10 * np.log10(np.sum(psd[(f >= a) & (f < b)]) * df + 1e-30) for a, b in zip(edges, edges[1:])])


def decay_times(run, t_from: float) -> list[float]:
    """Time [ms] each impact peak of AC4 (truth, high-passed at 200 Hz to leave out the mechanism's own motion at the
    crank rate and its harmonics) takes for its envelope to fall to 10 % of the peak."""
    from scipy.signal import butter, sosfiltfilt

    rate = run.rate_hz
    a = np.asarray(run["AC4"], dtype=np.float64) / G
    a = sosfiltfilt(butter(4, 200.0, "highpass", fs=rate, output="sos"), a)
    a = a[int(t_from * rate):]
    env_n = max(1, int(2e-4 * rate))
    env = np.array([np.max(np.abs(a[i:i + env_n])) for i in range(0, a.size - env_n, env_n)])
    thr = 0.5 * env.max()
    out = []
    i = 1
    while i < env.size - 1:
        if env[i] >= thr and env[i] >= env[i - 1] and env[i] >= env[i + 1]:
            j = i
            while j < env.size and env[j] > 0.1 * env[i]:
                j += 1
            if j < env.size:
                out.append((j - i) * env_n / rate * 1e3)
            i = j
        i += 1
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=2.0)
    ap.add_argument("--window", type=float, default=1.0)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--drive", default="motor", choices=("motor", "pid"),
                    help="drive.mode: the bench's motor and V-belt (default) or the crank PID")
    a = ap.parse_args()
    out = OUT / a.drive
    out.mkdir(parents=True, exist_ok=True)
    res: dict = {}
    spec: dict = {}
    for mode in ("rigid", "flexible"):
        for test in (3, 6):
            print(f"simulating test {test}, {mode} ({a.duration:g} s)...", flush=True)
            cfg, run = run_case(test, mode, a.duration, a.drive)
            f, p = spectra(cfg, run, a.window, a.repeats)
            spec[(mode, test)] = (f, p)
            res[(mode, test)] = bands(f, p)
            if test == 6:
                res[(mode, "decay")] = decay_times(run, a.duration - a.window)
    edges = np.arange(0.0, F_MAX + BAND_HZ, BAND_HZ)
    lines = ["band_hz,rigid_ideal_db,rigid_clearance_db,rigid_increase_db,flex_ideal_db,flex_clearance_db,"
             "flex_increase_db"]
    print(f"\nAC4, 250 Hz bands, dB re 1 g^2 (last {a.window:g} s, Hann, {a.repeats} sensor-chain repeats)")
    print(f"{'band [Hz]':>12s} | {'rigid: ideal':>12s} {'clear.':>7s} {'incr.':>6s} | {'flexible: ideal':>15s} "
          f"{'clear.':>7s} {'incr.':>6s}")
    for i, (lo, hi) in enumerate(zip(edges, edges[1:])):
        r3, r6, f3, f6 = res[("rigid", 3)][i], res[("rigid", 6)][i], res[("flexible", 3)][i], res[("flexible", 6)][i]
        print(f"{lo:5.0f}-{hi:5.0f} | {r3:12.1f} {r6:7.1f} {r6 - r3:6.1f} | {f3:15.1f} {f6:7.1f} {f6 - f3:6.1f}")
        lines.append(f"{lo:.0f}-{hi:.0f},{r3:.2f},{r6:.2f},{r6 - r3:.2f},{f3:.2f},{f6:.2f},{f6 - f3:.2f}")
    summary = {"version": __version__, "commit": git_commit(), "drive_mode": a.drive, "duration_s": a.duration,
               "window_s": a.window,
               "repeats": a.repeats, "band_hz": BAND_HZ}
    for mode in ("rigid", "flexible"):
        inc = res[(mode, 6)] - res[(mode, 3)]
        top = np.argsort(inc)[::-1][:3]
        summary[mode] = {"largest_increase_bands_hz": [f"{edges[i]:.0f}-{edges[i + 1]:.0f}" for i in top],
                         "largest_increase_db": [round(float(inc[i]), 1) for i in top],
                         "increase_1000_hz_band_db": round(float(inc[4]), 1),
                         "increase_3000_hz_band_db": round(float(inc[12]), 1),
                         "impact_decay_ms": {"count": len(res[(mode, 'decay')]),
                                             "median": (round(float(np.median(res[(mode, 'decay')])), 2)
                                                        if res[(mode, 'decay')] else None)}}
        print(f"{mode}: largest increases in {summary[mode]['largest_increase_bands_hz']} "
              f"({summary[mode]['largest_increase_db']} dB); impact decay to 10 %: "
              f"{summary[mode]['impact_decay_ms']}")
    for name, text in (("bands.csv", "\n".join(lines) + "\n"), ("summary.json", json.dumps(stamped(summary), indent=2) + "\n")):
        fd, tmp = tempfile.mkstemp(dir=out)
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        os.replace(tmp, out / name)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for ax, mode in zip(axes, ("rigid", "flexible")):
        for test, col in ((3, "tab:blue"), (6, "tab:red")):
            f, p = spec[(mode, test)]
            ax.semilogy(f, p, color=col, lw=0.5, label=f"test {test}" + (" (ideal)" if test == 3 else " (0.1 mm at C)"))
        for fc in (1000.0, 3000.0):
            ax.axvspan(fc - 250, fc + 250, color="0.85", zorder=0)
        ax.set_title(f"AC4, {mode} structure, {a.drive} drive (reference engine); shaded: S003 Fig. 15b's 1 and 3 kHz",
                     fontsize=10)
        ax.set_ylabel("PSD [g²/Hz]")
        ax.legend(loc="upper right")
    axes[-1].set_xlim(0, F_MAX)
    axes[-1].set_xlabel("frequency [Hz]")
    fig.tight_layout()
    fd, tmp = tempfile.mkstemp(dir=out, suffix=".png")
    os.close(fd)
    fig.savefig(tmp, dpi=110, metadata=figure_metadata())
    os.replace(tmp, out / "fig15.png")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
