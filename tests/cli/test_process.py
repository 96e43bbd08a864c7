"""The console script's process (``moveability.cli.run``): the same output and
exit status as ``main``, every byte of it written, the atexit handlers run, and
the usual exit while other threads are alive."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from click.testing import CliRunner

from moveability.cli import main, process

SPEC = "examples/five-bar-paper.toml"


def run_script(args: list[str], before: str = "") -> subprocess.CompletedProcess[str]:
    """``moveability ARGS`` as the console script runs it, in a fresh interpreter
    (``before``: Python run first)."""
    code = (
        f"import sys\n{before}\n"
        "from moveability.cli import run\n"
        f"sys.argv = ['moveability', *{args!r}]\n"
        "run()\n"
    )
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)


def test_the_script_prints_what_main_prints(tmp_path: Path) -> None:
    """A summary on stdout (a pipe: block-buffered, flushed before the quick exit),
    a JSON file, and both equal to what ``main`` gives in process."""
    out = tmp_path / "r.json"
    args = ["regions", SPEC, "-p", "0.4", "--json", str(out)]
    done = run_script(args)
    assert done.returncode == 0, done.stderr
    text = out.read_text()
    in_process = CliRunner().invoke(main, [*args[:-1], str(tmp_path / "s.json")])
    assert in_process.exit_code == 0
    assert done.stdout == in_process.stdout and done.stdout.count("\n") > 5
    assert json.loads(text) == json.loads((tmp_path / "s.json").read_text())
    piped = run_script(["regions", SPEC, "-p", "0.4", "--json", "-"])
    # (stdout a pipe: the JSON waits in its buffer until the flush before the exit)
    assert piped.returncode == 0 and json.loads(piped.stdout)["precision"] == 0.4


def test_the_script_keeps_the_exit_status_and_runs_the_atexit_handlers() -> None:
    bye = "import atexit; atexit.register(lambda: print('bye', flush=False))"
    done = run_script(["regions", "missing.toml"], before=bye)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "Error: invalid spec: expected an existing TOML file, got 'missing.toml'"
    ]
    assert done.stdout == "bye\n"
    version = run_script(["--version"], before=bye)
    assert version.returncode == 0 and version.stdout.splitlines()[-1] == "bye"


def test_finish_exits_as_usual_while_another_thread_runs() -> None:
    """With a thread alive, ``finish`` raises SystemExit (Python then joins the
    thread) rather than ending the process at once."""
    release = threading.Event()
    worker = threading.Thread(target=release.wait)
    worker.start()
    try:
        with pytest.raises(SystemExit) as raised:
            process.finish(3)
        assert raised.value.code == 3
    finally:
        release.set()
        worker.join()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_the_allocator_takes_the_setting() -> None:
    probe = "from moveability.cli import process; print(process.tune_allocator())"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True)
    assert done.stdout.split() == ["True"]
