"""PGS against Newton for MuJoCo's flexible structure at full speed: band energies against the reference engine and
against the scene's own sensitivity, side by side.

For Table 4 tests 3, 6 and 12 (``structure.mode = "flexible"``, default fields, default step) this script runs
``--duration`` s from rest (the drive's ramp ends at 0.5 s) and takes AC1–AC6's third-octave band energies
(100 Hz – 10 kHz, :mod:`twin.structure.bands`) over t >= ``--skip`` s, i.e. at full speed, where the impacts
make the scene chaotic and any change of a solver's round-off grows to O(1) in the time series. Runs: MuJoCo with
``mujoco.flexible_solver`` "PGS" and "Newton", each again with the slider's mass changed by a relative
``--perturb`` (the scene's own sensitivity: what any perturbation of round-off size does to the bands), and the
reference engine. It prints, per test, the largest |dB| over the sensors and bands of: PGS against Newton, each
solver against its own perturbed run (the noise floor a solver change must be judged against), and each solver
against the reference (the accuracy against an independent engine).

Run: ``python analysis/structure_solver_bands.py [--duration 1.1] [--skip 0.6] [--tests 3,6,12] [--perturb 1e-9]``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

ACCELS = ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=1.1)
    ap.add_argument("--skip", type=float, default=0.6)
    ap.add_argument("--tests", default="3,6,12")
    ap.add_argument("--perturb", type=float, default=1e-9)
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "structure" / "solver_bands.md"))
    a = ap.parse_args()
    import mujoco

    import twin
    from twin.config import preset
    from twin.provenance import git_commit, write_stamped_text
    from twin.structure.bands import band_difference_db
    from twin.provenance import stamped
    from twin.util import atomic_write_text

    rows = []
    raw = {}
    for test in (int(x) for x in a.tests.split(",")):
        base = preset(test).replace(**{"structure.mode": "flexible", "simulation.duration_s": a.duration})
        m0 = base.bodies.slider.mass_kg
        arms = {"PGS": {"mujoco.flexible_solver": "PGS"}, "Newton": {"mujoco.flexible_solver": "Newton"}}
        arms.update({f"{k} perturbed": {**v, "bodies.slider.mass_kg": m0 * (1 + a.perturb)} for k, v in list(arms.items())})
        arms["reference"] = {"simulation.engine": "reference"}
        runs = {k: twin.simulate(base.replace(**v)) for k, v in arms.items()}
        rate = runs["PGS"].rate_hz
        i0 = int(round(a.skip * rate))

        def worst(x: str, y: str) -> tuple[float, str]:
            best = (0.0, "")
            for s in ACCELS:
                d = band_difference_db(np.asarray(runs[x][s][i0:], float), np.asarray(runs[y][s][i0:], float), rate)
                k = int(np.argmax(np.abs(d)))
                if abs(d[k]) > best[0]:
                    best = (float(abs(d[k])), s)
                raw[f"{test} {x} / {y} {s}"] = d.tolist()
            return best

        pairs = [("PGS", "Newton"), ("Newton perturbed", "Newton"), ("PGS perturbed", "PGS"),
                 ("PGS", "reference"), ("Newton", "reference")]
        rows.append((test, [worst(x, y) for x, y in pairs]))
        print(f"  test {test} done", flush=True)
    commit = git_commit()
    lines = [f"twin {twin.__version__}, MuJoCo {mujoco.__version__}, commit {commit or '?'}; structure.mode = flexible, "
             f"default step; {a.duration:g} s from rest, bands over t >= {a.skip:g} s (full speed); largest "
             f"|10 log10(E_x / E_y)| over AC1-AC6 and the third-octave bands 100 Hz - 10 kHz (sensor); perturbed = "
             f"the slider's mass x (1 + {a.perturb:g}).", "",
             "| test | PGS / Newton | Newton perturbed / Newton (noise) | PGS perturbed / PGS (noise) | "
             "PGS / reference | Newton / reference |", "|---|---:|---:|---:|---:|---:|"]
    for test, cells in rows:
        lines.append(f"| {test} | " + " | ".join(f"{v:.2f} ({s})" for v, s in cells) + " |")
    text = "\n".join(lines) + "\n"
    print(text)
    out = write_stamped_text(a.out, text)
    atomic_write_text(out.with_suffix(".json"), json.dumps(stamped({"bands": raw})))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
