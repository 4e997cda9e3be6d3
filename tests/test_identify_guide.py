"""The slider guide G as a clearance location of the identification: dataset labels and fault classes, the model
file with a G size regressor (format 5) and the format before it (4, B and C only), and the shipped model on
simulated runs with guide play only and with no play."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from twin.identification.features import feature_names
from twin.identification.model import CLASSES, MODEL_FORMAT, ClearanceModel, ModelError, label_mm
from twin.identification.ranges import feature_reference
from twin.identification.results import IdentifyResult

ROOT = Path(__file__).resolve().parent.parent
DEFAULT = ROOT / "twin" / "data" / "identify_default.npz"
RANGES = {"source": "random", "runs": 160, "crank_hz": [1.0, 3.0], "ripple_pct": [[0.0, 0.5]],
          "noise_ug_rthz": [28.0, 33.0], "orientations": ["y", "z"]}


def test_a_run_with_guide_play_is_labelled_with_G_and_its_play():
    from twin.config import preset
    from twin.dataset.factors import NAMED, labels

    base = preset(1)
    assert "clearance_guide_mm" not in labels(base) and labels(base)["fault"] == "none"
    g = labels(base.replace(**{"joints.clearance_guide_mm": 0.15}))
    assert g["fault"] == "G" and g["clearance_guide_mm"] == 0.15
    bg = labels(base.replace(**{"joints.clearance_guide_mm": 0.15, "joints.clearance_b_mm": 0.1}))
    assert bg["fault"] == "BG"
    # the fault factor: a location it names keeps the size given it (else 0.1 mm), one it leaves out gets 0
    ov: dict = {"joints.clearance_guide_mm": 0.3}
    NAMED["fault"].apply("CG", ov, np.random.default_rng(0), base)
    assert ov["joints.clearance_guide_mm"] == 0.3 and ov["joints.clearance_c_mm"] == 0.1 and \
        ov["joints.clearance_b_mm"] == 0.0
    ov = {"joints.clearance_guide_mm": 0.3}
    NAMED["fault"].apply("B", ov, np.random.default_rng(0), base)
    assert ov["joints.clearance_guide_mm"] == 0.0
    assert label_mm({"clearance_guide_mm": float("nan")}, "G") == 0.0 and label_mm({}, "G") == 0.0


def _small(joints: tuple[str, ...]) -> ClearanceModel:
    """A model of tiny trees on this twin's features over ``joints`` (random data: its answers mean nothing)."""
    from sklearn.ensemble import HistGradientBoostingClassifier as C
    from sklearn.ensemble import HistGradientBoostingRegressor as R

    nf = len(feature_names())
    X = np.random.default_rng(1).standard_normal((240, nf))
    classes = [c for c in CLASSES if c == "none" or set(c) <= set(joints)]
    y = np.array(classes)[np.arange(len(X)) % len(classes)]
    clf = C(max_iter=3, max_leaf_nodes=4, random_state=0).fit(X, y)
    reg = R(max_iter=3, max_leaf_nodes=4).fit(X, X[:, 2] - 1)
    seen = {j: {"min": 0.0125, "max": 0.4 if j == "G" else 1.6, "distinct": 50, "ball_bearing": True} for j in joints}
    return ClearanceModel(clf, {j: reg for j in joints}, {j: 0.2 for j in joints},
                          trained_on={"rate_hz": 100000.0, "crank_hz_range": [1.0, 3.0], "dataset": "random",
                                      "ranges": RANGES, "feature_reference": feature_reference(X),
                                      "clearances_mm": seen})


def test_a_model_with_the_guide_saves_and_loads_back_with_its_G_answer(tmp_path):
    m = _small(("B", "C", "G"))
    p = m.save(tmp_path / "g.npz")
    meta = json.loads(str(np.load(p)["model.json"][()]))
    assert meta["format"] == MODEL_FORMAT == "twin-identify-model/5" and meta["joints"] == ["B", "C", "G"]
    back = ClearanceModel.load(p)
    assert back.joints == ("B", "C", "G") and back.classes == CLASSES
    X = np.random.default_rng(2).standard_normal((4, len(feature_names())))
    a, b = m.identify(X, {"B": True, "C": True}), back.identify(X, {"B": True, "C": True})
    assert a == b and [j.joint for j in b.joints] == ["B", "C", "G"] and set(b.probabilities) == set(CLASSES)
    g = b.joint("G")
    assert 0 < g.interval_if_faulty_mm[0] < g.size_if_faulty_mm < g.interval_if_faulty_mm[1]
    d = b.to_dict()
    assert {"clearance_g_mm", "clearance_g_interval_mm", "clearance_g_if_faulty_mm"} <= set(d)
    assert IdentifyResult.from_json(b.to_json()) == b


