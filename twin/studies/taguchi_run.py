"""``twin study taguchi SPEC --out DIR``: an orthogonal-array experiment simulated through the dataset
generator, then the Taguchi analysis of :mod:`twin.studies.taguchi` (S002's L27).

* **SPEC** is a dataset spec (``twin/dataset/spec.py``, a ``list`` design: one point per run of the
  array, in run order) with one more table, ``[taguchi]``:

  - ``factors``: analysis factor name → the spec factor that holds its level (other factors of the
    spec may vary with them: a crank length and its inertia);
  - ``responses``: per run, from the stored channels over t ≥ ``settle_s``: ``max_slider_accel``
    (max |slider_acceleration| [m/s²]), ``rms_slider_accel``, ``max_force_A``/``_B``/``_C`` (max of
    ``fn_J`` [N]), ``max_force`` (over every joint);
  - ``settle_s`` [s] (default 0), ``sn`` (``smaller``, default, or ``larger``), ``interactions``
    (e.g. ``["crank_length_m*clearance_a_mm"]``), ``alpha`` (0.05).

* The design runs through the dataset generator (:func:`twin.dataset.generate.generate`) into
  ``DIR/dataset`` (a second call resumes it); either engine (``base.engine``).

Outputs: ``DIR/responses.csv`` (one row per run: run id, the analysis factors, the responses, the
run's wall time) and what ``twin study taguchi-analyze`` writes from it: ``taguchi.json``,
``report.md``, main-effect and S/N PNGs.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from twin.dataset.spec import DatasetSpec, SpecError, parse_spec, read_spec_toml
from twin.errors import unknown

RESPONSES = ("max_slider_accel", "rms_slider_accel", "max_force_A", "max_force_B", "max_force_C", "max_force")


@dataclasses.dataclass(frozen=True)
class TaguchiSpec:
    """A parsed ``[taguchi]`` table and its dataset spec."""

    dataset: DatasetSpec
    factors: dict[str, str]
    responses: tuple[str, ...]
    settle_s: float = 0.0
    sn: str = "smaller"
    interactions: tuple[str, ...] = ()
    alpha: float = 0.05


def parse_taguchi(data: Mapping[str, Any], source: str = "") -> TaguchiSpec:
    """Validate a spec given as nested dicts: a dataset spec plus ``[taguchi]``."""
    data = dict(data)
    tg = data.pop("taguchi", None)
    if not isinstance(tg, Mapping):
        raise SpecError("taguchi", "a Taguchi study spec needs a [taguchi] table (factors, responses)")
    allowed = ("factors", "responses", "settle_s", "sn", "interactions", "alpha")
    for k in tg:
        if k not in allowed:
            raise SpecError(f"taguchi.{k}", unknown("key", k, allowed))
    ds = parse_spec(data, source)
    if ds.design != "list":
        raise SpecError("design.kind", f"must be \"list\" for a Taguchi study (the array's runs), got {ds.design!r}")
    fac = tg.get("factors")
    names = {f.name for f in ds.factors} | {k for p in ds.points for k in p}
    if not (isinstance(fac, Mapping) and fac and all(isinstance(v, str) for v in fac.values())):
        raise SpecError("taguchi.factors", "must be a table: analysis factor name = the spec factor it reads")
    for k, v in fac.items():
        if v not in names:
            raise SpecError(f"taguchi.factors.{k}", f"{v!r} is not a factor of the design ({', '.join(sorted(names))})")
    resp = tg.get("responses")
    if not (isinstance(resp, list) and resp and all(r in RESPONSES for r in resp)):
        raise SpecError("taguchi.responses", f"must be a non-empty list of {', '.join(RESPONSES)}; got {resp!r}")
    settle = tg.get("settle_s", 0.0)
    if not (isinstance(settle, (int, float)) and 0 <= settle < ds.duration_s):
        raise SpecError("taguchi.settle_s", f"must lie in [0, base.duration_s = {ds.duration_s:g}) s, got {settle!r}")
    sn = tg.get("sn", "smaller")
    if sn not in ("smaller", "larger"):
        raise SpecError("taguchi.sn", f"must be smaller or larger, got {sn!r}")
    inter = tg.get("interactions", [])
    if not (isinstance(inter, list) and all(isinstance(i, str) for i in inter)):
        raise SpecError("taguchi.interactions", f"must be a list of A*B strings, got {inter!r}")
    alpha = tg.get("alpha", 0.05)
    if not (isinstance(alpha, (int, float)) and 0 < alpha < 1):
        raise SpecError("taguchi.alpha", f"must lie in (0, 1), got {alpha!r}")
    return TaguchiSpec(ds, dict(fac), tuple(resp), float(settle), sn, tuple(inter), float(alpha))


def load_taguchi(path: str | Path) -> TaguchiSpec:
    """Read a Taguchi study spec file (one-line errors naming the file or key)."""
    p = Path(path)
    spec = parse_taguchi(read_spec_toml(p, "a Taguchi study spec"), source=str(p))
    if spec.dataset.base_config is not None and not Path(spec.dataset.base_config).is_absolute():
        spec = dataclasses.replace(spec, dataset=dataclasses.replace(
            spec.dataset, base_config=str(p.parent / spec.dataset.base_config)))
    return spec


def preflight(spec: TaguchiSpec) -> list[Any]:
    """Everything about ``spec`` that can be known without simulating, checked before the first run (one
    line naming the key otherwise): every analysis factor holds a finite number in every run of the design and
    at least two levels, the interactions name pairs of analysis factors, the design is an orthogonal array for
    those terms (the analysis's own checks, on the planned levels), the stored channels hold what every response
    reads (the group ``slider_accel`` for the slider responses, ``joints`` and a clearance at the joint for the
    forces). Returns the planned runs."""
    from twin.dataset.design import plan
    from twin.studies.taguchi import TableError, anova, level_index, parse_interactions

    runs = plan(spec.dataset)
    names = list(spec.factors)
    cols = []
    for k, v in spec.factors.items():
        vals = [r.factors.get(v) for r in runs]
        odd = next((x for x in vals if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x)),
                   None) if vals else None
        if odd is not None or not vals:
            raise SpecError(f"taguchi.factors.{k}", f"{v!r} must hold a finite number in every run of the design, "
                                                   f"got {odd!r}")
        try:
            cols.append(level_index(vals, k)[0])
        except TableError as err:
            raise SpecError(f"taguchi.factors.{k}", str(err).split(": ", 1)[-1]) from None
    try:
        inter = parse_interactions(",".join(spec.interactions), names)
    except TableError as err:
        raise SpecError("taguchi.interactions", str(err).split(": ", 1)[-1]) from None
    try:
        anova(np.column_stack(cols), np.arange(len(runs), dtype=float), names, inter)
    except TableError as err:
        raise SpecError("taguchi.factors", str(err).split(": ", 1)[-1]) from None
    truth = set(spec.dataset.outputs.truth)
    for resp in spec.responses:
        if resp.endswith("slider_accel") and "slider_accel" not in truth:
            raise SpecError("taguchi.responses", f"{resp} needs the channel group slider_accel in outputs.truth")
        if resp.startswith("max_force"):
            if "joints" not in truth:
                raise SpecError("taguchi.responses", f"{resp} needs the channel group joints in outputs.truth")
            joint = resp[-1] if resp != "max_force" else None
            bare = next((r for r in runs if (joint not in r.config.joints.clearance_joints if joint
                                             else not r.config.joints.clearance_joints)), None)
            if bare is not None:
                raise SpecError("taguchi.responses", f"{resp} needs a clearance at "
                                f"{'joint ' + joint if joint else 'some joint'} in every run; run {bare.index} "
                                f"({bare.factors}) has none"[:400])
    return runs


def run_responses(path: Path, rate_hz: float, settle_s: float, names: tuple[str, ...]) -> dict[str, float]:
    """The responses of one stored run (``data/<run_id>.parquet``) over t >= settle_s."""
    import pyarrow.parquet as pq

    cols = pq.read_schema(path).names
    want = [c for c in cols if c == "slider_acceleration" or c.startswith("fn_")]
    tab = pq.read_table(path, columns=want)
    i0 = int(math.ceil(settle_s * rate_hz - 1e-9))
    col = {c: np.asarray(tab.column(c).to_numpy(zero_copy_only=False), float)[i0:] for c in tab.column_names}
    out = {}
    for r in names:
        if r in ("max_slider_accel", "rms_slider_accel"):
            if "slider_acceleration" not in col:
                raise SpecError("taguchi.responses", f"{r} needs the channel group slider_accel in outputs.truth")
            a = col["slider_acceleration"]
            out[r] = float(np.max(np.abs(a))) if r.startswith("max") else float(np.sqrt(np.mean(a * a)))
        elif r == "max_force":
            fn = [float(np.max(v)) for k, v in col.items() if k.startswith("fn_")]
            out[r] = max(fn) if fn else 0.0
        else:
            key = "fn_" + r[-1]
            if key not in col:
                raise SpecError("taguchi.responses", f"{r} needs joint {r[-1]} with a clearance and the group "
                                                     "joints in outputs.truth")
            out[r] = float(np.max(col[key]))
    return out


def simulate(spec: TaguchiSpec, out: Path, workers: int | None, progress: bool) -> list[dict[str, Any]]:
    """Generate the design into ``out`` (resumes); per run: id, analysis factors, responses, wall time."""
    from twin.dataset.design import plan
    from twin.dataset.generate import generate
    from twin.errors import TwinError

    generate(spec.dataset, out, workers=workers, progress=progress)
    rows = []
    for r in plan(spec.dataset):
        res = json.loads((out / "results" / f"{r.run_id}.json").read_text())
        if res["status"] != "ok":
            raise TwinError(f"Taguchi run {r.run_id} ({r.factors}) failed: {res.get('reason')}")
        resp = run_responses(out / "data" / f"{r.run_id}.parquet", spec.dataset.outputs.rate_hz, spec.settle_s,
                             spec.responses)
        rows.append({"run_id": r.run_id, **{k: r.factors[v] for k, v in spec.factors.items()}, **resp,
                     "wall_s": res.get("wall_s")})
    return rows


def responses_csv(rows: list[dict[str, Any]]) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    return buf.getvalue()


@dataclasses.dataclass(frozen=True)
class TaguchiRunOptions:
    """What :func:`run_study` simulates and analyses.

    Attributes:
        spec: the study spec (:func:`load_taguchi`); :func:`preflight` checks it here, before the
            first simulation.
        out: output folder (created; the design is generated into ``out/dataset``, resumed by a second call).
        workers: simulations at a time (None = the machine's cores; else 1..1024).
        progress: a progress bar on stderr.
    """

    spec: TaguchiSpec
    out: str | Path
    workers: int | None = None
    progress: bool = False

    def __post_init__(self) -> None:
        from twin.util import resolve_workers

        preflight(self.spec)  # every check that needs no simulation, before the first one
        if self.workers is not None:
            resolve_workers(self.workers)


@dataclasses.dataclass(frozen=True)
class TaguchiRunResult:
    """The experiment: per run its analysis factors, responses and wall time (``responses.csv``),
    the simulations' wall time [s] and the Taguchi analysis of the responses."""

    runs: list[dict[str, Any]]
    wall_s: float
    analysis: Any  # twin.studies.taguchi.TaguchiResult

    def to_dict(self) -> dict[str, Any]:
        """The JSON data of ``taguchi.json`` (the analysis; the runs are ``responses.csv``)."""
        return self.analysis.to_dict()


def run_study(options: TaguchiRunOptions) -> TaguchiRunResult:
    """Simulate the design into ``out/dataset``, write ``out/responses.csv``, then analyse it as
    :func:`twin.studies.taguchi.run_study` does (``taguchi.json``, ``report.md``, PNGs in ``out``)."""
    import time

    from twin.studies import taguchi
    from twin.util import atomic_write_text

    spec, out = options.spec, Path(options.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    rows = simulate(spec, out / "dataset", options.workers, options.progress)
    wall = time.perf_counter() - t0
    atomic_write_text(out / "responses.csv", responses_csv(rows))
    analysis = taguchi.run_study(taguchi.TaguchiOptions(
        out / "responses.csv", ",".join(spec.responses), ",".join(spec.factors), out, sn=spec.sn,
        interactions=",".join(spec.interactions) or None, alpha=spec.alpha))
    return TaguchiRunResult(rows, wall, analysis)
