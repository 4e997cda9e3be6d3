"""Why guide play is hard to see with y vertical: the slider guide's normal force over a crank turn, closed form.

With y vertical the guide (along x) is horizontal and the slider's weight presses it on its lower rail. Steady turning
of the ideal rigid mechanism (Table 1's bodies from the default configuration, d_off = 0, constant crank rate,
gravity along -y) loads the guide with N(θ) = m_s g + F_Cy(θ): F_Cy the rod's transverse force on the slider from the
rod's Newton-Euler equations (inverse dynamics; accelerations by central differences in the crank angle). Where N
keeps one sign over the turn, the slider never crosses its play: the guide's play shows only through what else lifts
the slider (impacts at B or C, spin-up), so play at G alone is not told from none. With z vertical gravity is normal
to the mechanism's plane and the guide's in-plane load reverses twice a turn; with x vertical gravity lies along the
guide.

    python analysis/identify/guide_load.py [--out analysis/results/identify/guide_load.json]

Prints and writes (stamped JSON) the smallest and largest N over a turn at motor speeds 250-800 rpm.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
RPM = (250, 325, 400, 475, 550, 650, 725, 800)


def guide_load(motor_rpm: float, cfg) -> np.ndarray:
    """N(θ) [N] over one crank turn (3600 angles) at ``motor_rpm`` with y vertical (module docstring)."""
    from twin.config import Drive

    cr, rod, sl = cfg.bodies.crank, cfg.bodies.rod, cfg.bodies.slider
    r, L, xg, g = cr.length_m, rod.length_m, rod.x_g_m, cfg.mechanism.gravity_mps2
    w = motor_rpm / Drive.belt_ratio * 2 * np.pi / 60

    def kin(t: np.ndarray) -> tuple[np.ndarray, ...]:
        B = np.stack([r * np.cos(t), r * np.sin(t)], -1)
        C = np.stack([r * np.cos(t) + np.sqrt(L ** 2 - (r * np.sin(t)) ** 2), 0 * t], -1)
        return B, C, B + xg / L * (C - B), np.arctan2(C[..., 1] - B[..., 1], C[..., 0] - B[..., 0])

    th, h = np.linspace(0, 2 * np.pi, 3600, endpoint=False), 1e-4
    acc = [w ** 2 * (p - 2 * q + m) / h ** 2 for p, q, m in zip(kin(th + h), kin(th), kin(th - h))]
    (B, C, G, _), (_, aC, aG, alpha) = kin(th), acc
    out = np.empty_like(th)
    for i in range(th.size):
        fcx = -sl.mass_kg * aC[i, 0]  # the rod's force on the slider along the guide drives it (friction aside)
        bx, by = B[i] - G[i]
        cx, cy = C[i] - G[i]
        # rod: F_B + F_C - m g ŷ = m a_G; I α = (B-G)×F_B + (C-G)×F_C; unknowns F_Bx, F_By, F_Cy
        A = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0], [-by, bx, cx]])
        rhs = np.array([rod.mass_kg * aG[i, 0] - fcx, rod.mass_kg * (aG[i, 1] + g), rod.inertia_kgm2 * alpha[i] + cy * fcx])
        out[i] = sl.mass_kg * g + np.linalg.solve(A, rhs)[2]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "analysis" / "results" / "identify" / "guide_load.json"))
    args = ap.parse_args()
    from twin.config import BenchConfig
    from twin.provenance import stamped

    cfg = BenchConfig()
    rows = []
    for rpm in RPM:
        n = guide_load(rpm, cfg)
        rows.append({"motor_rpm": rpm, "min_n": float(n.min()), "max_n": float(n.max())})
        print(f"motor {rpm} rpm, y vertical: guide normal force {n.min():.1f} to {n.max():.1f} N "
              f"({'one sign: the slider stays on its rail' if n.min() > 0 else 'reverses: it crosses its play'})")
    Path(args.out).write_text(json.dumps(stamped({"orientation": "y", "d_off_m": 0.0, "rows": rows}), indent=1))


if __name__ == "__main__":
    main()
