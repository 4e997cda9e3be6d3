"""Static figures of a run, a bench recording or a replay (``twin plot``): matplotlib, no GPU, no display.

One figure, drawn from the twin's own readers and spectrum code:

* **channels over a time window**, one panel each (default: the accelerometers AC1–AC6 and the
  contact forces at the clearance joints where the file has them). In a replay, a recorded
  ``meas_ACi`` panel also draws its simulated counterpart ``sim_meas_ACi`` (the pair
  ``twin replay`` compares: both through the sensor chain and the calibration);
* with ``spectrum``: beside each panel its single-sided Hann amplitude spectrum over the same window
  (:func:`twin.signals.hann_spectrum`, mean removed; log frequency, log magnitude), with the crank
  rate's harmonics as dashed lines and the bands of interest of the bench paper shaded
  (:data:`twin.bench_replay.DEFAULT_BANDS_HZ`, or those a replay's report used). The crank rate is
  the mean over the window of the crank angle's rate (the crank angle of a run, the encoder angle
  or counts of a recording);
* the **journal orbits** of the clearance joints (eccentricity x/y in µm inside the circle of the
  radial clearance, the samples in contact in red) when the file has joint channels (simulated runs
  and replays; a bench recording has none: the figure says so).

Sources: a run file (``twin simulate``), a bench recording (``twin import``: the volts are
calibrated with the recording's calibration into ``meas_ACi`` [m/s²]), a replay folder or its
``replay.mcap`` (``twin replay``), or a :class:`~twin.run.Run` in memory. The figure is a
:class:`matplotlib.figure.Figure` rendered by Agg (no pyplot state, no display); :func:`plot` writes
the PNG to a temporary file and renames it into place (:func:`twin.util.atomic_write_bytes`).
:func:`draw` draws into any figure or subfigure (``docs/make_figure.py`` puts it beside a sketch
of the bench for the README's picture).
"""

from __future__ import annotations

import fnmatch
import io
import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from twin.config import ACCELEROMETERS, JOINTS, BenchConfig
from twin.errors import RecordingError, TwinError
from twin.run import Run
from twin.util import check_size_px, show

#: default time window: the last this many seconds of the run [s]
DEFAULT_WINDOW_S = 0.4
#: crank-rate harmonics marked on the spectra
HARMONICS = 10
#: highest frequency of the spectra [Hz] (the bench paper's Fig. 15 spans 0–5 kHz)
SPECTRUM_MAX_HZ = 5000.0
#: a window turning the crank less than this [rev] marks no harmonics (the crank is at rest)
MIN_TURNS = 0.25
#: resolution of the PNG [dots per inch]; sizes are given in pixels
DPI = 100
#: most points a curve is drawn with; longer ones are reduced to the min and max of each group of
#: samples (time series: every peak stays visible) or the peak of each group of bins (spectra)
MAX_POINTS = 20_000
#: the replay folder's run file
REPLAY_RUN = "replay.mcap"

_SIM = tuple(c / 255 for c in (31, 119, 180))    # twin.viz.style.SIM_COLOUR: simulated, blue
_MEAS = tuple(c / 255 for c in (255, 127, 14))   # twin.viz.style.MEAS_COLOUR: recorded, orange


@dataclass(frozen=True)
class PlotSource:
    """What :func:`draw` draws from (:func:`load`).

    Attributes:
        kind: ``"run"`` (simulated), ``"recording"`` (bench recording) or ``"replay"``.
        name: shown in the title (file stem, or ``"run"`` for a run in memory).
        run: the channels; a recording's calibrated ``meas_ACi`` are added to its volts.
        bands_hz: frequency bands shaded on the spectra [Hz].
        notes: lines about the data shown under the title (repairs of a recording).
    """

    kind: str
    name: str
    run: Run
    bands_hz: tuple[tuple[float, float], ...]
    notes: tuple[str, ...] = ()

    @property
    def config(self) -> BenchConfig | None:
        return self.run.config

    @property
    def span_s(self) -> tuple[float, float]:
        """First sample's time and the end of the last sample's period [s]."""
        return (self.run.t0, self.run.t0 + self.run.n / self.run.rate_hz)


