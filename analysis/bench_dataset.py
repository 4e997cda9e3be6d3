"""Dataset generation speed: scaling over workers, runs per hour, bytes per simulated second, memory.

Method: the same spec is generated from scratch (a new folder each time) with 1 worker and with
N workers (``twin.dataset.generate.generate``, the code ``twin dataset generate`` runs), in one
run of this script, so the ratio is measured side by side on the same machine state.

* throughput = simulated seconds / wall seconds of the whole generation (process start-up,
  planning, manifest and statistics included);
* scaling efficiency = throughput(N) / (N × throughput(1));
* runs per hour per core = runs / wall hours / N;
* bytes per simulated second = data files' bytes / simulated seconds;
* peak memory per worker = the largest ``ru_maxrss`` a worker reported (resident set of the worker
  process, imports included);
* the machine's own parallel efficiency, as a baseline measured in the same run: N plain
  ``twin simulate`` processes of the same scene started together against one alone (a 2-vCPU
  virtual machine whose vCPUs share a core gives well under 2x; no dataset code can beat that).

Scenes: ``--scene scaling`` (default): Table 4 tests 4–12 at their constant speeds, 2 s each with
the instrumented channels (9 runs, 18 s simulated). ``--scene protocol``: the issue's target,
Table 4 × 5 repeats of the 38 s protocol (60 runs, 2,280 s simulated) with the instrumented
channels, on N workers only (``--workers``; about 15-20 min on 2 cores).

``--compare``: the protocol dataset (``--repeats`` R of the Table 4 tests ``--tests``, default all
twelve x 5) generated in this run by the MuJoCo twin with ``mujoco.contact_source = "law"``,
``"force"`` and ``"force"`` with warm starts (the repeats of a design point share one engine run) and
by the reference engine without and with warm starts, interleaved in slices of ``--workers`` design
points: wall times stage by stage and the ratios twin / reference; then the first
``--nuisance-limit`` runs of a nuisance identification spec (its design cut to that many points)
with and without warm starts.

Run: ``python analysis/bench_dataset.py [--scene scaling|protocol] [--workers N] [--engine mujoco]
[--compare --repeats R --tests 4,12 --nuisance-limit K]``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time

from twin.dataset.generate import generate
from twin.dataset.spec import parse_spec


def spec_for(scene: str, engine: str, truth: list[str], contact_source: str = "law", repeats: int = 5) -> dict:
    if scene == "scaling":
        return {"dataset": {"name": "bench-scaling", "seed": 1},
                "base": {"test": 4, "engine": engine, "duration_s": 2.0, "set": {"drive.ramp_s": 0.3}},
                "design": {"kind": "list", "points": [
                    {"clearance_b_mm": b, "clearance_c_mm": c, "motor_rpm": rpm}
                    for b, c, rpm in [(0.0, 0.1, 250.0), (0.0, 0.1, 500.0), (0.0, 0.1, 750.0),
                                      (0.1, 0.0, 250.0), (0.1, 0.0, 500.0), (0.1, 0.0, 750.0),
                                      (0.1, 0.1, 250.0), (0.1, 0.1, 500.0), (0.1, 0.1, 750.0)]]},
                "outputs": {"truth": truth, "instrumented": True}}
    from twin.config import TABLE4

    return {"dataset": {"name": "bench-protocol", "seed": 1},
            "base": {"test": 1, "engine": engine, "duration_s": 0.0, "program": "protocol",
                     "set": {"mujoco.contact_source": contact_source}},
            "design": {"kind": "list", "repeats": repeats, "points": [
                {"clearance_b_mm": b, "clearance_c_mm": c, "motor_rpm": rpm} for b, c, rpm in TABLE4.values()]},
            "outputs": {"truth": truth, "instrumented": True}}


def measure(spec, workers: int, work: str) -> dict:
    out = os.path.join(work, f"w{workers}")
    t = time.perf_counter()
    info = generate(spec, out, workers=workers, progress=True)
    wall = time.perf_counter() - t
    import pyarrow.parquet as pq

    runs = pq.read_table(os.path.join(out, "runs.parquet")).to_pylist()
    import json

    results = [json.load(open(os.path.join(out, "results", f"{r['run_id']}.json"))) for r in runs]
    peak = max(x["peak_rss_mb"] for x in results)
    engine_s = sum(x.get("sim_wall_s") or 0.0 for x in results)  # the engines' own stepping
    run_s = sum(x.get("wall_s") or 0.0 for x in results)  # each run in its worker: engine, sensor chain, writer
    sim = sum(r["simulated_s"] for r in runs)
    size = sum(r["bytes"] for r in runs)
    shutil.rmtree(out)
    return {"workers": workers, "runs": len(runs), "ok": info["runs"]["ok"], "wall_s": wall, "sim_s": sim,
            "throughput": sim / wall, "runs_per_hour_core": len(runs) / (wall / 3600) / workers,
            "bytes_per_sim_s": size / sim, "peak_rss_mb": peak, "size_mb": size / 1e6, "engine_s": engine_s,
            "run_s": run_s}


def machine_efficiency(workers: int, duration: float = 4.0) -> float:
    """wall(1 process) / wall(N processes at once) of the same plain simulation, times N / N."""
    import subprocess
    import sys

    argv = [sys.executable, "-m", "twin.cli", "simulate", "--test", "12", "--duration", f"{duration:g}", "--no-out",
            "--no-progress"]

    def wall(n: int) -> float:
        t = time.perf_counter()
        procs = [subprocess.Popen(argv, stdout=subprocess.DEVNULL) for _ in range(n)]
        for p in procs:
            p.wait()
        return time.perf_counter() - t

    wall(1)  # warm the file cache
    return wall(1) / wall(workers)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", choices=("scaling", "protocol"), default="scaling")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--engine", choices=("mujoco", "reference"), default="mujoco")
    ap.add_argument("--truth", default="", help="truth channel groups stored besides the instrumented ones "
                                                 "(comma-separated; default none: the sensor chain needs "
                                                 "accel and encoder, which the engine computes anyway)")
    ap.add_argument("--compare", action="store_true",
                    help="protocol scene: the MuJoCo twin with contact_source \"law\" and \"force\" and the "
                         "reference engine, one after another in this run (ratios side by side)")
    ap.add_argument("--repeats", type=int, default=5, help="protocol scene: repeats of Table 4 (default 5)")
    ap.add_argument("--tests", default="1,2,3,4,5,6,7,8,9,10,11,12",
                    help="--compare: the Table 4 tests of the protocol dataset (default all twelve)")
    ap.add_argument("--nuisance", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "datasets",
                                                       "clearance_id_nuisance.toml"),
                    help="--compare: the identification spec whose first runs are generated with and without warm "
                         "starts")
    ap.add_argument("--nuisance-limit", type=int, default=4,
                    help="--compare: that spec's design cut to this many points (0: skip)")
    args = ap.parse_args()
    truth = [g for g in args.truth.split(",") if g]
    if args.compare:
        compare(args.workers, truth, args.repeats, [int(t) for t in args.tests.split(",")], args.nuisance,
                args.nuisance_limit)
        return
    spec = parse_spec(spec_for(args.scene, args.engine, truth, repeats=args.repeats))
    work = tempfile.mkdtemp(prefix="twin_bench_ds_")
    try:
        counts = (1, args.workers) if args.scene == "scaling" and args.workers > 1 else (args.workers,)
        rows = [measure(spec, w, work) for w in counts]
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"\n{args.scene}: {rows[0]['runs']} runs, {rows[0]['sim_s']:.0f} s simulated, engine {args.engine}, "
          f"instrumented channels{' + ' + ','.join(truth) if truth else ''}, {os.cpu_count()} cores")
    print("| workers | wall s | sim s / wall s | runs/h/core | MB | bytes / sim s | peak RSS / worker MB |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['workers']} | {r['wall_s']:.1f} | {r['throughput']:.2f} | {r['runs_per_hour_core']:.0f} | "
              f"{r['size_mb']:.0f} | {r['bytes_per_sim_s'] / 1e6:.2f} M | {r['peak_rss_mb']:.0f} |")
    if len(rows) == 2:
        eff = rows[1]["throughput"] / (rows[1]["workers"] * rows[0]["throughput"])
        mach = machine_efficiency(rows[1]["workers"])
        print(f"scaling efficiency {rows[1]['workers']} workers vs 1: {eff * 100:.0f} %; the machine's own, "
              f"{rows[1]['workers']} plain 'twin simulate' processes at once vs one: {mach * 100:.0f} %; "
              f"the dataset's relative to the machine's: {eff / mach * 100:.0f} %")


#: the variants of --compare: (engine, contact_source, warm start)
VARIANTS = [("mujoco", "law", False), ("mujoco", "force", False), ("mujoco", "force", True),
            ("reference", "law", False), ("reference", "law", True)]


def _label(v) -> str:
    engine, source, warm = v
    return f"{engine}{'/' + source if engine == 'mujoco' else ''}{' + warm' if warm else ''}"


def measure_warm(spec, workers: int, work: str, warm: bool, limit: int | None = None) -> dict:
    """One generation of ``spec`` (with or without warm starts), timed, folder removed after."""
    import json

    out = os.path.join(work, f"g{'w' if warm else 'c'}")
    t = time.perf_counter()
    info = generate(spec, out, workers=workers, progress=False, warm_start=warm, limit=limit)
    wall = time.perf_counter() - t
    results = [json.load(open(os.path.join(out, "results", f))) for f in sorted(os.listdir(os.path.join(out, "results")))]
    shutil.rmtree(out)
    return {"wall_s": wall, "runs": len(results), "ok": sum(r["status"] == "ok" for r in results),
            "sim_s": sum(r.get("simulated_s") or 0.0 for r in results),
            "engine_s": sum(r.get("sim_wall_s") or 0.0 for r in results),
            "run_s": sum(r.get("wall_s") or 0.0 for r in results),
            "engine_runs": info["generation"]["engine_runs_this_call"]}


def _stamp() -> str:
    import mujoco

    from twin import __version__
    from twin.provenance import git_commit

    commit = git_commit()
    return f"twin {__version__}, MuJoCo {mujoco.__version__}, commit {commit or '?'}, {os.cpu_count()} cores"


def compare(workers: int, truth: list[str], repeats: int, tests: list[int], nuisance: str, nuisance_limit: int) -> None:
    """The protocol dataset (Table 4 tests ``tests`` x ``repeats``) generated by each of
    :data:`VARIANTS` in this one run, on ``workers`` workers, interleaved: the design points are cut
    into slices of ``workers`` points (with all their repeats, so that a warm start finds its group
    whole), and each slice is generated by every variant in turn (a dataset of its own, so process
    and planning overheads are counted as in a whole one), so that the machine's load hits them
    alike. Wall times summed per variant, split into the engines' stepping, the rest of the runs
    (sensor chain, Parquet writer) and the driver, and their ratios to the reference engine's. Then
    the nuisance identification spec ``nuisance`` with its design cut to ``nuisance_limit`` points,
    with and without warm starts, side by side."""
    from pathlib import Path

    from twin.config import TABLE4

    print(_stamp(), flush=True)
    points = [{"clearance_b_mm": TABLE4[t][0], "clearance_c_mm": TABLE4[t][1], "motor_rpm": TABLE4[t][2]} for t in tests]
    slices = [points[i:i + workers] for i in range(0, len(points), workers)]
    keys = ("wall_s", "sim_s", "runs", "engine_s", "run_s", "engine_runs")
    rows = {v: dict.fromkeys(keys, 0.0) for v in VARIANTS}
    work = tempfile.mkdtemp(prefix="twin_bench_ds_")
    try:
        for k, pts in enumerate(slices):
            for v in VARIANTS:
                engine, source, warm = v
                raw = spec_for("protocol", engine, truth, source, repeats)
                raw["design"]["points"] = pts
                raw["dataset"]["name"] = f"bench-protocol-{k}"
                r = measure_warm(parse_spec(raw), workers, work, warm)
                if r["ok"] != r["runs"]:
                    raise SystemExit(f"{_label(v)}: {r['runs'] - r['ok']} runs failed")
                for key in keys:
                    rows[v][key] += r[key]
            print(f"slice {k + 1}/{len(slices)}: " + ", ".join(f"{_label(v)} {rows[v]['wall_s']:.0f} s" for v in VARIANTS),
                  flush=True)
        nuis = []
        if nuisance_limit > 0:
            # the spec with its design cut to nuisance_limit points (planning its 1600 runs alone takes 1-2 min)
            from twin.dataset.spec import read_spec_toml

            raw = read_spec_toml(Path(nuisance))
            raw["design"]["runs"] = nuisance_limit
            spec = parse_spec(raw, source=nuisance)
            for warm in (False, True, False, True):  # interleaved twice
                nuis.append((warm, measure_warm(spec, workers, work, warm)))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    ref = rows[("reference", "law", False)]["wall_s"]
    r0 = rows[VARIANTS[0]]
    print(f"\nprotocol dataset: Table 4 tests {','.join(map(str, tests))} x {repeats} repeats, {r0['runs']:.0f} runs, "
          f"{r0['sim_s']:.0f} s simulated, {workers} workers, instrumented channels"
          f"{' + ' + ','.join(truth) if truth else ''}, interleaved in slices of {workers} design points")
    print("| variant | engine runs | wall s | sim s / wall s | wall / reference's | engine stepping s (sum over runs) | "
          "rest of the runs s (sensor chain, writer) | driver s (wall - run s / workers) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for v, r in rows.items():
        print(f"| {_label(v)} | {r['engine_runs']:.0f} | {r['wall_s']:.1f} | {r['sim_s'] / r['wall_s']:.2f} | "
              f"{r['wall_s'] / ref:.2f} | {r['engine_s']:.1f} | {r['run_s'] - r['engine_s']:.1f} | "
              f"{r['wall_s'] - r['run_s'] / workers:.1f} |")
    fw, rw = rows[("mujoco", "force", True)]["wall_s"], rows[("reference", "law", True)]["wall_s"]
    print(f"\nwarm starts save: mujoco/force {1 - fw / rows[('mujoco', 'force', False)]['wall_s']:.0%} of the wall time, "
          f"reference {1 - rw / ref:.0%}; mujoco/force + warm / reference + warm = {fw / rw:.2f}")
    if nuis:
        print(f"\nnuisance identification spec {os.path.basename(nuisance)} cut to {nuisance_limit} design points "
              f"(its factors and ranges), {workers} workers, without and with warm starts, interleaved twice")
        print("| warm start | engine runs | wall s | engine stepping s | rest of the runs s |")
        print("|---|---:|---:|---:|---:|")
        for warm, r in nuis:
            print(f"| {'on' if warm else 'off'} | {r['engine_runs']} | {r['wall_s']:.1f} | {r['engine_s']:.1f} | "
                  f"{r['run_s'] - r['engine_s']:.1f} |")


if __name__ == "__main__":
    main()
