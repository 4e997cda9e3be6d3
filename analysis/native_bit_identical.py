"""Digests of the runs that go through the native code's less common paths, for a change of the native code
that must keep its outputs bit for bit (analysis/bit_identical.py covers the standard scenes).

Scenes (0.06 s each, Table 4 tests 6 and 12 with overrides): the guide clearance (both friction laws), the
drive train ("motor" with its energy accounts, "torque"), the Adams/COSMOS friction law (contact row and
passive force), RK4 (sensor passes that skip sensors), every contact law (hysteresis, ADAMS IMPACT, linear,
Johnson's cylindrical law), the frictionloss guide and a clearance at A with the passive force. One SHA-256
(first 16 hex digits) per scene over every channel's bytes.

    python analysis/native_bit_identical.py --save /tmp/native_before.txt
    python analysis/native_bit_identical.py --against /tmp/native_before.txt
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

import numpy as np

CHANNELS = ("accel", "encoder", "crank", "slider", "joints", "drive")
SCENES = {
    "guide clearance coulomb": (6, {"joints.clearance_guide_mm": 0.1}),
    "guide clearance adams": (6, {"joints.clearance_guide_mm": 0.1, "contact.friction_law": "adams"}),
    "motor drive + energy": (12, {"drive.mode": "motor", "sensors.channels": CHANNELS + ("motor", "drive_energy")}),
    "torque drive": (12, {"drive.mode": "torque", "sensors.channels": CHANNELS + ("motor",)}),
    "adams friction law": (12, {"contact.friction_law": "adams"}),
    "adams friction force": (12, {"contact.friction_law": "adams", "mujoco.contact_source": "force"}),
    "RK4 law": (12, {"mujoco.integrator": "RK4"}),
    "impact law": (12, {"contact.law": "adams-impact"}),
    "impact law force": (12, {"contact.law": "adams-impact", "mujoco.contact_source": "force"}),
    "linear law": (12, {"contact.law": "linear"}),
    "cylindrical law": (12, {"contact.law": "johnson-cylindrical"}),
    "frictionloss guide": (12, {"mujoco.guide_friction": "frictionloss"}),
    "clearance A force": (12, {"joints.clearance_a_mm": 0.1, "mujoco.contact_source": "force"}),
}


def digests() -> dict[str, str]:
    import twin
    from twin.config import preset

    out = {}
    for name, (test, overrides) in SCENES.items():
        run = twin.simulate(preset(test).replace(**overrides), duration=0.06)
        h = hashlib.sha256()
        for channel in sorted(run.channels):
            h.update(channel.encode() + np.ascontiguousarray(run[channel]).tobytes())
        out[name] = h.hexdigest()[:16]
        print(f"  {name}: done", file=sys.stderr, flush=True)
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--save", type=Path, help="write the digests to this file")
    p.add_argument("--against", type=Path, help="compare with digests saved earlier; exit 1 on a difference")
    a = p.parse_args(argv)
    d = digests()
    text = "".join(f"{k}\t{v}\n" for k, v in d.items())
    print(text, end="")
    if a.save:
        a.save.write_text(text)
    if a.against:
        old = dict(line.split("\t") for line in a.against.read_text().splitlines() if line)
        bad = [k for k in d if old.get(k) != d[k]]
        if bad:
            print("DIFFERENT: " + ", ".join(bad), file=sys.stderr)
            return 1
        print("bit-identical: all items", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
