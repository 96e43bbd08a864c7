"""VTK export, read back by a small reader of the XML unstructured-grid format."""

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from click.testing import CliRunner

from moveability import analyze, load_spec
from moveability.cli import main
from moveability.hypertree.measurement import locate
from moveability.output.vtk import VTK_HEXAHEDRON, VTK_QUAD, export_vtk

SPEC = "examples/three-rpr.toml"
PRECISION = (2.0, 2.0, 0.4)


def read_vtu(path):
    """Points, cells (corner indices), cell types and cell data of a .vtu file."""
    root = ET.parse(path).getroot()
    assert root.get("type") == "UnstructuredGrid"
    piece = root.find("UnstructuredGrid/Piece")
    n_points, n_cells = int(piece.get("NumberOfPoints")), int(piece.get("NumberOfCells"))

    def values(node):
        kind = np.float64 if node.get("type").startswith("Float") else np.int64
        return np.array(node.text.split(), dtype=kind)

    points = values(piece.find("Points/DataArray")).reshape(-1, 3)
    arrays = {a.get("Name"): values(a) for a in piece.find("Cells")}
    offsets = arrays["offsets"]
    starts = np.r_[0, offsets[:-1]]
    cells = [arrays["connectivity"][a:b] for a, b in zip(starts, offsets, strict=True)]
    data = {a.get("Name"): values(a) for a in piece.find("CellData")}
    assert points.shape == (n_points, 3) and len(cells) == n_cells == arrays["types"].size
    assert all(v.size == n_cells for v in data.values())
    return points, cells, arrays["types"], data


@pytest.fixture(scope="module")
def result():
    return analyze(load_spec(SPEC), precision=PRECISION)


def _check_region_files(result, paths, cell_type, corners):
    tree = result.tree
    leaves = tree.leaves()
    k = tree.ndim
    for j, region in enumerate(result.regions):
        assert paths[j].name == f"region-{region.id}.vtu"
        points, cells, types, data = read_vtu(paths[j])
        certain, possible = result.region_cells(j)
        assert len(cells) == int((certain | possible).sum())
        assert (types == cell_type).all() and all(c.size == corners for c in cells)
        boxes = np.array([points[c] for c in cells])  # (n, corners, 3)
        lo, hi = boxes.min(axis=1)[:, :k], boxes.max(axis=1)[:, :k]
        if k == 2:
            assert (boxes[:, :, 2] == 0).all()
        # corner order: round the lower face, then the upper one (positive orientation)
        first, second, fourth = boxes[:, 0], boxes[:, 1], boxes[:, 3]
        assert np.allclose(first[:, :k], lo) and np.allclose(second[:, 0], hi[:, 0])
        assert np.allclose(fourth[:, 1], hi[:, 1]) and np.allclose(fourth[:, 0], lo[:, 0])
        # each cell is a leaf of the region, with its level and certificate
        _, leaf = locate(tree, 0.5 * (lo + hi))
        assert np.allclose(lo, leaves.lo[leaf]) and np.allclose(hi, leaves.hi[leaf])
        assert np.array_equal(data["leaf_level"], leaves.level[leaf])
        assert np.array_equal(data["certified"], certain[leaf].astype(int))
        measure = (hi - lo).prod(axis=1)
        certified = data["certified"] == 1
        assert measure[certified].sum() == pytest.approx(region.area[0], rel=1e-9)
        assert measure.sum() == pytest.approx(region.area[1], rel=1e-9)


def test_regions_round_trip_3d(result, tmp_path):
    paths = export_vtk(result, tmp_path / "vtk")
    assert [p.name for p in paths[-1:]] == ["undecided.vtu"]
    assert len(paths) == len(result.regions) + 1
    _check_region_files(result, paths, VTK_HEXAHEDRON, 8)
    points, cells, _, data = read_vtu(paths[-1])
    boxes = np.array([points[c] for c in cells])
    volume = (boxes.max(axis=1) - boxes.min(axis=1)).prod(axis=1)
    assert len(cells) == result.tree.counts()["BOUNDARY"]
    assert volume.sum() == pytest.approx(result.undecided["boundary_volume"], rel=1e-9)
    assert (data["certified"] == 0).all()
    # corners shared between cells are written once
    assert len(points) < 8 * len(cells) and len(np.unique(points, axis=0)) == len(points)


def test_regions_round_trip_2d(tmp_path):
    five_bar = analyze(load_spec("examples/five-bar-paper.toml"), precision=0.4)
    paths = export_vtk(five_bar, tmp_path)
    _check_region_files(five_bar, paths, VTK_QUAD, 4)


def test_cli_export(tmp_path):
    runner = CliRunner()
    out = tmp_path / "out"
    args = ["export", SPEC, "--out", str(out), "--precision", "2,2,0.4"]
    done = runner.invoke(main, args)
    assert done.exit_code == 0, done.output
    listed = done.output.split()
    names = ["region-0.vtu", "region-1.vtu", "undecided.vtu"]
    assert [p.rsplit("/", 1)[1] for p in listed] == names
    again = runner.invoke(main, args)
    assert again.exit_code == 2 and "--overwrite" in again.output
    done = runner.invoke(main, [*args, "--overwrite", "--json", "-"])
    assert done.exit_code == 0, done.output
    data = json.loads(done.output)
    assert [f["path"] for f in data["files"]] == listed
    for entry in data["files"]:
        _, cells, _, flags = read_vtu(entry["path"])
        assert entry["cells"] == len(cells)
        assert entry["certified_cells"] == int(flags["certified"].sum())
    assert data["files"][0]["region"] == 0 and len(data["files"][0]["volume"]) == 2
