"""Figures, checked by the data they draw."""

import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
from click.testing import CliRunner
from matplotlib.colors import to_rgb
from scipy import ndimage

from moveability import analyze, default_poses, load_spec, plan_motion
from moveability.cli import main
from moveability.hypertree.measurement import locate
from moveability.hypertree.status import IN, OUT
from moveability.output import plot as plot_module
from moveability.output.axes import EXCLUDED, PALETTE, UNDECIDED
from moveability.output.plot import (
    MAX_POSTURE_CHANGES,
    WORKSPACE_PAD,
    animate_path,
    figure,
    joint_space_raster,
    plot_joint_space,
    plot_path,
    plot_postures,
    plot_regions,
    plot_workspace,
)

SPEC = "examples/five-bar-paper.toml"
FULL_TURN = "examples/five-bar-full-turn.toml"
BIGLIDE = "examples/biglide.toml"
#: poses of the paper's five-bar joined only through two posture changes
THROUGH_CHANGES = [[-4.0, -1.0], [1.0, 3.0], [10.0, 2.0]]


@pytest.fixture(scope="module")
def result():
    return analyze(load_spec(SPEC), precision=0.1)


@pytest.fixture(scope="module")
def biglide():
    return analyze(load_spec(BIGLIDE), precision=0.1)


@pytest.fixture(scope="module")
def motion(result):
    return plan_motion(result, THROUGH_CHANGES)


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _labelled(ax):
    assert ax.get_xlabel() and ax.get_ylabel()
    assert ax.get_aspect() == 1.0


def _outer_labelled(fig):
    """Pose axes labelled on the left column and under the lowest panel of each column."""
    shown = _shown(fig)
    lowest = {}
    for ax in shown:
        assert ax.get_aspect() == 1.0
        spec = ax.get_subplotspec()
        if spec.is_first_col():
            assert ax.get_ylabel()
        col = spec.colspan.start
        if col not in lowest or spec.rowspan.start > lowest[col].get_subplotspec().rowspan.start:
            lowest[col] = ax
    assert all(ax.get_xlabel() for ax in lowest.values())


def _shown(fig):
    return [ax for ax in fig.axes if ax.axison]


def _legends(fig):
    return [*fig.legends, *(ax.get_legend() for ax in fig.axes if ax.get_legend())]


def _link_points(ax):
    """Every vertex of the polylines of legs drawn (2 or 3 points: base, ..., tip)."""
    lines = [ln for ln in ax.get_lines() if len(ln.get_xdata()) in (2, 3)]
    return np.concatenate([np.c_[ln.get_xdata(), ln.get_ydata()] for ln in lines])


def _within_limits(ax, points):
    x0, x1 = sorted(ax.get_xlim())
    y0, y1 = sorted(ax.get_ylim())
    x, y = points[:, 0], points[:, 1]
    return bool(((x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)).all())


def _step(ax):
    return int(re.search(r"step (\d+)", ax.get_title()).group(1))


# -------------------------------------------------------------- workspace
def test_workspace_loci_are_singular(result):
    fig = plot_workspace(result)
    ax = fig.axes[0]
    _labelled(ax)
    m = result.mechanism
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    for p in range(4):
        assert f"det A = 0, posture {m.posture_name(p)}" in labels
    # vertices of the parallel-singularity contours: det A vanishes there for some posture
    contours = [
        c
        for c in ax.collections
        if hasattr(c, "get_paths") and type(c).__name__ in ("QuadContourSet", "ContourSet")
    ]
    vertices = np.concatenate(
        [p.vertices for c in contours[:4] for p in c.get_paths() if len(p.vertices)]
    )
    q = m.joint_angles(vertices)
    det = np.stack([m.det_a(vertices, q[:, k]) for k in range(4)], axis=1)
    scale = np.nanmax(np.abs(det))
    assert (np.nanmin(np.abs(det), axis=1) < 0.05 * scale).mean() > 0.95


