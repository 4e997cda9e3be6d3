"""Time to identify a 2 s bench recording on one core, against the time to read it.

Method: a synthetic 2 s bench recording of Table 4 test 12 (the reference engine through the
sensor chain, as ``recordings/make_samples.py`` makes the samples) is written once; then, in this
process and on one core (the model's own thread count set to 1), ``twin.identification.model.
identify_recording`` runs ``--repeats`` times with the shipped model (or ``--model``): read and
calibrate the recording, cut its steady part into windows, compute the features, predict. Best and
median of the repeats, beside the time of reading the recording alone (the floor every answer
pays).

Run: ``python analysis/identify/bench_identify.py [--repeats 5] [--model MODEL.npz]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core: scikit-learn's OpenMP prediction


def make_recording(path: Path) -> None:
    from twin.config import preset
    from twin.recording import synthetic_recording, write_recording
    from twin.simulation import simulate_run

    cfg = preset(12).replace(**{"simulation.duration_s": 2.0, "simulation.engine": "reference", "drive.ramp_s": 0.3})
    truth = simulate_run(cfg)
    daq, info = synthetic_recording(truth, cfg, notes="bench_identify: 2 s of test 12")
    write_recording(path, daq, info)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--model", help="model file (default: the shipped one)")
    args = ap.parse_args()
    from twin.identification.model import default_model_path
    from twin.identification.inputs import recording_inputs
    from twin.identification.model import ClearanceModel, identify_recording

    model = ClearanceModel.load(args.model or default_model_path())
    with tempfile.TemporaryDirectory() as d:
        rec = Path(d) / "test12_2s.mcap"
        make_recording(rec)
        reads, ids = [], []
        for _ in range(args.repeats):
            t = time.perf_counter()
            recording_inputs(rec)
            reads.append(time.perf_counter() - t)
            t = time.perf_counter()
            a = identify_recording(model, rec)
            ids.append(time.perf_counter() - t)
    print(f"2 s recording of test 12 (answer: {a.fault}, B {a.joint('B').size_mm:.3g} mm, C {a.joint('C').size_mm:.3g} mm, "
          f"{a.evidence.windows} windows)")
    print(f"identify: best {min(ids):.3f} s, median {statistics.median(ids):.3f} s (target <= 2 s on one core); "
          f"reading and calibrating alone: best {min(reads):.3f} s")


if __name__ == "__main__":
    main()
