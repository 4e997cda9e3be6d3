"""A tap on the reference engine's flexible rod, either rod: the chain's
(:func:`twin.reference.flexible.chain_tap_response`) or the modal rod's
(:func:`twin.reference.flexible_modal_run.modal_tap_response`). Its own module so that the chain's module need not
import the modal rod's runner, which builds on it."""

from __future__ import annotations

import numpy as np


def tap_response(cfg, speed_mps: float = 0.01, duration_s: float = 0.2, every: int = 5, theta0: float = 0.3,
                 drive: bool = False, axial: bool = False, rod_model: str = "chain") -> tuple[np.ndarray, np.ndarray]:
    """The mechanism at rest at crank angle ``theta0`` [rad], the rod's middle tapped at ``speed_mps`` [m/s]
    (``axial``: the bore C along the chord); returns (t [s], the response [m]) every ``every`` steps for
    ``duration_s`` [s] (details: :func:`twin.reference.flexible.chain_tap_response`). ``rod_model``: "chain" or
    "modal"."""
    if rod_model == "modal":
        from twin.reference.flexible_modal_run import modal_tap_response

        return modal_tap_response(cfg, speed_mps, duration_s, every, theta0, drive, axial)
    if rod_model != "chain":
        raise ValueError(f"rod_model must be 'chain' or 'modal', got {rod_model!r}")
    from twin.reference.flexible import chain_tap_response

    return chain_tap_response(cfg, speed_mps, duration_s, every, theta0, drive, axial)
