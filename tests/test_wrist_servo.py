"""The wrist servo's compiled engine (src/wrist_servo.cpp) against its Python twin (MountServo on the pose path).

The truth is the Python servo: its MountReference of a PosePath (held or not), the nominal hand's inverse dynamics and
the PD.  The compiled servo must give the same torques, reference and error to round-off (measured: 1.6e-15 of the
largest torque) on random mounts, paths, states and holds, with the fingers zero or held, and the same closed loop.
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.bench.objects import DEVELOPMENT_SET
from bhgrasp.bench.protocol import Trial
from bhgrasp.bench.reach import FLIP
from bhgrasp.bench.trial import setup
from bhgrasp.controllers.mount import MountServo
from bhgrasp.data import State
from bhgrasp.errors import FrozenSettingError, InputError
from bhgrasp.model.mount import mounted
from bhgrasp.motion.held import HeldReference
from bhgrasp.motion.pose_references import PoseMotion, PosePath
from bhgrasp.motion.trajectories import Quintic
from bhgrasp.motion.wrist import MountReference

ROUND_OFF = 1e-13  # of the largest torque (measured: 1.2e-15 here, 4.5e-16 on the benchmark's paths)


def random_path(rng: np.random.Generator):
    """A mounted hand placed anywhere and a path of three moves and a pause from a pose near its base.

    The base turned by at most 2.5 rad: near a half turn the pose's rotation vector (the sample's log R, which both
    engines take back through exp) is ill-conditioned, and the engines' round-off grows there (4e-12 rad in the
    mount's angles 0.02 rad from pi); the benchmark's half-turned hands are tested below, with their own paths.
    """
    axis = rng.normal(size=3)
    base = pin.SE3(pin.exp3(axis / np.linalg.norm(axis) * rng.uniform(0.0, 2.5)), rng.normal(size=3) * 0.3)
    hand = mounted(bh.BarrettHand(base_placement=base))
    moves = [(np.r_[rng.normal(size=3) * 0.05, rng.normal(size=3) * 0.3], 0.5 + rng.random()) for _ in range(3)]
    moves.insert(1, (np.zeros(6), 0.3))
    start = base * pin.SE3(pin.exp3(rng.normal(size=3) * 0.2), rng.normal(size=3) * 0.02)
    return hand, MountReference(PosePath(start, moves, delay=0.1), hand.base_placement)


def random_state(hand: bh.Hand, rng: np.random.Generator) -> State:
    q = hand.neutral()
    q[:6] = rng.normal(size=6) * 0.1
    q[6:] += rng.random(hand.nq - 6) * 0.5
    return State(t=0.0, q=q, v=rng.normal(size=hand.nv))


def servos(hand: bh.Hand, reference, fingers) -> tuple[MountServo, MountServo]:
    both = [
        MountServo(hand, reference(), fingers=fingers, compensate_load=False, engine=engine)
        for engine in ("compiled", "python")
    ]
    assert [servo.engine for servo in both] == ["compiled", "python"]
    return both[0], both[1]


@pytest.mark.parametrize("fingers", ["zero", None])
def test_the_compiled_servo_is_its_python_twin_to_round_off(fingers) -> None:
    rng = np.random.default_rng(7)
    for _ in range(6):
        hand, path = random_path(rng)
        compiled, python = servos(hand, lambda path=path: HeldReference(path), fingers)
        for k in range(120):
            t = float(rng.uniform(-0.2, 3.5))
            if k == 90:  # the path stops here (the benchmark's guarded place); before, after and at the hold
                for servo in (compiled, python):
                    servo.reference.hold(t)
            state = random_state(hand, rng)
            ours, truth = compiled(t, state), python(t, state)
            scale = np.abs(truth).max()
            np.testing.assert_allclose(ours, truth, rtol=0, atol=ROUND_OFF * scale)
            for key in ("mount_reference", "mount_error"):  # [m, rad] (measured: 1.1e-14)
                np.testing.assert_allclose(compiled.log[key], python.log[key], rtol=0, atol=1e-13)
            if fingers is None:  # the fingers held where the first call found them
                assert np.any(ours[6:] != 0.0)
            else:
                assert not ours[6:].any()
        c, c_dot, c_dd = compiled._compiled.reference(1.3)
        truth = python.reference(1.3)
        for a, b in zip((c, c_dot, c_dd), truth):
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-13 * max(1.0, np.abs(b).max()))


def test_a_lone_pose_motion_and_a_reset_finger_hold_agree() -> None:
    rng = np.random.default_rng(3)
    hand, _ = random_path(rng)
    motion = PoseMotion(hand.base_placement, [0.0, 0.02, 0.05, 0.1, 0.0, -0.2], 0.8, delay=0.2)
    compiled, python = servos(hand, lambda: MountReference(motion, hand.base_placement), None)
    for k in range(40):
        state = random_state(hand, rng)
        if k == 20:
            compiled.reset(state)
            python.reset(state)
        t = 0.05 * k
        np.testing.assert_allclose(compiled(t, state), python(t, state), rtol=0, atol=ROUND_OFF * 2e3)


@pytest.mark.parametrize("heading", [0.0, 0.7, -2.5])
def test_the_benchmarks_half_turned_hand_on_its_paths_agrees_to_round_off(heading: float) -> None:
    """Palm down (a half turn, FLIP), turned by a heading as among neighbours; the wrist's moves are translations."""
    base = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, heading) @ FLIP, np.array([0.1, 0.2, 0.3]))
    hand = mounted(bh.BarrettHand(base_placement=base))
    moves = [(np.array([0.03, -0.02, -0.05, 0, 0, 0]), 1.0), (np.zeros(6), 2.0), (np.array([0, 0, 0.1, 0, 0, 0]), 1.0)]
    path = MountReference(PosePath(base, moves), hand.base_placement)
    compiled, python = servos(hand, lambda: HeldReference(path), "zero")
    rng = np.random.default_rng(2)
    for k in range(200):
        state = random_state(hand, rng)
        t = 0.022 * k
        truth = python(t, state)
        np.testing.assert_allclose(compiled(t, state), truth, rtol=0, atol=ROUND_OFF * np.abs(truth).max())


