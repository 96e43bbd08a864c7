"""Compile the package's kernels ahead of time: ``python -m moveability.compiled.build``.

numba.pycc compiles each kernel that Python code calls, once for each tuple of
argument types in :data:`EXPORTS`, into the extension ``_aot`` beside this file
(kernels that only kernels call are compiled into their callers), with its
manifest (see :mod:`moveability.compiled`): the hash of every source the
compiled code comes from, this file included, and each variant's argument
types. It compiles for the CPU numba's JIT compiles for (its model and
instruction sets; the extension then runs on an identical CPU only), or with
``--generic`` for any CPU of the architecture (slower: no SIMD beyond SSE2 on
x86-64). Never with fastmath: the IEEE operations of the JIT code, bit for bit.

It prints one line, and nothing when the extension is up to date. When it
cannot compile (no C compiler, numba without pycc, ...) it says why and exits
0: the package then runs on numba's JIT. A kernel that pycc cannot compile is
left out, and named: it runs on the JIT. ``--force`` rebuilds an extension
that is up to date; ``--check`` only says whether it is (exit status 1 if not).

The argument types are those the package passes (the JIT dispatchers'
``signatures`` after the test suite), for C-contiguous arrays. An array the
kernel only reads is declared read-only: the variant takes it writeable or
not, and a contiguous copy of it when it is not contiguous. Calls with other
types run on the JIT.
"""

from __future__ import annotations

import argparse
import ast
import importlib
import inspect
import json
import os
import sys
import tempfile
import time
import types
from pathlib import Path
from typing import Any

from . import (
    CALLS,
    EXTENSION,
    FORMAT,
    KERNELS,
    PACKAGE_DIR,
    cpu_id,
    environment,
    jit_of,
    manifest_problem,
    source_hashes,
    wrapper_source,
    write_calls,
)

__all__ = ["EXPORTS", "build", "main"]


def array(dtype: str, ndim: int = 1, *, out: bool = False) -> list[Any]:
    """An array argument (any layout), read-only unless the kernel writes it (``out``)."""
    return ["array", dtype, ndim, not out]


def uniform(n: int, item: list[Any]) -> list[Any]:
    """A tuple of ``n`` arrays of one type."""
    return ["tuple", n, item]


F8, I8, U8, B1 = "float64", "int64", "uint64", "bool"
R1, R2, W1, W2 = array(F8), array(F8, 2), array(F8, out=True), array(F8, 2, out=True)
#: the interval matrices' entries: (rows, derivatives, velocity, rates) of k = 1, 2, 3
_DET_ITEMS, _RATE_ITEMS = (1, 4, 9), (5, 20, 51)

