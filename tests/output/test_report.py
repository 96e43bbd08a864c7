"""The HTML report: its content, its spec as TOML, and the cells it embeds.

The page itself, in a real browser, is tested in ``test_report_browser.py``.
"""

import html
import math
import re
import tomllib

import numpy as np
import pytest

from moveability import BOUNDARY, analyze
from moveability.mechanisms import from_spec
from moveability.mechanisms.registry import load_spec
from moveability.output.report import spec_toml, write_report
from moveability.output.report_cells import page_cells

SPEC = "examples/five-bar-paper.toml"


@pytest.fixture(scope="module")
def analysis():
    return analyze(load_spec(SPEC), precision=0.2)


def _motion(result):
    """A motion as plan_motion gives it: three configurations in one leaf of
    region 0, the middle one a pose asked on the way."""
    leaves = result.tree.leaves()
    leaf = int(np.flatnonzero(result.region_cells(0)[0])[0])
    lo, hi = leaves.lo[leaf], leaves.hi[leaf]
    poses = lo + np.array([[0.25], [0.5], [0.75]]) * (hi - lo)
    certain = result.graph.certain[leaf] == result.regions[0].certain
    posture = int(np.flatnonzero(certain)[0])
    joints = result.mechanism.joint_angles(poses)[:, posture]
    name = result.mechanism.posture_name(posture)
    return {
        "feasible": True,
        "region": result.regions[0].id,
        "path": [
            {"pose": p.tolist(), "joints": q.tolist(), "posture": name}
            for p, q in zip(poses, joints, strict=True)
        ],
        "waypoints": [0, 1, 2],
        "length": {
            "pose": {"before": 0.5, "after": 0.25},
            "joints": {"before": 0.125, "after": 0.125},
        },
    }


