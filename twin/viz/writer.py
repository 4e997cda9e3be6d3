"""Streaming conversion of a run (whole, or chunk by chunk) into a rerun ``.rrd`` recording.

:class:`RerunWriter` is a sink like :class:`twin.mcapfile.RunWriter`: ``write(chunk)`` for
consecutive chunks of one run, then ``close(meta, summary)``; ``abort()`` on failure. The
file is written under a temporary name beside the target and renamed once the recording is
flushed and its footer written, so a failed conversion never leaves a partial ``.rrd``.

Entity paths (see :mod:`twin.viz.scene` for ``/bench``; a run of the spatial mechanism,
``spatial.enabled``, draws it with :mod:`twin.viz.spatial_view` instead: its insets and arrows
under the sockets' bodies, its orbits in 3-D):

* ``/signals/<group>``: every channel of the run at its full rate, one ``Scalars`` series per
  channel of the group (MCAP topic) in run order, sent with ``send_columns`` in blocks of
  ``ViewOptions.block_rows`` rows on the ``time`` timeline (simulation time; recordings: time
  since start). One entity per group, not per channel: each row costs a row id and a time
  stamp, so grouping halves the file and the conversion time; the blueprint's plots pick
  their series with ``visible_series`` overrides;
* ``/bench/crank``, ``/bench/rod``, ``/bench/slider``: body poses (``Transform3D``) at
  ``pose_rate_hz``; ``/bench/rod/orbit_J/journal``: magnified journal centre;
  ``/bench/rod/contact_J``: contact force on the pin, peak of each pose window (for a clearance
  at the ground pivot A both under ``/bench/frame``, whose frame A's eccentricity is given in);
* ``/bench/rod/bent`` (a flexible-structure run with the channel group ``structure``): the rod's centre line
  bent by its mid-span deflection ``rod_deflection`` (drawn as a half sine between the eyes) and stretched by
  ``rod_stretch``, both magnified :data:`ROD_DEFLECTION_MAGNIFICATION` times, on the front face;
* ``/orbit/J/clearance`` and ``/orbit/J/journal``: the journal-centre orbit in the rod frame
  (A: bench frame) in micrometres at ``orbit_rate_hz`` (red while in contact);
* ``/fft/<ACi>/sim``, ``/fft/<ACi>/meas`` (recorded ``meas_ACi``) and ``/fft/<ACi>/sim_chain``
  (a replay's ``sim_meas_ACi``): amplitude spectra of the FFT window (static);
* ``/config``: the configuration, run metadata and summary as a markdown document.

Timeline values are integers (nanoseconds from t = 0), and the recording id, name and every
value derive from the input only: converting the same input twice gives recordings with the
same content (``rerun rrd compare`` passes); the bytes differ only in rerun's internal
chunk and row ids, which it draws at random.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr

from twin.config import ACCELEROMETERS, JOINTS, BenchConfig
from twin.errors import TwinError
from twin.util import check_not_link, remove_stale_temps, temp_path
from twin.run import Channel, Run
from twin.viz import blueprint as bp
from twin.viz import scene
from twin.viz import spatial_view
from twin.viz.options import ViewOptions
from twin.viz.pose import poses
from twin.viz.spectrum import DB_REF_MPS2, amplitude_db, check_window, default_window
from twin.viz.style import CHAIN_COLOUR, MEAS_COLOUR, SIM_COLOUR, series_colour, series_label, series_width

APP_ID = "twin"
TIMELINE = "time"

#: magnification of the flexible rod's deflection and stretch in the 3-D view (a 10 µm deflection: 10 mm)
ROD_DEFLECTION_MAGNIFICATION = 1000
#: points of the drawn bent centre line
ROD_LINE_POINTS = 25

#: free space a .rrd needs before rerun's writer starts [bytes] (its blueprint and first chunks)
MIN_FREE_BYTES = 1 << 20
#: rows of signals sent between two flushes of the recording stream (bounds its queue)
FLUSH_ROWS = 200_000
_ANGLE_SOURCES = ("crank_angle", "encoder_angle", "encoder_counts")


def signal_path(group: str) -> str:
    """Entity path of a channel group's time series (one series per channel, in run order)."""
    return f"/signals/{group}"


