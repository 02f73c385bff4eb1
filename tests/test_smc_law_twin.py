"""The compiled SMC-adaptive law (``src/smc_law.cpp``) against its Python twin, state by state.

The grasp demo's scene (the Barrett hand lifts and turns a 0.6 kg box, the law told 0.3 kg) is simulated once and
every sensed state is fed to a compiled and a Python :class:`SMCAdaptiveGrasp`, each with its own internal state
(estimate, force integrals, QP warm starts, hold pose, clock): bare laws through the approach branch, the grasp
transition, the hold and a reset; laws under a :class:`GraspSupervisor` through its reset and the moving
reference; fingers letting go (another contact count, infeasible QPs, lost integrals).  Torques and every log
entry must agree to 1e-9 relative, to the largest value the entry takes over the run (the wrench's for the wrench
residual, itself round-off); measured: < 2e-15, NumPy's and Eigen's sums round differently.  Integer-valued
entries (contacts, QP iterations, feasibility) must be equal.
"""

from __future__ import annotations

import copy
import pickle
import sys
from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp
from bhgrasp import _native
from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
from bhgrasp.controllers.grasp_options import GraspOptions
from bhgrasp.controllers.object_identification import ObjectIdentification
from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.errors import CompiledEngineUnavailable, InputError
from bhgrasp.model.objects import Box
from bhgrasp.motion.pose_references import PoseMotion
from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.scenarios.demo_result import MU_ASSUMED
from bhgrasp.scenarios.grasp_controllers import SQUEEZE
from bhgrasp.scenarios.grasp_demo import OFFSET
from bhgrasp.sim.compiled import core_module

DEMO = GraspOptions(mu=MU_ASSUMED, squeeze=SQUEEZE)  # the demo's shared options
PINV = GraspOptions(distribution="pinv")

pytest.importorskip("bhgrasp._core")

TOLERANCE = 1e-9
EXACT = ("contacts", "qp_iterations", "feasible", "infeasible_cycles", "phase", "arrived")
SCALE_OF = {"wrench_residual": "wrench"}  # |G f - w| is round-off of the QP's solve (<= 4e-10 N): scaled by |w|


def smc(setup, engine, **options):
    """The demo's SMC-adaptive law (told 0.3 kg) on ``engine``."""
    box = Box(size=setup.box.size, mass=0.3)
    return SMCAdaptiveGrasp(setup.hand, box, options=DEMO, engine=engine, **options)


@pytest.fixture(scope="module")
def run():
    """The demo (3 s): its scene and every (t, state) the controller was given."""
    setup = box_grasp(mass=0.6)
    states = []
    supervisor = GraspSupervisor(setup.hand, setup.q_contact, smc(setup, "compiled"), offset=OFFSET)

    def capture(t, state):
        states.append((t, state))
        return supervisor(t, state)

    setup.simulator.run(capture, 3.0, state=setup.state, progress=False)
    return setup, states


def lockstep(compiled, python, states, reset_at=()) -> dict[str, float]:
    """Feed both controllers every state; per log key (and "tau") the largest |compiled - python| over the run
    divided by the largest |python| over the run (by the wrench's for the wrench residual; integer-valued entries
    must be equal)."""
    difference: dict[str, float] = {}
    scale: dict[str, float] = {}
    for k, (t, state) in enumerate(states):
        if k in reset_at:
            compiled.reset(state)
            python.reset(state)
        pairs = {"tau": (compiled(t, state), python(t, state))}
        assert compiled.log.keys() == python.log.keys(), (k, set(compiled.log) ^ set(python.log))
        pairs.update((key, (compiled.log[key], value)) for key, value in python.log.items())
        for key, (a, b) in pairs.items():
            a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
            assert a.shape == b.shape, (k, key)
            if key in EXACT:
                np.testing.assert_array_equal(a, b, err_msg=f"{key} at call {k}")
            difference[key] = max(difference.get(key, 0.0), float(np.max(np.abs(a - b), initial=0.0)))
            scale[key] = max(scale.get(key, 0.0), float(np.max(np.abs(b), initial=0.0)))
    worst = {key: value / scale[SCALE_OF.get(key, key)] if value else 0.0 for key, value in difference.items()}
    assert max(worst.values()) <= TOLERANCE, worst
    return worst


