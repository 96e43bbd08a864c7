"""The command workflow: analyse once and answer many times from the saved file;
output paths refused before any computation; nothing half-written; one
progress display across the phases.

These tests run the real analysis of the paper's five-bar at a coarse
precision (about a second), once per module.
"""

from __future__ import annotations

import json
import os
import stat
import zipfile

import numpy as np
import pytest
from click.testing import CliRunner

import moveability.analysis.result as result_module
from moveability import analyze, load_analysis, load_spec, save_analysis
from moveability.cli import main

EXAMPLES = os.path.join(os.path.dirname(__file__), "..", "..", "examples")
PAPER = os.path.abspath(os.path.join(EXAMPLES, "five-bar-paper.toml"))
EPS = "0.2"


def run(args, input=None):
    return CliRunner().invoke(main, args, input=input)


def one_line_error(result, *names, code=2):
    assert result.exit_code == code, (result.exit_code, result.output)
    message = result.stderr
    assert message.startswith("Error: ") and message.count("\n") == 1, message
    assert "Traceback" not in message
    for name in names:
        assert name in message, (name, message)


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """The paper's five-bar analysed by ``moveability analyze --out``."""
    path = str(tmp_path_factory.mktemp("saved") / "paper.npz")
    result = run(["analyze", PAPER, "-p", EPS, "--out", path])
    assert result.exit_code == 0, result.output
    assert "N-connected regions: 2" in result.stdout
    return path


@pytest.fixture
def no_computation(monkeypatch):
    """Make any analysis fail: the command must not compute. Returns the refusal."""

    def refuse(*args, **kwargs):
        raise AssertionError("computed again")

    # point queries still certify the points themselves (classify_sheets)
    for name in ("analyze", "flow_conditions", "count_in_joint_space"):
        monkeypatch.setattr(result_module, name, refuse)
    import moveability.cli.running as running
    from moveability.hypertree.tree import HyperTree

    monkeypatch.setattr(running, "run_analysis", refuse)
    monkeypatch.setattr(HyperTree, "build", refuse)
    return refuse


@pytest.fixture(scope="module")
def poses(tmp_path_factory):
    """Two poses certainly in region 0 only, and one certainly in region 1 only."""
    result = analyze(load_spec(PAPER), precision=float(EPS))
    rng = np.random.default_rng(3)
    pts = rng.uniform([-8.0, -2.0], [15.0, 14.0], size=(4000, 2))
    located = result.locate(pts)["points"]
    only = {0: [], 1: []}
    for p, a in zip(pts, located, strict=True):
        r = a["regions"]
        if r["0"] is True and r["1"] is False:
            only[0].append(p)
        if r["1"] is True and r["0"] is False:
            only[1].append(p)
    folder = tmp_path_factory.mktemp("poses")
    same = folder / "same.csv"
    apart = folder / "apart.csv"
    a, b = only[0][0], only[0][-1]
    same.write_text(f"x,y\n{a[0]},{a[1]}\n{b[0]},{b[1]}\n")
    c = only[1][0]
    apart.write_text(f"x,y\n{a[0]},{a[1]}\n{c[0]},{c[1]}\n")
    return str(same), str(apart)


# ------------------------------------------------------------- save once
def test_saved_analysis_gives_the_answers_of_the_spec(saved, poses):
    same, apart = poses
    for command in (["regions"], ["locate", same], ["feasible", same], ["feasible", apart]):
        from_spec = run([command[0], PAPER, *command[1:], "-p", EPS, "--json", "-"])
        from_file = run([command[0], saved, *command[1:], "--json", "-"])
        assert from_spec.exit_code == from_file.exit_code == 0, (from_spec.output, from_file.output)
        assert json.loads(from_spec.stdout) == json.loads(from_file.stdout), command


def test_every_command_answers_from_the_file_without_computing(
    saved, poses, tmp_path, no_computation
):
    same, _ = poses
    assert run(["regions", saved]).exit_code == 0
    assert run(["locate", saved, same]).exit_code == 0
    assert json.loads(run(["feasible", saved, same, "--json", "-"]).stdout)["feasible"] is True
    planned = run(["plan", saved, same, "--json", "-"])
    assert planned.exit_code == 0 and json.loads(planned.stdout)["path"]
    png = tmp_path / "regions.png"
    assert run(["plot", saved, "--figure", "regions", "--out", str(png)]).exit_code == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    report = run(["report", saved, "--out", str(tmp_path / "report")])
    assert report.exit_code == 0, report.output
    assert (tmp_path / "report" / "index.html").stat().st_size > 1000
    exported = run(["export", saved, "--out", str(tmp_path / "vtk"), "--json", "-"])
    assert exported.exit_code == 0, exported.output
    files = json.loads(exported.stdout)["files"]
    assert all(os.path.isfile(f["path"]) for f in files) and len(files) == 3


