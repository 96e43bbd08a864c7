"""Postures whose valid configurations sit over the same poses of a leaf.

A configuration of posture p at a pose X is valid when every leg reaches X and
every joint of p lies within its limits. Each leg's joint depends on that
leg's branch alone, and a leg's branches exist at the same poses (two roots,
a double root at the fold, or none). So over a leaf where a leg's joint is
certainly within its limits on every branch, and the leg has no more than its
branches there, the leg's branch changes nothing in which poses hold a valid
configuration: two postures that differ only in the branches of such legs have
the *same valid set* over the leaf, the same poses of W. This is what lets a
region be shown to cover W where a joint limit cuts it: over a leaf cut by the
limit of leg 2 only, a region that holds posture (a, b) wherever it is valid
holds every pose where any posture (a', b) is valid.

Constraints beyond the joint limits (passive limits, obstacles, collisions)
depend on every joint of a configuration: with any of them each posture keeps
its own valid set.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..hypertree.status import OUT
from ..intervals import Interval
from ..limits import INSIDE
from ..mechanisms.base import FOLD_INNER, FOLD_OUTER, REGULAR, Mechanism
from .sheets import SheetTable

__all__ = ["covered_by_classes", "free_legs", "valid_set_classes"]


def free_legs(mechanism: Mechanism, table: SheetTable) -> NDArray[np.bool_]:
    """(n, n_legs): legs whose branch changes no valid set over the leaf.

    A leg is *free* over a leaf when it is REGULAR there or certainly folds in it
    (its branches then exist at the same poses: both, meeting at the fold, or
    neither) and its joint is certainly within its limits on every posture's
    enclosure (a free or whole-turn joint always is). A leg that may hold more
    roots than its branches (``REACH_UNKNOWN``) is never free.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability.analysis.sheets import classify_sheets
    >>> from moveability.limits import JointLimit
    >>> from moveability.mechanisms import FiveBar
    >>> m = FiveBar(limits=(JointLimit.unlimited(), JointLimit(0.0, 0.6)))
    >>> table = classify_sheets(m, np.array([[3.0, 9.0]]), np.array([[3.1, 9.1]]))
    >>> free_legs(m, table).tolist()
    [[True, False]]
    """
    status = table.leg_status
    free = (status == REGULAR) | (status == FOLD_OUTER) | (status == FOLD_INNER)
    n, n_post = table.status.shape
    for i, limit in enumerate(mechanism.limits):
        if limit.periodic or (not limit.prismatic and limit.hi - limit.lo >= 2 * np.pi):
            continue
        angles = Interval(table.angles_lo[:, :, i].ravel(), table.angles_hi[:, :, i].ravel())
        with np.errstate(invalid="ignore"):
            inside = (limit.classify(angles) == INSIDE).reshape(n, n_post)
        free[:, i] &= inside.all(axis=1)
    return np.asarray(free, dtype=bool)


def valid_set_classes(mechanism: Mechanism, table: SheetTable) -> NDArray[np.int64]:
    """(n, P): per leaf, a label of each posture; postures with one label have the
    same valid set over the leaf (see the module's docstring).

    The label spells the posture's branches of the legs that are not free over
    the leaf (:func:`free_legs`). With constraints beyond the joint limits each
    posture is its own class.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability.analysis.sheets import classify_sheets
    >>> from moveability.limits import JointLimit
    >>> from moveability.mechanisms import FiveBar
    >>> m = FiveBar(limits=(JointLimit.unlimited(), JointLimit(0.0, 0.6)))
    >>> table = classify_sheets(m, np.array([[3.0, 9.0]]), np.array([[3.1, 9.1]]))
    >>> [m.posture_name(p) for p in range(4)], valid_set_classes(m, table).tolist()
    (['++', '+-', '-+', '--'], [[0, 2, 0, 2]])
    """
    n, n_post = table.status.shape
    postures = mechanism.postures
    if not mechanism.restrictions.empty:
        return np.broadcast_to(np.arange(n_post, dtype=np.int64), (n, n_post)).copy()
    free = free_legs(mechanism, table)
    radix = int(postures.max(initial=0)) + 1
    labels = np.zeros((n, n_post), dtype=np.int64)
    weight = 1
    for i in range(postures.shape[1]):
        labels += np.where(free[:, i : i + 1], 0, postures[None, :, i]) * weight
        weight *= radix
    return labels


def covered_by_classes(
    labels: NDArray[np.int64], status: NDArray[np.uint8], good: NDArray[np.bool_]
) -> NDArray[np.bool_]:
    """(n,): leaves where every class of postures (``labels``, see
    :func:`valid_set_classes`) holds a ``good`` node or only nodes with no valid
    configuration (OUT).

    Where ``good`` marks nodes each of whose valid configurations lies in one
    region, such a leaf has, at every pose of W over it, a configuration in
    that region: a pose of W has a valid configuration of some posture, and a
    good node of that posture's class holds a valid configuration at the same
    pose.

    Examples
    --------
    >>> import numpy as np
    >>> labels = np.array([[0, 1, 0, 1], [0, 1, 0, 1]])
    >>> status = np.array([[4, 4, 4, 4], [4, 2, 4, 2]], dtype=np.uint8)  # 2: OUT
    >>> good = np.array([[True, False, False, False], [True, False, False, False]])
    >>> covered_by_classes(labels, status, good).tolist()
    [False, True]
    """
    out = status == OUT
    ok = np.ones(labels.shape[0], dtype=bool)
    for p in range(labels.shape[1]):
        same = labels == labels[:, p : p + 1]
        ok &= (same & good).any(axis=1) | (~same | out).all(axis=1)
    return ok
