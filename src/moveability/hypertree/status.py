"""Cell statuses of a 2^k-tree and their three-valued (Kleene) logic.

A leaf is entirely in the set (``IN``), entirely outside it (``OUT``) or not
decided at its depth (``BOUNDARY``). The values are bit flags, so a set of
statuses is written ``IN | BOUNDARY`` where a function accepts several.
"""

from __future__ import annotations

import enum

import numpy as np
from numpy.typing import NDArray

__all__ = ["BOUNDARY", "IN", "OUT", "Status"]


class Status(enum.IntFlag):
    """Status of a cell; members combine as flags.

    Examples
    --------
    >>> from moveability import IN, BOUNDARY, Status
    >>> Status(IN | BOUNDARY)
    <Status.IN|BOUNDARY: 5>
    """

    IN = 1
    OUT = 2
    BOUNDARY = 4


IN = Status.IN
OUT = Status.OUT
BOUNDARY = Status.BOUNDARY

_VALID = np.array([False, True, True, False, True, False, False, False])


def _table(rule: dict[tuple[int, int], int]) -> NDArray[np.uint8]:
    table = np.zeros((8, 8), dtype=np.uint8)
    for (a, b), value in rule.items():
        table[a, b] = value
    return table


def _kleene(op: str) -> NDArray[np.uint8]:
    rule = {}
    for a in (IN, OUT, BOUNDARY):
        for b in (IN, OUT, BOUNDARY):
            if op == "and":
                if a == OUT or b == OUT:
                    v = OUT
                elif a == IN and b == IN:
                    v = IN
                else:
                    v = BOUNDARY
            else:
                if a == IN or b == IN:
                    v = IN
                elif a == OUT and b == OUT:
                    v = OUT
                else:
                    v = BOUNDARY
            rule[int(a), int(b)] = int(v)
    return _table(rule)


AND_TABLE = _kleene("and")
OR_TABLE = _kleene("or")
NOT_TABLE = np.array([0, int(OUT), int(IN), 0, int(BOUNDARY), 0, 0, 0], dtype=np.uint8)


def is_valid_status(values: NDArray[np.integer]) -> NDArray[np.bool_]:
    """Whether each value is exactly one of IN, OUT, BOUNDARY."""
    v = np.asarray(values)
    inside = (v >= 0) & (v < 8)
    out = np.zeros(v.shape, dtype=bool)
    out[inside] = _VALID[v[inside].astype(np.intp)]
    return out


def status_mask(status: int) -> NDArray[np.bool_]:
    """Lookup table: ``mask[s]`` is True when status value ``s`` is in ``status``."""
    s = int(status)
    return np.array([bool(v & s) and bool(_VALID[v]) for v in range(8)])
