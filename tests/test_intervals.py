"""Property tests of the outward-rounded interval arithmetic in ``moveability.intervals``.

Random arrays of a few intervals (finite bounds over the whole float range,
degenerate intervals, intervals straddling 0, widths of a few ulps up to
huge, bounds at or next to multiples of pi/2) are sampled at points inside
each operand (endpoints, their neighbours, interior points, zero and the
floats next to the extrema of sin and cos). Enclosures are judged

* exactly, with :class:`fractions.Fraction`, for ``+ - * /``, ``square``
  and ``sqrt`` (``lo**2 <= p <= hi**2``);
* against numpy's own float value at the point for ``sin``, ``cos``,
  ``arccos`` and ``arctan2``, and against a 400-digit pi for the extrema of
  ``sin``/``cos`` and the ends of ``arccos``/``arctan2`` (the exact extremum
  may lie between two adjacent floats, where no float sample sees it).
"""

from __future__ import annotations

import math
import warnings
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from moveability.intervals import (
    Interval,
    arccos,
    arctan2,
    as_interval,
    cos,
    hull,
    sin,
    sqrt,
    square,
)
from references import pi_fraction

FMAX = float(np.finfo(np.float64).max)
TINY = 5e-324
SETTINGS = settings(deadline=None, max_examples=300, suppress_health_check=[HealthCheck.too_slow])


def quiet_overflow() -> np.errstate:
    """Overflow to inf is how bounds become infinite; its warnings are tested on their own."""
    return np.errstate(over="ignore")


# ---------------------------------------------------------------- exact pi
def _pi_fraction(digits: int = 400) -> Fraction:
    return pi_fraction(digits)


PI = _pi_fraction()
TWO_PI = 2 * PI
HALF_PI = PI / 2


def test_reference_pi():
    assert float(PI) == math.pi
    assert Fraction(math.pi) < PI < Fraction(math.nextafter(math.pi, 4.0))


# ---------------------------------------------------------------- helpers
def _steps(x: float, k: int) -> float:
    """``x`` moved ``|k|`` floats up (``k > 0``) or down."""
    target = math.inf if k > 0 else -math.inf
    for _ in range(abs(k)):
        x = math.nextafter(x, target)
    return x


def _finite(x: float) -> float:
    return min(max(x, -FMAX), FMAX)


def _floor_float(v: Fraction) -> float:
    """The largest float <= v."""
    f = float(v)
    return f if Fraction(f) <= v else math.nextafter(f, -math.inf)


def _ceil_float(v: Fraction) -> float:
    """The smallest float >= v."""
    f = float(v)
    return f if Fraction(f) >= v else math.nextafter(f, math.inf)


def _extremum_points(lo: float, hi: float, phase: Fraction, limit: int = 3) -> list[Fraction]:
    """The points ``phase + 2 pi n`` in the real interval [lo, hi] (at most ``limit``)."""
    lo_f, hi_f = Fraction(lo), Fraction(hi)
    n = math.ceil((lo_f - phase) / TWO_PI)
    out = []
    while len(out) < limit:
        p = phase + TWO_PI * n
        if p > hi_f:
            break
        out.append(p)
        n += 1
    return out


def _in(v: Fraction, lo: float, hi: float) -> bool:
    """Whether the exact value ``v`` lies in the float interval [lo, hi] (bounds may be inf)."""
    assert not (math.isnan(lo) or math.isnan(hi)), (lo, hi)
    lo_ok = lo == -math.inf or (lo != math.inf and Fraction(lo) <= v)
    hi_ok = hi == math.inf or (hi != -math.inf and v <= Fraction(hi))
    return lo_ok and hi_ok


def _points(lo: float, hi: float, ts: list[float], trig: bool = False) -> list[float]:
    """Sample points of [lo, hi]: ends, their neighbours inside, interior points, 0."""
    pts = {lo, hi, min(math.nextafter(lo, math.inf), hi), max(math.nextafter(hi, -math.inf), lo)}
    for t in ts:
        p = lo * (1.0 - t) + hi * t
        p = p if math.isfinite(p) else 0.5 * lo + 0.5 * hi
        pts.add(min(max(p, lo), hi))
    if lo <= 0.0 <= hi:
        pts.add(0.0)
    if trig and hi - lo < 100.0:
        for k in range(4):
            for p in _extremum_points(lo, hi, k * HALF_PI, limit=2):
                pts.add(min(max(_floor_float(p), lo), hi))
                pts.add(min(max(_ceil_float(p), lo), hi))
    out = sorted(pts)
    assert all(lo <= p <= hi for p in out)
    return out


def _arrays(bounds: list[tuple[float, float]]) -> Interval:
    lo = np.array([b[0] for b in bounds], dtype=np.float64)
    hi = np.array([b[1] for b in bounds], dtype=np.float64)
    assert np.all(lo <= hi) and np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))
    return Interval(lo, hi)


