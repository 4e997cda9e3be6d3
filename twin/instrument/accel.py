"""ADXL1001 / ADXL1002 uniaxial MEMS accelerometers: from proper acceleration to output volts.

Stages, in signal order (each can be switched off in :class:`twin.config.Instrumentation`):

1. frequency response of the sensing element (``response``): a second-order pole pair at the
   model's resonance (21 kHz), ω_n² / (s² + (ω_n/Q) s + ω_n²), discretized by matched pole–zero
   mapping (:func:`response_ba`), started in steady state at the first sample;

   * ``"datasheet"``: quality factor ``resonance_q``. The gain rises towards the resonance and
     crosses +3 dB near 11 kHz (11.4 kHz for Q = 10; the pole pair alone gives at most +2.8 dB
     at 11 kHz). That is the datasheets' "3 dB
     bandwidth": the ADXL100x family sheets say in so many words that it "is a 3 dB response,
     meaning there is a gain in sensitivity at this frequency".
   * ``"lowpass"``: the pole pair damped so that the gain is −3 dB at the model's 11 kHz
     bandwidth (no peak): the "DC–11 kHz at −3 dB" reading of S003 / BENCH.md.
2. range saturation (``saturation``): the output acceleration is clipped at ±range (±100 g,
   ±50 g), after the response (the resonance can drive the output into saturation);
3. volts: ``V = V_0g + S · a_g`` with the model's sensitivity S [V/g] and the sensor's zero-g
   output ``V_0g`` (``zero_g_v``, mid-supply by default);
4. noise (``noise``): white, one-sided density ``noise_g_rthz`` · S [V/√Hz] over 0 … rate/2 of the
   run it is applied to (per-sample σ = density · S · √(rate/2));
5. output-rail clipping (``saturation``): V within [rail_margin_v, supply_v − rail_margin_v].

Acceleration in g: ``a_g = a / STANDARD_G`` (datasheet sensitivities are per standard g).

:func:`accel_to_volts` takes a whole signal; :class:`AccelStream` takes it in consecutive pieces
(filter state and noise stream carried) and gives the same volts bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from twin.config import Instrumentation
from twin.errors import ConfigError

#: Standard gravity: the "g" of the sensitivities and of a_g [m/s²].
STANDARD_G = 9.80665


@dataclass(frozen=True)
class AccelModel:
    """Datasheet numbers of an accelerometer model (S003 §2.3.3, Table 3; ADXL1001/1002 sheets).

    Attributes:
        name: part number.
        sensitivity_v_per_g: output sensitivity S [V/g].
        range_g: full-scale range ±range_g [g].
        noise_g_rthz: noise density [g/√Hz].
        resonance_hz: sensor resonance [Hz].
        bandwidth_hz: the "3 dB bandwidth" of the datasheet [Hz].
    """

    name: str
    sensitivity_v_per_g: float
    range_g: float
    noise_g_rthz: float
    resonance_hz: float
    bandwidth_hz: float


ACCEL_MODELS: dict[str, AccelModel] = {
    "ADXL1001": AccelModel("ADXL1001", 0.020, 100.0, 30e-6, 21_000.0, 11_000.0),
    "ADXL1002": AccelModel("ADXL1002", 0.040, 50.0, 25e-6, 21_000.0, 11_000.0),
}


def model_of(inst: Instrumentation, sensor: str) -> AccelModel:
    """Datasheet model of ``sensor`` (AC1..AC6) under ``inst``."""
    return ACCEL_MODELS[inst.models[sensor]]


def response_q(model: AccelModel, inst: Instrumentation) -> float:
    """Quality factor of the sensor's pole pair for ``inst.response`` [-]."""
    if inst.response == "datasheet":
        return float(inst.resonance_q)
    # "lowpass": |H(f_bw)| = 1/√2 for H = 1/(1 − r² + j r/Q), r = f_bw/f_n: (1 − r²)² + (r/Q)² = 2
    r = model.bandwidth_hz / model.resonance_hz
    return r / math.sqrt(2.0 - (1.0 - r * r) ** 2)


def analog_gain(f_hz: np.ndarray, model: AccelModel, inst: Instrumentation) -> np.ndarray:
    """|H(j 2π f)| of the continuous-time sensor response ω_n² / (s² + (ω_n/Q) s + ω_n²)."""
    r = np.asarray(f_hz, dtype=float) / model.resonance_hz
    q = response_q(model, inst)
    return 1.0 / np.sqrt((1.0 - r * r) ** 2 + (r / q) ** 2)


