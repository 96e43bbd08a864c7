"""Design sweeps: rows that match single analyses, resume, failures, tables and the map."""

from __future__ import annotations

import csv
import math

import pytest
from click.testing import CliRunner
from hypothesis import given
from hypothesis import strategies as st

import moveability.analysis.result
from moveability import analyze, load_spec
from moveability.cli import main
from moveability.errors import InvalidParameterError, ResolutionError
from moveability.sweep import (
    RESULT_COLUMNS,
    SweepProgress,
    Vary,
    design_grid,
    parse_vary,
    plot_sweep_map,
    read_table,
    restore_malloc_thresholds,
    run_sweep,
    table_columns,
)
from moveability.sweep import runner as runner_module
from moveability.sweep.figure import FAILED, MISSING, UNKNOWN, map_grid
from moveability.sweep.table import decode_cell, encode_cell

SPEC = "examples/five-bar-paper.toml"
UNLIMITED_SPEC = "examples/five-bar-unlimited.toml"
VARY = ["--vary", "L2=4.5:5.5:3", "--vary", "theta1.max=pi/2:pi:2"]
EPS = "0.25"
COLUMNS = ["L2", "theta1.max", *RESULT_COLUMNS]


def sweep(*args: str) -> object:
    return CliRunner().invoke(main, ["sweep", SPEC, *args])


def by_key(rows, names=("L2", "theta1.max")):
    return {tuple(row[n] for n in names): row for row in rows}


def without_seconds(rows):
    return sorted(
        (tuple((k, v) for k, v in row.items() if k != "seconds") for row in rows), key=repr
    )


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    """The 3 x 2 sweep of the paper's five-bar, through the command line."""
    out = tmp_path_factory.mktemp("sweep") / "designs.csv"
    result = CliRunner().invoke(main, ["sweep", SPEC, *VARY, "-p", EPS, "--out", str(out)])
    assert result.exit_code == 0, result.output
    return out, result


# ------------------------------------------------------------------ rows
def test_rows_match_single_analyses(swept):
    out, result = swept
    assert "6 designs: 6 computed, 0 already in" in result.output
    columns, rows = read_table(out)
    assert columns == COLUMNS
    assert len(rows) == 6
    table = by_key(rows)
    assert set(table) == {(l2, t) for l2 in (4.5, 5.0, 5.5) for t in (math.pi / 2, math.pi)}
    for (l2, t_max), row in table.items():
        spec = {
            "mechanism": "five-bar",
            "parameters": {"L0": 7, "L1": 8, "L2": l2, "L3": 8, "L4": 5},
            "limits": {"theta1": [0.0, t_max], "theta2": [0.0, "pi"]},
        }
        direct = analyze(spec, precision=float(EPS), resolve=True)
        inner, outer = direct.workspace["area"]
        assert row["error"] is None
        assert row["workspace_inner"] == inner
        assert row["workspace_outer"] == outer
        assert row["n_connected"] is direct.n_connected
        # the count where it is proved, and its bounds
        assert row["regions"] == direct.n_regions
        assert (row["regions_at_least"], row["regions_at_most"]) == direct.count
        largest = max(r.area[0] for r in direct.regions)
        assert row["largest_share"] == largest / outer
        assert 0 < row["largest_share"] <= 1
        assert row["seconds"] > 0
    # at this precision some designs are resolved: the comparison is not vacuous
    assert {row["regions"] for row in rows} >= {2}


def test_csv_text_is_exact_and_in_column_order(swept):
    out, _ = swept
    with open(out, newline="") as stream:
        lines = list(csv.reader(stream))
    assert lines[0] == COLUMNS
    for cells in lines[1:]:
        assert cells[COLUMNS.index("n_connected")] in ("true", "false", "")
        assert cells[COLUMNS.index("error")] == ""
        value = float(cells[1])
        assert cells[1] == repr(value)  # floats as repr: they read back exactly


def test_paper_design_row(tmp_path):
    """The paper's five-bar at 0.1: two regions, W not N-connected."""
    out = tmp_path / "paper.csv"
    assert sweep("--vary", "L2=5:5:1", "--out", str(out)).exit_code == 0
    (row,) = read_table(out)[1]
    direct = analyze(load_spec(SPEC), precision=0.1, resolve=True)
    assert row["regions"] == 2 == direct.n_regions
    assert row["n_connected"] is False
    assert row["workspace_outer"] == direct.workspace["area"][1]


# ------------------------------------------------------------------ resume
def count_designs(monkeypatch):
    calls = []
    original = runner_module.design_row

    def counted(spec, names, values, precision, analyze=None, resolve=True):
        calls.append(tuple(values))
        return original(spec, names, values, precision, analyze, resolve)

    monkeypatch.setattr(runner_module, "design_row", counted)
    return calls


