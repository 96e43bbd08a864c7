"""Benchmark of the 2^k-tree engine: build, adjacency, components and projection.

For k = 2, 4 and 6 axes and a few maximal depths each, a tree of a thin
spherical shell (or, with ``--shape ball``, of a ball) centred at the origin is
built in the box ``[-1.1, 1.2]^k``. The set is boundary-dominated: its cells are
classified conservatively, with numpy, by the nearest and farthest distance of
each box from the centre, and only BOUNDARY cells are split. On each tree the
script times

* ``HyperTree.build(lo, hi, classify, max_depth=depth)``;
* ``adjacency(tree, connectivity=1)`` (all pairs of face-adjacent leaves);
* ``components(tree, status=IN | BOUNDARY, connectivity=1)``;
* ``project(tree, [0, 1])``;

and, for k = 2 and 4 at one depth, ``components`` with ``connectivity=k``.
Then it measures the peak memory of each phase with :mod:`tracemalloc` in a
second, separate pass, so that tracing never slows the timed runs. numpy
reports its buffers to tracemalloc, and so does numba's runtime, which holds
the union-find arrays of the components kernel.

Run ``python benchmarks/bench_tree.py --quick`` for a check in seconds; the
default run keeps within ``--max-seconds`` (about three minutes in all on a
two-core machine) by skipping the phases whose estimated cost would not fit.
The script prints figures only: it asserts nothing about wall-clock times.
"""

from __future__ import annotations

import argparse
import cProfile
import gc
import math
import os
import platform
import pstats
import sys
import time
import tracemalloc
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy
from numpy.typing import NDArray

import moveability
from moveability import BOUNDARY, IN, OUT, HyperTree, adjacency, components, project
from moveability.hypertree.topology import directions

try:  # not on Windows
    import resource
except ImportError:  # pragma: no cover
    resource = None  # type: ignore[assignment]

LO, HI = -1.1, 1.2  # the box [LO, HI]^k, deliberately not centred on the set
R_OUTER = 1.0
R_INNER = 0.75  # inner radius of the shell (the ball has none)

#: depths per number of axes, in the default run and with --quick
DEPTHS = {2: (8, 10, 12, 14), 4: (4, 5, 6, 7), 6: (3, 4)}
QUICK_DEPTHS = {2: (6, 8), 4: (3, 4), 6: (2, 3)}
#: depth at which components is also timed with connectivity=k (vertex adjacency)
FULL_CONNECTIVITY = {2: 12, 4: 5}
QUICK_FULL_CONNECTIVITY = {2: 8, 4: 4}
#: depth profiled with --profile (k = 4)
PROFILE_DEPTH, QUICK_PROFILE_DEPTH = 6, 4

#: a phase is run 3 times (best kept) if its first run took less than FAST
#: seconds, twice if less than MEDIUM seconds, once otherwise
FAST, MEDIUM = 0.5, 3.0
#: the estimated cost of a phase grows as (leaves ratio) ** GROWTH_EXPONENT from
#: the last smaller depth (sorting, cache misses), times a margin SAFETY
GROWTH_EXPONENT, SAFETY = 1.15, 1.3

PHASES = ("build", "adj", "comp", "conn", "proj")
TAKEN = IN | BOUNDARY

Classifier = Callable[[NDArray[np.float64], NDArray[np.float64]], NDArray[np.uint8]]


# ------------------------------------------------------------------ the set
def make_classifier(shape: str) -> Classifier:
    """Conservative classifier of boxes against a shell or ball at the origin."""
    r_inner = R_INNER if shape == "shell" else 0.0

    def classify(lo: NDArray[np.float64], hi: NDArray[np.float64]) -> NDArray[np.uint8]:
        nearest = np.sqrt((np.clip(0.0, lo, hi) ** 2).sum(axis=1))
        farthest = np.sqrt((np.maximum(np.abs(lo), np.abs(hi)) ** 2).sum(axis=1))
        inside = (nearest >= r_inner) & (farthest <= R_OUTER)
        outside = (farthest < r_inner) | (nearest > R_OUTER)
        return np.where(inside, IN, np.where(outside, OUT, BOUNDARY)).astype(np.uint8)

    return classify


def build(k: int, depth: int, classify: Classifier) -> HyperTree:
    return HyperTree.build([LO] * k, [HI] * k, classify, max_depth=depth)


