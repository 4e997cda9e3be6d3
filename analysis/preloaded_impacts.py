"""Single impacts under a preload: the reference law, the twin's native law, MuJoCo's soft contact.

In the mechanism a pin is pushed towards the bushing wall by the load it carries (tens of N at
C in test 6: the flight between the first rebound and the next approach shows ~25 m/s² on
~1.3 kg). This script repeats single impacts of a mass m_eff at speed v with a constant preload
P pressing it into the wall:

* reference: m δ̈ = P − max(0, K δ^n (1 + χ max(δ̇/v, −1))), Lankarani–Nikravesh damping χ from
  e, solved at tight tolerance by ``twin.impact.impact_hysteresis`` (its ``preload_n``);
* the twin's default contact (``mujoco.contact_source = "law"``, issue 15): the probe of
  ``twin.studies.contact_check.probe_model`` (real bore collider, the native module applying the same law,
  the twin's timestep and integrator) with P applied as gravity along the impact direction,
  stepped by MuJoCo;
* MuJoCo's own soft contact (``contact_source = "first-guess"``): the linear spring-damper with
  the LN law's duration and restitution at 0.1 m/s, in the same probe.

It prints the restitution −δ̇(separation)/v of the three (0 = captured: the mass never leaves
the wall within 5 ms). The reference's damping grows without bound as the impact speed falls,
so under a preload it captures slow impacts; the native law captures the same ones (and returns
the same 0.70 on free impacts); the soft linear contact, whose damping does not know the impact
speed, bounces off them. Before issue 15 the twin's fitted two-pair contact did the same: the
micro-rebounds behind test 6's extra impacts (README, issue 4).

Run: ``python analysis/preloaded_impacts.py [--joint C] [--clearance-mm 0.1] [--mass KG] [--timestep H]``
(about 10 s).
"""

from __future__ import annotations

import argparse

from twin.studies.contact_check import reference_impacts, twin_impacts
from twin.config import BenchConfig

PRELOADS_N = (0.0, 10.0, 30.0, 100.0)
SPEEDS_MPS = (0.002, 0.005, 0.008, 0.014, 0.03, 0.1)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--joint", default="C", choices=("B", "C"))
    ap.add_argument("--clearance-mm", type=float, default=0.1)
    ap.add_argument("--mass", type=float, default=1.31, help="effective mass [kg] (C's median: 1.31)")
    ap.add_argument("--timestep", type=float, default=1e-5, help="the twin's timestep [s]")
    a = ap.parse_args()
    cfg = BenchConfig().replace(**{f"joints.clearance_{a.joint.lower()}_mm": a.clearance_mm,
                                   "simulation.timestep_s": a.timestep, "sensors.output_rate_hz": 1 / a.timestep})
    soft = cfg.replace(**{"mujoco.contact_source": "first-guess"})
    print(f"joint {a.joint}, clearance {a.clearance_mm} mm, m_eff {a.mass} kg, LN e = {cfg.contact.restitution}, "
          f"n = {cfg.contact.exponent}, h = {a.timestep:g} s; restitution reference / twin (native law, default) / "
          f"MuJoCo soft contact (first guess); 0 = captured")
    print("| preload [N] | " + " | ".join(f"{v * 1e3:g} mm/s" for v in SPEEDS_MPS) + " |")
    print("|---:|" + "---:|" * len(SPEEDS_MPS))
    for p in PRELOADS_N:
        ref = reference_impacts(cfg, a.joint, a.mass, SPEEDS_MPS, p)
        tw = twin_impacts(cfg, a.joint, a.mass, SPEEDS_MPS, p)
        sf = twin_impacts(soft, a.joint, a.mass, SPEEDS_MPS, p)
        cells = [f"{r.restitution:.2f} / {t.restitution:.2f} / {s.restitution:.2f}" for r, t, s in zip(ref, tw, sf)]
        print(f"| {p:g} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
