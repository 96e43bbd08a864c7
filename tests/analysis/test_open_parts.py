"""Where an analysis is still open: parts of touching open leaves, against
``scipy.ndimage.label`` on grids, and the output that carries them."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from moveability import analyze
from moveability.analysis.open_parts import open_parts, open_text
from moveability.hypertree.topology import touching
from moveability.hypertree.tree import HyperTree


@pytest.mark.parametrize("ndim", [2, 3])
@pytest.mark.parametrize("seed", range(3))
def test_parts_are_the_components_of_a_grid(ndim, seed):
    rng = np.random.default_rng(seed)
    shape = (16,) * ndim if ndim == 2 else (8,) * ndim
    grid = rng.random(shape) < 0.35
    # a tree of the grid's cells (every cell a leaf), the open ones those of grid
    tree = HyperTree.from_array(np.ones(shape, dtype=bool), merge=False)
    leaves = tree.leaves()
    cell = np.floor((leaves.lo - tree.lo) / (tree.hi - tree.lo) * np.array(shape)).astype(int)
    mask = grid[tuple(cell.T)]
    pairs, _ = touching(tree)
    volumes = np.prod(leaves.hi - leaves.lo, axis=1)
    found = open_parts(leaves.lo, leaves.hi, volumes, pairs, mask, "volume", limit=1000)
    labels, n = ndimage.label(grid, structure=np.ones((3,) * ndim))
    assert found["parts"] == n
    assert found["volume"] == pytest.approx(volumes[mask].sum())
    sizes = sorted((np.bincount(labels.ravel())[1:] * volumes[0]).tolist(), reverse=True)
    assert [p["volume"] for p in found["largest"]] == pytest.approx(sizes)
    # each part's box holds its cells and no larger than the grid's own box of them
    for part in found["largest"]:
        lo, hi = np.array(part["box"])
        assert (lo >= tree.lo).all() and (hi <= tree.hi).all() and (lo < hi).all()


def test_nothing_open_gives_no_part_and_no_line():
    found = open_parts(
        np.zeros((2, 2)), np.ones((2, 2)), np.ones(2), np.zeros((0, 2), int), np.zeros(2, bool)
    )
    assert found == {"parts": 0, "area": 0.0, "largest": []}
    assert open_text(found, ("x", "y"), "area") == ""


def test_an_open_count_says_where_it_is_open():
    """The 3-RRR keeps its count open: the output names the open parts, in W's
    box, with their measure, and the summary says it in one line."""
    result = analyze("examples/three-rrr.toml", precision=0.4)
    assert result.count[1] is None
    where = result.undecided["open"]
    assert where["parts"] >= 1 and where["volume"] > 0
    lo, hi = result.tree.lo, result.tree.hi
    for part in where["largest"]:
        box_lo, box_hi = np.array(part["box"])
        assert (box_lo >= lo - 1e-9).all() and (box_hi <= hi + 1e-9).all()
    assert sum(p["volume"] for p in where["largest"]) <= where["volume"] + 1e-9
    assert any(line.startswith("still open:") for line in result.summary().splitlines())


def test_a_decided_analysis_has_nothing_open():
    result = analyze("examples/five-bar-paper.toml", precision=0.1)
    assert result.n_regions == 2 and result.n_connected is not None
    assert result.undecided["open"] == {"parts": 0, "area": 0.0, "largest": []}
    assert "still open" not in result.summary()
