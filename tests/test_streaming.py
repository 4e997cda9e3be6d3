"""Streaming runs: the chunk loop, sinks with a lifecycle, summaries kept chunk by chunk.

Independent bases: the whole-record impact count (:func:`twin.summary.count_impacts`, the batch
algorithm) for the streaming counter; the whole collected run for the streamed summary; the
chunks themselves (weak references) for "nothing keeps a chunk after the sinks saw it".
"""

from __future__ import annotations

import gc
import json
import weakref

import numpy as np
import pytest

from twin.config import preset
from twin.errors import SimulationError, TwinError
from twin.mcapfile import RunWriter, read_run, read_summary
from twin.simulation import Collector, run_chunks, simulate, simulate_run
from twin.summary import ImpactCounter, SummaryAccumulator, SummaryJsonWriter, count_impacts, summarize

from conftest import short


@pytest.mark.parametrize("seed", range(8))
def test_streaming_impact_count_equals_the_whole_record(seed):
    rng = np.random.default_rng(seed)
    # contact bursts and gaps of 1..40 samples, starting in or out of contact
    runs = rng.integers(1, 40, size=300)
    state = bool(seed % 2)
    x = np.concatenate([np.full(r, (state := not state)) for r in runs])
    for min_free_s in (1e-5, 1e-4, 2.5e-4):
        whole = count_impacts(x, 1e5, min_free_s)
        cuts = np.sort(rng.choice(np.arange(1, len(x)), size=25, replace=False))
        c = ImpactCounter(1e5, min_free_s)
        for part in np.split(x, cuts):
            c.update(part)
        assert c.count == whole > 0


def test_one_sample_chunks_count_the_same():
    x = np.array([1, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 0, 1], bool)
    c = ImpactCounter(1.0, 3.0)  # 3 samples of separation make a new impact
    for v in x:
        c.update(np.array([v]))
    assert c.count == count_impacts(x, 1.0, 3.0) == 2  # the start in contact is not an impact


@pytest.mark.parametrize("engine", ["mujoco", "reference"])
def test_streamed_summary_equals_the_summary_of_the_whole_run(engine):
    cfg = short(preset(12), 0.12, **{"simulation.chunk_s": 0.013, "simulation.engine": engine})
    keep = Collector()
    outcome = simulate(cfg, [keep])
    whole = summarize(keep.run)
    assert keep.run.n == cfg.n_samples and len(set(whole) ^ set(outcome.summary)) == 0
    for k, v in whole.items():
        if isinstance(v, dict):
            for kk, vv in v.items():
                assert outcome.summary[k][kk] == pytest.approx(vv, rel=1e-12, abs=0), (k, kk)
    assert outcome.summary["B"]["impacts"] >= 1 and outcome.summary["C"]["impacts"] >= 1


def test_nothing_keeps_a_chunk_after_the_sinks_saw_it():
    """Bounded memory without timing anything: every chunk but the last is garbage once the sinks
    have written it (the MCAP writer keeps at most a partial block, as a copy)."""
    refs: list[weakref.ref] = []

    class Watch:
        def write(self, chunk):
            refs.append(weakref.ref(chunk.channels["AC1"].data))

        def close(self, meta, summary):
            pass

        def abort(self):
            pass

    class Check(Watch):
        def write(self, chunk):
            gc.collect()
            alive = sum(r() is not None for r in refs)
            assert alive <= 1, f"{alive} earlier chunks still referenced"
            super().write(chunk)

    cfg = short(preset(6), 0.1, **{"simulation.chunk_s": 0.01})
    simulate(cfg, [Check(), RunWriter_tmp(cfg)])
    assert len(refs) == 10


def RunWriter_tmp(cfg):  # noqa: N802 - a sink factory for the test above
    import tempfile
    from pathlib import Path

    d = Path(tempfile.mkdtemp())
    return RunWriter(d / "x.mcap", cfg, block=300)  # blocks straddle chunks


