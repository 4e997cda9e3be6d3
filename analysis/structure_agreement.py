"""Engine agreement on the flexible structure's spectra: AC1–AC6 third-octave band energies, MuJoCo against the
reference, Table 4 tests 3, 6 and 12 (``structure.mode = "flexible"``, default ``[structure]`` fields).

Each scene runs in both engines for ``--duration`` s from rest; the band energies (Hann window, mean removed,
base-10 third-octave bands 100 Hz – 10 kHz, :mod:`twin.structure.bands`) of each accelerometer are taken over
the samples after ``--skip`` s (the start-up) and compared as 10 log10(E_mujoco / E_reference) per band. The
issue's target: every band within 1 dB. ``--set KEY=VALUE`` (repeatable) changes a field in both engines (e.g.
``contact.mu0=0`` to take the bores' friction out).

Writes ``analysis/results/structure/agreement.md`` (per test and sensor: the largest |dB| and the band where it
occurs; then every band) and the same numbers as JSON beside it, with the versions and the commit.

Run: ``python analysis/structure_agreement.py [--duration 0.6] [--skip 0.2] [--tests 3,6,12] [--set K=V]``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from twin.provenance import stamped, with_stamp_line

ACCELS = ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6")


def agreement(test: int, duration: float, skip: float, overrides: dict) -> dict:
    """{sensor: [dB per band]} for one Table 4 test (see the module docstring)."""
    import twin
    from twin.config import preset
    from twin.structure.bands import band_difference_db

    runs = {}
    for engine in ("mujoco", "reference"):
        cfg = preset(test).replace(**{"structure.mode": "flexible", "simulation.duration_s": duration,
                                      "simulation.engine": engine, **overrides})
        runs[engine] = twin.simulate(cfg)
    rate = runs["mujoco"].rate_hz
    i0 = int(round(skip * rate))
    return {a: band_difference_db(runs["mujoco"][a][i0:], runs["reference"][a][i0:], rate).tolist() for a in ACCELS}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.6)
    ap.add_argument("--skip", type=float, default=0.2)
    ap.add_argument("--tests", default="3,6,12")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "structure" / "agreement.md"))
    args = ap.parse_args()
    import mujoco

    import twin
    from twin.structure.bands import third_octave_centres
    from twin.util import toml_loads

    overrides = {}
    for item in args.set:
        k, v = item.split("=", 1)
        overrides[k.strip()] = toml_loads(f"v = {v}")["v"]
    centres = third_octave_centres()
    results = {}
    for t in (int(x) for x in args.tests.split(",")):
        results[t] = agreement(t, args.duration, args.skip, overrides)
        print(f"  test {t} done", flush=True)
    from twin.provenance import git_commit

    commit = git_commit()
    head = (f"twin {twin.__version__}, MuJoCo {mujoco.__version__}, commit {commit or '?'}; structure.mode = flexible "
            f"(default [structure]){', ' + ', '.join(f'{k} = {v}' for k, v in overrides.items()) if overrides else ''}; "
            f"{args.duration:g} s from rest, bands over t >= {args.skip:g} s; 10 log10(E_mujoco / E_reference) per "
            f"third-octave band, {centres[0]:.0f} Hz - {centres[-1]:.0f} Hz. Target: |dB| <= 1 in every band.")
    lines = [head, "", "| test | " + " | ".join(ACCELS) + " |", "|---|" + "---:|" * len(ACCELS)]
    for t, per in results.items():
        cells = []
        for a in ACCELS:
            d = per[a]
            i = max(range(len(d)), key=lambda k: abs(d[k]))
            cells.append(f"{abs(d[i]):.2f} ({centres[i]:.0f} Hz)")
        lines.append(f"| {t} | " + " | ".join(cells) + " |")
    lines += ["", "Largest |dB| per sensor (band centre). Every band:", ""]
    for t, per in results.items():
        lines += [f"Test {t}:", "", "| band [Hz] | " + " | ".join(ACCELS) + " |", "|---:|" + "---:|" * len(ACCELS)]
        for k, fc in enumerate(centres):
            lines.append(f"| {fc:.0f} | " + " | ".join(f"{per[a][k]:+.2f}" for a in ACCELS) + " |")
        lines.append("")
    text = "\n".join(lines)
    print(text)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_suffix(out.suffix + ".tmp")
    tmp.write_text(with_stamp_line(text))
    tmp.replace(out)
    js = out.with_suffix(".json")
    tmp = js.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(stamped({"header": head, "band_centres_hz": centres.tolist(),
                                       "db": {str(t): v for t, v in results.items()}}), indent=1))
    tmp.replace(js)
    print(f"wrote {out} and {out.with_suffix('.json')}")


if __name__ == "__main__":
    main()
