"""Page packing benchmark (not a test): `polyfold.pack.pack_outlines` against bounding-box shelves.

Generates net-like pieces deterministically (triangle strips that wander like unfolded bands,
with glue tabs on some cut edges; L shapes; combs; a mix) and packs every set onto A4 (210 x 297
mm, 10 mm margins, 2 mm gap) twice: with the outline packer, and with a simple shelf packer over
bounding boxes (each piece turned so its minimum-area bounding rectangle lies flat, tallest first,
left to right in rows), written here only as the baseline. Both results go through
`check_packing` with the gap. Prints pieces | pages ours / shelf | utilisation ours / shelf |
seconds ours / shelf; seconds are wall-clock, the numba kernel already compiled.

    .venv/bin/python bench/bench_pack.py [--seed 0] [--angles 16] [--tries 2] [--png out/pack]

(The pages `polyfold make` needs for real meshes, splitting included: bench/bench_build.py.)
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np
import shapely
import shapely.affinity
from shapely import Polygon

from polyfold.fabricate.pack import check_packing, fits_page, pack_outlines, Packing, placed_outline, Placement

A4 = (210.0, 297.0)
MARGIN, GAP = 10.0, 2.0


# ----------------------------------------------------------------------------------------------
# pieces


def _tab(a: np.ndarray, b: np.ndarray, depth: float) -> Polygon:
    """Glue tab (trapezoid) on the right of the edge a -> b."""
    d = b - a
    n = np.array([d[1], -d[0]]) / np.hypot(*d) * depth
    return Polygon([a, b, b + n - d * 0.25, a + n + d * 0.25])


def strip(rng: np.random.Generator, n_tris: int, side: float) -> Polygon:
    """A strip of roughly equilateral triangles, each glued to an edge of the previous one and
    turning at random (like an unfolded band), never overlapping itself; glue tabs on about a
    third of its outer edges."""
    a, b = np.array([0.0, 0.0]), np.array([side, 0.0])
    tris: list[Polygon] = []
    union = Polygon()
    other, free = (a, b), 0  # the last triangle's other free edge, and whether it is still free
    while len(tris) < n_tris:
        d = b - a
        c = (a + b) / 2 + np.array([-d[1], d[0]]) * 0.866 * rng.uniform(0.85, 1.15)
        t = Polygon([a, b, c])
        if union.intersection(t).area > 1e-6 * t.area:
            if free == 0:
                break  # both free edges of the last triangle are blocked: the strip ends here
            free -= 1
            a, b = other  # the last triangle's other free edge
            continue
        tris.append(t)
        union = union.union(t)
        # the new triangle goes on the far side of one of the two new edges (reversed: apex on the left)
        first, second = ((c, b), (a, c)) if rng.random() < 0.5 else ((a, c), (c, b))
        (a, b), other, free = first, second, 1
    piece = shapely.union_all(tris)
    ring = np.asarray(piece.exterior.coords)
    if not piece.exterior.is_ccw:
        ring = ring[::-1]
    for k in range(len(ring) - 1):
        if rng.random() < 0.35:
            tab = _tab(ring[k], ring[k + 1], min(6.0, 0.35 * side))
            if piece.intersection(tab).area < 1e-6:
                piece = piece.union(tab)
    piece = shapely.simplify(piece, 1e-9)
    s = fits_page(piece, A4, MARGIN)
    return shapely.affinity.scale(piece, 0.9 * s, 0.9 * s, origin=(0, 0)) if s < 1.0 else piece  # long walks: shrink onto the page


def l_shape(rng: np.random.Generator) -> Polygon:
    a, b, t = rng.uniform(60, 120), rng.uniform(40, 100), rng.uniform(12, 25)
    return Polygon([(0, 0), (a, 0), (a, t), (t, t), (t, b), (0, b)])


def comb(rng: np.random.Generator) -> Polygon:
    """A spine with 3..6 teeth; all combs share one pitch, with gaps wide enough for another
    comb's tooth plus the gap on both sides, so they can interlock."""
    teeth, w, depth, spine = int(rng.integers(3, 7)), 8.0, rng.uniform(25, 45), 10.0
    gapw = w + 12.0
    pts = [(0.0, 0.0)]
    x = 0.0
    for k in range(teeth):
        pts += [(x, spine + depth), (x + w, spine + depth), (x + w, spine)]
        x += w
        if k < teeth - 1:
            pts += [(x + gapw, spine)]
            x += gapw
    pts += [(x, 0.0)]
    return Polygon(pts)


def cases(seed: int) -> list[tuple[str, list[Polygon]]]:
    rng = np.random.default_rng(seed)
    strips20 = [strip(rng, int(rng.integers(6, 30)), rng.uniform(18, 30)) for _ in range(20)]
    long20 = [strip(rng, int(rng.integers(50, 90)), rng.uniform(9, 13)) for _ in range(20)]
    strips60 = [strip(rng, int(rng.integers(4, 24)), rng.uniform(12, 24)) for _ in range(60)]
    ls = [l_shape(rng) for _ in range(20)]
    combs = [comb(rng) for _ in range(16)]
    mixed = [strip(rng, int(rng.integers(5, 25)), rng.uniform(15, 25)) for _ in range(20)]
    mixed += [l_shape(rng) for _ in range(10)] + [comb(rng) for _ in range(10)]
    return [("strips-20", strips20), ("long-20", long20), ("strips-60", strips60), ("L-20", ls), ("combs-16", combs), ("mixed-40", mixed)]


# ----------------------------------------------------------------------------------------------
# baseline


