"""Speed as a user sees it: regenerates the summary table of docs/speed.md in place.

Measures in one run, the variants interleaved so that the machine's other work hits them alike:

* **whole process** of the README's commands, fresh processes timed from start to exit (imports,
  configuration, model build, the run, the run file written, the summary printed):
  ``twin simulate`` (the README's first command: Table 4 test 6 for 2 s), ``twin simulate --test 12
  --duration 4`` and the same with ``--engine reference``; median and range of ``--repeats``;
* **per step**: the ideal (test 3), C-only (test 6) and B+C (test 12) scenes at h = 10 µs inside
  ``mujoco.rollout`` with the default (post hoc) accelerometers, best of ``--repeats`` rollouts of
  ``--steps`` steps (``analysis/bench_mujoco.py``'s timing, which also gives the floors);
* **the reference engine's first process after an install** (numba compiles: an empty numba cache,
  ``NUMBA_CACHE_DIR`` pointed at a new folder) and the **second** (the cache loaded):
  ``twin simulate --engine reference --duration 0.1 --no-progress --out F.mcap``;
* the **machine**: CPU model, cores, load average, and the share of the machine's CPU time that other
  work took while the timings ran (``/proc/stat`` less this script's own processes), so that a figure
  measured under load says so.

Writes the table between the markers ``<!-- speed-summary:begin -->`` and ``<!-- speed-summary:end -->``
of docs/speed.md (stamped with twin's version) and the full results to
analysis/results/speed/speed_table.md (version and commit). The processes run with Python's byte-code
cache allowed (as an ordinary install has it) from a temporary folder.

Run: ``python analysis/speed_table.py [--repeats 5] [--steps 50000] [--no-write]`` (2–4 minutes).
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "speed.md"
RESULTS = ROOT / "analysis" / "results" / "speed" / "speed_table.md"
BEGIN, END = "<!-- speed-summary:begin -->", "<!-- speed-summary:end -->"
TWIN = [sys.executable, "-m", "twin.cli"]

sys.path.insert(0, str(ROOT / "analysis"))
from bench_threads import machine_busy_s, own_cpu_s  # noqa: E402  (a sibling script)
from twin.provenance import with_stamp_line  # noqa: E402

# (label, arguments of `twin`, simulated seconds)
PROCESSES = [
    ("README's first command: test 6 (C), 2 s, MuJoCo", ["simulate"], 2.0),
    ("test 12 (B+C), 4 s, MuJoCo", ["simulate", "--test", "12", "--duration", "4"], 4.0),
    ("test 12 (B+C), 4 s, reference engine", ["simulate", "--test", "12", "--duration", "4", "--engine", "reference"],
     4.0),
]
REF_START = ["simulate", "--engine", "reference", "--duration", "0.1", "--no-progress", "--out", "F.mcap"]


def _env(**extra: str) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # an ordinary install keeps its byte code
    env.update(extra)
    return env


def timed(args: list[str], cwd: str, **extra: str) -> float:
    """Wall time [s] of one fresh `twin` process, start to exit."""
    t0 = time.perf_counter()
    subprocess.run(TWIN + args, cwd=cwd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                   env=_env(**extra))
    return time.perf_counter() - t0


class MachineShare:
    """The share of the machine's CPU time taken by other work between start() and stop()
    (``analysis/bench_threads.py``'s counters: the machine's busy time less this script's)."""

    def __init__(self) -> None:
        self.busy0 = self.own0 = self.t0 = 0.0

    def start(self) -> None:
        self.busy0, self.own0, self.t0 = machine_busy_s(), own_cpu_s(), time.perf_counter()

    def stop(self) -> float:
        busy, own = machine_busy_s() - self.busy0, own_cpu_s() - self.own0
        return max(0.0, busy - own) / ((os.cpu_count() or 1) * (time.perf_counter() - self.t0))


def cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            m = re.search(r"model name\s*:\s*(.+)", f.read())
        return m.group(1).strip() if m else platform.processor()
    except OSError:
        return platform.processor() or "unknown CPU"


def commit() -> str:
    from twin.provenance import git_commit

    return git_commit()


def per_step(steps: int, repeats: int) -> dict[str, float]:
    """Best µs per step of each scene (posthoc accelerometers, the default), rollouts interleaved."""
    from bench_mujoco import SCENES, prepare_posthoc, step_time

    prepared = {lab: prepare_posthoc(tid, steps) for lab, tid in SCENES.items()}
    best = {lab: math.inf for lab in SCENES}
    for _ in range(repeats):
        for lab, (m, s, c, post) in prepared.items():
            best[lab] = min(best[lab], step_time(m, s, c, steps, post))
    return best


def measure(repeats: int, steps: int) -> dict:
    import mujoco

    import twin

    res: dict = {"version": twin.__version__, "commit": commit(), "mujoco": mujoco.__version__,
                 "cpu": cpu_model(), "cores": os.cpu_count(),
                 "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
                 "load_before": os.getloadavg()[0]}
    share = MachineShare()
    share.start()
    with tempfile.TemporaryDirectory() as cwd:
        # the reference engine's first process after an install, then the second
        cold = Path(cwd) / "numba-cache"
        res["ref_first_s"] = timed(REF_START, cwd, NUMBA_CACHE_DIR=str(cold))
        res["ref_second_s"] = timed(REF_START, cwd, NUMBA_CACHE_DIR=str(cold))
        for _, args, _ in PROCESSES:  # warm the file system cache, numba's own cache and the byte code
            timed(args, cwd)
        walls: dict[str, list[float]] = {lab: [] for lab, _, _ in PROCESSES}
        for _ in range(repeats):
            for lab, args, _ in PROCESSES:
                walls[lab].append(timed(args, cwd))
        res["walls"] = walls
    res["steps"] = per_step(steps, repeats)
    res["other_share"] = share.stop()
    res["load_after"] = os.getloadavg()[0]
    res["repeats"], res["nsteps"] = repeats, steps
    return res


def table(res: dict, with_commit: bool = False) -> str:
    """The summary table with its measuring conditions (the commit only in the results file: the
    user-facing page carries no commit hashes)."""
    reps = res["repeats"]
    lines = [
        f"Measured by `python analysis/speed_table.py` on {res['date']}: twin {res['version']}"
        + (f" (commit {res['commit']})" if with_commit else "")
        + f", MuJoCo {res['mujoco']}, {res['cpu']}, {res['cores']} cores; 1-minute load "
        f"average {res['load_before']:.1f} before and {res['load_after']:.1f} after, other work took "
        f"{100 * res['other_share']:.0f} % of the machine's CPU time while it measured"
        + (" (figures under load: on an idle machine they are lower)." if res["other_share"] > 0.15 else "."),
        "",
        "| what | figure | command |",
        "|---|---|---|",
    ]
    for lab, args, sim_s in PROCESSES:
        w = res["walls"][lab]
        med = statistics.median(w)
        lines.append(f"| whole process, {lab} | {med:.2f} s ({min(w):.2f}–{max(w):.2f}), "
                     f"{sim_s / med:.2f}× real time (median, range of {reps} fresh processes) | "
                     f"`twin {' '.join(args)}` |")
    h_us = 10.0
    for lab, us in res["steps"].items():
        lines.append(f"| one step, {lab}, h = 10 µs, all channels at 100 kHz | {us:.2f} µs, "
                     f"{h_us / us:.2f}× real time (best of {reps} rollouts of {res['nsteps']} steps) | "
                     "`python analysis/bench_mujoco.py` (also the constraint-free floor) |")
    lines.append(f"| reference engine, first process after an install (numba compiles) | {res['ref_first_s']:.1f} s | "
                 f"`twin {' '.join(REF_START)}` |")
    lines.append(f"| reference engine, second process (compiled code loaded from the cache) | "
                 f"{res['ref_second_s']:.2f} s | the same |")
    return "\n".join(lines)


def write_page(text: str) -> None:
    page = PAGE.read_text()
    if BEGIN not in page or END not in page:
        raise SystemExit(f"{PAGE}: the markers {BEGIN} and {END} are missing")
    head, rest = page.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    tmp = PAGE.with_suffix(".md.tmp")
    tmp.write_text(f"{head}{BEGIN}\n{text}\n{END}{tail}")
    tmp.replace(PAGE)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="fresh processes per command and rollouts per scene")
    ap.add_argument("--steps", type=int, default=50_000, help="steps of each timed rollout")
    ap.add_argument("--no-write", action="store_true", help="print the table only")
    args = ap.parse_args()
    res = measure(args.repeats, args.steps)
    text = table(res)
    print(text)
    if not args.no_write:
        write_page(text)
        raw = "\n".join(f"- {lab}: " + ", ".join(f"{x:.3f}" for x in w) + " s" for lab, w in res["walls"].items())
        RESULTS.write_text(with_stamp_line(f"{table(res, with_commit=True)}\n\nEvery process's wall time:\n\n{raw}"))
        print(f"wrote {PAGE.relative_to(ROOT)} and {RESULTS.relative_to(ROOT)}", file=sys.stderr)


if __name__ == "__main__":
    main()
