// Python bindings of bhgrasp._core: thin wrappers, no logic.  Input checks that a user can trip live in Python
// (bhgrasp/sim/compiled.py and each kernel's Python caller); the checks here only keep a wrong call from reading out
// of bounds.  Models cross the boundary serialised: pin.Model.saveToString() / pin.GeometryModel.saveToString().
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include "barrett.hpp"
#include "batch.hpp"
#include "dynamics.hpp"
#include "engine.hpp"
#include "force_qp.hpp"
#include "grasp.hpp"
#include "model_io.hpp"
#include "options.hpp"
#include "recording.hpp"
#include "sensing.hpp"
#include "smc_law.hpp"
#include "workspace.hpp"

namespace nb = nanobind;
using namespace nb::literals;

// An option struct of options.hpp bound from its field list: a default constructor, each field read-write, and the
// tuple FIELDS of their names (bhgrasp/sim/native_options.py fills every one of them).
#define BHGRASP_DEF_RW(type, name) .def_rw(#name, &Self::name)
#define BHGRASP_NAME(type, name) #name,
#define BHGRASP_BIND_OPTIONS(module, Struct, FIELDS)                                                \
  [&] {                                                                                             \
    using Self = Struct;                                                                            \
    nb::class_<Self> options(module, #Struct);                                                      \
    options.def(nb::init<>()) FIELDS(BHGRASP_DEF_RW);                                               \
    options.attr("FIELDS") = nb::cast(std::vector<std::string>{FIELDS(BHGRASP_NAME)});              \
  }()

NB_MODULE(_core, m) {
  using namespace bhgrasp;
  m.doc() =
      "bhgrasp's compiled core: the simulation step and the grasp kinematics on Pinocchio's and coal's C++ API, the "
      "internal-force QP on proxsuite's.";
  BHGRASP_BIND_OPTIONS(m, ContactLaw, BHGRASP_CONTACT_LAW);
  BHGRASP_BIND_OPTIONS(m, Pair, BHGRASP_PAIR);
  BHGRASP_BIND_OPTIONS(m, Query, BHGRASP_QUERY);
  BHGRASP_BIND_OPTIONS(m, Spinning, BHGRASP_SPINNING);
  BHGRASP_BIND_OPTIONS(m, Settings, BHGRASP_SETTINGS);
  BHGRASP_BIND_OPTIONS(m, Drive, BHGRASP_DRIVE);
  BHGRASP_BIND_OPTIONS(m, Barrett, BHGRASP_BARRETT);

  nb::class_<Memory>(m, "Memory")
      .def(nb::init<>())
      .def("__init__",
           [](Memory* memory, Indices pair, Points local_b, Points displacement, Flags sliding) {
             const Eigen::Index n = pair.size();
             if (local_b.rows() != n || displacement.rows() != n || sliding.size() != n)
               throw std::invalid_argument("memory arrays of different lengths");
             new (memory) Memory{std::move(pair), std::move(local_b), std::move(displacement), std::move(sliding)};
           },
           "pair"_a, "local_b"_a, "displacement"_a, "sliding"_a)
      .def_ro("pair", &Memory::pair).def_ro("local_b", &Memory::local_b)
      .def_ro("displacement", &Memory::displacement).def_ro("sliding", &Memory::sliding)
      .def("__len__", [](const Memory& memory) { return memory.pair.size(); });

  nb::class_<Contacts>(m, "Contacts")
      .def_ro("pair", &Contacts::pair).def_ro("point", &Contacts::point)
      .def_ro("normal", &Contacts::normal).def_ro("depth", &Contacts::depth)
      .def_ro("friction", &Contacts::friction).def_ro("displacement", &Contacts::displacement)
      .def_ro("weight", &Contacts::weight).def_ro("local_b", &Contacts::local_b)
      .def_ro("force", &Contacts::force).def_ro("sticking", &Contacts::sticking)
      .def_ro("was_sliding", &Contacts::was_sliding)
      .def("__len__", &Contacts::size);
  nb::class_<FingerSums>(m, "FingerSums")
      .def_ro("force", &FingerSums::force).def_ro("normal_force", &FingerSums::normal_force)
      .def_ro("normal", &FingerSums::normal).def_ro("count", &FingerSums::count)
      .def_ro("point", &FingerSums::point)
      .def_ro("strongest", &FingerSums::strongest);
  m.def("finger_contacts", &finger_contacts, "finger"_a, "fingers"_a, "points"_a, "normals"_a, "forces"_a,
        "Per finger, its sensed contacts summed (bhgrasp.grasp.sensing.ContactSensing.fingers).");
  m.def("object_regressor", &object_regressor, "rotation"_a, "omega"_a, "v_r"_a, "a_r"_a, "gravity"_a,
        "Y_o (6, 7) of bhgrasp.controllers.adaptive_grasp.object_regressor.");
  m.def(
      "contact_frames",
      [](const Points& normals, double zero_length, double switch_x) {
        Eigen::Index zero = -1;
        Points frames = contact_frames(normals, zero_length, switch_x, zero);
        return std::make_pair(std::move(frames), zero);
      },
      "normals"_a, "zero_length"_a, "switch_x"_a,
      "Contact frames (3m, 3) of bhgrasp.grasp.frames.contact_frames and the first zero normal's index (-1: none).");
  m.def("independent_model_text", &independent_model_text, "model"_a,
        "pin.Model.saveToString() of the model with every mimic joint made an independent joint (bhgrasp.model.couplings).");
  m.def("concatenate", &concatenate, "parts"_a, "The contacts of many steps as one Contacts (rows in order).");

  nb::class_<Divergence>(m, "Divergence")
      .def_ro("kind", &Divergence::kind).def_ro("index", &Divergence::index)
      .def_ro("value", &Divergence::value);

  nb::class_<StepResult>(m, "StepResult")
      .def_ro("q", &StepResult::q).def_ro("v", &StepResult::v)
      .def_ro("contacts", &StepResult::contacts).def_ro("memory", &StepResult::memory)
      .def_ro("drive", &StepResult::drive).def_ro("load", &StepResult::load)
      .def_ro("divergence", &StepResult::divergence);

  nb::class_<Engine>(m, "Engine")
      .def(nb::init<const std::string&, const std::string&, Settings>(), "model"_a, "geometry"_a, "settings"_a)
      .def("step", &Engine::step, "q"_a, "v"_a, "tau_hand"_a, "drive"_a, "memory"_a, "max_speed"_a,
           "max_penetration"_a, nb::call_guard<nb::gil_scoped_release>())
      .def("detect", &Engine::detect, "q"_a, "memory"_a)
      .def_prop_ro("nq", &Engine::nq)
      .def_prop_ro("nv", &Engine::nv);

  nb::class_<Batch>(m, "Batch")
      .def(nb::init<const std::string&, const std::string&, const Settings&, int>(), "model"_a, "geometry"_a,
           "settings"_a, "size"_a)
      .def_prop_ro("size", &Batch::size)
      .def("set_state", &Batch::set_state, "env"_a, "q"_a, "v"_a, "memory"_a)
      .def("step", &Batch::step, "tau_hand"_a, "drive"_a, "max_speed"_a, "max_penetration"_a, "threads"_a,
           nb::call_guard<nb::gil_scoped_release>())
      .def_prop_ro("q", [](const Batch& batch) { return Rows(batch.q()); })
      .def_prop_ro("v", [](const Batch& batch) { return Rows(batch.v()); })
      .def("memory", [](const Batch& batch, int env) { return Memory(batch.memory(env)); }, "env"_a)
      .def("contacts", [](const Batch& batch, int env) { return Contacts(batch.contacts(env)); }, "env"_a)
      .def("divergence", [](const Batch& batch, int env) { return Divergence(batch.divergence(env)); }, "env"_a)
      .def("set_barrett", &Batch::set_barrett, "barrett"_a)
      .def("set_modes", &Batch::set_modes, "env"_a, "modes"_a)
      .def("modes", &Batch::modes, "env"_a)
      .def("step_barrett", &Batch::step_barrett, "u"_a, "max_speed"_a, "max_penetration"_a, "threads"_a,
           nb::call_guard<nb::gil_scoped_release>())
      .def("gravity", &Batch::gravity, "threads"_a, nb::call_guard<nb::gil_scoped_release>())
      .def("frame_jacobians", &Batch::frame_jacobians, "frames"_a, "threads"_a,
           nb::call_guard<nb::gil_scoped_release>());

  nb::class_<HandDynamics>(m, "HandDynamics")
      .def(nb::init<const std::string&>(), "model"_a)
      .def(
          "slotine_li_torque",
          [](HandDynamics& kernel, const Eigen::Vector3d& gravity, const HandDynamics::ConstVector& q,
             const HandDynamics::ConstVector& v, const HandDynamics::ConstVector& v_r,
             const HandDynamics::ConstVector& a_r) -> Eigen::VectorXd {
            return kernel.slotine_li_torque(gravity, q, v, v_r, a_r);  // a copy: the kernel's is overwritten
          },
          "gravity"_a, "q"_a, "v"_a, "v_r"_a, "a_r"_a)
      .def(
          "contact_torques",
          [](HandDynamics& kernel, const Eigen::Matrix3d& base_rotation, const Eigen::Vector3d& base_translation,
             const HandDynamics::ConstVector& q, const std::vector<int>& joints, const HandDynamics::ConstRows& points,
             const HandDynamics::ConstRows& forces) -> Eigen::VectorXd {
            return kernel.contact_torques(base_rotation, base_translation, q, joints, points, forces);  // a copy
          },
          "base_rotation"_a, "base_translation"_a, "q"_a, "joints"_a, "points"_a, "forces"_a)
      .def_prop_ro("nv", &HandDynamics::nv);

  nb::class_<WorkspaceTerms>(m, "WorkspaceTerms")  // the fields of bhgrasp.controllers._workspace_terms._Workspace
      .def_ro("singular", &WorkspaceTerms::singular).def_ro("position", &WorkspaceTerms::position)
      .def_ro("jacobian", &WorkspaceTerms::jacobian).def_ro("basis", &WorkspaceTerms::basis)
      .def_ro("task_jacobian", &WorkspaceTerms::task_jacobian).def_ro("mass", &WorkspaceTerms::mass)
      .def_ro("coriolis", &WorkspaceTerms::coriolis).def_ro("gravity", &WorkspaceTerms::gravity)
      .def("torque", &fingertip_torque, "velocity"_a, "x_d"_a, "xd_d"_a, "xdd_d"_a, "kp"_a, "kv"_a);
  nb::class_<FingerDynamics>(m, "FingerDynamics")
      .def(nb::init<const std::string&, const std::vector<int>&, const std::vector<std::vector<int>>&>(), "model"_a,
           "frames"_a, "indices"_a)
      // copies out as writable arrays in NumPy's layout (the kernel's own are overwritten by its next call), in the
      // order of bhgrasp.controllers._workspace_terms._finger_terms_python
      .def(
          "compute",
          [](FingerDynamics& kernel, int finger, const Eigen::Vector3d& gravity, const FingerDynamics::ConstVector& q,
             const FingerDynamics::ConstVector& v) {
            const FingerTerms& terms = kernel.compute(finger, gravity, q, v);
            return std::make_tuple(terms.positions, terms.jacobian, terms.mass, terms.gravity, terms.velocity,
                                   terms.bias);
          },
          "finger"_a, "gravity"_a, "q"_a, "v"_a)
      .def("workspace", &FingerDynamics::workspace, nb::rv_policy::copy, "finger"_a, "gravity"_a, "rotation"_a,
           "translation"_a, "q"_a, "v"_a)
      .def_prop_ro("nv", &FingerDynamics::nv);

  nb::class_<GraspKinematics>(m, "GraspKinematics")
      .def(nb::init<const std::string&>(), "model"_a)
      // the maps copied out as writable arrays (the kernel's own are overwritten by its next call), in the order of
      // bhgrasp.grasp.kinematics.GraspKinematics
      .def(
          "compute",
          [](GraspKinematics& kernel, const Eigen::Matrix3d& base_rotation, const Eigen::Vector3d& base_translation,
             const GraspKinematics::ConstVector& q, const Eigen::Vector3d& com, const Vector6& twist,
             const GraspKinematics::ConstRows& points, const GraspKinematics::ConstRows& frames,
             const std::vector<int>& joints) {
            const GraspMaps& maps =
                kernel.compute(base_rotation, base_translation, q, com, twist, points, frames, joints);
            return std::make_tuple(maps.joint_map, maps.joint_map_rate, maps.grasp_map, maps.hand_jacobian,
                                   maps.hand_jacobian_pinv);
          },
          "base_rotation"_a, "base_translation"_a, "q"_a, "com"_a, "twist"_a, "points"_a, "frames"_a, "joints"_a)
      .def_prop_ro("nq", &GraspKinematics::nq)
      .def_prop_ro("nv", &GraspKinematics::nv);

  nb::class_<ContactForceQP> force_qp(m, "ContactForceQP");
  force_qp
      .def(nb::init<int, double, const ContactForceQP::ConstRows&, double, double, double, int, int>(),
           "n_contacts"_a, "mu"_a, "pyramid"_a, "inscribed"_a, "min_normal_force"_a, "tolerance"_a, "max_iter"_a,
           "max_iter_in"_a)
      .def("holds", &ContactForceQP::holds, "grasp"_a)
      .def("set_grasp_map", &ContactForceQP::set_grasp_map, "grasp"_a, "torque_scale"_a)
      // the fields of bhgrasp.grasp.forces.ContactForceResult in order, arrays copied out
      .def(
          "solve",
          [](ContactForceQP& qp, const Vector6& wrench, const ContactForceQP::ConstVector& desired) {
            const ForceResult& r = qp.solve(wrench, desired);
            return std::make_tuple(r.forces, r.feasible, r.wrench_residual, r.cone_violation, r.normal_margin,
                                   std::string(r.status), r.iterations, r.wrench_error);
          },
          "wrench"_a, "desired"_a)
      .def_prop_ro("n_contacts", &ContactForceQP::n_contacts);
  force_qp.attr("NEAREST_WEIGHT") = ForceQPConstants::nearest_weight;
  force_qp.attr("PRIMAL_INFEASIBILITY") = ForceQPConstants::primal_infeasibility;
  force_qp.attr("DOUBTFUL_ERROR") = ForceQPConstants::doubtful_error;
  force_qp.attr("DUALITY_GAP_REL") = ForceQPConstants::duality_gap_rel;
  force_qp.attr("FEASIBLE_RESIDUAL") = ForceQPConstants::feasible_residual;
  force_qp.attr("ADMISSIBLE_TOLERANCE") = ForceQPConstants::admissible_tolerance;
  force_qp.attr("CHECK_ITER") = ForceQPConstants::check_iter;
  nb::class_<SMCAdaptiveLaw>(m, "SMCAdaptiveLaw")
      .def(nb::init<GraspKinematics&, HandDynamics&, int>(), "kinematics"_a, "dynamics"_a, "fingers"_a,
           nb::keep_alive<1, 2>(), nb::keep_alive<1, 3>())
      .def("configure", &SMCAdaptiveLaw::configure, "rho"_a, "k_o"_a, "object_adaptation"_a, "force_gain"_a,
           "force_integral"_a, "k_f"_a, "normal_only"_a, "squeeze"_a, "gravity"_a, "initial_estimate"_a, "mu"_a,
           "pyramid"_a, "inscribed"_a, "min_normal_force"_a, "tolerance"_a, "max_iter"_a, "max_iter_in"_a,
           "zero_length"_a, "switch_x"_a)
      .def("reset", &SMCAdaptiveLaw::reset)
      .def("set_base", &SMCAdaptiveLaw::set_base, "rotation"_a, "translation"_a, "gravity"_a)
      .def("sense", &SMCAdaptiveLaw::sense, "finger"_a, "joint"_a, "points"_a, "normals"_a, "forces"_a)
      .def("grasp", &SMCAdaptiveLaw::grasp, "q"_a, "v"_a, "rotation"_a, "translation"_a, "twist"_a, "dt"_a,
           "target_rotation"_a, "target_translation"_a, "velocity"_a, "acceleration"_a, "out"_a)
      .def_prop_rw("object_estimate", &SMCAdaptiveLaw::object_estimate, &SMCAdaptiveLaw::set_object_estimate)
      .def_prop_ro("log_size", &SMCAdaptiveLaw::log_size);
}
