"""Digital twin of a configurable slider-crank clearance test bench.

The Python API (each name is imported on first use, so ``import twin`` stays quick):

* ``twin.preset(6)``, ``twin.preset("s001")``: a bench configuration, a frozen
  :class:`twin.config.BenchConfig` (Table 4 test 1..12 of the bench paper, or another mechanism);
* ``twin.simulate(cfg, duration=0.5)``: simulate it; returns a :class:`twin.run.Run` in memory
  (``run.time`` [s], ``run["AC6"]`` a numpy array per channel, ``run.to_pandas()``);
* ``twin.record(cfg, "rec.mcap")``: simulate ``cfg`` and write a bench recording of it through the
  sensor chain (DAQ volts, encoder counts, motor command, static calibration), as the bench's DAQ
  would; returns a :class:`twin.bench_record.RecordResult`;
* ``twin.replay(recording, out_dir)``: replay a bench recording through the twin; returns the
  report (a :class:`twin.replay_result.ReplayResult`; ``.to_dict()``) and writes the comparison folder;
* ``twin.dataset.open(DIR)``: a generated dataset (:class:`twin.dataset.Dataset`: manifest,
  signals, training windows as numpy arrays);
* ``twin.calibrate(recordings, ["contact.mu0"], "out_dir")``: fit configuration fields to bench
  recordings, with intervals; returns a :class:`twin.calibration.CalibrationResult` and writes
  ``calibrated.toml`` and a report;
* ``twin.identify(recording)``: locate and size the clearance faults of a recording; returns the
  answer (a :class:`twin.identification.results.IdentifyResult`: ``.fault``, ``.joint("C").size_mm``, ...);
* ``twin.samples.path("test6")``, ``twin.samples.spec_path("tiny")``: the sample recordings and
  dataset specs that ship with the package, by name;
* ``twin.plot(source, "fig.png")``: draw a run file, recording, replay folder or run as a PNG
  (channels, spectra, journal orbits; matplotlib, no GPU); returns what it drew;
* ``twin.__version__``: the package version.

>>> import twin
>>> run = twin.simulate(twin.preset(6), duration=0.05)
>>> round(run.duration_s, 6), run.channels["AC6"].unit
(0.05, 'm/s^2')

The command line does the same and more: ``twin --help``. Streaming long runs to files, engines
and sinks: :mod:`twin.simulation`.
"""

from __future__ import annotations

import importlib

__version__ = "0.4.0"

#: the API's calls, by the module that defines them
_CALLS = {"preset": "twin.api", "simulate": "twin.api", "replay": "twin.api", "identify": "twin.api",
          "plot": "twin.api", "record": "twin.bench_record", "calibrate": "twin.calibration", "BenchConfig": "twin.config", "Run": "twin.run"}
#: subpackages and modules reached as attributes (``twin.dataset.open``) without importing them first
_MODULES = ("api", "config", "dataset", "errors", "run", "samples", "simulation")

__all__ = ["__version__", *sorted(_CALLS)]


def __getattr__(name: str) -> object:  # PEP 562: import on first use
    if name in _CALLS:
        value = getattr(importlib.import_module(_CALLS[name]), name)
        globals()[name] = value  # later look-ups skip this function
        return value
    if name in _MODULES:
        return importlib.import_module(f"twin.{name}")  # the import sets the attribute itself
    raise AttributeError(f"module 'twin' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_CALLS, *_MODULES})