def test_loading_repeats_no_interval_work(saved, monkeypatch):
    expected = analyze(load_spec(PAPER), precision=float(EPS))

    def refuse(*args, **kwargs):
        raise AssertionError("interval work on loading")

    for name in ("classify_sheets", "flow_conditions", "count_in_joint_space"):
        monkeypatch.setattr(result_module, name, refuse)
    again = load_analysis(saved)
    assert again.to_dict() == expected.to_dict()
    assert again.joint_count == expected.joint_count


def test_a_different_precision_with_a_saved_file_is_refused(saved):
    one_line_error(run(["regions", saved, "-p", "0.1"]), "--precision", "0.2", "0.1")
    # the saved precision itself is accepted
    assert run(["regions", saved, "-p", EPS]).exit_code == 0


def test_generalized_aspects_must_agree_with_the_file(saved):
    one_line_error(run(["regions", saved, "--generalized-aspects"]), "--generalized-aspects")


def test_analyze_refuses_a_saved_analysis_and_a_bad_suffix(saved, tmp_path):
    one_line_error(run(["analyze", saved, "--out", str(tmp_path / "x.npz")]), "SPEC")
    one_line_error(run(["analyze", PAPER, "--out", str(tmp_path / "x.json")]), "--out", ".npz")
    one_line_error(run(["analyze", PAPER, "--out", saved]), "refusing to overwrite")


def test_damaged_or_foreign_files_are_refused(saved, tmp_path):
    fields = dict(np.load(saved, allow_pickle=False))
    damaged = tmp_path / "damaged.npz"
    fields_bad = dict(fields)
    fields_bad["table.status"] = fields["table.status"].copy()
    fields_bad["table.status"][0, 0] ^= 1
    np.savez(damaged, **fields_bad)
    one_line_error(run(["regions", str(damaged)]), "path", "damaged")
    old = tmp_path / "old.npz"
    np.savez(old, **{**fields, "version": np.array(1)})
    one_line_error(run(["regions", str(old)]), "path", "version")
    garbage = tmp_path / "garbage.npz"
    garbage.write_bytes(b"PK\x03\x04 not a zip archive")
    one_line_error(run(["regions", str(garbage)]), "path")
    one_line_error(run(["regions", str(tmp_path / "missing.npz")]), "path")
    assert zipfile.is_zipfile(saved)


def test_saved_file_mode_follows_the_umask(tmp_path):
    result = analyze(load_spec(PAPER), precision=0.5)
    old = os.umask(0o022)
    try:
        save_analysis(result, tmp_path / "a.npz")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.npz").stat().st_mode) == 0o644
    assert os.listdir(tmp_path) == ["a.npz"]


# ------------------------------------------- outputs checked before computing
@pytest.mark.parametrize(
    ("args", "names"),
    [
        (["plot", PAPER, "--figure", "regions", "--out", "{missing}/x.png"], ["--out"]),
        (["plot", PAPER, "--figure", "regions", "--out", "{file}/x.png"], ["--out"]),
        (["report", PAPER, "--out", "{file}"], ["--out", "is a file"]),
        (["report", PAPER, "--out", "{file}/sub"], ["--out"]),
        (["export", PAPER, "--out", "{file}"], ["--out"]),
        (["regions", PAPER, "--json", "{missing}/x.json"], ["--json"]),
        (["analyze", PAPER, "--out", "{missing}/x.npz"], ["--out"]),
        (
            ["sweep", PAPER, "--vary", "L0=6:7:2", "--out", "{missing}/t.csv"],
            ["--out"],
        ),
        (
            [
                "sweep", PAPER, "--vary", "L0=6:7:2", "--vary", "L2=4:5:2", "--out",
                "{dir}/t.csv", "--figure", "{missing}/map.png",
            ],
            ["--figure"],
        ),
    ],
)  # fmt: skip
def test_unwritable_outputs_are_refused_before_computing(
    args, names, tmp_path, no_computation, monkeypatch
):
    import moveability.sweep as sweep

    monkeypatch.setattr(sweep, "run_sweep", no_computation)
    a_file = tmp_path / "plain-file"
    a_file.write_text("x")
    values = {"missing": str(tmp_path / "no" / "such"), "file": str(a_file), "dir": str(tmp_path)}
    one_line_error(run([arg.format(**values) for arg in args]), *names)


