"""Test 3's engine gap in the 10 kHz band: controlled experiments on MuJoCo's loop closure at the ideal joint C.

With ideal joints (Table 4 test 3, flexible structure) MuJoCo closes the mechanism's loop with one equality, the
``connect`` at C (``mujoco.equality_solref`` = (τ, dampratio), ``mujoco.equality_solimp``), where the reference
engine's constraint is exact (natural coordinates, projected every step). Each row below runs MuJoCo and the
reference for ``--duration`` s from rest with the given step and overrides and compares AC3 and AC5 (third-octave
bands, Hann, bands over t >= ``--skip`` s, as ``analysis/structure_agreement.py``): 10 log10(E_mujoco / E_reference)
in the 10 kHz band and the largest |dB| over 100 Hz - 10 kHz with its band; the last columns give each engine's
10 kHz band of AC5 relative to AC5's strongest band (how little the band carries). The reference's own step error
is the first rows' (reference against reference).

Writes ``analysis/results/structure/closure.md`` with the versions and the commit.
Run: ``python analysis/structure_closure.py [--duration 0.6] [--skip 0.2]``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from twin.provenance import git_commit, write_stamped_text

FINE = 1.25e-6
#: (label, MuJoCo step [s], MuJoCo overrides, reference step [s], overrides of both)
ROWS = (
    ("default closure (τ 2e-5 s), default step", 1e-5, {}, 1e-5, {}),
    ("default closure, both at 2.5e-6 s", 2.5e-6, {}, 2.5e-6, {}),
    ("default closure, both at 1.25e-6 s", FINE, {}, FINE, {}),
    ("τ 1e-5 s, both at 2.5e-6 s", 2.5e-6, {"mujoco.equality_solref": (1e-5, 1.0)}, 2.5e-6, {}),
    ("τ 1e-5 s, MuJoCo at 5e-6 s, reference 2.5e-6 s", 5e-6, {"mujoco.equality_solref": (1e-5, 1.0)}, 2.5e-6, {}),
    ("τ 1e-5 s, both at 1.25e-6 s", FINE, {"mujoco.equality_solref": (1e-5, 1.0)}, FINE, {}),
    ("τ 5e-6 s, both at 1.25e-6 s", FINE, {"mujoco.equality_solref": (5e-6, 1.0)}, FINE, {}),
    ("τ 1e-5 s, impedance 0.9999 constant, 2.5e-6 s", 2.5e-6,
     {"mujoco.equality_solref": (1e-5, 1.0), "mujoco.equality_solimp": (0.9999, 0.9999, 1e-6, 0.5, 2.0)}, 2.5e-6, {}),
    ("τ 1e-5 s, impedance 0.99 constant, 2.5e-6 s", 2.5e-6,
     {"mujoco.equality_solref": (1e-5, 1.0), "mujoco.equality_solimp": (0.99, 0.99, 1e-6, 0.5, 2.0)}, 2.5e-6, {}),
    ("τ 1e-4 s (softer), default step", 1e-5, {"mujoco.equality_solref": (1e-4, 1.0)}, 1e-5, {}),
    ("default step, Newton tolerance 1e-15, 200 iterations", 1e-5,
     {"mujoco.tolerance": 1e-15, "mujoco.iterations": 200}, 1e-5, {}),
    ("τ 5e-6 s, no guide friction, 1.25e-6 s", FINE, {"mujoco.equality_solref": (5e-6, 1.0)}, FINE,
     {"mechanism.guide_friction_n": 0.0}),
    ("τ 5e-6 s, mounts at 30 kHz, 1.25e-6 s", FINE, {"mujoco.equality_solref": (5e-6, 1.0)}, FINE,
     {"structure.mount_frequency_hz": 30000.0}),
)


def _run(engine: str, step: float, over: dict, duration: float, skip: float) -> tuple[dict, float]:
    import twin
    from twin.config import preset

    cfg = preset(3).replace(**{"structure.mode": "flexible", "simulation.duration_s": duration,
                               "simulation.engine": engine, "simulation.timestep_s": step, **over})
    r = twin.simulate(cfg)
    i0 = int(round(skip * r.rate_hz))
    return {a: np.asarray(r[a])[i0:] for a in ("AC3", "AC5")}, r.rate_hz


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.6)
    ap.add_argument("--skip", type=float, default=0.2)
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "structure" / "closure.md"))
    args = ap.parse_args()
    import mujoco

    import twin
    from twin.structure.bands import band_difference_db, band_energies, third_octave_centres

    centres = third_octave_centres()
    refs: dict = {}

    def ref(step: float, over: dict):
        key = (step, tuple(sorted(over.items())))
        if key not in refs:
            refs[key] = _run("reference", step, over, args.duration, args.skip)
        return refs[key]

    def cells(a, b) -> list[str]:
        (x, rate), (y, _) = a, b
        out = []
        for s in ("AC3", "AC5"):
            d = band_difference_db(x[s], y[s], rate)
            i = int(np.argmax(np.abs(d)))
            out += [f"{d[-1]:+.2f}", f"{abs(d[i]):.2f} ({centres[i]:.0f} Hz)"]
        return out

    lines = ["| experiment | AC3 10 kHz [dB] | AC3 largest | AC5 10 kHz [dB] | AC5 largest | AC5 10 kHz band re its "
             "strongest, MuJoCo / reference [dB] |", "|---|---:|---:|---:|---:|---:|"]
    for step in (1e-5, 2.5e-6):
        row = cells(ref(step, {}), ref(FINE, {}))
        lines.append(f"| reference at {step:g} s against the reference at {FINE:g} s | " + " | ".join(row) + " | |")
        print(lines[-1], flush=True)
    for label, h_mj, over_mj, h_ref, over in ROWS:
        m = _run("mujoco", h_mj, {**over, **over_mj}, args.duration, args.skip)
        r = ref(h_ref, over)
        em, er = band_energies(m[0]["AC5"], m[1]), band_energies(r[0]["AC5"], r[1])
        lvl = f"{10 * np.log10(em[-1] / em.max()):.1f} / {10 * np.log10(er[-1] / er.max()):.1f}"
        lines.append(f"| {label} | " + " | ".join(cells(m, r)) + f" | {lvl} |")
        print(lines[-1], flush=True)
    commit = git_commit()
    head = (f"twin {twin.__version__}, MuJoCo {mujoco.__version__}, commit {commit or '?'}; Table 4 test 3 (ideal "
            f"joints), structure.mode = flexible (default [structure]); {args.duration:g} s from rest, bands over "
            f"t >= {args.skip:g} s; 10 log10(E_mujoco / E_reference) per third-octave band (100 Hz - 10 kHz).")
    text = "\n".join([head, ""] + lines) + "\n"
    out = write_stamped_text(args.out, text)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
