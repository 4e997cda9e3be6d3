"""Multi-criteria decision making over a table of responses (``twin study mcdm``; S002's methods).

S002 ranks the 27 runs of its Taguchi L27 by two smaller-the-better
responses (the slider's maximum acceleration and the contact force in the revolute clearance joint)
with four methods, the criteria weighted by MEREC. This module implements them from their
original definitions, as pure functions of a decision matrix ``x`` (m alternatives in rows,
n criteria in columns, every value > 0), a benefit flag per criterion (True: larger is better,
False: smaller is better, a *cost* criterion) and weights ``w`` (n values ≥ 0; the CLI scales them
to sum 1, the functions use them as given):

* **MEREC** (Keshavarz-Ghorabaee, Amiri, Zavadskas, Turskis & Antucheviciene 2021, *Symmetry*
  13:525), :func:`merec_weights`: ``n_ij = min_k x_kj / x_ij`` for a benefit criterion,
  ``x_ij / max_k x_kj`` for a cost criterion (so that every n_ij is in (0, 1] and smaller is
  better); the overall performance ``S_i = ln(1 + (1/n) Σ_j |ln n_ij|)``; the performance with
  criterion j removed ``S'_ij = ln(1 + (1/n) Σ_{k≠j} |ln n_ik|)`` (the divisor stays n); the removal
  effect ``E_j = Σ_i |S'_ij − S_i|``; ``w_j = E_j / Σ_k E_k``.
* **GRA**, grey relational analysis (Deng 1989; as used with Taguchi designs, e.g. Lin & Lin 2002,
  *Int. J. Mach. Tools Manuf.* 42:237), :func:`gra`: min-max normalisation
  ``x* = (x − min)/(max − min)`` (benefit) or ``(max − x)/(max − min)`` (cost); deviation from the
  ideal sequence ``Δ_ij = |1 − x*_ij|``; grey relational coefficient
  ``γ_ij = (Δmin + ξ Δmax)/(Δ_ij + ξ Δmax)`` with Δmin, Δmax the smallest and largest Δ over the
  whole matrix and the distinguishing coefficient ξ = 0.5; grade ``Σ_j w_j γ_ij``.
* **TOPSIS** (Hwang & Yoon 1981), :func:`topsis`: vector normalisation ``r = x/√(Σ_i x_ij²)``,
  ``v = w r``; ideal and anti-ideal points (column max/min of v, min/max for a cost criterion);
  Euclidean distances S⁺, S⁻; closeness ``S⁻/(S⁺ + S⁻)``.
* **SAW** (simple additive weighting, the weighted sum model), :func:`saw`: linear-max
  normalisation ``x/max`` (benefit) or ``min/x`` (cost), score ``Σ_j w_j n_ij``.
* **WASPAS** (Zavadskas, Turskis, Antucheviciene & Zakarevicius 2012, *Elektronika ir
  Elektrotechnika* 122:3), :func:`waspas`: on the same linear-max normalised values,
  ``Q = λ Σ_j w_j n_ij + (1 − λ) Π_j n_ij^{w_j}`` (λ = 0.5 in the original; S002 uses 0.9).
  **S002's variant** (its Eq. 28-31), :func:`waspas_paper`: the product part is taken over the
  *weighted* values, ``P_i = Π_j (w_j n_ij)^{w_j}``, which equals ``c · Π_j n_ij^{w_j}`` with the
  constant ``c = Π_j w_j^{w_j}`` (< 1 for two or more non-zero weights). Its score
  ``λ·WSM + (1 − λ)·c·WPM`` is therefore the standard score with λ replaced by
  ``λ' = λ/(λ + (1 − λ)c)``, times ``λ + (1 − λ)c``: the product part weighs less than λ says
  and rankings can differ from the standard form's.

Every score is larger-is-better; ranks are competition ranks (rank 1 = best, ties share the
smallest rank). ``twin study mcdm RESPONSES.csv --criteria NAME:min|max,… --weights
merec|equal|W1,… --out DIR`` reads the matrix from a CSV (one row per alternative, a header row)
and writes ``DIR/mcdm.json`` and ``DIR/report.md``. The alternatives are named by a name column
(:func:`name_column`: ``--name-column COL``, or else the first column of text that names every row
once, such as ``name`` or ``run``), else numbered by row; other columns are ignored.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from twin.errors import TwinError, did_you_mean
from twin.typed import Record

#: distinguishing coefficient of GRA (the customary value, S002's)
GRA_XI = 0.5
#: λ of WASPAS as S002 uses it
WASPAS_LAMBDA = 0.9
METHODS = ("gra", "topsis", "saw", "waspas")


class TableError(TwinError):
    """A responses table or a decision-making argument is unusable; the message names the field."""


# ------------------------------------------------------------------ input
def read_csv_table(path: str | Path, flag: str = "csv_path") -> tuple[list[str], list[list[str]]]:
    """The header and data rows of a CSV file (blank lines skipped); one-line :class:`TableError`
    naming ``flag`` when the file is missing, unreadable, empty or ragged."""
    p = Path(path)
    try:
        with p.open(newline="", encoding="utf-8-sig") as f:
            rows = [r for r in csv.reader(f) if any(c.strip() for c in r)]
    except FileNotFoundError:
        raise TableError(f"{p} does not exist", field=flag) from None
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise TableError(f"cannot read {p} ({err})", field=flag) from None
    if not rows:
        raise TableError(f"{p} is empty (a header row and at least one data row are needed)", field=flag)
    header = [h.strip() for h in rows[0]]
    if len(set(header)) != len(header):
        dup = sorted({h for h in header if header.count(h) > 1})
        raise TableError(f"duplicate column name(s) {', '.join(map(repr, dup))} in {p}", field=flag)
    data = rows[1:]
    if not data:
        raise TableError(f"{p} has a header but no data rows", field=flag)
    for i, r in enumerate(data, start=2):
        if len(r) != len(header):
            raise TableError(f"line {i} of {p} has {len(r)} cells, the header has {len(header)}", field=flag)
    return header, data


def numeric_column(header: Sequence[str], rows: Sequence[Sequence[str]], name: str,
                   flag: str = "criteria") -> np.ndarray:
    """Column ``name`` as floats; a one-line error naming ``flag``, the column and the first bad
    row for an unknown column or a cell that is not a finite number."""
    if name not in header:
        raise TableError(f"unknown column {name!r}{did_you_mean(name, header)}; the file has "
                         f"{', '.join(header)}", field=flag)
    j = list(header).index(name)
    out = np.empty(len(rows))
    for i, r in enumerate(rows):
        try:
            out[i] = float(r[j])
        except ValueError:
            out[i] = math.nan
        if not math.isfinite(out[i]):
            raise TableError(f"column {name!r}, data row {i + 1}: {r[j]!r} is not a finite number", field=flag)
    return out


def _is_number(text: str) -> bool:
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def name_column(header: Sequence[str], rows: Sequence[Sequence[str]], skip: Sequence[str] = (),
                given: str | None = None, flag: str = "names_from") -> str | None:
    """The column that names the alternatives: ``given``, which must name every row once (a
    one-line error otherwise), or else the first column not in ``skip`` whose cells are text (not
    all numbers), none empty, none repeated; None when there is none (rows are then numbered)."""
    def names_rows(j: int) -> bool:
        cells = [r[j].strip() for r in rows]
        return all(cells) and len(set(cells)) == len(cells)

    if given is not None:
        if given not in header:
            raise TableError(f"unknown column {given!r}{did_you_mean(given, header)}; the file has "
                             f"{', '.join(header)}", field=flag)
        if not names_rows(list(header).index(given)):
            raise TableError(f"column {given!r} must name every row once (no empty or repeated cell)", field=flag)
        return given
    for j, h in enumerate(header):
        if h not in skip and names_rows(j) and not all(_is_number(r[j]) for r in rows):
            return h
    return None


def parse_criteria(text: str) -> list[tuple[str, bool]]:
    """``NAME:min|max,…`` as (name, benefit) pairs; benefit is True for ``max``."""
    out: list[tuple[str, bool]] = []
    for item in (s.strip() for s in text.split(",")):
        name, sep, goal = item.rpartition(":")
        if not sep or not name or goal not in ("min", "max"):
            raise TableError(f"{item!r} must be NAME:min or NAME:max", field="criteria")
        if name in (n for n, _ in out):
            raise TableError(f"{name!r} is given twice", field="criteria")
        out.append((name, goal == "max"))
    if not out:
        raise TableError("at least one NAME:min|max is needed", field="criteria")
    return out


def check_matrix(x: np.ndarray, names: Sequence[str], flag: str = "criteria") -> np.ndarray:
    """A decision matrix every method here accepts: 2-D, finite, every value > 0 (MEREC, SAW and
    WASPAS divide by the values and take their logarithms) and no constant column (min-max and
    linear normalisations would divide by zero or carry no information)."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 2 or x.shape[0] < 1 or x.shape[1] != len(names):
        raise TableError(f"need a matrix of alternatives x {len(names)} criteria, got shape {x.shape}", field=flag)
    if x.shape[0] < 2:
        raise TableError(f"at least two alternatives (rows) are needed, got {x.shape[0]}", field=flag)
    for j, n in enumerate(names):
        col = x[:, j]
        if not np.all(np.isfinite(col)):
            raise TableError(f"column {n!r} has a value that is not finite", field=flag)
        if np.any(col <= 0):
            raise TableError(f"column {n!r} has a value <= 0 (row {int(np.argmax(col <= 0)) + 1}); "
                             "MEREC, SAW and WASPAS need every value > 0", field=flag)
        if np.all(col == col[0]):
            raise TableError(f"column {n!r} is constant ({col[0]:g}); it cannot rank the alternatives", field=flag)
        if col.min() / col.max() < MIN_RATIO:
            raise TableError(f"column {n!r} spans more than 300 decades ({col.min():g} to {col.max():g}); "
                             "its ratios (min/x, x/max) are not representable in floating point", field=flag)
    return x