def _well_formed(r: Interval, n: int) -> None:
    """An Interval of ``n`` float intervals, no nan, ``lo <= hi``."""
    assert isinstance(r, Interval), type(r)
    assert r.lo.shape == r.hi.shape == (n,)
    assert r.lo.dtype == r.hi.dtype == np.float64
    assert not np.any(np.isnan(r.lo)) and not np.any(np.isnan(r.hi))
    assert np.all(r.lo <= r.hi)


# ---------------------------------------------------------------- strategies
def _magnitudes(lo_exp: int = -300, hi_exp: int = 308) -> st.SearchStrategy[float]:
    return st.builds(
        lambda m, e: _finite(m * 10.0**e), st.floats(1.0, 9.999), st.integers(lo_exp, hi_exp)
    )


def _signed(s: st.SearchStrategy[float]) -> st.SearchStrategy[float]:
    return st.builds(lambda x, neg: -x if neg else x, s, st.booleans())


@st.composite
def _half_pi_multiples(draw: st.DrawFn, max_exp: int = 13) -> float:
    """``m pi / 2`` for an integer ``m``, rounded in one of a few float ways."""
    e = draw(st.integers(0, max_exp))
    m = draw(st.integers(-(10**e), 10**e))
    how = draw(st.sampled_from(["mul", "mul2", "down", "up"]))
    if how == "mul":
        return m * (math.pi / 2)
    if how == "mul2":
        return m * math.pi / 2
    exact = m * HALF_PI
    return _floor_float(exact) if how == "down" else _ceil_float(exact)


def _centers(max_exp: int = 308) -> st.SearchStrategy[float]:
    bound = min(10.0**max_exp, FMAX)
    return st.one_of(
        st.just(0.0),
        _signed(_magnitudes(-300, max_exp)),
        st.floats(-bound, bound, allow_nan=False, allow_infinity=False),
        _half_pi_multiples(min(max_exp, 15)),
        st.sampled_from([1.0, -1.0, 0.5, -0.5, 2.0, 1e-308, -1e-308]),
    )


def _widths(max_exp: int = 308) -> st.SearchStrategy[float]:
    two_pi = 2 * math.pi
    return st.one_of(
        st.just(0.0),
        _magnitudes(-300, max_exp),
        st.floats(0.0, 10.0),
        st.sampled_from(
            [TINY, math.pi / 2, math.pi, two_pi, _steps(two_pi, -1), _steps(two_pi, 1), 7.0]
        ),
    )


@st.composite
def _bounds(draw: st.DrawFn, max_exp: int = 308) -> tuple[float, float]:
    """One interval with finite bounds."""
    kinds = ["ulps", "center", "straddle", "any", "degenerate", "extremum", "huge"]
    kind = draw(st.sampled_from(kinds))
    if kind == "ulps":
        c = draw(_centers(max_exp))
        lo = _steps(c, -draw(st.integers(0, 4)))
        hi = _steps(c, draw(st.integers(0, 4)))
    elif kind == "center":
        c = draw(_centers(max_exp))
        lo = c - draw(_widths(max_exp))
        hi = c + draw(_widths(max_exp))
    elif kind == "straddle":
        lo = -draw(st.one_of(st.just(0.0), _magnitudes(-300, max_exp)))
        hi = draw(st.one_of(st.just(0.0), _magnitudes(-300, max_exp)))
    elif kind == "any":
        bound = min(10.0**max_exp, FMAX)
        finite = st.floats(-bound, bound, allow_nan=False, allow_infinity=False)
        lo, hi = sorted([draw(finite), draw(finite)])
    elif kind == "degenerate":
        lo = hi = draw(_centers(max_exp))
    elif kind == "huge":
        bound = min(10.0**max_exp, FMAX)
        ends = st.sampled_from([-bound, -bound / 2, 0.0, bound / 2, bound]) | st.floats(
            -bound, bound
        )
        lo, hi = sorted([draw(ends), draw(ends)])
    else:
        # the floats next to a true extremum of sin/cos, phase + 2 pi n
        e = draw(st.integers(0, min(max_exp, 15)))
        n = draw(st.integers(-(10**e), 10**e))
        exact = draw(st.integers(0, 3)) * HALF_PI + TWO_PI * n
        lo = _steps(_floor_float(exact), -draw(st.integers(0, 2)))
        hi = _steps(_ceil_float(exact), draw(st.integers(0, 2)))
    lo, hi = _finite(lo), _finite(hi)
    assert lo <= hi
    return lo, hi


