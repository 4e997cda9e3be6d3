"""S000 report: the DOE/Kriging study of Zhang, Xu, Flores & Lankarani reproduced with the twin.

Runs ``twin study doe`` (``twin.studies.doe``) on the four specs of ``analysis/datasets/``:

* ``s000_example1.toml``: Example 1, 10 Latin hypercube points of our own (radial clearance at C
  0.05-0.5 mm x K 3.4e9-1.7e10 N/m^1.5, 5000 rpm), S000's 11th point as hold-out;
* ``s000_example1_paper.toml``: the same at Table 4's own 10 points (a point-by-point comparison);
* ``s000_example2.toml``: Example 2, 30 LHS points (50-5000 rpm x K 3.3e8-3.3e11 x 0.02-1.0 mm),
  the 31st point as hold-out, Fig. 16's slices at 1480/3000/4450 rpm;
* ``s000_example2_paper.toml``: the same at Table 6's own 30 points;

plus Table 4's points in the MuJoCo twin (the same spec on the other engine), and writes
``analysis/results/s000/``: one folder per study (``doe.md``, ``doe.json``, a PNG per surrogate) and
``comparison.json`` / ``comparison.md`` (our numbers beside the paper's). The generated datasets go to
``--work`` (default ``/tmp/s000_work``; a second call resumes them). About two minutes on 2 cores.

    python analysis/s000_report.py [--work DIR] [--workers N]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import shutil
import sys
from pathlib import Path

import numpy as np
from twin.provenance import stamped, with_stamp_line

ROOT = Path(__file__).resolve().parent.parent
RES = ROOT / "analysis" / "results" / "s000"
SPECS = ROOT / "analysis" / "datasets"
STUDIES = ("s000_example1", "s000_example1_paper", "s000_example2", "s000_example2_paper")
#: S000's hold-out checks: (study, point, simulated, predicted) of the max slider acceleration [m/s^2]
PAPER_HOLDOUT = {"s000_example1": (3.2e4, 3.0e4), "s000_example2": (4.5e4, 4.4e4)}


def run(name: str, work: Path, workers: int, engine: str | None = None) -> dict:
    from twin.studies import doe as doe_study

    spec = doe_study.load_doe(SPECS / f"{name}.toml")
    tag = name
    if engine is not None and engine != spec.dataset.engine:
        spec = dataclasses.replace(spec, dataset=dataclasses.replace(spec.dataset, engine=engine,
                                                                     name=spec.dataset.name + "-" + engine))
        tag = f"{name}_{engine}"
    out = work / tag
    res = doe_study.run_study(doe_study.DoeOptions(spec, out, workers),
                              log=lambda m: print(f"[{tag}] {m}", file=sys.stderr)).to_dict()
    dst = RES / tag
    dst.mkdir(parents=True, exist_ok=True)
    for f in ["doe.md", "doe.json", *res["figures"]]:
        shutil.copy(out / f, dst / f)
    return res


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", default="/tmp/s000_work", help="where the generated datasets go")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    work = Path(args.work)
    RES.mkdir(parents=True, exist_ok=True)
    paper = json.loads((RES / "paper_tables.json").read_text())
    res = {n: run(n, work, args.workers) for n in STUDIES}
    res["s000_example1_paper_mujoco"] = run("s000_example1_paper", work, args.workers, engine="mujoco")

    cmp: dict = {"table4": [], "table6": [], "holdout": {}, "optimum": {}, "sensitivity": {}, "loo": {}}
    # Table 4 point by point: paper, reference engine, MuJoCo twin
    r1, r1m = res["s000_example1_paper"], res["s000_example1_paper_mujoco"]
    for i, (c, K, a, F, P) in enumerate(paper["table4"]):
        cmp["table4"].append({"clearance_mm": c, "K": K, "paper": {"max_slider_accel": a, "max_contact_force": F,
                                                                    "max_power": P},
                              "reference": r1["points"][i]["responses"], "mujoco": r1m["points"][i]["responses"]})
    r2 = res["s000_example2_paper"]
    for i, (rpm, K, c, F, a, P) in enumerate(paper["table6"]):
        cmp["table6"].append({"crank_rpm": rpm, "K": K, "clearance_mm": c,
                              "paper": {"max_contact_force": F, "max_slider_accel": a, "max_power": P},
                              "reference": r2["points"][i]["responses"]})
    for n in STUDIES:
        r = res[n]
        hold = [c for c in r["checks"] if c["kind"] == "holdout"]
        if hold:
            h = hold[0]
            ps, pp = PAPER_HOLDOUT[n.replace("_paper", "")]
            cmp["holdout"][n] = {"factors": h["factors"], "paper_simulated": ps, "paper_predicted": pp,
                                 "simulated": h["responses"], "predicted": {k: v["mean"] for k, v in h["predicted"].items()},
                                 "predicted_std": {k: v["std"] for k, v in h["predicted"].items()}}
        cmp["optimum"][n] = {}
        for rn, s in r["responses"].items():
            chk = [c for c in r["checks"] if c["kind"] == "optimum" and all(
                abs(c["factors"][f] - s["optimum"]["factors"][f]) <= 1e-9 * max(1.0, abs(s["optimum"]["factors"][f]))
                for f in c["factors"])]
            cmp["optimum"][n][rn] = {"factors": s["optimum"]["factors"], "predicted": s["optimum"]["predicted"],
                                     "simulated": chk[0]["responses"][rn] if chk else None,
                                     "train_min": min(p["responses"][rn] for p in r["points"])}
        cmp["sensitivity"][n] = {rn: s["sobol"] for rn, s in r["responses"].items()}
        cmp["loo"][n] = {rn: s["loo_stats"] for rn, s in r["responses"].items()}
    # ratios of ours to the paper's at its own points (median and spread), per response
    ratios = {}
    for tab, key in (("table4", "reference"), ("table4", "mujoco"), ("table6", "reference")):
        for rn in ("max_slider_accel", "max_contact_force", "max_power"):
            q = np.array([row[key][rn] / row["paper"][rn] for row in cmp[tab]])
            ratios[f"{tab}/{key}/{rn}"] = {"median": float(np.median(q)), "min": float(q.min()), "max": float(q.max())}
    cmp["ratios"] = ratios
    # rank agreement (Spearman) of ours and the paper's at the paper's points
    from scipy.stats import spearmanr

    cmp["spearman"] = {}
    for tab in ("table4", "table6"):
        for rn in ("max_slider_accel", "max_contact_force", "max_power"):
            rho = spearmanr([row["paper"][rn] for row in cmp[tab]], [row["reference"][rn] for row in cmp[tab]])
            cmp["spearman"][f"{tab}/{rn}"] = float(rho.statistic)
    # F / (m a): the paper's contact force over its acceleration, and ours
    cmp["force_over_accel"] = {
        "table4_paper": [row["paper"]["max_contact_force"] / row["paper"]["max_slider_accel"] for row in cmp["table4"]],
        "table4_reference": [row["reference"]["max_contact_force"] / row["reference"]["max_slider_accel"]
                             for row in cmp["table4"]],
        "table6_paper": [row["paper"]["max_contact_force"] / row["paper"]["max_slider_accel"] for row in cmp["table6"]],
    }
    cmp["ideal_5000rpm"] = ideal_run()
    (RES / "comparison.json").write_text(json.dumps(stamped(cmp), indent=1))
    (RES / "comparison.md").write_text(with_stamp_line(comparison_md(cmp)))
    print(f"wrote {RES}")
    return 0


def ideal_run() -> dict:
    """The ideal mechanism (no clearance) at 5000 rpm in both engines: the floor of the responses."""
    import math

    from twin.config import named_preset
    from twin.simulation import simulate_run

    out = {}
    for engine in ("reference", "mujoco"):
        cfg = named_preset("s000").replace(**{"joints.clearance_c_mm": 0.0, "simulation.engine": engine})
        run = simulate_run(cfg)
        m = run.time >= 0.024
        out[engine] = {"max_slider_accel": float(np.abs(run["AC6"][m]).max()),
                       "max_power": float(np.abs(run["crank_torque"][m] * run["crank_speed"][m]).max()),
                       "max_crank_torque": float(np.abs(run["crank_torque"][m]).max())}
    r, L, w = 0.05, 0.12, 5000 * 2 * math.pi / 60
    out["closed_form_max_slider_accel"] = r * w * w * (1 + r / L)
    return out


def _g(v) -> str:
    return "—" if v is None else f"{v:.3g}"


def comparison_md(c: dict) -> str:
    L = ["# S000: the twin's numbers beside the paper's (generated by analysis/s000_report.py)", "",
         "## Table 4 (Example 1, 5000 rpm) at the paper's own points", "",
         "| # | c [mm] | K [N/m^1.5] | accel paper | ref | MuJoCo | force paper | ref | MuJoCo | power paper | ref | MuJoCo |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for i, r in enumerate(c["table4"], 1):
        cells = []
        for rn in ("max_slider_accel", "max_contact_force", "max_power"):
            cells += [_g(r["paper"][rn]), _g(r["reference"][rn]), _g(r["mujoco"][rn])]
        L.append(f"| {i} | {r['clearance_mm']:g} | {r['K']:.2g} | " + " | ".join(cells) + " |")
    i5 = c["ideal_5000rpm"]
    L += ["", f"Ideal mechanism at 5000 rpm (no clearance): max slider acceleration {i5['reference']['max_slider_accel']:.4g}"
          f" (reference) / {i5['mujoco']['max_slider_accel']:.4g} (MuJoCo) m/s^2, closed form r w^2 (1 + r/L) "
          f"{i5['closed_form_max_slider_accel']:.4g}; max drive power {i5['reference']['max_power']:.3g} / "
          f"{i5['mujoco']['max_power']:.3g} W; max crank torque {i5['reference']['max_crank_torque']:.3g} / "
          f"{i5['mujoco']['max_crank_torque']:.3g} N m.", "",
          "Contact force / slider acceleration, Table 4: paper " + ", ".join(f"{v:.3f}" for v in c["force_over_accel"]["table4_paper"])
          + "; ours " + ", ".join(f"{v:.3f}" for v in c["force_over_accel"]["table4_reference"]) + " kg.", ""]
    L += ["", "## Table 6 (Example 2) at the paper's own points (reference engine)", "",
          "| # | rpm | K [N/m^1.5] | c [mm] | force paper | ours | accel paper | ours | power paper | ours |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for i, r in enumerate(c["table6"], 1):
        cells = []
        for rn in ("max_contact_force", "max_slider_accel", "max_power"):
            cells += [_g(r["paper"][rn]), _g(r["reference"][rn])]
        L.append(f"| {i} | {r['crank_rpm']:g} | {r['K']:.3g} | {r['clearance_mm']:g} | " + " | ".join(cells) + " |")
    L += ["", "## Ours / paper at the paper's points", "", "| table / engine / response | median | min | max |",
          "|---|---|---|---|"]
    for k, v in c["ratios"].items():
        L.append(f"| {k} | {v['median']:.2f} | {v['min']:.2f} | {v['max']:.2f} |")
    L += ["", "Spearman rank correlation, ours against the paper's (reference engine): "
          + ", ".join(f"{k} {v:.2f}" for k, v in c["spearman"].items()), "",
          "## Hold-out points (max slider acceleration)", "",
          "| study | point | paper simulated | paper predicted | ours simulated | ours predicted (±1σ) |", "|---|---|---|---|---|---|"]
    for n, h in c["holdout"].items():
        L.append(f"| {n} | " + ", ".join(f"{k} {v:g}" for k, v in h["factors"].items())
                 + f" | {h['paper_simulated']:.2g} | {h['paper_predicted']:.2g} | {_g(h['simulated']['max_slider_accel'])} | "
                 f"{_g(h['predicted']['max_slider_accel'])} ± {_g(h['predicted_std']['max_slider_accel'])} |")
    L += ["", "## Optima of the surrogates (minimum), simulated", "",
          "| study | response | factors | predicted | simulated | smallest training value |", "|---|---|---|---|---|---|"]
    for n, o in c["optimum"].items():
        for rn, v in o.items():
            L.append(f"| {n} | {rn} | " + ", ".join(f"{k} {x:.3g}" for k, x in v["factors"].items())
                     + f" | {_g(v['predicted'])} | {_g(v['simulated'])} | {_g(v['train_min'])} |")
    L += ["", "## Sensitivity (Sobol indices of the surrogates, first order / total)", "",
          "| study | response | " + "factor: S1 / ST |", "|---|---|---|"]
    for n, s in c["sensitivity"].items():
        for rn, v in s.items():
            L.append(f"| {n} | {rn} | " + "; ".join(f"{f} {v['first_order'][f]:.2f} / {v['total'][f]:.2f}"
                                                    for f in v["first_order"]) + " |")
    L += ["", "## Leave-one-out errors", "", "| study | response | RMSE | RMSE / std | max rel. |", "|---|---|---|---|---|"]
    for n, s in c["loo"].items():
        for rn, v in s.items():
            L.append(f"| {n} | {rn} | {v['rmse']:.3g} | {v['rmse_over_std']:.2f} | {100 * v['max_rel']:.0f} % |")
    return "\n".join(L) + "\n"


if __name__ == "__main__":
    sys.exit(main())
