"""More bad input, tried as a new user or a hostile file would: one line, exit 2, nothing changed.

The table :data:`CASES` extends ``test_bad_input.py`` with inputs of every command that are not
what they claim (FIFOs, /dev/zero, symbolic-link loops, names longer than the file system
allows, deeply nested TOML, damaged run-file metadata, MCAP files cut short), physically absurd
values (a trace in degrees, volts beyond the sensor's rails, a mass of 1e300 kg, a rod shorter
than the crank), options out of range and dataset specs that contradict themselves. Each case
runs ``twin.cli.main`` in-process in a workspace of valid and broken inputs; the workspace must
be unchanged afterwards (names, kinds, sizes, contents; FIFOs and links are not followed).

Below the table: replay never deletes what it did not write, the dataset folder lock (a second
generator refused naming the holder, the lock of a SIGKILLed holder taken over), leftovers of
dead processes removed by any later run in their folder, a full standard output, and
property-based tests (hypothesis) of configuration files, ``--set`` values and recording
metadata.
"""

from __future__ import annotations

import hashlib
import os
import shlex
import shutil
import signal
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from twin.cli import main

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "recordings" / "test6_synthetic.mcap"
LONG = "L" * 256  # longer than the 255 bytes of NAME_MAX


# ------------------------------------------------------------------------ helpers
class Hung(BaseException):
    """Raised by the alarm: a BaseException, so that no handler of the command line catches it."""


@pytest.fixture(autouse=True)
def no_hang():
    """Every test here fails (instead of hanging the suite) after 60 s."""
    def ring(signum, frame):
        raise Hung("the command hung (60 s)")

    old = signal.signal(signal.SIGALRM, ring)
    signal.alarm(60)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def rewrite_mcap(src: Path, dst: Path, run_meta=None, chan_meta=None, drop=()) -> Path:
    """A copy of an MCAP run file with its 'twin.run' record (``run_meta(dict) -> dict``) and its
    channels' metadata (``chan_meta(topic, dict) -> dict``) changed, or records dropped."""
    from mcap.reader import make_reader
    from mcap.writer import Writer

    with open(src, "rb") as fh:
        r = make_reader(fh)
        records = [(m.name, dict(m.metadata)) for m in r.iter_metadata()]
        msgs = list(r.iter_messages(log_time_order=False))
    with open(dst, "wb") as out:
        w = Writer(out)
        w.start()
        sids, cids = {}, {}
        for sc, ch, m in msgs:
            if sc.id not in sids:
                sids[sc.id] = w.register_schema(sc.name, sc.encoding, sc.data)
            if ch.id not in cids:
                md = dict(ch.metadata)
                if chan_meta is not None:
                    md = chan_meta(ch.topic, md)
                cids[ch.id] = w.register_channel(ch.topic, ch.message_encoding, sids[sc.id], metadata=md)
            w.add_message(cids[ch.id], log_time=m.log_time, publish_time=m.publish_time, sequence=m.sequence,
                          data=m.data)
        for name, rec in records:
            if name in drop:
                continue
            if name == "twin.run" and run_meta is not None:
                rec = run_meta(dict(rec))
            w.add_metadata(name, {str(k): str(v) for k, v in rec.items()})
        w.finish()
    return dst


def _export(path: Path, n: int, volts=None, counts=None, rate: float = 1e5) -> Path:
    cols = {"t": np.arange(n) / rate}
    for i in range(1, 7):
        cols[f"volt_AC{i}"] = np.full(n, 2.5) if volts is None else volts(i, n)
    cols["encoder_counts"] = np.arange(n, dtype=float) // 40 if counts is None else counts
    header = ",".join(f"{k} [V]" if k.startswith("volt") else (f"{k} [count]" if k.startswith("enc") else k)
                      for k in cols)
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",", header=header, comments="")
    return path


ZERO_G = "AC1=2.5,AC2=2.5,AC3=2.5,AC4=2.5,AC5=2.5,AC6=2.5"


def _trace(path: Path, t: np.ndarray, angle: np.ndarray) -> Path:
    if path.suffix == ".csv":
        np.savetxt(path, np.column_stack([t, angle]), delimiter=",", header="t,angle", comments="")
    else:
        np.savez(path, t=t, angle=angle)
    return path


def snapshot(root: Path) -> dict[str, tuple]:
    """Every entry under ``root``: kind, size and hash (regular files under 4 MB; larger ones by size
    and modification time); links and FIFOs by kind and target only, never followed or read."""
    out: dict[str, tuple] = {}
    for dirpath, dirnames, filenames in os.walk(root, followlinks=False):
        for name in dirnames + filenames:
            p = Path(dirpath) / name
            st = os.lstat(p)
            rel = str(p.relative_to(root))
            if stat.S_ISLNK(st.st_mode):
                out[rel] = ("link", os.readlink(p))
            elif stat.S_ISDIR(st.st_mode):
                out[rel] = ("dir",)
            elif stat.S_ISREG(st.st_mode):
                if st.st_size > 4 << 20:
                    out[rel] = ("big", st.st_size, st.st_mtime_ns)
                else:
                    out[rel] = ("file", st.st_size, hashlib.sha256(p.read_bytes()).hexdigest())
            else:
                out[rel] = ("other", stat.S_IFMT(st.st_mode))
    return out


