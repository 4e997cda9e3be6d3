"""The scripts in examples/ run (each with its --small option, in a temporary folder) and write
what they say they write."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
PNG = b"\x89PNG\r\n\x1a\n"


def _run(script: str, *args: str, cwd: Path) -> str:
    p = subprocess.run([sys.executable, str(EXAMPLES / script), "--small", *args], cwd=cwd,
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-3000:]
    return p.stdout


def _png(tmp_path: Path, script: str) -> str:
    out = tmp_path / "plot.png"
    text = _run(script, "--out", str(out), cwd=tmp_path)
    assert out.read_bytes()[:8] == PNG and f"wrote {out}" in text
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plot.png"]  # nothing else left behind
    return text


def test_sweep_example_writes_a_png_and_a_line_per_clearance(tmp_path):
    text = _png(tmp_path, "sweep.py")
    assert [ln.split(":")[0] for ln in text.splitlines()[:2]] == ["clearance C 0.00 mm", "clearance C 0.10 mm"]


def test_replay_example_writes_a_png_and_the_comparison(tmp_path):
    text = _png(tmp_path, "replay_plot.py")
    assert text.startswith("test6_repeat1_synthetic.mcap: AC6 NRMSE ")


def test_loader_example_batches_every_window_once(tmp_path):
    text = _run("loader.py", "--batch-size", "4", cwd=tmp_path)
    head = text.splitlines()[0]
    n = int(head.split(": ")[1].split()[0])  # "<name>: N training windows of ..."
    batches = [ln for ln in text.splitlines() if ln.startswith("batch: ")]
    assert n > 0 and len(batches) == -(-n // 4)
    assert all("x float32 (" in b and ", 6, 200)" in b for b in batches)
    assert list(tmp_path.iterdir()) == []  # the dataset went to a temporary folder, removed
