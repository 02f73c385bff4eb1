"""The BH8-280's drive inside the compiled step (src/barrett.cpp) against its Python rules (BarrettActuation's hooks).

The compiled Simulator runs a ``BarrettActuation``'s worm locks, gears, TorqueSwitch and per-mode drive in the same
C++ call as the step; a subclass runs the Python hooks (tests/scenes.py: PythonBarrettRules) on the same compiled
engine.  The truth is that Python model: every step's configuration, velocity, contact forces and modes must equal it
bit for bit, on the wrist-mounted hand of the grasp benchmark (six directly driven mount joints) as it closes on an
object, is pushed and re-opens, and on a bare hand without self-locking.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scenes import PythonBarrettRules

from bhgrasp.bench.objects import DEVELOPMENT_SET
from bhgrasp.bench.protocol import CLOSE_AT, Trial
from bhgrasp.bench.trial import BenchController, setup
from bhgrasp.errors import InputError
from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation


def twin(simulator: Simulator, actuation: BarrettActuation) -> Simulator:
    """``simulator``'s scene, step and contact law under the Python rules of an actuation like ``actuation``."""
    rules = PythonBarrettRules(
        simulator.scene.hand,
        breakaway_torque=actuation.breakaway_torque,
        saturate=actuation.saturate,
        motor_damping=actuation.motor_damping,
        damping=actuation.damping,
        friction=actuation.friction,
        efficiency=actuation.drive.efficiency,
        self_locking=actuation.self_locking,
    )
    return Simulator.from_settings(simulator.scene, simulator.settings, simulator.law, rules)


def assert_same_step(ours, theirs) -> None:
    (state, info), (truth, truth_info) = ours, theirs
    np.testing.assert_array_equal(state.scene_q, truth.scene_q)
    np.testing.assert_array_equal(state.scene_v, truth.scene_v)
    np.testing.assert_array_equal(state.actuation_modes, truth.actuation_modes)
    np.testing.assert_array_equal(info.contacts.force, truth_info.contacts.force)
    np.testing.assert_array_equal(info.drive_torques, truth_info.drive_torques)


def test_the_mounted_hand_closes_is_pushed_and_opens_as_the_python_rules_step_it() -> None:
    """The benchmark's box, closed by the driver at its grip, pushed (object forces and joint torques), re-opened."""
    trial = Trial(DEVELOPMENT_SET[0], "power")
    simulator, start, hand, path = setup(trial)
    assert type(simulator.actuation) is BarrettActuation and simulator.engine_name == "compiled"
    truth = twin(simulator, simulator.actuation)
    controllers = [BenchController(trial, hand, path) for _ in range(2)]
    opening = CLOSE_AT + 0.6
    for controller in controllers:
        controller.driver.script(
            [(0.0, "set_position_mode", "SPREAD"), (CLOSE_AT, "close", "GRASP"), (opening, "open", "GRASP")]
        )
        controller.reset(start)
    push = np.zeros((1, 3))
    push[0] = (2.0, -1.0, 0.5)  # [N] on the box
    kick = np.zeros(hand.nv)
    kick[hand.joint_index("F3_distal")] = 0.05  # [N m]
    states, seen = [start, start], set()
    for _ in range(round((opening + 0.5) / simulator.dt)):
        t = states[0].t
        forces = push if 1.2 <= t < 1.3 else None
        disturbance = kick if 1.3 <= t < 1.4 else None
        steps = [
            sim.step(state, controller(t, state), disturbance, forces)
            for sim, state, controller in zip((simulator, truth), states, controllers)
        ]
        assert_same_step(*steps)
        states = [step[0] for step in steps]
        seen.update(enumerate(states[0].actuation_modes.tolist()))
    assert {mode for k, mode in seen if k < 3} == {0.0, 1.0, 2.0}  # armed, broken away, re-opening ...
    assert {mode for k, mode in seen if k >= 3} == {0.0, 1.0}  # ... the worms locked and unlocked
    assert not states[0].actuation_modes.flags.writeable  # one read-only array per combination, shared by states
    np.testing.assert_array_equal(states[0].actuation_modes, simulator.actuation.modes())


