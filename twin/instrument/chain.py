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
static calibration recording (1) from the test itself (0). Streams in use: 0 a recording made by
the twin, 1 its static calibration recording, 2 and 3 the same for the virtual sensors of a
replay (so a replay of a synthetic recording does not reuse the recording's noise).

Whole runs or chunks: :class:`ChainStream` takes a run as consecutive chunks (e.g. those
:func:`twin.simulation.simulate` streams to its sinks) and returns each chunk's DAQ samples,
carrying every piece of state across chunks (filter states started in steady state at the run's
very first sample, the noise generators' streams, the decimation phase, the sample count behind
the time base); :func:`apply_chain` is one :class:`ChainStream` fed the whole run. The DAQ
samples of a run are therefore bit-identical however the run is cut into chunks (chunks of one
sample included; ``tests/test_instrument.py``). :func:`daq_specs` and :func:`meas_specs` give the
output channels (names, units, groups, dtypes) without running anything; calibration
(:func:`twin.instrument.calibration.measured_accel`) is per sample and applies to chunks as to
whole runs.
"""

from __future__ import annotations

from typing import Any, Iterable

import numpy as np

from twin.channels import ChannelSpec, channel_specs, encoder_from_bench
from twin.config import ACCELEROMETERS, BenchConfig
from twin.errors import RecordingError
from twin.instrument.accel import AccelStream
from twin.instrument.calibration import Calibration, calibrate_static, calibration_pose_g, nominal_sensitivities
from twin.instrument.daq import DaqSampler, decimation_factor, first_daq_sample, quantize
from twin.instrument.encoder import angle_to_counts
from twin.run import Channel, Run
from twin.tracefile import DriveInputs

DAQ_GROUP = "daq"
MEAS_GROUP = "meas_accel"


def daq_names(prefix: str = "") -> list[str]:
    """Raw DAQ channel names (``volt_AC1``..``volt_AC6``, ``encoder_counts``, ``motor_command``)."""
    return [f"{prefix}volt_{a}" for a in ACCELEROMETERS] + [f"{prefix}encoder_counts", f"{prefix}motor_command"]


def meas_names(prefix: str = "") -> list[str]:
    """Calibrated acceleration channel names (``meas_AC1``..``meas_AC6``)."""
    return [f"{prefix}meas_{a}" for a in ACCELEROMETERS]


def daq_specs(cfg: BenchConfig, prefix: str = "", command: bool = True,
              inputs: Iterable[str] | None = None) -> list[ChannelSpec]:
    """The DAQ channels the chain makes, in order, without running anything.

    ``inputs``: the truth channel names the run carries (default: those a run of ``cfg``
    produces, :func:`twin.channels.channel_specs`); ``volt_ACi`` for each accelerometer among
    them, ``encoder_counts`` if ``encoder_angle`` is, ``motor_command`` if ``command``. All are
    float64 (counts are whole numbers), group ``{prefix}daq``, at ``instrumentation.daq_rate_hz``.
    """
    names = set(inputs) if inputs is not None else {c.name for c in channel_specs(cfg)}
    group = prefix + DAQ_GROUP
    out = [ChannelSpec(f"{prefix}volt_{a}", "V", group, "float64", f"{a} accelerometer output, as the DAQ read it")
           for a in ACCELEROMETERS if a in names]
    if "encoder_angle" in names:
        out.append(ChannelSpec(f"{prefix}encoder_counts", "count", group, "float64",
                               "crank encoder, 4x quadrature counts (whole counts)"))
    if command:
        out.append(ChannelSpec(f"{prefix}motor_command", "V", group, "float64",
                               "motor speed command (+-10 V <-> +-1000 rpm), as the DAQ read it"))
    return out


def meas_specs(prefix: str = "", sensors: Iterable[str] = ACCELEROMETERS) -> list[ChannelSpec]:
    """Calibrated acceleration channels (:func:`~twin.instrument.calibration.measured_accel`) of
    ``sensors`` [m/s²], float64, group ``{prefix}meas_accel``."""
    wanted = set(sensors)
    return [ChannelSpec(f"{prefix}meas_{a}", "m/s^2", prefix + MEAS_GROUP, "float64",
                        f"{a} calibrated acceleration") for a in ACCELEROMETERS if a in wanted]


class ChainStream:
    """The sensor chain fed a run as consecutive chunks (:meth:`process`); see the module docstring.

    ``rate_hz`` is the run's sample rate (an integer multiple k of ``daq_rate_hz``). The first
    chunk fixes the truth channels used (the others must carry the same ones), the start time
    ``t0`` and the filters' steady-state start. State carried from chunk to chunk:

    * per accelerometer (:class:`~twin.instrument.accel.AccelStream`): the response filter's
      state and the noise generator ``default_rng([seed, stream, sensor index])``;
    * per DAQ input (:class:`~twin.instrument.daq.DaqSampler`): the anti-alias filter's state and
      the run samples seen (decimation phase: the DAQ samples are run samples 0, k, 2k, ...);
    * here: the run samples seen and the DAQ samples made (time base ``t0 + i / rate_hz`` from
      the global sample index i, as a whole run computes it; the encoder and the motor command
      are decimated with the same phase). Saturation, volts, rail clipping, quantization and
      encoder counting are per sample.

    Each chunk must follow the previous one (its ``t0`` within a quarter sample of the next
    sample's time, same rate, same truth channels); chunks of any length, including those
    holding no DAQ sample (then the result has 0 samples and ``t0`` is the time of the next DAQ
    sample). A stream is for one run: make a new one for the next (and after an error other than
    a refused chunk, which changes nothing).
    """

    def __init__(self, cfg: BenchConfig, rate_hz: float, prefix: str = "", stream: int = 0, command: bool = True,
                 drive_inputs: DriveInputs | None = None):
        self.cfg, self.inst = cfg, cfg.instrumentation
        self.drive_inputs = drive_inputs  # recorded drive trace in memory, for the command channel
        self.rate_hz = float(rate_hz)
        self.k = decimation_factor(self.rate_hz, self.inst)
        self.prefix, self.stream, self.command = prefix, stream, command
        self.group = prefix + DAQ_GROUP
        self.t0: float | None = None  # time of the run's first sample (set by the first chunk)
        self.seen = 0  # run samples processed
        self.made = 0  # DAQ samples returned
        self._inputs: tuple[str, ...] | None = None  # truth channels used, fixed by the first chunk
        self._accel: dict[str, tuple[AccelStream, DaqSampler]] = {}
        self._drive = None

    def _start(self, chunk: Run) -> None:
        inputs = tuple(a for a in ACCELEROMETERS if a in chunk)
        inputs += ("encoder_angle",) if "encoder_angle" in chunk else ()
        if not inputs and not self.command:
            raise RecordingError("apply_chain: the run has no AC1..AC6 or encoder_angle channels")
        inst = self.inst
        for i, name in enumerate(ACCELEROMETERS):
            if name in inputs:
                rng = np.random.default_rng([inst.seed, self.stream, i]) if inst.noise else None
                self._accel[name] = (AccelStream(name, inst, self.rate_hz, rng), DaqSampler(self.rate_hz, inst))
        if self.command:
            from twin.drive import DriveReference

            self._drive = DriveReference(self.cfg, self.drive_inputs)
        self._inputs = inputs
        self.t0 = float(chunk.t0)

    def process(self, chunk: Run) -> Run:
        """DAQ samples (group ``{prefix}daq``, :func:`daq_specs` order) of the next chunk of the run."""
        if abs(chunk.rate_hz - self.rate_hz) > 1e-9 * self.rate_hz:
            raise RecordingError(f"sensor chain: a chunk at {chunk.rate_hz:g} Hz in a run at {self.rate_hz:g} Hz")
        if self._inputs is None:
            self._start(chunk)
        else:
            self._check(chunk)
        inst, k, prefix = self.inst, self.k, self.prefix
        first = self.seen + first_daq_sample(self.seen, k)  # run index of the chunk's first DAQ sample
        chans: list[Channel] = []
        for name, (accel, sampler) in self._accel.items():
            v = sampler.process(accel.process(chunk[name]))
            if inst.quantization:
                v = quantize(v, inst)
            chans.append(Channel(f"{prefix}volt_{name}", "V", self.group, v))
        if "encoder_angle" in self._inputs:
            phi = chunk["encoder_angle"].astype(np.float64)[first - self.seen::k]
            chans.append(Channel(f"{prefix}encoder_counts", "count", self.group,
                                 angle_to_counts(phi, inst.encoder_counts_per_rev, inst.encoder_quantization)))
        m = len(range(first, self.seen + chunk.n, k))
        if self.command:
            t = self.t0 + np.arange(first, self.seen + chunk.n, k) / self.rate_hz
            v = self._drive.command_rpm(t) * inst.command_v_per_rpm
            if inst.quantization:
                v = quantize(v, inst)
            chans.append(Channel(f"{prefix}motor_command", "V", self.group, np.asarray(v, dtype=np.float64)))
        self.seen += chunk.n
        self.made += m
        meta = {"chain": "twin.instrument", "chain_seed": inst.seed, "chain_stream": self.stream,
                "source_rate_hz": self.rate_hz, "samples": self.made}
        return Run(self.t0 + first / self.rate_hz, inst.daq_rate_hz, {c.name: c for c in chans}, self.cfg, meta)

    def get_state(self) -> dict[str, Any]:
        """The stream's whole state after the chunks so far (start time, samples seen and made,
        truth channels used, each accelerometer's filter and noise generator, each DAQ input's
        filter and phase): plain JSON data, for :meth:`set_state` of a new stream of the same
        configuration, rate, stream number and command flag."""
        return {"t0": self.t0, "seen": self.seen, "made": self.made,
                "inputs": None if self._inputs is None else list(self._inputs),
                "accel": {n: {"sensor": a.get_state(), "daq": s.get_state()} for n, (a, s) in self._accel.items()}}

    def set_state(self, state: dict[str, Any]) -> None:
        """Continue from :meth:`get_state` (see there); the next chunk must follow the last one
        the saved stream processed."""
        if state["inputs"] is None:
            return  # the saved stream had seen no chunk
        # set up as the first chunk would (channels, generators, the drive program), then overwrite
        probe = Run(float(state["t0"]), self.rate_hz, {n: Channel(n, "", "", np.zeros(0)) for n in state["inputs"]})
        self._start(probe)
        if sorted(self._accel) != sorted(state["accel"]):
            raise RecordingError("sensor chain: the saved state is of other accelerometers")
        for name, (accel, sampler) in self._accel.items():
            accel.set_state(state["accel"][name]["sensor"])
            sampler.set_state(state["accel"][name]["daq"])
        self.seen, self.made = int(state["seen"]), int(state["made"])

    def _check(self, chunk: Run) -> None:
        have = tuple(a for a in (*ACCELEROMETERS, "encoder_angle") if a in chunk)
        if have != self._inputs:
            raise RecordingError(f"sensor chain: a chunk carries {', '.join(have) or 'no truth channels'}; "
                                 f"the run's first chunk carried {', '.join(self._inputs) or 'none'}")
        expected = self.t0 + self.seen / self.rate_hz
        if abs(chunk.t0 - expected) > 0.25 / self.rate_hz:
            raise RecordingError(f"sensor chain: a chunk starts at t = {chunk.t0:.9f} s; the next sample of the run "
                                 f"is at t = {expected:.9f} s (chunks must be consecutive)")


def apply_chain(run: Run, cfg: BenchConfig | None = None, prefix: str = "", stream: int = 0,
                command: bool = True, drive_inputs: DriveInputs | None = None) -> Run:
    """Raw DAQ channels of ``run`` under ``cfg.instrumentation`` (``cfg`` defaults to ``run.config``).

    Returns a run at ``instrumentation.daq_rate_hz`` holding the ``{prefix}daq`` group for the
    truth channels present (accelerometers, ``encoder_angle``) and, if ``command``, the motor
    command of ``cfg``'s drive program (``drive_inputs``: its recorded trace in memory, if any). The
    whole run as one chunk of a :class:`ChainStream`.
    """
    cfg = cfg if cfg is not None else run.config
    if cfg is None:
        raise RecordingError("apply_chain: the run carries no configuration; pass cfg")
    return ChainStream(cfg, run.rate_hz, prefix, stream, command, drive_inputs).process(run)


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
