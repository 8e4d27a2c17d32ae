"""Edge unfolding: spanning trees of the dual graph from heuristics and a genetic algorithm.

In: a manifold, consistently oriented `Mesh` (one edge-connected component, closed or open).
Out: a `Net` — a spanning forest of the dual graph with its planar layout, one tree per piece,
overlap-free (checked with the exact test of `collide.flat`).

Genome (ALGORITHMS.md 5.1, 5.5): one weight in [0, 1] per mesh edge; Prim's algorithm from the base
face keeps light edges as creases. Fitness = -(G + 100 L), G = overlapping face pairs, L = overlaps
at cuts around hyperbolic vertices. The GA stops at the first valid net. When the time (a
`Deadline`) or the generation budget runs out, the best tree is split into the fewest overlap-free
pieces found by a set cover of the crease paths between overlapping faces (ALGORITHMS.md 5.6).
Where no single net exists (`UnfoldProblem.single_net_blocked`), "auto" runs no GA: a short search
for the tree cut into the fewest pieces (`fewest_pieces`).
The merged edges of flat regions (`UnfoldProblem.merged`) are creases of every tree; the local
search and the fallback never cut them (the fallback only when two faces of one region overlap).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..deadline import Deadline, clock
from ..errors import NoNetFound
from ..mesh.mesh import Mesh
from . import kernels as K
from .net import Net
from .problem import HEURISTICS, UnfoldProblem


METHODS = ("auto", "ga", "steepest-edge", "flat-tree", "unflat-tree", "min-perimeter", "max-perimeter", "random")


@dataclass(frozen=True)
class UnfoldStats:
    seconds: float
    generations: int
    evaluations: int
    method: str
    pieces: int
    timed_out: bool
    best_overlaps: int = 0
    accepted: bool | None = None  # passed the caller's `accept` test (None: no test asked)
    no_single_net: str | None = None  # why none exists, when that was told without a search (`single_net_blocked`)


# the search's time when no single net exists (`UnfoldProblem.single_net_blocked`): it can only trade
# overlaps for pieces, and a short search does that as well as a long one (9 blocked parts of 16-580
# faces, star-4split-96's and a subdivided bunny's, seeds 1-3: the same piece counts at 0.25-0.5 s as
# at 5-10 s; make had spent 51 s of the star's 53 s searching its four blocked parts)
BLOCKED_SEARCH_S = 0.5
# `fewest_pieces` (method "auto" on such a mesh) stops sooner when this many trees in a row are cut
# into no fewer pieces. Against the GA it replaced there (0.5 s, seeds 1-3): 14 blocked parts of 16-96
# faces (a 24 x 10 torus's inside, star-4split-96 and its parts) 141 -> 100 pieces, 0.72 -> 0.18 s a
# search (the GA's generation on 16 faces overran its deadline by up to 0.4 s); saddles z = x^2 - y^2
# of 32-392 faces 87 -> 64 pieces, 1.0 -> 0.46 s (bench/bench_no_single_net.py); 4 s instead of 0.5
# saved 1 and 3 pieces over three seeds on the 200- and 392-face saddles, none on star-4split-96
BLOCKED_STALL = 500
FIRST_BATCH = 25  # heuristic nets built before the memetic search's first local search
RESTART_GENERATIONS = 3  # the memetic search's restart unit (generations, times the Luby sequence)


# The GA's initial population draws from these creators (ALGORITHMS.md 5.5).
GA_CREATORS = ("steepest-edge", "flat-tree", "unflat-tree", "random-edge")


def _fitness(G: np.ndarray, L: np.ndarray) -> np.ndarray:
    return -(G + 100 * L).astype(np.float64)


def _seed_population(problem: UnfoldProblem, rng: np.random.Generator, deadline: Deadline, population: int,
                     finished: Callable[[np.ndarray], bool]) -> tuple[np.ndarray, np.ndarray, list[str], int, int]:
    """The GA's initial population: each individual from a creator drawn from GA_CREATORS.

    Evaluated in small batches so a valid heuristic net (one `finished` accepts) stops the search
    at once; valid but unaccepted ones get fitness -0.5 (good parents, not answers). Returns
    (pop, fit, origin, evaluations, index of the accepted individual or -1); pop is cut short
    when the deadline passes.
    """
    mesh = problem.mesh
    pop = np.empty((population, mesh.topology.n_edges))
    creators = rng.integers(0, len(GA_CREATORS), size=population)
    origin = [GA_CREATORS[c] for c in creators]
    fit = np.full(population, -np.inf)
    evaluations = filled = 0
    start, size = 0, 2
    while start < population:
        # batches of 2, 4, 8, 16, then 25: small meshes are often done by the first heuristic
        stop = min(start + size, population)
        size = min(2 * size, 25)
        for i in range(start, stop):
            pop[i] = HEURISTICS[origin[i]](problem, rng)
        G, L = problem.evaluate(pop[start:stop])
        fit[start:stop] = _fitness(G, L)
        evaluations += stop - start
        filled = stop
        for i in start + np.flatnonzero(fit[start:stop] == 0):
            if finished(pop[i]):
                return pop, fit, origin, evaluations, int(i)
            fit[i] = -0.5
        start = stop
        if deadline.expired():
            break
    return pop[:filled], fit[:filled], origin[:filled], evaluations, -1


def run_ga(
    problem: UnfoldProblem,
    rng: np.random.Generator,
    deadline: Deadline,
    max_generations: int,
    population: int = 400,
    children: int = 50,
    tournament: int = 7,
    p_cross: float = 0.4,
    p_mut: float = 0.01,
    sigma: float = 0.3,
    progress: Callable[[int, float], None] | None = None,
) -> tuple[np.ndarray, float, int, int, str]:
    """Genetic algorithm of ALGORITHMS.md 5.5, seeded with the heuristics.

    Returns (best genome, best fitness, generations, evaluations, creator of the best). Stops at
    the first valid net (fitness 0), after max_generations or when the deadline passes.
    """
    mesh = problem.mesh
    n_e = mesh.topology.n_edges
    pop, fit, origin_list, evaluations, hit = _seed_population(problem, rng, deadline, population, lambda g: True)
    if hit >= 0:
        return pop[hit].copy(), 0.0, 0, evaluations, origin_list[hit]
    population = len(pop)
    origin = np.array(origin_list, dtype=object)
    best = float(fit.max())
    stall = 0
    generation = 0
    while generation < max_generations and not deadline.expired():
        generation += 1
        pm = p_mut if stall <= 100 else min(1.0, p_mut * 1.25 ** (stall / 100))
        pc = p_cross if stall <= 100 else min(1.0, p_cross * 1.1 ** (stall / 100))
        # tournament selection, two parents per child
        draws = rng.integers(0, population, size=(children, 2, tournament))
        winners = np.take_along_axis(draws, np.argmax(fit[draws], axis=2)[..., None], axis=2)[..., 0]
        a = pop[winners[:, 0]]
        b = pop[winners[:, 1]]
        swap = rng.random((children, n_e)) < pc
        kids = np.where(swap, b, a)
        mutate = rng.random((children, n_e)) < pm
        if mutate.any():
            idx = np.nonzero(mutate)
            vals = kids[idx] + rng.normal(0.0, sigma, size=len(idx[0]))
            bad = (vals < 0) | (vals > 1)
            while bad.any():  # redraw until inside [0, 1]
                vals[bad] = kids[idx][bad] + rng.normal(0.0, sigma, size=int(bad.sum()))
                bad = (vals < 0) | (vals > 1)
            kids[idx] = vals
        G, L = problem.evaluate(kids)
        evaluations += children
        kid_fit = _fitness(G, L)
        worst = np.argsort(fit)[:children]
        pop[worst] = kids
        fit[worst] = kid_fit
        origin[worst] = "ga"
        top = float(kid_fit.max())
        if top > best:
            best = top
            stall = 0
        else:
            stall += 1
        if progress is not None and generation % 20 == 0:
            progress(generation, best)
        if best == 0:
            break
    i = int(np.argmax(fit))
    return pop[i].copy(), float(fit[i]), generation, evaluations, str(origin[i])


def _crease_mask(problem: UnfoldProblem, genome: np.ndarray, parent_edge: np.ndarray | None = None) -> np.ndarray:
    """(E,) bool: the creases of the tree of `genome` (parent_edge: its decoded parent edges, if
    at hand)."""
    if parent_edge is None:
        parent_edge = problem.decode(genome)[1]
    crease = np.zeros(problem.mesh.topology.n_edges, dtype=np.bool_)
    crease[parent_edge[parent_edge >= 0]] = True
    return crease


def _genome_of_tree(crease: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Weights that make Prim's algorithm rebuild exactly this tree (creases light, cuts heavy)."""
    return np.where(crease, 0.0, 0.5) + 0.5 * rng.random(len(crease)) * np.where(crease, 0.0, 1.0)