@pytest.mark.parametrize("self_locking", [True, False])
def test_a_bare_hand_follows_the_python_rules_and_their_parameters_as_they_change(self_locking: bool) -> None:
    """Closing over the limit (clipped), opening; the breakaway torque and saturation changed between steps."""
    scenario = box_grasp(mass=0.3, actuation="barrett")
    actuation = BarrettActuation(scenario.hand, damping=0.01, friction=0.002, self_locking=self_locking)
    simulator = Simulator(
        scenario.simulator.scene, dt=scenario.simulator.dt, contact=scenario.simulator.law, actuation=actuation
    )
    truth = twin(simulator, actuation)
    start = simulator.initial_state(scenario.q_start)
    close, opening = np.array([0.02, 0.11, 0.11, 0.11]), np.array([0.0, -0.11, -0.11, -0.11])
    states = [start, start]
    for k in range(2400):
        if k == 300:  # a weaker clutch on both, and the pucks' clip
            for model in (actuation, truth.actuation):
                model.drive.breakaway_torque, model.saturate = 0.2, True
        if k == 1800:  # the worms' self-locking switched (the modes then have the other length)
            for model in (actuation, truth.actuation):
                model.drive.self_locking = not self_locking
        u = 1.3 * (close if k < 1400 else opening)
        steps = [sim.step(state, u) for sim, state in zip((simulator, truth), states)]
        assert_same_step(*steps)
        states = [step[0] for step in steps]
    assert len(states[0].actuation_modes) == (3 if self_locking else 6)


@pytest.mark.parametrize("self_locking", [True, False])
@pytest.mark.parametrize("flags", [[1, 0, 0, 1, 0, 1], (2.0, 0.0, 1.0), np.array([0.0, 1.0, 0.0, 0.0, 1.0, 0.0])])
def test_a_state_brings_its_modes_as_the_python_rules_take_them(self_locking: bool, flags) -> None:
    """Any switch and lock a state carries, as a list, tuple or array (a hand without self-locking ignores the locks:
    its worms hold nothing), as the Python rules take them."""
    scenario = box_grasp(mass=0.3, actuation="barrett")
    actuation = BarrettActuation(scenario.hand, self_locking=self_locking)
    simulator = Simulator(
        scenario.simulator.scene, dt=scenario.simulator.dt, contact=scenario.simulator.law, actuation=actuation
    )
    truth = twin(simulator, actuation)
    start = dataclasses.replace(simulator.initial_state(scenario.q_start), actuation_modes=flags)
    states = [start, start]
    for _ in range(300):
        steps = [sim.step(state, np.array([0.01, 0.02, 0.02, 0.02])) for sim, state in zip((simulator, truth), states)]
        assert_same_step(*steps)
        states = [step[0] for step in steps]


def test_a_state_with_impossible_modes_is_refused_by_name_on_either_drive() -> None:
    scenario = box_grasp(mass=0.3, actuation="barrett")
    simulator = scenario.simulator
    assert type(simulator.actuation) is BarrettActuation
    state = simulator.initial_state(scenario.q_start)
    for stepper in (simulator, twin(simulator, simulator.actuation)):
        for modes in ([3.0, 0.0, 0.0], [0.0, np.nan, 0.0, 0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], [1]):
            bad = dataclasses.replace(state, actuation_modes=np.array(modes))
            with pytest.raises(InputError, match="Barrett modes must be 3 TorqueSwitch values"):
                stepper.step(bad, np.zeros(4))
        with pytest.raises(InputError, match="Barrett modes must be numbers"):
            stepper.step(dataclasses.replace(state, actuation_modes=["armed", 0, 0]), np.zeros(4))
