"""Stamp the results files made before the live stamp (:mod:`twin.provenance`) with what git history says.

Many files of ``analysis/results/`` were written before the scripts stamped their output, and some are
one-time results (a fresh look at a held-out set) that must never be made again. Rather than re-running
them, this script writes in each unstamped file the provenance git history gives it:

* ``git_commit``: the last commit that changed the file (the commit that committed its present content,
  so the content was made by the code at or before it);
* ``first_committed``: the commit that first added the file at its path;
* ``twin_version``: the package version (``twin.__version__``, or ``version`` in ``pyproject.toml`` where
  the version lived there) at ``git_commit``;
* ``stamped_from``: :data:`STAMPED_FROM`, saying the stamp is read from history, not written by the run.

Where it goes (the data are untouched; only the stamp is added, and each file is checked after):

* JSON: the key ``provenance`` (:data:`twin.provenance.PROVENANCE_KEY`) first in the top-level object,
  inserted into the text, so every other byte stays as it was;
* Markdown: a last line in the form of :func:`twin.provenance.stamp_line`, after a blank line;
* PNG: the ``Software`` text chunk (the chunk live figures carry their stamp in, see
  :func:`twin.provenance.figure_metadata`), in place of matplotlib's own; the image chunks are kept byte
  for byte.

A file already stamped (live or from history) is left alone, so the script can run again at no harm; a
file git does not know (not committed yet) is refused: a new result is written stamped by its script.

Run: ``python analysis/stamp_history.py [--check]`` (a few seconds; ``--check`` lists what it would stamp).
"""

from __future__ import annotations

import argparse
import json
import re
import struct
import subprocess
import sys
import zlib
from pathlib import Path

from twin.provenance import PROVENANCE_KEY
from twin.util import atomic_write_bytes

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS = HERE / "results"

#: what a stamp read from git history says about itself
STAMPED_FROM = "git history: the commit that committed this file; made by the code at or before it"
#: the marker a history stamp carries in every kind of file (JSON value, Markdown line, PNG text)
MARK = "stamped from git history"

_PNG_SIG = b"\x89PNG\r\n\x1a\n"


def _git(*args: str) -> str:
    return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, check=True).stdout


def commits_by_path(rev: str = "HEAD") -> dict[str, list[str]]:
    """Path (relative to the repository) -> the full hashes of the commits up to ``rev`` that touched it under
    analysis/results/, newest first (one ``git log`` for all)."""
    out: dict[str, list[str]] = {}
    commit = ""
    for line in _git("log", "--format=%x00%H", "--name-only", "--no-renames", rev, "--",
                     "analysis/results").splitlines():
        if line.startswith("\x00"):
            commit = line[1:]
        elif line.strip():
            out.setdefault(line.strip(), []).append(commit)
    return out


def version_at(commit: str) -> str:
    """The package version at ``commit``: ``twin.__version__`` or, before it was the one source, ``pyproject.toml``."""
    for path, pattern in (("twin/__init__.py", r'^__version__\s*=\s*"([^"]+)"'),
                          ("pyproject.toml", r'^version\s*=\s*"([^"]+)"')):
        try:
            text = _git("show", f"{commit}:{path}")
        except subprocess.CalledProcessError:
            continue
        m = re.search(pattern, text, re.M)
        if m:
            return m.group(1)
    raise RuntimeError(f"no package version found at commit {commit}")


def history_stamp(commits: list[str], versions: dict[str, str] | None = None) -> dict[str, str]:
    """The stamp of a file touched by ``commits`` (newest first)."""
    last, first = commits[0], commits[-1]
    versions = {} if versions is None else versions
    if last not in versions:
        versions[last] = version_at(last)
    return {"twin_version": versions[last], "git_commit": last[:12], "first_committed": first[:12],
            "stamped_from": STAMPED_FROM}


def markdown_line(st: dict[str, str]) -> str:
    """The Markdown form (the live :func:`twin.provenance.stamp_line`'s, with where it comes from)."""
    return (f"_Written with twin {st['twin_version']}, commit `{st['git_commit']}` ({MARK}: the commit that "
            f"committed this file, first committed in `{st['first_committed']}`; made by the code at or before it)._")


def png_text(st: dict[str, str], before: str = "") -> str:
    """The PNG ``Software`` text (the live :func:`twin.provenance.figure_metadata`'s form, with where it comes
    from and the text the chunk held before)."""
    return (f"twin {st['twin_version']} (commit {st['git_commit']}), {MARK}: the commit that committed this file, "
            f"first committed in {st['first_committed']}; made by the code at or before it"
            + (f"; drawn with {before}" if before else ""))


# ------------------------------------------------------------------ the three kinds
def stamp_json(text: str, st: dict[str, str]) -> str:
    """``text`` (a JSON object) with ``"provenance": st`` inserted as its first key; every other byte kept."""
    m = re.match(r"\{(\s*)", text)
    if not m or not isinstance(json.loads(text), dict):
        raise ValueError("the top level is not a JSON object")
    ws = m.group(1)
    body = text[m.end():]
    entry = f"{json.dumps(PROVENANCE_KEY)}: {json.dumps(st)}"
    if body.startswith("}"):  # an empty object
        new = "{" + ws + entry + body
    else:
        new = "{" + ws + entry + "," + (ws if ws else " ") + body
    a, b = json.loads(new), json.loads(text)
    if list(a) != [PROVENANCE_KEY, *b] or json.dumps({k: v for k, v in a.items() if k != PROVENANCE_KEY}) != \
            json.dumps(b) or a[PROVENANCE_KEY] != st:
        raise AssertionError("stamping changed the data")
    return new


