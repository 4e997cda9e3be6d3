"""Synthetic datasets of the bench (``twin dataset``): specs, designs, generation, reading.

* :mod:`twin.dataset.spec`: the TOML spec (base configuration, factors, design, outputs, splits);
* :mod:`twin.dataset.factors`: what can be varied and how a value becomes configuration;
* :mod:`twin.dataset.design`: design points, seeds, run ids, configurations, splits;
* :mod:`twin.dataset.worker`: one run in a worker (simulate, sensor chain, Parquet);
* :mod:`twin.dataset.generate`: the driver (resume, process pool or Dask, manifest);
* :mod:`twin.dataset.reader`: ``open(DIR)``, windows for training, ``verify``, ``describe``.

The layout is documented in ``twin/dataset/FORMAT.md``.
"""

from twin.dataset.reader import Dataset, describe, open, verify  # noqa: A004 - twin.dataset.open(DIR)
from twin.dataset.spec import DatasetSpec, SpecError, load_spec

__all__ = ["Dataset", "DatasetSpec", "SpecError", "describe", "load_spec", "open", "verify"]
