"""User-defined mechanisms: the five-bar written as constraints against the built-in
FiveBar, and the spec's errors."""

from __future__ import annotations

import copy
import json
import pathlib
import tomllib

import numpy as np
import pytest

from custom_specs import five_bar_spec
from moveability import analyze, plan_motion
from moveability.errors import SpecError
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar
from moveability.mechanisms.custom import CustomMechanism, normalise_custom_spec

EXAMPLE = pathlib.Path(__file__).parents[2] / "examples" / "five-bar-custom.toml"
PRECISION = 0.5


DESIGNS = [
    ((7.0, 8.0, 5.0, 8.0, 5.0), (0.0, "pi")),
    ((7.0, 8.0, 5.0, 8.0, 5.0), ("-pi", "pi")),
    ((6.0, 7.0, 4.0, 6.0, 5.5), (0.0, "pi")),
]


@pytest.fixture(scope="module", params=range(len(DESIGNS)), ids=["paper", "full-turn", "other"])
def pair(request):
    lengths, limits = DESIGNS[request.param]
    custom = CustomMechanism(five_bar_spec(lengths, limits))
    lim = tuple(
        JointLimit(*(np.pi if v == "pi" else -np.pi if v == "-pi" else v for v in limits))
        for _ in range(2)
    )
    builtin = FiveBar(*lengths, limits=lim)
    # the plain pass: both trees alike (the resolution refines where each is open)
    return analyze(custom, PRECISION, resolve=False), analyze(builtin, PRECISION, resolve=False)


def test_paper_design_meets_the_same_postures(pair):
    a, b = pair
    if a.mechanism.to_spec() == normalise_custom_spec(five_bar_spec()):
        for ra in a.regions:
            rb = next(r for r in b.regions if r.sign == ra.sign)
            # the built-in's det A enclosure is sharper where a leg folds: its
            # certified part may meet a posture more (each region of this design
            # meets all four, as a grid over the joint space shows)
            assert set(ra.postures) <= set(rb.postures)
            assert len(ra.postures) >= 3


def test_example_is_the_paper_design():
    with open(EXAMPLE, "rb") as stream:
        spec = tomllib.load(stream)
    assert normalise_custom_spec(spec) == normalise_custom_spec(five_bar_spec())


def test_same_regions_as_the_built_in_five_bar(pair):
    a, b = pair
    assert len(a.regions) == len(b.regions)
    signs_a = sorted(r.sign for r in a.regions)
    assert signs_a == sorted(r.sign for r in b.regions)
    assert len(set(signs_a)) == len(signs_a)  # one region per sign: match them by sign
    for ra in a.regions:
        rb = next(r for r in b.regions if r.sign == ra.sign)
        # the legs are written alike: branch 0 is theta + alpha in both. The postures
        # met in the certified parts depend on the resolution: one set holds the other
        pa, pb = set(ra.postures), set(rb.postures)
        assert pa <= pb or pb <= pa
        assert ra.area[0] <= rb.area[1] and rb.area[0] <= ra.area[1]
        if ra.equals_workspace is not None and rb.equals_workspace is not None:
            assert ra.equals_workspace == rb.equals_workspace
    wa, wb = a.workspace["area"], b.workspace["area"]
    assert wa[0] <= wb[1] and wb[0] <= wa[1]
    if a.n_connected is not None and b.n_connected is not None:
        assert a.n_connected == b.n_connected


def test_locate_never_contradicts_the_built_in(pair):
    a, b = pair
    rng = np.random.default_rng(7)
    lo, hi = b.mechanism.bounds
    points = rng.uniform(lo, hi, (300, 2))
    la, lb = a.locate(points), b.locate(points)
    by_sign_a = {r.sign: str(r.id) for r in a.regions}
    by_sign_b = {r.sign: str(r.id) for r in b.regions}
    decided = 0
    for pa, pb in zip(la["points"], lb["points"], strict=True):
        assert {pa["workspace"], pb["workspace"]} != {True, False}
        for s in by_sign_a:
            answers = {pa["regions"][by_sign_a[s]], pb["regions"][by_sign_b[s]]}
            assert answers != {True, False}
            decided += None not in answers
    assert decided > 200


def test_feasible_agrees_on_the_papers_example():
    a = analyze(CustomMechanism(five_bar_spec()), PRECISION)
    assert a.feasible([[-4.0, -1.0], [3.5, 1.5]])["feasible"] is False
    answer = a.feasible([[3.5, 9.0], [1.0, 6.0]])
    assert answer["feasible"] is True
    q = np.array(answer["postures"])
    pts = np.array([[3.5, 9.0], [1.0, 6.0]])
    assert np.abs(a.mechanism.constraints(pts, q)).max() < 1e-9


# ------------------------------------------------------------------- the spec
def test_normalised_spec_is_stable_and_json_ready():
    spec = normalise_custom_spec(five_bar_spec(limits=("-pi/2", "3*pi/4")))
    assert normalise_custom_spec(spec) == spec
    assert json.loads(json.dumps(spec)) == spec
    assert spec["limits"]["t1"] == [-np.pi / 2, 3 * np.pi / 4]
    m = CustomMechanism(spec)
    assert m.to_spec() == spec
    assert CustomMechanism(m.to_spec()).to_spec() == spec
    assert m.name == "custom" and m.periodic_axes == ()
    assert "CustomMechanism" in repr(m)


