"""The stability campaign's flexible scenes in MuJoCo with PGS and with Newton, side by side.

Scenes ``--first`` … ``--first + --scenes - 1`` of seed ``--seed`` (``twin study stability --structure``'s draws:
clearances, orientation, drive program, timestep, contact perturbations and every ``[structure]`` placeholder over
its documented range), each run in MuJoCo with ``mujoco.flexible_solver`` "PGS" and "Newton" and measured with the
campaign's own metrics (:func:`twin.studies.stability.scene_metrics`: divergence, warnings, pen/c, crank tracking,
energy balance). Prints and writes (``--out``) the two solvers' counts and the largest per-scene differences of
pen/c and of the energy residual. The converged-reference check of the campaign (which sorts pen/c > 0.25 into
physical and numerical) is not repeated: it does not depend on MuJoCo's solver.

Run: ``python analysis/structure_solver_stability.py [--scenes 500] [--seed 1] [--durations 0.05 0.2]``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import time
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=500)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--durations", type=float, nargs=2, default=(0.05, 0.2))
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "structure" / "solver_stability.md"))
    a = ap.parse_args()
    import mujoco

    import twin
    from twin.provenance import write_stamped_text
    from twin.errors import SimulationError
    from twin.simulation import simulate_run
    from twin.studies.stability import PEN_LIMIT, sample_scene, scene_config, scene_inputs, scene_metrics
    from twin.provenance import stamped
    from twin.util import atomic_write_text

    solvers = ("PGS", "Newton")
    rows = []
    t0 = time.perf_counter()
    for i in range(a.first, a.first + a.scenes):
        sc = sample_scene(a.seed, i, tuple(a.durations), structure=True)
        row = {"index": i}
        for s in solvers:
            cfg = scene_config(sc).replace(**{"mujoco.flexible_solver": s})
            try:
                met = scene_metrics(simulate_run(cfg, inputs=scene_inputs(sc)), cfg, sc)
            except SimulationError as err:
                met = {"diverged": True, "error": str(err), "max_pen_over_c": float("nan")}
            row[s] = {k: met.get(k) for k in ("diverged", "warnings", "max_pen_over_c", "energy_created",
                                               "residual_rel", "residual_min_rel", "tracking_max_rad")}
        rows.append(row)
        if (i - a.first + 1) % 50 == 0:
            print(f"  {i - a.first + 1}/{a.scenes} scenes ({time.perf_counter() - t0:.0f} s)", flush=True)

    def count(s: str, f) -> int:
        return sum(1 for r in rows if f(r[s]))

    lines = [f"twin {twin.__version__}, MuJoCo {mujoco.__version__}, commit "
             f"{subprocess.run(['git', 'describe', '--always', '--dirty'], capture_output=True, text=True, cwd=Path(__file__).resolve().parent).stdout.strip() or '?'}; "
             f"stability scenes {a.first}-{a.first + a.scenes - 1} of seed {a.seed}, structure drawn, durations "
             f"{a.durations[0]:g}-{a.durations[1]:g} s, MuJoCo only.", "",
             "| solver | scenes | diverged (or warnings) | energy created | pen/c > 0.25 | largest pen/c | "
             "most negative min R/W+ | largest tracking error [rad] |", "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for s in solvers:
        ok = [r[s] for r in rows if not r[s]["diverged"]]
        lines.append(f"| {s} | {len(rows)} | {count(s, lambda m: m['diverged'])} | "
                     f"{count(s, lambda m: bool(m.get('energy_created')))} | "
                     f"{count(s, lambda m: (m['max_pen_over_c'] or 0) > PEN_LIMIT)} | "
                     f"{max(m['max_pen_over_c'] for m in ok):.3f} | {min(m['residual_min_rel'] for m in ok):.2e} | "
                     f"{max(m['tracking_max_rad'] for m in ok):.2e} |")
    both = [r for r in rows if not r["PGS"]["diverged"] and not r["Newton"]["diverged"]]
    dpen = max(abs(r["PGS"]["max_pen_over_c"] - r["Newton"]["max_pen_over_c"]) for r in both)
    dres = max(abs(r["PGS"]["residual_rel"] - r["Newton"]["residual_rel"]) for r in both)
    flips = [r["index"] for r in both if (r["PGS"]["max_pen_over_c"] > PEN_LIMIT) != (r["Newton"]["max_pen_over_c"] > PEN_LIMIT)]
    lines += ["", f"Per scene, PGS against Newton: largest |Δ pen/c| {dpen:.2e}, largest |Δ R/W+| {dres:.2e}; scenes "
              f"whose pen/c criterion differs: {flips or 'none'}."]
    text = "\n".join(lines) + "\n"
    print(text)
    out = write_stamped_text(a.out, text)
    atomic_write_text(out.with_suffix(".json"), json.dumps(stamped({"scenes": rows}), default=str))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
