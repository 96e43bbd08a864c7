"""The ``moveability`` command line: JSON outputs, files, and one-line errors on bad input.

Most tests replace the analysis with a stand-in (``FakeResult``) so that they
check the CLI alone; the last ones run the real analysis on the paper's
five-bar when it is importable.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from moveability.cli import main, options, running
from moveability.errors import MoveabilityError, ResolutionError

PAPER_TOML = """\
mechanism = "five-bar"
[parameters]
L0 = 7.0
L1 = 8.0
L2 = 5.0
L3 = 8.0
L4 = 5.0
[limits]
theta1 = [0.0, "pi"]
theta2 = [0.0, "pi"]
"""

REGIONS_KEYS = {"precision", "workspace", "regions", "n_connected"}
LOCATE_KEYS = {"regions", "points"}
FEASIBLE_KEYS = {"feasible", "region", "postures"}


class FakeMechanism:
    pose_names = ("x", "y")
    joint_names = ("theta1", "theta2")

    def __init__(self, spec):
        self.spec = spec


class FakeResult:
    """Answers as the contract says the analysis does; records the points it is given."""

    def __init__(self, mechanism, precision):
        self.mechanism = mechanism
        self.precision = precision
        self.points = []
        self.regions = [object(), object()]
        self.n_connected = False
        self.workspace = object()

    def to_dict(self):
        return {
            "precision": self.precision,
            "workspace": {"area": [30.5, 34.25]},
            "regions": [
                {"id": 0, "area": [12.0, 14.0], "equals_workspace": False},
                {"id": 1, "area": [np.float64(18.0), 20.5], "equals_workspace": None},
            ],
            "n_connected": False,
            "extra": np.array([1, 2]),
        }

    def locate(self, points):
        self.points.append(points)
        return {
            "regions": [0, 1],
            "points": [
                {
                    "pose": [float(x) for x in p],
                    "workspace": bool(p[0] >= 0),
                    "regions": {"0": bool(p[0] >= 0), "1": None},
                }
                for p in points
            ],
        }

    def feasible(self, points):
        self.points.append(points)
        return {
            "feasible": True,
            "region": 0,
            "postures": [[0.5 + i, 1.0] for i in range(len(points))],
        }


@pytest.fixture
def fake(monkeypatch):
    """Replace the library's mechanism and analysis; return the record of the calls."""
    calls = {"specs": [], "analyses": [], "results": []}

    def make_mechanism(spec):
        calls["specs"].append(spec)
        return FakeMechanism(spec)

    def run_analysis(mechanism, precision, progress):
        calls["analyses"].append({"precision": precision, "progress": progress})
        if progress is not None:
            progress(3, 12, 40)
            progress("done", cells=40)
        result = FakeResult(mechanism, precision)
        calls["results"].append(result)
        return result

    monkeypatch.setattr(running, "make_mechanism", make_mechanism)
    monkeypatch.setattr(running, "run_analysis", run_analysis)
    return calls


@pytest.fixture
def spec(tmp_path):
    path = tmp_path / "paper.toml"
    path.write_text(PAPER_TOML)
    return str(path)


@pytest.fixture
def points(tmp_path):
    path = tmp_path / "points.csv"
    path.write_text("x,y\n3.5,9.0\n-1.0,2.5\n")
    return str(path)


def run(args, input=None):
    return CliRunner().invoke(main, args, input=input)


def assert_bad_input(result, *names):
    """Exit 2, nothing on stdout, one line ``Error: ...`` on stderr naming every one of names."""
    assert result.exit_code == 2, (result.exit_code, result.output)
    assert result.stdout == ""
    message = result.stderr
    assert message.startswith("Error: "), message
    assert message.count("\n") == 1 and message.endswith("\n"), message
    assert "Traceback" not in message
    for name in names:
        assert name in message, (name, message)


# ------------------------------------------------------------------ group
def test_help_and_version():
    result = run(["--help"])
    assert result.exit_code == 0
    for command in ("regions", "locate", "feasible"):
        assert command in result.stdout
        sub = run([command, "-h"])
        assert sub.exit_code == 0 and "--precision" in sub.stdout and "--json" in sub.stdout
        assert str(options.DEFAULT_PRECISION) in sub.stdout
    version = run(["--version"])
    assert version.exit_code == 0 and "moveability" in version.stdout
    # the version written once in the package is the one installed
    import importlib.metadata

    import moveability

    installed = importlib.metadata.version("moveability")
    assert moveability.__version__ == installed and installed in version.stdout


