"""The library knows no command line: only ``twin/commands/`` and ``twin/cli.py`` speak in flags.

* No module outside them imports ``argparse``, ``twin.cli`` or ``twin.commands`` (read with :mod:`ast`,
  every import statement, module level and function-local alike).
* No error the library raises names a ``--flag``: its field is the parameter's or configuration
  field's own name (a Python argument, a dotted TOML path), and no parameter defaults to a flag.
  The CLI maps field names to its flags (:func:`twin.cli.error_message`), so a user of the command
  line still reads the flag.
"""

from __future__ import annotations

import argparse
import ast
import re
from pathlib import Path

import pytest

import twin
from twin.cli import error_message
from twin.errors import ConfigError, TwinError

ROOT = Path(twin.__file__).resolve().parent
#: a command-line flag inside a string: --name (not a dash rule, not a decrement)
FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]*")


def _library_modules() -> list[Path]:
    return [p for p in sorted(ROOT.rglob("*.py"))
            if p.relative_to(ROOT).parts[0] != "commands" and p.relative_to(ROOT).as_posix() != "cli.py"]


LIBRARY = _library_modules()
IDS = [p.relative_to(ROOT.parent).as_posix() for p in LIBRARY]


def _imports(tree: ast.AST) -> list[tuple[int, str]]:
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            out.append((node.lineno, node.module))
            out += [(node.lineno, f"{node.module}.{a.name}") for a in node.names]
    return out


def cli_imports(source: str) -> list[str]:
    """``line: name`` of every import of argparse, twin.cli or twin.commands in ``source``."""
    bad = []
    for line, name in _imports(ast.parse(source)):
        if name == "argparse" or name.startswith("argparse.") or name in ("twin.cli", "twin.commands") \
                or name.startswith(("twin.cli.", "twin.commands.")):
            bad.append(f"{line}: {name}")
    return bad


def _error_calls(tree: ast.AST):
    """The expressions of ``raise X`` and every call of a name ending in ``Error`` (errors built to be
    returned or raised later)."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Raise) and node.exc is not None:
            yield node.exc
        elif isinstance(node, ast.Call):
            name = getattr(node.func, "id", None) or getattr(node.func, "attr", "")
            if name.endswith("Error"):
                yield node


def flags_named(source: str) -> list[str]:
    """``line: flags`` of every string of an error the source builds that names a ``--flag``, and of
    every parameter default that is a flag."""
    tree = ast.parse(source)
    found: dict[int, list[str]] = {}
    for expr in _error_calls(tree):
        for sub in ast.walk(expr):
            if isinstance(sub, ast.Constant) and isinstance(sub.value, str) and FLAG.search(sub.value):
                found.setdefault(sub.lineno, []).extend(FLAG.findall(sub.value))
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for d in node.args.defaults + [d for d in node.args.kw_defaults if d is not None]:
                if isinstance(d, ast.Constant) and isinstance(d.value, str) and FLAG.fullmatch(d.value):
                    found.setdefault(d.lineno, []).append(d.value)
    return [f"{line}: {', '.join(sorted(set(f)))}" for line, f in sorted(found.items())]


def test_the_scans_find_what_they_look_for():
    """The two scans below can fail: each finds its target in a sample source, and nothing in a clean one."""
    bad = ('import argparse\n'
           'def f(x, flag="--out"):\n'
           '    from twin.commands.inputs import spec\n'
           '    if x:\n'
           '        raise ConfigError("--starts", "must be >= 1")\n'
           '    return TwinError(f"--window: {x} is outside the run")\n')
    assert cli_imports(bad) == ["1: argparse", "3: twin.commands.inputs", "3: twin.commands.inputs.spec"]
    assert flags_named(bad) == ["2: --out", "5: --starts", "6: --window"]
    good = ('import math\n'
            'def f(x, field="out"):\n'
            '    raise ConfigError("starts", "must be >= 1 (a dash -- here is no flag)")\n')
    assert cli_imports(good) == [] and flags_named(good) == []


@pytest.mark.parametrize("path", LIBRARY, ids=IDS)
def test_the_library_imports_no_cli(path):
    assert cli_imports(path.read_text(encoding="utf-8")) == [], path


@pytest.mark.parametrize("path", LIBRARY, ids=IDS)
def test_library_errors_name_fields_not_flags(path):
    assert flags_named(path.read_text(encoding="utf-8")) == [], path


# ------------------------------------------------------------------ the CLI's translation
def _args(**kw) -> argparse.Namespace:
    return argparse.Namespace(**kw)


def test_the_cli_names_the_flag_of_a_field_it_sets():
    flags = {"max_lag": "--max-lag", "test": "--test", "out": "--out", "output_rate": "--output-rate"}
    err = ConfigError("max_lag_s", "must lie in [0, 0.5] s, got 5.0")
    # by dest, less the unit suffix, when the option has a value
    assert error_message(err, _args(_flags=flags, max_lag=5.0)) == "--max-lag: must lie in [0, 0.5] s, got 5.0"
    # an option left unset did not give the value: test = 13 in a --config file is the file's key
    err = ConfigError("test", "must be a Table 4 test id 1..12, got 13")
    assert error_message(err, _args(_flags=flags, test=None)) == "test: must be a Table 4 test id 1..12, got 13"
    assert error_message(err, _args(_flags=flags, test=13)) == "--test: must be a Table 4 test id 1..12, got 13"
    # an explicit map for a name spelt otherwise; any TwinError with a field
    err = TwinError("unknown target channel 'x'", field="mapping")
    assert error_message(err, _args(_flags={}, _field_flags={"mapping": "--map"})) == \
        "--map: unknown target channel 'x'"
    # names between backticks in the text; a configuration field names its option too
    err = TwinError("no time column; give the sample rate (`rate_hz`); or set `sensors.output_rate_hz`")
    assert error_message(err, _args(_flags={"rate": "--rate", "output_rate": "--output-rate"}, rate=None)) == \
        "no time column; give the sample rate (--rate); or set sensors.output_rate_hz or --output-rate"
    # a name the command has no option for stays the library's; no arguments: the library's text
    err = ConfigError("joints.clearance_b_mm", "must be >= 0")
    assert error_message(err, _args(_flags=flags)) == str(err) == error_message(err)


def test_an_error_keeps_its_field_through_pickling():
    """Errors raised in worker processes reach the parent with their field (dataset generation, studies)."""
    import pickle

    err = pickle.loads(pickle.dumps(TwinError("must be >= 1", field="workers")))
    assert (str(err), err.field, err.message) == ("workers: must be >= 1", "workers", "must be >= 1")
    assert TwinError("plain").field is None


def test_every_field_map_of_a_command_names_its_own_options():
    """``_field_flags`` (library name -> option) of every command names an option of that command, or its
    positional arguments' metavar: a typo would print a flag the command does not have."""
    from twin.cli import _leaf_parsers, build_parser

    checked = 0
    for leaf in _leaf_parsers(build_parser()):
        names = {s for a in leaf._actions for s in a.option_strings}
        names |= {f"{a.metavar}..." if a.nargs == "+" else str(a.metavar) for a in leaf._actions if not a.option_strings}
        for field, flag in (leaf._defaults.get("_field_flags") or {}).items():
            assert flag in names, (leaf.prog, field, flag)
            checked += 1
    assert checked >= 10
