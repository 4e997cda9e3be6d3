"""Which recording length tells the restitution? (docs/calibration.md, "What can be calibrated").

One bench (Table 4 test 6, joint C 0.5 mm, 1000 motor rpm, reference engine by default; ``--test``,
``--clearance``, ``--engine``, ``--e-true`` change it), a "recording"
at a true restitution e_t (two noise seeds: the repeats that set the term scales, as ``twin calibrate``
does), and simulations at e_t + offsets. For analysis windows of growing length L (starting at 0.5 s,
after the start-up), the calibration objective (bands, peaks; the term scales from the two repeats over
the same window) is computed against the first recording, as ``twin calibrate`` computes it, for every
offset. Printed per L: the objective per offset, its largest deterministic jump (the fall below the
running maximum moving away from the minimum, :func:`twin.calibration.bootstrap.roughness`), the rise at
±0.05 (the issue's target) and whether the minimum lies within ±0.05 of the truth.

    python analysis/restitution_length.py [--duration 2.6] [--engine reference] [--out FILE.json]

Cost: one simulation per offset (plus the recording), each ``--duration`` seconds long.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

OFFSETS = (-0.2, -0.1, -0.05, -0.02, -0.01, 0.0, 0.01, 0.02, 0.05, 0.1, 0.2)
E_TRUE = 0.3872  # the first validation set's e_1 (analysis/calibration_validation/truth.json)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--duration", type=float, default=2.6)
    ap.add_argument("--engine", default="reference", choices=("reference", "mujoco"))
    ap.add_argument("--lengths", default="0.25,0.5,1.0,2.0")
    ap.add_argument("--test", type=int, default=6, help="Table 4 test (default 6)")
    ap.add_argument("--clearance", type=float, default=0.5, help="joint C clearance [mm] (default 0.5)")
    ap.add_argument("--e-true", type=float, default=E_TRUE, help=f"the true restitution (default {E_TRUE})")
    ap.add_argument("--out", type=Path, default=None)
    a = ap.parse_args()

    from twin.calibration.bootstrap import roughness
    from twin.calibration.objective import DEFAULT_SCALES, SCALE_FLOOR, features, raw_terms
    from twin.config import ACCELEROMETERS, CHANNEL_GROUPS, preset
    from twin.instrument import apply_chain, measured_accel, simulated_calibration
    from twin.simulation import simulate_run

    e_true = a.e_true
    base = preset(a.test).replace(**{"simulation.engine": a.engine, "simulation.duration_s": a.duration,
                                "drive.motor_rpm": 1000.0, "drive.ramp_s": 0.05, "joints.clearance_c_mm": a.clearance,
                                "sensors.channels": list(CHANNEL_GROUPS)})
    rate = base.sensors.output_rate_hz
    cal = simulated_calibration(base, 1.0, stream=3)

    def measured(e: float, stream: int, seed: int, run=None):
        cfg = base.replace(**{"contact.restitution": e, "instrumentation.seed": seed})
        run = run if run is not None else simulate_run(cfg)
        daq = apply_chain(run, cfg, prefix="sim_", stream=stream)
        meas = measured_accel(daq, cal, prefix="sim_")
        return run, {s: np.asarray(meas[f"sim_meas_{s}"], dtype=np.float64) for s in ACCELEROMETERS
                     if f"sim_meas_{s}" in meas}

    t0 = time.perf_counter()
    run_t, rec1 = measured(e_true, 2, 1)
    _, rec2 = measured(e_true, 2, 2, run_t)  # the repeat: the same physics, another noise seed
    angle_t = np.asarray(run_t["crank_angle"], dtype=np.float64)
    sims = {}
    for off in OFFSETS:
        run, acc = measured(e_true + off, 2, 7)  # the simulation's own noise (common random numbers)
        sims[off] = (acc, np.asarray(run["crank_angle"], dtype=np.float64))
        print(f"e = {e_true + off:.4f}: simulated ({time.perf_counter() - t0:.0f} s)", flush=True)
    lengths = [float(x) for x in a.lengths.split(",")]
    i0 = int(0.5 * rate)
    dtw_n = int(0.05 * rate)
    out = {"e_true": e_true, "test": a.test, "clearance_c_mm": a.clearance, "engine": a.engine, "duration_s": a.duration, "offsets": list(OFFSETS), "lengths": {}}
    for L in lengths:
        i1 = min(len(angle_t) - int(0.02 * rate), i0 + int(L * rate))
        sl = slice(i0, i1)
        sensors = [s for s in rec1 if np.ptp(rec1[s][sl]) > 0]
        f1 = features({s: rec1[s][sl] for s in sensors}, angle_t[sl], rate, dtw_n)
        f2 = features({s: rec2[s][sl] for s in sensors}, angle_t[sl], rate, dtw_n)
        scat = raw_terms(f1, f2, rate, 0.002, False)
        scales = {k: max(SCALE_FLOOR * DEFAULT_SCALES[k], scat.get(k, 0.0)) for k in DEFAULT_SCALES}
        J = []
        for off in OFFSETS:
            acc, ang = sims[off]
            fs = features({s: acc[s][sl] for s in sensors}, ang[sl], rate, dtw_n)
            t = raw_terms(fs, f1, rate, 0.002, False)
            J.append(sum((t[k] / scales[k]) ** 2 for k in ("bands", "peaks") if k in t))
        J = np.asarray(J)
        du = np.asarray(OFFSETS)
        rg = roughness(e_true, du, J, 1.0)
        k0 = int(np.argmin(J))
        rise = float(min(J[du == -0.05][0], J[du == 0.05][0]) - J[du == 0.0][0])
        turns = abs(float(angle_t[i1 - 1] - angle_t[i0])) / (2 * np.pi)
        out["lengths"][str(L)] = {"window_s": [i0 / rate, i1 / rate], "turns": turns, "J": J.tolist(),
                                  "scales": scales, "max_drop": rg.max_drop, "rise_at_0.05": rise,
                                  "argmin_offset": OFFSETS[k0], "min_within_0.05": bool(abs(OFFSETS[k0]) <= 0.05)}
        print(f"L = {L:g} s ({turns:.1f} turns): J = {' '.join(f'{x:.3g}' for x in J)}; largest jump "
              f"{rg.max_drop:.3g}, rise at ±0.05 {rise:.3g}, minimum at {OFFSETS[k0]:+.2f}", flush=True)
    out["wall_s"] = time.perf_counter() - t0
    if a.out:
        from twin.provenance import stamped

        a.out.write_text(json.dumps(stamped(out), indent=1) + "\n")


if __name__ == "__main__":
    main()
