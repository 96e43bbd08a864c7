"""Figures, checked by the data they draw."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
from click.testing import CliRunner

from moveability import analyze, load_spec, plan_motion
from moveability.cli import main
from moveability.output.plot import (
    plot_joint_space,
    plot_path,
    plot_postures,
    plot_regions,
    plot_workspace,
)

SPEC = "examples/five-bar-paper.toml"


@pytest.fixture(scope="module")
def result():
    return analyze(load_spec(SPEC), precision=0.1)


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _labelled(ax):
    assert ax.get_xlabel() and ax.get_ylabel()
    assert ax.get_aspect() == 1.0


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


def test_postures_draw_the_links(result):
    m = result.mechanism
    pose = np.array([3.5, 6.0])
    fig = plot_postures(m, pose)
    q = m.joint_angles(pose[None, :])[0]
    for k, ax in enumerate(fig.axes[:4]):
        _labelled(ax)
        lines = [ln for ln in ax.get_lines() if len(ln.get_xdata()) == 3]
        assert len(lines) == 2
        for i, line in enumerate(lines):
            xy = np.c_[line.get_xdata(), line.get_ydata()]
            leg = m.legs[i]
            assert np.allclose(xy[0], leg.base)
            assert np.allclose(xy[1], leg.elbow(q[k, i]))
            assert np.allclose(xy[2], pose)
    # a pose where some postures are beyond the [0, pi] limits says so
    fig = plot_postures(m, np.array([-4.0, -1.0]))
    titles = [ax.get_title() for ax in fig.axes]
    assert any("beyond a joint limit" in t for t in titles)
    assert any("beyond" not in t and "unreachable" not in t for t in titles)


def test_regions_panels_and_areas(result):
    fig = plot_regions(result)
    axes = [ax for ax in fig.axes if ax.axison]
    assert len(axes) == len(result.regions) + 1
    for region, ax in zip(result.regions, axes, strict=False):
        _labelled(ax)
        text = " ".join(t.get_text() for t in ax.get_legend().get_texts())
        assert f"{region.area[0]:.3f}" in text and f"{region.area[1]:.3f}" in text
        assert "undecided band" in text


def test_joint_space_traces_are_within_limits(result):
    fig = plot_joint_space(result)
    ax = fig.axes[0]
    assert ax.get_xlabel().startswith("theta1") and "rad" in ax.get_ylabel()
    offsets = np.concatenate(
        [c.get_offsets() for c in ax.collections if type(c).__name__ == "PathCollection"]
    )
    assert len(offsets) > 100
    for i, lim in enumerate(result.mechanism.limits):
        assert (offsets[:, i] >= lim.lo - 1e-9).all() and (offsets[:, i] <= lim.hi + 1e-9).all()


def test_path_snapshots_match_the_motion(result):
    motion = plan_motion(result, [[-4.0, -1.0], [1.0, 3.0], [10.0, 2.0]])
    fig = plot_path(result, motion)
    m = result.mechanism
    path = motion["path"]
    shown = [ax for ax in fig.axes if ax.axison]
    assert len(shown) >= 6
    for ax in shown:
        _labelled(ax)
        step = int(ax.get_title().split("step ")[1].split(",")[0])
        conf = path[step]
        lines = [ln for ln in ax.get_lines() if len(ln.get_xdata()) == 3]
        for i, line in enumerate(lines):
            xy = np.c_[line.get_xdata(), line.get_ydata()]
            assert np.allclose(xy[1], m.legs[i].elbow(conf["joints"][i]))
            assert np.allclose(xy[2], conf["pose"])
        changed = step > 0 and path[step - 1]["posture"] != conf["posture"]
        assert ("posture change" in ax.get_title()) == changed


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
