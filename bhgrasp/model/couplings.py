"""Joint couplings: a hand's mimic joints (URDF ``<mimic>``) as Pinocchio builds them, and their independent twin.

A mimic joint has no coordinate of its own: its position is ``multiplier * q[mimics] + offset`` (URDF's
``<mimic joint multiplier offset>``), its velocity ``multiplier * v[mimics]``.  Pinocchio 4.1 builds such a model
with one coordinate per independent joint (``pin.buildModelFromXML(text, mimic=True)``): ``nq`` and ``nv`` count the
independent joints only, and CRBA, RNEA, the frame Jacobians and accelerations act in those coordinates.  Pinocchio
4.1 refuses mimic joints in ABA, the regressors and the kinetic energy, and gets its Coriolis matrix and the joint
Jacobians' time variation wrong for them (the Coriolis matrix of the test gripper 25-74 % off; tests/test_couplings.py
measures J_dot); bhgrasp computes those on the twin below, and the grasp kinematics and the opposition search, which
read per-joint Jacobian columns or solve one IK per finger, refuse a coupled hand.  Its CRBA is right on a fresh
Data but, for some trees, accumulates across calls: :func:`check_couplings` refuses those trees.

The **independent twin** is the same tree with every mimic joint made an ordinary joint of its own coordinate.  With
``q_twin = G q + c`` (``G`` (nv_twin, nv): a 1 per own coordinate, the multiplier per mimic joint; ``c``: the
offsets), the coupled model is the twin under the constraint ``q_twin in {G q + c}``: M = G^T M_twin G,
tau = G^T tau_twin, J = J_twin G.  The twin also serialises whole, which the coupled model does not in Pinocchio 4.1
(a mimic joint's extended sizes are not written: a model read back makes every algorithm read past its vectors), so
:class:`~bhgrasp.model.hand.Hand` pickles a coupled model as its twin plus its :class:`Coupling` list.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from bhgrasp._native import required_core
from bhgrasp.errors import ModelError


@dataclass(frozen=True)
class Coupling:
    """One mimic joint: ``q[joint] = multiplier * q[mimics] + offset`` ([rad] or [m])."""

    joint: str
    mimics: str
    multiplier: float
    offset: float


def model_couplings(model: pin.Model) -> tuple[Coupling, ...]:
    """The mimic joints of a Pinocchio model, in joint order (empty for a model without any)."""
    result = []
    for mimicking, mimicked in zip(model.mimicking_joints, model.mimicked_joints):
        joint = model.joints[mimicking].extract()
        result.append(
            Coupling(model.names[mimicking], model.names[mimicked], float(joint.scaling), float(joint.offset))
        )
    return tuple(result)


def check_couplings(model: pin.Model, couplings: tuple[Coupling, ...]) -> None:
    """Refuse a coupled model that Pinocchio 4.1 cannot compute with (checked when a hand is built).

    - a mimic joint whose configuration is not its angle or length (a continuous joint: cos and sin), which the
      linear map to the twin cannot carry;
    - a model whose CRBA gives another mass matrix on a second call with the same Data: Pinocchio 4.1 accumulates
      some entries when a mimic joint has moving joints both above and below it (e.g. a coupled hand on a wrist
      mount, or independent -> mimic -> independent along a finger).  Checked at one configuration, two calls.

    Raises:
        ModelError: Naming the joints, and ``mimic='independent'`` as the way to load the hand.
    """
    if not couplings:
        return
    for coupling in couplings:
        joint = model.joints[model.getJointId(coupling.mimics)]
        if joint.nq != joint.nv:
            raise ModelError(
                f"mimic joint {coupling.joint!r} follows {coupling.mimics!r}, a joint of {joint.nq} configuration "
                f"coordinates for {joint.nv} velocities (continuous): bhgrasp couples angles and lengths only; load "
                "the hand with mimic='independent'"
            )
    q = pin.integrate(model, pin.neutral(model), np.full(model.nv, 0.3))
    data = model.createData()
    first = pin.crba(model, data, q).copy()
    second = pin.crba(model, data, q)
    if not np.array_equal(first, second):
        raise ModelError(
            f"Pinocchio 4.1's mass matrix of this coupled model ({', '.join(c.joint for c in couplings)} mimic other "
            f"joints) changes from one call to the next by up to {np.abs(second - first).max():.3g} kg m^2: a mimic "
            "joint with moving joints above and below it (a wrist mount, or independent -> mimic -> independent) "
            "triggers it; load the hand with mimic='independent'"
        )


def refuse_couplings(couplings: tuple[Coupling, ...], what: str) -> None:
    """Raise for a hand with mimic joints where ``what`` reads per-joint Jacobian columns (grasp kinematics).

    Pinocchio 4.1 adds a mimic joint's motion into its mimicked joint's column of ``data.J`` and gets its
    ``data.dJ`` wrong (tests/test_couplings.py measures it), so a body's columns no longer say how it moves.

    Raises:
        ModelError: ``couplings`` is not empty.
    """
    if couplings:
        raise ModelError(
            f"{what} does not support mimic joints ({', '.join(c.joint for c in couplings)}): Pinocchio 4.1's joint "
            "Jacobian columns and their time variation mix the coupled joints; load the hand with "
            "mimic='independent' (an actuation model then couples the joints)"
        )


def independent_model(model: pin.Model) -> pin.Model:
    """The independent twin of ``model``: each mimic joint an ordinary joint (same joint and frame indexes).

    A mimic joint's limits in the twin are its mimicked joint's mapped through the coupling (its own URDF limits are
    not in the coupled model); its effort limit is the mimicked joint's.  Built by the compiled core (only C++ reaches
    a mimic joint's own joint model).

    Raises:
        CompiledEngineUnavailable: The compiled core does not load.
    """
    if not model.mimicking_joints:
        return pin.Model(model)
    core = required_core("the independent twin of a model with mimic joints")
    twin = pin.Model()
    twin.loadFromString(core.independent_model_text(model.saveToString()))
    return twin


def coupled_model(twin: pin.Model, couplings: tuple[Coupling, ...]) -> pin.Model:
    """The model in which each coupling's joint mimics its joint again (inverse of :func:`independent_model`)."""
    model = twin
    for coupling in couplings:
        mimicked, mimicking = twin.getJointId(coupling.mimics), twin.getJointId(coupling.joint)
        model = pin.transformJointIntoMimic(model, mimicked, mimicking, coupling.multiplier, coupling.offset)
    return model if couplings else pin.Model(twin)


