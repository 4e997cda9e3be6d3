"""The crank's motion program and the PID that tracks it (S003 §2.2.2, §4.2–4.3)."""

from __future__ import annotations

import math
import typing
from dataclasses import dataclass

from twin.config.common import PROGRAMS, XML_DEFAULTS, _check, _choice, _finite, _positive, check_types


# ---------------------------------------------------------------------------- drive
@dataclass(frozen=True)
class Drive:
    """Crank motion program tracked by the PID (S003 §2.2.2, §4.2–4.3).

    Attributes:
        program: "constant" (spin up from rest to ``motor_rpm`` and hold), "steps" (motor
            command steps ``steps_rpm`` at times ``steps_s``, each followed by the cosine ramp:
            any speed profile, e.g. the random profiles of ``twin dataset``), "protocol"
            (the 38 s three-speed test of §4.3) or "trace" (crank angle from a file).
        motor_rpm: motor speed of the constant program [rpm] (S003: 250, 500, 750).
        belt_ratio: motor:crank speed ratio of the V-belt [-] (S003 §2.2.2: 3.97).
        ramp_s: duration of each speed change (smooth cosine ramp of the speed) [s].
            PLACEHOLDER: the motor controller's acceleration is not given; 0.5 s.
        ramp_shape: shape of each speed change: "cosine" (smooth, the bench's placeholder) or
            "linear" (constant acceleration over ``ramp_s``: the inverter's set acceleration
            time of S001 §VI.B.1, "increase the motor speed linearly").
        protocol_rpm: the three motor speeds of the protocol [rpm].
        protocol_hold_s: time at each protocol speed [s] (10 s).
        protocol_stop_s: stops before, between and after the speeds [s] (2 s).
        initial_encoder_angle_rad: crank encoder angle at t = 0 [rad] (0 = crank along −y).
            PLACEHOLDER: S003 did not control the start position; 0.
        trace_file: encoder trace for the "trace" program (``.npz`` with ``t`` [s] and
            ``angle`` [rad], or ``.csv`` with those columns), encoder angle convention.
        trace_filter_hz: cutoff of the zero-phase low-pass that turns the (quantized) trace
            into the reference angle [Hz]: 4th-order Butterworth run forward and backward
            (``scipy.signal.sosfiltfilt``), so the cutoff is the −6 dB point of the combined
            filter and there is no lag. 100 Hz keeps ~30 harmonics of the fastest crank rate
            (3.15 Hz at 750 motor rpm) and removes the count quantization's broadband part.
            0 = no filtering (interpolating spline through the raw samples).
        steps_s: times of the motor command steps of the "steps" program [s].
        steps_rpm: motor speed commanded at each of those times [rpm] (0 = stop).
        mode: how the crank follows the program: "pid" (the bench's crank PID tracks the
            reference angle and rate: a finite drive stiffness, S003 §4.3) or "prescribed" (an
            infinitely stiff drive: the crank angle *is* the program, θ(t) = θ_ref(t), as the
            papers that impose the crank motion assume, S001's CosmosMotion motor, S004's
            constant 30 rad/s, S000's 5000 rpm), "motor" (the bench's drive train: the motor's
            speed loop follows the analog command of the program on its own encoder and drives
            the crank through the V-belt; parameters in ``[drivetrain]``,
            :mod:`twin.config.drivetrain`) or "torque" (the same motor and belt driven by the
            torque program ``drivetrain.torque_s``/``torque_nm``, released at
            ``drivetrain.release_s``: the program's speeds are not used). Reference engine: the crank angle is a driving
            constraint of the R-matrix model (θ and θ̇ set from the program every step, the
            other coordinates from the reduced equations with θ̈ = α_ref; the drive torque is
            the θ row's residual). MuJoCo twin: the crank turns as an infinitely heavy
            flywheel, armature A ≈ 1e9 × the crank-side inertia, driven by a dead-beat law
            A [(θ_ref(t + h) − θ)/h² − θ̇/h] that lands the next step on the program
            (integrator Euler only); the drive torque channel is that torque minus A θ̈.
            A program whose speed jumps after t = 0 (ramp_s = 0 with "steps"/"protocol") is
            refused; ramp_s = 0 with "constant" starts the mechanism at full speed at t = 0
            (consistent velocities of every body). The PID gains are not used.
        crank_rpm: crank speed of the constant program given directly [rpm], bypassing the
            motor and the belt (the papers give crank speeds; S000 runs 50–5000 rpm);
            0 = ``motor_rpm`` / ``belt_ratio`` (the bench). When nonzero, ``motor_rpm`` is not
            used and the motor command channel reads crank_rpm × belt_ratio. |crank_rpm| ≤ 6000.
        ripple_pct: within-turn speed ripple imposed on the reference (``pid`` and ``prescribed``
            drives, any program, traces included): amplitude of harmonic k = 1, 2, ... of the crank
            rate, in percent of the speed [%], each in [0, 10]; () = none. The reference's encoder
            angle φ_b(t) becomes φ(t) = φ_b + Σ_k (a_k/k) [cos(k φ_b(0) + p_k) − cos(k φ_b + p_k)],
            so dφ/dt = dφ_b/dt · (1 + Σ_k a_k sin(k φ_b + p_k)) (a_k = ripple_pct[k-1]/100): the
            speed fluctuates with the crank position, as a belt drive's does (S003 §4.3: "not
            constant within a turn"); amplitudes are not measured on the bench (PLACEHOLDER: none).
            The motor command channel is the program's (unrippled). The ``motor`` and ``torque``
            drives make their own ripple (drive train) and refuse this field.
        ripple_phase_rad: phase p_k of each harmonic [rad], one per ``ripple_pct`` entry (() = all 0).
    """

    program: str = "constant"
    motor_rpm: float = 750.0
    belt_ratio: float = 3.97
    ramp_s: float = 0.5
    ramp_shape: str = "cosine"
    protocol_rpm: tuple[float, ...] = (250.0, 500.0, 750.0)
    protocol_hold_s: float = 10.0
    protocol_stop_s: float = 2.0
    initial_encoder_angle_rad: float = 0.0
    trace_file: str = ""
    trace_filter_hz: float = 100.0
    steps_s: tuple[float, ...] = ()
    steps_rpm: tuple[float, ...] = ()
    mode: str = "pid"
    crank_rpm: float = 0.0
    ripple_pct: tuple[float, ...] = ()
    ripple_phase_rad: tuple[float, ...] = ()

    MODES: typing.ClassVar[tuple[str, ...]] = ("pid", "prescribed", "motor", "torque")

    def __post_init__(self) -> None:

        check_types(self)
        _choice(self.program, "program", PROGRAMS)
        _choice(self.mode, "mode", self.MODES)
        _check(isinstance(self.crank_rpm, (int, float)) and math.isfinite(self.crank_rpm)
               and abs(self.crank_rpm) <= 6000, "crank_rpm",
               f"must lie in [-6000, 6000] rpm (0 = motor_rpm / belt_ratio), got {self.crank_rpm!r}")
        if self.crank_rpm != 0:
            _check(self.program == "constant", "crank_rpm",
                   f"sets the speed of the constant program only; got program = {self.program!r} (use 0)")
        if self.mode == "prescribed" and self.program in ("steps", "protocol"):
            _check(self.ramp_s > 0, "ramp_s",
                   "must be > 0 for a prescribed drive whose speed changes after t = 0 (a speed jump is an "
                   f"infinite crank acceleration), got {self.ramp_s!r}")
        _check(isinstance(self.motor_rpm, (int, float)) and math.isfinite(self.motor_rpm)
               and abs(self.motor_rpm) <= 1000, "motor_rpm",
               f"must lie in [-1000, 1000] rpm (±10 V command range), got {self.motor_rpm!r}")
        _positive(self.belt_ratio, "belt_ratio", "-")
        _check(isinstance(self.ramp_s, (int, float)) and 0 <= self.ramp_s <= 10,
               "ramp_s", f"must lie in [0, 10] s, got {self.ramp_s!r}")
        _choice(self.ramp_shape, "ramp_shape", ("cosine", "linear"))
        _check(len(self.protocol_rpm) >= 1 and all(abs(r) <= 1000 for r in self.protocol_rpm),
               "protocol_rpm", f"must hold 1+ speeds within ±1000 rpm, got {list(self.protocol_rpm)!r}")
        _check(self.protocol_hold_s > self.ramp_s, "protocol_hold_s",
               f"must exceed ramp_s ({self.ramp_s} s), got {self.protocol_hold_s!r}")
        _check(self.protocol_stop_s > self.ramp_s or self.protocol_stop_s >= 0, "protocol_stop_s",
               f"must be >= 0 s, got {self.protocol_stop_s!r}")
        _finite(self.initial_encoder_angle_rad, "initial_encoder_angle_rad", "rad")
        _check(isinstance(self.trace_filter_hz, (int, float)) and math.isfinite(self.trace_filter_hz)
               and self.trace_filter_hz >= 0, "trace_filter_hz",
               f"must be >= 0 Hz (0 = no filtering), got {self.trace_filter_hz!r}")
        if self.program == "trace":
            _check(bool(self.trace_file), "trace_file", "must name a trace file when program = \"trace\"")
        _check(len(self.steps_s) == len(self.steps_rpm), "steps_rpm",
               f"must hold one speed per time of steps_s ({len(self.steps_s)}), got {len(self.steps_rpm)}")
        if self.program == "steps":
            _check(len(self.steps_s) >= 1, "steps_s", "must hold at least one step time for program = \"steps\"")
        _check(all(isinstance(t, (int, float)) and math.isfinite(t) and t >= 0 for t in self.steps_s)
               and all(b > a for a, b in zip(self.steps_s, self.steps_s[1:])), "steps_s",
               f"must be times >= 0 s in increasing order, got {list(self.steps_s)!r}")
        _check(all(isinstance(r, (int, float)) and math.isfinite(r) and abs(r) <= 1000 for r in self.steps_rpm),
               "steps_rpm", f"must be motor speeds within ±1000 rpm, got {list(self.steps_rpm)!r}")
        _check(len(self.ripple_pct) <= 8 and all(isinstance(a, (int, float)) and not isinstance(a, bool)
                                                 and math.isfinite(a) and 0 <= a <= 10 for a in self.ripple_pct),
               "ripple_pct", f"must hold at most 8 amplitudes in [0, 10] % (harmonics 1, 2, ... of the crank rate), "
                             f"got {list(self.ripple_pct)!r}")
        _check(len(self.ripple_phase_rad) in (0, len(self.ripple_pct))
               and all(isinstance(p, (int, float)) and math.isfinite(p) for p in self.ripple_phase_rad),
               "ripple_phase_rad", f"must hold one finite phase [rad] per ripple_pct entry ({len(self.ripple_pct)}) "
                                   f"or none, got {list(self.ripple_phase_rad)!r}")
        if any(self.ripple_pct):
            _check(self.mode in ("pid", "prescribed"), "ripple_pct",
                   f"applies to the pid and prescribed drives; drive.mode = {self.mode!r} makes its own ripple "
                   "(drive train): use ()")

    @property
    def crank_rad_s(self) -> float:
        """Crank speed of the constant program [rad/s] (``crank_rpm``, or motor rpm / belt ratio)."""
        if self.crank_rpm != 0:
            return self.crank_rpm * 2.0 * math.pi / 60.0
        return self.motor_rpm / self.belt_ratio * 2.0 * math.pi / 60.0

    @property
    def protocol_duration_s(self) -> float:
        """Length of the protocol: stops and holds (38 s for the paper's protocol) [s]."""
        n = len(self.protocol_rpm)
        return (n + 1) * self.protocol_stop_s + n * self.protocol_hold_s


