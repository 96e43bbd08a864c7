"""Passive joint limits, obstacles and link collisions on the 3-RRR and the 3-RPR.

Checked against an independent pointwise reference (tests/three_legged_references.py:
closed-form legs, passive angles, segment-disk distances and crossings in
plain floats): certified sheets, ``locate``, planned motions, counts against a
brute-force grid of poses, and the interval enclosures of the linkage's points
and velocities on random boxes.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy import ndimage

from moveability import analyze, from_spec, plan_motion
from moveability.errors import SpecError
from moveability.hypertree.status import IN, OUT
from moveability.intervals import Interval
from moveability.limits import JointLimit
from moveability.mechanisms import ThreeRPR
from moveability.mechanisms.constraints import Constraints
from moveability.mechanisms.registry import load_spec
from moveability.mechanisms.three_rrr import ThreeRRR
from three_legged_references import (
    det_a,
    platform_joints,
    turned_within,
    valid,
    valid_postures,
)

#: the middle of the default 3-RRR's workspace (as in tests/mechanisms/test_three_rrr.py)
RRR_BOX = ((-3.0, -2.0), (3.0, 4.0))
RRR_ALL = {
    "passive_limits": {"C1": [-2.5, 2.5], "B3": [-2.8, 1.0]},
    "obstacles": [{"center": [-4.0, 6.0], "radius": 1.0}],
    "collisions": {"links": True},
}
RPR_DESIGN = ([[0, 0], [10, 0], [4, 8]], [[0, 0], [5, 0], [2, 4]], (4.0, 12.0))
RPR_ALL = {
    "passive_limits": {"B1": [-2.5, 2.5], "A2": [0.5, 3.0]},
    "obstacles": [{"center": [5.0, 3.0], "radius": 1.0}],
}
RPR_COLLISIONS = {"collisions": {"links": True}}

DESIGNS = {
    "rrr-all": ("3-RRR", RRR_ALL, 0.5),
    "rpr-all": ("3-RPR", RPR_ALL, (0.5, 0.5, 0.15)),
    "rpr-collisions": ("3-RPR", RPR_COLLISIONS, (0.75, 0.75, 0.2)),
}


def _plain(kind):
    if kind == "3-RRR":
        m = ThreeRRR.default()
        return ThreeRRR(m.base, m.platform, m.proximal, m.distal, m.limits, RRR_BOX)
    base, platform, (lo, hi) = RPR_DESIGN
    stroke = JointLimit(lo, hi, prismatic=True)
    return ThreeRPR(base, platform, (stroke, stroke, stroke))


def _mechanism(kind, extra):
    spec = load_spec({**_plain(kind).to_spec(), **extra})
    return _plain(kind).constrained(Constraints.from_spec(spec))


def _reference(extra):
    """The constraints as the reference takes them."""
    out = {}
    if "passive_limits" in extra:
        out["passive"] = {k: tuple(map(float, v)) for k, v in extra["passive_limits"].items()}
    if "obstacles" in extra:
        out["obstacles"] = [(o["center"], o["radius"]) for o in extra["obstacles"]]
    if "collisions" in extra:
        out["collisions"] = True
    return out


_CACHE: dict[str, object] = {}


def _analysis(name):
    if name not in _CACHE:
        kind, extra, precision = DESIGNS[name]
        _CACHE[name] = analyze(_mechanism(kind, extra), precision=precision, resolve=False)
    return _CACHE[name]


# ------------------------------------------------------------------ the spec


@pytest.mark.parametrize(
    ("kind", "passive", "unknown"),
    [("3-RRR", ("C1", "C2", "C3", "B1", "B2", "B3"), ("B4", "A1")),
     ("3-RPR", ("A1", "A2", "A3", "B1", "B2", "B3"), ("B4", "C1"))],
)  # fmt: skip
def test_spec_tables_round_trip_and_errors_name_the_key(kind, passive, unknown):
    plain = _plain(kind).to_spec()
    extra = {
        "passive_limits": {name: ["-pi/2", "pi/2"] for name in passive},
        "obstacles": [{"center": [1.0, -2.0], "radius": 0.5}],
        "collisions": {"links": True},
    }
    m = from_spec({**plain, **extra})
    assert set(m.restrictions.passive) == set(passive)
    assert m.restrictions.obstacles[0].radius == 0.5 and m.restrictions.collisions
    again = from_spec(m.to_spec())
    assert again.restrictions == m.restrictions
    assert again.to_spec() == m.to_spec()
    assert "restrictions=" in repr(m) and "restrictions=" not in repr(from_spec(plain))
    for name in unknown:
        with pytest.raises(SpecError, match=rf"invalid passive_limits\.{name}"):
            from_spec({**plain, "passive_limits": {name: [0, 1]}})
    with pytest.raises(SpecError, match=r"invalid obstacles\[0\]\.radius"):
        from_spec({**plain, "obstacles": [{"center": [0, 0], "radius": -1}]})
    with pytest.raises(SpecError, match=r"invalid collisions\.links"):
        from_spec({**plain, "collisions": {"links": "yes"}})


def test_the_report_shows_the_tables_as_toml_that_reads_back():
    import tomllib

    from moveability.output.report import spec_toml

    m = _mechanism("3-RPR", {**RPR_ALL, **RPR_COLLISIONS})
    text = spec_toml(m)
    assert "[passive_limits]" in text and "[[obstacles]]" in text
    assert from_spec(tomllib.loads(text)).restrictions == m.restrictions


# ------------------------------------------------------- interval enclosures


def _layout(m, pose, joints):
    """The named points of one configuration, in plain floats."""
    out = {}
    for i, b in enumerate(platform_joints(m.platform, pose[None])):
        a = np.asarray(m.base[i], dtype=float)
        out[f"A{i + 1}"] = a
        out[f"B{i + 1}"] = b[0]
        if m.name == "3-RRR":
            out[f"C{i + 1}"] = a + m.proximal[i] * np.array([np.cos(joints[i]), np.sin(joints[i])])
    return out


@pytest.mark.parametrize("kind", ["3-RRR", "3-RPR"])
def test_point_and_velocity_enclosures_hold_sampled_values(kind):
    m = _plain(kind)
    rng = np.random.default_rng(11)
    lo0, hi0 = m.pose_box()
    checked = 0
    for _ in range(150):
        centre = rng.uniform(lo0, hi0)
        half = rng.uniform(0.0, 0.3, 3) * rng.choice([0.0, 1.0], 3, p=[0.1, 0.9])
        q_mid, q_half = rng.uniform(-np.pi, np.pi, 3), rng.uniform(0.0, 0.3, 3)
        v_mid, v_half = rng.normal(size=3), rng.uniform(0.0, 0.5, 3)
        r_mid, r_half = rng.normal(size=3), rng.uniform(0.0, 0.5, 3)

        def box(mid, half):
            return [
                Interval(np.array([c - h]), np.array([c + h]))
                for c, h in zip(mid, half, strict=True)
            ]

        lo, hi = (centre - half)[None], (centre + half)[None]
        angles = box(q_mid, q_half)
        points = m.linkage_points(lo, hi, angles)
        moving = m.linkage_velocities(lo, hi, angles, box(v_mid, v_half), box(r_mid, r_half))
        assert set(points) == set(moving) >= {n for link in m.linkage.links for n in link}
        for _ in range(10):
            pose = centre + rng.uniform(-1, 1, 3) * half
            joints = q_mid + rng.uniform(-1, 1, 3) * q_half
            velocity = v_mid + rng.uniform(-1, 1, 3) * v_half
            rates = r_mid + rng.uniform(-1, 1, 3) * r_half
            here = _layout(m, pose, joints)
            e = 1e-6
            ahead = _layout(m, pose + e * velocity, joints + e * rates)
            behind = _layout(m, pose - e * velocity, joints - e * rates)
            for name, xy in here.items():
                for axis in range(2):
                    enclosure = points[name][axis]
                    assert enclosure.lo[0] <= xy[axis] <= enclosure.hi[0], (name, axis)
                    rate = (ahead[name][axis] - behind[name][axis]) / (2 * e)
                    enclosure = moving[name][axis]
                    # the central difference is exact up to O(e^2) and rounding
                    assert enclosure.lo[0] - 1e-6 <= rate <= enclosure.hi[0] + 1e-6, (name, axis)
                    checked += 1
    assert checked > 10000


# -------------------------------------------------------- certified answers


@pytest.mark.parametrize("name", list(DESIGNS))
def test_certified_sheets_agree_with_pointwise_constraints(name):
    """Every configuration sampled in a node certified IN satisfies every
    constraint (with the node's sign of det A), none in a node certified OUT does."""
    result = _analysis(name)
    m = result.mechanism
    extra = _reference(DESIGNS[name][1])
    leaves, table = result.tree.leaves(), result.table
    rng = np.random.default_rng(3)
    checked = {"in": 0, "out": 0}
    certified = np.argwhere(table.status == IN)
    empty = np.argwhere(table.status == OUT)
    empty = empty[rng.choice(len(empty), size=min(400, len(empty)), replace=False)]
    for (leaf, p), count in itertools.chain(
        zip(certified, itertools.repeat(max(4, 800 // max(len(certified), 1)))),
        zip(empty, itertools.repeat(2)),
    ):
        poses = rng.uniform(leaves.lo[leaf], leaves.hi[leaf], size=(count, 3))
        ok, joints = valid_postures(m, poses, **extra)
        if table.status[leaf, p] == IN:
            assert ok[:, p].all(), (leaf, p, poses[~ok[:, p]])
            with np.errstate(invalid="ignore"):
                signs = np.sign(det_a(m, poses, joints[:, p]))
            assert (signs == table.sign[leaf, p]).all(), (leaf, p)
            checked["in"] += count
        else:
            assert not ok[:, p].any(), (leaf, p, poses[ok[:, p]])
            checked["out"] += count
    assert checked["in"] >= 300 and checked["out"] >= 300, checked


@pytest.mark.parametrize("name", list(DESIGNS))
def test_locate_agrees_with_pointwise_constraints(name):
    result = _analysis(name)
    m = result.mechanism
    extra = _reference(DESIGNS[name][1])
    lo, hi = m.pose_box()
    rng = np.random.default_rng(7)
    poses = rng.uniform(lo, hi, size=(1000, 3))
    answers = result.locate(poses)["points"]
    moves = np.array([[0, 0, 0]] + [s * row for row in np.eye(3) for s in (1e-3, -1e-3)])
    checked = {True: 0, False: 0}
    for pose, answer in zip(poses, answers, strict=True):
        if answer["workspace"] is None:
            continue
        ok, _ = valid_postures(m, pose[None] + moves, **extra)
        verdicts = set(ok.any(axis=1).tolist())
        if len(verdicts) == 1:  # stable under small moves
            assert answer["workspace"] is verdicts.pop(), pose
            checked[answer["workspace"]] += 1
    assert checked[True] > 20 and checked[False] > 20, checked


@pytest.mark.parametrize("name", ["rrr-all", "rpr-all"])
def test_planned_motions_satisfy_every_constraint(name):
    result = _analysis(name)
    m = result.mechanism
    extra = _reference(DESIGNS[name][1])
    region = max(result.regions, key=lambda r: r.area[0])
    sure = np.flatnonzero(result.region_cells(region.id)[0])
    leaves = result.tree.leaves()
    centres = 0.5 * (leaves.lo[sure] + leaves.hi[sure])
    ends = centres[[np.argmin(centres[:, 0]), np.argmax(centres[:, 0])]]
    motion = plan_motion(result, ends)
    assert motion["feasible"] and len(motion["path"]) > 2
    limits = [(None, None) if lim.periodic else (lim.lo, lim.hi) for lim in m.limits]
    for conf in motion["path"]:
        pose, joints = np.asarray(conf["pose"]), np.asarray(conf["joints"], dtype=float)
        points = _layout(m, pose, joints)
        for i in "123":
            if m.name == "3-RRR":
                length = np.hypot(*(points[f"B{i}"] - points[f"C{i}"]))
                assert abs(length - m.distal[int(i) - 1]) < 1e-6
            else:
                length = np.hypot(*(points[f"B{i}"] - points[f"A{i}"]))
                assert abs(length - joints[int(i) - 1]) < 1e-6
        rows = {k: v[None] for k, v in points.items()}
        assert valid(m.name, limits, joints[None], rows, **extra)[0], conf


# ------------------------------------------------------------------- counts


def _grid_components(m, extra, n):
    """Components of the valid configurations on a grid of poses (phi periodic), per
    posture and sign of det A (26-connected): how many, and how many of at least
    ``n[3]`` cells. Regions joined through serial singularities (3-RRR) count once
    per posture here, so the grid counts at least every region it resolves."""
    lo, hi = m.bounds
    axes = [lo[i] + (np.arange(n[i]) + 0.5) * (hi[i] - lo[i]) / n[i] for i in range(3)]
    poses = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    ok, joints = valid_postures(m, poses, **extra)
    every = large = 0
    for p in range(ok.shape[1]):
        with np.errstate(invalid="ignore"):
            sign = np.sign(det_a(m, poses, joints[:, p]))
        for s in (1, -1):
            mask = (ok[:, p] & (sign == s)).reshape(n[:3])
            labels, count = ndimage.label(mask, structure=np.ones((3, 3, 3)))
            parent = list(range(count + 1))

            def find(x, parent=parent):
                while parent[x] != x:
                    parent[x] = parent[parent[x]]
                    x = parent[x]
                return x

            # glue across the seam of phi, 26-connected (no wrap in x, y)
            first = np.pad(labels[:, :, 0], 1)
            last = labels[:, :, -1]
            for u, v in itertools.product(range(3), repeat=2):
                across = first[u : u + n[0], v : v + n[1]]
                for x, y in zip(across.ravel(), last.ravel(), strict=True):
                    if x and y:
                        parent[find(x)] = find(y)
            sizes: dict[int, int] = {}
            for lab, size in enumerate(np.bincount(labels.ravel())[1:], start=1):
                root = find(lab)
                sizes[root] = sizes.get(root, 0) + int(size)
            every += len(sizes)
            large += sum(size >= n[3] for size in sizes.values())
    return every, large


@pytest.mark.parametrize("name", list(DESIGNS))
def test_counts_do_not_contradict_a_grid_of_poses(name):
    result = _analysis(name)
    kind, extra, _ = DESIGNS[name]
    every, large = _grid_components(result.mechanism, _reference(extra), (48, 48, 64, 200))
    at_least, at_most = result.count
    assert 1 <= at_least <= every
    if kind == "3-RPR" and at_most is not None:
        # one posture: each large grid component lies in one region of its own
        assert at_most >= large


def test_no_upper_bound_without_flows():
    """Valid configurations exist: the count may not be bounded by 0 (the 3-RRR's
    legs give no flows, so its uncertified nodes stay open)."""
    m = _mechanism("3-RRR", {"passive_limits": {"B2": [0.5, 3.0]}})
    poses = np.random.default_rng(0).uniform(*m.pose_box(), size=(200, 3))
    ok, _ = valid_postures(m, poses, passive={"B2": (0.5, 3.0)})
    assert ok.any()  # valid configurations exist
    _, at_most = analyze(m, precision=0.75, resolve=False).count
    assert at_most is None or at_most >= 1


def test_postures_are_numbered_alike():
    """The reference's postures (branch 0: the platform joint on the right of A_i
    C_i) are the library's, joint for joint."""
    m = _plain("3-RRR")
    poses = np.random.default_rng(2).uniform(*m.pose_box(), size=(300, 3))
    _, joints = valid_postures(m, poses)
    ours = m.joint_angles(poses)
    both = np.isfinite(joints) & np.isfinite(ours)
    assert (np.isfinite(joints) == np.isfinite(ours)).all() and both.any()
    assert np.abs(np.angle(np.exp(1j * (joints[both] - ours[both])))).max() < 1e-9
    assert list(itertools.product((0, 1), repeat=3)) == [tuple(b) for b in m.postures]


def test_the_readme_example():
    """examples/three-rpr-passive.toml: the README's first pose is a valid
    configuration, the second only of the plain 3-RPR (two links cross)."""
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "examples" / "three-rpr-passive.toml"
    m = from_spec(path)
    assert m.name == "3-RPR" and m.restrictions.collisions
    extra = _reference(load_spec(path))
    poses = np.array([[5.3, 11.5, 0.27], [12.9, 0.64, 2.7]])
    assert valid_postures(m, poses, **extra)[0][:, 0].tolist() == [True, False]
    assert valid_postures(m, poses)[0][:, 0].tolist() == [True, True]
    answers = analyze(m, precision=(1.5, 1.5, 0.2), resolve=False).locate(poses)["points"]
    assert [a["workspace"] for a in answers] == [True, False]


def test_reference_meets_revolute_limits_modulo_a_turn():
    """The pointwise reference takes a revolute joint's angle modulo a turn, as the
    library's limits do: limits that cross pi (and the passive ones) included."""
    rng = np.random.default_rng(5)
    angles = rng.uniform(-3 * np.pi, 3 * np.pi, 4000)
    for lo, hi in [(1.83, 5.59), (-np.pi, np.pi), (-1.0, 2.0), (3.0, 3.5), (-4.0, -2.5)]:
        expected = JointLimit(lo, hi).contains(angles)
        assert np.array_equal(turned_within(angles, lo, hi), expected), (lo, hi)
