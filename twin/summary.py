"""Run summaries: the numbers ``twin simulate --summary-json`` reports, for either engine.

Definitions (identical for both engines, so summaries compare line by line):

* ``max_eccentricity_m``: max |e| over the run.
* ``max_penetration_m``: max of ``pen_J`` = max(0, |e| − c).
* ``impacts``: number of contact onsets: rising edges of the contact indicator
  (``fn_J > 0``) that follow at least ``min_free_s`` of separation. Re-contacts after
  shorter separations belong to the same impact event (chatter).
* ``max_contact_force_N``: max of ``fn_J``.
* ``rms_mps2`` / ``peak_mps2`` per accelerometer (and of ``slider_acceleration``, spatial runs): RMS and max |a| of the proper
  acceleration over the run (gravity included, as the sensor reads it).
* ``drive_train`` (runs with the channel group ``motor``): the motor's RMS and peak torque
  [N m], its continuous rating and whether the RMS exceeds it (the drive's thermal limit is not
  modelled: this flags runs the real motor would not sustain), the fraction of samples at the
  peak clamp, the peak belt torque on the crank [N m] and the peak belt slip speed [m/s].
* ``guide`` (runs with a guide clearance and the channel group ``joints``): the play [mm], the
  slider's max |y_g| [m] and |tilt| [rad], the max rail force at its front and rear ends [N] and
  the contact onsets of each end (either rail; defined as ``impacts``).
* ``structure`` (``structure.mode = "flexible"``): the rod's modes in the mechanism (B pinned, C on the
  guide with the slider's mass; the shared discrete model, :func:`twin.structure.modes`): the first bending and
  the first axial frequency [Hz]; with the channel group ``structure`` also the max |rod_deflection| and
  |rod_stretch| [m] and the supports' max displacement [m].
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from twin.config import ACCELEROMETERS, JOINTS, BenchConfig
from twin.run import Run

#: Minimum separation before a contact onset counts as a new impact [s].
MIN_FREE_S = 1e-4


def contact_onsets(in_contact: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(sample index of every contact onset, samples of separation before it).

    An onset is the first sample of a rising edge of ``in_contact``; an onset with no
    separation before it in the record (the record starts free) gets the largest int64.
    """
    c = np.asarray(in_contact, dtype=bool)
    idx = np.flatnonzero(np.diff(c.astype(np.int8))) + 1  # first sample after each transition
    onsets = idx[c[idx]]                                  # off -> on
    offsets = idx[~c[idx]]                                # on -> off (first free sample)
    prev = np.searchsorted(offsets, onsets) - 1           # last offset before each onset
    free = np.full(onsets.shape, np.iinfo(np.int64).max)  # no offset before: free since the start
    has_prev = prev >= 0
    free[has_prev] = onsets[has_prev] - offsets[prev[has_prev]]
    return onsets, free


def count_impacts(in_contact: np.ndarray, rate_hz: float, min_free_s: float = MIN_FREE_S) -> int:
    """Contact onsets preceded by at least ``min_free_s`` of separation.

    The run start counts as separated: a run starting in contact has no impact at t = 0.
    """
    if np.size(in_contact) == 0:
        return 0
    min_free = max(1, int(round(min_free_s * rate_hz)))
    _, free = contact_onsets(in_contact)
    return int(np.count_nonzero(free >= min_free))



def _sum_sq(x: np.ndarray) -> float:
    """Σ x² of a float array, in float64, by NumPy's own (pairwise) summation: not ``np.dot``, whose BLAS splits
    the sum by the thread count, so that a summary's last bits would follow the machine's threads."""
    x = np.asarray(x, dtype=np.float64)
    return float(np.sum(x * x))

class ImpactCounter:
    """:func:`count_impacts` over a stream of chunks: same count as on the whole record.

    Keeps the contact state of the last sample seen and the global index of the last
    contact-to-free transition, so onsets and separations that straddle chunk boundaries count
    as on the whole record (the record start counts as separated; a record starting in contact
    has no impact at t = 0).
    """

    def __init__(self, rate_hz: float, min_free_s: float = MIN_FREE_S):
        self.min_free = max(1, int(round(min_free_s * rate_hz)))
        self.count = 0
        self._last: bool | None = None  # contact state of the last sample seen
        self._last_off: int | None = None  # global index of the first free sample after contact
        self._seen = 0

    def update(self, in_contact: np.ndarray) -> None:
        c = np.asarray(in_contact, dtype=bool)
        if c.size == 0:
            return
        if self._last is None:
            ext, base = c, self._seen
        else:
            ext, base = np.concatenate([[self._last], c]), self._seen - 1
        idx = np.flatnonzero(np.diff(ext.astype(np.int8))) + 1
        onsets = base + idx[ext[idx]]
        offsets = base + idx[~ext[idx]]
        offs = offsets if self._last_off is None else np.concatenate([[self._last_off], offsets])
        prev = np.searchsorted(offs, onsets) - 1
        has_prev = prev >= 0
        free_ok = np.ones(onsets.shape, dtype=bool)  # no offset before: free since the start
        free_ok[has_prev] = onsets[has_prev] - offs[prev[has_prev]] >= self.min_free
        self.count += int(np.count_nonzero(free_ok))
        if offs.size:
            self._last_off = int(offs[-1])
        self._last = bool(c[-1])
        self._seen += c.size


