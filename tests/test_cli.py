"""The command line: clear one-line errors, no partial files, the summary JSON."""

from __future__ import annotations

import json

import pytest

from twin import simulation as simulate_mod
from twin.cli import main
from twin.errors import ConfigError, SimulationError
from twin.mcapfile import read_run, read_summary


def _run(capsys, *argv):
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.mark.parametrize("argv, fragment", [
    (["--clearance-b", "0.3"], "joints.clearance_b_mm"),
    (["--speed", "2000"], "drive.motor_rpm"),
    (["--test", "13"], "--test"),
    (["--duration", "-1"], "simulation.duration_s"),
    (["--timestep", "7e-6"], "does not divide"),
    (["--set", "drive.motor_rmp=3"], "drive.motor_rmp"),
    (["--set", "nonsense"], "KEY=VALUE"),
    (["--config", "missing.toml"], "cannot read"),
    (["--trace", "missing.npz"], "--trace: no such file"),
    (["--trace", "missing.csv"], "--trace: no such file"),
    (["--channels", "accel,gps"], "sensors.channels"),
    (["--summary-json", "s.txt"], "--summary-json"),
])
def test_bad_input_is_one_line_and_writes_nothing(argv, fragment, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "old.mcap").write_bytes(b"old")
    rc, out, err = _run(capsys, "simulate", "--out", "old.mcap", "--duration", "0.01", *argv)
    assert rc == 2
    assert err.count("\n") == 1 and err.startswith("twin: error:") and fragment in err
    assert "Traceback" not in err
    assert (tmp_path / "old.mcap").read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.mcap"]


