"""Neither engine imports the other: ``twin.mujoco_engine.*`` never imports ``twin.reference.*``
and the reference engine never imports the MuJoCo twin, at module level or inside a function.
What both need (the contact law constants, the mechanism's effective masses) lives in neutral
modules (``twin.contact_params``, ``twin.natural_coordinates``).

Method: parse every module of both engine packages with :mod:`ast` and collect every import
statement anywhere in it (``import x``, ``from x import y``, relative imports resolved, and
``importlib.import_module("x")`` with a literal name).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import twin

PACKAGE = Path(twin.__file__).parent
ENGINES = {"twin.mujoco_engine": "twin.reference", "twin.reference": "twin.mujoco_engine"}


def _module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imported_modules(path: Path, module: str | None = None) -> set[str]:
    """Every module name ``path`` (the module ``module``, default from its place in the package)
    imports, anywhere in the file (module level, functions, classes). ``from pkg import name``
    counts as importing ``pkg`` and ``pkg.name`` (name may be a submodule)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    me = module or _module_name(path)
    package = me if path.name == "__init__.py" else me.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            found.add(mod)
            found.update(f"{mod}.{a.name}" for a in node.names)
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
              and node.func.attr == "import_module" and node.args
              and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)):
            found.add(node.args[0].value)
    return found


def _engine_modules(package: str) -> list[Path]:
    return sorted((PACKAGE.parent / package.replace(".", "/")).rglob("*.py"))


def _is_within(name: str, package: str) -> bool:
    return name == package or name.startswith(package + ".")


def test_the_walker_sees_local_relative_and_dynamic_imports(tmp_path):
    """The checker itself finds a function-local, a relative and an importlib import."""
    src = tmp_path / "probe.py"
    src.write_text("import math\n"
                   "def f():\n"
                   "    from twin.mujoco_engine.builder import build\n"
                   "class C:\n"
                   "    def g(self):\n"
                   "        from ..mujoco_engine import engine\n"
                   "        importlib.import_module('twin.mujoco_engine.accel')\n")
    found = imported_modules(src, "twin.reference.probe")
    assert {"math", "twin.mujoco_engine.builder", "twin.mujoco_engine", "twin.mujoco_engine.engine",
            "twin.mujoco_engine.accel"} <= found
    assert any(_is_within(n, "twin.mujoco_engine") for n in found)
    # and on a real module: imports inside functions only
    real = imported_modules(PACKAGE / "reference" / "engine.py")
    assert {"twin.drive", "numba"} <= real


@pytest.mark.parametrize("engine", sorted(ENGINES))
def test_engine_does_not_import_the_other_engine(engine):
    other = ENGINES[engine]
    modules = _engine_modules(engine)
    assert modules, f"no modules found for {engine}"
    edges = [f"{_module_name(p)} -> {name}" for p in modules for name in sorted(imported_modules(p))
             if _is_within(name, other)]
    assert not edges, "engine-to-engine imports:\n" + "\n".join(edges)


def test_neutral_contact_modules_import_neither_engine():
    """The shared modules stay neutral, so no engine reaches the other through them."""
    for name in ("contact_params", "natural_coordinates", "impact"):
        found = imported_modules(PACKAGE / f"{name}.py")
        bad = [n for n in found if any(_is_within(n, e) for e in ENGINES)]
        assert not bad, f"twin.{name} imports an engine: {bad}"
