"""The answer of the clearance identification as typed, frozen values: :class:`IdentifyResult` with one
:class:`JointAnswer` per clearance location, its :class:`Evidence` and, per joint, the :class:`HeldOut` accuracy.

``to_dict()`` gives the answer as the plain dict ``twin identify clearance --json`` writes (the key layout of the
JSON file, ``clearance_b_mm``, ``clearance_b_interval_mm``, ...: built here and nowhere else); ``to_json()`` the
text of that file; ``IdentifyResult.from_dict`` reads such a dict back. The joints are a tuple in the order of the
mechanism's clearance locations, so that a further location adds one :class:`JointAnswer` and its keys.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from typing import Any, Mapping

__all__ = ["Evidence", "HeldOut", "IdentifyResult", "JointAnswer"]


def _key(joint: str) -> str:
    """The prefix of a joint's keys in the answer's dict: ``clearance_b`` for "B"."""
    return f"clearance_{joint.lower()}"


@dataclass(frozen=True)
class HeldOut:
    """How often the model's sizes held in training runs left out, at a recording's speed and orientation
    (:func:`twin.identification.intervals.held_out_at`).

    Attributes:
        within_factor: the factor of the truth an answer had to lie within [-].
        share: the share of the held-out answers within it, interpolated at the recording's crank rate [-].
        runs: the training runs behind the share.
        training_crank_hz: the crank rates of the training speeds used (one or two) [Hz].
    """

    within_factor: float
    share: float
    runs: int
    training_crank_hz: tuple[float, ...]

    def to_dict(self) -> dict[str, Any]:
        return {"within_factor": self.within_factor, "share": self.share, "runs": self.runs,
                "training_crank_hz": list(self.training_crank_hz)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> "HeldOut | None":
        """The value of a dict as :meth:`to_dict` writes it; None for None."""
        if d is None:
            return None
        return cls(d["within_factor"], d["share"], d["runs"], tuple(d["training_crank_hz"]))


@dataclass(frozen=True)
class JointAnswer:
    """The answer at one clearance location.

    Attributes:
        joint: the location's name ("B", "C", or "G": the slider guide, whose size is its two-sided play).
        faulty: whether the location answer (the most probable class) names this joint.
        size_if_faulty_mm: the size the regressor reads, the median over the windows [mm] (diametral clearance),
            whether or not the joint is located faulty.
        interval_if_faulty_mm: its 90 % interval (lo, hi) [mm], widened where the recording is outside the
            training data.
        size_resolved: whether the bench's sensors resolve the size at this joint at the recording's speed and
            orientation (:func:`twin.identification.intervals.size_resolved`); None where not checked.
        size_held_out: the held-out accuracy at this joint, speed and orientation; None where the model holds no
            such table.
    """

    joint: str
    faulty: bool
    size_if_faulty_mm: float
    interval_if_faulty_mm: tuple[float, float]
    size_resolved: bool | None = None
    size_held_out: HeldOut | None = None

    @property
    def size_mm(self) -> float:
        """The reported size [mm]: :attr:`size_if_faulty_mm` where the joint is located faulty, else 0 (a ball
        bearing)."""
        return self.size_if_faulty_mm if self.faulty else 0.0

    @property
    def interval_mm(self) -> tuple[float, float]:
        """The reported 90 % interval [mm]: :attr:`interval_if_faulty_mm` where located faulty, else (0, 0)."""
        return tuple(self.interval_if_faulty_mm) if self.faulty else (0.0, 0.0)


@dataclass(frozen=True)
class Evidence:
    """What an answer was made from.

    Attributes:
        windows: windows of steady running answered.
        revolutions: crank revolutions in them.
        crank_hz: the recording's crank rate [Hz].
        motor_rpm_if_belt_3_97: the motor speed at the bench's belt ratio [rpm].
        steady_s: the steady part's length [s].
        features: features per window.
        feature_version: the feature definition's version.
        training_data_check: the checks against the training data (:func:`twin.identification.model.training_check`).
        model: what the model was trained on (dataset, identity digest, engine, crank rate range [Hz]).
    """

    windows: int
    revolutions: float
    crank_hz: float
    motor_rpm_if_belt_3_97: float
    steady_s: float
    features: int
    feature_version: str
    training_data_check: Mapping[str, Any]
    model: Mapping[str, Any]

    def to_dict(self) -> dict[str, Any]:
        return {"windows": self.windows, "revolutions": self.revolutions, "crank_hz": self.crank_hz,
                "motor_rpm_if_belt_3_97": self.motor_rpm_if_belt_3_97, "steady_s": self.steady_s,
                "features": self.features, "feature_version": self.feature_version,
                "training_data_check": dict(self.training_data_check), "model": dict(self.model)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> "Evidence | None":
        if d is None:
            return None
        return cls(**{k: d[k] for k in cls.__dataclass_fields__})


@dataclass(frozen=True)
class IdentifyResult:
    """The clearance identification of one recording (``twin.identify``, ``twin identify clearance``).

    Attributes:
        fault: the located fault, the most probable class: "none", or the locations with play among B, C and the
            slider guide G ("B", "C", "BC", "G", "BG", "CG", "BCG"; a model trained without guide play: no G).
        probabilities: class -> probability, the mean over the windows [-].
        joints: one :class:`JointAnswer` per clearance location, in the mechanism's order.
        recording: the recording answered ("" for inputs not read from a file).
        warnings: one line per reason to doubt the answer (outside the training data, size not resolved).
        evidence: what the answer was made from; None for a bare model answer
            (:meth:`twin.identification.model.ClearanceModel.identify`).
        seconds: wall time of the answer [s]; None for a bare model answer.
    """

    fault: str
    probabilities: Mapping[str, float]
    joints: tuple[JointAnswer, ...]
    recording: str = ""
    warnings: tuple[str, ...] = ()
    evidence: Evidence | None = None
    seconds: float | None = None

    def joint(self, name: str) -> JointAnswer:
        """The answer at the location ``name`` ("B", "C", "G"); KeyError naming the locations there are."""
        for j in self.joints:
            if j.joint == name:
                return j
        have = ", ".join(j.joint for j in self.joints)
        raise KeyError(f"{name!r}: no such clearance location; the answer has {have}")

    def to_dict(self) -> dict[str, Any]:
        """The answer as the plain dict of the JSON file (keys in the file's order; ``refused`` false: a refused
        recording's file holds ``refused: true`` and the reason instead, ``twin identify clearance --json``)."""
        out: dict[str, Any] = {"refused": False, "fault": self.fault, "probabilities": dict(self.probabilities)}
        for j in self.joints:
            k = _key(j.joint)
            out[f"{k}_mm"] = j.size_mm
            out[f"{k}_interval_mm"] = list(j.interval_mm)
            out[f"{k}_if_faulty_mm"] = {"median": j.size_if_faulty_mm, "interval_90": list(j.interval_if_faulty_mm)}
        for j in self.joints:
            k = _key(j.joint)
            out[f"{k}_size_resolved"] = None if j.size_resolved is None else bool(j.size_resolved)
            out[f"{k}_size_held_out"] = None if j.size_held_out is None else j.size_held_out.to_dict()
        out["recording"] = self.recording
        out["warnings"] = list(self.warnings)
        out["evidence"] = None if self.evidence is None else self.evidence.to_dict()
        out["seconds"] = self.seconds
        return out

    def to_json(self) -> str:
        """The text ``twin identify clearance --json`` writes (indented strict JSON, numpy values as floats)."""
        from twin.util import json_text

        return json_text(json.loads(json.dumps(self.to_dict(), default=float)))

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "IdentifyResult":
        """The answer of a dict as :meth:`to_dict` (or the JSON file) holds it; ValueError with its reason for a
        refused recording's record (``refused: true``)."""
        if d.get("refused"):
            raise ValueError(f"{d.get('recording', '')}: refused, no answer ({d.get('reason', '')})")
        names = [m.group(1).upper() for k in d if (m := re.fullmatch(r"clearance_(\w+?)_if_faulty_mm", k))]
        joints = tuple(JointAnswer(
            joint=j, faulty=j in d["fault"], size_if_faulty_mm=d[f"{_key(j)}_if_faulty_mm"]["median"],
            interval_if_faulty_mm=tuple(d[f"{_key(j)}_if_faulty_mm"]["interval_90"]),
            size_resolved=d.get(f"{_key(j)}_size_resolved"),
            size_held_out=HeldOut.from_dict(d.get(f"{_key(j)}_size_held_out"))) for j in names)
        return cls(fault=d["fault"], probabilities=dict(d["probabilities"]), joints=joints,
                   recording=d.get("recording", ""), warnings=tuple(d.get("warnings", ())),
                   evidence=Evidence.from_dict(d.get("evidence")), seconds=d.get("seconds"))

    @classmethod
    def from_json(cls, text: str) -> "IdentifyResult":
        """The answer of a JSON text as :meth:`to_json` writes it."""
        return cls.from_dict(json.loads(text))
