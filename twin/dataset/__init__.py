"""Synthetic datasets of the bench (``twin dataset``): specs, designs, generation, reading.

* :mod:`twin.dataset.spec`: the TOML spec (base configuration, factors, design, outputs, splits);
* :mod:`twin.dataset.factors`: what can be varied and how a value becomes configuration;
* :mod:`twin.dataset.design`: design points, seeds, run ids, configurations, splits;
* :mod:`twin.dataset.worker`: one run in a worker (simulate, sensor chain, Parquet);
* :mod:`twin.dataset.generate`: the driver (resume, process pool or Dask, manifest);
* :mod:`twin.dataset.reader`: ``open(DIR)``, windows for training, ``verify``, ``describe``, ``summary``.

The layout is documented in ``twin/dataset/FORMAT.md``.

The names below are loaded on first use (PEP 562), so importing one submodule (a study reading a
spec, the CLI registering its commands) does not import the reader and the driver with it.
"""

from __future__ import annotations

import importlib
from typing import Any

_LAZY = {"Dataset": "reader", "describe": "reader", "open": "reader", "summary": "reader", "verify": "reader",
         "DatasetSpec": "spec", "SpecError": "spec", "load_spec": "spec"}
__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(f"twin.dataset.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'twin.dataset' has no attribute {name!r}")
