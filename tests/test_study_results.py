"""Studies without a command line: ``run_study(options)`` takes a frozen options dataclass and returns a
typed, frozen result whose ``to_dict()`` is the JSON file the study writes (the CLI only parses,
delegates and prints). Short cases of the studies that run in seconds; the long ones are covered by
their own test modules through the same API."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from twin.errors import ConfigError


def _data_of(path: Path) -> dict:
    """The JSON a study wrote, less its provenance stamp (the file's, not the result's: checked here, then
    dropped, so that the rest compares with ``to_dict()`` key for key)."""
    import twin
    from twin.provenance import PROVENANCE_KEY, git_commit

    d = json.loads(path.read_text())
    assert list(d)[0] == PROVENANCE_KEY, f"{path.name}: not stamped"
    st = d.pop(PROVENANCE_KEY)
    assert st["twin_version"] == twin.__version__ and st["git_commit"] == git_commit()
    return d


def _stamped_md(path: Path) -> bool:
    from twin.provenance import stamp_line

    return path.read_text().endswith("\n\n" + stamp_line() + "\n")


def _stamped_png(path: Path) -> bool:
    from PIL import Image

    from twin.provenance import figure_metadata

    with Image.open(path) as im:
        return im.info.get("Software") == figure_metadata()["Software"]


def _frozen(obj) -> None:
    field = dataclasses.fields(obj)[0].name
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(obj, field, None)


def test_mcdm_result_is_its_json(tmp_path):
    from twin.studies.mcdm import McdmOptions, McdmResult, run_study

    src = tmp_path / "r.csv"
    src.write_text("run,acc,force,label\n1,32.7,1345,a\n2,51.1,1756,b\n3,73.6,1956,c\n4,54.8,1012,d\n")
    opts = McdmOptions(src, "acc:min,force:min", tmp_path / "out", weights="merec")
    res = run_study(opts)
    assert isinstance(res, McdmResult)
    _frozen(opts), _frozen(res)
    assert res.to_dict() == _data_of(tmp_path / "out" / "mcdm.json")
    assert _stamped_md(tmp_path / "out" / "report.md")
    assert res.names == ["a", "b", "c", "d"] and res.weights_source == "MEREC" and res.merec is not None
    # the best alternative by SAW is the one of largest score
    saw = res.methods["saw"]
    assert res.best("saw") == res.names[int(np.argmax(saw["scores"]))]


def test_taguchi_result_is_its_json(tmp_path):
    from twin.studies import taguchi

    d = taguchi.s002_design()
    rng = np.random.default_rng(0)
    lines = ["crank,clearance,mu,rpm,acc"]
    for i in range(27):
        lines.append(f"{d['crank_length'][i]:g},{d['clearance'][i]:g},{d['friction'][i]:g},{d['speed'][i]:g},"
                     f"{50 + d['clearance'][i] * 10 + rng.normal():.6f}")
    src = tmp_path / "runs.csv"
    src.write_text("\n".join(lines) + "\n")
    res = taguchi.run_study(taguchi.TaguchiOptions(src, "acc", "crank,clearance,mu,rpm", tmp_path / "out"))
    assert isinstance(res, taguchi.TaguchiResult)
    _frozen(res)
    assert res.to_dict() == _data_of(tmp_path / "out" / "taguchi.json")
    assert _stamped_md(tmp_path / "out" / "report.md")
    assert all(_stamped_png(tmp_path / "out" / f) for f in res.figures)
    assert res.runs == 27 and set(res.responses) == {"acc"}
    assert all((tmp_path / "out" / f).is_file() for f in res.figures) and len(res.figures) == 2


def test_continuous_contact_result_is_its_json(tmp_path):
    from twin.config import named_preset
    from twin.studies.continuous_contact import ContinuousContactOptions, ContinuousContactResult, run_study

    opts = ContinuousContactOptions(tmp_path / "out", named_preset("s004"), 0.02)
    res = run_study(opts)
    assert isinstance(res, ContinuousContactResult)
    assert res.to_dict() == _data_of(tmp_path / "out" / "continuous_contact.json")
    assert _stamped_png(tmp_path / "out" / "continuous_contact.png")
    # the golden file: what the dict code wrote for the same run (layout; values as a regression guard, 1e-9)
    golden = json.loads((Path(__file__).resolve().parent / "golden" / "continuous_contact_s004_0.02s.json").read_text())
    assert list(res.to_dict()) == list(golden)
    assert all(res.to_dict()[k] == pytest.approx(v, rel=1e-9, abs=1e-300)
               for k, v in golden.items() if k != "ft_max_abs_n")  # ft: round-off, ~1e-10 N
    assert res.summary.valid_until_crank_deg == res.to_dict()["valid_until_crank_deg"]
    with np.load(tmp_path / "out" / "continuous_contact.npz") as z:
        assert set(z.files) == set(res.series) and np.array_equal(z["fn"], res.series["fn"])
    # the model's assumptions are the options' rules: a mechanism without clearance at B is refused
    with pytest.raises(ConfigError, match=r"^joints\.clearance_b_mm: "):
        ContinuousContactOptions(tmp_path / "o2", named_preset("s004").replace(**{"joints.clearance_b_mm": 0.0}))
    assert not (tmp_path / "o2").exists()


def test_formulations_result_is_its_json(tmp_path):
    from twin.studies import formulations as F

    opts = F.FormulationsOptions(tmp_path, duration_s=0.1, cases=(F.Case("R-matrix", 1e-4),),
                                 work_precision_methods={})
    res = F.run_study(opts)
    assert isinstance(res, F.FormulationsResult)
    assert res.to_dict() == _data_of(tmp_path / "formulations.json")
    assert _stamped_md(tmp_path / "formulations.md") and all(_stamped_png(tmp_path / f) for f in res.figures)
    assert [r.case for r in res.rows] == [F.Case("R-matrix", 1e-4).label] and res.work_precision == ()
    assert isinstance(res.rows[0], F.CaseRow) and res.rows[0]["case"] == res.rows[0].case  # read by key as the dict was
    with pytest.raises(ConfigError, match=r"^duration_s: must lie in \(0, 60\] s"):
        F.FormulationsOptions(tmp_path, duration_s=0.0)


def test_options_hold_the_rules_the_cli_used_to_check():
    """Rules that lived in the CLI (or in both places) are the options' own now."""
    from twin.studies import accuracy, stability

    with pytest.raises(ConfigError, match=r"^window_s: must lie in \[0\.05, 60\] s"):
        accuracy.StudySettings(window_s=61.0)
    assert accuracy.StudySettings(window_s=60.0).window_s == 60.0
    with pytest.raises(ConfigError, match=r"^variants: must contain"):
        accuracy.AccuracyOptions("unused", variants=(accuracy.TRUTH,))
    with pytest.raises(ConfigError, match=r"^family: must be bench or spatial"):
        stability.StudySettings(family="planar")
