"""The browser viewer behind `polyfold view` (issue 7), built on viser.

In: an output folder of `polyfold make` (assembly.json, report.json, part-K.obj, piece-X.fold, and
model.glb for a model with a texture or colours).
Out: a local web page (viser serves its bundled client; nothing else is served, nothing is
fetched) showing the model with its parts in colour, the flat nets of the chosen part, its
folding animation along the verified path of every piece (folded, the model is shown in the
texture or colours of model.glb instead, issue 21: the "Model's colours" box), an inflation
panel (mode, pressure, stiffness ratio, steps; hyperbolic vertices in red, their count as
"HV: N") and buttons that run `make` / export the inflated mesh into the folder.

Only its own page gets in: every request and websocket handshake must come with the right Host,
Origin and session token (the printed URL's `?token=`, then a SameSite cookie), else 403 before
viser sees it (`view_guard`).

The folder itself is read by `pipeline.folder.load_folder` (a frozen `MakeFolder`, whose pieces
pose themselves along their folding paths); here: `check_host`, `serve` (starts the server and
returns at once), `wait` (blocks until Ctrl+C, for the CLI) and the `Viewer` (the page).
"""

from __future__ import annotations

import contextlib
import math
import io
import ipaddress
import re
import threading
import time
from dataclasses import replace
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import PolyfoldError, one_line
from ..formats.meshes import obj_text
from ..mesh.mesh import Mesh
from ..pipeline.folder import MakeFolder, ViewPiece, load_folder, make_folder
from ..pipeline.options import MakeOptions
from .view_guard import Gate, guarded_start

DEFAULT_HOST = "127.0.0.1"
DEBOUNCE_S = 0.3  # inflation re-runs wait until the sliders rest this long
PLAY_SECONDS = 4.0  # one play of the folding animation, flat to folded
PLAY_FPS = 25.0
GHOST = (190, 190, 190)  # colour of the parts that are not being animated
GHOST_OPACITY = 0.18
LINE_COLORS = {"M": (214, 39, 40), "V": (31, 119, 180)}  # mountain red, valley blue (as the sheets)
CUT_COLOR = (40, 40, 40)
HV_COLOR = (230, 20, 20)
INFLATED_COLOR = (150, 175, 215)
ORIGINAL_COLOR = (205, 200, 190)  # the mesh a convex approximation stands for, left of it
ALL_PARTS = "all parts"
NET_GAP = 0.8  # view units (the model is 2 long): model to nets, on the right
INFLATED_GAP = 1.4  # model to the inflated copy, on the left


# ----------------------------------------------------------------------------------------------
# Serving


def check_host(host: str, explicit: bool) -> str:
    """The address to listen on. Only an IP address or 'localhost'; anything that is not a
    loopback address must have been asked for explicitly (--host), since the page can run make
    and write into the folder."""
    h = (host or "").strip()
    if h.lower() == "localhost":
        return "127.0.0.1"
    try:
        addr = ipaddress.ip_address(h)
    except ValueError:
        raise PolyfoldError(f"--host must be an IP address such as 127.0.0.1 or 0.0.0.0 (or localhost), "
                            f"not {host!r}") from None
    if not addr.is_loopback and not explicit:
        raise PolyfoldError(f"refusing to listen on {h}, which other machines can reach: "
                            f"pass --host {h} explicitly to allow it")
    return str(addr)


