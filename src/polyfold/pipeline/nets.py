"""The `unfold` command's job: a net of every component, one FOLD document, optionally a folding
path (`--fold`) or a preference for nets whose straight-line fold is free (`--prefer-linear`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ..collide.tolerance import CONTACT_TOL, THICKNESS_REL
from ..deadline import Deadline
from ..errors import PolyfoldError
from ..fold.plan import FoldPath, is_linearly_foldable
from ..fold.tree import FoldTree, collides
from ..formats.fold import pattern_fold
from ..mesh.repair import LoadedMesh
from ..unfold.net import Net
from ..unfold.pattern import CreasePattern, crease_pattern
from ..unfold.search import UnfoldStats
from .folding import plan_checked
from .parts import unfold_components


@dataclass(frozen=True)
class NetsOptions:
    """Options of the `unfold` command (see its --help)."""

    method: str = "auto"
    seed: int = 1
    max_pieces: int | None = None  # 1: a single piece per component or NoNetFound
    fold: bool = False
    prefer_linear: bool = False
    planner: str = "auto"
    resolution_deg: float = 1.0
    contact_tol: float = CONTACT_TOL
    thickness: float = THICKNESS_REL  # with --fold: of the material, relative to the model size


@dataclass(frozen=True, eq=False)
class NetsResult:
    """nets / stats: one per component; pattern: all of them in one plane; fold: the FOLD
    document (with `polyfold:path` when a path was found); path: the folding path, or None;
    path_error: why `--fold` found none (the flat net is still valid); linear: with
    --prefer-linear, whether the straight-line fold of the net is collision-free."""

    nets: tuple[Net, ...]
    stats: tuple[UnfoldStats, ...]
    pattern: CreasePattern
    fold: dict
    path: FoldPath | None = None
    path_error: str | None = None
    linear: bool | None = None


def linear_fold_test(contact_tol: float, resolution_deg: float) -> Callable[[Net], bool]:
    """An `accept` test for `unfold`: the net folds along the straight line without collision.
    When the folded shape itself intersects, no net can pass: every net is accepted at once."""
    hopeless = []

    def accept(net: Net) -> bool:
        tree = FoldTree.from_net(net, contact_tol)
        if hopeless or collides(tree, tree.goal):
            hopeless.append(True)  # the shape itself intersects: no net can fold, stop looking
            return True
        return is_linearly_foldable(tree, resolution_deg)

    return accept


def unfold_nets(loaded: LoadedMesh, title: str, opts: NetsOptions, deadline: Deadline,
                progress: Callable[[int, int, float], None] | None = None) -> NetsResult:
    """Unfold every component of the mesh in its share of the time to `deadline`, then (--fold)
    plan a folding path for the time left (at least 1 s). progress(component, generation, best).
    Raises NoNetFound (see `parts.unfold_components`)."""
    accept = linear_fold_test(opts.contact_tol, opts.resolution_deg) if opts.prefer_linear else None
    found = unfold_components(loaded.components, method=opts.method, seed=opts.seed, deadline=deadline,
                              max_pieces=opts.max_pieces, progress=progress, accept=accept)
    nets = tuple(net for net, _ in found)
    pattern = crease_pattern(nets)
    fold = pattern_fold(pattern, title=title)
    path, error, linear = None, None, None
    if opts.fold:
        try:
            fold, path, error = plan_checked(
                fold, FoldTree.from_pattern(pattern, opts.contact_tol), planner=opts.planner,
                resolution_deg=opts.resolution_deg, time_limit=max(1.0, deadline.left()), seed=opts.seed,
                contact_tol=opts.contact_tol, thickness_rel=opts.thickness)
        except PolyfoldError as exc:  # e.g. the goal shape itself intersects: the flat net is still valid
            error = str(exc)
    if opts.prefer_linear:
        linear = is_linearly_foldable(FoldTree.from_pattern(pattern, opts.contact_tol), opts.resolution_deg)
    return NetsResult(nets, tuple(st for _, st in found), pattern, fold, path, error, linear)
