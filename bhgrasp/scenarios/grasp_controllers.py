"""The grasp demo's object-space controllers by name, with their gains (:func:`grasp_controller`)."""

from __future__ import annotations

from typing import Any

from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
from bhgrasp.controllers.grasp_force import GraspForceController
from bhgrasp.controllers.grasp_options import GraspOptions
from bhgrasp.controllers.grasping import ObjectGraspController
from bhgrasp.controllers.object_identification import ObjectIdentification
from bhgrasp.controllers.object_space import ObjectSpaceController
from bhgrasp.errors import InputError
from bhgrasp.model.objects import Box
from bhgrasp.scenarios.demo_result import MU_ASSUMED

CONTROLLERS = ("smc-adaptive", "ctc", "natural", "stiffness", "pd")
ADAPTATIONS = (
    "thesis",
    "composite",
)  # the SMC-adaptive law's object estimate: (5.52) alone, or with the measured wrench
COMPOSITE_RATES = (5.0, 1e-3)  # Gamma_o = P(0) of the composite law: mass, inertia (chapter 5's adaptation case)
SQUEEZE = 5.0  # [N] desired normal force per contact (the thesis' 5 N)


def grasp_controller(
    name: str,
    hand,
    nominal_box: Box,
    distribution: str = "qp",
    gains: tuple[Any, Any] | None = None,
    mu: float = MU_ASSUMED,
    adaptation: str = "thesis",
    friction_margin: float | None = None,
    torque_limit: Any = None,
) -> ObjectGraspController:
    """The object-space controller called ``name`` (one of :data:`CONTROLLERS`) with the demo's gains.

    ``gains`` = (kp, kv) overrides the gains of "ctc", "natural" and "stiffness"; ``mu`` is the friction
    coefficient the force distribution assumes; ``adaptation`` (one of :data:`ADAPTATIONS`, "smc-adaptive" only):
    "composite" adds the measured wrench's prediction error
    (:class:`~bhgrasp.controllers.object_identification.ObjectIdentification`, Gamma_o = :data:`COMPOSITE_RATES`);
    ``friction_margin`` the fraction of ``mu`` kept in reserve
    (:class:`~bhgrasp.controllers.grasp_options.GraspOptions`); ``torque_limit`` [N m] the joints' limit the
    controller keeps within (``None``: none).
    """
    options = GraspOptions(
        mu=mu, squeeze=SQUEEZE, distribution=distribution, friction_margin=friction_margin, torque_limit=torque_limit
    )
    shared = {"options": options}
    if adaptation not in ADAPTATIONS:
        raise InputError(f"`adaptation` must be one of {ADAPTATIONS}, got {adaptation!r}")
    if adaptation == "composite" and name != "smc-adaptive":
        raise InputError(f"`adaptation='composite'` applies to the 'smc-adaptive' controller, not {name!r}")
    if name == "smc-adaptive" and adaptation == "composite":
        return SMCAdaptiveGrasp(
            hand, nominal_box, object_adaptation=COMPOSITE_RATES, identification=ObjectIdentification(), **shared
        )
    if name == "smc-adaptive":
        return SMCAdaptiveGrasp(hand, nominal_box, **shared)
    if name == "pd":
        return GraspForceController(hand, nominal_box.mass, **shared)
    if name == "ctc":
        kp, kv = gains or (2500.0, 100.0)
        return ObjectSpaceController(hand, nominal_box, "ctc", kp=kp, kv=kv, **shared)
    if name in ("natural", "stiffness"):
        kp, kv = gains or ((400.0, 0.5), (8.0, 0.01))
        return ObjectSpaceController(hand, nominal_box, name, kp=kp, kv=kv, **shared)
    raise InputError(f"`controller` must be one of {CONTROLLERS}, got {name!r}")


__all__ = ["ADAPTATIONS", "COMPOSITE_RATES", "CONTROLLERS", "SQUEEZE", "grasp_controller"]