def response_ba(model: AccelModel, inst: Instrumentation, rate_hz: float) -> tuple[np.ndarray, np.ndarray] | None:
    """Digital sensor response at ``rate_hz`` as (b, a); None when ``response = "off"``.

    Matched pole–zero design: the poles are the analog poles mapped exactly (z = e^{pT}), so the
    resonance sits at its frequency with its damping; one zero at z = −β, with β ∈ [0, 1] fitted
    so that the digital gain equals the analog gain at the model's bandwidth frequency (11 kHz),
    and unit gain at DC. (The bilinear transform would compress 11 kHz towards DC by the
    pre-warping at 21 kHz and put the +3 dB point above 12 kHz.)
    """
    from scipy.optimize import brentq
    from scipy.signal import freqz

    if inst.response == "off":
        return None
    if model.resonance_hz >= 0.5 * rate_hz:
        raise ConfigError("instrumentation.response",
                          f"the {model.name} resonance ({model.resonance_hz:g} Hz) is above the Nyquist "
                          f"frequency of a {rate_hz:g} Hz run; run at >= {2 * model.resonance_hz:g} Hz "
                          "or set instrumentation.response = \"off\"")
    wn = 2.0 * math.pi * model.resonance_hz
    q = response_q(model, inst)
    poles = np.roots([1.0, wn / q, wn * wn])
    a = np.real(np.poly(np.exp(poles / rate_hz)))
    fb = model.bandwidth_hz
    target = float(analog_gain(np.array([fb]), model, inst)[0])

    def b_of(beta: float) -> np.ndarray:
        return np.array([1.0, beta]) * (np.sum(a) / (1.0 + beta))

    def err(beta: float) -> float:
        _, h = freqz(b_of(beta), a, worN=[fb], fs=rate_hz)
        return float(abs(h[0])) - target

    e0, e1 = err(0.0), err(1.0)
    beta = brentq(err, 0.0, 1.0, xtol=1e-12) if e0 * e1 < 0 else (0.0 if abs(e0) < abs(e1) else 1.0)
    return b_of(beta), a


def response_gain_db(f_hz: np.ndarray, model: AccelModel, inst: Instrumentation, rate_hz: float) -> np.ndarray:
    """Gain of the discretized sensor response at ``f_hz`` [dB] (0 dB when off)."""
    from scipy.signal import freqz

    f = np.asarray(f_hz, dtype=float)
    ba = response_ba(model, inst, rate_hz)
    if ba is None:
        return np.zeros_like(f)
    _, h = freqz(ba[0], ba[1], worN=f, fs=rate_hz)
    return 20.0 * np.log10(np.abs(h))


class AccelStream:
    """Accelerometer ``sensor`` turned into volts chunk by chunk (the stages of
    :func:`accel_to_volts`, state carried across calls).

    State: the response filter's state (started in steady state at the very first sample, then
    carried: ``lfilter`` with ``zi``), and ``rng`` itself (its normal draws continue their
    stream). Saturation, volts and rail clipping are per sample. Feeding a signal in pieces gives
    bit-identical volts to feeding it whole (``tests/test_instrument.py``).
    """

    def __init__(self, sensor: str, inst: Instrumentation, rate_hz: float, rng: np.random.Generator | None):
        self.sensor, self.inst, self.rate_hz, self.rng = sensor, inst, float(rate_hz), rng
        self.model = model_of(inst, sensor)
        self.ba = response_ba(self.model, inst, rate_hz)
        if inst.noise and rng is None:
            raise ValueError("accel_to_volts: noise is on but no random generator was given")
        self.sigma = self.model.noise_g_rthz * self.model.sensitivity_v_per_g * math.sqrt(rate_hz / 2.0)
        if inst.noise_scale != 1.0:  # (the default leaves sigma as it was, bit for bit)
            self.sigma *= inst.noise_scale
        self._zi: np.ndarray | None = None  # response filter state; None until the first sample

    def get_state(self) -> dict[str, Any]:
        """The stream's state (the response filter's ``zi`` as a list or None, the noise
        generator's ``bit_generator.state``): plain JSON data, for :meth:`set_state`."""
        return {"zi": None if self._zi is None else [float(x) for x in self._zi],
                "rng": None if self.rng is None else self.rng.bit_generator.state}

    def set_state(self, state: dict[str, Any]) -> None:
        """Continue from :meth:`get_state` of a stream of the same sensor and instrumentation."""
        zi = state["zi"]
        self._zi = None if zi is None else np.array(zi, dtype=np.float64)
        if (state["rng"] is None) != (self.rng is None):
            raise ValueError(f"{self.sensor}: the saved sensor state and this stream differ in having noise")
        if self.rng is not None:
            self.rng.bit_generator.state = state["rng"]

    def process(self, a_mps2: np.ndarray) -> np.ndarray:
        """Output voltage [V] (float64) for the next samples ``a_mps2`` of proper acceleration [m/s²]."""
        from scipy.signal import lfilter, lfilter_zi

        inst, model = self.inst, self.model
        a_g = np.asarray(a_mps2, dtype=np.float64) / STANDARD_G
        if self.ba is not None and a_g.size:
            b, a = self.ba
            if self._zi is None:  # steady state at the first sample of the signal (no start-up transient)
                self._zi = lfilter_zi(b, a) * a_g[0]
            a_g, self._zi = lfilter(b, a, a_g, zi=self._zi)
        if inst.saturation:
            a_g = np.clip(a_g, -model.range_g, model.range_g)
        v = inst.zero_g(self.sensor) + model.sensitivity_v_per_g * a_g
        if inst.noise:
            v = v + self.rng.normal(0.0, self.sigma, v.size)
        if inst.saturation:
            v = np.clip(v, inst.rail_margin_v, inst.supply_v - inst.rail_margin_v)
        return v


def accel_to_volts(a_mps2: np.ndarray, sensor: str, inst: Instrumentation, rate_hz: float,
                   rng: np.random.Generator | None) -> np.ndarray:
    """Output voltage of accelerometer ``sensor`` for proper acceleration ``a_mps2`` [V] (float64).

    ``rng`` supplies the noise (required when ``inst.noise``); see the module docstring for the
    stages and their order. The whole signal at once; :class:`AccelStream` for a signal in pieces.
    """
    return AccelStream(sensor, inst, rate_hz, rng).process(a_mps2)
