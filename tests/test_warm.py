"""Warm starts (twin.warm): a run continued from a saved state, and one engine run shared by runs
that differ only in the sensor chain.

Independent bases: the uninterrupted run from rest, compared bit for bit (every channel, the
sensor chain's DAQ channels included) with the run spun up to t0, saved to a file, loaded, restored
into a NEW engine (new model and data) and new sensor chains and continued to T; and each run of a
dataset generated alone (``--no-warm-start``), compared file by file with the dataset whose
repeats share one engine run.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from twin.config import preset
from twin.instrument.chain import ChainStream
from twin.run import Run
from twin.simulation import Collector, make_engine, simulate
from twin.warm import CHAIN_ONLY_FIELDS, WarmState, WarmStateError, mechanical_key, share_groups, simulate_shared, spin_up

from conftest import short

T, T0 = 0.05, 0.0213  # the state is saved mid-chunk (chunks of 10 ms), after the crank has started turning


def _cfg(test: int = 12, **ov):
    base = {"simulation.chunk_s": 0.01, "sensors.output_rate_hz": 100_000.0, "instrumentation.daq_rate_hz": 100_000.0,
            "sensors.channels": ["accel", "encoder", "joints", "crank", "drive"], "instrumentation.seed": 11}
    base.update(ov)
    return short(preset(test), T, **base)


class _Chain:
    """Sink: the sensor chain's DAQ channels of every chunk."""

    def __init__(self, chain: ChainStream):
        self.chain, self.chunks = chain, []

    def write(self, chunk):
        self.chunks.append(self.chain.process(chunk))

    def close(self, meta, summary):
        return Run.concat(self.chunks)

    def abort(self):
        pass


def _chain(cfg):
    return ChainStream(cfg, cfg.output_rate_hz, stream=0, command=True)


def _same_bits(a: Run, b: Run, what: str) -> None:
    assert a.n == b.n and list(a.channels) == list(b.channels), what
    assert abs(a.t0 - b.t0) < 1e-12, what
    for name, ch in a.channels.items():
        assert ch.data.dtype == b.channels[name].data.dtype, f"{what}: {name}"
        assert ch.data.tobytes() == b.channels[name].data.tobytes(), f"{what}: {name} differs"


