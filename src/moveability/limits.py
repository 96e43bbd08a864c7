"""Joint limits and the three-valued test of an angle enclosure against them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .compiled import kernel
from .errors import InvalidParameterError
from .intervals import Interval, flat_arrays, next_below

__all__ = ["INSIDE", "OUTSIDE", "STRADDLES", "JointLimit", "classify_angles"]

#: codes returned by :meth:`JointLimit.classify`
INSIDE, OUTSIDE, STRADDLES = 1, 2, 4

_TWO_PI = 2.0 * np.pi
# 2 pi is not a float: the shift by k turns is enclosed in [k * lo, k * hi]
_TWO_PI_LO = float(np.nextafter(_TWO_PI, 0.0))
_TWO_PI_HI = float(np.nextafter(_TWO_PI, np.inf))


@dataclass(frozen=True)
class JointLimit:
    """Range ``[lo, hi]`` of a revolute joint angle (radians), or unlimited; or the
    stroke of a prismatic joint (``prismatic=True``, pose units).

    A limited joint cannot wrap around: with ``[-pi, pi]`` the angle ``pi`` is a
    stop, not the same position as ``-pi`` reached from the other side.
    Revolute ranges wider than one turn are refused. A prismatic stroke is a
    plain interval: its values never wrap.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability.intervals import Interval
    >>> limit = JointLimit(0.0, np.pi)
    >>> limit.classify(Interval([0.1, 3.0, -3.0], [0.2, 3.3, -2.0])).tolist()
    [1, 4, 2]
    >>> JointLimit.unlimited().classify(Interval([5.0], [9.0])).tolist()
    [1]
    >>> stroke = JointLimit(10.0, 25.0, prismatic=True)
    >>> stroke.classify(Interval([9.0, 12.0], [11.0, 13.0])).tolist()
    [4, 1]
    """

    lo: float
    hi: float
    periodic: bool = False
    prismatic: bool = False

    def __post_init__(self) -> None:
        if self.periodic:
            if self.prismatic:
                raise InvalidParameterError("limits", "a finite stroke [lo, hi]", "unlimited")
            return
        if not (np.isfinite(self.lo) and np.isfinite(self.hi)):
            raise InvalidParameterError("limits", "finite bounds", (self.lo, self.hi))
        if not self.lo < self.hi:
            raise InvalidParameterError("limits", "lo < hi", (self.lo, self.hi))
        if not self.prismatic and self.hi - self.lo > _TWO_PI_HI:
            raise InvalidParameterError(
                "limits", "a range of at most 2 pi (use 'unlimited')", (self.lo, self.hi)
            )

    @classmethod
    def unlimited(cls) -> JointLimit:
        """A joint that turns freely (a periodic axis)."""
        return cls(-np.pi, np.pi, periodic=True)

    def classify(self, angles: Interval) -> NDArray[np.uint8]:
        """Whether every angle of each interval is inside the range (``INSIDE``),
        none is (``OUTSIDE``), or it cannot tell (``STRADDLES``).

        Angles are unwrapped: an interval stands for its values modulo 2 pi.
        """
        if self.periodic:
            return np.full(angles.lo.shape, INSIDE, dtype=np.uint8)
        if self.prismatic:
            shape, (a_lo, a_hi) = flat_arrays(angles.lo, angles.hi)
            return _classify_stroke(a_lo, a_hi, float(self.lo), float(self.hi)).reshape(shape)
        return classify_angles(angles, self.lo, self.hi)

    def pieces(
        self, angles: Interval
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.bool_]]:
        """The pieces of the range that each enclosure meets, and which of their ends
        are stops inside the enclosure.

        An enclosure of a limited revolute joint may hold values on both sides of a
        stop: near ``hi`` and, a turn on, near ``lo``. Piece 0 is where the
        enclosure enters the range, piece 1 its next turn from ``lo`` (see
        :func:`moveability.analysis.regions.region_graph`). Returns ``(exists, lower,
        upper)``, each of shape (2, ...): whether the piece may hold values,
        whether its lower end is a lower stop inside the enclosure (a motion that
        never decreases the joint keeps such values valid), and whether its upper
        end is an upper stop inside the enclosure. Free joints have one piece
        without stops; strokes one piece.

        Examples
        --------
        >>> import numpy as np
        >>> from moveability.intervals import Interval
        >>> exists, lower, upper = JointLimit(-np.pi, np.pi).pieces(Interval([3.0], [3.3]))
        >>> exists[:, 0].tolist(), lower[:, 0].tolist(), upper[:, 0].tolist()
        ([True, True], [False, True], [True, False])
        """
        shape = (2, *angles.lo.shape)
        exists = np.zeros(shape, dtype=bool)
        lower = np.zeros(shape, dtype=bool)
        upper = np.zeros(shape, dtype=bool)
        a, b = angles.lo, angles.hi
        with np.errstate(invalid="ignore", over="ignore"):
            tol = 1e-9 * np.maximum(1.0, np.maximum(np.abs(a), np.abs(b)))
            if self.periodic:
                exists[0] = True
                return exists, lower, upper
            if self.prismatic:
                exists[0] = ~((b < self.lo - tol) | (a > self.hi + tol))
                lower[0] = ~(a > self.lo + tol)
                upper[0] = ~(b < self.hi - tol)
                return exists, lower, upper
            k = np.floor((a - self.lo) / _TWO_PI)
            k = np.where(np.isfinite(k), k, 0.0)
            a0 = a - _TWO_PI * k
            b0 = b - _TWO_PI * k
            wide = ~(b - a < _TWO_PI - tol)
            exists[0] = wide | ~(a0 > self.hi + tol)
            lower[0] = wide | ~(a0 > self.lo + tol)
            upper[0] = wide | ~(b0 < self.hi - tol)
            exists[1] = ~wide & ~(b0 - _TWO_PI < self.lo - tol)
            lower[1] = True
            upper[1] = ~(b0 - _TWO_PI < self.hi - tol)
        return exists, lower, upper

    def wrap(self, angles: ArrayLike) -> NDArray[np.float64]:
        """Representatives of angles in ``[lo, lo + 2 pi)`` (in ``[-pi, pi)`` if unlimited);
        prismatic values as they are."""
        a = np.asarray(angles, dtype=np.float64)
        if self.prismatic:
            return a
        return self.lo + np.mod(a - self.lo, _TWO_PI)

    def contains(self, angles: ArrayLike) -> NDArray[np.bool_]:
        """Whether point angles (any turn) fall in the range."""
        if self.periodic:
            return np.isfinite(np.asarray(angles, dtype=np.float64))
        if self.prismatic:
            a = np.asarray(angles, dtype=np.float64)
            return (a >= self.lo) & (a <= self.hi)
        return self.wrap(angles) <= self.hi


def classify_angles(angles: Interval, lo: ArrayLike, hi: ArrayLike) -> NDArray[np.uint8]:
    """Whether every angle of each interval lies in ``[lo, hi]`` modulo 2 pi (``INSIDE``),
    none does (``OUTSIDE``), or it cannot tell (``STRADDLES``).

    ``angles`` are unwrapped intervals; ``lo`` and ``hi`` (scalars or arrays) are
    bounds of ranges at most one turn wide.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability.intervals import Interval
    >>> classify_angles(Interval([0.1, 6.4], [0.2, 6.5]), [0.0, 0.0], [1.0, 0.1]).tolist()
    [1, 2]
    """
    with np.errstate(over="ignore", invalid="ignore"):
        shape, flat = flat_arrays(angles.lo, angles.hi, lo, hi)
        return _classify(*flat).reshape(shape)


@kernel
def _classify_stroke(
    a_lo: NDArray[np.float64], a_hi: NDArray[np.float64], lo: float, hi: float
) -> NDArray[np.uint8]:  # pragma: no cover - compiled
    """:meth:`JointLimit.classify` of a stroke ``[lo, hi]``, flat arrays: ``INSIDE``
    where ``lo <= a_lo`` and ``a_hi <= hi``, then ``OUTSIDE`` where ``a_hi < lo``
    or ``a_lo > hi``, ``STRADDLES`` elsewhere (NaN bounds included)."""
    out = np.empty(a_lo.size, dtype=np.uint8)
    for i in range(a_lo.size):
        if a_hi[i] < lo or a_lo[i] > hi:
            out[i] = OUTSIDE
        elif a_lo[i] >= lo and a_hi[i] <= hi:
            out[i] = INSIDE
        else:
            out[i] = STRADDLES
    return out


@kernel
def _shifted(a: float, turns: float) -> float:  # pragma: no cover - compiled
    """An enclosure's bound ``a`` moved ``turns`` turns: ``turns * 2 pi`` is enclosed in
    ``[turns * 2pi_lo, turns * 2pi_hi]`` and every rounding is widened outwards
    (down for a lower bound; an upper bound calls it on ``-a``, ``-turns``)."""
    shift = turns * _TWO_PI_LO if turns >= 0 else turns * _TWO_PI_HI
    return next_below(a + next_below(shift))


@kernel
def _classify_one(a_lo: float, a_hi: float, lo: float, hi: float) -> int:  # pragma: no cover
    width = a_hi - a_lo
    # k turns bring the interval near [lo, lo + 2 pi); the tests below are sound for
    # any k, the choice only makes them sharp
    k = np.floor((a_lo - lo) / _TWO_PI)
    k = -k if np.isfinite(k) else 0.0
    narrow = width < _TWO_PI_LO
    if narrow and _shifted(a_lo, k) >= lo and -_shifted(-a_hi, -k) <= hi:
        return INSIDE
    if not narrow:
        return STRADDLES
    for j in (-2.0, -1.0, 0.0, 1.0, 2.0):
        t_lo = _shifted(a_lo, k + j)
        t_hi = -_shifted(-a_hi, -(k + j))
        if not (t_lo > hi or t_hi < lo):
            return STRADDLES
    return OUTSIDE


@kernel
def _classify(
    a_lo: NDArray[np.float64],
    a_hi: NDArray[np.float64],
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
) -> NDArray[np.uint8]:  # pragma: no cover - compiled
    out = np.empty(a_lo.size, dtype=np.uint8)
    for i in range(a_lo.size):
        out[i] = _classify_one(a_lo[i], a_hi[i], lo[i], hi[i])
    return out
