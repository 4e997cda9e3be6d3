"""Validation of ``twin calibrate`` on synthetic recordings with known truth (docs/calibration.md,
"Validation protocol"). Two steps, each run once:

    python analysis/calibration_validation.py make --work DIR   # truths (truth.json), then the recordings
    python analysis/calibration_validation.py run --work DIR    # the calibrations, results.json, table.md

``make`` draws the truths (``numpy.random.default_rng(2026)``), writes
``analysis/calibration_validation/truth.json`` (before any calibration exists), then records two
repeats (noise seeds 1 and 2) of every case through ``twin record`` (the sensor chain, a static
calibration) into ``DIR``. ``run`` calibrates every case once (``--drive program``, then the
trace-drive cases), compares with the truth and writes ``results.json`` and ``table.md`` next to
``truth.json``. Nothing is tuned between the two: the targets are the issue's.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent / "calibration_validation"
SEED = 2026
DURATION_S, MOTOR_RPM, RAMP_S = 0.5, 1000.0, 0.05
#: budget of every calibration (the same for all cases)
BUDGET = dict(n_global=8, local_short=10, local_full=8, replicates=4, workers=2)

# case: engine, Table 4 test, joint C clearance [mm], extra fixed settings, fitted fields (truth drawn
# uniformly in the documented range, log-uniform for log fields), fields set outside their range
CASES = [
    ("mu_1", "reference", 6, 0.5, {}, ["contact.mu0"], {}),
    ("mu_2", "mujoco", 6, 0.5, {}, ["contact.mu0"], {}),
    ("mu_3", "reference", 12, 1.0, {}, ["contact.mu0"], {}),
    ("mu_4", "mujoco", 12, 1.0, {}, ["contact.mu0"], {}),
    ("e_1", "reference", 6, 0.5, {}, ["contact.restitution"], {}),
    ("e_2", "mujoco", 6, 0.5, {}, ["contact.restitution"], {}),
    ("guide_1", "reference", 6, 0.5, {}, ["mechanism.guide_friction_n"], {"mechanism.guide_friction_n": 1.2}),
    ("kp_1", "mujoco", 6, 0.5, {"drive.mode": "motor", "simulation.duration_s": 0.6}, ["drivetrain.speed_kp_nms"], {}),
    ("kp_2", "reference", 6, 0.5, {"drive.mode": "motor", "simulation.duration_s": 0.6}, ["drivetrain.speed_kp_nms"],
     {"drivetrain.speed_kp_nms": 1.2}),
    ("frame_1", "reference", 6, 0.5, {"structure.mode": "flexible"},
     ["structure.frame_frequency_hz", "structure.frame_damping_ratio"], {}),
]
#: the trace-drive runs (reported separately), on the friction cases
TRACE_CASES = ["mu_1", "mu_2", "mu_3", "mu_4"]
#: noise seeds of the two repeats of every case
REPEAT_SEEDS = (1, 2)

# The second set (docs/calibration.md, "Second validation protocol"), committed before any of its
# recordings existed: other seeds, 2.0 s recordings (the analysis window holds four crank turns: the
# bootstrap's blocks are whole turns), the current intervals (bootstrap) and verdicts (ROUGH).
SET2 = {
    "here": Path(__file__).resolve().parent / "calibration_validation_2",
    "seed": 2027, "duration_s": 2.0, "repeat_seeds": (3, 4), "trace_cases": [],
    "budget": dict(n_global=6, local_short=8, local_full=6, replicates=0, boot_replicates=400, workers=2),
    "cases": [
        ("mu_a", "reference", 6, 0.5, {}, ["contact.mu0"], {}),
        ("mu_b", "mujoco", 6, 0.5, {"simulation.duration_s": 1.0}, ["contact.mu0"], {}),
        ("mu_c", "reference", 12, 1.0, {}, ["contact.mu0"], {}),
        ("mu_d", "mujoco", 12, 1.0, {"simulation.duration_s": 1.0}, ["contact.mu0"], {}),
        ("e_a", "reference", 6, 0.5, {}, ["contact.restitution"], {}),
        ("e_b", "mujoco", 12, 1.0, {"simulation.duration_s": 1.0}, ["contact.restitution"], {}),
        ("guide_a", "mujoco", 6, 0.5, {"simulation.duration_s": 1.0}, ["mechanism.guide_friction_n"], {}),
        ("kp_a", "reference", 6, 0.5, {"drive.mode": "motor"}, ["drivetrain.speed_kp_nms"], {}),
        ("belt_a", "mujoco", 6, 0.5, {"drive.mode": "motor", "simulation.duration_s": 1.0}, ["drivetrain.belt_ea_n"], {}),
        ("mu_guide_a", "reference", 6, 0.5, {}, ["contact.mu0", "mechanism.guide_friction_n"], {}),
    ],
}
# The third set (docs/calibration.md, "Third validation protocol"): the second set's cases and budget with
# other seeds, for the roughness rule changed after the second look; committed before its recordings.
SET3 = {**SET2, "here": Path(__file__).resolve().parent / "calibration_validation_3", "seed": 2028,
        "repeat_seeds": (5, 6)}
# The fourth set (docs/calibration.md, "Fourth validation protocol"), committed before any of its recordings
# existed: the search with restarts, ROUGH with split low sets, the interval never narrower than the ΔJ one;
# 12 configurations (24 recordings), two truths outside their ranges, an accelerometer-mount structure case
# (flexible, 1.0 s), the trace drive on two friction cases, and the replay floor beside the criterion.
SET4 = {
    "here": Path(__file__).resolve().parent / "calibration_validation_4",
    "seed": 2029, "duration_s": 2.0, "repeat_seeds": (7, 8), "trace_cases": ["mu_a", "mu_b"],
    "budget": dict(n_global=6, local_short=8, local_full=6, replicates=0, boot_replicates=400, workers=2,
                   restarts=2),
    "cases": [
        ("mu_a", "reference", 6, 0.5, {}, ["contact.mu0"], {}),
        ("mu_b", "mujoco", 6, 0.5, {"simulation.duration_s": 1.0}, ["contact.mu0"], {}),
        ("mu_c", "reference", 12, 1.0, {}, ["contact.mu0"], {}),
        ("mu_d", "mujoco", 12, 1.0, {"simulation.duration_s": 1.0}, ["contact.mu0"], {}),
        ("e_a", "reference", 6, 0.5, {}, ["contact.restitution"], {}),
        ("e_b", "mujoco", 12, 1.0, {"simulation.duration_s": 1.0}, ["contact.restitution"], {}),
        ("guide_a", "mujoco", 6, 0.5, {"simulation.duration_s": 1.0}, ["mechanism.guide_friction_n"],
         {"mechanism.guide_friction_n": 1.2}),
        ("kp_a", "reference", 6, 0.5, {"drive.mode": "motor"}, ["drivetrain.speed_kp_nms"], {}),
        ("belt_a", "mujoco", 6, 0.5, {"drive.mode": "motor", "simulation.duration_s": 1.0}, ["drivetrain.belt_ea_n"],
         {"drivetrain.belt_ea_n": 1.2}),
        ("mu_guide_a", "reference", 6, 0.5, {}, ["contact.mu0", "mechanism.guide_friction_n"], {}),
        ("kp_b", "mujoco", 12, 1.0, {"drive.mode": "motor", "simulation.duration_s": 1.0}, ["drivetrain.speed_kp_nms"],
         {}),
        ("mount_a", "reference", 6, 0.5, {"structure.mode": "flexible", "simulation.duration_s": 1.0},
         ["structure.mount_frequency_hz", "structure.mount_damping_ratio"], {}),
    ],
}
# The fifth set (analysis/calibration_validation_5/PROTOCOL.md), committed before any of its recordings existed:
# recordings the calibration could not replay on their trace before (an imposed ripple replayed twice, the motor's
# own speed loop instead of the encoder trace), calibrated once with the default drive (trace) and the fourth
# set's budget; both engines, friction, guide friction and the speed-loop gain drawn across their ranges.
SET5 = {
    "here": Path(__file__).resolve().parent / "calibration_validation_5",
    "seed": 2030, "duration_s": 2.0, "repeat_seeds": (9, 10),
    "trace_cases": ["ripple_mu", "motor_guide", "motor_kp", "ripple_guide"], "program": False,
    "budget": dict(SET4["budget"]),
    "cases": [
        ("ripple_mu", "reference", 6, 0.5, {"drive.ripple_pct": (3.0,)}, ["contact.mu0"], {}),
        ("motor_guide", "mujoco", 6, 0.5, {"drive.mode": "motor", "simulation.duration_s": 1.0},
         ["mechanism.guide_friction_n"], {}),
        ("motor_kp", "reference", 6, 0.5, {"drive.mode": "motor"}, ["drivetrain.speed_kp_nms"], {}),
        ("ripple_guide", "mujoco", 12, 1.0, {"drive.ripple_pct": (2.0, 1.0), "simulation.duration_s": 1.0},
         ["mechanism.guide_friction_n"], {}),
    ],
}
#: whether the set's cases are calibrated with the program drive (sets 1-4; set 5: the trace drive only)
PROGRAM_JOBS = True
#: the fourth set's restitution verdict rule (analysis/restitution_length.py: on analysis windows of at least
#: four crank turns the objective's largest jump stayed below ΔJ in 5 of 6 benches, on shorter ones it
#: ranged from 0.02 to 7 ΔJ): ROUGH or FLAT is a miss on windows of >= RESTITUTION_TOLD_TURNS turns, either
#: verdict is right on shorter ones
RESTITUTION_TOLD_TURNS = 4.0
#: relative perturbations of the truth whose replays are the floor of the replay criterion (set 4)
FLOOR_PERTURB = (1e-9, -1e-9)
#: fields whose ROUGH or FLAT verdict is the right answer on these recordings (measured before the
#: second set: analysis/restitution_length.py); a ROUGH or FLAT verdict on any other field is a miss
NOT_TOLD = ("contact.restitution",)
#: targets (the issue's): relative for friction / drive train / structure frequency and damping,
#: absolute for restitution
#: the set in use (select_set)
SET_NAME = "1"
TARGETS = {"contact.mu0": ("rel", 0.25), "mechanism.guide_friction_n": ("rel", 0.25),
           "contact.restitution": ("abs", 0.05), "drivetrain.speed_kp_nms": ("rel", 0.20),
           "drivetrain.belt_ea_n": ("rel", 0.20), "structure.frame_frequency_hz": ("rel", 0.03),
           "structure.frame_damping_ratio": ("rel", 0.30), "structure.mount_frequency_hz": ("rel", 0.03),
           "structure.mount_damping_ratio": ("rel", 0.30)}


def draw_truths() -> list[dict]:
    from twin.calibration.params import LOG_FIELDS, documented_ranges

    rng = np.random.default_rng(SEED)
    ranges = documented_ranges()
    out = []
    for name, engine, test, clr, extra, fields, outside in CASES:
        truth = {}
        for f in fields:
            lo, hi = ranges[f]
            u = rng.uniform()
            if f in outside:  # 20 % (of the range's high end) above it
                truth[f] = float(hi * outside[f])
            elif f in LOG_FIELDS and lo > 0:
                truth[f] = float(math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo))))
            else:
                truth[f] = float(lo + u * (hi - lo))
        out.append({"case": name, "engine": engine, "test": test, "clearance_c_mm": clr, "fixed": extra,
                    "fields": fields, "truth": truth, "outside": sorted(outside)})
    return out


def config_of(case: dict, seed: int, fitted_at_default: bool = False):
    from twin.config import BenchConfig, preset

    cfg = preset(case["test"]).replace(**{"simulation.engine": case["engine"], "simulation.duration_s": DURATION_S,
                                          "drive.motor_rpm": MOTOR_RPM, "drive.ramp_s": RAMP_S,
                                          "joints.clearance_c_mm": case["clearance_c_mm"],
                                          "instrumentation.seed": seed, **case["fixed"]})
    if fitted_at_default:
        d = BenchConfig()
        from twin.calibration.params import field_value

        return cfg.replace(**{f: field_value(d, f) for f in case["fields"]})
    return cfg.replace(**case["truth"])


def make(work: Path, again: bool = False) -> None:
    """Draw the truths, write truth.json, then the recordings; ``again``: only the recordings again, from
    the committed truth.json (checked equal to the drawn truths), when the work folder was lost."""
    truth_path = HERE / "truth.json"
    cases = draw_truths()
    if again:
        if json.loads(truth_path.read_text())["cases"] != json.loads(json.dumps(cases)):
            sys.exit(f"{truth_path} differs from the truths drawn now: not the same set")
    elif truth_path.exists():
        sys.exit(f"{truth_path} exists: the set is made once (--again makes its recordings again)")
    else:
        HERE.mkdir(parents=True, exist_ok=True)
        from twin.provenance import stamped

        truth_path.write_text(json.dumps(stamped({"seed": SEED, "duration_s": DURATION_S, "motor_rpm": MOTOR_RPM,
                                                  "ramp_s": RAMP_S, "cases": cases}), indent=1) + "\n")
    work.mkdir(parents=True, exist_ok=True)
    twin_exe = str(Path(sys.executable).with_name("twin"))
    for case in cases:
        for seed in REPEAT_SEEDS:
            cfg = config_of(case, seed)
            toml = work / f"{case['case']}_s{seed}.toml"
            toml.write_text(cfg.to_toml())
            out = work / f"{case['case']}_s{seed}.mcap"
            t0 = time.perf_counter()
            subprocess.run([twin_exe, "record", "--config", str(toml), "--out", str(out), "--no-progress"],
                           check=True, stdout=subprocess.DEVNULL)
            print(f"{out.name}: {time.perf_counter() - t0:.1f} s", flush=True)


def verdict_right(field: str, not_told: bool, turns: float) -> bool:
    """Whether a ROUGH/FLAT (``not_told``) or identified verdict is the right one: sets 1-3, ROUGH or FLAT right
    on restitution only; set 4, restitution's by the window's crank turns (:data:`RESTITUTION_TOLD_TURNS`)."""
    if field not in NOT_TOLD:
        return not not_told
    if SET_NAME == "4":
        return (not not_told) if turns >= RESTITUTION_TOLD_TURNS else True
    return not_told


def verdict(field: str, truth: float, value: float) -> tuple[float, bool]:
    kind, tol = TARGETS[field]
    err = (value - truth) / truth if kind == "rel" else value - truth
    return float(err), bool(abs(err) <= tol)


#: the replay metrics compared fitted against truth: the issue's (time-domain NRMSE, chaos-limited at
#: 0.5-1 mm clearance) and those chaotic impacts do not scramble (band energies, impact peaks)
REPLAY_FEATURES = ("band_rms_db", "peak_median_dlog10", "peak_p90_dlog10")


def replay_compare(case: dict, recs: list[Path], base, fitted: dict[str, float], drive: str) -> dict:
    """Replay metrics per accelerometer on the first recording with the true and the fitted values, and
    the repeat-to-repeat value of the feature metrics (the second recording against the first)."""
    from twin.calibration.objective import get_target
    from twin.calibration.report import feature_metrics, replay_metrics

    motor = any(f.startswith("drivetrain.") for f in case["fields"])
    tg = get_target(str(recs[0]), base.to_toml(), 1.0, 0.05, motor, drive)
    tg2 = get_target(str(recs[1]), base.to_toml(), 1.0, 0.05, motor, drive)
    m_true, _ = replay_metrics(tg, tg.base.replace(**case["truth"]))
    m_fit, _ = replay_metrics(tg, tg.base.replace(**fitted))
    rep = feature_metrics(tg.rec_acc, {a: tg2.rec_acc[a] for a in tg.rec_acc if a in tg2.rec_acc}, tg.rate) \
        if set(tg.rec_acc) <= set(tg2.rec_acc) else {}
    nrmse = {a: {"truth": m_true[a]["nrmse_pct"], "fitted": m_fit[a]["nrmse_pct"]} for a in m_true}
    feats = {a: {k: {"truth": m_true[a].get(k), "fitted": m_fit[a].get(k), "repeat": rep.get(a, {}).get(k)}
                 for k in REPLAY_FEATURES} for a in m_true}
    i0, i1 = tg.window
    turns = abs(float(tg.phi[i1 - 1] - tg.phi[i0])) / (2 * math.pi)
    floor = {}
    if SET_NAME in ("4", "5"):  # the replay floor: the truth moved by 1e-9 (analysis/replay_noise_floor.py)
        for k in FLOOR_PERTURB:
            m_p, _ = replay_metrics(tg, tg.base.replace(**{f: v * (1.0 + k) for f, v in case["truth"].items()}))
            for a in m_p:
                floor[a] = max(floor.get(a, 0.0), m_p[a]["nrmse_pct"])
        for a in nrmse:
            nrmse[a]["truth_1e-9_max"] = floor.get(a)
    bands_ok = all(v["band_rms_db"]["fitted"] <= 1.10 * v["band_rms_db"]["truth"] for v in feats.values())
    bands_rep = all(v["band_rms_db"]["repeat"] is not None
                    and v["band_rms_db"]["fitted"] <= v["band_rms_db"]["truth"] + v["band_rms_db"]["repeat"]
                    for v in feats.values())
    out_floor = ({"replay_within_floor": all(v["fitted"] <= 1.10 * v["truth_1e-9_max"] for v in nrmse.values())}
                 if floor else {})
    return {"nrmse": nrmse, "replay_within_10pct": all(v["fitted"] <= 1.10 * v["truth"] for v in nrmse.values()),
            **out_floor, "window_turns": turns,
            "replay_features": feats, "bands_within_10pct": bands_ok, "bands_within_truth_plus_repeat": bands_rep}


def run_case(case: dict, work: Path, drive: str) -> dict:
    import twin
    from twin.calibration import CalibrationOptions
    from twin.calibration.objective import get_target
    from twin.calibration.report import replay_metrics

    base = config_of(case, 0, fitted_at_default=True)
    recs = [work / f"{case['case']}_s{s}.mcap" for s in REPEAT_SEEDS]
    out = work / f"cal_{case['case']}_{drive}"
    t0 = time.perf_counter()
    try:
        res = twin.calibrate(recs, case["fields"], out, config=base,
                             options=CalibrationOptions(drive=drive, plots=False, **BUDGET))
    except Exception as err:  # a failed calibration is a miss, reported as such
        return {"case": case["case"], "drive": drive, "error": f"{type(err).__name__}: {err}",
                "wall_s": time.perf_counter() - t0}
    wall = time.perf_counter() - t0
    params = []
    for p in res.parameters:
        tr = case["truth"][p.field]
        err, hit = verdict(p.field, tr, p.value)
        params.append({"field": p.field, "truth": tr, "base": p.base, "value": p.value, "lo": p.lo, "hi": p.hi,
                       "noise_lo": p.noise_lo, "noise_hi": p.noise_hi, "method": p.method, "flat": p.flat,
                       "rough": p.rough, "dj": [p.dj_lo, p.dj_hi], "boot": [p.boot_lo, p.boot_hi],
                       "verdict_right": None,
                       "on_bound": p.on_bound, "error": err, "hit": hit, "covered": bool(p.lo <= tr <= p.hi),
                       "outside_range": p.field in case["outside"]})
    replay = replay_compare(case, recs, base, res.values(), drive)
    for p in params:
        p["verdict_right"] = verdict_right(p["field"], p["flat"] or p["rough"], replay["window_turns"])
    return {"case": case["case"], "engine": case["engine"], "drive": drive, "params": params,
            "warnings": res.warnings, "wall_s": wall, "evaluations": res.evaluations,
            "restarts": res.report["uncertainty"].get("restarts", []),
            "objective": [res.objective_before, res.objective_after], **replay}


def reassess(work: Path, only: list[str] | None) -> None:
    """Development on the set already looked at (docs/calibration.md, "Intervals: development on the
    first set"): at each program-drive case's fitted values from results.json, the profiles and the
    block bootstrap of the current code (``twin.calibrate`` with no search: the base point is the
    fitted one), no noise replicates; every interval variant against the truth, in reassess.json."""
    import twin
    from twin.calibration import CalibrationOptions

    doc = json.loads((HERE / "truth.json").read_text())
    old = {(r["case"], r["drive"]): r for r in json.loads((HERE / "results.json").read_text())["results"]}
    out_path = HERE / "reassess.json"
    rows = json.loads(out_path.read_text())["rows"] if out_path.exists() else []
    done = {r["case"] for r in rows}
    from twin.provenance import stamped

    for case in doc["cases"]:
        if case["case"] in done or (only and case["case"] not in only):
            continue
        o = old[(case["case"], "program")]
        fitted = {p["field"]: p["value"] for p in o["params"]}
        base = config_of(case, 0, fitted_at_default=True).replace(**fitted)
        recs = [work / f"{case['case']}_s{s}.mcap" for s in (1, 2)]
        t0 = time.perf_counter()
        res = twin.calibrate(recs, case["fields"], work / f"reassess_{case['case']}", config=base,
                             options=CalibrationOptions(drive="program", plots=False, n_global=0, local_short=0,
                                                        local_full=0, replicates=0, workers=BUDGET["workers"]))
        bt = res.report["bootstrap"]
        replay = replay_compare(case, recs, config_of(case, 0, fitted_at_default=True), fitted, "program")
        for p, q in zip(res.parameters, bt.get("parameters", [{}] * len(res.parameters))):
            op = next(x for x in o["params"] if x["field"] == p.field)
            tr = case["truth"][p.field]
            rows.append({"case": case["case"], "engine": case["engine"], "field": p.field, "truth": tr,
                         "value": p.value, "outside_range": p.field in case["outside"],
                         "old": [op["lo"], op["hi"]], "old_noise": [op["noise_lo"], op["noise_hi"]],
                         "dj": [p.dj_lo, p.dj_hi], "boot": [p.boot_lo, p.boot_hi], "reported": [p.lo, p.hi],
                         "jitter": [q.get("jitter_lo"), q.get("jitter_hi")],
                         "rough": p.rough, "flat": p.flat, "roughness": q.get("roughness"),
                         "boot_sd_u": q.get("boot_sd_u"),
                         "surrogate_shift_u": q.get("surrogate_shift_u"), "blocks": bt.get("blocks"),
                         "wall_s": time.perf_counter() - t0, "replay_old_fit": replay})
            r = rows[-1]
            print(f"{case['case']} {p.field}: truth {fmt(tr)} fit {fmt(p.value)} old [{fmt(r['old'][0])}, "
                  f"{fmt(r['old'][1])}] boot [{fmt(p.boot_lo)}, {fmt(p.boot_hi)}] jitter [{fmt(r['jitter'][0])}, "
                  f"{fmt(r['jitter'][1])}] rough={p.rough} {r['roughness']} {r['wall_s']:.0f} s", flush=True)
        out_path.write_text(json.dumps(stamped({"rows": rows}), indent=1, default=str) + "\n")


def reverdict(work: Path, prefix: str) -> None:
    """Development after a look: the ROUGH verdicts and reported intervals of the current
    :func:`twin.calibration.bootstrap.roughness` recomputed from the calibrations' logs and reports in
    ``work`` (folders ``{prefix}{case}...``; the bootstrap intervals as the reports hold them), against the
    truths; no simulation. Writes reverdict_{prefix}.json next to truth.json."""
    from twin.calibration.bootstrap import roughness
    from twin.calibration.objective import combine
    from twin.provenance import stamped

    doc = json.loads((HERE / "truth.json").read_text())
    rows = []
    for case in doc["cases"]:
        dirs = sorted(work.glob(f"{prefix}{case['case']}*"))
        dirs = [d for d in dirs if d.name in (f"{prefix}{case['case']}", f"{prefix}{case['case']}_program")]
        if not dirs:
            continue
        d = dirs[0]
        rep = json.loads((d / "report.json").read_text())
        lines = (d / "evaluations.jsonl").read_text().splitlines()
        hdr = json.loads(lines[0])
        scales = rep["objective"]["scales"]
        pts = {}
        for ln in lines[1:]:
            e = json.loads(ln)
            if e["stage"] == "full" and e["status"] == "ok":
                pts[tuple(round(x, 10) for x in e["u"])] = sum(combine(t, scales) for t in e["terms"])
        U = np.asarray(list(pts), dtype=np.float64)
        J = np.asarray(list(pts.values()))
        dim = U.shape[1]
        # the profile centre: the point with the most points differing from it in one coordinate only
        mates = [int(np.sum(np.sum(np.abs(U - u) > 1e-9, axis=1) == 1)) for u in U]
        centre = U[int(np.argmax(mates))]
        bt = {q["field"]: q for q in rep["bootstrap"]["parameters"]}
        for i, hp in enumerate(hdr["parameters"]):
            from twin.calibration.params import Parameter  # noqa: F401 - the unit map below is the log's

            lo_f, hi_f, log = hp["lo"], hp["hi"], hp["log"]

            def from_unit(u: float) -> float:
                return float(math.exp(math.log(lo_f) + u * (math.log(hi_f) - math.log(lo_f)))) if log \
                    else float(lo_f + u * (hi_f - lo_f))

            others = [k for k in range(dim) if k != i]
            on = np.all(np.abs(U[:, others] - centre[others]) < 1e-9, axis=1) if others else np.ones(len(U), bool)
            rg = roughness(float(centre[i]), U[on, i] - centre[i], J[on], rep["objective"]["delta_j_used"])
            q = bt[hp["field"]]
            lo, hi = q["boot_lo"], q["boot_hi"]
            if rg.rough:
                lo, hi = min(lo, from_unit(rg.lo_u)), max(hi, from_unit(rg.hi_u))
            value = next(p["value"] for p in rep["parameters"] if p["field"] == hp["field"])
            lo, hi = min(lo, value), max(hi, value)
            tr = case["truth"][hp["field"]]
            rows.append({"case": case["case"], "field": hp["field"], "truth": tr, "value": value,
                         "rough_before": bool(q["rough"]), "rough": rg.rough, "max_drop": rg.max_drop,
                         "delta_j": rep["objective"]["delta_j_used"], "interval_before": [q["lo"], q["hi"]],
                         "interval": [lo, hi], "covered_before": bool(min(q["lo"], value) <= tr <= max(q["hi"], value)),
                         "covered": bool(lo <= tr <= hi), "outside_range": hp["field"] in case["outside"],
                         "verdict_right": rg.rough == (hp["field"] in NOT_TOLD)})
            r = rows[-1]
            print(f"{r['case']} {r['field']}: truth {fmt(tr)} fit {fmt(value)} ROUGH {r['rough_before']} -> {r['rough']} "
                  f"(jump {r['max_drop']:.3g}, ΔJ {r['delta_j']:.3g}); interval [{fmt(lo)}, {fmt(hi)}] "
                  f"holds: {r['covered_before']} -> {r['covered']}", flush=True)
    n = len(rows)
    summ = {"values": n, "covered": sum(r["covered"] for r in rows), "covered_before": sum(r["covered_before"] for r in rows),
            "rough": sum(r["rough"] for r in rows), "verdicts_right": sum(r["verdict_right"] for r in rows),
            "covered_told": [sum(r["covered"] for r in rows if not r["rough"]), sum(1 for r in rows if not r["rough"])]}
    print(json.dumps(summ))
    (HERE / f"reverdict_{prefix.rstrip('_')}.json").write_text(json.dumps(stamped({"rows": rows, "summary": summ}),
                                                                          indent=1) + "\n")


def fmt(v: float) -> str:
    return f"{v:.4g}" if v is not None and math.isfinite(v) else "—"


def _error_and_verdict(p: dict) -> tuple[str, str]:
    """A fitted value's error against its truth (relative or absolute, as its target) and verdict cell."""
    kind, _tol = TARGETS[p["field"]]
    err = f"{100 * p['error']:+.1f} %" if kind == "rel" else f"{p['error']:+.3f}"
    v = (("FLAT" if p["flat"] else "") + (" ROUGH" if p.get("rough") else "")
         + (f" on {p['on_bound']} bound" if p["on_bound"] else ""))
    if p["outside_range"]:
        v += " (truth outside range)"
    return err, v


def table(results: list[dict]) -> str:
    if SET_NAME in ("4", "5"):
        return table4(results)
    lines = ["| case | engine | drive | field | truth | fitted | error | interval | verdict | target | interval holds truth | replay NRMSE fitted ≤ 1.1 × truth | band energies fitted ≤ 1.1 × truth | wall [s] |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        if "error" in r:
            lines.append(f"| {r['case']} | | {r['drive']} | FAILED: {r['error']} | | | | | | miss | | | | {r['wall_s']:.0f} |")
            continue
        for p in r["params"]:
            err, v = _error_and_verdict(p)
            lines.append(f"| {r['case']} | {r['engine']} | {r['drive']} | {p['field']} | {fmt(p['truth'])} | "
                         f"{fmt(p['value'])} | {err} | {fmt(p['lo'])} – {fmt(p['hi'])} | {v.strip() or 'fit'} | "
                         f"{'hit' if p['hit'] else 'MISS'} | {'yes' if p['covered'] else 'NO'} | "
                         f"{'yes' if r['replay_within_10pct'] else 'NO'} | "
                         f"{'—' if 'bands_within_10pct' not in r else 'yes' if r['bands_within_10pct'] else 'NO'} | "
                         f"{r['wall_s']:.0f} |")
    return "\n".join(lines) + "\n"


def table4(results: list[dict]) -> str:
    """The fourth set's table: the verdict judged, the replay criterion literal and against its floor."""
    lines = ["| case | engine | drive | field | truth | fitted | error | interval | verdict | target | interval holds "
             "truth | verdict right | replay NRMSE ≤ 1.1 × truth (literal) | replay NRMSE ≤ 1.1 × truth ± 1e-9 (floor) "
             "| band energies ≤ 1.1 × truth | wall [s] |", "|---" * 16 + "|"]
    for r in results:
        if "error" in r:
            lines.append(f"| {r['case']} | | {r['drive']} | FAILED: {r['error']} | | | | | | miss | | | | | | "
                         f"{r['wall_s']:.0f} |")
            continue
        for p in r["params"]:
            err, v = _error_and_verdict(p)
            yn = {True: "yes", False: "NO", None: "—"}
            lines.append(f"| {r['case']} | {r['engine']} | {r['drive']} | {p['field']} | {fmt(p['truth'])} | "
                         f"{fmt(p['value'])} | {err} | {fmt(p['lo'])} – {fmt(p['hi'])} | {v.strip() or 'fit'} | "
                         f"{'hit' if p['hit'] else 'MISS'} | {yn[p['covered']]} | {yn[p['verdict_right']]} | "
                         f"{yn[r['replay_within_10pct']]} | {yn[r.get('replay_within_floor')]} | "
                         f"{yn[r.get('bands_within_10pct')]} | {r['wall_s']:.0f} |")
    return "\n".join(lines) + "\n"


def summary(results: list[dict]) -> dict:
    out: dict = {}
    for drive in ("program", "trace"):
        rs = [r for r in results if r["drive"] == drive]
        ps = [p for r in rs if "params" in r for p in r["params"]]
        nf = [p for p in ps if not p["flat"]]  # (not FLAT; ROUGH counted in coverage_told)
        out[drive] = {"calibrations": len(rs), "failed": sum("error" in r for r in rs),
                      "parameters": len(ps), "hits": sum(p["hit"] for p in ps), "flat": sum(p["flat"] for p in ps),
                      "coverage_not_flat": (sum(p["covered"] for p in nf) / len(nf)) if nf else None,
                      "coverage_all": (sum(p["covered"] for p in ps) / len(ps)) if ps else None,
                      "replay_within_10pct": sum(bool(r.get("replay_within_10pct")) for r in rs),
                      "replay_within_floor": sum(bool(r.get("replay_within_floor")) for r in rs),
                      "restarts": sum(len(r.get("restarts", [])) for r in rs),
                      "bands_within_10pct": sum(bool(r.get("bands_within_10pct")) for r in rs),
                      "bands_within_truth_plus_repeat": sum(bool(r.get("bands_within_truth_plus_repeat")) for r in rs),
                      "rough_or_flat": sum(bool(p.get("rough") or p["flat"]) for p in ps),
                      "verdicts_right": sum(bool(p.get("verdict_right", True)) for p in ps),
                      "coverage_told": ((sum(p["covered"] for p in ps if not (p.get("rough") or p["flat"]))
                                         / max(1, sum(1 for p in ps if not (p.get("rough") or p["flat"]))))
                                        if ps else None),
                      "coverage_per_field": {f: [sum(p["covered"] for p in ps if p["field"] == f),
                                                 sum(1 for p in ps if p["field"] == f)]
                                             for f in sorted({p["field"] for p in ps})},
                      "wall_s": [round(r["wall_s"], 1) for r in rs]}
    return out


def run(work: Path, deadline_utc: str | None) -> None:
    doc = json.loads((HERE / "truth.json").read_text())
    res_path = HERE / "results.json"
    results: list[dict] = json.loads(res_path.read_text())["results"] if res_path.exists() else []
    done = {(r["case"], r["drive"]) for r in results}
    jobs = ([(c, "program") for c in doc["cases"]] if PROGRAM_JOBS else []) \
        + [(c, "trace") for c in doc["cases"] if c["case"] in TRACE_CASES]
    from datetime import datetime, timezone

    from twin.provenance import stamped, with_stamp_line

    for case, drive in jobs:
        if (case["case"], drive) in done:
            continue  # an interrupted run continues; nothing is run twice
        if deadline_utc and datetime.now(timezone.utc).strftime("%H:%M") >= deadline_utc:
            print(f"deadline {deadline_utc} UTC reached: {case['case']} ({drive}) not run", flush=True)
            continue
        r = run_case(case, work, drive)
        results.append(r)
        res_path.write_text(json.dumps(stamped({"budget": BUDGET, "results": results, "summary": summary(results)}),
                                       indent=1, default=str) + "\n")
        (HERE / "table.md").write_text(with_stamp_line(table(results)))
        print(f"{case['case']} ({drive}): {r.get('wall_s', 0):.0f} s "
              + ("; ".join(f"{p['field']} {fmt(p['truth'])} -> {fmt(p['value'])} [{fmt(p['lo'])}, {fmt(p['hi'])}]"
                           for p in r.get("params", [])) or r.get("error", "")), flush=True)
    print(json.dumps(summary(results), indent=1))


def select_set(name: str) -> None:
    """Make set ``name`` ("1" to "4") the module's current set (its folder, seed, cases, budget)."""
    global HERE, SEED, CASES, TRACE_CASES, DURATION_S, REPEAT_SEEDS, SET_NAME, PROGRAM_JOBS
    SET_NAME = name
    st = {"2": SET2, "3": SET3, "4": SET4, "5": SET5}.get(name)
    if st is not None:
        PROGRAM_JOBS = st.get("program", True)
        HERE, SEED, CASES, TRACE_CASES = st["here"], st["seed"], st["cases"], st["trace_cases"]
        DURATION_S, REPEAT_SEEDS = st["duration_s"], st["repeat_seeds"]
        BUDGET.clear()
        BUDGET.update(st["budget"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("step", choices=("make", "run", "reassess", "reverdict"))
    ap.add_argument("--prefix", default="cal_", help="with reverdict: the calibration folders' prefix (cal_ or reassess_)")
    ap.add_argument("--work", required=True, type=Path, help="folder for the recordings and calibrations")
    ap.add_argument("--set", choices=("1", "2", "3", "4", "5"), default="1",
                    help="1: the first set (its results are in); 2: the second set (docs/calibration.md, \"Second "
                         "validation protocol\")")
    ap.add_argument("--again", action="store_true",
                    help="with make: the recordings again from the committed truth.json (a lost work folder)")
    ap.add_argument("--deadline-utc", default=None, help="HH:MM: start no calibration after it")
    ap.add_argument("--smoke", metavar="DIR", type=Path, default=None,
                    help="a trial of the pipeline (not the validation): truths with another seed into DIR, the cases "
                         "given by --cases, a small budget")
    ap.add_argument("--cases", default=None, help="with --smoke: the cases to make and run (comma-separated)")
    a = ap.parse_args()
    select_set(a.set)
    global HERE, SEED, CASES, TRACE_CASES
    if a.smoke is not None:
        HERE, SEED = a.smoke, 99
        if a.cases:
            CASES = [c for c in CASES if c[0] in a.cases.split(",")]
        TRACE_CASES = [c for c in TRACE_CASES if c in a.cases.split(",")] if a.cases else TRACE_CASES
        BUDGET.update(n_global=2, local_short=2, local_full=2, replicates=2)
    if a.step == "make":
        make(a.work, a.again)
    elif a.step == "reverdict":
        reverdict(a.work, a.prefix)
    elif a.step == "reassess":
        reassess(a.work, a.cases.split(",") if a.cases else None)
    else:
        run(a.work, a.deadline_utc)


if __name__ == "__main__":
    main()
