"""The virtual sensors a run computes (accelerometer mounts, channel groups, output rate) and the
bench's sensor chain applied to simulated runs (S003 §2.3, Table 3)."""

from __future__ import annotations

import math
import types
from dataclasses import dataclass, field, fields
from typing import Mapping

from twin.config.common import (ACCELEROMETERS, ALL_CHANNEL_GROUPS, CHANNEL_GROUPS, XML_DEFAULTS, _check, _choice,
                                _positive, check_types)


# -------------------------------------------------------------------------- sensors
@dataclass(frozen=True)
class AccelMount:
    """Mounting of a uniaxial accelerometer on a body (S003 Table 3, Fig. 6/9).

    Attributes:
        body: "rod" or "slider".
        position_m: position in the body frame (x along the body from its origin B or C',
            y perpendicular in the plane) [m]. PLACEHOLDER: "near the named joint".
        axis: sensitive axis in the body frame: "+x", "-x", "+y" or "-y". PLACEHOLDER signs:
            longitudinal sensors point from B to C, perpendicular and vertical ones point up
            when the rod is horizontal (calibration pose), AC6 points along +x.
    """

    body: str
    position_m: tuple[float, float]
    axis: str

    def __post_init__(self) -> None:

        check_types(self)
        _choice(self.body, "body", ("rod", "slider"))
        _check(len(self.position_m) == 2 and all(math.isfinite(v) and abs(v) < 1 for v in self.position_m),
               "position_m", f"must be [x, y] within ±1 m, got {list(self.position_m)!r}")
        _choice(self.axis, "axis", ("+x", "-x", "+y", "-y"))


def _default_mounts() -> dict[str, AccelMount]:
    """Default: mjcf/bench.xml (the AC1..AC6 sites: parent body, position, x axis; positions
    PLACEHOLDERS of S003 Table 3, "near the joint")."""
    return {name: AccelMount(m.body, m.position_m, m.axis) for name, m in XML_DEFAULTS.accelerometers}


@dataclass(frozen=True)
class Sensors:
    """Virtual sensors and the channel groups a run computes and keeps.

    Attributes:
        accelerometers: mounting of AC1–AC6 (keys must be AC1..AC6). Default: mjcf/bench.xml
            (the AC1..AC6 sites).
        channels: channel groups to compute (subset of accel, encoder, crank, slider,
            joints, drive, and the optional energy); a scene computes only the sensors these
            need. The default is every group except the optional ones.
        output_rate_hz: sample rate of the run's channels [Hz] (the bench logs at 100 kHz).
    """

    accelerometers: Mapping[str, AccelMount] = field(default_factory=_default_mounts)
    channels: tuple[str, ...] = CHANNEL_GROUPS
    output_rate_hz: float = 100_000.0

    def __post_init__(self) -> None:

        check_types(self)
        _check(sorted(self.accelerometers) == list(ACCELEROMETERS), "accelerometers",
               f"must define exactly {', '.join(ACCELEROMETERS)}, got {', '.join(sorted(self.accelerometers))}")
        _check(len(self.channels) >= 1, "channels",
               f"must name at least one group of {', '.join(ALL_CHANNEL_GROUPS)}, got none")
        for g in self.channels:
            _choice(g, "channels", ALL_CHANNEL_GROUPS)
        _check(len(set(self.channels)) == len(self.channels), "channels", "must not repeat a group")
        _positive(self.output_rate_hz, "output_rate_hz", "Hz")
        # hashability of the frozen config: store the mapping as a read-only proxy
        object.__setattr__(self, "accelerometers", types.MappingProxyType(dict(self.accelerometers)))

    def __hash__(self) -> int:  # MappingProxyType is not hashable
        return hash((tuple(sorted(self.accelerometers.items())), self.channels, self.output_rate_hz))


# ------------------------------------------------------------------ instrumentation
#: Accelerometer models of the bench (datasheet numbers in :mod:`twin.instrument.accel`).
ACCEL_MODEL_NAMES: tuple[str, ...] = ("ADXL1001", "ADXL1002")
#: Input ranges of the MCC USB-1808X analog inputs [V] (S003 §2.3.1).
DAQ_RANGES: dict[str, tuple[float, float]] = {"+-10": (-10.0, 10.0), "+-5": (-5.0, 5.0),
                                              "0-10": (0.0, 10.0), "0-5": (0.0, 5.0)}
