"""Taguchi analysis (twin/studies/taguchi.py) and ``twin study taguchi-analyze``.

Independent bases: the combinatorics of the orthogonal array (every pair of columns holds every
level pair equally often; a few rows of the standard table as printed, e.g. Ross 1996, appendix);
closed forms (an exactly additive response is recovered exactly, also at a level combination the
array does not contain; sums of squares of a balanced one-way layout; the interaction of columns
1 and 2 lives in columns 3 and 4); least squares on indicator variables for the sums of squares;
the regularized incomplete beta function for F probabilities; the F table value the paper quotes
(F0.05(1, 6) = 5.9874); and S002's own Tables 8-10 from its printed grey relational coefficients.
"""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
from scipy.special import betainc

from twin.cli import main
from twin.studies import taguchi

# rows of the standard L27 table as printed (run number: 13 levels)
PRINTED_ROWS = {
    1: "1111111111111", 2: "1111222222222", 4: "1222111222333", 10: "2123123123123",
    14: "2231231312123", 19: "3132132132132", 23: "3213213321132", 27: "3321321213132"}
S002 = (1, 2, 5, 8)  # x, y, z, t columns


def test_l27_is_the_standard_orthogonal_array():
    a = taguchi.L27
    assert a.shape == (27, 13) and set(np.unique(a)) == {1, 2, 3}
    for run, row in PRINTED_ROWS.items():
        assert "".join(map(str, a[run - 1])) == row, run
    for i, j in itertools.combinations(range(13), 2):  # every level pair 3 times in every column pair
        pairs = np.bincount((a[:, i] - 1) * 3 + a[:, j] - 1, minlength=9)
        assert pairs.tolist() == [3] * 9, (i + 1, j + 1)
    assert all(np.bincount(a[:, c])[1:].tolist() == [9, 9, 9] for c in range(13))


def test_s002_design_levels():
    d = taguchi.s002_design()
    assert [d[f][0] for f in ("crank_length", "clearance", "friction", "speed")] == [80, 0.1, 0.01, 800]
    assert sorted(set(d["speed"])) == [800, 1000, 1200] and len(set(zip(*d.values()))) == 27


def test_sn_ratios_closed_form():
    # smaller: y = (1, 3): mean y^2 = 5 -> -10 log10 5 = -6.98970; one value y: -20 log10 y
    assert taguchi.sn_ratio(np.array([[1.0, 3.0]]), "smaller")[0] == pytest.approx(-6.989700, abs=1e-6)
    assert taguchi.sn_ratio(np.array([10.0]), "smaller")[0] == pytest.approx(-20.0)
    # larger: y = (1, 2): mean 1/y^2 = 0.625 -> -10 log10 0.625 = 2.04120
    assert taguchi.sn_ratio(np.array([[1.0, 2.0]]), "larger")[0] == pytest.approx(2.041200, abs=1e-6)


def _levels(cols=S002):
    return np.column_stack([taguchi.L27[:, c - 1] - 1 for c in cols])


EFFECTS = np.array([[-3.0, 1.0, 2.0], [-0.5, 0.25, 0.25], [-2.0, 1.0, 1.0], [0.3, -0.6, 0.3]])


def test_additive_response_is_recovered_exactly():
    lv = _levels()
    mu = 10.0
    y = mu + sum(EFFECTS[f][lv[:, f]] for f in range(4))
    a = taguchi.analyze(lv, y, "xyzt", goal="min")
    assert np.allclose(a["main_effects"], mu + EFFECTS, atol=1e-12)
    tab = {r["source"]: r for r in a["anova"]["rows"]}
    for f, name in enumerate("xyzt"):  # balanced one-way SS: 9 runs per level
        assert tab[name]["ss"] == pytest.approx(9 * np.sum(EFFECTS[f] ** 2), rel=1e-12)
    assert tab["Error"]["ss"] == pytest.approx(0, abs=1e-20) and tab["Error"]["dof"] == 18
    # the best combination (levels 1, 1, 1, 2) is not a run of the array: the additive model reaches it
    opt = a["optimum_levels"]
    assert opt == [0, 0, 0, 1]
    assert not any((lv == opt).all(axis=1))
    assert a["prediction"]["predicted"] == pytest.approx(mu + sum(EFFECTS[f][opt[f]] for f in range(4)), abs=1e-12)
    assert a["prediction"]["n_eff"] == pytest.approx(27 / 9)


