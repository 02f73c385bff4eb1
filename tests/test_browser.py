"""The grasp replay in a real browser: headless Debian Chromium driven by Playwright, offline, on localhost.

.ci/run installs Debian's chromium and sets BHGRASP_REQUIRE_BROWSER=1, so there a missing browser fails the test;
elsewhere it is skipped with the reason.  BHGRASP_SCREENSHOT=path also writes the screenshot there (docs/).

No assertion depends on how fast the browser plays: the test waits until every scene command of the page has been
applied, waits (without a pace assumption) for the clip to play through its end and wrap on its own, then pauses the
animator and sets its clock itself, reading the box's pose at chosen clip times and comparing it with the recorded
trajectory (the npz the same `bhgrasp demo` run wrote, not the viewer's own frame list).
"""

from __future__ import annotations

import contextlib
import functools
import http.server
import io
import os
import shutil
import threading
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from bhgrasp.cli import main
from bhgrasp.data import Trajectory

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-quic",
]
LINKS = ["palm_0", "F1_proximal_link_0", "F2_distal_link_0", "F3_distal_link_0", "object0"]
TIMEOUT = 60_000  # [ms] only an upper bound for a loaded machine: nothing below waits a fixed time

# Before the page's scripts: count the scene commands.  MeshCat's static page issues one fetch of a data: URL per
# command and applies it in the promise chain after `response.arrayBuffer()`, in the same microtask checkpoint as
# this counter's update; a poll (a later task) that sees handled == issued therefore sees every command applied.
COUNT_COMMANDS = """
window.bhgrasp = {issued: 0, handled: 0, loops: 0};
const pageFetch = window.fetch;
window.fetch = function (resource, ...rest) {
    if (String(resource).startsWith("data:")) window.bhgrasp.issued += 1;
    return pageFetch.call(this, resource, ...rest);
};
const arrayBuffer = Response.prototype.arrayBuffer;
Response.prototype.arrayBuffer = function () {
    return arrayBuffer.call(this).finally(() => { window.bhgrasp.handled += 1; });
};
"""
LOADED = (
    "document.readyState === 'complete' && window.bhgrasp.issued > 0"
    " && window.bhgrasp.handled === window.bhgrasp.issued && viewer.animator.actions.length > 0"
)
# the box node's 4 x 4 placement (column-major) in the scene's own frame (the `bhgrasp` node, which look_at shifts)
BOX_POSE = """() => {
    const root = viewer.scene_tree.find(["meshcat", "bhgrasp"]).object;
    const box = viewer.scene_tree.find(["meshcat", "bhgrasp", "visuals", "object0"]).object;
    box.updateWorldMatrix(true, false);
    return Array.from(root.matrixWorld.clone().invert().multiply(box.matrixWorld).elements);
}"""
BOX_ACTION = """viewer.animator.actions.find(
    (action) => action.getRoot() === viewer.scene_tree.find(["meshcat", "bhgrasp", "visuals", "object0"]).object)"""

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def replay(tmp_path_factory) -> Path:
    """`bhgrasp demo --html`: the README's main job writes the replay (and the trajectory, grasp_demo.npz)."""
    folder = tmp_path_factory.mktemp("replay")
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        assert main(["demo", "--output", str(folder), "--duration", "2.5", "--html", str(folder / "replay.html")]) == 0
    assert "http://" not in printed.getvalue()  # the export's MeshCat server ends with the command: no dead address
    return folder / "replay.html"


def assert_the_grasp_is_visible(shot: Path) -> None:
    """The screenshot of the lifted box: the hand framed large, the contact forces seen through the translucent
    box, a ground reference (colour classes of this scene: grey hand, yellow-green arrows through orange, light
    plate).  Before these fixes: hand 4.0 % of the pixels, 0 arrow pixels, no ground."""
    import matplotlib.image

    rgb = (matplotlib.image.imread(shot)[:, :, :3] * 255).astype(int)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    hand = (abs(r - g) < 15) & (abs(g - b) < 30) & (r > 80) & (r < 175)
    arrows = (g >= r) & (g > b + 50)
    ground = (r > 180) & (g > 180) & (b > 170) & (abs(r - b) < 30)
    assert hand.mean() > 0.055, f"the hand covers {100 * hand.mean():.1f} % of the frame"
    assert arrows.sum() > 50, f"{arrows.sum()} pixels of contact-force arrows visible"
    assert ground.mean() > 0.05, f"the ground plate covers {100 * ground.mean():.1f} % of the frame"


def recorded_poses(traj: Trajectory, time: float) -> list[np.ndarray]:
    """The box's recorded 4 x 4 poses at the samples next to ``time`` [s] (a replay frame shows one of them)."""
    k = int(np.searchsorted(traj.t, time))
    samples = range(max(k - 1, 0), min(k + 2, len(traj)))
    poses = np.concatenate((traj.object_position[:, 0], traj.object_quaternion[:, 0]), axis=1)
    return [pin.XYZQUATToSE3(poses[i]).homogeneous for i in samples]


