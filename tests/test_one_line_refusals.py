"""Bad inputs a new user gave (a robustness probe): each is refused in one line naming the option or field and what
is allowed, before any work, where before it was accepted and ignored, contradicted silently, named a field the user
had not set, or ran for minutes. Each test says what happened before."""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.cli import build_parser, config_from_args, main
from twin.errors import ConfigError, TwinError


def _one_line(err: BaseException) -> str:
    text = str(err)
    assert "\n" not in text, text
    return text


@pytest.mark.parametrize("argv, field", [
    # before: the --set won silently (C simulated with 0.1 mm)
    (["--test", "6", "--clearance-c", "0.5", "--set", "joints.clearance_c_mm=0.1"], "--set joints.clearance_c_mm"),
    # before: refused as "sensors.channels: the optional group 'structure' is produced by the flexible structure
    # only", a field the user had not set
    (["--test", "6", "--structure", "flexible", "--set", 'structure={mode="rigid"}'], "--set structure.mode"),
    (["--test", "6", "--speed", "500", "--set", "drive.motor_rpm=250"], "--set drive.motor_rpm"),
])
def test_a_set_contradicting_an_option_is_refused(argv, field):
    args = build_parser().parse_args(["simulate", *argv, "--out", "x.mcap"])
    with pytest.raises(ConfigError) as err:
        config_from_args(args)
    assert _one_line(err.value).startswith(f"{field}: contradicts ")


def test_a_set_agreeing_with_an_option_is_accepted():
    args = build_parser().parse_args(["simulate", "--test", "6", "--speed", "500", "--set", "drive.motor_rpm=500",
                                      "--out", "x.mcap"])
    assert config_from_args(args).drive.motor_rpm == 500.0


def test_record_refuses_channel_groups_it_would_ignore(capsys):
    """Before, `twin record --channels accel` was accepted and wrote the same recording as without it (a recording
    holds the DAQ's channels whatever groups are computed)."""
    assert main(["record", "--test", "6", "--channels", "accel", "--out", "x.mcap"]) == 2
    assert "unrecognized arguments: --channels" in capsys.readouterr().err
    args = build_parser().parse_args(["record", "--test", "6", "--set", 'sensors.channels=["accel"]', "--out", "x.mcap"])
    with pytest.raises(ConfigError, match=r"^--set sensors\.channels: does not apply to this command"):
        config_from_args(args)


def test_a_recording_too_short_to_measure_its_rate_says_so():
    """Before: "too little motion: 4.17 crank revolutions ... (at least 2 steady revolutions are needed)" for a
    0.05 s recording of S000's 5000 rpm crank: more than 2 turns, but too short for the 50 ms rate windows."""
    from twin.identification.features import IdentifyError, steady_windows

    rate, cpr = 100_000.0, 32768.0
    t = np.arange(int(0.05 * rate)) / rate
    counts = np.floor(83.3 * t * cpr)  # 83.3 turns/s: 4.2 turns in 0.05 s
    with pytest.raises(IdentifyError) as err:
        steady_windows(counts, rate, cpr)
    text = _one_line(err.value)
    assert text.startswith("too short: 0.050 s") and "more than 0.1 s are needed" in text


def test_replay_refuses_a_dtw_without_a_band():
    """Before, --dtw-window 0 ran the library's band-free DTW on 0.5 s at 100 kHz: 4.5 minutes for one replay."""
    from twin.bench_replay import ReplayOptions

    with pytest.raises(ConfigError) as err:
        ReplayOptions(dtw_window_s=0.0)
    assert err.value.field == "dtw_window_s" and "(0, 10] s" in _one_line(err.value)
    assert ReplayOptions(dtw_window_s=0.001).dtw_window_s == 0.001


def test_view_refuses_a_spectrum_window_for_a_file_without_accelerations(tmp_path, capsys):
    """Before, `twin view REC --fft-window T0 T1` on a bench recording (DAQ volts: no spectra) was accepted and
    ignored; now refused, and no .rrd is left."""
    out = tmp_path / "v.rrd"
    assert main(["view", "sample:test6", "--save", str(out), "--fft-window", "0", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("twin: error: --fft-window: this file has no accelerations"), err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("kw, field", [
    # before: 1e8 scenes filled 4.5 GB of memory before the first one ran
    ({"scenes": 100_000_000}, "scenes"),
    # before: refused as "drive.ramp_s: must lie in [0, 10] s, got 132819.0214", a field the user had not set
    ({"duration_range_s": (1e6, 2e6)}, "durations"),
])
def test_the_stability_study_bounds_its_campaign(kw, field):
    from twin.studies.stability import StudySettings

    with pytest.raises(ConfigError) as err:
        StudySettings(**{"scenes": 1, "seed": 1, **kw})
    assert err.value.field == field
    _one_line(err.value)


def test_the_longest_stability_scenes_build_valid_configurations(tmp_path):
    """The bound on the durations holds the drive's ramp within its 10 s (checked on 200 draws at the bound)."""
    from twin.studies.stability import MAX_DURATION_S, sample_scene, scene_config

    for i in range(200):
        cfg = scene_config(sample_scene(1, i, (MAX_DURATION_S, MAX_DURATION_S)), tmp_path)
        assert math.isfinite(cfg.drive.ramp_s) and cfg.drive.ramp_s <= 10.0