# ------------------------------------------------------------------------ workspace
@pytest.fixture(scope="module")
def ws(tmp_path_factory) -> Path:
    ws = tmp_path_factory.mktemp("bad_input_more")
    from twin.mcapfile import write_run
    from twin.simulation import simulate_run

    from conftest import short
    from twin.config import preset

    write_run(ws / "run.mcap", simulate_run(short(preset(6), 0.02)))
    shutil.copy(SAMPLE, ws / "rec.mcap")
    (ws / "afile").write_text("a plain file\n")
    (ws / "adir.json").mkdir()
    (ws / "empty_dir").mkdir()
    os.mkfifo(ws / "fifo.toml")
    os.mkfifo(ws / "fifo.mcap")
    os.mkfifo(ws / "fifo.csv")
    os.mkfifo(ws / "fifo.npz")
    os.symlink("loop2", ws / "loop1")
    os.symlink("loop1", ws / "loop2")
    os.symlink("selfloop.mcap", ws / "selfloop.mcap")
    os.symlink("selfloop", ws / "selfloop")
    os.symlink("selfloop.xml", ws / "selfloop.xml")
    os.symlink("nowhere.mcap", ws / "dangling.mcap")
    # configuration files that are not what they claim
    (ws / "deep_arrays.toml").write_text("[drive]\nmotor_rpm = " + "[" * 3000 + "1" + "]" * 3000 + "\n")
    (ws / "deep_tables.toml").write_text("drive = " + "{a = " * 3000 + "1" + "}" * 3000 + "\n")
    (ws / "deep_dotted.toml").write_text(".".join(["k"] * 200) + " = 1\n")
    (ws / "deep_headers.toml").write_text("[" + ".".join(["k"] * 200) + "]\nx = 1\n")
    with open(ws / "big.toml", "wb") as fh:  # sparse: 20 MB that take no disk
        fh.truncate(20 << 20)
    (ws / "list_top.toml").write_text("drive = [1, 2]\n")
    (ws / "mass.toml").write_text("[bodies.rod]\nmass_kg = 1e300\n")
    (ws / "short_rod.toml").write_text("[bodies.rod]\nlength_m = 0.05\n")
    (ws / "tiny_clearance.toml").write_text("[joints]\nallow_noncatalogue = true\nclearance_c_mm = 1e-9\n")
    (ws / "nl\nname.toml").write_text("[joints\n")
    # dataset specs that contradict themselves
    base = ('[dataset]\nname = "x"\n[base]\ntest = 6\nduration_s = 0.05\n[outputs]\nrate_hz = 10000.0\n'
            'truth = ["accel"]\ninstrumented = false\n')
    (ws / "spec_none_c.toml").write_text(base + '[factors]\nfault = ["none"]\nclearance_c_mm = [0.5]\n')
    (ws / "spec_b0.toml").write_text(base + '[factors]\nfault = ["B"]\nclearance_b_mm = [0.0]\n')
    (ws / "spec_b_range0.toml").write_text(
        base + '[factors]\nfault = ["none", "B"]\nclearance_b_mm = { range = [0.0, 0.5], levels = 3 }\n')
    (ws / "spec_c_no_c.toml").write_text(base + '[factors]\nfault = ["none", "B"]\nclearance_c_mm = [0.1, 0.5]\n')
    (ws / "spec_hold_missing.toml").write_text(
        base + '[factors]\nmotor_rpm = [300.0, 500.0]\n[splits]\nholdout = { motor_rpm = [400.0] }\n')
    (ws / "spec_hold_all.toml").write_text(
        base + '[factors]\nmotor_rpm = [300.0, 500.0]\n[splits]\nholdout = { motor_rpm = [300.0, 500.0] }\n')
    (ws / "spec_hold_range.toml").write_text(
        base + '[design]\nkind = "random"\nruns = 4\n[factors]\nmotor_rpm = { range = [300.0, 500.0] }\n'
               '[splits]\nholdout = { motor_rpm = [900.0] }\n')
    (ws / "spec_hold_fault.toml").write_text(
        base + '[factors]\nfault = ["none", "C"]\n[splits]\nholdout = { fault = ["B"] }\n')
    (ws / "spec_hold_fault_all.toml").write_text(
        base + '[factors]\nfault = ["none", "C"]\n[splits]\nholdout = { fault = ["none", "C"] }\n')
    (ws / "deep_spec.toml").write_text(base + "[factors]\nmotor_rpm = " + "[" * 3000 + "1" + "]" * 3000 + "\n")
    shutil.copy(ROOT / "analysis" / "datasets" / "tiny.toml", ws / "tiny.toml")
    for name, info in (("info_list_ds", "[]"), ("info_text_ds", '"text"'), ("info_notjson_ds", "{not json")):
        (ws / name).mkdir()
        (ws / name / "info.json").write_text(info)
    # drive traces
    t = np.arange(2001) / 1000.0
    rad = 2 * np.pi * (200.0 / 60.0) * t  # 200 crank rpm (794 motor rpm): a plausible trace
    _trace(ws / "ok_trace.npz", t, rad)
    _trace(ws / "degrees.npz", t, np.degrees(rad))
    _trace(ws / "degrees.csv", t, np.degrees(rad))
    _trace(ws / "three.npz", t[:3], rad[:3])
    _trace(ws / "tiny_dt.npz", np.arange(200) * 1e-12, np.zeros(200))
    _trace(ws / "gap.npz", np.r_[t[:100], t[100:] + 5.0], rad)
    np.savez(ws / "trace2d.npz", t=np.ones((10, 2)), angle=np.ones((10, 2)))
    np.save(ws / "npy_as.npy", np.arange(10.0))
    os.replace(ws / "npy_as.npy", ws / "npy_as.npz")
    (ws / "empty.csv").write_text("")
    # DAQ exports
    _export(ws / "export.csv", 200)
    np.savetxt(ws / "notime.csv", np.loadtxt(ws / "export.csv", delimiter=",", skiprows=1)[:, 1:], delimiter=",",
               header=",".join([f"volt_AC{i} [V]" for i in range(1, 7)] + ["encoder_counts [count]"]), comments="")
    _export(ws / "rails.csv", 200, volts=lambda i, n: np.full(n, 7.5 if i == 3 else 2.5))
    _export(ws / "neg_rails.csv", 200, volts=lambda i, n: np.full(n, -1.0 if i == 2 else 2.5))
    # recordings: a small valid one (too little motion to replay) and damaged copies
    assert main(["import", str(ws / "export.csv"), "--test", "6", "--out", str(ws / "small.mcap"),
                 "--zero-g", ZERO_G]) == 0
    rng = np.random.default_rng(3)
    n = 20000
    _export(ws / "walk.csv", n, volts=lambda i, n: 2.5 + 0.3 * rng.standard_normal(n),
            counts=np.cumsum(rng.integers(-1, 2, n)).astype(float))
    assert main(["import", str(ws / "walk.csv"), "--test", "6", "--out", str(ws / "walk.mcap"),
                 "--zero-g", ZERO_G]) == 0
    (ws / "walk.csv").unlink()
    src = ws / "small.mcap"
    rewrite_mcap(src, ws / "meta_notjson.mcap", run_meta=lambda d: {**d, "meta": "{not json"})
    rewrite_mcap(src, ws / "meta_list.mcap", run_meta=lambda d: {**d, "meta": "[1, 2]"})
    rewrite_mcap(src, ws / "t0_text.mcap", run_meta=lambda d: {**d, "t0": "noon"})
    rewrite_mcap(src, ws / "t0_nan.mcap", run_meta=lambda d: {**d, "t0": "nan"})
    rewrite_mcap(src, ws / "rate_text.mcap", run_meta=lambda d: {**d, "rate_hz": "fast"})
    rewrite_mcap(src, ws / "rate_zero.mcap", run_meta=lambda d: {**d, "rate_hz": "0"})
    rewrite_mcap(src, ws / "n_text.mcap", run_meta=lambda d: {**d, "n": "many"})
    rewrite_mcap(src, ws / "n_negative.mcap", run_meta=lambda d: {**d, "n": "-5"})
    rewrite_mcap(src, ws / "no_names.mcap", chan_meta=lambda tp, d: {k: v for k, v in d.items() if k != "names"})
    rewrite_mcap(src, ws / "fewer_names.mcap",
                 chan_meta=lambda tp, d: {**d, "names": ",".join(d["names"].split(",")[:-2])})
    rewrite_mcap(src, ws / "dup_names.mcap",
                 chan_meta=lambda tp, d: {**d, "names": ",".join(["x"] * len(d["names"].split(",")))})
    rewrite_mcap(src, ws / "no_dtypes.mcap", chan_meta=lambda tp, d: {k: v for k, v in d.items() if k != "dtypes"})
    rewrite_mcap(src, ws / "no_config.mcap", drop=("twin.config",))
    rewrite_mcap(src, ws / "bad_config.mcap")
    (ws / "magic_only.mcap").write_bytes(b"\x89MCAP0\r\n")
    (ws / "empty.mcap").write_bytes(b"")
    (ws / "sub").mkdir()
    shutil.copy(src, ws / "sub" / "rec2.mcap")
    (ws / "userdir").mkdir()
    (ws / "userdir" / "thesis.tex").write_text("months of work\n")
    (ws / "userdir" / "report.json").write_text("{}\n")
    return ws


