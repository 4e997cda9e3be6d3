"""A twin dataset in a PyTorch-style loader, without torch.

``twin.dataset.open(DIR)`` reads a dataset folder made by ``twin dataset generate``. This script
wraps its windows in the two things a training loop needs, written with numpy only:

* ``WindowDataset``: a map-style dataset (``len(ds)``, ``ds[i]`` -> (window, label)), the interface
  of ``torch.utils.data.Dataset``, so ``torch.utils.data.DataLoader(WindowDataset(...))`` works
  unchanged where torch is installed;
* ``batches(ds, batch_size)``: a batching iterator (shuffled, seeded) giving ``x`` float32
  [batch, channels, samples] and ``y`` int64 [batch] (fault class index).

    python examples/loader.py DIR                 # an existing dataset folder
    python examples/loader.py --small             # generates a 4-run dataset in a temporary folder
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path
from typing import Iterator

import numpy as np

import twin

CLASSES = ("none", "B", "C", "BC")  # fault classes of the dataset's labels


class WindowDataset:
    """Fixed-length windows of the runs of one split, with the run's fault class as the label.

    The window index (run, first sample) is built once; ``ds[i]`` reads that window from the run's
    Parquet file (one column slice per channel), so memory holds one window at a time.
    """

    def __init__(self, path: str | Path, split: str = "train", channels: list[str] | None = None,
                 length_s: float = 0.02, normalize: bool = True):
        self.ds = twin.dataset.open(path)
        self.channels = channels or [c for c in self.ds.channels if c.startswith("meas_AC")] or \
            [c for c, d in self.ds.channels.items() if d["dtype"].startswith("float")]
        self.length = int(round(length_s * self.ds.rate_hz))
        self.index: list[tuple[str, int, int]] = []  # (run id, first sample, class index)
        for row in self.ds.rows(split):
            n = int(round(row["duration_s"] * self.ds.rate_hz))  # samples of the run
            for start in range(0, n - self.length + 1, self.length):
                self.index.append((row["run_id"], start, CLASSES.index(row["fault"])))
        if normalize:
            st = self.ds.stats
            self.mean = np.array([st[c]["mean"] for c in self.channels], np.float32)[:, None]
            self.std = np.array([st[c]["std"] or 1.0 for c in self.channels], np.float32)[:, None]
        else:
            self.mean, self.std = np.float32(0), np.float32(1)

    def __len__(self) -> int:
        return len(self.index)

    def __getitem__(self, i: int) -> tuple[np.ndarray, int]:
        run_id, start, label = self.index[i]
        cols = self.ds.read(run_id, self.channels, start, start + self.length)
        x = np.stack([np.asarray(cols[c], np.float32) for c in self.channels])
        return (x - self.mean) / self.std, label


def batches(ds: WindowDataset, batch_size: int = 32, shuffle: bool = True, seed: int = 0,
            drop_last: bool = False) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Batches of (x float32 [batch, channels, samples], y int64 [batch]), like a DataLoader."""
    order = np.random.default_rng(seed).permutation(len(ds)) if shuffle else np.arange(len(ds))
    for k in range(0, len(order), batch_size):
        idx = order[k:k + batch_size]
        if drop_last and len(idx) < batch_size:
            return
        items = [ds[int(i)] for i in idx]
        yield np.stack([x for x, _ in items]), np.array([y for _, y in items], np.int64)


def small_dataset(out: Path) -> Path:
    """A 4-run dataset (one run per fault class, 0.1 s, truth accelerations) generated in ``out``."""
    from twin.dataset.generate import generate
    from twin.dataset.spec import parse_spec

    spec = parse_spec({
        "dataset": {"name": "loader-example", "seed": 1},
        "base": {"test": 3, "duration_s": 0.1, "program": "constant"},
        "design": {"kind": "grid"},
        "factors": {"fault": ["none", "B", "C", "BC"]},
        "outputs": {"truth": ["accel"], "instrumented": False, "rate_hz": 10000.0},
        "splits": {"train": 0.5, "val": 0.25, "test": 0.25},
    })
    generate(spec, out, workers=1, scheduler="threads", progress=False)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset", nargs="?", help="dataset folder (twin dataset generate SPEC --out DIR)")
    ap.add_argument("--small", action="store_true", help="generate a 4-run dataset in a temporary folder")
    ap.add_argument("--batch-size", type=int, default=8)
    args = ap.parse_args(argv)
    if not args.dataset and not args.small:
        ap.error("give a dataset folder or --small")

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(args.dataset) if args.dataset else small_dataset(Path(tmp) / "ds")
        train = WindowDataset(path, "train")
        print(f"{path.name}: {len(train)} training windows of {train.length} samples, channels "
              f"{', '.join(train.channels)}")
        x0, y0 = train[0]
        print(f"train[0]: x {x0.dtype} {x0.shape}, label {y0} ({CLASSES[y0]})")
        n = 0
        for x, y in batches(train, args.batch_size):
            n += len(y)
            print(f"batch: x {x.dtype} {x.shape}, y {y.dtype} {y.tolist()}")
        assert n == len(train)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
