"""The typed results of identification and replay, and the training options.

The golden dicts in ``tests/golden/`` were captured from the code that returned plain dicts, before the typed
results existed (the identify answers of three sample recordings, the ``seconds`` set to null; the report of the
replay that ``tests/test_replay.py``'s ``ideal`` fixture makes, the recording's path shortened; the ``doe.json`` of
a 4-point DOE as ``tests/test_doe.py``'s spec with 0.015 s runs writes it, the spec's path shortened and the wall
times set to null; the continuous-contact study's JSON for S004 over 0.02 s; the committed
``analysis/results/accuracy/accuracy.json``): ``to_dict()`` must give exactly that dict back, key order included,
and the JSON text must read back to the same value. The answer's ``refused`` (false) and
``evidence.training_data_check.measured.speed_swing_pct`` were added to the identify answers when the answer
gained them, and test3's sizes if faulty (a healthy recording, its answers below the smallest size trained on)
clipped to that size when intervals were held within the trained hull.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from twin.identification.results import Evidence, HeldOut, IdentifyResult, JointAnswer
from twin.replay_result import ReplayResult

ROOT = Path(__file__).resolve().parent.parent
GOLDEN = Path(__file__).resolve().parent / "golden"
IDENTIFY_GOLDEN = json.loads((GOLDEN / "identify_samples.json").read_text())
REPLAY_GOLDEN = json.loads((GOLDEN / "replay_t3.json").read_text())


def _layout(value):
    """The key order at every level of a JSON-like value (lists element by element), without the values."""
    if isinstance(value, dict):
        return [(k, _layout(v)) for k, v in value.items()]
    if isinstance(value, (list, tuple)):
        return [_layout(v) for v in value]
    return None


# ------------------------------------------------------------------ identify
@pytest.mark.parametrize("name", sorted(IDENTIFY_GOLDEN))
def test_an_identify_result_gives_back_the_golden_dict_exactly(name):
    golden = IDENTIFY_GOLDEN[name]
    r = IdentifyResult.from_dict(golden)
    assert r.to_dict() == golden and _layout(r.to_dict()) == _layout(golden)
    assert [j.joint for j in r.joints] == ["B", "C"] and r.fault == golden["fault"]
    for j in r.joints:
        key = f"clearance_{j.joint.lower()}"
        assert j.size_mm == golden[f"{key}_mm"] and list(j.interval_mm) == golden[f"{key}_interval_mm"]
        assert j.size_if_faulty_mm == golden[f"{key}_if_faulty_mm"]["median"]
    # JSON round trip: the text reads back to an equal value, and writing that value again gives the same text
    text = r.to_json()
    back = IdentifyResult.from_json(text)
    assert back == r and back.to_json() == text and json.loads(text) == golden


@pytest.mark.parametrize("name", sorted(IDENTIFY_GOLDEN))
def test_the_evidence_reads_into_typed_frozen_values(name):
    """The training-data check and the model's description are frozen dataclasses (no dicts left in the
    evidence); the old read access by key still gives the dict's values; an unknown key is refused, not lost."""
    from twin.identification.results import FeatureDistance, ModelInfo, RecordingMeasures, TrainingDataCheck

    golden = IDENTIFY_GOLDEN[name]["evidence"]
    ev = Evidence.from_dict(golden)
    check, model = ev.training_data_check, ev.model
    assert isinstance(check, TrainingDataCheck) and isinstance(check.measured, RecordingMeasures)
    assert isinstance(check.feature_distance, FeatureDistance) and isinstance(model, ModelInfo)
    assert check.measured.ripple_pct == tuple(golden["training_data_check"]["measured"]["ripple_pct"])
    assert model.crank_hz_range == tuple(golden["model"]["crank_hz_range"])
    assert model.dataset == golden["model"]["dataset"]
    assert check.feature_distance.of == golden["training_data_check"]["feature_distance"]["of"]
    assert check["measured"]["crank_hz"] == check.measured.crank_hz and "feature_distance" in check
    assert ev.to_dict() == golden and _layout(ev.to_dict()) == _layout(golden)
    with pytest.raises(dataclasses.FrozenInstanceError):
        check.outside_training_data = True
    with pytest.raises(ValueError, match="'extra'"):
        TrainingDataCheck.from_dict({**golden["training_data_check"], "extra": 1})
    # a model without training ranges: the reason in place of the distance, and no swing measured
    bare = {"measured": {"crank_hz": 3.0, "ripple_pct": [1.0], "noise_ug_rthz": None},
            "ranges": "unavailable (the model stores no training ranges)", "outside_training_data": False,
            "interval_rule": "r"}
    c = TrainingDataCheck.from_dict(bare)
    assert c.feature_distance is None and c.measured.speed_swing_pct is None
    assert c.to_dict() == bare and list(c.to_dict()) == list(bare)


