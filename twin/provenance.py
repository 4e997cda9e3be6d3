"""Provenance of a results file: the package version and the git commit that wrote it.

The scripts of ``analysis/`` (and anything else that writes a result a reader should be able to
trace) stamp what they write with these helpers:

* JSON: :func:`stamped` adds ``"provenance": {"twin_version", "git_commit", "script"}`` to the
  top-level object;
* Markdown or other text a person reads: :func:`stamp_line` is one line to put at its end
  (:func:`with_stamp_line` appends it);
* PNG figures: ``fig.savefig(path, metadata=figure_metadata())`` writes the stamp into the PNG's
  ``Software`` text chunk (``PIL.Image.open(path).info["Software"]`` reads it back).

The commit is ``git describe --always --dirty`` of the checkout the package was imported from
(``unknown`` when it is not a checkout, e.g. an installed wheel); ``-dirty`` says the working tree
held uncommitted changes when the file was written.
"""

from __future__ import annotations

import functools
import subprocess
import sys
from pathlib import Path
from typing import Any

from twin import __version__

#: the key :func:`stamped` adds to a JSON object
PROVENANCE_KEY = "provenance"


@functools.lru_cache(maxsize=1)
def git_commit() -> str:
    """``git describe --always --dirty`` of the checkout holding the package, or ``"unknown"``."""
    here = Path(__file__).resolve().parent
    try:
        out = subprocess.run(["git", "describe", "--always", "--dirty", "--abbrev=12"], capture_output=True,
                             text=True, cwd=here, timeout=10, check=False)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return out.stdout.strip() if out.returncode == 0 and out.stdout.strip() else "unknown"


def _script() -> str:
    """The running script, relative to the checkout's root when it lies inside it ("" for none)."""
    main = sys.argv[0] if sys.argv and sys.argv[0] not in ("", "-c") else ""
    if not main:
        return ""
    p = Path(main).resolve()
    root = Path(__file__).resolve().parents[1]
    try:
        return p.relative_to(root).as_posix()
    except ValueError:
        return p.name


def stamp() -> dict[str, str]:
    """``{"twin_version", "git_commit", "script"}`` of this process."""
    return {"twin_version": __version__, "git_commit": git_commit(), "script": _script()}


def stamped(obj: dict[str, Any]) -> dict[str, Any]:
    """``obj`` (a JSON object) with :data:`PROVENANCE_KEY` first: the stamp of this process."""
    if not isinstance(obj, dict):
        raise TypeError(f"obj: a results file's top level must be a JSON object (dict), got {type(obj).__name__}")
    return {PROVENANCE_KEY: stamp(), **{k: v for k, v in obj.items() if k != PROVENANCE_KEY}}


def stamp_line() -> str:
    """One line for the end of a Markdown or text results file."""
    s = stamp()
    by = f" by `{s['script']}`" if s["script"] else ""
    return f"_Written{by} with twin {s['twin_version']}, commit `{s['git_commit']}`._"


def figure_metadata() -> dict[str, str]:
    """PNG text chunks for ``matplotlib.figure.Figure.savefig(..., metadata=...)``."""
    s = stamp()
    return {"Software": f"twin {s['twin_version']} (commit {s['git_commit']})"
                        + (f", {s['script']}" if s["script"] else "")}


def with_stamp_line(text: str) -> str:
    """``text`` (Markdown) ending with :func:`stamp_line` after a blank line."""
    return text.rstrip("\n") + "\n\n" + stamp_line() + "\n"


def write_stamped_text(path: str | Path, text: str) -> Path:
    """Write a Markdown or text results file: ``text`` with :func:`stamp_line` at its end, the parent folders made,
    atomically (temporary file, then rename); returns the path."""
    from twin.util import atomic_write_text

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return atomic_write_text(path, with_stamp_line(text))
