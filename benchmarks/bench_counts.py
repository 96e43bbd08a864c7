"""Certified counts of regions: how often they are decided, and at what cost.

Prints, for random five-bars (seeded) at one precision, the time per design
with and without the resolution below the precision, and the share of designs
whose count and N-connectivity are decided, with the cost and the decided share
of the count proved in the joint space alone (part of the resolution); the same
for random biglides (a third with equal legs) at twice the precision; then the
time to the certified count of the issue's designs: the gap five-bar, the
equal-leg biglide and the 3-RPR (at 1/128 of each span: about 40 s; skip it
with ``--no-three-rpr``).

Run: ``.venv/bin/python benchmarks/bench_counts.py [N] [PRECISION] [--no-three-rpr]``
"""

from __future__ import annotations

import statistics
import sys
import time

import numpy as np

from moveability import analyze
from moveability.analysis.joint_space import count_in_joint_space
from moveability.limits import JointLimit
from moveability.mechanisms import FiveBar, from_spec


def random_five_bars(n: int, seed: int = 11) -> list[FiveBar]:
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
        try:
            out.append(FiveBar(*lengths, limits=(limits[0], limits[1])))
        except ValueError:
            continue
    return out


def _sweep(designs: list, eps: float, label: str) -> None:
    rows: dict[bool, list[tuple[float, bool, bool]]] = {False: [], True: []}
    for m in designs:
        for resolve in (False, True):
            start = time.perf_counter()
            result = analyze(m, precision=eps, resolve=resolve)
            seconds = time.perf_counter() - start
            rows[resolve].append(
                (seconds, result.n_regions is not None, result.n_connected is not None)
            )
    joint = []
    for m in designs:
        start = time.perf_counter()
        found = count_in_joint_space(m)
        joint.append((time.perf_counter() - start, found is not None and found.decided))
    print(f"{len(designs)} random {label} at precision {eps}")
    print(f"{'':>12} {'median s':>9} {'max s':>7} {'count decided':>14} {'N-conn. decided':>16}")
    for resolve in (False, True):
        data = rows[resolve]
        times = [r[0] for r in data]
        counts = sum(r[1] for r in data) / len(data)
        nconn = sum(r[2] for r in data) / len(data)
        name = "resolved" if resolve else "plain pass"
        print(
            f"{name:>12} {statistics.median(times):9.2f} {max(times):7.2f} "
            f"{counts:14.0%} {nconn:16.0%}"
        )
    times = [r[0] for r in joint]
    share = sum(r[1] for r in joint) / len(joint)
    print(
        f"{'joint space':>12} {statistics.median(times):9.2f} {max(times):7.2f} "
        f"{share:14.0%} {'-':>16}"
    )


def random_biglides(n: int, seed: int = 5) -> list:
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        lengths = [float(v) for v in np.round(rng.uniform(2.0, 7.0, 2), 1)]
        if len(out) % 3 == 0:
            lengths[1] = lengths[0]
        limits = {}
        for name in ("rho1", "rho2"):
            lo = float(np.round(rng.uniform(-8.0, 6.0), 1))
            limits[name] = [lo, lo + float(np.round(rng.uniform(0.5, 10.0), 1))]
        out.append(
            from_spec(
                {
                    "mechanism": "biglide",
                    "parameters": {"L1": lengths[0], "L2": lengths[1]},
                    "limits": limits,
                }
            )
        )
    return out


def _timed(label: str, m: object, precision: object, **options: object) -> None:
    start = time.perf_counter()
    result = analyze(m, precision=precision, **options)  # type: ignore[arg-type]
    print(
        f"{label}: count {result.count} in {time.perf_counter() - start:.1f} s, "
        f"{len(result.tree)} leaves"
    )


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 20
    eps = float(sys.argv[2]) if len(sys.argv) > 2 else 0.05
    with_rpr = "--no-three-rpr" not in sys.argv
    analyze(FiveBar(), precision=0.5)  # compile the kernels first
    _sweep(random_five_bars(n), eps, "five-bars")
    _sweep(random_biglides(n), 2 * eps, "biglides (a third with equal legs)")
    gap = FiveBar(
        6, 5, 6, 5, 6,
        limits=(
            JointLimit(1.3704384060045658, np.pi),
            JointLimit(-2.171858256624643, 1.9887034049203582),
        ),
    )
    _timed("gap five-bar at 0.05, plain pass", gap, 0.05, resolve=False)
    for precision in (0.05, 0.02, 0.01):
        _timed(f"gap five-bar at {precision}", gap, precision)
    equal = from_spec(
        {
            "mechanism": "biglide",
            "parameters": {"L1": 5.0, "L2": 5.0},
            "limits": {"rho1": [-3.0, 8.0], "rho2": [-4.0, -2.0]},
        }
    )
    for precision in (0.1, 0.05):
        _timed(f"equal-leg biglide at {precision}", equal, precision)
    rpr = from_spec(
        {
            "mechanism": "3-RPR",
            "parameters": {
                "base": [[0, 0], [10, 1], [3, 9]],
                "platform": [[0, 0], [5, -1], [2, 4]],
            },
            "limits": {"rho1": [4, 14], "rho2": [4, 14], "rho3": [4, 14]},
        }
    )
    lo, hi = rpr.pose_box()
    for parts in (32, 64) + ((128,) if with_rpr else ()):
        precision = tuple(float(v) for v in (hi - lo) / parts)
        _timed(f"3-RPR at 1/{parts} of each span", rpr, precision)


if __name__ == "__main__":
    main()
