"""The bench's sensor chain and calibration (S003 §2.3, Table 3; Eq. 1–4).

* :mod:`twin.instrument.accel`: ADXL1001/ADXL1002 accelerometers (sensitivity, zero-g offset,
  frequency response with the 21 kHz resonance, noise, range and rail clipping);
* :mod:`twin.instrument.daq`: the MCC USB-1808X (simultaneous sampling, optional anti-alias
  filter, 18-bit quantization over the input range);
* :mod:`twin.instrument.encoder`: the crank encoder (4× quadrature counts, unwrap, glitch
  detection and repair, counts ↔ angle);
* :mod:`twin.instrument.calibration`: the static calibration of S003 Eq. 1–4, one function for
  real and simulated recordings;
* :mod:`twin.instrument.chain`: the whole chain applied to a simulated :class:`~twin.run.Run`,
  whole (:func:`apply_chain`) or chunk by chunk (:class:`ChainStream`, bit-identical) (the
  physics runs once; the chain is cheap and deterministic for a seed).

Parameters live in :class:`twin.config.Instrumentation` (``[instrumentation]`` in TOML).

Channel names (shared with the viewer): raw DAQ channels, group ``daq``: ``volt_AC1``..``volt_AC6``
[V], ``encoder_counts`` [count] (whole counts stored as float64), ``motor_command`` [V];
calibrated accelerations, group ``meas_accel``: ``meas_AC1``..``meas_AC6`` [m/s²] (a_g · g).
"""

from twin.instrument.accel import ACCEL_MODELS, STANDARD_G, AccelModel
from twin.instrument.calibration import (Calibration, apply_calibration, calibrate_static,
                                         calibration_pose_g, measured_accel)
from twin.instrument.chain import (DAQ_GROUP, MEAS_GROUP, ChainStream, apply_chain, daq_names, daq_specs,
                                   meas_names, meas_specs, simulated_calibration, static_truth_run)
from twin.instrument.encoder import (EncoderReport, angle_to_counts, check_counts, counts_to_angle,
                                     max_counts_per_sample, unwrap_counts)

__all__ = [
    "ACCEL_MODELS", "STANDARD_G", "AccelModel", "Calibration", "apply_calibration", "calibrate_static",
    "calibration_pose_g", "measured_accel", "DAQ_GROUP", "MEAS_GROUP", "ChainStream", "apply_chain",
    "daq_names", "daq_specs", "meas_names", "meas_specs", "simulated_calibration", "static_truth_run",
    "EncoderReport", "angle_to_counts", "check_counts", "counts_to_angle", "max_counts_per_sample", "unwrap_counts",
]
