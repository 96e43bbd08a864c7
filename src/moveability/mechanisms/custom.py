"""User-defined mechanisms: each leg's constraint ``F_i(X, q_i) = 0`` as an expression.

A spec names the pose and joint variables, the box of poses to explore, each
leg's constraint and (optionally) closed-form inverse-kinematic branches. The
paper's five-bar::

    mechanism = "custom"
    pose = ["x", "y"]
    joints = ["t1", "t2"]
    [parameters]
    L0 = 7.0
    L1 = 8.0
    L2 = 5.0
    L3 = 8.0
    L4 = 5.0
    [[legs]]
    joint = "t1"
    constraint = "(x - L1*cos(t1))**2 + (y - L1*sin(t1))**2 - L2**2"
    [[legs]]
    joint = "t2"
    constraint = "(x - L0 - L3*cos(t2))**2 + (y - L3*sin(t2))**2 - L4**2"
    [limits]
    t1 = [0.0, "pi"]
    t2 = [0.0, "pi"]
    [bounds]
    x = [-14.0, 22.0]
    y = [-14.0, 14.0]

Keys: ``pose`` (names of the pose coordinates), optional ``periodic`` (pose
coordinates that wrap around; their bounds must span one turn, 2 pi),
``joints`` (names of the actuated joints, one per leg), ``[parameters]``
(finite numbers), ``[[legs]]`` each with ``joint``, ``constraint``, optional
``kind`` (``"revolute"``, the default, or ``"prismatic"``) and optional
``branches`` (expressions of the pose giving the joint's values, used at
points only and checked there) and optional ``passive`` (a table of passive
angles, below), ``[limits]`` per joint (``[lo, hi]``,
radians for a revolute joint, with ``"pi"`` expressions; or
``"unlimited"`` for a revolute joint), ``[bounds]`` per pose coordinate
(``[lo, hi]``, numbers or ``"pi"`` expressions).

Passive joint limits: a leg may declare passive angles (names unique across
the legs), each an expression of the pose, the leg's own joint and the
parameters, with limits ``[lo, hi]`` (radians, at most one turn wide)::

    [legs.passive]
    C = { angle = "atan2(y - L1*sin(t1), x - L1*cos(t1)) - t1", limits = [-1.0, 2.2] }

The angle is wrapped to ``(-pi, pi]``, i.e. compared with the limits modulo
2 pi (:class:`~moveability.limits.JointLimit`), as the built-in mechanisms'
``[passive_limits]``. Over a box of poses and the leg's joint enclosure it is
enclosed by interval arithmetic (an ``atan2`` whose turn does not matter
without its cut, see :func:`modular`) and classified INSIDE, OUTSIDE or
STRADDLES (:meth:`CustomMechanism.constraint_codes`); the sheets count a
configuration valid only within them. The legs give no flows, so no rate of
the angles is needed (nor given).

Expressions may use the pose, joint and parameter names, numbers, ``pi``,
``+ - * / **`` and the functions ``sin cos tan sqrt exp log atan2 abs``.
They are read by Python's :mod:`ast` parser and checked node by node (no
``eval``), then built as sympy expressions; sympy differentiates them, and
each derivative is printed as Python code calling the guarded functions of
:mod:`moveability.mechanisms.expressions`, so one function evaluates both on
float arrays and on intervals. Numbers are kept exact (rationals) and
enclosed when evaluated over intervals; parameters enter as numbers at
evaluation. Over intervals, each leg function is also traced once into a
compiled tape (:mod:`moveability.mechanisms.tape`, :class:`BoundExpression`),
which gives the same bounds without the interpreter.

The normalised spec and the printed bodies are kept in a cache
(``$MOVEABILITY_CACHE_DIR``, else ``$XDG_CACHE_HOME/moveability`` or
``~/.cache/moveability``; an empty ``MOVEABILITY_CACHE_DIR`` turns it off),
keyed by what each depends on as given (with the types of its values): the
spec but its parameter values, joint limits and pose bounds, and for the
bodies only the names and the legs; with the source of this module and of :mod:`moveability.spec`,
and sympy's version. A spec met before, even with other limits, bounds or
parameter values, is built without importing sympy. A body read back is compiled only if it is
one the printer could have written (numbers, the arguments, ``PI``, ``+``,
``*`` and calls of the guarded functions).

A leg whose constraint is ``lam (|X - K(q)|^2 - b^2)`` (``lam`` a nonzero
number, ``b`` free of the pose and the joint) is a dyad: sympy finds its knee
``K`` and radius ``b``, and the leg is a :class:`~.dyad_leg.DyadLeg`, which
the joint-space count of :mod:`moveability.analysis.joint_space` takes as it
takes the built-in twins' legs (two over two pose axes; three of one radius
over three, :meth:`CustomMechanism.joint_condition`).

Entry points: :func:`normalise_custom_spec` and :class:`CustomMechanism`.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import importlib.util
import json
import keyword
import math
import os
import types
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from .. import intervals as iv
from ..errors import Plain, SpecError
from ..intervals import Interval
from ..limits import INSIDE, OUTSIDE, STRADDLES, JointLimit
from ..spec import parse_angle
from ..types import Array
from . import expressions as ex
from . import tape as tp
from .base import Mechanism
from .constraint_leg import ConstraintLeg
from .constraints import ConstraintMargins, Constraints
from .dyad_leg import DyadLeg, SphereCentres
from .sheet_det import det_along_sheets, dets_along_sheets

if TYPE_CHECKING:
    import sympy
else:
    if importlib.util.find_spec("sympy") is None:  # the "custom" extra, checked on import
        raise ModuleNotFoundError("No module named 'sympy'", name="sympy")

    class _LazySympy:
        """sympy, imported on first use (a second of imports): a spec found in the
        cache of compiled specs (:func:`_cached`) is built without it."""

        def __getattr__(self, name: str) -> Any:
            import sympy as module

            globals()["sympy"] = module
            return getattr(module, name)

    sympy = _LazySympy()

__all__ = [
    "BoundExpression",
    "CustomMechanism",
    "PassiveAngle",
    "compile_expression",
    "modular",
    "normalise_custom_spec",
]

_KEYS = (
    "mechanism",
    "pose",
    "periodic",
    "joints",
    "parameters",
    "legs",
    "limits",
    "bounds",
)
_LEG_KEYS = ("joint", "constraint", "kind", "branches", "passive")
_PASSIVE_KEYS = ("angle", "limits")
_KINDS = ("revolute", "prismatic")
_FUNCTIONS = ("sin", "cos", "tan", "sqrt", "exp", "log", "atan2", "abs")
_ARITY = {"atan2": 2}
_RESERVED = {*_FUNCTIONS, "pi", "E", "I"}
_TWO_PI_LO = math.nextafter(2 * math.pi, 0.0)
_TWO_PI_HI = math.nextafter(2 * math.pi, math.inf)
#: atan2 whose value counts modulo 2 pi only (see :func:`modular`)


def _sympy_function(name: str) -> Any:
    """The sympy function an expression calls by ``name``."""
    return getattr(sympy, "Abs" if name == "abs" else name)


@functools.cache
def _atan2_turn() -> Any:
    return sympy.Function("atan2_turn")


_EXPRESSION_ALLOWED = (
    "an expression of the declared names, numbers, pi, + - * / ** and "
    + ", ".join(sorted(_FUNCTIONS))
)


# --------------------------------------------------------------------- parsing
def _parse(text: object, key: str, names: Mapping[str, sympy.Symbol]) -> sympy.Expr:
    """A sympy expression from text, checked node by node (nothing is evaluated)."""
    if not isinstance(text, str) or not text.strip():
        raise SpecError(key, _EXPRESSION_ALLOWED, text)
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as error:
        raise SpecError(key, f"a well-formed expression ({error.msg})", text) from None

    def build(node: ast.AST) -> sympy.Expr:
        if isinstance(node, ast.Expression):
            return build(node.body)
        if isinstance(node, ast.Constant):
            value = node.value
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise SpecError(key, _EXPRESSION_ALLOWED + f" (not {value!r})", text)
            if not math.isfinite(value):
                raise SpecError(key, "finite numbers", text)
            return sympy.Integer(value) if isinstance(value, int) else sympy.Rational(value)
        if isinstance(node, ast.Name):
            if node.id in names:
                return names[node.id]
            if node.id == "pi":
                return sympy.pi
            raise SpecError(key, _EXPRESSION_ALLOWED, Plain(f"unknown symbol {node.id!r} in {key}"))
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
            operand = build(node.operand)
            return -operand if isinstance(node.op, ast.USub) else operand
        if isinstance(node, ast.BinOp):
            left, right = build(node.left), build(node.right)
            if isinstance(node.op, ast.Add):
                return left + right
            if isinstance(node.op, ast.Sub):
                return left - right
            if isinstance(node.op, ast.Mult):
                return left * right
            if isinstance(node.op, ast.Div):
                return left / right
            if isinstance(node.op, ast.Pow):
                return left**right
            shown = "'^' (write powers as **)" if isinstance(node.op, ast.BitXor) else "operator"
            raise SpecError(key, _EXPRESSION_ALLOWED, Plain(f"unsupported {shown} in {key}"))
        if isinstance(node, ast.Call):
            func = node.func.id if isinstance(node.func, ast.Name) else None
            if func not in _FUNCTIONS:
                shown = func if func is not None else ast.unparse(node.func)
                raise SpecError(
                    key, _EXPRESSION_ALLOWED, Plain(f"unknown function {shown!r} in {key}")
                )
            if node.keywords or len(node.args) != _ARITY.get(func, 1):
                raise SpecError(
                    key,
                    f"{func} with {_ARITY.get(func, 1)} argument(s)",
                    Plain(ast.unparse(node)),
                )
            return _sympy_function(func)(*(build(a) for a in node.args))
        raise SpecError(
            key, _EXPRESSION_ALLOWED, Plain(f"unsupported {ast.unparse(node)!r} in {key}")
        )

    expr = build(tree)
    if expr.has(sympy.zoo, sympy.nan, sympy.oo, -sympy.oo, sympy.I):
        raise SpecError(key, "a finite real expression", text)
    return expr


# ------------------------------------------------------------------- printing
class _Printer:
    """Python source of a sympy expression, calling the guarded functions."""

    def __init__(self, names: Mapping[sympy.Symbol, str]) -> None:
        self.names = names

    def __call__(self, e: sympy.Basic) -> str:
        if isinstance(e, sympy.Symbol):
            return self.names[e]
        if e is sympy.pi:
            return "PI"
        if e is sympy.E:
            return "exp(1)"
        if isinstance(e, sympy.Integer):
            return f"({int(e)})"
        if isinstance(e, sympy.Rational):
            return f"rational({int(e.p)}, {int(e.q)})"
        if isinstance(e, sympy.Float):
            return f"rational({Fraction(float(e)).numerator}, {Fraction(float(e)).denominator})"
        if isinstance(e, sympy.Add):
            return "(" + " + ".join(self(a) for a in e.args) + ")"
        if isinstance(e, sympy.Mul):
            return "(" + " * ".join(self(a) for a in e.args) + ")"
        if isinstance(e, sympy.Pow):
            base, n = e.args
            if isinstance(n, sympy.Integer):
                return f"power({self(base)}, {int(n)})"
            if n == sympy.Rational(1, 2):
                return f"sqrt({self(base)})"
            if n == sympy.Rational(-1, 2):
                return f"power(sqrt({self(base)}), -1)"
            return f"exp({self(n)} * log({self(base)}))"
        names = {
            sympy.sin: "sin",
            sympy.cos: "cos",
            sympy.tan: "tan",
            sympy.exp: "exp",
            sympy.log: "log",
            sympy.Abs: "absolute",
            sympy.atan2: "atan2",
        }
        if isinstance(e, sympy.Function) and e.func in names:
            return f"{names[e.func]}(" + ", ".join(self(a) for a in e.args) + ")"
        if isinstance(e, sympy.atan):
            # sympy writes atan2(u, c) with a constant c > 0 as atan(u / c): the same
            # angle as atan2(u / c, 1), for every real u
            return f"atan2({self(e.args[0])}, 1)"
        if isinstance(e, sympy.Function) and e.func == _atan2_turn():
            return "atan2_turn(" + ", ".join(self(a) for a in e.args) + ")"
        if isinstance(e, sympy.sign):
            # derivative of abs: d|u| = sign(u) du, undefined at 0 (guarded over intervals)
            return f"sign({self(e.args[0])})"
        raise SpecError("expression", _EXPRESSION_ALLOWED, Plain(str(e)))


def _sign(x: Any) -> Any:
    if isinstance(x, Interval):
        pos, neg = x.lo > 0, x.hi < 0
        value = np.where(pos, 1.0, np.where(neg, -1.0, 0.0))
        both = ~pos & ~neg
        return Interval(np.where(both, -np.inf, value), np.where(both, np.inf, value))
    return np.sign(x)


def _rational_float(p: int, q: int) -> float:
    return float(Fraction(p, q))


_PI_IV = Interval(np.float64(np.pi), np.nextafter(np.pi, np.inf))
_COMMON: dict[str, Callable[..., Any]] = {
    **ex.FUNCTIONS,
    "absolute": ex.absolute,
    "power": ex.power,
    "sign": _sign,
    "atan2_turn": ex.atan2_turn,
}
_FLOAT_NS = {**_COMMON, "PI": float(np.pi), "rational": _rational_float}
_INTERVAL_NS = {**_COMMON, "PI": _PI_IV, "rational": iv.rational}


def compile_expression(
    expr: sympy.Expr, args: Sequence[sympy.Symbol], key: str = "expression"
) -> Callable[..., Any]:
    """A function of ``args`` evaluating ``expr`` on float arrays or on Intervals.

    Examples
    --------
    >>> import numpy as np, sympy
    >>> from moveability.intervals import Interval
    >>> x, t = sympy.symbols("x t")
    >>> g = compile_expression((x - 2 * sympy.cos(t)) ** 2 / 3, [x, t])
    >>> round(float(g(np.float64(1.0), np.float64(0.0))), 12)
    0.333333333333
    >>> r = g(Interval(1.0, 1.5), Interval(0.0))
    >>> bool(r.lo <= 1 / 3 and 0.25 / 3 >= r.lo)
    True
    """
    names = {s: f"_a{i}" for i, s in enumerate(args)}
    g = _compile_body(_Printer(names)(expr), len(args), key)
    g.__doc__ = f"{key}: {expr}"
    return g


def _exact(value: Any) -> Interval:
    """A number (or an array of numbers) as a degenerate interval."""
    v = np.asarray(value, dtype=np.float64)
    return Interval(v, v)


def _body_code(body: str, n_args: int, key: str) -> types.CodeType:
    """The code of ``def _g(_a0, ..., _a{n_args - 1}): return body``, to run in a
    namespace of the guarded functions (or their mpmath counterparts)."""
    source = f"def _g({', '.join(f'_a{i}' for i in range(n_args))}):\n    return {body}\n"
    return compile(source, f"<{key}>", "exec")


def _compile_body(body: str, n_args: int, key: str) -> Callable[..., Any]:
    """The function of ``_a0, ..., _a{n_args - 1}`` returning the printed ``body``
    (see :func:`compile_expression`)."""
    code = _body_code(body, n_args, key)
    float_ns: dict[str, Any] = dict(_FLOAT_NS)
    interval_ns: dict[str, Any] = dict(_INTERVAL_NS)
    trace_ns: dict[str, Any] = {name: tp.traced(f, name) for name, f in _COMMON.items()}
    float_trace_ns = dict(trace_ns)
    trace_ns.update(PI=tp.constant(lambda: _PI_IV)(), rational=tp.constant(iv.rational))
    float_trace_ns.update(PI=_FLOAT_NS["PI"], rational=_rational_float)
    exec(code, float_ns)  # the source is printed from a checked sympy tree
    exec(code, interval_ns)
    exec(code, trace_ns)
    exec(code, float_trace_ns)
    g_float, g_interval = float_ns["_g"], interval_ns["_g"]

    def g(*values: Any) -> Any:
        if ex.is_interval(*values):
            # numbers (the parameters) as degenerate intervals: an operation among
            # them (L1*L2, L2**2) is then rounded outwards too
            return g_interval(*(v if isinstance(v, Interval) else _exact(v) for v in values))
        with np.errstate(all="ignore"):
            return g_float(*values)

    g.__doc__ = f"{key}: {body}"
    # the same source on tracers (moveability.mechanisms.tape), for BoundExpression.tape,
    # and with the constants of the float path, for BoundExpression.float_tape
    g.traceable = trace_ns["_g"]  # type: ignore[attr-defined]
    g.float_traceable = float_trace_ns["_g"]  # type: ignore[attr-defined]
    return g


def _mp_function(body: str, n_args: int, values: Sequence[float], k: int) -> Callable[..., Any]:
    """The printed ``body`` of ``(x_1, ..., x_k, q, *parameters)`` with the
    parameters bound, as ``h(q, ctx)`` in an mpmath interval context ``ctx``
    (the pose is given as 0: for bodies free of it, as the knees')."""
    code = _body_code(body, n_args, "knee")
    compiled: dict[int, Callable[..., Any]] = {}

    def h(q: Any, ctx: Any) -> Any:
        g = compiled.get(id(ctx))
        if g is None:
            ns: dict[str, Any] = {
                name: getattr(ctx, name) for name in ("sin", "cos", "tan", "exp", "log", "sqrt")
            }
            ns.update(
                PI=ctx.pi,
                power=lambda b, n: b**n,
                rational=lambda p, r: ctx.mpf(p) / r,
                absolute=abs,
            )
            exec(code, ns)  # printed from a checked sympy tree
            g = compiled[id(ctx)] = ns["_g"]
        return g(*([ctx.mpf(0)] * k), q, *(ctx.mpf(v) for v in values))

    return h


class BoundExpression:
    """A compiled expression of ``(x_1, ..., x_k, q, *parameters)`` with the
    parameters bound: ``self(x_1, ..., x_k, q)``; :attr:`tape` is its compiled
    interval enclosure (:mod:`moveability.mechanisms.tape`), or None where the
    expression cannot be traced.

    Examples
    --------
    >>> x, q, a = sympy.symbols("x q a")
    >>> f = BoundExpression(compile_expression(x - a * sympy.cos(q), [x, q, a]), [2.0], 1)
    >>> float(f(np.float64(1.0), np.float64(0.0)))
    -1.0
    >>> f.tape is not None
    True
    """

    def __init__(self, g: Callable[..., Any], values: Sequence[float], k: int) -> None:
        self.g, self.values, self.k = g, tuple(values), k
        self._tapes: dict[str, tp.Tape | None] = {}

    def __call__(self, *xs: Any) -> Any:
        return self.g(*xs, *self.values)

    def _traced(self, name: str, constant: Callable[[float], Any]) -> tp.Tape | None:
        """The tape of ``self.g``'s ``name`` source with each parameter as
        ``constant`` makes it (built on first use; None where it cannot be traced)."""
        if name not in self._tapes:
            traceable = getattr(self.g, name, None)
            tape = None
            if traceable is not None:
                values = [constant(v) for v in self.values]
                try:
                    tape = tp.trace(lambda *xs: traceable(*xs, *values), self.k)
                except tp.Untraceable:
                    tape = None
            self._tapes[name] = tape
        return self._tapes[name]

    @property
    def tape(self) -> tp.Tape | None:
        """The traced tape (built on first use)."""
        # the parameters as the interpreted path takes them (see _compile_body)
        return self._traced("traceable", tp.constant(_exact))

    @property
    def float_tape(self) -> tp.Tape | None:
        """The operations the expression performs on float arrays, in order (its
        constants floats, operated on as the float path does), or None where it
        cannot be traced: what the compiled fold certificates evaluate
        (:func:`moveability.mechanisms._fold_kernels.float_program`)."""
        return self._traced("float_traceable", lambda v: v)


def modular(expr: sympy.Expr) -> sympy.Expr:
    """``expr`` with each ``atan2`` whose value counts modulo 2 pi only marked so.

    A passive angle is compared with its limits modulo 2 pi, so an ``atan2``
    in it may be enclosed up to whole turns (without the cut on the negative
    x axis: :func:`~moveability.mechanisms.expressions.atan2_turn`) where a
    turn more or less changes the angle by whole turns only: at the top of the
    expression, in the terms of a sum there, in ``n * u`` with ``n`` an
    integer there, and in the argument of ``sin``, ``cos``, ``tan`` anywhere.
    Elsewhere (``atan2(..)/2``, ``atan2(..)**2``, ``exp(atan2(..))``) it is
    left as it is, the guarded ``atan2`` (the whole line over a box meeting
    its cut).

    Examples
    --------
    >>> x, y, t = sympy.symbols("x y t", real=True)
    >>> modular(sympy.atan2(y, x) - t)
    -t + atan2_turn(y, x)
    >>> modular(sympy.atan2(y, x) / 2)
    atan2(y, x)/2
    >>> modular(sympy.exp(sympy.cos(2 * sympy.atan2(y, x))))
    exp(cos(2*atan2_turn(y, x)))
    """

    def walk(e: sympy.Basic, mod: bool) -> sympy.Basic:
        if not e.args:
            return e
        if isinstance(e, sympy.atan2):
            y, x = (walk(a, False) for a in e.args)
            return _atan2_turn()(y, x) if mod else sympy.atan2(y, x, evaluate=False)
        if isinstance(e, sympy.sin | sympy.cos | sympy.tan):
            return e.func(walk(e.args[0], True), evaluate=False)
        if mod and isinstance(e, sympy.Add):
            return sympy.Add(*(walk(a, True) for a in e.args), evaluate=False)
        if mod and isinstance(e, sympy.Mul):
            coeff, rest = e.as_coeff_Mul()
            if coeff.is_Integer and not isinstance(rest, sympy.Mul):
                return sympy.Mul(coeff, walk(rest, True), evaluate=False)
        return e.func(*(walk(a, False) for a in e.args), evaluate=False)

    out: sympy.Expr = walk(expr, True)
    return out


# ---------------------------------------------------------------- the spec
def _names(value: object, key: str, taken: set[str]) -> list[str]:
    allowed = "a list of distinct names (identifiers)"
    if isinstance(value, str) or not isinstance(value, Sequence) or not value:
        raise SpecError(key, allowed, value)
    out: list[str] = []
    for i, name in enumerate(value):
        if not isinstance(name, str) or not name.isidentifier() or keyword.iskeyword(name):
            raise SpecError(f"{key}[{i}]", "a name (an identifier)", name)
        if name in _RESERVED:
            raise SpecError(f"{key}[{i}]", "a name that is not a function nor pi", name)
        if name in taken or name in out:
            raise SpecError(f"{key}[{i}]", "a name not used before", name)
        out.append(name)
    return out


def _number(value: object, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise SpecError(key, "a finite number", value)
    if not math.isfinite(value):
        raise SpecError(key, "a finite number", value)
    return float(value)


def _table(value: object, key: str, allowed: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise SpecError(key, allowed, value)
    return value


def _pair(value: object, key: str, angle: bool) -> list[float]:
    allowed = "[lo, hi] with lo < hi"
    if isinstance(value, str) or not isinstance(value, Sequence) or len(value) != 2:
        raise SpecError(key, allowed, value)
    if angle:
        lo, hi = parse_angle(value[0], f"{key}[0]"), parse_angle(value[1], f"{key}[1]")
    else:
        lo, hi = _number(value[0], f"{key}[0]"), _number(value[1], f"{key}[1]")
    if not lo < hi:
        raise SpecError(key, allowed + " (an empty or reversed range)", value)
    return [lo, hi]


def _passive(
    value: object,
    key: str,
    joint: str,
    symbols: Mapping[str, sympy.Symbol],
    joints: Sequence[str],
    taken: set[str],
) -> dict[str, dict[str, Any]]:
    """A leg's passive angles ``{name: {"angle": text, "limits": [lo, hi]}}``,
    checked (``taken``: the names of the legs before, updated)."""
    table = _table(
        value, key, "a table of passive angles: name = { angle = ..., limits = [lo, hi] }"
    )
    out: dict[str, dict[str, Any]] = {}
    for name, item in table.items():
        pkey = f"{key}.{name}"
        if not isinstance(name, str) or not name.isidentifier() or keyword.iskeyword(name):
            raise SpecError(pkey, "a name (an identifier)", name)
        if name in taken:
            raise SpecError(pkey, "a passive angle name not used before", Plain(name))
        item = _table(item, pkey, "a table { angle = expression, limits = [lo, hi] }")
        for k in item:
            if k not in _PASSIVE_KEYS:
                raise SpecError(f"{pkey}.{k}", "one of " + ", ".join(_PASSIVE_KEYS), Plain(str(k)))
        text = item.get("angle")
        if text is None:
            raise SpecError(f"{pkey}.angle", _EXPRESSION_ALLOWED, Plain("nothing"))
        expr = _parse(text, f"{pkey}.angle", symbols)
        if any(s.name in joints and s.name != joint for s in expr.free_symbols):
            raise SpecError(f"{pkey}.angle", f"an expression of the pose and {joint} only", text)
        if "limits" not in item:
            raise SpecError(f"{pkey}.limits", "[lo, hi] in radians", Plain("nothing"))
        limits = _pair(item["limits"], f"{pkey}.limits", angle=True)
        if limits[1] - limits[0] > _TWO_PI_HI:
            raise SpecError(f"{pkey}.limits", "a range no wider than 2*pi", item["limits"])
        taken.add(name)
        out[name] = {"angle": str(text).strip(), "limits": limits}
    return out


def normalise_custom_spec(data: Mapping[str, Any]) -> dict[str, Any]:
    """Check a custom mechanism's spec and return it normalised (JSON-ready, stable).

    Parameters
    ----------
    data : mapping
        The parsed TOML (see the module's notes), or a normalised spec.

    Returns
    -------
    dict
        ``{"mechanism": "custom", "pose": [...], "periodic": [...], "joints":
        [...], "parameters": {name: float}, "legs": [{"joint", "constraint",
        "kind", "branches"?, "passive"?: {name: {"angle", "limits": [lo, hi]}}}],
        "limits": {joint: [lo, hi] or "unlimited"},
        "bounds": {pose: [lo, hi]}}``, legs in the order of ``joints``.

    Raises
    ------
    SpecError
        Naming the key at fault: ``legs[1].constraint`` for a malformed
        expression or an unknown symbol (named), a leg whose constraint does
        not involve its joint, a joint without leg or without limit, duplicated
        names, bounds with ``lo >= hi``, non-finite numbers, unknown keys;
        ``legs[0].passive.C.angle`` (as a constraint, of the pose and the leg's
        joint only) or ``.limits``, a passive angle name used twice, a
        top-level ``passive_limits``.

    Examples
    --------
    >>> spec = normalise_custom_spec({
    ...     "mechanism": "custom", "pose": ["x"], "joints": ["q"],
    ...     "parameters": {"a": 2},
    ...     "legs": [{"joint": "q", "constraint": "x - a*cos(q)"}],
    ...     "limits": {"q": [0, "pi"]}, "bounds": {"x": [-3, 3]}})
    >>> spec["limits"], spec["legs"][0]["kind"]
    ({'q': [0.0, 3.141592653589793]}, 'revolute')
    >>> normalise_custom_spec(spec) == spec
    True
    >>> normalise_custom_spec({**spec, "legs": [{"joint": "q", "constraint": "x - z*cos(q)"}]})
    Traceback (most recent call last):
        ...
    moveability.errors.SpecError: invalid legs[0].constraint: expected an expression of \
the declared names, numbers, pi, + - * / ** and abs, atan2, cos, exp, log, sin, sqrt, tan, \
got unknown symbol 'z' in legs[0].constraint
    """
    if not isinstance(data, Mapping):
        raise SpecError("spec", "a mapping", data)
    # what needs sympy (the names and the legs) is cached apart from the numbers, so
    # that a spec differing only in its parameter values, limits or bounds is built
    # without sympy
    shape = {k: v for k, v in data.items() if k not in _RANGES}
    if isinstance(shape.get("parameters"), Mapping):
        shape["parameters"] = list(shape["parameters"])
    key = _cache_key("spec", shape)
    found = None if key is None else _cache_load(key)
    if isinstance(found, dict):
        names = found
    else:
        names = _normalise_names(data)
        if key is not None:
            _cache_store(key, names)
    return _normalise_numbers(data, names)


#: the spec's keys that :func:`_normalise_numbers` reads alone
_RANGES = ("limits", "bounds")


def _normalise_names(data: Mapping[str, Any]) -> dict[str, Any]:
    """:func:`normalise_custom_spec` but the limits and bounds (sympy parses the legs)."""
    if not isinstance(data, Mapping):
        raise SpecError("spec", "a mapping", data)
    for key in data:
        if key == "passive_limits":
            raise SpecError(
                key, "passive angles declared per leg ([legs.passive])", Plain("a table")
            )
        if key not in _KEYS:
            raise SpecError(str(key), "one of the keys " + ", ".join(_KEYS), Plain(str(key)))
    if data.get("mechanism", "custom") != "custom":
        raise SpecError("mechanism", "'custom'", data.get("mechanism"))
    pose = _names(data.get("pose"), "pose", set())
    joints = _names(data.get("joints"), "joints", set(pose))
    periodic_raw = data.get("periodic", [])
    if isinstance(periodic_raw, str) or not isinstance(periodic_raw, Sequence):
        raise SpecError("periodic", "a list of pose names", periodic_raw)
    periodic: list[str] = []
    for i, name in enumerate(periodic_raw):
        if name not in pose or name in periodic:
            raise SpecError(f"periodic[{i}]", f"one of the pose names {pose}, once", name)
        periodic.append(str(name))
    params_raw = _table(data.get("parameters", {}), "parameters", "a table of numbers")
    parameters: dict[str, float] = {}
    taken = set(pose) | set(joints)
    for name, value in params_raw.items():
        key = f"parameters.{name}"
        if not isinstance(name, str) or not name.isidentifier() or keyword.iskeyword(name):
            raise SpecError(key, "a name (an identifier)", name)
        if name in _RESERVED or name in taken:
            raise SpecError(key, "a name not used by a pose, joint or function", name)
        parameters[name] = _number(value, key)

    symbols = {n: sympy.Symbol(n, real=True) for n in (*pose, *joints, *parameters)}
    legs_raw = data.get("legs")
    if isinstance(legs_raw, str) or not isinstance(legs_raw, Sequence) or not legs_raw:
        raise SpecError("legs", "a list of legs ([[legs]] tables)", legs_raw)
    by_joint: dict[str, dict[str, Any]] = {}
    passive_names: set[str] = set()
    for i, leg in enumerate(legs_raw):
        key = f"legs[{i}]"
        leg = _table(leg, key, "a table with joint and constraint")
        for k in leg:
            if k not in _LEG_KEYS:
                raise SpecError(f"{key}.{k}", "one of " + ", ".join(_LEG_KEYS), Plain(str(k)))
        joint = leg.get("joint")
        if joint not in joints:
            raise SpecError(f"{key}.joint", f"one of the joints {joints}", joint)
        if joint in by_joint:
            raise SpecError(f"{key}.joint", "a joint not driven by another leg", joint)
        text = leg.get("constraint")
        expr = _parse(text, f"{key}.constraint", symbols)
        if symbols[joint] not in expr.free_symbols:
            raise SpecError(f"{key}.constraint", f"an expression involving {joint}", text)
        others = [s.name for s in expr.free_symbols if s.name in joints and s.name != joint]
        if others:
            raise SpecError(
                f"{key}.constraint", f"an expression of the pose and {joint} only", text
            )
        kind = leg.get("kind", "revolute")
        if kind not in _KINDS:
            raise SpecError(f"{key}.kind", "'revolute' or 'prismatic'", kind)
        entry: dict[str, Any] = {"joint": joint, "constraint": str(text).strip(), "kind": kind}
        if "branches" in leg:
            branches = leg["branches"]
            if isinstance(branches, str) or not isinstance(branches, Sequence) or not branches:
                raise SpecError(f"{key}.branches", "a list of expressions", branches)
            pose_syms = {n: symbols[n] for n in (*pose, *parameters)}
            for b, branch in enumerate(branches):
                _parse(branch, f"{key}.branches[{b}]", pose_syms)
            entry["branches"] = [str(b).strip() for b in branches]
        if "passive" in leg:
            passive = _passive(
                leg["passive"], f"{key}.passive", joint, symbols, joints, passive_names
            )
            if passive:
                entry["passive"] = passive
        by_joint[joint] = entry
    for joint in joints:
        if joint not in by_joint:
            raise SpecError("legs", f"a leg for joint {joint}", Plain("nothing"))
    return {
        "mechanism": "custom",
        "pose": pose,
        "periodic": periodic,
        "joints": joints,
        "parameters": parameters,
        "legs": [by_joint[j] for j in joints],
    }


def _normalise_numbers(data: Mapping[str, Any], names: dict[str, Any]) -> dict[str, Any]:
    """The normalised spec: ``names`` (:func:`_normalise_names` of ``data``, or of a
    spec differing from it in these numbers alone) with the parameter values, joint
    limits and pose bounds of ``data``, checked against them."""
    pose, joints, periodic = names["pose"], names["joints"], names["periodic"]
    given = data.get("parameters", {})
    parameters = {name: _number(given[name], f"parameters.{name}") for name in names["parameters"]}
    kinds = {leg["joint"]: leg["kind"] for leg in names["legs"]}
    limits_raw = _table(data.get("limits"), "limits", "a table giving each joint's limits")
    limits: dict[str, Any] = {}
    for name in limits_raw:
        if name not in joints:
            raise SpecError(f"limits.{name}", f"one of the joints {joints}", limits_raw[name])
    for joint in joints:
        key = f"limits.{joint}"
        if joint not in limits_raw:
            raise SpecError(key, '[lo, hi] or "unlimited"', Plain("nothing"))
        value = limits_raw[joint]
        prismatic = kinds[joint] == "prismatic"
        if isinstance(value, str):
            if value.strip().lower() != "unlimited" or prismatic:
                allowed = "[lo, hi]" if prismatic else '[lo, hi] or "unlimited"'
                raise SpecError(key, allowed, value)
            limits[joint] = "unlimited"
            continue
        pair = _pair(value, key, angle=not prismatic)
        if not prismatic and pair[1] - pair[0] > _TWO_PI_HI:
            raise SpecError(key, 'a range no wider than 2*pi (or "unlimited")', value)
        limits[joint] = pair

    bounds_raw = _table(data.get("bounds"), "bounds", "a table giving each pose coordinate's range")
    for name in bounds_raw:
        if name not in pose:
            raise SpecError(f"bounds.{name}", f"one of the pose names {pose}", bounds_raw[name])
    bounds: dict[str, list[float]] = {}
    for name in pose:
        key = f"bounds.{name}"
        if name not in bounds_raw:
            raise SpecError(key, "[lo, hi]", Plain("nothing"))
        pair = _pair(bounds_raw[name], key, angle=True)
        if name in periodic and not (_TWO_PI_LO <= pair[1] - pair[0] <= _TWO_PI_HI):
            raise SpecError(key, "one full turn (hi - lo = 2*pi) for a periodic coordinate", pair)
        bounds[name] = pair
    return {**names, "parameters": parameters, "limits": limits, "bounds": bounds}


def _leg_bodies(spec: Mapping[str, Any]) -> dict[str, str]:
    """The printed bodies of every function of a normalised spec's legs (sympy):
    ``"{i}.f"``, ``"{i}.df_dq"``, ``"{i}.d2f_dq2"``, ``"{i}.df_dx.{j}"``,
    ``"{i}.branch.{b}"``, ``"{i}.passive.{name}"`` for leg ``i``."""
    pose_syms = [sympy.Symbol(n, real=True) for n in spec["pose"]]
    param_syms = [sympy.Symbol(n, real=True) for n in spec["parameters"]]
    symbols = {sym.name: sym for sym in (*pose_syms, *param_syms)}
    out: dict[str, str] = {}
    for i, leg in enumerate(spec["legs"]):
        q = sympy.Symbol(leg["joint"], real=True)
        f = _parse(leg["constraint"], f"legs[{i}].constraint", {**symbols, q.name: q})
        names = {sym: f"_a{a}" for a, sym in enumerate([*pose_syms, q, *param_syms])}
        printer = _Printer(names)
        key = f"legs[{i}].constraint"
        derivatives = {
            f"{i}.df_dq": (sympy.diff(f, q), f"dF/d{q.name}"),
            f"{i}.d2f_dq2": (sympy.diff(f, q, 2), f"d2F/d{q.name}^2"),
        }
        for j, x in enumerate(pose_syms):
            derivatives[f"{i}.df_dx.{j}"] = (sympy.diff(f, x), f"dF/d{x.name}")
        out[f"{i}.f"] = printer(f)
        for name, (expr, what) in derivatives.items():
            out[name] = _printed_derivative(printer, expr, what, key)
        if leg["kind"] == "prismatic":
            out.update(_second_derivative_bodies(f, pose_syms, q, printer, i))
        if not spec["periodic"]:
            out.update(_knee_bodies(f, pose_syms, q, printer, i))
        pose_printer = _Printer({sym: f"_a{a}" for a, sym in enumerate([*pose_syms, *param_syms])})
        for b, text in enumerate(leg.get("branches", [])):
            out[f"{i}.branch.{b}"] = pose_printer(_parse(text, f"legs[{i}].branches[{b}]", symbols))
        for name, item in leg.get("passive", {}).items():
            akey = f"legs[{i}].passive.{name}.angle"
            out[f"{i}.passive.{name}"] = printer(
                modular(_parse(item["angle"], akey, {**symbols, q.name: q}))
            )
    return out


def _second_derivative_bodies(
    f: sympy.Expr, pose: list[sympy.Symbol], q: sympy.Symbol, printer: _Printer, i: int
) -> dict[str, str]:
    """The derivatives of leg ``i``'s row of A (``dF/dX``), printed:
    ``"{i}.d2f_dxdx.{j}.{k}"`` (``d2F/dX_j dX_k``, ``j <= k``: the same as
    ``d2F/dX_k dX_j``) and ``"{i}.d2f_dqdx.{j}"`` (``d2F/dq dX_j``); none where
    one cannot be printed (the Dirac delta of a differentiated ``abs`` or
    ``sign``): det A is then enclosed on intervals alone (see :mod:`.sheet_det`).

    Only prismatic legs are given them. A slider's joint moves about as fast as
    the pose, so over a cell its enclosure is about as wide as the cell, and the
    form along the sheets narrows det A where a mechanism's legs are all
    prismatic (a 3-RPR written as a spec: about ten times the volume certified
    in its regions, for about a fifth more time). A revolute joint's enclosure is
    often many times the cell (its rate is unbounded at a fold): the user-defined
    Delta kept the same leaves at 0.1 and 0.05 for a third more time, the
    five-bar 13 % fewer leaves at 0.05 for a quarter more."""
    out: dict[str, str] = {}
    try:
        for j, xj in enumerate(pose):
            row = sympy.diff(f, xj)
            out[f"{i}.d2f_dqdx.{j}"] = printer(sympy.diff(row, q))
            for k, xk in enumerate(pose[j:], start=j):
                out[f"{i}.d2f_dxdx.{j}.{k}"] = printer(sympy.diff(row, xk))
    except SpecError:
        return {}
    return out


def _knee_bodies(
    f: sympy.Expr, pose: list[sympy.Symbol], q: sympy.Symbol, printer: _Printer, i: int
) -> dict[str, str]:
    """Where leg ``i``'s constraint is ``lam (|X - K(q)|^2 - b^2)`` with ``lam`` a
    nonzero number and ``b^2`` free of the pose and the joint (a dyad, see
    :mod:`.dyad_leg`): the knee ``K_j`` and its first two derivatives, printed
    (``"{i}.knee.{j}"``, ``"{i}.knee_rate.{j}"``, ``"{i}.knee_curve.{j}"``),
    and ``b^2`` (``"{i}.distal2"``); none otherwise."""
    try:
        poly = sympy.Poly(sympy.expand(f), *pose)
    except sympy.PolynomialError:
        return {}
    if poly.total_degree() != 2:
        return {}
    lam = poly.coeff_monomial(pose[0] ** 2)
    if not lam.is_number or lam == 0:
        return {}
    knee = []
    for x in pose:
        if sympy.simplify(poly.coeff_monomial(x**2) - lam) != 0:
            return {}
        knee.append(-poly.coeff_monomial(x) / (2 * lam))
    for monomial in poly.monoms():
        degree = sum(monomial)
        if degree == 2 and max(monomial) != 2:
            return {}  # a cross term x_j x_k
    constant = poly.coeff_monomial(1)
    distal2 = sympy.expand(sum(k**2 for k in knee) - constant / lam)
    if q in distal2.free_symbols:
        distal2 = sympy.simplify(distal2)
    if q in distal2.free_symbols or set(pose) & distal2.free_symbols:
        return {}
    out = {f"{i}.distal2": printer(distal2)}
    try:
        for j, k in enumerate(knee):
            out[f"{i}.knee.{j}"] = printer(k)
            out[f"{i}.knee_rate.{j}"] = printer(sympy.diff(k, q))
            out[f"{i}.knee_curve.{j}"] = printer(sympy.diff(k, q, 2))
    except SpecError:
        return {}
    return out


def _printed_derivative(printer: _Printer, expr: sympy.Expr, what: str, key: str) -> str:
    """A derivative ``expr`` (named ``what``) of the constraint at ``key``, printed:
    one the printer cannot write (the Dirac delta of ``abs`` or ``sign`` of an
    expression of the joint, differentiated) is an error of that constraint."""
    try:
        return printer(expr)
    except SpecError:
        raise SpecError(
            key,
            f"a constraint with a derivative {what} everywhere (abs or sign of an "
            "expression of the joint has none)",
            Plain(f"{what} = {expr}"),
        ) from None


# ------------------------------------------------------------------ the cache
#: the functions a printed body may call (see _Printer)
_BODY_CALLS = frozenset(
    {"sin", "cos", "tan", "exp", "log", "sqrt", "absolute", "atan2", "atan2_turn", "power",
     "sign", "rational"}
)  # fmt: skip
_MEMO: dict[str, Any] = {}


def _cache_dir() -> str | None:
    """Where compiled specs are kept: ``$MOVEABILITY_CACHE_DIR`` (empty: no cache),
    else ``$XDG_CACHE_HOME/moveability`` or ``~/.cache/moveability``."""
    chosen = os.environ.get("MOVEABILITY_CACHE_DIR")
    if chosen is not None:
        return chosen or None
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "moveability")


@functools.cache
def _fingerprint() -> str:
    """What the cached results depend on: the source of this module and of
    :mod:`moveability.spec` (angles as ``"pi/2"``), and sympy's version (its
    ``release.py``, read rather than imported: neither sympy nor
    :mod:`importlib.metadata`, a hundredth of a second, is imported for it)."""
    digest = hashlib.sha256()
    for path in (__file__, os.path.join(os.path.dirname(__file__), "..", "spec.py")):
        with open(path, "rb") as handle:
            digest.update(handle.read())
    found = importlib.util.find_spec("sympy")
    origin = None if found is None else found.origin
    release = b""
    if origin is not None:
        try:
            with open(os.path.join(os.path.dirname(origin), "release.py"), "rb") as handle:
                release = handle.read()
        except OSError:  # pragma: no cover
            pass
    # without sympy's release file, a key no later process meets: nothing is reused
    digest.update(release or os.urandom(16))
    return digest.hexdigest()


def _canonical(value: object) -> object:
    """``value`` as JSON telling its types apart (tuple from list, int from float);
    ValueError for anything else."""
    if value is None or isinstance(value, str | bool):
        return value
    if isinstance(value, int):
        return {"i": str(value)}
    if isinstance(value, float):
        return {"f": repr(value)}
    if isinstance(value, Mapping):
        return {"d": [[_canonical(k), _canonical(v)] for k, v in value.items()]}
    if isinstance(value, list | tuple):
        return {"l" if isinstance(value, list) else "t": [_canonical(v) for v in value]}
    raise ValueError(type(value).__name__)


def _cache_key(kind: str, data: object) -> str | None:
    try:
        text = json.dumps([kind, _canonical(data)], separators=(",", ":"))
    except (ValueError, TypeError, RecursionError):
        return None
    return hashlib.sha256((_fingerprint() + text).encode()).hexdigest()


def _cache_load(key: str) -> Any:
    """The cached JSON value of ``key`` (in this process, else on disk), or None."""
    if key in _MEMO:
        return json.loads(_MEMO[key])
    folder = _cache_dir()
    if folder is None:
        return None
    try:
        with open(os.path.join(folder, key + ".json"), encoding="utf-8") as handle:
            text = handle.read()
        value = json.loads(text)
    except (OSError, ValueError):
        return None
    _MEMO[key] = text
    return value


def _cache_store(key: str, value: Any) -> None:
    """Keep ``value`` (JSON) for ``key``; a cache that cannot be written is skipped."""
    text = json.dumps(value, separators=(",", ":"))
    _MEMO[key] = text
    folder = _cache_dir()
    if folder is None:
        return
    try:
        os.makedirs(folder, exist_ok=True)
        path = os.path.join(folder, key + ".json")
        tmp = f"{path}.{os.getpid()}.tmp"
        with open(tmp, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.replace(tmp, path)
    except OSError:
        pass


def _body_ok(body: object, n_args: int) -> bool:
    """Whether a cached body is one :class:`_Printer` could print: numbers, the
    arguments, ``PI``, ``+``, ``*``, negative integers and calls of the guarded
    functions, nothing else (so that compiling it runs no other code)."""
    if not isinstance(body, str):
        return False
    try:
        tree = ast.parse(body, mode="eval")
    except SyntaxError:
        return False
    names = {f"_a{i}" for i in range(n_args)} | {"PI"}
    for node in ast.walk(tree):
        if isinstance(node, ast.Expression | ast.Load | ast.Add | ast.Mult | ast.USub):
            continue
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add | ast.Mult):
            continue
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            continue
        if isinstance(node, ast.Constant) and type(node.value) is int:
            continue
        if isinstance(node, ast.Name) and (node.id in names or node.id in _BODY_CALLS):
            continue
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in _BODY_CALLS
            and not node.keywords
        ):
            continue
        return False
    return True


def _bodies(spec: Mapping[str, Any]) -> dict[str, str]:
    """:func:`_leg_bodies`, kept in the cache of compiled specs (checked when read)."""
    # the bodies depend on the names (of the parameters too, not their values) and the legs
    key = _cache_key(
        "bodies",
        {
            "pose": spec["pose"],
            "joints": spec["joints"],
            "parameters": list(spec["parameters"]),
            "legs": spec["legs"],
        },
    )
    if key is not None:
        found = _cache_load(key)
        if isinstance(found, dict):
            k, p = len(spec["pose"]), len(spec["parameters"])
            if all(
                _body_ok(body, k + p if ".branch." in name else k + 1 + p)
                for name, body in found.items()
            ):
                return found
    bodies = _leg_bodies(spec)
    if key is not None:
        _cache_store(key, bodies)
    return bodies


@dataclass(frozen=True)
class PassiveAngle:
    """A passive angle of a leg: ``function(*pose, q_leg)`` (floats or intervals,
    parameters bound), to keep within ``limit`` modulo 2 pi."""

    name: str
    leg: int
    function: Callable[..., Any]
    limit: JointLimit


class CustomMechanism(Mechanism):
    """A mechanism from a custom spec (see :func:`normalise_custom_spec`).

    Parameters
    ----------
    spec : mapping
        A custom spec, normalised or not.

    Examples
    --------
    >>> import numpy as np
    >>> m = CustomMechanism({
    ...     "mechanism": "custom", "pose": ["x", "y"], "joints": ["t1", "t2"],
    ...     "parameters": {"L0": 7, "L1": 8, "L2": 5, "L3": 8, "L4": 5},
    ...     "legs": [
    ...         {"joint": "t1", "constraint": "(x - L1*cos(t1))**2 + (y - L1*sin(t1))**2 - L2**2"},
    ...         {"joint": "t2",
    ...          "constraint": "(x - L0 - L3*cos(t2))**2 + (y - L3*sin(t2))**2 - L4**2"}],
    ...     "limits": {"t1": [0, "pi"], "t2": [0, "pi"]},
    ...     "bounds": {"x": [-14, 22], "y": [-14, 14]}})
    >>> m.joint_names, m.pose_names
    (('t1', 't2'), ('x', 'y'))
    >>> q = m.joint_angles(np.array([[3.5, 9.0]]))
    >>> bool(np.allclose(m.constraints(np.array([[3.5, 9.0]] * 4), q[0]), 0.0))
    True
    """

    name = "custom"

    def __init__(self, spec: Mapping[str, Any]) -> None:
        self.spec = normalise_custom_spec(spec)
        s = self.spec
        self.pose_names = tuple(s["pose"])
        self.periodic_axes = tuple(s["pose"].index(n) for n in s["periodic"])
        params = s["parameters"]
        values = [params[n] for n in params]
        k = len(s["pose"])
        bodies = _bodies(s)
        legs = []
        limits = []
        passive: list[PassiveAngle] = []
        for i, leg in enumerate(s["legs"]):
            key = f"legs[{i}].constraint"
            n_args = k + 1 + len(params)

            def bind(name: str, what: str, n_args: int = n_args) -> Callable[..., Any]:
                g = _compile_body(bodies[name], n_args, what)
                return BoundExpression(g, values, k)

            closed = None
            if "branches" in leg:
                fns = [
                    _compile_body(bodies[f"{i}.branch.{b}"], k + len(params), "expression")
                    for b in range(len(leg["branches"]))
                ]

                def closed_form(points: Array, fns: Any = fns) -> Array:
                    cols = [points[:, j] for j in range(points.shape[1])]
                    return np.stack(
                        [
                            np.broadcast_to(
                                np.asarray(g(*cols, *values), dtype=np.float64), (points.shape[0],)
                            )
                            for g in fns
                        ],
                        axis=1,
                    )

                closed = closed_form
            limit = s["limits"][leg["joint"]]
            prismatic = leg["kind"] == "prismatic"
            if limit == "unlimited":
                limits.append(JointLimit.unlimited())
            else:
                limits.append(JointLimit(limit[0], limit[1], prismatic=prismatic))
            q_name = leg["joint"]
            d2f_dxdx = d2f_dqdx = None
            if f"{i}.d2f_dqdx.0" in bodies:
                # symmetric: one function for (j, c) and (c, j)
                upper = {
                    (j, c): bind(f"{i}.d2f_dxdx.{j}.{c}", f"d2{key}/d{x}d{y}")
                    for j, x in enumerate(s["pose"])
                    for c, y in enumerate(s["pose"])
                    if j <= c
                }
                d2f_dxdx = tuple(
                    tuple(upper[min(j, c), max(j, c)] for c in range(k)) for j in range(k)
                )
                d2f_dqdx = tuple(
                    bind(f"{i}.d2f_dqdx.{j}", f"d2{key}/d{q_name}d{x}")
                    for j, x in enumerate(s["pose"])
                )
            dyad: dict[str, Any] = {}
            if all(f"{i}.knee.{j}" in bodies for j in range(k)):
                radius2 = _compile_body(bodies[f"{i}.distal2"], n_args, key)
                b2 = float(radius2(*[0.0] * (k + 1), *values))
                if b2 > 0:
                    dyad = {
                        "distal": math.sqrt(b2),
                        **{
                            name: tuple(
                                bind(f"{i}.{name}.{j}", f"{name} of {key}") for j in range(k)
                            )
                            for name in ("knee", "knee_rate", "knee_curve")
                        },
                        "knee_mp": tuple(
                            _mp_function(bodies[f"{i}.knee.{j}"], n_args, values, k)
                            for j in range(k)
                        ),
                        "knee_mp_rate": tuple(
                            _mp_function(bodies[f"{i}.knee_rate.{j}"], n_args, values, k)
                            for j in range(k)
                        ),
                    }
            legs.append(
                (DyadLeg if dyad else ConstraintLeg)(
                    leg["joint"],
                    f=bind(f"{i}.f", key),
                    df_dq=bind(f"{i}.df_dq", f"d{key}/d{q_name}"),
                    d2f_dq2=bind(f"{i}.d2f_dq2", f"d2{key}/d{q_name}2"),
                    df_dx=tuple(
                        bind(f"{i}.df_dx.{j}", f"d{key}/d{x}") for j, x in enumerate(s["pose"])
                    ),
                    prismatic=prismatic,
                    stroke=(limit[0], limit[1]) if prismatic else None,
                    closed_form=closed,
                    d2f_dxdx=d2f_dxdx,
                    d2f_dqdx=d2f_dqdx,
                    **dyad,
                )
            )
            for name, item in leg.get("passive", {}).items():
                akey = f"legs[{i}].passive.{name}.angle"
                lo, hi = item["limits"]
                passive.append(
                    PassiveAngle(name, i, bind(f"{i}.passive.{name}", akey), JointLimit(lo, hi))
                )
        self.passive_angles = tuple(passive)
        if passive:
            self.restrictions = Constraints(passive={a.name: a.limit for a in passive})
        self.legs = tuple(legs)
        self.limits = tuple(limits)
        # the user's box: it may cut the workspace, so the analysis keeps it
        self.bounds_hold_workspace = False
        self.bounds = (
            np.array([s["bounds"][n][0] for n in s["pose"]], dtype=np.float64),
            np.array([s["bounds"][n][1] for n in s["pose"]], dtype=np.float64),
        )

    def joint_condition(self) -> SphereCentres | None:
        """Three dyad legs on spheres of one radius about knees (a Delta written as
        a spec): the condition whose components in the joint space are the
        regions (:class:`~moveability.mechanisms.dyad_leg.SphereCentres`); None
        otherwise (two dyads are found by the joint space itself)."""
        legs = self.legs
        if (
            len(self.pose_names) != 3
            or len(legs) != 3
            or self.periodic_axes
            or not all(isinstance(leg, DyadLeg) for leg in legs)
            or len({leg.distal for leg in legs}) != 1  # type: ignore[attr-defined]
        ):
            return None
        return SphereCentres(legs)  # type: ignore[arg-type]

    @classmethod
    def from_spec(cls, spec: Mapping[str, Any]) -> CustomMechanism:
        """The mechanism of a custom spec."""
        return cls(spec)

    @staticmethod
    def normalise_spec(data: Mapping[str, Any]) -> dict[str, Any]:
        """The spec checked and normalised (:func:`normalise_custom_spec`)."""
        return normalise_custom_spec(data)

    def to_spec(self) -> dict[str, Any]:
        """The normalised spec (JSON-ready)."""
        return normalise_custom_spec(self.spec)

    def det_a_boxes(
        self, lo: Array, hi: Array, angles: list[Interval], posture: int | None = None
    ) -> Interval:
        """Enclosure of det A over boxes of poses and the legs' joint enclosures: the
        determinant of the legs' rows on intervals, narrowed along the sheet where
        the legs have their second derivatives (:func:`.sheet_det.det_along_sheets`)."""
        rows = [leg.a_row_boxes(lo, hi, angles[i]) for i, leg in enumerate(self.legs)]
        return det_along_sheets(self, lo, hi, angles, rows)

    def det_a_postures(
        self, lo: Array, hi: Array, branch_angles: Sequence[Sequence[Interval | None]]
    ) -> list[Interval]:
        """:meth:`det_a_boxes` of every posture, what each leg needs on a branch
        (its rows, and its terms of the form along the sheets) computed once for
        every posture that takes it (:func:`.sheet_det.dets_along_sheets`)."""
        rows: dict[tuple[int, int], list[Interval]] = {}
        for p, branches in enumerate(self.postures):
            for i, b in enumerate(branches):
                angle = branch_angles[i][int(b)]
                if angle is None:
                    raise ValueError(f"branch_angles: no enclosure for a branch of posture {p}")
                if (i, int(b)) not in rows:
                    rows[i, int(b)] = self.legs[i].a_row_boxes(lo, hi, angle)
        return dets_along_sheets(self, lo, hi, branch_angles, self.postures, rows)

    def constraint_codes(
        self,
        lo: Array,
        hi: Array,
        angles: list[Interval],
        posture: int | None = None,
        regular: NDArray[np.bool_] | None = None,
    ) -> NDArray[np.uint8] | None:
        """Whether every configuration over each box keeps every passive angle
        within its limits (``INSIDE``), one certainly leaves them (``OUTSIDE``),
        or it cannot tell; None without passive limits.

        Each angle is enclosed over the box of poses and its leg's joint
        enclosure ``angles[leg]`` (which holds the posture's configurations),
        then classified modulo 2 pi (:meth:`JointLimit.classify`). A
        non-finite enclosure (an expression undefined or discontinuous over
        the box) cannot tell. ``posture`` and ``regular`` are not needed.
        """
        chosen = self.restrictions.passive
        if not self.passive_angles or not chosen:
            return None
        n = lo.shape[0]
        pose = [Interval(lo[:, j], hi[:, j]) for j in range(lo.shape[1])]
        holds = np.ones(n, dtype=bool)
        fails = np.zeros(n, dtype=bool)
        for angle in self.passive_angles:
            if angle.name not in chosen:
                continue
            with np.errstate(all="ignore"):
                value = iv.as_interval(angle.function(*pose, angles[angle.leg]))
                a_lo = np.broadcast_to(value.lo, (n,))
                a_hi = np.broadcast_to(value.hi, (n,))
                known = np.isfinite(a_lo) & np.isfinite(a_hi)
                codes = chosen[angle.name].classify(
                    Interval(np.where(known, a_lo, -np.inf), np.where(known, a_hi, np.inf))
                )
            codes = np.where(known, codes, STRADDLES)
            holds &= codes == INSIDE
            fails |= codes == OUTSIDE
        return np.where(fails, OUTSIDE, np.where(holds, INSIDE, STRADDLES)).astype(np.uint8)

    def constraint_margins(
        self,
        lo: Array,
        hi: Array,
        angles: list[Interval],
        posture: int | None = None,
        regular: NDArray[np.bool_] | None = None,
    ) -> ConstraintMargins | None:
        """The rates of the passive angles along motions are not known (the legs give
        no flows, :func:`moveability.analysis.flows.supports_flows`): refused
        rather than answered as if there were no constraint."""
        if self.passive_angles and self.restrictions.passive:
            raise NotImplementedError("no rates for the passive angles of a custom mechanism")
        return None

    def __repr__(self) -> str:
        legs = "; ".join(f"{leg['joint']}: {leg['constraint']} = 0" for leg in self.spec["legs"])
        extra = "".join(
            f"; {a.name}: {self.spec['legs'][a.leg]['passive'][a.name]['angle']} in "
            f"[{a.limit.lo:g}, {a.limit.hi:g}]"
            for a in self.passive_angles
        )
        return f"CustomMechanism(pose={list(self.pose_names)}, {legs}{extra})"
