"""``twin export-mjcf``: save the compiled variant of a configuration as MJCF XML."""

from __future__ import annotations

import argparse

from twin.cli import MODEL_OPTIONS, SELECT_OPTIONS, add_config_args, config_from_args


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export-mjcf", help="save a configuration's MuJoCo model as XML",
                       description="Build the MuJoCo variant of a configuration and save it as MJCF.")
    # what shapes the MuJoCo model: the bench, the step and the sensors the channel groups need
    add_config_args(p, SELECT_OPTIONS + MODEL_OPTIONS + ("timestep", "channels", "drive_mode"),
                    refused_set=("simulation.engine", "simulation.duration_s", "drive."))
    p.add_argument("--out", metavar="MODEL.xml", required=True, help="XML file to write")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:

    from twin.mujoco_engine.builder import export_xml
    from twin.util import atomic_write_text, check_output_file

    out = check_output_file(args.out, "--out", ".xml")
    cfg = config_from_args(args)
    atomic_write_text(out, export_xml(cfg))
    drive = f"; drive {cfg.drive.mode}" if cfg.drive.mode in ("motor", "torque") else ""
    print(f"wrote {out} ({cfg.name}: clearance joints {', '.join(cfg.joints.clearance_joints) or 'none'}{drive})")
    return 0
