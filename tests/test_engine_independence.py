"""No engine imports another, and what they share lives in engine-free modules.

The three engine packages: the planar reference (``twin.reference``), the planar MuJoCo twin
(``twin.mujoco_engine``) and the spatial mechanism in both engines (``twin.spatial``). None imports
another, at module level or inside a function. What they share lives in neutral modules: the
contact laws and the MuJoCo parameters in :mod:`twin.physics`, the native MuJoCo hooks in
:mod:`twin.native`, the contact constants
(``twin.contact_params``, ``twin.impact``) and the planar coordinates (``twin.natural_coordinates``);
these import no engine, and neither does the configuration (``twin.config``).

No edge is allowed, not even inside a function: the native hooks that both MuJoCo models run
(the C module, its colliders and callbacks, and their installer) live in :mod:`twin.native`, a
neutral package that imports no engine, not in either engine's package.

Method: parse every module of the packages with :mod:`ast` and collect every import
statement anywhere in it (``import x``, ``from x import y``, relative imports resolved, and
``importlib.import_module("x")`` with a literal name).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import twin

PACKAGE = Path(twin.__file__).parent
ENGINES = ("twin.reference", "twin.mujoco_engine", "twin.spatial")
#: packages and modules that every engine may use and that import no engine
NEUTRAL = ("twin.physics", "twin.native", "twin.config", "twin.contact_params", "twin.natural_coordinates",
           "twin.impact")


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


def _package_files(name: str) -> list[Path]:
    """The files of a package (all its modules) or of a single module."""
    base = PACKAGE.parent / name.replace(".", "/")
    return sorted(base.rglob("*.py")) if base.is_dir() else [base.with_suffix(".py")]


@pytest.mark.parametrize("engine", ENGINES)
def test_engine_does_not_import_another_engine(engine):
    others = [e for e in ENGINES if e != engine]
    modules = _engine_modules(engine)
    assert modules, f"no modules found for {engine}"
    edges = [f"{_module_name(p)} -> {name}" for p in modules for name in sorted(imported_modules(p))
             if any(_is_within(name, o) for o in others)]
    assert not edges, "engine-to-engine imports:\n" + "\n".join(edges)


def test_both_mujoco_models_reach_the_native_hooks_through_the_neutral_package():
    """The planar and the spatial MuJoCo models install the native hooks from :mod:`twin.native`
    (guards the test above against passing because the hooks moved out of sight)."""
    for engine in ("twin.mujoco_engine", "twin.spatial"):
        used = set().union(*(imported_modules(p) for p in _engine_modules(engine)))
        assert "twin.native.collider" in used, engine
    assert not list((PACKAGE / "mujoco_engine").glob("_bore*")), "the native module is built in twin/native"


@pytest.mark.parametrize("name", NEUTRAL)
def test_neutral_modules_import_no_engine(name):
    """The shared modules and the configuration stay neutral, so no engine reaches another through them."""
    files = _package_files(name)
    assert files and all(f.exists() for f in files), name
    bad = [f"{_module_name(f)} -> {n}" for f in files for n in sorted(imported_modules(f))
           if any(_is_within(n, e) for e in ENGINES)]
    assert not bad, f"{name} imports an engine:\n" + "\n".join(bad)


def test_shared_physics_is_engine_free():
    """``twin.physics`` imports no simulator either (``mujoco``): the engines take numbers from it."""
    bad = [f"{_module_name(f)} -> {n}" for f in _package_files("twin.physics") for n in sorted(imported_modules(f))
           if _is_within(n, "mujoco")]
    assert not bad, "twin.physics imports mujoco:\n" + "\n".join(bad)


def test_the_checker_catches_an_engine_edge_in_the_configuration(tmp_path):
    """The walker flags a configuration module that imports an engine (the check can fail)."""
    src = tmp_path / "probe.py"
    src.write_text("def f(cfg):\n    from twin.spatial.checks import check_spatial\n    check_spatial(cfg)\n")
    found = imported_modules(src, "twin.config.probe")
    assert any(_is_within(n, "twin.spatial") for n in found)


#: the layers above the engines: the library's run loop and sinks, the studies, the commands
ABOVE = ("twin.simulation", "twin.studies", "twin.commands", "twin.cli", "twin.api", "twin.bench_replay",
         "twin.identification", "twin.dataset", "twin.viz", "twin.mcapfile")


@pytest.mark.parametrize("name", ENGINES + NEUTRAL)
def test_no_arrow_back_up(name):
    """Layering: commands -> library -> engines -> shared physics. Neither an engine package nor a
    shared module (nor the configuration) imports the layers above it."""
    files = _package_files(name)
    bad = [f"{_module_name(f)} -> {n}" for f in files for n in sorted(imported_modules(f))
           if any(_is_within(n, a) for a in ABOVE)]
    assert not bad, f"{name} imports a layer above it:\n" + "\n".join(bad)


def _all_modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _closure(start: str, modules: dict[str, Path]) -> set[str]:
    """Every module of the package that ``start`` (a package or module) reaches through imports, at
    any depth (an edge to ``pkg.name`` counts for the longest module it lies in)."""
    def resolve(name: str) -> str | None:
        parts = name.split(".")
        while parts and ".".join(parts) not in modules:
            parts.pop()
        return ".".join(parts) or None

    todo = [m for m in modules if _is_within(m, start)]
    seen: set[str] = set()
    while todo:
        m = todo.pop()
        if m in seen:
            continue
        seen.add(m)
        todo.extend(r for r in map(resolve, imported_modules(modules[m], m)) if r and r not in seen)
    return seen


@pytest.mark.parametrize("name", ENGINES + NEUTRAL)
def test_no_engine_reached_indirectly(name):
    """Through any chain of imports (a neutral module importing a module that imports an engine),
    an engine reaches no other engine, and a neutral module (the configuration included) none."""
    reached = _closure(name, _all_modules())
    bad = sorted(m for m in reached for e in ENGINES if e != name and _is_within(m, e))
    assert not bad, f"{name} reaches another engine through its imports: {bad}"
