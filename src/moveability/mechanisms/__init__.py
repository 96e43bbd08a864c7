"""Mechanism models: one module per manipulator, a registry, and :func:`from_spec`."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..errors import InvalidParameterError
from ..limits import JointLimit
from .base import Mechanism
from .five_bar import FiveBar

__all__ = ["MECHANISMS", "FiveBar", "Mechanism", "from_spec"]

MECHANISMS: dict[str, type[Mechanism]] = {"five-bar": FiveBar}


def _limit(name: str, value: Any) -> JointLimit:
    if isinstance(value, str) and value == "unlimited":
        return JointLimit.unlimited()
    try:
        lo, hi = value
        return JointLimit(float(lo), float(hi))
    except InvalidParameterError as exc:
        raise InvalidParameterError(f"limits.{name}", exc.allowed, exc.received) from None
    except (TypeError, ValueError):
        raise InvalidParameterError(
            f"limits.{name}", "[lo, hi] in radians or 'unlimited'", value
        ) from None


def from_spec(spec: Mapping[str, Any]) -> Mechanism:
    """Build a mechanism from a spec mapping (see :func:`moveability.spec.load_spec`).

    Examples
    --------
    >>> m = from_spec({"mechanism": "five-bar",
    ...                "parameters": {"L0": 7, "L1": 8, "L2": 5, "L3": 8, "L4": 5},
    ...                "limits": {"theta1": [0, 3.14159], "theta2": "unlimited"}})
    >>> m.name, m.joint_names
    ('five-bar', ('theta1', 'theta2'))
    """
    name = spec.get("mechanism")
    if name not in MECHANISMS:
        raise InvalidParameterError("mechanism", f"one of {sorted(MECHANISMS)}", name)
    params = dict(spec.get("parameters", {}))
    limits_spec = spec.get("limits", {})
    if name == "five-bar":
        for joint in ("theta1", "theta2"):
            if joint not in limits_spec:
                raise InvalidParameterError(f"limits.{joint}", "[lo, hi] or 'unlimited'", "nothing")
        limits = tuple(_limit(j, limits_spec[j]) for j in ("theta1", "theta2"))
        missing = [k for k in ("L0", "L1", "L2", "L3", "L4") if k not in params]
        if missing:
            raise InvalidParameterError(f"parameters.{missing[0]}", "a positive length", "nothing")
        L0, L1, L2, L3, L4 = (float(params[k]) for k in ("L0", "L1", "L2", "L3", "L4"))
        return FiveBar(L0, L1, L2, L3, L4, limits=(limits[0], limits[1]))
    raise InvalidParameterError("mechanism", f"one of {sorted(MECHANISMS)}", name)
