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

from twin.typed import ByKey

__all__ = ["Evidence", "FeatureDistance", "HeldOut", "IdentifyResult", "JointAnswer", "ModelInfo", "RecordingMeasures",
           "TrainingDataCheck"]


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


def _no_other_keys(cls: type, d: Mapping[str, Any], known: tuple[str, ...], optional: tuple[str, ...] = ()) -> None:
    """ValueError naming the keys of ``d`` that ``cls`` does not know, or the ``known`` ones missing (``optional``
    aside): a key is never lost silently."""
    other = [k for k in d if k not in known]
    if other:
        raise ValueError(f"{cls.__name__}: keys {', '.join(map(repr, other))} unknown; allowed: {', '.join(known)}")
    missing = [k for k in known if k not in d and k not in optional]
    if missing:
        raise ValueError(f"{cls.__name__}: keys {', '.join(map(repr, missing))} missing")


@dataclass(frozen=True)
class RecordingMeasures(ByKey):
    """What was measured of a recording's steady windows (:func:`twin.identification.ranges.recording_measures`).

    Attributes:
        crank_hz: the crank rate [Hz].
        ripple_pct: the within-turn speed ripple per harmonic of the crank rate, 1x first [%].
        noise_ug_rthz: the sensors' noise level [µg/√Hz] (NaN, null in JSON, where it could not be measured).
        speed_swing_pct: the crank rate's largest swing within 50 ms [%]; None where not measured (answers made
            before it was).
        rotation: the crank's direction, "forward" (encoder counts increasing) or "reverse"
            (:mod:`twin.identification.rotation`); None where not measured (answers made before it was).
    """

    crank_hz: float
    ripple_pct: tuple[float, ...]
    noise_ug_rthz: float | None
    speed_swing_pct: float | None = None
    rotation: str | None = None

    def to_dict(self) -> dict[str, Any]:
        d = {"crank_hz": self.crank_hz, "ripple_pct": list(self.ripple_pct), "noise_ug_rthz": self.noise_ug_rthz}
        d = d if self.speed_swing_pct is None else d | {"speed_swing_pct": self.speed_swing_pct}
        return d if self.rotation is None else d | {"rotation": self.rotation}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "RecordingMeasures":
        _no_other_keys(cls, d, ("crank_hz", "ripple_pct", "noise_ug_rthz", "speed_swing_pct", "rotation"),
                       ("speed_swing_pct", "rotation"))
        return cls(d["crank_hz"], tuple(d["ripple_pct"]), d["noise_ug_rthz"], d.get("speed_swing_pct"),
                   d.get("rotation"))


@dataclass(frozen=True)
class FeatureDistance(ByKey):
    """How far a recording's median window features lie from the training windows'
    (:func:`twin.identification.ranges.feature_outliers`).

    Attributes:
        beyond_far_out_fences: features beyond the training windows' far-out fences.
        of: features compared.
        training_runs_max: the most such features a training run had; None where the model stores no such count.
    """

    beyond_far_out_fences: int
    of: int
    training_runs_max: int | None

    def to_dict(self) -> dict[str, Any]:
        return {"beyond_far_out_fences": self.beyond_far_out_fences, "of": self.of,
                "training_runs_max": self.training_runs_max}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "FeatureDistance":
        _no_other_keys(cls, d, ("beyond_far_out_fences", "of", "training_runs_max"))
        return cls(d["beyond_far_out_fences"], d["of"], d["training_runs_max"])


@dataclass(frozen=True)
class RigidRod(ByKey):
    """The rigid-rod check (:data:`twin.identification.ranges.RIGID_ROD_FEATURE`): the log10 ratio of the 0.8-6 kHz
    band energies of the rod's two longitudinal accelerometers (AC1 at B over AC4 at C) [log10], and the largest
    a rod moving as one body gives (:data:`twin.identification.ranges.RIGID_ROD_RATIO_MAX`) [log10]."""

    measured: float
    limit: float

    def to_dict(self) -> dict[str, Any]:
        return {"measured": self.measured, "limit": self.limit}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "RigidRod":
        _no_other_keys(cls, d, ("measured", "limit"))
        return cls(d["measured"], d["limit"])