def test_report_refuses_to_overwrite_without_the_flag(saved, tmp_path):
    out = tmp_path / "report"
    assert run(["report", saved, "--out", str(out)]).exit_code == 0
    first = (out / "index.html").stat().st_mtime_ns
    one_line_error(run(["report", saved, "--out", str(out)]), "refusing to overwrite")
    assert (out / "index.html").stat().st_mtime_ns == first
    assert run(["report", saved, "--out", str(out), "--overwrite"]).exit_code == 0


@pytest.mark.parametrize(
    ("pose", "names"),
    [("1,2,3", ["--pose", "2 numbers"]), ("100,100", ["--pose", "outside the workspace"])],
)
def test_plot_pose_is_checked(pose, names, tmp_path, no_computation):
    out = tmp_path / "p.png"
    result = run(["plot", PAPER, "--figure", "postures", "--pose", pose, "--out", str(out)])
    one_line_error(result, *names)
    assert not out.exists()


def test_postures_at_a_given_pose_need_no_analysis(tmp_path, no_computation):
    out = tmp_path / "p.png"
    result = run(["plot", PAPER, "--figure", "postures", "--pose", "3.5,9", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert out.read_bytes()[:4] == b"\x89PNG"


# ---------------------------------------------------- nothing half-written
def test_an_interrupted_animation_leaves_no_file(saved, tmp_path, monkeypatch):
    import moveability.output.plot as plot

    def interrupted(result, motion, out, fps=20):
        with open(out, "wb") as stream:
            stream.write(b"GIF89a half")
        raise KeyboardInterrupt

    monkeypatch.setattr(plot, "animate_path", interrupted)
    out = tmp_path / "motion.gif"
    result = run(["plot", saved, "--figure", "path", "--animate", "--out", str(out)])
    assert result.exit_code != 0
    assert os.listdir(tmp_path) == []
    # the next run is not blocked by a truncated file
    monkeypatch.undo()
    done = run(["plot", saved, "--figure", "path", "--animate", "--out", str(out)])
    assert done.exit_code == 0, done.output
    assert out.read_bytes()[:6] == b"GIF89a" and os.listdir(tmp_path) == ["motion.gif"]


def test_an_interrupted_report_leaves_no_folder(saved, tmp_path, monkeypatch):
    import moveability.output.report as report

    def interrupted(result, out_dir, *args, **kwargs):
        with open(os.path.join(out_dir, "index.html"), "w") as stream:
            stream.write("<html>")
        raise KeyboardInterrupt

    monkeypatch.setattr(report, "write_report", interrupted)
    out = tmp_path / "report"
    assert run(["report", saved, "--out", str(out)]).exit_code != 0
    assert os.listdir(tmp_path) == []


# ------------------------------------------------------------------ plan
def test_plan_prints_json_when_no_region_holds_the_poses(saved, poses):
    _, apart = poses
    result = run(["plan", saved, apart, "--json", "-"])
    assert result.exit_code == 3
    data = json.loads(result.stdout)
    assert data["feasible"] is False and data["path"] == [] and data["region"] is None
    assert "no common region" in data["reason"]
    assert json.loads(run(["feasible", saved, apart, "--json", "-"]).stdout)["feasible"] is False


# ------------------------------------------------------------------ messages
def test_messages_name_the_cell_size_and_print_no_reprs(saved):
    text = run(["regions", saved]).stdout
    # the cells of the pass at the precision are leaves of the tree, at most the
    # precision wide; without the resolution they are the smallest leaves
    result = load_analysis(saved)
    cells = result.cell_size
    widths = result.tree.leaves().hi - result.tree.leaves().lo
    assert (cells <= float(EPS)).all()
    assert np.isclose(widths, cells, rtol=1e-12, atol=0).all(axis=1).any()
    assert f"cells {cells[0]:.4g} x {cells[1]:.4g}" in text
    plain = analyze(load_spec(PAPER), precision=float(EPS), resolve=False)
    leaves = plain.tree.leaves()
    assert np.allclose(plain.cell_size, (leaves.hi - leaves.lo).min(axis=0), rtol=1e-12, atol=0)
    summary = load_analysis(saved).summary()
    assert "JointLimit" not in summary and "theta1 in [0, pi]" in summary
    one_line_error(run(["regions", PAPER, "-p", "1e-9"]), "precision", "1e-09")
    assert "array(" not in run(["regions", PAPER, "-p", "1e-9"]).stderr
