"""Run files: bit-identical round trip, independent readers, damage detection, atomic writes."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from twin.config import preset
from twin.errors import RecordingError, TwinError
from twin.mcapfile import DEFAULT_BLOCK, RunWriter, read_metadata, read_run, write_run
from twin.run import Run
from twin.simulation import simulate_run
from twin.summary import summarize

from conftest import short


@pytest.fixture(scope="module")
def run12() -> Run:
    return simulate_run(short(preset(12), 0.0505))  # not a multiple of the 5000-sample block


def test_round_trip_is_bit_identical(run12, tmp_path):
    p = write_run(tmp_path / "r.mcap", run12, summary=summarize(run12))
    back = read_run(p)
    assert list(back.channels) == list(run12.channels)
    for name, ch in run12.channels.items():
        assert back[name].dtype == ch.data.dtype
        assert back[name].tobytes() == ch.data.tobytes(), name
        assert back.channels[name].unit == ch.unit and back.channels[name].group == ch.group
    assert (back.t0, back.rate_hz, back.n) == (run12.t0, run12.rate_hz, run12.n)
    assert back.config == run12.config
    assert back.meta == run12.meta
    # selective read of one group
    acc = read_run(p, groups=["accel"])
    assert list(acc.channels) == ["AC1", "AC2", "AC3", "AC4", "AC5", "AC6"]


def test_streaming_in_odd_chunks_equals_whole_write(run12, tmp_path):
    whole = write_run(tmp_path / "a.mcap", run12)
    with RunWriter(tmp_path / "b.mcap", run12.config) as w:
        for i0, i1 in ((0, 1), (1, 777), (777, 3001), (3001, run12.n)):
            w.write(run12.slice(i0, i1))
        w.close(run12.meta)
    a, b = read_run(whole), read_run(tmp_path / "b.mcap")
    for name in run12.channels:
        assert np.array_equal(a[name], b[name])


def test_independent_decoders_read_the_file(run12, tmp_path):
    p = write_run(tmp_path / "r.mcap", run12)
    # Python ros2msg/CDR decoder (not twin's)
    with open(p, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        _, channel, msg, decoded = next(reader.iter_decoded_messages(topics=["/twin/joint_C"]))
        assert channel.message_encoding == "cdr" and decoded.first_index == 0 and decoded.rate_hz == 1e5
        assert np.array_equal(np.asarray(decoded.ecc_c_x), run12["ecc_C_x"][:DEFAULT_BLOCK])
        assert msg.log_time == 0
    # rerun's MCAP reader (Rust), when the CLI is installed
    rerun = shutil.which("rerun") or str(Path(sys.executable).with_name("rerun"))
    if Path(rerun).exists():
        out = subprocess.run([rerun, "mcap", "check", str(p)], capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
        assert "/twin/accel" in out.stdout


@pytest.mark.parametrize("codec", ["lz4", "zstd"])
def test_files_with_compressed_chunks_read_the_same(run12, tmp_path, codec):
    """Files of earlier versions (LZ4 chunks in 0.3.0, zstd before, 1000-sample blocks) read bit for
    bit like the default's uncompressed chunks of 5000-sample blocks."""
    plain = read_run(write_run(tmp_path / "plain.mcap", run12))
    with RunWriter(tmp_path / "old.mcap", run12.config, block=1000, compression=codec) as w:
        w.write(run12)
        w.close(run12.meta)
    old = read_run(tmp_path / "old.mcap")
    with open(tmp_path / "old.mcap", "rb") as fh:
        summary = make_reader(fh).get_summary()
    assert {c.compression for c in summary.chunk_indexes} == {codec}
    for name in run12.channels:
        assert old[name].tobytes() == plain[name].tobytes() == run12[name].tobytes(), name
    with pytest.raises(TwinError, match="compression: must be one of none, lz4, zstd"):
        RunWriter(tmp_path / "x.mcap", run12.config, compression="gzip")


