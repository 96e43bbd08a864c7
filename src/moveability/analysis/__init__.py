"""The analysis: from a mechanism to its regions R_j, their projections W_Nj and
the answers about poses.

:mod:`.sheets` certifies the posture sheets over the cells of the workspace,
:mod:`.regions` joins them into certain and possible components, :mod:`.flows`
proves that no region hides in the undecided cells, :mod:`.joint_space` counts
the regions of two-dyad mechanisms and the Delta in their joint space, :mod:`.result` holds
:func:`analyze` and :class:`Analysis` (regions, counts, point queries),
:mod:`.saved` writes and reads analyses,
:mod:`.planning` plans motions inside a region and :mod:`.wxq` builds the
paper's W x Q tree directly.
"""

from .result import (
    RESOLVE_GROWTH,
    RESOLVE_LEVELS,
    RESOLVE_ROUND,
    Analysis,
    Region,
    analyze,
    count_text,
    resolve_analysis,
)
from .saved import load_analysis, save_analysis

__all__ = [
    "RESOLVE_GROWTH",
    "RESOLVE_LEVELS",
    "RESOLVE_ROUND",
    "Analysis",
    "Region",
    "analyze",
    "count_text",
    "load_analysis",
    "resolve_analysis",
    "save_analysis",
]