@pytest.mark.parametrize("name", ["workspace", "joint-space"])
def test_single_panel_legends_stand_beside_the_data(result, biglide, name):
    for analysis in (result, biglide):
        fig = figure(name, analysis)
        fig.canvas.draw()
        ax = fig.axes[0]
        legend = ax.get_legend()
        assert legend.get_frame().get_alpha() == 1.0
        box, frame = legend.get_window_extent(), ax.get_window_extent()
        overlap_x = min(box.x1, frame.x1) - max(box.x0, frame.x0)
        overlap_y = min(box.y1, frame.y1) - max(box.y0, frame.y0)
        assert overlap_x <= 0 or overlap_y <= 0, (name, analysis.mechanism.name)


# --------------------------------------------------------------- postures
def test_postures_draw_the_links(result):
    m = result.mechanism
    pose = np.array([3.5, 6.0])
    fig = plot_postures(m, pose)
    _outer_labelled(fig)
    q = m.joint_angles(pose[None, :])[0]
    for k, ax in enumerate(fig.axes[:4]):
        assert ax.get_aspect() == 1.0 and ax.get_xlabel()
        lines = [ln for ln in ax.get_lines() if len(ln.get_xdata()) == 3]
        assert len(lines) == 2
        for i, line in enumerate(lines):
            xy = np.c_[line.get_xdata(), line.get_ydata()]
            leg = m.legs[i]
            assert np.allclose(xy[0], leg.base)
            assert np.allclose(xy[1], leg.elbow(q[k, i]))
            assert np.allclose(xy[2], pose)
        # the whole mechanism is framed, elbows included
        assert _within_limits(ax, _link_points(ax))
    # a pose where some postures are beyond the [0, pi] limits says so
    fig = plot_postures(m, np.array([-4.0, -1.0]))
    titles = [ax.get_title() for ax in fig.axes]
    assert any("beyond a joint limit" in t for t in titles)
    assert any("beyond" not in t and "unreachable" not in t for t in titles)


def test_prismatic_joints_are_lengths(biglide):
    m = biglide.mechanism
    fig = plot_postures(m, np.array([1.0, -2.0]))
    titles = [ax.get_title() for ax in _shown(fig)]
    assert titles and all("length units" in t and "rad" not in t for t in titles)
    for ax in _shown(fig):
        assert _within_limits(ax, _link_points(ax))
    ax = plot_joint_space(biglide, resolution=60).axes[0]
    for label in (ax.get_xlabel(), ax.get_ylabel()):
        assert "length units" in label and "rad" not in label
    # the revolute joints of the five-bar stay in radians
    fig = plot_postures(analyze(load_spec(SPEC), precision=0.5).mechanism, np.array([3.5, 6.0]))
    assert all(" rad" in ax.get_title() for ax in _shown(fig))


# ---------------------------------------------------------------- regions
def test_regions_panels_areas_and_overlay(result, biglide):
    for analysis in (result, biglide):
        fig = plot_regions(analysis)
        axes = _shown(fig)
        assert len(axes) == len(analysis.regions) + 1
        _outer_labelled(fig)
        for region, ax in zip(analysis.regions, axes, strict=False):
            assert ax.get_aspect() == 1.0
            lo, hi = region.area
            bounds = [float(v) for v in re.search(r"\[(.*), (.*)\]", ax.get_title()).groups()]
            # three significant digits, rounded outwards: the bounds still hold the area
            assert bounds[0] <= lo <= hi <= bounds[1]
            assert bounds[1] - bounds[0] <= (hi - lo) + 0.02 * hi
        (legend,) = fig.legends
        texts = [t.get_text() for t in legend.get_texts()]
        assert any("undecided band" in t for t in texts)
        # every colour of the overlay is a region's or a mixture the legend names
        overlay = axes[-1]
        entries = {
            to_rgb(h.get_facecolor()): t.get_text()
            for h, t in zip(legend.legend_handles, legend.get_texts(), strict=True)
        }
        drawn = {
            to_rgb(c.get_facecolor()[0])
            for c in overlay.collections
            if len(c.get_facecolor()) and len(c.get_paths())
        }
        assert drawn
        for color in drawn:
            match = [t for rgb, t in entries.items() if np.allclose(rgb, color, atol=1e-6)]
            assert match, color
        mixtures = [t for t in texts if "overlay" in t]
        if analysis is result:
            # the paper's two regions share the upper part of W
            assert mixtures == ["W_N0 and W_N1 (overlay)"]


