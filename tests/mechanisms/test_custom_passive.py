"""Passive joint limits of user-defined mechanisms: the paper's five-bar written as a
custom spec with a limit on the passive angle at C (from link AC to link CP) against
the built-in five-bar with ``[passive_limits] C``, and against an independent
closed-form reference; the spec's errors."""

from __future__ import annotations

import copy
import json
import pathlib

import numpy as np
import pytest
from click.testing import CliRunner

from moveability import analyze, plan_motion
from moveability.analysis.sheets import classify_sheets
from moveability.cli import main
from moveability.errors import SpecError
from moveability.hypertree.status import IN, OUT
from moveability.intervals import Interval
from moveability.limits import INSIDE, OUTSIDE, STRADDLES, JointLimit
from moveability.mechanisms import FiveBar
from moveability.mechanisms import expressions as ex
from moveability.mechanisms.constraints import Constraints
from moveability.mechanisms.custom import CustomMechanism, compile_expression, modular
from moveability.mechanisms.registry import from_spec, load_spec

L0, L1, L2, L3, L4 = 7.0, 8.0, 5.0, 8.0, 5.0
ANGLE_C = "atan2(y - L1*sin(t1), x - L1*cos(t1)) - t1"
PRECISION = 0.5
# two limits at C: one about 0, one across pi (the cut of atan2: wrap-around)
CASES = {"about-zero": (-1.0, 2.2), "across-pi": (2.0, 4.6)}


def custom_spec(limits=(-1.0, 2.2)) -> dict:
    return {
        "mechanism": "custom",
        "pose": ["x", "y"],
        "joints": ["t1", "t2"],
        "parameters": {"L0": L0, "L1": L1, "L2": L2, "L3": L3, "L4": L4},
        "legs": [
            {
                "joint": "t1",
                "constraint": "(x - L1*cos(t1))**2 + (y - L1*sin(t1))**2 - L2**2",
                "passive": {"C": {"angle": ANGLE_C, "limits": list(limits)}},
            },
            {
                "joint": "t2",
                "constraint": "(x - L0 - L3*cos(t2))**2 + (y - L3*sin(t2))**2 - L4**2",
            },
        ],
        "limits": {"t1": [0.0, "pi"], "t2": [0.0, "pi"]},
        "bounds": {"x": [-14.0, 22.0], "y": [-14.0, 14.0]},
    }


def built_in(limits) -> FiveBar:
    paper = FiveBar(L0, L1, L2, L3, L4, (JointLimit(0.0, np.pi), JointLimit(0.0, np.pi)))
    return paper.constrained(Constraints(passive={"C": JointLimit(*limits)}))


# ------------------------------------------------------- independent reference
def wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def reference_joint(points, base, proximal, distal, sign):
    """theta = atan2(P - base) + sign * alpha (law of cosines); NaN out of reach."""
    d = points - np.asarray(base)
    r = np.hypot(d[:, 0], d[:, 1])
    with np.errstate(invalid="ignore", divide="ignore"):
        c = (r**2 + proximal**2 - distal**2) / (2 * proximal * r)
        alpha = np.where(np.abs(c) <= 1.0, np.arccos(np.clip(c, -1, 1)), np.nan)
    return np.arctan2(d[:, 1], d[:, 0]) + sign * alpha


def reference_angle_c(points, t1):
    """From AC to CP, wrapped to (-pi, pi]."""
    cx, cy = L1 * np.cos(t1), L1 * np.sin(t1)
    return wrap(np.arctan2(points[:, 1] - cy, points[:, 0] - cx) - t1)


def in_range(angle, lo, hi):
    """Whether angles (any turn) lie in [lo, hi] modulo 2 pi."""
    return np.mod(np.asarray(angle) - lo, 2 * np.pi) <= hi - lo


