"""A command imports what it needs: the models of other mechanisms, numba,
scipy, sympy and matplotlib stay unimported where they are not used."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

MODELS = ("biglide", "custom", "delta", "five_bar", "three_rpr", "three_rrr", "tape")
EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
HEAVY = ("numba", "scipy", "sympy", "matplotlib")


def imported_after(code: str) -> set[str]:
    """The modules a fresh interpreter holds after running ``code``."""
    probe = f"{code}\nimport sys, json\nprint(json.dumps(sorted(sys.modules)))"
    out = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True
    ).stdout
    return set(json.loads(out.splitlines()[-1]))


def models(modules: set[str]) -> set[str]:
    return {m for m in MODELS if f"moveability.mechanisms.{m}" in modules}


def after_command(args: list[str]) -> set[str]:
    """The modules a fresh interpreter holds after ``moveability`` ran ``args``."""
    return imported_after(
        f"from moveability.cli import main\ntry:\n    main({args!r})\nexcept SystemExit:\n    pass"
    )


COMMANDS = ("analyze", "export", "feasible", "locate", "plan", "plot", "regions", "report", "sweep")


def commands(modules: set[str]) -> set[str]:
    return {c for c in COMMANDS if f"moveability.cli.{c}" in modules}


def test_version_imports_neither_the_analysis_nor_heavy_packages():
    modules = after_command(["--version"])
    assert "moveability.cli" in modules
    assert not {m for m in HEAVY if m in modules}
    assert "moveability.analysis.result" not in modules
    assert not models(modules)
    assert commands(modules) == set()


def test_a_command_imports_its_own_module_alone():
    regions = after_command(["regions", str(EXAMPLES / "five-bar-paper.toml"), "-p", "1"])
    assert commands(regions) == {"regions"}
    # the help lists every command, importing each
    assert commands(after_command(["--help"])) == set(COMMANDS)


@pytest.mark.parametrize(
    ("name", "module"),
    [("FiveBar", "five_bar"), ("ThreeRPR", "three_rpr"), ("Delta", "delta")],
)
def test_a_mechanism_class_imports_its_model_alone(name: str, module: str):
    modules = imported_after(f"from moveability.mechanisms import {name}")
    assert models(modules) == {module}
    assert not {m for m in HEAVY if m in modules}


def test_analysing_a_five_bar_imports_no_other_model():
    modules = imported_after(
        "from moveability import analyze\n"
        f"r = analyze({str(EXAMPLES / 'five-bar-paper.toml')!r}, precision=0.5)\n"
        "assert len(r.regions) == 2, r.regions"
    )
    assert models(modules) == {"five_bar"}
    assert not {m for m in HEAVY if m in modules}


def test_every_exported_mechanism_class_resolves():
    import moveability.mechanisms as mechanisms

    for name in ("Biglide", "Delta", "FiveBar", "ThreeRPR", "ThreeRRR"):
        cls = getattr(mechanisms, name)
        assert cls.__name__ == name and issubclass(cls, mechanisms.Mechanism)
        assert name in dir(mechanisms)
    with pytest.raises(AttributeError, match="NoSuchRobot"):
        mechanisms.NoSuchRobot  # type: ignore[attr-defined]  # noqa: B018


@pytest.mark.parametrize(("given", "expected"), [(None, "1"), ("3", "3")])
def test_a_command_runs_blas_on_one_thread_unless_the_user_says(given, expected):
    """The command line sets OpenBLAS to one thread before numpy's first import (a
    user's own value is kept): what numpy's configuration then reads."""
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if given is not None:
        env["OPENBLAS_NUM_THREADS"] = given
    probe = (
        "import moveability.cli, os, sys\n"
        "assert 'numpy' in sys.modules\n"
        "print(os.environ['OPENBLAS_NUM_THREADS'])"
    )
    out = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True, env=env
    ).stdout
    assert out.split() == [expected]