def fresh_copy(tree: HyperTree) -> HyperTree:
    """The same leaves in a new tree, without the cached anchors (used by project)."""
    return HyperTree(
        tree.lo, tree.hi, tree.max_depth, tree.keys, tree.levels, tree.status, tree.periodic
    )


# ------------------------------------------------------------ time budget
class Budget:
    """Wall-clock budget of the whole run."""

    def __init__(self, max_seconds: float) -> None:
        self.start = time.perf_counter()
        self.max_seconds = max_seconds

    def elapsed(self) -> float:
        return time.perf_counter() - self.start

    def left(self) -> float:
        return self.max_seconds - self.elapsed()

    def fits(self, seconds: float | None) -> bool:
        return seconds is None or seconds <= self.left()


def log(budget: Budget, message: str) -> None:
    print(f"[{budget.elapsed():7.1f} s] {message}", file=sys.stderr, flush=True)


def best_of(
    run: Callable[[Any], Any],
    setup: Callable[[], Any],
    budget: Budget,
    reserve: float,
) -> tuple[float, Any]:
    """Best wall time of 1 to 3 runs of ``run(setup())``, and the last run's result.

    ``setup`` is not timed. A repeat is skipped when it would leave less than
    ``reserve`` times the first run's duration of budget (for the memory pass).
    """
    times: list[float] = []
    result: Any = None
    while True:
        result = None  # release the previous result before the next run
        arg = setup()
        gc.collect()
        t0 = time.perf_counter()
        result = run(arg)
        times.append(time.perf_counter() - t0)
        wanted = 3 if times[0] < FAST else 2 if times[0] < MEDIUM else 1
        if len(times) >= wanted or not budget.fits(times[0] * (1.0 + reserve)):
            break
    return min(times), result


def traced_peak(run: Callable[[], Any]) -> tuple[int, Any]:
    """Peak traced bytes above the current level during ``run()``; tracing must be on."""
    gc.collect()
    base = tracemalloc.get_traced_memory()[0]
    tracemalloc.reset_peak()
    result = run()
    return tracemalloc.get_traced_memory()[1] - base, result


# --------------------------------------------------------------------- rows
@dataclass
class Row:
    k: int
    depth: int
    leaves: int | None = None
    n_in: int | None = None
    n_boundary: int | None = None
    pairs: int | None = None
    n_components: int | None = None
    n_components_full: int | None = None
    tree_bytes: int | None = None
    seconds: dict[str, float] = field(default_factory=dict)
    peak: dict[str, int] = field(default_factory=dict)
    #: estimated seconds of the phases skipped for the budget
    skipped: dict[str, float] = field(default_factory=dict)
    memory_skipped: set[str] = field(default_factory=set)

    @property
    def taken(self) -> int | None:
        if self.n_in is None or self.n_boundary is None:
            return None
        return self.n_in + self.n_boundary


def estimate(
    history: list[Row], k: int, depth: int, phase: str, leaves: int | None
) -> float | None:
    """Seconds of ``phase`` at ``depth`` extrapolated from the last smaller depth of ``k``.

    The cost is taken as growing a little faster than the number of leaves,
    which grows by a constant factor per level for a boundary-dominated set
    (``2^(k-1)`` for a hypersurface). ``None`` when there is nothing to
    extrapolate from.
    """
    done = [r for r in history if r.k == k and r.depth < depth and r.leaves]
    if not done:
        return None
    prev = done[-1]
    cost = prev.seconds.get(phase, prev.skipped.get(phase))
    if cost is None or prev.leaves is None:
        return None
    if leaves is None:
        if len(done) >= 2 and done[-2].leaves:
            a, b = done[-2], prev
            assert a.leaves is not None and b.leaves is not None
            growth = (b.leaves / a.leaves) ** (1.0 / (b.depth - a.depth))
        else:
            growth = 2.0 ** (k - 1)
        leaves = int(prev.leaves * growth ** (depth - prev.depth))
    return cost * max(leaves / prev.leaves, 1.0) ** GROWTH_EXPONENT * SAFETY


