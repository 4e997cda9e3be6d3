"""``twin calibrate``: fit configuration fields to bench recordings (:func:`twin.calibration.calibrate`).

The contact-law check that this name used to alias is ``twin check contact``.
"""

from __future__ import annotations

import argparse
import re
import sys

from twin.util import resolve_workers


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "calibrate", help="fit uncertain configuration fields (restitution, friction, drive train) to bench recordings",
        description="Fit configuration fields (dotted paths) to one or more bench recordings: band energies, impact "
                    "peaks, DTW and crank-speed ripple of the replayed twin against the recording, a global (Sobol) "
                    "then a local (Nelder-Mead) search, intervals and identifiability warnings. Writes "
                    "OUT/calibrated.toml (a partial configuration for --config), report.md/.json, PNGs and the "
                    "evaluation log that a second run with the same inputs resumes. See docs/calibration.md.")
    p.add_argument("recording", metavar="RECORDING", nargs="+", help="bench recording(s) (.mcap)")
    p.add_argument("--params", required=True, metavar="FIELD,FIELD",
                   help="configuration fields to fit, e.g. contact.restitution,contact.mu0")
    p.add_argument("--config", metavar="BASE.toml",
                   help="configuration the fields are set in for every recording (default: each recording's own)")
    p.add_argument("--bounds", action="append", default=[], metavar="FIELD=LO:HI",
                   help="bounds of a field (default: its documented range); repeat for several fields")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (a previous run's log there is resumed)")
    p.add_argument("--drive", choices=("trace", "program"), default="trace",
                   help="trace: the recorded encoder drives the crank PID, as twin replay (default); program: the "
                        "configuration's own drive program (synthetic recordings, known programs)")
    p.add_argument("--global-points", type=int, default=16, dest="n_global", metavar="N",
                   help="Sobol points of the global stage (default 16)")
    p.add_argument("--local-short", type=int, default=20, metavar="N",
                   help="Nelder-Mead evaluations on short windows (default 20)")
    p.add_argument("--local-full", type=int, default=12, metavar="N",
                   help="Nelder-Mead evaluations on the whole recordings (default 12)")
    p.add_argument("--profile-steps", default="0.01,0.03,0.1,0.25", metavar="D,D",
                   help="offsets of the profile points, as shares of each parameter's range (default 0.01,0.03,0.1,0.25)")
    p.add_argument("--short-fraction", type=float, default=0.5, metavar="F",
                   help="share of each recording simulated in the short stage (default 0.5)")
    p.add_argument("--workers", type=int, default=1, metavar="N", help="worker processes (default 1)")
    p.add_argument("--seed", type=int, default=0, help="seed of the Sobol sample (default 0)")
    p.add_argument("--replicates", type=int, default=4, metavar="K",
                   help="noise replicates per full-length evaluation: other sensor-noise realizations of the same "
                        "simulation, whose minimizers' scatter widens each interval by the noise's share "
                        "(default 4; 0: the objective-rise rule alone)")
    p.add_argument("--boot-replicates", type=int, default=400, metavar="B",
                   help="replicates of the block bootstrap over crank turns at the fitted point (default 400; 0: none)")
    p.add_argument("--restarts", type=int, default=2, metavar="R",
                   help="local searches restarted from the next-best global points while the fit misses the "
                        "recordings (default 2; 0: none)")
    p.add_argument("--interval", choices=("bootstrap", "hull", "dj"), default="bootstrap",
                   help="the reported interval: bootstrap (with the objective's jitter, default), hull (of it and the "
                        "objective-rise interval) or dj (the objective-rise interval with the noise replicates')")
    p.add_argument("--waveform", action=argparse.BooleanOptionalAction, default=False,
                   help="after the feature fit, least squares on the low-passed replayed accelerations, where the "
                        "fitted point's replay is not chaotic (default off: on a bench it may fit model error; "
                        "the report gives each change against its interval)")
    p.add_argument("--waveform-budget", type=int, default=16, metavar="N",
                   help="replays of all recordings the waveform stage may use (default 16)")
    p.add_argument("--no-plots", action="store_true", help="no PNG figures")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=run, _field_flags={"params": "--params", "bounds": "--bounds", "recordings": "RECORDING...",
                                           "out": "--out", "n_global": "--global-points",
                                           "local_short": "--local-short", "local_full": "--local-full",
                                           "short_fraction": "--short-fraction", "workers": "--workers",
                                           "seed": "--seed", "log": "--out",
                                           "profile_steps": "--profile-steps",
                                           "boot_replicates": "--boot-replicates", "interval": "--interval",
                                           "restarts": "--restarts", "waveform": "--waveform",
                                           "waveform_budget": "--waveform-budget"})


