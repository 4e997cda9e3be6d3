"""MCC USB-1808X data acquisition: simultaneous sampling, optional anti-alias filter, ADC.

* Sampling: all channels are sampled at the same instants (the USB-1808X has one ADC per
  channel), at ``daq_rate_hz``. A simulated run at an integer multiple k of that rate is
  decimated by taking every k-th sample; with ``anti_alias`` on, a causal Butterworth low-pass
  (``anti_alias_hz``, ``anti_alias_order``) is applied first, otherwise content above
  daq_rate/2 aliases as in a real unfiltered sampler.
* ADC: ``adc_bits`` over the input range [lo, hi] of ``daq_range``: LSB = (hi − lo) / 2^bits;
  code = round((V − lo) / LSB) clipped to [0, 2^bits − 1]; the recorded value is lo + code · LSB
  (inputs beyond the range read the end codes: range clipping).
"""

from __future__ import annotations

import numpy as np

from twin.config import DAQ_RANGES, Instrumentation
from twin.errors import ConfigError


def daq_range_v(inst: Instrumentation) -> tuple[float, float]:
    """Input range (lo, hi) [V]."""
    return DAQ_RANGES[inst.daq_range]


def lsb_v(inst: Instrumentation) -> float:
    """Quantization step of the ADC [V]."""
    lo, hi = daq_range_v(inst)
    return (hi - lo) / 2 ** inst.adc_bits


def decimation_factor(run_rate_hz: float, inst: Instrumentation) -> int:
    """Integer k = run rate / DAQ rate; an error if the run is slower or not a multiple."""
    k = run_rate_hz / inst.daq_rate_hz
    ki = int(round(k))
    if ki < 1 or abs(k - ki) > 1e-9 * k:
        raise ConfigError("instrumentation.daq_rate_hz",
                          f"the run is sampled at {run_rate_hz:g} Hz; the DAQ rate ({inst.daq_rate_hz:g} Hz) "
                          "must equal it or divide it by an integer")
    return ki


def sample(x: np.ndarray, run_rate_hz: float, inst: Instrumentation, analog: bool = True) -> np.ndarray:
    """Sample a signal of the run at the DAQ instants (anti-alias filter first for analog inputs)."""
    k = decimation_factor(run_rate_hz, inst)
    x = np.asarray(x, dtype=np.float64)
    if analog and inst.anti_alias and x.size:
        from scipy.signal import butter, sosfilt, sosfilt_zi

        if inst.anti_alias_hz >= 0.5 * run_rate_hz:
            raise ConfigError("instrumentation.anti_alias_hz",
                              f"must be below half the run rate ({0.5 * run_rate_hz:g} Hz)")
        sos = butter(inst.anti_alias_order, inst.anti_alias_hz, fs=run_rate_hz, output="sos")
        x, _ = sosfilt(sos, x, zi=sosfilt_zi(sos) * x[0])
    return x[::k] if k > 1 else x


def quantize(v: np.ndarray, inst: Instrumentation) -> np.ndarray:
    """ADC reading of voltages ``v`` [V]: range clipping and ``adc_bits`` quantization."""
    lo, _ = daq_range_v(inst)
    q = lsb_v(inst)
    code = np.clip(np.rint((np.asarray(v, dtype=np.float64) - lo) / q), 0, 2 ** inst.adc_bits - 1)
    return lo + code * q


def adc_codes(v: np.ndarray, inst: Instrumentation) -> np.ndarray:
    """Integer ADC codes of recorded voltages (inverse of :func:`quantize` for on-grid values)."""
    lo, _ = daq_range_v(inst)
    return np.rint((np.asarray(v, dtype=np.float64) - lo) / lsb_v(inst)).astype(np.int64)
