"""The SMC-adaptive grasp controller of thesis 5.6, (5.46)-(5.60): object and hand parameters learnt online.

Object level (world, COM): e = (x - x_d, log(R R_d^T)), v_r = X_dot_d - rho e (5.46), a_r = X_dd_d - rho e_dot,
s_o = X_dot - v_r.  The desired object wrench is F_do = Y_o(R, omega, v_r, a_r) sigma_o - k_o s_o (5.49)-(5.51) with
sigma_o = (m, I_xx, I_xy, I_xz, I_yy, I_yz, I_zz) (body-frame inertia about the COM) and

    Y_o sigma_o = [m (a_r,v - g);  I_w alpha_r + C(omega, I_w) omega_r],
    C(omega, I_w) = (skew(omega) I_w - I_w skew(omega) - skew(I_w omega)) / 2,   I_w = R I R^T,

a Coriolis form for which M_o_dot - 2 C_o = skew(I_w omega) is skew-symmetric, as the Lyapunov argument (5.63)
needs.  The estimate follows sigma_o_dot = -Gamma_o Y_o^T s_o (the thesis prints (5.52) without the sign and with
Gamma^-1; with s_o = X_dot - v_r the minus sign is the one that makes V_dot <= 0).  The desired contact forces are
F_dc = QP(G, F_do) (inside the friction cones, closest to the squeeze, which a friction margin raises with the
measured load) or the thesis' (5.53) G^+ F_do + (I - G^+ G) f_squeeze (``GraspOptions(distribution="pinv")``).

Finger level: with P = J_h^+ G^T (J_h^-1 G^T of (5.55) for square J_h), the reference joint velocity (5.57) is
q_dot_r = P v_r + J_h^+ (c e_fc + h eta), e_fc = F_dc - F_c the contact force error (measured, contact frames;
``force_error="normal"`` keeps only its normal components) and eta its integral; s_f = q_dot - q_dot_r (5.59) and

    tau = Y_f(q, q_dot, q_dot_r, q_dd_r) sigma_f + J_h^T F_dc - k_f s_f        (5.58)

with q_dd_r = P a_r + P_dot v_r (the force terms are not differentiated) and, when ``hand_adaptation`` is given,
sigma_f_dot = -Gamma_f Y_f^T s_f (5.60) over the hand's Pinocchio inertial parameters (10 per body), with
Gamma_f = gamma_f diag(scale^2) relative to each parameter's natural size (chapter 3's
:func:`~bhgrasp.controllers.sliding.parameter_scales`: one gamma_f suits heavy and light links alike).

Two engines: ``"compiled"`` runs a grasp cycle in one call of ``bhgrasp._core.SMCAdaptiveLaw`` (``src/smc_law.cpp``,
glued in :mod:`bhgrasp.controllers._smc_law`), ``"python"`` runs the code below (the readable twin;
``tests/test_smc_law_twin.py`` holds the two equal to round-off).  The compiled law covers ``hand_adaptation=None``
and ``options.distribution="qp"`` (either ``force_error``); other options run the Python code.
"""

from __future__ import annotations

import math
from functools import partial
from typing import Any

import numpy as np

from bhgrasp._native import engine_name, required_core
from bhgrasp._validation import as_positive, as_real, as_vector
from bhgrasp.controllers._smc_law import CompiledSMCLaw, compiled_state, restore_compiled, uncovered_options
from bhgrasp.controllers.base import gain_vector
from bhgrasp.controllers.compiled_control import CompiledControl, held_rows
from bhgrasp.controllers.grasp_options import DEFAULT_GRASP, GraspOptions
from bhgrasp.controllers.grasping import GraspContacts, ObjectGraspController
from bhgrasp.controllers.object_identification import ObjectIdentification
from bhgrasp.controllers.object_regressors import object_parameters, object_regressor, object_regressor_python
from bhgrasp.controllers.object_space import grasp_maps, pose_gains
from bhgrasp.controllers.sliding import parameter_scales
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand
from bhgrasp.model.objects import RigidObject
from bhgrasp.motion.trajectories import Reference