def branch_signs(m):
    """The sign of alpha of each leg's branch b, fixed once against the reference."""
    rng = np.random.default_rng(3)
    pts = rng.uniform((-6.0, 2.0), (12.0, 11.0), (400, 2))
    q = m.joint_angles(pts)
    bases = [((0.0, 0.0), L1, L2), ((L0, 0.0), L3, L4)]
    signs = {}
    for i, (base, prox, dist) in enumerate(bases):
        for b in range(2):
            p = int(np.nonzero(m.postures[:, i] == b)[0][0])
            got = q[:, p, i]
            for s in (1.0, -1.0):
                ref = reference_joint(pts, base, prox, dist, s)
                ok = np.isfinite(got) & np.isfinite(ref)
                if ok.sum() > 100 and np.abs(wrap(got[ok] - ref[ok])).max() < 1e-9:
                    signs[i, b] = s
    assert len(signs) == 4, signs
    return signs


# ----------------------------------------------------------------- fixtures
@pytest.fixture(scope="module", params=list(CASES), ids=list(CASES))
def pair(request):
    limits = CASES[request.param]
    custom = CustomMechanism(custom_spec(limits))
    builtin = built_in(limits)
    return (
        limits,
        analyze(custom, PRECISION, resolve=False),
        analyze(builtin, PRECISION, resolve=False),
    )


# ---------------------------------------------------------- against the five-bar
def test_locate_agrees_with_the_built_in(pair):
    _, a, b = pair
    rng = np.random.default_rng(11)
    lo, hi = b.mechanism.bounds
    points = rng.uniform(lo, hi, (600, 2))
    la, lb = a.locate(points), b.locate(points)
    by_sign_a = {r.sign: str(r.id) for r in a.regions}
    by_sign_b = {r.sign: str(r.id) for r in b.regions}
    assert sorted(by_sign_a) == sorted(by_sign_b)
    agree = inside = 0
    for pa, pb in zip(la["points"], lb["points"], strict=True):
        if None not in (pa["workspace"], pb["workspace"]):
            assert pa["workspace"] == pb["workspace"]
            agree += 1
        for s in by_sign_a:
            answers = (pa["regions"][by_sign_a[s]], pb["regions"][by_sign_b[s]])
            if None not in answers:
                assert answers[0] == answers[1]
                agree += 1
                inside += answers[0]
    assert agree >= 1000, agree
    assert inside >= 100, inside


def test_the_limit_changes_the_answers(pair):
    """The passive limit bites: some poses of the plain five-bar's regions are left out."""
    limits, a, _ = pair
    plain = analyze(
        CustomMechanism(
            {
                **custom_spec(limits),
                "legs": [
                    {k: v for k, v in leg.items() if k != "passive"}
                    for leg in custom_spec()["legs"]
                ],
            }
        ),
        PRECISION,
        resolve=False,
    )
    assert sum(r.area[1] for r in a.regions) < sum(r.area[0] for r in plain.regions)


def test_counts_and_areas_agree_with_the_built_in(pair):
    _, a, b = pair
    assert a.count[0] == b.count[0]
    assert a.count[1] is None  # the custom legs give no flows: at most stays open
    for ra in a.regions:
        for rb in (r for r in b.regions if r.sign == ra.sign):
            assert ra.area[0] <= rb.area[1] and rb.area[0] <= ra.area[1]
    wa, wb = a.workspace["area"], b.workspace["area"]
    assert wa[0] <= wb[1] and wb[0] <= wa[1]


def test_planned_motions_keep_the_passive_limit(pair):
    """Motions planned in the largest region: every configuration keeps the passive
    angle at C within its limits (checked by the planner, and here by the reference)."""
    limits, a, _ = pair
    m = a.mechanism
    region = max(a.regions, key=lambda r: r.area[0])
    rng = np.random.default_rng(9)
    cand = rng.uniform(*m.bounds, (3000, 2))
    answers = a.locate(cand)["points"]
    inside = cand[[p["regions"][str(region.id)] is True for p in answers]]
    assert len(inside) >= 20
    configurations = 0
    for _ in range(3):
        motion = plan_motion(a, inside[rng.choice(len(inside), 2, replace=False)])
        poses = np.array([c["pose"] for c in motion["path"]])
        joints = np.array([c["joints"] for c in motion["path"]])
        assert np.abs(m.constraints(poses, joints)).max() <= 1e-9
        assert in_range(reference_angle_c(poses, joints[:, 0]), *limits).all()
        assert m.constraints_hold(poses, joints).all()
        configurations += len(poses)
    assert configurations >= 6


