"""The package's compiled kernels: ahead of time when the extension is up to date,
numba's JIT otherwise.

Every kernel (a loop over arrays, in numba's subset of Python) is decorated
with :func:`kernel`. When the extension built by :mod:`moveability.compiled.build`
is present and was compiled from the sources installed now, a kernel that
Python code calls binds its ahead-of-time (AOT) compiled variants and numba is
never imported: a process saves numba's import, its initialisation and the
loading of each cached kernel (0.5 to 0.7 s). Otherwise every kernel is
``numba.njit(cache=True, nogil=True)`` of the function, as it always was.
(The AOT variants hold the GIL: the package calls no kernel from threads.)

The extension embeds a manifest: the SHA-256 of every source file its code
comes from (the build script included) and of numba's version file, numpy's
version, the CPU it was compiled for, and the argument types of each compiled
variant. At import each listed file is hashed again; any difference, or no
extension, selects the JIT for every kernel (``MOVEABILITY_KERNELS_LOG=1``
says which and why on stderr). A call whose arguments are not of one variant's
types (the types numba infers for them: dtype, dimensions, an array the kernel
writes writeable and C-contiguous, scalars of the Python or numpy type) goes
to the JIT kernel instead, compiled on first use: correct, only slower. (An
array the kernel only reads and that is not contiguous is copied: the same
values.) ``MOVEABILITY_KERNELS=jit`` selects the JIT whatever the extension.

Examples
--------
>>> from moveability.intervals import next_below
>>> MODE in ("aot", "jit") and next_below(1.0) < 1.0
True
"""

from __future__ import annotations

import functools
import hashlib
import importlib
import importlib.util
import json
import marshal
import os
import sys
import types
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar, overload

import numpy as np

__all__ = [
    "CALLS",
    "EXTENSION",
    "FORMAT",
    "KERNELS",
    "MODE",
    "PACKAGE_DIR",
    "REASON",
    "cpu_id",
    "environment",
    "jit_of",
    "kernel",
    "manifest_problem",
    "source_hashes",
    "wrapper_filename",
    "wrapper_source",
    "write_calls",
]

F = TypeVar("F", bound=Callable[..., Any])

#: the package directory: the manifest's source paths are relative to it
PACKAGE_DIR = Path(__file__).resolve().parent.parent
#: the extension module, beside this file
EXTENSION = f"{__name__}._aot"
#: version of the manifest's layout
FORMAT = 1
#: ``jit``: never load the extension
ENV_MODE = "MOVEABILITY_KERNELS"
#: ``1``: say on stderr which kernels run how (once each)
ENV_LOG = "MOVEABILITY_KERNELS_LOG"

#: "module.qualname" -> the kernel (a numba dispatcher in JIT mode): what the build compiles
KERNELS: dict[str, Any] = {}


def _log(message: str) -> None:
    if os.environ.get(ENV_LOG, "") not in ("", "0"):
        print(f"moveability: {message}", file=sys.stderr)


def source_hashes(paths: Sequence[str]) -> dict[str, str]:
    """SHA-256 of each file, by its path relative to the package directory (an
    absent file hashes as ``"missing"``)."""
    out = {}
    for rel in paths:
        try:
            out[rel] = hashlib.sha256((PACKAGE_DIR / rel).read_bytes()).hexdigest()
        except OSError:
            out[rel] = "missing"
    return out


def environment() -> dict[str, str]:
    """What else the compiled code depends on: numba (the hash of its version file,
    found without importing it), numpy's version and the interpreter."""
    spec = importlib.util.find_spec("numba")
    numba_id = "missing"
    if spec is not None and spec.origin is not None:
        try:
            numba_id = hashlib.sha256(
                (Path(spec.origin).parent / "_version.py").read_bytes()
            ).hexdigest()
        except OSError:
            pass
    return {"numba": numba_id, "numpy": np.__version__, "python": sys.implementation.cache_tag}


#: the lines of /proc/cpuinfo that say which instructions the CPU runs
_CPU_KEYS = frozenset(
    ("vendor_id", "cpu family", "model", "model name", "flags", "Features", "CPU implementer")
) | frozenset(("CPU architecture", "CPU variant", "CPU part"))