def test_resume_computes_only_missing_rows(tmp_path, monkeypatch):
    out = tmp_path / "designs.csv"
    calls = count_designs(monkeypatch)
    assert sweep(*VARY, "-p", "0.5", "--out", str(out)).exit_code == 0
    assert len(calls) == 6
    text = out.read_text().splitlines()
    # drop two rows, and cut the last one short as a sweep killed while writing would
    kept = [*text[:3], text[4]]
    out.write_text("\n".join(kept) + "\n" + text[5][:10])
    calls.clear()
    result = sweep(*VARY, "-p", "0.5", "--out", str(out))
    assert result.exit_code == 0, result.output
    assert "6 designs: 3 computed, 3 already in" in result.output
    redone = {tuple(float(c) for c in line.split(",")[:2]) for line in (text[3], text[5], text[6])}
    assert set(calls) == redone
    lines = out.read_text().splitlines()
    assert lines[:4] == kept  # the rows already there are untouched
    assert len(lines) == 7
    # a third run has nothing left to do
    calls.clear()
    result = sweep(*VARY, "-p", "0.5", "--out", str(out))
    assert "6 designs: 0 computed, 6 already in" in result.output
    assert calls == []


def test_resume_with_more_values_adds_the_new_designs(tmp_path, monkeypatch):
    out = tmp_path / "designs.csv"
    calls = count_designs(monkeypatch)
    assert sweep("--vary", "L2=4:6:2", "-p", "0.5", "--out", str(out)).exit_code == 0
    result = sweep("--vary", "L2=4:6:3", "-p", "0.5", "--out", str(out))
    assert "3 designs: 1 computed, 2 already in" in result.output
    assert calls == [(4.0,), (6.0,), (5.0,)]


def test_other_sweep_in_out_is_refused(tmp_path):
    out = tmp_path / "designs.csv"
    assert sweep("--vary", "L2=4:6:2", "-p", "0.5", "--out", str(out)).exit_code == 0
    before = out.read_text()
    result = sweep("--vary", "L1=7:8:2", "-p", "0.5", "--out", str(out))
    assert result.exit_code == 2
    assert result.output.count("\n") == 1
    assert "invalid --out" in result.output and "sweep over L2" in result.output
    assert out.read_text() == before


# ------------------------------------------------------------------ failures
def test_failing_designs_are_recorded_and_the_sweep_goes_on(tmp_path, monkeypatch):
    out = tmp_path / "designs.csv"
    original = moveability.analysis.result.analyze

    def fragile(spec, precision, **kwargs):
        if spec["parameters"]["L1"] == 9.0:
            raise ResolutionError("precision", "a precision that fits", precision)
        return original(spec, precision, **kwargs)

    monkeypatch.setattr(moveability.analysis.result, "analyze", fragile)
    result = sweep(
        "--vary", "L1=8:9:2", "--vary", "theta1.min=-1:4:2", "-p", "0.5", "--out", str(out)
    )
    assert result.exit_code == 0, result.output
    assert "4 designs: 4 computed, 0 already in" in result.output and "3 failed" in result.output
    rows = by_key(read_table(out)[1], ("L1", "theta1.min"))
    assert rows[8.0, -1.0]["error"] is None
    assert rows[8.0, -1.0]["workspace_inner"] > 0
    # theta1.min = 4 > pi: not a valid spec
    assert rows[8.0, 4.0]["error"].startswith(
        "invalid limits.theta1: expected [lo, hi] with lo < hi"
    )
    assert rows[9.0, -1.0]["error"] == "invalid precision: expected a precision that fits, got 0.5"
    for key in ((8.0, 4.0), (9.0, -1.0), (9.0, 4.0)):
        assert rows[key]["workspace_inner"] is None and rows[key]["n_connected"] is None

    # a rerun keeps the failures; --retry-errors computes them again, without duplicates
    calls = count_designs(monkeypatch)
    args = ["--vary", "L1=8:9:2", "--vary", "theta1.min=-1:4:2", "-p", "0.5", "--out", str(out)]
    assert "0 computed" in sweep(*args).output
    monkeypatch.setattr(moveability.analysis.result, "analyze", original)
    result = sweep(*args, "--retry-errors")
    assert "3 computed, 1 already in" in result.output and "2 failed" in result.output
    assert sorted(calls) == [(8.0, 4.0), (9.0, -1.0), (9.0, 4.0)]
    _, rows = read_table(out)
    assert len(rows) == 4
    assert by_key(rows, ("L1", "theta1.min"))[9.0, -1.0]["error"] is None


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize(
    ("vary", "named"),
    [
        ("L9=1:2:3", "--vary L9"),
        ("L2=1:2", "--vary"),
        ("L2", "--vary"),
        ("L2=a:2:3", "--vary L2 START"),
        ("L2=1:inf:3", "--vary L2 STOP"),
        ("L2=1:2:0", "--vary L2 COUNT"),
        ("L2=1:2:2.5", "--vary L2 COUNT"),
        ("theta1.max=pi/2:2pi:3", "--vary theta1.max STOP"),
        ("theta1.mid=0:1:2", "--vary theta1.mid"),
        ("x.min=0:1:2", "--vary x.min"),
    ],
)
def test_bad_vary_exits_2_with_one_line(tmp_path, vary, named):
    out = tmp_path / "designs.csv"
    result = sweep("--vary", vary, "--out", str(out))
    assert result.exit_code == 2
    assert result.output.count("\n") == 1
    assert result.output.startswith(f"Error: invalid {named}")
    assert not out.exists()


