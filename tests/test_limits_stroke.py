"""JointLimit.classify of a stroke (a compiled pass, limits._classify_stroke)
against the numpy formula it replaces: the same codes for enclosures inside,
outside, straddling and touching the stroke, NaN and infinite bounds, any shape."""

from __future__ import annotations

import numpy as np
import pytest

from moveability.intervals import Interval
from moveability.limits import INSIDE, OUTSIDE, STRADDLES, JointLimit


def _formula(limit: JointLimit, angles: Interval) -> np.ndarray:
    out = np.full(angles.lo.shape, STRADDLES, dtype=np.uint8)
    out[(angles.lo >= limit.lo) & (angles.hi <= limit.hi)] = INSIDE
    out[(angles.hi < limit.lo) | (angles.lo > limit.hi)] = OUTSIDE
    return out


@pytest.mark.parametrize("shape", [(), (7,), (5, 3)])
def test_stroke_codes_are_the_formula(shape):
    rng = np.random.default_rng(len(shape))
    limit = JointLimit(10.0, 25.0, prismatic=True)
    n = int(np.prod(shape, dtype=int)) * 400
    a = rng.choice([np.nan, -np.inf, np.inf, 10.0, 25.0, 0.0], n)
    b = rng.choice([np.nan, np.inf, 10.0, 25.0, 30.0], n)
    free = rng.random(n) < 0.6
    a[free] = rng.uniform(0.0, 35.0, free.sum())
    b[free] = a[free] + rng.uniform(0.0, 20.0, free.sum())
    for k in range(400):
        part = slice(k * (n // 400), (k + 1) * (n // 400))
        angles = Interval(a[part].reshape(shape), b[part].reshape(shape))
        codes = limit.classify(angles)
        assert codes.dtype == np.uint8 and codes.shape == shape
        np.testing.assert_array_equal(codes, _formula(limit, angles))
