"""polyfold's numba kernels, called from Python without numba where they were compiled ahead of
time: `njit`, the decorator every kernel module uses in place of numba's, and `build_ahead`, which
`polyfold warm-up` runs.

Why: before a warm process runs its first kernel, numba costs it about 0.4 s: importing numba
(0.14 s), its target's registries on the first call (which import scipy.linalg, 0.09 s) and
loading each kernel from numba's cache (3-9 ms each; a bunny's make calls 35). `build_ahead`
compiles the kernels polyfold's Python calls, for the argument types the warm-up gave them, into
extension modules (numba's `pycc`, machine code for this CPU: its model and instruction set are
in the stamp; one per core, built at once); a process with them calls the kernels without
importing numba at all.

Each exported function is a wrapper that calls the kernel's own numba dispatcher, so the kernel is
compiled as numba's just-in-time compiler compiles it: its options (`error_model`, `inline`), its
typing, the same machine-independent optimisation. Called from Python, a `Kernel` takes the
ahead-of-time function whose argument types match its arguments exactly (a numpy array's dtype,
dimensions, C order and writeable; int64 as Python int or np.int64, float64 as float or
np.float64, bool as bool or np.bool_, None; tuples of these), and numba's dispatcher otherwise, made at
the first need, from numba's cache, as before. So do all kernels when the modules are missing,
stale (its stamp: the sizes and modification times of polyfold's sources and of numba's and
numpy's installs, and the CPU) or switched off (POLYFOLD_AHEAD=off). Inside other kernels numba
types a Kernel as its dispatcher (`_typeof_kernel`), so kernels call kernels as before.

The modules and their table live where numba keeps its cache: $NUMBA_CACHE_DIR when set, else the
package's `__pycache__`. It needs a C compiler to build (pycc links with the system's); without
one `build_ahead` says so and every kernel stays just-in-time.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

SWITCH = "POLYFOLD_AHEAD"  # "off": never call ahead-of-time code (the build itself, tests)
TABLE = "polyfold_ahead.json"  # beside the modules: {"stamp", "modules": [[module, file]], "kernels": {name: [[module index, export, specs]]}}

# numba's scalar type names -> (the numpy scalar type, the Python type numba gives the same type)
_SCALARS: dict[str, tuple[type, ...]] = {
    "int64": (np.int64, int), "float64": (np.float64, float), "bool": (np.bool_, bool),
    "int32": (np.int32,), "int16": (np.int16,), "int8": (np.int8,), "uint64": (np.uint64,),
    "uint32": (np.uint32,), "uint16": (np.uint16,), "uint8": (np.uint8,), "float32": (np.float32,),
    "none": (type(None),),  # (an optional argument left out)
}
_INT64 = 2 ** 63
_ARRAY_DTYPES = ("bool", "int8", "int16", "int32", "int64", "uint8", "uint16", "uint32", "uint64",
                 "float32", "float64")


class Kernel:
    """A numba kernel: `py_func` with `numba.njit`'s options (`targetoptions`). Called from Python
    it runs the ahead-of-time function whose argument types match (see the module docstring),
    else numba's dispatcher (`dispatcher`, made at the first need). Other attributes are the
    dispatcher's (`signatures`, `overloads`, ...: numba is imported for them)."""

    def __init__(self, py_func: Callable, options: dict[str, Any]) -> None:
        self.py_func = py_func
        self.targetoptions = {"nopython": True, **options}  # (as numba's: the inliner reads it)
        self._dispatcher = None
        self._ahead: tuple[tuple[tuple, Callable], ...] | None = None  # None: not looked up yet
        for name in ("__module__", "__name__", "__qualname__", "__doc__"):
            setattr(self, name, getattr(py_func, name, None))
        self.__wrapped__ = py_func

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        ahead = self._ahead
        if ahead is None:
            ahead = self._ahead = _ahead_functions(self)
        if ahead and not kwargs and not _only_jit:
            for specs, fn in ahead:
                if len(specs) == len(args) and all(map(_fits, specs, args)):
                    return fn(*args)
        if _recorded is not None:
            _record(self, args, kwargs)
        return self.dispatcher(*args, **kwargs)

    @property
    def dispatcher(self) -> Any:
        """numba's dispatcher of py_func (numba imported, and its cache read, at the first need)."""
        if self._dispatcher is None:
            with _lock:
                if self._dispatcher is None:
                    import numba

                    _prepare_numba()
                    dispatcher = numba.njit(**{k: v for k, v in self.targetoptions.items()
                                               if k != "nopython"})(self.py_func)
                    _stamp_with_imports(dispatcher, self.py_func.__module__)
                    self._dispatcher = dispatcher
        return self._dispatcher

    def jit_signatures(self) -> list:
        """The argument types numba's dispatcher holds compiled in this process (none before it is
        made: a kernel only ever called ahead of time has none)."""
        return [] if self._dispatcher is None else list(self._dispatcher.signatures)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__") or name in ("_dispatcher", "_ahead", "py_func", "targetoptions"):
            raise AttributeError(name)  # (not yet set, or a protocol numba's dispatcher has no say in)
        return getattr(self.dispatcher, name)

    def __repr__(self) -> str:
        return f"<polyfold kernel {self.__module__}.{self.__qualname__}>"

    def __reduce__(self) -> tuple:
        # by name, as a function pickles (its dispatcher and ahead-of-time functions stay here)
        return _kernel_named, (self.py_func.__module__, self.py_func.__qualname__)