def cpu_id() -> str:
    """The CPU's identity (a hash of its model and instruction sets, read from the
    first processor of /proc/cpuinfo), or ``""`` where that file cannot be read:
    the extension compiled for this CPU runs on an identical one only."""
    lines = []
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            for line in f:
                if not line.strip():
                    break
                key, _, value = line.partition(":")
                if key.strip() in _CPU_KEYS:
                    lines.append(f"{key.strip()}: {value.strip()}")
    except OSError:
        return ""
    return hashlib.sha256("\n".join(lines).encode()).hexdigest() if lines else ""


def manifest_problem(manifest: dict[str, Any]) -> str | None:
    """Why the extension with this manifest must not be used (None: it is up to
    date with the sources and the environment).

    Examples
    --------
    >>> manifest_problem({"format": FORMAT, "sources": {"intervals.py": "0" * 64}})
    'intervals.py changed since the extension was built'
    """
    if manifest.get("format") != FORMAT:
        return f"manifest format {manifest.get('format')!r}, not {FORMAT}"
    built = manifest.get("sources", {})
    for rel, digest in source_hashes(sorted(built)).items():
        if digest != built[rel]:
            return f"{rel} changed since the extension was built"
    for key, value in environment().items():
        if manifest.get(key) != value:
            return f"{key} changed since the extension was built"
    if manifest.get("cpu") not in ("generic", cpu_id()):
        return "compiled for another CPU"
    return None


def _load() -> tuple[Any, dict[str, Any] | None, str]:
    """The extension and its manifest when they can be used, and why (not)."""
    if os.environ.get(ENV_MODE, "") == "jit":
        return None, None, f"{ENV_MODE}=jit"
    try:
        ext = importlib.import_module(EXTENSION)
    except ImportError as exc:
        return None, None, f"no extension ({exc})"
    try:
        manifest = json.loads(ext.manifest())
    except Exception as exc:  # a broken extension: the JIT still works
        return None, None, f"unreadable manifest ({exc!r})"
    problem = manifest_problem(manifest)
    if problem is not None:
        return None, None, problem
    return ext, manifest, "the extension is up to date"


_EXT, _MANIFEST, REASON = _load()
#: "aot" (the extension's kernels, JIT for other types) or "jit" (numba alone)
MODE = "jit" if _EXT is None else "aot"
_log(f"kernels: {MODE} ({REASON})")


# ------------------------------------------------------------------ JIT mode
def _njit(fn: Callable[..., Any], inline: bool) -> Any:
    """``numba.njit(cache=True, nogil=True)`` of ``fn``, with ``inline="always"``
    when ``inline``: numba imported at the first kernel, as the modules did."""
    from numba import njit

    if inline:
        return njit(cache=True, nogil=True, inline="always")(fn)
    return njit(cache=True, nogil=True)(fn)


# ------------------------------------------------------------------ AOT mode
class _Kernel:
    """What an AOT-mode kernel carries: its function, its compiled variants and,
    once needed, its JIT dispatcher."""

    def __init__(self, fn: Callable[..., Any], inline: bool, variants: list[Any]) -> None:
        self.fn = fn
        self.inline = inline
        self.variants = variants
        self.dispatcher: Any = None
        self.logged = False


def _names(code: types.CodeType) -> set[str]:
    """The global names a function's code (and its nested code) refers to."""
    out = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            out |= _names(const)
    return out


def _dispatcher(info: _Kernel) -> Any:
    """The kernel's JIT dispatcher, made on first use: numba compiles a copy of the
    function whose globals hold the JIT dispatchers of the kernels it calls (not
    their AOT wrappers), so the code is the JIT mode's, inlining included."""
    if info.dispatcher is None:
        fn = info.fn
        scope = dict(fn.__globals__)
        copy = types.FunctionType(
            fn.__code__, scope, fn.__name__, fn.__defaults__, fn.__closure__
        )
        copy.__qualname__, copy.__doc__ = fn.__qualname__, fn.__doc__
        copy.__kwdefaults__, copy.__annotations__ = fn.__kwdefaults__, fn.__annotations__
        info.dispatcher = _njit(copy, info.inline)
        for name in _names(fn.__code__):
            callee = getattr(scope.get(name), "_moveability_kernel", None)
            if isinstance(callee, _Kernel):
                scope[name] = _dispatcher(callee)
    return info.dispatcher


