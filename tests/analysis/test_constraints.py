"""Passive joint limits, obstacles and link collisions (beyond the paper).

Checked against the counts Caro, Chablat, Goldsztejn, Ishii and Jermann (2014)
publish for a five-bar, and against an independent grid over the joint space
(tests/constraint_references.py) on further designs.
"""

from __future__ import annotations

import numpy as np
import pytest

from constraint_references import constrained, grid_count, pose_configurations
from moveability import analyze, from_spec, plan_motion
from moveability.errors import SpecError
from moveability.hypertree.status import IN, OUT
from moveability.intervals import Interval
from moveability.limits import INSIDE, OUTSIDE
from moveability.mechanisms.constraints import segment_codes, vector_angle

CARO = {
    "mechanism": "five-bar",
    "parameters": {"L0": 9, "L1": 8, "L2": 5, "L3": 5, "L4": 8},
    "limits": {"theta1": "unlimited", "theta2": "unlimited"},
}
MIRRORED = {**CARO, "parameters": {"L0": 9, "L1": 5, "L2": 8, "L3": 8, "L4": 5}}
PASSIVE = {"passive_limits": {"P": ["-pi/2", "pi/2"]}}
OBSTACLE = {"obstacles": [{"center": [4.5, 0.0], "radius": 1.0}]}
COLLISIONS = {"collisions": {"links": True}}


def _reference_kwargs(extra):
    kwargs = {}
    if "passive_limits" in extra:
        from moveability.spec import parse_angle

        kwargs["passive"] = {
            k: (parse_angle(v[0]), parse_angle(v[1])) for k, v in extra["passive_limits"].items()
        }
    if "obstacles" in extra:
        kwargs["obstacles"] = [(o["center"], o["radius"]) for o in extra["obstacles"]]
    if "collisions" in extra:
        kwargs["collisions"] = True
    return kwargs


def _lengths(spec):
    return tuple(float(spec["parameters"][k]) for k in ("L0", "L1", "L2", "L3", "L4"))


@pytest.mark.parametrize("base", [CARO, MIRRORED], ids=["caro", "mirrored"])
@pytest.mark.parametrize(
    ("extra", "published"),
    [({}, 10), (PASSIVE, 12), (COLLISIONS, 10)],
    ids=["plain", "passive-P", "collisions"],
)
def test_published_generalized_aspects(base, extra, published):
    spec = {**base, **extra}
    result = analyze(from_spec(spec), precision=0.2, generalized_aspects=True)
    at_least, at_most = result.count
    # the independent reference: components of the grid that grow with it
    reference, _ = grid_count(
        _lengths(spec), (None, None), 400, True, min_cells=100, **_reference_kwargs(extra)
    )
    assert reference == published
    assert (at_least, at_most) == (published, published)  # a definite count


@pytest.mark.parametrize("base", [CARO, MIRRORED], ids=["caro", "mirrored"])
def test_obstacle_aspects_find_the_small_ones(base):
    spec = {**base, **OBSTACLE}
    reference, _ = grid_count(
        _lengths(spec), (None, None), 400, True, min_cells=10, **_reference_kwargs(OBSTACLE)
    )
    # 20 large aspects and 8 small ones (their cells grow fourfold with the grid)
    assert reference == 28
    coarse = analyze(from_spec(spec), precision=0.2, generalized_aspects=True)
    assert 22 <= coarse.count[0] <= 28
    assert coarse.count[1] is None or coarse.count[1] >= 28
    # finer, every aspect is found and no other can hide: the count is definite
    assert analyze(from_spec(spec), precision=0.05, generalized_aspects=True).count == (28, 28)


GEOMETRIES = [
    # the paper's five-bar, [0, pi], with a passive limit at C and collisions
    ({"mechanism": "five-bar", "parameters": {"L0": 7, "L1": 8, "L2": 5, "L3": 8, "L4": 5},
      "limits": {"theta1": [0, "pi"], "theta2": [0, "pi"]},
      "passive_limits": {"C": [-2.5, 2.5]}, "collisions": {"links": True}}),
    # the paper's design turning freely, an obstacle above the base
    ({"mechanism": "five-bar", "parameters": {"L0": 7, "L1": 8, "L2": 5, "L3": 8, "L4": 5},
      "limits": {"theta1": "unlimited", "theta2": "unlimited"},
      "obstacles": [{"center": [3.5, 4.0], "radius": 1.5}]}),
    # equal links, a passive limit at P and an obstacle below
    ({"mechanism": "five-bar", "parameters": {"L0": 6, "L1": 5, "L2": 6, "L3": 5, "L4": 6},
      "limits": {"theta1": ["-pi", "pi"], "theta2": ["-pi", "pi"]},
      "passive_limits": {"P": [-2.0, 2.0]}, "obstacles": [{"center": [3.0, -3.0], "radius": 1.0}]}),
]  # fmt: skip


