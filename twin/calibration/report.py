"""The outputs of a calibration: ``calibrated.toml``, replay metrics before/after, ``report.md``, PNGs."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

#: the replay metrics tabulated per accelerometer before and after
METRICS = ("nrmse_pct", "correlation", "dtw_distance_pct", "rms_error_mps2")
#: replay metrics that chaotic impacts do not scramble (the time-domain ones above are, at 0.5-1 mm
#: clearance, limited by the impact sequence): RMS third-octave band-energy difference [dB] and the
#: differences of log10 of the impact-peak statistics (median, 90th percentile, median decay)
FEATURE_METRICS = ("band_rms_db", "peak_median_dlog10", "peak_p90_dlog10", "decay_dlog10")


def feature_metrics(rec_acc: dict[str, np.ndarray], sim_acc: dict[str, np.ndarray], rate: float) -> dict[str, dict]:
    """Per accelerometer, :data:`FEATURE_METRICS` of the simulated window against the recorded one."""
    from twin.calibration.objective import band_levels_db, peak_stats

    out = {}
    for a, x in rec_acc.items():
        d = band_levels_db(sim_acc[a], rate) - band_levels_db(x, rate)
        m = {"band_rms_db": float(np.sqrt(np.mean(d * d)))}
        pr, ps = peak_stats(x, rate), peak_stats(sim_acc[a], rate)
        for k, name in enumerate(FEATURE_METRICS[1:]):
            m[name] = float(ps[k] - pr[k]) if pr is not None and ps is not None else None
        out[a] = m
    return out


def replay_metrics(target, cfg) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """``twin replay``'s per-accelerometer metrics of ``cfg`` on ``target`` (no time shift: the same
    window), and the simulated window's accelerations."""
    from twin.bench_replay import ReplayOptions, compare_accelerations
    from twin.calibration.objective import simulate_target

    acc, angle, _ = simulate_target(target, cfg)
    i0, i1 = target.window
    turns = abs(float(target.phi[i1 - 1] - target.phi[i0])) / (2 * math.pi)
    crank_hz = turns / ((i1 - 1 - i0) / target.rate)
    comp = compare_accelerations(target.rec_acc, acc, target.rate, crank_hz, ReplayOptions(plots=False, dtw_max_s=0.1))
    feats = feature_metrics(target.rec_acc, acc, target.rate)
    return {a: {**{k: comp[a][k] for k in METRICS}, **feats.get(a, {})} for a in comp}, acc


def write_outputs(out: Path, report: dict[str, Any], targets, params, x0, x1, config, ev, options,
                  bases) -> None:
    """Fill ``report`` with the replay metrics and write calibrated.toml, report.md and the PNGs."""
    import tomli_w

    from twin.calibration.params import overlay
    from twin.util import atomic_write_text

    metrics, sims = [], []
    for t in targets:
        before, acc0 = replay_metrics(t, t.base.replace(**{p.field: v for p, v in zip(params, x0)}))
        after, acc1 = replay_metrics(t, t.base.replace(**{p.field: v for p, v in zip(params, x1)}))
        metrics.append({"recording": t.path, "window_s": [t.window[0] / t.rate, t.window[1] / t.rate],
                        "before": before, "after": after})
        sims.append((acc0, acc1))
    report["replay_metrics"] = metrics

    values = {p.field: v for p, v in zip(params, x1)}
    text = ("# twin calibrate: a partial configuration (fields not given keep their defaults);\n"
            "# use it with `twin simulate --config` or `twin replay REC --config`.\n"
            + "".join(f"# {p['field']} = {p['value']:.6g}, interval {p['lo']:.4g}..{p['hi']:.4g} ({p['method']}"
                      + (", FLAT" if p["flat"] else "") + (", ROUGH" if p.get("rough") else "") + (f", on its {p['on_bound']} bound" if p["on_bound"] else "")
                      + ")\n" for p in report["parameters"])
            + tomli_w.dumps(overlay(config, values)))
    atomic_write_text(out / "calibrated.toml", text)
    files = ["calibrated.toml", "report.json", "report.md", "evaluations.jsonl"]
    if options.plots:
        files += _plots(out, targets, sims, params, ev, report)
    report["files"] = files
    atomic_write_text(out / "report.md", render_markdown(report))


def _fmt(v: Any, spec: str = ".4g") -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    return format(v, spec)