def test_default_chunks_are_uncompressed_blocks_of_default_size(run12, tmp_path):
    p = write_run(tmp_path / "r.mcap", run12)
    with open(p, "rb") as fh:
        summary = make_reader(fh).get_summary()
    assert {c.compression for c in summary.chunk_indexes} == {""}
    # blocks of DEFAULT_BLOCK samples: messages per topic = ceil(n / block)
    assert summary.statistics.message_count == len(summary.channels) * -(-run12.n // DEFAULT_BLOCK)


def test_log_times_are_simulation_time(run12, tmp_path):
    p = write_run(tmp_path / "r.mcap", run12)
    with open(p, "rb") as fh:
        times = [m.log_time for _, _, m in make_reader(fh).iter_messages(topics=["/twin/crank"])]
    assert times == [round(i * DEFAULT_BLOCK / run12.rate_hz * 1e9) for i in range(len(times))]


def test_damaged_files_give_clear_errors(run12, tmp_path):
    p = write_run(tmp_path / "r.mcap", run12)
    data = p.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(RecordingError, match="cut.mcap"):
        read_run(cut)
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not an mcap file at all" * 10)
    with pytest.raises(RecordingError):
        read_run(junk)
    with pytest.raises(RecordingError, match="no such file"):
        read_run(tmp_path / "missing.mcap")
    flipped = bytearray(data)
    flipped[len(data) // 3] ^= 0xFF  # corrupt a chunk: its CRC no longer matches
    bad = tmp_path / "flipped.mcap"
    bad.write_bytes(bytes(flipped))
    with pytest.raises(RecordingError):
        read_run(bad)
    with pytest.raises(RecordingError, match="no groups"):
        read_run(p, groups=["nonexistent"])
    assert "twin.run" in read_metadata(p)


def test_failed_write_leaves_existing_file_untouched(run12, tmp_path):
    target = tmp_path / "keep.mcap"
    target.write_bytes(b"precious")
    with pytest.raises(RuntimeError):
        with RunWriter(target, run12.config) as w:
            w.write(run12.slice(0, 2500))
            raise RuntimeError("engine died")
    assert target.read_bytes() == b"precious"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["keep.mcap"]


# ---------------------------------------------------------------------------- preview topic
def test_preview_decodes_as_one_message_per_sample_with_every_channel_a_field(run12, tmp_path):
    # decoded as Foxglove does: the MCAP index and the ros2msg/CDR decoder of mcap-ros2-support;
    # independent basis: block means of the full-rate arrays computed here by summation
    p = write_run(tmp_path / "r.mcap", run12, preview_rate_hz=1000.0)
    m = 100  # 100 kHz / 1 kHz
    with open(p, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        msgs = list(reader.iter_decoded_messages(topics=["/preview"], log_time_order=True))
    n = run12.n // m
    assert len(msgs) == n == 50
    stamps = []
    for k, (schema, channel, message, dec) in enumerate(msgs):
        assert schema.name == "twin_msgs/msg/Preview" and channel.message_encoding == "cdr"
        t_ns = round((k * m + (m - 1) / 2) / run12.rate_hz * 1e9)  # the block's centre
        assert message.log_time == message.publish_time == t_ns
        assert dec.header.stamp.sec * 10**9 + dec.header.stamp.nanosec == t_ns
        stamps.append(t_ns)
        for name, ch in run12.channels.items():
            block = ch.data[k * m:(k + 1) * m].astype(np.float64)
            want = sum(block.tolist()) / m
            got = getattr(dec, name.lower())
            tol = 1e-6 if ch.data.dtype == np.float32 else 1e-12
            assert got == pytest.approx(want, rel=tol, abs=tol * (np.max(np.abs(block)) + 1e-300)), (k, name)
    assert np.all(np.diff(stamps) == 1_000_000)  # monotonic, at the preview rate
    fields = [f for f in msgs[0][3].__slots__ if f != "header"] if hasattr(msgs[0][3], "__slots__") else \
        [f for f in vars(msgs[0][3]) if f != "header"]
    assert fields == [c.lower() for c in run12.channels]


def test_a_run_file_with_a_preview_reads_bit_for_bit_as_without(run12, tmp_path):
    from twin.mcapfile import read_preview

    plain = read_run(write_run(tmp_path / "a.mcap", run12))
    p = tmp_path / "b.mcap"
    with RunWriter(p, run12.config, preview_rate_hz=3000.0) as w:  # 33 samples a block: straddles chunks
        for i0, i1 in ((0, 1), (1, 777), (777, 3001), (3001, run12.n)):
            w.write(run12.slice(i0, i1))
        w.close(run12.meta)
    back = read_run(p)
    assert list(back.channels) == list(plain.channels) and back.n == plain.n
    for name in run12.channels:
        assert back[name].tobytes() == run12[name].tobytes(), name
    assert read_preview(tmp_path / "a.mcap") is None
    stamps, prev = read_preview(p)
    assert prev.n == run12.n // 33 and prev.rate_hz == pytest.approx(1e5 / 33)
    assert prev.t0 == pytest.approx(16 / 1e5) and stamps[1] - stamps[0] == 330_000
    np.testing.assert_allclose(prev["AC4"], run12["AC4"][:prev.n * 33].reshape(-1, 33).astype(np.float64).mean(1),
                               rtol=1e-6)
    with pytest.raises(TwinError, match="^preview_rate_hz: must be >= 0 Hz"):
        RunWriter(tmp_path / "c.mcap", run12.config, preview_rate_hz=-1.0)


def test_simulate_writes_a_1khz_preview_unless_told_otherwise(tmp_path, capsys):
    from twin.cli import main
    from twin.mcapfile import read_preview

    base = ["simulate", "--test", "6", "--duration", "0.02", "--no-progress"]
    assert main(base + ["--out", str(tmp_path / "a.mcap")]) == 0
    stamps, prev = read_preview(tmp_path / "a.mcap")
    assert prev.rate_hz == 1000.0 and prev.n == 20 and set(prev.channels) == set(read_run(tmp_path / "a.mcap").channels)
    assert main(base + ["--out", str(tmp_path / "b.mcap"), "--preview-rate", "0"]) == 0
    assert read_preview(tmp_path / "b.mcap") is None
    capsys.readouterr()
    for bad in ("-5", "2e5", "nan"):
        assert main(base + ["--out", str(tmp_path / "c.mcap"), "--preview-rate", bad]) == 2
        err = capsys.readouterr().err.strip()
        assert "--preview-rate" in err and err.count("\n") == 0
    assert not (tmp_path / "c.mcap").exists()


def _strict(text: str):
    """json.loads that refuses NaN/Infinity (RFC 8259 has no such numbers)."""
    def bad(name):
        raise ValueError(f"non-strict JSON constant {name}")
    return __import__("json").loads(text, parse_constant=bad)


def test_json_metadata_inside_run_files_is_strict(run12, tmp_path):
    # a summary or meta with a non-finite number (a metric with no data) is written as null, not NaN
    import dataclasses
    run = dataclasses.replace(run12, meta={**run12.meta, "odd": float("nan"), "big": float("inf")})
    path = write_run(tmp_path / "r.mcap", run, summary={"peak": float("nan"), "rms": np.float64(-np.inf), "ok": 1.5})
    meta = read_metadata(path)
    assert _strict(meta["twin.summary"]["json"]) == {"peak": None, "rms": None, "ok": 1.5}
    inner = _strict(meta["twin.run"]["meta"])
    assert inner["odd"] is None and inner["big"] is None
