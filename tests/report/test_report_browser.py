"""The report page in a real headless browser (Debian chromium).

Skips with a reason when chromium is not on PATH (``tests/report/install_chromium.sh``
installs it). Checks, through the DevTools protocol, that the page loads without console
errors or exceptions and that every figure is decoded (naturalWidth > 0); also checks
``--dump-dom`` and keeps a screenshot in ``tests/artifacts/``.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from mvtk.plot import plot_decay, plot_frf, plot_mode_shapes, plot_spectra, plot_time_responses
from mvtk.report import Report, collect_provenance
from mvtk.validation import Check, check_table, frequency_table

ARTIFACTS = Path(__file__).resolve().parents[1] / "artifacts"
FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--disable-dev-shm-usage",
]


@pytest.fixture(scope="module")
def chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.skip("chromium not installed (run tests/report/install_chromium.sh as root)")
    return exe


@pytest.fixture(scope="module")
def report_page(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("report")
    rep = Report("mvtk browser test")
    f = np.linspace(5, 50, 901)
    w, wn = 2 * np.pi * f, 2 * np.pi * 13.26
    H = 1 / (wn**2 - w**2 + 2j * 0.01 * wn * w)
    t = np.arange(2000) / 200.0
    x = np.exp(-0.5 * t) * np.sin(2 * np.pi * 13.26 * t)
    gx, gy = np.meshgrid(np.linspace(0, 0.18, 13), np.linspace(0, 0.133, 9))
    nodes = np.c_[gx.ravel(), gy.ravel(), np.zeros(gx.size)]
    uz = np.c_[nodes[:, 0] ** 2, nodes[:, 0] * (nodes[:, 1] - 0.0665)]
    rep.section("Figures").figure(plot_frf(f, H, bands=[(13.1, 13.4, 13.26)]), "FRF") \
        .figure(plot_decay(t, x, fit=np.exp(-0.5 * t)), "decay") \
        .figure(plot_mode_shapes(nodes, uz, [13.26, 41.14]), "modes") \
        .figure(plot_time_responses(t, {"open": x, "ppf": x * np.exp(-t)}, zoom=(0, 1)), "tip") \
        .figure(plot_spectra(f, {"open": np.abs(H), "ppf": np.abs(H) / 3}), "spectra")
    rep.section("Tables").table(
        frequency_table({"test": [13.26, 41.14], "FE": [13.81, 42.67]}, "test"), "t2",
        "Table 2").table(check_table([Check("f1", 13.3, 13.26, 0.01, "Hz")]), "checks")
    rep.add_provenance(collect_provenance([], {"study": "browser test"}))
    return rep.write(out)


def _run(cmd, timeout=90):
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)


def test_dump_dom_and_screenshot(chromium, report_page, tmp_path):
    url = report_page.as_uri()
    dom = _run([chromium, *FLAGS, f"--user-data-dir={tmp_path / 'ud1'}", "--dump-dom", url])
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert dom.stdout.count('class="report-figure"') == 5
    assert "1 of 1 checks passed" in dom.stdout
    ARTIFACTS.mkdir(exist_ok=True)
    shot = ARTIFACTS / "report_screenshot.png"
    shot.unlink(missing_ok=True)
    res = _run([chromium, *FLAGS, f"--user-data-dir={tmp_path / 'ud2'}",
                f"--screenshot={shot}", "--window-size=1280,2400", url])
    assert res.returncode == 0, res.stderr[-2000:]
    assert shot.read_bytes().startswith(b"\x89PNG") and shot.stat().st_size > 10_000


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


def _inspect(chromium: str, page_path: Path, user_dir: Path):
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


def test_devtools_no_console_errors_and_images_decoded(chromium, report_page, tmp_path):
    pytest.importorskip("websocket", reason="websocket-client needed for the DevTools check")
    images, errors = _inspect(chromium, report_page, tmp_path / "ud3")
    assert len(images) == 5
    assert all(done and width > 100 for done, width in images), images
    assert errors == []


def test_devtools_check_detects_a_broken_page(chromium, tmp_path):
    # negative control: the same inspection must see a console error and an undecodable image
    pytest.importorskip("websocket", reason="websocket-client needed for the DevTools check")
    bad = tmp_path / "bad.html"
    bad.write_text('<!DOCTYPE html><html><body><img src="data:image/png;base64,AAAA">'
                   '<script>console.error("boom")</script></body></html>')
    images, errors = _inspect(chromium, bad, tmp_path / "ud4")
    assert images == [[True, 0]]
    assert any(ev.get("method") == "Runtime.consoleAPICalled" for ev in errors)
