"""Parameters of the bench's drive train: motor, speed controller and V-belt (S003 §2.3.2, §4.2).

Used with ``drive.mode = "motor"`` (the motor's speed loop follows the analog command) and
``drive.mode = "torque"`` (a motor torque program, then release and coast-down). The crank PID
and the prescribed drive do not read these numbers.

Model (both engines, the same equations; the dynamics are :mod:`twin.reference.drivetrain`
and the native passive callback of the MuJoCo twin, ``twin/native/_bore.c``):

* Motor rotor: one more generalized coordinate, the motor angle φ_m, with the rotor (and motor
  pulley) inertia J_m: J_m φ̈_m = τ_m − r_m F, F the belt's effective pull (tight minus slack).
* Belt: linear units along the belt. Pitch radii r_m (motor pulley) and r_c = ``drive.belt_ratio``
  × r_m (crank pulley); belt speeds v_m = r_m ω_m, v_c = r_c θ̇, relative speed v_rel = v_m − v_c.
  The two spans are springs in parallel, k = 2 EA / L, with a damper c (Kelvin–Voigt) on their
  stretch x, in series with the belt's slip on the pulleys at speed w:
  ẋ = v_rel − w, F = k x + c ẋ. The slip speed follows the pull:
  creep below the friction limit, w = F |v_m| / EA (the elastic strain change around the
  pulley: a speed loss proportional to the transmitted pull, zero at standstill), and
  regularized sliding beyond it, w = sign(F) [F_max |v_m| / EA + (|F| − F_max) / c_slip].
  F_max = 2 F_0 tanh(μ' φ / 2) is the Euler–Eytelwein (capstan) limit of T_tight/T_slack =
  e^{μ' φ} with the preload F_0 = (T_tight + T_slack)/2, the wedge effect μ' = μ / sin(β/2) and
  the wrap angle φ of the smaller (motor) pulley. F follows from x and v_rel in closed form
  (w is piecewise linear in F), so there is no stick discontinuity. The crank receives the
  torque r_c F, the motor −r_m F. Dissipation: c ẋ² (belt damping) and F w ≥ 0 (creep and slip).
* Speed controller (``drive.mode = "motor"``), a discrete PI at ``controller_rate_hz``: the
  motor's own encoder (``encoder_counts`` per turn) is read as an integer count; the speed
  estimate is the count difference over the sample period, low-passed (first order,
  ``speed_filter_hz``); the set point is the analog command (±10 V ↔ ±1000 rpm, the program's
  motor speed with the controller's profile ramp ``drive.ramp_s``); torque = kp e + ki ∫e,
  clamped to ± ``peak_torque_nm``, held until the next sample (the current loop is taken as
  ideal). The integral stops while the torque is clamped (anti-windup). The continuous rating
  ``continuous_torque_nm`` is not a clamp: the run summary reports the motor's RMS torque
  against it (the drive's I²t derating acts over seconds to minutes and is not modelled).
* Torque program (``drive.mode = "torque"``): the motor torque steps to ``torque_nm[i]`` at
  ``torque_s[i]`` through a linear ramp of ``torque_ramp_s`` (steps and ramps), and is zero
  from ``release_s`` on (release: the mechanism coasts down through the belt); clamped to
  the peak torque.

Every number the papers do not give is a PLACEHOLDER, with the range a user should explore.
The defaults run the 38 s protocol of S003 §4.3 stably at h = 1e-5 s in both engines.
"""

from __future__ import annotations

import math
import typing
from dataclasses import dataclass

from twin.config.common import check_types
from twin.errors import ConfigError


def _num(value: typing.Any, name: str, lo: float, hi: float, unit: str, lo_open: bool = False) -> None:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) \
        and (value > lo if lo_open else value >= lo) and value <= hi
    if not ok:
        raise ConfigError(name,
                          f"must lie in {'(' if lo_open else '['}{lo:g}, {hi:g}] {unit}, got {value!r}")