class SMCAdaptiveGrasp(ObjectGraspController):
    """Thesis (5.46)-(5.60): adaptive object wrench, QP contact forces, sliding finger law with force PI.

    Logs, besides the base's: ``object_parameters`` (sigma_o estimate), ``mass_estimate`` [kg], ``object_sliding``
    (s_o), ``joint_sliding`` (s_f, zeros without a grasp), ``force_error`` (e_fc per touching finger's contact,
    contact frame, in finger order of the hand; zeros for fingers not touching), ``desired_force`` (F_dc, same
    layout) [N].

    :attr:`engine` says which engine runs (module docstring).  The compiled one reads the gains and ``force_error``
    when it is built and at every :meth:`reset` (the Python one at every call); the shared :attr:`options` are fixed
    for the controller's life; ``reference`` is read at every call by both (the compiled one copies a ``PoseMotion``'s
    or ``PosePath``'s moves the first time it meets that object: a path is fixed once built).
    """

    def __init__(
        self,
        nominal: Hand,
        nominal_object: RigidObject,
        reference: Reference | None = None,
        rho: float = 50.0,
        k_o: Any = (8.0, 0.01),
        object_adaptation: Any = (5.0, 0.0),
        force_gain: float = 0.02,
        force_integral: float = 1.0,
        k_f: Any = 0.05,
        hand_adaptation: float | None = None,
        force_error: str = "normal",
        options: GraspOptions = DEFAULT_GRASP,
        engine: str | None = None,
        identification: ObjectIdentification | None = None,
    ) -> None:
        """Set up the controller.

        Args:
            nominal: The controller's hand model (its parameters start sigma_f).
            nominal_object: Initial object estimate (mass, inertia about the COM): sigma_o(0).
            reference: Object pose reference of size 6; ``None`` holds the pose where the grasp closed.
            rho: rho [1/s] of (5.46): the sliding surface's bandwidth.
            k_o: Object gains on s_o (translation [N s/m], rotation [N m s/rad]; scalar, pair or six): with rho
                they make a PD of stiffness k_o rho.
            object_adaptation: Gamma_o as (mass rate, inertia rate) or seven rates; 0 freezes a parameter.
            force_gain: c [m/s / N] of (5.57).
            force_integral: h [m/s / (N s)] of (5.57).
            k_f: Joint gain k_f [N m s/rad] of (5.58), scalar or per joint.
            hand_adaptation: gamma_f [1/(N m rad)] of (5.60), relative to each parameter's scale (module
                docstring), or ``None`` (hand model fixed).
            force_error: ``"normal"`` (feed back the normal force errors) or ``"full"`` (all three components, as
                printed in (5.57)).
            options: The shared options (:class:`~bhgrasp.controllers.grasp_options.GraspOptions`), as in
                :class:`~bhgrasp.controllers.grasping.ObjectGraspController`.
            engine: ``None`` (default): the default engine (:func:`~bhgrasp._native.default_engine`) where the
                compiled law covers the options (``hand_adaptation=None``, ``options.distribution="qp"``, no
                ``options.torque_limit``, no subclass overriding a step of the law), else the Python one;
                ``"compiled"`` (raises if the core does not load or the law does not cover the options) or
                ``"python"``.
            identification: Composite adaptation of sigma_o
                (:class:`~bhgrasp.controllers.object_identification.ObjectIdentification`: the measured contact
                wrench's prediction error joins (5.52), P(0) = Gamma_o); ``None``: the thesis' law (5.52) alone.

        Raises:
            InputError: A bad argument, or ``engine="compiled"`` with options it does not cover.
            CompiledEngineUnavailable: ``engine="compiled"`` but ``bhgrasp._core`` does not load.
        """
        super().__init__(nominal, reference, options)
        if not isinstance(nominal_object, RigidObject):
            raise InputError(f"`nominal_object` must be a bhgrasp RigidObject (e.g. Box), got {nominal_object!r}")
        if force_error not in ("normal", "full"):
            raise InputError(f"`force_error` must be 'normal' or 'full', got {force_error!r}")
        self.nominal_object = nominal_object
        self.rho = as_positive(rho, "rho")
        self.k_o = pose_gains(k_o, "k_o")
        rates = np.asarray(object_adaptation, dtype=float)
        self.object_adaptation = gain_vector(
            np.repeat(rates, (1, 6)) if rates.shape == (2,) else rates, 7, "object_adaptation", allow_zero=True
        )
        self.force_gain = as_real(force_gain, "force_gain")
        self.force_integral = as_real(force_integral, "force_integral")
        if self.force_gain < 0.0 or self.force_integral < 0.0:
            raise InputError(f"`force_gain` and `force_integral` must be >= 0, got {force_gain}, {force_integral}")
        self.k_f = gain_vector(k_f, nominal.nv, "k_f")
        self.hand_adaptation = None if hand_adaptation is None else as_positive(hand_adaptation, "hand_adaptation")
        self._hand_rates = None if hand_adaptation is None else self.hand_adaptation * parameter_scales(nominal) ** 2
        self.force_error = force_error
        chosen = engine_name(engine)
        self._compiled: CompiledSMCLaw | None = None
        self._initial_object = object_parameters(nominal_object.mass, nominal_object.inertia)
        self.object_estimate = self._initial_object.copy()
        self.hand_estimate = nominal.inertial_parameters()
        self._integral: dict[str, np.ndarray] = {}
        if identification is not None and not isinstance(identification, ObjectIdentification):
            raise InputError(f"`identification` must be an ObjectIdentification or None, got {identification!r}")
        self.identification = identification
        if identification is not None:
            identification.bind(nominal, self.object_adaptation)
        uncovered = uncovered_options(self, SMCAdaptiveGrasp)
        if engine == "compiled" and uncovered:
            raise InputError(f"engine='compiled' does not cover {uncovered}; pass engine='python' (or None)")
        if chosen == "compiled" and not uncovered:
            self._compiled = CompiledSMCLaw(self, required_core("the compiled SMC-adaptive law"))
        self.engine = "python" if self._compiled is None else "compiled"

    def __getstate__(self) -> dict:
        """Copies and pickles rebuild the compiled law; refused once it has run grasp cycles since :meth:`reset`."""
        return compiled_state(self, self.__dict__.copy())

    def __setstate__(self, state: dict) -> None:
        """Restore a copy, building its own compiled law if the original had one."""
        restore_compiled(self, state)

    @property
    def object_estimate(self) -> np.ndarray:
        """sigma_o = (m [kg], I_xx, I_xy, I_xz, I_yy, I_yz, I_zz [kg m^2], body frame, COM), the object estimate.

        On the compiled engine a copy (the estimate lives in C++): assign the whole vector to change it.
        """
        return self._object_estimate if self._compiled is None else self._compiled.kernel.object_estimate

    @object_estimate.setter
    def object_estimate(self, value: Any) -> None:
        if self._compiled is None:
            self._object_estimate = value
        else:
            self._compiled.kernel.object_estimate = as_vector(value, "object_estimate", 7)

    def reset(self, state: State) -> None:
        """Restart the estimates from the nominal models and clear the force integrals."""
        super().reset(state)
        self.object_estimate = self._initial_object.copy()
        self.hand_estimate = self.nominal.inertial_parameters()
        self._integral.clear()
        if self.identification is not None:
            self.identification.reset()
        if self._compiled is not None:
            self._compiled.configure(self)  # also resets the compiled law's estimate, integrals and QPs

    def compiled_control(self, t: float, state: State) -> CompiledControl | None:
        """The grasp cycles from ``state`` on as a compiled loop for :meth:`Simulator.run`, or ``None``.

        Offered by the compiled law for a state a compiled step made, once a grasp is under way toward a minimum-jerk
        pose path (:meth:`CompiledSMCLaw.loop <bhgrasp.controllers._smc_law.CompiledSMCLaw.loop>`); the loop hands a
        cycle with fewer than two fingers touching back to :meth:`__call__`.
        """
        compiled = self._compiled
        if compiled is None or type(self).__call__ is not SMCAdaptiveGrasp.__call__:
            return None
        loop = compiled.loop(self, state)
        if loop is None:
            return None

        def log_rows(rows: np.ndarray, q_hand: np.ndarray) -> dict[str, np.ndarray]:
            entries = held_rows(self.log, len(rows))
            entries.update(compiled.log_rows(rows))
            return entries

        def settle(run: Any, q_hand: np.ndarray) -> None:
            compiled.settle(self, loop, run, len(q_hand))

        return CompiledControl(loop, math.inf, log_rows, settle, lambda run, after: compiled.fail(self, run, after))

    def __call__(self, t: float, state: State) -> np.ndarray:
        """Joint torques [N m]; before the grasp the base closes the fingers."""
        if self._compiled is not None:
            return self._compiled(self, t, state)
        n = len(self.nominal.fingers)
        self.log["joint_sliding"] = np.zeros(self.nominal.nv)
        self.log["force_error"] = self.log["desired_force"] = np.zeros((n, 3))
        self.log["object_sliding"] = np.zeros(6)
        self.log["object_parameters"], self.log["mass_estimate"] = self.object_estimate, self.object_estimate[:1]
        return super().__call__(t, state)

    def grasp_torques(self, t: float, dt: float, state: State, contacts: GraspContacts) -> np.ndarray:
        """Thesis (5.46)-(5.60)."""
        hand = self.nominal
        current, maps = grasp_maps(hand, state, contacts, self.nominal_object)
        contacts.reference = current.com
        wrench, regressor, s_o, v_r, a_r = self.object_law(t, dt, state)
        desired = self.distribute(contacts, wrench)
        finger_law = partial(self._finger_law, dt, state, contacts, maps, v_r, a_r)
        evaluated: dict[int, tuple] = {}  # the law's result for forces limit_squeeze evaluated, by their array

        def torques_of(forces: np.ndarray) -> np.ndarray:
            evaluated[id(forces)] = (forces, finger_law(forces))
            return evaluated[id(forces)][1][0]

        limited = self.limit_squeeze(contacts, desired, torques_of)
        known = evaluated.get(id(limited))  # left unchanged: the law already ran for them
        result = known[1] if known is not None and known[0] is limited else finger_law(limited)
        tau, integral, force_error, s_f, hand_estimate = result
        desired = limited
        self._integral = dict(zip(contacts.fingers, integral))
        if hand_estimate is not None:
            self.hand_estimate = hand_estimate
        if self.identification is not None:  # after the cycle, as the compiled engine does it
            self.identify(dt, state, regressor, s_o)
        self._log(contacts, s_o, s_f, force_error, desired)
        return tau

    def _finger_law(self, dt: float, state: State, contacts: GraspContacts, maps: Any, v_r, a_r, desired) -> tuple:
        """(5.57)-(5.60) for the desired contact forces (n, 3) [N], without side effects.

        Returns (tau, the force errors' integrals, e_fc, s_f, the hand estimate after (5.60) or ``None``).
        """
        hand = self.nominal
        force_error = desired - contacts.measured()
        if self.force_error == "normal":
            force_error[:, :2] = 0.0
        integral = np.array([self._integral.get(f, np.zeros(3)) for f in contacts.fingers]) + dt * force_error
        correction = self.force_gain * force_error + self.force_integral * integral
        q_dot_r = maps.joint_map @ v_r + maps.hand_jacobian_pinv @ correction.ravel()
        q_dd_r = maps.joint_map @ a_r + maps.joint_map_rate @ v_r
        s_f = np.asarray(state.v, dtype=float) - q_dot_r
        hand_estimate = None
        if self.hand_adaptation is None:
            model = hand.slotine_li_torque(state.q, state.v, q_dot_r, q_dd_r)
        else:
            y_f = hand.slotine_li_regressor(state.q, state.v, q_dot_r, q_dd_r)
            hand_estimate = self.hand_estimate - dt * self._hand_rates * (y_f.T @ s_f)
            model = y_f @ hand_estimate
        tau = model + maps.hand_jacobian.T @ desired.ravel() - self.k_f * s_f
        return tau, integral, force_error, s_f, hand_estimate

    def parameter_information(self) -> np.ndarray:
        """P^-1 (7, 7) weighing the object estimate's error in V (5.63) (:mod:`bhgrasp.controllers.grasp_lyapunov`).

        Gamma_o^-1 for (5.52), the composite law's information with ``identification``; zero rows and columns for
        the parameters held fixed.
        """
        if self.identification is not None:
            return self.identification.information_matrix()
        rates = self.object_adaptation
        return np.diag(np.divide(1.0, rates, out=np.zeros(7), where=rates > 0.0))

    def object_law(self, t: float, dt: float, state: State) -> tuple[np.ndarray, ...]:
        """(5.46)-(5.52): the desired object wrench F_do, Y_o, s_o, v_r and a_r (world, COM) of a cycle of ``dt`` [s].

        Updates the estimate by (5.52) first (without ``identification``; with it :meth:`identify` runs after the
        cycle).  Reads only the object's pose and twist from ``state`` (the ideal-loop tests drive it alone).
        """
        rotation, twist = state.object_poses[0].rotation, np.asarray(state.object_twists[0], dtype=float)
        error, velocity_error, velocity, acceleration = self.errors(t, state)
        v_r, a_r = velocity - self.rho * error, acceleration - self.rho * velocity_error
        s_o = twist - v_r
        regressor = object_regressor(rotation, twist, v_r, a_r, self.gravity)
        if self.identification is None:
            self.object_estimate = self.object_estimate - dt * self.object_adaptation * (regressor.T @ s_o)
            self.object_estimate[0] = max(self.object_estimate[0], 1e-3)  # projection: a mass stays positive
        return regressor @ self.object_estimate - self.k_o * s_o, regressor, s_o, v_r, a_r

    def identify(self, dt: float, state: State, regressor: np.ndarray, s_o: np.ndarray, measured=None) -> None:
        """Composite update of the object estimate after a grasp cycle (``identification`` set; both engines).

        ``measured`` = (wrench (6,), free) replaces the wrench and support read from the state's contacts.
        """
        if measured is None:
            estimate = self.identification.update(self.object_estimate, dt, state, regressor, s_o, self.gravity)
        else:
            pose, (wrench, free) = state.object_poses[0], measured
            estimate = self.identification.step(
                self.object_estimate,
                dt,
                pose.rotation,
                state.object_twists[0],
                wrench,
                free,
                regressor,
                s_o,
                self.gravity,
            )
        estimate[0] = max(estimate[0], 1e-3)  # projection: a mass stays positive
        self.object_estimate = estimate
        self.log.update(self.identification.log())

    def _log(self, contacts: GraspContacts, s_o, s_f, force_error, desired) -> None:
        per_finger_error, per_finger_desired = np.zeros((2, len(self.nominal.fingers), 3))
        for k, finger in enumerate(contacts.fingers):
            index = self.nominal.fingers.index(finger)
            per_finger_error[index], per_finger_desired[index] = force_error[k], desired[k]
        self.log.update(
            object_sliding=s_o,
            joint_sliding=s_f,
            force_error=per_finger_error,
            desired_force=per_finger_desired,
            object_parameters=self.object_estimate,
            mass_estimate=self.object_estimate[:1],
        )


__all__ = ["SMCAdaptiveGrasp", "object_parameters", "object_regressor", "object_regressor_python"]
