"""The crank's direction of rotation: measured on a recording's encoder, checked against the training runs'.

The window features read the crank rate as a magnitude (:mod:`twin.identification.features`), so a model cannot
tell a crank turned backwards from one turned forwards: the impacts' pattern in the crank-angle domain differs
(the rod's load reverses through the joints at other crank angles) and the sizes read off it are answers for a
mechanism the trees never saw. Directions:

* ``forward``: the encoder counts increase over the steady windows (a positive motor speed ``drive.motor_rpm``
  or crank speed; the sample recordings);
* ``reverse``: they decrease (a negative speed).

Where the training runs turned: a model trained since the direction was measured stores the directions of its
runs in ``trained_on.ranges.rotations`` (:func:`training_rotations`, beside the other ranges of
:func:`twin.identification.ranges.training_ranges`: one more key of the JSON, no change of the file format). A
model without that key is read as trained forward only (:data:`ASSUMED_TRAINED`): every training set of the
shipped models (``analysis/datasets/clearance_id_*.toml``) draws constant motor speeds of +250 to +800 rpm. A
recording turning another way than every training run is outside the training data
(:func:`twin.identification.ranges.out_of_range`): a warning, and the intervals widened to every clearance trained.
"""

from __future__ import annotations

from typing import Any

import numpy as np

FORWARD = "forward"
REVERSE = "reverse"
ROTATIONS = (FORWARD, REVERSE)
#: the directions a model without ``ranges.rotations`` is read as trained on (module docstring)
ASSUMED_TRAINED = (FORWARD,)


def rotation(counts: np.ndarray, start: int, stop: int) -> str:
    """The crank's direction over samples [start, stop) of the encoder ``counts``: :data:`FORWARD` where the
    counts increase, :data:`REVERSE` where they decrease (a span that does not move reads forward: the steady
    windows it is measured on turn through whole turns)."""
    c = np.asarray(counts)
    if stop - start < 2:
        return FORWARD
    return REVERSE if float(c[stop - 1]) < float(c[start]) else FORWARD


def training_rotations(measures: list[dict[str, Any]]) -> dict[str, Any]:
    """``{"rotations": [...]}``: the directions of the training runs' ``measures``
    (:func:`twin.identification.ranges.recording_measures`), for the model's training ranges; empty where a run's
    measures lack the direction (features computed before it was measured): nothing is claimed then."""
    seen = [m.get("rotation") for m in measures]
    if not seen or any(r not in ROTATIONS for r in seen):
        return {}
    return {"rotations": sorted(set(seen))}


def trained_rotations(ranges: dict[str, Any] | None) -> tuple[tuple[str, ...], bool]:
    """The directions the model's training runs turned (``ranges``: ``trained_on["ranges"]``) and whether the model
    stores them (False: :data:`ASSUMED_TRAINED`, module docstring)."""
    stored = (ranges or {}).get("rotations")
    if isinstance(stored, list) and stored and all(r in ROTATIONS for r in stored):
        return tuple(stored), True
    return ASSUMED_TRAINED, False


def rotation_warning(measured: str | None, ranges: dict[str, Any] | None) -> str | None:
    """The warning for a recording turning ``measured`` (None: not measured, no warning) where no training run
    turned that way; None where some did."""
    if measured is None:
        return None
    trained, stored = trained_rotations(ranges)
    if measured in trained:
        return None
    how = "" if stored else " (read as such: the model stores no direction, and the training sets of the shipped " \
                            "models all turn forwards)"
    way = "backwards (the encoder counts decrease)" if measured == REVERSE else "forwards (the encoder counts increase)"
    return (f"the crank turns {way}, the model was trained on runs turning {' and '.join(trained)} only{how}: "
            "the answer is an extrapolation")
