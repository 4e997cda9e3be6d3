"""Property-based tests (hypothesis) of the bad-input guarantees.

Whatever configuration file, ``--set`` value or run-file metadata is given, the command line
answers with a normal run (exit 0) or one line ``twin: error: ...`` (exit 2): never a traceback,
never a hang (an alarm fails the test after 60 s), never a multi-line error, and no file but the
command's own output is created or changed. Examples are few (``max_examples``) so that the
default suite stays fast; ``HYPOTHESIS_PROFILE=thorough`` runs many more.
"""

from __future__ import annotations

import os
import shutil
import signal
import tempfile
from pathlib import Path

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from test_bad_input_more import Hung, rewrite_mcap, snapshot  # noqa: E402
from twin.cli import main  # noqa: E402

settings.register_profile("default", max_examples=25, deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
settings.register_profile("thorough", max_examples=1000, deadline=None,
                          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))


def _fields() -> list[str]:
    from twin.config import BenchConfig

    out = []

    def walk(prefix, d):
        for k, v in d.items():
            if isinstance(v, dict) and v:
                walk(f"{prefix}{k}.", v)
            else:
                out.append(prefix + k)
    walk("", BenchConfig().to_dict())
    return out


FIELDS = _fields()
SECTIONS = sorted({f.split(".")[0] for f in FIELDS if "." in f})

scalars = st.one_of(st.integers(-10**20, 10**20), st.floats(allow_nan=True, allow_infinity=True),
                    st.booleans(), st.text(max_size=20))
values = st.recursive(scalars, lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                        st.dictionaries(st.text(min_size=1, max_size=8), inner,
                                                                        max_size=3)), max_leaves=8)
keys = st.one_of(st.sampled_from(FIELDS), st.text(min_size=1, max_size=15))


def _run(argv: list[str], cwd: Path, capsys, own: tuple[str, ...] = ()) -> tuple[int, str]:
    """Run the command line with an alarm; check the one-line/exit-code contract; return (rc, err)."""
    def ring(signum, frame):
        raise Hung(f"hung: {argv}")

    before = {k: v for k, v in snapshot(cwd).items() if k not in own}
    old = signal.signal(signal.SIGALRM, ring)
    signal.alarm(60)
    try:
        rc = main(argv)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    out, err = capsys.readouterr()
    assert rc in (0, 2), (rc, argv, err[-2000:])
    assert "Traceback" not in err, err[-2000:]
    if rc == 2:
        assert err.startswith("twin: error: ") and err.count("\n") == 1, err[-2000:]
    after = {k: v for k, v in snapshot(cwd).items() if k not in own}
    assert after == before, (argv, set(after) ^ set(before))
    return rc, err


def _section_dict(draw_sections):
    return draw_sections


configs = st.dictionaries(st.one_of(st.sampled_from(SECTIONS), st.text(min_size=1, max_size=10)),
                          st.one_of(st.dictionaries(keys.map(lambda k: k.split(".")[-1]), values, max_size=4), values),
                          max_size=4)


@given(cfg=configs)
def test_any_configuration_file_is_run_or_refused_in_one_line(cfg, capsys):
    import tomli_w

    d = Path(tempfile.mkdtemp(prefix="twin_prop_"))
    try:
        try:
            text = tomli_w.dumps(cfg)
        except (TypeError, ValueError):
            return  # not representable as TOML
        (d / "c.toml").write_text(text)
        _run(["export-mjcf", "--config", str(d / "c.toml"), "--out", str(d / "m.xml")], d, capsys, own=("m.xml",))
    finally:
        shutil.rmtree(d, ignore_errors=True)


@given(text=st.text(max_size=200))
def test_any_text_as_a_configuration_file_is_run_or_refused_in_one_line(text, capsys):
    d = Path(tempfile.mkdtemp(prefix="twin_prop_"))
    try:
        (d / "c.toml").write_text(text, encoding="utf-8", errors="surrogatepass") if "\ud800" not in text else None
        if not (d / "c.toml").exists():
            return
        _run(["export-mjcf", "--config", str(d / "c.toml"), "--out", str(d / "m.xml")], d, capsys, own=("m.xml",))
    finally:
        shutil.rmtree(d, ignore_errors=True)


@given(key=keys, value=st.one_of(st.text(max_size=40), scalars.map(str), st.sampled_from(
    ["nan", "inf", "-inf", "1e309", "[]", "{}", "[[1]]", '"x"', "true", "0", "-1", "1e300", "{a = 1}"])))
def test_any_set_value_is_run_or_refused_in_one_line(key, value, capsys):
    d = Path(tempfile.mkdtemp(prefix="twin_prop_"))
    try:
        _run(["export-mjcf", "--set", f"{key}={value}", "--out", str(d / "m.xml")], d, capsys, own=("m.xml",))
    finally:
        shutil.rmtree(d, ignore_errors=True)


@pytest.fixture(scope="module")
def small_recording(tmp_path_factory) -> Path:
    from test_bad_input_more import ZERO_G, _export

    d = tmp_path_factory.mktemp("prop_rec")
    _export(d / "export.csv", 200)
    assert main(["import", str(d / "export.csv"), "--test", "6", "--out", str(d / "small.mcap"),
                 "--zero-g", ZERO_G]) == 0
    return d / "small.mcap"


meta_text = st.one_of(st.text(max_size=30), st.sampled_from(["nan", "inf", "-1", "0", "1e300", "[]", "{}", "null",
                                                             "100000.0", "200", "twin-run/1", ""]))


@given(field=st.sampled_from(["t0", "rate_hz", "n", "meta", "channels", "format"]), value=meta_text,
       cfield=st.sampled_from(["names", "units", "dtypes", None]), cvalue=meta_text)
def test_any_run_metadata_is_refused_in_one_line(field, value, cfield, cvalue, small_recording, capsys):
    """A small recording (too little motion to replay) with one 'twin.run' field and one channel
    metadata entry replaced: replay refuses it in one line whatever the values."""
    d = Path(tempfile.mkdtemp(prefix="twin_prop_"))
    try:
        rewrite_mcap(small_recording, d / "r.mcap", run_meta=lambda m: {**m, field: value},
                     chan_meta=(lambda tp, m: {**m, cfield: cvalue}) if cfield else None)
        rc, _ = _run(["replay", str(d / "r.mcap"), "--out", str(d / "rp"), "--no-plots"], d, capsys)
        assert rc == 2
    finally:
        shutil.rmtree(d, ignore_errors=True)
