"""What the MCAP preview topic costs in size and write time (``twin simulate --preview-rate``).

Method: Table 4 test 12 (B+C clearances, the default channel groups: 23 channels at 100 kHz) is
simulated once per duration into memory (``--durations``: 2 s, and 38 s of the three-speed
protocol by default); the same run is then written with :func:`twin.mcapfile.write_run` without
and with a preview at ``--rate`` Hz, alternately (which of the two goes first alternates too: a
file written right after another meets the page cache's write-back of the first), ``--repeats``
times each, in 0.05 s chunks as ``twin simulate`` hands them to its writer; the best time of each
is kept (the least disturbed by other processes on a shared machine). The time spent in the
preview's own code (block means, CDR records, ``add_message``) is also timed on its own. Reported:
the file sizes, the write times and their difference, the preview's own time, and the
simulation's wall time, to put them in proportion (``twin simulate`` writes on a thread beside
the stepping, so the run's wall time grows by at most the added write time). Files go to a
temporary folder and are deleted.

Run: ``python analysis/bench_preview.py [--durations 2,38] [--rate 1000] [--repeats 3] [--engine mujoco]``.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import twin.mcapfile
from twin.config import preset
from twin.mcapfile import RunWriter
from twin.simulation import simulate_run

_OWN = [0.0]
_add = twin.mcapfile._Preview.add


def _timed_add(self, chunk) -> None:
    t0 = time.perf_counter()
    _add(self, chunk)
    _OWN[0] += time.perf_counter() - t0


twin.mcapfile._Preview.add = _timed_add


def write(path: Path, run, rate: float, chunk: int) -> float:
    t0 = time.perf_counter()
    with RunWriter(path, run.config, preview_rate_hz=rate) as w:
        for i in range(0, run.n, chunk):
            w.write(run.slice(i, min(run.n, i + chunk)))
        w.close(run.meta)
    return time.perf_counter() - t0


def measure(duration: float, rate: float, engine: str, repeats: int, folder: Path) -> dict:
    cfg = preset(12).replace(**{"simulation.engine": engine})
    if duration >= 38:
        cfg = cfg.replace(**{"drive.program": "protocol", "simulation.duration_s": 0.0})
    else:
        cfg = cfg.replace(**{"simulation.duration_s": duration})
    t0 = time.perf_counter()
    run = simulate_run(cfg)
    sim_wall = time.perf_counter() - t0
    chunk = int(round(0.05 * run.rate_hz))
    best = {0.0: float("inf"), rate: float("inf")}
    own = float("inf")
    sizes = {}
    for k in range(repeats):
        for r in ((0.0, rate) if k % 2 == 0 else (rate, 0.0)):
            p = folder / f"r{r:g}.mcap"
            _OWN[0] = 0.0
            best[r] = min(best[r], write(p, run, r, chunk))
            if r:
                own = min(own, _OWN[0])
            sizes[r] = p.stat().st_size
            p.unlink()
    return {"simulated_s": run.n / run.rate_hz, "sim_wall_s": sim_wall, "write_plain_s": best[0.0],
            "write_preview_s": best[rate], "preview_own_s": own, "bytes_plain": sizes[0.0], "bytes_preview": sizes[rate],
            "messages": run.n // max(1, int(round(run.rate_hz / rate))), "channels": len(run.channels)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--durations", default="2,38", help="simulated seconds, comma separated (38: the protocol)")
    ap.add_argument("--rate", type=float, default=1000.0, help="preview rate [Hz]")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--engine", default="mujoco")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        for dur in (float(x) for x in args.durations.split(",")):
            r = measure(dur, args.rate, args.engine, args.repeats, Path(d))
            added = r["write_preview_s"] - r["write_plain_s"]
            print(f"test 12, {r['simulated_s']:g} s ({args.engine}, {r['channels']} channels), preview at "
                  f"{args.rate:g} Hz, {r['messages']} messages: file {r['bytes_plain'] / 1e6:.2f} -> "
                  f"{r['bytes_preview'] / 1e6:.2f} MB (+{(r['bytes_preview'] / r['bytes_plain'] - 1) * 100:.2f} %, "
                  f"{(r['bytes_preview'] - r['bytes_plain']) / max(r['messages'], 1):.0f} bytes per message); "
                  f"write {r['write_plain_s']:.2f} -> {r['write_preview_s']:.2f} s (+{added:.2f} s, "
                  f"best of {args.repeats}; the preview's own code {r['preview_own_s']:.2f} s, "
                  f"{r['preview_own_s'] / max(r['messages'], 1) * 1e6:.1f} us per message); "
                  f"simulation {r['sim_wall_s']:.1f} s wall (write difference {added / r['sim_wall_s'] * 100:.1f} %, "
                  f"preview's code {r['preview_own_s'] / r['sim_wall_s'] * 100:.1f} % of it)")


if __name__ == "__main__":
    main()
