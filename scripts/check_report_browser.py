#!/usr/bin/env python3
"""Open an HTML report in headless Chromium, fail on console errors, and take a screenshot.

Usage::

    python scripts/check_report_browser.py runs/elcentro/report.html --screenshot report.png
    python scripts/check_report_browser.py report.html --screenshot cdf.png --section distribution
    python scripts/check_report_browser.py report.html --screenshot shot.png --section verdict --section table2-gap

With several ``--section`` (any element id), each is written next to the
screenshot path with its id appended: ``shot-verdict.png``, ``shot-table2-gap.png``.

The page is loaded from disk in Debian's ``chromium`` (``apt-get install -y
chromium``) with networking features off and a fresh profile, driven over the
DevTools protocol (a minimal WebSocket client from the standard library, so
nothing beyond Python is needed). The check fails (exit status 1) when:

- the page does not load (missing file, navigation error, no load event in time);
- anything is logged as an error: console errors, uncaught exceptions,
  browser log entries of level "error" (e.g. a resource that failed to load);
- a request leaves the machine (http, https, ws): the report must be self-contained;
- an image is broken (not decoded or zero width).

Exit status 2 means the check could not run (no Chromium, bad arguments).
"""

from __future__ import annotations

import argparse
import base64
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.parse
from pathlib import Path

CHROMIUM_CANDIDATES = ("/usr/bin/chromium", "chromium", "chromium-browser", "google-chrome", "google-chrome-stable")

#: Flags for a quiet, reproducible, offline browser (no first-run UI, no background traffic).
CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--no-default-browser-check",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-extensions",
    "--disable-dev-shm-usage",
    "--hide-scrollbars",
    "--mute-audio",
)

#: Page width of the screenshot [CSS px]; the report's main column is 1080 px wide.
VIEW_WIDTH = 1200
VIEW_HEIGHT = 900


def find_chromium(explicit: str | None = None) -> str | None:
    """Path of a Chromium executable, or None."""
    for c in (explicit,) if explicit else CHROMIUM_CANDIDATES:
        if c and (os.path.isfile(c) and os.access(c, os.X_OK) or shutil.which(c)):
            return c if os.path.isfile(c) else shutil.which(c)
    return None


