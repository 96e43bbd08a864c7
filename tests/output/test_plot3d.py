"""Figures of 3-dof mechanisms, checked by the data they draw."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
from click.testing import CliRunner

from moveability import HyperTree, analyze, load_spec
from moveability.cli import main
from moveability.errors import InvalidParameterError
from moveability.hypertree.measurement import locate
from moveability.hypertree.status import BOUNDARY
from moveability.hypertree.topology import boundary_faces
from moveability.output.plot import figure
from moveability.output.plot3d import plot_regions_3d, plot_slices

SPEC = "examples/three-rpr.toml"
PRECISION = (2.0, 2.0, 0.4)


@pytest.fixture(scope="module")
def result():
    # the plain pass: the faces are checked on a raster of the finest grid of the tree
    return analyze(load_spec(SPEC), precision=PRECISION, resolve=False)


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _boxes(coll):
    """Lower and upper corners of the rectangles of a PolyCollection."""
    verts = [p.vertices for p in coll.get_paths()]
    if not verts:
        return np.zeros((0, 2)), np.zeros((0, 2))
    return np.array([v.min(axis=0) for v in verts]), np.array([v.max(axis=0) for v in verts])


def _certain_phis(result):
    """One angle through a certified leaf of each region, and one through none."""
    leaves = result.tree.leaves()
    phis = []
    for j in range(len(result.regions)):
        i = int(np.flatnonzero(result.region_cells(j)[0])[0])
        phis.append(0.5 * (leaves.lo[i, 2] + leaves.hi[i, 2]))
    return np.array([*phis, -3.0])


def test_slices_draw_the_leaves_of_the_cut_with_their_certificates(result):
    phis = _certain_phis(result)
    fig = plot_slices(result, phis=phis)
    leaves = result.tree.leaves()
    masks = [result.region_cells(j) for j in range(len(result.regions))]
    ids = [r.id for r in result.regions]
    drawn_certain = 0
    shown = [ax for ax in fig.axes if ax.axison]
    for ax, phi in zip(shown, phis, strict=True):
        assert ax.get_xlabel() == "x (length units)" and ax.get_ylabel() == "y (length units)"
        assert ax.get_aspect() == 1.0
        assert ax.get_title() == f"phi = {np.degrees(phi):.4g}\N{DEGREE SIGN}"
        cut = (leaves.lo[:, 2] <= phi) & (phi < leaves.hi[:, 2])
        for coll in ax.collections:
            gid = coll.get_gid()
            if gid is None:  # the outline of W
                continue
            lo, hi = _boxes(coll)
            centres = np.c_[0.5 * (lo + hi), np.full(lo.shape[0], phi)]
            _, leaf = locate(result.tree, centres)
            # each rectangle is exactly the (x, y) box of the leaf holding its centre
            assert (leaf >= 0).all()
            assert np.allclose(lo, leaves.lo[leaf, :2]) and np.allclose(hi, leaves.hi[leaf, :2])
            if gid == "undecided":
                assert (leaves.status[leaf] == BOUNDARY).all()
                continue
            _, rid, kind = gid.split()
            j = ids.index(int(rid))
            certain, possible = masks[j]
            answers = [p["regions"][rid] for p in result.locate(centres)["points"]]
            if kind == "certain":
                assert certain[leaf].all() and all(a is True for a in answers)
                # every certified leaf of the region in the cut is drawn, once
                assert np.array_equal(np.sort(leaf), np.flatnonzero(cut & certain))
                drawn_certain += leaf.size
            else:
                # undecided leaves: the pose at the centre may still be certified out of W
                assert possible[leaf].all()
                assert np.array_equal(np.sort(leaf), np.flatnonzero(cut & possible))
    assert drawn_certain >= len(result.regions)
    legend = " ".join(t.get_text() for t in fig.legends[0].get_texts())
    for region in result.regions:
        assert f"region {region.id}: det A {'>' if region.sign > 0 else '<'} 0" in legend
        assert f"volume in [{region.area[0]:.3g}, {region.area[1]:.3g}]" in legend


def test_slices_wrap_the_angle(result):
    a = plot_slices(result, phis=[0.3 + 2 * np.pi])
    b = plot_slices(result, phis=[0.3])
    assert a.axes[0].get_title() == b.axes[0].get_title()
    for ca, cb in zip(a.axes[0].collections, b.axes[0].collections, strict=True):
        if ca.get_gid() is not None:
            assert np.allclose(_boxes(ca)[0], _boxes(cb)[0])


def _inside(result, mask, points):
    tree = result.tree
    p = points.copy()
    period = tree.hi[2] - tree.lo[2]
    p[:, 2] = tree.lo[2] + np.mod(p[:, 2] - tree.lo[2], period)
    _, leaf = locate(tree, p)
    return (leaf >= 0) & mask[np.maximum(leaf, 0)]


def test_3d_faces_lie_on_the_boundary_of_each_region(result):
    fig = plot_regions_3d(result)
    ax = fig.axes[0]
    assert [ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()] == [
        "x (length units)",
        "y (length units)",
        "phi (rad)",
    ]
    assert "faces shown" not in ax.get_title()
    drawn = [c for c in ax.collections if (c.get_gid() or "").startswith("region")]
    assert len(drawn) == len(result.regions)
    widths = result.tree.hi - result.tree.lo
    for j, coll in enumerate(drawn):
        certain = result.region_cells(j)[0]
        lo, hi, axis, side = boundary_faces(result.tree, certain)
        faces = getattr(coll, "_faces", None)
        if faces is not None:  # the polygons drawn are the faces found
            assert len(faces) == axis.size
            assert np.allclose(np.asarray(faces).min(axis=1), lo)
            assert np.allclose(np.asarray(faces).max(axis=1), hi)
        centre = 0.5 * (lo + hi)
        step = np.zeros_like(centre)
        step[np.arange(axis.size), axis] = 1e-7 * widths[axis]
        outward = step * side[:, None]
        # the region is on the inner side of each face, not on the outer one
        assert _inside(result, certain, centre - outward).all()
        assert not _inside(result, certain, centre + outward).any()


def _surface_by_raster(tree, mask):
    """Area of the boundary of the union of chosen leaves, on the finest grid."""
    res = [1 << d for d in tree.max_depth]
    grid = np.zeros(res, dtype=bool)
    anchors, sizes = tree.anchors, tree.layout.cell_sizes(tree.levels)
    for i in np.flatnonzero(mask):
        a, s = anchors[i], sizes[i]
        grid[a[0] : a[0] + s[0], a[1] : a[1] + s[1], a[2] : a[2] + s[2]] = True
    cell = (tree.hi - tree.lo) / res
    total = 0.0
    for axis in range(3):
        face = np.prod(np.delete(cell, axis))
        if axis in tree.periodic:
            changes = grid != np.roll(grid, 1, axis=axis)
        else:
            pad = [(0, 0)] * 3
            pad[axis] = (1, 1)
            g = np.pad(grid, pad)
            changes = np.diff(g, axis=axis)
        total += face * np.count_nonzero(changes)
    return total


def test_3d_faces_cover_the_surface(result):
    """Differential: the faces' area equals the surface counted on the finest grid."""
    for j in range(len(result.regions)):
        certain = result.region_cells(j)[0]
        lo, hi, axis, _ = boundary_faces(result.tree, certain)
        spans = hi - lo
        spans[np.arange(axis.size), axis] = 1.0
        area = spans.prod(axis=1).sum()
        assert area == pytest.approx(_surface_by_raster(result.tree, certain), rel=1e-9)


