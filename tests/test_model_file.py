"""The identification model file: plain arrays and JSON, nothing in it runs.

Independent bases: scikit-learn's own ``predict`` / ``predict_proba`` (the exported trees must answer
the same, bit for bit), the model of format 2 as committed before the conversion (from git), and
hostile files whose payload is shown to run when unpickled the ordinary way, and not when loaded.
"""

from __future__ import annotations

import hashlib
import io
import json
import pickle
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest

from twin.cli import main
from twin.identification.features import feature_names
from twin.identification.model import MODEL_FORMAT, ClearanceModel, ModelError
from twin.identification.ranges import feature_reference
from twin.identification.trees import TreeEnsemble, from_sklearn

ROOT = Path(__file__).resolve().parent.parent
REC = ROOT / "recordings" / "test6_synthetic.mcap"
SHIPPED = ROOT / "twin" / "data" / "identify_default.npz"
OLD = "twin/data/identify_default.joblib"  # the shipped model of format 2 (pickle), in the git history


@pytest.fixture(autouse=True, scope="module")
def _one_thread():
    """scikit-learn's OpenMP threads on a loaded machine spin: one thread is faster here (its OpenMP
    runtime must be loaded for the limit to hold)."""
    import sklearn.ensemble  # noqa: F401
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1):
        yield


