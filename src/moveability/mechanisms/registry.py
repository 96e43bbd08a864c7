"""The mechanisms moveability knows: one table, name -> (model, schema).

Adding a robot is writing its module (a :class:`~moveability.mechanisms.base.Mechanism`
whose constructor takes the parameters of its schema in order, then the joint
limits) and adding one line to :data:`MECHANISMS`. :func:`load_spec` checks a
specification against the schema its ``mechanism`` key names;
:func:`from_spec` builds the mechanism. A mechanism whose specification has a
format of its own (``custom``) has no schema: its class reads the spec
(``normalise_spec``, ``from_spec``).

Models are imported when first used, so that a command pays only for the
mechanism it analyses (the user-defined one needs sympy).
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Mapping
from typing import Any, NamedTuple

from ..errors import MissingExtraError, SpecError
from ..limits import JointLimit
from ..spec import NOTHING, MechanismSchema, check_spec, read_toml
from .base import Mechanism
from .constraints import Constraints

__all__ = ["MECHANISMS", "Registered", "from_spec", "load_spec", "mechanism_class"]


class Registered(NamedTuple):
    """One known mechanism.

    Parameters
    ----------
    model : str
        ``"module:Class"``, the module under :mod:`moveability.mechanisms`.
    schema : MechanismSchema or None
        What its specification gives; ``None`` when the class reads a format
        of its own.
    extra : str or None
        The optional dependency group the model needs (``pip install
        moveability[extra]``), if any.
    """

    model: str
    schema: MechanismSchema | None
    extra: str | None = None


_THREE = ("1", "2", "3")

#: known mechanisms, by the name a specification gives in its ``mechanism`` key
MECHANISMS: dict[str, Registered] = {
    "five-bar": Registered(
        "five_bar:FiveBar",
        MechanismSchema(
            parameters=("L0", "L1", "L2", "L3", "L4"),
            joints=("theta1", "theta2"),
            passive=("P", "C", "D"),
            shapes=True,
        ),
    ),
    "3-RPR": Registered(
        "three_rpr:ThreeRPR",
        MechanismSchema(
            parameters=("base", "platform"),
            joints=tuple(f"rho{i}" for i in _THREE),
            kinds={"base": "points", "platform": "points"},
            joint_kind="distance",
            passive=(*(f"A{i}" for i in _THREE), *(f"B{i}" for i in _THREE)),
            shapes=True,
        ),
    ),
    "biglide": Registered(
        "biglide:Biglide",
        MechanismSchema(parameters=("L1", "L2"), joints=("rho1", "rho2"), joint_kind="position"),
    ),
    "3-RRR": Registered(
        "three_rrr:ThreeRRR",
        MechanismSchema(
            parameters=("base", "platform", "proximal", "distal"),
            joints=tuple(f"theta{i}" for i in _THREE),
            kinds={
                "base": "points",
                "platform": "points",
                "proximal": "lengths",
                "distal": "lengths",
            },
            passive=(*(f"C{i}" for i in _THREE), *(f"B{i}" for i in _THREE)),
            shapes=True,
        ),
    ),
    "delta": Registered(
        "delta:Delta",
        MechanismSchema(
            parameters=("base_radius", "platform_radius", "arm", "rod"),
            joints=tuple(f"theta{i}" for i in _THREE),
        ),
    ),
    "custom": Registered("custom:CustomMechanism", None, extra="custom"),
}


def mechanism_class(name: str) -> type[Mechanism]:
    """The class modelling the mechanism ``name`` (a key of :data:`MECHANISMS`).

    Raises
    ------
    MissingExtraError
        When the model needs an optional dependency that is not installed.

    Examples
    --------
    >>> mechanism_class("five-bar").__name__
    'FiveBar'
    """
    entry = MECHANISMS[name]
    module, _, cls = entry.model.partition(":")
    try:
        loaded = importlib.import_module(f"{__package__}.{module}")
    except ModuleNotFoundError as error:
        if entry.extra is None or (error.name or "").startswith("moveability"):
            raise
        raise MissingExtraError(entry.extra, f"the {name} mechanism", error.name) from None
    found: type[Mechanism] = getattr(loaded, cls)
    return found


def _name(value: object) -> str:
    known = ", ".join(map(repr, MECHANISMS))
    if isinstance(value, str):
        lowered = {n.lower(): n for n in MECHANISMS}
        name = value.strip().lower()
        if name in lowered:
            return lowered[name]
    raise SpecError("mechanism", f"one of {known}", value)


def load_spec(source: str | os.PathLike[str] | Mapping[str, Any]) -> dict[str, Any]:
    """Read, check and normalise the specification of a manipulator.

    Parameters
    ----------
    source : str, os.PathLike or mapping
        Path to a TOML file, or the mapping such a file parses to (the output of
        :func:`load_spec` is accepted too).

    Returns
    -------
    dict
        ``{"mechanism": name, "parameters": {name: float}, "limits": {joint:
        (lo, hi) or "unlimited"}}``: parameters and joints in the order of the
        mechanism's schema, bounds as floats in radians (see
        :func:`moveability.spec.check_spec`); a ``custom`` mechanism's own
        normalised format.

    Raises
    ------
    SpecError
        A subclass of :class:`~moveability.errors.InvalidParameterError` whose
        message names the key at fault: the file (missing, unreadable, not
        TOML: tomllib's line and column are quoted), ``mechanism`` (unknown;
        the known ones are listed), ``parameters.<name>`` (missing, unknown,
        not a positive finite number), ``limits.<joint>`` (missing, unknown,
        not a pair ``[lo, hi]`` nor ``"unlimited"``, a bound that is not an
        angle, ``lo >= hi``, wider than 2 pi), or a top-level key that is
        not one of ``mechanism``, ``parameters``, ``limits``.

    Examples
    --------
    >>> spec = load_spec({
    ...     "mechanism": "five-bar",
    ...     "parameters": {"L0": 7, "L1": 8, "L2": 5, "L3": 8, "L4": 5},
    ...     "limits": {"theta1": [0, "pi"], "theta2": "unlimited"},
    ... })
    >>> spec["parameters"]
    {'L0': 7.0, 'L1': 8.0, 'L2': 5.0, 'L3': 8.0, 'L4': 5.0}
    >>> spec["limits"]
    {'theta1': (0.0, 3.141592653589793), 'theta2': 'unlimited'}
    >>> load_spec(spec) == spec
    True

    From a file:

    >>> import pathlib, tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = pathlib.Path(tmp, "five-bar.toml")
    ...     _ = path.write_text('''
    ... mechanism = "five-bar"
    ... [parameters]
    ... L0 = 7.0
    ... L1 = 8.0
    ... L2 = 5.0
    ... L3 = 8.0
    ... L4 = 5.0
    ... [limits]
    ... theta1 = ["-pi", "pi"]
    ... theta2 = [0.0, "pi/2"]
    ... ''')
    ...     load_spec(path)["limits"]["theta2"]
    (0.0, 1.5707963267948966)

    Errors name the key:

    >>> load_spec({"mechanism": "five-bar", "parameters": {"L0": 7, "L1": 8, "L2": -5}})
    Traceback (most recent call last):
        ...
    moveability.errors.SpecError: invalid parameters.L2: expected a positive finite length, got -5
    """
    if isinstance(source, Mapping):
        data: Mapping[str, Any] = source
    elif isinstance(source, str | os.PathLike):
        data = read_toml(source)
    else:
        raise SpecError("spec", "a path to a TOML file or a mapping", source)
    name = _name(data.get("mechanism", NOTHING))
    schema = MECHANISMS[name].schema
    if schema is None:
        own_format: Any = mechanism_class(name)
        return dict(own_format.normalise_spec(data))
    return check_spec(data, name, schema)


def from_spec(spec: str | os.PathLike[str] | Mapping[str, Any]) -> Mechanism:
    """Build the mechanism of a specification (checked by :func:`load_spec` first).

    Examples
    --------
    >>> m = from_spec({"mechanism": "five-bar",
    ...                "parameters": {"L0": 7, "L1": 8, "L2": 5, "L3": 8, "L4": 5},
    ...                "limits": {"theta1": [0, 3.14159], "theta2": "unlimited"}})
    >>> m.name, m.joint_names
    ('five-bar', ('theta1', 'theta2'))
    """
    checked = load_spec(spec)
    name = checked["mechanism"]
    cls = mechanism_class(name)
    schema = MECHANISMS[name].schema
    if schema is None:
        own_format: Any = cls
        built: Mechanism = own_format.from_spec(checked)
        return built
    prismatic = schema.joint_kind != "angle"
    limits = tuple(
        JointLimit.unlimited()
        if isinstance(value, str)
        else JointLimit(value[0], value[1], prismatic=prismatic)
        for value in (checked["limits"][joint] for joint in schema.joints)
    )
    parameters = [checked["parameters"][key] for key in schema.parameters]
    built = cls(*parameters, limits)  # type: ignore[call-arg]
    extra = Constraints.from_spec(checked)
    return built if extra.empty else built.constrained(extra)