@contextlib.contextmanager
def _quiet_stdout():
    """viser prints a banner and 'Server stopped' on stdout; the CLI prints its own one line."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield


class _Debounced:
    """Runs `func()` in a background thread once requests have stopped for `delay` seconds;
    requests made while it runs cause one more run afterwards."""

    def __init__(self, func: Callable[[], None], delay: float) -> None:
        self._func = func
        self._delay = delay
        self._cv = threading.Condition()
        self._last = 0.0
        self._pending = False
        self._closed = False
        self._thread = threading.Thread(target=self._loop, daemon=True, name="polyfold-view-debounce")
        self._thread.start()

    def request(self) -> None:
        with self._cv:
            self._pending = True
            self._last = time.monotonic()
            self._cv.notify()

    def close(self) -> None:
        with self._cv:
            self._closed = True
            self._cv.notify()

    def _loop(self) -> None:
        while True:
            with self._cv:
                while not self._pending and not self._closed:
                    self._cv.wait()
                if self._closed:
                    return
                # wait until the requests have been quiet for `delay`
                while not self._closed and time.monotonic() - self._last < self._delay:
                    self._cv.wait(self._delay - (time.monotonic() - self._last))
                if self._closed:
                    return
                self._pending = False
            try:
                self._func()
            except Exception:  # a failed run must not kill the worker; func reports its own errors
                pass


def _wait_until(done: Callable[[], bool], timeout: float) -> bool:
    """Poll done() every 50 ms until it holds or `timeout` seconds have passed; -> done()."""
    end = time.monotonic() + timeout
    while not done() and time.monotonic() < end:
        time.sleep(0.05)
    return done()


def _crop_texture(image: np.ndarray, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The part of a texture (H, W, C) that UVs (N, 2) use (v up; a pixel of margin), with the
    UVs moved onto it, so that every part does not carry the whole picture to the browser. UVs
    outside [0, 1] (a repeating texture) keep the whole picture."""
    if not len(uv) or uv.min() < 0.0 or uv.max() > 1.0:
        return image, uv
    h, w = image.shape[:2]
    px, py = uv[:, 0] * w, (1.0 - uv[:, 1]) * h  # pixel coordinates, rows from the top
    x0, x1 = max(int(np.floor(px.min())) - 1, 0), min(int(np.ceil(px.max())) + 1, w)
    y0, y1 = max(int(np.floor(py.min())) - 1, 0), min(int(np.ceil(py.max())) + 1, h)
    moved = np.stack([(px - x0) / (x1 - x0), 1.0 - (py - y0) / (y1 - y0)], axis=1)
    return image[y0:y1, x0:x1], moved