@pytest.mark.parametrize("name", sorted(IDENTIFY_GOLDEN))
def test_the_answer_of_a_sample_has_the_golden_layout_and_values(name):
    """The answer made now has the golden dict's keys in its order at every level; its values equal the golden
    ones to 1e-9 (a regression guard: the golden values are this code's own earlier output)."""
    import twin

    a = twin.identify(twin.samples.path(name))
    assert isinstance(a, IdentifyResult) and isinstance(a.seconds, float) and a.seconds >= 0
    d = json.loads(a.to_json())
    d["seconds"] = None
    assert Path(d["recording"]).name == f"{name}_synthetic.mcap"
    d["recording"] = IDENTIFY_GOLDEN[name]["recording"]
    assert _layout(d) == _layout(IDENTIFY_GOLDEN[name])
    assert _close(d, IDENTIFY_GOLDEN[name])


def _close(a, b) -> bool:
    """Equal, floats to a relative 1e-9, at every level."""
    if isinstance(a, dict):
        return isinstance(b, dict) and list(a) == list(b) and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, (int, float)):
        return a == pytest.approx(b, rel=1e-9, abs=1e-300)
    return a == b


def test_the_json_file_of_the_command_is_the_results_json(tmp_path):
    """``twin identify clearance --json`` writes ``to_json()``: the file reads back to a result that writes the
    same bytes again."""
    from twin.cli import main

    js = tmp_path / "a.json"
    assert main(["identify", "clearance", str(ROOT / "recordings" / "test6_synthetic.mcap"), "--json", str(js)]) == 0
    text = js.read_text()
    r = IdentifyResult.from_json(text)
    assert r.to_json() + "\n" == text and r.fault == "C" and r.evidence.windows >= 1


def test_a_joint_located_healthy_reports_no_size_and_the_joints_are_found_by_name():
    held = HeldOut(1.5, 0.8, 120, (3.0, 3.2))
    b = JointAnswer("B", False, 0.03, (0.02, 0.05), size_resolved=True, size_held_out=held)
    c = JointAnswer("C", True, 0.1, (0.08, 0.13), size_resolved=False)
    assert (b.size_mm, b.interval_mm) == (0.0, (0.0, 0.0)) and (c.size_mm, c.interval_mm) == (0.1, (0.08, 0.13))
    from twin.identification.results import ModelInfo, RecordingMeasures, TrainingDataCheck

    check = TrainingDataCheck(RecordingMeasures(3.1, (1.0, 2.0), 30.0), False, "inside")
    ev = Evidence(1, 2.0, 3.1, 740.0, 0.7, 178, "v", check, ModelInfo("d", "0" * 64, "mujoco", (3.0, 3.2)))
    assert Evidence(1, 2.0, 3.1, 740.0, 0.7, 178, "v", check.to_dict(), ev.model.to_dict()) == ev  # dicts read in
    with pytest.raises(ValueError, match="missing"):
        Evidence(1, 2.0, 3.1, 740.0, 0.7, 178, "v", {"outside_training_data": False}, ev.model)
    r = IdentifyResult("C", {"none": 0.1, "B": 0.0, "C": 0.9, "BC": 0.0}, (b, c), "rec.mcap", ("w",), ev, 0.5)
    d = r.to_dict()
    assert d["clearance_b_mm"] == 0.0 and d["clearance_b_if_faulty_mm"] == {"median": 0.03, "interval_90": [0.02, 0.05]}
    assert d["clearance_b_size_held_out"] == {"within_factor": 1.5, "share": 0.8, "runs": 120,
                                              "training_crank_hz": [3.0, 3.2]}
    assert d["clearance_c_size_held_out"] is None and d["clearance_c_interval_mm"] == [0.08, 0.13]
    assert IdentifyResult.from_dict(d) == r and r.joint("C") is c
    with pytest.raises(KeyError, match="'G': no such clearance location; the answer has B, C"):
        r.joint("G")
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.fault = "B"