def test_the_benchmark_trial_runs_the_same_on_either_servo() -> None:
    """One second of the benchmark's wrist approach and close, the whole loop on each engine."""
    trial = Trial(DEVELOPMENT_SET[0], "power")
    simulator, start, hand, path = setup(trial)
    runs = []
    for engine in ("compiled", "python"):
        servo = MountServo(hand, HeldReference(path), fingers="zero", compensate_load=False, engine=engine)
        servo.reset(start)
        state = start
        for _ in range(2000):
            u = np.zeros(simulator.actuation.n_inputs)
            u[4:] = servo(state.t, state)[:6]
            state, _ = simulator.step(state, u)
        runs.append(state)
    np.testing.assert_allclose(runs[0].scene_q, runs[1].scene_q, rtol=0, atol=1e-12)
    c_d = path(runs[0].t)[0]
    assert np.linalg.norm(runs[0].scene_q[:3] - start.scene_q[:3]) > 0.02  # the wrist moved on its approach ...
    assert np.linalg.norm(runs[0].scene_q[:3] - c_d[:3]) < 1e-3  # ... as the path asks


def test_the_engines_cover_what_they_say_and_copies_keep_theirs() -> None:
    hand, path = random_path(np.random.default_rng(5))
    assert MountServo(hand, path).engine == "python"  # load feedforward: Python's
    assert MountServo(hand, path, compensate_load=False).engine == "compiled"
    assert MountServo(hand, Quintic(np.zeros(6), np.ones(6) * 0.01, 1.0), compensate_load=False).engine == "python"
    with pytest.raises(InputError, match="does not cover .*compensate_load=True"):
        MountServo(hand, path, engine="compiled")
    with pytest.raises(InputError, match="does not cover .*a finger controller"):
        MountServo(hand, path, fingers=lambda t, s: np.zeros(hand.nv), compensate_load=False, engine="compiled")
    with pytest.raises(InputError, match="`fingers` must be a controller"):
        MountServo(hand, path, fingers="free")
    rng = np.random.default_rng(6)
    for engine in ("compiled", "python"):  # a copy made mid-run holds the fingers where the original holds them
        servo = MountServo(hand, HeldReference(path), compensate_load=False, engine=engine)
        servo(0.4, random_state(hand, rng))
        later = random_state(hand, rng)
        for twin in (copy.deepcopy(servo), pickle.loads(pickle.dumps(servo))):
            assert twin.engine == engine
            np.testing.assert_array_equal(twin(0.5, later), servo(0.5, later))
    with pytest.raises(InputError, match="`t` must be a finite"):
        servo(float("nan"), later)


def test_a_servo_and_its_path_are_fixed_once_built() -> None:
    """Both engines read the set-up given when built (the compiled one copied it; the path keeps its last sample)."""
    hand, path = random_path(np.random.default_rng(8))
    servo = MountServo(hand, path, compensate_load=False)
    with pytest.raises(FrozenSettingError, match="MountServo.kp cannot change"):
        servo.kp = np.ones(6)
    with pytest.raises(ValueError, match="read-only"):
        servo.kd[0] = 1.0
    motion = path.pose.segments[0]
    with pytest.raises(ValueError, match="read-only"):
        motion.offset[0] = 1.0
    with pytest.raises(AttributeError):
        path.origin = pin.SE3.Identity()
    moved = motion.start
    moved.translation[:] = 9.0  # a copy
    assert not np.allclose(motion.start.translation, 9.0)
