"""``twin identify``: clearance identification (train, evaluate, clearance) from the twin's datasets."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from twin.commands.inputs import RECORDING_HELP, recording
from twin.errors import TwinError
from twin.identification.model import resolve_model
from twin.util import resolve_workers


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("identify", help="identify clearance from a bench recording (train, evaluate, clearance)",
                       description="Which joint has clearance, and how much: features of the calibrated "
                                   "accelerations in the crank-angle domain, a gradient-boosting model trained on a "
                                   "twin dataset (twin dataset generate).")
    ids = p.add_subparsers(dest="identify_command", metavar="ACTION", parser_class=type(p))
    ids.required = True

    t = ids.add_parser("train", help="train a model on a dataset, or several pooled (train and val splits)")
    t.add_argument("dataset", metavar="DATASET", nargs="+",
                   help="dataset folder(s) of one engine, sample rate and encoder resolution; several are pooled "
                        "(e.g. catalogue clearances beside continuous ones)")
    t.add_argument("--out", metavar="MODEL.npz", required=True, help="model file to write (.npz: plain arrays and JSON)")
    t.add_argument("--splits", default="train,val", help="splits to train on (default train,val)")
    t.add_argument("--workers", type=int, metavar="N", help="processes for the features (default: the cores)")
    t.add_argument("--interval-folds", choices=("runs", "speed"), default="runs",
                   help="out-of-fold groups of the 90 %% intervals' calibration: 5 random groups of runs (default) "
                        "or one group per motor speed (answers at speeds the regressor never saw)")
    t.add_argument("--location-only", metavar="DATASET", nargs="+", default=[],
                   help="dataset folder(s) pooled for the fault location only, not for the size regressors "
                        "(runs of a regime the others lack, e.g. one speed, that would tilt the sizes)")
    for j in ("B", "C"):
        t.add_argument(f"--{j.lower()}-size-only", metavar="DATASET", nargs="+", default=[],
                       help=f"dataset folder(s) pooled for the fault location and the size at {j} only, not for the "
                            f"other joint's size (runs drawn to fill a regime at {j} that would tilt the other's sizes)")
    t.add_argument("--fault-split", choices=("none", "B", "C", "BC"), default="C",
                   help="joints whose 90 %% intervals are calibrated apart for recordings located with both joints "
                        "faulty (default C: the other joint's impacts scatter its size)")
    t.set_defaults(func=_train)

    e = ids.add_parser("evaluate", help="evaluate a model on a dataset, or several pooled: confusion matrix, "
                                        "recall, size errors")
    e.add_argument("model", metavar="MODEL.npz", help="model file (twin identify train writes one)")
    e.add_argument("dataset", metavar="DATASET", nargs="+",
                   help="dataset folder(s) of one engine, sample rate and encoder resolution; several are pooled "
                        "(e.g. a test set and its extension by another seed)")
    e.add_argument("--out", metavar="REPORT_DIR", required=True,
                   help="report folder to write (report.md, report.json, PNG plots)")
    e.add_argument("--splits", default="train,val,test", help="splits to evaluate (default: all)")
    e.add_argument("--workers", type=int, metavar="N", help="processes for the features (default: the cores)")
    e.set_defaults(func=_evaluate)

    c = ids.add_parser("clearance", help="which joint has clearance in a bench recording, and how much")
    c.add_argument("recording", metavar="REC.mcap", help=RECORDING_HELP)
    c.add_argument("--model", metavar="MODEL", help="a model file (.npz) or a shipped model: 'default' (B and C) or "
                   "'bench' (B, C and the slider guide G, trained on the whole bench); default: 'default'")
    c.add_argument("--json", metavar="OUT.json", help="also write the answer as JSON (a refused recording: its record, "
                                                      "refused: true and the reason)")
    c.set_defaults(func=_clearance)

    r = ids.add_parser("restitution", help="sweep the restitution until the simulated slider acceleration matches "
                                           "a recording (S001's procedure)",
                       description="Simulate the recording's configuration with a coarse-to-fine sweep of "
                                   "contact.restitution and keep the value whose calibrated accelerometer signal "
                                   "(sensor chain and calibration on both sides) is closest (RMS) to the recording's "
                                   "(twin.identification.restitution).")
    r.add_argument("recording", metavar="REC.mcap", help=RECORDING_HELP)
    r.add_argument("--sensor", default="AC6", help="accelerometer compared (default AC6, the slider along the guide)")
    r.add_argument("--start", type=float, default=0.0, metavar="S", help="window start [s] (default 0)")
    r.add_argument("--stop", type=float, default=0.0, metavar="S", help="window end [s] (default 0 = the end)")
    r.add_argument("--engine", choices=("mujoco", "reference"), help="engine of the candidates (default: the "
                                                                      "recording's configuration's)")
    r.add_argument("--parameter", choices=("restitution", "c_max"), default="restitution",
                   help="what to sweep: restitution (hysteresis laws, default) or c_max (the damping of the "
                        "adams-impact law, S001 Table IV)")
    r.add_argument("--grid", metavar="V,V,...", help="coarse grid (default e 0.15,0.20,...,0.95; c_max "
                                                       "5000,7500,...,50000 N s/m)")
    r.add_argument("--fine-step", type=float, default=None, metavar="DV",
                   help="step of the fine grid around the coarse best (default e 0.01, c_max 500 N s/m; "
                        "0 = coarse only)")
    r.add_argument("--lowpass", type=float, default=200.0, metavar="HZ",
                   help="low-pass of the coarse and fine stages' mismatch [Hz] (default 200; 0 = full band)")
    r.add_argument("--max-lag", type=float, default=0.0, metavar="S",
                   help="search a constant time shift up to this many seconds (default 0: none)")
    r.add_argument("--starts", type=int, default=3, metavar="N",
                   help="refine the N best local minima of the coarse grid, each on its own (default 3)")
    r.add_argument("--json", metavar="OUT.json", help="also write the answer and every candidate as JSON")
    # twin.identification.restitution.SweepOptions' names whose option is spelt otherwise
    r.set_defaults(func=_restitution, _field_flags={"coarse": "--grid"})


def _splits(text: str) -> tuple[str, ...]:
    s = tuple(x.strip() for x in text.split(","))
    bad = [x for x in s if x not in ("train", "val", "test")]
    if bad or not s:
        raise TwinError(f"--splits: comma-separated train, val, test; got {text!r}")
    return s


def _train(args: argparse.Namespace) -> int:
    from twin.identification.model import MODEL_SUFFIX
    from twin.identification.training import TrainOptions, train
    from twin.util import check_output_file

    out = check_output_file(args.out, "--out", MODEL_SUFFIX)
    opts = TrainOptions(splits=_splits(args.splits), workers=resolve_workers(args.workers),
                        interval_folds=args.interval_folds, location_only=tuple(args.location_only),
                        size_only_at={"B": tuple(args.b_size_only), "C": tuple(args.c_size_only)},
                        fault_split=tuple(j for j in args.fault_split if j in "BC"))  # "none": no joint
    model, info = train(list(args.dataset), opts)
    model.save(out)
    print(f"{out}: trained on {info['runs']} runs ({info['windows']} windows) of dataset {info['dataset']} "
          f"({info['engine']}); classes {info['classes']}; crank {info['crank_hz_range'][0]:.2f}-"
          f"{info['crank_hz_range'][1]:.2f} Hz; features {info['feature_seconds']:.1f} s, fit {info['fit_seconds']:.1f} s")
    if info["runs_left_out"]:
        print(f"  {len(info['runs_left_out'])} runs left out: {info['runs_left_out'][0]['reason']} ...")
    return 0


def _evaluate(args: argparse.Namespace) -> int:
    from twin.identification.evaluate import evaluate, write_report
    from twin.identification.model import ClearanceModel
    from twin.util import check_output_dir

    out = check_output_dir(args.out, "--out")
    model = ClearanceModel.load(args.model)
    r = evaluate(model, list(args.dataset), _splits(args.splits), resolve_workers(args.workers))
    files = write_report(r, out)
    print(f"{r['runs']} runs of {r['dataset']} ({r['engine']}): accuracy {r['accuracy'] * 100:.1f} %, recall "
          + ", ".join(f"{c} {v * 100:.0f} %" for c, v in r["recall"].items() if v is not None))
    for J, g in r["by_clearance"].items():
        print(f"  size at {J}: interval coverage {g['interval_coverage'] * 100:.0f} %; "
              + ", ".join(f"{c} mm: {v['median_abs_error_mm']:.3g} mm ({'ok' if v['meets_target'] else 'over'})"
                          for c, v in g["values"].items()))
    o = r["outside_training_data"]
    print(f"  outside the training data (warned, intervals widened): {o['runs']} of {r['runs']} runs")
    print(f"  wrote {out}/: {', '.join(files)}")
    return 0


def _recording_and_json(args: argparse.Namespace) -> tuple[Path, Path | None]:
    """The recording argument (an .mcap file) and the checked --json output, before any work."""
    from twin.util import check_output_file

    rec = recording(args.recording)
    if rec.suffix.lower() != ".mcap":
        raise TwinError(f"{rec}: a recording is an .mcap file; convert DAQ exports with 'twin import'")
    return rec, check_output_file(args.json, "--json", ".json") if args.json else None


def _clearance(args: argparse.Namespace) -> int:
    from twin.identification.model import ClearanceModel, identify_recording
    from twin.util import atomic_write_text, check_output_file

    js = check_output_file(args.json, "--json", ".json") if args.json else None
    try:
        rec, _js = _recording_and_json(args)
    except TwinError as err:  # not a recording (another file type, an unknown sample): refused in the --json too
        if js is not None:
            atomic_write_text(js, refusal_json(str(args.recording), str(err)) + "\n")
        raise
    path = resolve_model(args.model)
    if not args.model and not path.is_file():
        raise TwinError(f"no default model in this installation ({path}); give --model MODEL.npz")
    model = ClearanceModel.load(path)
    try:
        a = identify_recording(model, rec)
    except TwinError as err:  # a refusal: the --json file says so too (exit status 2, as every bad input)
        if js is not None:
            atomic_write_text(js, refusal_json(str(args.recording), str(err)) + "\n")
        raise
    p = a.probabilities
    print(f"{args.recording}: fault {a.fault}, probability {p[a.fault]:.2f} (class probabilities: "
          + ", ".join(f"{k} {v:.2f}" for k, v in p.items()) + ")")
    for j in a.joints:
        lo, hi = j.interval_mm
        v = j.size_mm
        held = j.size_held_out
        name, healthy = ("G (slider guide play)", "none (tight guide)") if j.joint == "G" else (j.joint, "none (ball bearing)")
        print(f"  clearance {name}: " + (f"{v:.3g} mm (90 % interval {lo:.3g}-{hi:.3g} mm)" if v > 0 else healthy)
              + (f"; at this speed and orientation the model's sizes held within x{held.within_factor:g} in "
                 f"{held.share * 100:.0f} % of {held.runs} training runs left out" if v > 0 and held else ""))
    ev = a.evidence
    lo_hz, hi_hz = ev.model.crank_hz_range
    print(f"  evidence: {ev.windows} window{'s' if ev.windows != 1 else ''}, {ev.revolutions} crank revolutions, "
          f"{ev.steady_s:.2f} s of steady running at a crank rate of {ev.crank_hz:.3f} Hz")
    print(f"  model: trained on dataset {ev.model.dataset} at crank rates {lo_hz:.2f}-{hi_hz:.2f} Hz; "
          f"identification time {a.seconds:.2f} s")
    if ev.training_data_check.outside_training_data:
        n = sum("extrapolation" in w or "unlike the training data" in w for w in a.warnings)
        print(f"  outside the training data: {n} reason{'s' if n != 1 else ''} (warnings below); the intervals are "
              "widened to every clearance the model was trained on at that joint")
    for w in a.warnings:
        print(f"  WARNING: {w}", file=sys.stderr)
    if js is not None:
        atomic_write_text(js, a.to_json() + "\n")
    return 0


def refusal_json(recording: str, reason: str) -> str:
    """The ``--json`` record of a refused recording: ``refused: true``, the one-line reason, the recording."""
    from twin.util import json_text

    return json_text({"refused": True, "reason": reason, "recording": recording})


def _restitution(args: argparse.Namespace) -> int:
    from twin.identification.restitution import SweepOptions, sweep_restitution
    from twin.util import atomic_write_json

    rec, js = _recording_and_json(args)
    import math

    grid: tuple[float, ...] = ()
    if args.grid is not None:
        try:
            grid = tuple(float(x) for x in args.grid.split(","))
        except ValueError:
            raise TwinError(f"--grid: comma-separated {args.parameter} values, got {args.grid!r}") from None
        if not all(math.isfinite(v) for v in grid):
            raise TwinError(f"--grid: values must be finite numbers, got {args.grid!r}")
    if args.fine_step is not None and not (math.isfinite(args.fine_step) and args.fine_step >= 0):
        raise TwinError(f"--fine-step: must be >= 0 (0 = coarse grid only), got {args.fine_step!r}")
    # the other settings are SweepOptions' to check (one owner: --lowpass >= 0 Hz, --max-lag in [0, 0.5] s)
    opts = SweepOptions(sensor=args.sensor, start_s=args.start, stop_s=args.stop, coarse=grid,
                        fine_step=-1.0 if args.fine_step is None else args.fine_step, engine=args.engine or "", max_lag_s=args.max_lag,
                        lowpass_hz=args.lowpass, parameter=args.parameter, starts=args.starts)
    res = sweep_restitution(rec, opts)
    found = (f"restitution e = {res.value:.3f}" if res.parameter == "restitution"
             else f"c_max = {res.value:.0f} N s/m")
    print(f"{args.recording}: {found} ({res.sensor}, RMS mismatch {res.mismatch_mps2:.2f} m/s^2 of "
          f"{res.recorded_rms_mps2:.1f} m/s^2 recorded, window {res.window_s[0]:.3f}-{res.window_s[1]:.3f} s; "
          f"{res.simulations} {res.engine} runs in {res.seconds:.1f} s)")
    for n in res.notes:
        print(f"  {n}")
    if js is not None:
        atomic_write_json(js, res.to_dict())
        print(f"  wrote {js}")
    return 0