def _arrays(items: tuple[Any, ...], dtype: np.dtype[Any], ndim: int) -> bool:
    """Whether every item of a tuple is an aligned array of the dtype and dimensions."""
    for a in items:
        if not (type(a) is np.ndarray and a.ndim == ndim and a.dtype == dtype):
            return False
        if not a.flags.aligned:
            return False
    return True


def _contiguous(items: tuple[Any, ...]) -> bool:
    """Whether every item of a tuple of arrays is C-contiguous."""
    return all(a.flags.c_contiguous for a in items)


def _copied(args: tuple[Any, ...], inputs: tuple[int, ...], outputs: tuple[int, ...]) -> Any:
    """The arguments with C-contiguous copies of the read-only ones that are not
    (arrays or tuples of arrays at ``inputs``): the same values for a kernel that
    only reads them. None when one may share memory with an array the kernel
    writes (``outputs``): a copy could change what it reads."""
    out = list(args)
    written = [args[i] for i in outputs]
    for i in inputs:
        items = args[i] if type(args[i]) is tuple else (args[i],)
        fixed = []
        for a in items:
            if not a.flags.c_contiguous:
                if any(np.may_share_memory(a, w) for w in written):
                    return None
                a = np.ascontiguousarray(a)
            fixed.append(a)
        out[i] = tuple(fixed) if type(args[i]) is tuple else fixed[0]
    return out


class _Checks:
    """Python source of the checks that ``args`` have a variant's argument types
    (see the manifest written by :mod:`moveability.compiled.build`), with the
    objects the source refers to."""

    def __init__(self) -> None:
        self.scope: dict[str, Any] = {
            "_ndarray": np.ndarray,
            "_float": (float, np.float64),
            "_bool": (bool, np.bool_),
            "_int": int,
            "_int64": np.int64,
            "_uint64": np.uint64,
            "_arrays": _arrays,
            "_contiguous": _contiguous,
            "_copied": _copied,
        }

    def dtype(self, name: str) -> str:
        key = f"_dtype_{np.dtype(name).name}"
        self.scope[key] = np.dtype(name)
        return key

    def types(self, var: str, spec: Any) -> str:
        """Whether ``var`` has the type of ``spec``: for an array its dtype and
        dimensions, aligned, and for one the kernel writes, writeable and
        C-contiguous (a read-only one may be copied, see :func:`_copied`)."""
        if spec == "float64":
            return f"type({var}) in _float"
        if spec == "bool":
            return f"type({var}) in _bool"
        if spec == "int64":
            # numba types a Python int as int64 when it fits
            return (
                f"(type({var}) is _int64 or (type({var}) is _int"
                f" and -9223372036854775808 <= {var} <= 9223372036854775807))"
            )
        if spec == "uint64":
            return f"type({var}) is _uint64"
        if spec[0] == "array":
            _, dtype, ndim, readonly = spec
            check = (
                f"type({var}) is _ndarray and {var}.ndim == {int(ndim)}"
                f" and {var}.dtype == {self.dtype(dtype)}"
            )
            flags = self.flags(var)
            if readonly:
                return f"{check} and ({flags} := {var}.flags).aligned"
            return (
                f"{check} and ({flags} := {var}.flags).aligned and {flags}.writeable"
                f" and {flags}.c_contiguous"
            )
        if spec[0] == "tuple":
            _, n, (kind, dtype, ndim, readonly) = spec
            if kind != "array" or not readonly:
                raise ValueError(f"unknown argument type in the manifest: {spec!r}")
            return (
                f"type({var}) is tuple and len({var}) == {int(n)}"
                f" and _arrays({var}, {self.dtype(dtype)}, {int(ndim)})"
            )
        raise ValueError(f"unknown argument type in the manifest: {spec!r}")

    @staticmethod
    def flags(var: str) -> str:
        """The local name of the flags of ``args[i]`` (read once)."""
        return f"_flags{var[5:-1]}"

    def contiguous(self, var: str, spec: Any) -> str | None:
        """Whether a read-only array (or tuple of arrays) is C-contiguous (after
        :meth:`types`)."""
        if isinstance(spec, str) or not (spec[0] == "tuple" or spec[3]):
            return None
        if spec[0] == "tuple":
            return f"_contiguous({var})"
        return f"{self.flags(var)}.c_contiguous"


