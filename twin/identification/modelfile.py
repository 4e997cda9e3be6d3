"""The identification model's file: a NumPy ``.npz`` archive of plain arrays and one JSON text (the
format is described in :mod:`twin.identification.model`), written deterministically (fixed member order
and timestamps) and read without running anything from the file: no pickle, ``allow_pickle=False``,
every member's CRC checked before use, sizes bounded, the trees checked by
:class:`twin.identification.trees.TreeEnsemble`. Every refusal is one line naming the file."""

from __future__ import annotations

import json
import zipfile
import zlib
from io import BytesIO
from pathlib import Path
from typing import Any

import numpy as np

from twin.identification.trees import ARRAYS, ModelError, TreeEnsemble

MAX_MODEL_BYTES = 256 << 20  # a model file's size, and its members' unpacked sizes together, at most [B]
ZIP_MAGIC = b"PK\x03\x04"
_PICKLE = "never unpickled, as unpickling can run code"


def _is_pickle(head: bytes | None) -> bool:
    """Whether bytes begin as a pickle of protocol 2-5 does (the PROTO opcode and its number)."""
    return head is not None and head[:1] == b"\x80" and head[1:2] in (b"\x02", b"\x03", b"\x04", b"\x05")


def _zlib_head(data: bytes) -> bytes | None:
    """The first bytes a zlib stream at the start of ``data`` unpacks to (RFC 1950: 0x78 for deflate with
    a 32 KiB window, no preset dictionary, a header that is a multiple of 31), or None where it is not one.
    Only decompressed, never unpickled."""
    if len(data) < 2 or data[0] != 0x78 or data[1] & 0x20 or (data[0] << 8 | data[1]) % 31:
        return None
    try:
        return zlib.decompressobj().decompress(data[:4096], 16)
    except zlib.error:
        return None


# what a file that is not a zip archive most likely is, by its first bytes (for the refusal's message)
_NOT_ZIP = ((_is_pickle, f"a pickle file (as joblib and pickle write), {_PICKLE}"),
            (lambda d: _is_pickle(_zlib_head(d)), f"a zlib-compressed joblib pickle, {_PICKLE}"),
            (lambda d: _zlib_head(d) is not None, "a zlib stream"),
            (lambda d: d.startswith(b"\x1f\x8b"), f"a gzip file (a compressed joblib pickle?), {_PICKLE}"),
            (lambda d: d.startswith(b"BZh"), f"a bz2 file (a compressed joblib pickle?), {_PICKLE}"),
            (lambda d: d.startswith(b"\xfd7zXZ"), f"an xz file (a compressed joblib pickle?), {_PICKLE}"),
            (lambda d: d.startswith(b"\x93NUMPY"), "a single .npy array"))
_DATE = (1980, 1, 1, 0, 0, 0)  # members' timestamp: the same model gives the same bytes


def _one_line(err: BaseException) -> str:
    return " ".join((str(err) if isinstance(err, ModelError) else f"{type(err).__name__}: {err}").split())


