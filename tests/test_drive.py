"""Drive programs: the reference the PID tracks, and the tracking itself."""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.config import BenchConfig, preset
from twin.drive import RPM_TO_RAD_S, DriveReference, command_events
from twin.errors import RecordingError
from twin.simulation import simulate_run

from conftest import short

COUNT = 2 * math.pi / 32768  # one encoder count [rad]


def test_protocol_speeds_and_timing():
    cfg = preset(12).replace(**{"drive.program": "protocol"})
    ref = DriveReference(cfg)
    assert cfg.drive.protocol_duration_s == 38.0
    t = np.array([1.0, 7.0, 13.0, 19.0, 25.0, 31.0, 37.0])
    _, w = ref(t)
    crank = [rpm / 3.97 * RPM_TO_RAD_S for rpm in (250, 500, 750)]
    np.testing.assert_allclose(w, [0, crank[0], 0, crank[1], 0, crank[2], 0], atol=1e-12)
    assert command_events(cfg)[0] == (2.0, 250.0) and len(command_events(cfg)) == 6
    np.testing.assert_array_equal(ref.command_rpm(t), [0, 250, 0, 500, 0, 750, 0])


def test_reference_angle_is_the_integral_of_its_rate():
    ref = DriveReference(preset(9).replace(**{"drive.program": "protocol"}))
    t = np.linspace(0, 38, 380_001)
    th, w = ref(t)
    integral = th[0] + np.concatenate([[0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])
    assert np.max(np.abs(th - integral)) < 1e-6
    # smooth cosine ramps: the crank acceleration never exceeds π/2 Δω / ramp_s (no speed jump)
    accel = np.diff(w) / np.diff(t)
    assert np.max(np.abs(accel)) <= math.pi / 2 * (750 / 3.97 * RPM_TO_RAD_S) / 0.5 * 1.001


def test_initial_angle_follows_encoder_zero():
    th, _ = DriveReference(BenchConfig())(np.array([0.0]))
    assert th[0] == pytest.approx(-math.pi / 2)  # encoder zero: crank along -y


def test_pid_tracks_the_constant_program_within_one_count():
    run = simulate_run(short(preset(3), 1.2, **{"drive.ramp_s": 0.4}))
    steady = run.window(0.8, 1.2)
    err = steady["theta_ref"] - steady["crank_angle"]
    assert np.max(np.abs(err)) < COUNT


def test_trace_program_tracks_a_file(tmp_path):
    # a smooth non-constant crank motion written as an encoder trace (encoder convention)
    t = np.arange(0, 0.6, 1e-4)
    phi = 15.0 * t + 0.4 * np.sin(2 * np.pi * 3 * t)
    np.savez(tmp_path / "trace.npz", t=t, angle=phi)
    cfg = BenchConfig().replace(**{"drive.program": "trace", "drive.trace_file": str(tmp_path / "trace.npz"),
                                   "simulation.duration_s": 0.5, "sensors.channels": ["encoder", "drive"]})
    run = simulate_run(cfg)
    expected = np.interp(run.time, t, phi)
    assert np.max(np.abs(run["encoder_angle"][1000:] - expected[1000:])) < 2 * COUNT


def test_bad_trace_files(tmp_path):
    np.savez(tmp_path / "nan.npz", t=np.arange(5.0), angle=np.array([0, 1, np.nan, 3, 4.0]))
    np.savez(tmp_path / "back.npz", t=np.array([0, 1, 0.5, 2.0]), angle=np.zeros(4))
    np.savez(tmp_path / "cols.npz", time=np.arange(5.0), angle=np.zeros(5))
    for name, msg in (("nan.npz", "NaN"), ("back.npz", "increasing"), ("cols.npz", "'t' and 'angle'")):
        cfg = BenchConfig().replace(**{"drive.program": "trace", "drive.trace_file": str(tmp_path / name)})
        with pytest.raises(RecordingError, match=msg):
            DriveReference(cfg)


def test_steps_program_is_a_sequence_of_constant_program_steps():
    """A one-step "steps" program is the constant program; later steps take the speed to each
    commanded motor speed / belt ratio once their ramp is over, and the command reads back."""
    from twin.drive import DriveReference

    base = preset(6).replace(**{"drive.ramp_s": 0.2})
    t = np.linspace(0.0, 3.0, 3001)
    one = base.replace(**{"drive.program": "steps", "drive.steps_s": [0.0], "drive.steps_rpm": [750.0]})
    np.testing.assert_array_equal(DriveReference(one)(t)[0], DriveReference(base)(t)[0])
    prof = base.replace(**{"drive.program": "steps", "drive.steps_s": [0.0, 1.0, 2.0],
                           "drive.steps_rpm": [500.0, -250.0, 0.0]})
    ref = DriveReference(prof)
    _, om = ref(np.array([0.9, 1.9, 2.9]))
    np.testing.assert_allclose(om * 3.97 * 60 / (2 * np.pi), [500.0, -250.0, 0.0], atol=1e-9)
    np.testing.assert_array_equal(ref.command_rpm(np.array([0.5, 1.5, 2.5])), [500.0, -250.0, 0.0])
