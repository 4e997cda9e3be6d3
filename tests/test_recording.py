"""Bench recordings: layout round trip, CSV/NPZ import with column mapping, and bad recordings."""

from __future__ import annotations

import json

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
    with pytest.raises(RecordingError, match="--rate"):
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
    with pytest.raises(RecordingError, match="missing channel volt_AC3 .*--map volt_AC3=COLUMN"):
        _import(tmp_path, good_cols)


def test_nan_samples_error_or_reported_repair(tmp_path, good_cols):
    good_cols["volt_AC2"][1000:1003] = np.nan
    with pytest.raises(RecordingError, match=r"volt_AC2 has a NaN .* sample 1000 .*--repair-nan"):
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
    with pytest.raises(RecordingError, match="wrong sample rate: the time column says 100000 Hz, --rate says 200000"):
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
