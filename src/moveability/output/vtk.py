"""The regions as VTK unstructured grids (``.vtu``), for ParaView.

:func:`export_vtk` writes one file per region and one for the undecided
leaves, in the XML format with ASCII data, by hand (no VTK library needed).
Each leaf is one cell: a hexahedron (VTK type 12) with three pose axes, a
quad (type 9, in the plane z = 0) with two; these general types (rather than
voxel and pixel) are read by every VTK reader, ParaView's and meshio's alike.
The points are the pose coordinates; a periodic angle is in radians on its axis.

Cell data:

``certified``
    1 where the leaf is certainly in the region, 0 where the region may only
    extend there (always 0 in ``undecided.vtu``).
``leaf_level``
    Subdivision level of the leaf in the tree (0 is the whole box).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ..hypertree.status import BOUNDARY
from ..hypertree.tree import HyperTree, to_coordinates

if TYPE_CHECKING:
    from ..analysis.result import Analysis

__all__ = ["VTK_HEXAHEDRON", "VTK_QUAD", "export_vtk", "exported_files", "write_vtu"]

#: VTK cell types of a leaf with two and three axes
VTK_QUAD = 9
VTK_HEXAHEDRON = 12
#: corners of a cell in VTK's order, as bit patterns (bit a set: upper end of axis a)
_ORDER = {2: [0, 1, 3, 2], 3: [0, 1, 3, 2, 4, 5, 7, 6]}


def _corners(
    tree: HyperTree, cells: NDArray[np.intp]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Distinct corner points (m, 3) and each cell's corners as indices (n, 2^k).

    The corners go round the lower face, then the upper one: VTK's quad and
    hexahedron order.
    """
    k = tree.ndim
    anchors = tree.anchors[cells]
    sizes = tree.layout.cell_sizes(tree.levels[cells])
    bits = (np.asarray(_ORDER[k])[:, None] >> np.arange(k)[None, :]) & 1  # (2^k, k)
    ints = anchors[:, None, :] + bits[None, :, :] * sizes[:, None, :]  # (n, 2^k, k)
    unique, inverse = np.unique(ints.reshape(-1, k), axis=0, return_inverse=True)
    points = np.zeros((unique.shape[0], 3))
    points[:, :k] = to_coordinates(tree.lo, tree.hi, tree.layout, unique)
    return points, inverse.reshape(cells.size, 1 << k).astype(np.int64)


def _array(name: str, kind: str, values: NDArray[np.generic], fmt: str, extra: str = "") -> str:
    text = " ".join(fmt % v for v in np.ravel(values))
    return (
        f'        <DataArray type="{kind}" Name="{name}"{extra} format="ascii">\n'
        f"          {text}\n        </DataArray>\n"
    )


def write_vtu(
    path: str | os.PathLike[str],
    tree: HyperTree,
    cells: NDArray[np.intp],
    certified: NDArray[np.bool_],
    comment: str = "",
) -> Path:
    """Write leaves of a tree of 2 or 3 axes as a VTK unstructured grid.

    Parameters
    ----------
    path : path
        The ``.vtu`` file, replaced if it exists.
    tree : HyperTree
    cells : ndarray of int
        Indices of the leaves to write.
    certified : ndarray of bool
        One flag per written leaf, stored as the cell data ``certified``.
    comment : str
        A line kept in an XML comment at the top of the file.

    Returns
    -------
    Path

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from moveability import HyperTree
    >>> tree = HyperTree.from_array(np.ones((2, 2), dtype=bool), merge=False)
    >>> with tempfile.TemporaryDirectory() as d:
    ...     path = write_vtu(os.path.join(d, "a.vtu"), tree, np.arange(4), np.ones(4, bool))
    ...     text = path.read_text()
    >>> 'NumberOfPoints="9" NumberOfCells="4"' in text
    True
    """
    k = tree.ndim
    if k not in (2, 3):
        raise InvalidParameterError("tree", "a tree of 2 or 3 axes", k)
    cells = np.asarray(cells, dtype=np.intp).ravel()
    flags = np.asarray(certified, dtype=bool).ravel()
    if flags.size != cells.size:
        raise InvalidParameterError("certified", f"{cells.size} flags (one per cell)", flags.size)
    points, corners = _corners(tree, cells)
    n = cells.size
    cell_type = VTK_HEXAHEDRON if k == 3 else VTK_QUAD
    note = comment.replace("--", "-")
    text = (
        '<?xml version="1.0"?>\n'
        + (f"<!-- {note} -->\n" if note else "")
        + '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
        'header_type="UInt64">\n'
        "  <UnstructuredGrid>\n"
        f'    <Piece NumberOfPoints="{points.shape[0]}" NumberOfCells="{n}">\n'
        "      <Points>\n"
        + _array("points", "Float64", points, "%.17g", ' NumberOfComponents="3"')
        + "      </Points>\n"
        "      <Cells>\n"
        + _array("connectivity", "Int64", corners, "%d")
        + _array("offsets", "Int64", np.arange(1, n + 1) * (1 << k), "%d")
        + _array("types", "UInt8", np.full(n, cell_type), "%d")
        + "      </Cells>\n"
        '      <CellData Scalars="certified">\n'
        + _array("certified", "UInt8", flags.astype(np.uint8), "%d")
        + _array("leaf_level", "UInt8", tree.levels[cells], "%d")
        + "      </CellData>\n"
        "    </Piece>\n"
        "  </UnstructuredGrid>\n"
        "</VTKFile>\n"
    )
    out = Path(path)
    out.write_text(text, encoding="utf-8")
    return out


