"""The crank's direction of rotation against the identification model's training runs: a crank turned backwards
is answered as outside the training data (a warning, the intervals widened to every clearance trained), since the
window features read the crank rate as a magnitude and the shipped models were trained turning forwards only.

Independent basis: encoder traces of known direction (the counts of a closed-form crank angle, increasing or
decreasing); the shipped models' training specs (``analysis/datasets``) read for their motor speeds' sign.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from twin.identification import ranges as id_ranges
from twin.identification.rotation import FORWARD, REVERSE, rotation, trained_rotations

ROOT = Path(__file__).resolve().parents[1]
RATE = 100_000.0
CPR = 32768.0
RANGES = {"source": "test", "runs": 3, "crank_hz": [2.0, 2.5], "ripple_pct": [[0.0, 0.01]] * 4,
          "noise_ug_rthz": [29.0, 31.0], "orientations": ["y"]}


def _counts(sign: float) -> np.ndarray:
    t = np.arange(int(RATE * 1.5)) / RATE
    return np.floor(sign * 2 * math.pi * 2.2 * t / (2 * math.pi) * CPR)


@pytest.mark.parametrize("sign, want", [(1.0, FORWARD), (-1.0, REVERSE)])
def test_the_direction_reads_from_the_encoder_counts(sign, want):
    from twin.identification.features import steady_windows

    counts = _counts(sign)
    w = steady_windows(counts, RATE, CPR)
    acc = {f"AC{i}": np.zeros(counts.size) for i in range(1, 7)}
    assert id_ranges.recording_measures(acc, counts, RATE, CPR, w)["rotation"] == want
    assert rotation(counts, 0, counts.size) == want


@pytest.mark.parametrize("trained, measured, warned", [
    (None, FORWARD, False), (None, REVERSE, True),  # a model storing no direction: read as trained forwards
    (["forward"], REVERSE, True), (["reverse"], FORWARD, True), (["forward", "reverse"], REVERSE, False),
    (["forward"], None, False),  # not measured (an older answer's measures): nothing claimed
])
def test_a_direction_no_training_run_turned_is_outside_the_training_data(trained, measured, warned):
    ranges = dict(RANGES, **({"rotations": trained} if trained else {}))
    m = {"crank_hz": 2.2, "ripple_pct": [0.0] * 4, "noise_ug_rthz": 30.0, "rotation": measured}
    warnings, _ = id_ranges.out_of_range(m, "y", ranges)
    assert bool(warnings) == warned
    if warned:
        assert len(warnings) == 1 and "extrapolation" in warnings[0] and "crank turns" in warnings[0]


def test_the_training_ranges_store_the_runs_directions_and_nothing_where_unmeasured():
    m = {"crank_hz": 2.2, "ripple_pct": [0.0] * 4, "noise_ug_rthz": 30.0}
    both = id_ranges.training_ranges([dict(m, rotation=FORWARD), dict(m, rotation=REVERSE)], ["y", "y"], "t")
    assert both["rotations"] == ["forward", "reverse"]
    assert trained_rotations(both) == (("forward", "reverse"), True)
    old = id_ranges.training_ranges([m, dict(m, rotation=FORWARD)], ["y", "y"], "t")
    assert "rotations" not in old and trained_rotations(old) == (("forward",), False)


def test_the_shipped_models_training_sets_turn_forwards_as_assumed():
    """The assumption for models that store no direction, checked against the training specs the shipped models
    name (``trained_on.datasets``): every one draws constant, positive motor speeds."""
    from twin.identification.model import ClearanceModel, shipped_model_path

    for name in ("default", "bench"):
        tr = ClearanceModel.load(shipped_model_path(name)).trained_on
        assert "rotations" not in (tr.get("ranges") or {}) or tr["ranges"]["rotations"] == ["forward"]
        for ds in tr["datasets"]:
            spec = (ROOT / "analysis" / "datasets" / (ds["name"].replace("-", "_") + ".toml")).read_text()
            assert re.search(r'^program = "constant"', spec, re.M), ds["name"]
            rpm = re.search(r"^motor_rpm = \[([^\]]*)\]", spec, re.M)
            assert rpm and min(float(v) for v in rpm.group(1).split(",")) > 0, ds["name"]


def test_a_reversed_recording_is_warned_and_its_intervals_widened_to_the_trained_hull():
    """The sample recording of test 6 (0.1 mm at C) and the same with the encoder read backwards: the reversed
    one is outside the training data (warned, the interval at C every clearance trained), the original not for
    its direction."""
    from twin.identification.inputs import recording_inputs
    from twin.identification.model import ClearanceModel, default_model_path, identify_inputs
    from twin.identification.ranges import trained_hull

    model = ClearanceModel.load(default_model_path())
    acc, counts, rate, cpr, cfg = recording_inputs(ROOT / "recordings" / "test6_synthetic.mcap")
    fwd = identify_inputs(model, acc, counts, rate, cpr, orientation="y")
    rev = identify_inputs(model, acc, -counts, rate, cpr, orientation="y")
    assert not any("crank turns" in w for w in fwd.warnings)
    assert sum("crank turns backwards" in w for w in rev.warnings) == 1
    assert rev.evidence.training_data_check.outside_training_data
    assert rev.evidence.training_data_check.measured.rotation == REVERSE
    c = next(j for j in rev.joints if j.joint == "C")
    assert list(c.interval_if_faulty_mm) == list(trained_hull(model.trained_on["clearances_mm"]["C"]))
    # the answer's JSON keeps the direction
    from twin.identification.results import IdentifyResult

    assert IdentifyResult.from_json(rev.to_json()).evidence.training_data_check.measured.rotation == REVERSE
