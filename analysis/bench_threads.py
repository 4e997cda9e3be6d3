"""Multi-scene throughput: one scene alone against two on two threads and on two processes.

Measured in one run, interleaved round by round (the machine is shared, so only ratios taken side by
side mean anything), on the B+C scene (Table 4 test 12, 750 rpm; ``--duration`` simulated seconds):

* **scene**: :func:`twin.simulation.simulate` of the scene, every chunk's channels hashed (SHA-256 of
  the bytes, in order: the same work in every mode), in warm processes (imports and the first build
  done before timing): one scene alone in this process; two scenes on two threads of this process
  (:func:`twin.simulation.simulate_many`); two scenes in two warm worker processes started together;
* **dataset run**: :func:`twin.dataset.worker.run_one`, what a dataset generation runs per run (the
  engine, the sensor chain and the Parquet writer on its thread, instrumented and truth channels of
  ``analysis/datasets/tiny.toml``), alone, on two threads, on two processes, as above;
* **machine baseline**: two plain independent ``twin simulate --test 12 --no-out`` processes started
  together against one alone (whole processes, start-up included): what this machine gives two
  independent jobs at this moment; no threading or pooling can beat it;
* **generation** (default on; ``--no-generate``): ``twin dataset generate`` of ``--runs`` runs of the
  scene (whole processes: pool start-up, planning, manifest included) with ``--workers 2
  --scheduler processes`` against ``--workers 2 --scheduler threads``, once each per round;
* **outside the engine**: the CPU time of one scene and of one dataset run (alone) outside
  ``mujoco.rollout`` (process CPU time minus the rollout's thread CPU time), as a share of the
  run's CPU time: the Python of the chunk loop, the sinks, the sensor chain and the Parquet writer.
  Much of it holds the GIL (pyarrow's compression, hashing and large numpy operations release it),
  so it bounds how many threads one process can keep busy: 1 / share if all of it held the GIL.

Throughput ratio = 2 x wall(one alone) / wall(two together) (2.0: two cores fully used; the issue's
target is >= 1.8). CPU ratio = CPU seconds of one run alone / CPU seconds per run of two together
(process CPU time: this process for threads, each worker or child process otherwise): 1.0 means a
run costs the same CPU time together as alone; below 1.0 the two slow each other down per CPU second
(lock contention, or the two vCPUs sharing a core's resources: then the machine's own row shows it
too, and it bounds every way of running two at once). On a busy machine the alone run also shares
the CPUs with other work, so both ratios tend to 1.

Each ratio is taken within one round; the table gives the median over rounds and the range, and again
over the quiet rounds only: those in which, while the alone and the together sections ran, other work
used less than ``--quiet`` (default 10 %) of the machine's CPUs, measured as the machine's busy CPU time
(``/proc/stat``) minus this benchmark's own (its process, its worker processes, its reaped children).
Bit identity: every threaded and every process scene gives the alone scene's channel hash, every
threaded and process dataset run (and every generated file) the alone run's SHA-256 of the Parquet
file; the script exits with status 1 if any differs.

``--wait-quiet S``: before each comparison, wait up to S seconds for a moment when other work uses
less than ``--quiet`` of the machine (on a shared machine, to catch its quiet moments; the quiet-round
column says which rounds got one).

Run: ``python analysis/bench_threads.py [--rounds 5] [--duration 1.0] [--runs 6] [--no-generate]
[--wait-quiet S] [--quiet 0.1]``.
"""

from __future__ import annotations

import argparse
import hashlib
import multiprocessing as mp
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


class Digest:
    """Sink: SHA-256 of every chunk's channel names and bytes, in order."""

    def __init__(self) -> None:
        self.h = hashlib.sha256()

    def write(self, chunk) -> None:
        for name, ch in chunk.channels.items():
            self.h.update(name.encode())
            self.h.update(ch.data.tobytes())

    def close(self, meta, summary) -> str:
        return self.h.hexdigest()

    def abort(self) -> None:
        pass


_HZ = os.sysconf("SC_CLK_TCK")


def machine_busy_s() -> float:
    """CPU seconds all CPUs of the machine have been busy (``/proc/stat``: all but idle and iowait)."""
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    return (sum(v[:8]) - v[3] - v[4]) / _HZ


def own_cpu_s() -> float:
    """CPU seconds of this process and of its reaped descendants."""
    import resource

    ch = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + ch.ru_utime + ch.ru_stime


def others_now(window_s: float = 0.5) -> float:
    """Share of the machine's CPUs other work uses now (this benchmark idle meanwhile)."""
    with Section() as sec:
        time.sleep(window_s)
    return sec.end()[1]


