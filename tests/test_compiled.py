"""The ahead-of-time compiled kernels (:mod:`moveability.compiled`).

* the table of compiled variants names kernels with their number of arguments;
* a manifest whose source hash, environment or CPU differs is stale, and a stale
  extension (a kernel's module edited after the build) selects the JIT, quietly
  unless asked;
* a call with arguments of other types than the variants' goes to the JIT kernel
  (the same result as numba's), a non-contiguous read-only array is copied;
* AOT and JIT kernels agree bit for bit on random inputs with zeros, infinities,
  NaN, subnormals and overflowing products: the outward rounding of the interval
  operations, and the determinant of 3 x 3 interval matrices.

The last three need the extension (``make kernels``) and are skipped without it.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import marshal
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from moveability import compiled
from moveability.analysis.result import _walk_back
from moveability.compiled import build
from moveability.intervals import _product_bounds, _sum_bounds, _trig_bounds, _widen, next_below
from moveability.mechanisms import base

aot = pytest.mark.skipif(
    compiled.MODE != "aot", reason=f"no up-to-date extension ({compiled.REASON})"
)

SPECIAL = np.array(
    [0.0, -0.0, np.inf, -np.inf, np.nan, 5e-324, -5e-324, 1e-170, -1e-170, 1e308, -1e308, 1.0]
)


def floats(rng: np.random.Generator, n: int) -> np.ndarray:
    """Numbers of every magnitude with 20% special values."""
    x = rng.normal(size=n) * 10.0 ** rng.integers(-300, 300, size=n)
    special = rng.random(n) < 0.2
    x[special] = rng.choice(SPECIAL, size=int(special.sum()))
    return x


def same(a: Any, b: Any) -> bool:
    """Bit for bit, through tuples."""
    if isinstance(a, tuple):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def test_every_compiled_variant_names_a_kernel_with_its_arguments():
    for name, variants in build.EXPORTS.items():
        module, _, function = name.rpartition(".")
        fn = getattr(importlib.import_module(module), function)
        assert name in compiled.KERNELS, name
        n_params = len(inspect.signature(fn.py_func).parameters)
        assert all(len(v) == n_params for v in variants), name


def manifest_of_sources() -> dict[str, Any]:
    sources = ["intervals.py", "limits.py", "compiled/build.py"]
    return {
        "format": compiled.FORMAT,
        **compiled.environment(),
        "cpu": compiled.cpu_id() or "generic",
        "sources": compiled.source_hashes(sources),
    }


def test_a_manifest_is_stale_when_a_source_or_the_environment_changed():
    manifest = manifest_of_sources()
    assert compiled.manifest_problem(manifest) is None
    assert compiled.manifest_problem({**manifest, "cpu": "generic"}) is None
    edited = {**manifest["sources"], "limits.py": "0" * 64}
    assert "limits.py changed" in str(compiled.manifest_problem({**manifest, "sources": edited}))
    assert "numpy" in str(compiled.manifest_problem({**manifest, "numpy": "0.0"}))
    assert "numba" in str(compiled.manifest_problem({**manifest, "numba": "0" * 64}))
    assert "CPU" in str(compiled.manifest_problem({**manifest, "cpu": "0" * 64}))
    assert "format" in str(compiled.manifest_problem({**manifest, "format": 0}))


def mode_in_copy(tmp_path: Path, edit: bool, log: bool) -> subprocess.CompletedProcess[str]:
    """The kernels' mode in a copy of the package, a kernel's module edited or not."""
    package = Path(compiled.__file__).resolve().parents[1]
    copy = tmp_path / "moveability"
    shutil.copytree(package, copy, ignore=shutil.ignore_patterns("__pycache__"))
    if edit:
        source = copy / "limits.py"
        source.write_text(source.read_text() + "\n# edited after the build\n")
    code = (
        "import sys; from moveability import compiled; from moveability.intervals import"
        " next_below; print(compiled.MODE, compiled.REASON, 'numba' in sys.modules)"
    )
    env = {"PYTHONPATH": str(tmp_path), "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    if log:
        env["MOVEABILITY_KERNELS_LOG"] = "1"
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    )


@aot
def test_an_edited_kernel_module_selects_the_jit(tmp_path: Path):
    fresh = mode_in_copy(tmp_path / "fresh", edit=False, log=False)
    assert fresh.stdout.split()[0] == "aot"
    assert fresh.stdout.split()[-1] == "False"  # numba not imported
    assert fresh.stderr == ""
    stale = mode_in_copy(tmp_path / "stale", edit=True, log=False)
    assert stale.stdout.startswith("jit limits.py changed since the extension was built")
    assert stale.stderr == ""  # quiet unless asked
    told = mode_in_copy(tmp_path / "told", edit=True, log=True)
    assert "kernels: jit (limits.py changed" in told.stderr


@aot
def test_arguments_of_other_types_run_on_the_jit():
    rng = np.random.default_rng(1)
    a, b = floats(rng, 50), floats(rng, 50)
    # float32 arrays: numba compiles a float32 kernel; the float64 variant must not run
    a32, b32 = (rng.normal(size=50).astype(np.float32) for _ in range(2))
    assert _sum_bounds.match(a32, b32, True) == -1
    out = _sum_bounds(a32, b32, True)
    assert out.dtype == np.float32
    assert same(out, compiled.jit_of(_sum_bounds)(a32, b32, True))
    # integers where the variant takes floats (the same bits would be misread)
    ints = rng.integers(-(2**40), 2**40, size=50)
    assert _widen.match(ints, 1e-16, 5e-324, False) == -1
    jit = compiled.jit_of(_widen)(ints, 1e-16, 5e-324, False)
    assert same(_widen(ints, 1e-16, 5e-324, False), jit)
    # a Python int for a float: numba types it int64, so does the fallback
    assert next_below.match(3) == -1 and next_below(3) == compiled.jit_of(next_below)(3)
    # keywords, wrong counts
    assert same(_sum_bounds(a, b, up=True), compiled.jit_of(_sum_bounds)(a, b, True))
    with pytest.raises(TypeError):
        _sum_bounds(a, b)


@aot
def test_read_only_arguments_are_copied_when_not_contiguous_and_outputs_never():
    rng = np.random.default_rng(2)
    wide = floats(rng, 200).reshape(50, 4)
    column = wide[:, 1]  # strided
    assert not column.flags.c_contiguous and _sum_bounds.match(column, column, False) == 0
    contiguous = column.copy()
    assert same(_sum_bounds(column, column, False), _sum_bounds(contiguous, contiguous, False))
    # an output that is not contiguous: the JIT writes it in place
    n = 40
    starts = rng.integers(0, n, size=6)
    source = np.where(rng.random(n) < 0.3, 0, -1)
    pred = rng.integers(-1, n, size=n)
    expected = np.zeros(n, dtype=bool)
    assert _walk_back.match(expected, starts, source, pred) == 0
    _walk_back(expected, starts, source, pred)
    column = np.zeros((n, 2), dtype=bool)[:, 0]
    assert _walk_back.match(column, starts, source, pred) == -1
    _walk_back(column, starts, source, pred)
    assert expected.any() and same(column.copy(), expected)
    # nor a read-only one
    expected.flags.writeable = False
    assert _walk_back.match(expected, starts, source, pred) == -1


@aot
@pytest.mark.parametrize("seed", range(3))
def test_aot_and_jit_agree_bit_for_bit(seed: int):
    rng = np.random.default_rng(seed)
    n = 400
    a_lo, a_hi, b_lo, b_hi = (floats(rng, n) for _ in range(4))
    a_lo, a_hi = np.minimum(a_lo, a_hi), np.maximum(a_lo, a_hi)
    b_lo, b_hi = np.minimum(b_lo, b_hi), np.maximum(b_lo, b_hi)
    cases = [
        (_widen, (a_lo, 5 * 2.0**-52, 4 * 5e-324, False)),
        (_widen, (a_hi, 2 * 2.0**-52, 5e-324, True)),
        (_sum_bounds, (a_lo, b_lo, False)),
        (_sum_bounds, (a_hi, b_hi, True)),
        (_product_bounds, (a_lo, a_hi, b_lo, b_hi)),
        (_trig_bounds, (a_lo, a_hi, True, 5 * 2.0**-52, 4 * 5e-324)),
        (_trig_bounds, (a_lo / 1e295, a_hi / 1e295, False, 5 * 2.0**-52, 4 * 5e-324)),
    ]
    # 3 x 3 interval matrices: det A of a three-legged mechanism's rows
    entries = [np.sort(np.stack([floats(rng, n), floats(rng, n)]), axis=0) for _ in range(9)]
    lo = tuple(e[0] for e in entries)
    hi = tuple(e[1] for e in entries)
    for kernel, args in cases:
        assert kernel.match(*args) == 0
        assert same(kernel(*args), compiled.jit_of(kernel)(*args)), kernel.__name__
    for x in floats(rng, 50):
        assert same(next_below(float(x)), compiled.jit_of(next_below)(float(x)))
    outputs = [(np.empty(n), np.empty(n)) for _ in range(2)]
    assert base._det_bounds.match(lo, hi, *outputs[0]) == 2
    base._det_bounds(lo, hi, *outputs[0])
    compiled.jit_of(base._det_bounds)(lo, hi, *outputs[1])
    assert same(outputs[0], outputs[1])


@aot
def test_every_wrapper_comes_compiled_from_the_build():
    """The build wrote the wrappers' code (the table of the file CALLS): each
    kernel's wrapper source, as a process makes it from the manifest, is there,
    and its code is what compiling that source gives."""
    table = compiled._compiled_calls()
    manifest = compiled._MANIFEST
    assert manifest is not None and table
    for name, variants in manifest["kernels"].items():
        if not any(hasattr(compiled._EXT, symbol) for symbol, _ in variants):
            continue
        source, _ = compiled.wrapper_source([specs for _, specs in variants])
        key = (compiled.wrapper_filename(name), source)
        assert key in table, name
        assert marshal.loads(table[key]).co_code == compile(source, key[0], "exec").co_code


def test_a_missing_or_foreign_calls_table_compiles_the_wrappers(tmp_path: Path):
    """write_calls writes what the table reader takes back; a file of another
    Python (its magic number) or no file at all gives no entry: the wrappers are
    then compiled in the process."""
    source, _ = compiled.wrapper_source([["float64", "float64"]])
    path = tmp_path / "calls"
    assert compiled.write_calls({"m.k": source}, path) == 1
    data = path.read_bytes()
    assert data.startswith(importlib.util.MAGIC_NUMBER)
    real = compiled.CALLS
    try:
        compiled.CALLS = path
        compiled._compiled_calls.cache_clear()
        assert set(compiled._compiled_calls()) == {(compiled.wrapper_filename("m.k"), source)}
        key = (compiled.wrapper_filename("m.k"), source)
        assert compiled._known_code(*key) is not None
        # an entry that is not marshalled code is not taken
        path.write_bytes(importlib.util.MAGIC_NUMBER + marshal.dumps({key: b"junk"}))
        compiled._compiled_calls.cache_clear()
        assert compiled._known_code(*key) is None
        path.write_bytes(b"\0\0\0\0" + data[4:])
        compiled._compiled_calls.cache_clear()
        assert compiled._compiled_calls() == {}
        path.unlink()
        compiled._compiled_calls.cache_clear()
        assert compiled._compiled_calls() == {}
    finally:
        compiled.CALLS = real
        compiled._compiled_calls.cache_clear()


@aot
def test_an_up_to_date_build_writes_a_missing_calls_table(tmp_path: Path, monkeypatch):
    """An extension built before the wrappers' table existed: the build, finding
    it up to date, writes the table alone (the same entries)."""
    path = tmp_path / "_aot.calls"
    monkeypatch.setattr(build, "CALLS", path)
    assert build.build() == ""
    table = compiled._compiled_calls()
    written = marshal.loads(path.read_bytes()[len(importlib.util.MAGIC_NUMBER) :])
    assert set(written) == set(table)
