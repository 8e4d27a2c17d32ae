"""The look of a mesh file: OBJ materials (MTL `Kd`, `map_Kd`), texture images (Pillow) and the
visuals trimesh reads from GLB / glTF / PLY (base-colour texture and factor, vertex and face
colours), as an `mesh.appearance.Appearance` per triangle of the file.

Nothing here stops a load: a missing or unreadable image, a broken MTL line or bad texture
coordinates are one warning line each, and the faces concerned are printed without the texture.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..mesh.appearance import Appearance

MAX_TEXTURE_PX = 8192  # larger images are reduced to this on their longest side (more than any print needs)
MAX_UV = 1e4  # texture coordinates beyond this are broken, not a repeating texture
UV_SLACK = 0.1  # coordinates this far outside 0..1 repeat the texture without a warning


@dataclass
class Material:
    """One `newmtl` of an MTL file: its diffuse colour (0..1) and texture image (None: none)."""

    kd: tuple[float, float, float] = (1.0, 1.0, 1.0)
    image: np.ndarray | None = None


@dataclass
class Looks:
    """What the readers gather about a file's look, and the warnings to say."""

    warnings: list[str] = field(default_factory=list)

    def warn(self, message: str) -> None:
        if message not in self.warnings:
            self.warnings.append(message)


def read_image(path: str, looks: Looks, what: str) -> np.ndarray | None:
    """The image at `path` as (h, w, 3) uint8 (alpha dropped, palettes and greys expanded,
    larger than MAX_TEXTURE_PX reduced); None with a warning when it cannot be read."""
    from PIL import Image

    try:
        with Image.open(path) as im:
            im.draft("RGB", (MAX_TEXTURE_PX, MAX_TEXTURE_PX))
            rgb = im.convert("RGB")
            if max(rgb.size) > MAX_TEXTURE_PX:
                rgb.thumbnail((MAX_TEXTURE_PX, MAX_TEXTURE_PX))
            return np.asarray(rgb, dtype=np.uint8)
    except FileNotFoundError:
        looks.warn(f"{what} {os.path.basename(path)!r} not found: printed without it")
    except Exception as exc:  # Pillow raises many kinds on broken files: say which file, not how
        why = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        looks.warn(f"{what} {os.path.basename(path)!r} cannot be read ({why}): printed without it")
    return None


def _map_file(tokens: list[str]) -> str:
    """The file name of a `map_Kd [options] file` line: options (-o u v w, -s u v w, -bm x,
    -clamp on, ...) skipped; a name with spaces kept whole."""
    takes = {"-blendu": 1, "-blendv": 1, "-bm": 1, "-boost": 1, "-cc": 1, "-clamp": 1, "-imfchan": 1,
             "-mm": 2, "-o": 3, "-s": 3, "-t": 3, "-texres": 1}
    i = 0
    while i < len(tokens) and tokens[i].lower() in takes:
        n = takes[tokens[i].lower()]
        i += 1
        # -o/-s/-t take 1 to 3 numbers
        while n and i < len(tokens) and _is_number(tokens[i]):
            i, n = i + 1, n - 1
        if tokens[i - 1].lower() in ("-blendu", "-blendv", "-clamp", "-cc") and i < len(tokens) and tokens[i].lower() in ("on", "off"):
            i += 1
    return " ".join(tokens[i:])


