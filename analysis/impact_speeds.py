"""The impact speeds that occur on the bench, measured from reference-engine runs.

The check of the twin's contact law against the reference's single impacts
(``twin/studies/contact_check.py``, ``SPEEDS``; before issue 15 the range of the retired contact calibration)
must cover the normal impact speeds the pins actually reach (issue 4: "measure that range from
reference runs; at least 1 mm/s to 0.5 m/s"). This script runs the reference engine (R-matrix, Lankarani–Nikravesh,
h = 1e-5 s) over

* Table 4 tests 4–12 (0.1 mm at B and/or C, 250/500/750 motor rpm, y up), 3 s each with
  the default 0.5 s start-up ramp;
* every catalogue clearance (0.02–1.00 mm) at B and C together, in each orientation
  (x, y, z up), at 750 motor rpm (the fastest tested speed), 2 s each;
* the 38 s three-speed protocol of test 12 (starts and stops included);

and takes, at every contact onset of each clearance joint (``fn_J`` turning positive), the
normal approach speed d|e|/dt over the step before the onset — the speed the reference stores
for that contact event (onsets in the first 2 ms, where a loaded start settles, are left
out). It prints, per joint, the number of contact events and of impacts
(onsets after at least ``twin.summary.MIN_FREE_S`` of separation), the 1st/5th/50th/95th/99th
percentiles and extremes of the impact speed, and the share inside the checked range.
With ``--png FILE`` it also writes a histogram.

Run: ``python analysis/impact_speeds.py [--png impact_speeds.png]`` (about a minute on one
core: ~140 s simulated by the reference).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from tqdm import tqdm

from twin.studies.contact_check import SPEEDS
from twin.config import CATALOGUE_DIAMETRAL_MM, BenchConfig, preset
from twin.simulation import simulate_run
from twin.summary import MIN_FREE_S, contact_onsets
from twin.provenance import figure_metadata

CHANNELS = ["crank", "joints"]
#: onsets in the first SETTLE_S of a run are left out: a loaded start settles onto its static
#: load there (contacts at ~0.1 mm/s and forces of 1e-14 N, measured), which is no impact
SETTLE_S = 2e-3


def scenes() -> list[tuple[str, BenchConfig]]:
    """(label, configuration) of every run of the survey (reference engine)."""
    common = {"simulation.engine": "reference", "sensors.channels": CHANNELS}
    out = [(f"test {i}", preset(i).replace(**common, **{"simulation.duration_s": 3.0})) for i in range(4, 13)]
    for mm in CATALOGUE_DIAMETRAL_MM:
        for up in ("x", "y", "z"):
            cfg = preset(12).replace(**common, **{
                "joints.clearance_b_mm": mm, "joints.clearance_c_mm": mm, "mechanism.orientation": up,
                "simulation.duration_s": 2.0})
            out.append((f"B=C={mm:g} mm, {up} up", cfg))
    out.append(("test 12 protocol", preset(12).replace(**common, **{"drive.program": "protocol",
                                                                    "simulation.duration_s": 0.0})))
    return out


def onset_speeds(run, joint: str) -> tuple[np.ndarray, np.ndarray]:
    """(approach speed at every contact onset [m/s], separation before it [s]) of ``joint``."""
    rate = run.rate_hz
    e = np.hypot(np.asarray(run[f"ecc_{joint}_x"], float), np.asarray(run[f"ecc_{joint}_y"], float))
    onsets, free = contact_onsets(np.asarray(run[f"fn_{joint}"]) > 0)
    keep = onsets >= max(1, int(round(SETTLE_S * rate)))
    onsets, free = onsets[keep], free[keep] / rate  # no separation before: ~9e18 samples, "forever"
    return (e[onsets] - e[onsets - 1]) * rate, free


def main() -> None:
    ap = argparse.ArgumentParser(description="impact speeds of the bench, measured from reference runs")
    ap.add_argument("--png", metavar="FILE", help="write a histogram of the impact speeds")
    ap.add_argument("--no-progress", action="store_true")
    a = ap.parse_args()
    speeds: dict[str, list[np.ndarray]] = {"B": [], "C": []}
    free: dict[str, list[np.ndarray]] = {"B": [], "C": []}
    for label, cfg in tqdm(scenes(), disable=a.no_progress, unit="run"):
        run = simulate_run(cfg)
        for j in cfg.joints.clearance_joints:
            v, f = onset_speeds(run, j)
            speeds[j].append(v)
            free[j].append(f)
    lo, hi = min(SPEEDS), max(SPEEDS)
    print(f"checked range (twin.studies.contact_check.SPEEDS): {lo * 1e3:g} mm/s to {hi * 1e3:g} mm/s")
    print("| joint | contact events | impacts | v at impacts [mm/s]: min / p1 / p5 / median / p95 / p99 / max "
          "| impacts below / in / above range | all events: min / max [mm/s] |")
    print("|---|---:|---:|---|---|---|")
    hist = {}
    for j in ("B", "C"):
        v, f = np.concatenate(speeds[j]), np.concatenate(free[j])
        imp = v[f >= MIN_FREE_S]
        hist[j] = imp
        q = np.percentile(imp, [0, 1, 5, 50, 95, 99, 100]) * 1e3
        shares = [np.mean(imp < lo) * 100, np.mean((imp >= lo) & (imp <= hi)) * 100, np.mean(imp > hi) * 100]
        print(f"| {j} | {v.size} | {imp.size} | " + " / ".join(f"{x:.3g}" for x in q)
              + " | " + " / ".join(f"{x:.1f} %" for x in shares)
              + f" | {v.min() * 1e3:.3g} / {v.max() * 1e3:.3g} |")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 3.5))
        bins = np.geomspace(1e-5, 2.0, 60)
        for j, v in hist.items():
            ax.hist(np.clip(v, bins[0], None), bins=bins, histtype="step", label=f"{j} ({v.size} impacts)")
        ax.axvspan(lo, hi, color="0.9", zorder=0, label="checked range")
        ax.set(xscale="log", xlabel="normal impact speed [m/s]", ylabel="impacts",
               title="Impact speeds in reference runs (tests 4-12, catalogue x orientation, protocol)")
        ax.legend(fontsize=8)
        fig.tight_layout()
        out = Path(a.png)
        tmp = out.with_name(f".{out.name}.tmp.png")
        fig.savefig(tmp, dpi=120, metadata=figure_metadata())
        tmp.replace(out)
        print(f"wrote {out}")


if __name__ == "__main__":
    main()
