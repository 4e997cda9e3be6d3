"""Approximate warm starts against the repeat-to-repeat scatter, on runs of the nuisance spec.

Method: the nuisance identification spec (``analysis/datasets/clearance_id_nuisance.toml``, every run
its own mechanism) is grouped as ``twin dataset generate --approx-warm-start`` groups it
(:func:`twin.warm_approx.approx_groups`). For ``--cases`` groups of two or more runs (taken evenly over
the groups in design order), the group's second run is simulated three ways, each for the spec's
whole duration:

* **fresh**: from rest, as without the approximation;
* **approx**: switched from the spin-up of the group's first run (:func:`twin.warm_approx.simulate_approx`),
  its features from ``valid_from_s`` on (what the identification reads of such a file);
* **repeat**: from rest with another sensor-noise seed and another start angle (drawn): the scatter
  between two recordings of one configuration, the basis of the comparison (independent of the
  approximation).

Each run's features (:mod:`twin.identification.features`, mean over its windows, through its own sensor
chain) are standardized by each feature's spread over the fresh runs of the sample; D(x, fresh) is the
RMS over features of the standardized difference. Printed: per case D(approx, fresh) and D(repeat,
fresh); per feature the ratio of the summed |approx − fresh| to the summed |repeat − fresh|; the verdict
(mean D(approx) below mean D(repeat)). Also the wall time of the three arms (engine runs side by side in
one process).

Run: ``python analysis/warm_approx_check.py [--cases 6] [--duration 3.0] [--switch-s 0.35] [--settle-s 0.1]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spec", default="analysis/datasets/clearance_id_nuisance.toml")
    ap.add_argument("--cases", type=int, default=6)
    ap.add_argument("--duration", type=float, default=None, help="run duration [s] (default: the spec's)")
    ap.add_argument("--switch-s", type=float, default=None)
    ap.add_argument("--settle-s", type=float, default=None)
    ap.add_argument("--seed", type=int, default=47)
    args = ap.parse_args()

    from twin.config import with_overrides
    from twin.dataset.design import plan
    from twin.dataset.spec import load_spec
    from twin.identification.features import feature_names
    from twin.provenance import git_commit
    from twin.warm_approx import SETTLE_S, approx_groups, compare_case
    from twin import __version__

    settle = SETTLE_S if args.settle_s is None else args.settle_s
    spec = load_spec(args.spec)
    cfgs = [r.config for r in plan(spec)]
    groups = [g for g in approx_groups(cfgs) if len(g) >= 2]
    pick = [groups[int(k)] for k in np.linspace(0, len(groups) - 1, args.cases)]
    rng = np.random.default_rng(args.seed)
    print(f"twin {__version__}, commit {git_commit()}; {args.spec}: {len(cfgs)} runs in {len(groups)} groups of 2+ "
          f"(approx_groups); {args.cases} cases; switch {args.switch_s or 'ramp + 0.05'} s, settle {settle} s")
    rows, walls = [], np.zeros(3)
    for n, g in enumerate(pick):
        ov = {} if args.duration is None else {"simulation.duration_s": args.duration}
        ref, cfg = with_overrides(cfgs[g[0]], ov), with_overrides(cfgs[g[1]], ov)
        rep = with_overrides(cfg, {"instrumentation.seed": int(rng.integers(2**62)),
                                   "drive.initial_encoder_angle_rad": float(rng.uniform(0, 2 * np.pi))})
        t = time.perf_counter()
        f = compare_case(ref, cfg, rep, args.switch_s, settle)
        walls[0] += time.perf_counter() - t
        rows.append(f)
        print(f"case {n}: {cfg.joints.clearance_joints or ('none',)} b={cfg.joints.clearance_b_mm:.3f} "
              f"c={cfg.joints.clearance_c_mm:.3f} mm, {cfg.mechanism.orientation} vertical, {cfg.drive.motor_rpm:g} rpm "
              f"(spin-up of b={ref.joints.clearance_b_mm:.3f} c={ref.joints.clearance_c_mm:.3f} mm)", flush=True)
    F = np.array([r["fresh"] for r in rows])
    A = np.array([r["approx"] for r in rows])
    R = np.array([r["repeat"] for r in rows])
    scale = F.std(axis=0, ddof=1)
    ok = scale > 1e-12 * (1 + np.abs(F).max(axis=0))  # constant features (orientation one-hot of one value)
    dA = np.sqrt(np.mean(((A - F)[:, ok] / scale[ok]) ** 2, axis=1))
    dR = np.sqrt(np.mean(((R - F)[:, ok] / scale[ok]) ** 2, axis=1))
    print("\n| case | D(approx, fresh) | D(repeat, fresh) |\n|---|---|---|")
    for n in range(len(rows)):
        print(f"| {n} | {dA[n]:.3f} | {dR[n]:.3f} |")
    print(f"| mean | **{dA.mean():.3f}** | **{dR.mean():.3f}** |")
    names = np.array(feature_names())
    ratio = np.abs(A - F).sum(axis=0)[ok] / np.maximum(np.abs(R - F).sum(axis=0)[ok], 1e-300)
    print(f"\nper feature, sum |approx - fresh| / sum |repeat - fresh| over the cases: median {np.median(ratio):.2f}, "
          f"below 1 for {np.sum(ratio < 1)} of {ok.sum()} features; largest: " +
          ", ".join(f"{n} {r:.2f}" for n, r in sorted(zip(names[ok], ratio), key=lambda x: -x[1])[:6]))
    print(f"verdict: mean D(approx) {'<' if dA.mean() < dR.mean() else '>='} mean D(repeat) "
          f"({dA.mean() / dR.mean():.2f}x)")


if __name__ == "__main__":
    main()