def test_the_engines_agree_on_the_demo_with_a_hold_and_a_reset(run):
    setup, states = run
    compiled, python = smc(setup, None), smc(setup, "python")
    assert (compiled.engine, python.engine) == ("compiled", "python")
    grasped = [k for k, (t, s) in enumerate(states) if sum(c.link is not None for c in python.touching(s).values()) > 1]
    first = grasped[0]
    assert 100 < first < 1000 and len(grasped) > 2000  # the approach branch, the transition and a long hold
    worst = lockstep(compiled, python, states, reset_at=(0, first + 500))
    print("hold:", {key: f"{error:.1e}" for key, error in worst.items()})
    assert worst["tau"] > 0.0  # the two really are two computations
    # holding the first pose while the replayed box moves away drives the mass to its projection's floor
    assert compiled.log["mass_estimate"][0] == python.log["mass_estimate"][0] == 1e-3


def test_the_engines_agree_under_the_supervisor_on_the_moving_reference(run):
    setup, states = run
    compiled, python = (
        GraspSupervisor(setup.hand, setup.q_contact, smc(setup, engine), offset=OFFSET)
        for engine in ("compiled", "python")
    )
    worst = lockstep(compiled, python, states)
    print("moving:", {key: f"{error:.1e}" for key, error in worst.items()})
    assert isinstance(compiled.grasp.reference, PoseMotion) and compiled.log["phase"] == 2.0
    np.testing.assert_allclose(compiled.grasp.object_estimate, python.grasp.object_estimate, rtol=1e-12)


def test_the_engines_agree_with_the_full_force_error_and_other_gains(run):
    setup, states = run
    options = {"force_error": "full", "k_f": 0.08, "rho": 30.0, "object_adaptation": np.arange(1.0, 8.0)}
    compiled, python = smc(setup, "compiled", **options), smc(setup, "python", **options)
    lockstep(compiled, python, states[::3])  # dt of 3 ms


def without(state, prefixes):
    """The state without the contacts of the fingers whose links start with ``prefixes``."""
    keep = [k for k, (link, _) in enumerate(state.contact_bodies) if not link.startswith(prefixes)]
    return replace(
        state,
        contact_points=state.contact_points[keep],
        contact_normals=state.contact_normals[keep],
        contact_forces=state.contact_forces[keep],
        contact_bodies=tuple(state.contact_bodies[k] for k in keep),
    )


def test_the_engines_agree_when_fingers_let_go_and_touch_again(run):
    """F3 lets go now and then (two contacts: another QP, F3's integral lost), F2 too (the approach branch)."""
    setup, states = run
    stream = []
    for k, (t, state) in enumerate(states[600:2400]):
        phase = k % 300
        if 100 <= phase < 140:
            state = without(state, ("F3",))
        elif 200 <= phase < 210:
            state = without(state, ("F2", "F3"))
        stream.append((t, state))
    compiled, python = smc(setup, "compiled"), smc(setup, "python")
    worst = lockstep(compiled, python, stream)
    print("let go:", {key: f"{error:.1e}" for key, error in worst.items()})
    counts = {sum(c.link is not None for c in python.touching(state).values()) for _, state in stream}
    assert counts >= {1, 2, 3}


def test_the_options_the_compiled_law_does_not_cover_run_the_python_code(barrett):
    box = Box(size=(0.06, 0.05, 0.05), mass=0.3)
    assert SMCAdaptiveGrasp(barrett, box).engine == "compiled"
    assert SMCAdaptiveGrasp(barrett, box, hand_adaptation=0.1).engine == "python"
    assert SMCAdaptiveGrasp(barrett, box, options=PINV).engine == "python"

    class Scaled(SMCAdaptiveGrasp):
        def distribute(self, contacts, wrench):
            return 2.0 * super().distribute(contacts, wrench)

    assert Scaled(barrett, box).engine == "python"
    with pytest.raises(InputError, match=r"engine='compiled' does not cover hand_adaptation=0.1, distribution='pinv'"):
        SMCAdaptiveGrasp(barrett, box, hand_adaptation=0.1, options=PINV, engine="compiled")
    with pytest.raises(InputError, match="a subclass overriding distribute"):
        Scaled(barrett, box, engine="compiled")
    with pytest.raises(InputError, match="`engine` must be one of"):
        SMCAdaptiveGrasp(barrett, box, engine="c++")


