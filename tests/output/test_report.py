"""The HTML report, opened in a real headless browser."""

import html
import os
import re
import shutil
import subprocess
import tempfile

import pytest
from click.testing import CliRunner

from moveability.cli import main

SPEC = "examples/five-bar-paper.toml"
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    done = CliRunner().invoke(main, ["report", SPEC, "--out", str(out), "--precision", "0.2"])
    assert done.exit_code == 0, done.output
    path = out / "index.html"
    assert done.output.strip().endswith("index.html")
    return path


def test_report_holds_spec_summary_and_figures(report):
    page = report.read_text()
    assert '"L0": 7.0' in html.unescape(page) and "Precision: 0.2" in page
    assert page.count("<tr><td>") == 2  # the two regions of the paper's case
    assert "W is N-connected: <strong>no</strong>" in page
    for name in ("workspace", "postures", "regions", "joint-space", "path"):
        assert f'<figure id="{name}">' in page
    assert len(re.findall(r'src="data:image/png;base64,', page)) == 5
    assert "http://" not in page and "https://" not in page  # nothing to fetch


def test_images_render_in_chromium(report):
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        if os.environ.get("CI"):
            pytest.fail("chromium is missing: .ci/run installs Debian's chromium package")
        pytest.skip("chromium is not installed here")
    with tempfile.TemporaryDirectory() as profile:
        dom = subprocess.run(
            [browser, *FLAGS, f"--user-data-dir={profile}", "--dump-dom", report.as_uri()],
            capture_output=True,
            text=True,
            timeout=120,
            check=True,
        ).stdout
    widths = [int(w) for w in re.findall(r'data-natural-width="(\d+)"', dom)]
    assert len(widths) == 5
    assert all(w > 100 for w in widths)