@pytest.mark.parametrize("spec", GEOMETRIES, ids=["paper-C-collisions", "obstacle", "equal-links"])
@pytest.mark.parametrize("aspects", [False, True], ids=["regions", "aspects"])
def test_counts_against_the_joint_space_grid(spec, aspects):
    mechanism = from_spec(spec)
    extra = {k: spec[k] for k in ("passive_limits", "obstacles", "collisions") if k in spec}
    limits = tuple(None if lim.periodic else (lim.lo, lim.hi) for lim in mechanism.limits)
    small, _ = grid_count(
        _lengths(spec), limits, 300, aspects, min_cells=30, **_reference_kwargs(extra)
    )
    every, _ = grid_count(
        _lengths(spec), limits, 300, aspects, min_cells=1, **_reference_kwargs(extra)
    )
    result = analyze(mechanism, precision=0.15, generalized_aspects=aspects)
    at_least, at_most = result.count
    # certified bounds hold the true count; the grid's large components are
    # true ones, and every true one shows on the grid unless smaller than a cell
    assert at_least <= every
    assert at_most is None or at_most >= small
    assert at_least >= 1
    if spec is GEOMETRIES[0]:
        # coarse enough to separate every component: the lower bound is the count
        assert at_least == small == (5 if aspects else 2)


@pytest.mark.parametrize("spec", [{**CARO, **PASSIVE, **OBSTACLE, **COLLISIONS}, *GEOMETRIES])
def test_locate_agrees_with_pointwise_constraints(spec):
    mechanism = from_spec(spec)
    extra = _reference_kwargs(
        {k: spec[k] for k in ("passive_limits", "obstacles", "collisions") if k in spec}
    )
    result = analyze(mechanism, precision=0.15)
    lo, hi = mechanism.pose_box()
    rng = np.random.default_rng(7)
    poses = rng.uniform(lo, hi, size=(400, 2))
    answers = result.locate(poses)["points"]
    checked = 0
    for pose, answer in zip(poses, answers, strict=True):
        if answer["workspace"] is None:
            continue
        # stable under small moves: the pointwise answer is the same around the pose
        verdicts = set()
        for dx, dy in ((0, 0), (1e-3, 0), (-1e-3, 0), (0, 1e-3), (0, -1e-3)):
            p = pose + np.array([dx, dy])
            found = False
            for t1, t2, mode in pose_configurations(_lengths(spec), p):
                within = all(
                    lim.contains(np.array([t]))[0]
                    for lim, t in zip(mechanism.limits, (t1, t2), strict=True)
                )
                if within and constrained(mode, **extra)[0]:
                    found = True
            verdicts.add(found)
        if len(verdicts) == 1:
            assert answer["workspace"] is verdicts.pop(), pose
            checked += 1
    assert checked > 200


def test_planned_motions_satisfy_every_constraint():
    spec = {**CARO, **PASSIVE, **OBSTACLE, **COLLISIONS}
    mechanism = from_spec(spec)
    result = analyze(mechanism, precision=0.1)
    region = max(result.regions, key=lambda r: r.area[0])
    sure = np.flatnonzero(result.region_cells(region.id)[0])
    leaves = result.tree.leaves()
    centres = 0.5 * (leaves.lo[sure] + leaves.hi[sure])
    points = centres[[np.argmin(centres[:, 0]), np.argmax(centres[:, 0])]]
    motion = plan_motion(result, points)
    extra = _reference_kwargs(spec)
    L0, L1, _, L3, _ = _lengths(spec)
    for conf in motion["path"]:
        t1, t2 = conf["joints"]
        mode = {
            "A": np.zeros(2), "B": np.array([L0, 0.0]),
            "C": np.array([[L1 * np.cos(t1), L1 * np.sin(t1)]]),
            "D": np.array([[L0 + L3 * np.cos(t2), L3 * np.sin(t2)]]),
            "P": np.array([conf["pose"]]), "valid": np.array([True]),
        }  # fmt: skip
        assert constrained(mode, **extra)[0], conf