#: smallest ratio min/max of a column that the normalisations represent (10^-300, above the smallest normal
#: double 2.2e-308: every normalised value stays a normal number)
MIN_RATIO = 1e-300


def _scaled(x: np.ndarray) -> np.ndarray:
    """``x`` with every column divided by its largest magnitude: every method here is invariant to a positive
    factor on a criterion (ratios and min-max normalisations), and on the scaled values its squares and sums
    neither overflow (responses of 1e300) nor lose their digits to underflow (subnormal responses)."""
    x = np.asarray(x, dtype=float)
    top = np.abs(x).max(axis=0)
    return x / np.where(top > 0, top, 1.0)


def _finite_scores(name: str, scores: np.ndarray) -> np.ndarray:
    """The scores of method ``name``, refused in one line if one is not finite (never ranked as ties)."""
    if not np.all(np.isfinite(scores)):
        raise TableError(f"{name}: a score is not finite (row {int(np.argmin(np.isfinite(scores))) + 1}); "
                         "check the decision matrix and the weights")
    return scores


def parse_weights(text: str, x: np.ndarray, benefit: Sequence[bool], names: Sequence[str]) -> tuple[np.ndarray, str]:
    """``merec``, ``equal`` or ``W1,W2,…`` (as many as criteria, ≥ 0, not all 0; scaled to sum 1).
    Returns the weights and a word saying where they came from."""
    t = text.strip().lower()
    n = len(names)
    if t == "merec":
        return merec_weights(x, benefit), "MEREC"
    if t == "equal":
        return np.full(n, 1.0 / n), "equal"
    parts = [s.strip() for s in text.split(",")]
    if len(parts) != n:
        raise TableError(f"{len(parts)} value(s) for {n} criteria ({', '.join(names)}); "
                         "give merec, equal or one weight per criterion", field="weights")
    try:
        w = np.array([float(s) for s in parts])
    except ValueError:
        raise TableError(f"{text!r} must be merec, equal or numbers W1,W2,…", field="weights") from None
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise TableError(f"every weight must be a finite number >= 0, got {text!r}", field="weights")
    if w.max() <= 0:
        raise TableError(f"the weights must not all be 0, got {text!r}", field="weights")
    w = w / w.max()  # scale-free: huge weights do not overflow their sum, subnormal ones keep their ratios
    return w / w.sum(), "given"


