"""The 2^k-tree engine: generalized octrees over boxes of any dimension.

It knows nothing of robots. A :class:`HyperTree` holds the leaves of an
adaptive subdivision as numpy arrays (key, level, status IN / OUT / BOUNDARY);
:mod:`.subdivision` builds and refines it, :mod:`.setops` combines trees,
:mod:`.topology` finds touching leaves and connected components (across
periodic axes too), :mod:`.projection` projects onto fewer axes and
:mod:`.measurement` measures and locates points. :mod:`.keys` lays out the
Morton-style keys the leaves are sorted by.
"""

from .measurement import leaf_volumes, locate, measure
from .projection import project
from .setops import complement, difference, equals, intersection, union
from .status import BOUNDARY, IN, OUT, Status
from .topology import adjacency, components
from .tree import HyperTree, Leaves, load

__all__ = [
    "BOUNDARY",
    "IN",
    "OUT",
    "HyperTree",
    "Leaves",
    "Status",
    "adjacency",
    "complement",
    "components",
    "difference",
    "equals",
    "intersection",
    "leaf_volumes",
    "load",
    "locate",
    "measure",
    "project",
    "union",
]
