"""``twin export-mjcf``: save the compiled variant of a configuration as MJCF XML."""

from __future__ import annotations

import argparse

from twin.cli import add_config_args, config_from_args
from twin.errors import TwinError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export-mjcf", help="save a configuration's MuJoCo model as XML",
                       description="Build the MuJoCo variant of a configuration and save it as MJCF.")
    add_config_args(p)
    p.add_argument("--out", metavar="MODEL.xml", required=True, help="XML file to write")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from twin.mujoco_engine.builder import export_xml
    from twin.util import atomic_write_text

    out = Path(args.out)
    if out.suffix != ".xml":
        raise TwinError(f"--out: must end in .xml, got {out.name}")
    cfg = config_from_args(args)
    atomic_write_text(out, export_xml(cfg))
    print(f"wrote {out} ({cfg.name}: clearance joints {', '.join(cfg.joints.clearance_joints) or 'none'})")
    return 0
