"""Every results file carries its provenance (version and commit, :mod:`twin.provenance`): a live stamp
written by the script or command that made it, or, for a file committed before live stamps existed, a stamp
read from git history (``analysis/stamp_history.py``: the commit that committed the file's content and the
package version then, marked ``stamped_from`` git history).

* Every results file under ``analysis/results/`` is stamped (CSV files and folder READMEs aside, as
  ``analysis/run.py``'s :func:`is_stamped` says); every file a page of ``docs/`` or the README names (by path,
  by a pattern such as ``size_observability*.json`` or ``{b,c}``, or by its folder) exists and is stamped.
* A history stamp is allowed only on a file git history held at :data:`BEFORE_HISTORY_STAMPS` (the commit
  before history stamps existed), and it names that file's last commit up to then, its first commit and the
  version at its last commit: a new result cannot take a history stamp, it is written stamped by its script.
* The history-stamped files are no more than :data:`CEILING` (lowered as they are rebuilt live; never raised).
* The stamping keeps the data: the JSON text gains one key, the Markdown one last line, the PNG a text
  chunk with every image chunk byte for byte.

Stamps are read by ``analysis/run.py``'s own :func:`is_stamped` (the driver's ``--unstamped``) and
``analysis/stamp_history.py``'s :func:`read_history_stamp`, both loaded from their files.
"""

from __future__ import annotations

import fnmatch
import importlib.util
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "analysis" / "results"
#: the last commit before history stamps: the files its tree held under analysis/results/ (and only those) may
#: carry a stamp read from git history
BEFORE_HISTORY_STAMPS = "309661175cea7fbd3aa5d6b3be8271daf7cfe6f8"
#: the number of history-stamped files when they were written; lower it as files are rebuilt live, never raise it
CEILING = 325


def _load(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def _driver():
    return _load("analysis_run_stamps", ROOT / "analysis" / "run.py")


def _history():
    return _load("analysis_stamp_history", ROOT / "analysis" / "stamp_history.py")


def _expand(ref: str) -> list[str]:
    """A reference as patterns: ``{a,b}`` alternatives each, ``*`` kept for fnmatch."""
    m = re.search(r"\{([^}]*)\}", ref)
    if not m:
        return [ref]
    return [p for alt in m.group(1).split(",") for p in _expand(ref[:m.start()] + alt + ref[m.end():])]


def doc_references(texts: dict[str, str], files: list[Path]) -> dict[Path, str]:
    """The results files among ``files`` that the texts name: a path or pattern ``analysis/results/...`` (a
    folder names every file under it) -> the first page naming it."""
    out: dict[Path, str] = {}
    for page, text in texts.items():
        for m in re.finditer(r"analysis/results/[\w./{},*+-]*", text):
            for pat in _expand(m.group(0).rstrip(".,)")):
                pat = pat.rstrip("/")
                for f in files:
                    rel = f.relative_to(ROOT).as_posix()
                    if fnmatch.fnmatch(rel, pat) or rel.startswith(pat + "/") or \
                            any(fnmatch.fnmatch(a.as_posix(), pat) for a in f.relative_to(ROOT).parents):
                        out.setdefault(f, page)
    return out


def _docs() -> dict[str, str]:
    pages = sorted((ROOT / "docs").rglob("*.md")) + [ROOT / "README.md"]
    return {p.relative_to(ROOT).as_posix(): p.read_text(encoding="utf-8") for p in pages}


def _results() -> list[Path]:
    return sorted(p for p in RESULTS.rglob("*") if p.is_file())


def test_the_reference_scan_finds_paths_patterns_braces_and_folders(tmp_path):
    files = [ROOT / "analysis/results/x/a_b.json", ROOT / "analysis/results/x/a_c.json",
             ROOT / "analysis/results/y/z/q.png", ROOT / "analysis/results/w.md"]
    texts = {"p1": "see `analysis/results/x/a_{b,c}.json`.", "p2": "[f](../analysis/results/y/) and",
             "p3": "analysis/results/w*.md"}
    found = doc_references(texts, files)
    assert set(found) == set(files) and found[files[2]] == "p2"
    assert doc_references({"p": "analysis/results/x/a_b.json"}, files) == {files[0]: "p"}


def test_every_results_file_the_docs_name_exists_and_is_stamped():
    drv = _driver()
    refs = doc_references(_docs(), _results())
    assert len(refs) > 50, "the docs name results files: the scan found too few"
    bad = [f"{f.relative_to(ROOT).as_posix()} (named by {page})" for f, page in sorted(refs.items())
           if drv.is_stamped(f) is False]
    assert not bad, "unstamped results files named by the docs:\n" + "\n".join(bad)


def test_every_results_file_is_stamped():
    drv = _driver()
    files = _results()
    state = {p: drv.is_stamped(p) for p in files}
    assert sum(s is True for s in state.values()) > 300, "the results folder is nearly empty: the scan is wrong"
    new = [p.relative_to(ROOT).as_posix() for p, s in state.items() if s is False]
    assert not new, "results files without a stamp (write them through twin.provenance):\n" + "\n".join(new)


def _git(*args: str) -> str:
    try:
        out = subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, timeout=60, check=False)
    except (OSError, subprocess.SubprocessError) as e:
        pytest.skip(f"git is not usable here ({e}): history stamps are checked in a checkout")
    if out.returncode != 0:
        pytest.skip(f"git {args[0]} failed ({out.stderr.strip()[:200]}): history stamps are checked in a full checkout")
    return out.stdout