# ------------------------------------------------------------------ methods
def _benefit(benefit: Sequence[bool], n: int) -> np.ndarray:
    b = np.asarray(benefit, dtype=bool)
    if b.shape != (n,):
        raise TableError(f"need one benefit flag per criterion ({n}), got {b.shape}")
    return b


def _w(w: Sequence[float], n: int) -> np.ndarray:
    """The weights as given (the CLI scales them to sum 1; a published example whose rounded
    weights do not sum to 1 is reproduced with them as printed)."""
    w = np.asarray(w, dtype=float)
    if w.shape != (n,) or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise TableError(f"weights: need {n} finite values >= 0, got {w.tolist()}")
    if not np.isfinite(w.sum()):
        raise TableError(f"weights: their sum overflows ({w.tolist()}); scale them (e.g. to sum 1)")
    return w


def merec_normalize(x: np.ndarray, benefit: Sequence[bool]) -> np.ndarray:
    """MEREC's normalisation: ``min/x`` for a benefit criterion, ``x/max`` for a cost criterion."""
    x = _scaled(x)
    b = _benefit(benefit, x.shape[1])
    return np.where(b, x.min(axis=0) / x, x / x.max(axis=0))


def merec_details(x: np.ndarray, benefit: Sequence[bool]) -> dict[str, np.ndarray]:
    """Every intermediate of MEREC: ``n`` (normalised), ``S`` (m), ``S_removed`` (m x n: column j
    with criterion j removed), ``E`` (n) and ``weights`` (n)."""
    nrm = merec_normalize(x, benefit)
    m, n = nrm.shape
    a = np.abs(np.log(nrm))
    s = np.log1p(a.sum(axis=1) / n)
    s_rem = np.log1p((a.sum(axis=1, keepdims=True) - a) / n)
    e = np.abs(s_rem - s[:, None]).sum(axis=0)
    if e.sum() <= 0:
        raise TableError("merec: every removal effect is 0 (no criterion separates the alternatives)", field="weights")
    return {"n": nrm, "S": s, "S_removed": s_rem, "E": e, "weights": e / e.sum()}


