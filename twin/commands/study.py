"""``twin study <STUDY>``: the project's numerical studies, one sub-subcommand each.

Every study is a library module of :mod:`twin.studies` that knows no command line: a frozen options
dataclass (its rules checked there, once), ``run_study(options)`` writing its outputs and returning
a typed result (``to_dict()`` = its JSON). This module parses each study's arguments into its
options and prints the result. Adding a study is a ``register_NAME(studies)`` function here and its
name in :data:`STUDIES`; keep heavy imports inside the handlers so ``twin --help`` stays fast.
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import Callable


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
    import dataclasses

    from twin.cli import load_config_file
    from twin.studies.formulations import FormulationsOptions, run_study
    from twin.util import check_output_dir

    opts = FormulationsOptions(args.out, None, args.duration, progress=not args.no_progress and sys.stderr.isatty(),
                               work_precision_methods={} if args.no_work_precision else None)  # checked first
    out = check_output_dir(args.out)
    cfg = load_config_file(args.config) if args.config else None
    res = run_study(dataclasses.replace(opts, out=out, config=cfg))
    print(f"wrote {out / 'formulations.md'}, {out / 'formulations.json'}, "
          + ", ".join(str(out / f) for f in res.figures))
    for r in res.rows:
        print(f"  {r.case:38s} dE {r.final_energy_error_J * 1e3:10.3f} mJ  max|Phi| {r.max_phi:9.2e}  "
              f"{'DIVERGED at %.3f s' % r.t_end_s if r.diverged else 'ok':22s} wall {r.wall_s:.3f} s")
    if res.work_precision:
        print(f"work-precision, theta({args.duration:g} s) error against the exact solution"
              + ("" if res.exudyn else " (Exudyn not installed: skipped)") + ":")
    for r in res.work_precision:
        err = r.theta_error_rad
        print(f"  {r.method:30s} h {r.timestep_s:<7g} {r.us_per_step:7.2f} us/step "
              f"{r.s_per_sim_s:8.4f} s/sim s  error {'failed' if err is None else format(err, '.2e'):>9s}"
              f"{'  P' if r.front else ''}")
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
        settings = dataclasses.replace(settings, window_s=args.window)
    out = check_output_dir(args.out)
    res = accuracy_study.run_study(accuracy_study.AccuracyOptions(
        out, settings, quick=args.quick, progress=not args.no_progress and sys.stderr.isatty()),
        log=lambda m: print(m, file=sys.stderr, flush=True))
    print(f"wrote {out / 'accuracy.md'}, {out / 'accuracy.json'} and {len(res.figures)} PNG plots")
    for r in res.summary:
        print(f"  {r.key:32s} {r.wall_per_sim_s:7.3f} s/sim s  score {r.score:6.2f}"
              f"{'  (default)' if r.key == res.default else ''}{'  P' if r.pareto else ''}")
    return 0


# ------------------------------------------------------------------ stability
def register_stability(studies: argparse._SubParsersAction) -> None:
    p = studies.add_parser(
        "stability", help="numerical-stability stress test of the MuJoCo twin over random scenes",
        description="N randomized scenes (clearances, orientation, drive program, timestep, contact parameters "
                    "within their calibrated uncertainty); per scene divergence, max penetration/clearance, "
                    "tracking error and an energy-balance residual. Writes stability.json, stability.md and "
                    "stability.png; exit status 0 when every scene passes (no divergence, pen/c <= 0.25).")
    p.add_argument("--scenes", type=int, required=True, metavar="N", help="number of scenes (>= 1)")
    p.add_argument("--seed", type=int, required=True, metavar="S", help="seed (>= 0); scene i depends on (S, i)")
    p.add_argument("--out", metavar="DIR", default="stability", help="output directory (default ./stability)")
    p.add_argument("--quick", action="store_true", help="short scenes (0.3-1.0 s instead of 0.5-3.0 s): the CI version")
    p.add_argument("--bench", action="store_true",
                   help="the whole bench: also draw the slider guide's clearance and the drive (crank PID or the "
                        "motor with its V-belt, the drive train's parameters over their ranges), and run every "
                        "scene in both engines (one row each)")
    p.add_argument("--structure", action="store_true",
                   help="every scene with the flexible structure (flexible rod, sprung frame and guide, sensor mounts), "
                        "its placeholders drawn over their documented ranges, in both engines (one row each)")
    p.add_argument("--family", choices=("bench", "spatial"), default="bench",
                   help="scene family: the bench's planar twin (default) or S002's spatial mechanism in both engines")
    p.add_argument("--durations", nargs=2, type=float, metavar=("LO", "HI"),
                   help="the scenes' simulated durations, uniform in [LO, HI] s (0 < LO <= HI; default 0.5-3.0 s, "
                        "0.3-1.0 s with --quick)")
    p.add_argument("--first", type=int, default=0, metavar="I",
                   help="index of the first scene (default 0): a long campaign in parts, joined by "
                        "twin.studies.stability.merge_results")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_run_stability)


def _run_stability(args: argparse.Namespace) -> int:
    import dataclasses

    from twin.studies.stability import StudySettings, one_line, quick, run_study
    from twin.util import check_output_dir

    settings = (quick(args.scenes, args.seed, args.bench) if args.quick
                else StudySettings(scenes=args.scenes, seed=args.seed, bench=args.bench))
    if args.family != "bench" or args.structure:
        settings = dataclasses.replace(settings, family=args.family, structure=args.structure)
    if args.durations is not None:
        settings = dataclasses.replace(settings, duration_range_s=tuple(args.durations))
    if args.first:
        settings = dataclasses.replace(settings, first=args.first)
    out = check_output_dir(args.out)
    res = run_study(settings, out=out, progress=not args.no_progress,
                    log=lambda m: print(m, file=sys.stderr, flush=True))
    print(one_line(res))
    return 0 if res.passed else 1


# ------------------------------------------------------------------ doe
def register_doe(studies: argparse._SubParsersAction) -> None:
    p = studies.add_parser(
        "doe", help="design of experiments with a Kriging surrogate (S000's method)",
        description="A Latin hypercube (or listed points) over named factors, simulated through the dataset "
                    "generator; per run the responses (max slider acceleration, contact force, power); a Kriging "
                    "surrogate of each (scikit-learn Gaussian process, anisotropic Matern kernel) with its "
                    "leave-one-out error; its global optimum (differential evolution), simulated; hold-out "
                    "predictions; Sobol sensitivities; a PNG of each surrogate. SPEC is a dataset spec with a "
                    "[doe] table (the shipped s000_example1 is S000's Example 1).")
    p.add_argument("spec", metavar="SPEC", help="DOE spec: a dataset spec plus [doe], a .toml file or the name of one "
                   "that ships with twin (s000_example1)")
    p.add_argument("--out", metavar="DIR", required=True, help="output directory (created; a second call resumes)")
    p.add_argument("--workers", type=int, metavar="N", help="simulations at a time (default: the cores)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_run_doe)


def _run_doe(args: argparse.Namespace) -> int:
    from twin.commands.inputs import spec
    from twin.studies.doe import DoeOptions, load_doe, run_study
    from twin.util import check_output_dir

    doe = load_doe(spec(args.spec))
    opts = DoeOptions(doe, args.out, args.workers, progress=not args.no_progress and sys.stderr.isatty())
    out = check_output_dir(args.out)
    res = run_study(opts, log=lambda m: print(m, file=sys.stderr, flush=True))
    print(f"wrote {out / 'doe.md'}, {out / 'doe.json'}, " + ", ".join(str(out / f) for f in res.figures))
    for r, s in res.responses.items():
        o = s.optimum
        print(f"  {r:18s} LOO RMSE/std {s.loo_stats['rmse_over_std']:.3f}  {doe.goal} "
              + ", ".join(f"{n}={v:.4g}" for n, v in o["factors"].items()) + f" -> {o['predicted']:.4g}")
    for c in res.checks:
        print(f"  {c.kind:8s} " + ", ".join(f"{n}={v:.4g}" for n, v in c.factors.items()) + ": "
              + ", ".join(f"{r} {c.responses[r]:.3g} (pred {c.predicted[r]['mean']:.3g})" for r in res.responses))
    return 0


# ------------------------------------------------------------------ continuous contact
def register_continuous_contact(studies: argparse._SubParsersAction) -> None:
    p = studies.add_parser(
        "continuous-contact", help="S004's continuous-contact model (clearance at B as a massless virtual rod)",
        description="S004 §2.1: the clearance at the crank-rod joint B as a massless rod of length c, the crank "
                    "prescribed, one degree of freedom from Lagrange's equations. Runs it "
                    "from the quasi-static start (the journal where the ideal pin force pushes it) and writes "
                    "continuous_contact.json (the crank angle up to which the journal stays on the wall, f_N >= 0, "
                    "and the slider's deviation from the ideal motion up to there), continuous_contact.npz (time "
                    "series) and continuous_contact.png. (In the repository, python analysis/s004_report.py compares "
                    "it with the contact model.)")
    p.add_argument("--preset", metavar="NAME", help="mechanism (default s004)")
    p.add_argument("--config", metavar="FILE",
                   help="TOML configuration instead of the preset: a file replaces s004 (its missing fields are "
                        "twin's default bench's); write preset = \"s004\" in it to start from s004")
    p.add_argument("--clearance-b", type=float, metavar="MM", help="diametral clearance at B [mm] (S004: 0.5, 1.0)")
    p.add_argument("--duration", type=float, default=2 * math.pi / 30.0, metavar="S",
                   help="simulated time [s] (default one turn at 30 rad/s)")
    p.add_argument("--out", metavar="DIR", required=True, help="output directory (created if missing)")
    p.set_defaults(func=_run_continuous_contact)


def _run_continuous_contact(args: argparse.Namespace) -> int:
    from twin.cli import load_config_file
    from twin.config import named_preset
    from twin.errors import ConfigError
    from twin.studies.continuous_contact import ContinuousContactOptions, run_study
    from twin.util import check_output_dir

    if args.config and args.preset:
        raise ConfigError("--preset", "cannot be combined with --config (put 'preset = \"NAME\"' in the file)")
    cfg = load_config_file(args.config) if args.config else named_preset(args.preset or "s004")
    # a --config file replaces the s004 preset, not merged with it: said once, in the error or as a note
    replaced = (f"{args.config} replaces the s004 preset: its missing fields are twin's default bench's; write "
                "preset = \"s004\" in it to start from s004") if args.config and not _starts_from_preset(args.config) \
        else None
    if args.clearance_b is not None:
        cfg = cfg.replace(**{"joints.clearance_b_mm": args.clearance_b, "joints.allow_noncatalogue": True})
    try:
        opts = ContinuousContactOptions(args.out, cfg, args.duration)
    except ConfigError as err:
        if replaced and err.field and err.field.startswith(("joints.", "mechanism.", "drive.")):
            raise ConfigError(err.field, f"{err.message} ({replaced})") from None
        raise
    if replaced:
        print(f"twin: note: {replaced}", file=sys.stderr)
    out = check_output_dir(args.out)
    sm = run_study(opts).summary
    print(f"continuous-contact model, c = {1e3 * sm.clearance_radial_m:g} mm: journal on the wall up to "
          f"{sm.valid_until_crank_deg:.1f} deg; deviation from the ideal slider until then: "
          f"x {1e3 * sm.dx_max_m:.3f} mm, v {sm.dv_max_mps:.3f} m/s, a {sm.da_max_mps2:.0f} m/s^2; wrote {out}")
    return 0


def _starts_from_preset(path: str) -> bool:
    """Whether the TOML file ``path`` (already read by the configuration) starts from a preset or test."""
    import tomllib
    from pathlib import Path

    data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    return "preset" in data or "test" in data


# ------------------------------------------------------------------ mcdm
def register_mcdm(studies: argparse._SubParsersAction) -> None:
    from twin.studies.mcdm import WASPAS_LAMBDA

    p = studies.add_parser(
        "mcdm", help="rank alternatives by several criteria: GRA, TOPSIS, SAW, WASPAS (S002's methods)",
        description="Rank the rows of a CSV of responses by several criteria with grey relational analysis "
                    "(xi = 0.5), TOPSIS, SAW and WASPAS (standard form and S002's variant), the criteria weighted "
                    "by MEREC, equally or as given, each by its original definition. The alternatives are named "
                    "by a name column when the CSV has one (--name-column), else by row number. Writes "
                    "DIR/mcdm.json and DIR/report.md (the formulas, the weights, every score and rank).")
    p.add_argument("responses", metavar="RESPONSES.csv", help="CSV with a header row, one row per alternative")
    p.add_argument("--name-column", metavar="COL",
                   help="column naming the alternatives (default: the first column of text that names every row "
                        "once; without one, alternatives are numbered by row)")
    p.add_argument("--criteria", required=True, metavar="NAME:min|max,…",
                   help="criterion columns and whether smaller (min) or larger (max) is better")
    p.add_argument("--weights", default="merec", metavar="merec|equal|W1,W2,…",
                   help="MEREC weights (default), equal weights or one weight >= 0 per criterion (scaled to sum 1)")
    p.add_argument("--waspas-lambda", type=float, default=WASPAS_LAMBDA, metavar="L",
                   help=f"lambda of WASPAS in [0, 1] (default {WASPAS_LAMBDA}, S002's; the original method uses 0.5)")
    p.add_argument("--out", required=True, metavar="DIR", help="output directory (created if missing)")
    # twin.studies.mcdm's names for what these set
    p.set_defaults(func=_run_mcdm, _field_flags={"csv_path": "RESPONSES.csv", "lam": "--waspas-lambda",
                                                 "names_from": "--name-column"})


def _run_mcdm(args: argparse.Namespace) -> int:
    from twin.studies.mcdm import METHODS, McdmOptions, run_study
    from twin.util import check_output_dir

    out = check_output_dir(args.out)
    res = run_study(McdmOptions(args.responses, args.criteria, out, args.weights, args.waspas_lambda,
                                args.name_column))
    w = ", ".join(f"{c.name} {v:.4f}" for c, v in zip(res.criteria, res.weights))
    print(f"wrote {out / 'mcdm.json'}, {out / 'report.md'}; weights ({res.weights_source}): {w}")
    for k in METHODS:
        print(f"  {k:7s} best {'alternative' if res.name_column else 'row'} {res.best(k)}")
    return 0


# ------------------------------------------------------------------ taguchi
def register_taguchi_analyze(studies: argparse._SubParsersAction) -> None:
    from twin.studies.taguchi import SN_KINDS

    p = studies.add_parser(
        "taguchi-analyze", help="Taguchi analysis of an orthogonal-array experiment from a CSV of runs (S002)",
        description="S/N ratios (smaller- or larger-the-better), main effects, ANOVA with contributions, F and p "
                    "(raw responses and S/N; interactions and pooling on request) and the additive-model prediction "
                    "at the best levels with its confidence intervals, from a CSV with one row per run. Writes "
                    "DIR/taguchi.json, DIR/report.md and per response main-effect and S/N PNG plots.")
    p.add_argument("responses_csv", metavar="RESPONSES.csv", help="CSV with a header row, one row per run")
    p.add_argument("--responses", required=True, metavar="COL,…",
                   help="response columns; COL1+COL2 names the replicates of one response")
    p.add_argument("--factors", required=True, metavar="COL,…", help="factor columns (their distinct values are the levels)")
    p.add_argument("--sn", default="smaller", choices=SN_KINDS, help="S/N ratio kind (default smaller-the-better)")
    p.add_argument("--interactions", metavar="A*B,…", help="two-factor interactions to include in the ANOVA")
    p.add_argument("--pool", metavar="TERM,…", help="terms pooled into the error (e.g. speed or A*B)")
    p.add_argument("--predict-with", metavar="FACTOR,…", help="factors of the prediction at the optimum (default all)")
    p.add_argument("--alpha", type=float, default=0.05, help="significance level of the intervals (default 0.05)")
    p.add_argument("--confirmation-runs", type=int, default=1, metavar="R",
                   help="R of the confirmation-run interval (default 1)")
    p.add_argument("--out", required=True, metavar="DIR", help="output directory (created if missing)")
    p.set_defaults(func=_run_taguchi_analyze, _field_flags={"csv_path": "RESPONSES.csv"})


def _print_taguchi(res, out) -> None:
    print(f"wrote {out / 'taguchi.json'}, {out / 'report.md'}, " + ", ".join(str(out / f) for f in res.figures))
    for spec, r in res.responses.items():
        a = r.sn_analysis
        best = ", ".join(f"{f}={res.levels[i][a.optimum_levels[i]]:g}" for i, f in enumerate(res.factors))
        print(f"  {spec}: best S/N levels {best}; predicted S/N {a.prediction.predicted:.4g} dB")


def _run_taguchi_analyze(args: argparse.Namespace) -> int:
    from twin.studies.taguchi import TaguchiOptions, run_study
    from twin.util import check_output_dir

    out = check_output_dir(args.out)
    _print_taguchi(run_study(TaguchiOptions(args.responses_csv, args.responses, args.factors, out, args.sn,
                                            args.interactions, args.pool, args.predict_with, args.alpha,
                                            args.confirmation_runs)), out)
    return 0


def register_taguchi(studies: argparse._SubParsersAction) -> None:
    p = studies.add_parser(
        "taguchi", help="an orthogonal-array experiment (S002's L27) simulated, then its Taguchi analysis",
        description="S002's Taguchi experiment: simulates every run of SPEC's orthogonal array (a dataset spec "
                    "with a list design, one point per run, and a [taguchi] table naming the analysis factors and "
                    "the responses; the shipped s002_l27 is S002's L27: crank length, clearance, friction and "
                    "speed at three levels in 27 runs) through the dataset generator into DIR/dataset (a second "
                    "call resumes), computes each run's responses after settle_s (the slider's largest "
                    "acceleration, the largest contact force per joint), writes DIR/responses.csv and analyses "
                    "it as twin study taguchi-analyze does: S/N ratios, main effects, ANOVA with contributions, "
                    "the prediction at the optimum with its confidence intervals, PNG plots.")
    p.add_argument("spec", metavar="SPEC", help="Taguchi study spec: a dataset spec plus [taguchi], a .toml file or the "
                   "name of one that ships with twin (s002_l27)")
    p.add_argument("--out", required=True, metavar="DIR", help="output directory (created if missing)")
    p.add_argument("--workers", type=int, default=None, metavar="N", help="worker processes (default: all cores)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_run_taguchi)


def _run_taguchi(args: argparse.Namespace) -> int:
    from twin.commands.inputs import spec as spec_arg
    from twin.studies.taguchi_run import TaguchiRunOptions, load_taguchi, run_study
    from twin.util import check_output_dir

    spec = load_taguchi(spec_arg(args.spec))
    opts = TaguchiRunOptions(spec, args.out, args.workers, not args.no_progress and sys.stderr.isatty())
    out = check_output_dir(args.out)
    check_output_dir(out / "dataset", "--out", need_parent=False)
    res = run_study(opts)
    print(f"simulated {len(res.runs)} runs ({spec.dataset.engine}, {spec.dataset.duration_s:g} s each) in "
          f"{res.wall_s:.1f} s; wrote {out / 'responses.csv'}")
    _print_taguchi(res.analysis, out)
    return 0


#: the ``twin study`` subcommands, in help order
STUDIES: tuple[Callable[[argparse._SubParsersAction], None], ...] = (
    register_formulations, register_accuracy, register_stability, register_doe, register_continuous_contact,
    register_mcdm, register_taguchi_analyze, register_taguchi,
)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("study", help="run a numerical study (formulations, ...)",
                       description="Numerical studies of the twin and its reference engine.")
    studies = p.add_subparsers(dest="study", metavar="STUDY", parser_class=type(p))
    studies.required = True
    for add in STUDIES:
        add(studies)
