"""Saved analyses: an :class:`~moveability.analysis.result.Analysis` in one ``.npz`` file.

The file holds the mechanism's spec, the precision, the tree, the sheet table
and the rest of the evidence (touching pairs, flows), so that loading it
repeats no interval computation: only the graphs are joined again, which is
quick. A SHA-256 digest of every array guards against a damaged file; a file
of another format version is refused. Written to a temporary file in the
same folder and renamed, so that an interrupted save leaves no partial file.
"""

from __future__ import annotations

import hashlib
import json
import os
import secrets
from dataclasses import fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ..hypertree.tree import HyperTree, read_archive
from ..mechanisms import from_spec
from .joint_space import JointSpaceCount
from .result import Analysis, Evidence
from .sheets import SheetTable

__all__ = ["FORMAT", "FORMAT_VERSION", "load_analysis", "save_analysis"]

#: the ``format`` field of a saved analysis
FORMAT = "moveability.Analysis"
#: raised whenever the fields change
FORMAT_VERSION = 4
_FLOWS = ("nodes", "bits", "exists", "faces")
_WHAT = "a file written by moveability analyze --out (save_analysis)"


def _digest(arrays: dict[str, NDArray[Any]]) -> str:
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}:{a.dtype.str}:{a.shape};".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def save_analysis(result: Analysis, path: str | os.PathLike[str]) -> None:
    """Write ``result`` to a ``.npz`` file that :func:`load_analysis` reads back.

    Examples
    --------
    >>> import os, tempfile
    >>> from moveability import analyze
    >>> from moveability.mechanisms import FiveBar
    >>> result = analyze(FiveBar(), precision=0.5)
    >>> path = os.path.join(tempfile.mkdtemp(), "five-bar.npz")
    >>> save_analysis(result, path)
    >>> again = load_analysis(path)
    >>> again.count == result.count, len(again.tree) == len(result.tree)
    (True, True)
    """
    tree, evidence = result.tree, result.evidence()
    arrays: dict[str, NDArray[Any]] = {
        "spec": np.array(json.dumps(result.mechanism.to_spec())),
        "precision": np.asarray(result.precisions, dtype=np.float64),
        "generalized_aspects": np.array(result.generalized_aspects),
        "lo": tree.lo,
        "hi": tree.hi,
        "max_depth": np.asarray(tree.max_depth, dtype=np.int64),
        "keys": tree.keys,
        "levels": tree.levels,
        "status": tree.status,
        "pairs": evidence.pairs,
        "face_pairs": evidence.face_pairs,
        "contact": evidence.contact,
    }
    arrays.update({f"flows.{n}": a for n, a in zip(_FLOWS, evidence.flows, strict=True)})
    arrays.update({f"table.{f.name}": getattr(result.table, f.name) for f in fields(SheetTable)})
    count = result.joint_count
    if count is not None:
        arrays["joint_count"] = np.array(
            [count.at_least, -1 if count.at_most is None else count.at_most, count.leaves]
        )
        arrays["joint_open_measure"] = np.array(count.open_measure)
        arrays["joint_witnesses"] = np.asarray(count.witnesses, dtype=np.float64)
        arrays["joint_notes"] = np.array(count.notes, dtype=np.str_)
        arrays["joint_witness_poses"] = np.asarray(count.witnessed, dtype=bool)
    arrays["digest"] = np.array(_digest(arrays))
    arrays["format"] = np.array(FORMAT)
    arrays["version"] = np.array(FORMAT_VERSION)
    target = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(target))
    temporary = os.path.join(folder, f".moveability-{secrets.token_hex(6)}.npz")
    try:
        # created as open() would: its mode follows the umask
        handle = os.open(temporary, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666)
        with os.fdopen(handle, "wb") as stream:
            np.savez_compressed(stream, **arrays)  # type: ignore[arg-type]
        os.replace(temporary, target)
    finally:
        if os.path.exists(temporary):
            os.unlink(temporary)


