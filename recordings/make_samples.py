"""Generate the SYNTHETIC sample bench recordings in ``recordings/`` (none of them is bench data).

Method, per sample:

1. A realistic, non-constant crank motion (:func:`twin.recording.crank_trace`): the crank rests,
   ramps up with a cosine speed ramp to the Table 4 speed (750 motor rpm → 188.9 crank rpm through
   the 3.97 belt) and then fluctuates within each turn by 1.5 % at the crank rate and 2.5 % at
   twice the crank rate, tied to the crank position (illustrative amplitudes, not measured:
   S003 only says the speed "is not constant within a turn").
2. That motion, as an encoder trace, drives the chosen engine (default: the REFERENCE engine,
   R-matrix with Lankarani–Nikravesh contact, ``--engine reference``) through the PID, with the
   trace used unfiltered (``drive.trace_filter_hz = 0``: the truth motion is smooth), at
   h = 1e-5 s and 100 kHz output. The physics runs once.
3. The twin's sensor chain (:func:`twin.instrument.apply_chain`, ``[instrumentation]`` defaults:
   datasheet response with the 21 kHz resonance, noise, saturation, 18-bit ±10 V DAQ, 32768-count
   encoder) turns the truth into raw DAQ channels, with per-sensor zero-g offsets typical of real
   parts (tens of mV off mid-supply, :data:`OFFSETS`) and a per-recording noise seed. The motor
   command channel is the Table 4 step command (7.5 V), as the bench's DAQ would output it.
4. The calibration data stored in each recording come from a simulated static recording in the
   calibration pose (rod horizontal, at rest) put through the same chain, reduced with S003
   Eq. 1–2 — the bench's procedure. The static recording itself is written too
   (``static_calibration_synthetic.mcap``), so ``twin import --calibration`` can be tried on it.
5. The stored bench configuration is the Table 4 preset (constant program, the engine named),
   i.e. what an operator would record for the test; ``twin replay`` replaces the drive program by
   the recording's own encoder trace.

Samples: ``test3_synthetic.mcap`` (ideal joints) and ``test6_synthetic.mcap`` (0.1 mm at C),
1.5 s each (0.1 s rest, 0.4 s ramp, ~3 turns at speed), ``test6_repeat{1,2,3}_synthetic.mcap``,
three 0.8 s "repetitions" of test 6 (0.05 s rest, 0.15 s ramp) that differ in start position (the
paper did not control it), ripple phase and noise seed, for ``twin analyze repeatability
--align-angle``, and the 0.3 s static calibration recording. About 0.85 MB per recorded second
(the 18-bit noise does not compress further).

Usage: ``python recordings/make_samples.py [--engine reference|mujoco] [--out recordings]``.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from twin.config import preset
from twin.instrument.chain import static_recording
from twin.recording import RecordingInfo, crank_trace, synthetic_recording, write_recording
from twin.simulation import simulate_run

#: zero-g output voltages of the six (synthetic) sensors [V]; mid-supply is 2.5 V
OFFSETS = {"AC1": 2.513, "AC2": 2.488, "AC3": 2.506, "AC4": 2.471, "AC5": 2.522, "AC6": 2.494}
RIPPLE = (0.015, 0.025)
RATE = 100_000.0

#: file stem, Table 4 test, duration [s], rest [s], ramp [s], start encoder angle [rad], ripple phases, seed
SAMPLES = [
    ("test3_synthetic", 3, 1.5, 0.1, 0.4, 0.0, (0.4, 1.3), 3),
    ("test6_synthetic", 6, 1.5, 0.1, 0.4, 0.0, (0.4, 1.3), 6),
    ("test6_repeat1_synthetic", 6, 0.8, 0.05, 0.15, 0.0, (0.4, 1.3), 61),
    ("test6_repeat2_synthetic", 6, 0.8, 0.05, 0.15, 1.1, (0.45, 1.25), 62),
    ("test6_repeat3_synthetic", 6, 0.8, 0.05, 0.15, 2.6, (0.35, 1.35), 63),
]


def make(out: Path, engine: str) -> None:
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        for stem, test, duration, rest, ramp, phi0, phases, seed in SAMPLES:
            t0 = time.perf_counter()
            base = preset(test).replace(**{
                "name": f"test{test}", "simulation.engine": engine, "simulation.duration_s": duration,
                "drive.ramp_s": ramp, "drive.initial_encoder_angle_rad": phi0,
                "instrumentation.zero_g_v": OFFSETS, "instrumentation.seed": seed})
            t, phi = crank_trace(base.drive.motor_rpm, base.drive.belt_ratio, duration, RATE, ramp_s=ramp,
                                 rest_s=rest, ripple=RIPPLE, ripple_phase=phases, phi0=phi0)
            trace = Path(tmp) / f"{stem}.npz"
            np.savez(trace, t=t, angle=phi)
            truth = simulate_run(base.replace(**{"drive.program": "trace", "drive.trace_file": str(trace),
                                             "drive.trace_filter_hz": 0.0}))
            notes = (f"SYNTHETIC recording (not bench data): Table 4 test {test}, {duration:g} s, made by "
                     f"recordings/make_samples.py with the {engine} engine and the twin's sensor chain "
                     f"(seed {seed}); crank speed ramp {ramp:g} s after {rest:g} s at rest, ripple {RIPPLE} at 1x/2x "
                     f"the crank rate, start angle {phi0:g} rad")
            daq, info = synthetic_recording(truth, base, notes=notes, static_s=1.0, created_by="recordings/make_samples.py",
                                            extra={"test": test, "ripple": list(RIPPLE), "ripple_phase": list(phases),
                                                   "start_encoder_angle_rad": phi0,
                                                   "truth_impacts_C": int(np.sum(np.diff((truth["pen_C"] > 0).astype(int)) == 1))
                                                   if "pen_C" in truth else 0})
            info.source_file = "recordings/make_samples.py"
            path = write_recording(out / f"{stem}.mcap", daq, info)
            print(f"{path}: {duration:g} s, {path.stat().st_size / 1e6:.2f} MB, "
                  f"{engine} {truth.meta.get('wall_s', 0):.1f} s, total {time.perf_counter() - t0:.1f} s")
        cfg = preset(6).replace(**{"instrumentation.zero_g_v": OFFSETS, "instrumentation.seed": 5})
        static = static_recording(cfg, 0.3)
        info = RecordingInfo(static.rate_hz, source_file="recordings/make_samples.py", synthetic=True,
                             created_by="recordings/make_samples.py",
                             notes="SYNTHETIC static calibration recording: rod horizontal, at rest (S003 §2.3.3); "
                                   "AC2/AC3/AC5 read +1 g, AC1/AC4/AC6 0 g; same sensors as the other samples")
        path = write_recording(out / "static_calibration_synthetic.mcap", static, info)
        print(f"{path}: 0.3 s, {path.stat().st_size / 1e6:.2f} MB")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--engine", default="reference", choices=("reference", "mujoco"))
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent))
    args = ap.parse_args()
    make(Path(args.out), args.engine)


if __name__ == "__main__":
    main()
