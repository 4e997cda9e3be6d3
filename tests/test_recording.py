"""Bench recordings: layout round trip, CSV/NPZ import with column mapping, and bad recordings."""

from __future__ import annotations

import json
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest

from twin.cli import main
from twin.config import ACCELEROMETERS, BenchConfig
from twin.errors import RecordingError
from twin.instrument import measured_accel
from twin.mcapfile import read_metadata, write_run
from twin.recording import (RECORDING_RECORD, import_table, read_recording, synthetic_recording,
                            write_recording)
from twin.run import Run

RATE = 100_000.0
OFFSETS = {"AC1": 2.513, "AC2": 2.488, "AC3": 2.506, "AC4": 2.471, "AC5": 2.522, "AC6": 2.494}
N = 4000


def _cfg() -> BenchConfig:
    return BenchConfig().replace(**{"instrumentation.zero_g_v": OFFSETS, "instrumentation.seed": 4})


def _truth(cfg: BenchConfig, n: int = N) -> Run:
    """Crank-like truth signals (no physics needed here): 19.8 rad/s crank, accelerations of its harmonics."""
    t = np.arange(n) / RATE
    arrays = {a: 30.0 * np.sin(19.8 * t + k) + (9.81 if a in ("AC2", "AC3", "AC5") else 0.0)
              for k, a in enumerate(ACCELEROMETERS)}
    arrays["encoder_angle"] = 19.8 * t + 0.2
    return Run.from_arrays(0.0, RATE, arrays, cfg)


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    cfg = _cfg()
    daq, info = synthetic_recording(_truth(cfg), cfg, notes="unit test", static_s=0.2)
    path = tmp_path_factory.mktemp("rec") / "rec.mcap"
    write_recording(path, daq, info)
    return path, daq, info


def _export(daq: Run, names: dict[str, str] | None = None, units: dict[str, str] | None = None,
            time: np.ndarray | None = None) -> dict[str, np.ndarray]:
    cols = {"t": daq.time if time is None else time}
    for c in daq.channels:
        cols[(names or {}).get(c, c)] = daq[c].copy()
    return cols


def _write_csv(path, cols: dict[str, np.ndarray], units: dict[str, str]) -> None:
    header = ",".join(f"{k} [{units[k]}]" if k in units else k for k in cols)
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",", header=header, comments="", fmt="%.10g")


def _std_units(cols) -> dict[str, str]:
    return {k: ("count" if "encoder" in k else "V") for k in cols if k != "t"} | {"t": "s"}


# ------------------------------------------------------------------------ layout
def test_recording_round_trip_and_layout(recording):
    path, daq, info = recording
    run, info2, repairs = read_recording(path)
    assert repairs == []
    assert list(run.channels) == [f"volt_{a}" for a in ACCELEROMETERS] + ["encoder_counts", "motor_command"]
    assert {c.group for c in run.channels.values()} == {"daq"}
    assert run.channels["encoder_counts"].unit == "count" and run.channels["volt_AC1"].unit == "V"
    for c in daq.channels:
        np.testing.assert_array_equal(run[c], daq[c])  # bit-identical
    assert run.config == daq.config
    assert info2.synthetic and info2.notes == "unit test" and info2.rate_hz == RATE
    assert info2.calibration.zero_g_v == pytest.approx(OFFSETS, abs=3e-5)
    assert info2.extra["chain_seed"] == 4
    md = read_metadata(path)
    assert json.loads(md[RECORDING_RECORD]["json"])["calibration"]["method"].startswith("static")
    # the calibrated accelerations are the truth within noise and the sensor response
    meas = measured_accel(run, info2.calibration)
    truth = _truth(_cfg())
    for a in ("AC1", "AC5"):
        err = meas[f"meas_{a}"] - truth[a]
        assert abs(np.mean(err)) < 0.02 and np.std(err) < 0.2  # m/s^2 (noise 0.07-0.12 m/s^2 RMS)