def _intervals(
    bounds: st.SearchStrategy[tuple[float, float]] | None = None, max_size: int = 4
) -> st.SearchStrategy[list[tuple[float, float]]]:
    return st.lists(_bounds() if bounds is None else bounds, min_size=1, max_size=max_size)


@st.composite
def _pairs(
    draw: st.DrawFn,
    left: st.SearchStrategy[tuple[float, float]] | None = None,
    right: st.SearchStrategy[tuple[float, float]] | None = None,
) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
    n = draw(st.integers(1, 4))
    a = draw(st.lists(_bounds() if left is None else left, min_size=n, max_size=n))
    b = draw(st.lists(_bounds() if right is None else right, min_size=n, max_size=n))
    return a, b


@st.composite
def _nonzero_bounds(draw: st.DrawFn, max_exp: int = 308) -> tuple[float, float]:
    """An interval not containing 0, of either sign."""
    lo, hi = draw(_bounds(max_exp))
    a, b = sorted([abs(lo), abs(hi)])
    a = a if a > 0 else min(TINY, b) if b > 0 else TINY
    b = max(a, b)
    return (-b, -a) if draw(st.booleans()) else (a, b)


@st.composite
def _zero_bounds(draw: st.DrawFn) -> tuple[float, float]:
    """An interval containing 0 (possibly at an end)."""
    lo, hi = draw(_bounds())
    return min(lo, 0.0), max(hi, 0.0)


TS = st.lists(st.floats(0.0, 1.0), max_size=3)
NUMBERS = st.one_of(
    st.floats(-FMAX, FMAX, allow_nan=False, allow_infinity=False),
    _signed(_magnitudes()),
    st.sampled_from([0.0, -0.0, 1.0, -1.0, 3.0, 0.1, TINY]),
)


# ---------------------------------------------------------------- + - * /
def _check_binary(a_b, b_b, ts, result: Interval, exact) -> None:
    _well_formed(result, len(a_b))
    for i, ((alo, ahi), (blo, bhi)) in enumerate(zip(a_b, b_b, strict=True)):
        lo, hi = float(result.lo[i]), float(result.hi[i])
        for pa in _points(alo, ahi, ts):
            for pb in _points(blo, bhi, ts):
                v = exact(Fraction(pa), Fraction(pb))
                assert _in(v, lo, hi), (i, pa, pb, float(v), lo, hi)


@SETTINGS
@given(_pairs(), TS)
def test_add_sub_mul_enclose_exact_values(pair, ts):
    a_b, b_b = pair
    a, b = _arrays(a_b), _arrays(b_b)
    with quiet_overflow():  # overflow warnings are tested on their own
        add, sub, mul, add_neg = a + b, a - b, a * b, a + (-b)
    _check_binary(a_b, b_b, ts, add, lambda x, y: x + y)
    _check_binary(a_b, b_b, ts, sub, lambda x, y: x - y)
    _check_binary(a_b, b_b, ts, mul, lambda x, y: x * y)
    _check_binary(a_b, [(-h, -lo) for lo, h in b_b], ts, add_neg, lambda x, y: x + y)


@SETTINGS
@given(_pairs(right=_nonzero_bounds()), TS)
def test_division_encloses_exact_values(pair, ts):
    a_b, b_b = pair
    a, b = _arrays(a_b), _arrays(b_b)
    with quiet_overflow():
        r = a / b
    _check_binary(a_b, b_b, ts, r, lambda x, y: x / y)


@SETTINGS
@given(_pairs(right=_zero_bounds()))
def test_division_by_interval_holding_zero_is_unbounded(pair):
    a_b, b_b = pair
    with quiet_overflow():
        r = _arrays(a_b) / _arrays(b_b)
    _well_formed(r, len(a_b))
    for i, (alo, ahi) in enumerate(a_b):
        if alo == ahi == 0.0:
            continue  # 0 / y is 0 wherever defined
        assert r.lo[i] == -np.inf and r.hi[i] == np.inf, (a_b[i], b_b[i], r.lo[i], r.hi[i])


@SETTINGS
@given(_intervals(), NUMBERS, TS)
def test_operations_with_plain_numbers_on_either_side(a_b, c, ts):
    a = _arrays(a_b)
    cb = [(c, c)] * len(a_b)
    with quiet_overflow():
        cases = _plain_cases(a, a_b, c, cb)
    for r, left, right, exact in cases:
        _check_binary(left, right, ts, r, exact)