def _stamp_with_imports(dispatcher: Any, module: str) -> None:
    """Make the freshness stamp of a dispatcher's numba cache cover the polyfold modules its module
    imports, transitively, not only its own file (numba's rule). A kernel's cached machine code
    holds its callees' code and refers to their modules by name: with numba's rule, a callee
    changed or moved to another file (a `git pull`, an edit) left the caller's stale code in the
    cache, which then ran the old callee or failed to load its gone module."""
    cache_file = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    if cache_file is not None and hasattr(cache_file, "_source_stamp"):
        cache_file._source_stamp = (cache_file._source_stamp, _imports_stamp(module))


_import_stamps: dict[str, tuple] = {}
_IMPORT_LINE = None  # (compiled at the first need)


def _imports_stamp(module: str) -> tuple:
    """((module, mtime, size), ...) of `module` and of the modules of its top-level package (polyfold
    for polyfold's kernels) it imports, at its top level or in its functions, transitively, sorted.
    Not this module's: it compiles no kernel code."""
    global _IMPORT_LINE
    if module in _import_stamps:
        return _import_stamps[module]
    import re

    if _IMPORT_LINE is None:
        _IMPORT_LINE = re.compile(r"^[ \t]*(?:from[ \t]+(\.*)([\w.]*)[ \t]+import[ \t]+\(?([\w, \t]*)|import[ \t]+([\w.]+))",
                                  re.MULTILINE)
    top = module.split(".")[0]
    top_file = getattr(sys.modules.get(top), "__file__", None)
    if not top_file or not top_file.endswith("__init__.py"):
        return ()  # (a module of its own, no package: numba's stamp of its file is all)
    root = Path(top_file).resolve().parent  # (the package's modules' files, read, not imported)
    seen: dict[str, tuple] = {}
    todo = [module]
    while todo:
        name = todo.pop()
        if name in seen or name.split(".")[0] != top or name == __name__:
            continue
        folder = root.joinpath(*name.split(".")[1:])
        path = folder / "__init__.py" if folder.is_dir() else folder.with_suffix(".py")
        if not path.is_file():
            seen[name] = ()  # (a name imported from a module, not a module)
            continue
        st = path.stat()
        seen[name] = (name, st.st_mtime_ns, st.st_size)
        package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        for dots, base, names, plain in _IMPORT_LINE.findall(path.read_text(encoding="utf-8")):
            if plain:
                todo.append(plain)
                continue
            if dots:
                base = ".".join(package[:len(package) - len(dots) + 1] + ([base] if base else []))
            todo.append(base)
            todo += [f"{base}.{n.strip()}" for n in names.split(",") if n.strip()]  # (submodules imported by name)
    _import_stamps[module] = tuple(sorted(v for v in seen.values() if v))
    return _import_stamps[module]


