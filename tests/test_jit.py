"""polyfold/jit.py: kernels called from Python run ahead of time exactly where numba would type the
arguments as the exported ones, and just in time otherwise, with the same results."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest
from numba import types

from polyfold import jit
from polyfold.jit import Kernel, _fits, _spec_from_json, _spec_to_json, njit

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent


def _values() -> list:
    a = np.zeros((2, 3))
    readonly = np.zeros((2, 3))
    readonly.setflags(write=False)
    unaligned = np.frombuffer(np.zeros(7 * 8 + 1, dtype=np.uint8).data, dtype=np.float64, count=6, offset=1)
    return [a, a.T, a[:, ::2], readonly, unaligned.reshape(2, 3), np.zeros((2, 3), np.float32), np.zeros(6),
            np.zeros((1, 4)), np.zeros((0, 3)), np.zeros(3, dtype=np.int64), np.zeros(3, dtype=bool), 3, -(2 ** 63),
            2 ** 63, np.int64(3), np.int32(3), True, np.bool_(False), 1.5, np.float64(1.5), np.float32(1.5),
            (np.zeros(3), 2.0), (np.zeros(3), 2), [np.zeros(3), 2.0], (np.zeros(3),), (1, 2), (1, 2.0), None]


TYPES = [types.Array(types.float64, 2, "C"), types.Array(types.float64, 1, "C"), types.Array(types.int64, 1, "C"),
         types.Array(types.bool_, 1, "C"), types.int64, types.int32, types.float64, types.boolean, types.none,
         types.Tuple((types.Array(types.float64, 1, "C"), types.float64)), types.UniTuple(types.int64, 2)]


@pytest.mark.parametrize("numba_type", TYPES, ids=str)
def test_a_value_fits_an_exported_type_exactly_when_numba_types_it_so(numba_type):
    """The matcher against numba's own typeof, on arrays of every order, flag and dtype, Python
    and numpy scalars, tuples and lists."""
    spec = _spec_from_json(json.loads(json.dumps(_spec_to_json(numba_type))))
    for value in _values():
        assert _fits(spec, value) == (numba.typeof(value) == numba_type), (numba_type, value)


def test_a_subclass_of_ndarray_or_an_unsupported_type_stays_just_in_time():
    class Tagged(np.ndarray):
        pass

    spec = _spec_from_json(_spec_to_json(types.Array(types.float64, 1, "C")))
    assert not _fits(spec, np.zeros(3).view(Tagged))
    for unsupported in (types.Array(types.float64, 2, "F"), types.Array(types.float64, 1, "C", readonly=True),
                        types.Array(types.complex128, 1, "C"), types.complex128, types.unicode_type,
                        types.Tuple((types.float64, types.unicode_type))):
        assert _spec_to_json(unsupported) is None, unsupported


def test_kernels_run_just_in_time_without_ahead_code_and_call_kernels():
    from jit_kernels import _square, ratio, row_sums_of_squares

    assert isinstance(row_sums_of_squares, Kernel) and row_sums_of_squares.__name__ == "row_sums_of_squares"
    a = np.arange(6.0).reshape(2, 3)
    with jit.just_in_time():
        assert np.array_equal(row_sums_of_squares(a), (a * a).sum(axis=1))
        assert ratio(1.0, 0.0) == np.inf  # (error_model="numpy", as numba's own njit)
    assert row_sums_of_squares.jit_signatures() and _square.targetoptions["inline"] == "always"
    assert isinstance(row_sums_of_squares.dispatcher, numba.core.registry.CPUDispatcher)
    assert row_sums_of_squares.py_func(a).tolist() == (a * a).sum(axis=1).tolist()

    lazy = njit(lambda x: x + 1)  # numba's other spelling: the function given directly
    assert isinstance(lazy, Kernel) and lazy(1) == 2

    import pickle

    assert pickle.loads(pickle.dumps(row_sums_of_squares)) is row_sums_of_squares  # (by name)


_BUILD = r"""
import json, os, sys
from polyfold.jit import build_ahead, record_calls
import numpy as np
import jit_kernels as K
if os.environ.get("BUILD_NO_FORK"):  # (as where there is no fork: the modules one after another, here)
    import polyfold.processes
    polyfold.processes.can_fork = lambda: False