def test_a_model_of_B_and_C_only_answers_the_four_classes_and_a_format_4_file_still_loads(tmp_path):
    from twin.identification.modelfile import write_model
    from twin.identification.trees import from_sklearn

    m = _small(("B", "C"))
    p = m.save(tmp_path / "bc.npz")
    back = ClearanceModel.load(p)
    assert back.joints == ("B", "C") and back.classes == ("none", "B", "C", "BC")
    # a format-4 file: the same members, no joints list (as models were before the guide was a location)
    meta = json.loads(str(np.load(p)["model.json"][()]))
    meta["format"] = "twin-identify-model/4"
    del meta["joints"]
    est = {"classifier": from_sklearn(m.classifier), "size_B": from_sklearn(m.size["B"]),
           "size_C": from_sklearn(m.size["C"])}
    old = write_model(tmp_path / "old.npz", meta, est)
    four = ClearanceModel.load(old)
    X = np.random.default_rng(3).standard_normal((3, len(feature_names())))
    assert four.joints == ("B", "C") and four.identify(X, {"B": True, "C": True}) == back.identify(X, {"B": True,
                                                                                                        "C": True})


@pytest.mark.parametrize("joints", [["G"], ["B", "C", "G", "G"], ["B", "C", "D"], "BCG"])
def test_a_model_file_listing_other_joints_is_refused_in_one_line(tmp_path, joints):
    from twin.identification.modelfile import write_model
    from twin.identification.trees import from_sklearn

    m = _small(("B", "C", "G"))
    p = m.save(tmp_path / "g.npz")
    meta = json.loads(str(np.load(p)["model.json"][()]))
    meta["joints"] = joints
    est = {"classifier": from_sklearn(m.classifier)} | {f"size_{j}": from_sklearn(m.size[j]) for j in "BCG"}
    bad = write_model(tmp_path / "bad.npz", meta, est)
    with pytest.raises(ModelError) as e:
        ClearanceModel.load(bad)
    assert "\n" not in str(e.value) and str(e.value).startswith(f"{bad}: ")


def test_a_format_3_file_is_refused_in_one_line_naming_its_version(tmp_path):
    from twin.identification.modelfile import write_model
    from twin.identification.trees import from_sklearn

    m = _small(("B", "C"))
    p = m.save(tmp_path / "bc.npz")
    meta = json.loads(str(np.load(p)["model.json"][()])) | {"format": "twin-identify-model/3"}
    est = {"classifier": from_sklearn(m.classifier), "size_B": from_sklearn(m.size["B"]),
           "size_C": from_sklearn(m.size["C"])}
    bad = write_model(tmp_path / "three.npz", meta, est)
    with pytest.raises(ModelError, match=r"format 'twin-identify-model/3'") as e:
        ClearanceModel.load(bad)
    assert "\n" not in str(e.value)


BENCH = ROOT / "twin" / "data" / "identify_bench.npz"


def _shipped_with_guide() -> ClearanceModel:
    """The shipped model that locates the guide: the default where it does, else the whole-bench model shipped
    beside it as ``bench`` (analysis/identify/FRESH_TEST_WHOLE_BENCH.md), else skip."""
    for path in (DEFAULT, BENCH):
        if path.is_file():
            m = ClearanceModel.load(path)
            if "G" in m.joints:
                return m
    pytest.skip("no committed model locates the guide")


@pytest.mark.parametrize("guide_mm, fault", [(0.2, "G"), (0.0, "none")])
def test_the_guide_model_locates_guide_play_alone_and_leaves_a_tight_bench_healthy(guide_mm, fault):
    """Regression guard of the repository's guide model (no independent basis: the located class is the model's): a simulated
    run of the reference engine with play only in the slider guide (0.2 mm, z vertical, 550 motor rpm, crank PID,
    3 s through the sensor chain) is located G with a proper interval at G (0 < lo < size < hi, lo no lower than the
    smallest guide play trained on) and its size resolved (a boolean). Not y vertical: there gravity holds the slider on its lower rail and the guide's play is not resolved (model
    card; a candidate model called this run with y vertical none); the same bench with a tight guide stays none."""
    from twin.config import preset
    from twin.identification.inputs import simulated_inputs
    from twin.identification.model import identify_inputs
    from twin.simulation import simulate_run

    m = _shipped_with_guide()
    cfg = preset(1).replace(**{"simulation.engine": "reference", "simulation.duration_s": 3.0, "drive.ramp_s": 0.3,
                               "drive.motor_rpm": 550.0, "joints.clearance_b_mm": 0.0, "joints.clearance_c_mm": 0.0,
                               "joints.clearance_guide_mm": guide_mm, "mechanism.orientation": "z",
                               "sensors.channels": ("accel", "encoder")})
    a = identify_inputs(m, *simulated_inputs(simulate_run(cfg), cfg), orientation="z", source="sim")
    assert a.fault == fault, a.probabilities
    g = a.joint("G")
    lo, hi = g.interval_if_faulty_mm
    if fault == "G":
        assert g.faulty and g.size_mm > 0 and 0 < lo < g.size_mm < hi and g.size_resolved is True
        assert lo >= m.trained_on["clearances_mm"]["G"]["min"]  # never below the smallest play trained on
    else:
        assert not g.faulty and g.size_mm == 0.0 and g.interval_mm == (0.0, 0.0)