def _plain_cases(a, a_b, c, cb):
    cases = [
        (a + c, a_b, cb, lambda x, y: x + y),
        (c + a, a_b, cb, lambda x, y: x + y),
        (a - c, a_b, cb, lambda x, y: x - y),
        (c - a, cb, a_b, lambda x, y: x - y),
        (a * c, a_b, cb, lambda x, y: x * y),
        (c * a, a_b, cb, lambda x, y: x * y),
        (np.float64(c) * a, a_b, cb, lambda x, y: x * y),
        (a * np.float64(c), a_b, cb, lambda x, y: x * y),
        (np.float64(c) + a, a_b, cb, lambda x, y: x + y),
        (np.float64(c) - a, cb, a_b, lambda x, y: x - y),
        (2 * a, a_b, [(2.0, 2.0)] * len(a_b), lambda x, y: x * y),
    ]
    if c != 0:
        cases.append((a / c, a_b, cb, lambda x, y: x / y))
    return cases


@SETTINGS
@given(_intervals(), TS)
def test_operations_with_numpy_arrays(a_b, ts):
    a = _arrays(a_b)
    c = np.linspace(-1.5, 2.5, len(a_b))
    cb = [(float(x), float(x)) for x in c]
    with quiet_overflow():
        cases = [
            (a * c, a_b, cb, lambda x, y: x * y),
            (a + c, a_b, cb, lambda x, y: x + y),
            (a - c, a_b, cb, lambda x, y: x - y),
            (a / c, a_b, cb, lambda x, y: x / y),
        ]
    for r, left, right, exact in cases:
        _check_binary(left, right, ts, r, exact)


@pytest.mark.parametrize("op", ["add", "sub", "mul"])
def test_numpy_array_on_the_left_gives_an_interval(op):
    """``ndarray op Interval`` must be an Interval, as ``Interval op ndarray`` is.

    Without ``__array_ufunc__ = None`` numpy broadcasts the Interval as an
    object scalar and returns an object array of Intervals.
    """
    c = np.array([1.0, -2.0])
    x = Interval([1.0, 3.0], [2.0, 4.0])
    r = {"add": lambda: c + x, "sub": lambda: c - x, "mul": lambda: c * x}[op]()
    assert isinstance(r, Interval), type(r)
    exact = {
        "add": (c + x.lo, c + x.hi),
        "sub": (c - x.hi, c - x.lo),
        "mul": ([1.0, -8.0], [2.0, -6.0]),
    }
    assert np.all(r.lo <= exact[op][0]) and np.all(exact[op][1] <= r.hi)


def test_multiplication_by_zero_times_unbounded_is_zero():
    r = Interval([0.0, -1.0], [0.0, 2.0]) * Interval([-np.inf, 1.0], [np.inf, np.inf])
    assert r.lo[0] <= 0.0 <= r.hi[0] and abs(r.hi[0] - r.lo[0]) < 1e-300
    assert r.lo[1] == -np.inf and r.hi[1] == np.inf


