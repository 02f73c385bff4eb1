"""The compiled engine: the C++ step of ``bhgrasp._core`` on one scene, contact law and settings.

The C++ step (``src/engine.cpp``) mirrors the Python one line for line: contact detection with coal on every
collision pair, contact patches and per-point depths, matching to the last step's contacts, the stick-slip
linearisation with its active set, joint stops, springs, damping and friction, the implicit-midpoint gyroscopic
torque, and the implicit, semi-implicit and RK4 integrators.  The actuation model stays in Python: each step
passes its current transmission and damping (:class:`~bhgrasp.sim.engine.DriveTerms`, built once per mode).
``tests/test_compiled.py`` steps both engines in lockstep.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from bhgrasp._native import required_core
from bhgrasp.data import ContactMemory, ContactSet, empty_contact_set
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.engine import DriveTerms, StepResult
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.scene_layout import SceneLayout
from bhgrasp.sim.settings import SimulatorSettings

if TYPE_CHECKING:
    from bhgrasp.sim.actuation import Actuation, BarrettActuation

_INTEGRATORS = {"implicit": 0, "semi-implicit": 1, "rk4": 2}


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
        model, geometry = scene.model.saveToString(), scene.geometry.saveToString()
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

    def step(self, q: np.ndarray, v: np.ndarray, tau_hand: np.ndarray, drive: Any, memory: Any) -> StepResult:
        """One step from the engine's own ``Memory`` with a ``Drive`` of :meth:`drive`.

        Returns the :class:`~bhgrasp.sim.engine.StepResult` with the C++ engine's ``Contacts`` and ``Memory``
        objects (converted by :func:`contact_set` and :func:`memory_of` when read).
        """
        result = self._engine.step(q, v, tau_hand, drive, memory, *self._limits)
        return StepResult(
            result.q, result.v, result.contacts, result.drive, result.memory, result.divergence, result.load
        )

    def detect(self, q: np.ndarray, memory: ContactMemory) -> ContactSet:
        """The contacts at ``q`` matched to ``memory`` (no forces)."""
        return contact_set(self._engine.detect(q, native_memory(memory)))


def engine_settings(
    scene: Scene, layout: SceneLayout, law: SpringDamper, settings: SimulatorSettings, match_radius: float
):
    """A scene's sizes, the settings, the contact law and the collision queries as the C++ engine's ``Settings``."""
    core = core_module()
    result = core.Settings()
    result.dt = settings.dt
    result.integrator = _INTEGRATORS[settings.integrator]
    result.nq_hand, result.nv_hand = scene.nq_hand, scene.nv_hand
    result.lower, result.upper = scene.hand.lower, scene.hand.upper
    result.limit_stiffness, result.limit_damping = settings.joint_limit_stiffness, settings.joint_limit_damping
    result.max_coordinate = settings.max_coordinate
    result.joint_stiffness, result.joint_damping = scene.joint_stiffness, scene.joint_damping
    result.spring_q = [int(i) for i in layout.spring_q]
    result.spring_v = [int(i) for i in layout.spring_v]
    spinning = []
    for angular, axes, moments in layout.spinning_bodies:
        body = core.Spinning()
        body.angular, body.axes, body.moments = angular.start, axes, np.array(moments)
        spinning.append(body)
    result.spinning = spinning
    contact = core.ContactLaw()
    contact.stiffness, contact.damping = law.stiffness, law.damping
    contact.tangential_stiffness, contact.tangential_damping = law.k_t, law.c_t
    contact.hunt_crossley, contact.exponent = law.normal_law == "hunt-crossley", law.exponent
    contact.tanh_friction, contact.slip_velocity = law.friction_law == "tanh", law.slip_velocity
    contact.match_radius = match_radius
    result.law = contact
    pairs, queries = [], []
    for pair in scene.pairs:
        item = core.Pair()
        item.geom_a, item.geom_b, item.joint_a, item.joint_b = pair.geom_a, pair.geom_b, pair.joint_a, pair.joint_b
        item.friction = pair.friction(law.friction)
        pairs.append(item)
        request = scene.geometry_data.collisionRequests[pair.index]
        patch = scene.geometry_data.contactPatchRequests[pair.index]
        query = core.Query()
        query.num_max_contacts = request.num_max_contacts
        query.security_margin, query.break_distance = request.security_margin, request.break_distance
        query.max_num_patch = patch.max_num_patch
        query.num_samples_curved_shapes = patch.getNumSamplesCurvedShapes()
        query.patch_tolerance = patch.getPatchTolerance()
        queries.append(query)
    result.pairs, result.queries = pairs, queries
    return result


def native_drive(terms: DriveTerms):
    """A drive's terms as the C++ engine's ``Drive``."""
    drive = core_module().Drive()
    drive.transmission = terms.transmission
    drive.joint_damping = terms.joint_damping
    drive.friction = terms.friction
    drive.motor_damping = terms.motor_damping
    return drive


def drive_of(actuation: Actuation):
    """An actuation model's transmission and damping in its current mode as the C++ engine's ``Drive``."""
    return native_drive(DriveTerms.of(actuation))


def barrett_of(actuation: BarrettActuation):
    """A Barrett actuation's parameters as the C++ ``Barrett`` of the batch (its modes are per environment)."""
    from bhgrasp.barrett import transmission as model

    barrett = core_module().Barrett()
    barrett.nv_hand = actuation.hand.nv
    drive = actuation.drive
    barrett.spread_first, barrett.spread_second = drive.spread
    barrett.proximal, barrett.distal = list(drive.proximal), list(drive.distal)
    barrett.spread_ratio, barrett.proximal_ratio = model.SPREAD_RATIO, model.PROXIMAL_RATIO
    barrett.distal_ratio, barrett.distal_alone_ratio = model.DISTAL_RATIO, model.DISTAL_ALONE_RATIO
    barrett.max_motor_torque, barrett.breakaway_torque = model.MAX_MOTOR_TORQUE, actuation.breakaway_torque
    barrett.motor_damping = actuation.motor_damping
    barrett.saturate = actuation.saturate
    barrett.efficiency, barrett.self_locking = actuation.drive.efficiency, actuation.self_locking
    barrett.damping, barrett.friction, barrett.lower = actuation.damping, actuation.friction, actuation.hand.lower
    return barrett


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
    "native_memory",
]
