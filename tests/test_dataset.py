"""Synthetic datasets: specs, designs, splits, generation, resuming, executors, reading.

Independent bases: the design's counts and ranges from the spec (closed form); splits checked
per configuration group; bit-identity across worker counts, executors and a resumed generation
(the same spec must give the same bytes); statistics recomputed from the files with pyarrow;
the files read in a separate Python process that never imports twin.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from twin.cli import main
from twin.dataset import describe, load_spec, open as open_dataset, verify
from twin.dataset.design import design_points, plan
from twin.dataset.spec import SpecError, parse_spec

ROOT = Path(__file__).resolve().parent.parent
TINY = ROOT / "analysis" / "datasets" / "tiny.toml"


def _spec(**sections) -> dict:
    base = {"dataset": {"name": "t", "seed": 3}, "base": {"test": 3, "duration_s": 0.05}}
    base.update(sections)
    return base


# ------------------------------------------------------------------------ designs
def test_designs_cover_their_ranges_and_counts():
    grid = parse_spec(_spec(factors={"fault": ["none", "C"], "motor_rpm": {"range": [250, 750], "levels": 3}},
                            design={"kind": "grid", "repeats": 2}))
    pts = design_points(grid)
    assert len(pts) == 6 and {p["motor_rpm"] for p in pts} == {250.0, 500.0, 750.0}
    assert len(plan(grid)) == 12
    for kind in ("lhs", "sobol", "random"):
        s = parse_spec(_spec(factors={"clearance_c_mm": {"range": [0.02, 1.0], "scale": "log"},
                                      "orientation": ["x", "y", "z"], "restitution": {"range": [0.3, 0.5]}},
                             design={"kind": kind, "runs": 64}))
        pts = design_points(s)
        c = np.array([p["clearance_c_mm"] for p in pts])
        assert len(pts) == 64 and c.min() >= 0.02 and c.max() <= 1.0
        # log scale: as many points below the geometric mean as above it (within sampling error)
        assert abs(np.mean(c < math.sqrt(0.02)) - 0.5) < 0.2
        assert {p["orientation"] for p in pts} == {"x", "y", "z"}
        if kind == "lhs":  # one point per stratum of each factor
            u = (np.log(c) - np.log(0.02)) / (np.log(1.0) - np.log(0.02))
            assert sorted(np.floor(u * 64).astype(int)) == list(range(64))


def test_an_excluded_band_is_never_drawn_and_the_design_keeps_its_strata():
    f = {"clearance_c_mm": {"range": [0.02, 1.0], "scale": "log", "exclude": [0.06, 0.085]}}
    s = parse_spec(_spec(factors=f, design={"kind": "lhs", "runs": 60}))
    c = np.array([p["clearance_c_mm"] for p in design_points(s)])
    assert c.min() >= 0.02 and c.max() <= 1.0 and not np.any((c > 0.06) & (c < 0.085))
    # the two parts laid end to end in log: one point per stratum of their joint length
    lg, a, b = np.log(c), math.log(0.06), math.log(0.085)
    u = np.where(lg <= a, lg - math.log(0.02), lg - (b - a) - math.log(0.02))
    u /= math.log(1.0 / 0.02) - (b - a)
    assert sorted(np.floor(u * 60 + 1e-9).astype(int)) == list(range(60))
    g = parse_spec(_spec(factors={"motor_rpm": {"range": [200, 800], "levels": 5, "exclude": [400, 600]}}))
    assert [p["motor_rpm"] for p in design_points(g)] == pytest.approx([200, 300, 400, 700, 800])
    # a spec without the key keeps its identity (the key did not exist when older datasets were made)
    assert "exclude" not in json.dumps(parse_spec(_spec(factors={"motor_rpm": [250.0]})).canonical())
    with pytest.raises(SpecError, match=r"factors.motor_rpm.exclude: must be \[a, b\] with 200 < a < b < 800"):
        parse_spec(_spec(factors={"motor_rpm": {"range": [200, 800], "levels": 5, "exclude": [100, 600]}}))


def test_runs_are_labelled_seeded_and_identified_by_configuration():
    s = load_spec(TINY)
    runs = plan(s)
    assert [r.labels["fault"] for r in runs] == ["none", "none", "B", "B", "C", "C", "BC", "BC"]
    assert all(r.config.joints.clearance_b_mm == (0.1 if "B" in r.labels["fault"] else 0.0) for r in runs)
    assert plan(s) == runs  # deterministic
    seeds = [r.seed for r in runs]
    ref = [int(c.generate_state(1, np.uint64)[0]) for c in np.random.SeedSequence(7).spawn(8)]
    assert seeds == ref
    assert len({r.run_id for r in runs}) == 8
    assert {r.config.instrumentation.seed for r in runs} == {x % 2**63 for x in ref}


def test_splits_are_per_configuration_group_stratified_and_hold_out_values():
    s = parse_spec(_spec(factors={"fault": ["none", "B", "C", "BC"], "orientation": ["x", "y", "z"],
                                  "motor_rpm": [250.0, 500.0, 750.0]},
                         design={"kind": "grid", "repeats": 3},
                         splits={"train": 0.6, "val": 0.2, "test": 0.2, "holdout": {"motor_rpm": [500.0]}}))
    runs = plan(s)
    by_point: dict[int, set] = {}
    for r in runs:
        by_point.setdefault(r.point, set()).add(r.split)
    assert all(len(v) == 1 for v in by_point.values())  # no configuration in two splits
    assert all(r.split == "test" for r in runs if r.factors["motor_rpm"] == 500.0)
    train = [r for r in runs if r.split == "train"]
    assert {r.factors["motor_rpm"] for r in train} == {250.0, 750.0}
    for f in ("none", "B", "C", "BC"):  # every class in every split
        assert {r.split for r in runs if r.labels["fault"] == f} == {"train", "val", "test"}
    # train fraction of the non-held-out groups: 0.6 within one group per class
    free = [p for p, v in by_point.items() if runs[p * 3].factors["motor_rpm"] != 500.0]
    n_train = len({r.point for r in train})
    assert abs(n_train - 0.6 * len(free)) <= 4


def test_random_profiles_and_per_run_draws_come_from_the_run_seed():
    s = parse_spec(_spec(factors={"program": ["random-profile"], "zero_g_spread_v": [0.02],
                                  "mount_offset_m": [0.002]}, design={"kind": "grid", "repeats": 3},
                         base={"test": 3, "duration_s": 2.0, "profile": {"rpm": [300, 700], "hold_s": [0.3, 0.6]}}))
    runs = plan(s)
    profiles = [r.config.drive.steps_rpm for r in runs]
    assert len(set(profiles)) == 3  # each repeat its own profile
    for r in runs:
        d = r.config.drive
        assert d.program == "steps" and d.steps_s[0] == 0 and all(b - a >= 0.3 - 1e-9 for a, b in zip(d.steps_s, d.steps_s[1:]))
        assert all(x == 0 or 300 <= x <= 700 for x in d.steps_rpm)
        offs = np.array(list(r.config.instrumentation.zero_g_v.values()))
        assert len(offs) == 6 and np.all(np.abs(offs - 2.5) < 0.2)
        from twin.config import BenchConfig

        nominal = BenchConfig().sensors.accelerometers
        for a, m in r.config.sensors.accelerometers.items():  # each sensor within ±2 mm of its mount
            assert all(abs(p - q) <= 0.002 + 1e-12 for p, q in zip(m.position_m, nominal[a].position_m)), a
        assert any(m.position_m != nominal[a].position_m for a, m in r.config.sensors.accelerometers.items())
    assert plan(s)[0].config == runs[0].config


# ----------------------------------------------------------------- bad spec input
BAD_SPECS = [
    ('[dataset]\nname = "x"\n[factors]\nclearence_c_mm = [0.1]\n', "factors.clearence_c_mm: unknown factor"),
    ('[dataset]\nname = "x"\n[factors]\nmotor_rpm = { range = [750, 250] }\n[design]\nkind = "lhs"\nruns = 4\n',
     "factors.motor_rpm.range: is empty or inverted"),
    ('[dataset]\nname = "x"\n[factors]\nmotor_rpm = { range = [250, 250] }\n[design]\nkind = "lhs"\nruns = 4\n',
     "is empty or inverted"),
    ('[dataset]\nname = "x"\n[factors]\nmotor_rpm = []\n', "factors.motor_rpm: needs at least one value"),
    ('[dataset]\nname = "x"\n[base]\nengine = "reference"\n[factors]\n"mujoco.contact_damping_scale" = [1.0]\n',
     "not supported by the reference engine"),
    ('[dataset]\nname = "x"\n[design]\nkind = "lhs"\nruns = 0\n', "design.runs"),
    ('[dataset]\nname = "x"\n[factors]\nmotor_rpm = { range = [250, 750] }\n', "a grid needs values"),
    ('[dataset]\nname = "x"\n[factors]\nfault = ["none", "A"]\n', "factors.fault: must be one of"),
    ('[dataset]\nname = "x"\n[factors]\nmotor_rpm = [2000.0]\n', "factors.motor_rpm: must lie in"),
    ('[dataset]\nname = "x"\n[factors]\nclearance_c_mm = { range = [0, 1], scale = "log", levels = 3 }\n',
     "a log scale needs low > 0"),
    ('[dataset]\nname = "x"\n[base]\ntest = 3\nset = { "drive.ramp_s" = -1 }\n', "drive.ramp_s"),
    ('[dataset]\nname = "x"\n[outputs]\ntruth = []\ninstrumented = false\n', "outputs: stores nothing"),
    ('[dataset]\nname = "x"\n[outputs]\ntruth = ["accel", "gps"]\n', "sensors.channels"),
    ('[dataset]\nname = "x"\n[splits]\ntrain = 0.5\nval = 0.1\ntest = 0.1\n', "summing to 1"),
    ('[dataset]\nname = "x"\n[splits]\nholdout = { orientation = ["z"] }\n', "is not a varied factor"),
    ('[dataset]\nname = "x"\n[extra]\na = 1\n', "extra: unknown section"),
    ('[dataset]\nname = "x y"\n', "dataset.name"),
    ('[dataset\nname = "x"\n', "is not valid TOML"),
]


@pytest.mark.parametrize("text, fragment", BAD_SPECS, ids=[f[1][:40] for f in BAD_SPECS])
def test_bad_specs_are_one_line_and_write_nothing(text, fragment, tmp_path, capsys):
    spec = tmp_path / "bad.toml"
    spec.write_text(text)
    for argv in (["dataset", "plan", str(spec), "--no-estimate"],
                 ["dataset", "generate", str(spec), "--out", str(tmp_path / "ds"), "--workers", "1"]):
        rc = main(argv)
        err = capsys.readouterr().err
        assert rc == 2 and err.startswith("twin: error: ") and err.count("\n") == 1 and fragment in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_bad_spec_object_errors_name_the_key():
    with pytest.raises(SpecError, match="design.repeats"):
        parse_spec(_spec(design={"repeats": 0}))


# ------------------------------------------------------------------- generation
def _sha(p: Path) -> str:
    return hashlib.sha256(p.read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def tiny(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("ds") / "tiny"
    assert main(["dataset", "generate", str(TINY), "--out", str(out), "--workers", "2", "--no-progress"]) == 0
    return out


def test_generated_dataset_matches_its_manifest(tiny):
    assert verify(tiny) == []
    info = json.loads((tiny / "info.json").read_text())
    assert info["complete"] and info["runs"] == {"planned": 8, "ok": 8, "failed": 0, "pending": 0}
    runs = pq.read_table(tiny / "runs.parquet").to_pylist()
    names = [c["name"] for c in info["channels"]]
    labels = ["point", "repeat", "split", "factor_fault", "factor_motor_rpm", "fault", "clearance_b_mm",
              "clearance_c_mm", "orientation", "program", "motor_rpm"]
    assert info["format"] == "twin-dataset/2" and info["label_columns"] == labels
    for r in runs:
        t = pq.read_table(tiny / r["file"])
        assert t.column_names == ["run_id", "t"] + labels + names and t.num_rows == 30_000 == r["rows"]
        # labels from the configuration stored in the file itself
        meta = json.loads(pq.read_schema(tiny / r["file"]).metadata[b"twin.dataset"])
        import tomllib
        cfg = tomllib.loads(meta["config_toml"])
        assert cfg["joints"]["clearance_b_mm"] == r["clearance_b_mm"] and meta["run_id"] == r["run_id"]
        ecc_b = t["ecc_B_x"].to_numpy()
        assert np.all(np.isnan(ecc_b)) == (r["clearance_b_mm"] == 0)
    types = {c["name"]: c["dtype"] for c in info["channels"]}
    assert types["encoder_counts"] == "int32" and types["volt_AC1"] == "float32" and types["AC4"] == "float32"
    assert types["encoder_angle"] == "float64" and types["ecc_C_x"] == "float64"
    text = describe(tiny)
    assert "train     4       4     1  1  1   1" in text


def test_volts_are_stored_exactly_and_counts_are_whole(tiny):
    f = next((tiny / "data").glob("*.parquet"))
    t = pq.read_table(f)
    v = t["volt_AC4"].to_numpy().astype(np.float64)
    lsb = 20.0 / 2**18
    codes = (v + 10.0) / lsb
    np.testing.assert_array_equal(codes, np.round(codes))  # on the 18-bit grid: nothing lost in float32
    assert t["encoder_counts"].type == "int32"


def test_stats_are_over_the_train_split_only(tiny):
    runs = pq.read_table(tiny / "runs.parquet").to_pylist()
    stats = json.loads((tiny / "stats.json").read_text())
    assert stats["split"] == "train"
    for ch in ("meas_AC4", "volt_AC1", "fn_C"):
        xs = [pq.read_table(tiny / r["file"], columns=[ch])[ch].to_numpy().astype(np.float64)
              for r in runs if r["split"] == "train"]
        x = np.concatenate(xs)
        x = x[np.isfinite(x)]
        s = stats["channels"][ch]
        assert s["count"] == x.size
        assert s["mean"] == pytest.approx(x.mean(), rel=1e-9, abs=1e-12)
        assert s["std"] == pytest.approx(x.std(), rel=1e-6)
        assert (s["min"], s["max"]) == (x.min(), x.max())


def test_same_spec_gives_the_same_bytes_with_one_worker_and_with_dask(tiny, tmp_path, capsys):
    ref = {f.name: _sha(f) for f in (tiny / "data").glob("*.parquet")}
    one = tmp_path / "one"
    assert main(["dataset", "generate", str(TINY), "--out", str(one), "--workers", "1", "--limit", "2",
                 "--no-progress"]) == 0
    got = {f.name: _sha(f) for f in (one / "data").glob("*.parquet")}
    assert len(got) == 2 and all(ref[k] == v for k, v in got.items())
    info = json.loads((one / "info.json").read_text())
    assert not info["complete"] and info["runs"]["pending"] == 6
    # the same folder finished on a Dask LocalCluster: the missing runs only
    assert main(["dataset", "generate", str(TINY), "--out", str(one), "--workers", "2", "--scheduler", "local",
                 "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "6 runs simulated" in out
    got = {f.name: _sha(f) for f in (one / "data").glob("*.parquet")}
    assert got == ref and verify(one) == []


def test_worker_processes_give_the_same_bytes_as_threads(tiny, tmp_path, capsys):
    from twin.dataset.generate import default_scheduler

    # the fixture ran on the default executor: 2 workers are threads of the driver, more are processes
    assert default_scheduler(2) == "threads" and default_scheduler(3) == "processes"
    ref = {f.name: _sha(f) for f in (tiny / "data").glob("*.parquet")}
    out = tmp_path / "processes"
    assert main(["dataset", "generate", str(TINY), "--out", str(out), "--workers", "2", "--scheduler", "processes",
                 "--no-progress"]) == 0
    assert "8 runs simulated (0 failed) on 2 worker processes" in capsys.readouterr().out
    got = {f.name: _sha(f) for f in (out / "data").glob("*.parquet")}
    assert got == ref and verify(out) == []


def test_a_driver_that_stops_interrupts_its_threads_runs(tmp_path):
    from twin.dataset.generate import _threads, prepare, task_of

    p = prepare(load_spec(TINY), tmp_path / "stopped")
    (p.out / "data").mkdir(parents=True)
    runs = _threads(2)([task_of(p, r) for r in p.runs])
    assert next(runs)["status"] == "ok"
    runs.close()  # the driver stops (an error, Ctrl-C): the run in flight ends at its next chunk
    files = list((p.out / "data").iterdir())
    assert not [f for f in files if ".tmp" in f.name] and 1 <= len(files) <= 2
    for f in files:
        assert pq.read_table(f).num_rows == 30_000


def test_killed_generation_resumes_with_the_missing_runs_only(tiny, tmp_path, capsys):
    out = tmp_path / "killed"
    proc = subprocess.Popen([sys.executable, "-m", "twin.cli", "dataset", "generate", str(TINY), "--out", str(out),
                             "--workers", "1", "--no-progress"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while not (out / "results").is_dir() or len(list((out / "results").glob("*.json"))) < 2:
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    time.sleep(1.0)  # the orphaned worker notices its driver is gone
    done_before = {p.stem for p in (out / "results").glob("*.json")}
    kept = {rid: (out / "data" / f"{rid}.parquet").stat() for rid in done_before}
    rc = main(["dataset", "generate", str(TINY), "--out", str(out), "--workers", "2", "--no-progress"])
    assert rc == 0
    # the finished runs were not simulated again: their files are the very same ones
    for rid, st in kept.items():
        now = (out / "data" / f"{rid}.parquet").stat()
        assert (now.st_ino, now.st_mtime_ns) == (st.st_ino, st.st_mtime_ns), rid
    assert f"{8 - len(done_before)} runs simulated" in capsys.readouterr().out
    assert verify(out) == []
    runs = pq.read_table(out / "runs.parquet").to_pylist()
    assert len(runs) == 8 and len({r["run_id"] for r in runs}) == 8 and all(r["status"] == "ok" for r in runs)
    assert {f.name: _sha(f) for f in (out / "data").glob("*.parquet")} == \
        {f.name: _sha(f) for f in (tiny / "data").glob("*.parquet")}
    assert not [p for p in out.rglob("*") if ".tmp" in p.name]
    assert len(done_before) >= 2


def test_a_folder_of_another_dataset_is_refused(tiny, tmp_path, capsys):
    other = tmp_path / "other.toml"
    other.write_text(TINY.read_text().replace("seed = 7", "seed = 8"))
    before = {p: p.stat().st_mtime_ns for p in tiny.rglob("*")}
    rc = main(["dataset", "generate", str(other), "--out", str(tiny), "--workers", "1"])
    err = capsys.readouterr().err
    assert rc == 2 and "holds a different dataset" in err and "seed" in err and err.count("\n") == 1
    assert {p: p.stat().st_mtime_ns for p in tiny.rglob("*")} == before
    junk = tmp_path / "junk"
    junk.mkdir()
    (junk / "notes.txt").write_text("mine")
    assert main(["dataset", "generate", str(TINY), "--out", str(junk), "--workers", "1"]) == 2
    assert "holds no dataset" in capsys.readouterr().err
    assert sorted(p.name for p in junk.iterdir()) == ["notes.txt"]


def test_runs_of_another_twin_version_are_not_mixed_in(tmp_path, capsys):
    out = tmp_path / "half"
    assert main(["dataset", "generate", str(TINY), "--out", str(out), "--workers", "1", "--limit", "2",
                 "--no-progress"]) == 0
    info = json.loads((out / "info.json").read_text())
    info["versions"]["twin"] = "0.0.1"  # as if the finished runs came from an older physics
    (out / "info.json").write_text(json.dumps(info))
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*")}
    rc = main(["dataset", "generate", str(TINY), "--out", str(out), "--workers", "1", "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "twin '0.0.1'" in err and "another folder" in err
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*")} == before


def test_runs_the_spec_no_longer_plans_are_not_mixed_in(tmp_path, capsys):
    out = tmp_path / "half"
    assert main(["dataset", "generate", str(TINY), "--out", str(out), "--workers", "1", "--limit", "1",
                 "--no-progress"]) == 0
    res = next((out / "results").glob("*.json"))
    res.rename(res.with_name("0123456789abcdef.json"))  # as if the configuration of that run had changed
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*")}
    rc = main(["dataset", "generate", str(TINY), "--out", str(out), "--workers", "1", "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "1 runs that this spec no longer plans" in err
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*")} == before


def test_verify_finds_a_changed_file(tiny, tmp_path, capsys):
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(tiny, copy)
    f = next((copy / "data").glob("*.parquet"))
    raw = bytearray(f.read_bytes())
    raw[200] ^= 0xFF
    f.write_bytes(bytes(raw))
    assert main(["dataset", "verify", str(copy), "--no-progress"]) == 1
    assert "SHA-256 differs" in capsys.readouterr().out


def test_failed_runs_are_recorded_and_a_full_disk_stops_with_one_line(tmp_path, monkeypatch, capsys):
    """A run that fails is recorded with its reason and the dataset goes on; a write the file system
    refuses (full disk) stops the generation with one line, keeping what is done."""
    import errno

    import twin.dataset.generate as dataset_generate
    import twin.dataset.storage as storage
    from twin.dataset.worker import run_one
    from twin.errors import SimulationError
    from twin.simulation import simulate as real_simulate

    runs = plan(load_spec(TINY))
    bad_id, full_id = runs[1].run_id, runs[5].run_id

    def inline(scheduler, workers):
        return lambda tasks: (run_one(t) for t in tasks)

    def flaky_simulate(cfg, sinks=(), **kw):
        if cfg.name.endswith(bad_id):
            raise SimulationError("diverged at t = 0.1 s (test)")
        return real_simulate(cfg, sinks, **kw)

    real_write = storage.ParquetRunWriter.write

    def full_write(self, chunk):
        if self.run_id == full_id:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write(self, chunk)

    monkeypatch.setattr(dataset_generate, "executor", inline)
    monkeypatch.setattr("twin.simulation.simulate", flaky_simulate)
    monkeypatch.setattr(storage.ParquetRunWriter, "write", full_write)
    out = tmp_path / "ds"
    rc = main(["dataset", "generate", str(TINY), "--out", str(out), "--workers", "1"])
    err = capsys.readouterr().err
    assert rc == 2 and "No space left" in err and err.count("\n") == 1
    res = {p.stem: json.loads(p.read_text()) for p in (out / "results").glob("*.json")}
    assert res[bad_id]["status"] == "failed" and "diverged" in res[bad_id]["reason"]
    assert full_id not in res and len(res) == 5  # runs 0-4 kept, the full-disk run not recorded
    assert not list((out / "data").glob(f"*{full_id}*"))
    info = json.loads((out / "info.json").read_text())
    assert not info["complete"] and info["runs"]["failed"] == 1
    # room again: the same command finishes the three missing runs, the failed one stays failed
    monkeypatch.setattr(storage.ParquetRunWriter, "write", real_write)
    assert main(["dataset", "generate", str(TINY), "--out", str(out), "--workers", "1"]) == 0
    info = json.loads((out / "info.json").read_text())
    assert info["complete"] and info["runs"] == {"planned": 8, "ok": 7, "failed": 1, "pending": 0}
    assert verify(out) == []


# ---------------------------------------------------------------------- reading
def test_every_row_of_a_data_file_carries_its_run_id_time_and_labels(tiny):
    # independent basis: the manifest row of the run, and t = k / rate_hz (FORMAT.md)
    runs = pq.read_table(tiny / "runs.parquet").to_pylist()
    info = json.loads((tiny / "info.json").read_text())
    for r in runs:
        t = pq.read_table(tiny / r["file"], columns=["run_id", "t"] + info["label_columns"])
        for name in ["run_id"] + info["label_columns"]:
            vals = set(t[name].to_pylist())
            want = r[name]
            assert len(vals) == 1 and (vals == {want} or (math.isnan(want) and math.isnan(vals.pop()))), name
        np.testing.assert_array_equal(t["t"].to_numpy(), np.arange(t.num_rows) / 100_000.0)
    assert {r["motor_rpm"] for r in runs} == {500.0, 750.0}


def test_verify_finds_a_file_whose_labels_disagree_with_the_manifest(tiny, tmp_path):
    import shutil

    import pyarrow as pa
    import pyarrow.compute as pc

    d = tmp_path / "copy"
    shutil.copytree(tiny, d)
    runs = pq.read_table(d / "runs.parquet")
    rows = runs.to_pylist()
    r = rows[0]
    t = pq.read_table(d / r["file"])
    k = t.column_names.index("fault")
    t = t.set_column(k, "fault", pc.if_else(pc.equal(t["t"], 0.1), "BC", t["fault"]))  # one row relabelled
    k = t.column_names.index("t")
    t = t.set_column(k, "t", pa.array(t["t"].to_numpy() + 1e-9))
    pq.write_table(t, d / r["file"])
    rows[0] = {**r, "bytes": (d / r["file"]).stat().st_size, "sha256": _sha(d / r["file"])}
    pq.write_table(pa.Table.from_pylist(rows, schema=runs.schema), d / "runs.parquet")
    problems = verify(d)
    assert len(problems) == 2 and all(p.startswith(r["run_id"]) for p in problems)
    assert "column t is not t0 + k / rate_hz" in problems[0] and "column fault holds" in problems[1]


def test_a_dataset_of_the_previous_format_is_read_and_not_added_to(tiny, tmp_path, capsys):
    # a twin-dataset/1 folder: data files with the channels only (made here from the tiny one)
    old = tmp_path / "old"
    (old / "data").mkdir(parents=True)
    info = json.loads((tiny / "info.json").read_text())
    for k in ("key_columns", "label_columns"):
        info.pop(k)
    info["format"] = "twin-dataset/1"
    (old / "info.json").write_text(json.dumps(info))
    (old / "stats.json").write_bytes((tiny / "stats.json").read_bytes())
    runs = pq.read_table(tiny / "runs.parquet")
    rows = []
    for r in runs.to_pylist():
        t = pq.read_table(tiny / r["file"])
        t = t.select([c["name"] for c in info["channels"]]).replace_schema_metadata(t.schema.metadata)
        pq.write_table(t, old / r["file"])
        rows.append({**r, "bytes": (old / r["file"]).stat().st_size, "sha256": _sha(old / r["file"])})
    import pyarrow as pa
    pq.write_table(pa.Table.from_pylist(rows, schema=runs.schema), old / "runs.parquet")
    assert verify(old) == []
    ds = open_dataset(old)
    x, y = next(ds.windows("train", channels=["meas_AC4"], length_s=0.1))
    assert x.shape == (1, 10_000) and y["fault"] in ("none", "B", "C", "BC")
    assert main(["dataset", "info", str(old)]) == 0 and "twin-dataset/1" in capsys.readouterr().out
    assert main(["dataset", "generate", str(TINY), "--out", str(old), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert "twin-dataset/1" in err and "new folder" in err and err.count("\n") == 0


def test_a_data_file_is_labelled_rows_for_hugging_face_datasets(tiny):
    datasets = pytest.importorskip("datasets")
    runs = pq.read_table(tiny / "runs.parquet").to_pylist()
    train = [str(tiny / r["file"]) for r in runs if r["split"] == "train"]
    ds = datasets.load_dataset("parquet", data_files={"train": train}, split="train",
                               cache_dir=str(tiny.parent / "hf-cache"))
    assert ds.num_rows == 4 * 30_000
    row = ds[30_000 + 123]  # a row of the second file, as the library gives it
    r = next(r for r in runs if r["run_id"] == row["run_id"])
    assert (row["fault"], row["clearance_c_mm"], row["motor_rpm"], row["split"]) == \
        (r["fault"], r["clearance_c_mm"], r["motor_rpm"], "train")
    assert row["t"] == 123 / 100_000.0 and isinstance(row["meas_AC4"], float)


def test_data_files_are_labelled_rows_for_polars(tiny):
    pl = pytest.importorskip("polars")
    runs = {r["run_id"]: r for r in pq.read_table(tiny / "runs.parquet").to_pylist()}
    per_run = (pl.scan_parquet(str(tiny / "data" / "*.parquet"))
               .filter(pl.col("t") < 0.1)
               .group_by("run_id", "fault", "clearance_b_mm", "factor_motor_rpm")
               .agg(pl.len().alias("n"), pl.col("AC4").mean().alias("ac4"))
               .collect())
    assert per_run.height == 8 and set(per_run["n"]) == {10_000}
    for d in per_run.iter_rows(named=True):
        r = runs[d["run_id"]]
        assert (d["fault"], d["clearance_b_mm"], d["factor_motor_rpm"]) == \
            (r["fault"], r["clearance_b_mm"], r["factor_motor_rpm"])


def _format_snippets() -> list[str]:
    import re

    text = (ROOT / "twin" / "dataset" / "FORMAT.md").read_text()
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


@pytest.mark.parametrize("k", range(len(_format_snippets())))
def test_format_md_snippets_run_on_a_generated_dataset(tiny, k, tmp_path):
    code = _format_snippets()[k]
    for lib in ("datasets", "polars"):
        if re.search(rf"^\s*(import|from) {lib}\b", code, flags=re.M):
            pytest.importorskip(lib)
    assert 'DIR = "tiny"' in code  # the snippet names its folder DIR, which the test points at its dataset
    code = code.replace('DIR = "tiny"', f"DIR = {str(tiny)!r}")
    env = {**os.environ, "HF_HOME": str(tmp_path / "hf"), "HF_DATASETS_OFFLINE": "1"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, env=env)
    assert out.returncode == 0, out.stderr[-2000:]


def test_files_are_read_without_twin(tiny):
    script = textwrap.dedent(f"""
        import json, sys
        import pyarrow.parquet as pq
        runs = pq.read_table({str(tiny / 'runs.parquet')!r}).to_pylist()
        t = pq.read_table({str(tiny)!r} + "/" + runs[0]["file"], columns=["meas_AC4", "encoder_counts"])
        assert t.num_rows == runs[0]["rows"]
        assert not any(m == "twin" or m.startswith("twin.") for m in sys.modules)
        print(json.dumps([len(runs), t.num_rows, str(t.schema.field("meas_AC4").type)]))
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd="/", check=True)
    assert json.loads(out.stdout) == [8, 30000, "float"]