def test_regions_panels_frame_the_workspace(result, biglide):
    """Each panel encloses every cell of W (certified or undecided) and no more
    than their box widened by the margin; equal scales on both axes."""
    for analysis in (result, biglide):
        fig = plot_regions(analysis)
        fig.canvas.draw()
        leaves = analysis.tree.leaves()
        possible = (analysis.table.status != OUT).any(axis=1)
        lo, hi = leaves.lo[possible].min(axis=0), leaves.hi[possible].max(axis=0)
        margin = WORKSPACE_PAD * float((hi - lo).max())
        assert margin > 0
        for ax in _shown(fig):
            assert ax.get_aspect() == 1.0
            view = np.array([sorted(ax.get_xlim()), sorted(ax.get_ylim())])
            assert (view[:, 0] <= lo).all() and (view[:, 1] >= hi).all()
            assert (view[:, 0] >= lo - margin - 1e-9).all()
            assert (view[:, 1] <= hi + margin + 1e-9).all()
        # the paper's W leaves most of the lower half of its pose box empty: the
        # panels no longer show it
        if analysis is result:
            assert view[1, 0] > analysis.mechanism.bounds[0][1] + 5.0


# ------------------------------------------------------------ joint space
def _knees(m, q):
    if m.name == "biglide":
        return np.c_[q[:, 0], 0 * q[:, 0]], np.c_[q[:, 1], 0 * q[:, 1]]
    return m.legs[0].elbow(q[:, 0]), m.legs[1].elbow(q[:, 1])


def _forward(m, q):
    """Both poses of each joint vector, by the angle at the first knee (NaN: none)."""
    c1, c2 = _knees(m, q)
    b1, b2 = m.legs[0].distal, m.legs[1].distal
    v = c2 - c1
    d = np.hypot(v[:, 0], v[:, 1])
    with np.errstate(invalid="ignore", divide="ignore"):
        gamma = np.arccos((b1**2 + d**2 - b2**2) / (2 * b1 * d))
    towards = np.arctan2(v[:, 1], v[:, 0])
    return [
        c1 + b1 * np.c_[np.cos(towards + s * gamma), np.sin(towards + s * gamma)] for s in (1, -1)
    ]


def _brute_region(analysis, pose, q):
    """Region (index) certified to hold the configuration, None if undecided."""
    m = analysis.mechanism
    _, leaf = locate(analysis.tree, pose[None, :])
    angles = m.joint_angles(pose[None, :], clip=True)[0]
    t, g = analysis.table, analysis.graph
    found = None
    for p in range(angles.shape[0]):
        gap = angles[p] - q
        for i, lim in enumerate(m.limits):
            if not lim.prismatic:
                gap[i] = (gap[i] + np.pi) % (2 * np.pi) - np.pi
        if not np.all(np.abs(gap) < 1e-6 * 20):
            continue
        node = (int(leaf[0]), p)
        if t.status[node] == IN or t.group[node]:
            for j, region in enumerate(analysis.regions):
                if g.certain[node] == region.certain:
                    found = j
    if found is not None:
        # the pose-level answer agrees: that region holds a configuration of the pose
        answer = analysis.locate(pose[None, :])["points"][0]["regions"]
        assert answer[str(analysis.regions[found].id)] is True
    return found


@pytest.mark.parametrize("spec", [SPEC, FULL_TURN, BIGLIDE])
def test_joint_space_raster_matches_brute_force(spec):
    analysis = analyze(load_spec(spec), precision=0.1)
    m = analysis.mechanism
    fig = plot_joint_space(analysis, resolution=90)
    ax = fig.axes[0]
    (image,) = ax.get_images()
    rgba = np.asarray(image.get_array())
    n = rgba.shape[0]
    x0, x1, y0, y1 = image.get_extent()
    rng = np.random.default_rng(7)
    cells = rng.integers(0, n, size=(150, 2))
    q = np.c_[x0 + (cells[:, 1] + 0.5) * (x1 - x0) / n, y0 + (cells[:, 0] + 0.5) * (y1 - y0) / n]
    poses = _forward(m, q)
    colors = [*(PALETTE[j] for j in range(len(analysis.regions))), UNDECIDED]
    seen = set()
    for k in range(q.shape[0]):
        labels = []
        for pose in (poses[0][k], poses[1][k]):
            if np.isfinite(pose).all():
                j = _brute_region(analysis, pose, q[k])
                labels.append(len(analysis.regions) if j is None else j)
        pixel = rgba[cells[k, 0], cells[k, 1]]
        if not labels:
            assert pixel[3] == 0.0  # nothing drawn where no configuration exists
            continue
        expected = np.mean([to_rgb(colors[j]) for j in sorted(set(labels))], axis=0)
        assert pixel[3] == 1.0 and np.allclose(pixel[:3], expected, atol=1e-9), (q[k], labels)
        seen.update(labels)
    # the samples met every region
    assert set(range(len(analysis.regions))) <= seen


