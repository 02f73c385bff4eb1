"""The compiled engine: the C++ step of ``bhgrasp._core`` on one scene, contact law and settings.

The C++ step (``src/engine.cpp``) mirrors the Python one line for line: contact detection with coal on every
collision pair, contact patches and per-point depths, matching to the last step's contacts, the stick-slip
linearisation with its active set, joint stops, springs, damping and friction, the implicit-midpoint gyroscopic
torque, and the implicit, semi-implicit and RK4 integrators.  An actuation model stays in Python (each step passes
its current transmission and damping, :class:`~bhgrasp.sim.engine.DriveTerms`, built once per mode), but for the
BH8-280's (:class:`~bhgrasp.sim.actuation.BarrettActuation` itself; a subclass may change its rules and runs them in
Python) the drive runs in the same C++ call as the step
(:meth:`CompiledEngine.step_barrett`, ``src/barrett.cpp``: its worm locks, gears, TorqueSwitch and the drive of each
mode).  ``tests/test_compiled.py`` steps both engines in lockstep; ``tests/test_compiled_drive.py`` holds the
compiled drive to the Python actuation's rules bit for bit.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from bhgrasp._native import required_core
from bhgrasp.data import ContactMemory, ContactSet, empty_contact_set
from bhgrasp.sim.coal_queries import FALLBACK_TOLERANCE, NARROW_TOLERANCE
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.engine import DriveTerms, StepFields
from bhgrasp.sim.geometry_text import geometry_text
from bhgrasp.sim.native_options import filled
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.scene_layout import SceneLayout
from bhgrasp.sim.settings import SimulatorSettings

if TYPE_CHECKING:
    from bhgrasp.sim.actuation import Actuation, BarrettActuation

_INTEGRATORS = {"implicit": 0, "semi-implicit": 1, "rk4": 2}
_NONE = np.zeros(0)  # no extra torques


def core_module():
    """The compiled extension ``bhgrasp._core``.

    Raises:
        CompiledEngineUnavailable: It is missing or does not load (the message says why and how to rebuild).
    """
    return required_core("the compiled engine")


class CompiledEngine:
    """The C++ step on one scene, contact law and settings (the :class:`~bhgrasp.sim.engine.Engine` protocol)."""

    name = "compiled"

    def __init__(
        self, scene: Scene, layout: SceneLayout, law: SpringDamper, settings: SimulatorSettings, match_radius: float
    ) -> None:
        """Copy the scene (Pinocchio's serialisation), the contact law and the settings into C++."""
        model, geometry = scene.model.saveToString(), geometry_text(scene.geometry)
        native = engine_settings(scene, layout, law, settings, match_radius)
        self._engine = core_module().Engine(model, geometry, native)
        self._limits = (settings.max_speed, settings.max_penetration)

    def drive(self, terms: DriveTerms):
        """``terms`` as the C++ engine's ``Drive``."""
        return native_drive(terms)

    def memory(self, memory: ContactMemory):
        """A :class:`~bhgrasp.data.contacts.ContactMemory` as the C++ engine's ``Memory``."""
        return native_memory(memory)

    def contact_set(self, contacts) -> ContactSet:
        """A step's ``Contacts`` as a :class:`~bhgrasp.data.contacts.ContactSet`."""
        return contact_set(contacts)

    def contact_memory(self, memory) -> ContactMemory:
        """A step's ``Memory`` as a :class:`~bhgrasp.data.contacts.ContactMemory` (keeping the native one)."""
        return memory_of(memory)

    def step(self, q: np.ndarray, v: np.ndarray, tau_hand: np.ndarray, drive: Any, memory: Any) -> StepFields:
        """One step from the engine's own ``Memory`` with a ``Drive`` of :meth:`drive`.

        Returns the C++ engine's own ``StepResult``: the fields of :class:`~bhgrasp.sim.engine.StepResult`, each
        read from C++ when asked for (``q`` and ``v`` as read-only views; the ``Contacts`` and ``Memory`` objects
        converted by :func:`contact_set` and :func:`memory_of` when read).
        """
        return self._engine.step(q, v, tau_hand, drive, memory, *self._limits)

    def barrett(self, actuation: BarrettActuation):
        """A Barrett actuation's drive as C++ builds and steps it (its parameters now; its modes are a step's)."""
        return core_module().BarrettDrive(barrett_of(actuation))

    def step_barrett(
        self,
        drive: Any,
        q: np.ndarray,
        v: np.ndarray,
        u: np.ndarray,
        extra: np.ndarray | None,
        modes: tuple[int, ...],
        memory: Any,
    ) -> tuple[StepFields, tuple[int, ...]]:
        """One step under a Barrett drive of :meth:`barrett` in ``modes`` (6: TorqueSwitch, then worm locks).

        ``u``: the motor torques, then one per directly driven joint; ``extra``: joint torques (nv_hand) or
        generalized forces (nv) added to the drive's, or ``None``.  The C++ call locks an idle motor's worm for the
        step, applies the gears (clipped inputs if ``saturate``), steps in that mode's drive and applies the
        TorqueSwitch and lock rules (:class:`~bhgrasp.sim.actuation.BarrettActuation`'s ``begin``,
        ``joint_torques`` and ``update``).  Returns the step and the modes after it (before it: if it diverged).
        """
        result, after = drive.step(
            self._engine, q, v, u, _NONE if extra is None else extra, modes, memory, *self._limits
        )
        return result, tuple(after)

    def detect(self, q: np.ndarray, memory: ContactMemory) -> ContactSet:
        """The contacts at ``q`` matched to ``memory`` (no forces)."""
        return contact_set(self._engine.detect(q, native_memory(memory)))

    def run_loop(
        self, controller: Any, drive: Any, start: tuple, dt: float, steps: int, until: float, limit: Any
    ) -> Any:
        """Up to ``steps`` steps under a compiled loop controller (``bhgrasp._core.LoopController``) in one call.

        ``start``: (q, v, contacts, memory, t [s]) as a compiled step made them; ``drive``: a ``Drive`` of
        :meth:`drive`; each step's joint torques are the controller's inputs, clipped to +-``limit`` unless ``None``;
        the loop stops before a step at t >= ``until`` [s].  Returns the C++ ``LoopRun`` (``src/closed_loop.hpp``).
        """
        clip = _NONE if limit is None else limit
        arguments = (*start, dt, steps, until, clip, *self._limits)
        return core_module().run_closed_loop(self._engine, controller, drive, *arguments)


def engine_settings(
    scene: Scene, layout: SceneLayout, law: SpringDamper, settings: SimulatorSettings, match_radius: float
):
    """A scene's sizes, the settings, the contact law and the collision queries as the C++ engine's ``Settings``."""
    core = core_module()
    return filled(
        core.Settings,
        dt=settings.dt,
        integrator=_INTEGRATORS[settings.integrator],
        nq_hand=scene.nq_hand,
        nv_hand=scene.nv_hand,
        lower=scene.hand.lower,
        upper=scene.hand.upper,
        limit_stiffness=settings.joint_limit_stiffness,
        limit_damping=settings.joint_limit_damping,
        max_coordinate=settings.max_coordinate,
        joint_stiffness=scene.joint_stiffness,
        joint_damping=scene.joint_damping,
        spring_q=[int(i) for i in layout.spring_q],
        spring_v=[int(i) for i in layout.spring_v],
        spinning=[
            filled(core.Spinning, angular=angular.start, axes=axes, moments=np.array(moments))
            for angular, axes, moments in layout.spinning_bodies
        ],
        pairs=[native_pair(pair, law) for pair in scene.pairs],
        law=native_law(law, match_radius),
        query=native_query(scene),
        sparse=settings.solves_sparse(scene.nv),
    )


def native_law(law: SpringDamper, match_radius: float):
    """The contact law (and the radius [m] within which contacts match last step's) as the C++ ``ContactLaw``."""
    return filled(
        core_module().ContactLaw,
        stiffness=law.stiffness,
        damping=law.damping,
        tangential_stiffness=law.k_t,
        tangential_damping=law.c_t,
        hunt_crossley=law.normal_law == "hunt-crossley",
        exponent=law.exponent,
        tanh_friction=law.friction_law == "tanh",
        slip_velocity=law.slip_velocity,
        match_radius=match_radius,
    )


def native_pair(pair, law: SpringDamper):
    """A scene's :class:`~bhgrasp.sim.collision_pair.CollisionPair` as the C++ ``Pair`` (friction from ``law``'s)."""
    return filled(
        core_module().Pair,
        geom_a=pair.geom_a,
        geom_b=pair.geom_b,
        joint_a=pair.joint_a,
        joint_b=pair.joint_b,
        friction=pair.friction(law.friction),
    )


def native_query(scene: Scene):
    """The coal requests of ``scene``'s pairs (and both GJK/EPA tolerances) as the C++ ``Query``."""
    request, patch = scene.collision_request, scene.patch_request
    return filled(
        core_module().Query,
        num_max_contacts=request.num_max_contacts,
        security_margin=request.security_margin,
        break_distance=request.break_distance,
        tolerance=NARROW_TOLERANCE,
        fallback_tolerance=FALLBACK_TOLERANCE,
        max_num_patch=patch.max_num_patch,
        num_samples_curved_shapes=patch.getNumSamplesCurvedShapes(),
        patch_tolerance=patch.getPatchTolerance(),
    )


def native_drive(terms: DriveTerms):
    """A drive's terms as the C++ engine's ``Drive``."""
    return filled(
        core_module().Drive,
        transmission=terms.transmission,
        joint_damping=terms.joint_damping,
        friction=terms.friction,
        motor_damping=terms.motor_damping,
    )


def drive_of(actuation: Actuation):
    """An actuation model's transmission and damping in its current mode as the C++ engine's ``Drive``."""
    return native_drive(DriveTerms.of(actuation))


def barrett_of(actuation: BarrettActuation):
    """A Barrett actuation's parameters as the C++ ``Barrett`` (a Simulator's step and the batch's; modes apart)."""
    from bhgrasp.barrett import transmission as model

    drive = actuation.drive
    return filled(
        core_module().Barrett,
        nv_hand=actuation.hand.nv,
        spread_first=drive.spread[0],
        spread_second=drive.spread[1],
        proximal=list(drive.proximal),
        distal=list(drive.distal),
        spread_ratio=model.SPREAD_RATIO,
        proximal_ratio=model.PROXIMAL_RATIO,
        distal_ratio=model.DISTAL_RATIO,
        distal_alone_ratio=model.DISTAL_ALONE_RATIO,
        max_motor_torque=model.MAX_MOTOR_TORQUE,
        breakaway_torque=actuation.breakaway_torque,
        motor_damping=actuation.motor_damping,
        efficiency=drive.efficiency,
        saturate=actuation.saturate,
        self_locking=actuation.self_locking,
        damping=actuation.damping,
        friction=actuation.friction,
        lower=actuation.hand.lower,
        direct=list(drive.direct),
    )


def native_memory(memory: ContactMemory):
    """A :class:`~bhgrasp.data.contacts.ContactMemory` as the C++ engine's ``Memory`` (its native copy, if any)."""
    if memory.native is not None:
        return memory.native
    arrays = (memory.pair, memory.local_b, memory.displacement, memory.sliding)
    return core_module().Memory(*(array.copy() for array in arrays))  # (writable copies of the read-only arrays)


def memory_of(native) -> ContactMemory:
    """The C++ engine's contact memory as a :class:`~bhgrasp.data.contacts.ContactMemory` (keeping the native one)."""
    return ContactMemory.with_native(native)


def contact_set(contacts) -> ContactSet:
    """The C++ engine's contacts as a :class:`~bhgrasp.data.contacts.ContactSet`."""
    if len(contacts) == 0:
        return empty_contact_set()
    return ContactSet(
        contacts.pair,
        contacts.point,
        contacts.normal,
        contacts.depth,
        contacts.friction,
        contacts.displacement,
        contacts.weight,
        contacts.local_b,
        contacts.force,
        contacts.sticking,
        contacts.was_sliding,
    )


__all__ = [
    "CompiledEngine",
    "barrett_of",
    "contact_set",
    "core_module",
    "drive_of",
    "engine_settings",
    "memory_of",
    "native_drive",
    "native_law",
    "native_memory",
    "native_pair",
    "native_query",
]