def _kernel_named(module: str, qualname: str) -> Kernel:
    import importlib

    return getattr(importlib.import_module(module), qualname)


def njit(fn: Callable | None = None, **options: Any) -> Any:
    """`numba.njit` for polyfold's kernels: `@njit(cache=True)` or `njit(cache=True)(fn)` gives a
    Kernel (numba is not imported until a kernel needs its just-in-time compiler)."""
    if fn is not None:
        return Kernel(fn, options)
    return lambda f: Kernel(f, options)


_lock = threading.RLock()
_numba_ready = False
_only_jit = 0  # >0 inside `just_in_time`


@contextmanager
def just_in_time() -> Iterator[None]:
    """Kernels called inside run just in time, whatever is built ahead: for the warm-up, which
    fills numba's cache, and a server, which keeps both loaded."""
    global _only_jit
    with _lock:
        _only_jit += 1
    try:
        yield
    finally:
        with _lock:
            _only_jit -= 1


def _prepare_numba() -> None:
    """Once numba is needed: numba types a Kernel (a global of another kernel) as its dispatcher,
    and the deadline clock starts counting numba's compiling."""
    global _numba_ready
    if _numba_ready:
        return
    from numba.extending import typeof_impl

    from .deadline import watch_compiles

    @typeof_impl.register(Kernel)
    def _typeof_kernel(val: Kernel, c: Any) -> Any:
        return typeof_impl(val.dispatcher, c)

    watch_compiles()
    _numba_ready = True


def start_compiler() -> None:
    """numba's one-time set-up in this process, done now: before forking processes that will
    compile (a first run's `apps.warmup.Beside`), which then inherit it instead of each doing it
    again. What numba does once per process, at its first compile, costs each process 1-1.5 s
    (its LLVM target, the registries of its typing and lowering: some 70 modules, the runtime
    that allocates arrays); a throwaway kernel that makes an array (never cached) gets it done in
    0.3 s, which this process would spend at its own first compile anyway. Measured on 2 cores: the
    sections `Beside` runs took 17.5-18.1 s forked after it, 19.2-19.7 s without; a bare `pip
    install`'s first make of the bunny 16.6-18.0 s against 18.1-18.5 s (four rounds alternating)."""
    import numba

    _prepare_numba()

    @numba.njit(cache=False)
    def _first(a):
        b = np.empty(a.shape[0])
        b[0] = a[0]
        return b[0]

    _first(np.zeros(1))


# ------------------------------------------------------------------ calling ahead-of-time code

def _fits(spec: Any, value: Any) -> bool:
    """Whether numba would type `value` as `spec`: an array (dtype, ndim), a scalar (the frozenset
    of classes it may be), a tuple (a list of specs)."""
    kind = spec.__class__
    if kind is frozenset:
        cls = value.__class__
        return cls in spec and (cls is not int or -_INT64 <= value < _INT64)  # (numba: uint64 beyond)
    if kind is tuple:
        if value.__class__ is not np.ndarray or value.ndim != spec[1] or value.dtype != spec[0]:
            return False
        flags = value.flags  # (numba's typeof ignores alignment: so does this)
        return flags.c_contiguous and flags.writeable
    return value.__class__ is tuple and len(value) == len(spec) and all(map(_fits, spec, value))


def _spec_from_json(item: list) -> Any:
    if item[0] == "array":
        return (np.dtype(item[1]), int(item[2]))
    if item[0] == "scalar":
        return frozenset(_SCALARS[item[1]])
    return [_spec_from_json(x) for x in item[1]]


_table: dict[str, tuple[tuple[tuple, Callable], ...]] | None = None


def _loaded_table() -> dict[str, tuple[tuple[tuple, Callable], ...]]:
    global _table
    if _table is None:
        with _lock:
            if _table is None:
                _table = _load_table()
    return _table


