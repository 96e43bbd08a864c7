"""Bad input gives clear errors of the documented types, naming the parameter at fault."""

from __future__ import annotations

import re
import zipfile
from pathlib import Path

import numpy as np
import pytest

from moveability import (
    BOUNDARY,
    IN,
    OUT,
    HyperTree,
    IncompatibleTreesError,
    InvalidParameterError,
    MoveabilityError,
    ResolutionError,
    adjacency,
    components,
    equals,
    load,
    locate,
    project,
)

IN_, OUT_, BND = int(IN), int(OUT), int(BOUNDARY)


def half(lo, hi):
    """x < 0.3 on the first axis."""
    return np.where(hi[:, 0] < 0.3, IN_, np.where(lo[:, 0] > 0.3, OUT_, BND))


def tree2(**kw):
    kw.setdefault("max_depth", 3)
    return HyperTree.build([0.0, 0.0], [1.0, 1.0], half, **kw)


def raises(exc, *names):
    """``pytest.raises`` for ``exc`` whose message names every one of ``names``."""
    return pytest.raises(exc, match="(?s)" + "".join(f"(?=.*{re.escape(n)})" for n in names))


def test_exception_hierarchy():
    assert issubclass(InvalidParameterError, ValueError)
    assert issubclass(InvalidParameterError, MoveabilityError)
    assert issubclass(ResolutionError, InvalidParameterError)
    assert issubclass(IncompatibleTreesError, InvalidParameterError)
    err = InvalidParameterError("foo", "a bar", 3)
    assert err.name == "foo" and "foo" in str(err) and "a bar" in str(err) and "3" in str(err)
    long = InvalidParameterError("foo", "x", "y" * 1000)
    assert len(str(long)) < 200


# ------------------------------------------------------------------ box
@pytest.mark.parametrize(
    ("lo", "hi", "names"),
    [
        ([0.0, 1.0], [1.0, 1.0], ("hi[1]", "lo[1]")),  # lo == hi
        ([0.0, 2.0], [1.0, 1.0], ("hi[1]", "lo[1]")),  # lo > hi
        ([np.nan, 0.0], [1.0, 1.0], ("lo",)),
        ([0.0, 0.0], [1.0, np.inf], ("hi",)),
        ([0.0, 0.0], [1.0, 1.0, 1.0], ("lo", "hi")),  # mismatched lengths
        ([[0.0, 0.0]], [[1.0, 1.0]], ("lo", "hi")),  # not 1-D
        ([], [], ("lo",)),  # k = 0
        ([0.0] * 13, [1.0] * 13, ("lo", "12")),  # k = 13
        (["a", "b"], [1.0, 1.0], ("lo",)),
    ],
)
def test_bad_box(lo, hi, names):
    with raises(InvalidParameterError, *names):
        HyperTree.build(lo, hi, half, max_depth=1)


def test_bad_box_in_from_array():
    with raises(InvalidParameterError, "hi[0]", "lo[0]"):
        HyperTree.from_array(np.ones(4, dtype=bool), [1.0], [1.0])
    with raises(InvalidParameterError, "lo", "hi"):
        HyperTree.from_array(np.ones(4, dtype=bool), [0.0, 0.0], [1.0])
    with raises(InvalidParameterError, "lo"):
        HyperTree.from_array(np.ones(4, dtype=bool), [np.nan], [1.0])


def test_twelve_axes_are_allowed():
    t = HyperTree.build([0.0] * 12, [1.0] * 12, lambda lo, hi: np.full(len(lo), IN_), max_depth=1)
    assert t.ndim == 12 and len(t) == 1


# ------------------------------------------------------------ max_depth
@pytest.mark.parametrize("max_depth", [-1, (2, -1), 1.5, (1.0, 2.0), (1, 2, 3), "3", True])
def test_bad_max_depth(max_depth):
    with raises(InvalidParameterError, "max_depth"):
        HyperTree.build([0.0, 0.0], [1.0, 1.0], half, max_depth=max_depth)


@pytest.mark.parametrize(
    ("k", "max_depth"), [(1, 63), (2, (40, 23)), (2, 32), (12, 6), (6, (11, 11, 11, 11, 9, 10))]
)
def test_max_depth_too_large(k, max_depth):
    with raises(ResolutionError, "max_depth", "62"):
        HyperTree.build([0.0] * k, [1.0] * k, half, max_depth=max_depth)


