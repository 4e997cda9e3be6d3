"""A replay drives the crank by the recording's encoder trace, whatever drove the recorded run: recordings of the
motor drive, of a steps program and of a drive with an imposed ripple replay with the crank on the trace; a drive
mode asked on the command line that does not follow a trace, or a field of the program the trace replaces, is
refused in one line naming the field and the allowed values.

Independent basis: the recorded encoder counts themselves (the replayed crank follows them within their
quantization, below one count, as in test_replay.py)."""

from __future__ import annotations

import argparse

import pytest

from twin.bench_replay import ReplayOptions, motor_config, replay, replay_config, trace_drive
from twin.config import preset
from twin.errors import ConfigError, TwinError


@pytest.mark.parametrize("overrides", [
    # the motor drive: before, replayed by the motor's speed loop on the trace (3390 counts behind, a tenth of a turn)
    {"drive.mode": "motor"},
    # a steps program: before, refused ("drive.steps_s: is not used by drive.program = 'trace'"), a field not set
    {"drive.program": "steps", "drive.steps_s": (0.0,), "drive.steps_rpm": (600.0,)},
    # a ripple imposed on the program: before, imposed again on the trace that holds it (314 counts off)
    {"drive.ripple_pct": (3.0,)},
], ids=["motor", "steps", "ripple"])
def test_recordings_of_other_drives_replay_on_their_trace(tmp_path, overrides):
    import twin

    rec = tmp_path / "rec.mcap"
    twin.record(preset(6).replace(**{"simulation.duration_s": 0.7, "drive.ramp_s": 0.2, **overrides}), rec,
                static_s=0.1)
    report = replay(rec, tmp_path / "out", opts=ReplayOptions(plots=False))
    assert report.tracking.sim_vs_recorded_max_counts < 1.0, report.tracking


def _args(*argv: str) -> argparse.Namespace:
    from twin.commands import replay as replay_cmd

    parser = argparse.ArgumentParser()
    replay_cmd.register(parser.add_subparsers())
    return parser.parse_args(["replay", "rec.mcap", *argv])


@pytest.mark.parametrize("setting", ["drive.mode=torque", "drive.mode=motor", 'drive={mode="torque"}'])
def test_a_drive_mode_that_does_not_follow_the_trace_is_refused(setting):
    """Before, --set drive.mode=torque was replayed by the crank PID (the torque drive has no program to follow)
    and motor by the motor's speed loop behind the trace, neither saying so."""
    from twin.commands.replay import replay_overrides

    with pytest.raises(TwinError, match=r"^--set drive\.mode: a replay drives the crank by the recording's encoder "
                                        r"trace, with pid or prescribed .*got '(torque|motor)'") as err:
        replay_overrides(_args("--set", setting), preset(6))
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("key", ["drive.ripple_pct=[2.0]", "drive.motor_rpm=300", "drive.steps_rpm=[500]",
                                 "drive.ramp_s=0.1"])
def test_fields_of_the_program_the_trace_replaces_are_refused(key):
    from twin.commands.replay import replay_overrides

    name = key.split("=")[0]
    with pytest.raises(ConfigError, match=rf"^--set {name}: does not apply to this command"):
        replay_overrides(_args("--set", key), preset(6))


@pytest.mark.parametrize("mode", ["pid", "prescribed"])
def test_a_motor_recording_replays_with_the_trace_mode_asked(mode):
    """Before, --set drive.mode=pid on a motor recording was refused for the recording's motor channels
    ("sensors.channels: the optional group 'motor' needs ..."), a field the replay sets itself."""
    from twin.commands.replay import replay_overrides

    rec = preset(6).replace(**{"drive.mode": "motor", "drivetrain.belt_ea_n": 3e4,
                               "sensors.channels": ["accel", "encoder", "crank", "slider", "joints", "drive", "motor"]})
    assert replay_overrides(_args("--set", f"drive.mode={mode}"), rec).drive.mode == mode


def test_the_motor_comparison_keeps_the_recordings_drive_train(tmp_path):
    """A motor recording is replayed by the PID (drive-train fields back to their defaults), and the motor model
    driven by its recorded command (--drive motor) by the recording's own drive train."""
    base = preset(6).replace(**{"drive.mode": "motor", "drivetrain.belt_ea_n": 3e4})
    assert trace_drive(base)["drive.mode"] == "pid"

    class _Rec:  # what replay_config reads of a recording
        n, rate_hz = 1000, 1e5

    cfg = replay_config(base, tmp_path / "trace.npz", _Rec(), {})
    assert cfg.drive.mode == "pid" and cfg.drivetrain.belt_ea_n != 3e4
    m = motor_config(cfg, tmp_path / "cmd.npz", base)
    assert m.drive.mode == "motor" and m.drivetrain.belt_ea_n == 3e4
    assert motor_config(cfg, tmp_path / "cmd.npz").drivetrain.belt_ea_n == cfg.drivetrain.belt_ea_n  # PID: defaults
