"""Default blueprint (layout) of a run's rerun recording: useful at first sight, readable in a
1920x1080 window (the default of ``twin view --screenshot``) and still in 1600x900.

Left (2/5 of the width): the 3-D bench (true sizes, magnified orbit insets, contact arrows), the
journal orbits of the clearance joints (µm, trailing the time cursor), the contact forces and
the crank speed. Right (3/5), in tabs: the accelerometers (simulated and recorded overlaid) in
a 2 x 3 grid; drive and encoder; contact details; spectra of the FFT window; raw DAQ channels;
any other channel; the configuration document. Only views whose data exist are created.

Readability, given how rerun 0.41 labels its axes (measured on screenshots; its source: a time
label at every power of ten of seconds whose marks are at least ~150 px apart, a value label at
every power of ten at least ~20 px apart):

* time: the windowed plots are at least ~450 px wide, so the default 0.3 s window around the
  cursor (:class:`ViewOptions`) gets a label every 100 ms (3 or 4); the crank speed over a 38 s
  protocol run is ~600 px wide (a label every 10 s);
* values: the accelerometer plots are ~290 px high at 1920x1080 (~225 at 1600x900): a range of
  up to ~145 (1.45 powers of ten) gets a label every 10, a wider one one label per 100 (2 or
  more); rerun has no setting for the value step;
* titles carry the unit and the colour of each series (legends would list the hidden series of
  a channel group too) and fit their title bars (:data:`MAX_TITLE_CHARS`).
"""

from __future__ import annotations

import rerun as rr
import rerun.blueprint as rrb

from twin.config import ACCELEROMETERS, JOINTS, BenchConfig
from twin.run import Channel
from twin.viz.options import ViewOptions
from twin.viz.scene import nice_magnification
from twin.viz.style import CHAIN_COLOUR, COLOUR_NAMES, MEAS_COLOUR, SIM_COLOUR, view_title

TIMELINE = "time"
#: Longest plot title [characters] that fits the title bar of a plot of the right-hand tabs at
#: 1600x900 (~480 px wide, ~375 px of it for the title at ~5.7 px a character, measured on a
#: screenshot where 56 characters took 320 px; checked by the tests).
MAX_TITLE_CHARS = 60


class _Series:
    """Builds time-series views from channel names: each channel is series ``k`` of its
    group's entity ``/signals/<group>``; a view shows its channels by overriding
    ``visible_series`` on those entities."""

    def __init__(self, groups: dict[str, list[str]], channels: dict[str, Channel]):
        self.where = {n: (g, k) for g, names in groups.items() for k, n in enumerate(names)}
        self.groups = groups
        self.channels = channels
        self.used: set[str] = set()

    def pick(self, *names: str) -> list[str]:
        """The given channels that exist (marked as shown)."""
        out = [n for n in names if n in self.where]
        self.used.update(out)
        return out

    def view(self, title: str, names: list[str], legend: bool = False,
             window: rrb.VisibleTimeRange | None = None) -> rrb.TimeSeriesView:
        masks: dict[str, list[bool]] = {}
        for n in names:
            g, k = self.where[n]
            masks.setdefault(g, [False] * len(self.groups[g]))[k] = True
        return rrb.TimeSeriesView(
            origin="/", contents=[f"/signals/{g}" for g in masks],
            name=view_title(title, [self.channels[n] for n in names]),
            overrides={f"/signals/{g}": rr.SeriesLines.from_fields(visible_series=m) for g, m in masks.items()},
            plot_legend=rrb.PlotLegend(corner="LeftTop", visible=legend),
            time_ranges=[window] if window is not None else None)


def _eye(cfg: BenchConfig) -> rrb.EyeControls3D:
    l = cfg.bodies.rod.length_m
    if cfg.spatial.enabled:  # from the crank's side (−x), above and in front: both planes seen at an angle
        cx = l / 2.0
        return rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=(cx - 0.21, 0.08, 0.27),
                                 look_target=(cx - 0.04, -0.035, 0.0), eye_up=(0.0, 1.0, 0.0))
    cx = (l + 0.02) / 2.0  # the mechanism spans x = -r .. l + r (+ the guide)
    up = cfg.mechanism.orientation
    if up == "y":
        return rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=(cx, 0.06, 0.36),
                                 look_target=(cx, -0.02, 0.0), eye_up=(0.0, 1.0, 0.0))
    if up == "x":
        return rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=(cx + 0.06, 0.0, 0.36),
                                 look_target=(cx, 0.0, 0.0), eye_up=(1.0, 0.0, 0.0))
    return rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=(cx, -0.20, 0.25),
                             look_target=(cx, 0.0, 0.0), eye_up=(0.0, 0.0, 1.0))