def test_windows_are_normalized_with_train_statistics(tiny):
    ds = open_dataset(tiny)
    xs, ys = [], []
    for x, y in ds.windows("train", channels=["meas_AC4", "AC6"], length_s=0.1, normalize=True):
        xs.append(x)
        ys.append(y)
    assert all(x.shape == (2, 10_000) and x.dtype == np.float32 for x in xs)
    assert len(xs) == 4 * 3  # 4 train runs of 0.3 s, windows of 0.1 s without overlap
    allx = np.concatenate(xs, axis=1).astype(np.float64)
    np.testing.assert_allclose(allx.mean(axis=1), 0.0, atol=1e-4)
    np.testing.assert_allclose(allx.std(axis=1), 1.0, rtol=1e-4)
    assert {y["fault"] for y in ys} == {"none", "B", "C", "BC"} and {y["split"] for y in ys} == {"train"}
    raw = next(ds.windows("test", channels=["meas_AC4"], length_s=0.05, hop_s=0.025))
    assert raw[0].shape == (1, 5000) and raw[1]["split"] == "test"


def test_revolution_edges_ignore_jitter_at_a_boundary():
    from twin.dataset.reader import revolution_edges

    # at rest on a boundary, jittering by a count, then two and a half turns forward
    turns = np.concatenate([np.tile([0.0, -1e-4, 0.0, 1e-4], 50), np.linspace(0.0, 2.5, 2501)])
    edges = revolution_edges(turns)
    assert list(turns[edges]) == pytest.approx([1.0, 2.0])
    assert list(revolution_edges(-turns)) == list(edges)  # the other direction


