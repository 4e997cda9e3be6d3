"""Drive programs: the crank angle and rate references the PID tracks.

With ``drive.mode`` "pid" or "prescribed" the motor and the V-belt are not modelled (S003 §4.3):
a PID on the crank tracks a reference crank angle, or the crank follows it exactly. With "motor"
the motor's speed loop follows the program's motor speed (:mod:`twin.drivetrain_params`,
:mod:`twin.motor_drive`). Three programs produce that reference:

* ``constant``: from rest, the motor command steps to ``motor_rpm`` at t = 0;
* ``protocol``: the 38 s test of S003 §4.3 (stop, speed 1, stop, speed 2, stop, speed 3, stop);
* ``trace``: a recorded crank encoder angle (replay of a bench recording).

For the synthetic programs the motor command is a step and the crank speed follows it
with a smooth cosine ramp of ``drive.ramp_s`` (PLACEHOLDER for the motor controller's
acceleration), so reference angle, rate and acceleration are continuous. All angles
returned here are bench angles θ (see :mod:`twin.config`).
"""

from __future__ import annotations

import math

import numpy as np

from twin.channels import bench_from_encoder
from twin.config import BenchConfig
from twin.errors import ConfigError
from twin.tracefile import DriveInputs, load_trace, trace_duration  # noqa: F401 (trace_duration: re-exported)

RPM_TO_RAD_S = 2.0 * math.pi / 60.0


def command_events(cfg: BenchConfig) -> list[tuple[float, float]]:
    """(time [s], motor command [rpm]) steps of a synthetic program, starting at rest."""
    d = cfg.drive
    if d.program == "constant":
        # drive.crank_rpm gives the crank speed directly: its motor equivalent through the belt
        return [(0.0, d.crank_rpm * d.belt_ratio if d.crank_rpm != 0 else d.motor_rpm)]
    if d.program == "steps":
        return [(float(t), float(r)) for t, r in zip(d.steps_s, d.steps_rpm)]
    if d.program == "protocol":
        ev, t = [], d.protocol_stop_s
        for rpm in d.protocol_rpm:
            ev.append((t, rpm))
            ev.append((t + d.protocol_hold_s, 0.0))
            t += d.protocol_hold_s + d.protocol_stop_s
        return ev
    raise ConfigError("drive.program", f"{d.program!r} has no command steps")


def _ramp(tau: np.ndarray, T: float, shape: str = "cosine") -> tuple[np.ndarray, np.ndarray]:
    """Ramp s(τ) from 0 to 1 over T and its integral ∫0^τ s; τ clipped to [0, ∞).

    ``shape`` "cosine": s = (1 − cos(π τ/T))/2 (continuous acceleration); "linear": s = τ/T
    (constant acceleration, ``drive.ramp_shape``)."""
    tau = np.maximum(tau, 0.0)
    if T <= 0:
        return (tau > 0).astype(float), tau
    tc = np.minimum(tau, T)
    if shape == "linear":
        return tc / T, 0.5 * tc * tc / T + (tau - tc)
    s = 0.5 * (1.0 - np.cos(np.pi * tc / T))
    integral = 0.5 * (tc - T / np.pi * np.sin(np.pi * tc / T)) + (tau - tc)
    return s, integral


def _ramp_rate(tau: np.ndarray, T: float, shape: str = "cosine") -> np.ndarray:
    """ds/dτ of :func:`_ramp` [1/s] (0 outside the ramp; a ramp of T = 0 is a jump: 0 here)."""
    tau = np.asarray(tau, dtype=np.float64)
    if T <= 0:
        return np.zeros_like(tau)
    inside = (tau > 0) & (tau < T)
    if shape == "linear":
        return np.where(inside, 1.0 / T, 0.0)
    return np.where(inside, 0.5 * np.pi / T * np.sin(np.pi * np.clip(tau, 0.0, T) / T), 0.0)


def _extrapolate(x: np.ndarray, n: int) -> np.ndarray:
    """``n`` samples continuing ``x`` (uniformly sampled) by its least-squares quadratic."""
    k = np.arange(x.size, dtype=np.float64) - (x.size - 1)
    c = np.polyfit(k, x, 2 if x.size >= 3 else 1)
    return np.polyval(c, np.arange(1, n + 1, dtype=np.float64))


