"""mkdocs hooks: pages that are written from the code at build time.

- A line ``<!-- cli-help: COMMAND -->`` in a page becomes the ``--help`` of
  ``mesh-normal COMMAND`` as a ``text`` block, from the parser itself, so that the command
  line's page lists every option there is (``<!-- cli-help: mesh-normal -->``: the top level).
- The Sphinx roles of the docstrings (``:func:`orient```) show as the code they mark; ``~``
  keeps the last name only, as Sphinx does.
"""

from __future__ import annotations

import argparse
import functools
import re
from typing import Any

from mesh_normal.cli.commands import parser

MARKER = re.compile(r"^<!-- cli-help: ([\w-]+) -->$", re.M)
ROLE = re.compile(r":(?:func|class|meth|attr|mod|data|obj|exc):<code>(~?)\.?([^<]*)</code>")
WIDTH = 88  # the help's lines, whatever the terminal that builds the site


def commands() -> dict[str, argparse.ArgumentParser]:
    """``mesh-normal`` and each of its sub-commands, by name."""
    main = parser()
    found = {"mesh-normal": main}
    for action in main._actions:
        if isinstance(action, argparse._SubParsersAction):
            found.update(action.choices)
    return found


def command_help(name: str, found: dict[str, argparse.ArgumentParser]) -> str:
    if name not in found:
        raise ValueError(f"<!-- cli-help: {name} -->: mesh-normal has no command {name!r}")
    command = found[name]
    command.formatter_class = functools.partial(argparse.HelpFormatter, width=WIDTH)
    return f"```text\n{command.format_help().rstrip()}\n```"


def on_page_markdown(markdown: str, **_: Any) -> str:
    if not MARKER.search(markdown):
        return markdown
    found = commands()
    return MARKER.sub(lambda match: command_help(match[1], found), markdown)


def on_page_content(html: str, **_: Any) -> str:
    return ROLE.sub(lambda m: f"<code>{m[2].rsplit('.')[-1] if m[1] else m[2]}</code>", html)
