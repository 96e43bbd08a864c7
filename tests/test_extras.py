"""A missing optional extra is refused at once, in one line naming the extra to install."""

from __future__ import annotations

import sys

import pytest
from click.testing import CliRunner

from moveability.cli import main, running
from moveability.errors import MissingExtraError
from moveability.extras import EXTRAS, require
from moveability.mechanisms.registry import from_spec

PAPER = "examples/five-bar-paper.toml"
CUSTOM = "examples/five-bar-custom.toml"


@pytest.fixture
def no_analysis(monkeypatch):
    """Any analysis started fails the test: the refusal must come first."""

    def refuse(*args, **kwargs):
        raise AssertionError("the analysis ran before the missing extra was refused")

    monkeypatch.setattr(running, "run_analysis", refuse)


def hide(monkeypatch, *modules):
    for name in list(sys.modules):
        if any(name == m or name.startswith(m + ".") for m in modules):
            monkeypatch.delitem(sys.modules, name)
    for m in modules:
        monkeypatch.setitem(sys.modules, m, None)


def one_line_naming(result, extra):
    lines = result.output.strip().splitlines()
    assert len(lines) == 1, result.output
    assert f'pip install "moveability[{extra}]"' in lines[0]
    assert "Traceback" not in result.output


@pytest.mark.parametrize(
    "args",
    [
        ["plot", PAPER, "--figure", "workspace", "--out", "{tmp}/w.png"],
        ["report", PAPER, "--out", "{tmp}/report"],
    ],
)
def test_figures_without_matplotlib(monkeypatch, tmp_path, no_analysis, args):
    hide(monkeypatch, "matplotlib")
    result = CliRunner().invoke(main, [a.format(tmp=tmp_path) for a in args])
    assert result.exit_code == 1
    one_line_naming(result, "plot")
    assert list(tmp_path.iterdir()) == []


def test_custom_mechanism_without_sympy(monkeypatch, no_analysis):
    monkeypatch.delitem(sys.modules, "moveability.mechanisms.custom", raising=False)
    hide(monkeypatch, "sympy")
    with pytest.raises(MissingExtraError, match=r"moveability\[custom\]"):
        from_spec(CUSTOM)
    result = CliRunner().invoke(main, ["regions", CUSTOM])
    assert result.exit_code == 1
    one_line_naming(result, "custom")


def test_parquet_sweep_without_pyarrow(monkeypatch, tmp_path):
    hide(monkeypatch, "pyarrow")
    out = tmp_path / "designs.parquet"
    result = CliRunner().invoke(
        main, ["sweep", PAPER, "--vary", "L0=6:8:2", "--out", str(out)]
    )
    assert result.exit_code == 1
    one_line_naming(result, "sweep")
    assert not out.exists()


def test_every_extra_module_is_installed_here():
    """`make test` installs every extra: each module of each extra imports."""
    for extra, modules in EXTRAS.items():
        for module in modules:
            assert require(module, extra, "the tests").__name__ == module


def test_a_broken_module_is_not_called_missing(monkeypatch, tmp_path):
    """A module that is there but fails to import its own dependency is not a missing extra."""
    (tmp_path / "broken_extra_module.py").write_text("import no_such_dependency_anywhere\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(ModuleNotFoundError) as info:
        require("broken_extra_module", "plot", "figures")
    assert not isinstance(info.value, MissingExtraError)
