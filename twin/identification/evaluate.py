"""Evaluation of a clearance model on a dataset: per-run answers against the labels.

Reported (``report.json``, ``report.md``, PNG plots): accuracy and the confusion matrix of the
fault location, per-class recall, the size error per joint by true clearance value (median
absolute error against half the gap to the neighbouring catalogue values: the issue's target),
the coverage of the 90 % intervals, and every figure per clearance value and per speed. Sizes are
judged on the runs whose joint truly has a clearance (a miss is counted in the confusion matrix).
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from twin.config import CATALOGUE_DIAMETRAL_MM
from twin.identification.inputs import pooled_features
from twin.identification.intervals import SIZE_RESOLVED_FROM_RPM, held_out_at, resolution
from twin.identification.model import ClearanceModel, training_check


def half_gap_mm(c: float) -> float:
    """The size target at ``c``: half the gap between neighbouring catalogue values there. A
    catalogue value: half the gap to its nearer neighbour; a value between two catalogue values:
    half the gap between those two; outside the catalogue: half the gap of the nearest end."""
    cat = sorted(CATALOGUE_DIAMETRAL_MM)
    i = min(range(len(cat)), key=lambda k: abs(cat[k] - c))
    if abs(cat[i] - c) <= 1e-9:
        gaps = [cat[k + 1] - cat[k] for k in (i - 1, i) if 0 <= k < len(cat) - 1]
        return 0.5 * min(gaps)
    if c < cat[0]:
        return 0.5 * (cat[1] - cat[0])
    if c > cat[-1]:
        return 0.5 * (cat[-1] - cat[-2])
    lo = max(x for x in cat if x < c)
    hi = min(x for x in cat if x > c)
    return 0.5 * (hi - lo)


def evaluate(model: ClearanceModel, dataset_dir: str | Path | list[str | Path], splits: tuple[str, ...],
             workers: int = 1, features: tuple | None = None) -> dict[str, Any]:
    """The report of ``model`` on the runs of ``splits`` of one dataset, or of several pooled (one
    sample rate and encoder resolution; e.g. a test set and its extension by another seed),
    with the location accuracy of each beside the pooled figures; each run answered from the windows a
    recording's answer takes (``model.hop_revs``). ``features``: what
    :func:`twin.identification.inputs.pooled_features` returns for them with that hop, computed before."""
    t0 = time.perf_counter()
    dirs = [dataset_dir] if isinstance(dataset_dir, (str, Path)) else list(dataset_dir)
    X, rows, owner, skipped, dss = features if features is not None else \
        pooled_features(dirs, splits, workers, model.hop_revs)
    owner = np.asarray(owner)
    preds = []
    table = model.trained_on.get("held_out_size_accuracy") or {}
    for i, r in enumerate(rows):
        resolved = resolution(r["orientation"], r["crank_hz"])
        held = {j: held_out_at(table.get(j), r["orientation"], r["crank_hz"]) for j in ("B", "C")}
        a = model.identify(X[owner == i], resolved, ripple_pct=r["measures"]["ripple_pct"])
        # the checks against the training data, as a recording's answer makes them (intervals widened outside)
        a, warned, _ = training_check(model, a, r["measures"], r["orientation"], X[owner == i])
        b, c = a.joint("B"), a.joint("C")
        preds.append({"warnings": warned, "outside_training_data": bool(warned), "measures": r["measures"],"run_id": r["run_id"], "true_fault": r["fault"], "fault": a.fault,
                      "true_b_mm": r["clearance_b_mm"], "true_c_mm": r["clearance_c_mm"],
                      "b_mm": b.size_if_faulty_mm, "b_int": list(b.interval_if_faulty_mm),
                      "c_mm": c.size_if_faulty_mm, "c_int": list(c.interval_if_faulty_mm),
                      "crank_hz": r["crank_hz"], "motor_rpm": r.get("motor_rpm"), "orientation": r["orientation"],
                      "b_resolved": resolved["B"], "c_resolved": resolved["C"], "dataset": r["dataset"],
                      "b_held_out": held["B"]["share"] if held["B"] else None,
                      "c_held_out": held["C"]["share"] if held["C"] else None,
                      "probabilities": dict(a.probabilities)})
    t_pred = time.perf_counter() - t0
    y = [p["true_fault"] for p in preds]
    yhat = [p["fault"] for p in preds]
    classes = model.classes  # none, B, C, BC and, for a model of the guide, G, BG, CG, BCG
    conf = {t: {q: sum(1 for a, b in zip(y, yhat) if a == t and b == q) for q in classes} for t in classes}
    recall = {c: (conf[c][c] / sum(conf[c].values())) if sum(conf[c].values()) else None for c in classes}
    acc = float(np.mean([a == b for a, b in zip(y, yhat)])) if preds else float("nan")
    report: dict[str, Any] = {
        "dataset": "+".join(d.info["name"] for d in dss), "dataset_dir": ", ".join(map(str, dirs)),
        "splits": list(splits), "engine": dss[0].info["identity"]["engine"], "runs": len(preds), "windows": int(len(X)),
        "runs_left_out": skipped, "model": model.trained_on.get("dataset"),
        "accuracy": acc, "recall": recall, "confusion": conf,
        "targets": {"accuracy": 0.95, "recall_each_class": 0.90, "interval_coverage": 0.85},
    }
    if len(dss) > 1:
        report["by_dataset"] = _group(preds, lambda p: p["dataset"], _location)
    # fault location by speed and by clearance value
    report["by_speed"] = _group(preds, _speed_key, _location)
    report["by_clearance"] = {}
    for j in ("b", "c"):
        faulty = [p for p in preds if p[f"true_{j}_mm"] > 0]
        J = j.upper()
        groups = {f"{c:g}": {**_size_cell(ps, j, c), "detected": float(np.mean([J in p["fault"] for p in ps]))}
                  for c, ps in _by_value(faulty, j)}
        cover_all = float(np.mean([p[f"{j}_int"][0] <= p[f"true_{j}_mm"] <= p[f"{j}_int"][1] for p in faulty])) \
            if faulty else float("nan")
        report["by_clearance"][J] = {"values": groups, "interval_coverage": cover_all, "runs": len(faulty),
                                     "by_speed": size_by_speed(faulty, j), "resolved": size_where_resolved(preds, j),
                                     "held_out_check": held_out_check(faulty, j)}
    # the healthy runs: how often a joint without clearance is called faulty, by speed
    report["false_alarms"] = {J: float(np.mean([J in p["fault"] for p in preds if p[f"true_{J.lower()}_mm"] == 0]))
                              for J in ("B", "C")}
    warned = [p["outside_training_data"] for p in preds]
    report["outside_training_data"] = {"runs": int(sum(warned)), "share": float(np.mean(warned)) if preds else float("nan")}
    report["seconds"] = {"features_and_predictions": t_pred}
    report["predictions"] = preds
    return report


def _location(ps: list[dict[str, Any]]) -> dict[str, Any]:
    """Runs and fault-location accuracy of a group of predictions."""
    return {"runs": len(ps), "accuracy": float(np.mean([p["fault"] == p["true_fault"] for p in ps]))}


def median_ci90(values: np.ndarray | list[float]) -> list[float]:
    """90 % bootstrap interval (percentile, 2000 resamples of the runs, fixed seed) of the median of
    ``values``: how far a cell's median could move with other runs of the same design. One value:
    that value twice (no spread to resample)."""
    from scipy.stats import bootstrap

    v = np.asarray(values, float)
    if v.size < 2 or np.all(v == v[0]):
        return [float(v[0]), float(v[0])]
    ci = bootstrap((v,), np.median, confidence_level=0.9, n_resamples=2000, method="percentile",
                   vectorized=True, random_state=np.random.default_rng(0)).confidence_interval
    return [float(ci.low), float(ci.high)]


def _size_cell(qs: list[dict[str, Any]], j: str, c: float) -> dict[str, Any]:
    errs = [abs(q[f"{j}_mm"] - c) for q in qs]
    err = float(np.median(errs))
    return {"runs": len(qs), "median_abs_error_mm": err, "median_abs_error_ci90_mm": median_ci90(errs),
            "within_factor_1_5": float(np.mean([within_factor(q[f"{j}_mm"], c) for q in qs])),
            "target_mm": half_gap_mm(c), "meets_target": bool(err <= half_gap_mm(c)),
            "interval_coverage": float(np.mean([q[f"{j}_int"][0] <= c <= q[f"{j}_int"][1] for q in qs])),
            "median_estimate_mm": float(np.median([q[f"{j}_mm"] for q in qs]))}


#: bins of the held-out share an answer reads, for :func:`held_out_check`
HELD_OUT_BINS = (0.0, 0.7, 0.85, 0.92, 1.0)


def held_out_check(faulty: list[dict[str, Any]], j: str) -> list[dict[str, Any]]:
    """Whether the held-out shares the answers read (``clearance_*_size_held_out``) say how often their sizes hold:
    the runs with a clearance at ``j`` ("b" or "c") binned by that share (:data:`HELD_OUT_BINS`), each bin's
    mean share beside the share of its runs whose size lies within a factor 1.5 of the truth. Empty where the
    model holds no held-out table."""
    runs = [p for p in faulty if p.get(f"{j}_held_out") is not None]
    last = len(HELD_OUT_BINS) - 2
    bins = [min(int(np.searchsorted(HELD_OUT_BINS, p[f"{j}_held_out"], side="right")) - 1, last) for p in runs]
    out = []
    for k, (lo, hi) in enumerate(zip(HELD_OUT_BINS, HELD_OUT_BINS[1:])):
        ps = [p for p, b in zip(runs, bins) if b == k]
        if ps:
            out.append({"held_out_from": lo, "held_out_to": hi, "runs": len(ps),
                        "mean_held_out": float(np.mean([p[f"{j}_held_out"] for p in ps])),
                        "within_factor_1_5": float(np.mean([within_factor(p[f"{j}_mm"], p[f"true_{j}_mm"])
                                                            for p in ps]))})
    return out


def size_by_speed(faulty: list[dict[str, Any]], j: str) -> dict[str, dict[str, dict[str, Any]]]:
    """Size figures of joint ``j`` ("b" or "c") per clearance value and speed: {value: {speed: {runs,
    median_abs_error_mm, median_abs_error_ci90_mm, target_mm, meets_target, interval_coverage,
    median_estimate_mm}}}, from the
    predictions of the runs with a clearance at ``j``."""
    return {f"{c:g}": _group(ps, _speed_key, lambda qs, c=c: _size_cell(qs, j, c)) for c, ps in _by_value(faulty, j)}


def size_where_resolved(preds: list[dict[str, Any]], j: str) -> dict[str, Any]:
    """Size figures at joint ``j`` ("b" or "c") per clearance value over the runs whose speed and
    orientation the bench's sensors resolve the size at (:func:`twin.identification.intervals.size_resolved`),
    and how many are not."""
    faulty = [p for p in preds if p[f"true_{j}_mm"] > 0]
    ok = [p for p in faulty if p[f"{j}_resolved"]]
    within = [within_factor(p[f"{j}_mm"], p[f"true_{j}_mm"]) for p in ok]
    return {"runs": len(ok), "runs_not_resolved": len(faulty) - len(ok),
            "within_factor_1_5": float(np.mean(within)) if ok else float("nan"),
            "values": {f"{c:g}": _size_cell(ps, j, c) for c, ps in _by_value(ok, j)}}


#: the size target of a single answer: within this factor of the truth
SIZE_FACTOR = 1.5


def within_factor(answer_mm: float, truth_mm: float, factor: float = SIZE_FACTOR) -> bool:
    """Whether a size answer (the joint's size if faulty, whatever the location says) lies within
    ``factor`` of the truth."""
    return truth_mm / factor <= answer_mm <= truth_mm * factor


def _by_value(preds: list[dict[str, Any]], j: str) -> list[tuple[float, list[dict[str, Any]]]]:
    """The predictions grouped by their true clearance at joint ``j`` ("b" or "c"), in increasing order."""
    out: dict[float, list[dict[str, Any]]] = {}
    for p in preds:
        out.setdefault(p[f"true_{j}_mm"], []).append(p)
    return sorted(out.items())


def _speed_key(p: dict[str, Any]) -> str:
    rpm = p.get("motor_rpm")
    if rpm is not None and isinstance(rpm, float) and math.isfinite(rpm):
        return f"{rpm:g} rpm"
    return f"{p['crank_hz']:.2f} Hz"


def _group(items, key, fn) -> dict[str, Any]:
    out: dict[str, list] = {}
    for it in items:
        out.setdefault(key(it), []).append(it)
    return {k: fn(v) for k, v in sorted(out.items(), key=lambda kv: _num(kv[0]))}


def _num(s: str) -> float:
    try:
        return float(s.split()[0])
    except ValueError:
        return 0.0


def _err_ci(v: dict[str, Any]) -> str:
    ci = v.get("median_abs_error_ci90_mm")
    return f"{v['median_abs_error_mm']:.3g}" + (f" ({ci[0]:.3g}–{ci[1]:.3g})" if ci else "")


def _meets(v: dict[str, Any]) -> str:
    """yes / no by the median; "yes*" / "no*" where the bootstrap interval of the median error holds
    the target (other runs of the same design could give the other answer)."""
    ans = "yes" if v["meets_target"] else "no"
    ci = v.get("median_abs_error_ci90_mm")
    return ans + "*" if ci and ci[0] <= v["target_mm"] <= ci[1] else ans


def render_markdown(r: dict[str, Any]) -> str:
    classes = list(r["confusion"])  # the model's classes
    lines = [f"# Clearance identification: model `{r['model']}` on dataset `{r['dataset']}`", "",
             f"- test data: {r['runs']} runs ({r['windows']} windows of 2 crank revolutions), engine {r['engine']}, "
             f"splits {', '.join(r['splits'])}; {len(r['runs_left_out'])} runs left out (fewer than 2 steady "
             "revolutions)",
             f"- fault location accuracy **{r['accuracy'] * 100:.1f} %** (target 95 %)"
             + ("".join(f"; {k}: {v['accuracy'] * 100:.1f} % of {v['runs']} runs" for k, v in r["by_dataset"].items())
                if r.get("by_dataset") else "")]
    if "outside_training_data" in r:
        o = r["outside_training_data"]
        lines.append(f"- outside the training data (warned, intervals widened): {o['runs']} of {r['runs']} runs "
                     f"({o['share'] * 100:.1f} %)")
    lines += ["",
              "## Confusion matrix (rows: truth, columns: answer)", "",
              "| truth \\ answer | " + " | ".join(classes) + " | recall |", "|---|" + "---|" * (len(classes) + 1)]
    for t in classes:
        rc = r["recall"][t]
        lines.append(f"| {t} | " + " | ".join(str(r["confusion"][t][q]) for q in classes)
                     + f" | {'–' if rc is None else f'{rc * 100:.0f} %'} |")
    lines += ["", "## Fault location by speed", "", "| speed | runs | accuracy |", "|---|---|---|"]
    for k, v in r["by_speed"].items():
        lines.append(f"| {k} | {v['runs']} | {v['accuracy'] * 100:.0f} % |")
    for J, g in r["by_clearance"].items():
        lines += ["", f"## Size of the clearance at {J} (runs with a clearance at {J}: {g['runs']}; 90 % interval "
                      f"coverage {g['interval_coverage'] * 100:.0f} %, target 85 %)", "",
                  "| clearance mm | runs | detected | median estimate mm | median abs error mm (90 % bootstrap "
                  "interval) | target mm | meets | interval coverage |", "|---|---|---|---|---|---|---|---|"]
        for c, v in g["values"].items():
            lines.append(f"| {c} | {v['runs']} | {v['detected'] * 100:.0f} % | {v['median_estimate_mm']:.3g} | "
                         f"{_err_ci(v)} | {v['target_mm']:.3g} | {_meets(v)} | {v['interval_coverage'] * 100:.0f} % |")
    for J, g in r["by_clearance"].items():
        by = g.get("by_speed")
        if not by:
            continue
        speeds = sorted({k for v in by.values() for k in v}, key=_num)
        lines += ["", f"## Size at {J} by clearance value and speed", "",
                  "Median absolute error in mm (runs; 90 % interval coverage); **bold**: over the target "
                  "(half the catalogue gap).", "",
                  "| clearance mm | target mm | " + " | ".join(speeds) + " |", "|---|---|" + "---|" * len(speeds)]
        for c, v in by.items():
            cells = []
            for k in speeds:
                x = v.get(k)
                if x is None:
                    cells.append("–")
                    continue
                e = f"{x['median_abs_error_mm']:.3g}"
                cells.append(f"{e if x['meets_target'] else f'**{e}**'} ({x['runs']}; "
                             f"{x['interval_coverage'] * 100:.0f} %)")
            lines.append(f"| {c} | {half_gap_mm(float(c)):.3g} | " + " | ".join(cells) + " |")
    for J, g in r["by_clearance"].items():
        res = g.get("resolved")
        if not res or not res["values"]:
            continue
        lines += ["", f"## Size at {J} where the bench's sensors resolve it ({res['runs']} runs; "
                      f"{res['runs_not_resolved']} at a speed and orientation where they do not)", "",
                  f"Within a factor {SIZE_FACTOR:g} of the truth: **{res['within_factor_1_5'] * 100:.1f} %** of "
                  "these runs (target 90 %).", "",
                  "Resolved: motor speed at or over " + ", ".join(
                      f"{rpm:g} rpm with {o} vertical" for o, rpm in SIZE_RESOLVED_FROM_RPM[J].items())
                  + " (the model card's size-resolution map).", "",
                  "| clearance mm | runs | median estimate mm | median abs error mm (90 % bootstrap interval) | "
                  "target mm | meets | within ×1.5 | interval coverage |", "|---|---|---|---|---|---|---|---|"]
        for c, v in res["values"].items():
            lines.append(f"| {c} | {v['runs']} | {v['median_estimate_mm']:.3g} | {_err_ci(v)} | "
                         f"{v['target_mm']:.3g} | {_meets(v)} | {v['within_factor_1_5'] * 100:.0f} % | "
                         f"{v['interval_coverage'] * 100:.0f} % |")
    for J, g in r["by_clearance"].items():
        check = g.get("held_out_check")
        if not check:
            continue
        lines += ["", f"## Size at {J}: the held-out share the answers read against what happened", "",
                  "Each answer reads how often the model's sizes held at its speed and orientation in training runs "
                  "left out (`clearance_*_size_held_out`); here the runs with a clearance at the joint, binned by "
                  "that share, and the share of them whose size lies within a factor 1.5 of the truth.", "",
                  "| held-out share read | runs | mean share read | within ×1.5 here |", "|---|---|---|---|"]
        for b in check:
            lines.append(f"| {b['held_out_from'] * 100:.0f}–{b['held_out_to'] * 100:.0f} % | {b['runs']} | "
                         f"{b['mean_held_out'] * 100:.0f} % | {b['within_factor_1_5'] * 100:.0f} % |")
    lines += ["", "Bootstrap intervals: 90 % percentile intervals of each median over resampled runs; a * marks a "
                  "cell whose interval holds the target (the runs do not settle it either way)."]
    lines += ["", f"False alarms on healthy joints: B {r['false_alarms']['B'] * 100:.1f} %, "
                  f"C {r['false_alarms']['C'] * 100:.1f} %.", ""]
    for p in r.get("plots", []):
        lines.append(f"![{p}]({p})")
    return "\n".join(lines) + "\n"


def plots(r: dict[str, Any], out: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    files = []
    fig, ax = plt.subplots(figsize=(4.8, 4.2))
    classes = list(r["confusion"])
    m = np.array([[r["confusion"][t][q] for q in classes] for t in classes], dtype=float)
    ax.imshow(m / np.maximum(m.sum(axis=1, keepdims=True), 1), cmap="Blues", vmin=0, vmax=1)
    for i in range(4):
        for k in range(4):
            ax.text(k, i, int(m[i, k]), ha="center", va="center")
    ax.set_xticks(range(len(classes)), classes)
    ax.set_yticks(range(len(classes)), classes)
    ax.set_xlabel("answer")
    ax.set_ylabel("truth")
    ax.set_title(f"fault location, accuracy {r['accuracy'] * 100:.1f} %")
    fig.tight_layout()
    fig.savefig(out / "confusion.png", dpi=110)
    plt.close(fig)
    files.append("confusion.png")
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    for ax, j in zip(axes, ("b", "c")):
        ps = [p for p in r["predictions"] if p[f"true_{j}_mm"] > 0]
        if not ps:
            continue
        t = np.array([p[f"true_{j}_mm"] for p in ps])
        e = np.array([p[f"{j}_mm"] for p in ps])
        lo = np.array([p[f"{j}_int"][0] for p in ps])
        hi = np.array([p[f"{j}_int"][1] for p in ps])
        jit = t * (1 + 0.06 * (np.random.default_rng(0).random(len(t)) - 0.5))
        ax.errorbar(jit, e, yerr=[e - lo, hi - e], fmt="o", ms=3, alpha=0.5, lw=0.6)
        lim = [0.01, 2.0]
        ax.plot(lim, lim, "k--", lw=0.8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(lim)
        ax.set_ylim(lim)
        ax.set_xlabel(f"true clearance at {j.upper()} [mm]")
        ax.set_ylabel("estimate and 90 % interval [mm]")
        ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(out / "sizes.png", dpi=110)
    plt.close(fig)
    files.append("sizes.png")
    return files


def write_report(r: dict[str, Any], out: Path) -> list[str]:
    from twin.util import atomic_write_json, atomic_write_text

    out.mkdir(parents=True, exist_ok=True)
    r["plots"] = plots(r, out)
    atomic_write_json(out / "report.json", json.loads(json.dumps(r, default=float)))
    atomic_write_text(out / "report.md", render_markdown(r))
    return ["report.json", "report.md", *r["plots"]]