def test_plain_run_file_is_not_a_recording(tmp_path):
    cfg = _cfg()
    p = tmp_path / "sim.mcap"
    write_run(p, _truth(cfg, 500))
    with pytest.raises(RecordingError, match="not a bench recording"):
        read_recording(p)


# ------------------------------------------------------------------------ importers
def test_csv_import_with_mapping_units_and_mv(tmp_path, recording):
    _, daq, _ = recording
    names = {f"volt_{a}": f"ai{i}" for i, a in enumerate(ACCELEROMETERS)} | {"encoder_counts": "ctr0",
                                                                               "motor_command": "ao_mon"}
    cols = _export(daq, names)
    cols["ai2"] = cols["ai2"] * 1000.0  # exported in mV
    units = {"t": "s", "ai0": "V", "ai1": "V", "ai2": "mV", "ai3": "V", "ai4": "V", "ai5": "V"}
    csv = tmp_path / "export.csv"
    _write_csv(csv, cols, units)
    mapping = {f"volt_{a}": (f"ai{i}", None) for i, a in enumerate(ACCELEROMETERS)}
    mapping |= {"encoder_counts": ("ctr0", "count"), "motor_command": ("ao_mon", "V")}
    run, repairs = import_table(csv, _cfg(), mapping)
    assert run.rate_hz == RATE and run.n == N
    assert repairs == ["volt_AC3: converted mV to V"]
    for c in daq.channels:
        np.testing.assert_allclose(run[c], daq[c], rtol=1e-9, atol=1e-9)
    # the same through the CLI, with known offsets
    out = tmp_path / "imported.mcap"
    argv = ["import", str(csv), "--out", str(out), "--notes", "bench run 5",
            "--map", ",".join(f"volt_{a}=ai{i}" for i, a in enumerate(ACCELEROMETERS) if i != 2),
            "--map", "volt_AC3=ai2:mV", "--map", "encoder_counts=ctr0:count,motor_command=ao_mon:V"]
    assert main(argv + ["--zero-g", ",".join(f"{k}={v}" for k, v in OFFSETS.items())]) == 0
    rec, info, _ = read_recording(out)
    assert info.notes == "bench run 5" and info.calibration.zero_g_v == OFFSETS
    assert info.source_sha256 and not info.synthetic and "volt_AC3: converted mV to V" in info.repairs


def test_csv_import_with_static_calibration_file(tmp_path, recording):
    _, daq, _ = recording
    from twin.instrument.chain import static_recording

    csv, static = tmp_path / "test.csv", tmp_path / "static.csv"
    cols = _export(daq)
    _write_csv(csv, cols, _std_units(cols))
    st = _export(static_recording(_cfg(), 0.2))
    _write_csv(static, st, _std_units(st))
    out = tmp_path / "r.mcap"
    assert main(["import", str(csv), "--out", str(out), "--calibration", str(static)]) == 0
    _, info, _ = read_recording(out)
    assert info.calibration.zero_g_v == pytest.approx(OFFSETS, abs=3e-5)  # Eq. 1-2 on the static export
    assert info.calibration.source == "static.csv"


def test_npz_import_without_time_column(tmp_path, recording):
    _, daq, _ = recording
    arrays = {c: daq[c] for c in daq.channels}
    arrays["units"] = np.array(json.dumps({c: daq.channels[c].unit for c in daq.channels}))
    p = tmp_path / "export.npz"
    np.savez(p, **arrays)
    with pytest.raises(RecordingError, match=r"no time column; give the sample rate \(`rate_hz`\)"):
        import_table(p, _cfg())
    run, repairs = import_table(p, _cfg(), rate_hz=RATE)
    assert run.t0 == 0.0 and run.n == N and repairs == []
    np.testing.assert_array_equal(run["encoder_counts"], daq["encoder_counts"])


# ------------------------------------------------------------------ bad recordings
@pytest.fixture
def good_cols(recording):
    return _export(recording[1])


