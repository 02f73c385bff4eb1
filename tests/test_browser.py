"""The grasp replay in a real browser: headless Debian Chromium driven by Playwright, offline, on localhost.

.ci/run installs Debian's chromium and sets BHGRASP_REQUIRE_BROWSER=1, so there a missing browser fails the test;
elsewhere it is skipped with the reason.  BHGRASP_SCREENSHOT=path also writes the screenshot there (docs/).
"""

from __future__ import annotations

import functools
import http.server
import os
import shutil
import threading
import time
from pathlib import Path

import pytest

from bhgrasp.cli import main

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
FLAGS = ["--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--disable-quic"]  # fmt: skip
BOX_HEIGHT = "viewer.scene_tree.find(['meshcat','bhgrasp','visuals','object0']).object.position.z"
LINKS = ["palm_0", "F1_proximal_link_0", "F2_distal_link_0", "F3_distal_link_0", "object0"]

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def replay(tmp_path_factory) -> Path:
    """`bhgrasp demo --html`: the README's main job writes the replay."""
    folder = tmp_path_factory.mktemp("replay")
    assert main(["demo", "--output", str(folder), "--duration", "2.5", "--html", str(folder / "replay.html")]) == 0
    return folder / "replay.html"


def test_replay_opens_offline_in_chromium_and_animates(replay: Path, tmp_path: Path) -> None:
    if not Path(CHROMIUM).exists():
        if os.environ.get("BHGRASP_REQUIRE_BROWSER") == "1":
            pytest.fail(f"no Chromium at {CHROMIUM}; .ci/run installs Debian's chromium package")
        pytest.skip(f"no Chromium at {CHROMIUM} (apt-get install chromium)")
    from playwright.sync_api import sync_playwright

    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(replay.parent))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    url = f"http://127.0.0.1:{server.server_address[1]}/{replay.name}"
    requests: list[str] = []
    try:
        with sync_playwright() as playwright:
            context = playwright.chromium.launch_persistent_context(
                str(tmp_path / "profile"), executable_path=CHROMIUM, headless=True, args=FLAGS
            )
            page = context.new_page()
            page.on("request", lambda request: requests.append(request.url))
            page.goto(url)
            page.wait_for_function("typeof viewer !== 'undefined' && viewer.scene_tree !== undefined", timeout=30_000)
            visuals = page.evaluate(
                "Object.keys(viewer.scene_tree.children.meshcat.children.bhgrasp.children.visuals.children)"
            )
            assert set(LINKS) <= set(visuals)  # the hand's links and the box are in the three.js scene tree
            start = page.evaluate("viewer.animator.mixer.time")
            height = page.evaluate(
                "viewer.scene_tree.find(['meshcat','bhgrasp','visuals','object0']).object.position.z"
            )
            time.sleep(1.5)
            later = page.evaluate("viewer.animator.mixer.time")
            # the animation plays (its pace follows the machine's load: 0.98 s in 1.5 s with both cores busy)
            assert later > start + 0.3
            page.evaluate("viewer.animator.seek(0.9 * viewer.animator.duration)")  # the box is lifted late in the run
            page.evaluate("viewer.set_dirty()")
            time.sleep(0.3)
            lifted = page.evaluate(
                "viewer.scene_tree.find(['meshcat','bhgrasp','visuals','object0']).object.position.z"
            )
            assert abs(lifted - height) > 1e-3  # [m] the object node moves with the animation
            shot = tmp_path / "replay.png"
            page.screenshot(path=str(shot))
            context.close()
    finally:
        server.shutdown()
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 20_000
    assert all(request.startswith("http://127.0.0.1") or request.startswith("data:") for request in requests)
    if os.environ.get("BHGRASP_SCREENSHOT"):
        shutil.copy(shot, os.environ["BHGRASP_SCREENSHOT"])