class Viewer:
    """A running viewer: the viser server, its scene and GUI. Create with `serve`."""

    def __init__(self, server, folder: MakeFolder, source: Mesh, source_path: Path | None, root: Path,
                 gate: Gate) -> None:
        self.server = server
        self.gate = gate  # what every request must show (view_guard)
        self.folder = folder
        self.root = root.resolve()  # make / export write only inside this folder
        self.source = source  # the mesh the inflation panel inflates
        self.source_path = source_path
        self.port = int(server.get_port())
        self.url = gate.url(self.port)  # with the session token: the page opens only from this URL
        self.inflation = None  # last InflateResult
        self.inflation_runs = 0
        self.make_runs = 0
        self._lock = threading.RLock()
        self._playing = threading.Event()
        self._play_thread: threading.Thread | None = None
        self._stopped = False
        self._part_nodes: list = []
        self._net_nodes: list = []
        self._fold_nodes: list = []  # (piece, mesh handle)
        self._build_nodes: list = []  # per piece, folded in place, for the build steps
        self.look_nodes: list = []  # per part, its faces in the model's look (GLB handles; none without one)
        self._animated: set[int] = set()  # the parts whose pieces fold
        self._make_running = False

        self._set_view_frame(source)
        server.gui.configure_theme(show_share_button=False, show_logo=False, control_width="medium")
        self._set_camera()
        self._add_panels()
        self._add_inflated_nodes()
        self._original_node = None
        self._connect()
        self._inflater = _Debounced(self._inflate, DEBOUNCE_S)
        self.load(folder)
        self._inflater.request()

    # ---- set-up

    def _set_view_frame(self, source: Mesh) -> None:
        """A fixed view frame (camera and offsets stay put when a new make result is loaded): the
        model centred at the origin, longest side 2, z up. As the project's PNG previews
        (raster.render_mesh) do, the axis of middle extent is up and the longest one runs left
        to right."""
        v = source.vertices[np.unique(source.faces)]
        lo, hi = v.min(axis=0), v.max(axis=0)
        ext = hi - lo
        order = np.argsort(ext, kind="stable")  # shortest, middle, longest
        rot = np.zeros((3, 3))
        rot[0, order[2]] = rot[1, order[0]] = rot[2, order[1]] = 1.0  # view x, y, z <- model axes
        if np.linalg.det(rot) < 0:
            rot[1] *= -1.0  # a rotation, not a mirror image
        self._rot = rot
        self._center = (lo + hi) / 2
        self._k = 2.0 / max(float(ext.max()), 1e-12)
        self._half = np.abs(rot @ ext) * self._k / 2  # half extents along view x, y, z

    def _set_camera(self) -> None:
        """z up; the camera takes in the inflated copy, the model and the row of nets."""
        self.server.scene.set_up_direction("+z")
        hx, hz = float(self._half[0]), float(self._half[2])
        left, right = self._inflated_offset()[0] - hx, hx + NET_GAP + self._net_row_width()
        # look a little right of the middle: the control panel covers the right of the page
        mid = (left + right) / 2 + 0.12 * (right - left)
        dist = 0.5 * (right - left) + 0.8
        self.server.initial_camera.look_at = (mid, 0.0, -0.3 * hz)
        self.server.initial_camera.position = (mid, -dist, 0.55 * dist)

    def _add_panels(self) -> None:
        """The title and the Folding, Inflation and Make panels."""
        gui = self.server.gui
        self._title = gui.add_markdown("")
        with gui.add_folder("Folding"):
            self.part_dropdown = gui.add_dropdown("Part", [ALL_PARTS], initial_value=ALL_PARTS,
                                                  hint="The part whose pieces fold; the others are ghosted.")
            self.fold_slider = gui.add_slider("Fold", 0.0, 1.0, 0.01, 1.0, hint="0 = flat net, 1 = folded onto the model.")
            self.play_button = gui.add_button("Play", hint="Play the folding path from flat to folded.")
            self.original_checkbox = gui.add_checkbox(
                "Show original", True, disabled=self.folder.original is None,
                hint="A convex approximation (make --approximate hulls): the mesh it stands for, on its left.")
            self.look_checkbox = gui.add_checkbox(
                "Model's colours", True, hint="Folded, show the model in its texture / colours (model.glb) "
                "instead of the part colours.")
            self.fold_info = gui.add_markdown("")
        with gui.add_folder("Build steps"):
            self.step_slider = gui.add_slider(
                "Step", 0, 1, 1, 0, hint="The assembly guide's steps (guide.pdf): the model part-built, the new "
                "piece in full colour. 0 = off.")
            self.step_info = gui.add_markdown("")
        with gui.add_folder("Inflation"):
            self.mode_dropdown = gui.add_dropdown("Mode", ["constrained", "uniform"], initial_value="constrained")
            self.pressure_slider = gui.add_slider("Pressure", 0.1, 1.0, 0.05, 0.5)
            self.stiffness_slider = gui.add_slider("Stiffness ratio", 1.0, 20.0, 0.5, 10.0,
                                                   hint="Stiff-edge multiplier (constrained mode).")
            self.steps_slider = gui.add_slider("Steps", 0, 20000, 100, 2000, hint="max_steps of the inflation run.")
            self.show_inflated = gui.add_checkbox("Show inflated", True)
            self.hv_text = gui.add_markdown(f"input HV {int(self.source.hyperbolic.sum())}")
        with gui.add_folder("Make"):
            self.output_text = gui.add_text("Output folder", ".", hint="Inside the viewed folder ('.' = the folder itself).")
            self.use_inflated = gui.add_checkbox("Use inflated mesh", True,
                                                 hint="Make (and export) the mesh inflated with the settings above.")
            self.make_button = gui.add_button("Run make")
            self.export_button = gui.add_button("Export inflated OBJ")
            self.make_status = gui.add_markdown("")

    def _add_inflated_nodes(self) -> None:
        """The inflated copy (left of the model) and its hyperbolic vertices, hidden until inflated."""
        scene = self.server.scene
        self._inflated_mesh = scene.add_mesh_simple(
            "/inflated", np.zeros((3, 3), np.float32), np.array([[0, 1, 2]], np.uint32), color=INFLATED_COLOR,
            flat_shading=True, side="double", position=self._inflated_offset(), visible=False)
        self._hv_points = scene.add_point_cloud(
            "/inflated/hv", np.zeros((0, 3), np.float32), HV_COLOR, point_size=0.04, point_shape="circle",
            visible=False)

    def _connect(self) -> None:
        """The callbacks of the controls."""
        self.part_dropdown.on_update(lambda _: self._leave_steps() or self._show_part())
        self.fold_slider.on_update(lambda _: self._leave_steps() or self._pose())
        self.step_slider.on_update(lambda _: self._show_step())
        self.play_button.on_click(lambda _: self.toggle_play())
        self.look_checkbox.on_update(lambda _: self._show_look())
        for h in (self.mode_dropdown, self.pressure_slider, self.stiffness_slider, self.steps_slider):
            h.on_update(lambda _: self._inflater.request())
        self.show_inflated.on_update(lambda _: self._show_inflated_visibility())
        self.original_checkbox.on_update(lambda _: self._show_original())
        self.make_button.on_click(lambda _: self._start(self._run_make))
        self.export_button.on_click(lambda _: self._start(self._export))

    # ---- geometry helpers

    def _to_view(self, x: np.ndarray) -> np.ndarray:
        return (((np.asarray(x, dtype=np.float64) - self._center) @ self._rot.T) * self._k).astype(np.float32)

    def _original_offset(self) -> tuple[float, float, float]:
        return (-2.0 * float(self._half[0]) - INFLATED_GAP, 0.0, 0.0)  # left of the model

    def _inflated_offset(self) -> tuple[float, float, float]:
        """Left of the model; left of the original when the folder is a convex approximation."""
        steps = 2 if self.folder.original is not None else 1
        return (steps * (-2.0 * float(self._half[0]) - INFLATED_GAP), 0.0, 0.0)

    def _net_row_width(self) -> float:
        return max(2.5, 2.5 * float(self._half[0]))

    # ---- scene

    def load(self, folder: MakeFolder) -> None:
        """Show a make folder: part meshes, the part picker, nets and animation."""
        from ..formats.raster import part_colors

        with self._lock:
            self.folder = folder
            for h in self._part_nodes:
                h.remove()
            self._part_nodes = []
            self._colors = [tuple(int(c) for c in rgb) for rgb in part_colors(len(folder.parts))]
            for k, part in enumerate(folder.parts):
                self._part_nodes.append(self.server.scene.add_mesh_simple(
                    f"/model/part-{k}", self._to_view(part.vertices), part.faces.astype(np.uint32),
                    color=self._colors[k], flat_shading=True, side="double"))
            for h in self.look_nodes:
                h.remove()
            self.look_nodes = []
            if folder.look is not None:
                for k in range(len(folder.parts)):
                    self.look_nodes.append(self.server.scene.add_mesh_trimesh(
                        f"/look/part-{k}", self.part_look_mesh(k), visible=False))
            self.look_checkbox.disabled = folder.look is None
            self._add_build_nodes()
            options = [ALL_PARTS] + [self._part_label(k) for k in range(len(folder.parts))]
            self.part_dropdown.options = options
            verified = sum(p.verified for p in folder.pieces)
            self._load_original(folder.original)
            self._title.content = (f"**{folder.model}**"
                                   + (" (convex approximation; the original on its left)" if folder.original is not None
                                      else "")
                                   + f": {len(folder.parts)} part(s), {len(folder.pieces)} piece(s), "
                                   f"{verified}/{len(folder.pieces)} folding paths verified")
            self._show_part()

    def _load_original(self, original: Mesh | None) -> None:
        """The mesh a convex approximation stands for (the folder's original.obj), left of the
        model; none for other folders."""
        if self._original_node is not None:
            self._original_node.remove()
            self._original_node = None
        self.original_checkbox.disabled = original is None
        if original is not None:
            self._original_node = self.server.scene.add_mesh_simple(
                "/original", self._to_view(original.vertices), original.faces.astype(np.uint32), color=ORIGINAL_COLOR,
                flat_shading=True, side="double", position=self._original_offset(),
                visible=bool(self.original_checkbox.value))

    def _show_original(self) -> None:
        if self._original_node is not None:
            self._original_node.visible = bool(self.original_checkbox.value)

    def _add_build_nodes(self) -> None:
        """Every piece folded in place (hidden until a build step is picked), in the guide's piece
        colours; the step slider's range."""
        from ..guide.pictures import piece_palette

        for h in self._build_nodes:
            h.remove()
        pieces = self.folder.pieces
        self._piece_colors = piece_palette(len(pieces))
        self._build_nodes = []
        for i, piece in enumerate(pieces):
            corners = self._to_view(piece.pose(1.0).reshape(-1, 3))
            self._build_nodes.append(self.server.scene.add_mesh_simple(
                f"/build/piece-{i}", corners, np.arange(len(corners), dtype=np.uint32).reshape(-1, 3),
                color=tuple(int(c) for c in self._piece_colors[i]), flat_shading=True, side="double",
                visible=False))
        n = len(self.folder.steps)
        self.step_slider.value = 0
        self.step_slider.max = max(1, n)
        self.step_slider.disabled = n == 0
        self.step_info.content = (f"{n} steps (as in guide.pdf)" if n else
                                  "no build steps in this folder (made with --no-guide?)")

    def part_look_mesh(self, k: int):
        """Part k in the model's look (folder.look), in the view frame: a trimesh, every face with
        corners of its own, with the texture and its UVs, or the colours per corner; a matte,
        double-sided material (as paper)."""
        import trimesh
        from PIL import Image

        part, look = self.folder.parts[k], self.folder.look
        corners = self._to_view(part.vertices[part.faces].reshape(-1, 3))
        tris = np.arange(len(corners)).reshape(-1, 3)
        if look.textured:
            image, uv = _crop_texture(look.image, look.part_uv(k).reshape(-1, 2))
            material = trimesh.visual.material.PBRMaterial(
                baseColorTexture=Image.fromarray(image), metallicFactor=0.0, roughnessFactor=1.0, doubleSided=True)
            visual = trimesh.visual.TextureVisuals(uv=uv, material=material)
        else:  # vertex colours (COLOR_0) under a white material: glTF's default one is metallic
            material = trimesh.visual.material.PBRMaterial(metallicFactor=0.0, roughnessFactor=1.0, doubleSided=True)
            visual = trimesh.visual.TextureVisuals(material=material)
            visual.vertex_attributes["color"] = look.part_colors(k).reshape(-1, 4)
        return trimesh.Trimesh(corners, tris, visual=visual, process=False)

    def _part_label(self, k: int) -> str:
        names = [p.name for p in self.folder.pieces if p.part == k]
        return f"part {k} ({', '.join(names)})" if names else f"part {k}"

    def _chosen_part(self) -> int | None:
        value = self.part_dropdown.value
        m = re.match(r"part (\d+)", value)
        return int(m.group(1)) if m else None

    def _show_part(self) -> None:
        """Rebuild the nets and the animated pieces for the part picked in the dropdown."""
        with self._lock:
            for h in self._net_nodes:
                h.remove()
            for _, h in self._fold_nodes:
                h.remove()
            self._net_nodes, self._fold_nodes = [], []
            chosen = self._chosen_part()
            parts = range(len(self.folder.parts)) if chosen is None else [chosen]
            self._animated = set(parts)
            pieces = [p for p in self.folder.pieces if p.part in parts]
            for k, node in enumerate(self._part_nodes):
                animated = k in parts
                # The animated part is drawn by its pieces; the rest is ghosted while one part folds.
                node.visible = not animated
                node.color = self._colors[k] if chosen is None else GHOST
                node.opacity = None if chosen is None else GHOST_OPACITY
            for i, piece in enumerate(pieces):  # node names by index: piece names come from a file
                n_f = piece.tree.n_faces
                h = self.server.scene.add_mesh_simple(
                    f"/fold/piece-{i}", np.zeros((3 * n_f, 3), np.float32),
                    np.arange(3 * n_f, dtype=np.uint32).reshape(-1, 3), color=self._colors[piece.part],
                    flat_shading=True, side="double")
                self._fold_nodes.append((piece, h))
            self._add_nets(pieces)
            bad = [p.name for p in pieces if not p.verified]
            errs = [p.fit_error for p in pieces if not math.isnan(p.fit_error)]
            lines = [f"{len(pieces)} piece(s): {', '.join(p.name for p in pieces)}"]
            if errs:
                lines.append(f"folded vs model: max corner error {max(errs) * self._k / 2:.1e} of the model size")
            if bad:
                lines.append(f"no verified path (shown folded): {', '.join(bad)}")
            self.fold_info.content = "  \n".join(lines)
            self._pose()

    def _add_nets(self, pieces: list[ViewPiece]) -> None:
        """Flat nets of `pieces` on the ground to the right of the model, printed side up, creases
        drawn as on the sheets (mountain red, valley blue, cuts dark)."""
        x0 = float(self._half[0]) + NET_GAP
        y0 = -float(self._half[1])
        ground = -float(self._half[2])
        row_width = self._net_row_width()
        x = y = shelf = 0.0
        gap = 0.15
        for i, piece in enumerate(pieces):
            xy = piece.flat_xy * self._k
            faces = piece.net.faces
            lo, hi = xy.min(axis=0), xy.max(axis=0)
            w, d = hi - lo
            if x > 0 and x + w > row_width:
                x, y, shelf = 0.0, y + shelf + gap, 0.0
            # the crease pattern's +z (outer, printed side) faces up; rows go away from the viewer
            u = xy[:, 0] - lo[0] + x0 + x
            v = xy[:, 1] - lo[1] + y0 + y
            pts = np.stack([u, v, np.full_like(u, ground)], axis=1).astype(np.float32)
            self._net_nodes.append(self.server.scene.add_mesh_simple(
                f"/net/piece-{i}", pts, faces.astype(np.uint32), color=self._colors[piece.part],
                flat_shading=True, side="double", opacity=0.9))
            edges = piece.net.edges
            assign = piece.net.assignments
            lifted = pts + np.array([0.0, 0.0, 0.002], np.float32)
            colors = np.array([LINE_COLORS.get(a, CUT_COLOR if a in ("B", "C") else (120, 120, 120)) for a in assign],
                              dtype=np.uint8)
            self._net_nodes.append(self.server.scene.add_line_segments(
                f"/net/lines-{i}", lifted[edges], colors[:, None, :].repeat(2, axis=1),
                thickness=0.006))
            x += w + gap
            shelf = max(shelf, d)

    def _pose(self) -> None:
        """Move the animated pieces to the slider's fraction of their folding paths."""
        with self._lock:
            t = float(self.fold_slider.value)
            for piece, h in self._fold_nodes:
                h.vertices = self._to_view(piece.pose(t).reshape(-1, 3))
            self._show_look()

    def _show_look(self) -> None:
        """Folded (the slider at 1, or no piece of the part has a path to move along), an animated
        part is shown in the model's look instead of its pieces in the part colour, when the
        folder has a look and the "Model's colours" box is ticked."""
        with self._lock:
            on = bool(self.look_checkbox.value) and bool(self.look_nodes)
            folded = float(self.fold_slider.value) >= 1.0
            for k, node in enumerate(self.look_nodes):
                mine = [(p, h) for p, h in self._fold_nodes if p.part == k]
                shown = on and k in self._animated and (folded or not any(p.verified for p, _ in mine))
                node.visible = shown
                for _, h in mine:
                    h.visible = not shown

    def _leave_steps(self) -> None:
        """Back from a build step to the folding view (moving the fold slider or picking a part)."""
        if int(self.step_slider.value) != 0:
            self.step_slider.value = 0

    def _show_step(self) -> None:
        """The model after build step k of the slider (0: the folding view): the pieces placed so
        far folded in place, the step's new piece (or, gluing on, the pieces it glues) in full
        colour, the rest lighter; everything else hidden."""
        from ..guide.pictures import lighter

        with self._lock:
            k = int(self.step_slider.value)
            steps = self.folder.steps
            if k <= 0 or not steps:
                for h in self._build_nodes:
                    h.visible = False
                self._show_part()
                return
            k = min(k, len(steps))
            step = steps[k - 1]
            order = self.folder.placed_after(k)
            placed = set(order)
            names = [p.name for p in self.folder.pieces]
            if step.piece in names:
                new = {names.index(step.piece)}
            else:  # gluing on: the pieces of its seams (the last placed and those it glues to)
                new = {names.index(n) for n in step.attach_to if n in names}
                if step.kind == "glue" and order:
                    new.add(order[-1])
            for node in (*self._part_nodes, *self.look_nodes, *self._net_nodes, *(h for _, h in self._fold_nodes)):
                node.visible = False
            for i, h in enumerate(self._build_nodes):
                h.visible = i in placed
                rgb = self._piece_colors[i] if i in new else lighter(self._piece_colors[i], 0.6)
                h.color = tuple(int(c) for c in rgb)
            what = {"piece": f"fold and attach piece **{step.piece}**", "glue": "glue on",
                    "join": f"join part {step.part + 1} to the model"}.get(step.kind, step.kind)
            sheets = f" (sheet {', '.join(map(str, step.sheets))})" if step.sheets else ""
            self.step_info.content = (f"**Step {k}/{len(steps)}**: {what}{sheets}  \n"
                                      f"glue: {', '.join(step.labels) or 'nothing'}"
                                      + (f"  \nto: {', '.join(step.attach_to)}" if step.attach_to else ""))

    # ---- controls

    def set_step(self, k: int) -> None:
        """Show build step k (0: the folding view), as the step slider does."""
        self.step_slider.value = int(min(max(0, k), max(1, len(self.folder.steps))))

    def set_part(self, part: int | None) -> None:
        """Pick a part (None: all parts), as the dropdown does."""
        self.part_dropdown.value = ALL_PARTS if part is None else self._part_label(part)

    def set_fold(self, t: float) -> None:
        """Move the fold slider (0 flat .. 1 folded), as the GUI does."""
        self.fold_slider.value = float(min(1.0, max(0.0, t)))

    def toggle_play(self) -> None:
        """Play / pause the folding animation."""
        if self._playing.is_set():
            self._playing.clear()
            return
        if self.fold_slider.value >= 1.0:
            self.set_fold(0.0)
        self._playing.set()
        self.play_button.label = "Pause"
        self._play_thread = threading.Thread(target=self._play, daemon=True, name="polyfold-view-play")
        self._play_thread.start()

    def _play(self) -> None:
        step = 1.0 / (PLAY_SECONDS * PLAY_FPS)
        try:
            while self._playing.is_set() and not self._stopped:
                t = min(1.0, float(self.fold_slider.value) + step)
                self.set_fold(t)
                if t >= 1.0:
                    break
                time.sleep(1.0 / PLAY_FPS)
        finally:
            self._playing.clear()
            if not self._stopped:
                self.play_button.label = "Play"

    # ---- inflation

    def _inflate(self) -> None:
        from ..inflate.inflate import inflate

        mode = str(self.mode_dropdown.value)
        p, r, n = float(self.pressure_slider.value), float(self.stiffness_slider.value), int(self.steps_slider.value)
        hv0 = int(self.source.hyperbolic.sum())
        # keep the last count on screen while the new run goes (readers never see it vanish)
        last = self.hv_text.content.split("  \n")[0]
        self.hv_text.content = f"{last}  \ninflating ({mode}, pressure {p:.2f}, stiffness {r:g}, {n} steps) ..."
        try:
            res = inflate(self.source, mode=mode, pressure=p, stiffness_ratio=r, max_steps=n)
        except Exception as exc:  # shown in the page; the next slider change tries again
            self.hv_text.content = f"input HV {hv0}  \ninflation failed: {one_line(exc)}"
            return
        mesh = res.mesh
        hv = mesh.hyperbolic
        with self._lock:
            self.inflation = res
            self._inflated_mesh.vertices = self._to_view(mesh.vertices)
            self._inflated_mesh.faces = mesh.faces.astype(np.uint32)
            self._hv_points.points = self._to_view(mesh.vertices[hv]).reshape(-1, 3)
            self._show_inflated_visibility()
            self.inflation_runs += 1
        self.hv_text.content = (f"HV: {int(hv.sum())} (input {hv0})  \n{mode}, pressure {p:.2f}, stiffness {r:g}, "
                                f"{res.steps} steps: {res.stop_reason}")

    def _show_inflated_visibility(self) -> None:
        on = bool(self.show_inflated.value) and self.inflation is not None
        self._inflated_mesh.visible = on
        self._hv_points.visible = on

    def wait_inflation(self, runs: int = 1, timeout: float = 30.0) -> bool:
        """Wait until at least `runs` inflation runs finished (for tests and scripts)."""
        return _wait_until(lambda: self.inflation_runs >= runs, timeout)

    # ---- make / export

    def _start(self, job: Callable[[], None]) -> None:
        with self._lock:
            if self._make_running:
                self.make_status.content = "busy: wait for the running job to finish"
                return
            self._make_running = True
        self.make_button.disabled = self.export_button.disabled = True

        def run() -> None:
            try:
                job()
            except Exception as exc:  # report in the page; the server keeps running
                self.make_status.content = f"failed: {one_line(exc)}"
            finally:
                with self._lock:
                    self._make_running = False
                if not self._stopped:
                    self.make_button.disabled = self.export_button.disabled = False

        threading.Thread(target=run, daemon=True, name="polyfold-view-make").start()

    def output_dir(self) -> Path:
        """The folder the Make panel names, which must lie inside the viewed folder."""
        text = str(self.output_text.value).strip() or "."
        out = (self.root / text).resolve()
        if out != self.root and self.root not in out.parents:
            raise PolyfoldError(f"the output folder must be inside {self.root} (got {text!r})")
        return out

    def _mesh_for_make(self) -> tuple[Mesh, str]:
        res = self.inflation
        if self.use_inflated.value and res is not None:
            return res.mesh, "inflated"
        return self.source, "original"

    def _stem(self) -> str:
        return re.sub(r"[^A-Za-z0-9_.-]+", "_", Path(self.folder.model).stem) or "model"

    def _export(self) -> None:
        from ..formats.files import atomic_write

        out = self.output_dir()
        mesh, kind = self._mesh_for_make()
        out.mkdir(parents=True, exist_ok=True)
        name = f"{self._stem()}-{kind}.obj" if kind == "original" else f"{self._stem()}-inflated-{self.mode_dropdown.value}.obj"
        atomic_write(out / name, obj_text(mesh.vertices, mesh.faces, f"{self.folder.model} ({kind}) exported by polyfold view"))
        self.make_status.content = f"exported {name} to {out}"

    def _run_make(self) -> None:
        """Run make on the original or inflated mesh into the output folder, then show the result."""
        out = self.output_dir()
        mesh, kind = self._mesh_for_make()
        t0 = time.perf_counter()
        opts = replace(self.folder.options or MakeOptions(), inflate="none")

        def progress(stage: str, msg: str) -> None:
            self.make_status.content = f"make: {stage}: {msg}"

        if kind == "original" and self.source_path is not None:
            folder = make_folder(self.source_path, out, opts, progress)
        else:  # the mesh in memory, named after the model (the report and the sheets name it)
            folder = make_folder(mesh, out, opts, progress, name=f"{self._stem()}{'' if kind == 'original' else '-inflated'}")
        self.make_runs += 1
        verified = sum(p.verified for p in folder.pieces)
        self.make_status.content = (f"make ({kind} mesh) done in {time.perf_counter() - t0:.1f} s: "
                                    f"{len(folder.parts)} part(s), {len(folder.pieces)} piece(s), "
                                    f"{verified}/{len(folder.pieces)} paths verified, in {out}")
        self.load(folder)

    def wait_make(self, runs: int = 1, timeout: float = 120.0) -> bool:
        """Wait until at least `runs` make runs finished (for tests and scripts)."""
        return _wait_until(lambda: self.make_runs >= runs, timeout)

    # ---- life cycle

    def stop(self) -> None:
        """Stop the animation, the inflation worker and the server."""
        if self._stopped:
            return
        self._stopped = True
        self._playing.clear()
        self._inflater.close()
        with _quiet_stdout():
            self.server.stop()


