"""One command for the scripts of ``analysis/``: what each rebuilds, what it costs, and running them.

    python analysis/run.py --list              every script: name, cost, what it rebuilds (LONG: > 10 min)
    python analysis/run.py NAME [NAME ...]     run the named scripts in turn with the arguments that
                                               rebuild their committed results
    python analysis/run.py NAME -- ARGS        one script with other arguments (its own --help says which)
    python analysis/run.py --unstamped         the results files that carry no version and commit

Names are the script's path under ``analysis/`` without ``.py`` (``s004_report``,
``identify/held_out_plot``). Costs are rough wall times on the project's two-core machine, from the
scripts' own docstrings where they give one (``~`` marks an estimate). A script marked LONG runs
only with ``--long`` beside its name. Every results file a script writes carries the package
version and the git commit (:mod:`twin.provenance`); the files committed before that stamp existed carry
one read from git history (``stamp_history``: the commit that committed the file and the version then),
until a run through this driver rebuilds them with a live stamp.

The study commands (``twin study ...``) write the other folders of ``analysis/results/``
(accuracy, formulations, stability, ...); :data:`STUDY_OUTPUTS` names them with their command.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


@dataclass(frozen=True)
class Script:
    """One script of ``analysis/``.

    Attributes:
        rebuilds: what it writes (paths under ``analysis/results/`` unless said) or prints.
        cost: rough wall time of a run with ``args`` on two cores.
        long: more than about 10 minutes: runs only with ``--long``.
        args: the arguments that rebuild its committed results.
        needs: what must exist before it runs (a generated dataset, a work folder), "" for nothing.
    """

    rebuilds: str
    cost: str
    long: bool = False
    args: tuple[str, ...] = ()
    needs: str = ""


R = "analysis/results"

#: name (path under analysis/ without .py) -> the script
SCRIPTS: dict[str, Script] = {
    # ---- reproductions of the papers
    "s000_report": Script(f"{R}/s000/comparison.json, comparison.md (runs twin study doe into s000_example*/)",
                          "2 min"),
    "s000_impact_law": Script(f"{R}/s000/impact_law.json, impact_law.md", "15 s"),
    "s001_report": Script(f"{R}/s001/: results.json, tables.md, 7 PNG figures", "5 min"),
    "s002_paper_tables": Script(f"{R}/s002/paper_tables.json, paper_tables.md, responses_reconstructed.csv",
                                "2 s"),
    "s002_guide_offset": Script("prints the guide offset fitted to s002/responses_reconstructed.csv", "~10 s"),
    "s002_l27_spec": Script("analysis/datasets/s002_l27.toml, s002_l27_reference.toml (study specs, not results)",
                            "1 s"),
    "s002_placeholders": Script(f"{R}/s002/simulated/placeholders.md", "1 min"),
    "s004_report": Script(f"{R}/s004/: s004.json, slider_*.png, contact_force_05mm.png", "3 min"),
    "s004_cylindrical": Script(f"{R}/s004/cylindrical_law.json, cylindrical_law.md", "1 min"),
    # ---- physics checks (print, figures)
    "contact_table": Script(f"{R}/contact_law/contact_table.json, contact_table.md", "2 min",
                            args=("--out", f"{R}/contact_law")),
    "impact_speeds": Script(f"prints the impact-speed table; {R}/impact_speeds/impact_speeds.png", "1 min",
                            args=("--png", f"{R}/impact_speeds/impact_speeds.png")),
    "preloaded_impacts": Script("prints single impacts under a preload, three laws", "10 s"),
    "peak_accel_convergence": Script("prints peak |AC6| of the 0.5 mm scene against the timestep", "~10 min",
                                     long=True),
    "bushing_representations": Script("prints cost per step and geometric error of the bushing forms", "2 min"),
    "drivetrain_checks": Script("prints the drive train's check figures (both engines)", "~2 min"),
    "guide_checks": Script("prints the guide clearance's check figures (both engines)", "~1 min"),
    "ripple_study": Script(f"{R}/drivetrain_ripple/: ripple.json, ripple_defaults.png, ripple_sensitivity.png",
                           "2 min"),
    "step_study": Script(f"{R}/step_study/step_study.json, step_study.md", "~15 min", long=True),
    "tune_pid": Script("prints the crank PID gains (twin.config.PID's defaults)", "1 min"),
    # ---- speed (print; docs/speed.md)
    "speed_table": Script(f"docs/speed.md's summary table in place; {R}/speed/speed_table.md", "2-4 min"),
    "bench_mujoco": Script("prints µs per step of the MuJoCo twin", "~2 min"),
    "bench_reference": Script("prints the reference engine's speed and compile cost", "~2 min"),
    "bench_drivetrain": Script("prints the drive train's cost per simulated second, both engines", "~3 min"),
    "bench_output": Script("prints the share of a run's wall time each output costs", "~3 min"),
    "bench_preview": Script("prints the MCAP preview topic's size and write time", "~3 min"),
    "bench_startup": Script("prints the start-up time of a twin process", "~1 min"),
    "bench_memory": Script("prints peak memory against simulated duration", "6 min"),
    "bench_threads": Script("prints multi-scene throughput (threads against processes)", "~10 min", long=True),
    "bench_dataset": Script("prints dataset generation speed over workers", "15-20 min", long=True),
    "bench_approx_warm": Script("prints the approximate warm starts' saving on a nuisance spec slice, side by side",
                                "~5-15 min", long=True),
    "warm_approx_check": Script("prints the approximate warm starts' feature distances against the repeat scatter",
                                "~20 min", long=True),
    "s002_force": Script("prints S002's force source against \"law\" and the spatial reference: accuracy, cost",
                         "~10 min", long=True),
    "bench_storage": Script("prints the dataset signal layouts measured (Parquet, Zarr, NPZ, MCAP, HDF5)",
                            "~10 min", long=True),
    "profile_scenes": Script("prints µs per step of each scene's skipped parts", "~2 min"),
    "native_threads": Script("prints the GIL's share during a rollout and two scenes on two threads (bytes checked)",
                             "~1 min"),
    "profile_stages": Script(f"prints where a MuJoCo step goes; {R}/speed/profile_stages.json", "~3 min",
                             args=("--json", f"{R}/speed/profile_stages.json")),
    "stamp_history": Script(f"the stamp read from git history in each unstamped committed file under {R}/ "
                            "(data untouched)", "5 s"),
    "bit_identical": Script("prints (or --save/--against) digests of the outputs a refactoring keeps", "30 s"),
    # ---- identification (analysis/identify/README.md)
    "identify/train_default": Script(f"twin/data/identify_default.npz and {R}/identify/dev*, samples.json "
                                     "(through twin commands)", "150 min", long=True),
    "identify/nuisance_study": Script(f"{R}/identify/nuisance_dev.json", "15 min + 3-10 min per variant",
                                      long=True, needs="a work folder of generated sets (--work)"),
    "identify/slow_b_probe": Script(f"{R}/identify/slow_b_probe.json", "2 min",
                                    needs="nuisance_study's feature cache (--work)"),
    "identify/size_fit_probe": Script("prints the size regressors' variants on the development sets", "3 min",
                                      needs="nuisance_study's feature cache (--work)"),
    "identify/contact_probe": Script("prints whether the features see the contact's parameters", "1 min",
                                     needs="nuisance_study's feature cache (--work)"),
    "identify/held_out_plot": Script(f"{R}/identify/held_out_accuracy.png (and prints its table)", "5 s"),
    "identify/convert_joblib_model": Script(f"a format-3 model file; {R}/identify/model_conversion.json "
                                            "(--report)", "30 s", needs="a format-2 (joblib) model file"),
    "identify/convert_model_ranges": Script(f"a format-4 model file; {R}/identify/ranges_shipped.json", "3 min",
                                            needs="a format-3 model file (argument)"),
    "identify/recording_length": Script(f"{R}/identify/recording_length*.json (--json)", "1 min",
                                        needs="a dataset generated from clearance_id_length*.toml (argument)"),
    "identify/ripple_check": Script(f"{R}/identify/ripple.json", "~3 min"),
    "identify/speed_swing": Script(f"{R}/identify/speed_swing.json", "6 s",
                                   needs="the datasets of analysis/datasets/speed_swing*.toml (arguments; 8 min)"),
    "identify/size_observability": Script(f"{R}/identify/size_observability*.json (--json)", "2 min",
                                          args=("--json", f"{R}/identify/size_observability.json")),
    "identify/start_angle_check": Script(f"{R}/identify/start_angle.json (--json)", "2 min",
                                         args=("--json", f"{R}/identify/start_angle.json")),
    "identify/bench_identify": Script("prints the time to identify a 2 s recording against reading it", "~1 min"),
    "identify/train_bench": Script("WORK/bench_VARIANT.npz, WORK/dev_VARIANT.json (the whole-bench model of B, C and "
                                   "the guide; twin/data/identify_bench.npz by --save)", "66 min of data + 13 min",
                                   long=True, needs="a work folder (--work)"),
    "identify/bench_variants": Script("prints development-set figures of location and size variants on kept "
                                      "features", "~15 min", long=True, needs="a work folder (--work)"),
    "identify/guide_load": Script(f"{R}/identify/guide_load.json (the slider guide's normal force over a turn with y "
                                  "vertical, closed form)", "~10 s"),
    "identify/rigid_rod_check": Script(f"{R}/identify/rigid_rod_check.json (the rigid-rod check on training, "
                                       "development and flexible-structure recordings)", "~20 min", long=True,
                                       needs="a work folder (--work)"),
    "identify/hull_floor": Script("a model file with the hull-floor interval rule on (arguments IN.npz OUT.npz; "
                                  "every array checked unchanged)", "~5 s", needs="a model file (arguments)"),
    "identify/bench_eval": Script(f"{R}/identify/bench_*.json (--out): whole-bench figures through the answer path",
                                  "20 s per 100 runs", needs="a model file and dataset folders (arguments)"),
    "structure_modes": Script("prints the flexible rod's modes against the closed forms (results/structure_modes.txt "
                              "by hand)", "~10 s"),
    "structure_cost": Script("prints flexible / rigid cost per simulated second, test 12, per engine", "~3 min"),
    "structure_stability": Script("prints the flexible structure's stability over random scenes, both engines",
                                  "~5 min"),
    "bench_structure": Script(f"{R}/structure/bench_structure.md (flexible / rigid cost, tests 3, 6, 12, side by "
                              "side)", "~5 min"),
    "profile_flexible": Script("prints where a step of the reference's flexible structure goes, kernel by kernel",
                               "~1 min"),
    "profile_reference_flexible": Script(f"{R}/structure/profile_reference_flexible.md (the reference's flexible "
                                         "step, kernel by kernel, chain and modal rod)", "~2 min"),
    "structure_modal_basis": Script(f"{R}/structure/modal_basis.md (the modal rod's basis against the closed forms)",
                                    "~10 s"),
    "structure_agreement_rod_model": Script(f"{R}/structure/agreement_rod_model.md (MuJoCo against the reference's chain and modal rod, "
                                            "third-octave bands)", "~10 min"),
    "structure_fullspeed": Script(f"{R}/structure/fullspeed.md, .json (the engines at full speed: step convergence, "
                                  "the physical bisection, the slider-mass ensemble)", "~60 min", long=True,
                                  args=("--bisect",)),
    "mujoco_flexible_options": Script("prints MuJoCo stepping options for the flexible structure: cost and output "
                                      "difference", "~2 min"),
    "structure_agreement": Script(f"{R}/structure/agreement.md, .json (third-octave bands, MuJoCo against the "
                                  "reference)", "~10 min"),
    "structure_fig15": Script(f"{R}/structure_fig15/motor (S003 Fig. 15 and §6 rigid against flexible)", "~20 min",
                              long=True),
    "structure_sensitivity": Script(f"{R}/structure/sensitivity.md (which structure placeholder moves which band)",
                                    "~1 min", args=("--runs",)),
    "structure_closure": Script(f"{R}/structure/closure.md (test 3's 10 kHz engine gap against MuJoCo's loop "
                                "closure at C)", "~10 min"),
    "structure_closure_floor": Script(f"{R}/structure/closure_floor.md (test 3's 10 kHz band: output precision, "
                                      "step convergence, the closure's numerical floor)", "~10 min"),
    "mujoco_flexible_pgs": Script(f"{R}/structure/mujoco_flexible_pgs.md (PGS against Newton for the flexible "
                                  "model: convergence, loop-closure residual, penetration)", "~5 min"),
    "structure_solver_bands": Script(f"{R}/structure/solver_bands.md, .json (band energies PGS against Newton against "
                                     "the reference, with the scene's own noise)", "~10 min"),
    "structure_solver_stability": Script(f"{R}/structure/solver_stability.md, .json (the stability campaign's scenes "
                                         "under both solvers)", "~30 min", long=True),
    # ---- calibration
    "restitution_length": Script("analysis/calibration_validation/restitution_length_*.json (which recording "
                                 "length tells the restitution)", "~5 min",
                                 args=("--out", "analysis/calibration_validation/restitution_length_t6_c0.5_e0.39.json")),
    "replay_noise_floor": Script("analysis/calibration_validation_N/replay_noise_floor.json (the replay "
                                 "criterion's floor: noise streams and ±1e-9 offsets of the truth)", "~30 min",
                                 long=True, needs="a validation set's recordings (--set, --work)"),
    "waveform_stage": Script("analysis/calibration_validation_N/waveform_stage.json, .png (the calibration's "
                             "waveform stage from a set's fitted values: errors and the replay criterion)",
                             "~20 min", long=True, needs="a validation set's recordings (--set, --work)"),
    "calibration_walltime": Script("prints the wall time of a two-recording, five-field calibration", "~15 min",
                                   long=True, needs="a work folder (--work)"),
    "calibration_validation": Script("analysis/calibration_validation/truth.json, results.json, table.md (the "
                                     "validation on synthetic recordings: `make`, then `run`)", "~2 h", long=True,
                                     needs="a step and a work folder (make|run --work DIR)"),
}

#: folders of analysis/results/ written by a twin command rather than a script here
STUDY_OUTPUTS: dict[str, str] = {
    "accuracy": "twin study accuracy",
    "contact_law/contact_check.json": "twin check contact",
    "formulations": "twin study formulations",
    "stability": "twin study stability",
    "stability_bench": "twin study stability --bench",
    "s000/s000_example*": "twin study doe (run by s000_report)",
    "s002/taguchi, s002/mcdm_*, s002/simulated": "twin study taguchi / twin study mcdm",
    "s004/continuous_vs_contact*.png": "twin study continuous-contact",
    "threads/bench_threads*.md, speed/*.md": "the printed output of the bench_* scripts, kept by hand",
    "identify/dev*, identify/fresh*": "twin dataset generate + twin identify evaluate (identify/train_default)",
}

#: modules of analysis/ that are not scripts (imported by the scripts or installed as package data)
NOT_SCRIPTS = ("run.py", "datasets/__init__.py")


def script_path(name: str) -> Path:
    return HERE / f"{name}.py"


def all_scripts() -> list[str]:
    """Every script file of analysis/ as a name (what :data:`SCRIPTS` must list)."""
    out = []
    for p in sorted(HERE.rglob("*.py")):
        rel = p.relative_to(HERE).as_posix()
        if rel in NOT_SCRIPTS or "/results/" in f"/{rel}":
            continue
        out.append(rel.removesuffix(".py"))
    return out


def listing() -> str:
    width = max(map(len, SCRIPTS))
    lines = [f"{'script':<{width}}  {'cost':<14}  rebuilds"]
    for name in sorted(SCRIPTS):
        s = SCRIPTS[name]
        cost = s.cost + (" LONG" if s.long else "")
        extra = f"  [needs {s.needs}]" if s.needs else ""
        lines.append(f"{name:<{width}}  {cost:<14}  {s.rebuilds}{extra}")
    lines.append("")
    lines.append("Written by twin commands, not by these scripts:")
    lines += [f"  {R}/{k}: {v}" for k, v in STUDY_OUTPUTS.items()]
    return "\n".join(lines)


def is_stamped(path: Path) -> bool | None:
    """Whether a results file carries the version and commit (:mod:`twin.provenance`; the ``commit``
    and ``version`` keys some scripts wrote before it count too); None for a kind that carries none
    (CSV: read by other programs, stamped through the JSON written beside it; a folder's README.md:
    a page of documentation about the results, not one of them)."""
    import json

    if path.name == "README.md":
        return None

    if path.suffix == ".json":
        try:
            top = json.loads(path.read_text(encoding="utf-8"))
        except ValueError:
            return False
        return isinstance(top, dict) and ("provenance" in top or "commit" in top)
    if path.suffix == ".md":
        lines = [ln for ln in path.read_text(encoding="utf-8").splitlines() if ln.strip()]
        return bool(lines) and (lines[-1].startswith("_Written ") or "commit" in lines[0].lower())
    if path.suffix == ".png":
        from PIL import Image

        with Image.open(path) as im:
            return str(im.info.get("Software", "")).startswith("twin ")
    return None


def unstamped() -> str:
    """The results files of analysis/results/ without a stamp, by folder."""
    from collections import Counter

    files = sorted(p for p in (HERE / "results").rglob("*") if p.is_file())
    state = {p: is_stamped(p) for p in files}
    old = [p for p, s in state.items() if s is False]
    per_dir = Counter(p.parent.relative_to(ROOT).as_posix() for p in old)
    lines = [f"{len(old)} of {sum(s is not None for s in state.values())} results files carry no version and commit "
             f"(write them stamped from their script; {sum(s is None for s in state.values())} CSV files and folder "
             "READMEs carry none by design):"]
    lines += [f"  {d}: {n}" for d, n in sorted(per_dir.items())]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    extra: list[str] = []
    if "--" in argv:
        i = argv.index("--")
        argv, extra = argv[:i], argv[i + 1:]
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="*", metavar="NAME", help="scripts to run (see --list)")
    ap.add_argument("--list", action="store_true", help="list the scripts, their cost and what they rebuild")
    ap.add_argument("--long", action="store_true", help="also run the named scripts marked LONG")
    ap.add_argument("--unstamped", action="store_true", help="list the results files without version and commit")
    args = ap.parse_args(argv)
    if args.unstamped:
        print(unstamped())
        return 0
    if args.list or not args.names:
        print(listing())
        return 0
    unknown = [n for n in args.names if n not in SCRIPTS]
    if unknown:
        print(f"run.py: unknown script {', '.join(unknown)}; allowed: see 'python analysis/run.py --list'",
              file=sys.stderr)
        return 2
    if extra and len(args.names) != 1:
        print("run.py: arguments after -- go to one script; name exactly one", file=sys.stderr)
        return 2
    long = [n for n in args.names if SCRIPTS[n].long]
    if long and not args.long:
        print(f"run.py: {', '.join(long)} {'is' if len(long) == 1 else 'are'} LONG "
              f"({'; '.join(SCRIPTS[n].cost for n in long)}); add --long to run", file=sys.stderr)
        return 2
    for name in args.names:
        s = SCRIPTS[name]
        cmd = [sys.executable, str(script_path(name)), *(extra or s.args)]
        print(f"== {name} ({s.cost}): {' '.join(cmd[1:])}", flush=True)
        t0 = time.perf_counter()
        rc = subprocess.run(cmd, cwd=ROOT, check=False).returncode
        print(f"== {name}: exit {rc} after {time.perf_counter() - t0:.0f} s", flush=True)
        if rc != 0:
            return rc
    return 0


if __name__ == "__main__":
    sys.exit(main())