def test_history_stamps_only_on_files_committed_before_them_and_true_to_history():
    hist = _history()
    _git("cat-file", "-e", f"{BEFORE_HISTORY_STAMPS}^{{commit}}")
    before = set(_git("ls-tree", "-r", "--name-only", BEFORE_HISTORY_STAMPS, "--", "analysis/results").split())
    commits = hist.commits_by_path(BEFORE_HISTORY_STAMPS)
    stamps = {p.relative_to(ROOT).as_posix(): s for p in _results() if (s := hist.read_history_stamp(p)) is not None}
    assert 0 < len(stamps) <= CEILING, f"{len(stamps)} files carry a history stamp (ceiling {CEILING}: it only shrinks)"
    new = sorted(set(stamps) - before)
    assert not new, ("a history stamp on a file committed after history stamps existed (write it stamped from its "
                     "script):\n" + "\n".join(new))
    versions: dict[str, str] = {}
    wrong = []
    for rel, st in sorted(stamps.items()):
        true = hist.history_stamp(commits[rel], versions)
        if {k: st[k] for k in ("twin_version", "git_commit", "first_committed")} != \
                {k: true[k] for k in ("twin_version", "git_commit", "first_committed")}:
            wrong.append(f"{rel}: {st} (git history: {true})")
    assert not wrong, "history stamps that git history does not bear out:\n" + "\n".join(wrong)


def test_stamping_keeps_the_json_text_and_data(tmp_path):
    hist = _history()
    st = {"twin_version": "9.9", "git_commit": "abc", "first_committed": "def", "stamped_from": hist.STAMPED_FROM}
    for text in ('{\n  "a": [1, 2.5e-07],\n  "b": {"c": NaN}\n}\n', '{"a": 1}', "{ }", '{\n "x": "\u00e9"\n}'):
        new = hist.stamp_json(text, st)
        d = json.loads(new)
        assert list(d)[0] == "provenance" and d.pop("provenance") == st
        assert json.dumps(d) == json.dumps(json.loads(text))
        assert new.endswith(text[re.match(r"\{\s*", text).end():])  # the text after the opening brace, byte for byte
        p = tmp_path / "r.json"
        p.write_text(new)
        assert _driver().is_stamped(p) is True and hist.read_history_stamp(p) == st
    with pytest.raises(ValueError, match="JSON object"):
        hist.stamp_json("[1, 2]", st)


def test_stamping_keeps_the_markdown_text(tmp_path):
    hist = _history()
    st = {"twin_version": "9.9", "git_commit": "abc", "first_committed": "def", "stamped_from": hist.STAMPED_FROM}
    for text in ("# T\n\n| a |\n", "# T\r\nno newline at end"):
        new = hist.stamp_markdown(text, st)
        assert new.startswith(text) and new.endswith(hist.markdown_line(st) + "\n")
        p = tmp_path / "r.md"
        p.write_bytes(new.encode())
        assert _driver().is_stamped(p) is True
        assert hist.read_history_stamp(p) == {k: st[k] for k in ("twin_version", "git_commit", "first_committed")}


def test_stamping_keeps_the_png_image(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from PIL import Image

    hist = _history()
    st = {"twin_version": "9.9", "git_commit": "abc", "first_committed": "def", "stamped_from": hist.STAMPED_FROM}
    fig, ax = plt.subplots(figsize=(1, 1))
    ax.plot([0, 1], [1, 0])
    p = tmp_path / "f.png"
    fig.savefig(p)
    plt.close(fig)
    assert _driver().is_stamped(p) is False  # matplotlib's own Software text is no stamp
    old = p.read_bytes()
    p.write_bytes(hist.stamp_png(old, st))
    assert _driver().is_stamped(p) is True
    assert hist.read_history_stamp(p) == {k: st[k] for k in ("twin_version", "git_commit", "first_committed")}
    with Image.open(tmp_path / "f.png") as a:
        (tmp_path / "g.png").write_bytes(old)
        with Image.open(tmp_path / "g.png") as b:
            assert np.array_equal(np.asarray(a), np.asarray(b)) and a.mode == b.mode
            assert a.info["Software"].endswith("drawn with " + b.info["Software"])