@dataclass(frozen=True)
class TrainingDataCheck(ByKey):
    """A recording checked against the model's training data (:func:`twin.identification.model.training_check`).

    Attributes:
        measured: what was measured of the recording.
        outside_training_data: whether any check found the recording outside the training data.
        interval_rule: which interval the answer gives, in words.
        ranges: why the ranges were not checked ("unavailable ..."); None where they were.
        feature_distance: the features' distance from the training data, or why it is unavailable (text); None
            where not checked (no training ranges).
        rigid_rod_ratio_log10: the rigid-rod check (:class:`RigidRod`); None where not checked.
    """

    measured: RecordingMeasures
    outside_training_data: bool
    interval_rule: str
    ranges: str | None = None
    feature_distance: FeatureDistance | str | None = None
    rigid_rod_ratio_log10: RigidRod | None = None

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"measured": self.measured.to_dict()}
        if self.ranges is not None:
            d["ranges"] = self.ranges
        if self.feature_distance is not None:
            fd = self.feature_distance
            d["feature_distance"] = fd if isinstance(fd, str) else fd.to_dict()
        if self.rigid_rod_ratio_log10 is not None:
            d["rigid_rod_ratio_log10"] = self.rigid_rod_ratio_log10.to_dict()
        return d | {"outside_training_data": self.outside_training_data, "interval_rule": self.interval_rule}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "TrainingDataCheck":
        _no_other_keys(cls, d, ("measured", "ranges", "feature_distance", "rigid_rod_ratio_log10",
                                "outside_training_data", "interval_rule"),
                       ("ranges", "feature_distance", "rigid_rod_ratio_log10"))
        fd, rr = d.get("feature_distance"), d.get("rigid_rod_ratio_log10")
        return cls(measured=RecordingMeasures.from_dict(d["measured"]),
                   outside_training_data=d["outside_training_data"], interval_rule=d["interval_rule"],
                   ranges=d.get("ranges"), feature_distance=fd if fd is None or isinstance(fd, str) else
                   FeatureDistance.from_dict(fd),
                   rigid_rod_ratio_log10=None if rr is None else RigidRod.from_dict(rr))


@dataclass(frozen=True)
class ModelInfo(ByKey):
    """What the model answering was trained on.

    Attributes:
        dataset: the training datasets' names, joined by "+".
        identity_sha256: the digest of the model's identity (its training data and settings).
        engine: the engine(s) the training data were simulated with.
        crank_hz_range: the training data's crank rates (lowest, highest) [Hz].
    """

    dataset: str
    identity_sha256: str
    engine: str
    crank_hz_range: tuple[float, float]

    def to_dict(self) -> dict[str, Any]:
        return {"dataset": self.dataset, "identity_sha256": self.identity_sha256, "engine": self.engine,
                "crank_hz_range": list(self.crank_hz_range)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "ModelInfo":
        _no_other_keys(cls, d, ("dataset", "identity_sha256", "engine", "crank_hz_range"))
        return cls(d["dataset"], d["identity_sha256"], d["engine"], tuple(d["crank_hz_range"]))


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
        model: what the model was trained on.
    """

    windows: int
    revolutions: float
    crank_hz: float
    motor_rpm_if_belt_3_97: float
    steady_s: float
    features: int
    feature_version: str
    training_data_check: TrainingDataCheck
    model: ModelInfo

    def __post_init__(self) -> None:  # dicts as to_dict() writes them are read into the typed values
        if isinstance(self.training_data_check, Mapping):
            object.__setattr__(self, "training_data_check", TrainingDataCheck.from_dict(self.training_data_check))
        if isinstance(self.model, Mapping):
            object.__setattr__(self, "model", ModelInfo.from_dict(self.model))

    def to_dict(self) -> dict[str, Any]:
        return {"windows": self.windows, "revolutions": self.revolutions, "crank_hz": self.crank_hz,
                "motor_rpm_if_belt_3_97": self.motor_rpm_if_belt_3_97, "steady_s": self.steady_s,
                "features": self.features, "feature_version": self.feature_version,
                "training_data_check": self.training_data_check.to_dict(), "model": self.model.to_dict()}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> "Evidence | None":
        if d is None:
            return None
        plain = {k: d[k] for k in cls.__dataclass_fields__}
        return cls(**plain | {"training_data_check": TrainingDataCheck.from_dict(d["training_data_check"]),
                              "model": ModelInfo.from_dict(d["model"])})


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
