"""The sheet table's rows in one compiled pass (``_sheet_kernels.posture_rows``)
against the same rules in numpy, posture by posture, on random inputs: limit
codes of every kind, constraint rows present or not, det A's bounds with NaN,
signed zeros and infinities, boxes out of reach or folding. Every output is
compared bit for bit (signed zeros included)."""

from __future__ import annotations

import numpy as np
import pytest

from moveability.analysis._sheet_kernels import posture_rows
from moveability.hypertree.status import BOUNDARY, IN, OUT
from moveability.limits import INSIDE, OUTSIDE, STRADDLES


def numpy_rows(postures, codes, ang_lo, ang_hi, det_lo, det_hi, det_row, beyond, beyond_row,
               no_plus, no_minus, signs_row, any_out, any_fold, fold_ok):  # fmt: skip
    """The rules of :func:`posture_rows`, one posture at a time, in numpy."""
    n = any_out.size
    n_post, n_legs = postures.shape
    out = {
        "status": np.empty((n, n_post), np.uint8), "sign": np.empty((n, n_post), np.int8),
        "exists": np.empty((n, n_post), bool), "within": np.empty((n, n_post), bool),
        "group": np.empty((n, n_post), bool), "det_lo": np.empty((n, n_post)),
        "det_hi": np.empty((n, n_post)), "ang_lo": np.empty((n, n_post, n_legs)),
        "ang_hi": np.empty((n, n_post, n_legs)),
    }  # fmt: skip
    regular = ~any_fold & ~any_out
    for p in range(n_post):
        lim_in = np.ones(n, bool)
        lim_out = np.zeros(n, bool)
        for i, b in enumerate(postures[p]):
            out["ang_lo"][:, p, i], out["ang_hi"][:, p, i] = ang_lo[i, b], ang_hi[i, b]
            lim_in &= codes[i, b] == INSIDE
            lim_out |= codes[i, b] == OUTSIDE
        if beyond_row[p] >= 0:
            lim_in &= beyond[beyond_row[p]] == INSIDE
            lim_out |= beyond[beyond_row[p]] == OUTSIDE
        d_lo, d_hi = det_lo[det_row[p]], det_hi[det_row[p]]
        if signs_row[p] >= 0:
            plus_none, minus_none = no_plus[signs_row[p]], no_minus[signs_row[p]]
            lim_out |= plus_none & minus_none
            d_lo = np.where(minus_none, np.maximum(d_lo, 0.0), d_lo)
            d_hi = np.where(plus_none, np.minimum(d_hi, 0.0), d_hi)
        out["det_lo"][:, p], out["det_hi"][:, p] = d_lo, d_hi
        s = np.where(d_lo > 0, 1, np.where(d_hi < 0, -1, 0))
        out["sign"][:, p] = s
        out["exists"][:, p] = regular
        out["within"][:, p] = lim_in
        dead = any_out | lim_out
        sure = np.where(regular & lim_in & (s != 0), IN, BOUNDARY)
        out["status"][:, p] = np.where(dead, OUT, sure)
        out["group"][:, p] = fold_ok & lim_in & (s != 0)
    return out


def bits(a: np.ndarray) -> np.ndarray:
    return a.view(np.uint64) if a.dtype == np.float64 else a


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize(("n_legs", "n_branch"), [(2, 2), (3, 1), (3, 2)])
def test_posture_rows_are_the_numpy_rules(seed: int, n_legs: int, n_branch: int) -> None:
    rng = np.random.default_rng(seed * 10 + n_legs + n_branch)
    n = 3000
    postures = np.array(
        np.meshgrid(*[np.arange(n_branch)] * n_legs, indexing="ij")
    ).reshape(n_legs, -1).T.copy()  # fmt: skip
    n_post = postures.shape[0]
    code_set = np.array([INSIDE, INSIDE, INSIDE, OUTSIDE, STRADDLES, 0], dtype=np.uint8)
    codes = rng.choice(code_set, size=(n_legs, n_branch, n)).astype(np.uint8)
    ang_lo = rng.normal(size=(n_legs, n_branch, n))
    ang_hi = ang_lo + rng.random((n_legs, n_branch, n))
    specials = np.array([np.nan, 0.0, -0.0, np.inf, -np.inf, 1e-300, -1e-300])

    def dets(rows: int) -> np.ndarray:
        d = rng.normal(size=(rows, n))
        odd = rng.random((rows, n)) < 0.15
        d[odd] = rng.choice(specials, size=int(odd.sum()))
        return d

    one_det = rng.random() < 0.3  # a det A of the pose alone: one row for every posture
    d_a, d_b = dets(1 if one_det else n_post), dets(1 if one_det else n_post)
    det_lo, det_hi = np.minimum(d_a, d_b), np.maximum(d_a, d_b)
    det_lo[rng.random(det_lo.shape) < 0.05] = np.nan
    det_row = np.zeros(n_post, np.int64) if one_det else np.arange(n_post, dtype=np.int64)
    # constraint rows for some postures only
    beyond_row = np.where(rng.random(n_post) < 0.5, np.arange(n_post), -1).astype(np.int64)
    signs_row = np.where(rng.random(n_post) < 0.5, np.arange(n_post), -1).astype(np.int64)
    beyond = rng.choice(code_set, size=(n_post, n)).astype(np.uint8)
    no_plus = rng.random((n_post, n)) < 0.3
    no_minus = rng.random((n_post, n)) < 0.3
    any_out = rng.random(n) < 0.1
    any_fold = rng.random(n) < 0.2
    fold_ok = rng.random(n) < 0.5
    args = (postures, codes, ang_lo, ang_hi, det_lo, det_hi, det_row, beyond, beyond_row,
            no_plus, no_minus, signs_row, any_out, any_fold, fold_ok)  # fmt: skip
    want = numpy_rows(*args)
    got = {k: np.empty_like(v) for k, v in want.items()}
    with np.errstate(invalid="ignore"):
        posture_rows(*args, *(got[k] for k in want))
    for key in want:
        assert np.array_equal(bits(got[key]), bits(want[key])), key
    # every outcome met: each status, both signs, clamped zeros
    assert {OUT, IN, BOUNDARY} <= set(np.unique(got["status"]).tolist())
    assert {-1, 0, 1} <= set(np.unique(got["sign"]).tolist())
    assert got["group"].any() and got["within"].any() and not got["within"].all()
