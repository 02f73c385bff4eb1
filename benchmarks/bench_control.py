"""Cost of one control-law evaluation against one raw Pinocchio RNEA call, measured in the same run.

Each controller runs on the Barrett hand (8 joints) with a nominal model; the baseline is ``pin.rnea`` (what an
ideal computed-torque law costs at least).  Prints microseconds per call and the ratio to the baseline (compare
ratios, not absolute times: machines are noisy).  Usage: ``python benchmarks/bench_control.py [--repeat N]``.
"""

from __future__ import annotations

import argparse
import platform

import numpy as np
import pinocchio as pin
from bench_hand import per_call_us

import bhgrasp as bh
from bhgrasp.controllers import AdaptiveSlidingMode, ComputedTorque, GraspForceController, PDGravity, SlidingMode, hosm
from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
from bhgrasp.controllers.object_space import ObjectSpaceController
from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.model.objects import Box
from bhgrasp.motion.trajectories import Sinusoid
from bhgrasp.scenarios.box_grasp import box_grasp


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=5_000)
    repeat = parser.parse_args().repeat
    hand = bh.BarrettHand()
    nominal = hand.perturbed(0.7)
    rng = np.random.default_rng(0)
    q = hand.configuration(F1_proximal=0.6, F2_proximal=0.6, F3_proximal=0.6)
    state = bh.State(0.5, q, rng.normal(size=8))
    reference = Sinusoid(q, 0.1, 1.0)
    model, data = hand.model, hand.model.createData()
    baseline = per_call_us(lambda: pin.rnea(model, data, q, state.v, state.v), repeat)
    controllers = {
        "PD + gravity": PDGravity(nominal, reference),
        "computed torque": ComputedTorque(nominal, reference),
        "SMC": SlidingMode(nominal, reference),
        "ASMC (80 parameters)": AdaptiveSlidingMode(nominal, reference),
        "HOSM A": hosm("A", nominal, reference),
        "HOSM C (super-twisting)": hosm("C", nominal, reference),
        "HOSMA C": hosm("C", nominal, reference, adaptive=True),
    }
    print(f"{platform.processor() or platform.machine()}, Python {platform.python_version()}, pin {pin.__version__}")
    print(f"baseline pin.rnea: {baseline:.2f} us")
    print(f"{'controller':<26}{'us/call':>10}{'x rnea':>9}{'max rate [kHz]':>16}")
    for name, controller in controllers.items():
        controller.reset(state)
        cost = per_call_us(lambda c=controller: c(0.5, state), repeat)
        print(f"{name:<26}{cost:10.1f}{cost / baseline:9.1f}{1e3 / cost:16.1f}")
    grasp_controllers(baseline, max(repeat // 20, 5))


def grasp_controllers(baseline: float, repeat: int) -> None:
    """Object-space grasp laws on a grasped state of the chapter-5 box (3 finger contacts, QP forces)."""
    setup = box_grasp(mass=0.6)
    captured = {}

    def capture(t, sensed):
        if t >= 1.0 and "state" not in captured:
            captured["state"] = sensed
        return supervisor(t, sensed)

    supervisor = GraspSupervisor(
        setup.hand, setup.q_contact, SMCAdaptiveGrasp(setup.hand, Box(size=setup.box.size, mass=0.6))
    )
    setup.simulator.run(capture, 1.01, state=setup.state, progress=False)
    state = captured["state"]
    laws = {
        "grasp PD + QP": GraspForceController(setup.hand, 0.6),
        "object CTC (5.32) + QP": ObjectSpaceController(setup.hand, Box(size=setup.box.size, mass=0.6), "ctc"),
        "SMC-adaptive (5.58) + QP": SMCAdaptiveGrasp(setup.hand, Box(size=setup.box.size, mass=0.6)),
    }
    print(f"grasp laws on a held box ({len(state.contact_points)} contact points, 3 fingers):")
    for name, law in laws.items():
        law.reset(state)
        law(1.0, state)  # builds the QP once (the cold solve is benchmarked in bench_qp.py)
        cost = per_call_us(lambda c=law: c(1.0, state), repeat)
        print(f"{name:<26}{cost:10.1f}{cost / baseline:9.1f}{1e3 / cost:16.1f}")


if __name__ == "__main__":
    main()