@pytest.mark.parametrize(
    ("name", "op", "lo", "hi"),
    [
        ("add", lambda: Interval(FMAX) + Interval(FMAX), FMAX, np.inf),
        ("sub", lambda: Interval(-FMAX) - Interval(FMAX), -np.inf, -FMAX),
        ("mul", lambda: Interval(1e300) * Interval(1e300), FMAX, np.inf),
        ("mul_neg", lambda: Interval(-1e300) * Interval(1e300), -np.inf, -FMAX),
        ("square", lambda: square(Interval(1e300)), FMAX, np.inf),
        ("div_tiny", lambda: Interval(1.0) / Interval(1e-310), FMAX, np.inf),
        ("div_big", lambda: Interval(1e300) / Interval(1e-10), FMAX, np.inf),
        ("sin_all", lambda: sin(Interval(-FMAX, FMAX)), -1.0, 1.0),
        ("cos_all", lambda: cos(Interval(-FMAX, FMAX)), -1.0, 1.0),
        ("cos_top", lambda: cos(Interval(FMAX / 2, FMAX)), -1.0, 1.0),
    ],
)
def test_overflow_is_silent_and_unbounded(name, op, lo, hi):
    """Overflow is how a bound becomes infinite: no RuntimeWarning (warnings are errors here)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = op()
    assert r.lo[()] <= lo and r.hi[()] == hi, (name, r)


# ---------------------------------------------------------------- square, sqrt
@SETTINGS
@given(_intervals(), TS)
def test_square_encloses_exact_values(a_b, ts):
    with quiet_overflow():
        r = square(_arrays(a_b))
        xx = _arrays(a_b) * _arrays(a_b)
    _well_formed(r, len(a_b))
    assert np.all(r.lo >= 0.0)
    for i, (lo, hi) in enumerate(a_b):
        for p in _points(lo, hi, ts):
            assert _in(Fraction(p) ** 2, float(r.lo[i]), float(r.hi[i])), (p, r[i])
        if lo <= 0.0 <= hi:
            assert r.lo[i] == 0.0
        # tighter than x * x: never wider
        assert r.lo[i] >= xx.lo[i] and r.hi[i] <= xx.hi[i]


@SETTINGS
@given(_intervals(_zero_bounds() | _bounds()), TS)
def test_sqrt_encloses_exact_values(a_b, ts):
    a_b = [(lo, hi) if hi >= 0 else (-hi, -lo) for lo, hi in a_b]  # non-empty non-negative part
    r = sqrt(_arrays(a_b))
    _well_formed(r, len(a_b))
    assert np.all(r.lo >= 0.0)
    for i, (lo, hi) in enumerate(a_b):
        rlo, rhi = Fraction(float(r.lo[i])), float(r.hi[i])
        for p in _points(max(lo, 0.0), hi, ts):
            # rlo <= sqrt(p) <= rhi  <=>  rlo**2 <= p <= rhi**2 for rlo, rhi >= 0
            assert rlo**2 <= Fraction(p), (p, r[i])
            assert rhi == math.inf or Fraction(p) <= Fraction(rhi) ** 2, (p, r[i])
            assert r.lo[i] <= np.sqrt(p) <= r.hi[i]
        if lo <= 0.0:
            assert r.lo[i] == 0.0


def test_sqrt_of_negative_interval_is_nan():
    r = sqrt(Interval([-2.0, -1.0, -TINY], [-1.0, 0.0, 4.0]))
    assert math.isnan(r.hi[0])
    assert r.lo[1] == 0.0 and 0.0 <= r.hi[1] < 1e-300
    assert r.lo[2] == 0.0 and r.hi[2] >= 2.0


# ---------------------------------------------------------------- sin, cos
#: floats around a true extremum of sin or cos that the enclosures missed
EXTREMUM_BETWEEN_FLOATS = [
    ("cos", -1.0, 102884739803.811, 102884739803.81102),
    ("sin", 1.0, 5600124843591.095, 5600124843591.096),
    ("sin", -1.0, 102319193217.56374, 102319193217.56375),
]


def _check_trig(a_b: list[tuple[float, float]], ts: list[float]) -> None:
    x = _arrays(a_b)
    for name, f, fn, max_phase in [
        ("sin", sin, np.sin, HALF_PI),
        ("cos", cos, np.cos, Fraction(0)),
    ]:
        with quiet_overflow():
            r = f(x)
        _well_formed(r, len(a_b))
        assert np.all(r.lo >= -1.0) and np.all(r.hi <= 1.0)
        for i, (lo, hi) in enumerate(a_b):
            rlo, rhi = r.lo[i], r.hi[i]
            pts = np.array(_points(lo, hi, ts, trig=True))
            vals = fn(pts)
            assert np.all((rlo <= vals) & (vals <= rhi)), (name, lo, hi, pts, vals, rlo, rhi)
            # the exact extrema: an extremum in the real interval must be reached
            if Fraction(hi) - Fraction(lo) >= TWO_PI:
                assert rlo == -1.0 and rhi == 1.0, (name, lo, hi)
                continue
            if _extremum_points(lo, hi, max_phase, limit=1):
                assert rhi == 1.0, (name, "max", lo, hi, rlo, rhi)
            if _extremum_points(lo, hi, max_phase + PI, limit=1):
                assert rlo == -1.0, (name, "min", lo, hi, rlo, rhi)


@SETTINGS
@given(_intervals(), TS)
@example([EXTREMUM_BETWEEN_FLOATS[0][2:]], [])
@example([EXTREMUM_BETWEEN_FLOATS[1][2:]], [])
@example([EXTREMUM_BETWEEN_FLOATS[2][2:]], [])
def test_sin_cos_enclose_values_and_reach_extrema(a_b, ts):
    _check_trig(a_b, ts)


@SETTINGS
@given(_intervals(_bounds(max_exp=2) | _bounds(max_exp=16)), TS)
def test_sin_cos_moderate_arguments(a_b, ts):
    _check_trig(a_b, ts)


@st.composite
def _near_large_extremum(draw: st.DrawFn) -> tuple[float, float]:
    """The floats around ``k pi / 2 + 2 pi n`` for ``|n|`` in 1e7 .. 1e14."""
    n = draw(st.integers(10**7, 10**14)) * draw(st.sampled_from([-1, 1]))
    exact = draw(st.integers(0, 3)) * HALF_PI + TWO_PI * n
    return _floor_float(exact), _steps(_ceil_float(exact), draw(st.integers(0, 1)))


@SETTINGS
@given(st.lists(_near_large_extremum(), min_size=4, max_size=4), TS)
@example([(12453499363.545256, 12453499363.54526), (5631904500.336218, 5631904500.33622)], [])
def test_sin_cos_reach_extrema_at_large_arguments(a_b, ts):
    _check_trig(a_b, ts)


@pytest.mark.parametrize(("name", "extremum", "lo", "hi"), EXTREMUM_BETWEEN_FLOATS)
def test_sin_cos_extremum_between_adjacent_floats(name, extremum, lo, hi):
    """The true extremum lies strictly between two adjacent floats: it must be in the enclosure."""
    assert math.nextafter(lo, math.inf) == hi
    phase = (HALF_PI if name == "sin" else Fraction(0)) + (PI if extremum < 0 else 0)
    assert _extremum_points(lo, hi, phase), "the interval holds a true extremum"
    r = (sin if name == "sin" else cos)(Interval(lo, hi))
    bound = r.hi[()] if extremum > 0 else r.lo[()]
    assert bound == extremum, (name, lo, hi, r.lo[()], r.hi[()])


@SETTINGS
@given(
    st.floats(-1e4, 1e4, allow_nan=False, allow_infinity=False),
    st.integers(0, 3) | st.floats(0.0, 1e-6),
)
def test_sin_cos_tight_on_tiny_intervals(c, w):
    """Width at most the interval width (both are 1-Lipschitz) plus a few 1e-15: the
    library's error and the outward rounding, a few ulps of the values."""
    if isinstance(w, int):
        lo, hi = c, _steps(c, w)
    else:
        lo, hi = c, c + w
    for f in (sin, cos):
        r = f(Interval(lo, hi))
        assert r.hi[()] - r.lo[()] <= (hi - lo) + 6e-15, (f, lo, hi, r)


