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

#: "module:function" registering each ``twin study`` subcommand, in help order
STUDIES: list[str] = [
    "twin.commands.study:register_formulations",
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
                    "(several α, ζ, ω) at h = 1e-4 s and 1e-3 s. Writes formulations.md, formulations.json and PNG "
                    "plots of crank speed, mechanical energy and ‖Φ‖.")
    p.add_argument("--out", metavar="DIR", required=True, help="output directory (created if missing)")
    p.add_argument("--config", metavar="FILE",
                   help="TOML configuration for the bodies and d_off (joints are made ideal, y up)")
    p.add_argument("--duration", type=float, default=5.0, metavar="S", help="simulated time [s] (default 5)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_run_formulations)


def _run_formulations(args: argparse.Namespace) -> int:
    import sys
    from pathlib import Path

    from twin.config import load_config
    from twin.errors import ConfigError, TwinError

    if not (0 < args.duration <= 60):
        raise ConfigError("--duration", f"must lie in (0, 60] s, got {args.duration!r}")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise TwinError(f"--out: {out} exists and is not a directory")
    if not out.parent.exists():
        raise TwinError(f"--out: parent directory {out.parent} does not exist")
    cfg = load_config(args.config) if args.config else None

    from twin.reference.formulations import run_study

    data = run_study(out, cfg, args.duration, progress=not args.no_progress and sys.stderr.isatty())
    print(f"wrote {out / 'formulations.md'}, {out / 'formulations.json'}, "
          + ", ".join(str(out / f) for f in data["figures"]))
    for r in data["rows"]:
        print(f"  {r['case']:38s} dE {r['final_energy_error_J'] * 1e3:10.3f} mJ  max|Phi| {r['max_phi']:9.2e}  "
              f"{'DIVERGED at %.3f s' % r['t_end_s'] if r['diverged'] else 'ok':22s} wall {r['wall_s']:.3f} s")
    return 0
