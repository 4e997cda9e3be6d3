"""Digest of the outputs a refactoring must leave bit for bit unchanged.

Method: simulate a fixed set of scenes through the public API (Table 4 tests 6 and 12 in both planar
engines, the S001, S002 and S004 presets, each for a short duration), generate the ``tiny`` dataset
spec's first runs, and answer the identification for the sample recording ``test6``; hash every array
(its dtype, shape and raw bytes) and every JSON-able answer (sorted keys), and print one SHA-256 per item
plus a total. Run it before and after a change and compare the lines (``--save FILE`` writes them,
``--against FILE`` compares and exits 1 on any difference).

    python analysis/bit_identical.py --save /tmp/before.txt
    python analysis/bit_identical.py --against /tmp/before.txt

``--native`` adds the runs that go through the native code's less common paths (0.06 s each, Table 4
tests 6 and 12 with overrides, :data:`NATIVE_SCENES`): the guide clearance (both friction laws), the drive
train ("motor" with its energy accounts, "torque"), the Adams/COSMOS friction law (contact row and passive
force), RK4 (forward passes that skip sensors), every contact law, the frictionloss guide and a clearance at
A with the passive force.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import tempfile
from pathlib import Path

import numpy as np


def _digest_run(run) -> str:
    h = hashlib.sha256()
    for name in sorted(run.channels):
        a = np.ascontiguousarray(run[name])
        h.update(name.encode())
        h.update(str(a.dtype).encode())
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _digest_json(obj) -> str:
    def default(o):
        if hasattr(o, "to_dict"):
            return o.to_dict()
        if isinstance(o, np.generic):
            return o.item()
        if isinstance(o, np.ndarray):
            return o.tolist()
        return repr(o)
    return hashlib.sha256(json.dumps(obj, sort_keys=True, default=default).encode()).hexdigest()


_GROUPS = ("accel", "encoder", "crank", "slider", "joints", "drive")
#: name -> (Table 4 test, overrides) of the ``--native`` runs
NATIVE_SCENES = {
    "guide clearance coulomb": (6, {"joints.clearance_guide_mm": 0.1}),
    "guide clearance adams": (6, {"joints.clearance_guide_mm": 0.1, "contact.friction_law": "adams"}),
    "motor drive + energy": (12, {"drive.mode": "motor", "sensors.channels": _GROUPS + ("motor", "drive_energy")}),
    "torque drive": (12, {"drive.mode": "torque", "sensors.channels": _GROUPS + ("motor",)}),
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


def digests(quick: bool = False, native: bool = False) -> dict[str, str]:
    import twin

    out: dict[str, str] = {}
    scenes = [(6, "mujoco"), (6, "reference"), (12, "mujoco"), (12, "reference"),
              ("s001", None), ("s002", None), ("s004", None)]
    duration = 0.05 if quick else 0.15
    for which, engine in scenes:
        run = twin.simulate(twin.preset(which), duration=duration, engine=engine)
        out[f"simulate {which} {engine or 'preset'}"] = _digest_run(run)
        print(f"  {which} {engine or ''}: done", file=sys.stderr, flush=True)
    if native:
        for name, (test, overrides) in NATIVE_SCENES.items():
            run = twin.simulate(twin.preset(test).replace(**overrides), duration=0.06)
            out[f"native {name}"] = _digest_run(run)
            print(f"  native {name}: done", file=sys.stderr, flush=True)
    answer = twin.identify(twin.samples.path("test6")).to_dict()
    answer.pop("seconds", None)  # wall time of the answer, not an output
    answer["recording"] = Path(str(answer.get("recording", ""))).name  # where the checkout is, not an output
    out["identify sample:test6"] = _digest_json(answer)
    if not quick:
        from twin.dataset.generate import generate  # noqa: PLC0415
        from twin.dataset.spec import load_spec  # noqa: PLC0415
        with tempfile.TemporaryDirectory() as tmp:
            spec = load_spec(twin.samples.spec_path("tiny"))
            generate(spec, Path(tmp) / "ds", workers=1, limit=3, progress=False)
            import pyarrow.parquet as pq  # noqa: PLC0415
            h = hashlib.sha256()
            for f in sorted((Path(tmp) / "ds").rglob("*.parquet")):
                table = pq.read_table(f)
                for name in table.column_names:
                    if name in ("wall_s",):  # wall time, not an output
                        continue
                    h.update(f"{f.name}:{name}".encode())
                    h.update(json.dumps(table.column(name).to_pylist(), default=repr).encode())
            out["dataset tiny columns"] = h.hexdigest()
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--save", type=Path, help="write the digests to this file")
    p.add_argument("--against", type=Path, help="compare with digests saved earlier; exit 1 on a difference")
    p.add_argument("--quick", action="store_true", help="shorter runs, no dataset")
    p.add_argument("--native", action="store_true", help="also the native code's less common paths (NATIVE_SCENES)")
    a = p.parse_args(argv)
    d = digests(a.quick, a.native)
    lines = [f"{k}\t{v}" for k, v in d.items()]
    text = "\n".join(lines) + "\n"
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