@pytest.fixture(scope="module")
def page(analysis, tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    path = write_report(analysis, out, _motion(analysis), spec_path=f"some/where/{SPEC}")
    assert path == str(out / "index.html")
    return (out / "index.html").read_text()


def test_sections_are_named_in_words_with_contents(page):
    for name, title in (
        ("mechanism", "Mechanism"),
        ("analysis", "Analysis"),
        ("explore", "Explore the regions"),
        ("motion", "Planned motion"),
        ("figures", "Figures"),
    ):
        assert f'<section id="{name}"><h2>{title}</h2>' in page
        assert f'<a href="#{name}">{title}</a>' in page
    for name, title in (
        ("workspace", "Workspace"),
        ("postures", "Postures"),
        ("regions", "Regions"),
        ("joint-space", "Joint space"),
    ):
        assert f'<figure id="{name}"><h3>{title}</h3>' in page
        assert f'<a href="#{name}">{title}</a>' in page
    assert '<figure id="path"><h3>Planned motion</h3>' in page
    assert "<h3>joint-space</h3>" not in page
    assert len(re.findall(r'src="data:image/png;base64,', page)) == 5


def test_spec_is_toml_with_angles_in_pi_and_its_file_named(page):
    spec = html.unescape(re.search(r'<pre class="spec">(.*?)</pre>', page, re.S).group(1))
    assert 'theta1 = [0.0, "pi"]' in spec
    assert "3.141592653589793" not in spec
    assert tomllib.loads(spec)["parameters"]["L0"] == 7.0
    assert "specification from <code>five-bar-paper.toml</code>" in " ".join(page.split())
    assert "some/where" not in page  # the file's name only


def test_summary_gives_precision_and_cells_actually_used(analysis, page):
    text = html.unescape(re.sub(r"<[^>]+>", " ", page))
    assert "Precision 0.2 " in " ".join(text.split())
    # the leaves at the precision's level: x is halved once more than 0.2 asks,
    # the resolution's levels letting it
    widths = re.search(r"Cells at the precision\s+([\d.]+) \u00d7 ([\d.]+) \(x \u00d7 y\)", text)
    leaves = analysis.tree.leaves()
    undecided = analysis.tree.status == BOUNDARY
    largest = (leaves.hi - leaves.lo)[undecided].max(axis=0)
    assert [float(widths.group(1)), float(widths.group(2))] == pytest.approx(largest, rel=1e-3)
    for number in re.findall(r"\d+\.\d+", widths.group(0)):
        assert len(number.replace("0.", "", 1).lstrip("0")) <= 4
    assert page.count("<tr><td>") == 2  # the two regions of the paper's case
    assert "<dt>W N-connected</dt><dd><strong>no</strong>" in page
    assert "http://" not in page and "https://" not in page  # nothing to fetch


def test_motion_gives_its_poses_and_length(analysis, page):
    motion = _motion(analysis)
    text = " ".join(html.unescape(re.sub(r"<[^>]+>", " ", page)).split())
    start, middle, end = (motion["path"][k]["pose"] for k in (0, 1, 2))
    for what, pose in (("Start", start), ("Through", middle), ("End", end)):
        shown = ", ".join(f"{v:.4g}" for v in pose)
        assert f"{what} (x, y) = ({shown})" in text
    assert "Length 0.25 in pose coordinates (before smoothing 0.5); 0.125 in joint" in text


def test_page_without_motion_says_why(analysis, tmp_path):
    path = write_report(analysis, tmp_path, None, no_motion="the poses are apart")
    with open(path, encoding="utf-8") as handle:
        page = handle.read()
    assert "No motion: the poses are apart." in page
    assert '<figure id="path">' not in page
    assert "specification as given to the analysis" in " ".join(page.split())


@pytest.mark.parametrize(
    "spec",
    [
        "examples/five-bar-paper.toml",
        "examples/five-bar-full-turn.toml",
        "examples/five-bar-unlimited.toml",
        "examples/biglide.toml",
        "examples/three-rpr.toml",
        "examples/three-rrr.toml",
        "examples/five-bar-custom.toml",
    ],
)
def test_spec_toml_reads_back_to_the_same_mechanism(spec):
    if "custom" in spec:
        pytest.importorskip("sympy")
    mechanism = from_spec(load_spec(spec))
    text = spec_toml(mechanism)
    again = from_spec(load_spec(tomllib.loads(text)))
    assert again.to_spec() == mechanism.to_spec()
    if any(not lim.prismatic and not lim.periodic for lim in mechanism.limits):
        assert "pi" in text and str(math.pi) not in text


# ------------------------------------------------------------------- cells
def _poses(result, n, seed):
    rng = np.random.default_rng(seed)
    lo, hi = result.tree.lo, result.tree.hi
    inside = lo + rng.random((n, lo.size)) * (hi - lo)
    faces = result.tree.leaves().lo[rng.choice(len(result.tree), n // 4)]
    outside = lo - 0.1 * (hi - lo) + rng.random((n // 8, lo.size)) * 1.2 * (hi - lo)
    return result.as_poses(np.concatenate([inside, faces, outside]))


def _check_against_library(result, cells, poses, exact):
    """The page's answers never contradict the library's; with ``exact``, they
    equal the answers of each pose's leaf (certainly in, may meet)."""
    ours = cells.locate(poses)
    theirs = result.locate(poses)["points"]
    ids = [str(r.id) for r in result.regions]
    for mine, lib in zip(ours, theirs, strict=True):
        for j, i in enumerate(ids):
            assert mine["regions"][j] is None or mine["regions"][j] == lib["regions"][i]
        assert mine["workspace"] is None or mine["workspace"] == lib["workspace"]
    if exact:
        from moveability.hypertree.measurement import locate

        _, leaf = locate(result.tree, poses)
        for j in range(len(ids)):
            sure, maybe = result.region_cells(j)
            inside = leaf >= 0
            expect = np.where(sure[leaf], 1, np.where(maybe[leaf], -1, 0))
            got = np.array([{True: 1, False: 0, None: -1}[o["regions"][j]] for o in ours])
            assert (got[inside] == expect[inside]).all()
            assert (got[~inside] == -1).all()
    rng = np.random.default_rng(5)
    for size in (1, 2, 3):
        for _ in range(40):
            group = poses[rng.choice(len(poses), size)]
            mine = cells.feasible(group)
            assert mine is None or mine == result.feasible(group)["feasible"]


def test_cells_answer_as_the_library(analysis):
    cells = page_cells(analysis)
    assert not cells.coarse and len(cells.tree) < len(analysis.tree)
    _check_against_library(analysis, cells, _poses(analysis, 400, 1), exact=True)


def test_coarsened_cells_stay_conservative(analysis):
    cells = page_cells(analysis, max_cells=600)
    assert cells.coarse and len(cells.tree) <= 600 and 0 < cells.coarsened < 1
    _check_against_library(analysis, cells, _poses(analysis, 400, 2), exact=False)


def test_cells_keep_every_possible_component_while_regions_may_be_missing():
    result = analyze(load_spec("examples/three-rpr.toml"), precision=2.0)
    assert not result.complete  # feasibility then reads every possible component
    cells = page_cells(result, max_cells=30_000)
    assert cells.layout.n_extra > 0
    _check_against_library(result, cells, _poses(result, 300, 3), exact=not cells.coarse)


def test_user_defined_passive_limits_are_written_in_pi():
    spec = load_spec("examples/five-bar-custom-passive.toml")
    spec["legs"][0]["passive"]["C"]["limits"] = [-math.pi / 2, math.pi]
    mechanism = from_spec(spec)
    text = spec_toml(mechanism)
    assert 'limits = ["-pi/2", "pi"]' in text
    back = from_spec(tomllib.loads(text)).to_spec()
    assert back["legs"][0]["passive"] == mechanism.to_spec()["legs"][0]["passive"]
