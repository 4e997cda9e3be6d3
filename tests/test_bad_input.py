"""Bad input of every command: one line, exit status 2, nothing written or overwritten.

Each case of :data:`CASES` runs the real command line (``twin.cli.main``) in a workspace that
holds valid inputs next to broken ones (a run file, a bench recording, DAQ exports, traces,
configuration files, an existing output that must survive). For every case: exit status 2,
exactly one line on stderr that starts ``twin: error:`` and names the field, option or file
(the expected fragment), no traceback, nothing on stdout, and the workspace unchanged, file by
file (names, sizes, contents) — no new file, no temporary left behind, nothing overwritten.
Signals and killed runs are tested at the end with real child processes.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from twin.cli import main
from twin.config import preset

from conftest import short

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "recordings" / "test6_synthetic.mcap"


# ------------------------------------------------------------------------ workspace
@pytest.fixture(scope="module")
def workspace(tmp_path_factory) -> Path:
    ws = tmp_path_factory.mktemp("bad_input")
    from twin.mcapfile import write_run
    from twin.simulation import simulate_run

    write_run(ws / "run.mcap", simulate_run(short(preset(6), 0.02)))
    shutil.copy(SAMPLE, ws / "rec.mcap")
    (ws / "old.mcap").write_bytes(b"old contents")
    (ws / "afile").write_text("a plain file\n")
    (ws / "adir.mcap").mkdir()
    (ws / "garbage.mcap").write_bytes(b"\x89MCAP0\r\n" + os.urandom(200))
    (ws / "binary.toml").write_bytes(b"\x00\xff\xfe\x80 not text")
    (ws / "syntax.toml").write_text("[joints\nclearance_b_mm = 0.1\n")
    (ws / "unknown.toml").write_text("[joints]\nclearance_x_mm = 0.1\n")
    (ws / "type.toml").write_text('[joints]\nclearance_b_mm = "wide"\n')
    (ws / "notrace.toml").write_text('[drive]\nprogram = "trace"\n')
    (ws / "test99.toml").write_text("test = 99\n")
    (ws / "name.toml").write_text('name = "../escape"\n')
    (ws / "confdir.toml").mkdir()
    (ws / "confdir.toml" / "x").write_text("not a dataset")
    (ws / "unknown_factor.toml").write_text('[dataset]\nname = "u"\n[factors]\nclearence_c_mm = [0.1]\n')
    shutil.copy(ROOT / "analysis" / "datasets" / "tiny.toml", ws / "tiny.toml")
    # encoder traces
    t = np.arange(200) / 1000.0
    np.savez(ws / "bool_trace.npz", t=t, angle=np.ones(200, dtype=bool))
    (ws / "garbage_trace.npz").write_bytes(os.urandom(300))
    (ws / "trace.txt").write_text("t,angle\n0,0\n")
    (ws / "backwards.csv").write_text("t,angle\n0,0\n0.002,0.1\n0.001,0.2\n")
    # DAQ exports for import
    n = 200
    cols = {"t": np.arange(n) / 1e5, **{f"volt_AC{i}": np.full(n, 2.5) for i in range(1, 7)},
            "encoder_counts": np.arange(n, dtype=float) // 40}
    header = ",".join(f"{k} [V]" if k.startswith("volt") else (f"{k} [count]" if k.startswith("enc") else k)
                      for k in cols)
    np.savetxt(ws / "export.csv", np.column_stack(list(cols.values())), delimiter=",", header=header, comments="")
    np.savez(ws / "bool.npz", **{**cols, "volt_AC1": np.ones(n, dtype=bool)})
    np.savez(ws / "complex.npz", **{**cols, "volt_AC1": np.full(n, 2.5 + 1j)})
    (ws / "ragged.csv").write_text("t,volt_AC1\n0,2.5\n1e-5\n")
    return ws


def _snapshot(root: Path) -> dict[str, tuple[int, str]]:
    out = {}
    for p in sorted(root.rglob("*")):
        rel = str(p.relative_to(root))
        out[rel] = (-1, "dir") if p.is_dir() else (p.stat().st_size, hashlib.sha256(p.read_bytes()).hexdigest())
    return out


# --------------------------------------------------------------------------- cases
#: (command line, fragment the one-line error must contain). {ws} is the workspace.
CASES: list[tuple[str, str]] = [
    # record: its own options and the configuration's
    ("record --duration 0.01 --out r.mcap --static 0", "--static: must lie in [0.1, 60] s"),
    ("record --duration 0.01 --out r.csv", "--out: must end in .mcap"),
    ("record --duration 0.01", "the following arguments are required: --out"),
    ("record --clearance-b 0.3 --out r.mcap", "joints.clearance_b_mm"),
    # simulate: values of the configuration options
    ("simulate --clearance-b 0.3", "joints.clearance_b_mm"),
    ("simulate --clearance-c -1", "joints.clearance_c_mm"),
    ("simulate --clearance-c nan", "joints.clearance_c_mm"),
    ("simulate --speed 2000", "drive.motor_rpm"),
    ("simulate --speed fast", "--speed: invalid float value"),
    ("simulate --test 13", "--test"),
    ("simulate --test 6 --config {ws}/type.toml", "cannot be combined with --config"),
    ("simulate --preset s999", "--preset"),
    ("simulate --preset s001 --test 6", "--preset"),
    ("simulate --preset s001 --config {ws}/type.toml", "cannot be combined with --config"),
    ("simulate --preset s001 --set contact.friction_law=stribeck", "contact.friction_law"),
    ("simulate --preset s001 --set drive.ramp_shape=cubic", "drive.ramp_shape"),
    ("identify restitution {ws}/export.csv", "an .mcap file"),
    ("simulate --duration -1", "simulation.duration_s"),
    ("simulate --duration 1e-6", "at least one output sample"),
    ("simulate --duration 4000", "simulation.duration_s"),
    ("simulate --duration inf", "simulation.duration_s"),
    ("simulate --timestep 7e-6", "does not divide"),
    ("simulate --timestep 3e-5", "--output-rate"),
    ("simulate --timestep 0", "simulation.timestep_s"),
    ("simulate --output-rate 0", "sensors.output_rate_hz"),
    ("simulate --output-rate 300000", "simulation.timestep_s"),
    ("simulate --channels ''", "--channels"),
    ("simulate --channels accel,,crank", "--channels"),
    ("simulate --channels accel,gps", "sensors.channels"),
    ("simulate --channels accel,accel", "sensors.channels"),
    ("simulate --clearance-guide -1", "joints.clearance_guide_mm"),
    ("simulate --clearance-guide 5", "joints.clearance_guide_mm"),
    ("simulate --set joints.guide_span_m=0", "joints.guide_span_m"),
    ("simulate --orientation w", "--orientation: invalid choice"),
    ("simulate --engine bullet", "--engine: invalid choice"),
    ("simulate --speed 500 --protocol", "not allowed with"),
    ("simulate --frobnicate", "unrecognized arguments: --frobnicate"),
    ("simulate --test", "--test: expected one argument"),
    # simulate: output locations (checked before any work)
    ("simulate --out {ws}/run.txt", "--out"),
    ("simulate --out {ws}/missing/x.mcap", "--out: directory"),
    ("simulate --out /proc/x.mcap", "--out: cannot write"),
    ("simulate --out {ws}/afile/x.mcap", "is not a directory"),
    ("simulate --out {ws}/adir.mcap", "is a directory"),
    ("simulate --out {ws}/old.mcap --no-out", "--no-out"),
    ("simulate --out {ws}/old.mcap --summary-json {ws}/s.txt", "--summary-json"),
    ("simulate --out {ws}/old.mcap --summary-json /proc/s.json", "--summary-json: cannot write"),
    ("simulate --out {ws}/old.mcap --rerun {ws}/r.mcap", "--rerun"),
    ("simulate --out {ws}/old.mcap --rerun {ws}/afile/r.rrd", "--rerun"),
    # simulate: drive traces
    ("simulate --trace {ws}/missing.npz", "--trace: no such file"),
    ("simulate --trace {ws}/garbage_trace.npz", "garbage_trace.npz"),
    ("simulate --trace {ws}/trace.txt", "--trace: must be a .npz or .csv"),
    ("simulate --trace {ws}/bool_trace.npz", "must hold real numbers"),
    ("simulate --trace {ws}/backwards.csv", "strictly increasing"),
    # simulate: configuration files
    ("simulate --config {ws}/missing.toml", "--config: cannot read"),
    ("simulate --config {ws}/binary.toml", "not a UTF-8"),
    ("simulate --config {ws}/syntax.toml", "not valid TOML"),
    ("simulate --config {ws}/unknown.toml", "joints.clearance_x_mm: unknown field"),
    ("simulate --config {ws}/type.toml", "joints.clearance_b_mm: must be a number"),
    ("simulate --config {ws}/notrace.toml", "drive.trace_file"),
    ("simulate --config {ws}/test99.toml", "error: test: must be a Table 4 test id"),  # the file's key, not --test
    ("simulate --config {ws}/name.toml", "name"),
    ("simulate --config {ws}/confdir.toml", "is a directory"),
    # simulate: --set
    ("simulate --set nonsense", "KEY=VALUE"),
    ("simulate --set =3", "KEY=VALUE"),
    ("simulate --set drive.motor_rmp=3", "drive.motor_rmp: unknown field"),
    ("simulate --set joints=3", "joints"),
    ("simulate --set simulation.chunk_s=0", "simulation.chunk_s"),
    ("simulate --set mujoco.contact_damping=viscous", "mujoco.contact_damping"),
    ("simulate --set sensors.channels=[]", "sensors.channels"),
    ("simulate --set contact.impact_speed_floor_mps=0", "contact.impact_speed_floor_mps"),
    # export-mjcf
    ("export-mjcf --out {ws}/m.txt", "--out"),
    ("export-mjcf --out /proc/m.xml", "--out: cannot write"),
    ("export-mjcf --out {ws}/m.xml --engine reference", "unrecognized arguments: --engine"),
    ("export-mjcf --out {ws}/m.xml --set drive.motor_rpm=100", "does not apply"),
    ("export-mjcf --out {ws}/m.xml --clearance-c 0.3", "joints.clearance_c_mm"),
    # import
    ("import {ws}/missing.csv --test 6 --out {ws}/r.mcap", "missing.csv"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.txt", "--out"),
    ("import {ws}/export.csv --test 6 --out {ws}/afile/r.mcap", "--out"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --engine reference", "unrecognized arguments: --engine"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --timestep 2e-5", "unrecognized arguments: --timestep"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --set simulation.engine=reference", "does not apply"),
    ("import {ws}/bool.npz --test 6 --out {ws}/r.mcap", "volt_AC1"),
    ("import {ws}/complex.npz --test 6 --out {ws}/r.mcap", "volt_AC1"),
    ("import {ws}/ragged.csv --test 6 --out {ws}/r.mcap", "ragged.csv"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --rate 0", "--rate"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --zero-g AC1=high", "--zero-g"),
    ("import {ws}/export.csv --test 6 --out {ws}/r.mcap --zero-g AC1=2.5 --calibration {ws}/export.csv",
     "alternatives"),
    # replay
    ("replay {ws}/missing.mcap --out {ws}/rp", "missing.mcap"),
    ("replay {ws}/export.csv --out {ws}/rp", "twin import"),
    ("replay {ws}/rec.mcap --out {ws}/rp --speed 500", "unrecognized arguments: --speed"),
    ("replay {ws}/rec.mcap --out {ws}/rp --duration 0.1", "unrecognized arguments: --duration"),
    ("replay {ws}/rec.mcap --out {ws}/rp --window 5 6", "--window"),
    ("replay {ws}/rec.mcap --out {ws}/rp --max-lag -1", "--max-lag"),
    ("replay {ws}/rec.mcap --out {ws}/rp --max-lag inf", "--max-lag"),
    ("replay {ws}/rec.mcap --out {ws}/afile", "--out"),
    ("replay {ws}/garbage.mcap --out {ws}/rp", "garbage.mcap"),
    ("replay {ws}/rec.mcap --out {ws}/rp --set drive.program=constant", "does not apply"),
    ("replay {ws}/rec.mcap --out {ws}/rp --clearance-c 0.3", "joints.clearance_c_mm"),
    # view
    ("view {ws}/missing.mcap", "missing.mcap"),
    ("view {ws}/export.csv", ".mcap"),
    ("view {ws}/run.mcap --save {ws}/out.txt", "--save"),
    ("view {ws}/run.mcap --save {ws}/afile/out.rrd", "--save"),
    ("view {ws}/garbage.mcap --save {ws}/g.rrd", "garbage.mcap"),
    ("view {ws}/run.mcap --save {ws}/v.rrd --screenshot {ws}/shot.jpg", "--screenshot"),
    # plot
    ("plot {ws}/missing.mcap --out {ws}/p.png", "missing.mcap"),
    ("plot {ws}/export.csv --out {ws}/p.png", ".mcap"),
    ("plot {ws}/run.mcap", "--out"),
    ("plot {ws}/run.mcap --out {ws}/p.jpg", "--out: must end in .png"),
    ("plot {ws}/run.mcap --out {ws}/afile/p.png", "--out"),
    ("plot {ws}/run.mcap --out {ws}/nodir/p.png", "--out: directory"),
    ("plot {ws}/garbage.mcap --out {ws}/p.png", "garbage.mcap"),
    ("plot {ws}/afile --out {ws}/p.png", ".mcap"),
    ("plot {ws}/run.mcap --out {ws}/p.png --channels AC9", "--channels: 'AC9' matches no channel"),
    ("plot {ws}/rec.mcap --out {ws}/p.png --channels AC1", "--channels: 'AC1' matches no channel"),
    ("plot {ws}/run.mcap --out {ws}/p.png --window 1:2", "--window: 1..2 s lies outside the run"),
    ("plot {ws}/rec.mcap --out {ws}/p.png --window a:b", "--window: expects START:STOP"),
    ("plot {ws}/run.mcap --out {ws}/old.mcap", "--out"),
    # dataset
    ("dataset generate {ws}/missing.toml --out {ws}/ds", "missing.toml"),
    ("dataset generate {ws}/syntax.toml --out {ws}/ds", "not valid TOML"),
    ("dataset generate {ws}/unknown_factor.toml --out {ws}/ds", "factors.clearence_c_mm"),
    ("dataset generate {ws}/tiny.toml --out {ws}/afile", "--out"),
    ("dataset generate {ws}/tiny.toml --out {ws}/confdir.toml", "holds no dataset"),
    ("dataset generate {ws}/tiny.toml --out {ws}/ds --workers 0", "--workers"),
    ("dataset generate {ws}/tiny.toml --out {ws}/ds --limit -1", "--limit"),
    ("dataset generate {ws}/tiny.toml --out {ws}/ds --scheduler bogus", "--scheduler"),
    ("dataset plan {ws}/type.toml", "unknown section"),
    ("dataset info {ws}/afile", "not a dataset folder"),
    ("dataset verify {ws}/missing_ds", "not a dataset folder"),
    # identify
    ("identify clearance {ws}/missing.mcap", "missing.mcap"),
    ("identify clearance {ws}/export.csv", "twin import"),
    ("identify clearance {ws}/rec.mcap --model {ws}/afile", "not a readable identification model"),
    ("identify clearance {ws}/rec.mcap --model {ws}/missing.npz", "no such model file"),
    ("identify clearance {ws}/rec.mcap --json {ws}/a.txt", "--json"),
    ("identify clearance {ws}/run.mcap", "'twin record'"),  # a run file of twin simulate
    ("identify train {ws}/afile --out {ws}/m.npz", "not a dataset folder"),
    ("identify train {ws}/missing_ds --out {ws}/m.txt", "--out"),
    ("identify train {ws}/missing_ds --out {ws}/m.npz --splits train,dev", "--splits"),
    ("identify evaluate {ws}/afile {ws}/missing_ds --out {ws}/rep", "not a readable identification model"),
    # study, check, calibrate, analyze
    ("study formulations --out {ws}/afile", "--out"),
    ("study formulations --out {ws}/f --duration -1", "--duration"),
    ("study accuracy --out {ws}/afile --quick", "--out"),
    ("check contact --joints X --out {ws}/cal.json", "--joints"),
    ("check contact --out {ws}/cal.txt", "--out"),
    ("calibrate {ws}/rec.mcap --params contact.nothing --out {ws}/cal", "--params"),
    ("calibrate {ws}/rec.mcap --params drive.motor_rpm --out {ws}/cal", "--params"),
    ("calibrate {ws}/rec.mcap --params contact.mu0 --bounds contact.mu0=0.5:0.1 --out {ws}/cal", "--bounds"),
    ("calibrate {ws}/rec.mcap --params contact.mu0 --bounds contact.mu0=-1:0.1 --out {ws}/cal", "--bounds"),
    ("calibrate {ws}/rec.mcap --params mechanism.d_off_m --out {ws}/cal", "--bounds"),
    ("calibrate {ws}/rec.mcap --params contact.mu0 --out {ws}/afile", "--out"),
    ("calibrate {ws}/missing.mcap --params contact.mu0 --out {ws}/cal", "RECORDING"),
    ("calibrate {ws}/rec.mcap --params contact.mu0 --out {ws}/cal --short-fraction 2", "--short-fraction"),
    ("calibrate {ws}/rec.mcap --params contact.mu0 --out {ws}/cal --profile-steps 0.1,x", "--profile-steps"),
    ("calibrate {ws}/rec.mcap --params contact.mu0 --out {ws}/cal --profile-steps 0.9", "--profile-steps"),
    ("analyze repeatability {ws}/rec.mcap", "at least 2"),
    ("analyze repeatability {ws}/rec.mcap {ws}/missing.mcap", "missing.mcap"),
]


@pytest.mark.parametrize("line, fragment", CASES, ids=[c[0].replace("{ws}/", "") for c in CASES])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(line, fragment, workspace, capsys, monkeypatch):
    import shlex

    monkeypatch.chdir(workspace)
    before = _snapshot(workspace)
    argv = [a.replace("{ws}", str(workspace)) for a in shlex.split(line)]
    rc = main(argv)
    out, err = capsys.readouterr()
    assert rc == 2, (rc, err)
    assert err.startswith("twin: error: ") and err.count("\n") == 1, err
    assert fragment in err, err
    assert "Traceback" not in err and out == "", (out, err)
    assert _snapshot(workspace) == before


def test_the_table_covers_every_command_and_is_large():
    from twin.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    commands = {c[0].split()[0] for c in CASES}
    assert commands == set(sub.choices), set(sub.choices) - commands
    assert len(CASES) >= 60


# ---------------------------------------------------------------- replay output folder
def test_rejected_replay_keeps_the_existing_output_folder(workspace, capsys, monkeypatch):
    """A replay refused after its recording was read (bad --window) leaves an existing output
    folder as it was: today's trace is the one its replay.mcap points to."""
    monkeypatch.chdir(workspace)
    folder = workspace / "prev_replay"
    folder.mkdir()
    (folder / "encoder_trace.npz").write_bytes(b"trace of the earlier replay")
    (folder / "replay.mcap").write_bytes(b"earlier replay")
    before = _snapshot(workspace)
    assert main(["replay", str(workspace / "rec.mcap"), "--out", str(folder), "--window", "5", "6"]) == 2
    assert "--window" in capsys.readouterr().err
    assert _snapshot(workspace) == before


