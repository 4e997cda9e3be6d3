"""``twin check contact``: check the twin's contact law against the reference's closed forms.

Nothing is fitted: the MuJoCo twin applies the reference's contact law itself (native module
``_bore.c``). The command checks that law as MuJoCo integrates it, for every joint and catalogue
clearance at the smallest, median and largest effective mass (method:
:mod:`twin.studies.contact_check`): static penetration (1 %), free single impacts over
1 mm/s-0.5 m/s (restitution ±0.02, peak force 5 %, duration 10 %) and the capture of preloaded
slow impacts. Writes a JSON report; exit status 1 when a case misses a tolerance.

``twin calibrate contact``, the old name of this command, is gone: ``twin calibrate`` now fits
configuration fields to bench recordings (:mod:`twin.commands.calibrate`).
"""

from __future__ import annotations

import argparse
import sys

_CONTACT_HELP = "check the twin's contact law against the reference's single-impact solutions"
_CONTACT_DESCRIPTION = (
    "The twin's native contact law in a MuJoCo probe (real bore collider and native module) against the "
    "reference law: static penetration (F/K)^(1/n) within 1 %, free single impacts 1 mm/s to 0.5 m/s at the "
    "smallest, median and largest effective mass (restitution +-0.02, peak force 5 %, duration 10 %), capture "
    "of preloaded slow impacts. Nothing is fitted. Exit status 1 when a case misses a tolerance.")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check", help="check the twin against the reference (contact law)",
                       description="Checks of the MuJoCo twin against the reference engine's closed forms.")
    _add_contact(p, _run_contact)


def _add_contact(parent: argparse.ArgumentParser, func) -> None:
    what = parent.add_subparsers(dest="what", metavar="WHAT", parser_class=type(parent))
    what.required = True
    c = what.add_parser("contact", help=_CONTACT_HELP, description=_CONTACT_DESCRIPTION)
    c.add_argument("--config", metavar="FILE", help="TOML configuration (contact law, materials, timestep)")
    c.add_argument("--out", metavar="FILE", default="contact_check.json",
                   help="JSON report to write (default contact_check.json)")
    c.add_argument("--joints", default="B,C", help="joints to check (default B,C)")
    c.add_argument("--no-progress", action="store_true", help="no progress bar")
    c.set_defaults(func=func)


def _run_contact(args: argparse.Namespace) -> int:
    import json
    from pathlib import Path

    from twin.cli import load_config_file
    from twin.config import BenchConfig
    from twin.provenance import stamped
    from twin.studies.contact_check import check_joints, contact_check
    from twin.util import atomic_write_text, check_output_file, json_text

    joints = check_joints(j.strip().upper() for j in args.joints.split(",") if j.strip())  # before any work
    out = Path(args.out)
    check_output_file(out, "--out", ".json")
    cfg = load_config_file(args.config) if args.config else BenchConfig()
    report = contact_check(cfg, joints=joints, progress=not args.no_progress and sys.stderr.isatty())
    atomic_write_text(out, json_text(stamped(report), indent=1) + "\n")
    print("| case | m_eff min/median/max [kg] | restitution/0.02 | peak force/5 % | duration/10 % | static | capture |")
    print("|---|---|---:|---:|---:|---:|---|")
    for key, r in report["cases"].items():
        m, e = r["m_eff_kg"], r["max_scaled_error"]
        print(f"| {key} | {m['min']:.2f}/{m['median']:.2f}/{m['max']:.2f} | {e['restitution']:.2f} | "
              f"{e['peak_force']:.2f} | {e['duration']:.2f} | {100 * r['static_error']:.3f} % | "
              f"{'same' if r['capture_agrees'] else 'DIFFERS'} |")
    print(f"wrote {out}: {'every case within the tolerances' if report['ok'] else 'some case misses a tolerance'} "
          f"(scaled errors <= 1 meet them)")
    return 0 if report["ok"] else 1
