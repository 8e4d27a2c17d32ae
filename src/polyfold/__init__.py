"""polyfold: paper nets you can cut, fold and glue, with a verified folding path for every piece.

The pipeline, one package per stage, data flowing one way (Xi & Lien 2017; ALGORITHMS.md):

    mesh/       load & check: the `Mesh` record, topology, geometry, repairs
    inflate/    pop local dents (mass-spring inflation)
    segment/    nearly convex parts
    approximate/ each part as a closed convex polyhedron, none overlapping (not in make yet)
    unfold/     overlap-free nets (`Net`): heuristics, GA, multi-piece fallback
    fold/       a collision-free folding path per net (`FoldTree`, one validity checker, planners)
    fabricate/  pieces on paper: tabs, labels, splitting, packing, page checks
    pipeline/   `make`: every stage, the report and the assembly
    collide/    2D overlap and 3D collision tests (used by unfold, inflate and fold)
    formats/    files in and out: meshes, FOLD, SVG / PDF / DXF / PNG, safe writes
    apps/       the command line, the viewer, batch runs, the paper benchmark

The names below are the public API. They are imported on first use, so `import polyfold` (and
the command line's start-up) stays fast.
"""

from __future__ import annotations

__version__ = "0.1.0"

_API = {
    "PolyfoldError": "errors", "MeshError": "errors", "NoNetFound": "errors",
    "Deadline": "deadline",
    "Mesh": "mesh.mesh", "LoadedMesh": "mesh.repair", "describe": "mesh.repair",
    "load_mesh": "formats.meshes",
    "inflate": "inflate.inflate", "InflateResult": "inflate.inflate",
    "segment": "segment.segment", "Segmentation": "segment.segment",
    "approximate_hulls": "approximate.hulls", "HullApproximation": "approximate.hulls",
    "unfold": "unfold.search", "Net": "unfold.net", "UnfoldStats": "unfold.search",
    "FoldTree": "fold.tree", "plan_fold": "fold.plan", "FoldPath": "fold.plan", "sample_ratio": "fold.cspace",
    "make": "pipeline.make", "MakeOptions": "pipeline.options", "MakeResult": "pipeline.make", "MakeReport": "pipeline.report",
}

__all__ = sorted(_API)


def __getattr__(name: str):
    if name not in _API:
        raise AttributeError(f"module 'polyfold' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(f".{_API[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_API))
