"""Valid inputs that were refused: a UTF-8 byte-order mark at the start of a TOML or CSV file (Windows
editors write one), and file suffixes in capitals (``RUN.MCAP``). Each case failed before its fix."""

from __future__ import annotations

import numpy as np
import pytest

from twin.cli import main

BOM = b"\xef\xbb\xbf"


def _ok(args, capsys) -> str:
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    assert code == 0, out.err
    return out.out


def test_a_configuration_with_a_byte_order_mark_is_read(tmp_path, capsys):
    (tmp_path / "bom.toml").write_bytes(BOM + b"[simulation]\r\nduration_s = 0.01\r\n")
    _ok(["simulate", "--config", tmp_path / "bom.toml", "--no-progress", "--out", tmp_path / "r.mcap"], capsys)
    from twin.mcapfile import read_run

    assert read_run(tmp_path / "r.mcap").duration_s == pytest.approx(0.01)


def test_a_dataset_spec_with_a_byte_order_mark_is_read(tmp_path, capsys):
    import twin.samples

    text = twin.samples.spec_path("tiny").read_bytes()
    (tmp_path / "tiny_bom.toml").write_bytes(BOM + text)
    assert "estimated wall time" in _ok(["dataset", "plan", tmp_path / "tiny_bom.toml"], capsys)


def test_a_trace_csv_with_a_byte_order_mark_is_read(tmp_path):
    from twin.tracefile import load_trace

    t = np.linspace(0.0, 0.1, 20)
    rows = "\n".join(f"{a},{b}" for a, b in zip(t, 10.0 * t))
    (tmp_path / "tr.csv").write_bytes(BOM + f"t,angle\n{rows}\n".encode())
    tt, aa = load_trace(tmp_path / "tr.csv")
    np.testing.assert_allclose(tt, t)
    np.testing.assert_allclose(aa, 10.0 * t)


@pytest.mark.parametrize("suffix", [".MCAP", ".Mcap"])
def test_file_suffixes_in_capitals_are_accepted(tmp_path, capsys, suffix):
    run = tmp_path / f"RUN{suffix}"
    _ok(["simulate", "--duration", "0.01", "--no-progress", "--out", run], capsys)
    _ok(["plot", run, "--out", tmp_path / "P.PNG"], capsys)
    assert (tmp_path / "P.PNG").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
