"""Taguchi analysis of an orthogonal-array experiment (``twin study taguchi-analyze``; S002's method).

S002 varies four factors over three levels in a Taguchi L27 and
analyses the responses by signal-to-noise ratios, main effects, ANOVA and a prediction at the
optimum. This module is that analysis, from a table of runs (factor levels and responses):

* **L27** (:data:`L27`, :func:`l27`): the standard 27-run, 13-column, 3-level orthogonal array
  (Taguchi & Konishi 1987; reproduced in Ross, *Taguchi Techniques for Quality Engineering*, 2nd ed.,
  McGraw-Hill 1996, appendix). Built here from its three base columns a = run // 9,
  b = (run // 3) % 3, c = run % 3 (0-based levels): column k is (α a + β b + γ c) mod 3 with
  (α, β, γ) from :data:`L27_GENERATORS`. Columns 3, 4 carry the interaction of columns 1 and 2,
  6, 7 that of 1 and 5, 9, 10 that of 1 and 8, 12, 13 that of 1 and 11.
* **S002's assignment** (:data:`S002_COLUMNS`): crank length x in column 1, clearance y in column 2,
  friction z in column 5, speed t in column 8; its interactions x*y, x*z, x*t then sit in columns
  3-4, 6-7 and 9-10, and columns 11-13 are free (the 6 degrees of freedom of its ANOVA error). The
  paper does not print its run table; this assignment is the one whose level means of the paper's
  own grey relational grades reproduce its Table 8 (``analysis/s002_paper_tables.py``).
* **S/N ratios** (:func:`sn_ratio`): smaller-the-better ``−10 log10(mean(y²))``, larger-the-better
  ``−10 log10(mean(1/y²))`` over a run's replicates [dB].
* **Main effects**: the mean of the response (or S/N) at each level of each factor.
* **ANOVA** (:func:`anova`): the sum of squares of each term is the squared norm of the projection
  of the centred responses on the term's columns (for a main effect Σ_levels n_l (ȳ_l − ȳ)²; for an
  interaction A*B the two-way cell means' sum of squares less those of A and B); the design must
  make the terms mutually orthogonal (checked; a one-line error names two terms that are not).
  Error = total − terms (the unassigned columns, and the replicates); terms named in ``pool`` are
  added to the error (Taguchi's pooling). F = MS/MS_error, p from ``scipy.stats.f``, contribution =
  SS/SS_total.
* **Prediction at the optimum** (:func:`predict`): the additive model
  ``μ̂ = ȳ + Σ_f (ȳ_f,opt − ȳ)`` over the factors used, with the confidence intervals of Ross (1996,
  Ch. 5; also Roy, *A Primer on the Taguchi Method*, 1990): ``CI_pop = √(F_α(1, f_e) V_e / n_eff)``
  for the mean at the optimum and ``CI_ce = √(F_α(1, f_e) V_e (1/n_eff + 1/R))`` for the mean of R
  confirmation runs, ``n_eff = N / (1 + Σ dof of the effects used)``; V_e and f_e are the (pooled)
  error mean square and its degrees of freedom. S002's Eq. 17 is CI_ce.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from twin.provenance import figure_metadata
from twin.typed import Record
from twin.studies.mcdm import TableError, numeric_column, read_csv_table

#: (α, β, γ) of each L27 column: level = (α a + β b + γ c) mod 3 (0-based), a, b, c the base columns
L27_GENERATORS: tuple[tuple[int, int, int], ...] = (
    (1, 0, 0), (0, 1, 0), (1, 1, 0), (2, 1, 0), (0, 0, 1), (1, 0, 1), (2, 0, 1),
    (0, 1, 1), (1, 1, 1), (2, 1, 1), (0, 2, 1), (1, 2, 1), (2, 2, 1))
#: S002's factors and their L27 columns (1-based)
S002_COLUMNS: dict[str, int] = {"crank_length": 1, "clearance": 2, "friction": 5, "speed": 8}
#: S002's factor levels (Table 3): crank [mm], clearance [mm], friction coefficient [-], speed [rpm]
S002_LEVELS: dict[str, tuple[float, float, float]] = {
    "crank_length": (80.0, 100.0, 120.0), "clearance": (0.1, 0.4, 0.7),
    "friction": (0.01, 0.05, 0.1), "speed": (800.0, 1000.0, 1200.0)}
SN_KINDS = ("smaller", "larger")


def l27() -> np.ndarray:
    """The standard L27(3^13) array, levels 1..3, shape (27, 13)."""
    r = np.arange(27)
    a, b, c = r // 9, (r // 3) % 3, r % 3
    return np.column_stack([(al * a + be * b + ga * c) % 3 for al, be, ga in L27_GENERATORS]) + 1


L27 = l27()


def s002_design() -> dict[str, np.ndarray]:
    """S002's 27 runs: factor name -> its values in run order (units of :data:`S002_LEVELS`)."""
    return {f: np.array(S002_LEVELS[f])[L27[:, col - 1] - 1] for f, col in S002_COLUMNS.items()}


