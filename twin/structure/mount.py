"""The accelerometer's mount: a base-excited second-order oscillator, discretized exactly at the sample rate.

The sensor (grams) sits on its mount (stud, screws or adhesive; stiffness k, damping c) on the body: its
relative displacement r = x_s − x_b obeys r̈ + 2ζω ṙ + ω² r = −a_b, and it reads its own acceleration
a_s = a_b + r̈ = −ω² r − 2ζω ṙ: H(s) = (2ζω s + ω²)/(s² + 2ζω s + ω²), unit gain at DC (the +1 g of gravity
reads through unchanged). One-way coupled: the body does not feel the sensor.

Exact discretization: the body's acceleration is taken linear between samples (first-order hold), the
state [r, ṙ] is advanced by the matrix exponential of the augmented system ẋ = A x + B u, u̇ = d, ḋ = 0
(scipy.linalg.expm), and the recursion x_{k+1} = Φ x_k + G₀ u_k + G₁ u_{k+1}, y_k = C x_k is written as a
transfer function for scipy.signal.lfilter. Both engines filter their sampled accelerations with the same
:class:`MountFilter`, so their sensor chains agree by construction. A mount resonance must lie below half the
sample rate (the configuration checks it).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm
from scipy.signal import lfilter, lfilter_zi, ss2tf


def mount_coefficients(frequency_hz: float, damping_ratio: float, sample_rate_hz: float
                       ) -> tuple[np.ndarray, np.ndarray]:
    """(b, a) of the exactly discretized mount (first-order hold of the base acceleration)."""
    w, z, h = 2.0 * math.pi * frequency_hz, damping_ratio, 1.0 / sample_rate_hz
    A = np.array([[0.0, 1.0], [-w * w, -2.0 * z * w]])
    B = np.array([[0.0], [-1.0]])
    aug = np.zeros((4, 4))
    aug[:2, :2], aug[:2, 2:3], aug[2, 3] = A, B, 1.0
    E = expm(aug * h)
    Phi, E12, E13 = E[:2, :2], E[:2, 2:3], E[:2, 3:4]
    G1 = E13 / h
    G0 = E12 - G1
    Cm = np.array([[-w * w, -2.0 * z * w]])
    # w_k = x_k − G1 u_k: w_{k+1} = Φ w_k + (Φ G1 + G0) u_k, y_k = C w_k + C G1 u_k
    b, a = ss2tf(Phi, Phi @ G1 + G0, Cm, Cm @ G1)
    return np.asarray(b[0], dtype=np.float64), np.asarray(a, dtype=np.float64)


class MountFilter:
    """The mounts of several sensors, filtering chunks of their sampled accelerations in order.

    ``process(x)`` takes an array (samples, sensors) (or one sensor's samples) of the acceleration of the
    bodies at the mounting points [m/s² or g, the filter is linear] and returns what the sensors feel; the
    state carries over between calls. The first sample starts the mounts at rest relative to their bodies
    (steady state for that sample's value)."""

    def __init__(self, frequency_hz: float, damping_ratio: float, sample_rate_hz: float) -> None:
        self.b, self.a = mount_coefficients(frequency_hz, damping_ratio, sample_rate_hz)
        self._zi_unit = lfilter_zi(self.b, self.a)
        self._zi: np.ndarray | None = None

    def reset(self) -> None:
        """Forget the state: the next chunk starts at rest again."""
        self._zi = None

    def process(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=np.float64)
        if x.shape[0] == 0:
            return x.copy()
        if self._zi is None:
            first = x[0] if x.ndim == 1 else x[0][None, :]
            self._zi = (self._zi_unit[:, None] * first) if x.ndim > 1 else self._zi_unit * first
        y, self._zi = lfilter(self.b, self.a, x, axis=0, zi=self._zi)
        return y
