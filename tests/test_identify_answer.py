"""What the identification answers: every recording that turns through whole turns (a swinging speed included),
far-out features judged per recording, intervals held within the sizes trained on, booleans as booleans, a
refusal's ``--json`` record, a ``twin simulate`` file refused with the way to a recording, and the dataset
generator's bench recordings.

Independent bases: encoder traces of closed form (a speed ω = Ω (1 + a sin Ωt) after a linear spin-up: its
swing and its whole turns' mean rate are known); a feature vector with a known count beyond the fences; the
trained hull given in the test; the recordings of a dataset against ``twin.record`` of the same configuration
(one code path: sample for sample).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from twin.identification import features as F
from twin.identification import ranges as id_ranges

RATE = 100_000.0
CPR = 32768.0


def swinging_counts(swing: float, crank_hz: float = 2.0, ramp_s: float = 0.4, duration_s: float = 3.0) -> np.ndarray:
    """Encoder counts of a crank that spins up linearly over ``ramp_s`` to Ω = 2π ``crank_hz`` and then turns at
    ω = Ω (1 + ``swing`` sin Ωt'), t' the time after the ramp: φ = Ω t' + (swing)(1 − cos Ωt')."""
    t = np.arange(int(duration_s * RATE)) / RATE
    W = 2 * math.pi * crank_hz
    up = t < ramp_s
    tt = t - ramp_s
    phi = np.where(up, 0.5 * W * t * t / ramp_s, 0.5 * W * ramp_s + W * tt + swing * (1.0 - np.cos(W * tt)))
    return np.floor(phi / (2 * math.pi) * CPR)


# ------------------------------------------------------------------ the steadiness rule
@pytest.mark.parametrize("swing", [0.4, 0.65])
def test_a_recording_that_turns_with_a_large_speed_swing_is_answered_from_whole_steady_turns(swing):
    """The bench's motor drive swings the 50 ms crank rate by 32-65 % (soft speed loops, x vertical): such a
    recording has windows (the former 30 % cap refused it), reads its swing, and its windows leave the spin-up
    out: every window's mean rate (whole turns over their time) is the steady rate within TURN_TOL."""
    counts = swinging_counts(swing)
    w = F.steady_windows(counts, RATE, CPR)
    assert len(w.windows) >= 2
    # the 50 ms average of a sine at 2 Hz keeps sin(πfT)/(πfT) = 0.984 of its amplitude; the 95th percentile of
    # |sin| is 0.997 of its peak; the median the deviation is taken from, over the 2.95 periods of the last half,
    # lies within a few percent of the swing of Ω
    assert w.swing == pytest.approx(swing * 0.984 * 0.997, rel=0.05)
    for a, b in w.windows:
        rate = abs(counts[b] - counts[a]) / CPR * RATE / (b - a)
        assert abs(rate / 2.0 - 1.0) <= F.TURN_TOL
    assert w.windows[0][0] >= 0.4 * RATE * 0.5  # not from the first half of the spin-up


@pytest.mark.parametrize("duration_s", [2.6, 2.7, 2.8, 2.9, 3.0])
def test_the_spin_up_of_a_swinging_recording_is_left_out_by_whole_turns(duration_s):
    """With the tolerance widened to hold a 65 % swing, the 50 ms rate of the spin-up's second half lies within
    it; the steady part is made of the whole turns, counted back from the end, that turn at the steady rate, and
    of the part before them only where it too turns steadily, wherever the turns fall on the ramp."""
    counts = swinging_counts(0.65, duration_s=duration_s)  # the turns fall differently on the ramp
    w = F.steady_windows(counts, RATE, CPR)
    # a whole turn that straddles the ramp's end may turn at the steady mean rate (the swing's fast half making
    # up for the ramp's tail): the steady part may hold that tail, never the ramp's first half (below half the
    # speed), which the 65 % tolerance of the 50 ms rate alone would let in from 0.35 x 0.4 s on
    assert w.steady[0] >= 0.5 * 0.4 * RATE
    assert abs(counts[w.steady[1] - 1] - counts[w.steady[0]]) / CPR == pytest.approx(w.revolutions)


def test_a_steady_recording_keeps_its_windows():
    """No swing: the tolerance stays SPEED_TOL and the steady part starts within the 50 ms rate window after the
    ramp reaches within 10 % of the speed (the rule of the earlier versions)."""
    counts = swinging_counts(0.0)
    w = F.steady_windows(counts, RATE, CPR)
    assert w.swing < 0.01
    # the 50 ms rate over [t, t + 0.05 s] of the ramp is f (t + 0.025 s) / 0.4 s: within 10 % from t = 0.335 s
    assert w.steady[0] == pytest.approx((0.9 * 0.4 - 0.025) * RATE, abs=0.002 * RATE)


def test_less_than_two_whole_turns_is_still_refused():
    with pytest.raises(F.IdentifyError, match="too little motion"):
        F.steady_windows(swinging_counts(0.5, crank_hz=2.0, ramp_s=0.2, duration_s=0.8), RATE, CPR)


