"""Closed-form checks: volumes of balls, projections, components of annuli, point queries."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from moveability import (
    BOUNDARY,
    IN,
    OUT,
    HyperTree,
    components,
    locate,
    measure,
    project,
)

IN_, OUT_, BND = int(IN), int(OUT), int(BOUNDARY)


def ball(radius, centre):
    """Conservative classifier of the closed ball."""
    c = np.asarray(centre, dtype=np.float64)

    def classify(lo, hi):
        near = np.sqrt(((np.clip(c, lo, hi) - c) ** 2).sum(axis=1))
        far = np.sqrt((np.maximum(np.abs(lo - c), np.abs(hi - c)) ** 2).sum(axis=1))
        return np.where(far <= radius, IN_, np.where(near > radius, OUT_, BND))

    return classify


def ball_tree(k, radius, depth):
    return HyperTree.build(-np.ones(k), np.ones(k), ball(radius, np.zeros(k)), max_depth=depth)


R4 = 0.8
BALL4_VOLUME = math.pi**2 * R4**4 / 2
R3 = 0.7
BALL3_VOLUME = 4 / 3 * math.pi * R3**3


@pytest.fixture(scope="module")
def balls4():
    return {d: ball_tree(4, R4, d) for d in (3, 4, 5, 6)}


@pytest.fixture(scope="module")
def balls3():
    return {d: ball_tree(3, R3, d) for d in (3, 4, 5, 6, 7)}


def assert_tightening(brackets, exact):
    widths = []
    for inner, outer in brackets:
        assert inner < exact < outer
        widths.append(outer - inner)
    assert all(w1 < w0 for w0, w1 in itertools.pairwise(widths)), widths
    # the inner bound never decreases and the outer one never increases (up to the
    # rounding of sums taken in different orders)
    for (i0, o0), (i1, o1) in itertools.pairwise(brackets):
        assert i1 >= i0 - 1e-12 and o1 <= o0 + 1e-12


# ----------------------------------------------------------------- balls
def test_4d_ball_volume_is_bracketed_and_tightens(balls4):
    brackets = [measure(balls4[d]) for d in sorted(balls4)]
    assert_tightening(brackets, BALL4_VOLUME)
    # at depth 6 the bracket is already within 30% of the volume
    inner, outer = brackets[-1]
    assert outer - inner < 0.3 * BALL4_VOLUME


@pytest.mark.parametrize("axes", [(0, 1), (2, 3), (3, 1)])
def test_4d_ball_projects_onto_a_disk(balls4, axes):
    brackets = []
    for d in sorted(balls4):
        p = project(balls4[d], axes)
        assert p.ndim == 2
        assert p.max_depth == (d, d)
        assert np.array_equal(p.lo, [-1.0, -1.0]) and np.array_equal(p.hi, [1.0, 1.0])
        brackets.append(measure(p))
    assert_tightening(brackets, math.pi * R4**2)
    # against the disk built directly at the same depth: a projected cell is IN only if
    # it lies in the disk, and OUT wherever it misses the disk
    for d in sorted(balls4):
        p = project(balls4[d], axes)
        disk = ball_tree(2, R4, d)
        assert measure(p - disk)[0] == 0.0  # nowhere IN in p and OUT of the disk
        assert measure(p)[0] <= measure(disk)[0] and measure(p)[1] <= measure(disk)[1]
        s_p = locate(p, grid_centres(d))[0]
        s_d = locate(disk, grid_centres(d))[0]
        assert (s_d[s_p == IN_] == IN_).all()
        assert (s_p[s_d == OUT_] == OUT_).all()


def grid_centres(depth):
    side = 2**depth
    idx = np.indices((side, side)).reshape(2, -1).T
    return -1.0 + 2.0 * (idx + 0.5) / side


def test_4d_ball_projects_onto_a_segment_and_a_ball(balls4):
    seg = [measure(project(balls4[d], [2])) for d in sorted(balls4)]
    for inner, outer in seg:
        assert inner <= 2 * R4 <= outer
    b3 = [measure(project(balls4[d], [0, 1, 2])) for d in sorted(balls4)]
    assert_tightening(b3, 4 / 3 * math.pi * R4**3)


def test_3d_ball_volume_is_bracketed_and_tightens(balls3):
    brackets = [measure(balls3[d]) for d in sorted(balls3)]
    assert_tightening(brackets, BALL3_VOLUME)
    inner, outer = brackets[-1]
    assert outer - inner < 0.15 * BALL3_VOLUME
    proj = [measure(project(balls3[d], (0, 2))) for d in sorted(balls3)]
    assert_tightening(proj, math.pi * R3**2)


def test_ball_in_an_offset_box():
    # a box that is neither centred nor cubic, and a ball off its centre
    lo, hi = np.array([2.0, -3.0, 10.0]), np.array([4.0, 1.0, 11.0])
    centre, radius = np.array([3.1, -1.2, 10.45]), 0.4
    brackets = [
        measure(HyperTree.build(lo, hi, ball(radius, centre), max_depth=d)) for d in (4, 5, 6)
    ]
    assert_tightening(brackets, 4 / 3 * math.pi * radius**3)


def test_ball_is_one_component_and_its_complement_too(balls3):
    for d in (3, 5, 7):
        t = balls3[d]
        assert components(t, status=IN)[1] == 1
        assert components(t, status=IN | BOUNDARY)[1] == 1
        assert components(~t, status=IN)[1] == 1
        assert components(t, status=BOUNDARY)[1] == 1


def test_locate_in_the_ball(balls4):
    d = 5
    tree = balls4[d]
    diag = 2.0 / 2**d * math.sqrt(4)
    rng = np.random.default_rng(7)
    pts = rng.uniform(-1, 1, size=(4000, 4))
    dist = np.sqrt((pts**2).sum(axis=1))
    status, index = locate(tree, pts)
    well_inside = dist < R4 - diag - 1e-9
    well_outside = dist > R4 + diag + 1e-9
    assert well_inside.sum() > 50 and well_outside.sum() > 50
    assert (status[well_inside] == IN_).all()
    assert (status[well_outside] == OUT_).all()
    # every point of the box is in some leaf, and that leaf's box holds it
    assert (index >= 0).all()
    leaves = tree.leaves()
    assert (leaves.lo[index] <= pts).all() and (pts <= leaves.hi[index]).all()
    assert np.array_equal(status, leaves.status[index])
    # the centre, a corner and points outside the box
    s, i = locate(tree, [[0, 0, 0, 0], [1, 1, 1, 1], [-1, -1, -1, -1], [2, 0, 0, 0]])
    assert s.tolist() == [IN_, OUT_, OUT_, OUT_]
    assert i[:3].min() >= 0 and i[3] == -1
    # a single point given as a 1-D array
    s, _ = locate(tree, np.zeros(4))
    assert s.tolist() == [IN_]


# --------------------------------------------------------------- annuli
THETA_LO, THETA_HI = -math.pi, math.pi
R_IN, R_OUT = 0.6, 1.4  # the annulus, in polar coordinates a rectangle
STRIP_C, STRIP_HW = 0.3, 0.5  # the strip |theta - 0.3| < 0.5 that is removed


def polar_cut_annulus(lo, hi):
    """Exact classifier of {R_IN <= r <= R_OUT} minus the open strip |theta - c| < hw."""
    t0, t1, r0, r1 = lo[:, 0], hi[:, 0], lo[:, 1], hi[:, 1]
    band_in = (r0 >= R_IN) & (r1 <= R_OUT)
    band_out = (r1 < R_IN) | (r0 > R_OUT)
    strip_lo, strip_hi = STRIP_C - STRIP_HW, STRIP_C + STRIP_HW
    in_strip = (t0 > strip_lo) & (t1 < strip_hi)  # the whole cell is in the open strip
    meets_strip = (t1 > strip_lo) & (t0 < strip_hi)
    inside = band_in & ~meets_strip
    outside = band_out | in_strip
    return np.where(inside, IN_, np.where(outside, OUT_, BND))


def polar_tree(depth, periodic):
    return HyperTree.build(
        [THETA_LO, 0.0], [THETA_HI, 2.0], polar_cut_annulus, max_depth=depth, periodic=periodic
    )


@pytest.mark.parametrize("depth", [3, 4, 5, 7, (6, 4), (4, 6)])
@pytest.mark.parametrize("status", [IN, IN | BOUNDARY])
@pytest.mark.parametrize("connectivity", [1, 2])
def test_polar_annulus_minus_strip(depth, status, connectivity):
    flat = polar_tree(depth, periodic=())
    ring = polar_tree(depth, periodic=(0,))
    assert components(flat, status=status, connectivity=connectivity)[1] == 2
    assert components(ring, status=status, connectivity=connectivity)[1] == 1
    # the two trees are the same set; only the topology differs
    assert np.array_equal(flat.keys, ring.keys)
    assert np.array_equal(flat.status, ring.status)
    labels, count = components(flat, status=status, connectivity=connectivity)
    assert count == 2 and labels.max() == 1
    leaves = flat.leaves()
    taken = labels >= 0
    # one component lies at theta below the strip, the other above it
    centre = (leaves.lo[:, 0] + leaves.hi[:, 0]) / 2
    below = centre < STRIP_C
    assert len(set(labels[taken & below])) == 1
    assert len(set(labels[taken & ~below])) == 1
    assert set(labels[taken & below]) != set(labels[taken & ~below])


def test_polar_annulus_area():
    exact = (2 * math.pi - 2 * STRIP_HW) * (R_OUT - R_IN)
    assert_tightening([measure(polar_tree(d, periodic=(0,))) for d in (3, 4, 5, 6, 7)], exact)


def cartesian_annulus(r_in, r_out, strip_hw=None):
    """Conservative classifier of r_in <= |p| <= r_out, minus the open strip |x| < strip_hw."""

    def classify(lo, hi):
        near = np.sqrt((np.clip(0.0, lo, hi) ** 2).sum(axis=1))
        far = np.sqrt((np.maximum(np.abs(lo), np.abs(hi)) ** 2).sum(axis=1))
        inside = (near >= r_in) & (far <= r_out)
        outside = (far < r_in) | (near > r_out)
        if strip_hw is not None:
            inside &= (lo[:, 0] >= strip_hw) | (hi[:, 0] <= -strip_hw)
            outside |= (lo[:, 0] > -strip_hw) & (hi[:, 0] < strip_hw)
        return np.where(inside, IN_, np.where(outside, OUT_, BND))

    return classify


@pytest.mark.parametrize("depth", [4, 5, 6, 7])
def test_cartesian_annulus_components(depth):
    box = ([-2.0, -2.0], [2.0, 2.0])
    cut = HyperTree.build(*box, cartesian_annulus(0.5, 1.5, strip_hw=0.3), max_depth=depth)
    full = HyperTree.build(*box, cartesian_annulus(0.5, 1.5), max_depth=depth)
    for c in (1, 2):
        assert components(cut, status=IN, connectivity=c)[1] == 2
        assert components(cut, status=IN | BOUNDARY, connectivity=c)[1] == 2
        assert components(full, status=IN, connectivity=c)[1] == 1
        assert components(full, status=IN | BOUNDARY, connectivity=c)[1] == 1
        # the complement: the inner disk and the part outside the annulus
        assert components(~full, status=IN, connectivity=c)[1] == 2
    # outside the cut annulus, the strip joins the inner disk to the outer part
    assert components(~cut, status=IN)[1] == 1
    # gluing x: the halves of the cut annulus do not reach the box edges, still 2
    glued = HyperTree.build(
        *box, cartesian_annulus(0.5, 1.5, strip_hw=0.3), max_depth=depth, periodic=[0]
    )
    assert components(glued, status=IN)[1] == 2
    glued_full = HyperTree.build(*box, cartesian_annulus(0.5, 1.5), max_depth=depth, periodic=[0])
    assert components(~glued_full, status=IN)[1] == 2
    # the cut annulus is the full one minus the strip, as a set operation too
    strip = HyperTree.build(
        *box,
        lambda lo, hi: np.where(
            (lo[:, 0] > -0.3) & (hi[:, 0] < 0.3),
            IN_,
            np.where((hi[:, 0] <= -0.3) | (lo[:, 0] >= 0.3), OUT_, BND),
        ),
        max_depth=depth,
    )
    assert components(full - strip, status=IN)[1] == 2
    area = math.pi * (1.5**2 - 0.5**2)
    inner, outer = measure(full)
    assert inner <= area <= outer
    ci, co = measure(full - strip)
    assert ci <= inner and co <= outer


def test_components_labels_split_inner_disk_from_outside():
    box = ([-2.0, -2.0], [2.0, 2.0])
    full = HyperTree.build(*box, cartesian_annulus(0.5, 1.5), max_depth=6)
    comp = ~full
    labels, count = components(comp, status=IN)
    assert count == 2
    _, idx = locate(comp, [[0.0, 0.0], [0.1, -0.2], [1.95, 1.95], [-1.9, 0.0], [0.0, 1.99]])
    got = labels[idx]
    assert got[0] == got[1]
    assert got[2] == got[3] == got[4]
    assert got[0] != got[2]
    # labels are numbered from the first leaf by key: the leaf at the lower corner
    assert labels[0] == 0
    assert got[2] == 0 and got[0] == 1