# ------------------------------------------------------------------ S/N and main effects
#: largest and smallest (nonzero) magnitude of a response column the ANOVA takes: its sums of squares of up to
#: ~10^4 runs stay finite and normal (squares of 1e150 overflow near 1e300; of 1e-150 they underflow)
MAX_RESPONSE, MIN_RESPONSE = 1e150, 1e-150


def sn_ratio(y: np.ndarray, kind: str = "smaller") -> np.ndarray:
    """S/N ratio [dB] of each run (rows) over its replicates (columns; a 1-D array is one replicate
    per run): smaller-the-better −10 log10(mean y²), larger-the-better −10 log10(mean 1/y²)."""
    y = np.asarray(y, dtype=float)
    y = y[:, None] if y.ndim == 1 else y
    # scale-free: each run's values are divided by their largest magnitude s before squaring, and 20 log10 s is
    # added back, so that responses of 1e200 (squares overflow) or 1e-200 (squares underflow, 1/y^2 overflows)
    # give the S/N ratio the formula defines
    if kind == "smaller":
        s = np.abs(y).max(axis=1, keepdims=True)
        with np.errstate(divide="ignore", invalid="ignore"):
            return -10.0 * np.log10(np.mean((y / s) ** 2, axis=1)) - 20.0 * np.log10(s[:, 0])
    if kind == "larger":
        if np.any(y == 0):
            raise TableError("'larger': a response of 0 has no larger-the-better S/N ratio", field="sn")
        s = np.abs(y).min(axis=1, keepdims=True)
        return -10.0 * np.log10(np.mean((s / y) ** 2, axis=1)) + 20.0 * np.log10(s[:, 0])
    raise TableError(f"must be one of {', '.join(SN_KINDS)}, got {kind!r}", field="sn")


def level_index(values: Sequence[float], name: str) -> tuple[np.ndarray, list[float]]:
    """Level numbers 0..L−1 of a factor column (its distinct values in increasing order) and the values."""
    v = np.asarray(values, dtype=float)
    u = sorted(set(v.tolist()))
    if len(u) < 2:
        raise TableError(f"column {name!r} has a single level ({u[0]:g}); it cannot be analysed", field="factors")
    return np.searchsorted(np.array(u), v), u


def main_effects(levels: np.ndarray, y: np.ndarray) -> list[list[float]]:
    """Mean of ``y`` at each level of each factor (``levels``: runs x factors, 0-based)."""
    return [[float(y[levels[:, f] == l].mean()) for l in range(int(levels[:, f].max()) + 1)]
            for f in range(levels.shape[1])]


