"""Parameter sweep: how the clearance at joint C shows in the slider's acceleration.

Simulates Table 4 test 6 (750 motor rpm) with the clearance at joint C (diametral, the
bearing catalogue's values) swept from a ball bearing (0) to 0.5 mm, and plots the RMS and the peak of the slider-side accelerometer AC6
over the last half of each run against the clearance (a PNG). Every run is an in-memory
``twin.run.Run`` from ``twin.simulate``.

    python examples/sweep.py --out sweep.png            # 6 clearances, 1 s each (about 10 s)
    python examples/sweep.py --small --out sweep.png    # 2 clearances, 0.05 s each (a test)
"""

from __future__ import annotations

import argparse

import numpy as np

import twin


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="sweep.png", help="PNG to write (default: sweep.png)")
    ap.add_argument("--small", action="store_true", help="two clearances, 0.05 s each (quick check)")
    args = ap.parse_args(argv)

    clearances_mm = [0.0, 0.1] if args.small else [0.0, 0.02, 0.05, 0.07, 0.1, 0.5]
    duration_s = 0.05 if args.small else 1.0
    base = twin.preset(6)
    rms, peak = [], []
    for c in clearances_mm:
        run = twin.simulate(base, duration=duration_s,
                            overrides={"joints.clearance_c_mm": c, "sensors.channels": ["accel"]})
        a = run["AC6"][run.n // 2:]  # the last half: past the start from rest
        rms.append(float(np.sqrt(np.mean((a - a.mean()) ** 2))))
        peak.append(float(np.max(np.abs(a - a.mean()))))
        print(f"clearance C {c:.2f} mm: AC6 RMS {rms[-1]:8.1f} m/s^2, peak {peak[-1]:8.1f} m/s^2")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(clearances_mm, rms, "o-", label="RMS")
    ax.plot(clearances_mm, peak, "s--", label="peak")
    ax.set_xlabel("diametral clearance at joint C [mm]")
    ax.set_ylabel("AC6 acceleration, mean removed [m/s²]")
    ax.set_title(f"Test 6, 750 rpm, last {duration_s / 2:g} s of {duration_s:g} s")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
