"""The Python API of the twin: the calls ``import twin`` offers (``twin.preset``, ``twin.simulate``,
``twin.replay``, ``twin.identify``, ``twin.plot``), each a thin front of the module that does the work.

Every example below runs in the test suite (doctest), so it stays true:

>>> import twin
>>> cfg = twin.preset(6)                      # Table 4 test 6: 0.1 mm at C, 750 rpm
>>> run = twin.simulate(cfg, duration=0.05)   # a twin.run.Run, in memory
>>> run.n, run.rate_hz                      # 0.05 s at 100 kHz
(5000, 100000.0)
>>> float(run.time[-1])                       # sample times [s]
0.04999
>>> run["crank_angle"].dtype                  # channels are numpy arrays
dtype('float64')
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping, Sequence

from twin.config import BenchConfig
from twin.errors import ConfigError
from twin.run import Run

if TYPE_CHECKING:
    from twin.identification.results import IdentifyResult
    from twin.replay_result import ReplayResult


def _path(value: Any, name: str) -> Path:
    """A file or folder argument: a str or os.PathLike, else TypeError naming ``name``; an empty one is refused
    as a ConfigError naming it."""
    import os

    if isinstance(value, bool) or not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{name}: must be a path (str or os.PathLike), got {type(value).__name__}")
    if not str(value):
        raise ConfigError(name, "is empty; give a path")
    return Path(value)


def _overrides(value: Any, name: str = "overrides") -> dict[str, Any]:
    """Dotted-path overrides: a mapping of str keys, else TypeError naming ``name``."""
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise TypeError(f"{name}: must be a mapping of dotted field names to values, got {type(value).__name__}")
    for key in value:
        if not isinstance(key, str):
            raise TypeError(f"{name}: keys must be dotted field names (str), got {key!r}")
    return dict(value)


def _number(value: Any, name: str) -> float:
    """A real number (not a bool), else TypeError naming ``name``."""
    import numbers

    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name}: must be a number, got {type(value).__name__}")
    return float(value)


def preset(which: int | str = 6) -> BenchConfig:
    """The configuration of a bench test or of a paper's mechanism.

    ``which``: a Table 4 test id of the bench paper, 1..12 (clearances at joints B and C, constant
    motor speed; also ``"test6"`` for 6), or a named preset: another mechanism of the seed papers,
    ``"s000"``, ``"s001"``, ``"s002"`` (spatial), ``"s004"``, or the bench's torque-driven release
    test, ``"torque_release"`` and ``"torque_release_protocol"`` (``twin.config.NAMED_PRESETS``; a
    misspelt name gets the closest one in its error). Returns a :class:`twin.config.BenchConfig`
    (frozen; change fields with ``cfg.replace(**{"dotted.name": value})``).

    >>> import twin
    >>> cfg = twin.preset(6)
    >>> cfg.name, cfg.joints.clearance_c_mm, cfg.drive.motor_rpm
    ('test6', 0.1, 750.0)
    >>> twin.preset("s001").name
    's001'
    >>> twin.preset(13)
    Traceback (most recent call last):
    ...
    twin.errors.ConfigError: test: must be a Table 4 test id 1..12, got 13
    """
    from twin.config import named_preset
    from twin.config import preset as table4

    import numbers

    if isinstance(which, bool) or not isinstance(which, (numbers.Integral, str)):
        raise TypeError(f"which: must be a Table 4 test id (int) or a preset name (str), got {type(which).__name__}")
    if not isinstance(which, str):
        which = int(which)
    if isinstance(which, str):
        name = which.strip().lower()
        if name.startswith("test") and name[4:].isdigit():
            return table4(int(name[4:]))
        if name.isdigit():
            return table4(int(name))
        return named_preset(name, "preset")
    return table4(which)


def simulate(cfg: BenchConfig | int | str | None = None, duration: float | None = None, *,
             engine: str | None = None, overrides: Mapping[str, Any] | None = None,
             out: str | Path | None = None, progress: bool = False) -> Run:
    """Simulate a configuration and return the whole run in memory.

    ``cfg``: a :class:`~twin.config.BenchConfig`, or what :func:`preset` takes (default: test 6);
    ``duration``: simulated time [s] (default: the configuration's ``simulation.duration_s``);
    ``engine``: ``"mujoco"`` (the twin) or ``"reference"`` (the R-matrix engine); ``overrides``:
    other fields by dotted name, as in a TOML file (``{"drive.motor_rpm": 500.0}``); ``out``: also
    write the run file (MCAP) there; ``progress``: a progress bar on stderr.

    Returns a :class:`twin.run.Run`: ``run.time`` [s], ``run["AC6"]`` (a numpy array per channel,
    SI units in ``run.channels[name].unit``), ``run.config``, ``run.meta`` and ``run.to_pandas()``.
    A run keeps every sample in memory (about 0.9 MB per simulated second per channel at 100 kHz);
    stream long runs to files with :func:`twin.simulation.simulate` and its sinks instead.

    >>> import twin
    >>> run = twin.simulate(twin.preset(6), duration=0.05, overrides={"sensors.channels": ["crank"]})
    >>> list(run.channels)
    ['crank_angle', 'crank_speed']
    >>> run.channels["crank_speed"].unit
    'rad/s'
    """
    from twin.simulation import ThreadedSink, simulate_run

    if cfg is None or isinstance(cfg, (int, str)):
        cfg = preset(6 if cfg is None else cfg)
    if not isinstance(cfg, BenchConfig):
        raise ConfigError("cfg", f"must be a BenchConfig, a Table 4 test id or a preset name, got {type(cfg).__name__}")
    changes = _overrides(overrides)
    if duration is not None:
        changes["simulation.duration_s"] = _number(duration, "duration")
    if engine is not None:
        if not isinstance(engine, str):
            raise TypeError(f"engine: must be an engine name (str), got {type(engine).__name__}")
        changes["simulation.engine"] = engine
    if not isinstance(progress, bool):
        raise TypeError(f"progress: must be True or False, got {type(progress).__name__}")
    if changes:
        cfg = cfg.replace(**changes)
    sinks = []
    if out is not None:
        from twin.mcapfile import RunWriter
        from twin.util import check_output_file

        sinks.append(ThreadedSink(RunWriter(check_output_file(_path(out, "out"), "out", ".mcap"), cfg)))
    return simulate_run(cfg, progress=progress, sinks=sinks)


def replay(recording: str | Path, out_dir: str | Path, *, overrides: Mapping[str, Any] | None = None,
           window_s: tuple[float, float] | None = None, plots: bool = True, progress: bool = False) -> ReplayResult:
    """Replay a bench recording through the twin, as ``twin replay`` does.

    The recorded encoder angle drives the simulation; the simulated accelerations go through the
    bench's sensor chain and calibration and are compared with the recorded ones over the analysis
    window ``window_s`` = (start, stop) [s] from the recording's first sample (default: the second
    half, at most 1 s). ``overrides``: fields of the recording's configuration to change by dotted
    name (``{"joints.clearance_c_mm": 0.0}`` replays with an ideal joint C).

    Writes ``out_dir`` (``replay.mcap``, ``report.json``, ``report.md``, PNG plots unless
    ``plots=False``) and returns the report as a :class:`twin.replay_result.ReplayResult`:
    ``.sensors`` (per accelerometer a :class:`~twin.replay_result.SensorComparison`: RMS error, NRMSE,
    correlation, DTW distance, harmonics, band energies), ``.time_lag_s``, ``.tracking`` (crank tracking error), ``.window_s`` (the analysis
    window [s]), ...; ``.to_dict()`` is the report as ``report.json`` holds it
    (``recordings/FORMAT.md`` describes the files).
    """
    from twin.bench_replay import ReplayOptions
    from twin.bench_replay import replay as bench_replay

    recording, out_dir = _path(recording, "recording"), _path(out_dir, "out_dir")
    changes = _overrides(overrides)
    if window_s is not None:
        if isinstance(window_s, (str, bytes)) or not hasattr(window_s, "__len__") or len(window_s) != 2:
            raise TypeError(f"window_s: must be a pair (start, stop) of times [s], got {window_s!r}")
        window_s = (_number(window_s[0], "window_s"), _number(window_s[1], "window_s"))
        if not (math.isfinite(window_s[0]) and math.isfinite(window_s[1]) and 0 <= window_s[0] < window_s[1]):
            raise ConfigError("window_s", f"must be finite times 0 <= start < stop [s], got {window_s!r}")
    for name, flag in (("plots", plots), ("progress", progress)):
        if not isinstance(flag, bool):
            raise TypeError(f"{name}: must be True or False, got {type(flag).__name__}")
    configure = (lambda c: c.replace(**changes)) if changes else None
    return bench_replay(recording, out_dir, configure,
                        ReplayOptions(window_s=window_s, plots=plots, progress=progress))


def plot(source: str | Path | Run, out: str | Path, *, channels: Sequence[str] | None = None,
         window: tuple[float, float] | None = None, spectrum: bool = False,
         size_px: tuple[int, int] | None = None) -> Any:
    """Draw a run file, a bench recording, a replay folder (or a :class:`~twin.run.Run`) as the PNG
    ``out``, as ``twin plot`` does: matplotlib, no GPU, no display.

    ``channels``: names or shell-style globs (default: accelerometers and contact forces);
    ``window``: (start, stop) [s] (default: the last 0.4 s, with spectra the last second);
    ``spectrum``: add Hann spectra with the crank harmonics and the bands; ``size_px``: (width,
    height). Returns a :class:`twin.viz.plot.PlotInfo` (channels drawn, window, crank rate,
    harmonics marked, orbits' clearance radii, ...).
    """
    from twin.viz.plot import plot as draw_png

    return draw_png(source, out, channels=channels, window=window, spectrum=spectrum, size_px=size_px)


def identify(recording: str | Path, model: str | Path | None = None) -> IdentifyResult:
    """Locate and size the clearance faults of a bench recording, as ``twin identify clearance``.

    ``model``: a model file made by ``twin identify train``, or a shipped model by name: ``"default"``
    (B and C; used when None) or ``"bench"`` (B, C and the slider guide G, trained on recordings of the
    whole bench). Returns a :class:`twin.identification.results.IdentifyResult`: ``.fault`` (``"none"``,
    ``"B"``, ``"C"``, ``"BC"``; with the bench model also ``"G"``, ``"BG"``, ``"CG"``, ``"BCG"``),
    ``.probabilities`` per class, ``.joint("B")``, ``.joint("C")`` (and ``.joint("G")``)
    (``.size_mm``, 0 for a ball bearing, with its 90 % ``.interval_mm`` [mm]; ``.size_resolved``;
    ``.size_held_out``: how often the model's sizes held within x1.5 at this speed and orientation in
    training runs left out, None for a model without that table), ``.warnings`` (e.g. a size the
    bench's sensors do not resolve at that speed), ``.evidence`` (windows, revolutions, crank rate,
    model) and ``.seconds``; ``.to_dict()`` and ``.to_json()`` give the answer as ``--json`` writes it.

    A model file is plain arrays and JSON: loading one runs no code from it (a pickle is refused).

    >>> import twin
    >>> a = twin.identify(twin.samples.path("test6"))
    >>> a.fault, a.joint("C").size_mm > 0, a.joint("B").size_mm
    ('C', True, 0.0)
    """
    from twin.identification.model import SHIPPED_MODELS, ClearanceModel, ModelError, identify_recording, resolve_model

    recording = _path(recording, "recording")
    path = resolve_model(model if isinstance(model, str) and model in SHIPPED_MODELS else
                         (_path(model, "model") if model is not None else None))
    if model is None and not path.is_file():
        raise ModelError(f"no default model in this installation ({path}); give model=PATH")
    return identify_recording(ClearanceModel.load(path), recording)
