"""Default blueprint (layout) of a run's rerun recording: useful at first sight.

Left: the 3-D bench (true sizes, magnified orbit insets, contact arrows) above the journal
orbits of the clearance joints (µm, trailing the time cursor). Right, in tabs: the
accelerometers (simulated and recorded overlaid) with crank speed and contact forces; drive
and encoder; contact details; spectra of the FFT window; raw DAQ channels; any other channel;
the configuration document. Only views whose data exist are created.
"""

from __future__ import annotations

import rerun as rr
import rerun.blueprint as rrb

from twin.config import ACCELEROMETERS, JOINTS, BenchConfig
from twin.run import Channel
from twin.viz.options import ViewOptions
from twin.viz.scene import nice_magnification
from twin.viz.style import view_title

TIMELINE = "time"


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
    cx = (l + 0.02) / 2.0  # the mechanism spans x = -r .. l + r (+ the guide)
    up = cfg.mechanism.orientation
    if up == "y":
        return rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=(cx, 0.10, 0.60),
                                 look_target=(cx, -0.02, 0.0), eye_up=(0.0, 1.0, 0.0))
    if up == "x":
        return rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=(cx + 0.10, 0.0, 0.60),
                                 look_target=(cx, 0.0, 0.0), eye_up=(1.0, 0.0, 0.0))
    return rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=(cx, -0.33, 0.42),
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
    ecc = paths(*[f"ecc_{j}_{k}" for j in JOINTS for k in ("x", "y")])
    encoder = paths("encoder_angle", "rec_encoder_angle") or paths("encoder_counts", "sim_encoder_counts")
    motor = paths("motor_command", "sim_motor_command", "command_voltage")
    torque = paths("crank_torque")
    rotor = paths("motor_speed")                       # drive train (drive.mode motor/torque)
    motor_torque = paths("motor_torque", "belt_torque")
    slip = paths("belt_slip")
    angle = paths("crank_angle", "theta_ref")
    slider = paths("slider_position")

    tabs: list[rrb.Container | rrb.View] = []
    bottom = [v for v in (_series("crank speed", speed) if speed else None,
                          _series("contact force", force, window=win) if force else None,
                          _series("encoder", encoder) if encoder and not speed else None) if v is not None]
    if accel_views:
        grid = rrb.Grid(*accel_views, grid_columns=2, name="accelerometers")
        tabs.append(rrb.Vertical(grid, rrb.Horizontal(*bottom), row_shares=[3, 1], name="Signals")
                    if bottom else rrb.Vertical(grid, name="Signals"))
    drive = [_series(n, p) for n, p in (("crank speed", speed), ("encoder", encoder), ("motor command", motor),
                                         ("crank torque", torque), ("crank angle", angle),
                                         ("slider position", slider), ("motor speed", rotor),
                                         ("motor and belt torque", motor_torque), ("belt slip", slip)) if p]
    if drive:
        tabs.append(rrb.Grid(*drive, grid_columns=2, name="Drive & encoder"))
    contact = [_series(n, p, window=win) for n, p in (("contact force", force), ("friction force", friction),
                                                       ("penetration", pen), ("eccentricity (rod frame; A: bench frame)" if "ecc_A_x" in channels else "eccentricity (rod frame)", ecc)) if p]
    if contact:
        tabs.append(rrb.Grid(*contact, grid_columns=2, name="Contact"))
    if fft_window is not None and fft_names:
        t0, t1 = fft_window
        sensors = [a for a in ACCELEROMETERS if any(n in fft_names for n in (a, f"meas_{a}", f"sim_meas_{a}"))]
        kinds = (("", "sim (blue)"), ("sim_meas_", "sim+chain (purple)"), ("meas_", "rec (orange)"))
        bars = []
        for a in sensors:
            shown = ", ".join(text for pre, text in kinds if f"{pre}{a}" in fft_names)
            bars.append(rrb.BarChartView(origin=f"/fft/{a}", name=f"{a} {t0:g}–{t1:g} s [dB re 1 mm/s²]: {shown}",
                                         plot_legend=rrb.PlotLegend(visible=False)))
        tabs.append(rrb.Grid(*bars, grid_columns=2, name="Spectra"))
    daq = [_series(n, paths(n, f"sim_{n}")) for n in groups.get("daq", []) if n not in S.used]
    if daq:
        tabs.append(rrb.Grid(*daq, name="DAQ (raw)"))
    rest = [_series(n, paths(n)) for n in channels if n not in S.used]
    if rest:
        tabs.append(rrb.Grid(*rest, name="Other channels"))
    tabs.append(rrb.TextDocumentView(origin="/config", name="Configuration"))
    right = rrb.Tabs(*tabs, active_tab=0)

    if has_pose:
        mags = ", ".join(f"{j} ×{nice_magnification(cfg.joints.radial_m(j), opts.orbit_inset_radius_m)}"
                         for j in joints)
        title = "bench (true sizes)" + (f"; green circles: clearance, journal centre magnified {mags}" if mags else "")
        bench = rrb.Spatial3DView(origin="/bench", name=title,
                                  eye_controls=_eye(cfg), line_grid=rrb.LineGrid3D(visible=False))
        trail = rrb.VisibleTimeRange(TIMELINE, start=rr.TimeRangeBoundary.cursor_relative(seconds=-opts.orbit_trail_s),
                                     end=rr.TimeRangeBoundary.cursor_relative(seconds=0.0))
        orbits = []
        for j in joints:
            c_um = cfg.joints.radial_m(j) * 1e6
            orbits.append(rrb.Spatial3DView(
                origin=f"/orbit/{j}",
                name=f"{j} orbit [µm], c = {c_um:g} µm", time_ranges=[trail],
                line_grid=rrb.LineGrid3D(visible=False),
                eye_controls=rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=(0.0, 0.0, 3.2 * c_um),
                                               look_target=(0.0, 0.0, 0.0), eye_up=(0.0, 1.0, 0.0))))
        left = rrb.Vertical(bench, rrb.Horizontal(*orbits), row_shares=[3, 2]) if orbits else bench
        root = rrb.Horizontal(left, right, column_shares=[1, 1])
    else:
        root = right
    return rrb.Blueprint(root, rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="collapsed"),
                         rrb.TimePanel(state="collapsed", timeline=TIMELINE), auto_views=False)
