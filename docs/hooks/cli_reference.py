"""mkdocs hook: the CLI reference page, generated from the real argparse parser at build time.

``docs/reference/cli.md`` holds the marker ``<!-- cli-reference -->``; this hook replaces it with the
usage, description, arguments and epilog of ``housner`` and of each subcommand, read from
:func:`housner.cli.app.build_parser`, so that the page cannot drift from the command.

The parser is built in a fresh interpreter (this file run as a script): the registries it lists
(engines, effects, scenarios) are then the installed ones, not those that a page executed earlier in
the build has grown (the tutorial loads an effect plugin).
"""

from __future__ import annotations

import argparse
import html
import os
import subprocess
import sys

MARKER = "<!-- cli-reference -->"
PAGE = "reference/cli.md"
WIDTH = "100"  # columns of the usage lines: the same on every machine


def _cell(text: str) -> str:
    """Text for a Markdown table cell: HTML-escaped, pipes escaped, one line."""
    return html.escape(" ".join(text.split()), quote=False).replace("|", "\\|")


def _invocation(action: argparse.Action) -> str:
    """How an argument is written: ``--out OUT``, ``-q, --quiet``, or a positional's name."""
    if not action.option_strings:
        return action.metavar or action.dest
    if action.nargs == 0:
        return ", ".join(action.option_strings)
    meta = action.metavar or action.dest.upper()
    return ", ".join(f"{opt} {meta}" for opt in action.option_strings)


def _default(action: argparse.Action) -> str:
    if action.nargs == 0 or action.default in (None, argparse.SUPPRESS) or not action.option_strings:
        return ""
    return f"`{action.default}`"


def _arguments(parser: argparse.ArgumentParser) -> list[str]:
    formatter = parser._get_formatter()
    positionals, options = [], []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction) or action.help == argparse.SUPPRESS:
            continue
        helptext = formatter._expand_help(action) if action.help else ""
        row = f"| `{_invocation(action)}` | {_cell(helptext)} | {_default(action)} |"
        (options if action.option_strings else positionals).append(row)
    out = []
    for title, rows in (("Arguments", positionals), ("Options", options)):
        if rows:
            out += [f"**{title}**", "", "| argument | meaning | default |", "|---|---|---|", *rows, ""]
    return out


def _section(parser: argparse.ArgumentParser, title: str, summary: str | None) -> list[str]:
    out = [f"## `{title}`", ""]
    text = parser.description or (summary[0].upper() + summary[1:] + "." if summary else "")
    if text:
        out += [text, ""]
    out += ["```text", parser.format_usage().strip(), "```", ""]
    out += _arguments(parser)
    if parser.epilog:
        out += ["```text", parser.epilog.strip(), "```", ""]
    return out


def render() -> str:
    """The CLI reference as Markdown: ``housner`` itself, then each subcommand in the parser's order."""
    from housner.cli.app import build_parser

    parser = build_parser(full_help=True)
    lines = _section(parser, parser.prog, None)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            summaries = {a.dest: a.help for a in action._choices_actions}
            for name, sub in action.choices.items():
                lines += _section(sub, f"{parser.prog} {name}", summaries.get(name))
    return "\n".join(lines)


def render_fresh() -> str:
    """:func:`render` in a fresh interpreter, with usage lines :data:`WIDTH` columns wide."""
    env = {**os.environ, "COLUMNS": WIDTH}
    done = subprocess.run([sys.executable, __file__], capture_output=True, text=True, env=env, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"the CLI reference could not be generated:\n{done.stderr}")
    return done.stdout


def on_page_markdown(markdown: str, page, config, files) -> str:
    """Replace the marker of the CLI reference page with the generated reference."""
    if page.file.src_uri != PAGE:
        return markdown
    if MARKER not in markdown:
        raise ValueError(f"{PAGE} lost its marker {MARKER!r}: the generated CLI reference has nowhere to go")
    return markdown.replace(MARKER, render_fresh())


if __name__ == "__main__":
    sys.stdout.write(render())
