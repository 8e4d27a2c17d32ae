"""From a mesh to nets: which faces make a part, and the net of every part.

`make_parts` is make's segment + unfold stage: with `--tau` / `--parts` the mesh is segmented
first; with `--segment auto` every connected component stays whole when it has a single-piece net
(found within its share of half the time limit, and at most SINGLE_NET_S + SINGLE_NET_S_PER_FACE x
its faces) and is segmented otherwise (past the searches'
deadline, or when segmenting it would not fit in their time left (SEGMENT_S_PER_FACE): unfolded
into pieces as it is). `unfold_components`
is the `unfold` command's: every component unfolded in its share of the time left.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..deadline import Deadline
from ..errors import NoNetFound
from ..mesh.mesh import Mesh, face_components
from ..segment.segment import DEFAULT_TAU, segment
from ..unfold.net import Net
from ..unfold.search import UnfoldStats, unfold
from ..unfold.tabroom import open_notches
from .options import MakeOptions
from .report import NetReport, SegmentReport, UnfoldReport

MIN_UNFOLD_S = 0.5  # the least time a part's search gets, however little is left
# the most a part's search for a single net gets: SINGLE_NET_S + SINGLE_NET_S_PER_FACE x its faces
# (a part of 144 faces 3.4 s, of 1,280 faces 14.8 s); then it is segmented, or cut into pieces. Where
# single nets were found, the slowest took 0.53 s on the closed shared models (horse-302, seeds
# 1-10) and 5.2 s on generated meshes of 1,000-2,100 faces (a rough 1,280-face sphere, seeds 1-5,
# README "Where a user waits"); a search that finds none by then rarely finds one later (a
# 144-face torus: none in 20 s on seeds 1-3), and make had searched it for 30 s of its 32 s
SINGLE_NET_S = 2.0
SINGLE_NET_S_PER_FACE = 0.01
TAB_ROOM_S = 5.0  # the most time a part's net spends opening notches for tabs (`open_notches`)
# segmenting is one kernel run the time limit cannot stop, of about this much a face and more on
# big meshes (22k faces: 19 s; a 93,696-face subdivided Spot: minutes): a component is only
# segmented when that fits in the searches' time left, else unfolded into pieces as it is
SEGMENT_S_PER_FACE = 1e-3


@dataclass(frozen=True, eq=False)
class Part:
    """A part of the mesh (faces: ids into the mesh, ascending or in segmentation order) and its net."""

    faces: np.ndarray
    net: Net


def component_faces(mesh: Mesh) -> tuple[np.ndarray, list[np.ndarray]]:
    """(component label of every face, the face ids of every edge-connected component)."""
    comp = face_components(mesh.n_faces, mesh.topology)
    return comp, [np.flatnonzero(comp == c) for c in range(int(comp.max()) + 1)]


class _Segmenter:
    """Segmentations of sets of faces of one mesh, and what they add up to for the report."""

    def __init__(self, mesh: Mesh, deadline: Deadline) -> None:
        self.mesh = mesh
        self.deadline = deadline  # a --parts search stops here with the closest count so far
        self.seconds = 0.0
        self.tau: float | None = None
        self.concavity: list[float] = []

    def __call__(self, faces: np.ndarray, tau: float | None, parts: int | None) -> list[np.ndarray]:
        ts = time.perf_counter()
        seg = segment(self.mesh.submesh(faces), tau=DEFAULT_TAU if tau is None else tau, parts=parts, seed=0,
                      deadline=self.deadline)
        self.seconds += time.perf_counter() - ts
        self.tau = seg.tau
        self.concavity += [float(c) for c in seg.concavity]
        return [faces[f] for f in seg.face_ids]


def make_parts(mesh: Mesh, opts: MakeOptions, deadline: Deadline, say: Callable[[str, str], None],
               hard: Deadline = Deadline.never()) -> tuple[list[Part], SegmentReport, UnfoldReport]:
    """The parts of the mesh with their nets (see the module docstring), and the stage reports.
    `deadline`: the searches'; past `hard` OutOfTime (every part needs a net, however short its
    search: past `deadline` each still gets MIN_UNFOLD_S)."""
    comp, components = component_faces(mesh)
    mode = "tau" if opts.tau is not None else "parts" if opts.parts is not None else opts.segment
    segmenter = _Segmenter(mesh, deadline)
    segmented: list[int] = []
    nets: list[NetReport] = []
    unfold_s = 0.0
    budget = max(1.0, 0.5 * opts.time_limit)  # unfolding gets at most half the time limit
    if opts.segments:
        say("segment", f"segmenting ({mode})")
        todo = segmenter(np.arange(mesh.n_faces), opts.tau, opts.parts)
    else:
        todo = list(components)
    out: list[Part] = []
    def share() -> float:
        """Seconds for the part just taken off `todo`: its share of what is left (past `hard`:
        OutOfTime, as every part needs a net)."""
        hard.check(f"unfolding part {len(out) + 1} ({len(todo) + 1} to go)")
        return max(MIN_UNFOLD_S, min(budget, deadline.left()) / max(1, len(todo) + 1))

    while todo:
        faces = todo.pop(0)
        part_mesh = mesh.submesh(faces)
        left = min(share(), SINGLE_NET_S + SINGLE_NET_S_PER_FACE * len(faces))
        say("unfold", f"part {len(out) + 1}: {len(faces)} faces")
        tu = time.perf_counter()
        try:
            # past the searches' deadline a part is unfolded into pieces at once: no time for a
            # single net, nor for segmenting (one kernel run, 19 s on 22k faces, minutes on 89k)
            single = mode == "auto" and len(faces) > 1 and not deadline.expired()
            net, st = unfold(part_mesh, seed=opts.seed, time_limit=left, max_pieces=1 if single else None)
        except NoNetFound as exc:
            # auto: no single net for this component in time -> split it into nearly convex parts
            in_pieces = exc.pieces
            unfold_s += time.perf_counter() - tu
            if deadline.expired() or len(faces) * SEGMENT_S_PER_FACE > deadline.left():
                say("segment", f"no single net for a {len(faces)}-face component, and no time left to segment it: "
                               "unfolding it into pieces")
                subs = [faces]
            else:
                say("segment", f"no single net for a {len(faces)}-face component: segmenting it")
                segmented.append(int(comp[faces[0]]))
                subs = segmenter(faces, None, None)
            if len(subs) == 1:  # already nearly convex: accept several pieces instead
                tu = time.perf_counter()
                # the search's best net in pieces (the same seed would only search it again)
                net, st = in_pieces() if in_pieces is not None else unfold(part_mesh, seed=opts.seed, time_limit=share())
            else:
                todo = subs + todo
                continue
        net, room = open_notches(net, deadline=Deadline.after(min(TAB_ROOM_S, max(0.1, deadline.left()))))
        unfold_s += time.perf_counter() - tu
        nets.append(NetReport(faces=int(len(faces)), pieces=int(net.n_pieces), seconds=st.seconds, method=st.method,
                              timed_out=bool(st.timed_out), no_single_net=st.no_single_net))
        out.append(Part(faces, net))
    for reason in sorted({n.no_single_net for n in nets if n.no_single_net}):
        blocked = [n for n in nets if n.no_single_net == reason]
        say("unfold", f"{len(blocked)} part(s) cut into {sum(n.pieces for n in blocked)} pieces, the fewest found: "
                      f"{reason}")
    tau = segmenter.tau if opts.segments else (DEFAULT_TAU if segmented else None)
    seg_report = SegmentReport(mode=mode, tau=tau, parts=len(out), concavity=tuple(segmenter.concavity),
                               seconds=segmenter.seconds, segmented_components=tuple(segmented))
    return out, seg_report, UnfoldReport(seconds=unfold_s, nets=tuple(nets))


def unfold_components(components: list[Mesh] | tuple[Mesh, ...], *, method: str = "auto", seed: int = 1,
                      deadline: Deadline, max_pieces: int | None = None,
                      progress: Callable[[int, int, float], None] | None = None,
                      accept: Callable[[Net], bool] | None = None) -> list[tuple[Net, UnfoldStats]]:
    """Unfold every component (seed + i for component i) in its share of the time left.

    progress(component, generation, best fitness); accept: see `unfold.search.unfold`. Raises
    NoNetFound naming the component (when there are several) if max_pieces=1 cannot be met."""
    out = []
    for i, comp in enumerate(components):
        share = deadline.left() / (len(components) - i)  # what is left, shared among the components still to do
        label = f"component {i + 1}/{len(components)} " if len(components) > 1 else ""
        report = None if progress is None else (lambda gen, best, _i=i: progress(_i, gen, best))
        try:
            out.append(unfold(comp, method=method, seed=seed + i, time_limit=share, max_pieces=max_pieces,
                              progress=report, accept=accept))
        except NoNetFound as exc:
            raise NoNetFound(f"{label}{exc}") from None
    return out
