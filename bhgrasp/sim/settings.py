"""A simulator's settings: the step, the integrator, the joint stops and the divergence bounds, frozen once built.

A :class:`~bhgrasp.sim.simulator.Simulator` reads its settings once, when it is built, and gives them to its engine;
changing one means building a new Simulator (``Simulator(scene, dt=2e-3, ...)``), so the engine and the simulator
can never disagree about them.
"""

from __future__ import annotations

from dataclasses import dataclass

from bhgrasp._native import ENGINES, engine_name
from bhgrasp._validation import as_positive, as_real
from bhgrasp.errors import InputError

INTEGRATORS = ("implicit", "semi-implicit", "rk4")
START_CHECKS = ("warn", "error", "off")  # what an initial state that starts wrong does
LINEAR_SOLVERS = ("auto", "dense", "sparse")  # how the implicit step solves for the velocities
SPARSE_FROM = 32  # [velocities] "auto" goes sparse from here: the compiled step measured faster (bench_linear_solver)


@dataclass(frozen=True)
class SimulatorSettings:
    """What a Simulator steps with, beside its scene, contact law and actuation (immutable).

    Attributes:
        dt: Physics step [s].
        integrator: ``"implicit"``, ``"semi-implicit"`` or ``"rk4"``.
        joint_limit_stiffness: Stiffness [N m/rad] of the hand's joint stops.
        joint_limit_damping: Damping [N m s/rad] of the stops (acts only while a stop is penetrated).
        max_penetration: Contact depth [m] beyond which a run is declared diverged.
        max_speed: Joint or object speed [m/s or rad/s] beyond which a run is declared diverged.
        max_coordinate: Largest |coordinate| [m or rad] of a scene configuration: a state beyond it is refused
            and a step that reaches it has diverged (collision queries lose all precision far out, and coal's
            narrow phase crashes near 1e155 m).
        engine: ``"compiled"`` (the C++ step of ``bhgrasp._core``) or ``"python"`` (the readable reference);
            ``None`` is stored as the default engine (:func:`~bhgrasp._native.default_engine`).
        start_check: What an initial state that starts wrong (:mod:`~bhgrasp.sim.start_check`: bodies
            interpenetrating, objects the step cannot resolve) does: ``"warn"`` (a ``StartWarning``), ``"error"``
            (an ``InputError``) or ``"off"``.
        linear_solver: How the implicit step solves for the velocities: ``"dense"`` (one matrix of the whole scene, a
            Cholesky factorisation), ``"sparse"`` (by parts, :mod:`~bhgrasp.sim.part_system`: cost linear in objects
            and contacts; the implicit integrator only) or ``"auto"`` (sparse for scenes of :data:`SPARSE_FROM`
            velocities or more under the implicit integrator, dense otherwise; the threshold was measured on the
            compiled engine and the Python one follows it).  The two agree to round-off.
    """

    dt: float = 1e-3
    integrator: str = "implicit"
    joint_limit_stiffness: float = 1e3
    joint_limit_damping: float = 0.05
    max_penetration: float = 0.02
    max_speed: float = 100.0
    max_coordinate: float = 1e4
    engine: str | None = None
    start_check: str = "warn"
    linear_solver: str = "auto"

    def __post_init__(self) -> None:
        """Check every setting and store it as a float (or one of the allowed names)."""
        if self.integrator not in INTEGRATORS:
            raise InputError(f"`integrator` must be one of {INTEGRATORS}, got {self.integrator!r}")
        object.__setattr__(self, "engine", engine_name(self.engine))
        if self.start_check not in START_CHECKS:
            raise InputError(f"`start_check` must be one of {START_CHECKS}, got {self.start_check!r}")
        if self.linear_solver not in LINEAR_SOLVERS:
            raise InputError(f"`linear_solver` must be one of {LINEAR_SOLVERS}, got {self.linear_solver!r}")
        if self.linear_solver == "sparse" and self.integrator != "implicit":
            raise InputError(
                f"`linear_solver` 'sparse' serves the implicit integrator only, got integrator {self.integrator!r}: "
                "use linear_solver='dense' (or 'auto') with it"
            )
        for name in ("dt", "joint_limit_stiffness", "max_penetration", "max_speed", "max_coordinate"):
            object.__setattr__(self, name, as_positive(getattr(self, name), name))
        object.__setattr__(self, "joint_limit_damping", as_real(self.joint_limit_damping, "joint_limit_damping"))

    def solves_sparse(self, nv: int) -> bool:
        """Whether a scene of ``nv`` velocities is solved sparse (:attr:`linear_solver`)."""
        if self.linear_solver == "auto":
            return self.integrator == "implicit" and nv >= SPARSE_FROM
        return self.linear_solver == "sparse"


__all__ = ["ENGINES", "INTEGRATORS", "LINEAR_SOLVERS", "SPARSE_FROM", "START_CHECKS", "SimulatorSettings"]
