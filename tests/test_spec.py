"""Specifications: the TOML format, normalisation, and an error naming the key at fault."""

from __future__ import annotations

import math
import pathlib
import re

import pytest
from hypothesis import given
from hypothesis import strategies as st

from moveability.errors import InvalidParameterError, MoveabilityError, SpecError
from moveability.mechanisms.registry import MECHANISMS, load_spec
from moveability.spec import parse_angle

PAPER_TOML = """\
# Chablat & Wenger, DETC'99, table 1
mechanism = "five-bar"
[parameters]
L0 = 7.0
L1 = 8.0
L2 = 5.0
L3 = 8.0
L4 = 5.0
[limits]
theta1 = [0.0, "pi"]
theta2 = [0, "pi"]
"""


def paper(**changes):
    """The paper's spec as a mapping; ``section=value`` replaces or, with None, removes."""
    spec = {
        "mechanism": "five-bar",
        "parameters": {"L0": 7.0, "L1": 8.0, "L2": 5.0, "L3": 8.0, "L4": 5.0},
        "limits": {"theta1": [0.0, "pi"], "theta2": [0.0, "pi"]},
    }
    for key, value in changes.items():
        section, _, item = key.partition("__")
        target = spec[section] if item else spec
        name = item or section
        if value is None:
            del target[name]
        else:
            target[name] = value
    return spec


def raises(*names):
    """``pytest.raises(SpecError)`` whose message names every one of ``names``."""
    return pytest.raises(SpecError, match="(?s)" + "".join(f"(?=.*{re.escape(n)})" for n in names))


# ------------------------------------------------------------------ parse_angle
@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("pi", math.pi),
        ("-pi", -math.pi),
        ("+pi", math.pi),
        ("PI", math.pi),
        ("pi/2", math.pi / 2),
        ("-pi/2", -math.pi / 2),
        ("3*pi/4", 3 * math.pi / 4),
        ("-3*pi/4", -3 * math.pi / 4),
        ("2*pi", 2 * math.pi),
        ("0.5*pi", 0.5 * math.pi),
        (" 3 * pi / 4 ", 3 * math.pi / 4),
        ("pi/2.5", math.pi / 2.5),
        ("0.5", 0.5),
        ("-1.25", -1.25),
        (".5", 0.5),
        ("1e-3", 1e-3),
        ("0", 0.0),
        (0, 0.0),
        (-2, -2.0),
        (1.5, 1.5),
    ],
)
def test_parse_angle_accepts(text, expected):
    angle = parse_angle(text)
    assert type(angle) is float
    assert angle == pytest.approx(expected, rel=1e-15, abs=0.0)


@pytest.mark.parametrize(
    "value",
    [
        "",
        "2pi",
        "pi*2",
        "pi/0",
        "pi/2/2",
        "pi+1",
        "pi - 1",
        "--pi",
        "tau",
        "nan",
        "inf",
        "-inf",
        "1e999",
        "1e999*pi",
        "__import__('os')",
        "3*(pi)",
        "1_000",
        float("nan"),
        float("inf"),
        True,
        None,
        [1.0],
    ],
)
def test_parse_angle_refuses(value):
    with raises("limits.theta1[0]"):
        parse_angle(value, name="limits.theta1[0]")


@given(
    st.integers(-1000, 1000),
    st.integers(1, 1000),
)
def test_parse_angle_pi_fractions(numerator, denominator):
    text = f"{numerator}*pi/{denominator}"
    assert parse_angle(text) == pytest.approx(numerator * math.pi / denominator, rel=1e-15)


@given(st.floats(allow_nan=False, allow_infinity=False))
def test_parse_angle_reads_repr_of_floats(value):
    assert parse_angle(repr(value)) == value
    assert parse_angle(value) == value


