"""``twin dataset``: synthetic datasets (generate, plan, info, verify); layout in twin/dataset/FORMAT.md."""

from __future__ import annotations

import argparse
import sys
import time

from twin.commands.inputs import SPEC_HELP
from twin.commands.inputs import spec as spec_arg
from twin.errors import TwinError
from twin.util import resolve_workers


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("dataset", help="synthetic datasets: generate, plan, info, verify, list",
                       description="Synthetic datasets of the bench for clearance identification and observers: "
                                   "a TOML spec (a file, or the name of one that ships with twin: tiny, ...) varies "
                                   "clearances, orientation, speed, "
                                   "contact and sensor parameters; runs are simulated on all cores (or a Dask "
                                   "cluster) into Parquet files any ML tool reads.")
    ds = p.add_subparsers(dest="dataset_command", metavar="ACTION", parser_class=type(p))
    ds.required = True

    g = ds.add_parser("generate", help="simulate the runs of a spec into a dataset folder (resumes)",
                      description="Simulate every run of SPEC into --out (or finish an interrupted generation "
                                  "with the same command).")
    g.add_argument("spec", metavar="SPEC.toml", help=SPEC_HELP)
    g.add_argument("--out", metavar="DIR", required=True, help="dataset folder (new, empty, or this spec's)")
    g.add_argument("--workers", type=int, metavar="N",
                   help="runs at a time, on threads or worker processes (default: the number of cores)")
    g.add_argument("--scheduler", metavar="processes|threads|local|ADDRESS",
                   help="'processes': --workers worker processes; 'threads': --workers threads of this process "
                        "(default: threads up to 2 workers, processes beyond; the same files either way); Dask "
                        "distributed: 'local' starts a LocalCluster of --workers processes, tcp://HOST:8786 uses "
                        "a running cluster (workers must see --out); Dask comes with the cluster extra: "
                        "pip install 'twin[cluster]'")
    g.add_argument("--limit", type=int, metavar="K", help="simulate at most K of the missing runs this time")
    g.add_argument("--no-warm-start", action="store_true",
                   help="simulate every run alone (default: the repeats of a design point, which differ in their "
                        "sensor-noise seed only, share one engine run; the files are the same bytes either way)")
    g.add_argument("--approx-warm-start", action="store_true",
                   help="an approximation, off by default: runs that differ only in clearance sizes, contact, "
                        "guide friction, ripple, start angle or sensor mounts share one spin-up and switch to their "
                        "own parameters after it; each file's metadata says from when it holds its own physics "
                        "(docs/datasets.md)")
    g.add_argument("--no-progress", action="store_true", help="no progress bar")
    g.set_defaults(func=_generate, _field_flags={"out_dir": "--out"})  # twin.dataset.generate's argument

    pl = ds.add_parser("plan", help="print the runs of a spec and estimate the time, without writing anything")
    pl.add_argument("spec", metavar="SPEC.toml", help=SPEC_HELP)
    pl.add_argument("--workers", type=int, metavar="N", help="workers of the estimate (default: the cores)")
    pl.add_argument("--show", type=int, default=20, metavar="K", help="runs listed (default 20; 0 = all)")
    pl.add_argument("--no-estimate", action="store_true", help="skip the short timing runs of the estimate")
    pl.set_defaults(func=_plan)

    i = ds.add_parser("info", help="runs by status, class balance per split, channels, the runs with their labels",
                      description="Describe a dataset folder: runs by status, class balance per split, size, "
                                  "channels, and its runs with their ids and labels.")
    i.add_argument("dir", metavar="DIR", help="dataset folder (twin dataset generate --out DIR)")
    i.add_argument("--show", type=int, default=20, metavar="K", help="runs listed (default 20; 0 = all)")
    i.add_argument("--json", nargs="?", const="-", metavar="OUT.json",
                   help="the same as JSON, every run included: alone, printed instead of the text; with a file "
                        "name, written there")
    i.set_defaults(func=_info)

    v = ds.add_parser("verify", help="check every file against the manifest (checksums, lengths, labels)")
    v.add_argument("dir", metavar="DIR", help="dataset folder (twin dataset generate --out DIR)")
    v.add_argument("--no-progress", action="store_true", help="no progress bar")
    v.set_defaults(func=_verify)

    ls = ds.add_parser("list", help="print the names of the dataset specs that ship with twin, one a line",
                       description="Print the names of the dataset specs that ship with twin (what a SPEC "
                                   "argument may name instead of a .toml file), one a line.")
    ls.set_defaults(func=_list)


def _list(args: argparse.Namespace) -> int:
    from twin.samples import spec_names

    print("\n".join(spec_names()))
    return 0


