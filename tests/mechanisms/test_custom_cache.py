"""The cache of compiled user-defined specs (moveability.mechanisms.custom).

A spec found in the cache is built without sympy and gives the functions built
from sympy; a cached body that a printer could not have written (other names,
attribute access, keywords) is refused and the spec compiled again.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from moveability import load_spec
from moveability.errors import SpecError
from moveability.intervals import Interval
from moveability.mechanisms import custom
from moveability.mechanisms.custom import CustomMechanism

SPEC = "examples/five-bar-custom.toml"


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MOVEABILITY_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(custom, "_MEMO", {})
    return tmp_path


def values(mechanism: CustomMechanism) -> list[np.ndarray]:
    """Every leg function over a few boxes (compiled and interpreted paths)."""
    x = Interval(np.array([3.0, -1.0, 10.0]), np.array([3.5, 2.0, 10.1]))
    y = Interval(np.array([9.0, 0.0, 2.0]), np.array([9.2, 4.0, 2.5]))
    q = Interval(np.array([0.1, -3.0, 1.0]), np.array([0.3, 3.0, 1.01]))
    out = []
    for leg in mechanism.legs:
        for g in (leg.f, leg.df_dq, leg.d2f_dq2, *leg.df_dx):
            v = g(x, y, q)
            out += [v.lo, v.hi]
    return out


def test_cached_spec_gives_the_same_functions(cache) -> None:
    data = dict(load_spec(SPEC))
    fresh = CustomMechanism(data)
    assert len(list(cache.iterdir())) >= 2  # the normalised spec and the bodies
    custom._MEMO.clear()  # read back from the disk
    cached = CustomMechanism(data)
    assert cached.spec == fresh.spec
    for a, b in zip(values(fresh), values(cached), strict=True):
        assert np.array_equal(a, b, equal_nan=True)


def test_cached_spec_needs_no_sympy(cache) -> None:
    CustomMechanism(load_spec(SPEC))
    code = (
        "import sys; from moveability import analyze; "
        f"r = analyze({SPEC!r}, precision=0.5); "
        "assert 'sympy' not in sys.modules, 'sympy imported'; "
        "assert 'importlib.metadata' not in sys.modules, 'importlib.metadata imported'; "
        "print(r.to_dict()['leaves'])"
    )
    env = {**os.environ, "MOVEABILITY_CACHE_DIR": str(cache)}
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-500:]
    assert int(done.stdout) > 0


def test_other_numbers_need_no_sympy(cache) -> None:
    """Only the names and the legs go through sympy: a spec met before with other
    parameter values, joint limits and pose bounds is built from the cache, with
    its own numbers."""
    CustomMechanism(load_spec(SPEC))
    code = (
        "import sys; from moveability import load_spec; "
        "from moveability.mechanisms.custom import CustomMechanism; "
        f"d = dict(load_spec({SPEC!r})); "
        "d['limits'] = {'t1': [-1.0, 2.0], 't2': 'unlimited'}; "
        "d['bounds'] = {'x': [-5.0, 9.0], 'y': [0.0, 12.0]}; "
        "d['parameters'] = {**d['parameters'], 'L2': 6}; "
        "m = CustomMechanism(d); "
        "assert 'sympy' not in sys.modules, 'sympy imported'; "
        "print(m.spec['parameters']['L2'], m.spec['limits'], m.spec['bounds'])"
    )
    env = {**os.environ, "MOVEABILITY_CACHE_DIR": str(cache)}
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-500:]
    assert done.stdout.strip() == (
        "6.0 {'t1': [-1.0, 2.0], 't2': 'unlimited'} {'x': [-5.0, 9.0], 'y': [0.0, 12.0]}"
    )


def test_numbers_are_checked_when_the_names_are_cached(cache) -> None:
    data = dict(load_spec(SPEC))
    CustomMechanism(data)
    with pytest.raises(SpecError, match=r"bounds\.x"):
        CustomMechanism({**data, "bounds": {"x": [3.0, 1.0], "y": [0.0, 1.0]}})
    with pytest.raises(SpecError, match=r"limits\.t2"):
        CustomMechanism({**data, "limits": {"t1": [0.0, 1.0]}})
    with pytest.raises(SpecError, match=r"parameters\.L2"):
        CustomMechanism({**data, "parameters": {**data["parameters"], "L2": float("nan")}})


@pytest.mark.parametrize(
    "body",
    ["_a0.__class__", "__import__('os')", "open(_a0)", "sin(_a0, x=1)", "_a9", "1.5", 3],
)
def test_tampered_bodies_are_refused(cache, body) -> None:
    data = dict(load_spec(SPEC))
    fresh = CustomMechanism(data)
    changed = 0
    for path in cache.iterdir():
        stored = json.loads(path.read_text())
        if isinstance(stored, dict) and "0.f" in stored:
            stored["0.f"] = body
            path.write_text(json.dumps(stored))
            changed += 1
    assert changed == 1
    custom._MEMO.clear()
    again = CustomMechanism(data)
    for a, b in zip(values(fresh), values(again), strict=True):
        assert np.array_equal(a, b, equal_nan=True)


def test_no_cache_when_disabled(tmp_path, monkeypatch) -> None:
    monkeypatch.setenv("MOVEABILITY_CACHE_DIR", "")
    monkeypatch.setattr(custom, "_MEMO", {})
    monkeypatch.chdir(tmp_path)
    CustomMechanism(load_spec(os.path.join(os.path.dirname(__file__), "..", "..", SPEC)))
    assert not list(tmp_path.iterdir())


def test_the_cache_key_follows_sympy_s_release(tmp_path, monkeypatch) -> None:
    """The key of a cached spec depends on sympy's release file (read, not
    imported): another release of sympy builds the spec again."""
    import importlib.util

    real = importlib.util.find_spec("sympy")
    assert real is not None and real.origin is not None
    custom._fingerprint.cache_clear()
    before = custom._fingerprint()
    other = tmp_path / "sympy"
    other.mkdir()
    (other / "__init__.py").write_text("")
    (other / "release.py").write_text('__version__ = "0.0.1"\n')
    spec = importlib.util.spec_from_file_location("sympy", other / "__init__.py")
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: spec)
    custom._fingerprint.cache_clear()
    try:
        assert custom._fingerprint() != before
    finally:
        monkeypatch.undo()
        custom._fingerprint.cache_clear()
    assert custom._fingerprint() == before