def load_analysis(path: str | os.PathLike[str]) -> Analysis:
    """Read an analysis written by :func:`save_analysis`, without recomputing it.

    Raises :class:`~moveability.errors.InvalidParameterError` naming ``path``
    for a file that is missing, damaged, of another format version, or whose
    arrays do not fit together.
    """
    where = os.fspath(path)
    arrays = read_archive(path, _WHAT)
    if str(arrays.pop("format", "")) != FORMAT:
        raise InvalidParameterError("path", _WHAT, where)
    version = arrays.pop("version", None)
    if version is None or version.shape != () or int(version) != FORMAT_VERSION:
        found = "none" if version is None else str(version)
        raise InvalidParameterError(
            "path", f"a saved analysis of format version {FORMAT_VERSION}", f"{where} ({found})"
        )
    digest = str(arrays.pop("digest", ""))
    if digest != _digest(arrays):
        raise InvalidParameterError("path", "an undamaged saved analysis", f"{where} (digest)")
    try:
        return _rebuild(arrays)
    except (KeyError, ValueError, TypeError, IndexError) as error:
        raise InvalidParameterError("path", _WHAT, f"{where} ({error})") from None


def _rebuild(arrays: dict[str, NDArray[Any]]) -> Analysis:
    mechanism = from_spec(json.loads(str(arrays["spec"])))
    tree = HyperTree(
        arrays["lo"],
        arrays["hi"],
        tuple(int(d) for d in arrays["max_depth"]),
        arrays["keys"],
        arrays["levels"],
        arrays["status"],
        mechanism.periodic_axes,
    )
    table = SheetTable(**{f.name: arrays[f"table.{f.name}"] for f in fields(SheetTable)})
    n, n_post = len(tree), len(mechanism.postures)
    if table.status.shape != (n, n_post) or table.angles_lo.shape[:2] != (n, n_post):
        raise ValueError("the sheet table does not fit the tree")
    evidence = Evidence(
        arrays["pairs"],
        arrays["face_pairs"],
        arrays["contact"],
        tuple(arrays[f"flows.{name}"] for name in _FLOWS),
    )
    if evidence.contact.shape != (evidence.pairs.shape[0],):
        raise ValueError("the contacts do not fit the pairs")
    for pairs in (evidence.pairs, evidence.face_pairs):
        if pairs.ndim != 2 or pairs.shape[1] != 2 or (pairs.size and not 0 <= pairs.min()):
            raise ValueError("bad leaf pairs")
        if pairs.size and pairs.max() >= n:
            raise ValueError("leaf pairs beyond the tree")
    joint = None
    if "joint_count" in arrays:
        at_least, at_most, leaves = (int(v) for v in arrays["joint_count"])
        witnesses = np.asarray(arrays.get("joint_witnesses", np.zeros((0, 0))), dtype=np.float64)
        if witnesses.ndim != 2 or (witnesses.size and witnesses.shape[1] != len(mechanism.limits)):
            raise ValueError("bad witnesses of the joint-space count")
        witnessed = np.asarray(
            arrays.get("joint_witness_poses", np.ones((witnesses.shape[0], 2))), dtype=bool
        )
        if witnessed.shape != (witnesses.shape[0], 2):
            raise ValueError("bad witnesses of the joint-space count")
        joint = JointSpaceCount(
            at_least,
            None if at_most < 0 else at_most,
            leaves,
            float(arrays["joint_open_measure"]),
            witnesses,
            tuple(str(v) for v in np.atleast_1d(arrays.get("joint_notes", np.zeros(0, np.str_)))),
            witnessed,
        )
    eps = arrays["precision"]
    precision = float(eps[0]) if (eps == eps[0]).all() else tuple(float(v) for v in eps)
    return Analysis(
        mechanism,
        precision,
        tree,
        generalized_aspects=bool(arrays["generalized_aspects"]),
        table=table,
        joint_count=joint,
        evidence=evidence,
    )
