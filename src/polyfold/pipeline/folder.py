"""A `polyfold make` output folder, read back: `load_folder` -> `MakeFolder`.

In: the folder (assembly.json with its build steps, report.json, part-K.obj, piece-X.fold, and
model.glb when the model has a texture or colours). Out: the parts as meshes, the whole model (the parts welded back
together), the model's look matched to the parts' faces (`ModelLook`), and every piece ready to
be posed along its folding path (`ViewPiece.pose`: face corners in the model frame at a fraction
t of the path). The viewer draws it; tests and scripts use it without a browser. `make_folder`
runs make, then reads the result.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import PolyfoldError
from ..fold.plan import path_at as path_degrees  # (FOLD degrees here; the name its callers know)
from ..fold.tree import FoldTree, fold_positions
from ..formats.fold import FoldNet, fold_net, read_fold
from ..formats.meshes import read_mesh_as_is
from ..mesh.geometry import fold_deg_to_rho
from ..mesh.mesh import Mesh
from ..mesh.repair import LoadedMesh
from .options import MakeOptions
from .report import Assembly, AssemblyStep, MakeReport


@dataclass(frozen=True, eq=False)
class ViewPiece:
    """One piece of a make folder, ready to animate.

    fold: its FOLD dict; net: the net read from it (`formats.fold.fold_net`: tree, flat net, path);
    frames (K, E): the folding path in FOLD degrees (valley positive), None when the piece has no
    verified path (it is then shown folded only);
    rotation (P, 3, 3) / translation (P, 3): per FOLD piece, the rigid motion (Kabsch fit of the
    goal pose onto the foldedForm) that puts the folded net onto the model, in the file's unit;
    unit: model units per unit of the file (1 / `polyfold:mmPerModelUnit` for make's pieces,
    which are in mm; 1 for files in the model's units); fit_error: largest corner distance
    between the aligned goal pose and the foldedForm, in model units (nan without a foldedForm
    frame).
    """

    name: str
    part: int
    fold: dict
    net: FoldNet
    frames: np.ndarray | None
    rotation: np.ndarray
    translation: np.ndarray
    fit_error: float
    unit: float = 1.0

    @property
    def verified(self) -> bool:
        return self.frames is not None

    @property
    def tree(self) -> FoldTree:
        return self.net.tree

    @property
    def flat_xy(self) -> np.ndarray:
        """The flat net's vertices (V, 2) in model units (printed side +z)."""
        return self.net.coords * self.unit

    def pose(self, t: float) -> np.ndarray:
        """Face corners (F, 3, 3) in the model frame at fraction t in [0, 1] of the folding path
        (0 flat, 1 folded onto the model). Without a path the piece stays folded."""
        deg = self.net.goal if self.frames is None else path_degrees(self.frames, t)
        corners = fold_positions(self.tree, fold_deg_to_rho(deg))
        piece = self.tree.piece
        posed = np.einsum("fij,fkj->fki", self.rotation[piece], corners) + self.translation[piece][:, None, :]
        return posed * self.unit if self.unit != 1.0 else posed


@dataclass(frozen=True, eq=False)
class ModelLook:
    """model.glb of a make folder: the model as made, in the look its sheets print.

    corners (C, 3): the model's face corners as stored (float32; every face its own 3 corners, so
    C = 3 x faces); either a texture, uv (C, 2) with image (H, W, 3 or 4) uint8, or colors (C, 4)
    uint8 RGBA per corner; part_corners: per part, (F_k, 3) the row of `corners` of each corner of
    the part's faces (in the part's face and corner order; `load_folder` matches them by position).
    """

    corners: np.ndarray
    uv: np.ndarray | None
    image: np.ndarray | None
    colors: np.ndarray | None
    part_corners: tuple[np.ndarray, ...] = ()

    @property
    def textured(self) -> bool:
        return self.image is not None

    def part_uv(self, k: int) -> np.ndarray | None:
        """UVs (F_k, 3, 2) of part k's face corners; None without a texture."""
        return None if self.uv is None else self.uv[self.part_corners[k]]

    def part_colors(self, k: int) -> np.ndarray | None:
        """RGBA (F_k, 3, 4) uint8 of part k's face corners; None for a texture."""
        return None if self.colors is None else self.colors[self.part_corners[k]]


@dataclass(frozen=True, eq=False)
class MakeFolder:
    """A `polyfold make` output folder: parts (in part order), pieces (in assembly order), the
    whole model (the parts welded back together), the model's file name, the make options of
    report.json (None when there is no readable report) and the model's look of model.glb (None
    when the folder has none: a model without texture or colours, or made with --color none)."""

    path: Path
    model: str
    parts: tuple[Mesh, ...]
    pieces: tuple[ViewPiece, ...]
    whole: Mesh
    options: MakeOptions | None
    look: ModelLook | None = None
    steps: tuple[AssemblyStep, ...] = ()  # the guide's build steps (none: made with --no-guide)
    original: Mesh | None = None  # original.obj: what a convex approximation (--approximate hulls) stands for

    def placed_after(self, step: int) -> list[int]:
        """The pieces (indices into `pieces`) in the model after build step `step` (1-based), in
        the order they came."""
        index = {p.name: i for i, p in enumerate(self.pieces)}
        return [index[s.piece] for s in self.steps[:step] if s.piece is not None and s.piece in index]


def _kabsch(p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation R and translation t minimising |R p + t - q| over the rows (a proper rotation)."""
    cp, cq = p.mean(axis=0), q.mean(axis=0)
    u, _, vt = np.linalg.svd((p - cp).T @ (q - cq))
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return r, cq - r @ cp


def model_units_per_file_unit(fold: dict) -> float:
    """Model units per unit of a FOLD file: 1 / `polyfold:mmPerModelUnit` for a file in mm that
    states it (make's pieces), else 1. PolyfoldError when the stated scale is not positive."""
    if fold.get("frame_unit") != "mm" or "polyfold:mmPerModelUnit" not in fold:
        return 1.0
    scale = fold["polyfold:mmPerModelUnit"]
    if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not (math.isfinite(scale) and scale > 0):
        raise PolyfoldError(f"polyfold:mmPerModelUnit must be a positive number, not {scale!r}")
    return 1.0 / float(scale)


def prepare_piece(fold: dict, name: str = "", part: int = 0) -> ViewPiece:
    """A ViewPiece of a FOLD dict: builds the fold tree, checks the path and fits the rigid motion
    that lands the goal pose on the foldedForm (fold_positions keeps each root face flat)."""
    unit = model_units_per_file_unit(fold)
    net = fold_net(fold)
    tree = net.tree
    frames = net.path
    if frames is None and tree.n_faces == 1:
        frames = np.zeros((2, tree.n_edges))  # a single face is trivially foldable
    goal = fold_positions(tree, fold_deg_to_rho(net.goal))
    n_p = int(tree.piece.max()) + 1
    rotation = np.repeat(np.eye(3)[None], n_p, axis=0)
    translation = np.zeros((n_p, 3))
    fit_error = float("nan")
    if tree.folded is not None:
        target = tree.folded[tree.faces]
        fit_error = 0.0
        for k in range(n_p):
            on = tree.piece == k
            if not on.any():
                continue
            r, t = _kabsch(goal[on].reshape(-1, 3), target[on].reshape(-1, 3))
            rotation[k], translation[k] = r, t
            moved = goal[on] @ r.T + t
            fit_error = max(fit_error, float(np.abs(moved - target[on]).max()))
    return ViewPiece(name=name, part=part, fold=fold, net=net, frames=frames, rotation=rotation,
                     translation=translation, fit_error=fit_error * unit, unit=unit)


def pose_piece(fold: dict, t: float) -> np.ndarray:
    """Face corners (F, 3, 3) of a FOLD piece in the model frame at fraction t of its folding
    path (see `ViewPiece.pose`; prepare the piece once with `prepare_piece` to pose it often)."""
    return prepare_piece(fold).pose(t)


def weld_parts(parts: tuple[Mesh, ...] | list[Mesh]) -> Mesh:
    """The whole model from its parts: vertices at the same position become one (make writes
    them bit-exact). When that would join more than two faces at an edge (the input had split a
    non-manifold vertex) the parts are kept side by side instead."""
    verts = np.concatenate([p.vertices for p in parts])
    offsets = np.cumsum([0] + [p.n_vertices for p in parts])[:-1]
    faces = np.concatenate([p.faces + o for p, o in zip(parts, offsets)])
    uniq, inverse = np.unique(verts, axis=0, return_inverse=True)
    welded = Mesh(uniq, inverse.reshape(-1)[faces])
    if (welded.topology.face_count > 2).any():
        return Mesh(verts, faces)
    return welded


def _inside(root: Path, name: str) -> Path:
    """root / name for a plain file name from assembly.json, refusing anything that leaves root."""
    if not isinstance(name, str) or not name or Path(name).name != name or name in (".", ".."):
        raise PolyfoldError(f"{root.name}/assembly.json: bad file name {name!r}")
    return root / name


def _read_assembly(root: Path) -> Assembly:
    path = root / "assembly.json"
    if not path.is_file():
        raise PolyfoldError(f"{root}: not a `polyfold make` output folder (no assembly.json)")
    try:
        assembly = Assembly.from_dict(json.loads(path.read_text(encoding="utf-8")))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise PolyfoldError(f"{path}: not a readable assembly file ({type(exc).__name__}: {exc})") from None
    if not assembly.parts:
        raise PolyfoldError(f"{path}: no parts")
    return assembly


def _read_options(root: Path) -> MakeOptions | None:
    """The make options of report.json; None when there is no readable report of this version."""
    try:
        return MakeReport.from_dict(json.loads((root / "report.json").read_text(encoding="utf-8"))).options
    except (OSError, UnicodeDecodeError, ValueError):
        return None


def read_look(path: str | Path) -> ModelLook:
    """The look of a model.glb (see `ModelLook`; part_corners left empty): one mesh with a base
    colour texture and UVs, or with vertex (or face) colours. PolyfoldError (one line, naming the
    file) when it cannot be read or has neither."""
    import trimesh

    path = Path(path)
    try:
        mesh = trimesh.load(str(path), file_type="glb", force="mesh", process=False)
        corners = np.asarray(mesh.vertices, dtype=np.float32)[np.asarray(mesh.faces, dtype=np.int64)].reshape(-1, 3)
        visual = mesh.visual
        uv = image = colors = None
        if getattr(visual, "kind", None) == "texture":
            material = visual.material
            picture = getattr(material, "baseColorTexture", None)
            if picture is None:
                picture = getattr(material, "image", None)
            if picture is None or visual.uv is None:
                raise ValueError("a texture visual without image or UVs")
            image = np.asarray(picture.convert("RGBA" if "A" in picture.mode else "RGB"), dtype=np.uint8)
            uv = np.asarray(visual.uv, dtype=np.float64)[mesh.faces].reshape(-1, 2)
        elif getattr(visual, "kind", None) == "vertex":
            colors = np.asarray(visual.vertex_colors, dtype=np.uint8)[mesh.faces].reshape(-1, 4)
        elif getattr(visual, "kind", None) == "face":
            colors = np.repeat(np.asarray(visual.face_colors, dtype=np.uint8), 3, axis=0)
        else:
            raise ValueError("neither a texture nor colours")
    except Exception as exc:  # trimesh raises many kinds on a broken file
        raise PolyfoldError(f"{path}: not a readable model look ({type(exc).__name__}: {_first_line(exc)})") from None
    if not len(corners) or not np.isfinite(corners).all() or (uv is not None and not np.isfinite(uv).all()):
        raise PolyfoldError(f"{path}: not a readable model look (no faces, or a non-finite coordinate)")
    return ModelLook(corners=corners, uv=uv, image=image, colors=colors)


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else "no message"


def match_corners(corners: np.ndarray, mine: np.ndarray) -> np.ndarray | None:
    """For every face corner of `mine` (F, 3, 3), the row of `corners` (C, 3; 3 corners a face,
    face after face) at its position, in the face at its place: (F, 3). Faces are matched by their
    centroids (the nearest few, KD-tree), corners within a face by position; positions agree up
    to float32 rounding (model.glb stores float32). None when some face has no counterpart."""
    from scipy.spatial import cKDTree

    model = np.asarray(corners, dtype=np.float64).reshape(-1, 3, 3)
    mine = np.asarray(mine, dtype=np.float64).reshape(-1, 3, 3)
    if not len(mine):
        return np.zeros((0, 3), dtype=np.int64)
    tol = 1e-6 * max(float(np.abs(model).max()), float(np.abs(mine).max()), 1e-30)
    k = min(3, len(model))  # a few nearest centroids: distinct faces may share one
    _, near = cKDTree(model.mean(axis=1)).query(mine.mean(axis=1), k=k)
    near = np.asarray(near).reshape(len(mine), k)
    # (F, k candidates, 3 mine, 3 theirs): how far each of my corners is from each of theirs
    gap = np.abs(mine[:, None, :, None, :] - model[near][:, :, None, :, :]).max(axis=4)
    which = gap.argmin(axis=3)
    fits = (np.take_along_axis(gap, which[..., None], axis=3)[..., 0] <= tol).all(axis=2)
    fits &= (np.sort(which, axis=2) == np.arange(3)).all(axis=2)  # each of theirs used once
    if not fits.any(axis=1).all():
        return None
    pick = fits.argmax(axis=1)
    face, which = near[np.arange(len(mine)), pick], which[np.arange(len(mine)), pick]
    return 3 * face[:, None] + which


def _read_look(root: Path, parts: list[Mesh]) -> ModelLook | None:
    """model.glb matched to the parts' faces; None when the folder has no model.glb."""
    path = root / "model.glb"
    if not path.is_file():
        return None
    look = read_look(path)
    rows = match_corners(look.corners, np.concatenate([p.vertices[p.faces] for p in parts]))
    if rows is None:
        raise PolyfoldError(f"{path}: not the model of the parts (a face of a part-K.obj is not in it)")
    ends = np.cumsum([p.n_faces for p in parts])[:-1]
    return replace(look, part_corners=tuple(np.split(rows, ends)))


def load_folder(path: str | Path) -> MakeFolder:
    """Read a `polyfold make` output folder. Raises PolyfoldError (one line) when it is not one."""
    root = Path(path)
    if not root.is_dir():
        raise PolyfoldError(f"{root}: no such folder")
    assembly = _read_assembly(root)
    parts = []
    for row in assembly.parts:
        f = _inside(root, row.obj)
        if not f.is_file():
            raise PolyfoldError(f"{root}: {row.obj} is missing")
        parts.append(read_mesh_as_is(f))
    pieces = []
    for row in assembly.pieces:
        if not 0 <= row.part < len(parts):
            raise PolyfoldError(f"{root / 'assembly.json'}: piece {row.piece} belongs to part {row.part}, "
                                "which does not exist")
        fold = read_fold(_inside(root, row.fold))
        try:
            pieces.append(prepare_piece(fold, row.piece, row.part))
        except PolyfoldError as exc:
            raise PolyfoldError(f"{row.fold}: {exc}") from None
        except (ValueError, TypeError, KeyError, IndexError) as exc:  # malformed values in the JSON
            raise PolyfoldError(f"{row.fold}: malformed FOLD data ({type(exc).__name__}: {exc})") from None
    return MakeFolder(path=root, model=assembly.model or root.name, parts=tuple(parts), pieces=tuple(pieces),
                      whole=weld_parts(parts), options=_read_options(root), look=_read_look(root, parts),
                      steps=assembly.steps,
                      original=read_mesh_as_is(root / "original.obj") if (root / "original.obj").is_file() else None)


def make_folder(source: str | Path | Mesh | LoadedMesh, out_dir: str | Path, opts: MakeOptions | None = None,
                progress: Callable[[str, str], None] | None = None, *, name: str | None = None) -> MakeFolder:
    """Run make on a mesh (a file, or in memory named `name`) into out_dir and read the result back
    (the MESH form of `polyfold view`, and the viewer's Make button)."""
    from .make import make

    make(source, out_dir, opts or MakeOptions(), progress, name=name)
    return load_folder(out_dir)