calls = record_calls()
K.row_sums_of_squares(np.arange(6.0).reshape(2, 3))
K.ratio(1.0, 2.0)
K.shifted((np.zeros(3), 0.5), 2, True)
K.first_negative(np.array([1.0, -1.0]))
print(json.dumps(build_ahead(calls, processes=int(os.environ.get("BUILD_PROCESSES", "1")))))
"""

_CALL = r"""
import json, sys
import numpy as np
import jit_kernels as K
from polyfold import jit
out = {"ready": jit.ahead_ready()}
out["sums"] = K.row_sums_of_squares(np.arange(6.0).reshape(2, 3)).tolist()
out["ratio"] = repr(K.ratio(1.0, 0.0))
a, flag = K.shifted((np.ones(2), 0.5), 4, False)
out["shifted"] = [a.tolist(), bool(flag)]
try:
    K.first_negative(np.ones(2))
except ValueError as exc:
    out["raised"] = str(exc)
out["numba"] = "numba" in sys.modules
out["other"] = K.row_sums_of_squares(np.ones((1, 2), dtype=np.float32)).tolist()  # not exported: numba
out["numba after"] = "numba" in sys.modules
print(json.dumps(out))
"""


def _python(code: str, cache: Path, **env: str) -> dict:
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                          env={**os.environ, "NUMBA_CACHE_DIR": str(cache), "PYTHONPATH": str(TESTS), **env})
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.splitlines()[-1])


@pytest.mark.parametrize("processes,fork", [(1, True), (2, True), (2, False)])
def test_built_ahead_a_fresh_process_calls_the_kernels_without_numba(tmp_path, processes, fork):
    """Recorded calls built into modules (a C compiler: pycc; two built at once by two processes,
    or one after another where there is no fork),
    then a process of its own: the same results as just in time (numpy's division by zero, a
    tuple in and out, an exception from compiled code) with numba never imported, until a call
    with other argument types needs it."""
    said = _python(_BUILD, tmp_path, POLYFOLD_AHEAD="off", BUILD_PROCESSES=str(processes),
                   BUILD_NO_FORK="" if fork else "1")
    assert said.startswith("4 calls of 4 kernels compiled"), said
    table = json.loads((tmp_path / jit.TABLE).read_text())
    assert len(table["modules"]) == processes and all((tmp_path / file).is_file() for _, file in table["modules"])
    assert set(table["kernels"]) == {
        f"jit_kernels.{k}" for k in ("row_sums_of_squares", "ratio", "shifted", "first_negative")}
    assert {m for rows in table["kernels"].values() for m, _, _ in rows} == set(range(processes))
    assert sorted(p.name for p in tmp_path.glob("polyfold_ahead_*")) == sorted(file for _, file in table["modules"])

    got = _python(_CALL, tmp_path)
    jit_got = _python(_CALL, tmp_path, POLYFOLD_AHEAD="off")
    assert got["ready"] and not jit_got["ready"]
    assert got["numba"] is False and got["numba after"] is True and jit_got["numba"] is True
    for key in ("sums", "ratio", "shifted", "raised", "other"):
        assert got[key] == jit_got[key], key
    assert got["ratio"] == "inf" and got["raised"] == "no negative entry" and got["sums"] == [5.0, 50.0]

    # a table whose stamp is not this code's (polyfold, numba or numpy changed since): not used
    table["stamp"] = "0" * 64
    (tmp_path / jit.TABLE).write_text(json.dumps(table))
    stale = _python(_CALL, tmp_path)
    assert not stale["ready"] and stale["numba"] is True and stale["sums"] == got["sums"]


_START = r"""
import json, os, sys
import numpy as np
import numba  # (as a first run's make has, from `apps.warmup.kernels_cached`)
from polyfold import jit
out = {"set up before": "numba.np.arraymath" in sys.modules}
jit.start_compiler()
out["set up after"] = "numba.np.arraymath" in sys.modules
read, write = os.pipe()
if os.fork() == 0:  # a forked process compiles a kernel with what it inherited
    import jit_kernels as K
    before = {m for m in sys.modules if m.startswith("numba.")}
    sums = K.row_sums_of_squares(np.arange(6.0).reshape(2, 3)).tolist()
    os.write(write, json.dumps({"sums": sums, "numba modules imported": sorted(
        m for m in sys.modules if m.startswith("numba.") and m not in before)}).encode())
    os._exit(0)