def serve(folder: MakeFolder | str | Path, host: str = DEFAULT_HOST, port: int = 8080, *,
          allow_remote: bool = False, source: Mesh | None = None, source_path: str | Path | None = None) -> Viewer:
    """Start the viewer on host:port (port 0: any free port; a taken port moves to the next free
    one) and return at once. Only loopback addresses unless allow_remote (the CLI's explicit
    --host). source: the mesh the inflation panel and make use (default: the folder's parts
    welded); source_path: its file, if any. Serves only viser's bundled client."""
    import viser

    host = check_host(host, allow_remote)
    if not 0 <= int(port) <= 65535:
        raise PolyfoldError(f"--port must be 0..65535, not {port}")
    if not isinstance(folder, MakeFolder):
        folder = load_folder(folder)
    gate = Gate(host)
    with _quiet_stdout(), guarded_start(gate):
        server = viser.ViserServer(host=host, port=int(port), label="polyfold", verbose=False)
    try:
        # the inflation panel and "Run make" work on the mesh the folder was made from: a convex
        # approximation's original.obj, else the parts welded back together
        whole = folder.original if folder.original is not None else folder.whole
        return Viewer(server, folder, source if source is not None else whole,
                      Path(source_path) if source_path is not None else None, folder.path, gate)
    except BaseException:
        with _quiet_stdout():
            server.stop()
        raise


def wait(viewer: Viewer) -> None:
    """Block until Ctrl+C (or SIGTERM), then stop the viewer."""
    import signal

    def on_term(signum, frame):  # noqa: ARG001 - a polite kill ends like Ctrl+C (temp folders removed)
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, on_term)
    try:
        while True:
            time.sleep(0.5)
    except KeyboardInterrupt:
        pass
    finally:
        signal.signal(signal.SIGTERM, previous)
        viewer.stop()
