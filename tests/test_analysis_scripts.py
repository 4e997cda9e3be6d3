"""The scripts of ``analysis/``: one driver lists them all, none imports a private name, and what they
write is stamped with the version and the commit (:mod:`twin.provenance`).

Method: the scripts are read with :mod:`ast`, not run (most take minutes); the driver
``analysis/run.py`` is loaded from its file and asked for its list.
"""

from __future__ import annotations

import ast
import importlib.util
import json
import sys
from pathlib import Path

import pytest

import twin
from twin.provenance import PROVENANCE_KEY, figure_metadata, git_commit, stamp_line, stamped, with_stamp_line

ROOT = Path(__file__).resolve().parents[1]
ANALYSIS = ROOT / "analysis"

#: script -> (private names it still imports, why): each entry a known gap, not a permission, to be closed by
#: making the name public (the test below fails on an entry that is no longer needed). None at present.
PENDING_PRIVATE: dict[str, tuple[set[str], str]] = {}

#: writes of a script that are not results files (a cache, a work folder, a spec, the docs page in place)
NOT_RESULTS = {
    ("identify/nuisance_study", "js"),        # feature cache in the work folder
    ("identify/bench_variants", "js"),        # feature cache of the development sets (--cache)
    ("profile_stages", "src"),                # C source of the timing shims, in a temporary folder
    ("bench_storage", "folder / 'source.json'"),  # the benchmark's own input, in its work folder
    ("s002_l27_spec", "HERE / name"),         # study specs (analysis/datasets/*.toml), inputs not results
    ("speed_table", "tmp"),                   # docs/speed.md rewritten in place (through a temporary file)
    ("bit_identical", "a.save"),              # a digest list for --against, not a result
    ("bench_threads", "gen_file"),            # a dataset spec in a temporary folder
    ("s002_paper_tables", "out / 'responses_reconstructed.csv'"),  # CSV read by twin study mcdm/taguchi
    ("calibration_validation", "toml"),       # a case's configuration in the work folder, read by twin record
}