@pytest.mark.parametrize(
    ("table", "key"),
    [
        ({"obstacles": [{"center": [0, 0], "radius": 1}, {"center": [1, 1], "radius": -1}]},
         "obstacles[1].radius"),
        ({"obstacles": [{"center": [0], "radius": 1}]}, "obstacles[0].center"),
        ({"obstacles": {"center": [0, 0], "radius": 1}}, "obstacles"),
        ({"passive_limits": {"P": ["pi/2", "-pi/2"]}}, "passive_limits.P"),
        ({"passive_limits": {"Q": [0, 1]}}, "passive_limits.Q"),
        ({"collisions": {"links": "yes"}}, "collisions.links"),
        ({"collisions": {"bodies": True}}, "collisions.bodies"),
    ],
)  # fmt: skip
def test_errors_name_the_key(table, key):
    with pytest.raises(SpecError, match=rf"invalid {key.replace('[', '.').replace(']', '.')}"):
        from_spec({**CARO, **table})


def test_tables_are_refused_where_they_do_not_apply():
    spec = {
        "mechanism": "biglide",
        "parameters": {"L1": 5, "L2": 4},
        "limits": {"rho1": [-6, 6], "rho2": [-6, 6]},
        "obstacles": [{"center": [0, 0], "radius": 1}],
    }
    with pytest.raises(SpecError, match="obstacles"):
        from_spec(spec)


def test_spec_round_trip_keeps_the_constraints():
    spec = {**CARO, **PASSIVE, **OBSTACLE, **COLLISIONS}
    mechanism = from_spec(spec)
    again = from_spec(mechanism.to_spec())
    assert again.restrictions == mechanism.restrictions
    assert not again.restrictions.empty


def test_interval_geometry_is_sound_on_random_boxes():
    rng = np.random.default_rng(1)
    for _ in range(200):
        centre = rng.uniform(-3, 3, size=(4, 2))
        half = rng.uniform(0, 0.3, size=(4, 2))
        boxes = [(Interval(np.array([c[0] - h[0]]), np.array([c[0] + h[0]])),
                  Interval(np.array([c[1] - h[1]]), np.array([c[1] + h[1]])))
                 for c, h in zip(centre, half, strict=True)]  # fmt: skip
        code = int(segment_codes(*boxes)[0])
        angle = vector_angle(boxes[0][0], boxes[0][1])
        for _ in range(20):
            pts = centre + rng.uniform(-1, 1, size=(4, 2)) * half
            a, b, c, d = pts

            def cross(u, v):
                return u[0] * v[1] - u[1] * v[0]

            o1, o2 = cross(b - a, c - a), cross(b - a, d - a)
            o3, o4 = cross(d - c, a - c), cross(d - c, b - c)
            crossing = o1 * o2 < 0 and o3 * o4 < 0
            if code == INSIDE:
                assert not crossing
            if code == OUTSIDE:
                assert crossing
            t = np.arctan2(a[1], a[0])
            assert any(angle.lo[0] <= t + k * 2 * np.pi <= angle.hi[0] for k in (-1, 0, 1))


def test_figures_draw_the_obstacles():
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.patches import Circle

    from moveability.output.plot import figure

    result = analyze(from_spec({**CARO, **OBSTACLE}), precision=0.3)
    fig = figure("regions", result)
    panels = [ax for ax in fig.axes if ax.get_xlabel().startswith("x")]
    assert len(panels) >= 3
    for ax in panels:
        circles = [p for p in ax.patches if isinstance(p, Circle) and p.get_hatch()]
        assert len(circles) == 1, ax.get_title()
        assert np.allclose(circles[0].center, (4.5, 0.0)) and circles[0].radius == 1.0


def test_report_shows_the_constraints_as_toml_that_reads_back():
    import tomllib

    from moveability.output.report import spec_toml

    mechanism = from_spec({**CARO, **PASSIVE, **OBSTACLE, **COLLISIONS})
    text = spec_toml(mechanism)
    assert 'P = ["-pi/2", "pi/2"]' in text and "[[obstacles]]" in text
    assert from_spec(tomllib.loads(text)).restrictions == mechanism.restrictions


SHEET_DESIGNS = [
    {**CARO, **COLLISIONS},
    {**CARO, **PASSIVE, **OBSTACLE},
    {**MIRRORED, **COLLISIONS, "passive_limits": {"C": [-2.5, 2.0]}},
    GEOMETRIES[0],
]