def test_boundary_faces_across_a_periodic_axis():
    grid = np.zeros((2, 2, 4), dtype=bool)
    grid[0, 0, [0, 3]] = True  # two cells glued across the ends of the periodic axis
    tree = HyperTree.from_array(grid, merge=False, periodic=[2])
    _, _, axis, side = boundary_faces(tree, tree.status == 1)
    assert axis.size == 2 * 4 + 2  # a 1 x 1 x 2 bar: the glued faces are inside
    assert sorted(side[axis == 2].tolist()) == [-1, 1]


def test_3d_face_count_is_bounded(result):
    fig = plot_regions_3d(result, max_faces=20)
    ax = fig.axes[0]
    assert "largest" in ax.get_title() and "faces shown" in ax.get_title()
    faces = [c for c in ax.collections if (c.get_gid() or "").startswith("region")]
    counts = [len(getattr(c, "_faces", c.get_paths())) for c in faces]
    assert 0 < sum(counts) <= 20


def test_figures_refuse_the_other_number_of_axes(result):
    with pytest.raises(InvalidParameterError, match="figure"):
        figure("regions", result)
    five_bar = analyze(load_spec("examples/five-bar-paper.toml"), precision=0.5)
    with pytest.raises(InvalidParameterError, match="figure"):
        figure("slices", five_bar)
    with pytest.raises(InvalidParameterError, match="figure"):
        plot_regions_3d(five_bar)
    with pytest.raises(InvalidParameterError, match="phis"):
        plot_slices(result, phis=[np.nan])