def test_default_precision(fake, spec):
    assert options.DEFAULT_PRECISION == 0.1
    result = run(["regions", spec, "--json", "-"])
    assert result.exit_code == 0
    assert fake["analyses"][0]["precision"] == 0.1
    assert json.loads(result.stdout)["precision"] == 0.1


# ------------------------------------------------------------------ regions
def test_regions_json_to_stdout(fake, spec):
    result = run(["regions", spec, "--precision", "0.25", "--json", "-"])
    assert result.exit_code == 0, result.output
    assert result.stderr == ""
    data = json.loads(result.stdout)
    assert REGIONS_KEYS <= set(data)
    assert data["precision"] == 0.25
    assert data["workspace"] == {"area": [30.5, 34.25]}
    assert [set(r) for r in data["regions"]] == [{"id", "area", "equals_workspace"}] * 2
    assert data["regions"][1]["equals_workspace"] is None
    assert data["n_connected"] is False
    assert data["extra"] == [1, 2]
    # the spec reaches the library normalised
    assert fake["specs"][0]["limits"]["theta1"] == (0.0, math.pi)
    assert fake["analyses"][0] == {"precision": 0.25, "progress": None}


def test_regions_summary(fake, spec):
    result = run(["regions", spec, "-p", "0.5"])
    assert result.exit_code == 0, result.output
    out = result.stdout
    assert "workspace area: [30.5, 34.25]" in out
    assert "N-connected regions: 2" in out
    assert "workspace N-connected: no" in out
    assert "unknown" in out
    with pytest.raises(json.JSONDecodeError):
        json.loads(out)


def test_regions_json_to_file_and_overwrite(fake, spec, tmp_path):
    out = tmp_path / "regions.json"
    first = run(["regions", spec, "--json", str(out)])
    assert first.exit_code == 0, first.output
    assert "N-connected regions: 2" in first.stdout  # summary too
    assert REGIONS_KEYS <= set(json.loads(out.read_text()))

    out.write_text("keep me")
    refused = run(["regions", spec, "--json", str(out)])
    assert_bad_input(refused, str(out), "--overwrite")
    assert out.read_text() == "keep me"
    assert len(fake["analyses"]) == 1  # refused before computing

    again = run(["regions", spec, "--precision", "0.3", "--json", str(out), "--overwrite"])
    assert again.exit_code == 0, again.output
    assert json.loads(out.read_text())["precision"] == 0.3


def test_json_into_a_missing_directory(fake, spec, tmp_path):
    out = tmp_path / "no" / "such" / "dir.json"
    assert_bad_input(run(["regions", spec, "--json", str(out)]), str(out))
    assert fake["analyses"] == []


def test_verbosity_logs_to_stderr(fake, spec):
    loud = run(["-v", "regions", spec, "--json", "-"])
    assert loud.exit_code == 0
    assert json.loads(loud.stdout)["precision"] == 0.1  # stdout stays pure JSON
    assert "level 3: 12 cells split, 40 leaves" in loud.stderr
    assert "progress: done cells=40" in loud.stderr
    assert fake["analyses"][0]["progress"] is not None
    quiet = run(["-q", "regions", spec, "--json", "-"])
    assert quiet.exit_code == 0 and quiet.stderr == ""
    assert fake["analyses"][1]["progress"] is None


