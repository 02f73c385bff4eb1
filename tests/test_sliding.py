"""How far contacts slide (bhgrasp.grasp.metrics.sliding_distances) against finite differences and a dropped box."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from bhgrasp.grasp.metrics import sliding_distances, slip_events
from bhgrasp.scenarios.hold import reference_hold


@pytest.fixture(scope="module")
def holds():
    """The reference hold (8 N squeeze, mu 0.8: 6.4 N of friction) of a 0.2 kg and a 1 kg box, 0.3 s each."""
    runs = {}
    for mass in (0.2, 1.0):
        hold = reference_hold(box_mass=mass)
        runs[mass] = hold, hold.simulator.run(hold.controller, 0.3, state=hold.state, progress=False)
    return runs


def _moving_finger(hold, traj, sticking: np.ndarray):
    """``traj`` rewritten: F1 turns at 0.5 rad/s on every joint, the box stands still, and two points fixed on F1's
    distal link touch it each sample (``sticking``: (N, 2) their flags)."""
    hand, n = hold.hand, len(traj.t)
    velocity = np.full(hand.nv, 0.5)
    q = traj.q[0] + (traj.t - traj.t[0])[:, None] * velocity
    link = "F1_distal_link"
    local = [np.array([0.01, 0.0, 0.0]), np.array([0.02, 0.005, 0.0])]  # on the link [m]
    points = np.array([[hand.frame_placement(qk, link).act(p) for p in local] for qk in q])  # (N, 2, 3) world
    normal = np.array([0.0, 0.0, 1.0])
    pair = int(np.flatnonzero(traj.pair_bodies[:, 0] == link)[0])
    return (
        replace(
            traj,
            q=q,
            v=np.tile(velocity, (n, 1)),
            object_twist=np.zeros_like(traj.object_twist),
            object_position=np.repeat(traj.object_position[:1], n, axis=0),
            contact_offsets=2 * np.arange(n + 1),
            contact_pair=np.full(2 * n, pair),
            contact_point=points.reshape(-1, 3),
            contact_normal=np.tile(normal, (2 * n, 1)),
            contact_depth=np.zeros(2 * n),
            contact_force=np.zeros((2 * n, 3)),
            contact_sticking=sticking.reshape(-1),
        ),
        points,
        normal,
        link,
    )


def test_a_sliding_link_adds_the_tangential_path_of_its_fastest_point(holds):
    """Truth: the path length of each point's tangential motion by finite differences of its world position (no
    Jacobian); a link's two points count once (the faster), sticking points add nothing."""
    hold, traj = holds[0.2]
    n = len(traj.t)
    sticking = np.zeros((n, 2), dtype=bool)
    sticking[: n // 2, 1] = True  # the first half: only the nearer point slides
    sticking[n - n // 4 :] = True  # the last quarter: both stick
    moved, points, normal, link = _moving_finger(hold, traj, sticking)
    steps = np.diff(points, axis=0)  # (N-1, 2, 3)
    steps -= (steps @ normal)[..., None] * normal
    lengths = np.linalg.norm(steps, axis=2)  # tangential path per interval and point
    expected = np.sum(np.max(np.where(sticking[:-1], 0.0, lengths), axis=1))
    assert expected > 1e-3  # [m] a millimetre and more: a real path
    assert sliding_distances(hold.hand, moved)[link] == pytest.approx(expected, rel=1e-3)
    assert sliding_distances(hold.hand, moved, start_time=float(traj.t[-1])) == {}
    assert sliding_distances(hold.hand, replace(moved, contact_sticking=np.ones(2 * n, dtype=bool))) == {}


def test_a_box_that_slides_out_of_the_hold_slides_as_far_as_it_moves_against_the_fingertips(holds):
    """1 kg in 6.4 N of friction: it slides out, and each distal link's slide is within 15 % of how far the box's
    centre moved in that link's frame while it slid there (the box also turns a little); 0.2 kg: nothing slides."""
    hold, traj = holds[1.0]
    assert slip_events(hold.hand, traj) > 0 and sliding_distances(holds[0.2][0].hand, holds[0.2][1]) == {}
    slides = sliding_distances(hold.hand, traj)
    for link in ("F1_distal_link", "F2_distal_link", "F3_distal_link"):
        rows = np.arange(len(traj.contact_pair))
        sliding = (traj.pair_bodies[traj.contact_pair, 0] == link) & ~traj.contact_sticking
        samples = np.searchsorted(traj.contact_offsets, rows[sliding], side="right") - 1
        first, last = int(samples.min()), int(samples.max()) + 1

        placements = (hold.hand.frame_placement(traj.q[k], link) for k in (first, last))
        start, end = (pose.actInv(traj.object_position[k, 0]) for pose, k in zip(placements, (first, last)))
        moved = np.linalg.norm(end - start)
        assert moved > 0.02  # [m]
        assert slides[link] == pytest.approx(moved, rel=0.15)