def test_argparse_errors_are_one_line(capsys):
    assert main(["simulate", "--orientation", "w"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "invalid choice" in err


def test_engine_failure_midway_keeps_old_file(capsys, tmp_path, monkeypatch):
    real = simulate_mod.make_engine

    class Dying:
        """The real engine, which diverges in its second chunk."""

        def __init__(self, cfg, inputs=None):
            self.inner = real(cfg, inputs)
            self.name, self.meta = self.inner.name, self.inner.meta
            self.calls = 0

        def reset(self, theta0=None):
            self.inner.reset(theta0)

        def advance(self, theta_ref, omega_ref, stride):
            self.calls += 1
            if self.calls == 2:
                raise SimulationError("diverged at t = 0.01 s (test)")
            return self.inner.advance(theta_ref, omega_ref, stride)

    monkeypatch.setattr(simulate_mod, "make_engine", Dying)
    out = tmp_path / "run.mcap"
    out.write_bytes(b"old")
    rc, _, err = _run(capsys, "simulate", "--test", "6", "--duration", "0.03", "--set", "simulation.chunk_s=0.01",
                      "--out", str(out), "--summary-json", str(tmp_path / "s.json"), "--rerun", str(tmp_path / "r.rrd"))
    assert rc == 2 and "diverged" in err and err.count("\n") == 1
    assert out.read_bytes() == b"old" and not (tmp_path / "s.json").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.mcap"]


def test_simulate_writes_run_and_summary(capsys, tmp_path):
    out, js = tmp_path / "t12.mcap", tmp_path / "s.json"
    rc, stdout, _ = _run(capsys, "simulate", "--test", "12", "--duration", "0.05", "--out", str(out),
                         "--summary-json", str(js), "--no-progress")
    assert rc == 0 and "test12" in stdout
    s = json.loads(js.read_text())
    for key in ("engine", "duration_s", "timestep_s", "steps", "wall_s", "real_time_factor"):
        assert key in s
    assert s["engine"] == "mujoco" and s["steps"] == 5000 and s["duration_s"] == pytest.approx(0.05)
    assert s["real_time_factor"] == pytest.approx(0.05 / s["wall_s"])
    for j in ("B", "C"):
        assert set(s[j]) == {"clearance_mm", "max_eccentricity_m", "max_penetration_m", "impacts",
                             "max_contact_force_N"}
        assert s[j]["clearance_mm"] == 0.1 and s[j]["max_eccentricity_m"] > 0
    for a in ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6"):
        assert s[a]["peak_mps2"] >= s[a]["rms_mps2"] > 0
    run = read_run(out)
    assert run.n == 5000 and run.config.name == "test12"
    assert read_summary(out) == s


def test_export_mjcf(capsys, tmp_path):
    rc, out, _ = _run(capsys, "export-mjcf", "--test", "9", "--out", str(tmp_path / "m.xml"))
    assert rc == 0 and (tmp_path / "m.xml").read_text().count("<pair") == 1  # B: one pair (the native law)
    rc, _, err = _run(capsys, "export-mjcf", "--test", "9", "--out", str(tmp_path / "m.txt"))
    assert rc == 2 and "must end in .xml" in err


@pytest.mark.parametrize("sig, rc", [("SIGTERM", 143), ("SIGINT", 130)])
def test_killed_run_leaves_no_file(tmp_path, sig, rc):
    """A run stopped by SIGTERM (a job scheduler, `kill`) or Ctrl-C removes its temporary file
    and leaves nothing under the final name; the exit status says which signal stopped it."""
    import signal
    import subprocess
    import sys
    import time
    out = tmp_path / "run.mcap"
    # a shell's background job (`cmd &`, nohup) inherits SIGINT ignored, and Python then keeps
    # ignoring it (as it should); give the child the default disposition Ctrl-C would meet
    proc = subprocess.Popen([sys.executable, "-m", "twin.cli", "simulate", "--test", "12",
                             "--duration", "60", "--no-progress", "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 60
    while not list(tmp_path.glob(".run.mcap.*.tmp")):   # wait until the writer is under way
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.05)
    time.sleep(0.3)
    proc.send_signal(getattr(signal, sig))
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == rc, err
    assert list(tmp_path.iterdir()) == []
    assert err.strip().splitlines()[-1] in ("twin: terminated", "twin: interrupted")


def test_set_with_a_table_sets_its_fields_only(capsys, tmp_path):
    from twin.cli import build_parser, config_from_args

    args = build_parser().parse_args(["simulate", "--duration", "0.3", "--set", "simulation={timestep_s=5e-6}"])
    cfg = config_from_args(args)
    assert cfg.simulation.timestep_s == 5e-6 and cfg.simulation.duration_s == 0.3  # the rest kept
    rc = main(["export-mjcf", "--out", str(tmp_path / "m.xml"), "--set", 'simulation={engine="reference"}'])
    assert rc == 2 and "--set simulation.engine: does not apply" in capsys.readouterr().err
    assert main(["simulate", "--config", "", "--no-out"]) == 2
    assert "--config: is empty" in capsys.readouterr().err


def test_a_trace_config_without_duration_runs_for_the_trace(tmp_path):
    """A configuration file with the trace program and no duration runs for the trace's length: the
    command line's ``--config`` fills it in from the trace; the library's loader opens no data file
    (its configuration keeps 0, "the trace's length", and the run fills it in from the trace it reads)."""
    import numpy as np

    from twin.cli import load_config_file
    from twin.config import load_config
    from twin.tracefile import with_trace_duration

    np.savez(tmp_path / "tr.npz", t=np.linspace(0, 0.75, 751), angle=np.linspace(0, 1, 751))
    (tmp_path / "c.toml").write_text(f'[drive]\nprogram = "trace"\ntrace_file = "{tmp_path / "tr.npz"}"\n')
    assert load_config_file(str(tmp_path / "c.toml")).simulation.duration_s == 0.75
    loaded = load_config(tmp_path / "c.toml")
    assert loaded.simulation.duration_s == 0 and loaded.trace_length_pending
    assert with_trace_duration(loaded).simulation.duration_s == 0.75
    assert with_trace_duration(loaded).to_dict() == load_config_file(str(tmp_path / "c.toml")).to_dict()
    with pytest.raises(ConfigError, match="simulation.duration_s: is 0, the trace's length"):
        loaded.duration_s  # noqa: B018 - asked before the trace is read: one line, naming the field
    (tmp_path / "d.toml").write_text(f'[drive]\nprogram = "trace"\ntrace_file = "{tmp_path / "tr.npz"}"\n'
                                     "[simulation]\nduration_s = 0.5\n")
    assert load_config(tmp_path / "d.toml").simulation.duration_s == 0.5
    assert load_config_file(str(tmp_path / "d.toml")).simulation.duration_s == 0.5
    # the loader reads no data file: a trace that does not exist loads, and is refused when read
    (tmp_path / "e.toml").write_text(f'[drive]\nprogram = "trace"\ntrace_file = "{tmp_path / "absent.npz"}"\n')
    assert load_config(tmp_path / "e.toml").trace_length_pending
    with pytest.raises(ConfigError, match="drive.trace_file: no such file"):
        load_config_file(str(tmp_path / "e.toml"))


def test_check_contact_wiring(tmp_path, monkeypatch, capsys):
    """``twin check contact`` passes its options to the check and prints and writes its report.
    The check itself is replaced by a fixed report here (this is the command line's wiring; the
    check's physics is tests/test_calibration.py). Its old name ``twin calibrate contact`` is gone:
    ``twin calibrate`` fits configuration fields (tests/test_calibrate_fit.py)."""
    import json

    import twin.studies.contact_check as contact_check_module
    from twin.cli import main

    seen = []

    def fake_check(cfg, joints, progress):
        seen.append(joints)
        return {"ok": True, "cases": {"B:0.1": {"m_eff_kg": {"min": 0.8, "median": 1.3, "max": 3.5},
                                                "max_scaled_error": {"restitution": 0.04, "peak_force": 0.2,
                                                                     "duration": 0.05},
                                                "static_error": 1e-6, "capture_agrees": True}}}

    monkeypatch.setattr(contact_check_module, "contact_check", fake_check)
    out = tmp_path / "check.json"
    assert main(["check", "contact", "--joints", "B", "--no-progress", "--out", str(out)]) == 0
    cap = capsys.readouterr()
    assert seen == [("B",)]
    assert "| B:0.1 | 0.80/1.30/3.50 | 0.04 | 0.20 | 0.05 | 0.000 % | same |" in cap.out
    assert json.loads(out.read_text())["ok"] is True
    assert cap.err == ""


def test_bad_value_in_a_config_file_names_the_file_and_the_field(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "old.mcap").write_bytes(b"old")
    (tmp_path / "bad.toml").write_text("[joints]\nclearance_b_mm = -1\n")
    rc, out, err = _run(capsys, "simulate", "--out", "old.mcap", "--config", "bad.toml")
    assert rc == 2 and err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("twin: error: joints.clearance_b_mm:") and "bad.toml" in err
    assert (tmp_path / "old.mcap").read_bytes() == b"old"
    # a trace file the configuration names: the field and the file it is in
    (tmp_path / "trace.toml").write_text('[drive]\nprogram = "trace"\ntrace_file = "nope.csv"\n')
    rc, out, err = _run(capsys, "simulate", "--out", "old.mcap", "--config", "trace.toml")
    assert rc == 2 and err.count("\n") == 1
    assert err.startswith("twin: error: drive.trace_file: no such file") and "trace.toml" in err


def test_an_option_value_starting_with_a_dash_is_named_with_how_to_write_it(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "r.csv").write_text("name,a,b\nx,1,2\ny,2,1\n")
    base = ["study", "mcdm", "r.csv", "--criteria", "a:min,b:max", "--out", "o"]
    rc, out, err = _run(capsys, *base, "--weights", "-1,2")
    assert rc == 2 and err.count("\n") == 1
    assert "--weights" in err and "'-1,2' reads as an option: write --weights=-1,2" in err
    rc, out, err = _run(capsys, *base, "--weights=-1,2")  # as the message says: read, then refused by its rule
    assert rc == 2 and err.count("\n") == 1 and err.startswith("twin: error: --weights:") and ">= 0" in err
    rc, out, err = _run(capsys, "study", "mcdm", "r.csv", "--criteria", "a:min,b:max", "--weights", "--out", "o")
    assert rc == 2 and "reads as an option" not in err  # a real option after the flag: no such advice
    assert not (tmp_path / "o").exists()


def test_continuous_contact_config_says_it_replaces_the_preset(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "alone.toml").write_text("[joints]\nclearance_b_mm = 0.5\n")  # from the default bench: C has play
    rc, out, err = _run(capsys, "study", "continuous-contact", "--config", "alone.toml", "--out", "o",
                        "--duration", "0.02")
    assert rc == 2 and err.count("\n") == 1 and err.startswith("twin: error: joints.clearance_c_mm:")
    assert "alone.toml replaces the s004 preset" in err and 'preset = "s004"' in err and not (tmp_path / "o").exists()
    (tmp_path / "s004.toml").write_text('preset = "s004"\n[joints]\nclearance_b_mm = 0.5\n')
    rc, out, err = _run(capsys, "study", "continuous-contact", "--config", "s004.toml", "--out", "o",
                        "--duration", "0.02")
    assert rc == 0 and "replaces" not in err  # the file starts from s004: nothing replaced
    rc, out, err = _run(capsys, "study", "continuous-contact", "--config", "s004.toml", "--preset", "s004",
                        "--out", "o2")
    assert rc == 2 and err.count("\n") == 1 and "--preset: cannot be combined with --config" in err
    (tmp_path / "ok.toml").write_text('[joints]\nclearance_b_mm = 0.5\nclearance_c_mm = 0\n'
                                      '[drive]\nmode = "prescribed"\nprogram = "constant"\nramp_s = 0\n')
    rc, out, err = _run(capsys, "study", "continuous-contact", "--config", "ok.toml", "--out", "o3",
                        "--duration", "0.02")
    assert rc == 0 and err.count("\n") == 1 and err.startswith("twin: note: ok.toml replaces the s004 preset")
