"""Run summaries: the numbers ``twin simulate --summary-json`` reports, for either engine.

Definitions (identical for both engines, so summaries compare line by line):

* ``max_eccentricity_m``: max |e| over the run.
* ``max_penetration_m``: max of ``pen_J`` = max(0, |e| − c).
* ``impacts``: number of contact onsets: rising edges of the contact indicator
  (``fn_J > 0``) that follow at least ``min_free_s`` of separation. Re-contacts after
  shorter separations belong to the same impact event (chatter).
* ``max_contact_force_N``: max of ``fn_J``.
* ``rms_mps2`` / ``peak_mps2`` per accelerometer: RMS and max |a| of the proper
  acceleration over the run (gravity included, as the sensor reads it).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from twin.config import ACCELEROMETERS, JOINTS
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


def joint_summary(run: Run, joint: str) -> dict[str, Any]:
    """Summary numbers of one clearance joint (see module docstring)."""
    cfg = run.config
    out: dict[str, Any] = {"clearance_mm": cfg.joints.diametral_mm(joint) if cfg else None}
    if f"ecc_{joint}_x" not in run:
        return out
    ex, ey = run[f"ecc_{joint}_x"], run[f"ecc_{joint}_y"]
    fn = run[f"fn_{joint}"]
    out.update(
        max_eccentricity_m=float(np.max(np.hypot(ex, ey))) if run.n else 0.0,
        max_penetration_m=float(np.max(run[f"pen_{joint}"])) if run.n else 0.0,
        impacts=count_impacts(fn > 0, run.rate_hz),
        max_contact_force_N=float(np.max(fn)) if run.n else 0.0,
    )
    return out


def summarize(run: Run) -> dict[str, Any]:
    """Summary dict of a run (keys documented in the module docstring and README)."""
    meta = run.meta
    out: dict[str, Any] = {
        "name": run.config.name if run.config else None,
        "engine": meta.get("engine"),
        "duration_s": run.n / run.rate_hz,
        "timestep_s": meta.get("timestep_s"),
        "steps": meta.get("steps"),
        "wall_s": meta.get("wall_s"),
        "real_time_factor": meta.get("real_time_factor"),
        "sample_rate_hz": run.rate_hz,
        "samples": run.n,
    }
    for j in JOINTS:
        out[j] = joint_summary(run, j)
    for a in ACCELEROMETERS:
        if a in run:
            x = run[a].astype(np.float64)
            out[a] = {"rms_mps2": float(np.sqrt(np.mean(x * x))) if run.n else 0.0,
                      "peak_mps2": float(np.max(np.abs(x))) if run.n else 0.0}
    if "crank_angle" in run and "theta_ref" in run and run.n:
        err = run["theta_ref"] - run["crank_angle"]
        out["tracking"] = {"max_abs_error_rad": float(np.max(np.abs(err))),
                           "rms_error_rad": float(np.sqrt(np.mean(err * err)))}
    return out
