"""The twin registry: every name ``bhgrasp._core`` binds, its Python twin and the test that holds them together.

A kernel of the compiled core is a second implementation of something the Python code states readably; the two are
kept equal by a lockstep test (to the bit, or to round-off where NumPy and Eigen sum in another order).  A bound data
type (an option struct, a result) mirrors one Python type, filled from it or read into it.  ``tests/test_twins.py``
fails when the core binds a name this registry lacks, when a twin cannot be imported, or when a lockstep test does
not exist; CI sets ``BHGRASP_REQUIRE_CORE=1`` so that no lockstep test can skip.

Three micro-kernels were measured against their twins on the default engine's callers (2-core machine, 2026-12-05):
``contact_frames`` 3.3 us against 24.6 us a call (every grasp-law cycle), ``object_regressor`` 3.7 against 15.4 us
(every adaptive cycle), ``concatenate`` 0.4 against 11.1 ms for a 3,000-sample run's contacts (every recorded run).
Each is kept: at the 1 kHz control rate the first two save 2 % and 1 % of the cycle, the third most of the
recorder's join.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Twin:
    """One bound name of ``bhgrasp._core``.

    Attributes:
        name: The name in ``bhgrasp._core``.
        twin: Dotted path of its Python twin (a kernel), or of the Python type it mirrors (a data type); ``""`` if
            it has none (``reason`` says why).
        lockstep: ``tests/<file>.py::<test>``: the test that holds them together (or, with no twin, checks it
            against an independent truth).
        reason: Why the name has no Python twin.
    """

    name: str
    twin: str
    lockstep: str
    reason: str = ""


_STEP = "tests/test_compiled.py::test_reference_hold"
_DIVERGED = "tests/test_simulator_contract.py::test_a_non_finite_result_names_its_coordinate_and_value"
_RUN = "tests/test_simulator_contract.py::test_a_whole_run_agrees_across_engines"
_LOOP = "tests/test_closed_loop.py::test_the_demo_runs_in_the_compiled_loop_with_the_python_loops_bits"

KERNELS = (
    Twin("Engine", "bhgrasp.sim.python_engine.PythonEngine", _STEP),
    Twin(
        "Batch",
        "bhgrasp.sim.simulator.Simulator",
        "tests/test_batch.py::test_a_batch_reproduces_separate_runs_bit_for_bit",
    ),
    Twin(
        "BarrettDrive",
        "bhgrasp.sim.actuation.BarrettActuation",
        "tests/test_compiled_drive.py::test_the_mounted_hand_closes_is_pushed_and_opens_as_the_python_rules_step_it",
    ),
    Twin(
        "WristServo",
        "bhgrasp.controllers.mount.MountServo",
        "tests/test_wrist_servo.py::test_the_compiled_servo_is_its_python_twin_to_round_off",
    ),
    Twin(
        "PosePath",
        "bhgrasp.motion.pose_references.PosePath",
        "tests/test_pose_path_kernel.py::test_the_compiled_path_samples_what_the_python_reference_does",
    ),
    Twin(
        "TouchSearch",
        "bhgrasp.bench.reach.Reach._touch",
        "tests/test_touch_search.py::test_every_touch_angle_is_the_twins_to_the_bit",
    ),
    Twin(
        "HandDynamics",
        "bhgrasp.model.hand_dynamics._slotine_li_torque_python",
        "tests/test_hand_kernels.py::test_slotine_li_torque_is_the_python_twin_to_the_bit",
    ),
    Twin(
        "FingerDynamics",
        "bhgrasp.controllers._workspace_terms._finger_terms_python",
        "tests/test_workspace_kernels.py::test_finger_terms_are_the_python_twin_to_the_bit",
    ),
    Twin(
        "GraspKinematics",
        "bhgrasp.grasp.kinematics.contact_kinematics_python",
        "tests/test_grasp_kernels.py::test_compiled_kernel_agrees_with_its_python_twin_at_random_configurations",
    ),
    Twin(
        "ContactForceQP",
        "bhgrasp.grasp._force_qp.ContactForceQPPython",
        "tests/test_force_qp_twin.py::test_the_engines_agree_bit_for_bit_against_the_plain_proxsuite",
    ),
    Twin(
        "SMCAdaptiveLaw",
        "bhgrasp.controllers.adaptive_grasp.SMCAdaptiveGrasp",
        "tests/test_smc_law_twin.py::test_the_engines_agree_on_the_demo_with_a_hold_and_a_reset",
    ),
    Twin(
        "finger_contacts",
        "bhgrasp.grasp.sensing.ContactSensing._fingers_python",
        "tests/test_sensing_kernels.py::test_finger_sums_match_the_numpy_twin",
    ),
    Twin(
        "object_regressor",
        "bhgrasp.controllers.object_regressors.object_regressor_python",
        "tests/test_sensing_kernels.py::test_object_regressor_matches_its_twin_and_its_definition",
    ),
    Twin(
        "contact_frames",
        "bhgrasp.grasp.frames.unit_normal_frames",
        "tests/test_sensing_kernels.py::test_contact_frames_match_the_numpy_twin",
    ),
    Twin(
        "concatenate",
        "bhgrasp.sim.recorder.Recorder._contact_arrays",
        "tests/test_compiled.py::test_the_recorders_join_is_its_numpy_twin",
    ),
    Twin("run_closed_loop", "bhgrasp.sim.run_loop.run", _LOOP),
    Twin("SMCGraspLoop", "bhgrasp.controllers._smc_law.CompiledSMCLaw.__call__", _LOOP),
    Twin("ApproachLoop", "bhgrasp.controllers.supervisor.GraspSupervisor.__call__", _LOOP),
    Twin(
        "box_separation",
        "",
        "tests/test_narrowphase.py::test_the_box_separation_is_a_lower_bound_of_coals_distance",
        reason="a shortcut of the compiled contact detection (pairs of boxes it need not ask coal about); held to "
        "coal's distance, and the step with it to the step without it bit for bit",
    ),
    Twin(
        "independent_model_text",
        "",
        "tests/test_couplings.py::test_the_twin_is_pinocchios_independent_model_and_pickles_rebuild_the_coupled_hand",
        reason="only Pinocchio's C++ API reaches a mimic joint's own joint model; checked against the free hand "
        "Pinocchio builds from the same URDF",
    ),
)

DATA = (
    Twin("Settings", "bhgrasp.sim.settings.SimulatorSettings", _STEP),
    Twin("ContactLaw", "bhgrasp.sim.contact_law.SpringDamper", "tests/test_compiled.py::test_tanh_friction_law"),
    Twin("Pair", "bhgrasp.sim.collision_pair.CollisionPair", _STEP),
    Twin("Query", "bhgrasp.sim.contact.ContactEngine", _STEP),
    Twin("Spinning", "bhgrasp.sim.scene_layout.SceneLayout", "tests/test_compiled.py::test_free_flight_with_spin"),
    Twin(
        "Drive",
        "bhgrasp.sim.engine.DriveTerms",
        "tests/test_compiled.py::test_barrett_closing_on_a_box_breaks_away_and_reopens",
    ),
    Twin("Memory", "bhgrasp.data.contacts.ContactMemory", _STEP),
    Twin("Contacts", "bhgrasp.data.contacts.ContactSet", _RUN),
    Twin("Divergence", "bhgrasp.sim.engine.Divergence", _DIVERGED),
    Twin("StepResult", "bhgrasp.sim.engine.StepResult", _STEP),
    Twin("LoopController", "bhgrasp.controllers.compiled_control.CompiledControl", _LOOP),
    Twin("LoopRun", "bhgrasp.sim.recorder.Recorder.add_run", _LOOP),
    Twin(
        "Barrett",
        "bhgrasp.sim.actuation.BarrettActuation",
        "tests/test_batch.py::test_a_batch_of_barrett_hands_switches_like_separate_runs",
    ),
    Twin(
        "WorkspaceTerms",
        "bhgrasp.controllers._workspace_terms._Workspace",
        "tests/test_workspace_kernels.py::test_the_workspace_terms_are_the_python_twin_to_round_off",
    ),
    Twin(
        "FingerSums",
        "bhgrasp.grasp.sensing.FingerContact",
        "tests/test_sensing_kernels.py::test_finger_sums_match_the_numpy_twin",
    ),
)

REGISTRY = {entry.name: entry for entry in (*KERNELS, *DATA)}

__all__ = ["DATA", "KERNELS", "REGISTRY", "Twin"]