def test_cli_plot_3d_figures(tmp_path):
    runner = CliRunner()
    eps = ",".join(str(v) for v in PRECISION)
    out = tmp_path / "slices.png"
    args = ["plot", SPEC, "--figure", "slices", "--out", str(out), "--precision", eps]
    done = runner.invoke(main, [*args, "--phi", "10", "--phi", "-170"])
    assert done.exit_code == 0, done.output
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    out = tmp_path / "view.svg"
    done = runner.invoke(
        main, ["plot", SPEC, "--figure", "regions-3d", "--out", str(out), "--precision", eps]
    )
    assert done.exit_code == 0, done.output
    assert b"<svg" in out.read_bytes()[:1000]
    for spec, name in ((SPEC, "regions"), ("examples/five-bar-paper.toml", "slices")):
        bad = runner.invoke(
            main, ["plot", spec, "--figure", name, "--out", str(tmp_path / "x.png"), "-p", "1"]
        )
        assert bad.exit_code == 2
        lines = bad.output.strip().splitlines()
        assert len(lines) == 1 and "--figure" in lines[0] and name in lines[0]
    bad = runner.invoke(
        main, ["plot", SPEC, "--figure", "regions-3d", "--phi", "3", "--out", str(out)]
    )
    assert bad.exit_code == 2 and "--phi" in bad.output


def test_report_uses_the_3d_figures(result, tmp_path):
    from moveability.output.report import write_report

    with open(write_report(result, tmp_path), encoding="utf-8") as handle:
        page = handle.read()
    assert '<figure id="slices">' in page and '<figure id="regions-3d">' in page
    assert '<figure id="regions">' not in page and '<figure id="workspace">' not in page
    assert page.count('src="data:image/png;base64,') == 2
    assert "volume of W_Nj" in page


def test_3d_titles_have_three_digits_and_legends_are_opaque():
    import re

    odd = analyze(load_spec(SPEC), precision=(2.0 / 3, 2.0 / 3, np.pi / 9), resolve=False)
    for fig in (plot_slices(odd), plot_regions_3d(odd)):
        texts = [fig.get_suptitle()] + [ax.get_title() for ax in fig.axes]
        for text in texts:
            for number in re.findall(r"\d+\.\d+", text):
                assert len(number.replace(".", "").lstrip("0")) <= 3, (number, text)
        legends = fig.legends + [ax.get_legend() for ax in fig.axes if ax.get_legend()]
        assert legends and all(leg.get_frame().get_alpha() == 1.0 for leg in legends)
    assert "0.667, 0.667, 0.349" in plot_slices(odd).get_suptitle()


def test_delta_slices_cut_heights(tmp_path):
    """A translational mechanism (x, y, z): slices across z, by default four through
    the leaves that may hold W, titled with the height; the CLI takes --z, not --phi."""
    import re

    delta = analyze("examples/delta.toml", precision=0.1, resolve=False)
    fig = plot_slices(delta)
    titles = [ax.get_title() for ax in fig.axes[:4]]
    assert all(t.startswith("z = ") for t in titles)
    heights = [float(t[4:]) for t in titles]
    assert heights == sorted(heights)
    lo, hi = delta.tree.lo[2], delta.tree.hi[2]
    assert lo < heights[0] and heights[-1] < hi
    # every default slice cuts W's leaves (the Delta's W has a gap about z = 0)
    for ax in fig.axes[:4]:
        assert any(len(c.get_paths()) for c in ax.collections if c.get_gid())
    plt.close(fig)
    fig = plot_slices(delta, phis=[-0.8, -0.612345])
    assert [ax.get_title() for ax in fig.axes[:2]] == ["z = -0.8", "z = -0.612"]
    plt.close(fig)
    # the default heights, too, with three significant digits at most
    for number in re.findall(r"\d+\.\d+", " ".join(titles)):
        assert len(number.replace(".", "").lstrip("0")) <= 3, titles
    fig = plot_regions_3d(delta)
    assert fig.axes[0].get_zlabel() == "z (length units)"
    plt.close(fig)
    runner = CliRunner()
    out = tmp_path / "slices.png"
    args = ["plot", "examples/delta.toml", "--figure", "slices", "--out", str(out), "-p", "0.1"]
    done = runner.invoke(main, [*args, "--no-resolve", "--z", "-0.8", "--z", "0.5"])
    assert done.exit_code == 0, done.output
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bad = runner.invoke(main, [*args, "--overwrite", "--phi", "10"])
    assert bad.exit_code == 2 and "--z" in bad.output
    bad = runner.invoke(
        main, ["plot", SPEC, "--figure", "slices", "--z", "1", "--out", str(tmp_path / "x.png")]
    )
    assert bad.exit_code == 2 and "--phi" in bad.output