def export_vtk(result: Analysis, directory: str | os.PathLike[str]) -> list[Path]:
    """Write each region, and the undecided leaves, as ``.vtu`` files for ParaView.

    ``region-<id>.vtu`` holds the leaves certainly in the region
    (``certified`` = 1; their volumes sum to the region's inner bound) and those
    where it may extend (0; all together they sum to the outer bound);
    ``undecided.vtu`` holds every leaf left undecided at the precision.

    Parameters
    ----------
    result : Analysis
        An analysis with 2 or 3 pose axes.
    directory : path
        Created if missing; files of the same names are replaced.

    Returns
    -------
    list of Path
        The files written, regions first.

    Examples
    --------
    >>> import tempfile
    >>> from moveability import analyze
    >>> from moveability.mechanisms import FiveBar
    >>> result = analyze(FiveBar(7, 8, 5, 8, 5), precision=0.5)
    >>> with tempfile.TemporaryDirectory() as d:
    ...     [p.name for p in export_vtk(result, d)]
    ['region-0.vtu', 'region-1.vtu', 'undecided.vtu']
    """

    tree = result.tree
    if tree.ndim not in (2, 3):
        raise InvalidParameterError("result", "an analysis of 2 or 3 pose axes", tree.ndim)
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    measure = result.measure_name
    paths = []
    for j, region in enumerate(result.regions):
        certain, possible = result.region_cells(j)
        cells = np.flatnonzero(certain | possible)
        comment = (
            f"moveability: {result.mechanism.name}, precision {result.precision_text}, "
            f"region {region.id}, det A {'>' if region.sign > 0 else '<'} 0, {measure} in "
            f"[{region.area[0]:.17g}, {region.area[1]:.17g}]; axes "
            + ", ".join(result.mechanism.pose_names)
        )
        paths.append(
            write_vtu(out / f"region-{region.id}.vtu", tree, cells, certain[cells], comment)
        )
    cells = np.flatnonzero(tree.status == BOUNDARY)
    comment = (
        f"moveability: {result.mechanism.name}, precision {result.precision_text}, "
        "leaves undecided at this precision; axes " + ", ".join(result.mechanism.pose_names)
    )
    paths.append(
        write_vtu(out / "undecided.vtu", tree, cells, np.zeros(cells.size, dtype=bool), comment)
    )
    return paths


def exported_files(result: Analysis, paths: list[Path]) -> list[dict[str, Any]]:
    """What :func:`export_vtk` wrote, one JSON-ready entry per file.

    Each entry gives the ``path``, the ``region`` id (``None`` for the file of
    undecided leaves), its number of ``cells``, of ``certified_cells``, and the
    bounds of the region's measure (``area`` or ``volume``).
    """
    measure = result.measure_name
    files: list[dict[str, Any]] = []
    for j, region in enumerate(result.regions):
        certain, possible = result.region_cells(j)
        files.append(
            {
                "path": str(paths[j]),
                "region": region.id,
                "cells": int((certain | possible).sum()),
                "certified_cells": int(certain.sum()),
                measure: list(region.area),
            }
        )
    files.append(
        {
            "path": str(paths[-1]),
            "region": None,
            "cells": int((result.tree.status == BOUNDARY).sum()),
            "certified_cells": 0,
            measure: [0.0, result.undecided[f"boundary_{measure}"]],
        }
    )
    return files
