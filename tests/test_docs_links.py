"""The user-facing documentation: every relative link resolves, the README stays short, no issue
numbers or commit hashes.

Checked files: README.md, CHANGELOG.md, docs/*.md, and every markdown file of the repository they
link to, transitively (a link into analysis/results/... is checked as well as the page it sits on).
A link is ``[text](target)`` or ``![alt](target)`` outside code; a target with a scheme (https:,
mailto:) is external and not fetched. A ``#anchor`` must name a heading of the target file, slugged
as GitHub does (lower case, punctuation dropped, spaces to hyphens, -1, -2 for repeats).
"""

from __future__ import annotations

import re
import unicodedata
from pathlib import Path
from urllib.parse import unquote

import pytest

ROOT = Path(__file__).resolve().parents[1]
README_MAX_LINES = 250

# user-facing text that must not carry issue numbers or commit hashes (developer notes may)
ENTRY_FILES = ["README.md", "CHANGELOG.md"]


def _entry_files() -> list[Path]:
    return [ROOT / f for f in ENTRY_FILES] + sorted((ROOT / "docs").glob("*.md"))


def _clean_files() -> list[Path]:
    """Files that must be free of issue numbers and commit hashes."""
    return (_entry_files() + [ROOT / "analysis" / "identify" / "README.md"]
            + sorted((ROOT / "analysis" / "results").glob("*/README.md")))


_FENCE = re.compile(r"^\s*(```|~~~)")
_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
_INLINE_CODE = re.compile(r"(`+)(.+?)\1")
_HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
_SCHEME = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")

# "issue 18", "issues 4 and 15", "Issue #3", "#12"
_ISSUE = re.compile(r"\bissues?\s+#?\d+|(?<![\w&/])#\d+\b", re.IGNORECASE)
# a git commit hash: 7-40 hex digits with at least one letter a-f and one digit, as a whole word
_HASH = re.compile(r"(?<![\w.-])(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,40}(?![\w-])")


def _prose_lines(text: str) -> list[tuple[int, str]]:
    """(line number, line) outside fenced code blocks."""
    out, fenced = [], False
    for n, line in enumerate(text.splitlines(), 1):
        if _FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            out.append((n, line))
    return out


def links(path: Path) -> list[tuple[int, str]]:
    """(line number, target) of every markdown link outside code."""
    found = []
    for n, line in _prose_lines(path.read_text(encoding="utf-8")):
        line = _INLINE_CODE.sub("", line)
        found += [(n, m.group(1)) for m in _LINK.finditer(line)]
    return found


def slug(heading: str) -> str:
    """GitHub's anchor of a heading text."""
    text = _INLINE_CODE.sub(lambda m: m.group(2), heading)
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)      # a link in a heading keeps its text
    text = text.strip().lower()
    kept = "".join(c for c in text
                   if c in " -_" or unicodedata.category(c)[0] in "LN")
    return kept.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    seen: dict[str, int] = {}
    out = set()
    for _, line in _prose_lines(path.read_text(encoding="utf-8")):
        m = _HEADING.match(line)
        if not m:
            continue
        s = slug(m.group(2))
        k = seen.get(s, 0)
        out.add(s if k == 0 else f"{s}-{k}")
        seen[s] = k + 1
    return out


def _checked_files() -> list[Path]:
    """The entry files and every repository markdown file reachable from them by links."""
    todo, done = list(_entry_files()), []
    while todo:
        p = todo.pop()
        if p in done:
            continue
        done.append(p)
        for _, target in links(p):
            if _SCHEME.match(target) or target.startswith("#"):
                continue
            q = (p.parent / unquote(target.split("#", 1)[0])).resolve()
            if q.suffix == ".md" and q.is_file() and ROOT in q.parents and q not in done:
                todo.append(q)
    return sorted(done)


def _broken(path: Path) -> list[str]:
    bad = []
    for n, target in links(path):
        if _SCHEME.match(target):
            continue
        file_part, _, anchor = target.partition("#")
        dest = (path.parent / unquote(file_part)).resolve() if file_part else path
        where = f"{path.relative_to(ROOT)}:{n}: {target}"
        if not dest.exists():
            bad.append(f"{where} (no such file)")
        elif ROOT not in dest.parents and dest != ROOT:
            bad.append(f"{where} (outside the repository)")
        elif anchor and (dest.suffix != ".md" or unquote(anchor) not in anchors(dest)):
            bad.append(f"{where} (no heading with that anchor)")
    return bad


def test_the_link_checker_finds_links_and_anchors(tmp_path):
    """The checker itself: links outside code are found, inside code not; slugs as GitHub makes them."""
    page = tmp_path / "a.md"
    page.write_text("# Title: `code` (x)\n\n[one](b.md#sec-2) and ![img](p.png) `[no](x.md)`\n"
                    "```\n[no](y.md)\n```\n## Sec 2\n## Sec 2\n", encoding="utf-8")
    assert [t for _, t in links(page)] == ["b.md#sec-2", "p.png"]
    assert anchors(page) == {"title-code-x", "sec-2", "sec-2-1"}
    assert slug("The 0.5 mm AC6 peak") == "the-05-mm-ac6-peak"
    assert _ISSUE.search("as issue 18 asks") and _ISSUE.search("see #12")
    assert not _ISSUE.search("Table 4 test 12") and not _ISSUE.search("[x](#s001)")
    assert _HASH.search("at f819579 the") and _HASH.search("(a83bef6)")
    assert not _HASH.search("0.0006926 kg") and not _HASH.search("h = 1e-5 s") and not _HASH.search("decade")


def test_checked_files_include_the_pages_they_link():
    files = {p.relative_to(ROOT).as_posix() for p in _checked_files()}
    assert {"README.md", "CHANGELOG.md", "docs/index.md"} <= files
    assert "recordings/FORMAT.md" in files           # linked from the README, checked in turn


@pytest.mark.parametrize("path", _checked_files(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_relative_link_resolves(path):
    assert _broken(path) == []


def test_every_docs_page_is_listed_in_the_index():
    index = (ROOT / "docs" / "index.md")
    listed = {(index.parent / t.split("#")[0]).resolve() for _, t in links(index) if not _SCHEME.match(t)}
    missing = [p.name for p in sorted((ROOT / "docs").glob("*.md")) if p != index and p.resolve() not in listed]
    assert missing == []


def test_readme_is_short():
    n = len((ROOT / "README.md").read_text(encoding="utf-8").splitlines())
    assert n <= README_MAX_LINES, f"README.md has {n} lines; at most {README_MAX_LINES}: move detail to docs/"


@pytest.mark.parametrize("path", _clean_files(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_no_issue_numbers_or_commit_hashes(path):
    bad = []
    for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        for pattern, what in ((_ISSUE, "issue number"), (_HASH, "commit hash")):
            bad += [f"{path.relative_to(ROOT)}:{n}: {what} {m.group(0)!r}" for m in pattern.finditer(line)]
    assert bad == []