def test_limit_end_of_unlimited_joint(tmp_path):
    result = CliRunner().invoke(
        main,
        ["sweep", UNLIMITED_SPEC, "--vary", "theta1.min=0:1:2", "--out", str(tmp_path / "o.csv")],
    )
    assert result.exit_code == 2
    assert "invalid --vary theta1.min" in result.output and "unlimited" in result.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["--vary", "L2=4:5:2", "--vary", "L2=6:7:2"],
            "invalid --vary L2: expected each name once",
        ),
        (["--vary", "L2=4:5:2", "--jobs", "0"], "invalid --jobs"),
        (["--vary", "L2=4:5:2", "--jobs", "two"], "invalid --jobs"),
        (
            ["--vary", "L2=4:5:2", "--jobs", "2", "--scheduler", "tcp://127.0.0.1:9"],
            "invalid --jobs",
        ),
        (["--vary", "L2=4:5:2", "--figure", "m.png"], "invalid --figure"),
        (["--vary", "L2=4:5:2", "--precision", "0"], "invalid --precision"),
    ],
)
def test_bad_options_exit_2_with_one_line(tmp_path, args, message):
    result = sweep(*args, "--out", str(tmp_path / "o.csv"))
    assert result.exit_code == 2
    assert result.output.count("\n") == 1
    assert result.output.startswith(f"Error: {message}")


def test_bad_out(tmp_path):
    result = sweep("--vary", "L2=4:5:2", "--out", str(tmp_path / "o.xlsx"))
    assert result.exit_code == 2 and "invalid --out" in result.output
    result = sweep("--vary", "L2=4:5:2", "--out", str(tmp_path / "none" / "o.csv"))
    assert result.exit_code == 2 and "invalid --out" in result.output


# ------------------------------------------------------------------ designs
def test_vary_values_and_grid():
    spec = load_spec(SPEC)
    assert parse_vary("L2=4:6:1", spec).values == (4.0,)
    assert parse_vary(" L2 = 6:4:3", spec).values == (6.0, 5.0, 4.0)
    assert parse_vary("theta2.min=-pi:0:3", spec).values == (-math.pi, -math.pi / 2, 0.0)
    grid = design_grid([Vary("a", (1.0, 2.0)), Vary("b", (3.0,)), Vary("c", (4.0, 5.0))])
    assert len(grid) == 4 and grid[1] == (1.0, 3.0, 5.0)
    with pytest.raises(InvalidParameterError, match="--vary"):
        parse_vary("L2=1:2:3:4", spec)


@given(
    start=st.floats(-1e6, 1e6, allow_nan=False),
    stop=st.floats(-1e6, 1e6, allow_nan=False),
    count=st.integers(1, 50),
)
def test_vary_property(start, stop, count):
    spec = load_spec(SPEC)
    values = parse_vary(f"L1={start!r}:{stop!r}:{count}", spec).values
    assert len(values) == count
    assert values[0] == start
    if count > 1:
        assert values[-1] == stop


@given(st.one_of(st.floats(allow_nan=False, allow_infinity=False), st.none()))
def test_cells_read_back_exactly(value):
    assert decode_cell("workspace_inner", encode_cell(value)) == value


# ------------------------------------------------------------------ parquet
def test_parquet_round_trip_and_resume(tmp_path, swept, monkeypatch):
    csv_out, _ = swept
    out = tmp_path / "designs.parquet"
    result = sweep(*VARY, "-p", EPS, "--out", str(out))
    assert result.exit_code == 0, result.output
    columns, rows = read_table(out)
    assert columns == COLUMNS
    assert without_seconds(rows) == without_seconds(read_table(csv_out)[1])

    import pyarrow.parquet as pq

    schema = pq.read_schema(out)
    assert str(schema.field("regions").type) == "int64"
    assert str(schema.field("n_connected").type) == "bool"
    assert str(schema.field("error").type) == "string"

    # resume: drop rows, rerun, only they are computed
    pq.write_table(pq.read_table(out).slice(0, 4), out)
    calls = count_designs(monkeypatch)
    result = sweep(*VARY, "-p", EPS, "--out", str(out))
    assert "2 computed, 4 already in" in result.output
    assert len(calls) == 2
    assert without_seconds(read_table(out)[1]) == without_seconds(rows)
    assert not list(tmp_path.glob("*.tmp"))


