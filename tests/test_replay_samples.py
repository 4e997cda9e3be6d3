"""The committed sample recordings, and ``twin analyze repeatability`` (S003 §5)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from twin.cli import main
from twin.config import BenchConfig
from twin.instrument import measured_accel
from twin.mcapfile import write_run
from twin.recording import read_recording
from twin.bench_replay import ReplayOptions, render_markdown, replay
from twin.run import Run

SAMPLES = Path(__file__).resolve().parents[1] / "recordings"
RATE = 100_000.0


@pytest.mark.parametrize("name", ["test3_synthetic", "test6_synthetic", "test6_repeat1_synthetic",
                                  "test6_repeat2_synthetic", "test6_repeat3_synthetic",
                                  "static_calibration_synthetic"])
def test_sample_recordings_are_valid_and_labelled_synthetic(name):
    run, info, repairs = read_recording(SAMPLES / f"{name}.mcap")
    assert info.synthetic and "SYNTHETIC" in info.notes and repairs == []
    assert run.rate_hz == RATE and run.config.instrumentation.daq_rate_hz == RATE
    if name.startswith("static"):
        return
    assert info.extra["engine"] == "reference"
    cal = info.calibration
    assert cal is not None and cal.samples == 100_000
    meas = measured_accel(run, cal)
    # slider, vertical: 1 g on average; starts at rest (the replay's initial state)
    assert np.mean(meas["meas_AC5"]) == pytest.approx(9.81, abs=0.02)
    assert np.ptp(run["encoder_counts"][:1000]) <= 1  # at rest: at most one count edge flickers
    assert run.config.joints.clearance_c_mm == (0.1 if "test6" in name else 0.0)


def test_static_sample_calibrates_like_the_stored_calibration(tmp_path):
    from twin.recording import static_calibration_from

    _, info, _ = read_recording(SAMPLES / "test6_synthetic.mcap")
    cal = static_calibration_from(SAMPLES / "static_calibration_synthetic.mcap", BenchConfig())
    assert cal.zero_g_v == pytest.approx(dict(info.calibration.zero_g_v), abs=2e-5)


@pytest.mark.parametrize("name", ["test3_synthetic", "test6_synthetic"])
def test_replay_of_a_sample_with_its_own_model(tmp_path, name):
    r = replay(SAMPLES / f"{name}.mcap", tmp_path / "out", opts=ReplayOptions(plots=False))
    assert r.configuration.engine == "reference" and r.configuration.same_as_recording
    assert r.tracking.sim_vs_recorded_max_counts < 1.0
    for a in ("AC1", "AC2", "AC4", "AC6"):
        assert r.sensors[a].nrmse_pct < 1.5
        if name == "test6_synthetic":
            assert abs(r.sensors[a].bands[0].difference_db) < 1.5
    # the recorded encoder trace drives the simulation: aligned by construction, up to the
    # 10-50 us by which impact instants move with the quantized counts (test 6, clearance)
    lo, hi = r.time_lag_ci_s
    assert r.time_lag_well_defined and lo <= r.time_lag_s <= hi
    if name == "test3_synthetic":
        # ideal joints, smooth signals: lag 0 within one sample (was +4.3 ms, NRMSE 3.4 %, when
        # the noise-only AC5 weighed as much as the other sensors in the lag search)
        assert r.time_lag_s == 0.0 and -1 / RATE <= lo <= hi <= 1 / RATE
        # two independent ADXL1001 noise records, sqrt(2) x 0.066 m/s^2, on a ~90 m/s^2 range: ~0.1 %
        assert r.sensors["AC4"].nrmse_pct < 0.3
    else:
        assert abs(r.time_lag_s) <= 5e-5 and hi - lo <= 1e-4
    assert "CI" in render_markdown(r.to_dict())


# ---------------------------------------------------------------- repeatability
def _runs(tmp_path, delays, starts=None, n=30_000):
    """Crank-periodic AC4 signals of 'repeated runs', each delayed by delays[i] [s]."""
    paths = []
    w = 19.8
    cfg = BenchConfig()
    rng = np.random.default_rng(0)
    for i, d in enumerate(delays):
        t = np.arange(n) / RATE - d
        phi0 = 0.0 if starts is None else starts[i]
        theta = w * t + phi0
        ac4 = 40 * np.sin(theta) + 12 * np.sin(2 * theta + 0.5) + rng.normal(0, 0.05, n)
        run = Run.from_arrays(0.0, RATE, {"AC4": ac4, "encoder_angle": theta}, cfg)
        p = tmp_path / f"run{i + 1}.mcap"
        write_run(p, run)
        paths.append(str(p))
    return paths


def test_repeatability_table_recovers_shifts(tmp_path, capsys):
    paths = _runs(tmp_path, [0.0, 0.002, -0.003])
    out = tmp_path / "rep.json"
    assert main(["analyze", "repeatability", *paths, "--dtw-window", "0.01", "--json", str(out),
                 "--no-progress"]) == 0
    res = json.loads(out.read_text())
    shifts = {(p["run_a"], p["run_b"]): p for p in res["pairs"]}
    assert set(shifts) == {(1, 2), (1, 3), (2, 3)}
    # mean |shift| along the path: a little below the delay (the path ramps in at the start)
    assert shifts[(1, 2)]["mean_shift_s"] == pytest.approx(0.002, abs=4e-4)
    assert shifts[(2, 3)]["mean_shift_s"] == pytest.approx(0.005, abs=6e-4)
    assert shifts[(1, 2)]["signed_shift_s"] > 0 > shifts[(1, 3)]["signed_shift_s"]
    assert res["worst"]["run_a"] == 2 and res["worst"]["run_b"] == 3
    for p in res["pairs"]:
        assert p["distance_pct"] < 2.0  # edges only; noise 0.05 on a range of ~100
    assert "worst: runs 2 and 3" in capsys.readouterr().out


def test_repeatability_aligns_runs_with_different_start_angles(tmp_path, capsys):
    paths = _runs(tmp_path, [0.0, 0.0, 0.0], starts=[0.0, 1.0, 2.5])
    common = ["analyze", "repeatability", *paths, "--start", "0.02", "--stop", "0.1", "--dtw-window", "0.005",
              "--no-progress", "--json"]
    assert main(common + [str(tmp_path / "raw.json")]) == 0
    assert main(common + [str(tmp_path / "al.json"), "--align-angle", "90"]) == 0
    raw = json.loads((tmp_path / "raw.json").read_text())
    al = json.loads((tmp_path / "al.json").read_text())
    assert raw["worst"]["distance_pct"] > 10.0  # up to 2.5 rad out of phase: no 5 ms band fixes that
    assert al["worst"]["distance_pct"] < 0.5
    # each window starts where that run passes 90 deg
    for start, phi0 in zip(al["window_starts_s"], [0.0, 1.0, 2.5]):
        k = math.ceil((phi0 + 19.8 * 0.02 - math.pi / 2) / (2 * math.pi))
        expected = (math.pi / 2 + 2 * math.pi * k - phi0) / 19.8
        assert start == pytest.approx(expected, abs=2 / RATE)


def test_repeatability_errors(tmp_path, capsys):
    paths = _runs(tmp_path, [0.0, 0.001], n=2000)
    assert main(["analyze", "repeatability", paths[0]]) == 2
    assert "at least 2" in capsys.readouterr().err
    assert main(["analyze", "repeatability", *paths, "--channel", "AC9"]) == 2
    assert "no channel 'AC9'" in capsys.readouterr().err
    assert main(["analyze", "repeatability", *paths, "--start", "5"]) == 2
    assert "window" in capsys.readouterr().err
    assert main(["analyze", "repeatability", paths[0], str(tmp_path / "missing.mcap")]) == 2
    assert "no such file" in capsys.readouterr().err
