"""twin plot: a PNG of a run, a bench recording and a replay without a GPU or a display.

What the figure shows is checked against independent facts: the crank harmonics against the
crank speed of the configuration in closed form (motor rpm / belt ratio 3.97), the orbit's circle
against the joint's clearance, the drawn curves against the file's samples; the PNG's size is read
from its header.
"""

from __future__ import annotations

import math
import struct
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

from tests.conftest import short
from twin.cli import main
from twin.config import preset
from twin.mcapfile import write_run
from twin.simulation import simulate_run
from twin.viz.plot import draw, load, plot

ROOT = Path(__file__).resolve().parents[1]
RECORDING = ROOT / "recordings" / "test6_synthetic.mcap"


def png_size(path: Path) -> tuple[int, int]:
    """(width, height) [px] from the PNG signature and IHDR chunk; fails for anything else."""
    head = path.read_bytes()[:24]
    assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR", head
    return struct.unpack(">II", head[16:24])


def crank_hz(cfg) -> float:
    """Steady crank rate of a constant-speed configuration, closed form [Hz]."""
    return cfg.drive.motor_rpm / cfg.drive.belt_ratio / 60.0


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    """Table 4 test 12 (0.1 mm at B and C), 0.2 s with a 0.05 s ramp, as a run file."""
    cfg = short(preset(12), 0.2)
    path = tmp_path_factory.mktemp("plot") / "t12.mcap"
    write_run(path, simulate_run(cfg))
    return path, cfg


def test_a_run_is_drawn_without_a_gpu(run_file, tmp_path):
    path, cfg = run_file
    out = tmp_path / "t12.png"
    info = plot(path, out, window=(0.1, 0.2), spectrum=True, size_px=(900, 700))
    assert png_size(out) == (900, 700) and info.size_px == (900, 700)
    assert info.kind == "run" and info.path == out
    assert info.channels == ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6", "fn_B", "fn_C")
    assert info.window_s == pytest.approx((0.1, 0.2))
    # the crank rate from the crank angle over the steady window vs 750 rpm / 3.97 (the PID follows
    # the reference to well below 1 %)
    f = crank_hz(cfg)
    assert f == pytest.approx(3.1486, abs=1e-4)
    assert info.crank_hz == pytest.approx(f, rel=0.01)
    assert info.harmonics_hz == pytest.approx([k * f for k in range(1, 11)], rel=0.01)
    assert info.bands_hz == ((800.0, 1200.0), (2700.0, 3300.0))
    # orbit circles: the radial clearance, half the 0.1 mm diametral clearance
    assert info.orbits == pytest.approx({"B": 50e-6, "C": 50e-6}) and info.note == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t12.png"]  # no temporary file left
    from PIL import Image

    import twin
    with Image.open(out) as im:
        assert im.size == (900, 700) and im.text["Software"] == f"twin {twin.__version__} (twin plot)"
        assert im.text["Description"].startswith("run t12: AC1, AC2")


def test_the_figure_draws_the_files_samples_and_marks(run_file):
    """What the axes hold: the window's samples, harmonic lines at k f_crank, the clearance circle."""
    path, cfg = run_file
    src = load(path)
    fig = Figure(figsize=(9, 7))
    info = draw(fig, src, channels=["AC6", "fn_*"], window=(0.1, 0.2), spectrum=True)
    assert info.channels == ("AC6", "fn_B", "fn_C")
    by_label = {ax.get_ylabel().split("\n")[0]: ax for ax in fig.axes if ax.get_ylabel()}
    assert set(by_label) == {"AC6", "fn_B", "fn_C"}
    t, y = by_label["AC6"].lines[0].get_data()
    i0, i1 = 10_000, 20_000
    np.testing.assert_array_equal(y, src.run["AC6"][i0:i1])
    assert t[0] == pytest.approx(0.1) and t[-1] == pytest.approx(0.2 - 1e-5)
    # dashed vertical lines on each spectrum: at the crank harmonics from the closed form
    spectra = [ax for ax in fig.axes if ax.get_xscale() == "log"]
    assert len(spectra) == 3
    marks = sorted(ln.get_xdata()[0] for ln in spectra[0].lines if ln.get_linestyle() == "--")
    assert marks == pytest.approx([k * crank_hz(cfg) for k in range(1, 11)], rel=0.01)
    # orbits: the green circle's radius is the radial clearance in µm
    orbits = [ax for ax in fig.axes if ax.get_title().startswith("journal at")]
    assert [ax.get_title()[11] for ax in orbits] == ["B", "C"]
    cx, cy = orbits[1].lines[0].get_data()
    assert np.hypot(cx, cy) == pytest.approx(cfg.joints.clearance_c_mm / 2 * 1e3)