def _ahead_functions(kernel: Kernel) -> tuple[tuple[tuple, Callable], ...]:
    """The (argument specs, function) pairs built ahead of time for `kernel`; () when none."""
    return _loaded_table().get(f"{kernel.py_func.__module__}.{kernel.py_func.__qualname__}", ())


def ahead_dir() -> Path:
    """Where the ahead-of-time module and its table are: numba's cache folder."""
    cache = os.environ.get("NUMBA_CACHE_DIR")
    return Path(cache) if cache else Path(__file__).resolve().parent / "__pycache__"


def stamp() -> str:
    """What the ahead-of-time code is built from, as a digest: this Python, numpy's and numba's
    installs (their __init__'s size and modification time) and polyfold's sources (`sources`)."""
    import importlib.util

    from .sources import hash_sources

    h = hashlib.sha256(f"{sys.version}\n{np.__version__}\n{_cpu() or 'generic'}\n".encode())
    spec = importlib.util.find_spec("numba")
    for origin in (spec.origin if spec else None, np.__file__):
        st = os.stat(origin) if origin else None
        h.update(f"{origin}:{st.st_size}:{st.st_mtime_ns}\n".encode() if st else b"-\n")
    hash_sources(h)
    return h.hexdigest()


# the lines of /proc/cpuinfo that say which instructions a CPU has (x86, then ARM); not its clock
_CPU_KEYS = ("vendor_id", "cpu family", "model", "model name", "stepping", "flags", "Features", "CPU implementer",
             "CPU architecture", "CPU variant", "CPU part", "CPU revision")


def _cpu() -> str:
    """This machine's CPU, for code built for it alone (LLVM's "host"): the model and instruction
    set lines of /proc/cpuinfo's first processor; "" where there is none (the code is then built
    for the CPU family). In the stamp: a folder moved to another CPU runs just in time, never
    code with instructions that CPU lacks."""
    try:
        with open("/proc/cpuinfo") as f:
            first = f.read().split("\n\n", 1)[0]
    except OSError:
        return ""
    keep = [line for line in first.splitlines() if line.split(":", 1)[0].strip() in _CPU_KEYS]
    return "\n".join(keep)


def ahead_ready() -> bool:
    """Whether this process calls kernels ahead of time (a fresh module is built and not switched off)."""
    return bool(_loaded_table())


def _load_table() -> dict[str, tuple[tuple[tuple, Callable], ...]]:
    """The table of ahead-of-time functions by kernel name; {} when off, missing or stale."""
    if os.environ.get(SWITCH, "").lower() == "off":
        return {}
    folder = ahead_dir()
    try:
        table = json.loads((folder / TABLE).read_text())
        if table.get("stamp") != stamp():
            return {}
        modules = [_load_module(module, folder / file) for module, file in table["modules"]]
        return {name: tuple((tuple(_spec_from_json(s) for s in specs), getattr(modules[m], export))
                            for m, export, specs in rows)
                for name, rows in table["kernels"].items()}
    except (OSError, ValueError, KeyError, IndexError, ImportError, AttributeError, TypeError):
        return {}  # (none built, or not by this code: the kernels run just in time)


