"""Replay a bench recording through the twin and plot recorded against simulated acceleration.

``twin.replay`` drives the simulation with the recording's encoder angle, passes the simulated
accelerations through the bench's sensor chain and calibration, compares them and writes a
folder (``replay.mcap``, ``report.json``, ...). This script then reads both signals back from
``replay.mcap`` and plots one sensor over the report's analysis window (a PNG).

    python examples/replay_plot.py --out replay_ac6.png                      # test 6, 1.5 s
    python examples/replay_plot.py recordings/test3_synthetic.mcap --sensor AC4 --out ac4.png
    python examples/replay_plot.py --small --out replay_ac6.png              # a 0.8 s recording (a test)

The sample recordings ship with twin (``twin.samples.path(NAME)``, the files of recordings/); they are
SYNTHETIC (made by the reference engine), not bench data.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import twin


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("recording", nargs="?", help="recording (.mcap; default: the sample recording test6)")
    ap.add_argument("--sensor", default="AC6", help="accelerometer to plot, AC1..AC6 (default AC6)")
    ap.add_argument("--out", default="replay.png", help="PNG to write (default: replay.png)")
    ap.add_argument("--keep", metavar="DIR", help="keep the replay folder there (default: a temporary folder)")
    ap.add_argument("--small", action="store_true", help="the 0.8 s sample recording, no report plots (quick check)")
    args = ap.parse_args(argv)

    rec = Path(args.recording) if args.recording else twin.samples.path("test6_repeat1" if args.small else "test6")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(args.keep) if args.keep else Path(tmp) / "replay"
        report = twin.replay(rec, folder, plots=not args.small)
        s = report.sensors[args.sensor]
        print(f"{rec.name}: {args.sensor} NRMSE {s.nrmse_pct:.2f} %, correlation {s.correlation:.4f} "
              f"over {report.window_s[0]:.3f}-{report.window_s[1]:.3f} s")
        from twin.mcapfile import read_run

        both = read_run(folder / "replay.mcap", groups=["meas_accel", "sim_meas_accel"])
    t0, t1 = report.window_s
    w = both.window(both.t0 + t0, both.t0 + t1)
    t = w.time - both.t0

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(t, w[f"meas_{args.sensor}"], lw=0.8, label="recorded")
    ax.plot(t, w[f"sim_meas_{args.sensor}"], lw=0.8, label="twin")
    ax.set_xlabel("time from the recording's start [s]")
    ax.set_ylabel(f"{args.sensor} [m/s²]")
    ax.set_title(f"{rec.name}: {args.sensor}, the report's analysis window")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