#: option fields the library's warnings name, as this command's flags
_WARNING_FLAGS = {"n_global": "--global-points", "local_full": "--local-full", "local_short": "--local-short",
                  "boot_replicates": "--boot-replicates", "restarts": "--restarts"}


def check_outputs_are_not_inputs(out: str, recordings: list[str], config: str | None) -> None:
    """Refuse, before any work, an input that is one of the files a calibration writes in ``out``
    (``twin.calibration.calibrate.OUTPUT_FILES``: e.g. ``--config DIR/calibrated.toml --out DIR``, a calibration
    started from the last one's result, would write over its base). Anything else in the folder is safe: a
    calibration writes only those names there, each through a temporary file renamed into place."""
    from pathlib import Path

    from twin.calibration.calibrate import OUTPUT_FILES
    from twin.errors import TwinError
    from twin.util import show

    inputs = [("--config", config)] if config else []
    inputs += [("RECORDING", r) for r in recordings]
    for name in OUTPUT_FILES:
        target = (Path(out) / name).resolve()
        for flag, path in inputs:
            if Path(path).resolve() == target:
                raise TwinError(f"{show(out)} would receive {name}, written over the input {flag} {show(path)}; "
                                f"give another folder or move the input (a calibration writes "
                                f"{', '.join(OUTPUT_FILES)} there)", field="--out")


def run(args: argparse.Namespace) -> int:
    from twin.calibration import CalibrationOptions, calibrate, parse_bounds
    from twin.cli import load_config_file
    from twin.errors import TwinError

    check_outputs_are_not_inputs(args.out, args.recording, args.config)
    workers = resolve_workers(args.workers, "workers")
    bounds = parse_bounds(args.bounds)
    try:
        steps = tuple(float(x) for x in args.profile_steps.split(",") if x.strip())
    except ValueError:
        raise TwinError(f"expected numbers separated by commas, got {args.profile_steps!r}",
                        field="--profile-steps") from None
    opts = CalibrationOptions(profile_steps=steps, n_global=args.n_global, local_short=args.local_short, local_full=args.local_full,
                              replicates=args.replicates, boot_replicates=args.boot_replicates, restarts=args.restarts,
                              interval=args.interval, waveform=args.waveform, waveform_budget=args.waveform_budget,
                              short_fraction=args.short_fraction, drive=args.drive, workers=workers, seed=args.seed,
                              plots=not args.no_plots, progress=not args.no_progress and sys.stderr.isatty())
    cfg = load_config_file(args.config) if args.config else None
    res = calibrate(args.recording, args.params, args.out, config=cfg, bounds=bounds, options=opts,
                    note=lambda s: print(s, file=sys.stderr))
    print("| field | base | fitted | interval | notes |")
    print("|---|---|---|---|---|")
    for p in res.parameters:
        notes = ", ".join(x for x in ("FLAT" if p.flat else "", "ROUGH" if p.rough else "",
                                      f"on {p.on_bound} bound" if p.on_bound else "",
                                      f"waveform stage (features: {p.feature_value:.6g})"
                                      if p.feature_value == p.feature_value else "") if x)
        print(f"| {p.field} | {p.base:.4g} | {p.value:.4g} | {p.lo:.4g} – {p.hi:.4g} | {notes} |")
    for w in res.warnings:
        for field, flag in _WARNING_FLAGS.items():   # the library names options' fields; the CLI says the flags
            w = re.sub(rf"\b{field}\b", flag, w)
        print(f"warning: {w}", file=sys.stderr)
    print(f"objective {res.objective_before:.4g} -> {res.objective_after:.4g}; {res.evaluations} evaluations "
          f"({res.simulated} simulated, {res.resumed} from the log) in {res.wall_s:.1f} s; wrote {res.out_dir}/"
          "calibrated.toml and report.md")
    return 0
