"""bhgrasp.viz: placements match the collision model, overlays encode forces and cones, replays are decimated."""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.experiments.hold import reference_hold
from bhgrasp.viz import MAX_FPS, LiveView, SceneViewer, _contact_overlays, _frame_samples


@pytest.fixture(scope="module")
def held():
    hold = reference_hold()
    traj = hold.simulator.run(hold.controller, 0.2, state=hold.state, progress=False)
    viewer = SceneViewer(hold.simulator.scene)
    yield hold, traj, viewer
    viewer.close()


def test_viz_is_not_imported_by_the_package():
    import subprocess
    import sys

    code = "import sys, bhgrasp; print('bhgrasp.viz' in sys.modules, 'meshcat' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout.split() == ["False"] * 2


def test_placements_match_the_scene_collision_geometry(held):
    """The viewer's placements equal the simulator's own geometry placements at the full scene configuration."""
    hold, traj, viewer = held
    scene = hold.simulator.scene
    k = len(traj) - 1
    poses = [pin.XYZQUATToSE3(np.r_[p, quat]) for p, quat in zip(traj.object_position[k], traj.object_quaternion[k])]
    q = np.concatenate((traj.q[k], pin.SE3ToXYZQUAT(poses[0])))
    data, geometry_data = scene.model.createData(), pin.GeometryData(scene.geometry)
    pin.updateGeometryPlacements(scene.model, data, scene.geometry, geometry_data, q)
    for shown, truth in zip(viewer.placements(traj.q[k], poses), geometry_data.oMg):
        np.testing.assert_allclose(shown, truth.homogeneous, atol=1e-12)


def test_contact_overlays_draw_the_force_and_the_friction_cone():
    point, normal, force = np.array([0.1, 0.0, 0.2]), np.array([0.0, 1.0, 0.0]), np.array([0.3, 4.0, 0.0])
    overlays = _contact_overlays(point, normal, force, True, force_scale=0.01, mu=0.5)
    transform, scale, visible = overlays["stick"]
    assert visible and not overlays["slip"][2]
    length = scale[1]
    assert length == pytest.approx(0.01 * np.linalg.norm(force))  # [m] per newton
    axis = transform[:3, 1]  # the cylinder's axis (local y)
    np.testing.assert_allclose(axis, force / np.linalg.norm(force), atol=1e-12)
    np.testing.assert_allclose(transform[:3, 3] - 0.5 * length * axis, point, atol=1e-12)  # starts at the contact
    cone, cone_scale, _ = overlays["cone"]
    np.testing.assert_allclose(cone[:3, 1], normal, atol=1e-12)
    assert cone_scale[0] / cone_scale[1] == pytest.approx(0.5)  # radius / height = mu: the cone's half-angle


def test_frames_are_decimated_to_at_most_60_per_second():
    t = np.arange(0.0, 2.0 + 1e-9, 1e-3)
    frames = _frame_samples(t, 30.0)
    assert len(frames) == 61 and frames[0] == 0 and frames[-1] == len(t) - 1
    np.testing.assert_allclose(np.diff(t[frames]), 1.0 / 30.0, atol=1e-3)
    assert MAX_FPS == 60.0


def test_replay_exports_a_self_contained_animated_page(held, tmp_path):
    _, traj, viewer = held
    animation = viewer.replay(traj, fps=30)
    paths = {clip.lower().casefold() for clip in animation.clips}  # meshcat Path.lower() gives "/meshcat/bhgrasp/..."
    assert "/meshcat/bhgrasp/visuals/f3_distal_link_0" in paths  # hand links are animated
    assert "/meshcat/bhgrasp/visuals/object0" in paths and "/meshcat/bhgrasp/contacts/0/stick" in paths
    path = viewer.save_html(tmp_path / "replay.html")
    html = path.read_text()
    assert path.stat().st_size > 200_000  # the meshcat bundle is inlined
    assert not re.search(r"<script[^>]+src=", html)  # no external script: it works offline
    with pytest.raises(bh.InputError, match="fps"):
        viewer.replay(traj, fps=120)


def test_replays_loop_whether_or_not_they_start_playing(held, monkeypatch):
    """three.js stops a LoopRepeat action after `repetitions` passes (0 included): a replay asks for Infinity."""
    _, traj, viewer = held
    sent = []

    def record(visualizer, animation, **options):
        sent.append(options)

    monkeypatch.setattr(type(viewer.viewer), "set_animation", record)  # on the class: Visualizer has __slots__
    viewer.replay(traj, fps=30)
    viewer.replay(traj, fps=30, play=False)
    assert sent == [{"play": True, "repetitions": np.inf}, {"play": False, "repetitions": np.inf}]


def test_live_view_shows_every_nth_state_and_leaves_the_run_unchanged(held, monkeypatch):
    _, _, viewer = held
    shown = []
    real_display = viewer.display
    monkeypatch.setattr(viewer, "display", lambda state: (shown.append(state.t), real_display(state)))
    hold, other = reference_hold(), reference_hold()  # fresh simulators: contacts keep their stick anchors
    plain = hold.simulator.run(hold.controller, 0.05, state=hold.state, progress=False)
    live = other.simulator.run(LiveView(other.controller, viewer, every=10), 0.05, state=other.state, progress=False)
    np.testing.assert_array_equal(live.q, plain.q)
    np.testing.assert_allclose(shown, plain.t[:-1:10])  # the sensed states of calls 0, 10, 20, ...
    with pytest.raises(bh.InputError, match="every"):
        LiveView(hold.controller, viewer, every=0)


def test_a_mounted_hands_viewer_follows_the_wrist():
    """The viewer of a hand on a wrist mount draws its links where the scene's geometry is, mount moved and turned."""
    from bhgrasp.mount import mounted
    from bhgrasp.objects import Box
    from bhgrasp.sim.scene import Scene

    hand = mounted(bh.BarrettHand())
    box = Box(size=(0.05,) * 3, mass=0.1, pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.3])))
    scene = Scene(hand, [box])
    viewer = SceneViewer(scene)
    try:
        q = np.r_[0.1, -0.05, 0.2, 0.3, 0.1, -0.2, hand.neutral()[6:]]
        data, geometry_data = scene.model.createData(), pin.GeometryData(scene.geometry)
        pin.updateGeometryPlacements(scene.model, data, scene.geometry, geometry_data, np.r_[q, 0, 0, 0.3, 0, 0, 0, 1])
        shown = viewer.placements(q, [pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.3]))])
        assert len(shown) == len(geometry_data.oMg)
        for placement, truth in zip(shown, geometry_data.oMg):
            np.testing.assert_allclose(placement, truth.homogeneous, atol=1e-12)
    finally:
        viewer.close()