def test_a_shipped_model_is_named_by_its_name_and_an_unknown_name_is_refused_in_one_line(tmp_path):
    """``--model bench`` / ``model="bench"`` is the whole-bench model shipped in the package (it locates G), no name is
    the default (B and C); an unknown shipped name raises naming the field and the allowed names."""
    from twin.identification.model import SHIPPED_MODELS, resolve_model, shipped_model_path

    assert resolve_model(None) == shipped_model_path("default")
    assert resolve_model("bench") == BENCH and BENCH.is_file()
    assert "G" in ClearanceModel.load(resolve_model("bench")).joints
    assert resolve_model(str(tmp_path / "m.npz")) == tmp_path / "m.npz"  # anything else is a file
    with pytest.raises(ModelError, match=r"^model: unknown shipped model 'nope'; allowed: default, bench") as e:
        shipped_model_path("nope")
    assert "\n" not in str(e.value) and set(SHIPPED_MODELS) == {"default", "bench"}


def test_presence_detectors_combined_give_the_product_of_their_probabilities_and_save_as_one_classifier(tmp_path):
    """One presence detector per location, stored as one softmax classifier over the eight classes: by the algebra
    of the logistic link (softmax of the sums of the detectors' raw scores = the product over the locations of
    sigmoid or 1 - sigmoid), each class's probability equals the product of the detectors' (independent basis: the
    detectors' own probabilities, multiplied here), and the model file saves and loads it as any classifier."""
    from sklearn.ensemble import HistGradientBoostingClassifier as C

    from twin.identification.training import detectors_as_classes
    from twin.identification.trees import from_sklearn

    rng = np.random.default_rng(4)
    nf = len(feature_names())
    X = rng.standard_normal((320, nf))
    y = np.array(CLASSES)[np.arange(len(X)) % 8]
    for k, j in enumerate("BCG"):
        X[:, k] += np.array([j in c for c in y])  # each location seen by one feature
    det = {j: from_sklearn(C(max_iter=8, max_leaf_nodes=4, random_state=0).fit(X, np.array([str(j in c) for c in y])),
                           check=X) for j in "BCG"}
    both = detectors_as_classes(det)
    assert both.classes == CLASSES and both.kind == "softmax"
    Xq = rng.standard_normal((50, nf))
    p = {j: det[j].predict_proba(Xq)[:, 1] for j in "BCG"}
    want = np.stack([np.prod([p[j] if j in c else 1 - p[j] for j in "BCG"], axis=0) for c in CLASSES], axis=1)
    np.testing.assert_allclose(both.predict_proba(Xq), want, rtol=0, atol=1e-12)
    m = _small(("B", "C", "G"))
    m = ClearanceModel(both, m.size, m.interval_log10, trained_on=m.trained_on)
    back = ClearanceModel.load(m.save(tmp_path / "det.npz"))
    assert back.identify(Xq[:3], {"B": True, "C": True}) == m.identify(Xq[:3], {"B": True, "C": True})
    with pytest.raises(ModelError, match="binary ensemble"):
        detectors_as_classes({"B": both})


def test_a_guide_play_answered_at_the_top_of_the_trained_hull_warns_that_it_may_lie_beyond_it():
    """The rule of the guide's out-of-range play (twin.identification.ranges.HULL_TOP_FACTOR): an answer within the
    factor of the largest play trained warns, one below does not, and the joints B and C have no such rule."""
    from twin.identification.ranges import HULL_TOP_FACTOR, at_hull_top

    seen = {"min": 0.0125, "max": 0.4, "distinct": 50, "ball_bearing": True}
    top = 0.4 / HULL_TOP_FACTOR["G"]
    assert at_hull_top("G", 0.4, seen) == pytest.approx(top) and at_hull_top("G", top * 1.01, seen) is not None
    assert at_hull_top("G", top * 0.99, seen) is None
    assert at_hull_top("B", 1.6, {"min": 0.0125, "max": 1.6, "distinct": 50, "ball_bearing": True}) is None


