"""The grasp benchmark: a wrist-mounted BH8-280 approaches, closes on, lifts, shakes and places household objects.

:mod:`~bhgrasp.bench.protocol` fixes the protocol (phases, thresholds, contact law,
:class:`~bhgrasp.bench.protocol.Trial`); :mod:`~bhgrasp.bench.objects` the object sets (development, four
held-out, meshes);
:mod:`~bhgrasp.bench.placement` where the hand goes over the object, :mod:`~bhgrasp.bench.height` how high and
:mod:`~bhgrasp.bench.opening` how far the hand opens, all from :mod:`~bhgrasp.bench.reach`'s touch angles, or, where
no height qualifies, :mod:`~bhgrasp.bench.side` a side
pinch; :mod:`~bhgrasp.bench.closing` when each finger starts to close;
:mod:`~bhgrasp.bench.trial` runs one trial, alone on its stand or, with :mod:`~bhgrasp.bench.neighbours`, among
settled neighbours on the table around it (:mod:`~bhgrasp.bench.table`), the hand turned away from them
(:mod:`~bhgrasp.bench.heading`);
:mod:`~bhgrasp.bench.metrics` scores it; :mod:`~bhgrasp.bench.runs` runs many and :mod:`~bhgrasp.bench.report`
writes their JSON and markdown report (``bhgrasp grasp-bench``).
"""

from bhgrasp.bench.closing import finger_starts
from bhgrasp.bench.heading import clearest_heading, hand_base, heading_clearance
from bhgrasp.bench.height import STAND_HEIGHT, STAND_MARGIN, TABLE_REACH, grasp_clearance, stand_clearance
from bhgrasp.bench.metrics import contact_summary, evaluate, failure_reason, held_forces, least_grip, relative_poses
from bhgrasp.bench.neighbours import neighbour_displacements, run_among_neighbours, settle_neighbours
from bhgrasp.bench.objects import (
    DEVELOPMENT_SET,
    HELD_OUT_SET,
    HELD_OUT_SET_2,
    HELD_OUT_SET_3,
    HELD_OUT_SET_4,
    HELD_OUT_SET_5,
    KINDS,
    OBJECT_SET,
    SETS,
    BenchObject,
)
from bhgrasp.bench.opening import top_down, way_in_gap, widened
from bhgrasp.bench.placement import closing_planes_meet, grasp_offset
from bhgrasp.bench.protocol import (
    ACTUATIONS,
    APPROACH,
    CLOSE_AT,
    DIRECTIONS,
    DISTURBED,
    DROP,
    DT,
    FORCE_LIMIT,
    FRICTION,
    GRASPS,
    GRIP_MT,
    HELD_AT,
    LIFT,
    LIFT_AT,
    LOOSE,
    PRESHAPE,
    RELEASE,
    SHAKE_TIME,
    STAND,
    STIFFNESS,
    STRICT,
    THREE_FINGER_SPREAD,
    Trial,
    spread_of,
)
from bhgrasp.bench.reach import hand_depth
from bhgrasp.bench.report import compare, markdown, success_rates, write_json
from bhgrasp.bench.runs import bench_rollout, run_bench
from bhgrasp.bench.side import SIDE_SPREAD, approach_of, side_centre
from bhgrasp.bench.table import Clutter, floor_below, stand_of, table_around
from bhgrasp.bench.trial import (
    BenchController,
    fallen,
    idealised_damping,
    run_protocol,
    run_trial,
    setup,
    shake_force,
    simulate_trial,
)

__all__ = [
    "ACTUATIONS",
    "APPROACH",
    "CLOSE_AT",
    "DEVELOPMENT_SET",
    "DIRECTIONS",
    "DISTURBED",
    "DROP",
    "DT",
    "FORCE_LIMIT",
    "FRICTION",
    "GRASPS",
    "GRIP_MT",
    "HELD_AT",
    "HELD_OUT_SET",
    "HELD_OUT_SET_2",
    "HELD_OUT_SET_3",
    "HELD_OUT_SET_4",
    "HELD_OUT_SET_5",
    "KINDS",
    "LIFT",
    "LIFT_AT",
    "LOOSE",
    "OBJECT_SET",
    "PRESHAPE",
    "RELEASE",
    "SETS",
    "SHAKE_TIME",
    "SIDE_SPREAD",
    "STAND",
    "STAND_HEIGHT",
    "STAND_MARGIN",
    "STIFFNESS",
    "STRICT",
    "TABLE_REACH",
    "THREE_FINGER_SPREAD",
    "BenchController",
    "BenchObject",
    "Clutter",
    "Trial",
    "approach_of",
    "bench_rollout",
    "clearest_heading",
    "closing_planes_meet",
    "compare",
    "contact_summary",
    "evaluate",
    "failure_reason",
    "fallen",
    "finger_starts",
    "floor_below",
    "grasp_clearance",
    "grasp_offset",
    "hand_base",
    "hand_depth",
    "heading_clearance",
    "held_forces",
    "idealised_damping",
    "least_grip",
    "markdown",
    "neighbour_displacements",
    "relative_poses",
    "run_among_neighbours",
    "run_bench",
    "run_protocol",
    "run_trial",
    "settle_neighbours",
    "setup",
    "shake_force",
    "side_centre",
    "simulate_trial",
    "spread_of",
    "stand_clearance",
    "stand_of",
    "success_rates",
    "table_around",
    "top_down",
    "way_in_gap",
    "widened",
    "write_json",
]
