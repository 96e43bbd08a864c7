"""The compiled tapes of user-defined expressions give the interpreted bounds, bit for bit.

Every leg function of the custom five-bar (constraint and derivatives), and
expressions with constants, rationals, pi, negation, squares straddling 0 and
derived inputs of the pose, evaluated on random boxes mixing ordinary numbers,
zeros, infinities and NaN: :func:`moveability.mechanisms.tape.run` against the
same function on :class:`~moveability.intervals.Interval` operands. Expressions
the tape cannot record (a division, sqrt of a computed value) have no tape.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import sympy

from moveability import load_spec
from moveability.intervals import Interval
from moveability.mechanisms import from_spec
from moveability.mechanisms import tape as tp
from moveability.mechanisms.custom import BoundExpression, compile_expression

SPECIAL = np.array([0.0, -0.0, np.inf, -np.inf, np.nan, 1e-170, -1e308, 1.0])


def boxes(rng: np.random.Generator, n: int, k: int, scale: float) -> tuple[np.ndarray, ...]:
    a = rng.normal(size=(n, k)) * scale
    b = a + np.abs(rng.normal(size=(n, k))) * rng.choice([0.0, 1e-9, 0.1, 3.0], size=(n, k))
    for x in (a, b):
        m = rng.random((n, k)) < 0.05
        x[m] = rng.choice(SPECIAL, size=int(m.sum()))
    return np.minimum(a, b), np.maximum(a, b)


def same(x: Interval, y: Interval) -> bool:
    return np.array_equal(x.lo, y.lo, equal_nan=True) and np.array_equal(x.hi, y.hi, equal_nan=True)


def interpreted(g, lo, hi, box, q: Interval) -> Interval:
    coords = [Interval(lo[box, j], hi[box, j]) for j in range(lo.shape[1])]
    with np.errstate(all="ignore"):
        v = g(*coords, q)
    v = v if isinstance(v, Interval) else Interval(v)
    return Interval(np.broadcast_to(v.lo, box.shape), np.broadcast_to(v.hi, box.shape))


def check(g, k: int, seed: int, scale: float = 10.0) -> None:
    assert g.tape is not None
    rng = np.random.default_rng(seed)
    lo, hi = boxes(rng, 300, k, scale)
    box = rng.integers(0, 300, size=700)
    q_lo, q_hi = boxes(rng, 700, 1, 3.0)
    q = Interval(q_lo[:, 0], q_hi[:, 0])
    with np.errstate(all="ignore"):
        compiled = tp.run(g.tape, lo, hi, box, q)
    assert same(compiled, interpreted(g, lo, hi, box, q))


@pytest.mark.parametrize("seed", range(3))
def test_custom_five_bar_legs(seed: int) -> None:
    mechanism = from_spec(load_spec("examples/five-bar-custom.toml"))
    for leg in mechanism.legs:
        for g in (leg.f, leg.df_dq, leg.d2f_dq2, *leg.df_dx):
            check(g, 2, seed)


X, Y, Q, A = sympy.symbols("x y q a", real=True)
TRACED = [
    (X - A * sympy.cos(Q)) ** 2 + (Y - A * sympy.sin(Q)) ** 2 - A**2,
    -X * Y + sympy.Rational(1, 3) * Q - sympy.pi * sympy.sin(Q) * sympy.cos(Q),
    sympy.Float(0.1) * X**2 - 7 * Y * Q + 2,
    sympy.sqrt(X) * sympy.exp(Q) + sympy.atan2(Y, X) * Y,  # functions of inputs: derived
    A * 3,  # a constant
]


@pytest.mark.parametrize("expr", TRACED, ids=range(len(TRACED)))
def test_expressions_with_constants_and_derived_inputs(expr) -> None:
    g = BoundExpression(compile_expression(expr, [X, Y, Q, A]), [2.5], 2)
    for seed in range(2):
        check(g, 2, seed)


@pytest.mark.parametrize(
    "expr", [X / (Y + 3), sympy.sqrt(X + Y) * Q, (X + Q) ** 3], ids=["div", "sqrt", "cube"]
)
def test_untraceable_expressions_have_no_tape(expr) -> None:
    g = BoundExpression(compile_expression(expr, [X, Y, Q, A]), [2.5], 2)
    assert g.tape is None
    q = Interval(np.array([0.1]), np.array([0.2]))
    assert np.isfinite(g(Interval([1.0], [1.5]), Interval([2.0], [2.5]), q).lo).all()


def test_sine_and_cosine_of_points_match_the_interval_functions() -> None:
    from moveability import intervals as iv
    from moveability.mechanisms import expressions as ex

    rng = np.random.default_rng(7)
    x = np.concatenate([
        rng.normal(size=2000) * 10.0 ** rng.integers(-20, 20, size=2000),
        SPECIAL,
        np.pi * np.arange(-8, 9) / 2,  # the extrema, where the bounds become -1 or 1
        np.nextafter(np.pi * np.arange(-8, 9) / 2, np.inf),
    ])  # fmt: skip
    p = ex.points(x)
    assert same(ex.sin(p), iv.sin(Interval(x)))
    assert same(ex.cos(p), iv.cos(Interval(x)))


@pytest.mark.parametrize("seed", range(2))
def test_compiled_contraction_matches_the_interpreted_one(seed: int, monkeypatch) -> None:
    """``ConstraintLeg.reach`` of the custom five-bar's legs over random boxes: the
    branch enclosures of the compiled contraction equal those of the Python loop."""
    mechanism = from_spec(load_spec("examples/five-bar-custom.toml"))
    rng = np.random.default_rng(seed)
    centre = rng.uniform([-14.0, -14.0], [22.0, 14.0], size=(400, 2))
    size = rng.choice([1e-3, 0.05, 0.5, 2.0], size=(400, 1))
    lo, hi = centre - size, centre + size
    for leg in mechanism.legs:
        compiled = leg.reach(lo, hi)
        with monkeypatch.context() as m:
            m.setattr(tp, "trig_kinds", lambda tape: None)
            plain = leg.reach(lo, hi)
        assert (compiled.status == plain.status).all()
        assert (compiled.status == 1).sum() > 50  # many regular boxes, contracted
        for a, b in zip(compiled.branches, plain.branches, strict=True):
            assert same(a, b)


@pytest.mark.parametrize(
    ("expr_of", "values"),
    [
        # the float a*b - c is 0 where the real one is about 1e-17
        (lambda a, b, c: a * b - c, [1.947, 0.882, 1.947 * 0.882]),
        (lambda a, b, c: a * b - c, [0.219, 0.148, 0.219 * 0.148]),
        (lambda a, b, c: a**2 - b * c, [1.234, 2.345, 1.234 * 1.234 / 2.345]),
    ],
)
def test_operations_among_parameters_are_rounded_outwards(expr_of, values) -> None:
    """Operations among parameters alone give no float: the enclosure of ``x *
    f(a, b, c)`` at x = 1, interpreted and compiled alike, holds the exact
    value of the parameters' floats (compared as fractions)."""
    from fractions import Fraction

    x, q, a, b, c = sympy.symbols("x q a b c", real=True)
    f = compile_expression(x * expr_of(a, b, c) + 0 * q, [x, q, a, b, c])
    g = BoundExpression(f, values, 1)
    exact = expr_of(*(Fraction(v) for v in values))
    one = np.ones((1, 1))
    at = np.zeros(1, dtype=np.int64)
    q_box = Interval(np.zeros(1))
    for value in (interpreted(g, one, one, at, q_box), tp.run(g.tape, one, one, at, q_box)):
        assert Fraction(float(value.lo[0])) <= exact <= Fraction(float(value.hi[0]))