@dataclass(frozen=True)
class PlotInfo:
    """What a figure shows (returned by :func:`draw` and :func:`plot`).

    Attributes:
        kind: the source's kind (:class:`PlotSource`).
        window_s: the time window of the panels and spectra [s].
        channels: the panels' channels, top to bottom.
        overlays: panel channel -> the simulated channel drawn over it (a replay's pairs).
        crank_hz: mean crank rate over the window [Hz]; None when the crank barely turns or no angle
            channel is there.
        harmonics_hz: the crank harmonics marked on the spectra [Hz] (empty without spectra).
        bands_hz: the shaded bands [Hz] (empty without spectra).
        orbits: joint -> radius of the clearance circle drawn [m] (half the diametral clearance).
        note: why no orbit is drawn ("" when one is).
        path: the PNG written (:func:`plot`), None from :func:`draw`.
        size_px: its width and height [px].
        seconds: wall time of :func:`plot` [s] (read, draw, write).
        spectrum: whether the spectra are drawn.
    """

    kind: str
    window_s: tuple[float, float]
    channels: tuple[str, ...]
    overlays: dict[str, str]
    crank_hz: float | None
    harmonics_hz: tuple[float, ...]
    bands_hz: tuple[tuple[float, float], ...]
    orbits: dict[str, float]
    note: str = ""
    path: Path | None = None
    size_px: tuple[int, int] | None = None
    seconds: float = 0.0
    spectrum: bool = False


# ---------------------------------------------------------------------------------- sources
def _default_bands() -> tuple[tuple[float, float], ...]:
    from twin.bench_replay import DEFAULT_BANDS_HZ

    return tuple(DEFAULT_BANDS_HZ)


def load(source: str | Path | Run) -> PlotSource:
    """A run file, a bench recording, a replay folder (or its ``replay.mcap``) or a :class:`Run`,
    read with the twin's readers (:func:`twin.mcapfile.read_run`, :func:`twin.recording.read_recording`).
    Raises a one-line :class:`TwinError` for anything else."""
    if isinstance(source, Run):
        kind = "replay" if "replay_of" in source.meta else "run"
        return PlotSource(kind, "run", source, _default_bands())
    from twin.mcapfile import read_metadata, read_run

    p = Path(source)
    if p.is_dir():
        if not (p / REPLAY_RUN).is_file():
            raise TwinError(f"{show(p)}: a folder without {REPLAY_RUN}: not a replay folder (give a run file, "
                            "a recording or the folder 'twin replay' wrote)")
        p = p / REPLAY_RUN
    elif not p.exists():
        raise TwinError(f"{show(p)}: no such file")
    elif not p.is_file():
        raise TwinError(f"{show(p)}: not a regular file (a pipe or device)")
    elif p.suffix.lower() != ".mcap":
        raise TwinError(f"{show(p)}: expected a .mcap run or recording file, or a replay folder")
    records = read_metadata(p)
    name = p.parent.name if p.name == REPLAY_RUN else p.stem
    if "twin.replay" in records:
        run = read_run(p)
        try:
            report = json.loads(records["twin.replay"].get("json", "{}"))
            bands = tuple((float(lo), float(hi)) for lo, hi in report.get("bands_hz", []))
        except (ValueError, TypeError, AttributeError):
            raise RecordingError(f"{show(p)}: metadata twin.replay holds no readable report") from None
        return PlotSource("replay", name, run, bands or _default_bands())
    if "twin.recording" in records:
        from twin.instrument import measured_accel
        from twin.recording import read_recording

        daq, info, repairs = read_recording(p, nan="interpolate")
        run = daq
        if info.calibration is not None:
            run = daq.with_channels(measured_accel(daq, info.calibration).channels.values())
        notes = tuple(f"repaired for the plot: {r}" for r in [*info.repairs, *repairs])
        if info.calibration is None:
            notes += ("no calibration in the recording: volts shown",)
        return PlotSource("recording", name, run, _default_bands(), notes)
    return PlotSource("run", name, read_run(p), _default_bands())


# ------------------------------------------------------------------------------- selection
def default_channels(src: PlotSource) -> list[str]:
    """Accelerometers (calibrated ones of a recording or replay, else volts) and contact forces."""
    run = src.run
    for prefix in ("meas_", "", "volt_"):
        acc = [f"{prefix}{a}" for a in ACCELEROMETERS if f"{prefix}{a}" in run]
        if acc:
            break
    forces = [f"fn_{j}" for j in JOINTS if f"fn_{j}" in run]
    return acc + forces or list(run.channels)[:6]


def select_channels(src: PlotSource, patterns: Sequence[str] | None) -> list[str]:
    """The channels named by ``patterns`` (names or shell-style globs, in order, each match once);
    the defaults (:func:`default_channels`) when None. One line naming the allowed channels when a
    pattern matches none."""
    names = list(src.run.channels)
    if not names:
        raise TwinError(f"{src.name}: holds no channels to draw")
    if patterns is None:
        return default_channels(src)
    out: list[str] = []
    for pat in patterns:
        hits = [n for n in names if fnmatch.fnmatchcase(n, pat)]
        if not hits:
            raise TwinError(f"{pat!r} matches no channel of {src.name}; channels: {', '.join(names)}", field="channels")
        out += [h for h in hits if h not in out]
    return out