@pytest.mark.parametrize("spec", SHEET_DESIGNS, ids=["caro", "caro-all", "mirrored", "paper"])
def test_certified_sheets_agree_with_pointwise_constraints(spec):
    """Every configuration sampled in a certified node satisfies every constraint
    and none in a node certified empty does: the sides known from the branches
    and the pinched joints decide nodes, and must do so rightly."""
    mechanism = from_spec(spec)
    extra = _reference_kwargs(
        {k: spec[k] for k in ("passive_limits", "obstacles", "collisions") if k in spec}
    )
    result = analyze(mechanism, precision=0.2, resolve=False)
    leaves, table = result.tree.leaves(), result.table
    rng = np.random.default_rng(3)
    L0, L1, _, L3, _ = _lengths(spec)
    checked = {"in": 0, "out": 0}
    for leaf in rng.choice(len(leaves.lo), size=1500, replace=False):
        poses = rng.uniform(leaves.lo[leaf], leaves.hi[leaf], size=(6, 2))
        joints = mechanism.joint_angles(poses)
        for p in range(joints.shape[1]):
            status = table.status[leaf, p]
            if status not in (IN, OUT):
                continue
            t1, t2 = joints[:, p, 0], joints[:, p, 1]
            exists = np.isfinite(t1) & np.isfinite(t2)
            mode = {
                "A": np.zeros(2), "B": np.array([L0, 0.0]),
                "C": np.stack([L1 * np.cos(t1), L1 * np.sin(t1)], -1),
                "D": np.stack([L0 + L3 * np.cos(t2), L3 * np.sin(t2)], -1),
                "P": poses, "valid": exists,
            }  # fmt: skip
            within = exists.copy()
            for lim, t in zip(mechanism.limits, (t1, t2), strict=True):
                within[exists] &= lim.contains(t[exists])
            valid = within & constrained(mode, **extra)
            if status == IN:
                assert valid.all(), (leaf, p, poses[~valid])
                checked["in"] += 1
            else:
                assert not valid.any(), (leaf, p, poses[valid])
                checked["out"] += 1
    assert checked["in"] > 100 and checked["out"] > 100


def _apart(a, b, c, d):
    """Closed segments [a, b] and [c, d] (rows of points) share no point, up to 1e-12."""

    def distance(o, s, t):
        u = t - s
        k = np.clip(((o - s) * u).sum(-1) / (u * u).sum(-1), 0.0, 1.0)
        return np.hypot(*(s + k[..., None] * u - o).T)

    def cross(u, v):
        return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]

    crossing = (cross(b - a, c - a) * cross(b - a, d - a) < 0) & (
        cross(d - c, a - c) * cross(d - c, b - c) < 0
    )
    gap = np.minimum.reduce(
        [distance(a, c, d), distance(b, c, d), distance(c, a, b), distance(d, a, b)]
    )
    return ~crossing & (gap > 1e-12)


def test_links_kept_apart_stay_apart_along_the_motion():
    """Where :class:`ConstraintMargins` says a motion keeps two links that may touch
    apart, sampled configurations that start apart and move at velocities inside
    the enclosures stay apart while they stay in the box."""
    from moveability.mechanisms.constraints import ConstraintMargins, Constraints, Linkage

    linkage = Linkage(links=(("a", "b"), ("c", "d")), passive={})
    constraints = Constraints(collisions=True)
    rng = np.random.default_rng(5)
    kept_cases = 0
    for _ in range(3000):
        # two links near touching: d's end close to the segment [a, b]
        a, b = rng.uniform(-2, 2, size=(2, 2))
        c = rng.uniform(-2, 2, size=2)
        d = a + rng.uniform(0.1, 0.9) * (b - a) + rng.normal(0, 0.05, size=2)
        centre = np.stack([a, b, c, d])
        half = rng.uniform(0.005, 0.05, size=(4, 2))
        speed = rng.normal(0, 1, size=(4, 2))
        spread = rng.uniform(0, 0.3, size=(4, 2))

        def box(values, widths):
            return {
                name: (Interval(np.array([v[0] - w[0]]), np.array([v[0] + w[0]])),
                       Interval(np.array([v[1] - w[1]]), np.array([v[1] + w[1]])))
                for name, v, w in zip("abcd", values, widths, strict=True)
            }  # fmt: skip

        margins = ConstraintMargins(constraints, linkage, box(centre, half))
        if margins.codes[0] == INSIDE or not margins.kept(box(speed, spread))[0]:
            continue
        kept_cases += 1
        for _ in range(20):
            start = centre + rng.uniform(-1, 1, size=(4, 2)) * half
            if not _apart(*start[:, None, :])[0]:
                continue
            velocity = speed + rng.uniform(-1, 1, size=(4, 2)) * spread
            steps = np.linspace(0.0, 1.0, 200)[:, None, None]
            # the motion until the first point leaves its box
            safe = np.where(velocity == 0, 1.0, velocity)
            room = np.where(velocity > 0, centre + half - start, centre - half - start) / safe
            limit = np.min(np.where(velocity == 0, np.inf, room))
            path = start[None] + steps * limit * velocity[None]
            assert _apart(path[:, 0], path[:, 1], path[:, 2], path[:, 3]).all()
    assert kept_cases > 50