PRISMATIC = {
    "mechanism": "custom",
    "pose": ["x", "y"],
    "joints": ["d"],
    "legs": [{"joint": "d", "kind": "prismatic", "constraint": "x**2 + (y - 1)**2 - d**2"}],
    "limits": {"d": [2.0, 6.0]},
    "bounds": {"x": [-8, 8], "y": [-8, 8]},
}


@pytest.mark.parametrize(
    ("source", "seed", "depth"),
    [
        ("examples/five-bar-custom.toml", 0, None),
        ("examples/delta-custom.toml", 1, None),
        ("prismatic", 2, None),
        # levels 10 and 11 have more pieces than a level's table holds
        ("examples/five-bar-custom.toml", 3, 11),
    ],
)
def test_compiled_isolation_matches_the_interpreted_one(source, seed, depth, monkeypatch) -> None:
    """``ConstraintLeg._isolate`` (and ``reach``) of user-defined legs over random
    boxes (points, small and large ones, a few unbounded): the compiled levels
    (``tape.isolate_level``, each level's joint enclosures and their sines and
    cosines from the leg's table, or computed where it has none; the pieces of a
    certified sign tested at their ends there) give the pieces of the Python
    loop and its end test, bit for bit."""
    from dataclasses import replace

    from moveability.mechanisms import constraint_leg
    from moveability.mechanisms.constraint_leg import ConstraintLeg
    from moveability.mechanisms.custom import CustomMechanism

    if source == "prismatic":
        mechanism = CustomMechanism(PRISMATIC)
    else:
        mechanism = from_spec(load_spec(source))
    legs = [leg for leg in mechanism.legs if leg._compiled() is not None]
    assert legs
    if depth is not None:
        legs = [replace(leg, depth=depth) for leg in legs]
        assert legs[0]._level_table(depth) is None
        assert legs[0].pieces << (depth - 2) <= constraint_leg._TABLE_CAP
    rng = np.random.default_rng(seed)
    low, high = (np.asarray(b, dtype=float) for b in mechanism.bounds)
    k = low.size
    centre = rng.uniform(low, high, size=(600, k))
    size = rng.choice([0.0, 1e-3, 0.02, 0.3, 3.0], size=(600, 1)) * (high - low) / 10
    lo, hi = centre - size, centre + size
    lo[:5, 0], hi[5:10, -1] = -np.inf, np.inf
    def rows(pieces):
        return set(zip(pieces.box.tolist(), pieces.lo.tolist(), pieces.hi.tolist(), strict=True))

    for leg in legs:
        with np.errstate(all="ignore"):  # the unbounded boxes' centres
            compiled = (leg._root_pieces(lo, hi), leg.reach(lo, hi), leg._isolate(lo, hi))
            with monkeypatch.context() as m:
                m.setattr(ConstraintLeg, "_compiled", lambda self: None)
                plain = (leg._root_pieces(lo, hi), leg.reach(lo, hi), leg._isolate(lo, hi))
        for name in ("box", "lo", "hi", "mono", "finite"):
            a, b = getattr(compiled[0], name), getattr(plain[0], name)
            assert a.dtype == b.dtype and np.array_equal(a, b), name
        # the compiled levels test the ends themselves: they leave out pieces of
        # the Python loop's, only ones its end test leaves out too
        assert rows(plain[0]) <= rows(compiled[2]) <= rows(plain[2])
        assert compiled[2].tested.any() and not plain[2].tested.any()
        if source != "prismatic":  # (its enclosures leave out all those pieces first)
            assert rows(compiled[2]) != rows(plain[2])
        if depth is not None:
            # pieces of the levels without a table among them
            start, stop = leg._range
            widest_untabled = (stop - start) / leg.pieces / 2.0**9
            assert (compiled[0].hi - compiled[0].lo < widest_untabled).any()
        assert (compiled[0].mono != 0).sum() > 100 and (compiled[0].mono == 0).any()
        assert (compiled[1].status == plain[1].status).all()
        assert (compiled[1].fold_connected == plain[1].fold_connected).all()
        for a, b in zip(
            [*compiled[1].branches, compiled[1].hull],
            [*plain[1].branches, plain[1].hull],
            strict=True,
        ):
            assert same(a, b)