# --------------------------------------------------- against the reference
def _boxes(step):
    xs = np.arange(-14.0, 22.0, step)
    ys = np.arange(-14.0, 14.0, step)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    lo = np.stack([gx.ravel(), gy.ravel()], axis=1)
    return lo, lo + step


@pytest.mark.parametrize("case", list(CASES))
def test_certified_sheets_hold_pointwise(case):
    """Configurations sampled in sheets certified valid satisfy the passive limit (and
    the joint limits); those in sheets certified empty are not valid; those where the
    passive angle is certified outside its limits violate it."""
    lo_c, hi_c = CASES[case]
    m = CustomMechanism(custom_spec((lo_c, hi_c)))
    signs = branch_signs(m)
    lo, hi = _boxes(0.4)
    table = classify_sheets(m, lo, hi)
    rng = np.random.default_rng(5)
    samples = 6
    u = rng.uniform(0.0, 1.0, (lo.shape[0], samples, 2))
    pts = lo[:, None, :] + u * (hi - lo)[:, None, :]
    flat = pts.reshape(-1, 2)
    counts = {"in": 0, "out": 0, "inside": 0, "outside": 0, "out_by_passive": 0}
    for p, posture in enumerate(m.postures):
        t1 = reference_joint(flat, (0.0, 0.0), L1, L2, signs[0, posture[0]])
        t2 = reference_joint(flat, (L0, 0.0), L3, L4, signs[1, posture[1]])
        reach = np.isfinite(t1) & np.isfinite(t2)
        joints_ok = reach & in_range(t1, 0.0, np.pi) & in_range(t2, 0.0, np.pi)
        with np.errstate(invalid="ignore"):
            passive_ok = reach & in_range(reference_angle_c(flat, t1), lo_c, hi_c)
        valid = (joints_ok & passive_ok).reshape(-1, samples)
        passive_ok = passive_ok.reshape(-1, samples)
        reach = reach.reshape(-1, samples)
        # sheets certified valid: every sampled configuration valid
        certified = table.status[:, p] == IN
        assert valid[certified].all()
        counts["in"] += int(certified.sum())
        # certified empty: none valid
        empty = table.status[:, p] == OUT
        assert not valid[empty].any()
        counts["out"] += int(empty.sum())
        # the passive angle's own certificate, over the sheet's joint enclosures
        angles = [Interval(table.angles_lo[:, p, i], table.angles_hi[:, p, i]) for i in range(2)]
        codes = m.constraint_codes(lo, hi, angles, p, table.leg_status == 1)
        regular = table.leg_status[:, 0] == 1
        inside = (codes == INSIDE) & regular
        outside = (codes == OUTSIDE) & regular
        assert passive_ok[inside][reach[inside]].all()
        assert not passive_ok[outside][reach[outside]].any()
        counts["inside"] += int(inside.sum())
        counts["outside"] += int(outside.sum())
        counts["out_by_passive"] += int(
            (empty & outside & (table.leg_status == 1).all(axis=1)).sum()
        )
    assert counts["in"] >= 500, counts
    assert counts["out"] >= 500, counts
    assert counts["inside"] >= 500 and counts["outside"] >= 200, counts
    assert counts["out_by_passive"] >= 50, counts


