"""The 3-RPR against a brute-force labelling of a grid over (x, y, phi).

One posture per pose: a region is a connected set of poses where the three
lengths are within their strokes and det A keeps one sign. The reference
computes, at every node of a uniform grid (phi periodic), the closed-form
lengths and det A, and labels the valid nodes of each sign with 26-connectivity,
joining labels across the phi seam. The tree analysis must agree with it:

* a resolved region's certified leaves hold grid nodes of one grid component;
* two resolved regions never share a grid component;
* every valid grid node lies in a leaf whose possible part of its sign is
  alive, and one grid component never meets two possible components;
* pointwise answers of ``locate`` agree with the closed form.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from moveability import analyze, plan_motion
from moveability.hypertree.measurement import locate
from moveability.hypertree.status import BOUNDARY, IN
from moveability.limits import JointLimit
from moveability.mechanisms import ThreeRPR

PAPER_LIKE = ([[0, 0], [15.91, 0], [0, 10]], [[0, 0], [17.04, 0], [13.24, 16.10]], (10, 25))
DESIGNS = [
    PAPER_LIKE,
    ([[0, 0], [10, 0], [4, 8]], [[0, 0], [5, 0], [2, 4]], (4, 12)),
    ([[0, 0], [12, 1], [-2, 9]], [[1, -1], [6, 0], [3, 5]], (3, 14)),
]


def _mechanism(design):
    base, platform, (lo, hi) = design
    stroke = JointLimit(float(lo), float(hi), prismatic=True)
    return ThreeRPR(base, platform, (stroke, stroke, stroke))


def _join_periodic(labels, axis):
    """Merge labels that meet across the two ends of a periodic axis."""
    first = np.take(labels, 0, axis=axis).ravel()
    last = np.take(labels, -1, axis=axis).ravel()
    parent = np.arange(labels.max() + 1)

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a, b in zip(first, last, strict=True):
        if a and b:
            ra, rb = find(a), find(b)
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)
    roots = np.array([find(a) for a in range(parent.size)])
    return roots[labels]


class GridReference:
    """Valid nodes of a grid over the box, their sign of det A, and their labels."""

    def __init__(self, m, n=(120, 120, 96)):
        lo, hi = m.bounds
        axes = [np.linspace(lo[i], hi[i], n[i], endpoint=i != 2) for i in range(3)]
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
        self.points = grid.reshape(-1, 3)
        self.valid, self.det = self.evaluate(m, self.points)
        self.labels = np.zeros(self.points.shape[0], dtype=np.int64)
        offset = 0
        for s in (1, -1):
            mask = (self.valid & (np.sign(self.det) == s)).reshape(n)
            lab, count = ndimage.label(mask, structure=np.ones((3, 3, 3)))
            lab = _join_periodic(lab, axis=2)
            flat = lab.ravel()
            self.labels[flat > 0] = flat[flat > 0] + offset
            offset += count + 1

    @staticmethod
    def evaluate(m, points):
        q = m.joint_angles(points)[:, 0, :]
        valid = np.ones(points.shape[0], dtype=bool)
        for i, lim in enumerate(m.limits):
            valid &= (q[:, i] >= lim.lo) & (q[:, i] <= lim.hi)
        det = m.det_a(points, q)
        return valid, det


@pytest.fixture(scope="module", params=range(len(DESIGNS)))
def case(request):
    m = _mechanism(DESIGNS[request.param])
    # the plain pass: its certified cells are compared with a grid's components
    result = analyze(m, precision=(1.0, 1.0, 0.15), resolve=False)
    return result, GridReference(m)


def test_certified_regions_match_grid_components(case):
    result, ref = case
    g, t = result.graph, result.table
    _, leaf = locate(result.tree, ref.points)
    seen: dict[int, int] = {}
    for region in result.regions:
        certified = (g.certain[:, 0] == region.certain) & (t.status[:, 0] == IN)
        nodes = certified[np.maximum(leaf, 0)] & (leaf >= 0)
        assert ref.valid[nodes].all()
        assert (np.sign(ref.det[nodes]) == region.sign).all()
        labels = set(np.unique(ref.labels[nodes]).tolist())
        assert len(labels) == 1, (region, labels)
        label = labels.pop()
        assert label not in seen, (region, seen)
        seen[label] = region.id


def test_grid_nodes_lie_in_the_possible_parts(case):
    result, ref = case
    g = result.graph
    _, leaf = locate(result.tree, ref.points)
    inside = ref.valid & (leaf >= 0) & (np.abs(ref.det) > 0)
    assert (leaf[ref.valid] >= 0).all()
    row = np.where(ref.det > 0, 0, 1)
    # one posture: the sub-nodes of posture 0 are the first `slots` columns
    possible = np.where(
        inside, g.possible[row, np.maximum(leaf, 0), 0], -1
    )  # prismatic joints: one slot
    assert g.slots == 1
    assert (possible[inside] >= 0).all()
    for label in np.unique(ref.labels[inside]):
        nodes = inside & (ref.labels == label)
        assert np.unique(possible[nodes] + 1000 * row[nodes]).size == 1


def test_locate_is_true_pose_by_pose(case):
    result, _ = case
    m = result.mechanism
    rng = np.random.default_rng(3)
    lo, hi = m.bounds
    pts = rng.uniform(lo, hi, size=(1500, 3))
    pts[:, 2] += rng.integers(-2, 3, size=1500) * 2 * np.pi  # any turn
    valid, det = GridReference.evaluate(m, pts)
    answers = result.locate(pts)["points"]
    definite = 0
    for k, answer in enumerate(answers):
        assert answer["workspace"] is not True or valid[k]
        assert answer["workspace"] is not False or not valid[k]
        for region in result.regions:
            verdict = answer["regions"][str(region.id)]
            if verdict is True:
                assert valid[k] and np.sign(det[k]) == region.sign
            definite += verdict is not None
    assert definite > 0


def test_precision_per_axis_and_volumes():
    m = _mechanism(PAPER_LIKE)
    result = analyze(m, precision=(2.0, 2.0, 0.3))
    data = result.to_dict()
    assert data["pose"] == ["x", "y", "phi"]
    assert data["precision"] == [2.0, 2.0, 0.3]
    assert "volume" in data["workspace"] and "area" not in data["workspace"]
    inner, outer = data["workspace"]["volume"]
    # a grid estimate of the workspace volume lies within the bounds
    ref = GridReference(m, n=(100, 100, 80))
    lo, hi = m.bounds
    cell = np.prod((hi - lo) / np.array([99, 99, 80]))
    assert inner <= ref.valid.sum() * cell * 1.02
    assert ref.valid.sum() * cell * 0.98 <= outer
    # undecided leaves were refined to the precision of each axis, not finer
    leaves = result.tree.leaves()
    undecided = result.tree.status == BOUNDARY
    widths = (leaves.hi - leaves.lo)[undecided]
    assert (widths[:, :2] <= 2.0).all() and (widths[:, 2] <= 0.3).all()
    assert (widths[:, :2] > 1.0).any() and (widths[:, 2] > 0.15).any()


def test_planned_motions_are_continuous_across_the_seam(case):
    """Motions between certified leaves of each region: poses continuous (phi
    unwrapped), lengths within strokes, one sign of det A, ends equal to the poses
    asked modulo 2 pi. Where a region's certified part reaches both ends of the phi
    range, a motion between nearby poses on either side crosses the seam."""
    result, _ = case
    leaves = result.tree.leaves()
    centres = 0.5 * (leaves.lo + leaves.hi)
    lo, hi = result.mechanism.bounds
    step = float(result.precisions.min())
    for region in result.regions:
        ok = (result.graph.certain[:, 0] == region.certain) & (result.table.status[:, 0] == IN)
        pts = centres[ok]
        pairs = [(pts[np.argmin(pts[:, 2])], pts[np.argmax(pts[:, 2])])]
        top, bottom = ok & (leaves.hi[:, 2] >= hi[2]), ok & (leaves.lo[:, 2] <= lo[2])
        seam = bool(top.any() and bottom.any())
        if seam:
            a = centres[np.flatnonzero(top)[0]]
            below = centres[bottom]
            b = below[np.argmin(np.linalg.norm(below[:, :2] - a[:2], axis=1))]
            pairs.append((a, b))
        for a, b in pairs:
            motion = plan_motion(result, [a, b])
            path = np.array([s["pose"] for s in motion["path"]])
            joints = np.array([s["joints"] for s in motion["path"]])
            assert np.abs(np.diff(path, axis=0)).max() <= step * (1 + 1e-9)
            assert np.abs(np.diff(joints, axis=0)).max() <= step * (1 + 1e-9)
            assert np.allclose(path[0], a)
            turns = (path[-1, 2] - b[2]) / (2 * np.pi)
            assert np.allclose(path[-1, :2], b[:2]) and abs(turns - round(turns)) < 1e-9
            valid, det = GridReference.evaluate(result.mechanism, path)
            assert valid.all() and (np.sign(det) == region.sign).all()
        if seam:
            # the short way round: through the seam, one turn from the pose asked
            assert np.abs(path[:, 2]).max() > np.pi and round(turns) == 1


def _joined_across_the_grid(result, ref, labels):
    """Pairs of the grid's components (of ``labels``) that one certified motion of
    the analysis joins, checked pose by pose on the grid's own formulas: each
    pose valid with det A of the region's sign, consecutive poses at most the
    precision apart. A grid splits a region at a neck thinner than its spacing;
    such a motion shows the split is the grid's."""
    step = float(result.precisions.min())
    rng = np.random.default_rng(0)
    # per component, a pose of it certainly in a region, per region
    held: dict[int, dict[str, np.ndarray]] = {}
    for label in labels:
        inside = ref.points[ref.labels == label]
        sample = inside[rng.choice(len(inside), min(len(inside), 400), replace=False)]
        for pose, point in zip(sample, result.locate(sample)["points"], strict=True):
            for rid, answer in point["regions"].items():
                if answer is True:
                    held.setdefault(label, {}).setdefault(rid, pose)
    joined = []
    for i, a in enumerate(labels):
        for b in labels[i + 1 :]:
            shared = set(held.get(a, {})) & set(held.get(b, {}))
            if not shared:
                continue
            rid = min(shared)
            pa, pb = held[a][rid], held[b][rid]
            answer = result.feasible([pa, pb])
            if answer["feasible"] is not True:
                continue
            motion = plan_motion(result, [pa, pb])
            path = np.array([s["pose"] for s in motion["path"]])
            valid, det = GridReference.evaluate(result.mechanism, path)
            sign = result.regions[answer["region"]].sign
            gaps = np.abs(np.diff(path, axis=0)).max(axis=1)
            if valid.all() and (np.sign(det) == sign).all() and (gaps <= step * (1 + 1e-9)).all():
                joined.append((a, b))
    return joined


def test_resolved_counts_agree_with_the_grid():
    """With the resolution on, at 1/64 of each span: the bounds always hold the
    number of large components of the grid, less those a checked motion joins (a
    grid may cut a region at a thin channel: it is a check, not the truth); where
    the count is proved it is that number, and every design is decided."""
    decided = 0
    for design in DESIGNS:
        m = _mechanism(design)
        ref = GridReference(m)
        sizes = np.bincount(ref.labels)[1:]
        large_labels = (np.flatnonzero(sizes > 200) + 1).tolist()
        large = len(large_labels)
        lo, hi = m.pose_box()
        result = analyze(m, precision=tuple(float(v) for v in (hi - lo) / 64))
        at_least, at_most = result.count
        if at_most is not None and at_most < large:
            # fewer regions than the grid's components: the analysis joins some
            merged = _joined_across_the_grid(result, ref, large_labels)
            parent = {label: label for label in large_labels}

            def find(x, parent=parent):
                while parent[x] != x:
                    x = parent[x]
                return x

            for a, b in merged:
                parent[find(a)] = find(b)
            large = len({find(label) for label in large_labels})
        assert at_least <= large and (at_most is None or large <= at_most), (design, large)
        decided += at_least == at_most
    assert decided == len(DESIGNS)
