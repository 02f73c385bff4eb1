"""Cost of the Hand wrapper against raw Pinocchio calls, and of closed-form IK against DLS, measured in one run.

Prints microseconds per call and the ratio to the baseline measured in the same process (machines are noisy:
compare ratios, not absolute times).  Usage: ``python benchmarks/bench_hand.py [--repeat N]``.
"""

from __future__ import annotations

import argparse
import platform
import time
from collections.abc import Callable

import numpy as np
import pinocchio as pin

import bhgrasp as bh


def per_call_us(function: Callable[[], object], repeat: int) -> float:
    """Best of 5 batches of ``repeat`` calls, in microseconds per call."""
    best = np.inf
    for _ in range(5):
        start = time.perf_counter()
        for _ in range(repeat):
            function()
        best = min(best, (time.perf_counter() - start) / repeat)
    return best * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=20_000)
    repeat = parser.parse_args().repeat

    hand = bh.BarrettHand()
    model, data = hand.model, hand.model.createData()
    rng = np.random.default_rng(0)
    q, v, tau = hand.random_configuration(rng), rng.normal(size=8), rng.normal(size=8)
    tip = model.getFrameId("F3_tip")

    def raw_jacobian() -> np.ndarray:
        return pin.computeFrameJacobian(model, data, q, tip, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:3]

    def raw_tips() -> np.ndarray:
        pin.framesForwardKinematics(model, data, q)
        return np.array([data.oMf[model.getFrameId(f"F{i}_tip")].translation for i in (1, 2, 3)])

    pairs = [
        ("mass_matrix (CRBA)", lambda: hand.mass_matrix(q), lambda: pin.crba(model, data, q)),
        ("forward_dynamics (ABA)", lambda: hand.forward_dynamics(q, v, tau), lambda: pin.aba(model, data, q, v, tau)),
        (
            "inverse_dynamics (RNEA)",
            lambda: hand.inverse_dynamics(q, v, tau),
            lambda: pin.rnea(model, data, q, v, tau),
        ),
        ("gravity_torques", lambda: hand.gravity_torques(q), lambda: pin.computeGeneralizedGravity(model, data, q)),
        ("fingertip_jacobian", lambda: hand.fingertip_jacobian(q, "F3"), raw_jacobian),
        ("fingertip_positions", lambda: hand.fingertip_positions(q), raw_tips),
    ]
    print(f"machine: {platform.machine()} {platform.processor() or ''} python {platform.python_version()}")
    print(f"pinocchio {pin.__version__}, {repeat} calls x best of 5\n")
    print(f"{'call':<26}{'bhgrasp [us]':>14}{'raw pin [us]':>14}{'ratio':>8}")
    for name, wrapped, raw in pairs:
        ours, base = per_call_us(wrapped, repeat), per_call_us(raw, repeat)
        print(f"{name:<26}{ours:14.2f}{base:14.2f}{ours / base:8.2f}")

    targets = dict(zip(hand.fingers, hand.fingertip_positions(q)))
    closed = per_call_us(lambda: [bh.finger_ik(hand, f, p) for f, p in targets.items()], max(repeat // 100, 10))
    numeric = per_call_us(lambda: bh.ik(hand, targets, restarts=30, rng=0), max(repeat // 1000, 3))
    print(f"\n{'IK, 3 fingers':<26}{'closed [us]':>14}{'DLS [us]':>14}{'DLS/closed':>11}")
    print(f"{'':<26}{closed:14.1f}{numeric:14.1f}{numeric / closed:11.1f}")


if __name__ == "__main__":
    main()