def _import(tmp_path, cols, units=None, **kw):
    p = tmp_path / "bad.csv"
    _write_csv(p, cols, _std_units(cols) if units is None else units)
    return import_table(p, _cfg(), **kw)


def test_truncated_and_corrupt_mcap(tmp_path, recording):
    path = recording[0]
    data = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(RecordingError, match="cut.mcap"):
        read_recording(cut)
    bad = bytearray(data)
    mid = len(bad) // 3
    bad[mid:mid + 64] = bytes(64)  # zeroed bytes inside a compressed chunk
    corrupt = tmp_path / "corrupt.mcap"
    corrupt.write_bytes(bytes(bad))
    with pytest.raises(RecordingError, match="corrupt.mcap"):
        read_recording(corrupt)
    with pytest.raises(RecordingError, match="no such file"):
        read_recording(tmp_path / "missing.mcap")


def test_missing_channel(tmp_path, good_cols):
    del good_cols["volt_AC3"]
    with pytest.raises(RecordingError, match="missing channel volt_AC3 .*`mapping` volt_AC3=COLUMN"):
        _import(tmp_path, good_cols)


def test_nan_samples_error_or_reported_repair(tmp_path, good_cols):
    good_cols["volt_AC2"][1000:1003] = np.nan
    with pytest.raises(RecordingError, match=r"volt_AC2 has a NaN .* sample 1000 .*`nan='interpolate'`"):
        _import(tmp_path, good_cols)
    run, repairs = _import(tmp_path, good_cols, nan="interpolate")
    assert repairs == ["volt_AC2: interpolated 3 NaN samples in 1 gap(s) (longest 3, first at t = 0.010000 s)"]
    assert np.all(np.isfinite(run["volt_AC2"]))
    good_cols["volt_AC2"][2000:2100] = np.nan
    with pytest.raises(RecordingError, match="gap of 100 NaN samples"):
        _import(tmp_path, good_cols, nan="interpolate")


def test_encoder_nan_and_non_integer_counts(tmp_path, good_cols):
    cols = {k: v.copy() for k, v in good_cols.items()}
    cols["encoder_counts"][50] = np.nan
    with pytest.raises(RecordingError, match="encoder_counts has a NaN"):
        _import(tmp_path, cols, nan="interpolate")
    cols = {k: v.copy() for k, v in good_cols.items()}
    cols["encoder_counts"] = cols["encoder_counts"] * 0.5
    with pytest.raises(RecordingError, match="non-integer count"):
        _import(tmp_path, cols)


def test_time_not_monotonic_or_irregular(tmp_path, good_cols):
    t = good_cols["t"].copy()
    t[100], t[101] = t[101], t[100]
    with pytest.raises(RecordingError, match="not strictly increasing at row 101"):
        _import(tmp_path, good_cols | {"t": t})
    t = good_cols["t"].copy()
    t[2000:] += 3e-5  # three samples dropped
    with pytest.raises(RecordingError, match="irregular time base: step 4e-05 s at row 2000"):
        _import(tmp_path, good_cols | {"t": t})


def test_wrong_sample_rate(tmp_path, good_cols):
    slow = good_cols | {"t": np.arange(N) / 50_000.0}
    with pytest.raises(RecordingError, match="sampled at 50000 Hz but instrumentation.daq_rate_hz is 100000"):
        _import(tmp_path, slow)
    with pytest.raises(RecordingError, match="wrong sample rate: the time column says 100000 Hz, `rate_hz` says 200000"):
        _import(tmp_path, good_cols, rate_hz=200_000.0)