#: "module.kernel" -> the argument types of each compiled variant
EXPORTS: dict[str, list[tuple[Any, ...]]] = {
    "moveability.intervals._widen": [(R1, F8, F8, B1)],
    "moveability.intervals._sum_bounds": [(R1, R1, B1)],
    "moveability.intervals._sum_bounds_one": [(R1, F8, B1)],
    "moveability.intervals._product_bounds": [(R1, R1, R1, R1)],
    "moveability.intervals._product_bounds_one": [(R1, R1, F8, F8)],
    "moveability.intervals._holds_angles": [(R1, R1, R1)],
    "moveability.intervals._trig_bounds": [(R1, R1, B1, F8, F8)],
    "moveability.intervals.next_below": [(F8,)],
    "moveability.limits._classify": [(R1, R1, R1, R1)],
    "moveability.limits._classify_stroke": [(R1, R1, F8, F8)],
    "moveability.mechanisms.base._det_bounds": [
        (uniform(n, R1), uniform(n, R1), W1, W1) for n in _DET_ITEMS
    ],
    "moveability.mechanisms.base._det_rate_bounds": [
        (uniform(n, R1), uniform(n, R1), W1, W1) for n in _RATE_ITEMS
    ],
    "moveability.mechanisms.base._det_rate_bounds_at": [
        (uniform(n, R1), uniform(n, R1), array(I8), W1, W1) for n in _RATE_ITEMS
    ],
    "moveability.mechanisms.tape._run": [
        (array(I8, 2), R1, R1, I8, R2, R2, array(I8), R1, R1, R2, R2, I8, I8, W1, W1)
    ],
    "moveability.mechanisms.tape._contract": [
        (
            array(I8, 2), R1, R1, I8, array(I8), R2, R2, I8, I8, R2, R2, array(I8), R1,
            W1, W1, W1, W1, array(I8, out=True), array(I8, out=True),
            W1, W1, W1, W1, array(I8, out=True), array(I8, out=True), I8, F8,
        )
    ],
    "moveability.mechanisms.expressions._point_trig": [(R1,)],
    "moveability.mechanisms._rpr_kernels.det_a_bounds": [(R2, R2, R2, R2, W1, W1)],
    "moveability.mechanisms._rpr_kernels.row_bounds": [(R2, R2, R2, R2, W2, W2)],
    "moveability.mechanisms._rpr_kernels.joint_gradient_bounds": [
        (R2, R2, R2, R1, R1, R1, W2, W2)
    ],
    "moveability.mechanisms._rpr_kernels.reach_bounds": [(R2, R2, R2, R1, W1, W1)],
    "moveability.mechanisms._rpr_kernels.pose_bounds": [(R2, R2, R2, W2, W2, W1, W1)],
    "moveability.mechanisms._rr_kernels.knee_bounds": [(R1, R1, R1, W2, W2)],
    "moveability.mechanisms._rr_kernels.det_a_bounds": [(R2, R2, R2, R2, R2, array(I8), W1, W1)],
    "moveability.mechanisms._rr_kernels.det_a_postures": [
        (R2, R2, array(F8, 3), array(F8, 3), R2, array(I8, 2), W2, W2)
    ],
    "moveability.mechanisms._rr_kernels.reach_prepare": [
        (R2, R2, R1, R1, R1, array("uint8"), W2, array("uint8", out=True))
    ],
    "moveability.mechanisms._rr_kernels.reach_finish": [
        (
            R2, R2, array("uint8"), array("uint8"), R1, R1, R1, R2, R2, R2, R1, W2, W2,
            array(B1, out=True),
        )
    ],
    "moveability.mechanisms._rr_kernels.fold_terms_prepare": [(R2, R2, R1, W2, W2, W2)],
    "moveability.mechanisms._rr_kernels.fold_terms_finish": [(R2, W2, W2)],
    "moveability.mechanisms._rr_kernels.fold_rate_bounds": [
        (R2, R2, R2, R2, array("uint8"), array("uint8"), F8, array(B1, out=True), W1, W1)
    ],
    "moveability.hypertree._bits.encode": [(array(I8, 2), array(I8, 2), array(I8))],
    "moveability.hypertree._bits.decode": [(array(U8), array(I8, 2), array(I8))],
    "moveability.hypertree._boxes.cell_boxes": [
        (array(I8, 2), array("uint8"), array(I8), R1, R1, R1)
    ],
    "moveability.hypertree._kernels._label": [
        (
            array(U8), array("uint8"), array(B1), array(I8), array(U8), array(I8, 2),
            array(B1), array("int8", 2),
        )
    ],
    "moveability.hypertree._kernels._pairs": [
        (
            array(U8), array("uint8"), array(B1), array(I8), array(U8), array(I8, 2),
            array(B1), array("int8", 2), array(B1), array(B1),
        )
    ],
    "moveability.hypertree._kernels._sorted_pairs": [
        (array(I8, out=True), array(I8, out=True), I8)
    ],
    "moveability.hypertree._kernels._in_order": [(array(I8, 2),)],
    "moveability.hypertree._kernels._merged_pairs": [(array(I8, 2), array(I8, 2))],
    "moveability.hypertree._kernels.remap_pairs": [
        (array(I8, 2), array(I8), array(B1, out=True))
    ],
    "moveability.hypertree._kernels.edge_labels": [(I8, array(I8), array(I8), array(B1))],
    "moveability.analysis.regions._certain_edges": [
        (
            array(I8, 2), array("int8", 2), array(B1, 2), array(B1, 2), array(B1, 2),
            array(B1), B1, array(I8, 2), array(B1, 2),
        )
    ],
    "moveability.analysis.flows._face_sides": [
        (array(I8, 2), array(I8, 2), array(I8, 2), array(I8), array(B1))
    ],
    "moveability.analysis.flows._propagate": [
        (
            array(B1, 2, out=True), array(U8, 2), array(I8, 3, out=True), array(B1, 2),
            array("uint8", 2), array(I8), array(I8), array(I8), array(I8),
        )
    ],
    "moveability.analysis.result._walk_back": [
        (array(B1, out=True), array(I8), array(I8), array(I8))
    ],
    "moveability.analysis.result._chain_search": [
        (array(I8, 2), array(I8), array(I8), array(I8))
    ],
    "moveability.analysis.result._grown": [(array(B1), array(I8, 2), array(I8))],
    "moveability.mechanisms.tape._isolate_level": [
        (
            array(I8, 2), R1, R1, I8, I8, array(I8, 2), array(I8), array(I8, 2), array(I8), R2,
            R2, array(I8), I8, array(I8), R1, R1, R2, R2, R2, R2, R2, R2, array(I8, out=True),
            I8, B1, array(I8, 2), R1, R2, R2, I8,
        )
    ],
    "moveability.mechanisms.tape._merge_order": [(array(I8), R1, array(I8))],
    "moveability.mechanisms._delta_kernels.det_a_prepare": [
        (R2, R2, R2, R2, R2, W1, W1, array(F8, 3, out=True))
    ],
    "moveability.mechanisms._delta_kernels.regular_boxes": [(R2, R2, R2, array(B1, out=True))],
    "moveability.mechanisms._delta_kernels.centre_args": [(R2, R2, R2, array(F8, 3, out=True))],
    "moveability.mechanisms._delta_kernels.centre_turn": [
        (R2, R2, R2, R2, R2, array(F8, 3, out=True))
    ],
    "moveability.mechanisms._delta_kernels.centre_angles": [
        (R2, R2, R2, array(F8, 3), array(F8, 3), array(F8, 3), array(F8, 3, out=True))
    ],
    "moveability.mechanisms._delta_kernels.centre_trig": [
        (array(F8, 3), array(F8, 4, out=True))
    ],
    "moveability.mechanisms._delta_kernels.mean_value_bounds": [
        (R2, R2, array(F8, 3), array(I8), array(F8, 4), R2, W1, W1)
    ],
    "moveability.analysis.regions._piece_bounds": [
        (
            array(F8, 3), array(F8, 3), array(I8), array(F8), array(F8), array(I8, 2),
            array(F8, 5, out=True), array(B1, 3, out=True),
        )
    ],
    "moveability.analysis.regions._possible_labels_both": [
        (
            array(I8, 2), array(B1, 3), array(B1, 3), array(F8, 5), array(I8, 2),
            array(I8, 2), array(B1, 2), array(B1, 2), F8, array(I8, 2), array("int8", 2),
        )
    ],
    "moveability.analysis._sheet_kernels.posture_rows": [
        (
            array(I8, 2), array("uint8", 3), array(F8, 3), array(F8, 3), R2, R2, array(I8),
            array("uint8", 2), array(I8), array(B1, 2), array(B1, 2), array(I8), array(B1),
            array(B1), array(B1), array("uint8", 2, out=True), array("int8", 2, out=True),
            array(B1, 2, out=True), array(B1, 2, out=True), array(B1, 2, out=True), W2, W2,
            array(F8, 3, out=True), array(F8, 3, out=True),
        )
    ],
    "moveability.hypertree._kernels.mark_sources": [
        (array(I8, 2), array(I8), array(B1, out=True))
    ],
    "moveability.hypertree._kernels._remapped_merged": [
        (array(I8, 2), array(I8, 2), array(I8))
    ],
    "moveability.analysis.flows._dependencies": [
        (
            array(I8, 2), array(I8), array(I8, 2), array(B1, 3), array(B1, 3),
            array(F8, 4), array(B1, 2),
        )
    ],
    "moveability.mechanisms._delta_kernels.mean_value_all": [
        (R2, R2, array(F8, 3), array(F8, 3), array(I8, 2), array(F8, 4), R2, W2, W2)
    ],
    "moveability.mechanisms._delta_kernels.intersect_finite": [(R1, R1, W1, W1)],
    "moveability.mechanisms._delta_kernels.det_a_all": [
        (R2, R2, array(F8, 3), array(F8, 3), array(I8, 2), R2, W2, W2)
    ],
    "moveability.mechanisms._delta_leg_kernels.reach_prepare": [
        (
            R2, R2, R1, array("uint8"), array("uint8", out=True), array("uint8", out=True),
            array(B1, out=True), W2,
        )
    ],
    "moveability.mechanisms._delta_leg_kernels.reach_turn": [(R2, R1, R1, W2)],
    "moveability.mechanisms._delta_leg_kernels.reach_finish": [
        (array("uint8"), R1, R1, R1, R2, R2, R2, W2, W2)
    ],
    "moveability.mechanisms._delta_leg_kernels.joint_gradient_bounds": [
        (R2, R2, R1, R1, R1, W2, W2)
    ],
    "moveability.mechanisms._delta_leg_kernels.fold_terms_prepare": [(R2, R2, R1, W2, W2, W2)],
    "moveability.mechanisms._delta_leg_kernels.fold_terms_finish": [(R2, W2, W2)],
    "moveability.mechanisms._delta_leg_kernels.fold_rate_bounds": [
        (
            R2, R2, R2, R2, array("uint8"), array("uint8"), F8, R1, array(B1, out=True), W1,
            W1,
        )
    ],
    "moveability.mechanisms._fold_kernels._fold": [
        (
            array(I8, 2), R1, R1, I8, I8, array(I8), I8, uniform(8, array(I8, 2)),
            uniform(4, array(I8)), R1, I8, I8, I8, R2, R2, array(I8), array(I8), R1, R1, R1,
            array(B1), R2, R2, R2, R2, R2, R2, array(F8, 3), array(F8, 3), array(F8, 3),
            array(F8, 3), array(F8, 3), array(F8, 3), array(I8), R1, R1, R2, R2,
        )
    ],
    "moveability.mechanisms.tape._pose_ops": [
        (array(I8, 2), R1, R1, I8, I8, I8, R2, R2, R2, R2, array(I8))
    ],
}