@dataclass(frozen=True)
class PID:
    """Crank PID tracking the reference angle and rate (native MuJoCo ``<pid>`` law).

    torque = kp (θ_ref − θ) + kv (ω_ref − ω) + ki ∫(θ_ref − θ) dt, integral clamped to ±imax.
    Gains from ``analysis/tune_pid.py`` (pole placement on the crank's largest effective
    inertia over a turn, kp sized for 0.5 encoder count of error at 750 motor rpm; see its
    docstring), rounded to two digits. Defaults: mjcf/bench.xml (the ``crank_pid`` actuator).

    Attributes:
        kp: proportional gain [N m/rad].
        kv: rate gain [N m s/rad].
        ki: integral gain [N m/(rad s)].
        imax: anti-windup clamp of the integral state [rad s]; 0 = unclamped.
    """

    kp: float = XML_DEFAULTS.kp
    kv: float = XML_DEFAULTS.kv
    ki: float = XML_DEFAULTS.ki
    imax: float = XML_DEFAULTS.imax

    def __post_init__(self) -> None:

        check_types(self)
        _positive(self.kp, "kp", "N m/rad")
        for name in ("kv", "ki", "imax"):
            v = getattr(self, name)
            _check(isinstance(v, (int, float)) and math.isfinite(v) and v >= 0,
                   name, f"must be a finite number >= 0, got {v!r}")