def test_max_depth_62_is_accepted():
    t = HyperTree.build([0.0, 0.0], [1.0, 1.0], half, max_depth=(60, 2))
    assert t.max_depth == (60, 2)
    assert int(t.levels.max()) == 60
    t = HyperTree.build([0.0], [1.0], half, max_depth=62)
    assert t.max_depth == (62,)
    # the boundary x = 0.3 is followed to the finest level
    assert int(t.levels.max()) == 62


def test_build_exceeding_max_leaves():
    def disk(lo, hi):
        near = np.sqrt(((np.clip(0.5, lo, hi) - 0.5) ** 2).sum(axis=1))
        far = np.sqrt((np.maximum(np.abs(lo - 0.5), np.abs(hi - 0.5)) ** 2).sum(axis=1))
        return np.where(far <= 0.3, IN_, np.where(near > 0.3, OUT_, BND))

    with raises(ResolutionError, "max_depth", "max_leaves=500") as info:
        HyperTree.build([0.0, 0.0], [1.0, 1.0], disk, max_depth=8, max_leaves=500)
    assert info.value.name == "max_depth"
    # the same build within the budget succeeds
    t = HyperTree.build([0.0, 0.0], [1.0, 1.0], disk, max_depth=8)
    assert len(t) > 500
    assert len(HyperTree.build([0.0, 0.0], [1.0, 1.0], disk, max_depth=8, max_leaves=len(t) * 2))


@pytest.mark.parametrize("max_leaves", [0, -5])
def test_bad_max_leaves(max_leaves):
    with raises(InvalidParameterError, "max_leaves"):
        HyperTree.build([0.0], [1.0], half, max_depth=2, max_leaves=max_leaves)


# ------------------------------------------------------------- classify
@pytest.mark.parametrize(
    "classify",
    [
        lambda lo, hi: np.full(len(lo) + 1, IN_),  # one too many
        lambda lo, hi: np.full((len(lo), 1), IN_),  # 2-D
        lambda lo, hi: IN_,  # a scalar
        lambda lo, hi: np.full(len(lo), 1.0),  # floats
        lambda lo, hi: np.full(len(lo), "IN"),  # strings
        lambda lo, hi: None,
    ],
)
def test_classify_wrong_shape_or_type(classify):
    with raises(InvalidParameterError, "classify"):
        HyperTree.build([0.0, 0.0], [1.0, 1.0], classify, max_depth=2)


@pytest.mark.parametrize("value", [0, 3, 5, 8, -1, 255])
def test_classify_invalid_status(value):
    with raises(InvalidParameterError, "classify", str(value)):
        HyperTree.build([0.0], [1.0], lambda lo, hi: np.full(len(lo), value), max_depth=2)


def test_classify_invalid_status_at_a_deeper_level():
    def classify(lo, hi):
        return np.where(hi[:, 0] - lo[:, 0] > 0.3, BND, 3)

    with raises(InvalidParameterError, "classify"):
        HyperTree.build([0.0], [1.0], classify, max_depth=4)


def test_classify_not_callable():
    with raises(InvalidParameterError, "classify"):
        HyperTree.build([0.0], [1.0], "half", max_depth=2)


# ------------------------------------------------------------- periodic
@pytest.mark.parametrize("periodic", [[2], [-1], [0, 5], ["x"], [None]])
def test_bad_periodic(periodic):
    with raises(InvalidParameterError, "periodic"):
        HyperTree.build([0.0, 0.0], [1.0, 1.0], half, max_depth=2, periodic=periodic)
    with raises(InvalidParameterError, "periodic"):
        HyperTree.from_array(np.ones((2, 2), dtype=bool), periodic=periodic)


# ------------------------------------------------------- combining trees
def other_trees():
    return {
        "box": HyperTree.build([0.0, 0.0], [1.0, 2.0], half, max_depth=3),
        "shifted box": HyperTree.build([0.5, 0.0], [1.5, 1.0], half, max_depth=3),
        "periodic": tree2(periodic=[0]),
        "dimension": HyperTree.build([0.0, 0.0, 0.0], [1.0, 1.0, 1.0], half, max_depth=3),
        "one axis": HyperTree.build([0.0], [1.0], half, max_depth=3),
    }


@pytest.mark.parametrize("which", list(other_trees()))
def test_incompatible_trees(which):
    a, b = tree2(), other_trees()[which]
    for op in (
        lambda x, y: x | y,
        lambda x, y: x & y,
        lambda x, y: x - y,
    ):
        with raises(IncompatibleTreesError, "other"):
            op(a, b)
        with raises(IncompatibleTreesError, "other"):
            op(b, a)
    assert (a == b) is False
    assert (b == a) is False
    assert a != b
    assert equals(a, b) is False
    # the same trees compare equal to themselves
    assert a == a and b == b