def run_row(
    k: int,
    depth: int,
    classify: Classifier,
    *,
    full_connectivity: bool,
    memory: bool,
    budget: Budget,
    history: list[Row],
) -> Row:
    row = Row(k, depth)
    passes = 2.0 if memory else 1.0  # a phase costs a timed run and a traced run
    reserve = passes - 1.0
    label = f"k={k} depth={depth}"

    def guard(phase: str, leaves: int | None) -> bool:
        est = estimate(history, k, depth, phase, leaves)
        if est is None and phase == "conn" and "comp" in row.seconds:
            # no smaller depth to go by: scale by the number of probe directions
            ratio = len(directions(k, k)) / len(directions(k, 1))
            est = row.seconds["comp"] * ratio * SAFETY
        if budget.fits(None if est is None else est * passes):
            return True
        row.skipped[phase] = est if est is not None else math.inf
        log(budget, f"{label}: {phase} skipped (estimated {est:.1f} s per run)")
        return False

    # ---- timed pass
    if not guard("build", None):
        return row
    log(budget, f"{label}: build")
    row.seconds["build"], tree = best_of(
        lambda _: build(k, depth, classify), lambda: None, budget, reserve
    )
    counts = tree.counts()
    row.leaves, row.n_in, row.n_boundary = len(tree), counts["IN"], counts["BOUNDARY"]
    row.tree_bytes = tree.keys.nbytes + tree.levels.nbytes + tree.status.nbytes

    calls: dict[str, Callable[[HyperTree], Any]] = {
        "adj": lambda t: adjacency(t, connectivity=1),
        "comp": lambda t: components(t, status=TAKEN, connectivity=1),
        "conn": lambda t: components(t, status=TAKEN, connectivity=k),
        "proj": lambda t: project(t, [0, 1]),
    }
    phases = ["adj", "comp", *(["conn"] if full_connectivity else []), "proj"]
    done: list[str] = []
    for phase in phases:
        if not guard(phase, row.leaves):
            continue
        log(budget, f"{label}: {phase} ({row.leaves} leaves)")
        # project caches the leaves' anchors on the tree: give every run a new tree
        setup = (lambda: fresh_copy(tree)) if phase == "proj" else (lambda: tree)
        row.seconds[phase], result = best_of(calls[phase], setup, budget, reserve)
        if phase == "adj":
            row.pairs = len(result)
        elif phase == "comp":
            row.n_components = result[1]
        elif phase == "conn":
            row.n_components_full = result[1]
        del result
        done.append(phase)

    # ---- traced pass
    if not memory:
        return row
    log(budget, f"{label}: memory pass")
    tracemalloc.start()
    try:
        if budget.fits(row.seconds["build"] * SAFETY):
            del tree  # rebuild under tracing; the new tree serves the phases below
            row.peak["build"], tree = traced_peak(lambda: build(k, depth, classify))
        else:
            row.memory_skipped.add("build")
        for phase in done:
            if not budget.fits(row.seconds[phase] * SAFETY):
                row.memory_skipped.add(phase)
                continue
            row.peak[phase], result = traced_peak(lambda: calls[phase](tree))  # noqa: B023
            del result
    finally:
        tracemalloc.stop()
    return row


# ------------------------------------------------------------------- output
def fmt_int(value: int | None) -> str:
    return "-" if value is None else f"{value:,}"


def fmt_sec(row: Row, phase: str) -> str:
    if phase in row.skipped:
        return "skip"
    value = row.seconds.get(phase)
    if value is None:
        return "-"
    return f"{value:.4f}" if value < 1 else f"{value:.3g}" if value < 100 else f"{value:.0f}"


def fmt_mib(row: Row, phase: str) -> str:
    if phase in row.skipped or phase in row.memory_skipped:
        return "skip"
    value = row.peak.get(phase)
    return "-" if value is None else f"{value / 2**20:.1f}"


def fmt_rate(count: int | None, seconds: float | None) -> str:
    if count is None or not seconds:
        return "-"
    rate = count / seconds
    return f"{rate / 1e6:.2f}M" if rate >= 1e6 else f"{rate / 1e3:.0f}k"


