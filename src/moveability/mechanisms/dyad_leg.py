"""A leg given by its constraint that is a dyad: a distal link of fixed length
from a knee that the actuated joint moves.

A user-defined leg whose constraint is ``F(X, q) = lam (|X - K(q)|^2 - b^2)``,
``lam`` a nonzero constant, puts the platform point on the circle (sphere) of
radius ``b`` about the knee ``K(q)``, as the built-in five-bar's and biglide's
legs do. :mod:`moveability.mechanisms.custom` recognises such constraints
(sympy) and gives the knee, its first two derivatives along q and ``b``; the
joint-space count of :mod:`moveability.analysis.joint_space` then applies to
two of them, as to the built-in twins.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import intervals as iv
from ..intervals import Interval
from ..types import Array
from .constraint_leg import ConstraintLeg, Function
from .delta import Circumradius

__all__ = ["DyadLeg", "SphereCentres"]


@dataclass(frozen=True, eq=False)
class DyadLeg(ConstraintLeg):
    """A :class:`~moveability.mechanisms.constraint_leg.ConstraintLeg` whose
    constraint is a circle (sphere) of radius :attr:`distal` about a knee.

    Parameters
    ----------
    knee, knee_rate, knee_curve : tuple of callable
        ``K_j(q)``, ``K_j'(q)`` and ``K_j''(q)`` per pose axis, with the
        signature of the constraint (``g(x_1, ..., x_k, q)``, the pose unused),
        on floats and on Intervals.
    knee_mp : tuple of callable
        ``K_j`` as ``h(q, ctx)`` in an mpmath interval context ``ctx``.
    distal : float
        The radius ``b``.
    """

    knee: tuple[Function, ...] = ()
    knee_rate: tuple[Function, ...] = ()
    knee_curve: tuple[Function, ...] = ()
    knee_mp: tuple[Callable[[Any, Any], Any], ...] = ()
    knee_mp_rate: tuple[Callable[[Any, Any], Any], ...] = ()
    distal: float = 0.0

    def knee_boxes(self, angles: Interval) -> tuple[list[Interval], ...]:
        """The knee and its first two derivatives along the joint over enclosures
        of the joint (see :mod:`moveability.analysis.joint_space`)."""
        angles = iv.as_interval(angles)
        zero = iv.as_interval(np.zeros(np.shape(angles.lo)))
        pose = [zero] * len(self.knee)

        def at(fns: tuple[Function, ...]) -> list[Interval]:
            out = []
            for g in fns:
                v = iv.as_interval(g(*pose, angles))
                # constants (a knee's fixed coordinate) spread over the angles
                out.append(Interval(v.lo + zero.lo, v.hi + zero.lo))
            return out

        return at(self.knee), at(self.knee_rate), at(self.knee_curve)

    def centre_boxes(self, angles: Interval) -> list[Interval]:
        """The knee over enclosures of the joint: the centre of the sphere the
        platform point lies on (as the Delta's legs give it)."""
        return self.knee_boxes(angles)[0]

    def knee_exact(self, angle: Any, ctx: Any) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
        """The knee and its derivative at an interval ``angle`` of the mpmath
        interval context ``ctx`` (the stop traces of
        :mod:`moveability.analysis.stop_traces`)."""
        return (
            tuple(h(angle, ctx) for h in self.knee_mp),
            tuple(h(angle, ctx) for h in self.knee_mp_rate),
        )


class SphereCentres(Circumradius):
    """The Delta's condition in the joint space (see
    :class:`~moveability.mechanisms.delta.Circumradius`) for three dyad legs
    whose spheres have one radius: the centres and their rates come from the
    legs' knees."""

    def __init__(self, legs: tuple[DyadLeg, ...]) -> None:
        self.legs = legs  # type: ignore[assignment]
        self.rod = float(legs[0].distal)
        self.lower = Interval(0.0)
        self.upper = Interval(np.inf)

    def _centres(self, lo: Array, hi: Array) -> tuple[list[list[Interval]], list[list[Interval]]]:
        centres, rates = [], []
        for i, leg in enumerate(self.legs):
            knee, rate, _ = leg.knee_boxes(Interval(lo[:, i], hi[:, i]))  # type: ignore[attr-defined]
            centres.append(knee)
            rates.append(rate)
        return centres, rates
