// Bindings of the grasp family: sensed contacts per finger, contact frames, the grasp maps, the internal-force QP,
// the compiled SMC-adaptive grasp law and the benchmark's touch search.
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include "force_qp.hpp"
#include "grasp.hpp"
#include "pose_path.hpp"
#include "sensing.hpp"
#include "smc_law.hpp"
#include "touch_search.hpp"

#include "bindings.hpp"

namespace nb = nanobind;
using namespace nb::literals;

namespace bhgrasp {

void bind_grasp(nb::module_& m) {
  nb::class_<TouchSearch>(m, "TouchSearch")
      .def(nb::init<const std::string&, const std::string&, int, std::vector<std::vector<int>>, const Eigen::VectorXd&,
                    std::vector<int>, std::vector<int>, const Eigen::Matrix3d&>(),
           "model"_a, "geometry"_a, "object"_a, "links"_a, "configuration"_a, "proximal"_a, "distal"_a, "axes"_a)
      .def("apart", &TouchSearch::apart, "finger"_a, "angle"_a, "centre"_a)
      .def("touch", &TouchSearch::touch, "finger"_a, "centre"_a, "opening"_a, "closed"_a,
           nb::call_guard<nb::gil_scoped_release>());
  nb::class_<FingerSums>(m, "FingerSums")
      .def_ro("force", &FingerSums::force).def_ro("normal_force", &FingerSums::normal_force)
      .def_ro("normal", &FingerSums::normal).def_ro("count", &FingerSums::count)
      .def_ro("point", &FingerSums::point)
      .def_ro("strongest", &FingerSums::strongest);
  m.def("finger_contacts", &finger_contacts, "finger"_a, "fingers"_a, "points"_a, "normals"_a, "forces"_a,
        "Per finger, its sensed contacts summed (bhgrasp.grasp.sensing.ContactSensing.fingers).");
  m.def(
      "contact_frames",
      [](const Points& normals, double zero_length, double switch_x) {
        Eigen::Index zero = -1;
        Points frames = contact_frames(normals, zero_length, switch_x, zero);
        return std::make_pair(std::move(frames), zero);
      },
      "normals"_a, "zero_length"_a, "switch_x"_a,
      "Contact frames (3m, 3) of bhgrasp.grasp.frames.contact_frames and the first zero normal's index (-1: none).");

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
  force_qp.attr("ACTIVE_TOLERANCE") = ForceQPConstants::active_tolerance;
  force_qp.attr("FULL_RANK") = ForceQPConstants::full_rank;
  nb::class_<SMCAdaptiveLaw>(m, "SMCAdaptiveLaw")
      .def(nb::init<GraspKinematics&, HandDynamics&, int>(), "kinematics"_a, "dynamics"_a, "fingers"_a,
           nb::keep_alive<1, 2>(), nb::keep_alive<1, 3>())
      .def("configure", &SMCAdaptiveLaw::configure, "rho"_a, "k_o"_a, "object_adaptation"_a, "force_gain"_a,
           "force_integral"_a, "k_f"_a, "normal_only"_a, "squeeze"_a, "grip_reflex"_a,
           "gravity"_a, "initial_estimate"_a, "mu"_a,
           "pyramid"_a, "inscribed"_a, "min_normal_force"_a, "tolerance"_a, "max_iter"_a, "max_iter_in"_a,
           "zero_length"_a, "switch_x"_a)
      .def("reset", &SMCAdaptiveLaw::reset)
      .def("set_base", &SMCAdaptiveLaw::set_base, "rotation"_a, "translation"_a, "gravity"_a)
      .def("sense", &SMCAdaptiveLaw::sense, "finger"_a, "joint"_a, "points"_a, "normals"_a, "forces"_a)
      .def("sense_contacts", &SMCAdaptiveLaw::sense_contacts, "contacts"_a, "finger_of_pair"_a, "joint_of_pair"_a)
      .def("grasp", &SMCAdaptiveLaw::grasp, "q"_a, "v"_a, "rotation"_a, "translation"_a, "twist"_a, "dt"_a,
           "target_rotation"_a, "target_translation"_a, "velocity"_a, "acceleration"_a, "out"_a)
      .def("grasp_free_body", &SMCAdaptiveLaw::grasp_free_body, "q"_a, "v"_a, "object_q"_a, "object_v"_a, "dt"_a,
           "target_rotation"_a, "target_translation"_a, "velocity"_a, "acceleration"_a, "out"_a)
      .def("grasp_free_body_on_path", &SMCAdaptiveLaw::grasp_free_body_on_path, "q"_a, "v"_a, "object_q"_a,
           "object_v"_a, "dt"_a, "path"_a, "t"_a, "out"_a)
      .def_prop_rw("object_estimate", &SMCAdaptiveLaw::object_estimate, &SMCAdaptiveLaw::set_object_estimate)
      .def_prop_ro("log_size", &SMCAdaptiveLaw::log_size);
}

}  // namespace bhgrasp
