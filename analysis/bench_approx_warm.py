"""Saving of the approximate warm starts on a slice of the nuisance identification spec, side by side.

Method: the nuisance spec (``analysis/datasets/clearance_id_nuisance.toml``: every run its own mechanism, so the
exact warm starts share nothing) is planned and grouped as ``twin dataset generate --approx-warm-start`` groups it
(:func:`twin.warm_approx.approx_groups`: 1,600 runs in 204 groups). ``--groups`` whole groups of the median size
are taken, and each is generated twice through the dataset worker (``twin.dataset.worker.run_one``: engine,
sensor chain, Parquet file), in this one process, alternating: every run from rest (the default), and the group
sharing one spin-up. Printed: the wall time of each arm, the engine's stepping time, and the ratios; the
expected engine ratio (1 + (n − 1)(T − t_switch)/T)/n for a group of n runs of T s.

Run: ``python analysis/bench_approx_warm.py [--groups 2]``.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spec", default="analysis/datasets/clearance_id_nuisance.toml")
    ap.add_argument("--groups", type=int, default=2)
    args = ap.parse_args()

    from twin import __version__
    from twin.dataset.generate import group_tasks, prepare
    from twin.dataset.spec import load_spec
    from twin.dataset.worker import run_one
    from twin.provenance import git_commit
    from twin.warm_approx import approx_groups, switch_time

    spec = load_spec(args.spec)
    tmp = Path(tempfile.mkdtemp(prefix="bench_approx_"))
    try:
        p = prepare(spec, tmp / "ds")
        (tmp / "ds" / "data").mkdir(parents=True)
        groups = approx_groups([r.config for r in p.runs])
        sizes = np.array([len(g) for g in groups])
        med = int(np.median(sizes))
        pick = [g for g in groups if len(g) == med][:args.groups]
        print(f"twin {__version__}, commit {git_commit()}; {args.spec}: {len(p.runs)} runs in {len(groups)} approximate "
              f"groups (sizes {sizes.min()}-{sizes.max()}, median {med}); {len(pick)} groups of {med} runs")
        wall = {"fresh": 0.0, "approx": 0.0}
        sim = {"fresh": 0.0, "approx": 0.0}
        expect_num = expect_den = 0.0
        for g in pick:
            runs = [p.runs[i] for i in g]
            for arm in ("fresh", "approx"):
                tasks = group_tasks(p, runs, warm_start=False, approx_warm_start=arm == "approx")
                t = time.perf_counter()
                for task in tasks:
                    res = run_one(task)
                    for r in (res["group"] if "group" in res else [res]):
                        if r["status"] != "ok":
                            raise SystemExit(f"run {r['run_id']}: {r['reason']}")
                        sim[arm] += r.get("sim_wall_s") or 0.0
                wall[arm] += time.perf_counter() - t
                for f in (tmp / "ds" / "data").glob("*.parquet"):
                    f.unlink()
            T, ts = runs[0].config.duration_s, switch_time(runs[0].config)
            expect_num += T + (len(g) - 1) * (T - ts)
            expect_den += len(g) * T
            print(f"group of {len(g)} ({runs[0].config.drive.motor_rpm:g} rpm, {runs[0].config.mechanism.orientation} "
                  f"vertical, {runs[0].config.joints.clearance_joints or 'no clearance'}): wall so far fresh "
                  f"{wall['fresh']:.1f} s, approx {wall['approx']:.1f} s", flush=True)
        print("\n| arm | wall [s] | engine stepping [s] |\n|---|---|---|")
        for arm in ("fresh", "approx"):
            print(f"| {arm} | {wall[arm]:.1f} | {sim[arm]:.1f} |")
        print(f"\napprox / fresh: wall {wall['approx'] / wall['fresh']:.3f}, engine {sim['approx'] / sim['fresh']:.3f} "
              f"(expected engine {expect_num / expect_den:.3f})")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