def _box(values, widths, names="abcd"):
    return {
        name: (Interval(np.array([v[0] - w[0]]), np.array([v[0] + w[0]])),
               Interval(np.array([v[1] - w[1]]), np.array([v[1] + w[1]])))
        for name, v, w in zip(names, values, widths, strict=True)
    }  # fmt: skip


@pytest.mark.parametrize("turning", [False, True], ids=["straight", "turning"])
def test_overlapping_links_nearly_along_one_line(turning):
    """Links nearly along one line and overlapping (order d < a < c < b, where the
    plain side tests all straddle): the codes agree with an exact test on
    sampled configurations, and a motion said to keep them apart does, also
    when one end turns about a centre at a joint's rate (:class:`Turning`)."""
    from moveability.limits import STRADDLES
    from moveability.mechanisms.constraints import (
        ConstraintMargins,
        Constraints,
        Linkage,
        Turning,
    )

    linkage = Linkage(links=(("a", "b"), ("c", "d")), passive={})
    constraints = Constraints(collisions=True)
    rng = np.random.default_rng(11)
    seen = {INSIDE: 0, OUTSIDE: 0, STRADDLES: 0}
    kept_cases = 0
    for _ in range(1500):
        angle = rng.uniform(-np.pi, np.pi)
        u = np.array([np.cos(angle), np.sin(angle)])
        n = np.array([-u[1], u[0]])
        along = np.array([0.0, 8.0, 3.0, -5.0]) + rng.normal(0, 0.3, size=4)
        across = rng.normal(0, 0.2, size=4)
        centre = along[:, None] * u + across[:, None] * n + rng.uniform(-3, 3, size=2)
        half = rng.uniform(0.002, 0.03, size=(4, 2))
        margins = ConstraintMargins(constraints, linkage, _box(centre, half))
        code = int(margins.codes[0])
        seen[code] += 1
        samples = centre + rng.uniform(-1, 1, size=(200, 4, 2)) * half
        apart = _apart(samples[:, 0], samples[:, 1], samples[:, 2], samples[:, 3])
        if code == INSIDE:
            assert apart.all()
        elif code == OUTSIDE:
            assert not apart.any()
        if code == INSIDE:
            continue
        speed = rng.normal(0, 1, size=(4, 2))
        spread = rng.uniform(0, 0.2, size=(4, 2))
        velocities = _box(speed, spread)
        pivot = centre[2] + rng.normal(0, 1.0, size=2)  # c turns about it when turning
        omega = (rng.normal(0, 1.0), rng.uniform(0, 0.2))
        if turning:
            lever = _box([centre[2] - pivot], [half[2]], names="c")["c"]
            rate = Interval(np.array([omega[0] - omega[1]]), np.array([omega[0] + omega[1]]))
            velocities["c"] = Turning(rate, lever)
        if not margins.kept(velocities)[0]:
            continue
        kept_cases += 1
        for _ in range(20):
            start = centre + rng.uniform(-1, 1, size=(4, 2)) * half
            if not _apart(*start[:, None, :])[0]:
                continue
            velocity = speed + rng.uniform(-1, 1, size=(4, 2)) * spread
            w = omega[0] + rng.uniform(-1, 1) * omega[1]
            path = [start]
            for _ in range(400):
                now = path[-1]
                step = 0.0005
                nxt = now + step * velocity
                if turning:
                    r = now[2] - pivot
                    nxt[2] = now[2] + step * w * np.array([-r[1], r[0]])
                if (np.abs(nxt - centre) > half).any():
                    break
                path.append(nxt)
            p = np.array(path)
            assert _apart(p[:, 0], p[:, 1], p[:, 2], p[:, 3]).all()
    # every kind of answer occurs, and some motions are kept
    assert seen[INSIDE] > 50 and seen[OUTSIDE] > 50 and seen[STRADDLES] > 50
    assert kept_cases > 20
