"""The calibration replays a recording as ``twin replay`` does, whatever drove it: with ``--drive trace`` the crank
follows the recording's encoder trace (steps programs, imposed ripples and motor drives included); with
``--drive program`` the recording's own program is run once; where drive-train fields are fitted, the motor
model runs with the fitted values. Bad ``--params`` are refused naming the real cause.

Independent basis of the tracking tests: the recorded encoder counts themselves (a crank on its trace follows
them within their quantization, below one count, as in test_replay_trace_drive.py)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from twin.calibration import make_parameters
from twin.calibration import objective as obj
from twin.config import preset
from twin.errors import ConfigError

_STEPS = {"drive.program": "steps", "drive.steps_s": (0.0,), "drive.steps_rpm": (600.0,)}
_RIPPLE = {"drive.ripple_pct": (3.0,)}


def _record(tmp_path, overrides, duration_s=0.5):
    import twin

    path = tmp_path / "rec.mcap"
    twin.record(preset(6).replace(**{"simulation.duration_s": duration_s, "drive.ramp_s": 0.2, **overrides}), path,
                static_s=0.1)
    return str(path)


def _tracking_counts(target) -> float:
    """Largest deviation of the simulated crank from the recorded encoder angle over the window [counts],
    their constant offset (the encoder's zero) removed."""
    sim, _scfg, _wall = obj.simulate_raw(target, target.base)
    i0, i1 = target.window
    d = (np.asarray(sim["crank_angle"][i0:i1]) - target.phi[i0:i1]) \
        * target.base.instrumentation.encoder_counts_per_rev / (2 * np.pi)
    return float(np.max(np.abs(d - np.median(d))))


@pytest.mark.parametrize("overrides", [_STEPS, _RIPPLE], ids=["steps", "ripple"])
def test_a_steps_or_ripple_recording_follows_its_trace(tmp_path, overrides):
    """Before: a steps recording was refused mid-run ("drive.steps_s: is not used by drive.program = 'trace'");
    a ripple recording had its ripple imposed again on the trace holding it (197 counts off)."""
    target = obj.prepare_target(_record(tmp_path, overrides), None, 1.0, 0.05, False, "trace")
    assert _tracking_counts(target) < 1.0


def test_a_motor_recording_follows_its_trace(tmp_path):
    """Before: the motor's own speed loop followed the trace through its dynamics (1082 counts off, a thirtieth
    of a turn). The trace filtered at 30 Hz leaves out the belt's faster speed fluctuations (3.6 counts
    measured): the bound, 1/1000 of a turn (33 counts), is a regression guard against the loop's lag."""
    target = obj.prepare_target(_record(tmp_path, {"drive.mode": "motor"}, 0.8), None, 1.0, 0.05, False, "trace")
    assert _tracking_counts(target) < 32768 / 1000


def _target(drive: str, motor: bool):
    return SimpleNamespace(drive=drive, n_sim=1000, rate=100000.0, zero_g={}, motor=motor)


_TORQUE = {"drive.mode": "torque", "drivetrain.torque_s": (0.02,), "drivetrain.torque_nm": (1.0,)}


@pytest.mark.parametrize("overrides", [{"drive.mode": "motor", **_STEPS}, _TORQUE], ids=["motor", "torque"])
def test_fitted_drive_train_values_run_in_the_motor_model_on_the_trace(overrides):
    """Before: on a torque recording the drive train went back to its defaults (the PID's) before the motor
    mode was set: every fitted value gave the same simulation."""
    cfg = obj.sim_config(_target("trace", True), preset(6).replace(**overrides, **{"drivetrain.belt_ea_n": 7.5e4}))
    assert cfg.drive.mode == "motor" and cfg.drive.program == "trace"
    assert cfg.drivetrain.belt_ea_n == 7.5e4 and cfg.drive.steps_s == preset(6).drive.steps_s


def test_the_program_drive_runs_a_torque_recordings_own_program_with_fitted_values():
    """Before: refused ("drivetrain.torque_s: is not used with drive.mode = 'motor'")."""
    cfg = obj.sim_config(_target("program", True), preset(6).replace(**_TORQUE, **{"drivetrain.belt_ea_n": 7.5e4}))
    assert cfg.drive.mode == "torque" and cfg.drivetrain.torque_nm == (1.0,) and cfg.drivetrain.belt_ea_n == 7.5e4


def test_the_program_drive_keeps_the_recordings_program():
    cfg = obj.sim_config(_target("program", False), preset(6).replace(**_STEPS, **_RIPPLE))
    assert cfg.drive.program == "steps" and cfg.drive.ripple_pct == (3.0,)


def _refused(call, words: str) -> None:
    with pytest.raises(ConfigError) as err:
        call()
    assert err.value.field == "params" and words in str(err.value) and "\n" not in str(err.value), str(err.value)


def test_drive_train_fields_on_a_pid_configuration_name_the_drive_mode():
    """Before: refused as --bounds ("drivetrain.belt_ea_n=5000:100000: the configuration refuses 5000")."""
    _refused(lambda: make_parameters("drivetrain.belt_ea_n", preset(6)), "drive.mode")


def test_a_trailing_comma_in_params_is_accepted_and_an_empty_field_named():
    assert [p.field for p in make_parameters("contact.mu0,contact.restitution,", preset(6))] == [
        "contact.mu0", "contact.restitution"]
    _refused(lambda: make_parameters("contact.mu0,,contact.restitution", preset(6)), "empty field between commas")
    _refused(lambda: make_parameters(",", preset(6)), "give one or more")
