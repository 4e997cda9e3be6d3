"""twin view / twin.viz: run -> rerun recording (issue 6).

Short simulated runs (0.2 s) are converted and read back with rerun's own chunk reader and
CLI: the file verifies, holds the expected entities and sample counts, carries the run's
values and time stamps exactly, reconstructs the mechanism's pose consistently with the run,
and is reproducible; bad inputs fail with one line and leave no file.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest
from rerun.chunk import RrdReader

from conftest import short
from twin.channels import encoder_from_bench
from twin.cli import main
from twin.config import preset
from twin.kinematics import rod_angle as ideal_rod_angle
from twin.mcapfile import read_run, write_run
from twin.run import Channel, Run
from twin.simulation import simulate_run
from twin.viz import RerunWriter, ViewOptions, convert_file, file_recording_id, write_rrd
from twin.viz import blueprint as bp
from twin.viz.pose import ENCODER_COUNTS_PER_REV, poses, rod_angle
from twin.viz.scene import nice_magnification
from twin.viz.spectrum import amplitude_db, default_window

RERUN = str(Path(sys.executable).with_name("rerun"))
P = 100  # pose stride at 100 kHz / 1 kHz
SO = 10  # orbit stride at 100 kHz / 10 kHz


# ----------------------------------------------------------------------------- helpers
def read_rrd(path: Path) -> dict[str, dict]:
    """{entity: {"static": {col: value}, "time": int ns array, col: list of row values}}."""
    out: dict[str, dict] = {}
    batches: dict[str, list[pa.RecordBatch]] = {}
    for ch in RrdReader(str(path)).stream().to_chunks():
        rb = ch.to_record_batch()
        ent = out.setdefault(ch.entity_path, {"static": {}})
        if ch.is_static:
            for name in rb.schema.names:
                if not name.startswith("rerun."):
                    ent["static"][name] = rb.column(name).to_pylist()[-1]
        else:
            batches.setdefault(ch.entity_path, []).append(rb)
    for ent_path, rbs in batches.items():
        table = pa.Table.from_batches(rbs) if len({b.schema for b in rbs}) == 1 else pa.concat_tables(
            [pa.Table.from_batches([b]) for b in rbs], promote_options="default")
        t = table.column("time").cast(pa.int64()).to_numpy()
        order = np.argsort(t, kind="stable")
        ent = out[ent_path]
        ent["time"] = t[order]
        for name in table.column_names:
            if name != "time" and not name.startswith("rerun."):
                rows = table.column(name).to_pylist()
                ent[name] = [rows[i] for i in order]
    return out


def scalars(ent: dict) -> np.ndarray:
    return np.array(ent["Scalars:scalars"], dtype=float)


def cli(*argv: str) -> int:
    return main([str(a) for a in argv])


# ---------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def clearance_run() -> Run:
    """Table 4 test 12 (0.1 mm at B and C, 750 rpm), 0.2 s: impacts at both joints."""
    return simulate_run(short(preset(12), 0.2))


@pytest.fixture(scope="module")
def clearance_file(clearance_run: Run, tmp_path_factory) -> tuple[Path, Path, dict]:
    d = tmp_path_factory.mktemp("view")
    mcap = d / "run12.mcap"
    write_run(mcap, clearance_run)
    assert cli("view", mcap) == 0
    rrd = d / "run12.rrd"
    return mcap, rrd, read_rrd(rrd)


# -------------------------------------------------------------------------------- tests
def test_view_writes_verified_rrd_beside_input(clearance_file):
    mcap, rrd, _ = clearance_file
    assert rrd.is_file() and rrd.parent == mcap.parent
    res = subprocess.run([RERUN, "rrd", "verify", str(rrd)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in mcap.parent.iterdir()) == ["run12.mcap", "run12.rrd"]  # no temp files left


def test_rrd_holds_entities_counts_and_exact_values(clearance_run, clearance_file):
    _, _, rr_ = clearance_file
    run = clearance_run
    n = run.n
    expected = {"/bench/crank", "/bench/rod", "/bench/slider", "/bench/rod/orbit_B/journal",
                "/bench/rod/orbit_C/journal", "/bench/rod/contact_B", "/bench/rod/contact_C",
                "/orbit/B/journal", "/orbit/C/journal", "/orbit/B/clearance", "/orbit/C/clearance", "/config",
                *(f"/fft/AC{i}/sim" for i in range(1, 7)), *(f"/signals/{g}" for g in run.groups)}
    assert expected <= set(rr_)
    # every channel at its full rate, one series per channel of its group, exact values and times
    for group, names in run.groups.items():
        ent = rr_[f"/signals/{group}"]
        assert len(ent["time"]) == n
        np.testing.assert_array_equal(ent["time"], np.arange(n, dtype=np.int64) * 10_000)
        vals = scalars(ent)
        assert vals.shape == (n, len(names))
        for k, name in enumerate(names):
            np.testing.assert_array_equal(vals[:, k], run[name].astype(np.float64))
        assert len(ent["static"]["SeriesLines:names"]) == len(names)
    # poses at 1 kHz, orbits at 10 kHz
    for ent in ("/bench/crank", "/bench/rod", "/bench/slider", "/bench/rod/contact_C", "/bench/rod/orbit_C/journal"):
        assert len(rr_[ent]["time"]) == -(-n // P), ent
        np.testing.assert_array_equal(rr_[ent]["time"], np.arange(0, n, P, dtype=np.int64) * 10_000)
    for j in ("B", "C"):
        orbit = rr_[f"/orbit/{j}/journal"]
        assert len(orbit["time"]) == n // SO
        pos = np.array([r[0] for r in orbit["Points3D:positions"]])
        np.testing.assert_allclose(pos[:, 0], run[f"ecc_{j}_x"][::SO] * 1e6, rtol=1e-6, atol=1e-9)
        np.testing.assert_allclose(pos[:, 1], run[f"ecc_{j}_y"][::SO] * 1e6, rtol=1e-6, atol=1e-9)
    text = rr_["/config"]["static"]["TextDocument:text"][0]
    assert "[joints]" in text and "clearance_b_mm = 0.1" in text and "×" in text


def test_poses_close_the_loop_and_match_the_run(clearance_run, clearance_file):
    run = clearance_run
    p = poses(run)
    # the rod angle from the y equation makes the x of C' equal the simulated slider position
    np.testing.assert_allclose(p.slider_x, run["slider_position"], atol=1e-9)
    # eccentricities move the slider by up to ~c: visibly different from ideal kinematics
    ideal = ideal_rod_angle(p.theta, 0.12, 0.60)
    assert np.max(np.abs(p.phi - ideal)) > 1e-5
    _, _, rr_ = clearance_file
    slider = np.array([r[0] for r in rr_["/bench/slider"]["Transform3D:translation"]])
    np.testing.assert_allclose(slider[:, 0], run["slider_position"][::P], atol=1e-9)
    q = np.array([r[0] for r in rr_["/bench/crank"]["Transform3D:quaternion"]])
    ang = 2 * np.arctan2(q[:, 2], q[:, 3])
    np.testing.assert_allclose(np.angle(np.exp(1j * (ang - run["crank_angle"][::P]))), 0, atol=1e-6)
    # rod frame origin = B' = B - R(phi) e_B
    rod = np.array([r[0] for r in rr_["/bench/rod"]["Transform3D:translation"]])
    np.testing.assert_allclose(rod[:, :2], p.b_bush[::P], atol=1e-7)


def test_pose_from_encoder_and_ideal_kinematics():
    r, l, d = 0.12, 0.60, 0.01
    theta = np.linspace(-3, 10, 500)
    np.testing.assert_allclose(rod_angle(theta, r, l, d), ideal_rod_angle(theta, r, l, d), atol=1e-14)
    # with eccentricities: the loop closes in y exactly
    rng = np.random.default_rng(1)
    eb, ec = rng.uniform(-5e-5, 5e-5, (500, 2)), rng.uniform(-5e-5, 5e-5, (500, 2))
    phi = rod_angle(theta, r, l, d, eb, ec)
    rot = lambda a, v: np.stack([np.cos(a) * v[:, 0] - np.sin(a) * v[:, 1],  # noqa: E731
                                 np.sin(a) * v[:, 0] + np.cos(a) * v[:, 1]], axis=1)
    c_pin_y = r * np.sin(theta) - rot(phi, eb)[:, 1] + l * np.sin(phi) + rot(phi, ec)[:, 1]
    np.testing.assert_allclose(c_pin_y, d, atol=1e-15)
    assert np.all(np.cos(phi) > 0)
    # a recording with only encoder counts gives the same pose to within one count
    cfg = preset(3)
    counts = np.round(encoder_from_bench(theta) * ENCODER_COUNTS_PER_REV / (2 * np.pi))
    rec = Run.from_arrays(0.0, 1e5, {"encoder_counts": counts}, config=cfg, units={"encoder_counts": "count"},
                          groups={"encoder_counts": "daq"})
    p = poses(rec)
    assert np.max(np.abs(p.theta - theta)) <= np.pi / ENCODER_COUNTS_PER_REV + 1e-12


def test_contact_arrows_show_peak_force_of_each_window(clearance_run, clearance_file):
    run = clearance_run
    _, _, rr_ = clearance_file
    s = ViewOptions().force_scale_m_per_n
    for j in ("B", "C"):
        fn, ft = run[f"fn_{j}"].astype(float), run[f"ft_{j}"].astype(float)
        ent = rr_[f"/bench/rod/contact_{j}"]
        n_arrows = [len(v) for v in ent["Arrows3D:vectors"]]
        for k, count in enumerate(n_arrows):
            win = fn[max(0, k * P - P // 2): k * P + P // 2]
            assert count == (1 if win.max() > 0 else 0)
            if count:
                i = max(0, k * P - P // 2) + int(np.argmax(win))
                v = np.array(ent["Arrows3D:vectors"][k][0])
                assert np.hypot(v[0], v[1]) == pytest.approx(s * np.hypot(fn[i], ft[i]), rel=1e-5)
                assert ent["Arrows3D:labels"][k][0] == f"{fn[i]:.0f} N"
        assert sum(n_arrows) > 0


def test_streamed_chunks_give_the_same_recording(clearance_run, clearance_file, tmp_path):
    """Odd chunk sizes through the streaming sink = whole-run conversion (buffering is exact)."""
    run = clearance_run
    out = tmp_path / "stream.rrd"
    w = RerunWriter(out, run.config, recording_id="x", name="run12", t_start=0.0, t_end=run.duration_s)
    for i in range(0, run.n, 3337):
        w.write(run.slice(i, i + 3337))
    w.close(run.meta)
    a, b = clearance_file[2], read_rrd(out)
    assert set(a) == set(b)
    for ent in a:
        if ent == "/config":
            continue
        assert a[ent].keys() == b[ent].keys(), ent
        for col in a[ent]:
            if col == "time":
                np.testing.assert_array_equal(a[ent][col], b[ent][col])
            else:
                assert a[ent][col] == b[ent][col], (ent, col)


def test_same_input_same_recording(clearance_file, tmp_path):
    mcap, rrd, _ = clearance_file
    again = tmp_path / "again.rrd"
    assert cli("view", mcap, "--save", again) == 0
    res = subprocess.run([RERUN, "rrd", "compare", str(rrd), str(again)], capture_output=True, text=True)
    assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-2000:]
    ids = {e.recording_id for e in RrdReader(str(again)).recordings()}
    assert ids == {file_recording_id(mcap)}


def test_bench_recording_overlays_measured_on_simulated(clearance_run, tmp_path):
    """A recording/replay with measured accelerations, raw DAQ channels and only encoder counts."""
    run = clearance_run
    rng = np.random.default_rng(0)
    extra = [Channel(f"meas_AC{i}", "m/s^2", "meas_accel",
                     (run[f"AC{i}"] + rng.normal(0, 0.5, run.n)).astype(np.float32)) for i in range(1, 7)]
    extra += [Channel(f"volt_AC{i}", "V", "daq", (2.5 + run[f"AC{i}"] / 9.81 * 0.02).astype(np.float32))
              for i in range(1, 7)]
    counts = np.round(run["encoder_angle"] * ENCODER_COUNTS_PER_REV / (2 * np.pi))
    extra += [Channel("encoder_counts", "count", "daq", counts),
              Channel("motor_command", "V", "daq", np.full(run.n, 7.5, dtype=np.float32))]
    keep = [n for n in run.channels if n.startswith("AC") or n.startswith("ecc_") or n.startswith("fn_")]
    rec = run.select(keep).with_channels(extra)
    mcap = tmp_path / "replay.mcap"
    write_run(mcap, rec)
    out = convert_file(mcap)
    rr_ = read_rrd(out)
    assert {"/signals/meas_accel", "/signals/daq", "/fft/AC4/meas", "/fft/AC4/sim"} <= set(rr_)
    assert scalars(rr_["/signals/daq"]).shape == (run.n, 8)
    # pose from encoder counts: slider within a count's worth of the simulated slider position
    slider = np.array([r[0] for r in rr_["/bench/slider"]["Transform3D:translation"]])
    assert np.max(np.abs(slider[:, 0] - run["slider_position"][::P])) < 0.12 * 2 * np.pi / ENCODER_COUNTS_PER_REV
    # the accelerometer plots overlay simulated and recorded; raw volts go to their own tab
    back = read_run(mcap)
    blue = bp.default_blueprint(back.config, back.groups, back.channels, ("B", "C"), True, (0.1, 0.2),
                                [f"AC{i}" for i in range(1, 7)], ViewOptions())
    views = {v.name: v for v in _walk(blue.root_container)}
    ac4 = views["AC4 [m/s²]: sim (blue), rec (orange)"]
    assert sorted(ac4.contents) == ["/signals/accel", "/signals/meas_accel"]
    assert any(n.startswith("motor_command") for n in views)
    assert any(n.startswith("encoder_counts") for n in views)


def _walk(node):
    contents = getattr(node, "contents", None)
    if isinstance(contents, (list, tuple)) and contents and hasattr(contents[0], "id"):
        for c in contents:
            yield from _walk(c)
    else:
        yield node


def test_default_layout_titles_fit_and_say_units_and_colours(clearance_run):
    """Every plot title fits a plot of the right-hand tabs (bp.MAX_TITLE_CHARS), for a simulated run
    and for a replay (simulated, through the sensor chain, recorded), and carries a unit in
    brackets; a title naming several series names each one's colour, and those colours differ."""
    import rerun.blueprint as rrb

    from twin.viz.style import COLOUR_NAMES

    run = clearance_run
    replay = run.with_channels([Channel(f"{pre}AC{i}", "m/s^2", grp, run[f"AC{i}"]) for i in range(1, 7)
                                for pre, grp in (("sim_meas_", "sim_meas_accel"), ("meas_", "meas_accel"))])
    for r in (run, replay):
        blue = bp.default_blueprint(r.config, r.groups, r.channels, ("B", "C"), True, (0.1, 0.2),
                                    [n for n in r.channels if "AC" in n], ViewOptions())
        views = list(_walk(blue.root_container))
        plots = [v for v in views if isinstance(v, (rrb.TimeSeriesView, rrb.BarChartView))]
        assert len(plots) >= 16
        for v in plots:
            assert len(v.name) <= bp.MAX_TITLE_CHARS and "[" in v.name and "]" in v.name, v.name
            if ": " in v.name:  # "name [unit]: a (colour), b (colour)"
                named = re.findall(r"\((\w+)\)", v.name.split(": ", 1)[1])
                assert named and set(named) <= set(COLOUR_NAMES.values()) and len(set(named)) == len(named), v.name
        bench = [v for v in views if v.name.startswith("bench")]
        assert len(bench) == 1 and len(bench[0].name) <= 90
    titles = {v.name for v in views}
    assert {"AC4 [m/s²]: sim (blue), sim+chain (purple), rec (orange)",
            "AC4 [dB]: sim (blue), sim+chain (purple), rec (orange)"} <= titles
    assert {f"eccentricity {k} (rod frame) [m]: B (green), C (red)" for k in "xy"} <= titles


