"""The report's explorer in real headless Chromium, driven over the DevTools protocol.

Chromium is started with ``--remote-debugging-pipe``: it reads commands on file
descriptor 3 and writes answers on 4, JSON messages ended by a NUL byte, so no
driver and no network port are needed. Clicks are real mouse events at the
pixels the page's own mapping gives; the answers read from the DOM are compared
with the library's.
"""

from __future__ import annotations

import base64
import itertools
import json
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time
from typing import Any

import numpy as np
import pytest

from moveability import analyze
from moveability.mechanisms.registry import load_spec
from moveability.output.report import write_report

SPEC = "examples/five-bar-paper.toml"
_LAUNCH = """
import fcntl, os, sys
ends = [fcntl.fcntl(int(fd), fcntl.F_DUPFD, 10) for fd in sys.argv[1:3]]
for target, fd in zip((3, 4), ends):
    os.dup2(fd, target)
os.execv(sys.argv[3], sys.argv[3:])
"""
#: longest wait for a condition in the page (seconds); never asserted
WAIT = 60.0
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--no-default-browser-check",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-extensions",
    "--mute-audio",
    "--remote-debugging-pipe",
]


def chromium() -> str:
    """Chromium's path; a missing one fails in CI (CI=true) and skips elsewhere."""
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        if os.environ.get("CI"):
            pytest.fail("chromium is missing: .ci/run installs Debian's chromium package")
        pytest.skip("chromium is not installed here")
    return browser


class Browser:
    """A headless Chromium with one page, driven over the DevTools pipe."""

    def __init__(self, executable: str, width: int = 1280, height: int = 1000) -> None:
        self._profile = tempfile.TemporaryDirectory()
        to_child, self._send = os.pipe()
        self._receive, from_child = os.pipe()

        # a small Python process puts the pipe's ends at the descriptors Chromium
        # reads (3) and writes (4), then becomes Chromium (no preexec_fn: safe
        # with threads); both ends go above 4 first, so that neither is overwritten
        self.process = subprocess.Popen(
            [
                sys.executable,
                "-c",
                _LAUNCH,
                str(to_child),
                str(from_child),
                executable,
                *FLAGS,
                f"--user-data-dir={self._profile.name}",
                "about:blank",
            ],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            pass_fds=(to_child, from_child),
        )
        os.close(to_child)
        os.close(from_child)
        self._buffer = b""
        self._ids = itertools.count(1)
        self.errors: list[str] = []
        page = next(t for t in self.call("Target.getTargets")["targetInfos"] if t["type"] == "page")
        self.session = self.call("Target.attachToTarget", targetId=page["targetId"], flatten=True)[
            "sessionId"
        ]
        self.call("Runtime.enable", session=True)
        self.call("Page.enable", session=True)
        self.call(
            "Emulation.setDeviceMetricsOverride",
            session=True,
            width=width,
            height=height,
            deviceScaleFactor=1,
            mobile=False,
        )

    def _message(self, deadline: float) -> dict[str, Any]:
        while b"\0" not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self._receive], [], [], left)[0]:
                raise TimeoutError("Chromium did not answer")
            chunk = os.read(self._receive, 1 << 20)
            if not chunk:
                raise RuntimeError("Chromium closed the DevTools pipe")
            self._buffer += chunk
        raw, self._buffer = self._buffer.split(b"\0", 1)
        message: dict[str, Any] = json.loads(raw)
        return message

    def call(self, method: str, session: bool = False, **params: Any) -> dict[str, Any]:
        ident = next(self._ids)
        message: dict[str, Any] = {"id": ident, "method": method, "params": params}
        if session:
            message["sessionId"] = self.session
        os.write(self._send, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + WAIT
        while True:
            answer = self._message(deadline)
            if answer.get("method") == "Runtime.exceptionThrown":
                details = answer["params"]["exceptionDetails"]
                self.errors.append(str(details.get("exception", {}).get("description", details)))
            if answer.get("id") == ident:
                if "error" in answer:
                    raise RuntimeError(f"{method}: {answer['error']}")
                result: dict[str, Any] = answer.get("result", {})
                return result

    def evaluate(self, expression: str) -> Any:
        """The value of a JavaScript expression (promises awaited)."""
        result = self.call(
            "Runtime.evaluate",
            session=True,
            expression=expression,
            awaitPromise=True,
            returnByValue=True,
        )
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression}: {result['exceptionDetails']}")
        return result["result"].get("value")

    def wait_for(self, expression: str, what: str) -> Any:
        """Poll an expression until it is truthy; fail after :data:`WAIT` seconds."""
        deadline = time.monotonic() + WAIT
        while True:
            value = self.evaluate(expression)
            if value:
                return value
            if time.monotonic() > deadline:
                pytest.fail(f"the page never showed {what} (page errors: {self.errors})")
            time.sleep(0.05)

    def open(self, url: str) -> None:
        self.call("Page.navigate", session=True, url=url)
        state = self.wait_for(
            "document.readyState === 'complete' && document.body.dataset.reportReady",
            "its explorer ready",
        )
        assert state == "yes", self.evaluate("document.querySelector('.explore-error').textContent")

    def click(self, pose: list[float]) -> None:
        """A left click on the regions drawing at a pose."""
        self.evaluate("document.querySelector('canvas.explore-overlay').scrollIntoView()")
        at = self.evaluate(f"moveabilityReport.toClient({json.dumps(pose)})")
        for kind in ("mousePressed", "mouseReleased"):
            self.call(
                "Input.dispatchMouseEvent",
                session=True,
                type=kind,
                x=at["x"],
                y=at["y"],
                button="left",
                clickCount=1,
            )

    def screenshot(self, path: str, selector: str, margin: int = 8) -> None:
        """A PNG of the element matching ``selector``, with a margin around it."""
        box = self.evaluate(
            f"(() => {{ const e = document.querySelector({json.dumps(selector)});"
            " e.scrollIntoView(); const r = e.getBoundingClientRect();"
            f" const m = {margin};"
            " const x = Math.max(0, Math.floor(r.left + window.scrollX) - m);"
            " const y = Math.max(0, Math.floor(r.top + window.scrollY) - m);"
            " return {x, y, width: Math.ceil(r.width) + 2 * m,"
            " height: Math.ceil(r.height) + 2 * m}; })()"
        )
        shot = self.call(
            "Page.captureScreenshot",
            session=True,
            format="png",
            clip={**box, "scale": 1},
            captureBeyondViewport=True,
        )
        with open(path, "wb") as handle:
            handle.write(base64.b64decode(shot["data"]))

    def close(self) -> None:
        try:
            self.call("Browser.close")
        except (RuntimeError, TimeoutError, OSError):
            pass
        try:
            self.process.wait(timeout=WAIT)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        os.close(self._send)
        os.close(self._receive)
        self._profile.cleanup()