def _ss_by_least_squares(lv, y, terms):
    """SS of each term as the rise of the residual sum of squares when it is dropped from a least
    squares fit on indicator variables (numpy.linalg.lstsq), independent of the projection code."""
    def design(ts):
        cols = [np.ones(len(y))]
        for t in ts:
            cells = lv[:, t[0]] if len(t) == 1 else lv[:, t[0]] * 3 + lv[:, t[1]]
            cols += [(cells == c).astype(float) for c in np.unique(cells)]
            if len(t) == 2:  # interaction cells plus their main effects
                cols += [(lv[:, f] == l).astype(float) for f in t for l in range(3)]
        return np.column_stack(cols)

    def rss(ts):
        x = design(ts)
        beta = np.linalg.lstsq(x, y, rcond=None)[0]
        return float(np.sum((y - x @ beta) ** 2))

    full = rss(terms)
    out = {}
    for t in terms:
        rest = [u for u in terms if u != t]
        if len(t) == 1:  # keep the interactions' marginal columns out of a main effect's test
            rest = [u for u in rest if t[0] not in u]
        out[t] = rss(rest) - full if len(t) == 2 else rss([u for u in terms if u != t and len(u) == 1]) - rss(
            [u for u in terms if len(u) == 1])
    return out, full


def test_anova_sums_of_squares_match_least_squares_and_add_up():
    rng = np.random.default_rng(11)
    lv = _levels()
    y = rng.normal(size=27) + 2 * lv[:, 0] + lv[:, 0] * lv[:, 2] * 0.5
    inter = [(0, 1), (0, 2), (0, 3)]
    tab = taguchi.anova(lv, y, "xyzt", inter)
    rows = {r["source"]: r for r in tab["rows"]}
    terms = [(0,), (1,), (2,), (3,), (0, 1), (0, 2), (0, 3)]
    ls, rss_full = _ss_by_least_squares(lv, y, terms)
    names = ["x", "y", "z", "t", "x*y", "x*z", "x*t"]
    for t, n in zip(terms, names):
        assert rows[n]["ss"] == pytest.approx(ls[t], rel=1e-9), n
    assert rows["Error"]["ss"] == pytest.approx(rss_full, rel=1e-9) and rows["Error"]["dof"] == 6
    assert sum(rows[n]["ss"] for n in names) + rows["Error"]["ss"] == pytest.approx(rows["Total"]["ss"], rel=1e-12)
    assert sum(rows[n]["contribution_pct"] for n in names + ["Error"]) == pytest.approx(100.0)
    for n in names:  # F survival function as a regularized incomplete beta: I_{d2/(d2+d1 F)}(d2/2, d1/2)
        d1, d2, f = rows[n]["dof"], 6, rows[n]["f"]
        assert rows[n]["p"] == pytest.approx(betainc(d2 / 2, d1 / 2, d2 / (d2 + d1 * f)), rel=1e-9)


@pytest.mark.parametrize("cols", [(1, 2, 3, 4), (1, 5, 6, 7), (1, 8, 9, 10), (1, 11, 12, 13)])
def test_interaction_columns_of_the_l27(cols):
    # the interaction of columns i and j of the L27 is carried by two further columns (the standard
    # interaction table): its SS equals the SS of those two columns taken as factors
    rng = np.random.default_rng(2)
    y = rng.normal(size=27)
    lv = _levels(cols)
    tab = {r["source"]: r for r in taguchi.anova(lv[:, :2], y, "ab", [(0, 1)])["rows"]}
    by_col = {r["source"]: r for r in taguchi.anova(lv, y, "abcd")["rows"]}
    assert tab["a*b"]["ss"] == pytest.approx(by_col["c"]["ss"] + by_col["d"]["ss"], rel=1e-12)
    assert tab["a*b"]["dof"] == 4


