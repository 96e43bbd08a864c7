"""Certified counts of regions: how often they are decided, and at what cost.

Draws designs at random with fixed seeds (one ``random_<family>(n, seed)``
function per family, near-degenerate designs included), analyses each with
:func:`moveability.analyze` at the family's precision and the default settings
(resolution on), prints a line per design as it goes, and at the end one table,
a line per kind of design::

    family | designs | count definite | all listed | N-conn decided | median s | max s

*count definite*: ``n_regions is not None``; *all listed*: the count is
definite and every counted region is listed (``len(regions) == count[1]``);
*N-conn decided*: ``n_connected is not None``; times are those of ``analyze``
alone, per design (kernels loaded and each kind analysed once coarsely
beforehand, untimed). Below the table, per kind, the counts left open
(``#index [at_least, at_most]``) and the definite counts with regions unlisted.

Families (``--families``, comma-separated; all by default) and their default
number of designs:

``five-bar`` (20)
    random five-bars (lengths 2..8, random limits, a quarter of the joints
    unlimited), precision 0.05;
``five-bar-near`` (24)
    near-degenerate five-bars, six kinds in turn: four equal links; L1 = L3 and
    L2 = L4; L1 = L2 (each with stops at 0, pi, +-pi/2 or none); a stop of
    theta1 exactly where the limit is tangent to the parallel singularity; a
    corner of the limits exactly on a parallel singularity; a corner exactly on
    a serial one; precision 0.05;
``biglide`` (15 + 15)
    ``n`` random biglides (a third with equal legs) and ``n`` near-degenerate
    ones whose strokes overlap the legs' reach by 1e-9 or less; precision 0.1;
``three-rpr`` (10)
    random 3-RPRs (base and platform triangles, strokes) at 1/64 of each span of
    ``pose_box()``;
``delta`` (10)
    random Deltas at 1/32 of each span;
``constrained`` (12)
    random five-bars with passive limits, obstacles and link collisions,
    precision 0.05;
``custom`` (12)
    the five-bar, the 3-RPR and the Delta in turn written as user-defined
    specs, each next to its built-in twin (same box) at the precision of its
    family; a pair shares its index;
``three-rrr`` (8)
    random 3-RRRs at 1/64 of each span (seconds per design).

Run: ``.venv/bin/python benchmarks/bench_counts.py [--n N] [--families a,b,...]
[--seed S] [--csv FILE]`` (all families at their defaults: about 8 minutes on
two cores). ``--n`` designs per family instead of the defaults, ``--seed``
replaces every family's seed, ``--csv`` writes one row per design: family (the
kind of design), design index, parameters (the spec, JSON), at_least, at_most,
n_listed, n_connected, seconds, leaves.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from moveability import analyze
from moveability.errors import MoveabilityError
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar, from_spec
from moveability.mechanisms.base import Mechanism

Precision = float | tuple[float, ...]

TWO_PI = 2.0 * math.pi


def _angle(value: float) -> float:
    """``value`` wrapped to [-pi, pi)."""
    return (value + math.pi) % TWO_PI - math.pi


def _window(rng: np.random.Generator, wide: float = 1.0) -> list[float]:
    """A random revolute limit ``[lo, hi]``, at least ``wide`` and less than a turn."""
    lo = float(np.round(rng.uniform(-math.pi, math.pi), 2))
    return [lo, lo + float(np.round(rng.uniform(wide, TWO_PI - 0.01), 2))]


def _limit(rng: np.random.Generator, unlimited: float = 0.25) -> list[float] | str:
    return "unlimited" if rng.random() < unlimited else _window(rng)


def _five_bar(lengths: Sequence[float], limits: Sequence[Any], **extra: Any) -> dict[str, Any]:
    return {
        "mechanism": "five-bar",
        "parameters": dict(zip(("L0", "L1", "L2", "L3", "L4"), map(float, lengths), strict=True)),
        "limits": {"theta1": limits[0], "theta2": limits[1]},
        **extra,
    }


def _spec(m: Mechanism) -> dict[str, Any]:
    spec: dict[str, Any] = m.to_spec()
    return spec


def _build(spec: dict[str, Any]) -> Mechanism | None:
    """The mechanism of ``spec``, or None when the spec is not a valid design."""
    try:
        return from_spec(spec)
    except ValueError:
        return None


# ------------------------------------------------------------------ five-bars
def random_five_bars(n: int, seed: int = 11) -> list[FiveBar]:
    """Lengths in 2..8 (0.1 steps), each joint unlimited one time in four, else
    a random window at least 1 rad wide."""
    rng = np.random.default_rng(seed)
    out: list[FiveBar] = []
    while len(out) < n:
        lengths = np.round(rng.uniform(2.0, 8.0, 5), 1)
        limits = []
        for _ in range(2):
            if rng.random() < 0.25:
                limits.append(JointLimit.unlimited())
            else:
                lo = float(np.round(rng.uniform(-np.pi, np.pi), 2))
                width = float(np.round(rng.uniform(1.0, 2 * np.pi - 0.01), 2))
                limits.append(JointLimit(lo, lo + width))
        L0, L1, L2, L3, L4 = (float(v) for v in lengths)
        try:
            out.append(FiveBar(L0, L1, L2, L3, L4, limits=(limits[0], limits[1])))
        except ValueError:
            continue
    return out


#: stops that a near-degenerate five-bar may take besides the computed ones
_STOPS = (
    [0.0, math.pi],
    [-math.pi, math.pi],
    [-math.pi, 0.0],
    [-math.pi / 2, math.pi / 2],
    [0.0, math.pi / 2],
    "unlimited",
)


def _stop_at(rng: np.random.Generator, angle: float) -> list[float]:
    """A limit with one end exactly at ``angle`` (wrapped), the other 0.5..5 rad away."""
    width = float(rng.uniform(0.5, 5.0))
    a = _angle(angle)
    return [a, a + width] if rng.random() < 0.5 else [a - width, a]


def _tangent_stop(lengths: Sequence[float], rng: np.random.Generator) -> tuple[float, float] | None:
    """A configuration (theta1, theta2) where the line theta1 = const is tangent
    to the parallel singularity in the joint space: |C - B| + L3 = L2 + L4 (D
    farthest from C: both distal links stretched in line) or
    |C - B| - L3 = +-|L2 - L4| (D nearest to C)."""
    L0, L1, L2, L3, L4 = lengths
    targets = [(L2 + L4 - L3, -1.0), (L3 + abs(L2 - L4), 1.0), (L3 - abs(L2 - L4), 1.0)]
    rng.shuffle(targets)
    for s, towards in targets:
        if s <= 0:
            continue
        c = (L0 * L0 + L1 * L1 - s * s) / (2.0 * L0 * L1)  # |C - B| = s
        if abs(c) <= 1.0:
            t1 = math.acos(c) * (1.0 if rng.random() < 0.5 else -1.0)
            # D on the line BC, towards C or away from it
            dx, dy = L1 * math.cos(t1) - L0, L1 * math.sin(t1)
            return t1, math.atan2(towards * dy, towards * dx)
    return None


def _singular_corner(
    lengths: Sequence[float], t1: float, rng: np.random.Generator, serial: bool
) -> float | None:
    """theta2 such that (t1, theta2) is a configuration on a singularity: P, C, D
    aligned (|C - D| = L2 + L4 or |L2 - L4|) or, with ``serial``, leg 1 stretched
    or folded (P on line AC at L1 +- L2 from A)."""
    L0, L1, L2, L3, L4 = lengths
    c = np.array([L1 * math.cos(t1), L1 * math.sin(t1)])
    b = np.array([L0, 0.0])
    if serial:
        for arm in rng.permutation([L1 + L2, L1 - L2]):
            p = c / L1 * arm
            d = float(np.hypot(*(p - b)))
            if d == 0.0:
                continue
            cos_ = (L3 * L3 + d * d - L4 * L4) / (2.0 * L3 * d)
            if abs(cos_) <= 1.0:
                towards = math.atan2(p[1] - b[1], p[0] - b[0])
                return towards + math.acos(cos_) * (1.0 if rng.random() < 0.5 else -1.0)
        return None
    r = float(np.hypot(*(c - b)))
    for span in rng.permutation([L2 + L4, abs(L2 - L4)]):
        if span == 0.0 or r == 0.0:
            continue
        cos_ = (r * r + L3 * L3 - span * span) / (2.0 * L3 * r)  # |C - D| = span
        if abs(cos_) <= 1.0:
            towards = math.atan2(c[1] - b[1], c[0] - b[0])
            return towards + math.acos(cos_) * (1.0 if rng.random() < 0.5 else -1.0)
    return None


def random_near_five_bars(n: int, seed: int = 13) -> list[Mechanism]:
    """Near-degenerate five-bars, six kinds in turn: all four links equal; L1 = L3
    and L2 = L4; L1 = L2 (a leg folds onto its base joint), each with stops at
    0, pi, +-pi/2 or none; a stop of theta1 exactly where the limit is tangent
    to the parallel singularity; a corner of the limits exactly on a parallel
    singularity; a corner exactly on a serial singularity (leg 1 stretched or
    folded)."""
    rng = np.random.default_rng(seed)
    out: list[Mechanism] = []
    while len(out) < n:
        kind = len(out) % 6
        a, b, c, d = (float(v) for v in np.round(rng.uniform(2.0, 8.0, 4), 1))
        L0 = float(np.round(rng.uniform(1.0, 10.0), 1))
        if kind == 0:
            lengths = [L0, a, a, a, a]
        elif kind == 1:
            lengths = [L0, a, b, a, b]
        else:
            lengths = [L0, a, a if kind == 2 else b, c, d]
        limits: list[Any]
        if kind < 3:
            limits = [_STOPS[int(rng.integers(len(_STOPS)))] for _ in range(2)]
        elif kind == 3:
            tangent = _tangent_stop(lengths, rng)
            if tangent is None:
                continue
            t1, t2 = tangent
            # theta2's window holds the point of tangency
            t2 = _angle(t2)
            around = [t2 - float(rng.uniform(0.3, 2.5)), t2 + float(rng.uniform(0.3, 2.5))]
            limits = [_stop_at(rng, t1), "unlimited" if rng.random() < 0.3 else around]
        else:
            t1 = float(np.round(rng.uniform(-math.pi, math.pi), 2))
            corner = _singular_corner(lengths, t1, rng, serial=kind == 5)
            if corner is None:
                continue
            # (t1, corner) is a corner of the limits whichever end each stop is
            limits = [_stop_at(rng, t1), _stop_at(rng, corner)]
        m = _build(_five_bar(lengths, limits))
        if m is not None:
            out.append(m)
    return out


def random_constrained_five_bars(n: int, seed: int = 17) -> list[Mechanism]:
    """Random five-bars (lengths 2..8) with, each one time in two (at least one of
    them): a passive limit on P, C or D (a window of 1.5..5 rad), one or two
    obstacles (disks of radius 0.3..1.5 within the legs' reach), link collisions."""
    rng = np.random.default_rng(seed)
    out: list[Mechanism] = []
    while len(out) < n:
        lengths = [float(v) for v in np.round(rng.uniform(2.0, 8.0, 5), 1)]
        limits = [_limit(rng), _limit(rng)]
        picks = rng.random(3) < 0.5
        if not picks.any():
            picks[int(rng.integers(3))] = True
        extra: dict[str, Any] = {}
        if picks[0]:
            joint = str(rng.choice(["P", "C", "D"]))
            lo = float(np.round(rng.uniform(-math.pi, 0.0), 2))
            extra["passive_limits"] = {joint: [lo, lo + float(np.round(rng.uniform(1.5, 5.0), 2))]}
        if picks[1]:
            reach = max(lengths[1] + lengths[2], lengths[3] + lengths[4])
            extra["obstacles"] = [
                {
                    "center": [
                        float(np.round(rng.uniform(-0.5 * reach, lengths[0] + 0.5 * reach), 1)),
                        float(np.round(rng.uniform(-0.7 * reach, 0.7 * reach), 1)),
                    ],
                    "radius": float(np.round(rng.uniform(0.3, 1.5), 1)),
                }
                for _ in range(int(rng.integers(1, 3)))
            ]
        if picks[2]:
            extra["collisions"] = {"links": True}
        m = _build(_five_bar(lengths, limits, **extra))
        if m is not None:
            out.append(m)
    return out


# ------------------------------------------------------------------ biglides
def _biglide(lengths: Sequence[float], strokes: Sequence[Sequence[float]]) -> dict[str, Any]:
    return {
        "mechanism": "biglide",
        "parameters": {"L1": float(lengths[0]), "L2": float(lengths[1])},
        "limits": {"rho1": list(strokes[0]), "rho2": list(strokes[1])},
    }


def _biglide_legs(rng: np.random.Generator, equal: bool) -> list[float]:
    """Two leg lengths in 2..7 (one decimal), the second equal to the first if asked."""
    lengths = [float(v) for v in np.round(rng.uniform(2.0, 7.0, 2), 1)]
    if equal:
        lengths[1] = lengths[0]
    return lengths


def random_biglides(n: int, seed: int = 5) -> list[Mechanism]:
    """Legs 2..7 (a third equal), strokes 0.5..10 long starting in -8..6."""
    rng = np.random.default_rng(seed)
    out: list[Mechanism] = []
    while len(out) < n:
        lengths = _biglide_legs(rng, equal=len(out) % 3 == 0)
        strokes = []
        for _ in range(2):
            lo = float(np.round(rng.uniform(-8.0, 6.0), 1))
            strokes.append([lo, lo + float(np.round(rng.uniform(0.5, 10.0), 1))])
        m = _build(_biglide(lengths, strokes))
        if m is not None:  # strokes that let the legs meet
            out.append(m)
    return out


#: by how much the strokes overlap the legs' reach
_HAIRS = (1e-9, 1e-10, 1e-12, 5e-10)


def random_near_biglides(n: int, seed: int = 7) -> list[Mechanism]:
    """Biglides whose sliders can come just close enough for the legs to meet:
    the nearest ends of the strokes are L1 + L2 - h apart, h in 1e-12..1e-9
    (slider 2 right of slider 1, or left in turn); a third with equal legs."""
    rng = np.random.default_rng(seed)
    out: list[Mechanism] = []
    while len(out) < n:
        lengths = _biglide_legs(rng, equal=len(out) % 3 == 0)
        hair = _HAIRS[len(out) % len(_HAIRS)]
        lo1 = float(np.round(rng.uniform(-8.0, 0.0), 1))
        hi1 = lo1 + float(np.round(rng.uniform(0.5, 8.0), 1))
        gap = lengths[0] + lengths[1] - hair
        width = float(np.round(rng.uniform(0.5, 8.0), 1))
        if (len(out) // 2) % 2 == 0:
            strokes = [[lo1, hi1], [hi1 + gap, hi1 + gap + width]]
        else:
            strokes = [[lo1, hi1], [lo1 - gap - width, lo1 - gap]]
        m = _build(_biglide(lengths, strokes))
        if m is not None:
            out.append(m)
    return out


def random_biglide_designs(n: int, seed: int = 5) -> list[Mechanism]:
    """The biglide family: ``n`` random biglides then ``n`` near-degenerate ones."""
    return [*random_biglides(n, seed), *random_near_biglides(n, seed + 2)]


# ------------------------------------------------------------------ three-legged
def _triangle(rng: np.random.Generator, size: float, min_area: float) -> list[list[float]]:
    while True:
        pts = np.round(rng.uniform(0.0, size, (3, 2)), 1)
        (ax, ay), (bx, by), (cx, cy) = pts
        if abs((bx - ax) * (cy - ay) - (cx - ax) * (by - ay)) / 2 >= min_area * size * size:
            return [[float(x), float(y)] for x, y in pts]


def _three_rpr(
    base: list[list[float]], platform: list[list[float]], strokes: Sequence[Sequence[float]]
) -> dict[str, Any]:
    return {
        "mechanism": "3-RPR",
        "parameters": {"base": base, "platform": platform},
        "limits": {f"rho{i + 1}": list(s) for i, s in enumerate(strokes)},
    }


def random_three_rprs(n: int, seed: int = 19) -> list[Mechanism]:
    """Base triangles in a 16 x 16 square, platform triangles in a 4..12 square
    (platform origin at a random point), strokes from 2..8 and 6..14 long (one
    stroke for the three legs one time in two)."""
    rng = np.random.default_rng(seed)
    out: list[Mechanism] = []
    while len(out) < n:
        base = _triangle(rng, 16.0, 0.1)
        platform = _triangle(rng, float(np.round(rng.uniform(4.0, 12.0), 1)), 0.1)
        strokes = []
        for _ in range(3):
            lo = float(np.round(rng.uniform(2.0, 8.0), 1))
            strokes.append([lo, lo + float(np.round(rng.uniform(6.0, 14.0), 1))])
        if rng.random() < 0.5:
            strokes = [strokes[0]] * 3
        m = _build(_three_rpr(base, platform, strokes))
        if m is not None:
            out.append(m)
    return out


def _delta(design: Sequence[float], limits: Sequence[Any]) -> dict[str, Any]:
    names = ("base_radius", "platform_radius", "arm", "rod")
    return {
        "mechanism": "delta",
        "parameters": dict(zip(names, map(float, design), strict=True)),
        "limits": {f"theta{i + 1}": lim for i, lim in enumerate(limits)},
    }


def random_deltas(n: int, seed: int = 23) -> list[Mechanism]:
    """Base radius 5..12, platform radius 1..0.7 R, arm 4..12, rod 1..2 arms;
    per joint a window from -pi/2..0 to pi/4..pi (one design in four with equal
    windows)."""
    rng = np.random.default_rng(seed)
    out: list[Mechanism] = []
    while len(out) < n:
        R = float(np.round(rng.uniform(5.0, 12.0), 1))
        r = float(np.round(rng.uniform(1.0, 0.7 * R), 1))
        la = float(np.round(rng.uniform(4.0, 12.0), 1))
        lb = float(np.round(la * rng.uniform(1.0, 2.0), 1))
        limits = [
            [
                float(np.round(rng.uniform(-math.pi / 2, 0.0), 2)),
                float(np.round(rng.uniform(math.pi / 4, math.pi), 2)),
            ]
            for _ in range(3)
        ]
        if rng.random() < 0.25:
            limits = [limits[0]] * 3
        m = _build(_delta((R, r, la, lb), limits))
        if m is not None:
            out.append(m)
    return out


def random_three_rrrs(n: int, seed: int = 29) -> list[Mechanism]:
    """Base joints near a circle of radius 8..12 (at 90, 210, 330 degrees, each
    moved up to 15 degrees), platform joints near a circle of radius 2..4,
    proximal links 4..9 and distal links 3..8; joints unlimited one design in
    two, else a window at least 2 rad wide per joint."""
    rng = np.random.default_rng(seed)
    out: list[Mechanism] = []
    while len(out) < n:
        rb = rng.uniform(8.0, 12.0)
        rp = rng.uniform(2.0, 4.0)
        angles = np.radians([90.0, 210.0, 330.0])
        jb = angles + np.radians(rng.uniform(-15.0, 15.0, 3))
        jp = angles + np.radians(rng.uniform(-15.0, 15.0, 3))
        base = np.round(rb * np.stack([np.cos(jb), np.sin(jb)], axis=1), 2).tolist()
        platform = np.round(rp * np.stack([np.cos(jp), np.sin(jp)], axis=1), 2).tolist()
        proximal = np.round(rng.uniform(4.0, 9.0, 3), 1).tolist()
        distal = np.round(rng.uniform(3.0, 8.0, 3), 1).tolist()
        unlimited = rng.random() < 0.5
        spec = {
            "mechanism": "3-RRR",
            "parameters": {
                "base": base,
                "platform": platform,
                "proximal": proximal,
                "distal": distal,
            },
            "limits": {
                f"theta{i + 1}": "unlimited" if unlimited else _window(rng, 2.0) for i in range(3)
            },
        }
        m = _build(spec)
        if m is not None:
            out.append(m)
    return out


# ------------------------------------------------------------------ user-defined twins
def _custom_five_bar(m: Mechanism) -> dict[str, Any]:
    spec = _spec(m)
    lo, hi = m.bounds
    return {
        "mechanism": "custom",
        "pose": ["x", "y"],
        "joints": ["t1", "t2"],
        "parameters": spec["parameters"],
        "legs": [
            {"joint": "t1", "constraint": "(x - L1*cos(t1))**2 + (y - L1*sin(t1))**2 - L2**2"},
            {
                "joint": "t2",
                "constraint": "(x - L0 - L3*cos(t2))**2 + (y - L3*sin(t2))**2 - L4**2",
            },
        ],
        "limits": {"t1": spec["limits"]["theta1"], "t2": spec["limits"]["theta2"]},
        "bounds": {n: [float(lo[k]), float(hi[k])] for k, n in enumerate("xy")},
    }


def _custom_three_rpr(m: Mechanism) -> dict[str, Any]:
    spec = _spec(m)
    params: dict[str, float] = {}
    legs = []
    for i in range(3):
        j = i + 1
        (ax, ay) = spec["parameters"]["base"][i]
        (bx, by) = spec["parameters"]["platform"][i]
        params.update({f"ax{j}": ax, f"ay{j}": ay, f"bx{j}": bx, f"by{j}": by})
        px = f"(x + cos(phi)*bx{j} - sin(phi)*by{j} - ax{j})"
        py = f"(y + sin(phi)*bx{j} + cos(phi)*by{j} - ay{j})"
        legs.append(
            {"joint": f"r{j}", "kind": "prismatic", "constraint": f"{px}**2 + {py}**2 - r{j}**2"}
        )
    lo, hi = m.bounds
    return {
        "mechanism": "custom",
        "pose": ["x", "y", "phi"],
        "periodic": ["phi"],
        "joints": ["r1", "r2", "r3"],
        "parameters": params,
        "legs": legs,
        "limits": {f"r{i + 1}": list(spec["limits"][f"rho{i + 1}"]) for i in range(3)},
        "bounds": {"x": [float(lo[0]), float(hi[0])], "y": [float(lo[1]), float(hi[1])],
                   "phi": ["-pi", "pi"]},
    }  # fmt: skip


#: the unit vectors of the Delta's legs as written in the constraints (exact)
_COS = ("1", "(-1/2)", "(-1/2)")
_SIN = ("0", "(sqrt(3)/2)", "(-sqrt(3)/2)")


def _custom_delta(m: Mechanism) -> dict[str, Any]:
    spec = _spec(m)
    p = spec["parameters"]
    legs = []
    for i in range(3):
        t = f"t{i + 1}"
        h = f"(r - (R + la*cos({t})))"
        constraint = (
            f"(x + {_COS[i]}*{h})**2 + (y + {_SIN[i]}*{h})**2 + (z + la*sin({t}))**2 - lb**2"
        )
        legs.append({"joint": t, "constraint": constraint})
    lo, hi = m.bounds
    return {
        "mechanism": "custom",
        "pose": ["x", "y", "z"],
        "joints": ["t1", "t2", "t3"],
        "parameters": {
            "R": p["base_radius"], "r": p["platform_radius"], "la": p["arm"], "lb": p["rod"],
        },
        "legs": legs,
        "limits": {f"t{i + 1}": spec["limits"][f"theta{i + 1}"] for i in range(3)},
        "bounds": {n: [float(lo[k]), float(hi[k])] for k, n in enumerate("xyz")},
    }  # fmt: skip


#: the built-in twins of the user-defined specs: kind, designs, the spec of its twin
_TWINS: tuple[tuple[str, Callable[[int, int], list[Any]], Callable[[Mechanism], Any]], ...] = (
    ("five-bar", random_five_bars, _custom_five_bar),
    ("3-RPR", random_three_rprs, _custom_three_rpr),
    ("Delta", random_deltas, _custom_delta),
)


def random_custom_twins(n: int, seed: int = 31) -> list[Mechanism]:
    """``n`` pairs (user-defined spec, its built-in twin): a five-bar, a 3-RPR and a
    Delta in turn, drawn as in their own families (with this seed)."""
    per_kind = [len(range(k, n, len(_TWINS))) for k in range(len(_TWINS))]
    drawn = [designs(count, seed) for (_, designs, _), count in zip(_TWINS, per_kind, strict=True)]
    out: list[Mechanism] = []
    for i in range(n):
        k = i % len(_TWINS)
        builtin = drawn[k][i // len(_TWINS)]
        out += [from_spec(_TWINS[k][2](builtin)), builtin]
    return out


# ------------------------------------------------------------------ families
def span_precision(parts: int) -> Callable[[Mechanism], Precision]:
    """The precision at 1/``parts`` of each span of the mechanism's ``pose_box()``."""

    def precision(m: Mechanism) -> Precision:
        lo, hi = m.pose_box()
        return tuple(float(v) for v in (hi - lo) / parts)

    return precision


def _twin_kind(m: Mechanism) -> str:
    names = tuple(m.pose_names)
    return "Delta" if "z" in names else "3-RPR" if "phi" in names else "five-bar"


def _twin_precision(m: Mechanism) -> Precision:
    """The precision of the twin's family; a user-defined spec's bounds are its
    twin's, so both twins get the same spans and precision."""
    kind = _twin_kind(m)
    if kind == "five-bar":
        return 0.05
    return span_precision(64 if kind == "3-RPR" else 32)(m)


@dataclass(frozen=True)
class Family:
    """A family of designs: how to draw them, at what precision to analyse each,
    and the table line each design counts in."""

    designs: Callable[[int, int], Sequence[Mechanism]]
    precision: Callable[[Mechanism], Precision]
    seed: int
    n: int
    label: Callable[[Mechanism], str]


def _fixed(value: float) -> Callable[[Mechanism], Precision]:
    return lambda m: value


def _named(text: str) -> Callable[[Mechanism], str]:
    return lambda m: text


def _biglide_label(m: Mechanism) -> str:
    lo = [lim.lo for lim in m.limits]
    hi = [lim.hi for lim in m.limits]
    reach = sum(_spec(m)["parameters"].values())
    near = max(lo[1] - hi[0], lo[0] - hi[1]) > reach - 1e-8
    return f"biglide, {'near-degenerate' if near else 'random'}"


def _custom_label(m: Mechanism) -> str:
    return f"{_twin_kind(m)}, {'user-defined' if m.name == 'custom' else 'built-in twin'}"


FAMILIES: dict[str, Family] = {
    "five-bar": Family(random_five_bars, _fixed(0.05), 11, 20, _named("five-bar, random")),
    "five-bar-near": Family(
        random_near_five_bars, _fixed(0.05), 13, 24, _named("five-bar, near-degenerate")
    ),
    "biglide": Family(random_biglide_designs, _fixed(0.1), 5, 15, _biglide_label),
    "three-rpr": Family(random_three_rprs, span_precision(64), 19, 10, _named("3-RPR, 1/64")),
    "delta": Family(random_deltas, span_precision(32), 23, 10, _named("Delta, 1/32")),
    "constrained": Family(
        random_constrained_five_bars, _fixed(0.05), 17, 12,
        _named("five-bar, passive/obstacles/collisions"),
    ),
    "custom": Family(random_custom_twins, _twin_precision, 31, 12, _custom_label),
    "three-rrr": Family(random_three_rrrs, span_precision(64), 29, 8, _named("3-RRR, 1/64")),
}  # fmt: skip


# ------------------------------------------------------------------ the run
@dataclass(frozen=True)
class Row:
    """One design's answers."""

    family: str
    index: int
    parameters: str
    at_least: int
    at_most: int | None
    n_listed: int
    n_connected: bool | None
    seconds: float
    leaves: int

    @property
    def definite(self) -> bool:
        return self.at_least == self.at_most

    @property
    def listed(self) -> bool:
        return self.definite and self.n_listed == self.at_most


def run_design(label: str, index: int, m: Mechanism, precision: Precision) -> Row:
    """Analyse one design at the default settings, timed."""
    start = time.perf_counter()
    result = analyze(m, precision=precision)
    seconds = time.perf_counter() - start
    at_least, at_most = result.count
    return Row(
        label, index, json.dumps(m.to_spec()), at_least, at_most, len(result.regions),
        result.n_connected, seconds, len(result.tree),
    )  # fmt: skip


def _warm_up(m: Mechanism, precision: Precision) -> None:
    """Analyse coarsely, untimed: kernels loaded, user-defined specs compiled."""
    coarse = tuple(8.0 * v for v in np.broadcast_to(precision, len(m.pose_names)))
    try:
        analyze(m, precision=coarse, resolve=False)
    except MoveabilityError:
        pass


def run_family(name: str, n: int, seed: int) -> list[Row]:
    family = FAMILIES[name]
    rows: list[Row] = []
    seen: dict[str, int] = {}
    for m in family.designs(n, seed):
        label, precision = family.label(m), family.precision(m)
        if label not in seen:
            _warm_up(m, precision)
        # the design's place among those of its line (twins share it)
        index = seen[label] = seen.get(label, -1) + 1
        row = run_design(label, index, m, precision)
        print(
            f"  {label:<40} #{index:<3} count {row.at_least}..{row.at_most} "
            f"listed {row.n_listed} N-conn {row.n_connected} {row.seconds:7.2f} s",
            flush=True,
        )
        rows.append(row)
    return rows


def _share(flags: Sequence[bool]) -> str:
    return f"{sum(flags)}/{len(flags)} {sum(flags) / len(flags):4.0%}"


def table(rows: Sequence[Row]) -> str:
    """The table, a line per kind of design, then the counts left open."""
    labels = list(dict.fromkeys(r.family for r in rows))
    head = (
        f"{'family':<40} | {'designs':>7} | {'count definite':>14} | {'all listed':>14} | "
        f"{'N-conn decided':>14} | {'median s':>8} | {'max s':>7}"
    )
    lines = [head, "-" * len(head)]
    opened = []
    for label in labels:
        group = [r for r in rows if r.family == label]
        times = [r.seconds for r in group]
        lines.append(
            f"{label:<40} | {len(group):>7} | {_share([r.definite for r in group]):>14} | "
            f"{_share([r.listed for r in group]):>14} | "
            f"{_share([r.n_connected is not None for r in group]):>14} | "
            f"{statistics.median(times):8.2f} | {max(times):7.2f}"
        )
        left = [f"#{r.index} [{r.at_least}, {r.at_most}]" for r in group if not r.definite]
        left += [
            f"#{r.index} {r.at_most} counted, {r.n_listed} listed"
            for r in group
            if r.definite and not r.listed
        ]
        if left:
            opened.append(f"{label}: {', '.join(left)}")
    if opened:
        lines += ["", "open:", *opened]
    return "\n".join(lines)


def write_csv(path: str, rows: Sequence[Row]) -> None:
    with open(path, "w", newline="") as stream:
        out = csv.writer(stream)
        out.writerow(
            ["family", "design", "parameters", "at_least", "at_most", "n_listed",
             "n_connected", "seconds", "leaves"]
        )  # fmt: skip
        for r in rows:
            out.writerow(
                [r.family, r.index, r.parameters, r.at_least,
                 "" if r.at_most is None else r.at_most, r.n_listed,
                 "" if r.n_connected is None else r.n_connected, f"{r.seconds:.3f}", r.leaves]
            )  # fmt: skip


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, help="designs per family (default: each family's own)")
    parser.add_argument(
        "--families", default=",".join(FAMILIES), help=f"comma-separated, of {', '.join(FAMILIES)}"
    )
    parser.add_argument("--seed", type=int, help="one seed for every family (default: theirs)")
    parser.add_argument("--csv", help="write one row per design to this file")
    args = parser.parse_args(argv)
    names = [f.strip() for f in args.families.split(",") if f.strip()]
    unknown = [f for f in names if f not in FAMILIES]
    if unknown:
        parser.error(f"unknown families {unknown}; known: {', '.join(FAMILIES)}")
    analyze(FiveBar(), precision=0.5)  # load the kernels first, untimed
    start = time.perf_counter()
    rows: list[Row] = []
    for name in names:
        family = FAMILIES[name]
        n = family.n if args.n is None else args.n
        seed = family.seed if args.seed is None else args.seed
        print(f"{name}: {n} designs, seed {seed}", flush=True)
        rows += run_family(name, n, seed)
        if args.csv:
            write_csv(args.csv, rows)
    print()
    print(table(rows))
    print(f"\n{len(rows)} designs in {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main(sys.argv[1:])