os.close(write)
out.update(json.loads(os.read(read, 1 << 16)))
os.wait()
print(json.dumps(out))
"""


def test_ahead_groups_split_the_calls_once_each_and_keep_a_kernel_with_the_kernels_it_calls():
    """Every call in exactly one group, none empty; a kernel called from Python and from another
    kernel goes into the module that has the other already (each module compiles what its calls
    reach), and the groups stay about equal."""
    import jit_kernels as K

    calls = [(K.row_sums_of_squares, ()), (K._square, ()), (K.ratio, ()), (K.shifted, ()), (K.first_negative, ())]
    assert jit.ahead_groups(calls, 1) == [[0, 1, 2, 3, 4]]
    for n in (2, 3, 10):
        groups = jit.ahead_groups(calls, n)
        assert sorted(i for g in groups for i in g) == list(range(5)) and all(groups) and len(groups) <= n
        assert len(groups) == min(n, 4)  # (_square rides with row_sums_of_squares: four groups at most)
        assert next(g for g in groups if 0 in g) == next(g for g in groups if 1 in g)


def test_start_compiler_sets_numba_up_once_for_forked_processes_and_caches_nothing(tmp_path):
    """`start_compiler` does numba's one-time set-up here (its registries of array functions
    loaded), caching nothing: a process forked after it compiles a kernel into the cache without
    importing any more of numba (forked after a bare `import numba`, it imports its array
    functions, ufuncs and more: about 70 modules)."""
    got = _python(_START, tmp_path, POLYFOLD_AHEAD="off")
    assert not got["set up before"] and got["set up after"]
    assert got["sums"] == [5.0, 50.0] and got["numba modules imported"] == []
    cached = {p.name.split(".")[0] for p in tmp_path.rglob("*.nbi")}
    assert cached == {"jit_kernels"}, cached  # (the child's kernel; nothing of start_compiler's)


def test_the_stamp_holds_the_cpu(monkeypatch):
    """Code built for this CPU (its instruction set) is stale on another: the stamp says which."""
    here = jit.stamp()
    monkeypatch.setattr(jit, "_cpu", lambda: "model name : another\nflags : fpu sse2")
    assert jit.stamp() != here
    monkeypatch.setattr(jit, "_cpu", lambda: "")  # (no /proc/cpuinfo: built for the CPU family)
    assert jit.stamp() != here


def test_without_a_c_compiler_nothing_is_built_and_nothing_breaks(tmp_path):
    """pycc links with the system's C compiler: where there is none (CC and LDSHARED pointing at a
    program that fails), build_ahead says so in one line and leaves no table (kernels stay just in
    time)."""
    said = _python(_BUILD, tmp_path, POLYFOLD_AHEAD="off", CC="/bin/false", LDSHARED="/bin/false")
    assert said.startswith("not built: ") and "\n" not in said, said
    assert not (tmp_path / jit.TABLE).exists() and not list(tmp_path.glob("polyfold_ahead_*"))
    assert not list(tmp_path.glob("polyfold-ahead-*"))  # (its build folder removed)


def test_a_missing_or_foreign_table_means_just_in_time(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert jit._load_table() == {}  # none
    (tmp_path / jit.TABLE).write_text("{not json")
    assert jit._load_table() == {}
    (tmp_path / jit.TABLE).write_text(json.dumps({"stamp": jit.stamp(), "modules": [["polyfold_ahead_x", "gone.so"]],
                                                  "kernels": {}}))
    assert jit._load_table() == {}  # its module is gone
    (tmp_path / jit.TABLE).write_text(json.dumps({"stamp": jit.stamp(), "module": "polyfold_ahead_x",
                                                  "file": "gone.so", "kernels": {}}))
    assert jit._load_table() == {}  # an older table (one module)
    monkeypatch.setenv(jit.SWITCH, "off")
    assert jit._load_table() == {}


_PROBE = r"""
import atexit, sys
atexit.register(lambda: print("numba imported" if "numba" in sys.modules else "no numba"))
from polyfold.apps.cli import main
sys.argv = ["polyfold"] + sys.argv[1:]
main()
"""


def test_make_ahead_of_time_writes_what_it_writes_just_in_time(tmp_path):
    """After `polyfold warm-up` (make setup) the bunny's make calls every kernel ahead of time and
    imports no numba, and writes the same files, byte for byte, as with POLYFOLD_AHEAD=off (but
    report.json's timings and the DXFs' creation stamps)."""
    if not jit.ahead_ready():
        pytest.skip("no ahead-of-time kernels for this code: `polyfold warm-up` builds them (make setup does)")
    bunny = ROOT / "examples" / "bunny-128.obj"
    outs = {}
    for switch in ("on", "off"):
        out = tmp_path / switch
        proc = subprocess.run([sys.executable, "-c", _PROBE, "make", str(bunny), "-o", str(out), "-q"],
                              capture_output=True, text=True, timeout=600,
                              env={**os.environ, jit.SWITCH: switch, "POLYFOLD_SERVER": "off"})
        assert proc.returncode == 0, proc.stderr[-3000:]
        outs[switch] = (out, proc.stdout.strip().splitlines()[-1])
    assert outs["on"][1] == "no numba" and outs["off"][1] == "numba imported"
    names = sorted(p.name for p in outs["on"][0].iterdir())
    assert names == sorted(p.name for p in outs["off"][0].iterdir()) and len(names) > 10
    for name in names:
        if name != "report.json" and not name.endswith(".dxf"):
            assert (outs["on"][0] / name).read_bytes() == (outs["off"][0] / name).read_bytes(), name


def test_a_kernels_cached_code_is_stale_when_a_module_it_imports_changes(tmp_path):
    """numba keeps a kernel's machine code (its callees' code in it) fresh by its own file's stamp;
    polyfold's kernels also by the stamps of the modules of their package they import, so a callee
    changed in another file is not run from the caller's old code (a stale cache once made the
    segmenter fail to load a moved module)."""
    pkg = tmp_path / "stampkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    callee = pkg / "callee.py"
    callee.write_text("from polyfold.jit import njit\n\n\n@njit(cache=True)\ndef step(x):\n    return x + 1\n")
    (pkg / "caller.py").write_text("from polyfold.jit import njit\n\nfrom .callee import step\n\n\n"
                                   "@njit(cache=True)\ndef twice(x):\n    return 2 * step(x)\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"), jit.SWITCH: "off",
           "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}
    probe = "import stampkg.caller as c; print(c.twice(1), sum(c.twice.stats.cache_hits.values()))"

    def run() -> list[str]:
        proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, timeout=300)
        assert proc.returncode == 0, proc.stderr[-2000:]
        return proc.stdout.split()

    assert run()[0] == "4"
    assert run() == ["4", "1"]  # from the cache
    callee.write_text(callee.read_text().replace("x + 1", "x + 10"))
    assert run() == ["22", "0"]  # compiled again, not the cached 4
