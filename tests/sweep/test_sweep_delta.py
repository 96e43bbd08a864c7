"""A sweep over the Delta's rod: each design's row against the brute-force reference
of the Delta's hostile tests (its regions labelled on a grid of the joints)."""

from __future__ import annotations

import functools
import importlib.util
import pathlib

import numpy as np

import moveability.analysis.result
from moveability.sweep import read_table, run_sweep

PI = np.pi
_HOSTILE = pathlib.Path(__file__).parents[1] / "mechanisms" / "test_delta_hostile.py"


def _reference_module():
    spec = importlib.util.spec_from_file_location("delta_reference", _HOSTILE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_rod_sweep_rows_match_the_reference(tmp_path, monkeypatch):
    """rod = 8, 10, 12 on a Delta with limits [-pi/2, pi/2]: 4, 16 and 2 regions
    by the reference; each row's count is proved (in the joint space) and equal
    to it, and its workspace bounds hold a Monte Carlo estimate."""
    ref_module = _reference_module()
    design, limits = (10.0, 4.0, 8.0, 10.0), [(-PI / 2, PI / 2)] * 3
    spec = ref_module._spec(design, limits)
    # the count in the joint space, without refining the poses below the precision
    original = moveability.analysis.result.analyze
    monkeypatch.setattr(
        moveability.analysis.result, "analyze", functools.partial(original, resolve_levels=0)
    )
    out = tmp_path / "rods.csv"
    done = run_sweep(spec, ["rod=8:12:3"], out, precision=2.0)
    assert done["computed"] == 3 and done["failed"] == 0
    _, rows = read_table(out)
    assert sorted(row["rod"] for row in rows) == [8.0, 10.0, 12.0]
    rng = np.random.default_rng(21)
    counts = []
    for row in rows:
        assert row["error"] is None, row
        rod = row["rod"]
        ref = ref_module.Ref((*design[:3], rod), limits, n=61)
        expected = 2 * ref.n_components
        counts.append(expected)
        assert row["regions"] == row["regions_at_least"] == row["regions_at_most"] == expected
        m = ref_module.from_spec(ref_module._spec((*design[:3], rod), limits))
        lo, hi = m.pose_box()
        box = float(np.prod(hi - lo))
        sample = lo + (hi - lo) * rng.random((100_000, 3))
        frac = ref.in_w(sample).mean()
        se = np.sqrt(frac * (1 - frac) / sample.shape[0]) * box
        assert row["workspace_inner"] - 4 * se <= frac * box <= row["workspace_outer"] + 4 * se
    # the rod changes the count: the sweep sees designs of different counts
    assert len(set(counts)) >= 2