def _generate(args: argparse.Namespace) -> int:
    from twin.dataset.generate import generate
    from twin.dataset.reader import describe
    from twin.dataset.spec import load_spec

    spec = load_spec(spec_arg(args.spec))
    t = time.perf_counter()
    info = generate(spec, args.out, workers=resolve_workers(args.workers), scheduler=args.scheduler, limit=args.limit,
                    progress=not args.no_progress and sys.stderr.isatty(), warm_start=not args.no_warm_start,
                    approx_warm_start=args.approx_warm_start)
    g = info["generation"]
    on = {"processes": "worker processes", "threads": "threads"}.get(g["scheduler"], f"{g['scheduler']} workers")
    shared = g.get("engine_runs_this_call", g["runs_this_call"])
    shared = (f"; {shared} engine run{'s' if shared != 1 else ''}, the repeats sharing theirs"
              if shared < g["runs_this_call"] else "")
    print(f"{args.out}: {g['runs_this_call']} runs simulated ({g['failed_this_call']} failed) on {g['workers']} "
          f"{on} in {time.perf_counter() - t:.1f} s{shared}")
    print(describe(args.out))
    return 0


def _plan(args: argparse.Namespace) -> int:
    from twin.dataset.design import plan
    from twin.dataset.reader import SHOWN_LABELS, format_table
    from twin.dataset.spec import load_spec

    if args.show < 0:
        raise TwinError(f"--show: must be >= 0 (0 = all), got {args.show}")
    workers = resolve_workers(args.workers)
    spec = load_spec(spec_arg(args.spec))
    runs = plan(spec)
    sim = sum(r.config.duration_s for r in runs)
    names = list(dict.fromkeys(k for r in runs for k in r.factors))
    print(f"{spec.name}: {len(runs)} runs ({spec.design} design, {len(runs) // spec.repeats} points x "
          f"{spec.repeats} repeats), {sim:.1f} s simulated, engine {spec.engine}, outputs at "
          f"{spec.outputs.rate_hz:g} Hz")
    counts: dict[tuple[str, str], int] = {}
    for r in runs:
        counts[(r.split, r.labels["fault"])] = counts.get((r.split, r.labels["fault"]), 0) + 1
    for s in ("train", "val", "test"):
        row = {f: counts.get((s, f), 0) for f in ("none", "B", "C", "BC")}
        print(f"  {s:5s}: " + ", ".join(f"{f} {n}" for f, n in row.items()))
    show = runs if args.show == 0 else runs[:args.show]
    # factors that are a label (fault, the clearances) are the label columns already
    names = [k for k in names if k not in SHOWN_LABELS]
    for line in format_table(["index", "run_id", "split", "fault", "B mm", "C mm", *names],
                             [[r.index, r.run_id, r.split, r.labels["fault"], r.labels["clearance_b_mm"],
                               r.labels["clearance_c_mm"], *(_cell(r.factors.get(k)) for k in names)] for r in show]):
        print("  " + line)
    if len(show) < len(runs):
        print(f"  ... {len(runs) - len(show)} more (--show 0 lists all)")
    if not args.no_estimate:
        from twin.dataset.estimate import estimate_wall

        est = estimate_wall(spec, runs, workers)
        shared = f"; {est['engine_runs']} engine runs, the repeats sharing theirs" if est["engine_runs"] < len(runs) else ""
        print(f"  estimated wall time on {workers} workers: {est['wall_s'] / 60:.1f} min "
              f"({est['per_sim_s']:.2f} s per simulated second per worker, measured on {est['probes']} short "
              f"runs; {est['overhead_s']:.2f} s per run of set-up{shared})")
    return 0


def _cell(v):
    """A factor value as a table cell: numbers as they are (formatted by the table), others as text."""
    return v if isinstance(v, (int, float)) and not isinstance(v, bool) else str(v)


def _info(args: argparse.Namespace) -> int:
    from twin.dataset.reader import describe, summary
    from twin.util import atomic_write_json, check_output_file, json_text

    if args.show < 0:
        raise TwinError(f"--show: must be >= 0 (0 = all), got {args.show}")
    # the dataset folder is an input: --json inside it (its info.json, its stats.json) is refused
    js = check_output_file(args.json, "--json", ".json", folders=(args.dir,)) if args.json not in (None, "-") else None
    if args.json == "-":
        print(json_text(summary(args.dir)))  # strict JSON: a missing number is null, never NaN
        return 0
    print(describe(args.dir, show=args.show, all_hint="--show 0 lists all"))
    if js is not None:
        atomic_write_json(js, summary(args.dir))
        print(f"  wrote {js}")
    return 0


def _verify(args: argparse.Namespace) -> int:
    from twin.dataset.reader import Dataset, verify

    problems = verify(args.dir, progress=not args.no_progress and sys.stderr.isatty())
    n = len(Dataset(args.dir).runs)
    if problems:
        for p in problems:
            print(f"  {p}")
        print(f"{args.dir}: {len(problems)} problem(s) in {n} runs", file=sys.stderr)
        return 1
    print(f"{args.dir}: {n} runs, every file matches the manifest")
    return 0
