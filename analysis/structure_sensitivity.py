"""Which placeholder moves which band: the flexible structure's resonances against each `[structure]` placeholder at
the ends of its documented range (the others at their defaults), for calibration against S003 Fig. 15 (the
clearance's rise "specially around 1000 Hz and 3000 Hz").

The resonances: the rod's first three bending modes (B pinned, C held normal to the rod) and its first axial mode
(B fixed, the end mass and the slider at C), from the discrete model's linearization (:func:`twin.structure.modes`,
the model both engines integrate); the frame's and the guide's supports and the sensor mounts at their own natural
frequencies (the fields themselves). In the mechanism the supports couple to the rod (the tap in both engines rings
the axial mode at 1263 Hz against 1041 Hz with B fixed, docs/structure-mujoco.md), so the table says which field
moves which family of bands and how far, not where the coupled peaks sit to the hertz.

With ``--runs`` it also simulates (MuJoCo engine, test 6: 0.1 mm at C, 750 motor rpm with the crank PID, ``--duration``
s from rest, the last ``--window`` s) the defaults and the placeholders that move a resonance, each at both ends of its
range, and gives AC4's energy per 250 Hz band (Hann, as :mod:`analysis.structure_fig15`) in the two bands of Fig. 15b
(1000–1250 Hz, 3000–3250 Hz) relative to the defaults' [dB], and the three strongest 250 Hz bands from 500 Hz up.

Writes ``analysis/results/structure/sensitivity.md`` (stamped). Run: ``python analysis/structure_sensitivity.py
[--runs] [--duration 0.5] [--window 0.3]``.
"""

from __future__ import annotations

from pathlib import Path

from twin.provenance import with_stamp_line
from twin.util import atomic_write_text


def resonances(cfg) -> dict[str, float]:
    """{name: frequency [Hz]} of the structure of ``cfg`` (module docstring)."""
    from twin.structure import modes, rod_chain

    st = cfg.structure
    chain = rod_chain(st, cfg.bodies.rod, cfg.bodies.slider.mass_kg)
    md = modes(chain, "mechanism", cfg.bodies.slider.mass_kg)
    b, a = md.of_kind("bending"), md.of_kind("axial")
    return {"bending 1": b[0], "bending 2": b[1], "bending 3": b[2], "axial 1": a[0],
            "frame": st.frame_frequency_hz, "guide": st.guide_frequency_hz, "mount": st.mount_frequency_hz}


RUN_FIELDS = ("rod_section_height_m", "rod_section_width_m", "rod_youngs_modulus_pa", "rod_end_inertia_kgm2",
              "frame_frequency_hz", "guide_frequency_hz", "mount_frequency_hz")


def band_db(cfg, duration: float, window: float) -> "np.ndarray":
    """AC4's energy per 250 Hz band, 0–5 kHz [dB re 1 (m/s²)² s], over the last ``window`` s of a ``duration`` s
    run of ``cfg``."""
    import numpy as np

    import twin

    run = twin.simulate(cfg.replace(**{"simulation.duration_s": duration}))
    x = np.asarray(run["AC4"])[-int(round(window * run.rate_hz)):]
    x = (x - x.mean()) * np.hanning(len(x))
    p = np.abs(np.fft.rfft(x)) ** 2 / run.rate_hz
    f = np.fft.rfftfreq(len(x), 1.0 / run.rate_hz)
    return np.array([10 * np.log10(p[(f >= lo) & (f < lo + 250)].sum()) for lo in range(0, 5000, 250)])


def main() -> None:
    import argparse

    import twin

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", action="store_true")
    ap.add_argument("--duration", type=float, default=0.5)
    ap.add_argument("--window", type=float, default=0.3)
    args = ap.parse_args()
    from twin.config import preset
    from twin.config.structure import EXPLORE_RANGES

    base = preset(6).replace(**{"structure.mode": "flexible"})
    ref = resonances(base)
    names = list(ref)
    lines = [f"Resonances of the flexible structure [Hz] (twin {twin.__version__}; S003 Table 1's rod and slider; the "
             "other placeholders at their defaults). Defaults first, then each placeholder at the low and the high end "
             "of its explore range; a cell is the frequency where it moves by more than 1 % (else '·'). Bands of "
             "S003 Fig. 15b: around 1000 Hz and 3000 Hz.", "",
             "| field = value | " + " | ".join(names) + " |", "|---|" + "---:|" * len(names),
             "| defaults | " + " | ".join(f"{ref[n]:.0f}" for n in names) + " |"]
    for _, field, _, (lo, hi) in EXPLORE_RANGES:
        for v in (lo, hi):
            try:
                r = resonances(base.replace(**{f"structure.{field}": v}))
            except Exception as exc:  # a value the configuration refuses at the default step
                lines.append(f"| {field} = {v:g} | refused: {str(exc)[:80]} |")
                continue
            cells = [f"{r[n]:.0f}" if abs(r[n] / ref[n] - 1) > 0.01 else "·" for n in names]
            lines.append(f"| {field} = {v:g} | " + " | ".join(cells) + " |")
    if args.runs:
        import numpy as np

        dflt = band_db(base, args.duration, args.window)
        lines += ["", f"AC4 of test 6 (MuJoCo, crank PID, {args.duration:g} s from rest, the last {args.window:g} s, Hann): "
                  "energy in the 1000–1250 Hz and 3000–3250 Hz bands relative to the defaults' [dB], and the three "
                  "strongest 250 Hz bands from 500 Hz (their lower edges [Hz]).", "",
                  "| field = value | 1 kHz band [dB] | 3 kHz band [dB] | strongest bands [Hz] |", "|---|---:|---:|---|"]

        def row(label, e):
            top = np.argsort(e[2:])[::-1][:3] + 2
            lines.append(f"| {label} | {e[4] - dflt[4]:+.1f} | {e[12] - dflt[12]:+.1f} | "
                         + ", ".join(str(250 * int(k)) for k in top) + " |")

        row("defaults", dflt)
        ranges = {field: rng for _, field, _, rng in EXPLORE_RANGES}
        for field in RUN_FIELDS:
            for v in ranges[field]:
                if field == "rod_end_inertia_kgm2" and v == 0.0:
                    continue
                row(f"{field} = {v:g}", band_db(base.replace(**{f"structure.{field}": v}), args.duration, args.window))
                print(f"  {field} = {v:g} done", flush=True)
    text = "\n".join(lines)
    print(text)
    out = Path(__file__).resolve().parent / "results" / "structure" / "sensitivity.md"
    atomic_write_text(out, with_stamp_line(text))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
