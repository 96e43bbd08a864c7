"""Mechanism models: one module per manipulator, and the registry that names them.

:mod:`.registry` holds the one table of known mechanisms (name -> model and
schema), :func:`load_spec` and :func:`from_spec`. The user-defined mechanism
(:class:`CustomMechanism`, which needs sympy) is imported when used.
"""

from __future__ import annotations

from typing import Any

from . import registry
from .base import Mechanism
from .biglide import Biglide
from .delta import Delta
from .five_bar import FiveBar
from .registry import MECHANISMS, from_spec, load_spec
from .three_rpr import ThreeRPR
from .three_rrr import ThreeRRR

__all__ = [
    "MECHANISMS",
    "Biglide",
    "CustomMechanism",
    "Delta",
    "FiveBar",
    "Mechanism",
    "ThreeRPR",
    "ThreeRRR",
    "from_spec",
    "load_spec",
]


def __getattr__(name: str) -> Any:
    # sympy takes a second to import: the user-defined mechanism loads it when used
    if name == "CustomMechanism":
        return registry.mechanism_class("custom")
    raise AttributeError(name)