@pytest.mark.parametrize("case", list(CASES))
def test_pointwise_check_matches_the_reference(case):
    """constraints_hold at configurations (planned motions, figures) against the
    reference angle, away from the stops by a hair."""
    lo_c, hi_c = CASES[case]
    m = CustomMechanism(custom_spec((lo_c, hi_c)))
    b = built_in((lo_c, hi_c))
    rng = np.random.default_rng(8)
    pts = rng.uniform((-14.0, -14.0), (22.0, 14.0), (4000, 2))
    q = m.joint_angles(pts)
    checked = 0
    for p in range(q.shape[1]):
        ok = np.isfinite(q[:, p]).all(axis=1)
        ref = reference_angle_c(pts[ok], q[ok, p, 0])
        margin = np.minimum(np.abs(wrap(ref - lo_c)), np.abs(wrap(ref - hi_c)))
        clear = margin > 1e-9
        holds = m.constraints_hold(pts[ok], q[ok, p])
        expect = in_range(ref, lo_c, hi_c)
        assert (holds[clear] == expect[clear]).all()
        # the built-in five-bar's check agrees (its joints named alike, in order)
        assert (b.constraints_hold(pts[ok], q[ok, p])[clear] == expect[clear]).all()
        checked += int(clear.sum())
    assert checked >= 3000


def test_sharpness_next_to_the_built_in():
    """Over small boxes and the same joint enclosures, the custom enclosure of the angle
    decides about as often as the built-in one, and never against it."""
    limits = CASES["across-pi"]
    m, b = CustomMechanism(custom_spec(limits)), built_in(limits)
    lo, hi = _boxes(0.25)
    table = classify_sheets(b, lo, hi)
    regular = (table.leg_status == 1).all(axis=1)
    open_a = open_b = 0
    for p in range(len(b.postures)):
        angles = [Interval(table.angles_lo[:, p, i], table.angles_hi[:, p, i]) for i in range(2)]
        ca = m.constraint_codes(lo, hi, angles, p, table.leg_status == 1)
        cb = b.constraint_codes(lo, hi, angles, p, table.leg_status == 1)
        assert ca is not None and cb is not None
        sure = (ca != STRADDLES) & (cb != STRADDLES)
        assert (ca[sure] == cb[sure]).all()
        open_a += int(((ca == STRADDLES) & regular).sum())
        open_b += int(((cb == STRADDLES) & regular).sum())
    assert open_a <= open_b, (open_a, open_b)


# ----------------------------------------------------------- atan2 up to turns
def test_atan2_turn_encloses_across_both_cuts():
    rng = np.random.default_rng(2)
    # boxes (y, x) about the x axis: many cross a cut of atan2
    c = np.stack([rng.uniform(-0.6, 0.1, 2000), rng.uniform(-3.0, 3.0, 2000)], axis=1)
    w = rng.uniform(0.0, 0.5, (2000, 2))
    y, x = Interval(c[:, 0], c[:, 0] + w[:, 0]), Interval(c[:, 1], c[:, 1] + w[:, 1])
    turn = ex.atan2_turn(y, x)
    plain = ex.atan2(y, x)
    s = rng.uniform(0.0, 1.0, (2000, 8, 2))
    ys = c[:, None, 0] + s[..., 0] * w[:, None, 0]
    xs = c[:, None, 1] + s[..., 1] * w[:, None, 1]
    true = np.arctan2(ys, xs)
    mid = 0.5 * (turn.lo + turn.hi)[:, None]
    shifted = true + 2 * np.pi * np.round((mid - true) / (2 * np.pi))
    assert ((shifted >= turn.lo[:, None]) & (shifted <= turn.hi[:, None])).all()
    cut = ~np.isfinite(plain.lo)
    assert cut.sum() > 300
    # across the negative x axis, away from the origin, the enclosure stays narrow
    away = cut & (x.hi < -0.5)
    assert away.sum() > 200
    assert (turn.hi - turn.lo)[away].max() < 1.0


