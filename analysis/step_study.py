"""Output rate versus physics step: is h = 2e-5 s with 100 kHz instrumented output within the sensor
noise floor of the h = 1e-5 s result?

The bench's accelerometers are band-limited (ADXL100x: 21 kHz resonance, "3 dB bandwidth" 11 kHz)
before the 100 kHz DAQ, so a physics step longer than the output period might do: run the twin at
h = 2e-5 s (50 kHz samples) and produce the instrumented channels at 100 kHz. For each Table 4
test with a clearance (4-12) this script runs the MuJoCo twin (default settings, accelerometers
only) through the constant-speed program (``--ramp`` spin-up, ``--settle``, then a ``--window``
that is analysed) at

* h = 1e-5 s: the reference of the comparison (the twin's default);
* h = 2e-5 s: the candidate (50 kHz samples);
* h = 5e-6 s (output decimated to 100 kHz): how far the h = 1e-5 s result itself is from a finer
  step, for scale.

Each is turned into what the bench's DAQ would record, as calibrated acceleration [m/s²]: the
accelerometer model of ``twin.instrument.accel`` (frequency response, range saturation; noise
off, it is the yardstick) at 100 kHz. The 50 kHz candidate reaches 100 kHz two ways:

* ``upsample→sensor``: the truth upsampled 2x (``scipy.signal.resample_poly``, zero-phase
  Kaiser FIR: sample 2k of the result is sample k of the input), then the sensor at 100 kHz;
* ``sensor→upsample``: the sensor model discretized at 50 kHz (the 21 kHz resonance is below
  its 25 kHz Nyquist frequency), then the output upsampled 2x the same way.

The error of a candidate is its difference from the h = 1e-5 s channel over the window, per
accelerometer: RMS [m/s²] against the sensor's own noise floor, the standard deviation of its
white noise over the DAQ band, σ = density · g · √(50 kHz) (ADXL1001 30 µg/√Hz: 0.066 m/s²;
ADXL1002 25 µg/√Hz: 0.055 m/s²). "Within the noise floor" means RMS error < σ for every sensor
of the test. Also reported: the error below 5 kHz (the band the accuracy study and the replay
compare; zero-phase Butterworth low-pass, order 8) and the same ratios for h = 5e-6 s against
h = 1e-5 s. Cost: engine stepping time per simulated second of each run (runs one after another
in this process: a rough ratio), and an interleaved best-of-3 of test 12 for the ratio.

Run: ``python analysis/step_study.py [--tests 4,...,12] [--window S] [--out DIR]`` (writes
``step_study.md`` and ``step_study.json`` into ``--out``, default ``analysis/results/step_study``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from pathlib import Path

import numpy as np

from twin.config import ACCELEROMETERS, preset
from twin.instrument.accel import STANDARD_G, AccelStream, model_of
from twin.provenance import git_commit, stamped, with_stamp_line
from twin.simulation import simulate_run

H_REF, H_LONG, H_FINE = 1e-5, 2e-5, 5e-6
DAQ_HZ = 100_000.0
LOW_BAND_HZ = 5_000.0


def run_accel(test_id: int, h: float, duration_s: float, ramp_s: float) -> tuple[dict[str, np.ndarray], float, float]:
    """AC1..AC6 proper accelerations of a MuJoCo run at step ``h`` (output at min(100 kHz, 1/h));
    returns (channels, rate, engine seconds per simulated second)."""
    rate = min(DAQ_HZ, 1.0 / h)
    cfg = preset(test_id).replace(**{"simulation.timestep_s": h, "sensors.output_rate_hz": rate,
                                     "sensors.channels": ["accel"], "simulation.duration_s": duration_s,
                                     "drive.ramp_s": ramp_s})
    run = simulate_run(cfg)
    return {a: np.asarray(run[a], dtype=np.float64) for a in ACCELEROMETERS}, rate, run.meta["wall_s"] / duration_s


def sensed(a: np.ndarray, sensor: str, inst, rate_hz: float) -> np.ndarray:
    """Calibrated output [m/s²] of accelerometer ``sensor`` (response and saturation, no noise) for a
    signal at ``rate_hz``."""
    stream = AccelStream(sensor, inst, rate_hz, None)
    m = model_of(inst, sensor)
    return (stream.process(a) - inst.zero_g(sensor)) / m.sensitivity_v_per_g * STANDARD_G


def up2(x: np.ndarray) -> np.ndarray:
    from scipy.signal import resample_poly

    return resample_poly(x, 2, 1)


def lowpass(x: np.ndarray) -> np.ndarray:
    from scipy.signal import butter, sosfiltfilt

    return sosfiltfilt(butter(8, LOW_BAND_HZ, fs=DAQ_HZ, output="sos"), x)


def noise_floor(inst, sensor: str) -> float:
    """Standard deviation of the sensor's white noise over the DAQ band [m/s²]."""
    return model_of(inst, sensor).noise_g_rthz * STANDARD_G * math.sqrt(DAQ_HZ / 2.0)


