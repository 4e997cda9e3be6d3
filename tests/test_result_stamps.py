"""Results files carry their provenance (version and commit, :mod:`twin.provenance`), or are named on the
committed list of files made before the stamp existed (``analysis/made_before_stamping.txt``), which may only
shrink.

* Every results file a page of ``docs/`` or the README names (by path, by a pattern such as
  ``size_observability*.json`` or ``{b,c}``, or by its folder) is stamped or on the list.
* The list holds only files that exist and still carry no stamp: a file rebuilt through
  ``python analysis/run.py NAME`` (and so stamped) or deleted leaves it, in the same commit.
* No unstamped results file is off the list: a new results file is written stamped.
* The list is no longer than :data:`CEILING`, lowered whenever the list shrinks (it never grows).

Stamps are read by ``analysis/run.py``'s own :func:`is_stamped` (the driver's ``--unstamped``), loaded from
its file.
"""

from __future__ import annotations

import fnmatch
import importlib.util
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "analysis" / "results"
LIST = ROOT / "analysis" / "made_before_stamping.txt"
#: the list's length when last shrunk; lower it with the list, never raise it
CEILING = 325


def _driver():
    spec = importlib.util.spec_from_file_location("analysis_run_stamps", ROOT / "analysis" / "run.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def listed() -> list[str]:
    """The list's paths (relative to the repository), comments and blank lines aside."""
    return [ln.strip() for ln in LIST.read_text(encoding="utf-8").splitlines()
            if ln.strip() and not ln.lstrip().startswith("#")]


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


def test_every_results_file_the_docs_name_is_stamped_or_listed():
    drv = _driver()
    on_list = set(listed())
    refs = doc_references(_docs(), _results())
    assert len(refs) > 50, "the docs name results files: the scan found too few"
    bad = [f"{f.relative_to(ROOT).as_posix()} (named by {page})" for f, page in sorted(refs.items())
           if drv.is_stamped(f) is False and f.relative_to(ROOT).as_posix() not in on_list]
    assert not bad, "unstamped results files named by the docs, not on the made-before-stamping list:\n" + \
        "\n".join(bad)


def test_the_list_holds_only_files_that_exist_and_carry_no_stamp():
    drv = _driver()
    entries = listed()
    assert len(entries) == len(set(entries)), "a file is listed twice"
    gone = [e for e in entries if not (ROOT / e).is_file()]
    assert not gone, "listed but gone (take them off the list):\n" + "\n".join(gone)
    stamped_now = [e for e in entries if drv.is_stamped(ROOT / e) is not False]
    assert not stamped_now, "listed but stamped now (rebuilt: take them off the list):\n" + "\n".join(stamped_now)


def test_every_unstamped_results_file_is_on_the_list():
    drv = _driver()
    on_list = set(listed())
    new = [p.relative_to(ROOT).as_posix() for p in _results()
           if drv.is_stamped(p) is False and p.relative_to(ROOT).as_posix() not in on_list]
    assert not new, "results files without a stamp (write them through twin.provenance):\n" + "\n".join(new)


def test_the_list_only_shrinks():
    n = len(listed())
    assert n <= CEILING, f"the made-before-stamping list grew to {n} entries (ceiling {CEILING}): it may only shrink"
