"""How far contacts slide (bhgrasp.grasp.metrics.sliding_distances) against finite differences and a dropped box."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
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


def _rewritten(traj, hand, velocity, object_motion, sticking: np.ndarray):
    """``traj`` rewritten: every joint of ``hand`` turns at ``velocity`` [rad/s], the box moves by ``object_motion``
    = (v [m/s], w [rad/s]) from its first pose (a constant twist at its origin), and two points fixed on F1's distal
    link touch it each sample (``sticking``: (N, 2) their flags).  Returns it, the points (N, 2, 3) and the box's
    poses (N)."""
    n, link = len(traj.t), "F1_distal_link"
    elapsed = traj.t - traj.t[0]
    q = traj.q[0] + elapsed[:, None] * velocity
    local = [np.array([0.01, 0.0, 0.0]), np.array([0.02, 0.005, 0.0])]  # on the link [m]
    points = np.array([[hand.frame_placement(qk, link).act(p) for p in local] for qk in q])  # (N, 2, 3) world
    linear, angular = (np.asarray(part, dtype=float) for part in object_motion)
    start = traj.object_position[0, 0]
    poses = [pin.SE3(pin.exp3(angular * dt), start + linear * dt) for dt in elapsed]  # world-aligned twist
    quaternions = np.array([pin.Quaternion(pose.rotation).coeffs() for pose in poses])  # (x, y, z, w)
    pair = int(np.flatnonzero(traj.pair_bodies[:, 0] == link)[0])
    rewritten = replace(
        traj,
        q=q,
        v=np.tile(velocity, (n, 1)),
        object_twist=np.tile(np.concatenate((linear, angular)), (n, 1))[:, None],
        object_position=np.array([pose.translation for pose in poses])[:, None],
        object_quaternion=quaternions[:, None],
        contact_offsets=2 * np.arange(n + 1),
        contact_pair=np.full(2 * n, pair),
        contact_point=points.reshape(-1, 3),
        contact_normal=np.tile(NORMAL, (2 * n, 1)),
        contact_depth=np.zeros(2 * n),
        contact_force=np.zeros((2 * n, 3)),
        contact_sticking=sticking.reshape(-1),
    )
    return rewritten, points, poses


NORMAL = np.array([0.0, 0.0, 1.0])


def _expected(points: np.ndarray, poses, sticking: np.ndarray, first: int = 1) -> float:
    """Truth by finite differences, no Jacobian: each interval (k-1, k), how far each point moved against the box's
    material point under it (the box's motion carried from the pose at k-1 to the pose at k), tangentially; the
    faster of the two sliding points, summed from sample ``first``."""
    total = 0.0
    for k in range(first, len(points)):
        carried = poses[k] * poses[k - 1].inverse()  # the box's material points from k-1 to k
        moves = [points[k, i] - carried.act(points[k - 1, i]) for i in range(2)]
        lengths = [np.linalg.norm(m - (m @ NORMAL) * NORMAL) for m in moves]
        total += max((length for length, stuck in zip(lengths, sticking[k]) if not stuck), default=0.0)
    return total


@pytest.mark.parametrize(
    ("placed", "object_motion"),
    [
        (False, ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))),  # a still box
        (False, ((0.01, -0.02, 0.005), (0.0, 0.0, 2.0))),  # the box moves and spins under the link
        (True, ((0.01, 0.0, 0.0), (0.5, -1.0, 0.0))),  # and the hand's base placed off the world's origin
    ],
    ids=["still box", "moving box", "placed base"],
)
def test_a_sliding_link_adds_the_tangential_path_of_its_fastest_point(holds, placed, object_motion):
    """Against finite differences of the link points and the box's material points (no Jacobian): a link's two
    points count once (the faster), sticking points add nothing, ``start_time`` counts from its sample."""
    traj = holds[0.2][1]
    hand = bh.BarrettHand()
    if placed:
        hand.base_placement = pin.SE3(pin.exp3(np.array([0.2, -0.3, 0.5])), np.array([0.1, -0.05, 0.3]))
    n = len(traj.t)
    sticking = np.zeros((n, 2), dtype=bool)
    sticking[: n // 2, 1] = True  # the first half: only the nearer point slides
    sticking[n - n // 4 :] = True  # the last quarter: both stick
    moved, points, poses = _rewritten(traj, hand, np.full(hand.nv, 0.5), object_motion, sticking)
    expected = _expected(points, poses, sticking)
    assert expected > 1e-3  # [m] a millimetre and more: a real path
    assert sliding_distances(hand, moved)["F1_distal_link"] == pytest.approx(expected, rel=2e-3)
    middle = n // 3
    later = sliding_distances(hand, moved, start_time=float(traj.t[middle]))["F1_distal_link"]
    assert later == pytest.approx(_expected(points, poses, sticking, first=middle), rel=2e-3)
    assert sliding_distances(hand, replace(moved, contact_sticking=np.ones(2 * n, dtype=bool))) == {}
    with pytest.raises(bh.InputError, match="start_time"):
        sliding_distances(hand, moved, start_time=float("nan"))


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
