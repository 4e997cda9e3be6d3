"""One owner per rule: each option is checked in one place (its options dataclass or the library
function that takes it); the command line parses and delegates.

Each case gives a bad value on the command line and the same value to the library: the CLI's one
line must be exactly the library's message with the field named by its flag. A second, different
check in the CLI (another limit, another wording) fails here; so does a value the CLI accepts that
the library refuses, or the reverse.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from twin.cli import main
from twin.errors import TwinError

ROOT = Path(__file__).resolve().parent.parent
REC = str(ROOT / "recordings" / "test6_synthetic.mcap")


def _library_error(call) -> TwinError:
    with pytest.raises(TwinError) as info:
        call()
    return info.value


def _sweep(**kw):
    from twin.identification.restitution import SweepOptions

    return lambda: SweepOptions(**kw)


def _replay(**kw):
    from twin.bench_replay import ReplayOptions

    return lambda: ReplayOptions(**kw)


def _formulations(duration_s):
    from twin.studies.formulations import FormulationsOptions

    return lambda: FormulationsOptions("unused", duration_s=duration_s)


def _accuracy(**kw):
    from twin.studies.accuracy import StudySettings

    return lambda: StudySettings(**kw)


def _stability(**kw):
    from twin.studies.stability import StudySettings

    return lambda: StudySettings(**kw)


def _continuous(duration_s):
    from twin.config import named_preset
    from twin.studies.continuous_contact import ContinuousContactOptions

    return lambda: ContinuousContactOptions("unused", named_preset("s004"), duration_s)


def _repeatability(**kw):
    from twin.studies.repeatability import check_arguments

    args = {"runs": [REC, REC], "start": None, "stop": None, "dtw_window": 0.05, "align_angle": None,
            "decimate": 1} | kw
    return lambda: check_arguments(**args)


def _screenshot(wait_s):
    from twin.viz.screenshot import check_screenshot_args

    return lambda: check_screenshot_args(wait_s, None, (1920, 1080))


def _size(size):
    from twin.util import check_size_px

    return lambda: check_size_px(size, "size_px")


def _waspas(lam):
    from twin.studies.mcdm import _check_lambda

    return lambda: _check_lambda(lam)


CASES = [
    # (id, command line ({out}: a fresh folder), flag, the library call given the same value)
    ("restitution max-lag", ["identify", "restitution", REC, "--max-lag", "0.7"], "--max-lag", _sweep(max_lag_s=0.7)),
    ("restitution max-lag 11", ["identify", "restitution", REC, "--max-lag", "11"], "--max-lag",
     _sweep(max_lag_s=11.0)),
    ("restitution lowpass", ["identify", "restitution", REC, "--lowpass", "-1"], "--lowpass", _sweep(lowpass_hz=-1.0)),
    ("replay max-lag", ["replay", REC, "--out", "{out}", "--max-lag", "11"], "--max-lag", _replay(max_lag_s=11.0)),
    ("replay dtw-max", ["replay", REC, "--out", "{out}", "--dtw-max", "0.0001"], "--dtw-max", _replay(dtw_max_s=0.0001)),
    ("replay dtw-window", ["replay", REC, "--out", "{out}", "--dtw-window", "nan"], "--dtw-window",
     _replay(dtw_window_s=math.nan)),
    ("formulations duration", ["study", "formulations", "--out", "{out}", "--duration", "61"], "--duration",
     _formulations(61.0)),
    ("accuracy window", ["study", "accuracy", "--out", "{out}", "--window", "61"], "--window", _accuracy(window_s=61.0)),
    ("accuracy tests", ["study", "accuracy", "--out", "{out}", "--tests", "3"], "--tests", _accuracy(tests=(3,))),
    ("stability scenes", ["study", "stability", "--scenes", "0", "--seed", "1", "--out", "{out}"], "--scenes",
     _stability(scenes=0)),
    ("continuous-contact duration", ["study", "continuous-contact", "--out", "{out}", "--duration", "11"],
     "--duration", _continuous(11.0)),
    ("mcdm lambda", ["study", "mcdm", REC, "--criteria", "a:min", "--waspas-lambda", "2", "--out", "{out}"],
     "--waspas-lambda", _waspas(2.0)),
    ("repeatability dtw-window", ["analyze", "repeatability", REC, REC, "--dtw-window", "11"], "--dtw-window",
     _repeatability(dtw_window=11.0)),
    ("repeatability stop", ["analyze", "repeatability", REC, REC, "--start", "2", "--stop", "1"], "--stop",
     _repeatability(start=2.0, stop=1.0)),
    ("view wait", ["view", REC, "--save", "{out}.rrd", "--screenshot", "{out}.png", "--wait", "-1"], "--wait",
     _screenshot(-1.0)),
    ("plot size", ["plot", REC, "--out", "{out}.png", "--size", "10x10"], "--size", _size((10, 10))),
]


@pytest.mark.parametrize("argv, flag, call", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_the_cli_reports_the_library_rule(argv, flag, call, tmp_path, capsys):
    lib = _library_error(call)
    out = str(tmp_path / "o")
    rc = main([a.replace("{out}", out) for a in argv])
    err = capsys.readouterr().err
    assert rc == 2, err
    # names the library quotes (`start`) are the command's options there
    text = re.sub(r"`([a-z_]+)`", lambda m: "--" + m.group(1).replace("_", "-"), lib.message)
    assert err == f"twin: error: {flag}: {text}\n"
    assert list(tmp_path.iterdir()) == []  # refused before anything was written


def test_the_max_lag_limit_is_the_sweep_s():
    """--max-lag of twin identify restitution: the CLI once accepted up to 10 s, SweepOptions 0.5 s.
    The one rule is SweepOptions' [0, 0.5] s: the sweep aligns a window of a few crank turns, and a
    shift of more than half a second is a wrong window, not a lag."""
    from twin.identification.restitution import SweepOptions

    assert SweepOptions(max_lag_s=0.5).max_lag_s == 0.5
    with pytest.raises(TwinError, match=r"\[0, 0\.5\] s"):
        SweepOptions(max_lag_s=0.51)


def test_a_lowpass_above_nyquist_is_the_full_band():
    """--lowpass: the CLI once refused more than 1 MHz; SweepOptions' rule is >= 0 Hz only, since a
    cut-off at or above the Nyquist frequency filters nothing (the full band, as 0 does)."""
    from twin.identification.restitution import SweepOptions, zero_phase_lowpass as _lowpass

    assert SweepOptions(lowpass_hz=1e7).lowpass_hz == 1e7
    assert _lowpass(1e7, 100_000.0) is None and _lowpass(0.0, 100_000.0) is None
    assert _lowpass(200.0, 100_000.0) is not None


def test_the_cli_passes_a_lowpass_above_a_megahertz_to_the_sweep(monkeypatch, capsys):
    """The CLI has no limit of its own on --lowpass: the value reaches SweepOptions as given."""
    import twin.identification.restitution as R

    seen = []

    class Stop(TwinError):
        pass

    def fake_sweep(rec, opts):
        seen.append(opts)
        raise Stop("stopped before simulating")

    monkeypatch.setattr(R, "sweep_restitution", fake_sweep)
    assert main(["identify", "restitution", REC, "--lowpass", "2e6", "--max-lag", "0.5"]) == 2
    assert "stopped before simulating" in capsys.readouterr().err
    assert seen[0].lowpass_hz == 2e6 and seen[0].max_lag_s == 0.5


def test_contact_check_joints_are_checked_by_the_check(tmp_path, capsys):
    from twin.config import BenchConfig
    from twin.studies.contact_check import contact_check

    lib = _library_error(lambda: contact_check(BenchConfig(), joints=("X",), progress=False))
    assert main(["check", "contact", "--joints", "X", "--out", str(tmp_path / "c.json")]) == 2
    assert capsys.readouterr().err == f"twin: error: --joints: {lib.message}\n"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("rate", ["-1", "nan", "200000"])
def test_the_preview_rate_rule_is_the_writer_s(rate, tmp_path, capsys):
    from twin.mcapfile import check_preview_rate

    lib = _library_error(lambda: check_preview_rate(float(rate), 100_000.0))
    assert main(["simulate", "--duration", "0.001", "--out", str(tmp_path / "r.mcap"), "--preview-rate", rate]) == 2
    assert capsys.readouterr().err == f"twin: error: --preview-rate: {lib.message}\n"
    assert list(tmp_path.iterdir()) == []
