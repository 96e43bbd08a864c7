"""Every command of the README runs as written, from a copy of the examples.

The shell blocks of README.md are read; each line (with its continuations)
that calls ``.venv/bin/moveability`` runs in a fresh folder holding the
examples, with the console script of the interpreter running the tests in
place of ``.venv/bin/moveability``. A command must exit 0 and write every
output file it names.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = str(Path(sys.executable).parent / "moveability")


def readme_commands() -> list[str]:
    """The moveability commands of the README's ``sh`` blocks, continuations joined."""
    text = (ROOT / "README.md").read_text()
    commands = []
    for block in re.findall(r"```sh\n(.*?)```", text, flags=re.S):
        for line in block.replace("\\\n", " ").splitlines():
            if ".venv/bin/moveability" in line:
                commands.append(" ".join(line.split("#")[0].split()))
    return commands


COMMANDS = readme_commands()


def test_the_readme_has_commands():
    assert len(COMMANDS) >= 15
    assert any(c.startswith(".venv/bin/moveability analyze") for c in COMMANDS)


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A fresh folder with the examples, shared so that later commands may read what
    earlier ones saved (the README's order)."""
    where = tmp_path_factory.mktemp("readme")
    shutil.copytree(ROOT / "examples", where / "examples")
    return where


@pytest.mark.parametrize("command", COMMANDS, ids=range(len(COMMANDS)))
def test_readme_command_runs_as_written(command, folder):
    if "HOST" in command:
        pytest.skip("needs a Dask scheduler at the address the reader supplies")
    shell = command.replace(".venv/bin/moveability", SCRIPT)
    done = subprocess.run(
        ["bash", "-c", f"set -o pipefail; {shell}"],
        cwd=folder,
        capture_output=True,
        text=True,
        env={**os.environ, "MPLBACKEND": "Agg"},
        timeout=600,
    )
    assert done.returncode == 0, (command, done.stderr[-2000:])
    assert "Traceback" not in done.stderr
    for option in ("--out", "--figure"):
        match = re.search(rf"{option} (\S+)", command)
        if match and option == "--figure" and "sweep" not in command:
            continue  # plot's --figure names the figure, not a file
        if match:
            assert (folder / match.group(1)).exists(), (command, match.group(1))
