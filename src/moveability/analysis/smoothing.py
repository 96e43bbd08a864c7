"""Shorter, smoother motions: straight shortcuts and cut corners, certified over boxes.

A motion planned along the certain graph (:mod:`moveability.analysis.planning`)
goes from cell to cell, so it zigzags. Where it keeps one posture, a straight
pose segment may replace the stretch between two of its configurations,
provided every configuration of that posture along the segment is valid and
has the region's sign of det A. That is proved, not sampled: the segment lies
in the union of the axis-aligned boxes of its pieces, and
:func:`~moveability.analysis.sheets.classify_sheets` certifies the posture's
sheet over each box (status IN: the posture exists over the whole box, within
the joint limits, every leg regular, det A of one known sign). A piece whose
box is undecided is bisected, down to a resolution, so that a long shortcut
across a wide certified area costs a few boxes and one that grazes a boundary
is refined only where it does.

Why the shortcut stays in the motion's region: over each box the
configurations of the posture form one continuous sheet, so those along the
segment form a continuous curve of valid configurations, of one sign of det A,
that starts and ends at configurations of the motion. A connected set of such
configurations lies in one region.

The functions here are pure: they take poses and a mechanism and return new
arrays. :func:`certify_segments` proves segments, :func:`shortcut` picks the
kept configurations of a stretch greedily, :func:`cut_corners` rounds the
corners of a polyline, :func:`smooth_path` does both on a whole motion and
:func:`path_length` measures one.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Generator

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ..hypertree.status import IN, OUT
from ..mechanisms.base import Mechanism
from ..types import Array
from .sheets import classify_sheets

__all__ = ["certify_segments", "cut_corners", "path_length", "shortcut", "smooth_path"]

#: the first pieces of a segment are at most this many resolutions wide (wider
#: boxes are rarely certified, and each level of bisection is one more call)
_FIRST_PIECE = 8.0
#: boxes of the first level of a batch of proofs at most (wider first pieces then)
_FIRST_BOXES = 4096
#: a segment needing more live pieces than this in one level is given up (unproved)
_MAX_PIECES = 4096
#: candidates tested at once when narrowing down the farthest shortcut
_FAN = 16
#: cuts tried at a corner per round, each a quarter of the one before
_CUT_TRIES = 3
#: corners turning by less than this (radians) are left alone: they are straight
_STRAIGHT = 1e-6

#: a tester of shortcuts in a stretch: from index i to each index of js, proved or not
Tester = Callable[[int, NDArray[np.intp]], NDArray[np.bool_]]


def _resolution(value: ArrayLike, k: int) -> Array:
    res = np.asarray(value, dtype=np.float64)
    if res.ndim == 0:
        res = np.full(k, float(res))
    if res.shape != (k,) or not (np.isfinite(res) & (res > 0)).all():
        raise InvalidParameterError(
            "resolution", f"a positive length, or {k} of them (one per pose axis)", value
        )
    return res


def certify_segments(
    mechanism: Mechanism,
    starts: ArrayLike,
    ends: ArrayLike,
    posture: ArrayLike,
    sign: int,
    resolution: ArrayLike,
) -> NDArray[np.bool_]:
    """Whether every configuration of ``posture`` along each pose segment is proved
    valid, with det A of ``sign``.

    Parameters
    ----------
    mechanism : Mechanism
        The manipulator.
    starts, ends : array_like, shape (n, k)
        The ends of the segments (poses; periodic angles may be unwrapped).
    posture : int or array_like of int, shape (n,)
        The posture (index into ``mechanism.postures``) held along them, one
        for all or one per segment.
    sign : {1, -1}
        The sign det A must keep.
    resolution : float or array_like of shape (k,)
        Pieces are bisected while their box is wider than this along some axis.

    Returns
    -------
    ndarray of bool, shape (n,)
        True where the segment is proved: covered by boxes over which the
        posture's sheet is IN with det A of ``sign``. False says only that no
        proof was found at the resolution (or that some box is certainly
        invalid).

    Notes
    -----
    All the pieces of all the segments are classified together, one call of
    :func:`~moveability.analysis.sheets.classify_sheets` per level of
    bisection. A segment fails as soon as one of its pieces is certainly OUT,
    of the opposite sign, or undecided at the resolution; its other pieces are
    then dropped. The first pieces are eight resolutions wide (wider when the
    batch would start with more than 4096 boxes); a segment of length L then
    costs at most about ``2 L / r`` boxes (``r`` the resolution along it) in
    ``log2(L / r)`` levels, and one that needs more than 4096 live pieces in a
    level (one grazing a boundary along its length) is given up.

    Examples
    --------
    >>> from moveability.mechanisms import FiveBar
    >>> m = FiveBar()
    >>> certify_segments(m, [[2.0, 3.0], [2.0, 3.0]], [[5.0, 3.0], [2.0, 20.0]],
    ...                  posture=1, sign=-1, resolution=0.01).tolist()
    [True, False]
    """
    k = len(mechanism.pose_names)
    try:
        a = np.asarray(starts, dtype=np.float64).reshape(-1, k)
        b = np.asarray(ends, dtype=np.float64).reshape(-1, k)
    except (TypeError, ValueError):
        raise InvalidParameterError(
            "starts, ends", f"two arrays of poses of shape (n, {k})", (starts, ends)
        ) from None
    if a.shape != b.shape:
        raise InvalidParameterError("ends", f"an array of shape {a.shape}", b.shape)
    n = a.shape[0]
    n_post = mechanism.postures.shape[0]
    try:
        post = np.broadcast_to(np.asarray(posture, dtype=np.intp), (n,))
    except ValueError:
        raise InvalidParameterError("posture", f"an index or {n} of them", posture) from None
    if ((post < 0) | (post >= n_post)).any():
        raise InvalidParameterError("posture", f"indices in [0, {n_post})", posture)
    if sign not in (1, -1):
        raise InvalidParameterError("sign", "1 or -1", sign)
    res = _resolution(resolution, k)
    ok: NDArray[np.bool_] = np.asarray(np.isfinite(a).all(axis=1) & np.isfinite(b).all(axis=1))
    d = np.where(ok[:, None], b - a, 0.0)
    # the rounding of a + t d when the segment is walked later: boxes are widened by it
    slack = 8.0 * np.spacing(np.abs(a) + np.abs(d)) + 1e-300
    count = np.ceil((np.abs(d) / (_FIRST_PIECE * res)).max(axis=1))
    if count.sum() > _FIRST_BOXES:
        count = np.ceil(count * (_FIRST_BOXES / count.sum()))
    count = np.where(ok, np.maximum(count, 1), 0).astype(np.intp)
    seg = np.repeat(np.arange(n), count)
    first = np.repeat(np.cumsum(count) - count, count)
    rank = np.arange(seg.size) - first
    t0 = rank / count[seg]
    t1 = np.where(rank + 1 == count[seg], 1.0, (rank + 1) / count[seg])
    while seg.size:
        p0 = a[seg] + t0[:, None] * d[seg]
        p1 = a[seg] + t1[:, None] * d[seg]
        lo = np.minimum(p0, p1) - slack[seg]
        hi = np.maximum(p0, p1) + slack[seg]
        table = classify_sheets(mechanism, lo, hi)
        rows, cols = np.arange(seg.size), post[seg]
        status, got = table.status[rows, cols], table.sign[rows, cols]
        good = (status == IN) & (got == sign)
        # certainly hopeless boxes: every sub-box is as bad
        hopeless = (status == OUT) | (got == -sign) | table.singular[rows, cols]
        small = (hi - lo <= res).all(axis=1)
        ok[seg[~good & (hopeless | small)]] = False
        split = ~good & ok[seg]
        crowded = np.bincount(seg[split], minlength=n) > _MAX_PIECES // 2
        ok[crowded] = False
        split &= ok[seg]
        seg, t0, t1 = seg[split], t0[split], t1[split]
        mid = 0.5 * (t0 + t1)
        seg = np.concatenate([seg, seg])
        t0, t1 = np.concatenate([t0, mid]), np.concatenate([mid, t1])
    return ok


def shortcut(test: Tester, n: int) -> list[int]:
    """Indices of a stretch ``0 .. n-1`` kept by greedy shortcutting.

    From each kept index ``i``, the next one is the farthest ``j`` found with
    ``test(i, [j])`` true, or ``i + 1`` (the stretch's own step) when none is.
    Candidates are tested in batches: the last index and ``i + 2, i + 4, i +
    8, ...`` first, then evenly spaced ones between the farthest success and
    the nearest failure beyond it, until they are adjacent. A shortcut need
    not be monotone (a shorter one may fail where a longer one passes), so the
    search finds a far success, not always the farthest.

    Parameters
    ----------
    test : callable
        ``test(i, js)`` returns, for each index of ``js`` (all above ``i``),
        whether the straight shortcut from ``i`` to it is allowed.
    n : int
        Length of the stretch.

    Returns
    -------
    list of int
        Increasing, from 0 to ``n - 1``; consecutive kept indices are joined by
        an allowed shortcut or are neighbours.

    Examples
    --------
    >>> # indices on a line, a wall between 5 and 6 that shortcuts cannot cross
    >>> shortcut(lambda i, js: (js <= 5) | (i >= 6), 12)
    [0, 5, 6, 11]
    """
    if n < 1:
        raise InvalidParameterError("n", "a positive length", n)
    search = _shortcut_search(n)
    step = _advance(search, None)
    while isinstance(step, tuple):
        step = _advance(search, test(*step))
    return step


#: what a search asks: shortcuts from index i to each index of js
Request = tuple[int, NDArray[np.intp]]
Search = Generator[Request, NDArray[np.bool_] | None, list[int]]


def _advance(search: Search, answer: NDArray[np.bool_] | None) -> Request | list[int]:
    """Send a search the answer to its last request (None to start it): its next
    request, or its result when it is done."""
    try:
        return search.send(answer)
    except StopIteration as stop:
        return list(stop.value)


def _shortcut_search(n: int) -> Search:
    """The greedy search of :func:`shortcut` as a coroutine: it yields the shortcuts
    it wants tested and is sent the answers (see :func:`_advance`), so that the
    searches of several stretches can share each batch of proofs."""
    kept = [0]
    i, last = 0, n - 1
    while i < last:
        best = i + 1
        powers = i + (1 << np.arange(1, max(1, int(last - i).bit_length())))
        cands = np.unique(np.append(powers[powers < last], last)).astype(np.intp)
        cands = cands[cands > best]
        upper = last + 1
        while cands.size:
            ok = yield i, cands
            assert ok is not None
            if ok.any():
                best = max(best, int(cands[ok].max()))
            failed = cands[~ok & (cands > best)]
            upper = int(failed.min()) if failed.size else upper
            if upper > last or upper - best <= 1:
                break
            cands = np.unique(np.linspace(best, upper, _FAN + 2).round().astype(np.intp))
            cands = cands[(cands > best) & (cands < upper)]
        i = best
        kept.append(i)
    return kept


def cut_corners(
    test: Callable[[Array, Array, NDArray[np.intp]], NDArray[np.bool_]],
    vertices: ArrayLike,
    movable: ArrayLike,
    rounds: int = 3,
    cut: float = 0.25,
) -> tuple[Array, NDArray[np.intp]]:
    """A polyline with its corners cut where the cutting segments are allowed.

    Each round replaces every movable corner ``v`` (between ``u`` and ``w``)
    by two points ``v + f (u - v)`` and ``v + f (w - v)``, if the straight
    segment between them is allowed by ``test``: ``f`` is ``cut``, or a
    quarter of it, or a sixteenth, the first allowed; a corner refused all
    three stays for good.
    The other pieces of the new polyline lie on the old one. Repeated, this is
    Chaikin's corner cutting, which tends to a quadratic spline; each cut
    shortens the polyline.

    Parameters
    ----------
    test : callable
        ``test(starts, ends, at)`` (arrays of shape (m, k), and the index of
        the input vertex each cut corner comes from) returns, for each
        segment, whether it is allowed.
    vertices : array_like, shape (n, k)
        The polyline.
    movable : array_like of bool, shape (n,)
        Corners that may be cut (the ends never are).
    rounds : int
        Number of rounds.
    cut : float
        Fraction of each adjacent side taken off, in ``(0, 0.5]``.

    Returns
    -------
    vertices : ndarray, shape (m, k)
        The new polyline.
    origin : ndarray of int, shape (m,)
        Index of the original vertex each new vertex is, or -1 for a new one.

    Examples
    --------
    >>> import numpy as np
    >>> square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    >>> v, origin = cut_corners(lambda a, b, at: np.ones(len(a), bool), square,
    ...                         [False, True, False], rounds=1)
    >>> v.tolist(), origin.tolist()
    ([[0.0, 0.0], [0.75, 0.0], [1.0, 0.25], [1.0, 1.0]], [0, -1, -1, 2])
    """
    v = np.asarray(vertices, dtype=np.float64)
    free = np.asarray(movable, dtype=bool).copy()
    if free.shape != v.shape[:1]:
        raise InvalidParameterError("movable", f"{v.shape[0]} flags, one per vertex", free.shape)
    if not 0.0 < cut <= 0.5:
        raise InvalidParameterError("cut", "a fraction in (0, 0.5]", cut)
    origin = np.arange(v.shape[0], dtype=np.intp)
    source = origin.copy()  # the input vertex each vertex comes from
    for _ in range(int(rounds)):
        if v.shape[0] < 3:
            break
        free[[0, -1]] = False
        corner = np.flatnonzero(free[1:-1]) + 1
        before, after = v[corner] - v[corner - 1], v[corner + 1] - v[corner]
        norms = np.linalg.norm(before, axis=1) * np.linalg.norm(after, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            cos = np.einsum("ij,ij->i", before, after) / norms
        corner = corner[(norms > 0) & (cos < np.cos(_STRAIGHT))]
        if not corner.size:
            break
        # the cut of each corner, shrunk where it is refused
        frac = np.full(corner.size, float(cut))
        ok = np.zeros(corner.size, dtype=bool)
        for _ in range(_CUT_TRIES):
            todo = np.flatnonzero(~ok)
            at_c = corner[todo]
            c1 = v[at_c] + frac[todo, None] * (v[at_c - 1] - v[at_c])
            c2 = v[at_c] + frac[todo, None] * (v[at_c + 1] - v[at_c])
            ok[todo] = np.asarray(test(c1, c2, source[at_c]), dtype=bool)
            frac[todo[~ok[todo]]] *= 0.25
            if ok.all():
                break
        free[corner[~ok]] = False  # a corner refused at every try stays
        corner, frac = corner[ok], frac[ok]
        if not corner.size:
            continue
        c1 = v[corner] + frac[:, None] * (v[corner - 1] - v[corner])
        c2 = v[corner] + frac[:, None] * (v[corner + 1] - v[corner])
        # each cut corner becomes two new vertices, in place
        repeat = np.ones(v.shape[0], dtype=np.intp)
        repeat[corner] = 2
        at = np.cumsum(repeat) - repeat
        new_v = np.repeat(v, repeat, axis=0)
        new_v[at[corner]], new_v[at[corner] + 1] = c1, c2
        new_origin = np.repeat(origin, repeat)
        new_origin[at[corner]] = new_origin[at[corner] + 1] = -1
        v, origin = new_v, new_origin
        free, source = np.repeat(free, repeat), np.repeat(source, repeat)
    return v, origin


def smooth_path(
    mechanism: Mechanism,
    poses: ArrayLike,
    postures: ArrayLike,
    fixed: ArrayLike,
    sign: int,
    resolution: ArrayLike,
    rounds: int = 3,
    passes: int = 1,
    spacing: float | None = None,
) -> tuple[Array, NDArray[np.intp], NDArray[np.intp]]:
    """The corners of a shorter motion along the same sheets.

    The motion is cut at its fixed configurations (asked poses and both sides
    of each posture change); each stretch between them keeps one posture and
    is shortened by :func:`shortcut` and rounded by :func:`cut_corners`, every
    new segment proved by :func:`certify_segments`. Between consecutive
    returned configurations the pose moves straight (those of a posture
    change share their pose).

    A second pass finds shortcuts between configurations on the first one's
    segments (the greedy search of the first is bound to the input's
    configurations); between passes the motion is subdivided so that
    consecutive poses are at most ``spacing`` apart.

    Parameters
    ----------
    mechanism : Mechanism
        The manipulator.
    poses : array_like, shape (n, k)
        Poses of the motion (unwrapped), consecutive ones joined straight by
        valid configurations of the region.
    postures : array_like of int, shape (n,)
        Posture of each configuration.
    fixed : array_like of bool, shape (n,)
        Configurations to keep. Both sides of every posture change, and the
        ends, are kept whatever ``fixed`` says.
    sign : {1, -1}
        The region's sign of det A.
    resolution : float or array_like of shape (k,)
        Smallest boxes of the proofs (see :func:`certify_segments`).
    rounds : int
        Rounds of corner cutting (0 for none).
    passes : int
        Passes of shortcutting and corner cutting.
    spacing : float, optional
        Largest distance between consecutive poses given to the passes after
        the first (default: eight resolutions, the smallest).

    Returns
    -------
    poses : ndarray, shape (m, k)
    postures : ndarray of int, shape (m,)
    origin : ndarray of int, shape (m,)
        Index in the input of each returned configuration, or -1 for a new one.

    Examples
    --------
    >>> import numpy as np
    >>> from moveability.mechanisms import FiveBar
    >>> zigzag = np.array([[2.0, 3.0], [3.0, 4.0], [4.0, 3.0], [5.0, 4.0]])
    >>> p, _, origin = smooth_path(FiveBar(), zigzag, [1, 1, 1, 1], [True, False, False, True],
    ...                            sign=-1, resolution=0.01, rounds=0)
    >>> p.tolist(), origin.tolist()
    ([[2.0, 3.0], [5.0, 4.0]], [0, 3])
    """
    p = np.asarray(poses, dtype=np.float64)
    post = np.asarray(postures, dtype=np.intp)
    keep = np.asarray(fixed, dtype=bool).copy()
    n = p.shape[0]
    if post.shape != (n,) or keep.shape != (n,):
        raise InvalidParameterError(
            "postures, fixed", f"{n} values each, one per pose", (post.shape, keep.shape)
        )
    res = _resolution(resolution, p.shape[1])
    gap = _FIRST_PIECE * float(res.min()) if spacing is None else float(spacing)
    if not (np.isfinite(gap) and gap > 0):
        raise InvalidParameterError("spacing", "a positive length", spacing)
    keep[[0, -1]] = True
    change = np.flatnonzero(post[1:] != post[:-1])
    keep[change] = keep[change + 1] = True
    origin = np.arange(n, dtype=np.intp)
    for i in range(int(passes)):
        if i:
            p, post, inside = _subdivide(p, post, gap)
            origin = np.where(inside >= 0, origin[np.maximum(inside, 0)], -1)
            keep = keep[np.maximum(inside, 0)] & (inside >= 0)
        p, post, kept = _smooth_once(mechanism, p, post, keep, sign, res, rounds)
        origin = np.where(kept >= 0, origin[np.maximum(kept, 0)], -1)
        keep = keep[np.maximum(kept, 0)] & (kept >= 0)
    return p, post, origin


def _smooth_once(
    mechanism: Mechanism,
    p: Array,
    post: NDArray[np.intp],
    keep: NDArray[np.bool_],
    sign: int,
    res: Array,
    rounds: int,
) -> tuple[Array, NDArray[np.intp], NDArray[np.intp]]:
    """One pass of :func:`smooth_path` (``keep`` holds the ends and both sides of
    every posture change)."""
    anchors = np.flatnonzero(keep)
    # one greedy search per stretch of one posture, their requests proved together
    searches: dict[int, Search] = {}
    done: dict[int, list[int]] = {}
    asked: dict[int, Request | list[int]] = {}
    for f, g in itertools.pairwise(anchors):
        if post[f] == post[g]:
            searches[int(f)] = _shortcut_search(int(g - f + 1))
            asked[int(f)] = _advance(searches[int(f)], None)
    while asked:
        waiting = {f: r for f, r in asked.items() if isinstance(r, tuple)}
        done.update({f: r for f, r in asked.items() if not isinstance(r, tuple)})
        if not waiting:
            break
        heads = np.concatenate([np.full(js.size, f + i) for f, (i, js) in waiting.items()])
        tails = np.concatenate([f + js for f, (_, js) in waiting.items()])
        ok = certify_segments(mechanism, p[heads], p[tails], post[heads], sign, res)
        sizes = np.cumsum([js.size for _, js in waiting.values()])
        asked = {
            f: _advance(searches[f], part)
            for f, part in zip(waiting, np.split(ok, sizes[:-1]), strict=True)
        }
    kept = np.unique(np.concatenate([anchors, *[f + np.asarray(k) for f, k in done.items()]]))

    def test(starts: Array, ends: Array, at: NDArray[np.intp]) -> NDArray[np.bool_]:
        return certify_segments(mechanism, starts, ends, post[kept[at]], sign, res)

    corners, origin = cut_corners(test, p[kept], ~keep[kept], rounds=rounds)
    # a vertex added by cutting lies in the stretch of the kept vertex before it
    source = np.maximum.accumulate(np.where(origin >= 0, origin, 0))
    origin = np.where(origin >= 0, kept[np.maximum(origin, 0)], -1)
    return corners, post[kept[source]], origin


def _subdivide(
    p: Array, post: NDArray[np.intp], gap: float
) -> tuple[Array, NDArray[np.intp], NDArray[np.intp]]:
    """Poses added along each segment so that consecutive ones are at most ``gap``
    apart (in the posture of the segment's end); with the index in the input of
    each pose, -1 for those added."""
    count = np.maximum(1, np.ceil(np.linalg.norm(np.diff(p, axis=0), axis=1) / gap))
    count = np.concatenate([[1], count]).astype(np.intp)
    seg = np.repeat(np.arange(p.shape[0]), count)  # the segment ending at pose seg
    rank = np.arange(seg.size) - np.repeat(np.cumsum(count) - count, count) + 1
    t = (rank / count[seg])[:, None]
    before = p[np.maximum(seg - 1, 0)]
    out = np.where(rank[:, None] == count[seg][:, None], p[seg], before + t * (p[seg] - before))
    inside = np.where(rank == count[seg], seg, -1).astype(np.intp)
    return out, post[seg], inside


def path_length(values: ArrayLike) -> float:
    """Euclidean length of a polyline (the sum of its segments' lengths).

    Examples
    --------
    >>> path_length([[0.0, 0.0], [3.0, 4.0], [3.0, 5.0]])
    6.0
    """
    v = np.asarray(values, dtype=np.float64)
    if v.ndim == 1:
        v = v[:, None]
    return float(np.linalg.norm(np.diff(v, axis=0), axis=1).sum())
