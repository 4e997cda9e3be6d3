"""Where a MuJoCo twin step goes, stage by stage.

For the ideal (Table 4 test 3), C-only (test 6) and B+C (test 12) scenes at h = 1e-5 s
(models, state at full speed and control sequence from ``analysis/bench_mujoco.py``'s
``prepare``), this script measures in one run, interleaved (best of ``--repeats`` rollouts of
``--steps`` steps each, so that machine load hits every variant alike):

* ``scene``: the twin's model as built, all sensors of the default channel groups: the true
  cost per step (no timers). ``--accelerometers`` picks the accelerometer setting
  (``mujoco.accelerometers``; default ``posthoc``, the twin's default, whose readings are
  computed after the rollout and are not part of the step: ``analysis/bench_mujoco.py`` times
  them with the rollout; ``sensor``: MuJoCo's ``<accelerometer>`` sensors);
* ``timed``: the same rollout with MuJoCo's own stage timers on (``mjData.timer``; MuJoCo
  only times when the global ``mjcb_time`` is set, so the script installs a native clock) and
  the three native callbacks of ``twin/native/_bore.c`` wrapped by native timing
  shims: the bore collider (entry ``mjCOLLISIONFUNC[cylinder][cylinder]``, called in the
  narrow phase), ``mjcb_passive`` (friction and impact-speed damping, called at the end of
  ``mj_passive`` in the velocity stage; it also writes the friction sensors) and ``mjcb_sensor``
  (position stage of the sensors since the friction sensors moved there; velocity stage
  before). Clock and shims are a few lines of C compiled here with the system C
  compiler into a temporary folder (``_bore.c`` itself is untouched); each shim reads the
  clock before and after calling the callback it replaced. The clock is the CPU's time-stamp
  counter calibrated against ``CLOCK_MONOTONIC`` (a read costs about 11 ns here against 29 ns
  for ``clock_gettime``). The difference timed − scene is the cost of the timers themselves
  (about 40 clock reads per step), reported as a row;
* ``floor``: the same model with the constraint solver disabled (``mjDSBL_CONSTRAINT``: no
  collision, contact, loop closure or guide friction), sensors on;
* ``raw floor``: the floor without sensors (``mjDSBL_SENSOR``, no sensor output).

MuJoCo's timers nest: ``step`` = checks + ``forward`` + ``advance``; ``forward`` =
``position`` + ``velocity`` + ``actuation`` + ``constraint`` (solver) + the untimed rest
(position-stage sensors, velocity-stage sensors, ``mj_fwdAcceleration``, acceleration-stage
sensors, energy); ``position`` = kinematics + inertia + collision + make constraints +
project constraints + the untimed rest (tendons, transmission). The table gives each stage
in µs per step of the timed run and its share of that run's step; ``rollout`` is what the
rollout loop spends outside ``mj_step`` (state, control and sensor copies).

Run: ``python analysis/profile_stages.py [--steps N] [--repeats R] [--json FILE]``. The
script builds every model first and only then installs the timing shims (the twin's
``collider.ensure_installed`` re-chains hooks that are not its own), and removes them before
it returns.
"""

from __future__ import annotations

import argparse
import copy
import ctypes
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_mujoco import SCENES, prepare  # noqa: E402

from twin.native.collider import mujoco_library  # noqa: E402
from twin.provenance import stamped  # noqa: E402

D = mujoco.mjtDisableBit
T = mujoco.mjtTimer

