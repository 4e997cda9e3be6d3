"""S001's rig reproduced: the ideal run against the closed form, the clearance run's
journal orbit, contact force and acceleration spikes against the paper's figures, and the
restitution recovery table of ``twin identify restitution``.

Run: ``python analysis/s001_report.py [--out analysis/results/s001] [--quick]`` (about 5 min on
two shared cores; ``--quick`` leaves out the off-grid and cross-engine recoveries). Writes
``results.json``, the PNGs and ``tables.md`` (the numbers the README of the folder quotes).

Everything is simulated from ``--preset s001`` (``twin/config/presets/s001.toml``: the paper's Table I-II,
0 -> 300 rpm in 0.2 s, vertical plane) in both engines: the ideal run with joint C ideal, the
clearance run with 0.5 mm radial clearance at C and e = 0.55, and the same with the paper's own
contact law (ADAMS IMPACT, c_max 27 960 N s/m, d_max 10 µm). Force, orbit and the unsampled
acceleration at 100 kHz; the slider accelerometer also at the paper's 5 kHz.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from twin.provenance import figure_metadata, stamped, with_stamp_line

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

ENGINES = ("mujoco", "reference")
SEP_S = 1e-4          # contact onsets after at least 0.1 ms of separation (the summary's impacts)
BURST_GAP_S = 0.02    # onsets closer than this belong to one burst (a first impact and its rebounds)


def closed_form_acc(theta, omega, alpha, r, L):
    """Exact slider acceleration of the ideal slider-crank (zero offset) [m/s^2]
    (:func:`twin.kinematics.slider_kinematics`)."""
    from twin.kinematics import slider_kinematics

    return slider_kinematics(theta, omega, alpha, r, L)[2]


def impacts(run, rate):
    """Contact onsets after >= SEP_S of separation (:func:`twin.summary.contact_onsets`): indices,
    approach speeds [m/s]."""
    from twin.summary import contact_onsets

    ecc = np.hypot(np.asarray(run["ecc_C_x"], float), np.asarray(run["ecc_C_y"], float))
    onsets, free = contact_onsets(np.asarray(run["pen_C"], dtype=float) > 0)
    idx = onsets[free >= int(round(SEP_S * rate))].astype(int)
    speed = (ecc[idx] - ecc[idx - 1]) * rate if idx.size else np.array([])
    return idx, speed


def bursts(idx, rate):
    """Group onset indices into bursts: [(first, last onset index, count)]."""
    out = []
    for i in idx:
        if out and (i - out[-1][1]) / rate < BURST_GAP_S:
            out[-1] = (out[-1][0], i, out[-1][2] + 1)
        else:
            out.append((i, i, 1))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "analysis/results/s001"))
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from twin.config import ln_stiffness, named_preset
    from twin.identification.restitution import SweepOptions, sweep_restitution, write_synthetic_recording
    from twin.simulation import simulate_run

    base = named_preset("s001")
    r, L = base.bodies.crank.length_m, base.bodies.rod.length_m
    w = 300 * 2 * math.pi / 60
    K = ln_stiffness(base.joints, base.materials, "C")
    res: dict = {"K_N_per_m1.5": K, "closed_form_mps2": {"min": -r * w * w * (1 + r / L), "max": r * w * w * (1 - r / L)}}
    runs = {}
    t0 = time.perf_counter()
    for eng in ENGINES:
        for kind, ov in (("ideal", {"joints.clearance_c_mm": 0.0}), ("clearance", {}),
                         ("impact", {"contact.law": "adams-impact"})):   # the paper's own law and c_max
            for rate in (5000.0, 100000.0):
                cfg = base.replace(**{"simulation.engine": eng, "sensors.output_rate_hz": rate, **ov})
                runs[eng, kind, rate] = simulate_run(cfg)
    res["simulation_wall_s"] = time.perf_counter() - t0

    # ---------------------------------------------------------------- ideal: closed form
    res["ideal"] = {}
    for eng in ENGINES:
        run = runs[eng, "ideal", 5000.0]
        t, a = run.time, np.asarray(run["AC6"], float)
        st = t >= 0.3
        cf = res["closed_form_mps2"]
        res["ideal"][eng] = {"min_mps2": float(a[st].min()), "max_mps2": float(a[st].max()),
                             "min_error_pct": float(100 * (a[st].min() / cf["min"] - 1)),
                             "max_error_pct": float(100 * (a[st].max() / cf["max"] - 1))}
        hi = runs[eng, "ideal", 100000.0]
        th = np.asarray(hi["crank_angle"], float)
        om = np.asarray(hi["crank_speed"], float)
        al = np.gradient(om, hi.time)
        exact = closed_form_acc(th, om, al, r, L)
        res["ideal"][eng]["max_abs_dev_from_exact_kinematics_mps2"] = float(np.max(np.abs(np.asarray(hi["AC6"], float) - exact)[hi.time > 0.01]))

    fig, ax = plt.subplots(figsize=(9, 4))
    for eng, ls in zip(ENGINES, ("-", "--")):
        run = runs[eng, "ideal", 5000.0]
        ax.plot(run.time, run["AC6"], ls, lw=1, label=f"{eng} (AC6, 5 kHz)")
    hi = runs["reference", "ideal", 100000.0]
    ax.plot(hi.time, closed_form_acc(np.asarray(hi["crank_angle"], float), np.asarray(hi["omega_ref"], float),
                                     np.gradient(np.asarray(hi["omega_ref"], float), hi.time), r, L), ":k", lw=1,
            label="closed form at the reference drive")
    for v in (res["closed_form_mps2"]["min"], res["closed_form_mps2"]["max"]):
        ax.axhline(v, color="grey", lw=0.5)
    ax.set(xlabel="time [s]", ylabel="slider acceleration [m/s²]",
           title="S001 ideal joints, 0 → 300 rpm in 0.2 s (cf. paper Fig. 15)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "ideal_acceleration.png", dpi=120, metadata=figure_metadata())
    plt.close(fig)

    # ------------------------------------------------------------ clearance: figures 8-11, 16
    res["clearance"], res["impact"] = {}, {}
    for eng, kind in [(e, k) for k in ("clearance", "impact") for e in ENGINES]:
        hi = runs[eng, kind, 100000.0]
        lo = runs[eng, kind, 5000.0]
        rate = hi.rate_hz
        idx, spd = impacts(hi, rate)
        bs = bursts(idx, rate)
        fn = np.asarray(hi["fn_C"], float)
        pen = np.asarray(hi["pen_C"], float)
        ecc = np.hypot(np.asarray(hi["ecc_C_x"], float), np.asarray(hi["ecc_C_y"], float))
        c = base.joints.radial_m("C")
        th = np.asarray(hi["crank_angle"], float)
        om = np.asarray(hi["crank_speed"], float)
        ideal_hi = runs[eng, "ideal", 100000.0]
        a_ideal = np.asarray(ideal_hi["AC6"], float)
        v_slider = np.gradient(np.asarray(ideal_hi["slider_position"], float), ideal_hi.time)
        burst_rows = []
        for first, last, n in bs:
            seg = slice(first, last + int(0.005 * rate))
            k_first = slice(first, first + int(0.001 * rate))
            burst_rows.append({"t_s": float(hi.time[first]), "crank_deg": float(np.degrees(th[first]) % 360),
                               "impacts": int(n), "first_impact_speed_mps": float(spd[list(idx).index(first)]),
                               "max_force_N": float(fn[seg].max()), "first_impact_force_N": float(fn[k_first].max()),
                               "ideal_slider_acc_mps2": float(a_ideal[first]),
                               "ideal_slider_speed_mps": float(v_slider[first])})
        steady = hi.time >= 0.2
        in_contact = (ecc >= c - 1e-6)
        res[kind][eng] = {
            "impacts": int(idx.size), "bursts": burst_rows,
            "max_contact_force_N": float(fn.max()), "max_penetration_um": float(pen.max() * 1e6),
            "max_eccentricity_um": float(ecc.max() * 1e6),
            "share_in_contact_after_0.2s": float(in_contact[steady].mean()),
            "mean_impact_speed_mps": float(np.mean(spd)) if spd.size else None,
            "median_impact_speed_mps": float(np.median(spd)) if spd.size else None,
            "acc_5kHz_min_mps2": float(np.min(lo["AC6"])), "acc_5kHz_max_mps2": float(np.max(lo["AC6"])),
            "acc_100kHz_min_mps2": float(np.min(hi["AC6"])), "acc_100kHz_max_mps2": float(np.max(hi["AC6"])),
            "crank_torque_range_Nm": [float(np.min(hi["crank_torque"])), float(np.max(hi["crank_torque"]))],
            "ideal_crank_torque_range_Nm": [float(np.min(ideal_hi["crank_torque"])), float(np.max(ideal_hi["crank_torque"]))],
            "burst_first_is_largest_share": float(np.mean([b["first_impact_force_N"] >= 0.999 * b["max_force_N"]
                                                           for b in burst_rows])) if burst_rows else None,
        }
        # S001 Eq. 10-11: the c_max that e = 0.55 gives with this run's mean impact speed
        if spd.size:
            mu = 3 * K * (1 - 0.55 ** 2) / (4 * np.mean(spd))
            res[kind][eng]["c_max_eq11_Ns_per_m"] = float(mu * (1e-5) ** 1.5)

    fig, axs = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    for ax, eng in zip(axs, ENGINES):
        lo, hi = runs[eng, "clearance", 5000.0], runs[eng, "clearance", 100000.0]
        ax.plot(hi.time, hi["AC6"], color="0.75", lw=0.5, label="100 kHz (unsampled)")
        ax.plot(lo.time, lo["AC6"], lw=0.9, label="clearance, 5 kHz (as the paper's DAQ)")
        ax.plot(runs[eng, "ideal", 5000.0].time, runs[eng, "ideal", 5000.0]["AC6"], "k", lw=0.8, label="ideal")
        ax.set(ylabel="slider acc. [m/s²]", title=f"{eng}: 0.5 mm radial clearance at C, e = 0.55 (cf. Fig. 8, 16)")
        ax.set_ylim(-700, 700)
        ax.legend(fontsize=7, loc="lower left")
    axs[-1].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(out / "clearance_acceleration.png", dpi=120, metadata=figure_metadata())
    plt.close(fig)

    fig, axs = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    for eng, ls in zip(ENGINES, ("-", "--")):
        for kind, col in (("clearance", "C0"), ("impact", "C3")):
            lab = "LN, e = 0.55" if kind == "clearance" else "ADAMS IMPACT, c_max 27 960 N s/m"
            axs[0].plot(runs[eng, kind, 5000.0].time, runs[eng, kind, 5000.0]["AC6"], ls, color=col, lw=0.8,
                        label=f"{eng}: {lab}")
            axs[1].plot(runs[eng, kind, 100000.0].time, runs[eng, kind, 100000.0]["fn_C"], ls, color=col, lw=0.7,
                        label=f"{eng}: {lab}")
    axs[0].set(ylabel="slider acc., 5 kHz [m/s²]", title="Lankarani–Nikravesh (e = 0.55) against the paper's ADAMS IMPACT law")
    axs[1].set(ylabel="contact force at C [N]", xlabel="time [s]")
    for ax in axs:
        ax.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    fig.savefig(out / "impact_law.png", dpi=120, metadata=figure_metadata())
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(10, 3.8))
    for eng, ls in zip(ENGINES, ("-", "--")):
        hi = runs[eng, "clearance", 100000.0]
        ax.plot(hi.time, hi["fn_C"], ls, lw=0.7, label=eng)
    ax.set(xlabel="time [s]", ylabel="contact force at C [N]", title="Normal contact force at the rod–slider joint (cf. Fig. 10)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "contact_force.png", dpi=120, metadata=figure_metadata())
    plt.close(fig)

    fig, axs = plt.subplots(1, 2, figsize=(10, 5))
    c_mm = base.joints.radial_m("C") * 1e3
    for ax, eng in zip(axs, ENGINES):
        hi = runs[eng, "clearance", 100000.0]
        ax.plot(np.asarray(hi["ecc_C_x"]) * 1e3, np.asarray(hi["ecc_C_y"]) * 1e3, lw=0.4)
        phi = np.linspace(0, 2 * np.pi, 400)
        ax.plot(c_mm * np.cos(phi), c_mm * np.sin(phi), "k--", lw=0.8, label="0.5 mm circle")
        ax.set(aspect="equal", xlim=(-0.6, 0.6), ylim=(-0.6, 0.6), xlabel="x [mm]", ylabel="y [mm]",
               title=f"{eng}: journal centre in the bushing (cf. Fig. 11)")
        ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(out / "journal_orbit.png", dpi=120, metadata=figure_metadata())
    plt.close(fig)

    fig, axs = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    for eng, ls in zip(ENGINES, ("-", "--")):
        hi, ideal = runs[eng, "clearance", 100000.0], runs[eng, "ideal", 100000.0]
        axs[0].plot(hi.time, np.gradient(np.asarray(hi["slider_position"], float), hi.time), ls, lw=0.7, label=f"{eng} clearance")
        axs[1].plot(hi.time, hi["crank_torque"], ls, lw=0.7, label=f"{eng} clearance")
    ideal = runs["reference", "ideal", 100000.0]
    axs[0].plot(ideal.time, np.gradient(np.asarray(ideal["slider_position"], float), ideal.time), "k", lw=0.6, label="ideal")
    axs[1].plot(ideal.time, ideal["crank_torque"], "k", lw=0.6, label="ideal")
    axs[0].set(ylabel="slider velocity [m/s]", title="Slider velocity (cf. Fig. 7) and drive torque (cf. Fig. 9)")
    axs[1].set(ylabel="crank torque [N m]", xlabel="time [s]")
    for ax in axs:
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "velocity_torque.png", dpi=120, metadata=figure_metadata())
    plt.close(fig)

    # ------------------------------------------------------------------ restitution recovery
    tmp = out / "_tmp"
    tmp.mkdir(exist_ok=True)
    cases = [("mujoco", "mujoco", e) for e in (0.55, 0.4, 0.7)] + [("reference", "reference", e) for e in (0.55, 0.4, 0.7)]
    if not args.quick:
        cases += [("mujoco", "mujoco", e) for e in (0.553, 0.437, 0.712)]
        cases += [("reference", "mujoco", 0.55), ("mujoco", "reference", 0.55)]
    rec_rows = []
    for rec_eng, sweep_eng, e in cases:
        p = tmp / f"rec_{rec_eng}_{e}.mcap"
        if not p.exists():
            write_synthetic_recording(base.replace(**{"simulation.engine": rec_eng}), p, e, noise_mps2=5.0, seed=11)
        grid = tuple(round(0.17 + 0.05 * k, 2) for k in range(17))   # the known values are off this grid
        s = sweep_restitution(p, SweepOptions(coarse=grid, engine=sweep_eng))
        rec_rows.append({"recording_engine": rec_eng, "sweep_engine": sweep_eng, "e_true": e,
                         "e_found": s.restitution, "error": s.restitution - e, "rms_mismatch_mps2": s.mismatch_mps2,
                         "simulations": s.simulations, "seconds": s.seconds, "notes": s.notes})
        print(f"recovery {rec_eng}->{sweep_eng} e={e}: {s.restitution:.3f} ({s.seconds:.0f} s)", flush=True)
    # S001's own procedure: the IMPACT law's c_max (Table IV), recordings with the paper's 27 960 N s/m
    cmax_rows = []
    for eng in ENGINES:
        cfg_i = base.replace(**{"simulation.engine": eng, "contact.law": "adams-impact"})
        p = tmp / f"rec_impact_{eng}.mcap"
        write_synthetic_recording(cfg_i, p, 27960.0, noise_mps2=5.0, seed=11, parameter="c_max")
        s = sweep_restitution(p, SweepOptions(parameter="c_max", coarse=tuple(6100.0 + 2500 * k for k in range(18))))
        cmax_rows.append({"engine": eng, "c_max_true": 27960.0, "c_max_found": s.value,
                          "error_pct": 100 * (s.value / 27960.0 - 1), "rms_mismatch_mps2": s.mismatch_mps2,
                          "simulations": s.simulations, "seconds": s.seconds, "notes": s.notes})
        print(f"c_max recovery {eng}: {s.value:.0f} ({s.seconds:.0f} s)", flush=True)
    res["c_max_recovery"] = cmax_rows
    res["restitution_recovery"] = rec_rows
    for p in tmp.iterdir():
        p.unlink()
    tmp.rmdir()

    # landscape of the 0.55 recovery, low-passed and full band, on a regular grid
    from twin.identification.restitution import (recorded_acceleration, rms_mismatch, simulated_acceleration,
                                                 zero_phase_lowpass)

    p = out / "_land.mcap"
    write_synthetic_recording(base, p, 0.55, noise_mps2=5.0, seed=11)
    rec, cfg, rate = recorded_acceleration(p)
    p.unlink()
    lp = zero_phase_lowpass(200.0, rate)
    es = np.round(np.arange(0.30, 0.801, 0.01), 3)
    full, low = [], []
    for e in es:
        sim = simulated_acceleration(cfg, e, rec.size, rate)
        full.append(rms_mismatch(rec, sim, 0, rec.size))
        low.append(rms_mismatch(lp(rec), lp(sim), 0, rec.size))
    res["landscape_e055"] = {"e": es.tolist(), "full_band_rms": full, "lowpass200_rms": low}
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(es, full, "o-", ms=3, label="full band (5 kHz samples)")
    ax2 = ax.twinx()
    ax2.plot(es, low, "s-", ms=3, color="C1", label="low-passed at 200 Hz")
    ax.axvline(0.55, color="k", lw=0.5)
    ax.set(xlabel="restitution e of the candidate", ylabel="RMS mismatch, full band [m/s²]",
           title="Mismatch against a noisy synthetic recording at e = 0.55 (MuJoCo twin)")
    ax2.set_ylabel("RMS mismatch, low-passed [m/s²]", color="C1")
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(out / "restitution_landscape.png", dpi=120, metadata=figure_metadata())
    plt.close(fig)

    (out / "results.json").write_text(json.dumps(stamped(res), indent=1, default=float))
    # tables
    lines = ["| engine | min [m/s²] | error | max [m/s²] | error |", "|---|---|---|---|---|"]
    cf = res["closed_form_mps2"]
    lines.append(f"| closed form rω²(1 ± r/L) | {cf['min']:.2f} | | {cf['max']:.2f} | |")
    for eng in ENGINES:
        g = res["ideal"][eng]
        lines.append(f"| {eng} | {g['min_mps2']:.2f} | {g['min_error_pct']:+.3f} % | {g['max_mps2']:.2f} | {g['max_error_pct']:+.3f} % |")
    lines += ["", "| quantity | LN mujoco | LN reference | IMPACT mujoco | IMPACT reference |", "|---|---|---|---|---|"]
    keys = [("impacts", "impacts (0.6 s)", "{:d}"), ("max_contact_force_N", "max contact force [N]", "{:.0f}"),
            ("max_penetration_um", "max penetration [µm]", "{:.1f}"), ("max_eccentricity_um", "max eccentricity [µm]", "{:.1f}"),
            ("share_in_contact_after_0.2s", "share of time on the circle after 0.2 s", "{:.2f}"),
            ("mean_impact_speed_mps", "mean impact speed [m/s]", "{:.3f}"),
            ("acc_5kHz_min_mps2", "slider acc. min, 5 kHz [m/s²]", "{:.0f}"), ("acc_5kHz_max_mps2", "slider acc. max, 5 kHz [m/s²]", "{:.0f}"),
            ("acc_100kHz_min_mps2", "slider acc. min, 100 kHz [m/s²]", "{:.0f}"), ("acc_100kHz_max_mps2", "slider acc. max, 100 kHz [m/s²]", "{:.0f}"),
            ("burst_first_is_largest_share", "bursts whose first impact is the largest", "{:.2f}"),
            ("c_max_eq11_Ns_per_m", "c_max of Eq. 10-11 at e = 0.55 [N s/m]", "{:.0f}")]
    for k, label, fmt in keys:
        lines.append(f"| {label} | " + " | ".join(fmt.format(res[kd][e][k]) for kd in ("clearance", "impact")
                                                  for e in ENGINES) + " |")
    for eng in ENGINES:
        lines += ["", f"Bursts ({eng}): t [s], crank angle [deg], impacts, first impact speed [m/s], max force [N], "
                      "ideal slider acceleration and speed at the onset", "",
                  "| t [s] | θ [deg] | impacts | v_imp [m/s] | max F [N] | ideal ẍ [m/s²] | ideal ẋ [m/s] |",
                  "|---|---|---|---|---|---|---|"]
        for b in res["clearance"][eng]["bursts"]:
            lines.append(f"| {b['t_s']:.4f} | {b['crank_deg']:.0f} | {b['impacts']} | {b['first_impact_speed_mps']:.3f} | "
                         f"{b['max_force_N']:.0f} | {b['ideal_slider_acc_mps2']:.1f} | {b['ideal_slider_speed_mps']:.3f} |")
    lines += ["", "| recording | sweep | e true | e found | error | RMS mismatch [m/s²] | runs | wall [s] |",
              "|---|---|---|---|---|---|---|---|"]
    for row in rec_rows:
        lines.append(f"| {row['recording_engine']} | {row['sweep_engine']} | {row['e_true']:g} | {row['e_found']:.3f} | "
                     f"{row['error']:+.3f} | {row['rms_mismatch_mps2']:.2f} | {row['simulations']} | {row['seconds']:.0f} |")
    lines += ["", "| engine | c_max true [N s/m] | found | error | RMS mismatch [m/s²] | runs | wall [s] |",
              "|---|---|---|---|---|---|---|"]
    for row in res["c_max_recovery"]:
        lines.append(f"| {row['engine']} | {row['c_max_true']:.0f} | {row['c_max_found']:.0f} | {row['error_pct']:+.1f} % | "
                     f"{row['rms_mismatch_mps2']:.2f} | {row['simulations']} | {row['seconds']:.0f} |")
    (out / "tables.md").write_text(with_stamp_line("\n".join(lines)))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
