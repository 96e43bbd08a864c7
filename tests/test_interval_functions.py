"""Property tests of the interval functions added for expressions (power, exp, log,
tan, absolute, rational): the enclosure holds the value at sampled points, judged
exactly with fractions for power, absolute and rational, against numpy's float
value for exp, log and tan."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from moveability.intervals import Interval, absolute, exp, log, power, rational, tan

SETTINGS = settings(deadline=None, max_examples=200, suppress_health_check=[HealthCheck.too_slow])
finite = st.floats(-1e6, 1e6, allow_nan=False)


def _interval_and_points(a: float, b: float, t: float) -> tuple[Interval, list[float]]:
    lo, hi = min(a, b), max(a, b)
    return Interval(lo, hi), [lo, hi, min(hi, lo + t * (hi - lo)), 0.0 if lo <= 0 <= hi else lo]


@SETTINGS
@given(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3), st.floats(0, 1), st.integers(-6, 9))
def test_power_encloses_exactly(a, b, t, n):
    x, points = _interval_and_points(a, b, t)
    r = power(x, n)
    for p in points:
        if n < 0 and p == 0:
            continue
        if n < 0 and x.lo <= 0 <= x.hi:
            assert r.lo == -np.inf or r.hi == np.inf
            continue
        exact = Fraction(p) ** n
        assert r.lo == -np.inf or Fraction(float(r.lo)) <= exact
        assert r.hi == np.inf or exact <= Fraction(float(r.hi))


@SETTINGS
@given(finite, finite, st.floats(0, 1))
def test_absolute_and_tan(a, b, t):
    x, points = _interval_and_points(a, b, t)
    r = absolute(x)
    for p in points:
        assert r.lo <= abs(p) <= r.hi
    small, pts = _interval_and_points(a * 1e-5, b * 1e-5, t)
    rt = tan(small)
    for p in pts:
        assert rt.lo <= np.tan(p) <= rt.hi


@SETTINGS
@given(st.floats(-700, 700), st.floats(-700, 700), st.floats(0, 1))
def test_exp_and_log(a, b, t):
    x, points = _interval_and_points(a, b, t)
    r = exp(x)
    for p in points:
        assert r.lo <= np.exp(p) <= r.hi
    pos = Interval(np.exp(x.lo), np.exp(x.hi))
    rl = log(pos)
    for p in (pos.lo, pos.hi, 0.5 * (pos.lo + pos.hi)):
        assert rl.lo <= np.log(p) <= rl.hi


@SETTINGS
@given(st.integers(-(10**20), 10**20), st.integers(1, 10**20))
def test_rational_is_tight_and_enclosing(p, q):
    r = rational(p, q)
    exact = Fraction(p, q)
    assert Fraction(float(r.lo)) <= exact <= Fraction(float(r.hi))
    assert float(np.nextafter(r.lo, np.inf)) >= float(r.hi)


def test_tan_pole_gives_the_whole_line():
    r = tan(Interval(1.5, 1.6))
    assert r.lo == -np.inf and r.hi == np.inf