@dataclass(frozen=True)
class TwinMap:
    """How a coupled model's coordinates give its twin's: ``v_twin = velocity @ v``, ``q_twin = configuration(q)``.

    ``velocity`` (twin.nv, model.nv) has a 1 per own coordinate and the multiplier per mimic joint; a mimic joint's
    position is ``multiplier * q[mimics] + offset`` (a hand's mimic joints are 1-DOF with nq = nv, as
    :func:`check_couplings` requires); every other joint's configuration is copied (nq != nv, e.g. spherical,
    included).
    """

    velocity: np.ndarray
    _sources: np.ndarray  # per twin coordinate: the model's coordinate it reads
    _scales: np.ndarray
    _offsets: np.ndarray

    def configuration(self, q: np.ndarray) -> np.ndarray:
        """The twin's configuration of the coupled configuration ``q`` (model.nq,), shape (twin.nq,)."""
        return self._scales * q[self._sources] + self._offsets


def twin_map(model: pin.Model, twin: pin.Model) -> TwinMap:
    """The :class:`TwinMap` from ``model`` to its independent twin (:func:`independent_model`)."""
    velocity = np.zeros((twin.nv, model.nv))
    sources, scales, offsets = np.zeros(twin.nq, dtype=int), np.ones(twin.nq), np.zeros(twin.nq)
    mimics = {coupling.joint: coupling for coupling in model_couplings(model)}
    for joint in range(1, model.njoints):
        own, source = twin.joints[joint], model.joints[joint]  # a mimic joint's idx_q/idx_v are its mimicked joint's
        coupling = mimics.get(model.names[joint])
        scale = 1.0 if coupling is None else coupling.multiplier
        for k in range(own.nv):
            velocity[own.idx_v + k, source.idx_v + k] = scale
        for k in range(own.nq):
            sources[own.idx_q + k], scales[own.idx_q + k] = source.idx_q + k, scale
            offsets[own.idx_q + k] = 0.0 if coupling is None else coupling.offset
    return TwinMap(velocity, sources, scales, offsets)