def waveform_lines(w: dict[str, Any] | None) -> list[str]:
    """The report's section on the waveform stage (twin.calibration.waveform)."""
    if not w:
        return []
    if not w.get("ran"):
        return ["## Waveform stage", "", f"Not run: {w.get('reason')}.", ""]
    lines = ["## Waveform stage", "",
             f"Least squares on the accelerations low-passed at {w['lowpass_hz']:g} Hz from the feature fit "
             f"({w['replays']} replays, {w['wall_s']:.1f} s; {w['reason']}); predictability: the fitted values × "
             f"(1 ± 1e-9) replay {max(w['predictability_pct']):.2g} % away (limit {w['chaos_pct']:g} %). Misfit "
             f"{w['cost_before']:.3g} → {w['cost_after']:.3g}. The intervals are the feature fit's: a change of "
             "several half-widths on a bench recording is more likely model error than information.", "",
             "| field | feature fit | waveform stage | change | change / interval half-width | inside interval |",
             "|---|---|---|---|---|---|"]
    for c in w["changes"]:
        rel = f" ({100 * c['relative_change']:+.3g} %)" if c.get("relative_change") is not None else ""
        lines.append(f"| {c['field']} | {_fmt(c['before'], '.6g')} | {_fmt(c['after'], '.6g')} | "
                     f"{_fmt(c['change'], '+.3g')}{rel} | {_fmt(c.get('shift_in_half_widths'), '+.2f')} | "
                     f"{'yes' if c.get('inside_interval', True) else 'NO'} |")
    lines += ["", "Replay NRMSE [%] per recording and accelerometer, feature fit → waveform stage: "
              + "; ".join(f"{i + 1}: " + ", ".join(f"{a} {b:.3g} → {w['nrmse_after'][i][a]:.3g}" for a, b in nb.items())
                          for i, nb in enumerate(w["nrmse_before"])), ""]
    return lines