def assert_shows(shown: list[float], traj: Trajectory, time: float) -> None:
    """The page's box pose (column-major) is the recorded pose at sim time ``time`` (float32 three.js tracks)."""
    shown = np.reshape(shown, (4, 4)).T
    error = min(np.abs(shown - truth).max() for truth in recorded_poses(traj, time))
    assert error < 1e-5, f"the box at t = {time:.4f} s is {error:.2e} off every recorded pose next to that time"


def wait_for(page, condition: str, what: str) -> None:
    """Wait until the page's ``condition`` holds (up to TIMEOUT), failing with ``what`` did not happen."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    try:
        page.wait_for_function(condition, timeout=TIMEOUT)
    except PlaywrightTimeout:
        pytest.fail(f"{what} within {TIMEOUT / 1000:g} s ({condition})")


def test_replay_opens_offline_in_chromium_and_animates(replay: Path, tmp_path: Path) -> None:
    if not Path(CHROMIUM).exists():
        if os.environ.get("BHGRASP_REQUIRE_BROWSER") == "1":
            pytest.fail(f"no Chromium at {CHROMIUM}; .ci/run installs Debian's chromium package")
        pytest.skip(f"no Chromium at {CHROMIUM} (apt-get install chromium)")
    from playwright.sync_api import sync_playwright

    traj = Trajectory.load(replay.parent / "grasp_demo.npz")
    t0 = float(traj.t[0])
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
            page.add_init_script(COUNT_COMMANDS)
            page.on("request", lambda request: requests.append(request.url))
            page.goto(url)
            wait_for(page, LOADED, "the page did not apply its scene commands")
            visuals = page.evaluate(
                "Object.keys(viewer.scene_tree.children.meshcat.children.bhgrasp.children.visuals.children)"
            )
            assert set(LINKS) <= set(visuals)  # the hand's links and the box are in the three.js scene tree
            duration = page.evaluate("viewer.animator.duration")
            assert duration == pytest.approx(traj.t[-1] - t0, abs=1.0 / 30)  # the clip spans the run

            # it plays on its own, through the clip's end and back to its start (however slow the machine)
            page.evaluate("viewer.animator.mixer.addEventListener('loop', () => { window.bhgrasp.loops += 1; })")
            wait_for(page, "window.bhgrasp.loops > 0", "the replay did not play through its end and loop")
            playing, paused, time = page.evaluate(f"[viewer.animator.playing, {BOX_ACTION}.paused, {BOX_ACTION}.time]")
            assert playing and not paused and 0.0 <= time < duration

            # from here on the test owns the clock: the animator stops reading wall time and each evaluate sets the
            # clip time and reads the pose in one JavaScript task, so no browser frame can come in between
            page.evaluate("viewer.animator.pause()")
            times = np.array(page.evaluate(f"Array.from({BOX_ACTION}.getClip().tracks[0].times)"))
            assert times[0] == 0.0 and times[-1] == pytest.approx(duration)
            first, early, late = 0.0, float(times[len(times) // 20]), float(times[round(0.9 * (len(times) - 1))])
            seek = f"(time) => {{ viewer.animator.seek(time); return ({BOX_POSE})(); }}"
            start = page.evaluate(seek, first)
            assert_shows(start, traj, t0 + first)
            lifted = page.evaluate(seek, late)
            assert_shows(lifted, traj, t0 + late)  # the box is lifted late in the run ...
            assert lifted[14] - start[14] > 1e-3  # [m] ... so its node really moved with the clock

            # the loop: from 90 % run the mixer past the clip's end; the clock wraps to `early`, the box with it
            wrapped = page.evaluate(
                f"""(step) => {{
                    const loops = window.bhgrasp.loops;
                    viewer.animator.mixer.update(step);
                    return [{BOX_ACTION}.time, window.bhgrasp.loops - loops, ({BOX_POSE})()];
                }}""",
                duration - late + early,
            )
            assert wrapped[0] == pytest.approx(early, abs=1e-6) and wrapped[1] > 0
            assert_shows(wrapped[2], traj, t0 + early)

            page.evaluate(seek, late)  # the screenshot shows the lifted box
            shot = tmp_path / "replay.png"
            page.screenshot(path=str(shot))
            context.close()
    finally:
        server.shutdown()
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 20_000
    assert_the_grasp_is_visible(shot)
    assert all(request.startswith("http://127.0.0.1") or request.startswith("data:") for request in requests)
    if os.environ.get("BHGRASP_SCREENSHOT"):
        shutil.copy(shot, os.environ["BHGRASP_SCREENSHOT"])
