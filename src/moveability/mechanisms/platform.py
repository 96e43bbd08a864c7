"""The platform of a three-legged planar mechanism, for its constraints.

The platform joints ``B_i = P + R(phi) b_i`` (pose ``(x, y, phi)``, ``b_i`` in
the platform frame) and their velocities, enclosed over boxes of poses, and
the platform's sides as links (see :mod:`moveability.mechanisms.constraints`).
"""

from __future__ import annotations

from collections.abc import Sequence

from .. import intervals as iv
from ..intervals import Interval
from ..types import Array

__all__ = ["platform_points", "platform_sides", "platform_velocities"]

#: a point of the linkage over n boxes: (x, y) enclosures
_Point = tuple[Interval, Interval]


def platform_points(
    lo: Array, hi: Array, platform: Sequence[tuple[float, float]]
) -> tuple[dict[str, _Point], list[_Point]]:
    """Enclosures of the platform joints ``B_i = P + R(phi) b_i`` over boxes of poses
    (x, y, phi), by name, and of the turned vectors ``R(phi) b_i``."""
    phi = Interval(lo[:, 2], hi[:, 2])
    c, s = iv.cos(phi), iv.sin(phi)
    x, y = Interval(lo[:, 0], hi[:, 0]), Interval(lo[:, 1], hi[:, 1])
    points, turned = {}, []
    for i, (bx, by) in enumerate(platform):
        rb = (c * bx - s * by, s * bx + c * by)
        turned.append(rb)
        points[f"B{i + 1}"] = (x + rb[0], y + rb[1])
    return points, turned


def platform_velocities(turned: list[_Point], velocity: list[Interval]) -> dict[str, _Point]:
    """Enclosures of the velocities of the platform joints when the pose moves at
    ``velocity`` (x', y', phi'): ``P' + phi' (-(R b_i)_y, (R b_i)_x)``."""
    return {
        f"B{i + 1}": (velocity[0] - velocity[2] * rb[1], velocity[1] + velocity[2] * rb[0])
        for i, rb in enumerate(turned)
    }


def platform_sides() -> tuple[tuple[str, str], ...]:
    """The platform's sides ``B1 B2``, ``B2 B3``, ``B3 B1``."""
    return tuple((f"B{i + 1}", f"B{(i + 1) % 3 + 1}") for i in range(3))