def wait_quiet(limit: float, budget_s: float) -> float:
    """Wait (at most ``budget_s``) until other work uses less than ``limit`` of the machine; returns
    the seconds waited."""
    t = time.perf_counter()
    while budget_s > 0 and time.perf_counter() - t < budget_s and others_now() >= limit:
        pass
    return time.perf_counter() - t


class Section:
    """Wall time of a timed section and the share of the machine other work used meanwhile:
    (busy CPU seconds of the machine - this benchmark's own) / (CPUs x wall)."""

    def __enter__(self) -> "Section":
        self.t, self.busy, self.own = time.perf_counter(), machine_busy_s(), own_cpu_s()
        return self

    def end(self, extra_own_s: float = 0.0) -> tuple[float, float]:
        """(wall s, others' share); ``extra_own_s``: CPU of this benchmark's processes not reaped yet."""
        wall = time.perf_counter() - self.t
        others = machine_busy_s() - self.busy - (own_cpu_s() - self.own) - extra_own_s
        return wall, max(0.0, others) / ((os.cpu_count() or 1) * wall)

    def __exit__(self, *exc) -> None:
        pass


def scene(toml: str) -> str:
    from twin.config import config_from_toml
    from twin.simulation import simulate

    d = Digest()
    simulate(config_from_toml(toml), [d])
    return d.h.hexdigest()


def dataset_run(task: dict) -> str:
    from twin.dataset.worker import run_one

    res = run_one(task)
    if res["status"] != "ok":
        raise RuntimeError(f"dataset run failed: {res['reason']}")
    return res["sha256"]


def _worker(conn) -> None:
    """A warm worker process: runs what it is sent, answers (wall s, hash)."""
    while True:
        msg = conn.recv()
        if msg is None:
            return
        kind, arg = msg
        t, c = time.perf_counter(), time.process_time()
        out = scene(arg) if kind == "scene" else dataset_run(arg)
        conn.send((time.perf_counter() - t, time.process_time() - c, out))


