"""Generalized aspects (det A and det B of constant sign) against the joint space.

For a five-bar, an assembly mode s gives the pose P_s(q) on the set D of joint
vectors without parallel singularity; the generalized aspects are the
components of {q in D : both legs' serial terms non-zero} for each s, labelled
here on a grid of Q with scipy.ndimage, independently of the tree.
"""

import numpy as np
import pytest
from scipy import ndimage

from moveability import analyze
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar

N = 1000


def _reference(m):
    L0, L1, L2, L3, L4 = m.lengths
    lo = [lim.lo for lim in m.limits]
    hi = [lim.hi for lim in m.limits]
    c = [np.linspace(lo[i], hi[i], N + 1) for i in range(2)]
    c = [0.5 * (a[1:] + a[:-1]) for a in c]
    t1, t2 = np.meshgrid(*c, indexing="ij")
    C = np.stack([L1 * np.cos(t1), L1 * np.sin(t1)], -1)
    D = np.stack([L0 + L3 * np.cos(t2), L3 * np.sin(t2)], -1)
    d = D - C
    dist = np.linalg.norm(d, axis=-1)
    inside = (dist > abs(L2 - L4)) & (dist < L2 + L4)
    a = (L2**2 - L4**2 + dist**2) / (2 * dist)
    h = np.sqrt(np.maximum(L2**2 - a**2, 0.0))
    u = d / dist[..., None]
    perp = np.stack([-u[..., 1], u[..., 0]], -1)
    found = []
    for s in (1, -1):
        P = C + a[..., None] * u + s * h[..., None] * perp
        pc, pd = P - C, P - D
        det = pc[..., 0] * pd[..., 1] - pc[..., 1] * pd[..., 0]
        # branch 0 of a leg is theta + alpha: the elbow is clockwise of the base-pose line
        s1 = C[..., 0] * pc[..., 1] - C[..., 1] * pc[..., 0]
        db = D - np.array([L0, 0.0])
        s2 = db[..., 0] * pd[..., 1] - db[..., 1] * pd[..., 0]
        for b1 in (1, -1):
            for b2 in (1, -1):
                mask = inside & (np.sign(s1) == b1) & (np.sign(s2) == b2)
                labels, n = ndimage.label(mask)
                sizes = np.bincount(labels.ravel())[1:]
                for k in range(n):
                    if sizes[k] > 50:  # pieces of a few grid cells are artefacts
                        sign = int(np.sign(det[labels == k + 1].mean()))
                        found.append((sign, b1, b2))
    return found


def _posture_signs(name):
    """Posture '+-' as the signs of the legs' serial terms (branch 0 is '-')."""
    return tuple(-1 if ch == "+" else 1 for ch in name)


@pytest.mark.parametrize(
    ("lengths", "limit"),
    [
        ((7, 8, 5, 8, 5), (0.0, np.pi)),
        ((6, 5, 7, 5, 7), (0.0, np.pi)),
        # stops at +-pi split aspects that unlimited joints would join
        ((7, 8, 5, 8, 5), (-np.pi, np.pi)),
    ],
)
def test_aspects_match_the_joint_space(lengths, limit):
    joint = JointLimit(*limit)
    m = FiveBar(*lengths, limits=(joint, joint))
    ref = _reference(m)
    counts = set()
    for eps in (0.1, 0.05):
        result = analyze(m, precision=eps, generalized_aspects=True, resolve=eps == 0.1)
        counts.add(len(result.regions))
        found = sorted((r.sign, *_posture_signs(r.postures[0])) for r in result.regions)
        assert all(len(r.postures) == 1 for r in result.regions)
        assert found == sorted(ref)
    assert counts == {len(ref)}


def test_aspects_lie_inside_regions():
    joint = JointLimit(0.0, np.pi)
    m = FiveBar(limits=(joint, joint))
    # one tree for both (the plain pass): their nodes compare leaf by leaf
    regions = analyze(m, precision=0.1, resolve=False)
    aspects = analyze(m, precision=0.1, generalized_aspects=True, resolve=False)
    assert len(aspects.regions) > len(regions.regions)
    g_r, g_a = regions.graph, aspects.graph
    for aspect in aspects.regions:
        nodes = g_a.certain == aspect.certain
        # the certified sheets of an aspect are certified sheets of one region
        holders = {int(x) for x in np.unique(g_r.certain[nodes]) if x >= 0}
        owners = {r.id for r in regions.regions if r.certain in holders}
        assert len(owners) <= 1
        if aspect.area[0] > 1.0:
            assert owners, aspect
        assert all(regions.regions[o].sign == aspect.sign for o in owners)


def test_cli_generalized_aspects_flag():
    from click.testing import CliRunner

    from moveability.cli import main

    runner = CliRunner()
    spec = "examples/five-bar-paper.toml"
    plain = runner.invoke(main, ["regions", spec, "--precision", "0.1", "--json", "-"])
    aspects = runner.invoke(
        main, ["regions", spec, "--precision", "0.1", "--json", "-", "--generalized-aspects"]
    )
    assert plain.exit_code == aspects.exit_code == 0
    import json

    assert len(json.loads(plain.output)["regions"]) == 2
    data = json.loads(aspects.output)
    assert data["generalized_aspects"] is True and len(data["regions"]) == 9