def table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(header)]
    lines = ["  ".join(h.rjust(w) for h, w in zip(header, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
    return "\n".join(lines)


HEADER = """\
moveability 2^k-tree benchmark: {shape} in [{lo}, {hi}]^k, {what}
Columns (times in seconds, wall clock, best of 1-3 runs: 3 runs when the first
took < {fast} s, 2 when < {medium} s; memory in MiB; 'skip' = not run, its estimated
cost exceeding what is left of --max-seconds; '-' = not measured):
  k, depth     number of axes and maximal depth of every axis (2^depth cells per axis)
  leaves       leaves of the tree after merging; IN and BND count the IN and BOUNDARY ones
  build        HyperTree.build(lo, hi, classify, max_depth=depth), the classifier included
  adj          adjacency(tree, connectivity=1); pairs = number of face-adjacent pairs found
  comp         components(tree, status=IN | BOUNDARY, connectivity=1); ncomp = components
  comp/s       IN and BOUNDARY leaves labelled per second by comp
  proj         project(tree, [0, 1]) on a tree without cached anchors (decoding included)
  M:phase      tracemalloc peak of the phase above the memory in use when it started
               (the tree itself is not counted, the results are), in a separate traced pass
  tree B/l     bytes per leaf held by the tree (keys, levels, status arrays)
  peak B/l     largest M:phase per leaf (bytes of working memory per leaf)"""


def print_report(rows: list[Row], args: argparse.Namespace, budget: Budget, warmup: float) -> None:
    what = f"thin shell {R_INNER:g} <= |x| <= {R_OUTER:g}"
    if args.shape == "ball":
        what = f"ball |x| <= {R_OUTER:g}"
    print(HEADER.format(shape=args.shape, lo=LO, hi=HI, what=what, fast=FAST, medium=MEDIUM))
    print()
    header = [
        "k", "depth", "leaves", "IN", "BND", "build", "adj", "pairs", "comp", "comp/s",
        "ncomp", "proj", "M:build", "M:adj", "M:comp", "M:proj", "tree B/l", "peak B/l",
    ]  # fmt: skip
    body = []
    for r in rows:
        peaks = [r.peak[p] for p in ("build", "adj", "comp", "proj") if p in r.peak]
        body.append(
            [
                str(r.k),
                str(r.depth),
                fmt_int(r.leaves),
                fmt_int(r.n_in),
                fmt_int(r.n_boundary),
                fmt_sec(r, "build"),
                fmt_sec(r, "adj"),
                fmt_int(r.pairs),
                fmt_sec(r, "comp"),
                fmt_rate(r.taken, r.seconds.get("comp")),
                fmt_int(r.n_components),
                fmt_sec(r, "proj"),
                fmt_mib(r, "build"),
                fmt_mib(r, "adj"),
                fmt_mib(r, "comp"),
                fmt_mib(r, "proj"),
                f"{r.tree_bytes / r.leaves:.1f}" if r.tree_bytes and r.leaves else "-",
                f"{max(peaks) / r.leaves:.1f}" if peaks and r.leaves else "-",
            ]
        )
    print(table(header, body))

    full = [r for r in rows if "conn" in r.seconds or "conn" in r.skipped]
    if full:
        print()
        print(
            "components(tree, status=IN | BOUNDARY) with connectivity=1 (faces, 2k probe\n"
            "directions per leaf) and connectivity=k (vertices, 3^k - 1 directions):"
        )
        header = [
            "k", "depth", "IN+BND", "dirs c=1", "comp c=1", "dirs c=k", "comp c=k",
            "c=k / c=1", "comp/s c=k", "ncomp c=k", "M:comp c=k",
        ]  # fmt: skip
        body = []
        for r in full:
            ratio = "-"
            if "conn" in r.seconds and r.seconds.get("comp"):
                ratio = f"{r.seconds['conn'] / r.seconds['comp']:.1f}"
            body.append(
                [
                    str(r.k),
                    str(r.depth),
                    fmt_int(r.taken),
                    str(len(directions(r.k, 1))),
                    fmt_sec(r, "comp"),
                    str(len(directions(r.k, r.k))),
                    fmt_sec(r, "conn"),
                    ratio,
                    fmt_rate(r.taken, r.seconds.get("conn")),
                    fmt_int(r.n_components_full),
                    fmt_mib(r, "conn"),
                ]
            )
        print(table(header, body))

    print()
    skipped = [
        f"k={r.k} depth={r.depth} {p} (~{s:.0f} s per run)"
        if s >= 10
        else f"k={r.k} depth={r.depth} {p} (~{s:.1g} s per run)"
        for r in rows
        for p, s in r.skipped.items()
    ]
    if skipped:
        print(f"Skipped for --max-seconds={args.max_seconds:g}: {'; '.join(skipped)}")
    untraced = [
        f"k={r.k} depth={r.depth} {p}" for r in rows for p in PHASES if p in r.memory_skipped
    ]
    if untraced:
        print(f"Timed but not traced for --max-seconds: {'; '.join(untraced)}")
    print(
        f"First components call (numba compilation or cache load, not in the table): {warmup:.2f} s"
    )
    line = f"Total {budget.elapsed():.1f} s"
    if resource is not None:
        # ru_maxrss is in KiB on Linux, in bytes on macOS
        scale = 1 if sys.platform == "darwin" else 1024
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * scale
        line += f"; process peak RSS {rss / 2**20:.0f} MiB"
    print(line)
    print(
        f"moveability {moveability.__version__}, numpy {np.__version__}, scipy "
        f"{scipy.__version__}, Python {platform.python_version()}, {os.cpu_count()} CPUs, "
        f"{platform.machine()} {platform.system()}"
    )


# ------------------------------------------------------------------ profile
def profile(depth: int, classify: Classifier, top: int) -> None:
    """Print cProfile's top functions, by cumulative time, of each phase at k = 4."""
    k = 4
    tree = build(k, depth, classify)
    print(f"cProfile at k={k} depth={depth} ({len(tree):,} leaves), top {top} by cumulative time")
    fresh = fresh_copy(tree)  # for project: no cached anchors, made outside the profile
    phases: list[tuple[str, Callable[[], Any]]] = [
        ("build", lambda: build(k, depth, classify)),
        ("components(connectivity=1)", lambda: components(tree, status=TAKEN, connectivity=1)),
        ("adjacency(connectivity=1)", lambda: adjacency(tree, connectivity=1)),
        ("project([0, 1])", lambda: project(fresh, [0, 1])),
    ]
    for name, call in phases:
        profiler = cProfile.Profile()
        profiler.runcall(call)
        print(f"\n--- {name}")
        stats = pstats.Stats(profiler, stream=sys.stdout)
        stats.strip_dirs().sort_stats("cumulative").print_stats(top)


# --------------------------------------------------------------------- main
def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--quick", action="store_true", help="small depths only, to check the script in seconds"
    )
    parser.add_argument(
        "--max-seconds",
        type=float,
        default=150.0,
        help="skip the phases whose estimated cost exceeds what is left of this budget "
        "(default: %(default)s; an estimate, so the run may end somewhat later)",
    )
    parser.add_argument(
        "--shape", choices=("shell", "ball"), default="shell", help="the set (default: shell)"
    )
    parser.add_argument(
        "--no-memory", action="store_true", help="skip the tracemalloc pass (halves the run)"
    )
    parser.add_argument(
        "--profile",
        action="store_true",
        help="instead of the table, print cProfile's top functions of each phase at k=4 "
        f"and --profile-depth (default {PROFILE_DEPTH}, {QUICK_PROFILE_DEPTH} with --quick)",
    )
    parser.add_argument("--profile-depth", type=int, help="depth of the tree for --profile")
    parser.add_argument("--top", type=int, default=12, help="functions listed by --profile")
    return parser.parse_args(argv)


def plan(quick: bool) -> list[tuple[int, int]]:
    """(k, depth) pairs, breadth first: the smallest depth of every k, then the next..."""
    depths = QUICK_DEPTHS if quick else DEPTHS
    order = []
    for rank in range(max(len(d) for d in depths.values())):
        order += [(k, ds[rank]) for k, ds in depths.items() if rank < len(ds)]
    return order


def main(argv: Sequence[str] | None = None) -> None:
    args = parse_args(argv)
    budget = Budget(args.max_seconds)
    classify = make_classifier(args.shape)
    if args.profile:
        depth = args.profile_depth or (QUICK_PROFILE_DEPTH if args.quick else PROFILE_DEPTH)
        components(build(2, 2, classify), status=TAKEN)  # compile the kernel first
        profile(depth, classify, args.top)
        return
    full = QUICK_FULL_CONNECTIVITY if args.quick else FULL_CONNECTIVITY

    # the first components call compiles the numba kernel (or loads it from its cache)
    t0 = time.perf_counter()
    components(build(2, 2, classify), status=TAKEN)
    warmup = time.perf_counter() - t0
    # move the objects of the imports out of the collector's sight: the
    # gc.collect() before every run then costs microseconds, not ~50 ms
    gc.collect()
    gc.freeze()

    history: list[Row] = []
    for k, depth in plan(args.quick):
        history.append(
            run_row(
                k,
                depth,
                classify,
                full_connectivity=full.get(k) == depth,
                memory=not args.no_memory,
                budget=budget,
                history=history,
            )
        )
    rows = sorted(history, key=lambda r: (r.k, r.depth))
    print_report(rows, args, budget, warmup)


if __name__ == "__main__":
    main()