def merec_weights(x: np.ndarray, benefit: Sequence[bool]) -> np.ndarray:
    """MEREC weights (Keshavarz-Ghorabaee et al. 2021), one per column of ``x``."""
    return merec_details(x, benefit)["weights"]


def gra(x: np.ndarray, benefit: Sequence[bool], w: Sequence[float], xi: float = GRA_XI) -> dict[str, np.ndarray]:
    """Grey relational analysis: ``normalized`` (x*), ``delta``, ``coefficient`` (γ) and
    ``scores`` (the grades)."""
    b = _benefit(benefit, x.shape[1])
    w = _w(w, x.shape[1])
    if not 0 < xi <= 1:
        raise TableError(f"xi: the distinguishing coefficient must lie in (0, 1], got {xi}")
    x = _scaled(x)
    lo, hi = x.min(axis=0), x.max(axis=0)
    xs = np.where(b, (x - lo) / (hi - lo), (hi - x) / (hi - lo))
    d = np.abs(1.0 - xs)
    dmin, dmax = d.min(), d.max()
    g = (dmin + xi * dmax) / (d + xi * dmax)
    return {"normalized": xs, "delta": d, "coefficient": g, "scores": g @ w}


def topsis(x: np.ndarray, benefit: Sequence[bool], w: Sequence[float]) -> dict[str, np.ndarray]:
    """TOPSIS with vector normalisation: ``normalized``, ``weighted``, ``ideal``, ``anti_ideal``,
    ``d_plus``, ``d_minus`` and ``scores`` (the closeness coefficients)."""
    b = _benefit(benefit, x.shape[1])
    w = _w(w, x.shape[1])
    x = _scaled(x)
    r = x / np.sqrt((x ** 2).sum(axis=0))
    v = r * w
    best = np.where(b, v.max(axis=0), v.min(axis=0))
    worst = np.where(b, v.min(axis=0), v.max(axis=0))
    # the closeness S-/(S+ + S-) does not change with a common factor on the distances: they are computed
    # on v / max|v - ideal| so that subnormal or huge weights neither underflow to 0/0 nor overflow
    span = np.abs(best - worst).max()
    if not span > 0:
        raise TableError("topsis: every weighted criterion is constant (weights all 0 or constant columns)")
    dps = np.sqrt((((v - best) / span) ** 2).sum(axis=1))
    dms = np.sqrt((((v - worst) / span) ** 2).sum(axis=1))
    dp, dm, close = dps * span, dms * span, dms / (dps + dms)
    return {"normalized": r, "weighted": v, "ideal": best, "anti_ideal": worst,
            "d_plus": dp, "d_minus": dm, "scores": close}