def specs(duration: float, runs: int) -> tuple[dict, dict]:
    """(one dataset run of the scene, the generation's spec of ``runs`` runs of it)."""
    base = {"test": 12, "engine": "mujoco", "duration_s": duration, "program": "constant",
            "set": {"drive.ramp_s": min(0.5, duration / 4)}}
    outputs = {"truth": ["accel", "encoder", "crank", "joints"], "instrumented": True, "rate_hz": 100000.0}
    one = {"dataset": {"name": "bench-threads", "seed": 1}, "base": base,
           "design": {"kind": "list", "points": [{"motor_rpm": 750.0}]}, "outputs": outputs}
    many = {"dataset": {"name": "bench-threads-gen", "seed": 1}, "base": base,
            "design": {"kind": "list", "repeats": runs, "points": [{"motor_rpm": 750.0}]}, "outputs": outputs}
    return one, many


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--duration", type=float, default=1.0, help="simulated seconds per scene (default 1)")
    ap.add_argument("--runs", type=int, default=6, help="runs of the generation comparison (default 6)")
    ap.add_argument("--no-generate", action="store_true", help="skip the dataset generation comparison")
    ap.add_argument("--gen-duration", type=float, default=None, metavar="S",
                    help="simulated seconds per run of the generation comparison (default: --duration)")
    ap.add_argument("--wait-quiet", type=float, default=0.0, metavar="S",
                    help="before each comparison wait up to S seconds for other work to drop below --quiet "
                         "(default 0: no waiting)")
    ap.add_argument("--quiet", type=float, default=0.1,
                    help="a round is quiet for a comparison when other work used less than this share of the "
                         "machine's CPUs while its alone and together sections ran (default 0.1)")
    args = ap.parse_args()
    load0 = os.getloadavg()[0]

    import tomllib

    import tomli_w  # noqa: F401 - the generation's spec file is written as TOML below

    from twin.config import preset
    from twin.dataset.generate import prepare, task_of
    from twin.dataset.spec import parse_spec
    from twin.simulation import simulate_many

    cfg = preset(12).replace(**{"simulation.duration_s": args.duration,
                                "drive.ramp_s": min(preset(12).drive.ramp_s, args.duration / 4)})
    toml = cfg.to_toml()
    one_spec, _ = specs(args.duration, args.runs)
    gen_s = args.gen_duration or args.duration
    _, gen_spec = specs(gen_s, args.runs)
    work = Path(tempfile.mkdtemp(prefix="twin_bench_threads_"))
    p = prepare(parse_spec(one_spec), work / "plan")
    run = p.runs[0]

    def task(slot: str) -> dict:  # the same run in a folder of its own: the same bytes
        t = task_of(p, run)
        t["data_dir"] = str(work / slot)
        os.makedirs(t["data_dir"], exist_ok=True)
        return t

    gen_file = work / "gen.toml"
    gen_file.write_text(tomli_w.dumps(gen_spec))
    assert tomllib.loads(gen_file.read_text()) == gen_spec
    twin = [sys.executable, "-m", "twin.cli"]
    plain = twin + ["simulate", "--test", "12", "--duration", f"{args.duration:g}", "--no-out", "--no-progress"]

    ctx = mp.get_context("spawn")
    pipes, procs = [], []
    for _ in range(2):
        a, b = ctx.Pipe()
        pr = ctx.Process(target=_worker, args=(b,), daemon=True)
        pr.start()
        pipes.append(a)
        procs.append(pr)

    def on_processes(kind: str, args_: list) -> tuple[float, float, float, list[str]]:
        """(wall, others' share, CPU seconds per run, hashes) of one run on each worker process, started
        together."""
        with Section() as sec:
            for c, a in zip(pipes, args_):
                c.send((kind, a))
            outs = [c.recv() for c in pipes]
        wall, others = sec.end(sum(o[1] for o in outs))
        return wall, others, sum(o[1] for o in outs) / len(outs), [o[2] for o in outs]

    def timed(fn, *a):
        """(wall, others' share, CPU seconds of this process, result)"""
        c = time.process_time()
        with Section() as sec:
            out = fn(*a)
        wall, others = sec.end()
        return wall, others, time.process_time() - c, out

    def whole(argvs: list[list[str]]) -> tuple[float, float, float]:
        """(wall, others' share, CPU seconds per process) of whole processes started together."""
        c = own_cpu_s()
        with Section() as sec:
            ps = [subprocess.Popen(a, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) for a in argvs]
            if any(pp.wait() for pp in ps):
                raise RuntimeError(f"{argvs[0]} failed")
        wall, others = sec.end()
        return wall, others, (own_cpu_s() - c) / len(argvs)

    def generation(threads: bool, r: int) -> tuple[float, dict[str, str]]:
        out = work / f"gen_{'t' if threads else 'p'}{r}"
        argv = twin + ["dataset", "generate", str(gen_file), "--out", str(out), "--workers", "2", "--no-progress"]
        wall, _, _ = whole([argv + ["--scheduler", "threads" if threads else "processes"]])
        sha = {f.name: hashlib.sha256(f.read_bytes()).hexdigest() for f in sorted((out / "data").glob("*.parquet"))}
        shutil.rmtree(out)
        return wall, sha

    # CPU outside the engine (first, alone): process CPU minus the rollout's own thread CPU
    import mujoco.rollout as mj_rollout

    real_rollout, in_engine = mj_rollout.rollout, [0.0]

    def counted(*a, **k):
        t = time.thread_time()
        try:
            return real_rollout(*a, **k)
        finally:
            in_engine[0] += time.thread_time() - t

    outside: dict[str, float] = {}
    mj_rollout.rollout = counted
    try:
        for name, fn, arg in (("scene", scene, toml), ("dataset run", dataset_run, task("cpu"))):
            fn(arg)  # warm
            in_engine[0] = 0.0
            c = time.process_time()
            fn(arg)
            c = time.process_time() - c
            outside[name] = (c - in_engine[0]) / c
    finally:
        mj_rollout.rollout = real_rollout

    # warm-up: imports, first builds, the file cache, the workers' imports
    ref_scene = scene(toml)
    ref_ds = dataset_run(task("warm"))
    on_processes("scene", [toml, toml])
    on_processes("dataset", [task("pw0"), task("pw1")])
    whole([plain])

    ratios: dict[str, list[float]] = {}
    walls: dict[str, list[float]] = {}
    cpu: dict[str, list[float]] = {}  # CPU seconds per run alone / per run together
    quiet: dict[str, list[float]] = {}  # ratios of the rounds where other work used < QUIET of the machine
    busy_others: dict[str, list[float]] = {}  # other work's share of the machine, the larger of the two sections
    same = {"scene": True, "dataset": True, "generation": True}
    gen_ref: dict[str, str] | None = None

    def note(key: str, alone: float, pair: float, others: tuple[float, float], cpu_alone: float | None = None,
             cpu_each: float | None = None) -> None:
        ratios.setdefault(key, []).append(2 * alone / pair)
        quiet.setdefault(key, [])
        busy_others.setdefault(key, []).append(max(others))
        if max(others) < args.quiet:
            quiet[key].append(2 * alone / pair)
        walls.setdefault(key, []).append(pair)
        walls.setdefault(key + " alone", []).append(alone)
        if cpu_alone is not None:
            cpu.setdefault(key, []).append(cpu_alone / cpu_each)

    for r in range(args.rounds):
        wait_quiet(args.quiet, args.wait_quiet)
        t1, o1, c1, h = timed(scene, toml)
        same["scene"] &= h == ref_scene
        keeps = [Digest(), Digest()]
        t2, o2, c2, _ = timed(simulate_many, [cfg, cfg], [[keeps[0]], [keeps[1]]], 2)
        same["scene"] &= all(k.h.hexdigest() == ref_scene for k in keeps)
        note("scene, 2 threads", t1, t2, (o1, o2), c1, c2 / 2)
        wait_quiet(args.quiet, args.wait_quiet)
        t2, o2, c2, hs = on_processes("scene", [toml, toml])
        same["scene"] &= all(x == ref_scene for x in hs)
        note("scene, 2 processes", t1, t2, (o1, o2), c1, c2)

        wait_quiet(args.quiet, args.wait_quiet)
        t1, o1, c1, h = timed(dataset_run, task(f"a{r}"))
        same["dataset"] &= h == ref_ds
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(2) as ex:
            t2, o2, c2, hs = timed(lambda: list(ex.map(dataset_run, [task(f"t{r}0"), task(f"t{r}1")])))
        same["dataset"] &= all(x == ref_ds for x in hs)
        note("dataset run, 2 threads", t1, t2, (o1, o2), c1, c2 / 2)
        wait_quiet(args.quiet, args.wait_quiet)
        t2, o2, c2, hs = on_processes("dataset", [task(f"p{r}0"), task(f"p{r}1")])
        same["dataset"] &= all(x == ref_ds for x in hs)
        note("dataset run, 2 processes", t1, t2, (o1, o2), c1, c2)

        wait_quiet(args.quiet, args.wait_quiet)
        t1, o1, c1 = whole([plain])
        t2, o2, c2 = whole([plain, plain])
        note("machine: 2 plain twin simulate processes", t1, t2, (o1, o2), c1, c2)

        if not args.no_generate:
            for threads in (False, True) if r % 2 == 0 else (True, False):
                wait_quiet(args.quiet, args.wait_quiet)
                w, sha = generation(threads, r)
                gen_ref = gen_ref or sha
                same["generation"] &= sha == gen_ref and len(sha) == args.runs
                walls.setdefault("generation, " + ("2 threads" if threads else "2 processes"), []).append(w)
        print(f"round {r + 1}/{args.rounds}: " + ", ".join(f"{k} {v[-1]:.2f} (others {busy_others[k][-1] * 100:.0f} %)"
                                                           for k, v in ratios.items()), file=sys.stderr)

    for c in pipes:
        c.send(None)
    for pr in procs:
        pr.join(timeout=10)
    shutil.rmtree(work, ignore_errors=True)

    def rng(v: list[float]) -> str:
        return f"{statistics.median(v):.2f} ({min(v):.2f}-{max(v):.2f})"

    from twin.provenance import git_commit

    commit = git_commit()
    print(f"commit {commit}; B+C scene (test 12, 750 rpm), {args.duration:g} s simulated, {args.rounds} interleaved "
          f"rounds, {os.cpu_count()} CPUs, 1-min load average {load0:.1f} at the start, "
          f"{os.getloadavg()[0]:.1f} at the end (other work on the machine counts in it)")
    print()
    print(f"| two together | throughput vs one alone: median (range) | the same, quiet rounds only (other work "
          f"< {args.quiet * 100:.0f} % of the machine): median (range), rounds | CPU per run, alone / together: "
          "median (range) | other work's share of the machine: median (range) | wall of one alone [s]: median | "
          "wall of two together [s]: median |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for k, v in ratios.items():
        q = f"{rng(quiet[k])}, {len(quiet[k])}" if quiet[k] else "none"
        o = busy_others[k]
        print(f"| {k} | {rng(v)} | {q} | {rng(cpu[k]) if k in cpu else '-'} | "
              f"{statistics.median(o) * 100:.0f} % ({min(o) * 100:.0f}-{max(o) * 100:.0f} %) | "
              f"{statistics.median(walls[k + ' alone']):.3f} | {statistics.median(walls[k]):.3f} |")
    if not args.no_generate:
        gp, gt = walls["generation, 2 processes"], walls["generation, 2 threads"]
        per_round = [a / b for a, b in zip(gp, gt)]
        print()
        print(f"`twin dataset generate`, {args.runs} runs of {gen_s:g} s, whole process, --workers 2: "
              f"processes median {statistics.median(gp):.2f} s, threads (--scheduler threads) "
              f"{statistics.median(gt):.2f} s; processes / threads per round {rng(per_round)}")
    print()
    print("CPU time outside `mujoco.rollout`, share of a run's CPU time (alone): " +
          ", ".join(f"{k} {v * 100:.0f} %" for k, v in outside.items()))
    print()
    for k, ok in same.items():
        if k != "generation" or not args.no_generate:
            print(f"bit identity, {k}: {'identical' if ok else 'DIFFERENT'}")
    return 0 if all(same.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
