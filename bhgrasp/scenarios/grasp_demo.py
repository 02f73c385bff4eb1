"""The main job: the Barrett hand grasps a box of unknown mass, lifts it and turns it (``bhgrasp demo``).

The box (thesis 5.7: 0.06 x 0.05 x 0.05 m) stands on a pedestal; a :class:`~bhgrasp.controllers.GraspSupervisor`
closes the fingers from the IK contact configuration opened by 0.3 rad, squeezes, then moves the box by
``offset`` (default: 10 mm up and 0.1 rad about x) under the chosen object-space controller.  The controller
starts from a wrong mass (``estimate``); the SMC-adaptive law (5.46)-(5.60) learns it.  The summary reports the
final object pose error, the contact force error after settling (measured normal force vs. the commanded one, per
finger), slip events (sliding hand-object contact samples after the grasp closed), the cone margin of the
commanded forces (negative: the distribution asked for forces outside the assumed cone, as the thesis' G^+ form
does) and the run time.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from bhgrasp._validation import as_positive, as_vector
from bhgrasp.controllers.base import Controller
from bhgrasp.controllers.estimated_object import EstimatedObject
from bhgrasp.controllers.grasp_options import GraspOptions
from bhgrasp.controllers.motor_commands import MotorCommands
from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.controllers.supervisor_options import Approach, Planning
from bhgrasp.errors import InputError
from bhgrasp.grasp.metrics import finger_normal_forces
from bhgrasp.model.objects import Box
from bhgrasp.scenarios.allegro_grasp import allegro_box_grasp
from bhgrasp.scenarios.box_grasp import STIFFNESS, BoxGrasp, box_grasp
from bhgrasp.scenarios.demo_estimator import demo_estimator
from bhgrasp.scenarios.demo_result import MU_ASSUMED, GraspDemoResult, evaluate_demo
from bhgrasp.scenarios.grasp_choice import choose_pinch, given_grasp
from bhgrasp.scenarios.grasp_controllers import ADAPTATIONS, CONTROLLERS, grasp_controller
from bhgrasp.scenarios.uncertainty import (
    PLANT,
    SENSED,
    UNCERTAINTIES,
    check_uncertainty,
    sensor_model,
)

if TYPE_CHECKING:
    from bhgrasp.plots import Figure

HANDS = ("barrett", "allegro")
ESTIMATORS = (None, "hand")
OFFSET = (0.0, 0.0, 0.010, 0.1, 0.0, 0.0)  # [m, rad]: 10 mm up, 0.1 rad about x


SWEEPABLE = (
    "mass",
    "estimate",
    "controller",
    "adaptation",
    "duration",
    "offset",
    "distribution",
    "approach_gains",
    "gains",
    "stiffness",
    "sensor_noise",
    "hand",
    "finger_spacing",
    "friction_margin",
    "estimator",
    "torque_limit_known",
    *UNCERTAINTIES,
)
"""The parameters of :func:`run_grasp_demo` a sweep case may set (the case's seed comes from the sweep)."""


def check_demo_arguments(**arguments: Any) -> None:
    """Check :func:`run_grasp_demo` arguments without running anything (names in :data:`SWEEPABLE`).

    Raises:
        InputError: An unknown name, or a value of the wrong kind or range; the message names the argument.
    """
    unknown = sorted(set(arguments) - set(SWEEPABLE))
    if unknown:
        raise InputError(f"the grasp demo has no parameter {unknown[0]!r}; it takes {', '.join(SWEEPABLE)}")
    for name in ("mass", "estimate", "duration", "stiffness"):
        if name in arguments:
            as_positive(arguments[name], name)
    choices = {
        "controller": CONTROLLERS,
        "adaptation": ADAPTATIONS,
        "distribution": ("qp", "pinv"),
        "hand": HANDS,
        "estimator": ESTIMATORS,
    }
    for name, allowed in choices.items():
        if name in arguments and arguments[name] not in allowed:
            raise InputError(f"`{name}` must be one of {allowed}, got {arguments[name]!r}")
    controller = arguments.get("controller", "smc-adaptive")
    if arguments.get("adaptation") == "composite" and controller != "smc-adaptive":
        raise InputError(f"`adaptation='composite'` applies to the 'smc-adaptive' controller, not {controller!r}")
    if "offset" in arguments:
        as_vector(arguments["offset"], "offset", 6)
    if "approach_gains" in arguments:
        gains = as_vector(arguments["approach_gains"], "approach_gains", 2)
        if (gains <= 0.0).any():
            raise InputError(f"`approach_gains` (Kp, Kv) must be positive, got {gains.tolist()}")
    noise = arguments.get("sensor_noise")
    if noise is not None:
        sigma = as_vector(noise, "sensor_noise", 2)
        if (sigma < 0.0).any():
            raise InputError(f"`sensor_noise` (sigma_q, sigma_v) must be >= 0, got {sigma.tolist()}")
    barrett_only = sorted(name for name in (*UNCERTAINTIES, "finger_spacing") if name in arguments)
    if arguments.get("estimator") is not None:
        barrett_only.append("estimator")
    if barrett_only and arguments.get("hand", "barrett") != "barrett":
        raise InputError(f"the arguments {barrett_only} apply to the Barrett scene, not {arguments['hand']}")
    if "finger_spacing" in arguments:
        as_positive(arguments["finger_spacing"], "finger_spacing")
    if arguments.get("friction_margin") is not None:
        GraspOptions(friction_margin=arguments["friction_margin"])  # its check: a fraction in [0, 1)
    if not isinstance(arguments.get("torque_limit_known", False), (bool, np.bool_)):
        raise InputError(f"`torque_limit_known` must be True or False, got {arguments['torque_limit_known']!r}")
    if arguments.get("torque_limit_known") and arguments.get("torque_limit") is None:
        raise InputError("`torque_limit_known=True` tells the controller the `torque_limit`, but none was given")
    check_uncertainty(**{name: arguments[name] for name in UNCERTAINTIES if name in arguments})


def run_grasp_demo(
    mass: float = 0.6,
    estimate: float = 0.3,
    controller: str = "smc-adaptive",
    duration: float = 3.0,
    offset: Any = OFFSET,
    distribution: str = "qp",
    approach_gains: tuple[float, float] = (400.0, 40.0),
    gains: tuple[Any, Any] | None = None,
    progress: bool = False,
    viewer: Any = None,
    stiffness: float = STIFFNESS,
    sensor_noise: tuple[float, float] | None = None,
    seed: int = 0,
    hand: str = "barrett",
    finger_spacing: float | None = None,
    adaptation: str = "thesis",
    friction_margin: float | None = None,
    estimator: str | None = None,
    torque_limit_known: bool = False,
    **uncertainty: Any,
) -> GraspDemoResult:
    """Grasp, lift and turn the box; see the module docstring.

    Raises:
        UnreachableError: ``offset`` is outside the planned grasp's manipulable space
            (:meth:`~bhgrasp.scenarios.box_grasp.BoxGrasp.manipulable_space`); the message names the missing
            direction or the joint, and gives the nearest offset the grasp can make.  Or its path drives the box
            into the pedestal: the message gives the lift that clears it.

    Args:
        mass: True box mass [kg].
        estimate: Mass [kg] the controller starts from.
        controller: One of :data:`~bhgrasp.scenarios.grasp_controllers.CONTROLLERS`.
        duration: Simulated time [s].
        offset: Object motion after the squeeze (position [m], rotation vector [rad], world); one the planned grasp
            cannot make without sliding, or without a joint passing its limit, is refused before simulating.
        distribution: ``"qp"`` (friction-cone QP) or ``"pinv"`` (the thesis' G^+ baseline).
        approach_gains: Joint computed-torque gains (Kp [1/s^2], Kv [1/s]) of the approach.
        gains: (kp, kv) of the "ctc", "natural" or "stiffness" controller instead of the demo's.
        progress: Show a progress bar.
        viewer: A :class:`bhgrasp.viz.SceneViewer` of this scene to stream the run to (real time, <= 30 frames/s).
        stiffness: Contact stiffness [N/m].
        sensor_noise: (sigma_q [rad], sigma_v [rad/s]) Gaussian noise on the joint state the controller reads.
        seed: Seed of the sensor noise.
        hand: ``"barrett"`` (the thesis' scene, :func:`~bhgrasp.scenarios.box_grasp.box_grasp`) or
            ``"allegro"`` (the 16-DOF Allegro hand of example-robot-data grasping a box with thumb, index and
            middle finger, :func:`~bhgrasp.scenarios.allegro_grasp.allegro_box_grasp`).  The controllers are
            the same; where the scene asks for it (the Allegro) the commands also cancel the joints' viscous
            damping (known to the controller), which dominates its light links' inertia.
        finger_spacing: Distance [m] between F1's and F2's contacts (Barrett scene; 50 mm: the thesis' pinch, the
            spread on its stop; :data:`~bhgrasp.scenarios.box_grasp.OFF_STOP_SPACING` takes it off).  ``None``: the
            first pinch that makes ``offset`` (:mod:`bhgrasp.scenarios.grasp_choice`; the result's
            ``grasp_choice`` says which, and why the others were refused).
        adaptation: The SMC-adaptive law's object estimate
            (:data:`~bhgrasp.scenarios.grasp_controllers.ADAPTATIONS`): the thesis' (5.52), or ``"composite"``,
            which also fits the wrench the hand measures on the object once it is off its pedestal
            (:mod:`bhgrasp.controllers.object_identification`: not fooled by joint friction, chapter 5's adaptation
            case).
        friction_margin: The fraction of the assumed ``mu`` kept in reserve (``None``: none): the QP's cones at
            (1 - m) mu and the grip raised with the measured tangential load
            (:class:`~bhgrasp.controllers.grasp_options.GraspOptions`).
        estimator: ``None``: the controller reads the object's pose and twist as the tracker reports them;
            ``"hand"``: through a :class:`~bhgrasp.controllers.object_estimator.HeldObjectEstimator` (Barrett
            scene), which carries the estimate with the fingers' encoders once three fingers hold the box and
            corrects it with the tracker (its noise taken as ``pose_noise``; 0.5 mm / 5 mrad for a part without one).
        torque_limit_known: ``False`` (default): the joints' ``torque_limit`` (an uncertainty below) is the
            drive's alone, which clips the torques the controller commands; ``True``: the controller is told it and
            keeps its commands within it (``GraspOptions.torque_limit``: it squeezes less where a joint would pass
            it).
        uncertainty: What the controller does not know (:data:`UNCERTAINTIES`, Barrett scene only):
            ``pose_noise`` (sigma [m], sigma [rad]) on the object pose, ``twist_noise`` (sigma [m/s], sigma
            [rad/s]) on its twist, ``force_noise`` sigma [N] on the contact forces, ``delay`` [s] of every reading,
            ``joint_friction`` Coulomb [N m] and ``joint_damping`` viscous [N m s/rad] on the joints,
            ``torque_limit`` [N m] on each joint torque, ``friction`` the true friction coefficient (0.8) and
            ``mu`` the one the force distribution assumes (0.6).
    """
    check_demo_arguments(
        mass=mass,
        estimate=estimate,
        controller=controller,
        adaptation=adaptation,
        duration=duration,
        offset=offset,
        distribution=distribution,
        approach_gains=approach_gains,
        stiffness=stiffness,
        sensor_noise=sensor_noise,
        hand=hand,
        friction_margin=friction_margin,
        estimator=estimator,
        torque_limit_known=torque_limit_known,
        **uncertainty,
        **({} if finger_spacing is None else {"finger_spacing": finger_spacing}),
    )
    mass, estimate, duration, offset = float(mass), float(estimate), float(duration), as_vector(offset, "offset", 6)
    plant = {name: uncertainty[name] for name in PLANT if name in uncertainty}
    if hand == "barrett" and finger_spacing is None:  # the first pinch that makes the motion, before simulating
        setup, choice = choose_pinch(mass, offset, float(stiffness), **plant)
    else:  # the given grasp, refused before simulating if it cannot make the motion
        spacing = {} if finger_spacing is None else {"finger_spacing": finger_spacing}
        setup = grasp_scene(hand, mass, float(stiffness), **plant, **spacing)
        choice = given_grasp(setup, offset, finger_spacing)
    nominal_box, mu = Box(size=setup.box.size, mass=estimate), float(uncertainty.get("mu", MU_ASSUMED))
    limit = uncertainty.get("torque_limit") if torque_limit_known else None
    grasp = grasp_controller(
        controller, setup.hand, nominal_box, distribution, gains, mu, adaptation, friction_margin, limit
    )
    supervisor = _supervisor(setup, grasp, offset, approach_gains, hand)
    law: Controller = MotorCommands(supervisor, setup.simulator.actuation.drive) if setup.cancel_damping else supervisor
    if estimator == "hand":
        law = EstimatedObject(law, demo_estimator(setup, uncertainty.get("pose_noise")))
    if viewer is not None:
        from bhgrasp.viz import LiveView

        law = LiveView(law, viewer)  # real time, 30 frames per second at most
    start = time.perf_counter()
    sensors = sensor_model(sensor_noise, **{name: uncertainty[name] for name in SENSED if name in uncertainty})
    traj = setup.simulator.run(law, duration, state=setup.state, progress=progress, sensors=sensors, seed=seed)
    wall = time.perf_counter() - start
    result = evaluate_demo(traj, setup.hand, controller, mass, estimate, supervisor, wall, setup.simulator.scene)
    return replace(result, grasp_choice=choice)


def _supervisor(setup: BoxGrasp, grasp: Any, offset: Any, approach_gains: tuple, hand: str) -> GraspSupervisor:
    """The demo's supervisor: approach at ``approach_gains`` = (kp, kv), then ``grasp`` moves the box by ``offset``."""
    kp, kv = approach_gains
    shape = setup.box.geometry() if hand == "barrett" else None  # the Barrett scene's motions are checked to the end
    return GraspSupervisor(
        setup.hand,
        setup.q_contact,
        grasp,
        offset=offset,
        approach=Approach(kp=kp, kv=kv),
        q_close=setup.q_close,
        fingers=setup.fingers,
        planning=Planning(object_shape=shape),
    )


def grasp_scene(hand: str, mass: float, stiffness: float = STIFFNESS, **plant: Any) -> BoxGrasp:
    """The demo's scene for ``hand`` (one of :data:`HANDS`) with a box of ``mass`` [kg].

    ``plant``: the Barrett scene's true friction, joint friction and damping and torque limit (:data:`PLANT`), and
    its ``finger_spacing``.
    """
    if hand == "barrett":
        return box_grasp(mass=mass, stiffness=stiffness, **plant)
    if hand == "allegro":
        return allegro_box_grasp(mass=mass, stiffness=stiffness)
    raise InputError(f"`hand` must be one of {HANDS}, got {hand!r}")


def demo_figure(result: GraspDemoResult, hand) -> Figure:
    """Object pose error, measured vs. commanded normal forces, and the mass estimate (or the cone margin)."""
    from bhgrasp.plots import grasp_figure

    measured = finger_normal_forces(hand, result.trajectory)
    return grasp_figure(
        result.trajectory,
        hand.fingers,
        measured,
        result.true_mass,
        grasp_time=result.grasp_time,
        motion=(result.motion_start, result.motion_end),
    )


def save_demo(result: GraspDemoResult, hand, output: Path) -> list[Path]:
    """Write the figure (PNG) and the trajectory (npz) under ``output``; returns the paths."""
    output.mkdir(parents=True, exist_ok=True)
    figure_path = output / "grasp_demo.png"
    demo_figure(result, hand).savefig(figure_path, dpi=110)
    data_path = output / "grasp_demo.npz"
    result.trajectory.save(data_path)
    return [figure_path, data_path]


__all__ = [
    "HANDS",
    "demo_figure",
    "grasp_scene",
    "run_grasp_demo",
    "save_demo",
]