# ------------------------------------------------------------------ ANOVA
def _term_basis(levels: np.ndarray, term: tuple[int, ...], main: dict[int, np.ndarray]) -> np.ndarray:
    """Orthonormal basis of the columns of a term: indicator columns of its levels (or cells),
    centred, with the spaces of its factors' main effects removed for an interaction."""
    cells = levels[:, term[0]] if len(term) == 1 else np.ravel_multi_index(
        tuple(levels[:, f] for f in term), tuple(int(levels[:, f].max()) + 1 for f in term))
    u = np.unique(cells)
    d = (cells[:, None] == u[None, :]).astype(float)
    d -= d.mean(axis=0)
    if len(term) > 1:
        for f in term:
            q = main[f]
            d -= q @ (q.T @ d)
    uu, s, _ = np.linalg.svd(d, full_matrices=False)
    return uu[:, s > 1e-9 * max(1.0, s.max(initial=0.0))]


def anova(levels: np.ndarray, y: np.ndarray, names: Sequence[str],
          interactions: Sequence[tuple[int, int]] = (), pool: Sequence[str] = ()) -> dict[str, Any]:
    """ANOVA of ``y`` (one value per row of ``levels``, runs x factors, 0-based levels).

    Returns ``rows`` (one per term, then ``Error`` and ``Total``: source, dof, ss, ms, f, p,
    contribution_pct, pooled), ``error_dof``, ``error_ms`` and ``summary`` (S, R², adjusted R²,
    PRESS and predicted R² of the model of the unpooled terms). Terms whose names are in ``pool``
    are moved into the error. F and p are None where the error has no degree of freedom.
    """
    from scipy.stats import f as f_dist

    y = np.asarray(y, dtype=float)
    n = y.size
    terms: list[tuple[str, tuple[int, ...]]] = [(names[i], (i,)) for i in range(levels.shape[1])]
    terms += [(f"{names[i]}*{names[j]}", (i, j)) for i, j in interactions]
    unknown = [p for p in pool if p not in {t for t, _ in terms}]
    if unknown:
        raise TableError(f"unknown term(s) {', '.join(unknown)}; terms are {', '.join(t for t, _ in terms)}", field="pool")
    main: dict[int, np.ndarray] = {}
    bases: list[np.ndarray] = []
    for name, term in terms:
        q = _term_basis(levels, term, main)
        if len(term) == 1:
            main[term[0]] = q
        bases.append(q)
    for a in range(len(terms)):
        for b in range(a):
            if np.abs(bases[a].T @ bases[b]).max(initial=0.0) > 1e-8:
                raise TableError(f"terms {terms[b][0]} and {terms[a][0]} are not orthogonal in this "
                                 "design (confounded or unbalanced); this analysis needs an orthogonal array", field="factors")
    yc = y - y.mean()
    ss_total = float(yc @ yc)
    rows = []
    for (name, _), q in zip(terms, bases):
        ss = float(np.sum((q.T @ yc) ** 2))
        rows.append({"source": name, "dof": int(q.shape[1]), "ss": ss, "pooled": name in pool})
    dof_err = (n - 1) - sum(r["dof"] for r in rows if not r["pooled"])
    ss_err = ss_total - sum(r["ss"] for r in rows if not r["pooled"])
    ss_err = max(ss_err, 0.0)
    ms_err = ss_err / dof_err if dof_err > 0 else None
    for r in rows:
        r["ms"] = r["ss"] / r["dof"] if r["dof"] else None
        r["contribution_pct"] = 100.0 * r["ss"] / ss_total if ss_total > 0 else None
        usable = not r["pooled"] and ms_err and r["ms"] is not None
        r["f"] = r["ms"] / ms_err if usable else None
        r["p"] = float(f_dist.sf(r["f"], r["dof"], dof_err)) if usable else None
    rows.append({"source": "Error", "dof": dof_err, "ss": ss_err, "ms": ms_err, "f": None, "p": None,
                 "contribution_pct": 100.0 * ss_err / ss_total if ss_total > 0 else None,
                 "pooled": bool(pool), "pooled_terms": list(pool)})
    rows.append({"source": "Total", "dof": n - 1, "ss": ss_total, "ms": None, "f": None, "p": None,
                 "contribution_pct": 100.0 if ss_total > 0 else None, "pooled": False})
    # model summary of the fitted (unpooled) terms, as Minitab prints it: S = √MS_error, R², adjusted R²,
    # PRESS = Σ (e_i / (1 − h_ii))² with the leverages h_ii of the orthogonal model, predicted R²
    kept = [q for q, r in zip(bases, rows) if not r["pooled"]]
    fit = sum((q @ (q.T @ yc) for q in kept), np.zeros(n))
    e = yc - fit
    h = 1.0 / n + sum((q ** 2).sum(axis=1) for q in kept)
    press = float(np.sum((e / (1.0 - h)) ** 2)) if np.all(h < 1 - 1e-12) else None
    summary = {"s": math.sqrt(ms_err) if ms_err is not None else None,
               "r_sq": 1 - ss_err / ss_total if ss_total > 0 else None,
               "r_sq_adj": 1 - ms_err / (ss_total / (n - 1)) if ms_err is not None and ss_total > 0 else None,
               "press": press,
               "r_sq_pred": 1 - press / ss_total if press is not None and ss_total > 0 else None}
    return {"rows": rows, "error_dof": dof_err, "error_ms": ms_err, "summary": summary}


