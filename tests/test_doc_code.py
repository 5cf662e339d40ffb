"""The extractor of scripts/check_doc_code.py: which blocks of a page run, in what order, and how a failure reads."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("check_doc_code", ROOT / "scripts" / "check_doc_code.py")
dc = importlib.util.module_from_spec(_spec)
sys.modules["check_doc_code"] = dc  # its dataclasses look their module up
_spec.loader.exec_module(dc)

PAGE = """# A page

```python exec="on" session="s"
hidden = 1  # the build's own setup
```

```python exec="on" source="above" session="s" result="text"
x = 2
```

```toml
[motions]
```

<!-- doc-check: skip (needs a cluster) -->
```bash
dask scheduler
```

```console
$ DATA=../data
$ housner run elcentro \\
    --engines housner
simulating ...
$ echo done
done
```

```python
y = x + 1
```
"""


@pytest.fixture
def page(tmp_path):
    path = tmp_path / "page.md"
    path.write_text(PAGE)
    return path


def test_blocks_kinds_and_lines(page):
    blocks = dc.parse_page(page)
    assert [(b.lang, b.line) for b in blocks] == [
        ("python", 4),
        ("python", 8),
        ("toml", 12),
        ("bash", 17),
        ("console", 21),
        ("python", 30),
    ]
    hidden, shown, toml, skipped, console, plain = blocks
    assert hidden.hidden and not shown.hidden and not plain.hidden
    assert toml.kind == "other"
    assert skipped.skip == "needs a cluster" and console.skip is None
    assert console.commands == [
        (21, "DATA=../data"),
        (22, "housner run elcentro \\\n    --engines housner"),
        (25, "echo done"),
    ]


def test_commands_without_prompts():
    assert dc.shell_commands("# a comment\nhousner tune mujoco --r 0.9\n\npytest\n", 10) == [
        (11, "housner tune mujoco --r 0.9"),
        (13, "pytest"),
    ]


def test_snippet_is_expanded(tmp_path):
    path = tmp_path / "page.md"
    path.write_text('```python\n--8<-- "examples/effects/pivot_friction.py"\n```\n')
    (block,) = dc.parse_page(path)
    assert "register_effect" in block.code


def _checked(tmp_path, text: str) -> dict:
    """What :func:`check_page` finds on a page of ``text`` (git's check off)."""
    path = tmp_path / "page.md"
    path.write_text(text)
    return dc.check_page(path, git_check=False)


def test_names_flow_between_blocks_and_a_failure_names_its_line(tmp_path):
    result = _checked(
        tmp_path, "```python\nx = 2\n```\n\ntext\n\n```python\nassert x == 2\nprint(x)\nundefined_name\n```\n"
    )
    assert result["run"] == 2
    ((where, error),) = result["failures"]
    assert where.endswith("page.md:10")  # the failing line of the second block, in the page's numbering
    assert error == "NameError: name 'undefined_name' is not defined"


def test_a_failing_command_stops_the_page(tmp_path):
    result = _checked(tmp_path, "```console\n$ true\n$ false\n```\n\n```python\nprint('never')\n```\n")
    assert result["run"] == 1
    ((where, error),) = result["failures"]
    assert where.endswith("page.md:3") and "exit status 1" in error
