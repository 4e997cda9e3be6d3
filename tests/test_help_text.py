"""The text a user reads stays true: every command, argument and option has help; the presets, the
dataset format version and the view's plot window named in the docs are the code's; the README's
commands need no file of the repository (they run after ``pip install`` outside it)."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

import twin
from twin.cli import build_parser
from twin.config import NAMED_PRESETS
from twin.config.presets import PRESET_SUMMARIES

ROOT = Path(__file__).resolve().parent.parent


def _walk(parser: argparse.ArgumentParser, path: str = "twin"):
    """(command path, what, name, help) for every subcommand, positional argument and option."""
    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            helps = {c.dest: c.help for c in a._choices_actions}
            for name, sub in a.choices.items():
                yield path, "command", name, helps.get(name)
                yield from _walk(sub, f"{path} {name}")
        elif isinstance(a, argparse._HelpAction):
            continue
        else:
            yield path, "option" if a.option_strings else "argument", a.dest, a.help


def test_every_command_argument_and_option_has_help():
    items = list(_walk(build_parser()))
    assert sum(kind == "command" for _, kind, _, _ in items) >= 25  # the walk reaches the nested commands
    missing = [f"{path}: {kind} {name}" for path, kind, name, text in items if not (text or "").strip()]
    assert missing == []


def test_help_describes_studies_not_source_files():
    texts = [build_parser()]
    found = []
    while texts:
        p = texts.pop()
        for a in p._actions:
            if isinstance(a, argparse._SubParsersAction):
                texts += list(a.choices.values())
        if re.search(r"twin/\S+\.py", p.description or ""):
            found.append(p.prog)
    assert found == []


def test_every_preset_file_has_a_summary_and_every_text_names_every_preset():
    assert list(PRESET_SUMMARIES) == list(NAMED_PRESETS)
    simulate_help = build_parser()._subparsers._group_actions[0].choices["simulate"].format_help()
    texts = {
        "README.md": (ROOT / "README.md").read_text(encoding="utf-8"),
        "docs/commands.md": (ROOT / "docs" / "commands.md").read_text(encoding="utf-8"),
        "docs/configuration.md": (ROOT / "docs" / "configuration.md").read_text(encoding="utf-8"),
        "twin.preset's docstring": twin.preset.__doc__,
        "twin simulate --help": re.sub(r"\s+", " ", simulate_help),
    }
    missing = [f"{where}: {name}" for where, text in texts.items() for name in NAMED_PRESETS
               if not re.search(rf"(?<![\w]){re.escape(name)}(?![\w])", text)]
    assert missing == []


def test_the_docs_state_the_code_s_dataset_format_and_plot_window():
    from twin.commands.view import DEFAULT_PLOT_WINDOW_S
    from twin.dataset.generate import FORMAT

    datasets = (ROOT / "docs" / "datasets.md").read_text(encoding="utf-8")
    assert f"versioned `{FORMAT}`" in datasets
    view = (ROOT / "docs" / "view.md").read_text(encoding="utf-8")
    assert f"±{DEFAULT_PLOT_WINDOW_S / 2:g} s window" in view


def _readme_commands() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```bash\n(.*?)```", text, flags=re.S)
    return [line.split("#")[0].strip() for b in blocks for line in b.splitlines()
            if line.strip().startswith("twin ")]


def test_the_readme_s_commands_use_no_file_of_the_repository():
    commands = _readme_commands()
    assert len(commands) > 20
    assert [c for c in commands if re.search(r"recordings/|analysis/|\.toml\b(?<!my_bench\.toml)", c)] == []
    assert any("sample:test6" in c for c in commands) and "twin dataset plan tiny" in commands


@pytest.mark.parametrize("path", ["README.md", *sorted(p.relative_to(ROOT).as_posix()
                                                         for p in (ROOT / "docs").glob("*.md"))])
def test_no_page_points_outside_the_repository(path):
    assert "../shared" not in (ROOT / path).read_text(encoding="utf-8")


def test_docs_index_lists_each_page_once():
    text = (ROOT / "docs" / "index.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| \[([\w.-]+\.md)\]", text, flags=re.M)
    assert len(rows) == len(set(rows))
