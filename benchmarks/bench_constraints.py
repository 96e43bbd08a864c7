"""Cost of each constraint beyond the paper against the unconstrained analysis.

The five-bar of Caro et al. (2014): L0..L4 = 9, 8, 5, 5, 8, actuated joints
unlimited; plain, with the passive limit P in [-pi/2, pi/2], with the
obstacle of radius 1 at (4.5, 0), with link collisions, and all three. For each:
leaves, seconds and count bounds of the regions and of the generalized aspects.
Run: ``.venv/bin/python benchmarks/bench_constraints.py [precision]``.
"""

from __future__ import annotations

import sys
import time

from moveability import analyze, from_spec

BASE = {
    "mechanism": "five-bar",
    "parameters": {"L0": 9, "L1": 8, "L2": 5, "L3": 5, "L4": 8},
    "limits": {"theta1": "unlimited", "theta2": "unlimited"},
}
CASES = {
    "plain": {},
    "passive P": {"passive_limits": {"P": ["-pi/2", "pi/2"]}},
    "obstacle": {"obstacles": [{"center": [4.5, 0.0], "radius": 1.0}]},
    "collisions": {"collisions": {"links": True}},
}
CASES["all three"] = {k: v for case in list(CASES.values()) for k, v in case.items()}


def bounds(count: tuple[int, int | None]) -> str:
    return str(count[0]) if count[0] == count[1] else f"{count[0]}..{count[1] or '?'}"


def main() -> None:
    eps = float(sys.argv[1]) if len(sys.argv) > 1 else 0.1
    analyze(from_spec(BASE), precision=0.5)  # compile the kernels, untimed
    print(f"constraints on the five-bar of Caro et al., precision {eps:g}")
    half = f"{'leaves':>8} {'s':>6}"
    print(f"{'case':<11} {'aspects':>8} {half}   {'regions':>8} {half}")
    for name, extra in CASES.items():
        mechanism = from_spec({**BASE, **extra})
        row = [f"{name:<11}"]
        for aspects in (True, False):
            start = time.perf_counter()
            result = analyze(mechanism, precision=eps, generalized_aspects=aspects)
            seconds = time.perf_counter() - start
            row.append(f"{bounds(result.count):>8} {len(result.tree):>8} {seconds:>6.2f}")
        print("   ".join(row))


if __name__ == "__main__":
    main()