def shelf_pack(outlines: list[Polygon], page_size: tuple[float, float], margin: float, gap: float) -> Packing:
    """Bounding-box shelves: minimum-area rectangle flat (long side horizontal when it fits),
    tallest first, rows left to right, a new page when a row does not fit."""
    W, H = page_size
    pw, ph = W - 2 * margin, H - 2 * margin
    boxes = []
    for i, g in enumerate(outlines):
        rect = shapely.get_coordinates(shapely.minimum_rotated_rectangle(g))
        d = rect[1] - rect[0]
        base = -math.degrees(math.atan2(d[1], d[0]))
        best = None
        for a in (base, base + 90.0):
            t = math.radians(a)
            r = np.array([[math.cos(t), -math.sin(t)], [math.sin(t), math.cos(t)]])
            xy = shapely.get_coordinates(g) @ r.T
            lo, hi = xy.min(0), xy.max(0)
            w, h = hi - lo
            if w <= pw and h <= ph and (best is None or h < best[1]):
                best = (w, h, a, lo)
        if best is None:
            raise ValueError(f"piece {i} does not fit")
        boxes.append((best[1], best[0], i, best[2], best[3]))
    boxes.sort(key=lambda b: (-b[0], b[2]))
    place: dict[int, Placement] = {}
    page, x, y, shelf_h = 0, 0.0, 0.0, 0.0
    for h, w, i, a, lo in boxes:
        if x > 0 and x + w > pw:
            x, y, shelf_h = 0.0, y + shelf_h + gap, 0.0
        if y > 0 and y + h > ph:
            page, x, y, shelf_h = page + 1, 0.0, 0.0, 0.0
        place[i] = Placement(page, a, (margin + x - lo[0], margin + y - lo[1]))
        x, shelf_h = x + w + gap, max(shelf_h, h)
    n_pages = page + 1 if outlines else 0
    area = sum(g.area for g in outlines)
    return Packing(tuple(place[i] for i in range(len(outlines))), n_pages, (W, H), margin, area / max(n_pages * pw * ph, 1e-300))


# ----------------------------------------------------------------------------------------------


def draw(path: Path, outlines: list[Polygon], packing: Packing) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    W, H = packing.page_size
    fig, axes = plt.subplots(1, packing.n_pages, figsize=(3 * packing.n_pages, 4.2), squeeze=False)
    for p, ax in enumerate(axes[0]):
        ax.add_patch(plt.Rectangle((0, 0), W, H, fill=False, lw=0.5))
        ax.add_patch(plt.Rectangle((packing.margin,) * 2, W - 2 * packing.margin, H - 2 * packing.margin, fill=False, ls=":", lw=0.5))
        for i, (g, pl) in enumerate(zip(outlines, packing.placements)):
            if pl.page == p:
                for part in shapely.get_parts(placed_outline(g, pl)):
                    ax.fill(*part.exterior.xy, alpha=0.5, lw=0.3, ec="k")
                    for hole in part.interiors:
                        ax.fill(*hole.xy, color="w", lw=0.3, ec="k")
                c = placed_outline(g, pl).representative_point()
                ax.text(c.x, c.y, str(i), fontsize=5, ha="center", va="center")
        ax.set_xlim(0, W)
        ax.set_ylim(0, H)
        ax.set_aspect("equal")
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--angles", type=int, default=16)
    ap.add_argument("--tries", type=int, default=2, help="piece orders pack_outlines fills")
    ap.add_argument("--png", type=Path, default=None, help="write one PNG per case (ours and shelf) here")
    args = ap.parse_args()

    pack_outlines([shapely.box(0, 0, 10, 10)], A4)  # compile (or load) the numba kernel outside the timings
    print(f"A4, margin {MARGIN:g} mm, gap {GAP:g} mm, {args.angles} angles, seed {args.seed}")
    head = f"{'case':<10} {'pieces':>6} {'verts':>6} {'pages ours':>10} {'shelf':>6} {'util ours':>9} {'shelf':>6} {'s ours':>7} {'shelf':>6}"
    print(head)
    print("-" * len(head))
    tot = np.zeros(2)
    for name, outlines in cases(args.seed):
        t = time.perf_counter()
        ours = pack_outlines(outlines, A4, MARGIN, GAP, angles=args.angles, seed=args.seed, tries=args.tries)
        t_ours = time.perf_counter() - t
        t = time.perf_counter()
        shelf = shelf_pack(outlines, A4, MARGIN, GAP)
        t_shelf = time.perf_counter() - t
        for label, pk in (("ours", ours), ("shelf", shelf)):
            problems = check_packing(outlines, pk, GAP)
            if problems:
                raise SystemExit(f"{name} ({label}): {problems[0]}")
        verts = np.mean([len(shapely.get_coordinates(g)) for g in outlines])
        tot += (ours.n_pages, shelf.n_pages)
        print(
            f"{name:<10} {len(outlines):>6} {verts:>6.0f} {ours.n_pages:>10} {shelf.n_pages:>6} "
            f"{ours.utilisation:>9.1%} {shelf.utilisation:>6.1%} {t_ours:>7.3f} {t_shelf:>6.3f}"
        )
        if args.png:
            args.png.mkdir(parents=True, exist_ok=True)
            draw(args.png / f"{name}-ours.png", outlines, ours)
            draw(args.png / f"{name}-shelf.png", outlines, shelf)
    print(f"{'total':<10} {'':>6} {'':>6} {int(tot[0]):>10} {int(tot[1]):>6}")


if __name__ == "__main__":
    main()
