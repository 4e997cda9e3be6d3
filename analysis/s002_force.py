"""S002's spatial scene with ``mujoco.contact_source = "force"`` beside ``"law"`` and the spatial reference.

Method: the ``s002`` preset at one clearance level for A, B and C (``--clearances``, diametral mm; S002's
radial levels 0.1, 0.4, 0.7 mm are 0.2, 0.8, 1.4), run for ``--duration`` seconds by the spatial reference
engine and by MuJoCo with the contact law on a contact row (``"law"``, the colliders of ``_bore.c`` and
``_socket.c``) and as a passive force (``"force"``: no pair, no row, the same law and friction). Accuracy as
``tests/test_spatial_engines.py`` measures it: the mean over whole crank turns (after the first) of each
joint's peak contact force and the slider acceleration's RMS, against the reference; the first contacts'
sample and peak (first 3 ms). Cost: MuJoCo's stepping time per step, both sources in this one process
(``--rounds`` alternations, the best of each), and their ratio.

Run: ``python analysis/s002_force.py [--clearances 0.2,1.4] [--duration 2.0] [--rounds 3]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def _cfg(engine: str, source: str | None, c: float, duration: float):
    from twin.config import named_preset

    o = {"simulation.engine": engine, "simulation.duration_s": duration, "joints.clearance_a_mm": c,
         "joints.clearance_b_mm": c, "joints.clearance_c_mm": c}
    if source:
        o["mujoco.contact_source"] = source
    return named_preset("s002").replace(**o)


def turn_statistics(run) -> dict[str, float]:
    """Mean per-turn peak contact force of A, B, C [N] (whole turns after the first), slider acc. RMS."""
    th = np.unwrap(np.asarray(run["crank_angle"], float))
    turn = np.floor((th - th[0]) / (2 * np.pi)).astype(int)
    edges = np.searchsorted(turn, np.arange(1, turn.max() + 1))
    out = {j: float(np.mean(np.maximum.reduceat(np.asarray(run[f"fn_{j}"]), edges)[:-1])) for j in "ABC"}
    a = np.asarray(run["slider_acceleration"], float)[turn >= 1]
    out["rms"] = float(np.sqrt(np.mean(a * a)))
    out["turns"] = int(turn.max()) - 1
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clearances", default="0.2,1.4")
    ap.add_argument("--duration", type=float, default=2.0)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()

    from twin import __version__
    from twin.provenance import git_commit
    from twin.simulation import simulate_run

    print(f"twin {__version__}, commit {git_commit()}; s002 preset, {args.duration:g} s per run")
    for c in (float(x) for x in args.clearances.split(",")):
        first = {k: simulate_run(_cfg(e, s, c, 0.003)) for k, e, s in
                 (("reference", "reference", None), ("law", "mujoco", "law"), ("force", "mujoco", "force"))}
        print(f"\n## {c:g} mm diametral (radial {c / 2:g} mm)\n\nfirst contacts (3 ms): " + "; ".join(
            f"{j}: sample " + "/".join(str(int(np.argmax(r[f'fn_{j}'] > 0))) for r in first.values()) +
            ", peak " + "/".join(f"{float(np.max(r[f'fn_{j}'])):.0f}" for r in first.values()) + " N"
            for j in "ABC") + " (reference/law/force)")
        ref = turn_statistics(simulate_run(_cfg("reference", None, c, args.duration)))
        best = {"law": np.inf, "force": np.inf}
        stats = {}
        for _ in range(args.rounds):
            for src in ("law", "force"):
                run = simulate_run(_cfg("mujoco", src, c, args.duration))
                best[src] = min(best[src], run.meta["wall_s"] / run.meta["steps"])
                stats[src] = turn_statistics(run)
        print(f"\n| source | turns | A | B | C | RMS slider acc. | µs per step |\n|---|---|---|---|---|---|---|")
        print(f"| reference | {ref['turns']} | {ref['A']:.0f} N | {ref['B']:.0f} N | {ref['C']:.0f} N | "
              f"{ref['rms']:.1f} m/s² | |")
        for src in ("law", "force"):
            s = stats[src]
            gaps = " | ".join(f"{100 * (s[q] / ref[q] - 1):+.1f} %" for q in ("A", "B", "C", "rms"))
            print(f"| {src} | {s['turns']} | {gaps} | {1e6 * best[src]:.2f} |")
        print(f"\nforce / law per step: {best['force'] / best['law']:.2f}x (best of {args.rounds}, side by side)")


if __name__ == "__main__":
    main()
