"""No module of the package is over :data:`MAX_LINES` lines: a module that grows past it does more than one
job and is split by job (as ``twin.identification`` was). Read from the files, not imported."""

from __future__ import annotations

from pathlib import Path

import twin

ROOT = Path(twin.__file__).resolve().parent
MAX_LINES = 800


def test_the_scan_reads_the_package():
    sizes = {p: len(p.read_text(encoding="utf-8").splitlines()) for p in ROOT.rglob("*.py")}
    assert len(sizes) > 100 and max(sizes.values()) > 100  # the walk found the modules, not an empty folder


def test_no_module_is_over_the_limit():
    over = sorted((n, p.relative_to(ROOT.parent).as_posix()) for p in ROOT.rglob("*.py")
                  if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES)
    assert not over, f"modules over {MAX_LINES} lines: " + ", ".join(f"{p} ({n})" for n, p in over)
