"""Run the code of the tutorial and the how-to guides as a reader would paste it, from the repository root.

For every page, the code blocks a reader sees are run in the order of the page:

- the ``python`` blocks in one fresh interpreter (each block fed to it in turn, so a name defined by one block
  is there for the next), markdown-exec blocks with ``source=`` included: what the page shows is what runs;
- the commands of the ``console``, ``bash``, ``sh`` and ``shell`` blocks, each in ``bash`` from the repository
  root (a leading ``$ `` is stripped; in a block with prompts, the lines without one are output; a line
  ending in ``\\`` continues on the next; ``NAME=value`` alone on a line holds for the page's later commands).

Not run: blocks in other languages (TOML, text, ...), and markdown-exec blocks that the page does not show (no
``source=``: the build's own setup and figure embedding). A block that cannot run on a CI machine (a cluster,
the network, data that do not ship, an hour's run) is skipped only where the page says so, in a comment a
maintainer sees just above it::

    <!-- doc-check: skip (needs a Dask cluster) -->

Every skip is listed with its reason. After each page, ``git status --porcelain`` must be what it was before:
whatever a documented command writes goes to a folder git ignores (``runs/``).

Usage::

    python scripts/check_doc_code.py                      # the tutorial and every how-to
    python scripts/check_doc_code.py --page docs/how-to/studies.md --page docs/tutorial.md
    python scripts/check_doc_code.py --list               # the blocks, without running them

Exit status 1 when a block fails or a page leaves the repository changed; each failure is printed as
``page:line: the error's last line``.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: the pages checked when none is given; a listed page that does not exist is left out (it may not be written yet)
DEFAULT_PAGES = ("docs/tutorial.md", "docs/how-to/*.md", "docs/reference/effects-api.md")
PYTHON = {"python", "py", "python3"}
SHELL = {"console", "bash", "sh", "shell", "shell-session"}
FENCE = re.compile(r"^(?P<indent>[ \t]*)(?P<fence>`{3,}|~{3,})(?P<info>.*)$")
SKIP = re.compile(r"<!--\s*doc-check:\s*skip\s*\((?P<reason>.+?)\)\s*-->")
SNIPPET = re.compile(r'^\s*--8<--\s+"(?P<path>[^"]+)"\s*$')
ASSIGNMENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*=\S*$")


@dataclass
class Block:
    """One fenced code block of a page."""

    page: str
    line: int  #: the line of the block's first line of code (1-based)
    lang: str
    info: str
    code: str
    skip: str | None = None  #: the reason the page gives for not running it
    hidden: bool = False  #: a markdown-exec block the page does not show
    commands: list[tuple[int, str]] = field(default_factory=list)  #: (line, command) of a shell block

    @property
    def kind(self) -> str:
        if self.lang in PYTHON:
            return "python"
        return "shell" if self.lang in SHELL else "other"


def _attrs(info: str) -> dict[str, str]:
    return {k: v for k, v in re.findall(r'([\w-]+)="([^"]*)"', info)}


def _expand_snippets(code: str, page: str, line: int) -> str:
    out = []
    for i, text in enumerate(code.splitlines()):
        m = SNIPPET.match(text)
        if m:
            path = ROOT / m["path"]
            if not path.is_file():
                raise SystemExit(f"{page}:{line + i}: the snippet {m['path']!r} does not exist")
            out.append(path.read_text().rstrip("\n"))
        else:
            out.append(text)
    return "\n".join(out) + "\n"


def shell_commands(code: str, first_line: int) -> list[tuple[int, str]]:
    """The commands of a console block: ``(line, command)``, prompts stripped and continuations joined."""
    lines = code.splitlines()
    prompted = any(t.lstrip().startswith("$ ") or t.strip() == "$" for t in lines)
    commands: list[tuple[int, str]] = []
    pending: tuple[int, str] | None = None
    for i, text in enumerate(lines):
        n = first_line + i
        if pending is not None:  # the previous line ended in a backslash
            pending = (pending[0], pending[1] + "\n" + text)
        elif prompted:
            stripped = text.lstrip()
            if not stripped.startswith("$"):
                continue  # output
            pending = (n, stripped[1:].lstrip())
        else:
            if not text.strip() or text.lstrip().startswith("#"):
                continue
            pending = (n, text)
        if not pending[1].rstrip().endswith("\\"):
            commands.append(pending)
            pending = None
    if pending is not None:
        commands.append(pending)
    return commands


def parse_page(path: Path) -> list[Block]:
    """The fenced code blocks of a Markdown page, in order, with the skips its comments declare."""
    page = os.path.relpath(path, ROOT) if path.is_absolute() else str(path)
    lines = path.read_text().splitlines()
    blocks: list[Block] = []
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence, indent, info = m["fence"], len(m["indent"]), m["info"].strip()
        start = i
        body: list[str] = []
        i += 1
        while i < len(lines):
            end = FENCE.match(lines[i])
            if end and end["fence"][0] == fence[0] and len(end["fence"]) >= len(fence) and not end["info"].strip():
                break
            body.append(lines[i][indent:] if lines[i][:indent].strip() == "" else lines[i].lstrip())
            i += 1
        i += 1
        lang = info.split()[0].lower() if info else ""
        lang = lang.lstrip("{.").rstrip("}")
        attrs = _attrs(info)
        prev = next((lines[j] for j in range(start - 1, -1, -1) if lines[j].strip()), "")
        skip = SKIP.search(prev)
        code = "\n".join(body) + "\n"
        if lang in PYTHON:
            code = _expand_snippets(code, page, start + 2)
        executed = attrs.get("exec", "").lower() in ("on", "1", "true", "yes")
        block = Block(
            page=page,
            line=start + 2,
            lang=lang,
            info=info,
            code=code,
            skip=skip["reason"] if skip else None,
            hidden=executed and attrs.get("source", "") in ("", "none"),
        )
        if block.kind == "shell":
            block.commands = shell_commands(code, block.line)
        blocks.append(block)
    return blocks


# The interpreter that runs a page's python blocks: it reads one block per line of JSON on stdin, runs it in one
# namespace (as if typed into the interpreter: __name__ is "__main__"), and answers on the status pipe.
DRIVER = r"""
import json, os, sys, traceback
if __name__ == "__main__":
    status = os.fdopen(int(sys.argv[1]), "w")
    ns = {"__name__": "__main__", "__builtins__": __builtins__}
    for raw in sys.stdin:
        msg = json.loads(raw)
        try:
            # "<page>", not the page's path: as typed into an interpreter, the code has no source file
            exec(compile("\n" * (msg["line"] - 1) + msg["code"], f"<{msg['page']}>", "exec"), ns)
            answer = {"ok": True}
        except BaseException as exc:  # noqa: BLE001 - every failure is reported, SystemExit included
            traceback.print_exc()
            last = traceback.format_exception_only(type(exc), exc)[-1].strip()
            tb = [f for f in traceback.extract_tb(exc.__traceback__) if f.filename == f"<{msg['page']}>"]
            answer = {"ok": False, "error": last, "line": tb[-1].lineno if tb else msg["line"]}
        sys.stdout.flush()
        sys.stderr.flush()
        status.write(json.dumps(answer) + "\n")
        status.flush()