_SHIMS = r"""
#include <time.h>
#include <x86intrin.h>
typedef void (*gen_t)(const void*, void*);
typedef void (*sens_t)(const void*, void*, int);
typedef int (*col_t)(const void*, void*, void*, int, int, double);
/* the clock: the CPU's time-stamp counter (about 11 ns a read here, clock_gettime 29 ns),
   scaled to microseconds by prof_calibrate against CLOCK_MONOTONIC */
static unsigned long long base = 0;
static double us_per_tick = 0;
static inline double now_us(void) { return (double)(__rdtsc() - base) * us_per_tick; }
static double mono_us(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec * 1e6 + (double)ts.tv_nsec * 1e-3;
}
double prof_calibrate(double seconds) {
  base = __rdtsc();
  double t0 = mono_us();
  unsigned long long c0 = __rdtsc();
  while (mono_us() - t0 < seconds * 1e6) {}
  double t1 = mono_us();
  unsigned long long c1 = __rdtsc();
  us_per_tick = (t1 - t0) / (double)(c1 - c0);
  return 1.0 / us_per_tick;                              /* ticks per microsecond */
}
double prof_clock(void) { return now_us(); }          /* mjcb_time: microseconds */
gen_t inner_passive = 0; sens_t inner_sensor = 0; col_t inner_collide = 0;
double t_passive = 0, t_sensor = 0, t_collide = 0;
long n_passive = 0, n_sensor = 0, n_collide = 0;
void shim_passive(const void* m, void* d) {
  double t0 = now_us(); inner_passive(m, d); t_passive += now_us() - t0; n_passive++;
}
void shim_sensor(const void* m, void* d, int stage) {
  double t0 = now_us(); inner_sensor(m, d, stage); t_sensor += now_us() - t0; n_sensor++;
}
int shim_collide(const void* m, void* d, void* con, int g1, int g2, double margin) {
  double t0 = now_us(); int n = inner_collide(m, d, con, g1, g2, margin);
  t_collide += now_us() - t0; n_collide++; return n;
}
void prof_reset(void) { t_passive = t_sensor = t_collide = 0; n_passive = n_sensor = n_collide = 0; }
"""

_CB = ("passive", "sensor", "collide")


class Shims:
    """The native clock (``mjcb_time``) and the timing shims around the twin's callbacks."""

    def __init__(self) -> None:
        self.dir = tempfile.TemporaryDirectory(prefix="twin_prof_")
        src = Path(self.dir.name) / "shims.c"
        so = Path(self.dir.name) / "shims.so"
        src.write_text(_SHIMS)
        subprocess.run(["cc", "-O2", "-shared", "-fPIC", str(src), "-o", str(so)], check=True)
        self.lib = ctypes.CDLL(str(so))
        self.lib.prof_calibrate.restype = ctypes.c_double
        self.ticks_per_us = self.lib.prof_calibrate(ctypes.c_double(0.2))
        self.mj = mujoco_library()
        self._slots = {
            "time": ctypes.c_void_p.in_dll(self.mj, "mjcb_time"),
            "passive": ctypes.c_void_p.in_dll(self.mj, "mjcb_passive"),
            "sensor": ctypes.c_void_p.in_dll(self.mj, "mjcb_sensor"),
        }
        table = ctypes.addressof(ctypes.c_void_p.in_dll(self.mj, "mjCOLLISIONFUNC"))
        ncyl = int(mujoco.mjtGeom.mjGEOM_CYLINDER)
        nty = int(mujoco.mjtGeom.mjNGEOMTYPES)
        self._slots["collide"] = ctypes.c_void_p.from_address(table + (ncyl * nty + ncyl) * ctypes.sizeof(ctypes.c_void_p))
        self._saved: dict[str, int | None] = {}

    def _addr(self, name: str) -> int:
        return ctypes.cast(getattr(self.lib, name), ctypes.c_void_p).value

    @property
    def clock(self) -> int | None:
        """The address in ``mjcb_time`` (None: MuJoCo's stage timers are off)."""
        return self._slots["time"].value

    @clock.setter
    def clock(self, addr: int | None) -> None:
        self._slots["time"].value = addr

    def install(self) -> None:
        """Clock on, shims around the installed callbacks (call after every model is built)."""
        self._saved = {k: s.value for k, s in self._slots.items()}
        for cb in _CB:
            if not self._saved[cb]:
                raise RuntimeError(f"no {cb} callback installed: build a twin model first")
            ctypes.c_void_p.in_dll(self.lib, f"inner_{cb}").value = self._saved[cb]
        self._slots["time"].value = self._addr("prof_clock")
        for cb in _CB:
            self._slots[cb].value = self._addr(f"shim_{cb}")

    def remove(self) -> None:
        """Put back what :meth:`install` replaced (no-op when not installed)."""
        for k, v in self._saved.items():
            self._slots[k].value = v
        self._saved = {}

    def reset(self) -> None:
        self.lib.prof_reset()

    def callbacks(self) -> dict[str, tuple[float, int]]:
        return {cb: (ctypes.c_double.in_dll(self.lib, f"t_{cb}").value, ctypes.c_long.in_dll(self.lib, f"n_{cb}").value)
                for cb in _CB}


