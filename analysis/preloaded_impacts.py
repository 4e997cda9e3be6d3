"""Single impacts under a preload: reference, twin with fixed damping, twin with impact-speed damping.

The contact calibration (``twin/calibrate.py``) fits the twin's two-term MuJoCo contact to
*free* single impacts of the reference's Lankarani–Nikravesh (LN) law: a mass m_eff hits the
bushing at speed v with nothing else acting on it. In the mechanism the pin is also pushed
towards the bushing wall by the load it carries (tens of N at C in test 6: the flight between
the first rebound and the next approach shows ~25 m/s² on ~1.3 kg). This script repeats the
calibration's single impacts with a constant preload P pressing the mass into the wall:

* reference: m δ̈ = P − max(0, K δ^n (1 + χ δ̇/v)), LN damping χ from e, solved at tight
  tolerance by ``twin.impact.impact_hysteresis`` (its ``preload_n``);
* twin with fixed damping: the calibration's own probe model (``twin.calibrate.probe_model``:
  real bore collider, the table's law, the twin's timestep and integrator) with P applied as
  gravity along the impact direction, stepped by MuJoCo;
* the twin with the default impact-speed damping (``mujoco.contact_damping``): the same probe
  with the pairs' damping cut to 1 % and the native χ K δⁿ δ̇ / v_imp term of ``_bore.c``.

It prints the restitution −δ̇(separation)/v of the three (0 = captured: the mass never leaves
the wall within 5 ms). With the fixed damping, free impacts (P = 0) agree within the
calibration's ±0.02, but under a preload the reference's damping, which grows without bound
as v falls, captures slow impacts the twin still bounces off: the extra re-contact behind the
impact-count gap of test 6 (README, issue 4). The impact-speed damping returns 0.72–0.77 on
free impacts (the elastic law is not exactly Hertzian) and follows the reference's trend
with preload only in part; in the mechanism it brings the twin much closer (``twin study
accuracy``).

Run: ``python analysis/preloaded_impacts.py [--joint C] [--clearance-mm 0.1] [--mass KG]``
(about 20 s).
"""

from __future__ import annotations

import argparse
import json

import mujoco

from twin.calibrate import ContactLaw, ContactTerm, probe_model
from twin.config import BenchConfig, ln_stiffness
from twin.impact import impact_hysteresis
from twin.mujoco_engine.builder import CALIBRATION_FILE, IMPACT_SPEED_RESIDUAL_DAMPING, impact_speed_coefficient

PRELOADS_N = (0.0, 10.0, 30.0, 100.0)
SPEEDS_MPS = (0.002, 0.005, 0.008, 0.014, 0.03, 0.1)
T_MAX_S = 5e-3  # the twin probe's horizon: no separation by then = captured


def reference_restitution(K: float, n: float, e: float, m: float, v: float, preload: float) -> float:
    """Restitution of an LN impact at speed v under a constant preload (0 = captured)."""
    return impact_hysteresis("lankarani-nikravesh", K, n, e, m, v, preload).restitution


def impact_speed_variant(cfg: BenchConfig, joint: str, law: ContactLaw) -> tuple[ContactLaw, tuple]:
    """The law and native damping of ``mujoco.contact_damping = "impact-speed"`` (the builder's
    rule: the terms keep IMPACT_SPEED_RESIDUAL_DAMPING of their damping, plus the native term)."""
    law = ContactLaw(tuple(ContactTerm(t.stiffness_n_per_m, t.damping_ns_per_m * IMPACT_SPEED_RESIDUAL_DAMPING,
                                       t.solimp) for t in law.terms))
    return law, (impact_speed_coefficient(cfg, joint), cfg.contact.exponent, cfg.contact.impact_speed_floor_mps)


def twin_restitution(cfg: BenchConfig, joint: str, law: ContactLaw, m: float, v: float, preload: float,
                     impact_damping: tuple | None = None) -> float:
    """Restitution of the twin's contact (MuJoCo probe) under a preload (0 = captured)."""
    model = probe_model(cfg, joint, m, law, impact_damping)
    model.opt.gravity[:] = [preload / m, 0.0, 0.0]  # the probe's slide axis points into the wall
    d = mujoco.MjData(model)
    c, h = cfg.joints.radial_m(joint), model.opt.timestep
    d.qpos[0], d.qvel[0] = c - v * h * 0.5, v
    touched = False
    for _ in range(int(T_MAX_S / h)):
        mujoco.mj_step(model, d)
        touched |= d.qpos[0] > c
        if touched and d.qpos[0] <= c:
            return float(-d.qvel[0] / v)
    return 0.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--joint", default="C", choices=("B", "C"))
    ap.add_argument("--clearance-mm", type=float, default=0.1)
    ap.add_argument("--mass", type=float, default=1.31, help="effective mass [kg] (C's median: 1.31)")
    a = ap.parse_args()
    over = {f"joints.clearance_{a.joint.lower()}_mm": a.clearance_mm}
    cfg = BenchConfig().replace(**over)
    table = json.loads(CALIBRATION_FILE.read_text())
    key = f"{a.joint}:{a.clearance_mm:g}"
    law = ContactLaw.from_json(table["entries"][key])
    K = ln_stiffness(cfg.joints, cfg.materials, a.joint)
    n, e = cfg.contact.exponent, cfg.contact.restitution
    law_is, damp_is = impact_speed_variant(cfg, a.joint, law)
    print(f"joint {a.joint}, clearance {a.clearance_mm} mm, m_eff {a.mass} kg, LN e = {e}, n = {n}; restitution "
          f"reference / twin with fixed damping / twin with impact-speed damping (the default; 0 = captured)")
    print("| preload [N] | " + " | ".join(f"{v * 1e3:g} mm/s" for v in SPEEDS_MPS) + " |")
    print("|---:|" + "---:|" * len(SPEEDS_MPS))
    for p in PRELOADS_N:
        cells = []
        for v in SPEEDS_MPS:
            r = reference_restitution(K, n, e, a.mass, v, p)
            t = twin_restitution(cfg, a.joint, law, a.mass, v, p)
            ti = twin_restitution(cfg, a.joint, law_is, a.mass, v, p, damp_is)
            cells.append(f"{r:.2f} / {t:.2f} / {ti:.2f}")
        print(f"| {p:g} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