def linear_max_normalize(x: np.ndarray, benefit: Sequence[bool]) -> np.ndarray:
    """SAW's and WASPAS's normalisation: ``x/max`` for a benefit criterion, ``min/x`` for a cost
    criterion (1 for the best value of each criterion)."""
    x = _scaled(x)
    b = _benefit(benefit, x.shape[1])
    return np.where(b, x / x.max(axis=0), x.min(axis=0) / x)


def saw(x: np.ndarray, benefit: Sequence[bool], w: Sequence[float]) -> dict[str, np.ndarray]:
    """Simple additive weighting: ``normalized`` and ``scores`` = Σ_j w_j n_ij."""
    w = _w(w, x.shape[1])
    nrm = linear_max_normalize(x, benefit)
    return {"normalized": nrm, "scores": nrm @ w}


def _check_lambda(lam: float) -> float:
    if not (isinstance(lam, (int, float)) and 0 <= lam <= 1):
        raise TableError(f"must lie in [0, 1], got {lam!r}", field="lam")
    return float(lam)


def waspas(x: np.ndarray, benefit: Sequence[bool], w: Sequence[float],
           lam: float = WASPAS_LAMBDA) -> dict[str, np.ndarray]:
    """WASPAS in its standard form (Zavadskas et al. 2012): ``wsm`` = Σ w n, ``wpm`` = Π n^w,
    ``scores`` = λ·wsm + (1 − λ)·wpm, on linear-max normalised values."""
    lam = _check_lambda(lam)
    w = _w(w, x.shape[1])
    nrm = linear_max_normalize(x, benefit)
    q1 = nrm @ w
    q2 = np.prod(nrm ** w, axis=1)
    return {"normalized": nrm, "wsm": q1, "wpm": q2, "scores": lam * q1 + (1 - lam) * q2}


def waspas_paper(x: np.ndarray, benefit: Sequence[bool], w: Sequence[float],
                 lam: float = WASPAS_LAMBDA) -> dict[str, np.ndarray]:
    """S002's WASPAS (its Eq. 28-31): ``Q`` = Σ_j v_ij and ``P`` = Π_j v_ij^{w_j} with the
    weighted values ``v_ij = w_j n_ij``; ``scores`` = λQ + (1 − λ)P. P equals ``c`` times the
    standard WPM with ``c = Π_j w_j^{w_j}`` (``c`` returned too); see the module docstring."""
    lam = _check_lambda(lam)
    w = _w(w, x.shape[1])
    nrm = linear_max_normalize(x, benefit)
    v = nrm * w
    q = v.sum(axis=1)
    p = np.prod(v ** w, axis=1)  # 0**0 = 1: a criterion of weight 0 drops out, as in the standard form
    c = float(np.prod(w ** w))
    return {"normalized": nrm, "weighted": v, "Q": q, "P": p, "c": c, "scores": lam * q + (1 - lam) * p}


