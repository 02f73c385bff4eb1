"""A URDF as a Pinocchio model, read safely and with every inertia checked; a hand from a URDF, its collision shapes.

:func:`build_model` reads a URDF without DTDs or entities (:func:`~bhgrasp.model.resources.read_urdf`), refuses
``<inertial>`` blocks that urdfdom would silently drop or that no rigid body can have, builds the model (``<mimic>``
tags applied as Pinocchio's mimic joints, or ignored: independent joints) and checks the inertias Pinocchio built
(links merged across fixed joints).  :func:`hand_from_urdf` is :meth:`Hand.from_urdf
<bhgrasp.model.hand.Hand.from_urdf>`, :func:`collision_model` is :meth:`Hand.collision_model
<bhgrasp.model.hand.Hand.collision_model>`.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp.errors import InputError, ModelError
from bhgrasp.model.hand_description import HandDescription as Hand
from bhgrasp.model.resources import leaf_links, read_urdf


def build_model(path: str | Path, mimic: bool = False) -> tuple[pin.Model, Any]:
    """Safely read a URDF and build its Pinocchio model (``mimic``: ``<mimic>`` tags applied, else ignored)."""
    text, root = read_urdf(path)
    _check_inertials(root, path)
    try:
        model = pin.buildModelFromXML(text, mimic=mimic)
    except (ValueError, RuntimeError) as error:
        raise ModelError(f"Pinocchio cannot build a model from {str(path)!r}: {error}") from error
    if model.nv == 0:
        raise ModelError(f"URDF {str(path)!r} has no moving joints")
    _check_model_inertias(model, path)
    return model, root


def hand_from_urdf(
    cls: type[Hand],
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
    model, root = build_model(path, mimic=mimic == "coupled")
    if fingertips is None:
        fingertips = leaf_links(root)
        if not fingertips:
            raise ModelError(f"URDF {str(path)!r} has no leaf links to use as fingertips; pass `fingertips`")
    if not isinstance(fingertips, Mapping):
        fingertips = {frame: frame for frame in fingertips}
    hand_class = cls.__mro__[-2]  # Hand itself: a subclass (BarrettHand) has a constructor of its own
    return hand_class(model, fingertips, urdf_path=Path(path), **kwargs)


def collision_model(hand: Hand) -> pin.GeometryModel:
    """A copy of the hand's collision shapes on its own model (``collision_geometry``, else its URDF's, else none).

    Raises:
        ModelError: The URDF's collision geometry does not load.
    """
    if hand.collision_geometry is not None:
        return hand.collision_geometry.copy()
    path = hand.urdf_path
    if path is None:
        return pin.GeometryModel()
    try:
        return pin.buildGeomFromUrdfString(
            hand.model, path.read_text(), pin.GeometryType.COLLISION, None, [str(p) for p in path.parents]
        )
    except (ValueError, RuntimeError, OSError) as error:
        raise ModelError(f"cannot load the collision geometry of {str(path)!r}: {error}") from error


# Inertia checks: relative tolerance on the principal moments, plus an absolute floor [kg m^2] far below any real
# body's inertia (a 1 mg, 1 mm cube has ~2e-13) that absorbs the 1e-20-sized noise some published URDFs carry.
_INERTIA_RTOL = 1e-9
_INERTIA_ATOL = 1e-15
_INERTIA_ATTRIBUTES = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


def _check_inertials(root: Any, path: str | Path) -> None:
    """Refuse ``<inertial>`` blocks that urdfdom would silently drop or that no rigid body can have.

    Every ``<inertial>`` of every ``<link>`` needs a ``<mass value>`` that is finite and >= 0, six finite
    ``<inertia>`` components, a finite ``<origin>`` and a tensor that :func:`_inertia_error` accepts.  A massless
    link with zero inertia (or no ``<inertial>``), a point mass and a thin rod stay legal.  Principal moments that
    break the triangle inequality while ``ixx, iyy, izz`` satisfy it (off-diagonal products of inertia that no
    body has, e.g. example-robot-data's Allegro fingertips) only warn: such a tensor is still positive definite.

    Raises:
        ModelError: Naming the file and the link.
    """
    odd = []  # links whose principal moments break the triangle inequality: one warning for the file
    for link in root.findall("link"):
        where = f"URDF {str(path)!r} link {link.get('name')!r}"
        for inertial in link.findall("inertial"):
            mass_element = inertial.find("mass")
            mass = _urdf_number(None if mass_element is None else mass_element.get("value"))
            if mass is None or mass < 0.0:
                got = "no <mass value=...>" if mass_element is None else repr(mass_element.get("value"))
                raise ModelError(f"{where}: <inertial> mass must be a finite number >= 0 [kg], got {got}")
            inertia_element = inertial.find("inertia")
            c: dict[str, float] = {}
            for name in _INERTIA_ATTRIBUTES:
                value = None if inertia_element is None else inertia_element.get(name)
                number = _urdf_number(value)
                if number is None:
                    got = "no <inertia>" if inertia_element is None else f"{name}={value!r}"
                    raise ModelError(
                        f"{where}: <inertial> needs six finite <inertia> components "
                        f"{', '.join(_INERTIA_ATTRIBUTES)} [kg m^2], got {got}"
                    )
                c[name] = number
            origin = inertial.find("origin")
            for name in ("xyz", "rpy"):
                value = None if origin is None else origin.get(name)
                numbers = [] if value is None else [_urdf_number(x) for x in value.split()]
                if value is not None and (len(numbers) != 3 or None in numbers):
                    raise ModelError(f"{where}: <inertial> <origin {name}> must be 3 finite numbers, got {value!r}")
            tensor = np.array(
                [[c["ixx"], c["ixy"], c["ixz"]], [c["ixy"], c["iyy"], c["iyz"]], [c["ixz"], c["iyz"], c["izz"]]]
            )
            components = ", ".join(f"{name}={c[name]:.6g}" for name in _INERTIA_ATTRIBUTES)
            error = _inertia_error(tensor)
            if error:
                raise ModelError(f"{where}: {error} ({components})")
            moments = np.linalg.eigvalsh(tensor)
            if moments[0] + moments[1] < moments[2] - _inertia_tolerance(moments):
                odd.append((link.get("name"), moments, components))
    if odd:
        name, moments, components = odd[0]
        names = ", ".join(repr(item[0]) for item in odd)
        warnings.warn(
            f"URDF {str(path)!r}: no rigid body has the inertias of {len(odd)} link(s) ({names}); check the signs "
            f"of ixy, ixz, iyz; the dynamics use them as given. E.g. link {name!r}: the principal moments of inertia "
            f"[{_shown(moments)}] kg m^2 break the triangle inequality ({components})",
            UserWarning,
            stacklevel=4,
        )


def _check_model_inertias(model: pin.Model, path: str | Path) -> None:
    """Refuse non-finite, negative or indefinite inertias in what Pinocchio built (links merged across fixed joints)."""
    for joint, inertia in enumerate(model.inertias):
        links = [f.name for f in model.frames if f.type == pin.FrameType.BODY and f.parentJoint == joint]
        where = f"URDF {str(path)!r}: the body of joint {model.names[joint]!r} (links {', '.join(links)})"
        mass, lever, tensor = float(inertia.mass), np.array(inertia.lever), np.array(inertia.inertia)
        if not (np.isfinite(mass) and mass >= 0.0 and np.all(np.isfinite(lever)) and np.all(np.isfinite(tensor))):
            raise ModelError(
                f"{where} must have a finite mass >= 0 [kg], centre of mass and inertia in Pinocchio's model, got "
                f"mass {mass!r}, centre of mass {lever.tolist()}, inertia {tensor.tolist()}"
            )
        error = _inertia_error(tensor)
        if error:
            raise ModelError(f"{where}: {error} in Pinocchio's model")


def _inertia_error(tensor: np.ndarray) -> str | None:
    """Why a finite rotational inertia about the centre of mass [kg m^2] is impossible, or ``None``.

    It must be positive semi-definite (zero moments, of point masses and thin rods, are legal) and its diagonal
    ``ixx, iyy, izz`` must satisfy the triangle inequality (``ixx + iyy - izz = 2 * integral(z^2 dm) >= 0``), both
    within ``_INERTIA_RTOL`` of the largest principal moment plus ``_INERTIA_ATOL``.
    """
    moments = np.linalg.eigvalsh(0.5 * (tensor + tensor.T))  # ascending
    tolerance = _inertia_tolerance(moments)
    if moments[0] < -tolerance:
        return f"the inertia tensor must be positive semi-definite, got principal moments [{_shown(moments)}] kg m^2"
    diagonal = np.sort(np.diag(tensor))
    if diagonal[0] + diagonal[1] < diagonal[2] - tolerance:
        return (
            f"the moments of inertia ixx, iyy, izz break the triangle inequality "
            f"({diagonal[0]:.6g} + {diagonal[1]:.6g} < {diagonal[2]:.6g} kg m^2): no rigid body has them"
        )
    return None


def _inertia_tolerance(moments: np.ndarray) -> float:
    return _INERTIA_RTOL * float(np.max(np.abs(moments))) + _INERTIA_ATOL


def _shown(values: np.ndarray) -> str:
    return ", ".join(f"{value:.6g}" for value in values)


def _urdf_number(text: str | None) -> float | None:
    """A finite float from a URDF attribute, or ``None`` if it is missing, not a number, NaN or inf."""
    if text is None or "_" in text:  # Python's float() accepts "1_000", urdfdom does not
        return None
    try:
        value = float(text)
    except ValueError:
        return None
    return value if np.isfinite(value) else None