def test_incompatible_periodicity_both_periodic():
    a, b = tree2(periodic=[0]), tree2(periodic=[1])
    with raises(IncompatibleTreesError, "periodic"):
        a | b
    assert (a == b) is False
    assert tree2(periodic=[0]) == a


def test_combining_with_something_else():
    a = tree2()
    with raises(IncompatibleTreesError, "other"):
        a | 3
    with raises(IncompatibleTreesError, "other"):
        a & np.ones(4)
    assert (a == 3) is False
    assert (a == "tree") is False
    with pytest.raises(TypeError):
        hash(a)


# ---------------------------------------------------------- connectivity
@pytest.mark.parametrize("connectivity", [0, 3, -1, 1.0, True, "1", None])
def test_bad_connectivity(connectivity):
    t = tree2()
    with raises(InvalidParameterError, "connectivity", "[1, 2]"):
        components(t, connectivity=connectivity)
    with raises(InvalidParameterError, "connectivity"):
        adjacency(t, connectivity=connectivity)


def test_connectivity_bounds_are_allowed():
    t = tree2()
    assert components(t, connectivity=1)[1] == 1
    assert components(t, connectivity=2)[1] == 1
    assert components(t, connectivity=np.int64(2))[1] == 1


# --------------------------------------------------------------- project
@pytest.mark.parametrize(
    ("axes", "names"),
    [
        ([0, 0], ("axes", "distinct")),
        ([1, 0, 1], ("axes", "distinct")),
        ([], ("axes",)),
        ([2], ("axes", "[0, 1]")),
        ([-1], ("axes", "[0, 1]")),
        ([0, 5], ("axes",)),
        (["x"], ("axes",)),
        (None, ("axes",)),
    ],
)
def test_bad_project_axes(axes, names):
    with raises(InvalidParameterError, *names):
        project(tree2(), axes)


# ---------------------------------------------------------------- locate
@pytest.mark.parametrize(
    ("points", "names"),
    [
        ([[0.5, np.nan]], ("points[0]", "finite")),
        ([[0.5, 0.5], [np.inf, 0.1]], ("points[1]", "finite")),
        ([[0.5, 0.5, 0.5]], ("points", "(m, 2)")),
        ([0.5], ("points", "(m, 2)")),
        (np.zeros((2, 2, 2)), ("points", "(m, 2)")),
        (0.5, ("points",)),
        ([["a", "b"]], ("points",)),
    ],
)
def test_bad_locate_points(points, names):
    with raises(InvalidParameterError, *names):
        locate(tree2(), points)


def test_locate_empty_and_outside():
    status, index = locate(tree2(), np.zeros((0, 2)))
    assert status.shape == (0,) and index.shape == (0,)
    status, index = locate(tree2(), [[-0.1, 0.5], [0.5, 1.0000001], [0.1, 0.5]])
    assert status.tolist() == [OUT_, OUT_, IN_]
    assert index[:2].tolist() == [-1, -1] and index[2] >= 0


# ------------------------------------------------------------ from_array
@pytest.mark.parametrize(
    ("values", "names"),
    [
        (np.ones(3, dtype=bool), ("values", "powers of two")),
        (np.ones((4, 6), dtype=bool), ("values", "powers of two")),
        (np.ones((0,), dtype=bool), ("values",)),
        (np.array(True), ("values",)),
        (np.ones((1,) * 13, dtype=bool), ("values", "12")),
        (np.full(4, 3), ("values",)),
        (np.full(4, 0), ("values",)),
        (np.full(4, -1), ("values",)),
        (np.full(4, 1.0), ("values",)),
    ],
)
def test_bad_from_array(values, names):
    with raises(InvalidParameterError, *names):
        HyperTree.from_array(values)


def test_from_array_one_cell_per_axis_is_allowed():
    t = HyperTree.from_array(np.array([[BND]]))
    assert t.max_depth == (0, 0) and t.status.tolist() == [BND]


# ---------------------------------------------------------------- select
@pytest.mark.parametrize(
    ("mask", "names"),
    [
        ("short", ("mask",)),
        ("long", ("mask",)),
        ("2d", ("mask",)),
        ("index", ("mask", "indices below")),
        ("negative", ("mask", "indices below")),
        ("float", ("mask",)),
    ],
)
def test_bad_select_mask(mask, names):
    t = tree2()
    n = len(t)
    bad = {
        "short": np.ones(n - 1, dtype=bool),
        "long": np.ones(n + 1, dtype=bool),
        "2d": np.ones((n, 1), dtype=bool),
        "index": np.array([0, n]),
        "negative": np.array([-n - 1]),
        "float": np.array([0.0, 1.0]),
    }[mask]
    with raises(InvalidParameterError, *names):
        t.select(bad)