def ranks(scores: Sequence[float]) -> np.ndarray:
    """Competition ranks of larger-is-better scores: 1 for the best, ties share the smallest rank."""
    s = np.asarray(scores, dtype=float)
    return np.array([1 + int(np.sum(s > v)) for v in s], dtype=int)


def evaluate(x: np.ndarray, benefit: Sequence[bool], w: Sequence[float], lam: float = WASPAS_LAMBDA,
             xi: float = GRA_XI) -> dict[str, dict[str, Any]]:
    """All four methods: ``{method: {"scores": [...], "ranks": [...], ...}}`` in row order;
    ``waspas`` also carries ``lambda`` and S002's variant (``paper_variant``)."""
    out: dict[str, dict[str, Any]] = {}
    for name, res in (("gra", gra(x, benefit, w, xi)), ("topsis", topsis(x, benefit, w)), ("saw", saw(x, benefit, w))):
        sc = _finite_scores(name, res["scores"])
        out[name] = {"scores": sc.tolist(), "ranks": ranks(sc).tolist()}
    out["gra"]["xi"] = xi
    std = waspas(x, benefit, w, lam)
    pap = waspas_paper(x, benefit, w, lam)
    _finite_scores("waspas", std["scores"])
    _finite_scores("waspas (S002's form)", pap["scores"])
    out["waspas"] = {
        "scores": std["scores"].tolist(), "ranks": ranks(std["scores"]).tolist(), "lambda": lam,
        "form": "standard (Zavadskas et al. 2012): lambda*sum(w*n) + (1-lambda)*prod(n**w)",
        "paper_variant": {
            "scores": pap["scores"].tolist(), "ranks": ranks(pap["scores"]).tolist(), "c": pap["c"],
            "form": "S002 Eq. 28-31: lambda*sum(w*n) + (1-lambda)*prod((w*n)**w) = "
                    "lambda*WSM + (1-lambda)*c*WPM, c = prod(w**w)"},
    }
    return out


# ------------------------------------------------------------------ study
def run_mcdm(csv_path: str | Path, criteria: str, weights: str,
             lam: float = WASPAS_LAMBDA, names_from: str | None = None) -> tuple[dict[str, Any], np.ndarray]:
    """Read, validate and evaluate: the result that ``mcdm.json`` holds, and the decision matrix.
    ``names_from``: the column naming the alternatives (default: found by :func:`name_column`)."""
    lam = _check_lambda(lam)
    crit = parse_criteria(criteria)
    header, rows = read_csv_table(csv_path)
    names = [n for n, _ in crit]
    benefit = [b for _, b in crit]
    x = check_matrix(np.column_stack([numeric_column(header, rows, n) for n in names]), names)
    w, source = parse_weights(weights, x, benefit, names)
    col = name_column(header, rows, skip=names, given=names_from)
    j = list(header).index(col) if col is not None else -1
    res: dict[str, Any] = {
        "input": str(csv_path), "alternatives": x.shape[0],
        # the alternatives' names, in row order: the name column's cells, or the row numbers (from 1)
        "name_column": col, "names": [r[j].strip() for r in rows] if col is not None else
        [str(i + 1) for i in range(x.shape[0])],
        "criteria": [{"name": n, "goal": "max" if b else "min"} for n, b in crit],
        "weights": w.tolist(), "weights_source": source,
        "methods": evaluate(x, benefit, w, lam),
    }
    if source == "MEREC":
        d = merec_details(x, benefit)
        res["merec"] = {"S": d["S"].tolist(), "E": d["E"].tolist()}
    return res, x