def test_a_further_location_adds_its_keys_after_the_others():
    """The joints are a tuple: a third location (a guide, say "G") adds its keys in the same pattern, after B's
    and C's, and reads back."""
    joints = tuple(JointAnswer(j, j == "G", 0.1, (0.05, 0.2)) for j in ("B", "C", "G"))
    r = IdentifyResult("G", {"none": 0.0, "G": 1.0}, joints)
    d = r.to_dict()
    keys = [k for k in d if k.startswith("clearance_")]
    assert keys[:9] == [f"clearance_{j}_{s}" for j in "bcg" for s in ("mm", "interval_mm", "if_faulty_mm")]
    assert keys[9:] == [f"clearance_{j}_{s}" for j in "bcg" for s in ("size_resolved", "size_held_out")]
    assert d["clearance_g_mm"] == 0.1 and d["clearance_b_mm"] == 0.0
    assert IdentifyResult.from_dict(d) == r


# ------------------------------------------------------------------ replay
def test_a_replay_result_gives_back_the_golden_report_exactly():
    r = ReplayResult.from_dict(REPLAY_GOLDEN)
    assert r.to_dict() == REPLAY_GOLDEN and _layout(r.to_dict()) == _layout(REPLAY_GOLDEN)
    assert r.configuration.name == "test3" and r.tracking.count_rad == REPLAY_GOLDEN["tracking"]["count_rad"]
    assert r.window_s == tuple(REPLAY_GOLDEN["window_s"]) and r.plots is None and r.motor_drive is None
    text = r.to_json()
    assert ReplayResult.from_json(text) == r and json.loads(text) == REPLAY_GOLDEN


def test_a_replay_results_dict_is_a_copy_and_optional_sections_appear_when_present():
    r = ReplayResult.from_dict(REPLAY_GOLDEN)
    d = r.to_dict()
    d["sensors"]["AC1"]["nrmse_pct"] = -1.0
    d["files"]["mcap"] = "x"
    assert r.to_dict() == REPLAY_GOLDEN  # the result is unchanged
    with_plots = dict(REPLAY_GOLDEN, plots={"tracking.png": "crank rate"})
    with_plots["wall_s"] = with_plots.pop("wall_s")  # the report's order: plots before wall_s
    assert list(ReplayResult.from_dict(with_plots).to_dict()) == list(with_plots)
    with pytest.raises(TypeError, match="unknown key.*nonsense"):
        ReplayResult.from_dict(dict(REPLAY_GOLDEN, nonsense=1))
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.crank_rate_hz = 0.0