class Recorder:
    """A sink that records its calls and can fail on demand."""

    def __init__(self, log, name, fail_write=None, fail_close=False):
        self.log, self.name, self.fail_write, self.fail_close = log, name, fail_write, fail_close
        self.n = 0

    def write(self, chunk):
        self.n += 1
        if self.fail_write == self.n:
            raise TwinError(f"{self.name}: disk full (test)")
        self.log.append((self.name, "write"))

    def close(self, meta, summary):
        if self.fail_close:
            raise TwinError(f"{self.name}: cannot rename (test)")
        self.log.append((self.name, "close"))

    def abort(self):
        self.log.append((self.name, "abort"))


def test_a_failing_sink_aborts_every_sink_not_yet_closed():
    cfg = short(preset(3), 0.03, **{"simulation.chunk_s": 0.01})
    log = []
    with pytest.raises(TwinError, match="disk full"):
        simulate(cfg, [Recorder(log, "a"), Recorder(log, "b", fail_write=2)])
    assert log[-2:] == [("a", "abort"), ("b", "abort")] and ("a", "close") not in log
    log = []
    with pytest.raises(TwinError, match="cannot rename"):
        simulate(cfg, [Recorder(log, "a"), Recorder(log, "b", fail_close=True), Recorder(log, "c")])
    assert log[-3:] == [("a", "close"), ("b", "abort"), ("c", "abort")]


def test_engine_construction_failure_aborts_the_sinks(tmp_path):
    cfg = short(preset(3), 0.03).replace(**{"drive.program": "trace", "drive.trace_file": str(tmp_path / "no.npz")})
    log = []
    with pytest.raises(TwinError, match="drive.trace_file"):
        simulate(cfg, [Recorder(log, "a")])
    assert log == [("a", "abort")]


def test_mcap_and_summary_sinks_write_on_close_only(tmp_path):
    cfg = short(preset(6), 0.03, **{"simulation.chunk_s": 0.01})
    out, js = tmp_path / "r.mcap", tmp_path / "s.json"
    outcome = simulate(cfg, [RunWriter(out, cfg), SummaryJsonWriter(js)])
    assert read_summary(out) == json.loads(js.read_text()) == json.loads(json.dumps(outcome.summary))
    run = read_run(out)
    assert run.n == 3000 and run.meta["steps"] == 3000
    # a failing run writes neither, and the writer made no file before its first chunk
    w = RunWriter(tmp_path / "never.mcap", cfg)
    assert not list(tmp_path.glob(".never*"))
    w.abort()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.mcap", "s.json"]


def test_run_chunks_is_the_one_loop_and_engines_do_not_import_it():
    import ast
    from pathlib import Path

    import twin

    root = Path(twin.__file__).parent
    for path in (root / "mujoco_engine" / "engine.py", root / "reference" / "engine.py"):
        tree = ast.parse(path.read_text())
        mods = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
        mods |= {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        assert "twin.simulation" not in mods and "twin.cli" not in mods, path
    cfg = short(preset(3), 0.02, **{"simulation.chunk_s": 0.007})
    chunks = list(run_chunks(cfg))
    assert [c.n for c in chunks] == [700, 700, 600] and [c.t0 for c in chunks] == pytest.approx([0, 0.007, 0.014])


def test_engine_that_returns_too_few_samples_is_refused():
    from twin.simulation import make_engine

    cfg = short(preset(3), 0.02)
    eng = make_engine(cfg)
    real = eng.advance
    eng.advance = lambda th, om, stride: {k: v[:-1] for k, v in real(th, om, stride).items()}
    with pytest.raises(SimulationError, match="expected"):
        simulate(cfg, [], engine=eng)


def test_simulate_run_keeps_the_whole_run_for_short_runs():
    cfg = short(preset(6), 0.02)
    run = simulate_run(cfg)
    acc = SummaryAccumulator(cfg)
    acc.update(run)
    assert run.n == 2000 and acc.result(run.meta)["samples"] == 2000