def report_md(res: dict[str, Any], x: np.ndarray) -> str:
    """``report.md``: the weights, then one table of scores and ranks for every alternative."""
    names = [c["name"] for c in res["criteria"]]
    m = res["methods"]
    lines = [
        "# Multi-criteria decision making", "",
        f"Input: `{res['input']}`, {res['alternatives']} alternatives (rows, numbered from 1 in file order"
        + (f"; named by the column `{res['name_column']}`" if res["name_column"] else "") + ").", "",
        "| criterion | goal | weight |", "|---|---|---|",
        *[f"| {c['name']} | {c['goal']} | {w:.4f} |" for c, w in zip(res["criteria"], res["weights"])], "",
        f"Weights: {res['weights_source']}"
        + (" (Keshavarz-Ghorabaee et al. 2021: n = min/x for max criteria, x/max for min criteria; "
           "S_i = ln(1 + (1/n) sum|ln n_ij|); E_j = sum_i |S'_ij - S_i| with criterion j removed; w = E/sum E)."
           if res["weights_source"] == "MEREC" else "."), "",
        "Methods (every score larger is better; rank 1 = best, ties share the smaller rank):", "",
        f"* GRA: min-max normalisation, grey relational coefficient with xi = {m['gra']['xi']}, grade = sum of "
        "weighted coefficients.",
        "* TOPSIS: vector normalisation, weighted, closeness to the ideal point S-/(S+ + S-).",
        "* SAW: x/max (max criteria) or min/x (min criteria), weighted sum.",
        f"* WASPAS, standard form (Zavadskas et al. 2012), lambda = {m['waspas']['lambda']}: "
        "lambda*sum(w n) + (1-lambda)*prod(n^w) on the SAW normalisation.",
        f"* WASPAS, S002's variant (its Eq. 28-31): the product is taken over the weighted values, "
        f"prod((w n)^w) = c * prod(n^w) with c = prod(w^w) = {m['waspas']['paper_variant']['c']:.4f}; "
        "the product part therefore weighs less than lambda says, and ranks can differ from the standard form.", "",
        "| row | " + (f"{res['name_column']} | " if res["name_column"] else "") + " | ".join(names)
        + " | GRA | rank | TOPSIS | rank | SAW | rank | WASPAS | rank | WASPAS (S002) | rank |",
        "|" + "---|" * (len(names) + 11 + bool(res["name_column"])),
    ]
    pv = m["waspas"]["paper_variant"]
    for i in range(res["alternatives"]):
        vals = " | ".join(f"{v:.6g}" for v in x[i])
        cells = [f"{m[k]['scores'][i]:.4f} | {m[k]['ranks'][i]}" for k in METHODS]
        named = f"{res['names'][i]} | " if res["name_column"] else ""
        lines.append(f"| {i + 1} | {named}{vals} | " + " | ".join(cells) + f" | {pv['scores'][i]:.4f} | {pv['ranks'][i]} |")
    lines += ["", f"Best {'alternative' if res['name_column'] else 'row'} by method: "
              + ", ".join(f"{k.upper()} {best_names(res, m[k]['ranks'])}" for k in METHODS)
              + f", WASPAS (S002) {best_names(res, pv['ranks'])}.", ""]
    return "\n".join(lines)


def best_names(res: dict[str, Any], ranks_: Sequence[int]) -> str:
    """The alternatives ranked 1, by name (or row number), comma-separated."""
    return ", ".join(res["names"][i] for i, r in enumerate(ranks_) if r == 1)


@dataclass(frozen=True)
class McdmOptions:
    """What :func:`run_study` ranks (the texts are parsed and checked by :func:`run_mcdm`).

    Attributes:
        csv_path: CSV with a header row, one row per alternative.
        criteria: ``NAME:min|max,…``: criterion columns and whether smaller or larger is better.
        out: output folder (created if missing).
        weights: ``merec`` (default), ``equal`` or one weight per criterion ``W1,W2,…``.
        lam: lambda of WASPAS in [0, 1] (default S002's).
        names_from: the column naming the alternatives (default: found by :func:`name_column`).
    """

    csv_path: str | Path
    criteria: str
    out: str | Path
    weights: str = "merec"
    lam: float = WASPAS_LAMBDA
    names_from: str | None = None


