"""When each finger starts to close in a benchmark trial: so that the three touch the object together.

Where the placement puts a round object's axis where F1's and F2's closing planes meet
(:func:`~bhgrasp.bench.placement.grasp_offset`), F3 is the nearer finger.  Closing all three at once, F3 touched the
development set's ball, large ball and can 0.42-0.50 s before F1 and F2 and pushed each 15-19 mm towards them, off
the planes, where the grasp closed with F3 pressing up to twice what F1 and F2 did.  Started later by the time F1
needs to close the difference of their touch angles, all three arrive together: the objects moved 0.4-2.6 mm and the
three fingers pressed within 20 % of each other.  Elsewhere (boxes, spreads whose planes do not meet) the placement
has them arrive together already, and all start at once, with libbarrett's ``close()`` of the whole grasp.

The time a finger takes to close to an angle comes from an unloaded close of the real drive (its pucks at
:data:`~bhgrasp.bench.protocol.GRIP_MT`, the pre-shape, the step, the hand palm down), simulated once per process.
The idealised hand (``actuation="full"``) closes with constant torques of its own and starts all fingers at once.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pinocchio as pin

import bhgrasp as bh
from bhgrasp.barrett.commands import BarrettDriver
from bhgrasp.barrett.pucks import FINGER_PUCK
from bhgrasp.bench.placement import closing_planes_meet, touch_angles
from bhgrasp.bench.protocol import DT, GRIP_MT, PRESHAPE, Trial
from bhgrasp.bench.side import approach_of, top_grasp
from bhgrasp.errors import ModelError
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation
from bhgrasp.sim.scene import Scene

CLOSE_SPAN = 3.0  # [s] of the unloaded close: at GRIP_MT it closes at ~0.65 rad/s and stalls on its stops in ~2.5 s


@functools.lru_cache(maxsize=4)
def close_profile(opening: float = PRESHAPE) -> tuple[np.ndarray, np.ndarray]:
    """(times [s], F1's proximal angle [rad]) of an unloaded close from ``opening`` [rad], as the benchmark closes.

    The BH8-280 palm down (the trial's orientation), its finger pucks at GRIP_MT, libbarrett's ``close()`` at
    t = 0; up to where the angle stops rising (the finger stalls on its stop), read-only.
    """
    hand = bh.BarrettHand(base_placement=pin.SE3(pin.rpy.rpyToMatrix(math.pi, 0.0, 0.0), np.zeros(3)))
    simulator = Simulator(Scene(hand), dt=DT, actuation=BarrettActuation(hand, saturate=True))
    driver = BarrettDriver(hand, finger=FINGER_PUCK.with_(MT=GRIP_MT))
    driver.script([(0.0, "close", "GRASP")])
    q = hand.neutral()
    for finger in hand.fingers:
        q[hand.joint_index(f"{finger}_proximal")], q[hand.joint_index(f"{finger}_distal")] = opening, opening / 3
    trajectory = simulator.run(driver, CLOSE_SPAN, state=simulator.initial_state(q), progress=False, record_every=4)
    angle = np.maximum.accumulate(trajectory.q[:, hand.joint_index("F1_proximal")])
    stop = int(np.argmax(angle)) + 1  # up to where it stalls
    if angle[stop - 1] - angle[0] < 1.0:
        raise ModelError(
            f"the unloaded close reached only {angle[stop - 1]:.2f} rad from {angle[0]:.2f} in {CLOSE_SPAN} s; "
            "a profile of at least 1 rad was expected"
        )
    times, angles = trajectory.t[:stop].copy(), angle[:stop].copy()
    times.setflags(write=False)
    angles.setflags(write=False)
    return times, angles


def close_time(angle: float, opening: float = PRESHAPE) -> float:
    """The time [s] an unloaded finger takes to close from ``opening`` to proximal ``angle`` [rad]."""
    times, angles = close_profile(opening)
    return float(np.interp(angle, angles, times))


def finger_starts(trial: Trial) -> dict[str, float]:
    """Each finger's start [s] after the close command, ``{"F1": ..., "F2": ..., "F3": ...}``.

    On the closing planes (a round object, :func:`~bhgrasp.bench.placement.closing_planes_meet`): the finger that
    needs the longest to reach its touch angle starts at 0, the others later by the difference, F2 with F1 (the
    spread mirrors them about the object's plane of symmetry).  Otherwise (a box, a side pinch), and for the idealised
    hand, all 0.
    """
    item, spread = trial.item, trial.preshape_spread
    side = approach_of(trial) == "side"  # F1 and F2 mirror each other across the object
    if side or trial.actuation != "barrett" or item.kind == "box" or closing_planes_meet(spread) is None:
        return dict.fromkeys(("F1", "F2", "F3"), 0.0)
    opening, clearance = top_grasp(trial)
    angles = touch_angles(item, spread, clearance, opening)
    needs = {finger: close_time(angles[finger], opening) for finger in ("F1", "F3")}
    last = max(needs.values())
    return {"F1": last - needs["F1"], "F2": last - needs["F1"], "F3": last - needs["F3"]}


__all__ = ["CLOSE_SPAN", "close_profile", "close_time", "finger_starts"]
