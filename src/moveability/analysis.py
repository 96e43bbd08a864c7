"""The paper's analysis, certified: regions R_j, N-connected regions W_Nj, feasibility.

:func:`analyze` subdivides the workspace box into a 2^k-tree whose leaves are
split until every posture sheet over them is certified (see
:mod:`moveability.sheets`) or the leaf is ``precision`` wide. The regions come
from :mod:`moveability.regions`; every answer is three-valued.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidParameterError, ResolutionError
from .keys import MAX_KEY_BITS
from .measurement import leaf_volumes, locate
from .mechanisms import Mechanism, from_spec
from .mechanisms.base import REGULAR
from .regions import RegionGraph, region_graph
from .sheets import SheetTable, classify_sheets
from .status import BOUNDARY, IN, OUT
from .topology import adjacency
from .tree import HyperTree, read_archive

__all__ = ["Analysis", "Region", "analyze", "load_analysis"]

Progress = Callable[[int, int, int], object]
_FORMAT = "moveability.Analysis"


def _tri(value: bool | None) -> str:
    return {True: "in", False: "out", None: "unknown"}[value]


@dataclass(frozen=True)
class Region:
    """A resolved region R_j and its projection W_Nj.

    Attributes
    ----------
    id : int
        Deterministic for a mechanism and precision.
    sign : int
        Sign of det A in the region.
    area : (float, float)
        Inner and outer bounds of the area (volume) of W_Nj.
    equals_workspace : bool or None
        Whether W_Nj = W; None where the precision cannot decide.
    postures : tuple of str
        Postures met in the certified part of the region.
    """

    id: int
    sign: int
    area: tuple[float, float]
    equals_workspace: bool | None
    postures: tuple[str, ...]
    certain: int
    possible: int


def _check_precision(precision: float | Sequence[float], k: int) -> NDArray[np.float64]:
    """Per-axis precision from one number or one per pose axis."""
    allowed = f"a positive length, or {k} of them (one per pose axis)"
    try:
        value = np.asarray(precision, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError("precision", allowed, precision) from None
    if value.ndim == 0:
        value = np.full(k, float(value))
    if value.shape != (k,) or not (np.isfinite(value).all() and (value > 0).all()):
        raise InvalidParameterError("precision", allowed, precision)
    return value


def _as_given(eps: NDArray[np.float64]) -> float | tuple[float, ...]:
    """One number when every axis has the same precision, else a tuple."""
    return float(eps[0]) if (eps == eps[0]).all() else tuple(float(v) for v in eps)


def _depths(
    lo: NDArray[np.float64], hi: NDArray[np.float64], precision: NDArray[np.float64]
) -> tuple[int, ...]:
    widths = np.asarray(hi) - np.asarray(lo)
    depths = tuple(
        int(max(0, np.ceil(np.log2(w / e)))) for w, e in zip(widths, precision, strict=True)
    )
    if sum(depths) > MAX_KEY_BITS:
        raise ResolutionError(
            "precision",
            f"a precision coarser than about {(hi - lo).max() / 2.0**(62 / len(lo)):.3g}",
            precision,
        )
    return depths


def analyze(
    mechanism: Mechanism | Mapping[str, Any] | str | os.PathLike[str],
    precision: float | Sequence[float] = 0.1,
    *,
    max_leaves: int = 1 << 23,
    progress: Progress | None = None,
    generalized_aspects: bool = False,
) -> Analysis:
    """Regions of feasible point-to-point motions of a mechanism.

    Parameters
    ----------
    mechanism : Mechanism, mapping or path
        A mechanism, or a spec (see :func:`moveability.spec.load_spec`).
    precision : float or sequence of float
        Undecided leaves are refined until at most this wide (pose units: lengths
        and radians); one number, or one per pose axis.
    max_leaves : int
        Fail with :class:`~moveability.ResolutionError` rather than hold more leaves.
    progress : callable, optional
        Called as ``progress(level, n_split, n_leaves)`` while the tree grows.
    generalized_aspects : bool, optional
        Forbid serial singularities as well (det A != 0 and det B != 0): the
        regions are then the generalized aspects, in which the posture never
        changes.

    Examples
    --------
    >>> from moveability import analyze
    >>> from moveability.mechanisms import FiveBar
    >>> result = analyze(FiveBar(7, 8, 5, 8, 5), precision=0.5)
    >>> len(result.regions), result.n_connected
    (2, False)
    """
    if not isinstance(mechanism, Mechanism):
        from .spec import load_spec

        mechanism = from_spec(load_spec(mechanism))
    eps = _check_precision(precision, len(mechanism.pose_names))
    lo, hi = mechanism.pose_box()
    depths = _depths(lo, hi, eps)

    def classify(cell_lo: NDArray[np.float64], cell_hi: NDArray[np.float64]) -> NDArray[np.uint8]:
        table = classify_sheets(mechanism, cell_lo, cell_hi)
        dead = (table.status == OUT).all(axis=1)
        return np.where(dead, OUT, np.where(table.decided(), IN, BOUNDARY)).astype(np.uint8)

    n_levels = max(depths)

    def watch(level: int, n_split: int, n_leaves: int) -> None:
        # undecided cells follow curves in W: their number about doubles per level,
        # so a precision that cannot fit is refused early, not after filling memory
        remaining = n_levels - level - 1
        if remaining > 0 and n_leaves + n_split * 4.0 * (2.0**remaining - 1) > 4 * max_leaves:
            raise ResolutionError("max_depth", "a tree that fits", n_split)
        if progress is not None:
            progress(level, n_split, n_leaves)

    # no merging: a parent is not certified by its children's certificates
    try:
        tree = HyperTree.build(
            lo,
            hi,
            classify,
            max_depth=depths,
            periodic=mechanism.periodic_axes,
            max_leaves=max_leaves,
            progress=watch,
            merge=False,
        )
    except ResolutionError:
        raise ResolutionError(
            "precision",
            f"a precision whose tree holds at most max_leaves={max_leaves} leaves",
            precision,
        ) from None
    return Analysis(mechanism, _as_given(eps), tree, generalized_aspects=generalized_aspects)


class Analysis:
    """Result of :func:`analyze`: regions, workspace, point queries.

    The tree's leaves are IN where every sheet is decided, OUT where no valid
    configuration exists, BOUNDARY where undecided at the precision.
    """

    def __init__(
        self,
        mechanism: Mechanism,
        precision: float | Sequence[float],
        tree: HyperTree,
        generalized_aspects: bool = False,
    ) -> None:
        self.mechanism = mechanism
        self.generalized_aspects = bool(generalized_aspects)
        #: per pose axis
        self.precisions = _check_precision(precision, len(mechanism.pose_names))
        #: as given: one number, or one per pose axis
        self.precision = _as_given(self.precisions)
        self.tree = tree
        leaves = tree.leaves()
        self.table: SheetTable = classify_sheets(mechanism, leaves.lo, leaves.hi)
        self.areas = leaf_volumes(tree)
        live = np.flatnonzero(tree.status != OUT)
        pairs = adjacency(tree, status=IN | BOUNDARY, connectivity=tree.ndim)
        self._n_live = live.size
        self.graph: RegionGraph = region_graph(
            self.table,
            pairs,
            mechanism.postures,
            cross_serial=not self.generalized_aspects,
            limits=mechanism.limits,
        )
        self._resolve()

    @property
    def precision_text(self) -> str:
        """The precision for titles and summaries (``0.1`` or ``0.1, 0.1, 0.02``)."""
        return ", ".join(f"{v:g}" for v in np.atleast_1d(self.precision))

    # ------------------------------------------------------------ regions
    def _resolve(self) -> None:
        g, t = self.graph, self.table
        n_post = t.status.shape[1]
        # certain component -> possible component of its sign
        self._certain_to_possible = np.full(g.certain_sign.size, -1, dtype=np.int64)
        for row, s in enumerate((1, -1)):
            mask = (g.certain >= 0) & (t.sign == s)
            # a certified node lies within the limits: one piece, its first sub-node
            self._certain_to_possible[g.certain[mask]] = g.possible[row][:, :: g.slots][mask]
        # each possible component holding certified parts is one region (distinct
        # possible components hold distinct regions); its largest certified part
        # represents it, the others may or may not belong to it
        sizes = np.bincount(g.certain[g.certain >= 0], minlength=g.certain_sign.size)
        regions: list[tuple[int, int, int]] = []  # (first node, certain, row * 2^40 + possible)
        self._unresolved: list[tuple[int, int]] = []
        self._extra_certain: list[int] = []
        for row, s in enumerate((1, -1)):
            for u in range(g.n_possible[row]):
                inside = np.flatnonzero((g.certain_sign == s) & (self._certain_to_possible == u))
                if not inside.size:
                    self._unresolved.append((row, u))
                    continue
                c = int(inside[np.argmax(sizes[inside])])
                self._extra_certain.extend(int(x) for x in inside if x != c)
                first = int(np.flatnonzero(g.certain.ravel() == c)[0])
                regions.append((first, c, row * (1 << 40) + u))
        regions.sort()
        certified_leaf_in = t.status == IN
        w_certain = (t.exists & t.within).any(axis=1)  # whole leaf in W
        w_possible = (t.status != OUT).any(axis=1)
        self._w_certain, self._w_possible = w_certain, w_possible
        self.regions: list[Region] = []
        self._region_nodes: list[tuple[int, int, int]] = []  # (certain id, row, possible id)
        for rid, (_, c, code) in enumerate(regions):
            row, u = divmod(code, 1 << 40)
            in_c = g.certain == c
            inner = float(self.areas[(in_c & certified_leaf_in).any(axis=1)].sum())
            touch = (g.possible[row] == u).any(axis=1)
            outer = float(self.areas[touch].sum())
            covered = (in_c & ((t.status == IN) | t.group)).any(axis=1)
            if not (w_possible & ~covered).any():
                equals: bool | None = True
            elif (w_certain & ~touch).any():
                equals = False
            else:
                equals = None
            used = np.flatnonzero(in_c.any(axis=0))
            self.regions.append(
                Region(
                    id=rid,
                    sign=(1, -1)[row],
                    area=(inner, outer),
                    equals_workspace=equals,
                    postures=tuple(self.mechanism.posture_name(int(p)) for p in used),
                    certain=c,
                    possible=u,
                )
            )
            self._region_nodes.append((c, row, u))
        del n_post

    @property
    def measure_name(self) -> str:
        """What the measures of sets of poses are: ``area`` (2 pose axes), ``volume`` (3)."""
        return {1: "length", 2: "area", 3: "volume"}.get(self.tree.ndim, "measure")

    @property
    def workspace(self) -> dict[str, tuple[float, float]]:
        """Bounds on the area (volume) of the workspace W, keyed by :attr:`measure_name`."""
        return {
            self.measure_name: (
                float(self.areas[self._w_certain].sum()),
                float(self.areas[self._w_possible].sum()),
            )
        }

    @property
    def undecided(self) -> dict[str, float | int]:
        """What the precision left open.

        ``components``: possible components with no certified part (a region
        may or may not hide there), with the ``area`` of the leaves they touch;
        ``detached``: certified parts whose region is not known (they lie in a
        listed region's possible part but may belong to another region hiding
        there); ``boundary_area``: area of the leaves left undecided. With three
        pose axes the keys say ``volume`` for ``area``.
        """
        g = self.graph
        touch = np.zeros(self.areas.size, dtype=bool)
        for row, u in self._unresolved:
            touch |= (g.possible[row] == u).any(axis=1)
        undecided_leaves = self.tree.status == BOUNDARY
        measure = self.measure_name
        return {
            "components": len(self._unresolved),
            measure: float(self.areas[touch].sum()),
            "detached": len(self._extra_certain),
            f"boundary_{measure}": float(self.areas[undecided_leaves].sum()),
        }

    @property
    def n_connected(self) -> bool | None:
        """Whether W is N-connected: some W_Nj equals W."""
        if any(r.equals_workspace for r in self.regions):
            return True
        g = self.graph
        # every possible component misses a leaf certainly in W
        for row in (0, 1):
            for u in range(g.n_possible[row]):
                touch = (g.possible[row] == u).any(axis=1)
                if not (self._w_certain & ~touch).any():
                    return None
        return False

    # ------------------------------------------------------------- points
    def _points(self, points: ArrayLike) -> NDArray[np.float64]:
        k = len(self.mechanism.pose_names)
        try:
            p = np.asarray(points, dtype=np.float64)
        except (TypeError, ValueError):
            raise InvalidParameterError(
                "points", f"an array of poses ({k} numbers each)", points
            ) from None
        if p.ndim == 1:
            p = p.reshape(1, -1)
        if p.ndim != 2 or p.shape[1] != k:
            raise InvalidParameterError("points", f"an array of shape (m, {k})", p.shape)
        bad = ~np.isfinite(p).all(axis=1)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise InvalidParameterError(f"points[{i}]", "finite coordinates", p[i].tolist())
        return self.mechanism.wrap_poses(p)

    def _point_table(self, p: NDArray[np.float64]) -> SheetTable:
        """Sheet certificates at the points themselves (degenerate boxes)."""
        return classify_sheets(self.mechanism, p, p)

    def _locate_leaves(self, p: NDArray[np.float64]) -> tuple[NDArray[np.uint8], NDArray[np.intp]]:
        return locate(self.tree, p)

    def plan(self, points: ArrayLike, step: float | None = None) -> dict[str, Any]:
        """A continuous motion through the poses in order, inside one region.

        Consecutive configurations are at most ``step`` (default: the precision)
        apart in pose and in each joint; every configuration satisfies the
        constraints, keeps the region's sign of det A and respects the limits.
        Raises :class:`moveability.planning.PlanningError` (exit 3 in the CLI)
        when no region is known to hold every pose.

        Examples
        --------
        >>> from moveability import analyze
        >>> from moveability.mechanisms import FiveBar
        >>> result = analyze(FiveBar(), precision=0.2)
        >>> motion = result.plan([[1.0, 3.0], [5.0, 3.0]])
        >>> motion["feasible"], motion["path"][0]["pose"]
        (True, [1.0, 3.0])
        """
        from .planning import plan_motion

        return plan_motion(self, self._points(points), step)

    def _point_answers(
        self, p: NDArray[np.float64]
    ) -> tuple[NDArray[np.int8], NDArray[np.int8], NDArray[np.intp]]:
        """Workspace answer (1 in, 0 out, -1 unknown), region answers (m, R), leaves."""
        m = p.shape[0]
        _, leaf = locate(self.tree, p)
        point_table = classify_sheets(self.mechanism, p, p)
        ws = np.full(m, -1, dtype=np.int8)
        ws[(point_table.exists & point_table.within).any(axis=1)] = 1
        ws[(point_table.status == OUT).all(axis=1)] = 0
        answers = np.full((m, len(self.regions)), -1, dtype=np.int8)
        inside_box = leaf >= 0
        lf = np.where(inside_box, leaf, 0)
        g, t = self.graph, self.table
        point_regular = (point_table.leg_status == REGULAR).all(axis=1)
        for j, (c, row, u) in enumerate(self._region_nodes):
            nodes_c = g.certain[lf] == c
            sure = (nodes_c & (t.status[lf] == IN)).any(axis=1)
            sure |= (nodes_c & t.group[lf]).any(axis=1) & point_regular
            touch = (g.possible[row][lf] == u).any(axis=1)
            # a pose outside the box is outside W (the box holds W); unless the pose
            # itself is certified out, say so only through `ws` below
            answers[:, j] = np.where(sure & inside_box, 1, np.where(~touch & inside_box, 0, -1))
        answers[ws == 0] = 0
        return ws, answers, np.where(inside_box, leaf, -1)

    def locate(self, points: ArrayLike) -> dict[str, Any]:
        """Workspace and region membership of each pose, as a JSON-ready dict.

        Examples
        --------
        >>> from moveability import analyze
        >>> from moveability.mechanisms import FiveBar
        >>> result = analyze(FiveBar(), precision=0.5)
        >>> result.locate([[3.5, 9.0]])["points"][0]["workspace"]
        'in'
        """
        p = self._points(points)
        ws, answers, _ = self._point_answers(p)
        names = {1: "in", 0: "out", -1: "unknown"}
        return {
            "regions": [r.id for r in self.regions],
            "points": [
                {
                    "pose": [float(v) for v in p[i]],
                    "workspace": names[int(ws[i])],
                    "regions": {
                        str(r.id): names[int(answers[i, j])] for j, r in enumerate(self.regions)
                    },
                }
                for i in range(p.shape[0])
            ],
        }

    def feasible(self, points: ArrayLike) -> dict[str, Any]:
        """Whether one region holds a configuration of every pose, with witnesses.

        Returns ``{"feasible": true|false|null, "region": id|null,
        "postures": [[t1, t2], ...]|null}``; the postures are joint angles of one
        valid configuration per pose in that region.
        """
        p = self._points(points)
        ws, answers, leaf = self._point_answers(p)
        for j, region in enumerate(self.regions):
            if (answers[:, j] == 1).all():
                return {
                    "feasible": True,
                    "region": region.id,
                    "postures": self._witnesses(p, leaf, j),
                }
        if (ws == 0).any():
            return {"feasible": False, "region": None, "postures": None}
        if (leaf < 0).any():
            # a pose outside the box that the pose-level test could not place
            return {"feasible": None, "region": None, "postures": None}
        g = self.graph
        for row in (0, 1):
            for u in range(g.n_possible[row]):
                if (g.possible[row][leaf] == u).any(axis=1).all():
                    return {"feasible": None, "region": None, "postures": None}
        return {"feasible": False, "region": None, "postures": None}

    def _witnesses(
        self, p: NDArray[np.float64], leaf: NDArray[np.intp], j: int
    ) -> list[list[float]]:
        c = self._region_nodes[j][0]
        g, t = self.graph, self.table
        # the poses are certified reachable: clip the rounding of the closed form
        joints = self.mechanism.joint_angles(p, clip=True)
        out = []
        for i in range(p.shape[0]):
            ok = (g.certain[leaf[i]] == c) & ((t.status[leaf[i]] == IN) | t.group[leaf[i]])
            ok &= np.isfinite(joints[i]).all(axis=1)
            posture = int(np.flatnonzero(ok)[0])
            q = [
                float(lim.wrap(v))
                for lim, v in zip(self.mechanism.limits, joints[i, posture], strict=True)
            ]
            out.append(q)
        return out

    # -------------------------------------------------------------- output
    def to_dict(self) -> dict[str, Any]:
        """The summary as a JSON-ready dict (the ``regions --json`` document)."""
        measure = self.measure_name
        return {
            "precision": (
                list(self.precision) if isinstance(self.precision, tuple) else self.precision
            ),
            "pose": list(self.mechanism.pose_names),
            "workspace": {measure: list(self.workspace[measure])},
            "regions": [
                {
                    "id": r.id,
                    measure: list(r.area),
                    "equals_workspace": r.equals_workspace,
                    "sign": r.sign,
                    "postures": list(r.postures),
                }
                for r in self.regions
            ],
            "n_connected": self.n_connected,
            "generalized_aspects": self.generalized_aspects,
            "undecided": self.undecided,
            "mechanism": self.mechanism.name,
            "leaves": len(self.tree),
        }

    def summary(self) -> str:
        """A readable summary."""
        measure = self.measure_name
        w = self.workspace[measure]
        lines = [
            f"{self.mechanism!r}",
            f"precision {self.precision_text}: {len(self.tree)} leaves",
            f"workspace {measure} in [{w[0]:.4f}, {w[1]:.4f}]",
            f"{len(self.regions)} region(s):",
        ]
        for r in self.regions:
            eq = {True: "yes", False: "no", None: "unknown"}[r.equals_workspace]
            lines.append(
                f"  region {r.id}: det A {'>' if r.sign > 0 else '<'} 0, {measure} in "
                f"[{r.area[0]:.4f}, {r.area[1]:.4f}], postures {', '.join(r.postures)}, "
                f"equals W: {eq}"
            )
        u = self.undecided
        lines.append(
            f"undecided: {u['components']} component(s) without certified part, "
            f"{u['detached']} detached certified part(s), "
            f"{u[f'boundary_{measure}']:.4f} of {measure} in undecided leaves"
        )
        nc = {True: "yes", False: "no", None: "unknown"}[self.n_connected]
        lines.append(f"W N-connected: {nc}")
        return "\n".join(lines)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Analysis:
        """Read an analysis written by :meth:`save` (see :func:`load_analysis`)."""
        return load_analysis(path)

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the analysis (mechanism spec, precision, tree) to a ``.npz`` file."""
        np.savez_compressed(
            path,
            format=np.array(_FORMAT),
            spec=np.array(json.dumps(self.mechanism.to_spec())),
            precision=self.precisions,
            generalized_aspects=np.array(self.generalized_aspects),
            lo=self.tree.lo,
            hi=self.tree.hi,
            max_depth=np.asarray(self.tree.max_depth),
            keys=self.tree.keys,
            levels=self.tree.levels,
            status=self.tree.status,
        )


def load_analysis(path: str | os.PathLike[str]) -> Analysis:
    """Read an analysis written by :meth:`Analysis.save` (the sheets are re-certified)."""
    fields = read_archive(path, "a file written by Analysis.save")
    if str(fields.get("format", "")) != _FORMAT:
        raise InvalidParameterError("path", "a file written by Analysis.save", os.fspath(path))
    mechanism = from_spec(json.loads(str(fields["spec"])))
    tree = HyperTree(
        fields["lo"],
        fields["hi"],
        tuple(int(d) for d in fields["max_depth"]),
        fields["keys"],
        fields["levels"],
        fields["status"],
        mechanism.periodic_axes,
    )
    aspects = bool(fields["generalized_aspects"]) if "generalized_aspects" in fields else False
    precision = np.atleast_1d(np.asarray(fields["precision"], dtype=np.float64))
    return Analysis(mechanism, _as_given(precision), tree, generalized_aspects=aspects)