@SETTINGS
@given(st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False), st.floats(2 * math.pi, 1e3))
def test_sin_cos_of_wide_intervals_are_whole(c, w):
    r_s, r_c = sin(Interval(c, c + w)), cos(Interval(c, c + w))
    assert r_s.lo[()] == r_c.lo[()] == -1.0 and r_s.hi[()] == r_c.hi[()] == 1.0


def test_sin_cos_at_multiples_of_half_pi():
    m = np.arange(-8, 9)
    x = Interval(m * (np.pi / 2))
    s, c = sin(x), cos(x)
    np.testing.assert_array_less(s.lo, np.sin(m * np.pi / 2) + 1e-15)
    np.testing.assert_array_less(np.sin(m * np.pi / 2) - 1e-15, s.hi)
    np.testing.assert_array_less(c.lo, np.cos(m * np.pi / 2) + 1e-15)
    np.testing.assert_array_less(np.cos(m * np.pi / 2) - 1e-15, c.hi)
    assert np.all(s.width < 6e-15) and np.all(c.width < 6e-15)


# ---------------------------------------------------------------- arccos
@st.composite
def _acos_bounds(draw: st.DrawFn) -> tuple[float, float]:
    kind = draw(st.sampled_from(["inside", "near_end", "across", "general"]))
    if kind == "inside":
        lo, hi = sorted([draw(st.floats(-1.0, 1.0)), draw(st.floats(-1.0, 1.0))])
    elif kind == "near_end":
        end = draw(st.sampled_from([-1.0, 1.0]))
        lo = _steps(end, -draw(st.integers(0, 3)))
        hi = _steps(end, draw(st.integers(0, 3)))
    elif kind == "across":
        lo = draw(st.floats(-3.0, 1.0))
        hi = draw(st.floats(max(lo, -1.0), 3.0))
    else:
        lo, hi = draw(_bounds())
        lo, hi = min(lo, 1.0), max(hi, -1.0)  # meets [-1, 1]
    return lo, hi


@SETTINGS
@given(_intervals(_acos_bounds()), TS)
def test_arccos_encloses_values_inside_domain(a_b, ts):
    r = arccos(_arrays(a_b))
    _well_formed(r, len(a_b))
    assert np.all(r.lo >= 0.0)
    for i, (lo, hi) in enumerate(a_b):
        clo, chi = max(lo, -1.0), min(hi, 1.0)
        assert clo <= chi
        assert Fraction(float(r.hi[i])) <= PI + Fraction(1, 10**15)  # within [0, pi] up to ulps
        pts = np.array(_points(clo, chi, ts))
        vals = np.arccos(pts)
        assert np.all((r.lo[i] <= vals) & (vals <= r.hi[i])), (lo, hi, pts, vals, r[i])
        if clo == -1.0:
            assert Fraction(float(r.hi[i])) >= PI  # arccos(-1) = pi, above float pi
        if chi == 1.0:
            assert r.lo[i] <= 0.0