def predict(levels: np.ndarray, y: np.ndarray, opt: Sequence[int], used: Sequence[int], table: dict[str, Any],
            alpha: float = 0.05, confirmation_runs: int = 1) -> dict[str, Any]:
    """Additive-model prediction of ``y`` at the levels ``opt`` (one per factor) from the factors
    ``used``, with CI_pop and CI_ce of Ross (1996) from the ANOVA ``table`` (None without error dof)."""
    from scipy.stats import f as f_dist

    y = np.asarray(y, dtype=float)
    grand = float(y.mean())
    pred = grand + sum(float(y[levels[:, f] == opt[f]].mean()) - grand for f in used)
    dof_used = sum(int(levels[:, f].max()) for f in used)
    n_eff = y.size / (1 + dof_used)
    out: dict[str, Any] = {"predicted": pred, "grand_mean": grand, "n_eff": n_eff, "alpha": alpha,
                           "confirmation_runs": confirmation_runs, "ci_pop": None, "ci_ce": None, "f_crit": None}
    fe, ve = table["error_dof"], table["error_ms"]
    if fe > 0 and ve is not None:
        fc = float(f_dist.ppf(1 - alpha, 1, fe))
        out.update(f_crit=fc, ci_pop=math.sqrt(fc * ve / n_eff),
                   ci_ce=math.sqrt(fc * ve * (1 / n_eff + 1 / confirmation_runs)))
    return out


def analyze(levels: np.ndarray, y: np.ndarray, names: Sequence[str], goal: str = "min",
            interactions: Sequence[tuple[int, int]] = (), pool: Sequence[str] = (),
            used: Sequence[int] | None = None, alpha: float = 0.05, confirmation_runs: int = 1) -> dict[str, Any]:
    """Main effects, ANOVA, optimum levels (``goal`` min or max of the level means) and the
    prediction there, for one series ``y`` (raw responses or S/N ratios)."""
    me = main_effects(levels, y)
    opt = [int(np.argmin(m) if goal == "min" else np.argmax(m)) for m in me]
    tab = anova(levels, y, names, interactions, pool)
    used = list(range(levels.shape[1])) if used is None else list(used)
    delta = [max(m) - min(m) for m in me]
    order = sorted(range(len(me)), key=lambda f: -delta[f])
    return {"main_effects": me, "delta": delta, "rank": [order.index(f) + 1 for f in range(len(me))],
            "optimum_levels": opt, "anova": tab,
            "prediction": predict(levels, y, opt, used, tab, alpha, confirmation_runs) | {
                "factors_used": [names[f] for f in used]}}