# ------------------------------------------------------------------ types
def numba_type(spec: Any) -> Any:
    """The numba type of an argument of :data:`EXPORTS`."""
    from numba import types as nt

    if isinstance(spec, str):
        return {"bool": nt.boolean}.get(spec) or getattr(nt, spec)
    if spec[0] == "array":
        _, dtype, ndim, readonly = spec
        return nt.Array(numba_type(dtype), ndim, "C", readonly=readonly)
    _, n, item = spec
    return nt.UniTuple(numba_type(item), n)


# ---------------------------------------------------------------- sources
def _kernel_modules() -> list[str]:
    """The package's modules that define kernels (``@kernel`` in their source)."""
    found = []
    for path in sorted(PACKAGE_DIR.rglob("*.py")):
        if path.parent.name == "compiled" or "@kernel" not in path.read_text():
            continue
        parts = path.relative_to(PACKAGE_DIR.parent).with_suffix("").parts
        found.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return found


def _module_file(name: str) -> str | None:
    """A package module's source path relative to the package directory."""
    module = sys.modules.get(name)
    path = getattr(module, "__file__", None)
    if path is None or not name.startswith(PACKAGE_DIR.name + "."):
        return None
    return Path(path).resolve().relative_to(PACKAGE_DIR).as_posix()