# ---------------------------------------------------------------- arctan2
@st.composite
def _boxes(draw: st.DrawFn) -> tuple[tuple[float, float], tuple[float, float]]:
    """(y, x) bounds: small or large boxes in every quadrant, across axes, over the origin."""
    kind = draw(st.sampled_from(["general", "small", "axis", "origin", "cut", "halfplane"]))
    if kind == "general":
        return draw(_bounds()), draw(_bounds())
    if kind == "small":
        angle = draw(st.floats(-math.pi, math.pi))
        radius = draw(_magnitudes(-100, 100))
        cy, cx = radius * math.sin(angle), radius * math.cos(angle)
        w = radius * draw(st.sampled_from([0.0, 1e-12, 1e-6, 1e-3, 0.1]))
        return (cy - w, cy + w), (cx - w, cx + w)
    if kind == "axis":  # a degenerate coordinate on an axis
        zero = draw(st.sampled_from([0.0, -0.0]))
        other = draw(_bounds())
        return ((zero, zero), other) if draw(st.booleans()) else (other, (zero, zero))
    if kind == "origin":
        return draw(_zero_bounds()), draw(_zero_bounds())
    if kind == "cut":  # x <= 0, y across 0 (or touching it)
        lo, hi = draw(_bounds())
        x = (min(lo, 0.0), min(hi, 0.0)) if hi > lo else (-abs(lo), -abs(lo))
        return draw(_zero_bounds()), x
    # half-planes: y of one sign, x anything
    y = draw(_nonzero_bounds())
    return y, draw(_bounds())


@SETTINGS
@given(st.lists(_boxes(), min_size=1, max_size=4), TS)
def test_arctan2_encloses_values(boxes, ts):
    y_b = [b[0] for b in boxes]
    x_b = [b[1] for b in boxes]
    r = arctan2(_arrays(y_b), _arrays(x_b))
    _well_formed(r, len(boxes))
    for i, ((ylo, yhi), (xlo, xhi)) in enumerate(boxes):
        rlo, rhi = r.lo[i], r.hi[i]
        # within [-pi, pi] up to the outward rounding (4 ulps)
        assert Fraction(float(rlo)) >= -PI - Fraction(2, 10**15)
        assert Fraction(float(rhi)) <= PI + Fraction(2, 10**15)
        py = np.array(_points(ylo, yhi, ts))
        px = np.array(_points(xlo, xhi, ts))
        vals = np.arctan2(py[:, None], px[None, :])
        assert np.all((rlo <= vals) & (vals <= rhi)), (boxes[i], rlo, rhi)
        on_cut = xlo <= 0.0 and ylo <= 0.0 <= yhi  # holds a point (x <= 0, y = 0)
        if on_cut:
            # the angles of such boxes approach -pi and pi (or are undefined at 0)
            assert Fraction(float(rlo)) <= -PI and Fraction(float(rhi)) >= PI, (boxes[i], r[i])


def test_arctan2_quadrants_and_cut():
    y = Interval([1.0, 1.0, -2.0, -2.0, -1.0, -1.0, 0.0], [2.0, 2.0, -1.0, -1.0, 1.0, 1.0, 0.0])
    x = Interval([1.0, -2.0, -2.0, 1.0, 1.0, -2.0, 1.0], [2.0, -1.0, -1.0, 2.0, 2.0, -1.0, 2.0])
    r = arctan2(y, x)
    expected = [
        (math.atan2(1, 2), math.atan2(2, 1)),
        (math.atan2(2, -1), math.atan2(1, -2)),
        (math.atan2(-1, -2), math.atan2(-2, -1)),
        (math.atan2(-2, 1), math.atan2(-1, 2)),
        (math.atan2(-1, 1), math.atan2(1, 1)),
        (-math.pi, math.pi),
        (0.0, 0.0),
    ]
    for i, (elo, ehi) in enumerate(expected):
        assert r.lo[i] <= elo and ehi <= r.hi[i], (i, r[i])
        assert (r.hi[i] - r.lo[i]) - (ehi - elo) < 1e-14 * max(1.0, ehi - elo), (i, r[i])


@SETTINGS
@given(
    st.floats(-math.pi, math.pi),
    _magnitudes(-100, 100),
    st.floats(1e-12, 1e-3),
    st.floats(1e-12, 1e-3),
)
def test_arctan2_tight_away_from_cut(angle, radius, wy, wx):
    """A small box away from the cut: width close to its true angular width."""
    cy, cx = radius * math.sin(angle), radius * math.cos(angle)
    y = Interval(cy - wy * radius, cy + wy * radius)
    x = Interval(cx - wx * radius, cx + wx * radius)
    if (x.lo <= 0) & (y.lo <= 0) & (y.hi >= 0):
        return  # on the cut
    corners = np.arctan2(np.array([y.lo, y.lo, y.hi, y.hi]), np.array([x.lo, x.hi, x.lo, x.hi]))
    true_width = corners.max() - corners.min()
    r = arctan2(y, x)
    assert r.lo[()] <= corners.min() and corners.max() <= r.hi[()]
    # the library's error and the outward rounding: a few ulps of the angle
    assert r.hi[()] - r.lo[()] <= true_width * (1 + 1e-12) + 2e-14, (angle, radius, r, true_width)