def rrr_boxes(rng: np.random.Generator, low: np.ndarray, high: np.ndarray, n: int):
    """Random boxes of (x, y, phi): small and large in x, y; phi boxes wide, thin,
    points, across -pi / pi (ends beyond the cut) and the whole turn."""
    centre = rng.uniform(low, high, size=(n, 3))
    size = rng.choice([0.0, 1e-3, 0.02, 0.3, 3.0], size=(n, 1)) * (high[:2] - low[:2]) / 10
    lo, hi = centre.copy(), centre.copy()
    lo[:, :2] -= size
    hi[:, :2] += size
    half = rng.choice([0.0, 1e-9, 1e-3, 0.05, 0.4, 1.5], size=n)
    phi = rng.uniform(-np.pi, np.pi, size=n)
    across = rng.random(n) < 0.15  # about the cut at -pi / pi
    phi[across] = rng.choice([-np.pi, np.pi], size=int(across.sum())) + rng.normal(
        scale=0.01, size=int(across.sum())
    )
    lo[:, 2], hi[:, 2] = phi - half, phi + half
    whole = rng.random(n) < 0.05
    lo[whole, 2], hi[whole, 2] = -np.pi, np.pi
    return lo, hi


@pytest.mark.parametrize("source", ["default", "examples/three-rrr.toml"])
def test_three_rrr_compiled_isolation_matches_the_interpreted_one(source, monkeypatch) -> None:
    """The 3-RRR's legs (tapes with derived inputs of the pose angle, sin and cos
    of phi): ``_root_pieces`` and ``reach`` of the compiled levels (their end
    tests among them) and contraction equal those of the Python loops with every
    function interpreted on Intervals,
    bit for bit, and ``tape.run`` equals the interpreted functions."""
    from moveability.mechanisms.constraint_leg import ConstraintLeg
    from moveability.mechanisms.three_rrr import ThreeRRR

    mechanism = ThreeRRR.default() if source == "default" else from_spec(load_spec(source))
    rng = np.random.default_rng(3 if source == "default" else 4)
    low, high = (np.asarray(b, dtype=float) for b in mechanism.bounds)
    lo, hi = rrr_boxes(rng, low, high, 500)
    for leg in mechanism.legs:
        assert leg._compiled() is not None and leg._compiled()[0].pose_derived
        compiled = (leg._root_pieces(lo, hi), leg.reach(lo, hi))
        with monkeypatch.context() as m:
            m.setattr(ConstraintLeg, "_compiled", lambda self: None)
            m.setattr(tp, "trig_kinds", lambda tape: None)  # the contraction's Python loop
            m.setattr(
                ConstraintLeg,
                "_box_eval",
                lambda self, g, lo, hi, box, q: self._eval(g, self._coords(lo, hi, box), q),
            )
            plain = (leg._root_pieces(lo, hi), leg.reach(lo, hi))
        for name in ("box", "lo", "hi", "mono", "finite"):
            a, b = getattr(compiled[0], name), getattr(plain[0], name)
            assert a.dtype == b.dtype and np.array_equal(a, b), name
        assert (compiled[0].mono != 0).sum() > 100 and (compiled[0].mono == 0).any()
        status = compiled[1].status
        assert (status == plain[1].status).all()
        assert len(set(status.tolist())) >= 3  # regular, out and fold or unknown boxes
        assert (status == 1).sum() > 50 and compiled[1].fold_connected.any()
        assert (compiled[1].fold_connected == plain[1].fold_connected).all()
        for a, b in zip(
            [*compiled[1].branches, compiled[1].hull],
            [*plain[1].branches, plain[1].hull],
            strict=True,
        ):
            assert same(a, b)
        box = rng.integers(0, lo.shape[0], size=900)
        q_lo, q_hi = boxes(rng, 900, 1, 3.0)
        q = Interval(q_lo[:, 0], q_hi[:, 0])
        for g in (leg.f, leg.df_dq, leg.d2f_dq2, *leg.df_dx):
            with np.errstate(all="ignore"):
                assert same(tp.run(g.tape, lo, hi, box, q), interpreted(g, lo, hi, box, q))