# ------------------------------------------------------------------ load_spec
def test_paper_spec_from_file(tmp_path):
    path = tmp_path / "paper.toml"
    path.write_text(PAPER_TOML)
    for source in (path, str(path)):
        spec = load_spec(source)
        assert spec == {
            "mechanism": "five-bar",
            "parameters": {"L0": 7.0, "L1": 8.0, "L2": 5.0, "L3": 8.0, "L4": 5.0},
            "limits": {"theta1": (0.0, math.pi), "theta2": (0.0, math.pi)},
        }
        assert all(type(v) is float for v in spec["parameters"].values())
        assert all(type(b) is float for lim in spec["limits"].values() for b in lim)
        assert list(spec["parameters"]) == ["L0", "L1", "L2", "L3", "L4"]
        assert list(spec["limits"]) == ["theta1", "theta2"]


def test_mapping_and_idempotence():
    spec = load_spec(paper(limits__theta2="unlimited"))
    assert spec["limits"]["theta2"] == "unlimited"
    assert load_spec(spec) == spec
    assert load_spec(dict(spec)) is not spec


def test_normalisation():
    spec = load_spec(
        paper(
            mechanism=" Five-Bar ",
            parameters__L0=7,
            limits__theta1=("-pi", "pi"),
            limits__theta2=" Unlimited ",
        )
    )
    assert spec["mechanism"] == "five-bar"
    assert spec["parameters"]["L0"] == 7.0 and type(spec["parameters"]["L0"]) is float
    assert spec["limits"] == {"theta1": (-math.pi, math.pi), "theta2": "unlimited"}


@pytest.mark.parametrize(
    "limit", [["-pi", "pi"], [0, "2*pi"], ["-3*pi/4", "5*pi/4"], ["-pi/2", "3*pi/2"]]
)
def test_a_whole_turn_is_allowed(limit):
    lo, hi = load_spec(paper(limits__theta1=limit))["limits"]["theta1"]
    assert hi - lo == pytest.approx(2 * math.pi)


def test_errors_are_of_the_documented_types():
    assert issubclass(SpecError, InvalidParameterError)
    assert issubclass(SpecError, ValueError)
    assert issubclass(SpecError, MoveabilityError)
    with pytest.raises(InvalidParameterError) as info:
        load_spec(paper(parameters__L2=-5.0))
    assert info.value.name == "parameters.L2"
    assert info.value.received == -5.0


def test_registry_lists_the_five_bar():
    schema = MECHANISMS["five-bar"].schema
    assert schema.parameters == ("L0", "L1", "L2", "L3", "L4")
    assert schema.joints == ("theta1", "theta2")


@pytest.mark.parametrize(
    ("changes", "names"),
    [
        # mechanism
        ({"mechanism": "six-bar"}, ["mechanism", "six-bar", "five-bar"]),
        ({"mechanism": None}, ["mechanism", "five-bar", "nothing"]),
        ({"mechanism": 5}, ["mechanism", "five-bar"]),
        # parameters
        ({"parameters": None}, ["parameters", "L0, L1, L2, L3, L4"]),
        ({"parameters": [7, 8, 5, 8, 5]}, ["parameters"]),
        ({"parameters__L2": None}, ["parameters.L2", "nothing"]),
        ({"parameters__L2": 0}, ["parameters.L2", "positive"]),
        ({"parameters__L2": -5.0}, ["parameters.L2", "positive", "-5.0"]),
        ({"parameters__L3": float("nan")}, ["parameters.L3", "nan"]),
        ({"parameters__L3": float("inf")}, ["parameters.L3", "inf"]),
        ({"parameters__L4": "5"}, ["parameters.L4", "'5'"]),
        ({"parameters__L4": True}, ["parameters.L4", "True"]),
        ({"parameters__L4": [5.0]}, ["parameters.L4"]),
        ({"parameters__L5": 1.0}, ["parameters.L5", "L0, L1, L2, L3, L4"]),
        # limits
        ({"limits": None}, ["limits", "theta1, theta2", "unlimited"]),
        ({"limits__theta1": None}, ["limits.theta1", "nothing", "unlimited"]),
        ({"limits__theta3": [0, 1]}, ["limits.theta3", "theta1, theta2"]),
        ({"limits__theta1": "pi"}, ["limits.theta1", "unlimited"]),
        ({"limits__theta1": "free"}, ["limits.theta1", "'free'"]),
        ({"limits__theta1": [0.0]}, ["limits.theta1", "[lo, hi]"]),
        ({"limits__theta1": [0.0, 1.0, 2.0]}, ["limits.theta1", "[lo, hi]"]),
        ({"limits__theta1": 1.0}, ["limits.theta1"]),
        ({"limits__theta1": {"lo": 0, "hi": 1}}, ["limits.theta1"]),
        ({"limits__theta2": [0.0, "2pi"]}, ["limits.theta2[1]", "'2pi'"]),
        ({"limits__theta2": ["pi/", 1.0]}, ["limits.theta2[0]", "'pi/'"]),
        ({"limits__theta2": [float("nan"), 1.0]}, ["limits.theta2[0]", "nan"]),
        ({"limits__theta2": [0.0, float("inf")]}, ["limits.theta2[1]", "inf"]),
        ({"limits__theta2": [0.0, None]}, ["limits.theta2[1]"]),
        ({"limits__theta2": ["pi", 0.0]}, ["limits.theta2", "lo < hi", "reversed"]),
        ({"limits__theta2": [1.0, 1.0]}, ["limits.theta2", "lo < hi", "empty"]),
        ({"limits__theta2": ["pi/2", "pi/2"]}, ["limits.theta2", "lo < hi"]),
        ({"limits__theta2": ["-pi", "1.01*pi"]}, ["limits.theta2", "2*pi", "unlimited"]),
        ({"limits__theta2": [0, 7]}, ["limits.theta2", "2*pi", "unlimited"]),
        # top level
        ({"limit": {"theta1": [0, 1]}}, ["limit", "mechanism", "parameters", "limits"]),
    ],
)
def test_errors_name_the_key(changes, names):
    with raises(*names):
        load_spec(paper(**changes))


