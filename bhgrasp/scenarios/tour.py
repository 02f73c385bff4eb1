"""The tour of the hand (``bhgrasp tour``): fingertips at a tripod pose and IK back, the workspace, a held box."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np

from bhgrasp.model.hand import Hand
from bhgrasp.model.ik import finger_ik, workspace


def tripod_lines(hand: Hand) -> list[str]:
    """Each fingertip's position in frame W at a tripod pose, and F3's closed-form IK back from its tip.

    The pose: spread 60 deg, proximal joints 1 rad; the IK must give back the pose's joint angles.
    """
    q = hand.configuration(F1_spread=np.pi / 3, F1_proximal=1.0, F2_proximal=1.0, F3_proximal=1.0)
    lines = ["fingertip positions [m] in frame W at a tripod pose (spread 60 deg, proximal 57.3 deg):"]
    for finger, position in zip(hand.fingers, hand.fingertip_positions(q)):
        lines.append(f"  {finger}: {np.array2string(position, precision=4, floatmode='fixed', suppress_small=True)}")
    solution = finger_ik(hand, "F3", hand.fingertip_positions(q)[2])
    lines.append(f"closed-form IK of F3 back from that point: {np.round(solution.angles, 6)} rad")
    return lines


def workspace_figure(hand: Hand, samples: int, seed: int):
    """The tour's workspace figure (:func:`bhgrasp.plots.workspace_figure`) of ``samples`` seeded tips per finger."""
    from bhgrasp.plots import workspace_figure as draw

    points = {finger: workspace(hand, finger, samples, rng=seed).points for finger in hand.fingers}
    return draw(points, f"Barrett BH8-280 fingertip workspace ({samples} samples per finger, seed {seed})")


def save_workspace_figure(hand: Hand, output: Path, samples: int, seed: int) -> Path:
    """:func:`workspace_figure` written to ``output/workspace.png`` (the folder made if needed)."""
    output.mkdir(parents=True, exist_ok=True)
    path = output / "workspace.png"
    workspace_figure(hand, samples, seed).savefig(path, dpi=120)
    return path


def hold_lines(duration: float) -> Iterator[str]:
    """Simulate the reference three-finger hold for ``duration`` [s], as lines to print.

    First a line saying so (before it runs), then its contacts at the end, and the box's sag and creep.
    """
    from bhgrasp.scenarios.hold import BOX_MASS, reference_hold

    yield f"simulating a {duration:g} s three-finger hold of a {BOX_MASS} kg box (implicit contacts, dt 2 ms) ..."
    hold = reference_hold(dt=2e-3)
    trajectory = hold.simulator.run(hold.controller, duration, state=hold.state, progress=False)
    last = trajectory.contacts_at(len(trajectory) - 1)
    for (link, _), force, sticking in zip(last["bodies"], last["force"], last["sticking"]):
        state = "sticks" if sticking else "slides"
        yield f"  {link:<16} force on box {np.array2string(force, precision=3, suppress_small=True)} N, {state}"
    position = trajectory.object_position[:, 0]
    half = len(position) // 2
    creep = np.linalg.norm(position[-1] - position[half]) / (trajectory.t[-1] - trajectory.t[half])
    yield f"  box sag {1e3 * (hold.box_height - position[-1, 2]):.3f} mm, creep {creep * 1e6:.3g} um/s"


__all__ = ["hold_lines", "save_workspace_figure", "tripod_lines", "workspace_figure"]