def test_closed_form_branches_are_used_and_checked():
    spec = five_bar_spec()
    spec["legs"][0]["branches"] = [
        "atan2(y, x) + acos_placeholder",  # replaced below
    ]
    spec["legs"][0]["branches"] = [
        "atan2(y, x) + (pi/2 - atan2((x**2 + y**2 + L1**2 - L2**2) / (2*L1*sqrt(x**2 + y**2)),"
        " sqrt(1 - ((x**2 + y**2 + L1**2 - L2**2) / (2*L1*sqrt(x**2 + y**2)))**2)))",
        "0.1",  # wrong: replaced by the numerical root
    ]
    m = CustomMechanism(spec)
    plain = CustomMechanism(five_bar_spec())
    p = np.random.default_rng(0).uniform(-12, 12, (200, 2))
    qa, qb = m.joint_angles(p), plain.joint_angles(p)
    assert (np.isfinite(qa) == np.isfinite(qb)).all()
    ok = np.isfinite(qa)
    assert np.abs(np.angle(np.exp(1j * (qa[ok] - qb[ok])))).max() < 1e-9


def test_periodic_pose_axis_and_prismatic_kind():
    spec = {
        "mechanism": "custom",
        "pose": ["x", "phi"],
        "periodic": ["phi"],
        "joints": ["d"],
        "legs": [{"joint": "d", "kind": "prismatic", "constraint": "x**2 + cos(phi)**2 - d**2"}],
        "limits": {"d": [1.0, 3.0]},
        "bounds": {"x": [-3, 3], "phi": ["-pi", "pi"]},
    }
    m = CustomMechanism(spec)
    assert m.periodic_axes == (1,) and m.limits[0].prismatic
    q = m.joint_angles(np.array([[2.0, 0.0]]))
    assert np.isclose(np.nanmax(q), np.sqrt(5.0))
    bad = copy.deepcopy(spec)
    bad["limits"]["d"] = "unlimited"
    with pytest.raises(SpecError, match=r"limits\.d"):
        normalise_custom_spec(bad)
    bad = copy.deepcopy(spec)
    bad["bounds"]["phi"] = [0, 3]
    with pytest.raises(SpecError, match=r"bounds\.phi"):
        normalise_custom_spec(bad)


def _with(path, value):
    spec = five_bar_spec()
    target = spec
    for key in path[:-1]:
        target = target[key]
    if value is KeyError:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return spec


@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        (("legs", 1, "constraint"), "(x - L0 - L3*cos(t2)**2", r"legs\[1\]\.constraint"),
        (
            ("legs", 0, "constraint"),
            "(x - z*cos(t1))**2 - L2**2",
            r"unknown symbol 'z' in legs\[0\]",
        ),
        (("legs", 0, "constraint"), "x ^ 2 + t1", r"legs\[0\]\.constraint.*\*\*"),
        (("legs", 0, "constraint"), "__import__('os').getcwd()", r"legs\[0\]\.constraint"),
        (("legs", 0, "constraint"), "x.real + t1", r"legs\[0\]\.constraint"),
        (("legs", 0, "constraint"), "foo(x) + t1", r"unknown function 'foo'"),
        (("legs", 0, "constraint"), "x**2 + y**2 - L2**2", r"legs\[0\]\.constraint.*involving t1"),
        (("legs", 0, "constraint"), "x + t1 + t2", r"legs\[0\]\.constraint"),
        (("legs", 1, "joint"), "t1", r"legs\[1\]\.joint"),
        (("limits", "t2"), KeyError, r"limits\.t2"),
        (("limits", "t2"), [1.0, 0.5], r"limits\.t2"),
        (("bounds", "x"), [3.0, -3.0], r"bounds\.x"),
        (("bounds", "y"), [0.0, float("inf")], r"bounds\.y"),
        (("parameters", "L1"), float("nan"), r"parameters\.L1"),
        (("pose",), ["x", "x"], r"pose\[1\]"),
        (("joints",), ["t1", "x"], r"joints\[1\]"),
        (("parameters", "sin"), 1.0, r"parameters\.sin"),
    ],
)
def test_spec_errors_name_the_key(path, value, message):
    with pytest.raises(SpecError, match=message):
        normalise_custom_spec(_with(path, value))


def test_a_constraint_without_second_derivative_names_its_key(monkeypatch):
    """``abs`` of an expression of the joint has no second derivative in it (sympy
    gives a Dirac delta): the error names the constraint and the derivative."""
    monkeypatch.setenv("MOVEABILITY_CACHE_DIR", "")
    spec = _with(("legs", 0, "constraint"), "abs(x - L1*cos(t1)) + (y - L1*sin(t1))**2 - L2")
    with pytest.raises(SpecError, match=r"legs\[0\]\.constraint.*d2F/dt1\^2"):
        CustomMechanism(spec)


