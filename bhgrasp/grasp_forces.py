"""Moved to :mod:`bhgrasp.grasp.forces` (the contact-force QP); this module re-exports its public names."""

from bhgrasp.grasp.forces import (  # noqa: F401  (the constants, as before)
    ADMISSIBLE_TOLERANCE,
    CHECK_ITER,
    DOUBTFUL_ERROR,
    DUALITY_GAP_REL,
    ENGINES,
    FEASIBLE_RESIDUAL,
    NEAREST_WEIGHT,
    PRIMAL_INFEASIBILITY,
    ContactForceQP,
    ContactForceQPPython,
    ContactForceResult,
    cone_violations,
    internal_forces,
    pseudo_inverse_forces,
    solver_arguments,
)

__all__ = ["ContactForceQP", "ContactForceResult", "cone_violations", "internal_forces", "pseudo_inverse_forces"]
