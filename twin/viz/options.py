"""Parameters of a rerun recording of a run (one frozen dataclass, validated)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from twin.errors import ConfigError


@dataclass(frozen=True)
class ViewOptions:
    """How a run is turned into a rerun recording.

    Attributes:
        pose_rate_hz: rate of the 3-D poses and contact arrows [Hz] (signals keep the run's
            rate). Each contact arrow shows the peak force of the 1/pose_rate window centred
            on its pose, so short impacts are not lost by the decimation.
        orbit_rate_hz: rate of the journal-centre orbit points [Hz].
        block_rows: rows per ``send_columns`` block of a signal.
        orbit_trail_s: length of the orbit trail shown behind the time cursor [s].
        plot_window_s: time window around the cursor shown by the accelerometer and contact
            plots [s] (waveforms and impacts stay readable while scrubbing, and the viewer
            draws a bounded number of points); 0 = the whole run. 0.3 s: about one crank
            revolution at the top test speed, and a time label every 100 ms on a plot of the
            default layout (rerun labels powers of ten of seconds, about 150 px apart at least).
            The crank-speed plot and the drive tab always show the whole run.
        orbit_inset_radius_m: drawn radius of the magnified clearance circle in the 3-D view [m];
            the magnification is the 1-2-5 number that brings the radial clearance closest to it
            without exceeding it.
        force_scale_m_per_n: length of a contact force arrow per newton [m/N] (3-D view).
        fft_window_s: (t0, t1) window of the spectra [s]; None = default (see
            :func:`twin.viz.spectrum.default_window`).
        fft_max_hz: highest frequency shown in the spectra [Hz] (the accelerometers are
            flat to 11 kHz).
    """

    pose_rate_hz: float = 1000.0
    orbit_rate_hz: float = 10_000.0
    block_rows: int = 10_000
    orbit_trail_s: float = 0.2
    plot_window_s: float = 0.3
    orbit_inset_radius_m: float = 0.06
    force_scale_m_per_n: float = 2e-4
    fft_window_s: tuple[float, float] | None = None
    fft_max_hz: float = 15_000.0

    def __post_init__(self) -> None:
        for name in ("pose_rate_hz", "orbit_rate_hz", "orbit_trail_s", "orbit_inset_radius_m",
                     "force_scale_m_per_n", "fft_max_hz"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ConfigError(name, f"must be a finite number > 0, got {v!r}")
        if not (isinstance(self.plot_window_s, (int, float)) and math.isfinite(self.plot_window_s)
                and self.plot_window_s >= 0):
            raise ConfigError("plot_window_s", f"must be a finite number >= 0 [s], got {self.plot_window_s!r}")
        if not (isinstance(self.block_rows, int) and 100 <= self.block_rows <= 1_000_000):
            raise ConfigError("block_rows", f"must be an integer in [100, 1000000], got {self.block_rows!r}")
        if self.fft_window_s is not None:
            w = tuple(self.fft_window_s)
            if len(w) != 2 or not all(isinstance(x, (int, float)) and math.isfinite(x) for x in w) or w[1] <= w[0]:
                raise ConfigError("fft_window_s", f"must be two times T0 < T1 [s], got {list(w)!r}")