class _AcceptFirst:
    """The memetic search's test of a valid genome: an answer when `accept` (None: any) passes it;
    the first valid genome it turns down is kept as the fallback answer."""

    def __init__(self, accept: Callable[[np.ndarray], bool] | None):
        self.accept = accept
        self.fallback: np.ndarray | None = None

    def __call__(self, genome: np.ndarray) -> bool:
        if self.accept is None or self.accept(genome):
            return True
        if self.fallback is None:
            self.fallback = genome.copy()
        return False


LOCAL_SEARCH_CALL = 1_000_000


def tree_local_search(problem: UnfoldProblem, child: np.ndarray, rng: np.random.Generator, deadline: Deadline,
                      temperature: float) -> tuple[np.ndarray, int, int]:
    """Edge-swap local search from the tree of a child genome (ALGORITHMS.md 5.5): (improved
    genome, overlap score, iterations). Runs up to max(1000, 4 F) iterations, in kernel calls short
    enough to check the deadline often; stops at a valid tree (score 0) or when the deadline passes."""
    mesh = problem.mesh
    topo = mesh.topology
    # Effort per generation: enough to finish most nets, small enough to restart from a fresh
    # child when the search is stuck in a local minimum.
    chunk_iters = max(1000, 4 * mesh.n_faces)
    # iterations per kernel call: tens of milliseconds a call (an iteration costs ~40 ns per face; a
    # call starts with a full overlap test), so the time checks stay frequent
    step = max(10, LOCAL_SEARCH_CALL // mesh.n_faces)
    crease = _crease_mask(problem, child)
    done_iters, score = 0, 0
    while done_iters < chunk_iters:
        score, it = K.local_search(
            crease, problem.merged, problem.base, problem.adj_ptr, problem.adj_face, problem.adj_edge, topo.edge_faces,
            mesh.faces, topo.face_edges, topo.edges, problem.hyperbolic, problem.local, problem.tol,
            step, int(rng.integers(2**31)), temperature, K.SURE_REJECT,
        )
        done_iters += max(it, 1)
        if score == 0 or deadline.expired():
            break
    return _genome_of_tree(crease, rng), int(score), done_iters


# Rings of faces around the overlapping faces whose edges a kick draws afresh. Seeds 6-15 at 12 s,
# single nets found and median seconds, noisy-ico4-s03 (5,120 faces) / bunny-348-loop2 (5,568):
# crossover children 2 / 4 of 10 nets; kicks of 1 ring 10 (3.7 s) / 10 (3.3 s), 2 rings 10 (3.8) /
# 10 (3.0), 3 rings 10 (5.4) / 10 (2.8), 5 rings 9 / 10 (3.5).
KICK_RINGS = 2


def kick(problem: UnfoldProblem, genome: np.ndarray, rng: np.random.Generator, rings: int) -> np.ndarray:
    """A genome for the tree of `genome` with the weights of the edges of the faces within `rings`
    edge-steps of its overlapping faces drawn afresh (uniform in [0, 1]): Prim's algorithm keeps
    the tree away from them and lays out that neighbourhood anew (the kick of an iterated local
    search). The tree's own genome when nothing overlaps."""
    parent, parent_edge, _, coords = problem.decode(genome)
    topo = problem.mesh.topology
    weights = _genome_of_tree(_crease_mask(problem, genome, parent_edge), rng)
    pairs = problem.overlaps(coords, parent)
    if len(pairs) == 0:
        return weights
    near = np.zeros(problem.mesh.n_faces, dtype=bool)
    near[pairs.ravel()] = True
    for _ in range(rings):
        across = topo.edge_faces[topo.face_edges[near].ravel()].ravel()
        near[across[across >= 0]] = True
    edges = np.unique(topo.face_edges[near].ravel())
    weights[edges] = rng.random(len(edges))
    return weights


class _Stream:
    """One memetic search (`run_memetic`), a step at a time: a step builds a first batch of the
    population (at the start and at each restart) or runs one generation. `answer` is set when a
    step finds a valid net that `accept` passes; `over()` once that or its budget ends it."""

    def __init__(self, problem: UnfoldProblem, rng: np.random.Generator, deadline: Deadline, max_generations: int,
                 population: int, tournament: int, p_cross: float, temperature: float,
                 progress: Callable[[int, float], None] | None, accept: Callable[[np.ndarray], bool] | None):
        self.problem, self.rng, self.deadline = problem, rng, deadline
        self.max_generations, self.population, self.tournament = max_generations, population, tournament
        self.p_cross, self.temperature, self.progress = p_cross, temperature, progress
        self.finished = _AcceptFirst(accept)
        self.pop: np.ndarray | None = None
        self.fit = np.zeros(0)
        self.best: np.ndarray | None = None
        self.best_fit = -np.inf
        self.generation = self.evaluations = self.since = self.batches = self.steps = 0
        self.answer: tuple[np.ndarray, str] | None = None  # (genome, how it was found)
        self.counts: list[tuple[int, int, int]] = []  # (round, generations, evaluations) of each step

    def over(self) -> bool:
        return self.answer is not None or (self.pop is not None and (
            self.generation >= self.max_generations or self.deadline.expired()))

    def step(self) -> None:
        """One step; its round is the generation it runs or builds the population for."""
        round_ = self.generation + 1
        self.steps += 1
        self._step()
        self.counts.append((round_, self.generation, self.evaluations))

    def _step(self) -> None:
        problem, rng, deadline = self.problem, self.rng, self.deadline
        if self.pop is None or self.since == RESTART_GENERATIONS * luby(self.batches):
            pop, fit, origin, more_ev, hit = _seed_population(problem, rng, deadline,
                                                              min(FIRST_BATCH, self.population), self.finished)
            self.evaluations += more_ev
            if hit >= 0:
                self.answer = (pop[hit].copy(), origin[hit])
                return
            self.pop, self.fit = pop, fit
            if fit.max() > self.best_fit:
                self.best, self.best_fit = pop[int(np.argmax(fit))].copy(), float(fit.max())
            self.batches += 1
            self.since = 0
            return
        pop, fit = self.pop, self.fit
        self.generation += 1
        self.since += 1
        if self.since == 1:
            child = pop[int(np.argmax(fit))].copy()
        else:
            if self.since == 2 and len(pop) < self.population:
                more, more_fit, more_origin, more_ev, hit = _seed_population(
                    problem, rng, deadline, self.population - len(pop), self.finished)
                self.evaluations += more_ev
                if hit >= 0:
                    self.answer = (more[hit].copy(), more_origin[hit])
                    return
                pop, fit = self.pop, self.fit = np.concatenate([pop, more]), np.concatenate([fit, more_fit])
            best = int(np.argmax(fit))
            if fit[best] < -0.5:  # the best tree overlaps: its overlaps' neighbourhood drawn afresh
                child = kick(problem, pop[best], rng, KICK_RINGS)
            else:  # the best is a valid net `accept` turned down: a child of two parents
                draws = rng.integers(0, len(pop), size=(2, self.tournament))
                winners = draws[np.arange(2), np.argmax(fit[draws], axis=1)]
                swap = rng.random(pop.shape[1]) < self.p_cross
                child = np.where(swap, pop[winners[1]], pop[winners[0]])
        genome, score, done_iters = tree_local_search(problem, child, rng, deadline, self.temperature)
        self.evaluations += done_iters
        worst = int(np.argmin(fit))
        pop[worst] = genome
        fit[worst] = -float(score)
        if self.progress is not None:
            self.progress(self.generation, max(self.best_fit, float(fit.max())))
        if score == 0:
            if self.finished(genome):
                self.answer = (genome, "ga+local-search")
                return
            fit[worst] = -0.5
        if fit[worst] > self.best_fit:
            self.best, self.best_fit = genome.copy(), float(fit[worst])

    def outcome(self) -> _Outcome:
        """What the search found (picklable: a forked race returns it)."""
        if self.answer is not None:
            return _Outcome(self.answer[0], 0.0, self.answer[1], False, tuple(self.counts))
        if self.finished.fallback is not None:
            return _Outcome(self.finished.fallback, 0.0, "ga+local-search", True, tuple(self.counts))
        best, best_fit = self.best, self.best_fit
        if len(self.fit):
            i = int(np.argmax(self.fit))
            if self.fit[i] > best_fit:
                best, best_fit = self.pop[i].copy(), float(self.fit[i])
        return _Outcome(best, best_fit, "ga+local-search", False, tuple(self.counts))


@dataclass(frozen=True, eq=False)
class _Outcome:
    """What a `_Stream` found: its answer, else the first valid net `accept` turned down
    (`fallback`), else its fittest genome; the fitness (0 for a valid net) and how it was found."""

    genome: np.ndarray
    fitness: float
    origin: str
    fallback: bool
    counts: tuple[tuple[int, int, int], ...]  # (round, generations, evaluations) of each step

    def upto(self, last_round: int) -> tuple[int, int]:
        """(generations, evaluations) after its steps of rounds up to last_round."""
        done = [(g, e) for r, g, e in self.counts if r <= last_round]
        return done[-1] if done else (0, 0)


# steps (first batch, first generation) the memetic search takes alone before a second search
# races it: most nets are found by then, and a race costs a forked process and its first batch
SOLO_STEPS = 2
NEVER = 2**62  # a race round no search reaches


def run_memetic(
    problem: UnfoldProblem,
    rng: np.random.Generator,
    deadline: Deadline,
    max_generations: int,
    population: int = 400,
    tournament: int = 7,
    p_cross: float = 0.4,
    temperature: float = 0.5,
    progress: Callable[[int, float], None] | None = None,
    accept: Callable[[np.ndarray], bool] | None = None,
    race: bool = True,
) -> tuple[np.ndarray, float, int, int, str]:
    """GA of ALGORITHMS.md 5.5 with a Lamarckian tree local search ("auto").

    Same heuristic-seeded population as `run_ga`; each generation makes one child, improves it
    with `tree_local_search` (a crease on the tree path between two overlapping faces is swapped
    for a cut edge that reconnects the halves), and writes the improved tree back into the
    population in place of the worst individual. The first generation after a (re)start improves
    the population's best; the next ones a `kick` of the best (its overlaps' neighbourhood drawn
    afresh, an iterated local search: at 5,000 faces a crossover child starts with tens of
    thousands of overlapping pairs and used most of its generation getting back to a handful), or,
    when the best is a valid net `accept` turned down, a child of two parents (tournament
    selection and uniform crossover as in `run_ga`). Restarted from a new first batch after 3, 3,
    6, 3, 3, 6, 12, ... generations (`luby`). Returns the same tuple as `run_ga` (the best genome
    met across restarts); stops like it.

    race: when the first SOLO_STEPS steps (`_Stream`) found no net, a second search with a random
    stream of its own (`rng.spawn`) races this one (`_race`); generations and evaluations are then
    the two searches' together, max_generations each one's, and progress is this one's.

    accept: optional extra test of a valid (overlap-free) genome; the search goes on, within the
    budget, until a valid genome passes it, and falls back to the first valid one otherwise.
    """
    # The first batch of the population only, then one local search from its best: most nets
    # are finished by that search, and building the whole population (hundreds of heuristic
    # trees) first would cost ten times more. The rest of the population is built only if not.
    # Restarts: the time a search needs is heavy-tailed (one seed in seconds, the next stuck on one
    # overlap for minutes), so runs are cut after a Luby sequence of generations (1, 1, 2, 1, 1,
    # 2, 4, ... x RESTART_GENERATIONS) and start afresh from a new first batch, the random stream
    # going on (deterministic for a seed). The same tail is why two searches racing find a net
    # sooner than one running twice as long.
    args = (max_generations, population, tournament, p_cross, temperature)
    first = _Stream(problem, rng, deadline, *args, progress, accept)
    while not first.over() and (first.steps < SOLO_STEPS or not race):
        first.step()
    if first.over():
        return _result(first.outcome())
    second = _Stream(problem, rng.spawn(1)[0], deadline, *args, None, accept)
    base = first.generation  # (the second search's rounds are numbered on from here)
    (a, b), won = _race(first, second)
    if min(won) < NEVER:  # the search that found a net in the earlier round; on a tie the first
        k = int(np.argmin(won))
        winner = (a, b)[k]
        # counted: the steps taken in turns up to the winning one (so the same on one core or two),
        # the first search's up to its round, the second's before it (on a tie the first is first)
        (g1, e1), (g2, e2) = a.upto(won[k]), b.upto(won[k] - base - (k == 0))
    else:  # neither: a valid net that `accept` turned down, else the fitter (the first on a tie)
        winner = a if a.fallback or (not b.fallback and a.fitness >= b.fitness) else b
        (g1, e1), (g2, e2) = a.upto(NEVER), b.upto(NEVER)
    return winner.genome, winner.fitness, g1 + g2, e1 + e2, winner.origin


def _result(out: _Outcome) -> tuple[np.ndarray, float, int, int, str]:
    return (out.genome, out.fitness, *out.upto(NEVER), out.origin)


def _race(first: _Stream, second: _Stream) -> tuple[tuple[_Outcome, _Outcome], list[int]]:
    """Two searches in rounds, a generation each (a step that builds a population belongs to the
    round of the generation after it): the first one's numbered on from its generations so far,
    the second's from there. Returns their outcomes and the round each found a net in
    (NEVER: none): the earliest wins, the first on a tie, so the winner does not depend on which
    search runs faster. With two cores the second runs in a forked process (`processes.beside`)
    and each stops once the other has won a round it cannot beat (its deadline is up then, so
    mid-step); on one core (or where no process can be forked) they take turns, a round each,
    until one wins."""
    from multiprocessing import RawArray

    from ..processes import beside, can_fork, usable_cores

    streams, offset = (first, second), (0, first.generation)
    won = RawArray("q", [NEVER, NEVER])  # (shared with the forked process)
    at = [0, 0]  # the round each search is in (or won); each process keeps its own's

    def beaten(k: int) -> bool:
        return (won[1 - k], 1 - k) < (at[k], k)

    def step(k: int) -> bool:
        """One step of search k unless it is over or beaten; whether it took one."""
        s = streams[k]
        if s.over():
            return False
        at[k] = s.generation + 1 + offset[k]
        if beaten(k):
            return False
        s.step()
        if s.answer is not None:
            won[k] = at[k]
        return True

    for k, s in enumerate(streams):
        s.deadline = s.deadline.or_when(lambda k=k: beaten(k))

    def run(k: int) -> _Outcome:
        while step(k):
            pass
        return streams[k].outcome()

    if usable_cores() >= 2 and can_fork():
        outcomes = beside(lambda: run(0), lambda: run(1))
    else:
        while any([step(0), step(1)]):
            pass
        outcomes = (first.outcome(), second.outcome())
    return outcomes, list(won)


def luby(i: int) -> int:
    """The i-th term (i >= 1) of the Luby sequence 1, 1, 2, 1, 1, 2, 4, 1, 1, 2, 1, 1, 2, 4, 8, ...
    (restart lengths within a log factor of the best fixed cutoff, whatever the run-time
    distribution: Luby, Sinclair and Zuckerman 1993)."""
    k = 1
    while (1 << k) - 1 < i:
        k += 1
    while i != (1 << k) - 1:
        i -= (1 << (k - 1)) - 1
        k = 1
        while (1 << k) - 1 < i:
            k += 1
    return 1 << (k - 1)


def run_heuristic(problem: UnfoldProblem, name: str, rng: np.random.Generator,
                  deadline: Deadline) -> tuple[np.ndarray, float, int]:
    """Plain heuristic mode: fresh random direction per try, keep the best (fewest overlaps)."""
    best_w, best_fit, tries = None, -np.inf, 0
    make = HEURISTICS[name]
    while tries < 100 and (tries == 0 or not deadline.expired()):
        w = make(problem, rng)[None, :]
        G, L = problem.evaluate(w)
        tries += 1
        f = float(_fitness(G, L)[0])
        if f > best_fit:
            best_w, best_fit = w[0], f
        if f == 0 or name in ("min-perimeter", "max-perimeter"):  # deterministic rules: one try
            break
    return best_w, best_fit, tries


MAX_PATH_CREASES = 20_000_000  # creases on all tree paths `split_into_pieces` covers at once (160 MB)
PATH_BLOCK_FACES = 4096  # the first block size it cuts a larger instance into (halved while still too large)


def split_into_pieces(parent: np.ndarray, parent_edge: np.ndarray, order: np.ndarray, pairs: np.ndarray,
                      exact_limit: int = 2000, exact_seconds: float = 5.0,
                      cuttable: np.ndarray | None = None) -> np.ndarray:
    """Cut the fewest creases so no overlapping pair stays in one piece (ALGORITHMS.md 5.6).

    Greedy set cover of the tree paths between overlapping faces (crease on most uncovered paths
    first, numba), refined by an exact ILP when the instance is small (at most `exact_limit`
    candidate creases). cuttable (F,): faces whose crease to their parent may be cut (None: all);
    the others (merged creases of flat regions) are cut only on a path that has no other crease
    (two faces of one flat region that overlap: a self-overlapping or not quite flat region, where
    an overlapping net would be worse). An instance with more than MAX_PATH_CREASES creases on its
    paths is first cut into blocks (`kernels.size_cuts`), so the cover is bounded in time and
    memory at the price of a few more pieces. Returns a boolean mask (F,) of faces whose crease to
    their parent is cut.
    """
    n = len(parent)
    cut = np.zeros(n, dtype=bool)
    if len(pairs) == 0:
        return cut
    pairs = np.ascontiguousarray(pairs, dtype=np.int64)
    # a net of tens of thousands of faces has long paths between many overlapping pairs (82k
    # faces: ~1e9 creases on them, a minute and gigabytes): it is first cut into blocks of about
    # `block` faces, and only the pairs inside one block are covered
    block = PATH_BLOCK_FACES
    while K.tree_path_ptr(parent, order, pairs, MAX_PATH_CREASES)[-1] > MAX_PATH_CREASES and block >= 16:
        blocks = K.size_cuts(parent, order, np.ones(n, dtype=np.bool_) if cuttable is None else cuttable, block)
        cut |= blocks
        parent = parent.copy()
        parent[blocks] = -1
        piece = K.piece_labels(order, parent)
        pairs = np.ascontiguousarray(pairs[piece[pairs[:, 0]] == piece[pairs[:, 1]]])
        block //= 2
    if len(pairs) == 0:
        return cut
    ptr, members = K.tree_paths(parent, order, pairs)
    if cuttable is not None:
        ptr, members = _cuttable_paths(ptr, members, cuttable)
    greedy = K.greedy_cover(ptr, members, n)
    chosen = np.flatnonzero(greedy)
    candidates = np.flatnonzero(np.bincount(members, minlength=n))  # ascending, as np.unique (and faster)
    if len(chosen) > 1 and len(candidates) <= exact_limit:
        try:
            from scipy.optimize import Bounds, LinearConstraint, milp
            from scipy.sparse import csr_matrix

            col = np.searchsorted(candidates, members)
            rows = np.repeat(np.arange(len(ptr) - 1), np.diff(ptr))
            A = csr_matrix((np.ones(len(members)), (rows, col)), shape=(len(ptr) - 1, len(candidates)))
            A.data[:] = 1.0  # a crease listed twice on one path still counts once
            res = milp(np.ones(len(candidates)), constraints=LinearConstraint(A, lb=1, ub=np.inf),
                       integrality=np.ones(len(candidates)), bounds=Bounds(0, 1),
                       options={"time_limit": exact_seconds})
            if res.x is not None and res.success:
                exact = candidates[res.x > 0.5]
                if len(exact) < len(chosen):
                    chosen = exact
        except Exception:  # the ILP is only a refinement of the greedy cover
            pass
    cut[chosen] = True
    return cut


def _cuttable(problem: UnfoldProblem, parent_edge: np.ndarray) -> np.ndarray:
    """(F,) faces whose crease to their parent the fallback may cut (not the base, no merged edge)."""
    return (parent_edge >= 0) & ~problem.merged[parent_edge]


def pieces_of(problem: UnfoldProblem, genome: np.ndarray, exact_seconds: float = 0.0) -> tuple[int, int]:
    """(pieces, overlapping pairs) of a genome's tree cut by `split_into_pieces`: its greedy cover,
    and its exact ILP too (for at most exact_seconds) when exact_seconds > 0, as `unfold` cuts it."""
    parent, parent_edge, order, coords = problem.decode(genome)
    pairs = problem.overlaps(coords, parent)
    if len(pairs) == 0:
        return 1, 0
    exact = {"exact_seconds": exact_seconds} if exact_seconds > 0 else {"exact_limit": 0}
    cut = split_into_pieces(parent, parent_edge, order, pairs, cuttable=_cuttable(problem, parent_edge), **exact)
    return int(np.count_nonzero(cut)) + 1, len(pairs)


def fewest_pieces(problem: UnfoldProblem, rng: np.random.Generator, deadline: Deadline) -> tuple[np.ndarray, int]:
    """For a mesh with no single net (`UnfoldProblem.single_net_blocked`): a genome whose tree the
    fallback cuts into few pieces, and how many trees were scored. The tree with the fewest
    overlapping pairs (what the GA looks for) is not the one cut into the fewest pieces (a 24-face
    part of a torus's inside: 6 pairs, 3 pieces; 14 pairs, 2), so trees are scored here by their
    pieces (`split_into_pieces`' greedy cover), then their pairs: the heuristics' trees, then one to
    three cut candidates' weights of the best drawn afresh, kept when no worse, until the deadline or
    BLOCKED_STALL trees in a row without a better one. The heuristics' trees are scored whatever the
    deadline (milliseconds), so a slow first call cannot leave the search without them."""
    scored = [(pieces_of(problem, genome), k, genome)
              for k, genome in enumerate(start(problem, rng) for start in HEURISTICS.values())]
    best_score, _, best = min(scored, key=lambda s: s[:2])
    trees, stall = len(scored), 0
    candidates = problem.cut_candidates
    while best_score[0] > 1 and stall < BLOCKED_STALL and len(candidates) and not deadline.expired():
        trial = best.copy()
        drawn = rng.choice(candidates, size=min(int(rng.integers(1, 4)), len(candidates)), replace=False)
        trial[drawn] = rng.random(len(drawn))
        score = pieces_of(problem, trial)
        trees += 1
        stall = 0 if score < best_score else stall + 1
        if score <= best_score:
            best, best_score = trial, score
    return best, trees


def _cuttable_paths(ptr: np.ndarray, members: np.ndarray, cuttable: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The tree paths (CSR ptr, members: creases named by their child face) without the creases
    that may not be cut, except on paths made of such creases only (kept whole)."""
    rows = np.repeat(np.arange(len(ptr) - 1), np.diff(ptr))
    ok = cuttable[members]
    free = np.bincount(rows, weights=ok, minlength=len(ptr) - 1)
    keep = ok | (free[rows] == 0)
    counts = np.bincount(rows[keep], minlength=len(ptr) - 1)
    return np.concatenate([[0], np.cumsum(counts)]).astype(np.int64), np.ascontiguousarray(members[keep])


def _net_from_tree(problem: UnfoldProblem, parent, parent_edge, order, coords, cut: np.ndarray | None = None) -> Net:
    parent = parent.copy()
    parent_edge = parent_edge.copy()
    if cut is not None and cut.any():
        parent[cut] = -1
        parent_edge[cut] = -1
        piece = K.piece_labels(order, parent)
    else:  # one spanning tree: one piece
        piece = np.zeros(len(parent), dtype=np.int64)
    return Net(mesh=problem.mesh, parent=parent, parent_edge=parent_edge, order=order.copy(), coords=coords, piece=piece)


def unfold(
    mesh: Mesh,
    method: str = "auto",
    seed: int = 0,
    time_limit: float = 60.0,
    max_pieces: int | None = None,
    max_generations: int = 15000,
    progress: Callable[[int, float], None] | None = None,
    accept: Callable[[Net], bool] | None = None,
    deadline: Deadline | None = None,
) -> tuple[Net, UnfoldStats]:
    """Unfold one edge-connected component into a net (one piece when one is found in time).

    method: "auto" (heuristics' best first, then the GA), "ga", or a heuristic name. max_pieces=1
    raises `NoNetFound` instead of falling back to several pieces (at once when
    `UnfoldProblem.single_net_blocked`; without max_pieces such a mesh is searched for at most
    BLOCKED_SEARCH_S, by `fewest_pieces` under "auto"). Deterministic for a given seed
    (the time limit can only make it stop earlier). accept (method "auto" only): keep searching,
    within the time limit, for a valid net that also passes this test (e.g. linear foldability);
    `UnfoldStats.accepted` says whether one did. deadline: when given, the search stops there
    instead of `time_limit` seconds from now (the generation cap stays max_generations).
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    t0 = time.perf_counter()
    if deadline is None:
        deadline = Deadline.after(time_limit)
    else:
        time_limit = deadline.left()
    rng = np.random.default_rng(seed)
    problem = UnfoldProblem.from_mesh(mesh)
    blocked = problem.single_net_blocked()
    if max_pieces == 1 and blocked:  # no search can succeed: say so at once
        raise NoNetFound(blocked)
    if blocked and time_limit > BLOCKED_SEARCH_S:  # a net in pieces whatever the search: a short one
        deadline, time_limit = Deadline(min(deadline.at, clock() + BLOCKED_SEARCH_S)), BLOCKED_SEARCH_S
    if np.count_nonzero(mesh.topology.interior) == mesh.n_faces - 1:
        # the faces' adjacency is a tree (one face, or a strip that closes no loop): the one
        # spanning tree there is, whatever the weights
        weights = np.zeros(mesh.topology.n_edges)
        fitness, generations, evaluations, winner = 0.0, 0, 0, "trivial"
    elif method == "auto" and blocked:  # no single net to find: the tree cut into the fewest pieces instead
        weights, evaluations = fewest_pieces(problem, rng, deadline)
        fitness, generations, winner = 0.0, 0, "fewest-pieces"
    elif method == "auto":
        accept_genome = None if accept is None else (
            lambda genome: bool(accept(_net_from_tree(problem, *problem.decode(genome)))))
        # Large meshes: a smaller seed population, so the local search gets the time budget.
        population = min(max(200_000 // mesh.n_faces, 50), 400)
        weights, fitness, generations, evaluations, winner = run_memetic(
            problem, rng, deadline, max_generations, population=population, progress=progress, accept=accept_genome)
    elif method == "ga":
        weights, fitness, generations, evaluations, winner = run_ga(problem, rng, deadline, max_generations, progress=progress)
    else:
        weights, fitness, evaluations = run_heuristic(problem, method, rng, deadline)
        generations, winner = 0, method
    parent, parent_edge, order, coords = problem.decode(weights)
    pairs = problem.overlaps(coords, parent)
    timed_out = len(pairs) > 0

    def in_pieces() -> Net:
        """The net, cut into pieces where faces overlap (none: as it is)."""
        cut = None
        if len(pairs):
            cut = split_into_pieces(parent, parent_edge, order, pairs, exact_seconds=min(5.0, 0.05 * time_limit + 0.5),
                                    cuttable=_cuttable(problem, parent_edge))
        return _net_from_tree(problem, parent, parent_edge, order, coords, cut)

    if len(pairs) and max_pieces == 1:
        searched = time.perf_counter() - t0

        def fallback() -> tuple[Net, UnfoldStats]:
            net = in_pieces()
            return net, UnfoldStats(seconds=searched, generations=generations, evaluations=evaluations, method=winner,
                                    pieces=net.n_pieces, timed_out=True, best_overlaps=len(pairs))

        raise NoNetFound(
            f"no single-piece net found in {searched:.1f} s "
            f"({generations} generations, best net has {len(pairs)} overlapping face pairs)",
            pieces=fallback)
    net = in_pieces()
    accepted = None
    if accept is not None:
        accepted = net.n_pieces == 1 and bool(accept(net))
    stats = UnfoldStats(
        seconds=time.perf_counter() - t0, generations=generations, evaluations=evaluations, method=winner,
        pieces=net.n_pieces, timed_out=timed_out, best_overlaps=len(pairs), accepted=accepted, no_single_net=blocked,
    )
    return net, stats
