"""What the identification model reads: a bench recording's calibrated accelerations and encoder counts, the same
made from a simulated run, and the window features of a dataset's runs, one dataset or several pooled.

Every function returns the accelerations as a dict sensor name (``"AC1"`` ... ``"AC6"``) -> array [n] of
calibrated accelerations [m/s²], the encoder counts as an array [n] [counts], the sample rate [Hz] and the
encoder's counts per crank turn; window features are arrays [windows, features]
(:mod:`twin.identification.features`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from twin.identification.features import REVS_PER_WINDOW, IdentifyError, features
from twin.identification.trees import ModelError


# ----------------------------------------------------------------- a recording
def recording_inputs(path: str | Path) -> tuple[dict[str, np.ndarray], np.ndarray, float, float, Any]:
    """Calibrated accelerations, encoder counts, rate, counts per turn and configuration of a bench
    recording (any recording ``twin replay`` accepts)."""
    from twin.instrument.calibration import measured_accel
    from twin.mcapfile import read_metadata
    from twin.recording import RECORDING_RECORD, read_recording

    records = read_metadata(Path(path))
    if RECORDING_RECORD not in records and "twin.config" in records:
        # a run file of twin simulate: the engine's own signals, without the sensor chain's response, noise, DAQ
        # and the static calibration the model was trained through; answering it would claim what it is not
        raise IdentifyError(f"{path}: a run file of 'twin simulate' (the engine's signals, not what the bench's "
                            "sensors and DAQ record); make a bench recording of the configuration with 'twin record' "
                            "(twin.record) and identify that")
    rec, info, _ = read_recording(path)
    if "encoder_counts" not in rec:
        raise IdentifyError(f"{path}: the recording has no encoder_counts channel")
    if info.calibration is None:
        raise IdentifyError(f"{path}: no calibration data; import it again with a static recording in the "
                            "calibration pose or the six sensors' known zero-g offsets")
    meas = measured_accel(rec, info.calibration)
    acc = {k[5:]: np.asarray(v.data) for k, v in meas.channels.items()}
    cfg = rec.config
    cpr = float(cfg.instrumentation.encoder_counts_per_rev) if cfg else 32768.0
    return acc, np.asarray(rec["encoder_counts"]), rec.rate_hz, cpr, cfg


def simulated_inputs(run: Any, cfg: Any) -> tuple[dict[str, np.ndarray], np.ndarray, float, float]:
    """What :func:`recording_inputs` reads from a recording, made from a simulated ``run`` of ``cfg``
    (channels accel and encoder): the bench's sensor chain (``cfg.instrumentation``: sensor response,
    noise, DAQ, encoder counts) and the static calibration it would get. Returns the calibrated
    accelerations, encoder counts, rate and counts per turn."""
    from twin.instrument.calibration import measured_accel
    from twin.instrument.chain import apply_chain, simulated_calibration

    daq = apply_chain(run, cfg, command=False)
    meas = measured_accel(daq, simulated_calibration(cfg))
    acc = {k[5:]: np.asarray(v.data, float) for k, v in meas.channels.items()}
    return acc, np.asarray(daq["encoder_counts"], float), daq.rate_hz, float(cfg.instrumentation.encoder_counts_per_rev)



# ----------------------------------------------------------------- a dataset's runs
def run_features(path: str, skip_s: float, counts_per_rev: float, orientation: str = "y",
                 hop_revs: float = REVS_PER_WINDOW) -> tuple[np.ndarray, float, dict[str, Any]] | str:
    """Window features of one dataset run file (windows ending every ``hop_revs`` turns:
    :func:`twin.identification.features.steady_windows`), its crank rate [Hz] and its measures
    (:func:`twin.identification.ranges.recording_measures`), or the reason it has none."""
    from twin.identification.ranges import recording_measures

    from twin.dataset.storage import read_columns, read_meta, valid_from_s

    meta = read_meta(path)
    cols = read_columns(path, [f"meas_{s}" for s in ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6")] + ["encoder_counts"])
    acc = {k[5:]: v for k, v in cols.items() if k.startswith("meas_")}
    skip_s = max(skip_s, valid_from_s(meta))  # an approximate warm start: its own physics from then on
    try:
        X, w = features(acc, cols["encoder_counts"], float(meta["rate_hz"]), counts_per_rev, skip_s, orientation,
                        hop_revs=hop_revs)
    except IdentifyError as err:
        return str(err)
    return X, w.crank_hz, recording_measures(acc, cols["encoder_counts"], float(meta["rate_hz"]), counts_per_rev, w)


def dataset_features(ds, splits: tuple[str, ...], workers: int = 1, hop_revs: float = REVS_PER_WINDOW
                     ) -> tuple[np.ndarray, list[dict[str, Any]], list[int], list[dict[str, Any]]]:
    """Features of every ok run of ``splits`` (windows ending every ``hop_revs`` turns): (X [windows, features],
    run rows, window -> row index, runs left out with their reason)."""
    needed = [f"meas_AC{i}" for i in range(1, 7)] + ["encoder_counts"]
    missing = [c for c in needed if c not in ds.channels]
    if missing:
        raise ModelError(f"{ds.path}: the dataset lacks {', '.join(missing)} (a dataset for identification needs "
                         "outputs.instrumented with counts and calibrated)")
    cpr = float(ds.info.get("encoder_counts_per_rev") or 32768)
    rows = [r for r in ds.rows() if r["split"] in splits]
    if not rows:
        raise ModelError(f"{ds.path}: no finished runs in the split(s) {', '.join(splits)}")
    paths = [str(ds.path / r["file"]) for r in rows]
    results = []
    if workers > 1:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn")) as ex:
            results = list(ex.map(run_features, paths, [0.0] * len(paths), [cpr] * len(paths),
                                  [r["orientation"] for r in rows], [hop_revs] * len(paths), chunksize=4))
    else:
        results = [run_features(p, 0.0, cpr, r["orientation"], hop_revs) for p, r in zip(paths, rows)]
    X, kept, owner, skipped = [], [], [], []
    for r, res in zip(rows, results):
        if isinstance(res, str):
            skipped.append({"run_id": r["run_id"], "reason": res})
            continue
        Xr, hz, measures = res
        r = dict(r, crank_hz=hz, measures=measures)
        owner += [len(kept)] * len(Xr)
        kept.append(r)
        X.append(Xr)
    if not X:
        raise ModelError(f"{ds.path}: no run has {REVS_PER_WINDOW} steady crank revolutions to identify")
    return np.concatenate(X), kept, owner, skipped


def pooled_features(dataset_dirs: list[str | Path], splits: tuple[str, ...], workers: int,
                    hop_revs: float = REVS_PER_WINDOW
                    ) -> tuple[np.ndarray, list[dict[str, Any]], list[int], list[dict[str, Any]], list[Any]]:
    """Features of several datasets pooled (runs keep their rows, with the dataset's name; windows ending every
    ``hop_revs`` turns, :func:`twin.identification.features.steady_windows`); the
    datasets must agree on sample rate and encoder resolution (checked before any feature is computed).
    They may come from different engines: the engines' contact laws differ as a bench's differs from both,
    and a model trained on both spans that difference as one more nuisance."""
    from twin.dataset import open as open_dataset

    dss = [open_dataset(d) for d in dataset_dirs]
    _check_poolable(dss)
    parts = []
    for ds in dss:
        X, r, o, sk = dataset_features(ds, splits, workers, hop_revs)
        parts.append((X, [dict(x, dataset=ds.info["name"]) for x in r], o, sk, [ds]))
    return pool_features(parts)


def pool_features(parts: list[tuple]) -> tuple[np.ndarray, list[dict[str, Any]], list[int], list[dict[str, Any]],
                                               list[Any]]:
    """Pool what :func:`pooled_features` returns for datasets taken one by one (e.g. features computed
    before and kept): rows and windows concatenated, each window's run index shifted; the datasets must
    agree as :func:`pooled_features` requires."""
    _check_poolable([ds for part in parts for ds in part[4]])
    Xs, rows, owner, skipped, dss = [], [], [], [], []
    for X, r, o, sk, d in parts:
        owner += [len(rows) + int(i) for i in o]
        rows += r
        Xs.append(X)
        skipped += sk
        dss += d
    return np.concatenate(Xs), rows, owner, skipped, dss


def _check_poolable(dss: list[Any]) -> None:
    """Raise ModelError unless the datasets agree on sample rate and encoder resolution (not the engine:
    :func:`pooled_features`)."""
    first = None
    for ds in dss:
        key = {"rate_hz": ds.rate_hz,
               "encoder_counts_per_rev": float(ds.info.get("encoder_counts_per_rev") or 32768)}
        if first is None:
            first = (ds.path, key)
            continue
        for k, v in key.items():
            if v != first[1][k]:
                raise ModelError(f"{ds.path}: {k} is {v!r}, {first[0]} has {first[1][k]!r}: datasets pooled together "
                                 "must agree on sample rate and encoder resolution")