def test_unknown_or_missing_units(tmp_path, good_cols):
    units = _std_units(good_cols) | {"volt_AC4": "g"}
    with pytest.raises(RecordingError, match="unknown unit 'g' for volt_AC4"):
        _import(tmp_path, good_cols, units)
    units = _std_units(good_cols)
    del units["encoder_counts"]
    with pytest.raises(RecordingError, match="unknown unit of column 'encoder_counts'"):
        _import(tmp_path, good_cols, units)
    units = _std_units(good_cols) | {"encoder_counts": "V"}
    with pytest.raises(RecordingError, match="unknown unit 'V' for encoder_counts"):
        _import(tmp_path, good_cols, units)


def test_encoder_glitch_repaired_and_reported_step_refused(tmp_path, good_cols):
    cols = {k: v.copy() for k, v in good_cols.items()}
    cols["encoder_counts"][3000] += 20000
    run, repairs = _import(tmp_path, cols)
    np.testing.assert_array_equal(run["encoder_counts"], good_cols["encoder_counts"])
    assert len(repairs) == 1 and "1-sample glitch" in repairs[0] and "t = 0.030000 s" in repairs[0]
    cols["encoder_counts"][3500:] += 700
    with pytest.raises(RecordingError, match="lost counts or a counter reset"):
        _import(tmp_path, cols)
    # a counter that wraps at 2**16 is unwrapped when its modulus is given
    cols = {k: v.copy() for k, v in good_cols.items()}
    cols["encoder_counts"] = np.mod(cols["encoder_counts"] + 63000, 2**16)  # wraps mid-recording
    with pytest.raises(RecordingError, match="cannot repair"):
        _import(tmp_path, cols)
    run, repairs = _import(tmp_path, cols, encoder_modulus=2**16)
    assert repairs == ["encoder_counts: unwrapped a counter of modulus 65536"]
    np.testing.assert_array_equal(np.diff(run["encoder_counts"]), np.diff(good_cols["encoder_counts"]))