def test_ideal_run_has_no_orbits(tmp_path):
    run = simulate_run(short(preset(3), 0.05))
    out = write_rrd(run, tmp_path / "ideal.rrd", recording_id="ideal", name="ideal")
    rr_ = read_rrd(out)
    assert "/bench/rod" in rr_ and not any(e.startswith("/orbit") or "contact_" in e for e in rr_)
    phi_ideal = ideal_rod_angle(run["crank_angle"][::P], 0.12, 0.60)
    q = np.array([r[0] for r in rr_["/bench/rod"]["Transform3D:quaternion"]])
    np.testing.assert_allclose(2 * np.arctan2(q[:, 2], q[:, 3]), phi_ideal, atol=1e-6)


def test_magnification_makes_10_um_visible():
    m = nice_magnification(10e-6, ViewOptions().orbit_inset_radius_m)
    assert m == 5000 and 10e-6 * m == pytest.approx(0.05)  # a 10 µm clearance is drawn 50 mm wide
    assert nice_magnification(0.5e-3, 0.06) == 100
    assert nice_magnification(0.0, 0.06) == 1


def test_spectrum_reads_amplitude_and_default_windows():
    rate, f0 = 1e5, 1000.0
    t = np.arange(100_000) / rate
    f, db = amplitude_db(9.81 + 2.0 * np.sin(2 * np.pi * f0 * t), rate, 15_000)
    assert f[np.argmax(db)] == f0
    assert db.max() == pytest.approx(20 * np.log10(2.0 / 1e-3), abs=0.01)  # 2 m/s² = 66 dB re 1 mm/s²
    assert f.max() <= 15_000
    proto = preset(6).replace(**{"drive.program": "protocol", "simulation.duration_s": 0.0})
    assert default_window(proto, 0.0, 38.0) == (34.0, 35.0)
    assert default_window(preset(6), 0.0, 0.2) == pytest.approx((0.1, 0.2))