def reach_both_folds(leg, lo, hi, monkeypatch) -> tuple[Any, list[tuple[np.ndarray, np.ndarray]]]:
    """``leg.reach(lo, hi)`` with every ``ConstraintLeg._fold`` call checked bit for
    bit against ``_fold_interpreted``, and with no compiled fold at all (the same
    statuses and fold connectivity asserted): the former, and the certificates of
    its ``_fold`` calls."""
    from moveability.mechanisms.constraint_leg import ConstraintLeg

    seen: list[tuple[np.ndarray, np.ndarray]] = []
    compiled_fold = ConstraintLeg._fold

    def both(self, lo, hi, runs, boxes, r, ends=None):
        got = compiled_fold(self, lo, hi, runs, boxes, r, ends)
        want = self._fold_interpreted(lo, hi, runs, boxes, r)
        assert got[0].dtype == want[0].dtype and np.array_equal(got[0], want[0])
        assert got[1].dtype == want[1].dtype and np.array_equal(got[1], want[1])
        seen.append(got)
        return got

    with monkeypatch.context() as m:
        m.setattr(ConstraintLeg, "_fold", both)
        compiled = leg.reach(lo, hi)
    with monkeypatch.context() as m:
        m.setattr(ConstraintLeg, "_fold_programs", lambda self: None)
        plain = leg.reach(lo, hi)
    assert (compiled.status == plain.status).all()
    assert (compiled.fold_connected == plain.fold_connected).all()
    return compiled, seen


