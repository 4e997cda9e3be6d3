"""``twin study <STUDY>``: the project's numerical studies, one sub-subcommand each.

Adding a study is one line: append ``"module:function"`` to :data:`STUDIES`, where
``function(subparsers)`` adds the study's parser to the ``twin study`` group and sets
``func`` (a handler taking the parsed arguments, returning an exit status), exactly like a
top-level command's ``register``. Keep heavy imports inside the handler so ``twin --help``
stays fast.
"""

from __future__ import annotations

import argparse
import importlib
import math

#: "module:function" registering each ``twin study`` subcommand, in help order
STUDIES: list[str] = [
    "twin.commands.study:register_formulations",
    "twin.commands.study:register_accuracy",
    "twin.studies.stability:register",
    "twin.studies.doe:register",
    "twin.studies.continuous_contact:register",
    "twin.studies.mcdm:register",
    "twin.studies.taguchi:register",
    "twin.studies.taguchi_run:register",
]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("study", help="run a numerical study (formulations, ...)",
                       description="Numerical studies of the twin and its reference engine.")
    studies = p.add_subparsers(dest="study", metavar="STUDY", parser_class=type(p))
    studies.required = True
    for entry in STUDIES:
        mod, func = entry.split(":")
        getattr(importlib.import_module(mod), func)(studies)


# ------------------------------------------------------------------ formulations
def register_formulations(studies: argparse._SubParsersAction) -> None:
    p = studies.add_parser(
        "formulations", help="S003 §4.1: R-matrix versus penalty formulation",
        description="S003 §4.1: the ideal mechanism released at rest at θ = π/3 under gravity (−y), no drive, "
                    "no friction, integrated with symplectic Euler by the R-matrix and by the penalty formulation "
                    "(several α, ζ, ω) at h = 1e-4 s and 1e-3 s, then a work-precision comparison of θ(T) "
                    "(R-matrix with symplectic Euler and explicit midpoint, the MuJoCo twin with Euler and RK4, "
                    "Exudyn's generalized-α when installed). Writes formulations.md, formulations.json and PNG "
                    "plots of crank speed, mechanical energy, ‖Φ‖ and work-precision.")
    p.add_argument("--out", metavar="DIR", required=True, help="output directory (created if missing)")
    p.add_argument("--config", metavar="FILE",
                   help="TOML configuration for the bodies and d_off (joints are made ideal, y up)")
    p.add_argument("--duration", type=float, default=5.0, metavar="S", help="simulated time [s] (default 5)")
    p.add_argument("--no-work-precision", action="store_true",
                   help="skip the work-precision comparison (R-matrix Euler/midpoint, MuJoCo Euler/RK4, Exudyn)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_run_formulations)


def _run_formulations(args: argparse.Namespace) -> int:
    import sys

    from twin.config import load_config
    from twin.errors import ConfigError
    from twin.util import check_output_dir

    if not (0 < args.duration <= 60):
        raise ConfigError("--duration", f"must lie in (0, 60] s, got {args.duration!r}")
    out = check_output_dir(args.out)
    cfg = load_config(args.config) if args.config else None

    from twin.studies.formulations import run_study

    data = run_study(out, cfg, args.duration, progress=not args.no_progress and sys.stderr.isatty(),
                     work_precision_methods={} if args.no_work_precision else None)
    print(f"wrote {out / 'formulations.md'}, {out / 'formulations.json'}, "
          + ", ".join(str(out / f) for f in data["figures"]))
    for r in data["rows"]:
        print(f"  {r['case']:38s} dE {r['final_energy_error_J'] * 1e3:10.3f} mJ  max|Phi| {r['max_phi']:9.2e}  "
              f"{'DIVERGED at %.3f s' % r['t_end_s'] if r['diverged'] else 'ok':22s} wall {r['wall_s']:.3f} s")
    if data["work_precision"]:
        print(f"work-precision, theta({args.duration:g} s) error against the exact solution"
              + ("" if data["exudyn"] else " (Exudyn not installed: skipped)") + ":")
    for r in data["work_precision"]:
        err = r["theta_error_rad"]
        print(f"  {r['method']:30s} h {r['timestep_s']:<7g} {r['us_per_step']:7.2f} us/step "
              f"{r['s_per_sim_s']:8.4f} s/sim s  error {'failed' if err is None else format(err, '.2e'):>9s}"
              f"{'  P' if r['front'] else ''}")
    return 0


# ------------------------------------------------------------------ accuracy
def register_accuracy(studies: argparse._SubParsersAction) -> None:
    p = studies.add_parser(
        "accuracy", help="run time versus error of the twin's variants against the converged reference",
        description="Table 4 tests 4-12: every MuJoCo variant (timestep, integrator, solver, contact calibration, "
                    "bushing representation) and the reference at its default step, against the reference at "
                    "h = 1e-6 s. Writes accuracy.md, accuracy.json and work-precision PNGs.")
    p.add_argument("--out", metavar="DIR", required=True, help="output directory (created if missing)")
    p.add_argument("--quick", action="store_true",
                   help="reduced version (tests 6 and 12, 0.3 s windows, 4 variants; about a minute)")
    p.add_argument("--tests", metavar="IDS", help="comma-separated Table 4 tests with a clearance (default 4..12)")
    p.add_argument("--window", type=float, metavar="S", help="analysed window [s] (default 2; quick 0.3)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_run_accuracy)


def _run_accuracy(args: argparse.Namespace) -> int:
    import dataclasses
    import sys

    from twin.errors import ConfigError
    from twin.studies import accuracy as accuracy_study
    from twin.util import check_output_dir

    settings = accuracy_study.QUICK if args.quick else accuracy_study.StudySettings()
    if args.tests is not None:
        try:
            tests = tuple(int(x) for x in args.tests.split(",") if x.strip())
        except ValueError:
            raise ConfigError("--tests", f"must be comma-separated integers from {list(accuracy_study.CLEARANCE_TESTS)}, "
                                         f"got {args.tests!r}") from None
        settings = dataclasses.replace(settings, tests=tests)
    if args.window is not None:
        if not (math.isfinite(args.window) and 0.05 <= args.window <= 60):
            raise ConfigError("--window", f"must lie in [0.05, 60] s, got {args.window!r}")
        settings = dataclasses.replace(settings, window_s=args.window)
    out = check_output_dir(args.out)
    data = accuracy_study.run_study(out, settings, quick=args.quick, progress=not args.no_progress and sys.stderr.isatty(),
                       log=lambda m: print(m, file=sys.stderr, flush=True))
    print(f"wrote {out / 'accuracy.md'}, {out / 'accuracy.json'} and {len(data['figures'])} PNG plots")
    for r in data["summary"]:
        print(f"  {r['key']:32s} {r['wall_per_sim_s']:7.3f} s/sim s  score {r['score']:6.2f}"
              f"{'  (default)' if r['key'] == data['default'] else ''}{'  P' if r.get('pareto') else ''}")
    return 0
