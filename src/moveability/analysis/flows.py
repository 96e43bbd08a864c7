"""Flows along pose axes: the certificate that no region hides in the undecided cells.

A region R_j is *hidden* when none of its configurations lies on a certified
sheet: nothing in the certain graph stands for it, so a count of the certified
parts says nothing of it. This module proves that no region is hidden in a
node (leaf, posture) that is not certified, one sign of det A at a time.

A node *flows* along a direction ``+e_k`` or ``-e_k`` of the pose box when,
over the whole leaf, moving a pose along that direction never makes a valid
configuration of the node invalid:

* det A is certainly of the sign, or (every leg regular) its derivative along
  the sheet in that direction is certainly of the sign (so |det A| never
  decreases);
* each joint whose enclosure may hold a lower stop never decreases, each one
  that may hold an upper stop never increases (both: no flow);
* a leg that may fold (a serial singularity in the leaf) stays reachable in
  that direction (the leg's ``fold_flow``), its joint is certainly within
  its limits and det A is certainly of the sign; the configurations of its
  branch vary continuously up to the fold. The leg's distance to its reach
  limit then never decreases, so a configuration off the fold (det B != 0, as
  every one of a generalized aspect) stays off it: the same flow serves
  generalized aspects, where no posture may change.

From any valid configuration of such a node, the ray along the direction then
stays valid until it leaves the leaf through the face on that side, where the
configuration is a valid one of the same posture over a leaf across the face.
A node is *attached* when it flows along a direction across which every leaf
holds, for that posture and sign, a certified sheet, a node with no valid
configuration of the sign, or a node attached before it. By induction on the
order of attachment every valid configuration of an attached node joins a
certified sheet by a path of valid configurations: its region is not hidden.
A face on the edge of the (non-periodic) pose box attaches nothing.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..compiled import kernel
from ..hypertree.status import BOUNDARY, IN
from ..hypertree.topology import adjacency
from ..hypertree.tree import HyperTree
from ..intervals import Interval
from ..mechanisms.base import REACH_OUT, REACH_UNKNOWN, REGULAR, Mechanism
from ..types import Array
from .regions import split_legs
from .sheets import SheetTable

__all__ = [
    "Attachment",
    "FaceNeighbours",
    "attached_nodes",
    "dead_or_certified",
    "doubled",
    "face_neighbours",
    "flow_conditions",
    "flow_directions",
    "into_corner",
    "slot_spans",
    "supports_flows",
]

#: slack when comparing joint ranges of slots (as in :mod:`moveability.analysis.regions`)
_SPAN_TOL = 1e-9
#: constraints whose enclosure, grown this many times about its midpoint, meets
#: their bound count as near a leaf when its own direction is chosen: the leaves
#: of a cluster around a corner (two stops and the singular surface of a 3-RPR
#: span about ten leaves) then share one direction and never wait on each other
_NEAR = 16.0


class FaceNeighbours:
    """Leaves across each face of each leaf.

    Direction ``2 k`` is ``+e_k`` and ``2 k + 1`` is ``-e_k``. ``pairs[d]`` is an
    (m, 2) array of leaf indices ``(a, b)``: ``b`` lies across ``a``'s face in
    direction ``d`` (only leaves that are not OUT are listed). ``open[a, d]`` says
    that face lies on the edge of the pose box.
    """

    def __init__(
        self,
        pairs: list[NDArray[np.int64]],
        open_faces: NDArray[np.bool_],
        flat: tuple[NDArray[np.int64], NDArray[np.int64]] | None = None,
    ) -> None:
        self.pairs = pairs
        self.open = open_faces
        #: all the pairs, direction by direction, and where each direction's start
        #: (``pairs[d]`` is ``flat[0][flat[1][d]:flat[1][d + 1]]``), when known
        self.flat = flat


def face_neighbours(tree: HyperTree, pairs: NDArray[np.intp] | None = None) -> FaceNeighbours:
    """Face neighbours of the leaves of ``tree`` that are not OUT, with their side.

    ``pairs``, when given, are those leaves' face-adjacent pairs
    (``adjacency(tree, status=IN | BOUNDARY, connectivity=1)``), known already.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability import HyperTree
    >>> tree = HyperTree.from_array(np.ones((2, 2), dtype=bool), merge=False)
    >>> faces = face_neighbours(tree)
    >>> faces.pairs[0].tolist(), faces.open[0].tolist()  # across +x; leaf 0's faces
    ([[0, 2], [1, 3]], [False, True, False, True])
    """
    k = tree.ndim
    if pairs is None:
        pairs = adjacency(tree, status=IN | BOUNDARY, connectivity=1)
    anchors = tree.anchors
    sizes = tree.layout.cell_sizes(tree.levels)
    extent = np.left_shift(np.int64(1), np.asarray(tree.max_depth, dtype=np.int64))
    periodic = np.zeros(k, dtype=bool)
    periodic[list(tree.periodic)] = True
    ends = anchors + sizes
    open_faces = np.zeros((len(tree), 2 * k), dtype=bool)
    for axis in range(k):
        if not periodic[axis]:
            open_faces[:, 2 * axis] = ends[:, axis] == extent[axis]
            open_faces[:, 2 * axis + 1] = anchors[:, axis] == 0
    flat, ptr = _face_sides(
        np.ascontiguousarray(pairs.reshape(-1, 2), dtype=np.int64),
        np.ascontiguousarray(anchors, dtype=np.int64),
        np.ascontiguousarray(ends, dtype=np.int64),
        extent,
        periodic,
    )
    out = [flat[ptr[d] : ptr[d + 1]] for d in range(2 * k)]
    return FaceNeighbours(out, open_faces, (flat, ptr))


@kernel
def _face_sides(
    pairs: NDArray[np.int64],
    anchors: NDArray[np.int64],
    ends: NDArray[np.int64],
    extent: NDArray[np.int64],
    periodic: NDArray[np.bool_],
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:  # pragma: no cover - compiled
    """The face-adjacent pairs ``(a, b)`` (each pair both ways: all of them as
    given, then all reversed) by the side of ``a`` that ``b`` lies across:
    ``(flat, ptr)``, direction ``d``'s pairs being ``flat[ptr[d]:ptr[d + 1]]``,
    in that order."""
    m = pairs.shape[0]
    k = anchors.shape[1]
    # per pair, bit d: b lies across a's side d (as given); reversed, the sides of
    # each axis swap. One pass over the leaves' cells, counting each side's
    # pairs, then one over the bits.
    sides = np.zeros(m, dtype=np.int64)
    count = np.zeros(2 * k, dtype=np.int64)
    for e in range(m):
        a = pairs[e, 0]
        b = pairs[e, 1]
        bits = 0
        for axis in range(k):
            end_a = ends[a, axis]
            end_b = ends[b, axis]
            if periodic[axis]:
                end_a = end_a % extent[axis]
                end_b = end_b % extent[axis]
            # +e_axis: b starts where a ends; -e_axis: a starts where b ends
            if end_a == anchors[b, axis]:
                bits |= 1 << (2 * axis)
            if anchors[a, axis] == end_b:
                bits |= 1 << (2 * axis + 1)
        sides[e] = bits
        for d in range(2 * k):
            # reversed, side 2 axis and 2 axis + 1 trade places
            count[d] += ((bits >> d) & 1) + ((bits >> (d ^ 1)) & 1)
    ptr = np.zeros(2 * k + 1, dtype=np.int64)
    for d in range(2 * k):
        ptr[d + 1] = ptr[d] + count[d]
    flat = np.empty((ptr[2 * k], 2), dtype=np.int64)
    count[:] = 0
    for half in range(2):
        for e in range(m):
            bits = sides[e]
            if not bits:
                continue
            a = pairs[e, half]
            b = pairs[e, 1 - half]
            for d in range(2 * k):
                if not (bits >> (d ^ half)) & 1:
                    continue
                flat[ptr[d] + count[d], 0] = a
                flat[ptr[d] + count[d], 1] = b
                count[d] += 1
    return flat, ptr


def supports_flows(mechanism: Mechanism) -> bool:
    """Whether the legs give the rates that flows need (``joint_gradient`` and
    ``row_partials``); without them no node is attached and no count bounded
    above."""
    return all(
        hasattr(leg, "joint_gradient") and hasattr(leg, "row_partials") for leg in mechanism.legs
    )


def flow_directions(k: int) -> tuple[NDArray[np.float64], list[list[int]]]:
    """The constant directions tried, and the faces through which each leaves a box.

    The ``2 k`` axis directions, then every diagonal of two axes (``+-e_i +- e_j``):
    a ray along a diagonal leaves the box through one of two faces.

    Examples
    --------
    >>> vectors, faces = flow_directions(2)
    >>> vectors.tolist()[4], faces[4]
    ([1.0, 1.0], [0, 2])
    """
    vectors: list[NDArray[np.float64]] = []
    faces: list[list[int]] = []
    for axis in range(k):
        for step in (1.0, -1.0):
            v = np.zeros(k)
            v[axis] = step
            vectors.append(v)
            faces.append([2 * axis + int(step < 0)])
    for i in range(k):
        for j in range(i + 1, k):
            for si in (1.0, -1.0):
                for sj in (1.0, -1.0):
                    v = np.zeros(k)
                    v[i], v[j] = si, sj
                    vectors.append(v)
                    faces.append([2 * i + int(si < 0), 2 * j + int(sj < 0)])
    return np.array(vectors), faces


def _exit_faces(low: list[Array], high: list[Array]) -> NDArray[np.uint8]:
    """Faces a flow may leave a box through, from bounds of its velocity on each
    axis: bit ``2 k`` where it may rise along axis k, ``2 k + 1`` where it may fall."""
    mask = np.zeros(np.shape(low[0]), dtype=np.uint8)
    for axis, (lo, hi) in enumerate(zip(low, high, strict=True)):
        mask |= np.where(hi > 0, 1 << (2 * axis), 0).astype(np.uint8)
        mask |= np.where(lo < 0, 1 << (2 * axis + 1), 0).astype(np.uint8)
    return mask


def _dot(values: list[Interval], velocity: list[Interval]) -> Interval:
    """``sum_k values[k] * velocity[k]``."""
    total = values[0] * velocity[0]
    for a, b in zip(values[1:], velocity[1:], strict=True):
        total = total + a * b
    return total


class _Field:
    """A flow over boxes: its velocity, the faces it may leave through, and the leg
    it turns rigidly (with that leg's joint rate), if any. A constant direction
    keeps its ``vector`` alone: its velocity over the boxes is made when asked
    for (the fields of many boxes then hold no arrays of velocities)."""

    def __init__(
        self,
        velocity: list[Interval] | None,
        faces: NDArray[np.uint8],
        vector: NDArray[np.float64] | None = None,
        leg: int = -1,
        turn: float = 0.0,
        usable: NDArray[np.bool_] | None = None,
    ) -> None:
        self._velocity = velocity
        self.faces = faces
        self.vector = vector
        self.leg = leg
        self.turn = turn
        self.usable = usable

    @property
    def velocity(self) -> list[Interval]:
        """One enclosure per pose axis over the boxes."""
        if self._velocity is not None:
            return self._velocity
        assert self.vector is not None
        n = self.faces.shape[0]
        return [Interval(np.full(n, v)) for v in self.vector]


#: the groups of rows of one leg's branches: ``(branch, rows)``, ``rows`` None for all
_Groups = list[tuple[int, NDArray[np.intp] | None]]


def _take(x: Any, at: NDArray[np.intp] | None) -> Any:
    """``x`` (an array or :class:`Interval` over rows) at the rows ``at`` (None: all);
    a number as it is."""
    return x if at is None or isinstance(x, (int, float)) else x[at]


def _branch_groups(branches: NDArray[np.int64]) -> _Groups:
    """The rows of each branch in ``branches`` (one per row), in increasing order of
    branch; one group of all the rows (None) when they share one branch.

    Examples
    --------
    >>> [(b, None if at is None else at.tolist()) for b, at in _branch_groups(np.array([1, 0, 1]))]
    [(0, [1]), (1, [0, 2])]
    >>> _branch_groups(np.array([1, 1]))
    [(1, None)]
    """
    # (np.unique would import numpy.ma, some milliseconds, on its first call)
    values = np.flatnonzero(np.bincount(branches))
    if values.size == 1:
        return [(int(values[0]), None)]
    return [(int(b), np.flatnonzero(branches == b)) for b in values]


def _joined(parts: list[tuple[NDArray[np.intp] | None, Any]], n: int) -> Any:
    """Results over groups of rows (``(rows, result)``; arrays, :class:`Interval`\\ s,
    lists or tuples of them, one value per row or one for all) put together over
    ``n`` rows, each row's from its group (rows of no group: zero)."""
    if len(parts) == 1 and parts[0][0] is None:
        return parts[0][1]
    first = parts[0][1]
    if isinstance(first, Interval):
        return Interval(
            _joined([(at, v.lo) for at, v in parts], n), _joined([(at, v.hi) for at, v in parts], n)
        )
    if isinstance(first, (list, tuple)):
        return type(first)(
            _joined([(at, v[j]) for at, v in parts], n) for j in range(len(first))
        )
    values = [np.asarray(v) for _, v in parts]
    out = np.zeros(n, dtype=np.result_type(*values))
    for (at, _), v in zip(parts, values, strict=True):
        out[slice(None) if at is None else at] = v
    return out


def _by_branch(groups: _Groups, n: int, call: Any) -> Any:
    """``call(branch, rows)`` once per group of rows (see :func:`_branch_groups`),
    the results put together row by row (:func:`_joined`)."""
    return _joined([(at, call(b, at)) for b, at in groups], n)


def _fields(
    mechanism: Mechanism,
    lo: Array,
    hi: Array,
    angles: list[Interval] | None = None,
    groups: list[_Groups] | None = None,
    axes_only: bool = False,
) -> list[_Field]:
    """Constant directions, then turns about the legs' turn centres (planar poses;
    ``angles`` are the joints' enclosures over the boxes and ``groups`` the rows
    of each leg's branches, for centres that move with the joint). With
    ``axes_only`` the ``2 k`` directions along the pose axes alone (the first)."""
    n, k = lo.shape
    vectors, faces = flow_directions(k)
    if axes_only:
        vectors, faces = vectors[: 2 * k], faces[: 2 * k]
    out = []
    for vector, fl in zip(vectors, faces, strict=True):
        mask = np.full(n, sum(1 << f for f in fl), dtype=np.uint8)
        out.append(_Field(None, mask, vector=vector))
    if k not in (2, 3) or axes_only:
        return out
    for i, leg in enumerate(mechanism.legs):
        if not hasattr(leg, "turn_centre") or len(leg.turn_centre(Interval(lo[:0, 0]))) != 2:
            continue
        angle = angles[i] if angles is not None else Interval(np.zeros(n))
        centre = leg.turn_centre(angle)
        if hasattr(leg, "turn_arm") and groups is not None:
            rel_x, rel_y = _by_branch(
                groups[i],
                n,
                lambda b, at, leg=leg, angle=angle: leg.turn_arm(
                    _take(lo, at), _take(hi, at), b, _take(angle, at)
                ),
            )
        else:
            rel_x = Interval(lo[:, 0], hi[:, 0]) - centre[0]
            rel_y = Interval(lo[:, 1], hi[:, 1]) - centre[1]
        # the orbit of a pose leaves a box that does not hold the centre
        outside = (
            (centre[0].hi < lo[:, 0])
            | (centre[0].lo > hi[:, 0])
            | (centre[1].hi < lo[:, 1])
            | (centre[1].lo > hi[:, 1])
        )
        if k == 3:
            # the platform (x, y, phi) turns about the point: phi turns with it, and
            # leaves a box narrower than a turn
            outside = (hi[:, 2] - lo[:, 2]) < np.pi
        for turn in (1.0, -1.0):
            velocity = [-rel_y * turn, rel_x * turn]
            if k == 3:
                velocity.append(Interval(np.full(n, turn)))
            mask = _exit_faces([v.lo for v in velocity], [v.hi for v in velocity])
            out.append(_Field(velocity, mask, leg=i, turn=turn, usable=outside))
    return out


def flow_conditions(
    mechanism: Mechanism,
    lo: Array,
    hi: Array,
    table: SheetTable,
    nodes: NDArray[np.intp],
    axes_only: bool = False,
) -> tuple[NDArray[np.uint64], NDArray[np.bool_], NDArray[np.uint8]]:
    """Where the pieces of some nodes flow.

    ``nodes`` is an (m, 2) array of (leaf, posture); ``lo``, ``hi`` and ``table``
    describe all the leaves. A node's configurations are split by the piece of
    each limited joint's range they lie in (its *slots*, as in
    :func:`moveability.analysis.regions.region_graph`). The flows tried are the
    directions of :func:`flow_directions` and, for planar poses, the turns about
    each leg's ``turn_centre`` (both senses): a turn keeps that leg's reach and
    moves its joint at the leg's ``turn_rate`` (the base of an RR leg: the leg
    turns rigidly; the slider of a biglide leg: it stays), even where the leg
    folds, on the branch where ``turn_keeps`` says so.

    Where every leg is regular, one more flow per slot and sign follows the
    constraints that may be active in the leaf: its direction is the sum of
    their unit normals at the leaf's centre (det A of the sign, joints away from
    the stops inside the slot), checked over the whole leaf like the others.
    It settles corners where two constraint curves cross at a sharp angle.

    With ``axes_only`` only the flows along the ``2 k`` pose axes are tried (the
    first ``2 k`` bits; the others are left clear): most nodes attach along an
    axis, and :func:`attached_nodes` is monotone in the flows, so the caller may
    try the rest on the nodes left open alone and attach exactly the nodes that
    every flow would.

    Returns
    -------
    flows : (2, m, slots) uint64
        Bit ``f`` set where the slot flows along flow ``f``; index 0 is
        det A > 0, 1 det A < 0.
    exists : (m, slots) bool
        The slots that may hold configurations.
    faces : (F, m) uint8
        Bit ``j`` set where flow ``f`` may leave the node's leaf through face ``j``.
    """
    slots = 1 << len(split_legs(mechanism.limits))
    m = nodes.shape[0]
    if not m:
        # the fixed flows are the same for every leaf: count them on no leaf at all
        n_flows = len(_fields(mechanism, lo[:0], hi[:0])) + 2 * slots
        return (
            np.zeros((2, 0, slots), dtype=np.uint64),
            np.zeros((0, slots), dtype=bool),
            np.zeros((n_flows, 0), dtype=np.uint8),
        )
    return _node_flows(mechanism, lo, hi, table, nodes, axes_only)


#: margins not yet enclosed (see :func:`_node_flows`)
_UNSET: Any = object()


def _bit(flags: NDArray[np.bool_], index: int) -> NDArray[np.uint64]:
    """Bit ``index`` (below 64) set where ``flags`` hold.

    Examples
    --------
    >>> _bit(np.array([True, False]), 3).tolist()
    [8, 0]
    """
    return np.left_shift(np.asarray(flags, dtype=np.uint64), np.uint64(index))


def _posture_any(
    mask: NDArray[np.bool_], group: NDArray[np.intp], n_groups: int
) -> NDArray[np.bool_]:
    """Per row: whether ``mask`` holds on some row of its group (``group[r]`` in
    ``range(n_groups)``).

    Examples
    --------
    >>> _posture_any(np.array([True, False, False]), np.array([0, 0, 1]), 2).tolist()
    [True, True, False]
    """
    hit = np.zeros(n_groups, dtype=bool)
    hit[group[mask]] = True
    return hit[group]


def _node_flows(
    mechanism: Mechanism,
    lo: Array,
    hi: Array,
    table: SheetTable,
    nodes: NDArray[np.intp],
    axes_only: bool = False,
    margins: Any = _UNSET,
) -> tuple[NDArray[np.uint64], NDArray[np.bool_], NDArray[np.uint8]]:
    """The flows of the nodes ``nodes`` ((m, 2): leaf, posture; at least one), as
    :func:`flow_conditions` returns them: ``(bits (2, m, slots), exists (m,
    slots), faces (F, m))``; with ``axes_only`` the flows along the pose axes
    alone (the others clear).

    One pass over the nodes of every posture: each node takes its own posture's
    joint enclosures, sign and det A, and the legs' branches enter through one
    call of each leg's method per branch (its rows'). What the flows of a node
    of one posture decide from the rows of that posture together (whether a
    leg may fold on one of them, whether a leaf's own direction moves on one of
    them) is decided per posture: every node's flows are those that its
    posture's nodes alone give. With constraints beyond the paper (their
    ``margins``, enclosed for one posture at a time) each posture is passed on
    its own."""
    n_legs = len(mechanism.legs)
    split = split_legs(mechanism.limits)
    slots = 1 << len(split)
    rows, post = nodes[:, 0], nodes[:, 1]
    m = rows.size
    postures = mechanism.postures
    # the postures present, and each row's among them
    index = np.zeros(postures.shape[0], dtype=np.int64)
    index[post] = 1
    present = np.flatnonzero(index)
    n_present = present.size
    index[present] = np.arange(n_present)
    post_row = index[post]
    at_posture = (
        [None] if n_present == 1 else [np.flatnonzero(post_row == j) for j in range(n_present)]
    )
    blo, bhi = lo[rows], hi[rows]
    branches = postures[post]
    groups = [_branch_groups(branches[:, i]) for i in range(n_legs)]
    angles = [
        Interval(table.angles_lo[rows, post, i], table.angles_hi[rows, post, i])
        for i in range(n_legs)
    ]
    if axes_only:
        # the first fields are the axis directions (see flow_directions); the
        # fixed flows are the same for every leaf: counted on no leaf at all
        n_fixed = len(_fields(mechanism, lo[:0], hi[:0]))
        fields = _fields(mechanism, blo, bhi, axes_only=True)
    else:
        fields = _fields(mechanism, blo, bhi, angles, groups)
        n_fixed = len(fields)
    n_flows = n_fixed + 2 * slots
    if n_flows > 64:
        raise ValueError("at most 64 flows per slot")
    bits = np.zeros((2, m, slots), dtype=np.uint64)
    exists = np.zeros((m, slots), dtype=bool)
    faces = np.zeros((n_flows, m), dtype=np.uint8)
    for ff, field in enumerate(fields):
        faces[ff] = field.faces
    combos = [
        [(c >> split.index(i)) & 1 if i in split else 0 for i in range(n_legs)]
        for c in range(slots)
    ]
    pieces = [mechanism.limits[i].pieces(angles[i]) for i in range(n_legs)]
    for c in range(slots):
        exists[:, c] = np.logical_and.reduce([pieces[i][0][combos[c][i]] for i in range(n_legs)])
    if not supports_flows(mechanism):
        # no flow: every piece that may exist stays open (none is attached)
        return bits, exists, faces
    leg_status = table.leg_status[rows]
    regular = leg_status == REGULAR
    folding = ~regular & (leg_status != REACH_UNKNOWN) & (leg_status != REACH_OUT)
    usable = ~(leg_status == REACH_UNKNOWN).any(axis=1)
    sign = table.sign[rows, post]

    def quiet() -> Any:
        return np.errstate(invalid="ignore", divide="ignore", over="ignore")

    if margins is _UNSET:

        def enclosed(at: NDArray[np.intp] | None, p: int) -> Any:
            """The constraints' margins over the rows ``at`` (None: all) of posture ``p``."""
            with quiet():
                return mechanism.constraint_margins(
                    _take(blo, at),
                    _take(bhi, at),
                    [_take(a, at) for a in angles],
                    p,
                    _take(regular, at),
                )

        # a mechanism has constraints or not, whatever the boxes: asked on none
        margins = enclosed(np.zeros(0, dtype=np.intp), int(present[0]))
        if margins is not None and n_present > 1:
            # the constraints' margins hold one posture's branches: one pass each
            for at, p in zip(at_posture, present, strict=True):
                assert at is not None
                own = enclosed(at, int(p))
                sub = _node_flows(mechanism, lo, hi, table, nodes[at], axes_only, own)
                bits[:, at], exists[at], faces[:, at] = sub
            return bits, exists, faces
        if margins is not None:
            margins = enclosed(None, int(present[0]))

    # the boxes of each leg's branches
    boxes = [{b: (_take(blo, at), _take(bhi, at)) for b, at in groups[i]} for i in range(n_legs)]

    def legs_call(i: int, method: str, *args: Any) -> Any:
        """Leg ``i``'s ``method(lo, hi, branch, *args)`` over every row, one call
        per branch (``args`` over rows are taken at the branch's rows)."""
        call = getattr(mechanism.legs[i], method)
        return _by_branch(
            groups[i], m, lambda b, at: call(*boxes[i][b], b, *[_take(x, at) for x in args])
        )

    with quiet():
        gradients = [legs_call(i, "joint_gradient", angles[i]) for i in range(n_legs)]
        known = mechanism.rows_and_partials(blo, bhi, angles)
    # where the nodes of a posture hold a leg that may fold, the joint's rate comes
    # from the leg's fold_flow on the rows where it is not regular: those rows of
    # each branch (with a cache of each: its rows stay the same), the others steady
    steady_leg: list[NDArray[np.bool_]] = []
    fold_rows: list[list[tuple[Any, ...]]] = []
    for i in range(n_legs):
        steady = regular[:, i] | ~_posture_any(folding[:, i], post_row, n_present)
        steady_leg.append(steady)
        per_branch: list[tuple[Any, ...]] = []
        for b, at in groups[i]:
            folds = np.flatnonzero(~steady) if at is None else at[~steady[at]]
            if folds.size:
                per_branch.append((b, folds, blo[folds], bhi[folds], leg_status[folds, i], {}))
        fold_rows.append(per_branch)
    for ff, field in enumerate(fields):
        velocity = field.velocity
        with quiet():
            ok = usable.copy() if field.usable is None else usable & field.usable
            rising, falling, rates = [], [], []
            for i, leg in enumerate(mechanism.legs):
                if i == field.leg:
                    # the leg keeps its reach; its joint moves at the leg's turn rate
                    speed = field.turn * float(leg.turn_rate)  # type: ignore[attr-defined]
                    rates.append(Interval(np.full(m, speed)))
                    rising.append(np.full(m, speed >= 0))
                    falling.append(np.full(m, speed <= 0))
                    # it keeps its distance to the fold (cross_serial or not)
                    keeps = legs_call(i, "turn_keeps", field.turn)
                    ok &= regular[:, i] | keeps
                    continue
                rate = _dot(gradients[i], velocity)
                if fold_rows[i]:
                    if hasattr(leg, "fold_flow"):
                        keeps, fold_rate = _joined(
                            [
                                (at, leg.fold_flow(
                                    glo, ghi, gstatus, b, [v[at] for v in velocity], cache=cache
                                ))
                                for b, at, glo, ghi, gstatus, cache in fold_rows[i]
                            ],
                            m,
                        )  # fmt: skip
                    else:
                        keeps = np.zeros(m, dtype=bool)
                        fold_rate = Interval(np.full(m, -np.inf), np.inf)
                    ok &= steady_leg[i] | keeps
                    # where the leg folds its joint's rate is unbounded: the leg's own enclosure
                    rate = Interval(
                        np.where(steady_leg[i], rate.lo, fold_rate.lo),
                        np.where(steady_leg[i], rate.hi, fold_rate.hi),
                    )
                up, down = rate.lo >= 0, rate.hi <= 0
                rates.append(rate)
                rising.append(up)
                falling.append(down)
            # passive limits, obstacles, collisions that may be active stay kept
            kept = _kept(mechanism, margins, blo, bhi, angles, velocity, rates)
        slot_oks = []
        for c in range(slots):
            slot_ok = ok.copy()
            for i in range(n_legs):
                _, lower, upper = pieces[i]
                j = combos[c][i]
                slot_ok &= (~lower[j] | rising[i]) & (~upper[j] | falling[i])
            slot_oks.append(slot_ok)
        # the rate of det A decides a flow only where a slot and a sign may flow
        # otherwise: elsewhere it is left out (NaN), which changes no flow
        need = np.logical_or.reduce(slot_oks) & (
            (kept[0] & (sign != 1)) | (kept[1] & (sign != -1))
        )
        with quiet():
            det_rate = _det_rate_where(
                mechanism, blo, bhi, angles, velocity, rates, known, need
            )
        for c, slot_ok in enumerate(slot_oks):
            for row, s in enumerate((1, -1)):
                steady = sign == s
                if det_rate is not None:
                    steady |= (det_rate.lo >= 0) if s > 0 else (det_rate.hi <= 0)
                bits[row, :, c] |= _bit(slot_ok & steady & kept[row], ff)
    if axes_only:
        return bits, exists, faces
    # the constraints that may be active near the leaf (within _NEAR of its size):
    # the leaves around one corner then share the direction into it
    det = Interval(table.det_lo[rows, post], table.det_hi[rows, post])
    with quiet():
        near_singular = (sign == 0) | _widened(det).contains(0.0)
        near = [mechanism.limits[i].pieces(_widened(angles[i])) for i in range(n_legs)]
    _adapted_flows(
        mechanism, blo, bhi, (groups, post_row, n_present), angles, gradients, (pieces, near),
        combos, usable & regular.all(axis=1), (sign, near_singular), bits, faces, n_fixed,
        (known, margins),
    )  # fmt: skip
    return bits, exists, faces


def _kept(
    mechanism: Mechanism,
    margins: Any,
    lo: Array,
    hi: Array,
    angles: list[Interval],
    velocity: list[Interval],
    rates: list[Interval],
) -> tuple[Any, Any]:
    """Per sign of det A (+, -): where a motion at ``velocity`` (joints at
    ``rates``) certainly keeps the constraints beyond the paper that may be
    active (True where the mechanism has none)."""
    if margins is None:
        return True, True
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        moving = mechanism.linkage_velocities(lo, hi, angles, velocity, rates)
        return margins.kept(moving, 1), margins.kept(moving, -1)


def _det_rate_where(
    mechanism: Mechanism,
    lo: Array,
    hi: Array,
    angles: list[Interval],
    velocity: list[Interval],
    rates: list[Interval],
    known: Any,
    need: Any,
) -> Interval | None:
    """:meth:`~moveability.mechanisms.base.Mechanism.det_a_rate` over the boxes
    where ``need`` holds, NaN elsewhere (no comparison holds there): the same
    bounds where it is computed, every operation being one box's own."""
    n = lo.shape[0]
    need = np.broadcast_to(np.asarray(need, dtype=bool), (n,))
    if need.all():
        return mechanism.det_a_rate(lo, hi, angles, velocity, rates, rows_and_partials=known)
    if known is None:
        return None
    at = np.flatnonzero(need)
    out_lo, out_hi = np.full(n, np.nan), np.full(n, np.nan)
    if at.size:
        sub = mechanism.det_a_rate(lo, hi, angles, velocity, rates, rows_and_partials=known, at=at)
        if sub is None:
            return None
        out_lo[at], out_hi[at] = sub.lo, sub.hi
    return Interval(out_lo, out_hi)


def _widened(x: Interval) -> Interval:
    """The enclosure grown about its midpoint to ``_NEAR`` times its width
    (unbounded or NaN bounds give NaN: nothing is near)."""
    mid, half = 0.5 * (x.lo + x.hi), 0.5 * _NEAR * (x.hi - x.lo)
    return Interval(mid - half, mid + half)


def _adapted_flows(
    mechanism: Mechanism,
    lo: Array,
    hi: Array,
    branches: tuple[list[_Groups], NDArray[np.intp], int],
    angles: list[Interval],
    gradients: list[list[Interval]],
    both_pieces: tuple[list[Any], list[Any]],
    combos: list[list[int]],
    usable: NDArray[np.bool_],
    signs: tuple[NDArray[np.int8], NDArray[np.bool_]],
    bits: NDArray[np.uint64],
    faces: NDArray[np.uint8],
    first: int,
    known_margins: tuple[Any, Any],
) -> None:
    """The flows along each leaf's own direction (see :func:`flow_conditions`),
    written into ``bits`` and ``faces`` from index ``first``, one per slot and sign.

    ``both_pieces`` holds the joints' pieces over the leaf and near it, ``signs``
    the sign of det A and whether it may vanish near the leaf: the direction
    comes from the constraints near the leaf, the conditions from those in it.
    ``branches`` holds the rows of each leg's branches (:func:`_branch_groups`),
    each row's posture (an index) and the number of postures: a posture none of
    whose rows moves along its own direction writes no exit faces."""
    groups, post_row, n_present = branches
    pieces, near = both_pieces
    sign, near_singular = signs
    known, margins = known_margins
    n, k = lo.shape
    n_legs = len(mechanism.legs)
    if not usable.any():
        return
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        # normals at the centre: narrow enclosures of the gradients there
        mid = 0.5 * (lo + hi)
        centre_angles = [Interval(a.mid) for a in angles]
        joint_at = [
            _by_branch(
                groups[i],
                n,
                lambda b, at, leg=leg, i=i: leg.joint_gradient(
                    _take(mid, at), _take(mid, at), b, _take(centre_angles[i], at)
                ),
            )
            for i, leg in enumerate(mechanism.legs)
        ]
        det_at = []
        # the rows and their partials at the centres, shared by the axes
        known_at = mechanism.rows_and_partials(mid, mid, centre_angles)
        for axis in range(k):
            along = [Interval(np.full(n, float(axis == j))) for j in range(k)]
            rate = mechanism.det_a_rate(
                mid, mid, centre_angles, along, [joint_at[i][axis] for i in range(n_legs)],
                rows_and_partials=known_at,
            )  # fmt: skip
            if rate is None:
                return
            det_at.append(rate.mid)
        det_normal = np.stack(det_at, axis=1)
        joint_normal = [np.stack([g.mid for g in joint_at[i]], axis=1) for i in range(n_legs)]
        del known_at, joint_at, det_at  # only the normals are needed below
        beyond = {
            s: _constraint_normals(mechanism, margins, lo, hi, angles, gradients, s)
            for s in (1, -1)
        }

    def unit(v: Array) -> Array:
        norm = np.linalg.norm(v, axis=1, keepdims=True)
        good = (norm > 0) & np.isfinite(norm)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(good, v / np.where(good, norm, 1.0), 0.0)

    # the unit normals, the same for every slot
    det_unit = {s: np.where(near_singular[:, None], unit(s * det_normal), 0.0) for s in (1, -1)}
    joint_unit = [unit(joint_normal[i]) for i in range(n_legs)]
    beyond_unit = {
        s: [(rise, fall, unit(normal)) for rise, fall, normal in beyond[s]] for s in (1, -1)
    }
    for c in range(len(combos)):
        for row, s in enumerate((1, -1)):
            normals = [det_unit[s]]
            for i in range(n_legs):
                _, lower, upper = near[i]
                j = combos[c][i]
                normals.append(
                    np.where(lower[j][:, None], joint_unit[i], 0.0)
                    - np.where(upper[j][:, None], joint_unit[i], 0.0)
                )
            for rise, fall, normal in beyond_unit[s]:
                normals.append(
                    np.where(rise[:, None], normal, 0.0) - np.where(fall[:, None], normal, 0.0)
                )
            direction = unit(into_corner(np.stack(normals, axis=1)))
            moving = usable & (np.abs(direction).sum(axis=1) > 0)
            if not moving.any():
                continue
            # (the postures none of whose rows moves keep no exit faces)
            moves = _posture_any(moving, post_row, n_present)
            velocity = [Interval(direction[:, axis]) for axis in range(k)]
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
                rates = [_dot(gradients[i], velocity) for i in range(n_legs)]
            ok = moving.copy()
            for i in range(n_legs):
                _, lower, upper = pieces[i]
                j = combos[c][i]
                ok &= (~lower[j] | (rates[i].lo >= 0)) & (~upper[j] | (rates[i].hi <= 0))
            kept = _kept(mechanism, margins, lo, hi, angles, velocity, rates)[row]
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
                # the rate decides the flow only where the rest allows it (see _node_flows)
                det_rate = _det_rate_where(
                    mechanism, lo, hi, angles, velocity, rates, known, ok & kept & (sign != s)
                )
            steady = sign == s
            if det_rate is not None:
                steady |= (det_rate.lo >= 0) if s > 0 else (det_rate.hi <= 0)
            index = first + 2 * c + row
            bits[row, :, c] |= _bit(ok & steady & kept, index)
            columns = [direction[:, axis] for axis in range(k)]
            faces[index] = np.where(moves, _exit_faces(columns, columns), np.uint8(0))


def _constraint_normals(
    mechanism: Mechanism,
    margins: Any,
    lo: Array,
    hi: Array,
    angles: list[Interval],
    gradients: list[list[Interval]],
    det_sign: int,
) -> list[tuple[NDArray[np.bool_], NDArray[np.bool_], Array]]:
    """For each constraint beyond the paper that may be active in some leaf at
    the configurations with det A of sign ``det_sign`` (see
    :meth:`~moveability.mechanisms.constraints.ConstraintMargins.rates`): where it
    may be active at a lower bound, at an upper bound, and (n, k) the midpoints
    of the enclosures of its gradient over the leaves (a direction only)."""
    if margins is None:
        return []
    n, k = lo.shape
    per_axis = []
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for axis in range(k):
            along = [Interval(np.full(n, float(axis == j))) for j in range(k)]
            rates = [g[axis] for g in gradients]
            moving = mechanism.linkage_velocities(lo, hi, angles, along, rates)
            per_axis.append(margins.rates(moving, det_sign=det_sign))
    out = []
    for j, (rise, fall, _) in enumerate(per_axis[0]):
        normal = np.stack([per_axis[axis][j][2].mid for axis in range(k)], axis=1)
        out.append((rise, fall, normal))
    return out


def into_corner(normals: Array) -> Array:
    """(n, k): a direction that moves into the corner that the active constraints'
    unit normals (n, C, k) bound (inactive rows are zero): the one whose dot
    product with each active normal is 1 (the dual basis), where the normals are
    independent; their sum elsewhere. With two normals in the plane both are
    the bisector; with three in space only the first one always exists."""
    total = normals.sum(axis=1)
    active = np.abs(normals).sum(axis=2) > 0
    gram = np.einsum("nck,ndk->ncd", normals, normals)
    gram += np.eye(normals.shape[1])[None] * ~active[:, :, None]
    good = np.abs(np.linalg.det(gram)) > 1e-9
    weights = np.zeros(active.shape)
    if good.any():
        weights[good] = np.linalg.solve(gram[good], active[good, :, None].astype(float))[..., 0]
    dual = np.einsum("nc,nck->nk", weights, normals)
    return np.where((good & np.isfinite(dual).all(axis=1))[:, None], dual, total)


@kernel(inline=True)
def _ready(
    d: int,
    r: int,
    c: int,
    faces: NDArray[np.uint8],
    remaining: NDArray[np.int64],
    never: NDArray[np.bool_],
) -> bool:  # pragma: no cover - compiled
    """Whether slot ``(r, c)`` waits on nothing across the exit faces of flow ``d``
    (and none of them is a face never crossed)."""
    mask = faces[d, r]
    for f in range(remaining.shape[0]):
        if (mask >> f) & 1 and (never[f, r] or remaining[f, r, c] != 0):
            return False
    return True


@kernel
def _propagate(
    slot_done: NDArray[np.bool_],
    bits: NDArray[np.uint64],
    remaining: NDArray[np.int64],
    never: NDArray[np.bool_],
    faces: NDArray[np.uint8],
    dep_ptr: NDArray[np.int64],
    dep_row: NDArray[np.int64],
    dep_slot: NDArray[np.int64],
    dep_face: NDArray[np.int64],
) -> None:  # pragma: no cover - compiled
    """Attach slots (row, slot) until none more can be: a slot attaches along a flow
    it has once no slot it may reach across that flow's exit faces is waiting
    (``remaining[f, row, slot]``: how many across face ``f`` still are), and
    none of those faces is ``never`` crossed. The slots attached are the least
    fixed point, whatever the order."""
    m, n_slots = slot_done.shape
    n_flows = faces.shape[0]
    queue = np.empty(m * n_slots, dtype=np.int64)
    tail = 0
    for r in range(m):
        for c in range(n_slots):
            if slot_done[r, c]:
                continue
            for d in range(n_flows):
                if (bits[r, c] >> np.uint64(d)) & np.uint64(1) and _ready(
                    d, r, c, faces, remaining, never
                ):
                    slot_done[r, c] = True
                    queue[tail] = r * n_slots + c
                    tail += 1
                    break
    head = 0
    while head < tail:
        sub = queue[head]
        head += 1
        for j in range(dep_ptr[sub], dep_ptr[sub + 1]):
            r, c, f = dep_row[j], dep_slot[j], dep_face[j]
            if slot_done[r, c]:
                continue
            remaining[f, r, c] -= 1
            if remaining[f, r, c] != 0:
                continue
            for d in range(n_flows):
                if (
                    (faces[d, r] >> f) & 1
                    and (bits[r, c] >> np.uint64(d)) & np.uint64(1)
                    and _ready(d, r, c, faces, remaining, never)
                ):
                    slot_done[r, c] = True
                    queue[tail] = r * n_slots + c
                    tail += 1
                    break


@kernel(inline=True)
def doubled(buffer: NDArray[np.int64], used: int) -> NDArray[np.int64]:  # pragma: no cover
    """A buffer twice as long as ``buffer`` with its first ``used`` entries (a
    compiled loop's growing output)."""
    grown = np.empty(2 * buffer.size, dtype=np.int64)
    grown[:used] = buffer[:used]
    return grown


@kernel
def _dependencies(
    pairs: NDArray[np.int64],
    face_ptr: NDArray[np.int64],
    node_row: NDArray[np.int64],
    done: NDArray[np.bool_],
    slot_done: NDArray[np.bool_],
    spans: NDArray[np.float64],
    open_faces: NDArray[np.bool_],
) -> tuple[
    NDArray[np.int64],
    NDArray[np.bool_],
    NDArray[np.int64],
    NDArray[np.int64],
    NDArray[np.int64],
    NDArray[np.int64],
]:  # pragma: no cover - compiled
    """What each waiting slot waits on, for :func:`attached_nodes`, for attachments
    of the same nodes (``done`` (sets, n, P) and ``slot_done`` (sets, m, slots),
    one of each per attachment) from one pass over the pairs.

    ``pairs[face_ptr[f]:face_ptr[f + 1]]`` are the leaves ``(a, b)`` with ``b``
    across ``a``'s face ``f``; ``node_row`` the row of each node (-1: none),
    ``open_faces`` (m, faces) those of each row's leaf on the edge of the box.
    Returns, for each attachment ``s``, ``per_face[s]`` (faces, m, slots): the
    slots across face ``f`` a slot may land in that are waiting; ``never[s]``
    (faces, m): faces that can never be crossed (the box's edge, or a node
    across neither done nor listed); and the triples (row, slot, face) waiting
    on each slot ``sub = row * slots + slot`` across, as
    ``dep_*[dep_ptr[s, sub]:dep_ptr[s, sub + 1]]`` (those of all attachments in
    one array, the first's first; each one's by face, pair, posture, own slot,
    then slot across)."""
    n_sets, m, slots = slot_done.shape
    n_post = done.shape[2]
    n_faces = face_ptr.size - 1
    n_legs = spans.shape[2]
    per_face = np.zeros((n_sets, n_faces, m, slots), dtype=np.int64)
    never = np.zeros((n_sets, n_faces, m), dtype=np.bool_)
    dep_ptr = np.zeros((n_sets, m * slots + 1), dtype=np.int64)
    fill = np.zeros((n_sets, m * slots), dtype=np.int64)
    # one pass over the pairs: the triples in the order met, each with the slot
    # across it waits on; then placed by that slot (a counting sort, stable)
    cap = max(1024, pairs.shape[0] // 2)
    got_set = np.empty(cap, dtype=np.int64)
    got_row = np.empty(cap, dtype=np.int64)
    got_slot = np.empty(cap, dtype=np.int64)
    got_face = np.empty(cap, dtype=np.int64)
    got_sub = np.empty(cap, dtype=np.int64)
    total = 0
    for f in range(n_faces):
        for e in range(face_ptr[f], face_ptr[f + 1]):
            a, b = pairs[e, 0], pairs[e, 1]
            for p in range(n_post):
                ra = node_row[a, p]
                if ra < 0:
                    continue
                rb = node_row[b, p]
                for s in range(n_sets):
                    if done[s, b, p]:
                        continue
                    if rb < 0:
                        # a node across that is neither done nor listed never attaches
                        never[s, f, ra] = True
                        continue
                    for ca in range(slots):
                        if slot_done[s, ra, ca]:
                            continue
                        for cb in range(slots):
                            if slot_done[s, rb, cb]:
                                continue
                            # their joint ranges meet
                            meet = True
                            for j in range(n_legs):
                                if not (
                                    spans[ra, ca, j, 0] <= spans[rb, cb, j, 1] + _SPAN_TOL
                                    and spans[rb, cb, j, 0] <= spans[ra, ca, j, 1] + _SPAN_TOL
                                ):
                                    meet = False
                            if not meet:
                                continue
                            sub = rb * slots + cb
                            per_face[s, f, ra, ca] += 1
                            fill[s, sub] += 1
                            if total == cap:
                                cap *= 2
                                got_set = doubled(got_set, total)
                                got_row = doubled(got_row, total)
                                got_slot = doubled(got_slot, total)
                                got_face = doubled(got_face, total)
                                got_sub = doubled(got_sub, total)
                            got_set[total] = s
                            got_row[total] = ra
                            got_slot[total] = ca
                            got_face[total] = f
                            got_sub[total] = sub
                            total += 1
    # a counting sort by (set, slot waited on), stable
    start = 0
    for s in range(n_sets):
        dep_ptr[s, 0] = start
        for sub in range(m * slots):
            dep_ptr[s, sub + 1] = dep_ptr[s, sub] + fill[s, sub]
            fill[s, sub] = 0
        start = dep_ptr[s, m * slots]
    dep_row = np.empty(total, dtype=np.int64)
    dep_slot = np.empty(total, dtype=np.int64)
    dep_face = np.empty(total, dtype=np.int64)
    for t in range(total):
        s = got_set[t]
        sub = got_sub[t]
        at = dep_ptr[s, sub] + fill[s, sub]
        dep_row[at] = got_row[t]
        dep_slot[at] = got_slot[t]
        dep_face[at] = got_face[t]
        fill[s, sub] += 1
    for s in range(n_sets):
        for f in range(n_faces):
            for r in range(m):
                # a face on the edge of the box can never be crossed
                never[s, f, r] |= open_faces[r, f]
    return per_face, never, dep_ptr, dep_row, dep_slot, dep_face


def slot_spans(
    table: SheetTable, nodes: NDArray[np.intp], limits: tuple[Any, ...]
) -> NDArray[np.float64]:
    """(m, slots, legs, 2): the range of values of each limited revolute joint in each
    slot of the nodes (see :func:`moveability.analysis.regions.split_legs`)."""
    from .regions import joint_pieces

    split = split_legs(limits)
    slots = 1 << len(split)
    m = nodes.shape[0]
    spans = np.zeros((m, slots, len(split), 2))
    for j, i in enumerate(split):
        lo, hi, _ = joint_pieces(
            table.angles_lo[nodes[:, 0], nodes[:, 1], i],
            table.angles_hi[nodes[:, 0], nodes[:, 1], i],
            limits[i],
        )
        for c in range(slots):
            k = (c >> j) & 1
            spans[:, c, j, 0] = lo[k]
            spans[:, c, j, 1] = hi[k]
    return spans


def attached_nodes(
    done: NDArray[np.bool_],
    nodes: NDArray[np.intp],
    bits: NDArray[np.uint64],
    exists: NDArray[np.bool_],
    faces: NDArray[np.uint8],
    neighbours: FaceNeighbours,
    spans: NDArray[np.float64] | None = None,
) -> NDArray[np.bool_]:
    """The nodes (leaf, posture) attached for one sign.

    Parameters
    ----------
    done : (n, P) bool
        Nodes that need no certificate: certified for the sign, or holding no
        valid configuration of it.
    nodes : (m, 2) int
        The nodes whose flows are given, as (leaf, posture); a node that is not
        done and not among them is never attached (it blocks its neighbours).
    bits, exists, faces
        Their flows for the sign, slots and exit faces (see :func:`flow_conditions`).
    neighbours : FaceNeighbours
        The tree's face neighbours.
    spans : (m, slots, legs, 2) float, optional
        The joint ranges of the slots (:func:`slot_spans`). A configuration
        leaving a slot across a face lands, in the node across, in a slot
        whose ranges meet those of its own; without ``spans`` every slot
        across is taken.

    Notes
    -----
    A slot attaches along one of its flows once every slot across that flow's
    exit faces that it may land in is done. Linear in the number of (slot,
    flow, slot across) triples. :class:`Attachment` does the same and may be
    resumed with more flows.
    """
    return Attachment(done, nodes, exists, neighbours, spans).run(bits, faces)


class Attachment:
    """The attachment of nodes for one sign (see :func:`attached_nodes`), resumable.

    Built once from what does not depend on the flows (the slots each one waits
    on); :meth:`run` attaches with the flows given and keeps its state, so that
    a later run with more flows (bits only added, exit faces given for the flows
    added) continues from the slots already attached: attachment is monotone in
    the flows, and the result is that of the last flows given.
    """

    def __init__(
        self,
        done: NDArray[np.bool_],
        nodes: NDArray[np.intp],
        exists: NDArray[np.bool_],
        neighbours: FaceNeighbours,
        spans: NDArray[np.float64] | None = None,
    ) -> None:
        leaf, post, node_row, slot_done, args = _attachment_inputs(
            [done], nodes, exists, neighbours, spans
        )
        self._done, self._leaf, self._post = done, leaf, post
        self._slot_done = slot_done[0]
        per_face, never, dep_ptr, *triples = _dependencies(
            args[0], args[1], node_row, np.ascontiguousarray(done)[None], slot_done,
            args[2], args[3],
        )  # fmt: skip
        #: what each slot waits on (see :func:`_dependencies`)
        self._waiting: tuple[NDArray[Any], ...] = (per_face[0], never[0], dep_ptr[0], *triples)

    @classmethod
    def both(
        cls,
        done: list[NDArray[np.bool_]],
        nodes: NDArray[np.intp],
        exists: NDArray[np.bool_],
        neighbours: FaceNeighbours,
        spans: NDArray[np.float64] | None = None,
    ) -> list[Attachment]:
        """The attachments of two ``done`` (two signs) of the same nodes, what their
        slots wait on found from one pass over the face pairs: the same as
        ``[Attachment(d, nodes, exists, neighbours, spans) for d in done]``."""
        if len(done) != 2:
            return [cls(d, nodes, exists, neighbours, spans) for d in done]
        leaf, post, node_row, slot_done, args = _attachment_inputs(
            done, nodes, exists, neighbours, spans
        )
        per_face, never, dep_ptr, dep_row, dep_slot, dep_face = _dependencies(
            args[0], args[1], node_row, np.ascontiguousarray(np.stack(done)), slot_done,
            args[2], args[3],
        )  # fmt: skip
        out = []
        for s, d in enumerate(done):
            run = cls.__new__(cls)
            run._done, run._leaf, run._post = d, leaf, post
            run._slot_done = slot_done[s]
            # each one's pointers index the triples of both
            run._waiting = (per_face[s], never[s], dep_ptr[s], dep_row, dep_slot, dep_face)
            out.append(run)
        return out

    def run(self, bits: NDArray[np.uint64], faces: NDArray[np.uint8]) -> NDArray[np.bool_]:
        """The nodes attached with the flows ``bits`` (m, slots) and their exit
        ``faces`` (F, m), beyond ``done``: (n, P) bool."""
        per_face, never, dep_ptr, dep_row, dep_slot, dep_face = self._waiting
        _propagate(
            self._slot_done,
            np.ascontiguousarray(bits),
            per_face,
            never,
            np.ascontiguousarray(faces),
            dep_ptr,
            dep_row,
            dep_slot,
            dep_face,
        )
        state = self._done.copy()
        state[self._leaf, self._post] |= self._slot_done.all(axis=1)
        return state & ~self._done


def _attachment_inputs(
    done: list[NDArray[np.bool_]],
    nodes: NDArray[np.intp],
    exists: NDArray[np.bool_],
    neighbours: FaceNeighbours,
    spans: NDArray[np.float64] | None,
) -> tuple[Any, ...]:
    """What :func:`_dependencies` takes for attachments of ``done`` (each (n, P)):
    the nodes' leaves and postures, each node's row (n, P), the slots done of
    each attachment (len(done), m, slots) and (face pairs, their pointers, the
    slots' spans, the nodes' open faces)."""
    n, n_post = done[0].shape
    m = nodes.shape[0]
    slots = exists.shape[1]
    n_faces = neighbours.open.shape[1]
    leaf, post = nodes[:, 0].astype(np.int64), nodes[:, 1].astype(np.int64)
    node_row = np.full((n, n_post), -1, dtype=np.int64)
    node_row[leaf, post] = np.arange(m)
    slot_done = np.empty((len(done), m, slots), dtype=bool)
    for s, d in enumerate(done):
        slot_done[s] = ~exists | d[leaf, post][:, None]
    if neighbours.flat is not None:
        all_pairs, face_ptr = neighbours.flat
    else:
        face_ptr = np.zeros(n_faces + 1, dtype=np.int64)
        face_ptr[1:] = np.cumsum([neighbours.pairs[f].shape[0] for f in range(n_faces)])
        all_pairs = (
            np.concatenate([neighbours.pairs[f].reshape(-1, 2) for f in range(n_faces)])
            if n_faces
            else np.zeros((0, 2), dtype=np.int64)
        )
    if spans is None:
        spans = np.zeros((m, slots, 0, 2))
    args = (
        np.ascontiguousarray(all_pairs, dtype=np.int64),
        face_ptr,
        np.ascontiguousarray(spans, dtype=np.float64),
        np.ascontiguousarray(neighbours.open[leaf]),
    )
    return leaf, post, node_row, slot_done, args


def dead_or_certified(table: SheetTable, s: int, cross_serial: bool = True) -> NDArray[np.bool_]:
    """(n, P): nodes certified with det A of sign ``s``, or with no valid configuration
    of that sign (OUT, the other sign certainly, or det A identically zero)."""
    group = table.group if cross_serial else np.zeros_like(table.group)
    certified = ((table.status == IN) | group) & (table.sign == s)
    return certified | ~table.may_hold(s)