#: Accelerometer frequency-response models (see :class:`Instrumentation`).
ACCEL_RESPONSES: tuple[str, ...] = ("datasheet", "lowpass", "off")


def _default_accel_models() -> dict[str, str]:
    return {"AC1": "ADXL1001", "AC2": "ADXL1001", "AC3": "ADXL1001", "AC4": "ADXL1001",
            "AC5": "ADXL1002", "AC6": "ADXL1002"}


@dataclass(frozen=True)
class Instrumentation:
    """Bench sensor chain applied to simulated runs (S003 §2.3, Table 3; ``twin.instrument``).

    Accelerometer → volts: ``V = V_0g + S · a/g`` with the model's sensitivity S, then the
    frequency response, noise, range saturation and output-rail clipping; the DAQ samples all
    channels simultaneously at ``daq_rate_hz`` and quantizes them to ``adc_bits`` over
    ``daq_range``; the crank encoder counts 4× quadrature edges; the motor command voltage is
    ``command_v_per_rpm`` × the drive's motor speed command. Every stage can be switched off;
    the noise is deterministic for a given ``seed``.

    Attributes:
        models: accelerometer model per sensor ("ADXL1001": 20 mV/g, ±100 g, 30 µg/√Hz;
            "ADXL1002": 40 mV/g, ±50 g, 25 µg/√Hz; both resonate near 21 kHz).
        supply_v: accelerometer supply [V]. PLACEHOLDER: not given by S003; 5.0 V.
        zero_g_v: zero-g output voltage per sensor [V]; sensors not listed sit at mid-supply
            (supply_v / 2, the datasheet's nominal). Real sensors differ by tens of mV: this is
            what the static calibration (Eq. 1–2) measures.
        rail_margin_v: the output swings within [rail_margin_v, supply_v − rail_margin_v] [V].
            PLACEHOLDER: datasheet-typical swing limit, 0.2 V.
        response: "datasheet": second-order mechanical resonance at the model's 21 kHz with
            quality factor ``resonance_q``; its gain crosses +3 dB near 11 kHz, which is how the
            ADXL100x datasheets state the "3 dB bandwidth" (a gain, not a loss).
            "lowpass": the same pole pair at 21 kHz damped so that the response is −3 dB at the
            model's 11 kHz bandwidth (no peaking; the "DC–11 kHz at −3 dB" reading of S003).
            "off": flat.
        resonance_q: quality factor of the sensor resonance for ``response = "datasheet"`` [-].
            PLACEHOLDER: the datasheets plot the peak but do not tabulate Q; 10.
        noise: add white sensor noise of the model's density [g/√Hz] over the DAQ band.
        noise_scale: factor on that density [-], in [0, 100] (1 = the datasheet's; a noisier
            installation, cabling or a worn sensor read more).
        saturation: clip at the model's range (±100 g / ±50 g) and at the output rails.
        daq_rate_hz: simultaneous sample rate of all DAQ channels [Hz] (S003: 100 kHz). The
            simulated run must be at this rate or an integer multiple of it (decimated).
        daq_range: analog input range ("+-10", "+-5", "0-10", "0-5") [V]. PLACEHOLDER: ±10 V.
        adc_bits: ADC resolution [bit] (USB-1808X: 18).
        quantization: quantize analog inputs to adc_bits over daq_range (and clip to it).
        anti_alias: apply a causal Butterworth low-pass before sampling (the USB-1808X has none
            documented; off by default). When the run rate is a multiple of daq_rate_hz and this
            is off, decimation aliases, as a real unfiltered sampler does.
        anti_alias_hz: its −3 dB frequency [Hz]; must be below daq_rate_hz / 2.
        anti_alias_order: its order [-].
        encoder_counts_per_rev: counts per crank turn with 4× quadrature counting (SICK DGS80:
            8192 lines × 4 = 32768).
        encoder_quantization: count whole quadrature edges (off: fractional counts).
        command_v_per_rpm: motor command voltage per motor rpm [V/rpm] (±10 V ↔ ±1000 rpm).
        seed: seed of the noise generator (each sensor gets its own stream).
    """

    models: Mapping[str, str] = field(default_factory=_default_accel_models)
    supply_v: float = 5.0
    zero_g_v: Mapping[str, float] = field(default_factory=dict)
    rail_margin_v: float = 0.2
    response: str = "datasheet"
    resonance_q: float = 10.0
    noise: bool = True
    noise_scale: float = 1.0
    saturation: bool = True
    daq_rate_hz: float = 100_000.0
    daq_range: str = "+-10"
    adc_bits: int = 18
    quantization: bool = True
    anti_alias: bool = False
    anti_alias_hz: float = 40_000.0
    anti_alias_order: int = 4
    encoder_counts_per_rev: int = 32768
    encoder_quantization: bool = True
    command_v_per_rpm: float = 0.01
    seed: int = 0

    def __post_init__(self) -> None:

        check_types(self)
        _check(sorted(self.models) == list(ACCELEROMETERS), "models",
               f"must give a model for each of {', '.join(ACCELEROMETERS)}, got {', '.join(sorted(self.models))}")
        for k, v in self.models.items():
            _choice(v, f"models.{k}", ACCEL_MODEL_NAMES)
        _check(isinstance(self.supply_v, (int, float)) and 2.0 <= self.supply_v <= 6.0,
               "supply_v", f"must lie in [2, 6] V (ADXL100x supply), got {self.supply_v!r}")
        for k, v in self.zero_g_v.items():
            _choice(k, "zero_g_v", ACCELEROMETERS)
            _check(isinstance(v, (int, float)) and math.isfinite(v) and 0 < v < self.supply_v,
                   f"zero_g_v.{k}", f"must lie in (0, supply_v = {self.supply_v}) V, got {v!r}")
        _check(isinstance(self.rail_margin_v, (int, float)) and 0 <= self.rail_margin_v < self.supply_v / 2,
               "rail_margin_v", f"must lie in [0, supply_v/2) V, got {self.rail_margin_v!r}")
        _choice(self.response, "response", ACCEL_RESPONSES)
        _check(isinstance(self.noise_scale, (int, float)) and not isinstance(self.noise_scale, bool)
               and math.isfinite(self.noise_scale) and 0 <= self.noise_scale <= 100,
               "noise_scale", f"must lie in [0, 100], got {self.noise_scale!r}")
        _check(isinstance(self.resonance_q, (int, float)) and 0.5 <= self.resonance_q <= 1000,
               "resonance_q", f"must lie in [0.5, 1000], got {self.resonance_q!r}")
        _positive(self.daq_rate_hz, "daq_rate_hz", "Hz")
        _choice(self.daq_range, "daq_range", tuple(DAQ_RANGES))
        _check(isinstance(self.adc_bits, int) and 8 <= self.adc_bits <= 24, "adc_bits",
               f"must be an integer in [8, 24], got {self.adc_bits!r}")
        _positive(self.anti_alias_hz, "anti_alias_hz", "Hz")
        if self.anti_alias:
            _check(self.anti_alias_hz < self.daq_rate_hz / 2, "anti_alias_hz",
                   f"must lie below daq_rate_hz/2 = {self.daq_rate_hz / 2:g} Hz when anti_alias is on, "
                   f"got {self.anti_alias_hz!r}")
        _check(isinstance(self.anti_alias_order, int) and 1 <= self.anti_alias_order <= 10,
               "anti_alias_order", f"must be an integer in [1, 10], got {self.anti_alias_order!r}")
        _check(isinstance(self.encoder_counts_per_rev, int) and self.encoder_counts_per_rev >= 4,
               "encoder_counts_per_rev", f"must be an integer >= 4, got {self.encoder_counts_per_rev!r}")
        _positive(self.command_v_per_rpm, "command_v_per_rpm", "V/rpm")
        _check(isinstance(self.seed, int) and self.seed >= 0, "seed",
               f"must be an integer >= 0, got {self.seed!r}")
        object.__setattr__(self, "models", types.MappingProxyType(dict(self.models)))
        object.__setattr__(self, "zero_g_v", types.MappingProxyType(dict(self.zero_g_v)))

    def __hash__(self) -> int:  # MappingProxyType is not hashable
        return hash(tuple((f.name, tuple(sorted(v.items())) if isinstance(v, Mapping) else v)
                          for f in fields(self) for v in [getattr(self, f.name)]))

    def zero_g(self, sensor: str) -> float:
        """Zero-g output voltage of ``sensor`` [V] (mid-supply unless configured)."""
        return float(self.zero_g_v.get(sensor, self.supply_v / 2.0))
