"""make's layout and check stages: the pieces on paper, packed onto pages, checked before
anything is written.

Scale: the model's longest bounding-box side becomes `--size` mm. Parts whose pieces (with room
for their tabs) do not fit a page are split along creases first (`fit_parts`); then pieces are
split further where that saves pages (`split_for_pages`). Both happen before folding, which plans
a path for every piece; the layout after folding (`lay_out`) tries the packing order found before
it first, so unless folding split a piece the pages come out as planned.

Where pieces go on a page (`pack_box`): inside the margins and above the footer strip; with
`--marks` the top and left margins grow to `paper.MARK_CLEAR_MM` so the registration marks'
corners (top-left, top-right, bottom-left) stay free. That gives up a strip along two sides
rather than only the three corner squares, but keeps the packing a rectangle, so fitting,
packing and the check all reason about one box.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import shapely

from ..deadline import Deadline
from ..errors import PolyfoldError
from ..fabricate.fit import PieceTooLarge, split_to_fit
from ..fabricate.pack import ORDER_TRIES, Packing, pack_outlines
from ..fabricate.page import place
from ..fabricate.paper import FOOTER_MM, GAP_MM, MARK_CLEAR_MM
from ..fabricate.pieces import (GlueEdge, LayoutStats, PieceInput, SheetPiece, build_sheet_pieces, piece_input,
                                with_side_notes)
from ..fabricate.split import PagePlan, plan_label_cuts, plan_pages
from ..mesh.mesh import Mesh
from ..processes import ForkedStream
from ..unfold.net import cut_creases, piece_net
from .folding import FoldedPiece
from .options import MakeOptions
from .parts import Part


def pack_box(width: float, height: float, opts: MakeOptions) -> tuple[float, float, float, float]:
    """(x0, y0, x1, y1) mm: the part of a width x height page that pieces are packed into (see
    the module docstring); the footer strip is the FOOTER_MM below y1."""
    near = max(opts.margin, MARK_CLEAR_MM) if opts.marks else opts.margin
    return near, near, width - opts.margin, height - opts.margin - FOOTER_MM


def _packer_page(box: tuple[float, float, float, float]) -> tuple[tuple[float, float], float]:
    """The (page size, margin) that the packer and `split_to_fit`, which know one margin all
    round, are given for `box`: x0 == y0, so a (x1 + x0) x (y1 + y0) mm page with margin x0 has
    exactly `box` inside its margins."""
    x0, y0, x1, y1 = box
    return (x1 + x0, y1 + y0), x0


def fit_parts(parts: list[Part], scale: float, opts: MakeOptions, box: tuple[float, float, float, float],
              name: str, deadline: Deadline = Deadline.never()) -> tuple[list[Part], int]:
    """The parts with their nets split along creases until every piece (with room for its tabs)
    fits `box` (`pack_box`); the number of pieces that added (`split_to_fit`). PolyfoldError naming
    the largest size that fits when a single face (or flat polygon) does not; OutOfTime past
    `deadline`."""
    fitted, splits = [], 0
    for part in parts:
        try:
            net, cuts = split_to_fit(part.net, scale, *_packer_page(box), deadline=deadline)
        except PieceTooLarge as exc:
            largest = math.floor(opts.size * exc.factor * 10) / 10
            raise PolyfoldError(f"{name}: at --size {opts.size:g} mm {exc.what} alone (with its tabs) does not "
                                f"fit on {opts.paper} paper with {opts.margin:g} mm margins"
                                f"{' and registration marks' if opts.marks else ''}; the largest size that "
                                f"fits is {largest:g} mm (or use larger --paper)") from None
        splits += cuts
        fitted.append(Part(part.faces, net))
    return fitted, splits


PLAN_ROUNDS = 3  # plans of the cuts for one page count, each on the pieces the last one cut
# where a plan puts a part it splits off: on the emptiest page that takes one, then (when that fails)
# on the first; the plans are greedy, and which of the two meets a page count varies from model to model
PAGE_CHOICES = (True, False)
# page counts at which the outlines grown by half the gap (the room the packer gives each) would fill
# more than this of the printable area are not tried, and failing plans take the longest: over the
# 35 closed shared models and 8 generated meshes (80-1,280 faces) every plan that met its page count
# filled at most 0.68 (a generated torus; with compact parts at most 0.58) and every one above 0.72
# failed, in 0.4-2.9 s each (the 1,280-face sphere tried 3 pages at 0.76 twice: 4.5 s of its 11 s
# layout; it had tried every count whose outlines, not grown, filled at most 0.75)
MAX_FILL = 0.7
# hull areas (fractions of the printable area) that compact parts are cut to, the coarsest first
# (fewest cuts): a sprawling net encloses gaps that the bottom-left fill cannot use
CAPS = (0.4, 0.3, 0.2, 0.15, 0.1)


def pack_budget(deadline: Deadline) -> float:
    """Seconds the packer (and the page split) may take: 2 to 10, what is left of the time limit."""
    return max(2.0, min(10.0, deadline.left()))


def part_piece_inputs(mesh: Mesh, parts: list[Part]) -> list[PieceInput]:
    """What fabricate needs of every piece of the parts' nets, in the order `fold_pieces` makes
    them (part by part, piece by piece) when it splits none."""
    out = []
    for k, part in enumerate(parts):
        for piece in range(part.net.n_pieces):
            pnet, fids = piece_net(part.net, piece)
            faces = part.faces[fids]
            out.append(piece_input(pnet, k, mesh.faces[faces], faces))
    return out


@dataclass(frozen=True, eq=False)
class PageSplit:
    """`split_for_pages`' result: the parts with the creases it cut (`cuts` of them); the pieces
    (net pieces and glue strips) and the packing found for them (its pages and piece order:
    `pages`, `order`); every mesh face's place in that order (`lay_out` follows it when folding
    splits a piece); whether the time budget stopped the search."""

    parts: list[Part]
    cuts: int
    pieces: int
    net_pieces: int
    rank: np.ndarray
    ran_out: bool
    drawn: tuple[list[SheetPiece], list[GlueEdge], LayoutStats]  # build_sheet_pieces of `parts`' pieces
    inputs: list[PieceInput]  # what was drawn
    packing: Packing  # of `drawn`'s pieces
    label_cuts: int = 0  # creases cut before that where labels found no readable place (in `parts`)
    labels_ran_out: bool = False  # the time limit stopped those cuts with labels still crowded
    # its drawings' memo (`build_sheet_pieces`): a drawing of pieces that folding split takes from
    # it what it can (the tabs and labels of the pieces not split, the same as drawn afresh)
    memo: dict = field(default_factory=dict)

    @property
    def pages(self) -> int:
        return self.packing.n_pages

    @property
    def order(self) -> tuple[int, ...]:
        """The piece order whose fill gave the packing."""
        return tuple(self.packing.order)

    def same_pieces(self, folded: list[FoldedPiece]) -> bool:
        """Whether the folded pieces are the very pieces planned (folding split none)."""
        return len(folded) == len(self.inputs) and all(
            np.array_equal(f.mesh_faces, inp.face_ids) for f, inp in zip(folded, self.inputs))

    def hint(self, folded: list[FoldedPiece], n_pieces: int) -> list[int]:
        """The order to pack `n_pieces` pieces in, the first `folded` ones drawn from the folded
        pieces (glue strips after them): the planned packing's order for the planned pieces, else
        the order of the planned pieces they come from."""
        if self.same_pieces(folded) and n_pieces == self.pieces:
            return list(self.order)
        rank = [int(self.rank[f.mesh_faces[0]]) for f in folded] + [len(self.order)] * (n_pieces - len(folded))
        return sorted(range(n_pieces), key=lambda i: rank[i])


def _cut_plan(parts: list[Part], inputs: list[PieceInput], plan: PagePlan) -> tuple[list[Part], int]:
    """The parts with the plan's creases cut (plan.cuts[i] are faces of inputs[i]'s net)."""
    n_faces = max(int(p.faces.max()) for p in parts) + 1
    cut_faces: list[list[np.ndarray]] = [[] for _ in parts]
    for inp, faces in zip(inputs, plan.cuts):
        cut_faces[inp.part].append(inp.face_ids[faces])
    out, n = [], 0
    for part, faces in zip(parts, cut_faces):
        mesh_faces = np.concatenate(faces) if faces else np.zeros(0, dtype=np.int64)
        if len(mesh_faces) == 0:
            out.append(part)
            continue
        local = np.full(n_faces, -1, dtype=np.int64)
        local[part.faces] = np.arange(len(part.faces))
        out.append(Part(part.faces, cut_creases(part.net, local[mesh_faces])))
        n += len(mesh_faces)
    return out, n


def _owner(inputs: list[PieceInput], n_faces: int) -> np.ndarray:
    """(n_faces,) the piece (index into inputs) every mesh face is in; -1 for none."""
    owner = np.full(n_faces, -1, dtype=np.int64)
    for i, inp in enumerate(inputs):
        owner[inp.face_ids] = i
    return owner


# from this many pieces on, the first page plan is made beside the first packing (`split_for_pages`):
# a 1,500-face model's 190-290 pieces take 0.4 s to pack and 0.6-0.8 s to plan, each on one core
PARALLEL_PLAN_PIECES = 100


def _plan_ahead(n_pieces: int) -> bool:
    """Whether `split_for_pages` makes its first page plan in a forked process beside its first
    packing: two cores or more, and PARALLEL_PLAN_PIECES pieces or more."""
    from ..processes import can_fork, usable_cores

    return n_pieces >= PARALLEL_PLAN_PIECES and usable_cores() >= 2 and can_fork()


LABEL_ROUNDS = 3  # rounds of cuts for labels with no readable place (each redraws every piece)


def _split_for_labels(mesh: Mesh, parts: list[Part], inputs: list[PieceInput], drawn, draw,
                      say: Callable[[str, str], None], deadline: Deadline, draw_seconds: float):
    """The parts, their pieces and drawing with a crease cut in every piece some of whose labels
    found no readable place (`fabricate.split.plan_label_cuts`), redrawn, for up to LABEL_ROUNDS
    rounds while that leaves fewer such labels; the creases cut; and whether `deadline` stopped
    the rounds (a round is started only with `draw_seconds`, one drawing's time, left: the
    unfold searches of a dense mesh take their time first, so here is where a tight limit shows)."""
    cuts = 0
    for _ in range(LABEL_ROUNDS):
        crowded = drawn[2].crowded
        if not crowded:
            break
        if deadline.left() < draw_seconds:
            say("layout", f"no time left to cut pieces where {len(crowded)} label(s) found no room")
            return parts, inputs, drawn, cuts, True
        plan = plan_label_cuts(drawn[0], [inp.net for inp in inputs], crowded)
        if not any(len(c) for c in plan):
            break
        say("layout", f"cutting {sum(len(c) > 0 for c in plan)} piece(s) where {len(crowded)} label(s) found no room")
        cut_parts, n_cut = _cut_plan(parts, inputs, PagePlan(plan, (), 0))
        cut_inputs = part_piece_inputs(mesh, cut_parts)
        cut_drawn = draw(cut_inputs)
        if len(cut_drawn[2].crowded) >= len(crowded):
            break
        parts, inputs, drawn, cuts = cut_parts, cut_inputs, cut_drawn, cuts + n_cut
    return parts, inputs, drawn, cuts, False


def split_for_pages(mesh: Mesh, parts: list[Part], scale: float, opts: MakeOptions,
                    box: tuple[float, float, float, float], deadline: Deadline,
                    say: Callable[[str, str], None], hard: Deadline = Deadline.never()) -> PageSplit:
    """Cut creases where that puts the pieces on fewer pages (`fabricate.split`), before folding.

    The pieces are drawn (tabs and labels included) and packed as they are; when their labels had
    to go by seam run, so do the labels of every redrawing (`build_sheet_pieces`' by_run). Then, for each page
    count from the fewest that their outlines grown by half the gap fill to at most MAX_FILL up to
    one fewer than that packing:
    `plan_pages` plans the cuts, the cut pieces are redrawn (their tabs are real now) and planned
    again, up to PLAN_ROUNDS times, until a plan needs no cut; the redrawn pieces are packed in the
    plan's order; when that misses the page count, the plans are made again with PAGE_CHOICES'
    other choice. Kept: the fewest pages, then the fewest pieces; the first page count met ends the
    search. Then one page fewer than the best so far is planned with compact parts (`plan_pages`'
    cap, each of CAPS in turn, emptiest page first) while the outlines grown by half the gap would
    fill at most MAX_FILL of the pages; when that is met, one page fewer again. With two cores the
    first plan (the fewest pages, the first choice) is made in a forked process while the pieces
    are packed (`_plan_ahead`: the same plan, ready when the packing needs fewer pages). `box`:
    `pack_box`. Time: `pack_budget` and one drawing's time (as long as the first drawing took),
    from after the first drawing (`lay_out` reuses it when folding splits nothing); a plan is only
    started with that drawing's time left. `deadline` ends this optional work (the label rounds
    too); a drawing stops the run at `hard` (OutOfTime)."""
    page, margin = _packer_page(box)
    by_run = False  # the first drawing's labels went by seam run: so do the redrawings of its pieces
    memo: dict = {}  # (a redrawn piece's tabs and labels found before are taken again: `build_sheet_pieces`)

    def draw(inputs: list[PieceInput]) -> tuple[list[SheetPiece], list[GlueEdge], LayoutStats]:
        pieces, glue, stats = build_sheet_pieces(inputs, scale, tabs=opts.tabs, min_label_mm=opts.min_label_mm,
                                                 deadline=hard, by_run=by_run, memo=memo)
        return pieces, glue, stats

    def pack(pcs: list[SheetPiece], hint: list[int] | None, seconds: float) -> Packing:
        return pack_outlines([p.footprint for p in pcs], page, margin=margin, gap=GAP_MM, seed=opts.seed,
                             time_limit=seconds, hint=hint)

    inputs = part_piece_inputs(mesh, parts)
    t0 = time.perf_counter()
    drawn = draw(inputs)  # lay_out's drawing when folding splits nothing: not this stage's cost
    draw_seconds = time.perf_counter() - t0
    by_run = drawn[2].labels_by_run
    parts, inputs, drawn, label_cuts, labels_ran_out = _split_for_labels(mesh, parts, inputs, drawn, draw, say,
                                                                         deadline, draw_seconds)
    pieces = drawn[0]
    box_area = (box[2] - box[0]) * (box[3] - box[1])
    grown = float(shapely.area(shapely.buffer([p.footprint for p in pieces], GAP_MM / 2)).sum()) / box_area
    fewest = max(1, math.ceil(grown / MAX_FILL - 1e-9))
    rasters: dict[int, tuple] = {}  # per drawing: (the drawing, kept alive so its id stays its own, rasters)

    def attempt(n_pages: int, cap: float | None, emptiest_first: bool, planned: ForkedStream | None = None) -> None:
        """Plan the cuts for `n_pages` (rounds of plan, cut, redraw), pack the cut pieces in the
        plan's order and keep them in `best` when they beat it. planned: the first round's plan,
        made ahead in a forked process, or None."""
        nonlocal best, ran_out
        cur_parts, cur_inputs, cur_drawn, cuts, hint = parts, inputs, drawn, 0, None
        for k in range(PLAN_ROUNDS):
            if budget.left() < draw_seconds:  # no time to draw the pieces this plan would cut
                ran_out = True
                break
            got, plan = (False, None) if k or planned is None else planned.next()
            if not got:  # (none made ahead, or its process died: made here)
                plan = plan_pages(cur_drawn[0], [inp.net for inp in cur_inputs], page, margin, GAP_MM, n_pages,
                                  budget.at, seed=opts.seed, emptiest_first=emptiest_first,
                                  rasters=rasters.setdefault(id(cur_drawn), (cur_drawn, {}))[1], cap=cap)
            if plan is None:
                ran_out |= budget.expired()
                break
            if not any(len(c) for c in plan.cuts):
                hint = [t for t, _ in plan.order]
                break
            cur_parts, n_cut = _cut_plan(cur_parts, cur_inputs, plan)
            cut_inputs = part_piece_inputs(mesh, cur_parts)
            owner = _owner(cut_inputs, mesh.n_faces)
            # the plan's order (glue strips are drawn anew: after the net pieces)
            hint = [int(owner[cur_inputs[t].face_ids[root]]) for t, root in plan.order if t < len(cur_inputs)]
            cuts += n_cut
            cur_inputs = cut_inputs
            cur_drawn = draw(cur_inputs)
        if hint is not None:
            cut_packing = pack(cur_drawn[0], hint, max(0.5, budget.left()))
            ran_out |= cut_packing.ran_out
            if (cut_packing.n_pages, len(cur_drawn[0])) < best[:2]:
                best = (cut_packing.n_pages, len(cur_drawn[0]), cur_parts, cur_inputs, cuts, cur_drawn, cut_packing)

    # the plans' time and one drawing of the pieces they cut: a plan is pointless without the drawing
    # (1,000+ faces: 7-10 s, as long as the budget, so without it horse-302-loop1 planned or not by chance)
    budget = deadline.within(pack_budget(deadline) + draw_seconds)
    first_plan = None
    if _plan_ahead(len(pieces)):
        # the first plan (the fewest pages, the first choice) is made in a forked process while this
        # one packs the pieces as they are, each on one core: read when that packing needs more
        # pages (the same plan: the process starts from this one's state)
        first_plan = ForkedStream(lambda: iter([plan_pages(pieces, [inp.net for inp in inputs], page, margin, GAP_MM,
                                                           fewest, budget.at, seed=opts.seed,
                                                           emptiest_first=PAGE_CHOICES[0], cap=None)]))
    try:
        packing = pack(pieces, None, pack_budget(deadline))
        best = (packing.n_pages, len(pieces), parts, inputs, 0, drawn, packing)
        ran_out = packing.ran_out
        for n_pages in range(fewest, packing.n_pages):
            say("layout", f"splitting pieces to fit {n_pages} page{'s' * (n_pages > 1)}")
            for emptiest_first in PAGE_CHOICES:
                first = n_pages == fewest and emptiest_first == PAGE_CHOICES[0]
                attempt(n_pages, None, emptiest_first, first_plan if first else None)
                if best[0] <= n_pages or ran_out:
                    break
            if best[0] <= n_pages or ran_out:
                break
    finally:
        if first_plan is not None:
            first_plan.close()  # (when the packing needed no more pages, the plan is not read)
    # one page fewer than that, with the parts cut compact (hulls of at most CAPS of a page, the
    # largest first); when that is met, one page fewer again
    n_pages = best[0] - 1
    while n_pages >= fewest and not ran_out:
        say("layout", f"splitting pieces into compact parts to fit {n_pages} page{'s' * (n_pages > 1)}")
        for cap in CAPS:
            attempt(n_pages, cap, True)
            if best[0] <= n_pages or ran_out:
                break
        if best[0] > n_pages:
            break
        n_pages = best[0] - 1
    _, n_pieces, parts, inputs, cuts, drawn, packing = best
    rank = np.full(mesh.n_faces, len(packing.order), dtype=np.int64)
    for pos, i in enumerate(packing.order):
        if i < len(inputs):  # glue strips come after the net pieces and have no faces
            rank[inputs[i].face_ids] = pos
    return PageSplit(parts, cuts, n_pieces, len(inputs), rank, ran_out, drawn, inputs, packing, label_cuts,
                     labels_ran_out, memo)


@dataclass(frozen=True, eq=False)
class Sheets:
    """The pieces in mm, placed on their pages (pieces[i] is folded[i]), the glue pairs, the
    layout facts, the packing (page of each piece), the page size and the scale (mm per model
    unit)."""

    pieces: tuple[SheetPiece, ...]
    glue: tuple[GlueEdge, ...]
    stats: LayoutStats
    packing: Packing
    width: float
    height: float
    seconds: float
    scale: float
    unnoted_sides: int = 0  # glued sides (`glued_to`) with no room for their "glue to X" note

    def page_of_piece(self) -> list[int]:
        """0-based page of every piece."""
        return [pl.page for pl in self.packing.placements]


def piece_inputs(mesh: Mesh, folded: list[FoldedPiece]) -> list[PieceInput]:
    """What fabricate needs of every piece: its net, part, and its vertices and faces in the mesh."""
    return [piece_input(fp.net, fp.part, mesh.faces[fp.mesh_faces], fp.mesh_faces) for fp in folded]


def lay_out(mesh: Mesh, folded: list[FoldedPiece], scale: float, opts: MakeOptions, width: float, height: float,
            deadline: Deadline, say: Callable[[str, str], None], planned: PageSplit | None = None,
            glued_to: np.ndarray | None = None) -> Sheets:
    """Tabs and labels for every piece, then the pieces packed onto as few pages as possible. With
    the `planned` split, its packing order goes first; when folding split no piece, the pieces it
    drew are the ones laid out, and its packing is kept (unless the time limit cut it short: then
    its order, the best of those tried on them, is the only one tried).
    glued_to: faces glued flat onto other pieces' faces (`pieces.with_side_notes`; a convex
    approximation's touching sides)."""
    tl = time.perf_counter()
    same = planned is not None and planned.same_pieces(folded)
    if same:  # drawn before folding: the same inputs draw the same pieces
        pieces, glue, stats = planned.drawn
    else:
        say("layout", f"tabs and labels for {len(folded)} pieces")
        pieces, glue, stats = build_sheet_pieces(piece_inputs(mesh, folded), scale, tabs=opts.tabs,
                                                 min_label_mm=opts.min_label_mm, deadline=deadline,
                                                 by_run=planned is not None and planned.drawn[2].labels_by_run,
                                                 memo=None if planned is None else planned.memo)
    unnoted = 0
    if glued_to is not None:
        pieces, unnoted = with_side_notes(list(pieces), glued_to, opts.min_label_mm)
    say("layout", f"packing {len(pieces)} pieces onto {opts.paper} pages")
    if same and not planned.packing.ran_out:
        # the very pieces packed before folding: filling them in the order that packing found, from
        # the same seed, gives the same placements again (checked on 11 models); 0.3 s at 1,500 faces
        packing = planned.packing
    else:
        page, margin = _packer_page(pack_box(width, height, opts))
        hint = None if planned is None else planned.hint(folded, len(pieces))
        packing = pack_outlines([p.footprint for p in pieces], page, margin=margin, gap=GAP_MM, seed=opts.seed,
                                time_limit=pack_budget(deadline), hint=hint, tries=1 if same else ORDER_TRIES)
    placed = tuple(place(p, packing.placements[i]) for i, p in enumerate(pieces))
    return Sheets(placed, tuple(glue), stats, packing, width, height, time.perf_counter() - tl, scale, unnoted)