class SummaryAccumulator:
    """The run summary (module docstring), kept chunk by chunk in memory that does not grow with
    the run: maxima, sums of squares and the impact counters. ``result(meta)`` equals
    :func:`summarize` of the whole run up to the rounding of the sums."""

    def __init__(self, config: BenchConfig | None):
        self.config = config
        self.n = 0
        self.rate_hz: float | None = None
        self._joints: dict[str, dict[str, Any]] = {}
        self._impacts: dict[str, ImpactCounter] = {}
        self._acc: dict[str, list[float]] = {}  # name -> [sum of squares, peak |a|]
        self._track: list[float] | None = None  # [max |err|, sum err^2]
        self._motor: list[float] | None = None  # [sum u^2, max |u|, samples at the clamp, max |belt|, max |slip|]
        self._guide: list[float] | None = None  # [max |y|, max |tilt|, max |fn front|, max |fn rear|]
        self._guide_impacts: dict[str, ImpactCounter] = {}
        self._structure: dict[str, float] = {}  # channel -> max |x| (group "structure")

    def update(self, chunk: Run) -> None:
        if self.rate_hz is None:
            self.rate_hz = chunk.rate_hz
        if chunk.n == 0:
            return
        for j in JOINTS:
            if f"ecc_{j}_x" not in chunk:
                continue
            ex, ey, fn = chunk[f"ecc_{j}_x"], chunk[f"ecc_{j}_y"], chunk[f"fn_{j}"]
            st = self._joints.setdefault(j, {"max_eccentricity_m": 0.0, "max_penetration_m": 0.0,
                                             "max_contact_force_N": 0.0})
            ecc = np.hypot(ex, ey) if f"ecc_{j}_z" not in chunk else np.hypot(np.hypot(ex, ey), chunk[f"ecc_{j}_z"])
            st["max_eccentricity_m"] = max(st["max_eccentricity_m"], float(np.max(ecc)))
            st["max_penetration_m"] = max(st["max_penetration_m"], float(np.max(chunk[f"pen_{j}"])))
            st["max_contact_force_N"] = max(st["max_contact_force_N"], float(np.max(fn)))
            self._impacts.setdefault(j, ImpactCounter(chunk.rate_hz)).update(fn > 0)
        if "fn_guide_front" in chunk:
            gd = self._guide if self._guide is not None else [0.0, 0.0, 0.0, 0.0]
            for i, name in enumerate(("slider_y", "slider_tilt", "fn_guide_front", "fn_guide_rear")):
                gd[i] = max(gd[i], float(np.max(np.abs(chunk[name]))))
            for end in ("front", "rear"):
                self._guide_impacts.setdefault(end, ImpactCounter(chunk.rate_hz)).update(
                    chunk[f"fn_guide_{end}"] != 0)
            self._guide = gd
        for a in ACCELEROMETERS + ("slider_acceleration",):
            if a in chunk:
                x = chunk[a].astype(np.float64)
                acc = self._acc.setdefault(a, [0.0, 0.0])
                acc[0] += _sum_sq(x)
                acc[1] = max(acc[1], float(np.max(np.abs(x))))
        if "crank_angle" in chunk and "theta_ref" in chunk and not (self.config and self.config.drive.mode == "torque"):
            err = chunk["theta_ref"] - chunk["crank_angle"]
            tr = self._track if self._track is not None else [0.0, 0.0]
            tr[0] = max(tr[0], float(np.max(np.abs(err))))
            tr[1] += _sum_sq(err)
            self._track = tr
        for name in ("rod_deflection", "rod_stretch", "frame_x", "frame_y", "guide_y"):
            if name in chunk:
                self._structure[name] = max(self._structure.get(name, 0.0), float(np.max(np.abs(chunk[name]))))
        if "motor_torque" in chunk:
            u = chunk["motor_torque"].astype(np.float64)
            mo = self._motor if self._motor is not None else [0.0, 0.0, 0.0, 0.0, 0.0]
            peak = self.config.drivetrain.peak_torque_nm if self.config else np.inf
            mo[0] += _sum_sq(u)
            mo[1] = max(mo[1], float(np.max(np.abs(u))))
            mo[2] += float(np.count_nonzero(np.abs(u) >= peak * (1 - 1e-6)))  # float32 channel
            mo[3] = max(mo[3], float(np.max(np.abs(chunk["belt_torque"]))))
            mo[4] = max(mo[4], float(np.max(np.abs(chunk["belt_slip"]))))
            self._motor = mo
        self.n += chunk.n

    def result(self, meta: dict[str, Any] | None = None) -> dict[str, Any]:
        """Summary dict (keys documented in the module docstring and README)."""
        meta = meta or {}
        cfg, n, rate = self.config, self.n, self.rate_hz or 0.0
        out: dict[str, Any] = {
            "name": cfg.name if cfg else None,
            "engine": meta.get("engine"),
            "duration_s": n / rate if rate else 0.0,
            "timestep_s": meta.get("timestep_s"),
            "steps": meta.get("steps"),
            "wall_s": meta.get("wall_s"),
            "real_time_factor": meta.get("real_time_factor"),
            "sample_rate_hz": rate,
            "samples": n,
        }
        for j in JOINTS:
            if j == "A" and j not in self._joints and not (cfg and cfg.joints.diametral_mm("A") > 0):
                continue  # the ground pivot is a ball bearing unless configured otherwise: no entry
            js: dict[str, Any] = {"clearance_mm": cfg.joints.diametral_mm(j) if cfg else None}
            if j in self._joints:
                st = self._joints[j]
                js.update(max_eccentricity_m=st["max_eccentricity_m"], max_penetration_m=st["max_penetration_m"],
                          impacts=self._impacts[j].count, max_contact_force_N=st["max_contact_force_N"])
            out[j] = js
        if self._guide is not None:
            out["guide"] = {"clearance_mm": cfg.joints.clearance_guide_mm if cfg else None,
                            "max_transverse_m": self._guide[0], "max_tilt_rad": self._guide[1],
                            "max_force_front_N": self._guide[2], "max_force_rear_N": self._guide[3],
                            "impacts_front": self._guide_impacts["front"].count,
                            "impacts_rear": self._guide_impacts["rear"].count}
        for a in ACCELEROMETERS + ("slider_acceleration",):
            if a in self._acc:
                ss, peak = self._acc[a]
                out[a] = {"rms_mps2": float(np.sqrt(ss / n)) if n else 0.0, "peak_mps2": peak}
        if self._track is not None and n:
            out["tracking"] = {"max_abs_error_rad": self._track[0], "rms_error_rad": float(np.sqrt(self._track[1] / n))}
        if self._motor is not None and n:
            rms = float(np.sqrt(self._motor[0] / n))
            cont = cfg.drivetrain.continuous_torque_nm if cfg else None
            out["drive_train"] = {"motor_rms_torque_Nm": rms, "motor_peak_torque_Nm": self._motor[1],
                                  "continuous_torque_Nm": cont,
                                  "rms_exceeds_continuous": bool(cont is not None and rms > cont),
                                  "fraction_at_peak_clamp": self._motor[2] / n,
                                  "max_belt_torque_Nm": self._motor[3], "max_belt_slip_mps": self._motor[4]}
        if cfg is not None and cfg.structure.flexible:
            out["structure"] = _structure_summary(cfg, self._structure)
        return out