def stamp_markdown(text: str, st: dict[str, str]) -> str:
    """``text`` with :func:`markdown_line` as its last line after a blank line; the text before kept as it was."""
    return text + ("" if text.endswith("\n") else "\n") + "\n" + markdown_line(st) + "\n"


def _chunks(data: bytes) -> list[tuple[bytes, bytes]]:
    if not data.startswith(_PNG_SIG):
        raise ValueError("not a PNG file")
    out, i = [], len(_PNG_SIG)
    while i < len(data):
        (n,) = struct.unpack(">I", data[i:i + 4])
        kind, body = data[i + 4:i + 8], data[i + 8:i + 8 + n]
        out.append((kind, body))
        i += 12 + n
    return out


def _chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)


def stamp_png(data: bytes, st: dict[str, str]) -> bytes:
    """``data`` (a PNG) with its ``Software`` tEXt chunk holding :func:`png_text` (matplotlib's text kept at its
    end); every other chunk kept byte for byte."""
    chunks = _chunks(data)
    before = ""
    kept = []
    for kind, body in chunks:
        if kind == b"tEXt" and body.split(b"\0", 1)[0] == b"Software":
            before = body.split(b"\0", 1)[1].decode("latin-1")
            continue
        kept.append((kind, body))
    text = b"Software\0" + png_text(st, before).encode("latin-1")
    at = next(k for k, (kind, _) in enumerate(kept) if kind == b"IDAT")
    kept.insert(at, (b"tEXt", text))
    new = _PNG_SIG + b"".join(_chunk(k, b) for k, b in kept)
    if [c for c in _chunks(new) if c[0] != b"tEXt"] != [c for c in chunks if c[0] != b"tEXt"]:
        raise AssertionError("stamping changed an image chunk")
    return new


# ------------------------------------------------------------------ reading a history stamp back
def read_history_stamp(path: Path) -> dict[str, str] | None:
    """The history stamp of a results file (``twin_version``, ``git_commit``, ``first_committed``), or None when it
    carries none (no stamp, or a live one)."""
    if path.suffix == ".json":
        try:
            top = json.loads(path.read_text(encoding="utf-8"))
        except ValueError:
            return None
        p = top.get(PROVENANCE_KEY) if isinstance(top, dict) else None
        return dict(p) if isinstance(p, dict) and p.get("stamped_from") == STAMPED_FROM else None
    if path.suffix == ".md":
        lines = [ln for ln in path.read_text(encoding="utf-8").splitlines() if ln.strip()]
        m = re.fullmatch(r"_Written with twin (\S+), commit `(\w+)` \(" + MARK + r": the commit that committed this "
                         r"file, first committed in `(\w+)`; made by the code at or before it\)\._",
                         lines[-1] if lines else "")
        return {"twin_version": m[1], "git_commit": m[2], "first_committed": m[3]} if m else None
    if path.suffix == ".png":
        from PIL import Image

        with Image.open(path) as im:
            text = str(im.info.get("Software", ""))
        m = re.match(r"twin (\S+) \(commit (\w+)\), " + MARK + r": the commit that committed this file, first "
                     r"committed in (\w+); made by the code at or before it", text)
        return {"twin_version": m[1], "git_commit": m[2], "first_committed": m[3]} if m else None
    return None


def _driver():
    import importlib.util

    spec = importlib.util.spec_from_file_location("analysis_run_history", HERE / "run.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="list the files it would stamp; write nothing")
    args = ap.parse_args(argv)
    drv = _driver()
    files = sorted(p for p in RESULTS.rglob("*") if p.is_file())
    todo = [p for p in files if drv.is_stamped(p) is False]
    history = commits_by_path()
    unknown = [p for p in todo if p.relative_to(ROOT).as_posix() not in history]
    if unknown:
        print("stamp_history.py: not in git history (write them stamped from their script instead):\n  "
              + "\n  ".join(p.relative_to(ROOT).as_posix() for p in unknown), file=sys.stderr)
        return 1
    versions: dict[str, str] = {}
    for p in todo:
        rel = p.relative_to(ROOT).as_posix()
        st = history_stamp(history[rel], versions)
        if args.check:
            print(f"{rel}: twin {st['twin_version']}, commit {st['git_commit']} (first {st['first_committed']})")
            continue
        if p.suffix == ".json":
            atomic_write_bytes(p, stamp_json(p.read_bytes().decode("utf-8"), st).encode("utf-8"))
        elif p.suffix == ".md":
            atomic_write_bytes(p, stamp_markdown(p.read_bytes().decode("utf-8"), st).encode("utf-8"))
        elif p.suffix == ".png":
            atomic_write_bytes(p, stamp_png(p.read_bytes(), st))
        if drv.is_stamped(p) is not True or read_history_stamp(p) != {k: st[k] for k in read_history_stamp(p)}:
            raise AssertionError(f"{rel}: the stamp does not read back")
    print(f"{'would stamp' if args.check else 'stamped'} {len(todo)} results files from git history "
          f"({len(files)} files under analysis/results)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
