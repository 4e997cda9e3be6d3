"""Recorded drive inputs travel in memory (:class:`twin.tracefile.DriveInputs`): the drive takes the
encoder trace and the motor command as arrays, the run they give is the run of the same numbers
read from a file, and a replay never reads back the files it writes (they are outputs only)."""

from __future__ import annotations

import numpy as np
import pytest

from twin.config import preset
from twin.errors import ConfigError, RecordingError
from twin.recording import crank_trace, synthetic_recording, write_recording
from twin.simulation import simulate_run
from twin.tracefile import DriveInputs


def _trace(duration: float = 0.12):
    t, phi = crank_trace(preset(6).drive.motor_rpm, preset(6).drive.belt_ratio, duration, 1e4, ramp_s=0.05)
    return t, phi


def _trace_cfg(path: str, duration: float = 0.1):
    return preset(6).replace(**{"simulation.engine": "mujoco", "simulation.duration_s": duration,
                                "drive.program": "trace", "drive.trace_file": path})


def test_in_memory_trace_runs_as_the_same_trace_read_from_a_file(tmp_path):
    """Same numbers, two ways in: bit for bit the same run. The in-memory run names a file that
    does not exist, so it cannot have read one."""
    t, phi = _trace()
    np.savez(tmp_path / "trace.npz", t=t, angle=phi)
    from_file = simulate_run(_trace_cfg(str(tmp_path / "trace.npz")))
    in_memory = simulate_run(_trace_cfg(str(tmp_path / "absent.npz")), inputs=DriveInputs(trace=(t, phi)))
    assert set(from_file.channels) == set(in_memory.channels)
    for name in from_file.channels:
        assert np.array_equal(from_file[name], in_memory[name]), name
    with pytest.raises(ConfigError, match="drive.trace_file"):  # and without the arrays it would have to
        simulate_run(_trace_cfg(str(tmp_path / "absent.npz")))


def test_in_memory_motor_command_is_the_command_file(tmp_path):
    from twin.motor_drive import command_voltage, motor_input

    t = np.arange(2000) / 1e4
    volts = 5.0 * np.minimum(t / 0.05, 1.0)
    np.savez(tmp_path / "cmd.npz", t=t, volts=volts)
    cfg = preset(6).replace(**{"drive.mode": "motor", "drivetrain.command_file": str(tmp_path / "cmd.npz")})
    absent = cfg.replace(**{"drivetrain.command_file": str(tmp_path / "absent.npz")})
    inputs = DriveInputs(command=(t, volts))
    omega = np.zeros(500)
    assert np.array_equal(motor_input(cfg, 10, 500, omega), motor_input(absent, 10, 500, omega, inputs))
    tq = np.linspace(0.0, 0.19, 300)
    assert np.array_equal(command_voltage(cfg, tq), command_voltage(absent, tq, inputs))
    with pytest.raises(ConfigError, match="no such file"):
        motor_input(absent, 10, 500, omega)


@pytest.mark.parametrize("trace, message", [
    ((np.arange(20.0) * 1e-3, np.zeros(19)), "equal length"),
    ((np.arange(20.0)[::-1] * 1e-3, np.zeros(20)), "strictly increasing"),
    ((np.arange(20.0) * 1e-3, np.full(20, np.nan)), "NaN"),
    ((np.arange(4.0) * 1e-3, np.zeros(4)), "at least"),
])
def test_bad_trace_arrays_get_a_one_line_error(trace, message):
    with pytest.raises(RecordingError, match=message) as err:
        DriveInputs(trace=trace)
    assert "\n" not in str(err.value) and str(err.value).startswith("drive trace")


def test_bad_command_arrays_name_the_field():
    t = np.arange(10) * 1e-3
    with pytest.raises(ConfigError, match="drivetrain.command_file.*10.2 V") as err:
        DriveInputs(command=(t, np.full(10, 50.0)))
    assert "\n" not in str(err.value)


def test_replay_does_not_read_back_its_own_files(tmp_path, monkeypatch):
    """The replay writes encoder_trace.npz and motor_command_trace.npz as outputs; with every file
    reader of the drive disabled it still runs (PID and motor drive), and the outputs are there."""
    from twin import drive as drive_mod, motor_drive, tracefile
    from twin.bench_replay import ReplayOptions, replay

    base = preset(3).replace(**{"simulation.duration_s": 0.4, "drive.ramp_s": 0.1, "instrumentation.seed": 1,
                                "simulation.engine": "mujoco"})
    t, phi = crank_trace(base.drive.motor_rpm, base.drive.belt_ratio, 0.4, 1e5, ramp_s=0.1)
    truth = simulate_run(base.replace(**{"drive.program": "trace", "drive.trace_filter_hz": 0.0,
                                         "drive.trace_file": str(tmp_path / "in-memory.npz")}),
                         inputs=DriveInputs(trace=(t, phi)))
    daq, info = synthetic_recording(truth, base, notes="drive inputs test", static_s=0.1)
    rec = write_recording(tmp_path / "rec.mcap", daq, info)

    def refuse(*_args, **_kw):
        raise AssertionError("a drive input was read from a file")

    monkeypatch.setattr(tracefile, "load_trace", refuse)
    monkeypatch.setattr(drive_mod, "load_trace", refuse)
    monkeypatch.setattr(motor_drive, "_command_file", refuse)
    out = tmp_path / "out"
    report = replay(rec, out, opts=ReplayOptions(plots=False, drive="motor"))
    assert (out / "encoder_trace.npz").is_file() and (out / "motor_command_trace.npz").is_file()
    assert report.motor_drive is not None
    with np.load(out / "encoder_trace.npz") as z:  # the output holds the trace the drive followed
        assert z["t"].size == daq.n


def test_a_trace_without_duration_runs_for_the_trace_length(tmp_path):
    """``simulation.duration_s = 0`` with the trace program: the run lasts as long as the trace (last
    minus first time stamp), read from the file or taken from memory, and both give the run of the
    same configuration with that duration written out."""
    t, phi = _trace(0.03)
    length = float(t[-1] - t[0])
    np.savez(tmp_path / "trace.npz", t=t, angle=phi)
    pending = _trace_cfg(str(tmp_path / "trace.npz"), 0.0)
    assert pending.trace_length_pending
    explicit = simulate_run(_trace_cfg(str(tmp_path / "trace.npz"), length))
    from_file = simulate_run(pending)
    absent = _trace_cfg(str(tmp_path / "absent.npz"), 0.0)
    in_memory = simulate_run(absent, inputs=DriveInputs(trace=(t, phi)))
    assert len(explicit.time) == round(length * explicit.rate_hz) and from_file.config.duration_s == length
    for run in (from_file, in_memory):
        assert run.config.simulation.duration_s == length
        for name in explicit.channels:
            assert np.array_equal(explicit[name], run[name]), name
    with pytest.raises(ConfigError, match="drive.trace_file: no such file"):
        simulate_run(absent)