def test_select_accepts_negative_indices():
    t = tree2()
    assert t.select([-1]).status.tolist() == [OUT_] * (len(t) - 1) + [int(t.status[-1])]


# ------------------------------------------------------------------ load
def saved_fields(tmp_path):
    t = tree2(max_depth=4)
    path = tmp_path / "good.npz"
    t.save(path)
    with np.load(path) as data:
        return t, {name: data[name] for name in data.files}


def test_load_missing_file(tmp_path):
    path = tmp_path / "missing.npz"
    with raises(InvalidParameterError, "path", "missing.npz"):
        load(path)


def test_load_text_file(tmp_path):
    path = tmp_path / "text.npz"
    path.write_text("not a tree\n")
    with raises(InvalidParameterError, "path", "text.npz"):
        load(path)


def test_load_npz_of_other_arrays(tmp_path):
    path = tmp_path / "other.npz"
    np.savez(path, a=np.arange(3))
    with raises(InvalidParameterError, "path", "missing"):
        load(path)


@pytest.mark.parametrize("field", ["format", "keys", "levels", "status", "lo", "max_depth"])
def test_load_npz_missing_a_field(tmp_path, field):
    _, fields = saved_fields(tmp_path)
    del fields[field]
    path = tmp_path / "partial.npz"
    np.savez(path, **fields)
    with raises(InvalidParameterError, "path", field if field != "format" else "path"):
        load(path)


def test_load_wrong_format_name_and_version(tmp_path):
    t, fields = saved_fields(tmp_path)
    path = tmp_path / "bad.npz"
    np.savez(path, **{**fields, "format": np.array("something.else")})
    with raises(InvalidParameterError, "path"):
        load(path)
    np.savez(path, **{**fields, "version": np.array(99)})
    with raises(InvalidParameterError, "path", "99"):
        load(path)
    np.savez(path, **fields)
    assert load(path) == t


def corrupt(fields, how):
    keys, levels, status = fields["keys"], fields["levels"], fields["status"]
    if how == "drop a leaf":
        return {"keys": keys[1:], "levels": levels[1:], "status": status[1:]}
    if how == "drop the last leaf":
        return {"keys": keys[:-1], "levels": levels[:-1], "status": status[:-1]}
    if how == "duplicate a leaf":
        idx = np.r_[0, np.arange(len(keys))]
        return {"keys": keys[idx], "levels": levels[idx], "status": status[idx]}
    if how == "unsorted":
        idx = np.r_[1, 0, np.arange(2, len(keys))]
        return {"keys": keys[idx], "levels": levels[idx], "status": status[idx]}
    if how == "coarser level":
        lv = levels.copy()
        lv[-1] -= 1
        return {"levels": lv}
    if how == "finer level":
        lv = levels.copy()
        lv[0] += 1
        return {"levels": lv}
    if how == "level too deep":
        lv = levels.copy()
        lv[0] = 200
        return {"levels": lv}
    if how == "misaligned key":
        k = keys.copy()
        k[1] += 1
        return {"keys": k}
    if how == "no leaves":
        empty = np.zeros(0, dtype=np.uint8)
        return {"keys": np.zeros(0, dtype=np.uint64), "levels": empty, "status": empty}
    raise AssertionError(how)


@pytest.mark.parametrize(
    "how",
    [
        "drop a leaf",
        "drop the last leaf",
        "duplicate a leaf",
        "unsorted",
        "coarser level",
        "finer level",
        "level too deep",
        "misaligned key",
        "no leaves",
    ],
)
def test_load_corrupted_partition(tmp_path, how):
    t, fields = saved_fields(tmp_path)
    assert len(t) > 3
    path = tmp_path / "corrupt.npz"
    np.savez(path, **{**fields, **corrupt(fields, how)})
    with raises(InvalidParameterError, "path", "tiling"):
        load(path)


@pytest.mark.parametrize(
    ("change", "names"),
    [
        ({"status": "bad status"}, ("status",)),
        ({"keys": "short keys"}, ("keys",)),
        ({"periodic": np.array([7])}, ("periodic",)),
        ({"lo": np.array([1.0, 0.0])}, ("hi[0]",)),
        ({"max_depth": np.array([40, 40])}, ("max_depth",)),
    ],
)
def test_load_inconsistent_fields(tmp_path, change, names):
    _, fields = saved_fields(tmp_path)
    new = dict(fields)
    for key, value in change.items():
        if isinstance(value, str) and value == "bad status":
            s = fields["status"].copy()
            s[0] = 3
            new[key] = s
        elif isinstance(value, str) and value == "short keys":
            new[key] = fields["keys"][:-1]
        else:
            new[key] = value
    path = tmp_path / "inconsistent.npz"
    np.savez(path, **new)
    with raises(InvalidParameterError, *names):
        load(path)