def render_markdown(r: dict[str, Any]) -> str:
    o = r["objective"]
    lines = ["# Calibration report", "",
             f"Recordings: {', '.join('`' + x['path'] + '`' for x in r['recordings'])}; base configuration: "
             f"{r['base_config']}; drive: {r['options']['drive']}.", "",
             "## Parameters", "",
             "| field | base | fitted | interval | method | bounds | notes |", "|---|---|---|---|---|---|---|"]
    for p in r["parameters"]:
        notes = []
        if p["flat"]:
            notes.append("FLAT: not told by these recordings")
        if p.get("rough"):
            notes.append("ROUGH: the objective jumps between neighbouring values; not told by these recordings")
        if p["on_bound"]:
            notes.append(f"on its {p['on_bound']} bound")
        lines.append(f"| {p['field']} | {_fmt(p['base'])} | {_fmt(p['value'])} | {_fmt(p['lo'])} – {_fmt(p['hi'])} | "
                     f"{p['method']} | {p['bounds'][0]:g} – {p['bounds'][1]:g} | {'; '.join(notes)} |")
    nrep = r["uncertainty"].get("noise_replicates", 0)
    boot_used = any(p["method"].startswith("bootstrap+jitter") for p in r["parameters"])
    lines += ["", ("Intervals: the block bootstrap's (method bootstrap+jitter, below; +dj: widened to the ΔJ interval where that is wider); the ΔJ interval beside it: "
                   if boot_used else "Intervals: ")
              + f"where the objective stays within ΔJ = {o['delta_j_used']:.3g} of its minimum "
              f"({o['delta_j']:g} × max(1, misfit per term J*/n)); {r['uncertainty']['note']}"
              + (f"; widened to hold the 90 % noise interval from {nrep} noise replicates (method +noise)" if nrep else "")
              + ". Their coverage on known truths: docs/calibration.md.", ""]
    bt = r.get("bootstrap") or {}
    if bt.get("available"):
        lines += [f"Bootstrap: {bt['method']}; blocks: {'; '.join(bt['blocks'])}. Per field (interval as "
                  f"reported with method bootstrap+jitter; the bootstrap alone; the largest deterministic jump of the "
                  "objective along the profile and the interval where it stays within ΔJ + that jump):", "",
                  "| field | bootstrap alone | reported | ΔJ interval | largest jump | jitter interval | ROUGH |",
                  "|---|---|---|---|---|---|---|"]
        dj = {p["field"]: p for p in r["parameters"]}
        for q in bt["parameters"]:
            g = q["roughness"]
            lines.append(f"| {q['field']} | {_fmt(q['boot_lo'])} – {_fmt(q['boot_hi'])} | {_fmt(q['lo'])} – "
                         f"{_fmt(q['hi'])} | {_fmt(dj[q['field']].get('dj_lo'))} – {_fmt(dj[q['field']].get('dj_hi'))} | "
                         f"{_fmt(g['max_drop'], '.3g')} | {_fmt(q['jitter_lo'])} – {_fmt(q['jitter_hi'])} | "
                         f"{'yes' if q['rough'] else 'no'} |")
        lines.append("")
    elif bt:
        lines += [f"Bootstrap: not available ({bt.get('why')}).", ""]
    lines += waveform_lines(r.get("waveform"))
    if r["warnings"]:
        lines += ["## Warnings", ""] + [f"- {w}" for w in r["warnings"]] + [""]
    if r.get("identifiability"):
        lines += ["## Identifiability", "",
                  "What these recordings tell about each field: **told** (interval under a quarter of the range), "
                  "**weak** (wider), **FLAT** (the objective does not rise by ΔJ across the range: the fitted "
                  "number means nothing; fix the field from another source or record what shows it).", "",
                  "| field | verdict | objective rise along its profile | interval / range | noise interval / range "
                  "| correlated with |", "|---|---|---|---|---|---|"]
        for d in r["identifiability"]:
            lines.append(f"| {d['field']} | {d['verdict'].upper() if d['verdict'] in ('flat', 'rough') else d['verdict']} | "
                         f"{_fmt(d['profile_rise'], '.3g')} (ΔJ {_fmt(d['delta_j'], '.3g')}) | "
                         f"{_fmt(d['interval_share_of_range'], '.2f')} | {_fmt(d['noise_share_of_range'], '.2g')} | "
                         f"{', '.join(d['correlated_with']) or '–'} |")
        lines.append("")
    lines += ["## Objective", "", f"Total (full length): before {_fmt(o['before'])}, after {_fmt(o['after'])}. "
              f"Term scales: {', '.join(f'{k} {v:.3g}' for k, v in o['scales'].items())} ({o['scales_note']}).", "",
              "| recording | term | before | after |", "|---|---|---|---|"]
    for i, (tb, ta) in enumerate(zip(o["terms_before"], o["terms_after"])):
        for k in tb:
            lines.append(f"| {i + 1} | {k} | {_fmt(tb[k])} | {_fmt(ta.get(k))} |")
    lines += ["", "Terms: bands = RMS third-octave band energy difference [dB]; peaks = RMS difference of log10 "
              "impact-peak statistics; dtw = mean normalized DTW distance [%]; ripple = RMS crank-speed harmonic "
              "difference [rad/s]; command = RMS difference of the low-passed crank speed over the whole run [rad/s].", "",
              "## Replay metrics per accelerometer (before → after)", ""]
    for m in r.get("replay_metrics", []):
        lines += [f"`{m['recording']}`, window {m['window_s'][0]:.3f}–{m['window_s'][1]:.3f} s:", "",
                  "| sensor | NRMSE % | correlation | DTW % | RMS error m/s² | band energies RMS dB | "
                  "median impact peak Δlog10 |", "|---|---|---|---|---|---|---|"]
        for a, b in m["before"].items():
            c = m["after"][a]
            lines.append(f"| {a} | {_fmt(b['nrmse_pct'], '.3g')} → {_fmt(c['nrmse_pct'], '.3g')} | "
                         f"{_fmt(b['correlation'], '.4f')} → {_fmt(c['correlation'], '.4f')} | "
                         f"{_fmt(b['dtw_distance_pct'], '.3g')} → {_fmt(c['dtw_distance_pct'], '.3g')} | "
                         f"{_fmt(b['rms_error_mps2'], '.3g')} → {_fmt(c['rms_error_mps2'], '.3g')} | "
                         f"{_fmt(b.get('band_rms_db'), '.3g')} → {_fmt(c.get('band_rms_db'), '.3g')} | "
                         f"{_fmt(b.get('peak_median_dlog10'), '+.3f')} → {_fmt(c.get('peak_median_dlog10'), '+.3f')} |")
        lines.append("")
    e = r["evaluations"]
    lines += ["## Cost", "", f"{e['total']} evaluations ({e['simulated_now']} simulated by this run, {e['resumed']} "
              f"read back from the log, {e['failed']} failed); mean wall time per evaluation: short "
              f"{_fmt(e['seconds_per_evaluation']['short'], '.3g')} s, full {_fmt(e['seconds_per_evaluation']['full'], '.3g')} s.", ""]
    for f in r.get("files", []):
        if f.endswith(".png"):
            lines += [f"![{f}]({f})", ""]
    from twin.provenance import stamp_line

    lines += [stamp_line(), ""]
    return "\n".join(lines)


