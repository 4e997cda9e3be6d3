"""Do two MuJoCo twins step at the same time on two threads? (the native hooks, twin/native/collider.py)

Two measurements, side by side in one run:

1. The GIL during a rollout. A thread runs one ``mujoco.rollout`` call of the spatial S002 model
   (one C call, the native passive/sensor hooks and colliders inside) while the main thread counts
   iterations of a pure-Python loop; the count per second is compared with the same loop's rate
   while nothing else runs. A call that held the GIL would stop the loop for its whole length
   (ratio about 0); a released GIL leaves it running (ratio near 1 with a free core, about 0.5 when
   the two threads share one).
2. Two scenes on two threads. The planar B+C scene (Table 4 test 12, ``mujoco.contact_source``
   "law") and S002, each alone one after the other, then both at once on two threads (the bytes
   of each are checked equal to its solo run, as tests/test_native_hooks.py does). Wall-time ratio
   (both at once) / (sum of the solo runs): 1 for no overlap, max/sum for a perfect one, provided
   two cores are free (the machine's load average is printed with it); and the process's CPU time
   over the wall time of that phase, above 1 only if two threads ran at the same time.

    python analysis/native_threads.py [--duration 0.2]
"""

from __future__ import annotations

import argparse
import hashlib
import os
import threading
import time

import mujoco
import numpy as np
from mujoco import rollout

import twin
from twin.config import preset
from twin.provenance import git_commit


def _digest(run) -> str:
    h = hashlib.sha256()
    for name in sorted(run.channels):
        h.update(name.encode() + np.ascontiguousarray(run[name]).tobytes())
    return h.hexdigest()


def _loop_rate(stop: threading.Event) -> float:
    n, t0 = 0, time.perf_counter()
    while not stop.is_set():
        n += 1
    return n / (time.perf_counter() - t0)


def gil_ratio(nstep: int) -> tuple[float, float, float]:
    """(loop rate alone [1/s], loop rate during the rollout [1/s], rollout wall [s])."""
    from twin.simulation import make_engine

    e = make_engine(twin.preset("s002"))
    e.reset()
    m, d = e.model, e.data
    state0 = np.empty((1, mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS)))
    mujoco.mj_getState(m, d, state0[0], mujoco.mjtState.mjSTATE_FULLPHYSICS)
    ctrl = np.full((1, nstep, m.nu), d.ctrl[0])
    stop = threading.Event()
    timer = threading.Timer(0.3, stop.set)
    timer.start()
    alone = _loop_rate(stop)
    stop.clear()
    wall = [0.0]

    def run():
        t0 = time.perf_counter()
        rollout.rollout(m, d, state0, ctrl, nstep=nstep)
        wall[0] = time.perf_counter() - t0
        stop.set()

    t = threading.Thread(target=run)
    t.start()
    during = _loop_rate(stop)
    t.join()
    return alone, during, wall[0]


def two_scenes(duration: float) -> dict[str, float]:
    cfgs = [preset(12).replace(**{"simulation.duration_s": duration, "mujoco.contact_source": "law"}),
            twin.preset("s002").replace(**{"simulation.duration_s": duration})]
    for c in cfgs:  # warm up (imports, first compile)
        twin.simulate(c, duration=min(duration, 0.01))
    solo, digests = [], []
    for c in cfgs:
        t0 = time.perf_counter()
        digests.append(_digest(twin.simulate(c)))
        solo.append(time.perf_counter() - t0)
    both: list = [None, None]
    start = threading.Barrier(2)

    def run(i):
        start.wait()
        both[i] = _digest(twin.simulate(cfgs[i]))

    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    t0, c0 = time.perf_counter(), time.process_time()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    if both != digests:
        raise SystemExit("the runs on two threads differ from the solo runs")
    return {"planar_s": solo[0], "s002_s": solo[1], "both_s": wall,
            "ratio": wall / sum(solo), "perfect": max(solo) / sum(solo), "cpu": cpu / wall}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--duration", type=float, default=0.2, help="simulated time of each scene [s] (default 0.2)")
    p.add_argument("--nstep", type=int, default=20000, help="steps of the rollout of measurement 1 (default 20000)")
    a = p.parse_args(argv)
    print(f"twin {twin.__version__} ({git_commit()}), mujoco {mujoco.__version__}, {os.cpu_count()} CPUs, "
          f"load average {os.getloadavg()[0]:.1f}")
    alone, during, wall = gil_ratio(a.nstep)
    print(f"1. GIL: Python loop {alone:.3g}/s alone, {during:.3g}/s during a {wall:.2f} s rollout "
          f"(ratio {during / alone:.2f}; 0 = GIL held)")
    r = two_scenes(a.duration)
    print(f"2. two scenes, {a.duration} s each: planar B+C {r['planar_s']:.2f} s, S002 {r['s002_s']:.2f} s alone; "
          f"both on two threads {r['both_s']:.2f} s: ratio {r['ratio']:.2f} (1 = serial, {r['perfect']:.2f} = "
          f"perfect overlap); process CPU time / wall {r['cpu']:.2f} (> 1: two threads ran at the "
          "same time); bytes equal to the solo runs")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
