"""The command line's page shows the help of every command, from the parser itself: the mkdocs
hook (docs/hooks.py) replaces each ``<!-- cli-help: COMMAND -->`` marker with it."""

from __future__ import annotations

import argparse
import importlib.util
from types import ModuleType

import pytest

from tests.paths import ROOT


def load_hooks() -> ModuleType:
    spec = importlib.util.spec_from_file_location("docs_hooks", ROOT / "docs" / "hooks.py")
    assert spec is not None and spec.loader is not None
    hooks = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hooks)
    return hooks


HOOKS = load_hooks()
PAGE = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
BUILT = HOOKS.on_page_markdown(PAGE)
COMMANDS = HOOKS.commands()


def test_the_parser_has_its_sub_commands() -> None:
    assert {"analyze", "fix", "export", "normals", "points", "batch", "serve"} <= set(COMMANDS)


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_command_s_help_is_on_the_page(name: str) -> None:
    usage = "usage: mesh-normal" if name == "mesh-normal" else f"usage: mesh-normal {name} "
    assert usage in BUILT, f"docs/cli.md needs <!-- cli-help: {name} -->"


@pytest.mark.parametrize("name", sorted(set(COMMANDS) - {"mesh-normal"}))
def test_every_option_of_a_command_is_on_the_page(name: str) -> None:
    for action in COMMANDS[name]._actions:
        if action.help == argparse.SUPPRESS:  # accepted for old scripts, not shown
            continue
        for option in action.option_strings:
            assert option in BUILT, f"mesh-normal {name} {option}"


def test_no_marker_is_left_and_the_help_is_a_text_block() -> None:
    assert "cli-help" not in BUILT
    assert "```text\nusage: mesh-normal analyze " in BUILT


def test_an_unknown_command_fails_the_build() -> None:
    with pytest.raises(ValueError, match="no command 'nonexistent'"):
        HOOKS.on_page_markdown("<!-- cli-help: nonexistent -->\n")


def test_a_page_without_markers_is_left_alone() -> None:
    assert HOOKS.on_page_markdown("# Title\n\ntext\n") == "# Title\n\ntext\n"