@pytest.mark.parametrize("spec", [SPEC, FULL_TURN])
def test_joint_space_traces_are_filled(spec):
    analysis = analyze(load_spec(spec), precision=0.05)
    q1, q2, holds = joint_space_raster(analysis, resolution=150)
    g1, g2 = np.meshgrid(q1, q2)
    m = analysis.mechanism
    c1, c2 = _knees(m, np.c_[g1.ravel(), g2.ravel()])
    d = np.hypot(*(c1 - c2).T).reshape(g1.shape)
    b1, b2 = m.legs[0].distal, m.legs[1].distal
    inside = (d > abs(b1 - b2)) & (d < b1 + b2)
    anything = holds.any(axis=2)
    assert not (anything & ~inside).any()
    assert anything[inside].all()
    for j in range(len(analysis.regions)):
        trace = holds[..., j]
        # the paper's cases: each region holds one configuration over almost every q of D
        assert trace[inside].mean() > 0.97
        # coarse check (blocks of 5 x 5 cells): no hole inside a trace
        coarse = trace.reshape(30, 5, 30, 5).any(axis=(1, 3))
        assert not (ndimage.binary_fill_holes(coarse) & ~coarse).any()


def test_user_defined_joint_space_is_sampled_inside_d():
    """Without forward kinematics the traces come from sampled configurations: they
    stay where the legs of the same five-bar can meet, and the figures still draw.
    (The legs written as distances, not squared: no dyads are recognised.)"""
    pytest.importorskip("sympy")
    spec = dict(load_spec("examples/five-bar-custom.toml"))
    spec["legs"] = [
        {"joint": "t1", "constraint": "sqrt((x - L1*cos(t1))**2 + (y - L1*sin(t1))**2) - L2"},
        {
            "joint": "t2",
            "constraint": "sqrt((x - L0 - L3*cos(t2))**2 + (y - L3*sin(t2))**2) - L4",
        },
    ]
    analysis = analyze(spec, precision=0.3)
    q1, q2, holds = joint_space_raster(analysis, resolution=90)
    assert holds.shape == (30, 30, len(analysis.regions) + 2)
    reference = load_spec(SPEC)
    m = analyze(reference, precision=0.5).mechanism
    g1, g2 = np.meshgrid(q1, q2)
    c1, c2 = _knees(m, np.c_[g1.ravel(), g2.ravel()])
    d = np.hypot(*(c1 - c2).T).reshape(g1.shape)
    # D is d < L2 + L4 (L2 = L4); a cell's centre may fall just outside D when the
    # cell straddles its boundary
    step = np.pi / 30 * (m.legs[0].proximal + m.legs[1].proximal)
    near = d < m.legs[0].distal + m.legs[1].distal + step
    assert holds[..., : len(analysis.regions)].any() and not holds.any(axis=2)[~near].any()
    ax = plot_joint_space(analysis, resolution=90).axes[0]
    assert "sampled" in ax.get_title()
    fig = plot_postures(analysis.mechanism, np.array([3.5, 6.0]))
    assert all(_within_limits(ax, np.array([[3.5, 6.0]])) for ax in _shown(fig))
    # written as the example writes them, the legs are dyads: forward kinematics
    dyads = analyze(load_spec("examples/five-bar-custom.toml"), precision=0.3)
    assert joint_space_raster(dyads, resolution=90)[2].shape[:2] == (90, 90)
    assert "sampled" not in plot_joint_space(dyads, resolution=90).axes[0].get_title()