# ------------------------------------------------------------------ locate
def test_locate_json(fake, spec, points):
    result = run(["locate", spec, points, "--json", "-"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert set(data) == LOCATE_KEYS
    assert data["regions"] == [0, 1]
    assert [p["pose"] for p in data["points"]] == [[3.5, 9.0], [-1.0, 2.5]]
    for point in data["points"]:
        assert set(point) == {"pose", "workspace", "regions"}
        assert point["workspace"] in {True, False, None}
        assert set(point["regions"]) == {"0", "1"}
    given = fake["results"][0].points[0]
    assert given.dtype == np.float64 and given.shape == (2, 2)


def test_locate_summary(fake, spec, points):
    result = run(["locate", spec, points])
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0].split() == ["pose", "workspace", "region", "0", "region", "1"]
    assert lines[1].split() == ["3.5,", "9", "yes", "yes", "unknown"]
    assert len(lines) == 3


@pytest.mark.parametrize(
    "text",
    [
        "x,y\n3.5,9.0\n-1.0,2.5\n",
        "y,x\n9.0,3.5\n2.5,-1.0\n",
        "  y ,  x  \n 9.0 , 3.5 \n\n2.5,\t-1.0\n\n",
        "\ufeffx,y\r\n3.5,9\r\n-1,2.5\r\n",
        '"x","y"\n"3.5","9.0"\n-1.0,2.5e0\n',
    ],
)
def test_csv_columns_are_read_by_name(fake, spec, tmp_path, text):
    path = tmp_path / "p.csv"
    path.write_text(text, encoding="utf-8")
    result = run(["locate", spec, str(path), "--json", "-"])
    assert result.exit_code == 0, result.output
    np.testing.assert_array_equal(fake["results"][0].points[0], [[3.5, 9.0], [-1.0, 2.5]])


def test_points_from_stdin(fake, spec):
    result = run(["locate", spec, "-", "--json", "-"], input="y,x\n1,2\n")
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["points"][0]["pose"] == [2.0, 1.0]


# ------------------------------------------------------------------ feasible
def test_feasible_json(fake, spec, points, tmp_path):
    result = run(["feasible", spec, points, "--json", "-"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert set(data) == FEASIBLE_KEYS
    assert data == {"feasible": True, "region": 0, "postures": [[0.5, 1.0], [1.5, 1.0]]}

    out = tmp_path / "feasible.json"
    to_file = run(["feasible", spec, points, "--json", str(out)])
    assert to_file.exit_code == 0
    assert json.loads(out.read_text()) == data
    assert "feasible: yes (N-connected region 0)" in to_file.stdout
    assert_bad_input(run(["feasible", spec, points, "--json", str(out)]), "overwrite")


def test_feasible_summary(fake, spec, points):
    result = run(["feasible", spec, points])
    assert result.exit_code == 0
    assert result.stdout.splitlines() == [
        "feasible: yes (N-connected region 0)",
        "posture 1: 0.5, 1",
        "posture 2: 1.5, 1",
    ]


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize(
    ("old", "new", "names"),
    [
        ('"five-bar"', '"six-bar"', ["mechanism", "six-bar", "five-bar"]),
        ("L2 = 5.0\n", "", ["parameters.L2"]),
        ("L2 = 5.0", "L2 = 0.0", ["parameters.L2", "positive"]),
        ("L2 = 5.0", "L2 = -5.0", ["parameters.L2", "positive"]),
        ("L2 = 5.0", "L2 = nan", ["parameters.L2"]),
        ("L2 = 5.0", 'L2 = "five"', ["parameters.L2"]),
        ('theta1 = [0.0, "pi"]', 'theta1 = ["pi", 0.0]', ["limits.theta1", "lo < hi"]),
        ('theta1 = [0.0, "pi"]', 'theta1 = ["pi", "pi"]', ["limits.theta1", "lo < hi"]),
        ('theta1 = [0.0, "pi"]', 'theta1 = [0.0, "3*pi"]', ["limits.theta1", "unlimited"]),
        ('theta1 = [0.0, "pi"]', 'theta1 = [0.0, "2pi"]', ["limits.theta1[1]"]),
        ('theta1 = [0.0, "pi"]\n', "", ["limits.theta1"]),
        ("L2 = 5.0", "L2 = = 5.0", ["TOML", "line 5", "column"]),
    ],
)
def test_bad_spec(fake, tmp_path, points, old, new, names):
    assert old in PAPER_TOML
    path = tmp_path / "bad.toml"
    path.write_text(PAPER_TOML.replace(old, new))
    for command in (["regions", str(path)], ["locate", str(path), points]):
        assert_bad_input(run([*command, "--json", "-"]), *names)
    assert fake["analyses"] == []


def test_missing_spec_file(fake, tmp_path, points):
    path = str(tmp_path / "missing.toml")
    assert_bad_input(run(["regions", path]), path)
    assert_bad_input(run(["feasible", path, points]), path)


@pytest.mark.parametrize("precision", ["0", "-0.1", "nan", "inf", "-inf", "abc", ""])
def test_bad_precision(fake, spec, points, precision):
    for command in (["regions", spec], ["locate", spec, points], ["feasible", spec, points]):
        assert_bad_input(run([*command, "--precision", precision]), "--precision")
    assert fake["analyses"] == []


@pytest.mark.parametrize("growth", ["-1", "nan", "inf", "abc", ""])
def test_bad_resolve_growth(fake, spec, points, growth):
    for command in (["regions", spec], ["locate", spec, points], ["feasible", spec, points]):
        assert_bad_input(run([*command, "--resolve-growth", growth]), "--resolve-growth")
    assert fake["analyses"] == []


def test_resolve_growth_reaches_the_analysis(monkeypatch, spec):
    """``--resolve-growth`` is passed to ``analyze`` as ``resolve_growth``; without
    it ``analyze``'s default stands (no keyword), and the help says that default."""
    import moveability.analysis.result as result_module

    seen = []

    def record(mechanism, precision, **kwargs):
        seen.append(kwargs)
        raise ResolutionError("precision", "a tree that fits in memory", precision)

    monkeypatch.setattr(result_module, "analyze", record)
    run(["regions", spec, "--resolve-growth", "16"])
    run(["regions", spec])
    run(["regions", spec, "--no-resolve", "--resolve-growth", "2.5"])
    assert seen[0]["resolve_growth"] == 16.0 and seen[0]["resolve"] is True
    assert "resolve_growth" not in seen[1]
    assert seen[2]["resolve_growth"] == 2.5 and seen[2]["resolve"] is False
    helped = " ".join(run(["regions", "-h"]).stdout.split())
    assert f"[default: {result_module.RESOLVE_GROWTH:g}]" in helped
    # a sweep keeps the default budget: it offers no option it would ignore
    assert "--resolve-growth" not in run(["sweep", "-h"]).stdout


def test_precision_too_fine_for_memory(monkeypatch, fake, spec):
    def refuse(mechanism, precision, progress):
        raise ResolutionError("precision", "a tree that fits in memory", precision)

    monkeypatch.setattr(running, "run_analysis", refuse)
    assert_bad_input(run(["regions", spec, "-p", "1e-9"]), "precision", "memory", "1e-09")


def test_mechanism_refusing_the_spec_is_bad_input(monkeypatch, spec):
    from moveability.errors import InvalidParameterError

    def refuse(spec):
        raise InvalidParameterError("parameters.L0", "a mechanism that can be assembled", 7.0)

    monkeypatch.setattr(running, "make_mechanism", refuse)
    assert_bad_input(run(["regions", spec]), "parameters.L0")


def test_other_library_errors_exit_1(monkeypatch, fake, spec):
    def fail(mechanism, precision, progress):
        raise MoveabilityError("the analysis went wrong\nat depth 3")

    monkeypatch.setattr(running, "run_analysis", fail)
    result = run(["regions", spec])
    assert result.exit_code == 1
    assert result.stderr == "Error: the analysis went wrong at depth 3\n"


@pytest.mark.parametrize(
    ("text", "names"),
    [
        ("", ["empty"]),
        ("\n\n", ["empty"]),
        ("x,y\n", ["no rows"]),
        ("a,b\n1,2\n", ["header", "x, y", "a,b"]),
        ("x\n1\n", ["header", "x, y"]),
        ("x,y,z\n1,2,3\n", ["header", "x,y,z"]),
        ("x,x\n1,2\n", ["header", "x,x"]),
        ("X,Y\n1,2\n", ["header"]),
        ("1,2\n3,4\n", ["header", "1,2"]),
        ("x,y\n1,2\n3,nan\n", ["line 3", "row 2", "column y", "nan"]),
        ("y,x\n1,2\nNaN,4\n", ["line 3", "row 2", "column y", "NaN"]),
        ("x,y\n1,2\n\nabc,4\n", ["line 4", "row 2", "column x", "abc"]),
        ("x,y\n1,\n", ["line 2", "row 1", "column y"]),
        ("x,y\n1,inf\n", ["row 1", "column y", "inf"]),
        ("x,y\n1,2,3\n", ["line 2", "row 1", "2 values"]),
        ("x,y\n1\n", ["line 2", "row 1", "2 values"]),
    ],
)
def test_bad_points(fake, spec, tmp_path, text, names):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    for command in ("locate", "feasible"):
        assert_bad_input(run([command, spec, str(path), "--json", "-"]), str(path), *names)
        assert_bad_input(run([command, spec, "-"], input=text), "<stdin>", *names)
    assert fake["analyses"] == []  # refused before computing


def test_missing_points_file(fake, spec, tmp_path):
    path = str(tmp_path / "missing.csv")
    assert_bad_input(run(["locate", spec, path]), "POINTS", path)


# ------------------------------------------------------------------ end to end
@pytest.fixture
def real(spec):
    pytest.importorskip("moveability.analysis.result")
    return spec


def test_end_to_end_regions(real):
    result = run(["regions", real, "--precision", "0.5", "--json", "-"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert REGIONS_KEYS <= set(data)
    assert data["precision"] == 0.5
    inner, outer = data["workspace"]["area"]
    assert 0 <= inner <= outer and math.isfinite(outer)
    assert isinstance(data["regions"], list)
    for region in data["regions"]:
        assert {"id", "area", "equals_workspace"} <= set(region)
        assert isinstance(region["id"], int)
        lo, hi = region["area"]
        assert 0 <= lo <= hi <= outer + 1e-9
        assert region["equals_workspace"] in (True, False, None)
    assert data["n_connected"] in (True, False, None)


def test_end_to_end_locate_and_feasible(real, tmp_path):
    path = tmp_path / "two.csv"
    path.write_text("x,y\n3.5,8.0\n3.5,4.0\n")
    located = run(["locate", real, str(path), "--precision", "0.5", "--json", "-"])
    assert located.exit_code == 0, located.output
    data = json.loads(located.stdout)
    assert set(data) >= LOCATE_KEYS
    ids = data["regions"]
    assert len(data["points"]) == 2
    for point, pose in zip(data["points"], [[3.5, 8.0], [3.5, 4.0]], strict=True):
        assert point["pose"] == pytest.approx(pose)
        assert point["workspace"] in {True, False, None}
        assert set(point["regions"]) == {str(i) for i in ids}
        assert set(point["regions"].values()) <= {True, False, None}

    feasible = run(["feasible", real, str(path), "--precision", "0.5", "--json", "-"])
    assert feasible.exit_code == 0, feasible.output
    answer = json.loads(feasible.stdout)
    assert set(answer) >= FEASIBLE_KEYS
    assert answer["feasible"] in (True, False, None)
    if answer["feasible"]:
        assert answer["region"] in ids
        assert len(answer["postures"]) == 2
        assert all(len(posture) == 2 for posture in answer["postures"])
    else:
        assert answer["region"] is None or answer["region"] in ids


def test_end_to_end_precision_too_fine(real):
    assert_bad_input(run(["regions", real, "--precision", "1e-300"]), "precision")


def test_terminal_progress_line_appears_after_the_delay():
    import io

    from moveability.cli.running import TerminalProgress

    stream = io.StringIO()
    quiet = TerminalProgress(stream, delay=3600.0)
    quiet(3, 10, 20)
    assert stream.getvalue() == ""
    shown = TerminalProgress(stream, delay=0.0)
    shown.phase("refining", levels=8)
    shown(3, 12, 40)
    shown(7, 0, 52)
    shown.phase("joining the regions")
    shown.phase("resolving", round=2, levels=20)
    shown(9, 5, 60)
    shown.close()
    writes = stream.getvalue().split("\r\x1b[K")
    # every update rewrites the whole line; the last one clears it
    assert writes[0] == "" and writes[-1] == ""
    assert "level 4/8" in writes[2] and "40 cells" in writes[2]
    assert f"[{'#' * 24}] level 8/8" in writes[3]
    assert writes[4].startswith("joining the regions")
    assert writes[5].startswith("resolving the open cells: round 2")
    assert writes[6].startswith("resolving the open cells: round 2, level 9")
    assert "60 cells" in writes[6]
