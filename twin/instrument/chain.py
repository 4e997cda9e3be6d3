"""The bench's sensor chain applied to a simulated run: truth signals → what the DAQ records.

:func:`apply_chain` turns a simulated :class:`~twin.run.Run` (``AC1``..``AC6`` proper
accelerations [m/s²], ``encoder_angle`` [rad], and the drive program of its configuration) into
the raw channels of a bench recording, group ``daq``:

* ``volt_ACi`` [V]: accelerometer output (:mod:`twin.instrument.accel`) sampled and quantized
  by the DAQ (:mod:`twin.instrument.daq`);
* ``encoder_counts`` [count]: 4× quadrature counts of the encoder angle (float64 holding whole
  counts; :mod:`twin.instrument.encoder`);
* ``motor_command`` [V]: the motor speed command (:meth:`twin.drive.DriveReference.command_rpm`)
  × ``command_v_per_rpm`` (±10 V ↔ ±1000 rpm), read back through the same ADC.

The physics runs once; the chain is a few vectorized filters (a 2 s run takes well under a
second). Noise is drawn from ``numpy.random.default_rng([seed, stream, sensor index])``: the same
seed gives the same recording, each sensor has its own stream, and ``stream`` separates e.g. the
static calibration recording (1) from the test itself (0). Apply the chain to a whole run, not
chunk by chunk (filters and noise would restart at each chunk). Streams in use: 0 a recording
made by the twin, 1 its static calibration recording, 2 and 3 the same for the virtual sensors of
a replay (so a replay of a synthetic recording does not reuse the recording's noise).
"""

from __future__ import annotations

import numpy as np

from twin.channels import encoder_from_bench
from twin.config import ACCELEROMETERS, BenchConfig
from twin.errors import RecordingError
from twin.instrument.accel import accel_to_volts
from twin.instrument.calibration import Calibration, calibrate_static, calibration_pose_g, nominal_sensitivities
from twin.instrument.daq import decimation_factor, quantize, sample
from twin.instrument.encoder import angle_to_counts
from twin.run import Channel, Run

DAQ_GROUP = "daq"
MEAS_GROUP = "meas_accel"


def daq_names(prefix: str = "") -> list[str]:
    """Raw DAQ channel names (``volt_AC1``..``volt_AC6``, ``encoder_counts``, ``motor_command``)."""
    return [f"{prefix}volt_{a}" for a in ACCELEROMETERS] + [f"{prefix}encoder_counts", f"{prefix}motor_command"]


def meas_names(prefix: str = "") -> list[str]:
    """Calibrated acceleration channel names (``meas_AC1``..``meas_AC6``)."""
    return [f"{prefix}meas_{a}" for a in ACCELEROMETERS]


def apply_chain(run: Run, cfg: BenchConfig | None = None, prefix: str = "", stream: int = 0,
                command: bool = True) -> Run:
    """Raw DAQ channels of ``run`` under ``cfg.instrumentation`` (``cfg`` defaults to ``run.config``).

    Returns a run at ``instrumentation.daq_rate_hz`` holding the ``{prefix}daq`` group for the
    truth channels present (accelerometers, ``encoder_angle``) and, if ``command``, the motor
    command of ``cfg``'s drive program.
    """
    cfg = cfg if cfg is not None else run.config
    if cfg is None:
        raise RecordingError("apply_chain: the run carries no configuration; pass cfg")
    inst = cfg.instrumentation
    k = decimation_factor(run.rate_hz, inst)
    group = prefix + DAQ_GROUP
    chans: list[Channel] = []
    for i, name in enumerate(ACCELEROMETERS):
        if name not in run:
            continue
        rng = np.random.default_rng([inst.seed, stream, i]) if inst.noise else None
        v = accel_to_volts(run[name], name, inst, run.rate_hz, rng)
        v = sample(v, run.rate_hz, inst, analog=True)
        if inst.quantization:
            v = quantize(v, inst)
        chans.append(Channel(f"{prefix}volt_{name}", "V", group, v))
    n = (run.n + k - 1) // k
    if "encoder_angle" in run:
        phi = run["encoder_angle"].astype(np.float64)[::k]
        chans.append(Channel(f"{prefix}encoder_counts", "count", group,
                             angle_to_counts(phi, inst.encoder_counts_per_rev, inst.encoder_quantization)))
    if command:
        from twin.drive import DriveReference

        t = run.time[::k]
        v = DriveReference(cfg).command_rpm(t) * inst.command_v_per_rpm
        if inst.quantization:
            v = quantize(v, inst)
        chans.append(Channel(f"{prefix}motor_command", "V", group, np.asarray(v, dtype=np.float64)))
    if not chans:
        raise RecordingError("apply_chain: the run has no AC1..AC6 or encoder_angle channels")
    meta = {"chain": "twin.instrument", "chain_seed": inst.seed,
            "chain_stream": stream, "source_rate_hz": run.rate_hz, "samples": n}
    return Run(run.t0, inst.daq_rate_hz, {c.name: c for c in chans}, cfg, meta)


def static_truth_run(cfg: BenchConfig, duration_s: float = 1.0) -> Run:
    """Truth signals of the static calibration pose (rod horizontal along +x, at rest).

    Accelerometers read −gravity along their axes (:func:`calibration_pose_g` × g), the crank
    sits at bench angle 0 (B on the guide line, so the rod is horizontal for d_off = 0).
    Sampled at the DAQ rate.
    """
    rate = cfg.instrumentation.daq_rate_hz
    n = max(2, int(round(duration_s * rate)))
    pose = calibration_pose_g(cfg)
    g = cfg.mechanism.gravity_mps2
    arrays = {a: np.full(n, pose[a] * g, dtype=np.float64) for a in ACCELEROMETERS}
    arrays["encoder_angle"] = np.full(n, float(encoder_from_bench(0.0, cfg.mechanism.crank_direction)))
    return Run.from_arrays(0.0, rate, arrays, cfg, {"kind": "static calibration pose (truth)"})


def static_recording(cfg: BenchConfig, duration_s: float = 1.0, stream: int = 1) -> Run:
    """A simulated static calibration recording: the pose's truth through the sensor chain
    (noise stream ``stream``, 1 by default; motor command 0 V)."""
    daq = apply_chain(static_truth_run(cfg, duration_s), cfg, stream=stream, command=False)
    zero = quantize(np.zeros(daq.n), cfg.instrumentation) if cfg.instrumentation.quantization else np.zeros(daq.n)
    return daq.with_channels([Channel("motor_command", "V", DAQ_GROUP, zero)])


def simulated_calibration(cfg: BenchConfig, duration_s: float = 1.0, stream: int = 1) -> Calibration:
    """Calibrate the virtual sensors the way the bench calibrates the real ones (Eq. 1–4) on a
    simulated static recording of ``duration_s`` (noise stream ``stream``)."""
    static = static_recording(cfg, duration_s, stream)
    volts = {a: static[f"volt_{a}"] for a in ACCELEROMETERS}
    return calibrate_static(volts, nominal_sensitivities(cfg), calibration_pose_g(cfg),
                            source=f"simulated static recording, {duration_s:g} s, seed {cfg.instrumentation.seed}")
