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

Run: ``python analysis/bench_dataset.py [--scene scaling|protocol] [--workers N] [--engine mujoco]``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time

from twin.dataset.generate import generate
from twin.dataset.spec import parse_spec


def spec_for(scene: str, engine: str, truth: list[str]) -> dict:
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
            "base": {"test": 1, "engine": engine, "duration_s": 0.0, "program": "protocol"},
            "design": {"kind": "list", "repeats": 5, "points": [
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

    peak = max(json.load(open(os.path.join(out, "results", f"{r['run_id']}.json")))["peak_rss_mb"] for r in runs)
    sim = sum(r["simulated_s"] for r in runs)
    size = sum(r["bytes"] for r in runs)
    shutil.rmtree(out)
    return {"workers": workers, "runs": len(runs), "ok": info["runs"]["ok"], "wall_s": wall, "sim_s": sim,
            "throughput": sim / wall, "runs_per_hour_core": len(runs) / (wall / 3600) / workers,
            "bytes_per_sim_s": size / sim, "peak_rss_mb": peak, "size_mb": size / 1e6}


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
    args = ap.parse_args()
    truth = [g for g in args.truth.split(",") if g]
    spec = parse_spec(spec_for(args.scene, args.engine, truth))
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


if __name__ == "__main__":
    main()
