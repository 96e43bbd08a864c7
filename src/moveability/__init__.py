"""moveability: regions of feasible point-to-point motions of fully-parallel manipulators.

The spaces of the analysis (the Cartesian workspace, the joint space and their
product) are represented by :class:`HyperTree`, a k-dimensional generalized
octree whose leaves are IN, OUT or BOUNDARY.
"""

from importlib.metadata import PackageNotFoundError, version

from .analysis.planning import default_poses, plan_motion
from .analysis.result import Analysis, Region, analyze, load_analysis
from .errors import (
    IncompatibleTreesError,
    InvalidParameterError,
    MoveabilityError,
    PlanningError,
    ResolutionError,
    SpecError,
)
from .hypertree.measurement import leaf_volumes, locate, measure
from .hypertree.projection import project
from .hypertree.setops import complement, difference, equals, intersection, union
from .hypertree.status import BOUNDARY, IN, OUT, Status
from .hypertree.topology import adjacency, components
from .hypertree.tree import HyperTree, Leaves, load
from .mechanisms.registry import load_spec

try:
    __version__ = version("moveability")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0.0.0"

__all__ = [
    "BOUNDARY",
    "IN",
    "OUT",
    "Analysis",
    "HyperTree",
    "IncompatibleTreesError",
    "InvalidParameterError",
    "Leaves",
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
    "intersection",
    "leaf_volumes",
    "load",
    "load_analysis",
    "load_spec",
    "locate",
    "measure",
    "plan_motion",
    "project",
    "union",
]