@dataclass(frozen=True)
class MethodScores(Record):
    """One method's answer (``mcdm.json``'s ``methods[name]``).

    Attributes:
        scores: per alternative its score, in row order [-]; ranks: its rank (1 best).
        xi: GRA's distinguishing coefficient; lam: WASPAS's λ (``lambda`` in JSON); c: the constant of S002's
            WASPAS form; form: the formula, in words; paper_variant: WASPAS in S002's form. Each None (and absent
            from the JSON) where the method has none.
    """

    _OMIT_NONE = ("xi", "lam", "c", "form", "paper_variant")
    _KEYS = {"lam": "lambda"}

    scores: tuple[float, ...]
    ranks: tuple[int, ...]
    xi: float | None = None
    lam: float | None = None
    c: float | None = None
    form: str | None = None
    paper_variant: "MethodScores | None" = None


MethodScores._NESTED = {"paper_variant": MethodScores}


@dataclass(frozen=True)
class Criterion(Record):
    """A criterion: its column ``name`` and ``goal`` ("min" or "max")."""

    name: str
    goal: str


@dataclass(frozen=True)
class MerecSums(Record):
    """MEREC's intermediate sums: ``S`` the alternatives' overall performances, ``E`` each criterion's removal
    effect [-]."""

    S: tuple[float, ...]
    E: tuple[float, ...]


@dataclass(frozen=True)
class McdmResult:
    """The ranking (``mcdm.json``): the alternatives' ``names``, the ``criteria`` and their
    ``weights``, per method its scores and ranks (``methods``: :class:`MethodScores`), MEREC's intermediate
    sums. Dicts given for the typed fields are read into them. ``names`` None: a file written before the
    alternatives were named (it holds neither ``name_column`` nor ``names``)."""

    input: str
    alternatives: int
    name_column: str | None
    names: list[str] | None
    criteria: tuple[Criterion, ...]
    weights: list[float]
    weights_source: str
    methods: dict[str, MethodScores]
    merec: MerecSums | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "criteria", tuple(c if isinstance(c, Criterion) else Criterion.from_dict(c)
                                                   for c in self.criteria))
        object.__setattr__(self, "methods", {k: m if isinstance(m, MethodScores) else MethodScores.from_dict(m)
                                             for k, m in self.methods.items()})
        if self.merec is not None and not isinstance(self.merec, MerecSums):
            object.__setattr__(self, "merec", MerecSums.from_dict(self.merec))

    def best(self, method: str) -> str:
        """The alternatives ``method`` ranks first, by name (or row number), comma-separated."""
        names = self.names if self.names is not None else [str(i + 1) for i in range(self.alternatives)]
        return best_names({"names": names}, list(self.methods[method].ranks))

    def to_dict(self) -> dict[str, Any]:
        """The JSON data of ``mcdm.json``."""
        d: dict[str, Any] = {"input": self.input, "alternatives": self.alternatives}
        if self.names is not None:
            d |= {"name_column": self.name_column, "names": self.names}
        d |= {"criteria": [c.to_dict() for c in self.criteria], "weights": self.weights,
              "weights_source": self.weights_source, "methods": {k: m.to_dict() for k, m in self.methods.items()}}
        return d if self.merec is None else d | {"merec": self.merec.to_dict()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "McdmResult":
        """The result of ``mcdm.json``'s data (its provenance stamp ignored)."""
        return cls(d["input"], d["alternatives"], d.get("name_column"), d.get("names"), d["criteria"], d["weights"],
                   d["weights_source"], d["methods"], d.get("merec"))


def run_study(options: McdmOptions) -> McdmResult:
    """Rank the alternatives of ``options.csv_path`` and write ``mcdm.json`` and ``report.md`` (the
    formulas, the weights, every score and rank) to ``options.out``."""
    from twin.provenance import stamped, with_stamp_line
    from twin.util import atomic_write_json, atomic_write_text

    o = options
    res, x = run_mcdm(o.csv_path, o.criteria, o.weights, o.lam, o.names_from)
    out = Path(o.out)
    out.mkdir(exist_ok=True)
    atomic_write_json(out / "mcdm.json", stamped(res))
    atomic_write_text(out / "report.md", with_stamp_line(report_md(res, x)))
    return McdmResult(**res)