def _is_number(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


def read_mtl(path: str, looks: Looks, images: dict[str, np.ndarray | None]) -> dict[str, Material]:
    """The materials of an MTL file; unreadable lines and images are warnings. `images` caches
    images by path (several materials often share one)."""
    name = os.path.basename(path)
    try:
        with open(path, "rb") as fh:
            text = fh.read().decode("utf-8", errors="replace")
    except OSError as exc:
        looks.warn(f"material file {name!r} cannot be read ({exc.strerror or exc}): printed without colours")
        return {}
    materials: dict[str, Material] = {}
    cur: Material | None = None
    for lineno, line in enumerate(text.splitlines(), 1):
        tokens = line.split("#", 1)[0].split()
        if not tokens:
            continue
        tag = tokens[0]
        if tag == "newmtl":
            cur = materials.setdefault(" ".join(tokens[1:]), Material())
        elif cur is None:
            continue
        elif tag == "Kd":
            try:
                kd = [float(t) for t in tokens[1:4]]
                if len(kd) == 1:
                    kd *= 3
                if len(kd) != 3 or not all(np.isfinite(kd)):
                    raise ValueError
                cur.kd = tuple(min(1.0, max(0.0, v)) for v in kd)
            except ValueError:
                looks.warn(f"{name}: line {lineno}: a Kd colour that is not 3 numbers: ignored")
        elif tag == "map_Kd":
            file = _map_file(tokens[1:])
            if not file:
                looks.warn(f"{name}: line {lineno}: map_Kd without a file name: ignored")
                continue
            full = os.path.join(os.path.dirname(path), file.replace("\\", os.sep))
            if full not in images:
                images[full] = read_image(full, looks, "texture")
            cur.image = images[full]
    return materials


def _uv_ok(uv: np.ndarray, looks: Looks, name: str) -> np.ndarray:
    """(F,) bool: faces whose texture coordinates (F, 3, 2) are usable; a warning for the others
    and for coordinates outside 0..1 (the texture repeats there)."""
    ok = np.isfinite(uv).all(axis=(1, 2)) & (np.abs(uv) <= MAX_UV).all(axis=(1, 2))
    if (~ok).any():
        looks.warn(f"{name}: {int((~ok).sum())} faces have broken texture coordinates (e.g. face "
                   f"{int(np.flatnonzero(~ok)[0])}): printed without the texture")
    # a little past the edge is common (island margins) and not worth a word
    outside = ok & ((uv < -UV_SLACK) | (uv > 1 + UV_SLACK)).any(axis=(1, 2))
    if outside.any():
        looks.warn(f"{name}: {int(outside.sum())} faces have texture coordinates outside 0..1: the texture "
                   f"repeats there")
    return ok


def obj_appearance(n_tris: int, corner_vertex: np.ndarray, corner_vt: np.ndarray, tri_material: list[str | None],
                   uvs: np.ndarray, vertex_colors: np.ndarray | None, mtllibs: list[str], path: str,
                   looks: Looks) -> Appearance | None:
    """The Appearance of an OBJ file's triangles: corner_vertex / corner_vt (T, 3) the vertex and
    texture-coordinate index of every corner (-1: none), tri_material the `usemtl` in force for
    each, uvs (n, 2) the `vt` lines, vertex_colors (n, 3) 0..1 or None; mtllibs the `mtllib`
    files (relative to the OBJ). None when the file says nothing about colour."""
    name = os.path.basename(path)
    materials: dict[str, Material] = {}
    images: dict[str, np.ndarray | None] = {}
    for lib in mtllibs:
        materials.update(read_mtl(os.path.join(os.path.dirname(path), lib.replace("\\", os.sep)), looks, images))
    used = sorted({m for m in tri_material if m is not None})
    for m in used:
        if m not in materials and mtllibs:
            looks.warn(f"{name}: material {m!r} is not in {', '.join(mtllibs)}: printed white")
    textures: list[np.ndarray] = []
    slot: dict[int, int] = {}
    face_image = np.full(n_tris, -1, dtype=np.int64)
    colors = np.full((n_tris, 3, 3), 255, dtype=np.uint8)
    mat_of = np.array([-1 if m is None else used.index(m) for m in tri_material], dtype=np.int64)
    kds = set()
    for j, m in enumerate(used):
        mat = materials.get(m)
        if mat is None:
            continue
        on = mat_of == j
        kds.add(mat.kd)
        if mat.image is not None:
            # map_Kd is printed as it is, not tinted by Kd: Blender writes Kd 0.8 beside its
            # textures, and tinting would print every such model a fifth darker than it looks
            key = id(mat.image)
            if key not in slot:
                slot[key] = len(textures)
                textures.append(mat.image)
            face_image[on] = slot[key]
        colors[on] = (np.array(mat.kd) * 255 + 0.5).astype(np.uint8)
    uv = np.full((n_tris, 3, 2), np.nan)
    has_uv = (corner_vt >= 0).all(axis=1)
    if (face_image >= 0).any():
        bad_index = has_uv & (corner_vt >= len(uvs)).any(axis=1)
        if bad_index.any():
            looks.warn(f"{name}: {int(bad_index.sum())} faces refer to texture coordinates past the end of the "
                       f"{len(uvs)} vt lines: printed without the texture")
        has_uv &= ~bad_index
        uv[has_uv] = uvs[corner_vt[has_uv]]
        missing = (face_image >= 0) & ~has_uv & ~bad_index
        if missing.any():
            looks.warn(f"{name}: {int(missing.sum())} textured faces have no texture coordinates (f v/vt): "
                       f"printed without the texture")
        ok = np.zeros(n_tris, dtype=bool)
        ok[has_uv] = _uv_ok(uv[has_uv], looks, name)
        face_image[~ok] = -1
        uv[~ok] = np.nan
    if vertex_colors is not None:
        vc = (np.clip(vertex_colors, 0.0, 1.0) * 255 + 0.5).astype(np.uint8)
        colors = vc[corner_vertex]
    if (face_image >= 0).any():
        kind = "texture"
    elif vertex_colors is not None:
        kind = "vertex"
    elif len(kds) > 1:
        kind = "face"  # materials of several colours: a coloured model (one Kd everywhere is no colouring)
    else:
        return None
    return Appearance(tuple(textures), face_image, uv, colors, kind)


def trimesh_appearance(tm, n_tris: int, name: str, looks: Looks) -> Appearance | None:
    """The Appearance of a mesh trimesh read (GLB/glTF base-colour texture times its factor,
    vertex or face colours of PLY/GLB), per face of tm.faces. None when it has none."""
    visual = getattr(tm, "visual", None)
    kind = getattr(visual, "kind", None)
    faces = np.asarray(tm.faces, dtype=np.int64).reshape(-1, 3)
    if kind == "texture":
        material = getattr(visual, "material", None)
        image = getattr(material, "baseColorTexture", None)
        if image is None:
            image = getattr(material, "image", None)
        factor = getattr(material, "baseColorFactor", None)
        rgb = np.ones(3) if factor is None else np.asarray(factor, dtype=np.float64).reshape(-1)[:3]
        if factor is not None and np.asarray(factor).dtype.kind in "ui" or rgb.max(initial=0) > 1.0:
            rgb = rgb / 255.0
        uv = getattr(visual, "uv", None)
        colors = np.tile((np.clip(rgb, 0, 1) * 255 + 0.5).astype(np.uint8), (n_tris, 3, 1))
        if image is None or uv is None or len(uv) < len(tm.vertices):
            if image is not None:
                looks.warn(f"{name}: a texture without texture coordinates: printed without it")
            return Appearance((), np.full(n_tris, -1), np.full((n_tris, 3, 2), np.nan), colors, "face")
        try:
            pixels = np.asarray(image.convert("RGB"), dtype=np.uint8)
        except Exception as exc:
            looks.warn(f"{name}: its texture cannot be read ({type(exc).__name__}): printed without it")
            return None
        pixels = (pixels * np.clip(rgb, 0, 1) + 0.5).astype(np.uint8)
        corner_uv = np.asarray(uv, dtype=np.float64)[faces]
        ok = _uv_ok(corner_uv, looks, name)
        face_image = np.where(ok, 0, -1)
        corner_uv[~ok] = np.nan
        return Appearance((pixels,), face_image, corner_uv, colors, "texture")
    if kind == "vertex":
        vc = np.asarray(visual.vertex_colors, dtype=np.uint8)[:, :3]
        return Appearance((), np.full(n_tris, -1), np.full((n_tris, 3, 2), np.nan), vc[faces], "vertex")
    if kind == "face":
        fc = np.asarray(visual.face_colors, dtype=np.uint8)[:, :3]
        return Appearance((), np.full(n_tris, -1), np.full((n_tris, 3, 2), np.nan),
                          np.repeat(fc[:, None, :], 3, axis=1), "face")
    return None