"""


class Interpreter:
    """One fresh ``python`` process at the repository root, fed a page's python blocks one by one."""

    def __init__(self, log):
        read, write = os.pipe()
        self.proc = subprocess.Popen(
            [sys.executable, "-c", DRIVER, str(write)],
            cwd=ROOT,
            stdin=subprocess.PIPE,
            stdout=log,
            stderr=subprocess.STDOUT,
            pass_fds=(write,),
            text=True,
            env={**os.environ, "MPLBACKEND": "Agg"},
        )
        os.close(write)
        self.status = os.fdopen(read)

    def run(self, block: Block) -> dict:
        self.proc.stdin.write(json.dumps({"page": block.page, "line": block.line, "code": block.code}) + "\n")
        self.proc.stdin.flush()
        answer = self.status.readline()
        if not answer:
            return {"ok": False, "error": f"the interpreter died (exit status {self.proc.wait()})", "line": block.line}
        return json.loads(answer)

    def close(self) -> None:
        self.proc.stdin.close()
        self.proc.wait()
        self.status.close()


def git_status() -> str:
    return subprocess.run(
        ["git", "status", "--porcelain", "--untracked-files=all"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout


def last_line(text: str) -> str:
    lines = [t.strip() for t in text.splitlines() if t.strip()]
    return lines[-1] if lines else "(no output)"


def check_page(path: Path, verbose: bool = False, git_check: bool = True) -> dict:
    """Run one page's visible blocks; returns its counts, its failures and its skips.

    ``git_check``: compare ``git status --porcelain`` before and after the page (a failure when it changed).
    """
    blocks = parse_page(path)
    page = blocks[0].page if blocks else str(path)
    result = {"page": page, "run": 0, "skipped": [], "failures": [], "seconds": 0.0, "blocks": []}
    t0 = time.perf_counter()
    before = git_status() if git_check else ""
    env = {**os.environ, "MPLBACKEND": "Agg"}
    assignments: list[str] = []  # NAME=value lines of the page's console blocks, for its later commands
    with tempfile.TemporaryFile("w+") as log:
        interp: Interpreter | None = None
        for b in blocks:
            if b.kind == "other" or b.hidden:
                continue
            if b.skip:
                result["skipped"].append((f"{b.page}:{b.line}", b.skip))
                continue
            tb = time.perf_counter()
            if b.kind == "python":
                interp = interp or Interpreter(log)
                answer = interp.run(b)
                result["run"] += 1
                result["blocks"].append((f"{b.page}:{b.line}", time.perf_counter() - tb))
                if not answer["ok"]:
                    result["failures"].append((f"{b.page}:{answer['line']}", answer["error"]))
                    break
                continue
            failed = False
            for line, cmd in b.commands:
                if ASSIGNMENT.match(cmd.strip()):
                    assignments.append(cmd.strip())
                    continue
                script = "set -euo pipefail\n" + "".join(f"export {a}\n" for a in assignments) + cmd
                log.write(f"\n$ {cmd}\n")
                log.flush()
                proc = subprocess.run(["bash", "-c", script], cwd=ROOT, env=env, capture_output=True, text=True)
                log.write(proc.stdout + proc.stderr)
                log.flush()
                if proc.returncode != 0:
                    program = shlex.split(cmd)[0] if cmd.split() else cmd
                    error = f"`{program}` exit status {proc.returncode}: {last_line(proc.stderr or proc.stdout)}"
                    result["failures"].append((f"{b.page}:{line}", error))
                    failed = True
                    break
            result["run"] += 1
            result["blocks"].append((f"{b.page}:{b.line}", time.perf_counter() - tb))
            if failed:
                break
        if interp is not None:
            interp.close()
        if verbose or result["failures"]:
            log.seek(0)
            text = log.read()
            if verbose:
                print(text, end="")
            elif text.strip():
                print(f"--- {page}: the last lines of its output\n" + "\n".join(text.splitlines()[-25:]))
    after = git_status() if git_check else ""
    if after != before:
        new = sorted(set(after.splitlines()) - set(before.splitlines()))
        changed = "; ".join(new or ["(lines removed)"])
        result["failures"].append((page, f"git status changed after the page's commands: {changed}"))
    result["seconds"] = time.perf_counter() - t0
    return result


def default_pages() -> list[Path]:
    pages: list[Path] = []
    for pattern in DEFAULT_PAGES:
        pages += sorted(ROOT.glob(pattern))
    return pages


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument(
        "--page",
        action="append",
        type=Path,
        metavar="FILE",
        help="a Markdown page to check (repeatable); default: the tutorial and every how-to",
    )
    ap.add_argument("--list", action="store_true", help="list each page's blocks and what would be done with them")
    ap.add_argument("-v", "--verbose", action="store_true", help="print everything the blocks print")
    args = ap.parse_args(argv)
    pages = [p if p.is_absolute() else (Path.cwd() / p).resolve() for p in args.page] if args.page else default_pages()
    for p in pages:
        if not p.is_file():
            print(f"check_doc_code: error: --page {p}: no such file", file=sys.stderr)
            return 2
    if args.list:
        for p in pages:
            for b in parse_page(p):
                what = (
                    "not code"
                    if b.kind == "other"
                    else "hidden (build only)"
                    if b.hidden
                    else f"skip ({b.skip})"
                    if b.skip
                    else f"run {b.kind}"
                )
                extra = f" {len(b.commands)} command(s)" if b.kind == "shell" and what.startswith("run") else ""
                print(f"{b.page}:{b.line}: {b.lang or '-'}: {what}{extra}")
        return 0
    results = []
    total = time.perf_counter()
    for p in pages:
        r = check_page(p, args.verbose)
        results.append(r)
        state = "FAIL" if r["failures"] else "ok"
        print(
            f"{state:4s} {r['page']}: {r['run']} block(s) run, {len(r['skipped'])} skipped, {r['seconds']:.0f} s",
            flush=True,
        )
        for where, error in r["failures"]:
            print(f"  {where}: {error}", flush=True)
    skips = [s for r in results for s in r["skipped"]]
    if skips:
        print("skipped, as the pages declare:")
        for where, reason in skips:
            print(f"  {where}: {reason}")
    slowest = sorted((s for r in results for s in r["blocks"]), key=lambda s: -s[1])[:5]
    if slowest:
        print("the slowest blocks: " + ", ".join(f"{where} {sec:.0f} s" for where, sec in slowest))
    failures = [f for r in results for f in r["failures"]]
    print(
        f"{len(results)} page(s), {sum(r['run'] for r in results)} block(s) run, {len(skips)} skipped, "
        f"{len(failures)} failure(s), {time.perf_counter() - total:.0f} s"
    )
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
