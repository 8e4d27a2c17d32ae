"""apps/view.py, `polyfold view` (issue 7): the address checks, the command line (URL printed, MESH
input, bad input), the gate in front of viser (apps/view_guard.py, issue 20: Host, Origin and
token checked on every request and websocket handshake; a foreign page in the browser gets
nothing and writes nothing) and the page itself in a real headless browser (Debian's Chromium driven by
Playwright; never a downloaded browser), and the model's look (model.glb, issue 21: read with the
folder, matched to the parts, drawn on the folded model). (The folder loader and the folding
poses it shows: pipeline/test_folder.py.)

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


def _changed_by_click(page, canvas, text: str, done, what: str) -> float:
    """The fraction of the canvas that changes when the control showing `text` is clicked (once
    done() says the viewer took it, and the rendering settled)."""
    before = _stable_shot(canvas)
    page.get_by_text(text).click()
    _until(done, 10, what)
    after = _stable_shot(canvas)
    return float((np.abs(before - after).max(axis=2) > 30).mean())


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

                # the build steps: step 1 shows one piece, the last the whole model; back to folding at 0
                steps = _slider(page, "Step")
                steps.press("Home")
                steps.press("ArrowRight")
                _until(lambda: viewer.step_slider.value == 1, 10, "the step slider at 1")
                page.get_by_text(re.compile(r"Step 1/\d+")).wait_for(timeout=10000)
                first = _stable_shot(canvas)
                steps.press("End")
                _until(lambda: viewer.step_slider.value == len(viewer.folder.steps), 10, "the last step")
                last = _stable_shot(canvas)
                assert sum(h.visible for h in viewer._build_nodes) == len(viewer.folder.pieces)
                changed = (np.abs(first - last).max(axis=2) > 30).mean()
                assert changed > 0.005, f"only {changed:.2%} of the canvas changed between the first and last step"
                steps.press("Home")
                _until(lambda: viewer.step_slider.value == 0, 10, "the step slider at 0")
                _until(lambda: not any(h.visible for h in viewer._build_nodes), 10, "the folding view back")

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
# The model's look (model.glb, issue 21): read with the folder, shown on the folded model


def _ball_uv(xyz: np.ndarray) -> np.ndarray:
    """The test texture's UVs: a function of the position (the left ball in [0, 0.5]^2, the right
    one partly beyond 1: the texture repeats there)."""
    return (np.asarray(xyz)[..., :2] + 1.0) / 4.0


@pytest.fixture(scope="module")
def look_dirs(tmp_path_factory) -> dict[str, Path]:
    """Make folders of two textured balls (two parts, verified paths): printed in the texture
    ('texture'), in flat colours ('flat': model.glb has colours per corner) and without a look
    ('none': no model.glb)."""
    import trimesh
    from PIL import Image

    from polyfold.pipeline.make import make
    from polyfold.pipeline.options import MakeOptions

    root = tmp_path_factory.mktemp("look")
    a, b = trimesh.creation.icosphere(subdivisions=1), trimesh.creation.icosphere(subdivisions=0)
    verts = np.concatenate([a.vertices, b.vertices + [3.0, 0.0, 0.0]])
    faces = np.concatenate([a.faces, b.faces + len(a.vertices)])
    uv = _ball_uv(verts)
    i, j = np.mgrid[:32, :32]
    image = np.stack([i * 8, j * 8, ((i // 4 + j // 4) % 2) * 255], axis=2).astype(np.uint8)
    Image.fromarray(image).save(root / "balls.png")
    (root / "balls.mtl").write_text("newmtl skin\nKd 1 1 1\nmap_Kd balls.png\n")
    lines = ["mtllib balls.mtl", *(f"v {x!r} {y!r} {z!r}" for x, y, z in verts.tolist()),
             *(f"vt {u!r} {v!r}" for u, v in uv.tolist()), "usemtl skin",
             *(f"f {p + 1}/{p + 1} {q + 1}/{q + 1} {r + 1}/{r + 1}" for p, q, r in faces.tolist())]
    (root / "balls.obj").write_text("\n".join(lines) + "\n")
    out = {}
    for color in ("texture", "flat", "none"):
        out[color] = root / color
        make(root / "balls.obj", out[color], MakeOptions(size=60, color=color, time_limit=30))
    return out


def _glb_attributes(glb: bytes) -> tuple[dict[str, np.ndarray], np.ndarray | None]:
    """The first primitive of a GLB (as viser gets it): its attributes by name, and its base
    colour texture as pixels (None without one)."""
    import struct

    from PIL import Image

    n_json = struct.unpack_from("<I", glb, 12)[0]
    doc = json.loads(glb[20:20 + n_json])
    binary = glb[20 + n_json + 8:]
    kinds = {5126: np.float32, 5121: np.uint8, 5125: np.uint32, 5123: np.uint16}
    widths = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}

    def data(view: int, offset: int = 0) -> bytes:
        v = doc["bufferViews"][view]
        return binary[v.get("byteOffset", 0) + offset:v.get("byteOffset", 0) + v["byteLength"]]

    def accessor(k: int) -> np.ndarray:
        acc = doc["accessors"][k]
        return np.frombuffer(data(acc["bufferView"], acc.get("byteOffset", 0)), dtype=kinds[acc["componentType"]],
                             count=acc["count"] * widths[acc["type"]]).reshape(acc["count"], -1)

    prim = doc["meshes"][0]["primitives"][0]
    attrs = {name: accessor(k) for name, k in prim["attributes"].items()}
    attrs["indices"] = accessor(prim["indices"]).reshape(-1, 3)
    pbr = doc["materials"][prim["material"]].get("pbrMetallicRoughness", {})
    if "baseColorTexture" not in pbr:
        return attrs, None
    source = doc["textures"][pbr["baseColorTexture"]["index"]]["source"]
    picture = Image.open(io.BytesIO(data(doc["images"][source]["bufferView"])))
    return attrs, np.asarray(picture.convert("RGB"))


def _sample(image: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """The texel under each UV (v up, repeating), nearest."""
    h, w = image.shape[:2]
    x = np.floor(uv[:, 0] * w).astype(int) % w
    y = np.floor((1.0 - uv[:, 1]) * h).astype(int) % h
    return image[y, x]


def test_a_folder_with_a_look_loads_it(look_dirs: dict[str, Path]) -> None:
    """model.glb is read and matched to the parts: every face of the model once, each corner with
    the UVs of its position (the texture as the OBJ had it) or the colour of its face."""
    from PIL import Image

    from polyfold.pipeline.folder import load_folder

    folder = load_folder(look_dirs["texture"])
    look = folder.look
    assert look is not None and look.textured and look.colors is None and len(folder.parts) == 2
    np.testing.assert_array_equal(look.image, np.asarray(Image.open(look_dirs["texture"].parent / "balls.png")))
    rows = np.concatenate(look.part_corners)
    assert sorted(rows.reshape(-1).tolist()) == list(range(len(look.corners)))  # each model corner once
    for k, part in enumerate(folder.parts):
        corners = part.vertices[part.faces]
        np.testing.assert_allclose(look.corners[look.part_corners[k]], corners, rtol=0, atol=1e-6)
        np.testing.assert_allclose(look.part_uv(k), _ball_uv(corners), rtol=0, atol=1e-6)

    flat = load_folder(look_dirs["flat"]).look
    assert flat is not None and not flat.textured and flat.uv is None
    for k in range(2):
        rgba = flat.part_colors(k)
        assert (rgba == rgba[:, :1]).all() and (rgba[..., 3] == 255).all()  # one colour a face, opaque
        assert len(np.unique(rgba[:, 0], axis=0)) > 3

    assert not (look_dirs["none"] / "model.glb").exists() and load_folder(look_dirs["none"]).look is None


def test_a_broken_look_is_one_line(look_dirs: dict[str, Path], tmp_path: Path) -> None:
    import shutil

    import trimesh

    from polyfold.pipeline.folder import load_folder

    copy = tmp_path / "copy"
    shutil.copytree(look_dirs["flat"], copy)
    (copy / "model.glb").write_bytes(b"glTF not really")
    with pytest.raises(PolyfoldError, match=r"model\.glb: not a readable model look") as err:
        load_folder(copy)
    assert "\n" not in str(err.value)
    box = trimesh.creation.box()
    box.visual.vertex_colors = [200, 30, 30, 255]
    (copy / "model.glb").write_bytes(box.export(file_type="glb"))  # a look, but of another model
    with pytest.raises(PolyfoldError, match=r"model\.glb: not the model of the parts"):
        load_folder(copy)
    (copy / "model.glb").unlink()
    assert load_folder(copy).look is None  # old folders (no model.glb) load as before


def test_the_viewer_shows_the_texture(look_dirs: dict[str, Path]) -> None:
    """Folded, every part is drawn in the model's texture (a GLB per part: its corners, their UVs,
    the texture) instead of its pieces; while folding, and with the box unticked, the pieces in
    the part colours are."""
    viewer = serve(look_dirs["texture"], port=0)
    try:
        look = viewer.folder.look
        assert len(viewer.look_nodes) == len(viewer.folder.parts) == 2 and not viewer.look_checkbox.disabled
        for k, node in enumerate(viewer.look_nodes):
            attrs, image = _glb_attributes(node.glb_data)
            part = viewer.folder.parts[k]
            corners = attrs["POSITION"][attrs["indices"]]
            np.testing.assert_allclose(corners, viewer._to_view(part.vertices[part.faces]), rtol=0, atol=1e-6)
            uv = attrs["TEXCOORD_0"][attrs["indices"]].astype(np.float64)
            uv[..., 1] = 1.0 - uv[..., 1]  # glTF's v runs down
            # a part whose UVs stay in [0, 1] gets only the piece of the texture it uses
            inside = 0 <= look.part_uv(k).min() and look.part_uv(k).max() <= 1
            assert image.shape[0] < look.image.shape[0] if inside else image.shape == look.image.shape
            # the texel at every face's middle is the model's there
            texels = _sample(look.image, look.part_uv(k).mean(axis=1))
            np.testing.assert_array_equal(_sample(image, uv.mean(axis=1)), texels)
            assert texels.std() > 10  # a texture, not one colour

        def shown() -> tuple[list[bool], list[bool]]:
            return [n.visible for n in viewer.look_nodes], [h.visible for _, h in viewer._fold_nodes]

        assert shown() == ([True, True], [False, False])  # folded: the look
        viewer.set_fold(0.5)
        assert shown() == ([False, False], [True, True])  # folding: the pieces move in part colours
        viewer.set_fold(1.0)
        viewer.set_part(1)
        assert shown() == ([False, True], [False] * len(viewer._fold_nodes))  # part 0 ghosted, part 1 in its look
        assert viewer._part_nodes[0].visible and viewer._part_nodes[0].color == (190, 190, 190)
        viewer.look_checkbox.value = False
        assert shown() == ([False, False], [True])
    finally:
        viewer.stop()


def test_the_viewer_shows_colours_and_works_without_a_look(look_dirs: dict[str, Path]) -> None:
    viewer = serve(look_dirs["flat"], port=0)
    try:
        look = viewer.folder.look
        for k, node in enumerate(viewer.look_nodes):
            attrs, image = _glb_attributes(node.glb_data)
            assert image is None
            np.testing.assert_array_equal(attrs["COLOR_0"][attrs["indices"]], look.part_colors(k))
        assert all(n.visible for n in viewer.look_nodes)
    finally:
        viewer.stop()
    viewer = serve(look_dirs["none"], port=0)
    try:
        assert viewer.folder.look is None and viewer.look_nodes == [] and viewer.look_checkbox.disabled
        assert all(h.visible for _, h in viewer._fold_nodes)  # the pieces in the part colours, as before
    finally:
        viewer.stop()


@needs_chromium
def test_the_texture_in_the_browser(look_dirs: dict[str, Path]) -> None:
    """The page draws the parts' GLBs (no console errors) and the "Model's colours" box swaps them
    for the part colours."""
    from playwright.sync_api import sync_playwright

    viewer = serve(look_dirs["texture"], port=0)
    problems: list[str] = []
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
            try:
                page = browser.new_page(viewport={"width": 1024, "height": 640})
                page.on("console", lambda m: problems.append(f"console: {m.text}") if m.type == "error" else None)
                page.on("pageerror", lambda e: problems.append(f"pageerror: {e}"))
                page.goto(viewer.url)
                page.wait_for_selector("canvas", timeout=30000)
                canvas = page.locator("canvas").first
                changed = _changed_by_click(page, canvas, "Model's colours", lambda: viewer.look_checkbox.value is False,
                                            "the box to be unticked")
                assert changed > 0.002, f"only {changed:.2%} of the canvas changed with the model's colours"
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


# ----------------------------------------------------------------------------------------------
# A convex approximation beside its original (issue 24)


@pytest.fixture(scope="module")
def hull_dir(models_dir: Path, tmp_path_factory) -> Path:
    from polyfold.pipeline.make import make
    from polyfold.pipeline.options import MakeOptions

    out = tmp_path_factory.mktemp("view-hulls") / "bunny-128"
    make(models_dir / "bunny-128.obj", out, MakeOptions(approximate="hulls", time_limit=30))
    return out


def test_the_viewer_shows_the_original_beside_the_approximation(hull_dir: Path, make_dir: Path) -> None:
    viewer = serve(hull_dir, port=0)
    try:
        original = viewer.folder.original
        assert original is not None and viewer._original_node is not None and viewer._original_node.visible
        assert not viewer.original_checkbox.disabled and "convex approximation" in viewer._title.content
        assert viewer.source is original  # inflation and "Run make" work on the original, not the parts
        # left of the model, clear of it; the inflated copy further left, clear of the original
        width = 2.0 * float(viewer._half[0])
        left = viewer._original_offset()[0]
        assert left <= -width and viewer._inflated_offset()[0] <= left - width
        np.testing.assert_allclose(viewer._original_node.vertices, viewer._to_view(original.vertices), atol=1e-6)
        viewer.original_checkbox.value = False
        _until(lambda: not viewer._original_node.visible, 5, "the original hidden")
    finally:
        viewer.stop()
    viewer = serve(make_dir, port=0)  # an ordinary folder: no original, the box greyed out
    try:
        assert viewer.folder.original is None and viewer._original_node is None and viewer.original_checkbox.disabled
    finally:
        viewer.stop()


@needs_chromium
def test_the_approximation_in_the_browser(hull_dir: Path) -> None:
    """The page draws the original: hiding it changes the left of the picture. Set
    POLYFOLD_HULLS_SCREENSHOT=path to save the page (docs/approximate/viewer.png)."""
    from playwright.sync_api import sync_playwright

    viewer = serve(hull_dir, port=0)
    try:
        viewer.show_inflated.value = False
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
            try:
                page = browser.new_page(viewport={"width": 1280, "height": 800})
                page.goto(viewer.url)
                page.wait_for_selector("canvas", timeout=30000)
                page.get_by_text(re.compile(r"convex approximation")).wait_for(timeout=30000)
                canvas = page.locator("canvas").first
                shot = os.environ.get("POLYFOLD_HULLS_SCREENSHOT")
                if shot:
                    close = page.locator("button.mantine-Notification-closeButton, .mantine-Notification-root button")
                    if close.count():
                        close.first.click()
                    _stable_shot(canvas)
                    page.screenshot(path=shot)
                changed = _changed_by_click(page, canvas, "Show original", lambda: not viewer._original_node.visible,
                                            "the original hidden")
                assert changed > 0.005, f"only {changed:.2%} of the canvas changed hiding the original"
            finally:
                browser.close()
    finally:
        viewer.stop()