class DriveReference:
    """Reference bench angle θ_ref(t) [rad] and rate ω_ref(t) [rad/s] of a configuration.

    The "trace" program follows ``inputs.trace`` (t [s], encoder angle [rad]; the library passes the
    arrays, e.g. a replay's recorded encoder), else the file ``drive.trace_file`` a user names."""

    def __init__(self, cfg: BenchConfig, inputs: DriveInputs | None = None):
        self.cfg = cfg
        d = cfg.drive
        self.direction = cfg.mechanism.crank_direction
        self.theta0 = float(bench_from_encoder(d.initial_encoder_angle_rad, self.direction))
        self._trace = None
        if d.program == "trace":
            from twin.tracefile import check_trace_speed

            if inputs is not None and inputs.trace is not None:
                # a library's arrays (a replay's recorded encoder, in radians by construction; its counts were
                # checked against the recording's own drive, which may be faster than this one's, e.g. torque)
                t, phi = inputs.trace
            else:
                t, phi = load_trace(d.trace_file)
                # a user's file: the fastest crank the drive commands (the motor's ±1000 rpm through the belt,
                # or crank_rpm); far faster is an angle in degrees
                check_trace_speed(t, phi, max(1000.0 / d.belt_ratio, abs(d.crank_rpm)), str(d.trace_file))
            self._trace = self._prepare_trace(t, phi)
            h = float(np.median(np.diff(t)))
            run_s = float(cfg.simulation.duration_s)
            if run_s > self.trace_duration_s + h + 1e-9:
                raise ConfigError("simulation.duration_s", f"is {run_s:g} s but the trace {d.trace_file} covers "
                                                           f"{self.trace_duration_s:g} s; shorten the run or give a "
                                                           "longer trace")
        else:
            self.events = command_events(cfg)

    # -- synthetic programs
    def _speed_terms(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        d = self.cfg.drive
        omega = np.zeros_like(t)
        angle = np.zeros_like(t)
        prev = 0.0
        for t_ev, rpm in self.events:
            target = rpm / d.belt_ratio * RPM_TO_RAD_S
            s, integ = _ramp(t - t_ev, d.ramp_s, d.ramp_shape)
            omega += (target - prev) * s
            angle += (target - prev) * integ
            prev = target
        return omega, angle

    # -- trace program
    def _prepare_trace(self, t: np.ndarray, phi: np.ndarray):
        """Zero-phase filtered reference from an encoder trace (cutoff ``drive.trace_filter_hz``).

        The trace is put on a uniform grid (its median spacing; linear interpolation only if it
        is not uniform already), extended at both ends by 3/cutoff seconds of the quadratic that
        fits its first/last 1/cutoff seconds (constant acceleration: no start/end transient in
        the filtered angle, rate or acceleration), low-passed forward and backward with a
        4th-order Butterworth (no lag; −6 dB at the cutoff) and cut back; a C2 cubic spline
        through the filtered samples gives θ_ref(t) and its derivative ω_ref(t).
        """
        from scipy.interpolate import make_interp_spline  # scipy import only when needed
        from scipy.signal import butter, sosfiltfilt

        theta = np.asarray(bench_from_encoder(phi, self.direction), dtype=np.float64)
        tt = np.asarray(t, dtype=np.float64) - t[0]
        fc = float(self.cfg.drive.trace_filter_hz)
        if fc > 0 and tt.size >= 4:
            h = float(np.median(np.diff(tt)))
            if np.max(np.abs(np.diff(tt) - h)) > 1e-6 * h:
                grid = np.arange(int(np.floor(tt[-1] / h + 1e-9)) + 1) * h
                theta, tt = np.interp(grid, tt, theta), grid
            fs = 1.0 / h
            if fc >= 0.5 * fs:
                raise ConfigError("drive.trace_filter_hz",
                                  f"must be below half the trace's sample rate ({0.5 * fs:g} Hz), got {fc:g}")
            sos = butter(4, fc, fs=fs, output="sos")
            pad = int(np.ceil(3.0 * fs / fc))
            fit = max(8, min(theta.size, int(np.ceil(fs / fc))))
            ext = np.concatenate([_extrapolate(theta[:fit][::-1], pad)[::-1], theta, _extrapolate(theta[-fit:], pad)])
            theta = sosfiltfilt(sos, ext, padtype=None)[pad:pad + theta.size]
        spline = make_interp_spline(tt, theta, k=3)
        self.theta0 = float(theta[0])
        self.trace_duration_s = float(tt[-1])
        return spline, spline.derivative()

    # -- within-turn ripple (drive.ripple_pct)
    def _ripple_terms(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """(D, S, C) of the ripple at the base reference angle θ_b: the encoder-angle shift
        D = Σ (a_k/k)[cos(k φ_b(0) + p_k) − cos(k φ_b + p_k)], the speed factor S = Σ a_k sin(k φ_b + p_k)
        and its derivative in φ_b, C = Σ a_k k cos(k φ_b + p_k); None without ripple."""
        d = self.cfg.drive
        if not any(d.ripple_pct):
            return None
        phases = d.ripple_phase_rad or (0.0,) * len(d.ripple_pct)
        phi = self.direction * (np.asarray(theta, dtype=np.float64) + np.pi / 2.0)  # encoder angle
        phi0 = self.direction * (self._base_start_theta + np.pi / 2.0)
        D, S, C = np.zeros_like(phi), np.zeros_like(phi), np.zeros_like(phi)
        for k, (pct, p) in enumerate(zip(d.ripple_pct, phases), start=1):
            a = pct / 100.0
            D += a / k * (math.cos(k * phi0 + p) - np.cos(k * phi + p))
            S += a * np.sin(k * phi + p)
            C += a * k * np.cos(k * phi + p)
        return D, S, C

    @property
    def _base_start_theta(self) -> float:
        """θ_b(0) [rad], computed once."""
        if not hasattr(self, "_theta_b0"):
            self._theta_b0 = float(self._base(np.zeros(1))[0][0])
        return self._theta_b0

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """θ_ref(t) [rad] and ω_ref(t) [rad/s], with the ripple of ``drive.ripple_pct``:
        θ = θ_b + direction·D, ω = ω_b (1 + S) (:meth:`_ripple_terms`)."""
        theta, omega = self._base(t)
        r = self._ripple_terms(theta)
        if r is None:
            return theta, omega
        D, S, _ = r
        return theta + self.direction * D, omega * (1.0 + S)

    def _base(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        t = np.asarray(t, dtype=np.float64)
        if self._trace is not None:
            spline, dspline = self._trace
            tc = np.clip(t, 0.0, self.trace_duration_s)
            return spline(tc), dspline(tc)
        omega, angle = self._speed_terms(t)
        return self.theta0 + self.direction * angle, self.direction * omega

    def acceleration(self, t: np.ndarray) -> np.ndarray:
        """Reference crank acceleration α_ref(t) = dω_ref/dt [rad/s²] (the prescribed drive's
        feed-forward; a ramp of ``ramp_s = 0`` contributes nothing: its jump is at t = 0 only); with
        ripple, α_b (1 + S) + direction·ω_b² C (:meth:`_ripple_terms`)."""
        alpha = self._base_acceleration(t)
        if not any(self.cfg.drive.ripple_pct):
            return alpha
        theta, omega = self._base(t)
        _, S, C = self._ripple_terms(theta)
        return alpha * (1.0 + S) + self.direction * omega * omega * C

    def _base_acceleration(self, t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, dtype=np.float64)
        if self._trace is not None:
            spline, _ = self._trace
            d2 = spline.derivative(2)
            inside = (t >= 0.0) & (t <= self.trace_duration_s)
            return np.where(inside, d2(np.clip(t, 0.0, self.trace_duration_s)), 0.0)
        d = self.cfg.drive
        alpha = np.zeros_like(t)
        prev = 0.0
        for t_ev, rpm in self.events:
            target = rpm / d.belt_ratio * RPM_TO_RAD_S
            alpha += (target - prev) * _ramp_rate(t - t_ev, d.ramp_s, d.ramp_shape)
            prev = target
        return self.direction * alpha

    def start_rate(self) -> float:
        """Crank rate the mechanism starts with at t = 0 [rad/s]. PID drive: 0 (at rest; the
        PID spins it up). Prescribed drive: the program's rate at t = 0, the right-hand limit
        for a speed jump at t = 0 (``ramp_s = 0``), so that such a run is at constant speed from
        its first step (every body's velocity consistent with it); a trace's rate at its start."""
        d = self.cfg.drive
        if d.mode != "prescribed":
            return 0.0
        if self._trace is not None:
            return float(self(np.zeros(1))[1][0])
        if d.ramp_s > 0:
            return float(self(np.zeros(1))[1][0])
        at0 = [rpm for t_ev, rpm in self.events if t_ev == 0.0]  # the last command at t = 0 holds
        w0 = self.direction * (at0[-1] if at0 else 0.0) / d.belt_ratio * RPM_TO_RAD_S
        r = self._ripple_terms(np.array([self._base_start_theta]))
        return w0 if r is None else w0 * (1.0 + float(r[1][0]))

    def command_rpm(self, t: np.ndarray) -> np.ndarray:
        """Motor speed command [rpm] (the DAQ's analog output, ±10 V ↔ ±1000 rpm)."""
        t = np.asarray(t, dtype=np.float64)
        if self._trace is not None:
            _, dspline = self._trace
            w = dspline(np.clip(t, 0.0, self.trace_duration_s))
            return self.direction * w / RPM_TO_RAD_S * self.cfg.drive.belt_ratio
        out = np.zeros_like(t)
        for t_ev, rpm in self.events:
            out = np.where(t >= t_ev, rpm, out)
        return out
