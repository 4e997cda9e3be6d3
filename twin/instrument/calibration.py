"""Static accelerometer calibration exactly as the bench does it (S003 §2.3.3, Eq. 1–4).

With the connecting rod held horizontal and the mechanism at rest, a few seconds are recorded.
Each sensor then reads a known acceleration e (in g): 0 g for sensitive axes perpendicular to
gravity (AC1, AC4, AC6 in the paper's y-up bench), +1 g for axes pointing up (AC2, AC3, AC5).

* Eq. 1 (e = 0):  V_0g = mean(V)
* Eq. 2 (e = +1): V_0g = mean(V_+1g) − S
* Eq. 3:          V_corr = V_meas − V_0g
* Eq. 4:          a_g = V_corr / S

Both equations are ``V_0g = mean(V) − e · S`` (:func:`calibrate_static`), which also covers a
sensor pointing down (e = −1) in other orientations. S is the nominal datasheet sensitivity (the
paper uses the nominal value; the calibration fixes offsets only). The same functions serve real
and simulated recordings: a simulated static recording is the calibration pose's truth put
through the same sensor chain (:func:`twin.instrument.chain.simulated_calibration`).

Calibrated accelerations are stored in m/s² as ``meas_ACi = a_g · STANDARD_G``. Note: Eq. 2
assumes the local gravity is exactly 1 g (9.80665 m/s²); a twin with ``gravity_mps2 = 9.81``
therefore calibrates +1 g sensors with a bias of 0.034 % of S (7 µV at 20 mV/g), exactly as a
bench whose local gravity differs from standard gravity would.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from twin.config import ACCELEROMETERS, BenchConfig
from twin.errors import RecordingError
from twin.instrument.accel import STANDARD_G, model_of
from twin.run import Channel, Run
from twin.util import json_text

_AXES = {"+x": (0, 1.0), "-x": (0, -1.0), "+y": (1, 1.0), "-y": (1, -1.0)}


@dataclass(frozen=True)
class Calibration:
    """Zero-g offsets from a static recording (S003 Eq. 1–2) and what they were computed from.

    Attributes:
        zero_g_v: V_0g per sensor [V].
        sensitivity_v_per_g: S per sensor [V/g] (nominal).
        expected_g: reading assumed in the calibration pose per sensor [g] (0 → Eq. 1, +1 → Eq. 2).
        mean_v: mean static voltage per sensor [V].
        std_v: standard deviation of the static voltage per sensor [V] (noise seen).
        samples: number of static samples averaged.
        source: where the static recording came from (file name, "simulated", ...).
    """

    zero_g_v: Mapping[str, float]
    sensitivity_v_per_g: Mapping[str, float]
    expected_g: Mapping[str, float]
    mean_v: Mapping[str, float] = field(default_factory=dict)
    std_v: Mapping[str, float] = field(default_factory=dict)
    samples: int = 0
    source: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {"method": "static, S003 Eq. 1-4", "zero_g_v": dict(self.zero_g_v),
                "sensitivity_v_per_g": dict(self.sensitivity_v_per_g), "expected_g": dict(self.expected_g),
                "mean_v": dict(self.mean_v), "std_v": dict(self.std_v), "samples": int(self.samples),
                "source": self.source}

    def to_json(self) -> str:
        return json_text(self.to_dict(), indent=None, sort_keys=True)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "Calibration":
        try:
            zero = {str(k): float(v) for k, v in d["zero_g_v"].items()}
            sens = {str(k): float(v) for k, v in d["sensitivity_v_per_g"].items()}
            exp = {str(k): float(v) for k, v in d.get("expected_g", {}).items()}
        except (KeyError, TypeError, ValueError, AttributeError) as err:
            raise RecordingError(f"calibration data is incomplete or malformed ({type(err).__name__}: {err})") from None
        for k in zero:
            if k not in sens:
                raise RecordingError(f"calibration data: no sensitivity for {k}")
            if not (math.isfinite(zero[k]) and math.isfinite(sens[k]) and sens[k] > 0):
                raise RecordingError(f"calibration data: invalid values for {k}: V_0g={zero[k]!r}, S={sens[k]!r}")
        return cls(zero, sens, exp, {str(k): float(v) for k, v in d.get("mean_v", {}).items()},
                   {str(k): float(v) for k, v in d.get("std_v", {}).items()}, int(d.get("samples", 0)),
                   str(d.get("source", "")))


def calibration_pose_g(cfg: BenchConfig) -> dict[str, float]:
    """Reading of each accelerometer in the calibration pose [g] (0, +1 or −1).

    Pose: rod horizontal along +x (B → C), mechanism at rest, so the rod and slider frames are
    the bench frame; a sensor reads the proper acceleration −gravity along its axis, in units of
    the configured gravity. y-up bench: AC2, AC3, AC5 → +1, AC1, AC4, AC6 → 0 (S003 §2.3.3).
    """
    gvec = np.asarray(cfg.mechanism.gravity_vector, dtype=float)
    gmag = float(np.linalg.norm(gvec))
    out = {}
    for name in ACCELEROMETERS:
        idx, sign = _AXES[cfg.sensors.accelerometers[name].axis]
        out[name] = float(round(-gvec[idx] * sign / gmag, 12)) if gmag > 0 else 0.0
        out[name] += 0.0  # no negative zero
    return out


def nominal_sensitivities(cfg: BenchConfig) -> dict[str, float]:
    """Datasheet sensitivity S of each accelerometer under ``cfg.instrumentation`` [V/g]."""
    return {a: model_of(cfg.instrumentation, a).sensitivity_v_per_g for a in ACCELEROMETERS}


def calibrate_static(volts: Mapping[str, np.ndarray], sensitivity_v_per_g: Mapping[str, float],
                     expected_g: Mapping[str, float], source: str = "") -> Calibration:
    """Zero-g offsets from a static recording: V_0g = mean(V) − e · S (Eq. 1 for e = 0, Eq. 2 for e = 1).

    Args:
        volts: static voltages per sensor [V] (e.g. ``{"AC1": run["volt_AC1"], ...}``).
        sensitivity_v_per_g: S per sensor [V/g].
        expected_g: e per sensor in the calibration pose [g] (:func:`calibration_pose_g`).
        source: provenance note kept in the result.
    """
    zero, mean, std = {}, {}, {}
    n = None
    for name, v in volts.items():
        v = np.asarray(v, dtype=np.float64)
        if v.ndim != 1 or v.size < 2:
            raise RecordingError(f"static calibration: {name} needs at least 2 samples")
        if not np.all(np.isfinite(v)):
            raise RecordingError(f"static calibration: {name} holds NaN or infinite samples")
        if name not in sensitivity_v_per_g or name not in expected_g:
            raise RecordingError(f"static calibration: no sensitivity or expected reading for {name}")
        m = float(np.mean(v))
        zero[name] = m - float(expected_g[name]) * float(sensitivity_v_per_g[name])
        mean[name], std[name] = m, float(np.std(v))
        n = v.size if n is None else min(n, v.size)
    if not zero:
        raise RecordingError("static calibration: no accelerometer channels")
    return Calibration(zero, {k: float(sensitivity_v_per_g[k]) for k in zero},
                       {k: float(expected_g[k]) for k in zero}, mean, std, int(n or 0), source)


def apply_calibration(v: np.ndarray, zero_g_v: float, sensitivity_v_per_g: float) -> np.ndarray:
    """Acceleration in g from volts: a_g = (V − V_0g) / S (Eq. 3–4)."""
    return (np.asarray(v, dtype=np.float64) - zero_g_v) / sensitivity_v_per_g


def measured_accel(daq: Run, cal: Calibration, prefix: str = "") -> Run:
    """Calibrated accelerations ``{prefix}meas_ACi`` [m/s²] (group ``{prefix}meas_accel``) from a
    run holding ``{prefix}volt_ACi`` channels. Sensors without a volt channel are skipped; a
    volt channel without calibration data is an error. Per sample and stateless: applied to each
    chunk of a streamed DAQ run (:class:`twin.instrument.chain.ChainStream`) it gives the whole
    run's values bit for bit, with each chunk's ``t0``."""
    chans = []
    for name in ACCELEROMETERS:
        vname = f"{prefix}volt_{name}"
        if vname not in daq:
            continue
        if name not in cal.zero_g_v:
            raise RecordingError(f"no calibration offset for {name} (channel {vname})")
        a = apply_calibration(daq[vname], cal.zero_g_v[name], cal.sensitivity_v_per_g[name]) * STANDARD_G
        chans.append(Channel(f"{prefix}meas_{name}", "m/s^2", f"{prefix}meas_accel", a))
    if not chans:
        raise RecordingError(f"no {prefix}volt_AC1..{prefix}volt_AC6 channels to calibrate")
    return Run(daq.t0, daq.rate_hz, {c.name: c for c in chans}, daq.config, dict(daq.meta))
