"""The waveform stage on the development sets (docs/calibration.md, "The waveform stage").

Sets 3 and 4 have been looked at: here they are development data. For each program-drive case of the
set's ``results.json``, the stage (:func:`twin.calibration.waveform.waveform_stage`) runs from the
validation's fitted values, on the same two repeat recordings and the same base configuration the
calibration had — what ``twin.calibrate(..., options=CalibrationOptions(waveform=True))`` does after its
feature fit. Then the validation's replay comparison (``calibration_validation.replay_compare``: the
first recording replayed with the true and the fitted values) at the stage's values, and the errors
against the truth before and after.

    python analysis/waveform_stage.py --set 4 --work /tmp/val4 [--cases mu_a,mu_b] [--budget 16]

Writes ``analysis/calibration_validation_{set}/waveform_stage.json`` (stamped) and prints a table; with
``--plot`` also ``waveform_stage.png`` (replay NRMSE over the truth's, before and after, per case).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import json
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def run_case(cv, case: dict, fit: dict, work: Path, budget: int, other_engine: bool = False) -> dict:
    from twin.calibration.objective import get_target
    from twin.calibration.params import make_parameters
    from twin.calibration.waveform import waveform_stage

    motor = any(f.startswith("drivetrain.") for f in case["fields"])
    base = cv.config_of(case, 0, fitted_at_default=True)
    if other_engine:  # model error: the recordings' engine is not the model's
        base = base.replace(**{"simulation.engine": "reference" if case["engine"] == "mujoco" else "mujoco"})
    recs = [work / f"{case['case']}_s{s}.mcap" for s in cv.REPEAT_SEEDS]
    tgs = [get_target(str(r), base.to_toml(), 1.0, 0.05, motor, "program") for r in recs]
    P = make_parameters(case["fields"], tgs[0].base)
    fitted = {p["field"]: p["value"] for p in fit["params"]}
    u = np.asarray([p.to_unit(min(p.hi, max(p.lo, fitted[p.field]))) for p in P])
    ivs = [(p["lo"], p["hi"]) for p in fit["params"]]
    t0 = time.perf_counter()
    st = waveform_stage(tgs, P, u, ivs, budget=budget, say=lambda s: print("   ", s, flush=True))
    wall = time.perf_counter() - t0
    after = dict(zip(st["fields"], st["values"])) if st.get("values") else fitted
    rep = cv.replay_compare(case, recs, base, after, "program") if st["ran"] and not other_engine else None
    params = []
    for p in fit["params"]:
        tr = case["truth"][p["field"]]
        e1, h1 = cv.verdict(p["field"], tr, after[p["field"]])
        params.append({"field": p["field"], "truth": tr, "before": p["value"], "after": after[p["field"]],
                       "error_before": p["error"], "error_after": e1, "hit_before": p["hit"], "hit_after": h1,
                       "interval": [p["lo"], p["hi"]], "inside_interval_after": bool(p["lo"] <= after[p["field"]] <= p["hi"])})
    row = {"case": case["case"], "engine": case["engine"], "model_engine": base.simulation.engine, "stage": st, "params": params, "stage_wall_s": wall,
           "calibration_wall_s": fit["wall_s"],
           "nrmse_before": fit["nrmse"], "literal_before": fit["replay_within_10pct"],
           "floor_before": fit.get("replay_within_floor")}
    if rep is not None:
        row.update(nrmse_after=rep["nrmse"], literal_after=rep["replay_within_10pct"],
                   floor_after=rep.get("replay_within_floor"))
    elif other_engine:  # no replay comparison: the truth's replay is the recordings' engine
        row.update(nrmse_after=None, literal_after=None, floor_after=None)
    else:
        row.update(nrmse_after=fit["nrmse"], literal_after=fit["replay_within_10pct"],
                   floor_after=fit.get("replay_within_floor"))
    return row


def plot(rows: list[dict], path: Path) -> None:
    from twin.provenance import figure_metadata
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 4))
    names = [r["case"] for r in rows]
    for j, (key, mk, lab) in enumerate((("nrmse_before", "o", "feature fit"), ("nrmse_after", "s", "+ waveform stage"))):
        y = [max(v["fitted"] / v["truth"] for v in r[key].values()) for r in rows]
        ax.scatter(np.arange(len(rows)) + (j - 0.5) * 0.2, y, marker=mk, label=lab)
    ax.axhline(1.1, color="k", ls="--", lw=0.8, label="criterion (1.1 × truth)")
    ax.set_yscale("log")
    ax.set_xticks(range(len(rows)), [n + ("" if r["stage"]["ran"] else "\n(skipped)") for n, r in zip(names, rows)],
                  fontsize=8)
    ax.set_ylabel("worst accelerometer: replay NRMSE / truth's")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".png")   # then renamed: a figure is whole or absent
    os.close(fd)
    fig.savefig(tmp, dpi=110, metadata=figure_metadata())
    os.replace(tmp, path)
    plt.close(fig)


def table(rows: list[dict]) -> str:
    """Markdown: per case and field, the errors and the replay criterion before/after, the stage's cost."""
    out = ["| case | engine | stage | field | error: feature fit → + waveform | change / interval half-width | "
           "replay NRMSE ≤ 1.1 × truth (literal): before → after | worst NRMSE / truth: before → after | stage [s] "
           "(calibration [s]) |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        st = r["stage"]
        how = f"ran ({st['replays']} replays)" if st["ran"] else "skipped: not predictable" if "predictable" in st[
            "reason"] else f"skipped: {st['reason']}"
        ch = {c["field"]: c for c in st.get("changes", [])}
        worst = lambda k: max(v["fitted"] / v["truth"] for v in r[k].values()) if r[k] else float("nan")  # noqa: E731
        for p in r["params"]:
            e = (lambda x: f"{100 * x:+.3g} %") if abs(p["truth"]) > 0 and "restitution" not in p["field"] else (
                lambda x: f"{x:+.3g}")
            sh = ch.get(p["field"], {}).get("shift_in_half_widths")
            out.append(f"| {r['case']} | {r['engine']}{'' if r.get('model_engine', r['engine']) == r['engine'] else ' → model ' + r['model_engine']} "
                       f"| {how} | {p['field']} | {e(p['error_before'])} → {e(p['error_after'])} | "
                       f"{'–' if sh is None else f'{sh:+.2f}'} | {'yes' if r['literal_before'] else 'no'} → "
                       f"{'–' if r['literal_after'] is None else 'yes' if r['literal_after'] else 'no'} | {worst('nrmse_before'):.3g} → {worst('nrmse_after'):.3g} | "
                       f"{r['stage_wall_s']:.0f} ({r['calibration_wall_s']:.0f}) |")
    return "\n".join(out) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--set", choices=("3", "4"), default="4")
    ap.add_argument("--work", type=Path, required=True, help="the set's recordings (its make step's --work)")
    ap.add_argument("--cases", default=None, help="comma-separated cases (default: every program-drive case)")
    ap.add_argument("--budget", type=int, default=None, help="replays (default: the stage's default)")
    ap.add_argument("--plot", action="store_true")
    ap.add_argument("--table", action="store_true", help="only print the table of the set's waveform_stage.json")
    ap.add_argument("--other-engine", action="store_true",
                    help="model error: the model runs the other engine than the recordings' (waveform_stage_cross.json); "
                         "the replay comparison is left out (the truth's replay is the recordings' engine)")
    a = ap.parse_args()
    sys.path.insert(0, str(HERE))
    import calibration_validation as cv
    from twin.calibration.waveform import DEFAULT_BUDGET
    from twin.provenance import stamped
    from twin.util import atomic_write_text

    cv.select_set(a.set)
    doc = json.loads((cv.HERE / "truth.json").read_text())
    fits = {r["case"]: r for r in json.loads((cv.HERE / "results.json").read_text())["results"]
            if r.get("drive") == "program" and "params" in r}
    if a.table:
        for name in ("waveform_stage.json", "waveform_stage_cross.json"):
            if (cv.HERE / name).exists():
                print(name)
                print(table(json.loads((cv.HERE / name).read_text())["rows"]))
        return
    only = a.cases.split(",") if a.cases else None
    out = cv.HERE / ("waveform_stage_cross.json" if a.other_engine else "waveform_stage.json")
    rows = json.loads(out.read_text())["rows"] if out.exists() else []
    rows = [r for r in rows if not only or r["case"] not in only]
    for case in doc["cases"]:
        if (only and case["case"] not in only) or case["case"] not in fits or any(r["case"] == case["case"] for r in rows):
            continue
        print(f"{case['case']} ({case['engine']}):", flush=True)
        r = run_case(cv, case, fits[case["case"]], a.work, a.budget or DEFAULT_BUDGET, a.other_engine)
        rows.append(r)
        st = r["stage"]
        print(f"  {'ran' if st['ran'] else 'skipped'}: {st['reason']}; {st['replays']} replays, {r['stage_wall_s']:.0f} s "
              f"(calibration {r['calibration_wall_s']:.0f} s); predictability {st.get('predictability_pct')}", flush=True)
        for p in r["params"]:
            print(f"  {p['field']}: truth {p['truth']:.6g}; {p['before']:.6g} ({p['error_before']:+.2e}) -> "
                  f"{p['after']:.6g} ({p['error_after']:+.2e}); in interval {p['inside_interval_after']}", flush=True)
        print("  NRMSE/truth before " + " ".join(f"{s} {v['fitted'] / v['truth']:.3g}" for s, v in r["nrmse_before"].items())
              + f" (literal {r['literal_before']})", flush=True)
        print("  NRMSE/truth after  " + " ".join(f"{s} {v['fitted'] / v['truth']:.3g}" for s, v in (r["nrmse_after"] or {}).items())
              + f" (literal {r['literal_after']}, floor {r['floor_after']})", flush=True)
        atomic_write_text(out, json.dumps(stamped({"set": a.set, "rows": rows}), indent=1, default=str) + "\n")
    if rows:
        print(table(rows))
    if a.plot and rows and not a.other_engine:
        plot(rows, cv.HERE / "waveform_stage.png")


if __name__ == "__main__":
    main()
