"""Chapter 4's contact without force control: a link driven into the object, and F3 pushed into it, plain or PIM.

:func:`one_link_contact` (Fig 4.4): the one-link finger under a PD law, its reaction torques J^T F (4.8) zero before
contact; :func:`f3_push` (Figs 4.6-4.9, 4.15-4.16): F3 commanded :data:`PUSH_DEPTH` beyond the surface by fingertip
computed torque, without and with position-based impedance (PIM).
"""

from __future__ import annotations

import numpy as np

from bhgrasp.controllers import PDGravity, WorkspaceComputedTorque
from bhgrasp.controllers.impedance import PositionImpedance
from bhgrasp.controllers.impedance_controller import ImpedanceController
from bhgrasp.data import State, Trajectory
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.motion.trajectories import Constant, Quintic
from bhgrasp.scenarios.finger_press import (
    F3_GAINS,
    F3_IMPEDANCE,
    STIFFNESSES,
    Setup,
    f3_setup,
    force_metrics,
    normal_force,
    planar_setup,
    run,
)
from bhgrasp.thesis.case import Case
from bhgrasp.thesis.chapter4_metrics import FORCE_HEADER, force_row

PUSH_DEPTH = 0.05  # [m] how far beyond the surface the uncontrolled push commands the fingertip


def one_link_contact(scale: float = 1.0) -> Case:
    """Fig 4.4: the 1-DOF link (l = 0.2 m) driven by a PD law (0.9, 0.25) into the mass-spring object."""
    case = Case("one_link", "One-link finger pushed into a mass-spring object (Fig 4.4)")
    case.header = [*FORCE_HEADER, "max |reaction| before contact [N m]"]
    for spring in (1000.0, 1500.0, 2000.0, 2500.0):
        setup = planar_setup(spring, one_link=True)
        target = Constant(np.array([1.0]))  # [rad] beyond the object
        traj = run(setup, PDGravity(setup.hand, target, kp=0.9, kd=0.25), 3.0 * scale)
        force = normal_force(setup, traj)
        m = force_metrics(traj.t, force)
        before = traj.t < m.contact_time if np.isfinite(m.contact_time) else np.ones(len(traj), bool)
        reaction = _reaction_torques(setup, traj)
        case.table.append(force_row(f"K_s = {spring:g} N/m", m, [f"{np.abs(reaction[before]).max():.1e}"]))
        case.traces[f"K_s {spring:g}"] = (traj.t, force, None)
    case.notes.append(
        "Thesis: contact at ~1.1 s, reaction torque zero before contact, force growing with time after it."
        "  Ours: link 1 kg (the thesis gives none), object 0.06 m ahead of the tip along the tip's path; PD gains"
        " 0.9 N m/rad and 0.25 N m s/rad as the thesis."
    )
    return case


def _reaction_torques(setup: Setup, traj: Trajectory) -> np.ndarray:
    """J^T F of the recorded contacts (thesis (4.8)) per sample [N m], via the sensing module."""
    sensing = ContactSensing(setup.hand)
    out = np.zeros((len(traj), setup.hand.nv))
    for k in range(len(traj)):
        c = traj.contacts_at(k)
        state = State(
            traj.t[k],
            traj.q[k],
            traj.v[k],
            contact_points=c["point"],
            contact_normals=c["normal"],
            contact_forces=c["force"],
            contact_bodies=tuple(map(tuple, c["bodies"])),
        )
        out[k] = sensing.reaction_torques(state)
    return out


def f3_push(scale: float = 1.0) -> Case:
    """Figs 4.6-4.9 and 4.15-4.16: F3 pushed 5 cm into the object, uncontrolled (fingertip CTC) and with PIM."""
    case = Case("f3_push", "F3 pushed into the object: uncontrolled vs position-based impedance (Figs 4.6-4.16)")
    case.header = FORCE_HEADER
    for spring in STIFFNESSES:
        setup = f3_setup(spring)
        goal = setup.surface_point() + PUSH_DEPTH * setup.normal  # commanded beyond the surface
        reference = Quintic(setup.tip0, goal, 2.0 * scale)
        plain = WorkspaceComputedTorque(setup.hand, {"F3": reference}, kp=F3_GAINS[0], kv=F3_GAINS[1])
        pim = ImpedanceController(setup.hand, {"F3": PositionImpedance(reference, **F3_IMPEDANCE)}, *F3_GAINS)
        for name, controller in (("uncontrolled", plain), ("PIM", pim)):
            traj = run(setup, controller, 3.0 * scale)
            force = normal_force(setup, traj)
            case.table.append(force_row(f"{name}, K_s = {spring:g}", force_metrics(traj.t, force)))
            case.traces[f"{name} K_s {spring:g}"] = (traj.t, force, None)
    case.notes += [
        "Thesis: uncontrolled 110-240 N for K_s = 10-50 kN/m; PIM (M_I 15, B_I 780, K_I 5000) settles at 20-30 N,"
        " k_e = 1e3: peak 58 N, steady 27 N, ~17 s; k_e = 5e4: peak 24 N, steady 20 N, 5.1 s.",
        "Ours: fingertip computed torque (Kp 430, Kv 175) commanded 5 cm beyond the surface along a 2 s quintic."
        "  Under a contact force that loop is a spring of stiffness M_x Kp (the fingertip's effective mass times"
        " Kp, tens of N/m here), so the uncontrolled force is ~M_x Kp x 5 cm, not the thesis' hundreds of newtons;"
        " PIM (M_I 0.05 kg, K_I 100 N/m, critical damping) adds its compliance in series.",
    ]
    return case


__all__ = ["PUSH_DEPTH", "f3_push", "one_link_contact"]
