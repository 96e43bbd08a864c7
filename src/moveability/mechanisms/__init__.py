"""Mechanism models: one module per manipulator, and the registry that names them.

:mod:`.registry` holds the one table of known mechanisms (name -> model and
schema), :func:`load_spec` and :func:`from_spec`. Each model's module is
imported when its class is first asked for (``from moveability.mechanisms
import FiveBar`` imports the five-bar's alone), so a command pays only for the
mechanism it analyses; the user-defined one (:class:`CustomMechanism`) also
needs sympy.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from . import registry
from .base import Mechanism
from .registry import MECHANISMS, from_spec, load_spec

if TYPE_CHECKING:
    from .biglide import Biglide
    from .custom import CustomMechanism
    from .delta import Delta
    from .five_bar import FiveBar
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

#: the classes imported when first asked for, by the registry's name of their model
_MODELS = {
    "Biglide": "biglide",
    "CustomMechanism": "custom",
    "Delta": "delta",
    "FiveBar": "five-bar",
    "ThreeRPR": "3-RPR",
    "ThreeRRR": "3-RRR",
}


def __getattr__(name: str) -> Any:
    if name in _MODELS:
        return registry.mechanism_class(_MODELS[name])
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