def run(model, state, ctrl, steps: int, sensors: bool = True) -> tuple[float, mujoco.MjData]:
    """One rollout of ``steps`` steps; (µs per step, the data object holding the timers)."""
    d = mujoco.MjData(model)
    sd = np.empty((1, steps, model.nsensordata)) if sensors and model.nsensordata else None
    t0 = time.perf_counter()
    rollout.rollout(model, d, state[None], ctrl, nstep=steps, sensordata=sd)
    wall = time.perf_counter() - t0
    if abs(d.time - (state[0] + steps * model.opt.timestep)) > 0.5 * model.opt.timestep:
        raise RuntimeError("rollout stopped early (warning)")
    return wall / steps * 1e6, d


def stages(d: mujoco.MjData, cbs: dict[str, tuple[float, int]], steps: int, wall_us: float) -> dict[str, float]:
    """µs per step of each stage of the timed run (see the module docstring)."""
    t = {k: d.timer[int(v)].duration / steps for k, v in
         (("step", T.mjTIMER_STEP), ("forward", T.mjTIMER_FORWARD), ("position", T.mjTIMER_POSITION),
          ("velocity", T.mjTIMER_VELOCITY), ("actuation", T.mjTIMER_ACTUATION),
          ("constraint", T.mjTIMER_CONSTRAINT), ("advance", T.mjTIMER_ADVANCE),
          ("kinematics", T.mjTIMER_POS_KINEMATICS), ("inertia", T.mjTIMER_POS_INERTIA),
          ("collision", T.mjTIMER_POS_COLLISION), ("make", T.mjTIMER_POS_MAKE),
          ("project", T.mjTIMER_POS_PROJECT), ("narrow", T.mjTIMER_COL_NARROW))}
    n = d.timer[int(T.mjTIMER_STEP)].number
    if n != steps:
        raise RuntimeError(f"timer counted {n} steps, expected {steps}")
    cb = {k: v[0] / steps for k, v in cbs.items()}
    pos_rest = t["position"] - (t["kinematics"] + t["inertia"] + t["collision"] + t["make"] + t["project"])
    fwd_rest = t["forward"] - (t["position"] + t["velocity"] + t["actuation"] + t["constraint"])
    return {
        "kinematics": t["kinematics"],
        "inertia": t["inertia"],
        "collision": t["collision"],
        "  bore collider (native)": cb["collide"],
        "make constraints": t["make"],
        "project constraints": t["project"],
        "position, rest (tendon, transmission)": pos_rest,
        "velocity (incl. passive)": t["velocity"],
        "  passive callback (native; contact law, friction and its sensors)": cb["passive"],
        "actuation": t["actuation"],
        "constraint solver": t["constraint"],
        "sensors + acceleration + energy": fwd_rest,
        "  sensor callback (native; marks the pass for the friction sensors)": cb["sensor"],
        "advance (integrator)": t["advance"],
        "step checks": t["step"] - t["forward"] - t["advance"],
        "rollout loop (outside mj_step)": wall_us - t["step"],
        "= step (timed)": wall_us,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=50_000)
    ap.add_argument("--repeats", type=int, default=9)
    ap.add_argument("--json", metavar="FILE", help="also write the numbers as JSON")
    ap.add_argument("--accelerometers", choices=("posthoc", "sensor"), default="posthoc",
                    help="mujoco.accelerometers of the profiled models (default: the twin's default, posthoc)")
    ap.add_argument("--structure", choices=("rigid", "flexible", "both"), default="rigid",
                    help="structure.mode of the profiled models; both: test 12 rigid and flexible side by side")
    args = ap.parse_args()
    global SCENES
    if args.structure == "both":
        SCENES = {"test 12 rigid": (12, "rigid"), "test 12 flexible": (12, "flexible")}
    else:
        SCENES = {label: (tid, args.structure) for label, tid in SCENES.items()}
    shims = Shims()  # before any model is built: reads MuJoCo's own clock (mjcb_time) as the library set it
    mujoco_clock = shims.clock
    variants: dict[str, dict[str, tuple]] = {}
    for label, (tid, structure) in SCENES.items():
        m, s, c = prepare(tid, args.steps, accelerometers=args.accelerometers, structure=structure)
        floor = copy.copy(m)
        floor.opt.disableflags |= D.mjDSBL_CONSTRAINT
        raw = copy.copy(floor)
        raw.opt.disableflags |= D.mjDSBL_SENSOR
        # (model, state, control, sensors?, clock: None = off, "mujoco" = MuJoCo's own, "shims")
        variants[label] = {"scene": (m, s, c, True, None), "scene, MuJoCo's clock on": (m, s, c, True, "mujoco"),
                           "timed": (m, s, c, True, "shims"), "floor": (floor, s, c, True, None),
                           "raw floor": (raw, s, c, False, None)}
    shims.clock = None  # as the twin runs (twin.mujoco_engine.engine.stage_timers_off)
    best = {(lab, k): math.inf for lab, v in variants.items() for k in v}
    prof: dict[str, dict[str, float]] = {}
    for v in variants.values():  # warm-up (the first rollouts of a process run slow), not counted
        for m, s, c, sens, _ in v.values():
            run(m, s, c[:, :min(args.steps, 5000)], min(args.steps, 5000), sens)
    try:
        for _ in range(args.repeats):  # interleaved repeats
            for lab, v in variants.items():
                for k, (m, s, c, sens, clock) in v.items():
                    if clock == "shims":  # clock and shims only for this rollout
                        shims.install()
                        shims.reset()
                    elif clock == "mujoco":
                        shims.clock = mujoco_clock
                    try:
                        us, d = run(m, s, c, args.steps, sens)
                    finally:
                        shims.remove()
                        shims.clock = None
                    if clock == "shims" and us < best[(lab, k)]:
                        prof[lab] = stages(d, shims.callbacks(), args.steps, us)
                    best[(lab, k)] = min(best[(lab, k)], us)
    finally:
        shims.remove()
        shims.clock = mujoco_clock  # leave the process as it was
    from twin.provenance import git_commit

    commit = git_commit()
    print(f"MuJoCo {mujoco.__version__}, h = 1e-5 s, {args.steps} steps, best of {args.repeats} (interleaved), "
          f"commit {commit or '?'}, accelerometers {args.accelerometers}")
    print()
    print("| µs per step | " + " | ".join(SCENES) + " |")
    print("|---|" + "---:|" * len(SCENES))
    for k in ("scene", "scene, MuJoCo's clock on", "floor", "raw floor"):
        print(f"| {k} | " + " | ".join(f"{best[(lab, k)]:.2f}" for lab in SCENES) + " |")
    print("| scene / floor | " + " | ".join(f"{best[(lab, 'scene')] / best[(lab, 'floor')]:.2f}" for lab in SCENES)
          + " |")
    print("| scene / raw floor | " + " | ".join(f"{best[(lab, 'scene')] / best[(lab, 'raw floor')]:.2f}"
                                              for lab in SCENES) + " |")
    print("| real-time factor of the scene | " + " | ".join(f"{10.0 / best[(lab, 'scene')]:.2f}" for lab in SCENES)
          + " |")
    print()
    print("Where a step goes (timed run: µs per step and share of the timed step):")
    print()
    print("| stage | " + " | ".join(SCENES) + " |")
    print("|---|" + "---:|" * len(SCENES))
    for key in prof[next(iter(SCENES))]:
        cells = []
        for lab in SCENES:
            v = prof[lab][key]
            cells.append(f"{v:.2f} ({v / prof[lab]['= step (timed)']:.0%})")
        print(f"| {key} | " + " | ".join(cells) + " |")
    print("| profiling overhead (timed − scene) | " + " | ".join(
        f"{best[(lab, 'timed')] - best[(lab, 'scene')]:.2f}" for lab in SCENES) + " |")
    if args.json:
        Path(args.json).write_text(json.dumps(stamped({
            "mujoco": mujoco.__version__, "commit": commit, "steps": args.steps, "repeats": args.repeats,
            "best_us_per_step": {f"{lab}|{k}": v for (lab, k), v in best.items()}, "stages_us": prof}), indent=1))


if __name__ == "__main__":
    main()
