"""Restitution from a recording (``twin identify restitution REC``): S001's procedure as a tool.

S001 (§VI.B.2, Table IV) found its coefficient of restitution by running the simulation again
and again with a different damping and comparing the slider acceleration with the measured one
until they agreed (0.55 after seven trials). Here:

1. the recording is read through the project's recording path (:func:`twin.recording.read_recording`:
   validation, the bench configuration stored with it) and its accelerometer is calibrated with
   the recording's own static calibration (:func:`twin.instrument.calibration.measured_accel`);
2. a candidate e sets ``contact.restitution`` of the recording's configuration (the contact law's
   damping χ(e); every other field as recorded) and the twin simulates the recording's length at
   its sample rate, driven by the configuration's drive program (S001 ran its simulation with the
   experiment's 0.2 s ramp; the rig has no encoder);
3. the simulated accelerometer goes through the same sensor chain without noise and is calibrated
   the same way (:func:`twin.instrument.apply_chain`, :func:`~twin.instrument.simulated_calibration`),
   so the two sides differ only by the physics and the recording's noise;
4. the mismatch of a candidate is the RMS difference of the two calibrated slider accelerations
   over the window (after an optional constant time shift, estimated once from the motion's low
   frequencies with :func:`twin.signals.estimate_lag`, S001 reports 0.01 s between its
   experiment and simulation);
5. coarse to fine: the impact spikes last about one 5 kHz sample, so the sampled spikes change at
   random with sub-sample shifts of an impact and the full-band mismatch is a needle at the answer
   among spurious dips; low-passed at ``lowpass_hz`` the minimum is wider (a few hundredths on S001),
   though still with dips elsewhere (``analysis/results/s001``). A coarse grid is scored
   low-passed; around each of its ``starts`` best local minima (default 3) a grid of ``fine_step``
   over ±``fine_half_width`` is scored low-passed and a grid of ``fine_step``/5 over ±2
   ``fine_step`` around that one's best over the full band; the answer is the best of those
   finest stages over the full band. One start (the coarse best only) found 0.55 from a MuJoCo
   recording at e = 0.55 until the secant-rate friction (f819579), then 0.428: the coarse 0.57 landed
   beside the answer's narrow basin and scored 1.8 m/s² low-passed against a wide wrong basin's 1.71
   at 0.42, while over the full band 0.428 reads 9.2 m/s² and the answer the noise's 5.

:func:`write_synthetic_recording` writes the recordings of the recovery check: a run of the configuration at
a known e, white noise added to the accelerometer's truth, through the sensor chain.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from twin.config import ACCELEROMETERS, BenchConfig
from twin.errors import ConfigError, RecordingError

#: default coarse grid of the restitution coefficient [-]
COARSE_GRID: tuple[float, ...] = tuple(round(0.15 + 0.05 * k, 2) for k in range(17))  # 0.15 .. 0.95
#: default step of the fine grid [-]
FINE_STEP = 0.01
#: default coarse grid of the IMPACT law's c_max [N s/m] (S001 Table IV: 25 000-28 000)
C_MAX_GRID: tuple[float, ...] = tuple(5000.0 + 2500.0 * k for k in range(19))  # 5 000 .. 50 000
#: parameters a sweep can vary: name -> (configuration field, default coarse grid, default fine step,
#: allowed range (lo, hi], law the recording's configuration must use, unit)
PARAMETERS: dict[str, tuple[str, tuple[float, ...], float, tuple[float, float], str, str]] = {
    "restitution": ("contact.restitution", COARSE_GRID, FINE_STEP, (0.0, 1.0), "hysteresis", "-"),
    "c_max": ("contact.impact_c_max_nspm", C_MAX_GRID, 500.0, (0.0, 1e7), "adams-impact", "N s/m"),
}


@dataclass(frozen=True)
class SweepOptions:
    """Settings of a restitution sweep.

    Attributes:
        sensor: accelerometer compared (S001's slider accelerometer is AC6 of the preset).
        start_s: start of the compared window, from the recording's first sample [s].
        stop_s: end of the window [s]; 0 = the recording's end.
        parameter: what the sweep varies: "restitution" (``contact.restitution``, the damping of the
            hysteresis laws) or "c_max" (``contact.impact_c_max_nspm``, the damping of the ADAMS
            IMPACT law, S001's Table IV procedure) (:data:`PARAMETERS`).
        coarse: coarse grid of the parameter (empty = its default: e 0.15-0.95, c_max 5 000-50 000 N s/m).
        fine_step: step of the fine grid around the best coarse value (< 0 = the parameter's default,
            0.01 for e, 500 N s/m for c_max; 0 = no fine grid).
        fine_half_width: half width of the fine grid (0 = 5 fine steps).
        engine: engine of the candidates ("" = the recording's configuration's).
        max_lag_s: largest time shift searched between recording and simulation [s]; 0 = none.
        lowpass_hz: low-pass of the coarse and first fine stage's mismatch [Hz] (0 = full band).
        starts: how many of the coarse grid's best local minima the fine stages refine, each on
            its own (the mismatch of a run with impacts has several basins: a coarse step can land
            beside the answer's narrow basin and score worse than a wide wrong one); the answer is
            the best of the finest stage's candidates over the full band.
    """

    sensor: str = "AC6"
    start_s: float = 0.0
    stop_s: float = 0.0
    coarse: tuple[float, ...] = ()
    fine_step: float = -1.0
    fine_half_width: float = 0.0
    parameter: str = "restitution"
    engine: str = ""
    max_lag_s: float = 0.0
    lowpass_hz: float = 200.0
    starts: int = 3

    def __post_init__(self) -> None:
        if not (isinstance(self.starts, int) and self.starts >= 1):
            raise ConfigError("starts", f"must be a whole number >= 1, got {self.starts!r}")
        if self.sensor not in ACCELEROMETERS:
            raise ConfigError("sensor", f"must be one of {', '.join(ACCELEROMETERS)}, got {self.sensor!r}")
        if not (math.isfinite(self.start_s) and self.start_s >= 0):
            raise ConfigError("start_s", f"must be a time >= 0 s, got {self.start_s!r}")
        if not (math.isfinite(self.stop_s) and (self.stop_s == 0 or self.stop_s > self.start_s)):
            raise ConfigError("stop_s", f"must be 0 (the end) or a time > `start_s` ({self.start_s} s), "
                                        f"got {self.stop_s!r}")
        if self.parameter not in PARAMETERS:
            raise ConfigError("parameter", f"must be one of {', '.join(PARAMETERS)}, got {self.parameter!r}")
        _, grid, step, (lo, hi), _, unit = PARAMETERS[self.parameter]
        if not self.coarse:
            object.__setattr__(self, "coarse", grid)
        if self.fine_step < 0:
            object.__setattr__(self, "fine_step", step)
        if self.fine_half_width == 0:
            object.__setattr__(self, "fine_half_width", 5 * self.fine_step)
        if len(self.coarse) < 2 or not all(isinstance(e, (int, float)) and lo < e <= hi for e in self.coarse):
            raise ConfigError("coarse", f"must hold 2+ {self.parameter} values in ({lo:g}, {hi:g}] {unit}, "
                                  f"got {list(self.coarse)!r}")
        if not (math.isfinite(self.fine_step) and 0 <= self.fine_step < (hi - lo) / 2
                and 0 <= self.fine_half_width < (hi - lo) / 2):
            raise ConfigError("fine_step", f"must lie in [0, {(hi - lo) / 2:g}) {unit}, got {self.fine_step!r}")
        if self.engine not in ("", "mujoco", "reference"):
            raise ConfigError("engine", f"must be mujoco or reference, got {self.engine!r}")
        if not (math.isfinite(self.lowpass_hz) and self.lowpass_hz >= 0):
            raise ConfigError("lowpass_hz", f"must be a frequency >= 0 Hz (0 = full band), got {self.lowpass_hz!r}")
        if not (math.isfinite(self.max_lag_s) and 0 <= self.max_lag_s <= 0.5):
            raise ConfigError("max_lag_s", f"must lie in [0, 0.5] s, got {self.max_lag_s!r}")


@dataclass
class SweepResult:
    """Outcome of a sweep: the best value, every candidate's mismatch, and what was compared."""

    value: float
    mismatch_mps2: float
    candidates: list[tuple[float, float]]           # (e, RMS mismatch [m/s^2]) in evaluation order
    lag_s: float
    sensor: str
    window_s: tuple[float, float]
    engine: str
    recording: str
    rate_hz: float
    recorded_rms_mps2: float
    seconds: float
    simulations: int
    notes: list[str] = field(default_factory=list)
    parameter: str = "restitution"

    @property
    def restitution(self) -> float | None:
        """The restitution found (a restitution sweep), else None."""
        return self.value if self.parameter == "restitution" else None

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d[self.parameter] = self.value
        d["candidates"] = [{self.parameter: e, "rms_mismatch_mps2": m} for e, m in sorted(self.candidates)]
        return d


# ------------------------------------------------------------------------ recording
def recorded_acceleration(path: str | Path, sensor: str = "AC6") -> tuple[np.ndarray, BenchConfig, float]:
    """Calibrated acceleration of ``sensor`` in a bench recording [m/s²], the recording's
    configuration and its sample rate [Hz]."""
    from twin.instrument.calibration import measured_accel
    from twin.recording import read_recording

    rec, info, _ = read_recording(path)
    if f"volt_{sensor}" not in rec:
        raise RecordingError(f"{path}: no channel volt_{sensor}")
    meas = measured_accel(rec, info.calibration)
    return np.asarray(meas[f"meas_{sensor}"], dtype=np.float64), rec.config, rec.rate_hz


def _candidate_config(cfg: BenchConfig, e: float, n: int, rate_hz: float, engine: str,
                      parameter: str = "restitution") -> BenchConfig:
    ov: dict[str, Any] = {PARAMETERS[parameter][0]: float(e), "simulation.duration_s": n / rate_hz,
                          "sensors.output_rate_hz": float(rate_hz), "sensors.channels": ["accel", "encoder"],
                          "instrumentation.noise": False}
    if engine:
        ov["simulation.engine"] = engine
    return cfg.replace(**ov)


def simulated_acceleration(cfg: BenchConfig, e: float, n: int, rate_hz: float, sensor: str = "AC6",
                           engine: str = "", parameter: str = "restitution") -> np.ndarray:
    """The twin's calibrated ``sensor`` acceleration [m/s²] (sensor chain without noise, simulated
    static calibration) for restitution ``e``: ``n`` samples at ``rate_hz``."""
    from twin.instrument import apply_chain, measured_accel, simulated_calibration
    from twin.simulation import simulate_run

    c = _candidate_config(cfg, e, n, rate_hz, engine, parameter)
    sim = simulate_run(c)
    daq = apply_chain(sim, c, command=False)
    meas = measured_accel(daq, simulated_calibration(c))
    a = np.asarray(meas[f"meas_{sensor}"], dtype=np.float64)
    if a.size != n:
        raise RecordingError(f"internal: simulated {a.size} samples for a {n}-sample recording")
    return a


def zero_phase_lowpass(f_hz: float, rate_hz: float):
    """Zero-phase 4th-order Butterworth low-pass at ``f_hz`` (None for 0 or at/above Nyquist)."""
    if not f_hz or f_hz >= 0.5 * rate_hz:
        return None
    from scipy.signal import butter, sosfiltfilt

    sos = butter(4, f_hz, fs=rate_hz, output="sos")
    return lambda x: sosfiltfilt(sos, np.asarray(x, dtype=np.float64))


def rms_mismatch(rec: np.ndarray, sim: np.ndarray, i0: int, i1: int, lag: int = 0) -> float:
    """RMS of rec[i + lag] − sim[i] over i in [i0, i1) (clipped to the overlap) [m/s²]."""
    j0, j1 = max(i0, -lag, 0), min(i1, rec.size - lag, sim.size)
    d = rec[j0 + lag:j1 + lag] - sim[j0:j1]
    return float(np.sqrt(np.mean(d * d)))


def sweep_restitution(path: str | Path, opts: SweepOptions = SweepOptions(), progress=None) -> SweepResult:
    """Sweep the restitution until the simulated ``opts.sensor`` matches the recording (module doc)."""
    wall0 = time.perf_counter()
    rec, cfg, rate = recorded_acceleration(path, opts.sensor)
    key, _, _, (lo, hi), law, _ = PARAMETERS[opts.parameter]
    law_ok = cfg.contact.law == law if law == "adams-impact" else cfg.contact.law not in ("linear", "adams-impact")
    if not law_ok or not cfg.joints.clearance_joints:
        want = "the adams-impact law" if law == "adams-impact" else "a hysteresis law (restitution sets its damping)"
        raise ConfigError("contact.law", f"a {opts.parameter} sweep needs a clearance joint and {want} in the "
                                         f"recording's configuration; got law {cfg.contact.law!r}, clearance joints "
                                         f"{list(cfg.joints.clearance_joints) or 'none'} (the recording's configuration "
                                         "is set when it is imported)")
    n = rec.size
    i0 = int(round(opts.start_s * rate))
    if opts.stop_s > n / rate + 1e-9:
        raise ConfigError("stop_s", f"{opts.stop_s:g} s lies beyond the recording's end ({n / rate:.3f} s)")
    if opts.start_s >= n / rate:
        raise ConfigError("start_s", f"{opts.start_s:g} s lies at or beyond the recording's end ({n / rate:.3f} s)")
    i1 = n if opts.stop_s == 0 else min(n, int(round(opts.stop_s * rate)))
    if i1 - i0 < 10:
        raise ConfigError("start_s", f"the window holds {max(i1 - i0, 0)} samples of the {n / rate:.3f} s recording; "
                                     "it needs at least 10")
    engine = opts.engine or cfg.simulation.engine
    # each candidate's run is reduced at once to its two mismatches (full band, low-passed): no
    # run is kept, so memory does not grow with the number of candidates
    cache: dict[float, float] = {}
    cache_lp: dict[float, float] = {}
    notes: list[str] = []
    lag = 0
    # coarse to fine: the slider's impact spikes last about one 5 kHz sample, so the sampled
    # spikes (and the full-band mismatch) change at random with sub-sample shifts of an impact:
    # over the full band the mismatch is a needle at the answer among spurious dips. Low-passed
    # (``lowpass_hz``) the minimum is wider, still rugged. The coarse grid and the first fine grid are
    # scored low-passed, the finest grid (fine_step/5 over ±2 fine_step) over the full band.
    lp = zero_phase_lowpass(opts.lowpass_hz, rate)
    rec_lp = lp(rec) if lp else rec

    def evaluate(e: float) -> float:
        e = round(float(e), 6)
        if e not in cache:
            sim = simulated_acceleration(cfg, e, n, rate, opts.sensor, engine, opts.parameter)
            cache[e] = rms_mismatch(rec, sim, i0, i1, lag)
            cache_lp[e] = rms_mismatch(rec_lp, lp(sim), i0, i1, lag) if lp else cache[e]
            if progress:
                progress(e, cache[e])
        return cache[e]

    coarse = sorted(set(float(e) for e in opts.coarse))
    if opts.max_lag_s > 0:  # one shift for every candidate, from the motion (low-passed) of the middle one
        from twin.signals import estimate_lag

        mid = coarse[len(coarse) // 2]
        sim_mid = simulated_acceleration(cfg, mid, n, rate, opts.sensor, engine, opts.parameter)
        est = estimate_lag([rec[i0:i1]], [sim_mid[i0:i1]], int(round(opts.max_lag_s * rate)), rate,
                           lowpass_hz=min(50.0, 0.2 * rate))
        lag = int(est.lag)
        notes.append(f"time shift {lag / rate * 1e3:+.1f} ms (recording late), from e = {mid:g}")

    def score(e: float, low: bool) -> float:
        key = round(float(e), 6)
        evaluate(key)
        return cache_lp[key] if low else cache[key]

    def band(low: bool) -> str:
        return f"low-passed at {opts.lowpass_hz:g} Hz" if low and lp else "full band"

    scores = {e: score(e, True) for e in coarse}
    # the coarse grid's local minima, best first: each is refined on its own (opts.starts)
    minima = [e for i, e in enumerate(coarse) if (i == 0 or scores[e] <= scores[coarse[i - 1]])
              and (i == len(coarse) - 1 or scores[e] <= scores[coarse[i + 1]])]
    seeds = sorted(minima, key=scores.get)[:opts.starts] if opts.fine_step > 0 else [min(scores, key=scores.get)]
    notes.append(f"{len(coarse)} values {min(coarse):g}-{max(coarse):g}, {band(True)}: best {opts.parameter} = "
                 f"{seeds[0]:g} ({scores[seeds[0]]:.2f} m/s^2); refined from "
                 + ", ".join(f"{e:g} ({scores[e]:.2f})" for e in seeds))
    finals: dict[float, float] = {}
    for seed in seeds:
        best = seed
        for step, low in ([(opts.fine_step, True), (opts.fine_step / 5, False)] if opts.fine_step > 0 else []):
            half = opts.fine_half_width if step == opts.fine_step else 2 * opts.fine_step
            k = int(round(half / step))
            grid = [round(best + i * step, 6) for i in range(-k, k + 1) if lo < round(best + i * step, 6) <= hi]
            st = {e: score(e, low) for e in grid}
            best = min(st, key=st.get)
            notes.append(f"  from {seed:g}: {len(grid)} values {min(grid):g}-{max(grid):g}, {band(low)}: best "
                         f"{opts.parameter} = {best:g} ({st[best]:.2f} m/s^2)")
        finals[best] = cache[round(float(best), 6)]
    best = min(finals, key=finals.get)  # over the full band
    if len(finals) > 1:
        notes.append(f"answer: {best:g}, the smallest full-band mismatch of " + ", ".join(
            f"{e:g} ({m:.2f})" for e, m in finals.items()))
    e_hat, m_hat = float(best), cache[round(float(best), 6)]
    xs = sorted(cache)
    i = xs.index(round(float(best), 6))
    if i in (0, len(xs) - 1):
        notes.append(f"best value {best:g} at the edge of the grid: the answer may lie outside it")
    return SweepResult(value=float(e_hat), mismatch_mps2=float(m_hat), candidates=list(cache.items()),
                       lag_s=lag / rate, sensor=opts.sensor, window_s=(i0 / rate, i1 / rate), engine=engine,
                       recording=str(path), rate_hz=float(rate), recorded_rms_mps2=float(np.sqrt(np.mean(rec[i0:i1] ** 2))),
                       seconds=time.perf_counter() - wall0, simulations=len(cache) + (1 if opts.max_lag_s > 0 else 0),
                       notes=notes, parameter=opts.parameter)


# ------------------------------------------------------------------------ synthetic
def write_synthetic_recording(cfg: BenchConfig, path: str | Path, value: float, noise_mps2: float = 5.0,
                              seed: int = 0, sensor: str = "AC6", parameter: str = "restitution") -> Path:
    """Write a synthetic bench recording of ``cfg`` at a known ``parameter`` value (restitution, or the
    IMPACT law's c_max): the twin's run (engine of ``cfg``), white Gaussian noise of ``noise_mps2`` RMS
    [m/s²] added to ``sensor``'s truth, then the sensor chain of ``cfg.instrumentation`` (its own
    datasheet noise too, seed ``seed``) and the simulated static calibration
    (:func:`twin.recording.synthetic_recording`)."""
    from twin.recording import synthetic_recording as make, write_recording
    from twin.run import Channel
    from twin.simulation import simulate_run

    c = cfg.replace(**{PARAMETERS[parameter][0]: float(value), "instrumentation.seed": int(seed),
                       "sensors.output_rate_hz": cfg.instrumentation.daq_rate_hz})
    truth = simulate_run(c)
    rng = np.random.default_rng(seed)
    a = np.asarray(truth[sensor], dtype=np.float64) + rng.normal(0.0, noise_mps2, truth.n)
    ch = truth.channels[sensor]
    truth = truth.with_channels([Channel(sensor, ch.unit, ch.group, a.astype(ch.data.dtype))])
    daq, info = make(truth, c, notes=f"synthetic: {parameter} {value:g}, {noise_mps2:g} m/s^2 RMS white "
                                     f"noise on {sensor}, engine {c.simulation.engine}",
                     extra={parameter: float(value), "noise_mps2": float(noise_mps2), "sensor": sensor},
                     created_by="twin.identification.restitution")
    return write_recording(path, daq, info)