def test_copies_and_pickles_build_their_own_compiled_law(run):
    setup, states = run
    law = smc(setup, "compiled")
    law.object_estimate = law.object_estimate * 1.5
    for copied in (copy.deepcopy(law), pickle.loads(pickle.dumps(law))):
        assert copied.engine == "compiled" and copied._compiled is not law._compiled
        np.testing.assert_array_equal(copied.object_estimate, law.object_estimate)
    t, state = states[-1]
    law(t, state)
    with pytest.raises(InputError, match="call reset\\(\\) first"):
        copy.deepcopy(law)
    law.reset(state)
    twin = copy.deepcopy(law)
    np.testing.assert_array_equal(twin(t, state), law(t, state))


def test_without_the_core_the_law_says_so_unless_python_is_the_default(barrett, monkeypatch):
    """No silent fallback (the default used to become the Python law without a word)."""
    box = Box(size=(0.06, 0.05, 0.05), mass=0.3)
    monkeypatch.delattr(bhgrasp, "_core")  # the core does not load
    monkeypatch.setitem(sys.modules, "bhgrasp._core", None)
    for engine in (None, "compiled"):
        with pytest.raises(CompiledEngineUnavailable, match="BHGRASP_ENGINE=python for everything"):
            SMCAdaptiveGrasp(barrett, box, engine=engine)
    assert SMCAdaptiveGrasp(barrett, box, engine="python").engine == "python"
    monkeypatch.setattr(_native, "DEFAULT_ENGINE", "python")  # BHGRASP_ENGINE=python
    assert SMCAdaptiveGrasp(barrett, box).engine == "python"


def opposed(state):
    """The state with a second contact on F1's strongest link pressing along the opposite normal: a zero mean."""
    rows = [k for k, (link, _) in enumerate(state.contact_bodies) if link.startswith("F1")]
    k = max(rows, key=lambda r: state.contact_forces[r] @ state.contact_normals[r])
    normals = np.vstack((state.contact_normals, -state.contact_normals[k]))
    forces = np.vstack((state.contact_forces, -state.contact_forces[k]))
    points = np.vstack((state.contact_points, state.contact_points[k]))
    keep = [r for r in range(len(normals)) if r not in rows or r == k]
    bodies = (*state.contact_bodies, state.contact_bodies[k])
    return replace(
        state,
        contact_points=points[keep],
        contact_normals=normals[keep],
        contact_forces=forces[keep],
        contact_bodies=tuple(bodies[r] for r in keep),
    )


@pytest.mark.parametrize(
    "bad",
    [
        lambda s: replace(s, q=s.q[:5]),
        lambda s: replace(s, q=np.full_like(s.q, np.nan)),
        lambda s: replace(s, object_poses=()),
        lambda s: replace(s, v=np.full_like(s.v, np.nan)),
        lambda s: replace(s, object_twists=np.full_like(s.object_twists, np.nan)),
        lambda s: replace(s, object_poses=(pin.SE3(s.object_poses[0].rotation, np.full(3, np.nan)),)),
        opposed,
    ],
    ids=["q-shape", "q-nan", "no-object", "v-nan", "twist-nan", "com-nan", "zero-normal"],
)
def test_bad_input_raises_the_same_error_on_both_engines(run, bad):
    setup, states = run
    t, state = states[-1]
    messages = []
    for engine in ("compiled", "python"):
        law = smc(setup, engine)
        law.reset(state)
        law(t - 1e-3, state)
        with pytest.raises(InputError) as error:
            law(t, bad(state))
        messages.append(str(error.value))
    assert messages[0] == messages[1]


def test_time_going_backwards_raises_on_both_engines(run):
    setup, states = run
    t, state = states[-1]
    for engine in ("compiled", "python"):
        law = smc(setup, engine)
        law(t, state)
        with pytest.raises(InputError, match="time went backwards"):
            law(t - 1e-3, state)


def test_the_engines_agree_with_composite_identification(run):
    """The composite law (measured wrench's prediction error) runs after either engine's cycle, on the same bits."""
    setup, states = run
    compiled, python = (
        smc(setup, engine, identification=ObjectIdentification(), object_adaptation=(5.0, 1e-3))
        for engine in ("compiled", "python")
    )
    assert (compiled.engine, python.engine) == ("compiled", "python")
    worst = lockstep(compiled, python, states)
    print("composite:", {key: f"{error:.1e}" for key, error in worst.items()})
    assert compiled.log["identifying"] == 1.0  # the demo lifted the box off its pedestal