def choose_window(src: PlotSource, window: tuple[float, float] | None, spectrum: bool) -> tuple[float, float]:
    """The time window [s]: ``window`` checked to lie in the run and to hold enough samples for a
    spectrum; by default the last :data:`DEFAULT_WINDOW_S` (with spectra: the spectrum window of
    ``twin view``, :func:`twin.viz.spectrum.default_window`, the last second at most half the run)."""
    from twin.viz.spectrum import check_window, default_window

    t_start, t_end = src.span_s
    rate = src.run.rate_hz
    if window is None:
        if spectrum:
            return default_window(src.config, t_start, t_end)
        return (max(t_start, t_end - DEFAULT_WINDOW_S), t_end)
    t0, t1 = (float(v) for v in window)
    if not (np.isfinite(t0) and np.isfinite(t1) and t0 < t1):
        raise TwinError(f"START:STOP must be finite seconds with START < STOP, got {t0:g}:{t1:g}", field="window")
    check_window((t0, t1), t_start, t_end, rate, flag="window")
    return (max(t0, t_start), min(t1, t_end))


def crank_rate_hz(run: Run, i0: int, i1: int) -> float | None:
    """Mean crank rate over samples [i0, i1) [Hz] from the crank's unwrapped angle (``crank_angle``,
    ``encoder_angle``, a replay's ``rec_encoder_angle``, or a recording's ``encoder_counts``);
    None without one, or when the crank turns less than :data:`MIN_TURNS` in the window."""
    for name in ("crank_angle", "encoder_angle", "rec_encoder_angle", "encoder_counts"):
        if name in run:
            a = np.asarray(run[name][i0:i1], dtype=np.float64)
            if name == "encoder_counts":
                cpr = (run.config or BenchConfig()).instrumentation.encoder_counts_per_rev
                a = a * (2 * np.pi / cpr)
            break
    else:
        return None
    if a.size < 2:
        return None
    turns = abs(a[-1] - a[0]) / (2 * np.pi)
    if turns < MIN_TURNS:
        return None
    return float(turns / ((a.size - 1) / run.rate_hz))


def _orbits(src: PlotSource) -> tuple[dict[str, float], str]:
    """Joints with eccentricity channels -> radial clearance [m]; the note when there is none."""
    run, cfg = src.run, src.config
    out: dict[str, float] = {}
    if cfg is not None and cfg.spatial.enabled:
        return out, "no journal orbit: the spatial mechanism's eccentricities are 3-D ('twin view' shows them)"
    for j in JOINTS:
        if f"ecc_{j}_x" in run and f"ecc_{j}_y" in run and cfg is not None:
            c_mm = getattr(cfg.joints, f"clearance_{j.lower()}_mm", 0.0)
            if c_mm > 0:
                out[j] = c_mm / 2 * 1e-3
    if out:
        return out, ""
    if src.kind == "recording":
        return out, "no journal orbit: a bench recording has no joint channels"
    return out, "no journal orbit: the run has no channels of a clearance joint"


# ---------------------------------------------------------------------------------- drawing
def envelope(t: np.ndarray, y: np.ndarray, max_points: int) -> tuple[np.ndarray, np.ndarray]:
    """``(t, y)`` unchanged up to ``max_points`` samples; longer, the min and the max of each group
    of k consecutive samples (k the smallest that fits), at the group's first time: the curve's
    envelope at the figure's resolution, impacts included."""
    y = np.asarray(y)
    n = y.size
    if n <= max_points:
        return t, y
    k = int(np.ceil(2 * n / max_points))
    m = n // k * k
    g = y[:m].reshape(-1, k)
    tt = np.repeat(t[:m:k], 2)
    yy = np.column_stack([g.min(axis=1), g.max(axis=1)]).ravel()
    return tt, yy


def _label(run: Run, name: str) -> str:
    from twin.viz.style import unit_text

    return f"{name}\n[{unit_text(run.channels[name].unit)}]"