def default_blueprint(cfg: BenchConfig, groups: dict[str, list[str]], channels: dict[str, Channel],
                      joints: tuple[str, ...], has_pose: bool,
                      fft_window: tuple[float, float] | None, fft_names: list[str],
                      opts: ViewOptions) -> rrb.Blueprint:
    """Blueprint for a recording with these channel groups (see module docstring)."""
    S = _Series(groups, channels)
    paths = S.pick
    _series = S.view
    win = None
    if opts.plot_window_s > 0:
        half = opts.plot_window_s / 2.0
        win = rrb.VisibleTimeRange(TIMELINE, start=rr.TimeRangeBoundary.cursor_relative(seconds=-half),
                                   end=rr.TimeRangeBoundary.cursor_relative(seconds=half))

    # accelerometers: simulated + recorded overlaid; raw volts only when nothing calibrated exists
    accel_views = []
    for a in ACCELEROMETERS:
        p = paths(a, f"sim_meas_{a}", f"meas_{a}")
        if not p:
            p = paths(f"volt_{a}", f"sim_volt_{a}")
        if p:
            accel_views.append(_series(a, p, window=win))
    speed = paths("crank_speed", "omega_ref")
    force = paths(*[f"fn_{j}" for j in JOINTS])
    pen = paths(*[f"pen_{j}" for j in JOINTS])
    friction = paths(*[f"ft_{j}" for j in JOINTS])
    encoder = paths("encoder_angle", "rec_encoder_angle") or paths("encoder_counts", "sim_encoder_counts")
    motor = paths("motor_command", "sim_motor_command", "command_voltage")
    torque = paths("crank_torque")
    rotor = paths("motor_speed")                       # drive train (drive.mode motor/torque)
    motor_torque = paths("motor_torque", "belt_torque")
    slip = paths("belt_slip")
    angle = paths("crank_angle", "theta_ref")
    slider = paths("slider_position")
    # guide clearance (joints.clearance_guide_mm): one plot per channel (titled by it)
    guide = [(name, paths(name)) for name in ("fn_guide_front", "fn_guide_rear", "ft_guide_front",
                                              "ft_guide_rear", "slider_y", "slider_tilt")]

    tabs: list[rrb.Container | rrb.View] = []
    speed_view = _series("crank speed", speed) if speed else None
    force_view = _series("contact force", force, window=win) if force else None
    encoder_view = _series("encoder", encoder) if encoder and not speed else None
    bottom = [v for v in (speed_view, force_view, encoder_view) if v is not None]
    if accel_views:
        grid = rrb.Grid(*accel_views, grid_columns=2, name="accelerometers")
        if bottom and not has_pose:  # no left column: speed and forces below the accelerometers
            tabs.append(rrb.Vertical(grid, rrb.Horizontal(*bottom), row_shares=[3, 1], name="Signals"))
        else:
            tabs.append(rrb.Vertical(grid, name="Signals"))
    drive = [_series(n, p) for n, p in (("crank speed", speed), ("encoder", encoder), ("motor command", motor),
                                         ("crank torque", torque), ("crank angle", angle),
                                         ("slider position", slider), ("motor speed", rotor),
                                         ("motor and belt torque", motor_torque), ("belt slip", slip)) if p]
    if drive:
        tabs.append(rrb.Grid(*drive, grid_columns=2, name="Drive & encoder"))
    frame = "rod frame; A: bench frame" if "ecc_A_x" in channels else "rod frame"
    axes: tuple[str, ...] = ("x", "y")
    if cfg.spatial.enabled:
        frame, axes = "spatial frame", ("x", "y", "z")
    ecc_xy = [(f"eccentricity {k} ({frame})", paths(*[f"ecc_{j}_{k}" for j in JOINTS])) for k in axes]
    contact = [_series(n, p, window=win) for n, p in (("contact force", force), ("friction force", friction),
                                                       ("penetration", pen), *ecc_xy, *guide) if p]
    if contact:
        tabs.append(rrb.Grid(*contact, grid_columns=2, name="Contact"))
    if fft_window is not None and fft_names:
        t0, t1 = fft_window
        sensors = [a for a in ACCELEROMETERS if any(n in fft_names for n in (a, f"meas_{a}", f"sim_meas_{a}"))]
        kinds = (("", f"sim ({COLOUR_NAMES[SIM_COLOUR]})"), ("sim_meas_", f"sim+chain ({COLOUR_NAMES[CHAIN_COLOUR]})"),
                 ("meas_", f"rec ({COLOUR_NAMES[MEAS_COLOUR]})"))
        bars = []
        for a in sensors:
            shown = ", ".join(text for pre, text in kinds if f"{pre}{a}" in fft_names)
            bars.append(rrb.BarChartView(origin=f"/fft/{a}", name=f"{a} [dB]: {shown}",
                                         plot_legend=rrb.PlotLegend(visible=False)))
        tabs.append(rrb.Grid(*bars, grid_columns=2, name=f"Spectra {t0:g}–{t1:g} s (dB re 1 mm/s², Hz)"))
    daq = [_series(n, paths(n, f"sim_{n}")) for n in groups.get("daq", []) if n not in S.used]
    if daq:
        tabs.append(rrb.Grid(*daq, name="DAQ (raw)"))
    rest = [_series(n, paths(n)) for n in channels if n not in S.used]
    if rest:
        tabs.append(rrb.Grid(*rest, name="Other channels"))
    tabs.append(rrb.TextDocumentView(origin="/config", name="Configuration"))
    right = rrb.Tabs(*tabs, active_tab=0)

    if has_pose:
        target = opts.orbit_inset_radius_m
        if cfg.spatial.enabled:
            from twin.viz.spatial_view import inset_radius

            target = inset_radius(cfg, target)
        mags = [(j, nice_magnification(cfg.joints.radial_m(j), target)) for j in joints]
        if mags and len({m for _, m in mags}) == 1:
            mag_text = f"×{mags[0][1]} ({', '.join(j for j, _ in mags)})"
        else:
            mag_text = ", ".join(f"{j} ×{m}" for j, m in mags)
        title = "spatial slider-crank (true size)" if cfg.spatial.enabled else "bench (true size)"
        if mags:
            title += f"; green circles: clearance, journal centre magnified {mag_text}"
        bench = rrb.Spatial3DView(origin="/bench", name=title,
                                  eye_controls=_eye(cfg), line_grid=rrb.LineGrid3D(visible=False))
        trail = rrb.VisibleTimeRange(TIMELINE, start=rr.TimeRangeBoundary.cursor_relative(seconds=-opts.orbit_trail_s),
                                     end=rr.TimeRangeBoundary.cursor_relative(seconds=0.0))
        orbits = []
        for j in joints:
            c_um = cfg.joints.radial_m(j) * 1e6
            eye = rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=(0.0, 0.0, 3.2 * c_um),
                                    look_target=(0.0, 0.0, 0.0), eye_up=(0.0, 1.0, 0.0))
            if cfg.spatial.enabled:  # A: the crank's plane seen from −x; B, C: the sphere at an angle
                pos = (-3.2 * c_um, 0.0, 0.0) if j == "A" else (-1.6 * c_um, 1.3 * c_um, 2.5 * c_um)
                eye = rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=pos, look_target=(0.0, 0.0, 0.0),
                                        eye_up=(0.0, 1.0, 0.0))
            orbits.append(rrb.Spatial3DView(
                origin=f"/orbit/{j}",
                name=f"{j} orbit [µm], c = {c_um:g} µm", time_ranges=[trail],
                line_grid=rrb.LineGrid3D(visible=False), eye_controls=eye))
        rows: list[rrb.Container | rrb.View] = [bench]
        shares = [3.0]
        if orbits:
            rows.append(rrb.Horizontal(*orbits))
            shares.append(3.0)
        for v in (force_view, speed_view, encoder_view):  # below the bench: what explains the accelerations
            if v is not None:
                rows.append(v)
                shares.append(2.0)
        left = rrb.Vertical(*rows, row_shares=shares) if len(rows) > 1 else bench
        root = rrb.Horizontal(left, right, column_shares=[2, 3])
    else:
        root = right
    return rrb.Blueprint(root, rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="collapsed"),
                         rrb.TimePanel(state="collapsed", timeline=TIMELINE), auto_views=False)
