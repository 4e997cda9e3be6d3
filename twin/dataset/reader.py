"""Reading a dataset for training: the manifest, run signals and windows as numpy arrays.

``ds = twin.dataset.open(DIR)`` gives the manifest (``ds.runs``, a pyarrow table; ``ds.rows()``
as dicts), the normalization statistics of the training split (``ds.stats``), the channels with
units (``ds.channels``) and a window iterator::

    for x, y in ds.windows("train", channels=["meas_AC4", "meas_AC6"], length_s=0.1, normalize=True):
        ...   # x: float32 [channels, samples]; y: labels of the run (fault, clearances, run_id, ...)

Windows are cut from each run in order (``hop_s`` apart, default ``length_s``: no overlap), or one
per crank revolution (``per_revolution=True``, boundaries where the encoder passes a multiple of
a turn; ``samples_per_rev`` resamples each revolution to that many points in the angle domain,
order tracking). No torch: numpy arrays, for any framework. The files themselves need no twin:
pyarrow, pandas, polars, DuckDB and Hugging Face ``datasets`` read them (FORMAT.md).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Iterable, Iterator

import numpy as np

from twin.dataset.generate import READABLE, DatasetError
from twin.dataset.storage import read_columns, read_meta
from twin.util import file_sha256


class Dataset:
    """An opened dataset folder (see module docstring)."""

    def __init__(self, path: str | Path):
        import pyarrow.parquet as pq

        self.path = Path(path)
        info_path = self.path / "info.json"
        if not info_path.is_file():
            raise DatasetError(f"{self.path}: not a dataset folder (no info.json)")
        self.info = _read_json(info_path)
        if not isinstance(self.info, dict):
            raise DatasetError(f"{info_path}: must hold a JSON object, got {type(self.info).__name__}")
        if self.info.get("format") not in READABLE:
            raise DatasetError(f"{info_path}: format {self.info.get('format')!r}, this twin reads "
                               f"{', '.join(READABLE)} (a newer twin's dataset? update twin)")
        check_info(self.info, info_path)
        runs = self.path / "runs.parquet"
        if not runs.is_file():
            raise DatasetError(f"{self.path}: no runs.parquet (generation never finished a call; run it again)")
        try:
            self.runs = pq.read_table(runs)
        except Exception as err:  # noqa: BLE001 - pyarrow raises many kinds on a damaged file: one line
            raise DatasetError(f"{runs}: unreadable ({_one_line(err)})") from None
        check_manifest(self.runs, runs)
        stats = self.path / "stats.json"
        self.stats: dict[str, dict[str, float]] = check_stats(_read_json(stats), stats) if stats.is_file() else {}
        chans = self.info["channels"]
        self.channels = {c["name"]: c for c in chans}
        self.rate_hz = float(chans[0]["rate_hz"]) if chans else 0.0
        #: key and label columns of the data files before the channels (none in twin-dataset/1)
        self.key_columns: list[str] = list(self.info.get("key_columns", []))
        self.label_columns: list[str] = list(self.info.get("label_columns", []))

    def rows(self, split: str | None = None, status: str = "ok") -> list[dict[str, Any]]:
        """Manifest rows (dicts), optionally of one split, by default the runs that succeeded."""
        return [r for r in self.runs.to_pylist() if (split is None or r["split"] == split)
                and (status is None or r["status"] == status)]

    def read(self, run_id: str, channels: Iterable[str] | None = None, start: int = 0,
             stop: int | None = None) -> dict[str, np.ndarray]:
        """Signals of one run (rows [start, stop)): ``channels`` (default: every channel; key and
        label columns may be named too)."""
        f = self.path / "data" / f"{run_id}.parquet"
        if not f.is_file():
            raise DatasetError(f"{self.path}: no data for run {run_id!r}")
        return read_columns(f, list(self.channels) if channels is None else channels, start, stop)

    def _norm(self, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
        missing = [n for n in names if n not in self.stats]
        if missing:
            raise DatasetError(f"no training statistics for {', '.join(missing)} (stats.json)")
        mean = np.array([self.stats[n]["mean"] for n in names], dtype=np.float64)[:, None]
        std = np.array([self.stats[n]["std"] or 1.0 for n in names], dtype=np.float64)[:, None]
        return mean, std

    def windows(self, split: str = "train", channels: Iterable[str] | None = None, *, length_s: float = 0.1,
                hop_s: float | None = None, per_revolution: bool = False, samples_per_rev: int | None = None,
                normalize: bool = False, skip_s: float = 0.0) -> Iterator[tuple[np.ndarray, dict[str, Any]]]:
        """(window [channels, samples] float32, labels) over the runs of ``split`` (module docstring).

        ``skip_s`` leaves out the start of each run (the spin-up). Per-revolution windows need
        ``encoder_counts`` or ``encoder_angle`` in the dataset.
        """
        names = list(channels) if channels is not None else [c for c, d in self.channels.items()
                                                             if d["dtype"].startswith("float")]
        unknown = [n for n in names if n not in self.channels]
        if unknown:
            raise DatasetError(f"unknown channels {', '.join(unknown)}; the dataset has {', '.join(self.channels)}")
        mean, std = self._norm(names) if normalize else (None, None)
        rate = self.rate_hz
        n_win = int(round(length_s * rate))
        hop = int(round((hop_s if hop_s is not None else length_s) * rate))
        if not per_revolution and (n_win < 1 or hop < 1):
            raise DatasetError(f"length_s and hop_s must hold at least one sample at {rate:g} Hz")
        angle = None
        if per_revolution:
            angle = "encoder_counts" if "encoder_counts" in self.channels else \
                "encoder_angle" if "encoder_angle" in self.channels else None
            if angle is None:
                raise DatasetError("per_revolution needs encoder_counts or encoder_angle in the dataset")
        for row in self.rows(split):
            start = int(round(skip_s * rate))
            data = self.read(row["run_id"], names + ([angle] if angle and angle not in names else []), start=start)
            x = np.stack([np.asarray(data[n], dtype=np.float64) for n in names])
            if normalize:
                x = (x - mean) / std
            labels = {k: row[k] for k in ("run_id", "fault", "clearance_b_mm", "clearance_c_mm", "split")}
            if not per_revolution:
                for i in range(0, x.shape[1] - n_win + 1, hop):
                    yield x[:, i:i + n_win].astype(np.float32), {**labels, "start_s": skip_s + i / rate}
                continue
            turns = _turns(np.asarray(data[angle], dtype=np.float64), angle, self)
            edges = revolution_edges(turns)
            for a, b in zip(edges[:-1], edges[1:]):
                w = x[:, a:b]
                if samples_per_rev:
                    grid = np.floor(turns[a]) + (np.arange(samples_per_rev) + 0.5) / samples_per_rev \
                        if turns[b - 1] >= turns[a] else np.ceil(turns[a]) - (np.arange(samples_per_rev) + 0.5) / samples_per_rev
                    tt = turns[a:b]
                    order = np.argsort(tt, kind="stable")
                    w = np.stack([np.interp(grid, tt[order], ch[order]) for ch in w])
                yield w.astype(np.float32), {**labels, "start_s": skip_s + a / rate}


# ---------------------------------------------------------------- schema of the dataset's own files
# Every field the readers (open, info, verify, identify train/evaluate, view --run) rely on is checked
# when a dataset is opened: a file that is well-formed JSON or Parquet but holds other fields, other
# types or other values is refused in one line naming the file and the field, never a traceback later.

#: required ``runs.parquet`` columns and their kind (string, float: any number, int: an integer)
MANIFEST_COLUMNS = {"run_id": "string", "split": "string", "status": "string", "fault": "string",
                    "clearance_b_mm": "float", "clearance_c_mm": "float", "point": "int", "duration_s": "float",
                    "simulated_s": "float", "rows": "int", "bytes": "int", "sha256": "string", "reason": "string",
                    "file": "string"}
#: allowed values of the manifest's categorical columns
MANIFEST_VALUES = {"split": ("train", "val", "test"), "status": ("ok", "failed", "pending"),
                   "fault": ("none", "B", "C", "BC", "G", "BG", "CG", "BCG")}
#: the channel dtypes a data file may hold
CHANNEL_DTYPES = ("float32", "float64", "int32", "int64")


def _one_line(err: BaseException) -> str:
    return " ".join(f"{type(err).__name__}: {err}".split())[:300]


def _read_json(path: Path) -> Any:
    """A JSON file of the dataset (strict: NaN and infinities are not JSON), or one line naming it."""
    def no_constant(name: str) -> Any:
        raise ValueError(f"{name} is not JSON")

    try:
        return json.loads(path.read_bytes().decode("utf-8"), parse_constant=no_constant)
    except (OSError, ValueError, RecursionError) as err:
        raise DatasetError(f"{path}: unreadable ({_one_line(err)})") from None


def _is_num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def check_info(info: dict[str, Any], path: Path) -> None:
    """The fields of ``info.json`` the readers use: their presence, types and values."""
    def bad(field: str, want: str) -> DatasetError:
        got = info.get(field, "missing") if "." not in field else "another value"
        return DatasetError(f"{path}: field {field!r} must be {want}, got {got!r}"[:400])

    if not isinstance(info.get("name"), str):
        raise bad("name", "a string")
    if not isinstance(info.get("complete"), bool):
        raise bad("complete", "true or false")
    runs = info.get("runs")
    if not isinstance(runs, dict) or any(not (isinstance(runs.get(k), int) and not isinstance(runs.get(k), bool)
                                              and runs[k] >= 0) for k in ("planned", "ok", "failed", "pending")):
        raise bad("runs", "an object of counts planned, ok, failed, pending (integers >= 0)")
    chans = info.get("channels")
    if not isinstance(chans, list):
        raise bad("channels", "a list of {name, unit, dtype, rate_hz} objects")
    names = set()
    for k, c in enumerate(chans):
        where = f"channels[{k}]"
        if not isinstance(c, dict):
            raise DatasetError(f"{path}: field {where!r} must be an object {{name, unit, dtype, rate_hz}}")
        for key, ok, want in (("name", lambda v: isinstance(v, str) and v, "a non-empty string"),
                              ("unit", lambda v: isinstance(v, str), "a string"),
                              ("dtype", lambda v: v in CHANNEL_DTYPES, f"one of {', '.join(CHANNEL_DTYPES)}"),
                              ("rate_hz", lambda v: _is_num(v) and v > 0, "a positive number")):
            if not ok(c.get(key)):
                raise DatasetError(f"{path}: field '{where}.{key}' must be {want}, got {c.get(key, 'missing')!r}"[:400])
        if c["name"] in names:
            raise DatasetError(f"{path}: field '{where}.name' repeats the channel {c['name']!r}")
        names.add(c["name"])
        if c["rate_hz"] != chans[0]["rate_hz"]:
            raise DatasetError(f"{path}: field '{where}.rate_hz' differs from the first channel's "
                               f"({c['rate_hz']!r} against {chans[0]['rate_hz']!r}); a dataset has one rate")
    for field in ("key_columns", "label_columns"):
        v = info.get(field, [])
        if not isinstance(v, list) or not all(isinstance(x, str) and x for x in v):
            raise bad(field, "a list of column names")
    if info.get("key_columns") and list(info["key_columns"]) != ["run_id", "t"]:
        raise bad("key_columns", '["run_id", "t"]')
    cpr = info.get("encoder_counts_per_rev")
    if cpr is not None and not (_is_num(cpr) and cpr > 0):
        raise bad("encoder_counts_per_rev", "a positive number or null")
    ident = info.get("identity")
    if not isinstance(ident, dict) or not isinstance(ident.get("engine"), str):
        raise bad("identity", "an object naming the dataset's engine")


def check_manifest(table: Any, path: Path) -> None:
    """The columns of ``runs.parquet`` the readers use (:data:`MANIFEST_COLUMNS`), their types, no
    missing values where one is needed, the categorical values, unique run ids."""
    import pyarrow as pa
    import pyarrow.compute as pc

    for name, kind in MANIFEST_COLUMNS.items():
        if name not in table.column_names:
            raise DatasetError(f"{path}: no column {name!r} (a manifest has {', '.join(MANIFEST_COLUMNS)})")
        t = table.schema.field(name).type
        ok = {"string": pa.types.is_string(t) or pa.types.is_large_string(t),
              "float": pa.types.is_floating(t) or pa.types.is_integer(t),
              "int": pa.types.is_integer(t)}[kind]
        if not ok:
            raise DatasetError(f"{path}: column {name!r} is {t}, must be {kind}")
        col = table.column(name)
        if col.null_count and name not in ("reason", "file", "sha256"):
            raise DatasetError(f"{path}: column {name!r} has {col.null_count} missing values")
        if kind == "float" and len(col):
            x = col.to_numpy(zero_copy_only=False).astype(np.float64)
            if not np.all(np.isfinite(x)) or np.any(x < 0):
                raise DatasetError(f"{path}: column {name!r} must hold finite numbers >= 0")
        if kind == "int" and len(col) and pc.min(col).as_py() < 0:
            raise DatasetError(f"{path}: column {name!r} must hold integers >= 0")
    for name, allowed in MANIFEST_VALUES.items():
        odd = sorted(set(table.column(name).to_pylist()) - set(allowed))
        if odd:
            raise DatasetError(f"{path}: column {name!r} holds {odd[0]!r}; allowed: {', '.join(allowed)}"[:400])
    ids = table.column("run_id").to_pylist()
    if len(set(ids)) != len(ids):
        raise DatasetError(f"{path}: column 'run_id' repeats a run id")
    bad_id = next((i for i in ids if not i or "/" in i or "\\" in i or i in (".", "..") or "\x00" in i), None)
    if bad_id is not None:
        raise DatasetError(f"{path}: column 'run_id' holds {bad_id!r}, not a run id (a file name in data/)")
    ok_rows = [r for r in zip(table.column("status").to_pylist(), table.column("sha256").to_pylist(),
                              table.column("file").to_pylist()) if r[0] == "ok"]
    if any(not isinstance(sha, str) or not isinstance(f, str) for _, sha, f in ok_rows):
        raise DatasetError(f"{path}: columns 'sha256' and 'file' must be given for every ok run")


def check_stats(obj: Any, path: Path) -> dict[str, dict[str, float]]:
    """``stats.json``: ``{"channels": {NAME: {"mean": number, "std": number >= 0, ...}}}``."""
    chans = obj.get("channels") if isinstance(obj, dict) else None
    if not isinstance(chans, dict):
        raise DatasetError(f"{path}: field 'channels' must be an object of per-channel statistics; run generate "
                           "again to rewrite it")
    for name, st in chans.items():
        if not isinstance(st, dict) or not _is_num(st.get("mean")) or not (_is_num(st.get("std")) and st["std"] >= 0):
            raise DatasetError(f"{path}: field 'channels.{name}' must hold a finite mean and std >= 0; run generate "
                               "again to rewrite it"[:400])
    return chans


def revolution_edges(turns: np.ndarray) -> np.ndarray:
    """Sample indices where the crank completes each whole turn (the first sample at or past
    every integer number of turns, in the run's net direction of rotation): jitter of a count
    around a boundary (a crank at rest on it) does not start a new revolution."""
    if turns.size < 2 or turns[-1] == turns[0]:
        return np.zeros(0, dtype=np.int64)
    sign = 1.0 if turns[-1] > turns[0] else -1.0
    run_max = np.maximum.accumulate(sign * turns)  # monotone: the furthest the crank has got
    levels = np.arange(math.floor(run_max[0]) + 1, math.floor(run_max[-1]) + 1)
    return np.searchsorted(run_max, levels, side="left")


def _turns(phi: np.ndarray, kind: str, ds: Dataset) -> np.ndarray:
    if kind == "encoder_counts":
        cpr = _counts_per_rev(ds)
        return phi / cpr
    return phi / (2 * math.pi)


def _counts_per_rev(ds: Dataset) -> float:
    return float(ds.info.get("encoder_counts_per_rev") or 32768)


def open(path: str | Path) -> Dataset:  # noqa: A001 - twin.dataset.open(DIR), like datasets' API
    """Open a dataset folder for reading."""
    import os

    if isinstance(path, bool) or not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path: must be a dataset folder (str or os.PathLike), got {type(path).__name__}")
    return Dataset(path)


# --------------------------------------------------------------------- checks
def verify(path: str | Path, progress: bool = False) -> list[str]:
    """Check every file of a dataset against its manifest: each ok run's file exists, has the
    recorded SHA-256 and size, holds the expected rows and columns with the dataset's metadata,
    and its labels agree with the configuration. Returns the problems (empty: all good)."""
    ds = Dataset(path)
    problems: list[str] = []
    expected_cols = ds.key_columns + ds.label_columns + [c["name"] for c in ds.info["channels"]]
    rows = ds.runs.to_pylist()
    it = rows
    if progress:
        from tqdm import tqdm

        it = tqdm(rows, unit="run", desc="verify", leave=False)
    for r in it:
        rid = r["run_id"]
        f = ds.path / "data" / f"{rid}.parquet"
        if r["status"] != "ok":
            if f.exists():
                problems.append(f"{rid}: status {r['status']} but a data file exists")
            continue
        if not f.is_file():
            problems.append(f"{rid}: data file missing")
            continue
        if f.stat().st_size != r["bytes"]:
            problems.append(f"{rid}: size {f.stat().st_size} bytes, manifest {r['bytes']}")
            continue
        if file_sha256(f) != r["sha256"]:
            problems.append(f"{rid}: SHA-256 differs from the manifest (file changed or corrupt)")
            continue
        import pyarrow.parquet as pq

        meta = read_meta(f)
        pf = pq.ParquetFile(f)
        if pf.metadata.num_rows != r["rows"] or r["rows"] != int(round(r["duration_s"] * ds.rate_hz)):
            problems.append(f"{rid}: {pf.metadata.num_rows} rows, manifest {r['rows']}, expected "
                            f"{int(round(r['duration_s'] * ds.rate_hz))}")
        if pf.schema_arrow.names != expected_cols:
            problems.append(f"{rid}: columns differ from info.json")
        if meta.get("run_id") != rid:
            problems.append(f"{rid}: file metadata names run {meta.get('run_id')!r}")
        if ds.key_columns and pf.schema_arrow.names == expected_cols and pf.metadata.num_rows:
            problems += _check_labels(pf, r, ds, meta)
        fault = ("B" if r["clearance_b_mm"] > 0 else "") + ("C" if r["clearance_c_mm"] > 0 else "") or "none"
        if fault != r["fault"]:
            problems.append(f"{rid}: label fault {r['fault']!r} disagrees with clearances "
                            f"B {r['clearance_b_mm']} C {r['clearance_c_mm']} mm")
    ids = {r["run_id"] for r in rows}
    for f in (ds.path / "data").glob("*.parquet"):
        if f.stem not in ids:
            problems.append(f"{f.name}: not in the manifest")
    return problems


def _check_labels(pf, r: dict[str, Any], ds: Dataset, meta: dict[str, Any]) -> list[str]:
    """The key and label columns of a run file (twin-dataset/2) against its manifest row: every
    row holds the run's id and labels, ``t`` is ``t0 + k / rate_hz``."""
    import pyarrow.compute as pc

    rid, out = r["run_id"], []
    t = pf.read(columns=["t"])["t"].to_numpy()
    t0, rate = float(meta.get("t0", 0.0)), float(meta["rate_hz"])
    if not np.array_equal(t, t0 + np.arange(t.size, dtype=np.float64) / rate):
        out.append(f"{rid}: column t is not t0 + k / rate_hz ({t0:g} s, {rate:g} Hz)")
    tab = pf.read(columns=["run_id"] + ds.label_columns)
    for name in ["run_id"] + ds.label_columns:
        col = tab[name]
        uniq = pc.unique(col).to_pylist()
        want = r.get(name)
        same = len(uniq) == 1 and (uniq[0] == want or (isinstance(want, float) and isinstance(uniq[0], float)
                                                      and math.isnan(want) and math.isnan(uniq[0])))
        if not same:
            out.append(f"{rid}: column {name} holds {uniq[:3]!r}, manifest {want!r}")
    return out


#: label columns the run tables show (``info``, ``plan``); factors that are these are not repeated
SHOWN_LABELS = ("fault", "clearance_b_mm", "clearance_c_mm")


def run_label_names(rows: list[dict[str, Any]]) -> list[str]:
    """The label columns a run table shows: split, fault, the clearances, and every varied factor
    that is not one of them (``factor_fault`` is the fault column already)."""
    factors = [k for k in (rows[0] if rows else {}) if k.startswith("factor_") and k[7:] not in SHOWN_LABELS]
    return ["split", *SHOWN_LABELS, *factors]


def format_table(header: list[str], rows: list[list[Any]]) -> list[str]:
    """Lines of a plain text table: columns as wide as their widest cell, numbers right-aligned
    (4 significant digits), text left-aligned."""
    def cell(v: Any) -> str:
        if v is None or (isinstance(v, float) and math.isnan(v)):
            return "–"
        if isinstance(v, float):
            return f"{v:.4g}"
        return str(v)

    cells = [[cell(v) for v in r] for r in rows]
    numeric = [all(v is None or (isinstance(v, (int, float)) and not isinstance(v, bool)) for v in (r[k] for r in rows))
               for k in range(len(header))]
    widths = [max([len(h)] + [len(r[k]) for r in cells]) for k, h in enumerate(header)]

    def line(vals: list[str]) -> str:
        return "  ".join(v.rjust(w) if num else v.ljust(w) for v, w, num in zip(vals, widths, numeric)).rstrip()

    return [line(header)] + [line(r) for r in cells]


def summary(path: str | Path) -> dict[str, Any]:
    """``twin dataset info --json``: the dataset's name, format, completeness, run counts, size,
    channels, class balance per split, and every run with its id, status and labels."""
    ds = Dataset(path)
    info = ds.info
    rows = ds.runs.to_pylist()
    labels = run_label_names(rows)
    faults = sorted({r["fault"] for r in rows}, key=list(MANIFEST_VALUES["fault"]).index)
    splits = {}
    for s in ("train", "val", "test"):
        rs = [r for r in rows if r["split"] == s]
        if rs:
            splits[s] = {"runs": len(rs), "groups": len({r["point"] for r in rs}),
                         "by_fault": {f: sum(r["fault"] == f for r in rs) for f in faults}}
    return {
        "path": str(ds.path), "name": info["name"], "format": info["format"], "complete": info["complete"],
        "runs_by_status": info["runs"], "simulated_s": sum(r["simulated_s"] for r in rows),
        "bytes": sum(r["bytes"] for r in rows), "rate_hz": ds.rate_hz,
        "channels": [{k: c[k] for k in ("name", "unit", "dtype")} for c in info["channels"]],
        "label_columns": ds.label_columns, "splits": splits,
        "runs": [{"run_id": r["run_id"], "status": r["status"], **{k: _json_value(r.get(k)) for k in labels},
                  **({"reason": r["reason"]} if r["status"] == "failed" else {})} for r in rows],
    }


def _json_value(v: Any) -> Any:
    """NaN (a label a run lacks, e.g. motor_rpm of a speed program) as JSON's null."""
    return None if isinstance(v, float) and math.isnan(v) else v


def describe(path: str | Path, show: int = 20, *, all_hint: str = "show=0 lists all") -> str:
    """``twin dataset info``: runs by status, class balance per split, size, channels, and the
    first ``show`` runs with their ids and labels (0: every run); ``all_hint``: how to list every run, said
    after the runs left out (the command names its flag)."""
    d = summary(path)
    rs = d["runs_by_status"]
    lines = [f"{d['path']}: dataset {d['name']!r} ({d['format']}), "
             f"{'complete' if d['complete'] else 'INCOMPLETE (run generate again to finish)'}",
             f"  runs: {rs['planned']} planned, {rs['ok']} ok, {rs['failed']} failed, {rs['pending']} pending; "
             f"{d['simulated_s']:.1f} s simulated, {d['bytes'] / 1e6:.1f} MB of signals",
             f"  channels ({len(d['channels'])}, {d['rate_hz']:g} Hz): " + ", ".join(c["name"] for c in d["channels"])]
    faults = list(next(iter(d["splits"].values()))["by_fault"]) if d["splits"] else []
    lines += ["  " + x for x in format_table(
        ["split", "runs", "groups", *faults],
        [[s, v["runs"], v["groups"], *v["by_fault"].values()] for s, v in d["splits"].items()])]
    runs = d["runs"] if show == 0 else d["runs"][:show]
    if runs:
        labels = [k for k in runs[0] if k not in ("run_id", "status", "reason")]
        head = {"clearance_b_mm": "B mm", "clearance_c_mm": "C mm"}
        lines.append("  runs (id, status and labels):")
        lines += ["    " + x for x in format_table(
            ["run_id", "status", *(head.get(k, k.removeprefix("factor_")) for k in labels)],
            [[r["run_id"], r["status"], *(r[k] for k in labels)] for r in runs])]
        if len(runs) < len(d["runs"]):
            lines.append(f"    ... {len(d['runs']) - len(runs)} more ({all_hint})")
    failed = [r for r in d["runs"] if r["status"] == "failed"]
    for r in failed[:10]:
        lines.append(f"  failed {r['run_id']}: {r['reason']}")
    return "\n".join(lines)