def wrapper_source(specs: list[list[Any]]) -> tuple[str, dict[str, Any]]:
    """The source of a kernel's AOT wrapper for variants of argument types
    ``specs`` (see :func:`_wrapper`), and the objects it refers to but the
    variants (``_variant<i>``) and the JIT fallback (``_jit``)."""
    checks = _Checks()
    body, match = [], []
    for i, arg_specs in enumerate(specs):
        try:
            conds = [f"len(args) == {len(arg_specs)}"]
            conds += [checks.types(f"args[{j}]", s) for j, s in enumerate(arg_specs)]
            contiguous = [checks.contiguous(f"args[{j}]", s) for j, s in enumerate(arg_specs)]
        except (ValueError, TypeError, IndexError, KeyError):
            continue  # types this version cannot check: never taken
        inputs = tuple(j for j, c in enumerate(contiguous) if c is not None)
        outputs = tuple(
            j
            for j, s in enumerate(arg_specs)
            if not isinstance(s, str) and s[0] == "array" and not s[3]
        )
        ready = " and ".join(c for c in contiguous if c is not None) or "True"
        body += [
            f"    if {' and '.join(conds)}:",
            f"        if {ready}:",
            f"            return _variant{i}(*args)",
            f"        copied = _copied(args, {inputs}, {outputs})",
            "        if copied is not None:",
            f"            return _variant{i}(*copied)",
        ]
        match += [f"    if {' and '.join(conds)}:", f"        return {i}"]
    head = ["def call(*args, **kwargs):", "    if kwargs:", "        return _jit(*args, **kwargs)"]
    source = "\n".join(
        [*head, *body, "    return _jit(*args)", "def match(*args):", *match, "    return -1"]
    )
    return source, checks.scope


def wrapper_filename(name: str) -> str:
    """The file name of kernel ``name``'s wrapper code (in tracebacks)."""
    return f"<kernel {name}>"


#: the wrappers' code objects compiled by the build, beside the extension
CALLS = Path(__file__).resolve().parent / "_aot.calls"


@functools.cache
def _compiled_calls() -> dict[tuple[str, str], bytes]:
    """The table (file name, source) -> marshalled code that the build wrote (empty
    when it is missing or was written by another Python): a process compiles no
    wrapper whose source is there, and reads the code of those it calls alone."""
    try:
        data = CALLS.read_bytes()
    except OSError:
        return {}
    magic = importlib.util.MAGIC_NUMBER
    if not data.startswith(magic):
        return {}
    try:
        table = marshal.loads(data[len(magic) :])
    except (EOFError, ValueError, TypeError):
        return {}
    return table if isinstance(table, dict) else {}


def _known_code(filename: str, source: str) -> types.CodeType | None:
    """The build's code of a wrapper source, if the table holds it (and it reads)."""
    known = _compiled_calls().get((filename, source))
    if not isinstance(known, bytes):
        return None
    try:
        code = marshal.loads(known)
    except (EOFError, ValueError, TypeError):
        return None
    return code if isinstance(code, types.CodeType) else None


def write_calls(sources: dict[str, str], path: Path = CALLS) -> int:
    """Compile each wrapper source (kernel name -> source) and write the table
    :func:`_compiled_calls` reads, atomically; the number written."""
    table = {
        (wrapper_filename(name), source): marshal.dumps(
            compile(source, wrapper_filename(name), "exec")
        )
        for name, source in sources.items()
    }
    temporary = path.with_name(path.name + f".{os.getpid()}.tmp")
    temporary.write_bytes(importlib.util.MAGIC_NUMBER + marshal.dumps(table))
    os.replace(temporary, path)
    return len(table)


def _wrapper(fn: Callable[..., Any], info: _Kernel, specs: list[list[Any]]) -> Any:
    """A function that calls the first AOT variant whose argument types the
    arguments have, else the JIT kernel; and ``match(*args)``, the index of that
    variant (-1: none). Its code comes from the build's table when it is there
    (:func:`write_calls`), else is compiled now."""
    source, scope = wrapper_source(specs)
    scope["_jit"] = functools.partial(_fallback, info)
    for i in range(len(specs)):
        scope[f"_variant{i}"] = info.variants[i]
    filename = wrapper_filename(f"{fn.__module__}.{fn.__qualname__}")
    code = _known_code(filename, source)
    if code is None:
        code = compile(source, filename, "exec")
    exec(code, scope)
    call = scope["call"]
    functools.update_wrapper(call, fn)
    call.py_func = fn
    call.match = scope["match"]
    call._moveability_kernel = info
    return call