def draw(fig: Any, src: PlotSource, *, channels: Sequence[str] | None = None,
         window: tuple[float, float] | None = None, spectrum: bool = False, title: str | None = None) -> PlotInfo:
    """Draw ``src`` into ``fig`` (a :class:`matplotlib.figure.Figure` or ``SubFigure``): see the
    module docstring. ``channels``: names or globs (default :func:`default_channels`); ``window``:
    (start, stop) [s] (default :func:`choose_window`); ``title``: replaces the generated one."""
    from matplotlib.ticker import NullLocator

    from twin.signals import hann_spectrum
    from twin.viz.spectrum import peak_bins

    names = select_channels(src, channels)
    t0, t1 = choose_window(src, window, spectrum)
    run = src.run
    rate = run.rate_hz
    i0 = max(0, int(round((t0 - run.t0) * rate)))
    i1 = min(run.n, int(round((t1 - run.t0) * rate)))
    overlays = {n: f"sim_{n}" for n in names if n.startswith("meas_") and f"sim_{n}" in run}
    fc = crank_rate_hz(run, i0, i1)
    fmax = min(SPECTRUM_MAX_HZ, rate / 2)
    harmonics = tuple(k * fc for k in range(1, HARMONICS + 1) if k * fc <= fmax) if spectrum and fc else ()
    bands = tuple(b for b in src.bands_hz if b[0] < fmax) if spectrum else ()
    orbits, note = _orbits(src)

    cols = [2.2] + ([1.6] if spectrum else []) + ([1.0] if orbits else [])
    # fixed margins in pixels (constrained layout measures every tick label: most of the drawing time)
    w_px, h_px = fig.bbox.width, fig.bbox.height
    outer = fig.add_gridspec(1, len(cols), width_ratios=cols, left=min(0.3, 105 / w_px), right=1 - 12 / w_px,
                             top=1 - min(0.3, 62 / h_px), bottom=min(0.3, 50 / h_px), wspace=0.16)
    tgrid = outer[0, 0].subgridspec(len(names), 1, hspace=0.08)
    sgrid = outer[0, 1].subgridspec(len(names), 1, hspace=0.08) if spectrum else None
    t = run.t0 + np.arange(i0, i1) / rate
    first_t = first_s = None
    for row, name in enumerate(names):
        last = row == len(names) - 1
        ax = fig.add_subplot(tgrid[row, 0], sharex=first_t)
        first_t = first_t or ax
        recorded = name.startswith(("meas_", "volt_", "rec_")) or src.kind == "recording"
        series = [(name, _MEAS if recorded else _SIM, "recorded" if name in overlays else None)]
        if name in overlays:
            series.append((overlays[name], _SIM, "simulated"))
        for s, colour, label in series:
            ax.plot(*envelope(t, run[s][i0:i1], MAX_POINTS), lw=0.6, color=colour, label=label,
                    alpha=0.8 if s != name else 1.0)
        ax.set_ylabel(_label(run, name), fontsize=8, rotation=0, ha="right", va="center")
        ax.tick_params(labelsize=7, labelbottom=last)
        ax.grid(alpha=0.3)
        if name in overlays and not any(a.get_legend() for a in fig.axes):
            ax.legend(fontsize=7, loc="upper right")
        if last:
            ax.set_xlabel("time [s]", fontsize=8)
        if sgrid is None:
            continue
        sx = fig.add_subplot(sgrid[row, 0], sharex=first_s)
        first_s = first_s or sx
        for s, colour, _ in series:
            f, amp = hann_spectrum(np.asarray(run[s][i0:i1], dtype=np.float64), rate, remove_mean=True)
            keep = (f > 0) & (f <= fmax)
            f, amp = peak_bins(f[keep], amp[keep], MAX_POINTS)
            sx.loglog(f, np.maximum(amp, 1e-12 * max(amp.max(initial=0.0), 1e-300)), lw=0.5, color=colour)
        for h in harmonics:
            sx.axvline(h, color="0.35", ls="--", lw=0.5)
        for lo, hi in bands:
            sx.axvspan(lo, hi, color="tab:orange", alpha=0.25, lw=0)
        sx.set_xlim(rate / max(i1 - i0, 1), fmax)
        sx.tick_params(labelsize=7, labelbottom=last)
        sx.xaxis.set_minor_locator(NullLocator())  # log axes' minor ticks cost more than the curves
        sx.yaxis.set_minor_locator(NullLocator())
        sx.grid(alpha=0.3)
        if last:
            sx.set_xlabel("frequency [Hz]", fontsize=8)
        if row == 0:
            what = f"crank {fc:.3f} Hz × 1..{len(harmonics)} dashed" if harmonics else "crank at rest: no harmonics"
            shaded = ("\nbands " + ", ".join(f"{lo / 1e3:g}–{hi / 1e3:g}" for lo, hi in bands) + " kHz shaded"
                      if bands else "")
            sx.set_title(f"Hann amplitude spectrum; {what}{shaded}", fontsize=8)
    if orbits:
        ogrid = outer[0, len(cols) - 1].subgridspec(len(orbits), 1, hspace=0.4)
        for k, (j, radius) in enumerate(orbits.items()):
            ox = fig.add_subplot(ogrid[k, 0])
            r_um = radius * 1e6
            phi = np.linspace(0, 2 * np.pi, 361)
            ox.plot(r_um * np.cos(phi), r_um * np.sin(phi), color="tab:green", lw=1)
            step = max(1, -(-(i1 - i0) // (5 * MAX_POINTS)))  # long windows: every step-th sample
            ex = np.asarray(run[f"ecc_{j}_x"][i0:i1:step], dtype=np.float64) * 1e6
            ey = np.asarray(run[f"ecc_{j}_y"][i0:i1:step], dtype=np.float64) * 1e6
            ox.plot(ex, ey, color=_SIM, lw=0.5)
            if f"pen_{j}" in run:
                hit = np.asarray(run[f"pen_{j}"][i0:i1:step]) > 0
                ox.plot(ex[hit], ey[hit], ".", color="tab:red", ms=1)
            lim = 1.15 * r_um
            ox.set_xlim(-lim, lim)
            ox.set_ylim(-lim, lim)
            ox.set_aspect("equal")
            ox.tick_params(labelsize=7)
            sim = " (simulated)" if src.kind == "replay" else ""
            ox.set_title(f"journal at {j} [µm]{sim}\nclearance {r_um:g} µm, red: contact", fontsize=8)
    if title is None:
        title = _title(src, (t0, t1), fc)
    if title:
        fig.suptitle(title, fontsize=10)
    extra = [*src.notes, note] if note else list(src.notes)
    if extra:
        fig.text(0.01, 0.005, "; ".join(extra), fontsize=7, color="0.3", ha="left", va="bottom")
    return PlotInfo(src.kind, (t0, t1), tuple(names), overlays, fc, harmonics, bands, orbits, note,
                    spectrum=spectrum)


def _title(src: PlotSource, window: tuple[float, float], fc: float | None) -> str:
    what = {"run": "simulated run", "recording": "bench recording", "replay": "replay: recorded vs simulated"}
    parts = [f"{src.name}: {what[src.kind]}"]
    cfg = src.config
    if cfg is not None:
        parts.append(f"{cfg.name}, clearance B {cfg.joints.clearance_b_mm:g} mm, C {cfg.joints.clearance_c_mm:g} mm"
                     + (f", {cfg.simulation.engine} engine" if src.kind != "recording" else ""))
    parts.append(f"{window[0]:.3f}–{window[1]:.3f} s of {src.span_s[0]:g}–{src.span_s[1]:g} s")
    if fc:
        parts.append(f"crank {fc:.3f} Hz ({fc * 60:.1f} rpm)")
    return "; ".join(parts)


def figure_size(n_panels: int, spectrum: bool, orbit: bool) -> tuple[int, int]:
    """Default size of the figure [px]."""
    return (900 + (650 if spectrum else 0) + (380 if orbit else 0), max(520, 120 * n_panels + 110))


def plot(source: str | Path | Run, out: str | Path, *, channels: Sequence[str] | None = None,
         window: tuple[float, float] | None = None, spectrum: bool = False,
         size_px: tuple[int, int] | None = None) -> PlotInfo:
    """Draw ``source`` (:func:`load`) and write the PNG ``out`` (temporary file, then renamed: an
    error leaves no file and an existing one as it was); its text chunks name the twin's version
    (``Software``) and what is drawn (``Description``). ``size_px``: (width, height) [px], default
    :func:`figure_size`. Returns what the figure shows (:class:`PlotInfo`)."""
    from matplotlib.figure import Figure

    from twin.util import atomic_write_bytes

    start = time.perf_counter()
    src = load(source)
    names = select_channels(src, channels)
    if size_px is None:
        size_px = figure_size(len(names), spectrum, bool(_orbits(src)[0]))
    else:
        check_size_px(size_px, "size_px")
    w, h = size_px
    fig = Figure(figsize=(w / DPI, h / DPI), dpi=DPI)
    info = draw(fig, src, channels=channels, window=window, spectrum=spectrum)
    from twin import __version__

    what = (f"{src.kind} {src.name}: {', '.join(info.channels)} over {info.window_s[0]:.6g}-{info.window_s[1]:.6g} s"
            + (", spectra" if spectrum else "") + (", orbits " + ", ".join(info.orbits) if info.orbits else ""))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, metadata={"Software": f"twin {__version__} (twin plot)",
                                                      "Description": what})
    path = atomic_write_bytes(out, buf.getvalue())
    return PlotInfo(**{**info.__dict__, "path": path, "size_px": (w, h), "seconds": time.perf_counter() - start})