def _plots(out: Path, targets, sims, params, ev, report) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from scipy.signal import welch

    from twin.util import atomic_write_bytes

    def save(fig, name: str) -> str:
        import io

        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=100)
        plt.close(fig)
        atomic_write_bytes(out / name, buf.getvalue())
        return name

    files = []
    t = targets[0]
    acc0, acc1 = sims[0]
    n = len(t.sensors)
    fig, axes = plt.subplots(n, 1, figsize=(10, 2.0 * n), sharex=True, squeeze=False)
    nper = int(min(len(next(iter(t.rec_acc.values()))), 4096))
    for ax, a in zip(axes[:, 0], t.sensors):
        for x, lab, c in ((t.rec_acc[a], "recorded", "k"), (acc0[a], "before", "tab:blue"),
                          (acc1[a], "calibrated", "tab:red")):
            f, p = welch(x - np.mean(x), fs=t.rate, nperseg=nper)
            sel = (f > 0) & (f <= 10_000)
            ax.loglog(f[sel], p[sel], lw=0.7, color=c, label=lab)
        ax.set_ylabel(f"{a} PSD")
        ax.grid(alpha=0.3, which="both")
    axes[0, 0].legend(fontsize=8)
    axes[0, 0].set_title(f"Welch PSD [(m/s²)²/Hz], window {t.window[0] / t.rate:.2f}–{t.window[1] / t.rate:.2f} s of "
                         f"{Path(t.path).name}")
    axes[-1, 0].set_xlabel("frequency [Hz]")
    fig.tight_layout()
    files.append(save(fig, "spectra.png"))

    # time windows: about 1.2 crank turns from the window's start (at most the window)
    i0, i1 = t.window
    turns = abs(float(t.phi[i1 - 1] - t.phi[i0])) / (2 * math.pi)
    m = i1 - i0 if turns <= 1.2 else int((i1 - i0) * 1.2 / turns)
    tt = (i0 + np.arange(m)) / t.rate
    fig, axes = plt.subplots(n, 1, figsize=(11, 1.9 * n), sharex=True, squeeze=False)
    for ax, a in zip(axes[:, 0], t.sensors):
        ax.plot(tt, t.rec_acc[a][:m], lw=0.6, color="k", label="recorded")
        ax.plot(tt, acc0[a][:m], lw=0.6, color="tab:blue", alpha=0.8, label="before")
        ax.plot(tt, acc1[a][:m], lw=0.6, color="tab:red", alpha=0.8, label="calibrated")
        ax.set_ylabel(f"{a} [m/s²]")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8, loc="upper right")
    axes[0, 0].set_title(f"calibrated accelerations, {tt[0]:.3f}–{tt[-1]:.3f} s of {Path(t.path).name}")
    axes[-1, 0].set_xlabel("time [s]")
    fig.tight_layout()
    files.append(save(fig, "windows.png"))

    fig, ax = plt.subplots(figsize=(9, 3.5))
    hist = list(ev.cache.values())
    for st, c in (("short", "tab:blue"), ("full", "tab:red")):
        idx = [i for i, e in enumerate(hist) if e["stage"] == st]
        ax.semilogy(idx, [max(ev.value(hist[i]), 1e-6) for i in idx], ".", color=c, label=f"{st} windows")
    ax.set_xlabel("evaluation")
    ax.set_ylabel("objective")
    ax.set_title("objective history")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    files.append(save(fig, "history.png"))

    d = len(params)
    fig, axes = plt.subplots(1, d, figsize=(4.5 * d, 3.5), squeeze=False)
    full = [e for e in hist if e["stage"] == "full" and e["status"] == "ok"]
    for i, (ax, p) in enumerate(zip(axes[0], params)):
        fp = report["parameters"][i]
        ax.plot([e["x"][i] for e in full], [ev.value(e) for e in full], "o", ms=3, color="tab:gray",
                label="full-length evaluations")
        ax.axvline(fp["value"], color="tab:red", label="fitted")
        ax.axvspan(fp["lo"], fp["hi"], color="tab:red", alpha=0.15, label="interval")
        ax.axvline(fp["base"], color="tab:blue", ls="--", label="base")
        ax.set_xlabel(p.field)
        if p.log:
            ax.set_xscale("log")
        ax.set_ylabel("objective")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    files.append(save(fig, "profiles.png"))
    return files