def test_unknown_top_level_key():
    spec = five_bar_spec()
    spec["lengths"] = {}
    with pytest.raises(SpecError, match="lengths"):
        normalise_custom_spec(spec)


def test_planned_motion_changes_posture_through_a_user_defined_fold(pair):
    """Planning crosses the fold boxes of a user-defined leg along the certified axis
    (fold_anchor, fold_path): a motion through three poses of the largest region,
    every configuration checked against the constraints, the region's sign and the
    limits (by the planner, and again here)."""
    custom, _ = pair
    m = custom.mechanism
    region = max(custom.regions, key=lambda r: r.area[0])
    rng = np.random.default_rng(5)
    cand = rng.uniform(*m.bounds, (3000, 2))
    answers = custom.locate(cand)["points"]
    inside = cand[[a["regions"][str(region.id)] is True for a in answers]]
    changed = 0
    for _ in range(3):
        points = inside[rng.choice(len(inside), 3, replace=False)]
        motion = plan_motion(custom, points)
        poses = np.array([c["pose"] for c in motion["path"]])
        joints = np.array([c["joints"] for c in motion["path"]])
        assert np.abs(m.constraints(poses, joints)).max() <= 1e-9
        assert (np.sign(m.det_a(poses, joints)) == region.sign).all()
        assert np.linalg.norm(np.diff(poses, axis=0), axis=1).max() <= PRECISION + 1e-12
        changed += len({c["posture"] for c in motion["path"]}) > 1
    if len(region.postures) > 1:
        assert changed > 0


@pytest.mark.parametrize("name", ["five-bar-custom.toml", "delta-custom.toml", "three-rrr.toml"])
def test_det_a_of_every_posture_shares_the_legs_rows(name, monkeypatch):
    """``det_a_postures`` of mechanisms whose det A is the determinant of the legs'
    rows computes a leg's rows on a branch once for every posture that takes it:
    the enclosures of ``det_a_boxes`` posture by posture, bit for bit, from one
    ``a_row_boxes`` call over the boxes per leg and branch."""
    from moveability import load_spec
    from moveability.mechanisms import from_spec
    from moveability.mechanisms.constraint_leg import ConstraintLeg

    mechanism = from_spec(load_spec(EXAMPLE.parent / name))
    rng = np.random.default_rng(11)
    low, high = (np.asarray(b, dtype=float) for b in mechanism.bounds)
    span = high - low
    width = span * rng.uniform(1 / 100, 1 / 10, (400, 1))
    lo = low + (span - width) * rng.random((400, low.size))
    hi = lo + width
    angles = [list(leg.reach(lo, hi).branches) for leg in mechanism.legs]
    calls = []
    plain = ConstraintLeg.a_row_boxes

    def counted(self, *args):
        # the rows over the boxes (det A along the sheets also takes the rows at
        # the middles of the boxes where it applies, see sheet_det)
        if args[0] is lo:
            calls.append(self)
        return plain(self, *args)

    monkeypatch.setattr(ConstraintLeg, "a_row_boxes", counted)
    every = mechanism.det_a_postures(lo, hi, angles)
    used = {(i, int(b)) for row in mechanism.postures for i, b in enumerate(row)}
    assert len(calls) == len(used) < mechanism.postures.size
    finite = 0
    for p, row in enumerate(mechanism.postures):
        one = mechanism.det_a_boxes(lo, hi, [angles[i][b] for i, b in enumerate(row)], posture=p)
        assert np.array_equal(every[p].lo, one.lo, equal_nan=True)
        assert np.array_equal(every[p].hi, one.hi, equal_nan=True)
        finite += int(np.isfinite(one.lo).sum())
    assert finite > 100  # regular boxes among them: enclosures, not the whole line


def test_atan2_with_a_constant_second_argument():
    """sympy writes ``atan2(u, 3)`` as ``atan(u/3)``: the spec is accepted (the same
    angle, printed as ``atan2(u/3, 1)``) and the leg's roots are those of the
    constraint as written (here ``r1 = x - 1``)."""
    spec = {
        "mechanism": "custom",
        "pose": ["x", "y"],
        "joints": ["r1", "r2"],
        "legs": [
            {"joint": "r1", "kind": "prismatic", "constraint": "atan2(x - r1, 3) - atan2(1, 3)"},
            {"joint": "r2", "kind": "prismatic", "constraint": "(x - r2)**2 + y**2 - 4"},
        ],
        "limits": {"r1": [-10.0, 10.0], "r2": [-10.0, 10.0]},
        "bounds": {"x": [-5.0, 5.0], "y": [-3.0, 3.0]},
    }
    m = CustomMechanism(normalise_custom_spec(spec))
    points = np.array([[0.5, 0.2], [2.0, -1.0], [-4.0, 2.5]])
    roots = m.legs[0].angles(points)
    found = roots[np.isfinite(roots)]
    assert np.allclose(np.sort(found), np.sort(points[:, 0] - 1.0))
    result = analyze(spec, precision=1.0, resolve=False)
    assert result.count[0] >= 1
