"""Typed rows of a calibration's result (:class:`twin.calibration.CalibrationResult`): the pairs of fields the
recordings cannot tell apart and the wall time per evaluation, as frozen dataclasses whose ``to_dict()`` is the
JSON layout (:class:`twin.typed.Record`)."""

from __future__ import annotations

from dataclasses import dataclass

from twin.typed import Record

__all__ = ["CorrelatedPair", "EvaluationTimes"]


@dataclass(frozen=True)
class CorrelatedPair(Record):
    """Two fitted fields whose estimates are strongly correlated (:func:`twin.calibration.uncertainty.analyse`).

    Attributes:
        a, b: the fields (dotted paths); correlation: the correlation of their estimates [-].
    """

    a: str
    b: str
    correlation: float


@dataclass(frozen=True)
class EvaluationTimes(Record):
    """Mean wall time of an evaluation per stage [s] (NaN where the stage ran none).

    Attributes:
        short: the short stage's; full: the full-length stage's [s].
    """

    short: float
    full: float
