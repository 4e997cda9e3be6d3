"""Size regressors' options of ``twin.identification.training.train``: each run alike (``size_weights="runs"``) and the
other locations' play as context (``size_context=True``), on synthetic features whose laws are set here (the
independent basis): a column carrying log10 of the clearance, shifted by a known amount where another joint has play.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from twin.identification.features import feature_names

pytestmark = pytest.mark.long  # small fits: run by CI and with -m long


def _data(n_runs: int, shift_if_c: float, heavy: int = 0, seed: int = 3) -> tuple:
    """``n_runs`` one-window runs (classes B and BC, z vertical) whose column 0 is log10 of B's clearance (+ noise
    of 0.02), shifted by ``shift_if_c`` where C has play too (nothing else tells C's play); and, where ``heavy`` > 0,
    one more run of ``heavy`` windows labelled 10^-0.4 mm, every feature of every window 0 (no split can tell any
    window from another: the regressor is the weighted mean of the labels)."""
    rng = np.random.default_rng(seed)
    nf = len(feature_names())
    rows, owner, X = [], [], []
    for i in range(n_runs + (1 if heavy else 0)):
        last = heavy and i == n_runs
        fault = "B" if last else ("B", "BC")[i % 2]
        b = 10 ** -0.4 if last else 0.1 if heavy else 10 ** rng.uniform(-1.8, -0.2)
        c = 0.1 if "C" in fault else 0.0
        rpm = (300.0, 600.0)[i % 2]
        rows.append({"fault": fault, "clearance_b_mm": b, "clearance_c_mm": c, "dataset": "synthetic",
                     "orientation": "z", "crank_hz": rpm / 60 / 3.97, "motor_rpm": rpm, "engine": "reference",
                     "measures": {"crank_hz": rpm / 60 / 3.97, "ripple_pct": [0.0] * 4, "noise_ug_rthz": 30.0}})
        for _ in range(heavy if last else 1):
            x = np.zeros(nf) if heavy else rng.normal(size=nf)
            if not heavy:
                x[0] = math.log10(b) + rng.normal(0, 0.02) + (shift_if_c if c else 0.0)
            X.append(x)
            owner.append(i)
    return np.array(X), rows, owner


def _train(tmp_path, X, rows, owner, **options):
    from twin.identification.training import TrainOptions, train

    ds = SimpleNamespace(info={"name": "synthetic", "identity": {"engine": "reference"}}, rate_hz=100000.0,
                         path=tmp_path)
    return train([tmp_path], TrainOptions(**options), features=(X, rows, owner, [], [ds]))


def test_runs_alike_keeps_one_run_of_many_windows_from_outweighing_the_others(tmp_path):
    """120 one-window runs labelled 0.1 mm and one run of 300 windows labelled 10^-0.4 mm, features all alike: the
    answer is the weighted mean of log10 of the labels, (120 (-1) + 300 (-0.4)) / 420 with windows alike,
    (120 (-1) + 1 (-0.4)) / 121 with runs alike (arithmetic)."""
    X, rows, owner = _data(120, 0.0, heavy=300)
    want = {"windows": (120 * -1.0 + 300 * -0.4) / 420, "runs": (120 * -1.0 - 0.4) / 121}
    for w in ("windows", "runs"):
        m, info = _train(tmp_path, X, rows, owner, size_weights=w, fault_split=False, size_band_mm=None)
        assert float(m.size["B"].predict(X[:1])[0]) == pytest.approx(want[w], abs=1e-6)
        assert info.get("size_weights", "windows") == w


def test_the_other_joints_play_as_context_reads_a_size_shifted_by_it(tmp_path):
    """Column 0 reads log10(B) + 0.5 where C has play too: a regressor with the context answers B's size within
    x1.5 for a run located B+C and for one located B alone from the same law; the file keeps the option and
    answers the same after loading."""
    from twin.identification.model import ClearanceModel

    X, rows, owner = _data(160, 0.5)
    m, info = _train(tmp_path, X, rows, owner, size_context=True, fault_split=False, size_band_mm=None)
    assert info["size_context"] is True
    back = ClearanceModel.load(m.save(tmp_path / "ctx.npz"))
    assert back.size["B"].n_features == len(feature_names()) + 2
    x = X[:1].copy()
    x[0, 0] = math.log10(0.1) + 0.5  # B 0.1 mm beside play at C
    for mod in (m, back):
        got = {f: mod.size["B"].predict(np.hstack([x, [[float("C" in f), 0.0]]]))[0] for f in ("BC", "B")}
        assert abs(got["BC"] - math.log10(0.1)) < math.log10(1.5)  # the context undoes the shift
        assert abs(got["B"] - (math.log10(0.1) + 0.5)) < math.log10(1.5)  # the same reading alone: a larger B
    a, b = m.identify(x, {"B": True, "C": True}), back.identify(x, {"B": True, "C": True})
    assert a == b
