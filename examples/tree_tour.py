"""A tour of the 2^k-tree engine on sets with known answers.

Run with ``make demo``. It prints, for a 4-D ball, the measure bracket and its
tightening with depth, the projection onto two axes against the disk, and the
connected components of a cut annulus with and without a periodic axis.
"""

from __future__ import annotations

import time

import numpy as np

from moveability import BOUNDARY, IN, OUT, HyperTree, components, measure, project


def ball(lo: np.ndarray, hi: np.ndarray, radius: float = 1.0) -> np.ndarray:
    """IN if the cell is inside the ball, OUT if it misses it, else BOUNDARY."""
    nearest = np.sqrt((np.clip(0.0, lo, hi) ** 2).sum(axis=1))
    farthest = np.sqrt((np.maximum(np.abs(lo), np.abs(hi)) ** 2).sum(axis=1))
    return np.where(farthest <= radius, IN, np.where(nearest > radius, OUT, BOUNDARY))


def cut_annulus(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """In (theta, r): 0.8 <= r <= 1.6, minus the strip |theta - 0.3| < 0.5."""
    r_in = (lo[:, 1] >= 0.8) & (hi[:, 1] <= 1.6)
    r_out = (hi[:, 1] < 0.8) | (lo[:, 1] > 1.6)
    t_in = (lo[:, 0] >= 0.8) | (hi[:, 0] <= -0.2)  # wholly outside the strip
    t_out = (lo[:, 0] > -0.2) & (hi[:, 0] < 0.8)  # wholly inside the strip
    return np.where(r_in & t_in, IN, np.where(r_out | t_out, OUT, BOUNDARY))


def main() -> None:
    exact = np.pi**2 / 2
    print(f"4-D unit ball, volume pi^2/2 = {exact:.5f}")
    print(
        f"{'depth':>5} {'leaves':>9} {'inner':>9} {'outer':>9} {'disk in':>8} "
        f"{'disk out':>8} {'seconds':>8}"
    )
    for depth in range(3, 7):
        start = time.perf_counter()
        tree = HyperTree.build([-1.1] * 4, [1.2] * 4, ball, max_depth=depth)
        inner, outer = measure(tree)
        disk_in, disk_out = measure(project(tree, [0, 1]))
        seconds = time.perf_counter() - start
        print(
            f"{depth:>5} {len(tree):>9} {inner:>9.5f} {outer:>9.5f} {disk_in:>8.5f} "
            f"{disk_out:>8.5f} {seconds:>8.3f}"
        )
    print(f"projection onto (x0, x1) brackets the unit disk, pi = {np.pi:.5f}")
    print()
    print("annulus in polar coordinates (theta, r) minus a strip of theta")
    for periodic in ((), (0,)):
        tree = HyperTree.build(
            [-np.pi, 0.0], [np.pi, 2.0], cut_annulus, max_depth=8, periodic=periodic
        )
        _, count = components(tree, status=IN)
        kind = "theta periodic" if periodic else "theta not periodic"
        print(f"  {kind:<20}: {count} component(s)")


if __name__ == "__main__":
    main()