def test_joint_space_draws_limits_and_singular_curves(result):
    fig = plot_joint_space(result, resolution=60)
    ax = fig.axes[0]
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "joint limits" in texts and "det A = 0: |CD| = L2 + L4" in texts
    assert any(" and R" in t and "one configuration each" in t for t in texts)
    # the limit lines lie at the limits, inside the view
    stops = {
        round(float(v), 9)
        for ln in ax.get_lines()
        if ln.get_linestyle() == "-."
        for v in (*ln.get_xdata(), *ln.get_ydata())
    }
    assert {0.0, round(np.pi, 9)} <= stops
    assert ax.get_xlim()[0] < 0.0 and ax.get_xlim()[1] > np.pi
    assert ax.get_xlabel().startswith("theta1") and "rad" in ax.get_ylabel()


# ------------------------------------------------------------------- path
def test_path_snapshots_match_the_motion(result, motion):
    fig = plot_path(result, motion)
    m = result.mechanism
    path = motion["path"]
    shown = _shown(fig)
    assert len(shown) >= 6
    _outer_labelled(fig)
    steps = [_step(ax) for ax in shown]
    assert steps == sorted(steps) and steps[0] == 0 and steps[-1] == len(path) - 1
    changes = [k for k in range(1, len(path)) if path[k]["posture"] != path[k - 1]["posture"]]
    assert changes and set(changes) <= set(steps)
    poses = np.array([c["pose"] for c in path])
    for ax in shown:
        step = _step(ax)
        conf = path[step]
        lines = [ln for ln in ax.get_lines() if len(ln.get_xdata()) == 3]
        assert len(lines) == 2
        for i, line in enumerate(lines):
            xy = np.c_[line.get_xdata(), line.get_ydata()]
            assert np.allclose(xy[0], m.legs[i].base)
            assert np.allclose(xy[1], m.legs[i].elbow(conf["joints"][i]))
            assert np.allclose(xy[2], conf["pose"])
        changed = step > 0 and path[step - 1]["posture"] != conf["posture"]
        assert ("posture change" in ax.get_title()) == changed
        # the whole mechanism and the whole path are framed
        assert _within_limits(ax, _link_points(ax))
        assert _within_limits(ax, poses)
    # the last snapshot is the goal
    last = [ln for ln in shown[-1].get_lines() if len(ln.get_xdata()) == 3]
    assert np.allclose([last[0].get_xdata()[2], last[0].get_ydata()[2]], path[-1]["pose"])