def _driver():
    spec = importlib.util.spec_from_file_location("analysis_run", ANALYSIS / "run.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # its dataclasses look their module up while the class is made
    spec.loader.exec_module(mod)
    return mod


def _scripts() -> dict[str, Path]:
    drv = _driver()
    return {name: drv.script_path(name) for name in drv.all_scripts()}


def test_the_driver_lists_every_script_and_only_scripts(capsys):
    drv = _driver()
    on_disk = set(drv.all_scripts())
    assert len(on_disk) >= 40, sorted(on_disk)
    assert set(drv.SCRIPTS) == on_disk, (f"not in analysis/run.py's SCRIPTS: {sorted(on_disk - set(drv.SCRIPTS))}; "
                                         f"listed but gone: {sorted(set(drv.SCRIPTS) - on_disk)}")
    assert drv.main(["--list"]) == 0
    out = capsys.readouterr().out
    for name, s in drv.SCRIPTS.items():
        line = next((ln for ln in out.splitlines() if ln.split(" ")[0] == name), None)
        assert line is not None, f"--list does not show {name}"
        assert s.cost in line and (("LONG" in line) == s.long), line
        assert s.rebuilds and s.cost


def test_the_driver_refuses_unknown_and_unflagged_long_scripts(capsys):
    drv = _driver()
    assert drv.main(["no_such_script"]) == 2
    assert "unknown script no_such_script" in capsys.readouterr().err
    long = next(n for n, s in drv.SCRIPTS.items() if s.long)
    assert drv.main([long]) == 2
    assert "--long" in capsys.readouterr().err


def _private_imports(path: Path) -> set[str]:
    """Names starting with one underscore that ``path`` imports (from any module), and imported modules
    with such a component (``twin.x._y``); ``__future__`` and dunders aside."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module != "__future__":
            mods = (node.module or "").split(".")
            found.update(m for m in mods if m.startswith("_") and not m.startswith("__"))
            found.update(a.name for a in node.names if a.name.startswith("_") and not a.name.startswith("__"))
        elif isinstance(node, ast.Import):
            for a in node.names:
                found.update(m for m in a.name.split(".") if m.startswith("_") and not m.startswith("__"))
    return found


def test_the_private_import_check_can_fail(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text("from __future__ import annotations\nfrom twin.x import public, _hidden\nimport twin._native\n"
                     "def f():\n    from twin.y import _inner\n")
    assert _private_imports(probe) == {"_hidden", "_native", "_inner"}


def test_no_analysis_script_imports_a_private_name():
    bad = {}
    for name, path in _scripts().items():
        names = _private_imports(path)
        pending = PENDING_PRIVATE.get(name, (set(), ""))[0]
        if names - pending:
            bad[name] = sorted(names - pending)
    assert not bad, f"private imports in analysis scripts: {bad}"
    for name, (names, _why) in PENDING_PRIVATE.items():  # an entry that is no longer needed is removed
        assert names & _private_imports(ANALYSIS / f"{name}.py"), f"{name}: PENDING_PRIVATE entry is stale"


def _calls(tree: ast.AST, attr: str) -> list[ast.Call]:
    return [n for n in ast.walk(tree) if isinstance(n, ast.Call) and isinstance(n.func, ast.Attribute)
            and n.func.attr == attr]


def _is_call_to(node: ast.AST, name: str) -> bool:
    return isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == name


def test_every_result_a_script_writes_is_stamped():
    """Static check of every write: ``savefig`` with ``metadata=figure_metadata()``; ``write_text`` of
    ``json.dumps(stamped(...))`` or of ``with_stamp_line(...)``; ``atomic_write_json`` of ``stamped(...)``.
    The writes that are not results are named in :data:`NOT_RESULTS`."""
    unstamped = []
    for name, path in _scripts().items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for call in _calls(tree, "savefig"):
            if not any(k.arg == "metadata" and _is_call_to(k.value, "figure_metadata") for k in call.keywords):
                unstamped.append(f"{name}:{call.lineno} savefig")
        for call in _calls(tree, "write_text"):
            target = ast.unparse(call.func.value).replace('"', "'")
            if (name, target) in NOT_RESULTS:
                continue
            arg = call.args[0] if call.args else None
            ok = _is_call_to(arg, "with_stamp_line") or (
                isinstance(arg, ast.BinOp) and isinstance(arg.left, ast.Call)
                and ast.unparse(arg.left.func) == "json.dumps" and _is_call_to(arg.left.args[0], "stamped")) or (
                isinstance(arg, ast.Call) and ast.unparse(arg.func) == "json.dumps" and _is_call_to(arg.args[0], "stamped"))
            if not ok:
                unstamped.append(f"{name}:{call.lineno} write_text to {target}")
        for call in [n for n in ast.walk(tree) if _is_call_to(n, "atomic_write_json")]:
            if not _is_call_to(call.args[1], "stamped"):
                unstamped.append(f"{name}:{call.lineno} atomic_write_json")
    assert not unstamped, "results written without the version and commit:\n" + "\n".join(unstamped)


def test_stamp_carries_version_and_commit(tmp_path):
    out = stamped({"a": 1, PROVENANCE_KEY: "old"})
    assert list(out) == [PROVENANCE_KEY, "a"] and out["a"] == 1
    assert out[PROVENANCE_KEY]["twin_version"] == twin.__version__
    assert out[PROVENANCE_KEY]["git_commit"] == git_commit() != ""
    json.dumps(out)  # JSON as it is
    with pytest.raises(TypeError, match="obj"):
        stamped([1, 2])
    assert twin.__version__ in stamp_line() and git_commit() in stamp_line()
    assert with_stamp_line("# t\n\n").endswith("\n\n" + stamp_line() + "\n")


def test_figure_stamp_reads_back_from_the_png(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image

    fig, ax = plt.subplots(figsize=(1, 1))
    ax.plot([0, 1])
    fig.savefig(tmp_path / "f.png", metadata=figure_metadata())
    plt.close(fig)
    with Image.open(tmp_path / "f.png") as im:
        assert im.info["Software"] == figure_metadata()["Software"]
    assert twin.__version__ in im.info["Software"] and git_commit() in im.info["Software"]