# ------------------------------------------------------------------ study from a CSV of runs
def _fmt(v: Any, spec: str = ".4g") -> str:
    return "" if v is None else format(v, spec)


def _anova_md(tab: dict[str, Any]) -> list[str]:
    lines = ["| source | dof | SS | MS | F | p | contribution |", "|---|---|---|---|---|---|---|"]
    for r in tab["rows"]:
        src = r["source"] + (" (pooled)" if r["pooled"] and r["source"] not in ("Error", "Total") else "")
        if r["source"] == "Error" and r.get("pooled_terms"):
            src += " (pooled: " + ", ".join(r["pooled_terms"]) + ")"
        lines.append(f"| {src} | {r['dof']} | {_fmt(r['ss'], '.6g')} | {_fmt(r['ms'], '.6g')} | {_fmt(r['f'], '.4g')} "
                     f"| {_fmt(r['p'], '.3g')} | {_fmt(r['contribution_pct'], '.2f')} % |")
    return lines


def _analysis_md(title: str, a: dict[str, Any], names: Sequence[str], values: Sequence[Sequence[float]], unit: str) -> list[str]:
    nl = max(len(v) for v in values)
    lines = [f"### {title}", "", "| factor | " + " | ".join(f"level {i + 1}" for i in range(nl)) + " | delta | rank | best level |",
             "|" + "---|" * (nl + 4)]
    for f, name in enumerate(names):
        me = a["main_effects"][f]
        cells = [f"{m:.5g} ({values[f][i]:g})" for i, m in enumerate(me)] + [""] * (nl - len(me))
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {a['delta'][f]:.4g} | {a['rank'][f]} | "
                     f"{a['optimum_levels'][f] + 1} ({values[f][a['optimum_levels'][f]]:g}) |")
    p = a["prediction"]
    lines += ["", *_anova_md(a["anova"]), "",
              f"Prediction at the best levels (additive model over {', '.join(p['factors_used'])}): "
              f"{p['predicted']:.5g} {unit} (grand mean {p['grand_mean']:.5g}, n_eff = {p['n_eff']:.4g})"
              + (f"; {100 * (1 - p['alpha']):g} % interval of the mean ±{p['ci_pop']:.4g}, of "
                 f"{p['confirmation_runs']} confirmation run(s) ±{p['ci_ce']:.4g} "
                 f"(F({1 - p['alpha']:.2f}; 1, {a['anova']['error_dof']}) = {p['f_crit']:.4f})."
                 if p["ci_pop"] is not None else "; no confidence interval: the error has no degree of freedom "
                 "(pool terms into the error: the option pool)."), ""]
    return lines


def _plot(path: Path, title: str, names: Sequence[str], values: Sequence[Sequence[float]],
          me: Sequence[Sequence[float]], ylabel: str) -> None:
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from twin.util import atomic_write_bytes

    fig, axes = plt.subplots(1, len(names), figsize=(2.6 * len(names) + 1, 3.2), sharey=True, squeeze=False)
    allm = [v for m in me for v in m]
    grand = float(np.mean(allm))
    for ax, name, v, m in zip(axes[0], names, values, me):
        ax.plot(range(len(m)), m, "o-")
        ax.axhline(grand, color="grey", lw=0.8, ls="--")
        ax.set_xticks(range(len(m)), [f"{x:g}" for x in v])
        ax.set_xlabel(name)
    axes[0][0].set_ylabel(ylabel)
    fig.suptitle(title)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100, metadata=figure_metadata())
    plt.close(fig)
    atomic_write_bytes(path, buf.getvalue())


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name)