def test_the_replay_rows_are_typed_and_give_back_their_part_of_the_golden_report():
    """Each accelerometer's comparison is a frozen :class:`SensorComparison` (bands :class:`BandComparison`), read
    by attribute; its ``to_dict()`` is that sensor's part of the golden report, key order included."""
    from twin.replay_result import BandComparison, SensorComparison

    r = ReplayResult.from_dict(REPLAY_GOLDEN)
    for a, m in r.sensors.items():
        gold = REPLAY_GOLDEN["sensors"][a]
        assert isinstance(m, SensorComparison) and all(isinstance(b, BandComparison) for b in m.bands)
        assert m.to_dict() == gold and _layout(m.to_dict()) == _layout(gold)
        assert m.nrmse_pct == gold["nrmse_pct"] and m.bands[0].difference_db == gold["bands"][0]["difference_db"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.sensors["AC1"].nrmse_pct = 0.0
    with pytest.raises(KeyError, match="sensor comparison: missing key.*nrmse_pct"):
        SensorComparison.from_dict({k: v for k, v in REPLAY_GOLDEN["sensors"]["AC1"].items() if k != "nrmse_pct"})


def test_the_motor_drive_comparison_gives_back_its_dict():
    """The motor-drive section (the layout :func:`twin.bench_replay._motor_drive` writes) reads into a
    :class:`MotorDriveComparison` and back to the same dict, key order included."""
    from twin.replay_result import MotorDriveComparison, MotorDriveSensor

    row = {"nrmse_pct": 1.2, "correlation": 0.99, "dtw_distance_pct": 0.4, "simulated_rms_mps2": 30.0,
           "simulated_peak_mps2": 44.0, "pid_nrmse_pct": 0.2, "pid_correlation": 0.999, "pid_dtw_distance_pct": 0.1}
    md = {"note": "motor", "tracking": {"sim_vs_recorded_max_counts": 3.0, "sim_vs_recorded_rms_counts": 1.0,
                                        "pid_sim_vs_recorded_max_counts": 0.5},
          "crank_speed_ripple_pct": 2.5, "sensors": {"AC1": row, "AC4": dict(row, nrmse_pct=2.0)},
          "simulation": {"wall_s": 1.0, "engine": "reference", "steps": 100, "real_time_factor": 0.1}}
    m = MotorDriveComparison.from_dict(md)
    assert isinstance(m.sensors["AC4"], MotorDriveSensor) and m.sensors["AC4"].nrmse_pct == 2.0
    assert m.to_dict() == md and _layout(m.to_dict()) == _layout(md)
    report = dict(REPLAY_GOLDEN, motor_drive=md)
    report["wall_s"] = report.pop("wall_s")
    back = ReplayResult.from_dict(report)
    assert back.motor_drive == m and back.to_dict() == report


# ------------------------------------------------------------------ DOE
def test_a_doe_result_gives_back_the_golden_doe_json_with_typed_rows():
    from twin.studies.doe import DoeCheck, DoePoint, DoeResponse, DoeResult

    golden = json.loads((GOLDEN / "doe_small.json").read_text())
    r = DoeResult.from_dict(golden)
    assert r.to_dict() == golden and _layout(r.to_dict()) == _layout(golden)
    assert all(type(p) is DoePoint for p in r.points) and all(isinstance(c, DoeCheck) for c in r.checks)
    assert [c.kind for c in r.checks] == [c["kind"] for c in golden["checks"]] and r.checks[0].kind == "holdout"
    for name, s in r.responses.items():
        assert isinstance(s, DoeResponse) and s.loo_stats == golden["responses"][name]["loo_stats"]
        assert s.optimum["factors"] == golden["responses"][name]["optimum"]["factors"]
        assert len(s.loo) == len(r.points)
    assert r.checks[0].predicted["max_slider_accel"]["mean"] == golden["checks"][0]["predicted"]["max_slider_accel"]["mean"]
    d = r.to_dict()
    d["checks"][0]["factors"]["x"] = 1.0
    d["responses"]["max_slider_accel"]["loo"][0] = -1.0
    assert r.to_dict() == golden  # a copy: the result is unchanged
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.checks[0].kind = "optimum"


# ------------------------------------------------------------------ studies' summaries
def test_an_accuracy_result_gives_back_the_committed_accuracy_json_with_typed_rows():
    """The committed ``accuracy.json`` (written from plain dicts before the typed rows) reads into an
    :class:`AccuracyResult` whose summary rows are :class:`VariantSummary` values and back to the same dict."""
    from twin.studies.accuracy import AccuracyResult, VariantSummary

    golden = json.loads((ROOT / "analysis" / "results" / "accuracy" / "accuracy.json").read_text())
    golden.pop("provenance", None)  # a stamp, if the file is ever rebuilt, is the file's, not the result's
    r = AccuracyResult.from_dict(golden)
    assert r.to_dict() == golden and _layout(r.to_dict()) == _layout(golden)
    assert all(isinstance(v, VariantSummary) for v in r.summary) and len(r.summary) == len(golden["summary"])
    default = next(v for v in r.summary if v.key == r.default)
    assert default.pareto == r.default_on_pareto_front and default.engine == "mujoco"
    assert all(v.pareto is None for v in r.summary if v.engine == "reference")
    with pytest.raises(dataclasses.FrozenInstanceError):
        default.score = 0.0


def test_the_continuous_contact_summary_gives_back_the_golden_json():
    """``tests/golden/continuous_contact_s004_0.02s.json``: the file the dict code wrote for S004 over 0.02 s."""
    from twin.studies.continuous_contact import ContinuousContactSummary

    golden = json.loads((GOLDEN / "continuous_contact_s004_0.02s.json").read_text())
    sm = ContinuousContactSummary.from_dict(golden)
    assert sm.to_dict() == golden and list(sm.to_dict()) == list(golden)
    assert sm.valid_until_crank_deg == golden["valid_until_crank_deg"] and sm.clearance_radial_m == 0.0005


# ------------------------------------------------------------------ training options
def test_train_options_defaults_are_what_train_has_always_used():
    from twin.identification.intervals import CATALOGUE_BANDS_MM, FAULT_SPLIT_JOINTS
    from twin.identification.training import ANSWER_HOP_REVS, TrainOptions

    o = TrainOptions()
    assert (o.splits, o.workers, o.seed, o.interval_folds, o.size_regressor) == (("train", "val"), 1, 0, "runs", "mean")
    assert o.size_band_mm == CATALOGUE_BANDS_MM and o.fault_split == FAULT_SPLIT_JOINTS == ("C",)
    assert o.answer_hop_revs == ANSWER_HOP_REVS and o.ripple_split and o.interval_by_engine and not o.by_windows
    assert not o.normalized_intervals and o.location_only == () and o.size_only_at == {}
    # lists become tuples, True both joints, a single split string one split
    o = TrainOptions(splits="train", location_only=["a"], size_only_at={"B": ["b"]}, fault_split=True,
                     size_band_mm=[0.1, 0.5])
    assert (o.splits, o.location_only, o.size_only_at, o.fault_split, o.size_band_mm) == \
        (("train",), ("a",), {"B": ("b",)}, ("B", "C"), (0.1, 0.5))
    with pytest.raises(dataclasses.FrozenInstanceError):
        o.seed = 1


@pytest.mark.parametrize("field, value", [
    ("splits", ("train", "dev")), ("splits", ()), ("workers", 0), ("workers", 1.5), ("workers", True), ("seed", -1),
    ("interval_folds", "rpm"), ("size_regressor", "forest"), ("answer_hop_revs", 0.0), ("answer_hop_revs", 5.0),
    ("fault_split", ["A"]), ("fault_split", "C"), ("size_only_at", {"A": ["x"]}), ("size_only_at", ["B"]),
    ("size_band_mm", -0.1), ("size_band_mm", [0.1, float("nan")]), ("ripple_split", 1), ("by_windows", None),
])
def test_a_bad_train_option_is_refused_naming_its_field(field, value):
    from twin.errors import ConfigError
    from twin.identification.training import TrainOptions, TrainOptionsError
    from twin.identification.trees import ModelError

    with pytest.raises(TrainOptionsError) as err:
        TrainOptions(**{field: value})
    assert err.value.field == field and str(err.value).startswith(f"{field}: ") and "\n" not in str(err.value)
    assert isinstance(err.value, ConfigError) and isinstance(err.value, ModelError)


def test_train_takes_its_options_as_one_value():
    from twin.identification.training import train

    with pytest.raises(TypeError, match="options: must be a TrainOptions, got dict"):
        train("nowhere", {"seed": 1})
    with pytest.raises(TypeError):
        train("nowhere", interval_folds="speed")  # the options are no keyword arguments of train()


def test_train_makes_the_tables_by_windows_when_asked_and_not_by_default(tmp_path):
    """``by_windows``: synthetic features (two windows per run, the first column log10 of B's clearance, the second
    C's): asked for, the model holds the half widths of answers from one window, calibrated on the out-of-fold runs'
    first windows (equal to :func:`half_widths_by_windows` on the out-of-fold answers it hands out); by default the
    table is empty, as ``train`` has always written it."""
    import math
    from types import SimpleNamespace

    import numpy as np

    from twin.identification.features import feature_names
    from twin.identification.intervals import half_widths_by_windows
    from twin.identification.training import TrainOptions, train

    rng = np.random.default_rng(5)
    nf = len(feature_names())
    rows, owner, X = [], [], []
    for i in range(160):
        fault = ("B", "C", "BC", "none")[i % 4]
        size = {j: (10 ** rng.uniform(-1.7, -0.3) if j in fault else 0.0) for j in "BC"}
        rpm = (400.0, 550.0, 700.0, 750.0)[(i // 4) % 4]
        rows.append({"fault": fault, "clearance_b_mm": size["B"], "clearance_c_mm": size["C"], "dataset": "s",
                     "orientation": "z", "crank_hz": rpm / 60 / 3.97, "motor_rpm": rpm, "engine": "reference",
                     "measures": {"crank_hz": rpm / 60 / 3.97, "ripple_pct": [1.0, 0.5, 0.2, 0.0], "noise_ug_rthz": 30.0}})
        for _ in range(2):
            x = rng.normal(size=nf)
            x[:2] = [math.log10(size[j]) + rng.normal(0, 0.05) if size[j] else -3.0 for j in "BC"]
            X.append(x)
            owner.append(i)
    ds = SimpleNamespace(info={"name": "s", "identity": {"engine": "reference"}}, rate_hz=100000.0, path=tmp_path)
    opts = dict(interval_folds="speed", size_regressor="median")
    oof: dict = {}
    m, info = train([tmp_path], TrainOptions(**opts, by_windows=True), features=(np.array(X), rows, owner, [], [ds]),
                    out_of_fold=oof)
    table = info["interval"]["half_width_log10_by_windows"]
    assert list(table) == ["1"]
    for j in "BC":
        again = half_widths_by_windows(j, oof[j]["window_logs"], oof[j]["runs"], m.trained_on["interval"]["size_band_mm"],
                                        True, True, j == "C")
        assert again["1"] == {k: v for k, v in table["1"].items() if k[0] == j}
    _, plain = train([tmp_path], TrainOptions(**opts), features=(np.array(X), rows, owner, [], [ds]))
    assert plain["interval"]["half_width_log10_by_windows"] == {}
    assert plain["interval"]["half_width_log10"] == info["interval"]["half_width_log10"]


@pytest.mark.parametrize("pattern, cls_path", [
    ("**/taguchi.json", "twin.studies.taguchi:TaguchiResult"),
    ("**/mcdm.json", "twin.studies.mcdm:McdmResult"),
    ("**/stability.json", "twin.studies.stability:StabilityResult"),
    ("**/formulations.json", "twin.studies.formulations:FormulationsResult")])
def test_the_committed_study_files_read_into_typed_summaries_and_back_exactly(pattern, cls_path):
    """Every committed ``taguchi.json``, ``mcdm.json``, ``stability.json`` and ``formulations.json`` (written from
    plain dicts, before the typed summaries) reads into its result, whose nested summaries are frozen dataclasses,
    and back to the same data, key order included; the file's provenance stamp is the file's, dropped first."""
    import importlib

    from twin.typed import Record

    mod, name = cls_path.split(":")
    cls = getattr(importlib.import_module(mod), name)
    files = sorted((ROOT / "analysis" / "results").glob(pattern))
    assert files, pattern
    for f in files:
        golden = json.loads(f.read_text())
        assert "provenance" in golden, f"{f}: not stamped"
        r = cls.from_dict(golden)  # the stamp ignored
        golden.pop("provenance")
        assert r.to_dict() == golden and _layout(r.to_dict()) == _layout(golden), f
        nested = {"TaguchiResult": lambda: next(iter(r.responses.values())).raw.prediction,
                  "McdmResult": lambda: r.methods["waspas"].paper_variant,
                  "StabilityResult": lambda: r.summary.pen_over_c,
                  "FormulationsResult": lambda: r.rows[0]}[name]()
        assert isinstance(nested, Record)
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(nested, dataclasses.fields(nested)[0].name, None)


def test_a_calibration_result_holds_typed_rows_and_writes_the_same_dict(tmp_path):
    """The correlated pairs and the evaluation times (dicts as the search gives them) are frozen dataclasses in
    :class:`twin.calibration.CalibrationResult`; ``to_dict()`` writes the dicts they were, key for key."""
    from twin.calibration import CalibrationResult, FittedParameter
    from twin.calibration.rows import CorrelatedPair, EvaluationTimes

    pairs = [{"a": "contact.mu0", "b": "contact.restitution", "correlation": 0.97}]
    times = {"short": 0.5, "full": 2.0}
    fp = FittedParameter("contact.mu0", 0.1, 0.08, 0.12, 0.05, (0.0, 0.3), "slice", False, "")
    r = CalibrationResult((fp,), 3.0, 1.0, [{"band": 1.0}], [{"band": 0.5}], {"band": 1.0}, "note", pairs, [], 10,
                          8, 2, times, 12.0, tmp_path)
    assert r.correlated_pairs == (CorrelatedPair("contact.mu0", "contact.restitution", 0.97),)
    assert r.seconds_per_evaluation == EvaluationTimes(0.5, 2.0) and r.seconds_per_evaluation["full"] == 2.0
    d = r.to_dict()
    assert d["correlated_pairs"] == pairs and d["seconds_per_evaluation"] == times
    assert list(d["seconds_per_evaluation"]) == ["short", "full"] and json.loads(json.dumps(d)) == d
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.correlated_pairs[0].correlation = 0.0
    with pytest.raises(ValueError, match="'stage'"):
        EvaluationTimes.from_dict({"short": 1.0, "full": 2.0, "stage": "x"})
