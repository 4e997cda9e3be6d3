"""The 0.5 mm scene of the issue-15 table: where peak |AC6| comes from, how it converges in h.

For the 0.5 mm C-clearance scene of ``analysis/contact_table.py`` (B ideal, y up, 750 motor rpm,
statistics over t in [1, 2) s) and each engine/timestep run: the peak |AC6| raw and after the
ADXL sensor response (``twin.instrument.accel``, datasheet and lowpass, 100 kHz), the time of
the peak, the contact angle of the pin (in the bushing frame) at the onset of that impact, the
peak contact force, and the clearance joint's friction against its normal force: the median
and 99th percentile of |ft_C|/fn_C where fn_C > 5 N and the pin slides at full μ0 (a value
above μ0 = 0.05 means the friction took a larger normal force than the solver applied).

Run: ``python analysis/peak_accel_convergence.py [--steps 1e-5,5e-6,2e-6,1e-6] [--reference 1e-5,1e-6]``
(one process, one simulation at a time; ~30 s with the defaults on two cores).
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np


def measure(engine: str, h: float) -> dict:
    from scipy.signal import lfilter, lfilter_zi

    from contact_table import WINDOW_S, scene_config
    from twin.instrument.accel import model_of, response_ba
    from twin.simulation import simulate_run

    cfg = scene_config(0.5, 750.0, engine, h, 2.0)
    run = simulate_run(cfg)
    x = np.asarray(run["AC6"], float)
    i0, i1 = (int(round(t * run.rate_hz)) for t in WINDOW_S)
    out = {"engine": engine, "h": h, "raw": float(np.abs(x[i0:i1]).max())}
    k = i0 + int(np.argmax(np.abs(x[i0:i1])))
    out["t_peak"] = k / run.rate_hz
    for resp in ("datasheet", "lowpass"):
        inst = dataclasses.replace(cfg.instrumentation, response=resp)
        b, a = response_ba(model_of(inst, "AC6"), inst, run.rate_hz)
        y, _ = lfilter(b, a, x, zi=lfilter_zi(b, a) * x[0])
        out[resp] = float(np.abs(y[i0:i1]).max())
    fn = np.asarray(run["fn_C"], float)
    on = np.flatnonzero(fn[:k + 1] <= 0)
    s = on[-1] + 1 if len(on) else 0  # onset of the impact that holds the peak
    out["angle_deg"] = float(np.degrees(np.arctan2(run["ecc_C_y"][s], run["ecc_C_x"][s])))
    out["peak_fn"] = float(fn[i0:i1].max())
    ft = np.abs(np.asarray(run["ft_C"], float))
    m = fn > 5
    r = ft[m] / fn[m]
    r = r[r > 0.049]  # sliding at full mu0
    out["ft_fn_median"], out["ft_fn_p99"] = float(np.median(r)), float(np.percentile(r, 99))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", default="1e-5,5e-6,2e-6,1e-6", help="MuJoCo twin timesteps [s]")
    ap.add_argument("--reference", default="1e-5,1e-6", help="reference engine timesteps [s]")
    a = ap.parse_args()
    jobs = [("mujoco", float(h)) for h in a.steps.split(",") if h] + \
           [("reference", float(h)) for h in a.reference.split(",") if h]
    rows = [measure(e, h) for e, h in jobs]
    conv = next((r for r in rows if r["engine"] == "reference" and r["h"] == 1e-6), None)
    print("| engine | h [s] | peak abs(AC6) raw | datasheet | lowpass | vs reference 1e-6 (raw) | t of peak [s] "
          "| pin angle at the impact's onset | peak fn_C [N] | abs(ft)/fn sliding, median / p99 |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---|")
    for r in rows:
        rel = f"{100 * (r['raw'] / conv['raw'] - 1):+.1f} %" if conv else ""
        print(f"| {r['engine']} | {r['h']:g} | {r['raw']:.1f} | {r['datasheet']:.1f} | {r['lowpass']:.1f} | {rel} | "
              f"{r['t_peak']:.5f} | {r['angle_deg']:.1f}° | {r['peak_fn']:.1f} | "
              f"{r['ft_fn_median']:.4f} / {r['ft_fn_p99']:.4f} |")


if __name__ == "__main__":
    main()