def _data(n: int, nf: int, seed: int, nan: float = 0.1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    X = rng.standard_normal((n, nf))
    X[rng.random(X.shape) < nan] = np.nan
    return X


def _test_rows(nf: int) -> np.ndarray:
    X = 2 * _data(400, nf, 7, nan=0.2)
    X[0], X[1], X[2] = np.inf, -np.inf, np.nan  # all missing: every split's missing-go-left
    return X


def _same(e: TreeEnsemble, est, X: np.ndarray) -> bool:
    if e.kind == "identity":
        return np.array_equal(e.predict(X), est.predict(X))
    return np.array_equal(e.predict_proba(X), est.predict_proba(X)) and np.array_equal(e.predict(X), est.predict(X))


def test_exported_trees_answer_as_scikit_learn_bit_for_bit():
    """Multiclass (softmax), binary (sigmoid) and the regression losses, trained on data with NaNs,
    answered on other rows with 20 % NaN and rows of +inf, -inf and all NaN."""
    from sklearn.ensemble import HistGradientBoostingClassifier as C
    from sklearn.ensemble import HistGradientBoostingRegressor as R

    X = _data(300, 8, 1)
    a, b = np.nan_to_num(X[:, 0]) > 0, np.nan_to_num(X[:, 1]) > 0.3
    y4 = np.array(["B", "BC", "C", "none"])[a + 2 * b]
    yr = np.nan_to_num(X[:, 2]) - np.isnan(X[:, 3])
    Xt = _test_rows(8)
    cases = [(C(max_iter=25, class_weight="balanced", random_state=0), y4, "softmax"),
             (C(max_iter=25, random_state=0), np.where(a, "yes", "no"), "sigmoid"),
             (R(loss="quantile", quantile=0.5, max_iter=40, random_state=0), yr, "identity"),
             (R(max_iter=40, random_state=0), yr, "identity"),
             (R(loss="absolute_error", max_iter=20, random_state=0), yr, "identity")]
    for est, y, kind in cases:
        e = from_sklearn(est.fit(X, y), check=X)
        assert e.kind == kind and e.missing_left.any() and not e.missing_left.all()  # NaNs both ways
        assert _same(e, est, Xt), est


def test_export_refuses_what_it_cannot_reproduce():
    from sklearn.ensemble import HistGradientBoostingRegressor as R
    from sklearn.linear_model import LinearRegression

    X = _data(200, 4, 2, nan=0.0)
    X[:, 0] = np.round(np.abs(X[:, 0]) * 3)
    y = X[:, 0] + np.abs(X[:, 1])
    with pytest.raises(ModelError, match="categorical"):
        from_sklearn(R(max_iter=5, categorical_features=[0]).fit(X, y))
    with pytest.raises(ModelError, match="loss .*Poisson"):  # log link: not supported
        from_sklearn(R(loss="poisson", max_iter=5).fit(X, y))
    with pytest.raises(ModelError, match="LinearRegression"):
        from_sklearn(LinearRegression().fit(X, y))
    with pytest.raises(ModelError, match="fitted"):
        from_sklearn(R())


def _git_old_model(tmp: Path) -> Path:
    """The format-2 model file as last committed (from the git history), or skip."""
    git = shutil.which("git")
    if git is None or not (ROOT / ".git").exists():
        pytest.skip("no git history")
    run = lambda *a: subprocess.run([git, *a], cwd=ROOT, capture_output=True)  # noqa: E731
    last = run("rev-list", "-n", "1", "HEAD", "--", OLD).stdout.decode().strip()
    for rev in (f"{last}:{OLD}", f"{last}^:{OLD}"):
        r = run("show", rev)
        if last and r.returncode == 0:
            (tmp / "identify_default.joblib").write_bytes(r.stdout)
            return tmp / "identify_default.joblib"
    pytest.skip(f"{OLD} not in this checkout's history")


def test_the_shipped_model_of_format_2_exports_as_scikit_learn_answers(tmp_path):
    """The format-2 model (a trusted file: this repository's history) unpickled with scikit-learn,
    exported, answers bit for bit as scikit-learn on the test-6 sample's features and on random
    features with NaNs; where the shipped file was converted from it, its arrays are the export's."""
    import joblib

    from twin.identification.inputs import recording_inputs
    from twin.identification.features import features

    src = _git_old_model(tmp_path)
    # the format-2 pickle names the package by its former name, twin.identify
    import sys

    import twin.identification
    import twin.identification.model
    sys.modules.setdefault("twin.identify", twin.identification)
    sys.modules.setdefault("twin.identify.model", twin.identification.model)
    old = joblib.load(src)
    acc, counts, rate, cpr, cfg = recording_inputs(REC)
    Xs = features(acc, counts, rate, cpr, orientation=cfg.mechanism.orientation)[0]
    Xt = _test_rows(Xs.shape[1]) + Xs[0]  # around the recording's features
    exported = {"classifier": from_sklearn(old.classifier), "size_B": from_sklearn(old.size["B"]),
                "size_C": from_sklearn(old.size["C"])}
    sk = {"classifier": old.classifier, "size_B": old.size["B"], "size_C": old.size["C"]}
    # and rows with every feature exactly at one of its split thresholds (where <= and < part)
    rng = np.random.default_rng(0)
    Xe = np.repeat(Xs, 50, axis=0)
    for f in range(Xe.shape[1]):
        t = np.concatenate([e.threshold[~e.is_leaf & (e.feature == f)] for e in exported.values()])
        if np.isfinite(t).any():
            Xe[:, f] = rng.choice(t[np.isfinite(t)], len(Xe))
    for k, e in exported.items():
        assert e.kind == ("softmax" if k == "classifier" else "identity")
        assert _same(e, sk[k], Xs) and _same(e, sk[k], Xt) and _same(e, sk[k], Xe), k
    shipped = ClearanceModel.load(SHIPPED)
    conv = shipped.trained_on.get("converted_from")
    if conv is None or conv["sha256"] != hashlib.sha256(src.read_bytes()).hexdigest():
        return  # the shipped model was retrained since (not converted from this file): the export check above is all
    loaded = {"classifier": shipped.classifier, "size_B": shipped.size["B"], "size_C": shipped.size["C"]}
    for k, e in loaded.items():
        assert all(np.array_equal(a, exported[k].arrays()[n]) for n, a in e.arrays().items())
        assert _same(e, sk[k], Xt) and _same(e, sk[k], Xe)
    assert shipped.interval_log10 == old.interval_log10 and shipped.feature_names == old.feature_names


# ------------------------------------------------------------------ small model files
RANGES = {"source": "random", "runs": 160, "crank_hz": [1.0, 3.0], "ripple_pct": [[0.0, 0.5], [0.0, 0.25]],
          "noise_ug_rthz": [28.0, 33.0], "orientations": ["y", "z"]}
@pytest.fixture(scope="module")
def small_model(tmp_path_factory) -> Path:
    """A model file of tiny trees on this twin's features (random data: its answers mean nothing)."""
    from sklearn.ensemble import HistGradientBoostingClassifier as C
    from sklearn.ensemble import HistGradientBoostingRegressor as R

    nf = len(feature_names())
    X = _data(160, nf, 3, nan=0.0)
    y = np.array(["none", "B", "C", "BC"])[(X[:, 0] > 0) + 2 * (X[:, 1] > 0)]
    clf = C(max_iter=3, max_leaf_nodes=4, random_state=0).fit(X, y)
    reg = R(loss="quantile", quantile=0.5, max_iter=3, max_leaf_nodes=4).fit(X, X[:, 2] - 1)
    m = ClearanceModel(clf, {"B": reg, "C": reg}, {"B": 0.2, "C": 0.3},
                       trained_on={"rate_hz": 100000.0, "crank_hz_range": [1.0, 3.0], "dataset": "random",
                                   "ranges": RANGES, "feature_reference": feature_reference(X)})
    p = tmp_path_factory.mktemp("model") / "small.npz"
    m.save(p)
    return p


def _answers(m: ClearanceModel, X: np.ndarray) -> tuple:
    return (m.classifier.predict_proba(X).tobytes(), m.size["B"].predict(X).tobytes(),
            m.size["C"].predict(X).tobytes(), m.interval_log10, m.trained_on)


def _refused(path: Path, *match: str) -> str:
    with pytest.raises(ModelError) as e:
        ClearanceModel.load(path)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(f"{path}: "), msg
    for m in match:
        assert m in msg, msg
    return msg


class _Hostile:
    """Unpickling it runs Python code: it creates the file ``marker``."""

    def __init__(self, marker: Path):
        self.marker = marker

    def __reduce__(self):
        return exec, (f"open({str(self.marker)!r}, 'w').close()",)


def test_a_saved_model_loads_back_with_the_same_answers_and_is_plain_arrays(small_model, tmp_path):
    m = ClearanceModel.load(small_model)
    X = _test_rows(len(feature_names()))
    again = tmp_path / "again.npz"
    m.save(again)
    assert again.read_bytes() == small_model.read_bytes()  # deterministic: the same model, the same bytes
    assert _answers(ClearanceModel.load(again), X) == _answers(m, X)
    with zipfile.ZipFile(small_model) as z:
        for name in z.namelist():
            arr = np.lib.format.read_array(io.BytesIO(z.read(name)), allow_pickle=False)
            assert arr.dtype.kind in "fiubU" and not arr.dtype.hasobject, name
    assert json.loads(str(np.load(small_model)["model.json"][()]))["format"] == MODEL_FORMAT == "twin-identify-model/5"


def test_the_training_ranges_and_feature_quartiles_load_back_and_malformed_ones_are_refused(small_model, tmp_path):
    m = ClearanceModel.load(small_model)
    assert m.trained_on["ranges"] == RANGES
    ref = m.trained_on["feature_reference"]
    assert len(ref["q25"]) == len(ref["q75"]) == len(feature_names())
    for bad in ({"crank_hz": [3.0, 1.0]}, {"ripple_pct": [[0.0]]}, {"noise_ug_rthz": [float("nan"), 1.0]},
                {"orientations": [1]}):
        m.trained_on["ranges"] = dict(RANGES, **bad)
        m.save(tmp_path / "bad.npz")
        _refused(tmp_path / "bad.npz", "not a readable identification model", "ranges")
    m.trained_on["ranges"] = RANGES
    for bad in ("4.5", -1.0, float("inf")):  # the ripple band of the intervals' split
        m.trained_on["interval"] = {"ripple_band_pct": bad}
        m.save(tmp_path / "bad.npz")
        _refused(tmp_path / "bad.npz", "ripple_band_pct")
    m.trained_on["interval"] = {"ripple_band_pct": 4.5}
    m.save(tmp_path / "ok.npz")
    assert ClearanceModel.load(tmp_path / "ok.npz").trained_on["interval"]["ripple_band_pct"] == 4.5
    for bad in ("0.2", [0.2, -0.03], [float("nan")], {"b": 0.2}):  # the size bands of the intervals' split
        m.trained_on["interval"] = {"size_band_mm": bad}
        m.save(tmp_path / "bad.npz")
        _refused(tmp_path / "bad.npz", "size_band_mm")
    for good in (None, 0.2, [0.7071, 0.2236, 0.0316]):
        m.trained_on["interval"] = {"size_band_mm": good}
        m.save(tmp_path / "ok.npz")
        assert ClearanceModel.load(tmp_path / "ok.npz").trained_on["interval"]["size_band_mm"] == good
    for bad in ("yes", 1, ["A"], ["C", "C"], "C"):  # the joints whose half widths are split by the fault
        m.trained_on["interval"] = {"fault_split": bad}
        m.save(tmp_path / "bad.npz")
        _refused(tmp_path / "bad.npz", "fault_split")
    for good in (True, False, None, [], ["C"], ["B", "C"]):
        m.trained_on["interval"] = {"fault_split": good}
        m.save(tmp_path / "ok.npz")
        assert ClearanceModel.load(tmp_path / "ok.npz").trained_on["interval"]["fault_split"] == good
    for bad in ([0.2], {"one": {"C": 0.2}}, {"0": {"C": 0.2}}, {"1": {"A": 0.2}}, {"1": {"C": -0.1}},
                {"1": {"C": float("nan")}}, {"1": [0.2]}):  # the half widths of answers from 1, 2, ... windows
        m.trained_on["interval"] = {"half_width_log10_by_windows": bad}
        m.save(tmp_path / "bad.npz")
        _refused(tmp_path / "bad.npz", "half_width_log10_by_windows")
    for good in ({}, {"1": {"C": 0.4, "C_small": 0.5}, "2": {"B": 0.3}}):
        m.trained_on["interval"] = {"half_width_log10_by_windows": good}
        m.save(tmp_path / "ok.npz")
        assert ClearanceModel.load(tmp_path / "ok.npz").trained_on["interval"]["half_width_log10_by_windows"] == good
    m.trained_on["interval"] = {}
    for bad in (0, -0.5, 2.5, "0.5", None):  # where an answer's windows end, in crank turns: (0, 2]
        m.trained_on["answer_hop_revs"] = bad
        m.save(tmp_path / "bad.npz")
        _refused(tmp_path / "bad.npz", "answer_hop_revs")
    for good in (0.5, 1, 2.0):
        m.trained_on["answer_hop_revs"] = good
        m.save(tmp_path / "ok.npz")
        assert ClearanceModel.load(tmp_path / "ok.npz").hop_revs == good
    good = {"y": {"crank_hz": [1.05, 2.1], "within": [0.5, 0.95], "runs": [40, 60]}}
    for bad in ({"B": good}, {"B": good, "C": {"y": good["y"] | {"within": [0.5, 1.2]}}},
                {"B": good, "C": {"y": good["y"] | {"crank_hz": [2.1, 1.05]}}},
                {"B": good, "C": {"y": good["y"] | {"runs": [40]}}},
                {"B": good, "C": {"y": good["y"] | {"runs": [0, 1]}}}):
        m.trained_on["held_out_size_accuracy"] = bad  # the held-out size accuracy per orientation and speed
        m.save(tmp_path / "bad.npz")
        _refused(tmp_path / "bad.npz", "held_out_size_accuracy")
    m.trained_on["held_out_size_accuracy"] = {"B": good, "C": good, "method": "out of fold"}
    m.save(tmp_path / "ok.npz")
    assert ClearanceModel.load(tmp_path / "ok.npz").trained_on["held_out_size_accuracy"]["C"] == good
    del m.trained_on["held_out_size_accuracy"]
    del m.trained_on["answer_hop_revs"]  # a model made before the hop was recorded: windows back to back
    m.save(tmp_path / "ok.npz")
    assert ClearanceModel.load(tmp_path / "ok.npz").hop_revs == 2.0
    m.trained_on["feature_reference"] = {"q25": [0.0], "q75": [1.0]}
    m.save(tmp_path / "bad.npz")
    _refused(tmp_path / "bad.npz", "feature_reference")


def test_the_shipped_model_states_its_ranges_and_where_they_come_from():
    """The shipped model (trained on the nuisance sets, analysis/identify/train_default.py) holds the ranges
    measured on every training run: the crank rates of 250-800 motor rpm, the within-turn ripple read back from
    the encoder (the crank PID's imposed 0-4 % at 1-3x the crank rate, and the drive train's own, 15-25 % at 2x
    from 500 motor rpm by docs/drivetrain.md's ripple study), the noise of 0.7-2x the datasheet's 30 ug/rtHz,
    the three orientations, and its training features' reference with the runs' own far-out count."""
    m = ClearanceModel.load(SHIPPED)
    tr = m.trained_on
    r = tr["ranges"]
    assert r["crank_hz"] == tr["crank_hz_range"] and r["orientations"] == ["x", "y", "z"]
    assert r["source"].startswith("measured on every training run") and r["runs"] == tr["runs"]
    belt = 3.97
    assert r["crank_hz"][0] == pytest.approx(250 / belt / 60, rel=0.01) and r["crank_hz"][1] == pytest.approx(800 / belt / 60, rel=0.01)
    hi = [h for _, h in r["ripple_pct"]]
    assert len(hi) == 4 and min(hi[:3]) >= 4.0 - 0.05 and hi[1] > 15.0
    assert r["noise_ug_rthz"] == pytest.approx([0.7 * 30.1, 2.0 * 30.1], rel=0.03)
    ref = tr["feature_reference"]
    assert len(ref["q25"]) == len(m.feature_names) and 0 < ref["max_outliers"] < len(ref["q25"])


def test_a_hostile_pickle_is_refused_unopened(tmp_path, capsys):
    """A pickle (as a .joblib, plain or compressed, or named .npz) that would run code: refused in one
    line by ClearanceModel.load and by ``twin identify clearance --model``; the payload never ran.
    Control: unpickled the ordinary way, it does run."""
    import joblib

    marker = tmp_path / "ran"
    hostile = [tmp_path / "hostile.joblib", tmp_path / "hostile.pkl", tmp_path / "pickle.npz"]
    for h in hostile:
        h.write_bytes(pickle.dumps(_Hostile(marker), protocol=4))
    joblib.dump(_Hostile(marker), tmp_path / "hostile_z.joblib", compress=3)  # zlib, as the old model
    hostile.append(tmp_path / "hostile_z.joblib")
    assert not marker.exists()
    for h in hostile:
        _refused(h, "never unpickled")
        assert main(["identify", "clearance", str(REC), "--model", str(h)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "pickle" in err and str(h) in err
        assert not marker.exists()
    joblib.load(hostile[-1])  # the control: the ordinary way runs the payload
    assert marker.exists()


def test_a_file_that_is_not_a_model_is_named_by_what_its_first_bytes_are(tmp_path):
    """The refusal says what a foreign file most likely is from its first bytes, and does not call a text
    file starting with "x" (0x78, zlib's first byte) a compressed pickle: a zlib stream is 0x78 and a second
    byte making the 16-bit header a multiple of 31 (RFC 1950; "x " is one, with a preset dictionary, which
    joblib never writes); a pickle is 0x80 then its protocol, compressed or not."""
    import bz2
    import gzip
    import zlib

    cases = {"text.npz": (b"x = 1\n", "not a zip archive"),
             "one_x.npz": (b"x\n", "not a zip archive"),
             "zlib.npz": (zlib.compress(b"plain bytes"), "a zlib stream"),
             "zlib_pickle.npz": (zlib.compress(pickle.dumps([1, 2], protocol=4)), "zlib-compressed"),
             "protocol2.npz": (pickle.dumps([1, 2], protocol=2), "a pickle file"),
             "highbyte.npz": (b"\x80\x00 not a pickle", "not a zip archive"),
             "gzip.npz": (gzip.compress(b"plain"), "a gzip file"),
             "bz2.npz": (bz2.compress(b"plain"), "a bz2 file")}
    for name, (data, said) in cases.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(ModelError) as e:
            ClearanceModel.load(tmp_path / name)
        msg = str(e.value)
        assert said in msg and "\n" not in msg, (name, msg)
        assert ("pickle" in msg.split(";")[0]) == (said in ("zlib-compressed", "a pickle file", "a gzip file",
                                                           "a bz2 file")), (name, msg)


def _rewrite(src: Path, dst: Path, change) -> Path:
    """A copy of a model file with its members changed by ``change(name, bytes) -> bytes | None``
    (None drops the member); the zip is written afresh, so every CRC is right."""
    with zipfile.ZipFile(src) as z, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as out:
        for name in z.namelist():
            data = change(name, z.read(name))
            if data is not None:
                out.writestr(name, data)
    return dst


def _npy(a: np.ndarray) -> bytes:
    b = io.BytesIO()
    np.lib.format.write_array(b, a, allow_pickle=True)
    return b.getvalue()


def test_a_hostile_npz_with_an_object_array_is_refused_and_nothing_runs(small_model, tmp_path):
    marker = tmp_path / "ran"
    obj = np.empty(3, dtype=object)
    obj[:] = [_Hostile(marker)] * 3
    for member in ("classifier.value.npy", "model.json.npy", "size_C.left.npy"):
        bad = _rewrite(small_model, tmp_path / "bad.npz", lambda n, d: _npy(obj) if n == member else d)
        _refused(bad, "not a readable identification model")
        assert not marker.exists()
    np.load(bad, allow_pickle=True)["size_C.left"]  # the control: with pickles allowed it runs
    assert marker.exists()


def test_another_format_other_members_and_unsafe_trees_are_refused_in_one_line(small_model, tmp_path):
    def meta_of(change):
        def f(name, data):
            if name != "model.json.npy":
                return data
            meta = json.loads(str(np.lib.format.read_array(io.BytesIO(data))[()]))
            change(meta)
            return _npy(np.array(json.dumps(meta)))
        return f

    def arr(member, change):
        def f(name, data):
            if name != member:
                return data
            a = np.lib.format.read_array(io.BytesIO(data)).copy()
            return _npy(change(a))
        return f

    cases = [
        (meta_of(lambda m: m.update(format="twin-identify-model/3")),
         ("a model of format 'twin-identify-model/3', this twin reads 'twin-identify-model/5 or twin-identify-model/4'", "retrain")),
        (meta_of(lambda m: m.update(feature_version="twin-identify-features/0")), ("made for features", "retrain")),
        (meta_of(lambda m: m.pop("interval_log10")), ("metadata: KeyError",)),
        (lambda n, d: None if n == "size_B.value.npy" else d, ("size_B.value missing or unexpected",)),
        (lambda n, d: d + b"" if n != "model.json.npy" else _npy(np.array(["{}", "{}"])), ("not a text",)),
        (arr("classifier.left.npy", lambda a: np.where(a > 0, 0, a).astype(np.int32)), ("not after its parent",)),
        (arr("size_C.feature.npy", lambda a: a + 1000), ("an index outside 0-",)),
        (arr("size_B.threshold.npy", lambda a: np.full_like(a, np.nan)), ("threshold: NaN",)),
        (arr("size_B.value.npy", lambda a: a.astype(np.float32)), ("float32",)),
        (arr("classifier.tree_nodes.npy", lambda a: a[:-1]), ("tree_nodes",)),
    ]
    for i, (change, match) in enumerate(cases):
        _refused(_rewrite(small_model, tmp_path / f"case{i}.npz", change), *match)
    extra = _rewrite(small_model, tmp_path / "extra.npz", lambda n, d: d)
    with zipfile.ZipFile(extra, "a") as z:
        z.writestr("notes.npy", _npy(np.zeros(2)))
    _refused(extra, "notes missing or unexpected")


def test_bit_flips_and_truncation_are_refused_in_one_line_or_change_nothing(small_model, tmp_path):
    """Any one bit flipped anywhere (400 drawn places) gives a one-line refusal, or, where it lands in
    a field nothing reads (a member's timestamp, say), the very same model; a cut file is refused."""
    ref = ClearanceModel.load(small_model)
    X = _test_rows(len(feature_names()))
    want = _answers(ref, X)
    data = small_model.read_bytes()
    rng = np.random.default_rng(5)
    bad = tmp_path / "flipped.npz"
    refused = 0
    for pos in rng.choice(len(data), 400, replace=False):
        b = bytearray(data)
        b[pos] ^= 1 << int(rng.integers(8))
        bad.write_bytes(bytes(b))
        try:
            m = ClearanceModel.load(bad)
        except ModelError as err:
            assert "\n" not in str(err) and str(err).startswith(f"{bad}: ")
            refused += 1
            continue
        assert _answers(m, X) == want, pos
    assert refused > 300  # most bytes are member data, each under its CRC
    for n in (0, 3, 30, len(data) // 2, len(data) - 22, len(data) - 1):
        cut = tmp_path / f"cut{n}.npz"
        cut.write_bytes(data[:n])
        _refused(cut, "not a readable identification model")


def test_train_writes_the_npz_format_only(tmp_path, capsys):
    assert main(["identify", "train", str(tmp_path), "--out", str(tmp_path / "m.joblib")]) == 2
    assert "--out: must end in .npz" in capsys.readouterr().err


def test_the_shipped_model_answers_without_scikit_learn_or_joblib():
    """With scikit-learn and joblib made unimportable, the shipped model loads and answers the test-6
    sample as it does with them (the answer's fields but the time taken)."""
    import sys

    from twin.identification.model import identify_recording

    code = ("import sys, json; sys.modules['sklearn'] = sys.modules['joblib'] = None\n"
            "from twin.identification.model import ClearanceModel, identify_recording\n"
            f"a = identify_recording(ClearanceModel.load({str(SHIPPED)!r}), {str(REC)!r}).to_dict(); a.pop('seconds')\n"
            "print(json.dumps(a, default=float))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    a = identify_recording(ClearanceModel.load(SHIPPED), REC).to_dict()
    a.pop("seconds")
    assert json.loads(r.stdout) == json.loads(json.dumps(a, default=float))
