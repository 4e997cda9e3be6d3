"""What writing the output costs, as a share of a run's wall time, for both engines.

For Table 4 test 12 (B+C, all channels of the default groups, 100 kHz) over ``--duration``
simulated seconds, :func:`twin.simulation.simulate` runs in this process, interleaved, best of
``--repeats``, with:

* ``none``: no sink (engine build, stepping, the chunk loop and the summary);
* ``mcap``: the MCAP run file writer (:class:`twin.mcapfile.RunWriter`) called in the chunk loop;
* ``mcap, thread``: the same writer behind :class:`twin.simulation.ThreadedSink` (what
  ``twin simulate`` does);
* ``dataset``: what a dataset worker writes (``twin/dataset/worker.py``: the default outputs,
  truth groups accel, encoder, joints plus every instrumented channel: the streaming sensor chain
  and calibration, then :class:`twin.dataset.storage.ParquetRunWriter`), in the loop;
* ``dataset, thread``: the same behind :class:`~twin.simulation.ThreadedSink` (what the worker does).

Reported per engine and output: the wall time of the whole ``simulate`` call, the engine's
stepping time (``meta["wall_s"]``, which grows when a writer thread competes for the core), what
the output adds to the wall time (wall − wall of ``none``) and its share of the wall time; for
the in-loop variants also the time inside the sink's calls, for the dataset split between the
sensor chain and the Parquet writer. Files go to a temporary folder and are deleted.

``--mcap-variants`` instead compares the MCAP writer's chunk codec and block size (LZ4 or none,
1000 or 5000 samples per message), in the loop and on a writer thread, against no output, per
engine, interleaved, best of ``--repeats``: the measurement behind ``twin.mcapfile``'s choice.

Run: ``python analysis/bench_output.py [--duration S (4)] [--repeats R] [--engines mujoco,reference]
[--mcap-variants]``.
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

from twin.config import preset
from twin.simulation import ThreadedSink, simulate


class Timed:
    """Sink wrapper adding up the time spent in ``write`` and ``close``."""

    def __init__(self, inner) -> None:
        self.inner, self.s = inner, 0.0

    def write(self, chunk) -> None:
        t0 = time.perf_counter()
        self.inner.write(chunk)
        self.s += time.perf_counter() - t0

    def close(self, meta, summary):
        t0 = time.perf_counter()
        out = self.inner.close(meta, summary)
        self.s += time.perf_counter() - t0
        return out

    def abort(self) -> None:
        self.inner.abort()


def make_sinks(kind: str, cfg, folder: Path) -> tuple[list, dict[str, Timed]]:
    """The sinks of a variant and the timers to read after the run."""
    if kind == "none":
        return [], {}
    if kind.endswith(", thread"):
        sinks, _ = make_sinks(kind.split(",")[0], cfg, folder)
        return [ThreadedSink(sinks[0])], {}
    if kind == "mcap":
        from twin.mcapfile import RunWriter

        t = Timed(RunWriter(folder / "run.mcap", cfg))
        return [t], {"sink": t}
    from twin.dataset.storage import ParquetRunWriter
    from twin.dataset.worker import INSTRUMENTED_CHANNELS, InstrumentSink, column_specs

    inst = tuple(INSTRUMENTED_CHANNELS)
    cols = column_specs(cfg, ("accel", "encoder", "joints"), inst, "auto")
    parquet = Timed(ParquetRunWriter(folder / "run.parquet", cols, "bench", {"name": cfg.name,
                                                                             "config_toml": cfg.to_toml()}))
    outer = Timed(InstrumentSink(cfg, cols, parquet, inst))
    return [outer], {"sink": outer, "parquet": parquet}


MCAP_VARIANTS = {"lz4, 1000": ("lz4", 1000), "lz4, 5000": ("lz4", 5000), "none, 1000": ("none", 1000),
                 "none, 5000 (default)": ("none", 5000)}


def mcap_variants(engines: list[str], duration: float, repeats: int) -> None:
    """The ``--mcap-variants`` table (see the module docstring)."""
    from twin.mcapfile import RunWriter

    cfgs = {e: preset(12).replace(**{"simulation.engine": e, "simulation.duration_s": duration}) for e in engines}
    best: dict[tuple[str, str, bool], float] = {}
    with tempfile.TemporaryDirectory(prefix="twin_bench_output_") as tmp:
        folder = Path(tmp)
        for e in engines:
            simulate(cfgs[e].replace(**{"simulation.duration_s": 0.02}))
        for _ in range(repeats):
            for e in engines:
                for name, (codec, block) in [("no output", (None, 0)), *MCAP_VARIANTS.items()]:
                    for thread in ((False,) if codec is None else (False, True)):
                        sinks = []
                        if codec is not None:
                            w = RunWriter(folder / "run.mcap", cfgs[e], block=block, compression=codec)
                            sinks = [ThreadedSink(w) if thread else w]
                        t0 = time.perf_counter()
                        simulate(cfgs[e], sinks)
                        wall = time.perf_counter() - t0
                        best[(e, name, thread)] = min(best.get((e, name, thread), math.inf), wall)
                        for f in folder.iterdir():
                            f.unlink()
    print(f"test 12, {duration:g} s at 100 kHz, MCAP codec and block size, best of {repeats} (interleaved)")
    print()
    print("| engine | codec, samples per block | in the loop: wall [s], share | on a thread: wall [s], share |")
    print("|---|---|---:|---:|")
    for e in engines:
        base = best[(e, "no output", False)]
        print(f"| {e} | no output | {base:.3f} | |")
        for name in MCAP_VARIANTS:
            a, b = best[(e, name, False)], best[(e, name, True)]
            print(f"| {e} | {name} | {a:.3f}, {(a - base) / a:.1%} | {b:.3f}, {(b - base) / b:.1%} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=4.0)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--engines", default="mujoco,reference")
    ap.add_argument("--mcap-variants", action="store_true", help="compare MCAP codecs and block sizes instead")
    args = ap.parse_args()
    engines = args.engines.split(",")
    if args.mcap_variants:
        mcap_variants(engines, args.duration, args.repeats)
        return
    kinds = ("none", "mcap", "mcap, thread", "dataset", "dataset, thread")
    cfgs = {e: preset(12).replace(**{"simulation.engine": e, "simulation.duration_s": args.duration})
            for e in engines}
    best: dict[tuple[str, str], dict[str, float]] = {}
    with tempfile.TemporaryDirectory(prefix="twin_bench_output_") as tmp:
        folder = Path(tmp)
        for e in engines:  # warm-up: numba cache load, first-run costs
            simulate(cfgs[e].replace(**{"simulation.duration_s": 0.02}), make_sinks("dataset", cfgs[e], folder)[0])
        for _ in range(args.repeats):
            for e in engines:
                for k in kinds:
                    sinks, timers = make_sinks(k, cfgs[e], folder)
                    t0 = time.perf_counter()
                    out = simulate(cfgs[e], sinks)
                    wall = time.perf_counter() - t0
                    rec = {"wall": wall, "engine": out.meta["wall_s"], **{n: t.s for n, t in timers.items()}}
                    if wall < best.get((e, k), {"wall": math.inf})["wall"]:
                        best[(e, k)] = rec
                    for f in folder.iterdir():
                        f.unlink()
    from twin.provenance import git_commit

    commit = git_commit()
    print(f"test 12, {args.duration:g} s simulated at 100 kHz output, best of {args.repeats} (interleaved), "
          f"commit {commit or '?'}")
    print()
    print("| engine | output | wall [s] | engine stepping [s] | added wall [s] | share of wall | "
          "in the sink's calls [s] | of which sensor chain [s] | of which Parquet [s] |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for e in engines:
        for k in kinds:
            r = best[(e, k)]
            added = r["wall"] - best[(e, "none")]["wall"]
            sink = f"{r['sink']:.3f}" if "sink" in r else ""
            chain = f"{r['sink'] - r['parquet']:.3f}" if "parquet" in r else ""
            pq = f"{r['parquet']:.3f}" if "parquet" in r else ""
            print(f"| {e} | {k} | {r['wall']:.3f} | {r['engine']:.3f} | {added:.3f} | {added / r['wall']:.1%} | "
                  f"{sink} | {chain} | {pq} |")


if __name__ == "__main__":
    main()