def test_per_revolution_windows_follow_the_encoder(tmp_path):
    spec = tmp_path / "rev.toml"
    spec.write_text(textwrap.dedent("""
        [dataset]
        name = "rev"
        [base]
        test = 3
        duration_s = 1.2
        set = { "drive.ramp_s" = 0.05 }
        [factors]
        motor_rpm = [750.0]
        [outputs]
        truth = ["encoder"]
        instrumented = ["counts"]
        [splits]
        train = 1.0
        val = 0.0
        test = 0.0
    """))
    out = tmp_path / "ds"
    assert main(["dataset", "generate", str(spec), "--out", str(out), "--workers", "1", "--no-progress"]) == 0
    ds = open_dataset(out)
    revs = list(ds.windows("train", channels=["encoder_angle"], per_revolution=True))
    assert len(revs) == 2  # 1.2 s at 3.15 turns/s after a 0.05 s ramp: 3.7 turns, 2 whole ones between edges
    for x, _ in revs:  # each window spans one turn of the crank, to one encoder count
        turn = (x[0, -1] - x[0, 0]) / (2 * np.pi)
        assert 1.0 - 2 * 2.5e-3 < turn <= 1.0  # 0.5 ms at 3.15 turns/s = 1.6e-3 turn per sample
    shaped = list(ds.windows("train", channels=["encoder_angle"], per_revolution=True, samples_per_rev=256))
    assert len(shaped) == 2 and all(x.shape == (1, 256) for x, _ in shaped)
    # order tracking: the samples are uniform in the angle domain, to the encoder's count (the grid
    # comes from the quantized counts, the channel is the continuous angle)
    d = np.diff(shaped[0][0][0].astype(np.float64))
    np.testing.assert_allclose(d, 2 * np.pi / 256, atol=2 * 2 * np.pi / 32768)