def test_pooling_moves_terms_into_the_error():
    rng = np.random.default_rng(4)
    lv = _levels()
    y = rng.normal(size=27) + lv[:, 0]
    plain = {r["source"]: r for r in taguchi.anova(lv, y, "xyzt")["rows"]}
    pooled = taguchi.anova(lv, y, "xyzt", pool=["y", "t"])
    rows = {r["source"]: r for r in pooled["rows"]}
    assert pooled["error_dof"] == 18 + 4
    assert rows["Error"]["ss"] == pytest.approx(plain["Error"]["ss"] + plain["y"]["ss"] + plain["t"]["ss"])
    assert rows["y"]["f"] is None and rows["x"]["f"] == pytest.approx(rows["x"]["ms"] / rows["Error"]["ms"])


def test_confidence_interval_formula():
    # F0.05(1, 6) = 5.9874 as in the F table S002 quotes; CI_ce = sqrt(F Ve (1/n_eff + 1/R)), CI_pop = sqrt(F Ve/n_eff)
    rng = np.random.default_rng(8)
    lv = _levels()
    y = rng.normal(size=27) + lv[:, 0]
    tab = taguchi.anova(lv, y, "xyzt", [(0, 1), (0, 2), (0, 3)])
    p = taguchi.predict(lv, y, [0, 0, 0, 0], [0, 1, 2, 3], tab, alpha=0.05, confirmation_runs=1)
    assert p["f_crit"] == pytest.approx(5.9874, abs=5e-5)
    ve = tab["error_ms"]
    assert p["ci_ce"] == pytest.approx(np.sqrt(5.987378 * ve * (1 / 3 + 1)), rel=1e-6)
    assert p["ci_pop"] == pytest.approx(np.sqrt(5.987378 * ve / 3), rel=1e-6)


def test_confounded_terms_are_refused():
    lv = _levels((1, 2, 3))  # a factor in column 3 sits on the interaction of columns 1 and 2
    with pytest.raises(taguchi.TableError, match="a\\*b.*not orthogonal|not orthogonal"):
        taguchi.anova(lv, np.arange(27.0), "abc", [(0, 1)])


# S002 Table 6: grey relational coefficients gamma(1), gamma(2) as printed
S002_GAMMA = [
    (1.0000, 0.9346), (0.6887, 0.8651), (0.4990, 0.8347), (0.8278, 0.8913), (0.5767, 0.8636), (0.5171, 0.9901),
    (0.6944, 0.8803), (0.6494, 1.0000), (0.4621, 0.9671), (0.6729, 0.9542), (0.5441, 0.8197), (0.4460, 0.6964),
    (0.5754, 0.8065), (0.4831, 0.7052), (0.4655, 0.6925), (0.5081, 0.7092), (0.5198, 0.7112), (0.4259, 0.6120),
    (0.4006, 0.5682), (0.3743, 0.4916), (0.3429, 0.4198), (0.3668, 0.4673), (0.3451, 0.4105), (0.3549, 0.3837),
    (0.3374, 0.4023), (0.3589, 0.3823), (0.3333, 0.3333)]
S002_T8 = [(0.7861, 0.6310, 0.3931), (0.6422, 0.5961, 0.5719), (0.6669, 0.5998, 0.5435), (0.6424, 0.6033, 0.5645)]
S002_T9_SS = {"x": 0.704990, "y": 0.023005, "z": 0.068661, "t": 0.027308}


def test_s002_tables_8_and_9_from_its_printed_coefficients():
    # The grade of S002's Taguchi part is the equal-weight mean of its gammas (run 1: 0.9673, its
    # "optimal value 0.967"); the paper does not print it, and its Table 8 lies a uniform +0.0004
    # above these means (7e-4 covers that offset plus the 4-decimal rounding of the gammas).
    g = np.array(S002_GAMMA).mean(axis=1)
    lv = _levels()
    a = taguchi.analyze(lv, g, "xyzt", "max", [(0, 1), (0, 2), (0, 3)])
    assert np.allclose(a["main_effects"], S002_T8, atol=7e-4)
    rows = {r["source"]: r for r in a["anova"]["rows"]}
    # The paper's grades differ from these by more than the rounding of the gammas (x: 0.12 %, where
    # rounding bounds the change of SS by 2 sqrt(SS) sqrt(27) 5e-5 = 0.06 %): its main-effect sums of
    # squares are checked to 0.2 %; its interaction entries differ more (x*y 2.3 %, x*z 0.7 %) and are
    # reported in analysis/results/s002/README.md, not asserted here.
    for k, ss in S002_T9_SS.items():
        assert rows[k]["ss"] == pytest.approx(ss, rel=2e-3), k
    # its prediction: Table 8's level-1 means less 3 x its grand mean 0.6034 = 0.9273 (we: 0.9269)
    assert a["prediction"]["predicted"] == pytest.approx(0.9273 - 0.0004, abs=1e-4)
    # and no other column than 8 carries speed (t): the level means of every other column are further off
    err = [np.abs(np.array([g[taguchi.L27[:, c] == l].mean() for l in (1, 2, 3)]) - S002_T8[3]).max() for c in range(13)]
    assert int(np.argmin(err)) == 7 and sorted(err)[1] > 10 * min(err)


