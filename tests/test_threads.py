"""Several scenes in one process on threads (issue 16, item 4): bit for bit the serial runs.

Independent bases: serial runs of the same configurations in fresh engines (every channel compared
bit for bit, NaN included); a fresh engine for a reused one; the uninterrupted run for a run
continued from a snapshot in another engine. The per-scene native state is the contact law's
stored impact speed in ``mjData.userdata``, which ``mujoco.rollout`` neither sets nor resets: the
tests check that it matters (a stale value changes the result) and that it never leaks.
"""

from __future__ import annotations

import numpy as np
import pytest

from twin.config import preset
from twin.mujoco_engine.engine import MujocoEngine
from twin.simulation import Collector, simulate, simulate_many, simulate_run
from twin.drive import DriveReference

from conftest import short

#: clearance at C (test 6), at B and C (test 12), ideal joints (test 3); 750 rpm: the pins impact
SCENES = (6, 12, 3)


def _bits_equal(a, b) -> None:
    assert a.n == b.n and list(a.channels) == list(b.channels)
    for name, ch in a.channels.items():
        x, y = ch.data, b.channels[name].data
        assert x.dtype == y.dtype and x.shape == y.shape, name
        assert x.tobytes() == y.tobytes(), f"{a.config.name}: {name} differs"


@pytest.fixture(scope="module")
def serial():
    cfgs = [short(preset(t), 0.1) for t in SCENES]
    return cfgs, [simulate_run(c) for c in cfgs]


def test_scenes_on_threads_equal_serial_runs(serial):
    cfgs, runs = serial
    keeps = [Collector() for _ in cfgs]
    outcomes = simulate_many(cfgs, [[k] for k in keeps], threads=len(cfgs))
    for run, keep, out in zip(runs, keeps, outcomes):
        _bits_equal(run, keep.run)
        assert out.meta["steps"] == run.config.n_samples * run.config.output_stride
    # the clearance scenes impact, so the stored impact speeds were in use on every thread
    assert outcomes[0].summary["C"]["impacts"] > 0 and outcomes[1].summary["B"]["impacts"] > 0
    # twice as many scenes as threads: a thread runs one scene after another
    keeps2 = [Collector() for _ in range(2 * len(cfgs))]
    simulate_many(cfgs + cfgs, [[k] for k in keeps2], threads=2)
    for run, keep in zip(runs + runs, keeps2):
        _bits_equal(run, keep.run)


def test_reference_engine_scenes_on_threads_equal_serial_runs():
    # its compiled loop releases the GIL too; a dataset of the reference engine runs on threads alike
    cfgs = [short(preset(t), 0.05, **{"simulation.engine": "reference"}) for t in SCENES]
    runs = [simulate_run(c) for c in cfgs]
    keeps = [Collector() for _ in cfgs]
    simulate_many(cfgs, [[k] for k in keeps])
    for run, keep in zip(runs, keeps):
        _bits_equal(run, keep.run)


def test_an_error_in_one_scene_is_raised_after_the_others_end(serial):
    cfgs, runs = serial

    class Broken(Collector):
        def write(self, chunk):
            raise OSError("disk full")

    keep = Collector()
    with pytest.raises(OSError, match="disk full"):
        simulate_many([cfgs[2], cfgs[0]], [[Broken()], [keep]], threads=2)
    _bits_equal(runs[0], keep.run)


def test_a_reused_engine_gives_the_bits_of_a_fresh_one(serial):
    cfgs, runs = serial
    cfg = cfgs[1]  # B+C
    engine = MujocoEngine(cfg)
    keep = Collector()
    simulate(cfg, [keep], engine=engine)
    _bits_equal(runs[1], keep.run)
    # a stale impact speed (another scene's contact event) in the data object: reset clears it
    engine.data.userdata[:] = 0.37
    keep = Collector()
    simulate(cfg, [keep], engine=engine)
    _bits_equal(runs[1], keep.run)


def _refs(cfg, k0: int, n: int):
    return DriveReference(cfg)((k0 + np.arange(n)) * cfg.simulation.timestep_s)


def test_a_snapshot_carries_the_stored_impact_speed_to_another_engine(serial):
    cfg = serial[0][1]  # B+C
    a = MujocoEngine(cfg)
    a.reset()
    k, step = 0, 200
    floor = cfg.contact.impact_speed_floor_mps  # a resting contact stores the floor, re-stored alike
    while not np.any(a.data.userdata > 2 * floor):  # run into an impact
        a.advance(*_refs(cfg, k, step), 1)
        k += step
        assert k < cfg.n_samples * cfg.output_stride, "no contact event in the run"
    snap = a.snapshot()
    n = 3000  # on through the event and beyond
    want = a.advance(*_refs(cfg, k, n), 1)
    b = MujocoEngine(cfg)
    b.reset()
    b.advance(*_refs(cfg, 0, 50), 1)  # b's data holds a state of its own
    b.restore(snap)
    got = b.advance(*_refs(cfg, k, n), 1)
    assert list(got) == list(want)
    for name in want:
        assert got[name].tobytes() == want[name].tobytes(), name
    # the stored impact speed is state: the same physics state with it cleared gives other bits
    c = MujocoEngine(cfg)
    c.restore(snap)
    c.data.userdata[:] = 0.0
    other = c.advance(*_refs(cfg, k, n), 1)
    assert any(other[name].tobytes() != want[name].tobytes() for name in want)
    with pytest.raises(ValueError, match="state size"):
        MujocoEngine(serial[0][2]).restore(snap)  # the ideal scene has no clearance joints
