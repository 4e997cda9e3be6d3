"""Speed of the R-matrix reference engine (issue 3 target: B+C clearance scene at 1e-5 s ≥ 5× real time
on one core), its compile/first-call cost, and the impact-speed floor it needs.

Prints, for the ideal (test 3), C-only (test 6) and B+C (test 12) scenes at 750 motor rpm, h = 1e-5 s,
100 kHz output of every channel group:

* µs/step and real-time factor of ``ReferenceEngine`` (best of ``--repeats`` runs of ``--duration`` s;
  stepping only: numba's compiled loop is loaded before the clock starts, as in ``meta["wall_s"]``),
  beside the MuJoCo twin on the same scene with ``--mujoco``;
* compile and first-call time, each in a fresh Python process: with an empty numba cache (cold: the
  compile a first installation pays once) and with the cache just written (what every later process
  pays: import + load + first chunk);
* with ``--floor``: the sensitivity of test 12 to ``contact.impact_speed_floor_mps`` (floor of the
  stored impact speed δ̇⁻ of the Lankarani–Nikravesh law) at h = 1e-5 s and 2.5e-6 s: impact counts, peak
  forces, accelerometer RMS/peak. A floor is stable if its results do not change when h shrinks.

Run: ``python analysis/bench_reference.py [--duration 2] [--repeats 3] [--mujoco] [--floor]``.
Timings on a shared machine are noisy: compare numbers from one run.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time


from twin.config import preset
from twin.summary import summarize

SCENES = {"ideal (test 3)": 3, "C only (test 6)": 6, "B+C (test 12)": 12}

_FIRST_CALL = r"""
import time
t0 = time.perf_counter()
from twin.config import preset
from twin.reference.engine import ReferenceEngine
from twin.simulation import run_chunks
t1 = time.perf_counter()
cfg = preset(12).replace(**{"simulation.duration_s": 0.01, "simulation.engine": "reference"})
eng = ReferenceEngine(cfg)
t2 = time.perf_counter()
for _ in run_chunks(cfg, engine=eng):
    pass
t3 = time.perf_counter()
print(f"{t1 - t0:.3f} {eng.meta['compile_s']:.3f} {t3 - t0:.3f}")
"""


def _scene(test: int, duration: float, engine: str, **ov):
    return preset(test).replace(**{"simulation.duration_s": duration, "drive.ramp_s": 0.2,
                                   "simulation.engine": engine, **ov})


def speed(duration: float, repeats: int, with_mujoco: bool) -> None:
    from twin.reference.engine import ReferenceEngine
    from twin.simulation import run_chunks

    print(f"\nstepping speed, h = 1e-5 s, {duration:g} s per run, best of {repeats} (µs/step, real-time factor)")
    print(f"{'scene':18s} {'reference':>22s}" + (f" {'mujoco':>22s} {'ref speed-up':>13s}" if with_mujoco else ""))
    for label, test in SCENES.items():
        best = {}
        engines = ("reference", "mujoco") if with_mujoco else ("reference",)
        for eng_name in engines:
            cfg = _scene(test, duration, eng_name)
            walls = []
            for _ in range(repeats):
                if eng_name == "reference":
                    eng = ReferenceEngine(cfg)
                else:
                    from twin.mujoco_engine.engine import MujocoEngine

                    eng = MujocoEngine(cfg)
                for _chunk in run_chunks(cfg, engine=eng):
                    pass
                walls.append(eng.meta["wall_s"])
            best[eng_name] = (min(walls), eng.meta["steps"])
        wall, steps = best["reference"]
        line = f"{label:18s} {wall / steps * 1e6:9.3f} µs  {duration / wall:7.2f}×"
        if with_mujoco:
            w2, s2 = best["mujoco"]
            line += f" {w2 / s2 * 1e6:9.3f} µs  {duration / w2:7.2f}× {w2 / wall:12.1f}×"
        print(line)


def first_call() -> None:
    print("\ncompile / first call, fresh processes (import s, compile-or-load s, import→first chunk s)")
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        for label in ("cold (empty numba cache)", "cached (second process)"):
            t = time.perf_counter()
            out = subprocess.run([sys.executable, "-c", _FIRST_CALL], env=env, capture_output=True, text=True,
                                 check=True).stdout.split()
            total = time.perf_counter() - t
            print(f"  {label:26s} import {float(out[0]):6.2f} s, compile/load {float(out[1]):6.2f} s, "
                  f"first chunk done after {float(out[2]):6.2f} s (process {total:5.2f} s)")


def floor_sensitivity(duration: float) -> None:
    from twin.simulation import simulate_run

    print(f"\nimpact-speed floor (contact.impact_speed_floor_mps), test 12, {duration:g} s: "
          "impacts / max force [N] per joint, AC1 AC3 AC6 rms/peak [m/s²], wall [s]")
    for v in (1e-4, 1e-3, 1e-2, 1e-1):
        for h in (1e-5, 2.5e-6):
            cfg = _scene(12, duration, "reference", **{"simulation.timestep_s": h, "drive.ramp_s": 0.3,
                                                        "contact.impact_speed_floor_mps": v})
            run = simulate_run(cfg)
            s = summarize(run)
            joints = "  ".join(f"{j}: {s[j]['impacts']:3d} / {s[j]['max_contact_force_N']:6.1f}" for j in "BC")
            acc = "  ".join(f"{a} {s[a]['rms_mps2']:6.2f}/{s[a]['peak_mps2']:6.1f}" for a in ("AC1", "AC3", "AC6"))
            print(f"  floor {v:6.0e} m/s  h {h:6.1e} s   {joints}   {acc}   {run.meta['wall_s']:.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--duration", type=float, default=2.0, help="simulated seconds per speed run")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--mujoco", action="store_true", help="also time the MuJoCo twin on the same scenes")
    ap.add_argument("--floor", action="store_true", help="impact-speed floor sensitivity (slow: ~1 min)")
    args = ap.parse_args()
    first_call()
    speed(args.duration, args.repeats, args.mujoco)
    if args.floor:
        floor_sensitivity(args.duration)


if __name__ == "__main__":
    main()
