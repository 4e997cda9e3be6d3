"""Cost of the flexible structure: time per simulated second, flexible over rigid, for Table 4 tests 3, 6, 12.

For each test (``--tests``, default 3, 6 and 12: ideal, C only, B+C 0.1 mm; 750 motor rpm) and each engine
(MuJoCo with each contact source, the reference with its chain rod and with its modal rod,
``reference.rod_model``), this script builds the engine and runs its chunk loop for
``--duration`` simulated seconds with ``structure.mode = "rigid"`` and ``"flexible"`` (the default ``[structure]``
fields), interleaved round by round so that machine load hits every variant alike, and keeps the best of
``--rounds`` of the chunk loop's wall time (``meta["wall_s"]``: stepping, channels, mount filter; not the model's
build) and of its CPU time (``time.process_time``: the same loop, without the time spent waiting for a core,
the steadier figure on a shared machine). It prints a Markdown table (µs per step, real-time factor, ratio
flexible / rigid per engine, by wall and by CPU time) and writes it, with the versions and the commit, to
``analysis/results/structure/bench_structure.md``. The issue's target: flexible at most 1.5× rigid in each
engine (test 12).

``--compare KEY=VALUE`` (repeatable) adds a second flexible arm with those ``[structure]`` overrides (a dotted
``section.field`` key is taken as it stands), timed in the same rounds (e.g. the former default chain:
``--compare rod_chain='"uniform"' --compare rod_segments=6``; MuJoCo's Newton solver instead of PGS:
``--compare mujoco.flexible_solver='"Newton"'``), and a column with its CPU-time ratio to rigid. ``--mujoco-only``
leaves the reference engine out, ``--reference-only`` the MuJoCo engine.

Run: ``python analysis/bench_structure.py [--duration S] [--rounds R] [--tests 3,6,12] [--compare K=V] [--mujoco-only | --reference-only]``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from twin.provenance import git_commit, write_stamped_text

VARIANTS = {  # label: (engine, extra overrides)
    "mujoco (contact law rows)": ("mujoco", {}),
    "mujoco (contact as force)": ("mujoco", {"mujoco.contact_source": "force"}),
    "reference": ("reference", {}),
    "reference (modal rod)": ("reference", {}),
}
#: reference-engine options of a variant (:class:`twin.reference.engine.ReferenceOptions`; not configuration fields)
REFERENCE_OPTIONS = {"reference (modal rod)": {"rod_model": "modal"}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.3, help="simulated time per run [s]")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--tests", default="3,6,12", help="Table 4 tests, comma-separated")
    ap.add_argument("--compare", action="append", default=[], metavar="KEY=VALUE",
                    help="[structure] override of a second flexible arm (repeatable)")
    ap.add_argument("--mujoco-only", action="store_true", help="leave the reference engine out")
    ap.add_argument("--reference-only", action="store_true", help="leave the MuJoCo engine out")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "structure" / "bench_structure.md"))
    args = ap.parse_args()

    import mujoco
    import numba

    from twin.config import preset
    from twin.simulation import make_engine, run_chunks, simulate

    from twin.util import toml_loads

    tests = [int(t) for t in args.tests.split(",")]
    if args.mujoco_only and args.reference_only:
        ap.error("--mujoco-only and --reference-only exclude each other")
    variants = {k: v for k, v in VARIANTS.items() if not (args.mujoco_only and v[0] != "mujoco")
                and not (args.reference_only and v[0] != "reference")}
    compare = {(k.strip() if "." in k else f"structure.{k.strip()}"): toml_loads(f"v = {v}")["v"]
               for k, v in (item.split("=", 1) for item in args.compare)}
    modes = {"rigid": {"structure.mode": "rigid"}, "flexible": {"structure.mode": "flexible"}}
    if compare:
        modes["compared"] = {"structure.mode": "flexible", **compare}
    best: dict[tuple[int, str, str], float] = {}
    best_cpu: dict[tuple[int, str, str], float] = {}
    steps: dict[tuple[int, str, str], int] = {}
    from twin.reference.engine import ReferenceEngine, ReferenceOptions

    def engine_of(label, cfg):
        opts = REFERENCE_OPTIONS.get(label)
        return make_engine(cfg) if opts is None else ReferenceEngine(cfg, ReferenceOptions(**opts))

    for label, (cfg_engine, over) in variants.items():  # warm-up: numba's cache, MuJoCo's first rollouts
        cfg = preset(tests[-1]).replace(**{"simulation.engine": cfg_engine, "simulation.duration_s": 0.01,
                                           "structure.mode": "flexible", **over})
        simulate(cfg, engine=engine_of(label, cfg))
    for r in range(args.rounds):
        for tid in tests:
            for label, (engine, over) in variants.items():
                for mode, mode_over in modes.items():
                    cfg = preset(tid).replace(**{"simulation.engine": engine, "simulation.duration_s": args.duration,
                                                 **mode_over, **over})
                    eng = engine_of(label, cfg)   # the model's build outside the clocks
                    c0 = time.process_time()
                    for _ in run_chunks(cfg, eng):
                        pass
                    cpu = time.process_time() - c0
                    meta = eng.meta
                    key = (tid, label, mode)
                    best[key] = min(best.get(key, float("inf")), meta["wall_s"])
                    best_cpu[key] = min(best_cpu.get(key, float("inf")), cpu)
                    steps[key] = meta["steps"]
        print(f"  round {r + 1}/{args.rounds} done", flush=True)
    commit = git_commit()
    import twin

    lines = [f"twin {twin.__version__}, MuJoCo {mujoco.__version__}, numba {numba.__version__}, commit {commit or '?'}; "
             f"Table 4 tests {', '.join(map(str, tests))} (3 ideal, 6 C 0.1 mm, 12 B+C 0.1 mm; 750 motor rpm) from "
             f"rest, {args.duration:g} s simulated, h = 1e-5 s, "
             f"best of {args.rounds} interleaved rounds; wall time of the chunk loop (stepping, channels, mount filter).",
             "",
             "| test | engine | rigid µs/step | flexible µs/step | rigid RTF | flexible RTF | flexible / rigid "
             "| flexible / rigid, CPU time |" + (" compared / rigid, CPU time |" if compare else ""),
             "|---:|---|---:|---:|---:|---:|---:|---:|" + ("---:|" if compare else "")]
    if compare:
        lines.insert(1, "Compared arm: flexible with " + ", ".join(f"{k} = {v!r}" for k, v in compare.items()) + ".")
    for tid in tests:
        for label in variants:
            r, f = best[(tid, label, "rigid")], best[(tid, label, "flexible")]
            us_r, us_f = r / steps[(tid, label, "rigid")] * 1e6, f / steps[(tid, label, "flexible")] * 1e6
            lines.append(f"| {tid} | {label} | {us_r:.2f} | {us_f:.2f} | {args.duration / r:.2f} | "
                         f"{args.duration / f:.2f} | {f / r:.2f} | "
                         f"{best_cpu[(tid, label, 'flexible')] / best_cpu[(tid, label, 'rigid')]:.2f} |"
                         + (f" {best_cpu[(tid, label, 'compared')] / best_cpu[(tid, label, 'rigid')]:.2f} |"
                            if compare else ""))
    lines += ["", "Target (test 12): flexible / rigid <= 1.5 in each engine."]
    text = "\n".join(lines) + "\n"
    print(text)
    out = write_stamped_text(args.out, text)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