def times_ns(t0: float, rate_hz: float, gidx: np.ndarray) -> np.ndarray:
    """Integer nanosecond times of the samples with global indices ``gidx`` (exact integer
    arithmetic when t0 = 0 and the period is a whole number of nanoseconds, e.g. 100 kHz)."""
    gidx = np.asarray(gidx, dtype=np.int64)
    if t0 == 0.0 and 1e9 % rate_hz == 0:
        return gidx * int(1e9 // rate_hz)
    return np.round((t0 + gidx / rate_hz) * 1e9).astype(np.int64)


def _tcol(ns: np.ndarray) -> rr.TimeColumn:
    return rr.TimeColumn(TIMELINE, duration=ns.astype("timedelta64[ns]"))


_take = spatial_view.take  # the pose windows' padded slices


class RerunWriter:
    """Write a run as a rerun recording with a default blueprint (see module docstring).

    Args:
        path: target ``.rrd`` file (its directory must exist).
        config: the run's configuration (geometry, clearances, orientation, FFT window);
            None = the defaults (bench recordings without a stored configuration).
        recording_id: rerun recording id (derive it from the input for reproducible files).
        name: recording name shown in the viewer.
        options: :class:`ViewOptions`.
        t_start, t_end: time span the run will cover [s] (for the default FFT window);
            t_end defaults to ``config.duration_s``.
        source: description of the input, shown in the configuration document.
    """

    def __init__(self, path: str | Path, config: BenchConfig | None, *, recording_id: str, name: str,
                 options: ViewOptions = ViewOptions(), t_start: float = 0.0, t_end: float | None = None,
                 source: str = ""):
        self.path = Path(path)
        if self.path.suffix.lower() != ".rrd":
            raise TwinError(f"{self.path}: a rerun recording must end in .rrd")
        if not self.path.parent.is_dir():
            raise TwinError(f"{self.path}: directory {self.path.parent} does not exist")
        self.cfg = config or BenchConfig()
        self.opts = options
        self.name = name
        self.recording_id = recording_id
        self.source = source
        self.t_start = float(t_start)
        self.t_end = float(t_end if t_end is not None else t_start + self.cfg.duration_s)
        self._tmp = temp_path(self.path, keep_suffix=True)  # rerun wants the .rrd suffix
        self.rec: rr.RecordingStream | None = None
        self._n = 0  # samples written so far
        self._t0: float | None = None
        self._rate: float | None = None
        self._channels: dict[str, Channel] = {}
        self._buf: dict[str, np.ndarray] = {}
        self._buf_g0 = 0  # global index of the buffer's first sample
        self._next_pose = 0  # index k of the next pose (global sample k * P)
        self._next_orbit = 0  # global index of the next orbit sample
        self._fft_parts: dict[str, list[np.ndarray]] = {}
        self._fft_window: tuple[float, float] | None = None
        self._scene: scene.SceneInfo | None = None
        self._has_pose = False
        self._joints: tuple[str, ...] = ()
        self._spatial = bool(self.cfg.spatial.enabled)  # S002's mechanism: twin.viz.spatial_view
        self._closed = False
        self._pending_rows = 0

    # ------------------------------------------------------------------ setup
    def _start(self, chunk: Run) -> None:
        self._t0, self._rate = chunk.t0, chunk.rate_hz
        self._channels = {k: Channel(c.name, c.unit, c.group, c.data[:0]) for k, c in chunk.channels.items()}
        self._groups = chunk.groups
        rate = chunk.rate_hz
        so = max(1, int(round(rate / self.opts.orbit_rate_hz)))
        self._orbit_stride = so
        self._pose_stride = so * max(1, int(round(rate / self.opts.pose_rate_hz / so)))
        self._has_pose = any(a in chunk for a in _ANGLE_SOURCES)
        self._joints = tuple(j for j in JOINTS if f"ecc_{j}_x" in chunk and f"ecc_{j}_y" in chunk)
        fft_names = [n for a in ACCELEROMETERS for n in (a, f"sim_meas_{a}", f"meas_{a}") if n in chunk]
        if fft_names:
            w = self.opts.fft_window_s or default_window(self.cfg, self.t_start, self.t_end)
            check_window(w, self.t_start, self.t_end, rate)
            self._fft_window = (float(w[0]), float(w[1]))
            self._fft_parts = {n: [] for n in fft_names}
        elif self.opts.fft_window_s is not None:  # it would be accepted and ignored
            raise TwinError("this file has no accelerations in m/s² to take spectra of (a bench recording holds the "
                            "DAQ's volts: 'twin plot' draws its calibrated spectra); leave it out",
                            field="fft_window_s")

        blueprint = bp.default_blueprint(self.cfg, self._groups, self._channels, self._joints, self._has_pose,
                                         self._fft_window, fft_names, self.opts)
        remove_stale_temps(self.path)
        # rerun's save() blocks for good when its very first write (the blueprint) fails; a disk without
        # room for it is refused here (a disk that fills later makes the SDK raise, reported in close())
        free = shutil.disk_usage(self._tmp.parent).free
        if free < MIN_FREE_BYTES:
            raise TwinError(f"{self.path}: cannot write (no space left on the device: {free} bytes free)")
        rec = rr.RecordingStream(APP_ID, recording_id=self.recording_id, send_properties=False)
        rec.set_log_time_enabled(False)
        rec.set_log_tick_enabled(False)
        rec.save(self._tmp, default_blueprint=blueprint)
        rec.send_recording_name(self.name)
        self.rec = rec
        for group, names in self._groups.items():
            chans = [self._channels[n] for n in names]
            rec.log(signal_path(group), rr.SeriesLines(names=[series_label(c) for c in chans],
                                                       colors=[series_colour(c) for c in chans],
                                                       widths=[series_width(c) for c in chans]), static=True)
        if self._has_pose:
            draw = spatial_view.log_static_scene if self._spatial else scene.log_static_scene
            self._scene = draw(rec, self.cfg, self.opts.orbit_inset_radius_m)
            if self._joints:
                rec.log("/orbit", rr.ViewCoordinates.RIGHT_HAND_Y_UP, static=True)
            for j in self._joints:
                c = self.cfg.joints.radial_m(j)
                if c <= 0:
                    raise TwinError(f"run has eccentricities at {j} but its configuration has no clearance there")
                if self._spatial:
                    spatial_view.log_orbit_clearance(rec, j, c * 1e6)
                    continue
                rec.log(f"/orbit/{j}/clearance", rr.LineStrips3D(
                    [scene.circle(c * 1e6)], colors=[scene.C_ORBIT], radii=[c * 1e6 / 150]), static=True)
                rec.log(f"/orbit/{j}/axes", rr.Arrows3D(
                    origins=[(0, 0, 0), (0, 0, 0)], vectors=[(c * 1e6 * 0.25, 0, 0), (0, c * 1e6 * 0.25, 0)],
                    colors=[(200, 60, 60), (60, 160, 60)], radii=[c * 1e6 / 200] * 2), static=True)

    # ------------------------------------------------------------------ write
    def write(self, chunk: Run) -> None:
        """Append the next chunk of the run (same channels and rate as the first)."""
        if self._closed:
            raise TwinError("RerunWriter: write after close")
        if chunk.n == 0:
            return
        if self.rec is None:
            self._start(chunk)
        elif chunk.groups != self._groups or chunk.rate_hz != self._rate:
            raise TwinError("RerunWriter: chunk channels or rate differ from the first chunk")
        self._send_signals(chunk)
        self._collect_fft(chunk)
        if self._has_pose:
            self._buffer(chunk)
            self._emit_decimated(final=False)
        self._n += chunk.n

    def _send_signals(self, chunk: Run) -> None:
        rec, block = self.rec, self.opts.block_rows
        assert rec is not None
        for i in range(0, chunk.n, block):
            m = min(block, chunk.n - i)
            tcol = _tcol(times_ns(self._t0, self._rate, np.arange(self._n + i, self._n + i + m)))
            for group, names in self._groups.items():
                block_arr = np.empty((m, len(names)), dtype=np.float64)
                for k, name in enumerate(names):
                    block_arr[:, k] = chunk[name][i:i + m]
                rec.send_columns(signal_path(group), indexes=[tcol], columns=rr.Scalars.columns(scalars=block_arr))
            self._pending_rows += m
            if self._pending_rows >= FLUSH_ROWS:
                rec.flush()  # back-pressure: without it the SDK queues the whole run in memory
                self._pending_rows = 0

    def _collect_fft(self, chunk: Run) -> None:
        if not self._fft_parts:
            return
        t0, t1 = self._fft_window
        i0 = int(np.ceil((t0 - self._t0) * self._rate - 1e-9)) - self._n
        i1 = int(np.ceil((t1 - self._t0) * self._rate - 1e-9)) - self._n
        a, b = max(i0, 0), min(i1, chunk.n)
        if b > a:
            for n in self._fft_parts:
                self._fft_parts[n].append(np.asarray(chunk[n][a:b], dtype=float))

    # ------------------------------------------------------ decimated (poses)
    def _needed(self, chunk: Run) -> list[str]:
        names = [next(a for a in _ANGLE_SOURCES if a in chunk)]
        if self._spatial:
            names += [n for n in ("crank_angle", "slider_position") if n in chunk and n not in names]
        names += [n for n in ("rod_deflection", "rod_stretch") if n in chunk and not self._spatial]
        for j in self._joints:
            names += [f"ecc_{j}_x", f"ecc_{j}_y"] + [f"ecc_{j}_z"] * (self._spatial and f"ecc_{j}_z" in chunk) + [f"{p}_{j}" for p in ("pen", "fn", "ft") if f"{p}_{j}" in chunk]
        return names

    def _buffer(self, chunk: Run) -> None:
        for name in self._needed(chunk):
            new = np.asarray(chunk[name])
            self._buf[name] = np.concatenate([self._buf[name], new]) if name in self._buf else new

    def _emit_decimated(self, final: bool) -> None:
        P, so = self._pose_stride, self._orbit_stride
        h = P // 2
        g0 = self._buf_g0
        buf_end = g0 + len(next(iter(self._buf.values())))
        total = buf_end  # samples seen so far
        # poses whose window [kP - h, kP - h + P) is complete (or, at the end, whose sample exists)
        k_a = self._next_pose
        k_b = (total - 1) // P + 1 if final else max(k_a, (buf_end - P + h) // P + 1)
        if k_b > k_a:
            self._emit_poses(k_a, k_b, g0, final)
            self._next_pose = k_b
        # orbit samples available so far
        o_end = buf_end if final else buf_end - (buf_end % so)
        if o_end > self._next_orbit:
            self._emit_orbit(self._next_orbit, o_end, g0)
            self._next_orbit = o_end + ((-o_end) % so)
        keep_from = min(self._next_pose * P - h, self._next_orbit)
        drop = max(0, keep_from - g0)
        if drop:
            self._buf = {k: v[drop:] for k, v in self._buf.items()}
            self._buf_g0 = g0 + drop

    def _buf_run(self) -> Run:
        chans = {k: Channel(k, self._channels[k].unit, self._channels[k].group, v) for k, v in self._buf.items()}
        return Run(self._t0, self._rate, chans, self.cfg)

    def _emit_poses(self, k_a: int, k_b: int, g0: int, final: bool) -> None:
        rec, P = self.rec, self._pose_stride
        h = P // 2
        K = k_b - k_a
        gidx = np.arange(k_a, k_b, dtype=np.int64) * P
        local = gidx - g0
        tcol = _tcol(times_ns(self._t0, self._rate, gidx))
        if self._spatial:
            sp = spatial_view.spatial_poses(self._buf_run(), local, self.cfg)
            spatial_view.emit_poses(rec, tcol, sp, self._scene, self._joints, self._buf, local, k_a * P - h - g0, P,
                                    self.cfg, self.opts.force_scale_m_per_n)
            return
        p = poses(self._buf_run(), local, self.cfg)
        z = np.zeros(K)
        half = lambda a: np.stack([np.zeros(K), np.zeros(K), np.sin(a / 2), np.cos(a / 2)], axis=1)  # noqa: E731
        rec.send_columns("/bench/crank", indexes=[tcol], columns=rr.Transform3D.columns(
            translation=np.stack([p.e_a[:, 0], p.e_a[:, 1], z], axis=1), quaternion=half(p.theta)))
        rec.send_columns("/bench/rod", indexes=[tcol], columns=rr.Transform3D.columns(
            translation=np.stack([p.b_bush[:, 0], p.b_bush[:, 1], z], axis=1), quaternion=half(p.phi)))
        rec.send_columns("/bench/slider", indexes=[tcol], columns=rr.Transform3D.columns(
            translation=np.stack([p.c_pin[:, 0], p.c_pin[:, 1], z], axis=1), quaternion=half(np.zeros(K))))
        sc = self._scene
        assert sc is not None
        if "rod_deflection" in self._buf:
            self._emit_bent_rod(tcol, local, sc.front_z)
        for j in self._joints:
            cx, cy = sc.joint_centres[j]
            e = {"A": p.e_a, "B": p.e_b, "C": p.e_c}[j]
            parent = scene.joint_parent(j)
            m = sc.magnification[j]
            pen = self._buf.get(f"pen_{j}")
            fn = self._buf.get(f"fn_{j}")
            inc = (pen[local] > 0) if pen is not None else (fn[local] > 0) if fn is not None else np.zeros(K, bool)
            pos = np.stack([cx + m * e[:, 0], cy + m * e[:, 1], np.full(K, sc.front_z)], axis=1)
            colours = np.where(inc[:, None], np.array(scene.C_CONTACT), np.array(scene.C_ORBIT)).astype(np.uint8)
            rec.send_columns(f"{parent}/orbit_{j}/journal", indexes=[tcol], columns=rr.Points3D.columns(
                positions=pos, colors=colours, radii=np.full(K, 0.006, dtype=np.float32)))
            if fn is None:
                continue
            # peak force within each pose window [kP - h, kP - h + P)
            start = k_a * P - h - g0
            f_win = _take(fn, start, K * P, -np.inf).reshape(K, P)
            j_pk = np.argmax(f_win, axis=1)
            f_pk = f_win[np.arange(K), j_pk]
            idx_pk = np.clip(start + np.arange(K) * P + j_pk, 0, len(fn) - 1)
            ex, ey = self._buf[f"ecc_{j}_x"][idx_pk], self._buf[f"ecc_{j}_y"][idx_pk]
            ft = self._buf.get(f"ft_{j}")
            ftv = ft[idx_pk].astype(float) if ft is not None else np.zeros(K)
            norm = np.hypot(ex, ey)
            on = (f_pk > 0) & (norm > 0)
            nx, ny = np.where(on, ex / np.where(norm > 0, norm, 1), 0), np.where(on, ey / np.where(norm > 0, norm, 1), 0)
            ri = self.cfg.joints.bushing_radius_m(j)
            s = self.opts.force_scale_m_per_n
            fx, fy = -f_pk * nx - ftv * ny, -f_pk * ny + ftv * nx  # force on the pin: -fn n + ft (z × n)
            org = np.stack([cx + ri * nx, cy + ri * ny, np.full(K, sc.front_z)], axis=1)[on]
            vec = np.stack([s * fx, s * fy, np.zeros(K)], axis=1)[on]
            labels = [f"{f:.0f} N" for f in f_pk[on]]
            lengths = on.astype(np.int32)
            rec.send_columns(f"{parent}/contact_{j}", indexes=[tcol], columns=rr.Arrows3D.columns(
                origins=org, vectors=vec, labels=labels, colors=np.tile(np.array(scene.C_CONTACT, np.uint8),
                                                                        (int(on.sum()), 1)),
                radii=np.full(int(on.sum()), 0.002, dtype=np.float32)).partition(lengths))

    def _emit_bent_rod(self, tcol, local: np.ndarray, z: float) -> None:
        """The flexible rod's centre line in the rod frame (module docstring: ``/bench/rod/bent``)."""
        m, L = ROD_DEFLECTION_MAGNIFICATION, self.cfg.bodies.rod.length_m
        xi = np.linspace(0.0, 1.0, ROD_LINE_POINTS)
        w = self._buf["rod_deflection"][local].astype(float)
        u = self._buf["rod_stretch"][local].astype(float) if "rod_stretch" in self._buf else np.zeros(len(local))
        x = (L + m * u)[:, None] * xi[None, :]
        y = m * w[:, None] * np.sin(np.pi * xi)[None, :]
        pts = np.stack([x, y, np.full_like(x, z)], axis=2).reshape(-1, 3)
        self.rec.send_columns("/bench/rod/bent", indexes=[tcol], columns=rr.LineStrips3D.columns(
            strips=[p for p in pts.reshape(len(local), ROD_LINE_POINTS, 3)],
            colors=np.tile(np.array(scene.C_CONTACT, np.uint8), (len(local), 1)),
            radii=np.full(len(local), 0.0015, dtype=np.float32)).partition(np.ones(len(local), dtype=np.int32)))

    def _emit_orbit(self, g_a: int, g_b: int, g0: int) -> None:
        rec, so = self.rec, self._orbit_stride
        gidx = np.arange(g_a + ((-g_a) % so), g_b, so, dtype=np.int64)
        if len(gidx) == 0:
            return
        local = gidx - g0
        tcol = _tcol(times_ns(self._t0, self._rate, gidx))
        for j in self._joints:
            ex, ey = self._buf[f"ecc_{j}_x"][local], self._buf[f"ecc_{j}_y"][local]
            pen = self._buf.get(f"pen_{j}")
            fn = self._buf.get(f"fn_{j}")
            inc = (pen[local] > 0) if pen is not None else (fn[local] > 0) if fn is not None else np.zeros(len(local), bool)
            colours = np.where(inc[:, None], np.array(scene.C_CONTACT), np.array(scene.C_FREE)).astype(np.uint8)
            c_um = self.cfg.joints.radial_m(j) * 1e6
            ez = self._buf[f"ecc_{j}_z"][local] if f"ecc_{j}_z" in self._buf else np.zeros(len(local))
            rec.send_columns(f"/orbit/{j}/journal", indexes=[tcol], columns=rr.Points3D.columns(
                positions=np.stack([ex * 1e6, ey * 1e6, ez * 1e6], axis=1), colors=colours,
                radii=np.full(len(local), c_um / 40, dtype=np.float32)))

    # ------------------------------------------------------------------ close
    def close(self, meta: dict[str, Any] | None = None, summary: dict[str, Any] | None = None) -> Path:
        """Finish the recording (spectra, configuration document), flush, rename into place."""
        if self._closed:
            return self.path
        if self.rec is None:
            raise TwinError("RerunWriter: no samples were written")
        try:
            if self._has_pose and self._buf:
                self._emit_decimated(final=True)
            self._log_spectra()
            self.rec.log("/config", rr.TextDocument(self._document(meta, summary), media_type=rr.MediaType.MARKDOWN),
                         static=True)
            self.rec.flush()
            self.rec.disconnect()
            self._closed = True
            if not self._tmp.is_file() or self._tmp.stat().st_size == 0:
                raise TwinError(f"{self.path}: rerun wrote no data")
            try:
                check_not_link(self.path)
                os.replace(self._tmp, self.path)
            except OSError as err:
                raise TwinError(f"{self.path}: cannot write ({err.strerror})") from None
        except RuntimeError as err:  # rerun's file writer stopped (a full disk): name the file, one line
            self.abort()
            raise TwinError(f"{self.path}: cannot write (rerun: {' '.join(str(err).split())[:200]})") from None
        except BaseException:
            self.abort()
            raise
        return self.path

    def abort(self) -> None:
        """Drop the recording: disconnect and delete the temporary file."""
        self._closed = True
        if self.rec is not None:
            try:
                self.rec.disconnect()
            except Exception:  # noqa: BLE001 - best effort on the error path
                pass
        self._tmp.unlink(missing_ok=True)

    def __enter__(self) -> "RerunWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None:
            self.abort()

    def _log_spectra(self) -> None:
        if not self._fft_parts:
            return
        t0, t1 = self._fft_window
        for name, parts in self._fft_parts.items():
            x = np.concatenate(parts) if parts else np.zeros(0)
            if len(x) < 2:
                continue
            f, db = amplitude_db(x, self._rate, self.opts.fft_max_hz)
            if name.startswith("meas_"):
                sensor, kind, colour = name[5:], "meas", MEAS_COLOUR
            elif name.startswith("sim_meas_"):
                sensor, kind, colour = name[9:], "sim_chain", CHAIN_COLOUR
            else:
                sensor, kind, colour = name, "sim", SIM_COLOUR
            self.rec.log(f"/fft/{sensor}/{kind}", rr.BarChart(db.astype(np.float32), abscissa=f, color=colour),
                         static=True)

    def _document(self, meta: dict[str, Any] | None, summary: dict[str, Any] | None) -> str:
        cfg = self.cfg
        lines = [f"# {self.name}", ""]
        if self.source:
            lines += [f"Source: `{self.source}`", ""]
        lines += [f"- samples: {self._n} at {self._rate:g} Hz ({self._n / self._rate:.3f} s from t0 = {self._t0:g} s)",
                  f"- channels: {', '.join(self._channels)}",
                  f"- 3-D poses at {self._rate / self._pose_stride:g} Hz, orbits at {self._rate / self._orbit_stride:g} Hz,"
                  f" signals at {self._rate:g} Hz"]
        if self._scene is not None:
            for j, m in self._scene.magnification.items():
                lines.append(f"- joint {j}: radial clearance {self._scene.radial[j] * 1e6:g} µm, orbit inset "
                             f"magnified ×{m} in the 3-D view")
            lines.append(f"- contact force arrows: {self.opts.force_scale_m_per_n * 1e3 * 1000:g} mm per kN, "
                         "peak of each pose window")
        if self._fft_window is not None:
            t0, t1 = self._fft_window
            lines.append(f"- spectra: {t0:g}–{t1:g} s, Hann window, amplitude in dB re {DB_REF_MPS2 * 1e3:g} mm/s² "
                         "(floored at 0 dB)")
        lines += ["", "## Configuration", "", "```toml", cfg.to_toml().rstrip(), "```"]
        if summary:
            lines += ["", "## Summary", "", "```json", json.dumps(summary, indent=2, default=str), "```"]
        if meta:
            lines += ["", "## Run metadata", "", "```json", json.dumps(meta, indent=2, default=str), "```"]
        return "\n".join(lines) + "\n"