CASES = {
    "mujoco force B+C": _cfg(12, **{"mujoco.contact_source": "force"}),
    "mujoco law B+C": _cfg(12),
    "mujoco force C, motor drive": _cfg(6, **{"mujoco.contact_source": "force", "drive.mode": "motor"}),
    "reference B+C": _cfg(12, **{"simulation.engine": "reference"}),
    "reference C, motor drive": _cfg(6, **{"simulation.engine": "reference", "drive.mode": "motor"}),
    "mujoco force B+C, prescribed drive": _cfg(12, **{"mujoco.contact_source": "force", "drive.mode": "prescribed"}),
    "mujoco C, guide play": _cfg(6, **{"joints.clearance_guide_mm": 0.1}),
    "reference C, guide play": _cfg(6, **{"simulation.engine": "reference", "joints.clearance_guide_mm": 0.1}),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_run_continued_from_a_saved_state_in_a_new_engine_is_the_uninterrupted_run(case, tmp_path):
    cfg = CASES[case]
    keep, daq = Collector(), _Chain(_chain(cfg))
    fresh = simulate(cfg, [keep, daq])
    whole, whole_daq = keep.run, daq.close({}, {})
    state = spin_up(cfg, T0, chains=[_chain(cfg)])
    n0 = state.samples
    assert n0 == round(T0 * cfg.output_rate_hz) and state.steps == n0 * cfg.output_stride
    path = state.save(tmp_path / "state.npz")
    loaded = WarmState.load(path)
    chain = _chain(cfg)
    loaded.restore_chains([chain])
    keep2, daq2 = Collector(), _Chain(chain)
    out = simulate(cfg, [keep2, daq2], engine=make_engine(cfg), start=loaded)
    _same_bits(whole.slice(n0, whole.n), keep2.run, f"{case}: truth channels")
    _same_bits(whole_daq.slice(n0, whole_daq.n), daq2.close({}, {}), f"{case}: DAQ channels")
    assert out.meta["steps"] == fresh.meta["steps"]
    for j in ("B", "C"):  # the pins touch their bushings before and after t0: the contact state was in use
        if f"fn_{j}" in whole:
            assert np.any(whole[f"fn_{j}"][:n0] > 0) and np.any(keep2.run[f"fn_{j}"] > 0), j


def test_the_contact_and_controller_state_matter():
    """Guards that the test above can fail: the same physics state with the stored contact and
    controller state cleared, or the sensor chain started afresh, gives other bits."""
    cfg = CASES["mujoco force B+C"]
    state = spin_up(cfg, T0, chains=[_chain(cfg)])
    want, got = Collector(), Collector()
    simulate(cfg, [want], start=state)
    engine = make_engine(cfg)

    class Cleared(WarmState):
        def restore_engine(self, engine, cfg):
            n = super().restore_engine(engine, cfg)
            engine.data.userdata[:] = 0.0
            return n

    simulate(cfg, [got], engine=engine, start=Cleared(**vars(state)))
    assert any(want.run[n].tobytes() != got.run[n].tobytes() for n in want.run.channels)
    a, b = _Chain(_chain(cfg)), _Chain(_chain(cfg))
    state.restore_chains([a.chain])
    simulate(cfg, [a], start=state)
    simulate(cfg, [b], start=state)  # a new chain: filters start in steady state, noise from the seed's start
    ra, rb = a.close({}, {}), b.close({}, {})
    assert any(ra[n].tobytes() != rb[n].tobytes() for n in ra.channels)


def test_a_saved_state_refuses_another_configuration_and_bad_files(tmp_path):
    cfg = CASES["mujoco force B+C"]
    state = spin_up(cfg, T0)
    for other in (cfg.replace(**{"joints.clearance_b_mm": 0.5}), cfg.replace(**{"drive.motor_rpm": 500.0})):
        with pytest.raises(WarmStateError, match="another configuration"):
            simulate(other, [], start=state)
    # the noise seed and the name are not the engine's: accepted
    simulate(cfg.replace(name="other", **{"instrumentation.seed": 99}), [], start=state)
    path = state.save(tmp_path / "s.npz")
    with np.load(path, allow_pickle=False) as z:
        files = {k: z[k] for k in z.files}
    meta = json.loads(str(files["meta"]))

    def write(name, **changes):
        f = dict(files)
        f.update(changes)
        np.savez(tmp_path / name, **f)
        return tmp_path / name

    bad_versions = dict(meta, info=dict(meta["info"], versions={"twin": "0", "mujoco": "0"}))
    cases = [(write("v.npz", meta=np.array(json.dumps(bad_versions))), "versions that made it"),
             (write("f.npz", meta=np.array(json.dumps(dict(meta, format="x")))), "field 'format'"),
             (write("n.npz", a_state=np.full_like(files["a_state"], np.nan)), "finite"),
             (write("e.npz", meta=np.array(json.dumps(dict(meta, engine="bullet")))), "field 'engine'")]
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    cases.append((tmp_path / "junk.npz", "not a readable state file"))
    for p, msg in cases:
        with pytest.raises(WarmStateError, match=msg):
            WarmState.load(p)


def test_the_sensor_chain_fields_do_not_change_either_engine():
    """CHAIN_ONLY_FIELDS are left out of the mechanical key: changing them all leaves each engine's
    run bit for bit (the independent basis of the grouping)."""
    from twin.config import with_overrides

    changed = {"instrumentation.models": {"AC1": "ADXL1002"}, "instrumentation.seed": 5, "instrumentation.noise_scale": 1.7, "instrumentation.supply_v": 4.5,
               "instrumentation.zero_g_v": {"AC1": 2.0}, "instrumentation.rail_margin_v": 0.1,
               "instrumentation.response": "lowpass", "instrumentation.resonance_q": 5.0, "instrumentation.noise": False,
               "instrumentation.saturation": False, "instrumentation.daq_rate_hz": 50_000.0,
               "instrumentation.daq_range": "+-5", "instrumentation.adc_bits": 16,
               "instrumentation.quantization": False, "instrumentation.anti_alias": True,
               "instrumentation.anti_alias_hz": 20_000.0, "instrumentation.anti_alias_order": 2,
               "instrumentation.encoder_counts_per_rev": 4096, "instrumentation.encoder_quantization": False}
    assert {k.split(".")[1] for k in changed} == set(CHAIN_ONLY_FIELDS)
    for case in ("mujoco force C, motor drive", "reference C, motor drive", "mujoco law B+C"):
        cfg = CASES[case].replace(**{"simulation.duration_s": 0.01})
        other = with_overrides(cfg, changed)
        assert mechanical_key(other) == mechanical_key(cfg)
        a, b = Collector(), Collector()
        simulate(cfg, [a])
        simulate(other, [b])
        _same_bits(a.run, b.run, case)
    cfg = CASES["mujoco law B+C"]
    assert mechanical_key(cfg.replace(**{"instrumentation.command_v_per_rpm": 0.02})) != mechanical_key(cfg)


def test_a_shared_run_feeds_each_configuration_what_its_own_run_gives():
    cfg = CASES["mujoco force B+C"].replace(**{"simulation.duration_s": 0.02})
    cfgs = [cfg.replace(name=f"r{i}", **{"instrumentation.seed": s}) for i, s in enumerate((1, 2, 3))]
    other = cfg.replace(**{"joints.clearance_c_mm": 0.5})
    assert share_groups(cfgs + [other] + cfgs[:1]) == [[0, 1, 2, 4], [3]]
    alone = []
    for c in cfgs:
        keep, daq = Collector(), _Chain(_chain(c))
        simulate(c, [keep, daq])
        alone.append((keep.run, daq.close({}, {})))
    sinks = [[Collector(), _Chain(_chain(c))] for c in cfgs]
    simulate_shared(cfgs, sinks)
    for c, (run, daq), (keep, chain) in zip(cfgs, alone, sinks):
        _same_bits(run, keep.run, c.name)
        assert keep.run.config is c
        _same_bits(daq, chain.close({}, {}), c.name)
    assert alone[0][1]["volt_AC1"].tobytes() != alone[1][1]["volt_AC1"].tobytes()  # the seeds differ
    with pytest.raises(ValueError, match="mechanical keys"):
        simulate_shared([cfg, other], [[], []])


@pytest.mark.parametrize("engine", ["mujoco", "reference"])
def test_a_dataset_with_warm_starts_is_the_same_bytes_as_without(engine, tmp_path):
    from twin.dataset.generate import generate
    from twin.dataset.spec import parse_spec

    raw = {"dataset": {"name": "w", "seed": 3}, "base": {"test": 3, "duration_s": 0.03, "engine": engine},
           "design": {"kind": "grid", "repeats": 3},
           # the zero-g offsets are drawn per repeat (the sensor chain's): the repeats still share the engine run
           "factors": {"fault": ["C", "BC"], "zero_g_spread_v": [0.02]}}
    spec = parse_spec(raw)
    cold = generate(spec, tmp_path / "cold", workers=2, scheduler="threads", progress=False, warm_start=False)
    assert cold["generation"]["engine_runs_this_call"] == 6
    # warm, in two calls (the second finishes the group the first left half done): 2 + 1 engine runs for 6 runs
    first = generate(spec, tmp_path / "warm", workers=2, scheduler="threads", progress=False, limit=4)
    rest = generate(spec, tmp_path / "warm", workers=2, scheduler="threads", progress=False)
    assert (first["generation"]["engine_runs_this_call"], rest["generation"]["engine_runs_this_call"]) == (2, 1)
    files = sorted(p.name for p in (tmp_path / "cold" / "data").iterdir())
    assert len(files) == 6 and files == sorted(p.name for p in (tmp_path / "warm" / "data").iterdir())
    for name in files:
        assert (tmp_path / "cold" / "data" / name).read_bytes() == (tmp_path / "warm" / "data" / name).read_bytes(), name
    results = [json.loads(p.read_text()) for p in (tmp_path / "warm" / "results").iterdir()]
    assert all(r["status"] == "ok" for r in results)
    assert sum(r["sim_wall_s"] > 0 for r in results) == 3  # the engine's time is on one run per engine run


def test_repeats_with_their_own_mounting_do_not_share_an_engine_run(tmp_path):
    from twin.dataset.design import plan
    from twin.dataset.generate import Prepared, group_tasks
    from twin.dataset.spec import parse_spec

    spec = parse_spec({"dataset": {"name": "m", "seed": 3}, "base": {"test": 3, "duration_s": 0.03},
                       "design": {"kind": "grid", "repeats": 2},
                       # mounting offsets drawn per repeat move the accelerometers: the truth differs
                       "factors": {"fault": ["C"], "mount_offset_m": [0.002], "noise_scale": [1.5]}})
    runs = plan(spec)
    p = Prepared(spec, tmp_path, runs, [], {}, {})
    assert len(group_tasks(p, runs)) == 2
    spec2 = parse_spec({"dataset": {"name": "m", "seed": 3}, "base": {"test": 3, "duration_s": 0.03},
                        "design": {"kind": "grid", "repeats": 2}, "factors": {"fault": ["C"], "noise_scale": [1.5]}})
    runs2 = plan(spec2)
    tasks = group_tasks(Prepared(spec2, tmp_path, runs2, [], {}, {}), runs2)
    assert len(tasks) == 1 and [m["run_id"] for m in tasks[0]["members"]] == [r.run_id for r in runs2]


def test_the_plan_estimate_counts_one_engine_run_per_group(monkeypatch):
    """The estimate with warm starts leaves out the engine's share of the runs that reuse their group's engine
    run. The probes' timings are fixed here (1 s per simulated second, 0.8 of it the engine's, 0.2 s of set-up),
    so the expected walls follow by hand and no measured time enters the assertion."""
    import twin.dataset.worker as worker
    from twin.config import config_from_toml
    from twin.dataset.design import plan
    from twin.dataset.estimate import EFFICIENCY, START_S, estimate_wall
    from twin.dataset.spec import parse_spec

    def probe(task):
        T = config_from_toml(task["config_toml"]).simulation.duration_s
        return {"wall_s": 0.2 + 1.0 * T, "sim_wall_s": 0.8 * T}

    monkeypatch.setattr(worker, "run_one", probe)
    spec = parse_spec({"dataset": {"name": "e", "seed": 3}, "base": {"test": 3, "duration_s": 2.0},
                       "design": {"kind": "grid", "repeats": 4}, "factors": {"fault": ["C"]}})
    runs = plan(spec)
    warm, cold = estimate_wall(spec, runs, 1), estimate_wall(spec, runs, 1, warm_start=False)
    assert (warm["engine_runs"], cold["engine_runs"]) == (1, 4)
    assert cold["wall_s"] == pytest.approx(START_S + 4 * (0.2 + 1.0 * 2.0) / EFFICIENCY)
    assert warm["wall_s"] == pytest.approx(START_S + (4 * 0.2 + 2.0 + 3 * 0.2 * 2.0) / EFFICIENCY)