def test_the_engines_agree_with_a_friction_margin(run):
    """GraspOptions.friction_margin: the QP's cones at (1 - m) mu and the grip raised with the measured load, the
    same on both engines, on a run where the margin changes what they command (larger normals after the lift than
    the same law without it; the reflex's own closed form is tests/test_grasping.py's)."""
    setup, states = run
    box = Box(size=setup.box.size, mass=0.3)
    margin = replace(DEMO, friction_margin=0.3)
    compiled, python = (SMCAdaptiveGrasp(setup.hand, box, options=margin, engine=e) for e in ("compiled", "python"))
    assert compiled.engine == "compiled"
    late = states[len(states) // 2 :: 5]
    lockstep(compiled, python, late)
    plain = smc(setup, "python")
    for t, state in late:
        plain(t, state)
    assert np.sum(python.log["commanded_normal"]) > np.sum(plain.log["commanded_normal"]) + 1.0


class CountingKernel:
    """The compiled kernel, counting its calls by entry point (its grasp and sense entries)."""

    ENTRIES = ("grasp", "grasp_free_body", "grasp_free_body_on_path", "sense", "sense_contacts")

    def __init__(self, kernel):
        object.__setattr__(self, "kernel", kernel)
        object.__setattr__(self, "calls", dict.fromkeys(self.ENTRIES, 0))

    def __getattr__(self, name):
        attribute = getattr(self.kernel, name)
        if name not in self.ENTRIES:
            return attribute

        def counted(*arguments):
            self.calls[name] += 1
            return attribute(*arguments)

        return counted

    def __setattr__(self, name, value):  # the kernel's properties (the identification sets object_estimate)
        setattr(self.kernel, name, value)


def world_twist(scene, state):
    """The box's twist as Scene.object_twist makes it, R @ omega summed left to right (as the Haswell kernels CI
    pins do; OpenBLAS's AVX-512 ones fuse the multiply-adds)."""
    rotation = pin.XYZQUATToSE3(state.scene_q[scene.object_q_slice(0)]).rotation
    local = state.scene_v[scene.object_v_slice(0)]
    turned = [(row[0] * local[3] + row[1] * local[4]) + row[2] * local[5] for row in rotation]
    return np.concatenate((local[:3], turned))[None]


def test_a_simulated_state_gives_its_object_as_free_body_coordinates_with_the_same_bits(run):
    """A simulator's state hands the kernel the box's scene coordinates (its quaternion turned to R in C++, its
    body angular velocity to world) and the compiled step's contacts (each row's finger and joint by its collision
    pair); the same state made by dataclasses.replace hands it the pin.SE3 of Scene.object_pose, the twist of
    Scene.object_twist and the state's contact arrays with their body names.  Two compiled laws fed one and the other
    command the same bits."""
    setup, states = run
    direct, built = smc(setup, "compiled"), smc(setup, "compiled")
    direct._compiled.kernel = CountingKernel(direct._compiled.kernel)
    built._compiled.kernel = CountingKernel(built._compiled.kernel)
    for t, state in states[::4]:
        tau = direct(t, state)
        copy = replace(state, object_twists=world_twist(setup.simulator.scene, state))
        np.testing.assert_allclose(copy.object_twists, state.object_twists, rtol=0, atol=1e-15)
        np.testing.assert_array_equal(built(t, copy), tau, err_msg=f"t = {t}")
        assert built.log.keys() == direct.log.keys()
        for key, value in direct.log.items():
            np.testing.assert_array_equal(built.log[key], value, err_msg=f"{key} at t = {t}")
    grasp_cycles = direct._compiled.kernel.calls["grasp_free_body"]
    assert grasp_cycles > 400 and direct._compiled.kernel.calls["grasp"] == 0
    cycles = len(states[::4])
    # every state but the start state (whose contacts the scene found, a ContactSet) hands the kernel its step's
    assert (direct._compiled.kernel.calls["sense_contacts"], direct._compiled.kernel.calls["sense"]) == (cycles - 1, 1)
    assert built._compiled.kernel.calls == {
        "grasp": grasp_cycles,
        "grasp_free_body": 0,
        "grasp_free_body_on_path": 0,
        "sense": cycles,
        "sense_contacts": 0,
    }
    assert np.ptp(np.array([s.object_poses[0].rotation for _, s in states[::4]]), axis=0).max() > 0.05  # it turned


class Resampled(PoseMotion):
    """A PoseMotion the compiled law does not know (a subclass): sampled in Python, as the twin samples it."""


def test_the_compiled_law_samples_its_pose_path_in_cpp_and_commands_what_the_python_sample_commands(run, monkeypatch):
    """The supervisor's moving reference sampled by ``bhgrasp._core.PosePath`` (its rotation given to the law as
    exp(b dtheta) R_0) and by PoseMotion (the rotation exp(log(exp(b dtheta) R_0)), NumPy's product): fed the same
    states, two compiled laws command the same torques to round-off."""
    setup, states = run
    in_cpp = GraspSupervisor(setup.hand, setup.q_contact, smc(setup, "compiled"), offset=OFFSET)
    in_cpp.grasp._compiled.kernel = CountingKernel(in_cpp.grasp._compiled.kernel)
    torques = [in_cpp(t, state) for t, state in states]
    assert in_cpp.grasp._compiled.kernel.calls["grasp_free_body_on_path"] > 2000  # sampled in the grasp call
    monkeypatch.setattr("bhgrasp.controllers.supervisor.PoseMotion", Resampled)
    in_python = GraspSupervisor(setup.hand, setup.q_contact, smc(setup, "compiled"), offset=OFFSET)
    moving, largest = 0, max(float(np.abs(tau).max()) for tau in torques)
    for (t, state), tau in zip(states, torques, strict=True):
        np.testing.assert_allclose(in_python(t, state), tau, rtol=0, atol=1e-9 * largest, err_msg=f"t = {t}")
        moving += type(in_python.grasp.reference) is Resampled
    assert moving > 2000 and type(in_cpp.grasp.reference) is PoseMotion
    assert in_cpp.grasp._compiled._reference[1] is not None  # compiled
    assert in_python.grasp._compiled._reference[1] is None  # the subclass: in Python


def test_the_kernel_refuses_contacts_whose_pairs_it_was_not_given(run):
    setup, states = run
    kernel = smc(setup, "compiled")._compiled.kernel
    contacts = states[-1][1]._source.contacts  # the compiled step's, the box held
    assert type(contacts) is core_module().Contacts, "the run is on the compiled engine"
    assert len(contacts.pair) >= 3
    with pytest.raises(ValueError, match="not the scene's"):
        kernel.sense_contacts(contacts, np.zeros(0, np.int64), np.zeros(0, np.int64))
    with pytest.raises(ValueError, match="one entry per collision pair"):
        kernel.sense_contacts(contacts, np.zeros(3, np.int64), np.zeros(2, np.int64))


def test_a_pose_path_sampled_in_the_grasp_call_or_before_it_commands_the_same_bits(run):
    """Under the supervisor's moving reference, a simulator's states take the grasp call that samples the path
    (grasp_free_body_on_path); their dataclasses.replace copies take path.sample and the grasp call given the pose:
    the same bits."""
    setup, states = run
    assert type(states[-1][1]._source.contacts) is core_module().Contacts, "the run is on the compiled engine"
    direct, built = (GraspSupervisor(setup.hand, setup.q_contact, smc(setup, "compiled"), offset=OFFSET) for _ in "ab")
    direct.grasp._compiled.kernel = CountingKernel(direct.grasp._compiled.kernel)
    built.grasp._compiled.kernel = CountingKernel(built.grasp._compiled.kernel)
    for t, state in states:
        tau = direct(t, state)
        copy = replace(state, object_twists=world_twist(setup.simulator.scene, state))
        np.testing.assert_array_equal(built(t, copy), tau, err_msg=f"t = {t}")
        for key, value in direct.log.items():
            np.testing.assert_array_equal(built.log[key], value, err_msg=f"{key} at t = {t}")
    on_path = direct.grasp._compiled.kernel.calls["grasp_free_body_on_path"]
    assert on_path > 2000 and built.grasp._compiled.kernel.calls["grasp"] == on_path


def test_the_engines_agree_under_the_supervisor_with_composite_identification(run):
    """Identification wants the reference's twist and its rate in Python: the compiled law samples the path first
    (path.sample) and agrees with the twin to round-off."""
    setup, states = run
    compiled, python = (
        GraspSupervisor(
            setup.hand,
            setup.q_contact,
            smc(setup, engine, identification=ObjectIdentification(), object_adaptation=(5.0, 1e-3)),
            offset=OFFSET,
        )
        for engine in ("compiled", "python")
    )
    compiled.grasp._compiled.kernel = CountingKernel(compiled.grasp._compiled.kernel)
    worst = lockstep(compiled, python, states)
    print("moving, composite:", {key: f"{error:.1e}" for key, error in worst.items()})
    assert compiled.grasp._compiled.kernel.calls["grasp_free_body"] > 2000
    assert compiled.grasp._compiled.kernel.calls["grasp_free_body_on_path"] == 0