@pytest.mark.parametrize("source", ["default", "examples/three-rrr.toml"])
def test_three_rrr_compiled_fold_matches_the_interpreted_one(source, monkeypatch) -> None:
    """The fold certificates of the 3-RRR's legs (``ConstraintLeg._fold``: one
    kernel on the tapes and the float tape of F, ``_fold_kernels.fold``) equal
    those of ``_fold_interpreted`` on every call ``reach`` makes, bit for bit,
    over boxes of every kind (points, thin and wide ones, across -pi / pi, the
    whole turn) and boxes about the leg's outer and inner folds (``|B - A| =
    l1 + l2`` and ``|l1 - l2|``), many of them folds, some fold-connected."""
    from moveability.mechanisms.three_rrr import ThreeRRR

    mechanism = ThreeRRR.default() if source == "default" else from_spec(load_spec(source))
    rng = np.random.default_rng(5 if source == "default" else 6)
    low, high = (np.asarray(b, dtype=float) for b in mechanism.bounds)
    seen: list[tuple[np.ndarray, np.ndarray]] = []
    for i, leg in enumerate(mechanism.legs):
        lo, hi = rrr_boxes(rng, low, high, 600)
        # poses whose B - A is on a fold circle, and boxes about them
        a, b = np.asarray(mechanism.base[i]), np.asarray(mechanism.platform[i])
        l1, l2 = mechanism.proximal[i], mechanism.distal[i]
        n = 800
        phi = rng.uniform(-np.pi, np.pi, n)
        angle = rng.uniform(-np.pi, np.pi, n)
        radius = np.where(np.arange(n) % 2 == 0, l1 + l2, abs(l1 - l2))
        u = radius[:, None] * np.stack([np.cos(angle), np.sin(angle)], axis=1)
        turned = np.stack(
            [np.cos(phi) * b[0] - np.sin(phi) * b[1], np.sin(phi) * b[0] + np.cos(phi) * b[1]],
            axis=1,
        )
        centre = np.column_stack([a + u - turned, phi])
        half = rng.choice([0.0, 1e-3, 0.01, 0.1], size=(n, 1)) * np.array([1.0, 1.0, 0.3])
        lo = np.concatenate([lo, centre - half])
        hi = np.concatenate([hi, centre + half])
        assert leg._fold_programs() is not None
        compiled, calls = reach_both_folds(leg, lo, hi, monkeypatch)
        seen.extend(calls)
        assert (compiled.status == 2).sum() > 50  # (the RR legs' folds are convex)
        assert compiled.fold_connected.sum() > 20
    assert sum(int(s[1].sum()) for s in seen) > 60


def signed_leg(sign: float):
    """A 3-RRR leg (A = (0, 10), b = (0, 3), lengths 7 and 5) with its constraint
    multiplied by ``sign``: its folds are convex, or concave with ``sign = -1``."""
    from moveability.mechanisms.constraint_leg import ConstraintLeg
    from moveability.mechanisms.three_rrr import _Taped

    def make(name):
        def functions(cos, sin):
            def uv(x, y, phi):
                return x - sin(phi) * 3.0, y + cos(phi) * 3.0 - 10.0

            def f(x, y, phi, q):
                u, v = uv(x, y, phi)
                return sign * ((u - 7.0 * cos(q)) ** 2 + (v - 7.0 * sin(q)) ** 2 - 25.0)

            def df_dq(x, y, phi, q):
                u, v = uv(x, y, phi)
                return sign * 14.0 * (u * sin(q) - v * cos(q))

            def d2f_dq2(x, y, phi, q):
                u, v = uv(x, y, phi)
                return sign * 14.0 * (u * cos(q) + v * sin(q))

            def df_dx(x, y, phi, q):
                u, _ = uv(x, y, phi)
                return sign * 2.0 * (u - 7.0 * cos(q))

            def df_dy(x, y, phi, q):
                _, v = uv(x, y, phi)
                return sign * 2.0 * (v - 7.0 * sin(q))

            def df_dphi(x, y, phi, q):
                u, v = uv(x, y, phi)
                du, dv = -(cos(phi) * 3.0), -(sin(phi) * 3.0)
                return sign * 2.0 * ((u - 7.0 * cos(q)) * du + (v - 7.0 * sin(q)) * dv)

            return locals()[name]

        return _Taped(functions)

    return ConstraintLeg(
        "q",
        f=make("f"),
        df_dq=make("df_dq"),
        d2f_dq2=make("d2f_dq2"),
        df_dx=(make("df_dx"), make("df_dy"), make("df_dphi")),
    )