# ----------------------------------------------------------------------------
# a minimal WebSocket client (RFC 6455), enough for the DevTools protocol on localhost
class WebSocket:
    """Text-frame WebSocket client over a plain TCP socket (no TLS, no extensions)."""

    def __init__(self, url: str, timeout: float = 30.0):
        u = urllib.parse.urlparse(url)
        if u.scheme != "ws" or not u.hostname or not u.port:
            raise ValueError(f"expected a ws://host:port/... URL, got {url!r}")
        self.sock = socket.create_connection((u.hostname, u.port), timeout=timeout)
        key = base64.b64encode(os.urandom(16)).decode()
        request = (
            f"GET {u.path or '/'} HTTP/1.1\r\nHost: {u.hostname}:{u.port}\r\nUpgrade: websocket\r\n"
            f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n"
        )
        self.sock.sendall(request.encode())
        self._buf = bytearray()
        while b"\r\n\r\n" not in self._buf:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise ConnectionError("connection closed during the WebSocket handshake")
            self._buf += chunk
        head, _, rest = bytes(self._buf).partition(b"\r\n\r\n")
        self._buf = bytearray(rest)
        status = head.split(b"\r\n", 1)[0]
        if b" 101 " not in status + b" ":
            raise ConnectionError(f"WebSocket handshake refused: {status.decode(errors='replace')}")

    def _read(self, n: int) -> bytes:
        while len(self._buf) < n:
            chunk = self.sock.recv(max(65536, n - len(self._buf)))
            if not chunk:
                raise ConnectionError("WebSocket connection closed")
            self._buf += chunk
        out = bytes(self._buf[:n])
        del self._buf[:n]
        return out

    def _send_frame(self, opcode: int, payload: bytes) -> None:
        header = bytearray([0x80 | opcode])
        n = len(payload)
        if n < 126:
            header.append(0x80 | n)
        elif n < 1 << 16:
            header.append(0x80 | 126)
            header += n.to_bytes(2, "big")
        else:
            header.append(0x80 | 127)
            header += n.to_bytes(8, "big")
        mask = os.urandom(4)
        # Clients must mask every frame; XOR with the key repeated over the payload.
        key = (mask * (n // 4 + 1))[:n]
        masked = (int.from_bytes(payload, "big") ^ int.from_bytes(key, "big")).to_bytes(n, "big") if n else b""
        self.sock.sendall(bytes(header) + mask + masked)

    def send(self, text: str) -> None:
        self._send_frame(0x1, text.encode())

    def recv(self) -> str:
        message = bytearray()
        while True:
            b0, b1 = self._read(2)
            opcode = b0 & 0x0F
            n = b1 & 0x7F
            if n == 126:
                n = int.from_bytes(self._read(2), "big")
            elif n == 127:
                n = int.from_bytes(self._read(8), "big")
            mask = self._read(4) if b1 & 0x80 else None
            data = self._read(n)
            if mask:
                data = bytes(b ^ mask[i % 4] for i, b in enumerate(data))
            if opcode == 0x8:
                raise ConnectionError("WebSocket closed by the browser")
            if opcode == 0x9:
                self._send_frame(0xA, data)
                continue
            if opcode in (0x0, 0x1, 0x2):
                message += data
                if b0 & 0x80:
                    return message.decode("utf-8", errors="replace")

    def settimeout(self, seconds: float) -> None:
        self.sock.settimeout(seconds)

    def close(self) -> None:
        try:
            self._send_frame(0x8, b"")
        except OSError:
            pass
        self.sock.close()


class DevTools:
    """Calls and events of the Chrome DevTools protocol over one browser connection."""

    def __init__(self, ws: WebSocket):
        self.ws = ws
        self.next_id = 0
        self.events: list[dict] = []

    def _pump(self, timeout: float) -> dict | None:
        self.ws.settimeout(max(timeout, 0.01))
        try:
            msg = json.loads(self.ws.recv())
        except TimeoutError:  # socket.timeout is TimeoutError since Python 3.10
            return None
        if "method" in msg:
            self.events.append(msg)
        return msg

    def call(self, method: str, params: dict | None = None, session: str | None = None, timeout: float = 30.0):
        self.next_id += 1
        mid = self.next_id
        msg = {"id": mid, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        self.ws.send(json.dumps(msg))
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            reply = self._pump(end - time.monotonic())
            if reply is not None and reply.get("id") == mid:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error'].get('message', reply['error'])}")
                return reply.get("result", {})
        raise TimeoutError(f"no reply to {method} within {timeout:.0f} s")

    def wait_event(self, name: str, timeout: float) -> dict | None:
        end = time.monotonic() + timeout
        seen = len(self.events)
        while True:
            for ev in self.events[seen:]:
                if ev["method"] == name:
                    return ev
            seen = len(self.events)
            left = end - time.monotonic()
            if left <= 0:
                return None
            self._pump(left)

    def drain(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self._pump(end - time.monotonic())


# ----------------------------------------------------------------------------
_PAGE_FACTS = """(() => {
  const imgs = Array.from(document.images);
  return JSON.stringify({
    title: document.title,
    readyState: document.readyState,
    images: imgs.length,
    broken: imgs.filter(i => !i.complete || i.naturalWidth === 0).map(i => i.alt || i.src.slice(0, 60)),
    sections: Array.from(document.querySelectorAll('section[id]')).map(s => s.id),
    height: Math.ceil(document.documentElement.scrollHeight),
  });
})()"""

_EXTERNAL = re.compile(r"^(https?|wss?|ftp):", re.IGNORECASE)


def _describe_event(ev: dict) -> str | None:
    """An error message for an event that means a problem, else None."""
    m, p = ev["method"], ev.get("params", {})
    if m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
        args = " ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", []))
        return f"console.{p['type']}: {args}"
    if m == "Runtime.exceptionThrown":
        d = p.get("exceptionDetails", {})
        desc = (d.get("exception") or {}).get("description") or d.get("text", "")
        return f"uncaught exception: {desc} (line {d.get('lineNumber', '?')})"
    if m == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
        e = p["entry"]
        return f"browser log ({e.get('source', '')}): {e.get('text', '')} {e.get('url', '')}".rstrip()
    if m == "Network.loadingFailed" and not p.get("canceled"):
        return f"failed to load a resource: {p.get('errorText', '')} ({p.get('type', '')})"
    if m == "Network.requestWillBeSent":
        url = p.get("request", {}).get("url", "")
        if _EXTERNAL.match(url):
            return f"request to an external resource: {url}"
    return None


def check(
    page: Path,
    screenshot: Path | None = None,
    *,
    section: str | list[str] | None = None,
    chromium: str | None = None,
    timeout: float = 60.0,
) -> tuple[list[str], dict]:
    """Load ``page`` in headless Chromium; return the problems found and facts about the page.

    Parameters
    ----------
    page : pathlib.Path
        HTML file to open.
    screenshot : pathlib.Path, optional
        PNG to write: the full page, or only the section with id ``section``.
    section : str or list of str, optional
        Id of the element to photograph; with several ids, one PNG each, named
        ``<screenshot stem>-<id><suffix>`` (see :func:`shot_paths`). The
        ``screenshots`` entry of the returned facts lists the files written.
    chromium : str, optional
        Browser executable (default: the first of /usr/bin/chromium, chromium, ...).
    timeout : float
        Seconds allowed for the browser to start and the page to load.
    """
    exe = find_chromium(chromium)
    if exe is None:
        raise FileNotFoundError("no Chromium found; on Debian: apt-get install -y chromium")
    page = Path(page).resolve()
    problems: list[str] = []
    if not page.is_file():
        return [f"page not found: {page}"], {}
    profile = tempfile.mkdtemp(prefix="housner-chromium-")
    cmd = [
        exe,
        *CHROMIUM_FLAGS,
        f"--user-data-dir={profile}",
        "--remote-debugging-port=0",
        f"--window-size={VIEW_WIDTH},{VIEW_HEIGHT}",
        "about:blank",
    ]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    stderr_lines: list[str] = []
    found = threading.Event()
    url_box: list[str] = []

    def read_stderr() -> None:
        for line in proc.stderr:
            stderr_lines.append(line.rstrip())
            m = re.search(r"DevTools listening on (ws://\S+)", line)
            if m and not found.is_set():
                url_box.append(m.group(1))
                found.set()

    reader = threading.Thread(target=read_stderr, daemon=True)
    reader.start()
    ws = None
    facts: dict = {}
    try:
        if not found.wait(timeout):
            tail = "\n".join(stderr_lines[-10:])
            raise RuntimeError(f"Chromium did not open its DevTools port within {timeout:.0f} s:\n{tail}")
        ws = WebSocket(url_box[0], timeout=timeout)
        cdp = DevTools(ws)
        target = cdp.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = cdp.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        for domain in ("Runtime", "Log", "Network", "Page"):
            cdp.call(f"{domain}.enable", session=session)
        cdp.call(
            "Emulation.setDeviceMetricsOverride",
            {"width": VIEW_WIDTH, "height": VIEW_HEIGHT, "deviceScaleFactor": 1, "mobile": False},
            session=session,
        )
        nav = cdp.call("Page.navigate", {"url": page.as_uri()}, session=session, timeout=timeout)
        if nav.get("errorText"):
            problems.append(f"page failed to load: {nav['errorText']}")
        elif cdp.wait_event("Page.loadEventFired", timeout) is None:
            problems.append(f"no load event within {timeout:.0f} s")
        cdp.drain(0.3)  # late console messages and resource errors
        res = cdp.call("Runtime.evaluate", {"expression": _PAGE_FACTS, "returnByValue": True}, session=session)
        facts = json.loads(res.get("result", {}).get("value", "{}"))
        if facts.get("broken"):
            problems.append(f"broken image(s): {', '.join(map(str, facts['broken']))}")
        for ev in cdp.events:
            msg = _describe_event(ev)
            if msg:
                problems.append(msg)
        facts["screenshots"] = []
        for sec, path in shot_paths(screenshot, section) if screenshot is not None else ():
            clip = {"x": 0, "y": 0, "width": VIEW_WIDTH, "height": max(int(facts.get("height", VIEW_HEIGHT)), 1)}
            if sec:
                expr = (
                    f"(() => {{ const e = document.getElementById({json.dumps(sec)}); if (!e) return null; "
                    "const r = e.getBoundingClientRect(); "
                    "return JSON.stringify({x: r.left + scrollX, y: r.top + scrollY, w: r.width, h: r.height}); })()"
                )
                box = cdp.call("Runtime.evaluate", {"expression": expr, "returnByValue": True}, session=session)
                value = box.get("result", {}).get("value")
                if value is None:
                    problems.append(f"no element with id {sec!r} to photograph")
                    continue
                b = json.loads(value)
                clip = {"x": b["x"], "y": b["y"], "width": b["w"], "height": b["h"]}
            shot = cdp.call(
                "Page.captureScreenshot",
                {"format": "png", "captureBeyondViewport": True, "clip": {**clip, "scale": 1}},
                session=session,
                timeout=timeout,
            )
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(base64.b64decode(shot["data"]))
            facts["screenshots"].append(str(path))
        try:
            cdp.call("Browser.close", timeout=5)
        except Exception:
            pass
    finally:
        if ws is not None:
            ws.close()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        shutil.rmtree(profile, ignore_errors=True)
    return problems, facts


def shot_paths(screenshot: Path | str, section: str | list[str] | None) -> list[tuple[str | None, Path]]:
    """(element id or None for the whole page, PNG path) for each screenshot to take."""
    screenshot = Path(screenshot)
    ids = [section] if isinstance(section, str) else list(section or [])
    if len(ids) <= 1:
        return [(ids[0] if ids else None, screenshot)]
    return [(i, screenshot.with_name(f"{screenshot.stem}-{i}{screenshot.suffix or '.png'}")) for i in ids]


def main(argv: list[str] | None = None) -> int:
    """Command line; see the module docstring."""
    ap = argparse.ArgumentParser(description="Check an HTML report in headless Chromium (console errors, screenshot).")
    ap.add_argument("report", type=Path, help="the HTML file")
    ap.add_argument("--screenshot", type=Path, help="write a PNG screenshot here")
    ap.add_argument(
        "--section",
        action="append",
        help="photograph only the element with this id (e.g. distribution); repeat for one PNG per id",
    )
    ap.add_argument("--chromium", help="browser executable (default /usr/bin/chromium)")
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds for start-up and loading (default 60)")
    args = ap.parse_args(argv)
    try:
        problems, facts = check(
            args.report, args.screenshot, section=args.section, chromium=args.chromium, timeout=args.timeout
        )
    except FileNotFoundError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except (RuntimeError, TimeoutError, ConnectionError, OSError) as e:
        print(f"FAIL: {args.report}: the browser check broke down: {e}", file=sys.stderr)
        return 1
    if facts:
        print(
            f"{args.report}: title {facts.get('title', '')!r}, {facts.get('images', 0)} image(s), "
            f"sections: {', '.join(facts.get('sections', []))}, page height {facts.get('height', '?')} px"
        )
    for shot in facts.get("screenshots", []):
        print(f"screenshot: {shot}")
    if problems:
        print(f"FAIL: {len(problems)} problem(s):", file=sys.stderr)
        for p in problems:
            print(f"  - {p}", file=sys.stderr)
        return 1
    print("OK: loaded with no console errors")
    return 0


if __name__ == "__main__":
    sys.exit(main())