def test_view_a_dataset_run(tiny, tmp_path):
    run_id = pq.read_table(tiny / "runs.parquet").to_pylist()[-1]["run_id"]
    out = tmp_path / "v.rrd"
    assert main(["view", str(tiny), "--run", run_id, "--save", str(out)]) == 0
    assert out.stat().st_size > 1e5
    assert main(["view", str(tiny), "--save", str(tmp_path / "w.rrd")]) == 2
    assert main(["view", str(tiny), "--run", "nope", "--save", str(tmp_path / "w.rrd")]) == 2
    assert not (tmp_path / "w.rrd").exists()


def test_plan_prints_runs_and_an_estimate(capsys):
    assert main(["dataset", "plan", str(TINY), "--workers", "2"]) == 0
    out = capsys.readouterr().out
    assert "tiny: 8 runs" in out and "2.4 s simulated" in out and "estimated wall time on 2 workers" in out
    assert out.count("\n") >= 13
    # the fault factor is the fault label: one column, header and rows of the same width
    head = next(line for line in out.splitlines() if "run_id" in line)
    assert head.split() == ["index", "run_id", "split", "fault", "B", "mm", "C", "mm", "motor_rpm"]
    rows = [line for line in out.splitlines() if re.match(r"\s+\d+\s+[0-9a-f]{16}\s", line)]
    assert len(rows) == 8 and {len(r) for r in rows} == {len(head)}
    assert rows[2].split()[3:] == ["B", "0.1", "0", "500"]