def test_atan2_is_unwrapped_only_where_turns_do_not_matter():
    import sympy

    x, y, t = sympy.symbols("x y t", real=True)
    a = sympy.atan2(y, x)
    assert "atan2_turn" in str(modular(a - t))
    assert "atan2_turn" in str(modular(-2 * a + sympy.sin(a / 3)))
    assert "atan2_turn" not in str(modular(a / 2))
    assert "atan2_turn" not in str(modular(a**2))
    assert "atan2_turn" not in str(modular(x * a))
    # a half angle across the cut: never certified on the wrong side
    g = compile_expression(modular(a / 2), [x, y])
    box = g(Interval([-2.0], [-1.0]), Interval([-0.1], [0.1]))
    assert not np.isfinite(box.lo[0]) and not np.isfinite(box.hi[0])
    spec = custom_spec()
    spec["legs"][0]["passive"]["C"]["angle"] = f"({ANGLE_C})/2"
    m = CustomMechanism(spec)
    half = Interval(np.array([np.pi - 0.05]), np.array([np.pi + 0.05]))  # t1 near pi
    code = m.constraint_codes(np.array([[-14.0, -0.1]]), np.array([[-13.9, 0.1]]), [half, half])
    assert code is not None and code[0] == STRADDLES


# ------------------------------------------------------------------- the spec
def test_round_trip():
    spec = custom_spec(("-pi/3", "3*pi/4"))
    normal = load_spec(spec)
    assert normal["legs"][0]["passive"] == {
        "C": {"angle": ANGLE_C, "limits": [-np.pi / 3, 3 * np.pi / 4]}
    }
    assert "passive" not in normal["legs"][1]
    assert json.loads(json.dumps(normal)) == normal
    m = from_spec(spec)
    again = from_spec(m.to_spec())
    assert again.to_spec() == m.to_spec() == normal
    assert again.restrictions == m.restrictions
    assert not m.restrictions.empty and "C" in repr(m)
    lo, hi = _boxes(1.0)
    angles = [Interval(np.full(lo.shape[0], 0.5), np.full(lo.shape[0], 0.7))] * 2
    assert (m.constraint_codes(lo, hi, angles) == again.constraint_codes(lo, hi, angles)).all()
    # without passive angles: the paper's hypotheses
    plain = CustomMechanism(
        {**spec, "legs": [{k: v for k, v in leg.items() if k != "passive"} for leg in spec["legs"]]}
    )
    assert plain.restrictions.empty and plain.constraint_codes(lo, hi, angles) is None


def test_example_is_the_tested_design():
    example = pathlib.Path(__file__).parents[2] / "examples" / "five-bar-custom-passive.toml"
    assert load_spec(example) == load_spec(custom_spec(CASES["about-zero"]))


def test_custom_rates_are_refused_not_ignored():
    m = CustomMechanism(custom_spec())
    lo, hi = _boxes(4.0)
    angles = [Interval(np.zeros(lo.shape[0]), np.ones(lo.shape[0]))] * 2
    with pytest.raises(NotImplementedError):
        m.constraint_margins(lo, hi, angles)


def _bad(path, value):
    spec = custom_spec()
    target = spec
    for key in path[:-1]:
        target = target[key]
    if value is KeyError:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return spec