@pytest.mark.parametrize("argv, message", [
    (["view", "{d}/missing.mcap"], "no such file"),
    (["view", "{d}/notes.txt"], "expected a .mcap"),
    (["view", "{d}/broken.mcap"], "MCAP"),
    (["view", "{d}/good.mcap", "--save", "{d}/out.png"], "must end in .rrd"),
    (["view", "{d}/good.mcap", "--save", "{d}/nodir/out.rrd"], "does not exist"),
    (["view", "{d}/good.mcap", "--save", "{d}/adir.rrd"], "--save: {d}/adir.rrd is a directory"),
    (["view", "{d}/adir.rrd"], "expected a .mcap"),
    (["view", "{d}/good.mcap", "--screenshot", "{d}/shot.jpg"], "--screenshot: must end in .png"),
    (["view", "{d}/good.mcap", "--screenshot", "{d}/nodir/shot.png"], "--screenshot: directory"),
    (["view", "{d}/good.mcap", "--screenshot", "{d}/shot.png", "--wait", "-1"], "--wait: must be a finite number"),
    (["view", "{d}/good.mcap", "--screenshot", "{d}/shot.png", "--wait", "nan"], "--wait: must be a finite number"),
    (["view", "{d}/good.mcap", "--screenshot", "{d}/shot.png", "--at", "inf"], "--at: must be a finite time"),
    (["view", "{d}/good.mcap", "--at", "0.1"], "--at: applies to --screenshot only"),
    (["view", "{d}/good.mcap", "--wait", "5"], "--wait: applies to --screenshot only"),
    (["view", "{d}/good.mcap", "--window-size", "800x450"], "--window-size: applies to --screenshot only"),
    (["view", "{d}/good.mcap", "--screenshot", "{d}/shot.png", "--window-size", "16x9"],
     "--window-size: must be two whole numbers of pixels in 64..8192"),
    (["view", "{d}/good.mcap", "--fft-window", "0.5", "2.0"], "outside the run"),
    (["view", "{d}/good.mcap", "--fft-window", "0.1", "0.05"], "T0 < T1"),
])
def test_bad_inputs_give_one_line_errors_and_no_file(argv, message, clearance_file, tmp_path, capsys):
    mcap = clearance_file[0]
    (tmp_path / "notes.txt").write_text("x")
    (tmp_path / "broken.mcap").write_bytes(mcap.read_bytes()[:100_000])
    (tmp_path / "good.mcap").write_bytes(mcap.read_bytes())
    (tmp_path / "adir.rrd").mkdir()
    before = sorted(p.name for p in tmp_path.iterdir())
    assert cli(*[a.format(d=tmp_path) for a in argv]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("twin: error:") and message.format(d=tmp_path) in err and "\n" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written, no temp file


def test_simulate_streams_a_recording(tmp_path, capsys):
    out = tmp_path / "sim.rrd"
    assert cli("simulate", "--test", "12", "--duration", "0.05", "--set", "drive.ramp_s=0.01", "--no-out",
               "--no-progress", "--rerun", out) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    assert subprocess.run([RERUN, "rrd", "verify", str(out)], capture_output=True).returncode == 0
    rr_ = read_rrd(out)
    assert len(rr_["/signals/accel"]["time"]) == 5000
    assert len(rr_["/bench/rod"]["time"]) == 50 and len(rr_["/orbit/C/journal"]["time"]) == 500
    assert "real_time_factor" in rr_["/config"]["static"]["TextDocument:text"][0]
    assert list(tmp_path.iterdir()) == [out]


def test_simulate_rerun_rejects_bad_path(tmp_path, capsys):
    assert cli("simulate", "--duration", "0.01", "--no-out", "--rerun", tmp_path / "x.mcap") == 2
    assert "--rerun: must end in .rrd" in capsys.readouterr().err


# ------------------------------------------- what the machine needs: display, Vulkan driver
@pytest.fixture(scope="module")
def small_mcap(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("small")
    return write_run(d / "small.mcap", simulate_run(short(preset(3), 0.02)))


@pytest.fixture
def work(small_mcap, tmp_path) -> Path:
    """A folder holding only a copy of the small run file."""
    (tmp_path / "run.mcap").write_bytes(small_mcap.read_bytes())
    return tmp_path


def _one_line_error(capsys, *words: str) -> str:
    cap = capsys.readouterr()
    err = cap.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("twin: error: "), cap.err
    assert "Traceback" not in cap.err and "panicked" not in cap.err
    for w in words:
        assert w in err[0], (w, err[0])
    return err[0]


def _no_vulkan(monkeypatch, tmp_path: Path) -> None:
    """Vulkan ICD search pointed at empty folders, override variables removed."""
    import twin.viz.screenshot as shot

    empty = tmp_path / "empty-icd"
    empty.mkdir()
    for var in ("VK_DRIVER_FILES", "VK_ICD_FILENAMES", "VK_ADD_DRIVER_FILES"):
        monkeypatch.delenv(var, raising=False)
    for var in ("HOME", "XDG_CONFIG_HOME", "XDG_CONFIG_DIRS", "XDG_DATA_HOME", "XDG_DATA_DIRS"):
        monkeypatch.setenv(var, str(empty))
    monkeypatch.setattr(shot, "SYSTEM_ICD_DIRS", (str(empty),))


linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="display/Vulkan checks are for Linux")


@linux_only
def test_spawn_without_display_is_refused_before_converting(work, monkeypatch, capsys):
    for var in ("DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"):
        monkeypatch.delenv(var, raising=False)
    assert cli("view", work / "run.mcap", "--spawn") == 2
    _one_line_error(capsys, "--spawn: no display", "DISPLAY", "WAYLAND_DISPLAY")
    assert sorted(p.name for p in work.iterdir()) == ["run.mcap"]  # no .rrd, no temporary


@linux_only
@pytest.mark.parametrize("how", ["empty search folders", "VK_ICD_FILENAMES at nothing", "VK_DRIVER_FILES empty dir"])
def test_screenshot_without_vulkan_driver_is_refused_before_converting(how, work, monkeypatch, capsys):
    _no_vulkan(monkeypatch, work)
    if how == "VK_ICD_FILENAMES at nothing":
        monkeypatch.setenv("VK_ICD_FILENAMES", str(work / "missing_icd.json"))
    elif how == "VK_DRIVER_FILES empty dir":
        monkeypatch.setenv("VK_DRIVER_FILES", str(work / "empty-icd"))
    assert cli("view", work / "run.mcap", "--screenshot", work / "shot.png", "--wait", "0") == 2
    _one_line_error(capsys, "--screenshot: no Vulkan driver", "mesa-vulkan-drivers")
    assert sorted(p.name for p in work.iterdir()) == ["empty-icd", "run.mcap"]


def test_vulkan_driver_lookup(tmp_path, monkeypatch):
    import twin.viz.screenshot as shot

    _no_vulkan(monkeypatch, tmp_path)
    assert shot.vulkan_drivers() == []
    icd = tmp_path / "empty-icd" / "lvp_icd.x86_64.json"
    icd.write_text("{}")
    assert shot.vulkan_drivers() == [icd]  # found in the (patched) system folder
    monkeypatch.setenv("VK_ICD_FILENAMES", str(tmp_path / "other.json"))
    assert shot.vulkan_drivers() == []  # the override replaces the search
    monkeypatch.setenv("VK_ADD_DRIVER_FILES", str(icd))
    assert shot.vulkan_drivers() == [icd]


def test_viewer_message_is_one_line():
    from twin.viz.screenshot import viewer_message

    panic = ("\x1b[2m2026\x1b[0m INFO telemetry\n\nthread 'main' panicked at 'Failed to create render state: "
             "CustomNativeAdapterSelectionError(\"No graphics adapter\")'\negui_kittest/src/wgpu.rs:77\nstack backtrace:\n")
    assert viewer_message(panic) == 'Failed to create render state: CustomNativeAdapterSelectionError("No graphics adapter")'
    assert viewer_message("thread 'main' panicked at src/main.rs:3:5:\nno adapter\n") == "no adapter"
    assert viewer_message(b"INFO x\nError: winit EventLoopError: os error at /x/src/linux/mod.rs:788: Failed to open "
                          b"connection to X server\n") == "Error: winit EventLoopError: os error: Failed to open connection to X server"
    assert viewer_message("") == "no message"


def _fake_viewer(d: Path, body: str) -> Path:
    """A 'rerun' executable first on PATH that runs ``body`` (sh)."""
    bindir = d / "bin"
    bindir.mkdir()
    exe = bindir / "rerun"
    exe.write_text("#!/bin/sh\n" + body + "\n")
    exe.chmod(0o755)
    return bindir


@linux_only
def test_spawn_reports_a_viewer_that_exits_at_once(tmp_path, small_mcap, monkeypatch, capsys):
    import twin.commands.view as view

    bindir = _fake_viewer(tmp_path, 'echo "Error: winit EventLoopError: Failed to open connection to X server" >&2\nexit 1')
    monkeypatch.setenv("PATH", f"{bindir}{os.pathsep}{os.environ['PATH']}")
    monkeypatch.setenv("DISPLAY", ":97")
    monkeypatch.setattr(view, "SPAWN_CHECK_S", 5.0)
    out = tmp_path / "run.rrd"
    assert cli("view", small_mcap, "--save", out, "--spawn") == 2
    _one_line_error(capsys, "--spawn: the rerun viewer exited at once (status 1", "Failed to open connection to X server",
                    f"{out} is written")
    assert out.is_file()


@linux_only
def test_spawn_reports_open_only_when_the_viewer_keeps_running(tmp_path, small_mcap, monkeypatch, capsys):
    import twin.commands.view as view

    pidfile = tmp_path / "pid"
    bindir = _fake_viewer(tmp_path, f'echo $$ > "{pidfile}"\nexec sleep 30')
    monkeypatch.setenv("PATH", f"{bindir}{os.pathsep}{os.environ['PATH']}")
    monkeypatch.setenv("DISPLAY", ":97")
    monkeypatch.setattr(view, "SPAWN_CHECK_S", 0.5)
    try:
        assert cli("view", small_mcap, "--save", tmp_path / "run.rrd", "--spawn") == 0
        assert "opened the rerun viewer" in capsys.readouterr().out
    finally:
        if pidfile.exists():
            os.kill(int(pidfile.read_text()), signal.SIGTERM)


@linux_only
@pytest.mark.skipif(Path("/tmp/.X11-unix/X97").exists(), reason="an X server runs on :97")
def test_spawn_real_viewer_without_x_server(tmp_path, small_mcap, monkeypatch, capfd):
    monkeypatch.setenv("DISPLAY", ":97")
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_SOCKET", raising=False)
    # the wait ends when the viewer exits, so a long check costs nothing here; the default 1.5 s was
    # too short for the viewer to start and fail on a loaded machine (the test then saw it "open")
    import twin.commands.view as view
    monkeypatch.setattr(view, "SPAWN_CHECK_S", 60.0)
    assert cli("view", small_mcap, "--save", tmp_path / "run.rrd", "--spawn") == 2
    _one_line_error(capfd, "--spawn: the rerun viewer exited at once")


@linux_only
def test_screenshot_reports_a_viewer_that_panics(tmp_path, small_mcap, monkeypatch, capfd):
    """A registered driver whose library is missing: the real headless viewer panics (no adapter)."""
    icd = tmp_path / "broken_icd.json"
    icd.write_text('{"file_format_version": "1.0.0", "ICD": {"library_path": "/nonexistent/libvulkan_broken.so", '
                   '"api_version": "1.3.0"}}')
    monkeypatch.setenv("VK_ICD_FILENAMES", str(icd))
    monkeypatch.delenv("VK_DRIVER_FILES", raising=False)
    out, png = tmp_path / "run.rrd", tmp_path / "shot.png"
    assert cli("view", small_mcap, "--save", out, "--screenshot", png, "--wait", "20") == 2
    _one_line_error(capfd, "--screenshot: the headless viewer")  # file descriptors: the viewer and rerun's logger
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken_icd.json", "run.rrd"]  # no PNG, no temporary


def _has_vulkan() -> bool:
    from twin.viz.screenshot import vulkan_drivers

    return bool(vulkan_drivers())


@linux_only
@pytest.mark.skipif(not _has_vulkan(), reason="no Vulkan driver (Debian: mesa-vulkan-drivers) for the headless viewer")
def test_headless_screenshot_of_default_view(clearance_file, tmp_path, capsys):
    """A real screenshot (software Vulkan where there is no GPU) through the command line, in a small
    window: a PNG of that size whose plots are drawn: the simulated accelerations' blue in the
    right-hand tabs (3/5 of the width) and joint B's green contact force in the left column's plot
    below the orbits (62-77 % of the height). Taken before the view settled (--wait 0), the
    same picture had 54 and 0 such pixels; settled, 732 and 150."""
    from PIL import Image

    from twin.viz.style import JOINT_COLOUR, SIM_COLOUR

    mcap = clearance_file[0]
    png = tmp_path / "view.png"
    assert cli("view", mcap, "--save", tmp_path / "run.rrd", "--screenshot", png, "--at", "0.15", "--wait", "30",
               "--window-size", "800x450") == 0
    out = capsys.readouterr().out
    assert f"saved {png} in " in out and "(view settled)" in out, out
    img = np.asarray(Image.open(png).convert("RGB")).astype(int)
    assert img.shape == (450, 800, 3)

    def pixels(region: np.ndarray, colour) -> int:
        return int(np.sum(np.all(np.abs(region.reshape(-1, 3) - np.array(colour)) <= 12, axis=1)))

    blue, green = pixels(img[:, 330:], SIM_COLOUR), pixels(img[279:346, :320], JOINT_COLOUR["B"])
    assert blue > 300 and green > 50, (blue, green)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.rrd", "view.png"]  # no temporary left


def test_a_clearance_at_the_ground_pivot_is_drawn_on_the_frame(tmp_path):
    """Test 6 with 0.5 mm at A (reference engine, 0.2 s): the frame's bore, A's orbit inset and
    contact arrow live under /bench/frame (A's eccentricity is in the bench frame), the crank's
    transform carries the journal's offset e_A, and the rod's origin B' = e_A + r(cos θ, sin θ)
    − R(φ)e_B (here e_B = 0) follows from it."""
    cfg = preset(6).replace(**{"joints.clearance_a_mm": 0.5, "joints.clearance_c_mm": 0.0,
                               "simulation.engine": "reference"})
    run = simulate_run(short(cfg, 0.2))
    mcap = tmp_path / "a.mcap"
    write_run(mcap, run)
    assert cli("view", mcap) == 0
    rr_ = read_rrd(tmp_path / "a.rrd")
    assert {"/bench/frame/eye_A", "/bench/frame/orbit_A", "/bench/frame/orbit_A/journal", "/bench/frame/contact_A",
            "/bench/crank/pin_A", "/orbit/A/journal", "/orbit/A/clearance"} <= set(rr_)
    assert not any(k.startswith("/bench/rod/orbit_") for k in rr_)  # B and C are ball bearings here
    crank = np.array([r[0] for r in rr_["/bench/crank"]["Transform3D:translation"]])
    e_a = np.stack([run["ecc_A_x"], run["ecc_A_y"]], axis=1)[::P]
    np.testing.assert_allclose(crank[:, :2], e_a, atol=1e-12)
    assert np.max(np.hypot(*e_a.T)) > 0.9 * cfg.joints.radial_m("A")  # the journal does move in the bore
    theta = run["crank_angle"][::P]
    rod = np.array([r[0] for r in rr_["/bench/rod"]["Transform3D:translation"]])
    r = cfg.bodies.crank.length_m
    np.testing.assert_allclose(rod[:, :2], e_a + r * np.stack([np.cos(theta), np.sin(theta)], axis=1), atol=1e-9)
