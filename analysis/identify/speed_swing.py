"""The crank-rate swing the bench's motor drive gives in steady running, and what the identification's steadiness
rule does with it.

Why: the identification answers a recording from its steady part (``twin.identification.features.steady_windows``):
the stretch where the crank rate averaged over 50 ms stays within a tolerance of the rate of the recording's last
half. The tolerance once stopped at 30 %: recordings of the bench's own drive (motor speed loop through the V-belt,
soft speed loops, x vertical lifting the slider against gravity each turn) swing more and were refused "too little
steady motion" while the bench turned through whole turns.

Method: the datasets ``analysis/datasets/speed_swing.toml`` (48 runs of 3 s, MuJoCo engine, drive.mode = "motor"
with every drive-train placeholder drawn over the range its documentation asks users to explore, soft speed loops
included; motor speeds 250-800 rpm; x, y, z vertical; start angles; clearances at B, C and the guide; contact and
sensor parameters off default; Latin hypercube) and ``speed_swing_x.toml`` (24 more runs with x vertical, another
seed: the first set's largest swings were all x vertical). For each run, from the encoder counts alone:

* ``turns``: whether the crank turns through two whole turns at all (a run that stalls, e.g. x vertical from a
  start angle the motor cannot lift the slider from, is no steady running and is left out of the distribution);

* ``swing_pct``: the quantity the rule reads, :attr:`twin.identification.features.Windows.swing` — the 95th
  percentile over the last half of the recording of |50 ms rate / its median − 1| [%];
* ``swing_max_pct``: the largest such deviation over the last half [%];
* ``turn_dev_pct``: the largest deviation of a whole turn's mean rate from the last half's mean rate, over the
  whole turns of the last half [%] (what is left of the swing once averaged over a turn);
* ``old_rule``: the steady part under the former rule (tolerance capped at 30 %, no whole-turn start): the steady
  turns, or the refusal;
* ``new_rule``: the same under the rule of this version (no cap below a stop, the steady part starting at the first
  whole turn within ``TURN_TOL`` of the mean rate): steady turns and windows, or the refusal.

Result: ``analysis/results/identify/speed_swing.json`` (per run and the distribution) and a summary printed. The
threshold ``twin.identification.ranges.BENCH_SWING_PCT`` (the largest swing of steady running the bench gives; a
recording that swings more is answered with a warning, not refused) is the largest ``swing_pct`` measured on the runs
that turn plus the allowance the rule gives a recording's own spread (``RIPPLE_ALLOWANCE``, 5 points), rounded up
to 5 %.

Run (after generating the dataset):

    twin dataset generate analysis/datasets/speed_swing.toml --out speed_swing
    twin dataset generate analysis/datasets/speed_swing_x.toml --out speed_swing_x
    python analysis/identify/speed_swing.py speed_swing speed_swing_x [--out analysis/results/identify/speed_swing.json]
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def turn_deviation(turns: np.ndarray, rate_hz: float) -> float:
    """Largest |whole turn's mean rate / mean rate − 1| over the back-to-back whole turns of the last half of
    ``turns`` (crank turns, increasing) [-]."""
    t = np.abs(turns[len(turns) // 2:] - turns[len(turns) // 2])
    top = np.maximum.accumulate(t)
    mean = top[-1] / max(len(t) - 1, 1)
    edges = np.searchsorted(top, np.arange(0.0, math.floor(top[-1]) + 1.0), side="left")
    if len(edges) < 2 or mean <= 0:
        return float("nan")
    rates = 1.0 / np.diff(edges)
    return float(np.max(np.abs(rates / mean - 1.0)))


def old_rule(counts: np.ndarray, rate_hz: float, cpr: float) -> dict:
    """The steady part under the former rule (version 0.4.0 before this change): the longest stretch where the
    50 ms rate stays within max(10 %, min(spread + 5 %, 30 %)) of the last half's median rate, spread the 95th
    percentile of its deviation there; at least 2 turns, else refused."""
    turns = counts / cpr
    L = int(round(0.05 * rate_hz))
    if abs(turns[-1] - turns[0]) < 2.0:
        return {"steady_turns": None, "refused": "too little motion"}
    hz = (turns[L:] - turns[:-L]) * rate_hz / L
    ref = float(np.median(hz[len(hz) // 2:]))
    spread = float(np.quantile(np.abs(hz[len(hz) // 2:] / ref - 1.0), 0.95))
    tol = max(0.10, min(spread + 0.05, 0.30))
    ok = np.abs(hz / ref - 1.0) <= tol
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(np.int8), [0]]))).reshape(-1, 2)
    a, b = max(edges, key=lambda r: r[1] - r[0]) if len(edges) else (0, 0)
    b = b + L - 1
    st = float(abs(turns[b] - turns[a]))
    return {"steady_turns": round(st, 3), "refused": None if st >= 2.0 else
            f"too little steady motion: {st:.2f} crank revolutions within {tol:.0%}"}


def steady(counts: np.ndarray, rate_hz: float, cpr: float) -> dict:
    """The steady part under the rule of this version: turns and windows, or the refusal."""
    import twin.identification.features as F

    try:
        w = F.steady_windows(counts, rate_hz, cpr)
        return {"steady_turns": round(w.revolutions, 3), "windows": len(w.windows), "refused": None}
    except F.IdentifyError as err:
        return {"steady_turns": None, "windows": 0, "refused": str(err)}


def measure_run(ds, r: dict, cpr: float) -> dict:
    """The measures of one dataset run (module docstring)."""
    from twin.identification.features import steady_windows

    counts = np.asarray(ds.read(r["run_id"], ["encoder_counts"])["encoder_counts"], float)
    rate = float(ds.rate_hz)
    turns = counts / cpr
    L = int(round(0.05 * rate))
    hz = (turns[L:] - turns[:-L]) * rate / L
    last = hz[len(hz) // 2:]
    ref = float(np.median(last))
    moving = abs(turns[-1] - turns[0]) >= 2.0 and abs(ref) > 1e-6
    dev = np.abs(last / ref - 1.0) if moving else np.zeros(1)
    new = steady(counts, rate, cpr)
    swing = steady_windows(counts, rate, cpr).swing if new["refused"] is None else float(np.quantile(dev, 0.95))
    return {"dataset": ds.info["name"], "run_id": r["run_id"], "orientation": r.get("orientation"),
            "motor_rpm": r.get("factor_motor_rpm"),
            **{k[7:]: r[k] for k in r if k.startswith("factor_") and k[7:] in (
                "speed_kp_nms", "speed_ki_nm", "speed_filter_hz", "rotor_inertia_kgm2", "belt_ea_n",
                "belt_preload_n", "belt_mu", "clearance_guide_mm", "start_angle_rad")},
            "turns": bool(moving), "crank_hz": abs(ref),
            "swing_pct": round(100 * swing, 2) if moving else None,
            "swing_max_pct": round(100 * float(dev.max()), 2) if moving else None,
            "turn_dev_pct": round(100 * turn_deviation(turns, rate), 2) if moving else None,
            "old_rule": old_rule(counts, rate, cpr), "new_rule": new}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset", nargs="+", help="the generated datasets of analysis/datasets/speed_swing*.toml")
    ap.add_argument("--out", default=str(HERE.parent / "results" / "identify" / "speed_swing.json"))
    args = ap.parse_args()

    from twin.dataset import open as open_dataset
    from twin.identification.features import RIPPLE_ALLOWANCE
    from twin.provenance import stamped

    runs = []
    names = []
    for d in args.dataset:
        ds = open_dataset(d)
        names.append(ds.info["name"])
        cpr = float(ds.info.get("encoder_counts_per_rev") or 32768)
        for r in ds.rows():
            runs.append(measure_run(ds, r, cpr))
    turning = [x for x in runs if x["turns"]]
    sw = np.array([x["swing_pct"] for x in turning])
    td = np.array([x["turn_dev_pct"] for x in turning], float)
    by_o = {o: [x["swing_pct"] for x in turning if x["orientation"] == o] for o in ("x", "y", "z")}
    threshold = 5.0 * math.ceil((float(sw.max()) + 100 * RIPPLE_ALLOWANCE) / 5.0)
    out = {
        "what": "crank-rate swing of steady running, motor drive with the drive train's placeholders drawn "
                "(analysis/identify/speed_swing.py)",
        "datasets": names, "runs": len(runs), "runs_that_turn": len(turning),
        "swing_pct": {"min": float(sw.min()), "median": float(np.median(sw)), "p90": float(np.quantile(sw, 0.9)),
                      "max": float(sw.max()),
                      "by_orientation": {o: ({"runs": len(v), "median": float(np.median(v)), "max": float(max(v))}
                                             if v else None) for o, v in by_o.items()}},
        "turn_dev_pct": {"median": float(np.nanmedian(td)), "max": float(np.nanmax(td))},
        "over_30_pct": int(np.sum(sw > 30.0)),
        "refused_old_rule_of_runs_that_turn": sum(x["old_rule"]["refused"] is not None for x in turning),
        "refused_new_rule_of_runs_that_turn": sum(x["new_rule"]["refused"] is not None for x in turning),
        "refused_new_rule_of_runs_that_stall": sum(x["new_rule"]["refused"] is not None for x in runs if not x["turns"]),
        "bench_swing_pct_threshold": threshold,
        "threshold_rule": "largest swing_pct of the runs that turn + the rule's allowance RIPPLE_ALLOWANCE (5 points), "
                          "rounded up to 5 %",
        "per_run": runs,
    }
    Path(args.out).write_text(json.dumps(stamped(out), indent=1) + "\n")
    print(f"{len(runs)} motor-drive runs, {len(turning)} turn ({len(runs) - len(turning)} stall): swing (95th pct of "
          f"the 50 ms rate's deviation, last half) median {np.median(sw):.1f} %, 90th pct {np.quantile(sw, 0.9):.1f} %, "
          f"max {sw.max():.1f} %; {out['over_30_pct']} over 30 %")
    for o, v in by_o.items():
        if v:
            print(f"  {o} vertical: {len(v)} runs, median {np.median(v):.1f} %, max {max(v):.1f} %")
    print(f"  whole turns' mean rate: deviation median {np.nanmedian(td):.1f} %, max {np.nanmax(td):.1f} %")
    print(f"  refused of the runs that turn: former rule (cap 30 %) {out['refused_old_rule_of_runs_that_turn']}, this "
          f"rule {out['refused_new_rule_of_runs_that_turn']} of {len(turning)}")
    print(f"  threshold BENCH_SWING_PCT = {threshold:g} %  -> {args.out}")


if __name__ == "__main__":
    main()
