"""The compiled interval shortcuts give the same bounds, bit for bit, as the plain
:class:`~moveability.intervals.Interval` operations they replace.

* a sum, difference or product with one interval for every element (a number,
  a 0-d or a one-element array) against the same operation on broadcast arrays;
* :func:`~moveability.mechanisms.base.interval_det` of 1x1 to 3x3 matrices
  against the cofactor recursion on Interval operations;
* :meth:`~moveability.mechanisms.base.Mechanism.det_a_rate` against the same
  formula written with Interval operations.

The samples mix ordinary numbers with zeros of both signs, infinities, NaN,
subnormals and products that underflow or overflow.
"""

from __future__ import annotations

import numpy as np
import pytest

from moveability.intervals import Interval
from moveability.mechanisms import base

SPECIAL = np.array(
    [0.0, -0.0, np.inf, -np.inf, np.nan, 5e-324, -5e-324, 1e-170, -1e-170, 1e308, -1e308, 1.0]
)


def sample(rng: np.random.Generator, n: int) -> Interval:
    a = rng.normal(size=n) * 10.0 ** rng.integers(-200, 200, size=n)
    b = a + np.abs(rng.normal(size=n)) * rng.choice([0.0, 1e-8, 1.0], size=n)
    for x in (a, b):
        m = rng.random(n) < 0.15
        x[m] = rng.choice(SPECIAL, size=int(m.sum()))
    return Interval(np.minimum(a, b), np.maximum(a, b))


def same(x: Interval, y: Interval) -> bool:
    return (
        x.lo.shape == y.lo.shape
        and np.array_equal(x.lo, y.lo, equal_nan=True)
        and np.array_equal(x.hi, y.hi, equal_nan=True)
    )


def broadcast(x: Interval, shape: tuple[int, ...]) -> Interval:
    """The same intervals as full arrays (the general path of the operators)."""
    return Interval(np.broadcast_to(x.lo, shape).copy(), np.broadcast_to(x.hi, shape).copy())


@pytest.mark.parametrize("seed", range(5))
def test_operations_with_one_interval_match_broadcast(seed: int) -> None:
    rng = np.random.default_rng(seed)
    full = sample(rng, 400)
    for _ in range(20):
        one = sample(rng, 1)
        for other in (one, Interval(one.lo[0], one.hi[0]), float(one.lo[0])):
            o = other if isinstance(other, Interval) else Interval(other)
            wide = broadcast(o, full.shape)
            assert same(full + other, full + wide)
            assert same(full - other, full - wide)
            assert same(full * other, full * wide)
            assert same(other + full, wide + full)
            assert same(other - full, wide - full)
            assert same(other * full, wide * full)


def recursive_rate(
    rows: list[list[Interval]],
    partials: list[tuple[list[list[Interval]], list[Interval]]],
    velocity: list[Interval],
    rates: list[Interval],
) -> Interval:
    """det A's rate as :meth:`Mechanism.det_a_rate` writes it, on Interval operations."""
    k = len(velocity)
    total: Interval | None = None
    for i in range(k):
        along_x, along_q = partials[i]
        moved = []
        for j in range(k):
            rate = along_q[j] * rates[i]
            for axis in range(k):
                rate = rate + along_x[j][axis] * velocity[axis]
            moved.append(rate)
        term = base._interval_det([*rows[:i], moved, *rows[i + 1 :]])
        total = term if total is None else total + term
    assert total is not None
    return total


class _Legs(base.Mechanism):
    """Just enough of a mechanism for :meth:`det_a_rate` with given rows."""

    def __init__(self, k: int) -> None:
        self.legs = tuple(range(k))  # type: ignore[arg-type]


@pytest.mark.parametrize("k", [1, 2, 3])
@pytest.mark.parametrize("n", [0, 1, 5000])
def test_compiled_determinants_match_recursion(k: int, n: int) -> None:
    rng = np.random.default_rng(10 * k + n)
    rows = [[sample(rng, n) for _ in range(k)] for _ in range(k)]
    assert same(base.interval_det(rows), base._interval_det(rows))
    partials = [
        ([[sample(rng, n) for _ in range(k)] for _ in range(k)], [sample(rng, n) for _ in range(k)])
        for _ in range(k)
    ]
    velocity = [sample(rng, n) for _ in range(k)]
    rates = [sample(rng, n) for _ in range(k)]
    got = _Legs(k).det_a_rate(
        np.zeros((n, k)), np.zeros((n, k)), [], velocity, rates, rows_and_partials=(rows, partials)
    )
    assert got is not None
    assert same(got, recursive_rate(rows, partials, velocity, rates))


def test_compiled_determinant_broadcasts_numbers() -> None:
    rng = np.random.default_rng(7)
    rows = [[sample(rng, 9) if (r + c) % 2 else Interval(2.5) for c in range(3)] for r in range(3)]
    assert same(base.interval_det(rows), base._interval_det(rows))


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_det_a_rate_at_some_boxes_matches_all(k: int) -> None:
    """``at`` gives, at those boxes, the bounds of the whole (the compiled gather
    for k <= 3, the subset of the Interval formula for 4); numbers broadcast."""
    rng = np.random.default_rng(40 + k)
    n = 3000
    rows = [[sample(rng, n) if c else Interval(1.5) for c in range(k)] for _ in range(k)]
    partials = [
        ([[sample(rng, n) for _ in range(k)] for _ in range(k)], [sample(rng, n) for _ in range(k)])
        for _ in range(k)
    ]
    velocity = [sample(rng, n) for _ in range(k)]
    rates = [Interval(0.5)] + [sample(rng, n) for _ in range(k - 1)]
    box = np.zeros((n, k))
    legs = _Legs(k)
    whole = legs.det_a_rate(box, box, [], velocity, rates, rows_and_partials=(rows, partials))
    assert whole is not None
    for at in (np.flatnonzero(rng.random(n) < 0.3), np.arange(n), np.zeros(0, dtype=np.int64)):
        got = legs.det_a_rate(
            box, box, [], velocity, rates, rows_and_partials=(rows, partials), at=at
        )
        assert got is not None
        assert same(got, Interval(whole.lo[at], whole.hi[at]))