def test_cli_import_errors_are_one_line_and_leave_no_file(tmp_path, good_cols, capsys):
    del good_cols["volt_AC6"]
    p = tmp_path / "x.csv"
    _write_csv(p, good_cols, _std_units(good_cols))
    out = tmp_path / "x.mcap"
    assert main(["import", str(p), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("twin: error:") and "volt_AC6" in err[0]
    assert not out.exists() and not list(tmp_path.glob(".*tmp"))
    assert main(["import", str(tmp_path / "nope.csv"), "--out", str(out)]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["import", str(p), "--out", str(tmp_path / "x.txt")]) == 2
    assert main(["import", str(p), "--out", str(out), "--map", "volt_AC9=ai0"]) == 2
    assert "unknown target channel" in capsys.readouterr().err


# ------------------------------------------------------- bad inputs through the CLI
ZERO_G = ",".join(f"{k}={v}" for k, v in OFFSETS.items())


def _npz(path, cols, **over):
    """An NPZ export of ``cols`` with a ``units`` entry; ``over`` replaces or (None) drops columns."""
    arrays = {**cols, "units": np.array(json.dumps(_std_units(cols)))}
    arrays.update(over)
    np.savez(path, **{k: v for k, v in arrays.items() if v is not None})
    return path


def _csv_lines(path, cols, edit) -> None:
    """A CSV export of ``cols`` whose text lines (header = line 1) are changed by ``edit(lines)``."""
    _write_csv(path, cols, _std_units(cols))
    lines = path.read_text().splitlines()
    edit(lines)
    path.write_text("\n".join(lines) + "\n")


def _zip(path, members: dict[str, str]):
    with zipfile.ZipFile(path, "w") as zf:
        for name, text in members.items():
            zf.writestr(name, text)
    return path


def _truncated(path, size: int):
    path.write_bytes(path.read_bytes()[:size])
    return path


def _cell(lines, lineno, col, value) -> None:
    cells = lines[lineno - 1].split(",")
    cells[col] = value
    lines[lineno - 1] = ",".join(cells)


BAD_IMPORTS = {
    # NPZ columns must be 1-D arrays of real numbers
    "npz bool": (lambda d, c: _npz(d / "bad.npz", c, volt_AC1=c["volt_AC1"] > 2.5), [],
                 ["bad.npz", "'volt_AC1'", "boolean", "real numbers"]),
    "npz complex": (lambda d, c: _npz(d / "bad.npz", c, encoder_counts=c["encoder_counts"].astype(complex)), [],
                    ["bad.npz", "'encoder_counts'", "complex", "real numbers"]),
    "npz object (pickle)": (lambda d, c: _npz(d / "bad.npz", c, volt_AC2=np.array([1.0, "x", None], dtype=object)),
                            [], ["bad.npz", "'volt_AC2'", "Python objects", "real numbers"]),
    "npz strings": (lambda d, c: _npz(d / "bad.npz", c, volt_AC1=c["volt_AC1"].astype(str)), [],
                    ["bad.npz", "'volt_AC1'", "string", "real numbers"]),
    "npz bytes": (lambda d, c: _npz(d / "bad.npz", c, volt_AC1=c["volt_AC1"].astype("S12")), [],
                  ["bad.npz", "'volt_AC1'", "bytes"]),
    "npz datetime time": (lambda d, c: _npz(d / "bad.npz", c, t=np.arange(N).astype("datetime64[us]")), [],
                          ["bad.npz", "'t'", "datetime"]),
    "npz 0-d": (lambda d, c: _npz(d / "bad.npz", c, volt_AC3=np.array(2.5)), [], ["bad.npz", "'volt_AC3'", "1-D"]),
    "npz 2-D": (lambda d, c: _npz(d / "bad.npz", c, volt_AC3=c["volt_AC3"][:, None]), [],
                ["bad.npz", "'volt_AC3'", "(4000, 1)", "1-D"]),
    "npz unequal lengths": (lambda d, c: _npz(d / "bad.npz", c, volt_AC4=c["volt_AC4"][:10]), [],
                            ["bad.npz", "'volt_AC4'", "same length"]),
    "npz one sample": (lambda d, c: _npz(d / "bad.npz", {k: v[:1] for k, v in c.items()}), [],
                       ["bad.npz", "1 data row", "at least 2"]),
    "npz empty archive": (lambda d, c: (np.savez(d / "bad.npz"), d / "bad.npz")[1], [], ["bad.npz", "no columns"]),
    "npz not a zip": (lambda d, c: (d / "bad.npz", (d / "bad.npz").write_text("hello"))[0], [],
                      ["bad.npz", "not a .npz file"]),
    "npz is a .npy": (lambda d, c: (np.save(d / "bad.npy", c["t"]), (d / "bad.npy").rename(d / "bad.npz"),
                                    d / "bad.npz")[2], [], ["bad.npz", "single .npy array"]),
    "npz truncated": (lambda d, c: _truncated(_npz(d / "bad.npz", c), 5000), [], ["bad.npz", "not a readable .npz"]),
    "npz member not .npy": (lambda d, c: _zip(d / "bad.npz", {"t.npy": "junk"}), [], ["bad.npz", "member 't'", "not a numpy array"]),
    "npz huge volts": (lambda d, c: _npz(d / "bad.npz", c, volt_AC5=np.full(N, 1e308)), [],
                       ["bad.npz", "volt_AC5", "1e+308", "daq_range", "[-10, 10] V"]),
    "npz count beyond 2**53": (lambda d, c: _npz(d / "bad.npz", c, encoder_counts=np.full(N, 2**64 - 1, np.uint64)),
                               [], ["bad.npz", "encoder_counts", "2**53"]),
    "npz time step underflow": (lambda d, c: _npz(d / "bad.npz", c, t=np.arange(N) * 1e-320), [],
                                ["bad.npz", "time step", "seconds"]),
    # CSV
    "csv non-numeric cell": (lambda d, c: _csv_lines(d / "bad.csv", c, lambda ls: _cell(ls, 7, 2, "2.5V")), [],
                             ["bad.csv", "line 7, column 3 ('volt_AC2')", "'2.5V' is not a number"]),
    "csv ragged row": (lambda d, c: _csv_lines(d / "bad.csv", c, lambda ls: ls.__setitem__(9, ls[9] + ",1")), [],
                       ["bad.csv", "line 10 has 10 fields", "9 columns"]),
    "csv empty file": (lambda d, c: (d / "bad.csv").write_text(""), [], ["bad.csv", "empty file"]),
    "csv header only": (lambda d, c: _csv_lines(d / "bad.csv", c, lambda ls: ls.__delitem__(slice(1, None))), [],
                        ["bad.csv", "no data rows"]),
    "csv one data row": (lambda d, c: _csv_lines(d / "bad.csv", c, lambda ls: ls.__delitem__(slice(2, None))), [],
                         ["bad.csv", "1 data row", "at least 2"]),
    "csv duplicate names": (lambda d, c: _csv_lines(d / "bad.csv", c, lambda ls: ls.__setitem__(
        0, ls[0].replace("volt_AC3 [V]", "volt_AC2 [V]"))), [], ["bad.csv", "'volt_AC2' appears twice", "columns 3 and 4"]),
    "csv not UTF-8": (lambda d, c: (d / "bad.csv").write_bytes("t [s],Temp [°C]\n0,1\n".encode("latin-1")), [],
                      ["bad.csv", "not UTF-8", "0xb0"]),
    "csv not UTF-8 further down": (lambda d, c: (_csv_lines(d / "bad.csv", c, lambda ls: None),
                                                 (d / "bad.csv").write_bytes((d / "bad.csv").read_bytes() + b"1,\xff\n")),
                                   [], ["bad.csv", "line 4002 is not UTF-8", "0xff"]),
    "csv binary": (lambda d, c: (d / "bad.csv").write_bytes(bytes(range(256)) * 8), [], ["bad.csv", "binary"]),
    "csv inf in time": (lambda d, c: _csv_lines(d / "bad.csv", c, lambda ls: _cell(ls, 4001, 0, "inf")), [],
                        ["bad.csv", "time column", "infinite", "row 3999"]),
    "csv time in ms": (lambda d, c: _csv_lines(d / "bad.csv", c, lambda ls: ls.__setitem__(
        0, ls[0].replace("t [s]", "t [ms]"))), [], ["bad.csv", "time column 't'", "'ms'", "allowed: s"]),
    "csv volts beyond the DAQ range": (lambda d, c: _csv_lines(d / "bad.csv", c, lambda ls: _cell(ls, 50, 6, "12.5")),
                                       [], ["bad.csv", "volt_AC6", "12.5 at sample 48", "daq_range"]),
    # not an export file
    "unsupported suffix": (lambda d, c: (d / "bad.txt", (d / "bad.txt").write_text("t,x\n0,1\n"))[0], [],
                           ["bad.txt", "unsupported export format '.txt'", ".csv", ".npz"]),
    "missing file": (lambda d, c: d / "nope.csv", [], ["nope.csv", "no such file"]),
    "directory": (lambda d, c: (d / "dir.csv", (d / "dir.csv").mkdir())[0], [], ["dir.csv", "is a directory"]),
    # options
    "--rate inf": (None, ["--rate", "inf"], ["--rate", "finite", "> 0"]),
    "--rate 0": (None, ["--rate", "0"], ["--rate", "> 0"]),
    "--rate nan": (None, ["--rate", "nan"], ["--rate", "> 0"]),
    "--map no =": (None, ["--map", "volt_AC1"], ["--map", "TARGET=SOURCE"]),
    "--map empty unit": (None, ["--map", "volt_AC1=volt_AC1:"], ["--map", "empty unit"]),
    "--map unknown unit": (None, ["--map", "volt_AC1=volt_AC1:furlong"], ["good.csv", "'furlong'", "allowed: V"]),
    "--map target twice": (None, ["--map", "volt_AC1=volt_AC1,volt_AC1=volt_AC2"], ["--map", "volt_AC1 is mapped twice"]),
    "--map column used twice": (None, ["--map", "volt_AC1=volt_AC2"], ["good.csv", "'volt_AC2'", "both volt_AC1 and volt_AC2"]),
    "--map time column missing": (None, ["--map", "t=time"], ["good.csv", "no time column 'time'", "--map t="]),
    "--time-column missing": (None, ["--time-column", "time"], ["good.csv", "no time column 'time'", "--time-column"]),
    "--zero-g unknown sensor": (None, ["--zero-g", ZERO_G.replace("AC6", "AC7")], ["--zero-g", "'AC7'", "allowed: AC1"]),
    "--zero-g out of range": (None, ["--zero-g", ZERO_G.replace("AC3=2.506", "AC3=7")],
                              ["--zero-g", "AC3 = 7 V", "(0, supply_v = 5) V"]),
    "--zero-g negative": (None, ["--zero-g", ZERO_G.replace("AC3=2.506", "AC3=-0.1")], ["--zero-g", "AC3 = -0.1 V"]),
    "--encoder-modulus 0": (None, ["--encoder-modulus", "0"], ["--encoder-modulus", "[2, 2**64]", "got 0"]),
    "--encoder-modulus negative": (None, ["--encoder-modulus", "-5"], ["--encoder-modulus", "got -5"]),
    "--encoder-modulus too small": (None, ["--encoder-modulus", "4"], ["--encoder-modulus", "too small"]),
    "--encoder-modulus below the counts": (None, ["--encoder-modulus", "1000"],
                                           ["good.csv", "encoder_counts reaches", "does not wrap at 1000"]),
    "--calibration missing": (None, ["--calibration", "{d}/static.csv"], ["static.csv", "no such file"]),
    "--calibration directory": (None, ["--calibration", "{d}"], ["is a directory"]),
    "--calibration .txt": (lambda d, c: (d / "static.txt").write_text("x"), ["--calibration", "{d}/static.txt"],
                           ["static.txt", "allowed: .mcap", ".csv or .npz"]),
    "--calibration bool npz": (lambda d, c: _npz(d / "static.npz", c, volt_AC1=c["volt_AC1"] > 2.5),
                               ["--calibration", "{d}/static.npz"], ["static.npz", "'volt_AC1'", "boolean"]),
    "--calibration not a static recording": (
        lambda d, c: _write_csv(d / "static.csv", {k: (v + 6.0 if k.startswith("volt") else v) for k, v in c.items()},
                                _std_units(c)), ["--calibration", "{d}/static.csv"],
        ["static.csv", "zero-g offset", "outside the sensor's output range"]),
}


@pytest.mark.parametrize("case", list(BAD_IMPORTS))
def test_bad_imports_are_one_line_errors_and_write_nothing(case, tmp_path, good_cols, capsys):
    make, extra, expect = BAD_IMPORTS[case]
    good = tmp_path / "good.csv"
    _write_csv(good, good_cols, _std_units(good_cols))
    export = good  # option cases import the good export (and may make other files)
    if make is not None:
        made = make(tmp_path, {k: v.copy() for k, v in good_cols.items()})
        if not extra:  # export cases: the file made (or the bad.csv it wrote)
            export = made if isinstance(made, Path) else tmp_path / "bad.csv"
    before = sorted(p.name for p in tmp_path.iterdir())
    out = tmp_path / "out.mcap"
    argv = ["import", str(export), "--test", "6", "--out", str(out), *(a.format(d=tmp_path) for a in extra)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a numpy warning is a failure too
        assert main(argv) == 2
    cap = capsys.readouterr()
    err = cap.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("twin: error: "), cap.err
    assert "Traceback" not in cap.err and "Warning" not in cap.err
    for word in expect:
        assert word in err[0], (word, err[0])
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written, no temporary left
