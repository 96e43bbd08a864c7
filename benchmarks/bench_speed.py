"""Speed of the certified analysis against plain numpy grids, and how its cost scales.

Every measured thing runs in a fresh process. For a command (``moveability
regions``, ``moveability --version``, ``python -c "import numpy"``) the wall time
is taken around the process and the peak resident memory is the child's own
``ru_maxrss`` (from :func:`os.wait4`). For Python work (a numpy grid, an
in-process :func:`moveability.analyze`) this script runs itself with the hidden
``--case`` option; the child reports the time of the work alone and its own
``resource.getrusage(RUSAGE_SELF).ru_maxrss``, and the parent the process' wall
time. (The parent imports neither numpy nor moveability: on Linux a child's
``ru_maxrss`` starts from its parent's resident size at the fork.) The
comparisons printed, each with its target (printed, never asserted):

1. ``moveability regions examples/five-bar-paper.toml -p 0.035`` (the paper's
   five-bar, 0 <= theta1, theta2 <= pi) against an uncertified numpy grid of
   poses of the same spacing (the analysis' cells at the precision are that
   wide) over the mechanism's bounds (the analysis widens them to the
   precision times a power of two; the cells added hold no pose of W):
   closed-form inverse kinematics, the 4 postures, the sign of det A = (P - C) x (P - D), the
   regions labelled in the joint space (``scipy.ndimage.label`` on a grid over
   (theta1, theta2), same spacing in radians, each sign of det A apart) and
   the area of each region's image in W. Target: regions / numpy <= 0.5.
2. The same for the 3-RPR of examples/three-rpr.toml at 1/256 of the span of
   each pose axis: grid over (x, y, phi), strokes, sign of det A (the model's
   rows ``(B_i - A_i, (R b_i) x (P - A_i))``), labelled with phi periodic
   (``scipy.ndimage.label``, then a union-find across the faces phi = -pi, pi).
   Target: regions / numpy <= 0.5. ``--no-resolve`` (the plain pass) is timed
   too, and so is the classification alone (the tree built as ``analyze``
   builds it, every cell's reaches, limits and det A enclosed on intervals,
   then nothing else): the part of the work any certified analysis on this
   tree does first, a floor under the ratio.

   The command line runs OpenBLAS on one thread (``OPENBLAS_NUM_THREADS=1``
   unless the user set it): its thread pool is not started at numpy's import.
   For 1 and 2 the grid is also run in that environment, and that ratio is
   printed too: the part of the gain that is only the thread pool's start is
   then plain to see.
3. ``analyze`` of the user-defined five-bar (examples/five-bar-custom.toml,
   its [bounds] set to the box the built-in's analysis subdivides, so that
   both split the same cells) against the built-in one, both at precision
   0.05. Target: <= 3.
4. ``moveability --version`` against ``python -c "import numpy"``, best of 5.
   Target: <= 3.
5. Scaling: leaves and seconds of ``analyze`` for the built-in five-bar at
   precisions 0.1 .. 0.005 and the 3-RPR at 1/64 .. 1/256 of each span, with
   leaves * eps (2-D) and leaves * eps^2 (3-D, eps the fraction of the span):
   constant when the leaves follow the boundary of the sets.
6. The other mechanisms of the examples (biglide, the user-defined five-bar,
   the Delta, the 3-RRR): leaves, seconds and microseconds a leaf of
   ``analyze`` at one precision each.

The counts and areas of the numpy grids are printed beside the certified
bounds, so that a reader sees they agree. Run:
``.venv/bin/python benchmarks/bench_speed.py [--quick | --full]`` (``--quick``
in under a minute; ``--full`` adds finer scaling precisions).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
PAPER = EXAMPLES / "five-bar-paper.toml"  # 0 <= theta1, theta2 <= pi
CUSTOM = EXAMPLES / "five-bar-custom.toml"  # the same five-bar as a user-defined spec
RPR = EXAMPLES / "three-rpr.toml"
#: the console script next to the interpreter running this file
MOVEABILITY = str(Path(sys.executable).parent / "moveability")
#: grid components below this share of W's measure are counted apart as grid noise
TINY = 1e-4
#: a process that calls one compiled kernel of the package, as every analysis does
#: before its first leaf: the ahead-of-time extension's, or numba's (its import,
#: its initialisation and one cached kernel) when the extension is missing or stale
KERNEL_FLOOR = "from moveability.intervals import next_below; next_below(1.0)"
#: the environment the command line gives itself (moveability.cli): OpenBLAS on one
#: thread; the numpy grids are also run so, for a second ratio
ONE_BLAS_THREAD = {"OPENBLAS_NUM_THREADS": "1"}
#: which kernels a process of the package runs (moveability.compiled.MODE) and why
KERNEL_MODE = "import moveability.compiled as c; print(c.MODE, '-', c.REASON)"


# ------------------------------------------------------------- numpy grids
def five_bar_grid(params: dict[str, Any], h: float | Sequence[float]) -> dict[str, Any]:
    """Regions of a five-bar on a grid of poses of spacing ``h`` (uncertified).

    ``params`` (see :func:`mechanism_params`): lengths, joint limits and the
    analysis' box of poses; ``h`` one spacing or one per pose axis (the joint
    grid takes the smallest, in radians); numpy and scipy alone do the work.
    """
    import numpy as np
    from scipy import ndimage

    start = time.perf_counter()
    L0, L1, L2, L3, L4 = params["lengths"]
    limits = [tuple(lim) for lim in params["limits"]]
    if not np.isfinite(limits).all():
        raise ValueError("the joint-space grid needs finite joint limits")
    lo, hi = np.array(params["lo"]), np.array(params["hi"])
    hx, hy = np.broadcast_to(np.asarray(h, dtype=np.float64), (2,))
    hq = min(hx, hy)
    n = np.ceil((hi - lo) / (hx, hy)).astype(int)
    x = lo[0] + (np.arange(n[0]) + 0.5) * hx
    y = lo[1] + (np.arange(n[1]) + 0.5) * hy
    px, py = (v.ravel() for v in np.meshgrid(x, y, indexing="ij"))

    def inverse(bx: float, a: float, b: float) -> list[Any]:
        """Both elbow solutions of a leg based at (bx, 0): t = direction +- alpha."""
        dx, dy = px - bx, py
        rho = np.hypot(dx, dy)
        with np.errstate(divide="ignore", invalid="ignore"):
            alpha = np.arccos((rho**2 + a * a - b * b) / (2 * a * rho))  # NaN out of reach
        theta = np.arctan2(dy, dx)
        return [theta + alpha, theta - alpha]

    def within(t: Any, lim: tuple[float, float]) -> Any:
        """Whether the angles are within [lo, hi] (modulo 2 pi); False for NaN."""
        with np.errstate(invalid="ignore"):
            return np.mod(t - lim[0], 2 * np.pi) <= lim[1] - lim[0]

    # the 4 postures: angles, validity and sign of det A = (P - C) x (P - D)
    postures = []
    for t1 in inverse(0.0, L1, L2):
        for t2 in inverse(L0, L3, L4):
            ok = within(t1, limits[0]) & within(t2, limits[1])
            cx, cy = L1 * np.cos(t1), L1 * np.sin(t1)
            dx, dy = L0 + L3 * np.cos(t2), L3 * np.sin(t2)
            det = (px - cx) * (py - dy) - (py - cy) * (px - dx)
            postures.append((t1, t2, ok & (det != 0), np.sign(det)))
    in_w = np.logical_or.reduce([p[2] for p in postures])

    # the joint space: direct kinematics on a grid over (theta1, theta2), the two
    # assembly modes P = M +- k n (n normal to CD), each with its sign of det A
    nodes = [np.arange(int(np.floor((b - a) / hq)) + 1) * hq + a for a, b in limits]
    q1, q2 = np.meshgrid(*nodes, indexing="ij")
    cx, cy = L1 * np.cos(q1), L1 * np.sin(q1)
    dx, dy = L0 + L3 * np.cos(q2), L3 * np.sin(q2)
    ux, uy = dx - cx, dy - cy
    d = np.hypot(ux, uy)
    with np.errstate(divide="ignore", invalid="ignore"):
        along = (L2 * L2 - L4 * L4 + d * d) / (2 * d)
        k = np.sqrt(L2 * L2 - along**2)  # NaN where the circles do not meet
        ux, uy = ux / d, uy / d
    labels, comp_sign = [], []
    for s in (1.0, -1.0):
        qx = cx + along * ux - s * k * uy
        qy = cy + along * uy + s * k * ux
        det = (qx - cx) * (qy - dy) - (qy - cy) * (qx - dx)
        lab, count = ndimage.label(np.sign(det) == s)  # NaN compares unequal
        labels.append(lab)
        comp_sign += [int(s)] * count

    # each component's image in W: the grid poses with a configuration in it
    offsets = np.cumsum([0] + [int(lab.max()) for lab in labels])
    hits = []
    for t1, t2, ok, sign in postures:
        i1 = np.rint(np.mod(t1[ok] - limits[0][0], 2 * np.pi) / hq).astype(int)
        i2 = np.rint(np.mod(t2[ok] - limits[1][0], 2 * np.pi) / hq).astype(int)
        i1 = np.minimum(i1, len(nodes[0]) - 1)
        i2 = np.minimum(i2, len(nodes[1]) - 1)
        for j, s in enumerate((1.0, -1.0)):
            mine = sign[ok] == s
            lab = labels[j][i1[mine], i2[mine]]
            keep = lab > 0
            hits.append((offsets[j] + lab[keep] - 1) * px.size + np.flatnonzero(ok)[mine][keep])
    pairs = np.unique(np.concatenate(hits))
    areas = np.bincount(pairs // px.size, minlength=offsets[-1]) * hx * hy
    seconds = time.perf_counter() - start
    regions = sorted(
        ({"sign": s, "area": float(a)} for s, a in zip(comp_sign, areas, strict=True) if a > 0),
        key=lambda r: -r["area"],
    )
    return {
        "seconds": seconds,
        "grid": f"{n[0]}x{n[1]} poses, {q1.shape[0]}x{q1.shape[1]} joints",
        "cell": float(hx * hy),
        "workspace": float(in_w.sum() * hx * hy),
        "regions": regions,
    }


def three_rpr_grid(params: dict[str, Any], parts: int) -> dict[str, Any]:
    """Regions of a 3-RPR on a grid of ``parts`` poses per axis (uncertified).

    ``params`` (see :func:`mechanism_params`): base and platform points, strokes
    and the analysis' box of poses; numpy and scipy alone do the work.
    """
    import numpy as np
    from scipy import ndimage

    start = time.perf_counter()
    lo, hi = np.array(params["lo"]), np.array(params["hi"])
    h = (hi - lo) / parts
    h[2] = 2 * np.pi / parts  # phi: exactly one turn, so the seam faces meet
    x = lo[0] + (np.arange(parts) + 0.5) * h[0]
    y = lo[1] + (np.arange(parts) + 0.5) * h[1]
    phi = -np.pi + (np.arange(parts) + 0.5) * h[2]
    px, py = np.meshgrid(x, y, indexing="ij")
    px, py = px[..., None], py[..., None]
    sign = np.zeros((parts, parts, parts), dtype=np.int8)  # 0: out of W or singular
    chunk = 16  # phi slices at a time: (parts, parts, chunk) arrays
    for j in range(0, parts, chunk):
        c, s = np.cos(phi[j : j + chunk]), np.sin(phi[j : j + chunk])
        rows, ok = [], np.ones(px.shape[:2] + c.shape, dtype=bool)
        for (ax, ay), (bx, by), (r_lo, r_hi) in zip(
            params["base"], params["platform"], params["limits"], strict=True
        ):
            rbx, rby = c * bx - s * by, s * bx + c * by  # R(phi) b_i
            dx, dy = px + rbx - ax, py + rby - ay  # B_i - A_i
            rho = np.hypot(dx, dy)
            ok &= (rho >= r_lo) & (rho <= r_hi)
            rows.append((dx, dy, rbx * (py - ay) - rby * (px - ax)))
        (a, b, e), (f, g, i), (m, n, o) = rows
        det = a * (g * o - i * n) - b * (f * o - i * m) + e * (f * n - g * m)
        sign[:, :, j : j + chunk] = np.where(ok, np.sign(det), 0)
    cell = float(np.prod(h))
    workspace = float(np.count_nonzero(sign)) * cell  # det A = 0 has no volume on the grid

    regions = []
    for s in (1, -1):
        lab, count = ndimage.label(sign == s)
        # phi is periodic: merge the labels that meet across the faces phi = -pi, pi
        parent = np.arange(count + 1)

        def root(i: int, parent: Any = parent) -> int:
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        first, last = lab[:, :, 0].ravel(), lab[:, :, -1].ravel()
        both = (first > 0) & (last > 0)
        for u, v in np.unique(np.stack([first[both], last[both]], axis=1), axis=0):
            ru, rv = root(int(u)), root(int(v))
            if ru != rv:
                parent[max(ru, rv)] = min(ru, rv)
        roots = np.array([root(i) for i in range(count + 1)])
        volumes = np.bincount(roots[lab.ravel()], minlength=count + 1)[1:] * cell
        regions += [{"sign": s, "area": float(v)} for v in volumes if v > 0]
    seconds = time.perf_counter() - start
    regions.sort(key=lambda r: -r["area"])
    return {
        "seconds": seconds,
        "grid": f"{parts}^3 poses",
        "cell": cell,
        "workspace": workspace,
        "regions": regions,
    }


# ------------------------------------------------------------- analyses
def run_analysis(spec_file: str, precision: Any, resolve: bool) -> dict[str, Any]:
    """``analyze`` of a spec file, timed in this process (spec and mechanism included)."""
    from moveability import analyze

    start = time.perf_counter()
    result = analyze(spec_file, precision=precision, resolve=resolve)
    seconds = time.perf_counter() - start
    data = result.to_dict()
    data["seconds"] = seconds
    return data


def classification_only(spec_file: str, precision: Any) -> dict[str, Any]:
    """What every certified analysis does first, and nothing after: the tree of cells
    built as :func:`moveability.analyze` builds it, each cell classified (every
    leg's reach, its joint limits, the sign of det A, on intervals), without
    regions, connectivity, count or output. ``seconds`` is the build,
    ``enclosures`` the part of it spent classifying."""
    import numpy as np

    from moveability import load_spec
    from moveability.analysis.result import analysis_box, check_precision
    from moveability.analysis.sheets import classify_sheets
    from moveability.hypertree import BOUNDARY, HyperTree
    from moveability.mechanisms import from_spec

    start = time.perf_counter()
    mechanism: Any = from_spec(load_spec(spec_file))
    eps = check_precision(precision, len(mechanism.pose_names))
    lo, hi, depths = analysis_box(mechanism, eps)
    spent = [0.0, 0]

    def classify(cell_lo: Any, cell_hi: Any) -> Any:
        at = time.perf_counter()
        statuses = classify_sheets(mechanism, cell_lo, cell_hi).statuses()
        spent[0] += time.perf_counter() - at
        spent[1] += len(cell_lo)
        return statuses

    tree = HyperTree.build(
        lo, hi, classify, max_depth=list(depths), periodic=mechanism.periodic_axes,
        merge=False, stop_level=max(depths),
    )  # fmt: skip
    return {
        "seconds": time.perf_counter() - start,
        "enclosures": spent[0],
        "cells": int(spent[1]),
        "leaves": len(tree),
        "undecided": int(np.count_nonzero(tree.status == BOUNDARY)),
    }


def mechanism_params(spec_file: str) -> dict[str, Any]:
    """What the numpy grids need of a mechanism: its parameters, joint limits and
    the box of poses the analysis subdivides (``pose_box``)."""
    from moveability import load_spec
    from moveability.mechanisms import from_spec

    mechanism: Any = from_spec(load_spec(spec_file))
    lo, hi = mechanism.pose_box()
    out = {
        "limits": [[lim.lo, lim.hi] for lim in mechanism.limits],
        "lo": [float(v) for v in lo],
        "hi": [float(v) for v in hi],
    }
    if mechanism.name == "five-bar":
        out["lengths"] = list(mechanism.lengths)
    else:
        out["base"] = [list(a) for a in mechanism.base]
        out["platform"] = [list(b) for b in mechanism.platform]
    return out


def analysed_box(spec_file: str, precision: float) -> dict[str, Any]:
    """The box the analysis of a spec subdivides at ``precision`` (the built-in
    mechanisms widen their bounds to the precision times a power of two)."""
    import numpy as np

    from moveability import load_spec
    from moveability.analysis.result import analysis_box
    from moveability.mechanisms import from_spec

    mechanism: Any = from_spec(load_spec(spec_file))
    lo, hi, _ = analysis_box(mechanism, np.full(len(mechanism.pose_names), precision))
    return {"lo": [float(v) for v in lo], "hi": [float(v) for v in hi]}


def span_precision(params: dict[str, Any], parts: int) -> list[float]:
    """1/parts of the span of each axis of the box of poses."""
    return [(b - a) / parts for a, b in zip(params["lo"], params["hi"], strict=True)]


def child(kind: str, args: list[Any]) -> None:
    """Run one case in this (fresh) process and print its figures as JSON."""
    import resource

    if kind == "five-bar-grid":
        out = five_bar_grid(args[0], args[1])
    elif kind == "three-rpr-grid":
        out = three_rpr_grid(args[0], int(args[1]))
    elif kind == "analyze":
        out = run_analysis(args[0], args[1], bool(args[2]))
    elif kind == "params":
        out = mechanism_params(args[0])
    elif kind == "cells":
        out = classification_only(args[0], args[1])
    elif kind == "box":
        out = analysed_box(args[0], args[1])
    else:
        raise ValueError(kind)
    out["rss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps(out))


# ------------------------------------------------------------- processes
def run_process(
    cmd: Sequence[str], env: dict[str, str] | None = None
) -> tuple[float, float, str]:
    """Wall seconds, peak resident MiB (the child's own) and stdout of a command
    (with ``env`` added to this process' environment)."""
    full = None if env is None else {**os.environ, **env}
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        proc = subprocess.Popen(list(cmd), stdout=out, stderr=err, env=full)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        if proc.returncode != 0:
            message = err.read().decode(errors="replace").strip().splitlines()
            raise RuntimeError(f"{' '.join(cmd)}: exit {proc.returncode}: {message[-1:]}")
        return wall, usage.ru_maxrss / 1024, out.read().decode()


def run_case(kind: str, *args: Any, env: dict[str, str] | None = None) -> dict[str, Any]:
    """One case of :func:`child` in a fresh process (arguments passed as JSON, ``env``
    added to its environment); adds the process' wall time."""
    wall, _, text = run_process(
        [sys.executable, __file__, "--case", kind, json.dumps(args)], env=env
    )
    out: dict[str, Any] = json.loads(text.strip().splitlines()[-1])
    out["wall"] = wall
    return out


def run_analysis_case(spec: Path, precision: Any, resolve: bool = True) -> dict[str, Any]:
    """``analyze`` of a spec in a fresh process."""
    return run_case("analyze", str(spec), precision, resolve)


def regions_process(spec: Path, precision: str, *options: str) -> dict[str, Any]:
    """``moveability regions SPEC -p PRECISION --json -``: its JSON, time and memory."""
    wall, rss, text = run_process(
        [MOVEABILITY, "regions", str(spec), "-p", precision, "--json", "-", *options]
    )
    out: dict[str, Any] = json.loads(text)
    out["wall"], out["rss_mib"] = wall, rss
    return out


def best_of(cmd: Sequence[str], n: int) -> tuple[float, float]:
    """Best wall seconds and the peak MiB of that run, over ``n`` runs of a command."""
    runs = [run_process(cmd)[:2] for _ in range(n)]
    return min(runs)


# ------------------------------------------------------------- output
def table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """Columns right-aligned but the first (names), left-aligned."""
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(header)]

    def line(cells: Sequence[str]) -> str:
        first, *rest = (
            c.ljust(w) if i == 0 else c.rjust(w)
            for i, (c, w) in enumerate(zip(cells, widths, strict=True))
        )
        return "  ".join([first, *rest]).rstrip()

    return "\n".join([line(header), line(["-" * w for w in widths]), *map(line, rows)])


def ratio_line(label: str, a: float, b: float, target: float | None) -> str:
    """``a / b`` with the seconds, and whether it meets ``target`` (none: no target)."""
    ratio = a / b
    line = f"  ratio {label}: {a:.2f} s / {b:.2f} s = {ratio:.2f}"
    if target is None:
        return line
    mark = "met" if ratio <= target else "NOT met"
    return f"{line}   (target <= {target:g}: {mark})"


def bounds(pair: Sequence[float]) -> str:
    return f"[{pair[0]:.2f}, {pair[1]:.2f}]"


def agreement(certified: dict[str, Any], grid: dict[str, Any], measure: str) -> str:
    """The certified regions beside the grid's components (by sign, largest first).

    Components of the grid smaller than ``TINY`` of W (a few cells at the edge
    of W, where a one-cell-wide sliver breaks off) are counted apart.
    """
    w = certified["workspace"][measure]
    cert = sorted(certified["regions"], key=lambda r: (-r["sign"], -r[measure][1]))
    tiny = [r for r in grid["regions"] if r["area"] < TINY * grid["workspace"]]
    found = sorted(
        (r for r in grid["regions"] if r["area"] >= TINY * grid["workspace"]),
        key=lambda r: (-r["sign"], -r["area"]),
    )
    inside = w[0] <= grid["workspace"] <= w[1]
    rows = [["W", "", bounds(w), f"{grid['workspace']:.2f}", "yes" if inside else "no"]]
    for s in (1, -1):
        c = [r for r in cert if r["sign"] == s]
        g = [r for r in found if r["sign"] == s]
        for i in range(max(len(c), len(g))):
            ok = "-"
            if i < len(c) and i < len(g):
                ok = "yes" if c[i][measure][0] <= g[i]["area"] <= c[i][measure][1] else "no"
            rows.append([
                f"{'+' if s > 0 else '-'} region {i}",
                "> 0" if s > 0 else "< 0",
                bounds(c[i][measure]) if i < len(c) else "-",
                f"{g[i]['area']:.2f}" if i < len(g) else "-",
                ok,
            ])  # fmt: skip
    count = certified["count"]
    at_most = "?" if count["at_most"] is None else str(count["at_most"])
    proved = count["at_least"] if count["at_most"] == count["at_least"] else None
    said = f"{proved} (proved)" if proved is not None else f"{count['at_least']}..{at_most}"
    extra = ""
    if tiny:
        cells = sorted({round(r["area"] / grid["cell"]) for r in tiny})
        extra = (
            f" + {len(tiny)} tiny ({cells[0]}..{cells[-1]} cells each, "
            f"{sum(r['area'] for r in tiny):.3g} in all)"
        )
    head = ["", "det A", f"certified {measure} [in, out]", f"grid {measure}", "grid in bounds"]
    summary = f"  regions: certified {said}; grid {len(found)} components{extra}"
    return summary + "\n" + indent(table(head, rows))


def timing_rows(rows: Sequence[tuple[str, float, float | None, float]]) -> str:
    return table(
        ["what", "process s", "work s", "peak MiB"],
        [
            [name, f"{wall:.2f}", "-" if work is None else f"{work:.2f}", f"{rss:.0f}"]
            for name, wall, work, rss in rows
        ],
    )


def indent(text: str) -> str:
    return "\n".join("  " + line for line in text.splitlines())


# ------------------------------------------------------------- cases
def case_five_bar(eps: float) -> None:
    print(f"1. five-bar of the paper, [0, pi], precision {eps:g}: regions process vs numpy grid")
    cert = regions_process(PAPER, repr(eps))
    params = run_case("params", str(PAPER))
    grid = run_case("five-bar-grid", params, eps)
    # the analysis' finest cells: its box widened to eps times a power of two and
    # halved that many times, so eps wide (a spec whose box is the user's keeps it:
    # cells up to half as wide, and the grid at them is timed too)
    cell = cert["cell"]
    spacing = " x ".join(f"{v:.4g}" for v in cell)
    rows = [
        (f"moveability regions -p {eps:g} ({cert['leaves']} leaves, cells {spacing})",
         cert["wall"], None, cert["rss_mib"]),
        (f"numpy grid h={eps:g} ({grid['grid']})", grid["wall"], grid["seconds"],
         grid["rss_mib"]),
    ]  # fmt: skip
    finer = any(abs(v - eps) > 1e-9 * eps for v in cell)
    if finer:
        fine = run_case("five-bar-grid", params, cell)
        rows.append((f"numpy grid at the analysis' cells {spacing} ({fine['grid']})",
                     fine["wall"], fine["seconds"], fine["rss_mib"]))  # fmt: skip
    print(indent(timing_rows(rows)))
    print(ratio_line("regions / numpy (processes)", cert["wall"], grid["wall"], 0.5))
    if finer:
        print(ratio_line("regions / numpy at the analysis' cells", cert["wall"], fine["wall"],
                         0.5))  # fmt: skip
    single = run_case("five-bar-grid", params, eps, env=ONE_BLAS_THREAD)
    print(
        ratio_line("regions / numpy, its grid too on one BLAS thread", cert["wall"],
                   single["wall"], 0.5)
    )  # fmt: skip
    print(
        "  (the command line runs OpenBLAS on one thread; the grid so takes "
        f"{single['wall']:.2f} s)"
    )
    print(agreement(cert, grid, "area"))
    # what every run pays before its first leaf: numpy and one compiled kernel
    # (with numba's JIT: its import, its initialisation and one cached kernel) and
    # a whole process at a precision of a few leaves
    floor = best_of([sys.executable, "-c", KERNEL_FLOOR], 3)
    coarse = regions_process(PAPER, "0.5")
    budget = 0.5 * grid["wall"]
    print("  fixed costs (best of 3 / one run):")
    rows = [
        ("numpy + one compiled kernel", floor[0], None, floor[1]),
        (f"moveability regions -p 0.5 ({coarse['leaves']} leaves)", coarse["wall"], None,
         coarse["rss_mib"]),
    ]  # fmt: skip
    print(indent(timing_rows(rows)))
    print(
        f"  the target allows {budget:.2f} s for the whole process; numpy and one "
        f"kernel take {floor[0] / budget:.0%} of it, the process at -p 0.5 "
        f"{coarse['wall'] / budget:.0%}"
    )
    print()


def case_crossover(precisions: Sequence[float]) -> None:
    print("1b. the same comparison at finer precisions: the grid grows with the area,")
    print("    the certified analysis with the boundary")
    params = run_case("params", str(PAPER))
    rows = []
    for eps in precisions:
        cert = regions_process(PAPER, repr(eps))
        grid = run_case("five-bar-grid", params, eps)
        rows.append([
            f"{eps:g}", str(cert["leaves"]), f"{cert['wall']:.2f}", f"{cert['rss_mib']:.0f}",
            grid["grid"], f"{grid['wall']:.2f}", f"{grid['rss_mib']:.0f}",
            f"{cert['wall'] / grid['wall']:.2f}",
        ])  # fmt: skip
    head = ["eps", "leaves", "regions s", "MiB", "grid", "grid s", "MiB", "ratio"]
    print(indent(table(head, rows)))
    print()


def case_three_rpr(parts: int) -> None:
    params = run_case("params", str(RPR))
    eps = span_precision(params, parts)
    text = ",".join(repr(v) for v in eps)
    print(f"2. 3-RPR at 1/{parts} of each span (-p {','.join(f'{v:.4g}' for v in eps)})")
    cert = regions_process(RPR, text)
    plain = regions_process(RPR, text, "--no-resolve")
    cells = run_case("cells", str(RPR), eps)
    grid = run_case("three-rpr-grid", params, parts)
    rows = [
        (f"moveability regions ({cert['leaves']} leaves)", cert["wall"], None, cert["rss_mib"]),
        (f"  the same, --no-resolve ({plain['leaves']} leaves)", plain["wall"], None,
         plain["rss_mib"]),
        (f"  its cells' classification alone ({cells['cells']} cells)", cells["wall"],
         cells["seconds"], cells["rss_mib"]),
        (f"numpy grid ({grid['grid']})", grid["wall"], grid["seconds"], grid["rss_mib"]),
    ]  # fmt: skip
    print(indent(timing_rows(rows)))
    print(ratio_line("regions / numpy (processes)", cert["wall"], grid["wall"], 0.5))
    print(ratio_line("--no-resolve / numpy (processes)", plain["wall"], grid["wall"], 0.5))
    single = run_case("three-rpr-grid", params, parts, env=ONE_BLAS_THREAD)
    print(
        ratio_line("regions / numpy, its grid too on one BLAS thread", cert["wall"],
                   single["wall"], 0.5)
    )  # fmt: skip
    print(f"  (the grid on one BLAS thread takes {single['wall']:.2f} s)")
    print(ratio_line("classification alone / numpy", cells["wall"], grid["wall"], None))
    print(ratio_line("classification alone / numpy on one BLAS thread", cells["wall"],
                     single["wall"], None))  # fmt: skip
    print(
        f"  (a floor, not a target: the tree built as analyze builds it, its "
        f"{cells['cells']} cells' reaches, limits and det A\n   enclosed on intervals, "
        f"{cells['enclosures']:.2f} s of it in the enclosures, {cells['undecided']} leaves "
        f"undecided at the precision;\n   no region, connectivity, count or output)"
    )
    count = plain["count"]
    print(
        f"  --no-resolve: {len(plain['regions'])} regions listed, count "
        f"{count['at_least']}..{'?' if count['at_most'] is None else count['at_most']}"
    )
    print(agreement(cert, grid, "volume"))
    undecided = cert["undecided"]
    print(
        f"  certified run: {undecided['components']} possible region(s) without a certified "
        f"part, volume {undecided['boundary_volume']:.1f} in undecided leaves"
    )
    print()


def custom_on_box(eps: float, folder: str) -> Path:
    """examples/five-bar-custom.toml with its [bounds] the box the built-in five-bar's
    analysis subdivides: at precision ``eps`` the two analyses then split the same cells."""
    box = run_case("box", str(PAPER), eps)
    text = CUSTOM.read_text()
    text = text[: text.index("[bounds]")] + "[bounds]\n" + "".join(
        f"{name} = [{lo!r}, {hi!r}]\n"
        for name, lo, hi in zip(("x", "y"), box["lo"], box["hi"], strict=True)
    )
    path = Path(folder) / "five-bar-custom-same-box.toml"
    path.write_text(text)
    return path


def case_custom(eps: float) -> None:
    print(f"3. user-defined five-bar vs built-in, analyze at precision {eps:g} (fresh processes)")
    built = run_analysis_case(PAPER, eps)
    with tempfile.TemporaryDirectory() as folder:
        same_box = custom_on_box(eps, folder)
        run_analysis_case(same_box, 0.5)  # its derivatives in the spec cache
        custom = run_analysis_case(same_box, eps)
    rows = []
    for name, r in (("built-in five-bar", built), ("custom five-bar", custom)):
        area = r["workspace"]["area"]
        regions = ", ".join(bounds(x["area"]) for x in r["regions"])
        rows.append([
            name, f"{r['wall']:.2f}", f"{r['seconds']:.2f}", f"{r['rss_mib']:.0f}",
            str(r["leaves"]), bounds(area), regions,
        ])  # fmt: skip
    head = ["what", "process s", "analyze s", "peak MiB", "leaves", "W area", "regions"]
    print(indent(table(head, rows)))
    print(ratio_line("custom / built-in (analyze)", custom["seconds"], built["seconds"], 3.0))
    print("  (the custom spec's [bounds] set to the box the built-in subdivides: the same cells)")
    print()


def case_startup(n: int) -> None:
    print(f"4. start-up: moveability --version vs python -c 'import numpy' (best of {n})")
    mv = best_of([MOVEABILITY, "--version"], n)
    np_ = best_of([sys.executable, "-c", "import numpy"], n)
    rows = [("moveability --version", mv[0], None, mv[1]),
            ("python -c 'import numpy'", np_[0], None, np_[1])]  # fmt: skip
    print(indent(timing_rows(rows)))
    print(ratio_line("--version / import numpy", mv[0], np_[0], 3.0))
    print()


def case_scaling(five_bar: Sequence[float], rpr_parts: Sequence[int]) -> None:
    print("5. scaling of analyze (fresh process each; leaves * eps^(k-1) constant when the")
    print("   leaves follow the boundary; 3-RPR eps = the fraction of each span)")
    rows = []
    for eps in five_bar:
        rows.append(scaling_row("five-bar", PAPER, eps, eps, 1))
    params = run_case("params", str(RPR))
    for parts in rpr_parts:
        precision = span_precision(params, parts)
        rows.append(scaling_row("3-RPR", RPR, precision, 1.0 / parts, 2))
    print(indent(table(SCALING_HEAD, rows)))
    print()


SCALING_HEAD = ["mechanism", "eps", "leaves", "analyze s", "peak MiB", "regions",
                "leaves*eps^(k-1)", "s*eps^(k-1)", "us/leaf"]  # fmt: skip
#: the other mechanisms of the examples: (name, spec, precision, pose axes)
OTHERS = [
    ("biglide", EXAMPLES / "biglide.toml", 0.01, 2),
    ("custom five-bar", CUSTOM, 0.02, 2),
    ("Delta", EXAMPLES / "delta.toml", 0.03, 3),
    ("3-RRR", EXAMPLES / "three-rrr.toml", 0.2, 3),
]


def case_others(scale: float) -> None:
    print("6. the other mechanisms of the examples, analyze (fresh process each; eps the")
    print("   precision, in the pose's units)")
    rows = [
        scaling_row(name, spec, eps * scale, eps * scale, dims - 1, fraction=False)
        for name, spec, eps, dims in OTHERS
    ]
    print(indent(table(SCALING_HEAD, rows)))
    print()


def scaling_row(
    name: str, spec: Path, precision: Any, eps: float, power: int, fraction: bool = True
) -> list[str]:
    shown = f"{eps:g}" if power == 1 or not fraction else f"1/{round(1 / eps)}"
    try:
        r = run_analysis_case(spec, precision)
    except RuntimeError as error:
        return [name, shown, "failed", str(error)[-40:], "", "", "", "", ""]
    count = r["count"]
    regions = f"{count['at_least']}..{count['at_most'] or '?'}"
    if count["at_least"] == count["at_most"]:
        regions = str(count["at_least"])
    scale = eps**power
    return [
        name, shown, str(r["leaves"]), f"{r['seconds']:.2f}", f"{r['rss_mib']:.0f}", regions,
        f"{r['leaves'] * scale:.3g}", f"{r['seconds'] * scale:.3g}",
        f"{1e6 * r['seconds'] / r['leaves']:.1f}",
    ]  # fmt: skip


# ------------------------------------------------------------- main
def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    size = parser.add_mutually_exclusive_group()
    size.add_argument("--quick", action="store_true", help="small cases (under a minute)")
    size.add_argument("--full", action="store_true", help="finer scaling precisions too")
    parser.add_argument("--case", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.case:
        child(args.case[0], json.loads(args.case[1]))
        return
    start = time.perf_counter()
    # load (or, on the JIT, compile) the kernels once, untimed, so no case pays for it; the
    # same for the user-defined spec (its compiled bodies kept in the spec cache)
    run_analysis_case(PAPER, 0.5)
    run_analysis_case(CUSTOM, 0.5)
    run_analysis_case(RPR, span_precision(run_case("params", str(RPR)), 16))
    if args.quick:
        fb_eps, rpr_parts, custom_eps, n_start = 0.1, 64, 0.2, 3
        five_bar, parts, finer = [0.1, 0.05], [16, 32], [0.05]
    else:
        fb_eps, rpr_parts, custom_eps, n_start = 0.035, 256, 0.05, 5
        five_bar, parts = [0.1, 0.05, 0.02, 0.01, 0.005], [64, 128, 256]
        finer = [0.02, 0.01, 0.005]
        if args.full:
            five_bar += [0.002, 0.001]
            parts += [512]
    print(f"moveability speed benchmark ({os.cpu_count()} CPUs); times are wall seconds:")
    print("process s = the whole process, work s = the computation inside it; peak MiB =")
    print("the process' peak resident memory (ru_maxrss). Targets are printed, not asserted.")
    mode = subprocess.run(
        [sys.executable, "-c", KERNEL_MODE], capture_output=True, text=True, check=False
    ).stdout.strip()
    print(f"kernels: {mode} (make kernels builds them ahead of time)")
    print()
    case_five_bar(fb_eps)
    case_crossover(finer)
    case_three_rpr(rpr_parts)
    case_custom(custom_eps)
    case_startup(n_start)
    case_scaling(five_bar, parts)
    case_others(4.0 if args.quick else 1.0)
    print(f"total {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
