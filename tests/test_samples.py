"""The sample recordings and dataset specs that ship with the package (twin.samples), the command
line's names for them (``sample:NAME``, a spec's name) resolved by twin/commands/inputs.py, and the
"did you mean" of unknown names (twin.errors.did_you_mean) wherever a name is looked up."""

from __future__ import annotations

import filecmp
from pathlib import Path

import pytest

import twin.samples
from twin.cli import main
from twin.commands import inputs
from twin.errors import ConfigError, NameNotFoundError, did_you_mean, unknown

ROOT = Path(__file__).resolve().parent.parent


# ------------------------------------------------------------------ twin.samples
def test_docstring_examples_run_and_import_twin_reaches_the_module(capsys):
    import doctest
    import subprocess
    import sys

    res = doctest.testmod(twin.samples)
    assert res.attempted >= 3 and res.failed == 0, capsys.readouterr().out
    code = "import twin; print(twin.samples.path('test6').name)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.stdout.strip() == "test6_synthetic.mcap", r.stderr


def test_every_recording_and_spec_of_the_repository_is_named():
    assert twin.samples.names() == sorted(p.name[:-len("_synthetic.mcap")]
                                          for p in (ROOT / "recordings").glob("*_synthetic.mcap"))
    assert twin.samples.spec_names() == sorted(p.stem for p in (ROOT / "analysis" / "datasets").glob("*.toml"))
    # what the README and the docs use
    assert {"test3", "test6", "test6_repeat1", "test6_repeat2", "test6_repeat3", "static_calibration"} \
        <= set(twin.samples.names())
    assert {"tiny", "s000_example1", "s002_l27"} <= set(twin.samples.spec_names())


def test_a_name_gives_the_repository_file_one_copy():
    p = twin.samples.path("test6")
    assert p.name == "test6_synthetic.mcap" and p.is_file()
    assert filecmp.cmp(p, ROOT / "recordings" / "test6_synthetic.mcap", shallow=False)
    s = twin.samples.spec_path("tiny")
    assert s.name == "tiny.toml" and filecmp.cmp(s, ROOT / "analysis" / "datasets" / "tiny.toml", shallow=False)


@pytest.mark.parametrize("call, given, close", [
    (twin.samples.path, "test7", "test6"),
    (twin.samples.path, "Test6_repeat1", "test6_repeat1"),
    (twin.samples.spec_path, "tiyn", "tiny"),
    (twin.samples.spec_path, "s002_l72", "s002_l27"),
])
def test_an_unknown_name_is_one_line_with_the_closest_name_and_the_list(call, given, close):
    with pytest.raises(NameNotFoundError) as e:
        call(given)
    msg = str(e.value)
    assert "\n" not in msg and f"(did you mean {close!r}?)" in msg
    names = twin.samples.names() if call is twin.samples.path else twin.samples.spec_names()
    assert msg.endswith(", ".join(names))


@pytest.mark.parametrize("bad", ["", "zzzzzz", None, 6, "../recordings/test6"])
def test_names_that_are_no_sample_are_refused_without_a_suggestion_or_a_traceback(bad):
    with pytest.raises(NameNotFoundError, match="^no sample recording named") as e:
        twin.samples.path(bad)
    assert "did you mean" not in str(e.value)


# ------------------------------------------------------------------ the command line's resolver
def test_recording_argument_sample_name_or_path(tmp_path):
    assert inputs.recording("sample:test6") == twin.samples.path("test6")
    f = tmp_path / "mine.mcap"
    assert inputs.recording(str(f)) == f  # a path stays a path, existing or not (the command checks it)
    with pytest.raises(NameNotFoundError, match=r"^sample:tst6: no sample recording named 'tst6' "
                                                r"\(did you mean 'test6'\?\)"):
        inputs.recording("sample:tst6")