def test_with_y_vertical_an_answer_naming_no_guide_play_says_that_none_is_not_established():
    """guide_caveat: y vertical, a model of the guide, no play located at G -> the warning; G located, x or z
    vertical, or a model of B and C only -> none."""
    from twin.identification.model import GUIDE_HELD_DOWN, guide_caveat

    assert guide_caveat("y", ("B", "C", "G"), "none") == GUIDE_HELD_DOWN["y"]
    assert guide_caveat("y", ("B", "C", "G"), "BC") == GUIDE_HELD_DOWN["y"]
    assert guide_caveat("y", ("B", "C", "G"), "G") is None
    assert guide_caveat("z", ("B", "C", "G"), "none") is None and guide_caveat("x", ("B", "C", "G"), "B") is None
    assert guide_caveat("y", ("B", "C"), "none") is None


def test_the_guide_caveat_widens_the_interval_at_G_to_every_play_trained_and_leaves_the_rest():
    """guide_held_down_interval: with the caveat the guide's interval is the trained hull at G (its smallest play
    included, whatever the regressor read), B and C and every size untouched; a model without G: unchanged."""
    from twin.identification.model import guide_held_down_interval
    from twin.identification.results import JointAnswer

    seen = {"B": {"min": 0.0125, "max": 1.6}, "C": {"min": 0.0126, "max": 1.59}, "G": {"min": 0.0125, "max": 0.4}}
    joints = [JointAnswer("B", True, 0.1, (0.05, 0.2)), JointAnswer("C", False, 0.3, (0.2, 0.45)),
              JointAnswer("G", False, 0.136, (0.0201, 0.3966))]
    out = guide_held_down_interval(joints, seen)
    assert out[2].interval_if_faulty_mm == (0.0125, 0.4) and out[2].size_if_faulty_mm == 0.136
    assert out[:2] == joints[:2]
    assert guide_held_down_interval(joints[:2], {k: seen[k] for k in "BC"}) == joints[:2]


def test_the_guide_load_with_y_vertical_meets_statics_at_low_speed_and_keeps_one_sign_over_the_bench_speeds():
    """analysis/identify/guide_load.py (inverse dynamics of the ideal rigid bench): as the speed goes to zero the
    guide carries the slider's weight and the rod's share at C, m_s g + m_rod g x_G / L (statics, independent basis);
    at the bench's top speed (800 motor rpm) the load still keeps one sign (the caveat's basis)."""
    import sys

    from twin.config import BenchConfig

    sys.path.insert(0, str(ROOT / "analysis" / "identify"))
    try:
        from guide_load import guide_load
    finally:
        sys.path.remove(str(ROOT / "analysis" / "identify"))
    cfg = BenchConfig()
    b, g = cfg.bodies, cfg.mechanism.gravity_mps2
    static = b.slider.mass_kg * g + b.rod.mass_kg * g * b.rod.x_g_m / b.rod.length_m
    slow = guide_load(1.0, cfg)
    np.testing.assert_allclose(slow, static, rtol=1e-3)
    assert guide_load(800.0, cfg).min() > 0


def test_an_interval_within_its_half_width_of_the_smallest_size_trained_reaches_down_to_it():
    """reach_hull_floor (arithmetic, the rule as stated): lo < floor 10^w -> the floor; at or above -> lo unchanged;
    no hull -> unchanged; TrainOptions.hull_floor accepts booleans only."""
    from twin.identification.intervals import reach_hull_floor
    from twin.identification.training import TrainOptions, TrainOptionsError

    floor, w = 0.0125, 0.2
    edge = floor * 10 ** w  # 0.01981 mm
    assert reach_hull_floor(0.0183, w, floor) == floor  # the development miss at G: 0.0178 mm now inside
    assert reach_hull_floor(edge * 0.999, w, floor) == floor
    assert reach_hull_floor(edge * 1.001, w, floor) == edge * 1.001
    assert reach_hull_floor(0.0183, w, None) == 0.0183
    assert TrainOptions(hull_floor=True).hull_floor is True
    with pytest.raises(TrainOptionsError, match="hull_floor"):
        TrainOptions(hull_floor=1)


def test_the_shipped_bench_model_has_the_hull_floor_rule_and_a_model_with_a_bad_flag_is_refused(tmp_path):
    """The shipped `bench` file records interval.hull_floor = true; a file whose flag is not a boolean is refused in
    one line naming it."""
    from twin.identification.model import shipped_model_path

    m = ClearanceModel.load(shipped_model_path("bench"))
    assert m.trained_on["interval"]["hull_floor"] is True
    m.trained_on["interval"]["hull_floor"] = "yes"
    m.save(tmp_path / "bad.npz")
    with pytest.raises(ModelError, match="hull_floor"):
        ClearanceModel.load(tmp_path / "bad.npz")