def test_the_cli_draws_a_run(run_file, tmp_path, capsys):
    path, _ = run_file
    out = tmp_path / "fig.png"
    assert main(["plot", str(path), "--out", str(out)]) == 0
    w, h = png_size(out)
    assert w > 600 and h > 400
    line = capsys.readouterr().out
    assert f"wrote {out}" in line and "orbits at B, C" in line
    # default window: the last 0.4 s, here the whole 0.2 s run
    assert "0.000-0.200 s" in line


def test_a_recording_is_drawn_calibrated_with_no_orbit(tmp_path):
    out = tmp_path / "rec.png"
    info = plot(RECORDING, out, spectrum=True)
    assert png_size(out) == info.size_px
    assert info.kind == "recording"
    assert info.channels == tuple(f"meas_AC{i}" for i in range(1, 7))
    assert info.orbits == {} and "no joint channels" in info.note
    # encoder counts -> crank rate: the synthetic recording's crank rides at 750 rpm / 3.97 with a
    # ripple of a few percent (recordings/make_samples.py)
    assert info.crank_hz == pytest.approx(crank_hz(preset(6)), rel=0.03)
    assert len(info.harmonics_hz) == 10


def test_a_replay_draws_recorded_and_simulated(tmp_path):
    """A replay folder: each recorded meas_ACi panel also draws its simulated sim_meas_ACi."""
    from twin.bench_replay import ReplayOptions, replay
    from twin.recording import synthetic_recording, write_recording

    base = short(preset(6), 0.4).replace(**{"instrumentation.zero_g_v": {f"AC{i}": 2.5 for i in range(1, 7)}})
    daq, info = synthetic_recording(simulate_run(base), base, static_s=0.2)
    rec = tmp_path / "t6.mcap"
    write_recording(rec, daq, info)
    folder = tmp_path / "replay_t6"
    replay(rec, folder, opts=ReplayOptions(plots=False))
    fig = Figure(figsize=(10, 8))
    src = load(folder)
    pinfo = draw(fig, src, spectrum=True)
    assert src.kind == "replay" and pinfo.channels[:6] == tuple(f"meas_AC{i}" for i in range(1, 7))
    assert pinfo.overlays["meas_AC3"] == "sim_meas_AC3"
    ax = next(a for a in fig.axes if a.get_ylabel().startswith("meas_AC3"))
    (_, rec_y), (_, sim_y) = (ln.get_data() for ln in ax.lines)
    i0, i1 = (int(round((t - src.run.t0) * src.run.rate_hz)) for t in pinfo.window_s)
    np.testing.assert_array_equal(rec_y, src.run["meas_AC3"][i0:i1])
    np.testing.assert_array_equal(sim_y, src.run["sim_meas_AC3"][i0:i1])
    assert list(pinfo.orbits) == ["C"]  # test 6: clearance at C only
    out = tmp_path / "replay.png"
    assert main(["plot", str(folder), "--out", str(out), "--channels", "meas_AC6"]) == 0
    assert png_size(out)[0] > 0


