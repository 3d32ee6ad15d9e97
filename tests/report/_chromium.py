"""Headless Debian chromium helpers shared by the report and study browser tests.

Loaded by file path (the test folders are not packages). ``inspect_page`` loads a page
through the DevTools protocol and returns the decoded state of its images and every
console error or exception.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import time
import urllib.request
from pathlib import Path

ARTIFACTS = Path(__file__).resolve().parents[1] / "artifacts"
FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--disable-dev-shm-usage",
]


def find_chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


def run_cmd(cmd, timeout=90):
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)


def _devtools_port(user_dir: Path, proc: subprocess.Popen, timeout: float = 30.0) -> int:
    marker = user_dir / "DevToolsActivePort"
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if marker.is_file() and marker.read_text().strip():
            return int(marker.read_text().split()[0])
        if proc.poll() is not None:
            raise RuntimeError(f"chromium exited early with code {proc.returncode}")
        time.sleep(0.1)
    raise RuntimeError("chromium did not open a DevTools port")


class _Cdp:
    """A minimal Chrome DevTools Protocol client over one page websocket."""

    def __init__(self, ws_url: str):
        import websocket

        self.ws = websocket.create_connection(ws_url, timeout=30, suppress_origin=True)
        self.next_id = 0
        self.events: list[dict] = []

    def call(self, method: str, **params):
        self.next_id += 1
        my_id = self.next_id
        self.ws.send(json.dumps({"id": my_id, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv())
            if msg.get("id") == my_id:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return msg.get("result", {})
            self.events.append(msg)

    def wait_event(self, method: str, timeout: float = 30.0) -> dict:
        deadline = time.monotonic() + timeout
        for ev in self.events:
            if ev.get("method") == method:
                return ev
        while time.monotonic() < deadline:
            msg = json.loads(self.ws.recv())
            self.events.append(msg)
            if msg.get("method") == method:
                return msg
        raise TimeoutError(method)


def inspect_page(chromium: str, page_path: Path, user_dir: Path):
    """Load the page through DevTools; return (images [complete, naturalWidth], errors)."""
    proc = subprocess.Popen(
        [chromium, *FLAGS, f"--user-data-dir={user_dir}", "--remote-debugging-port=0",
         "about:blank"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )
    try:
        port = _devtools_port(user_dir, proc)
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10) as r:
            targets = json.load(r)
        page = next(t for t in targets if t.get("type") == "page")
        cdp = _Cdp(page["webSocketDebuggerUrl"])
        for domain in ("Runtime", "Log", "Page"):
            cdp.call(f"{domain}.enable")
        cdp.call("Page.navigate", url=page_path.as_uri())
        cdp.wait_event("Page.loadEventFired")
        res = cdp.call(
            "Runtime.evaluate", returnByValue=True,
            expression="Array.from(document.images).map(i => [i.complete, i.naturalWidth])",
        )
        images = res["result"]["value"]
        errors = [
            ev for ev in cdp.events
            if ev.get("method") == "Runtime.exceptionThrown"
            or (ev.get("method") == "Runtime.consoleAPICalled"
                and ev["params"].get("type") in ("error", "assert"))
            or (ev.get("method") == "Log.entryAdded"
                and ev["params"]["entry"].get("level") == "error")
        ]
        cdp.ws.close()
        return images, errors
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()




_LAYOUT_JS = r"""
(() => {
  const W = document.documentElement.clientWidth;
  const box = e => { const r = e.getBoundingClientRect();
                     return {left: r.left, right: r.right, width: r.width}; };
  const wraps = Array.from(document.querySelectorAll('.mvtk-table-wrap')).map(w => ({
    id: (w.querySelector('table') || {}).id || '', ...box(w),
    scrollWidth: w.scrollWidth, clientWidth: w.clientWidth,
    overflowX: getComputedStyle(w).overflowX}));
  const tables = Array.from(document.querySelectorAll('table')).map(t => ({
    id: t.id, ...box(t), wrapped: !!t.closest('.mvtk-table-wrap')}));
  const figures = Array.from(document.querySelectorAll('figure')).map(f => {
    const img = f.querySelector('img');
    return {figure: box(f), img: box(img), natural: img.naturalWidth,
            complete: img.complete};});
  return {viewport: W, pageScrollWidth: document.documentElement.scrollWidth,
          bodyRight: document.body.getBoundingClientRect().right,
          wraps, tables, figures};
})()
"""


def measure_layout(chromium: str, page_path: Path, user_dir: Path, widths=(1024, 1400),
                   height: int = 900, print_media: bool = False,
                   screenshot: Path | None = None) -> dict:
    """Lay the page out at each width (DevTools device metrics) and measure its boxes.

    Returns ``{width: layout}`` where ``layout`` holds the viewport width, the page's
    scrollWidth, every table scroll box (bounding box, scrollWidth, clientWidth, CSS
    overflow-x), every table and every figure/image box. With ``print_media`` the page is
    laid out with its print CSS. ``screenshot`` saves a PNG of the first screen at the
    last width.
    """
    import base64

    proc = subprocess.Popen(
        [chromium, *FLAGS, f"--user-data-dir={user_dir}", "--remote-debugging-port=0",
         "about:blank"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )
    out = {}
    try:
        port = _devtools_port(user_dir, proc)
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10) as r:
            targets = json.load(r)
        page = next(t for t in targets if t.get("type") == "page")
        cdp = _Cdp(page["webSocketDebuggerUrl"])
        cdp.call("Page.enable")
        cdp.call("Runtime.enable")
        if print_media:
            cdp.call("Emulation.setEmulatedMedia", media="print")
        for width in widths:
            cdp.call("Emulation.setDeviceMetricsOverride", width=width, height=height,
                     deviceScaleFactor=1, mobile=False)
            cdp.events.clear()
            cdp.call("Page.navigate", url=page_path.as_uri())
            cdp.wait_event("Page.loadEventFired")
            res = cdp.call("Runtime.evaluate", expression=_LAYOUT_JS, returnByValue=True)
            out[width] = res["result"]["value"]
        if screenshot is not None:
            shot = cdp.call("Page.captureScreenshot", format="png")
            screenshot.write_bytes(base64.b64decode(shot["data"]))
        cdp.ws.close()
        return out
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()


def evaluate_after(chromium: str, page_path: Path, user_dir: Path, expressions,
                   wait_s: float = 1.0, width: int = 1280, height: int = 900):
    """Load the page, wait ``wait_s`` seconds between the expressions (JavaScript,
    evaluated by value); return (values, console errors and exceptions)."""
    proc = subprocess.Popen(
        [chromium, *FLAGS, f"--user-data-dir={user_dir}", "--remote-debugging-port=0",
         "about:blank"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )
    try:
        port = _devtools_port(user_dir, proc)
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10) as r:
            targets = json.load(r)
        page = next(t for t in targets if t.get("type") == "page")
        cdp = _Cdp(page["webSocketDebuggerUrl"])
        for domain in ("Runtime", "Log", "Page"):
            cdp.call(f"{domain}.enable")
        cdp.call("Emulation.setDeviceMetricsOverride", width=width, height=height,
                 deviceScaleFactor=1, mobile=False)
        cdp.call("Page.navigate", url=page_path.as_uri())
        cdp.wait_event("Page.loadEventFired")
        values = []
        for expr in expressions:
            time.sleep(wait_s)
            res = cdp.call("Runtime.evaluate", expression=expr, returnByValue=True,
                           awaitPromise=True)
            values.append(res["result"].get("value"))
        errors = [
            ev for ev in cdp.events
            if ev.get("method") == "Runtime.exceptionThrown"
            or (ev.get("method") == "Runtime.consoleAPICalled"
                and ev["params"].get("type") in ("error", "assert"))
            or (ev.get("method") == "Log.entryAdded"
                and ev["params"]["entry"].get("level") == "error")
        ]
        cdp.ws.close()
        return values, errors
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
