"""``twin calibrate contact``: fit the MuJoCo pin/bushing contact to the reference law.

Method: :mod:`twin.calibrate` (module docstring). Writes the table the builder reads by
default (``twin/data/contact_calibration.json``) or ``--out FILE``; the write is atomic.
"""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("calibrate", help="calibrate the twin against the reference (contact)",
                       description="Calibrations of the MuJoCo twin against the reference engine.")
    what = p.add_subparsers(dest="what", metavar="WHAT", parser_class=type(p))
    what.required = True
    c = what.add_parser(
        "contact", help="fit solref/solimp of every joint and catalogue clearance to LN single impacts",
        description="Single impacts of the reference Lankarani-Nikravesh law vs the twin's contact (MuJoCo "
                    "probe with the real bore collider), 1 mm/s to 0.5 m/s, median effective mass of each "
                    "joint; tolerances restitution +-0.02, peak force 10 %, duration 20 %. A global fit of "
                    "one seed case (~10 min) is carried to every other case by similarity and refined locally.")
    c.add_argument("--config", metavar="FILE", help="TOML configuration (contact law, materials, timestep)")
    c.add_argument("--out", metavar="FILE", help="table to write (default: the builder's table in the package)")
    c.add_argument("--seed-from", metavar="TABLE",
                   help="reuse the seed law of an existing table instead of the global fit")
    c.add_argument("--joints", default="B,C", help="joints to fit (default B,C)")
    c.add_argument("--no-progress", action="store_true", help="no progress bar")
    c.set_defaults(func=_run_contact)


def _run_contact(args: argparse.Namespace) -> int:
    import json
    import sys
    from pathlib import Path

    from twin.calibrate import ContactLaw, calibration_table, save_table
    from twin.config import BenchConfig, load_config
    from twin.errors import ConfigError, TwinError
    from twin.mujoco_engine.builder import CALIBRATION_FILE

    joints = tuple(j.strip().upper() for j in args.joints.split(",") if j.strip())
    if not joints or any(j not in ("B", "C") for j in joints):
        raise ConfigError("--joints", f"must be a comma list of B, C; got {args.joints!r}")
    out = Path(args.out) if args.out else CALIBRATION_FILE
    if not out.parent.is_dir():
        raise TwinError(f"--out: directory {out.parent} does not exist")
    seed = None
    if args.seed_from:
        try:
            seed = ContactLaw.from_json(json.loads(Path(args.seed_from).read_text())["seed"]["law"])
        except (OSError, ValueError, KeyError, TypeError) as err:
            raise TwinError(f"--seed-from: cannot read a seed law from {args.seed_from}: {err}") from None
    cfg = load_config(args.config) if args.config else BenchConfig()
    table = calibration_table(cfg, joints=joints, seed_law=seed,
                              progress=not args.no_progress and sys.stderr.isatty())
    save_table(table, out)
    worst = max(max(r["max_scaled_error_median_mass"]) for r in table["report"].values())
    print(f"wrote {out}: {len(table['entries'])} entries, worst scaled error at the median mass {worst:.3f} "
          f"(<= 1 meets the tolerances)")
    return 0