def test_info_lists_the_runs_with_their_labels_and_as_json(tiny, capsys, tmp_path):
    runs = pq.read_table(tiny / "runs.parquet").to_pylist()
    assert main(["dataset", "info", str(tiny), "--show", "0"]) == 0
    out = capsys.readouterr().out
    for r in runs:  # every run id on a line with its status, split, fault and clearances
        line = next(x for x in out.splitlines() if r["run_id"] in x)
        assert line.split()[1:6] == ["ok", r["split"], r["fault"], f"{r['clearance_b_mm']:.4g}",
                                     f"{r['clearance_c_mm']:.4g}"]
    assert main(["dataset", "info", str(tiny), "--show", "3"]) == 0
    assert "... 5 more (--show 0 lists all)" in capsys.readouterr().out
    assert main(["dataset", "info", str(tiny), "--json"]) == 0
    d = json.loads(capsys.readouterr().out, parse_constant=lambda c: pytest.fail(f"{c} in JSON"))
    assert [x["run_id"] for x in d["runs"]] == [r["run_id"] for r in runs]
    assert d["runs"][0] == {"run_id": runs[0]["run_id"], "status": "ok", "split": runs[0]["split"],
                            "fault": runs[0]["fault"], "clearance_b_mm": runs[0]["clearance_b_mm"],
                            "clearance_c_mm": runs[0]["clearance_c_mm"], "factor_motor_rpm": 500.0}
    assert d["splits"]["train"] == {"runs": 4, "groups": 4, "by_fault": {"none": 1, "B": 1, "C": 1, "BC": 1}}
    assert main(["dataset", "info", str(tiny), "--json", str(tmp_path / "i.json")]) == 0
    assert json.loads((tmp_path / "i.json").read_text()) == d
    assert main(["dataset", "info", str(tiny), "--json", str(tmp_path / "i.txt")]) == 2