# ------------------------------------------------------------------ the checks against the training data
RANGES = {"source": "test", "runs": 3, "crank_hz": [1.0, 3.0], "ripple_pct": [[0.0, 100.0]] * 4,
          "noise_ug_rthz": [29.0, 31.0], "orientations": ["x", "y", "z"]}
M = {"crank_hz": 2.0, "ripple_pct": [0.0] * 4, "noise_ug_rthz": 30.0}


@pytest.mark.parametrize("swing, ranges, warned", [
    (40.0, RANGES, False), (id_ranges.BENCH_SWING_PCT, RANGES, False), (id_ranges.BENCH_SWING_PCT + 1, RANGES, True),
    (40.0, {**RANGES, "speed_swing_pct": [0.0, 30.0]}, True),   # beyond the trained swing + 5 points
    (34.0, {**RANGES, "speed_swing_pct": [0.0, 30.0]}, False),
])
def test_a_swing_beyond_the_bench_or_the_training_runs_is_a_warning_not_a_refusal(swing, ranges, warned):
    w, _ = id_ranges.out_of_range({**M, "speed_swing_pct": swing}, "y", ranges)
    assert bool(w) == warned
    if warned:
        assert "swings" in w[0] and "extrapolation" in w[0]


def test_a_third_of_the_features_beyond_the_fences_is_a_warning_whatever_the_training_runs_reach():
    """A training set whose own runs reach 20 of 40 features beyond the fences (``max_outliers``): a recording
    with 14 (a third, rounded up) is warned; 13 is not."""
    X = np.random.default_rng(0).normal(size=(400, 40))
    ref = {**id_ranges.feature_reference(X), "max_outliers": 20}
    for n, warned in ((13, False), (14, True)):
        x = np.median(X[:20], axis=0)
        x[:n] += 100.0
        w, ev = id_ranges.out_of_range(M, "y", RANGES, x, ref, [f"f{i}" for i in range(40)])
        assert ev["feature_distance"]["beyond_far_out_fences"] == n
        assert bool(w) == warned, n


# ------------------------------------------------------------------ intervals and the answer's JSON
def _answer(lo, hi, mid, resolved=True):
    from twin.identification.results import IdentifyResult, JointAnswer

    return IdentifyResult("C", {"none": 0.0, "B": 0.0, "C": 1.0, "BC": 0.0},
                          (JointAnswer("B", False, mid, (lo, hi), np.bool_(resolved)),
                           JointAnswer("C", True, mid, (lo, hi), np.bool_(resolved))))


SEEN = {"B": {"min": 0.0125, "max": 1.6, "distinct": 100, "ball_bearing": True}, "C": [0.0, 0.02, 0.1, 1.0]}


def _model(ranges):
    return SimpleNamespace(trained_on={"clearances_mm": SEEN, "ranges": ranges, "interval": {}},
                           feature_names=[f"f{i}" for i in range(4)])


def test_intervals_never_leave_the_sizes_trained_on_at_each_joint():
    from twin.identification.model import training_check

    a, warned, _ = training_check(_model(None), _answer(0.006, 0.05, 0.01), M, "y", np.zeros((3, 4)))
    assert not warned
    assert a.joint("B").interval_if_faulty_mm == (0.0125, 0.05) and a.joint("B").size_if_faulty_mm == 0.0125
    assert a.joint("C").interval_if_faulty_mm == (0.02, 0.05) and a.joint("C").size_if_faulty_mm == 0.02
    a, _, _ = training_check(_model(None), _answer(0.5, 3.0, 1.2), M, "y", np.zeros((3, 4)))
    assert a.joint("B").interval_if_faulty_mm == (0.5, 1.6) and a.joint("C").interval_if_faulty_mm == (0.5, 1.0)


def test_widened_intervals_end_at_the_trained_hull_of_each_joint_whatever_the_answer():
    from twin.identification.model import training_check

    ranges = {**RANGES, "orientations": ["y"]}  # an x-vertical recording is outside
    got = set()
    for lo, hi, mid in ((0.006, 0.05, 0.01), (0.5, 3.0, 1.2), (0.1, 0.2, 0.15)):
        a, warned, checks = training_check(_model(ranges), _answer(lo, hi, mid), M, "x", np.zeros((3, 4)))
        assert warned and checks["outside_training_data"]
        got.add((a.joint("B").interval_if_faulty_mm, a.joint("C").interval_if_faulty_mm))
    assert got == {((0.0125, 1.6), (0.02, 1.0))}


def test_size_resolved_is_a_json_boolean_and_an_answer_says_it_was_not_refused():
    d = json.loads(_answer(0.1, 0.2, 0.15).to_json())
    assert d["clearance_b_size_resolved"] is True and d["clearance_c_size_resolved"] is True
    assert d["refused"] is False
    d = json.loads(_answer(0.1, 0.2, 0.15, resolved=False).to_json())
    assert d["clearance_c_size_resolved"] is False


# ------------------------------------------------------------------ the command
def _short_recording(path: Path) -> Path:
    import twin

    twin.record(twin.preset(6).replace(**{"simulation.duration_s": 0.05}), path)
    return path


