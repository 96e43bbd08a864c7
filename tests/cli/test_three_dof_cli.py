"""Specs and commands of the mechanisms beyond the five-bar (3-RPR, biglide)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from moveability import analyze, load_analysis, save_analysis
from moveability.cli import main
from moveability.errors import InvalidParameterError, SpecError
from moveability.mechanisms import Biglide, ThreeRPR, from_spec
from moveability.mechanisms.registry import load_spec

RPR = {
    "mechanism": "3-RPR",
    "parameters": {
        "base": [[0.0, 0.0], [15.91, 0.0], [0.0, 10.0]],
        "platform": [[0.0, 0.0], [17.04, 0.0], [13.24, 16.10]],
    },
    "limits": {"rho1": [10.0, 25.0], "rho2": [10.0, 25.0], "rho3": [10.0, 25.0]},
}
BIGLIDE = {
    "mechanism": "biglide",
    "parameters": {"L1": 5.0, "L2": 4.0},
    "limits": {"rho1": [-6.0, 6.0], "rho2": [-6.0, 6.0]},
}


def _with(spec, path, value):
    out = json.loads(json.dumps(spec))
    *head, last = path
    node = out
    for key in head:
        node = node[key]
    if value is None:
        del node[last]
    else:
        node[last] = value
    return out


def test_specs_normalise_and_rebuild():
    for spec, cls in ((RPR, ThreeRPR), (BIGLIDE, Biglide)):
        normal = load_spec(spec)
        assert load_spec(normal) == normal
        m = from_spec(normal)
        assert isinstance(m, cls)
        assert load_spec(m.to_spec()) == normal
    assert load_spec({**RPR, "mechanism": "3-rpr"})["mechanism"] == "3-RPR"


@pytest.mark.parametrize(
    ("spec", "path", "value", "name"),
    [
        (RPR, ("parameters", "base"), [[0, 0], [1, 0]], "parameters.base"),
        (RPR, ("parameters", "platform"), [[0, 0], [1, 0], [1, "a"]], "parameters.platform[2]"),
        (RPR, ("parameters", "base"), [[0, 0], [1, 0], [math.nan, 0]], "parameters.base[2]"),
        (RPR, ("parameters", "base"), None, "parameters.base"),
        (RPR, ("limits", "rho2"), [25.0, 10.0], "limits.rho2"),
        (RPR, ("limits", "rho1"), [-1.0, 10.0], "limits.rho1"),
        (RPR, ("limits", "rho3"), "unlimited", "limits.rho3"),
        (RPR, ("limits", "rho3"), None, "limits.rho3"),
        (RPR, ("limits", "theta1"), [0, 1], "limits.theta1"),
        (BIGLIDE, ("parameters", "L2"), 0.0, "parameters.L2"),
        (BIGLIDE, ("limits", "rho1"), [3.0, 3.0], "limits.rho1"),
        (BIGLIDE, ("limits", "rho2"), [0.0, math.inf], "limits.rho2"),
    ],
)
def test_errors_name_the_key(spec, path, value, name):
    with pytest.raises(SpecError) as info:
        load_spec(_with(spec, path, value))
    assert info.value.name == name
    assert "\n" not in str(info.value)


def test_strokes_that_cannot_meet_are_refused():
    bad = _with(RPR, ("limits", "rho1"), [0.1, 0.2])
    bad["parameters"]["base"] = [[0.0, 0.0], [100.0, 0.0], [0.0, 100.0]]
    with pytest.raises(InvalidParameterError) as info:
        from_spec(load_spec(bad))
    assert info.value.name == "limits"


@pytest.fixture(scope="module")
def rpr_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("spec") / "rpr.toml"
    path.write_text(
        'mechanism = "3-RPR"\n[parameters]\n'
        "base = [[0.0, 0.0], [15.91, 0.0], [0.0, 10.0]]\n"
        "platform = [[0.0, 0.0], [17.04, 0.0], [13.24, 16.10]]\n"
        "[limits]\nrho1 = [10.0, 25.0]\nrho2 = [10.0, 25.0]\nrho3 = [10.0, 25.0]\n"
    )
    return path


def test_regions_json_says_volume(rpr_file):
    result = CliRunner().invoke(main, ["regions", str(rpr_file), "-p", "2,2,0.3", "--json", "-"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    assert data["pose"] == ["x", "y", "phi"] and data["precision"] == [2.0, 2.0, 0.3]
    direct = analyze(RPR, precision=(2.0, 2.0, 0.3)).to_dict()
    assert data["workspace"] == direct["workspace"]
    assert [r["volume"] for r in data["regions"]] == [r["volume"] for r in direct["regions"]]
    summary = CliRunner().invoke(main, ["regions", str(rpr_file), "-p", "2,2,0.3"])
    assert "workspace volume" in summary.output


def test_locate_and_feasible_read_x_y_phi(rpr_file, tmp_path):
    points = tmp_path / "poses.csv"
    # columns by name, in any order; phi in radians, any turn
    points.write_text("phi,x,y\n0.3,5,10\n6.583185307179586,5,10\n0.5,40,40\n")
    out = CliRunner().invoke(
        main, ["locate", str(rpr_file), str(points), "-p", "2,2,0.3", "--json", "-"]
    )
    assert out.exit_code == 0, out.output
    answers = json.loads(out.output)["points"]
    assert answers[0]["pose"] == [5.0, 10.0, 0.3]
    # the second pose is the first one turned once: the same answers
    assert answers[0]["workspace"] == answers[1]["workspace"]
    assert answers[0]["regions"] == answers[1]["regions"]
    assert answers[2]["workspace"] is False
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y\n1,2\n")
    out = CliRunner().invoke(main, ["locate", str(rpr_file), str(bad), "-p", "2,2,0.3"])
    assert out.exit_code == 2 and "phi" in out.output


def test_precision_with_the_wrong_number_of_axes(rpr_file):
    out = CliRunner().invoke(main, ["regions", str(rpr_file), "-p", "1,1"])
    assert out.exit_code == 2
    assert "precision" in out.output and "3" in out.output
    out = CliRunner().invoke(main, ["regions", str(rpr_file), "-p", "1,x,1"])
    assert out.exit_code == 2 and "--precision" in out.output


def test_save_and_load_keep_the_periodic_axis(tmp_path):
    result = analyze(RPR, precision=(2.0, 2.0, 0.3))
    path = tmp_path / "rpr.npz"
    save_analysis(result, path)
    again = load_analysis(path)
    assert again.tree.periodic == (2,)
    assert again.precision == (2.0, 2.0, 0.3)
    assert again.to_dict() == result.to_dict()
    pts = np.array([[5.0, 10.0, 0.3], [5.0, 10.0, 0.3 + 2 * np.pi]])
    assert again.locate(pts) == result.locate(pts)
