"""Peak memory of ``twin simulate`` against simulated duration, for both engines.

Method: every measurement is a fresh child process running the real command line
(``python -m twin.cli simulate --test 12 --protocol ...``), so imports, model build, numba's
cached loop, the chunk loop and the sinks all count; its peak resident set size is the
``ru_maxrss`` the kernel reports for that child alone (``os.wait4``), not a sampled value. The
protocol is stretched to the wanted duration through its hold time (stops of 2 s, three speeds
held ``(D - 8) / 3`` s each), so a longer run keeps doing the same work rather than idling. The
baseline of each engine is the same command for a single 10 ms chunk (imports, model, compiled
loop): the ratio ``peak / baseline`` is what a run adds, measured side by side in one run of
this script.

Run: ``python analysis/bench_memory.py [--durations 38,380] [--engines mujoco,reference]
[--no-out]`` (about 6 min for the defaults on two cores: the 380 s MuJoCo run dominates). The MCAP
files go to a temporary folder that is deleted afterwards (a 380 s run writes about 4 GB).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time


def peak_rss(argv: list[str], cwd: str) -> tuple[float, float, int]:
    """(peak RSS [MB], wall [s], exit status) of a child process running ``argv``."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    err = proc.stderr.read().decode() if proc.stderr else ""
    if proc.returncode != 0:
        raise SystemExit(f"child failed ({proc.returncode}): {' '.join(argv)}\n{err}")
    return usage.ru_maxrss / 1024.0, time.perf_counter() - t0, proc.returncode


def command(engine: str, duration: float, out: str | None) -> list[str]:
    argv = [sys.executable, "-m", "twin.cli", "simulate", "--test", "12", "--engine", engine, "--no-progress"]
    if duration <= 0.011:
        argv += ["--duration", f"{duration:g}"]
    else:
        hold = (duration - 8.0) / 3.0  # 4 stops of 2 s, three holds
        argv += ["--protocol", "--set", f"drive.protocol_hold_s={hold:.6f}"]
    argv += ["--out", out] if out else ["--no-out"]
    return argv


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--durations", default="38,380", help="simulated durations [s] (>= 9), comma-separated")
    ap.add_argument("--engines", default="mujoco,reference")
    ap.add_argument("--no-out", action="store_true", help="no MCAP file (memory of the engine and summary only)")
    args = ap.parse_args()
    durations = [float(d) for d in args.durations.split(",")]
    if any(d < 9 for d in durations):
        raise SystemExit("--durations: the stretched protocol needs at least 9 s")
    work = tempfile.mkdtemp(prefix="twin_mem_")
    try:
        print(f"peak RSS of 'twin simulate --test 12 --protocol' (stretched), {'no file' if args.no_out else 'MCAP file'}"
              ", fresh child process each")
        print(f"{'engine':10s} {'duration s':>10s} {'peak MB':>9s} {'/ baseline':>10s} {'/ shortest':>10s} {'wall s':>8s}")
        for engine in args.engines.split(","):
            base, _, _ = peak_rss(command(engine, 0.01, None), work)
            print(f"{engine:10s} {'0.01 (base)':>10s} {base:9.1f} {1.0:10.2f} {'':>10s}")
            first = None
            for d in durations:
                out = None if args.no_out else os.path.join(work, f"{engine}_{d:g}.mcap")
                mb, wall, _ = peak_rss(command(engine, d, out), work)
                first = first or mb
                print(f"{engine:10s} {d:10g} {mb:9.1f} {mb / base:10.2f} {mb / first:10.2f} {wall:8.1f}", flush=True)
                if out and os.path.exists(out):
                    os.unlink(out)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
