"""Make the clearance-identification model that ships with twin, its development figures and its fresh test.

Steps (each is a plain ``twin`` command; a step whose output exists is skipped, so the script resumes):

1. ``twin dataset generate analysis/datasets/clearance_id_nuisance.toml --out WORK/clearance_id_nuisance``: the
   training data, MuJoCo twin, 1600 runs of 3 s with every nuisance of the bench drawn over its training range
   (within-turn speed ripple 0-4 % at 1-3x the crank rate, contact restitution, friction and stiffness, guide
   friction, sensor offsets, mounting and noise, start angle, speed 250-800 rpm and orientation);
   ``clearance_id_nuisance_ends.toml``: 400 more runs with the clearances beyond the catalogue's ends
   (0.0125-0.02 and 1.0-1.6 mm), so that every catalogue value lies inside the trained sizes;
   ``clearance_id_nuisance_ref.toml``: 1600 runs of the same nuisances simulated by the reference engine
   (clearances 0.0125-1.6 mm), so that the model spans two contact laws; ``clearance_id_nuisance_motor.toml`` and
   ``clearance_id_nuisance_motor_yz.toml``: 480 + 480 reference-engine runs of the drive train (motor speed loop
   and V-belt, placeholders drawn; the second with y or z vertical only); ``clearance_id_nuisance_ref_small.toml``:
   1200 reference-engine runs with B, C or both faulty, clearances 0.0125-0.25 mm and no hole around 0.07 mm,
   ``clearance_id_nuisance_ref_small_b.toml``: 800 more with B's clearance 0.0125-0.25 mm (B or BC faulty);
   ``clearance_id_nuisance_ref_slow_b.toml``: 800 more of those at the slow speeds 250-425 rpm; and
   ``clearance_id_nuisance_ref_slow_b2.toml``: 2400 more at those speeds with y or z vertical, B's clearance
   0.0125-1.6 mm;
2. ``twin identify train WORK/clearance_id_nuisance WORK/clearance_id_nuisance_ends WORK/clearance_id_nuisance_ref
   WORK/clearance_id_nuisance_motor WORK/clearance_id_nuisance_motor_yz WORK/clearance_id_nuisance_ref_small
   WORK/clearance_id_nuisance_ref_small_b WORK/clearance_id_nuisance_ref_slow_b --b-size-only
   WORK/clearance_id_nuisance_ref_slow_b2 --interval-folds speed --out
   twin/data/identify_default.npz`` (train and val splits; the intervals calibrated on answers at speeds left out,
   split by the size-resolution map, by the measured ripple, at C by whether both joints are located faulty
   (``--fault-split C``, the default) and by the answer's size, one band per group of catalogue values, each the
   largest over the engines, and the same for answers from one to three windows; with the held-out size accuracy
   per orientation and
   training speed; the last set teaches the location and B's size only). The same ``train()`` on the same features
   is the development study's variant ``slow-b2-at-b-fault-c-windows`` (``analysis/identify/nuisance_study.py
   --variants slow-b2-at-b-fault-c-windows --save slow-b2-at-b-fault-c-windows:twin/data/identify_default.npz``,
   which reuses the features it keeps);
3. the development sets ``clearance_id_nuisance_dev.toml``, ``clearance_id_nuisance_dev_out.toml`` and
   ``clearance_id_nuisance_dev_motor.toml`` (reference engine), evaluated into ``analysis/results/identify/dev``,
   ``dev_out`` and ``dev_motor`` (every choice of the model was made on these:
   ``analysis/identify/nuisance_study.py``);
4. with ``--fresh6`` only, after the model is committed (``analysis/identify/FRESH_TEST.md``, "Sixth round",
   the one look): the seven sets of the sixth fresh test ``clearance_id_fresh6_*.toml`` (seeds never used), each
   evaluated into ``analysis/results/identify/fresh6_*`` (``--fresh5``, ``--fresh4``, ``--fresh3``, ``--fresh2``:
   the fifth to second rounds' seven sets, ``clearance_id_fresh5_*.toml`` ... ``clearance_id_fresh2_*.toml``,
   each looked at once with the model of its round; the first round's six sets, ``clearance_id_fresh_*.toml``,
   with the one before that: their reports, ``fresh5_*`` ... ``fresh2_*`` and ``fresh_*``, are history);
5. the answers on the sample recordings in ``recordings/`` (``analysis/results/identify/samples.json``).

Run: ``python analysis/identify/train_default.py [--work DIR] [--workers N] [--retrain] [--fresh6]``: about
95 min for the training data on two cores, 30 min to train, 6 min for the development sets and 20 min for the
sixth fresh test's sets. The datasets stay in ``--work`` (default ``../identify_work`` beside the checkout; about
70 GB for the training sets), not in the repository.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path
from twin.provenance import stamped

ROOT = Path(__file__).resolve().parents[2]
MODEL = ROOT / "twin" / "data" / "identify_default.npz"
REPORT = ROOT / "analysis" / "results" / "identify"
TRAIN = ("clearance_id_nuisance", "clearance_id_nuisance_ends", "clearance_id_nuisance_ref",
         "clearance_id_nuisance_motor", "clearance_id_nuisance_motor_yz", "clearance_id_nuisance_ref_small",
         "clearance_id_nuisance_ref_small_b", "clearance_id_nuisance_ref_slow_b")
#: training sets that teach the location and the size at B only (``twin identify train --b-size-only``)
B_SIZE_ONLY = ("clearance_id_nuisance_ref_slow_b2",)
DEV = {"clearance_id_nuisance_dev": "dev", "clearance_id_nuisance_dev_out": "dev_out",
       "clearance_id_nuisance_dev_motor": "dev_motor"}
#: the parts of the second to sixth fresh tests (the same seven parts each round)
FRESH_PARTS = ("in", "in_mujoco", "out_ripple", "out_speed", "out_noise", "out_params", "motor")
#: per round, its fresh test's sets (dataset name -> report folder); the last round's is the one look, the others
#: were each looked at once with the model of their round
FRESH = {r: {f"clearance_id_fresh{r}_{k}": f"fresh{r}_{k}" for k in FRESH_PARTS} for r in range(2, 7)}
_ORDINAL = {2: "second", 3: "third", 4: "fourth", 5: "fifth", 6: "sixth"}


def twin(*args: str) -> None:
    cmd = [sys.executable, "-m", "twin.cli", *args]
    print("$ twin " + " ".join(args), flush=True)
    subprocess.run(cmd, check=True, cwd=ROOT)


def generate(work: Path, name: str, workers: str) -> Path:
    d = work / name
    twin("dataset", "generate", f"analysis/datasets/{name}.toml", "--out", str(d), "--workers", workers, "--no-progress")
    return d


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", default=str(ROOT.parent / "identify_work"), help="folder of the datasets")
    ap.add_argument("--workers", default=str(os.cpu_count() or 1))
    ap.add_argument("--retrain", action="store_true", help="train again even if the model exists")
    for r in FRESH:
        ap.add_argument(f"--fresh{r}", action="store_true",
                        help=f"also generate and evaluate the {_ORDINAL[r]} fresh test's sets "
                             + ("(the one look)" if r == max(FRESH) else "(looked at once with the model before)"))
    ap.add_argument("--samples-only", action="store_true", help="only the answers on the sample recordings (step 5)")
    args = ap.parse_args()
    if args.samples_only:
        return samples()
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    t = time.perf_counter()
    train_ds = [generate(work, name, args.workers) for name in TRAIN]
    b_only = [generate(work, name, args.workers) for name in B_SIZE_ONLY]
    print(f"training data: {time.perf_counter() - t:.0f} s (0 if it existed)")
    if args.retrain or not MODEL.exists():
        twin("identify", "train", *map(str, train_ds), "--b-size-only", *map(str, b_only), "--interval-folds", "speed",
             "--out", str(MODEL), "--workers", args.workers)
    sets = dict(DEV)
    for r, parts in FRESH.items():
        if getattr(args, f"fresh{r}"):
            sets |= parts
    for name, sub in sets.items():
        d = generate(work, name, args.workers)
        twin("identify", "evaluate", str(MODEL), str(d), "--out", str(REPORT / sub), "--workers", args.workers)
    samples()


def samples() -> None:
    """The shipped model's answers on the sample recordings in ``recordings/`` (``samples.json``)."""
    samples = {}
    for rec in sorted((ROOT / "recordings").glob("*.mcap")):
        out = REPORT / f".{rec.stem}.json"
        r = subprocess.run([sys.executable, "-m", "twin.cli", "identify", "clearance", str(rec.relative_to(ROOT)), "--json", str(out)],
                           cwd=ROOT, capture_output=True, text=True)
        if r.returncode == 0:
            a = json.loads(out.read_text())
            out.unlink()
            samples[rec.name] = {k: a[k] for k in ("fault", "probabilities", "clearance_b_mm", "clearance_b_interval_mm",
                                                 "clearance_c_mm", "clearance_c_interval_mm", "warnings", "seconds")}
            samples[rec.name]["evidence"] = {k: a["evidence"][k] for k in ("windows", "revolutions", "crank_hz")}
        else:
            samples[rec.name] = {"refused": r.stderr.strip()}
    (REPORT / "samples.json").write_text(json.dumps(stamped(samples), indent=2) + "\n")
    print(json.dumps(samples, indent=2))


if __name__ == "__main__":
    main()
