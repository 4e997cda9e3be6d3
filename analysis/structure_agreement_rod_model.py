"""Engine agreement with each of the reference's rod models: MuJoCo's chain against the reference's chain and its
modal rod (``reference.rod_model``), AC1–AC6 third-octave band energies, Table 4 tests 3, 6 and 12.

The method of ``analysis/structure_agreement.py`` (``structure.mode = "flexible"``, default ``[structure]`` fields,
``--duration`` s from rest, bands over the samples after ``--skip`` s, 10 log10(E_mujoco / E_reference) per band,
:func:`twin.structure.bands.band_difference_db`), with one MuJoCo run per test compared with both reference runs.
Also the two reference models against each other (the modal rod's change to the reference's spectra).
Writes ``analysis/results/structure/agreement_rod_model.md`` and its JSON, with the versions and the commit.

Run: ``python analysis/structure_agreement_rod_model.py [--duration 0.6] [--skip 0.2] [--tests 3,6,12]``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from twin.provenance import stamped, write_stamped_text

ACCELS = ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6")
MODELS = ("chain", "modal")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.6)
    ap.add_argument("--skip", type=float, default=0.2)
    ap.add_argument("--tests", default="3,6,12")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "structure"
                                         / "agreement_rod_model.md"))
    args = ap.parse_args()
    import twin
    from twin.config import preset
    from twin.reference.engine import ReferenceEngine, ReferenceOptions
    from twin.simulation import Collector, simulate
    from twin.structure.bands import band_difference_db, third_octave_centres
    from twin.util import atomic_write_text

    tests = [int(t) for t in args.tests.split(",")]
    result: dict = {"duration_s": args.duration, "skip_s": args.skip, "bands_hz": third_octave_centres().tolist(),
                    "tests": {}}
    lines = [f"structure.mode = flexible (default [structure]); {args.duration:g} s from rest, bands over t >= "
             f"{args.skip:g} s; 10 log10(E_a / E_b) per third-octave band 100 Hz - 10 kHz; largest |dB| over the "
             "bands per sensor (band centre). Target (MuJoCo against the reference): |dB| <= 1.", "",
             "| test | compared | AC1 | AC2 | AC3 | AC4 | AC5 | AC6 | largest |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    centres = third_octave_centres()
    for tid in tests:
        def cfg(engine):
            return preset(tid).replace(**{"structure.mode": "flexible", "simulation.duration_s": args.duration,
                                          "simulation.engine": engine})
        runs = {"mujoco": twin.simulate(cfg("mujoco"))}
        for m in MODELS:
            c = cfg("reference")
            keep = Collector()
            simulate(c, [keep], engine=ReferenceEngine(c, ReferenceOptions(rod_model=m)))
            runs[m] = keep.run
            print(f"  test {tid}: reference {m} done", flush=True)
        rate = runs["mujoco"].rate_hz
        i0 = int(round(args.skip * rate))
        pairs = {f"mujoco / reference {m}": ("mujoco", m) for m in MODELS}
        pairs["reference chain / reference modal"] = ("chain", "modal")
        result["tests"][str(tid)] = {}
        for label, (a, b) in pairs.items():
            db = {s: band_difference_db(runs[a][s][i0:], runs[b][s][i0:], rate) for s in ACCELS}
            result["tests"][str(tid)][label] = {s: v.tolist() for s, v in db.items()}
            cells = []
            for s in ACCELS:
                i = int(np.nanargmax(np.abs(db[s])))
                cells.append(f"{abs(db[s][i]):.2f} ({centres[i]:.0f} Hz)")
            worst = max(float(np.nanmax(np.abs(db[s]))) for s in ACCELS)
            lines.append(f"| {tid} | {label} | " + " | ".join(cells) + f" | {worst:.2f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    out = write_stamped_text(args.out, text)
    atomic_write_text(out.with_suffix(".json"), json.dumps(stamped(result), indent=1) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