# ------------------------------------------------------------------ command line
def _write_csv(path, noise=0.0):
    d = taguchi.s002_design()
    lv = _levels()
    rng = np.random.default_rng(0)
    y1 = 50 + sum(EFFECTS[f][lv[:, f]] for f in range(4)) + noise * rng.normal(size=27)
    y2 = y1 * 1.1
    lines = ["crank,clearance,mu,rpm,acc_a,acc_b,force"]
    for i in range(27):
        lines.append(f"{d['crank_length'][i]:g},{d['clearance'][i]:g},{d['friction'][i]:g},{d['speed'][i]:g},"
                     f"{y1[i]:.6f},{y2[i]:.6f},{100 + 3 * y1[i]:.6f}")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_cli_taguchi_analyze(tmp_path, capsys):
    src = _write_csv(tmp_path / "runs.csv", noise=0.5)
    out = tmp_path / "out"
    assert main(["study", "taguchi-analyze", str(src), "--responses", "acc_a+acc_b,force",
                 "--factors", "crank,clearance,mu,rpm", "--interactions", "crank*clearance",
                 "--pool", "rpm", "--out", str(out)]) == 0
    res = json.loads((out / "taguchi.json").read_text())
    assert set(res["responses"]) == {"acc_a+acc_b", "force"}
    r = res["responses"]["acc_a+acc_b"]
    assert r["replicates"] == ["acc_a", "acc_b"] and len(r["sn_ratio"]) == 27
    rows = {x["source"]: x for x in r["raw"]["anova"]["rows"]}
    assert rows["Total"]["dof"] == 53 and rows["rpm"]["pooled"]  # 27 runs x 2 replicates
    assert r["sn_analysis"]["optimum_levels"] == [0, 0, 0, 1]
    for f in res["figures"]:
        assert (out / f).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(res["figures"]) == 4 and "## force" in (out / "report.md").read_text()


@pytest.mark.parametrize("args, fragment", [
    (["--responses", "acc_a", "--factors", "crank,speed"], "--factors: unknown column 'speed'"),
    (["--responses", "nope", "--factors", "crank"], "--responses: unknown column 'nope'"),
    (["--responses", "acc_a", "--factors", "crank,clearance", "--interactions", "crank+clearance"], "--interactions"),
    (["--responses", "acc_a", "--factors", "crank,clearance", "--pool", "mu"], "--pool: unknown term(s) mu"),
    (["--responses", "acc_a", "--factors", "crank,one"], "column 'one' has a single level"),
    (["--responses", "acc_a", "--factors", "crank,bad"], "column 'bad', data row 5"),
    (["--responses", "acc_a", "--factors", "crank,clearance,c3", "--interactions", "crank*clearance"],
     "not orthogonal"),
])
def test_cli_taguchi_bad_input(tmp_path, capsys, args, fragment):
    src = _write_csv(tmp_path / "runs.csv")
    text = src.read_text().splitlines()
    lv = taguchi.L27
    text[0] += ",one,bad,c3"
    for i in range(27):
        text[i + 1] += f",1,{'x' if i == 4 else lv[i, 0]},{lv[i, 2]}"
    src.write_text("\n".join(text) + "\n")
    out = tmp_path / "out"
    assert main(["study", "taguchi-analyze", str(src), *args, "--out", str(out)]) == 2
    cap = capsys.readouterr()
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("twin: error:") and fragment in lines[0], cap.err
    assert not out.exists()