def test_path_marks_the_asked_poses(result, motion):
    path = motion["path"]
    given = dict(motion)
    given["waypoints"] = [0, len(path) // 3, len(path) - 1]
    fig = plot_path(result, given)
    for ax in _shown(fig):
        marks = {t.get_text(): t.xy for t in ax.texts if t.get_text().startswith("X")}
        assert sorted(marks) == ["X1", "X2", "X3"]
        for i, k in enumerate(given["waypoints"]):
            assert np.allclose(marks[f"X{i + 1}"], path[k]["pose"][:2])
    steps = [_step(ax) for ax in _shown(fig)]
    assert len(path) // 3 in steps
    # without waypoints: the ends are X1 and X2
    bare = {k: v for k, v in motion.items() if k != "waypoints"}
    ax = _shown(plot_path(result, bare))[0]
    marks = {t.get_text(): t.xy for t in ax.texts if t.get_text().startswith("X")}
    assert np.allclose(marks["X1"], path[0]["pose"]) and np.allclose(marks["X2"], path[-1]["pose"])


def test_path_caps_the_posture_changes_shown(result, motion):
    # a motion whose posture label flips every few steps (the drawing reads joints)
    path = [dict(c) for c in motion["path"]]
    names = ["++", "+-"]
    for k, conf in enumerate(path):
        conf["posture"] = names[(k // 7) % 2]
    changes = [k for k in range(1, len(path)) if path[k]["posture"] != path[k - 1]["posture"]]
    assert len(changes) > MAX_POSTURE_CHANGES
    fig = plot_path(result, {"feasible": True, "region": motion["region"], "path": path})
    steps = [_step(ax) for ax in _shown(fig)]
    assert set(changes[:MAX_POSTURE_CHANGES]) <= set(steps)
    assert steps[0] == 0 and steps[-1] == len(path) - 1
    assert f"the first {MAX_POSTURE_CHANGES} shown" in fig.get_suptitle()


def test_biglide_path_frames_the_sliders(biglide):
    motion = plan_motion(biglide, default_poses(biglide))
    fig = plot_path(biglide, motion)
    path = motion["path"]
    for ax in _shown(fig):
        points = _link_points(ax)
        assert _within_limits(ax, points)
        conf = path[_step(ax)]
        for rho in conf["joints"]:
            # each leg starts at its slider, on the x axis
            assert np.isclose(points[:, 0], rho).any()
    # the slider strokes [-6, 6] are drawn and framed
    ax = _shown(fig)[0]
    assert ax.get_xlim()[0] < -6.0 and ax.get_xlim()[1] > 6.0


def test_animation_frames_the_motion(result, motion, tmp_path, monkeypatch):
    closed = []
    monkeypatch.setattr(plt, "close", lambda fig=None: closed.append(fig))
    given = dict(motion)
    given["waypoints"] = [0, len(motion["path"]) // 2, len(motion["path"]) - 1]
    out = tmp_path / "motion.gif"
    animate_path(result, given, str(out))
    assert out.read_bytes()[:3] == b"GIF"
    (fig,) = closed
    ax = fig.axes[0]
    path = motion["path"]
    # the last frame drawn is the goal
    assert f"step {len(path) - 1} of {len(path) - 1}" in ax.get_title()
    legs = [ln for ln in ax.get_lines() if len(ln.get_xdata()) == 3]
    assert np.allclose([legs[0].get_xdata()[2], legs[0].get_ydata()[2]], path[-1]["pose"])
    # the axes hold the mechanism over the whole motion
    m = result.mechanism
    elbows = np.concatenate(
        [m.legs[i].elbow(np.array([c["joints"][i] for c in path])) for i in range(2)]
    )
    assert _within_limits(ax, elbows)
    assert sorted(t.get_text() for t in ax.texts) == ["X1", "X2", "X3"]


# ------------------------------------------------------- every figure
def _numbers(text):
    return re.findall(r"\d+\.\d+(?:e[-+]?\d+)?", text)


def _significant(number):
    digits = number.split("e")[0].replace(".", "").lstrip("0")
    return len(digits)


def test_titles_legends_and_fonts_of_every_figure(tmp_path):
    # a precision whose shortest text has many digits
    for spec in (SPEC, BIGLIDE):
        analysis = analyze(load_spec(spec), precision=np.pi / 30)
        motion = plan_motion(analysis, default_poses(analysis))
        for name in plot_module.FIGURES:
            fig = figure(name, analysis, motion=motion)
            titles = [ax.get_title() for ax in fig.axes] + [fig.get_suptitle()]
            for title in titles:
                for number in _numbers(title):
                    assert _significant(number) <= 3, (name, title)
            legends = _legends(fig)
            assert legends or name == "postures"
            for legend in legends:
                assert legend.get_frame().get_alpha() == 1.0, name
            # constrained layout leaves no label over another panel's
            fig.savefig(tmp_path / f"{name}.png", dpi=40)
            renderer = fig.canvas.get_renderer()
            boxes = [ax.get_tightbbox(renderer) for ax in _shown(fig)]
            for a in range(len(boxes)):
                for b in range(a + 1, len(boxes)):
                    ov_x = min(boxes[a].x1, boxes[b].x1) - max(boxes[a].x0, boxes[b].x0)
                    ov_y = min(boxes[a].y1, boxes[b].y1) - max(boxes[a].y0, boxes[b].y0)
                    assert ov_x <= 1 or ov_y <= 1, (name, a, b)
            plt.close(fig)


def test_cli_plot_files(tmp_path):
    runner = CliRunner()
    for name, ext in (("workspace", "svg"), ("regions", "png"), ("joint-space", "png")):
        out = tmp_path / f"{name}.{ext}"
        done = runner.invoke(
            main,
            ["plot", SPEC, "--figure", name, "--out", str(out), "-p", "0.3", "--no-resolve"],
        )
        assert done.exit_code == 0, done.output
        head = out.read_bytes()[:8]
        assert head.startswith(b"\x89PNG") if ext == "png" else b"<?xml" in head
    gif = tmp_path / "path.gif"
    done = runner.invoke(
        main,
        ["plot", SPEC, "--figure", "path", "--animate", "--out", str(gif), "--precision", "0.3"],
    )
    assert done.exit_code == 0, done.output
    assert gif.read_bytes()[:3] == b"GIF"
    bad = runner.invoke(
        main,
        ["plot", SPEC, "--figure", "postures", "--pose", "1,x", "--out", str(tmp_path / "p.png")],
    )
    assert bad.exit_code == 2 and "--pose" in bad.output
    bad = runner.invoke(
        main, ["plot", SPEC, "--figure", "regions", "--out", str(tmp_path / "p.jpg")]
    )
    assert bad.exit_code == 2 and "--out" in bad.output


# ------------------------------------------------ constraints beyond the paper
#: the five-bar of the constraint tests: L0..L4, unlimited actuated joints
_CONSTRAINED = {
    "mechanism": "five-bar",
    "parameters": {"L0": 9.0, "L1": 8.0, "L2": 5.0, "L3": 5.0, "L4": 8.0},
    "limits": {"theta1": "unlimited", "theta2": "unlimited"},
}
_OBSTACLE = ((4.5, 0.0), 1.0)


def _reference_exclusion(q1, q2, passive, obstacle):
    """An independent pointwise check over the grid (q1[a], q2[b]), indexed [b, a]:
    where the legs meet, where some configuration violates a constraint, and
    where every configuration does. Passive limit [-pi/2, pi/2] at P: the angle
    from CP to DP is beyond a right angle exactly where (P - C) . (P - D) < 0;
    obstacle: some moving link comes nearer its centre than its radius."""
    L0, L1, L2, L3, L4 = (_CONSTRAINED["parameters"][f"L{i}"] for i in range(5))
    t1, t2 = np.meshgrid(q1, q2)
    A = np.zeros((*t1.shape, 2))
    B = A + np.array([L0, 0.0])
    C = np.stack([L1 * np.cos(t1), L1 * np.sin(t1)], axis=-1)
    D = np.stack([L0 + L3 * np.cos(t2), L3 * np.sin(t2)], axis=-1)
    v = D - C
    d = np.hypot(v[..., 0], v[..., 1])
    meet = (d > abs(L2 - L4)) & (d < L2 + L4)
    with np.errstate(invalid="ignore"):
        along = (L2**2 - L4**2 + d**2) / (2 * d)
        across = np.sqrt(L2**2 - along**2)
    e = v / d[..., None]
    normal = np.stack([-e[..., 1], e[..., 0]], axis=-1)

    def distance(o, c, p):
        u = p - c
        t = np.clip(((o - c) * u).sum(-1) / (u * u).sum(-1), 0.0, 1.0)
        return np.hypot(*np.moveaxis(c + t[..., None] * u - o, -1, 0))

    bad = []
    for side in (1.0, -1.0):
        P = C + along[..., None] * e + side * across[..., None] * normal
        violates = np.zeros(meet.shape, dtype=bool)
        if passive:
            violates |= ((P - C) * (P - D)).sum(-1) < 0
        if obstacle:
            centre, radius = np.array(_OBSTACLE[0]), _OBSTACLE[1]
            for c, p in ((A, C), (C, P), (B, D), (D, P)):
                violates |= distance(centre, c, p) < radius
        bad.append(meet & violates)
    return meet, bad[0] | bad[1], meet & bad[0] & bad[1]


def _on_boundary(mask):
    """Cells of a mask or next to one (3 x 3) that are not deep inside or outside it."""
    grow = ndimage.binary_dilation(mask, np.ones((3, 3), dtype=bool))
    shrink = ndimage.binary_erosion(mask, np.ones((3, 3), dtype=bool), border_value=1)
    return grow & ~shrink


@pytest.mark.parametrize("kind", ["passive", "obstacle"])
def test_joint_space_marks_configurations_excluded_by_constraints(kind):
    spec = dict(_CONSTRAINED)
    if kind == "passive":
        spec["passive_limits"] = {"P": ["-pi/2", "pi/2"]}
    else:
        spec["obstacles"] = [{"center": list(_OBSTACLE[0]), "radius": _OBSTACLE[1]}]
    analysis = analyze(load_spec(spec), precision=0.2)
    n_regions = len(analysis.regions)
    q1, q2, holds = joint_space_raster(analysis, resolution=150)
    assert holds.shape == (150, 150, n_regions + 2)
    meet, some, every = _reference_exclusion(q1, q2, kind == "passive", kind == "obstacle")
    layer = holds[..., n_regions + 1]
    # a sizeable part of Q is excluded, and only where the legs meet
    assert some.mean() > 0.05 and not (layer & ~meet).any()
    # the excluded layer is the reference's, but for a few cells on its boundary
    wrong = layer ^ some
    assert wrong.sum() <= 5, wrong.sum()
    assert not (wrong & ~(_on_boundary(some) | _on_boundary(meet))).any()
    # no configuration is both certified in a region and excluded
    assert not (holds[..., :n_regions].any(axis=2) & every).any()

    # the figure: the excluded colour exactly where every configuration is excluded
    fig = plot_joint_space(analysis, resolution=150)
    ax = fig.axes[0]
    (image,) = ax.get_images()
    rgba = np.asarray(image.get_array())
    pale = np.isclose(rgba[..., :3], to_rgb(EXCLUDED), atol=1e-9).all(axis=2) & (rgba[..., 3] == 1)
    wrong = pale ^ every
    assert every.any() and wrong.sum() <= 5, wrong.sum()
    assert not (wrong & ~(_on_boundary(every) | _on_boundary(meet))).any()
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    cause = "a passive joint limit" if kind == "passive" else "an obstacle"
    assert f"excluded by {cause}" in texts
    legend = ax.get_legend()
    handle = legend.legend_handles[texts.index(f"excluded by {cause}")]
    assert np.allclose(to_rgb(handle.get_facecolor()), to_rgb(EXCLUDED))


def test_joint_space_of_an_unconstrained_design_excludes_nothing(result):
    _, _, holds = joint_space_raster(result, resolution=90)
    assert holds.shape[2] == len(result.regions) + 2
    assert holds[..., : len(result.regions) + 1].any() and not holds[..., -1].any()
    ax = plot_joint_space(result, resolution=90).axes[0]
    rgba = np.asarray(ax.get_images()[0].get_array())
    assert not np.isclose(rgba[..., :3], to_rgb(EXCLUDED), atol=1e-9).all(axis=2).any()
    assert not any("excluded" in t.get_text() for t in ax.get_legend().get_texts())


# ------------------------------------------------------------- plot --points
@pytest.mark.parametrize(
    ("content", "expected"),
    [
        (None, "invalid --points: expected an existing CSV file"),
        ("x,y\n", "invalid --points ("),
        ("x,y\n1,nan\n", "invalid --points ("),
        ("a,b\n1,2\n", "invalid --points ("),
    ],
)
def test_cli_plot_points_errors_name_the_option(tmp_path, content, expected):
    path = tmp_path / "poses.csv"
    if content is not None:
        path.write_text(content)
    out = tmp_path / "path.png"
    done = CliRunner().invoke(
        main,
        ["plot", SPEC, "--figure", "path", "--points", str(path), "--out", str(out), "-p", "0.5"],
    )
    assert done.exit_code == 2, done.output
    assert done.stdout == ""
    message = done.stderr
    assert message.startswith("Error: " + expected), message
    assert message.count("\n") == 1 and "POINTS" not in message and "Traceback" not in message
    assert not out.exists()


def test_cli_plot_points_only_for_the_path_figure(tmp_path):
    path = tmp_path / "poses.csv"
    path.write_text("x,y\n3.5,6\n")
    done = CliRunner().invoke(
        main,
        ["plot", SPEC, "--figure", "regions", "--points", str(path), "--out",
         str(tmp_path / "r.png")],
    )  # fmt: skip
    assert done.exit_code == 2 and done.stderr.count("\n") == 1
    assert done.stderr.startswith("Error: invalid --points: only the path figure")