# ---------------------------------------------------------------- hull, mid, predicates
@SETTINGS
@given(_pairs(), TS)
def test_hull_is_smallest_enclosure(pair, ts):
    a_b, b_b = pair
    a, b = _arrays(a_b), _arrays(b_b)
    h = hull(a, b)
    _well_formed(h, len(a_b))
    np.testing.assert_array_equal(h.lo, np.minimum(a.lo, b.lo))
    np.testing.assert_array_equal(h.hi, np.maximum(a.hi, b.hi))
    for i in range(len(a_b)):
        for lo, hi in (a_b[i], b_b[i]):
            assert all(h[i].contains(p) for p in _points(lo, hi, ts))


@SETTINGS
@given(_intervals(), TS)
def test_mid_contains_and_sign_predicates(a_b, ts):
    x = _arrays(a_b)
    m = x.mid
    assert np.all(np.isfinite(m)) and np.all(x.lo <= m) and np.all(m <= x.hi)
    assert np.all(x.contains(m))
    with quiet_overflow():
        np.testing.assert_array_equal(x.width, x.hi - x.lo)
    pos, neg = x.positive(), x.negative()
    assert not np.any(pos & neg)
    for i, (lo, hi) in enumerate(a_b):
        pts = _points(lo, hi, ts)
        assert x[i].contains(pts).all()
        assert x.contains(np.full(len(a_b), lo))[i]
        if lo > -FMAX:
            assert not x[i].contains(math.nextafter(lo, -math.inf))
        if hi < FMAX:
            assert not x[i].contains(math.nextafter(hi, math.inf))
        assert pos[i] == all(p > 0 for p in pts) == (lo > 0)
        assert neg[i] == all(p < 0 for p in pts) == (hi < 0)
        # negation is exact
        assert (-x).lo[i] == -hi and (-x).hi[i] == -lo


def test_construction_broadcasting_and_indexing():
    x = Interval([1.0, 2.0, 3.0], 4.0)
    assert x.shape == (3,)
    np.testing.assert_array_equal(x.hi, [4.0, 4.0, 4.0])
    d = Interval([1.0, 2.0])
    np.testing.assert_array_equal(d.lo, d.hi)
    assert as_interval(x) is x
    y = x[1:]
    assert y.shape == (2,) and y.lo[0] == 2.0
    z = Interval(np.zeros((2, 3)), np.ones((2, 3)))
    assert (z + z * 2.0).shape == (2, 3)


# ------------------------------------------------------- outward rounding
def _nextafter_times(x: np.ndarray, ulps: int, towards: float) -> np.ndarray:
    with np.errstate(over="ignore"):
        for _ in range(ulps):
            x = np.nextafter(x, towards)
    return x


EDGES = np.concatenate(
    [
        2.0 ** np.arange(-1074, 1024),
        -(2.0 ** np.arange(-1074, 1024)),
        np.nextafter(2.0 ** np.arange(-1070, 1023), 0.0),
        [0.0, -0.0, np.inf, -np.inf, 5e-324, -5e-324, np.finfo(float).max, -np.finfo(float).max],
    ]
)


@pytest.mark.parametrize("ulps", [1, 2, 4])
def test_compiled_widening_is_at_least_repeated_nextafter(ulps):
    """The one-pass widening moves every float at least ``ulps`` floats outwards:
    powers of two (where the spacing halves below), subnormals, zeros, the
    largest floats and the infinities of an overflow."""
    from moveability.intervals import widen_down, widen_up

    rng = np.random.default_rng(ulps)
    x = np.concatenate([EDGES, rng.normal(size=20000) * 10.0 ** rng.integers(-320, 308, 20000)])
    assert (widen_down(x, ulps) <= _nextafter_times(x, ulps, -np.inf)).all()
    assert (widen_up(x, ulps) >= _nextafter_times(x, ulps, np.inf)).all()
    assert np.isnan(widen_down(np.array([np.nan]), ulps)).all()


@given(st.floats(allow_nan=False), st.integers(1, 6))
def test_compiled_widening_on_any_float(x, ulps):
    from moveability.intervals import widen_down, widen_up

    a = np.array([x])
    assert widen_down(a, ulps)[0] <= _nextafter_times(a, ulps, -np.inf)[0]
    assert widen_up(a, ulps)[0] >= _nextafter_times(a, ulps, np.inf)[0]
    # a sum keeps an exact zero, and is widened by one float at least otherwise
    total = Interval(a) + Interval(np.zeros(1))
    if x == 0:
        assert total.lo[0] == 0 and total.hi[0] == 0
    else:
        assert total.lo[0] <= _nextafter_times(a, 1, -np.inf)[0]
        assert total.hi[0] >= _nextafter_times(a, 1, np.inf)[0]
