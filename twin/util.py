"""Small shared helpers: atomic file writes."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from twin.errors import TwinError


def json_default(o: Any) -> Any:
    """``json.dumps(default=...)`` for numpy scalars and arrays and paths."""
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serializable: {type(o).__name__}")


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to a temporary file beside ``path`` and rename it into place."""
    p = Path(path)
    if not p.parent.exists():
        raise TwinError(f"{p}: directory {p.parent} does not exist")
    tmp = p.with_name(f".{p.name}.{os.getpid()}.tmp")
    try:
        tmp.write_bytes(data)
        os.replace(tmp, p)
    finally:
        tmp.unlink(missing_ok=True)
    return p


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Text version of :func:`atomic_write_bytes` (UTF-8)."""
    return atomic_write_bytes(path, text.encode())


def atomic_write_json(path: str | Path, obj: Any) -> Path:
    """Pretty JSON, written atomically."""
    return atomic_write_text(path, json.dumps(obj, indent=2, sort_keys=False) + "\n")


def check_out_dir(path: str | Path, flag: str = "--out", need_parent: bool = True) -> Path:
    """An output directory given on the command line: it may exist (as a directory) or be
    created (in an existing parent unless ``need_parent`` is False, for callers that create
    parents). Raises TwinError naming ``flag`` otherwise."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise TwinError(f"{flag}: {out} exists and is not a directory")
    if need_parent and not out.parent.exists():
        raise TwinError(f"{flag}: parent directory {out.parent} does not exist")
    return out