def test_unknown_parameter_is_reported_before_the_missing_one():
    spec = paper(parameters__L2=None, parameters__L22=5.0)
    with raises("parameters.L22"):
        load_spec(spec)


def test_error_messages_are_one_line_and_short():
    with pytest.raises(SpecError) as info:
        load_spec(paper(parameters__L2="x" * 1000))
    assert "\n" not in str(info.value)
    assert len(str(info.value)) < 250


def test_missing_file_names_the_path(tmp_path):
    path = tmp_path / "nope.toml"
    with raises("spec", str(path), "existing"):
        load_spec(path)


def test_directory_is_not_a_spec(tmp_path):
    with raises("spec", str(tmp_path)):
        load_spec(tmp_path)


@pytest.mark.parametrize(
    ("text", "line"),
    [
        ('mechanism = "five-bar"\n[parameters\nL0 = 7\n', 2),
        ('mechanism = "five-bar"\n[parameters]\nL0 = 7\nL1 = = 8\n', 4),
        ('mechanism = "five-bar"\n[limits]\ntheta1 = [0, pi]\n', 3),
        ('mechanism = five-bar"\n', 1),
    ],
)
def test_malformed_toml_gives_line_and_column(tmp_path, text, line):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with raises(str(path), "TOML", f"line {line}", "column"):
        load_spec(path)


def test_non_utf8_file(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes('mechanism = "fünf"\n'.encode("latin-1"))
    with raises(str(path), "UTF-8"):
        load_spec(path)


def test_toml_nan_and_inf_literals_are_refused(tmp_path):
    path = tmp_path / "nan.toml"
    path.write_text(PAPER_TOML.replace("L2 = 5.0", "L2 = nan"))
    with raises("parameters.L2", "nan"):
        load_spec(path)
    path.write_text(PAPER_TOML.replace('theta2 = [0, "pi"]', "theta2 = [0, inf]"))
    with raises("limits.theta2[1]", "inf"):
        load_spec(path)


def test_source_of_another_type():
    with raises("spec", "path", "mapping"):
        load_spec(42)  # type: ignore[arg-type]


def test_load_spec_does_not_modify_its_input():
    spec = paper()
    before = repr(spec)
    load_spec(spec)
    assert repr(spec) == before


def test_pathlike_subclass(tmp_path):
    path = pathlib.PurePath(tmp_path / "paper.toml")
    pathlib.Path(path).write_text(PAPER_TOML)
    assert load_spec(path)["mechanism"] == "five-bar"