def test_a_missing_file_named_like_a_sample_says_how_to_name_the_sample(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(NameNotFoundError, match="^test6: no such file; the sample recording of that name is "
                                                "sample:test6$"):
        inputs.recording("test6")
    (tmp_path / "test6").write_bytes(b"")  # a file of that name is the user's file
    assert inputs.recording("test6") == Path("test6")


def test_spec_argument_path_or_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert inputs.spec("tiny") == twin.samples.spec_path("tiny")
    (tmp_path / "tiny").mkdir()  # the dataset generated with --out tiny: still the spec's name
    assert inputs.spec("tiny") == twin.samples.spec_path("tiny")
    mine = tmp_path / "mine"
    mine.write_text("[dataset]\n")
    assert inputs.spec("mine") == Path("mine")  # an existing file is the user's
    for text in ("tiny.toml", "specs/tiny", str(tmp_path / "x")):  # a suffix or a folder: a path
        assert inputs.spec(text) == Path(text)
    with pytest.raises(NameNotFoundError, match=r"^tny: no such file, and no dataset spec named 'tny' ships with "
                                                r"twin \(closest: 'tiny'.*; 'twin dataset list' lists all \d+\)$"):
        inputs.spec("tny")


def _cli(argv, capsys):
    rc = main(argv)
    out, err = capsys.readouterr()
    return rc, out, err


def test_dataset_plan_by_name_outside_the_checkout(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    rc, out, err = _cli(["dataset", "plan", "tiny", "--no-estimate", "--show", "1"], capsys)
    assert rc == 0, err
    assert out.startswith("tiny: 8 runs (grid design")
    rc, out, err = _cli(["dataset", "plan", "tny", "--no-estimate"], capsys)
    assert rc == 2 and err.count("\n") == 1 and "closest: 'tiny'" in err


@pytest.mark.parametrize("argv", [["dataset", "plan", "clearance_id_bench", "--no-estimate"],
                                  ["study", "doe", "clearance_id_bench", "--out", "o"],
                                  ["study", "taguchi", "clearance_id_bench", "--out", "o"]])
def test_unknown_spec_name_gives_the_closest_names_not_all(argv, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    names = twin.samples.spec_names()
    assert len(names) > 20  # the case this guards: a list too long for one line
    rc, out, err = _cli(argv, capsys)
    assert rc == 2 and err.count("\n") == 1 and "Traceback" not in err
    assert "closest: 'clearance_id_bench_" in err and "'twin dataset list' lists all" in err
    assert sum(f"'{n}'" in err for n in names) <= 5  # a few matches, not the list
    assert not (tmp_path / "o").exists()
    rc, out, err = _cli(["dataset", "list"], capsys)
    assert rc == 0 and out.split() == names


def test_identify_clearance_of_a_sample_by_name(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    rc, out, err = _cli(["identify", "clearance", "sample:test6"], capsys)
    assert rc == 0, err
    assert out.startswith("sample:test6: fault C")  # test 6: 0.1 mm at C (recordings/make_samples.py)


@pytest.mark.parametrize("argv", [
    ["replay", "sample:tset6", "--out", "r"],
    ["identify", "clearance", "sample:tset6"],
    ["identify", "restitution", "sample:tset6"],
    ["analyze", "repeatability", "sample:test6_repeat1", "sample:tset6"],
    ["view", "sample:tset6"],
    ["import", "x.csv", "--test", "6", "--out", "r.mcap", "--calibration", "sample:tset6"],
])
def test_every_command_reading_a_recording_takes_sample_names(argv, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    rc, out, err = _cli(argv, capsys)
    assert rc == 2 and err.count("\n") == 1
    assert err.startswith("twin: error: sample:tset6: no sample recording named 'tset6' (did you mean 'test6'?)")
    assert list(tmp_path.iterdir()) == []


def test_analyze_repeatability_reads_sample_names(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    rc, out, err = _cli(["analyze", "repeatability", "sample:test6_repeat1", "sample:test6_repeat2", "--start", "0.2",
                         "--stop", "0.22", "--decimate", "10", "--no-progress"], capsys)
    assert rc == 0, err
    assert "test6_repeat1_synthetic.mcap" in out and "test6_repeat2_synthetic.mcap" in out


def test_view_of_a_sample_writes_into_the_working_folder_not_the_installation(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    before = sorted(p.name for p in twin.samples.path("test6").parent.iterdir())
    rc, out, err = _cli(["view", "sample:test6_repeat1", "--pose-rate", "100"], capsys)
    assert rc == 0, err
    assert (tmp_path / "test6_repeat1_synthetic.rrd").stat().st_size > 0
    assert sorted(p.name for p in twin.samples.path("test6").parent.iterdir()) == before


# ------------------------------------------------------------------ did you mean
def test_did_you_mean_suggests_the_closest_name_only_when_close():
    assert did_you_mean("s01", ["s000", "s001", "s002", "s004"]) == " (did you mean 's001'?)"
    assert did_you_mean("RESTITUTION", ["law", "restitution"]) == " (did you mean 'restitution'?)"
    assert did_you_mean("restitution", ["restitution"]) == ""  # the name itself: nothing to suggest
    assert did_you_mean("qqq", ["law", "restitution"]) == ""
    assert did_you_mean(3, ["law"]) == "" and did_you_mean("", ["law"]) == ""
    assert unknown("key", "nmae", ("name", "seed")) == "unknown key (did you mean 'name'?); allowed: name, seed"


@pytest.mark.parametrize("argv, message", [
    (["simulate", "--preset", "s01"], "--preset: must be one of s000, s001, s002, s004, torque_release, "
                                      "torque_release_protocol, got 's01' (did you mean 's001'?)"),
    (["simulate", "--preset", "torque_relase"], "(did you mean 'torque_release'?)"),
    (["simulate", "--set", "contact.restitutoin=0.4"], "contact.restitutoin: unknown field (did you mean "
                                                       "'restitution'?); allowed: law, restitution,"),
    (["simulate", "--set", "contct.restitution=0.4"], "contct.restitution: unknown section 'contct' (did you mean "
                                                      "'contact'?)"),
    (["simulate", "--set", "mechanism.orientation=yy"], "mechanism.orientation: must be one of x, y, z; got 'yy' "
                                                        "(did you mean 'y'?)"),
])
def test_cli_errors_suggest_the_closest_name(argv, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    rc, out, err = _cli(argv + ["--no-out", "--duration", "0.01"], capsys)
    assert rc == 2 and err.count("\n") == 1 and message in err, err


def test_python_and_toml_errors_suggest_the_closest_name(tmp_path):
    from twin.config import load_config

    with pytest.raises(ConfigError, match=r"^preset: .* got 's01' \(did you mean 's001'\?\)$"):
        twin.preset("s01")
    f = tmp_path / "c.toml"
    f.write_text('preset = "s0002"\n')
    with pytest.raises(ConfigError, match=r"\(did you mean 's002'\?\)$"):
        load_config(f)
    f.write_text("[joints]\nclearance_c_m = 0.1\n")
    with pytest.raises(ConfigError, match=r"^joints.clearance_c_m: unknown field \(did you mean 'clearance_c_mm'\?\)"):
        load_config(f)


@pytest.mark.parametrize("text, message", [
    ('[dataset]\nnmae = "x"\n', "dataset.nmae: unknown key (did you mean 'name'?)"),
    ('[dataset]\nname = "x"\n[factor]\nfault = ["B"]\n', "factor: unknown section (did you mean 'factors'?)"),
    ('[dataset]\nname = "x"\n[factors]\nclearence_c_mm = [0.1]\n',
     "factors.clearence_c_mm: unknown factor (did you mean 'clearance_c_mm'?)"),
    ('[dataset]\nname = "x"\n[base]\npreset = "s01"\n', "base.preset: must be one of"),
    ('[dataset]\nname = "x"\n[factors]\nmotor_rpm = { range = [100, 200], levles = 3 }\n',
     "factors.motor_rpm.levles: unknown key (did you mean 'levels'?)"),
])
def test_spec_errors_suggest_the_closest_key(text, message, tmp_path):
    from twin.dataset.design import plan
    from twin.dataset.spec import SpecError, load_spec

    f = tmp_path / "s.toml"
    f.write_text(text)
    with pytest.raises(SpecError) as e:
        plan(load_spec(f))
    assert message in str(e.value) and "\n" not in str(e.value)
