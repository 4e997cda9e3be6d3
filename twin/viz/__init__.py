"""Visual inspection of runs and recordings in rerun.

* :func:`convert_file`: a run/recording MCAP file -> ``.rrd`` (``twin view``);
* :func:`write_rrd`: an in-memory :class:`~twin.run.Run` -> ``.rrd``;
* :class:`RerunWriter`: the streaming sink behind both, also used by
  ``twin simulate --rerun`` to record a run while it is simulated;
* :mod:`twin.viz.pose`: body poses reconstructed from the run's channels.
* :mod:`twin.viz.spatial_view`: the same for the spatial slider–crank (``spatial.enabled``);
* :mod:`twin.viz.plot`: static PNG figures with matplotlib (``twin plot``), no rerun, GPU or display.

The recording holds the 3-D bench moving in time, the clearance joints' journal orbits,
contact force arrows, every channel as a time series, spectra of a window and the
configuration, with a default blueprint (:mod:`twin.viz.blueprint`).
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

#: ``RUST_LOG`` as the user's environment had it (None: unset). Unset, the twin silences the rerun SDK's
#: own log lines in this process before rerun is imported (they would print e.g. "ERROR ... file_sink:
#: Failed to write" above the twin's one-line error on a full disk; every failure the SDK reports is
#: raised and reported by the twin itself); the viewer processes the twin starts get the user's value
#: back (:func:`twin.commands.view` quotes their messages).
USER_RUST_LOG = os.environ.get("RUST_LOG")
if USER_RUST_LOG is None:
    os.environ["RUST_LOG"] = "off"

from twin.run import Run
from twin.viz.options import ViewOptions

# RerunWriter (and with it rerun, about 0.6 s to import) is loaded on first use: twin.viz.plot and
# twin.viz.spectrum do not need it

__all__ = ["RerunWriter", "ViewOptions", "convert_file", "default_output", "file_recording_id",
           "simulation_recording_id", "write_rrd"]


def __getattr__(name: str) -> object:  # PEP 562
    if name == "RerunWriter":
        from twin.viz.writer import RerunWriter

        globals()[name] = RerunWriter
        return RerunWriter
    raise AttributeError(f"module 'twin.viz' has no attribute {name!r}")


def file_recording_id(path: str | Path) -> str:
    """Recording id derived from a file's content (SHA-256): same input, same id."""
    with open(path, "rb") as fh:
        return "twin-" + hashlib.file_digest(fh, "sha256").hexdigest()[:32]


def simulation_recording_id(cfg_digest: str) -> str:
    """Recording id of a run streamed while it is simulated: from its configuration digest."""
    return f"twin-sim-{cfg_digest}"


def default_output(path: str | Path) -> Path:
    """``RUN.mcap`` -> ``RUN.rrd`` beside it."""
    return Path(path).with_suffix(".rrd")


def write_rrd(run: Run, out: str | Path, *, recording_id: str, name: str, options: ViewOptions = ViewOptions(),
              source: str = "", summary: dict | None = None) -> Path:
    """Write ``run`` as a rerun recording ``out`` (temp file + rename)."""
    from twin.viz.writer import RerunWriter

    w = RerunWriter(out, run.config, recording_id=recording_id, name=name, options=options,
                    t_start=run.t0, t_end=run.t0 + run.duration_s, source=source)
    try:
        w.write(run)
        return w.close(run.meta, summary)
    except BaseException:
        w.abort()
        raise


def convert_file(path: str | Path, out: str | Path | None = None, options: ViewOptions = ViewOptions(),
                 timings: dict[str, float] | None = None) -> Path:
    """Convert a twin run file (simulated run, bench recording or replay) into ``out``.

    ``timings`` (optional) receives the measured wall times [s] of ``read`` (MCAP -> Run),
    ``hash`` (recording id) and ``convert`` (Run -> .rrd, flushed and renamed).
    """
    import time

    from twin.mcapfile import read_run, read_summary

    p = Path(path)
    out = Path(out) if out is not None else default_output(p)
    if out.resolve() == p.resolve():
        from twin.errors import TwinError

        raise TwinError(f"{out}: output would overwrite the input")
    t0 = time.perf_counter()
    run = read_run(p)
    summary = read_summary(p)
    t1 = time.perf_counter()
    if run.n == 0:
        from twin.errors import TwinError

        raise TwinError(f"{p}: the run holds no samples")
    rid = file_recording_id(p)
    t2 = time.perf_counter()
    path = write_rrd(run, out, recording_id=rid, name=p.stem, options=options, source=p.name, summary=summary)
    if timings is not None:
        timings.update(read=t1 - t0, hash=t2 - t1, convert=time.perf_counter() - t2)
    return path
