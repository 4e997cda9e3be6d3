"""MCC USB-1808X data acquisition: simultaneous sampling, optional anti-alias filter, ADC.

* Sampling: all channels are sampled at the same instants (the USB-1808X has one ADC per
  channel), at ``daq_rate_hz``. A simulated run at an integer multiple k of that rate is
  decimated by taking every k-th sample; with ``anti_alias`` on, a causal Butterworth low-pass
  (``anti_alias_hz``, ``anti_alias_order``) is applied first, otherwise content above
  daq_rate/2 aliases as in a real unfiltered sampler.
* ADC: ``adc_bits`` over the input range [lo, hi] of ``daq_range``: LSB = (hi − lo) / 2^bits;
  code = round((V − lo) / LSB) clipped to [0, 2^bits − 1]; the recorded value is lo + code · LSB
  (inputs beyond the range read the end codes: range clipping).

:func:`sample` takes a whole signal, :class:`DaqSampler` consecutive pieces of it (filter state
and decimation phase carried; same samples bit for bit); :func:`quantize` is per sample.
"""

from __future__ import annotations

from typing import Any

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


class DaqSampler:
    """One DAQ input sampling consecutive pieces of a run's signal (what :func:`sample` does to a
    whole signal, bit for bit).

    State: the anti-alias filter's state (``sosfilt`` with ``zi``, started in steady state at the
    very first sample of the signal, then carried) and the number of run samples seen, which
    fixes the decimation phase: the DAQ takes the run's samples 0, k, 2k, ... whatever the
    lengths of the pieces.
    """

    def __init__(self, run_rate_hz: float, inst: Instrumentation, analog: bool = True):
        self.k = decimation_factor(run_rate_hz, inst)
        self.run_rate_hz, self.inst, self.analog = float(run_rate_hz), inst, analog
        self.seen = 0  # run samples seen so far
        self._sos: np.ndarray | None = None
        self._zi: np.ndarray | None = None  # anti-alias filter state; None until the first sample

    def get_state(self) -> dict[str, Any]:
        """The sampler's state (run samples seen, the anti-alias filter's ``zi`` as a list or None):
        plain JSON data, for :meth:`set_state`."""
        return {"seen": int(self.seen), "zi": None if self._zi is None else np.asarray(self._zi).tolist()}

    def set_state(self, state: dict[str, Any]) -> None:
        """Continue from :meth:`get_state` of a sampler of the same rates and instrumentation."""
        self.seen = int(state["seen"])
        zi = state["zi"]
        self._zi = None if zi is None else np.array(zi, dtype=np.float64)
        if self._zi is not None and self._sos is None:
            from scipy.signal import butter

            self._sos = butter(self.inst.anti_alias_order, self.inst.anti_alias_hz, fs=self.run_rate_hz, output="sos")

    def process(self, x: np.ndarray) -> np.ndarray:
        """DAQ samples among the next run samples ``x`` (float64)."""
        x = np.asarray(x, dtype=np.float64)
        inst = self.inst
        if self.analog and inst.anti_alias and x.size:
            from scipy.signal import butter, sosfilt, sosfilt_zi

            if self._sos is None:
                if inst.anti_alias_hz >= 0.5 * self.run_rate_hz:
                    raise ConfigError("instrumentation.anti_alias_hz",
                                      f"must be below half the run rate ({0.5 * self.run_rate_hz:g} Hz)")
                self._sos = butter(inst.anti_alias_order, inst.anti_alias_hz, fs=self.run_rate_hz, output="sos")
                self._zi = sosfilt_zi(self._sos) * x[0]
            x, self._zi = sosfilt(self._sos, x, zi=self._zi)
        first = first_daq_sample(self.seen, self.k)
        self.seen += x.size
        return x[first::self.k] if self.k > 1 else x


def first_daq_sample(seen: int, k: int) -> int:
    """Index, within a piece starting at run sample ``seen``, of its first DAQ sample (every k-th
    run sample from sample 0 is one)."""
    return (-seen) % k


def sample(x: np.ndarray, run_rate_hz: float, inst: Instrumentation, analog: bool = True) -> np.ndarray:
    """Sample a signal of the run at the DAQ instants (anti-alias filter first for analog inputs).
    A whole signal; :class:`DaqSampler` for a signal in pieces."""
    return DaqSampler(run_rate_hz, inst, analog).process(x)


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