@pytest.mark.parametrize("sign", [1.0, -1.0], ids=["convex", "concave"])
def test_compiled_fold_of_convex_and_concave_folds(sign, monkeypatch) -> None:
    """``_fold`` compiled and interpreted on a leg whose folds are convex (F at a
    minimum), or concave (-F): the same certificates, bit for bit, over boxes about
    its fold circles (points, thin and wide, across -pi / pi)."""
    leg = signed_leg(sign)
    rng = np.random.default_rng(8)
    n = 1500
    phi = rng.uniform(-np.pi, np.pi, n)
    phi[: n // 5] = rng.choice([-np.pi, np.pi], size=n // 5)  # about the cut
    angle = rng.uniform(-np.pi, np.pi, n)
    radius = np.where(np.arange(n) % 2 == 0, 12.0, 2.0) + rng.normal(scale=0.05, size=n)
    x = radius * np.cos(angle) + np.sin(phi) * 3.0
    y = radius * np.sin(angle) - np.cos(phi) * 3.0 + 10.0
    centre = np.column_stack([x, y, phi])
    half = rng.choice([0.0, 1e-3, 0.01, 0.1, 0.5], size=(n, 1)) * np.array([1.0, 1.0, 0.3])
    lo, hi = centre - half, centre + half
    compiled, seen = reach_both_folds(leg, lo, hi, monkeypatch)
    fold = 2 if sign > 0 else 3
    assert (compiled.status == fold).sum() > 100 and compiled.fold_connected.sum() > 50
    convexity = np.concatenate([s[0] for s in seen])
    assert (convexity == sign).sum() > 100 and not (convexity == -sign).any()


def test_three_rrr_rows_of_a_match_the_interpreted_functions() -> None:
    """``a_row_boxes`` of the 3-RRR's legs (the tapes of ``dF/dX_j``, the derived
    inputs of the pose computed once for the three) equals the functions on
    Intervals bit for bit, over boxes of every kind and over points (``lo is hi``)."""
    from moveability.mechanisms.three_rrr import ThreeRRR

    mechanism = ThreeRRR.default()
    rng = np.random.default_rng(9)
    low, high = (np.asarray(b, dtype=float) for b in mechanism.bounds)
    lo, hi = rrr_boxes(rng, low, high, 700)
    q_lo, q_hi = boxes(rng, 700, 1, 3.0)
    q = Interval(q_lo[:, 0], q_hi[:, 0])
    box = np.arange(700)
    for leg in mechanism.legs:
        for a, b in ((lo, hi), (lo, lo)):
            with np.errstate(all="ignore"):
                rows = leg.a_row_boxes(a, b, q)
                want = [interpreted(g, a, b, box, q) for g in leg.df_dx]
            assert all(same(x, y) for x, y in zip(rows, want, strict=True))


def float_tape_values(t: tp.Tape, columns: list[np.ndarray]) -> np.ndarray:
    """The float tape ``t`` run by numpy on the float arrays ``columns`` (the pose
    coordinates and the joint): its derived inputs by their functions, then its
    operations in order (a second reading of the tape, for the test)."""
    n = columns[0].size
    r = np.zeros((t.slots, n))
    with np.errstate(all="ignore"):
        for i, c in enumerate(columns):
            r[i] = c
        for d, (function, args) in enumerate(t.derived):
            r[t.k + 1 + d] = function(*(r[a] for a in args))
        first = t.k + 1 + len(t.derived)
        r[first : first + t.const_lo.size] = t.const_lo[:, None]
        for op, target, a, b in t.code:
            r[target] = [r[a] + r[b], r[a] - r[b], r[a] * r[b], -r[a], r[a] * r[a]][op]
    return r[t.out]


FLOAT_TRACED = [
    *TRACED,
    sympy.E * X - sympy.Float(0.3) * sympy.pi * Y**2 + sympy.Rational(-7, 9) * A**2 * Q,
    sympy.Abs(X) * Y - sympy.sign(Y) * sympy.tan(Q) + A * sympy.log(sympy.Abs(Q) + 1) * 0,
    (X * sympy.cos(Q) - Y * sympy.sin(Q)) ** 2 - (A + sympy.Rational(1, 10)) ** 2 * X,
]


@pytest.mark.parametrize("values", [[2.5], [0.1], [-3.7e-5]])
def test_float_tape_is_the_float_path(values) -> None:
    """``BoundExpression.float_tape`` records what the expression does on float
    arrays: run by numpy, it gives the float path's values bit for bit (NaN where
    it gives NaN), on arrays mixing ordinary numbers, zeros, infinities and NaN,
    for the custom five-bar's constraints and expressions with parameters,
    rationals, decimals, pi, e and functions of the inputs. Untraceable
    expressions have no float tape."""
    rng = np.random.default_rng(11)
    mechanism = from_spec(load_spec("examples/five-bar-custom.toml"))
    functions = [leg.f for leg in mechanism.legs]
    functions += [
        BoundExpression(compile_expression(e, [X, Y, Q, A]), values, 2) for e in FLOAT_TRACED
    ]
    for g in functions:
        t = g.float_tape
        assert t is not None and np.array_equal(t.const_lo, t.const_hi)
        columns = [rng.normal(size=3000) * 10.0 ** rng.integers(-3, 4, size=3000) for _ in range(3)]
        for c in columns:
            special = rng.random(c.size) < 0.03
            c[special] = rng.choice(SPECIAL, size=int(special.sum()))
        with np.errstate(all="ignore"):
            want = np.broadcast_to(np.asarray(g(*columns), dtype=np.float64), columns[0].shape)
        got = float_tape_values(t, columns)
        assert np.array_equal(got, want, equal_nan=True)
        assert np.isfinite(want).sum() > 1000  # (sqrt of x < 0 is NaN)
    for e in (X / (Y + 3), sympy.sqrt(X + Y) * Q, (X + Q) ** 3):
        assert BoundExpression(compile_expression(e, [X, Y, Q, A]), values, 2).float_tape is None


#: a five-bar written with equal links (its inner folds meet at the base points),
#: a decimal length, pi and a rational
EQUAL_LINKS = {
    "mechanism": "custom",
    "pose": ["x", "y"],
    "joints": ["t1", "t2"],
    "parameters": {"L0": 6.3, "L": 5.0},
    "legs": [
        {"joint": "t1", "constraint": "(x - L*cos(t1))**2 + (y - L*sin(t1))**2 - L**2"},
        {
            "joint": "t2",
            "constraint": "(x - L0 - (pi + 1/7)*cos(t2))**2 + (y - L*sin(t2))**2 - 0.1*L**2",
        },
    ],
    "limits": {"t1": [0.0, 3.0], "t2": [-2.0, 2.0]},
    "bounds": {"x": [-12, 18], "y": [-12, 12]},
}


@pytest.mark.parametrize(
    "source", ["examples/five-bar-custom.toml", "equal links", "examples/delta-custom.toml"]
)
def test_custom_compiled_fold_matches_the_interpreted_one(source, monkeypatch) -> None:
    """The fold certificates of user-defined legs, compiled (the interval tapes
    and ``F``'s float tape in one kernel) and interpreted (``_fold_interpreted``):
    the same on every call ``reach`` makes, bit for bit, over random boxes of
    every size, many of them folds, some fold-connected."""
    from moveability.mechanisms.custom import CustomMechanism

    if source == "equal links":
        mechanism = CustomMechanism(EQUAL_LINKS)
    else:
        mechanism = from_spec(load_spec(source))
    rng = np.random.default_rng(12)
    low, high = (np.asarray(b, dtype=float) for b in mechanism.bounds)
    k = low.size
    n_fold = n_connected = n_certified = 0
    legs = [leg for leg in mechanism.legs if leg._fold_programs() is not None]
    # (two of the Delta's legs have a derivative without a tape)
    assert len(legs) == (1 if "delta" in source else 2)
    for leg in legs:
        centre = rng.uniform(low, high, size=(2000, k))
        size = rng.choice([0.0, 1e-3, 0.01, 0.03, 0.1, 0.5], size=(2000, 1)) * (high - low) / 10
        compiled, seen = reach_both_folds(leg, centre - size, centre + size, monkeypatch)
        n_fold += int(np.isin(compiled.status, (2, 3)).sum())
        n_connected += int(compiled.fold_connected.sum())
        n_certified += sum(int((s[0] != 0).sum()) for s in seen)  # by the compiled fold
    assert n_fold > 50 and n_connected > 20 and n_certified >= n_fold, (n_fold, n_connected)