def parse_interactions(text: str | None, names: Sequence[str]) -> list[tuple[int, int]]:
    """``A*B,…`` as pairs of factor indices."""
    out: list[tuple[int, int]] = []
    for item in (s.strip() for s in (text or "").split(",") if s.strip()):
        parts = item.split("*")
        if len(parts) != 2 or any(p not in names for p in parts) or parts[0] == parts[1]:
            raise TableError(f"{item!r} must be A*B with two different factors of `factors` "
                             f"({', '.join(names)})", field="interactions")
        pair = (names.index(parts[0]), names.index(parts[1]))
        if pair in out or pair[::-1] in out:
            raise TableError(f"{item!r} is given twice", field="interactions")
        out.append(pair)
    return out


def run_analysis(csv_path: str | Path, responses: str, factors: str, sn: str = "smaller",
                 interactions: str | None = None, pool: str | None = None, predict_with: str | None = None,
                 alpha: float = 0.05, confirmation_runs: int = 1) -> dict[str, Any]:
    """Read and analyse: the result that ``taguchi.json`` holds."""
    if sn not in SN_KINDS:
        raise TableError(f"must be one of {', '.join(SN_KINDS)}, got {sn!r}", field="sn")
    if not 0 < alpha < 1:
        raise TableError(f"must lie in (0, 1), got {alpha!r}", field="alpha")
    if confirmation_runs < 1:
        raise TableError(f"must be >= 1, got {confirmation_runs!r}", field="confirmation_runs")
    header, rows = read_csv_table(csv_path)
    fnames = [s.strip() for s in factors.split(",") if s.strip()]
    if not fnames or len(set(fnames)) != len(fnames):
        raise TableError(f"need distinct column names, got {factors!r}", field="factors")
    cols = [level_index(numeric_column(header, rows, f, "factors"), f) for f in fnames]
    levels = np.column_stack([c[0] for c in cols])
    values = [c[1] for c in cols]
    inter = parse_interactions(interactions, fnames)
    pooled = [s.strip() for s in (pool or "").split(",") if s.strip()]
    used = list(range(len(fnames)))
    if predict_with:
        want = [s.strip() for s in predict_with.split(",") if s.strip()]
        bad = [w for w in want if w not in fnames]
        if bad or not want:
            raise TableError(f"{', '.join(bad) or repr(predict_with)} not among `factors` ({', '.join(fnames)})", field="predict_with")
        used = [fnames.index(w) for w in want]
    specs = [s.strip() for s in responses.split(",") if s.strip()]
    if not specs:
        raise TableError("at least one column is needed", field="responses")
    res: dict[str, Any] = {"input": str(csv_path), "runs": len(rows), "factors": fnames,
                           "levels": values, "sn": sn, "interactions": [f"{fnames[i]}*{fnames[j]}" for i, j in inter],
                           "pooled": pooled, "responses": {}}
    goal = "min" if sn == "smaller" else "max"
    for spec in specs:
        reps = [c.strip() for c in spec.split("+")]
        y = np.column_stack([numeric_column(header, rows, c, "responses") for c in reps])
        if sn == "smaller" and np.all(y == 0):
            raise TableError(f"{spec!r} is 0 in every run", field="responses")
        top = float(np.abs(y).max())
        if top > 0 and not MIN_RESPONSE <= top <= MAX_RESPONSE:
            raise TableError(f"column {spec!r} has magnitudes up to {top:g}: outside "
                             f"[{MIN_RESPONSE:g}, {MAX_RESPONSE:g}] its sums of squares (ANOVA) are not representable "
                             "in floating point; give it in another unit", field="responses")
        s = sn_ratio(y, sn)
        if not np.all(np.isfinite(s)):
            raise TableError(f"{spec!r} gives an S/N ratio that is not finite (a run of zeros)", field="responses")
        obs_levels = np.repeat(levels, y.shape[1], axis=0)
        raw = analyze(obs_levels, y.ravel(), fnames, goal, inter, pooled, used, alpha, confirmation_runs)
        sna = analyze(levels, s, fnames, "max", inter, pooled, used, alpha, confirmation_runs)
        res["responses"][spec] = {"replicates": reps, "sn_ratio": s.tolist(), "raw": raw, "sn_analysis": sna}
    return res


