"""The types every layer shares: float arrays and three-valued answers.

A definite answer is ``True`` or ``False``; ``None`` says the certified
computation could not decide (the cells that would tell are below the
precision). Arrays of answers hold the codes :data:`YES`, :data:`NO` and
:data:`UNKNOWN` (``int8``). In JSON the answers are ``true``, ``false`` and
``null``; text for people says ``yes``, ``no`` and ``unknown``.
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

__all__ = ["NO", "UNKNOWN", "YES", "Answer", "Array", "answer", "word"]

#: float64 arrays, the currency of the package
Array: TypeAlias = NDArray[np.float64]

#: a three-valued answer: True, False, or None when undecided
Answer: TypeAlias = bool | None

#: codes of three-valued answers in int8 arrays
YES, NO, UNKNOWN = 1, 0, -1


def answer(code: int) -> Answer:
    """The answer of a code (:data:`YES`, :data:`NO`, :data:`UNKNOWN`).

    Examples
    --------
    >>> [answer(c) for c in (YES, NO, UNKNOWN)]
    [True, False, None]
    """
    return None if code == UNKNOWN else bool(code == YES)


def word(value: Answer) -> str:
    """``yes``, ``no`` or ``unknown``: an answer in a text for people.

    Examples
    --------
    >>> [word(v) for v in (True, False, None)]
    ['yes', 'no', 'unknown']
    """
    if value is None:
        return "unknown"
    return "yes" if value else "no"
