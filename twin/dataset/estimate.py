"""Wall-time estimate of a dataset before it runs (``twin dataset plan``).

Method: for one run of each fault class of the spec (the classes differ most in cost: contacts
and their sensors), the real worker (:func:`twin.dataset.worker.run_one`, with the spec's outputs)
simulates two short probes, 0.05 s and 0.25 s at the run's highest motor speed (a protocol or a
profile that starts at rest would make a short probe cheaper than the run), into a temporary
folder, after a first 0.05 s probe whose time is not used (it pays the one-time costs of the
first run of a process and of a class: imports, caches; with it counted, the first probe could
take longer than the second and the slope came out 0: "0.00 s per simulated second" for a spec
whose 400 runs took 383 s). A line through the two wall times gives each class's set-up time per
run and its wall time per simulated second; the estimate is the sum over the runs divided by the workers, with
75 % parallel efficiency (two workers on this project's 2-vCPU machine gave 1.49-1.58× one,
``analysis/bench_threads.py``) and 2 s to start the workers. Checked against a real generation
(``analysis/datasets/clearance_id_cont.toml``, 400 runs of 3 s on two threads: 383 s): 4.3 min
estimated for 6.4 min (the probes run at full speed without the runs' spin-up and most of their
impacts). It is an estimate: the machine's load and
the runs' speed profiles move it.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

from twin.dataset.design import RunPlan
from twin.dataset.spec import DatasetSpec

PROBES_S = (0.05, 0.25)
WARMUP_S = 0.05
EFFICIENCY = 0.75
START_S = 2.0


def _probe_config(r: RunPlan, duration: float):
    d = r.config.drive
    speeds = [abs(d.motor_rpm)] if d.program == "constant" else list(map(abs, d.protocol_rpm if d.program == "protocol"
                                                                      else d.steps_rpm or (d.motor_rpm,)))
    rpm = max(speeds) if speeds else 750.0
    return r.config.replace(**{"drive.program": "constant", "drive.motor_rpm": rpm or 750.0,
                               "drive.ramp_s": 0.02, "simulation.duration_s": duration})


def estimate_wall(spec: DatasetSpec, runs: list[RunPlan], workers: int, warm_start: bool = True) -> dict[str, Any]:
    """The estimate (module docstring). With ``warm_start`` (as ``twin dataset generate`` runs by
    default), a run that shares its group's engine run (:func:`twin.warm.share_groups`) is counted
    without the engine's stepping (the probes' engine time per simulated second)."""
    from twin.dataset.generate import dataset_columns
    from twin.dataset.worker import run_one

    columns = [tuple(vars(c).values()) for c in dataset_columns(runs, spec)]
    per_class: dict[str, tuple[float, float]] = {}
    with tempfile.TemporaryDirectory() as d:
        for r in runs:
            cls = r.labels["fault"]
            if cls in per_class:
                continue
            walls, engine = [], []
            for k, T in enumerate((WARMUP_S, *PROBES_S)):
                cfg = _probe_config(r, T)
                res = run_one({"run_id": f"probe{k}", "index": 0, "config_toml": cfg.to_toml(), "data_dir": d,
                               "columns": columns, "instrumented": list(spec.outputs.instrumented)})
                walls.append(res["wall_s"])
                engine.append(res.get("sim_wall_s") or 0.0)
                Path(d, f"probe{k}.parquet").unlink(missing_ok=True)
            w0, w1 = walls[1:]  # the warm-up's time is not used
            b = max((w1 - w0) / (PROBES_S[1] - PROBES_S[0]), 0.0)
            a = max(w0 - b * PROBES_S[0], 0.0)
            e = min(max((engine[2] - engine[1]) / (PROBES_S[1] - PROBES_S[0]), 0.0), b)
            per_class[cls] = (a, b, e)
    shares = [False] * len(runs)  # the run reuses its group's engine run
    if warm_start:
        from twin.warm import share_groups

        for g in share_groups([r.config for r in runs]):
            for i in g[1:]:
                shares[i] = True
    total = 0.0
    for r, shared in zip(runs, shares):
        a, b, e = per_class[r.labels["fault"]]
        total += a + (b - e if shared else b) * r.config.duration_s
    wall = START_S + total / (workers * EFFICIENCY)
    sim = sum(r.config.duration_s for r in runs)
    return {"wall_s": wall, "probes": (1 + len(PROBES_S)) * len(per_class),
            "per_sim_s": sum(per_class[r.labels["fault"]][1] * r.config.duration_s for r in runs) / sim if sim else 0.0,
            "overhead_s": sum(per_class[r.labels["fault"]][0] for r in runs) / len(runs),
            "engine_runs": len(runs) - sum(shares)}