def _names(code: types.CodeType) -> set[str]:
    out = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            out |= _names(const)
    return out


def _top_level(module: types.ModuleType) -> tuple[dict[str, tuple[str, str]], list[ast.stmt]]:
    """A module's names bound by ``from X import name`` at its top level -> (X,
    name), and its top-level statements."""
    tree = ast.parse(Path(module.__file__ or "").read_text())
    package = module.__name__.rsplit(".", 1)[0]
    imported = {}
    for node in tree.body:
        if isinstance(node, ast.ImportFrom):
            base = package.split(".")
            if node.level:
                base = base[: len(base) - node.level + 1]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            for alias in node.names:
                imported[alias.asname or alias.name] = (source, alias.name)
    return imported, tree.body


def _defined_by(module_name: str, name: str, files: set[str], seen: set[tuple[str, str]]) -> None:
    """Add to ``files`` the package's sources that a module-level name's value comes
    from: the module that defines it (through imports) and, for a value computed
    at import (``_X = f(_Y) * other.Z``), those of the names it is computed from."""
    module = sys.modules.get(module_name)
    if (module_name, name) in seen or _module_file(module_name) is None or module is None:
        return
    seen.add((module_name, name))
    files.add(_module_file(module_name) or "")
    value = getattr(module, name, None)
    if isinstance(value, types.ModuleType):
        files.add(_module_file(value.__name__) or "")
        return
    imported, body = _top_level(module)
    if name in imported:
        _defined_by(*imported[name], files, seen)
        return
    rhs: ast.expr | None
    for node in body:
        if isinstance(node, ast.Assign):
            targets, rhs = node.targets, node.value
        elif isinstance(node, ast.AnnAssign | ast.AugAssign):
            targets, rhs = [node.target], node.value
        else:
            continue
        if rhs is not None and any(
            isinstance(t, ast.Name) and t.id == name for x in targets for t in ast.walk(x)
        ):
            for used in ast.walk(rhs):
                if isinstance(used, ast.Name):
                    _defined_by(module_name, used.id, files, seen)


