"""Reusable scenes: hands, objects and controllers set up for a run, for users, tests, notebooks and studies.

The reference hold (:mod:`~bhgrasp.scenarios.hold`), the chapter-5 box grasp (:mod:`~bhgrasp.scenarios.box_grasp`), the
Allegro box grasp (:mod:`~bhgrasp.scenarios.allegro_grasp`), any object grasped as the synthesis plans it
(:mod:`~bhgrasp.scenarios.object_grasp`), the grasp demo and its result (:mod:`~bhgrasp.scenarios.grasp_demo`,
:mod:`~bhgrasp.scenarios.demo_result`), its controllers by name (:mod:`~bhgrasp.scenarios.grasp_controllers`) and
uncertainties (:mod:`~bhgrasp.scenarios.uncertainty`), the tour of the hand (:mod:`~bhgrasp.scenarios.tour`), the ideal
object loop (:mod:`~bhgrasp.scenarios.object_loop`), the identification runs (:mod:`~bhgrasp.scenarios.identification`),
grasped objects carried along paths (:mod:`~bhgrasp.scenarios.carry`), a finger pressing a spring-mounted box
(:mod:`~bhgrasp.scenarios.finger_press`, chapter 4's benches) and the fitness that tunes its impedance
(:mod:`~bhgrasp.scenarios.press_fitness`), piles of mixed objects dropped into a bin or onto a table and settled
(:mod:`~bhgrasp.scenarios.clutter`), and the sweep rollouts built on them (:mod:`~bhgrasp.scenarios.rollouts`);
joint tracking with the thesis' joint controllers by name (:mod:`~bhgrasp.scenarios.joint_tracking`).
"""

from bhgrasp.scenarios.allegro_grasp import allegro_box_grasp, allegro_hand
from bhgrasp.scenarios.box_grasp import BoxGrasp, box_grasp
from bhgrasp.scenarios.carry import PathRun, circle, run_path, waypoints
from bhgrasp.scenarios.clutter import Pile, bin_walls, drop_pile, mixed_objects
from bhgrasp.scenarios.demo_result import MU_ASSUMED, SUCCESS, GraspDemoResult, evaluate_demo
from bhgrasp.scenarios.finger_press import ForceMetrics, Setup, f3_setup, force_metrics, normal_force, planar_setup
from bhgrasp.scenarios.grasp_controllers import ADAPTATIONS, CONTROLLERS, grasp_controller
from bhgrasp.scenarios.grasp_demo import HANDS, demo_figure, grasp_scene, run_grasp_demo, save_demo
from bhgrasp.scenarios.hold import HoldScenario, reference_hold
from bhgrasp.scenarios.identification import IdentificationRun, identification_run
from bhgrasp.scenarios.joint_tracking import f3_case
from bhgrasp.scenarios.object_grasp import OBJECTS, ObjectGrasp, object_grasp, run_object_grasp
from bhgrasp.scenarios.object_loop import ObjectLoopRun, ideal_object_loop
from bhgrasp.scenarios.press_fitness import impedance_fitness
from bhgrasp.scenarios.rollouts import check_grasp_case, grasp_rollout, hold_rollout
from bhgrasp.scenarios.tour import hold_lines, save_workspace_figure, tripod_lines
from bhgrasp.scenarios.uncertainty import UNCERTAINTIES, sensor_model

__all__ = [
    "ADAPTATIONS",
    "CONTROLLERS",
    "HANDS",
    "MU_ASSUMED",
    "OBJECTS",
    "SUCCESS",
    "UNCERTAINTIES",
    "BoxGrasp",
    "ForceMetrics",
    "GraspDemoResult",
    "HoldScenario",
    "IdentificationRun",
    "ObjectGrasp",
    "ObjectLoopRun",
    "PathRun",
    "Pile",
    "Setup",
    "allegro_box_grasp",
    "allegro_hand",
    "bin_walls",
    "box_grasp",
    "check_grasp_case",
    "circle",
    "demo_figure",
    "drop_pile",
    "evaluate_demo",
    "f3_case",
    "f3_setup",
    "force_metrics",
    "grasp_controller",
    "grasp_rollout",
    "grasp_scene",
    "hold_lines",
    "hold_rollout",
    "ideal_object_loop",
    "identification_run",
    "impedance_fitness",
    "mixed_objects",
    "normal_force",
    "object_grasp",
    "planar_setup",
    "reference_hold",
    "run_grasp_demo",
    "run_object_grasp",
    "run_path",
    "save_demo",
    "save_workspace_figure",
    "sensor_model",
    "tripod_lines",
    "waypoints",
]
