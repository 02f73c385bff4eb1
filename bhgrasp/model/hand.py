"""Hand: a robot hand loaded into Pinocchio, with kinematics, Jacobians and rigid-body dynamics.

Conventions: SI units and radians; ``q`` (size ``nq``) and ``v`` (size ``nv``) in Pinocchio's joint order
(:attr:`Hand.joint_names`).  "World" is the frame the hand base is placed in by :attr:`Hand.base_placement`
(identity by default, so world = hand base frame W); gravity is given in world coordinates.

A :class:`Hand` is built in layers, one module each: :class:`~bhgrasp.model.hand_model.HandModel` (model and data,
fingertip frames, names, sizes, limits, world placement, gravity, configurations),
:class:`~bhgrasp.model.hand_kinematics.HandKinematics` (frame poses, fingertip positions, Jacobians),
:class:`~bhgrasp.model.hand_dynamics.HandDynamics` (CRBA, RNEA, ABA, Coriolis, external forces, regressors) and this
module (loading a URDF, collision shapes, perturbed copies, the summary, the packaged :class:`BarrettHand`).  A
URDF is read and its inertias checked by :mod:`bhgrasp.model.urdf`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_vector
from bhgrasp.errors import InputError, ModelError
from bhgrasp.model.hand_dynamics import HandDynamics
from bhgrasp.model.hand_model import STANDARD_GRAVITY
from bhgrasp.model.resources import barrett_urdf_path, leaf_links
from bhgrasp.model.urdf import _build_model

BARRETT_FINGERTIPS = {"F1": "F1_tip", "F2": "F2_tip", "F3": "F3_tip"}


class Hand(HandDynamics):
    """A fixed-base hand: Pinocchio model and data, fingertip frames, limits, kinematics and dynamics.

    Every method takes the configuration explicitly and validates its inputs (shape, finiteness); results are
    fresh arrays that the caller may keep.  One :class:`pinocchio.Data` is reused between calls, so a ``Hand``
    is not thread-safe: give each thread or process its own (``copy.deepcopy`` works).
    """

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_urdf(
        cls,
        path: str | Path,
        fingertips: Sequence[str] | Mapping[str, str] | None = None,
        mimic: str = "coupled",
        **kwargs: Any,
    ) -> Hand:
        """Load any fixed-base hand URDF.

        A joint with a ``<mimic joint multiplier offset>`` tag is coupled as Pinocchio builds it (``mimic="coupled"``):
        it has no coordinate of its own and moves as ``multiplier * q[joint] + offset``, so ``nq`` and ``nv`` count
        the independent joints (:attr:`couplings` lists the others, :mod:`bhgrasp.model.couplings` says how dynamics and
        pickles treat them).  ``mimic="independent"`` loads every joint as its own DOF (the coupling is then up to an
        actuation model, as :class:`~bhgrasp.sim.actuation.BarrettActuation` does for the BH8-280's).

        Args:
            path: URDF file.  It is parsed without DTDs or entities before Pinocchio sees it.
            fingertips: Frame names of the fingertips (finger name = frame name), or a mapping finger name ->
                frame name; by default the URDF's leaf links below a moving joint
                (:func:`~bhgrasp.model.resources.leaf_links`: a palm pad fixed to the base is not a fingertip).
            mimic: ``"coupled"`` (default) or ``"independent"``, as above.
            **kwargs: ``name``, ``base_placement``, ``gravity`` as for :class:`Hand`.

        Raises:
            ModelError: Missing/malformed/unsafe/non-UTF-8 URDF, one Pinocchio cannot build (e.g. a mimic joint that
                mimics a mimic joint), or an ``<inertial>``
                no rigid body has: mass missing, NaN/inf or < 0; an inertia component missing or NaN/inf; a tensor
                that is not positive semi-definite or whose ixx, iyy, izz break the triangle inequality (the
                message names the file and the link).  Point masses and massless links are legal.
            InputError: A fingertip frame that the model does not have, or ``mimic`` not one of the two.

        Warns:
            UserWarning: A link whose principal moments of inertia break the triangle inequality although its
                diagonal does not (products of inertia no body has, e.g. example-robot-data's Allegro fingertips).
        """
        if mimic not in ("coupled", "independent"):
            raise InputError(f"`mimic` must be 'coupled' or 'independent', got {mimic!r}")
        model, root = _build_model(path, mimic=mimic == "coupled")
        if fingertips is None:
            fingertips = leaf_links(root)
            if not fingertips:
                raise ModelError(f"URDF {str(path)!r} has no leaf links to use as fingertips; pass `fingertips`")
        if not isinstance(fingertips, Mapping):
            fingertips = {frame: frame for frame in fingertips}
        return Hand(model, fingertips, urdf_path=Path(path), **kwargs)

    def collision_model(self) -> pin.GeometryModel:
        """A copy of the hand's collision shapes on its own model (``collision_geometry``, else its URDF's, else none).

        Raises:
            ModelError: The URDF's collision geometry does not load.
        """
        if self.collision_geometry is not None:
            return self.collision_geometry.copy()
        path = self.urdf_path
        if path is None:
            return pin.GeometryModel()
        try:
            return pin.buildGeomFromUrdfString(
                self._model, path.read_text(), pin.GeometryType.COLLISION, None, [str(p) for p in path.parents]
            )
        except (ValueError, RuntimeError, OSError) as error:
            raise ModelError(f"cannot load the collision geometry of {str(path)!r}: {error}") from error

    # ------------------------------------------------------------------ model errors
    def perturbed(
        self,
        mass_scale: float | Sequence[float] = 1.0,
        payload: tuple[str, float] | None = None,
        name: str | None = None,
    ) -> Hand:
        """A copy of this hand with different inertial parameters: a controller's nominal model, or a plant.

        Kinematics, limits and fingertips are unchanged; the copy has its own Pinocchio model and data.

        Args:
            mass_scale: Factor on each moving body's mass and rotational inertia (centre of mass unchanged): one
                number, or one per body in joint order (``nv`` values for a hand of 1-DOF joints, plus one per mimic
                joint).  0.7 is a nominal model that underestimates every body by 30 %.
            payload: ``(frame, mass [kg])``: a point mass rigidly attached at that frame's origin, e.g. an unknown
                load at a fingertip.
            name: Display name (default: this hand's name with the perturbation).

        Raises:
            InputError: Non-positive or non-finite scales, a negative payload, or an unknown frame.
        """
        n_bodies = self._model.njoints - 1
        uniform = np.ndim(mass_scale) == 0
        scales = as_vector(np.full(n_bodies, mass_scale) if uniform else mass_scale, "mass_scale", n_bodies)
        if np.any(scales <= 0.0):
            raise InputError(f"`mass_scale` must be positive and finite, got {mass_scale!r}")
        model = pin.Model(self._model)
        for joint, scale in enumerate(scales, start=1):
            inertia = model.inertias[joint]
            model.inertias[joint] = pin.Inertia(scale * inertia.mass, inertia.lever.copy(), scale * inertia.inertia)
        label = f"mass x{float(mass_scale):g}" if uniform else "masses scaled"
        if payload is not None:
            frame, mass = payload
            frame_id = self._frame_id(frame)
            mass = float(mass)
            if not np.isfinite(mass) or mass < 0.0:
                raise InputError(f"payload mass must be a finite number >= 0 [kg], got {payload[1]!r}")
            placement = model.frames[frame_id].placement  # frame in its parent joint's frame
            joint = model.frames[frame_id].parentJoint
            point = pin.Inertia(mass, placement.translation.copy(), np.zeros((3, 3)))
            model.inertias[joint] = model.inertias[joint] + point
            label += f", {mass:g} kg at {frame}"
        return Hand(
            model,
            self._fingertips,
            name=name or f"{self.name} ({label})",
            base_placement=self.base_placement,
            gravity=self.gravity,
            urdf_path=self.urdf_path,
            collision_geometry=self.collision_geometry,
            base_joints=self.base_joints,
        )

    # ------------------------------------------------------------------ display
    def summary(self) -> str:
        """A human-readable table of joints, limits, fingers and mass."""
        lines = [f"{self.name}: {self.nv} joints, {len(self.fingers)} fingers, {self.total_mass:.4f} kg"]
        lines.append(
            f"  {'joint':<16}{'lower':>9}{'upper':>9}  [deg]{'vel':>8} [rad/s]{'effort':>8} [N m]{'link mass':>11} [kg]"
        )
        for i, joint in enumerate(self.joint_names):
            joint_id = self._model.getJointId(joint)
            mass = self._model.inertias[joint_id].mass
            prismatic = self._model.joints[joint_id].shortname().startswith("JointModelP")
            limits = (
                f"{self.lower[i]:9.3f}{self.upper[i]:9.3f}"
                if prismatic  # a sliding joint: [m], [m/s], [N]
                else f"{np.degrees(self.lower[i]):9.1f}{np.degrees(self.upper[i]):9.1f}"
            )
            lines.append(
                f"  {joint:<16}{limits}{self.velocity_limit[i]:13.3f}{self.effort_limit[i]:15.3f}{mass:14.4f}"
                + "  [m, N]" * prismatic
            )
        for coupling in self.couplings:
            lines.append(f"  mimic {coupling.joint}: {coupling.multiplier:g} x {coupling.mimics} + {coupling.offset:g}")
        for finger in self.fingers:
            lines.append(
                f"  finger {finger}: tip {self._fingertips[finger]!r}, joints {', '.join(self.finger_joints(finger))}"
            )
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"Hand({self.name!r}, nq={self.nq}, fingers={self.fingers})"


class BarrettHand(Hand):
    """The packaged Barrett BH8-280 (``urdf/barrett_hand.urdf``): 8 independent joints, fingers F1, F2, F3.

    Joint order: F1_spread, F1_proximal, F1_distal, F2_spread, F2_proximal, F2_distal, F3_proximal, F3_distal.
    """

    def __init__(
        self,
        *,
        base_placement: pin.SE3 | None = None,
        gravity: Sequence[float] = STANDARD_GRAVITY,
        name: str = "BarrettHand BH8-280",
    ) -> None:
        """Load the packaged URDF; ``base_placement`` and ``gravity`` as for :class:`Hand`."""
        path = barrett_urdf_path()
        model, _ = _build_model(path)
        super().__init__(
            model, BARRETT_FINGERTIPS, name=name, base_placement=base_placement, gravity=gravity, urdf_path=path
        )