def report_md(res: dict[str, Any]) -> str:
    names, values = res["factors"], res["levels"]
    lines = ["# Taguchi analysis", "",
             f"Input: `{res['input']}`, {res['runs']} runs; factors {', '.join(names)}"
             + (f"; interactions {', '.join(res['interactions'])}" if res["interactions"] else "")
             + (f"; pooled into the error: {', '.join(res['pooled'])}" if res["pooled"] else "") + ".", "",
             f"S/N ratio: {res['sn']}-the-better, "
             + ("-10 log10(mean(y^2))" if res["sn"] == "smaller" else "-10 log10(mean(1/y^2))")
             + " [dB] over a run's replicates; the best level of a factor has the largest mean S/N "
               f"(and the {'smallest' if res['sn'] == 'smaller' else 'largest'} mean response). Sums of squares "
               "are those of the orthogonal terms; the error is the rest (free columns, replicates, pooled terms); "
               "p from the F distribution. Confidence intervals: Ross (1996), n_eff = N/(1 + dof of the effects used).", ""]
    for spec, r in res["responses"].items():
        lines += [f"## {spec}", ""]
        lines += _analysis_md("Means of the response", r["raw"], names, values, "")
        lines += _analysis_md("S/N ratios [dB]", r["sn_analysis"], names, values, "dB")
    return "\n".join(lines)


@dataclass(frozen=True)
class TaguchiOptions:
    """What :func:`run_study` analyses (the texts are parsed and checked by :func:`run_analysis`).

    Attributes:
        csv_path: CSV with a header row, one row per run.
        responses: response columns ``COL,…``; ``COL1+COL2`` names the replicates of one response.
        factors: factor columns ``COL,…`` (their distinct values are the levels).
        out: output folder (created if missing).
        sn: S/N ratio kind, smaller or larger (the better).
        interactions: two-factor interactions ``A*B,…`` in the ANOVA.
        pool: terms pooled into the error ``TERM,…``.
        predict_with: factors of the prediction at the optimum (default all).
        alpha: significance level of the intervals, in (0, 1).
        confirmation_runs: R of the confirmation-run interval (>= 1).
    """

    csv_path: str | Path
    responses: str
    factors: str
    out: str | Path
    sn: str = "smaller"
    interactions: str | None = None
    pool: str | None = None
    predict_with: str | None = None
    alpha: float = 0.05
    confirmation_runs: int = 1


@dataclass(frozen=True)
class Prediction(Record):
    """The additive model's prediction at the optimum levels (:func:`predict`).

    Attributes:
        predicted: the predicted value [the series' unit]; grand_mean: the series' mean; n_eff: the effective
            number of replications [-]; alpha: the significance level; confirmation_runs: runs the CI_ce is for;
        ci_pop, ci_ce: the half-widths of the confidence intervals of Ross (1996) (None without error dof);
        f_crit: the F quantile they use (None likewise); factors_used: the factors the prediction adds.
    """

    predicted: float
    grand_mean: float
    n_eff: float
    alpha: float
    confirmation_runs: int
    ci_pop: float | None
    ci_ce: float | None
    f_crit: float | None
    factors_used: tuple[str, ...]


@dataclass(frozen=True)
class SeriesAnalysis(Record):
    """The analysis of one series, the raw response or its S/N ratio (:func:`analyze`).

    Attributes:
        main_effects: per factor the series' mean at each level; delta: per factor its range; rank: per factor its
            rank by delta (1 largest); optimum_levels: per factor the best level (index).
        anova: the ANOVA table (:func:`anova`: ``rows`` with each source's ``dof``, ``ss``, ``ms``, ``f``, ``p``,
            ``contribution_pct`` and ``pooled``, the error's ``error_dof`` and ``error_ms``, a ``summary``), kept as
            the table it is: its rows differ in their keys (the error and total rows).
        prediction: the prediction at the optimum levels.
    """

    _NESTED = {"prediction": Prediction}

    main_effects: tuple[tuple[float, ...], ...]
    delta: tuple[float, ...]
    rank: tuple[int, ...]
    optimum_levels: tuple[int, ...]
    anova: dict[str, Any]
    prediction: Prediction