def _sources(kernel_modules: list[str]) -> list[str]:
    """The files the compiled code comes from: the kernels' modules, those that
    define the globals a kernel reads (constants imported from elsewhere or
    computed from them, modules used as namespaces), and this file."""
    files = {"compiled/build.py"}
    seen: set[tuple[str, str]] = set()
    for name in kernel_modules:
        importlib.import_module(name)
        files.add(_module_file(name) or "")
        for qualname, k in KERNELS.items():
            fn = getattr(k, "py_func", None)
            if fn is not None and qualname.startswith(name + "."):
                for global_name in _names(fn.__code__):
                    _defined_by(fn.__module__, global_name, files, seen)
    files.discard("")
    return sorted(files)


# ------------------------------------------------------------------ build
def up_to_date() -> str | None:
    """Why the extension must be rebuilt (None: it is up to date)."""
    try:
        ext = importlib.import_module(EXTENSION)
        return manifest_problem(json.loads(ext.manifest()))
    except Exception as exc:
        return f"no usable extension ({exc})"


def _host() -> tuple[str, str]:
    """The CPU name and features numba's JIT compiles for (see numba.core.codegen)."""
    import llvmlite.binding as ll
    from numba.core import config
    from numba.core.codegen import get_host_cpu_features

    name = getattr(config, "CPU_NAME", None) or ll.get_host_cpu_name()
    features = getattr(config, "CPU_FEATURES", None)
    return name, get_host_cpu_features() if features is None else features


def _constant(text: str) -> Any:
    """A function returning ``text`` (the manifest, compiled into the extension)."""

    def manifest() -> str:  # pragma: no cover - compiled
        return text

    return manifest


def _compile(
    entries: list[tuple[str, str, Any, tuple[Any, ...]]],
    manifest: dict[str, Any],
    out_dir: str,
) -> dict[str, str]:
    """Compile the entries (symbol, kernel name, function, argument types) and the
    manifest into ``out_dir``. A kernel that fails is left out (and out of the
    manifest), and the build retried; returns those left out, with the first
    line of why."""
    from numba.core.codegen import AOTCPUCodegen
    from numba.pycc import CC
    from numba.pycc import compiler as pycc_compiler

    left_out: dict[str, str] = {}
    real = pycc_compiler.compile_extra
    real_features = AOTCPUCodegen._customize_tm_features
    current: list[str] = []
    host = manifest["cpu"] != "generic"
    if host:
        cpu_name, features = _host()
        manifest["cpu_name"] = cpu_name

    def compile_extra(typingctx: Any, targetctx: Any, func: Any, *args: Any, **kw: Any) -> Any:
        current[:] = [getattr(func, "_moveability_name", "")]
        return real(typingctx, targetctx, func, *args, **kw)

    while True:
        kept = {k: v for k, v in manifest["kernels"].items() if k not in left_out}
        manifest_fn = _constant(json.dumps({**manifest, "kernels": kept}, sort_keys=True))
        cc = CC(EXTENSION.rsplit(".", 1)[1])
        cc.output_dir = out_dir
        cc.verbose = False
        if host:
            # the JIT's CPU and instruction sets (pycc takes the model's default set)
            cc.target_cpu = cpu_name
            AOTCPUCodegen._customize_tm_features = lambda self: features  # type: ignore[method-assign]
        for symbol, name, fn, argtypes in entries:
            if name not in left_out:
                cc.export(symbol, argtypes)(fn)
        cc.export("manifest", ())(manifest_fn)
        pycc_compiler.compile_extra = compile_extra
        try:
            cc.compile()
            return left_out
        except Exception as exc:
            if not current or current[0] in ("", *left_out):
                raise
            left_out[current[0]] = (str(exc).strip().splitlines() or [repr(exc)])[0]
        finally:
            pycc_compiler.compile_extra = real
            AOTCPUCodegen._customize_tm_features = real_features  # type: ignore[method-assign]