# ---------------------------------------------------------------------------- signals
def _start(args: list[str], cwd: Path) -> subprocess.Popen:
    # a shell's background job inherits SIGINT ignored; give the child the default disposition
    return subprocess.Popen([sys.executable, "-m", "twin.cli", *args], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _wait_for(cond, proc: subprocess.Popen, timeout: float = 90.0) -> None:
    deadline = time.monotonic() + timeout
    while not cond():
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.05)


def test_sigterm_during_replay_leaves_no_folder(tmp_path):
    out = tmp_path / "rp"
    proc = _start(["replay", str(SAMPLE), "--out", str(out), "--no-plots"], tmp_path)
    # the temporary folder holds the trace once the simulation starts (it takes seconds)
    _wait_for(lambda: any(p.name.startswith(".rp.") and (p / "encoder_trace.npz").exists()
                          for p in tmp_path.iterdir()), proc)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert list(tmp_path.iterdir()) == [], (list(tmp_path.iterdir()), err)
    assert err.strip().splitlines()[-1] == "twin: terminated", err


def test_sigkill_leftovers_are_removed_by_the_next_run_on_the_same_target(tmp_path):
    """SIGKILL cannot be handled: the killed run's temporary file stays, and the next run that
    writes the same target removes it (its process no longer exists)."""
    out = tmp_path / "run.mcap"
    proc = _start(["simulate", "--test", "12", "--duration", "60", "--no-progress", "--out", str(out)], tmp_path)
    _wait_for(lambda: list(tmp_path.glob(".run.mcap.*.tmp")), proc)
    time.sleep(0.3)
    proc.kill()
    proc.communicate(timeout=60)
    left = list(tmp_path.glob(".run.mcap.*.tmp"))
    assert len(left) == 1 and left[0].stat().st_size > 0
    assert main(["simulate", "--test", "3", "--duration", "0.01", "--no-progress", "--out", str(out)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.mcap"]


def _raise_bad_config() -> None:
    from twin.config import BenchConfig

    BenchConfig().replace(**{"joints.clearance_c_mm": 0.45})


def test_every_twin_error_survives_a_process_boundary():
    """Errors raised in a process-pool worker (dataset generation, the studies) are pickled back to
    the parent: each TwinError class round-trips with its message and fields, and a ConfigError raised
    in a spawned worker arrives as itself, naming the field (before, its two-argument constructor
    failed to unpickle and the pool broke with no message)."""
    import inspect
    import multiprocessing as mp
    import pickle
    from concurrent.futures import ProcessPoolExecutor

    import importlib

    for mod in ("twin.cli", "twin.dataset.generate", "twin.dataset.spec", "twin.dataset.storage",
                "twin.identification.features", "twin.identification.model", "twin.identification.training",
                "twin.signals"):  # each defines a TwinError
        importlib.import_module(mod)
    from twin.errors import ConfigError, TwinError

    def subclasses(c):
        for s in c.__subclasses__():
            yield s
            yield from subclasses(s)

    classes = set(subclasses(TwinError)) | {TwinError}
    assert len(classes) >= 12
    for cls in classes:
        n = len([p for p in inspect.signature(cls.__init__).parameters.values()
                 if p.name != "self" and p.default is p.empty and p.kind is p.POSITIONAL_OR_KEYWORD])
        args = ("joints.clearance_b_mm", "must be 0 or a catalogue value")[:n] if n else ("one line",)
        err = cls(*args)
        back = pickle.loads(pickle.dumps(err))
        assert type(back) is cls and str(back) == str(err) and vars(back) == vars(err), cls
    with ProcessPoolExecutor(1, mp_context=mp.get_context("spawn")) as ex:
        with pytest.raises(ConfigError, match=r"joints\.clearance_c_mm: .*catalogue") as info:
            ex.submit(_raise_bad_config).result(timeout=120)
    assert info.value.field == "joints.clearance_c_mm"