def _structure_summary(cfg: BenchConfig, maxima: dict[str, float]) -> dict[str, Any]:
    from twin.structure import modes, rod_chain

    md = modes(rod_chain(cfg.structure, cfg.bodies.rod, cfg.bodies.slider.mass_kg), "mechanism",
               cfg.bodies.slider.mass_kg)
    out: dict[str, Any] = {"mode": cfg.structure.mode,
                           "first_bending_hz": float(md.of_kind("bending")[0]),
                           "first_axial_hz": float(md.of_kind("axial")[0])}
    if maxima:
        out.update(max_rod_deflection_m=maxima.get("rod_deflection"), max_rod_stretch_m=maxima.get("rod_stretch"),
                   max_frame_displacement_m=max(maxima.get("frame_x", 0.0), maxima.get("frame_y", 0.0)),
                   max_guide_displacement_m=maxima.get("guide_y"))
    return out


def summarize(run: Run) -> dict[str, Any]:
    """Summary dict of a whole run (the same numbers :class:`SummaryAccumulator` keeps while a
    run streams)."""
    acc = SummaryAccumulator(run.config)
    acc.rate_hz = run.rate_hz
    acc.update(run)
    return acc.result(run.meta)


class SummaryJsonWriter:
    """Sink that writes the run's summary as JSON when the run closes (atomically); nothing on
    abort. Check the path before the run (:func:`twin.util.check_output_file`)."""

    def __init__(self, path: str | Path):
        self.path = Path(path)

    def write(self, chunk: Run) -> None:  # noqa: ARG002 - the summary is kept by simulate()
        pass

    def close(self, meta: dict[str, Any], summary: dict[str, Any]) -> Path:  # noqa: ARG002
        from twin.util import atomic_write_json

        return atomic_write_json(self.path, summary)

    def abort(self) -> None:
        pass