def study_test(test_id: int, args) -> dict:
    dur = args.ramp + args.settle + args.window
    inst = dataclasses.replace(preset(test_id).instrumentation, noise=False)
    ref, _, c_ref = run_accel(test_id, H_REF, dur, args.ramp)
    lng, r_lng, c_lng = run_accel(test_id, H_LONG, dur, args.ramp)
    fine, _, c_fine = run_accel(test_id, H_FINE, dur, args.ramp)
    i0 = int(round((args.ramp + args.settle) * DAQ_HZ))
    n = int(round(args.window * DAQ_HZ))
    win = slice(i0, i0 + n)
    out = {"test": test_id, "cost_s_per_sim_s": {"h=1e-5": c_ref, "h=2e-5": c_lng, "h=5e-6": c_fine}, "sensors": {}}
    for a in ACCELEROMETERS:
        y_ref = sensed(ref[a], a, inst, DAQ_HZ)
        cands = {
            "upsample→sensor": sensed(up2(lng[a]), a, inst, DAQ_HZ),
            "sensor→upsample": up2(sensed(lng[a], a, inst, r_lng)),
            "h=5e-6": sensed(fine[a], a, inst, DAQ_HZ),
        }
        sigma = noise_floor(inst, a)
        rec = {"sigma_mps2": sigma, "rms_signal_mps2": float(np.sqrt(np.mean(y_ref[win] ** 2)))}
        lo_ref = lowpass(y_ref)
        for k, y in cands.items():
            m = min(len(y), len(y_ref))
            e = (y[:m] - y_ref[:m])[win]
            e_lo = (lowpass(y[:m]) - lo_ref[:m])[win]
            rec[k] = {"rms_err_mps2": float(np.sqrt(np.mean(e ** 2))), "max_err_mps2": float(np.max(np.abs(e))),
                      "rms_err_below_5k_mps2": float(np.sqrt(np.mean(e_lo ** 2)))}
        out["sensors"][a] = rec
    return out


def interleaved_cost(test_id: int, repeats: int = 3, duration_s: float = 0.5) -> dict[str, float]:
    """Engine seconds per simulated second at each step, interleaved best of ``repeats``."""
    best = {"h=1e-5": math.inf, "h=2e-5": math.inf}
    for _ in range(repeats):
        for k, h in (("h=1e-5", H_REF), ("h=2e-5", H_LONG)):
            _, _, c = run_accel(test_id, h, duration_s, 0.2)
            best[k] = min(best[k], c)
    return best


def markdown(results: list[dict], cost: dict[str, float], args, commit: str) -> str:
    cands = ("upsample→sensor", "sensor→upsample", "h=5e-6")
    lines = [
        "# Output rate versus physics step (analysis/step_study.py)", "",
        f"MuJoCo twin, default settings, Table 4 tests {', '.join(str(r['test']) for r in results)}; "
        f"{args.ramp:g} s ramp, {args.settle:g} s settling, {args.window:g} s window; accelerometers through the "
        "ADXL100x model (response and saturation, noise off) at 100 kHz, as calibrated m/s². Reference: h = 1e-5 s. "
        f"Commit {commit}.", "",
        "Ratio = RMS error over the window / the sensor's noise floor σ (ADXL1001 "
        f"{noise_floor(preset(4).instrumentation, 'AC1'):.4f} m/s², ADXL1002 "
        f"{noise_floor(preset(4).instrumentation, 'AC6'):.4f} m/s²); the largest over AC1-AC6, and which sensor. "
        "Below 1: within the noise floor.", "",
        "| test | signal RMS (min-max over sensors) [m/s²] | " + " | ".join(f"{c}: worst ratio" for c in cands)
        + " | " + " | ".join(f"{c}: worst ratio < 5 kHz" for c in cands) + " |",
        "|---:|---|" + "---:|" * (2 * len(cands)),
    ]
    for r in results:
        s = r["sensors"]
        rms = [v["rms_signal_mps2"] for v in s.values()]
        cells = []
        for key in ("rms_err_mps2", "rms_err_below_5k_mps2"):
            for c in cands:
                a = max(s, key=lambda x: s[x][c][key] / s[x]["sigma_mps2"])
                cells.append(f"{s[a][c][key] / s[a]['sigma_mps2']:.2f} ({a})")
        lines.append(f"| {r['test']} | {min(rms):.1f}-{max(rms):.1f} | " + " | ".join(cells) + " |")
    lines += ["", "Engine cost, seconds per simulated second (runs of this study, one after another):", "",
              "| test | h = 1e-5 | h = 2e-5 | h = 5e-6 |", "|---:|---:|---:|---:|"]
    for r in results:
        c = r["cost_s_per_sim_s"]
        lines.append(f"| {r['test']} | {c['h=1e-5']:.3f} | {c['h=2e-5']:.3f} | {c['h=5e-6']:.3f} |")
    lines += ["", f"Test 12, interleaved best of 3 (0.5 s runs): h = 1e-5 s {cost['h=1e-5']:.3f} s/sim s, "
              f"h = 2e-5 s {cost['h=2e-5']:.3f} s/sim s (ratio {cost['h=1e-5'] / cost['h=2e-5']:.2f})."]
    within = [r["test"] for r in results
              if all(v[c]["rms_err_mps2"] < v["sigma_mps2"] for v in r["sensors"].values()
                     for c in ("upsample→sensor",))]
    lines += ["", f"Tests where h = 2e-5 s (upsample→sensor) is within the noise floor on every sensor: "
                  f"{within or 'none'}."]
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tests", default="4,5,6,7,8,9,10,11,12")
    ap.add_argument("--ramp", type=float, default=0.5)
    ap.add_argument("--settle", type=float, default=0.1)
    ap.add_argument("--window", type=float, default=1.0)
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "step_study"))
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results = []
    for t in (int(x) for x in args.tests.split(",")):
        results.append(study_test(t, args))
        print(f"test {t} done", flush=True)
    cost = interleaved_cost(12)
    commit = git_commit()
    text = markdown(results, cost, args, commit)
    (out / "step_study.md").write_text(with_stamp_line(text))
    (out / "step_study.json").write_text(json.dumps(stamped({"commit": commit, "settings": vars(args),
                                                             "tests": results, "cost_test12": cost}), indent=1))
    print(text)


if __name__ == "__main__":
    main()