# ------------------------------------------------------------------ fixtures
@pytest.fixture(scope="module")
def browser():
    executable = chromium()
    started = Browser(executable)
    try:
        yield started
    finally:
        started.close()


@pytest.fixture(scope="module")
def analysis():
    return analyze(load_spec(SPEC), precision=0.05)


@pytest.fixture(scope="module")
def report(analysis, tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    return write_report(analysis, out, spec_path=SPEC)


@pytest.fixture
def page(browser, report):
    """The browser showing the five-bar's report, with no pose clicked."""
    browser.open(f"file://{os.path.abspath(report)}")
    return browser


def _frames_are_valid(analysis, frames, region_id):
    """Every frame of a motion is a configuration of the region: the legs reach,
    the joints are within their limits, det A has the region's sign."""
    m = analysis.mechanism
    region = next(r for r in analysis.regions if r.id == region_id)
    poses = m.wrap_poses(np.array([f[0] for f in frames], dtype=np.float64))
    postures = np.array([f[1] for f in frames])
    q = m.joint_angles(poses, clip=True)[np.arange(len(poses)), postures]
    ok = np.isfinite(q).all(axis=1)
    for i, lim in enumerate(m.limits):
        ok &= lim.contains(np.where(np.isfinite(q[:, i]), q[:, i], 0.0))
    ok &= np.sign(m.det_a(poses, q)) == region.sign
    return bool(ok.all())


def _poses(analysis, radius):
    """Two poses certainly in different regions only, and two far apart in one; the
    library's answers hold on a square of ``radius`` around each (a click lands
    within a pixel of the pose)."""
    rng = np.random.default_rng(7)
    lo, hi = analysis.tree.lo, analysis.tree.hi
    poses = lo + rng.random((4000, 2)) * (hi - lo)
    offsets = np.array([[dx, dy] for dx in (-1, 0, 1) for dy in (-1, 0, 1)]) * radius
    points = analysis.locate((poses[:, None, :] + offsets[None]).reshape(-1, 2))["points"]
    ids = [str(r.id) for r in analysis.regions]
    answers = np.array([[p["regions"][i] for i in ids] for p in points], dtype=object)
    answers = answers.reshape(len(poses), len(offsets), len(ids))
    steady = (answers == answers[:, :1]).all(axis=(1, 2))
    only = {
        j: poses[steady & (answers[:, 0, j] == True) & (answers[:, 0, 1 - j] == False)]  # noqa: E712
        for j in (0, 1)
    }
    assert len(only[0]) and len(only[1])
    apart = [only[0][0].tolist(), only[1][0].tolist()]
    assert analysis.feasible(apart)["feasible"] is False
    one = only[0]
    pair = [one[np.argmin(one[:, 0])].tolist(), one[np.argmax(one[:, 0])].tolist()]
    assert analysis.feasible(pair)["feasible"] is True
    return apart, pair


# --------------------------------------------------------------------- tests
def test_clicks_answer_feasibility_and_play_a_motion(analysis, page):
    scale = float(page.evaluate("document.querySelector('canvas.explore-overlay').dataset.scale"))
    apart, pair = _poses(analysis, radius=3.0 / scale)
    page.evaluate("moveabilityReport.clear()")
    for pose in apart:
        page.click(pose)
    assert page.evaluate("moveabilityReport.poses().length") == 2
    answer = page.evaluate("document.querySelector('.feasible-answer').dataset.answer")
    assert answer == "no"
    assert "not feasible" in page.evaluate("document.querySelector('.feasible-answer').textContent")
    clicked = page.evaluate("moveabilityReport.poses()")
    assert analysis.feasible(clicked)["feasible"] is False
    rows = page.evaluate(
        "[...document.querySelectorAll('.pose-answers tbody tr')]"
        ".map(r => [...r.cells].map(c => c.textContent))"
    )
    assert [row[-2:] for row in rows] == [["yes", "no"], ["no", "yes"]]

    page.evaluate("moveabilityReport.clear()")
    for pose in pair:
        page.click(pose)
    assert page.evaluate("document.querySelector('.feasible-answer').dataset.answer") == "yes"
    text = page.evaluate("document.querySelector('.feasible-answer').textContent")
    assert text.startswith("Feasible: yes.")
    clicked = page.evaluate("moveabilityReport.poses()")
    assert analysis.feasible(clicked)["feasible"] is True
    status = page.evaluate("document.querySelector('.motion-status').dataset.state")
    assert status == "playing"
    assert "certified cells" in page.evaluate(
        "document.querySelector('.motion-status').textContent"
    )
    # the animation advances: the frame counter moves and the drawing changes
    overlay = "document.querySelector('canvas.explore-overlay').dataset"
    first = page.wait_for(
        f"{overlay}.frame !== undefined && [{overlay}.frame, {overlay}.mechanism]", "a frame"
    )
    later = page.wait_for(
        f"{overlay}.frame !== {json.dumps(first[0])} && {overlay}.mechanism !== "
        f"{json.dumps(first[1])} && [{overlay}.frame, {overlay}.mechanism]",
        "the motion move",
    )
    assert later[0] != first[0] and later[1] != first[1]
    frames = page.evaluate("moveabilityReport.motion()")
    assert _frames_are_valid(analysis, frames, analysis.feasible(clicked)["region"])
    # every drawn leg keeps its link lengths: the drawing is the mechanism's
    legs = json.loads(later[1])
    for leg, spec in zip(legs, analysis.mechanism.legs, strict=True):
        pts = np.array(leg)
        assert np.hypot(*(pts[1] - pts[0])) == pytest.approx(spec.proximal, abs=1e-4)
        assert np.hypot(*(pts[2] - pts[1])) == pytest.approx(spec.distal, abs=1e-4)
    assert not page.errors


def test_page_answers_match_the_library(analysis, page):
    """Differential: the page's locate and feasible against the library's on random
    poses; the page may say unknown where the library decides, never the reverse
    of a definite answer, and agrees wherever the analysis's cells decide."""
    rng = np.random.default_rng(11)
    lo, hi = analysis.tree.lo, analysis.tree.hi
    # a margin outside the box, and poses on cell faces, where the rules are strict
    poses = lo - 0.05 * (hi - lo) + rng.random((200, 2)) * 1.1 * (hi - lo)
    leaves = analysis.tree.leaves()
    faces = leaves.lo[rng.choice(len(leaves.lo), 40, replace=False)]
    poses = np.concatenate([poses, faces])
    ours = page.evaluate(f"moveabilityReport.locate({json.dumps(poses.tolist())})")
    theirs = analysis.locate(poses)
    assert ours["regions"] == theirs["regions"]
    from moveability.output.report_cells import page_cells

    cells = page_cells(analysis)
    reference = cells.locate(analysis.as_poses(poses))
    decided = 0
    for mine, lib, ref in zip(ours["points"], theirs["points"], reference, strict=True):
        for j, region in enumerate(analysis.regions):
            a, b = mine["regions"][str(region.id)], lib["regions"][str(region.id)]
            assert a is None or a == b
            assert a == ref["regions"][j]  # the same rule as the Python twin
            decided += a is not None
        assert mine["workspace"] is None or mine["workspace"] == lib["workspace"]
    assert decided > 0.8 * len(poses) * len(analysis.regions)
    # feasibility of random pairs and triples, biased towards the regions
    sure = [np.flatnonzero(analysis.region_cells(j)[0]) for j in range(len(analysis.regions))]
    centres = 0.5 * (leaves.lo + leaves.hi)
    groups = []
    for n in range(200):
        size = 2 + n % 2
        if n % 3 == 0:
            chosen = centres[rng.choice(sure[n % len(sure)], size)]
        else:
            chosen = poses[rng.choice(len(poses), size)]
        groups.append(chosen.tolist())
    ours_f = page.evaluate(f"{json.dumps(groups)}.map(g => moveabilityReport.feasible(g).feasible)")
    counts = {True: 0, False: 0, None: 0}
    for group, mine in zip(groups, ours_f, strict=True):
        lib = analysis.feasible(group)["feasible"]
        assert mine is None or mine == lib
        assert mine == cells.feasible(analysis.as_poses(group))
        counts[mine] += 1
    assert counts[True] and counts[False]


def test_drawn_legs_match_the_mechanism(analysis, page):
    """The page's legs (its twin of the legs' links) against the library's."""
    m = analysis.mechanism
    for pose in ([3.5, 9.0], [1.0, 5.0], [6.0, 4.0]):
        q = m.joint_angles(np.array([pose]))[0]
        for posture in range(len(m.postures)):
            if not np.isfinite(q[posture]).all():
                continue
            drawn = page.evaluate(f"moveabilityReport.mechanism({json.dumps(pose)}, {posture})")
            for i, leg in enumerate(m.legs):
                expected = leg.links(np.array(pose), float(q[posture, i]))
                assert np.allclose(drawn[i]["points"], expected, atol=1e-9)


def test_motions_in_the_page_are_configurations_of_their_region(analysis, page):
    """Motions between random poses certainly in one region, through posture
    changes where needed: every frame drawn is a valid configuration of it."""
    rng = np.random.default_rng(3)
    leaves = analysis.tree.leaves()
    changes = 0
    for j in range(len(analysis.regions)):
        sure = np.flatnonzero(analysis.region_cells(j)[0])
        for _ in range(8):
            pick = rng.choice(sure, 2)
            poses = (0.5 * (leaves.lo[pick] + leaves.hi[pick])).tolist()
            page.evaluate("moveabilityReport.clear()")
            for pose in poses:
                page.evaluate(f"moveabilityReport.addPose({json.dumps(pose)})")
            state = page.evaluate("document.querySelector('.motion-status').dataset.state")
            assert state == "playing"
            frames = page.evaluate("moveabilityReport.motion()")
            region = page.evaluate(f"moveabilityReport.feasible({json.dumps(poses)}).region")
            assert _frames_are_valid(analysis, frames, region)
            assert np.allclose(frames[0][0], poses[0]) and np.allclose(frames[-1][0], poses[1])
            changes += len({f[1] for f in frames}) > 1
    assert changes  # some motions cross a fold


def test_drawing_shows_the_regions(analysis, page):
    """The drawing holds the regions' colours where the library places poses
    certainly in one region only (the canvas's own pixels: a screenshot's clip
    may be off by the page's margins)."""
    view = [
        float(v)
        for v in page.evaluate(
            "document.querySelector('canvas.explore-overlay').dataset.view"
        ).split(",")
    ]
    scale = float(page.evaluate("document.querySelector('canvas.explore-overlay').dataset.scale"))
    ratio = float(page.evaluate("window.devicePixelRatio || 1"))
    apart, _ = _poses(analysis, radius=3.0 / scale)
    for j, pose in enumerate(apart):
        u = int((pose[0] - view[0]) * scale * ratio)
        v = int((view[3] - pose[1]) * scale * ratio)
        rgba = page.evaluate(
            "Array.from(document.querySelector('canvas.explore-cells').getContext('2d')"
            f".getImageData({u}, {v}, 1, 1).data)"
        )
        assert rgba[3] == 255  # the layers are opaque where W is certain
        pixel = np.array(rgba[:3]) / 255
        color = page.evaluate(
            f"JSON.parse(document.getElementById('explore-data').textContent).regions[{j}].color"
        )
        rgb = np.array([int(color[i : i + 2], 16) for i in (1, 3, 5)]) / 255
        # the region's colour at 55% over the pale colour of W
        assert np.allclose(pixel, 0.55 * rgb + 0.45 * np.array([0xE4, 0xEC, 0xF5]) / 255, atol=0.03)


def test_figures_render(page):
    widths = page.evaluate("[...document.images].map((i) => i.complete && i.naturalWidth)")
    assert len(widths) == 4  # no motion: no path figure
    assert all(w > 100 for w in widths)


def test_three_pose_axes_with_a_slice_and_coarse_cells(browser, tmp_path):
    """The 3-RPR: poses (x, y, phi) with phi from the slider; the cells coarsened,
    every possible component kept (the regions are not proved to be all)."""
    result = analyze(load_spec("examples/three-rpr.toml"), precision=2.0)
    assert not result.complete
    path = write_report(result, tmp_path, max_cells=20_000)
    browser.open(f"file://{path}")
    note = browser.evaluate("document.querySelector('#explore .note').textContent")
    assert "merged keeping only what all of them certify" in note
    browser.evaluate("moveabilityReport.setSlice(0.5)")
    phi = float(browser.evaluate("document.querySelector('.explore-slice').value"))
    assert phi == pytest.approx(0.5, abs=2 * np.pi / 720)  # the slider's step
    label = browser.evaluate("document.querySelector('.explore-slice-value').textContent")
    assert label.startswith(f"phi = {phi:.3f} rad")
    drawn = int(browser.evaluate("document.querySelector('canvas.explore-cells').dataset.drawn"))
    assert 0 < drawn
    # a click takes phi from the slider
    browser.click([-10.0, -10.0])
    assert browser.evaluate("moveabilityReport.poses()")[0][2] == phi
    rng = np.random.default_rng(4)
    lo, hi = result.tree.lo, result.tree.hi
    poses = lo + rng.random((150, 3)) * (hi - lo)
    poses[:, 2] += rng.integers(-1, 2, 150) * 2 * np.pi  # any turn: the page wraps
    ours = browser.evaluate(f"moveabilityReport.locate({json.dumps(poses.tolist())})")
    theirs = result.locate(poses)
    for mine, lib in zip(ours["points"], theirs["points"], strict=True):
        assert mine["pose"] == pytest.approx(lib["pose"], abs=0)
        for key, value in mine["regions"].items():
            assert value is None or value == lib["regions"][key]
    groups = [poses[rng.choice(150, 2)].tolist() for _ in range(60)]
    answers = browser.evaluate(
        f"{json.dumps(groups)}.map(g => moveabilityReport.feasible(g).feasible)"
    )
    for group, mine in zip(groups, answers, strict=True):
        assert mine is None or mine == result.feasible(group)["feasible"]
    # a motion between two poses the page places in one region
    leaves = result.tree.leaves()
    sure = np.flatnonzero(result.region_cells(0)[0])
    centres = 0.5 * (leaves.lo[sure] + leaves.hi[sure])
    placed = browser.evaluate(f"moveabilityReport.locate({json.dumps(centres.tolist())})")
    key = str(result.regions[0].id)
    yes = [c for c, p in zip(centres.tolist(), placed["points"], strict=True) if p["regions"][key]]
    assert len(yes) >= 2
    browser.evaluate("moveabilityReport.clear()")
    for pose in (yes[0], yes[-1]):
        browser.evaluate(f"moveabilityReport.addPose({json.dumps(pose)})")
    assert browser.evaluate("document.querySelector('.feasible-answer').dataset.answer") == "yes"
    frames = browser.evaluate("moveabilityReport.motion()")
    region = browser.evaluate(f"moveabilityReport.feasible({json.dumps([yes[0], yes[-1]])}).region")
    assert _frames_are_valid(result, frames, region)
    assert not browser.errors


def test_slider_legs_are_drawn_as_the_biglide(browser, tmp_path):
    result = analyze(load_spec("examples/biglide.toml"), precision=0.2)
    browser.open(f"file://{write_report(result, tmp_path)}")
    m = result.mechanism
    for pose in ([0.5, 2.0], [-1.0, -3.0]):
        q = m.joint_angles(np.array([pose]))[0]
        for posture in range(len(m.postures)):
            drawn = browser.evaluate(f"moveabilityReport.mechanism({json.dumps(pose)}, {posture})")
            for i, leg in enumerate(m.legs):
                expected = leg.links(np.array(pose), float(q[posture, i]))
                assert np.allclose(drawn[i]["points"], expected, atol=1e-9)
