"""MEREC, GRA, TOPSIS, SAW and WASPAS (twin/studies/mcdm.py) and ``twin study mcdm``.

Each method is checked against a small example worked by hand below (the arithmetic is in the
comments, done independently of the code) and against published numbers:

* MEREC: the illustrative example of Keshavarz-Ghorabaee, Amiri, Zavadskas, Turskis &
  Antucheviciene (2021), Symmetry 13:525, Section 3 (5 alternatives, 4 criteria, 2 beneficial and
  2 non-beneficial; weights 0.5752, 0.0141, 0.4016, 0.0091), as transcribed in the test suite of
  the pymcdm package (tests/test_weights.py, which cites the paper).
* TOPSIS: the fighter-aircraft example of Hwang & Yoon (1981), Multiple Attribute Decision Making,
  Springer, p. 133 (4 alternatives, 6 criteria, the 4th a cost; C* = 0.643, 0.268, 0.613, 0.312),
  as transcribed with its distances in a TypeScript TOPSIS package's example (the book's own
  normalised matrix carries 4th-digit errors, hence the 1e-3 tolerance on C*).
* WASPAS (standard form, λ = 0.5): the example of Chakraborty, Zavadskas & Antucheviciene (2015),
  Economic Computation and Economic Cybernetics Studies and Research 49(1):5-22 (8 alternatives,
  7 criteria; Q = 0.8329, 0.7884, 0.6987, 0.8831, 0.7971, 0.7036, 0.8728, 0.5749), as transcribed in
  pymcdm's tests/test_methods.py; its printed weights sum to 1.0155 and are used as printed.
* GRA, SAW, TOPSIS and S002's WASPAS variant: S002's own Tables 6, 11 and 13
  from their printed normalised inputs to their printed outputs.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from twin.cli import main
from twin.studies import mcdm


# ------------------------------------------------------------------ hand-worked examples
# A1 = (4, 2), A2 = (2, 1), A3 = (1, 4); criterion 1 larger-is-better, criterion 2 smaller-is-better;
# weights w = (0.6, 0.4).
X_HAND = np.array([[4.0, 2.0], [2.0, 1.0], [1.0, 4.0]])
B_HAND = [True, False]
W_HAND = [0.6, 0.4]


def test_saw_by_hand():
    # n1 = x/max = (1, 0.5, 0.25); n2 = min/x = (1/2, 1, 1/4)
    # scores 0.6*1 + 0.4*0.5 = 0.8; 0.6*0.5 + 0.4*1 = 0.7; 0.6*0.25 + 0.4*0.25 = 0.25
    r = mcdm.saw(X_HAND, B_HAND, W_HAND)
    assert np.allclose(r["scores"], [0.8, 0.7, 0.25], atol=1e-12)
    assert mcdm.ranks(r["scores"]).tolist() == [1, 2, 3]


def test_waspas_standard_and_paper_variant_by_hand():
    # WPM: A1 1^0.6 * 0.5^0.4 = 0.757858; A2 0.5^0.6 * 1 = 0.659754; A3 0.25^0.6 * 0.25^0.4 = 0.25
    # lambda = 0.5: A1 (0.8 + 0.757858)/2 = 0.778929; A2 (0.7 + 0.659754)/2 = 0.679877; A3 0.25
    r = mcdm.waspas(X_HAND, B_HAND, W_HAND, lam=0.5)
    assert np.allclose(r["wpm"], [0.757858, 0.659754, 0.25], atol=1e-6)
    assert np.allclose(r["scores"], [0.778929, 0.679877, 0.25], atol=1e-6)
    # S002's variant, lambda = 0.9: c = 0.6^0.6 * 0.4^0.4 = exp(-0.306495 - 0.366516) = 0.510170;
    # A1: P = c * 0.757858 = 0.386637, A = 0.9*0.8 + 0.1*0.386637 = 0.758664
    p = mcdm.waspas_paper(X_HAND, B_HAND, W_HAND, lam=0.9)
    assert p["c"] == pytest.approx(0.510170, abs=1e-6)
    assert p["P"][0] == pytest.approx(0.386637, abs=1e-6)
    assert p["scores"][0] == pytest.approx(0.758664, abs=1e-6)


def test_gra_by_hand():
    # x*: criterion 1 (x - 1)/3 = (1, 1/3, 0); criterion 2 (4 - x)/3 = (2/3, 1, 0)
    # delta = 1 - x*: A1 (0, 1/3), A2 (2/3, 0), A3 (1, 1); delta_min = 0, delta_max = 1
    # gamma = 0.5/(delta + 0.5): A1 (1, 0.6), A2 (0.428571, 1), A3 (1/3, 1/3)
    # grade: A1 0.6 + 0.24 = 0.84; A2 0.257143 + 0.4 = 0.657143; A3 1/3
    r = mcdm.gra(X_HAND, B_HAND, W_HAND)
    assert np.allclose(r["coefficient"], [[1, 0.6], [3 / 7, 1], [1 / 3, 1 / 3]], atol=1e-12)
    assert np.allclose(r["scores"], [0.84, 0.657143, 1 / 3], atol=1e-6)


def test_topsis_by_hand():
    # both columns have norm sqrt(21); in units of 1/sqrt(21): v = (0.6 x1, 0.4 x2)
    # A1 (2.4, 0.8), A2 (1.2, 0.4), A3 (0.6, 1.6); ideal (2.4, 0.4), anti-ideal (0.6, 1.6)
    # A1: d+ = 0.4, d- = sqrt(1.8^2 + 0.8^2) = 1.969772, C = 0.831206
    # A2: d+ = 1.2, d- = sqrt(0.6^2 + 1.2^2) = 1.341641, C = 0.527864;  A3: d- = 0, C = 0
    r = mcdm.topsis(X_HAND, B_HAND, W_HAND)
    s21 = math.sqrt(21)
    assert np.allclose(r["d_plus"] * s21, [0.4, 1.2, math.sqrt(4.68)], atol=1e-9)
    assert np.allclose(r["scores"], [0.831206, 0.527864, 0.0], atol=1e-6)


def test_merec_by_hand():
    # A1 = (1, 1), A2 = (2, 4), both smaller-is-better: n = x/max, A1 (0.5, 0.25), A2 (1, 1)
    # |ln n|: A1 (0.693147, 1.386294), A2 (0, 0); S_A1 = ln(1 + 2.079442/2) = 0.712813, S_A2 = 0
    # criterion 1 removed: S'_A1 = ln(1 + 1.386294/2) = 0.526589 -> E1 = 0.186224
    # criterion 2 removed: S'_A1 = ln(1.346574) = ln(1.35) + ln(0.997462) = 0.300105 - 0.002541 = 0.297563
    #   -> E2 = 0.415250
    # w = (0.186224, 0.415250)/0.601474 = (0.309613, 0.690387): the wider-spread criterion weighs more
    d = mcdm.merec_details(np.array([[1.0, 1.0], [2.0, 4.0]]), [False, False])
    assert np.allclose(d["S"], [0.712813, 0.0], atol=1e-6)
    assert np.allclose(d["E"], [0.186224, 0.415250], atol=2e-6)
    assert np.allclose(d["weights"], [0.309613, 0.690387], atol=2e-6)


def test_ranks_are_competition_ranks():
    assert mcdm.ranks([0.5, 0.9, 0.5, 0.1]).tolist() == [2, 1, 2, 4]


def test_paper_waspas_is_the_standard_form_with_another_lambda():
    # lambda*WSM + (1-lambda)*c*WPM = k * (lambda'*WSM + (1-lambda')*WPM), k = lambda + (1-lambda)c,
    # lambda' = lambda/k: an identity, checked on random data
    rng = np.random.default_rng(3)
    x = rng.uniform(1, 10, (12, 3))
    b = [True, False, True]
    w = np.array([0.2, 0.5, 0.3])
    lam = 0.9
    p = mcdm.waspas_paper(x, b, w, lam)
    k = lam + (1 - lam) * p["c"]
    s = mcdm.waspas(x, b, w, lam / k)
    assert p["c"] == pytest.approx(float(np.prod(w ** w)))
    assert np.allclose(p["scores"], k * s["scores"], rtol=1e-12)


def test_scores_do_not_depend_on_units():
    # every method normalises each criterion: a change of unit (m/s^2 -> g, N -> kN) changes nothing
    rng = np.random.default_rng(5)
    x = rng.uniform(1, 10, (9, 2))
    b, w = [False, False], mcdm.merec_weights(x, [False, False])
    a = mcdm.evaluate(x, b, w)
    c = mcdm.evaluate(x * [1 / 9.81, 1e-3], b, mcdm.merec_weights(x * [1 / 9.81, 1e-3], b))
    for k in mcdm.METHODS:
        assert np.allclose(a[k]["scores"], c[k]["scores"], rtol=1e-12)


# ------------------------------------------------------------------ published examples
def test_merec_published_illustrative_example():
    x = np.array([[450, 8000, 54, 145], [10, 9100, 2, 160], [100, 8200, 31, 153],
                  [220, 9300, 1, 162], [5, 8400, 23, 158]], dtype=float)
    w = mcdm.merec_weights(x, [True, True, False, False])
    assert np.allclose(w, [0.5752, 0.0141, 0.4016, 0.0091], atol=5e-5)


def test_topsis_published_aircraft_example():
    x = np.array([[2.0, 1500, 20000, 5.5, 5, 9], [2.5, 2700, 18000, 6.5, 3, 5],
                  [1.8, 2000, 21000, 4.5, 7, 7], [2.2, 1800, 20000, 5.0, 5, 5]])
    r = mcdm.topsis(x, [True, True, True, False, True, True], [0.2, 0.1, 0.1, 0.1, 0.2, 0.3])
    assert np.allclose(r["d_plus"], [0.0545, 0.1197, 0.0580, 0.1009], atol=2e-4)
    assert np.allclose(r["d_minus"], [0.0983, 0.0439, 0.0920, 0.0458], atol=2e-4)
    assert np.allclose(r["scores"], [0.643, 0.268, 0.613, 0.312], atol=1e-3)
    assert mcdm.ranks(r["scores"]).tolist() == [1, 4, 2, 3]


def test_waspas_published_example():
    x = np.array([[30, 23, 5, 0.745, 0.745, 1500, 5000], [18, 13, 15, 0.745, 0.745, 1300, 6000],
                  [15, 12, 10, 0.500, 0.500, 950, 7000], [25, 20, 13, 0.745, 0.745, 1200, 4000],
                  [14, 18, 14, 0.255, 0.745, 950, 3500], [17, 15, 9, 0.745, 0.500, 1250, 5250],
                  [23, 18, 20, 0.500, 0.745, 1100, 3000], [16, 8, 14, 0.255, 0.500, 1500, 3000]])
    w = [0.1181, 0.1181, 0.0445, 0.1181, 0.2861, 0.2861, 0.0445]
    r = mcdm.waspas(x, [True] * 5 + [False] * 2, w, lam=0.5)
    assert np.allclose(r["scores"], [0.8329, 0.7884, 0.6987, 0.8831, 0.7971, 0.7036, 0.8728, 0.5749], atol=5e-5)


# S002 Table 6 (GRA): D*(1), D*(2) as printed (3 significant decimals), gamma(1), gamma(2), psi, rank
S002_T6 = [
    (1.000, 0.965, 1.0000, 0.9346, 0.9726, 1), (0.774, 0.922, 0.6887, 0.8651, 0.7625, 6),
    (0.498, 0.901, 0.4990, 0.8347, 0.6395, 12), (0.896, 0.939, 0.8278, 0.8913, 0.8544, 2),
    (0.633, 0.921, 0.5767, 0.8636, 0.6968, 8), (0.533, 0.995, 0.5171, 0.9901, 0.7151, 7),
    (0.780, 0.932, 0.6944, 0.8803, 0.7722, 5), (0.730, 1.000, 0.6494, 1.0000, 0.7962, 3),
    (0.418, 0.983, 0.4621, 0.9671, 0.6735, 9), (0.757, 0.976, 0.6729, 0.9542, 0.7907, 4),
    (0.581, 0.890, 0.5441, 0.8197, 0.6595, 11), (0.379, 0.782, 0.4460, 0.6964, 0.5508, 17),
    (0.631, 0.880, 0.5754, 0.8065, 0.6721, 10), (0.465, 0.791, 0.4831, 0.7052, 0.5761, 15),
    (0.426, 0.778, 0.4655, 0.6925, 0.5605, 16), (0.516, 0.795, 0.5081, 0.7092, 0.5923, 14),
    (0.538, 0.797, 0.5198, 0.7112, 0.5999, 13), (0.326, 0.683, 0.4259, 0.6120, 0.5038, 18),
    (0.252, 0.620, 0.4006, 0.5682, 0.4708, 19), (0.164, 0.483, 0.3743, 0.4916, 0.4234, 20),
    (0.042, 0.309, 0.3429, 0.4198, 0.3751, 22), (0.137, 0.430, 0.3668, 0.4673, 0.4089, 21),
    (0.051, 0.282, 0.3451, 0.4105, 0.3725, 23), (0.091, 0.197, 0.3549, 0.3837, 0.3670, 25),
    (0.018, 0.257, 0.3374, 0.4023, 0.3646, 26), (0.107, 0.192, 0.3589, 0.3823, 0.3687, 24),
    (0.000, 0.000, 0.3333, 0.3333, 0.3333, 27)]
S002_W = [0.5814, 0.4186]


def test_gra_reproduces_s002_table_6():
    t = np.array(S002_T6)
    # D* is already min-max normalised (each column spans 0..1): as larger-is-better input it is unchanged
    r = mcdm.gra(t[:, :2], [True, True], S002_W)
    assert np.allclose(r["normalized"], t[:, :2], atol=1e-12)
    assert np.allclose(r["coefficient"], t[:, 2:4], atol=1e-4)  # printed to 4 decimals
    assert np.allclose(r["scores"], t[:, 4], atol=1e-4)
    assert mcdm.ranks(r["scores"]).tolist() == t[:, 5].astype(int).tolist()


# S002 Table 13 (WASPAS): n (min a / a) for D and S, Q, P, A as printed (runs 1-6, 18, 27)
S002_T13 = {1: (1.0000, 0.7519, 0.8961, 0.4497, 0.8515), 2: (0.6400, 0.5761, 0.6132, 0.3103, 0.5830),
            3: (0.4444, 0.5173, 0.4749, 0.2400, 0.4514), 6: (0.4622, 0.9532, 0.6677, 0.3171, 0.6326),
            8: (0.5977, 1.0000, 0.7661, 0.3757, 0.7271), 18: (0.3732, 0.2515, 0.3222, 0.1603, 0.3060),
            27: (0.2864, 0.0964, 0.2069, 0.0920, 0.1954)}


def test_saw_and_paper_waspas_reproduce_s002_table_13():
    t = np.array(list(S002_T13.values()))
    x = 1.0 / t[:, :2]  # n = min a / a: the responses up to their scale (runs 1 and 8 hold the minima)
    s = mcdm.saw(x, [False, False], S002_W)
    p = mcdm.waspas_paper(x, [False, False], S002_W, lam=0.9)
    assert np.allclose(s["normalized"], t[:, :2], atol=1e-12)
    assert np.allclose(s["scores"], t[:, 2], atol=1.5e-4)  # Q (= SAW's v_i) printed to 4 decimals
    assert np.allclose(p["P"], t[:, 3], atol=1.5e-4)
    assert np.allclose(p["scores"], t[:, 4], atol=1.5e-4)


def test_topsis_reproduces_s002_table_11():
    # Table 11's n_ij = a/|a| (vector-normalised) and CC for all 27 runs
    n = np.array([
        (0.0767, 0.0535), (0.1198, 0.0698), (0.1725, 0.0777), (0.0964, 0.0633), (0.1469, 0.0700),
        (0.1659, 0.0422), (0.1187, 0.0658), (0.1283, 0.0402), (0.1878, 0.0468), (0.1230, 0.0491),
        (0.1566, 0.0815), (0.1954, 0.1225), (0.1472, 0.0855), (0.1788, 0.1189), (0.1862, 0.1240),
        (0.1691, 0.1173), (0.1650, 0.1167), (0.2055, 0.1598), (0.2195, 0.1833), (0.2364, 0.2349),
        (0.2597, 0.3006), (0.2415, 0.2552), (0.2579, 0.3108), (0.2503, 0.3427), (0.2642, 0.3203),
        (0.2473, 0.3446), (0.2677, 0.4171)])
    cc = [0.9714, 0.8580, 0.7248, 0.9223, 0.7909, 0.7638, 0.8647, 0.8553, 0.7144, 0.8658, 0.7571, 0.6281,
          0.7750, 0.6655, 0.6440, 0.6877, 0.6970, 0.5578, 0.4985, 0.3882, 0.2434, 0.3457, 0.2249, 0.1682,
          0.2023, 0.1679, 0.0000]
    r = mcdm.topsis(n, [False, False], S002_W)
    assert np.allclose(r["normalized"], n, atol=2e-4)  # n is its own vector normalisation up to rounding
    # run 1's printed CC carries the 2-digit rounding of its S+ = 0.0056: 0.1884/(0.0056 + 0.1884) = 0.9711
    assert np.allclose(r["scores"], cc, atol=5e-4)


# ------------------------------------------------------------------ command line
def _csv(path, text):
    path.write_text(text)
    return path


GOOD = "run,acc,force,label\n1,32.7,1345,a\n2,51.1,1756,b\n3,73.6,1956,c\n4,54.8,1012,d\n"


def test_cli_writes_weights_and_four_methods(tmp_path, capsys):
    src = _csv(tmp_path / "r.csv", GOOD)
    out = tmp_path / "out"
    assert main(["study", "mcdm", str(src), "--criteria", "acc:min,force:min", "--weights", "merec",
                 "--out", str(out)]) == 0
    res = json.loads((out / "mcdm.json").read_text())
    x = np.array([[32.7, 1345], [51.1, 1756], [73.6, 1956], [54.8, 1012]])
    assert np.allclose(res["weights"], mcdm.merec_weights(x, [False, False]))
    assert set(res["methods"]) == {"gra", "topsis", "saw", "waspas"}
    for k in res["methods"]:
        assert len(res["methods"][k]["scores"]) == 4 and sorted(res["methods"][k]["ranks"])[0] == 1
    assert res["methods"]["waspas"]["lambda"] == 0.9 and "paper_variant" in res["methods"]["waspas"]
    assert "| 4 |" in (out / "report.md").read_text()
    # explicit weights are scaled to sum 1, in the order of --criteria
    assert main(["study", "mcdm", str(src), "--criteria", "force:min,acc:max", "--weights", "3,1",
                 "--waspas-lambda", "0.5", "--out", str(out)]) == 0
    res = json.loads((out / "mcdm.json").read_text())
    assert res["weights"] == [0.75, 0.25] and res["criteria"][1] == {"name": "acc", "goal": "max"}


@pytest.mark.parametrize("name, text, args, fragment", [
    ("unknown column", GOOD, ["--criteria", "acc:min,speed:min"], "--criteria: unknown column 'speed'"),
    ("bad goal", GOOD, ["--criteria", "acc:low"], "--criteria: 'acc:low'"),
    ("non-numeric", GOOD.replace("51.1", "n/a"), ["--criteria", "acc:min,force:min"], "column 'acc', data row 2"),
    ("weights count", GOOD, ["--criteria", "acc:min,force:min", "--weights", "1,2,3"], "--weights: 3 value(s) for 2"),
    ("negative weight", GOOD, ["--criteria", "acc:min,force:min", "--weights", "1,-2"], "--weights: every weight"),
    ("zero weights", GOOD, ["--criteria", "acc:min,force:min", "--weights", "0,0"], "--weights: the weights"),
    ("constant", "acc,force\n1,2\n1,3\n", ["--criteria", "acc:min,force:min"], "column 'acc' is constant"),
    ("empty file", "", ["--criteria", "acc:min"], "is empty"),
    ("header only", "acc,force\n", ["--criteria", "acc:min"], "no data rows"),
    ("non-positive", "acc,force\n1,2\n0,3\n", ["--criteria", "acc:min,force:min"], "column 'acc' has a value <= 0"),
    ("lambda", GOOD, ["--criteria", "acc:min", "--waspas-lambda", "1.5"], "--waspas-lambda"),
])
def test_cli_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, name, text, args, fragment):
    src = _csv(tmp_path / "r.csv", text)
    out = tmp_path / "out"
    out.mkdir()
    (out / "mcdm.json").write_text("previous")
    assert main(["study", "mcdm", str(src), *args, "--out", str(out)]) == 2
    cap = capsys.readouterr()
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("twin: error:") and fragment in lines[0], (name, cap.err)
    assert cap.out == "" and sorted(p.name for p in out.iterdir()) == ["mcdm.json"]
    assert (out / "mcdm.json").read_text() == "previous"


def test_cli_missing_file(tmp_path, capsys):
    assert main(["study", "mcdm", str(tmp_path / "none.csv"), "--criteria", "a:min", "--out", str(tmp_path / "o")]) == 2
    assert "none.csv" in capsys.readouterr().err and not (tmp_path / "o").exists()


def test_alternatives_are_named_by_a_name_column_kept_in_the_output(tmp_path, capsys):
    # "group" repeats a name and "run" is numbers: the first column of text naming every row once is "label"
    src = _csv(tmp_path / "r.csv", "group,run,acc,force,label\nx,1,32.7,1345,a\nx,2,51.1,1756,b\n"
                                   "y,3,73.6,1956,c\ny,4,54.8,1012,d\n")
    out = tmp_path / "out"
    assert main(["study", "mcdm", str(src), "--criteria", "acc:min,force:min", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    res = json.loads((out / "mcdm.json").read_text())
    assert res["name_column"] == "label" and res["names"] == ["a", "b", "c", "d"]
    best = [res["names"][i] for i, r in enumerate(res["methods"]["topsis"]["ranks"]) if r == 1]
    assert f"topsis  best alternative {', '.join(best)}" in printed
    report = (out / "report.md").read_text()
    assert "| row | label | acc | force |" in report and "| 2 | b | 51.1 | 1756 |" in report
    assert "named by the column `label`" in report and "Best alternative by method: " in report
    # chosen explicitly: a column of numbers may name the rows too
    assert main(["study", "mcdm", str(src), "--criteria", "acc:min,force:min", "--name-column", "run",
                 "--out", str(out)]) == 0
    assert json.loads((out / "mcdm.json").read_text())["names"] == ["1", "2", "3", "4"]


def test_without_a_name_column_alternatives_are_numbered_by_row(tmp_path, capsys):
    src = _csv(tmp_path / "r.csv", "run,acc,force\n1,32.7,1345\n2,51.1,1756\n3,73.6,1956\n")
    res, _ = mcdm.run_mcdm(src, "acc:min,force:min", "equal")
    assert res["name_column"] is None and res["names"] == ["1", "2", "3"]
    assert "Best row by method: GRA 1," in mcdm.report_md(res, _)


@pytest.mark.parametrize("column, fragment", [
    ("lable", "--name-column: unknown column 'lable' (did you mean 'label'?)"),
    ("group", "--name-column: column 'group' must name every row once"),
])
def test_a_bad_name_column_is_one_line(column, fragment, tmp_path, capsys):
    src = _csv(tmp_path / "r.csv", "group,acc,force,label\nx,32.7,1345,a\nx,51.1,1756,b\n")
    out = tmp_path / "out"
    assert main(["study", "mcdm", str(src), "--criteria", "acc:min,force:min", "--name-column", column,
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert fragment in err and err.count("\n") == 1 and not out.exists()
