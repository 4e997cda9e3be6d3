"""The package's import graph has no cycle.

Every module of ``twin`` is read with :mod:`ast` (not imported); every ``import`` statement counts,
at module level and inside functions alike (a function-local import only hides a cycle until the
function runs). ``from twin import x`` and ``from twin.pkg import x`` point to the submodule
``twin.pkg.x`` when ``x`` is one, to ``twin.pkg`` (its ``__init__``) otherwise; ``import twin.a.b``
and ``from twin.a.b import y`` point to ``twin.a.b``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import twin

ROOT = Path(twin.__file__).resolve().parent


def _modules() -> dict[str, Path]:
    """Dotted name -> file of every module of the package (packages by their ``__init__``)."""
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT.parent).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _resolve(name: str, modules: dict[str, Path]) -> str | None:
    """The longest module of the package that ``name`` (a dotted import path) lies in."""
    parts = name.split(".")
    while parts:
        cand = ".".join(parts)
        if cand in modules:
            return cand
        parts.pop()
    return None


def _edges(module: str, path: Path, modules: dict[str, Path]) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    is_pkg = path.name == "__init__.py"
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "twin":
                    out.add(_resolve(alias.name, modules))
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative import: from the module's package upwards
                base = module.split(".") if is_pkg else module.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "twin":
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                out.add(sub if sub in modules else _resolve(target, modules))
    out.discard(None)
    out.discard(module)
    return out


def import_graph() -> dict[str, set[str]]:
    """Module -> the package's modules it imports."""
    modules = _modules()
    return {m: _edges(m, p, modules) for m, p in modules.items()}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` as [a, b, ..., a], or None (iterative depth-first search)."""
    state: dict[str, int] = {}  # 1 on the stack, 2 done
    for start in sorted(graph):
        if state.get(start):
            continue
        stack = [(start, iter(sorted(graph[start])))]
        path = [start]
        state[start] = 1
        while stack:
            node, it = stack[-1]
            nxt = next(it, None)
            if nxt is None:
                stack.pop()
                path.pop()
                state[node] = 2
            elif state.get(nxt) == 1:
                return path[path.index(nxt):] + [nxt]
            elif not state.get(nxt):
                state[nxt] = 1
                path.append(nxt)
                stack.append((nxt, iter(sorted(graph.get(nxt, ())))))
    return None


def test_graph_reads_the_package():
    """The walk finds the modules and the edges it should (guards the test against reading nothing)."""
    graph = import_graph()
    assert {"twin.config", "twin.config.loading", "twin.simulation", "twin.drive", "twin.channels"} <= set(graph)
    assert "twin.config" in graph["twin.drive"]  # module level: from twin.config import BenchConfig
    assert "twin.tracefile" in graph["twin.simulation"]  # module level: the run reads the drive inputs


def test_the_configuration_imports_no_reader_of_data_files():
    """Loading a configuration opens no trace, command or recording: no module of ``twin.config`` imports the
    modules that read them (a trace program's length is filled in by the run, ``twin.tracefile``)."""
    graph = import_graph()
    readers = {"twin.tracefile", "twin.recording", "twin.mcapfile", "twin.motor_drive", "twin.drive"}
    bad = sorted(f"{m} -> {t}" for m, ts in graph.items() if m == "twin.config" or m.startswith("twin.config.")
                 for t in ts if t in readers)
    assert not bad, "the configuration imports a reader of data files:\n" + "\n".join(bad)


def test_from_package_import_resolves_submodules(tmp_path):
    """``from twin import x`` points to the submodule x, ``from twin.config import X`` to the package."""
    modules = {"twin": tmp_path / "__init__.py", "twin.a": tmp_path / "a.py", "twin.p": tmp_path / "p" / "__init__.py",
               "twin.p.q": tmp_path / "p" / "q.py"}
    src = tmp_path / "b.py"
    src.write_text("import os\nfrom twin import a\nfrom twin.p import Thing\n"
                   "def f():\n    from twin.p import q\n    import twin.p.q.r\n    from . import a\n")
    assert _edges("twin.b", src, modules) == {"twin.a", "twin.p", "twin.p.q"}


def test_find_cycle_finds_one():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": set()}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None
    assert find_cycle({"a": {"b", "c"}, "b": {"c"}, "c": set()}) is None


def test_no_import_cycle():
    cycle = find_cycle(import_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])
