"""Where the identification model's sizes hold: the held-out size accuracy a model file carries, as a figure and a
Markdown table.

Method. ``twin.identification.model.train`` answers every training run with a clearance at a joint by a size
regressor fitted without that run's fold (the shipped model: folds by motor speed, so each answer is one at a speed
its regressor never saw) and keeps, per joint, orientation and training speed, the share of those answers within a
factor 1.5 of the truth and the number of runs (``trained_on["held_out_size_accuracy"]``; every recording's answer
reads its own speed's from it). This script only reads the model file: nothing is fitted or simulated. The shares
are those of the training population (sizes spread log-uniformly over 0.0125-1.6 mm, every nuisance drawn over
its training range, both engines, 3 s runs), not of the catalogue values alone, and each rests on 45-139 runs of
the shipped model (a binomial standard error of up to 7.5 points).

Run: ``python analysis/identify/held_out_plot.py [--model twin/data/identify_default.npz] [--out
analysis/results/identify/held_out_accuracy.png]``; prints the table in Markdown.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from twin.provenance import figure_metadata

ROOT = Path(__file__).resolve().parents[2]
BELT = 3.97  # motor turns per crank turn (the bench's V-belt)


def table(held: dict) -> str:
    """A Markdown table: one row per joint and orientation, one column per training motor speed [rpm]."""
    speeds = sorted({round(h * 60 * BELT / 25) * 25
                     for j in ("B", "C") for e in held[j].values() for h in e["crank_hz"]})
    lines = ["| joint, vertical | " + " | ".join(f"{s:g}" for s in speeds) + " |",
             "|---|" + "---|" * len(speeds)]
    for j in ("B", "C"):
        for o, e in held[j].items():
            at = {round(h * 60 * BELT / 25) * 25: w for h, w in zip(e["crank_hz"], e["within"])}
            lines.append(f"| {j}, {o} | " + " | ".join(f"{at[s] * 100:.0f}" if s in at else "" for s in speeds) + " |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default=str(ROOT / "twin" / "data" / "identify_default.npz"))
    ap.add_argument("--out", default=str(ROOT / "analysis" / "results" / "identify" / "held_out_accuracy.png"))
    args = ap.parse_args()
    from twin.identification.model import ClearanceModel

    model = ClearanceModel.load(args.model)
    held = model.trained_on.get("held_out_size_accuracy")
    if not held:
        raise SystemExit(f"{args.model}: the model holds no held-out size accuracy (trained before it was kept)")
    print(table(held))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), sharey=True)
    for ax, j in zip(axes, ("B", "C")):
        for o, e in held[j].items():
            ax.plot([h * 60 * BELT for h in e["crank_hz"]], [w * 100 for w in e["within"]], "o-", label=f"{o} vertical")
        ax.axhline(90, color="k", lw=0.8, ls="--")
        ax.set_title(f"size at {j}: held-out answers within x1.5 of the truth")
        ax.set_xlabel("motor speed [rpm]")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("share of training runs left out [%]")
    axes[0].legend()
    fig.tight_layout()
    out = Path(args.out)
    tmp = out.with_suffix(".tmp.png")
    fig.savefig(tmp, dpi=110, metadata=figure_metadata())
    tmp.replace(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