@pytest.mark.long  # a few seconds: run by CI and with -m long
def test_workers_of_a_killed_driver_do_not_outlive_it(tmp_path):
    """SIGKILL leaves the pool's workers without a driver: they stop within seconds, not linger
    (Linux: the processes are found through /proc)."""
    out = tmp_path / "orphans"
    proc = subprocess.Popen([sys.executable, "-m", "twin.cli", "dataset", "generate", str(TINY), "--out", str(out),
                             "--workers", "2", "--scheduler", "processes", "--no-progress"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    kids: set[int] = set()
    while not kids:  # the spawned workers of this driver
        assert proc.poll() is None and time.monotonic() < deadline
        for d in Path("/proc").iterdir():
            if d.name.isdigit():
                try:
                    stat = (d / "stat").read_text().split()
                except OSError:
                    continue
                if int(stat[3]) == proc.pid and "spawn_main" in (d / "cmdline").read_bytes().decode(errors="replace"):
                    kids.add(int(d.name))
        time.sleep(0.05)
    time.sleep(1.0)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    deadline = time.monotonic() + 15
    while any(Path(f"/proc/{k}").exists() and "Z" not in (Path(f"/proc/{k}") / "stat").read_text().split()[2]
              for k in kids):
        assert time.monotonic() < deadline, f"workers {kids} still running 15 s after their driver was killed"
        time.sleep(0.2)
    assert not [p for p in out.rglob("*") if ".tmp" in p.name]


def _crash_on(task):  # a worker function for the test below (importable by spawned workers)
    import os

    if task["run_id"] == "crash":
        os._exit(9)  # the process dies as in a segmentation fault or the OOM killer
    return {"run_id": task["run_id"], "index": task["index"], "status": "ok"}


def test_a_worker_that_dies_fails_its_run_only():
    from twin.dataset.generate import _local

    tasks = [{"run_id": r, "index": i} for i, r in enumerate(["a", "b", "crash", "c", "d", "e"])]
    res = {r["run_id"]: r for r in _local(2, _crash_on)(tasks)}
    assert sorted(res) == ["a", "b", "c", "crash", "d", "e"]
    assert res["crash"]["status"] == "failed" and "worker process died" in res["crash"]["reason"]
    assert all(res[k]["status"] == "ok" for k in "abcde")


@pytest.mark.parametrize("text, fragment", [
    ('[dataset]\nname = "x"\n[factors]\n"pid.kp" = { range = [1e5, 2e5], levels = 1000 }\n'
     '"pid.kv" = { range = [100, 300], levels = 1000 }\n"pid.ki" = { range = [1e7, 3e7], levels = 1000 }\n',
     "design: has 1000000000 runs"),
    ('[dataset]\nname = "x"\n[factors]\n"simulation.duration_s" = [0.2, 0.3]\n', "decided by the spec itself"),
    ('[dataset]\nname = "x"\n[factors]\n"sensors.output_rate_hz" = [50000.0]\n', "decided by the spec itself"),
    ('[dataset]\nname = "x"\n[base]\nset = { "simulation.engine" = "reference" }\n', "base.set.simulation.engine"),
    ('[dataset]\nname = "x"\n[base]\nset = { "drive.program" = "trace" }\n', "decided by the spec itself"),
])
def test_designs_that_would_be_overwritten_or_too_large_are_refused_at_once(text, fragment, tmp_path, capsys):
    spec = tmp_path / "s.toml"
    spec.write_text(text)
    t = time.perf_counter()
    assert main(["dataset", "plan", str(spec), "--no-estimate"]) == 2
    err = capsys.readouterr().err
    assert fragment in err and err.count("\n") == 1 and time.perf_counter() - t < 10


def test_a_clearance_at_the_ground_pivot_is_a_dataset_factor(tmp_path):
    """The general mechanism's joint A as a dotted factor: its truth channels are stored for the
    run with a clearance there and are NaN for the run without. The loaded start rests the crank
    journal on the frame's bore, so the contact carries the frame's static load, |m_crank g + F_B|
    (statics, twin.kinematics), while the drive's ramp has barely begun (within 5 %)."""
    from twin.config import preset
    from twin.drive import DriveReference
    from twin.kinematics import static_pin_forces

    spec = tmp_path / "a.toml"
    spec.write_text(textwrap.dedent("""
        [dataset]
        name = "pivot-a"
        [base]
        test = 1
        engine = "reference"
        duration_s = 0.05
        [design]
        kind = "grid"
        [factors]
        "joints.clearance_a_mm" = [0.0, 0.5]
        [outputs]
        truth = ["encoder", "joints"]
        instrumented = []
        [splits]
        train = 1.0
        val = 0.0
        test = 0.0
    """))
    out = tmp_path / "ds"
    assert main(["dataset", "generate", str(spec), "--out", str(out), "--workers", "1", "--no-progress"]) == 0
    rows = {r["factor_joints.clearance_a_mm"]: r for r in pq.read_table(out / "runs.parquet").to_pylist()}
    with_a = pq.read_table(out / rows[0.5]["file"])
    without = pq.read_table(out / rows[0.0]["file"])
    labels = json.loads((out / "info.json").read_text())["label_columns"]
    assert "factor_joints.clearance_a_mm" in labels and set(with_a["factor_joints.clearance_a_mm"].to_pylist()) == {0.5}
    assert with_a.schema.names == without.schema.names == ["run_id", "t", *labels, "encoder_angle", "ecc_A_x",
                                                            "ecc_A_y", "pen_A", "fn_A", "ft_A"]
    cfg = preset(1).replace(**{"joints.clearance_a_mm": 0.5, "simulation.duration_s": 0.05})
    theta0 = float(DriveReference(cfg)(np.array([0.0]))[0][0])
    f_b, _ = static_pin_forces(cfg, theta0)
    load = np.linalg.norm(cfg.bodies.crank.mass_kg * np.asarray(cfg.mechanism.gravity_vector[:2]) + f_b)
    fn = with_a["fn_A"].to_numpy()
    assert np.all(fn[100:] > 0) and fn[-1] == pytest.approx(load, rel=0.05), (fn[-1], load)
    assert np.all(np.isnan(without["fn_A"].to_numpy()))