def _load_module(name: str, path: Path) -> Any:
    import importlib.machinery
    import importlib.util

    if name in sys.modules:
        return sys.modules[name]
    loader = importlib.machinery.ExtensionFileLoader(name, str(path))
    spec = importlib.util.spec_from_file_location(name, str(path), loader=loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    sys.modules[name] = module
    return module


# ------------------------------------------------------------------ building ahead-of-time code

_recorded: dict[Kernel, set[tuple]] | None = None


def _record(kernel: Kernel, args: tuple, kwargs: dict) -> None:
    import numba

    if kwargs:
        return  # (exported functions take positional arguments only)
    try:
        types = tuple(numba.typeof(a) for a in args)
    except Exception:  # (numba raises its own for values it cannot type: the call says so)
        return
    _recorded.setdefault(kernel, set()).add(types)


def record_calls() -> dict[Kernel, set[tuple]]:
    """Start recording, in this process, the argument types of every kernel called from Python just
    in time; the dict filled (give it to `build_ahead`)."""
    global _recorded
    _recorded = {}
    return _recorded


def _spec_to_json(t: Any) -> list | None:
    """A numba type as a table spec; None for types the table does not match (they stay just in time)."""
    from numba.core import types

    if isinstance(t, types.Array):
        if t.layout == "C" and t.mutable and t.aligned and str(t.dtype) in _ARRAY_DTYPES and t.ndim > 0:
            return ["array", str(t.dtype), t.ndim]
        return None
    if isinstance(t, (types.Integer, types.Float, types.Boolean, types.NoneType)) and str(t) in _SCALARS:
        return ["scalar", str(t)]
    if isinstance(t, (types.UniTuple, types.Tuple)) and not isinstance(t, types.BaseNamedTuple):
        items = [_spec_to_json(x) for x in t.types]
        return None if any(x is None for x in items) else ["tuple", items]
    return None


def build_ahead(calls: dict[Kernel, set[tuple]], processes: int = 1) -> str:
    """Compile the kernels of `calls` (`record_calls`), for the argument types recorded, into
    ahead-of-time modules and write their table (each to a temporary name, then renamed; older
    modules removed). processes: how many modules, each built in a process of its own at the same
    time (`ahead_groups`: pycc compiles a module in one thread). Returns a one-line account (what
    was built, or why nothing was)."""
    import shutil
    import tempfile

    exports = []
    for kernel in sorted(calls, key=lambda k: (k.py_func.__module__, k.py_func.__qualname__)):
        for types in sorted(calls[kernel], key=str):
            specs = [_spec_to_json(t) for t in types]
            if not any(s is None for s in specs):
                exports.append((f"k{len(exports)}", kernel, types, specs))
    if not exports:
        return "not built: no kernel was called"
    folder = ahead_dir()
    folder.mkdir(parents=True, exist_ok=True)
    digest = stamp()
    groups = ahead_groups([(kernel, types) for _, kernel, types, _ in exports], processes)
    modules = [f"polyfold_ahead_{digest[:16]}_{i}" for i in range(len(groups))]
    build = Path(tempfile.mkdtemp(prefix="polyfold-ahead-", dir=folder))
    try:
        files = _build_modules(modules, [[exports[i][:3] for i in group] for group in groups], build)
        if isinstance(files, str):
            return files
        keep = set(files)
        for old in folder.glob("polyfold_ahead_*"):
            if old.is_file() and old.name not in keep:  # (the same names: replaced below)
                old.unlink()
        for file in files:
            os.replace(build / file, folder / file)
    finally:
        shutil.rmtree(build, ignore_errors=True)
    rows: dict[str, list] = {}
    for m, group in enumerate(groups):
        for i in group:
            export, kernel, _, specs = exports[i]
            rows.setdefault(f"{kernel.py_func.__module__}.{kernel.py_func.__qualname__}", []).append([m, export, specs])
    table = {"stamp": digest, "modules": [[m, f] for m, f in zip(modules, files)], "kernels": rows}
    tmp = folder / f".{TABLE}.{os.getpid()}"
    tmp.write_text(json.dumps(table, indent=0))
    os.replace(tmp, folder / TABLE)
    where = f"{folder / files[0]}" if len(files) == 1 else f"{len(files)} modules in {folder} (built at once)"
    return f"{len(exports)} calls of {len(rows)} kernels compiled, {where}"


def _build_modules(modules: list[str], exports: list[list[tuple]], build: Path) -> list[str] | str:
    """Each module of `modules` compiled from its (export name, kernel, argument types) into
    `build`, the first here and each other in a process forked from this one at the same time
    (one after another here where there is no fork); the modules' file names, or the one-line
    account of the first failure."""
    from .processes import Forked, can_fork

    forked = len(modules) > 1 and can_fork()
    children = []
    for module, group in zip(modules[1:], exports[1:]) if forked else ():
        read, write = os.pipe()

        def child(module=module, group=group, write=write) -> None:
            os.write(write, _build_module(module, group, build).encode())

        children.append((Forked(child), read, write))
    files = [_build_module(module, group, build) for module, group in zip(modules[:1] if forked else modules, exports)]
    for proc, read, write in children:
        os.close(write)
        proc.wait()
        with os.fdopen(read, "rb") as said:
            files.append(said.read().decode() or f"not built: its process ended with {proc.returncode}")
    failed = [said for said in files if said.startswith("not built")]
    return failed[0] if failed else files


def _build_module(module: str, exports: list[tuple], build: Path) -> str:
    """One ahead-of-time module compiled into `build` (numba's pycc, then the C compiler): its
    file's name, or "not built: ..." (no pycc in this numba, no C compiler or no Python headers)."""
    import warnings

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # (pycc is pending deprecation: numba says so on import)
            from numba.pycc import CC  # (a numba without pycc: ImportError, said below)

            cc = CC(module)  # (its toolchain: no C compiler raises here already)
            cc.output_dir = str(build)
            cc.target_cpu = "host" if _cpu() else ""  # (this CPU's instructions where the stamp can tell it)
            for export, kernel, types in exports:
                dispatcher = kernel.dispatcher
                dispatcher.compile(types)
                returns = dispatcher.overloads[types].signature.return_type
                cc.export(export, returns(*types))(_calling(dispatcher, len(types)))
            cc.compile()
    except Exception as exc:  # (no pycc, C compiler or Python headers: numba's and distutils' errors, each its own class)
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        return f"not built: {type(exc).__name__}" + (f": {first}" if first else "")
    return cc.output_file


def ahead_groups(calls: list[tuple[Kernel, tuple]], n: int) -> list[list[int]]:
    """`calls` (kernel, argument types) split into at most n groups of about equal compiling, each
    built as a module of its own: a kernel is compiled into every module that calls it, itself or
    from another kernel, so a call goes where the kernels it reaches add the least (their sources'
    length as the measure), the largest first. Indices into calls, each group in their order;
    empty groups left out. (The twenty-ninth session's 77 calls: built in two modules at once,
    21.0 s against 41.6 s in one; every second call to each, 24.8 s; by package, 20.9-32.8 s.)"""
    import inspect

    sizes: dict[Kernel, int] = {}

    def size(kernel: Kernel) -> int:
        if kernel not in sizes:
            try:
                sizes[kernel] = len(inspect.getsource(kernel.py_func))
            except (OSError, TypeError):
                sizes[kernel] = 1
        return sizes[kernel]

    def reached(kernel: Kernel, seen: set[Kernel]) -> set[Kernel]:
        seen.add(kernel)
        code = kernel.py_func.__code__
        for name in code.co_names:
            other = kernel.py_func.__globals__.get(name)
            if isinstance(other, Kernel) and other not in seen:
                reached(other, seen)
        return seen

    reach = [reached(kernel, set()) for kernel, _ in calls]
    bins: list[set[Kernel]] = [set() for _ in range(max(1, n))]
    groups: list[list[int]] = [[] for _ in bins]
    for i in sorted(range(len(calls)), key=lambda i: -sum(map(size, reach[i]))):
        totals = [sum(map(size, b)) for b in bins]
        grown = [sum(map(size, b | reach[i])) for b in bins]
        # the bin whose largest total stays least; of equals, the one this call adds least to
        j = min(range(len(bins)), key=lambda j: (max([grown[j], *(t for k, t in enumerate(totals) if k != j)]),
                                                 grown[j] - totals[j], grown[j]))
        bins[j] |= reach[i]
        groups[j].append(i)
    return [sorted(g) for g in groups if g]


def _calling(dispatcher: Any, n: int) -> Callable:
    """def call(a0, .., an-1): return dispatcher(a0, .., an-1), for pycc to export: the kernel
    itself is compiled by its own dispatcher (its options and typing), as just in time."""
    params = ", ".join(f"a{i}" for i in range(n))
    namespace = {"kernel": dispatcher}
    exec(f"def call({params}):\n    return kernel({params})\n", namespace)
    return namespace["call"]