PASSIVE = ("legs", 0, "passive")
ERRORS = [
    (
        (*PASSIVE, "C", "angle"),
        "atan2(y - z, x) - t1",
        r"unknown symbol 'z' in legs\[0\]\.passive\.C\.angle",
    ),
    ((*PASSIVE, "C", "angle"), "atan2(y, x) - t2", r"legs\[0\]\.passive\.C\.angle.*t1 only"),
    ((*PASSIVE, "C", "angle"), "foo(x)", r"unknown function 'foo' in legs\[0\]\.passive\.C\.angle"),
    ((*PASSIVE, "C", "angle"), "atan2(y, (x)", r"legs\[0\]\.passive\.C\.angle"),
    ((*PASSIVE, "C", "angle"), 3.0, r"legs\[0\]\.passive\.C\.angle"),
    ((*PASSIVE, "C", "angle"), KeyError, r"legs\[0\]\.passive\.C\.angle"),
    ((*PASSIVE, "C", "limits"), [1.0, 0.5], r"legs\[0\]\.passive\.C\.limits"),
    ((*PASSIVE, "C", "limits"), [0.5], r"legs\[0\]\.passive\.C\.limits"),
    ((*PASSIVE, "C", "limits"), "pi", r"legs\[0\]\.passive\.C\.limits"),
    ((*PASSIVE, "C", "limits"), ["-pi", "2*pi"], r"legs\[0\]\.passive\.C\.limits"),
    ((*PASSIVE, "C", "limits"), [0.0, "2pi"], r"legs\[0\]\.passive\.C\.limits\[1\]"),
    ((*PASSIVE, "C", "limits"), KeyError, r"legs\[0\]\.passive\.C\.limits"),
    ((*PASSIVE, "C", "stop"), 1.0, r"legs\[0\]\.passive\.C\.stop"),
    ((*PASSIVE, "C"), [0.0, 1.0], r"legs\[0\]\.passive\.C"),
    (PASSIVE, [1.0], r"legs\[0\]\.passive"),
    (
        (*PASSIVE, "not a name"),
        {"angle": "t1", "limits": [0, 1]},
        r"legs\[0\]\.passive\.not a name",
    ),
    (
        ("legs", 1, "passive"),
        {"C": {"angle": "atan2(y, x - L0) - t2", "limits": [0, 1]}},
        r"legs\[1\]\.passive\.C.*not used before",
    ),
    (("passive_limits",), {"C": [0, 1]}, r"passive_limits.*legs\.passive"),
]


@pytest.mark.parametrize(("path", "value", "message"), ERRORS)
def test_spec_errors_name_the_key(path, value, message):
    with pytest.raises(SpecError, match=message) as info:
        load_spec(_bad(path, value))
    assert "\n" not in str(info.value)


def _toml_value(v):
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(v)


def _toml(spec: dict) -> str:
    """A custom spec written as TOML (the few shapes it uses)."""
    lines = [f"{k} = {_toml_value(spec[k])}" for k in ("mechanism", "pose", "joints")]
    for table in ("parameters", "limits", "bounds"):
        lines.append(f"[{table}]")
        lines += [f"{k} = {_toml_value(v)}" for k, v in spec[table].items()]
    for leg in spec["legs"]:
        lines.append("[[legs]]")
        lines += [f"{k} = {_toml_value(v)}" for k, v in leg.items() if k != "passive"]
        if "passive" in leg:
            lines.append("[legs.passive]")
            for name, item in leg["passive"].items():
                inner = ", ".join(f"{k} = {_toml_value(v)}" for k, v in item.items())
                lines.append(f"{name} = {{ {inner} }}")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(
    ("path", "value", "key"),
    [
        ((*PASSIVE, "C", "angle"), "atan2(y - z, x) - t1", "legs[0].passive.C.angle"),
        ((*PASSIVE, "C", "limits"), [1.0, 0.5], "legs[0].passive.C.limits"),
        (
            ("legs", 1, "passive"),
            {"C": {"angle": "atan2(y, x - L0) - t2", "limits": [0.0, 1.0]}},
            "legs[1].passive.C",
        ),
    ],
)
def test_cli_exits_2_naming_the_key(tmp_path, path, value, key):
    path_ = tmp_path / "spec.toml"
    path_.write_text(_toml(_bad(path, value)))
    result = CliRunner().invoke(main, ["regions", str(path_)])
    assert result.exit_code == 2, (result.exit_code, result.output)
    message = result.stderr
    assert message.startswith("Error: ") and message.count("\n") == 1, message
    assert key in message and "Traceback" not in message


def test_cli_reads_the_passive_table(tmp_path):
    path = tmp_path / "spec.toml"
    path.write_text(_toml(custom_spec()))
    result = CliRunner().invoke(main, ["regions", str(path), "-p", "1.0"])
    assert result.exit_code == 0, result.output
    assert copy.deepcopy(load_spec(path)) == load_spec(custom_spec())