@dataclass(frozen=True)
class Drivetrain:
    """Motor, speed controller and V-belt of the bench (see the module docstring for the model).

    Attributes:
        rotor_inertia_kgm2: inertia of the motor rotor with the motor pulley [kg m²].
            PLACEHOLDER (Maxon IDX 56 L rotor plus a small pulley; not in the seeds): 2e-4,
            explore 1e-4 – 6e-4.
        motor_pulley_radius_m: pitch radius r_m of the motor pulley [m]; the crank pulley's is
            ``drive.belt_ratio`` × r_m. PLACEHOLDER: 0.02, explore 0.015 – 0.04.
        belt_ea_n: axial stiffness EA of the belt (cords) [N]: span stiffness EA/L and creep
            strain F/EA. PLACEHOLDER: 2e4 (creep ≈ 1 % at the friction limit), explore 5e3 – 1e5.
        span_length_m: free length L of each belt span [m]. PLACEHOLDER: 0.3, explore 0.2 – 0.5.
        belt_damping_nspm: damping c of the two spans' stretch [N s/m]. PLACEHOLDER: 25
            (≈ 5 % of critical on the rotor–belt–crank mode of the defaults), explore 5 – 100.
        preload_n: static tension F_0 of each span [N]. PLACEHOLDER: 100, explore 30 – 300.
        friction_mu: belt–pulley friction coefficient μ [-]. PLACEHOLDER: 0.3 (rubber on cast
            iron), explore 0.15 – 0.5.
        groove_angle_deg: V-groove angle β [deg] (wedge effect μ' = μ / sin(β/2)).
            PLACEHOLDER: 38, explore 34 – 40 (ISO V-belt grooves).
        wrap_angle_rad: wrap angle φ on the motor pulley [rad]. PLACEHOLDER: 2.8 (≈ 160°, a
            1:3.97 open drive), explore 2.4 – 3.1.
        slip_damping_nspm: regularization c_slip of sliding beyond the friction limit [N s/m]:
            the pull exceeds F_max by c_slip × (slip speed − creep). Numerical, not physical:
            small is closer to Coulomb (explicit stability of the stretch needs
            h k / (c + c_slip) < 2, c the belt damping). Default 2 (1 m/s of sliding adds 2 N to a
            limit of ≈ 170 N with the default preload), explore 1 – 50.
        controller_rate_hz: sample rate of the speed loop [Hz]. PLACEHOLDER (the bench's EPOS
            settings are not known, S003 §6): 2500, explore 1000 – 10000. Its period must be a
            whole number of integration steps.
        encoder_counts: motor encoder counts per turn [-] (S003 §2.3.2: 12 bit, 4096).
        speed_filter_hz: cutoff of the first-order low-pass on the encoder speed estimate [Hz].
            PLACEHOLDER: 100, explore 30 – 500.
        speed_kp_nms: proportional gain of the speed loop [N m s/rad] (motor side).
            PLACEHOLDER: 0.2, explore 0.05 – 0.5.
        speed_ki_nm: integral gain [N m/rad]. PLACEHOLDER: 4, explore 0 – 20.
        peak_torque_nm: motor torque clamp [N m] (S003 §2.3.2: 1.589).
        continuous_torque_nm: continuous rating [N m] (S003 §2.3.2: 0.795), reported, not
            clamped (see the module docstring).
        torque_s: times of the torque program's steps [s] (``drive.mode = "torque"``). Default:
            the release test S003 §6 plans, at rest for 2 s, 1.2 N m for 0.5 s (≈ 500 motor rpm
            at release on the bench's mechanism), then released.
        torque_nm: motor torque from each of those times [N m].
        torque_ramp_s: linear ramp of each torque step [s] (0 = a true step).
        release_s: the torque is zero from this time on [s] (release and coast-down);
            0 = no release.
        command_file: recorded analog command for ``drive.mode = "motor"`` (``.npz`` with ``t`` [s]
            from the run's start and ``volts`` [V], e.g. a bench recording's ``motor_command``
            channel; ``twin replay --drive motor`` writes one): the speed set point is that voltage
            / ``instrumentation.command_v_per_rpm``, followed as recorded (no profile ramp), instead
            of the drive program's speed. Empty = the program.
    """

    rotor_inertia_kgm2: float = 2e-4
    motor_pulley_radius_m: float = 0.02
    belt_ea_n: float = 2e4
    span_length_m: float = 0.3
    belt_damping_nspm: float = 25.0
    preload_n: float = 100.0
    friction_mu: float = 0.3
    groove_angle_deg: float = 38.0
    wrap_angle_rad: float = 2.8
    slip_damping_nspm: float = 2.0
    controller_rate_hz: float = 2500.0
    encoder_counts: int = 4096
    speed_filter_hz: float = 100.0
    speed_kp_nms: float = 0.2
    speed_ki_nm: float = 4.0
    peak_torque_nm: float = 1.589
    continuous_torque_nm: float = 0.795
    torque_s: tuple[float, ...] = (2.0,)
    torque_nm: tuple[float, ...] = (1.2,)
    torque_ramp_s: float = 0.05
    release_s: float = 2.5
    command_file: str = ""

    def __post_init__(self) -> None:

        check_types(self)
        _num(self.rotor_inertia_kgm2, "rotor_inertia_kgm2", 0.0, 1.0, "kg m^2", lo_open=True)
        _num(self.motor_pulley_radius_m, "motor_pulley_radius_m", 0.0, 0.5, "m", lo_open=True)
        _num(self.belt_ea_n, "belt_ea_n", 0.0, 1e8, "N", lo_open=True)
        _num(self.span_length_m, "span_length_m", 0.0, 10.0, "m", lo_open=True)
        _num(self.belt_damping_nspm, "belt_damping_nspm", 0.0, 1e6, "N s/m")
        _num(self.preload_n, "preload_n", 0.0, 1e5, "N", lo_open=True)
        _num(self.friction_mu, "friction_mu", 0.0, 2.0, "", lo_open=True)
        _num(self.groove_angle_deg, "groove_angle_deg", 10.0, 180.0, "deg")
        _num(self.wrap_angle_rad, "wrap_angle_rad", 0.0, 2 * math.pi, "rad", lo_open=True)
        _num(self.slip_damping_nspm, "slip_damping_nspm", 0.0, 1e6, "N s/m", lo_open=True)
        _num(self.controller_rate_hz, "controller_rate_hz", 1.0, 1e6, "Hz")
        if isinstance(self.encoder_counts, bool) or not isinstance(self.encoder_counts, int) \
                or not 4 <= self.encoder_counts <= 2 ** 24:
            raise ConfigError("encoder_counts", f"must be an integer in [4, 16777216], got {self.encoder_counts!r}")
        _num(self.speed_filter_hz, "speed_filter_hz", 0.0, 1e6, "Hz", lo_open=True)
        _num(self.speed_kp_nms, "speed_kp_nms", 0.0, 100.0, "N m s/rad")
        _num(self.speed_ki_nm, "speed_ki_nm", 0.0, 1e4, "N m/rad")
        _num(self.peak_torque_nm, "peak_torque_nm", 0.0, 100.0, "N m", lo_open=True)
        _num(self.continuous_torque_nm, "continuous_torque_nm", 0.0, 100.0, "N m", lo_open=True)
        if len(self.torque_s) != len(self.torque_nm):
            raise ConfigError("torque_nm",
                              f"must hold one torque per time of torque_s ({len(self.torque_s)}), got {len(self.torque_nm)}")
        if not all(isinstance(t, (int, float)) and math.isfinite(t) and t >= 0 for t in self.torque_s) \
                or any(b <= a for a, b in zip(self.torque_s, self.torque_s[1:])):
            raise ConfigError("torque_s", f"must be times >= 0 s in increasing order, got {list(self.torque_s)!r}")
        if not all(isinstance(x, (int, float)) and math.isfinite(x) and abs(x) <= 100 for x in self.torque_nm):
            raise ConfigError("torque_nm", f"must be torques within ±100 N m, got {list(self.torque_nm)!r}")
        _num(self.torque_ramp_s, "torque_ramp_s", 0.0, 100.0, "s")
        _num(self.release_s, "release_s", 0.0, 3600.0, "s")
        if not isinstance(self.command_file, str):
            raise ConfigError("command_file", f"must be a file name (or empty), got {self.command_file!r}")

    # -- derived (SI)
    @property
    def wedge_mu(self) -> float:
        """Effective friction coefficient of the V-groove μ' = μ / sin(β/2) [-]."""
        return self.friction_mu / math.sin(math.radians(self.groove_angle_deg) / 2.0)

    @property
    def max_pull_n(self) -> float:
        """Friction limit of the effective pull F_max = 2 F_0 tanh(μ' φ / 2) [N] (capstan)."""
        return 2.0 * self.preload_n * math.tanh(self.wedge_mu * self.wrap_angle_rad / 2.0)

    @property
    def stiffness_npm(self) -> float:
        """Stiffness of the two spans in parallel k = 2 EA / L [N/m]."""
        return 2.0 * self.belt_ea_n / self.span_length_m

    def crank_pulley_radius_m(self, belt_ratio: float) -> float:
        """Pitch radius of the crank pulley r_c = ratio × r_m [m]."""
        return belt_ratio * self.motor_pulley_radius_m

    def controller_stride(self, timestep_s: float) -> int:
        """Integration steps per controller sample; ConfigError if the period is not a whole number of steps."""
        k = 1.0 / (self.controller_rate_hz * timestep_s)
        n = int(round(k))
        if n < 1 or abs(n - k) > 1e-6 * k:
            raise ConfigError("drivetrain.controller_rate_hz",
                              f"its period 1/{self.controller_rate_hz:g} Hz must be a whole number of timesteps "
                              f"({timestep_s:g} s), e.g. {1.0 / (max(1, n) * timestep_s):.10g} Hz")
        return n

    def torque_program(self, t: typing.Any) -> typing.Any:
        """Motor torque of the torque program at times ``t`` [N m] (numpy array in, array out)."""
        import numpy as np

        t = np.asarray(t, dtype=np.float64)
        out = np.zeros_like(t)
        prev = 0.0
        for ts, tq in zip(self.torque_s, self.torque_nm):
            if self.torque_ramp_s > 0:
                s = np.clip((t - ts) / self.torque_ramp_s, 0.0, 1.0)
            else:
                s = (t >= ts).astype(np.float64)
            out += (tq - prev) * s
            prev = tq
        if self.release_s > 0:
            out = np.where(t >= self.release_s, 0.0, out)
        return np.clip(out, -self.peak_torque_nm, self.peak_torque_nm)


#: the placeholders' ranges a user should explore (their documentation above), as (factor name,
#: field, description, (low, high)): the dataset factors and the stability campaign draw from them
EXPLORE_RANGES: tuple[tuple[str, str, str, tuple[float, float]], ...] = (
    ("rotor_inertia_kgm2", "rotor_inertia_kgm2", "motor rotor and pulley inertia [kg m^2]", (1e-4, 6e-4)),
    ("belt_ea_n", "belt_ea_n", "belt axial stiffness EA [N]", (5e3, 1e5)),
    ("belt_damping_nspm", "belt_damping_nspm", "belt span damping [N s/m]", (5.0, 100.0)),
    ("belt_preload_n", "preload_n", "belt span preload [N]", (30.0, 300.0)),
    ("belt_mu", "friction_mu", "belt-pulley friction coefficient [-]", (0.15, 0.5)),
    ("speed_kp_nms", "speed_kp_nms", "speed loop proportional gain [N m s/rad]", (0.05, 0.5)),
    ("speed_ki_nm", "speed_ki_nm", "speed loop integral gain [N m/rad]", (0.0, 20.0)),
    ("speed_filter_hz", "speed_filter_hz", "speed estimate low-pass cutoff [Hz]", (30.0, 500.0)),
)
