"""The data every layer speaks: states, trajectories and contacts (plain values; no simulator, no physics).

:mod:`~bhgrasp.data.state` (State: one instant as a controller sees it), :mod:`~bhgrasp.data.trajectory`
(Trajectory: the record of a run) and :mod:`~bhgrasp.data.contacts` (Contact, ContactSet, ContactMemory).  A
controller, a grasp analysis or a driver of the real hand imports these and nothing of :mod:`bhgrasp.sim`.
"""

from bhgrasp.data.contacts import Contact, ContactMemory, ContactSet, empty_contact_set
from bhgrasp.data.state import DERIVED_FIELDS, SimulatedState, State
from bhgrasp.data.trajectory import Trajectory

__all__ = [
    "DERIVED_FIELDS",
    "Contact",
    "ContactMemory",
    "ContactSet",
    "SimulatedState",
    "State",
    "Trajectory",
    "empty_contact_set",
]
