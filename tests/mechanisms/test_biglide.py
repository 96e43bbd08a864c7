"""The biglide against its joint-space description.

Given the slider positions (rho1, rho2), the platform point is where the
circles of radii L1 and L2 about (rho1, 0) and (rho2, 0) cross: two assembly
modes, y > 0 and y < 0. det A = y (rho2 - rho1) vanishes only on the line of
the sliders (tangent circles) and where the sliders meet, so the regions are
{mode} x {sign of rho2 - rho1} x {q in the limits : |L1 - L2| < |rho2 - rho1|
< L1 + L2}; each set is a band of the limit square between parallel lines:
convex, so connected when not empty. Hence 2 or 4 regions (or 0), found here
without any tree, and the areas of their projections estimated on a grid of
poses by testing, pose by pose, the postures of the region's sign.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from moveability import analyze, default_poses, plan_motion
from moveability.analysis.joint_space import count_in_joint_space
from moveability.errors import InvalidParameterError
from moveability.hypertree.status import IN
from moveability.limits import JointLimit
from moveability.mechanisms import Biglide, from_spec
from region_references import biglide_count, random_biglides

DESIGNS = [
    (5.0, 4.0, (-6.0, 6.0), (-6.0, 6.0)),
    (5.0, 3.0, (-2.0, 9.0), (-7.0, 1.0)),
    (4.0, 6.0, (0.0, 3.0), (1.5, 10.0)),
    (3.0, 3.5, (-1.0, 1.0), (-1.5, 1.5)),
]


def _mechanism(design):
    L1, L2, s1, s2 = design
    return Biglide(L1, L2, (JointLimit(*s1, prismatic=True), JointLimit(*s2, prismatic=True)))


def reference_regions(design):
    """(mode, band) pairs with a non-empty region: mode = sign of y, band = sign of
    rho2 - rho1."""
    L1, L2, (a1, b1), (a2, b2) = design
    lo, hi = abs(L1 - L2), L1 + L2
    out = []
    for band in (1, -1):
        # band * (rho2 - rho1) ranges over this interval on the limit square
        d_lo, d_hi = sorted((band * (a2 - b1), band * (b2 - a1)))
        if min(d_hi, hi) > max(d_lo, lo):
            out += [(1, band), (-1, band)]
    return out


def reference_area(design, mode, band, n=700):
    """Grid estimate of the area of the projection of the region (mode, band)."""
    m = _mechanism(design)
    lo, hi = m.bounds
    xs = np.linspace(lo[0], hi[0], n)
    ys = np.linspace(lo[1], hi[1], n)
    x, y = np.meshgrid(xs, ys, indexing="ij")
    pts = np.stack([x.ravel(), y.ravel()], axis=1)
    q = m.joint_angles(pts)  # (m, 4, 2)
    within = np.ones(q.shape[:2], dtype=bool)
    for i, lim in enumerate(m.limits):
        within &= (q[:, :, i] >= lim.lo) & (q[:, :, i] <= lim.hi)
    ok = within & (band * (q[:, :, 1] - q[:, :, 0]) > 0) & (mode * pts[:, 1:2] > 0)
    cell = (xs[1] - xs[0]) * (ys[1] - ys[0])
    return float(ok.any(axis=1).sum() * cell)


def _identify(result, region):
    """(mode, band) of an analysis region, from its postures and sign."""
    m = result.mechanism
    names = [m.posture_name(p) for p in range(m.postures.shape[0])]
    bands = set()
    for name in region.postures:
        p = names.index(name)
        # at any pose: branch 0 is x + h, branch 1 is x - h (h >= 0)
        b1, b2 = m.postures[p]
        L1, L2 = m.lengths
        if b1 != b2:
            bands.add(1 if b1 == 1 else -1)
        else:  # same branch: rho2 - rho1 = +-(h2 - h1), h larger for the longer leg
            bands.add((1 if L2 > L1 else -1) * (1 if b1 == 0 else -1))
    assert len(bands) == 1, region
    band = bands.pop()
    return region.sign * band, band


@pytest.mark.parametrize("design", DESIGNS)
def test_regions_match_the_joint_space(design):
    result = analyze(_mechanism(design), precision=0.1)
    expected = reference_regions(design)
    assert result.undecided["components"] == 0
    assert len(result.regions) == len(expected)
    found = [_identify(result, r) for r in result.regions]
    assert sorted(found) == sorted(expected)
    for region, (mode, band) in zip(result.regions, found, strict=True):
        area = reference_area(design, mode, band)
        inner, outer = region.area
        # the grid estimate errs by about a cell along the region's outline
        assert inner - 0.3 <= area <= outer + 0.3, (region, area)


@pytest.mark.parametrize("design", DESIGNS[:2])
def test_membership_is_true_pose_by_pose(design):
    """Every definite answer of locate agrees with the closed form at the pose."""
    result = analyze(_mechanism(design), precision=0.2)
    found = [_identify(result, r) for r in result.regions]
    m = result.mechanism
    rng = np.random.default_rng(7)
    lo, hi = m.bounds
    pts = rng.uniform(lo, hi, size=(3000, 2))
    answers = result.locate(pts)["points"]
    q = m.joint_angles(pts)
    within = np.ones(q.shape[:2], dtype=bool)
    for i, lim in enumerate(m.limits):
        within &= (q[:, :, i] >= lim.lo) & (q[:, :, i] <= lim.hi)
    n_definite = 0
    for k, answer in enumerate(answers):
        assert answer["workspace"] is not True or within[k].any()
        assert answer["workspace"] is not False or not within[k].any()
        for region, (mode, band) in zip(result.regions, found, strict=True):
            held = (within[k] & (band * (q[k, :, 1] - q[k, :, 0]) > 0)).any()
            held &= mode * pts[k, 1] > 0
            verdict = answer["regions"][str(region.id)]
            if verdict is True:
                assert held, (pts[k], region)
            elif verdict is False:
                assert not held, (pts[k], region)
            n_definite += verdict is not None
    assert n_definite > 0.8 * len(answers) * len(result.regions)


def test_posture_changes_at_the_fold():
    """A region changes posture where the leg stands perpendicular (|y| = L)."""
    result = analyze(_mechanism(DESIGNS[0]), precision=0.1)
    assert all(len(r.postures) == 2 for r in result.regions)
    # and a motion through the fold is planned and valid (the planner checks it)
    region = result.regions[0]
    inside = result.tree.leaves()
    leaf_in = (result.graph.certain == region.certain) & (result.table.status == IN)
    centres = 0.5 * (inside.lo + inside.hi)[leaf_in.any(axis=1)]
    a, b = centres[0], centres[-1]
    motion = plan_motion(result, [a, b])
    assert motion["feasible"] is True


def test_figures_draw_the_sliders(tmp_path):
    """The 2-D figures serve the biglide: its legs are drawn from the slider to P."""
    import matplotlib

    matplotlib.use("Agg")
    from moveability.output.plot import FIGURES, figure

    result = analyze(_mechanism(DESIGNS[0]), precision=0.2)
    pose = np.array([1.0, 2.0])
    fig = figure("postures", result, pose=pose)
    q = result.mechanism.joint_angles(pose[None, :])[0]
    drawn = [
        line.get_xydata()
        for ax in fig.axes
        for line in ax.get_lines()
        if len(line.get_xydata()) == 2
    ]
    # every posture's legs: slider at (rho_i, 0), tip at the pose
    for posture in q:
        for rho in posture:
            assert any(np.allclose(d, [[rho, 0.0], pose]) for d in drawn), rho
    motion = plan_motion(result, default_poses(result))
    for name in FIGURES:
        figure(name, result, motion=motion).savefig(tmp_path / f"{name}.png", dpi=50)


# ------------------------------------------------ the count in closed form
def _strokes(lengths, rho1, rho2):
    return from_spec(
        {
            "mechanism": "biglide",
            "parameters": {"L1": lengths[0], "L2": lengths[1]},
            "limits": {"rho1": list(rho1), "rho2": list(rho2)},
        }
    )


def _in_d(m, q) -> bool:
    """Whether the strokes ``q`` lie in the box and in D, in exact rationals."""
    (l1, l2), (s1, s2) = m.lengths, m.limits
    r1, r2 = Fraction(float(q[0])), Fraction(float(q[1]))
    inside = all(
        Fraction(lim.lo) <= r <= Fraction(lim.hi) for lim, r in ((s1, r1), (s2, r2))
    )
    t = abs(r2 - r1)
    return inside and abs(Fraction(l1) - Fraction(l2)) < t < Fraction(l1) + Fraction(l2)


@pytest.mark.parametrize("seed", range(3))
def test_closed_form_count_agrees_with_the_tree_of_the_joint_space(seed):
    for m in random_biglides(12, 40 + seed):
        n, witnesses, notes = m.exact_region_count()
        assert 2 * n == biglide_count(m)
        tree = count_in_joint_space(m, closed_form=False)
        if tree.decided:
            assert tree.at_least == 2 * n
        assert all(_in_d(m, q) for q in witnesses)
        assert notes == ()


@pytest.mark.parametrize("overlap", [1e-9, 1e-12, 2.0**-40, 0.0, -1e-12])
@pytest.mark.parametrize("lengths", [(5.0, 5.0), (6.5, 2.0)])
def test_strokes_that_overlap_the_reach_by_a_hair(overlap, lengths):
    far = lengths[0] + lengths[1]
    if overlap < 0:
        # the legs never meet: refused before any analysis
        with pytest.raises(InvalidParameterError, match="limits"):
            _strokes(lengths, (-2.0, 0.0), (far - overlap, far + 3.0))
        return
    m = _strokes(lengths, (-2.0, 0.0), (far - overlap, far + 3.0))
    n, witnesses, notes = m.exact_region_count()
    # the exact sum of the floats decides: rho2's low end against L1 + L2
    gap = Fraction(m.limits[1].lo) - Fraction(far)
    assert n == (1 if gap < 0 else 0)
    assert all(_in_d(m, q) for q in witnesses)
    assert (len(notes) == 1) == (gap == 0)
    if notes:
        assert "exactly degenerate" in notes[0]
    result = analyze(m, precision=0.1)
    assert result.count == (2 * n, 2 * n)
    assert list(result.notes) == list(notes)
    if n and not result.regions:
        # too thin to list: the output says where it is still open
        assert result.undecided["open"]["parts"] > 0
        assert "still open" in result.summary()
