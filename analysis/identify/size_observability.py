"""How far the size of a clearance at C (or B) shows in the identification features, against what the
contact parameters' uncertainty does to them (issue 17: the size targets).

Method. For each orientation and motor speed asked, the MuJoCo twin runs a C-only fault (``--joint B``:
B-only) at three
neighbouring catalogue sizes (default 0.05, 0.07, 0.1 mm) with the nominal contact parameters and with
``--draws`` random draws of the parameters the datasets randomize (restitution 0.32-0.48, μ0
0.04-0.06, Eq. 18's K ±20 %, the twin's contact damping ×0.5-2, impact-speed gain ×0.5-2, guide
friction 1.5-4 N: ``analysis/datasets/clearance_id.toml``), the same draws at every size. The
features are ``twin.identification.features`` on the calibrated accelerations and encoder counts of the
bench's sensor chain (``twin.instrument``: sensor response, noise of its own seed per run, 18-bit DAQ,
static calibration), as a dataset run's; with ``--truth`` on the noise-free accelerations (the encoder
counts from the crank angle), an upper bound of what a recording can hold. With ``--start-angles`` each
draw after the nominal one also starts the crank at its own angle, drawn uniformly over a turn by a
generator of its own (the contact and sensor draws stay those of the run without it, paired): a bench
recording starts wherever the crank stood, and where the mechanism has more than one steady periodic
motion the start angle picks one (model card, "The sample recordings"). Per run: the features averaged
over its windows; the contact share (fn > 0 at the joint) and the impacts per crank turn after the spin-up.

Reported per scene and per pair of neighbouring sizes: how many features separate the two sizes
by more than the draws' spread (|Δ mean| / pooled standard deviation > 2), the largest such ratio,
and the leave-one-out accuracy of a shrinkage LDA that tells the three sizes apart from all features
(chance 1/3). A scene where the sizes are not separable with noise-free features is a physical limit
of size identification there, whatever the model.

Run: ``python analysis/identify/size_observability.py [--scenes y:475,z:475,x:325] [--sizes 0.05,0.07,0.1]
[--draws 6] [--duration 2.5] [--joint C] [--start-angles] [--json FILE]`` (about 2 min for the defaults on two cores).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from twin.provenance import stamped

CPR = 32768.0  # encoder counts per crank turn used to build the counts (any fine resolution)


def draws(n: int, seed: int = 17, start_angles: bool = False, nuisance: bool = False) -> list[dict[str, float]]:
    """The nominal parameters and ``n`` random draws over the datasets' ranges; with ``start_angles``
    each draw also gets a start angle of the crank [rad], uniform over a turn, from a generator of its
    own (seed + 1), so that the other draws are those without it. With ``nuisance`` the draws span the
    nuisance training ranges of ``analysis/datasets/clearance_id_nuisance.toml`` instead (restitution
    0.3-0.6, mu0 0.02-0.10, stiffness x0.5-2 log-uniform, the twin's contact damping and impact gain x0.5-2,
    guide friction 1-6 N, sensor noise x0.7-2)."""
    rng = np.random.default_rng(seed)
    angles = np.random.default_rng(seed + 1).uniform(0.0, 2 * math.pi, n)
    out = [{}]
    for i in range(n):
        if nuisance:
            out.append({"contact.restitution": float(rng.uniform(0.3, 0.6)),
                        "contact.mu0": float(rng.uniform(0.02, 0.10)),
                        "contact.stiffness_scale": float(np.exp(rng.uniform(np.log(0.5), np.log(2.0)))),
                        "mujoco.contact_damping_scale": float(rng.uniform(0.5, 2.0)),
                        "mujoco.impact_damping_gain": float(rng.uniform(0.5, 2.0)),
                        "mechanism.guide_friction_n": float(rng.uniform(1.0, 6.0)),
                        "instrumentation.noise_scale": float(rng.uniform(0.7, 2.0))}
                       | ({"drive.initial_encoder_angle_rad": float(angles[i])} if start_angles else {}))
            continue
        out.append({"contact.restitution": float(rng.uniform(0.32, 0.48)),
                    "contact.mu0": float(rng.uniform(0.04, 0.06)),
                    "contact.stiffness_scale": float(rng.uniform(0.8, 1.2)),
                    "mujoco.contact_damping_scale": float(rng.uniform(0.5, 2.0)),
                    "mujoco.impact_damping_gain": float(rng.uniform(0.5, 2.0)),
                    "mechanism.guide_friction_n": float(rng.uniform(1.5, 4.0))}
                   | ({"drive.initial_encoder_angle_rad": float(angles[i])} if start_angles else {}))
    return out


def one_run(job: tuple) -> dict:
    """Features (mean over windows), contact share and impacts per turn of one run."""
    from twin.config import BenchConfig
    from twin.identification.features import features
    from twin.simulation import simulate_run
    from twin.summary import count_impacts

    orientation, rpm, size, k, over, duration, sensed, joint = job
    other = "b" if joint == "C" else "c"
    cfg = BenchConfig().replace(**{
        f"joints.clearance_{other}_mm": 0.0, f"joints.clearance_{joint.lower()}_mm": size,
        "joints.allow_noncatalogue": True,  # --sizes may ask for values between the catalogue's
        "mechanism.orientation": orientation,
        "drive.program": "constant", "drive.motor_rpm": rpm, "drive.ramp_s": 0.3,
        "simulation.duration_s": duration, "sensors.channels": ["accel", "encoder", "crank", "joints"],
        "instrumentation.seed": 1000 + k, **over})
    run = simulate_run(cfg)
    if sensed:  # the bench's chain: sensor response, noise, 18-bit DAQ, encoder, static calibration
        from twin.identification.inputs import simulated_inputs

        acc, counts, rate, cpr = simulated_inputs(run, cfg)
    else:
        acc = {f"AC{i}": np.asarray(run[f"AC{i}"], float) for i in range(1, 7)}
        counts, cpr, rate = np.round(np.asarray(run["crank_angle"], float) / (2 * math.pi) * CPR), CPR, run.rate_hz
    X, _ = features(acc, counts, rate, cpr, 0.5, orientation)
    i0 = int(0.5 * run.rate_hz)
    fn = np.asarray(run[f"fn_{joint}"], float)[i0:]
    turns = abs(float(run["crank_angle"][-1] - run["crank_angle"][i0])) / (2 * math.pi)
    return {"orientation": orientation, "rpm": rpm, "size": size, "draw": k, "x": X.mean(axis=0).tolist(),
            "contact_share": float(np.mean(fn > 0)),
            "impacts_per_turn": count_impacts(fn > 0, run.rate_hz) / max(turns, 1e-9)}


def separation(rows: list[dict], sizes: list[float]) -> dict:
    """Per-feature separation of neighbouring sizes and the LOO accuracy of a shrinkage LDA."""
    from sklearn.discriminant_analysis import LinearDiscriminantAnalysis
    from sklearn.model_selection import LeaveOneOut, cross_val_score
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    X = np.array([r["x"] for r in rows])
    y = np.array([sizes.index(r["size"]) for r in rows])
    keep = np.std(X, axis=0) > 0
    X = X[:, keep]
    pairs = {}
    for a, b in zip(range(len(sizes)), range(1, len(sizes))):
        xa, xb = X[y == a], X[y == b]
        pooled = np.sqrt(0.5 * (xa.var(axis=0, ddof=1) + xb.var(axis=0, ddof=1))) + 1e-12
        d = np.abs(xa.mean(axis=0) - xb.mean(axis=0)) / pooled
        pairs[f"{sizes[a]:g}-{sizes[b]:g}"] = {"features_over_2": int(np.sum(d > 2)), "max_ratio": float(d.max())}
    lda = make_pipeline(StandardScaler(), LinearDiscriminantAnalysis(solver="lsqr", shrinkage="auto"))
    acc = float(np.mean(cross_val_score(lda, X, y, cv=LeaveOneOut())))
    return {"pairs": pairs, "loo_accuracy": acc, "runs": len(rows)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default="y:475,z:475,x:325", help="orientation:motor_rpm, comma-separated")
    ap.add_argument("--sizes", default="0.05,0.07,0.1", help="diametral clearances at the joint [mm]")
    ap.add_argument("--joint", choices=("B", "C"), default="C", help="the joint with the clearance (the other: "
                                                                       "a ball bearing)")
    ap.add_argument("--draws", type=int, default=6)
    ap.add_argument("--duration", type=float, default=2.5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--truth", action="store_true",
                    help="noise-free accelerations (an upper bound) instead of the bench's sensor chain")
    ap.add_argument("--start-angles", action="store_true",
                    help="each draw also starts the crank at an angle drawn over a turn (the nominal run at 0)")
    ap.add_argument("--nuisance", action="store_true",
                    help="draw the contact, guide and noise parameters over the nuisance training ranges")
    ap.add_argument("--json", metavar="FILE")
    args = ap.parse_args()
    scenes = [(s.split(":")[0], float(s.split(":")[1])) for s in args.scenes.split(",")]
    sizes = [float(v) for v in args.sizes.split(",")]
    params = draws(args.draws, start_angles=args.start_angles, nuisance=args.nuisance)
    jobs = [(o, rpm, c, k, p, args.duration, not args.truth, args.joint) for o, rpm in scenes for c in sizes
            for k, p in enumerate(params)]
    print(f"{len(jobs)} runs ({len(scenes)} scenes x {len(sizes)} sizes x {len(params)} parameter sets)",
          file=sys.stderr, flush=True)
    with ProcessPoolExecutor(args.workers) as ex:
        rows = list(ex.map(one_run, jobs))
    out = {"joint": args.joint, "sizes_mm": sizes, "draws": params, "sensed": not args.truth,
           "start_angles": args.start_angles, "nuisance": args.nuisance, "scenes": []}
    print(f"accelerations: {'noise-free truth' if args.truth else 'the bench sensor chain (noise, DAQ, calibration)'}")
    print("| scene | size [mm] | contact share (min-max) | impacts per turn (min-max) |")
    print("|---|---:|---:|---:|")
    for o, rpm in scenes:
        rs = [r for r in rows if r["orientation"] == o and r["rpm"] == rpm]
        for c in sizes:
            cs = [r for r in rs if r["size"] == c]
            share = [r["contact_share"] for r in cs]
            imp = [r["impacts_per_turn"] for r in cs]
            print(f"| {o} {rpm:g} rpm | {c:g} | {min(share):.3f}-{max(share):.3f} | {min(imp):.1f}-{max(imp):.1f} |")
        sep = separation(rs, sizes)
        out["scenes"].append({"orientation": o, "motor_rpm": rpm, **sep,
                              "runs_detail": [{k: v for k, v in r.items() if k != "x"} for r in rs]})
    print()
    print("| scene | sizes | features with abs(mean difference) > 2 x spread over the draws | largest ratio | "
          "LDA leave-one-out accuracy, three sizes (chance 0.33) |")
    print("|---|---|---:|---:|---:|")
    for s in out["scenes"]:
        for k, v in s["pairs"].items():
            print(f"| {s['orientation']} {s['motor_rpm']:g} rpm | {k} | {v['features_over_2']} | {v['max_ratio']:.1f} | "
                  f"{s['loo_accuracy']:.2f} |")
    if args.json:
        Path(args.json).write_text(json.dumps(stamped(out), indent=1))


if __name__ == "__main__":
    main()