def _wrapper_sources(manifest: dict[str, Any], left_out: dict[str, str]) -> dict[str, str]:
    """Each compiled kernel's wrapper source, as a process makes it from the
    manifest (:func:`moveability.compiled.wrapper_source`)."""
    return {
        name: wrapper_source([list(s) for _, s in variants])[0]
        for name, variants in manifest["kernels"].items()
        if name not in left_out
    }


def build(force: bool = False, generic: bool = False) -> str:
    """Compile the extension (unless it is up to date); the line to print. For
    this CPU, as the JIT, unless ``generic`` (or the CPU cannot be identified):
    then for any CPU of the architecture, and slower (no SIMD beyond SSE2 on
    x86-64)."""
    start = time.perf_counter()
    if not force and up_to_date() is None:
        if not CALLS.exists():
            # an extension built before the wrappers' table was: write it now
            built = json.loads(importlib.import_module(EXTENSION).manifest())
            write_calls(_wrapper_sources(built, {}), CALLS)
        return ""
    with tempfile.TemporaryDirectory(prefix="moveability-aot-") as tmp:
        # a cache of its own: everything compiled here, for the generic CPU
        os.environ["NUMBA_CACHE_DIR"] = str(Path(tmp) / "numba-cache")
        modules = _kernel_modules()
        for name in modules:
            importlib.import_module(name)
        cpu = "" if generic else cpu_id()
        manifest: dict[str, Any] = {
            "format": FORMAT,
            **environment(),
            "cpu": cpu or "generic",
            "kernels": {},
        }
        entries = []
        for name, arg_lists in EXPORTS.items():
            if name not in KERNELS:
                print(f"moveability: no kernel {name} (see EXPORTS)", file=sys.stderr)
                continue
            fn = jit_of(KERNELS[name]).py_func
            fn._moveability_name = name
            n_params = len(inspect.signature(fn).parameters)
            if any(len(specs) != n_params for specs in arg_lists):
                # (cheaper said now than found by numba's typing, one build each)
                print(
                    f"moveability: kernel {name} left to the JIT: it takes {n_params}"
                    " arguments, not those of EXPORTS",
                    file=sys.stderr,
                )
                continue
            for i, specs in enumerate(arg_lists):
                symbol = f"{name.replace('.', '__')}__{i}"
                argtypes = tuple(numba_type(s) for s in specs)
                entries.append((symbol, name, fn, argtypes))
                manifest["kernels"].setdefault(name, []).append([symbol, list(specs)])
        manifest["sources"] = source_hashes(_sources(modules))
        left_out = _compile(entries, manifest, tmp)
        (extension,) = Path(tmp).glob("_aot*")
        target = Path(__file__).resolve().parent / extension.name
        # the kernels' wrappers compiled once here, not in every process
        write_calls(_wrapper_sources(manifest, left_out), CALLS)
        os.replace(extension, target)  # atomic: a running process keeps the old file
    for name, why in left_out.items():
        print(f"moveability: kernel {name} left to the JIT: {why}", file=sys.stderr)
    kept = [v for k, v in manifest["kernels"].items() if k not in left_out]
    return (
        f"moveability: {len(kept)} kernels ({sum(map(len, kept))} variants) compiled ahead"
        f" of time into {target.relative_to(PACKAGE_DIR.parent)} in"
        f" {time.perf_counter() - start:.0f} s"
    )


def main(argv: list[str] | None = None) -> int:
    """The command line (see the module's docstring)."""
    parser = argparse.ArgumentParser(prog="python -m moveability.compiled.build")
    parser.add_argument("--force", action="store_true", help="rebuild even if up to date")
    parser.add_argument("--check", action="store_true", help="only say whether up to date")
    parser.add_argument(
        "--generic", action="store_true", help="for any CPU of this architecture (slower)"
    )
    args = parser.parse_args(argv)
    if args.check:
        problem = up_to_date()
        print(f"moveability: ahead-of-time kernels {problem or 'up to date'}")
        return 0 if problem is None else 1
    try:
        line = build(force=args.force, generic=args.generic)
    except Exception as exc:
        reason = (str(exc).strip().splitlines() or [repr(exc)])[0]
        line = f"moveability: kernels not compiled ahead of time ({reason}); numba's JIT runs them"
    if line:
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