# Damaged files: each should be reported as an InvalidParameterError naming ``path``,
# like the text file above, not leak the reader's own exception.
def test_load_truncated_npz(tmp_path):
    tree2().save(tmp_path / "good.npz")
    raw = (tmp_path / "good.npz").read_bytes()
    path = tmp_path / "truncated.npz"
    path.write_bytes(raw[: len(raw) // 2])
    assert raw[:2] == b"PK"
    with raises(InvalidParameterError, "path"):
        load(path)


def test_load_empty_file(tmp_path):
    path = tmp_path / "empty.npz"
    path.write_bytes(b"")
    with raises(InvalidParameterError, "path"):
        load(path)


def test_load_npy_file(tmp_path):
    path = tmp_path / "array.npy"
    np.save(path, np.arange(3))
    with raises(InvalidParameterError, "path"):
        load(path)


def test_load_zip_with_a_damaged_member(tmp_path):
    _, fields = saved_fields(tmp_path)
    path = tmp_path / "damaged.npz"
    np.savez(path, **fields)  # stored, not compressed: the bytes of each array are in clear
    raw = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as z:
        info = z.getinfo("status.npy")
    # flip a byte inside the data of status.npy: its CRC no longer matches
    at = info.header_offset + 30 + len(info.filename) + len(info.extra) + info.file_size - 1
    raw[at] ^= 0xFF
    path.write_bytes(bytes(raw))
    with raises(InvalidParameterError, "path"):
        load(path)


def test_combining_very_different_per_axis_depths_is_a_resolution_error():
    def disk(lo, hi):
        near = np.sqrt(((np.clip(0.5, lo, hi) - 0.5) ** 2).sum(axis=1))
        far = np.sqrt((np.maximum(abs(lo - 0.5), abs(hi - 0.5)) ** 2).sum(axis=1))
        return np.where(far <= 0.4, IN, np.where(near > 0.4, OUT, BOUNDARY))

    a = HyperTree.build([0, 0], [1, 1], disk, max_depth=(14, 0))
    b = HyperTree.build([0, 0], [1, 1], disk, max_depth=(2, 12))
    with pytest.raises(ResolutionError, match="other"):
        a | b


def test_precision_too_fine_for_the_memory_available(monkeypatch):
    """With little memory available the leaf budget shrinks, and a precision whose
    tree cannot fit is refused while the tree is still small."""
    import moveability.analysis.result as result_module
    from moveability import analyze
    from moveability.mechanisms import FiveBar

    mechanism = FiveBar(7, 8, 5, 8, 5)
    monkeypatch.setattr(result_module, "available_memory", lambda: 64 * 2**20)
    budget = result_module.leaf_budget(mechanism)
    assert budget == 1 << 16  # the floor: 64 MiB hold fewer leaves
    classified = []
    classify = result_module.classify_sheets

    def counting(mechanism, lo, hi, **options):
        classified.append(len(lo))
        return classify(mechanism, lo, hi, **options)

    monkeypatch.setattr(result_module, "classify_sheets", counting)
    with raises(ResolutionError, "precision", "memory", f"max_leaves={budget}"):
        analyze(mechanism, precision=1e-4)
    # refused on the growth of the undecided cells, long before the budget is held
    assert 0 < sum(classified) < budget // 4
    # the same analysis at a coarse precision still runs within that budget
    assert analyze(mechanism, precision=0.2).count == (2, 2)


def test_leaf_budget_follows_the_memory_and_the_postures():
    from moveability.analysis.result import MAX_LEAVES, leaf_budget
    from moveability.mechanisms import FiveBar, from_spec, load_spec

    five_bar = FiveBar(7, 8, 5, 8, 5)
    examples = Path(__file__).resolve().parent.parent / "examples"
    delta = from_spec(load_spec(examples / "delta.toml"))
    gib = 2**30
    # (1 + postures) KiB a leaf for three quarters of the memory
    assert leaf_budget(five_bar, available=8 * gib) == int(0.75 * 8 * gib // (5 * 1024))
    assert leaf_budget(delta, available=8 * gib) == int(0.75 * 8 * gib // (9 * 1024))
    assert leaf_budget(five_bar, available=10**15) == MAX_LEAVES
    assert leaf_budget(five_bar, available=1) == 1 << 16