@dataclass(frozen=True)
class ResponseAnalysis(Record):
    """One response of the study (``taguchi.json``'s ``responses[spec]``).

    Attributes:
        replicates: the columns averaged into it; sn_ratio: per run its S/N ratio [dB];
        raw, sn_analysis: the analysis of the raw response and of the S/N ratio.
    """

    _NESTED = {"raw": SeriesAnalysis, "sn_analysis": SeriesAnalysis}

    replicates: tuple[str, ...]
    sn_ratio: tuple[float, ...]
    raw: SeriesAnalysis
    sn_analysis: SeriesAnalysis


@dataclass(frozen=True)
class TaguchiResult:
    """The analysis (``taguchi.json``): per response (:class:`ResponseAnalysis`) its S/N ratios, main effects,
    ANOVA and the prediction at the best levels, for the raw response and for the S/N ratio. Dicts given for the
    responses are read into those."""

    input: str
    runs: int
    factors: list[str]
    levels: list[list[float]]
    sn: str
    interactions: list[str]
    pooled: list[str]
    responses: dict[str, ResponseAnalysis]
    figures: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "responses", {k: r if isinstance(r, ResponseAnalysis) else
                                               ResponseAnalysis.from_dict(r) for k, r in self.responses.items()})

    def to_dict(self) -> dict[str, Any]:
        """The JSON data of ``taguchi.json``."""
        return {"input": self.input, "runs": self.runs, "factors": self.factors, "levels": self.levels, "sn": self.sn,
                "interactions": self.interactions, "pooled": self.pooled,
                "responses": {k: r.to_dict() for k, r in self.responses.items()}, "figures": list(self.figures)}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "TaguchiResult":
        """The result of ``taguchi.json``'s data (its provenance stamp ignored)."""
        return cls(d["input"], d["runs"], d["factors"], d["levels"], d["sn"], d["interactions"], d["pooled"],
                   d["responses"], tuple(d.get("figures", ())))


def run_study(options: TaguchiOptions) -> TaguchiResult:
    """Analyse ``options.csv_path`` and write ``taguchi.json``, ``report.md`` and per response its
    main-effect and S/N PNGs to ``options.out``."""
    from twin.provenance import stamped, with_stamp_line
    from twin.util import atomic_write_json, atomic_write_text, check_not_input

    o = options
    res = run_analysis(o.csv_path, o.responses, o.factors, o.sn, o.interactions, o.pool, o.predict_with, o.alpha,
                       o.confirmation_runs)
    out = Path(o.out)
    # every file this writes, checked against the inputs before the first is written (an input CSV named like
    # an output, in the output folder, would otherwise be refused only after the figures)
    names = [f"{kind}_{_safe(spec)}.png" for spec in res["responses"] for kind in ("main_effects", "sn")]
    for name in (*names, "taguchi.json", "report.md"):
        check_not_input(out / name, "out")
    out.mkdir(exist_ok=True)
    figs = []
    for spec, r in res["responses"].items():
        for key, kind, ylabel in (("raw", "main_effects", f"mean of {spec}"), ("sn_analysis", "sn", "mean S/N [dB]")):
            name = f"{kind}_{_safe(spec)}.png"
            _plot(out / name, f"{'Main effects' if kind == 'main_effects' else 'S/N ratios'}: {spec}",
                  res["factors"], res["levels"], r[key]["main_effects"], ylabel)
            figs.append(name)
    res["figures"] = figs
    atomic_write_json(out / "taguchi.json", stamped(res))
    atomic_write_text(out / "report.md", with_stamp_line(report_md(res)))
    return TaguchiResult(**{**res, "figures": tuple(figs)})