def write_model(path: str | Path, meta: dict[str, Any], estimators: dict[str, TreeEnsemble]) -> Path:
    """Write ``model.json`` (``meta`` as JSON) and each estimator's arrays as ``NAME.ARRAY`` members,
    atomically (a temporary file renamed into place)."""
    from twin.util import atomic_write_bytes, json_default

    members = {"model.json": np.array(json.dumps(meta, default=json_default))}  # the loader refuses NaN
    for name, e in estimators.items():
        members.update({f"{name}.{k}": a for k, a in e.arrays().items()})
    buf = BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as z:
        for name, a in members.items():
            b = BytesIO()
            np.lib.format.write_array(b, np.asarray(a, order="C"), allow_pickle=False)
            info = zipfile.ZipInfo(f"{name}.npy", date_time=_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(info, b.getvalue())
    return atomic_write_bytes(path, buf.getvalue())


def read_model(path: Path, fmt: str | dict[str, Any], estimators: tuple[str, ...] = ()
               ) -> tuple[dict[str, Any], dict[str, TreeEnsemble]]:
    """The metadata and estimators of a model file of format ``fmt`` holding ``estimators``; refuses
    anything else in one line (module docstring). ``fmt`` may also map each readable format to its estimators,
    or to a function of the file's metadata giving them (a format whose estimators the file lists)."""
    formats = fmt if isinstance(fmt, dict) else {fmt: estimators}
    fmt = " or ".join(formats)
    p = Path(path)
    if not p.is_file():
        raise ModelError(f"{p}: no such model file")
    no = f"{p}: not a readable identification model"
    what = f"a model file is a {fmt} .npz archive of plain arrays and JSON"
    if p.stat().st_size > MAX_MODEL_BYTES:
        raise ModelError(f"{no} ({p.stat().st_size} bytes, over {MAX_MODEL_BYTES}; {what})")
    data = p.read_bytes()
    if not data.startswith(ZIP_MAGIC):
        kind = next((k for is_it, k in _NOT_ZIP if is_it(data)), "not a zip archive")
        raise ModelError(f"{no} ({kind}; {what}: retrain it with 'twin identify train')")
    try:
        z = zipfile.ZipFile(BytesIO(data))
        infos = z.infolist()
        names = [i.filename for i in infos]
        if len(set(names)) != len(names):
            raise ModelError(f"{no} (a member name repeats; {what})")
        if sum(i.file_size for i in infos) > MAX_MODEL_BYTES:
            raise ModelError(f"{no} (its members unpack to over {MAX_MODEL_BYTES} bytes; {what})")
        bad = z.testzip()
        if bad is not None:
            raise ModelError(f"{no} (damaged: member {bad} fails its CRC check)")
        if "model.json.npy" not in names:
            raise ModelError(f"{no} (no model.json member; {what})")
        npz = np.load(BytesIO(data), allow_pickle=False)
        js = npz["model.json"]
        if js.dtype.kind != "U" or js.ndim != 0:
            raise ModelError(f"{no} (model.json is a {js.dtype} array of shape {js.shape}, not a text; {what})")
        meta = json.loads(str(js[()]))
    except ModelError:
        raise
    except Exception as err:  # noqa: BLE001 - a damaged or foreign archive, whatever broke: one line
        raise ModelError(f"{no} ({_one_line(err)})") from None
    found = meta.get("format") if isinstance(meta, dict) else None
    if found not in formats:
        raise ModelError(f"{p}: a model of format {found!r}, this twin reads {fmt!r}; retrain it with "
                         "'twin identify train'")
    estimators = formats[found]
    if callable(estimators):
        try:
            estimators = tuple(estimators(meta))
        except (KeyError, TypeError, ValueError) as err:
            raise ModelError(f"{no} (its estimators: {_one_line(err)})") from None
    want = {"model.json"} | {f"{e}.{k}" for e in estimators for k in ARRAYS}
    if set(npz.files) != want:
        odd = sorted(set(npz.files) ^ want)
        raise ModelError(f"{no} (members {', '.join(odd[:4])}{' ...' if len(odd) > 4 else ''} missing or "
                         f"unexpected; {what})")
    out: dict[str, TreeEnsemble] = {}
    for e in estimators:
        arrays = {}
        for k in ARRAYS:
            try:
                arrays[k] = npz[f"{e}.{k}"]
            except Exception as err:  # noqa: BLE001 - object arrays (never unpickled), damaged headers
                raise ModelError(f"{no} (member {e}.{k} is not a plain array: {_one_line(err)})") from None
        try:
            m = meta.get("estimators", {})[e]
            if not isinstance(m, dict):
                raise TypeError(f"estimators.{e} is not an object")
            out[e] = TreeEnsemble.from_file(m, arrays)
        except (ModelError, KeyError, TypeError, AttributeError) as err:
            raise ModelError(f"{no} (estimator {e}: {_one_line(err)})") from None
    return meta, out
