"""apps/view.py, `polyfold view` (issue 7): the address checks, the command line (URL printed, MESH
input, bad input), the gate in front of viser (apps/view_guard.py, issue 20: Host, Origin and
token checked on every request and websocket handshake; a foreign page in the browser gets
nothing and writes nothing) and the page itself in a real headless browser (Debian's Chromium driven by
Playwright; never a downloaded browser). (The folder loader and the folding poses it shows:
pipeline/test_folder.py.)

Set POLYFOLD_VIEWER_SCREENSHOT=path to also save a screenshot of the page (docs/viewer.png)."""

from __future__ import annotations

import io
import json
import os
import re
import signal
import subprocess
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from conftest import CLI, one_line, run_cli
from polyfold.apps.view import check_host, serve
from polyfold.errors import PolyfoldError

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--use-gl=swiftshader", "--enable-unsafe-swiftshader",
                 "--ignore-gpu-blocklist"]
needs_chromium = pytest.mark.skipif(not Path(CHROMIUM).exists(),
                                    reason=f"no {CHROMIUM} (Debian's chromium package; CI installs it in .ci/run)")


# ----------------------------------------------------------------------------------------------
# Addresses and the command line


def test_check_host() -> None:
    assert check_host("127.0.0.1", explicit=False) == "127.0.0.1"
    assert check_host("localhost", explicit=False) == "127.0.0.1"
    assert check_host("::1", explicit=False) == "::1"
    for host in ("0.0.0.0", "192.168.1.20", "::"):
        with pytest.raises(PolyfoldError, match="--host"):
            check_host(host, explicit=False)
        assert check_host(host, explicit=True) == host
    for bad in ("example.com", "", "127.0.0.1:80", "999.1.1.1"):
        with pytest.raises(PolyfoldError, match="IP address"):
            check_host(bad, explicit=True)


def test_serve_refuses_remote_by_default(make_dir: Path) -> None:
    with pytest.raises(PolyfoldError, match="refusing"):
        serve(make_dir, host="0.0.0.0", port=0)


@pytest.mark.parametrize("case", ["missing", "not-a-make-folder", "broken-fold", "bad-host", "bad-mesh"])
def test_cli_bad_input(tmp_path: Path, make_dir: Path, case: str) -> None:
    if case == "missing":
        proc = run_cli("view", tmp_path / "nothing-here", "--port", 0, timeout=60)
    elif case == "not-a-make-folder":
        (tmp_path / "x.txt").write_text("hello")
        proc = run_cli("view", tmp_path, "--port", 0, timeout=60)
    elif case == "broken-fold":
        import shutil

        copy = tmp_path / "copy"
        shutil.copytree(make_dir, copy)
        fold = json.loads((copy / "piece-A.fold").read_text())
        fold["polyfold:path"] = [[0.0, 1.0], [2.0]]  # ragged frames
        (copy / "piece-A.fold").write_text(json.dumps(fold))
        proc = run_cli("view", copy, "--port", 0, timeout=60)
    elif case == "bad-host":
        proc = run_cli("view", make_dir, "--host", "not-an-address", "--port", 0, timeout=60)
    else:
        (tmp_path / "broken.obj").write_text("v 0 0 0\nf 1 2 3\n")
        proc = run_cli("view", tmp_path / "broken.obj", "--port", 0, timeout=60)
    assert proc.returncode == 2, proc.stderr
    line = one_line(proc.stderr)
    assert line.startswith("polyfold: error:"), line


def _read_url(proc: subprocess.Popen, timeout: float) -> tuple[str, list[str]]:
    """Read stderr lines until the viewer's URL line; returns (url, lines so far)."""
    lines: list[str] = []
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        line = proc.stderr.readline()
        if not line:
            break
        lines.append(line.rstrip("\n"))
        m = re.fullmatch(r"polyfold: viewer at (http://127\.0\.0\.1:\d+/\?token=[\w-]{40,})", lines[-1])
        if m:
            return m.group(1), lines
    raise AssertionError("no URL line:\n" + "\n".join(lines))


