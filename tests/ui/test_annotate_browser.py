"""End-to-end: the annotate page in a real (headless Debian) Chromium, driven by Playwright.

Starts ``vidcap annotate sample_videos/walk_side.mp4 --no-browser`` in a subprocess on a
free port, opens the address it prints (with its token), flips a depth, steps frames with the
keyboard, drags a joint, draws a region that is not the person (and sees the silhouette
recomputed without it), and checks the annotations file holds exactly those events.
Screenshots go to ``test-artifacts/`` (and to ``docs/`` with ``VIDCAP_UPDATE_DOCS=1``).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import socket
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.browser

REPO = Path(__file__).resolve().parents[2]
CHROMIUM = "/usr/bin/chromium"
ARTIFACTS = REPO / "test-artifacts"
VIDEO = REPO / "sample_videos" / "walk_side.mp4"
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run"]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def stage_cache(tmp_path_factory):
    """One stage cache for the module: the first start runs the pipeline, the next reuse it."""
    return tmp_path_factory.mktemp("vidcap-cache")


@contextmanager
def annotate_server(annotations: Path, cache: Path, *, timeout: float = 300.0):
    """``vidcap annotate`` on the sample walk; yield (url, process, log); always kill it."""
    port = _free_port()
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    cmd = [sys.executable, "-m", "vidcap", "annotate", str(VIDEO), "--no-browser",
           "--port", str(port), "--annotations", str(annotations), "--cache-dir", str(cache)]
    log = annotations.with_suffix(".log")
    with open(log, "w") as fh:
        proc = subprocess.Popen(cmd, cwd=REPO, env=env, stdout=fh, stderr=subprocess.STDOUT)
    try:
        t0 = time.monotonic()
        while True:
            if proc.poll() is not None:
                pytest.fail(f"annotate server exited ({proc.returncode}):\n{log.read_text()}")
            found = re.search(r"vidcap annotate: (http://\S+)", log.read_text())
            if found:
                break
            if time.monotonic() - t0 > timeout:
                pytest.fail(f"annotate server did not start in {timeout} s:\n{log.read_text()}")
            time.sleep(0.2)
        url = found.group(1)
        assert url.startswith(f"http://127.0.0.1:{port}/") and "secret=" in url
        yield url, proc, log
    finally:
        proc.kill()
        proc.wait(10)


@pytest.fixture(scope="module")
def browser():
    if not Path(CHROMIUM).exists():
        if os.environ.get("CI") == "true":
            pytest.fail(f"{CHROMIUM} is missing (.ci/run installs Debian's chromium)")
        pytest.skip(f"{CHROMIUM} is missing: apt-get install -y chromium")
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        try:
            yield b
        finally:
            b.close()


def _state(page, name):
    return page.evaluate(f"window.trame.state.get('{name}')")


def _wait_state(page, expr: str, timeout: float = 15000):
    page.wait_for_function(f"window.trame && window.trame.state && ({expr})", timeout=timeout)


def _screenshot(page, name: str, *, docs: bool = True) -> None:
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / name))
    if docs and os.environ.get("VIDCAP_UPDATE_DOCS"):
        (REPO / "docs").mkdir(exist_ok=True)
        shutil.copy(ARTIFACTS / name, REPO / "docs" / name)


def test_annotate_flip_step_drag(browser, stage_cache, tmp_path):
    ann = tmp_path / "walk.json"
    with annotate_server(ann, stage_cache) as (url, _proc, log):
        page = browser.new_page(viewport={"width": 1280, "height": 860})
        page.goto(url)
        page.wait_for_selector("#frame-img[src^='data:image']", timeout=30000)
        _wait_state(page, "window.trame.state.get('segments').length == 10")

        # 1. flip the left lower arm's depth at frame 0
        seg = "l_lower_arm"
        sign0 = next(s["sign"] for s in _state(page, "segments") if s["name"] == seg)
        page.click(f"#flip-{seg}")
        page.wait_for_selector("#inputs-count:has-text('inputs: 1')")
        _wait_state(page, f"window.trame.state.get('segments')[3].sign == {-sign0}")

        # 2. step three frames with the keyboard (Right arrow)
        page.click("#frame-label")  # focus the page, not a control
        for _ in range(3):
            page.keyboard.press("ArrowRight")
        _wait_state(page, "window.trame.state.get('frame') == 3")
        page.wait_for_selector("#frame-label:has-text('frame 3 /')")

        # 3. drag the right wrist 24 px right and 12 px down (page pixels)
        names = _state(page, "joint_names")
        j = names.index("r_wrist")
        x, y = _state(page, "joints_display")[j]
        box = page.locator("#frame-img").bounding_box()
        natural = page.evaluate("document.querySelector('#frame-img').naturalWidth")
        k = box["width"] / natural  # CSS pixels per picture pixel
        page.mouse.move(box["x"] + x * k, box["y"] + y * k)
        page.mouse.down()
        page.mouse.move(box["x"] + (x + 12) * k, box["y"] + (y + 6) * k, steps=4)
        page.mouse.move(box["x"] + (x + 24) * k, box["y"] + (y + 12) * k, steps=4)
        page.mouse.up()
        page.wait_for_selector("#inputs-count:has-text('inputs: 2')")
        _wait_state(page, "window.trame.state.get('user_joints').includes('r_wrist')")
        _screenshot(page, "annotate.png")

        # 4. swap the legs from this frame on, and back
        page.click("#swap-legs")
        page.wait_for_selector("#inputs-count:has-text('inputs: 3')")
        _wait_state(page, "window.trame.state.get('sides_swapped').includes('legs')")
        page.click("#swap-legs")
        _wait_state(page, "window.trame.state.get('sides_swapped').length == 0")
        page.wait_for_selector("#inputs-count:has-text('inputs: 2')")

        # 5. regions that are not the person: a box over the head, an outline in a corner
        drawn, corner = _draw_regions(page)

        # the Review tab lists flagged frames; clicking one opens it
        page.click("#tab-review")
        chip = page.locator("#flagged-list .v-chip").first
        chip.wait_for()
        target = int(chip.inner_text().split(":")[0])
        chip.click()
        _wait_state(page, f"window.trame.state.get('frame') == {target}")
        page.wait_for_selector("#review-side[src^='data:image']")
        _screenshot(page, "annotate_review.png")

        # play advances the frames by itself; pause stops it
        page.click("#review-btn-play")
        _wait_state(page, f"window.trame.state.get('frame') != {target}")
        page.click("#review-btn-play")
        _wait_state(page, "window.trame.state.get('playing') == false")
        page.close()

    events = json.loads(ann.read_text())["events"]
    disp = 640 / 480  # the page shows the 480 px clip 640 px wide
    assert len(events) == 4, events
    depth, joint, region, outline = events
    assert depth == {"frame": 0, "type": "depth", "segment": seg,
                     "value": "away" if sign0 > 0 else "toward"}
    assert joint["frame"] == 3 and joint["type"] == "joint" and joint["joint"] == "r_wrist"
    assert joint["u"] == pytest.approx((x + 24) / disp, abs=1.5)
    assert joint["v"] == pytest.approx((y + 12) / disp, abs=1.5)
    assert region["type"] == "scene_region" and region["frame"] == 3
    assert region["box"] == pytest.approx([v / disp for v in drawn], abs=2.0)
    poly = np.array(outline["polygon"]) * disp
    assert outline["type"] == "scene_region" and 4 <= len(poly) <= 40
    assert poly.min(axis=0) == pytest.approx(corner[0], abs=3)
    assert poly.max(axis=0) == pytest.approx(corner[2], abs=3)
    assert "Traceback" not in log.read_text()


def test_malformed_annotations_shown_and_kept(browser, stage_cache, tmp_path):
    ann = tmp_path / "walk.json"
    text = '{"version": 1, "events": [{"frame": 0, "type": "depth"}]}\n'
    ann.write_text(text)
    with annotate_server(ann, stage_cache) as (url, _proc, log):
        page = browser.new_page(viewport={"width": 1280, "height": 860})
        page.goto(url)
        alert = page.locator("#load-error")
        alert.wait_for(timeout=30000)
        assert "walk.json" in alert.inner_text()
        assert "walk.json.bak" in alert.inner_text()
        page.wait_for_selector("#frame-img[src^='data:image']")
        _screenshot(page, "annotate_malformed.png", docs=False)
        # N jumps to the frame that most needs attention (no edit: nothing is written)
        first = next(it for it in _state(page, "flagged") if it["frame"] != 0)
        page.click("#frame-label")
        page.keyboard.press("n")
        _wait_state(page, f"window.trame.state.get('frame') == {first['frame']}")
        page.wait_for_selector(f"#message:has-text('frame {first['frame']}:')")
        page.close()
    assert ann.read_text() == text
    assert (tmp_path / "walk.json.bak").read_text() == text
    out = log.read_text()
    assert "walk.json" in out and "error" in out


def _draw_regions(page) -> tuple[list, list]:
    """Mark the person's head in the current frame as "not the person" (a deliberate
    mistake that shows plainly) and outline an empty corner; wait until the silhouettes
    are recomputed each time. Returns the box and the outline drawn, in page pixels."""
    area0 = _state(page, "sil_area")
    assert area0 > 0
    names = _state(page, "joint_names")
    joints = _state(page, "joints_display")
    (hx, hy), (_nx, ny) = joints[names.index("head_top")], joints[names.index("neck")]
    drawn = [hx - 20, hy - 12, hx + 20, ny]  # page pixels: the head
    x0, y0, x1, y1 = drawn
    page.click("#mode-scene_region")
    _wait_state(page, "window.trame.state.get('draw_mode') == 'scene_region'")
    box = page.locator("#frame-img").bounding_box()
    natural = page.evaluate("document.querySelector('#frame-img').naturalWidth")
    k = box["width"] / natural
    page.mouse.move(box["x"] + x0 * k, box["y"] + y0 * k)
    page.mouse.down()
    page.mouse.move(box["x"] + (x0 + x1) / 2 * k, box["y"] + (y0 + y1) / 2 * k, steps=3)
    page.wait_for_selector("#draw-band")  # the rubber band follows the mouse
    page.mouse.move(box["x"] + x1 * k, box["y"] + y1 * k, steps=3)
    page.mouse.up()
    page.wait_for_selector("#region-list :text('not the person')")
    _wait_state(page, "window.trame.state.get('reseg_status').includes('changed')",
                timeout=60000)
    _wait_state(page, f"window.trame.state.get('sil_area') < {area0}")  # the head is gone
    _screenshot(page, "annotate_regions.png")
    # an outline drawn around an empty corner: saved as a polygon, changes nothing
    page.click("#mode-scene_area")
    _wait_state(page, "window.trame.state.get('draw_mode') == 'scene_area'")
    corner = [(560, 20), (630, 20), (630, 90), (600, 60), (560, 80)]
    page.mouse.move(box["x"] + corner[0][0] * k, box["y"] + corner[0][1] * k)
    page.mouse.down()
    for cx, cy in corner[1:] + corner[:1]:
        page.mouse.move(box["x"] + cx * k, box["y"] + cy * k, steps=4)
    page.mouse.up()
    _wait_state(page, "window.trame.state.get('regions').length == 2")
    _wait_state(page, "window.trame.state.get('reseg_status').includes(': 0 frame')",
                timeout=60000)
    page.click("#mode-joints")
    return drawn, corner
