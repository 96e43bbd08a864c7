"""moveability: regions of feasible point-to-point motions of fully-parallel manipulators.

The spaces of the analysis (the Cartesian workspace, the joint space and their
product) are represented by :class:`HyperTree`, a k-dimensional generalized
octree whose leaves are IN, OUT or BOUNDARY.

The public names below are imported when first used, so that ``import
moveability`` (and a command that needs little, such as ``moveability
--version``) does not load numba, scipy and the analysis.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from ._version import __version__
from .errors import (
    IncompatibleTreesError,
    InputError,
    InvalidParameterError,
    MissingExtraError,
    MoveabilityError,
    PlanningError,
    ResolutionError,
    SpecError,
)

if TYPE_CHECKING:
    from .analysis.planning import default_poses, plan_motion
    from .analysis.result import Analysis, Region, analyze
    from .analysis.saved import load_analysis, save_analysis
    from .hypertree.measurement import leaf_volumes, locate, measure
    from .hypertree.projection import project
    from .hypertree.setops import complement, difference, equals, intersection, union
    from .hypertree.status import BOUNDARY, IN, OUT, Status
    from .hypertree.topology import adjacency, components
    from .hypertree.tree import HyperTree, Leaves, load
    from .mechanisms.registry import from_spec, load_spec


#: where each lazily imported public name lives
_LAZY: dict[str, str] = {
    **dict.fromkeys(("default_poses", "plan_motion"), "analysis.planning"),
    **dict.fromkeys(("Analysis", "Region", "analyze"), "analysis.result"),
    **dict.fromkeys(("load_analysis", "save_analysis"), "analysis.saved"),
    **dict.fromkeys(("leaf_volumes", "locate", "measure"), "hypertree.measurement"),
    "project": "hypertree.projection",
    **dict.fromkeys(
        ("complement", "difference", "equals", "intersection", "union"), "hypertree.setops"
    ),
    **dict.fromkeys(("BOUNDARY", "IN", "OUT", "Status"), "hypertree.status"),
    **dict.fromkeys(("adjacency", "components"), "hypertree.topology"),
    **dict.fromkeys(("HyperTree", "Leaves", "load"), "hypertree.tree"),
    **dict.fromkeys(("from_spec", "load_spec"), "mechanisms.registry"),
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "BOUNDARY",
    "IN",
    "OUT",
    "Analysis",
    "HyperTree",
    "IncompatibleTreesError",
    "InputError",
    "InvalidParameterError",
    "Leaves",
    "MissingExtraError",
    "MoveabilityError",
    "PlanningError",
    "Region",
    "ResolutionError",
    "SpecError",
    "Status",
    "__version__",
    "adjacency",
    "analyze",
    "complement",
    "components",
    "default_poses",
    "difference",
    "equals",
    "from_spec",
    "intersection",
    "leaf_volumes",
    "load",
    "load_analysis",
    "load_spec",
    "locate",
    "measure",
    "plan_motion",
    "project",
    "save_analysis",
    "union",
]