def test_parquet_header_checked(tmp_path):
    out = tmp_path / "designs.pq"
    assert sweep("--vary", "L2=4:6:2", "-p", "0.5", "--out", str(out)).exit_code == 0
    result = sweep("--vary", "L1=7:8:2", "-p", "0.5", "--out", str(out))
    assert result.exit_code == 2 and "invalid --out" in result.output


def test_run_sweep_from_python(tmp_path):
    spec = load_spec(SPEC)
    seen = []
    summary = run_sweep(
        spec,
        ["L2=4:6:2", Vary("theta1.max", (3.0,))],
        tmp_path / "designs.csv",
        precision=0.5,
        progress=lambda done, total: seen.append((done, total)),
    )
    assert summary == {"designs": 2, "skipped": 0, "computed": 2, "failed": 0}
    assert seen == [(0, 2), (1, 2), (2, 2)]
    assert read_table(tmp_path / "designs.csv")[0] == list(table_columns(["L2", "theta1.max"]))


# ------------------------------------------------------------------ figure
def test_figure_from_the_command(tmp_path):
    out, figure = tmp_path / "designs.csv", tmp_path / "map.png"
    result = sweep(*VARY, "-p", "0.5", "--out", str(out), "--figure", str(figure))
    assert result.exit_code == 0, result.output
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_map_data_and_labels():
    import matplotlib.pyplot as plt

    rows = [
        {"L2": 4.0, "theta1.max": 1.0, "regions": 2, "n_connected": False},
        {"L2": 5.0, "theta1.max": 1.0, "regions": 1, "n_connected": True},
        {"L2": 4.0, "theta1.max": 2.0, "regions": None, "n_connected": None},
        {"L2": 5.0, "theta1.max": 3.0, "error": "failed"},
    ]
    xs, ys, codes, connected = map_grid(COLUMNS, rows, "L2", "theta1.max")
    assert xs.tolist() == [4.0, 5.0] and ys.tolist() == [1.0, 2.0, 3.0]
    assert codes.tolist() == [[2, 1], [UNKNOWN, MISSING], [MISSING, FAILED]]
    assert connected.tolist() == [[False, True], [False, False], [False, False]]
    fig = plot_sweep_map((COLUMNS, rows))
    ax = fig.axes[0]
    assert ax.get_xlabel() == "L2 (length units of the spec)"
    assert ax.get_ylabel() == "theta1.max (rad)"
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert labels == [
        "1 region",
        "2 regions",
        "regions unknown at this precision",
        "design failed (see error column)",
        "not computed",
        "W N-connected",
    ]
    plt.close(fig)


def test_map_refuses_a_third_varied_name():
    rows = [{"L1": a, "L2": a, "theta1.max": a} for a in (1.0, 2.0)]
    with pytest.raises(InvalidParameterError, match="--figure"):
        plot_sweep_map((["L1", "L2", "theta1.max", *RESULT_COLUMNS], rows))


# ------------------------------------------------------------------ progress
def test_progress_is_silent_unless_asked(tmp_path):
    args = ["sweep", SPEC, "--vary", "L2=4:6:2", "-p", "0.5"]
    quiet = CliRunner().invoke(main, [*args, "--out", str(tmp_path / "a.csv")])
    assert quiet.stderr == ""
    loud = CliRunner().invoke(main, ["-v", *args, "--out", str(tmp_path / "b.csv")])
    assert loud.exit_code == 0
    lines = [line for line in loud.stderr.splitlines() if "sweep [" in line]
    assert len(lines) == 3
    assert lines[-1].startswith("INFO: sweep [") and "2/2 designs" in lines[-1]


def test_progress_bar_on_a_terminal():
    import io

    ticks = iter([0.0, 30.0, 60.0])
    out = io.StringIO()
    progress = SweepProgress(out, terminal=True, clock=lambda: next(ticks), width=4)
    progress(0, 2)
    progress(1, 2)
    progress(2, 2)
    text = out.getvalue()
    assert text.count("\r") == 3 and text.endswith("\n")
    assert "1/2 designs, 0:30 elapsed, about 0:30 left" in text


def test_malloc_fix_runs():
    import platform
    import sys

    applied = restore_malloc_thresholds()
    assert restore_malloc_thresholds() is applied
    if sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc":
        assert applied is True


def test_only_one_number_parameters_vary():
    spec = {**load_spec(SPEC)}
    spec["parameters"] = {**spec["parameters"], "L0": [7.0, 7.0]}
    with pytest.raises(
        InvalidParameterError, match="invalid --vary L0: expected a parameter given"
    ):
        parse_vary("L0=1:2:2", spec)
