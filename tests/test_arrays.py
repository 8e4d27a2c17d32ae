"""arrays.py: the kernels' copy without slice assignment; and a scan of every kernel's source for
the numba features that cost a first run seconds of compiling for what a few lines do (see
polyfold.arrays and polyfold.sorting)."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np

from polyfold.arrays import copy_flat

SRC = Path(__file__).resolve().parents[1] / "src" / "polyfold"

# np.argsort's float quicksort: one signature, compiled once per process and shared by the three
# sweeps that order boxes by their low end (ties in quicksort's order: the pairs they report and
# their order are the ones they always reported)
QUICKSORT_SWEEPS = {("collide/flat.py", "overlapping_pairs"), ("collide/sweep.py", "sweep_pairs"),
                    ("verify/paths.py", "_first_pair")}


def test_copy_flat_copies_the_first_elements_or_rows_in_c_order():
    rng = np.random.default_rng(3)
    src = rng.integers(0, 100, (7, 2))
    dst = np.full((12, 2), -1)
    copy_flat(dst, src, 2 * 5)
    assert np.array_equal(dst[:5], src[:5]) and (dst[5:] == -1).all()
    a, b = rng.random(9), np.zeros(9)
    copy_flat(b, a, 9)
    assert np.array_equal(a, b)
    copy_flat(b, np.ones(9), 0)
    assert np.array_equal(a, b)


def _constant(node: ast.expr) -> bool:
    """A literal, np.nan / np.inf, or either negated: a scalar, which numba fills in without
    comparing shapes."""
    if isinstance(node, ast.UnaryOp):
        node = node.operand
    return isinstance(node, ast.Constant) or (isinstance(node, ast.Attribute) and ast.unparse(node) in ("np.nan", "np.inf"))


def costly_constructs(root: Path) -> tuple[list[str], set[tuple[str, str]]]:
    """What the kernels (functions decorated with njit) under `root` do that costs a first run
    seconds of numba's compiling, and the kernels seen ((file, name))."""
    found, seen = [], set()
    for path in sorted(root.rglob("*.py")):
        for fn in ast.walk(ast.parse(path.read_text())):
            if not isinstance(fn, ast.FunctionDef) or not any("njit" in ast.unparse(d) for d in fn.decorator_list):
                continue
            name = (str(path.relative_to(root)), fn.name)
            seen.add(name)
            where = ":".join(name)
            for node in ast.walk(fn):
                if isinstance(node, ast.Assign):
                    for target in node.targets:
                        if isinstance(target, ast.Subscript):
                            index = target.slice.elts if isinstance(target.slice, ast.Tuple) else [target.slice]
                            if any(isinstance(i, ast.Slice) for i in index) and not _constant(node.value):
                                found.append(f"{where}: {ast.unparse(node)} (copy_flat or a loop)")
                if isinstance(node, ast.Call):
                    call = ast.unparse(node.func)
                    if call in ("np.unique", "np.sort", "sorted") or call.endswith(".sort"):
                        found.append(f"{where}: {call} (polyfold.sorting)")
                    if call == "np.argsort" and (name not in QUICKSORT_SWEEPS or node.keywords):
                        found.append(f"{where}: {ast.unparse(node)} (polyfold.sorting.stable_argsort)")
    return found, seen


def test_no_kernel_assigns_an_array_to_a_slice_or_calls_numbas_sorts():
    found, seen = costly_constructs(SRC)
    assert not found, found
    assert QUICKSORT_SWEEPS <= seen and len(seen) > 200  # the scan sees the kernels
