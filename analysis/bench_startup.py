"""Start-up cost of a ``twin simulate`` process: how long until the first step.

Measures, best of ``--repeats`` fresh processes each (interleaved):

* ``python -c pass``: the interpreter alone;
* ``twin simulate --test 12 --duration 1e-5 --no-out``: one step of the B+C scene, i.e. the whole
  path to the first step (imports, configuration, model build, native collider, engine reset)
  plus one step, the summary and the exit: an upper bound of the time to the first step;
* the same with ``--engine reference`` (the numba cache loaded, not compiled: run once first);
* the MuJoCo one with ``MUJOCO_GL=glfw``: MuJoCo's OpenGL set-up at import, which
  ``twin.cli.main`` now skips (it sets ``MUJOCO_GL=disable`` unless the user set it);
* the MuJoCo one again with Python's byte-code cache allowed: this environment sets
  ``PYTHONDONTWRITEBYTECODE=1``, so every process compiles twin's own sources (installed
  packages come with their byte code); an ordinary installation caches them (the run writes
  ``__pycache__`` folders, ignored by git).

Then one ``python -X importtime`` run of the MuJoCo command, listing the slowest imports by
cumulative time (top-level packages and the ``twin`` modules that pull them in).

Run: ``python analysis/bench_startup.py [--repeats N]``.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import time

PY = sys.executable
TWIN = [PY, "-m", "twin.cli"]
CMDS = {
    "python -c pass": [PY, "-c", "pass"],
    "twin simulate, one step (mujoco)": TWIN + ["simulate", "--test", "12", "--duration", "1e-5", "--no-out",
                                                "--no-progress"],
    "twin simulate, one step (reference)": TWIN + ["simulate", "--test", "12", "--duration", "1e-5", "--no-out",
                                                   "--no-progress", "--engine", "reference"],
}


PYC = "twin simulate, one step (mujoco), byte code cached"
GL = "twin simulate, one step (mujoco), MUJOCO_GL=glfw (MuJoCo's OpenGL set-up, as before)"
CMDS[PYC] = CMDS["twin simulate, one step (mujoco)"]
CMDS[GL] = CMDS["twin simulate, one step (mujoco)"]


def timed(cmd: list[str], cwd: str, variant: str = "") -> float:
    env = dict(os.environ)
    if variant == PYC:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
    if variant == GL:
        env["MUJOCO_GL"] = "glfw"
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=cwd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    return time.perf_counter() - t0


def importtime(cmd: list[str], cwd: str, top: int) -> list[tuple[int, str]]:
    """(cumulative µs, module) of the slowest imports that are not inside another listed one."""
    err = subprocess.run([cmd[0], "-X", "importtime", *cmd[1:]], cwd=cwd, capture_output=True, text=True).stderr
    rows = []
    for line in err.splitlines():
        m = re.match(r"import time:\s+(\d+) \|\s+(\d+) \|( *)(\S+)", line)
        if m:
            rows.append((int(m.group(2)), len(m.group(3)) // 2, m.group(4)))
    # keep a module if it is top level (depth 0) or a twin module
    keep = [(c, f"{'  ' * d}{n}") for c, d, n in rows if d == 0 or n.startswith("twin")]
    return sorted(keep, reverse=True)[:top]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--top", type=int, default=15)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as cwd:
        for k, cmd in CMDS.items():  # warm the file cache, numba's cache and the byte-code cache
            timed(cmd, cwd, k)
        best = {k: math.inf for k in CMDS}
        for _ in range(args.repeats):
            for k, cmd in CMDS.items():
                best[k] = min(best[k], timed(cmd, cwd, k))
        imports = importtime(CMDS["twin simulate, one step (mujoco)"], cwd, args.top)
    from twin.provenance import git_commit

    commit = git_commit()
    print(f"best of {args.repeats} fresh processes (interleaved), commit {commit}, MUJOCO_GL="
          f"{os.environ.get('MUJOCO_GL', '(unset)')}, PYTHONDONTWRITEBYTECODE="
          f"{os.environ.get('PYTHONDONTWRITEBYTECODE', '(unset)')}")
    print()
    print("| process | wall [s] |")
    print("|---|---:|")
    for k, v in best.items():
        print(f"| {k} | {v:.3f} |")
    print()
    print("Slowest imports of the MuJoCo one-step process (cumulative, `-X importtime`):")
    print()
    for c, name in imports:
        print(f"    {c / 1e3:7.1f} ms  {name}")


if __name__ == "__main__":
    main()