def test_cli_view_mesh(models_dir: Path, tmp_path: Path) -> None:
    """`polyfold view MESH`: make into a temporary folder, print one URL line, serve the client
    (and nothing from the folder), stop cleanly on SIGTERM and remove the temporary folder."""
    temp = tmp_path / "tmp"
    temp.mkdir()
    env = {**os.environ, "TMPDIR": str(temp)}
    proc = subprocess.Popen([*CLI, "view", str(models_dir / "octahedron-8.obj"), "--port", "0", "--time-limit", "20"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        url, lines = _read_url(proc, timeout=120)
        assert not any("Traceback" in line for line in lines)
        assert [p.name for p in temp.iterdir() if p.name.startswith("polyfold-view-")], "no temporary make folder"
        with pytest.raises(urllib.error.HTTPError) as err:  # the page without its token
            urllib.request.urlopen(url.split("?")[0], timeout=10)
        assert err.value.code == 403
        err.value.close()
        # the token URL sets the cookie and redirects to the page (urllib follows, with the cookie)
        opener = urllib.request.build_opener(urllib.request.HTTPCookieProcessor())
        with opener.open(url, timeout=10) as resp:
            assert resp.status == 200 and b"<html" in resp.read(4096).lower()
        base = url.split("/?")[0]
        for path in ("/assembly.json", "/report.json", "/piece-A.fold", "/part-0.obj", "/../assembly.json"):
            with pytest.raises(urllib.error.HTTPError) as err:
                opener.open(base + path, timeout=10)
            assert err.value.code == 404, path
            err.value.close()  # an open response would hold the connection (and the shutdown)
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=20) == 0
        rest = proc.stderr.read()
        assert "Traceback" not in rest
        assert proc.stdout.read() == ""  # viser's own banner is kept off the terminal
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert not [p for p in temp.iterdir() if p.name.startswith("polyfold-view-")], "temporary folder left behind"


# ----------------------------------------------------------------------------------------------
# In the browser


def _png(data: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB")).astype(np.int16)


def _stable_shot(locator, timeout: float = 15.0) -> np.ndarray:
    """A screenshot once the rendering has settled (two in a row alike)."""
    prev = _png(locator.screenshot())
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        time.sleep(0.3)
        cur = _png(locator.screenshot())
        if cur.shape == prev.shape and (np.abs(cur - prev).max(axis=2) > 8).mean() < 1e-4:
            return cur
        prev = cur
    return prev


def _slider(page, label: str):
    """The thumb of the viser slider labelled `label` (the element a user drags / keys)."""
    target = page.locator("label", has_text=re.compile(rf"^{re.escape(label)}$")).get_attribute("for")
    return page.locator(f"[id='{target}']").get_by_role("slider")


def _hv(page) -> int:
    text = page.get_by_text(re.compile(r"HV: \d+")).inner_text()
    return int(re.search(r"HV: (\d+)", text).group(1))


def _until(cond, timeout: float, what: str) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


@needs_chromium
def test_viewer_in_browser(make_dir: Path) -> None:
    from playwright.sync_api import sync_playwright

    viewer = serve(make_dir, port=0)
    problems: list[str] = []
    try:
        assert re.fullmatch(r"http://127\.0\.0\.1:\d+/\?token=[\w-]{40,}", viewer.url)
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
            try:
                page = browser.new_page(viewport={"width": 1280, "height": 800})
                page.on("console", lambda m: problems.append(f"console: {m.text}") if m.type == "error" else None)
                page.on("pageerror", lambda e: problems.append(f"pageerror: {e}"))
                page.goto(viewer.url)
                page.wait_for_selector("canvas", timeout=30000)
                page.get_by_text(re.compile(r"HV: \d+")).wait_for(timeout=30000)
                canvas = page.locator("canvas").first

                # pick part 0 in the dropdown, as a user does
                target = page.locator("label", has_text=re.compile(r"^Part$")).get_attribute("for")
                page.locator(f"[id='{target}']").click()
                page.get_by_role("option", name=re.compile(r"^part 0")).click()
                _until(lambda: viewer.part_dropdown.value.startswith("part 0"), 10, "the part picker")

                # the fold slider: flat, then folded
                fold = _slider(page, "Fold")
                fold.press("Home")
                _until(lambda: viewer.fold_slider.value == 0.0, 10, "the fold slider at 0")
                flat = _stable_shot(canvas)
                fold.press("End")
                _until(lambda: viewer.fold_slider.value == 1.0, 10, "the fold slider at 1")
                folded = _stable_shot(canvas)
                changed = (np.abs(flat - folded).max(axis=2) > 30).mean()
                assert changed > 0.005, f"only {changed:.2%} of the canvas changed between flat and folded"

                # play, then pause half way: the slider moves on its own and stops where paused
                page.get_by_role("button", name="Play").click()
                _until(lambda: 0.0 < viewer.fold_slider.value < 0.9, 10, "the animation to start")
                page.get_by_role("button", name="Pause").click()
                _until(lambda: viewer.play_button.label == "Play", 10, "the animation to pause")
                paused = viewer.fold_slider.value
                page.wait_for_timeout(300)
                assert viewer.fold_slider.value == paused < 1.0

                # inflation: a higher pressure leaves fewer saddles (bunny-128: 22 -> 20 at 2000 steps)
                assert viewer.wait_inflation(1, timeout=30)
                _until(lambda: _hv(page) == int(viewer.inflation.hyperbolic), 10, "the HV count in the page")
                before = _hv(page)
                _slider(page, "Pressure").press("End")
                _until(lambda: viewer.pressure_slider.value == 1.0, 10, "the pressure slider at 1")
                _until(lambda: _hv(page) != before, 30, "the HV count to change")
                assert _hv(page) == int(viewer.inflation.hyperbolic) < before

                # mid-fold picture for the docs
                shot = os.environ.get("POLYFOLD_VIEWER_SCREENSHOT")
                if shot:
                    viewer.set_fold(0.55)
                    close = page.locator("button.mantine-Notification-closeButton, .mantine-Notification-root button")
                    if close.count():
                        close.first.click()
                    _stable_shot(canvas)
                    page.screenshot(path=shot)

                # export and make, from the page's buttons, into a subfolder of the viewed folder
                viewer.output_text.value = "../elsewhere"
                page.get_by_role("button", name="Export inflated OBJ").click()
                page.get_by_text(re.compile("must be inside")).wait_for(timeout=10000)
                assert not (make_dir.parent / "elsewhere").exists()
                viewer.output_text.value = "again"
                page.get_by_role("button", name="Export inflated OBJ").click()
                page.get_by_text(re.compile(r"exported .*\.obj")).wait_for(timeout=10000)
                assert list((make_dir / "again").glob("*-inflated-constrained.obj"))
                page.get_by_role("button", name="Run make").click()
                assert viewer.wait_make(1, timeout=60)
                page.get_by_text(re.compile(r"make \(inflated mesh\) done")).wait_for(timeout=10000)
                assert (make_dir / "again" / "assembly.json").is_file()
                assert viewer.folder.path == (make_dir / "again").resolve()
                assert viewer.folder.options.parts == 3 and len(viewer.folder.parts) >= 2
                page.wait_for_timeout(500)
            finally:
                browser.close()
    finally:
        viewer.stop()
    assert not problems, "\n".join(problems)


# ----------------------------------------------------------------------------------------------
# The gate: only the viewer's own page, with its token


def _ask(port: int, path: str, headers: dict[str, str]) -> tuple[int, bytes]:
    import http.client

    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    try:
        conn.request("GET", path, headers=headers)
        resp = conn.getresponse()
        return resp.status, resp.read()
    finally:
        conn.close()


def test_the_gate_lets_in_only_the_page_with_its_token(make_dir: Path) -> None:
    import base64

    viewer = serve(make_dir, port=0)
    try:
        port, token = viewer.port, viewer.gate.token
        own = f"http://127.0.0.1:{port}"
        cookie = {"Cookie": f"polyfold-view-{port}={token}"}
        ws = {"Upgrade": "websocket", "Connection": "Upgrade", "Sec-WebSocket-Version": "13",
              "Sec-WebSocket-Key": base64.b64encode(os.urandom(16)).decode(), "Sec-WebSocket-Protocol": "viser-v1"}
        refused = [
            ("/", {}),  # no token
            ("/?token=wrong", {}),
            ("/", {"Cookie": f"polyfold-view-{port}=wrong"}),
            ("/", {**cookie, "Host": f"evil.example:{port}"}),  # DNS rebinding: a foreign name
            ("/", {**cookie, "Origin": "http://evil.example"}),
            ("/", {**ws, **cookie, "Origin": "http://evil.example"}),  # a foreign page's websocket
            ("/", {**ws, **cookie}),  # a websocket without Origin
            ("/", {**ws, "Origin": own}),  # without the token
        ]
        for path, headers in refused:
            status, body = _ask(port, path, headers)
            assert status == 403 and b"<html" not in body.lower(), (path, headers)
        assert viewer.gate.refused == len(refused)
        assert _ask(port, f"/?token={token}", {})[0] == 302
        status, body = _ask(port, "/", cookie)
        assert status == 200 and b"<html" in body.lower()
        assert _ask(port, "/", {**ws, **cookie, "Origin": own})[0] == 101  # the page's own websocket
    finally:
        viewer.stop()


FOREIGN_PAGE = """<!doctype html><html><body><script>
window.results = {};
const target = "127.0.0.1:%d";
fetch("http://" + target + "/?token=guess", {mode: "no-cors"}).then(() => results.fetch = "sent").catch(() => results.fetch = "failed");
const ws = new WebSocket("ws://" + target + "/", ["viser-v1.1.1"]);
ws.onopen = () => results.ws = "open";
ws.onmessage = () => results.message = "got data";
ws.onerror = () => results.ws = "refused";
</script></body></html>"""


@needs_chromium
def test_a_foreign_page_in_the_browser_gets_nothing(make_dir: Path, tmp_path: Path) -> None:
    """A page from another origin, open in the same browser as the viewer (after the user opened the
    viewer, so its cookie is there): its websocket is refused, nothing reaches it, nothing is written."""
    import http.server
    import threading

    from playwright.sync_api import sync_playwright

    before = sorted(p.name for p in make_dir.rglob("*"))
    viewer = serve(make_dir, port=0)
    site = tmp_path / "site"
    site.mkdir()
    (site / "index.html").write_text(FOREIGN_PAGE % viewer.port)
    handler = lambda *a, **k: http.server.SimpleHTTPRequestHandler(*a, directory=str(site), **k)  # noqa: E731
    foreign = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=foreign.serve_forever, daemon=True).start()
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
            try:
                context = browser.new_context()
                page = context.new_page()
                page.goto(viewer.url)  # the user's own tab: the viewer works, its cookie is set
                page.wait_for_selector("canvas", timeout=30000)
                evil = context.new_page()
                evil.goto(f"http://127.0.0.1:{foreign.server_address[1]}/index.html")
                evil.wait_for_function("window.results.ws !== undefined", timeout=15000)
                evil.wait_for_timeout(500)
                results = evil.evaluate("window.results")
            finally:
                browser.close()
        assert results.get("ws") == "refused" and "message" not in results, results
        assert viewer.gate.refused >= 1
    finally:
        foreign.shutdown()
        viewer.stop()
    assert sorted(p.name for p in make_dir.rglob("*")) == before  # nothing written
