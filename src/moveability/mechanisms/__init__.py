"""Mechanism models: one module per manipulator, a registry, and :func:`from_spec`."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..errors import InvalidParameterError
from ..limits import JointLimit
from .base import Mechanism
from .biglide import Biglide
from .five_bar import FiveBar
from .three_rpr import ThreeRPR
from .three_rrr import ThreeRRR

__all__ = [
    "MECHANISMS",
    "Biglide",
    "CustomMechanism",
    "FiveBar",
    "Mechanism",
    "ThreeRPR",
    "ThreeRRR",
    "from_spec",
]

#: built-in mechanisms by spec name; ``"custom"`` (sympy, imported when used) too
MECHANISMS: dict[str, type[Mechanism]] = {
    "five-bar": FiveBar,
    "3-RPR": ThreeRPR,
    "3-RRR": ThreeRRR,
    "biglide": Biglide,
}


def __getattr__(name: str) -> Any:
    # sympy takes a second to import: user-defined mechanisms load it when used
    if name == "CustomMechanism":
        from .custom import CustomMechanism

        return CustomMechanism
    raise AttributeError(name)


def _limit(name: str, value: Any, prismatic: bool = False) -> JointLimit:
    if isinstance(value, str) and value == "unlimited" and not prismatic:
        return JointLimit.unlimited()
    try:
        lo, hi = value
        return JointLimit(float(lo), float(hi), prismatic=prismatic)
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
    if name == "custom":
        from .custom import CustomMechanism

        return CustomMechanism.from_spec(spec)
    if name not in MECHANISMS:
        raise InvalidParameterError("mechanism", f"one of {[*MECHANISMS, 'custom']}", name)
    params = dict(spec.get("parameters", {}))
    limits_spec = spec.get("limits", {})

    def limits(*joints: str, prismatic: bool = False) -> tuple[JointLimit, ...]:
        for joint in joints:
            if joint not in limits_spec:
                raise InvalidParameterError(f"limits.{joint}", "[lo, hi] or 'unlimited'", "nothing")
        return tuple(_limit(j, limits_spec[j], prismatic) for j in joints)

    def parameters(*names: str) -> list[Any]:
        missing = [k for k in names if k not in params]
        if missing:
            raise InvalidParameterError(f"parameters.{missing[0]}", "a value", "nothing")
        return [params[k] for k in names]

    if name == "five-bar":
        lim = limits("theta1", "theta2")
        L0, L1, L2, L3, L4 = (float(v) for v in parameters("L0", "L1", "L2", "L3", "L4"))
        return FiveBar(L0, L1, L2, L3, L4, limits=(lim[0], lim[1]))
    if name == "3-RPR":
        lim = limits("rho1", "rho2", "rho3", prismatic=True)
        base, platform = parameters("base", "platform")
        return ThreeRPR(base, platform, (lim[0], lim[1], lim[2]))
    if name == "biglide":
        lim = limits("rho1", "rho2", prismatic=True)
        L1, L2 = (float(v) for v in parameters("L1", "L2"))
        return Biglide(L1, L2, (lim[0], lim[1]))
    if name == "3-RRR":
        lim = limits("theta1", "theta2", "theta3")
        base, platform, proximal, distal = parameters("base", "platform", "proximal", "distal")
        return ThreeRRR(base, platform, proximal, distal, lim)
    raise InvalidParameterError("mechanism", f"one of {sorted(MECHANISMS)}", name)