# --------------------------------------------------------------------------- cases
#: (command line, fragment the one-line error must contain). {ws} is the workspace, {LONG} a name
#: longer than NAME_MAX once suffixed.
CASES: list[tuple[str, str]] = [
    # ---- record: outputs that are inputs or links, configurations that are not what they claim
    ("record --config {ws}/fifo.toml --out {ws}/r.mcap", "not a regular file"),
    ("record --duration 0.01 --out {ws}/r.mcap --json {ws}/r.mcap", "--json: must end in .json"),
    ("record --duration 0.01 --static nan --out {ws}/r.mcap", "--static: must lie in [0.1, 60] s"),
    # ---- simulate: configuration files that are not what they claim
    ("simulate --config {ws}/fifo.toml", "not a regular file"),
    ("simulate --config /dev/zero", "not a regular file"),
    ("simulate --config {ws}/deep_arrays.toml", "nested deeper"),
    ("simulate --config {ws}/deep_tables.toml", "nested deeper"),
    ("simulate --config {ws}/deep_dotted.toml", "nested deeper"),
    ("simulate --config {ws}/deep_headers.toml", "nested deeper"),
    ("simulate --config {ws}/big.toml", "at most"),
    ("simulate --config ''", "--config"),
    ("simulate --config {ws}/loop1", "--config"),
    ("simulate --config {ws}/selfloop", "--config"),
    ("simulate --config {ws}/empty_dir", "is a directory"),
    ("simulate --config {ws}/list_top.toml", "drive"),
    ("simulate --config {ws}/mass.toml", "bodies.rod.mass_kg"),
    ("simulate --config {ws}/short_rod.toml", "bodies.rod.length_m"),
    ("simulate --config {ws}/tiny_clearance.toml", "joints.clearance_c_mm"),
    ("simulate --config '{ws}/nl\nname.toml'", "nl\\nname.toml"),
    ("simulate --config {ws}/{LONG}.toml", "--config"),
    # ---- simulate: --set values
    ("simulate --set drive.motor_rpm=" + "[" * 3000 + "1" + "]" * 3000, "nested deeper"),
    ("simulate --set drive=" + "{a=" * 3000 + "1" + "}" * 3000, "nested deeper"),
    ("simulate --set 'drive.motor_rpm=1\n2'", "one line"),
    ("simulate --set bodies.rod.mass_kg=1e300", "bodies.rod.mass_kg"),
    ("simulate --set bodies.crank.mass_kg=0", "bodies.crank.mass_kg"),
    ("simulate --set bodies.slider.mass_kg=-1", "bodies.slider.mass_kg"),
    ("simulate --set bodies.rod.length_m=0.1", "bodies.rod.length_m"),
    ("simulate --set bodies.rod.length_m=0.12", "bodies.rod.length_m"),
    ("simulate --set bodies.rod.length_m=1e9", "bodies.rod.length_m"),
    ("simulate --set mechanism.d_off_m=0.5", "mechanism.d_off_m"),
    ("simulate --set mechanism.d_off_m=0.09 --set bodies.rod.length_m=0.2", "bodies.rod.length_m"),
    ("simulate --set bodies.slider.inertia_kgm2=1e300", "bodies.slider.inertia_kgm2"),
    ("simulate --set bodies.rod.x_g_m=nan", "bodies.rod.x_g_m"),
    ("simulate --clearance-c 1e-9 --set joints.allow_noncatalogue=true", "joints.clearance_c_mm"),
    ("simulate --clearance-b 1e-5 --set joints.allow_noncatalogue=true", "joints.clearance_b_mm"),
    ("simulate --clearance-a inf --set joints.allow_noncatalogue=true", "joints.clearance_a_mm"),
    ("simulate --set contact.restitution=1.5", "contact.restitution"),
    ("simulate --set contact.restitution=0", "contact.restitution"),
    ("simulate --set contact.restitution=nan", "contact.restitution"),
    ("simulate --set drive.motor_rpm=nan", "drive.motor_rpm"),
    ("simulate --set drive.motor_rpm=inf", "drive.motor_rpm"),
    ("simulate --set drive.motor_rpm=1e309", "drive.motor_rpm"),
    ("simulate --set drive.belt_ratio=0", "drive.belt_ratio"),
    ("simulate --set drive.belt_ratio=-3.97", "drive.belt_ratio"),
    ("simulate --set simulation.timestep_s=-1e-5", "simulation.timestep_s"),
    ("simulate --set simulation.timestep_s=nan", "simulation.timestep_s"),
    ("simulate --set sensors.output_rate_hz=-1", "sensors.output_rate_hz"),
    ("simulate --set name=''", "name"),
    ("simulate --set 'name=\"a\\nb\"'", "name"),
    ("simulate --set drive.program=trace", "drive.trace_file"),
    ("simulate --duration nan", "simulation.duration_s"),
    ("simulate --timestep nan", "simulation.timestep_s"),
    ("simulate --timestep inf", "simulation.timestep_s"),
    ("simulate --output-rate nan", "sensors.output_rate_hz"),
    ("simulate --output-rate inf", "sensors.output_rate_hz"),
    ("simulate --speed nan", "drive.motor_rpm"),
    ("simulate --speed -1001", "drive.motor_rpm"),
    ("simulate --clearance-b inf", "joints.clearance_b_mm"),
    ("simulate --test 0", "--test"),
    # ---- simulate: output locations
    ("simulate --out ''", "--out: is empty"),
    ("simulate --out .", "--out"),
    ("simulate --out {ws}/", "--out"),
    ("simulate --out {ws}/{LONG}.mcap", "bytes long"),
    ("simulate --out {ws}/loop1/x.mcap", "symbolic-link loop"),
    ("simulate --out {ws}/selfloop.mcap", "symbolic-link loop"),
    ("simulate --out {ws}/dangling.mcap", "dangling"),
    ("simulate --out '{ws}/no\ndir/x.mcap'", "no\\ndir"),
    ("simulate --out /dev/null", "--out"),
    ("simulate --out {ws}/fifo.mcap --no-progress", "not a regular file"),
    ("simulate --out {ws}/fifo.mcap", "not a regular file"),
    ("simulate --out {ws}/x.mcap --summary-json ''", "--summary-json"),
    ("simulate --out {ws}/x.mcap --summary-json {ws}/loop1/s.json", "--summary-json"),
    ("simulate --out {ws}/x.mcap --summary-json {ws}/adir.json", "--summary-json"),
    ("simulate --out {ws}/x.mcap --rerun ''", "--rerun"),
    ("simulate --out {ws}/x.mcap --rerun {ws}/{LONG}.rrd", "--rerun"),
    # ---- simulate: drive traces that are not plausible
    ("simulate --trace {ws}/degrees.npz", "degrees"),
    ("simulate --trace {ws}/degrees.csv", "degrees"),
    ("simulate --trace {ws}/three.npz", "at least 8"),
    ("simulate --trace {ws}/tiny_dt.npz", "apart"),
    ("simulate --trace {ws}/gap.npz", "gap"),
    ("simulate --trace {ws}/ok_trace.npz --duration 5", "covers"),
    ("simulate --trace {ws}/npy_as.npz", "npy_as.npz"),
    ("simulate --trace {ws}/fifo.npz", "--trace:"),
    ("simulate --trace {ws}/trace2d.npz", "1-D"),
    ("simulate --trace ''", "--trace"),
    ("simulate --trace {ws}/empty.csv", "empty.csv"),
    ("simulate --trace {ws}/loop1", "--trace: must be a .npz or .csv"),
    # ---- export-mjcf
    ("export-mjcf --out ''", "--out: is empty"),
    ("export-mjcf --out .", "--out"),
    ("export-mjcf --out {ws}/loop1/m.xml", "symbolic-link loop"),
    ("export-mjcf --out {ws}/{LONG}.xml", "bytes long"),
    ("export-mjcf --out {ws}/selfloop.xml", "symbolic-link loop"),
    ("export-mjcf --out /dev/null", "--out"),
    ("export-mjcf --out {ws}/m.xml --config {ws}/fifo.toml", "not a regular file"),
    ("export-mjcf --out {ws}/m.xml --config {ws}/deep_arrays.toml", "nested deeper"),
    ("export-mjcf --out {ws}/m.xml --set bodies.rod.length_m=0.05", "bodies.rod.length_m"),
    ("export-mjcf --out {ws}/m.xml --set bodies.rod.mass_kg=1e300", "bodies.rod.mass_kg"),
    ("export-mjcf --out {ws}/m.xml --clearance-c 1e-9 --set joints.allow_noncatalogue=true",
     "joints.clearance_c_mm"),
    # ---- view: run files that are not what they claim
    ("view {ws}/magic_only.mcap", "magic_only.mcap"),
    ("view {ws}/empty.mcap", "empty.mcap"),
    ("view {ws}/meta_notjson.mcap", "not JSON"),
    ("view {ws}/meta_list.mcap", "JSON object"),
    ("view {ws}/t0_text.mcap", "t0"),
    ("view {ws}/t0_nan.mcap", "t0"),
    ("view {ws}/rate_text.mcap", "rate_hz"),
    ("view {ws}/rate_zero.mcap", "rate_hz"),
    ("view {ws}/n_text.mcap", "twin.run.n"),
    ("view {ws}/n_negative.mcap", "twin.run.n"),
    ("view {ws}/no_names.mcap", "names"),
    ("view {ws}/fewer_names.mcap", "channels"),
    ("view {ws}/dup_names.mcap", "unique"),
    ("view {ws}/no_dtypes.mcap", "dtypes"),
    ("view {ws}/fifo.mcap", "not a regular file"),
    ("view {ws}/selfloop.mcap", "selfloop.mcap"),
    ("view {ws}/run.mcap --save ''", "--save"),
    ("view {ws}/run.mcap --save {ws}/{LONG}.rrd", "--save"),
    ("view {ws}/run.mcap --save {ws}/loop1/v.rrd", "--save"),
    # ---- plot
    ("plot {ws}/magic_only.mcap --out {ws}/p.png", "magic_only.mcap"),
    ("plot {ws}/meta_notjson.mcap --out {ws}/p.png", "not JSON"),
    ("plot {ws}/rate_zero.mcap --out {ws}/p.png", "rate_hz"),
    ("plot {ws}/fifo.mcap --out {ws}/p.png", "not a regular file"),
    ("plot {ws}/selfloop.mcap --out {ws}/p.png", "selfloop.mcap"),
    ("plot {ws}/run.mcap --out ''", "--out"),
    ("plot {ws}/run.mcap --out {ws}/{LONG}.png", "--out"),
    ("plot {ws}/run.mcap --out {ws}/loop1/p.png", "--out"),
    ("plot {ws}/run.mcap --out {ws}/p.png --window nan:0.01", "--window"),
    ("plot {ws}/run.mcap --out {ws}/p.png --window 0:inf", "--window"),
    ("plot {ws}/run.mcap --out {ws}/p.png --window 0:0.0001", "fewer than 64 samples"),
    ("plot {ws}/run.mcap --out {ws}/p.png --channels ''", "--channels"),
    ("plot {ws}/run.mcap --out {ws}/p.png --channels 'AC1,,AC2'", "--channels"),
    ("plot {ws}/run.mcap --out {ws}/p.png --size 0x0", "--size"),
    # ---- import
    ("import {ws}/export.csv --test 6 --out ''", "--out"),
    ("import {ws}/export.csv --test 6 --out .", "--out"),
    ("import {ws}/export.csv --test 6 --out {ws}/{LONG}.mcap", "--out"),
    ("import {ws}/export.csv --test 6 --out {ws}/loop1/r.mcap", "--out"),
    ("import {ws}/rails.csv --test 6 --out {ws}/r.mcap", "rails"),
    ("import {ws}/neg_rails.csv --test 6 --out {ws}/r.mcap", "rails"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --rate 50000", "--rate"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --rate 100005", "--rate"),
    ("import {ws}/notime.csv --test 6 --out {ws}/r.mcap --rate 100005", "--rate"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --rate nan", "--rate"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --rate inf", "--rate"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --rate -5", "--rate"),
    ("import {ws}/fifo.csv --test 6 --out {ws}/r.mcap", "not a regular file"),
    ("import {ws}/npy_as.npz --test 6 --out {ws}/r.mcap", "npy_as.npz"),
    ("import {ws}/empty.csv --test 6 --out {ws}/r.mcap", "empty.csv"),
    ("import {ws}/export.csv --config {ws}/deep_arrays.toml --out {ws}/r.mcap", "nested deeper"),
    ("import {ws}/export.csv --config {ws}/fifo.toml --out {ws}/r.mcap", "not a regular file"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --set bodies.rod.mass_kg=1e300", "bodies.rod.mass_kg"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --calibration {ws}/fifo.csv", "fifo.csv"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --calibration ''", "--calibration"),
    # ---- replay: output folders it must never replace, recordings that cannot be replayed
    ("replay {ws}/rec.mcap --out {ws}", "holds the input"),
    ("replay {ws}/rec.mcap --out .", "--out"),
    ("replay {ws}/rec.mcap --out ''", "--out: is empty"),
    ("replay {ws}/rec.mcap --out {ws}/userdir", "did not write"),
    ("replay {ws}/sub/rec2.mcap --out {ws}/sub", "holds the input"),
    ("replay {ws}/rec.mcap --out {ws}/{LONG}", "bytes long"),
    ("replay {ws}/rec.mcap --out {ws}/loop1", "symbolic-link loop"),
    ("replay {ws}/rec.mcap --out {ws}/selfloop", "symbolic-link loop"),
    ("replay {ws}/rec.mcap --out {ws}/dangling.mcap", "--out"),
    ("replay {ws}/rec.mcap --out {ws}/rp --dtw-max 0", "--dtw-max"),
    ("replay {ws}/rec.mcap --out {ws}/rp --dtw-max nan", "--dtw-max"),
    ("replay {ws}/rec.mcap --out {ws}/rp --dtw-window -1", "--dtw-window"),
    ("replay {ws}/rec.mcap --out {ws}/rp --dtw-window nan", "--dtw-window"),
    ("replay {ws}/rec.mcap --out {ws}/rp --max-lag nan", "--max-lag"),
    ("replay {ws}/rec.mcap --out {ws}/rp --window nan 1", "--window"),
    ("replay {ws}/rec.mcap --out {ws}/rp --window 1 1", "--window"),
    ("replay {ws}/rec.mcap --out {ws}/rp --window -1 0.5", "--window"),
    ("replay {ws}/small.mcap --out {ws}/rp", "too little motion"),
    ("replay {ws}/walk.mcap --out {ws}/rp", "too little motion"),
    ("replay {ws}/magic_only.mcap --out {ws}/rp", "magic_only.mcap"),
    ("replay {ws}/empty.mcap --out {ws}/rp", "empty.mcap"),
    ("replay {ws}/meta_notjson.mcap --out {ws}/rp", "not JSON"),
    ("replay {ws}/t0_text.mcap --out {ws}/rp", "t0"),
    ("replay {ws}/no_names.mcap --out {ws}/rp", "names"),
    ("replay {ws}/fewer_names.mcap --out {ws}/rp", "channels"),
    ("replay {ws}/no_config.mcap --out {ws}/rp", "twin.config"),
    ("replay {ws}/fifo.mcap --out {ws}/rp", "not a regular file"),
    ("replay {ws}/rec.mcap --out {ws}/rp --config {ws}/fifo.toml", "not a regular file"),
    ("replay {ws}/rec.mcap --out {ws}/rp --set bodies.rod.length_m=0.01", "bodies.rod.length_m"),
    ("replay {ws}/rec.mcap --out {ws}/rp --timestep nan", "simulation.timestep_s"),
    # ---- analyze
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --align-angle nan", "--align-angle"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --align-angle inf", "--align-angle"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --align-angle 1e9", "--align-angle"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --json {ws}", "--json"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --json {ws}/adir.json", "--json"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --json ''", "--json"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --json {ws}/missing/x.json", "--json"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --json {ws}/{LONG}.json", "--json"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --dtw-window -1", "--dtw-window"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --dtw-window nan", "--dtw-window"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --start nan", "--start"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --start -1", "--start"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --stop -1", "--stop"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --start 2 --stop 1", "--stop"),
    ("analyze repeatability {ws}/rec.mcap {ws}/rec.mcap --decimate 0", "--decimate"),
    ("analyze repeatability {ws}/magic_only.mcap {ws}/rec.mcap", "magic_only.mcap"),
    ("analyze repeatability {ws}/rec.mcap {ws}/fifo.mcap", "fifo.mcap"),
    ("analyze repeatability {ws}/meta_notjson.mcap {ws}/rec.mcap", "not JSON"),
    # ---- dataset
    ("dataset generate {ws}/spec_none_c.toml --out {ws}/ds", "factors.clearance_c_mm"),
    ("dataset generate {ws}/spec_b0.toml --out {ws}/ds", "factors.clearance_b_mm"),
    ("dataset generate {ws}/spec_b_range0.toml --out {ws}/ds", "factors.clearance_b_mm"),
    ("dataset generate {ws}/spec_c_no_c.toml --out {ws}/ds", "factors.clearance_c_mm"),
    ("dataset generate {ws}/spec_hold_missing.toml --out {ws}/ds", "splits.holdout.motor_rpm"),
    ("dataset generate {ws}/spec_hold_all.toml --out {ws}/ds", "splits.holdout.motor_rpm"),
    ("dataset generate {ws}/spec_hold_range.toml --out {ws}/ds", "splits.holdout.motor_rpm"),
    ("dataset generate {ws}/spec_hold_fault.toml --out {ws}/ds", "splits.holdout.fault"),
    ("dataset generate {ws}/spec_hold_fault_all.toml --out {ws}/ds", "splits.holdout.fault"),
    ("dataset generate {ws}/tiny.toml --out {ws}/ds --scheduler tcp://", "--scheduler"),
    ("dataset generate {ws}/tiny.toml --out {ws}/ds --scheduler tcp://host:99999x", "--scheduler"),
    ("dataset generate {ws}/tiny.toml --out {ws}/ds --scheduler 'tcp://a b'", "--scheduler"),
    ("dataset generate {ws}/tiny.toml --out {ws}/ds --scheduler ''", "--scheduler"),
    ("dataset generate {ws}/fifo.toml --out {ws}/ds", "not a regular file"),
    ("dataset generate {ws}/deep_spec.toml --out {ws}/ds", "nested deeper"),
    ("dataset generate {ws}/big.toml --out {ws}/ds", "at most"),
    ("dataset generate {ws}/tiny.toml --out ''", "--out: is empty"),
    ("dataset generate {ws}/tiny.toml --out {ws}/{LONG}", "bytes long"),
    ("dataset generate {ws}/tiny.toml --out {ws}/loop1", "symbolic-link loop"),
    ("dataset generate {ws}/tiny.toml --out {ws}/info_list_ds", "JSON object"),
    ("dataset generate {ws}/tiny.toml --out {ws}/info_text_ds", "JSON object"),
    ("dataset generate {ws}/tiny.toml --out {ws}/userdir", "holds no dataset"),
    ("dataset info {ws}/info_list_ds", "JSON object"),
    ("dataset info {ws}/info_notjson_ds", "unreadable"),
    ("dataset verify {ws}/info_list_ds", "JSON object"),
    ("dataset plan {ws}/spec_none_c.toml", "factors.clearance_c_mm"),
    ("dataset plan {ws}/spec_hold_all.toml", "splits.holdout.motor_rpm"),
    ("dataset plan {ws}/fifo.toml", "not a regular file"),
    ("dataset plan {ws}/deep_spec.toml", "nested deeper"),
    ("dataset plan {ws}/tiny.toml --show -1", "--show"),
    ("dataset plan {ws}/tiny.toml --workers 0", "--workers"),
    # ---- identify
    ("identify restitution {ws}/rec.mcap --grid ''", "--grid"),
    ("identify restitution {ws}/rec.mcap --grid nan,0.5", "--grid"),
    ("identify restitution {ws}/rec.mcap --grid 0.5", "--grid"),
    ("identify restitution {ws}/rec.mcap --grid a,b", "--grid"),
    ("identify restitution {ws}/rec.mcap --fine-step -1", "--fine-step"),
    ("identify restitution {ws}/rec.mcap --fine-step nan", "--fine-step"),
    ("identify restitution {ws}/rec.mcap --fine-step inf", "--fine-step"),
    ("identify restitution {ws}/rec.mcap --stop 1e6", "--stop"),
    ("identify restitution {ws}/rec.mcap --start 1e6", "--start"),
    ("identify restitution {ws}/rec.mcap --lowpass -1", "--lowpass"),
    ("identify restitution {ws}/rec.mcap --max-lag nan", "--max-lag"),
    ("identify restitution {ws}/rec.mcap --starts 0", "--starts"),
    ("identify restitution {ws}/rec.mcap --json ''", "--json"),
    ("identify restitution {ws}/rec.mcap --json {ws}/adir.json", "--json"),
    ("identify restitution {ws}/magic_only.mcap", "magic_only.mcap"),
    ("identify restitution {ws}/t0_text.mcap", "t0"),
    ("identify clearance {ws}/magic_only.mcap", "magic_only.mcap"),
    ("identify clearance {ws}/meta_notjson.mcap", "not JSON"),
    ("identify clearance {ws}/fifo.mcap", "fifo.mcap"),
    ("identify clearance {ws}/rec.mcap --model {ws}/fifo.toml", "fifo.toml"),
    ("identify clearance {ws}/rec.mcap --json ''", "--json"),
    ("identify clearance {ws}/rec.mcap --json {ws}/loop1/a.json", "--json"),
    ("identify train {ws}/info_list_ds --out {ws}/m.npz", "JSON object"),
    ("identify train {ws}/missing_ds --out ''", "--out"),
    ("identify train {ws}/missing_ds --out {ws}/{LONG}.npz", "--out"),
    ("identify evaluate {ws}/afile {ws}/missing_ds --out ''", "--out"),
    ("identify evaluate {ws}/afile {ws}/missing_ds --out {ws}/loop1", "--out"),
    # ---- study, check, calibrate
    ("study formulations --out ''", "--out"),
    ("study formulations --out {ws}/{LONG}", "--out"),
    ("study formulations --out {ws}/loop1", "--out"),
    ("study formulations --out {ws}/f --duration nan", "--duration"),
    ("check contact --out ''", "--out"),
    ("check contact --out {ws}/{LONG}.json", "--out"),
    ("check contact --out {ws}/loop1/c.json", "--out"),
    ("calibrate {ws}/rec.mcap --params contact.mu0 --out ''", "--out"),
]


def check_case(line: str, fragment: str, ws: Path, capsys, subs: dict[str, str]) -> None:
    """Run one table case (``{ws}`` and the keys of ``subs`` replaced) in ``ws``: exit 2, one line holding
    ``fragment``, no traceback, nothing on stdout, ``ws`` unchanged."""
    before = snapshot(ws)
    argv = shlex.split(line)
    for k, v in {"{ws}": str(ws), **subs}.items():
        argv = [a.replace(k, v) for a in argv]
    rc = main(argv)
    out, err = capsys.readouterr()
    assert rc == 2, (rc, err[-3000:])
    assert err.startswith("twin: error: ") and err.count("\n") == 1, err[-3000:]
    assert fragment in err, err
    assert "Traceback" not in err and out == "", (out, err)
    assert snapshot(ws) == before


@pytest.mark.parametrize("line, fragment", CASES, ids=[c[0].replace("{ws}/", "")[:90] for c in CASES])
def test_more_bad_input_is_one_line_exit_2_and_changes_nothing(line, fragment, ws, capsys, monkeypatch):
    monkeypatch.chdir(ws)
    check_case(line, fragment, ws, capsys, {"{LONG}": LONG})


def test_the_new_table_covers_every_command_and_is_large():
    from twin.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    assert {c[0].split()[0] for c in CASES} == set(sub.choices)
    assert len(CASES) >= 150
    from test_bad_input import CASES as OLD

    assert not {c[0] for c in CASES} & {c[0] for c in OLD}, "the new cases repeat the old table"


# ------------------------------------------------------------ replay deletes nothing it did not write
def test_replay_into_the_recordings_own_folder_deletes_nothing(tmp_path, capsys, monkeypatch):
    """`twin replay DIR/rec.mcap --out DIR` once replaced DIR whole (the recording and the user's
    files deleted, exit 0): it is refused, and so is any folder holding files a replay did not write."""
    monkeypatch.chdir(tmp_path)
    d = tmp_path / "DIR"
    d.mkdir()
    shutil.copy(SAMPLE, d / "rec.mcap")
    (d / "notes.txt").write_text("mine\n")
    before = snapshot(tmp_path)
    for out in (d, Path("DIR"), Path("DIR/"), Path("DIR/..") / "DIR"):
        assert main(["replay", str(d / "rec.mcap"), "--out", str(out), "--no-plots"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "--out" in err, err
    assert snapshot(tmp_path) == before


def test_replay_may_replace_its_own_earlier_folder(tmp_path, capsys):
    """A folder holding only what a replay writes (an earlier replay) is replaced as before."""
    from twin.bench_replay import REPLAY_FILES  # noqa: F401

    from twin.util import check_output_dir

    out = tmp_path / "rp"
    out.mkdir()
    for name in ("replay.mcap", "report.json", "accelerations.png"):
        (out / name).write_bytes(b"earlier replay")
    assert check_output_dir(out, own=lambda n: n in REPLAY_FILES, inputs=(SAMPLE,)) == out
    (out / "mine.txt").write_text("x")
    with pytest.raises(Exception, match="did not write.*mine.txt"):
        check_output_dir(out, own=lambda n: n in REPLAY_FILES, inputs=(SAMPLE,))


# ------------------------------------------------------------------------ output names
def test_a_legal_250_character_name_is_written(tmp_path):
    """The temporary name beside a target must fit wherever the target fits (it once added 20+
    characters to a 250-character name and failed with ENAMETOOLONG)."""
    from twin.util import atomic_write_text, temp_path

    name = "n" * 245 + ".json"
    assert len(name) == 250
    tmp = temp_path(tmp_path / name)
    assert len(tmp.name.encode()) <= 255 and tmp.name.startswith(".")
    atomic_write_text(tmp_path / name, "{}\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]
    assert main(["export-mjcf", "--out", str(tmp_path / ("m" * 246 + ".xml"))]) == 0
    assert len(list(tmp_path.iterdir())) == 2


def test_leftovers_of_dead_processes_are_removed_by_any_later_run_in_the_folder(tmp_path):
    """A SIGKILLed writer leaves its temporary file; the next run writing anything in that folder
    removes it (its process no longer exists); a live process's temporary is kept."""
    from twin.util import _HOST

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    pid = int(dead.stdout)
    left = [tmp_path / f".run.mcap.{_HOST}-{pid}.tmp", tmp_path / f".old.rrd.{_HOST}-{pid}.tmp.rrd"]
    for p in left:
        p.write_bytes(b"half written")
    (tmp_path / f".x.tmp.dir.{_HOST}-{pid}.tmp").mkdir()
    live = tmp_path / f".busy.mcap.{_HOST}-{os.getppid()}.tmp"
    live.write_bytes(b"being written")
    assert main(["export-mjcf", "--out", str(tmp_path / "other.xml")]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([live.name, "other.xml"])


# --------------------------------------------------------------------------- full disk
def test_standard_output_on_a_full_disk_is_one_line(tmp_path):
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full")
    with open("/dev/full", "w") as full:
        r = subprocess.run([sys.executable, "-m", "twin.cli", "dataset", "plan", str(ROOT / "analysis" / "datasets" /
                            "tiny.toml"), "--no-estimate"], stdout=full, stderr=subprocess.PIPE, text=True,
                           cwd=tmp_path, timeout=120)
    assert r.returncode in (1, 2), r.stderr
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("twin: error: "), r.stderr
    assert "Traceback" not in r.stderr and "Exception ignored" not in r.stderr
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------- folder lock
def _tiny_spec(tmp_path: Path) -> Path:
    spec = tmp_path / "s.toml"
    spec.write_text('[dataset]\nname = "lock"\n[base]\ntest = 6\nduration_s = 0.01\n[factors]\n'
                    'motor_rpm = [300.0]\n[outputs]\nrate_hz = 10000.0\ntruth = ["accel"]\ninstrumented = false\n')
    return spec


def test_a_second_generator_on_a_folder_is_refused_naming_the_holder(tmp_path, capsys):
    import socket

    from twin.util import FolderLock

    spec, out = _tiny_spec(tmp_path), tmp_path / "ds"
    out.mkdir()
    with FolderLock(out, "--out", "twin dataset generate"):
        before = snapshot(tmp_path)
        assert main(["dataset", "generate", str(spec), "--out", str(out), "--limit", "0", "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "in use by another twin dataset generate" in err, err
        assert f"pid {os.getpid()}" in err and socket.gethostname() in err, err
        assert snapshot(tmp_path) == before
    # released: the same command runs
    assert main(["dataset", "generate", str(spec), "--out", str(out), "--limit", "0", "--no-progress"]) == 0


def test_the_lock_of_a_killed_holder_is_taken_over(tmp_path, capsys):
    """SIGKILL cannot be handled, but the kernel drops a dead process's flock: the next generator
    runs (the holder line of the dead process left in the file is overwritten)."""
    spec, out = _tiny_spec(tmp_path), tmp_path / "ds"
    out.mkdir()
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time; from twin.util import FolderLock; "
                               f"FolderLock({str(out)!r}).acquire(); print('held', flush=True); time.sleep(120)"],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        assert main(["dataset", "generate", str(spec), "--out", str(out), "--limit", "0", "--no-progress"]) == 2
        assert f"pid {holder.pid}" in capsys.readouterr().err
    finally:
        holder.kill()
        holder.wait(timeout=60)
    assert f"pid {holder.pid}" in (out / ".twin.lock").read_text()  # SIGKILL: no clean-up ran
    assert main(["dataset", "generate", str(spec), "--out", str(out), "--no-progress"]) == 0
    assert (out / "runs.parquet").is_file()
    assert (out / ".twin.lock").read_text() == ""  # released at the end of the run


# ----------------------------------------------------------------------- divergence
def test_a_diverging_run_stops_in_one_line_and_leaves_no_mujoco_log(tmp_path, capfd, monkeypatch):
    """A timestep of 1 ms (100 times the default) cannot resolve the 0.1 mm clearance's impacts and
    the run diverges within milliseconds: one line naming the time, the quantity and the fields
    likely responsible; MuJoCo's own warning neither printed nor written to MUJOCO_LOG.TXT; no
    output file."""
    monkeypatch.chdir(tmp_path)
    rc = main(["simulate", "--test", "6", "--duration", "0.05", "--no-progress", "--out", str(tmp_path / "x.mcap"),
               "--timestep", "1e-3", "--output-rate", "1000"])
    out, err = capfd.readouterr()
    assert rc == 2 and out == "" and err.count("\n") == 1, (rc, out, err)
    assert "diverged at t = " in err and "qacc" in err and "simulation.timestep_s" in err, err
    assert "WARNING" not in out + err and list(tmp_path.iterdir()) == []


def test_restitution_one_runs_without_damping():
    """e = 1 is a perfectly elastic contact: the linear equivalent has no damping (a root finder
    once failed on it with a traceback)."""
    from twin.impact import impact_linear, linear_damping_ratio

    assert linear_damping_ratio(1.0) == 0.0
    assert impact_linear(1.0, 0.0, 1.0, 1.0).restitution == pytest.approx(1.0, abs=1e-6)  # closed form: e = 1
    assert 0.3 < linear_damping_ratio(0.4) < 0.4  # the documented 0.358