@pytest.mark.parametrize("argv, fragment", [
    (["--channels", "AC9"], "--channels: 'AC9' matches no channel of t12; channels: AC1, AC2"),
    (["--channels", "AC1,,AC2"], "--channels: expects comma-separated"),
    (["--window", "0.1"], "--window: expects START:STOP"),
    (["--window", "0.2:0.1"], "--window: expects finite seconds START < STOP"),
    (["--window", "0.1:0.5"], "--window: 0.1..0.5 s lies outside the run (0..0.2 s)"),
    (["--window", "0.1:0.1001"], "--window: 0.1..0.1001 s holds fewer than 64 samples"),
    (["--size", "10x10"], "--size: must be two whole numbers of pixels in 64..8192"),
    (["--size", "ax10"], "--size: must be WIDTHxHEIGHT"),
])
def test_bad_arguments_are_one_line_and_write_nothing(run_file, tmp_path, capsys, argv, fragment):
    path, _ = run_file
    old = tmp_path / "fig.png"
    old.write_bytes(b"old")
    assert main(["plot", str(path), "--out", str(old), *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and fragment in err, err
    assert old.read_bytes() == b"old" and [p.name for p in tmp_path.iterdir()] == ["fig.png"]


def test_missing_input_and_missing_output_folder(run_file, tmp_path, capsys):
    path, _ = run_file
    assert main(["plot", str(tmp_path / "nope.mcap"), "--out", str(tmp_path / "a.png")]) == 2
    assert "nope.mcap: no such file or folder" in capsys.readouterr().err
    assert main(["plot", str(path), "--out", str(tmp_path / "missing" / "a.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--out: directory" in err and "does not exist" in err
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["plot", str(empty), "--out", str(tmp_path / "a.png")]) == 2
    assert "not a replay folder" in capsys.readouterr().err
    # an output inside the folder it reads is refused before any work (the output rule)
    assert main(["plot", str(empty), "--out", str(empty / "a.png")]) == 2
    assert "lies inside the input" in capsys.readouterr().err
    assert main(["plot", str(path), "--out", str(tmp_path / "a.jpg")]) == 2
    assert "--out: must end in .png" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == [empty] and list(empty.iterdir()) == []


def test_a_failed_write_leaves_the_old_figure(run_file, tmp_path, monkeypatch):
    """An error while the PNG is rendered: the old file stays whole, no temporary is left."""
    from matplotlib.figure import Figure as Fig

    from twin.errors import TwinError
    path, _ = run_file
    old = tmp_path / "fig.png"
    old.write_bytes(b"old")

    def broken(self, *a, **k):
        raise TwinError("disk full (simulated)")

    monkeypatch.setattr(Fig, "savefig", broken)
    with pytest.raises(TwinError, match="simulated"):
        plot(path, old)
    assert old.read_bytes() == b"old" and [p.name for p in tmp_path.iterdir()] == ["fig.png"]


def test_twin_plot_is_in_the_api(run_file, tmp_path):
    import twin

    path, _ = run_file
    info = twin.plot(path, tmp_path / "api.png", channels=["AC3"], size_px=(640, 480))
    assert info.channels == ("AC3",) and png_size(tmp_path / "api.png") == (640, 480)
    assert math.isfinite(info.seconds)


def test_long_curves_are_drawn_as_their_envelope():
    """A 1 M-sample curve with one impact sample: at most MAX_POINTS points, every group's min and max
    kept, so the impact's peak and the curve's range are drawn exactly."""
    from twin.viz.plot import MAX_POINTS, envelope

    t = np.arange(1_000_000) / 1e5
    y = np.sin(2 * np.pi * 3.0 * t)
    y[123_457] = 50.0
    tt, yy = envelope(t, y, MAX_POINTS)
    assert len(tt) == len(yy) <= MAX_POINTS
    assert yy.max() == 50.0 and yy.min() == y.min()
    assert np.all(np.diff(tt) >= 0) and tt[0] == t[0]
    short_t, short_y = envelope(t[:100], y[:100], MAX_POINTS)
    assert short_y is not None and np.array_equal(short_y, y[:100])  # short curves unchanged