def _deferred(fn: Callable[..., Any], info: _Kernel, specs: list[list[Any]]) -> Any:
    """:func:`_wrapper`, its source compiled at the kernel's first call: a process
    pays only for the kernels it calls (about 0.4 ms each)."""
    made: list[Any] = []

    def wrapped() -> Any:
        if not made:
            made.append(_wrapper(fn, info, specs))
        return made[0]

    def call(*args: Any, **kwargs: Any) -> Any:
        return (made[0] if made else wrapped())(*args, **kwargs)

    def match(*args: Any) -> int:
        found: int = wrapped().match(*args)
        return found

    functools.update_wrapper(call, fn)
    call.py_func = fn  # type: ignore[attr-defined]
    call.match = match  # type: ignore[attr-defined]
    call._moveability_kernel = info  # type: ignore[attr-defined]
    return call


def _fallback(info: _Kernel, *args: Any, **kwargs: Any) -> Any:
    if not info.logged:
        info.logged = True
        what = "no AOT variant" if not info.variants else "arguments no AOT variant takes"
        _log(f"kernel {info.fn.__module__}.{info.fn.__qualname__}: {what}, JIT")
    return _dispatcher(info)(*args, **kwargs)


@functools.cache
def _source(filename: str) -> str:
    """A module's path relative to the package directory ("" outside it)."""
    try:
        return Path(filename).resolve().relative_to(PACKAGE_DIR).as_posix()
    except ValueError:
        return ""


def _bind(fn: Callable[..., Any], inline: bool) -> Any:
    """The AOT-mode kernel of ``fn``: its variants in the extension, if any."""
    assert _EXT is not None and _MANIFEST is not None
    specs: list[list[Any]] = []
    variants = []
    # (a module outside the manifest's sources: none of its kernels was compiled)
    if _source(fn.__code__.co_filename) in _MANIFEST["sources"]:
        for symbol, arg_specs in _MANIFEST["kernels"].get(f"{fn.__module__}.{fn.__qualname__}", []):
            if hasattr(_EXT, symbol):
                variants.append(getattr(_EXT, symbol))
                specs.append(arg_specs)
    info = _Kernel(fn, inline, variants)
    if variants:
        return _deferred(fn, info, specs)

    def call(*args: Any, **kwargs: Any) -> Any:
        return _fallback(info, *args, **kwargs)

    def match(*args: Any) -> int:
        return -1

    functools.update_wrapper(call, fn)
    call.py_func = fn  # type: ignore[attr-defined]
    call.match = match  # type: ignore[attr-defined]
    call._moveability_kernel = info  # type: ignore[attr-defined]
    return call


# ----------------------------------------------------------------- the API
@overload
def kernel(fn: F) -> F: ...
@overload
def kernel(*, inline: bool = False) -> Callable[[F], F]: ...
def kernel(fn: Any = None, *, inline: bool = False) -> Any:
    """Decorate a kernel: ``numba.njit(cache=True, nogil=True)`` (``inline="always"``
    with ``inline=True``, for helpers that only kernels call), or its AOT variants
    when the extension is up to date (see the module's docstring).

    Examples
    --------
    >>> from moveability.intervals import next_below
    >>> next_below(0.0) < 0.0
    True
    """

    def decorate(f: Any) -> Any:
        out = _njit(f, inline) if _EXT is None else _bind(f, inline)
        KERNELS[f"{f.__module__}.{f.__qualname__}"] = out
        return out

    return decorate if fn is None else decorate(fn)


def jit_of(k: Any) -> Any:
    """The numba dispatcher of a kernel (itself in JIT mode), compiled on first use.

    Examples
    --------
    >>> from moveability.intervals import next_below
    >>> jit_of(next_below)(1.0) == next_below(1.0)
    True
    """
    info = getattr(k, "_moveability_kernel", None)
    return k if info is None else _dispatcher(info)