def test_a_refused_recording_writes_its_json_record_atomically_and_exits_2(tmp_path, capsys):
    """0.05 s of test 6: too little motion. The --json file (an earlier answer there) is replaced by the
    refusal's record; the exit status stays 2, the message one line."""
    from twin.cli import main

    rec = _short_recording(tmp_path / "short.mcap")
    js = tmp_path / "a.json"
    js.write_text('{"fault": "C"}\n')
    rc = main(["identify", "clearance", str(rec), "--json", str(js)])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "too little motion" in err
    d = json.loads(js.read_text())
    assert d["refused"] is True and "too little motion" in d["reason"] and d["recording"] == str(rec)
    from twin.identification.results import IdentifyResult

    with pytest.raises(ValueError, match="refused, no answer"):
        IdentifyResult.from_json(js.read_text())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json", "short.mcap"]  # no temporary file left


def test_a_twin_simulate_file_is_refused_in_one_line_naming_twin_record(tmp_path, capsys):
    """A run file of twin simulate holds the engine's signals, not the sensor chain's, DAQ's and calibration's
    the model was trained through: refused, saying how to make a recording of it."""
    from twin.cli import main

    run = tmp_path / "run.mcap"
    assert main(["simulate", "--test", "6", "--duration", "0.02", "--out", str(run), "--no-progress"]) == 0
    capsys.readouterr()
    js = tmp_path / "a.json"
    rc = main(["identify", "clearance", str(run), "--json", str(js)])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "twin simulate" in err and "'twin record'" in err
    assert json.loads(js.read_text())["refused"] is True


@pytest.mark.parametrize("name", ["export.npz", "sample:no-such-sample"])
def test_a_file_that_is_not_a_recording_is_refused_in_the_json_too(tmp_path, capsys, name):
    """Every refusal of the recording argument writes the --json record, as a recording refused for its
    content does (a pipeline reads the file, not the message): another file type, an unknown sample."""
    from twin.cli import main

    if not name.startswith("sample:"):
        (tmp_path / name).write_bytes(b"PK not a recording")
        name = str(tmp_path / name)
    js = tmp_path / "a.json"
    rc = main(["identify", "clearance", name, "--json", str(js)])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1
    d = json.loads(js.read_text())
    assert d["refused"] is True and d["recording"] == name and d["reason"] in err


# ------------------------------------------------------------------ the dataset generator's recordings
def test_the_dataset_generator_writes_the_bench_recording_twin_record_writes(tmp_path):
    """outputs.recordings: each run also a bench recording, through twin.record's code path: sample for sample
    the recording twin.record makes of the run's configuration, and the same encoder counts as the dataset's
    column."""
    import twin
    from twin.dataset.generate import generate
    from twin.dataset import open as open_dataset
    from twin.dataset.spec import parse_spec
    from twin.recording import read_recording

    spec = parse_spec({"dataset": {"name": "r", "seed": 5}, "base": {"test": 6, "duration_s": 0.05},
                       "design": {"kind": "grid"}, "factors": {"motor_rpm": [500.0]},
                       "outputs": {"truth": [], "instrumented": ["counts", "calibrated"], "recordings": True},
                       "splits": {"train": 1.0, "val": 0.0, "test": 0.0}})
    assert "recordings" in spec.canonical()["outputs"]
    info = generate(spec, tmp_path / "ds", workers=1, progress=False)
    assert info["files"]["recordings"] == "recordings/<run_id>.mcap"
    ds = open_dataset(tmp_path / "ds")
    (row,) = ds.rows()
    rec_path = tmp_path / "ds" / "recordings" / f"{row['run_id']}.mcap"
    daq, rinfo, _ = read_recording(rec_path)
    assert rinfo.created_by == "twin dataset generate"
    np.testing.assert_array_equal(daq["encoder_counts"], ds.read(row["run_id"], ["encoder_counts"])["encoder_counts"])
    ref = twin.record(daq.config, tmp_path / "ref.mcap")
    ref_daq, ref_info, _ = read_recording(ref.path)
    for name in ref_daq.channels:
        np.testing.assert_array_equal(daq[name], ref_daq[name], err_msg=name)
    assert rinfo.calibration.to_dict() == ref_info.calibration.to_dict()
    # what the identification reads from the recording is what it reads from the dataset's columns (float32)
    from twin.identification.inputs import recording_inputs

    acc, counts, *_ = recording_inputs(rec_path)
    cols = ds.read(row["run_id"], [f"meas_AC{i}" for i in range(1, 7)])
    for i in range(1, 7):
        np.testing.assert_array_equal(acc[f"AC{i}"].astype(np.float32), cols[f"meas_AC{i}"], err_msg=f"AC{i}")


def test_a_spec_without_recordings_keeps_its_identity():
    from twin.dataset.spec import parse_spec

    d = {"dataset": {"name": "r", "seed": 5}, "base": {"test": 6, "duration_s": 0.05}}
    assert "recordings" not in parse_spec(d).canonical()["outputs"]
    with pytest.raises(Exception, match="outputs.recordings: must be true or false"):
        parse_spec({**d, "outputs": {"recordings": "yes"}})
