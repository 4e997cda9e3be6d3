"""Output written on a thread (twin.simulation.ThreadedSink): same bytes, same lifecycle; chunks never
share memory with the engine's buffers."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from twin.config import preset
from twin.errors import TwinError
from twin.mcapfile import RunWriter, read_run
from twin.simulation import Collector, ThreadedSink, simulate, simulate_run

from conftest import short


def test_threaded_mcap_file_is_the_same_bytes(tmp_path):
    cfg = short(preset(12), 0.05, **{"simulation.chunk_s": 0.01})
    keep = Collector()
    out = simulate(cfg, [keep])
    run = keep.run
    pieces = [run.slice(i, min(i + 777, run.n)) for i in range(0, run.n, 777)]
    files = []
    for name, wrap in (("serial.mcap", lambda s: s), ("thread.mcap", ThreadedSink)):
        w = wrap(RunWriter(tmp_path / name, cfg, block=300))
        for p in pieces:
            w.write(p)
        w.close(out.meta, out.summary)
        files.append((tmp_path / name).read_bytes())
    assert files[0] == files[1]
    back = read_run(tmp_path / "thread.mcap")
    assert all(np.array_equal(back[k], run[k]) for k in run.channels)


def test_twin_simulate_writes_through_the_thread(tmp_path):
    cfg = short(preset(6), 0.04, **{"simulation.chunk_s": 0.01})
    simulate(cfg, [ThreadedSink(RunWriter(tmp_path / "a.mcap", cfg))])
    whole = simulate_run(cfg)
    back = read_run(tmp_path / "a.mcap")
    assert all(np.array_equal(back[k], whole[k]) for k in whole.channels)


class Failing:
    def __init__(self, at):
        self.at, self.n, self.log, self.thread = at, 0, [], None

    def write(self, chunk):
        self.n += 1
        self.thread = threading.current_thread()
        if self.n == self.at:
            raise TwinError("disk full (test)")
        self.log.append("write")

    def close(self, meta, summary):
        self.log.append("close")

    def abort(self):
        self.log.append("abort")


def test_an_error_on_the_writer_thread_reaches_the_caller_and_aborts(tmp_path):
    cfg = short(preset(3), 0.05, **{"simulation.chunk_s": 0.01})
    inner = Failing(at=2)
    with pytest.raises(TwinError, match="disk full"):
        simulate(cfg, [ThreadedSink(inner)])
    assert inner.thread is not threading.main_thread()
    assert inner.log[-1] == "abort" and "close" not in inner.log
    # a failing MCAP writer behind the thread leaves no temporary file
    w = RunWriter(tmp_path / "x.mcap", cfg)

    class Boom:
        def write(self, chunk):
            raise KeyboardInterrupt

        def close(self, meta, summary):
            pass

        def abort(self):
            pass

    with pytest.raises(KeyboardInterrupt):
        simulate(cfg, [ThreadedSink(w), Boom()])
    assert list(tmp_path.iterdir()) == []


def test_abort_before_any_write_and_close_without_chunks():
    inner = Failing(at=99)
    s = ThreadedSink(inner)
    s.abort()
    assert inner.log == ["abort"]
    inner = Failing(at=99)
    ThreadedSink(inner).close({}, {})
    assert inner.log == ["close"]


@pytest.mark.parametrize("channels", [["slider"], ["encoder"], ["drive"]])
def test_one_sensor_scenes_do_not_alias_the_engine_buffer(channels):
    # one sensor value per step: a column of MuJoCo's sensor buffer is contiguous, and the chunks
    # used to be views of the buffer the next chunk overwrote
    cfg = short(preset(3), 0.03, **{"sensors.channels": channels})
    a = simulate_run(cfg.replace(**{"simulation.chunk_s": 0.01}))
    b = simulate_run(cfg.replace(**{"simulation.chunk_s": 0.5}))
    assert all(np.array_equal(a[k], b[k]) for k in b.channels)
